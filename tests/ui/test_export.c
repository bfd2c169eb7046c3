/*
 * test_export.c - the editor's fan and grid exports: every row names its
 * ray (hx, hy, px, py) in CSV, JSON and text; an N by N grid is the cell
 * centres (2j + 1 - N) / N inside the pupil, so grid 2 is the four rays at
 * (+-0.5, +-0.5); a large export states its size and asks (batch mode:
 * refuses without export!); a cancelled export leaves no file.
 *
 * Independent references: the grid points and their count from integer
 * arithmetic here ((2j + 1 - N)^2 + (2i + 1 - N)^2 <= N^2), cJSON for the
 * JSON, and sg_trace_normalized() for every exported number of grid 2.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testutil.h"

#include "ed.h"

static char tmpdir[256];

static const char *tmp_path(const char *name, char *buf, size_t n)
{
    if (!tmpdir[0]) {
        snprintf(tmpdir, sizeof tmpdir, "%s/sg-export-test-XXXXXX",
                 getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
        assert_non_null(mkdtemp(tmpdir));
    }
    snprintf(buf, n, "%s/%s", tmpdir, name);
    return buf;
}

static ed *new_ed(void)
{
    char ex[1024], line[1200];
    ed *e = calloc(1, sizeof *e);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    e->batch = 1;
    e->out = tmpfile();
    assert_non_null(e->out);
    snprintf(line, sizeof line, "open %s", tu_path("examples/cassegrain.json", ex, sizeof ex));
    assert_false(cmd_exec(e, line) & ED_ERROR);
    assert_false(cmd_exec(e, "ray 0 1 0 0") & ED_ERROR);
    return e;
}

static void free_ed(ed *e)
{
    fclose(e->out);
    ed_free(e);
    free(e);
}

static int run(ed *e, const char *fmt, const char *path, const char *rest)
{
    char line[ED_LINE];
    snprintf(line, sizeof line, fmt, path, rest);
    return cmd_exec(e, line);
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *buf;
    long n;
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    rewind(f);
    buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

/* Grid points by integers: cell (i, j) of N is inside when
 * (2j + 1 - N)^2 + (2i + 1 - N)^2 <= N^2. */
static size_t grid_count(int n)
{
    size_t c = 0;
    int i, j;
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) {
            long a = 2L * j + 1 - n, b = 2L * i + 1 - n;
            c += a * a + b * b <= (long)n * n;
        }
    return c;
}

