/* index_cache.h - the engine's side of sg_index_cache (see sagitta.h). */
#ifndef SG_INDEX_CACHE_H
#define SG_INDEX_CACHE_H

#include <mpfr.h>
#include <stdint.h>

#include "internal.h"
#include "sagitta.h"

/* sg_system_glass_index_mpfr(sys, g, out, um), from the cache when it
 * holds the same inputs (every number of g, um's value, the system's
 * environment, out's precision), computed and kept otherwise.  The value
 * is the one a fresh computation gives, bit for bit.  cache may be NULL. */
int sg_index_cache_glass(sg_index_cache *cache, const sg_system *sys, const sg_glass *g,
                         mpfr_t out, const mpfr_t um);

/* The cache's paraxial memo (sg_paraxial_mpfr_memo), made on first use;
 * NULL without a cache or memory. */
struct sg_parax_memo *sg_index_cache_parax(sg_index_cache *cache);

/* The cache's prepared-surface memo (trace_internal.h) for n surfaces,
 * made on first use and emptied when n changes; NULL without a cache or
 * memory. */
struct sg_prep_memo *sg_index_cache_prep(sg_index_cache *cache, int n);

/* Each surface's generation in sys: a number that changes whenever the
 * surface's bits differ from those of the last call, and is never
 * reused, so equal numbers mean equal bits.  n numbers, valid until the
 * next call; NULL without a cache or memory.  With copy, *copy is
 * sg_system_clone(sys), made in the same pass (NULL when NULL is
 * returned). */
const uint64_t *sg_index_cache_gens(sg_index_cache *cache, const sg_system *sys,
                                    sg_system **copy);

/* The cache's validation memo (internal.h) for n surfaces, as above. */
sg_valid_memo *sg_index_cache_valid(sg_index_cache *cache, int n);

/* How many surfaces the prepared-surface and validation memos gave so
 * far (tests check the memos are used). */
void sg_index_cache_reused(const sg_index_cache *cache, unsigned long *prep,
                           unsigned long *valid);

/* sg_indices_mpfr (trace_internal.h) with its glass indices from cache. */
int sg_indices_mpfr_cached(const sg_system *sys, const sg_catalog *cat, int wave,
                           mpfr_t *idx, sg_index_cache *cache, sg_diag *d);

#endif
