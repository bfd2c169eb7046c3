/*
 * test_obscured.c - systems with a central obscuration analysed as Zemax
 * does: the chief ray (and every reference ray) traced past apertures and
 * obscurations, only the rays an obscuration stops left out.
 *
 * The truths: OpticStudio 2023 R1.02's printed spot and field curvature
 * values for optiland's Hubble with its obscuration
 * (tests/data/optiland/hubble_analyses.txt); the same spot computed here
 * by hand from the unobscured design's rays, keeping those whose point on
 * the primary lies outside the obscuration's radius; a paraboloid's
 * perfect axial image (closed form: every ray meets the focus, the
 * wavefront is a sphere); and the pupil points outside the obscuration,
 * counted on the pattern's own closed-form coordinates.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};
static const char *const method_names[] = {"precise", "classic", "mpfr"};

static sg_system *load(const char *rel)
{
    char path[1024];
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    sg_diag_clear(&d);
    if (sg_design_load(sys, tu_path(rel, path, sizeof path), &d) != SG_OK)
        fail_msg("%s: %s", rel, d.msg);
    return sys;
}

/* The value OpticStudio printed for (kind, field, what) in
 * tests/data/optiland/hubble_analyses.txt, and its printed text. */
static double zemax_value(const char *kind, int field, const char *what, char *text, size_t n)
{
    char path[1024], line[256];
    FILE *f = fopen(tu_path("tests/data/optiland/hubble_analyses.txt", path, sizeof path), "r");
    assert_non_null(f);
    while (fgets(line, sizeof line, f)) {
        char k[32], w[32], v[64];
        int fi;
        if (line[0] == '#' || sscanf(line, "%31s %d %31s %63s", k, &fi, w, v) != 4)
            continue;
        if (strcmp(k, kind) == 0 && fi == field && strcmp(w, what) == 0) {
            fclose(f);
            snprintf(text, n, "%s", v);
            return strtod(v, NULL);
        }
    }
    fclose(f);
    fail_msg("no %s %d %s in hubble_analyses.txt", kind, field, what);
    return NAN;
}

/* Half a unit of the last digit the text shows (mantissa digits after its
 * point, with its exponent). */
static double half_unit(const char *text)
{
    const char *dot = strchr(text, '.'), *e = strpbrk(text, "eE");
    int dec = 0, ex = e ? atoi(e + 1) : 0;
    if (dot)
        for (dot++; *dot >= '0' && *dot <= '9'; dot++)
            dec++;
    return 0.5 * pow(10.0, ex - dec);
}

static void spot_of(const sg_system *sys, sg_method m, sg_spot *s)
{
    sg_spot_opts o;
    sg_diag d;
    sg_spot_opts_init(&o);
    o.trace.method = m;
    o.nthreads = 2;
    sg_diag_clear(&d);
    if (sg_spot_compute(sys, NULL, &o, s, &d) != SG_OK)
        fail_msg("spot: %s", d.msg);
}

/* The Hubble with its obscuration: each field's chief ray is the
 * reference, the pupil's centre is stopped, and every spot value is
 * OpticStudio's to its printed digits (precise and mpfr).  One is 0.7 of
 * a unit beyond half: field 1's RMS, printed 0.233518114 where the exact
 * value (precise and mpfr agree to 17 digits) is 0.2335181147; it is
 * held to one unit, the rounding of a double trace over 16 m of path. */
