/*
 * shape_toroid.c - Zemax's toroidal surface: a curve in the y-z plane,
 * zy(y) = conic(y) + a_1 y^2 + ... + a_7 y^14 (the surface's radius,
 * conic and first seven asphere terms), turned about an axis parallel to
 * y at the radius of rotation Rr from the vertex (0 or inf: a cylinder,
 * flat in x) (sagitta-design(5), SURFACE TYPES):
 *
 *   z = Rr - sgn(u) sqrt(u^2 - x^2) = zy + x^2 / (u + sgn(u) sqrt(u^2 - x^2)),
 *   u = Rr - zy,
 *
 * the second form free of cancellation.  Its gradient is (x / q, u zy' /
 * q) with q = sgn(u) sqrt(u^2 - x^2).  Its double and double-double
 * kernels are shape_toroid_k.h, which shape_vd.h and shape_vdd.h also
 * compile on lanes.
 */
#include <math.h>

#include "shape.h"

static int tor_prepare(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d)
{
    (void)f;
    if (s->na > 7)
        return sg_diag_set(d, SG_ERANGE,
                           "surface %d: a toroid's y curve has terms up to y^14; the y^16 term "
                           "must be 0", isurf);
    return SG_OK;
}

/* tor_d and tor_dd, written once with their lane forms. */
#define SG_TMPL 1 /* SG_TMPL_D */
#include "shape_tmpl_on.h"
#include "shape_toroid_k.h"
#include "shape_tmpl_off.h"
#define SG_TMPL 3 /* SG_TMPL_DD */
#include "shape_tmpl_on.h"
#include "shape_toroid_k.h"
#include "shape_tmpl_off.h"

static int tor_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
                  mpfr_ptr gx, mpfr_ptr gy, mpfr_t *t)
{
    (void)mc;
    mpfr_sqr(t[8], y, MPFR_RNDN);
    if (!sg_rot_mp(s, t[8], t[9], t[10], t))
        return 0;
    mpfr_mul(t[10], t[10], y, MPFR_RNDN); /* zy' */
    if (!isfinite(s->Rx)) {
        mpfr_set(z, t[9], MPFR_RNDN);
        mpfr_set_zero(gx, 1);
        mpfr_set(gy, t[10], MPFR_RNDN);
        return 1;
    }
    /* t11 = u, t8 = q */
    mpfr_d_sub(t[11], s->Rx, t[9], MPFR_RNDN);
    mpfr_sqr(t[8], t[11], MPFR_RNDN);
    mpfr_sqr(t[7], x, MPFR_RNDN);
    mpfr_sub(t[8], t[8], t[7], MPFR_RNDN);
    if (mpfr_sgn(t[8]) <= 0)
        return 0;
    mpfr_sqrt(t[8], t[8], MPFR_RNDN);
    if (mpfr_sgn(t[11]) < 0)
        mpfr_neg(t[8], t[8], MPFR_RNDN);
    mpfr_add(t[6], t[11], t[8], MPFR_RNDN);
    mpfr_div(t[7], t[7], t[6], MPFR_RNDN);
    mpfr_add(z, t[9], t[7], MPFR_RNDN);
    mpfr_div(gx, x, t[8], MPFR_RNDN);
    mpfr_mul(gy, t[11], t[10], MPFR_RNDN);
    mpfr_div(gy, gy, t[8], MPFR_RNDN);
    return 1;
}

const sg_shape_ops sg_shape_toroid_ops = {"toroidal", tor_prepare, NULL, tor_d, tor_dd, tor_mp};

/* The y curve's y^2 ... y^14 terms and the radius of rotation; in .zmx
 * PARM 0 is the extrapolate flag of its Zernike terms (which sagitta does
 * not read), 1 the radius of rotation (0: a cylinder), 2 to 8 the terms. */
static const sg_shape_key tor_keys[] = {
    {"asphere", 7, -1, -2}, {"radius_x", 0, 1, 0}, {NULL, 0, 0, 0}};
static const sg_zmx_map tor_zmx[] = {{0, 1, "radius_x", 0, 1, SG_ZMX_ZERO_INF},
                                     {0, 2, "asphere", 0, 7, 0},
                                     {0, 0, NULL, 0, 0, 0}};
const sg_shape_type sg_shape_toroid_type = {
    .type = SG_SURF_TOROIDAL, .name = "toroidal", .ops = &sg_shape_toroid_ops, .keys = tor_keys,
    .parm_lo = 0, .parm_hi = 8, .parm_what = "a toroid has parameters 0 to 8", .zmx = tor_zmx,
    .xdat_what = "a toroid's Zernike terms are not supported"};
