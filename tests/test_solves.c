/*
 * test_solves.c - solves and pickups (sg_system_apply_solves): the
 * marginal-ray height, marginal-ray angle and F/# solves against the
 * thick-lens formulas computed here in MPFR, pickups, the errors, JSON and
 * .zmx round trips, and the MAZH solve of a file written by Zemax
 * (tests/data/zmx/zmax_55278.zmx, line 84), which must give back the
 * thickness the file stores (line 83).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gmp.h>
#include <mpfr.h>

#include "testutil.h"

/* A singlet of index 1.5 (no dispersion), radii R1 and R2, centre
 * thickness T, after an object at distance T0 ("inf" for infinity), with an
 * entrance pupil of 10; solves (JSON) on surface 1 and 2. */
static sg_system *singlet(const char *T0, double R1, double R2, double T, const char *solve1,
                          const char *solve2)
{
    char text[4096], r1[40], r2[40];
    sg_diag d;
    sg_system *sys = sg_system_new();
    int rc;
    assert_non_null(sys);
    snprintf(r1, sizeof r1, isinf(R1) ? "\"inf\"" : "%.17g", R1);
    snprintf(r2, sizeof r2, isinf(R2) ? "\"inf\"" : "%.17g", R2);
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 3, \"title\": \"t\", \"units\": "
             "\"mm\", \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5876}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"x\": 0, \"y\": 0}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
             "\"surfaces\": ["
             "{\"radius\": \"inf\", \"thickness\": %s},"
             "{\"radius\": %s, \"thickness\": %.17g, \"material\": 1.5, "
             "\"stop\": true%s},"
             "{\"radius\": %s, \"thickness\": 10%s},"
             "{\"radius\": \"inf\", \"thickness\": 0}]}",
             T0, r1, T, solve1, r2, solve2);
    sg_diag_clear(&d);
    rc = sg_design_parse(sys, text, strlen(text), "singlet", &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

static void apply(sg_system *sys)
{
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    rc = sg_system_validate(sys, NULL, &d);
    if (rc == SG_OK)
        rc = sg_system_apply_solves(sys, NULL, &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
}

/* a and b equal or neighbours: the solve and the formula each round once. */
static void near(double a, double b)
{
    if (!(a == b || nextafter(a, b) == b))
        fail_msg("%.17g and %.17g differ by more than one step", a, b);
}

/* The thick-lens formulas: powers P1 = (n-1)/R1, P2 = (1-n)/R2, the
 * lens's power P = P1 + P2 - t P1 P2 / n; its back focal distance from the
 * last vertex f (1 - t P1 / n) with f = 1/P. */
static double bfd_formula(double R1, double R2, double T)
{
    mpfr_t n, p1, p2, p, a;
    double r;
    mpfr_inits2(256, n, p1, p2, p, a, (mpfr_ptr)0);
    mpfr_set_d(n, 1.5, MPFR_RNDN);
    mpfr_sub_ui(p1, n, 1, MPFR_RNDN);
    mpfr_div_d(p1, p1, R1, MPFR_RNDN);
    mpfr_ui_sub(p2, 1, n, MPFR_RNDN);
    mpfr_div_d(p2, p2, R2, MPFR_RNDN);
    mpfr_mul(a, p1, p2, MPFR_RNDN);
    mpfr_mul_d(a, a, T, MPFR_RNDN);
    mpfr_div(a, a, n, MPFR_RNDN);
    mpfr_add(p, p1, p2, MPFR_RNDN);
    mpfr_sub(p, p, a, MPFR_RNDN);
    mpfr_mul_d(a, p1, T, MPFR_RNDN);
    mpfr_div(a, a, n, MPFR_RNDN);
    mpfr_ui_sub(a, 1, a, MPFR_RNDN);
    mpfr_div(a, a, p, MPFR_RNDN);
    r = mpfr_get_d(a, MPFR_RNDN);
    mpfr_clears(n, p1, p2, p, a, (mpfr_ptr)0);
    return r;
}

/* The image of an object at distance s0 before the first vertex, by the
 * vergences: n'/l' = n/l + P at each surface, l' - t for the next. */
static double image_formula(double s0, double R1, double R2, double T)
{
    mpfr_t n, v, l;
    double r;
    mpfr_inits2(256, n, v, l, (mpfr_ptr)0);
    mpfr_set_d(n, 1.5, MPFR_RNDN);
    /* Vergence at surface 1: 1 / (-s0), plus (n-1)/R1. */
    mpfr_set_d(v, -s0, MPFR_RNDN);
    mpfr_ui_div(v, 1, v, MPFR_RNDN);
    mpfr_sub_ui(l, n, 1, MPFR_RNDN);
    mpfr_div_d(l, l, R1, MPFR_RNDN);
    mpfr_add(v, v, l, MPFR_RNDN);
    /* l1' = n / v, then l2 = l1' - T, vergence n / l2. */
    mpfr_div(l, n, v, MPFR_RNDN);
    mpfr_sub_d(l, l, T, MPFR_RNDN);
    mpfr_div(v, n, l, MPFR_RNDN);
    mpfr_ui_sub(l, 1, n, MPFR_RNDN);
    mpfr_div_d(l, l, R2, MPFR_RNDN);
    mpfr_add(v, v, l, MPFR_RNDN);
    mpfr_ui_div(l, 1, v, MPFR_RNDN);
    r = mpfr_get_d(l, MPFR_RNDN);
    mpfr_clears(n, v, l, (mpfr_ptr)0);
    return r;
}

static void test_marginal_height_focus(void **state)
{
    static const double lens[][3] = {{50, -50, 5}, {80, -200, 8}, {-60, -30, 4}, {30, 1e18, 6}};
    int i;
    (void)state;
    for (i = 0; i < 4; i++) {
        double R2 = lens[i][1] > 1e17 ? INFINITY : lens[i][1];
        sg_system *sys = singlet("\"inf\"", lens[i][0], R2, lens[i][2], "",
                                 ", \"solves\": {\"thickness\": {\"type\": \"marginal_height\", "
                                 "\"value\": 0}}");
        apply(sys);
        near(sys->surf[2].thickness, bfd_formula(lens[i][0], R2, lens[i][2]));
        sg_system_free(sys);
        /* A finite object: the paraxial image distance. */
        sys = singlet("300", lens[i][0], R2, lens[i][2], "",
                      ", \"solves\": {\"thickness\": {\"type\": \"marginal_height\", "
                      "\"value\": 0}}");
        apply(sys);
        near(sys->surf[2].thickness, image_formula(300, lens[i][0], R2, lens[i][2]));
        sg_system_free(sys);
    }
}

static void test_marginal_height_value(void **state)
{
    /* Height h on the next surface: the ray from (bfd, 0) back to the last
     * vertex at height y2 = 5 (1 - T P1 / n), so t = bfd (1 - h / y2). */
    double R1 = 50, R2 = -50, T = 5, bfd = bfd_formula(R1, R2, T);
    double y2 = 5.0 * (1.0 - T * (0.5 / R1) / 1.5);
    sg_system *sys = singlet("\"inf\"", R1, R2, T, "",
                             ", \"solves\": {\"thickness\": {\"type\": \"marginal_height\", "
                             "\"value\": -1.25}}");
    (void)state;
    apply(sys);
    assert_true(fabs(sys->surf[2].thickness - bfd * (1.0 + 1.25 / y2)) < 1e-12 * bfd);
    sg_system_free(sys);
}

/* The last radius of a lens of power P (R1 = 60, T = 6, n = 1.5):
 * P2 = (P - P1) / (1 - T P1 / n) and R2 = (1 - n) / P2.  P is 1 / (F D)
 * for the F/# solve (D = 10), -u' / y1 for an angle u' (y1 = 5). */
static double last_radius(double F, double u)
{
    double R1 = 60, T = 6, want;
    mpfr_t P, P1, a;
    mpfr_inits2(256, P, P1, a, (mpfr_ptr)0);
    if (F != 0.0) {
        mpfr_set_d(P, F, MPFR_RNDN);
        mpfr_mul_ui(P, P, 10, MPFR_RNDN);
        mpfr_ui_div(P, 1, P, MPFR_RNDN);
    } else {
        mpfr_set_d(P, -u, MPFR_RNDN);
        mpfr_div_ui(P, P, 5, MPFR_RNDN);
    }
    mpfr_set_d(P1, 0.5, MPFR_RNDN);
    mpfr_div_d(P1, P1, R1, MPFR_RNDN);
    mpfr_mul_d(a, P1, T, MPFR_RNDN);
    mpfr_div_d(a, a, 1.5, MPFR_RNDN);
    mpfr_ui_sub(a, 1, a, MPFR_RNDN);
    mpfr_sub(P, P, P1, MPFR_RNDN);
    mpfr_div(P, P, a, MPFR_RNDN);
    mpfr_d_div(P, -0.5, P, MPFR_RNDN);
    want = mpfr_get_d(P, MPFR_RNDN);
    mpfr_clears(P, P1, a, (mpfr_ptr)0);
    return want;
}

/* The F/# solve on the last radius, and the marginal-ray angle solve. */
static void test_fnum_and_angle(void **state)
{
    static const double F[] = {2.0, 4.5, 10.0, -8.0};
    double R1 = 60, T = 6;
    int i;
    (void)state;
    for (i = 0; i < 4; i++) {
        char s2[160];
        sg_system *sys;
        sg_paraxial p;
        sg_diag d;
        double want = last_radius(F[i], 0.0), u = -0.5 / F[i];
        snprintf(s2, sizeof s2, ", \"solves\": {\"radius\": {\"type\": \"fnum\", \"value\": %g}}",
                 F[i]);
        sys = singlet("\"inf\"", R1, 100, T, "", s2);
        apply(sys);
        near(sys->surf[2].radius, want);
        sg_diag_clear(&d);
        assert_int_equal(sg_paraxial_compute(sys, NULL, 0, &p, &d), SG_OK);
        assert_true(fabs(p.image_fnum - fabs(F[i])) < 1e-12 * fabs(F[i]));
        sg_system_free(sys);

        /* The same as an angle solve of -1 / (2 F). */
        snprintf(s2, sizeof s2,
                 ", \"solves\": {\"radius\": {\"type\": \"marginal_angle\", \"value\": %.17g}}",
                 u);
        sys = singlet("\"inf\"", R1, 100, T, "", s2);
        apply(sys);
        near(sys->surf[2].radius, last_radius(0.0, u));
        sg_system_free(sys);
    }
}

/* A solve before the stop moves the entrance pupil, so the solves repeat:
 * the object 100 before surface 1, the stop on surface 2; an angle solve
 * of 0 on surface 1 (index 1 to 1.5) collimates the axial cone, which puts
 * the object at the surface's front focus: 0.5 / R1 = 1 / 100, R1 = 50,
 * whatever the pupil. */
static void test_pupil_iteration(void **state)
{
    sg_system *sys = singlet("100", 20, -80, 5,
                             ", \"solves\": {\"radius\": {\"type\": \"marginal_angle\", "
                             "\"value\": 0}}", "");
    (void)state;
    sys->stop = 2;
    apply(sys);
    near(sys->surf[1].radius, 50.0);
    sg_system_free(sys);
}

static void expect_error(sg_system *sys, int code, const char *text)
{
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    rc = sg_system_validate(sys, NULL, &d);
    if (rc == SG_OK)
        rc = sg_system_apply_solves(sys, NULL, &d);
    assert_int_equal(rc, code);
    if (!strstr(d.msg, text))
        fail_msg("'%s' does not say '%s'", d.msg, text);
}

/* The chief_height solve with the stop on surface 1 and a field of 10
 * degrees: height 0 puts the next surface on the exit pupil, the image of
 * surface 1 by surface 2 (vergence: 1 / l' = -n / T + (1 - n) / R2); a
 * height h, by the chief ray's y-nu steps in long double: y2 = T tan / n,
 * w2 = tan - y2 (1 - n) / R2, t = (h - y2) / w2. */
static void test_chief_height(void **state)
{
    const double R1 = 50, R2 = -50, T = 5;
    long double tn = tanl(10.0L * 3.14159265358979323846264338327950288L / 180.0L);
    long double y2 = T * tn / 1.5L, w2 = tn - y2 * (1.0L - 1.5L) / R2;
    sg_system *sys = singlet("\"inf\"", R1, R2, T, "",
                             ", \"solves\": {\"thickness\": {\"type\": \"chief_height\", "
                             "\"value\": 0}}");
    double want = (double)(1.0L / (-1.5L / T + (1.0L - 1.5L) / R2));
    (void)state;
    sys->field[0].y = 10.0;
    apply(sys);
    assert_true(fabs(sys->surf[2].thickness - want) < 1e-15 * fabs(want));
    sys->surf[2].solve[SG_SOLVE_THICKNESS].value = 2.5;
    apply(sys);
    want = (double)((2.5L - y2) / w2);
    assert_true(fabs(sys->surf[2].thickness - want) < 1e-15 * fabs(want));
    /* No field: the chief ray runs along the axis, no solution. */
    sys->field[0].y = 0.0;
    expect_error(sys, SG_ENONPHYS, "surface 2: thickness: the chief_height solve has no "
                 "solution");
    sg_system_free(sys);
}

static void test_pickups(void **state)
{
    sg_system *sys = singlet("\"inf\"", 40, 100, 5, ", \"conic\": -0.75",
                             ", \"solves\": {\"radius\": {\"type\": \"pickup\", \"from\": 1, "
                             "\"scale\": -1}, \"thickness\": {\"type\": \"pickup\", \"from\": 1, "
                             "\"scale\": 2.5, \"offset\": 0.25}, \"conic\": {\"type\": "
                             "\"pickup\", \"from\": 1}}");
    (void)state;
    apply(sys);
    assert_true(sys->surf[2].radius == -40.0);
    assert_true(sys->surf[2].thickness == 12.75);
    assert_true(sys->surf[2].conic == -0.75);
    /* Inserting a surface before the source follows it. */
    assert_int_equal(sg_system_insert(sys, 1), SG_OK);
    assert_int_equal(sys->surf[3].solve[SG_SOLVE_RADIUS].from, 2);
    /* Deleting the source leaves the value and drops the pickup. */
    assert_int_equal(sg_system_delete(sys, 2), SG_OK);
    assert_int_equal(sys->surf[2].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_NONE);
    assert_true(sys->surf[2].radius == -40.0);
    sg_system_free(sys);
}


/* L minus the thicknesses, in 2000-bit MPFR (exact for these doubles),
 * rounded once: the closed form of a position solve. */
static double position_closed(double L, const double *t, int n)
{
    mpfr_t x;
    double r;
    int k;
    mpfr_init2(x, 2000);
    mpfr_set_d(x, L, MPFR_RNDN);
    for (k = 0; k < n; k++)
        mpfr_sub_d(x, x, t[k], MPFR_RNDN);
    r = mpfr_get_d(x, MPFR_RNDN);
    mpfr_clear(x);
    return r;
}

/* Zemax's position solve: the axial distance from the reference surface's
 * vertex to the next surface is L, so the thickness is L minus the
 * thicknesses from the reference on; it follows edits, surfaces inserted
 * between, and is dropped with its reference. */
static void test_position(void **state)
{
    sg_system *sys;
    double t[3];
    (void)state;
    /* From the surface before: t2 = L - t1, with digits that do not
     * cancel (30.125 - 5.3 is not a double sum). */
    sys = singlet("100.7", 40, 100, 5.3, "",
                  ", \"solves\": {\"thickness\": {\"type\": \"position\", \"from\": 1, "
                  "\"value\": 30.125}}");
    apply(sys);
    t[0] = 5.3;
    assert_true(sys->surf[2].thickness == position_closed(30.125, t, 1));
    /* Follows an edit of the space before it. */
    sys->surf[1].thickness = 7.77;
    apply(sys);
    t[0] = 7.77;
    assert_true(sys->surf[2].thickness == position_closed(30.125, t, 1));
    /* From the object: L - t0 - t1. */
    sys->surf[2].solve[SG_SOLVE_THICKNESS].from = 0;
    apply(sys);
    t[0] = 100.7;
    t[1] = 7.77;
    assert_true(sys->surf[2].thickness == position_closed(30.125, t, 2));
    /* From itself: the thickness is L. */
    sys->surf[2].solve[SG_SOLVE_THICKNESS].from = 2;
    apply(sys);
    assert_true(sys->surf[2].thickness == 30.125);
    /* A surface inserted between the reference and the solve counts, and
     * the solve moves with its surface. */
    sys->surf[2].solve[SG_SOLVE_THICKNESS].from = 1;
    assert_int_equal(sg_system_insert(sys, 2), SG_OK);
    sys->surf[2].thickness = 2.5;
    assert_int_equal(sys->surf[3].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_POSITION);
    assert_int_equal(sys->surf[3].solve[SG_SOLVE_THICKNESS].from, 1);
    apply(sys);
    t[0] = 7.77;
    t[1] = 2.5;
    assert_true(sys->surf[3].thickness == position_closed(30.125, t, 2));
    /* A surface inserted before the reference renumbers it. */
    assert_int_equal(sg_system_insert(sys, 1), SG_OK);
    assert_int_equal(sys->surf[4].solve[SG_SOLVE_THICKNESS].from, 2);
    /* Written and read back (format version 5). */
    {
        char *j = sg_design_to_json(sys);
        sg_system *b = sg_system_new();
        sg_diag d;
        assert_non_null(strstr(j, "\"version\": 5,"));
        assert_non_null(strstr(j, "{\"type\": \"position\", \"from\": 2, \"value\": 30.125}"));
        sg_diag_clear(&d);
        if (sg_design_parse(b, j, strlen(j), "p.json", &d) != SG_OK)
            fail_msg("%s", d.msg);
        assert_true(sg_system_equal(sys, b));
        free(j);
        sg_system_free(b);
    }
    /* Deleting the reference leaves the value and drops the solve. */
    t[0] = sys->surf[4].thickness;
    assert_int_equal(sg_system_delete(sys, 2), SG_OK);
    assert_int_equal(sys->surf[3].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_NONE);
    assert_true(sys->surf[3].thickness == t[0]);
    sg_system_free(sys);
    /* Refused: a later reference, the image, a missing length; not
     * physical: the object at infinity among the thicknesses. */
    sys = singlet("\"inf\"", 40, 100, 5, "",
                  ", \"solves\": {\"thickness\": {\"type\": \"position\", \"from\": 3, "
                  "\"value\": 20}}");
    expect_error(sys, SG_ERANGE, "surface 2: thickness: the position solve's reference surface 3 "
                 "is not this or an earlier surface");
    sys->surf[2].solve[SG_SOLVE_THICKNESS].from = 0;
    expect_error(sys, SG_ENONPHYS, "surface 2: thickness: the position solve from surface 0 gives");
    sys->surf[2].solve[SG_SOLVE_THICKNESS].kind = SG_SOLVE_NONE;
    sys->surf[3].solve[SG_SOLVE_THICKNESS].kind = SG_SOLVE_POSITION;
    sys->surf[3].solve[SG_SOLVE_THICKNESS].from = 1;
    expect_error(sys, SG_ERANGE, "surface 3: thickness: a position solve needs a surface after "
                 "the object and before the image");
    sg_system_free(sys);
    {
        static const char text[] =
            "{\"surfaces\": [{}, {\"stop\": true, \"solves\": {\"thickness\": "
            "{\"type\": \"position\", \"value\": 3}}}, {}]}";
        sg_system *b = sg_system_new();
        sg_diag d;
        sg_diag_clear(&d);
        assert_int_equal(sg_design_parse(b, text, strlen(text), "q.json", &d), SG_EPARSE);
        if (!strstr(d.msg, "q.json: surface 1: solves: thickness: a position solve needs \"from\""))
            fail_msg("%s", d.msg);
        sg_system_free(b);
    }
}

static void test_errors(void **state)
{
    sg_system *sys;
    (void)state;
    /* A pickup from a later surface, and from itself. */
    sys = singlet("\"inf\"", 40, 100, 5,
                  ", \"solves\": {\"radius\": {\"type\": \"pickup\", \"from\": 2}}", "");
    expect_error(sys, SG_ERANGE, "surface 1: radius: the pickup's source surface 2");
    sys->surf[1].solve[SG_SOLVE_RADIUS].from = 1;
    expect_error(sys, SG_ERANGE, "surface 1: radius: the pickup's source surface 1");
    sg_system_free(sys);
    /* A plate: the marginal ray leaves parallel, no focus. */
    sys = singlet("\"inf\"", INFINITY, INFINITY, 5, "",
                  ", \"solves\": {\"thickness\": {\"type\": \"marginal_height\", \"value\": 0}}");
    expect_error(sys, SG_ENONPHYS, "surface 2: thickness: the marginal_height solve has no "
                 "solution");
    sg_system_free(sys);
    /* A thickness picked up from the object at infinity. */
    sys = singlet("\"inf\"", 40, 100, 5, "",
                  ", \"solves\": {\"thickness\": {\"type\": \"pickup\", \"from\": 0}}");
    expect_error(sys, SG_ENONPHYS, "surface 2: thickness: the pickup from surface 0 is not "
                 "finite");
    sg_system_free(sys);
    /* An F/# of 0. */
    sys = singlet("\"inf\"", 40, 100, 5, "",
                  ", \"solves\": {\"radius\": {\"type\": \"fnum\", \"value\": 0}}");
    expect_error(sys, SG_ERANGE, "surface 2: radius: the fnum solve's value 0");
    sg_system_free(sys);
}

static void test_json_kinds(void **state)
{
    char text[1024];
    sg_system *sys = sg_system_new();
    sg_diag d;
    (void)state;
    /* A marginal_height on the radius is refused with its place. */
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 3, \"title\": \"t\", \"units\": "
             "\"mm\", \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5876}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"x\": 0, \"y\": 0}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 10}, \"surfaces\": ["
             "{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": 50, \"thickness\": 5, \"stop\": true, \"solves\": {\"radius\": "
             "{\"type\": \"marginal_height\", \"value\": 0}}},"
             "{\"radius\": \"inf\", \"thickness\": 0}]}");
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(sys, text, strlen(text), "k", &d), SG_EPARSE);
    assert_non_null(strstr(d.msg, "surface 1: solves: radius"));
    sg_system_free(sys);
}

