/* index_cache.c - glass indices kept between tracers of one design.
 *
 * The editor makes new tracers after every edit, and each computes every
 * glass's index in MPFR several times (the tracer, its launch, the
 * paraxial data, the mpfr method).  An edit seldom changes a glass or a
 * wavelength, so the caller keeps an sg_index_cache and passes it in; an
 * index is computed once per set of inputs.  The key is every number the
 * computation reads, so a hit is the fresh value exactly. */
#include "trace_int.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* prec, um, adjust, temperature, pressure, formula, the coefficients,
 * lmin, lmax, nd, vd, td, tref, ed, has_td, has_ed. */
#define KEY_N (5 + 1 + SG_GLASS_NCOEF + 4 + 6 + 1 + 4 + 2)

/* Past this many indices the cache starts again (a design has a few
 * glasses and wavelengths; this only bounds a long session's memory). */
#define CACHE_MAX 4096

typedef struct entry {
    double key[KEY_N];
    uint64_t hash;
    mpfr_t val;
    int used;
} entry;

struct sg_index_cache {
    entry *e;
    size_t cap, n; /* cap a power of two, or 0 */
    unsigned long hits, misses;
    /* The paraxial traces' states after each surface, for the next
     * tracer of the same design (paraxial.c). */
    struct sg_parax_memo *pm;
    /* The last tracer's prepared surfaces (trace.c). */
    sg_prep_memo *prep;
    /* What the last validation found of each surface (system.c). */
    sg_valid_memo *valid;
    /* Every surface's bits as last seen and a number that changes with
     * them (sg_index_cache_gens): the memos compare numbers, not bytes. */
    sg_surface *seen;
    uint64_t *gen;
    int nseen;
    uint64_t next_gen;
};

void sg_index_cache_reused(const sg_index_cache *cache, unsigned long *prep,
                           unsigned long *valid)
{
    if (prep)
        *prep = cache && cache->prep ? cache->prep->reused : 0;
    if (valid)
        *valid = cache && cache->valid ? cache->valid->reused : 0;
}

static void valid_free(sg_valid_memo *m)
{
    if (!m)
        return;
    free(m->gen);
    free(m->ok);
    free(m);
}

sg_valid_memo *sg_index_cache_valid(sg_index_cache *cache, int n)
{
    sg_valid_memo *m;
    if (!cache || n < 1)
        return NULL;
    if (cache->valid && cache->valid->n == n)
        return cache->valid;
    valid_free(cache->valid);
    cache->valid = m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->n = n;
    m->gen = calloc((size_t)n, sizeof *m->gen);
    m->ok = calloc((size_t)n, 1);
    if (!m->gen || !m->ok) {
        valid_free(m);
        cache->valid = NULL;
    }
    return cache->valid;
}

static void prep_free(sg_prep_memo *m)
{
    if (!m)
        return;
    free(m->gen);
    free(m->idx); /* sg_mp_block_new: one allocation, nothing to clear */
    free(m->sp);
    free(m->xf);
    free(m->nsigned);
    free(m->ok);
    free(m->has_xf);
    free(m);
}

struct sg_prep_memo *sg_index_cache_prep(sg_index_cache *cache, int n)
{
    sg_prep_memo *m;
    if (!cache || n < 1)
        return NULL;
    if (cache->prep && cache->prep->n == n)
        return cache->prep;
    prep_free(cache->prep);
    cache->prep = m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->n = n;
    m->gen = calloc((size_t)n, sizeof *m->gen);
    m->idx = sg_mp_block_new((size_t)n, 256);
    m->sp = calloc((size_t)n, sizeof *m->sp);
    m->xf = calloc((size_t)n, sizeof *m->xf);
    m->nsigned = calloc((size_t)n, sizeof *m->nsigned);
    m->ok = calloc((size_t)n, 1);
    m->has_xf = calloc((size_t)n, 1);
    if (!m->gen || !m->idx || !m->sp || !m->xf || !m->nsigned || !m->ok || !m->has_xf) {
        prep_free(m);
        cache->prep = NULL;
        return NULL;
    }
    return m;
}


