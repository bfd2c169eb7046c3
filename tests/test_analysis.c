/*
 * test_analysis.c - the spot diagram, ray fans and layout against values
 * computed here: pupil patterns against their definitions, RMS and GEO
 * radii against the rays traced one by one and summed in this file, a
 * paraboloid's perfect on-axis focus, and a spherical mirror's transverse
 * aberration from an exact reflection worked out in MPFR.
 */
#include <math.h>
#include <mpfr.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define PI 3.14159265358979323846

/* ---- pupil patterns ---------------------------------------------------- */

static void test_hexapolar_definition(void **state)
{
    int n, i, j;
    (void)state;
    for (n = 1; n <= 12; n++) {
        size_t cnt = sg_pupil_count(SG_PUPIL_HEXAPOLAR, n), cur = 0, k = 1, total = 1;
        double (*p)[2] = malloc(cnt * sizeof *p);
        for (i = 1; i <= n; i++)
            total += (size_t)(6 * i);
        assert_int_equal(cnt, total);
        assert_int_equal(sg_pupil_fill(SG_PUPIL_HEXAPOLAR, n, &cur, p, cnt), cnt);
        assert_true(p[0][0] == 0.0 && p[0][1] == 0.0);
        /* Ring i: 6i rays at radius i/N, every 360/(6i) degrees from +x. */
        for (i = 1; i <= n; i++)
            for (j = 0; j < 6 * i; j++, k++) {
                double a = 2.0 * PI * j / (6.0 * i), r = (double)i / n;
                assert_true(fabs(p[k][0] - r * cos(a)) < 1e-15);
                assert_true(fabs(p[k][1] - r * sin(a)) < 1e-15);
            }
        free(p);
    }
    assert_int_equal(sg_pupil_count(SG_PUPIL_HEXAPOLAR, 5), 91); /* Zemax's example */
}

static void test_square_vogel_definition(void **state)
{
    int n, i, j;
    (void)state;
    for (n = 1; n <= 40; n++) {
        size_t cnt = sg_pupil_count(SG_PUPIL_SQUARE, n), cur = 0, got = 0, m = 0;
        double (*p)[2] = malloc((size_t)(n * n) * sizeof *p), (*q)[2];
        /* Cell centres in the unit circle, with a margin for the rounding of
         * the centres that lie on it. */
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++) {
                double x = -1.0 + (2.0 * j + 1.0) / n, y = -1.0 + (2.0 * i + 1.0) / n;
                if (x * x + y * y <= 1.0 + 1e-12)
                    m++;
            }
        assert_int_equal(cnt, m);
        /* Made three at a time, the same points as in one go. */
        q = malloc((cnt + 3) * sizeof *q);
        while (1) {
            size_t g = sg_pupil_fill(SG_PUPIL_SQUARE, n, &cur, q + got, 3);
            if (!g)
                break;
            got += g;
        }
        assert_int_equal(got, cnt);
        cur = 0;
        assert_int_equal(sg_pupil_fill(SG_PUPIL_SQUARE, n, &cur, p, (size_t)(n * n)), cnt);
        assert_memory_equal(p, q, cnt * sizeof *p);
        for (i = 0; i < (int)cnt; i++)
            assert_true(p[i][0] * p[i][0] + p[i][1] * p[i][1] <= 1.0 + 1e-12);
        free(p);
        free(q);
    }
    for (n = 1; n <= 2000; n += 333) {
        size_t cur = 0, k;
        double (*p)[2] = malloc((size_t)n * sizeof *p), ga = PI * (3.0 - sqrt(5.0));
        assert_int_equal(sg_pupil_count(SG_PUPIL_VOGEL, n), (size_t)n);
        assert_int_equal(sg_pupil_fill(SG_PUPIL_VOGEL, n, &cur, p, (size_t)n), (size_t)n);
        for (k = 0; k < (size_t)n; k++) {
            double r = sqrt((k + 0.5) / n);
            assert_true(fabs(hypot(p[k][0], p[k][1]) - r) < 1e-14);
            assert_true(fabs(p[k][0] - r * cos(ga * k)) < 1e-12);
        }
        free(p);
    }
    assert_int_equal(sg_pupil_count(SG_PUPIL_HEXAPOLAR, 0), 0);
    assert_int_equal(sg_pupil_check(SG_PUPIL_VOGEL, 0, NULL), SG_ERANGE);
    assert_int_equal(sg_pupil_pattern_parse("Vogel"), SG_PUPIL_VOGEL);
    assert_int_equal(sg_pupil_pattern_parse("grid"), -1);
}

