/*
 * test_frames.c - coordinate breaks and surface tilts and decenters in all
 * three methods, against a trace written here in 512-bit MPFR.
 *
 * The reference is built differently from the engine: it keeps each
 * surface's frame as an origin and three axis vectors in one global frame,
 * and carries out Zemax's description literally (decenter along the
 * current x and y, then turn the axes right-handed about the current x,
 * then the new y, then the new z; order 1 the other way round; "reverse"
 * returns to the frame before the surface's tilt).  The engine composes
 * matrices once per surface in frame.c.  Conics are met by the closed-form
 * quadratic, refraction by the vector law, all in 512 bits.
 *
 * Checked: the sign conventions against hand values; the inverse of a
 * break; a fold mirror built two ways and against the unfolded lens; an
 * off-axis parabola's focus (closed form); random tilted, decentred and
 * folded systems of conics, lenses and mirrors (surface 1 a break or
 * tilted in some), where precise and mpfr
 * must lie within their bounds and agree with the reference on every
 * status; the global frames; and the design format's round trip.
 */
#include <math.h>
#include <mpfr.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define PREC 512

static uint64_t rng_state;

static double urand(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * 0x1.0p-53;
}

static double srand1(double a)
{
    return a * (2.0 * urand() - 1.0);
}

/* ------------------------------------------------------------------------
 * The reference: frames as origin and axes, in MPFR.
 * ------------------------------------------------------------------------ */

typedef struct mframe {
    mpfr_t o[3];
    mpfr_t e[3][3]; /* e[k] is axis k, in global coordinates */
} mframe;

static void mf_init(mframe *f)
{
    int i, j;
    for (i = 0; i < 3; i++) {
        mpfr_init2(f->o[i], PREC);
        mpfr_set_zero(f->o[i], 1);
        for (j = 0; j < 3; j++) {
            mpfr_init2(f->e[i][j], PREC);
            mpfr_set_ui(f->e[i][j], i == j, MPFR_RNDN);
        }
    }
}

static void mf_clear(mframe *f)
{
    int i, j;
    for (i = 0; i < 3; i++) {
        mpfr_clear(f->o[i]);
        for (j = 0; j < 3; j++)
            mpfr_clear(f->e[i][j]);
    }
}

static void mf_copy(mframe *dst, const mframe *src)
{
    int i, j;
    for (i = 0; i < 3; i++) {
        mpfr_set(dst->o[i], src->o[i], MPFR_RNDN);
        for (j = 0; j < 3; j++)
            mpfr_set(dst->e[i][j], src->e[i][j], MPFR_RNDN);
    }
}

/* Moves the origin by s along axis k. */
static void mf_shift(mframe *f, int k, double s)
{
    mpfr_t t;
    int j;
    if (s == 0.0)
        return;
    mpfr_init2(t, PREC);
    for (j = 0; j < 3; j++) {
        mpfr_mul_d(t, f->e[k][j], s, MPFR_RNDN);
        mpfr_add(f->o[j], f->o[j], t, MPFR_RNDN);
    }
    mpfr_clear(t);
}

/* Turns the other two axes right-handed about axis k by deg degrees:
 * axis u goes toward axis v, where (k, u, v) is cyclic. */
static void mf_turn(mframe *f, int k, double deg)
{
    mpfr_t a, c, s, t1, t2;
    int u = (k + 1) % 3, v = (k + 2) % 3, j;
    if (deg == 0.0)
        return;
    mpfr_inits2(PREC, a, c, s, t1, t2, (mpfr_ptr)0);
    mpfr_const_pi(a, MPFR_RNDN);
    mpfr_mul_d(a, a, deg, MPFR_RNDN);
    mpfr_div_ui(a, a, 180, MPFR_RNDN);
    mpfr_sin_cos(s, c, a, MPFR_RNDN);
    for (j = 0; j < 3; j++) {
        /* e_u' = e_u cos + e_v sin; e_v' = e_v cos - e_u sin. */
        mpfr_mul(t1, f->e[u][j], c, MPFR_RNDN);
        mpfr_fma(t1, f->e[v][j], s, t1, MPFR_RNDN);
        mpfr_mul(t2, f->e[v][j], c, MPFR_RNDN);
        mpfr_mul(a, f->e[u][j], s, MPFR_RNDN);
        mpfr_sub(t2, t2, a, MPFR_RNDN);
        mpfr_set(f->e[u][j], t1, MPFR_RNDN);
        mpfr_set(f->e[v][j], t2, MPFR_RNDN);
    }
    mpfr_clears(a, c, s, t1, t2, (mpfr_ptr)0);
}

/* Zemax's description of a tilt and decenter, step by step. */
static void mf_change(mframe *f, const sg_frame_change *c)
{
    if (c->order == 0) {
        mf_shift(f, 0, c->dx);
        mf_shift(f, 1, c->dy);
        mf_turn(f, 0, c->tx);
        mf_turn(f, 1, c->ty);
        mf_turn(f, 2, c->tz);
    } else {
        mf_turn(f, 2, c->tz);
        mf_turn(f, 1, c->ty);
        mf_turn(f, 0, c->tx);
        mf_shift(f, 0, c->dx);
        mf_shift(f, 1, c->dy);
    }
}

typedef struct mray {
    mpfr_t p[3], d[3]; /* global */
} mray;

typedef struct truth_row {
    int status;
    double p[3], d[3]; /* local, rounded */
    double g[3], gd[3]; /* global (surface 1's frame), rounded */
    double o[3], e[3][3]; /* the surface's frame: origin and axes */
} truth_row;

/* Traces start/dir (surface 1's frame, which is the global one here)
 * through sys with fixed indices; rows[i] for surfaces 1..n-1. */
