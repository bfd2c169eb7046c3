/*
 * test_verify_design.c - "sagitta verify" on designs: a single sphere whose
 * intersection the test computes itself, and the bundled Cassegrain and
 * off-axis TMA.
 *
 * Expectations come from outside the program: the closed-form line-sphere
 * intersection computed here in MPFR, and the targets (15 or more
 * digits at every surface for the precise method, fewer for the classic).
 */
#include <math.h>
#include <mpfr.h>
#include <stdio.h>
#include <string.h>

#include "vtest.h"

/* One sphere, R = 40, in index 1.5 with its stop on it; EPD 20, aiming
 * off, so the ray (0, 0, 0, 1) runs parallel to the axis at y = 10. */
static const char sphere_design[] =
    "{\n"
    "  \"format\": \"sagitta-design\", \"version\": 1,\n"
    "  \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
    "  \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
    "             \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1},\n"
    "                      {\"x\": 0, \"y\": 10, \"weight\": 1}]},\n"
    "  \"aperture\": {\"type\": \"epd\", \"value\": 20},\n"
    "  \"ray_aiming\": \"off\",\n"
    "  \"surfaces\": [\n"
    "    {\"radius\": \"inf\", \"thickness\": \"inf\", \"material\": \"AIR\"},\n"
    "    {\"radius\": 40, \"thickness\": 50, \"material\": 1.5, \"stop\": true},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0, \"material\": \"AIR\"}\n"
    "  ]\n"
    "}\n";

static double ulp_of(double x)
{
    x = fabs(x);
    return x == 0.0 ? nextafter(0.0, 1.0) : nextafter(x, INFINITY) - x;
}

/* Every surface: precise digits at least min_digits; returns the least
 * precise and the least classic digits seen, and how many surfaces have
 * classic below precise. */
static int check_surfaces(const cJSON *root, double min_digits, double *pmin,
                          double *cmin)
{
    const cJSON *surfs = vt_get(root, "surfaces", NULL), *s;
    int lower = 0, n = 0;
    *pmin = *cmin = INFINITY;
    assert_true(cJSON_IsArray(surfs));
    cJSON_ArrayForEach(s, surfs) {
        double p = vt_num(s, "precise", "digits_min", NULL);
        double c = vt_num(s, "classic", "digits_min", NULL);
        double pd = vt_num(s, "precise", "dir_digits_min", NULL);
        print_message("#   surface %2d: precise min %.2f (dir %.2f), classic min %.2f\n",
                      (int)vt_num(s, "surface", NULL), p, pd, c);
        assert_true(p >= min_digits);
        assert_true(pd >= min_digits);
        if (c < p)
            lower++;
        *pmin = fmin(*pmin, p);
        *cmin = fmin(*cmin, c);
        n++;
    }
    assert_true(n > 0);
    return lower;
}

/* The closed-form path of the ray (0, 0, 0, 1): parallel to the axis at
 * y = 10, it meets the sphere at z1 = 40 - sqrt(1500), refracts by Snell's
 * law in vector form (mu = 1/1.5) and crosses the image plane at z = 50.
 * y[1], z[1] on surface 1 and y[2] on the image, in MPFR at 300 bits. */
static void sphere_truth(double y[3], double z[3])
{
    mpfr_t z1, ny, nz, c, mu, k, dy, dz, t, u;
    mpfr_inits2(300, z1, ny, nz, c, mu, k, dy, dz, t, u, (mpfr_ptr)0);
    mpfr_sqrt_ui(c, 1500, MPFR_RNDN);
    mpfr_ui_sub(z1, 40, c, MPFR_RNDN);
    /* Unit normal from the centre (0, 0, 40), toward the incoming light. */
    mpfr_set_d(ny, 0.25, MPFR_RNDN);
    mpfr_div_ui(nz, c, 40, MPFR_RNDN);
    mpfr_neg(nz, nz, MPFR_RNDN);
    mpfr_div_ui(c, c, 40, MPFR_RNDN); /* cos I = -N . (0, 0, 1) */
    mpfr_set_ui(mu, 2, MPFR_RNDN);
    mpfr_div_ui(mu, mu, 3, MPFR_RNDN);
    /* k = 1 - mu^2 (1 - cos^2 I) */
    mpfr_sqr(k, c, MPFR_RNDN);
    mpfr_ui_sub(k, 1, k, MPFR_RNDN);
    mpfr_sqr(u, mu, MPFR_RNDN);
    mpfr_mul(k, k, u, MPFR_RNDN);
    mpfr_ui_sub(k, 1, k, MPFR_RNDN);
    mpfr_sqrt(k, k, MPFR_RNDN);
    /* g = mu cos I - sqrt(k); d' = mu (0, 0, 1) + g N */
    mpfr_mul(t, mu, c, MPFR_RNDN);
    mpfr_sub(t, t, k, MPFR_RNDN);
    mpfr_mul(dy, t, ny, MPFR_RNDN);
    mpfr_mul(dz, t, nz, MPFR_RNDN);
    mpfr_add(dz, dz, mu, MPFR_RNDN);
    /* y on the image: 10 + (50 - z1) dy / dz */
    mpfr_ui_sub(t, 50, z1, MPFR_RNDN);
    mpfr_mul(t, t, dy, MPFR_RNDN);
    mpfr_div(t, t, dz, MPFR_RNDN);
    mpfr_add_ui(t, t, 10, MPFR_RNDN);
    y[0] = 0.0;
    z[0] = 0.0;
    y[1] = 10.0;
    z[1] = mpfr_get_d(z1, MPFR_RNDN);
    y[2] = mpfr_get_d(t, MPFR_RNDN);
    z[2] = 0.0;
    mpfr_clears(z1, ny, nz, c, mu, k, dy, dz, t, u, (mpfr_ptr)0);
}