/* ---- RMS spot radius against the rays traced one by one ----------------- */

/* Spot of field f of the Cooke triplet traced ray by ray here, by the
 * definitions: about the primary wavelength's chief ray, or the
 * weight-averaged centroid, with each wavelength's rays weighted by it. */
static void direct_spot(const sg_system *sys, const sg_catalog *cat, int f, int pattern,
                        int dens, int centroid, int only, double *rms, double *geo, double *cx,
                        double *cy)
{
    size_t cnt = sg_pupil_count(pattern, dens), cur = 0, k;
    double (*p)[2] = malloc(cnt * sizeof *p), hx, hy, chief[2] = {0, 0};
    double sw = 0, sx = 0, sy = 0, s2 = 0, g = 0;
    sg_ray_surface *row = malloc((size_t)sys->nsurf * sizeof *row);
    double (*img)[SG_MAX_WAVES][2] = malloc(cnt * sizeof *img);
    int (*ok)[SG_MAX_WAVES] = malloc(cnt * sizeof *ok), w, pass;
    sg_field_normalized(sys, f, &hx, &hy);
    sg_pupil_fill(pattern, dens, &cur, p, cnt);
    for (w = 0; w < sys->nwave; w++) {
        sg_trace_opts o;
        sg_tracer *t;
        sg_trace_opts_init(&o);
        o.wave = w;
        t = sg_tracer_new(sys, cat, &o, NULL);
        assert_non_null(t);
        if (w == sys->primary_wave) {
            assert_int_equal(sg_trace_normalized(t, hx, hy, 0, 0, row), SG_OK);
            chief[0] = row[sys->nsurf - 1].x;
            chief[1] = row[sys->nsurf - 1].y;
        }
        for (k = 0; k < cnt; k++) {
            ok[k][w] = sg_trace_normalized(t, hx, hy, p[k][0], p[k][1], row) == SG_OK;
            img[k][w][0] = row[sys->nsurf - 1].x;
            img[k][w][1] = row[sys->nsurf - 1].y;
        }
        sg_tracer_free(t);
    }
    for (pass = 0; pass < 2; pass++) {
        double rx = centroid && pass ? sx / sw : chief[0], ry = centroid && pass ? sy / sw : chief[1];
        for (w = 0; w < sys->nwave; w++)
            for (k = 0; k < cnt; k++) {
                double wt = sys->wave[w].weight, dx, dy;
                if (!ok[k][w] || (only >= 0 && w != only))
                    continue;
                dx = img[k][w][0] - rx;
                dy = img[k][w][1] - ry;
                if (pass == 0) {
                    sw += wt;
                    sx += wt * img[k][w][0];
                    sy += wt * img[k][w][1];
                } else {
                    s2 += wt * (dx * dx + dy * dy);
                    g = fmax(g, hypot(dx, dy));
                }
            }
    }
    *rms = sqrt(s2 / sw);
    *geo = g;
    *cx = sx / sw;
    *cy = sy / sw;
    free(p);
    free(row);
    free(img);
    free(ok);
}

