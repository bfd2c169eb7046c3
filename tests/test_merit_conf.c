/*
 * test_merit_conf.c - Zemax's CONF operand and the default merit function
 * over every configuration (issue 37's optimizer side).
 *
 * A two-lens zoom whose air space is 10 mm in configuration 1 and 30 mm in
 * configuration 2.  The merit function with CONF rows must equal the one
 * computed by hand from separate designs: each block of rows evaluated on
 * its own configuration (a copy with that configuration applied, its
 * solves recomputed, and no configurations left), MF^2 = (sum over blocks
 * of MF_b^2 W_b) / (sum of W_b).  Each EFFL row is also checked against
 * this file's own y-nu trace of that configuration's radii and spaces.
 * The default part over all configurations is checked the same way, and
 * damped least squares on the shared radii brings both positions' EFLs to
 * their targets (by the y-nu trace).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define LENS                                                                               \
    "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","                  \
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"                  \
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 2}]},"               \
    "\"aperture\": {\"type\": \"epd\", \"value\": 8},"                                     \
    "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"                        \
    "{\"radius\": 60, \"thickness\": 4, \"material\": 1.5, \"stop\": true,"                \
    " \"solves\": {\"radius\": {\"type\": \"variable\"}}},"                                \
    "{\"radius\": -120, \"thickness\": 10, \"solves\": {\"radius\": {\"type\": \"variable\"}}}," \
    "{\"radius\": 80, \"thickness\": 3, \"material\": 1.6,"                                \
    " \"solves\": {\"radius\": {\"type\": \"variable\"}}},"                                \
    "{\"radius\": -300, \"thickness\": 40, \"solves\": {\"thickness\": {\"type\": "        \
    "\"marginal_height\", \"value\": 0}}},"                                                \
    "{\"radius\": \"inf\", \"thickness\": 0}],"                                            \
    "\"configurations\": {\"count\": 2, \"operands\": [{\"type\": \"THIC\", \"surface\": 2," \
    " \"values\": [10, 30]}]},"

static sg_system *parse(const char *text)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "t", &d) != SG_OK)
        fail_msg("%s", d.msg);
    sg_diag_clear(&d);
    if (sg_system_apply_solves(sys, NULL, &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

/* Configuration k (0: the design as it is) as a design of its own, with
 * the merit's operands first..last (0-based) and no default part. */
static sg_system *block(const sg_system *sys, int k, int first, int last, int dflt)
{
    sg_system *c = sg_system_clone(sys);
    sg_diag d;
    int i;
    assert_non_null(c);
    sg_diag_clear(&d);
    if (k && sg_config_apply(c, k, &d) != SG_OK)
        fail_msg("%s", d.msg);
    sg_configs_release(c->configs);
    c->configs = NULL;
    if (sg_system_apply_solves(c, NULL, &d) != SG_OK)
        fail_msg("%s", d.msg);
    for (i = first; i <= last; i++)
        c->merit.op[i - first] = sys->merit.op[i];
    c->merit.nop = last >= first ? last - first + 1 : 0;
    c->merit.has_default = dflt;
    return c;
}

/* This file's y-nu trace: the EFL of configuration k's lens (air space
 * 10 or 30) from the radii and indices the design holds. */
static double ynu_efl(const sg_system *sys, double space)
{
    double y = 1, u = 0, n = 1;
    int i;
    for (i = 1; i <= 4; i++) {
        const sg_surface *s = &sys->surf[i];
        double n1 = s->mat.kind == SG_MAT_INDEX ? s->mat.index : 1.0;
        double c = isinf(s->radius) ? 0 : 1 / s->radius;
        u = (n * u - y * c * (n1 - n)) / n1;
        n = n1;
        if (i < 4)
            y += (i == 2 ? space : s->thickness) * u;
    }
    return -1 / u;
}

static void eval(const sg_system *sys, sg_merit_result *r)
{
    sg_diag d;
    sg_diag_clear(&d);
    if (sg_merit_eval(sys, NULL, r, &d) != SG_OK)
        fail_msg("%s", d.msg);
}

