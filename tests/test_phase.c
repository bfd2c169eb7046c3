/*
 * test_phase.c - Zemax's phase surfaces, Binary 2 (TYPE BINARY_2) and
 * Zernike Fringe Phase (TYPE FZERNPHA), of src/shape_phase.c.
 *
 * Expected values, none from sagitta:
 *  - the grating equation with the phase's gradient as the local grating
 *    vector: on a plane in air, a ray along the axis leaves with direction
 *    cosines (l, m) = (lambda / 2 pi) grad Phi, lambda in lens units, Phi
 *    = M (A1 rho^2 + A2 rho^4) written out by hand (d/dx of rho^(2i) is
 *    2 i rho^(2i-2) x / R^2), in each method; a Zernike phase's Z4 (2
 *    rho^2 - 1, in waves) likewise; an order whose direction would pass
 *    grazing fails with SG_EEVANESCENT;
 *  - the optical path the phase adds, lambda Phi / (2 pi), against the
 *    same design with the phase terms 0;
 *  - three files Zemax wrote (tests/data/zmx/README.md): its short-course
 *    sample sc_diffract2.zmx (a Binary 2 on the curved front of a BK7
 *    singlet, three wavelengths; the image distance solved by MAZH), the
 *    "Achromatic singlet" sample (a Binary 2 on a flat with three terms,
 *    fields to 5 degrees) and "Test Spherical" (a Zernike phase of Z1, Z4
 *    and Z9 before a paraxial lens): their automatic semi-diameters (DIAM)
 *    and solved thickness (DISZ) as Zemax stored them, and the design
 *    written as .zmx and read back traces to the same bits.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define PI 3.14159265358979323846

/* Object at infinity on axis; surface 1 a phase surface (type, order M,
 * norm radius R, terms) in air, the stop; the image 50 behind. */
static sg_system *phase_plate(const char *type, double M, double R, const double *t, int nt,
                              double um)
{
    char text[4096], terms[1024] = "";
    sg_system *sys = sg_system_new();
    sg_diag d;
    int k;
    size_t used = 0;
    for (k = 0; k < nt; k++)
        used += (size_t)snprintf(terms + used, sizeof terms - used, "%s%.17g", k ? ", " : "",
                                 t[k]);
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 3,\n"
             " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": %.17g}]},\n"
             " \"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},\n"
             " \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
             " \"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
             "  {\"type\": \"%s\", \"grating_order\": %.17g, \"norm_radius\": %.17g,\n"
             "   \"terms\": [%s], \"thickness\": 50, \"stop\": true},\n"
             "  {\"radius\": \"inf\", \"thickness\": 0}]}\n",
             um, type, M, R, terms);
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "phase.json", &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

/* Binary 2: (l, m) = (lambda / 2 pi) M (2 A1 / R^2 + 4 A2 r^2 / R^4) (x, y). */
static void test_binary2_gradient(void **state)
{
    static const double orders[] = {1, -1, 2};
    sg_catalog *cat = tu_catalog();
    double worst = 0.0;
    int io, meth, k, n = 0;
    (void)state;
    for (io = 0; io < 3; io++)
        for (meth = 0; meth < 3; meth++) {
            double M = orders[io], R = 4.0, um = 0.6328, t[2] = {-900.0, 150.0};
            double lam = um * 1e-3;
            sg_system *sys = phase_plate("binary_2", M, R, t, 2, um);
            sg_tracer *tr = tu_tracer(sys, cat, (sg_method)meth);
            assert_non_null(tr);
            for (k = 0; k < 5; k++) {
                sg_ray_surface rows[3];
                double px = 0.3 * (k - 2), py = 0.9 - 0.35 * k, x, y, r2, g, l, m;
                assert_int_equal(sg_trace_normalized(tr, 0, 0, px, py, rows), SG_OK);
                x = rows[1].x;
                y = rows[1].y;
                r2 = x * x + y * y;
                g = lam / (2.0 * PI) * M * (2.0 * t[0] / (R * R) + 4.0 * t[1] * r2 / (R * R * R * R));
                l = g * x;
                m = g * y;
                worst = fmax(worst, fmax(fabs(rows[1].l - l), fabs(rows[1].m - m)));
                assert_true(fabs(rows[1].l - l) <= 1e-15 && fabs(rows[1].m - m) <= 1e-15);
                assert_true(fabs(rows[1].n - sqrt(1.0 - l * l - m * m)) <= 1e-15);
                n++;
            }
            sg_tracer_free(tr);
            sg_system_free(sys);
        }
    print_message("# %d rays within %.3g of the grating equation\n", n, worst);
    sg_catalog_free(cat);
}

