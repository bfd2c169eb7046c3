/*
 * test_aperture.c - surface apertures and obscurations (circular,
 * rectangular, elliptical, each decentred), in all three methods.
 *
 * The truths are closed forms: a ray parallel to the axis crosses a flat
 * surface at its own x and y, so a point a relative 1e-7 inside or outside
 * an edge (100 times the clip tolerance) must pass or be vignetted; and a
 * central obscuration of radius e on the Cassegrain's primary (the stop)
 * blocks the pupil points of radius below e, whose share of a square grid
 * lies within the lattice bounds of the area ratio e^2.
 */
#include <math.h>

#define PI 3.14159265358979323846
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};
static const char *const method_names[] = {"precise", "classic", "mpfr"};

/* Surface 1 the stop, flat; surface 2 flat with the aperture; the image. */
static sg_system *aperture_system(sg_aperture_type type, double a, double b)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].thickness = 5.0;
    sys->surf[2].thickness = 10.0;
    sys->stop = 1;
    sys->aper_value = 40.0;
    sys->surf[2].aperture = type;
    if (type == SG_APERTURE_CIRCULAR || type == SG_OBSCURATION_CIRCULAR) {
        sys->surf[2].ap_rmin = a;
        sys->surf[2].ap_rmax = b;
    } else {
        sys->surf[2].ap_xhalf = a;
        sys->surf[2].ap_yhalf = b;
    }
    /* Decentred, by amounts exact in binary. */
    sys->surf[2].ap_xdec = 0.25;
    sys->surf[2].ap_ydec = -0.5;
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(sys, NULL, &d), SG_OK);
    return sys;
}

/* The status at surface 2 of the axial ray through (x, y), each method. */
static void expect_at(const sg_system *sys, double x, double y, int want, const char *what)
{
    sg_ray_surface out[4];
    double start[3] = {x, y, 0.0}, dir[3] = {0.0, 0.0, 1.0};
    int m;
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, NULL, methods[m]);
        int rc = sg_trace_start(t, start, dir, out);
        if (out[2].status != want)
            fail_msg("%s, %s: (%.17g, %.17g) gave %s at surface 2, expected %s", what,
                     method_names[m], x, y, sg_err_name(out[2].status), sg_err_name(want));
        assert_int_equal(rc, want == SG_OK ? SG_OK : want);
        sg_tracer_free(t);
    }
}

/* What stops a ray at surface 2: its obscuration, its aperture, or the
 * fixed semi-diameter (a surface with none of the first two). */
static int stopped_by(const sg_system *sys)
{
    switch (sys->surf[2].aperture) {
    case SG_OBSCURATION_CIRCULAR:
    case SG_OBSCURATION_RECTANGULAR:
    case SG_OBSCURATION_ELLIPTICAL:
        return SG_EOBSCURED;
    case SG_APERTURE_NONE:
        return SG_EVIGNETTED;
    default:
        return SG_EAPERTURE;
    }
}

/* Pass and stop for a point on an edge scaled by 1 - 1e-7 and 1 + 1e-7. */
static void edge(const sg_system *sys, double ex, double ey, int inside_passes, const char *what)
{
    double dx = sys->surf[2].ap_xdec, dy = sys->surf[2].ap_ydec;
    int in = inside_passes ? SG_OK : stopped_by(sys);
    int out = inside_passes ? stopped_by(sys) : SG_OK;
    expect_at(sys, dx + ex * (1.0 - 1e-7), dy + ey * (1.0 - 1e-7), in, what);
    expect_at(sys, dx + ex * (1.0 + 1e-7), dy + ey * (1.0 + 1e-7), out, what);
}

static void test_circular(void **state)
{
    sg_system *sys;
    int k;
    (void)state;
    /* An annulus 2 <= r <= 5 passes: inside 2 and beyond 5 are stopped. */
    sys = aperture_system(SG_APERTURE_CIRCULAR, 2.0, 5.0);
    for (k = 0; k < 8; k++) {
        double th = 0.3 + k * PI / 4;
        edge(sys, 5.0 * cos(th), 5.0 * sin(th), 1, "circular aperture, outer edge");
        edge(sys, 2.0 * cos(th), 2.0 * sin(th), 0, "circular aperture, inner edge");
    }
    /* Far from the aperture's centre but near the vertex: the decenter counts. */
    expect_at(sys, 0.25 - 1.9, -0.5, SG_EAPERTURE, "circular aperture, hole");
    expect_at(sys, 0.25 + 4.9, -0.5, SG_OK, "circular aperture, +x");
    expect_at(sys, -4.9, 0.0, SG_EAPERTURE, "circular aperture, beyond once decentred");
    sg_system_free(sys);

    /* The obscuration is the complement: 0 <= r <= 3 is stopped. */
    sys = aperture_system(SG_OBSCURATION_CIRCULAR, 0.0, 3.0);
    for (k = 0; k < 8; k++) {
        double th = 0.1 + k * PI / 4;
        edge(sys, 3.0 * cos(th), 3.0 * sin(th), 0, "circular obscuration");
    }
    expect_at(sys, 0.25, -0.5, SG_EOBSCURED, "circular obscuration, centre");
    sg_system_free(sys);
    /* With a minimum radius, the hole inside it passes again. */
    sys = aperture_system(SG_OBSCURATION_CIRCULAR, 1.0, 3.0);
    edge(sys, 0.0, 1.0, 1, "annular obscuration, inner edge");
    edge(sys, 3.0, 0.0, 0, "annular obscuration, outer edge");
    sg_system_free(sys);
}

