/*
 * trace_int.h - what only trace/'s own files share: the prepared system
 * shared by the trace methods, the launch of normalized rays, aiming, the
 * batch driver, and the engine's side of sg_index_cache (see sagitta.h).
 */
#ifndef SG_TRACE_INT_H
#define SG_TRACE_INT_H

/* First, so that an instruction-set variant renames the declarations of
 * sagitta.h and of this file alike. */
#include "isa.h"

#include <mpfr.h>

#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dd.h"
#include "model.h"
#include "shape.h"
#include "trace.h"
#include "vdd.h"

/* The prepared surfaces of the last tracer made with an sg_index_cache,
 * for the next one (prepare_surfaces in trace.c).  Surface i's sg_sprep
 * (but zg, the one sum over surfaces), transfer and signed index are read
 * from surfaces i - 1 and i and their 256-bit indices only, so entry i is
 * reused when those are the same bits as when it was made.  Surfaces with
 * a shape of their own (sg_shape_ops_of) are always prepared afresh. */
typedef struct sg_prep_memo {
    int n;
    uint64_t *gen;    /* the generations of the surfaces the entries were made from */
    mpfr_t *idx;      /* their indices, 256 bits, one block */
    sg_sprep *sp;     /* xf and shp not kept: has_xf says whether xf is set */
    sg_xfer *xf;
    double *nsigned;
    unsigned char *ok, *has_xf;
    unsigned long reused; /* surfaces taken from the memo, for tests */
} sg_prep_memo;

/* Launch constants of normalized rays, for one precision. */
typedef struct sg_launch {
    int obj_inf;     /* object at infinity */
    dd T0;           /* object vertex to surface 1 */
    dd enp;          /* entrance pupil z in surface 1's frame */
    dd epr;          /* entrance pupil radius */
    dd stop_r;       /* stop radius that aiming lands Py = 1 on */
    dd fx, fy;       /* field scale for Hx and Hy */
    dd pimg_slope;   /* paraxial image height per unit object-space tan or height */
    dd pimg_slope_f; /* the same at the paraxial image plane (sg_parax_mp) */
    int straight;    /* every surface between 1 and the stop leaves a ray straight */
    dd zstop;        /* the stop's vertex in surface 1's frame */
    /* Object-space telecentric: pupil point (px, py) is the direction of
     * slope (px, py) times tslope = tan(asin(NA / n0)) from the object
     * point, the limit of the paraxial pupil plane moved to infinity. */
    int tele;
    dd tslope;
} sg_launch;

typedef struct sg_mpfr_ctx sg_mpfr_ctx;

/* Object-space part of a launch: a direction for an object at infinity,
 * else an object point in surface 1's frame. */
typedef struct osp {
    int inf;
    dd3 dir;
    dd3 obj;
    dd lam; /* aiming off: enp / dir.z at infinity, else -obj.z / (enp - obj.z);
             * telecentric: -obj.z, the object point's distance to surface 1 */
    double n0; /* |index| of object space */
    /* At infinity, the optical path's start plane: the primary chief
     * ray's point on surface 1 dotted with dir (0 until the field's chief
     * ray is known, and where it fails). */
    dd plane;
} osp;

/* A field's launch data as launch.c's field_cached left it, keyed by
 * (hx, hy) bit for bit; used is 0 for an empty entry. */
enum { SG_FIELD_MEMO = 16 };
typedef struct sg_field_memo {
    int used;
    double hx, hy;
    osp field;
    int have_aimJ;
    double aimJ[2][2];
} sg_field_memo;

/* A tracer is two parts.  The prepared model (sys, o, wave, n, sp, xf,
 * shp, nsigned, px, ln, cat) is made once by sg_tracer_open and never
 * changes afterwards, so forks (sg_tracer_fork) share it and a thread
 * never writes it.  The workspace (unclipped, the field and aiming
 * caches, scratch, mp, rescue, and prim, a fork's own) belongs to one
 * tracer.  The options stay as the caller gave them. */
