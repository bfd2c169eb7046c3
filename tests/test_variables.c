/*
 * test_variables.c - variables on any real parameter of the surface table
 * (sagitta-design(5), SOLVES): an even asphere's r^4 term optimized on a
 * spherical mirror toward the paraboloid's -c^3 / 8 (the sphere's sag
 * c r^2 / 2 + c^3 r^4 / 8 + ..., the paraboloid's c r^2 / 2), a
 * coordinate break's tilt optimized so the axial ray lands 5 mm off the
 * axis 100 mm on (tan t = 5 / 100), the JSON round trip, and the errors
 * that name the surface and key.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define PI 3.14159265358979323846

static sg_system *parse(const char *text)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "t", &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

static void optimize(sg_system *sys, sg_opt_result *res)
{
    sg_opt_opts o;
    sg_diag d;
    sg_opt_opts_init(&o);
    sg_diag_clear(&d);
    if (sg_optimize(sys, NULL, &o, res, &d) != SG_OK)
        fail_msg("%s", d.msg);
}

static const char asph_mirror[] =
    "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
    "\"aperture\": {\"type\": \"epd\", \"value\": 40},"
    "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
    "{\"type\": \"even_asphere\", \"radius\": -1000, \"thickness\": -500, \"material\": "
    "\"MIRROR\", \"stop\": true, \"asphere\": [0, 0, 0],"
    " \"solves\": {\"asphere\": %s}},"
    "{\"radius\": \"inf\", \"thickness\": 0}],"
    "\"merit\": {\"operands\": [{\"type\": \"RSCE\", \"rings\": 4, \"wave\": 1}]}}";

/* The r^4 term of a spherical mirror's even asphere, varied toward the
 * paraboloid: the optimum A4 is -c^3 / 8 to a part in (h / R)^2 (the
 * r^6 term it cannot match, 4e-4 here). */
static void asphere_term(void **state)
{
    char text[4096];
    sg_system *sys;
    sg_opt_result res;
    double c = -1.0 / 1000, want = -c * c * c / 8;
    (void)state;
    snprintf(text, sizeof text, asph_mirror, "{\"type\": \"variable\", \"element\": 1}");
    sys = parse(text);
    assert_int_equal(sys->surf[1].nvar, 1);
    optimize(sys, &res);
    assert_true(res.merit < 1e-3 * res.merit0);
    if (!(fabs(sys->surf[1].asph[1] - want) <= 2e-3 * fabs(want)))
        fail_msg("A4 %.17g, expected %.17g", sys->surf[1].asph[1], want);
    /* Only the variable moved. */
    assert_true(sys->surf[1].asph[0] == 0.0 && sys->surf[1].asph[2] == 0.0);
    assert_true(sys->surf[1].radius == -1000.0);
    sg_system_free(sys);
}

/* A coordinate break's tilt about x, varied so the axial ray meets the
 * image 100 mm on at y = 5: |tan t| = 0.05, exactly (a flat system). */
static void tilt(void **state)
{
    const char *text =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 4},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": \"inf\", \"thickness\": 10, \"stop\": true},"
        "{\"type\": \"coordinate_break\", \"thickness\": 100, \"break\": {\"tilt\": [1, 0, 0]},"
        " \"solves\": {\"before.tx\": {\"type\": \"variable\", \"min\": -20, \"max\": 20}}},"
        "{\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"REAY\", \"surf\": 3, \"wave\": 1, "
        "\"target\": 5}]}}";
    sg_system *sys = parse(text);
    sg_opt_result res;
    sg_paddr v[4];
    char name[96];
    (void)state;
    assert_int_equal(sg_variables(sys, v, 4), 1);
    sg_paddr_name(&v[0], name, sizeof name);
    assert_string_equal(name, "surface 2 tilt about x");
    optimize(sys, &res);
    if (!(fabs(fabs(tan(sys->surf[2].before.tx * PI / 180)) - 0.05) <= 1e-12))
        fail_msg("tilt %.17g degrees, expected +-%.17g", sys->surf[2].before.tx,
                 atan(0.05) * 180 / PI);
    sg_system_free(sys);
}

