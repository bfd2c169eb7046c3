/*
 * test_cli_analysis.c - sagitta spot, fan and layout as a user runs them:
 * a spherical mirror's spot and fan against the exact reflection worked
 * out here in long double, the formats (CSV, JSON, PNG with its size read
 * back, SVG, PDF), and bad options named in the message.  The wavefront's
 * spherical term against Welford's SI / 8 for the mirror (see
 * test_wavefront_formats) in every format.
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

/* The singlet's fields lie on the y axis of a rotationally symmetric
 * system, so every centroid x is exactly 0 (symmetry): its rounding noise
 * (1e-18 mm), below its error bound, is printed as 0; the wavelength is the
 * design's number, 0.5875618, not 0.58756180000000002. */
static void test_spot_csv_noise(void **state)
{
    char d[1024], buf[64];
    const char *e = getenv("SAGITTA_EXAMPLES");
    ct_result r;
    int row;
    (void)state;
    assert_non_null(e);
    snprintf(d, sizeof d, "%s/singlet.json", e);
    ct_run(&r, "spot", d, "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    for (row = 0; row < 12; row++) {
        assert_non_null(ct_csv(r.out, row, "centroid_x", buf, sizeof buf));
        if (strcmp(buf, "0") != 0)
            fail_msg("row %d: centroid_x \"%s\", expected 0", row, buf);
    }
    assert_non_null(ct_csv(r.out, 1, "um", buf, sizeof buf));
    assert_string_equal(buf, "0.5875618");
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
    double y = -5.0, t5 = tan(5.0 * 3.14159265358979323846 / 180.0);
    int k;
    (void)state;
    ct_run(&r, "layout", d, "--rays", "3", "--field", "1", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    /* The mirror's profile starts at its rim: the sag of a radius-100
     * sphere at its automatic semi-diameter, which counts every field (as
     * Zemax's does, whichever field is drawn): the 5 degree ray through the
     * pupil's lower edge (y = -5 + z tan 5 from the vertex plane, the stop)
     * meets the sphere z = -100 + sqrt(10000 - y^2) at the greatest height. */
    for (k = 0; k < 60; k++)
        y = -5.0 + t5 * (-100.0 + sqrt(10000.0 - y * y));
    assert_string_equal(ct_csv(r.out, 0, "kind", buf, sizeof buf), "surface");
    ct_close(ct_csv_num(r.out, 0, "y"), y, 1e-9, 0, "rim y");
    ct_close(ct_csv_num(r.out, 0, "z"), -100.0 + sqrt(10000.0 - y * y), 1e-9, 0, "rim z");
    assert_non_null(strstr(r.out, "\nray,"));
    ct_free(&r);
}

static void png_size(const char *png, int w, int h)
{
    size_t n;
    char *b = slurp(png, &n);
    unsigned char *u = (unsigned char *)b;
    assert_true(n > 24 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0);
    assert_int_equal((u[16] << 24) | (u[17] << 16) | (u[18] << 8) | u[19], w);
    assert_int_equal((u[20] << 24) | (u[21] << 16) | (u[22] << 8) | u[23], h);
    free(b);
}

/* On axis the mirror (stop on it, h = 5, R = -100) has spherical
 * aberration alone: Welford's SI = -2 h^4 / R^3 (A = h / R, D(u/n) = 2h / R),
 * W040 = SI / 8, and Fringe Z9 = 6 rho^4 - ... takes W040 / 6.  Higher
 * orders are some 1.5 (h / R)^2 = 0.4% of it. */
static void test_wavefront_formats(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    const char *png = ct_path("wf.png"), *svg = ct_path("wf.svg"), *pdf = ct_path("wf.pdf");
    double W040 = -2.0 * 625.0 / -1e6 / 8.0 / 0.55e-3, z9;
    ct_result r;
    cJSON *j, *map;
    size_t n;
    char *b;
    int k, lines = 0;
    (void)state;
    ct_run(&r, "wavefront", d, "--grid", "21", "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    z9 = cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "zernike"), "coef"), 8)
             ->valuedouble;
    ct_close(6.0 * z9, W040, 1e-2, 0, "W040 from Z9");
    map = cJSON_GetObjectItem(j, "map");
    assert_int_equal(cJSON_GetArraySize(map), 21);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetArrayItem(map, 0)), 21);
    /* The corner is outside the pupil, the centre inside. */
    assert_true(cJSON_IsNull(cJSON_GetArrayItem(cJSON_GetArrayItem(map, 0), 0)));
    assert_true(cJSON_IsNumber(cJSON_GetArrayItem(cJSON_GetArrayItem(map, 10), 10)));
    cJSON_Delete(j);
    ct_free(&r);
    ct_run(&r, "wavefront", d, "--grid", "21", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    for (k = 0; r.out[k]; k++)
        lines += r.out[k] == '\n';
    assert_int_equal(lines, 1 + 21 * 21);
    ct_close(ct_csv_num(r.out, 220, "px"), 0.0, 0, 1e-15, "centre px");
    ct_free(&r);
    ct_run(&r, "wavefront", d, "--zernike", "standard", "--terms", "11", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "Standard Zernike coefficients"));
    assert_non_null(strstr(r.out, "piston and tilt removed"));
    assert_non_null(strstr(r.out, "█"));
    ct_free(&r);
    ct_run(&r, "wavefront", d, "--format", "png", "--size", "400x300", "-o", png, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    png_size(png, 400, 300);
    ct_run(&r, "wavefront", d, "--format", "svg", "-o", svg, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = slurp(svg, &n);
    assert_true(strncmp(b, "<?xml", 5) == 0 && strstr(b, "</svg>"));
    free(b);
    ct_run(&r, "wavefront", d, "--format", "pdf", "-o", pdf, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = slurp(pdf, &n);
    assert_true(n > 100 && strncmp(b, "%PDF-", 5) == 0);
    free(b);
    ct_run(&r, "wavefront", d, "--terms", "38", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--terms"));
    ct_free(&r);
    ct_run(&r, "wavefront", d, "--zernike", "noll", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "fringe or standard"));
    ct_free(&r);
}

/* OPD fans: the mirror's OPD at the rim against the same W040 rho^4
 * (SI / 8, with the higher orders within 1%), and 0 on the chief ray. */
static void test_fan_opd(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    double W040 = -2.0 * 625.0 / -1e6 / 8.0 / 0.55e-3;
    ct_result r;
    cJSON *j, *f0, *opd;
    (void)state;
    ct_run(&r, "fan", d, "--opd", "--field", "1", "--points", "5", "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    assert_string_equal(cJSON_GetObjectItem(j, "kind")->valuestring, "opd");
    f0 = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "fans"), 0);
    opd = cJSON_GetObjectItem(f0, "opd");
    assert_non_null(opd);
    ct_close(cJSON_GetArrayItem(opd, 2)->valuedouble, 0.0, 0, 1e-12, "chief OPD");
    ct_close(cJSON_GetArrayItem(opd, 4)->valuedouble, W040, 1e-2, 0, "rim OPD");
    cJSON_Delete(j);
    ct_free(&r);
    ct_run(&r, "fan", d, "--opd", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    assert_true(strncmp(r.out, "field,wave,um,fan,p,opd_waves,status", 36) == 0);
    ct_free(&r);
    ct_run(&r, "spot", d, "--opd", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--opd is an option of fan only"));
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
    assert_non_null(strstr(r.err, "--density is an option of spot only"));
    ct_free(&r);
    /* Hexapolar density beyond its limit is the library's message. */
    ct_run(&r, "spot", d, "--density", "9999", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "hexapolar density 9999"));
    ct_free(&r);
}

/* bench --view: every view of the editor rebuilt after edits, the median
 * between the extremes, 25 edits at least, the load named. */
static void test_bench_view(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    static const char *const kinds[] = {"layout", "spot", "fan", "opd",
                                        "wave", "mtf", "psf", "encircled"};
    ct_result r;
    cJSON *j, *v, *ms;
    int k = 0;
    (void)state;
    ct_run(&r, "bench", d, "--view", "all", "--repeat", "1", "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    v = cJSON_GetObjectItemCaseSensitive(j, "views");
    assert_int_equal(cJSON_GetArraySize(v), 8);
    for (k = 0; k < 8; k++) {
        cJSON *o = cJSON_GetArrayItem(v, k);
        double med, lo, hi;
        assert_string_equal(cJSON_GetObjectItemCaseSensitive(o, "view")->valuestring, kinds[k]);
        assert_int_equal(cJSON_GetObjectItemCaseSensitive(o, "edits")->valueint, 25);
        ms = cJSON_GetObjectItemCaseSensitive(o, "ms");
        med = cJSON_GetObjectItemCaseSensitive(ms, "median")->valuedouble;
        lo = cJSON_GetObjectItemCaseSensitive(ms, "min")->valuedouble;
        hi = cJSON_GetObjectItemCaseSensitive(ms, "max")->valuedouble;
        assert_true(lo > 0.0 && lo <= med && med <= hi);
        assert_true(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(o, "load_before")));
    }
    cJSON_Delete(j);
    ct_free(&r);
    ct_run(&r, "bench", d, "--view", "spot", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "view spot"));
    assert_non_null(strstr(r.out, "median"));
    assert_non_null(strstr(r.out, "load"));
    ct_free(&r);
    /* The spot mode names the load too. */
    ct_run(&r, "bench", d, "--spot", "--quick", "--repeat", "1", "--threads", "1", "--format",
           "json", NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    v = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(j, "spot"), 0);
    assert_non_null(v);
    assert_true(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(v, "load_before")));
    assert_true(cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(v, "load_after")));
    assert_true(cJSON_GetObjectItemCaseSensitive(
                    cJSON_GetObjectItemCaseSensitive(v, "ratio"), "median")->valuedouble > 0.0);
    cJSON_Delete(j);
    ct_free(&r);
    /* The merit mode: a design with no merit function gets Zemax's
     * default, TRAX and TRAY for 3 rings x 6 arms of each of the 2 fields
     * at the 1 wavelength: 72 rows. */
    ct_run(&r, "bench", d, "--merit", "--repeat", "5", "--clock", "cpu", "--format", "json",
           NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    v = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(j, "merit"), 0);
    assert_non_null(v);
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(v, "merit")->valuestring, "default");
    assert_int_equal(cJSON_GetObjectItemCaseSensitive(v, "rows")->valueint, 72);
    assert_true(cJSON_GetObjectItemCaseSensitive(v, "value")->valuedouble > 0.0);
    ms = cJSON_GetObjectItemCaseSensitive(v, "evaluation_s");
    assert_true(cJSON_GetObjectItemCaseSensitive(ms, "min")->valuedouble <=
                cJSON_GetObjectItemCaseSensitive(ms, "median")->valuedouble);
    assert_true(cJSON_GetObjectItemCaseSensitive(v, "evaluations_per_s")->valuedouble > 0.0);
    cJSON_Delete(j);
    ct_free(&r);
    ct_run(&r, "bench", d, "--view", "nope", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--view"));
    ct_free(&r);
}

