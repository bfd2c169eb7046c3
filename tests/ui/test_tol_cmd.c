/*
 * test_tol_cmd.c - the Tolerance Data Editor's commands without a screen:
 * tol insert, set and delete edit the design's tolerance rows as one
 * undoable change each, a row the design cannot take is refused with the
 * design unchanged, and tol runs the sensitivity analysis, printing each
 * row's criterion at its min and max.
 *
 * Independent reference: the criterion is the merit function, one EFFL
 * row with target 0, so at each limit it is the thick lens's focal length
 * from its closed form, 1/f = (n - 1) (1/R1 - 1/R2 + (n - 1) t / (n R1
 * R2)), with the radius or thickness the row changes.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "doc.h"
#include "ed.h"

static const char design[] =
    "{\"format\": \"sagitta-design\", \"units\": \"mm\","
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
    "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
    "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
    "{\"radius\": 60, \"thickness\": 5, \"material\": 1.5, \"stop\": true},"
    "{\"radius\": -80, \"thickness\": 45},"
    "{\"radius\": \"inf\", \"thickness\": 0}],"
    "\"merit\": {\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 0,"
    " \"weight\": 1}]},"
    "\"tolerances\": {\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, \"min\": -0.5,"
    " \"max\": 0.5}], \"criterion\": {\"type\": \"merit\"}}}";

static void ok(ed *e, const char *line)
{
    int f = cmd_exec(e, line);
    if (f & ED_ERROR)
        fail_msg("\"%s\" failed: %s", line, e->msg);
}

static double efl(double r1, double r2, double t, double n)
{
    return 1.0 / ((n - 1.0) * (1.0 / r1 - 1.0 / r2 + (n - 1.0) * t / (n * r1 * r2)));
}

/* The criteria "tol" printed for row k (1-based). */
static void printed(ed *e, int k, double *cmin, double *cmax)
{
    char line[1024];
    int found = 0;
    rewind(e->out);
    while (fgets(line, sizeof line, e->out)) {
        int row;
        const char *p = strstr(line, "criterion_min ");
        if (sscanf(line, "%d", &row) == 1 && row == k && p &&
            sscanf(p, "criterion_min %lf criterion_max %lf", cmin, cmax) == 2)
            found = 1;
    }
    rewind(e->out);
    if (ftruncate(fileno(e->out), 0) != 0)
        fail_msg("cannot empty the batch output");
    if (!found)
        fail_msg("tol printed no criteria for row %d", k);
}

static void tol_edits(void **state)
{
    char path[256], line[360];
    FILE *f;
    ed *e = calloc(1, sizeof *e);
    sg_system *before;
    double lo, hi;
    (void)state;
    snprintf(path, sizeof path, "%s/sg-tol-test-%d.json",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (int)getpid());
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
    before = sg_system_clone(e->doc.sys);

    /* A TTHI row on surface 1, appended, then its limits; Int2 equal to
     * Int1 adjusts nothing, as in Zemax's editor. */
    ok(e, "tol insert 2 TTHI");
    assert_int_equal(e->doc.sys->tol.nop, 2);
    ok(e, "tol set 2 int1 1 int2 1 min -0.1 max 0.1");
    assert_int_equal(e->doc.sys->tol.op[1].adjust, -1);
    assert_true(e->doc.sys->tol.op[1].max == 0.1);

    /* Refused, the design unchanged: the image's TRAD, a surface the
     * design lacks, min above max, an unknown type, TPAR, a row past the
     * last. */
    {
        sg_system *mid = sg_system_clone(e->doc.sys);
        assert_true(cmd_exec(e, "tol set 2 type TRAD int1 3") & ED_ERROR);
        print_message("# refused: %s\n", e->msg);
        assert_non_null(strstr(e->msg, "nothing changed"));
        assert_true(cmd_exec(e, "tol set 2 int1 9") & ED_ERROR);
        assert_true(cmd_exec(e, "tol set 2 min 1") & ED_ERROR);
        assert_true(cmd_exec(e, "tol set 2 type NOPE") & ED_ERROR);
        assert_true(cmd_exec(e, "tol insert 1 TPAR") & ED_ERROR);
        assert_true(cmd_exec(e, "tol delete 3") & ED_ERROR);
        assert_true(sg_system_equal(e->doc.sys, mid));
        sg_system_free(mid);
    }

    /* The run: each limit's merit function is |EFFL| of the lens changed
     * there, by the closed form. */
    ok(e, "tol");
    printed(e, 1, &lo, &hi);
    print_message("# TRAD: %.17g %.17g, closed form %.17g %.17g\n", lo, hi,
                  efl(59.5, -80, 5, 1.5), efl(60.5, -80, 5, 1.5));
    assert_true(fabs(lo - efl(59.5, -80, 5, 1.5)) <= 1e-11 * lo);
    assert_true(fabs(hi - efl(60.5, -80, 5, 1.5)) <= 1e-11 * hi);
    ok(e, "tol");
    printed(e, 2, &lo, &hi);
    assert_true(fabs(lo - efl(60, -80, 4.9, 1.5)) <= 1e-11 * lo);
    assert_true(fabs(hi - efl(60, -80, 5.1, 1.5)) <= 1e-11 * hi);
    /* The run changed nothing; the rows are there to list. */
    ok(e, "tol list");
    rewind(e->out);
    assert_non_null(fgets(line, sizeof line, e->out));
    assert_non_null(strstr(line, "nominal"));
    rewind(e->out);
    if (ftruncate(fileno(e->out), 0) != 0)
        fail_msg("cannot empty the batch output");

    /* Delete row 1, undo: every bit back; two more undos, the design as
     * opened. */
    {
        sg_system *two = sg_system_clone(e->doc.sys);
        ok(e, "tol delete 1");
        assert_int_equal(e->doc.sys->tol.nop, 1);
        assert_int_equal(e->doc.sys->tol.op[0].type, SG_TOL_TTHI);
        ok(e, "undo");
        assert_true(sg_system_equal(e->doc.sys, two));
        sg_system_free(two);
        ok(e, "undo");
        ok(e, "undo");
        assert_true(sg_system_equal(e->doc.sys, before));
    }
    sg_system_free(before);
    fclose(e->out);
    ed_free(e);
    free(e);
    remove(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(tol_edits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
