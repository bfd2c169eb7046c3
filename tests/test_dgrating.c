/*
 * test_dgrating.c - Zemax's diffraction grating (TYPE DGRATING), the ruled
 * plane or conic of src/shape/shape_dgrating.c.
 *
 * Expected values, none from sagitta: the grating equation n' sin(theta')
 * = n sin(theta) + m lambda T in the plane of the grating vector, with the
 * other direction cosine kept (n' l' = n l), at several orders and
 * wavelengths, in each method; an order past grazing fails the ray with
 * SG_EEVANESCENT; and three files OpticStudio saved for optiland's tests
 * (tests/data/zmx/optiland_*_grating.zmx, README there): a flat and a
 * curved (conic 1) transmission grating behind N-BK7, order -1, and a
 * curved reflection grating, order 1, all of 0.2 lines per micrometre, at
 * 0.587 um.  Zemax stored each image's automatic semi-diameter (DIAM), the
 * radial height of the edge ray Hx = 1, Px = 1 (flat, curved transmission)
 * or Hy = 1, Py = 1 (reflection) there; and optiland's test_grating.py
 * gives the flat grating's direction after it for one skew ray.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* Object at infinity, fields at angle a in y and in x; surface 1 a flat
 * grating (the stop) from index n0 into n1; the image 10 behind. */
static sg_system *flat_grating(double a, double n0, double n1, double T, double m, double um)
{
    char text[2048], m0[32], m1[32];
    sg_system *sys = sg_system_new();
    sg_diag d;
    snprintf(m0, sizeof m0, n0 == 1.0 ? "\"AIR\"" : "%.17g", n0);
    snprintf(m1, sizeof m1, n1 == 1.0 ? "\"AIR\"" : "%.17g", n1);
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 3,\n"
             " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": %.17g}]},\n"
             " \"fields\": {\"type\": \"angle\", \"normalization\": \"rectangular\",\n"
             "   \"list\": [{\"x\": 0, \"y\": 0}, {\"x\": %.17g, \"y\": %.17g}]},\n"
             " \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
             " \"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\", \"material\": %s},\n"
             "  {\"type\": \"diffraction_grating\", \"grating_lines\": %.17g,\n"
             "   \"grating_order\": %.17g, \"thickness\": 10, \"material\": %s, \"stop\": true},\n"
             "  {\"radius\": \"inf\", \"thickness\": 0, \"material\": %s}]}\n",
             um, a / 2.0, a, m0, T, m, m1, m1);
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "grating.json", &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

static void test_grating_equation(void **state)
{
    static const double orders[] = {-2, -1, 0, 1, 2, 3};
    static const double waves[] = {0.4, 0.55, 0.7};
    static const double media[][2] = {{1.0, 1.0}, {1.0, 1.5}, {1.6, 1.0}};
    sg_catalog *cat = tu_catalog();
    double worst = 0.0;
    int io, iw, im, meth, nok = 0, nev = 0;
    (void)state;
    for (im = 0; im < 3; im++)
        for (iw = 0; iw < 3; iw++)
            for (io = 0; io < 6; io++)
                for (meth = 0; meth < 3; meth++) {
                    double n0 = media[im][0], n1 = media[im][1], T = 0.6, m = orders[io];
                    double um = waves[iw], a = 12.0, tx, ty, h, L, M, sin_out;
                    sg_system *sys = flat_grating(a, n0, n1, T, m, um);
                    sg_tracer *t = tu_tracer(sys, cat, (sg_method)meth);
                    sg_ray_surface rows[3];
                    int rc;
                    assert_non_null(t);
                    /* The ray of field 2: tangents (tan a/2, tan a) in object space. */
                    tx = tan(a / 2.0 * (3.14159265358979323846 / 180.0));
                    ty = tan(a * (3.14159265358979323846 / 180.0));
                    h = sqrt(1.0 + tx * tx + ty * ty);
                    L = tx / h;
                    M = ty / h;
                    sin_out = (n0 * M + m * um * T) / n1;
                    rc = sg_trace_normalized(t, 1.0, 1.0, 0.3, -0.4, rows);
                    if ((n0 * L / n1) * (n0 * L / n1) + sin_out * sin_out > 1.0) {
                        /* Past grazing: a clear status, no numbers. */
                        assert_int_equal(rc, SG_EEVANESCENT);
                        assert_int_equal(rows[1].status, SG_EEVANESCENT);
                        nev++;
                    } else {
                        assert_int_equal(rc, SG_OK);
                        worst = fmax(worst, fabs(rows[1].m - sin_out));
                        worst = fmax(worst, fabs(rows[1].l - n0 * L / n1));
                        assert_true(fabs(rows[1].m - sin_out) <= 1e-14);
                        assert_true(fabs(rows[1].l - n0 * L / n1) <= 1e-14);
                        nok++;
                    }
                    sg_tracer_free(t);
                    sg_system_free(sys);
                }
    print_message("# %d rays within %.3g of the grating equation, %d evanescent\n", nok, worst,
                  nev);
    assert_true(nok > 0 && nev > 0);
    sg_catalog_free(cat);
}

/* The path the rulings add, m lambda T y, keeps a plane wave plane
 * (Malus and Dupin): rays of one collimated beam reach the plane normal to
 * the diffracted direction with the same optical path, in each method. */