static void test_rectangular(void **state)
{
    sg_system *sys;
    (void)state;
    sys = aperture_system(SG_APERTURE_RECTANGULAR, 4.0, 2.0);
    edge(sys, 4.0, 1.5, 1, "rectangular aperture, +x side");
    edge(sys, -4.0, -1.9, 1, "rectangular aperture, -x side");
    edge(sys, 3.0, 2.0, 1, "rectangular aperture, +y side");
    edge(sys, -3.9, -2.0, 1, "rectangular aperture, -y side");
    edge(sys, 4.0, 2.0, 1, "rectangular aperture, corner");
    /* Inside the circumscribed circle but outside the rectangle. */
    expect_at(sys, 0.25 + 3.0, -0.5 + 2.1, SG_EAPERTURE, "rectangular aperture, beyond y");
    sg_system_free(sys);

    sys = aperture_system(SG_OBSCURATION_RECTANGULAR, 4.0, 2.0);
    edge(sys, 4.0, 1.5, 0, "rectangular obscuration, +x side");
    edge(sys, -2.0, -2.0, 0, "rectangular obscuration, -y side");
    expect_at(sys, 0.25 + 3.0, -0.5 + 2.1, SG_OK, "rectangular obscuration, beyond y");
    sg_system_free(sys);
}

static void test_elliptical(void **state)
{
    sg_system *sys;
    int k;
    (void)state;
    sys = aperture_system(SG_APERTURE_ELLIPTICAL, 4.0, 2.0);
    for (k = 0; k < 12; k++) {
        double th = 0.2 + k * PI / 6;
        edge(sys, 4.0 * cos(th), 2.0 * sin(th), 1, "elliptical aperture");
    }
    /* Inside the rectangle of the half widths, outside the ellipse. */
    expect_at(sys, 0.25 + 3.5, -0.5 + 1.5, SG_EAPERTURE, "elliptical aperture, corner");
    sg_system_free(sys);

    sys = aperture_system(SG_OBSCURATION_ELLIPTICAL, 4.0, 2.0);
    for (k = 0; k < 12; k++) {
        double th = 0.2 + k * PI / 6;
        edge(sys, 4.0 * cos(th), 2.0 * sin(th), 0, "elliptical obscuration");
    }
    expect_at(sys, 0.25 + 3.5, -0.5 + 1.5, SG_OK, "elliptical obscuration, corner");
    sg_system_free(sys);
}

/* The fixed semi-diameter goes through the same test, about the vertex. */
static void test_semi_diameter(void **state)
{
    sg_system *sys = aperture_system(SG_APERTURE_NONE, 0.0, 0.0);
    int k;
    (void)state;
    sys->surf[2].semi_diameter = 6.0;
    sys->surf[2].sd_fixed = 1;
    sys->surf[2].ap_xdec = sys->surf[2].ap_ydec = 0.0;
    for (k = 0; k < 8; k++) {
        double th = 0.05 + k * PI / 4;
        edge(sys, 6.0 * cos(th), 6.0 * sin(th), 1, "fixed semi-diameter");
    }
    /* With an aperture too, either stops the ray. */
    sys->surf[2].aperture = SG_APERTURE_RECTANGULAR;
    sys->surf[2].ap_xhalf = 10.0;
    sys->surf[2].ap_yhalf = 1.0;
    expect_at(sys, 5.9, 0.0, SG_OK, "semi-diameter and rectangle");
    expect_at(sys, 6.1, 0.0, SG_EVIGNETTED, "beyond the semi-diameter, inside the rectangle");
    expect_at(sys, 0.0, 1.1, SG_EAPERTURE, "inside the semi-diameter, beyond the rectangle");
    sg_system_free(sys);
}

