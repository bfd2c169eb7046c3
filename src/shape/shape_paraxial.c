/*
 * shape_paraxial.c - Zemax's paraxial surface: an ideal thin lens of focal
 * length f on a plane (sagitta-design(5), SURFACE TYPES).
 *
 * A ray that meets the plane at (x, y) with direction tangents t = (l/n,
 * m/n) leaves with N' t' = N t - (x, y) / f, N and N' the signed indices
 * before and after: every ray from a point of the front focal plane leaves
 * parallel, and any plane is imaged onto its conjugate plane without
 * aberration (n' / s' + n / s = 1 / f).  In direction cosines that is the
 * unit vector along (mu l - c x n, mu m - c y n, n), mu = |N| / |N'| and c =
 * 1 / (N' f), which needs no division by n.
 *
 * Zemax adds an optical path at the surface so that the lens is perfect
 * at its conjugates: the term makes the path from the object point P the
 * ray comes from to the image point P' it goes to the same for every ray
 * through the lens.  P and P' are the points where the ray's lines before
 * and after cross the planes z = pz and z = qz, the conjugates of the
 * paraxial marginal ray (trace.c, prepare_surfaces), so the term needs no
 * other ray.  For the line X + lambda d through P:
 *
 *   A = |N| sigma (|P| - |lambda|) = |N| sigma (|X|^2 + 2 lambda X.d) / (|P| + |lambda|)
 *
 * with sigma = 1 for a real point (behind the ray, lambda < 0), -1 for a
 * virtual one, and A = -|N| X.d for a point at infinity (the limit of
 * both); B likewise with N', d' and P' (sigma' = 1 ahead).  The term is
 * A + B.  The quotient form keeps the digits a difference of lengths
 * would lose.
 */
#include <math.h>

#include "shape.h"

/* The direction and the optical path's term in double (classic). */
void sg_ideal_bend_d(const sg_sprep *s, const double p[3], double d[3], double *opl)
{
    double v[3], len, a, b, X2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    double xd = p[0] * d[0] + p[1] * d[1] + p[2] * d[2], lam, P;
    v[0] = s->mu.hi * d[0] - s->ic * p[0] * d[2];
    v[1] = s->mu.hi * d[1] - s->ic * p[1] * d[2];
    v[2] = d[2];
    len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (isinf(s->pz) || d[2] == 0.0) {
        a = -s->nb * xd;
    } else {
        lam = (s->pz - p[2]) / d[2];
        P = sqrt(fmax(0.0, X2 + 2.0 * lam * xd + lam * lam));
        a = (lam < 0.0 ? 1.0 : -1.0) * s->nb * (X2 + 2.0 * lam * xd) / (P + fabs(lam));
        if (!(P + fabs(lam) > 0.0))
            a = 0.0;
    }
    d[0] = v[0] / len;
    d[1] = v[1] / len;
    d[2] = v[2] / len;
    xd = p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
    if (isinf(s->qz) || d[2] == 0.0) {
        b = s->na * xd;
    } else {
        lam = (s->qz - p[2]) / d[2];
        P = sqrt(fmax(0.0, X2 + 2.0 * lam * xd + lam * lam));
        b = (lam > 0.0 ? 1.0 : -1.0) * s->na * (X2 + 2.0 * lam * xd) / (P + fabs(lam));
        if (!(P + fabs(lam) > 0.0))
            b = 0.0;
    }
    *opl += a + b;
}

static dd dot3(dd3 a, dd3 b)
{
    return dd_add(dd_add(dd_mul(a.x, b.x), dd_mul(a.y, b.y)), dd_mul(a.z, b.z));
}

/* One side's term in double-double: n sigma (|X|^2 + 2 lambda X.d) /
 * (|P| + |lambda|), sigma = ahead ? (lambda > 0) : (lambda < 0), as +-1. */
static dd side_dd(double n, double z0, dd3 p, dd3 d, dd X2, int ahead)
{
    dd xd = dot3(p, d), lam, P2, num, t;
    if (isinf(z0) || (d.z.hi == 0.0 && d.z.lo == 0.0)) {
        t = dd_mul_d(xd, n);
        return ahead ? t : dd_neg(t);
    }
    lam = dd_div(dd_sub(dd_from(z0), p.z), d.z);
    num = dd_add(X2, dd_mul_d(dd_mul(lam, xd), 2.0));
    P2 = dd_add(num, dd_sqr(lam));
    if (P2.hi < 0.0)
        P2 = dd_from(0.0);
    t = dd_add(dd_sqrt(P2), lam.hi < 0.0 ? dd_neg(lam) : lam);
    if (!(t.hi > 0.0))
        return dd_from(0.0);
    t = dd_mul_d(dd_div(num, t), n);
    return (ahead ? lam.hi > 0.0 : lam.hi < 0.0) ? t : dd_neg(t);
}

