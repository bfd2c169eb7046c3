/* test_verify_grid.c - the figures of "sagitta verify DESIGN --grid N",
 * which traces its rays a block at a time and keeps only each compared
 * point's digits, equal those computed here from every ray's rows.
 *
 * The rows come from another command, "sagitta trace --rays" of the same
 * rays by each method (CSV, %.17g); the ray set, the digits and the
 * medians are computed here from their definitions in sagitta(1): the
 * double Gauss's field points 0, 6 and 9 degrees with radial
 * normalization are hy = 0, 6/9 and 1; the N x N pupil grid clipped to
 * the unit circle, then the chief and the four marginal rays it lacks;
 * per coordinate -log10(|a - b| / max(|b|, 1e-6 max|b_k|)), 17 when
 * equal, a point the least of its three, and a reference point at the
 * origin judged against 1e-6 of the largest reference point of its
 * surface; the median of an even count the mean of the middle two. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

enum { NSURF = 17, MAXRAY = 512, NM = 3 };
static const char *const mname[NM] = { "precise", "classic", "mpfr" };

static char examples[1024];

typedef struct rows {
    double p[MAXRAY][NSURF][3];
    int ok[MAXRAY]; /* the ray reached the image */
} rows;

static size_t ray_set(int grid, double (*h)[4])
{
    static const double field[3] = { 0.0, 6.0 / 9.0, 1.0 };
    static const double extra[5][2] = { { 0, 0 }, { 0, 1 }, { 0, -1 }, { 1, 0 }, { -1, 0 } };
    double pp[MAXRAY][2];
    size_t np = 0, n = 0, j, f;
    int i, k;
    for (i = 0; i < grid; i++)
        for (k = 0; k < grid; k++) {
            double px = (2.0 * k - (grid - 1)) / (double)(grid - 1);
            double py = (2.0 * i - (grid - 1)) / (double)(grid - 1);
            if (px * px + py * py <= 1.0 + 1e-12) {
                pp[np][0] = px;
                pp[np][1] = py;
                np++;
            }
        }
    for (k = 0; k < 5; k++) {
        for (j = 0; j < np; j++)
            if (pp[j][0] == extra[k][0] && pp[j][1] == extra[k][1])
                break;
        if (j == np) {
            pp[np][0] = extra[k][0];
            pp[np][1] = extra[k][1];
            np++;
        }
    }
    for (f = 0; f < 3; f++)
        for (j = 0; j < np; j++, n++) {
            h[n][0] = 0.0;
            h[n][1] = field[f];
            h[n][2] = pp[j][0];
            h[n][3] = pp[j][1];
        }
    return n;
}

