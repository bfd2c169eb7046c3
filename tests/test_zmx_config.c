/*
 * test_zmx_config.c - configurations (issue 37): Zemax's Multi-Configuration
 * Editor rows read from a .zmx file, configuration N's design, the JSON
 * object, the .zmx save keeping the MNUM lines byte for byte, and refusals.
 *
 * The fixture restates the lines that matter of Zemax's sample "Zoom
 * lens.zmx" (VERS 91110; repository yiningli/Project_X, commit
 * 0da5949fe154939ceaefaa6c26119c04f43b85a2, path
 * Database_Files/Zemax_Data/Optical_System_Data/Zemax_Files/Sequential/Zoom
 * systems/Zoom lens.zmx, blob 969bfbc27b65098f274daa356cf1b7c11c368f9d; no
 * licence stated, so the file is not copied): a 29-78 mm zoom
 * (US 4936661, embodiment 4) whose three configurations change the F
 * number (APER: 5, 6.2, 7.8) and the thicknesses after surfaces 8 and 15.
 * The expected designs are the same text with each configuration's values
 * written into its FNUM and DISZ lines by hand; the expected number is
 * Zemax's stored stop semi-diameter of configuration 1.
 */
#define _GNU_SOURCE /* mkdtemp */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

/* FNUM, DISZ of surface 8, DISZ of surface 15, the rows after the surfaces. */
static const char zoom_fmt[] =
    "UNIT MM X W X CM MR CPMM\n"
    "FNUM %s 0\n"
    "GCAT OHARA HIKARI\n"
    "FTYP 2 0 3 3 0 0 0\n"
    "XFLN 0 0 0 0 0 0 0 0 0 0 0 0\n"
    "YFLN 0 4.1 5.8 0 0 0 0 0 0 0 0 0\n"
    "FWGN 1 1 1 1 1 1 1 1 1 1 1 1\n"
    "WAVM 1 5.8756E-1 1\n"
    "WAVM 2 4.8613E-1 1\n"
    "WAVM 3 6.5627E-1 1\n"
    "PWAV 1\n"
    "SURF 0\n"
    "  TYPE STANDARD\n"
    "  CURV 0.0 0 0 0 0 \"\"\n"
    "  DISZ INFINITY\n"
    "SURF 1\n"
    "  STOP\n"
    "  TYPE STANDARD\n"
    "  CURV 0.0 0 0 0 0 \"\"\n"
    "  DISZ 0\n"
    "SURF 2\n"
    "  TYPE STANDARD\n"
    "  CURV -6.171999999999999700E-002 0 0 0 0 \"\"\n"
    "  DISZ 5.18\n"
    "  GLAS LAH66 0 0 1.7762 4.94E+1 0 0 0 0 0 0 \n"
    "SURF 3\n"
    "  TYPE STANDARD\n"
    "  CURV -2.045999999999999900E-002 0 0 0 0 \"\"\n"
    "  DISZ 1.0E-1\n"
    "SURF 4\n"
    "  TYPE STANDARD\n"
    "  CURV 6.382999999999999800E-002 0 0 0 0 \"\"\n"
    "  DISZ 4.4\n"
    "  GLAS LLF6 0 0 1.5343 4.86E+1 0 0 0 0 0 0 \n"
    "SURF 5\n"
    "  TYPE EVENASPH\n"
    "  CURV -2.327999999999999900E-002 0 0 0 0 \"\"\n"
    "  PARM 1 0\n"
    "  PARM 2 1.0386E-4\n"
    "  PARM 3 1.4209E-7\n"
    "  PARM 4 -8.8495E-9\n"
    "  PARM 5 1.2477E-10\n"
    "  PARM 6 -1.0367E-12\n"
    "  PARM 7 3.6556E-15\n"
    "  PARM 8 0\n"
    "  DISZ 1.6E-1\n"
    "SURF 6\n"
    "  TYPE STANDARD\n"
    "  CURV 9.199999999999999800E-003 0 0 0 0 \"\"\n"
    "  DISZ 1\n"
    "  GLAS TIH6 0 0 1.8127 2.53E+1 0 0 0 0 0 0 \n"
    "SURF 7\n"
    "  TYPE STANDARD\n"
    "  CURV 4.233000000000000000E-002 0 0 0 0 \"\"\n"
    "  DISZ 4.96\n"
    "  GLAS FSL5 0 0 1.4891 7.02E+1 0 0 0 0 0 0 \n"
    "SURF 8\n"
    "  TYPE EVENASPH\n"
    "  CURV -6.226999999999999900E-002 0 0 0 0 \"\"\n"
    "  PARM 1 0\n"
    "  PARM 2 4.2721E-5\n"
    "  PARM 3 1.2484E-7\n"
    "  PARM 4 9.7079E-9\n"
    "  PARM 5 -1.8444E-10\n"
    "  PARM 6 1.8644E-12\n"
    "  PARM 7 -7.7975E-15\n"
    "  PARM 8 0\n"
    "  DISZ %s\n"
    "SURF 9\n"
    "  TYPE EVENASPH\n"
    "  CURV -2.350000000000000100E-003 0 0 0 0 \"\"\n"
    "  PARM 1 0\n"
    "  PARM 2 1.1339E-4\n"
    "  PARM 3 4.8165E-7\n"
    "  PARM 4 1.8778E-8\n"
    "  PARM 5 -5.7571E-10\n"
    "  PARM 6 8.9994E-12\n"
    "  PARM 7 -4.6768E-14\n"
    "  PARM 8 0\n"
    "  DISZ 4.04\n"
    "  GLAS FSL5 0 0 1.4891 7.02E+1 0 0 0 0 0 0 \n"
    "SURF 10\n"
    "  TYPE STANDARD\n"
    "  CURV -2.821999999999999900E-002 0 0 0 0 \"\"\n"
    "  DISZ 1.35\n"
    "SURF 11\n"
    "  TYPE STANDARD\n"
    "  CURV -7.069000000000000300E-002 0 0 0 0 \"\"\n"
    "  DISZ 1\n"
    "  GLAS LAL8 0 0 1.7162 5.37E+1 0 0 0 0 0 0 \n"
    "SURF 12\n"
    "  TYPE STANDARD\n"
    "  CURV -3.980000000000000000E-003 0 0 0 0 \"\"\n"
    "  DISZ 2.8\n"
    "  GLAS PBH25 0 0 1.7617 2.73E+1 0 0 0 0 0 0 \n"
    "SURF 13\n"
    "  TYPE STANDARD\n"
    "  CURV -4.444000000000000000E-002 0 0 0 0 \"\"\n"
    "  DISZ 3.0\n"
    "SURF 14\n"
    "  TYPE STANDARD\n"
    "  CURV -9.449000000000000500E-002 0 0 0 0 \"\"\n"
    "  DISZ 1.22\n"
    "  GLAS LAH66 0 0 1.7762 4.94E+1 0 0 0 0 0 0 \n"
    "SURF 15\n"
    "  TYPE STANDARD\n"
    "  CURV -2.249999999999999900E-002 0 0 0 0 \"\"\n"
    "  DISZ %s\n"
    "SURF 16\n"
    "  TYPE STANDARD\n"
    "  CURV 0.0 0 0 0 0 \"\"\n"
    "  DISZ 0\n"
    "%s\n";