static void test_grating_phase(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = flat_grating(12.0, 1.0, 1.5, 0.6, 2.0, 0.55);
    int meth, k;
    (void)state;
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *t = tu_tracer(sys, cat, (sg_method)meth);
        double ref = 0.0, worst = 0.0;
        for (k = 0; k < 5; k++) {
            sg_ray_surface rows[3];
            double px = 0.4 * (k - 2) * 0.5, py = 0.4 * (k - 2), w;
            assert_int_equal(sg_trace_normalized(t, 1.0, 1.0, px, py, rows), SG_OK);
            w = rows[2].opl + rows[2].opl_lo -
                1.5 * (rows[2].x * rows[2].l + rows[2].y * rows[2].m);
            if (k == 0)
                ref = w;
            worst = fmax(worst, fabs(w - ref));
        }
        print_message("# %s: paths to the wavefront plane within %.3g\n",
                      sg_method_name((sg_method)meth), worst);
        assert_true(worst <= 1e-12);
        sg_tracer_free(t);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Each wavelength diffracts by its own lambda: a tracer at the second of
 * two (0.55 and 0.7 um) follows 0.7, as a prism follows its index. */
static void test_grating_per_wavelength(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = flat_grating(0.0, 1.0, 1.0, 0.6, 1.0, 0.55);
    sg_trace_opts o;
    sg_tracer *t;
    sg_ray_surface rows[3];
    sg_diag d;
    int meth;
    (void)state;
    sys->nwave = 2;
    sys->wave[1].um = 0.7;
    sys->wave[1].weight = 1.0;
    for (meth = 0; meth < 3; meth++) {
        sg_trace_opts_init(&o);
        o.method = (sg_method)meth;
        o.wave = 1;
        sg_diag_clear(&d);
        t = sg_tracer_new(sys, cat, &o, &d);
        assert_non_null(t);
        assert_int_equal(sg_trace_normalized(t, 0, 0, 0.5, 0.5, rows), SG_OK);
        assert_true(fabs(rows[1].m - 0.7 * 0.6) <= 1e-15);
        sg_tracer_free(t);
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

/* The radial height on the image of ray (hx, hy, px, py), in each method,
 * against Zemax's DIAM. */
static void check_diam(const char *rel, int grating, double order, double hx, double hy,
                       double px, double py, double zemax)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load(rel, cat), *back = sg_system_new();
    sg_diag d;
    char *z;
    int meth;
    assert_int_equal(sys->surf[grating].type, SG_SURF_DGRATING);
    assert_true(sys->surf[grating].grating_lines == 0.20000000000000001);
    assert_true(sys->surf[grating].grating_order == order);
    for (meth = 0; meth < 3; meth++) {
        sg_tracer *t = tu_tracer(sys, cat, (sg_method)meth);
        sg_ray_surface rows[8];
        int im = sys->nsurf - 1;
        double r;
        assert_non_null(t);
        assert_int_equal(sg_trace_normalized(t, hx, hy, px, py, rows), SG_OK);
        r = hypot(rows[im].x, rows[im].y);
        print_message("# %s %s: %.17g, Zemax %.17g\n", rel, sg_method_name((sg_method)meth), r,
                      zemax);
        assert_true(fabs(r - zemax) <= (meth == SG_METHOD_CLASSIC ? 1e-12 : 4e-15) * zemax);
        sg_tracer_free(t);
    }
    /* Written as .zmx and read back: the same design. */
    sg_diag_clear(&d);
    z = sg_zmx_to_text(sys, cat, &d);
    assert_non_null(z);
    assert_int_equal(sg_zmx_parse(back, z, strlen(z), "back.zmx", cat, &d), SG_OK);
    assert_int_equal(back->surf[grating].type, SG_SURF_DGRATING);
    assert_true(back->surf[grating].grating_lines == sys->surf[grating].grating_lines);
    assert_true(back->surf[grating].grating_order == order);
    free(z);
    sg_system_free(back);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_zemax_flat(void **state)
{
    (void)state;
    check_diam("tests/data/zmx/optiland_flat_transmission_grating.zmx", 3, -1.0, 1, 0, 1, 0,
               13.319073572664644);
}

static void test_zemax_curved(void **state)
{
    (void)state;
    check_diam("tests/data/zmx/optiland_curved_transmission_grating.zmx", 3, -1.0, 1, 0, 1, 0,
               15.906291922754132);
}

static void test_zemax_reflective(void **state)
{
    (void)state;
    check_diam("tests/data/zmx/optiland_curved_reflective_grating.zmx", 1, 1.0, 0, 1, 0, 1,
               24.799609695789151);
}

/* optiland's test_flat_grating_transmission: Hx 0.2, Hy 0.8, Px -0.15, Py
 * 0.7 leaves the grating along (0.0345602649, 0.0216899611, 0.9991672201). */
static void test_optiland_ray(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load("tests/data/zmx/optiland_flat_transmission_grating.zmx", cat);
    sg_tracer *t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    sg_ray_surface rows[8];
    (void)state;
    assert_int_equal(sg_trace_normalized(t, 0.2, 0.8, -0.15, 0.7, rows), SG_OK);
    assert_true(fabs(rows[3].l - 0.0345602649) <= 1e-10);
    assert_true(fabs(rows[3].m - 0.0216899611) <= 1e-10);
    assert_true(fabs(rows[3].n - 0.9991672201) <= 1e-10);
    sg_tracer_free(t);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grating_equation),
        cmocka_unit_test(test_grating_phase),
        cmocka_unit_test(test_grating_per_wavelength),
        cmocka_unit_test(test_zemax_flat),
        cmocka_unit_test(test_zemax_curved),
        cmocka_unit_test(test_zemax_reflective),
        cmocka_unit_test(test_optiland_ray),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
