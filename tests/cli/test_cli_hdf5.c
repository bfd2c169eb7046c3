/* test_cli_hdf5.c - "trace --rays --format hdf5" read back by h5dump (the
 * HDF5 project's own reader) against the CSV written for the same rays by
 * report.c, an independent writer: every column, every row, bit for bit. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

static char examples[1024];
static int have_h5dump;

static const char *example(const char *file)
{
    static char buf[4][1100];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", examples, file);
    return buf[k];
}

/* The whole output of a command, or NULL. */
static char *slurp_cmd(const char *cmd)
{
    FILE *p = popen(cmd, "r");
    char *buf = NULL;
    size_t len = 0, cap = 0, got;
    if (!p)
        return NULL;
    do {
        if (len + 65536 + 1 > cap) {
            cap = 2 * cap + 65536 + 1;
            buf = realloc(buf, cap);
            assert_non_null(buf);
        }
        got = fread(buf + len, 1, 65536, p);
        len += got;
    } while (got > 0);
    buf[len] = '\0';
    if (pclose(p) != 0) {
        free(buf);
        return NULL;
    }
    return buf;
}

/* One dataset's values as h5dump prints them (-y -w 0, %.17g), split. */
static char **h5_column(const char *file, const char *name, size_t *n)
{
    char cmd[4096], *text, *p, **v = NULL;
    size_t cap = 0;
    const char *data = ct_path("column.txt");
    snprintf(cmd, sizeof cmd, "h5dump -d /%s -y -w 0 -m %%.17g -o %s %s >/dev/null && cat %s",
             name, data, file, data);
    text = slurp_cmd(cmd);
    assert_non_null(text);
    *n = 0;
    /* Values are separated by ", "; a status name may hold a space. */
    for (p = strtok(text, ",\n"); p; p = strtok(NULL, ",\n")) {
        while (*p == ' ')
            p++;
        if (!*p)
            continue;
        if (*n == cap) {
            cap = cap ? 2 * cap : 1024;
            v = realloc(v, cap * sizeof *v);
            assert_non_null(v);
        }
        v[(*n)++] = strdup(p);
    }
    free(text);
    return v;
}

static void free_column(char **v, size_t n)
{
    size_t k;
    for (k = 0; k < n; k++)
        free(v[k]);
    free(v);
}

/* A ray list with rays inside and outside the pupil, so some surfaces
 * fail and their numbers are NaN in HDF5, empty in CSV. */
static const char *ray_list(int n)
{
    char *text = malloc((size_t)n * 100 + 64), *p = text;
    const char *path;
    int k;
    p += sprintf(p, "hx,hy,px,py\n");
    for (k = 0; k < n; k++)
        p += sprintf(p, "%.17g,%.17g,%.17g,%.17g\n", (k % 7) / 7.0 - 0.4, (k % 5) / 5.0,
                     1.3 * sin(k * 0.37), 1.3 * cos(k * 0.53));
    path = ct_file("rays.csv", text);
    free(text);
    return path;
}

