/*
 * shape_zernike.c - Zemax's Zernike Fringe Sag and Zernike Standard Sag:
 * an even asphere (conic and a_1 r^2 ... a_8 r^16) plus sum A_j Z_j(rho,
 * theta), rho = r / the normalization radius, theta from the x axis, r and
 * theta about Zemax's Decenter X and Y (the conic and r^n terms stay on the
 * vertex; sagitta-design(5), SURFACE TYPES).  Fringe: the 37 terms of the
 * University of Arizona order, not normalized.  Standard: Noll's order
 * and normalization, sqrt(n + 1) or sqrt(2 (n + 1)).
 *
 * Each term is expanded once into a polynomial in u = x / norm and v =
 * y / norm with integer coefficients (rho^2 = u^2 + v^2, rho^m cos(m
 * theta) = Re (u + i v)^m), so the surface is traced as a polynomial.
 */
#include <math.h>
#include <string.h>

#include "shape.h"

static long long binom(int n, int k)
{
    long long r = 1;
    int i;
    if (k < 0 || k > n)
        return 0;
    for (i = 1; i <= k; i++)
        r = r * (n - k + i) / i;
    return r;
}

static long long fact(int n)
{
    long long r = 1;
    while (n > 1)
        r *= n--;
    return r;
}

int sg_zernike_poly(int standard, int j, long long *e, long *nsq)
{
    int n, m, am, s, rc;
    memset(e, 0, sizeof(long long) * SG_P2_N);
    rc = sg_zernike_nm(standard ? SG_ZERNIKE_STANDARD : SG_ZERNIKE_FRINGE, j, &n, &m);
    if (rc != SG_OK || n > SG_P2_DEG)
        return SG_ERANGE;
    am = m < 0 ? -m : m;
    *nsq = standard ? (m == 0 ? n + 1 : 2 * (n + 1)) : 1;
    /* R_n^|m| = sum_s (-1)^s (n - s)! / (s! ((n + |m|)/2 - s)! ((n - |m|)/2 - s)!)
     * rho^(n - 2s), and rho^(n - 2s) times the angular factor is
     * (u^2 + v^2)^p Re or Im (u + i v)^|m|, p = (n - 2s - |m|) / 2. */
    for (s = 0; s <= (n - am) / 2; s++) {
        long long rs = fact(n - s) / (fact(s) * fact((n + am) / 2 - s) * fact((n - am) / 2 - s));
        int p = (n - 2 * s - am) / 2, t, k;
        if (s % 2)
            rs = -rs;
        for (t = 0; t <= p; t++)
            for (k = 0; k <= am; k++) {
                /* (u + i v)^|m| term k: C(|m|, k) u^(|m|-k) (i v)^k. */
                long long ck;
                int iu, iv;
                if (m >= 0 && k % 2)
                    continue; /* the real part: even k */
                if (m < 0 && k % 2 == 0)
                    continue; /* the imaginary part: odd k */
                ck = binom(am, k) * ((k / 2) % 2 ? -1 : 1);
                iu = 2 * t + am - k;
                iv = 2 * (p - t) + k;
                e[SG_P2_AT(iu, iv)] += rs * binom(p, t) * ck;
            }
    }
    return SG_OK;
}

static int zern_prepare(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d)
{
    int std = f->type == SG_SURF_ZERNIKE_STANDARD, k, j;
    int rc = sg_p2_terms(f, s, isurf, d);
    if (rc != SG_OK)
        return rc;
    /* Zemax's Decenter X and Y move the terms, not the conic. */
    if (!isfinite(f->zern_dx) || !isfinite(f->zern_dy))
        return sg_diag_set(d, SG_ERANGE, "surface %d: Zernike decenter (%g, %g) must be finite",
                           isurf, f->zern_dx, f->zern_dy);
    s->px = f->zern_dx;
    s->py = f->zern_dy;
    if (!std && s->nz > SG_ZERNIKE_FRINGE_MAX)
        return sg_diag_set(d, SG_ERANGE, "surface %d: Fringe Zernike term %d; there are %d",
                           isurf, s->nz, SG_ZERNIKE_FRINGE_MAX);
    for (k = 0; k < s->nz; k++) {
        long long e[SG_P2_N];
        long nsq;
        dd an;
        if (f->terms[k] == 0.0)
            continue;
        if (sg_zernike_poly(std, k + 1, e, &nsq) != SG_OK)
            return sg_diag_set(d, SG_ERANGE, "surface %d: Zernike term %d is beyond order %d",
                               isurf, k + 1, SG_P2_DEG);
        an = dd_mul_d(dd_sqrt(dd_from((double)nsq)), f->terms[k]);
        for (j = 0; j < SG_P2_N; j++)
            if (e[j])
                sg_p2_add(s, j, dd_mul_d(an, (double)e[j]), fabs(an.hi * (double)e[j]));
    }
    return SG_OK;
}

