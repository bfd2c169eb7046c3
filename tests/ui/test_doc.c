/*
 * test_doc.c - the editor's document model and command path, without a
 * screen: cells keep exactly what was typed, bad text changes nothing,
 * insert/delete/stop behave, undo and redo return to the exact bytes, the
 * modified flag follows the file, batch scripts stop at the first error,
 * save and load round-trip and export equals the engine's own trace.
 *
 * Independent references: strtod() of the typed text (the C library's
 * correctly rounded conversion), copies of the document taken before each
 * change (compared with memcmp), and sg_trace_normalized() for the export.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "cells.h"
#include "doc.h"
#include "ed.h"
#include "numfmt.h"

static char tmpdir[256];

static const char *tmp_path(const char *name, char *buf, size_t n)
{
    if (!tmpdir[0]) {
        snprintf(tmpdir, sizeof tmpdir, "%s/sg-ui-test-XXXXXX",
                 getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
        assert_non_null(mkdtemp(tmpdir));
    }
    snprintf(buf, n, "%s/%s", tmpdir, name);
    return buf;
}

static ed *new_ed(void)
{
    ed *e = calloc(1, sizeof *e);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    e->batch = 1;
    e->out = tmpfile();
    assert_non_null(e->out);
    return e;
}

static void free_ed(ed *e)
{
    fclose(e->out);
    ed_free(e);
    free(e);
}

static int run(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int run(ed *e, const char *fmt, ...)
{
    char line[ED_LINE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    return cmd_exec(e, line);
}

static void ok(ed *e, const char *line)
{
    int f = cmd_exec(e, line);
    if (f & ED_ERROR)
        fail_msg("\"%s\" failed: %s", line, e->msg);
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Every byte of the surfaces and every settings field. */
static int sys_bytes_equal(const sg_system *a, const sg_system *b)
{
    sg_system x = *a, y = *b;
    if (a->nsurf != b->nsurf)
        return 0;
    if (memcmp(a->surf, b->surf, (size_t)a->nsurf * sizeof *a->surf) != 0)
        return 0;
    x.surf = y.surf = NULL;
    x.capsurf = y.capsurf = 0;
    return memcmp(x.title, y.title, sizeof x.title) == 0 &&
           memcmp(x.units, y.units, sizeof x.units) == 0 && x.nwave == y.nwave &&
           x.primary_wave == y.primary_wave &&
           memcmp(x.wave, y.wave, sizeof x.wave) == 0 && x.field_type == y.field_type &&
           x.field_norm == y.field_norm && x.nfield == y.nfield &&
           memcmp(x.field, y.field, sizeof x.field) == 0 && x.aper_type == y.aper_type &&
           same_bits(x.aper_value, y.aper_value) && x.aim == y.aim && x.stop == y.stop &&
           x.telecentric == y.telecentric;
}

/* ------------------------------------------------------------------------ */

/* The shapes beyond the even asphere by name, and their own columns; an
 * asphere term typed into a toroid leaves it a toroid. */
