/*
 * test_merit_cmd.c - the Merit Function Editor's commands without a
 * screen: merit insert, set, delete and default edit the design's merit
 * function as one undoable change each, a row the design cannot serve is
 * refused with the design unchanged, and the values are Zemax's.
 *
 * Independent references: the thick lens's focal length from its closed
 * form, 1/f = (n - 1) (1/R1 - 1/R2 + (n - 1) t / (n R1 R2)); TTHI as the
 * sum of the thicknesses written in the design; Zemax's merit function
 * MF^2 = sum w (v - t)^2 / sum w computed here by hand; the saved file
 * read back by cJSON.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "testutil.h"

#include "doc.h"
#include "ed.h"

#define R1 60.0
#define R2 (-80.0)
#define T1 5.0
#define N1 1.5

static const char design[] =
    "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 2}]},"
    "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
    "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
    "{\"radius\": 60, \"thickness\": 5, \"material\": 1.5, \"stop\": true},"
    "{\"radius\": -80, \"thickness\": 45},"
    "{\"radius\": \"inf\", \"thickness\": 0}]}";

static void ok(ed *e, const char *line)
{
    int f = cmd_exec(e, line);
    if (f & ED_ERROR)
        fail_msg("\"%s\" failed: %s", line, e->msg);
}

static double thick_lens_efl(void)
{
    double p = (N1 - 1.0) * (1.0 / R1 - 1.0 / R2 + (N1 - 1.0) * T1 / (N1 * R1 * R2));
    return 1.0 / p;
}

/* The merit value and row values "merit list" prints in batch mode. */
static double listed(ed *e, double *v, int max, int *n)
{
    char line[256];
    double mf = NAN;
    *n = 0;
    ok(e, "merit list");
    rewind(e->out);
    while (fgets(line, sizeof line, e->out)) {
        int row;
        char type[16];
        double t, w, val, c;
        if (sscanf(line, "merit %lf", &mf) == 1)
            continue;
        if (sscanf(line, "%d %15s %lf %lf %lf %lf", &row, type, &t, &w, &val, &c) == 6 &&
            *n < max)
            v[(*n)++] = val;
    }
    rewind(e->out);
    if (ftruncate(fileno(e->out), 0) != 0)
        fail_msg("cannot empty the batch output");
    return mf;
}

