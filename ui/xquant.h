/*
 * xquant.h - exact order statistics of many doubles in bounded memory.
 *
 * A median or a quantile needs every value, or several looks at them.
 * The values here come from seeded rays, so they can be made again: the
 * caller feeds the same values pass after pass, and each pass narrows the
 * wanted ranks by the bits of their keys (a double's bits, ordered as the
 * doubles), until the few values left fit in memory and are sorted.  The
 * result equals sorting every value.  Memory stays under XQ_MAX_BYTES a
 * statistic whatever the count.
 *
 * Use: xq_init; in the first pass, xq_add each value; xq_count tells the
 * number; xq_resolve(q, ranks, nrank) returns 1 when every rank is known,
 * 0 when it needs another pass: xq_add the same values again, in any
 * order, and call xq_resolve(q, NULL, 0), until it returns 1.
 */
#ifndef SG_XQUANT_H
#define SG_XQUANT_H

#include <stddef.h>
#include <stdint.h>

#define XQ_MAXRANK 4
/* Distinct values counted in the first pass: often all there are. */
#define XQ_DISTINCT 256
/* Values kept to be sorted for one rank; above this, another pass. */
#define XQ_STORE_MAX ((size_t)1 << 19)
/* Buckets of the first histogram (bits of the key), then of later ones. */
#define XQ_BITS_FIRST 20
#define XQ_BITS_NEXT 16
/* Values a statistic takes: its histograms count in 32 bits. */
#define XQ_MAX_VALUES ((size_t)UINT32_MAX)
/* An upper bound of the memory a statistic holds beside its struct: each
 * rank's group is a histogram or the keys it keeps. */
#define XQ_MAX_BYTES                                                                     \
    ((size_t)XQ_MAXRANK * (XQ_STORE_MAX * 8 > ((size_t)4 << XQ_BITS_FIRST)                \
                               ? XQ_STORE_MAX * 8                                        \
                               : ((size_t)4 << XQ_BITS_FIRST)))

enum { XQ_OK = 1, XQ_AGAIN = 0, XQ_ENOMEM = -1, XQ_ECHANGED = -2, XQ_ETOOMANY = -3 };

typedef struct xq_group {
    uint64_t prefix; /* keys whose top `bits` bits are prefix */
    int bits;
    int nb;          /* histogram: the next nb bits; 0: keep the keys */
    size_t count;    /* keys under prefix, from the last pass */
    uint32_t *hist;
    uint64_t *keys;
    size_t nkeys, seen;
} xq_group;

typedef struct xquant {
    size_t n;      /* values of the first pass */
    int pass;      /* passes ended */
    uint64_t kmin, kmax;
    int nrank;
    size_t rank[XQ_MAXRANK];
    int done[XQ_MAXRANK];
    uint64_t key[XQ_MAXRANK];
    int rgroup[XQ_MAXRANK];   /* the group that holds the rank */
    size_t rrest[XQ_MAXRANK]; /* its rank within that group */
    /* The first pass's distinct keys (open addressing, 2 * XQ_DISTINCT). */
    uint64_t dkey[2 * XQ_DISTINCT];
    uint32_t dcnt[2 * XQ_DISTINCT];
    int ndist, overflow;
    xq_group g[XQ_MAXRANK];
    int ngroup;
    int err;
    size_t store_max; /* XQ_STORE_MAX; a test may lower it to reach the
                       * histograms' later levels with few values */
} xquant;

void xq_init(xquant *q);
void xq_free(xquant *q);
void xq_add(xquant *q, double v);
size_t xq_count(const xquant *q);
/* rank: 0-based, each below xq_count; given once, after the first pass. */
int xq_resolve(xquant *q, const size_t *rank, int nrank);
/* The value of the k-th rank given to xq_resolve, once it returned XQ_OK. */
double xq_value(const xquant *q, int k);
/* The least and the largest value of the first pass. */
double xq_min(const xquant *q);
double xq_max(const xquant *q);

#endif
