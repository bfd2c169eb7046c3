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
 * q) with q = sgn(u) sqrt(u^2 - x^2).
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

static int tor_d(const sg_shape *s, double x, double y, double *z, double g[2], double *h)
{
    double zy, w, dw, zp, zpp, u, disc, q, zt, hxx, hxy, hyy;
    if (!sg_rot_d(s, y * y, &zy, &w, &dw))
        return 0;
    zp = w * y;
    /* |zy''| at most, from |w| and the magnitude dw. */
    zpp = fabs(w) + 2.0 * dw * y * y;
    if (!isfinite(s->Rx)) {
        *z = zy;
        g[0] = 0.0;
        g[1] = zp;
        *h = 1.5 * fabs(zpp);
        return 1;
    }
    u = s->Rx - zy;
    disc = u * u - x * x;
    if (disc < 0.0)
        return 0;
    q = copysign(sqrt(disc), u);
    zt = x * x / (u + q);
    *z = zy + zt;
    g[0] = x / q;
    g[1] = u * zp / q;
    hxx = u * u / (disc * fabs(q));
    hxy = fabs(x * u * zp) / (disc * fabs(q));
    hyy = (zp * zp + fabs(u * zpp)) / fabs(q) + u * u * zp * zp / (disc * fabs(q));
    *h = 1.5 * (hxx + 2.0 * hxy + hyy);
    return 1;
}

static int tor_dd(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg)
{
    dd y2 = dd_sqr(y), zy, w, zp, u, disc, q, zt;
    double ezy, ew, ezp, eu, cond, aq;
    if (!sg_rot_dd(s, y2, &zy, &w, &ezy, &ew))
        return 0;
    ezy += 4.0 * DD_U * fabs(w.hi) * y2.hi;
    zp = dd_mul(w, y);
    ezp = (ew + 4.0 * DD_U * fabs(w.hi)) * fabs(y.hi);
    if (!isfinite(s->Rx)) {
        *z = zy;
        g[0] = dd_from(0.0);
        g[1] = zp;
        *ez = ezy;
        *eg = ezp;
        return 1;
    }
    u = dd_sub(dd_from(s->Rx), zy);
    disc = dd_sub(dd_sqr(u), dd_sqr(x));
    if (disc.hi <= 0.0)
        return 0;
    q = dd_sqrt(disc);
    if (u.hi < 0.0)
        q = dd_neg(q);
    zt = dd_div(dd_sqr(x), dd_add(u, q));
    *z = dd_add(zy, zt);
    g[0] = dd_div(x, q);
    g[1] = dd_div(dd_mul(u, zp), q);
    /* u carries zy's error and its own rounding; u^2 - x^2 may cancel. */
    eu = ezy + 2.0 * DD_U * (fabs(s->Rx) + fabs(zy.hi));
    cond = (u.hi * u.hi + x.hi * x.hi) / disc.hi;
    aq = fabs(q.hi);
    *ez = ezy + eu * fabs(u.hi) / aq + 16.0 * DD_U * (fabs(zy.hi) + fabs(zt.hi) * (1.0 + cond));
    *eg = 16.0 * DD_U * (fabs(g[0].hi) + fabs(g[1].hi)) * (1.0 + cond) +
          eu * (fabs(x.hi * u.hi) + fabs(zp.hi) * (u.hi * u.hi + disc.hi)) / (disc.hi * aq) +
          ezp * fabs(u.hi) / aq;
    return 1;
}

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