static void test_hubble_spot_zemax(void **state)
{
    sg_system *sys = load("tests/data/optiland/hubble_obscured.json");
    int mi, f, q;
    (void)state;
    for (mi = 0; mi < 3; mi++) {
        sg_spot s;
        spot_of(sys, methods[mi], &s);
        assert_int_equal(s.nfield, 2);
        for (f = 0; f < 2; f++) {
            assert_int_equal(s.field[f].status, SG_OK);
            /* The centre ray alone is stopped: hexapolar ring 1 has radius
             * 1/6 of 1200, beyond 177.8. */
            assert_int_equal((int)s.cell[f].nray, 127);
            assert_int_equal((int)s.cell[f].nok, 126);
            for (q = 0; q < 2; q++) {
                char text[64];
                double z = zemax_value("spot", f + 1, q ? "geo" : "rms", text, sizeof text);
                double v = 1000.0 * (q ? s.cell[f].geo : s.cell[f].rms), tol = half_unit(text);
                print_message("# Hubble obscured, %s, field %d %s: %.12g um, OpticStudio %s\n",
                              method_names[mi], f + 1, q ? "GEO" : "RMS", v, text);
                if (methods[mi] == SG_METHOD_CLASSIC) {
                    /* Double arithmetic over 16 m of path: some 1e-12 mm
                     * of each image point (1.4e-6 um on the axial GEO). */
                    assert_true(fabs(v - z) <= 5e-6);
                    continue;
                }
                if (f == 0 && q == 0)
                    tol *= 2.0;
                if (!(fabs(v - z) <= tol))
                    fail_msg("field %d %s: %.12g against %s", f + 1, q ? "GEO" : "RMS", v, text);
            }
        }
        sg_spot_free(&s);
    }
    sg_system_free(sys);
}

/* The obscured spot is the unobscured design's spot over only the rays
 * that meet the primary outside the obscuration's radius: here that set
 * is traced ray by ray on the design without the obscuration, filtered by
 * hand on its surface-2 point, and reduced about the chief ray. */
static void test_hubble_spot_filtered(void **state)
{
    sg_system *open = load("tests/data/optiland/hubble.json");
    sg_system *obsc = load("tests/data/optiland/hubble_obscured.json");
    double (*pup)[2];
    size_t n = sg_pupil_count(SG_PUPIL_HEXAPOLAR, 6), cursor = 0, got, i;
    int mi, f;
    (void)state;
    pup = malloc(n * sizeof *pup);
    assert_non_null(pup);
    got = sg_pupil_fill(SG_PUPIL_HEXAPOLAR, 6, &cursor, pup, n);
    assert_int_equal((int)got, (int)n);
    for (mi = 0; mi < 3; mi++) {
        sg_tracer *t = tu_tracer(open, NULL, methods[mi]);
        sg_ray_surface rows[5];
        sg_spot s;
        spot_of(obsc, methods[mi], &s);
        for (f = 0; f < 2; f++) {
            double hx, hy, cx, cy, s2 = 0.0, max2 = 0.0, rms, geo;
            size_t kept = 0;
            sg_field_normalized(open, f, &hx, &hy);
            assert_int_equal(sg_trace_normalized(t, hx, hy, 0.0, 0.0, rows), SG_OK);
            cx = rows[4].x;
            cy = rows[4].y;
            for (i = 0; i < n; i++) {
                double dx, dy;
                assert_int_equal(sg_trace_normalized(t, hx, hy, pup[i][0], pup[i][1], rows),
                                 SG_OK);
                if (hypot(rows[2].x, rows[2].y) <= 177.80035)
                    continue;
                dx = rows[4].x - cx;
                dy = rows[4].y - cy;
                s2 += dx * dx + dy * dy;
                max2 = fmax(max2, dx * dx + dy * dy);
                kept++;
            }
            rms = sqrt(s2 / (double)kept);
            geo = sqrt(max2);
            print_message("# Hubble, %s, field %d: %zu rays outside the obscuration; RMS "
                          "%.17g by hand, %.17g by spot\n", method_names[mi], f + 1, kept, rms,
                          s.cell[f].rms);
            assert_int_equal((int)kept, (int)s.cell[f].nok);
            assert_true(fabs(s.cell[f].chief_x - cx) == 0.0 && s.cell[f].chief_y == cy);
            assert_true(fabs(s.cell[f].rms - rms) <= 1e-12 * rms);
            assert_true(fabs(s.cell[f].geo - geo) <= 1e-12 * geo);
        }
        sg_spot_free(&s);
        sg_tracer_free(t);
    }
    free(pup);
    sg_system_free(open);
    sg_system_free(obsc);
}

/* Field curvature of the obscured Hubble: the reference rays pass the
 * obscuration, so the exact foci are the unobscured design's (bit for
 * bit), and Zemax's recipe gives OpticStudio's three printed values and
 * its distortion. */
