/*
 * test_opt_cmd.c - the editor's optimization commands without a screen:
 * :var marks a value a variable (the cell shows V, as M and P are shown),
 * :opt runs damped least squares as one undoable change and lands on the
 * plano-convex lens's closed form (R = f (n - 1)), :undo returns the exact
 * design, :novar clears variables, and :opt without them changes nothing.
 * Stopped after a cycle (the screen's Esc, through e->opt_progress), :opt
 * keeps the best design so far as one undoable change: its merit,
 * evaluated afresh, is the one the last cycle reported and below the
 * start's.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "cells.h"
#include "doc.h"
#include "ed.h"

static const char design[] =
    "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
    "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
    "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
    "{\"radius\": 60, \"thickness\": 4, \"material\": 1.5, \"stop\": true},"
    "{\"radius\": \"inf\", \"thickness\": 95},"
    "{\"radius\": \"inf\", \"thickness\": 0}],"
    "\"merit\": {\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 100}]}}";

static void ok(ed *e, const char *line)
{
    int f = cmd_exec(e, line);
    if (f & ED_ERROR)
        fail_msg("\"%s\" failed: %s", line, e->msg);
}

static void var_opt_undo(void **state)
{
    char path[256], line[320], cell[64];
    FILE *f;
    ed *e = calloc(1, sizeof *e);
    sg_system *before;
    (void)state;
    snprintf(path, sizeof path, "%s/sg-opt-test-%d.json",
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
    ok(e, "var 1 radius");
    assert_int_equal(e->doc.sys->surf[1].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_VARIABLE);
    cell_text(e->doc.sys, 1, COL_RADIUS, cell, sizeof cell);
    assert_non_null(strstr(cell, " V"));
    before = sg_system_clone(e->doc.sys);
    ok(e, "opt");
    /* A plano-convex lens of index 1.5: f = R / (n - 1) whatever its
     * thickness, so R = 50. */
    assert_true(fabs(e->doc.sys->surf[1].radius - 50.0) <= 1e-12 * 50.0);
    ok(e, "undo");
    assert_true(sg_system_equal(e->doc.sys, before));
    ok(e, "novar all");
    assert_int_equal(e->doc.sys->surf[1].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_NONE);
    sg_system_free(before);
    before = sg_system_clone(e->doc.sys);
    assert_true(cmd_exec(e, "opt") & ED_ERROR);
    assert_non_null(strstr(e->msg, "no variables"));
    assert_true(sg_system_equal(e->doc.sys, before));
    /* Bounds through :solve, and the errors. */
    ok(e, "solve 2 thickness variable 2 20");
    assert_true(e->doc.sys->surf[2].solve[SG_SOLVE_THICKNESS].hi == 20);
    assert_true(cmd_exec(e, "var 1 radius 5") & ED_ERROR);
    assert_true(cmd_exec(e, "var 1 material") & ED_ERROR);
    assert_true(cmd_exec(e, "novar 1 radius") & ED_ERROR);
    /* Any real parameter of the surface table, by its key and element:
     * a decenter is one, an asphere term of a standard surface is not
     * read, and novar all clears them with the solves. */
    ok(e, "var 1 before.dy -1 1");
    assert_int_equal(e->doc.sys->surf[1].nvar, 1);
    assert_true(e->doc.sys->surf[1].var[0].hi == 1);
    assert_true(cmd_exec(e, "var 1 asphere[1]") & ED_ERROR);
    assert_non_null(strstr(e->msg, "does not use"));
    assert_true(cmd_exec(e, "var 1 asphere[x]") & ED_ERROR);
    ok(e, "novar 1 before.dy");
    assert_int_equal(e->doc.sys->surf[1].nvar, 0);
    ok(e, "set 1 type EVENASPH");
    ok(e, "var 1 asphere[1]");
    cell_text(e->doc.sys, 1, COL_ASPH0 + 1, cell, sizeof cell);
    assert_non_null(strstr(cell, " V"));
    ok(e, "novar all");
    assert_int_equal(e->doc.sys->surf[1].nvar, 0);
    sg_system_free(before);
    fclose(e->out);
    ed_free(e);
    free(e);
    unlink(path);
}

/* What the screen's progress sees: the cycles and the best merit. */
typedef struct seen {
    int calls, stop_at;
    double merit;
} seen;

static int stop_after(void *ctx, int cycle, double merit, double step, double seconds)
{
    seen *s = ctx;
    (void)step;
    (void)seconds;
    s->calls++;
    s->merit = merit;
    return cycle >= s->stop_at;
}

