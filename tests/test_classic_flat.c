/*
 * test_classic_flat.c - the classic method on spheres so flat (|R| from
 * 1e15 to 1e150) that the textbook quadratic formula cancels to nothing.
 * Before the fix classic put the hit at the previous surface (path 0,
 * residual 5 mm) with status OK from |R| = 1e18 on.
 *
 * The truth is the near crossing of the same double inputs with the
 * sphere x^2 + y^2 + z^2 - 2 R z = 0, computed here in MPFR at 1200 bits
 * with the cancellation-free root t = C / q, q = -(B + sgn(B) sqrt(B^2 - A C)).
 */
#include <math.h>
#include <mpfr.h>
#include <stdio.h>

#include "testutil.h"

/* Stop flat, then the flat sphere (glass after it), then air to the image. */
static sg_system *flat_system(double R)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 5), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].thickness = 5.0;
    sys->surf[2].radius = R;
    sys->surf[2].thickness = 10.0;
    sys->surf[2].mat.kind = SG_MAT_INDEX;
    sys->surf[2].mat.index = 1.5;
    sys->surf[3].thickness = 5.0;
    sys->stop = 1;
    return sys;
}

/* Crossing of P + t D (surface 2's frame, D unit in MPFR) with the sphere
 * of radius R; out = point, *path = t. */
static void truth(double R, const double P[3], const double Din[3], double out[3],
                  double *path)
{
    mpfr_t a, b, c, t, u, v, d[3], len;
    int k;
    mpfr_inits2(1200, a, b, c, t, u, v, d[0], d[1], d[2], len, (mpfr_ptr)0);
    mpfr_set_zero(len, 1);
    for (k = 0; k < 3; k++) {
        mpfr_set_d(d[k], Din[k], MPFR_RNDN);
        mpfr_sqr(u, d[k], MPFR_RNDN);
        mpfr_add(len, len, u, MPFR_RNDN);
    }
    mpfr_sqrt(len, len, MPFR_RNDN);
    for (k = 0; k < 3; k++)
        mpfr_div(d[k], d[k], len, MPFR_RNDN);
    /* A t^2 + 2 B t + C = 0 with A = 1, B = P.d - R d_z, C = |P|^2 - 2 R P_z */
    mpfr_set_ui(a, 1, MPFR_RNDN);
    mpfr_set_zero(b, 1);
    mpfr_set_zero(c, 1);
    for (k = 0; k < 3; k++) {
        mpfr_mul_d(u, d[k], P[k], MPFR_RNDN);
        mpfr_add(b, b, u, MPFR_RNDN);
        mpfr_set_d(u, P[k], MPFR_RNDN);
        mpfr_sqr(u, u, MPFR_RNDN);
        mpfr_add(c, c, u, MPFR_RNDN);
    }
    mpfr_mul_d(u, d[2], R, MPFR_RNDN);
    mpfr_sub(b, b, u, MPFR_RNDN);
    mpfr_set_d(u, P[2], MPFR_RNDN);
    mpfr_mul_d(u, u, 2.0 * R, MPFR_RNDN);
    mpfr_sub(c, c, u, MPFR_RNDN);
    /* q = -(B + sgn(B) sqrt(B^2 - A C)), near root C / q */
    mpfr_sqr(u, b, MPFR_RNDN);
    mpfr_mul(v, a, c, MPFR_RNDN);
    mpfr_sub(u, u, v, MPFR_RNDN);
    assert_true(mpfr_sgn(u) >= 0);
    mpfr_sqrt(u, u, MPFR_RNDN);
    if (mpfr_sgn(b) < 0)
        mpfr_neg(u, u, MPFR_RNDN);
    mpfr_add(u, u, b, MPFR_RNDN);
    mpfr_neg(u, u, MPFR_RNDN);
    mpfr_div(t, c, u, MPFR_RNDN);
    *path = mpfr_get_d(t, MPFR_RNDN);
    for (k = 0; k < 3; k++) {
        mpfr_mul(u, t, d[k], MPFR_RNDN);
        mpfr_add_d(u, u, P[k], MPFR_RNDN);
        out[k] = mpfr_get_d(u, MPFR_RNDN);
    }
    mpfr_clears(a, b, c, t, u, v, d[0], d[1], d[2], len, (mpfr_ptr)0);
}

/* Starts lie on surface 1 (z = 0), so the path to surface 2 is t. */
static void check_radius(sg_catalog *cat, double R, const double S[3], const double D[3])
{
    sg_system *sys = flat_system(R);
    sg_tracer *t = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
    sg_ray_surface out[5];
    double P[3] = { S[0], S[1], S[2] - 5.0 }, want[3], path;
    int rc = sg_trace_start(t, S, D, out), k;
    truth(R, P, D, want, &path);
    printf("# R = %g: classic (%.17g, %.17g, %.17g) path %.17g; truth (%.17g, %.17g, "
           "%.17g) path %.17g\n", R, out[2].x, out[2].y, out[2].z, out[2].path, want[0],
           want[1], want[2], path);
    assert_int_equal(rc, SG_OK);
    assert_int_equal(out[2].status, SG_OK);
    /* Coordinates near 1 mm, path near 5 mm: the old fault was 5 mm off. */
    for (k = 0; k < 3; k++)
        assert_true(fabs((&out[2].x)[k] - want[k]) <= 1e-14);
    assert_true(fabs(out[2].path - path) <= 1e-14 * fabs(path));
    assert_true(out[2].residual <= 1e-14);
    /* A sphere this flat barely bends the ray: the direction after it is
     * the refracted one of a plane to 1e-14, and finite. */
    assert_true(isfinite(out[2].l) && isfinite(out[2].m) && isfinite(out[2].n));
    assert_true(isfinite(out[2].error_bound) && out[2].error_bound < 1e-10);
    assert_true(isfinite(out[4].x) && out[4].status == SG_OK);
    sg_tracer_free(t);
    sg_system_free(sys);
}

static void classic_on_flat_spheres(void **state)
{
    /* Up to the largest radius a design may have (1e150; beyond, the trace
     * would square it past the double range, and validation refuses it). */
    static const double radii[] = { 1e15, 1e17, 1e18, -1e18, 3e19, -7e22, 1e30,
                                    1e100, 1e149, -1e150 };
    static const double starts[3][3] = { { 0.3, 0.2, 0.0 }, { -1.1, 0.0, 0.0 },
                                         { 0.0, 0.0, 0.0 } };
    static const double dirs[3][3] = { { 0.1, 0.2, 1.0 }, { 0.3, -0.05, 1.0 },
                                       { 0.0, 0.0, 1.0 } };
    sg_catalog *cat = tu_catalog();
    size_t i, j;
    (void)state;
    for (i = 0; i < sizeof radii / sizeof radii[0]; i++)
        for (j = 0; j < 3; j++)
            check_radius(cat, radii[i], starts[j], dirs[j]);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(classic_on_flat_spheres),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
