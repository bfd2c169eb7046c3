/*
 * test_optimize.c - damped least squares (sg_optimize) reaching known
 * optima: a singlet's curvature for an EFFL target against the thick-lens
 * formula, the same with its back radius a pickup of the front (the
 * quadratic's root), a bounded thickness ending on its bound, a two-mirror
 * telescope whose conics land on the Ritchey-Chretien conics of the
 * third-order closed form, and a singlet's bending for least spherical
 * against a golden-section scan; the errors without variables or merit.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static sg_system *parse(const char *text)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    int rc;
    assert_non_null(sys);
    sg_diag_clear(&d);
    rc = sg_design_parse(sys, text, strlen(text), "t", &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

static void optimize(sg_system *sys, sg_opt_result *res)
{
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    rc = sg_optimize(sys, NULL, NULL, res, &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
}

static void near(double got, double want, double rtol, const char *what)
{
    if (!(fabs(got - want) <= rtol * fmax(fabs(want), 1e-300)))
        fail_msg("%s: %.17g, expected %.17g (rtol %g)", what, got, want, rtol);
}

/* A singlet of index 1.5: surfaces 1 and 2 with the given radius JSON
 * (and solves), thickness T, then air B; the merit's JSON. */
static sg_system *singlet(const char *s1, double T, const char *s2, const char *B,
                          const char *merit, double epd)
{
    char text[8192];
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": %g},"
             "\"surfaces\": ["
             "{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{%s, \"thickness\": %.17g, \"material\": 1.5, \"stop\": true},"
             "{%s, \"thickness\": %s},"
             "{\"radius\": \"inf\", \"thickness\": 0}],"
             "\"merit\": %s}",
             epd, s1, T, s2, B, merit);
    return parse(text);
}

/* R1 for EFL f with R2 and T fixed: 1/f = (n-1)(c1 - c2 + (n-1) T c1 c2
 * / n) is linear in c1.  The front starts flat: the curvature is what
 * varies, so it bends. */
static void effl_singlet(void **state)
{
    const double n = 1.5, T = 5, R2 = -100, f = 80, c2 = 1 / R2;
    double c1 = (1 / f + (n - 1) * c2) / ((n - 1) * (1 + (n - 1) * T * c2 / n));
    sg_system *sys = singlet("\"radius\": \"inf\", \"solves\": {\"radius\": {\"type\": "
                             "\"variable\"}}", T, "\"radius\": -100", "70",
                             "{\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 80}]}",
                             10);
    sg_opt_result res;
    (void)state;
    optimize(sys, &res);
    near(sys->surf[1].radius, 1 / c1, 1e-11, "R1");
    assert_true(res.converged);
    assert_true(res.merit < 1e-9 && res.merit0 > 1);
    /* Only the variable moved. */
    assert_true(sys->surf[2].radius == -100 && sys->surf[1].thickness == T);
    sg_system_free(sys);
}

/* The back radius, a pickup of -1 times the front, follows the variable:
 * 1/f = (n-1)(2c - (n-1) T c^2 / n), the smaller root. */
static void effl_pickup(void **state)
{
    const double n = 1.5, T = 5, f = 100;
    double a = (n - 1) * (n - 1) * T / n, b = -2 * (n - 1), c0 = 1 / f;
    double c = (-b - sqrt(b * b - 4 * a * c0)) / (2 * a);
    sg_system *sys = singlet("\"radius\": 300, \"solves\": {\"radius\": {\"type\": "
                             "\"variable\"}}", T,
                             "\"radius\": -300, \"solves\": {\"radius\": {\"type\": "
                             "\"pickup\", \"from\": 1, \"scale\": -1}}", "90",
                             "{\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 100}]}",
                             10);
    sg_opt_result res;
    (void)state;
    optimize(sys, &res);
    near(sys->surf[1].radius, 1 / c, 1e-11, "R1");
    assert_true(sys->surf[2].radius == -sys->surf[1].radius);
    sg_system_free(sys);
}

/* A thickness bounded by max 20 against a TOTR target beyond it ends on
 * the bound; the min and max hold on every trial (the change of
 * variable). */
static void bounded_thickness(void **state)
{
    sg_system *sys = singlet("\"radius\": 50", 5, "\"radius\": -50, \"solves\": {\"thickness\": "
                             "{\"type\": \"variable\", \"min\": 2, \"max\": 20}}", "10",
                             "{\"operands\": [{\"type\": \"TOTR\", \"target\": 1000}]}", 10);
    sg_opt_result res;
    (void)state;
    optimize(sys, &res);
    near(sys->surf[2].thickness, 20, 1e-9, "thickness at its max");
    assert_true(sys->surf[2].thickness <= 20);
    sg_system_free(sys);
}

