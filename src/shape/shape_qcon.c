/*
 * shape_qcon.c - Zemax's Q-type asphere of Forbes' Qcon kind (G. W.
 * Forbes, "Shape specification for axially symmetric optical surfaces",
 * Opt. Express 15, 5218 (2007), eq. 2.3): a conic plus
 *
 *   u^4 sum_{m=0}^{M} a_m Q_m^con(u^2),   u = r / rn,
 *
 * with rn the normalization radius and Q_m^con(x) = P_m^(0,4)(2x - 1),
 * the Jacobi polynomials (Forbes' eq. A.1); the a_m are in lens units,
 * terms[m] of the surface (sagitta-design(5), SURFACE TYPES).
 *
 * The sums are formed by the polynomials' three-term recurrence (in x =
 * u^2, with integer constants), which stays well conditioned where the
 * expanded powers of x would cancel: P_n = (L_n P_{n-1} - D_n P_{n-2}) /
 * A_n, L_n = 2 B_n x + C_n - B_n,
 *
 *   A_n = 2n (n + 4)(2n + 2),  B_n = (2n + 3)(2n + 4)(2n + 2),
 *   C_n = -16 (2n + 3),        D_n = 2 (n - 1)(n + 3)(2n + 4),
 *
 * differentiated for the slopes.  The shape keeps a_m in c[m] and |a_m|
 * in cm[m] (as the polynomial shapes keep their coefficients).
 */
#include <math.h>

#include "shape.h"

/* Terms a_0 ... a_{QCON_MAX - 1}. */
#define QCON_MAX 20

static void qcon_abcd(int n, double *A, double *B, double *C, double *D)
{
    *A = 2.0 * n * (n + 4) * (2 * n + 2);
    *B = (2.0 * n + 3) * (2 * n + 4) * (2 * n + 2);
    *C = -16.0 * (2 * n + 3);
    *D = 2.0 * (n - 1) * (n + 3) * (2 * n + 4);
}

static int qcon_prepare(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d)
{
    int k, rc = sg_p2_terms(f, s, isurf, d);
    if (rc != SG_OK)
        return rc;
    if (s->nz > QCON_MAX)
        return sg_diag_set(d, SG_ERANGE,
                           "surface %d: Q-type asphere term %d; there are %d (a_0 to a_%d)",
                           isurf, s->nz, QCON_MAX, QCON_MAX - 1);
    for (k = 0; k < s->nz; k++) {
        s->c[k] = dd_from(f->terms[k]);
        s->cm[k] = fabs(f->terms[k]);
    }
    return SG_OK;
}

/* S = sum a_m P_m(x) and its first and second derivatives in x. */
static void qsum_d(const sg_shape *s, double x, double *S, double *S1, double *S2)
{
    double p1 = 1.0, p2 = 0.0, d1 = 0.0, d2 = 0.0, e1 = 0.0, e2 = 0.0;
    int n;
    *S = s->c[0].hi;
    *S1 = *S2 = 0.0;
    for (n = 1; n < s->nz; n++) {
        double A, B, C, D, L, p, dp, ep;
        qcon_abcd(n, &A, &B, &C, &D);
        L = 2.0 * B * x + (C - B);
        p = (L * p1 - D * p2) / A;
        dp = (2.0 * B * p1 + L * d1 - D * d2) / A;
        ep = (4.0 * B * d1 + L * e1 - D * e2) / A;
        *S += s->c[n].hi * p;
        *S1 += s->c[n].hi * dp;
        *S2 += s->c[n].hi * ep;
        p2 = p1;
        p1 = p;
        d2 = d1;
        d1 = dp;
        e2 = e1;
        e1 = ep;
    }
}

/* The gradient of a rotational sag is w (x, y), w = 2 dz / d(r^2); its
 * Hessian's row sums are at most |w| + 4 |w'| r^2, w' = dw / d(r^2).
 * The polynomial part x^2 S(x), x = r^2 / rn^2, adds 2 (2 x S + x^2 S')
 * / rn^2 to w and 2 (2 S + 4 x S' + x^2 S'') / rn^4 to w'. */
static int qcon_d(const sg_shape *s, double X, double Y, double *z, double g[2], double *h)
{
    double r2 = X * X + Y * Y, w, dw;
    if (!sg_rot_d(s, r2, z, &w, &dw))
        return 0;
    if (s->nz) {
        double n2 = s->norm * s->norm, x = r2 / n2, S, S1, S2;
        qsum_d(s, x, &S, &S1, &S2);
        *z += x * x * S;
        w += 2.0 * (2.0 * x * S + x * x * S1) / n2;
        dw += fabs(2.0 * (2.0 * S + 4.0 * x * S1 + x * x * S2) / (n2 * n2));
    }
    g[0] = w * X;
    g[1] = w * Y;
    *h = 1.5 * (fabs(w) + 4.0 * dw * r2);
    return 1;
}

