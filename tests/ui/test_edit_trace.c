/*
 * test_edit_trace.c - the editor's ray, chosen by its commands in batch
 * mode and exported, equals "sagitta trace" of the same ray value for
 * value.  The rays are asymmetric (Hx != 0, Hy != Py, Px != Py), so a
 * swapped or dropped coordinate shows.  "print ray" shows the editor's
 * live trace (what its screen shows), compared as text since the report
 * prints 16 digits.  argv[1] is the program.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

static char design[1024];

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *buf;
    long n;
    if (!f)
        fail_msg("cannot read %s", path);
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

/* The two CSV texts line by line, header included: both print %.17g, so
 * equal text is equal doubles in every column (whatever the columns are
 * called).  Returns the data rows compared. */
static int same_csv(const char *a, const char *b)
{
    int row = -1;
    for (;;) {
        const char *ea = strchr(a, '\n'), *eb = strchr(b, '\n');
        size_t la = ea ? (size_t)(ea - a) : strlen(a), lb = eb ? (size_t)(eb - b) : strlen(b);
        if (la != lb || memcmp(a, b, la) != 0)
            fail_msg("line %d differs:\neditor: %.*s\ntrace:  %.*s", row + 2, (int)la, a,
                     (int)lb, b);
        if (!ea || !eb) {
            assert_true(!ea && !eb);
            break;
        }
        a = ea + 1;
        b = eb + 1;
        if (!*a && !*b)
            break;
        row++;
    }
    return row + 1;
}

/* Runs the script (its export! replaces OUT) in the editor on the
 * Cassegrain, and compares with trace --ray r under the given method. */
static void check(const char *name, const char *script, const char *ray, const char *method)
{
    ct_result r, t;
    char *got;
    int rows;
    const char *sc = ct_file(name, script);
    ct_run(&r, "edit", design, "--batch", sc, (char *)NULL);
    if (r.code != 0)
        fail_msg("%s: edit --batch exit %d: %s", name, r.code, r.err);
    got = slurp(ct_path("out.csv"));
    ct_run(&t, "trace", design, "--ray", ray, "--method", method, "--format", "csv",
           (char *)NULL);
    assert_int_equal(t.code, 0);
    rows = same_csv(got, t.out);
    print_message("# %s: ray %s (%s): %d rows equal trace's\n", name, ray, method, rows);
    assert_int_equal(rows, 15);
    free(got);
    ct_free(&r);
    ct_free(&t);
}

static void ray_command(void **state)
{
    char s[1024];
    (void)state;
    snprintf(s, sizeof s, "ray 0.3 0.7 -0.4 0.2\nexport! %s csv\n", ct_path("out.csv"));
    check("ray.cmd", s, "0.3,0.7,-0.4,0.2", "precise");
    snprintf(s, sizeof s, "ray 0.3,-0.9,0.15,0.55\nexport! %s csv\n", ct_path("out.csv"));
    check("ray_commas.cmd", s, "0.3,-0.9,0.15,0.55", "precise");
}

static void coordinate_commands(void **state)
{
    char s[1024];
    (void)state;
    snprintf(s, sizeof s, "hx -0.5\nhy 0.25\npx 0.6\npy -0.1\nexport! %s csv\n",
             ct_path("out.csv"));
    check("coords.cmd", s, "-0.5,0.25,0.6,-0.1", "precise");
}

static void other_methods(void **state)
{
    char s[1024];
    (void)state;
    snprintf(s, sizeof s, "method classic\nray -0.2 0.8 0.45 -0.35\nexport! %s csv\n",
             ct_path("out.csv"));
    check("classic.cmd", s, "-0.2,0.8,0.45,-0.35", "classic");
    snprintf(s, sizeof s, "method mpfr\nray 0.6 -0.3 -0.1 0.7\nexport! %s csv\n",
             ct_path("out.csv"));
    check("mpfr.cmd", s, "0.6,-0.3,-0.1,0.7", "mpfr");
}

/* The table rows of a text report: from the "Surf" header on. */
static const char *table_of(const char *text)
{
    const char *p = strstr(text, "\nSurf ");
    if (!p)
        fail_msg("no table in:\n%s", text);
    return p;
}