static void test_hubble_fieldcurve(void **state)
{
    sg_system *open = load("tests/data/optiland/hubble.json");
    sg_system *obsc = load("tests/data/optiland/hubble_obscured.json");
    sg_fieldcurve_pt a[3], b[3], z[3];
    sg_trace_opts o;
    sg_diag d;
    char text[64];
    double v;
    int i;
    (void)state;
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    assert_int_equal(sg_fieldcurve(open, NULL, &o, 3, 0.01, a, &d), SG_OK);
    assert_int_equal(sg_fieldcurve(obsc, NULL, &o, 3, 0.01, b, &d), SG_OK);
    for (i = 0; i < 3; i++) {
        assert_int_equal(b[i].status, SG_OK);
        assert_true(a[i].tan_focus == b[i].tan_focus && a[i].sag_focus == b[i].sag_focus &&
                    a[i].distortion == b[i].distortion);
    }
    assert_int_equal(sg_fieldcurve_recipe(obsc, NULL, &o, 3, 0.001, SG_FIELDCURVE_ZEMAX, z, &d),
                     SG_OK);
    for (i = 0; i < 3; i++)
        assert_int_equal(z[i].status, SG_OK);
    v = zemax_value("fieldcurve", 0, "tangential", text, sizeof text);
    print_message("# Hubble, Zemax's recipe: on axis %.12g (OpticStudio %s)\n", z[0].tan_focus,
                  text);
    assert_true(fabs(z[0].tan_focus - v) <= half_unit(text));
    assert_true(fabs(z[0].sag_focus - v) <= half_unit(text));
    v = zemax_value("fieldcurve", 1, "tangential", text, sizeof text);
    print_message("# tangential %.12g (OpticStudio %s; exact limit %.12g)\n", z[2].tan_focus,
                  text, b[2].tan_focus);
    assert_true(fabs(z[2].tan_focus - v) <= half_unit(text));
    /* The exact limit is not Zemax's number: 0.6% apart. */
    assert_true(fabs(b[2].tan_focus - v) > 1e-3);
    v = zemax_value("fieldcurve", 1, "sagittal", text, sizeof text);
    print_message("# sagittal %.12g (OpticStudio %s)\n", z[2].sag_focus, text);
    assert_true(fabs(z[2].sag_focus - v) <= half_unit(text));
    v = zemax_value("fieldcurve", 1, "distortion", text, sizeof text);
    print_message("# distortion %.12g %% (OpticStudio %s)\n", z[2].distortion, text);
    assert_true(fabs(z[2].distortion - v) <= half_unit(text));
    assert_true(fabs(b[2].distortion - v) <= half_unit(text));
    assert_int_equal(sg_fieldcurve_recipe(obsc, NULL, &o, 3, 0.001, 7, z, &d), SG_EINVAL);
    sg_system_free(open);
    sg_system_free(obsc);
}

/* The Hubble's wavefront, OPD fan and the trace's OPD with the
 * obscuration: the reference sphere is the unobscured design's, and a ray
 * that passes has the same OPD. */
