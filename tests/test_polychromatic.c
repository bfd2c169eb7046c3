/*
 * test_polychromatic.c - the Zemax convention for several wavelengths:
 * the entrance pupil, the aperture and the fields are those of the primary
 * wavelength, and every wavelength's rays launch through that pupil.
 *
 * The truth is an MPFR (256-bit) trace of the Cooke triplet written here,
 * independent of the engine: the indices from the Schott Sellmeier
 * coefficients (Schott catalog, as in lensdb/SCHOTT.agf), the entrance
 * pupil from a paraxial trace at the primary wavelength, the field of a
 * real image height by a secant search on the primary chief ray, and
 * the rays through spheres by the closed-form intersection and the vector
 * law of refraction.
 */
#include <math.h>
#include <mpfr.h>
#include <string.h>

#include "testutil.h"

#define PREC 256
#define NS 8 /* object, six lens surfaces, image */

/* The Cooke triplet of examples/cooke_triplet.json. */
static const double R[NS] = {INFINITY, 23.713, 7331.288, -24.456, 21.896, 86.759, -20.4942,
                             INFINITY};
static const double T[NS] = {INFINITY, 4.831, 5.86, 0.975, 4.822, 3.127, 41.2365, 0};
static const int GLASS[NS] = {0, 1, 0, 2, 0, 1, 0, 0}; /* medium after: air, N-LAK9, N-SF5 */
static const int STOP = 3;
static const double EPD = 12.5, FIELD = 20.0;
static const double WAVES[3] = {0.4861327, 0.5875618, 0.6562725}; /* F, d (primary), C */

/* Schott Sellmeier coefficients B1 C1 B2 C2 B3 C3 of N-LAK9 and N-SF5. */
static const double SELL[3][6] = {
    {0},
    {1.46231905, 0.00724270156, 0.344399589, 0.0243353131, 1.15508372, 85.4686868},
    {1.52481889, 0.011254756, 0.187085527, 0.0588995392, 1.42729015, 129.141675}};

static void index_of(mpfr_t n, int glass, double um)
{
    mpfr_t l2, term, den;
    int k;
    if (glass == 0) {
        mpfr_set_ui(n, 1, MPFR_RNDN);
        return;
    }
    mpfr_inits2(PREC, l2, term, den, (mpfr_ptr)0);
    mpfr_set_d(l2, um, MPFR_RNDN);
    mpfr_sqr(l2, l2, MPFR_RNDN);
    mpfr_set_ui(n, 1, MPFR_RNDN);
    for (k = 0; k < 3; k++) {
        mpfr_sub_d(den, l2, SELL[glass][2 * k + 1], MPFR_RNDN);
        mpfr_mul_d(term, l2, SELL[glass][2 * k], MPFR_RNDN);
        mpfr_div(term, term, den, MPFR_RNDN);
        mpfr_add(n, n, term, MPFR_RNDN);
    }
    mpfr_sqrt(n, n, MPFR_RNDN);
    mpfr_clears(l2, term, den, (mpfr_ptr)0);
}

/* Paraxial height on the stop of the ray with height y1 on surface 1 and
 * slope u in object space, at wavelength um. */
static void parax_stop(mpfr_t ys, const mpfr_t y1, const mpfr_t u, double um)
{
    mpfr_t y, nu, n0, n1, phi, tmp;
    int i;
    mpfr_inits2(PREC, y, nu, n0, n1, phi, tmp, (mpfr_ptr)0);
    mpfr_set(y, y1, MPFR_RNDN);
    mpfr_set(nu, u, MPFR_RNDN); /* n u with n = 1 */
    mpfr_set_ui(n0, 1, MPFR_RNDN);
    for (i = 1; i < STOP; i++) {
        index_of(n1, GLASS[i], um);
        /* n'u' = n u - y (n' - n) / R */
        mpfr_sub(phi, n1, n0, MPFR_RNDN);
        mpfr_div_d(phi, phi, R[i], MPFR_RNDN);
        mpfr_mul(tmp, y, phi, MPFR_RNDN);
        mpfr_sub(nu, nu, tmp, MPFR_RNDN);
        mpfr_div(tmp, nu, n1, MPFR_RNDN);
        mpfr_mul_d(tmp, tmp, T[i], MPFR_RNDN);
        mpfr_add(y, y, tmp, MPFR_RNDN);
        mpfr_set(n0, n1, MPFR_RNDN);
    }
    mpfr_set(ys, y, MPFR_RNDN);
    mpfr_clears(y, nu, n0, n1, phi, tmp, (mpfr_ptr)0);
}