static void check_spot(int pattern, int dens, int ref)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_spot s;
    sg_spot_opts o;
    int f;
    sg_spot_opts_init(&o);
    o.pattern = pattern;
    o.density = dens;
    o.reference = ref;
    o.block = 37; /* many blocks, so the running sums and the hull are used */
    o.max_points = 50;
    assert_int_equal(sg_spot_compute(sys, cat, &o, &s, NULL), SG_OK);
    assert_int_equal(s.nfield, 3);
    assert_int_equal(s.nwave, 3);
    for (f = 0; f < 3; f++) {
        double rms, geo, cx, cy;
        direct_spot(sys, cat, f, pattern, dens, ref == SG_SPOT_REF_CENTROID, -1, &rms, &geo,
                    &cx, &cy);
        assert_int_equal(s.field[f].status, SG_OK);
        assert_true(fabs(s.field[f].rms - rms) <= 1e-9 * rms);
        assert_true(fabs(s.field[f].geo - geo) <= 1e-9 * geo);
        assert_true(fabs(s.field[f].centroid_x - cx) <= 1e-12 + 1e-12 * fabs(cx));
        assert_true(fabs(s.field[f].centroid_y - cy) <= 1e-9 * fabs(geo) + 1e-12 * fabs(cy));
        assert_true(s.cell[f * 3].npts > 0 && s.cell[f * 3].npts <= 50);
    }
    /* Airy radius: 1.22 lambda F/# (working), primary wavelength, in mm. */
    {
        sg_paraxial px;
        assert_int_equal(sg_paraxial_compute(sys, cat, 1, &px, NULL), SG_OK);
        assert_true(fabs(s.airy_radius - 1.22 * 0.5875618e-3 * px.working_fnum) <
                    1e-15);
    }
    sg_spot_free(&s);
    /* One wavelength alone: its own cell's radii. */
    o.wave = 1;
    assert_int_equal(sg_spot_compute(sys, cat, &o, &s, NULL), SG_OK);
    assert_int_equal(s.nwave, 1);
    for (f = 0; f < 3; f++) {
        double rms, geo, cx, cy;
        direct_spot(sys, cat, f, pattern, dens, ref == SG_SPOT_REF_CENTROID, 1, &rms, &geo,
                    &cx, &cy);
        assert_true(fabs(s.cell[f].rms - rms) <= 1e-9 * rms);
        assert_true(fabs(s.cell[f].geo - geo) <= 1e-9 * geo);
        assert_true(fabs(s.cell[f].centroid_y - cy) <= 1e-9 * geo + 1e-12 * fabs(cy));
    }
    sg_spot_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_spot_rms_chief_hex(void **state)
{
    (void)state;
    check_spot(SG_PUPIL_HEXAPOLAR, 6, SG_SPOT_REF_CHIEF);
}

static void test_spot_rms_centroid(void **state)
{
    (void)state;
    check_spot(SG_PUPIL_SQUARE, 15, SG_SPOT_REF_CENTROID);
    check_spot(SG_PUPIL_VOGEL, 300, SG_SPOT_REF_CENTROID);
}

/* ---- a mirror: the paraboloid's perfect focus and the sphere's aberration */

static sg_system *mirror(double conic)
{
    sg_system *sys = tu_one_surface();
    sys->surf[1].radius = -100.0;
    sys->surf[1].conic = conic;
    sys->surf[1].mat.kind = SG_MAT_MIRROR;
    sys->surf[1].thickness = -50.0;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = 20.0;
    return sys;
}

/* The centroid's error bound (the mean of the rays' bounds and the sums'
 * rounding) holds: the singlet's fields lie on the y axis of a rotationally
 * symmetric system, so every exact centroid x is 0 (symmetry, the
 * independent truth), and the precise centroids lie within their bounds
 * (plus the mpfr run's own) of those from the mpfr method at 256 bits.
 * The bound is not vacuous: below 1e-13 mm. */
