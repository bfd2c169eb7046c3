/*
 * shape_odd.c - Zemax's odd asphere: a conic plus b_1 r + b_2 r^2 + ...
 * + b_8 r^8 (sagitta-design(5), SURFACE TYPES).  Rotational: the sag and
 * its slope come from the shared rotational part in shape.c.
 */
#include <math.h>

#include "shape.h"

/* odd_d, written once with its lane form (shape_vd.h's sv_odd_d). */
#define SG_TMPL 1 /* SG_TMPL_D */
#define SG_ROT_K_ODD
#include "shape_tmpl_on.h"
#include "shape_rot_k.h"
#include "shape_tmpl_off.h"
#undef SG_ROT_K_ODD

static int odd_dd(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg)
{
    dd r2 = dd_add(dd_sqr(x), dd_sqr(y)), w;
    double ew, m = fmax(fabs(x.hi), fabs(y.hi));
    if (!sg_rot_dd(s, r2, z, &w, ez, &ew))
        return 0;
    /* r^2's own rounding moves the sag by dz/dr^2 = w / 2 times it. */
    *ez += 4.0 * DD_U * fabs(w.hi) * r2.hi;
    g[0] = dd_mul(w, x);
    g[1] = dd_mul(w, y);
    *eg = (ew + 8.0 * DD_U * fabs(w.hi)) * m;
    return 1;
}

static int odd_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
                  mpfr_ptr gx, mpfr_ptr gy, mpfr_t *t)
{
    (void)mc;
    mpfr_sqr(t[8], x, MPFR_RNDN);
    mpfr_sqr(t[9], y, MPFR_RNDN);
    mpfr_add(t[8], t[8], t[9], MPFR_RNDN);
    if (!sg_rot_mp(s, t[8], z, t[10], t))
        return 0;
    mpfr_mul(gx, t[10], x, MPFR_RNDN);
    mpfr_mul(gy, t[10], y, MPFR_RNDN);
    return 1;
}

const sg_shape_ops sg_shape_odd_ops = {"odd asphere", NULL, NULL, odd_d, odd_dd, odd_mp};

/* b_k on r^(k+1) is in lens units^-k. */
static const sg_shape_key odd_keys[] = {{"odd", 0, 0, -1}, {NULL, 0, 0, 0}};
static const sg_zmx_map odd_zmx[] = {{0, 1, "odd", 0, SG_NODD, 0}, {0, 0, NULL, 0, 0, 0}};
const sg_shape_type sg_shape_odd_type = {
    .type = SG_SURF_ODDASPH, .name = "odd asphere", .ops = &sg_shape_odd_ops, .keys = odd_keys,
    .parm_lo = 1, .parm_hi = SG_NODD,
    .parm_what = "the odd asphere has terms r^1 to r^8 (PARM 1 to 8)", .zmx = odd_zmx};