static void ref_trace(const sg_system *sys, const double S[3], const double Dv[3],
                      truth_row *rows)
{
    int n = sys->nsurf, i, j, k, done = 0;
    mframe f, keep;
    mray r;
    mpfr_t P[3], D[3], t, A, B, C, disc, q, tmp, nb, na, len, RR, K1;
    double sign = 1.0;
    mf_init(&f);
    mf_init(&keep);
    for (j = 0; j < 3; j++) {
        mpfr_inits2(PREC, r.p[j], r.d[j], P[j], D[j], (mpfr_ptr)0);
        mpfr_set_d(r.p[j], S[j], MPFR_RNDN);
        mpfr_set_d(r.d[j], Dv[j], MPFR_RNDN);
    }
    mpfr_inits2(PREC, t, A, B, C, disc, q, tmp, nb, na, len, RR, K1, (mpfr_ptr)0);
    /* Unit direction. */
    mpfr_set_zero(len, 1);
    for (j = 0; j < 3; j++)
        mpfr_fma(len, r.d[j], r.d[j], len, MPFR_RNDN);
    mpfr_sqrt(len, len, MPFR_RNDN);
    for (j = 0; j < 3; j++)
        mpfr_div(r.d[j], r.d[j], len, MPFR_RNDN);
    mpfr_set_ui(nb, 1, MPFR_RNDN);
    for (i = 1; i < n; i++) {
        const sg_surface *s = &sys->surf[i], *p = &sys->surf[i - 1];
        double c = sg_surface_curvature(s);
        rows[i].status = SG_ENOTREACHED;
        if (done)
            continue;
        if (i > 1) {
            if (p->type != SG_SURF_COORDBRK) {
                if (p->after_mode == SG_AFTER_REVERSE)
                    mf_copy(&f, &keep);
                else
                    mf_change(&f, &p->after);
            }
            mf_shift(&f, 2, p->thickness);
        }
        mf_copy(&keep, &f);
        mf_change(&f, &s->before);
        /* Local coordinates: projections on the axes. */
        for (k = 0; k < 3; k++) {
            mpfr_set_zero(P[k], 1);
            mpfr_set_zero(D[k], 1);
            for (j = 0; j < 3; j++) {
                mpfr_sub(tmp, r.p[j], f.o[j], MPFR_RNDN);
                mpfr_fma(P[k], tmp, f.e[k][j], P[k], MPFR_RNDN);
                mpfr_fma(D[k], r.d[j], f.e[k][j], D[k], MPFR_RNDN);
            }
        }
        /* x^2 + y^2 + k1 z^2 - 2 R z = 0 along P + t D, with R and
         * k1 = 1 + conic exact (1/R and 1 + conic in double would move
         * the surface by a rounding). */
        mpfr_set_d(K1, s->conic, MPFR_RNDN);
        mpfr_add_ui(K1, K1, 1, MPFR_RNDN);
        if (c == 0.0) {
            if (mpfr_zero_p(D[2])) {
                rows[i].status = SG_EMISS;
                done = 1;
                continue;
            }
            mpfr_div(t, P[2], D[2], MPFR_RNDN);
            mpfr_neg(t, t, MPFR_RNDN);
        } else {
            mpfr_set_d(RR, s->radius, MPFR_RNDN);
            /* A, B/2, C */
            mpfr_mul(A, D[2], D[2], MPFR_RNDN);
            mpfr_mul(A, A, K1, MPFR_RNDN);
            mpfr_fma(A, D[0], D[0], A, MPFR_RNDN);
            mpfr_fma(A, D[1], D[1], A, MPFR_RNDN);
            mpfr_mul(B, P[2], D[2], MPFR_RNDN);
            mpfr_mul(B, B, K1, MPFR_RNDN);
            mpfr_fma(B, P[0], D[0], B, MPFR_RNDN);
            mpfr_fma(B, P[1], D[1], B, MPFR_RNDN);
            mpfr_mul(tmp, RR, D[2], MPFR_RNDN);
            mpfr_sub(B, B, tmp, MPFR_RNDN);
            mpfr_mul(C, P[2], P[2], MPFR_RNDN);
            mpfr_mul(C, C, K1, MPFR_RNDN);
            mpfr_fma(C, P[0], P[0], C, MPFR_RNDN);
            mpfr_fma(C, P[1], P[1], C, MPFR_RNDN);
            mpfr_mul(tmp, RR, P[2], MPFR_RNDN);
            mpfr_mul_ui(tmp, tmp, 2, MPFR_RNDN);
            mpfr_sub(C, C, tmp, MPFR_RNDN);
            /* A t^2 + 2 B t + C = 0: the root whose point lies on the
             * vertex's sheet (k1 z / R < 1), nearer the tangent plane. */
            mpfr_mul(disc, B, B, MPFR_RNDN);
            mpfr_mul(tmp, A, C, MPFR_RNDN);
            mpfr_sub(disc, disc, tmp, MPFR_RNDN);
            if (mpfr_sgn(disc) < 0) {
                rows[i].status = SG_EMISS;
                done = 1;
                continue;
            }
            mpfr_sqrt(disc, disc, MPFR_RNDN);
            {
                mpfr_t t1, t2, z;
                int ok1, ok2;
                mpfr_inits2(PREC, t1, t2, z, (mpfr_ptr)0);
                /* q = -(B + sign(B) sqrt): roots q / A and C / q. */
                if (mpfr_sgn(B) >= 0)
                    mpfr_add(q, B, disc, MPFR_RNDN);
                else
                    mpfr_sub(q, B, disc, MPFR_RNDN);
                mpfr_neg(q, q, MPFR_RNDN);
                if (mpfr_zero_p(A))
                    mpfr_set_inf(t1, 1);
                else
                    mpfr_div(t1, q, A, MPFR_RNDN);
                if (mpfr_zero_p(q))
                    mpfr_set_inf(t2, 1);
                else
                    mpfr_div(t2, C, q, MPFR_RNDN);
                mpfr_fma(z, t1, D[2], P[2], MPFR_RNDN);
                mpfr_mul(z, z, K1, MPFR_RNDN);
                mpfr_div(z, z, RR, MPFR_RNDN);
                ok1 = mpfr_number_p(t1) && mpfr_cmp_ui(z, 1) <= 0;
                mpfr_fma(z, t2, D[2], P[2], MPFR_RNDN);
                mpfr_mul(z, z, K1, MPFR_RNDN);
                mpfr_div(z, z, RR, MPFR_RNDN);
                ok2 = mpfr_number_p(t2) && mpfr_cmp_ui(z, 1) <= 0;
                if (ok1 && ok2) {
                    /* nearer the tangent plane's step -P_z / D_z */
                    mpfr_div(tmp, P[2], D[2], MPFR_RNDN);
                    mpfr_neg(tmp, tmp, MPFR_RNDN);
                    mpfr_sub(A, t1, tmp, MPFR_RNDN);
                    mpfr_sub(C, t2, tmp, MPFR_RNDN);
                    mpfr_set(t, mpfr_cmpabs(A, C) <= 0 ? t1 : t2, MPFR_RNDN);
                } else if (ok1 || ok2) {
                    mpfr_set(t, ok1 ? t1 : t2, MPFR_RNDN);
                } else {
                    rows[i].status = SG_EMISS;
                    done = 1;
                }
                mpfr_clears(t1, t2, z, (mpfr_ptr)0);
                if (done)
                    continue;
            }
        }
        for (j = 0; j < 3; j++) {
            mpfr_fma(P[j], t, D[j], P[j], MPFR_RNDN);
            mpfr_fma(r.p[j], t, r.d[j], r.p[j], MPFR_RNDN);
        }
        /* The bend, in local coordinates, then back to global. */
        if (s->type != SG_SURF_COORDBRK && i < n - 1) {
            mpfr_t g[3], cosI;
            mpfr_inits2(PREC, g[0], g[1], g[2], cosI, (mpfr_ptr)0);
            /* (x, y, k1 z - R) / R, the gradient of the sag equation. */
            if (c == 0.0) {
                mpfr_set_zero(g[0], 1);
                mpfr_set_zero(g[1], 1);
                mpfr_set_si(g[2], -1, MPFR_RNDN);
            } else {
                mpfr_div(g[0], P[0], RR, MPFR_RNDN);
                mpfr_div(g[1], P[1], RR, MPFR_RNDN);
                mpfr_mul(g[2], P[2], K1, MPFR_RNDN);
                mpfr_div(g[2], g[2], RR, MPFR_RNDN);
                mpfr_sub_ui(g[2], g[2], 1, MPFR_RNDN);
            }
            mpfr_set_zero(len, 1);
            for (j = 0; j < 3; j++)
                mpfr_fma(len, g[j], g[j], len, MPFR_RNDN);
            mpfr_sqrt(len, len, MPFR_RNDN);
            mpfr_set_zero(cosI, 1);
            for (j = 0; j < 3; j++) {
                mpfr_div(g[j], g[j], len, MPFR_RNDN);
                mpfr_fma(cosI, g[j], D[j], cosI, MPFR_RNDN);
            }
            if (s->mat.kind == SG_MAT_MIRROR) {
                sign = -sign;
                mpfr_mul_ui(tmp, cosI, 2, MPFR_RNDN);
                for (j = 0; j < 3; j++) {
                    mpfr_mul(q, tmp, g[j], MPFR_RNDN);
                    mpfr_sub(D[j], D[j], q, MPFR_RNDN);
                }
            } else {
                mpfr_t mu, kk;
                mpfr_inits2(PREC, mu, kk, (mpfr_ptr)0);
                mpfr_set_d(na, s->mat.kind == SG_MAT_INDEX ? s->mat.index : 1.0, MPFR_RNDN);
                mpfr_div(mu, nb, na, MPFR_RNDN);
                /* k = 1 - mu^2 (1 - cos^2) */
                mpfr_sqr(kk, cosI, MPFR_RNDN);
                mpfr_ui_sub(kk, 1, kk, MPFR_RNDN);
                mpfr_mul(kk, kk, mu, MPFR_RNDN);
                mpfr_mul(kk, kk, mu, MPFR_RNDN);
                mpfr_ui_sub(kk, 1, kk, MPFR_RNDN);
                if (mpfr_sgn(kk) < 0) {
                    rows[i].status = SG_ETIR;
                    done = 1;
                } else {
                    mpfr_sqrt(kk, kk, MPFR_RNDN);
                    if (mpfr_sgn(cosI) < 0)
                        mpfr_neg(kk, kk, MPFR_RNDN);
                    mpfr_fms(kk, mu, cosI, kk, MPFR_RNDN);
                    mpfr_neg(kk, kk, MPFR_RNDN); /* sqrt(k) sgn(cos) - mu cos */
                    for (j = 0; j < 3; j++) {
                        mpfr_mul(D[j], D[j], mu, MPFR_RNDN);
                        mpfr_fma(D[j], kk, g[j], D[j], MPFR_RNDN);
                    }
                    mpfr_set(nb, na, MPFR_RNDN);
                }
                mpfr_clears(mu, kk, (mpfr_ptr)0);
            }
            mpfr_clears(g[0], g[1], g[2], cosI, (mpfr_ptr)0);
            if (done) {
                for (j = 0; j < 3; j++)
                    rows[i].p[j] = mpfr_get_d(P[j], MPFR_RNDN);
                continue;
            }
            /* Back to global: d = sum_k D_k e_k. */
            for (j = 0; j < 3; j++) {
                mpfr_set_zero(r.d[j], 1);
                for (k = 0; k < 3; k++)
                    mpfr_fma(r.d[j], D[k], f.e[k][j], r.d[j], MPFR_RNDN);
            }
        }
        rows[i].status = SG_OK;
        for (j = 0; j < 3; j++) {
            rows[i].p[j] = mpfr_get_d(P[j], MPFR_RNDN);
            rows[i].d[j] = mpfr_get_d(D[j], MPFR_RNDN);
            rows[i].g[j] = mpfr_get_d(r.p[j], MPFR_RNDN);
            rows[i].o[j] = mpfr_get_d(f.o[j], MPFR_RNDN);
            for (k = 0; k < 3; k++)
                rows[i].e[j][k] = mpfr_get_d(f.e[j][k], MPFR_RNDN);
        }
        /* The direction after the surface, globally. */
        for (j = 0; j < 3; j++) {
            mpfr_set_zero(tmp, 1);
            for (k = 0; k < 3; k++)
                mpfr_fma(tmp, D[k], f.e[k][j], tmp, MPFR_RNDN);
            rows[i].gd[j] = mpfr_get_d(tmp, MPFR_RNDN);
        }
    }
    (void)sign;
    mf_clear(&f);
    mf_clear(&keep);
    for (j = 0; j < 3; j++)
        mpfr_clears(r.p[j], r.d[j], P[j], D[j], (mpfr_ptr)0);
    mpfr_clears(t, A, B, C, disc, q, tmp, nb, na, len, RR, K1, (mpfr_ptr)0);
}