/* "print ray" reports the editor's live trace (the one its screen shows,
 * not the export's batch): its table must equal trace's text table. */
static void live_trace(void **state)
{
    static const char *const rays[][2] = {
        {"ray 0.3 0.7 -0.4 0.2", "0.3,0.7,-0.4,0.2"},
        {"ray -0.45 0.15 0.35 -0.6", "-0.45,0.15,0.35,-0.6"},
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof rays / sizeof rays[0]; k++) {
        char sc[256];
        ct_result r, t;
        snprintf(sc, sizeof sc, "%s\nprint ray\n", rays[k][0]);
        ct_run(&r, "edit", design, "--batch", ct_file("live.cmd", sc), (char *)NULL);
        assert_int_equal(r.code, 0);
        ct_run(&t, "trace", design, "--ray", rays[k][1], (char *)NULL);
        assert_int_equal(t.code, 0);
        if (strcmp(table_of(r.out), table_of(t.out)) != 0)
            fail_msg("ray %s: the editor's live trace differs from trace:\n%s\nvs\n%s",
                     rays[k][1], table_of(r.out), table_of(t.out));
        print_message("# print ray after '%s': the table equals trace --ray %s\n", rays[k][0],
                      rays[k][1]);
        ct_free(&r);
        ct_free(&t);
    }
}

/* ":global" on a folded, tilted design: the live rows ("print ray") and
 * an export both equal "trace --global" of the same ray, for reference
 * surfaces 1 and 4; ":global off" gives the local rows back; a break
 * cannot be the reference. */
static void global_toggle(void **state)
{
    static const char *const refs[][2] = {{"global", "1"}, {"global 4", "4"}};
    const char *root = getenv("SAGITTA_SOURCE_ROOT");
    char fold[1024];
    size_t k;
    (void)state;
    snprintf(fold, sizeof fold, "%s/tests/fuzz/corpus/fuzz_design/fold_tilts.json",
             root ? root : ".");
    for (k = 0; k < sizeof refs / sizeof refs[0]; k++) {
        char sc[512], g[32];
        ct_result r, t;
        char *got;
        snprintf(sc, sizeof sc, "ray 0.3 0.7 -0.4 0.2\n%s\nprint ray\nexport! %s csv\n",
                 refs[k][0], ct_path("out.csv"));
        ct_run(&r, "edit", fold, "--batch", ct_file("global.cmd", sc), (char *)NULL);
        assert_int_equal(r.code, 0);
        snprintf(g, sizeof g, "--global=%s", refs[k][1]);
        ct_run(&t, "trace", fold, "--ray", "0.3,0.7,-0.4,0.2", g, (char *)NULL);
        assert_int_equal(t.code, 0);
        if (strcmp(table_of(r.out), table_of(t.out)) != 0)
            fail_msg("%s: the live rows differ from trace %s:\n%s\nvs\n%s", refs[k][0], g,
                     table_of(r.out), table_of(t.out));
        assert_non_null(strstr(r.out, "Coordinates are global"));
        ct_free(&t);
        ct_run(&t, "trace", fold, "--ray", "0.3,0.7,-0.4,0.2", g, "--format", "csv",
               (char *)NULL);
        got = slurp(ct_path("out.csv"));
        assert_int_equal(same_csv(got, t.out), 8);
        free(got);
        ct_free(&r);
        ct_free(&t);
    }
    {
        ct_result r, t;
        ct_run(&r, "edit", fold, "--batch",
               ct_file("local.cmd", "ray 0.3 0.7 -0.4 0.2\nglobal\nglobal off\nprint ray\n"),
               (char *)NULL);
        ct_run(&t, "trace", fold, "--ray", "0.3,0.7,-0.4,0.2", (char *)NULL);
        assert_int_equal(r.code, 0);
        assert_string_equal(table_of(r.out), table_of(t.out));
        ct_free(&r);
        ct_free(&t);
        ct_run(&r, "edit", fold, "--batch", ct_file("bad.cmd", "global 3\n"), (char *)NULL);
        assert_int_not_equal(r.code, 0);
        assert_non_null(strstr(r.err, "global reference surface 3 is a coordinate break"));
        ct_free(&r);
    }
}

