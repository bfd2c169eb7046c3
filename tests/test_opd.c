/*
 * test_opd.c - the optical path and the OPD against independent truths.
 *
 * 1. The Cassegrain (object 500 km away) and the TMA (object at infinity)
 *    over a field x pupil grid: the precise method's OPD against one
 *    computed here in MPFR at 320 bits.  The test traces each ray itself,
 *    through its own conic intersection, reflection and refraction, from
 *    the object point (or the start plane) through the precise method's
 *    double point on surface 1; it builds the reference sphere and the
 *    path differences itself.  Nothing of src/trace/opd.c or the tracers'
 *    optical paths is used.  The plain double OPD (the classic method) is
 *    shown to err by about 1e-4 waves on the Cassegrain.
 * 2. A paraboloid mirror on axis with the object at infinity, and an
 *    ellipsoid mirror imaging one focus onto the other: zero OPD.
 * 3. OPD and transverse aberration agree through eps = -(R / n) dW / dY
 *    on a singlet and the Cooke triplet, which have real aberrations.
 */
#include <math.h>
#include <mpfr.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

enum { PREC = 320, MAXS = 64 };

/* ------------------------------------------------------------------------
 * An MPFR ray trace of standard (conic) surfaces, written for this test.
 * ------------------------------------------------------------------------ */

typedef struct mray {
    mpfr_t p[3], d[3], opl;
} mray;

typedef struct mtmp {
    mpfr_t a, b, c, e, f, g, h;
} mtmp;

static void mray_init(mray *r)
{
    int k;
    for (k = 0; k < 3; k++)
        mpfr_inits2(PREC, r->p[k], r->d[k], (mpfr_ptr)0);
    mpfr_init2(r->opl, PREC);
}

static void mray_clear(mray *r)
{
    int k;
    for (k = 0; k < 3; k++)
        mpfr_clears(r->p[k], r->d[k], (mpfr_ptr)0);
    mpfr_clear(r->opl);
}

static void mtmp_init(mtmp *t)
{
    mpfr_inits2(PREC, t->a, t->b, t->c, t->e, t->f, t->g, t->h, (mpfr_ptr)0);
}

static void mtmp_clear(mtmp *t)
{
    mpfr_clears(t->a, t->b, t->c, t->e, t->f, t->g, t->h, (mpfr_ptr)0);
}

/* out = a . b */
static void mdot(mpfr_t out, mpfr_t *a, mpfr_t *b, mpfr_t tmp)
{
    int k;
    mpfr_mul(out, a[0], b[0], MPFR_RNDN);
    for (k = 1; k < 3; k++) {
        mpfr_mul(tmp, a[k], b[k], MPFR_RNDN);
        mpfr_add(out, out, tmp, MPFR_RNDN);
    }
}

