/*
 * shape_phase.c - Zemax's phase surfaces: Binary 2 (TYPE BINARY_2) and
 * Zernike Fringe Phase (TYPE FZERNPHA), a plane or conic (traced by the
 * methods' own kernels) that adds a phase (sagitta-design(5), SURFACE
 * TYPES):
 *
 *   Binary 2:       Phi = M sum_i A_i rho^(2i),   i = 1 ... N
 *   Zernike phase:  Phi = M sum_j A_j Z_j(rho, theta), the 37 Fringe terms
 *
 * M the diffraction order, rho = r / the normalization radius; Phi in
 * radians, the Zernike phase's A_j in waves (Phi = 2 pi M sum A_j Z_j,
 * theta from the x axis), as Zemax's files show (tests/test_phase.c).
 * Both are expanded once into a polynomial P in u = x / norm, v = y /
 * norm (shape.c's sg_p2_*, as the Zernike sag is), so Phi = M P.  The
 * phase's gradient is the local grating vector: a ray's tangential part
 * follows the grating equation in vector form (shape_dgrating.c),
 *
 *   |n'| d'_t = |n| d_t + (lambda / 2 pi) M (grad P)_t,
 *
 * grad P = (dP/dx, dP/dy, 0) projected on the tangent plane, lambda in
 * lens units; the normal part makes d' a unit vector, on the far side (or
 * the near side on a mirror).  Where |d'_t| > 1 the order does not
 * propagate: SG_EEVANESCENT.  The optical path gains the phase over 2
 * pi, lambda M P / (2 pi).  Paraxially the surface adds the power
 * -lambda M c02 / (pi norm^2), c02 the coefficient of v^2
 * (sg_phase_power).
 */
#include <math.h>
#include <string.h>

#include "shape.h"

int sg_phase_type(int type)
{
    return type == SG_SURF_BINARY_2 || type == SG_SURF_ZERNIKE_PHASE;
}

static long long binom(int n, int k)
{
    long long r = 1;
    int i;
    for (i = 1; i <= k; i++)
        r = r * (n - k + i) / i;
    return r;
}

/* Term k (from 0) of f as integer coefficients e[SG_P2_N] of u^a v^b:
 * rho^(2k+2) = (u^2 + v^2)^(k+1), or the Fringe Zernike term k + 1. */
static int term_poly(const sg_surface *f, int k, long long *e)
{
    long nsq;
    int t, i = k + 1;
    if (f->type == SG_SURF_ZERNIKE_PHASE)
        return sg_zernike_poly(0, k + 1, e, &nsq);
    memset(e, 0, sizeof(long long) * SG_P2_N);
    if (2 * i > SG_P2_DEG)
        return SG_ERANGE;
    for (t = 0; t <= i; t++)
        e[SG_P2_AT(2 * t, 2 * (i - t))] = binom(i, t);
    return SG_OK;
}

/* What the terms are multiplied by to make radians: 2 pi for the Zernike
 * phase's waves, as a double-double. */
static dd unit_dd(const sg_surface *f)
{
    dd two_pi = {6.283185307179586232, 2.4492935982947064e-16};
    return f->type == SG_SURF_ZERNIKE_PHASE ? two_pi : dd_from(1.0);
}