/* The frame-change columns through a batch script: the folded, tilted
 * design of the fuzz corpus (fold_tilts.json, written by hand) is built
 * from its unfolded surfaces by "set" commands (coordinate breaks, a tilt
 * and decenter after surface 1 in order 1, a tilt before surface 6 with
 * "reverse" after, a tilt before the image), with an undo and redo on the
 * way; the editor's export and live rows must equal trace of the
 * hand-written file, number for number. */
static void batch_frames(void **state)
{
    static const char flat[] =
        "{\"fields\": {\"type\": \"angle\", \"list\": [{\"x\": 0, \"y\": 0}, {\"x\": 2, \"y\": 5}]},\n"
        " \"aperture\": {\"type\": \"epd\", \"value\": 10}, \"ray_aiming\": \"real\",\n"
        " \"surfaces\": [{\"thickness\": \"inf\"},\n"
        "  {\"radius\": 51.5, \"thickness\": 3.6, \"material\": 1.5168, \"stop\": true},\n"
        "  {\"thickness\": 40}, {}, {}, {}, {}, {}]}\n";
    static const char script[] =
        "set 1 adx 0.1\nset 1 aty 1\nset 1 aorder 1\n"
        "set 3 type COORDBRK\nset 3 tx 45\nset 4 material MIRROR\n"
        "set 5 type cb\nset 5 tx 45\nset 5 thickness -57.25\n"
        "set 6 radius -80\nset 6 thickness -5\nset 6 tx 3\nset 6 after reverse\n"
        "set 7 tz 10\nundo\nundo\nredo\nredo\n"
        "ray 0.3 0.7 -0.4 0.2\nprint ray\nexport! %s csv\n";
    const char *root = getenv("SAGITTA_SOURCE_ROOT");
    char fold[1024], sc[1024], start[1024];
    ct_result r, t;
    char *got;
    (void)state;
    snprintf(fold, sizeof fold, "%s/tests/fuzz/corpus/fuzz_design/fold_tilts.json",
             root ? root : ".");
    snprintf(start, sizeof start, "%s", ct_file("flat.json", flat));
    snprintf(sc, sizeof sc, script, ct_path("out.csv"));
    ct_run(&r, "edit", start, "--batch", ct_file("frames.cmd", sc), (char *)NULL);
    if (r.code != 0)
        fail_msg("edit --batch exit %d: %s", r.code, r.err);
    ct_run(&t, "trace", fold, "--ray", "0.3,0.7,-0.4,0.2", (char *)NULL);
    assert_int_equal(t.code, 0);
    if (strcmp(table_of(r.out), table_of(t.out)) != 0)
        fail_msg("the live rows differ from trace of the hand-written fold:\n%s\nvs\n%s",
                 table_of(r.out), table_of(t.out));
    ct_free(&t);
    ct_run(&t, "trace", fold, "--ray", "0.3,0.7,-0.4,0.2", "--format", "csv", (char *)NULL);
    assert_int_equal(t.code, 0);
    got = slurp(ct_path("out.csv"));
    assert_int_equal(same_csv(got, t.out), 8);
    print_message("# the fold built by set commands traces as fold_tilts.json: 8 rows equal\n");
    free(got);
    ct_free(&r);
    ct_free(&t);
    /* A bad value names the surface and the column, and stops the script. */
    ct_run(&r, "edit", start, "--batch", ct_file("bad.cmd", "set 3 type cb\nset 3 tx 400\n"),
           (char *)NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "surface 3 tx"));
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(global_toggle),
        cmocka_unit_test(ray_command),
        cmocka_unit_test(coordinate_commands),
        cmocka_unit_test(other_methods),
        cmocka_unit_test(live_trace),
        cmocka_unit_test(batch_frames),
    };
    const char *root = getenv("SAGITTA_SOURCE_ROOT");
    int rc;
    ct_init(argc, argv);
    snprintf(design, sizeof design, "%s/examples/cassegrain.json", root ? root : ".");
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