static void test_set_shapes(void **state)
{
    static const struct {
        const char *name;
        int type;
    } types[] = {{"TOROIDAL", SG_SURF_TOROIDAL}, {"odd_asphere", SG_SURF_ODDASPH},
                 {"biconicx", SG_SURF_BICONIC}, {"FZERNSAG", SG_SURF_ZERNIKE_FRINGE},
                 {"zernike_standard", SG_SURF_ZERNIKE_STANDARD}, {"XPOLYNOM", SG_SURF_XYPOLY}};
    ed *e = new_ed();
    size_t i;
    (void)state;
    ok(e, "insert 1");
    for (i = 0; i < sizeof types / sizeof types[0]; i++) {
        if (run(e, "set 1 type %s", types[i].name) & ED_ERROR)
            fail_msg("set 1 type %s: %s", types[i].name, e->msg);
        assert_int_equal(e->doc.sys->surf[1].type, types[i].type);
    }
    ok(e, "set 1 type toroidal");
    ok(e, "set 1 rx -35.5");
    ok(e, "set 1 a4 1e-7");
    ok(e, "set 1 b3 2e-5");
    ok(e, "set 1 t4 0.001");
    ok(e, "set 1 norm 12.5");
    assert_int_equal(e->doc.sys->surf[1].type, SG_SURF_TOROIDAL);
    assert_true(same_bits(e->doc.sys->surf[1].radius_x, -35.5));
    assert_true(same_bits(e->doc.sys->surf[1].asph[1], 1e-7));
    assert_true(same_bits(e->doc.sys->surf[1].odd[2], 2e-5));
    assert_true(same_bits(e->doc.sys->surf[1].terms[3], 0.001));
    assert_true(same_bits(e->doc.sys->surf[1].norm_radius, 12.5));
    /* A normalization radius must be positive. */
    assert_true(run(e, "set 1 norm 0") & ED_ERROR);
    /* Zernike decenters are a Zernike sag's own: dim on a toroid. */
    assert_false(cell_used(e->doc.sys, 1, cell_parse_name("zdx")));
    free_ed(e);

    /* Fringe Z1 + Z4 with equal coefficients c is 2 c rho^2: decentred to
     * (1.5, -0.75) with c = -R^2 / (8 F) it is a paraboloid of focal length
     * F about that point, so as a mirror it sends every axial ray through
     * (1.5, -0.75) at -F, wherever it strikes (the live trace, any pupil
     * point). */
    e = new_ed();
    ok(e, "set 1 type FZERNSAG");
    ok(e, "set 1 norm 10");
    ok(e, "set 1 t1 -0.5");
    ok(e, "set 1 t4 -0.5");
    ok(e, "set 1 zdx 1.5");
    ok(e, "set 1 zdy -0.75");
    ok(e, "set 1 material mirror");
    ok(e, "set 1 thickness -25");
    assert_true(same_bits(e->doc.sys->surf[1].zern_dx, 1.5) &&
                same_bits(e->doc.sys->surf[1].zern_dy, -0.75));
    assert_true(cell_used(e->doc.sys, 1, cell_parse_name("zdy")));
    assert_true(run(e, "set 1 zdx inf") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 1 zdx"));
    for (i = 0; i < 3; i++) {
        static const char *const rays[] = {"ray 0 0 0.5 0.3", "ray 0 0 -0.8 0.1",
                                           "ray 0 0 0 -0.6"};
        const sg_ray_surface *im;
        ok(e, rays[i]);
        ed_recompute(e);
        assert_int_equal(e->cmp.rc, SG_OK);
        im = &e->cmp.res[2];
        if (!(fabs(im->x - 1.5) <= im->error_bound && fabs(im->y + 0.75) <= im->error_bound))
            fail_msg("%s: (%.17g, %.17g), not the focus (1.5, -0.75) within %g", rays[i], im->x,
                     im->y, im->error_bound);
    }
    /* Undone, the terms are centred again. */
    ok(e, "undo 4");
    assert_true(e->doc.sys->surf[1].zern_dx == 0.0 && e->doc.sys->surf[1].zern_dy == 0.0);
    free_ed(e);
}

/* The chief ray's row at surface i in surface 1's (the global) frame. */
static sg_ray_surface chief_global(ed *e, int i)
{
    sg_frame *gf = calloc((size_t)e->doc.sys->nsurf, sizeof *gf);
    sg_ray_surface row;
    sg_diag d;
    assert_non_null(gf);
    ok(e, "ray 0 0 0 0");
    ed_recompute(e);
    if (e->cmp.build_rc != SG_EOK || e->cmp.rc != SG_EOK)
        fail_msg("trace: %d %d %s", e->cmp.build_rc, e->cmp.rc, e->cmp.build_msg);
    sg_diag_clear(&d);
    assert_int_equal(sg_global_frames(e->doc.sys, 1, gf, &d), SG_OK);
    row = e->cmp.res[i];
    sg_row_to_global(&gf[i], &row);
    free(gf);
    return row;
}

/* Zemax's coordinate-break columns (Decenter X ... Order) and a surface's
 * tilt and decenter before and after it, typed through the command path:
 * a 45-degree fold mirror built both ways must turn the chief ray from +z
 * to +y (the axes turn right-handed about x, sagitta.h: the mirror's
 * normal is (0, -sin 45, cos 45), so d - 2 (d.n) n = (0, 1, 0)), and the
 * image 20 beyond the fold at z = 10 lies at (0, 20, 10).  Cells that do
 * not apply are dim and refuse values with the surface and column named;
 * undo and redo return the exact bytes. */
static void test_frame_columns(void **state)
{
    ed *e = new_ed();
    sg_system *before, *after;
    sg_ray_surface r;
    char path[512];
    int c;
    (void)state;
    ok(e, "insert 2");
    ok(e, "insert 2");
    ok(e, "insert 2");
    before = sg_system_clone(e->doc.sys);
    ok(e, "set 2 type COORDBRK");
    ok(e, "set 2 tx 45");
    ok(e, "set 3 material mirror");
    ok(e, "set 4 type cb");
    ok(e, "set 4 tx 45");
    ok(e, "set 4 thickness -20");
    assert_int_equal(e->doc.sys->surf[2].type, SG_SURF_COORDBRK);
    assert_true(same_bits(e->doc.sys->surf[2].before.tx, 45.0));
    assert_true(same_bits(e->doc.sys->surf[4].before.tx, 45.0));
    r = chief_global(e, 5);
    print_message("# fold by breaks: chief at image (%.17g, %.17g, %.17g) dir (%.17g, %.17g, "
                  "%.17g)\n", r.x, r.y, r.z, r.l, r.m, r.n);
    assert_true(fabs(r.x) < 1e-14 && fabs(r.y - 20.0) < 1e-13 && fabs(r.z - 10.0) < 1e-13);
    assert_true(fabs(r.l) < 1e-15 && fabs(r.m - 1.0) < 1e-15 && fabs(r.n) < 1e-15);
    /* The image's own frame faces back along the beam. */
    assert_true(fabs(e->cmp.res[5].n + 1.0) < 1e-15);

    /* Order and the dim cells of a break. */
    ok(e, "set 2 order 1");
    assert_int_equal(e->doc.sys->surf[2].before.order, 1);
    ok(e, "set 2 order decenter_then_tilt");
    assert_int_equal(e->doc.sys->surf[2].before.order, 0);
    assert_true(run(e, "set 2 order 2") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 2 order"));
    assert_false(cell_used(e->doc.sys, 2, cell_parse_name("radius")));
    assert_false(cell_used(e->doc.sys, 2, cell_parse_name("adx")));
    assert_true(cell_used(e->doc.sys, 2, cell_parse_name("tz")));
    assert_true(cell_used(e->doc.sys, 3, cell_parse_name("adx")));
    /* Where no frame change may stand: dim, and refused by name. */
    assert_false(cell_used(e->doc.sys, 0, cell_parse_name("dx")));
    assert_true(cell_used(e->doc.sys, 1, cell_parse_name("tx")));
    assert_true(cell_used(e->doc.sys, 1, cell_parse_name("atx")));
    assert_false(cell_used(e->doc.sys, 5, cell_parse_name("ady")));
    assert_true(run(e, "set 0 dx 1") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 0 dx: the object cannot be tilted"));
    /* Surface 1 turns what follows the object (Zemax's tilt on surface 1). */
    ok(e, "set 1 tx 5");
    ok(e, "set 1 tx 0");
    assert_true(run(e, "set 5 after reverse") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 5 after: nothing follows the image"));
    assert_true(run(e, "set 2 adx 1") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 2 adx"));
    assert_true(run(e, "set 2 tx 400") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 2 tx"));
    assert_true(run(e, "set 1 type coordbrk") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 1 type"));
    assert_true(same_bits(e->doc.sys->surf[2].before.tx, 45.0));

    /* Saved and read back: the same design, frames in their JSON objects. */
    run(e, "save %s", tmp_path("fold.json", path, sizeof path));
    assert_false(e->msg_err);
    {
        sg_system *back = sg_system_new();
        sg_diag d;
        sg_diag_clear(&d);
        assert_int_equal(sg_design_load(back, path, &d), SG_OK);
        assert_true(sg_system_equal(back, e->doc.sys));
        sg_system_free(back);
    }

    /* Undone to the start, byte for byte; redone to the fold. */
    after = sg_system_clone(e->doc.sys);
    for (c = 0; c < 10; c++)
        ok(e, "undo");
    assert_true(sys_bytes_equal(e->doc.sys, before));
    for (c = 0; c < 10; c++)
        ok(e, "redo");
    assert_true(sys_bytes_equal(e->doc.sys, after));

    /* The same fold as one surface: the mirror tilted before and after. */
    ok(e, "delete 4");
    ok(e, "delete 2");
    ok(e, "set 2 tx 45");
    ok(e, "set 2 after reverse");
    assert_int_equal(e->doc.sys->surf[2].after_mode, SG_AFTER_REVERSE);
    assert_false(cell_used(e->doc.sys, 2, cell_parse_name("atx")));
    assert_true(run(e, "set 2 atx 45") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 2 atx"));
    /* Its order too: "reverse" in the file has none of its own. */
    assert_false(cell_used(e->doc.sys, 2, cell_parse_name("aorder")));
    assert_true(run(e, "set 2 aorder 1") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 2 aorder"));
    ok(e, "set 2 after explicit");
    ok(e, "set 2 atx 45");
    ok(e, "set 2 thickness -20");
    assert_true(same_bits(e->doc.sys->surf[2].after.tx, 45.0));
    r = chief_global(e, 3);
    print_message("# fold by tilts: chief at image (%.17g, %.17g, %.17g) dir (%.17g, %.17g, "
                  "%.17g)\n", r.x, r.y, r.z, r.l, r.m, r.n);
    assert_true(fabs(r.x) < 1e-14 && fabs(r.y - 20.0) < 1e-13 && fabs(r.z - 10.0) < 1e-13);
    assert_true(fabs(r.l) < 1e-15 && fabs(r.m - 1.0) < 1e-15 && fabs(r.n) < 1e-15);
    /* A decenter before the mirror moves the fold point along its x. */
    ok(e, "set 2 dx 1.5");
    r = chief_global(e, 3);
    assert_true(fabs(r.x) < 1e-14);
    /* The chief ray still leaves along +y from the axis at z = 10. */
    assert_true(fabs(r.m - 1.0) < 1e-15 && fabs(r.z - 10.0) < 1e-13);
    assert_true(same_bits(e->doc.sys->surf[2].before.dx, 1.5));
    /* A mirror made a break loses what a break cannot hold, says so, and
     * gets it back on undo. */
    ok(e, "set 2 radius 100");
    ok(e, "set 2 type COORDBRK");
    assert_non_null(strstr(e->msg, "radius, material, after change"));
    assert_true(isinf(e->doc.sys->surf[2].radius) && e->doc.sys->surf[2].mat.kind == SG_MAT_AIR &&
                sg_frame_change_is_zero(&e->doc.sys->surf[2].after));
    assert_true(same_bits(e->doc.sys->surf[2].before.tx, 45.0));
    ok(e, "undo");
    assert_true(e->doc.sys->surf[2].radius == 100.0 &&
                e->doc.sys->surf[2].mat.kind == SG_MAT_MIRROR &&
                same_bits(e->doc.sys->surf[2].after.tx, 45.0));
    sg_system_free(before);
    sg_system_free(after);
    free_ed(e);
}

static void test_set_exact(void **state)
{
    static const char *const texts[] = {
        "-50", "0.1", "1e-300", "123.456789012345678901234567890", "6.02214076e23",
        "-0.0", "1.7976931348623157e308", "4.9406564584124654e-324", "0.30000000000000004",
        "2.2250738585072011e-308", "-1234.5678e-3", "  42  ", "+7", ".5",
        "0.1000000000000000055511151231257827", "9007199254740993",
    };
    static const char *const cols[] = {"radius", "thickness", "conic", "a4", "a16"};
    ed *e = new_ed();
    size_t i, k;
    int n = 0;
    ok(e, "insert 1");
    for (k = 0; k < sizeof cols / sizeof cols[0]; k++)
        for (i = 0; i < sizeof texts / sizeof texts[0]; i++) {
            double want = strtod(texts[i], NULL), got;
            const sg_surface *s;
            if (run(e, "set 1 %s %s", cols[k], texts[i]) & ED_ERROR)
                fail_msg("set 1 %s %s: %s", cols[k], texts[i], e->msg);
            s = &e->doc.sys->surf[1];
            switch (k) {
            case 0: got = s->radius; break;
            case 1: got = s->thickness; break;
            case 2: got = s->conic; break;
            case 3: got = s->asph[1]; break;
            default: got = s->asph[7]; break;
            }
            if (!same_bits(got, want))
                fail_msg("%s \"%s\": stored %.17g, strtod gives %.17g", cols[k], texts[i], got,
                         want);
            n++;
        }
    /* The semi-diameter takes a trailing U to fix the aperture. */
    ok(e, "set 1 semi 12.345678901234567 U");
    assert_true(same_bits(e->doc.sys->surf[1].semi_diameter, strtod("12.345678901234567", NULL)));
    assert_int_equal(e->doc.sys->surf[1].sd_fixed, 1);
    ok(e, "set 1 semi 3.25");
    assert_int_equal(e->doc.sys->surf[1].sd_fixed, 0);
    /* A flat radius may be typed as Infinity. */
    ok(e, "set 1 radius Infinity");
    assert_true(isinf(e->doc.sys->surf[1].radius));
    /* The aperture columns come from the engine's parameter table. */
    ok(e, "set 1 aperture OBSC");
    assert_int_equal(e->doc.sys->surf[1].aperture, SG_OBSCURATION_CIRCULAR);
    ok(e, "set 1 aperture elliptical_aperture");
    assert_int_equal(e->doc.sys->surf[1].aperture, SG_APERTURE_ELLIPTICAL);
    ok(e, "set 1 ap_xhalf 4.5");
    ok(e, "set 1 ap_ydec -0.125");
    assert_true(same_bits(e->doc.sys->surf[1].ap_xhalf, 4.5));
    assert_true(same_bits(e->doc.sys->surf[1].ap_ydec, -0.125));
    assert_true(cmd_exec(e, "set 1 ap_rmax -1") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 1 ap_rmax"));
    assert_true(cmd_exec(e, "set 1 aperture square") & ED_ERROR);
    assert_non_null(strstr(e->msg, "not one of none, CLAP, OBSC, SQAP, SQOB, ELAP, ELOB"));
    ok(e, "set 1 aperture none");
    /* Zemax's vignetting factors of a field, rows of the field table. */
    ok(e, "field vignette 1 0.1 -0.2 0.25 0.5 30");
    assert_true(same_bits(e->doc.sys->field[0].vdx, 0.1) &&
                same_bits(e->doc.sys->field[0].vdy, -0.2) &&
                same_bits(e->doc.sys->field[0].vcx, 0.25) &&
                same_bits(e->doc.sys->field[0].vcy, 0.5) && same_bits(e->doc.sys->field[0].van, 30.0));
    assert_true(cmd_exec(e, "field vignette 1 0 0 2e6 0") & ED_ERROR);
    assert_non_null(strstr(e->msg, "field 1: vignetting compression x 2e+06 is beyond 1e+06"));
    ok(e, "field vignette 1 0 0 0 0");
    assert_true(same_bits(e->doc.sys->field[0].van, 0.0));
    print_message("# %d typed values stored; each equals strtod() of its text bit for bit "
                  "(worst difference 0 ulp)\n", n);
    free_ed(e);
}

static void test_set_text_cells(void **state)
{
    ed *e = new_ed();
    const sg_glass *g;
    ok(e, "set 1 comment \"say \\\"hi\\\" now\"");
    assert_string_equal(e->doc.sys->surf[1].comment, "say \"hi\" now");
    ok(e, "set 1 comment Primary mirror, f/4");
    assert_string_equal(e->doc.sys->surf[1].comment, "Primary mirror, f/4");
    ok(e, "set 1 type evenasph");
    assert_int_equal(e->doc.sys->surf[1].type, SG_SURF_EVENASPH);
    ok(e, "set 1 type standard");
    /* An asphere term on a standard surface makes it an asphere. */
    ok(e, "set 1 a6 1e-9");
    assert_int_equal(e->doc.sys->surf[1].type, SG_SURF_EVENASPH);
    ok(e, "set 1 material mirror");
    assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_MIRROR);
    ok(e, "set 1 material 1.5");
    assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_INDEX);
    assert_true(same_bits(e->doc.sys->surf[1].mat.index, 1.5));
    ok(e, "set 1 material air");
    assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_AIR);
    assert_non_null(e->cat);
    g = sg_catalog_find(e->cat, "N-BK7");
    if (g) {
        ok(e, "set 1 material n-bk7");
        assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_GLASS);
        assert_string_equal(e->doc.sys->surf[1].mat.name, g->name);
        print_message("# material n-bk7 stored as the catalog's name \"%s\"\n", g->name);
    }
    free_ed(e);
}

static void test_bad_values(void **state)
{
    static const char *const bad[] = {
        "set 1 radius abc",       "set 1 radius 1.5x",      "set 1 radius nan",
        "set 1 radius",           "set 1 radius 1e999",     "set 1 thickness inf",
        "set 1 thickness -inf",   "set 0 thickness nan",    "set 1 semi -1",
        "set 1 semi nan",         "set 1 semi 5 X",         "set 1 conic inf",
        "set 1 a4 NaN",           "set 1 material NOT-A-GLASS-XYZ",
        "set 0 material mirror",  "set ima material mirror", "set 1 material 0",
        "set 1 type toric",       "set 1 wibble 3",           "set 7 radius 3",
        "set -1 radius 3",        "set x radius 3",         "delete 0",
        "delete 2",               "insert 0",               "insert 3",
        "stop 0",                 "stop 2",                 "undo",
        "redo",                   "wavelength add -1",      "wavelength add 0",
        "wavelength delete 1",    "wavelength set 2 0.5",   "field add 95 0",
        "field delete 1",         "aperture -3",            "aperture na 1.5",
        "aim sideways",           "units furlongs",         "ray 0 1 0",
        "ray 0 1 0 nan",          "method fastest",         "bits 3",
        "wave 2",                 "set 1 comment \"unterminated",
        "frobnicate",             "quit",
    };
    ed *e = new_ed();
    sg_system *before;
    size_t i, depth;
    int modified;
    ok(e, "set 1 radius 25");
    ok(e, "set 1 comment keep me");
    before = sg_system_clone(e->doc.sys);
    assert_non_null(before);
    depth = doc_undo_depth(&e->doc);
    modified = doc_modified(&e->doc);
    /* "quit" is refused for the unsaved changes; undo and redo are tried
     * on a fresh document below. */
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int f;
        if (strcmp(bad[i], "undo") == 0 || strcmp(bad[i], "redo") == 0)
            continue;
        f = cmd_exec(e, bad[i]);
        if (!(f & ED_ERROR))
            fail_msg("\"%s\" was accepted", bad[i]);
        assert_true(e->msg_err);
        assert_true(e->msg[0] != '\0');
        if (!sys_bytes_equal(before, e->doc.sys))
            fail_msg("\"%s\" changed the design", bad[i]);
        assert_int_equal(doc_undo_depth(&e->doc), depth);
        assert_int_equal(doc_modified(&e->doc), modified);
    }
    print_message("# %zu bad commands refused; the design's bytes, undo depth and modified "
                  "flag unchanged after each\n", sizeof bad / sizeof bad[0] - 2);
    sg_system_free(before);
    free_ed(e);

    /* Nothing to undo or redo in a fresh document. */
    e = new_ed();
    assert_true(cmd_exec(e, "undo") & ED_ERROR);
    assert_true(cmd_exec(e, "redo") & ED_ERROR);
    free_ed(e);
}

static void test_insert_delete_stop(void **state)
{
    ed *e = new_ed();
    sg_system *s;
    /* OBJ, A, B(stop), C, IMA */
    ok(e, "insert 1");
    ok(e, "insert 1");
    ok(e, "insert 1");
    s = e->doc.sys;
    assert_int_equal(s->nsurf, 6);
    ok(e, "set 1 comment A");
    ok(e, "set 2 comment B");
    ok(e, "set 3 comment C");
    ok(e, "set 4 comment D");
    ok(e, "stop 2");
    assert_int_equal(e->doc.sys->stop, 2);
    /* The stop is a surface, not a row number: it moves with B. */
    ok(e, "insert 1");
    assert_int_equal(e->doc.sys->nsurf, 7);
    assert_int_equal(e->doc.sys->stop, 3);
    assert_string_equal(e->doc.sys->surf[3].comment, "B");
    assert_string_equal(e->doc.sys->surf[1].comment, "");
    ok(e, "insert 6"); /* before the image */
    assert_string_equal(e->doc.sys->surf[6].comment, "");
    assert_int_equal(e->doc.sys->stop, 3);
    ok(e, "delete 1");
    assert_int_equal(e->doc.sys->stop, 2);
    assert_string_equal(e->doc.sys->surf[2].comment, "B");
    ok(e, "delete 3"); /* C, after the stop */
    assert_int_equal(e->doc.sys->stop, 2);
    assert_string_equal(e->doc.sys->surf[3].comment, "D");
    ok(e, "stop stop");
    ok(e, "stop 3");
    assert_string_equal(e->doc.sys->surf[e->doc.sys->stop].comment, "D");
    ok(e, "delete 3"); /* the stop itself: it stays on a valid surface */
    assert_true(e->doc.sys->stop >= 1 && e->doc.sys->stop <= e->doc.sys->nsurf - 2);
    while (e->doc.sys->nsurf > 3)
        ok(e, "delete 1");
    assert_true(cmd_exec(e, "delete 1") & ED_ERROR);
    assert_int_equal(e->doc.sys->stop, 1);
    print_message("# the stop followed its surface through 2 inserts and 3 deletes\n");
    free_ed(e);
}

/* The back focal distance of a lens of index n, radii R1, R2 and centre
 * thickness T (thick-lens formulas, in long double). */
static double bfd(long double n, long double R1, long double R2, long double T)
{
    long double p1 = (n - 1) / R1, p2 = (1 - n) / R2, p = p1 + p2 - T * p1 * p2 / n;
    return (double)((1 - T * p1 / n) / p);
}

/* The solve command: a marginal_height solve follows every edit in the
 * same undo step, shows an M, and a value typed over it removes it. */
static void test_solve_command(void **state)
{
    ed *e = new_ed();
    sg_system *s;
    char buf[64];
    (void)state;
    ok(e, "insert 1");
    ok(e, "set 1 radius 50");
    ok(e, "set 1 thickness 5");
    ok(e, "set 1 material 1.5");
    ok(e, "set 2 radius -50");
    ok(e, "solve 2 thickness marginal_height 0");
    s = e->doc.sys;
    assert_true(fabs(s->surf[2].thickness - bfd(1.5L, 50, -50, 5)) < 1e-13 * s->surf[2].thickness);
    cell_text(s, 2, COL_THICKNESS, buf, sizeof buf);
    assert_int_equal(buf[strlen(buf) - 1], 'M');
    ok(e, "set 1 radius 40");
    s = e->doc.sys;
    assert_true(fabs(s->surf[2].thickness - bfd(1.5L, 40, -50, 5)) < 1e-13 * s->surf[2].thickness);
    ok(e, "undo");
    s = e->doc.sys;
    assert_true(fabs(s->surf[2].thickness - bfd(1.5L, 50, -50, 5)) < 1e-13 * s->surf[2].thickness);
    /* A pickup of the radius, shown P. */
    ok(e, "solve 2 radius pickup 1 -1");
    assert_true(e->doc.sys->surf[2].radius == -50.0);
    cell_text(e->doc.sys, 2, COL_RADIUS, buf, sizeof buf);
    assert_string_equal(buf, "-50 P");
    /* Zemax's curvature pickup: 1/R = -1 / 50 + 0.01, so R = -100
     * (the offset's double moves it by 2e-15, far below R's half ulp). */
    ok(e, "solve 2 radius curvature_pickup 1 -1 0.01");
    assert_true(e->doc.sys->surf[2].radius == -100.0);
    cell_text(e->doc.sys, 2, COL_RADIUS, buf, sizeof buf);
    assert_string_equal(buf, "-100 P");
    assert_true(cmd_exec(e, "solve 2 thickness curvature_pickup 1") & ED_ERROR);
    ok(e, "undo");
    assert_true(e->doc.sys->surf[2].radius == -50.0);
    /* A position solve: 30 from surface 1's vertex, whose thickness is 5. */
    ok(e, "solve 2 thickness position 1 30");
    assert_true(e->doc.sys->surf[2].thickness == 25.0);
    cell_text(e->doc.sys, 2, COL_THICKNESS, buf, sizeof buf);
    assert_string_equal(buf, "25 T");
    ok(e, "set 1 thickness 6");
    assert_true(e->doc.sys->surf[2].thickness == 24.0);
    assert_true(cmd_exec(e, "solve 2 thickness position 3 30") & ED_ERROR);
    ok(e, "undo");
    ok(e, "undo");
    /* Refusals, naming the surface. */
    assert_true(cmd_exec(e, "solve 1 radius pickup 2") & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 1"));
    assert_true(cmd_exec(e, "solve 2 radius marginal_height 0") & ED_ERROR);
    /* A typed value replaces the solve. */
    ok(e, "set 2 thickness 7");
    assert_true(e->doc.sys->surf[2].thickness == 7.0);
    assert_int_equal(e->doc.sys->surf[2].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_NONE);
    ok(e, "solve 2 radius none");
    assert_int_equal(e->doc.sys->surf[2].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_NONE);
    free_ed(e);
}

static void test_undo_redo_exact(void **state)
{
    static const char *const steps[] = {
        "set 3 radius -123.456789012345678",
        "set 4 material mirror",
        "set 2 comment undo me",
        "set 2 semi 17.5 U",
        "set 5 a8 -3.25e-12",
        "set 5 type standard",
        "insert 4",
        "set 4 thickness 3.3",
        "delete 2",
        "stop 3",
        "wavelength add 0.4861327 0.5",
        "wavelength primary 2",
        "wavelength set 1 0.6562725 2",
        "field add 0 0.5",
        "field set 2 0.1 0.7 3",
        "field type object",
        "field norm rect",
        "aperture fnum 8",
        "aim real",
        "title \"A title\"",
        "units in",
        "wavelength delete 1",
        "field delete 1",
        "set 1 fixed on",
    };
    enum { N = sizeof steps / sizeof steps[0] };
    ed *e = new_ed();
    sg_system *snap[N + 1];
    int i, worst = 0;
    /* A few surfaces so every step has something to work on. */
    for (i = 0; i < 5; i++)
        ok(e, "insert 1");
    ok(e, "set 3 radius 50");
    snap[0] = sg_system_clone(e->doc.sys);
    for (i = 0; i < N; i++) {
        ok(e, steps[i]);
        snap[i + 1] = sg_system_clone(e->doc.sys);
        assert_false(sys_bytes_equal(snap[i], snap[i + 1]));
    }
    /* Back to the start one step at a time, then forward again. */
    for (i = N; i > 0; i--) {
        assert_true(sys_bytes_equal(e->doc.sys, snap[i]));
        ok(e, "undo");
    }
    assert_true(sys_bytes_equal(e->doc.sys, snap[0]));
    assert_true(memcmp(e->doc.sys->surf, snap[0]->surf,
                       (size_t)snap[0]->nsurf * sizeof *snap[0]->surf) == 0);
    for (i = 1; i <= N; i++) {
        ok(e, "redo");
        if (!sys_bytes_equal(e->doc.sys, snap[i])) {
            worst = i;
            fail_msg("redo %d (\"%s\") differs", i, steps[i - 1]);
        }
    }
    ok(e, "undo 5");
    assert_true(sys_bytes_equal(e->doc.sys, snap[N - 5]));
    /* A new change drops what could be redone. */
    ok(e, "set 1 conic -1");
    assert_true(cmd_exec(e, "redo") & ED_ERROR);
    print_message("# %d kinds of change undone to the original and redone: all byte-identical "
                  "(memcmp), first mismatch %d\n", N, worst);
    for (i = 0; i <= N; i++)
        sg_system_free(snap[i]);
    free_ed(e);
}

static void test_modified_flag(void **state)
{
    ed *e = new_ed();
    sg_system *s;
    assert_false(doc_modified(&e->doc));
    ok(e, "set 1 radius 10");
    assert_true(doc_modified(&e->doc));
    ok(e, "undo");
    assert_false(doc_modified(&e->doc));
    ok(e, "redo");
    assert_true(doc_modified(&e->doc));
    ok(e, "undo");
    s = e->doc.sys;
    assert_true(same_bits(s->surf[1].radius, INFINITY));
    assert_false(doc_modified(&e->doc));
    free_ed(e);
}

static void test_modified_save(void **state)
{
    char path[512];
    ed *e = new_ed();
    size_t depth;
    assert_true(cmd_exec(e, "save") & ED_ERROR); /* no file name yet */
    ok(e, "set 1 radius 10");
    run(e, "save %s", tmp_path("mod.json", path, sizeof path));
    assert_false(e->msg_err);
    assert_false(doc_modified(&e->doc));
    assert_string_equal(doc_path(&e->doc), path);
    ok(e, "set 1 radius 20");
    assert_true(doc_modified(&e->doc));
    ok(e, "undo");
    assert_false(doc_modified(&e->doc)); /* back to what the file holds */
    depth = doc_undo_depth(&e->doc);
    ok(e, "set 1 radius 10"); /* the value it already has */
    assert_int_equal(doc_undo_depth(&e->doc), depth);
    assert_false(doc_modified(&e->doc));
    /* quit refuses unsaved changes in batch mode; quit! does not. */
    ok(e, "set 1 radius 30");
    assert_true(cmd_exec(e, "quit") & ED_ERROR);
    assert_true(cmd_exec(e, "quit!") & ED_QUIT);
    assert_true(cmd_exec(e, "open examples/none.json") & ED_ERROR);
    free_ed(e);
}

static void test_save_load_exact(void **state)
{
    char path[512];
    ed *e = new_ed();
    sg_system *back;
    sg_diag d;
    int i;
    for (i = 0; i < 4; i++)
        ok(e, "insert 1");
    ok(e, "set 1 radius 0.1");
    ok(e, "set 1 thickness 1.0000000000000002");
    ok(e, "set 2 radius -3.3333333333333335");
    ok(e, "set 2 conic -1.0000000000000002");
    ok(e, "set 2 a4 1.2345678901234567e-7");
    ok(e, "set 2 a16 -4.9406564584124654e-324");
    ok(e, "set 3 semi 12.7 U");
    ok(e, "set 3 material 1.5168");
    ok(e, "set 4 material mirror");
    ok(e, "set 4 thickness -7.25");
    ok(e, "set 4 comment \"a comment, with \\\"quotes\\\"\"");
    ok(e, "stop 3");
    ok(e, "wavelength add 0.4861327");
    ok(e, "field add 0 0.7071067811865476");
    ok(e, "aperture epd 25.4");
    ok(e, "aim paraxial");
    ok(e, "title round trip");
    run(e, "save %s", tmp_path("rt.json", path, sizeof path));
    assert_false(e->msg_err);
    back = sg_system_new();
    sg_diag_clear(&d);
    if (sg_design_load(back, path, &d) != SG_OK)
        fail_msg("reload: %s", d.msg);
    assert_int_equal(back->nsurf, e->doc.sys->nsurf);
    for (i = 0; i < back->nsurf; i++) {
        const sg_surface *a = &e->doc.sys->surf[i], *b = &back->surf[i];
        int k;
        assert_true(same_bits(a->radius, b->radius) || (isinf(a->radius) && isinf(b->radius)));
        assert_true(same_bits(a->thickness, b->thickness));
        assert_true(same_bits(a->conic, b->conic));
        assert_true(same_bits(a->semi_diameter, b->semi_diameter));
        assert_int_equal(a->sd_fixed, b->sd_fixed);
        assert_int_equal(a->mat.kind, b->mat.kind);
        if (a->mat.kind == SG_MAT_INDEX)
            assert_true(same_bits(a->mat.index, b->mat.index));
        assert_string_equal(a->comment, b->comment);
        for (k = 0; k < SG_NASPH; k++)
            assert_true(same_bits(a->asph[k], b->asph[k]));
    }
    assert_true(doc_system_equal(e->doc.sys, back));
    /* The editor's own open gives the same document. */
    run(e, "open %s", path);
    assert_false(e->msg_err);
    assert_true(doc_system_equal(e->doc.sys, back));
    print_message("# saved and reloaded %d surfaces: every double bit-identical\n", back->nsurf);
    sg_system_free(back);
    free_ed(e);
}

/* Runs a script through ed_batch() with stderr captured. */
static int batch(ed *e, const char *script_text, char *err, size_t errn)
{
    char spath[512], epath[512];
    FILE *f;
    int saved, fd, rc;
    ssize_t n;
    tmp_path("script.txt", spath, sizeof spath);
    tmp_path("stderr.txt", epath, sizeof epath);
    f = fopen(spath, "w");
    assert_non_null(f);
    fputs(script_text, f);
    fclose(f);
    fflush(stderr);
    saved = dup(2);
    fd = open(epath, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    assert_true(fd >= 0);
    dup2(fd, 2);
    close(fd);
    rc = ed_batch(e, spath);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    fd = open(epath, O_RDONLY);
    n = read(fd, err, errn - 1);
    close(fd);
    err[n > 0 ? n : 0] = '\0';
    return rc;
}

static void test_batch(void **state)
{
    char err[2048], path[512], script[2048];
    ed *e = new_ed();
    int rc;
    snprintf(script, sizeof script,
             "# a comment, then a blank line\n\n"
             "insert 1\n"
             "set 1 radius 100\n"
             "set 1 material 1.5\n"
             "set 1 thickness 5\n"
             "set 2 radius -100\n"
             "save %s\n",
             tmp_path("batch.json", path, sizeof path));
    rc = batch(e, script, err, sizeof err);
    assert_int_equal(rc, 0);
    assert_string_equal(err, "");
    assert_true(same_bits(e->doc.sys->surf[2].radius, -100.0));
    assert_false(doc_modified(&e->doc));
    free_ed(e);

    e = new_ed();
    rc = batch(e, "set 1 radius 7\nset 1 thickness 2\nset 1 radius seven\nset 1 radius 9\n", err,
               sizeof err);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(err, ":3: "));
    assert_non_null(strstr(err, "seven"));
    /* The first error stops the script. */
    assert_true(same_bits(e->doc.sys->surf[1].radius, 7.0));
    print_message("# batch: 6 commands ran; a bad line 3 stopped the next with: %s", err);
    free_ed(e);
}

static void test_export_matches_trace(void **state)
{
    char path[512], line[4096];
    ed *e = new_ed();
    sg_tracer *t;
    sg_ray_surface *ref;
    sg_diag d;
    FILE *f;
    int nsurf, row = 0, checked = 0;
    double worst = 0.0;
    char ex[1024];
    run(e, "open %s", tu_path("examples/cassegrain.json", ex, sizeof ex));
    if (e->msg_err)
        fail_msg("%s", e->msg);
    ok(e, "ray 0 1 0 1");
    run(e, "export %s", tmp_path("ray.csv", path, sizeof path));
    assert_false(e->msg_err);

    nsurf = e->doc.sys->nsurf;
    ref = calloc((size_t)nsurf, sizeof *ref);
    sg_diag_clear(&d);
    t = sg_tracer_new(e->doc.sys, e->cat, &e->opts, &d);
    assert_non_null(t);
    sg_trace_normalized(t, 0, 1, 0, 1, ref);
    f = fopen(path, "r");
    assert_non_null(f);
    while (fgets(line, sizeof line, f)) {
        double v[6], in[4];
        int s;
        /* Each row begins with the ray's launch, hx,hy,px,py. */
        if (sscanf(line, "%lf,%lf,%lf,%lf,%d,%lf,%lf,%lf,%lf,%lf,%lf", &in[0], &in[1], &in[2],
                   &in[3], &s, &v[0], &v[1], &v[2], &v[3], &v[4], &v[5]) != 11)
            continue;
        assert_true(in[0] == 0 && in[1] == 1 && in[2] == 0 && in[3] == 1);
        assert_int_equal(s, row);
        assert_true(same_bits(v[0], ref[s].x) && same_bits(v[1], ref[s].y) &&
                    same_bits(v[2], ref[s].z));
        assert_true(same_bits(v[3], ref[s].l) && same_bits(v[4], ref[s].m) &&
                    same_bits(v[5], ref[s].n));
        if (fabs(v[1] - ref[s].y) > worst)
            worst = fabs(v[1] - ref[s].y);
        row++;
        checked += 6;
    }
    fclose(f);
    assert_int_equal(row, nsurf);
    /* Zemax prints -162.77753496 for surface 8's y (the paper's Table 4):
     * those are the leading digits of the value. */
    assert_true(ref[8].y <= -162.77753496 && ref[8].y > -162.77753497);
    print_message("# export: %d numbers equal sg_trace_normalized() bit for bit (worst %g); "
                  "surface 8 y = %.11f vs Zemax -162.77753496\n", checked, worst, ref[8].y);
    sg_tracer_free(t);
    free(ref);
    free_ed(e);
}

static void test_numfmt(void **state)
{
    static const double v[] = {0.1, -162.77753496507066, 1e-300, 6.02214076e23, 1.0 / 3.0,
                               -2.5, 123456789012.5, 4.9406564584124654e-324, 100.0,
                               4500.0, 5e8, 5e-5, 1.25e-12};
    char s[NUMFMT_MAX], fit[64], less[400];
    size_t i;
    int w;
    for (i = 0; i < sizeof v / sizeof v[0]; i++) {
        numfmt_shortest(v[i], s, sizeof s);
        /* It reads back, and one digit fewer would not. */
        assert_true(same_bits(strtod(s, NULL), v[i]));
        {
            /* Significant digits: from the first nonzero one to the last
             * (zeros that only place the point do not count). */
            int p = 0, k = 0, first = -1, last = -1;
            char *q;
            for (q = s; *q && *q != 'e'; q++)
                if (*q >= '0' && *q <= '9') {
                    if (*q != '0') {
                        if (first < 0)
                            first = k;
                        last = k;
                    }
                    k++;
                }
            p = first < 0 ? 1 : last - first + 1;
            if (p > 1) {
                snprintf(less, sizeof less, "%.*g", p - 1, v[i]);
                assert_false(same_bits(strtod(less, NULL), v[i]));
            }
        }
        for (w = 4; w <= 24; w++) {
            numfmt_fit(s, w, "~", fit, sizeof fit);
            assert_true((int)strlen(fit) <= w);
            if (!strchr(fit, '~') && !strchr(fit, '#')) {
                assert_true(same_bits(strtod(fit, NULL), v[i]));
            }
        }
    }
    numfmt_fit("-162.77753496507066", 10, "~", fit, sizeof fit);
    assert_string_equal(fit, "-162.7775~");
    numfmt_fit("123456789012.5", 8, "~", fit, sizeof fit);
    assert_string_equal(fit, "1.23~e11");
    print_message("# shortest text of %zu doubles reads back exactly; cut text never exceeds "
                  "its width\n", sizeof v / sizeof v[0]);
}

/* The glass picker through the command path: by name and by nd and vd,
 * each glass with its index at the primary wavelength (checked against
 * sg_glass_index and, with "adjust on", sg_glass_index_env); "pick" goes
 * through "set" and undoes as one change; the environment commands. */
static void test_glass_picker(void **state)
{
    ed *e = new_ed();
    const gp_list *l = &e->glasses;
    const sg_glass *g;
    double um;
    int i, f;
    char cmd[64];
    (void)state;
    if (!e->cat) {
        print_message("# SKIP no glass catalog: %s\n", e->cat_msg);
        free_ed(e);
        return;
    }
    um = e->doc.sys->wave[e->doc.sys->primary_wave].um;
    ok(e, "glasses n-sf");
    assert_true(l->n >= 5);
    for (i = 0; i < l->n; i++) {
        assert_non_null(strstr(l->hit[i].g->name, "N-SF"));
        assert_true(l->hit[i].n == sg_glass_index(l->hit[i].g, um));
        if (i > 0)
            assert_true(strcmp(l->hit[i - 1].g->name, l->hit[i].g->name) <= 0);
    }
    /* Nearest by nd and vd: N-BK7's own figures (nd 1.5168, vd 64.17)
     * find it among the first, at distance 0 with the other glasses whose
     * NM line gives the same figures (SCHOTT's N-BK7HT and N-BK7HTi), then
     * the rest, farther; GP_MAX caps the list. */
    ok(e, "glasses 1.5168 64.17");
    assert_int_equal(l->n, sg_catalog_count(e->cat) < GP_MAX ? (int)sg_catalog_count(e->cat)
                                                              : GP_MAX);
    f = 0;
    for (i = 0; i < l->n && l->hit[i].dist == 0.0; i++) {
        assert_true(l->hit[i].g->nd == 1.5168 && l->hit[i].g->vd == 64.17);
        f |= strcmp(l->hit[i].g->name, "N-BK7") == 0;
    }
    assert_true(f && i >= 3 && i < l->n);
    for (i = 1; i < l->n; i++)
        assert_true(l->hit[i - 1].dist <= l->hit[i].dist);

    /* pick sets the cursor surface's material through "set". */
    ok(e, "goto 1");
    ok(e, "glasses n-bk7");
    /* By name: N-BK7 first, then SCHOTT's N-BK7HT and N-BK7HTi. */
    assert_true(l->n >= 1);
    assert_string_equal(l->hit[0].g->name, "N-BK7");
    ok(e, "pick 1");
    assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_GLASS);
    assert_string_equal(e->doc.sys->surf[1].mat.name, "N-BK7");
    ok(e, "undo");
    assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_AIR);
    snprintf(cmd, sizeof cmd, "pick %d", l->n + 1);
    f = cmd_exec(e, cmd);
    assert_true(f & ED_ERROR);
    snprintf(cmd, sizeof cmd, "not one of 1 to %d", l->n);
    assert_non_null(strstr(e->msg, cmd));
    f = cmd_exec(e, "pick 1.5");
    assert_true(f & ED_ERROR);
    ok(e, "goto 0");
    f = cmd_exec(e, "pick 1");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "cursor is on surface 0"));
    ok(e, "glasses nosuchglass");
    assert_int_equal(l->n, 0);
    f = cmd_exec(e, "pick 1");
    assert_true(f & ED_ERROR);

    /* A name several catalogs use: every catalog's glass is listed, and
     * picking one the name alone does not mean (INFRARED's barium
     * fluoride, by the search order) names its catalog. */
    ok(e, "goto 1");
    ok(e, "glasses baf2");
    f = -1;
    for (i = 0; i < l->n; i++)
        if (strcmp(l->hit[i].g->name, "BAF2") == 0 && strcmp(l->hit[i].g->catalog, "HOYA") == 0)
            f = i;
    assert_true(f >= 0);
    snprintf(cmd, sizeof cmd, "pick %d", f + 1);
    ok(e, cmd);
    assert_string_equal(e->doc.sys->surf[1].mat.name, "BAF2");
    assert_string_equal(e->doc.sys->surf[1].mat.catalog, "HOYA");
    g = sg_material_glass(e->cat, &e->doc.sys->surf[1].mat);
    assert_true(fabs(g->nd - 1.569650) < 1e-9);
    /* Typed: CATALOG:NAME, or the name alone. */
    ok(e, "set 1 material infrared:baf2");
    assert_string_equal(e->doc.sys->surf[1].mat.catalog, "");
    ok(e, "set 1 material cdgm:baf2");
    assert_string_equal(e->doc.sys->surf[1].mat.catalog, "CDGM");
    f = cmd_exec(e, "set 1 material schott:baf2");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "surface 1 material: catalog schott has no glass \"baf2\""));
    ok(e, "undo");
    ok(e, "undo");
    ok(e, "undo");
    assert_int_equal(e->doc.sys->surf[1].mat.kind, SG_MAT_AIR);

    /* The environment: indices in the list follow it once adjusted. */
    ok(e, "temperature 40");
    ok(e, "pressure 0.5");
    ok(e, "adjust on");
    assert_true(e->doc.sys->temperature == 40.0 && e->doc.sys->pressure == 0.5 &&
                e->doc.sys->adjust_index == 1);
    ok(e, "glasses S-LAH64");
    g = sg_catalog_find(e->cat, "S-LAH64");
    assert_int_equal(l->n, 1);
    assert_true(l->hit[0].n == sg_glass_index_env(g, um, 40.0, 0.5));
    assert_true(l->hit[0].n != sg_glass_index(g, um));
    f = cmd_exec(e, "temperature -300");
    assert_true(f & ED_ERROR);
    f = cmd_exec(e, "pressure 1000");
    assert_true(f & ED_ERROR);
    ok(e, "undo");
    ok(e, "undo");
    ok(e, "undo");
    assert_true(e->doc.sys->temperature == 20.0 && e->doc.sys->pressure == 1.0 &&
                e->doc.sys->adjust_index == 0);
    free_ed(e);
}