static void mnormalize(mpfr_t *v, mtmp *t)
{
    int k;
    mdot(t->a, v, v, t->b);
    mpfr_sqrt(t->a, t->a, MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_div(v[k], v[k], t->a, MPFR_RNDN);
}

/* Moves r along its direction by s, adding n s to the optical path. */
static void madvance(mray *r, mpfr_t s, double n, mtmp *t)
{
    int k;
    for (k = 0; k < 3; k++) {
        mpfr_mul(t->h, s, r->d[k], MPFR_RNDN);
        mpfr_add(r->p[k], r->p[k], t->h, MPFR_RNDN);
    }
    mpfr_mul_d(t->h, s, n, MPFR_RNDN);
    mpfr_add(r->opl, r->opl, t->h, MPFR_RNDN);
}

/* S(r2) and S'(r2) of a conic plus even asphere (coefficients of r^2,
 * r^4, ...): S = c r2 / (1 + sqrt(1 - k1 c^2 r2)) + sum a_j r2^j. */
static void sag_r2(const sg_surface *s, double c, double k1, mpfr_t r2, mpfr_t S, mpfr_t dS,
                   mtmp *t)
{
    mpfr_t q, pw;
    int j;
    mpfr_inits2(PREC, q, pw, (mpfr_ptr)0);
    (void)c;
    /* With the radius itself (1 / R would round): q = sign(R) sqrt(R^2 -
     * k1 r2), S = r2 / (R + q), S' = 1 / (2 q). */
    mpfr_set_d(q, s->radius, MPFR_RNDN);
    mpfr_sqr(q, q, MPFR_RNDN);
    mpfr_mul_d(pw, r2, k1, MPFR_RNDN);
    mpfr_sub(q, q, pw, MPFR_RNDN);
    mpfr_sqrt(q, q, MPFR_RNDN);
    if (s->radius < 0.0)
        mpfr_neg(q, q, MPFR_RNDN);
    mpfr_add_d(S, q, s->radius, MPFR_RNDN);
    mpfr_div(S, r2, S, MPFR_RNDN);
    mpfr_mul_2ui(dS, q, 1, MPFR_RNDN);
    mpfr_ui_div(dS, 1, dS, MPFR_RNDN);
    mpfr_set_ui(pw, 1, MPFR_RNDN); /* r2^(j-1) */
    for (j = 1; j <= SG_NASPH; j++) {
        double a = s->asph[j - 1];
        if (a != 0.0) {
            mpfr_mul_d(t->h, pw, a * j, MPFR_RNDN);
            mpfr_add(dS, dS, t->h, MPFR_RNDN);
            mpfr_mul(t->h, pw, r2, MPFR_RNDN);
            mpfr_mul_d(t->h, t->h, a, MPFR_RNDN);
            mpfr_add(S, S, t->h, MPFR_RNDN);
        }
        mpfr_mul(pw, pw, r2, MPFR_RNDN);
    }
    mpfr_clears(q, pw, (mpfr_ptr)0);
}

/* Newton along the ray on F = z - S(x^2 + y^2) from the step t->g (the
 * base conic's root) until the step is below 2^-250. */
static int polish(const sg_surface *s, double c, double k1, mpfr_t *P, mpfr_t *D, mtmp *t)
{
    mpfr_t X[3], r2, S, dS, F, Fp;
    int it, k, rc = -1;
    for (k = 0; k < 3; k++)
        mpfr_init2(X[k], PREC);
    mpfr_inits2(PREC, r2, S, dS, F, Fp, (mpfr_ptr)0);
    for (it = 0; it < 100; it++) {
        for (k = 0; k < 3; k++)
            mpfr_fma(X[k], t->g, D[k], P[k], MPFR_RNDN);
        mpfr_mul(r2, X[0], X[0], MPFR_RNDN);
        mpfr_fma(r2, X[1], X[1], r2, MPFR_RNDN);
        sag_r2(s, c, k1, r2, S, dS, t);
        mpfr_sub(F, X[2], S, MPFR_RNDN);
        /* dF/ds = D_z - 2 S' (x D_x + y D_y) */
        mpfr_mul(Fp, X[0], D[0], MPFR_RNDN);
        mpfr_fma(Fp, X[1], D[1], Fp, MPFR_RNDN);
        mpfr_mul(Fp, Fp, dS, MPFR_RNDN);
        mpfr_mul_2ui(Fp, Fp, 1, MPFR_RNDN);
        mpfr_sub(Fp, D[2], Fp, MPFR_RNDN);
        mpfr_div(F, F, Fp, MPFR_RNDN);
        mpfr_sub(t->g, t->g, F, MPFR_RNDN);
        if (mpfr_zero_p(F) || mpfr_get_exp(F) < -250) {
            rc = 0;
            break;
        }
    }
    for (k = 0; k < 3; k++)
        mpfr_clear(X[k]);
    mpfr_clears(r2, S, dS, F, Fp, (mpfr_ptr)0);
    return rc;
}

/* Traces r (in surface 1's frame, before it) through surfaces 1..n-1 of
 * sys; indices from the tracer (their absolute values).  Returns 0 when
 * it reaches the image, with r on it in the image's frame. */
static int mtrace(const sg_system *sys, const sg_tracer *tr, mray *r, mtmp *t)
{
    int i, k;
    for (i = 1; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        double c = sg_surface_curvature(s), k1 = 1.0 + s->conic;
        double nb = fabs(sg_tracer_index(tr, i - 1)), na = fabs(sg_tracer_index(tr, i));
        mpfr_t *P = r->p, *D = r->d;
        if (i > 1)
            mpfr_sub_d(P[2], P[2], sys->surf[i - 1].thickness, MPFR_RNDN);
        /* F = c (x^2 + y^2 + k1 z^2) - 2 z along P + s D: A s^2 + 2 B s + C. */
        if (c == 0.0) {
            mpfr_div(t->e, P[2], D[2], MPFR_RNDN);
            mpfr_neg(t->e, t->e, MPFR_RNDN);
        } else {
            /* R F = x^2 + y^2 + k1 z^2 - 2 R z, with R itself. */
            double R = s->radius;
            mpfr_mul(t->a, D[2], D[2], MPFR_RNDN);
            mpfr_mul_d(t->a, t->a, k1, MPFR_RNDN);
            mpfr_fma(t->a, D[1], D[1], t->a, MPFR_RNDN);
            mpfr_fma(t->a, D[0], D[0], t->a, MPFR_RNDN);
            mpfr_mul(t->b, P[2], D[2], MPFR_RNDN);
            mpfr_mul_d(t->b, t->b, k1, MPFR_RNDN);
            mpfr_fma(t->b, P[1], D[1], t->b, MPFR_RNDN);
            mpfr_fma(t->b, P[0], D[0], t->b, MPFR_RNDN);
            mpfr_mul_d(t->e, D[2], R, MPFR_RNDN);
            mpfr_sub(t->b, t->b, t->e, MPFR_RNDN);
            mpfr_mul(t->c, P[2], P[2], MPFR_RNDN);
            mpfr_mul_d(t->c, t->c, k1, MPFR_RNDN);
            mpfr_fma(t->c, P[1], P[1], t->c, MPFR_RNDN);
            mpfr_fma(t->c, P[0], P[0], t->c, MPFR_RNDN);
            mpfr_mul_d(t->e, P[2], 2.0 * R, MPFR_RNDN);
            mpfr_sub(t->c, t->c, t->e, MPFR_RNDN);
            /* The root of the vertex sheet: -C / (B + sign(B) sqrt(B^2 - A C))
             * where B's sign is the ray's towards the vertex plane. */
            mpfr_mul(t->e, t->b, t->b, MPFR_RNDN);
            mpfr_mul(t->f, t->a, t->c, MPFR_RNDN);
            mpfr_sub(t->e, t->e, t->f, MPFR_RNDN);
            if (mpfr_sgn(t->e) < 0)
                return -1;
            mpfr_sqrt(t->e, t->e, MPFR_RNDN);
            if (mpfr_sgn(t->b) < 0)
                mpfr_neg(t->e, t->e, MPFR_RNDN);
            mpfr_add(t->f, t->b, t->e, MPFR_RNDN);
            /* The two roots -C / q and -q / A (q = B + sign(B) sqrt); the
             * one nearest the vertex plane's crossing is the vertex
             * sheet's (a hyperboloid's other sheet may lie nearer). */
            mpfr_div(t->e, t->c, t->f, MPFR_RNDN);
            mpfr_neg(t->e, t->e, MPFR_RNDN);
            if (!mpfr_zero_p(t->a)) {
                mpfr_div(t->f, t->f, t->a, MPFR_RNDN);
                mpfr_neg(t->f, t->f, MPFR_RNDN);
                mpfr_div(t->h, P[2], D[2], MPFR_RNDN);
                mpfr_neg(t->h, t->h, MPFR_RNDN); /* the plane's step */
                mpfr_sub(t->b, t->e, t->h, MPFR_RNDN);
                mpfr_sub(t->c, t->f, t->h, MPFR_RNDN);
                if (mpfr_cmpabs(t->c, t->b) < 0)
                    mpfr_set(t->e, t->f, MPFR_RNDN);
            }
        }
        mpfr_set(t->g, t->e, MPFR_RNDN);
        if (s->type == SG_SURF_EVENASPH && polish(s, c, k1, P, D, t) != 0)
            return -3;
        madvance(r, t->g, nb, t);
        if (i == sys->nsurf - 1)
            return 0;
        /* The unit normal (c x, c y, c k1 z - 1), turned along D. */
        {
            mpfr_t N[3];
            for (k = 0; k < 3; k++)
                mpfr_init2(N[k], PREC);
            if (s->type == SG_SURF_EVENASPH) {
                /* grad (z - S(x^2 + y^2)) = (-2 x S', -2 y S', 1) */
                mpfr_mul(t->a, P[0], P[0], MPFR_RNDN);
                mpfr_fma(t->a, P[1], P[1], t->a, MPFR_RNDN);
                sag_r2(s, c, k1, t->a, t->b, t->c, t);
                mpfr_mul_2ui(t->c, t->c, 1, MPFR_RNDN);
                mpfr_mul(N[0], P[0], t->c, MPFR_RNDN);
                mpfr_neg(N[0], N[0], MPFR_RNDN);
                mpfr_mul(N[1], P[1], t->c, MPFR_RNDN);
                mpfr_neg(N[1], N[1], MPFR_RNDN);
                mpfr_set_ui(N[2], 1, MPFR_RNDN);
            } else {
                /* (x, y, k1 z - R), or the plane's (0, 0, -1) */
                mpfr_set(N[0], P[0], MPFR_RNDN);
                mpfr_set(N[1], P[1], MPFR_RNDN);
                mpfr_mul_d(N[2], P[2], k1, MPFR_RNDN);
                if (c == 0.0) {
                    mpfr_set_zero(N[0], 1);
                    mpfr_set_zero(N[1], 1);
                    mpfr_set_si(N[2], -1, MPFR_RNDN);
                } else {
                    mpfr_sub_d(N[2], N[2], s->radius, MPFR_RNDN);
                }
            }
            mnormalize(N, t);
            mdot(t->a, N, D, t->b); /* cos i */
            if (mpfr_sgn(t->a) < 0) {
                for (k = 0; k < 3; k++)
                    mpfr_neg(N[k], N[k], MPFR_RNDN);
                mpfr_neg(t->a, t->a, MPFR_RNDN);
            }
            if (s->mat.kind == SG_MAT_MIRROR) {
                mpfr_mul_2ui(t->a, t->a, 1, MPFR_RNDN);
                for (k = 0; k < 3; k++) {
                    mpfr_mul(t->b, t->a, N[k], MPFR_RNDN);
                    mpfr_sub(D[k], D[k], t->b, MPFR_RNDN);
                }
            } else {
                /* D' = mu D + (cos t - mu cos i) N */
                /* mu = n / n' at full precision. */
                mpfr_set_d(t->f, nb, MPFR_RNDN);
                mpfr_div_d(t->f, t->f, na, MPFR_RNDN);
                mpfr_mul(t->b, t->a, t->a, MPFR_RNDN);
                mpfr_ui_sub(t->b, 1, t->b, MPFR_RNDN);
                mpfr_mul(t->b, t->b, t->f, MPFR_RNDN);
                mpfr_mul(t->b, t->b, t->f, MPFR_RNDN);
                mpfr_ui_sub(t->b, 1, t->b, MPFR_RNDN);
                if (mpfr_sgn(t->b) < 0)
                    return -2;
                mpfr_sqrt(t->b, t->b, MPFR_RNDN);
                mpfr_mul(t->c, t->a, t->f, MPFR_RNDN);
                mpfr_sub(t->b, t->b, t->c, MPFR_RNDN);
                for (k = 0; k < 3; k++) {
                    mpfr_mul(D[k], D[k], t->f, MPFR_RNDN);
                    mpfr_mul(t->c, t->b, N[k], MPFR_RNDN);
                    mpfr_add(D[k], D[k], t->c, MPFR_RNDN);
                }
            }
            for (k = 0; k < 3; k++)
                mpfr_clear(N[k]);
        }
    }
    return 0;
}

/* The MPFR launch of the ray that the precise trace took: from the object
 * point through its point on surface 1, or, at infinity, from that point
 * along the field's direction, with the optical path from the plane
 * through the chief ray's point on surface 1 (c1) normal to it. */
static void mlaunch(const sg_system *sys, const sg_tracer *tr, const sg_ray_surface *rows,
                    const double c1[3], mray *r, mtmp *t)
{
    int k;
    double n0 = fabs(sg_tracer_index(tr, 0));
    mpfr_set_d(r->p[0], rows[1].x, MPFR_RNDN);
    mpfr_set_d(r->p[1], rows[1].y, MPFR_RNDN);
    mpfr_set_d(r->p[2], rows[1].z, MPFR_RNDN);
    if (isinf(sys->surf[0].thickness)) {
        mpfr_set_d(r->d[0], rows[0].l, MPFR_RNDN);
        mpfr_set_d(r->d[1], rows[0].m, MPFR_RNDN);
        mpfr_set_d(r->d[2], rows[0].n, MPFR_RNDN);
        mnormalize(r->d, t);
        mpfr_set_zero(r->opl, 1);
        for (k = 0; k < 3; k++) {
            mpfr_sub_d(t->e, r->p[k], c1[k], MPFR_RNDN);
            mpfr_mul(t->e, t->e, r->d[k], MPFR_RNDN);
            mpfr_add(r->opl, r->opl, t->e, MPFR_RNDN);
        }
        mpfr_mul_d(r->opl, r->opl, n0, MPFR_RNDN);
    } else {
        /* The object point, in surface 1's frame. */
        double o[3] = {rows[0].x, rows[0].y, rows[0].z - sys->surf[0].thickness};
        mpfr_sub_d(r->d[0], r->p[0], o[0], MPFR_RNDN);
        mpfr_sub_d(r->d[1], r->p[1], o[1], MPFR_RNDN);
        mpfr_sub_d(r->d[2], r->p[2], o[2], MPFR_RNDN);
        mdot(t->f, r->d, r->d, t->g);
        mpfr_sqrt(t->f, t->f, MPFR_RNDN);
        mpfr_mul_d(r->opl, t->f, n0, MPFR_RNDN);
        mnormalize(r->d, t);
    }
    /* The point is on surface 1 already: mtrace's first step is ~0. */
}

/* The OPL of r to the sphere through E = (0, 0, ez) centred on C, in
 * waves of lam (lens units); r on the image, direction d, index n. */
static void msphere_opl(mray *r, mpfr_t *C, double ez, double n, double side, mpfr_t out,
                        mtmp *t)
{
    mpfr_t W[3], R2;
    int k;
    for (k = 0; k < 3; k++)
        mpfr_init2(W[k], PREC);
    mpfr_init2(R2, PREC);
    for (k = 0; k < 3; k++)
        mpfr_sub(W[k], r->p[k], C[k], MPFR_RNDN);
    /* R^2 = C_x^2 + C_y^2 + (ez - C_z)^2 */
    mpfr_d_sub(t->a, ez, C[2], MPFR_RNDN);
    mpfr_mul(R2, t->a, t->a, MPFR_RNDN);
    mpfr_fma(R2, C[1], C[1], R2, MPFR_RNDN);
    mpfr_fma(R2, C[0], C[0], R2, MPFR_RNDN);
    /* s^2 + 2 b s + c = 0 (unit d): s = -b + side sqrt(b^2 - c) */
    mdot(t->b, W, r->d, t->a);
    mdot(t->c, W, W, t->a);
    mpfr_sub(t->c, t->c, R2, MPFR_RNDN);
    mpfr_mul(t->e, t->b, t->b, MPFR_RNDN);
    mpfr_sub(t->e, t->e, t->c, MPFR_RNDN);
    mpfr_sqrt(t->e, t->e, MPFR_RNDN);
    mpfr_mul_d(t->e, t->e, side, MPFR_RNDN);
    mpfr_sub(t->e, t->e, t->b, MPFR_RNDN);
    mpfr_mul_d(t->e, t->e, n, MPFR_RNDN);
    mpfr_add(out, r->opl, t->e, MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_clear(W[k]);
    mpfr_clear(R2);
}

static double wave_mm(const sg_system *sys)
{
    return sys->wave[sys->primary_wave].um * 1e-3;
}

/* The independent OPD of field (hx, hy) at the pupil points pts, against
 * the precise method's; returns the largest difference in waves and
 * fills the plain double (classic) method's largest difference. */
static double grid_check(const char *file, const double (*fields)[2], int nf,
                         double *classic_worst, double *bound_ratio)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_tracer *tp = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    sg_tracer *tc = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
    sg_tracer *tm = tu_tracer(sys, cat, SG_METHOD_MPFR);
    int n = sg_tracer_nsurf(tp), f, i, j, count = 0;
    double mworst = 0.0, worst = 0.0, lam = wave_mm(sys), ez = sg_tracer_paraxial(tp)->exp_pos;
    double nimg = fabs(sg_tracer_index(tp, n - 1));
    sg_ray_surface chief[MAXS], rows[MAXS], crow[MAXS];
    mray r;
    mtmp t;
    mpfr_t C[3], copl, ropl;
    assert_true(n <= MAXS);
    mray_init(&r);
    mtmp_init(&t);
    mpfr_inits2(PREC, C[0], C[1], C[2], copl, ropl, (mpfr_ptr)0);
    *classic_worst = 0.0;
    *bound_ratio = 0.0;
    for (f = 0; f < nf; f++) {
        double c1[3], side;
        sg_opd_ref ref, cref, mref;
        assert_int_equal(sg_trace_normalized(tp, fields[f][0], fields[f][1], 0, 0, chief), SG_OK);
        c1[0] = chief[1].x;
        c1[1] = chief[1].y;
        c1[2] = chief[1].z;
        mlaunch(sys, tp, chief, c1, &r, &t);
        assert_int_equal(mtrace(sys, tp, &r, &t), 0);
        for (i = 0; i < 3; i++)
            mpfr_set(C[i], r.p[i], MPFR_RNDN);
        /* The sphere lies behind the image point along the chief ray when
         * the pupil does. */
        mpfr_d_sub(t.a, ez, C[2], MPFR_RNDN);
        side = mpfr_get_d(t.a, MPFR_RNDN) * chief[n - 1].n -
                           mpfr_get_d(C[0], MPFR_RNDN) * chief[n - 1].l -
                           mpfr_get_d(C[1], MPFR_RNDN) * chief[n - 1].m <
                       0.0
                   ? -1.0
                   : 1.0;
        msphere_opl(&r, C, ez, nimg, side, copl, &t);
        assert_int_equal(sg_opd_reference(tp, fields[f][0], fields[f][1], &ref, NULL), SG_OK);
        assert_int_equal(sg_opd_reference(tc, fields[f][0], fields[f][1], &cref, NULL), SG_OK);
        assert_int_equal(sg_opd_reference(tm, fields[f][0], fields[f][1], &mref, NULL), SG_OK);
        /* At infinity the chief ray's path starts on surface 1 itself. */
        if (isinf(sys->surf[0].thickness))
            assert_true(chief[1].opl == 0.0 && chief[1].opl_lo == 0.0);
        for (i = -3; i <= 3; i++)
            for (j = -3; j <= 3; j++) {
                double px = i / 3.0, py = j / 3.0, got, want, e;
                sg_opd o, oc;
                if (px * px + py * py > 1.0)
                    continue;
                assert_int_equal(sg_trace_opd(tp, &ref, px, py, rows, &o), SG_OK);
                assert_int_equal(o.status, SG_OK);
                mlaunch(sys, tp, rows, c1, &r, &t);
                /* The path to surface 1 from the object point or the start
                 * plane, as the test forms it. */
                {
                    double o1 = mpfr_get_d(r.opl, MPFR_RNDN);
                    if (!(fabs(rows[1].opl - o1) <= 1e-15 * fabs(o1) + 1e-12))
                        fail_msg("%s: the OPL at surface 1 is %.17g, not %.17g", file,
                                 rows[1].opl, o1);
                }
                assert_int_equal(mtrace(sys, tp, &r, &t), 0);
                msphere_opl(&r, C, ez, nimg, side, ropl, &t);
                mpfr_sub(t.a, copl, ropl, MPFR_RNDN);
                mpfr_div_d(t.a, t.a, lam, MPFR_RNDN);
                want = mpfr_get_d(t.a, MPFR_RNDN);
                got = o.opd_waves;
                e = fabs(got - want);
                if (e > worst)
                    worst = e;
                if (o.error_bound > 0.0 && e / o.error_bound > *bound_ratio)
                    *bound_ratio = e / o.error_bound;
                /* The test's own launch from the rounded points errs by far
                 * less than 1e-13 waves (Fermat: a ray's OPD moves only
                 * with its pupil coordinate). */
                if (e > o.error_bound + 1e-13)
                    fail_msg("%s field (%g, %g) pupil (%g, %g): OPD %.17g off the MPFR %.17g by "
                             "%.3g waves, beyond its bound %.3g",
                             file, fields[f][0], fields[f][1], px, py, got, want, e,
                             o.error_bound);
                if (e > 1e-10)
                    fail_msg("%s field (%g, %g) pupil (%g, %g): OPD %.17g, MPFR %.17g: off by "
                             "%.3g waves",
                             file, fields[f][0], fields[f][1], px, py, got, want, e);
                /* Transverse aberration: the image points' difference. */
                assert_true(fabs(o.ey - (rows[n - 1].y - chief[n - 1].y)) <= 1e-15 &&
                            fabs(o.ex - (rows[n - 1].x - chief[n - 1].x)) <= 1e-15);
                assert_int_equal(sg_trace_opd(tc, &cref, px, py, crow, &oc), SG_OK);
                if (fabs(oc.opd_waves - want) > *classic_worst)
                    *classic_worst = fabs(oc.opd_waves - want);
                /* The mpfr method's OPD (its own indices in MPFR). */
                assert_int_equal(sg_trace_opd(tm, &mref, px, py, crow, &oc), SG_OK);
                if (fabs(oc.opd_waves - want) > mworst)
                    mworst = fabs(oc.opd_waves - want);
                count++;
            }
    }
    print_message("# %-15s %d rays: precise OPD within %.3g waves of the test's MPFR "
                  "(error / bound at most %.3g), mpfr method within %.3g; plain double "
                  "(classic) off by up to %.3g waves\n",
                  file, count, worst, *bound_ratio, mworst, *classic_worst);
    assert_true(mworst <= 1e-10);
    mpfr_clears(C[0], C[1], C[2], copl, ropl, (mpfr_ptr)0);
    mtmp_clear(&t);
    mray_clear(&r);
    sg_tracer_free(tp);
    sg_tracer_free(tc);
    sg_tracer_free(tm);
    sg_system_free(sys);
    sg_catalog_free(cat);
    return worst;
}

static void cassegrain_vs_mpfr(void **state)
{
    static const double fields[][2] = {{0, 0}, {0, 0.5}, {0, 1}, {0.6, 0.6}};
    double cw, br;
    (void)state;
    grid_check("cassegrain.json", fields, 4, &cw, &br);
    /* 5e8 mm of path in double: the plain OPD errs visibly, by about the
     * rounding of the path (6e-8 mm, 1e-4 waves), but no more. */
    assert_true(cw > 1e-6 && cw < 2e-3);
}

static void tma_vs_mpfr(void **state)
{
    static const double fields[][2] = {{0, 0}, {0, 0.5}, {0, 1}, {0.5, 0.8}};
    double cw, br;
    (void)state;
    grid_check("tma.json", fields, 4, &cw, &br);
    /* Paths of 3 m: the plain OPD is good to some 1e-9 waves. */
    assert_true(cw < 1e-7);
}

/* ------------------------------------------------------------------------
 * Perfect conics.
 * ------------------------------------------------------------------------ */

/* One mirror: object distance T0 (inf for infinity), mirror radius R and
 * conic k as the stop, image after -T1.  EPD 40. */
static sg_system *one_mirror(double T0, double R, double k, double T1)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 3), SG_OK);
    sys->surf[0].thickness = T0;
    sys->surf[1].radius = R;
    sys->surf[1].conic = k;
    sys->surf[1].mat.kind = SG_MAT_MIRROR;
    sys->surf[1].thickness = T1;
    sys->stop = 1;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = 40.0;
    sys->field_type = isinf(T0) ? SG_FIELD_ANGLE : SG_FIELD_OBJECT_HEIGHT;
    sys->nfield = 1;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[0].weight = 1.0;
    return sys;
}