/* The Ritchey-Chretien conics for magnification M, back focus B and
 * separation D (third order; Wilson, Reflecting Telescope Optics I,
 * eq. 3.109, as on Wikipedia's "Ritchey-Chretien telescope"):
 *   K1 = -1 - 2 B / (M^3 D),  K2 = -1 - 2 (M (2M - 1) + B / D) / (M - 1)^3.
 * The real-ray spot optimum over an on-axis and an off-axis field departs
 * from them by the balance of astigmatism (field^2) against coma (field),
 * so the departure falls as the square of the field: the test asks that
 * halving the field cuts it at least threefold, and that at 0.01 degree it
 * is under 5e-4 of each conic. */
static sg_system *two_mirror(double field)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": %g}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 100},"
             "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": -2000, \"thickness\": -700, \"material\": \"MIRROR\", \"stop\": true,"
             " \"solves\": {\"conic\": {\"type\": \"variable\"}}},"
             "{\"radius\": -900, \"thickness\": 900, \"material\": \"MIRROR\","
             " \"solves\": {\"conic\": {\"type\": \"variable\"}}},"
             "{\"radius\": \"inf\", \"thickness\": 0}],"
             "\"merit\": {\"default\": {\"criterion\": \"spot\", \"reference\": \"centroid\","
             " \"rings\": 3, \"arms\": 6}}}",
             field);
    return parse(text);
}

static void ritchey_chretien(void **state)
{
    /* f1 = 1000, the secondary 300 inside its focus and imaging it 900
     * away: M = 3, B = 900, D = 700. */
    const double M = 3, B = 900, D = 700;
    const double K1 = -1 - 2 * B / (M * M * M * D);
    const double K2 = -1 - 2 * (M * (2 * M - 1) + B / D) / ((M - 1) * (M - 1) * (M - 1));
    double dev[2][2];
    int i;
    (void)state;
    for (i = 0; i < 2; i++) {
        sg_system *sys = two_mirror(i ? 0.01 : 0.02);
        sg_opt_result res;
        sg_paraxial p;
        optimize(sys, &res);
        assert_true(res.merit < res.merit0 / 100);
        dev[i][0] = fabs(sys->surf[1].conic - K1);
        dev[i][1] = fabs(sys->surf[2].conic - K2);
        /* The paraxial design is M = 3 indeed. */
        assert_int_equal(sg_paraxial_compute(sys, NULL, 0, &p, NULL), SG_OK);
        near(p.efl, 3000, 1e-12, "EFL");
        sg_system_free(sys);
    }
    if (!(dev[1][0] < dev[0][0] / 3 && dev[1][1] < dev[0][1] / 3))
        fail_msg("the departure from the RC conics does not fall with the field: %g %g, then "
                 "%g %g", dev[0][0], dev[0][1], dev[1][0], dev[1][1]);
    if (!(dev[1][0] < 5e-4 * fabs(K1) && dev[1][1] < 5e-4 * fabs(K2)))
        fail_msg("conics depart from RC by %g and %g", dev[1][0], dev[1][1]);
}

/* The merit of the singlet with front radius R (the back one an F/#
 * solve, the focus a marginal-height solve). */
static double bend_merit(sg_system *sys, double R)
{
    sg_merit_result r;
    sg_diag d;
    double v;
    sys->surf[1].radius = R;
    sg_diag_clear(&d);
    if (sg_system_apply_solves(sys, NULL, &d) != SG_OK || sg_merit_eval(sys, NULL, &r, &d) != SG_OK)
        fail_msg("%s", d.msg);
    v = r.merit;
    sg_merit_result_free(&r);
    return v;
}

/* A singlet's bending for least spherical at F/5, the EFL held by an F/#
 * solve on the back radius and the focus by a marginal-height solve,
 * against a golden-section scan of the front curvature.  The scan shares
 * the merit's evaluation (sg_merit_eval), so this checks the optimizer,
 * not the merit; the closed forms above are the primary evidence. */