/* ":thermal T" is the engine's sg_thermal as one edit: the singlet's
 * radius grows by N-BK7's catalog TCE (7.1e-6/K, its ED line), the mount's
 * tce typed in the TCE column is kept, one undo restores every byte, and a
 * temperature beyond the limits changes nothing. */
static void test_thermal(void **state)
{
    ed *e = new_ed();
    char ex[512];
    sg_system *before;
    int f;
    (void)state;
    run(e, "open %s", tu_path("examples/singlet.json", ex, sizeof ex));
    ok(e, "set 2 tce 23.6");
    assert_true(e->doc.sys->surf[2].tce == 23.6);
    before = sg_system_clone(e->doc.sys);
    f = cmd_exec(e, "thermal 1001");
    assert_true(f & ED_ERROR);
    if (!strstr(e->msg, "temperature 1001 C is outside"))
        fail_msg("message: %s", e->msg);
    assert_true(sys_bytes_equal(e->doc.sys, before));
    ok(e, "thermal 60");
    assert_true(e->doc.sys->surf[1].radius == 51.5 * (1.0 + 7.1 * 1e-6 * 40.0));
    assert_true(e->doc.sys->temperature == 60.0 && e->doc.sys->adjust_index == 1 &&
                e->doc.sys->surf[2].tce == 23.6);
    ok(e, "undo");
    assert_true(sys_bytes_equal(e->doc.sys, before));
    sg_system_free(before);
    free_ed(e);
}