static void test_grid_counts(void **state)
{
    static const int ns[] = { 1, 2, 3, 4, 10, 11, 50 };
    char path[512], want[64];
    size_t k;
    (void)state;
    for (k = 0; k < sizeof ns / sizeof ns[0]; k++) {
        ed *e = new_ed();
        char n[16], name[32];
        snprintf(n, sizeof n, "grid %d", ns[k]);
        /* A file of its own each: export asks before replacing one. */
        snprintf(name, sizeof name, "count%d.csv", ns[k]);
        assert_false(run(e, "export %s csv %s", tmp_path(name, path, sizeof path), n) &
                     ED_ERROR);
        snprintf(want, sizeof want, "exported %zu ray%s", grid_count(ns[k]),
                 grid_count(ns[k]) == 1 ? "" : "s");
        if (!strstr(e->msg, want))
            fail_msg("grid %d: \"%s\", expected \"%s\"", ns[k], e->msg, want);
        free_ed(e);
    }
    assert_int_equal(grid_count(2), 4);
    print_message("# grid 1, 2, 3, 4, 10, 11, 50: %zu, %zu, %zu, %zu, %zu, %zu, %zu rays\n",
                  grid_count(1), grid_count(2), grid_count(3), grid_count(4), grid_count(10),
                  grid_count(11), grid_count(50));
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* grid 2 in CSV: each row starts with its ray, the pupil points are the
 * four cell centres, and the numbers equal the single-ray trace. */
static void test_grid2_csv(void **state)
{
    char path[512], *text, *line, *save = NULL;
    ed *e = new_ed();
    int nsurf = e->doc.sys->nsurf, rows = 0, seen[4] = { 0 };
    sg_ray_surface *ref = calloc((size_t)nsurf, sizeof *ref);
    sg_tracer *t;
    sg_diag d;
    (void)state;
    assert_false(run(e, "export %s %s", tmp_path("g2.csv", path, sizeof path), "grid 2") &
                 ED_ERROR);
    sg_diag_clear(&d);
    t = sg_tracer_new(e->doc.sys, e->cat, &e->opts, &d);
    assert_non_null(t);
    text = slurp(path);
    line = strtok_r(text, "\n", &save);
    assert_string_equal(line, "ray,hx,hy,px,py,surface,x,y,z,l,m,n,residual,error_bound,path,"
                              "status,opl,opl_error_bound,opd_waves,opd_error_bound,ex,ey");
    while ((line = strtok_r(NULL, "\n", &save))) {
        int r, s, q;
        double hx, hy, px, py, x, y, z;
        assert_int_equal(sscanf(line, "%d,%lf,%lf,%lf,%lf,%d,%lf,%lf,%lf", &r, &hx, &hy, &px,
                                &py, &s, &x, &y, &z),
                         9);
        assert_true(hx == 0.0 && hy == 1.0);
        assert_true(fabs(px) == 0.5 && fabs(py) == 0.5);
        q = (px > 0) + 2 * (py > 0);
        assert_int_equal(r, q); /* rows of py, then px, as the grid runs */
        seen[q]++;
        if (s == 0)
            assert_int_equal(sg_trace_normalized(t, hx, hy, px, py, ref), SG_OK);
        assert_true(same_bits(x, ref[s].x) && same_bits(y, ref[s].y) &&
                    same_bits(z, ref[s].z));
        rows++;
    }
    assert_int_equal(rows, 4 * nsurf);
    assert_true(seen[0] == nsurf && seen[1] == nsurf && seen[2] == nsurf && seen[3] == nsurf);
    print_message("# grid 2: 4 rays at (+-0.5, +-0.5), %d rows equal sg_trace_normalized()\n",
                  rows);
    free(text);
    free(ref);
    sg_tracer_free(t);
    free_ed(e);
}

/* export FILE.h5 writes sagitta trace's HDF5 table: its opd_waves column,
 * read back by h5dump, holds on each ray's image row the OPD the JSON
 * export gives (report.c's writer, another path), NaN on the other rows. */
static void test_fan_hdf5(void **state)
{
    char path[600], h5[512], cmd[2048], *text, *p;
    ed *e = new_ed();
    cJSON *j, *rays;
    double want[5];
    int k = 0, nnum = 0, nnan = 0;
    (void)state;
    if (system("h5dump --version >/dev/null 2>&1") != 0 && !(getenv("CI") && getenv("CI")[0])) {
        print_message("# SKIP h5dump not installed (hdf5-tools)\n");
        free_ed(e);
        return;
    }
    assert_false(run(e, "export %s %s", tmp_path("f.json", path, sizeof path), "fan 5") &
                 ED_ERROR);
    text = slurp(path);
    j = cJSON_Parse(text);
    assert_non_null(j);
    rays = cJSON_GetObjectItem(j, "rays");
    assert_int_equal(cJSON_GetArraySize(rays), 5);
    for (k = 0; k < 5; k++)
        want[k] = cJSON_GetObjectItem(cJSON_GetArrayItem(rays, k), "opd_waves")->valuedouble;
    cJSON_Delete(j);
    free(text);
    assert_false(run(e, "export %s %s", tmp_path("f.h5", h5, sizeof h5), "fan 5") & ED_ERROR);
    assert_non_null(strstr(e->msg, "exported 5 rays"));
    snprintf(cmd, sizeof cmd, "h5dump -d /opd_waves -y -w 0 -m %%.17g -o %s.txt %s >/dev/null",
             h5, h5);
    assert_int_equal(system(cmd), 0);
    snprintf(path, sizeof path, "%s.txt", h5);
    text = slurp(path);
    k = 0;
    for (p = strtok(text, ", \n"); p; p = strtok(NULL, ", \n")) {
        if (strcmp(p, "nan") == 0) {
            nnan++;
            continue;
        }
        assert_true(k < 5);
        if (strtod(p, NULL) != want[k])
            fail_msg("ray %d: HDF5 opd_waves %s, JSON %.17g", k, p, want[k]);
        k++;
        nnum++;
    }
    assert_int_equal(nnum, 5);
    assert_true(nnan > 0);
    free(text);
    free_ed(e);
}

/* A y fan in JSON and text carries each ray's coordinates too. */
static void test_fan_json_text(void **state)
{
    char path[512], *text;
    ed *e = new_ed();
    cJSON *j, *rays;
    int k;
    (void)state;
    assert_false(run(e, "export %s %s", tmp_path("fan.json", path, sizeof path), "fan 5") &
                 ED_ERROR);
    text = slurp(path);
    j = cJSON_Parse(text);
    assert_non_null(j);
    rays = cJSON_GetObjectItem(j, "rays");
    assert_int_equal(cJSON_GetArraySize(rays), 5);
    for (k = 0; k < 5; k++) {
        cJSON *in = cJSON_GetObjectItem(cJSON_GetArrayItem(rays, k), "input");
        assert_non_null(in);
        assert_true(cJSON_GetObjectItem(in, "hy")->valuedouble == 1.0);
        assert_true(cJSON_GetObjectItem(in, "px")->valuedouble == 0.0);
        assert_true(cJSON_GetObjectItem(in, "py")->valuedouble == -1.0 + 0.5 * k);
    }
    cJSON_Delete(j);
    free(text);
    assert_false(run(e, "export %s %s", tmp_path("x.txt", path, sizeof path), "xfan 3") &
                 ED_ERROR);
    text = slurp(path);
    assert_non_null(strstr(text, "Ray         : Hx = 0, Hy = 1, Px = -1, Py = 0\n"));
    assert_non_null(strstr(text, "Ray         : Hx = 0, Hy = 1, Px = 0, Py = 0\n"));
    assert_non_null(strstr(text, "Ray         : Hx = 0, Hy = 1, Px = 1, Py = 0\n"));
    free(text);
    free_ed(e);
}

/* The single ray's CSV export names its ray as a fan's does (the launch in
 * its shortest decimal, as typed), and the JSON's wavelength is the
 * design's number as written, not its %.17g expansion: the shortest of
 * %.1g ... %.17g that strtod reads back, found here by printf. */
static void test_single_ray_inputs(void **state)
{
    char path[512], want[128], *text, *line, *save = NULL;
    ed *e = new_ed();
    int nsurf = e->doc.sys->nsurf, rows = 0, prec;
    double um = e->doc.sys->wave[e->doc.sys->primary_wave].um;
    (void)state;
    assert_false(cmd_exec(e, "ray 0 0.7 0.3 -0.2") & ED_ERROR);
    assert_false(run(e, "export %s%s", tmp_path("one.csv", path, sizeof path), "") & ED_ERROR);
    text = slurp(path);
    line = strtok_r(text, "\n", &save);
    assert_string_equal(line, "hx,hy,px,py,surface,x,y,z,l,m,n,residual,error_bound,path,"
                              "status,opl,opl_error_bound,opd_waves,opd_error_bound,ex,ey");
    while ((line = strtok_r(NULL, "\n", &save))) {
        snprintf(want, sizeof want, "0,0.7,0.3,-0.2,%d,", rows);
        if (strncmp(line, want, strlen(want)) != 0)
            fail_msg("row %d: \"%.60s\", expected it to begin \"%s\"", rows, line, want);
        rows++;
    }
    assert_int_equal(rows, nsurf);
    free(text);
    assert_false(run(e, "export %s%s", tmp_path("one.json", path, sizeof path), "") & ED_ERROR);
    text = slurp(path);
    for (prec = 1; prec <= 17; prec++) {
        char b[40];
        snprintf(b, sizeof b, "%.*g", prec, um);
        if (strtod(b, NULL) == um) {
            snprintf(want, sizeof want, "\"wavelength_um\": %s,", b);
            break;
        }
    }
    if (!strstr(text, want))
        fail_msg("the JSON export lacks %s", want);
    print_message("# single ray CSV: %d rows beginning 0,0.7,0.3,-0.2; JSON has %s\n", rows,
                  want);
    free(text);
    free_ed(e);
}

/* grid 1001 would write gigabytes: batch mode refuses with the size, the
 * screen asks (y runs export!), and no file appears until then. */
static void test_large_asks(void **state)
{
    char path[512];
    struct stat st;
    char want[64];
    ed *e = new_ed();
    int f;
    (void)state;
    f = run(e, "export %s %s", tmp_path("big.csv", path, sizeof path), "grid 1001");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "would take about"));
    snprintf(want, sizeof want, "GB (%zu rays)", grid_count(1001));
    assert_non_null(strstr(e->msg, want));
    assert_non_null(strstr(e->msg, "export!"));
    assert_int_not_equal(stat(path, &st), 0);
    print_message("# batch: %s\n", e->msg);
    e->batch = 0;
    f = run(e, "export %s %s", path, "grid 1001");
    assert_true(f & ED_CONFIRM);
    assert_int_equal(e->confirm, CONFIRM_WRITE);
    snprintf(want, sizeof want, "%zu rays, about ", grid_count(1001));
    assert_non_null(strstr(e->question, want));
    assert_non_null(strstr(e->question, "Write it? (y)es (n)o"));
    assert_true(strncmp(e->pending, "export! ", 8) == 0);
    assert_int_not_equal(stat(path, &st), 0);
    print_message("# screen: %s\n", e->question);
    e->confirm = CONFIRM_NONE;
    e->batch = 1;
    free_ed(e);
}