/* The sums in double-double, with bounds: es on S and es1 on S' (their
 * roundings, before x's own error), and the magnitudes ms, ms1, ms2 of
 * S, S', S'' (sums of |a_m| times bounds on |P_m|, |P_m'|, |P_m''|).  A
 * step of the recurrence rounds by a few DD_U of the magnitudes it
 * combines, and an error carried in P_{n-1}, P_{n-2} grows as those
 * magnitudes do, so P_n's is at most 16 n DD_U of its magnitude. */
static void qsum_dd(const sg_shape *s, dd x, dd *S, dd *S1, double *es, double *es1, double *ms,
                    double *ms1, double *ms2)
{
    dd p1 = dd_from(1.0), p2 = dd_from(0.0), d1 = dd_from(0.0), d2 = dd_from(0.0);
    double mp1 = 1.0, mp2 = 0.0, md1 = 0.0, md2 = 0.0, me1 = 0.0, me2 = 0.0, ax = fabs(x.hi);
    double sz = s->cm[0], sg = 0.0;
    int n, M = s->nz;
    *S = s->c[0];
    *S1 = dd_from(0.0);
    *ms = s->cm[0];
    *ms1 = *ms2 = 0.0;
    for (n = 1; n < M; n++) {
        double A, B, C, D, ml, mp, md, me;
        dd L, p, dp;
        qcon_abcd(n, &A, &B, &C, &D);
        L = dd_add_d(dd_mul_d(x, 2.0 * B), C - B);
        p = dd_div_d(dd_sub(dd_mul(L, p1), dd_mul_d(p2, D)), A);
        dp = dd_div_d(dd_sub(dd_add(dd_mul_d(p1, 2.0 * B), dd_mul(L, d1)), dd_mul_d(d2, D)), A);
        *S = dd_add(*S, dd_mul(s->c[n], p));
        *S1 = dd_add(*S1, dd_mul(s->c[n], dp));
        /* |L| before its cancellation, so its rounding is covered. */
        ml = 2.0 * B * ax + fabs(C - B);
        mp = (ml * mp1 + D * mp2) / A;
        md = (2.0 * B * mp1 + ml * md1 + D * md2) / A;
        me = (4.0 * B * md1 + ml * me1 + D * me2) / A;
        *ms += s->cm[n] * mp;
        *ms1 += s->cm[n] * md;
        *ms2 += s->cm[n] * me;
        sz += s->cm[n] * mp * (16.0 * n + 8.0);
        sg += s->cm[n] * md * (16.0 * n + 8.0);
        p2 = p1;
        p1 = p;
        d2 = d1;
        d1 = dp;
        mp2 = mp1;
        mp1 = mp;
        md2 = md1;
        md1 = md;
        me2 = me1;
        me1 = me;
    }
    /* The sums' own roundings: a few DD_U of the running magnitudes each. */
    *es = (sz + 4.0 * M * *ms) * DD_U * 1.0625;
    *es1 = (sg + 4.0 * M * *ms1) * DD_U * 1.0625;
}

static int qcon_dd(const sg_shape *s, dd X, dd Y, dd *z, dd g[2], double *ez, double *eg)
{
    dd r2 = dd_add(dd_sqr(X), dd_sqr(Y)), w;
    double ew, m = fmax(fabs(X.hi), fabs(Y.hi));
    if (!sg_rot_dd(s, r2, z, &w, ez, &ew))
        return 0;
    /* r^2's own rounding moves the sag by dz/dr^2 = w / 2 times it. */
    *ez += 4.0 * DD_U * fabs(w.hi) * r2.hi;
    if (s->nz) {
        dd x = dd_div_d(dd_div_d(r2, s->norm), s->norm), x2 = dd_sqr(x), S, S1, zq, wq;
        double es, es1, ms, ms1, ms2, ax = fabs(x.hi), ax2 = ax * ax, n2 = s->norm * s->norm;
        /* x carries r^2's rounding and two quotients'. */
        double ex = 8.0 * DD_U * ax, eS, eS1;
        qsum_dd(s, x, &S, &S1, &es, &es1, &ms, &ms1, &ms2);
        eS = es + ms1 * ex;
        eS1 = es1 + ms2 * ex;
        zq = dd_mul(x2, S);
        /* w_q = 2 (2 x S + x^2 S') / rn^2. */
        wq = dd_div_d(dd_div_d(dd_mul_d(dd_add(dd_mul_d(dd_mul(x, S), 2.0), dd_mul(x2, S1)), 2.0),
                               s->norm),
                      s->norm);
        *z = dd_add(*z, zq);
        w = dd_add(w, wq);
        *ez += ax2 * eS + 2.0 * ax * ex * ms + 8.0 * DD_U * ax2 * ms +
               2.0 * DD_U * (fabs(z->hi) + fabs(zq.hi));
        ew += 2.0 * (2.0 * (ax * eS + ex * ms) + ax2 * eS1 + 2.0 * ax * ex * ms1 +
                     16.0 * DD_U * (2.0 * ax * ms + ax2 * ms1)) /
                  n2 * 1.0625 +
              2.0 * DD_U * (fabs(w.hi) + fabs(wq.hi));
    }
    g[0] = dd_mul(w, X);
    g[1] = dd_mul(w, Y);
    *eg = (ew + 8.0 * DD_U * fabs(w.hi)) * m;
    return 1;
}

