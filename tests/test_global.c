/*
 * test_global.c - the global search (multi-start damped least squares
 * from a Halton set, sg_opt_opts.global_seconds) on a merit of two local
 * minima: MF^2 proportional to ((x - 5)^2 - 4)^2 + 0.01 (x - 8)^2 in a
 * thickness x, built from CTVA, CONS, DIFF and PROD rows.  From x = 2 the
 * local method stops in the well near 3; the global one must find the
 * deeper well near 7, where the derivative 4 ((x-5)^2 - 4)(x-5) +
 * 0.02 (x-8) vanishes (found here by bisection), and give the same bits
 * for the same seed and count of starts.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const char design[] =
    "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
    "\"aperture\": {\"type\": \"epd\", \"value\": 4},"
    "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
    "{\"radius\": 50, \"thickness\": 2, \"material\": 1.5, \"stop\": true,"
    " \"solves\": {\"thickness\": {\"type\": \"variable\", \"min\": 0.5, \"max\": 10}}},"
    "{\"radius\": \"inf\", \"thickness\": 90},"
    "{\"radius\": \"inf\", \"thickness\": 0}],"
    "\"merit\": {\"operands\": ["
    "{\"type\": \"CTVA\", \"surf\": 1, \"weight\": 0},"
    "{\"type\": \"CONS\", \"target\": 5, \"weight\": 0},"
    "{\"type\": \"DIFF\", \"op1\": 1, \"op2\": 2, \"weight\": 0},"
    "{\"type\": \"PROD\", \"op1\": 3, \"op2\": 3, \"weight\": 0},"
    "{\"type\": \"CONS\", \"target\": 4, \"weight\": 0},"
    "{\"type\": \"DIFF\", \"op1\": 4, \"op2\": 5, \"target\": 0, \"weight\": 1},"
    "{\"type\": \"CTVA\", \"surf\": 1, \"target\": 8, \"weight\": 0.01}]}}";

static sg_system *parse(void)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    sg_diag_clear(&d);
    if (sg_design_parse(sys, design, strlen(design), "t", &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

static double dfdx(double x)
{
    return 4 * ((x - 5) * (x - 5) - 4) * (x - 5) + 0.02 * (x - 8);
}

static void two_wells(void **state)
{
    sg_system *loc = parse(), *g1 = parse(), *g2 = parse();
    sg_opt_opts o;
    sg_opt_result r;
    sg_diag d;
    double a = 6.5, b = 7.5, xs;
    int i;
    (void)state;
    /* The deeper well's minimum, by bisection on the derivative. */
    for (i = 0; i < 200; i++) {
        double m = 0.5 * (a + b);
        if ((dfdx(a) < 0) == (dfdx(m) < 0))
            a = m;
        else
            b = m;
    }
    xs = 0.5 * (a + b);
    sg_opt_opts_init(&o);
    sg_diag_clear(&d);
    if (sg_optimize(loc, NULL, &o, &r, &d) != SG_OK)
        fail_msg("%s", d.msg);
    /* The local method stays in the shallow well near 3. */
    assert_true(fabs(loc->surf[1].thickness - 3) < 0.1);
    o.global_seconds = 60;
    o.global_starts = 12;
    o.seed = 7;
    if (sg_optimize(g1, NULL, &o, &r, &d) != SG_OK)
        fail_msg("%s", d.msg);
    if (!(fabs(g1->surf[1].thickness - xs) <= 1e-6))
        fail_msg("global: x %.17g, expected %.17g", g1->surf[1].thickness, xs);
    if (sg_optimize(g2, NULL, &o, &r, &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_true(sg_system_equal(g1, g2));
    sg_system_free(loc);
    sg_system_free(g1);
    sg_system_free(g2);
}

/* A variable without both bounds cannot be searched globally. */
static void needs_bounds(void **state)
{
    sg_system *sys = parse();
    sg_opt_opts o;
    sg_opt_result r;
    sg_diag d;
    (void)state;
    sys->surf[1].solve[SG_SOLVE_THICKNESS].hi = INFINITY;
    sg_opt_opts_init(&o);
    o.global_seconds = 1;
    sg_diag_clear(&d);
    assert_int_equal(sg_optimize(sys, NULL, &o, &r, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "surface 1 thickness"));
    assert_non_null(strstr(d.msg, "min and max"));
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(two_wells),
        cmocka_unit_test(needs_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