static void opt_stopped(void **state)
{
    /* A singlet bent for least spherical: the default merit part takes
     * more than one cycle from this start. */
    static const char text[] =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 20},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": -300, \"thickness\": 5, \"material\": 1.5, \"stop\": true,"
        " \"solves\": {\"radius\": {\"type\": \"variable\"}}},"
        "{\"radius\": -100, \"thickness\": 90, \"solves\": {\"radius\": {\"type\": "
        "\"fnum\", \"value\": 5}, \"thickness\": {\"type\": \"marginal_height\", "
        "\"value\": 0}}},"
        "{\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"default\": {\"criterion\": \"spot\", \"reference\": "
        "\"centroid\", \"rings\": 4, \"arms\": 6}}}";
    char path[256], line[320];
    FILE *f;
    ed *e = calloc(1, sizeof *e);
    sg_system *before;
    sg_merit_result r0, r1;
    sg_diag d;
    seen s = {0, 1, 0};
    (void)state;
    snprintf(path, sizeof path, "%s/sg-opt-stop-%d.json",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (int)getpid());
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    e->batch = 1;
    e->out = tmpfile();
    snprintf(line, sizeof line, "open %s", path);
    ok(e, line);
    before = sg_system_clone(e->doc.sys);
    sg_diag_clear(&d);
    assert_int_equal(sg_merit_eval(before, e->cat, &r0, &d), SG_OK);
    e->opt_progress = stop_after;
    e->progress_ctx = &s;
    ok(e, "opt");
    assert_int_equal(s.calls, 1);
    assert_non_null(strstr(e->msg, "stopped after 1 cycle"));
    assert_false(sg_system_equal(e->doc.sys, before));
    assert_int_equal(sg_merit_eval(e->doc.sys, e->cat, &r1, &d), SG_OK);
    if (!(r1.merit == s.merit && r1.merit < r0.merit))
        fail_msg("kept merit %.17g, reported %.17g, start %.17g", r1.merit, s.merit, r0.merit);
    /* One change: one undo is the start, bit for bit. */
    ok(e, "undo");
    assert_true(sg_system_equal(e->doc.sys, before));
    ok(e, "redo");
    assert_true(e->doc.sys->surf[1].radius != before->surf[1].radius);
    sg_merit_result_free(&r0);
    sg_merit_result_free(&r1);
    sg_system_free(before);
    fclose(e->out);
    ed_free(e);
    free(e);
    unlink(path);
}

/* :config N shows configuration N (its THIC value set); an edit made
 * there is kept as that configuration's value when another is shown;
 * each switch is one undo step; the file saved in configuration 2 holds
 * its values as the design's own and "current": 2. */
static void config_switch(void **state)
{
    static const char text[] =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 8},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 60, \"thickness\": 4, \"material\": 1.5, \"stop\": true},"
        "{\"radius\": -120, \"thickness\": 10},"
        "{\"radius\": 80, \"thickness\": 3, \"material\": 1.6},"
        "{\"radius\": -300, \"thickness\": 40},"
        "{\"radius\": \"inf\", \"thickness\": 0}],"
        "\"configurations\": {\"count\": 2, \"operands\": [{\"type\": \"THIC\", "
        "\"surface\": 2, \"values\": [10, 30]}]}}";
    char path[256], line[320];
    FILE *f;
    ed *e = calloc(1, sizeof *e);
    sg_system *re;
    sg_diag d;
    (void)state;
    snprintf(path, sizeof path, "%s/sg-config-%d.json",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (int)getpid());
    f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    e->batch = 1;
    e->out = tmpfile();
    snprintf(line, sizeof line, "open %s", path);
    ok(e, line);
    ok(e, "config");
    assert_non_null(strstr(e->msg, "configuration 1 of 2"));
    ok(e, "config 2");
    assert_true(e->doc.sys->surf[2].thickness == 30 && e->doc.sys->configs->current == 2);
    ok(e, "set 2 thickness 25");
    ok(e, "config 1");
    assert_true(e->doc.sys->surf[2].thickness == 10 && e->doc.sys->configs->current == 1);
    assert_true(e->doc.sys->configs->op[0].value[1] == 25);
    ok(e, "config next");
    assert_true(e->doc.sys->surf[2].thickness == 25 && e->doc.sys->configs->current == 2);
    /* Undo walks back one switch or edit at a time. */
    ok(e, "undo");
    assert_true(e->doc.sys->surf[2].thickness == 10 && e->doc.sys->configs->current == 1);
    ok(e, "undo");
    assert_true(e->doc.sys->surf[2].thickness == 25 && e->doc.sys->configs->current == 2);
    ok(e, "undo");
    assert_true(e->doc.sys->surf[2].thickness == 30 && e->doc.sys->configs->current == 2);
    ok(e, "redo 3");
    assert_true(e->doc.sys->surf[2].thickness == 25 && e->doc.sys->configs->current == 2);
    assert_true(cmd_exec(e, "config 3") & ED_ERROR);
    ok(e, "save");
    re = sg_system_new();
    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(re, path, &d), SG_OK);
    assert_true(re->surf[2].thickness == 25 && re->configs->current == 2);
    assert_true(re->configs->op[0].value[0] == 10 && re->configs->op[0].value[1] == 25);
    sg_system_free(re);
    fclose(e->out);
    ed_free(e);
    free(e);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(var_opt_undo),
        cmocka_unit_test(opt_stopped),
        cmocka_unit_test(config_switch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
