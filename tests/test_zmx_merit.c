/*
 * test_zmx_merit.c - a .zmx file's merit function rows (after the
 * surfaces, "TYPE int1 int2 data1 data2 data3 data4 target weight data5
 * data6", as Zemax writes its Merit Function Editor): the rows sagitta
 * knows become operands with Zemax's parameters, the others are warned
 * about with their line and left out (rows that refer to them by number
 * too, the others renumbered), an empty editor (one BLNK) is no merit
 * function, and the export writes the rows back so the import of the
 * export is the same design.  The public file US00583336-2-scaled.zmx
 * holds a REAY row Zemax wrote: surface 13, wave 2, hy 1, target 22.54.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const char zmx[] =
    "MODE SEQ\nUNIT MM X W X CM AM CPMM\nENPD 1.0E+1\n"
    "FTYP 0 0 2 1 0 0 0\nXFLN 0 0\nYFLN 0 5\nFWGN 1 1\n"
    "WAVM 1 5.5E-1 1\nPWAV 1\n"
    "SURF 0\n  CURV 0.0\n  DISZ INFINITY\n"
    "SURF 1\n  STOP\n  CURV 2.0E-2\n  DISZ 6\n  GLAS ___BLANK 1 0 1.5 0 0 0 0 0 0 0 0\n"
    "SURF 2\n  CURV -1.25E-2\n  DISZ 90\n"
    "SURF 3\n  CURV 0.0\n  DISZ 0\n"
    "DMFS 0 0 0 0 0 0 0 0 0 0\n"            /* line 24: row 1 */
    "BLNK a comment\n"                      /* row 2 */
    "EFFL 0 1 0 0 0 0 1.0E+2 1 0 0\n"      /* row 3 */
    "EFLY 2 3 0 0 0 0 4.94E+1 9.9E+1 0 0\n" /* line 27, row 4: unknown */
    "REAY 3 1 0 1 0 5.0E-1 2.0 3.0E-1 0 0\n" /* row 5 */
    "DIFF 3 5 0 0 0 0 0 1 0 0\n"           /* row 6: 3 - 5 */
    "SUMM 3 4 0 0 0 0 0 1 0 0\n"           /* line 30, row 7: refers to row 4 */
    "ABSO 6 0 0 0 0 0 0 1 0 0\n"           /* row 8 */
    "MNUM 1 1\n";

static sg_system *load(const char *text, size_t n, sg_diag *d)
{
    sg_system *sys = sg_system_new();
    sg_catalog *cat = tu_catalog();
    sg_diag_clear(d);
    if (sg_zmx_parse(sys, text, n, "m.zmx", cat, d) != SG_OK)
        fail_msg("%s", d->msg);
    sg_catalog_free(cat);
    return sys;
}

static int has_warning(const sg_diag *d, const char *a, const char *b)
{
    int i;
    for (i = 0; i < d->nwarn && i < SG_DIAG_MAXWARN; i++)
        if (strstr(d->warn[i], a) && (!b || strstr(d->warn[i], b)))
            return 1;
    return 0;
}

static void rows(void **state)
{
    sg_diag d;
    sg_system *s = load(zmx, strlen(zmx), &d), *b;
    const sg_merit *m = &s->merit;
    sg_catalog *cat = tu_catalog();
    char *z, *j1, *j2;
    (void)state;
    assert_true(m->present);
    /* BLNK, EFFL, REAY, DIFF, ABSO: EFLY and the SUMM naming it are out. */
    assert_int_equal(m->nop, 5);
    assert_int_equal(m->op[0].type, SG_OP_BLNK);
    assert_int_equal(m->op[1].type, SG_OP_EFFL);
    assert_true(m->op[1].i2 == 1 && m->op[1].target == 100 && m->op[1].weight == 1);
    assert_int_equal(m->op[2].type, SG_OP_REAY);
    assert_true(m->op[2].i1 == 3 && m->op[2].i2 == 1 && m->op[2].hy == 1 &&
                m->op[2].py == 0.5 && m->op[2].target == 2 && m->op[2].weight == 0.3);
    /* DIFF 3 5 in Zemax's rows is DIFF 2 3 in the design's. */
    assert_int_equal(m->op[3].type, SG_OP_DIFF);
    assert_true(m->op[3].i1 == 2 && m->op[3].i2 == 3);
    assert_int_equal(m->op[4].type, SG_OP_ABSO);
    assert_int_equal(m->op[4].i1, 4);
    assert_true(has_warning(&d, "m.zmx:27", "EFLY is not one sagitta knows"));
    assert_true(has_warning(&d, "m.zmx:30", "refers to row 4"));
    /* The export writes the rows; its import is the same design. */
    sg_diag_clear(&d);
    z = sg_zmx_to_text(s, cat, &d);
    assert_non_null(z);
    assert_non_null(strstr(z, "\nEFFL 0 1 "));
    b = load(z, strlen(z), &d);
    j1 = sg_design_to_json(s);
    j2 = sg_design_to_json(b);
    assert_string_equal(j1, j2);
    free(j1);
    free(j2);
    free(z);
    sg_system_free(b);
    sg_system_free(s);
    sg_catalog_free(cat);
}

/* One BLNK is Zemax's empty editor; more rows than sagitta holds, or a
 * row that does not fit the design, leave the merit function out with a
 * warning, never the file. */
static void left_out(void **state)
{
    static char text[65536];
    const char *head = strstr(zmx, "DMFS");
    size_t n = (size_t)(head - zmx), i;
    sg_diag d;
    sg_system *s;
    (void)state;
    memcpy(text, zmx, n);
    strcpy(text + n, "BLNK\nMNUM 1 1\n");
    s = load(text, strlen(text), &d);
    assert_false(s->merit.present);
    sg_system_free(s);
    for (i = 0; i < 201; i++)
        n += (size_t)snprintf(text + n, sizeof text - n, "TOTR 0 0 0 0 0 0 0 1 0 0\n");
    strcpy(text + n, "MNUM 1 1\n");
    s = load(text, strlen(text), &d);
    assert_false(s->merit.present);
    assert_true(has_warning(&d, "more than 200 rows", NULL));
    sg_system_free(s);
    n = (size_t)(head - zmx);
    strcpy(text + n, "REAY 9 1 0 1 0 0 0 1 0 0\nMNUM 1 1\n");
    s = load(text, strlen(text), &d);
    assert_false(s->merit.present);
    assert_true(has_warning(&d, "surf 9", "leaves the merit function out"));
    sg_system_free(s);
}

/* The REAY row of a file Zemax wrote. */
static void zemax_file(void **state)
{
    char path[1024];
    sg_diag d;
    sg_system *s = sg_system_new();
    (void)state;
    sg_diag_clear(&d);
    if (sg_design_load(s, tu_path("tests/data/zmx/US00583336-2-scaled.zmx", path, sizeof path),
                       &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_true(s->merit.present);
    assert_int_equal(s->merit.nop, 1);
    assert_int_equal(s->merit.op[0].type, SG_OP_REAY);
    assert_true(s->merit.op[0].i1 == 13 && s->merit.op[0].i2 == 2 && s->merit.op[0].hy == 1 &&
                s->merit.op[0].target == 22.54);
    assert_true(has_warning(&d, "EFLY", "not one sagitta knows"));
    sg_system_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(rows),
        cmocka_unit_test(left_out),
        cmocka_unit_test(zemax_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
