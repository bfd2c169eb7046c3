/*
 * shape.h - the surface-kernel interface.
 *
 * A shape beyond the plane, the conic and the even asphere (which the
 * methods trace with kernels of their own, written for speed) is a sag
 * z = f(x, y) in its vertex frame.  Each such shape is one file
 * (shape_odd.c, shape_toroid.c, shape_biconic.c, shape_zernike.c,
 * shape_xypoly.c, shape_qcon.c) with its record (sg_shape_type, below,
 * named by its row of SG_SURF_TYPES in sagitta.h) that fills an sg_shape
 * and supplies f and its gradient in the three arithmetics the methods
 * use:
 *
 *   - double, with a bound on the second derivatives: classic's trace, the
 *     Newton seeds of precise, and the sizes that scale bounds; both
 *     vector traces evaluate it on all lanes at once through shape_vd.h's
 *     vector twin of each, to the same bits;
 *   - double-double, with bounds on the rounding of f and of its
 *     gradient: the precise method, which evaluates it on all lanes at
 *     once through shape_vdd.h's vector twin of each, to the same bits;
 *   - MPFR at any precision: the mpfr method and precise's rescue.
 *
 * shape.c registers them (sg_shape_ops_of) and holds what they share: the
 * rotational conic and even polynomial, and polynomials in x and y with
 * double-double and MPFR coefficients.  tests/test_shapes.c checks every
 * registered shape against its own definition in 512-bit MPFR.
 */
#ifndef SG_SHAPE_H
#define SG_SHAPE_H

#include "isa.h"

#include <math.h>
#include <mpfr.h>

#include "core.h"
#include "dd.h"

/* Polynomials in u = x / norm and v = y / norm up to this degree (the
 * 37th Fringe Zernike term is of degree 12). */
#define SG_P2_DEG 12
#define SG_P2_N ((SG_P2_DEG + 1) * (SG_P2_DEG + 2) / 2)
/* Index of the coefficient of u^i v^j. */
#define SG_P2_AT(i, j) (((i) + (j)) * ((i) + (j) + 1) / 2 + (j))

/* Scratch an sg_shape_ops.sag_mp may use. */
#define SG_SHAPE_MPTMP 12
/* MPFR variables sg_shape_mp_coefs makes: the coefficients, then room for
 * the powers of u and v. */
#define SG_SHAPE_MPC (SG_P2_N + 2 * (SG_P2_DEG + 1))

typedef struct sg_shape sg_shape;

typedef struct sg_shape_ops {
    const char *name;
    /* Fills what is the shape's own in s from f (shape.c has set the
     * rest); SG_OK, or SG_ERANGE with a message naming surface isurf.
     * May be NULL. */
    int (*prepare)(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d);
    /* Sets the polynomial's coefficients in mc (initialised to zero at
     * their precision) from s->src.  May be NULL. */
    void (*mp_coefs)(const sg_shape *s, mpfr_t *mc);
    /* f at (x, y), its gradient g = (df/dx, df/dy) and in *h a bound on
     * the second derivatives (the largest absolute row sum of the Hessian),
     * in double.  Returns 0 outside the shape's domain. */
    int (*sag_d)(const sg_shape *s, double x, double y, double *z, double g[2], double *h);
    /* The same in double-double, with *ez bounding |z - f(x, y)| and *eg
     * each component's error, for the x and y given. */
    int (*sag_dd)(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg);
    /* The same in MPFR at z's precision; mc holds the coefficients that
     * sg_shape_mp_coefs made, tmp SG_SHAPE_MPTMP variables of scratch. */
    int (*sag_mp)(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
                  mpfr_ptr gx, mpfr_ptr gy, mpfr_t *tmp);
} sg_shape_ops;

/* A parameter a surface type reads beyond those every surface has (the
 * surface table's rows marked SG_PARAM_SHAPE, src/model/param.c): its key, how
 * many of its elements the type reads (0: all), and its thermal rule,
 * the power of lens units its element k is in, p0 + pk k (sg_thermal
 * scales it by s^(p0 + pk k): 1 multiplies by s, 0 keeps it, a negative
 * power divides by s to the opposite power).  A key that ends in '.' is
 * every key it begins (a frame change's "before."). */
typedef struct sg_shape_key {
    const char *key;
    int n;
    int p0, pk;
} sg_shape_key;

/* A run of a type's values in a .zmx surface block: PARM (or XDAT) index
 * + j holds element elem + j of key, j < n; written in this order. */
typedef struct sg_zmx_map {
    int xdat;      /* 0: PARM, 1: XDAT */
    int index;
    const char *key;
    int elem, n;
    unsigned flags; /* SG_ZMX_* */
} sg_zmx_map;

#define SG_ZMX_ZERO_INF 0x1u /* 0 in the file is an infinite radius, and back */
#define SG_ZMX_IF_SET 0x2u   /* written only when some element of the run is not 0 */

/* A surface type: one record, one row of SG_SURF_TYPES (sagitta.h) that
 * names it sg_shape_<record>_type.  Everything the engine knows of the
 * type outside its kernels is here. */