/* The entrance pupil's z from surface 1 at wavelength um: the paraxial
 * ray of slope u that crosses the stop's centre meets the axis there. */
static void entrance_pupil(mpfr_t enp, double um)
{
    mpfr_t u, y0, y1, s0, s1;
    mpfr_inits2(PREC, u, y0, y1, s0, s1, (mpfr_ptr)0);
    mpfr_set_d(u, 0.01, MPFR_RNDN);
    mpfr_set_zero(y0, 1);
    mpfr_set_ui(y1, 1, MPFR_RNDN);
    parax_stop(s0, y0, u, um);
    parax_stop(s1, y1, u, um);
    /* The stop height is linear in y1: s0 + (s1 - s0) y1 = 0. */
    mpfr_sub(s1, s1, s0, MPFR_RNDN);
    mpfr_div(y1, s0, s1, MPFR_RNDN);
    mpfr_neg(y1, y1, MPFR_RNDN);
    /* y1 = -enp u */
    mpfr_div(enp, y1, u, MPFR_RNDN);
    mpfr_neg(enp, enp, MPFR_RNDN);
    mpfr_clears(u, y0, y1, s0, s1, (mpfr_ptr)0);
}

/* The meridional ray leaving surface 1's tangent plane at height y1 with
 * direction tangent tn, traced to surface upto at wavelength um; its height
 * there into y. */