struct sg_parax_memo *sg_index_cache_parax(sg_index_cache *cache)
{
    if (!cache)
        return NULL;
    if (!cache->pm)
        cache->pm = sg_parax_memo_new();
    return cache->pm;
}

sg_index_cache *sg_index_cache_new(void)
{
    return calloc(1, sizeof(sg_index_cache));
}

static void clear_entries(sg_index_cache *c)
{
    size_t i;
    for (i = 0; i < c->cap; i++)
        if (c->e[i].used)
            mpfr_clear(c->e[i].val);
    free(c->e);
    c->e = NULL;
    c->cap = c->n = 0;
}

void sg_index_cache_clear(sg_index_cache *c)
{
    if (!c)
        return;
    clear_entries(c);
    sg_parax_memo_free(c->pm);
    c->pm = NULL;
    prep_free(c->prep);
    c->prep = NULL;
    valid_free(c->valid);
    c->valid = NULL;
    free(c->seen);
    free(c->gen);
    c->seen = NULL;
    c->gen = NULL;
    c->nseen = 0;
    /* next_gen keeps counting: a number is never given twice. */
}

const uint64_t *sg_index_cache_gens(sg_index_cache *c, const sg_system *sys,
                                    sg_system **copy)
{
    int i, n = sys->nsurf, fresh;
    sg_system *cl = NULL;
    if (copy)
        *copy = NULL;
    if (!c || n < 1)
        return NULL;
    if (copy) {
        /* sg_system_clone's copy, made in the same pass: each surface is
         * read once for both. */
        cl = malloc(sizeof *cl);
        if (!cl)
            return NULL;
        *cl = *sys;
        sg_zmx_origin_retain(cl->zmx);
        sg_configs_retain(cl->configs);
        cl->capsurf = n;
        cl->surf = malloc((size_t)n * sizeof *cl->surf);
        if (!cl->surf) {
            sg_zmx_origin_release(cl->zmx);
            sg_configs_release(cl->configs);
            free(cl);
            return NULL;
        }
    }
    fresh = c->nseen != n;
    if (fresh) {
        sg_surface *s = malloc((size_t)n * sizeof *s);
        uint64_t *g = malloc((size_t)n * sizeof *g);
        if (!s || !g) {
            free(s);
            free(g);
            sg_system_free(cl);
            return NULL;
        }
        free(c->seen);
        free(c->gen);
        c->seen = s;
        c->gen = g;
        c->nseen = n;
    }
    /* One comparison of each surface with its last bits; a changed
     * surface gets a number no surface had before, so a memo entry
     * holding a surface's number was made from its present bits. */
    for (i = 0; i < n; i++) {
        const sg_surface *si = &sys->surf[i];
        if (fresh || memcmp(&c->seen[i], si, sizeof *si) != 0) {
            memcpy(&c->seen[i], si, sizeof *si);
            c->gen[i] = ++c->next_gen;
        }
        if (cl)
            memcpy(&cl->surf[i], si, sizeof *si);
    }
    if (copy)
        *copy = cl;
    return c->gen;
}

void sg_index_cache_free(sg_index_cache *c)
{
    sg_index_cache_clear(c);
    free(c);
}

unsigned long sg_index_cache_resumes(const sg_index_cache *c)
{
    return c ? sg_parax_memo_resumes(c->pm) : 0;
}

void sg_index_cache_stats(const sg_index_cache *c, unsigned long *hits, unsigned long *misses)
{
    if (hits)
        *hits = c ? c->hits : 0;
    if (misses)
        *misses = c ? c->misses : 0;
}