static void test_hubble_opd(void **state)
{
    sg_system *open = load("tests/data/optiland/hubble.json");
    sg_system *obsc = load("tests/data/optiland/hubble_obscured.json");
    int mi;
    (void)state;
    for (mi = 0; mi < 3; mi++) {
        sg_tracer *ta = tu_tracer(open, NULL, methods[mi]), *tb = tu_tracer(obsc, NULL, methods[mi]);
        sg_opd_ref ra, rb;
        sg_ray_surface rows[5];
        sg_opd oa, ob;
        sg_wavefront_opts wo;
        sg_wavefront w;
        sg_fan_opts fo;
        sg_fan fan;
        sg_diag d;
        int j;
        sg_diag_clear(&d);
        assert_int_equal(sg_opd_reference(ta, 0.0, 1.0, &ra, &d), SG_OK);
        assert_int_equal(sg_opd_reference(tb, 0.0, 1.0, &rb, &d), SG_OK);
        assert_int_equal(rb.status, SG_OK);
        assert_true(ra.radius == rb.radius && ra.cy == rb.cy && ra.chief_opl == rb.chief_opl);
        assert_int_equal(sg_trace_opd(ta, &ra, 0.0, 0.7, rows, &oa), SG_OK);
        assert_int_equal(sg_trace_opd(tb, &rb, 0.0, 0.7, rows, &ob), SG_OK);
        assert_int_equal(ob.status, SG_OK);
        assert_true(oa.opd_waves == ob.opd_waves);
        /* The stopped centre has no OPD, and says what stopped it. */
        assert_int_equal(sg_trace_normalized(tb, 0.0, 1.0, 0.0, 0.0, rows), SG_EOBSCURED);
        assert_int_equal(rows[2].status, SG_EOBSCURED);

        sg_wavefront_opts_init(&wo);
        wo.trace.method = methods[mi];
        wo.field = 1;
        wo.nthreads = 2;
        assert_int_equal(sg_wavefront_trace(obsc, NULL, &wo, &w, NULL, &d), SG_OK);
        print_message("# Hubble obscured, %s: wavefront RMS %.6g waves over %zu points\n",
                      method_names[mi], w.rms_chief, w.nvalid);
        assert_true(w.nvalid > 0 && isfinite(w.rms_chief));
        sg_wavefront_free(&w);

        sg_fan_opts_init(&fo);
        fo.trace.method = methods[mi];
        fo.npts = 21;
        fo.opd = 1;
        fo.nthreads = 2;
        assert_int_equal(sg_fan_compute(obsc, NULL, &fo, &fan, &d), SG_OK);
        for (j = 0; j < 21; j++) {
            double p = fan.tan[1].p[j];
            /* 177.8 of 1200 on the primary: |P| below 0.148 is stopped. */
            int want = fabs(p) < 0.14 ? SG_EOBSCURED : SG_OK;
            assert_int_equal(fan.status[1], SG_OK);
            if (fan.tan[1].status[j] != want)
                fail_msg("%s: OPD fan at Py %g: %s", method_names[mi], p,
                         sg_err_name(fan.tan[1].status[j]));
        }
        sg_fan_free(&fan);
        sg_tracer_free(ta);
        sg_tracer_free(tb);
    }
    sg_system_free(open);
    sg_system_free(obsc);
}

/* An F/10 paraboloid (R -2000, EPD 100) with a central obscuration of
 * radius e * 50 on the mirror, the stop: an axial point images perfectly. */
static sg_system *paraboloid(double e)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 3), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].radius = -2000.0;
    sys->surf[1].conic = -1.0;
    sys->surf[1].thickness = -1000.0;
    sys->surf[1].mat.kind = SG_MAT_MIRROR;
    sys->surf[1].aperture = SG_OBSCURATION_CIRCULAR;
    sys->surf[1].ap_rmax = e * 50.0;
    sys->stop = 1;
    sys->aper_value = 100.0;
    sg_diag_clear(&d);
    if (sg_system_validate(sys, NULL, &d) != SG_OK)
        fail_msg("paraboloid: %s", d.msg);
    return sys;
}