/* The same in double-double (precise), on one ray: its direction, the
 * optical path's term and both bounds. */
void sg_ideal_bend_dd(const sg_sprep *s, sg_pray *r)
{
    dd3 v, d0 = r->d;
    dd len, X2 = dot3(r->p, r->p), c = dd_from(s->ic), a, b;
    double X = sqrt(X2.hi), vz, dz, lever, gain;
    v.x = dd_sub(dd_mul(s->mu, r->d.x), dd_mul(dd_mul(c, r->p.x), r->d.z));
    v.y = dd_sub(dd_mul(s->mu, r->d.y), dd_mul(dd_mul(c, r->p.y), r->d.z));
    v.z = r->d.z;
    len = dd_sqrt(dot3(v, v));
    a = side_dd(s->nb, s->pz, r->p, d0, X2, 0);
    r->d.x = dd_div(v.x, len);
    r->d.y = dd_div(v.y, len);
    r->d.z = dd_div(v.z, len);
    b = side_dd(s->na, s->qz, r->p, r->d, X2, 1);
    r->opl = dd_add(r->opl, dd_add(a, b));
    /* The direction: v moves by at most (mu + |c| (|x| + |y|)) eD + |c| eP
     * a component, and the unit vector by twice that over |v|, which is at
     * least |n|; then the roundings, a few dozen DD_U of |v|'s parts. */
    vz = fabs(v.z.hi);
    gain = s->mu.hi + fabs(s->ic) * (fabs(r->p.x.hi) + fabs(r->p.y.hi));
    lever = gain * r->eD + fabs(s->ic) * r->eP;
    r->eD = 2.0 * sqrt(3.0) * lever / fmax(len.hi, 1e-300) + 64.0 * DD_U * (gain + 1.0) /
                                                                fmax(len.hi, 1e-300);
    /* The term: each side moves by at most 4 |n| (|X| + 1) times the
     * direction's error and 4 |n| times the point's, over the smaller
     * |n_z| (lambda is a quotient by it; A is 1-Lipschitz in lambda's
     * direction to first order), and its roundings are some 64 DD_U of
     * |n| (|X| + |X|^2). */
    dz = fmin(fabs(d0.z.hi), fabs(r->d.z.hi));
    dz = fmax(dz, 1e-300);
    r->eO = sg_bound_up(r->eO + (s->nb + s->na) *
                                    (4.0 * (X + 1.0) * (r->eD + lever) / dz + 4.0 * r->eP / dz +
                                     64.0 * DD_U * (X + X2.hi + 1.0)) +
                        4.0 * DD_U * fabs(r->opl.hi));
    (void)vz;
}

/* One side's term in MPFR, as side_dd; t holds 4 scratch variables. */
static void side_mp(mpfr_ptr out, double n, double z0, mpfr_srcptr const p[3],
                    mpfr_srcptr const d[3], mpfr_srcptr X2, int ahead, mpfr_t *t)
{
    mpfr_ptr xd = t[0], lam = t[1], num = t[2], P = t[3];
    int k, s;
    mpfr_mul(xd, p[0], d[0], MPFR_RNDN);
    for (k = 1; k < 3; k++)
        mpfr_fma(xd, p[k], d[k], xd, MPFR_RNDN);
    if (isinf(z0) || mpfr_zero_p(d[2])) {
        mpfr_mul_d(out, xd, ahead ? n : -n, MPFR_RNDN);
        return;
    }
    mpfr_d_sub(lam, z0, p[2], MPFR_RNDN);
    mpfr_div(lam, lam, d[2], MPFR_RNDN);
    mpfr_mul(num, lam, xd, MPFR_RNDN);
    mpfr_mul_2ui(num, num, 1, MPFR_RNDN);
    mpfr_add(num, num, X2, MPFR_RNDN);
    mpfr_sqr(P, lam, MPFR_RNDN);
    mpfr_add(P, P, num, MPFR_RNDN);
    if (mpfr_sgn(P) < 0)
        mpfr_set_zero(P, 1);
    mpfr_sqrt(P, P, MPFR_RNDN);
    s = mpfr_sgn(lam);
    mpfr_abs(lam, lam, MPFR_RNDN);
    mpfr_add(P, P, lam, MPFR_RNDN);
    if (mpfr_sgn(P) <= 0) {
        mpfr_set_zero(out, 1);
        return;
    }
    mpfr_div(out, num, P, MPFR_RNDN);
    mpfr_mul_d(out, out, (ahead ? s > 0 : s < 0) ? n : -n, MPFR_RNDN);
}

