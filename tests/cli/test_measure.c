/* test_measure.c - ui/measure.c: the digits metric verify and the editor
 * share, and the residual as defined, |z - sag(x, y)|.  Expectations are
 * closed forms: surfaces and points chosen so that the sag is exact in
 * binary, and points moved off them by a known power of two. */
#include <math.h>
#include <string.h>

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "measure.h"

static sg_surface surf(double R, double k)
{
    sg_surface s;
    memset(&s, 0, sizeof s);
    s.type = SG_SURF_STANDARD;
    s.radius = R;
    s.conic = k;
    return s;
}

static void test_digits(void **state)
{
    double a[3] = { 5e-29, 0.0, 0.0 }, b[3] = { 0.0, 0.0, 0.0 };
    double c[3] = { 1.0, 2.0, 3.0 }, d[3] = { 1.0, 2.0 + 2e-12, 3.0 };
    (void)state;
    /* A 5e-29 mm difference at a vertex of a 12.5 mm ray: all 17 digits
     * (the old purely relative metric, sg_digits, gave 0). */
    assert_true(meas_coord_digits(5e-29, 0.0, 12.5) == 17.0);
    assert_true(sg_digits(5e-29, 0.0) == 0.0);
    assert_true(meas_point_digits(a, b, 12.5) == 17.0);
    /* With nothing to borrow a size from, a nonzero error is 0 digits. */
    assert_true(meas_point_digits(a, b, 0.0) == 0.0);
    /* Ordinary coordinates: -log10(|a - b| / |b|). */
    assert_true(fabs(meas_point_digits(d, c, 0.0) - 12.0) < 1e-3);
    /* A small coordinate of a large point: judged against 1e-6 of it. */
    assert_true(fabs(meas_coord_digits(1e-9 + 1e-20, 1e-9, 100.0) -
                     (-log10(1e-20 / 1e-4))) < 1e-3);
    assert_true(meas_coord_digits(1.0, 1.0, 0.0) == MEAS_DIGITS_CAP);
    assert_true(meas_coord_digits(NAN, 1.0, 1.0) == 0.0);
}

static void test_residual(void **state)
{
    sg_surface s;
    (void)state;
    /* R = 1.25, r = 0.75: sag = 1.25 - sqrt(1.5625 - 0.5625) = 0.25 exactly. */
    s = surf(1.25, 0.0);
    assert_true(meas_residual(&s, 0.75, 0.0, 0.25) == 0.0);
    assert_true(meas_residual(&s, 0.75, 0.0, nextafter(0.25, 1.0)) == 0x1p-54);
    assert_true(meas_residual(&s, 0.0, -0.75, nextafter(0.25, 0.0)) == 0x1p-55);
    /* R = -0.75, x = y = 0.5: sag = -(0.75 - 0.25) = -0.5. */
    s = surf(-0.75, 0.0);
    assert_true(meas_residual(&s, 0.5, 0.5, nextafter(-0.5, 0.0)) == 0x1p-54);
    /* Parabola R = 2 (k = -1): sag = r^2 / 4; 1 off the vertex, 0.25. */
    s = surf(2.0, -1.0);
    assert_true(meas_residual(&s, 1.0, 0.0, nextafter(0.25, 1.0)) == 0x1p-54);
    /* A point 1 ulp off at a vertex far from 1: 2^-1074 below a flat. */
    s = surf(INFINITY, 0.0);
    assert_true(meas_residual(&s, 3.0, 4.0, 0x1p-1074) == 0x1p-1074);
    /* Even asphere, flat base, r^4 term 1: sag(0.5) = 0.0625. */
    s = surf(INFINITY, 0.0);
    s.type = SG_SURF_EVENASPH;
    s.asph[1] = 1.0;
    assert_true(meas_residual(&s, 0.5, 0.0, nextafter(0.0625, 0.0)) == 0x1p-57);
    /* The same terms on a STANDARD surface are ignored, as the trace does. */
    s.type = SG_SURF_STANDARD;
    assert_true(meas_residual(&s, 0.5, 0.0, 0.0625) == 0.0625);
    /* Outside the conic's domain there is no sag. */
    s = surf(1.0, 0.0);
    assert_true(isnan(meas_residual(&s, 2.0, 0.0, 0.0)));
    /* A huge radius: the sag 1.25e-19 of r = 0.5 at R = 1e18 is what the
     * point at z = 0 misses it by (to 1e-15 relative). */
    s = surf(1e18, 0.0);
    assert_true(fabs(meas_residual(&s, 0.5, 0.0, 0.0) - 1.25e-19) <= 1.25e-34);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_digits),
        cmocka_unit_test(test_residual),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