static void test_paraboloid(void **state)
{
    const double e = 0.3;
    sg_system *sys = paraboloid(e);
    int mi, i, j, inside = 0, ring;
    size_t want_hex = 1;
    (void)state;
    /* Hexapolar, 6 rings: ring k (6k rays) at radius k/6; those beyond e
     * pass. */
    want_hex = 0;
    for (ring = 1; ring <= 6; ring++)
        if (ring / 6.0 > e)
            want_hex += 6 * (size_t)ring;
    /* The wavefront's 64 x 64 grid: points inside the unit circle and
     * outside e (none lies within 1e-6 of either edge). */
    for (i = 0; i < 64; i++)
        for (j = 0; j < 64; j++) {
            double px = -1.0 + 2.0 * i / 63, py = -1.0 + 2.0 * j / 63, r = hypot(px, py);
            assert_true(fabs(r - e) > 1e-6 && fabs(r - 1.0) > 1e-6);
            inside += r <= 1.0 && r > e;
        }
    {
        /* The count against the annulus's area: with cell h = 2/63, the
         * points of radius in (e, 1] number between pi ((R - d)^2 - (eR +
         * d)^2) and pi ((R + d)^2 - (eR - d)^2), R = 1/h, d = sqrt(2)/2
         * (each point's cell lies within half a diagonal of it). */
        double R = 63.0 / 2.0, dd = sqrt(0.5), pi = 3.14159265358979323846;
        double lo = pi * ((R - dd) * (R - dd) - (e * R + dd) * (e * R + dd));
        double hi = pi * ((R + dd) * (R + dd) - (e * R - dd) * (e * R - dd));
        print_message("# 64 x 64 grid: %d points in the annulus; area bounds %.1f to %.1f "
                      "(1 - e^2 of pi R^2 = %.1f)\n", inside, lo, hi, (1.0 - e * e) * pi * R * R);
        assert_true(inside >= lo && inside <= hi);
    }
    for (mi = 0; mi < 3; mi++) {
        sg_spot s;
        sg_wavefront_opts wo;
        sg_wavefront w;
        sg_diag d;
        spot_of(sys, methods[mi], &s);
        assert_int_equal(s.field[0].status, SG_OK);
        assert_int_equal((int)s.cell[0].nok, (int)want_hex);
        print_message("# paraboloid F/10, obscuration %.1f, %s: spot RMS %.3g GEO %.3g mm over "
                      "%zu of %zu rays\n", e, method_names[mi], s.cell[0].rms, s.cell[0].geo,
                      s.cell[0].nok, s.cell[0].nray);
        /* Closed form 0: the rounding of a 2 m path, far below 1 nm. */
        assert_true(s.cell[0].rms < 1e-9 && s.cell[0].geo < 1e-9);
        sg_spot_free(&s);

        sg_wavefront_opts_init(&wo);
        wo.trace.method = methods[mi];
        wo.field = 0;
        wo.nthreads = 2;
        sg_diag_clear(&d);
        if (sg_wavefront_trace(sys, NULL, &wo, &w, NULL, &d) != SG_OK)
            fail_msg("wavefront: %s", d.msg);
        print_message("# %s: wavefront RMS %.3g waves, %zu points (%d by hand; annulus area "
                      "1 - e^2 = %.4f of the disc)\n", method_names[mi], w.rms_chief, w.nvalid,
                      inside, 1.0 - e * e);
        assert_int_equal((int)w.nvalid, inside);
        assert_true(w.rms_chief < 1e-6 && w.pv_chief < 1e-5);
        sg_wavefront_free(&w);
    }
    sg_system_free(sys);
}

/* What stopped a ray is named with its kind and surface. */
static void test_stop_text(void **state)
{
    sg_system *sys = paraboloid(0.3);
    char b[160];
    (void)state;
    assert_string_equal(sg_ray_stop_text(sys, 1, SG_EOBSCURED, b, sizeof b),
                        "ray stopped by the circular obscuration of surface 1");
    sys->surf[1].aperture = SG_APERTURE_RECTANGULAR;
    assert_string_equal(sg_ray_stop_text(sys, 1, SG_EAPERTURE, b, sizeof b),
                        "ray outside the rectangular aperture of surface 1");
    sys->surf[1].semi_diameter = 5.0;
    sys->surf[1].sd_fixed = 1;
    assert_string_equal(sg_ray_stop_text(sys, 1, SG_EVIGNETTED, b, sizeof b),
                        "ray outside the clear semi-diameter 5 of surface 1");
    assert_string_equal(sg_ray_stop_text(sys, 2, SG_ETIR, b, sizeof b),
                        "total internal reflection at surface 2");
    assert_string_equal(sg_strerror(SG_EOBSCURED), "ray stopped by an obscuration");
    assert_true(sg_err_is_ray_status(SG_EOBSCURED) && sg_err_is_ray_status(SG_EAPERTURE));
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hubble_spot_zemax),
        cmocka_unit_test(test_hubble_spot_filtered),
        cmocka_unit_test(test_hubble_fieldcurve),
        cmocka_unit_test(test_hubble_opd),
        cmocka_unit_test(test_paraboloid),
        cmocka_unit_test(test_stop_text),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