static void near(double got, double want, double rtol, const char *what)
{
    if (!(fabs(got - want) <= rtol * fabs(want)))
        fail_msg("%s: %.17g, expected %.17g", what, got, want);
}

/* Rows: TOTR (the design as it is), CONF 2, EFFL, RSCE, CONF 1, EFFL,
 * RSCE, REAY. */
static void conf_rows(void **state)
{
    sg_system *sys = parse(
        LENS "\"merit\": {\"operands\": [{\"type\": \"TOTR\", \"target\": 60, \"weight\": 0.5},"
             "{\"type\": \"CONF\", \"config\": 2},"
             "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 60, \"weight\": 1},"
             "{\"type\": \"RSCE\", \"rings\": 3, \"wave\": 1, \"hy\": 1, \"weight\": 10},"
             "{\"type\": \"CONF\", \"config\": 1},"
             "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 50, \"weight\": 2},"
             "{\"type\": \"RSCE\", \"rings\": 3, \"wave\": 1, \"hy\": 1, \"weight\": 10},"
             "{\"type\": \"REAY\", \"surf\": 5, \"wave\": 1, \"hy\": 1, \"py\": 1, "
             "\"target\": 1, \"weight\": 3}]}}");
    sg_system *b0 = block(sys, 0, 0, 0, 0), *b2 = block(sys, 2, 2, 3, 0),
              *b1 = block(sys, 1, 5, 7, 0);
    sg_merit_result r, r0, r1, r2;
    double s, w;
    (void)state;
    eval(sys, &r);
    eval(b0, &r0);
    eval(b2, &r2);
    eval(b1, &r1);
    assert_int_equal(r.nrow, 8);
    assert_true(r.row[1].type == SG_OP_CONF && r.row[1].value == 2 && r.row[1].weight == 0);
    /* Each row is its configuration's. */
    assert_true(r.row[0].value == r0.row[0].value);
    assert_true(r.row[2].value == r2.row[0].value && r.row[3].value == r2.row[1].value);
    assert_true(r.row[5].value == r1.row[0].value && r.row[6].value == r1.row[1].value &&
                r.row[7].value == r1.row[2].value);
    /* The two positions differ, and EFFL follows the y-nu trace of each. */
    near(r.row[2].value, ynu_efl(sys, 30), 1e-12, "EFFL in configuration 2");
    near(r.row[5].value, ynu_efl(sys, 10), 1e-12, "EFFL in configuration 1");
    /* The sum by hand. */
    s = r0.merit * r0.merit * r0.wsum + r1.merit * r1.merit * r1.wsum +
        r2.merit * r2.merit * r2.wsum;
    w = r0.wsum + r1.wsum + r2.wsum;
    near(r.wsum, w, 1e-15, "sum of weights");
    near(r.merit, sqrt(s / w), 1e-13, "merit");
    /* A configuration that is not there. */
    {
        sg_diag d;
        sys->merit.op[4].i1 = 3;
        sg_diag_clear(&d);
        sg_merit_result_free(&r);
        assert_int_equal(sg_merit_eval(sys, NULL, &r, &d), SG_ERANGE);
        assert_non_null(strstr(d.msg, "operand 5 (CONF): configuration 3 is not 1 to 2"));
    }
    sg_merit_result_free(&r0);
    sg_merit_result_free(&r1);
    sg_merit_result_free(&r2);
    sg_system_free(sys);
    sg_system_free(b0);
    sg_system_free(b1);
    sg_system_free(b2);
}

/* The default part: a CONF row, then configuration k's rows, for each
 * k; with one operand (EFFL, the design as it is) before them. */
