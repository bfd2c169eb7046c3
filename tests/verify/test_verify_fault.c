/*
 * test_verify_fault.c - "sagitta verify" shown designs that must fail.
 *
 * argv[1] is sagitta_faulty: the program built from its own sources with
 * the precise method's trace calls going through tests/verify/fault.c,
 * which moves the precise result by four times its bound (or fails the
 * ray) when $SAGITTA_TEST_FAULT asks.  Without a fault it must pass; with
 * one it must report the violation, name the surface, and exit 6.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vtest.h"

static char design[1024];

/* verify DESIGN --ray 0.3,1,0.2,0.9 --format json under the fault f. */
static void run_design(vt_result *r, const char *f)
{
    if (f)
        setenv("SAGITTA_TEST_FAULT", f, 1);
    else
        unsetenv("SAGITTA_TEST_FAULT");
    vt_run(r, "verify", design, "--ray", "0.3,1,0.2,0.9", "--format", "json", (char *)NULL);
    unsetenv("SAGITTA_TEST_FAULT");
    if (!r->json)
        fail_msg("verify printed no JSON (exit %d): %s", r->code, r->err);
}

static void no_fault_passes(void **state)
{
    vt_result r;
    (void)state;
    run_design(&r, NULL);
    assert_int_equal(r.code, 0);
    assert_int_equal(cJSON_GetArraySize(vt_get(r.json, "bound_violations", NULL)), 0);
    vt_free(&r);
}

/* The fault moves every surface of the Cassegrain (1 to 14): each must be
 * reported once, as a point or a direction. */
static void violation(const char *f, const char *what)
{
    vt_result r;
    const cJSON *a, *e;
    int seen[15] = {0}, i;
    run_design(&r, f);
    print_message("# fault %s: exit %d\n", f, r.code);
    assert_int_equal(r.code, 6);
    a = vt_get(r.json, "bound_violations", NULL);
    assert_int_equal(cJSON_GetArraySize(a), 14);
    cJSON_ArrayForEach(e, a) {
        const cJSON *w = vt_get(e, "what", NULL);
        int s = (int)vt_num(e, "surface", NULL);
        assert_true(s >= 1 && s <= 14);
        seen[s]++;
        assert_true(cJSON_IsString(w));
        assert_string_equal(w->valuestring, what);
        assert_true(vt_num(e, "error", NULL) > vt_num(e, "bound", NULL));
    }
    for (i = 1; i <= 14; i++)
        assert_int_equal(seen[i], 1);
    /* The message on standard error says so too. */
    assert_true(strstr(r.err, "bound") != NULL);
    vt_free(&r);
}

static void point_fault(void **state)
{
    (void)state;
    violation("point", "point");
}

static void dir_fault(void **state)
{
    (void)state;
    violation("dir", "direction");
}

/* A ray the precise method fails while the reference traces it. */
static void fail_fault(void **state)
{
    vt_result r;
    (void)state;
    run_design(&r, "fail");
    print_message("# fault fail: exit %d\n", r.code);
    assert_int_equal(r.code, 6);
    vt_free(&r);
}

/* The experiments trace through sg_trace_start: Table 1 must fail too. */
static void table1_fault(void **state)
{
    vt_result r;
    (void)state;
    vt_run(&r, "verify", "--experiment", "table1", "--format", "json", (char *)NULL);
    assert_int_equal(r.code, 0);
    vt_free(&r);
    setenv("SAGITTA_TEST_FAULT", "point", 1);
    vt_run(&r, "verify", "--experiment", "table1", "--format", "json", (char *)NULL);
    unsetenv("SAGITTA_TEST_FAULT");
    print_message("# table1 with the point fault: exit %d\n", r.code);
    assert_int_equal(r.code, 6);
    vt_free(&r);
}

/* Table 2 likewise: the point fault must make it fail, and say so. */
static void table2_fault(void **state)
{
    vt_result r;
    (void)state;
    vt_run(&r, "verify", "--experiment", "table2", "--count", "200", "--format", "json",
           (char *)NULL);
    assert_int_equal(r.code, 0);
    vt_free(&r);
    setenv("SAGITTA_TEST_FAULT", "point", 1);
    vt_run(&r, "verify", "--experiment", "table2", "--count", "200", (char *)NULL);
    unsetenv("SAGITTA_TEST_FAULT");
    print_message("# table2 with the point fault: exit %d\n", r.code);
    assert_int_equal(r.code, 6);
    assert_non_null(strstr(r.out, "FAIL"));
    vt_free(&r);
}

/* The reference itself fails (its aiming, here injected): verify says so,
 * does not blame precise, and exits 6 with the run marked incomplete. */
static void reference_failure_named(void **state)
{
    char path[512];
    vt_result r, j;
    (void)state;
    vt_source("examples/cassegrain.json", path, sizeof path);
    setenv("SAGITTA_TEST_FAULT", "reffail", 1);
    vt_run(&j, "verify", path, "--ray", "0,1,0,1", "--format", "json", (char *)NULL);
    vt_run(&r, "verify", path, "--ray", "0,1,0,1", (char *)NULL);
    unsetenv("SAGITTA_TEST_FAULT");
    assert_non_null(j.json);
    assert_true(vt_num(j.json, "rays", "reference_failed", NULL) == 1);
    assert_int_equal(j.code, 6);
    assert_true(vt_num(j.json, "rays", "disagreements_precise", NULL) == 0);
    assert_true(cJSON_IsFalse(vt_get(j.json, "complete", NULL)));
    assert_int_equal(r.code, 6);
    assert_non_null(strstr(r.out, "result: INCOMPLETE"));
    assert_non_null(strstr(r.out, "reference's failure, not precise's"));
    assert_null(strstr(r.out, "precise disagrees"));
    assert_non_null(strstr(r.err, "no fault of precise"));
    print_message("# mpfr AIM FAILED (injected): reported as the reference's failure\n");
    vt_free(&r);
    vt_free(&j);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(no_fault_passes),
        cmocka_unit_test(point_fault),
        cmocka_unit_test(dir_fault),
        cmocka_unit_test(fail_fault),
        cmocka_unit_test(table1_fault),
        cmocka_unit_test(table2_fault),
        cmocka_unit_test(reference_failure_named),
    };
    int rc;
    vt_init(argc, argv);
    vt_source("examples/cassegrain.json", design, sizeof design);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    vt_cleanup();
    return rc;
}
