/*
 * shape_biconic.c - Zemax's biconic: z = (cx x^2 + cy y^2) / (1 + sqrt(1
 * - (1 + kx) cx^2 x^2 - (1 + ky) cy^2 y^2)), with cy and ky the surface's
 * radius and conic and cx, kx its x radius and conic (an x radius of 0
 * or inf is flat in x) (sagitta-design(5), SURFACE TYPES).  Its double
 * and double-double kernels are shape_biconic_k.h, which shape_vd.h and
 * shape_vdd.h also compile on lanes.
 */
#include <math.h>

#include "shape.h"

/* bic_d and bic_dd, written once with their lane forms. */
#define SG_TMPL 1 /* SG_TMPL_D */
#include "shape_tmpl_on.h"
#include "shape_biconic_k.h"
#include "shape_tmpl_off.h"
#define SG_TMPL 3 /* SG_TMPL_DD */
#include "shape_tmpl_on.h"
#include "shape_biconic_k.h"
#include "shape_tmpl_off.h"

/* One section's slope, (2 c u D + N k1 c (c u) / S) / D^2, with cu = c u
 * and k1 = 1 + its conic; t[8] and t[11] are scratch. */
static void slope_mp(mpfr_ptr g, mpfr_srcptr k1, mpfr_srcptr c, mpfr_srcptr cu, mpfr_srcptr N,
                     mpfr_srcptr S, mpfr_srcptr D, mpfr_t *t)
{
    mpfr_mul(t[8], k1, c, MPFR_RNDN);
    mpfr_mul(t[8], t[8], cu, MPFR_RNDN);
    mpfr_mul(t[8], t[8], N, MPFR_RNDN);
    mpfr_div(t[8], t[8], S, MPFR_RNDN);
    mpfr_mul(t[11], cu, D, MPFR_RNDN);
    mpfr_mul_2ui(t[11], t[11], 1, MPFR_RNDN);
    mpfr_add(g, t[11], t[8], MPFR_RNDN);
    mpfr_div(g, g, D, MPFR_RNDN);
    mpfr_div(g, g, D, MPFR_RNDN);
}

static int bic_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
                  mpfr_ptr gx, mpfr_ptr gy, mpfr_t *t)
{
    const sg_surface *f = s->src;
    mpfr_ptr cx = t[0], cy = t[1], N = t[2], Q = t[3], S = t[4], D = t[5];
    (void)mc;
    mpfr_set_ui(cx, 1, MPFR_RNDN);
    mpfr_set_ui(cy, 1, MPFR_RNDN);
    if (isfinite(s->Rx))
        mpfr_div_d(cx, cx, s->Rx, MPFR_RNDN);
    else
        mpfr_set_zero(cx, 1);
    if (isfinite(s->R))
        mpfr_div_d(cy, cy, s->R, MPFR_RNDN);
    else
        mpfr_set_zero(cy, 1);
    /* t6 = cx x, t7 = cy y */
    mpfr_mul(t[6], cx, x, MPFR_RNDN);
    mpfr_mul(t[7], cy, y, MPFR_RNDN);
    mpfr_mul(N, t[6], x, MPFR_RNDN);
    mpfr_mul(t[8], t[7], y, MPFR_RNDN);
    mpfr_add(N, N, t[8], MPFR_RNDN);
    /* Q = 1 - (1 + kx)(cx x)^2 - (1 + ky)(cy y)^2, conics exact */
    mpfr_set_d(t[9], f->conic_x, MPFR_RNDN);
    mpfr_add_ui(t[9], t[9], 1, MPFR_RNDN);
    mpfr_sqr(t[8], t[6], MPFR_RNDN);
    mpfr_mul(t[8], t[8], t[9], MPFR_RNDN);
    mpfr_ui_sub(Q, 1, t[8], MPFR_RNDN);
    mpfr_set_d(t[10], f->conic, MPFR_RNDN);
    mpfr_add_ui(t[10], t[10], 1, MPFR_RNDN);
    mpfr_sqr(t[8], t[7], MPFR_RNDN);
    mpfr_mul(t[8], t[8], t[10], MPFR_RNDN);
    mpfr_sub(Q, Q, t[8], MPFR_RNDN);
    if (mpfr_sgn(Q) <= 0)
        return 0;
    mpfr_sqrt(S, Q, MPFR_RNDN);
    mpfr_add_ui(D, S, 1, MPFR_RNDN);
    mpfr_div(z, N, D, MPFR_RNDN);
    slope_mp(gx, t[9], cx, t[6], N, S, D, t);
    slope_mp(gy, t[10], cy, t[7], N, S, D, t);
    return 1;
}

const sg_shape_ops sg_shape_biconic_ops = {"biconic", NULL, NULL, bic_d, bic_dd, bic_mp};

static const sg_shape_key bic_keys[] = {{"radius_x", 0, 1, 0}, {"conic_x", 0, 0, 0}, {NULL, 0, 0, 0}};
static const sg_zmx_map bic_zmx[] = {{0, 1, "radius_x", 0, 1, SG_ZMX_ZERO_INF},
                                     {0, 2, "conic_x", 0, 1, 0},
                                     {0, 0, NULL, 0, 0, 0}};
const sg_shape_type sg_shape_biconic_type = {
    .type = SG_SURF_BICONIC, .name = "biconic", .ops = &sg_shape_biconic_ops, .keys = bic_keys,
    .parm_lo = 1, .parm_hi = 2,
    .parm_what = "a biconic has the x radius and x conic (PARM 1 and 2)", .zmx = bic_zmx};