/* surfaces, when given, is a --surface list for both runs. */
static void compare(const char *design, const char *method, int nray, const char *block,
                    const char *surfaces)
{
    /* NULL: the bound's column, named as the method's (classic: an estimate);
     * "~" prefixes the same for opl and opd. */
    static const char *const cols[] = { "ray", "hx", "hy", "px", "py", "surface", "x",
                                        "y", "z", "l", "m", "n", "residual", NULL, "path",
                                        "status", "opl", "~opl_", "opd_waves", "~opd_",
                                        "ex", "ey" };
    const char *est = strcmp(method, "classic") == 0 ? "error_estimate" : "error_bound";
    const char *rays = ray_list(nray), *h5 = ct_path("out.h5");
    ct_result csv, r;
    size_t c, rows = 0;
    char buf[64], *attrs;
    if (block)
        setenv("SAGITTA_RAYS_BLOCK", block, 1);
    else
        unsetenv("SAGITTA_RAYS_BLOCK");
    ct_run(&csv, "trace", design, "--method", method, "--rays", rays, "--format", "csv",
           surfaces ? "--surface" : (char *)NULL, surfaces, (char *)NULL);
    if (csv.code != 0)
        fail_msg("trace: %s", csv.err);
    ct_run(&r, "trace", design, "--method", method, "--rays", rays, "--format", "hdf5",
           "-o", h5, surfaces ? "--surface" : (char *)NULL, surfaces, (char *)NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    for (c = 0; c < sizeof cols / sizeof cols[0]; c++) {
        char nm[64];
        const char *name = nm, *csvname;
        if (!cols[c])
            snprintf(nm, sizeof nm, "%s", est);
        else if (cols[c][0] == '~')
            snprintf(nm, sizeof nm, "%s%s", cols[c] + 1, est);
        else
            snprintf(nm, sizeof nm, "%s", cols[c]);
        csvname = c >= 1 && c <= 4 ? NULL : name;
        size_t n, k;
        char **v = h5_column(h5, name, &n);
        if (c == 0)
            rows = n;
        if (n != rows)
            fail_msg("column %s: %zu rows, ray column %zu", name, n, rows);
        for (k = 0; k < n; k++) {
            const char *want;
            /* The launch is not a CSV column here: test_hdf5_inputs. */
            if (!csvname)
                break;
            want = ct_csv(csv.out, (int)k, csvname, buf, sizeof buf);
            assert_non_null(want);
            if (c == 15) {
                assert_string_equal(v[k], want);
            } else if (want[0] == '\0') {
                assert_string_equal(v[k], "nan");
            } else {
                double a = strtod(v[k], NULL), b = strtod(want, NULL);
                if (memcmp(&a, &b, sizeof a) != 0)
                    fail_msg("%s row %zu: h5dump %s, CSV %s", name, k, v[k], want);
            }
        }
        free_column(v, n);
    }
    assert_true(surfaces ? rows > 0 : rows > (size_t)nray);
    /* The settings, as attributes. */
    {
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "h5dump -A %s", h5);
        attrs = slurp_cmd(cmd);
        assert_non_null(attrs);
        assert_non_null(strstr(attrs, method));
        assert_non_null(strstr(attrs, "ATTRIBUTE \"wavelength_um\""));
        assert_non_null(strstr(attrs, "ATTRIBUTE \"sagitta_version\""));
        assert_non_null(strstr(attrs, "ATTRIBUTE \"units\""));
        assert_non_null(strstr(attrs, design));
        free(attrs);
    }
    ct_free(&csv);
    unsetenv("SAGITTA_RAYS_BLOCK");
}

static void test_hdf5_matches_csv(void **state)
{
    (void)state;
    if (!have_h5dump) {
        print_message("# SKIP h5dump not installed (hdf5-tools)\n");
        return;
    }
    compare(example("cassegrain.json"), "precise", 300, NULL, NULL);
    /* Blocks of 7 rays: the datasets grow across many blocks. */
    compare(example("cooke_triplet.json"), "classic", 200, "7", NULL);
    /* Chosen surfaces (test_cli_surface checks the CSV's rows against
     * the full table's). */
    compare(example("cassegrain.json"), "precise", 300, "7", "IMA");
    compare(example("cooke_triplet.json"), "classic", 200, NULL, "1,STO-4,IMA");
}

/* The launch columns against the list itself. */
static void test_hdf5_inputs(void **state)
{
    const char *rays, *h5 = ct_path("in.h5");
    ct_result r;
    size_t n;
    char **v;
    (void)state;
    if (!have_h5dump) {
        print_message("# SKIP h5dump not installed (hdf5-tools)\n");
        return;
    }
    rays = ct_file("in.csv", "hx,hy,px,py\n0,0.5,0.25,-0.125\n0.1,0,0,0.3\n");
    ct_run(&r, "trace", example("singlet.json"), "--rays", rays, "--format", "hdf5", "-o",
           h5, (char *)NULL);
    if (r.code != 0)
        fail_msg("trace: %s", r.err);
    ct_free(&r);
    v = h5_column(h5, "py", &n);
    assert_int_equal(n, 8); /* 2 rays, 4 surfaces */
    assert_string_equal(v[0], "-0.125");
    assert_string_equal(v[3], "-0.125");
    assert_string_equal(v[4], "0.29999999999999999");
    free_column(v, n);
}

static void test_hdf5_needs_file(void **state)
{
    const char *rays = ct_file("one.csv", "hx,hy,px,py\n0,0,0,0\n");
    ct_result r;
    (void)state;
    ct_run(&r, "trace", example("singlet.json"), "--rays", rays, "--format", "hdf5",
           (char *)NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--output"));
    ct_free(&r);
    ct_run(&r, "trace", example("singlet.json"), "--ray", "0,0,0,0", "--format", "hdf5",
           "-o", ct_path("x.h5"), (char *)NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "--rays"));
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const char *e = getenv("SAGITTA_EXAMPLES");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hdf5_matches_csv),
        cmocka_unit_test(test_hdf5_inputs),
        cmocka_unit_test(test_hdf5_needs_file),
    };
    int rc;
    ct_init(argc, argv);
    snprintf(examples, sizeof examples, "%s", e && *e ? e : "examples");
    have_h5dump = system("h5dump --version >/dev/null 2>&1") == 0;
    if (!have_h5dump && getenv("CI") && getenv("CI")[0])
        have_h5dump = 1; /* CI installs hdf5-tools: a missing one fails */
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