/* With clipping off, as aiming runs, no aperture stops a ray. */
static void test_clip_off(void **state)
{
    sg_system *sys = aperture_system(SG_OBSCURATION_CIRCULAR, 0.0, 3.0);
    sg_trace_opts o;
    sg_ray_surface out[4];
    double start[3] = {0.25, -0.5, 0.0}, dir[3] = {0.0, 0.0, 1.0};
    int m;
    (void)state;
    for (m = 0; m < 3; m++) {
        sg_tracer *t;
        sg_trace_opts_init(&o);
        o.method = methods[m];
        o.clip = 0;
        t = sg_tracer_new(sys, NULL, &o, NULL);
        assert_non_null(t);
        assert_int_equal(sg_trace_start(t, start, dir, out), SG_OK);
        sg_tracer_free(t);
    }
    sg_system_free(sys);
}

/* A Cassegrain's central obscuration: a radius e of the primary (the stop,
 * semi-diameter 1500, real aiming) stops the pupil points of radius below
 * e.  On an n x n grid of cell h over the pupil, the points of radius below
 * rho h number between pi (rho - sqrt(2)/2)^2 and pi (rho + sqrt(2)/2)^2
 * (every point's cell lies inside the circle grown by half a diagonal). */
static void test_cassegrain_obscuration(void **state)
{
    const double e = 0.3;
    const int n = 40;
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cassegrain.json");
    int counts[3][2] = {{0}}, m, i, j, f, expect_obsc = 0, expect_all = 0;
    double h = 2.0 / n, rho, half = sqrt(0.5), lo, hi;
    sg_ray_surface *out;
    (void)state;
    assert_int_equal(sys->stop, 2);
    sys->surf[2].aperture = SG_OBSCURATION_CIRCULAR;
    sys->surf[2].ap_rmax = e * 1500.0;
    out = malloc((size_t)sys->nsurf * sizeof *out);
    assert_non_null(out);
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) {
            double px = -1.0 + (i + 0.5) * h, py = -1.0 + (j + 0.5) * h, r = hypot(px, py);
            if (r > 1.0)
                continue;
            /* No grid point lies within the tolerances of an edge. */
            assert_true(fabs(r - e) > 1e-6 && fabs(r - 1.0) > 1e-6);
            expect_all++;
            expect_obsc += r < e;
        }
    for (m = 0; m < 3; m++) {
        for (f = 0; f < 2; f++) {
            sg_tracer *t = tu_tracer(sys, cat, methods[m]);
            for (i = 0; i < n; i++)
                for (j = 0; j < n; j++) {
                    double px = -1.0 + (i + 0.5) * h, py = -1.0 + (j + 0.5) * h;
                    int rc;
                    if (hypot(px, py) > 1.0)
                        continue;
                    rc = sg_trace_normalized(t, 0.0, (double)f, px, py, out);
                    if (rc == SG_EOBSCURED) {
                        assert_int_equal(out[2].status, SG_EOBSCURED);
                        assert_true(hypot(px, py) < e);
                        counts[m][f]++;
                    } else {
                        assert_int_equal(rc, SG_OK);
                        assert_true(hypot(px, py) > e);
                    }
                }
            sg_tracer_free(t);
        }
    }
    rho = 1.0 / h;
    lo = PI * (e * rho - half) * (e * rho - half);
    hi = PI * (e * rho + half) * (e * rho + half);
    print_message("# Cassegrain, obscuration e = %.2f on the primary, %d pupil points of a "
                  "%dx%d grid: vignetted precise %d/%d, classic %d/%d, mpfr %d/%d (fields 0 "
                  "and 1); lattice bounds %.1f to %.1f, area ratio e^2 = %.4f, counted %.4f\n",
                  e, expect_all, n, n, counts[0][0], counts[0][1], counts[1][0], counts[1][1],
                  counts[2][0], counts[2][1], lo, hi, e * e,
                  (double)counts[0][0] / expect_all);
    for (m = 0; m < 3; m++)
        for (f = 0; f < 2; f++) {
            assert_int_equal(counts[m][f], expect_obsc);
            assert_true(counts[m][f] >= lo && counts[m][f] <= hi);
        }
    /* The pupil itself obeys the same bounds, so the share is e^2 to
     * within them. */
    assert_true(expect_all >= PI * (rho - half) * (rho - half) &&
                expect_all <= PI * (rho + half) * (rho + half));
    free(out);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The keys read, write back only when set, and make the file version 2. */
