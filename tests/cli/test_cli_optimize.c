/*
 * test_cli_optimize.c - "sagitta merit" and "sagitta optimize" as a user
 * runs them: every row in text, CSV and JSON (a plano-convex lens of index
 * 1.5 and radius R has EFL R / (n - 1), the closed form), the optimized
 * design written to -o (R = 50 for EFL 100) while the input keeps its
 * bytes, one line per cycle, and the refusals: an existing output without
 * --force, the input as output, no variables, no merit function.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "clitest.h"

static const char *lens(const char *name, const char *solves, const char *merit)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
             "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": 60, \"thickness\": 4, \"material\": 1.5, \"stop\": true%s},"
             "{\"radius\": \"inf\", \"thickness\": 95},"
             "{\"radius\": \"inf\", \"thickness\": 0}]%s}",
             solves, merit);
    return ct_file(name, text);
}

#define VAR ", \"solves\": {\"radius\": {\"type\": \"variable\"}}"
#define MERIT                                                                                  \
    ", \"merit\": {\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 100, "         \
    "\"weight\": 2}, {\"type\": \"CTVA\", \"surf\": 1, \"target\": 4, \"weight\": 1}]}"

static void merit_formats(void **state)
{
    const char *d = lens("m.json", VAR, MERIT);
    ct_result r;
    cJSON *root, *ops, *row;
    (void)state;
    ct_run(&r, "merit", d, "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    /* EFL 120 against 100 with weight 2, CTVA on target: MF^2 = 2 * 400 / 3. */
    ct_close(cJSON_GetObjectItem(root, "merit")->valuedouble, sqrt(800.0 / 3.0), 1e-14, 0,
             "merit");
    ops = cJSON_GetObjectItem(root, "operands");
    assert_int_equal(cJSON_GetArraySize(ops), 2);
    row = cJSON_GetArrayItem(ops, 0);
    assert_string_equal(cJSON_GetObjectItem(row, "type")->valuestring, "EFFL");
    assert_int_equal(cJSON_GetObjectItem(row, "row")->valueint, 1);
    ct_close(cJSON_GetObjectItem(row, "value")->valuedouble, 120, 1e-14, 0, "EFFL");
    ct_close(cJSON_GetObjectItem(row, "contribution")->valuedouble, 100, 1e-14, 0, "contrib");
    assert_true(cJSON_GetObjectItem(row, "weight")->valuedouble == 2);
    cJSON_Delete(root);
    ct_free(&r);
    ct_run(&r, "merit", d, "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    ct_close(ct_csv_num(r.out, 0, "value"), 120, 1e-14, 0, "csv EFFL");
    ct_close(ct_csv_num(r.out, 1, "value"), 4, 0, 0, "csv CTVA");
    ct_free(&r);
    ct_run(&r, "merit", d, NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "EFFL"));
    assert_non_null(strstr(r.out, "Merit function: 16.32993161855"));
    ct_free(&r);
}

static void optimize_writes_output(void **state)
{
    const char *d = lens("o.json", VAR, MERIT), *out = ct_path("o_out.json");
    char *before = ct_read(d), *after, *res;
    ct_result r;
    cJSON *root, *s1;
    (void)state;
    ct_run(&r, "optimize", d, "-o", out, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    assert_non_null(strstr(r.out, "cycle    1  merit"));
    assert_non_null(strstr(r.out, "Converged"));
    after = ct_read(d);
    assert_string_equal(before, after);
    res = ct_read(out);
    root = cJSON_Parse(res);
    assert_non_null(root);
    s1 = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "surfaces"), 1);
    ct_close(cJSON_GetObjectItem(s1, "radius")->valuedouble, 50, 1e-12, 0, "R");
    assert_non_null(cJSON_GetObjectItem(root, "merit"));
    cJSON_Delete(root);
    ct_free(&r);
    /* The output exists now: refused without --force, written with it. */
    ct_run(&r, "optimize", d, "-o", out, NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--force"));
    ct_free(&r);
    ct_run(&r, "optimize", d, "-o", out, "--force", "--cycles", "2", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "cycle    2"));
    assert_null(strstr(r.out, "cycle    3"));
    ct_free(&r);
    /* Never the input. */
    ct_run(&r, "optimize", d, "-o", d, "--force", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "input"));
    ct_free(&r);
    after = (free(after), ct_read(d));
    assert_string_equal(before, after);
    free(before);
    free(after);
    free(res);
}

static void refusals(void **state)
{
    const char *novar = lens("nv.json", "", MERIT), *nomerit = lens("nm.json", VAR, "");
    ct_result r;
    (void)state;
    ct_run(&r, "optimize", novar, "-o", ct_path("nv_out.json"), NULL);
    assert_int_equal(r.code, 4);
    assert_non_null(strstr(r.err, "no variables"));
    ct_free(&r);
    ct_run(&r, "optimize", nomerit, "-o", ct_path("nm_out.json"), NULL);
    assert_int_equal(r.code, 4);
    assert_non_null(strstr(r.err, "no merit function"));
    ct_free(&r);
    ct_run(&r, "merit", nomerit, NULL);
    assert_int_equal(r.code, 4);
    ct_free(&r);
    ct_run(&r, "optimize", novar, NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(merit_formats),
        cmocka_unit_test(optimize_writes_output),
        cmocka_unit_test(refusals),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