static void singlet_bending(void **state)
{
    sg_system *sys = singlet("\"radius\": 100, \"solves\": {\"radius\": {\"type\": \"variable\"}}",
                             5, "\"radius\": -100, \"solves\": {\"radius\": {\"type\": \"fnum\", "
                             "\"value\": 5}, \"thickness\": {\"type\": \"marginal_height\", "
                             "\"value\": 0}}", "90",
                             "{\"default\": {\"criterion\": \"spot\", \"reference\": "
                             "\"centroid\", \"rings\": 4, \"arms\": 6}}", 20);
    sg_system *scan = sg_system_clone(sys);
    const double g = (sqrt(5.0) - 1) / 2;
    double a = 1 / 200.0, b = 1 / 40.0, x1, x2, f1, f2, cbest, mbest;
    sg_opt_result res;
    sg_paraxial p;
    int k;
    (void)state;
    assert_non_null(scan);
    /* Golden section over the curvature c1 in [1/200, 1/40]. */
    x1 = b - g * (b - a);
    x2 = a + g * (b - a);
    f1 = bend_merit(scan, 1 / x1);
    f2 = bend_merit(scan, 1 / x2);
    for (k = 0; k < 80; k++) {
        if (f1 < f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = bend_merit(scan, 1 / x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = bend_merit(scan, 1 / x2);
        }
    }
    cbest = (a + b) / 2;
    mbest = bend_merit(scan, 1 / cbest);
    optimize(sys, &res);
    near(1 / sys->surf[1].radius, cbest, 1e-6, "front curvature");
    near(res.merit, mbest, 1e-9, "merit");
    /* The solves held: F/5 at EPD 20 is an EFL of 100. */
    assert_int_equal(sg_paraxial_compute(sys, NULL, 0, &p, NULL), SG_OK);
    near(p.efl, 100, 1e-12, "EFL");
    sg_system_free(scan);
    sg_system_free(sys);
}

/* A stop before the first cycle keeps the start (the best so far), and
 * the Jacobian's columns on two threads give the single thread's bits. */
static void stop_and_threads(void **state)
{
    static const char *const s2 = "\"radius\": -100, \"solves\": {\"radius\": {\"type\": "
                                  "\"variable\"}}";
    const char *merit = "{\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 80},"
                        "{\"type\": \"ETGT\", \"surf\": 1, \"target\": 2}]}";
    sg_system *a = singlet("\"radius\": 200, \"solves\": {\"radius\": {\"type\": "
                           "\"variable\"}}", 5, s2, "70", merit, 10);
    sg_system *b = sg_system_clone(a), *c = sg_system_clone(a);
    sg_opt_opts o;
    sg_opt_result res;
    sg_diag d;
    volatile int stop = 1;
    (void)state;
    sg_opt_opts_init(&o);
    o.stop = &stop;
    sg_diag_clear(&d);
    assert_int_equal(sg_optimize(c, NULL, &o, &res, &d), SG_OK);
    assert_true(res.stopped);
    assert_true(sg_system_equal(a, c));
    stop = 0;
    o.nthreads = 1;
    assert_int_equal(sg_optimize(a, NULL, &o, &res, &d), SG_OK);
    o.nthreads = 2;
    assert_int_equal(sg_optimize(b, NULL, &o, &res, &d), SG_OK);
    assert_true(sg_system_equal(a, b));
    assert_true(a->surf[1].radius != 200);
    sg_system_free(a);
    sg_system_free(b);
    sg_system_free(c);
}

static void errors(void **state)
{
    sg_system *sys = singlet("\"radius\": 50", 5, "\"radius\": -50", "40",
                             "{\"operands\": [{\"type\": \"TOTR\", \"target\": 1}]}", 10);
    sg_opt_result res;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_optimize(sys, NULL, NULL, &res, &d), SG_ENOSYS);
    assert_non_null(strstr(d.msg, "no variables"));
    sys->surf[1].solve[SG_SOLVE_RADIUS].kind = SG_SOLVE_VARIABLE;
    sys->surf[1].solve[SG_SOLVE_RADIUS].lo = -INFINITY;
    sys->surf[1].solve[SG_SOLVE_RADIUS].hi = INFINITY;
    sys->merit.present = 0;
    sg_diag_clear(&d);
    assert_int_equal(sg_optimize(sys, NULL, NULL, &res, &d), SG_ENOSYS);
    assert_non_null(strstr(d.msg, "no merit function"));
    /* A start outside the variable's bounds. */
    sys->merit.present = 1;
    sys->surf[1].solve[SG_SOLVE_RADIUS].lo = 60;
    sg_diag_clear(&d);
    assert_int_equal(sg_optimize(sys, NULL, NULL, &res, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "surface 1 radius"));
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(effl_singlet),
        cmocka_unit_test(effl_pickup),
        cmocka_unit_test(bounded_thickness),
        cmocka_unit_test(ritchey_chretien),
        cmocka_unit_test(singlet_bending),
        cmocka_unit_test(stop_and_threads),
        cmocka_unit_test(errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