/* "telecentric on" turns on Zemax's telecentric object space only with
 * what Zemax requires (an object NA, a finite object, height fields), which
 * then stay so; undo turns it off again. */
static void test_telecentric(void **state)
{
    ed *e = new_ed();
    int f;
    (void)state;
    ok(e, "set 0 thickness 100");
    ok(e, "aperture epd 10");
    f = cmd_exec(e, "telecentric on");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "the aperture must be the object NA"));
    ok(e, "aperture na 0.1");
    ok(e, "field type angle");
    f = cmd_exec(e, "telecentric on");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "the fields must be heights"));
    ok(e, "field type object");
    ok(e, "telecentric on");
    assert_int_equal(e->doc.sys->telecentric, 1);
    f = cmd_exec(e, "aperture epd 10");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "telecentric off first"));
    f = cmd_exec(e, "field type angle");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "telecentric off first"));
    /* Zemax's object cone angle, in degrees, is the other aperture allowed. */
    ok(e, "aperture cone 6");
    assert_true(e->doc.sys->aper_type == SG_APER_OBJECT_CONE && e->doc.sys->aper_value == 6.0);
    f = cmd_exec(e, "aperture cone 90");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "below 90 degrees"));
    ok(e, "undo");
    ok(e, "undo");
    assert_int_equal(e->doc.sys->telecentric, 0);
    ok(e, "telecentric toggle");
    assert_int_equal(e->doc.sys->telecentric, 1);
    free_ed(e);
}