static const char zoom_mce[] =
    "MNUM 3 1\n"
    "APER   0   1 5.000000000000E+000 0 0 0 1 1 1.000000000000E+000 0.000000000000E+000 0\n"
    "APER   0   2 6.200000000000E+000 0 0 0 2 1 1.000000000000E+000 0.000000000000E+000 0\n"
    "APER   0   3 7.800000000000E+000 0 0 0 3 1 1.000000000000E+000 0.000000000000E+000 0\n"
    "THIC   8   1 9.480000000000E+000 0 0 0 1 2 1.000000000000E+000 0.000000000000E+000 0\n"
    "THIC   8   2 4.480000000000E+000 0 0 0 2 2 1.000000000000E+000 0.000000000000E+000 0\n"
    "THIC   8   3 2.000000000000E+000 0 0 0 3 2 1.000000000000E+000 0.000000000000E+000 0\n"
    "THIC  15   1 4.469706130000E+000 0 0 0 1 3 1.000000000000E+000 0.000000000000E+000 0\n"
    "THIC  15   2 2.121000000000E+001 0 0 0 2 3 1.000000000000E+000 0.000000000000E+000 0\n"
    "THIC  15   3 4.381000000000E+001 0 0 0 3 3 1.000000000000E+000 0.000000000000E+000 0\n";