struct sg_tracer {
    const sg_tracer *model; /* the tracer whose prepared part this one shares, or NULL */
    sg_system *sys;
    sg_trace_opts o;
    int wave;
    int n;
    sg_sprep *sp;
    sg_xfer *xf;       /* nsurf entries when any transfer turns or moves */
    sg_shape *shp;     /* nsurf entries when any surface is SHAPE_GEN */
    double *nsigned;   /* index after each surface, negative after odd mirrors */
    sg_paraxial px;
    sg_launch ln;
    /* Workspace.  While aiming lands rays, apertures do not stop them:
     * unclipped is then set (the options' clip stays as given). */
    int unclipped;
    /* The current field point's object-space launch, so a grid over the
     * pupil pays for the field's tangent once. */
    int have_field;
    double last_hx, last_hy;
    osp field;
    int have_aimJ;     /* aimJ belongs to the current field */
    double aimJ[2][2]; /* the field's landing Jacobian at its chief ray */
    /* The fields met before, so rays in any field order pay for each
     * field once (launch.c, field_cached). */
    int field_slot;    /* fmemo's entry of the current field, or -1 */
    int fmemo_next;    /* the entry the next new field takes */
    sg_field_memo fmemo[SG_FIELD_MEMO];
    sg_ray_surface *scratch; /* nsurf entries for aiming traces */
    const sg_catalog *cat;   /* must outlive the tracer */
    sg_mpfr_ctx *mp;   /* only for the mpfr method */
    sg_mpfr_ctx *rescue; /* the precise method's MPFR root for rays it cannot certify */
    /* The same system at the primary wavelength, when this tracer's is
     * another: pupil, aperture and fields are defined there. */
    struct sg_tracer *prim;
    /* The caller's glass indices, only while the tracer is made. */
    sg_index_cache *icache;
    /* The caller's mpfr ray memo (sg_tracer_use_memo), never a fork's. */
    sg_mpfr_memo *memo;
};

/* The state of SG_VL precise rays between surfaces, lane by lane: what
 * sg_pray holds for one ray. */
typedef struct sg_vray {
    vdd3 p, d;
    vd eP, eD;
    vdd opl;
    vd eO;
} sg_vray;

/* Lane k of v to and from one ray's state. */
static inline void sg_vray_get(const sg_vray *v, int k, sg_pray *r)
{
    r->p.x.hi = v->p.x.hi[k];
    r->p.x.lo = v->p.x.lo[k];
    r->p.y.hi = v->p.y.hi[k];
    r->p.y.lo = v->p.y.lo[k];
    r->p.z.hi = v->p.z.hi[k];
    r->p.z.lo = v->p.z.lo[k];
    r->d.x.hi = v->d.x.hi[k];
    r->d.x.lo = v->d.x.lo[k];
    r->d.y.hi = v->d.y.hi[k];
    r->d.y.lo = v->d.y.lo[k];
    r->d.z.hi = v->d.z.hi[k];
    r->d.z.lo = v->d.z.lo[k];
    r->eP = v->eP[k];
    r->eD = v->eD[k];
    r->opl.hi = v->opl.hi[k];
    r->opl.lo = v->opl.lo[k];
    r->eO = v->eO[k];
}

static inline void sg_vray_put(sg_vray *v, int k, const sg_pray *r)
{
    v->p.x.hi[k] = r->p.x.hi;
    v->p.x.lo[k] = r->p.x.lo;
    v->p.y.hi[k] = r->p.y.hi;
    v->p.y.lo[k] = r->p.y.lo;
    v->p.z.hi[k] = r->p.z.hi;
    v->p.z.lo[k] = r->p.z.lo;
    v->d.x.hi[k] = r->d.x.hi;
    v->d.x.lo[k] = r->d.x.lo;
    v->d.y.hi[k] = r->d.y.hi;
    v->d.y.lo[k] = r->d.y.lo;
    v->d.z.hi[k] = r->d.z.hi;
    v->d.z.lo[k] = r->d.z.lo;
    v->eP[k] = r->eP;
    v->eD[k] = r->eD;
    v->opl.hi[k] = r->opl.hi;
    v->opl.lo[k] = r->opl.lo;
    v->eO[k] = r->eO;
}

/* b takes a's state in the lanes of m. */
static inline void sg_vray_sel(vm m, const sg_vray *a, sg_vray *b)
{
    b->p.x = vdd_sel(m, a->p.x, b->p.x);
    b->p.y = vdd_sel(m, a->p.y, b->p.y);
    b->p.z = vdd_sel(m, a->p.z, b->p.z);
    b->d.x = vdd_sel(m, a->d.x, b->d.x);
    b->d.y = vdd_sel(m, a->d.y, b->d.y);
    b->d.z = vdd_sel(m, a->d.z, b->d.z);
    b->eP = vsel(m, a->eP, b->eP);
    b->eD = vsel(m, a->eD, b->eD);
    b->opl = vdd_sel(m, a->opl, b->opl);
    b->eO = vsel(m, a->eO, b->eO);
}

/* Traces surfaces 1..upto from a ray on or before surface 1 (frame 1).
 * path0 is the path already travelled before the start point.
 * Fills out[1..upto]; returns the ray status.  The state r is left on
 * surface upto, which is not bent when upto is not the image. */
