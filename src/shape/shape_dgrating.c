/*
 * shape_dgrating.c - Zemax's diffraction grating (TYPE DGRATING): a plane
 * or conic surface (its radius and conic, traced by the methods' own
 * kernels) ruled with lines parallel to its local x axis, T lines per
 * micrometre, diffracting into order m (sagitta-design(5), SURFACE TYPES).
 *
 * The phase the rulings add is 2 pi m T y (y in micrometres): the lines
 * are equally spaced in their projection on the x-y plane, so on a curved
 * substrate the grating vector is the y axis projected on the tangent
 * plane, g = e_y - (e_y . N) N.  The ray's tangential part follows the
 * grating equation in vector form,
 *
 *   |n'| d'_t = |n| d_t + m lambda T g,
 *
 * lambda in micrometres (in air, as the indices are relative to air), and
 * its normal part is what makes d' a unit vector, on the far side for a
 * transmission grating and on the near side for a reflection one.  On a
 * plane, n' sin(theta') = n sin(theta) + m lambda T in the y-z plane: the
 * sign Zemax's files take (tests/test_dgrating.c).  Where |d'_t| > 1 the
 * order does not propagate: the ray fails with SG_EEVANESCENT.  The
 * optical path gains the phase over 2 pi, m lambda T y.
 */
#include <math.h>

#include "shape.h"

/* The unnormalised normal the methods use: (0, 0, -1) on a plane, (x, y,
 * k1 z - R) on a conic. */
static void normal_d(const sg_sprep *s, const double p[3], double g[3])
{
    if (s->shape == SHAPE_PLANE) {
        g[0] = g[1] = 0.0;
        g[2] = -1.0;
    } else {
        g[0] = p[0];
        g[1] = p[1];
        g[2] = s->k1.hi * p[2] - s->R;
    }
}

/* In double (classic): d in place, the phase added to *opl; 0, or
 * SG_EEVANESCENT. */
int sg_grating_bend_d(const sg_sprep *s, const double p[3], double d[3], double *opl)
{
    double g[3], gn, dn, gy, v[3], a, sg;
    int k;
    normal_d(s, p, g);
    gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (k = 0; k < 3; k++)
        g[k] /= gn;
    dn = d[0] * g[0] + d[1] * g[1] + d[2] * g[2];
    gy = g[1];
    for (k = 0; k < 3; k++)
        v[k] = s->mu.hi * (d[k] - dn * g[k]) + s->gk / s->na * ((k == 1) - gy * g[k]);
    a = 1.0 - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(a >= 0.0))
        return SG_EEVANESCENT;
    sg = (dn >= 0.0 ? 1.0 : -1.0) * (s->mirror ? -1.0 : 1.0);
    for (k = 0; k < 3; k++)
        d[k] = v[k] + sg * sqrt(a) * g[k];
    *opl += s->gk * p[1];
    return 0;
}

static dd dot3(dd3 a, dd3 b)
{
    return dd_add(dd_add(dd_mul(a.x, b.x), dd_mul(a.y, b.y)), dd_mul(a.z, b.z));
}

/* In double-double (precise), on one ray, with its bounds. */
int sg_grating_bend_dd(const sg_sprep *s, sg_pray *r)
{
    dd3 g, v;
    dd gn, dn, gy, a, q = dd_div_d(dd_from(s->gk), s->na), sq;
    double sens, dN, sg, gain;
    if (s->shape == SHAPE_PLANE) {
        g.x = g.y = dd_from(0.0);
        g.z = dd_from(-1.0);
        sens = 0.0;
    } else {
        g.x = r->p.x;
        g.y = r->p.y;
        g.z = dd_sub(dd_mul(s->k1, r->p.z), dd_from(s->R));
        sens = fmax(1.0, fabs(s->k1.hi));
    }
    gn = dd_sqrt(dot3(g, g));
    /* How far the unit normal turns for the point's error. */
    dN = 2.0 * sens * r->eP / fmax(gn.hi, 1e-300);
    g.x = dd_div(g.x, gn);
    g.y = dd_div(g.y, gn);
    g.z = dd_div(g.z, gn);
    dn = dot3(r->d, g);
    gy = g.y;
    v.x = dd_sub(dd_mul(s->mu, dd_sub(r->d.x, dd_mul(dn, g.x))), dd_mul(q, dd_mul(gy, g.x)));
    v.y = dd_add(dd_mul(s->mu, dd_sub(r->d.y, dd_mul(dn, g.y))),
                 dd_mul(q, dd_sub(dd_from(1.0), dd_mul(gy, g.y))));
    v.z = dd_sub(dd_mul(s->mu, dd_sub(r->d.z, dd_mul(dn, g.z))), dd_mul(q, dd_mul(gy, g.z)));
    a = dd_sub(dd_from(1.0), dot3(v, v));
    if (!(a.hi >= 0.0))
        return SG_EEVANESCENT;
    sq = dd_sqrt(a);
    sg = (dn.hi >= 0.0 ? 1.0 : -1.0) * (s->mirror ? -1.0 : 1.0);
    if (sg < 0.0)
        sq = dd_neg(sq);
    r->d.x = dd_add(v.x, dd_mul(sq, g.x));
    r->d.y = dd_add(v.y, dd_mul(sq, g.y));
    r->d.z = dd_add(v.z, dd_mul(sq, g.z));
    /* The tangential part moves by (mu + |q|) (eD + 2 dN) at most, and the
     * normal part by that over its own size (the square root's slope),
     * bounded below as a refraction's is; then the roundings. */
    gain = (s->mu.hi + fabs(q.hi)) * (r->eD + 2.0 * dN);
    r->eD = 2.0 * gain * (1.0 + 1.0 / fmax(fabs(sq.hi), sqrt(1e-300))) + 2.0 * dN +
            128.0 * DD_U * (s->mu.hi + fabs(q.hi) + 1.0) / fmax(fabs(sq.hi), 1e-150);
    r->opl = dd_add(r->opl, dd_mul(dd_from(s->gk), r->p.y));
    r->eO = sg_bound_up(r->eO + fabs(s->gk) * (r->eP + 4.0 * DD_U * fabs(r->p.y.hi)) +
                        4.0 * DD_U * fabs(r->opl.hi));
    return 0;
}

