/*
 * test_verify_errors.c - "sagitta verify" refuses bad command lines with
 * status 2 and a message, and unreadable or untraceable designs with 3 and
 * 4, as sagitta(1) documents.
 */
#include <stdio.h>
#include <string.h>

#include "vtest.h"

static const char good_design[] =
    "{\n"
    "  \"format\": \"sagitta-design\", \"version\": 1,\n"
    "  \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
    "  \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
    "             \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1}]},\n"
    "  \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
    "  \"ray_aiming\": \"off\",\n"
    "  \"surfaces\": [\n"
    "    {\"radius\": \"inf\", \"thickness\": \"inf\", \"material\": \"AIR\"},\n"
    "    {\"radius\": 40, \"thickness\": 50, \"material\": %s, \"stop\": true},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0, \"material\": \"AIR\"}\n"
    "  ]\n"
    "}\n";

/* Runs the arguments and checks the status and that stderr says why. */
static void expect(int code, const char *why, const char *a1, const char *a2,
                   const char *a3, const char *a4)
{
    vt_result r;
    vt_run(&r, "verify", a1, a2, a3, a4, (char *)NULL);
    const char *p, *nl;
    print_message("# verify %s %s %s %s: exit %d (want %d)\n", a1 ? a1 : "",
                  a1 && a2 ? a2 : "", a1 && a2 && a3 ? a3 : "",
                  a1 && a2 && a3 && a4 ? a4 : "", r.code, code);
    /* Each line of the message as a TAP comment. */
    for (p = r.err; *p; p = nl + 1) {
        nl = strchr(p, '\n');
        if (!nl) {
            print_message("#   %s\n", p);
            break;
        }
        print_message("#   %.*s\n", (int)(nl - p), p);
    }
    assert_int_equal(r.code, code);
    assert_true(strncmp(r.err, "sagitta: ", 9) == 0);
    if (why)
        assert_non_null(strstr(r.err, why));
    /* A refused run prints no report. */
    assert_int_equal(strlen(r.out), 0);
    vt_free(&r);
}

static void usage_errors(void **state)
{
    char text[2048];
    const char *design;
    (void)state;
    snprintf(text, sizeof text, good_design, "1.5");
    design = vt_file("good.json", text);
    expect(2, "missing DESIGN.json", NULL, NULL, NULL, NULL);
    expect(2, "--grid", design, "--grid", "0", NULL);
    expect(2, "--grid", design, "--grid", "x", NULL);
    expect(2, "Hx,Hy,Px,Py", design, "--ray", "1,2", NULL);
    expect(2, "Hx,Hy,Px,Py", design, "--ray", "0,0,0,nan", NULL);
    expect(2, "only one of --ray and --grid", design, "--ray", "0,0,0,0", "--grid=3");
    expect(2, "--bits", design, "--bits", "40", NULL);
    expect(2, "--format", design, "--format", "csv", NULL);
    expect(2, "--experiment", "--experiment", "table3", NULL, NULL);
    expect(2, "no design file", "--experiment", "table1", design, NULL);
    expect(2, "table2 only", "--experiment", "table1", "--count", "10");
    expect(2, "table2 only", design, "--seed", "1", NULL);
    expect(2, "--count", "--experiment", "table2", "--count", "0");
    expect(2, "unknown option", design, "--frobnicate", NULL, NULL);
    expect(2, "unexpected argument", design, design, NULL, NULL);
    expect(2, "wavelength", design, "--wave", "2", NULL);
}

static void file_errors(void **state)
{
    char text[2048];
    (void)state;
    expect(3, "no-such-design.json", "no-such-design.json", NULL, NULL, NULL);
    expect(3, "broken.json", vt_file("broken.json", "{ \"format\": "), NULL, NULL, NULL);
    /* A glass no catalog holds: read, but not traceable. */
    snprintf(text, sizeof text, good_design, "\"NO-SUCH-GLASS\"");
    expect(4, "NO-SUCH-GLASS", vt_file("noglass.json", text), NULL, NULL, NULL);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(usage_errors),
        cmocka_unit_test(file_errors),
    };
    int rc;
    vt_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    vt_cleanup();
    return rc;
}