/* ------------------------------------------------------------------------
 * Systems.
 * ------------------------------------------------------------------------ */

static sg_system *base_system(int nsurf)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, nsurf), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->stop = 1;
    sys->aper_value = 4.0;
    return sys;
}

static void set_change(sg_frame_change *c, double dx, double dy, double tx, double ty,
                       double tz, int order)
{
    c->dx = dx;
    c->dy = dy;
    c->tx = tx;
    c->ty = ty;
    c->tz = tz;
    c->order = order;
}

static double maxdiff3(const double a[3], double x, double y, double z)
{
    return fmax(fabs(a[0] - x), fmax(fabs(a[1] - y), fabs(a[2] - z)));
}

/* ------------------------------------------------------------------------
 * Cases.
 * ------------------------------------------------------------------------ */

/* Zemax: "tilts in degrees about the respective axis in a right hand
 * direction".  Turning the axes right-handed about x by +30 puts the new
 * z toward -y, so a ray along +z has m = +sin 30 in the new frame; about
 * y, l = -sin 30; a decenter of +2 in x moves the origin, so x falls by 2. */
static void sign_conventions(void **state)
{
    static const struct {
        double dx, tx, ty, tz, D[3], want_l, want_m, want_x;
    } cs[] = {
        {0, 30, 0, 0, {0, 0, 1}, 0.0, 0.5, 0.0},
        {0, 0, 30, 0, {0, 0, 1}, -0.5, 0.0, 0.0},
        {0, 0, 0, 30, {0.6, 0, 0.8}, 0.6 * 0.86602540378443865, -0.3, 0.0},
        {2, 0, 0, 0, {0, 0, 1}, 0.0, 0.0, -2.0},
    };
    sg_catalog *cat = tu_catalog();
    size_t c;
    int m;
    (void)state;
    for (c = 0; c < sizeof cs / sizeof cs[0]; c++) {
        sg_system *sys = base_system(5);
        sys->surf[1].thickness = 10.0;
        sys->surf[2].type = SG_SURF_COORDBRK;
        set_change(&sys->surf[2].before, cs[c].dx, 0, cs[c].tx, cs[c].ty, cs[c].tz, 0);
        sys->surf[2].thickness = 5.0;
        for (m = 0; m < 3; m++) {
            sg_tracer *t = tu_tracer(sys, cat, (sg_method)m);
            sg_ray_surface out[5];
            double S[3] = {0, 0, 0};
            assert_int_equal(sg_trace_start(t, S, cs[c].D, out), SG_OK);
            /* With no turn about z, x is the ray's x less the decenter. */
            double want_x = cs[c].want_x + 10.0 * cs[c].D[0] / cs[c].D[2];
            if (fabs(out[2].l - cs[c].want_l) > 1e-15 || fabs(out[2].m - cs[c].want_m) > 1e-15 ||
                (cs[c].tz == 0.0 && fabs(out[2].x - want_x) > 1e-14))
                fail_msg("case %zu method %d: l %.17g m %.17g x %.17g", c, m, out[2].l,
                         out[2].m, out[2].x);
            sg_tracer_free(t);
        }
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* A break followed by its inverse (the other order, every value negated)
 * leaves the rays as the system without either. */
static void break_and_inverse(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *a = base_system(7), *b = base_system(5);
    int m, k;
    (void)state;
    rng_state = 0x5eedf00dULL;
    a->surf[1].radius = b->surf[1].radius = 40.0;
    a->surf[1].mat.kind = b->surf[1].mat.kind = SG_MAT_INDEX;
    a->surf[1].mat.index = b->surf[1].mat.index = 1.5;
    a->surf[1].thickness = b->surf[1].thickness = 3.0;
    a->surf[2].radius = b->surf[2].radius = -60.0;
    a->surf[2].thickness = 20.0;
    b->surf[2].thickness = 50.0;
    a->surf[3].type = SG_SURF_COORDBRK;
    set_change(&a->surf[3].before, 1.25, -0.5, 7.0, -3.0, 11.0, 0);
    a->surf[3].thickness = 30.0;
    a->surf[4].type = SG_SURF_COORDBRK;
    /* The inverse lies at the same place: back along the new z first. */
    a->surf[3].thickness = 0.0;
    set_change(&a->surf[4].before, -1.25, 0.5, -7.0, 3.0, -11.0, 1);
    a->surf[4].thickness = 30.0;
    a->surf[5].radius = b->surf[3].radius = 80.0;
    a->surf[5].thickness = b->surf[3].thickness = 10.0;
    for (m = 0; m < 3; m++) {
        sg_tracer *ta = tu_tracer(a, cat, (sg_method)m), *tb = tu_tracer(b, cat, (sg_method)m);
        for (k = 0; k < 50; k++) {
            sg_ray_surface oa[7], ob[5];
            double S[3] = {srand1(3), srand1(3), -5}, D[3] = {srand1(0.05), srand1(0.05), 1};
            assert_int_equal(sg_trace_start(ta, S, D, oa), SG_OK);
            assert_int_equal(sg_trace_start(tb, S, D, ob), SG_OK);
            /* The image rows: the same point, within both bounds. */
            if (fabs(oa[6].x - ob[4].x) > oa[6].error_bound + ob[4].error_bound + 1e-15 ||
                fabs(oa[6].y - ob[4].y) > oa[6].error_bound + ob[4].error_bound + 1e-15)
                fail_msg("method %d ray %d: %.17g,%.17g against %.17g,%.17g", m, k, oa[6].x,
                         oa[6].y, ob[4].x, ob[4].y);
        }
        sg_tracer_free(ta);
        sg_tracer_free(tb);
    }
    sg_system_free(a);
    sg_system_free(b);
    sg_catalog_free(cat);
}

/* A plano-convex lens focusing through a 45-degree fold mirror, built with
 * coordinate breaks and with the mirror's own tilts, against the same lens
 * unfolded: the image point is the same (the image frame turns with the
 * beam), its direction's n changes sign (the image faces back). */
static void fold_two_ways(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *cb = base_system(7), *td = base_system(5), *un = base_system(4);
    sg_system *all[3] = {cb, td, un};
    int m, k, j;
    (void)state;
    rng_state = 0xf01dULL;
    for (j = 0; j < 3; j++) {
        all[j]->surf[1].radius = 51.5;
        all[j]->surf[1].thickness = 3.6;
        all[j]->surf[1].mat.kind = SG_MAT_INDEX;
        all[j]->surf[1].mat.index = 1.5168;
        all[j]->surf[2].thickness = 40.0;
    }
    un->surf[2].thickness = 97.25;
    cb->surf[3].type = SG_SURF_COORDBRK;
    set_change(&cb->surf[3].before, 0, 0, 45, 0, 0, 0);
    cb->surf[4].mat.kind = SG_MAT_MIRROR;
    cb->surf[5].type = SG_SURF_COORDBRK;
    set_change(&cb->surf[5].before, 0, 0, 45, 0, 0, 0);
    cb->surf[5].thickness = -57.25;
    td->surf[3].mat.kind = SG_MAT_MIRROR;
    set_change(&td->surf[3].before, 0, 0, 45, 0, 0, 0);
    set_change(&td->surf[3].after, 0, 0, 45, 0, 0, 0);
    td->surf[3].thickness = -57.25;
    for (m = 0; m < 3; m++) {
        sg_tracer *tc = tu_tracer(cb, cat, (sg_method)m), *tt = tu_tracer(td, cat, (sg_method)m),
                  *tu = tu_tracer(un, cat, (sg_method)m);
        for (k = 0; k < 200; k++) {
            sg_ray_surface oc[7], ot[5], ou[4];
            double S[3] = {srand1(6), srand1(6), -2}, D[3] = {srand1(0.1), srand1(0.1), 1};
            double tol;
            assert_int_equal(sg_trace_start(tc, S, D, oc), SG_OK);
            assert_int_equal(sg_trace_start(tt, S, D, ot), SG_OK);
            assert_int_equal(sg_trace_start(tu, S, D, ou), SG_OK);
            tol = oc[6].error_bound + ou[3].error_bound + ot[4].error_bound;
            if (m == SG_METHOD_CLASSIC)
                tol = 1e-12;
            if (fabs(oc[6].x - ou[3].x) > tol || fabs(oc[6].y - ou[3].y) > tol ||
                fabs(ot[4].x - ou[3].x) > tol || fabs(ot[4].y - ou[3].y) > tol ||
                fabs(oc[6].n + ou[3].n) > 1e-15 || fabs(ot[4].m - ou[3].m) > 1e-15)
                fail_msg("method %d ray %d: breaks %.17g,%.17g tilts %.17g,%.17g unfolded "
                         "%.17g,%.17g tol %.3g n %.17g %.17g m %.17g %.17g",
                         m, k, oc[6].x, oc[6].y, ot[4].x, ot[4].y, ou[3].x, ou[3].y, tol, oc[6].n, ou[3].n, ot[4].m, ou[3].m);
            /* The optical path does not care how the beam is folded. */
            if (fabs(oc[6].opl - ou[3].opl) > 1e-12 || fabs(ot[4].opl - ou[3].opl) > 1e-12)
                fail_msg("method %d ray %d: OPL %.17g %.17g against %.17g", m, k, oc[6].opl,
                         ot[4].opl, ou[3].opl);
        }
        sg_tracer_free(tc);
        sg_tracer_free(tt);
        sg_tracer_free(tu);
    }
    for (j = 0; j < 3; j++)
        sg_system_free(all[j]);
    sg_catalog_free(cat);
}

/* The 90-degree off-axis parabola of Thorlabs' and Edmund's catalogs
 * (reflected focal length 190.6 mm, parent focal length 95.3 mm), laid
 * out as Zemax's file for it does (tests/data/zmx/zmax_37992.zmx): a
 * break decentres the parent's axis by -190.6 mm; the image, at the
 * parent's focus, is tilted 90 degrees about x to face the beam.  Every
 * ray parallel to the parent's axis meets at the focus: the closed form
 * of a paraboloid. */
static void off_axis_parabola(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = base_system(5);
    int m, k;
    double worst[3] = {0, 0, 0};
    (void)state;
    rng_state = 0x0a9ULL;
    sys->aper_value = 50.8;
    sys->surf[1].thickness = 200.0;
    sys->surf[2].type = SG_SURF_COORDBRK;
    set_change(&sys->surf[2].before, 0, -190.6, 0, 0, 0, 0);
    sys->surf[3].radius = -190.6;
    sys->surf[3].conic = -1.0;
    sys->surf[3].mat.kind = SG_MAT_MIRROR;
    sys->surf[3].thickness = -95.3;
    set_change(&sys->surf[4].before, 0, 0, 90, 0, 0, 0);
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, cat, (sg_method)m);
        for (k = 0; k < 300; k++) {
            sg_ray_surface o[5];
            double a = 6.283185307179586 * urand(), r = 25.4 * sqrt(urand());
            double S[3] = {r * cos(a), r * sin(a), -10}, D[3] = {0, 0, 1};
            double e;
            assert_int_equal(sg_trace_start(t, S, D, o), SG_OK);
            /* The image plane passes through the focus: the point is (0,
             * 0, 0) there, and the focus lies within its bound. */
            e = fmax(fabs(o[4].x), fmax(fabs(o[4].y), fabs(o[4].z)));
            worst[m] = fmax(worst[m], e);
            if (m != SG_METHOD_CLASSIC && e > o[4].error_bound)
                fail_msg("method %d ray %d: image point %.3g,%.3g,%.3g beyond its bound %.3g", m,
                         k, o[4].x, o[4].y, o[4].z, o[4].error_bound);
        }
        sg_tracer_free(t);
    }
    print_message("# OAP focus: worst distance precise %.3g classic %.3g mpfr %.3g mm\n",
                  worst[0], worst[1], worst[2]);
    /* Zemax stored this system's image semi-diameter as 1.67e-13 mm. */
    assert_true(worst[SG_METHOD_CLASSIC] < 1e-11);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Whether random_system changes the frame on surface 1 (a set of its
 * own, so that the other sets keep their systems). */
static int change_s1;

/* A random system: lenses, mirrors and breaks, with tilts and decenters
 * before and after, both orders and "reverse". */
static sg_system *random_system(double L, double T)
{
    int n = 9 + (int)(urand() * 5), i;
    sg_system *sys = base_system(n);
    double dir = 1.0; /* thickness sign: after a mirror the beam runs back */
    sys->aper_value = 4.0 * L;
    sys->surf[1].radius = L * (60.0 + srand1(20.0));
    sys->surf[1].thickness = 4.0 * L;
    sys->surf[1].mat.kind = SG_MAT_INDEX;
    sys->surf[1].mat.index = 1.5 + 0.2 * urand();
    /* Surface 1 may turn or move what follows it (Zemax's coordinate break
     * or tilt on surface 1): rays start at its place before the change. */
    if (change_s1) {
        double u = urand();
        if (u < 0.25) {
            sys->surf[1].type = SG_SURF_COORDBRK;
            sys->surf[1].radius = INFINITY;
            sys->surf[1].mat.kind = SG_MAT_AIR;
            sys->surf[1].thickness = L * (urand() < 0.3 ? 0.0 : 5.0 * urand());
        }
        if (u < 0.6)
            set_change(&sys->surf[1].before, L * srand1(2.0), L * srand1(2.0), srand1(T),
                       srand1(T), srand1(2.5 * T), urand() < 0.5);
    }
    for (i = 2; i < n - 1; i++) {
        sg_surface *s = &sys->surf[i];
        double u = urand();
        const sg_surface *p = &sys->surf[i - 1];
        int in_glass = p->type != SG_SURF_COORDBRK && p->mat.kind == SG_MAT_INDEX;
        if (p->type == SG_SURF_COORDBRK) {
            /* the medium before a break */
            int j = i - 1;
            while (j > 0 && sys->surf[j].type == SG_SURF_COORDBRK)
                j--;
            in_glass = sys->surf[j].mat.kind == SG_MAT_INDEX;
        }
        if (u < 0.25 && i < n - 2) {
            s->type = SG_SURF_COORDBRK;
            set_change(&s->before, L * srand1(2.0), L * srand1(2.0), srand1(T), srand1(T),
                       srand1(2.5 * T), urand() < 0.5);
            s->thickness = dir * L * (urand() < 0.3 ? 0.0 : 5.0 + 10.0 * urand());
            continue;
        }
        s->radius = urand() < 0.2 ? INFINITY : (urand() < 0.5 ? -1.0 : 1.0) * L * (40.0 + 200.0 * urand());
        s->conic = urand() < 0.5 ? 0.0 : srand1(1.5);
        if (!in_glass && urand() < 0.25) {
            s->mat.kind = SG_MAT_MIRROR;
            dir = -dir;
        } else if (!in_glass && urand() < 0.5) {
            s->mat.kind = SG_MAT_INDEX;
            s->mat.index = 1.45 + 0.4 * urand();
        }
        if (urand() < 0.5)
            set_change(&s->before, L * srand1(1.0), L * srand1(1.0), srand1(T / 2),
                       srand1(T / 2), srand1(20.0), urand() < 0.5);
        u = urand();
        if (u < 0.25)
            s->after_mode = SG_AFTER_REVERSE;
        else if (u < 0.5)
            set_change(&s->after, L * srand1(1.0), L * srand1(1.0), srand1(T / 2),
                       srand1(T / 2), srand1(20.0), urand() < 0.5);
        s->thickness = dir * L * (s->mat.kind == SG_MAT_INDEX ? 3.0 + 3.0 * urand() : 8.0 + 20.0 * urand());
    }
    /* A break is no stop: the first surface that is not one. */
    while (sys->surf[sys->stop].type == SG_SURF_COORDBRK)
        sys->stop++;
    /* The image may be tilted too. */
    if (urand() < 0.5)
        set_change(&sys->surf[n - 1].before, L * srand1(1.0), L * srand1(1.0), srand1(T),
                   srand1(T), srand1(30.0), urand() < 0.5);
    return sys;
}

/* nsys systems of scale L (every length) with tilts up to T degrees;
 * rays from within W of the axis (times L) at slopes up to A. */
static void run_random(int nsys, double L, double T, double W, double A, uint64_t seed,
                       int easy)
{
    sg_catalog *cat = tu_catalog();
    int nray = 25, q, k, i, m;
    long uncert = 0, classic_wrong = 0;
    long compared = 0, pcompared = 0, hits = 0, missed = 0, exact = 0, gcompared = 0;
    double worst_ratio[3] = {0, 0, 0}, worst_classic = 0.0;
    rng_state = seed;
    for (q = 0; q < nsys; q++) {
        sg_system *sys = random_system(L, T);
        int n = sys->nsurf;
        sg_tracer *t[3];
        sg_diag d;
        sg_diag_clear(&d);
        if (sg_system_validate(sys, cat, &d) != SG_OK)
            fail_msg("system %d: %s", q, d.msg);
        for (m = 0; m < 3; m++)
            t[m] = tu_tracer(sys, cat, (sg_method)m);
        for (k = 0; k < nray; k++) {
            double S[3] = {L * srand1(W), L * srand1(W), -2.0 * L},
                   D[3] = {srand1(A), srand1(A), 1.0};
            truth_row rows[16];
            sg_ray_surface out[16];
            ref_trace(sys, S, D, rows);
            for (m = 0; m < 3; m++) {
                sg_trace_start(t[m], S, D, out);
                for (i = 1; i < n; i++) {
                    double ep, ed;
                    uncert += m == SG_METHOD_PRECISE && out[i].status == SG_EUNCERT;
                    if (m == SG_METHOD_CLASSIC && !easy && rows[i].status != out[i].status) {
                        /* The textbook method may lose a grazing ray: counted. */
                        classic_wrong++;
                        break;
                    }
                    if (rows[i].status != out[i].status &&
                        !(m == SG_METHOD_PRECISE && out[i].status == SG_EUNCERT))
                        fail_msg("system %d ray %d method %d surface %d: status %d, the "
                                 "reference's %d",
                                 q, k, m, i, out[i].status, rows[i].status);
                    if (rows[i].status != SG_OK || out[i].status != SG_OK)
                        break;
                    compared++;
                    pcompared += m == SG_METHOD_PRECISE;
                    ep = maxdiff3(rows[i].p, out[i].x, out[i].y, out[i].z);
                    ed = maxdiff3(rows[i].d, out[i].l, out[i].m, out[i].n);
                    if (m == SG_METHOD_CLASSIC) {
                        worst_classic = fmax(worst_classic, ep / (1.0 + fabs(out[i].z) +
                                                                  fabs(out[i].x) + fabs(out[i].y)));
                        continue;
                    }
                    /* The reference rounds once: half an ulp of slack. */
                    if (ep > out[i].error_bound + 0.5 * tu_ulp(fmax(fabs(out[i].x),
                                                                 fmax(fabs(out[i].y), fabs(out[i].z)))) ||
                        (i < n - 1 &&
                         ed > out[i].dir_error_bound + 0.5 * tu_ulp(1.0)))
                    {
                        sg_design_save(sys, "/tmp/frames_fail.json", NULL);
                        print_message("# start %.17g,%.17g,%.17g dir %.17g,%.17g,%.17g\n", S[0], S[1], S[2], D[0], D[1], D[2]);
                        fail_msg("system %d ray %d method %d surface %d (type %d): error %.3g / %.3g "
                                 "beyond bound %.3g / %.3g; got %.17g %.17g %.17g want %.17g %.17g %.17g",
                                 q, k, m, i, sys->surf[i].type, ep, ed, out[i].error_bound, out[i].dir_error_bound,
                                 out[i].x, out[i].y, out[i].z, rows[i].p[0], rows[i].p[1], rows[i].p[2]);
                    }
                    if (ep > 0.0)
                        worst_ratio[m] = fmax(worst_ratio[m], ep / out[i].error_bound);
                    if (m == SG_METHOD_PRECISE)
                        exact += ep <= 1e-60 && ed <= 1e-60; /* the reference's own z on a plane is 1e-150 */
                }
            }
            /* Global rows: every precise row taken to surface 1's frame
             * (sg_global_frames, sg_row_to_global) against the reference's
             * own global point, within the converted bound. */
            {
                sg_frame gf[16], g3[16];
                sg_diag gd;
                sg_diag_clear(&gd);
                assert_int_equal(sg_global_frames(sys, 1, gf, &gd), SG_OK);
                if (sys->surf[3].type != SG_SURF_COORDBRK)
                    assert_int_equal(sg_global_frames(sys, 3, g3, &gd), SG_OK);
                sg_trace_start(t[SG_METHOD_PRECISE], S, D, out);
                for (i = 1; i < n && rows[i].status == SG_OK && out[i].status == SG_OK; i++) {
                    double e, ed;
                    int a, b;
                    for (a = 0; a < 3; a++) {
                        for (b = 0; b < 3; b++)
                            if (fabs(gf[i].R[a][b] - rows[i].e[b][a]) > 4e-16)
                                fail_msg("system %d surface %d: R[%d][%d] %.17g, the reference's "
                                         "%.17g", q, i, a, b, gf[i].R[a][b], rows[i].e[b][a]);
                        if (fabs(gf[i].o[a] - rows[i].o[a]) > 4e-16 * (1.0 + fabs(rows[i].o[a])))
                            fail_msg("system %d surface %d: origin[%d] %.17g, the reference's "
                                     "%.17g", q, i, a, gf[i].o[a], rows[i].o[a]);
                    }
                    if (i >= 3 && rows[3].status == SG_OK &&
                        sys->surf[3].type != SG_SURF_COORDBRK) {
                        /* Relative to surface 3: E3^T E_i and E3^T (o_i - o_3). */
                        for (a = 0; a < 3; a++) {
                            double oo = 0.0, mag = 0.0;
                            for (b = 0; b < 3; b++) {
                                double rr = 0.0;
                                int c2;
                                for (c2 = 0; c2 < 3; c2++)
                                    rr += rows[3].e[a][c2] * rows[i].e[b][c2];
                                if (fabs(g3[i].R[a][b] - rr) > 1e-15)
                                    fail_msg("system %d surface %d, reference 3: R[%d][%d] "
                                             "%.17g, the reference's %.17g", q, i, a, b,
                                             g3[i].R[a][b], rr);
                                oo += rows[3].e[a][b] * (rows[i].o[b] - rows[3].o[b]);
                                mag += fabs(rows[i].o[b]) + fabs(rows[3].o[b]);
                            }
                            /* The reference's origins are rounded: differences of them
                             * lose what their magnitudes hold. */
                            if (fabs(g3[i].o[a] - oo) > 1e-15 * (1.0 + 4.0 * mag))
                                fail_msg("system %d surface %d, reference 3: origin[%d] %.17g, "
                                         "the reference's %.17g", q, i, a, g3[i].o[a], oo);
                        }
                    }
                    sg_row_to_global(&gf[i], &out[i]);
                    e = maxdiff3(rows[i].g, out[i].x, out[i].y, out[i].z);
                    ed = maxdiff3(rows[i].gd, out[i].l, out[i].m, out[i].n);
                    if (e > out[i].error_bound + 0.5 * tu_ulp(fmax(fabs(out[i].x),
                                                          fmax(fabs(out[i].y), fabs(out[i].z)))) ||
                        (i < n - 1 && ed > out[i].dir_error_bound + 0.5 * tu_ulp(1.0)))
                        fail_msg("system %d ray %d surface %d: global error %.3g / %.3g beyond "
                                 "%.3g / %.3g", q, k, i, e, ed, out[i].error_bound,
                                 out[i].dir_error_bound);
                    gcompared++;
                }
            }
            if (rows[n - 1].status == SG_OK)
                hits++;
            else
                missed++;
        }
        for (m = 0; m < 3; m++)
            sg_tracer_free(t[m]);
        sg_system_free(sys);
    }
    print_message("# %d random systems (scale %g, tilts to %g deg), %ld rays reach the image, "
                  "%ld stop early, %ld UNCERT; %ld rows compared\n", nsys, L, T, hits, missed,
                  uncert, compared);
    print_message("# worst error/bound: precise %.3g, mpfr %.3g; classic worst relative "
                  "error %.3g, wrong status on %ld rays\n", worst_ratio[0], worst_ratio[2],
                  worst_classic, classic_wrong);
    print_message("# precise rows equal to the reference rounded: %ld of %ld\n", exact,
                  pcompared);
    print_message("# %ld global rows within their bounds\n", gcompared);
    /* The promise: on ordinary rays, precise is the exact answer rounded,
     * tilted or not. */
    assert_int_equal(exact, pcompared);
    if (easy) {
        /* Most rays must get through, or the test proves little; and
         * classic, though no bound, stays near. */
        assert_true(hits > missed);
        assert_true(worst_classic < 1e-9);
    } else {
        /* Hard sets must stop some rays (misses, TIR), or they test no edge. */
        assert_true(missed > 0 && hits > 0);
    }
    sg_catalog_free(cat);
}

static void random_systems(void **state)
{
    (void)state;
    run_random(120, 1.0, 12.0, 3.0, 0.04, 0x7117edULL, 1);
}

/* Surface 1 a break or tilted: the reference turns the frame at surface
 * 1's place, as Zemax does, and so must every method. */
static void surface1_changes(void **state)
{
    (void)state;
    change_s1 = 1;
    run_random(120, 1.0, 12.0, 3.0, 0.04, 0x5115ULL, 1);
    change_s1 = 0;
}

/* Where it is hard: steep tilts, wide and steep rays that graze and miss,
 * and lengths from 1e-3 to 1e4 mm. */
static void hard_systems(void **state)
{
    static const double scale[3] = {1e-3, 1.0, 1e4};
    int j;
    (void)state;
    for (j = 0; j < 3; j++)
        run_random(60, scale[j], 45.0, 12.0, 0.3, 0xbad5eedULL + (uint64_t)j, 0);
}

/* A Zemax file (UTF-16LE, as Zemax 13 wrote them; tests/data/zmx/
 * README.md): each listed surface's automatic semi-diameter against the
 * DIAM Zemax stored, and the .zmx written back traces to the same bits in
 * each method.  Returns the design for more checks. */
static sg_system *zemax_diams(sg_catalog *cat, const char *rel, const int *surf,
                              const double *diam, int n)
{
    sg_system *sys = sg_system_new(), *back = sg_system_new();
    char path[4096];
    double sd[64];
    sg_diag d;
    char *z;
    int k, meth;
    sg_diag_clear(&d);
    if (sg_design_load(sys, tu_path(rel, path, sizeof path), &d) != SG_OK)
        fail_msg("%s: %s", rel, d.msg);
    assert_int_equal(sg_semi_diameters(sys, cat, NULL, sd, &d), SG_OK);
    for (k = 0; k < n; k++) {
        print_message("# %s surface %d: %.13g, Zemax %.13g\n", rel, surf[k], sd[surf[k]],
                      diam[k]);
        /* Zemax prints 13 significant digits. */
        assert_true(fabs(sd[surf[k]] - diam[k]) <= 1e-11 * diam[k]);
    }
    z = sg_zmx_to_text(sys, cat, &d);
    assert_non_null(z);
    assert_int_equal(sg_zmx_parse(back, z, strlen(z), "back.zmx", cat, &d), SG_OK);
    assert_true(back->surf[0].thickness == sys->surf[0].thickness);
    assert_int_equal(back->surf[1].type, sys->surf[1].type);
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *a = tu_tracer(sys, cat, (sg_method)meth),
                  *b = tu_tracer(back, cat, (sg_method)meth);
        sg_ray_surface ra[64], rb[64];
        int im = sys->nsurf - 1;
        /* A ray inside every fixed semi-diameter of the files. */
        assert_int_equal(sg_trace_normalized(a, 0, 0.6, 0.2, 0.5, ra), SG_OK);
        assert_int_equal(sg_trace_normalized(b, 0, 0.6, 0.2, 0.5, rb), SG_OK);
        assert_true(ra[im].x == rb[im].x && ra[im].y == rb[im].y && ra[im].m == rb[im].m &&
                    ra[im].opl == rb[im].opl);
        sg_tracer_free(a);
        sg_tracer_free(b);
    }
    free(z);
    sg_system_free(back);
    return sys;
}

