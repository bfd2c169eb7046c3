/* test_cli_trace.c - "sagitta trace" against closed-form ray paths.
 *
 * The expected values are computed here, in long double, from Snell's law
 * and the line-sphere intersection; the program's output (CSV and JSON, both
 * printed with %.17g) must agree to a few 1e-16.  Batch runs must repeat the
 * single-ray runs digit for digit. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

static const char *const methods[3] = { "precise", "mpfr", "classic" };

/* Tolerances (relative to max(|expected|, 1)): the precise and MPFR methods
 * measure 1.9e-16 at worst here (about one ulp of the value, as a %.17g
 * print of a double within 0.5 ulp of the truth can show against the long
 * double expectation), the textbook method 7.8e-16; each is held to about
 * twice that, not 1e-14 or 1e-12. */
static const double method_tol[3] = { 4e-16, 4e-16, 2e-15 };

/* ------------------------------------------------------------ the slab */

#define SLAB_N 1.6L
#define SLAB_D 7.0L
#define SLAB_T 12.0L

static const char *const SLAB =
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": \"inf\", \"thickness\": 7, \"material\": 1.6, \"stop\": true},\n"
    "    {\"radius\": \"inf\", \"thickness\": 12},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}";

static void test_slab_snell(void **state)
{
    const char *d = ct_design("slab.json", SLAB);
    const long double p0[3] = { 1.25L, -0.5L, -3.0L };
    const long double v0[3] = { 0.2L, 0.1L, 1.0L };
    long double len = sqrtl(v0[0] * v0[0] + v0[1] * v0[1] + v0[2] * v0[2]);
    long double L = v0[0] / len, M = v0[1] / len, N = v0[2] / len;
    long double x1, y1, L2, M2, N2, x2, y2, x3, y3;
    long double ex[4][7];
    int k, s, c;

    (void)state;
    /* Surface 1 (z = 0): reach it from the start point, then Snell at a
     * plane keeps the tangential components times the index. */
    x1 = p0[0] + L * (-p0[2] / N);
    y1 = p0[1] + M * (-p0[2] / N);
    L2 = L / SLAB_N;
    M2 = M / SLAB_N;
    N2 = sqrtl(1 - L2 * L2 - M2 * M2);
    x2 = x1 + L2 / N2 * SLAB_D;
    y2 = y1 + M2 / N2 * SLAB_D;
    x3 = x2 + L / N * SLAB_T;
    y3 = y2 + M / N * SLAB_T;
    /* x, y, z, l, m, n, path for surfaces 1..3. */
    {
        const long double e1[7] = { x1, y1, 0, L2, M2, N2, NAN };
        const long double e2[7] = { x2, y2, 0, L, M, N, SLAB_D / N2 };
        const long double e3[7] = { x3, y3, 0, L, M, N, SLAB_T / N };
        memcpy(ex[1], e1, sizeof e1);
        memcpy(ex[2], e2, sizeof e2);
        memcpy(ex[3], e3, sizeof e3);
    }
    for (k = 0; k < 3; k++) {
        static const char *const col[7] = { "x", "y", "z", "l", "m", "n", "path" };
        ct_result r;
        double worst = 0;
        ct_run(&r, "trace", d, "--method", methods[k], "--start", "1.25,-0.5,-3",
               "--dir", "0.2,0.1,1", "--format", "csv", NULL);
        if (r.code != 0)
            fail_msg("exit %d: %s", r.code, r.err);
        for (s = 1; s <= 3; s++) {
            char buf[64], what[64];
            assert_string_equal(ct_csv(r.out, s, "status", buf, sizeof buf), "OK");
            assert_int_equal((int)ct_csv_num(r.out, s, "surface"), s);
            for (c = 0; c < 7; c++) {
                double e;
                if (isnan(ex[s][c]))
                    continue;
                snprintf(what, sizeof what, "%s surface %d %s", methods[k], s, col[c]);
                e = ct_close(ct_csv_num(r.out, s, col[c]), (double)ex[s][c],
                             method_tol[k], 1, what);
                if (e > worst)
                    worst = e;
            }
            if (!(ct_csv_num(r.out, s, "residual") <= 1e-12))
                fail_msg("%s surface %d residual too large", methods[k], s);
        }
        print_message("# slab n=1.6 d=7, tilted ray, %s: exit point and Snell "
                      "directions on 3 surfaces, worst scaled error %.3g\n",
                      methods[k], worst);
        ct_free(&r);
    }
}