static void trace_y(mpfr_t y, const mpfr_t y1, const mpfr_t tn, double um, int upto)
{
    mpfr_t P[3], D[3], N[3], n0, n1, mu, b, c, disc, t, cosi, cost, tmp;
    int i, k;
    for (k = 0; k < 3; k++)
        mpfr_inits2(PREC, P[k], D[k], N[k], (mpfr_ptr)0);
    mpfr_inits2(PREC, n0, n1, mu, b, c, disc, t, cosi, cost, tmp, (mpfr_ptr)0);
    mpfr_set_zero(P[0], 1);
    mpfr_set(P[1], y1, MPFR_RNDN);
    mpfr_set_zero(P[2], 1);
    /* D = (0, tn, 1) / sqrt(1 + tn^2) */
    mpfr_sqr(tmp, tn, MPFR_RNDN);
    mpfr_add_ui(tmp, tmp, 1, MPFR_RNDN);
    mpfr_sqrt(tmp, tmp, MPFR_RNDN);
    mpfr_set_zero(D[0], 1);
    mpfr_div(D[1], tn, tmp, MPFR_RNDN);
    mpfr_ui_div(D[2], 1, tmp, MPFR_RNDN);
    mpfr_set_ui(n0, 1, MPFR_RNDN);
    for (i = 1; i <= upto; i++) {
        if (i > 1)
            mpfr_sub_d(P[2], P[2], T[i - 1], MPFR_RNDN);
        if (isinf(R[i])) {
            /* t = -z / Dz onto the plane */
            mpfr_div(t, P[2], D[2], MPFR_RNDN);
            mpfr_neg(t, t, MPFR_RNDN);
        } else {
            /* |P + t D - (0, 0, R)|^2 = R^2: t^2 + 2 b t + c = 0 with
             * b = D.P - R Dz and c = P.P - 2 R Pz; the root on the
             * vertex's side. */
            mpfr_mul(b, D[1], P[1], MPFR_RNDN);
            mpfr_mul(tmp, D[2], P[2], MPFR_RNDN);
            mpfr_add(b, b, tmp, MPFR_RNDN);
            mpfr_mul_d(tmp, D[2], R[i], MPFR_RNDN);
            mpfr_sub(b, b, tmp, MPFR_RNDN);
            mpfr_sqr(c, P[1], MPFR_RNDN);
            mpfr_sqr(tmp, P[2], MPFR_RNDN);
            mpfr_add(c, c, tmp, MPFR_RNDN);
            mpfr_mul_d(tmp, P[2], 2.0 * R[i], MPFR_RNDN);
            mpfr_sub(c, c, tmp, MPFR_RNDN);
            mpfr_sqr(disc, b, MPFR_RNDN);
            mpfr_sub(disc, disc, c, MPFR_RNDN);
            mpfr_sqrt(disc, disc, MPFR_RNDN);
            if (R[i] > 0)
                mpfr_add(t, b, disc, MPFR_RNDN);
            else
                mpfr_sub(t, b, disc, MPFR_RNDN);
            mpfr_neg(t, t, MPFR_RNDN);
        }
        for (k = 0; k < 3; k++) {
            mpfr_mul(tmp, t, D[k], MPFR_RNDN);
            mpfr_add(P[k], P[k], tmp, MPFR_RNDN);
        }
        if (i == upto)
            break;
        /* Refraction: N = ((0, 0, R) - P) / R, unit, +z at the vertex. */
        index_of(n1, GLASS[i], um);
        if (isinf(R[i])) {
            mpfr_set_zero(N[0], 1);
            mpfr_set_zero(N[1], 1);
            mpfr_set_ui(N[2], 1, MPFR_RNDN);
        } else {
            mpfr_div_d(N[0], P[0], -R[i], MPFR_RNDN);
            mpfr_div_d(N[1], P[1], -R[i], MPFR_RNDN);
            mpfr_d_sub(N[2], R[i], P[2], MPFR_RNDN);
            mpfr_div_d(N[2], N[2], R[i], MPFR_RNDN);
        }
        mpfr_div(mu, n0, n1, MPFR_RNDN);
        mpfr_set_zero(cosi, 1);
        for (k = 0; k < 3; k++) {
            mpfr_mul(tmp, D[k], N[k], MPFR_RNDN);
            mpfr_add(cosi, cosi, tmp, MPFR_RNDN);
        }
        /* cos t = sqrt(1 - mu^2 (1 - cos^2 i)) */
        mpfr_sqr(cost, cosi, MPFR_RNDN);
        mpfr_ui_sub(cost, 1, cost, MPFR_RNDN);
        mpfr_sqr(tmp, mu, MPFR_RNDN);
        mpfr_mul(cost, cost, tmp, MPFR_RNDN);
        mpfr_ui_sub(cost, 1, cost, MPFR_RNDN);
        mpfr_sqrt(cost, cost, MPFR_RNDN);
        /* D' = mu D + (cos t - mu cos i) N */
        mpfr_mul(tmp, mu, cosi, MPFR_RNDN);
        mpfr_sub(cost, cost, tmp, MPFR_RNDN);
        for (k = 0; k < 3; k++) {
            mpfr_mul(D[k], D[k], mu, MPFR_RNDN);
            mpfr_mul(tmp, cost, N[k], MPFR_RNDN);
            mpfr_add(D[k], D[k], tmp, MPFR_RNDN);
        }
        mpfr_set(n0, n1, MPFR_RNDN);
    }
    mpfr_set(y, P[1], MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_clears(P[k], D[k], N[k], (mpfr_ptr)0);
    mpfr_clears(n0, n1, mu, b, c, disc, t, cosi, cost, tmp, (mpfr_ptr)0);
}

typedef struct chief_ctx {
    double um;
    int aim; /* the chief ray crosses the stop's centre, at um */
    mpfr_ptr enp;
} chief_ctx;

/* The chief ray of direction tangent tn at wavelength um: through the
 * primary's entrance pupil centre, or aimed at the stop's centre.  Its
 * image height into y. */
static void chief(mpfr_t y, const mpfr_t tn, const chief_ctx *c)
{
    mpfr_t y1, ya, yb, sa, sb, d;
    int it;
    mpfr_inits2(PREC, y1, ya, yb, sa, sb, d, (mpfr_ptr)0);
    mpfr_mul(y1, c->enp, tn, MPFR_RNDN);
    mpfr_neg(y1, y1, MPFR_RNDN);
    if (c->aim) {
        /* Secant on y1 until the stop height is 0. */
        mpfr_set(ya, y1, MPFR_RNDN);
        mpfr_add_d(yb, y1, 1e-3, MPFR_RNDN);
        trace_y(sa, ya, tn, c->um, STOP);
        for (it = 0; it < 60; it++) {
            trace_y(sb, yb, tn, c->um, STOP);
            if (mpfr_zero_p(sb))
                break;
            mpfr_sub(d, sb, sa, MPFR_RNDN);
            if (mpfr_zero_p(d))
                break;
            mpfr_sub(y1, yb, ya, MPFR_RNDN);
            mpfr_mul(y1, y1, sb, MPFR_RNDN);
            mpfr_div(y1, y1, d, MPFR_RNDN);
            mpfr_set(ya, yb, MPFR_RNDN);
            mpfr_set(sa, sb, MPFR_RNDN);
            mpfr_sub(yb, yb, y1, MPFR_RNDN);
            if (mpfr_zero_p(y1) || mpfr_get_exp(y1) < -PREC + 10)
                break;
        }
        mpfr_set(y1, yb, MPFR_RNDN);
    }
    trace_y(y, y1, tn, c->um, NS - 1);
    mpfr_clears(y1, ya, yb, sa, sb, d, (mpfr_ptr)0);
}

/* The object-space tangent whose primary chief ray lands on height h. */
static void field_for_height(mpfr_t tn, double h, const chief_ctx *prim)
{
    mpfr_t a, b, fa, fb, d, s;
    int it;
    mpfr_inits2(PREC, a, b, fa, fb, d, s, (mpfr_ptr)0);
    mpfr_set_d(a, 0.30, MPFR_RNDN);
    mpfr_set_d(b, 0.31, MPFR_RNDN);
    chief(fa, a, prim);
    mpfr_sub_d(fa, fa, h, MPFR_RNDN);
    for (it = 0; it < 80; it++) {
        chief(fb, b, prim);
        mpfr_sub_d(fb, fb, h, MPFR_RNDN);
        mpfr_sub(d, fb, fa, MPFR_RNDN);
        if (mpfr_zero_p(fb) || mpfr_zero_p(d))
            break;
        mpfr_sub(s, b, a, MPFR_RNDN);
        mpfr_mul(s, s, fb, MPFR_RNDN);
        mpfr_div(s, s, d, MPFR_RNDN);
        mpfr_set(a, b, MPFR_RNDN);
        mpfr_set(fa, fb, MPFR_RNDN);
        mpfr_sub(b, b, s, MPFR_RNDN);
        if (mpfr_zero_p(s) || mpfr_get_exp(s) < -PREC + 10)
            break;
    }
    mpfr_set(tn, b, MPFR_RNDN);
    mpfr_clears(a, b, fa, fb, d, s, (mpfr_ptr)0);
}

/* The engine's image height of (hx, hy, px, py) at wave w by method m. */
static double engine_y(const sg_system *sys, const sg_catalog *cat, sg_method m, int w,
                       double hy, double py)
{
    sg_trace_opts o;
    sg_tracer *t;
    sg_ray_surface out[NS];
    sg_diag d;
    int rc;
    sg_trace_opts_init(&o);
    o.method = m;
    o.wave = w;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    if (!t)
        fail_msg("tracer: %s", d.msg);
    rc = sg_trace_normalized(t, 0.0, hy, 0.0, py, out);
    assert_int_equal(rc, SG_OK);
    sg_tracer_free(t);
    return out[NS - 1].y;
}

static double tol_of(sg_method m)
{
    /* classic carries doubles through 41 mm of image space */
    return m == SG_METHOD_CLASSIC ? 1e-11 : 1e-13;
}

/* Lateral colour of the Cooke triplet, F - C chief-ray image height at 20
 * degrees, with the chief ray through the primary's entrance pupil; and
 * the marginal rays of F and C through that pupil's rim. */
static void lateral_colour(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_method methods[3] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};
    mpfr_t enp, tn, y, y1;
    double truth[3][3], lc;
    int w, m, p;
    static const double pys[3] = {0.0, 1.0, -1.0};
    (void)state;
    assert_int_equal(sys->nsurf, NS);
    assert_int_equal(sys->primary_wave, 1);
    mpfr_inits2(PREC, enp, tn, y, y1, (mpfr_ptr)0);
    entrance_pupil(enp, WAVES[1]);
    mpfr_set_d(tn, FIELD, MPFR_RNDN);
    mpfr_const_pi(y, MPFR_RNDN);
    mpfr_mul(tn, tn, y, MPFR_RNDN);
    mpfr_div_ui(tn, tn, 180, MPFR_RNDN);
    mpfr_tan(tn, tn, MPFR_RNDN);
    for (w = 0; w < 3; w++)
        for (p = 0; p < 3; p++) {
            /* y1 = Py EPD / 2 - enp tan */
            mpfr_mul(y1, enp, tn, MPFR_RNDN);
            mpfr_neg(y1, y1, MPFR_RNDN);
            mpfr_add_d(y1, y1, pys[p] * EPD / 2, MPFR_RNDN);
            trace_y(y, y1, tn, WAVES[w], NS - 1);
            truth[w][p] = mpfr_get_d(y, MPFR_RNDN);
        }
    lc = truth[0][0] - truth[2][0];
    print_message("# lateral colour F - C: %.9f mm (MPFR, primary pupil)\n", lc);
    /* The figure for the primary-wavelength launch. */
    assert_true(fabs(lc - 0.000267) < 1e-6);
    for (m = 0; m < 3; m++)
        for (w = 0; w < 3; w++)
            for (p = 0; p < 3; p++) {
                double e = engine_y(sys, cat, methods[m], w, 1.0, pys[p]);
                if (fabs(e - truth[w][p]) > tol_of(methods[m]) * fabs(truth[w][p]))
                    fail_msg("%s wave %d Py %g: %.17g, MPFR %.17g", sg_method_name(methods[m]),
                             w + 1, pys[p], e, truth[w][p]);
            }
    mpfr_clears(enp, tn, y, y1, (mpfr_ptr)0);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A real-image-height field: the primary's chief ray lands on the height,
 * the other wavelengths' chief rays, launched at the primary's field
 * angle, do not; aiming off and paraxial (the chief ray through the
 * stop's centre at its own wavelength, the field from the primary's). */
static void real_image_height(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_method methods[3] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};
    const double H = 17.0;
    mpfr_t enp, tn, y;
    double truth[3];
    int w, m, aim;
    (void)state;
    sys->field_type = SG_FIELD_REAL_IMAGE_HEIGHT;
    sys->nfield = 2;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[1].x = 0.0;
    sys->field[1].y = H;
    mpfr_inits2(PREC, enp, tn, y, (mpfr_ptr)0);
    entrance_pupil(enp, WAVES[1]);
    for (aim = 0; aim < 2; aim++) {
        chief_ctx prim = {WAVES[1], aim, enp};
        sys->aim = aim ? SG_AIM_PARAXIAL : SG_AIM_OFF;
        field_for_height(tn, H, &prim);
        for (w = 0; w < 3; w++) {
            chief_ctx c = {WAVES[w], aim, enp};
            chief(y, tn, &c);
            truth[w] = mpfr_get_d(y, MPFR_RNDN);
        }
        print_message("# aim %s: chief ray heights F %.12f d %.12f C %.12f (MPFR)\n",
                      aim ? "paraxial" : "off", truth[0], truth[1], truth[2]);
        assert_true(fabs(truth[1] - H) < 1e-14);
        /* Lateral colour is not zero by construction. */
        assert_true(fabs(truth[0] - truth[2]) > 1e-4);
        for (m = 0; m < 3; m++)
            for (w = 0; w < 3; w++) {
                double e = engine_y(sys, cat, methods[m], w, 1.0, 0.0);
                if (fabs(e - truth[w]) > tol_of(methods[m]) * H)
                    fail_msg("%s aim %d wave %d: %.17g, MPFR %.17g", sg_method_name(methods[m]),
                             aim, w + 1, e, truth[w]);
            }
    }
    mpfr_clears(enp, tn, y, (mpfr_ptr)0);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lateral_colour),
        cmocka_unit_test(real_image_height),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