static double zero_opd(sg_system *sys, sg_method m, const char *what)
{
    sg_catalog *cat = tu_catalog();
    sg_tracer *t = tu_tracer(sys, cat, m);
    sg_ray_surface rows[8];
    sg_opd_ref ref;
    double worst = 0.0, wb = 0.0;
    int i, j;
    assert_int_equal(sg_opd_reference(t, 0, 0, &ref, NULL), SG_OK);
    assert_int_equal(ref.status, SG_OK);
    for (i = -4; i <= 4; i++)
        for (j = -4; j <= 4; j++) {
            sg_opd o;
            double px = i / 4.0, py = j / 4.0;
            if (px * px + py * py > 1.0)
                continue;
            assert_int_equal(sg_trace_opd(t, &ref, px, py, rows, &o), SG_OK);
            assert_int_equal(o.status, SG_OK);
            if (fabs(o.opd_waves) > worst)
                worst = fabs(o.opd_waves);
            if (o.error_bound > wb)
                wb = o.error_bound;
        }
    print_message("# %-40s %s: |OPD| at most %.3g waves (bound %.3g)\n", what, sg_method_name(m),
                  worst, wb);
    sg_tracer_free(t);
    sg_catalog_free(cat);
    return worst;
}

static void paraboloid_is_perfect(void **state)
{
    /* z = r^2 / (2R) focuses a parallel beam at R / 2 exactly. */
    sg_system *sys = one_mirror(INFINITY, -200.0, -1.0, -100.0);
    (void)state;
    assert_true(zero_opd(sys, SG_METHOD_PRECISE, "paraboloid R -200 at infinity, f/2.5") <= 1e-10);
    assert_true(zero_opd(sys, SG_METHOD_MPFR, "paraboloid R -200 at infinity, f/2.5") <= 1e-10);
    /* The same mirror as a sphere has real spherical aberration. */
    sys->surf[1].conic = 0.0;
    assert_true(zero_opd(sys, SG_METHOD_PRECISE, "sphere R -200 at infinity") > 0.1);
    sg_system_free(sys);
}