/* The same in MPFR (the mpfr method): D in place, the term added to opl;
 * t holds 12 scratch variables. */
void sg_ideal_bend_mp(const sg_sprep *s, mpfr_srcptr mu, mpfr_ptr P[3], mpfr_ptr D[3],
                      mpfr_ptr opl, mpfr_t *t)
{
    mpfr_srcptr Pc[3] = {P[0], P[1], P[2]}, Dc[3] = {D[0], D[1], D[2]};
    mpfr_ptr X2 = t[0], a = t[1], len = t[2], v[3] = {t[3], t[4], t[5]};
    int k;
    mpfr_sqr(X2, P[0], MPFR_RNDN);
    mpfr_fma(X2, P[1], P[1], X2, MPFR_RNDN);
    mpfr_fma(X2, P[2], P[2], X2, MPFR_RNDN);
    side_mp(a, s->nb, s->pz, Pc, Dc, X2, 0, t + 6);
    for (k = 0; k < 2; k++) {
        mpfr_mul_d(v[k], P[k], s->ic, MPFR_RNDN);
        mpfr_mul(v[k], v[k], D[2], MPFR_RNDN);
        mpfr_fms(v[k], mu, D[k], v[k], MPFR_RNDN);
    }
    mpfr_set(v[2], D[2], MPFR_RNDN);
    mpfr_sqr(len, v[0], MPFR_RNDN);
    mpfr_fma(len, v[1], v[1], len, MPFR_RNDN);
    mpfr_fma(len, v[2], v[2], len, MPFR_RNDN);
    mpfr_sqrt(len, len, MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_div(D[k], v[k], len, MPFR_RNDN);
    mpfr_add(opl, opl, a, MPFR_RNDN);
    side_mp(a, s->na, s->qz, Pc, Dc, X2, 1, t + 6);
    mpfr_add(opl, opl, a, MPFR_RNDN);
}

/* Reads its focal length and Zemax's OPD mode, and every general row a
 * plane uses; not a radius or a conic (it is flat). */
static const sg_shape_key paraxial_keys[] = {
    {"type", 0, 0, 0},
    {"comment", 0, 0, 0},
    {"thickness", 0, 0, 0},
    {"material", 0, 0, 0},
    {"semi_diameter", 0, 0, 0},
    {"sd_fixed", 0, 0, 0},
    {"aperture", 0, 0, 0},
    {"aperture_min_radius", 0, 0, 0},
    {"aperture_max_radius", 0, 0, 0},
    {"aperture_x_half_width", 0, 0, 0},
    {"aperture_y_half_width", 0, 0, 0},
    {"aperture_x_decenter", 0, 0, 0},
    {"aperture_y_decenter", 0, 0, 0},
    {"before.", 0, 0, 0},
    {"after.", 0, 0, 0},
    {"tce", 0, 0, 0},
    /* An ideal lens has no glass to expand: its focal length stays. */
    {"focal_length", 0, 0, 0},
    {"opd_mode", 0, 0, 0},
    {NULL, 0, 0, 0}};
static const sg_zmx_map paraxial_zmx[] = {{0, 1, "focal_length", 0, 1, 0},
                                          {0, 2, "opd_mode", 0, 1, 0},
                                          {0, 0, NULL, 0, 0, 0}};
const sg_shape_type sg_shape_paraxial_type = {
    .type = SG_SURF_PARAXIAL,
    .name = "paraxial",
    .keys = paraxial_keys,
    .only = 1,
    .parm_lo = 1,
    .parm_hi = 2,
    .parm_what = "a paraxial surface has the focal length (PARM 1) and the OPD mode (PARM 2)",
    .zmx = paraxial_zmx,
    .xdat_what = "a paraxial surface has no extra data"};
