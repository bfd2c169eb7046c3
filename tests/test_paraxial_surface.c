/*
 * test_paraxial_surface.c - Zemax's paraxial surface (TYPE PARAXIAL), the
 * ideal thin lens of src/shape/shape_paraxial.c.
 *
 * Expected values, none from sagitta: the thin-lens (Gauss) equation n' /
 * s' + n / s = 1 / f for the image distance and m = -(n s') / (n' s) for
 * the magnification; a perfect lens's optical path difference, 0; the
 * focal length of two thin lenses, 1 / F = 1 / f1 + 1 / f2 - d / (f1 f2),
 * and its back focal length F (1 - d / f1); and the automatic
 * semi-diameters Zemax stored in its own sample "Telecentric system.zmx"
 * (tests/data/zmx/paraxial_telecentric.zmx, README there): a paraxial lens
 * of f = 100 with the stop at its front focal plane, fields to 20 degrees.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* Object at s in a medium of index n0 (1: air), a paraxial lens of focal
 * length f (the stop), image surface at t after it. */
static sg_system *one_lens(double s, double n0, double f, double t, int mode)
{
    char text[2048], mat[32];
    sg_system *sys = sg_system_new();
    sg_diag d;
    if (n0 == 1.0)
        snprintf(mat, sizeof mat, "\"AIR\"");
    else
        snprintf(mat, sizeof mat, "%.17g", n0);
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 3, \"units\": \"mm\",\n"
             " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
             " \"fields\": {\"type\": \"object_height\", \"list\": [{\"x\": 0, \"y\": 0},\n"
             "   {\"x\": 0, \"y\": 10}, {\"x\": 4, \"y\": -7}]},\n"
             " \"aperture\": {\"type\": \"epd\", \"value\": 40},\n"
             " \"surfaces\": [\n"
             "  {\"radius\": \"inf\", \"thickness\": %.17g, \"material\": %s},\n"
             "  {\"type\": \"paraxial\", \"focal_length\": %.17g, \"opd_mode\": %d,\n"
             "   \"thickness\": %.17g, \"material\": \"AIR\", \"stop\": true},\n"
             "  {\"radius\": \"inf\", \"thickness\": 0, \"material\": \"AIR\"}]}\n",
             s, mat, f, mode, t);
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "ideal.json", &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

/* Every ray of each field meets the image plane at m times the object
 * point, with an OPD of 0, in each method. */
static void check_perfect(sg_system *sys, double m, double tol_y, const double tol_w[3])
{
    sg_catalog *cat = tu_catalog();
    const double fx[3] = {0, 0, 4}, fy[3] = {0, 10, -7};
    int meth, fi, k;
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *t = tu_tracer(sys, cat, (sg_method)meth);
        sg_ray_surface rows[3];
        double worst_y = 0.0, worst_w = 0.0;
        assert_non_null(t);
        for (fi = 0; fi < 3; fi++) {
            sg_opd_ref ref;
            sg_diag d;
            double hy = fy[fi] / 10.0, hx = fx[fi] / 10.0;
            sg_diag_clear(&d);
            assert_int_equal(sg_opd_reference(t, hx, hy, &ref, &d), SG_OK);
            assert_int_equal(ref.status, SG_OK);
            for (k = 0; k < 25; k++) {
                double px = -1.0 + 0.5 * (k % 5), py = -1.0 + 0.5 * (k / 5);
                sg_opd o;
                if (px * px + py * py > 1.0)
                    continue;
                assert_int_equal(sg_trace_opd(t, &ref, px * 0.999, py * 0.999, rows, &o), SG_OK);
                worst_y = fmax(worst_y, fabs(rows[2].y - m * fy[fi]));
                worst_y = fmax(worst_y, fabs(rows[2].x - m * fx[fi]));
                worst_w = fmax(worst_w, fabs(o.opd_waves));
            }
        }
        print_message("# %s: image point within %.3g, OPD within %.3g waves\n",
                      sg_method_name((sg_method)meth), worst_y, worst_w);
        assert_true(worst_y <= tol_y * (meth == SG_METHOD_CLASSIC ? 1e3 : 1.0));
        assert_true(worst_w <= tol_w[meth]);
        sg_tracer_free(t);
    }
    sg_catalog_free(cat);
}