int sg_phase_prepare(const sg_surface *f, sg_shape *ph, int isurf, sg_diag *d)
{
    int k, j, rc;
    dd unit = unit_dd(f);
    memset(ph, 0, sizeof *ph);
    ph->type = f->type;
    ph->src = f;
    ph->norm = f->norm_radius;
    if ((rc = sg_p2_terms(f, ph, isurf, d)) != SG_OK)
        return rc;
    if (!isfinite(f->grating_order))
        return sg_diag_set(d, SG_ERANGE, "surface %d: diffraction order %g must be finite",
                           isurf, f->grating_order);
    if (f->type == SG_SURF_ZERNIKE_PHASE && ph->nz > SG_ZERNIKE_FRINGE_MAX)
        return sg_diag_set(d, SG_ERANGE, "surface %d: Fringe Zernike phase term %d; there are %d",
                           isurf, ph->nz, SG_ZERNIKE_FRINGE_MAX);
    for (k = 0; k < ph->nz; k++) {
        long long e[SG_P2_N];
        if (f->terms[k] == 0.0)
            continue;
        if (term_poly(f, k, e) != SG_OK)
            return sg_diag_set(d, SG_ERANGE,
                               "surface %d: binary 2 term %d (rho^%d) is beyond rho^%d", isurf,
                               k + 1, 2 * k + 2, SG_P2_DEG);
        for (j = 0; j < SG_P2_N; j++)
            if (e[j])
                sg_p2_add(ph, j, dd_mul(dd_mul_d(dd_from(f->terms[k]), (double)e[j]), unit),
                          fabs(f->terms[k] * (double)e[j] * unit.hi));
    }
    return SG_OK;
}

void sg_phase_mp_coefs(const sg_shape *ph, mpfr_t *mc, mpfr_prec_t prec)
{
    const sg_surface *f = ph->src;
    mpfr_t t, unit;
    int k, j;
    sg_shape_mp_coefs(ph, mc, prec);
    mpfr_inits2(prec, t, unit, (mpfr_ptr)0);
    mpfr_set_ui(unit, 1, MPFR_RNDN);
    if (f->type == SG_SURF_ZERNIKE_PHASE) {
        mpfr_const_pi(unit, MPFR_RNDN);
        mpfr_mul_2ui(unit, unit, 1, MPFR_RNDN);
    }
    for (k = 0; k < ph->nz; k++) {
        long long e[SG_P2_N];
        if (f->terms[k] == 0.0 || term_poly(f, k, e) != SG_OK)
            continue;
        for (j = 0; j < SG_P2_N; j++)
            if (e[j]) {
                mpfr_set_d(t, f->terms[k], MPFR_RNDN);
                mpfr_mul_si(t, t, (long)e[j], MPFR_RNDN);
                mpfr_mul(t, t, unit, MPFR_RNDN);
                mpfr_add(mc[j], mc[j], t, MPFR_RNDN);
            }
    }
    mpfr_clears(t, unit, (mpfr_ptr)0);
}

double sg_phase_power(const sg_system *sys, int i, double um)
{
    const sg_surface *f = &sys->surf[i];
    double c02 = 0.0, lam;
    int k, nz = 0;
    if (!sg_phase_type(f->type) || !(f->norm_radius > 0.0))
        return 0.0;
    for (k = 0; k < SG_NTERMS; k++)
        if (f->terms[k] != 0.0)
            nz = k + 1;
    for (k = 0; k < nz; k++) {
        long long e[SG_P2_N];
        if (f->terms[k] != 0.0 && term_poly(f, k, e) == SG_OK)
            c02 += f->terms[k] * (double)e[SG_P2_AT(0, 2)];
    }
    lam = um * 1e-3 / sg_lens_unit_mm(sys);
    return -lam * f->grating_order * c02 * unit_dd(f).hi /
           (3.14159265358979323846 * f->norm_radius * f->norm_radius);
}

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

int sg_phase_bend_d(const sg_sprep *s, const double p[3], double d[3], double *opl)
{
    double g[3], gn, dn, G[3], GN, v[3], a, sg, P, gr[2], h, q = s->pk / s->na;
    int k;
    normal_d(s, p, g);
    gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (k = 0; k < 3; k++)
        g[k] /= gn;
    sg_p2_d(s->phase, p[0], p[1], &P, gr, &h);
    G[0] = q * gr[0];
    G[1] = q * gr[1];
    G[2] = 0.0;
    dn = d[0] * g[0] + d[1] * g[1] + d[2] * g[2];
    GN = G[0] * g[0] + G[1] * g[1];
    for (k = 0; k < 3; k++)
        v[k] = s->mu.hi * (d[k] - dn * g[k]) + (G[k] - GN * g[k]);
    a = 1.0 - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(a >= 0.0))
        return SG_EEVANESCENT;
    sg = (dn >= 0.0 ? 1.0 : -1.0) * (s->mirror ? -1.0 : 1.0);
    for (k = 0; k < 3; k++)
        d[k] = v[k] + sg * sqrt(a) * g[k];
    *opl += s->pk * P;
    return 0;
}