static void conf_default(void **state)
{
    sg_system *sys = parse(LENS "\"merit\": {\"default\": {\"criterion\": \"spot\", "
                                "\"reference\": \"centroid\", \"rings\": 3, \"arms\": 6},"
                                "\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, "
                                "\"target\": 50}]}}");
    sg_system *b0 = block(sys, 0, 0, 0, 0), *b1 = block(sys, 1, 0, -1, 1),
              *b2 = block(sys, 2, 0, -1, 1);
    sg_merit_result r, r0, r1, r2;
    int i, nd;
    double s, w;
    (void)state;
    eval(sys, &r);
    eval(b0, &r0);
    eval(b1, &r1);
    eval(b2, &r2);
    nd = r1.nrow;
    assert_int_equal(nd, 2 * 2 * 3 * 6);
    assert_int_equal(r.nrow, 1 + 2 * (1 + nd));
    assert_true(r.row[1].type == SG_OP_CONF && r.row[1].value == 1);
    assert_true(r.row[2 + nd].type == SG_OP_CONF && r.row[2 + nd].value == 2);
    for (i = 0; i < nd; i++) {
        assert_true(r.row[2 + i].value == r1.row[i].value);
        assert_true(r.row[3 + nd + i].value == r2.row[i].value);
    }
    s = r0.merit * r0.merit * r0.wsum + r1.merit * r1.merit * r1.wsum +
        r2.merit * r2.merit * r2.wsum;
    w = r0.wsum + r1.wsum + r2.wsum;
    near(r.merit, sqrt(s / w), 1e-13, "merit");
    sg_merit_result_free(&r);
    sg_merit_result_free(&r0);
    sg_merit_result_free(&r1);
    sg_merit_result_free(&r2);
    sg_system_free(sys);
    sg_system_free(b0);
    sg_system_free(b1);
    sg_system_free(b2);
}

/* The zoom optimized over both positions: the shared radii bring EFL 50
 * at the 10 mm space and 56 at the 30 mm space. */
static void conf_optimize(void **state)
{
    sg_system *sys = parse(
        LENS "\"merit\": {\"operands\": [{\"type\": \"CONF\", \"config\": 1},"
             "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 50, \"weight\": 1},"
             "{\"type\": \"CONF\", \"config\": 2},"
             "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 56, \"weight\": 1}]}}");
    sg_opt_result res;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    if (sg_optimize(sys, NULL, NULL, &res, &d) != SG_OK)
        fail_msg("%s", d.msg);
    near(ynu_efl(sys, 10), 50, 1e-9, "EFL at position 1");
    near(ynu_efl(sys, 30), 56, 1e-9, "EFL at position 2");
    /* The design keeps its own values: only the radii moved. */
    assert_true(sys->surf[2].thickness == 10);
    sg_system_free(sys);
}

/* A .zmx file keeps the CONF rows: the first, right after the last
 * surface, is the merit function's, not the surface keyword CONF. */
static void conf_zmx(void **state)
{
    sg_system *sys = parse(LENS "\"merit\": {\"operands\": [{\"type\": \"CONF\", \"config\": 1},"
                                "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 50},"
                                "{\"type\": \"CONF\", \"config\": 2},"
                                "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 56}]}}");
    sg_system *b = sg_system_new();
    sg_diag d;
    char *z;
    int i;
    (void)state;
    /* MNUM's second number is the current configuration. */
    sys->configs->current = 2;
    sg_diag_clear(&d);
    z = sg_zmx_to_text(sys, NULL, &d);
    assert_non_null(z);
    assert_non_null(strstr(z, "\nCONF 1 "));
    sg_diag_clear(&d);
    if (sg_zmx_parse(b, z, strlen(z), "z.zmx", NULL, &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_equal(b->merit.nop, 4);
    assert_int_equal(b->configs->current, 2);
    for (i = 0; i < 4; i++)
        assert_true(b->merit.op[i].type == sys->merit.op[i].type &&
                    b->merit.op[i].i1 == sys->merit.op[i].i1 &&
                    b->merit.op[i].target == sys->merit.op[i].target);
    free(z);
    sg_system_free(b);
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(conf_rows),
        cmocka_unit_test(conf_default),
        cmocka_unit_test(conf_optimize),
        cmocka_unit_test(conf_zmx),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