/* The JSON round trip keeps the variables, an array where one key has
 * several; sg_variable_set adds and clears them. */
static void round_trip(void **state)
{
    char text[4096];
    sg_system *a, *b;
    char *out;
    sg_paddr v[8];
    double lo, hi;
    sg_diag d;
    (void)state;
    snprintf(text, sizeof text, asph_mirror,
             "[{\"type\": \"variable\", \"element\": 1, \"min\": -1, \"max\": 1},"
             " {\"type\": \"variable\", \"element\": 2}]");
    a = parse(text);
    assert_int_equal(a->surf[1].nvar, 2);
    out = sg_design_to_json(a);
    assert_non_null(out);
    b = parse(out);
    assert_true(sg_system_equal(a, b));
    assert_int_equal(sg_variables(b, v, 8), 2);
    assert_int_equal(v[1].elem, 2);
    assert_true(sg_variable_bounds(b, &v[0], &lo, &hi) && lo == -1 && hi == 1);
    /* Clearing one, then a conic through its solve. */
    sg_diag_clear(&d);
    assert_int_equal(sg_variable_set(b, 1, "asphere", 1, 0, 0, 0, &d), SG_OK);
    assert_int_equal(b->surf[1].nvar, 1);
    assert_false(sg_system_equal(a, b));
    assert_int_equal(sg_variable_set(b, 1, "conic", 0, 1, -2, 0, &d), SG_OK);
    assert_int_equal(b->surf[1].solve[SG_SOLVE_CONIC].kind, SG_SOLVE_VARIABLE);
    assert_int_equal(sg_variables(b, v, 8), 2);
    /* Errors name the parameter. */
    assert_int_equal(sg_variable_set(b, 1, "asphere", 9, 1, -1, 1, &d), SG_ERANGE);
    sg_diag_clear(&d);
    assert_int_equal(sg_variable_set(b, 1, "asphere", 1, 0, 0, 0, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "not a variable"));
    sg_diag_clear(&d);
    assert_int_equal(sg_variable_set(b, 2, "asphere", 1, 1, -1, 1, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "does not use"));
    assert_int_equal(sg_variable_set(b, 1, "material", 0, 1, -1, 1, &d), SG_ERANGE);
    free(out);
    sg_system_free(a);
    sg_system_free(b);
}

/* Bad variables in a design are refused naming the surface and key. */
static void bad(void **state)
{
    static const struct { const char *solves, *want; } t[] = {
        {"{\"type\": \"pickup\", \"from\": 1}", "only a \"variable\""},
        {"{\"type\": \"variable\", \"element\": 9}", "element"},
        {"{\"type\": \"variable\", \"element\": 1, \"min\": 2, \"max\": 1}", "min"},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof t / sizeof t[0]; i++) {
        char text[4096];
        sg_system *sys = sg_system_new();
        sg_diag d;
        snprintf(text, sizeof text, asph_mirror, t[i].solves);
        sg_diag_clear(&d);
        assert_int_not_equal(sg_design_parse(sys, text, strlen(text), "t", &d), SG_OK);
        if (!strstr(d.msg, t[i].want) || !strstr(d.msg, "surface 1: solves: asphere"))
            fail_msg("case %zu: %s", i, d.msg);
        sg_system_free(sys);
    }
    {
        /* A standard surface has no asphere terms. */
        const char *text =
            "{\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
            "{\"radius\": 50, \"thickness\": 5, \"stop\": true, \"solves\": {\"asphere\": "
            "{\"type\": \"variable\", \"element\": 1}}},"
            "{\"radius\": \"inf\", \"thickness\": 0}]}";
        sg_system *sys = sg_system_new();
        sg_diag d;
        sg_diag_clear(&d);
        assert_int_not_equal(sg_design_parse(sys, text, strlen(text), "t", &d), SG_OK);
        assert_non_null(strstr(d.msg, "standard surface does not use"));
        sg_system_free(sys);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(asphere_term),
        cmocka_unit_test(tilt),
        cmocka_unit_test(round_trip),
        cmocka_unit_test(bad),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
