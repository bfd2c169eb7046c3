/* test_cli_paraxial.c - "sagitta paraxial" on thick singlets in air, against
 * the thick-lens formulas, evaluated here in long double:
 *   1/f = (n-1) (1/R1 - 1/R2 + (n-1) d / (n R1 R2))
 *   BFL = f (1 - (n-1) d / (n R1))
 * With the stop on surface 1 and the object at infinity, the entrance pupil
 * is surface 1 itself and has the EPD's diameter.
 *
 * The program computes paraxial data in MPFR and prints %.17g, so each
 * value is held to PTOL, about one ulp (the long double formulas and the
 * double inputs differ from the exact values by some 1e-17); measured 0. */
#define PTOL 2.3e-16
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

typedef struct lens {
    long double r1, r2, d, n, t2;
} lens;

static const char *write_lens(const char *name, const lens *L)
{
    char s[1024];
    snprintf(s, sizeof s,
             "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
             "    {\"radius\": %.17g, \"thickness\": %.17g, \"material\": %.17g, \"stop\": true},\n"
             "    {\"radius\": %.17g, \"thickness\": %.17g},\n"
             "    {\"radius\": \"inf\", \"thickness\": 0}",
             (double)L->r1, (double)L->d, (double)L->n, (double)L->r2, (double)L->t2);
    return ct_design(name, s);
}

static long double efl(const lens *L)
{
    long double p = (L->n - 1) * (1 / L->r1 - 1 / L->r2 +
                                  (L->n - 1) * L->d / (L->n * L->r1 * L->r2));
    return 1 / p;
}

static double text_value(const char *out, const char *label)
{
    const char *p = strstr(out, label);
    char *end;
    double v;
    if (!p)
        fail_msg("no \"%s\" line in:\n%s", label, out);
    p = strchr(p, ':');
    assert_non_null(p);
    v = strtod(p + 1, &end);
    if (end == p + 1)
        fail_msg("\"%s\" has no number", label);
    return v;
}

static const lens lenses[] = {
    { 50, -50, 5, 1.5, 45 },   /* equiconvex */
    { 100, -75, 8, 1.7, 80 },  /* biconvex, unequal */
    { 30, 80, 4, 1.62, 40 },   /* meniscus */
};

static void test_efl_text(void **state)
{
    size_t k;
    (void)state;
    for (k = 0; k < sizeof lenses / sizeof lenses[0]; k++) {
        const lens *L = &lenses[k];
        const char *d = write_lens("lens.json", L);
        long double f = efl(L);
        long double bfl = f * (1 - (L->n - 1) * L->d / (L->n * L->r1));
        double e1, e2;
        ct_result r;
        ct_run(&r, "paraxial", d, NULL);
        if (r.code != 0)
            fail_msg("exit %d: %s", r.code, r.err);
        e1 = ct_close(text_value(r.out, "Effective focal length"), (double)f, PTOL, 0,
                      "EFL");
        e2 = ct_close(text_value(r.out, "Back focal length"), (double)bfl, PTOL, 0,
                      "BFL");
        ct_close(text_value(r.out, "Total track"), (double)(L->d + L->t2), 1e-15, 0,
                 "total track");
        assert_null(strstr(r.out, "nan"));
        print_message("# R1=%g R2=%g d=%g n=%g: EFL %.17g (formula %.17Lg, rel %.2g), "
                      "BFL rel %.2g\n", (double)L->r1, (double)L->r2, (double)L->d,
                      (double)L->n, text_value(r.out, "Effective focal length"), f, e1, e2);
        ct_free(&r);
    }
}

/* A marginal_height solve on the last thickness: the CLI applies it when it
 * loads the design, so the total track is d + BFL whatever thickness the
 * file stores; a pickup from a later surface is refused, naming it. */
static void test_solve_on_load(void **state)
{
    const lens *L = &lenses[1];
    long double f = efl(L);
    long double bfl = f * (1 - (L->n - 1) * L->d / (L->n * L->r1));
    char s[1024];
    const char *d;
    ct_result r;
    (void)state;
    snprintf(s, sizeof s,
             "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
             "    {\"radius\": %.17g, \"thickness\": %.17g, \"material\": %.17g, \"stop\": true},\n"
             "    {\"radius\": %.17g, \"thickness\": 1, \"solves\": {\"thickness\": "
             "{\"type\": \"marginal_height\", \"value\": 0}}},\n"
             "    {\"radius\": \"inf\", \"thickness\": 0}",
             (double)L->r1, (double)L->d, (double)L->n, (double)L->r2);
    d = ct_design("solved.json", s);
    ct_run(&r, "paraxial", d, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    ct_close(text_value(r.out, "Total track"), (double)(L->d + bfl), 1e-15, 0, "total track");
    ct_free(&r);
    snprintf(s, sizeof s,
             "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
             "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true, "
             "\"solves\": {\"radius\": {\"type\": \"pickup\", \"from\": 2}}},\n"
             "    {\"radius\": -50, \"thickness\": 40},\n"
             "    {\"radius\": \"inf\", \"thickness\": 0}");
    d = ct_design("badpickup.json", s);
    ct_run(&r, "paraxial", d, NULL);
    assert_int_not_equal(r.code, 0);
    if (!strstr(r.err, "surface 1: radius: the pickup's source surface 2"))
        fail_msg("message: %s", r.err);
    ct_free(&r);
}

static double jnum(const cJSON *o, const char *key)
{
    const cJSON *j = cJSON_GetObjectItem(o, key);
    if (!cJSON_IsNumber(j))
        fail_msg("JSON member \"%s\" is not a number", key);
    return j->valuedouble;
}

static void test_json(void **state)
{
    const lens *L = &lenses[1];
    const char *d = write_lens("lens.json", L);
    long double f = efl(L);
    ct_result r;
    cJSON *root;
    (void)state;
    ct_run(&r, "paraxial", d, "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    if (!root)
        fail_msg("not JSON:\n%s", r.out);
    ct_close(jnum(root, "efl"), (double)f, PTOL, 0, "efl");
    ct_close(jnum(root, "entrance_pupil_diameter"), 10, 1e-15, 0, "epd");
    ct_close(jnum(root, "entrance_pupil_position"), 0, PTOL, 1, "entrance pupil");
    ct_close(jnum(root, "image_fnum"), (double)(f / 10), PTOL, 0, "F/#");
    ct_close(jnum(root, "total_track"), (double)(L->d + L->t2), 1e-15, 0, "track");
    assert_true(jnum(root, "wavelength_um") == 0.55);
    print_message("# JSON: EFL, EPD 10, pupil at surface 1, F/# = EFL/10, track %g\n",
                  (double)(L->d + L->t2));
    cJSON_Delete(root);
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_efl_text),
        cmocka_unit_test(test_json),
        cmocka_unit_test(test_solve_on_load),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
