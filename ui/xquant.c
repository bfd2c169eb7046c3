/* xquant.c - see xquant.h. */
#include "xquant.h"

#include <stdlib.h>
#include <string.h>

/* A double's bits, turned so that unsigned order is the doubles' order
 * (-0 just below +0; NaNs beyond the infinities). */
static uint64_t key_of(double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    return u >> 63 ? ~u : u | (UINT64_C(1) << 63);
}

static double value_of(uint64_t k)
{
    double v;
    k = k >> 63 ? k & ~(UINT64_C(1) << 63) : ~k;
    memcpy(&v, &k, sizeof v);
    return v;
}

void xq_init(xquant *q)
{
    memset(q, 0, sizeof *q);
    q->store_max = XQ_STORE_MAX;
}

static void free_groups(xquant *q)
{
    int k;
    for (k = 0; k < q->ngroup; k++) {
        free(q->g[k].hist);
        free(q->g[k].keys);
    }
    memset(q->g, 0, sizeof q->g);
    q->ngroup = 0;
}

void xq_free(xquant *q)
{
    free_groups(q);
}

size_t xq_count(const xquant *q)
{
    return q->n;
}

static void group_add(xquant *q, xq_group *g, uint64_t key, uint32_t count)
{
    if (g->bits > 0 && key >> (64 - g->bits) != g->prefix)
        return;
    g->seen += count;
    if (g->nb) {
        g->hist[(key >> (64 - g->bits - g->nb)) & ((UINT64_C(1) << g->nb) - 1)] += count;
    } else if (g->nkeys < g->count) {
        g->keys[g->nkeys++] = key;
    } else {
        q->err = XQ_ECHANGED;
    }
}

/* The first pass outgrew its table of distinct keys: every key so far
 * goes into the first histogram. */
static void spill(xquant *q)
{
    xq_group *g = &q->g[0];
    int k;
    q->overflow = 1;
    q->ngroup = 1;
    g->nb = XQ_BITS_FIRST;
    g->hist = calloc((size_t)1 << XQ_BITS_FIRST, sizeof *g->hist);
    if (!g->hist) {
        q->err = XQ_ENOMEM;
        return;
    }
    for (k = 0; k < 2 * XQ_DISTINCT; k++)
        if (q->dcnt[k])
            group_add(q, g, q->dkey[k], q->dcnt[k]);
}

void xq_add(xquant *q, double v)
{
    uint64_t key = key_of(v);
    int k;
    if (q->err)
        return;
    if (q->pass == 0) {
        if (q->n == XQ_MAX_VALUES) {
            q->err = XQ_ETOOMANY;
            return;
        }
        if (q->n == 0 || key < q->kmin)
            q->kmin = key;
        if (q->n == 0 || key > q->kmax)
            q->kmax = key;
        q->n++;
        if (!q->overflow) {
            size_t h = (size_t)((key * UINT64_C(0x9E3779B97F4A7C15)) >> 55); /* 9 bits */
            while (q->dcnt[h] && q->dkey[h] != key)
                h = (h + 1) % (2 * XQ_DISTINCT);
            if (q->dcnt[h]) {
                q->dcnt[h]++;
                return;
            }
            if (q->ndist < XQ_DISTINCT) {
                q->dkey[h] = key;
                q->dcnt[h] = 1;
                q->ndist++;
                return;
            }
            spill(q);
            if (q->err)
                return;
        }
        group_add(q, &q->g[0], key, 1);
        return;
    }
    for (k = 0; k < q->ngroup; k++)
        group_add(q, &q->g[k], key, 1);
}