/* Configuration k's values as the rows give them, copied by hand. */
static const char *const fnum[3] = {"5.0", "6.2", "7.8"};
static const char *const t8[3] = {"9.48", "4.48", "2.0"};
static const char *const t15[3] = {"4.46970613", "21.21", "43.81"};

static char *zoom_text(const char *f, const char *a, const char *b, const char *mce)
{
    size_t n = sizeof zoom_fmt + strlen(mce) + 64;
    char *t = malloc(n);
    assert_non_null(t);
    snprintf(t, n, zoom_fmt, f, a, b, mce);
    return t;
}

static sg_system *parse(const char *text, const sg_catalog *cat, int want)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    int rc;
    assert_non_null(s);
    sg_diag_clear(&d);
    rc = sg_zmx_parse(s, text, strlen(text), "zoom.zmx", cat, &d);
    if (rc != want)
        fail_msg("parse: %s (rc %d, wanted %d)", d.msg, rc, want);
    return s;
}

static void ray(const sg_system *s, const sg_catalog *cat, sg_ray_surface *r)
{
    sg_trace_opts o;
    sg_tracer *t;
    sg_diag d;
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    t = sg_tracer_new(s, cat, &o, &d);
    if (!t)
        fail_msg("tracer: %s", d.msg);
    /* The edge field's upper marginal ray. */
    assert_int_equal(sg_trace_normalized(t, 0, 1, 0, 1, r), SG_OK);
    sg_tracer_free(t);
}

/* Configuration k of the file is the file edited by hand to k's values:
 * the same design, parameter for parameter, and the same ray. */
static void test_zoom_configurations(void **state)
{
    sg_catalog *cat = tu_catalog();
    char *text = zoom_text(fnum[0], t8[0], t15[0], zoom_mce);
    sg_system *base = parse(text, cat, SG_OK);
    int k, i;
    (void)state;
    assert_int_equal(sg_config_count(base), 3);
    assert_int_equal(base->configs->nop, 3);
    for (k = 1; k <= 3; k++) {
        char *ht = zoom_text(fnum[k - 1], t8[k - 1], t15[k - 1], "");
        sg_system *hand = parse(ht, cat, SG_OK), *c = sg_system_clone(base);
        sg_ray_surface *ra = calloc((size_t)base->nsurf, sizeof *ra);
        sg_ray_surface *rb = calloc((size_t)base->nsurf, sizeof *rb);
        sg_paraxial pa, pb;
        sg_diag d;
        assert_non_null(c);
        assert_non_null(ra);
        assert_non_null(rb);
        sg_diag_clear(&d);
        assert_int_equal(sg_config_apply(c, k, &d), SG_OK);
        assert_int_equal(sg_config_count(hand), 1);
        assert_true(c->aper_value == strtod(fnum[k - 1], NULL));
        assert_true(c->surf[8].thickness == strtod(t8[k - 1], NULL));
        assert_true(c->surf[15].thickness == strtod(t15[k - 1], NULL));
        ray(c, cat, ra);
        ray(hand, cat, rb);
        for (i = 0; i < base->nsurf; i++)
            assert_memory_equal(&ra[i], &rb[i], sizeof ra[i]);
        assert_int_equal(sg_paraxial_compute(c, cat, -1, &pa, &d), SG_OK);
        assert_int_equal(sg_paraxial_compute(hand, cat, -1, &pb, &d), SG_OK);
        assert_true(pa.efl == pb.efl);
        print_message("# configuration %d: EFL %.15g, F/%s\n", k, pa.efl, fnum[k - 1]);
        if (k == 1) {
            /* The stop is surface 1, the entrance pupil: Zemax's stored
             * DIAM 2.897739804036 (13 digits) is EFL / (2 F). */
            assert_true(fabs(pa.efl / (2 * 5.0) - 2.897739804036) <= 1e-12);
        }
        /* Without the rows the design is configuration k's alone. */
        sg_configs_release(c->configs);
        c->configs = NULL;
        assert_true(sg_system_equal(c, hand));
        free(ra);
        free(rb);
        sg_system_free(c);
        sg_system_free(hand);
        free(ht);
    }
    sg_diag d;
    sg_diag_clear(&d);
    assert_int_equal(sg_config_apply(base, 4, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "configurations 1 to 3"));
    sg_system_free(base);
    free(text);
    sg_catalog_free(cat);
}