/* s = 150, f = 100 in air: s' = 300, m = -2. */
static void test_images_perfectly(void **state)
{
    const double tol_w[3] = {1e-9, 1e-5, 1e-9};
    sg_system *sys = one_lens(150.0, 1.0, 100.0, 300.0, 1);
    (void)state;
    check_perfect(sys, -2.0, 1e-11, tol_w);
    sg_system_free(sys);
}

/* Object space of index 1.5, s = 300, f = 100, OPD mode 0: n' / s' = 1 /
 * f - n / s gives s' = 200, m = -(1.5 x 200) / 300 = -1.  Mode 3 makes the
 * same lens. */
static void test_images_from_a_medium(void **state)
{
    const double tol_w[3] = {1e-9, 1e-5, 1e-9};
    int mode;
    (void)state;
    for (mode = 0; mode <= 3; mode += 3) {
        sg_system *sys = one_lens(300.0, 1.5, 100.0, 200.0, mode);
        check_perfect(sys, -1.0, 1e-11, tol_w);
        sg_system_free(sys);
    }
}

/* OPD mode 2 is perfect at infinite conjugates only: at s = 150 its path
 * term leaves a wavefront error, while the rays still meet at the image. */
static void test_mode2_infinite(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = one_lens(150.0, 1.0, 100.0, 300.0, 2);
    sg_tracer *t = tu_tracer(sys, cat, SG_METHOD_MPFR);
    sg_ray_surface rows[3];
    sg_opd_ref ref;
    sg_opd o;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_opd_reference(t, 0, 0, &ref, &d), SG_OK);
    assert_int_equal(sg_trace_opd(t, &ref, 0, 1, rows, &o), SG_OK);
    assert_true(fabs(rows[2].y) <= 1e-12);
    print_message("# mode 2 at s = 150: marginal OPD %.6g waves\n", o.opd_waves);
    assert_true(fabs(o.opd_waves) > 1.0);
    sg_tracer_free(t);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Paraxial data: one lens has EFL f; two lenses f1 = 100 and f2 = -50, 20
 * apart, have 1 / F = 1 / 100 - 1 / 50 + 20 / 5000, F = -500 / 3, and a
 * back focal length F (1 - 20 / 100) = -400 / 3.  The ideal lens adds
 * no Seidel aberration. */
