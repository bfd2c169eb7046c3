/*
 * trace_internal.h - the prepared system shared by the trace methods,
 * the launch of normalized rays, aiming and the batch driver.
 */
#ifndef SG_TRACE_INTERNAL_H
#define SG_TRACE_INTERNAL_H

/* First, so that an instruction-set variant renames the declarations of
 * sagitta.h and of this file alike. */
#include "isa.h"

#include <mpfr.h>

#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "dd.h"
#include "index_cache.h"
#include "internal.h"
#include "shape.h"
#include "vdd.h"

#define U53 1.1102230246251565e-16 /* unit roundoff of double */

/* The plane, conic and even asphere have kernels of their own in each
 * method; every other shape is SHAPE_GEN, traced through its sg_shape_ops
 * (shape.h), seeded from its base conic as an asphere is. */
enum { SHAPE_PLANE = 0, SHAPE_CONIC = 1, SHAPE_ASPH = 2, SHAPE_GEN = 3 };

/* A transfer into a surface's frame that tilts or decenters (frame.c):
 * p_i = A^T (p_{i-1} - b), d_i = A^T d_{i-1}.  The plain step along z of
 * an untilted system has none, and keeps its exact subtraction. */
typedef struct sg_xfer {
    dd At[3][3];      /* A transposed, each entry rounded from MPFR */
    dd b[3];
    double Atd[3][3]; /* the same in double, for classic */
    double bd[3];
    double grow;      /* A^T's largest row sum, rounded up */
} sg_xfer;

/* One surface, reduced to what the per-ray code reads. */
typedef struct sg_sprep {
    int shape;
    double R;    /* vertex radius; inf for a flat base */
    double c;    /* 1/R rounded, used only for double estimates */
    dd k1;       /* 1 + conic, exact */
    double T;    /* vertex distance from the previous surface along z */
    int nasph;   /* asphere terms in use */
    double a[SG_NASPH];
    int mirror;
    dd mu;       /* |n before| / |n after|, for refraction */
    dd mu2;      /* mu squared, as the bend would form it */
    double sd;   /* clip radius, 0 for none */
    int aper;    /* sg_aperture_type of the surface aperture */
    double ap_a, ap_b;   /* circular: min and max radius; else x and y half widths */
    double ap_dx, ap_dy; /* the aperture's decenter */
    double zg;   /* vertex z in classic's frame (surface 1's until a transfer turns it) */
    const sg_xfer *xf; /* the transfer into this surface, when it turns or moves */
    const sg_shape *shp; /* SHAPE_GEN: the shape and its ops */
    /* A paraxial surface (shape_paraxial.c): an ideal lens on the plane,
     * c = 1 / (N' f), |N| and |N'|, and the z of the conjugates its
     * optical path term is perfect for (inf: at infinity; set after the
     * surfaces are prepared, from the paraxial marginal ray). */
    int ideal;
    double ic, nb, na;
    double pz, qz;
    /* A diffraction grating (shape_dgrating.c): m lambda T at the tracer's
     * wavelength (set after the surfaces are prepared); nb, na as above. */
    int grating;
    double gk;
    /* A phase surface (shape_phase.c): its phase polynomial P in x / norm
     * and y / norm (radians for order 1), and pk = m lambda / (2 pi),
     * lambda in lens units at the tracer's wavelength (set after the
     * surfaces are prepared); nb, na as above. */
    const sg_shape *phase;
    double pk;
} sg_sprep;

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

/* 1 + conic is exactly 1 on spheres, where a product by it is the other
 * factor itself and is skipped. */
static inline int sg_sprep_sphere(const sg_sprep *s)
{
    return s->k1.hi == 1.0 && s->k1.lo == 0.0;
}

/* A flat surface between equal indices leaves a ray's direction exactly
 * as it is (the normal is exact and nothing can reflect totally), so the
 * bend is skipped: dummy planes are common in real designs. */
static inline int sg_sprep_passes(const sg_sprep *s)
{
    return s->shape == SHAPE_PLANE && !s->mirror && !s->ideal && !s->grating && !s->phase &&
           fabs(s->mu.hi) == 1.0 &&
           s->mu.lo == 0.0;
}

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

/* Ray state of the precise method: position on the current surface in its
 * frame, unit direction, and running bounds on both errors. */
typedef struct sg_pray {
    dd3 p, d;
    double eP, eD;
    dd opl;    /* optical path so far */
    double eO; /* bound on its error */
} sg_pray;

/* The paraxial surface's bend and optical path term (shape_paraxial.c),
 * in the three arithmetics: classic's double, precise's double-double on
 * one ray (with its bounds), and MPFR (t: 12 scratch variables). */