/* The .zmx save keeps the MNUM rows byte for byte; JSON and sagitta's own
 * .zmx text carry the configurations. */
static void test_zoom_save(void **state)
{
    sg_catalog *cat = tu_catalog();
    char *text = zoom_text(fnum[0], t8[0], t15[0], zoom_mce), dir[] = "/tmp/sagitta_cfg_XXXXXX";
    char path[256], path2[256], *json, *json2;
    sg_system *s = sg_system_new(), *r = sg_system_new();
    FILE *f;
    size_t n;
    char *back;
    sg_diag d;
    (void)state;
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/zoom.zmx", dir);
    snprintf(path2, sizeof path2, "%s/out.zmx", dir);
    f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(s, path, &d), SG_OK);
    assert_int_equal(sg_design_save(s, path2, &d), SG_OK);
    f = fopen(path2, "rb");
    assert_non_null(f);
    back = calloc(1, strlen(text) + 2);
    n = fread(back, 1, strlen(text) + 1, f);
    fclose(f);
    assert_int_equal(n, strlen(text));
    assert_memory_equal(back, text, n);
    free(back);
    /* JSON: the configurations object reads back the same. */
    json = sg_design_to_json(s);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"configurations\""));
    assert_non_null(strstr(json, "{ \"type\": \"THIC\", \"surface\": 15, \"values\": "
                                 "[4.46970613, 21.21, 43.81] }"));
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(r, json, strlen(json), "zoom.json", &d), SG_OK);
    assert_true(sg_configs_equal(r->configs, s->configs));
    /* sagitta's own .zmx text of a JSON design writes the rows. */
    assert_int_equal(sg_design_save(r, path2, &d), SG_OK);
    sg_system_free(r);
    r = sg_system_new();
    assert_int_equal(sg_design_load(r, path2, &d), SG_OK);
    assert_true(sg_configs_equal(r->configs, s->configs));
    json2 = sg_design_to_json(r);
    assert_string_equal(json2, json);
    free(json);
    free(json2);
    unlink(path);
    unlink(path2);
    rmdir(dir);
    sg_system_free(s);
    sg_system_free(r);
    free(text);
    sg_catalog_free(cat);
}

/* The other operands, on the zoom's design: a curvature (CRVT's value is
 * c, the radius 1 / c), a glass, a field and a wavelength, and two rows
 * of one thickness (the later row wins, as rows apply in order).  The
 * values expected are the rows' own numbers. */
static void test_config_operands(void **state)
{
    static const char rows[] =
        "MNUM 2 1\n"
        "CRVT 2 1 -0.06172 0 0 0 1 1 1 0 0\n"
        "CRVT 2 2 0.0125 0 0 0 2 1 1 0 0\n"
        "GLSS 2 1 \"LAH66\" 0 0 0 1 2 0 0.0 \"\"\n"
        "GLSS 2 2 \"\" 0 0 0 2 2 0 0.0 \"\"\n"
        "YFIE 3 1 5.8 0 0 0 1 3 1 0 0\n"
        "YFIE 3 2 2.5 0 0 0 2 3 1 0 0\n"
        "WAVE 2 1 0.48613 0 0 0 1 4 1 0 0\n"
        "WAVE 2 2 0.55 0 0 0 2 4 1 0 0\n"
        "THIC 8 1 9.48 0 0 0 1 5 1 0 0\n"
        "THIC 8 2 4.48 0 0 0 2 5 1 0 0\n"
        "THIC 8 1 7 0 0 0 1 6 1 0 0\n"
        "THIC 8 2 3 0 0 0 2 6 1 0 0\n";
    sg_catalog *cat = tu_catalog();
    char *text = zoom_text(fnum[0], t8[0], t15[0], rows);
    sg_system *s = parse(text, cat, SG_OK), *c = sg_system_clone(s), *plain;
    sg_diag d;
    (void)state;
    assert_int_equal(s->configs->nop, 6);
    sg_diag_clear(&d);
    assert_int_equal(sg_config_apply(c, 2, &d), SG_OK);
    assert_true(c->surf[2].radius == 1.0 / 0.0125);
    assert_int_equal(c->surf[2].mat.kind, SG_MAT_AIR);
    assert_true(c->field[2].y == 2.5);
    assert_true(c->wave[1].um == 0.55);
    assert_true(c->surf[8].thickness == 3.0);
    assert_int_equal(sg_config_apply(c, 1, &d), SG_OK);
    assert_true(c->surf[2].radius == 1.0 / -0.06172);
    assert_int_equal(c->surf[2].mat.kind, SG_MAT_GLASS);
    assert_string_equal(c->surf[2].mat.name, "LAH66");
    assert_true(c->surf[8].thickness == 7.0);
    /* Configurations are part of the design: without them it is another. */
    plain = sg_system_clone(s);
    sg_configs_release(plain->configs);
    plain->configs = NULL;
    assert_false(sg_system_equal(plain, s));
    sg_system_free(plain);
    sg_system_free(c);
    sg_system_free(s);
    free(text);
    sg_catalog_free(cat);
}