static void test_json_roundtrip(void **state)
{
    sg_system *a = singlet("\"inf\"", 40, 100, 5, ", \"conic\": -0.5",
                           ", \"solves\": {\"radius\": {\"type\": \"fnum\", \"value\": 3.5}, "
                           "\"thickness\": {\"type\": \"marginal_height\", \"value\": 0.125}, "
                           "\"conic\": {\"type\": \"pickup\", \"from\": 1, \"scale\": 0.5, "
                           "\"offset\": 0.1}}");
    sg_system *b = sg_system_new();
    char *t1, *t2;
    sg_diag d;
    const char *const ex[] = {"singlet.json", "cooke_triplet.json", "double_gauss.json",
                              "cassegrain.json", "tma.json"};
    int i;
    (void)state;
    apply(a);
    t1 = sg_design_to_json(a);
    assert_non_null(t1);
    assert_non_null(strstr(t1, "\"solves\": { \"radius\": {\"type\": \"fnum\""));
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(b, t1, strlen(t1), "rt", &d), SG_OK);
    assert_true(sg_system_equal(a, b));
    t2 = sg_design_to_json(b);
    assert_string_equal(t1, t2);
    free(t1);
    free(t2);
    sg_system_free(a);
    sg_system_free(b);
    /* The examples hold no solves and write as they did: no "solves". */
    for (i = 0; i < 5; i++) {
        sg_system *e = tu_example(ex[i]);
        t1 = sg_design_to_json(e);
        assert_null(strstr(t1, "solves"));
        free(t1);
        sg_system_free(e);
    }
}