/* The Zernike phase in waves, Fringe terms Z1 = 1, Z2 = u, Z4 = 2 rho^2 -
 * 1, Z5 = u^2 - v^2, Z6 = 2 u v (u = x / R, v = y / R): Phi = 2 pi M sum
 * A_j Z_j, so (l, m) = lambda M / R (A2 + 4 A4 u + 2 A5 u + 2 A6 v, 4 A4 v
 * - 2 A5 v + 2 A6 u). */
static void test_zernike_phase_gradient(void **state)
{
    sg_catalog *cat = tu_catalog();
    double t[6] = {0.5, 0.2, 0, -30.0, 7.0, -4.0}, R = 5.0, um = 0.55, lam = um * 1e-3;
    sg_system *sys = phase_plate("zernike_fringe_phase", 1.0, R, t, 6, um);
    int meth;
    (void)state;
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *tr = tu_tracer(sys, cat, (sg_method)meth);
        sg_ray_surface rows[3];
        double l, m;
        assert_non_null(tr);
        assert_int_equal(sg_trace_normalized(tr, 0, 0, 0.6, -0.7, rows), SG_OK);
        {
            double u = rows[1].x / R, v = rows[1].y / R;
            l = lam / R * (t[1] + 4.0 * t[3] * u + 2.0 * t[4] * u + 2.0 * t[5] * v);
            m = lam / R * (4.0 * t[3] * v - 2.0 * t[4] * v + 2.0 * t[5] * u);
        }
        assert_true(fabs(rows[1].l - l) <= 1e-15 && fabs(rows[1].m - m) <= 1e-15);
        sg_tracer_free(tr);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The path the phase adds, against the same plate without it: lambda
 * Phi / (2 pi) at the point the ray crosses (the plate is the stop, so
 * the same pupil coordinates cross at the same point), seen at surface 2
 * less the step there. */
static void test_phase_path(void **state)
{
    sg_catalog *cat = tu_catalog();
    double t[2] = {-700.0, 90.0}, zero[2] = {0.0, 0.0}, R = 6.0, M = 2.0, um = 0.5;
    sg_system *sys = phase_plate("binary_2", M, R, t, 2, um);
    sg_system *flat = phase_plate("binary_2", M, R, zero, 2, um);
    int meth;
    (void)state;
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *a = tu_tracer(sys, cat, (sg_method)meth), *b = tu_tracer(flat, cat,
                                                                             (sg_method)meth);
        sg_ray_surface ra[3], rb[3];
        double rho2, phi, got;
        assert_int_equal(sg_trace_normalized(a, 0, 0, 0.4, 0.8, ra), SG_OK);
        assert_int_equal(sg_trace_normalized(b, 0, 0, 0.4, 0.8, rb), SG_OK);
        rho2 = (ra[1].x * ra[1].x + ra[1].y * ra[1].y) / (R * R);
        phi = M * (t[0] * rho2 + t[1] * rho2 * rho2);
        /* The path at surface 2 less the step from surface 1 (in air). */
        got = (ra[2].opl + ra[2].opl_lo - ra[2].path) - (rb[2].opl + rb[2].opl_lo - rb[2].path);
        print_message("# %s: path %.17g, lambda Phi / 2 pi %.17g\n",
                      sg_method_name((sg_method)meth), got, um * 1e-3 * phi / (2.0 * PI));
        assert_true(fabs(got - um * 1e-3 * phi / (2.0 * PI)) <= 1e-13);
        sg_tracer_free(a);
        sg_tracer_free(b);
    }
    sg_system_free(sys);
    sg_system_free(flat);
    sg_catalog_free(cat);
}