int sg_precise_run_to(const sg_tracer *t, sg_pray *r, double path0, sg_ray_surface *out,
                      int upto);
/* The same from surface from, with r as it left surface from - 1 (bent)
 * and still in that surface's frame; from = 1 is sg_precise_run_to. */
int sg_precise_run_from(const sg_tracer *t, sg_pray *r, double path0, sg_ray_surface *out,
                        int from, int upto);
/* The precise trace itself, on nl <= SG_VL rays at once in vector form
 * (in trace_vec.c): lane k < nl with start[k] <= upto starts at surface
 * start[k] from lane k of v and path0, as sg_precise_run_from takes one
 * ray, fills out[k], gets rc[k] and leaves its final state (its state
 * where it stopped, for a ray that failed) in lane k of v.  Other lanes
 * are not traced, not written and keep their state and rc.  The lanes do
 * not interact: a ray gets the same bits whatever rays share its call. */
void sg_precise_block(const sg_tracer *t, sg_vray *v, vd path0, sg_ray_surface *const *out,
                      int nl, const int *start, int upto, int *rc);
/* Completes surface i < n - 1 for the lanes of m, which a trace to upto =
 * i left on it with finite bounds: its aperture, the bend and the
 * direction columns of out[k][i], exactly as a trace through i would; a
 * lane is then ready for surface i + 1, or gets its failure in rc[k] and
 * its rows from sg_fail_rest.  Other lanes keep their state and rc. */
void sg_precise_finish(const sg_tracer *t, int i, sg_vray *v, sg_ray_surface *const *out,
                       vm m, int *rc);
/* The sag of s at radius^2 r2 on SG_VL lanes, in double-double as the
 * precise trace forms it; *bad marks lanes outside the conic's domain. */
vdd sg_sag_v(const sg_sprep *s, vdd r2, vm *bad);
/* Whether s's fixed semi-diameter or aperture stops a ray meeting it at
 * (x, y), edges widened in the ray's favour by rtol (aperture.c); every
 * method asks this. */
int sg_clip_point(const sg_sprep *s, double x, double y, double rtol);
/* Whether clipping at s stops a ray meeting it at (x, y). */
int sg_past_clip(const sg_tracer *t, const sg_sprep *s, double x, double y);
/* The classic method (trace_classic_vec.c) on nl <= SG_VL rays at once:
 * lane k < nl starts at S[k] along D[k] (not necessarily unit) in
 * surface 1's frame, fills out[k][1..upto] and gets its status in rc[k].
 * The lanes do not interact: a ray gets the same bits whatever rays share
 * its call. */
void sg_classic_block(const sg_tracer *t, const double (*S)[3], const double (*D)[3],
                      sg_ray_surface *const *out, int nl, int upto, int *rc);
/* One ray by sg_classic_block, alone in its block. */
int sg_classic_run_to(const sg_tracer *t, const double S[3], const double D[3],
                      sg_ray_surface *out, int upto);

/* Spacing of doubles at |x|, from its exponent bits (no libm call). */
static inline double sg_ulp_of(double x)
{
    uint64_t b;
    int e;
    x = fabs(x);
    if (!(x < DBL_MAX))
        return x;
    if (x < DBL_MIN)
        return DBL_TRUE_MIN;
    memcpy(&b, &x, sizeof b);
    e = (int)(b >> 52);
    b = (uint64_t)(e - 52) << 52;
    if (e <= 52)
        return ldexp(1.0, e - 1075);
    memcpy(&x, &b, sizeof x);
    return x;
}

/* fmax(|a|, fmax(|b|, |c|)) without a call into libm. */
static inline double sg_max_abs3(double a, double b, double c)
{
    double A = fabs(a), B = fabs(b), C = fabs(c), m = B > C || C != C ? B : C;
    return A > m || m != m ? A : m;
}

/* The last check of every method: the first row marked OK whose point,
 * direction, bound or path is not finite fails with SG_ERANGE, with the
 * rest not reached (the object row of an object at infinity keeps its
 * infinite point).  Returns the ray's status, rc when nothing failed. */
int sg_guard_rows(const sg_tracer *t, sg_ray_surface *out, int rc);
/* Marks surface from as failed with status and the rest as not reached. */
void sg_fail_rest(sg_ray_surface *out, int from, int n, int status);
/* Fills the object row from a start point and a unit direction. */
void sg_set_start_row(sg_ray_surface *o, const double S[3], const double u[3]);