static void test_paraxial_data(void **state)
{
    static const char two[] =
        "{\"format\": \"sagitta-design\", \"version\": 3,\n"
        " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},\n"
        " \"fields\": {\"type\": \"angle\", \"list\": [{\"x\": 0, \"y\": 0}, {\"x\": 0, \"y\": 5}]},\n"
        " \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
        " \"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "  {\"type\": \"paraxial\", \"focal_length\": 100, \"thickness\": 20, \"stop\": true},\n"
        "  {\"type\": \"paraxial\", \"focal_length\": -50, \"thickness\": 10},\n"
        "  {\"radius\": \"inf\", \"thickness\": 0}]}\n";
    sg_catalog *cat = tu_catalog();
    sg_system *sys = one_lens(150.0, 1.0, 100.0, 300.0, 1), *s2 = sg_system_new();
    sg_paraxial p;
    sg_seidel se;
    sg_diag d;
    int k;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    assert_true(fabs(p.efl - 100.0) <= 1e-13 * 100.0);
    assert_true(fabs(p.image_dist - 300.0) <= 1e-12 * 300.0);
    assert_int_equal(sg_design_parse(s2, two, strlen(two), "two.json", &d), SG_OK);
    assert_int_equal(sg_paraxial_compute(s2, cat, -1, &p, &d), SG_OK);
    print_message("# two lenses: EFL %.17g BFL %.17g\n", p.efl, p.bfl);
    assert_true(fabs(p.efl + 500.0 / 3.0) <= 1e-13 * 200.0);
    assert_true(fabs(p.bfl + 400.0 / 3.0) <= 1e-13 * 200.0);
    memset(&se, 0, sizeof se);
    assert_int_equal(sg_seidel_compute(s2, cat, &se, &d), SG_OK);
    for (k = 0; k < SG_SEIDEL_N; k++)
        assert_true(se.total[k] == 0.0);
    sg_seidel_free(&se);
    sg_system_free(sys);
    sg_system_free(s2);
    sg_catalog_free(cat);
}

/* Zemax's sample opens; its EFL is the lens's 100 and the automatic
 * semi-diameters are the ones Zemax stored (DIAM, lines 76, 86, 97 and
 * 106 of the UTF-16 text): 28.19851171331, 10, 46.39702342662 and
 * 36.39702342662 = 100 tan 20 degrees. */
static void test_zemax_telecentric(void **state)
{
    static const double zemax[5] = {0, 28.19851171331, 10, 46.39702342662, 36.39702342662};
    char path[1024];
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new(), *back = sg_system_new();
    double sd[5];
    sg_paraxial p;
    sg_diag d;
    char *z;
    int i;
    (void)state;
    sg_diag_clear(&d);
    if (sg_zmx_load(sys, tu_path("tests/data/zmx/paraxial_telecentric.zmx", path, sizeof path),
                    cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_equal(sys->nsurf, 5);
    assert_int_equal(sys->surf[3].type, SG_SURF_PARAXIAL);
    assert_true(sys->surf[3].focal_length == 100.0 && sys->surf[3].opd_mode == 1.0);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    assert_true(fabs(p.efl - 100.0) <= 1e-13 * 100.0);
    assert_int_equal(sg_semi_diameters(sys, cat, NULL, sd, &d), SG_OK);
    for (i = 1; i < 5; i++) {
        print_message("# surface %d: %.13g, Zemax %.13g\n", i, sd[i], zemax[i]);
        assert_true(fabs(sd[i] - zemax[i]) <= 1e-11 * zemax[i]);
    }
    assert_true(fabs(sd[4] - 100.0 * tan(20.0 * (3.14159265358979323846 / 180.0))) <= 1e-12 * 40.0);
    /* Written as .zmx and read back: the same design. */
    z = sg_zmx_to_text(sys, cat, &d);
    assert_non_null(z);
    assert_non_null(strstr(z, "TYPE PARAXIAL"));
    assert_int_equal(sg_zmx_parse(back, z, strlen(z), "back.zmx", cat, &d), SG_OK);
    assert_int_equal(back->surf[3].type, SG_SURF_PARAXIAL);
    assert_true(back->surf[3].focal_length == 100.0 && back->surf[3].opd_mode == 1.0);
    free(z);
    sg_system_free(back);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Bad input names the surface and what is wrong. */
static void test_refusals(void **state)
{
    static const char *const bad[][2] = {
        {"\"focal_length\": 0", "surface 1: a paraxial surface needs a nonzero, finite focal "
                                "length"},
        {"\"focal_length\": 50, \"opd_mode\": 1.5", "surface 1: opd_mode 1.5 is not one of"},
        {"\"focal_length\": 50, \"radius\": 20", "surface 1: a paraxial surface is flat"},
        {"\"focal_length\": 50, \"material\": \"MIRROR\"", "surface 1: a paraxial surface "
                                                          "cannot be a mirror"}};
    static const char zbad[] = "VERS 190513\nUNIT MM X W X CM MR CPMM\nENPD 10\nWAVM 1 0.55 1\n"
                               "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  TYPE PARAXIAL\n"
                               "  PARM 1 50\n  PARM 3 1\n  DISZ 50\nSURF 2\n  DISZ 0\n";
    char text[1024];
    size_t i;
    sg_diag d;
    (void)state;
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        sg_system *sys = sg_system_new();
        snprintf(text, sizeof text,
                 "{\"surfaces\": [{\"thickness\": \"inf\"}, {\"type\": \"paraxial\", %s, "
                 "\"thickness\": 50, \"stop\": true}, {}]}", bad[i][0]);
        sg_diag_clear(&d);
        if (sg_design_parse(sys, text, strlen(text), "t.json", &d) == SG_OK)
            assert_int_not_equal(sg_system_validate(sys, NULL, &d), SG_OK);
        print_message("# %s\n", d.msg);
        assert_non_null(strstr(d.msg, bad[i][1]));
        sg_system_free(sys);
    }
    {
        sg_system *sys = sg_system_new();
        sg_diag_clear(&d);
        assert_int_equal(sg_zmx_parse(sys, zbad, strlen(zbad), "t.zmx", NULL, &d),
                         SG_EUNSUPPORTED);
        print_message("# %s\n", d.msg);
        assert_non_null(strstr(d.msg, "t.zmx:11: surface 1: PARM 3"));
        assert_non_null(strstr(d.msg, "focal length (PARM 1)"));
        sg_system_free(sys);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_images_perfectly),
        cmocka_unit_test(test_images_from_a_medium),
        cmocka_unit_test(test_mode2_infinite),
        cmocka_unit_test(test_paraxial_data),
        cmocka_unit_test(test_zemax_telecentric),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