static void zern_mp_coefs(const sg_shape *s, mpfr_t *mc)
{
    const sg_surface *f = s->src;
    mpfr_t an, t;
    int k, j;
    mpfr_inits2(mpfr_get_prec(mc[0]), an, t, (mpfr_ptr)0);
    for (k = 0; k < s->nz; k++) {
        long long e[SG_P2_N];
        long nsq;
        if (f->terms[k] == 0.0 ||
            sg_zernike_poly(f->type == SG_SURF_ZERNIKE_STANDARD, k + 1, e, &nsq) != SG_OK)
            continue;
        mpfr_sqrt_ui(an, (unsigned long)nsq, MPFR_RNDN);
        mpfr_mul_d(an, an, f->terms[k], MPFR_RNDN);
        for (j = 0; j < SG_P2_N; j++)
            if (e[j]) {
                mpfr_mul_si(t, an, (long)e[j], MPFR_RNDN);
                mpfr_add(mc[j], mc[j], t, MPFR_RNDN);
            }
    }
    mpfr_clears(an, t, (mpfr_ptr)0);
}

const sg_shape_ops sg_shape_zernike_ops = {"Zernike sag", zern_prepare, zern_mp_coefs,
                                           sg_rot_p2_d, sg_rot_p2_dd, sg_rot_p2_mp};

/* The even terms, the normalization radius, the decenter and the terms
 * (lens units over coordinates divided by the normalization radius).  In
 * .zmx: PARM 0 the extrapolate flag (written 1: sagitta applies the terms
 * at every radius), 1 to 8 the even terms, 9 and 10 the decenter
 * (written only when set, so a centred surface writes as before); XDAT 1
 * the number of terms, 2 the normalization radius, 3 on the terms. */
#define ZERN_KEYS(nterms)                                                                 \
    {{"asphere", 0, -1, -2},           {"norm_radius", 0, 1, 0},                           \
     {"zernike_decenter_x", 0, 1, 0}, {"zernike_decenter_y", 0, 1, 0},                    \
     {"terms", nterms, 1, 0},          {NULL, 0, 0, 0}}
static const sg_shape_key fringe_keys[] = ZERN_KEYS(SG_ZERNIKE_FRINGE_MAX);
static const sg_shape_key standard_keys[] = ZERN_KEYS(0);
static const sg_zmx_map zern_zmx[] = {{0, 1, "asphere", 0, SG_NASPH, 0},
                                      {0, SG_NASPH + 1, "zernike_decenter_x", 0, 1, SG_ZMX_IF_SET},
                                      {0, SG_NASPH + 2, "zernike_decenter_y", 0, 1, SG_ZMX_IF_SET},
                                      {0, 0, NULL, 0, 0, 0}};
#define ZERN_PARM_WHAT                                                                    \
    "the Zernike sag has terms r^2 to r^16 (PARM 1 to 8) and the Zernike decenters x and y " \
    "(PARM 9 and 10)"
const sg_shape_type sg_shape_zernike_fringe_type = {
    .type = SG_SURF_ZERNIKE_FRINGE, .name = "Zernike Fringe sag", .ops = &sg_shape_zernike_ops,
    .keys = fringe_keys, .parm_lo = 0, .parm_hi = SG_NASPH + 2, .parm_what = ZERN_PARM_WHAT,
    .zmx = zern_zmx, .zmx_terms = SG_ZERNIKE_FRINGE_MAX, .extrapolate = 1};
const sg_shape_type sg_shape_zernike_standard_type = {
    .type = SG_SURF_ZERNIKE_STANDARD, .name = "Zernike Standard sag", .ops = &sg_shape_zernike_ops,
    .keys = standard_keys, .parm_lo = 0, .parm_hi = SG_NASPH + 2, .parm_what = ZERN_PARM_WHAT,
    .zmx = zern_zmx, .zmx_terms = SG_NTERMS, .extrapolate = 1};