/* Which keys type into a cell rather than run a command (issue 30, items
 * 13 and 14).  The reference for a number cell is the C library's strtod:
 * a key may begin a value when strtod reads some text that starts with it
 * whole (leading blanks aside: a blank is the Space key's toggle, not a
 * value's first character). */
static void test_key_begins(void)
{
    static const char *const tails[] = {"", "1", "5", ".5", "nf", "nfinity", "an", "0"};
    int k;
    size_t t;
    for (k = 0x21; k < 0x7f; k++) {
        int reads = 0;
        for (t = 0; t < sizeof tails / sizeof tails[0]; t++) {
            char buf[16], *end;
            snprintf(buf, sizeof buf, "%c%s", k, tails[t]);
            errno = 0;
            (void)strtod(buf, &end);
            if (end != buf && *end == '\0')
                reads = 1;
        }
        /* Hex (0x...) and exponents follow a digit; 'e' alone reads nothing. */
        if (cell_key_begins(COL_RADIUS, k) != reads ||
            cell_key_begins(COL_THICKNESS, k) != reads || cell_key_begins(COL_CONIC, k) != reads)
            fail_msg("key '%c': strtod %s a value beginning with it, but the cell says %d", k,
                     reads ? "reads" : "reads no", cell_key_begins(COL_RADIUS, k));
        /* Text cells take every printable key but ':', the command line's. */
        assert_int_equal(cell_key_begins(COL_COMMENT, k), k != ':');
        assert_int_equal(cell_key_begins(COL_MATERIAL, k), k != ':');
    }
    /* A UTF-8 letter types in a comment; nothing below the blank does. */
    assert_int_equal(cell_key_begins(COL_COMMENT, 0xE9), 1);
    assert_int_equal(cell_key_begins(COL_COMMENT, '\t'), 0);
    /* Type: the first letters of the names sagitta(1) lists (STANDARD,
     * EVENASPH, COORDBRK or cb, ODDASPHE, TOROIDAL, BICONICX, FZERNSAG,
     * SZERNSAG, XPOLYNOM, QTYPEASP, PARAXIAL, DGRATING, asph); i, n, u, w,
     * ':' are none. */
    {
        const char *yes = "seEcCotbfzxaqpd", *no = "inuwhjkl:0";
        for (; *yes; yes++)
            assert_int_equal(cell_key_begins(COL_TYPE, *yes), 1);
        for (; *no; no++)
            assert_int_equal(cell_key_begins(COL_TYPE, *no), 0);
    }
}