/* The radius pickup of scale -1 comes back from a .zmx as Zemax's
 * curvature pickup of scale 1/-1, which gives the same bits once applied;
 * otherwise b is a. */
static void same_after_reimport(sg_system *a, sg_system *b)
{
    assert_int_equal(b->surf[2].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_CURV_PICKUP);
    assert_true(b->surf[2].solve[SG_SOLVE_RADIUS].scale == -1.0 &&
                b->surf[2].solve[SG_SOLVE_RADIUS].from == 1);
    b->surf[2].radius = 7.0;
    apply(b);
    b->surf[2].solve[SG_SOLVE_RADIUS] = a->surf[2].solve[SG_SOLVE_RADIUS];
    assert_true(sg_system_equal(a, b));
}

static void test_zmx_roundtrip(void **state)
{
    sg_system *a = singlet("\"inf\"", 40, 100, 5, "",
                           ", \"solves\": {\"radius\": {\"type\": \"pickup\", \"from\": 1, "
                           "\"scale\": -1}, \"thickness\": {\"type\": \"marginal_height\", "
                           "\"value\": 0}}");
    sg_system *b = sg_system_new();
    char *z;
    sg_diag d;
    (void)state;
    a->surf[2].solve[SG_SOLVE_RADIUS].offset = 0.0;
    apply(a);
    sg_diag_clear(&d);
    z = sg_zmx_to_text(a, NULL, &d);
    assert_non_null(z);
    assert_non_null(strstr(z, " 4 1 -1 0 \"\"\n"));
    assert_non_null(strstr(z, "  MAZH 0 0\n"));
    sg_diag_clear(&d);
    assert_int_equal(sg_zmx_parse(b, z, strlen(z), "rt.zmx", NULL, &d), SG_OK);
    same_after_reimport(a, b);
    free(z);
    /* A thickness pickup comes back as a PZUP line. */
    a->surf[2].solve[SG_SOLVE_THICKNESS].kind = SG_SOLVE_PICKUP;
    a->surf[2].solve[SG_SOLVE_THICKNESS].from = 1;
    a->surf[2].solve[SG_SOLVE_THICKNESS].scale = 3;
    a->surf[2].solve[SG_SOLVE_THICKNESS].offset = 0.5;
    apply(a);
    assert_true(a->surf[2].thickness == 15.5);
    z = sg_zmx_to_text(a, NULL, &d);
    assert_non_null(strstr(z, "  PZUP 1 3 0.5 0\n"));
    sg_diag_clear(&d);
    assert_int_equal(sg_zmx_parse(b, z, strlen(z), "rt.zmx", NULL, &d), SG_OK);
    same_after_reimport(a, b);
    free(z);
    sg_system_free(a);
    sg_system_free(b);
}