/* ---------------------------------------------------------- the sphere */

#define SPH_R 40.0L
#define SPH_N 1.5L
#define SPH_T 20.0L

static const char *const SPHERE =
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": 40, \"thickness\": 20, \"material\": 1.5, \"stop\": true},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}";

static double jnum(const cJSON *o, const char *key)
{
    const cJSON *j = cJSON_GetObjectItem(o, key);
    if (!cJSON_IsNumber(j))
        fail_msg("JSON member \"%s\" is not a number", key);
    return j->valuedouble;
}

static void test_sphere_intersection(void **state)
{
    const char *d = ct_design("sphere.json", SPHERE);
    const long double P[3] = { 3.0L, -4.0L, -10.0L };
    const long double V[3] = { 0.05L, 0.1L, 1.0L };
    long double len = sqrtl(V[0] * V[0] + V[1] * V[1] + V[2] * V[2]);
    long double D[3], O[3], b, c, t, X[3], nrm[3], mu, ci, k2, g, D2[3], t2, X2[3];
    int i, k;

    (void)state;
    for (i = 0; i < 3; i++)
        D[i] = V[i] / len;
    /* |P + tD - C|^2 = R^2 with C = (0, 0, R); the nearer root is the cap
     * around the vertex.  The product form avoids cancellation. */
    O[0] = P[0];
    O[1] = P[1];
    O[2] = P[2] - SPH_R;
    b = O[0] * D[0] + O[1] * D[1] + O[2] * D[2];
    c = O[0] * O[0] + O[1] * O[1] + O[2] * O[2] - SPH_R * SPH_R;
    t = c / (-b + sqrtl(b * b - c));
    for (i = 0; i < 3; i++)
        X[i] = P[i] + t * D[i];
    /* Vector Snell with the unit normal (X - C)/R, which faces the ray. */
    nrm[0] = X[0] / SPH_R;
    nrm[1] = X[1] / SPH_R;
    nrm[2] = (X[2] - SPH_R) / SPH_R;
    mu = 1 / SPH_N;
    ci = -(nrm[0] * D[0] + nrm[1] * D[1] + nrm[2] * D[2]);
    k2 = 1 - mu * mu * (1 - ci * ci);
    g = mu * ci - sqrtl(k2);
    for (i = 0; i < 3; i++)
        D2[i] = mu * D[i] + g * nrm[i];
    /* The image plane is 20 behind the vertex. */
    t2 = (SPH_T - X[2]) / D2[2];
    for (i = 0; i < 3; i++)
        X2[i] = X[i] + t2 * D2[i];

    for (k = 0; k < 3; k++) {
        ct_result r;
        cJSON *root, *surfs, *s1, *s2;
        char what[64];
        double worst = 0, e;
        const double e1[6] = { (double)X[0], (double)X[1], (double)X[2],
                               (double)D2[0], (double)D2[1], (double)D2[2] };
        static const char *const key[6] = { "x", "y", "z", "l", "m", "n" };

        ct_run(&r, "trace", d, "--method", methods[k], "--start", "3,-4,-10", "--dir",
               "0.05,0.1,1", "--format", "json", NULL);
        if (r.code != 0)
            fail_msg("exit %d: %s", r.code, r.err);
        root = cJSON_Parse(r.out);
        if (!root)
            fail_msg("output is not JSON:\n%s", r.out);
        assert_string_equal(cJSON_GetObjectItem(root, "status")->valuestring, "OK");
        surfs = cJSON_GetObjectItem(root, "surfaces");
        assert_int_equal(cJSON_GetArraySize(surfs), 3);
        s1 = cJSON_GetArrayItem(surfs, 1);
        s2 = cJSON_GetArrayItem(surfs, 2);
        for (i = 0; i < 6; i++) {
            snprintf(what, sizeof what, "%s surface 1 %s", methods[k], key[i]);
            e = ct_close(jnum(s1, key[i]), e1[i], method_tol[k], 1, what);
            worst = e > worst ? e : worst;
        }
        snprintf(what, sizeof what, "%s image x", methods[k]);
        e = ct_close(jnum(s2, "x"), (double)X2[0], method_tol[k], 1, what);
        worst = e > worst ? e : worst;
        snprintf(what, sizeof what, "%s image y", methods[k]);
        e = ct_close(jnum(s2, "y"), (double)X2[1], method_tol[k], 1, what);
        worst = e > worst ? e : worst;
        snprintf(what, sizeof what, "%s image path", methods[k]);
        e = ct_close(jnum(s2, "path"), (double)t2, method_tol[k], 1, what);
        worst = e > worst ? e : worst;
        assert_true(jnum(s1, "residual") <= 1e-12);
        print_message("# sphere R=40, ray from (3,-4,-10), %s: intersection, "
                      "refracted direction, image point; worst scaled error %.3g\n",
                      methods[k], worst);
        cJSON_Delete(root);
        ct_free(&r);
    }
}