static void merit_edits(void **state)
{
    char path[256], out[300], line[360];
    FILE *f;
    ed *e = calloc(1, sizeof *e);
    sg_system *before;
    double v[64], mf, efl = thick_lens_efl(), want;
    int n;
    cJSON *root, *ops;
    char *text;
    (void)state;
    snprintf(path, sizeof path, "%s/sg-merit-test-%d.json",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (int)getpid());
    snprintf(out, sizeof out, "%s.saved.json", path);
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(design, f);
    fclose(f);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    e->batch = 1;
    e->out = tmpfile();
    snprintf(line, sizeof line, "open %s", path);
    ok(e, line);

    /* EFFL at wavelength 1, target 100: its value is the closed form, and a
     * lone row's MF is |v - t|. */
    ok(e, "merit insert 1 EFFL");
    ok(e, "merit set 1 int2 1");
    ok(e, "merit set 1 target 100");
    ok(e, "merit set 1 weight 1");
    mf = listed(e, v, 64, &n);
    assert_int_equal(n, 1);
    print_message("# EFFL %.17g, closed form %.17g\n", v[0], efl);
    assert_true(fabs(v[0] - efl) <= 1e-12 * efl);
    assert_true(fabs(mf - fabs(efl - 100.0)) <= 1e-12 * 100.0);

    /* TTHI 1 to 2, target 6, weight 3, appended: the thicknesses' sum, and
     * MF^2 = sum w (v - t)^2 / sum w. */
    before = sg_system_clone(e->doc.sys);
    ok(e, "merit insert 2 TTHI");
    ok(e, "merit set 2 int1 1 int2 2 target 6");
    ok(e, "merit set 2 weight 3");
    mf = listed(e, v, 64, &n);
    assert_int_equal(n, 2);
    assert_true(fabs(v[1] - (T1 + 45.0)) <= 1e-13 * 50.0);
    want = sqrt((1.0 * (efl - 100.0) * (efl - 100.0) + 3.0 * (50.0 - 6.0) * (50.0 - 6.0)) / 4.0);
    assert_true(fabs(mf - want) <= 1e-12 * want);

    /* Refused, the design unchanged: a surface the design lacks, a weight
     * below 0, a pupil coordinate outside -1 to 1, an unknown operand. */
    {
        sg_system *mid = sg_system_clone(e->doc.sys);
        assert_true(cmd_exec(e, "merit set 2 int2 9") & ED_ERROR);
        print_message("# refused: %s\n", e->msg);
        assert_non_null(strstr(e->msg, "operand 2"));
        assert_non_null(strstr(e->msg, "nothing changed"));
        assert_true(cmd_exec(e, "merit set 2 weight -1") & ED_ERROR);
        assert_true(cmd_exec(e, "merit set 1 type TRAY py 1.5") & ED_ERROR);
        assert_true(cmd_exec(e, "merit set 1 type NOPE") & ED_ERROR);
        assert_true(cmd_exec(e, "merit delete 3") & ED_ERROR);
        assert_true(sg_system_equal(e->doc.sys, mid));
        sg_system_free(mid);
    }

    /* Delete row 1: TTHI is row 1; undo brings EFFL back, every bit. */
    {
        sg_system *two = sg_system_clone(e->doc.sys);
        ok(e, "merit delete 1");
        assert_int_equal(e->doc.sys->merit.nop, 1);
        assert_int_equal(e->doc.sys->merit.op[0].type, SG_OP_TTHI);
        ok(e, "undo");
        assert_true(sg_system_equal(e->doc.sys, two));
        sg_system_free(two);
    }
    /* Three undos return the design before TTHI. */
    {
        int k;
        for (k = 0; k < 3; k++)
            ok(e, "undo");
        assert_true(sg_system_equal(e->doc.sys, before));
        for (k = 0; k < 3; k++)
            ok(e, "redo");
    }
    sg_system_free(before);

    /* Inserted before row 1: the rows below move down, whole. */
    ok(e, "merit insert 1 CONS");
    assert_int_equal(e->doc.sys->merit.nop, 3);
    assert_int_equal(e->doc.sys->merit.op[0].type, SG_OP_CONS);
    assert_int_equal(e->doc.sys->merit.op[1].type, SG_OP_EFFL);
    assert_int_equal(e->doc.sys->merit.op[2].type, SG_OP_TTHI);
    assert_true(e->doc.sys->merit.op[2].weight == 3.0);
    ok(e, "merit delete 1");
    assert_int_equal(e->doc.sys->merit.op[0].type, SG_OP_EFFL);

    /* The default part: rows after the operands. */
    ok(e, "merit default centroid 2 6");
    assert_int_equal(e->doc.sys->merit.has_default, 1);
    listed(e, v, 64, &n);
    assert_true(n > 2);

    /* Saved, the file holds the rows as sagitta-design(5) writes them. */
    snprintf(line, sizeof line, "save %s", out);
    ok(e, line);
    f = fopen(out, "r");
    assert_non_null(f);
    text = calloc(1, 1 << 16);
    assert_non_null(text);
    assert_true(fread(text, 1, (1 << 16) - 1, f) > 0);
    fclose(f);
    root = cJSON_Parse(text);
    assert_non_null(root);
    ops = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "merit"), "operands");
    assert_int_equal(cJSON_GetArraySize(ops), 2);
    assert_string_equal(cJSON_GetObjectItem(cJSON_GetArrayItem(ops, 0), "type")->valuestring,
                        "EFFL");
    assert_true(cJSON_GetObjectItem(cJSON_GetArrayItem(ops, 1), "weight")->valuedouble == 3.0);
    assert_non_null(cJSON_GetObjectItem(cJSON_GetObjectItem(root, "merit"), "default"));
    cJSON_Delete(root);
    free(text);

    fclose(e->out);
    ed_free(e);
    free(e);
    remove(path);
    remove(out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(merit_edits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