static void test_keys(void **state)
{
    (void)state;
    test_key_begins();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_numfmt),
        cmocka_unit_test(test_keys),
        cmocka_unit_test(test_set_exact),
        cmocka_unit_test(test_set_shapes),
        cmocka_unit_test(test_frame_columns),
        cmocka_unit_test(test_set_text_cells),
        cmocka_unit_test(test_bad_values),
        cmocka_unit_test(test_insert_delete_stop),
        cmocka_unit_test(test_solve_command),
        cmocka_unit_test(test_undo_redo_exact),
        cmocka_unit_test(test_modified_flag),
        cmocka_unit_test(test_modified_save),
        cmocka_unit_test(test_save_load_exact),
        cmocka_unit_test(test_batch),
        cmocka_unit_test(test_glass_picker),
        cmocka_unit_test(test_telecentric),
        cmocka_unit_test(test_thermal),
        cmocka_unit_test(test_export_matches_trace),
    };
    static const char *const files[] = {"mod.json", "rt.json", "script.txt", "stderr.txt",
                                        "batch.json", "ray.csv"};
    char path[512];
    size_t i;
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    if (tmpdir[0]) {
        for (i = 0; i < sizeof files / sizeof files[0]; i++)
            unlink(tmp_path(files[i], path, sizeof path));
        rmdir(tmpdir);
    }
    return rc;
}
