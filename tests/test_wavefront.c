/*
 * test_wavefront.c - the traced wavefront (sg_wavefront_trace) and OPD fans
 * against independent truths:
 *
 * 1. A paraboloid mirror with the object at infinity is perfect: the map
 *    is zero.
 * 2. A spherical mirror with its stop at the centre of curvature has pure
 *    spherical aberration.  Welford's SI = -A^2 h D(u/n) for the mirror,
 *    worked here from the paraxial marginal ray (A = h / R, n'u' = 2h / R,
 *    n' = -1): SI = -2 h^4 / R^3, W040 = SI / 8.  On W = W040 rho^4 the
 *    Fringe Z9 (6 rho^4 - 6 rho^2 + 1) takes W040 / 6 and Standard Z11
 *    (sqrt 5 times it) W040 / (6 sqrt 5).  Higher orders are of relative
 *    size (h / R)^2 = 6e-4 here (1.5e-3 seen), inside the 0.4% allowed.
 * 3. The map's RMS and P-V equal those computed here from sg_trace_opd
 *    at the same grid points (the single-ray path, not the batch).
 * 3b. At a non-primary wavelength the map is sg_trace_opd less that
 *    wavelength's chief ray's OPD (Zemax's map is zero at its chief ray).
 * 4. OPD fans equal sg_trace_opd at the fan's pupil points, and a
 *    paraboloid whose image plane is moved by dz gives the closed form of
 *    defocus (see opd_fan_defocus).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* Object at infinity; a flat stop (surface 1) a distance S before a
 * mirror of radius R and conic k; the image T1 after the mirror; EPD. */
static sg_system *stop_mirror(double S, double R, double k, double T1, double epd)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].radius = INFINITY;
    sys->surf[1].thickness = S;
    sys->surf[2].radius = R;
    sys->surf[2].conic = k;
    sys->surf[2].mat.kind = SG_MAT_MIRROR;
    sys->surf[2].thickness = T1;
    sys->stop = 1;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = epd;
    sys->field_type = SG_FIELD_ANGLE;
    sys->nfield = 1;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[0].weight = 1.0;
    return sys;
}