/* ----------------------------------------------------- misses, no NaN */

static void test_miss(void **state)
{
    /* A sphere of radius 5 cannot be met 8 off the axis. */
    const char *d = ct_design("small.json",
        "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "    {\"radius\": 5, \"thickness\": 10, \"material\": 1.5, \"stop\": true},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0}");
    static const char *const fmts[3] = { "text", "csv", "json" };
    int k;
    (void)state;
    for (k = 0; k < 3; k++) {
        ct_result r;
        ct_run(&r, "trace", d, "--start", "0,8,-1", "--dir", "0,0,1", "--format",
               fmts[k], NULL);
        if (r.code != 0)
            fail_msg("a miss is a result, but exit was %d: %s", r.code, r.err);
        assert_non_null(strstr(r.out, "MISS"));
        if (ct_contains_nocase(r.out, "nan") || ct_contains_nocase(r.err, "nan"))
            fail_msg("NaN in the %s output:\n%s", fmts[k], r.out);
        if (k == 2) {
            cJSON *root = cJSON_Parse(r.out), *s1;
            assert_non_null(root);
            assert_string_equal(cJSON_GetObjectItem(root, "status")->valuestring, "MISS");
            s1 = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "surfaces"), 1);
            assert_string_equal(cJSON_GetObjectItem(s1, "status")->valuestring, "MISS");
            assert_true(cJSON_IsNull(cJSON_GetObjectItem(s1, "x")));
            cJSON_Delete(root);
        }
        if (k == 1) {
            char buf[32];
            assert_string_equal(ct_csv(r.out, 1, "status", buf, sizeof buf), "MISS");
            assert_string_equal(ct_csv(r.out, 1, "x", buf, sizeof buf), "");
            assert_string_equal(ct_csv(r.out, 2, "status", buf, sizeof buf),
                                "NOT REACHED");
        }
        print_message("# miss at surface 1 (%s): exit 0, MISS printed, no NaN\n", fmts[k]);
        ct_free(&r);
    }
}