static int calls;

/* Cancels at the second block, as Esc would. */
static int cancel_soon(void *ctx, const char *what, size_t done, size_t total)
{
    (void)ctx;
    (void)what;
    (void)total;
    return done > 0 && ++calls >= 2;
}

static void test_cancel_leaves_no_file(void **state)
{
    char path[512], *text;
    struct stat st;
    ed *e = new_ed();
    FILE *f;
    (void)state;
    e->progress = cancel_soon;
    calls = 0;
    /* A new file: none appears. */
    assert_false(run(e, "export %s %s", tmp_path("c.csv", path, sizeof path), "grid 151") &
                 ED_ERROR);
    assert_non_null(strstr(e->msg, "export cancelled after"));
    assert_int_not_equal(stat(path, &st), 0);
    /* An existing file: it keeps its bytes. */
    f = fopen(path, "w");
    assert_non_null(f);
    fputs("old\n", f);
    fclose(f);
    calls = 0;
    /* export! replaces it, as the yes to export's question does. */
    assert_false(run(e, "export! %s %s", path, "grid 151") & ED_ERROR);
    text = slurp(path);
    assert_string_equal(text, "old\n");
    free(text);
    print_message("# %s\n", e->msg);
    /* Not cancelled, the same export completes. */
    e->progress = NULL;
    assert_false(run(e, "export! %s %s", path, "grid 151") & ED_ERROR);
    assert_non_null(strstr(e->msg, "exported"));
    free_ed(e);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static void same_text(const char *path, const char *want)
{
    char *text = slurp(path);
    assert_string_equal(text, want);
    free(text);
}

/* Issue 30, item 2: export never replaces the open design's file (by any
 * name: its own, a symbolic or a hard link, found by device and inode),
 * and replaces another existing file only when asked: the editor asks,
 * and yes runs export!; batch mode refuses without export!.  A device
 * (/dev/null) holds nothing to lose and is written. */
static void test_export_replaces(void **state)
{
    char ex[1024], design[512], other[512], alias[512], hard[512], png[512], line[1200];
    char *orig, *text;
    ed *e = new_ed();
    const char *names[3];
    int k, f;
    (void)state;
    orig = slurp(tu_path("examples/singlet.json", ex, sizeof ex));
    write_text(tmp_path("d.json", design, sizeof design), orig);
    snprintf(line, sizeof line, "open %s", design);
    assert_false(cmd_exec(e, line) & ED_ERROR);
    assert_int_equal(symlink(design, tmp_path("alias.json", alias, sizeof alias)), 0);
    assert_int_equal(link(design, tmp_path("hard.json", hard, sizeof hard)), 0);
    names[0] = design;
    names[1] = alias;
    names[2] = hard;
    for (k = 0; k < 3; k++) {
        f = run(e, "export %s %s", names[k], "fan 5");
        assert_true(f & ED_ERROR);
        assert_non_null(strstr(e->msg, "open design's file"));
        f = run(e, "export! %s %s", names[k], "csv");
        assert_true(f & ED_ERROR);
        same_text(design, orig);
        print_message("# %s\n", e->msg);
    }
    /* Nor does the editor offer to. */
    e->batch = 0;
    f = run(e, "export %s %s", design, "ray");
    assert_true(f & ED_ERROR);
    assert_false(f & ED_CONFIRM);
    e->batch = 1;
    same_text(design, orig);

    /* Another file: batch mode refuses and names export!. */
    write_text(tmp_path("other.csv", other, sizeof other), "keep\n");
    f = run(e, "export %s %s", other, "fan 5");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "export!"));
    assert_non_null(strstr(e->msg, "already exists"));
    same_text(other, "keep\n");
    print_message("# %s\n", e->msg);
    /* The editor asks; the answer's command replaces it. */
    e->batch = 0;
    f = run(e, "export %s %s", other, "fan 5");
    assert_true(f & ED_CONFIRM);
    assert_int_equal(e->confirm, CONFIRM_WRITE);
    assert_non_null(strstr(e->question, "Replace it?"));
    assert_int_equal(strncmp(e->pending, "export! ", 8), 0);
    same_text(other, "keep\n");
    print_message("# %s -> yes runs: %s\n", e->question, e->pending);
    e->confirm = CONFIRM_NONE;
    f = cmd_exec(e, e->pending);
    assert_false(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "exported 5 rays"));
    text = slurp(other);
    assert_int_equal(strncmp(text, "ray,hx,hy,px,py,", 16), 0);
    free(text);
    e->batch = 1;
    /* A device is written without a question. */
    f = cmd_exec(e, "export /dev/null csv fan 5");
    assert_false(f & ED_ERROR);
    /* A picture: the same rules. */
    assert_false(cmd_exec(e, "view layout") & ED_ERROR);
    write_text(tmp_path("v.png", png, sizeof png), "keep\n");
    f = run(e, "export %s %s", png, "png");
    assert_true(f & ED_ERROR);
    same_text(png, "keep\n");
    f = run(e, "export! %s %s", design, "png");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "open design's file"));
    same_text(design, orig);
    f = run(e, "export! %s %s", png, "png");
    assert_false(f & ED_ERROR);
    text = slurp(png);
    assert_int_equal(memcmp(text, "\x89PNG", 4), 0);
    free(text);
    free(orig);
    free_ed(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_counts),
        cmocka_unit_test(test_grid2_csv),
        cmocka_unit_test(test_fan_hdf5),
        cmocka_unit_test(test_fan_json_text),
        cmocka_unit_test(test_large_asks),
        cmocka_unit_test(test_cancel_leaves_no_file),
        cmocka_unit_test(test_export_replaces),
        cmocka_unit_test(test_single_ray_inputs),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[400];
    if (tmpdir[0]) {
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
        if (system(cmd) != 0)
            rc = rc ? rc : 1;
    }
    return rc;
}