static double vec_item(const cJSON *o, const char *name, int k)
{
    const cJSON *a = vt_get(o, name, NULL);
    assert_true(cJSON_IsArray(a) && cJSON_GetArraySize(a) == 3);
    return vt_num(cJSON_GetArrayItem(a, k), NULL);
}

static void sphere_one_ray(void **state)
{
    const char *path = vt_file("sphere.json", sphere_design);
    static const char *const meth[2] = { "mpfr", "precise" };
    vt_result r;
    const cJSON *pts, *e;
    double ty[3], tz[3], pmin, cmin, worst = 0.0;
    int i, m;
    (void)state;

    sphere_truth(ty, tz);
    vt_run(&r, "verify", path, "--ray", "0,0,0,1", "--format", "json", (char *)NULL);
    print_message("# verify sphere.json --ray 0,0,0,1: exit %d\n", r.code);
    assert_int_equal(r.code, 0);
    assert_non_null(r.json);
    assert_int_equal((int)vt_num(r.json, "rays", "total", NULL), 1);
    assert_int_equal((int)vt_num(r.json, "rays", "compared_precise", NULL), 1);
    check_surfaces(r.json, 15.0, &pmin, &cmin);
    assert_true(cJSON_IsTrue(vt_get(r.json, "pass", NULL)));

    /* The reference and the precise trace both land on the closed form. */
    pts = vt_get(r.json, "points", NULL);
    assert_int_equal(cJSON_GetArraySize(pts), 2);
    for (i = 1; i <= 2; i++) {
        e = cJSON_GetArrayItem(pts, i - 1);
        assert_int_equal((int)vt_num(e, "surface", NULL), i);
        for (m = 0; m < 2; m++) {
            const cJSON *o = vt_get(e, meth[m], NULL);
            double x = vec_item(o, "point", 0), y = vec_item(o, "point", 1);
            double z = vec_item(o, "point", 2);
            double scale = ulp_of(fmax(fabs(ty[i]), fabs(tz[i])));
            double err = fmax(fabs(x), fmax(fabs(y - ty[i]), fabs(z - tz[i]))) / scale;
            print_message("# surface %d %-7s y %.17g z %.17g; closed form y %.17g z %.17g: "
                          "%.2f ulp\n", i, meth[m], y, z, ty[i], tz[i], err);
            worst = fmax(worst, err);
        }
    }
    print_message("# worst %.2f ulp from the closed form\n", worst);
    assert_true(worst <= 1.0);
    vt_free(&r);
}

static void sphere_grid(void **state)
{
    const char *path = vt_file("sphere.json", sphere_design);
    vt_result r;
    double pmin, cmin;
    (void)state;
    vt_run(&r, "verify", path, "--format", "json", (char *)NULL);
    print_message("# verify sphere.json (default grid): exit %d\n", r.code);
    assert_int_equal(r.code, 0);
    assert_non_null(r.json);
    /* Two fields times the 29 points of a 7 x 7 grid inside the unit
     * circle (which already holds the chief and marginal rays). */
    assert_int_equal((int)vt_num(r.json, "rays", "total", NULL), 58);
    assert_int_equal((int)vt_num(r.json, "rays", "failed_in_mpfr", NULL), 0);
    assert_int_equal((int)vt_num(r.json, "rays", "disagreements_precise", NULL), 0);
    check_surfaces(r.json, 15.0, &pmin, &cmin);
    print_message("# precise min %.2f digits, classic min %.2f digits\n", pmin, cmin);
    assert_int_equal(cJSON_GetArraySize(vt_get(r.json, "bound_violations", NULL)), 0);
    assert_true(cJSON_IsTrue(vt_get(r.json, "pass", NULL)));
    vt_free(&r);
}