static void refused(const sg_catalog *cat, const char *mce, int code, const char *a, const char *b)
{
    char *text = zoom_text(fnum[0], t8[0], t15[0], mce);
    sg_system *s = sg_system_new();
    sg_diag d;
    sg_diag_clear(&d);
    assert_int_equal(sg_zmx_parse(s, text, strlen(text), "zoom.zmx", cat, &d), code);
    if (!strstr(d.msg, a) || (b && !strstr(d.msg, b)))
        fail_msg("message \"%s\" lacks \"%s\" or \"%s\"", d.msg, a, b ? b : "");
    sg_system_free(s);
    free(text);
}

/* Rows sagitta cannot apply, or that leave a configuration out, are
 * refused naming the operand and its line (the MNUM line is 113). */
static void test_config_refusals(void **state)
{
    sg_catalog *cat = tu_catalog();
    (void)state;
    refused(cat, "MNUM 2 1\nEDVA 11 1 0 0 4 0 1 1 1 0 0\nEDVA 11 2 0 0 4 0 2 1 1 0 0\n",
            SG_EUNSUPPORTED, "zoom.zmx:114: MNUM: operand EDVA", "THIC, CRVT");
    refused(cat, "MNUM 2 1\nTHIC 8 1 9.48 0 0 0 1 1 1 0 0\n", SG_EPARSE,
            "zoom.zmx:114: MNUM: operand THIC 8 has no value for configuration 2 of 2", NULL);
    refused(cat, "MNUM 2 1\nTHIC 8 1 9.48 0 0 0 1 1 1 0 0\nTHIC 8 2 9 0 0 0 2 1 1 0 0\n"
                 "THIC 8 2 9 0 0 0 2 1 1 0 0\n",
            SG_EPARSE, "zoom.zmx:116: MNUM: operand THIC 8: configuration 2 given twice", NULL);
    refused(cat, "MNUM 2 1\nTHIC 8 1 9.48 0 0 0 1 1 1 0 0\nTHIC 8 3 9 0 0 0 3 1 1 0 0\n",
            SG_ERANGE, "zoom.zmx:115: configuration", "from 1 to 2");
    refused(cat, "MNUM 2 1\nTHIC 40 1 1 0 0 0 1 1 1 0 0\nTHIC 40 2 1 0 0 0 2 1 1 0 0\n",
            SG_ERANGE, "configuration 1: configuration operand THIC 40", "surfaces 0 to 16");
    refused(cat, "MNUM 2 1\nGLSS 2 1 \"LAH66\" 0 0 0 1 1 0 0.0 \"\"\n"
                 "GLSS 2 2 \"NOSUCHGLASS\" 0 0 0 2 1 0 0.0 \"\"\n",
            SG_ENOGLASS, "zoom.zmx:115", "NOSUCHGLASS");
    refused(cat, "MNUM 2 1\nAPER 0 1 5 0 0 0 1 1 1 0 0\nAPER 0 2 -1 0 0 0 2 1 1 0 0\n",
            SG_ERANGE, "configuration 2:", "aperture");
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_zoom_configurations),
        cmocka_unit_test(test_zoom_save),
        cmocka_unit_test(test_config_operands),
        cmocka_unit_test(test_config_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