/* A kick past grazing: the ray fails with SG_EEVANESCENT in each method. */
static void test_evanescent(void **state)
{
    sg_catalog *cat = tu_catalog();
    double t[1] = {-2.0e5};
    sg_system *sys = phase_plate("binary_2", 1.0, 5.0, t, 1, 0.55);
    int meth;
    (void)state;
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *tr = tu_tracer(sys, cat, (sg_method)meth);
        sg_ray_surface rows[3];
        /* |grad| lambda / 2 pi at the edge: 2e5 * 2 * 5 / 25 * 8.75e-5 = 7. */
        assert_int_equal(sg_trace_normalized(tr, 0, 0, 0, 1, rows), SG_EEVANESCENT);
        assert_int_equal(rows[1].status, SG_EEVANESCENT);
        sg_tracer_free(tr);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static sg_system *load(const char *rel, sg_catalog *cat)
{
    char path[1024];
    sg_system *sys = sg_system_new();
    sg_diag d;
    sg_diag_clear(&d);
    if (sg_zmx_load(sys, tu_path(rel, path, sizeof path), cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

/* Zemax's DIAMs (surfaces from 1; 0: not checked) against sg_semi_diameters,
 * and the file written back traces to the same bits in each method. */
static void check_file(const char *rel, int isurf, int type, const double *zemax, int n,
                       double tol)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load(rel, cat), *back = sg_system_new();
    double sd[64];
    sg_diag d;
    char *z;
    int i, meth;
    sg_diag_clear(&d);
    assert_int_equal(sys->surf[isurf].type, type);
    assert_int_equal(sg_semi_diameters(sys, cat, NULL, sd, &d), SG_OK);
    for (i = 1; i <= n; i++) {
        if (zemax[i] == 0.0)
            continue;
        print_message("# %s surface %d: %.13g, Zemax %.13g\n", rel, i, sd[i], zemax[i]);
        /* Zemax prints 13 digits; a small image height takes them in
         * lens units. */
        assert_true(fabs(sd[i] - zemax[i]) <= tol * fmax(zemax[i], 1.0));
    }
    z = sg_zmx_to_text(sys, cat, &d);
    assert_non_null(z);
    assert_int_equal(sg_zmx_parse(back, z, strlen(z), "back.zmx", cat, &d), SG_OK);
    assert_int_equal(back->surf[isurf].type, type);
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *a = tu_tracer(sys, cat, (sg_method)meth), *b = tu_tracer(back, cat,
                                                                             (sg_method)meth);
        sg_ray_surface ra[64], rb[64];
        int im = sys->nsurf - 1;
        assert_int_equal(sg_trace_normalized(a, 0, 1, 0.3, 0.9, ra), SG_OK);
        assert_int_equal(sg_trace_normalized(b, 0, 1, 0.3, 0.9, rb), SG_OK);
        assert_true(ra[im].x == rb[im].x && ra[im].y == rb[im].y && ra[im].m == rb[im].m &&
                    ra[im].opl == rb[im].opl);
        sg_tracer_free(a);
        sg_tracer_free(b);
    }
    free(z);
    sg_system_free(back);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* sc_diffract2.zmx: surface 2's DIAM (line 106) and the image's (line
 * 115); the thickness Zemax solved (MAZH 0, DISZ on line 104), which the
 * Binary 2's power -lambda M A1 / (pi R^2) at the primary wavelength
 * enters. */
static void test_zemax_sc_diffract2(void **state)
{
    static const double zemax[] = {0, 0, 8.923065012065, 4.693575984866E-2};
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load("tests/data/zmx/binary2_sc_diffract2.zmx", cat);
    double stored = sys->surf[2].thickness;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    assert_true(stored == 3.438818248431E+1);
    sys->surf[2].thickness = 10.0;
    assert_int_equal(sg_system_apply_solves(sys, cat, &d), SG_OK);
    print_message("# solved %.17g, Zemax %.17g\n", sys->surf[2].thickness, stored);
    assert_true(fabs(sys->surf[2].thickness - stored) <= 1e-12 * stored);
    sg_system_free(sys);
    sg_catalog_free(cat);
    check_file("tests/data/zmx/binary2_sc_diffract2.zmx", 1, SG_SURF_BINARY_2, zemax, 3, 1e-11);
}

/* The Achromatic singlet: the image's DIAM (line 112 of the UTF-8 text),
 * the highest edge ray over three fields and three wavelengths. */
static void test_zemax_achromat(void **state)
{
    static const double zemax[] = {0, 0, 0, 5.175465768436};
    (void)state;
    check_file("tests/data/zmx/binary2_achromatic_singlet.zmx", 2, SG_SURF_BINARY_2, zemax, 3,
               1e-11);
}

/* Test Spherical: the DIAMs 1 before and at the paraxial focus (lines 113
 * and 123 of the UTF-8 text): Phi = 2 pi (-2 - 3 Z4 - Z9) = -12 pi rho^4. */
static void test_zemax_zernike_phase(void **state)
{
    static const double zemax[] = {0, 0, 0, 4.250034392839E-4, 4.125000350947E-2};
    (void)state;
    check_file("tests/data/zmx/fzernpha_test_spherical.zmx", 1, SG_SURF_ZERNIKE_PHASE, zemax, 4,
               1e-11);
}

/* Zemax's "Test Coma" and "Test Astigmatism" samples: Fringe Z7 1 and Z8
 * 3 waves (XDAT 9 and 10, lines 86 and 87), or Z1 and Z4 0.735 and Z5
 * -1.47 (XDAT 3, 6 and 7, lines 81, 84 and 85), before a paraxial lens of
 * focal length 100, on axis.  Their DIAMs behind it (lines 109 and 118;
 * 113 and 123) are the heights of the top and bottom edge rays (Py = +-1):
 * Zemax traced no ray at the pupil's sides here (on Test Astigmatism the
 * side ray, which the phase does not bend, stands 0.04 off axis at the
 * tangential focus, where Zemax stores 0.0012).  Each method's top and
 * bottom rays against them. */
static void check_top_bottom(const char *rel, const double *zemax, int n)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load(rel, cat);
    int meth, i, k;
    assert_int_equal(sys->surf[1].type, SG_SURF_ZERNIKE_PHASE);
    assert_int_equal(sys->nsurf, n + 1);
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *t = tu_tracer(sys, cat, (sg_method)meth);
        double h[8] = {0};
        for (k = 0; k < 2; k++) {
            sg_ray_surface rows[8];
            assert_int_equal(sg_trace_normalized(t, 0, 0, 0, k ? -1.0 : 1.0, rows), SG_OK);
            for (i = 1; i <= n; i++)
                h[i] = fmax(h[i], hypot(rows[i].x, rows[i].y));
        }
        for (i = 3; i <= n; i++) {
            print_message("# %s %s surface %d: %.13g, Zemax %.13g\n", rel,
                          sg_method_name((sg_method)meth), i, h[i], zemax[i]);
            assert_true(fabs(h[i] - zemax[i]) <= 1e-11 * fmax(zemax[i], 1.0));
        }
        sg_tracer_free(t);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_zemax_zernike_angular(void **state)
{
    static const double coma[] = {0, 2, 2, 3.467185971439E-2, 2.004389754117E-2};
    static const double astig[] = {0, 2, 2, 4.042500330309E-2, 1.233503369149E-3};
    (void)state;
    check_top_bottom("tests/data/zmx/fzernpha_test_coma.zmx", coma, 4);
    check_top_bottom("tests/data/zmx/fzernpha_test_astigmatism.zmx", astig, 4);
}

/* Bad input names the surface and what is wrong. */
static void test_refusals(void **state)
{
    sg_catalog *cat = tu_catalog();
    double many[7] = {1, 1, 1, 1, 1, 1, 1};
    sg_system *sys;
    sg_diag d;
    (void)state;
    sys = phase_plate("binary_2", 1.0, 4.0, many, 7, 0.55);
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(sys, cat, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "surface 1: phase term 7 is set; sagitta reads terms 1 to 6"));
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_binary2_gradient),
        cmocka_unit_test(test_zernike_phase_gradient),
        cmocka_unit_test(test_phase_path),
        cmocka_unit_test(test_evanescent),
        cmocka_unit_test(test_zemax_sc_diffract2),
        cmocka_unit_test(test_zemax_achromat),
        cmocka_unit_test(test_zemax_zernike_phase),
        cmocka_unit_test(test_zemax_zernike_angular),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