static int cmp_key(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Every rank from the sorted distinct keys of the first pass. */
static void from_table(xquant *q)
{
    uint64_t key[XQ_DISTINCT];
    size_t cnt[XQ_DISTINCT], cum = 0;
    int k, j, n = 0;
    for (k = 0; k < 2 * XQ_DISTINCT; k++)
        if (q->dcnt[k])
            key[n++] = q->dkey[k];
    qsort(key, (size_t)n, sizeof *key, cmp_key);
    for (k = 0; k < n; k++) {
        for (j = 0; j < 2 * XQ_DISTINCT; j++)
            if (q->dcnt[j] && q->dkey[j] == key[k])
                break;
        cnt[k] = q->dcnt[j];
    }
    for (k = 0; k < n; k++) {
        for (j = 0; j < q->nrank; j++)
            if (!q->done[j] && q->rank[j] < cum + cnt[k]) {
                q->key[j] = key[k];
                q->done[j] = 1;
            }
        cum += cnt[k];
    }
}

int xq_resolve(xquant *q, const size_t *rank, int nrank)
{
    xq_group ng[XQ_MAXRANK];
    int k, j, nng = 0, left = 0;

    if (q->err)
        return q->err;
    if (q->pass == 0) {
        if (nrank > XQ_MAXRANK)
            nrank = XQ_MAXRANK;
        q->nrank = nrank;
        for (k = 0; k < nrank; k++) {
            q->rank[k] = rank[k];
            q->rrest[k] = rank[k];
            q->rgroup[k] = 0;
            q->done[k] = 0;
            /* The ends are known already. */
            if (rank[k] == 0 || rank[k] + 1 == q->n) {
                q->key[k] = rank[k] == 0 ? q->kmin : q->kmax;
                q->done[k] = 1;
            }
        }
        if (!q->overflow) {
            from_table(q);
            q->pass = 1;
            return XQ_OK;
        }
        q->g[0].count = q->n;
    }
    q->pass++;
    memset(ng, 0, sizeof ng);
    for (k = 0; k < q->ngroup; k++) {
        xq_group *g = &q->g[k];
        if (g->seen != g->count)
            return q->err = XQ_ECHANGED;
        if (!g->nb)
            qsort(g->keys, g->nkeys, sizeof *g->keys, cmp_key);
    }
    for (j = 0; j < q->nrank; j++) {
        xq_group *g;
        size_t cum = 0, b, nbk;
        uint64_t prefix;
        int bits, i;
        if (q->done[j])
            continue;
        g = &q->g[q->rgroup[j]];
        if (!g->nb) {
            q->key[j] = g->keys[q->rrest[j]];
            q->done[j] = 1;
            continue;
        }
        nbk = (size_t)1 << g->nb;
        for (b = 0; b < nbk && cum + g->hist[b] <= q->rrest[j]; b++)
            cum += g->hist[b];
        bits = g->bits + g->nb;
        prefix = (bits - g->nb > 0 ? g->prefix << g->nb : 0) | (uint64_t)b;
        if (bits == 64) {
            q->key[j] = prefix;
            q->done[j] = 1;
            continue;
        }
        for (i = 0; i < nng; i++)
            if (ng[i].prefix == prefix && ng[i].bits == bits)
                break;
        if (i == nng) {
            ng[i].prefix = prefix;
            ng[i].bits = bits;
            ng[i].count = g->hist[b];
            if (ng[i].count <= q->store_max) {
                ng[i].keys = malloc((ng[i].count ? ng[i].count : 1) * sizeof *ng[i].keys);
            } else {
                ng[i].nb = 64 - bits < XQ_BITS_NEXT ? 64 - bits : XQ_BITS_NEXT;
                ng[i].hist = calloc((size_t)1 << ng[i].nb, sizeof *ng[i].hist);
            }
            nng++;
            if (!ng[i].keys && !ng[i].hist) {
                q->err = XQ_ENOMEM;
            }
        }
        q->rgroup[j] = i;
        q->rrest[j] -= cum;
        left++;
    }
    free_groups(q);
    memcpy(q->g, ng, sizeof ng);
    q->ngroup = nng;
    if (q->err)
        return q->err;
    return left ? XQ_AGAIN : XQ_OK;
}

double xq_value(const xquant *q, int k)
{
    return value_of(q->key[k]);
}

double xq_min(const xquant *q)
{
    return value_of(q->kmin);
}

double xq_max(const xquant *q)
{
    return value_of(q->kmax);
}