static void ellipsoid_is_perfect(void **state)
{
    /* Eccentricity 0.75 (k = -0.5625, exact), vertex radius 70: foci
     * R / (1 + e) = 40 and R / (1 - e) = 280 from the vertex, both exact. */
    sg_system *sys = one_mirror(280.0, -70.0, -0.5625, -40.0);
    (void)state;
    assert_true(zero_opd(sys, SG_METHOD_PRECISE, "ellipsoid e 0.75, foci 280 and 40") <= 1e-10);
    assert_true(zero_opd(sys, SG_METHOD_MPFR, "ellipsoid e 0.75, foci 280 and 40") <= 1e-10);
    /* Moved off its foci it is not perfect. */
    sys->surf[0].thickness = 270.0;
    assert_true(zero_opd(sys, SG_METHOD_PRECISE, "the ellipsoid with the object 10 mm off") >
                0.1);
    sg_system_free(sys);
}

/* ------------------------------------------------------------------------
 * OPD against transverse aberration.
 * ------------------------------------------------------------------------ */

/* eps_y = -(R / n') dW / dY, W in lens units and Y the sphere point's y;
 * checked by central differences of the OPD along the pupil's y (or x)
 * axis at several pupil points. */
static void fan_check(const char *file, double hx, double hy, int sagittal)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_tracer *t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    sg_ray_surface rows[MAXS];
    sg_opd_ref ref;
    double lam = wave_mm(sys), worst = 0.0, h = 1e-4;
    int n = sg_tracer_nsurf(t), k;
    assert_true(n <= MAXS);
    assert_int_equal(sg_opd_reference(t, hx, hy, &ref, NULL), SG_OK);
    for (k = -4; k <= 4; k++) {
        double p = 0.22 * k, pp[2], pm[2], pc[2], dW, dY, eps, pred, rel;
        sg_opd a, b, c;
        if (k == 0)
            continue;
        pc[0] = sagittal ? p : 0.0;
        pc[1] = sagittal ? 0.0 : p;
        pp[0] = pc[0] + (sagittal ? h : 0.0);
        pp[1] = pc[1] + (sagittal ? 0.0 : h);
        pm[0] = pc[0] - (sagittal ? h : 0.0);
        pm[1] = pc[1] - (sagittal ? 0.0 : h);
        assert_int_equal(sg_trace_opd(t, &ref, pp[0], pp[1], rows, &a), SG_OK);
        assert_int_equal(sg_trace_opd(t, &ref, pm[0], pm[1], rows, &b), SG_OK);
        assert_int_equal(sg_trace_opd(t, &ref, pc[0], pc[1], rows, &c), SG_OK);
        dW = (a.opd_waves - b.opd_waves) * lam;
        dY = sagittal ? a.sphere_x - b.sphere_x : a.sphere_y - b.sphere_y;
        eps = sagittal ? c.ex : c.ey;
        pred = -(ref.radius / ref.n_image) * dW / dY;
        rel = fabs(pred - eps) / fabs(eps);
        if (rel > worst)
            worst = rel;
        if (!(rel < 2e-3))
            fail_msg("%s field (%g, %g) %s pupil %g: transverse %.9g, -(R/n) dW/dY %.9g", file,
                     hx, hy, sagittal ? "x" : "y", p, eps, pred);
    }
    print_message("# %-18s field (%g, %g) %s fan: -(R/n) dW/dY matches the transverse "
                  "aberration within %.2g relative\n",
                  file, hx, hy, sagittal ? "sagittal" : "tangential", worst);
    sg_tracer_free(t);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void opd_vs_transverse(void **state)
{
    (void)state;
    fan_check("singlet.json", 0.0, 0.0, 0);
    fan_check("singlet.json", 0.0, 0.0, 1);
    fan_check("cooke_triplet.json", 0.0, 0.7, 0);
    fan_check("cooke_triplet.json", 0.0, 0.7, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(cassegrain_vs_mpfr),
        cmocka_unit_test(tma_vs_mpfr),
        cmocka_unit_test(paraboloid_is_perfect),
        cmocka_unit_test(ellipsoid_is_perfect),
        cmocka_unit_test(opd_vs_transverse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