/* Surface evaluation shared by the methods. */
double sg_sprep_sag_resid(const sg_sprep *s, double x, double y, double z);
/* The sag of s at (x, y) in double-double on SG_VL lanes, as
 * sg_sag_v for every shape; *bad marks lanes outside its domain. */
vdd sg_sag_xy_v(const sg_sprep *s, vdd x, vdd y, vm *bad);

/* The batch on nt prepared tracers, one per thread (in batch.c).  With
 * sel, ray r keeps surfaces sel[0..nsel-1] at out[r * nsel]; scratch
 * then holds nt * SG_BATCH_LANES * nsurf rows, enough for the widest
 * instruction-set variant (the caller may be compiled for a narrower one).
 * Returns SG_OK or SG_ENOMEM. */
#define SG_BATCH_LANES 8
int sg_batch_run(sg_tracer *const *t, int nt, sg_ray_kind kind, const sg_ray_in *rays,
                 size_t nray, const int *sel, int nsel, sg_ray_surface *scratch,
                 sg_ray_surface *out, int *status);

/* The OPD's helpers shared by opd.c and its vector form, opd_vec.c
 * (built once per instruction set, as batch.c): one micrometre in the
 * system's lens units, and each coordinate's error bound of a row's
 * point whose error_bound is eb. */
#define SG_SQRT3 1.7320508075688772
double sg_um_in_units(const sg_system *sys);
void sg_point_errors(const sg_tracer *t, double x, double y, double z, double eb, double e[3]);

/* A tracer sharing t's prepared model, with a workspace of its own (its
 * own MPFR context for the mpfr method, and a fork of t's primary-
 * wavelength tracer): what a thread of the batch traces with.  t must
 * outlive it.  SG_OK, or SG_ENOMEM. */
int sg_tracer_fork(const sg_tracer *t, sg_tracer **out, sg_diag *d);

/* Launch of normalized rays, in launch.c. */
int sg_launch_prepare(sg_tracer *t, sg_diag *d);
/* Forgets every field's launch data (a tracer whose method changes). */
static inline void sg_field_forget(sg_tracer *t)
{
    int i;
    t->have_field = 0;
    t->field_slot = -1;
    for (i = 0; i < SG_FIELD_MEMO; i++)
        t->fmemo[i].used = 0;
}
int sg_launch_precise(sg_tracer *t, double hx, double hy, double px, double py,
                      sg_ray_surface *out);
/* The launch of the precise method up to surface 1: fills the object row
 * and the start state, or fails every row and returns the status. */
int sg_launch_precise_prep(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out, sg_pray *r, double *path0);
/* sg_launch_precise_prep for nl <= SG_VL pupil points of field (hx, hy),
 * aimed together, into the vector state v and path0 that sg_precise_block
 * goes on from; the aiming traces write rows 1..stop of out[k].  Every lane
 * equals the single-ray launch bit for bit.  A lane whose last aiming trace
 * already reached the stop goes on from there: rows 1..stop filled, bent
 * at the stop and start[k] = stop + 1; others start[k] = 1, and their trace
 * writes every row again.  A lane that failed gets rc[k] and start[k] =
 * n, past any surface; the others rc[k] = SG_OK. */
void sg_launch_precise_block(sg_tracer *t, double hx, double hy, const double (*pupil)[2],
                             int nl, sg_ray_surface *const *out, sg_vray *v, vd *path0,
                             int *start, int *rc);
int sg_start_precise_prep(const sg_tracer *t, const double start[3], const double dir[3],
                          sg_ray_surface *out, sg_pray *r);
int sg_launch_classic(sg_tracer *t, double hx, double hy, double px, double py,
                      sg_ray_surface *out);
/* The launch of the classic method up to its start: fills the object row,
 * the start point S and direction D that sg_classic_block takes, and for
 * an object at infinity (*inf set) the optical path *off from the field's
 * start plane to the start; or fails every row and returns the status. */
int sg_launch_classic_prep(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out, double S[3], double D[3], double *off,
                           int *inf);
/* Adds the path off to the optical path of every surface a classic ray
 * reached (an object at infinity, after sg_launch_classic_prep). */
void sg_launch_classic_path(const sg_tracer *t, double off, sg_ray_surface *out);
/* The start of the classic method for a ray given by a start point and a
 * direction: checks the ray and fills the object row, or fails every row
 * and returns SG_EINVAL. */
int sg_start_classic_prep(const sg_tracer *t, const double start[3], const double dir[3],
                          sg_ray_surface *out);