/* Zemax's samples with a coordinate break as surface 1 (line numbers of
 * the UTF-8 text). */
static void zemax_break_first(void **state)
{
    /* Offner relay: the break decentres y by -3 (PARM 2, line 76); the
     * mirrors' DIAMs, lines 92 and 114.  Bi-ocular lens, configuration
     * 1: x by 25 (PARM 1, line 75); the stop's and the image's DIAMs,
     * lines 92 and 198. */
    static const int os[2] = {2, 4}, bs[2] = {2, 11};
    static const double od[2] = {4.686823252472, 4.676393457068},
                        bd[2] = {2.500000000011, 12.58899446594};
    sg_catalog *cat = tu_catalog();
    sg_system *o = zemax_diams(cat, "tests/data/zmx/offner_relay.zmx", os, od, 2),
              *b = zemax_diams(cat, "tests/data/zmx/biocular_lens.zmx", bs, bd, 2);
    (void)state;
    assert_int_equal(o->surf[1].type, SG_SURF_COORDBRK);
    assert_true(o->surf[1].before.dx == 0.0 && o->surf[1].before.dy == -3.0);
    assert_int_equal(b->surf[1].type, SG_SURF_COORDBRK);
    assert_true(b->surf[1].before.dx == 25.0 && b->surf[1].before.dy == 0.0);
    sg_system_free(o);
    sg_system_free(b);
    sg_catalog_free(cat);
}

