/*
 * test_cli_analysis.c - sagitta spot, fan and layout as a user runs them:
 * a spherical mirror's spot and fan against the exact reflection worked
 * out here in long double, the formats (CSV, JSON, PNG with its size read
 * back, SVG, PDF), and bad options named in the message.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

/* A concave sphere of radius 100, focus at 50 (the paraxial focus). */
#define MIRROR                                                                 \
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"                     \
    "    {\"radius\": -100, \"thickness\": -50, \"material\": \"MIRROR\", "    \
    "\"stop\": true},\n"                                                        \
    "    {\"radius\": \"inf\", \"thickness\": 0}"

/* Landing height on the paraxial focal plane of the axial ray at height h:
 * the exact reflection off the sphere of radius c < 0. */
static long double landing(long double c, long double h)
{
    long double z = c + sqrtl(c * c - h * h), ny = h / fabsl(c), nz = (z - c) / fabsl(c);
    long double dy = -2 * nz * ny, dz = 1 - 2 * nz * nz, t = (c / 2 - z) / dz;
    return h + t * dy;
}

static void test_spot_csv_mirror(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    ct_result r;
    long double s2 = 0, g = 0;
    int i, j, n = 8;
    (void)state;
    ct_run(&r, "spot", d, "--field", "1", "--density", "8", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    /* Hexapolar rings of 6i rays at radius i/N; the EPD is 10. */
    for (i = 0; i <= n; i++)
        for (j = 0; j < (i ? 6 * i : 1); j++) {
            long double e = landing(-100, 5.0L * i / n);
            s2 += e * e;
            g = fmaxl(g, fabsl(e));
        }
    s2 /= 1 + 3 * n * (n + 1);
    ct_close(ct_csv_num(r.out, 0, "rms"), (double)sqrtl(s2), 1e-12, 0, "rms");
    ct_close(ct_csv_num(r.out, 0, "geo"), (double)g, 1e-12, 0, "geo");
    ct_close(ct_csv_num(r.out, 0, "rays"), 217, 0, 0, "rays");
    ct_free(&r);
}

static void test_fan_json_mirror(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    ct_result r;
    cJSON *j, *fans, *f0, *py, *ey;
    int k;
    (void)state;
    ct_run(&r, "fan", d, "--field", "1", "--points", "5", "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    fans = cJSON_GetObjectItem(j, "fans");
    assert_int_equal(cJSON_GetArraySize(fans), 2);
    f0 = cJSON_GetArrayItem(fans, 0);
    assert_string_equal(cJSON_GetObjectItem(f0, "fan")->valuestring, "tangential");
    py = cJSON_GetObjectItem(f0, "py");
    ey = cJSON_GetObjectItem(f0, "ey");
    for (k = 0; k < 5; k++) {
        double p = cJSON_GetArrayItem(py, k)->valuedouble;
        ct_close(p, -1.0 + 0.5 * k, 0, 1, "py");
        ct_close(cJSON_GetArrayItem(ey, k)->valuedouble, (double)landing(-100, 5.0L * p),
                 1e-12, 1e-3, "ey");
    }
    cJSON_Delete(j);
    ct_free(&r);
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    char *b;
    long n;
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    rewind(f);
    b = malloc((size_t)n + 1);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    b[n] = '\0';
    fclose(f);
    *len = (size_t)n;
    return b;
}

static void test_pictures(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    const char *png = ct_path("spot.png"), *svg = ct_path("fan.svg"), *pdf = ct_path("lay.pdf");
    ct_result r;
    size_t n;
    char *b;
    unsigned char *u;
    (void)state;
    ct_run(&r, "spot", d, "--format", "png", "--size", "321x234", "-o", png, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = slurp(png, &n);
    u = (unsigned char *)b;
    assert_true(n > 24 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0);
    assert_int_equal((u[16] << 24) | (u[17] << 16) | (u[18] << 8) | u[19], 321);
    assert_int_equal((u[20] << 24) | (u[21] << 16) | (u[22] << 8) | u[23], 234);
    free(b);
    ct_run(&r, "fan", d, "--format", "svg", "-o", svg, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = slurp(svg, &n);
    assert_true(strncmp(b, "<?xml", 5) == 0 && strstr(b, "</svg>"));
    free(b);
    ct_run(&r, "layout", d, "--format", "pdf", "-o", pdf, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = slurp(pdf, &n);
    assert_true(n > 100 && strncmp(b, "%PDF-", 5) == 0);
    free(b);
}

static void test_layout_csv(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    ct_result r;
    char buf[64];
    (void)state;
    ct_run(&r, "layout", d, "--rays", "3", "--field", "1", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    /* The mirror's profile starts at its rim: the sag of a radius-100
     * sphere at the marginal ray's height 5 (its automatic semi-diameter). */
    assert_string_equal(ct_csv(r.out, 0, "kind", buf, sizeof buf), "surface");
    ct_close(ct_csv_num(r.out, 0, "y"), -5.0, 1e-12, 0, "rim y");
    ct_close(ct_csv_num(r.out, 0, "z"), -100.0 + sqrt(10000.0 - 25.0), 1e-12, 0, "rim z");
    assert_non_null(strstr(r.out, "\nray,"));
    ct_free(&r);
}

static void test_bad_options(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    ct_result r;
    (void)state;
    ct_run(&r, "spot", d, "--pattern", "grid", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--pattern"));
    ct_free(&r);
    ct_run(&r, "spot", d, "--density", "0", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--density"));
    ct_free(&r);
    ct_run(&r, "spot", d, "--field", "3", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--field 3 is not one of 1 to 2"));
    ct_free(&r);
    ct_run(&r, "fan", d, "--format", "gif", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "png, svg or pdf"));
    ct_free(&r);
    ct_run(&r, "layout", d, "--size", "5x5", "--format", "png", "-o", ct_path("x.png"), NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
    ct_run(&r, "fan", d, "--density", "3", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--density is for spot"));
    ct_free(&r);
    /* Hexapolar density beyond its limit is the library's message. */
    ct_run(&r, "spot", d, "--density", "9999", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "hexapolar density 9999"));
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spot_csv_mirror),
        cmocka_unit_test(test_fan_json_mirror),
        cmocka_unit_test(test_pictures),
        cmocka_unit_test(test_layout_csv),
        cmocka_unit_test(test_bad_options),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