/* In MPFR (the mpfr method): D in place, the phase added to opl; t holds
 * 8 scratch variables.  0 or SG_EEVANESCENT. */
int sg_grating_bend_mp(const sg_sprep *s, mpfr_srcptr mu, mpfr_srcptr R, mpfr_srcptr k1,
                       mpfr_ptr P[3], mpfr_ptr D[3], mpfr_ptr opl, mpfr_t *t)
{
    mpfr_ptr g[3] = {t[0], t[1], t[2]}, v[3] = {t[3], t[4], t[5]}, x = t[6], q = t[7];
    int k, sg;
    if (s->shape == SHAPE_PLANE) {
        mpfr_set_zero(g[0], 1);
        mpfr_set_zero(g[1], 1);
        mpfr_set_si(g[2], -1, MPFR_RNDN);
    } else {
        mpfr_set(g[0], P[0], MPFR_RNDN);
        mpfr_set(g[1], P[1], MPFR_RNDN);
        mpfr_mul(g[2], k1, P[2], MPFR_RNDN);
        mpfr_sub(g[2], g[2], R, MPFR_RNDN);
    }
    mpfr_sqr(x, g[0], MPFR_RNDN);
    mpfr_fma(x, g[1], g[1], x, MPFR_RNDN);
    mpfr_fma(x, g[2], g[2], x, MPFR_RNDN);
    mpfr_sqrt(x, x, MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_div(g[k], g[k], x, MPFR_RNDN);
    /* x = d . N; v = mu (d - x N) + q (e_y - N_y N). */
    mpfr_mul(x, D[0], g[0], MPFR_RNDN);
    mpfr_fma(x, D[1], g[1], x, MPFR_RNDN);
    mpfr_fma(x, D[2], g[2], x, MPFR_RNDN);
    sg = (mpfr_sgn(x) >= 0 ? 1 : -1) * (s->mirror ? -1 : 1);
    mpfr_set_d(q, s->gk, MPFR_RNDN);
    mpfr_div_d(q, q, s->na, MPFR_RNDN);
    for (k = 0; k < 3; k++) {
        mpfr_mul(v[k], x, g[k], MPFR_RNDN);
        mpfr_sub(v[k], D[k], v[k], MPFR_RNDN);
        mpfr_mul(v[k], v[k], mu, MPFR_RNDN);
    }
    for (k = 0; k < 3; k++) {
        /* q (e_y - N_y N) into v, through D[k] as scratch (D is rewritten). */
        mpfr_mul(D[k], g[1], g[k], MPFR_RNDN);
        if (k == 1)
            mpfr_ui_sub(D[k], 1, D[k], MPFR_RNDN);
        else
            mpfr_neg(D[k], D[k], MPFR_RNDN);
        mpfr_fma(v[k], q, D[k], v[k], MPFR_RNDN);
    }
    mpfr_sqr(x, v[0], MPFR_RNDN);
    mpfr_fma(x, v[1], v[1], x, MPFR_RNDN);
    mpfr_fma(x, v[2], v[2], x, MPFR_RNDN);
    mpfr_ui_sub(x, 1, x, MPFR_RNDN);
    if (mpfr_sgn(x) < 0)
        return SG_EEVANESCENT;
    mpfr_sqrt(x, x, MPFR_RNDN);
    if (sg < 0)
        mpfr_neg(x, x, MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_fma(D[k], x, g[k], v[k], MPFR_RNDN);
    mpfr_mul_d(x, P[1], s->gk, MPFR_RNDN);
    mpfr_add(opl, opl, x, MPFR_RNDN);
    return 0;
}

/* Every general row (the radius and conic of its substrate among them),
 * and its rulings: lines per micrometre divide by the part's expansion,
 * the order stays. */
static const sg_shape_key dgrating_keys[] = {
    {"grating_lines", 0, -1, 0}, {"grating_order", 0, 0, 0}, {NULL, 0, 0, 0}};
static const sg_zmx_map dgrating_zmx[] = {{0, 1, "grating_lines", 0, 1, 0},
                                          {0, 2, "grating_order", 0, 1, 0},
                                          {0, 0, NULL, 0, 0, 0}};
const sg_shape_type sg_shape_dgrating_type = {
    .type = SG_SURF_DGRATING,
    .name = "diffraction grating",
    .keys = dgrating_keys,
    .parm_lo = 1,
    .parm_hi = 2,
    .parm_what = "a diffraction grating has the lines per micrometre (PARM 1) and the order "
                 "(PARM 2)",
    .zmx = dgrating_zmx,
    .xdat_what = "a diffraction grating has no extra data"};
