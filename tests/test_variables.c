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

/* A singlet of model glass whose nd is varied for an EFL of 45: the
 * thick lens' 1/f = (n - 1) (c1 - c2 + (n - 1) t c1 c2 / n), solved for
 * n by bisection here, at the d line, where the model's index is nd. */
static void model_glass_nd(void **state)
{
    const char *text =
        "{\"units\": \"mm\", \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 5},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 50, \"thickness\": 5, \"stop\": true, \"material\": {\"nd\": 1.6, "
        "\"vd\": 50}, \"solves\": {\"material.nd\": {\"type\": \"variable\"}}},"
        "{\"radius\": -50, \"thickness\": 40},"
        "{\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 45}]}}";
    sg_system *sys = parse(text), *b;
    sg_opt_result res;
    sg_paddr v[4];
    double c1 = 1.0 / 50, c2 = -1.0 / 50, t = 5, lo = 1.0, hi = 4.0, n, vlo, vhi;
    char name[96], *out;
    int k;
    (void)state;
    assert_int_equal(sg_variables(sys, v, 4), 1);
    sg_paddr_name(&v[0], name, sizeof name);
    assert_string_equal(name, "surface 1 model glass nd");
    /* No min or max: the model's own limits. */
    assert_true(sg_variable_bounds(sys, &v[0], &vlo, &vhi) && vlo == 1.0 && vhi == 4.0);
    for (k = 0; k < 200; k++) {
        double m = 0.5 * (lo + hi);
        double p = (m - 1) * (c1 - c2 + (m - 1) * t * c1 * c2 / m);
        if (p < 1.0 / 45)
            lo = m;
        else
            hi = m;
    }
    n = 0.5 * (lo + hi);
    out = sg_design_to_json(sys);
    assert_non_null(out);
    b = parse(out);
    assert_true(sg_system_equal(sys, b));
    optimize(sys, &res);
    print_message("# model glass nd varied to EFL 45: %.15g, the thick lens' %.15g\n",
                  sys->surf[1].mat.index, n);
    assert_true(fabs(sys->surf[1].mat.index - n) < 1e-9);
    assert_true(sys->surf[1].mat.vd == 50.0);
    free(out);
    sg_system_free(b);
    sg_system_free(sys);
}

/* A thin achromat in contact, every thickness 0, of two model glasses:
 * the flint's vd varied for zero axial colour between F and C.  The
 * model gives n(F) - n(C) = (nd - 1) / vd exactly, so the powers match
 * at F and C where (nd1 - 1) K1 / V1 + (nd2 - 1) K2 / V2 = 0. */
static void model_glass_vd(void **state)
{
    const char *text =
        "{\"units\": \"mm\", \"wavelengths\": {\"primary\": 2, \"list\": [{\"um\": 0.4861327},"
        " {\"um\": 0.5875618}, {\"um\": 0.6562725}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 5},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 50, \"thickness\": 0, \"stop\": true, \"material\": {\"nd\": 1.5168, "
        "\"vd\": 64.17}},"
        "{\"radius\": -50, \"thickness\": 0, \"material\": {\"nd\": 1.62, \"vd\": 40},"
        " \"solves\": {\"material.vd\": {\"type\": \"variable\", \"min\": 1, \"max\": 300}}},"
        "{\"radius\": -200, \"thickness\": 80},"
        "{\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"AXCL\", \"wave1\": 1, \"wave2\": 3, "
        "\"target\": 0}]}}";
    sg_system *sys = parse(text);
    sg_opt_result res;
    sg_paddr v[4];
    double k1 = 1.0 / 50 + 1.0 / 50, k2 = -1.0 / 50 + 1.0 / 200, lo, hi;
    double want = -(1.62 - 1) * k2 * 64.17 / ((1.5168 - 1) * k1);
    sg_diag d;
    (void)state;
    /* min 1 and max 300 are narrowed to the model's 5 to 200. */
    assert_int_equal(sg_variables(sys, v, 4), 1);
    assert_true(sg_variable_bounds(sys, &v[0], &lo, &hi) && lo == 5.0 && hi == 200.0);
    optimize(sys, &res);
    print_message("# model glass vd varied for no axial colour: %.15g, the thin achromat's "
                  "%.15g\n", sys->surf[2].mat.vd, want);
    assert_true(fabs(sys->surf[2].mat.vd - want) < 1e-7 * want);
    assert_true(sys->surf[2].mat.index == 1.62);
    /* Made a variable through the API, within the model's limits too. */
    sg_diag_clear(&d);
    assert_int_equal(sg_variable_set(sys, 1, "material.nd", 0, 1, 0.5, 9, &d), SG_OK);
    assert_int_equal(sg_variables(sys, v, 4), 2);
    assert_true(sg_variable_bounds(sys, &v[0], &lo, &hi) && lo == 1.0 && hi == 4.0);
    /* On a material that is not a model glass they are refused. */
    sg_diag_clear(&d);
    assert_int_equal(sg_variable_set(sys, 3, "material.nd", 0, 1, -INFINITY, INFINITY, &d),
                     SG_ERANGE);
    assert_non_null(strstr(d.msg, "not a model glass"));
    sys->surf[2].mat.kind = SG_MAT_INDEX;
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(sys, NULL, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "surface 2: its model glass vd is a variable"));
    sg_system_free(sys);
    {
        const char *bad =
            "{\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
            "{\"radius\": 50, \"thickness\": 5, \"stop\": true, \"material\": \"N-BK7\","
            " \"solves\": {\"material.nd\": {\"type\": \"variable\"}}},"
            "{\"radius\": \"inf\", \"thickness\": 0}]}";
        sg_system *x = sg_system_new();
        sg_diag_clear(&d);
        assert_int_not_equal(sg_design_parse(x, bad, strlen(bad), "t", &d), SG_OK);
        assert_non_null(strstr(d.msg, "surface 1: solves: material.nd"));
        assert_non_null(strstr(d.msg, "not a model glass"));
        sg_system_free(x);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(asphere_term),
        cmocka_unit_test(tilt),
        cmocka_unit_test(round_trip),
        cmocka_unit_test(bad),
        cmocka_unit_test(model_glass_nd),
        cmocka_unit_test(model_glass_vd),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