static dd dot3(dd3 a, dd3 b)
{
    return dd_add(dd_add(dd_mul(a.x, b.x), dd_mul(a.y, b.y)), dd_mul(a.z, b.z));
}

int sg_phase_bend_dd(const sg_sprep *s, sg_pray *r)
{
    dd3 g, v;
    dd gn, dn, a, sq, P, gr[2], q = dd_div_d(dd_from(s->pk), s->na), Gx, Gy, GN;
    double sens, dN, sg, gain, ez, eg, Pd, grd[2], h, kick, qa = fabs(q.hi);
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
    dN = 2.0 * sens * r->eP / fmax(gn.hi, 1e-300);
    g.x = dd_div(g.x, gn);
    g.y = dd_div(g.y, gn);
    g.z = dd_div(g.z, gn);
    sg_p2_dd(s->phase, r->p.x, r->p.y, &P, gr, &ez, &eg);
    /* The second derivatives bound how far the gradient moves with the
     * point's error. */
    sg_p2_d(s->phase, r->p.x.hi, r->p.y.hi, &Pd, grd, &h);
    Gx = dd_mul(q, gr[0]);
    Gy = dd_mul(q, gr[1]);
    GN = dd_add(dd_mul(Gx, g.x), dd_mul(Gy, g.y));
    dn = dot3(r->d, g);
    v.x = dd_add(dd_mul(s->mu, dd_sub(r->d.x, dd_mul(dn, g.x))), dd_sub(Gx, dd_mul(GN, g.x)));
    v.y = dd_add(dd_mul(s->mu, dd_sub(r->d.y, dd_mul(dn, g.y))), dd_sub(Gy, dd_mul(GN, g.y)));
    v.z = dd_sub(dd_mul(s->mu, dd_sub(r->d.z, dd_mul(dn, g.z))), dd_mul(GN, g.z));
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
    /* The tangential part moves by mu (eD + 2 dN), the kick's projection
     * by |kick| 2 dN, and the kick itself by |q| (h eP + eg); the normal
     * part by that over its own size, as the grating's. */
    kick = qa * (fabs(grd[0]) + fabs(grd[1]));
    gain = s->mu.hi * (r->eD + 2.0 * dN) + 2.0 * kick * dN +
           qa * (2.0 * h * r->eP + 2.0 * eg);
    r->eD = 2.0 * gain * (1.0 + 1.0 / fmax(fabs(sq.hi), sqrt(1e-300))) + 2.0 * dN +
            128.0 * DD_U * (s->mu.hi + kick + 1.0) / fmax(fabs(sq.hi), 1e-150);
    r->opl = dd_add(r->opl, dd_mul(dd_from(s->pk), P));
    r->eO = sg_bound_up(r->eO +
                        fabs(s->pk) * (2.0 * (fabs(grd[0]) + fabs(grd[1])) * r->eP + ez +
                                       4.0 * DD_U * fabs(P.hi)) +
                        4.0 * DD_U * fabs(r->opl.hi));
    return 0;
}