typedef struct sg_shape_type {
    int type;             /* its sg_surf_type */
    const char *name;     /* in messages and tests */
    const sg_shape_ops *ops; /* NULL: the methods' own kernels (standard,
                              * even asphere, coordinate break) */
    /* The parameters it reads, ended by a NULL key; only: it reads no
     * other (a coordinate break), else also every row without
     * SG_PARAM_SHAPE. */
    const sg_shape_key *keys;
    int only;
    /* The .zmx surface block (design_zmx.c): the PARM numbers lo to hi
     * it may hold (others must be 0; why, in parm_what), its runs ended
     * by a NULL key; zmx_terms: XDAT 1 the number of terms, at most this,
     * XDAT 2 the normalization radius, XDAT 3 on the terms (0: none);
     * xdat_what: XDAT 3 on must be 0, and why; extrapolate: PARM 0 is
     * Zemax's extrapolate flag, written 1. */
    int parm_lo, parm_hi;
    const char *parm_what;
    const sg_zmx_map *zmx;
    int zmx_terms;
    const char *xdat_what;
    int extrapolate;
} sg_shape_type;

/* The record of each type, as SG_SURF_TYPES names it. */
#define SG_SHAPE_DECL_(name, json, zmx, rec) extern const sg_shape_type sg_shape_##rec##_type;
SG_SURF_TYPES(SG_SHAPE_DECL_)
#undef SG_SHAPE_DECL_

/* Whether a type is a phase surface (shape_phase.c). */
int sg_phase_type(int type);
/* The record of a surface type, or NULL for a value that is none. */
const sg_shape_type *sg_shape_type_of(int type);
/* Whether the type's record lists the parameter key. */
int sg_shape_reads(int type, const char *key);

/* A prepared shape: what its ops read. */
struct sg_shape {
    const sg_shape_ops *ops;
    int type;     /* sg_surf_type */
    double R;     /* base radius (the y-z section's for toroid and biconic); inf: flat */
    double k1;    /* 1 + its conic */
    double Rx;    /* biconic: x radius; toroid: radius of rotation; inf: flat */
    double kx1;   /* biconic: 1 + x conic */
    int na;       /* even terms in use: a[k] on r^(2k+2) (toroid: y^(2k+2)) */
    double a[SG_NASPH];
    int nodd;     /* odd asphere terms in use: odd[k] on r^(k+1) */
    double odd[SG_NODD];
    int deg;      /* polynomial in u, v: degree, 0 for none */
    double norm;  /* u = (x - px) / norm, v = (y - py) / norm */
    double px, py; /* the polynomial's centre: a Zernike sag's decenter, else 0 */
    int nz;       /* terms summed into each coefficient */
    dd c[SG_P2_N]; /* its coefficients, rounded to double-double from exact sums */
    double cm[SG_P2_N]; /* the magnitude of each coefficient's terms, for bounds */
    const sg_surface *src; /* the surface, for MPFR coefficients */
};

/* The ops of a surface type (its record's), or NULL for the types the
 * methods trace with their own kernels (standard, even asphere,
 * coordinate break). */
const sg_shape_ops *sg_shape_ops_of(int type);
/* Fills s from surface f; returns SG_OK or SG_ERANGE with a message. */
int sg_shape_prepare(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d);
/* The polynomial's coefficients at precision prec into mc[SG_SHAPE_MPC] (each
 * initialised here; the caller clears them with sg_shape_mp_clear). */
void sg_shape_mp_coefs(const sg_shape *s, mpfr_t *mc, mpfr_prec_t prec);
void sg_shape_mp_clear(mpfr_t *mc);

/* The sag of a prepared shape at (x, y) in double, NaN outside it. */
double sg_shape_sag(const sg_shape *s, double x, double y);

/* What the shapes share (shape.c). */

/* The rotational conic and even polynomial at r2 = x^2 + y^2: sag, w =
 * sag'(r) / r and w' = dw / d(r^2) in double; 0 outside the conic. */
int sg_rot_d(const sg_shape *s, double r2, double *z, double *w, double *dw);
/* In double-double: sag and w, and bounds on their errors. */
int sg_rot_dd(const sg_shape *s, dd r2, dd *z, dd *w, double *ez, double *ew);
int sg_rot_mp(const sg_shape *s, mpfr_srcptr r2, mpfr_ptr z, mpfr_ptr w, mpfr_t *tmp);

/* Adds A (of terms of size mag) to the coefficient at index at. */
void sg_p2_add(sg_shape *s, int at, dd A, double mag);
/* Checks f's normalization radius and sets s->nz from its terms. */
int sg_p2_terms(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d);
/* The polynomial in u, v: value and gradient in x and y. */
void sg_p2_d(const sg_shape *s, double x, double y, double *z, double g[2], double *h);
void sg_p2_dd(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg);
void sg_p2_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
              mpfr_ptr gx, mpfr_ptr gy, mpfr_t *tmp);

/* The rotational part plus the polynomial: the whole sag of the Zernike
 * and XY shapes, in the three arithmetics of sg_shape_ops. */
int sg_rot_p2_d(const sg_shape *s, double x, double y, double *z, double g[2], double *h);
int sg_rot_p2_dd(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg);
int sg_rot_p2_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
                 mpfr_ptr gx, mpfr_ptr gy, mpfr_t *tmp);

/* The ops of each shape file. */
extern const sg_shape_ops sg_shape_odd_ops, sg_shape_toroid_ops, sg_shape_biconic_ops,
    sg_shape_zernike_ops, sg_shape_xypoly_ops;

/* The Zernike term j of kind as a polynomial in u, v: integer
 * coefficients e[SG_P2_N] times sqrt(*nsq) (shape_zernike.c). */
int sg_zernike_poly(int standard, int j, long long *e, long *nsq);

/* What the methods read of a prepared surface, shared with the shapes'
 * own bends (shape_paraxial.c, shape_dgrating.c). */

/* Unit roundoff of double. */
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

/* A bound computed in floating point must not round down past the error
 * it bounds, so it is nudged up by more than its own rounding. */
static inline double sg_bound_up(double b)
{
    return b * (1.0 + 8.0 * U53);
}

#endif
