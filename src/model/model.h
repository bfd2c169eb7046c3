/*
 * model.h - the interface of model/ (the system, its parameters, solves'
 * rules, frames, materials, pupils and configurations) to the other
 * subsystems, beside what sagitta.h makes public.  The model sits on
 * core/ and shape/ (a surface's type is a record there).
 */
#ifndef SG_MODEL_H
#define SG_MODEL_H

#include <mpfr.h>
#include <stdint.h>

#include "core.h"
#include "sagitta.h"

/* The index a trace of sys uses for glass g: sg_glass_index_env_mpfr at the
 * system's temperature and pressure when sys->adjust_index is set, else
 * the catalog's sg_glass_index_mpfr. */
int sg_system_glass_index_mpfr(const sg_system *sys, const sg_glass *g, mpfr_t out,
                               const mpfr_t um);

/* sg_system_validate for functions that validate on the caller's behalf:
 * the error, if any, without repeating the warnings. */
int sg_system_check(const sg_system *sys, const sg_catalog *cat, sg_diag *d);

/* What sg_system_validate found of each surface last time (kept in an
 * sg_index_cache, for one number of surfaces n): surface i's own checks,
 * the ones that read only its bits and whether it is the object, the
 * image or between them, passed for the surface bits surf[i] when ok[i]
 * is set.  The checks that read other things (its frame changes against
 * the stop, the track, the catalog, the warnings) run every time. */
typedef struct sg_valid_memo {
    int n;
    uint64_t *gen;    /* the generations the entries were made from */
    const uint64_t *cur; /* the surfaces' generations now (sg_index_cache_gens) */
    unsigned char *ok;
    unsigned long reused; /* surfaces whose own checks were skipped, for tests */
} sg_valid_memo;

/* sg_system_validate with a memo (NULL: none): the same result, message
 * and warnings. */
int sg_system_validate_memo(const sg_system *sys, const sg_catalog *cat, sg_diag *d,
                            sg_valid_memo *m);

/* Where rays are launched, after the object along its axis: at surface
 * 1's place, or, for an object on that place (thickness 0, which Zemax
 * allows), this many lens units beyond it, so that a ray's launch point
 * is not its object point; the transfer into surface 1 steps back. */
double sg_launch_step(const sg_system *sys);
/* Whether the transfer into surface i (i >= 1) from surface i-1's frame
 * is more than the thickness along z. */
int sg_xfer_moves(const sg_system *sys, int i);
/* That transfer, p_i = A^T (p_{i-1} - b), at the precision of b (A's
 * entries take theirs), from MPFR 32 bits finer. */
int sg_xfer_mpfr(const sg_system *sys, int i, mpfr_t A[3][3], mpfr_t b[3]);

/* A catalog's glasses found in one pass over a system: a design names
 * few glasses on many surfaces, and sg_material_glass's answer depends
 * only on the catalog and the two names, so equal names are looked up
 * once.  Zero it before the pass; the catalog must not change in it. */
enum { SG_GLASS_SEEN = 8 };
typedef struct sg_glass_seen {
    int n, next;
    const sg_material *mat[SG_GLASS_SEEN];
    const sg_glass *g[SG_GLASS_SEEN];
} sg_glass_seen;
const sg_glass *sg_glass_seen_find(sg_glass_seen *gs, const sg_catalog *cat,
                                   const sg_material *m);

/* For messages: " (catalog X)" after a glass named with its catalog,
 * noting a catalog cat does not hold at all; "" otherwise. */
void sg_material_where(const sg_catalog *cat, const sg_material *m, char *buf, size_t n);

/* The file a design was read from (sys->zmx, made by formats/design_zmx.c)
 * begins with this head: copies of a system share it, so it is counted,
 * and the reader's free function releases it, so the model copies and
 * frees systems without knowing the format. */
struct sg_zmx_origin;
typedef struct sg_origin_head {
    int refs;
    void (*free)(struct sg_zmx_origin *o);
} sg_origin_head;
/* One more or one fewer holder of o (NULL is allowed); the last frees it. */
void sg_zmx_origin_retain(struct sg_zmx_origin *o);
void sg_zmx_origin_release(struct sg_zmx_origin *o);

#endif