/* Every ray's rows by one method, from trace --rays as CSV. */
static void trace_rows(const char *design, const char *rays, const char *method, size_t nray,
                       rows *out)
{
    ct_result r;
    const char *line;
    size_t got = 0;
    ct_run(&r, "trace", design, "--rays", rays, "--method", method, "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    line = strchr(r.out, '\n'); /* the header */
    assert_non_null(line);
    for (line++; *line; got++) {
        char *end;
        long ray = strtol(line, &end, 10), s;
        const char *st;
        int k;
        /* The launch columns hx, hy, px, py follow the ray's number. */
        for (k = 0; k < 4; k++)
            end = strchr(end + 1, ',');
        assert_non_null(end);
        s = strtol(end + 1, &end, 10);
        assert_true(ray >= 0 && (size_t)ray < nray && s >= 0 && s < NSURF);
        for (k = 0; k < 3; k++)
            out->p[ray][s][k] = strtod(end + 1, &end);
        /* end is at the comma before l; the status follows path's. */
        st = end;
        for (k = 0; k < 6; k++)
            st = strchr(st + 1, ',');
        assert_non_null(st);
        if (s == NSURF - 1)
            out->ok[ray] = strncmp(st + 1, "OK", 2) == 0;
        line = strchr(line, '\n');
        if (!line)
            break;
        line++;
    }
    assert_int_equal(got, nray * NSURF);
    ct_free(&r);
}

static double coord_digits(double a, double b, double size)
{
    double e, den, d;
    if (a == b)
        return 17.0;
    e = fabs(a - b);
    den = fmax(fabs(b), 1e-6 * size);
    if (!(den > 0.0) || !isfinite(e))
        return 0.0;
    d = -log10(e / den);
    return d < 0.0 ? 0.0 : d > 17.0 ? 17.0 : d;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double json_num(cJSON *o, const char *a, const char *b)
{
    cJSON *v = cJSON_GetObjectItem(cJSON_GetObjectItem(o, a), b);
    assert_true(cJSON_IsNumber(v));
    return v->valuedouble;
}

static void check_grid(int grid)
{
    static double h[MAXRAY][4];
    static rows tr[NM];
    static double dig[MAXRAY];
    char design[1200], *csv;
    size_t nray = ray_set(grid, h), len = 0, r, n;
    const char *rays;
    ct_result v;
    cJSON *root, *surf, *e;
    int m, i, k, checked = 0;

    snprintf(design, sizeof design, "%s/double_gauss.json", examples);
    csv = malloc(nray * 100 + 32);
    assert_non_null(csv);
    len += (size_t)sprintf(csv, "hx,hy,px,py\n");
    for (r = 0; r < nray; r++)
        len += (size_t)sprintf(csv + len, "%.17g,%.17g,%.17g,%.17g\n", h[r][0], h[r][1],
                               h[r][2], h[r][3]);
    rays = ct_file("grid_rays.csv", csv);
    free(csv);
    for (m = 0; m < NM; m++)
        trace_rows(design, rays, mname[m], nray, &tr[m]);

    ct_run(&v, "verify", design, "--grid", grid == 4 ? "4" : "7", "--format", "json", NULL);
    assert_int_equal(v.code, 0);
    root = cJSON_Parse(v.out);
    assert_non_null(root);
    assert_int_equal((int)cJSON_GetObjectItem(cJSON_GetObjectItem(root, "rays"), "total")
                         ->valuedouble,
                     (int)nray);
    surf = cJSON_GetObjectItem(root, "surfaces");
    cJSON_ArrayForEach(e, surf) {
        double scale = 0.0;
        i = (int)cJSON_GetObjectItem(e, "surface")->valuedouble;
        assert_true(i >= 1 && i < NSURF);
        for (r = 0; r < nray; r++)
            if (tr[2].ok[r])
                for (k = 0; k < 3; k++)
                    scale = fmax(scale, fabs(tr[2].p[r][i][k]));
        for (m = 0; m < 2; m++) {
            double dmin, dmed;
            for (r = 0, n = 0; r < nray; r++) {
                const double *a = tr[m].p[r][i], *b = tr[2].p[r][i];
                double size = fmax(fabs(b[0]), fmax(fabs(b[1]), fabs(b[2]))), d = 17.0;
                if (!tr[m].ok[r] || !tr[2].ok[r])
                    continue;
                if (!(size > 0.0))
                    size = scale;
                for (k = 0; k < 3; k++)
                    d = fmin(d, coord_digits(a[k], b[k], size));
                dig[n++] = d;
            }
            assert_true(n > 0);
            qsort(dig, n, sizeof *dig, cmp);
            dmin = dig[0];
            dmed = n % 2 ? dig[n / 2] : 0.5 * (dig[n / 2 - 1] + dig[n / 2]);
            assert_int_equal((long)json_num(e, mname[m], "rays"), (long)n);
            if (fabs(json_num(e, mname[m], "digits_min") - dmin) > 1e-12 ||
                fabs(json_num(e, mname[m], "digits_median") - dmed) > 1e-12)
                fail_msg("surface %d %s: verify's digits min %.17g median %.17g, here %.17g "
                         "and %.17g", i, mname[m], json_num(e, mname[m], "digits_min"),
                         json_num(e, mname[m], "digits_median"), dmin, dmed);
            checked++;
        }
    }
    assert_int_equal(checked, 2 * (NSURF - 1));
    cJSON_Delete(root);
    ct_free(&v);
    print_message("# verify --grid %d: %zu rays, digits min and median of %d surfaces "
                  "as computed here\n", grid, nray, NSURF - 1);
}

static void test_grid4(void **state)
{
    (void)state;
    check_grid(4);
}

static void test_grid7(void **state)
{
    (void)state;
    check_grid(7);
}

int main(int argc, char **argv)
{
    const char *e = getenv("SAGITTA_EXAMPLES");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid4),
        cmocka_unit_test(test_grid7),
    };
    int rc;
    snprintf(examples, sizeof examples, "%s", e && *e ? e : "examples");
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