static void test_spot_centroid_bound(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("singlet.json");
    sg_spot p, m;
    sg_spot_opts o;
    int f, w;
    double worst = 0.0;
    (void)state;
    sg_spot_opts_init(&o);
    o.density = 3;
    assert_int_equal(sg_spot_compute(sys, cat, &o, &p, NULL), SG_OK);
    o.trace.method = SG_METHOD_MPFR;
    assert_int_equal(sg_spot_compute(sys, cat, &o, &m, NULL), SG_OK);
    for (f = 0; f < p.nfield; f++) {
        for (w = 0; w < p.nwave; w++) {
            const sg_spot_cell *c = &p.cell[f * p.nwave + w], *r = &m.cell[f * p.nwave + w];
            assert_true(fabs(c->centroid_x) <= c->centroid_bound_x);
            assert_true(c->centroid_bound_x < 1e-13 && c->centroid_bound_y < 1e-13);
            assert_true(fabs(c->centroid_y - r->centroid_y) <=
                        c->centroid_bound_y + r->centroid_bound_y);
            if (fabs(c->centroid_x) > worst)
                worst = fabs(c->centroid_x);
        }
        assert_true(fabs(p.field[f].centroid_x) <= p.field[f].centroid_bound_x);
        assert_true(fabs(p.field[f].centroid_y - m.field[f].centroid_y) <=
                    p.field[f].centroid_bound_y + m.field[f].centroid_bound_y);
    }
    print_message("# singlet centroids: largest |x| %.3g mm, each within its bound (< 1e-13)\n",
                  worst);
    sg_spot_free(&p);
    sg_spot_free(&m);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_paraboloid_zero_spot(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = mirror(-1.0);
    sg_spot s;
    sg_spot_opts o;
    (void)state;
    sg_spot_opts_init(&o);
    o.density = 20;
    assert_int_equal(sg_spot_compute(sys, cat, &o, &s, NULL), SG_OK);
    assert_int_equal(s.cell[0].nok, s.nray_per_cell);
    /* Every ray meets the focus to the rounding of a 50 mm path. */
    assert_true(s.field[0].rms < 1e-13);
    assert_true(s.field[0].geo < 1e-13);
    sg_spot_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Exact landing height, in MPFR at 256 bits, of the ray parallel to the
 * axis at height h reflected by the sphere of radius c (vertex at 0,
 * centre at z = c) on the plane z = c / 2, the paraxial focus. */
static double sphere_landing(double c, double h)
{
    mpfr_t z, ny, nz, dn, dy, dz, t, y, tmp;
    double r;
    mpfr_inits2(256, z, ny, nz, dn, dy, dz, t, y, tmp, (mpfr_ptr)0);
    /* z = c + sqrt(c^2 - h^2) for c < 0 (the vertex at z = 0). */
    mpfr_set_d(tmp, c, MPFR_RNDN);
    mpfr_sqr(tmp, tmp, MPFR_RNDN);
    mpfr_set_d(z, h, MPFR_RNDN);
    mpfr_sqr(z, z, MPFR_RNDN);
    mpfr_sub(z, tmp, z, MPFR_RNDN);
    mpfr_sqrt(z, z, MPFR_RNDN);
    mpfr_add_d(z, z, c, MPFR_RNDN);
    /* Unit normal (0, h, z - c) / |c|; the direction (0, 0, 1) reflects to
     * d - 2 (d.n) n. */
    mpfr_set_d(ny, h, MPFR_RNDN);
    mpfr_div_d(ny, ny, fabs(c), MPFR_RNDN);
    mpfr_sub_d(nz, z, c, MPFR_RNDN);
    mpfr_div_d(nz, nz, fabs(c), MPFR_RNDN);
    mpfr_mul_2ui(dn, nz, 1, MPFR_RNDN);
    mpfr_mul(dy, dn, ny, MPFR_RNDN);
    mpfr_neg(dy, dy, MPFR_RNDN);
    mpfr_mul(dz, dn, nz, MPFR_RNDN);
    mpfr_d_sub(dz, 1.0, dz, MPFR_RNDN);
    /* t = (c/2 - z) / dz; y = h + t dy. */
    mpfr_set_d(t, c / 2.0, MPFR_RNDN);
    mpfr_sub(t, t, z, MPFR_RNDN);
    mpfr_div(t, t, dz, MPFR_RNDN);
    mpfr_mul(y, t, dy, MPFR_RNDN);
    mpfr_add_d(y, y, h, MPFR_RNDN);
    r = mpfr_get_d(y, MPFR_RNDN);
    mpfr_clears(z, ny, nz, dn, dy, dz, t, y, tmp, (mpfr_ptr)0);
    return r;
}

static void test_sphere_mirror_exact(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = mirror(0.0);
    sg_spot s;
    sg_spot_opts o;
    sg_fan fan;
    sg_fan_opts fo;
    size_t cnt, cur = 0, k;
    double (*p)[2], s2 = 0.0, g = 0.0;
    int j;
    (void)state;
    sg_spot_opts_init(&o);
    o.density = 10;
    assert_int_equal(sg_spot_compute(sys, cat, &o, &s, NULL), SG_OK);
    cnt = sg_pupil_count(SG_PUPIL_HEXAPOLAR, 10);
    p = malloc(cnt * sizeof *p);
    sg_pupil_fill(SG_PUPIL_HEXAPOLAR, 10, &cur, p, cnt);
    /* The chief ray is the axis; each ray lands at radius |e(rho)|. */
    for (k = 0; k < cnt; k++) {
        double e = sphere_landing(-100.0, 10.0 * hypot(p[k][0], p[k][1]));
        s2 += e * e;
        g = fmax(g, fabs(e));
    }
    assert_true(g > 1e-3); /* an aberration worth measuring: about 0.025 mm */
    assert_true(fabs(s.field[0].rms - sqrt(s2 / cnt)) <= 1e-12 * g);
    assert_true(fabs(s.field[0].geo - g) <= 1e-12 * g);
    sg_spot_free(&s);
    free(p);

    sg_fan_opts_init(&fo);
    fo.npts = 11;
    assert_int_equal(sg_fan_compute(sys, cat, &fo, &fan, NULL), SG_OK);
    for (j = 0; j < 11; j++) {
        double py = fan.tan[0].p[j], e = sphere_landing(-100.0, 10.0 * py);
        assert_true(fabs(py - (-1.0 + 0.2 * j)) < 1e-15);
        assert_int_equal(fan.tan[0].status[j], SG_OK);
        assert_true(fabs(fan.tan[0].e[j] - e) <= 1e-12 * g);
        /* Sagittal: the same ray turned by 90 degrees. */
        assert_true(fabs(fan.sag[0].e[j] - e) <= 1e-12 * g);
    }
    sg_fan_free(&fan);
    sg_system_free(sys);
    sg_catalog_free(cat);
}


/* A refined fan's polyline follows the true curve: the spherical mirror's
 * ey(Py) in closed form (sphere_landing, MPFR), evaluated at 2001 points,
 * departs from the piecewise-linear curve through the samples by at most
 * twice the tolerance asked (1e-3 of the largest |ey|), where the 5 even
 * samples alone miss it by far more; every sample is on the curve, in
 * increasing Py. */
static void test_fan_refine(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = mirror(0.0);
    sg_fan fan;
    sg_fan_opts fo;
    int pass, j, k;
    double g = fabs(sphere_landing(-100.0, 10.0)), dev[2];
    (void)state;
    for (pass = 0; pass < 2; pass++) {
        const sg_fan_curve *c;
        sg_fan_opts_init(&fo);
        fo.npts = 5;
        fo.refine = pass;
        assert_int_equal(sg_fan_compute(sys, cat, &fo, &fan, NULL), SG_OK);
        c = &fan.tan[0];
        assert_true(pass ? c->n > 20 : c->n == 5);
        for (j = 0; j < c->n; j++) {
            assert_int_equal(c->status[j], SG_OK);
            assert_true(fabs(c->e[j] - sphere_landing(-100.0, 10.0 * c->p[j])) <= 1e-12 * g);
            if (j)
                assert_true(c->p[j] > c->p[j - 1]);
        }
        dev[pass] = 0.0;
        for (k = 0, j = 0; k <= 2000; k++) {
            double py = -1.0 + k / 1000.0, t, lin;
            while (j + 2 < c->n && c->p[j + 1] < py)
                j++;
            t = (py - c->p[j]) / (c->p[j + 1] - c->p[j]);
            lin = c->e[j] + t * (c->e[j + 1] - c->e[j]);
            dev[pass] = fmax(dev[pass], fabs(lin - sphere_landing(-100.0, 10.0 * py)));
        }
        sg_fan_free(&fan);
    }
    print_message("# fan refine: max deviation %.3g of the range unrefined, %.3g refined\n",
                  dev[0] / g, dev[1] / g);
    assert_true(dev[0] > 1e-2 * g);
    assert_true(dev[1] <= 2e-3 * g);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Fans of every wavelength measure from the primary wavelength's chief ray. */
static void test_fan_polychromatic_reference(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_fan fan;
    sg_fan_opts fo;
    sg_ray_surface *row = malloc((size_t)sys->nsurf * sizeof *row);
    int w, j, img = sys->nsurf - 1;
    double hx, hy, cy;
    sg_tracer *t;
    (void)state;
    sg_fan_opts_init(&fo);
    fo.npts = 5;
    fo.field = 2;
    assert_int_equal(sg_fan_compute(sys, cat, &fo, &fan, NULL), SG_OK);
    sg_field_normalized(sys, 2, &hx, &hy);
    assert_true(hy == 1.0);
    t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    assert_int_equal(sg_trace_normalized(t, hx, hy, 0, 0, row), SG_OK);
    cy = row[img].y;
    sg_tracer_free(t);
    for (w = 0; w < 3; w++) {
        sg_trace_opts o;
        sg_trace_opts_init(&o);
        o.wave = w;
        t = sg_tracer_new(sys, cat, &o, NULL);
        for (j = 0; j < 5; j++) {
            int rc = sg_trace_normalized(t, hx, hy, 0, -1.0 + 0.5 * j, row);
            assert_int_equal(fan.tan[w].status[j], rc);
            if (rc == SG_OK)
                assert_true(fan.tan[w].e[j] == row[img].y - cy);
        }
        sg_tracer_free(t);
    }
    sg_fan_free(&fan);
    free(row);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The layout's points are the trace's, moved by the thicknesses. */
static void test_layout_positions(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cassegrain.json");
    sg_layout l;
    sg_layout_opts o;
    sg_tracer *t;
    sg_ray_surface *row = malloc((size_t)sys->nsurf * sizeof *row);
    int i, r;
    (void)state;
    sg_layout_opts_init(&o);
    o.nrays = 3;
    assert_int_equal(sg_layout_compute(sys, cat, &o, &l, NULL), SG_OK);
    assert_int_equal(l.nray, 3 * sys->nfield);
    t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    for (r = 0; r < l.nray; r++) {
        double hx, hy, z0 = 0.0;
        sg_field_normalized(sys, l.field_index[l.ray[r].field], &hx, &hy);
        assert_int_equal(sg_trace_normalized(t, hx, hy, 0, l.ray[r].py, row), l.ray[r].status);
        assert_int_equal(l.ray[r].npts, sys->nsurf - 1);
        for (i = 1; i < sys->nsurf; i++) {
            assert_true(l.ray[r].y[i - 1] == row[i].y);
            assert_true(fabs(l.ray[r].z[i - 1] - (row[i].z + z0)) <= 1e-9 * (1 + fabs(z0)));
            assert_true(fabs(l.surf[i - 1].z0 - z0) <= 1e-9 * (1 + fabs(z0)));
            z0 += sys->surf[i].thickness;
        }
    }
    /* The first mirror's profile: its sag at the vertex and at the rim. */
    for (i = 1; i < sys->nsurf; i++) {
        sg_layout_surface *s = &l.surf[i - 1];
        assert_true(s->npts == o.profile_pts);
        assert_true(s->y[0] == -s->sd && s->y[s->npts - 1] == s->sd);
        assert_true(s->z[0] == s->z0 + sg_surface_sag(&sys->surf[i], 0, -s->sd));
        assert_true(s->sd > 0.0);
    }
    assert_true(l.surf[1].mirror);
    sg_tracer_free(t);
    sg_layout_free(&l);
    free(row);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_bad_input(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("singlet.json");
    sg_spot s;
    sg_spot_opts o;
    sg_diag d;
    (void)state;
    sg_spot_opts_init(&o);
    o.field = 7;
    sg_diag_clear(&d);
    assert_int_equal(sg_spot_compute(sys, cat, &o, &s, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "field 8 is not one of 1 to"));
    o.field = -1;
    o.density = 0;
    sg_diag_clear(&d);
    assert_int_equal(sg_spot_compute(sys, cat, &o, &s, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "hexapolar density 0"));
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hexapolar_definition),
        cmocka_unit_test(test_square_vogel_definition),
        cmocka_unit_test(test_spot_rms_chief_hex),
        cmocka_unit_test(test_spot_rms_centroid),
        cmocka_unit_test(test_paraboloid_zero_spot),
        cmocka_unit_test(test_spot_centroid_bound),
        cmocka_unit_test(test_sphere_mirror_exact),
        cmocka_unit_test(test_fan_refine),
        cmocka_unit_test(test_fan_polychromatic_reference),
        cmocka_unit_test(test_layout_positions),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