static void paraboloid_flat(void **state)
{
    sg_system *sys = stop_mirror(100.0, -400.0, -1.0, -200.0, 80.0);
    sg_catalog *cat = tu_catalog();
    sg_wavefront_opts o;
    sg_wavefront w;
    sg_diag d;
    (void)state;
    sg_wavefront_opts_init(&o);
    o.grid = 33;
    assert_int_equal(sg_wavefront_trace(sys, cat, &o, &w, NULL, &d), SG_OK);
    print_message("# paraboloid: RMS %.3g, P-V %.3g waves over %zu rays\n", w.rms_chief,
                  w.pv_chief, w.nvalid);
    assert_true(w.nvalid > 780);
    assert_true(w.rms_chief < 1e-9 && w.pv_chief < 1e-9 && w.rms_centroid < 1e-9);
    sg_wavefront_free(&w);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void sphere_w040(void **state)
{
    const double R = -1000.0, h = 25.0;
    sg_system *sys = stop_mirror(-R, R, 0.0, R / 2, 2 * h);
    sg_catalog *cat = tu_catalog();
    sg_wavefront_opts o;
    sg_wavefront w;
    sg_diag d;
    double lambda, SI, W040, z;
    int kind;
    (void)state;
    lambda = sys->wave[sys->primary_wave].um * 1e-3; /* mm */
    SI = -2.0 * pow(h, 4) / pow(R, 3);
    W040 = SI / 8.0 / lambda;
    for (kind = 0; kind < 2; kind++) {
        sg_wavefront_opts_init(&o);
        o.grid = 65;
        o.kind = kind ? SG_ZERNIKE_STANDARD : SG_ZERNIKE_FRINGE;
        o.nterms = 37;
        assert_int_equal(sg_wavefront_trace(sys, cat, &o, &w, NULL, &d), SG_OK);
        z = kind ? w.coef[10] * 6.0 * sqrt(5.0) : w.coef[8] * 6.0;
        print_message("# sphere R %g, h %g: W040 %.9g waves from the fit, SI/8 %.9g\n", R, h,
                      z, W040);
        assert_true(fabs(z - W040) <= 4e-3 * fabs(W040));
        sg_wavefront_free(&w);
    }
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void rms_direct(void **state)
{
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_catalog *cat = tu_catalog();
    sg_tracer *t;
    sg_wavefront_opts o;
    sg_wavefront w;
    sg_opd_ref ref;
    sg_diag d;
    sg_ray_surface rows[32];
    double s = 0, s2 = 0, lo = INFINITY, hi = -INFINITY, mean, rms;
    size_t n = 0;
    int i, j, g = 25;
    (void)state;
    sg_wavefront_opts_init(&o);
    o.grid = g;
    o.field = 1;
    o.block = 37; /* several blocks, one of them short */
    assert_int_equal(sg_wavefront_trace(sys, cat, &o, &w, &ref, &d), SG_OK);
    t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    assert_true(sg_tracer_nsurf(t) <= 32);
    for (j = 0; j < g; j++)
        for (i = 0; i < g; i++) {
            double px = -1.0 + 2.0 * i / (g - 1), py = -1.0 + 2.0 * j / (g - 1);
            sg_opd r;
            if (px * px + py * py > 1.0)
                continue;
            if (sg_trace_opd(t, &ref, px, py, rows, &r) != SG_OK || r.status != SG_OK)
                continue;
            assert_true(w.valid[j * g + i]);
            assert_true(fabs(w.map[j * g + i] - r.opd_waves) <= 1e-12);
            s += r.opd_waves;
            n++;
            lo = fmin(lo, r.opd_waves);
            hi = fmax(hi, r.opd_waves);
        }
    mean = s / (double)n;
    for (j = 0; j < g; j++)
        for (i = 0; i < g; i++)
            if (w.valid[j * g + i])
                s2 += (w.map[j * g + i] - mean) * (w.map[j * g + i] - mean);
    rms = sqrt(s2 / (double)n);
    print_message("# Cooke field 2: RMS %.12g (direct %.12g), P-V %.12g (direct %.12g), %zu "
                  "rays\n", w.rms_chief, rms, w.pv_chief, hi - lo, n);
    assert_int_equal(w.nvalid, n);
    assert_true(rms > 0.1);
    assert_true(fabs(w.rms_chief - rms) <= 1e-10 * rms);
    assert_true(fabs(w.pv_chief - (hi - lo)) <= 1e-10 * (hi - lo));
    sg_tracer_free(t);
    sg_wavefront_free(&w);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* The Cooke triplet's map at its shortest wavelength (not the primary):
 * each value is sg_trace_opd against the primary sphere less the same
 * wavelength's chief ray's, zero at the pupil's centre; RMS and P-V are
 * those of sg_trace_opd's values, which the piston does not change. */
static void wave_own_chief(void **state)
{
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_catalog *cat = tu_catalog();
    sg_trace_opts to;
    sg_tracer *t;
    sg_wavefront_opts o;
    sg_wavefront w;
    sg_opd_ref ref;
    sg_opd c0;
    sg_diag d;
    sg_ray_surface rows[32];
    double worst = 0.0, lo = INFINITY, hi = -INFINITY;
    int i, j, g = 21, wv = sys->primary_wave == 0 ? 1 : 0;
    (void)state;
    sg_wavefront_opts_init(&o);
    o.grid = g;
    o.field = 1;
    o.trace.wave = wv;
    assert_int_equal(sg_wavefront_trace(sys, cat, &o, &w, &ref, &d), SG_OK);
    sg_trace_opts_init(&to);
    to.wave = wv;
    t = sg_tracer_new(sys, cat, &to, &d);
    assert_non_null(t);
    assert_true(sg_tracer_nsurf(t) <= 32);
    assert_int_equal(sg_trace_opd(t, &ref, 0.0, 0.0, rows, &c0), SG_OK);
    assert_true(fabs(c0.opd_waves) > 1.0); /* a piston to take away */
    /* The grid's centre is the chief ray. */
    assert_true(w.valid[(g / 2) * g + g / 2]);
    assert_true(fabs(w.map[(g / 2) * g + g / 2]) <= 1e-12);
    for (j = 0; j < g; j++)
        for (i = 0; i < g; i++) {
            double px = -1.0 + 2.0 * i / (g - 1), py = -1.0 + 2.0 * j / (g - 1);
            sg_opd r;
            if (px * px + py * py > 1.0 || !w.valid[j * g + i])
                continue;
            assert_int_equal(sg_trace_opd(t, &ref, px, py, rows, &r), SG_OK);
            worst = fmax(worst, fabs(w.map[j * g + i] - (r.opd_waves - c0.opd_waves)));
            lo = fmin(lo, r.opd_waves);
            hi = fmax(hi, r.opd_waves);
        }
    print_message("# Cooke wave %d: chief OPD %.6g waves taken away; largest difference "
                  "%.3g\n", wv + 1, c0.opd_waves, worst);
    assert_true(worst <= 1e-9);
    assert_true(fabs(w.pv_chief - (hi - lo)) <= 1e-9 * (hi - lo));
    sg_tracer_free(t);
    sg_wavefront_free(&w);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* OPD fans of the Cooke triplet at every wavelength equal sg_trace_opd
 * against the field's sphere at the same pupil points, less the same
 * wavelength's chief ray's. */
static void opd_fan_direct(void **state)
{
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_catalog *cat = tu_catalog();
    sg_fan_opts o;
    sg_fan fan;
    sg_diag d;
    sg_ray_surface rows[32];
    int fi, w, j, side, n = 0;
    double worst = 0.0;
    (void)state;
    sg_fan_opts_init(&o);
    o.npts = 11;
    o.opd = 1;
    assert_int_equal(sg_fan_compute(sys, cat, &o, &fan, &d), SG_OK);
    assert_int_equal(fan.opd, 1);
    for (w = 0; w < fan.nwave; w++) {
        sg_trace_opts to;
        sg_tracer *t;
        sg_trace_opts_init(&to);
        to.wave = fan.wave_index[w];
        t = sg_tracer_new(sys, cat, &to, &d);
        assert_non_null(t);
        for (fi = 0; fi < fan.nfield; fi++) {
            sg_opd_ref ref;
            sg_opd c0;
            assert_int_equal(sg_opd_reference(t, fan.hx[fi], fan.hy[fi], &ref, NULL), SG_OK);
            assert_int_equal(sg_trace_opd(t, &ref, 0.0, 0.0, rows, &c0), SG_OK);
            if (fan.wave_index[w] != sys->primary_wave)
                assert_true(fabs(c0.opd_waves) > 1.0); /* the piston taken away */
            for (side = 0; side < 2; side++) {
                const sg_fan_curve *c = side ? &fan.sag[fi * fan.nwave + w]
                                             : &fan.tan[fi * fan.nwave + w];
                for (j = 0; j < fan.npts; j++) {
                    double p = -1.0 + 2.0 * j / (fan.npts - 1);
                    sg_opd r;
                    int st = sg_trace_opd(t, &ref, side ? p : 0.0, side ? 0.0 : p, rows, &r);
                    assert_int_equal(c->status[j], st == SG_OK ? r.status : st);
                    if (c->status[j] != SG_OK)
                        continue;
                    worst = fmax(worst, fabs(c->e[j] - (r.opd_waves - c0.opd_waves)));
                    n++;
                }
            }
        }
        sg_tracer_free(t);
    }
    print_message("# Cooke OPD fans: %d rays, largest difference from sg_trace_opd %.3g "
                  "waves\n", n, worst);
    assert_true(n > 150);
    assert_true(worst <= 1e-9);
    sg_fan_free(&fan);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* A paraboloid (focal length f, stop on it, object at infinity) with its
 * image plane dz beyond the focus F.  After the mirror the wavefront is a
 * sphere about F; the one through the vertex E has radius f.  The
 * reference sphere is centred on the image point C, dz beyond F on the
 * axis, through E: radius f + dz.  A ray leaving the wavefront at angle
 * theta to the axis toward F meets it where its signed distance s from F
 * solves s^2 + 2 s dz cos(theta) + dz^2 = (f + dz)^2, having travelled
 * f - s; the chief ray travels 0.  So
 *     W = (s - f) / lambda,  s = -dz cos(theta) + sqrt((f + dz)^2 - dz^2 sin^2(theta)),
 * with tan(theta / 2) = h / (2 f) for the ray at height h = P * EPD / 2
 * (the paraboloid's focal chord).  Both fans are the same curve. */
static void opd_fan_defocus(void **state)
{
    const double f = 200.0, dz = 0.5, epd = 80.0;
    sg_system *sys = stop_mirror(0.0, -2 * f, -1.0, -(f + dz), epd);
    sg_catalog *cat = tu_catalog();
    sg_fan_opts o;
    sg_fan fan;
    sg_diag d;
    double lambda, worst = 0.0, big = 0.0;
    int j, side;
    (void)state;
    /* The stop on the mirror: surface 1 is a dummy at the mirror's vertex. */
    lambda = sys->wave[sys->primary_wave].um * 1e-3;
    sg_fan_opts_init(&o);
    o.npts = 21;
    o.opd = 1;
    assert_int_equal(sg_fan_compute(sys, cat, &o, &fan, &d), SG_OK);
    for (side = 0; side < 2; side++) {
        const sg_fan_curve *c = side ? &fan.sag[0] : &fan.tan[0];
        for (j = 0; j < fan.npts; j++) {
            double h = c->p[j] * epd / 2, th = 2.0 * atan(h / (2.0 * f)), s, W;
            s = -dz * cos(th) + sqrt((f + dz) * (f + dz) - dz * dz * sin(th) * sin(th));
            W = (s - f) / lambda;
            assert_int_equal(c->status[j], SG_OK);
            worst = fmax(worst, fabs(c->e[j] - W));
            big = fmax(big, fabs(W));
        }
    }
    print_message("# paraboloid f %g defocused %g: OPD fan against the closed form: largest "
                  "difference %.3g waves (largest OPD %.4g)\n", f, dz, worst, big);
    assert_true(big > 10.0);
    assert_true(worst <= 1e-9);
    sg_fan_free(&fan);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

static void bad_input(void **state)
{
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_catalog *cat = tu_catalog();
    sg_wavefront_opts o;
    sg_wavefront w;
    sg_diag d;
    (void)state;
    sg_wavefront_opts_init(&o);
    o.field = 9;
    sg_diag_clear(&d);
    assert_int_equal(sg_wavefront_trace(sys, cat, &o, &w, NULL, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "field 10"));
    sg_wavefront_opts_init(&o);
    o.grid = 2;
    assert_int_equal(sg_wavefront_trace(sys, cat, &o, &w, NULL, &d), SG_ERANGE);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(paraboloid_flat),
        cmocka_unit_test(sphere_w040),
        cmocka_unit_test(rms_direct),
        cmocka_unit_test(wave_own_chief),
        cmocka_unit_test(opd_fan_direct),
        cmocka_unit_test(opd_fan_defocus),
        cmocka_unit_test(bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