int sg_phase_bend_mp(const sg_sprep *s, mpfr_t *mc, mpfr_srcptr mu, mpfr_srcptr R,
                     mpfr_srcptr k1, mpfr_ptr P[3], mpfr_ptr D[3], mpfr_ptr opl, mpfr_t *t)
{
    mpfr_ptr g[3] = {t[0], t[1], t[2]}, v[3] = {t[3], t[4], t[5]}, x = t[6], q = t[7];
    mpfr_ptr ph = t[8], G[2] = {t[9], t[10]}, GN = t[11];
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
    /* The phase and its gradient; the kick G = q grad P, q = pk / |n'|. */
    sg_p2_mp(s->phase, mc, P[0], P[1], ph, G[0], G[1], t + 12);
    mpfr_set_d(q, s->pk, MPFR_RNDN);
    mpfr_div_d(q, q, s->na, MPFR_RNDN);
    mpfr_mul(G[0], G[0], q, MPFR_RNDN);
    mpfr_mul(G[1], G[1], q, MPFR_RNDN);
    mpfr_mul(GN, G[0], g[0], MPFR_RNDN);
    mpfr_fma(GN, G[1], g[1], GN, MPFR_RNDN);
    /* x = d . N; v = mu (d - x N) + (G - (G . N) N). */
    mpfr_mul(x, D[0], g[0], MPFR_RNDN);
    mpfr_fma(x, D[1], g[1], x, MPFR_RNDN);
    mpfr_fma(x, D[2], g[2], x, MPFR_RNDN);
    sg = (mpfr_sgn(x) >= 0 ? 1 : -1) * (s->mirror ? -1 : 1);
    for (k = 0; k < 3; k++) {
        mpfr_mul(v[k], x, g[k], MPFR_RNDN);
        mpfr_sub(v[k], D[k], v[k], MPFR_RNDN);
        mpfr_mul(v[k], v[k], mu, MPFR_RNDN);
        mpfr_mul(D[k], GN, g[k], MPFR_RNDN);
        mpfr_sub(v[k], v[k], D[k], MPFR_RNDN);
        if (k < 2)
            mpfr_add(v[k], v[k], G[k], MPFR_RNDN);
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
    mpfr_mul_d(x, ph, s->pk, MPFR_RNDN);
    mpfr_add(opl, opl, x, MPFR_RNDN);
    return 0;
}

/* Every general row (the radius and conic of the substrate among them),
 * the order, the normalization radius (which grows with the part) and the
 * terms (radians, over coordinates divided by it: they stay).  In .zmx:
 * PARM 0 the order (PARM 1 to 8, the even asphere terms Zemax's substrate
 * may have, must be 0); XDAT 1 the number of terms, 2 the normalization
 * radius, 3 on the terms. */
static const sg_shape_key binary2_keys[] = {{"grating_order", 0, 0, 0},
                                            {"norm_radius", 0, 1, 0},
                                            {"terms", SG_P2_DEG / 2, 0, 0},
                                            {NULL, 0, 0, 0}};
static const sg_shape_key fzernpha_keys[] = {{"grating_order", 0, 0, 0},
                                             {"norm_radius", 0, 1, 0},
                                             {"terms", SG_ZERNIKE_FRINGE_MAX, 0, 0},
                                             {NULL, 0, 0, 0}};
static const sg_zmx_map phase_zmx[] = {{0, 0, "grating_order", 0, 1, 0}, {0, 0, NULL, 0, 0, 0}};
#define PHASE_PARM_WHAT                                                                    \
    "a phase surface has the diffraction order (PARM 0); sagitta does not read the even " \
    "asphere terms of its substrate (PARM 1 to 8)"
const sg_shape_type sg_shape_binary2_type = {.type = SG_SURF_BINARY_2,
                                             .name = "binary 2",
                                             .keys = binary2_keys,
                                             .parm_lo = 0,
                                             .parm_hi = 0,
                                             .parm_what = PHASE_PARM_WHAT,
                                             .zmx = phase_zmx,
                                             .zmx_terms = SG_P2_DEG / 2};
const sg_shape_type sg_shape_fzernpha_type = {.type = SG_SURF_ZERNIKE_PHASE,
                                              .name = "Zernike Fringe phase",
                                              .keys = fzernpha_keys,
                                              .parm_lo = 0,
                                              .parm_hi = 0,
                                              .parm_what = PHASE_PARM_WHAT,
                                              .zmx = phase_zmx,
                                              .zmx_terms = SG_ZERNIKE_FRINGE_MAX};