static void test_tir(void **state)
{
    /* Inside glass of index 2, a ray parallel to the axis at height 4 meets
     * a sphere of radius 6 at sin(i) = 4/6; n sin(i) = 4/3 > 1, so it is
     * totally reflected there.  At height 2, n sin(i) = 2/3 and it passes. */
    const char *d = ct_design("tir.json",
        "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "    {\"radius\": \"inf\", \"thickness\": 5, \"material\": 2, \"stop\": true},\n"
        "    {\"radius\": 6, \"thickness\": 10},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0}");
    ct_result r;
    char buf[32];
    (void)state;
    ct_run(&r, "trace", d, "--start", "0,4,-1", "--dir", "0,0,1", "--format", "csv", NULL);
    if (r.code != 0)
        fail_msg("TIR is a result, but exit was %d: %s", r.code, r.err);
    assert_string_equal(ct_csv(r.out, 1, "status", buf, sizeof buf), "OK");
    assert_string_equal(ct_csv(r.out, 2, "status", buf, sizeof buf), "TIR");
    assert_string_equal(ct_csv(r.out, 3, "status", buf, sizeof buf), "NOT REACHED");
    assert_false(ct_contains_nocase(r.out, "nan"));
    ct_free(&r);
    ct_run(&r, "trace", d, "--start", "0,2,-1", "--dir", "0,0,1", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    assert_string_equal(ct_csv(r.out, 3, "status", buf, sizeof buf), "OK");
    ct_free(&r);
    print_message("# n=2 glass to air on R=6: height 4 (n sin i = 4/3) gives TIR at "
                  "surface 2, exit 0; height 2 (2/3) reaches the image\n");
}

/* ---------------------------------------------- batch equals single */

/* The CSV cells of one surface, as text, from x to status. */
static void cells(const char *csv, int row, char out[10][64])
{
    static const char *const col[10] = { "x", "y", "z", "l", "m", "n", "residual",
                                         "error_bound", "path", "status" };
    int c;
    for (c = 0; c < 10; c++)
        if (!ct_csv(csv, row, col[c], out[c], 64) &&
            !(c == 7 && ct_csv(csv, row, "error_estimate", out[c], 64))) /* classic */
            fail_msg("no row %d column %s", row, col[c]);
}

static void compare_batch(const char *d, const char *csvname, const char *csvtext,
                          const char *const *single_args, int nray, int nsurf,
                          const char *method)
{
    const char *c = ct_file(csvname, csvtext);
    ct_result rb;
    int r, s, k;

    ct_run(&rb, "trace", d, "--rays", c, "--format", "csv", "--threads", "2",
           "--method", method, NULL);
    if (rb.code != 0)
        fail_msg("batch exit %d: %s", rb.code, rb.err);
    for (r = 0; r < nray; r++) {
        ct_result r1;
        const char *args[16];
        int n = 0;
        args[n++] = "trace";
        args[n++] = d;
        args[n++] = "--format";
        args[n++] = "csv";
        args[n++] = "--method";
        args[n++] = method;
        args[n++] = single_args[2 * r];
        args[n++] = single_args[2 * r + 1];
        args[n] = NULL;
        ct_runv(&r1, args);
        if (r1.code != 0)
            fail_msg("single ray %d exit %d: %s", r, r1.code, r1.err);
        for (s = 0; s < nsurf; s++) {
            char a[10][64], b[10][64];
            cells(rb.out, r * nsurf + s, a);
            cells(r1.out, s, b);
            assert_int_equal((int)ct_csv_num(rb.out, r * nsurf + s, "ray"), r);
            for (k = 0; k < 10; k++)
                if (strcmp(a[k], b[k]) != 0)
                    fail_msg("ray %d surface %d: batch \"%s\" vs single \"%s\"", r, s,
                             a[k], b[k]);
        }
        ct_free(&r1);
    }
    ct_free(&rb);
}

static void test_batch_matches_single(void **state)
{
    const char *d = ct_design("sphere.json", SPHERE);
    /* Columns deliberately out of order, with a comment and a blank line. */
    static const char norm_csv[] =
        "py,hx,px,hy\n"
        "0,0,0,0\n"
        "# the marginal ray of the 5 degree field\n"
        "1,0,0,1\n"
        "\n"
        "-0.7,0.5,0.2,-0.3\n"
        "-1,0,0,1\n";
    static const char *const norm_single[] = {
        "--ray", "0,0,0,0",
        "--ray", "0,1,0,1",
        "--ray", "0.5,-0.3,0.2,-0.7",
        "--ray", "0,1,0,-1",
    };
    static const char sd_csv[] =
        "x,y,z,n,m,l\n"
        "3,-4,-10,1,0.1,0.05\n"
        "0,0,-1,1,0,0\n"
        "0,8,-1,1,0,0.25\n";
    static const char *const sd_single[][4] = {
        { "--start", "3,-4,-10", "--dir", "0.05,0.1,1" },
        { "--start", "0,0,-1", "--dir", "0,0,1" },
        { "--start", "0,8,-1", "--dir", "0.25,0,1" },
    };
    int r, m;
    (void)state;
    for (m = 0; m < 2; m++) {
        compare_batch(d, "norm.csv", norm_csv, norm_single, 4, 3, methods[m]);
        print_message("# %s: 4 normalized rays from a permuted CSV equal the "
                      "--ray runs in every cell\n", methods[m]);
    }
    /* Start/direction rays: each single run needs both options. */
    {
        const char *c = ct_file("sd.csv", sd_csv);
        ct_result rb;
        ct_run(&rb, "trace", d, "--rays", c, "--format", "csv", NULL);
        if (rb.code != 0)
            fail_msg("batch exit %d: %s", rb.code, rb.err);
        for (r = 0; r < 3; r++) {
            ct_result r1;
            int s, k;
            ct_run(&r1, "trace", d, "--format", "csv", sd_single[r][0], sd_single[r][1],
                   sd_single[r][2], sd_single[r][3], NULL);
            assert_int_equal(r1.code, 0);
            for (s = 0; s < 3; s++) {
                char a[10][64], b[10][64];
                cells(rb.out, r * 3 + s, a);
                cells(r1.out, s, b);
                for (k = 0; k < 10; k++)
                    if (strcmp(a[k], b[k]) != 0)
                        fail_msg("start/dir ray %d surface %d: batch \"%s\" vs "
                                 "single \"%s\"", r, s, a[k], b[k]);
            }
            ct_free(&r1);
        }
        ct_free(&rb);
        print_message("# 3 start/direction rays from a permuted CSV equal the "
                      "--start/--dir runs in every cell\n");
    }
}

static void test_output_file_and_text(void **state)
{
    const char *d = ct_design("sphere.json", SPHERE);
    const char *o = ct_path("out.json");
    ct_result r;
    FILE *f;
    char buf[65536];
    size_t n;
    cJSON *root;
    (void)state;
    ct_run(&r, "trace", d, "--ray", "0,1,0,1", "--format", "json", "-o", o, NULL);
    assert_int_equal(r.code, 0);
    assert_string_equal(r.out, "");
    ct_free(&r);
    f = fopen(o, "r");
    assert_non_null(f);
    n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    root = cJSON_Parse(buf);
    assert_non_null(root);
    assert_string_equal(cJSON_GetObjectItem(root, "method")->valuestring, "precise");
    assert_true(jnum(root, "wavelength_um") == 0.55);
    assert_int_equal((int)jnum(root, "wave"), 1);
    assert_true(jnum(cJSON_GetObjectItem(root, "input"), "py") == 1);
    cJSON_Delete(root);

    ct_run(&r, "trace", d, "--ray", "0,1,0,1", "--method", "mpfr", "--bits", "128", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "128"));
    assert_non_null(strstr(r.out, " OBJ "));
    assert_non_null(strstr(r.out, " IMA "));
    assert_non_null(strstr(r.out, "Residual"));
    assert_null(strstr(r.out, "nan"));
    ct_free(&r);
    print_message("# -o writes valid JSON (method, 0.55 um, wave 1, input echoed); "
                  "text names OBJ/IMA and the MPFR bits\n");
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slab_snell),
        cmocka_unit_test(test_sphere_intersection),
        cmocka_unit_test(test_miss),
        cmocka_unit_test(test_tir),
        cmocka_unit_test(test_batch_matches_single),
        cmocka_unit_test(test_output_file_and_text),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