/* bench --baseline: the lean double trace (a textbook trace written for
 * the bench, with no code of the methods) lands the precise method's
 * rays where precise lands them, to double rounding (1e-9 of the image's
 * size), on the Cassegrain (conic mirrors, a hyperboloid met from far
 * off its vertex) and the double Gauss (refraction); the random-order
 * figures are there. */
static void test_bench_baseline(void **state)
{
    char d1[1024], d2[1024];
    const char *e = getenv("SAGITTA_EXAMPLES");
    ct_result r;
    cJSON *j, *arr, *o;
    int k;
    (void)state;
    assert_non_null(e);
    snprintf(d1, sizeof d1, "%s/cassegrain.json", e);
    snprintf(d2, sizeof d2, "%s/double_gauss.json", e);
    ct_run(&r, "bench", d1, d2, "--baseline", "--quick", "--repeat", "1", "--format", "json",
           NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    arr = cJSON_GetObjectItemCaseSensitive(j, "baseline");
    assert_int_equal(cJSON_GetArraySize(arr), 2);
    for (k = 0; k < 2; k++) {
        cJSON *lean, *ro;
        double diff, nok, lok, rays, scale;
        o = cJSON_GetArrayItem(arr, k);
        lean = cJSON_GetObjectItemCaseSensitive(o, "lean_double_one_thread");
        assert_non_null(lean);
        diff = cJSON_GetObjectItemCaseSensitive(lean, "image_max_difference")->valuedouble;
        lok = cJSON_GetObjectItemCaseSensitive(lean, "rays_reached_image")->valuedouble;
        nok = cJSON_GetObjectItemCaseSensitive(o, "rays_reached_image")->valuedouble;
        rays = cJSON_GetObjectItemCaseSensitive(o, "rays")->valuedouble;
        /* The image's size, as precise found it: 219 mm and 17.3 mm. */
        scale = cJSON_GetObjectItemCaseSensitive(lean, "image_largest_coordinate")->valuedouble;
        assert_true(scale > (k == 0 ? 200.0 : 15.0) && scale < (k == 0 ? 240.0 : 20.0));
        if (!(diff <= scale * 1e-9))
            fail_msg("design %d: lean image points %g from precise's", k, diff);
        assert_true(lok == nok && nok > 0.9 * rays);
        assert_true(cJSON_GetObjectItemCaseSensitive(o, "lean_over_precise")->valuedouble > 0.0);
        ro = cJSON_GetObjectItemCaseSensitive(o, "random_field_order");
        assert_true(cJSON_GetObjectItemCaseSensitive(ro, "ratio_fastest")->valuedouble > 0.0);
    }
    cJSON_Delete(j);
    ct_free(&r);
}

/* bench --clock: the clock is named in the text and in the JSON
 * settings, the figures stay positive and ordered, and a clock it does
 * not know is a usage error naming the option. */
static void test_bench_clock(void **state)
{
    const char *d = ct_design("mirror.json", MIRROR);
    ct_result r;
    cJSON *j, *set, *des, *tp;
    int k;
    (void)state;
    ct_run(&r, "bench", d, "--rays", "2000", "--repeat", "3", "--threads", "1", "--clock", "cpu",
           "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    j = cJSON_Parse(r.out);
    assert_non_null(j);
    set = cJSON_GetObjectItemCaseSensitive(j, "settings");
    assert_string_equal(cJSON_GetObjectItemCaseSensitive(set, "clock")->valuestring, "cpu");
    des = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(j, "designs"), 0);
    assert_non_null(des);
    tp = cJSON_GetObjectItemCaseSensitive(des, "throughput");
    assert_true(cJSON_GetArraySize(tp) > 0);
    for (k = 0; k < cJSON_GetArraySize(tp); k++) {
        cJSON *c = cJSON_GetArrayItem(tp, k), *sec = cJSON_GetObjectItemCaseSensitive(c, "seconds");
        double lo, med, hi;
        assert_non_null(sec);
        lo = cJSON_GetObjectItemCaseSensitive(sec, "min")->valuedouble;
        med = cJSON_GetObjectItemCaseSensitive(sec, "median")->valuedouble;
        hi = cJSON_GetObjectItemCaseSensitive(sec, "max")->valuedouble;
        assert_true(lo > 0.0 && lo <= med && med <= hi);
    }
    cJSON_Delete(j);
    ct_free(&r);
    ct_run(&r, "bench", d, "--rays", "100", "--repeat", "1", "--threads", "1", "--clock", "wall",
           NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "clock:   wall"));
    assert_non_null(strstr(r.out, "over wall time"));
    ct_free(&r);
    ct_run(&r, "bench", d, "--clock", "tsc", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--clock"));
    assert_non_null(strstr(r.err, "tsc"));
    ct_free(&r);
}

/* "sagitta vignetting" (Zemax's Set Vignetting) on a flat stop (EPD 10)
 * with a fixed semi-diameter of 2 at 20 behind it: at 5 degrees the pupil
 * that passes is the disc of radius 0.4 about (0, -20 tan 5 / 5), so
 * VDY = -4 tan 5 degrees and VCY = 0.6 (closed form).  --save and the
 * editor's "field setvig" write the same design, and undo takes it back. */
static void test_vignetting_command(void **state)
{
    const char *d = ct_design("apert.json",
        "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "    {\"radius\": \"inf\", \"thickness\": 20, \"stop\": true},\n"
        "    {\"radius\": \"inf\", \"thickness\": 10, \"semi_diameter\": 2, "
        "\"sd_fixed\": true},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0}");
    char saved[1024], script_text[3 * 1024], plain_text[1024];
    const char *script, *plain;
    ct_result r;
    cJSON *js, *f2;
    long double vdy = -4.0L * tanl(5.0L * 3.141592653589793238462643383279502884L / 180.0L);
    char *a, *b;
    (void)state;
    snprintf(saved, sizeof saved, "%s", ct_path("cli_set.json"));
    snprintf(script_text, sizeof script_text, "field setvig\nsave %s\nundo\nsave %s\n",
             ct_path("ed_set.json"), ct_path("ed_undo.json"));
    snprintf(plain_text, sizeof plain_text, "save %s\n", ct_path("ed_plain.json"));
    script = ct_file("setvig.txt", script_text);
    plain = ct_file("plain.txt", plain_text);
    ct_run(&r, "vignetting", d, "--format", "json", "--save", saved, NULL);
    if (r.code != 0)
        fail_msg("vignetting: exit %d: %s", r.code, r.err);
    js = cJSON_Parse(r.out);
    assert_non_null(js);
    f2 = cJSON_GetArrayItem(cJSON_GetObjectItem(js, "fields"), 1);
    assert_non_null(f2);
    if (fabsl(cJSON_GetObjectItem(f2, "vdy")->valuedouble - vdy) > 2e-9L ||
        fabs(cJSON_GetObjectItem(f2, "vcy")->valuedouble - 0.6) > 2e-9 ||
        fabs(cJSON_GetObjectItem(f2, "vdx")->valuedouble) > 2e-9)
        fail_msg("field 2: %s; closed form VDY %.12Lg VCY 0.6", r.out, vdy);
    print_message("# vignetting: field 2 VDY %.12g (closed form %.12Lg), VCY %.12g (0.6)\n",
                  cJSON_GetObjectItem(f2, "vdy")->valuedouble, vdy,
                  cJSON_GetObjectItem(f2, "vcy")->valuedouble);
    cJSON_Delete(js);
    ct_free(&r);
    /* The editor, by the command path its keys and : line share. */
    ct_run(&r, "edit", d, "--batch", script, NULL);
    if (r.code != 0)
        fail_msg("edit --batch: exit %d: %s", r.code, r.err);
    ct_free(&r);
    ct_run(&r, "edit", d, "--batch", plain, NULL);
    if (r.code != 0)
        fail_msg("edit --batch (plain save): exit %d: %s", r.code, r.err);
    ct_free(&r);
    a = ct_read(saved);
    b = ct_read(ct_path("ed_set.json"));
    assert_string_equal(a, b);
    free(a);
    free(b);
    a = ct_read(ct_path("ed_undo.json"));
    b = ct_read(ct_path("ed_plain.json"));
    assert_string_equal(a, b);
    free(a);
    free(b);
    /* A bad grid is a usage error naming the option. */
    ct_run(&r, "vignetting", d, "--grid", "2", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--grid"));
    ct_free(&r);
}

/* Automatic semi-diameters on flat surfaces behind the stop (EPD 10,
 * fields 0 and 5 degrees, no aiming): the highest edge ray at z behind the
 * stop is 5 + z tan 5 degrees (closed form).  The layout draws a surface
 * whose semi-diameter is not fixed at that height (its stored 1 is too
 * small for the rays) and keeps a fixed one; the editor's "semidiam" sets
 * the same values as one edit, and undo takes it back. */
static void test_semidiam_auto(void **state)
{
    const char *d = ct_design("sdauto.json",
        "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "    {\"radius\": \"inf\", \"thickness\": 20, \"stop\": true, \"semi_diameter\": 1},\n"
        "    {\"radius\": \"inf\", \"thickness\": 10, \"semi_diameter\": 1},\n"
        "    {\"radius\": \"inf\", \"thickness\": 5, \"semi_diameter\": 9, "
        "\"sd_fixed\": true},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0}");
    const double t5 = tan(5.0 * 3.14159265358979323846 / 180.0);
    const double want[4] = {5.0, 5.0 + 20.0 * t5, 9.0, 5.0 + 35.0 * t5};
    char script_text[3 * 1024], plain_text[1024];
    ct_result r;
    cJSON *js, *ss;
    int i;
    char *a, *b;
    (void)state;
    ct_run(&r, "layout", d, "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("layout: exit %d: %s", r.code, r.err);
    js = cJSON_Parse(r.out);
    assert_non_null(js);
    ss = cJSON_GetObjectItem(js, "surfaces");
    for (i = 0; i < 4; i++) {
        double got = cJSON_GetObjectItem(cJSON_GetArrayItem(ss, i), "semi_diameter")->valuedouble;
        if (fabs(got - want[i]) > 1e-9)
            fail_msg("layout surface %d: semi-diameter %.12g, closed form %.12g", i + 1, got,
                     want[i]);
    }
    cJSON_Delete(js);
    ct_free(&r);
    snprintf(script_text, sizeof script_text, "semidiam\nsave %s\nundo\nsave %s\n",
             ct_path("sd_set.json"), ct_path("sd_undo.json"));
    snprintf(plain_text, sizeof plain_text, "save %s\n", ct_path("sd_plain.json"));
    ct_run(&r, "edit", d, "--batch", ct_file("sd.txt", script_text), NULL);
    if (r.code != 0)
        fail_msg("edit --batch: exit %d: %s", r.code, r.err);
    ct_free(&r);
    ct_run(&r, "edit", d, "--batch", ct_file("sdp.txt", plain_text), NULL);
    if (r.code != 0)
        fail_msg("edit --batch (plain save): exit %d: %s", r.code, r.err);
    ct_free(&r);
    a = ct_read(ct_path("sd_set.json"));
    js = cJSON_Parse(a);
    assert_non_null(js);
    ss = cJSON_GetObjectItem(js, "surfaces");
    for (i = 0; i < 4; i++) {
        cJSON *v = cJSON_GetObjectItem(cJSON_GetArrayItem(ss, i + 1), "semi_diameter");
        if (!v || fabs(v->valuedouble - want[i]) > 1e-9)
            fail_msg("semidiam surface %d: %s, closed form %.12g", i + 1, a, want[i]);
    }
    cJSON_Delete(js);
    free(a);
    a = ct_read(ct_path("sd_undo.json"));
    b = ct_read(ct_path("sd_plain.json"));
    assert_string_equal(a, b);
    free(a);
    free(b);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spot_csv_mirror),
        cmocka_unit_test(test_spot_csv_noise),
        cmocka_unit_test(test_fan_json_mirror),
        cmocka_unit_test(test_pictures),
        cmocka_unit_test(test_bench_view),
        cmocka_unit_test(test_bench_clock),
        cmocka_unit_test(test_bench_baseline),
        cmocka_unit_test(test_layout_csv),
        cmocka_unit_test(test_wavefront_formats),
        cmocka_unit_test(test_fan_opd),
        cmocka_unit_test(test_bad_options),
        cmocka_unit_test(test_vignetting_command),
        cmocka_unit_test(test_semidiam_auto),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