static void test_json(void **state)
{
    static const char text[] =
        "{\"version\": 2, \"surfaces\": [{}, {\"stop\": true, \"thickness\": 5},"
        " {\"thickness\": 10, \"aperture\": \"elliptical_obscuration\","
        " \"aperture_x_half_width\": 4, \"aperture_y_half_width\": 2,"
        " \"aperture_x_decenter\": 0.25, \"aperture_y_decenter\": -0.5}, {}]}";
    sg_system *sys = sg_system_new(), *back = sg_system_new();
    sg_diag d;
    char *json;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(sys, text, strlen(text), "t.json", &d), SG_OK);
    assert_int_equal(d.nwarn, 0);
    assert_int_equal(sys->surf[2].aperture, SG_OBSCURATION_ELLIPTICAL);
    assert_true(sys->surf[2].ap_xhalf == 4.0 && sys->surf[2].ap_yhalf == 2.0);
    assert_true(sys->surf[2].ap_xdec == 0.25 && sys->surf[2].ap_ydec == -0.5);
    assert_true(sys->surf[2].ap_rmin == 0.0 && sys->surf[2].ap_rmax == 0.0);
    json = sg_design_to_json(sys);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"version\": 2,"));
    assert_non_null(strstr(json, "\"aperture\": \"elliptical_obscuration\""));
    /* Keys at their defaults are not written. */
    assert_null(strstr(json, "aperture_min_radius"));
    assert_int_equal(sg_design_parse(back, json, strlen(json), "back", &d), SG_OK);
    assert_true(sg_system_equal(sys, back));
    free(json);
    /* The .zmx writer writes it as Zemax's ELOB and OBDC lines, and the
     * reader takes it back unchanged. */
    {
        char *z;
        sg_diag_clear(&d);
        z = sg_zmx_to_text(sys, NULL, &d);
        assert_non_null(z);
        assert_non_null(strstr(z, "  ELOB "));
        sg_diag_clear(&d);
        assert_int_equal(sg_zmx_parse(back, z, strlen(z), "back.zmx", NULL, &d), SG_OK);
        assert_true(back->surf[2].aperture == sys->surf[2].aperture &&
                    back->surf[2].ap_xhalf == sys->surf[2].ap_xhalf &&
                    back->surf[2].ap_yhalf == sys->surf[2].ap_yhalf &&
                    back->surf[2].ap_xdec == sys->surf[2].ap_xdec &&
                    back->surf[2].ap_ydec == sys->surf[2].ap_ydec);
        free(z);
    }
    /* Without an aperture the file stays version 1. */
    sys->surf[2].aperture = SG_APERTURE_NONE;
    sys->surf[2].ap_xhalf = sys->surf[2].ap_yhalf = 0.0;
    sys->surf[2].ap_xdec = sys->surf[2].ap_ydec = 0.0;
    json = sg_design_to_json(sys);
    assert_non_null(strstr(json, "\"version\": 1,"));
    assert_null(strstr(json, "aperture_"));
    assert_null(strstr(json, "obscuration"));
    free(json);
    sg_system_free(sys);
    sg_system_free(back);
}

/* Bad values name the file, the surface and the key. */
static void test_json_errors(void **state)
{
    static const struct {
        const char *surf2, *stage, *msg;
    } cases[] = {
        {"\"aperture\": \"square\"", "parse",
         "t.json: surface 2: aperture: expected \"none\", \"circular_aperture\""},
        {"\"aperture_max_radius\": -1", "parse",
         "t.json: surface 2: aperture_max_radius: must be finite and not negative, got number -1"},
        {"\"aperture_x_decenter\": \"a\"", "parse",
         "t.json: surface 2: aperture_x_decenter: expected a number, got string \"a\""},
        {"\"aperture\": \"circular_aperture\", \"aperture_min_radius\": 3,"
         " \"aperture_max_radius\": 2", "validate",
         "surface 2: aperture: the maximum radius 2 must be above the minimum radius 3"},
        {"\"aperture\": \"rectangular_obscuration\", \"aperture_x_half_width\": 3", "validate",
         "surface 2: aperture: the x and y half widths (3, 0) must be positive"},
        {"\"aperture_y_decenter\": 1e200", "validate",
         "surface 2: aperture y decenter 1e+200 is beyond 1e+150 lens units"},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[512];
        sg_system *sys = sg_system_new();
        sg_diag d;
        int rc;
        snprintf(text, sizeof text,
                 "{\"surfaces\": [{}, {\"stop\": true, \"thickness\": 5}, {%s}, {}]}",
                 cases[i].surf2);
        sg_diag_clear(&d);
        rc = sg_design_parse(sys, text, strlen(text), "t.json", &d);
        if (strcmp(cases[i].stage, "validate") == 0) {
            assert_int_equal(rc, SG_OK);
            rc = sg_system_validate(sys, NULL, &d);
        }
        assert_int_not_equal(rc, SG_OK);
        if (!strstr(d.msg, cases[i].msg))
            fail_msg("case %zu: \"%s\" lacks \"%s\"", i, d.msg, cases[i].msg);
        print_message("# %s\n", d.msg);
        sg_system_free(sys);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_circular),
        cmocka_unit_test(test_rectangular),
        cmocka_unit_test(test_elliptical),
        cmocka_unit_test(test_semi_diameter),
        cmocka_unit_test(test_clip_off),
        cmocka_unit_test(test_cassegrain_obscuration),
        cmocka_unit_test(test_json),
        cmocka_unit_test(test_json_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