void sg_ideal_bend_d(const sg_sprep *s, const double p[3], double d[3], double *opl);
void sg_ideal_bend_dd(const sg_sprep *s, sg_pray *r);
void sg_ideal_bend_mp(const sg_sprep *s, mpfr_srcptr mu, mpfr_ptr P[3], mpfr_ptr D[3],
                      mpfr_ptr opl, mpfr_t *t);
/* The diffraction grating's bend (shape_dgrating.c) in the same three:
 * 0, or SG_EEVANESCENT for an order that does not propagate (t: 8
 * scratch variables). */
int sg_grating_bend_d(const sg_sprep *s, const double p[3], double d[3], double *opl);
int sg_grating_bend_dd(const sg_sprep *s, sg_pray *r);
int sg_grating_bend_mp(const sg_sprep *s, mpfr_srcptr mu, mpfr_srcptr R, mpfr_srcptr k1,
                       mpfr_ptr P[3], mpfr_ptr D[3], mpfr_ptr opl, mpfr_t *t);
/* A phase surface's bend (shape_phase.c) in the same three: 0, or
 * SG_EEVANESCENT; mc the phase's coefficients from sg_phase_mp_coefs, t
 * 16 scratch variables. */
int sg_phase_bend_d(const sg_sprep *s, const double p[3], double d[3], double *opl);
int sg_phase_bend_dd(const sg_sprep *s, sg_pray *r);
int sg_phase_bend_mp(const sg_sprep *s, mpfr_t *mc, mpfr_srcptr mu, mpfr_srcptr R,
                     mpfr_srcptr k1, mpfr_ptr P[3], mpfr_ptr D[3], mpfr_ptr opl, mpfr_t *t);
/* A phase surface's phase polynomial into ph (an
 * sg_shape of no ops: deg, norm, c, cm), SG_OK or SG_ERANGE naming
 * surface isurf; its coefficients in MPFR (mc as sg_shape_mp_coefs). */
int sg_phase_prepare(const sg_surface *f, sg_shape *ph, int isurf, sg_diag *d);
void sg_phase_mp_coefs(const sg_shape *ph, mpfr_t *mc, mpfr_prec_t prec);
/* Surface i's paraxial power from its phase at um micrometres: -lambda M
 * c02 / (pi norm^2), lambda in lens units; 0 for other types. */
double sg_phase_power(const sg_system *sys, int i, double um);

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

/* A bound computed in floating point must not round down past the error
 * it bounds, so it is nudged up by more than its own rounding. */
static inline double sg_bound_up(double b)
{
    return b * (1.0 + 8.0 * U53);
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

/* Paraxial data at MPFR precision prec, in paraxial.c.  idx holds the
 * signed index after every surface (n entries, at least prec bits). */
typedef struct sg_parax_mp {
    mpfr_t efl, bfl, image_dist, epd, enp, exp_diam, exp_pos, image_fnum,
        working_fnum, object_na, pimg_h, mag, track, stop_r;
    mpfr_t pimg_slope; /* paraxial image height per unit tan(field) or object height */
    /* The same at the paraxial image plane (the image surface's when the
     * image is afocal): Zemax's paraxial-image-height fields are defined
     * there, while its distortion is referred to the image surface. */
    mpfr_t pimg_slope_f;
} sg_parax_mp;

void sg_parax_mp_init(sg_parax_mp *p, mpfr_prec_t prec);
void sg_parax_mp_clear(sg_parax_mp *p);
void sg_parax_to_double(const sg_parax_mp *p, sg_paraxial *o);
/* The axial object point's marginal slope for an object NA or cone angle
 * aperture (paraxial.c). */
int sg_object_slope_mpfr(const sg_system *sys, const mpfr_t n0, mpfr_t out, sg_diag *d);
int sg_paraxial_mpfr(const sg_system *sys, mpfr_t *idx, int wave, mpfr_prec_t prec,
                     sg_parax_mp *out, sg_diag *d);
/* The same, resuming each y-nu trace after the last surface whose inputs
 * (radius, thickness, index, and the one before) and the trace's start
 * are those memo last saw: the same bits.  memo may be NULL. */
typedef struct sg_parax_memo sg_parax_memo;
int sg_paraxial_mpfr_memo(const sg_system *sys, mpfr_t *idx, int wave, mpfr_prec_t prec,
                          sg_parax_mp *out, sg_diag *d, sg_parax_memo *memo);
sg_parax_memo *sg_parax_memo_new(void);
void sg_parax_memo_free(sg_parax_memo *memo);
unsigned long sg_parax_memo_resumes(const sg_parax_memo *memo);
/* Signed indices after every surface at wavelength wave, into idx[0..n-1]. */
int sg_indices_mpfr(const sg_system *sys, const sg_catalog *cat, int wave,
                    mpfr_t *idx, sg_diag *d);

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

#endif