/* Zemax's own MAZH solve: zmax_55278.zmx line 84 "MAZH 0 0" on surface 6,
 * whose DISZ (line 83) Zemax solved: 43.707716717029655. */
static void test_zemax_mazh(void **state)
{
    char path[1024];
    sg_system *sys = sg_system_new();
    sg_catalog *cat = tu_catalog();
    sg_diag d;
    double stored = strtod("43.707716717029655", NULL);
    int rc;
    (void)state;
    sg_diag_clear(&d);
    rc = sg_zmx_load(sys, tu_path("tests/data/zmx/zmax_55278.zmx", path, sizeof path), cat, &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_equal(sys->surf[6].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_MARGINAL_HEIGHT);
    assert_true(sys->surf[6].solve[SG_SOLVE_THICKNESS].value == 0.0);
    assert_true(sys->surf[6].thickness == stored);
    sys->surf[6].thickness = 1.0;
    sg_diag_clear(&d);
    assert_int_equal(sg_system_apply_solves(sys, cat, &d), SG_OK);
    printf("# MAZH: solved %.17g, stored %.17g, relative %.3g\n", sys->surf[6].thickness, stored,
           fabs(sys->surf[6].thickness - stored) / stored);
    assert_true(fabs(sys->surf[6].thickness - stored) <= 1e-12 * stored);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Zemax's pickups in US00583336-2-scaled.zmx: PZUP (lines 136, 147, 159,
 * 170, 182) and CURV ... 4 FROM -1 (lines 141, 153, 165, 176, 188) on
 * surfaces 7 to 12 of a symmetric lens, and MAZH at pupil zone 0.7 (line
 * 193, a real ray: frozen).  Its glasses N-BAK1 and N-BALF4 are in
 * lensdb/SCHOTT.agf.  Evaluated, the pickups give back the thicknesses and
 * curvatures Zemax stored. */
static void test_zemax_pickups(void **state)
{
    char path[1024];
    FILE *f;
    char *text;
    long len;
    sg_system *sys = sg_system_new(), *copy = sg_system_new();
    sg_catalog *cat = tu_catalog();
    sg_diag d;
    int rc, i, frozen = 0;
    (void)state;
    f = fopen(tu_path("tests/data/zmx/US00583336-2-scaled.zmx", path, sizeof path), "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    len = ftell(f);
    rewind(f);
    text = malloc((size_t)len + 1);
    assert_non_null(text);
    assert_int_equal(fread(text, 1, (size_t)len, f), (size_t)len);
    text[len] = '\0';
    fclose(f);
    sg_diag_clear(&d);
    rc = sg_zmx_parse(sys, text, (size_t)len, "US00583336-2-scaled.zmx", cat, &d);
    free(text);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
    for (i = 0; i < d.nwarn && i < SG_DIAG_MAXWARN; i++)
        if (strstr(d.warn[i], ":193: surface 12: MAZH") && strstr(d.warn[i], "frozen"))
            frozen = 1;
    assert_true(frozen);
    assert_int_equal(sys->surf[12].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_NONE);
    for (i = 7; i <= 11; i++) {
        assert_int_equal(sys->surf[i].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_PICKUP);
        assert_int_equal(sys->surf[i].solve[SG_SOLVE_THICKNESS].from, 13 - i);
    }
    for (i = 8; i <= 12; i++) {
        assert_int_equal(sys->surf[i].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_CURV_PICKUP);
        assert_int_equal(sys->surf[i].solve[SG_SOLVE_RADIUS].from, 14 - i);
        assert_true(sys->surf[i].solve[SG_SOLVE_RADIUS].scale == -1.0);
    }
    assert_int_equal(sg_system_assign(copy, sys), SG_OK);
    for (i = 7; i <= 12; i++) {
        sys->surf[i].thickness = 99.0;
        sys->surf[i].radius = 99.0;
    }
    sys->surf[7].radius = INFINITY; /* surface 7 holds no radius pickup */
    sg_diag_clear(&d);
    assert_int_equal(sg_system_apply_solves(sys, cat, &d), SG_OK);
    sys->surf[12].thickness = copy->surf[12].thickness; /* frozen */
    for (i = 7; i <= 12; i++) {
        assert_true(sys->surf[i].radius == copy->surf[i].radius);
        assert_true(sys->surf[i].thickness == copy->surf[i].thickness);
    }
    sg_system_free(sys);
    sg_system_free(copy);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_marginal_height_focus),
        cmocka_unit_test(test_marginal_height_value),
        cmocka_unit_test(test_fnum_and_angle),
        cmocka_unit_test(test_pupil_iteration),
        cmocka_unit_test(test_chief_height),
        cmocka_unit_test(test_pickups),
        cmocka_unit_test(test_position),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_json_kinds),
        cmocka_unit_test(test_json_roundtrip),
        cmocka_unit_test(test_zmx_roundtrip),
        cmocka_unit_test(test_zemax_mazh),
        cmocka_unit_test(test_zemax_pickups),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