/* A start direction whose squares would overflow or underflow (1e308 or
 * 1e-200 a component) scaled by a power of two, which is exact and keeps
 * its direction, so that its largest component lies in [1, 2); any other
 * direction (and a non-finite or zero one) copied unchanged, so its trace
 * keeps its bits. */
void sg_dir_scale(const double in[3], double out[3]);

/* The MPFR method, in trace_mpfr.c. */
int sg_mpfr_prepare(sg_tracer *t, sg_diag *d);
void sg_mpfr_free(sg_mpfr_ctx *m);
int sg_mpfr_trace_start(sg_tracer *t, const double S[3], const double D[3],
                        sg_ray_surface *out);
int sg_mpfr_trace_normalized(sg_tracer *t, double hx, double hy, double px,
                             double py, sg_ray_surface *out);
/* A one-surface context for sg_mpfr_rescue_root, or NULL. */
sg_mpfr_ctx *sg_mpfr_rescue_new(void);
/* How many roots sg_mpfr_rescue_root was asked for on m. */
unsigned long sg_mpfr_rescues(const sg_mpfr_ctx *m);
/* The step along D from P (in sp's vertex frame) to the surface sp, found
 * exactly as the mpfr method finds it (onto the tangent plane, the conic
 * root nearest it, Newton), in 320 bits; returns SG_OK, SG_EMISS or
 * SG_ENOCONV. */
int sg_mpfr_rescue_root(sg_mpfr_ctx *m, const sg_sprep *sp, dd3 P, dd3 D, int max_iter,
                        dd *step);

/* n MPFR numbers at precision prec, zero, in one allocation that free()
 * releases: a tracer needs thousands (an index a surface), and one
 * allocation each costs as much as the arithmetic.  Never give them to
 * mpfr_clear, mpfr_set_prec or mpfr_swap with another number.  NULL when
 * out of memory. */
static inline size_t sg_mp_limb_bytes(mpfr_prec_t prec)
{
    return (mpfr_custom_get_size(prec) + 15) & ~(size_t)15;
}

static inline void sg_mp_place(mpfr_ptr x, void *limbs, mpfr_prec_t prec)
{
    mpfr_custom_init(limbs, prec);
    mpfr_custom_init_set(x, MPFR_ZERO_KIND, 0, prec, limbs);
}

static inline mpfr_t *sg_mp_block_new(size_t n, mpfr_prec_t prec)
{
    size_t head = (n * sizeof(mpfr_t) + 15) & ~(size_t)15, sz = sg_mp_limb_bytes(prec), i;
    char *b = malloc(head + n * sz + 1);
    mpfr_t *v = (mpfr_t *)(void *)b;
    if (!b)
        return NULL;
    for (i = 0; i < n; i++)
        sg_mp_place(v[i], b + head + i * sz, prec);
    return v;
}

static inline dd dd_from_mpfr(const mpfr_t x, mpfr_t tmp)
{
    dd r;
    r.hi = mpfr_get_d(x, MPFR_RNDN);
    mpfr_sub_d(tmp, x, r.hi, MPFR_RNDN);
    r.lo = mpfr_get_d(tmp, MPFR_RNDN);
    return r;
}

static inline double dd_to_d(dd a)
{
    return a.hi + a.lo;
}

/* The engine's side of sg_index_cache (see sagitta.h). */

/* sg_system_glass_index_mpfr(sys, g, out, um), from the cache when it
 * holds the same inputs (every number of g, um's value, the system's
 * environment, out's precision), computed and kept otherwise.  The value
 * is the one a fresh computation gives, bit for bit.  cache may be NULL. */
int sg_index_cache_glass(sg_index_cache *cache, const sg_system *sys, const sg_glass *g,
                         mpfr_t out, const mpfr_t um);

/* The cache's paraxial memo (sg_paraxial_mpfr_memo), made on first use;
 * NULL without a cache or memory. */
struct sg_parax_memo *sg_index_cache_parax(sg_index_cache *cache);

/* The cache's prepared-surface memo (above) for n surfaces,
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

/* The cache's validation memo (model.h) for n surfaces, as above. */
sg_valid_memo *sg_index_cache_valid(sg_index_cache *cache, int n);

/* How many surfaces the prepared-surface and validation memos gave so
 * far (tests check the memos are used). */
void sg_index_cache_reused(const sg_index_cache *cache, unsigned long *prep,
                           unsigned long *valid);

/* sg_indices_mpfr (trace.h) with its glass indices from cache. */
int sg_indices_mpfr_cached(const sg_system *sys, const sg_catalog *cat, int wave,
                           mpfr_t *idx, sg_index_cache *cache, sg_diag *d);

#endif