static void qcon_mp_coefs(const sg_shape *s, mpfr_t *mc)
{
    int k;
    for (k = 0; k < s->nz; k++)
        mpfr_set_d(mc[k], s->src->terms[k], MPFR_RNDN);
}

/* The recurrence in MPFR; its scratch is the coefficients' spare room
 * (mc past SG_P2_N, which only the polynomial shapes use). */
static int qcon_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr X, mpfr_srcptr Y, mpfr_ptr z,
                   mpfr_ptr gx, mpfr_ptr gy, mpfr_t *t)
{
    mpfr_t *v = mc + SG_P2_N;
    mpfr_ptr x = v[0], S = v[1], S1 = v[2], p1 = v[3], p2 = v[4], d1 = v[5], d2 = v[6],
             p = v[7], dp = v[8], L = v[9], q = v[10];
    int n;
    mpfr_sqr(t[8], X, MPFR_RNDN);
    mpfr_sqr(t[9], Y, MPFR_RNDN);
    mpfr_add(t[8], t[8], t[9], MPFR_RNDN);
    if (!sg_rot_mp(s, t[8], z, t[10], t))
        return 0;
    if (s->nz) {
        mpfr_div_d(x, t[8], s->norm, MPFR_RNDN);
        mpfr_div_d(x, x, s->norm, MPFR_RNDN);
        mpfr_set(S, mc[0], MPFR_RNDN);
        mpfr_set_zero(S1, 1);
        mpfr_set_ui(p1, 1, MPFR_RNDN);
        mpfr_set_zero(p2, 1);
        mpfr_set_zero(d1, 1);
        mpfr_set_zero(d2, 1);
        for (n = 1; n < s->nz; n++) {
            double A, B, C, D;
            qcon_abcd(n, &A, &B, &C, &D);
            mpfr_mul_d(L, x, 2.0 * B, MPFR_RNDN);
            mpfr_add_d(L, L, C - B, MPFR_RNDN);
            /* dp = (2 B p1 + L d1 - D d2) / A, then p = (L p1 - D p2) / A. */
            mpfr_mul_d(dp, p1, 2.0 * B, MPFR_RNDN);
            mpfr_mul(q, L, d1, MPFR_RNDN);
            mpfr_add(dp, dp, q, MPFR_RNDN);
            mpfr_mul_d(q, d2, D, MPFR_RNDN);
            mpfr_sub(dp, dp, q, MPFR_RNDN);
            mpfr_div_d(dp, dp, A, MPFR_RNDN);
            mpfr_mul(p, L, p1, MPFR_RNDN);
            mpfr_mul_d(q, p2, D, MPFR_RNDN);
            mpfr_sub(p, p, q, MPFR_RNDN);
            mpfr_div_d(p, p, A, MPFR_RNDN);
            mpfr_mul(q, mc[n], p, MPFR_RNDN);
            mpfr_add(S, S, q, MPFR_RNDN);
            mpfr_mul(q, mc[n], dp, MPFR_RNDN);
            mpfr_add(S1, S1, q, MPFR_RNDN);
            mpfr_swap(p2, p1);
            mpfr_swap(p1, p);
            mpfr_swap(d2, d1);
            mpfr_swap(d1, dp);
        }
        /* z += x^2 S; w += 2 (2 x S + x^2 S') / rn^2. */
        mpfr_sqr(q, x, MPFR_RNDN);
        mpfr_mul(p, q, S, MPFR_RNDN);
        mpfr_add(z, z, p, MPFR_RNDN);
        mpfr_mul(p, q, S1, MPFR_RNDN);
        mpfr_mul(q, x, S, MPFR_RNDN);
        mpfr_mul_2ui(q, q, 1, MPFR_RNDN);
        mpfr_add(p, p, q, MPFR_RNDN);
        mpfr_mul_2ui(p, p, 1, MPFR_RNDN);
        mpfr_div_d(p, p, s->norm, MPFR_RNDN);
        mpfr_div_d(p, p, s->norm, MPFR_RNDN);
        mpfr_add(t[10], t[10], p, MPFR_RNDN);
    }
    mpfr_mul(gx, t[10], X, MPFR_RNDN);
    mpfr_mul(gy, t[10], Y, MPFR_RNDN);
    return 1;
}

static const sg_shape_ops qcon_ops = {"Q-type asphere", qcon_prepare, qcon_mp_coefs, qcon_d,
                                      qcon_dd, qcon_mp};

/* The normalization radius and a_m grow with the part (a_m in lens
 * units).  Zemax's .zmx layout of this surface is not published where
 * sagitta could check it, so the record has no .zmx map: such a file is
 * refused on import and the design on export. */
static const sg_shape_key qcon_keys[] = {
    {"norm_radius", 0, 1, 0}, {"terms", QCON_MAX, 1, 0}, {NULL, 0, 0, 0}};
const sg_shape_type sg_shape_qcon_type = {
    .type = SG_SURF_QCON, .name = "Q-type asphere", .ops = &qcon_ops, .keys = qcon_keys};