/* The sphere design with a fixed clear semi-diameter of 8 on the EPD-20
 * stop: by geometry the 8 grid points beyond pupil radius 0.8 (the four
 * marginal points at 1 and the four diagonal ones at 0.943) are vignetted
 * in both fields (the 10 degree field shifts the others by at most
 * 0.7 tan 10 = 0.12 mm, from 7.45 to under 7.6), and the rest pass. */
static void vignetted(void **state)
{
    static const char design[] =
        "{\n"
        "  \"format\": \"sagitta-design\", \"version\": 1,\n"
        "  \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
        "  \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
        "             \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1},\n"
        "                      {\"x\": 0, \"y\": 10, \"weight\": 1}]},\n"
        "  \"aperture\": {\"type\": \"epd\", \"value\": 20},\n"
        "  \"ray_aiming\": \"off\",\n"
        "  \"surfaces\": [\n"
        "    {\"radius\": \"inf\", \"thickness\": \"inf\", \"material\": \"AIR\"},\n"
        "    {\"radius\": 40, \"thickness\": 50, \"material\": 1.5, \"stop\": true,\n"
        "     \"semi_diameter\": 8, \"sd_fixed\": true},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0, \"material\": \"AIR\"}\n"
        "  ]\n"
        "}\n";
    const char *path = vt_file("vignetted.json", design);
    const cJSON *failed, *e;
    vt_result r;
    double pmin, cmin;
    (void)state;
    vt_run(&r, "verify", path, "--format", "json", (char *)NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(r.json);
    failed = vt_get(r.json, "failed_in_mpfr", NULL);
    print_message("# vignetted.json: %d rays fail in mpfr (expect 16), %d compared (expect 42)\n",
                  cJSON_GetArraySize(failed), (int)vt_num(r.json, "rays", "compared_precise", NULL));
    assert_int_equal((int)vt_num(r.json, "rays", "failed_in_mpfr", NULL), 16);
    assert_int_equal(cJSON_GetArraySize(failed), 16);
    assert_int_equal((int)vt_num(r.json, "rays", "compared_precise", NULL), 42);
    assert_int_equal((int)vt_num(r.json, "rays", "disagreements_precise", NULL), 0);
    cJSON_ArrayForEach(e, failed) {
        double px = vt_num(e, "ray", "px", NULL), py = vt_num(e, "ray", "py", NULL);
        assert_true(px * px + py * py > 0.8 * 0.8);
        assert_string_equal(cJSON_GetStringValue(vt_get(e, "mpfr", "status", NULL)),
                            "VIGNETTED");
        assert_int_equal((int)vt_num(e, "mpfr", "surface", NULL), 1);
    }
    check_surfaces(r.json, 15.0, &pmin, &cmin);
    vt_free(&r);
}

static void example(const char *file)
{
    char buf[1024];
    vt_result r;
    double pmin, cmin;
    int lower;
    vt_run(&r, "verify", vt_source(file, buf, sizeof buf), "--format", "json",
           (char *)NULL);
    print_message("# verify %s: exit %d\n", file, r.code);
    if (r.code != 0)
        print_message("# stderr: %s\n", r.err);
    assert_int_equal(r.code, 0);
    assert_non_null(r.json);
    assert_true(vt_num(r.json, "rays", "compared_precise", NULL) > 0);
    lower = check_surfaces(r.json, 15.0, &pmin, &cmin);
    print_message("# %s: precise min %.2f digits, classic min %.2f; classic lower on "
                  "%d surfaces\n", file, pmin, cmin, lower);
    assert_true(lower >= 1);
    assert_int_equal(cJSON_GetArraySize(vt_get(r.json, "bound_violations", NULL)), 0);
    assert_int_equal((int)vt_num(r.json, "rays", "disagreements_precise", NULL), 0);
    assert_true(cJSON_IsTrue(vt_get(r.json, "pass", NULL)));
    vt_free(&r);
}

static void cassegrain(void **state)
{
    (void)state;
    example("examples/cassegrain.json");
}

static void tma(void **state)
{
    (void)state;
    example("examples/tma.json");
}

/* The text report carries the same verdict as the JSON one. */
static void text_report(void **state)
{
    char buf[1024];
    vt_result r;
    (void)state;
    vt_run(&r, "verify", vt_source("examples/tma.json", buf, sizeof buf), (char *)NULL);
    print_message("# verify tma.json (text): exit %d, %zu bytes\n", r.code, strlen(r.out));
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "result: PASS"));
    assert_non_null(strstr(r.out, "IMA"));
    vt_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sphere_one_ray),
        cmocka_unit_test(sphere_grid),
        cmocka_unit_test(vignetted),
        cmocka_unit_test(cassegrain),
        cmocka_unit_test(tma),
        cmocka_unit_test(text_report),
    };
    int rc;
    vt_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    vt_cleanup();
    return rc;
}