/* Zemax's samples with the object on surface 1's place (DISZ 0): "Example
 * 1, A singlet eyepiece" (object heights to 11.5: surface 1's DIAM, line
 * 82, is the field; the image's, line 122) and the short course's
 * POP_Coupling (the image's DIAM, line 133). */
static void zemax_object_on_surface1(void **state)
{
    static const int es[2] = {1, 5}, ps[1] = {6};
    static const double ed[2] = {11.5, 582.7803973772}, pd[1] = {1.650196169345e-2};
    sg_catalog *cat = tu_catalog();
    sg_system *e = zemax_diams(cat, "tests/data/zmx/singlet_eyepiece.zmx", es, ed, 2),
              *p = zemax_diams(cat, "tests/data/zmx/pop_coupling.zmx", ps, pd, 1);
    (void)state;
    assert_true(e->surf[0].thickness == 0.0 && p->surf[0].thickness == 0.0);
    sg_system_free(e);
    sg_system_free(p);
    sg_catalog_free(cat);
}

/* A point on surface 1's place at the centre of a spherical mirror: every
 * ray comes back to it, after an optical path of twice the radius, in
 * each method (closed form). */
static void object_on_surface1_sphere(void **state)
{
    const double R = 50.0;
    sg_catalog *cat = tu_catalog();
    sg_system *sys = base_system(4);
    sg_diag d;
    int meth, k;
    (void)state;
    sys->surf[0].thickness = 0.0;
    sys->surf[1].thickness = R;
    sys->surf[2].radius = -R;
    sys->surf[2].mat.kind = SG_MAT_MIRROR;
    sys->surf[2].thickness = -R;
    sys->stop = 2;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = 60.0;
    sys->field_type = SG_FIELD_OBJECT_HEIGHT;
    sys->aim = SG_AIM_OFF;
    sg_diag_clear(&d);
    if (sg_system_validate(sys, cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    {
        /* The object and surface 1 at one place; the mirror R on. */
        sg_frame gf[4];
        assert_int_equal(sg_global_frames(sys, 1, gf, &d), SG_OK);
        assert_true(gf[0].o[2] == 0.0 && gf[1].o[2] == 0.0 && gf[2].o[2] == R &&
                    gf[3].o[2] == 0.0);
    }
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *t = tu_tracer(sys, cat, (sg_method)meth);
        for (k = 0; k < 40; k++) {
            double px = srand1(0.7), py = srand1(0.7);
            sg_ray_surface out[8];
            double tol = meth == SG_METHOD_CLASSIC ? 1e-12 : 0.0;
            assert_int_equal(sg_trace_normalized(t, 0, 0, px, py, out), SG_OK);
            if (!(fabs(out[3].x) <= out[3].error_bound + tol &&
                  fabs(out[3].y) <= out[3].error_bound + tol &&
                  fabs(out[3].opl - 2.0 * R) <= out[3].opl_error_bound + 2e-13))
                fail_msg("method %d pupil %g %g: image (%.17g, %.17g), OPL %.17g (bounds %.3g, "
                         "%.3g)", meth, px, py, out[3].x, out[3].y, out[3].opl,
                         out[3].error_bound, out[3].opl_error_bound);
            /* The ray leaves the object point itself, towards its point
             * of the entrance pupil, the mirror's vertex plane R on, of
             * radius 30 (aiming off). */
            assert_true(fabs(out[1].x) <= out[1].error_bound + tol &&
                        fabs(out[1].y) <= out[1].error_bound + tol);
            {
                double len = sqrt(900.0 * (px * px + py * py) + R * R);
                if (!(fabs(out[1].l - 30.0 * px / len) <= out[1].dir_error_bound + 1e-15 &&
                      fabs(out[1].m - 30.0 * py / len) <= out[1].dir_error_bound + 1e-15))
                    fail_msg("method %d pupil %g %g: direction (%.17g, %.17g), want (%.17g, "
                             "%.17g)", meth, px, py, out[1].l, out[1].m, 30.0 * px / len,
                             30.0 * py / len);
            }
        }
        sg_tracer_free(t);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The design format keeps every frame change bit for bit, writes version
 * 2 only for designs that need it, and traces the same after a round trip. */
static void design_round_trip(void **state)
{
    sg_catalog *cat = tu_catalog();
    int q;
    (void)state;
    rng_state = 0x2071dULL;
    for (q = 0; q < 30; q++) {
        sg_system *a = random_system(1.0, 30.0), *b = sg_system_new();
        char *ja = sg_design_to_json(a), *jb;
        sg_diag d;
        sg_ray_surface oa[16], ob[16];
        double S[3] = {0.5, -0.25, -1}, D[3] = {0.01, 0.02, 1};
        sg_tracer *ta, *tb;
        int i;
        assert_non_null(ja);
        assert_non_null(strstr(ja, "\"version\": 2"));
        sg_diag_clear(&d);
        if (sg_design_parse(b, ja, strlen(ja), "rt.json", &d) != SG_OK)
            fail_msg("system %d: %s", q, d.msg);
        jb = sg_design_to_json(b);
        assert_string_equal(ja, jb);
        for (i = 0; i < a->nsurf; i++) {
            assert_memory_equal(&a->surf[i].before, &b->surf[i].before, sizeof(sg_frame_change));
            assert_memory_equal(&a->surf[i].after, &b->surf[i].after, sizeof(sg_frame_change));
            assert_int_equal(a->surf[i].after_mode, b->surf[i].after_mode);
            assert_int_equal(a->surf[i].type, b->surf[i].type);
        }
        ta = tu_tracer(a, cat, SG_METHOD_PRECISE);
        tb = tu_tracer(b, cat, SG_METHOD_PRECISE);
        assert_int_equal(sg_trace_start(ta, S, D, oa), sg_trace_start(tb, S, D, ob));
        for (i = 0; i < a->nsurf; i++)
            assert_true(tu_same_row(&oa[i], &ob[i]));
        sg_tracer_free(ta);
        sg_tracer_free(tb);
        free(ja);
        free(jb);
        sg_system_free(a);
        sg_system_free(b);
    }
    /* Without frame changes a design is still version 1, as before. */
    {
        sg_system *e = tu_example("cooke_triplet.json");
        char *j = sg_design_to_json(e);
        assert_non_null(strstr(j, "\"version\": 1"));
        assert_null(strstr(j, "before"));
        free(j);
        sg_system_free(e);
    }
    sg_catalog_free(cat);
}

/* Each place a frame change cannot stand is refused, naming the surface. */
static void refusals(void **state)
{
    static const struct {
        int surf, type, which; /* which: 0 before, 1 after, 2 reverse with values */
        double v[5];
        int order;
        const char *msg;
    } cs[] = {
        {0, SG_SURF_STANDARD, 0, {1, 0, 0, 0, 0}, 0, "surface 0: the object cannot be tilted"},
        {4, SG_SURF_COORDBRK, 0, {0, 0, 1, 0, 0}, 0, "surface 4: the image cannot be a coordinate break"},
        {4, SG_SURF_STANDARD, 1, {0, 0, 1, 0, 0}, 0, "surface 4: nothing follows the image"},
        {2, SG_SURF_STANDARD, 0, {0, 0, 361, 0, 0}, 0, "surface 2: before tilt about x 361 is beyond 360 degrees"},
        {2, SG_SURF_STANDARD, 1, {0, 2e150, 0, 0, 0}, 0, "surface 2: after decenter y 2e+150 is beyond"},
        {2, SG_SURF_STANDARD, 0, {0, 0, 0, NAN, 0}, 0, "surface 2: before tilt about y is not finite"},
        {2, SG_SURF_STANDARD, 0, {0, 0, 0, 0, 1}, 2, "surface 2: before order 2 must be 0"},
        {2, SG_SURF_STANDARD, 2, {0, 0, 0, 0, 1}, 0, "surface 2: after: \"reverse\" undoes"},
        {2, SG_SURF_COORDBRK, 1, {0, 0, 1, 0, 0}, 0, "surface 2: a coordinate break has no after change"},
    };
    size_t c;
    (void)state;
    for (c = 0; c < sizeof cs / sizeof cs[0]; c++) {
        sg_system *sys = base_system(5);
        sg_surface *s = &sys->surf[cs[c].surf];
        sg_frame_change *f = cs[c].which == 0 ? &s->before : &s->after;
        sg_diag d;
        s->type = (sg_surf_type)cs[c].type;
        set_change(f, cs[c].v[0], cs[c].v[1], cs[c].v[2], cs[c].v[3], cs[c].v[4], cs[c].order);
        if (cs[c].which == 2)
            s->after_mode = SG_AFTER_REVERSE;
        sg_diag_clear(&d);
        if (sg_system_validate(sys, NULL, &d) == SG_OK || !strstr(d.msg, cs[c].msg))
            fail_msg("case %zu: got \"%s\", want \"%s\"", c, d.msg, cs[c].msg);
        sg_system_free(sys);
    }
    {
        /* A break as the stop, or holding a glass. */
        sg_system *sys = base_system(5);
        sg_diag d;
        sys->surf[2].type = SG_SURF_COORDBRK;
        sys->stop = 2;
        sg_diag_clear(&d);
        assert_int_not_equal(sg_system_validate(sys, NULL, &d), SG_OK);
        assert_non_null(strstr(d.msg, "surface 2: a coordinate break cannot be the stop"));
        sys->stop = 1;
        sys->surf[2].mat.kind = SG_MAT_MIRROR;
        sg_diag_clear(&d);
        assert_int_not_equal(sg_system_validate(sys, NULL, &d), SG_OK);
        assert_non_null(strstr(d.msg, "surface 2: a coordinate break keeps the medium"));
        sys->surf[2].mat.kind = SG_MAT_AIR;
        sys->surf[2].aperture = SG_APERTURE_CIRCULAR;
        sys->surf[2].ap_rmax = 3.0;
        sg_diag_clear(&d);
        assert_int_not_equal(sg_system_validate(sys, NULL, &d), SG_OK);
        assert_non_null(strstr(d.msg, "surface 2: a coordinate break has no aperture"));
        sg_system_free(sys);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sign_conventions),
        cmocka_unit_test(break_and_inverse),
        cmocka_unit_test(fold_two_ways),
        cmocka_unit_test(off_axis_parabola),
        cmocka_unit_test(random_systems),
        cmocka_unit_test(surface1_changes),
        cmocka_unit_test(zemax_break_first),
        cmocka_unit_test(zemax_object_on_surface1),
        cmocka_unit_test(object_on_surface1_sphere),
        cmocka_unit_test(hard_systems),
        cmocka_unit_test(design_round_trip),
        cmocka_unit_test(refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