static void make_key(double *k, const sg_system *sys, const sg_glass *g, mpfr_prec_t prec,
                     double um)
{
    int i, n = 0;
    k[n++] = (double)prec;
    k[n++] = um;
    k[n++] = sys && sys->adjust_index ? 1.0 : 0.0;
    k[n++] = sys ? sys->temperature : 0.0;
    k[n++] = sys ? sys->pressure : 0.0;
    k[n++] = (double)g->formula;
    for (i = 0; i < SG_GLASS_NCOEF; i++)
        k[n++] = g->c[i];
    k[n++] = g->lmin;
    k[n++] = g->lmax;
    k[n++] = g->nd;
    k[n++] = g->vd;
    for (i = 0; i < 6; i++)
        k[n++] = g->td[i];
    k[n++] = g->tref;
    for (i = 0; i < 4; i++)
        k[n++] = g->ed[i];
    k[n++] = (double)g->has_td;
    k[n++] = (double)g->has_ed;
}

/* A multiply-xor over the key's words: equal bits, equal hash. */
static uint64_t key_hash(const double *k)
{
    uint64_t h = UINT64_C(0x9e3779b97f4a7c15), w;
    size_t i;
    for (i = 0; i < KEY_N; i++) {
        memcpy(&w, &k[i], sizeof w);
        h = (h ^ w) * UINT64_C(0xff51afd7ed558ccd);
        h ^= h >> 29;
    }
    return h;
}

static entry *find(sg_index_cache *c, const double *k, uint64_t h)
{
    size_t i;
    if (!c->cap)
        return NULL;
    for (i = (size_t)h & (c->cap - 1);; i = (i + 1) & (c->cap - 1)) {
        entry *e = &c->e[i];
        if (!e->used)
            return e;
        if (e->hash == h && memcmp(e->key, k, sizeof e->key) == 0)
            return e;
    }
}

/* Room for one more entry, growing or starting again; 0 without memory. */
static int make_room(sg_index_cache *c)
{
    size_t i, oldcap;
    entry *old;
    if (c->n >= CACHE_MAX)
        clear_entries(c);
    if (c->cap && 2 * (c->n + 1) <= c->cap)
        return 1;
    old = c->e;
    oldcap = c->cap;
    c->cap = oldcap ? 2 * oldcap : 64;
    c->e = calloc(c->cap, sizeof *c->e);
    if (!c->e) {
        c->e = old;
        c->cap = oldcap;
        return 0;
    }
    for (i = 0; i < oldcap; i++)
        if (old[i].used)
            /* mpfr_t is a one-element array: the struct moves whole. */
            *find(c, old[i].key, old[i].hash) = old[i];
    free(old);
    return 1;
}

int sg_index_cache_glass(sg_index_cache *c, const sg_system *sys, const sg_glass *g,
                         mpfr_t out, const mpfr_t um)
{
    double k[KEY_N], umd;
    uint64_t h;
    entry *e;
    int rc;

    if (!c || !g || !mpfr_number_p(um))
        return sg_system_glass_index_mpfr(sys, g, out, um);
    /* The wavelength is a double in every caller; one that is not is not
     * kept. */
    umd = mpfr_get_d(um, MPFR_RNDN);
    if (mpfr_cmp_d(um, umd) != 0)
        return sg_system_glass_index_mpfr(sys, g, out, um);
    make_key(k, sys, g, mpfr_get_prec(out), umd);
    h = key_hash(k);
    e = find(c, k, h);
    if (e && e->used) {
        c->hits++;
        mpfr_set(out, e->val, MPFR_RNDN);
        return SG_OK;
    }
    c->misses++;
    rc = sg_system_glass_index_mpfr(sys, g, out, um);
    /* Failures are not kept: the caller reports them, and they are rare. */
    if (rc != SG_OK || !make_room(c))
        return rc;
    e = find(c, k, h);
    memcpy(e->key, k, sizeof e->key);
    e->hash = h;
    mpfr_init2(e->val, mpfr_get_prec(out));
    mpfr_set(e->val, out, MPFR_RNDN);
    e->used = 1;
    c->n++;
    return rc;
}
