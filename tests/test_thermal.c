/*
 * test_thermal.c - thermal expansion (sg_thermal, sg_thermal_tces) against
 * closed forms: a singlet's radii and thicknesses, its focal length by the
 * thick-lens formula at the index the thermal model gives, a thin lens's
 * thermal defocus in a housing against the opto-thermal coefficient
 * alpha - beta / (n - 1), an air space's spacer by the sphere's sag, and an
 * even asphere whose scaled sag at s r is s times the original at r in
 * 256-bit MPFR.  The TCEs come from the catalog's ED lines (data), the
 * rules from sagitta-design(5), THERMAL EXPANSION.
 */
#include <math.h>
#include <mpfr.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "shape.h"
#include "testutil.h"

static sg_catalog *cat;

static int setup(void **state)
{
    (void)state;
    cat = tu_catalog();
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    sg_catalog_free(cat);
    return 0;
}

static double glass_tce(const char *name)
{
    const sg_glass *g = sg_catalog_find(cat, name);
    assert_non_null(g);
    assert_true(g->has_ed);
    return g->ed[0];
}

/* A sphere's sag at height h, the closed form. */
static double sphere_sag(double r, double h)
{
    if (h == 0.0 || isinf(r))
        return 0.0;
    return h * h / (r * (1.0 + sqrt(1.0 - h * h / (r * r))));
}

static double rel(double a, double b)
{
    return fabs(a - b) / fabs(b);
}

/* Object at infinity, an N-BK7 singlet (the stop), an air space held by a
 * housing of TCE tce_h, the image. */
static sg_system *singlet(double r1, double r2, double t, double sd, double air,
                          double tce_h)
{
    sg_system *s = sg_system_new();
    assert_non_null(s);
    assert_int_equal(sg_system_reset(s, 4), SG_OK);
    s->stop = 1;
    s->surf[0].thickness = INFINITY;
    s->surf[1].radius = r1;
    s->surf[1].thickness = t;
    s->surf[1].mat.kind = SG_MAT_GLASS;
    snprintf(s->surf[1].mat.name, sizeof s->surf[1].mat.name, "N-BK7");
    s->surf[1].semi_diameter = sd;
    s->surf[2].radius = r2;
    s->surf[2].thickness = air;
    s->surf[2].semi_diameter = sd;
    s->surf[2].tce = tce_h;
    return s;
}

static sg_system *hot_of(const sg_system *s, double temp, double pres)
{
    sg_system *h = sg_system_new();
    sg_diag d;
    int rc;
    assert_non_null(h);
    sg_diag_clear(&d);
    rc = sg_thermal(s, cat, temp, pres, h, &d);
    if (rc != SG_OK)
        fail_msg("sg_thermal: %s", d.msg);
    return h;
}

/* The singlet at 70 C from 20 C: the glass's radii (front and rear face)
 * and centre thickness by its TCE, the air space by the housing's spacer
 * touching the rear face at its semi-diameter, the focal length by the
 * thick-lens formula at the thermal model's index. */
static void test_singlet(void **state)
{
    const double r1 = 51.5, r2 = -80.0, t = 4.0, sd = 12.0, air = 90.0, th = 23.6;
    const double temp = 70.0, dt = temp - 20.0;
    double ag = glass_tce("N-BK7"), sg = 1.0 + ag * 1e-6 * dt, sh = 1.0 + th * 1e-6 * dt;
    double n, f, spacer, want_air, um;
    sg_system *s = singlet(r1, r2, t, sd, air, th), *h;
    sg_paraxial px;
    sg_diag d;
    (void)state;
    assert_true(ag == 7.1);
    h = hot_of(s, temp, 1.0);
    assert_true(h->temperature == temp && h->pressure == 1.0 && h->adjust_index == 1);
    assert_true(rel(h->surf[1].radius, r1 * sg) < 2e-16);
    assert_true(rel(h->surf[2].radius, r2 * sg) < 2e-16);
    assert_true(rel(h->surf[1].thickness, t * sg) < 2e-16);
    assert_true(rel(h->surf[1].semi_diameter, sd * sg) < 2e-16);
    assert_true(rel(h->surf[2].semi_diameter, sd * sg) < 2e-16);
    /* The spacer from the rear face's edge (sag z at sd) to the flat
     * image: its length grows by the housing, and the grown rear face
     * meets it at the radius sd sh. */
    spacer = air - sphere_sag(r2, sd);
    want_air = spacer * sh + sphere_sag(r2 * sg, sd * sh);
    if (rel(h->surf[2].thickness, want_air) > 1e-14)
        fail_msg("air space %.17g, closed form %.17g", h->surf[2].thickness, want_air);
    /* Not the centre scaled alone: the spacer's contact shows. */
    assert_true(fabs(want_air - air * sh) > 1e-6);

    um = h->wave[h->primary_wave].um;
    n = sg_glass_index_env(sg_catalog_find(cat, "N-BK7"), um, temp, 1.0);
    {
        double R1 = r1 * sg, R2 = r2 * sg, T = t * sg;
        f = 1.0 / ((n - 1.0) * (1.0 / R1 - 1.0 / R2 + (n - 1.0) * T / (n * R1 * R2)));
    }
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(h, cat, h->primary_wave, &px, &d), SG_OK);
    if (rel(px.efl, f) > 1e-12)
        fail_msg("EFL at %g C: %.17g, thick-lens formula %.17g", temp, px.efl, f);
    print_message("# singlet 20 -> 70 C: radii, thickness, semi-diameters x (1 + 7.1e-6 dT); "
                  "air %.12g (spacer closed form %.12g); EFL %.12g (formula %.12g)\n",
                  h->surf[2].thickness, want_air, px.efl, f);
    sg_system_free(h);
    /* At the design's own temperature, with spacers touching off the axis,
     * nothing moves, bit for bit. */
    h = hot_of(s, 20.0, 1.0);
    h->adjust_index = 0;
    assert_true(sg_system_equal(h, s));
    h->adjust_index = 1;
    sg_system_free(h);
    sg_system_free(s);
}

/* A thin lens (zero centre thickness, contacts on the axis) focused at
 * 20 C in a housing of TCE 23.6: at T its focal length is exactly
 * f0 sg (n0 - 1) / (nT - 1), the image plane sits at f0 sh, and the
 * defocus agrees with the opto-thermal formula f0 (alpha_g - beta / (n -
 * 1) - alpha_h) dT to its second-order remainder. */
static void test_thin_lens_defocus(void **state)
{
    const double th = 23.6, temps[] = {-40.0, 0.0, 60.0, 120.0};
    const sg_glass *g = sg_catalog_find(cat, "N-BK7");
    double ag = glass_tce("N-BK7"), um, n0, f0, worst = 0.0;
    sg_system *s;
    sg_paraxial px;
    sg_diag d;
    size_t k;
    (void)state;
    s = singlet(100.0, -100.0, 0.0, 0.0, 1.0, th);
    um = s->wave[s->primary_wave].um;
    n0 = sg_glass_index(g, um);
    f0 = 1.0 / ((n0 - 1.0) * 0.02);
    s->surf[2].thickness = f0;
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(s, cat, s->primary_wave, &px, &d), SG_OK);
    assert_true(rel(px.efl, f0) < 1e-13);
    for (k = 0; k < sizeof temps / sizeof temps[0]; k++) {
        double temp = temps[k], dt = temp - 20.0, sg = 1.0 + ag * 1e-6 * dt;
        double sh = 1.0 + th * 1e-6 * dt, nt = sg_glass_index_env(g, um, temp, 1.0);
        double a = ag * 1e-6 * dt, b = (nt - n0) / (n0 - 1.0);
        double exact = f0 * (sg * (n0 - 1.0) / (nt - 1.0) - sh);
        double first = f0 * (ag * 1e-6 - (nt - n0) / dt / (n0 - 1.0) - th * 1e-6) * dt;
        double defocus;
        sg_system *h = hot_of(s, temp, 1.0);
        assert_true(rel(h->surf[2].thickness, f0 * sh) < 2e-16);
        sg_diag_clear(&d);
        assert_int_equal(sg_paraxial_compute(h, cat, h->primary_wave, &px, &d), SG_OK);
        assert_true(rel(px.efl, f0 * sg * (n0 - 1.0) / (nt - 1.0)) < 1e-12);
        defocus = px.bfl - h->surf[2].thickness;
        if (fabs(defocus - exact) > 1e-12 * f0)
            fail_msg("%g C: defocus %.17g, exact %.17g", temp, defocus, exact);
        /* (1 + a) / (1 + b) - 1 - (a - b) = (b^2 - a b) / (1 + b). */
        if (fabs(defocus - first) > f0 * (fabs(a * b) + b * b) / (1.0 - fabs(b)) + 1e-12 * f0)
            fail_msg("%g C: defocus %.17g, opto-thermal formula %.17g", temp, defocus, first);
        if (fabs(defocus) > worst)
            worst = fabs(defocus);
        sg_system_free(h);
    }
    print_message("# thin lens f %.6g in a 23.6e-6/K housing: defocus up to %.4g mm, equal to "
                  "the closed form and to the opto-thermal formula within its remainder\n", f0,
                  worst);
    sg_system_free(s);
}

/* z(r) of an even asphere in MPFR from the double coefficients. */
static void asph_sag_mp(mpfr_t z, const sg_surface *f, const mpfr_t r)
{
    mpfr_t c, r2, t, u;
    int k;
    mpfr_inits2(256, c, r2, t, u, (mpfr_ptr)0);
    mpfr_set_d(c, f->radius, MPFR_RNDN);
    mpfr_ui_div(c, 1, c, MPFR_RNDN);
    mpfr_sqr(r2, r, MPFR_RNDN);
    /* c r^2 / (1 + sqrt(1 - (1 + k) c^2 r^2)) */
    mpfr_sqr(t, c, MPFR_RNDN);
    mpfr_mul(t, t, r2, MPFR_RNDN);
    mpfr_set_d(u, f->conic, MPFR_RNDN);
    mpfr_add_ui(u, u, 1, MPFR_RNDN);
    mpfr_mul(t, t, u, MPFR_RNDN);
    mpfr_ui_sub(t, 1, t, MPFR_RNDN);
    mpfr_sqrt(t, t, MPFR_RNDN);
    mpfr_add_ui(t, t, 1, MPFR_RNDN);
    mpfr_mul(z, c, r2, MPFR_RNDN);
    mpfr_div(z, z, t, MPFR_RNDN);
    mpfr_set(u, r2, MPFR_RNDN);
    for (k = 0; k < SG_NASPH; k++) {
        mpfr_set_d(t, f->asph[k], MPFR_RNDN);
        mpfr_mul(t, t, u, MPFR_RNDN);
        mpfr_add(z, z, t, MPFR_RNDN);
        mpfr_mul(u, u, r2, MPFR_RNDN);
    }
    mpfr_clears(c, r2, t, u, (mpfr_ptr)0);
}

/* An even asphere on a mount of TCE 23.6 (air on both sides), 20 -> 100
 * C: the scaled surface's sag at s r equals s times the original's at r,
 * in 256-bit MPFR, to the rounding of the stored coefficients. */
static void test_asphere_mpfr(void **state)
{
    static const double a[SG_NASPH] = {1e-3, 1e-6, -1e-9, 1e-12, -1e-15, 1e-18, 1e-21, 1e-24};
    static const double rs[] = {0.5, 1.0, 2.5, 5.0, 7.5, 10.0, 12.0};
    sg_system *s = tu_one_surface(), *h;
    mpfr_t sc, r, sr, z0, z1;
    double worst = 0.0;
    size_t i;
    int k;
    (void)state;
    s->surf[1].type = SG_SURF_EVENASPH;
    s->surf[1].radius = 40.0;
    s->surf[1].conic = -0.5;
    s->surf[1].semi_diameter = 12.0;
    s->surf[1].tce = 23.6;
    s->surf[1].thickness = 50.0;
    for (k = 0; k < SG_NASPH; k++)
        s->surf[1].asph[k] = a[k];
    h = hot_of(s, 100.0, 1.0);
    assert_true(h->surf[1].conic == -0.5);
    mpfr_inits2(256, sc, r, sr, z0, z1, (mpfr_ptr)0);
    /* s = 1 + 23.6e-6 x 80, exactly. */
    mpfr_set_ui(sc, 236 * 8, MPFR_RNDN);
    mpfr_div_ui(sc, sc, 1000000, MPFR_RNDN);
    mpfr_add_ui(sc, sc, 1, MPFR_RNDN);
    for (i = 0; i < sizeof rs / sizeof rs[0]; i++) {
        double e;
        mpfr_set_d(r, rs[i], MPFR_RNDN);
        mpfr_mul(sr, r, sc, MPFR_RNDN);
        asph_sag_mp(z0, &s->surf[1], r);
        mpfr_mul(z0, z0, sc, MPFR_RNDN);
        asph_sag_mp(z1, &h->surf[1], sr);
        mpfr_sub(z1, z1, z0, MPFR_RNDN);
        mpfr_div(z1, z1, z0, MPFR_RNDN);
        e = fabs(mpfr_get_d(z1, MPFR_RNDN));
        if (e > worst)
            worst = e;
        if (e > 1e-14)
            fail_msg("r %g: scaled sag at s r differs from s z(r) by %.3g relative", rs[i], e);
    }
    print_message("# even asphere, 8 terms, TCE 23.6, 20 -> 100 C: z'(s r) = s z(r) to %.2g "
                  "relative (256-bit MPFR)\n", worst);
    mpfr_clears(sc, r, sr, z0, z1, (mpfr_ptr)0);
    sg_system_free(h);
    sg_system_free(s);
}

/* The worked example of a Zemax support answer (Zemax community forum,
 * "Thermal analysis - how thermal parameter values being calculated?",
 * 13 May 2019; docs/thermal.md, source 1): an even asphere of radius 100
 * whose TCE column holds 8, with its r^2, r^4 and r^6 terms at 100, from
 * 20 C to 60 and 100 C.  Zemax's thermal pickups gave radius 100.032 and
 * 100.064, and at 100 C the terms 99.93604093, 99.8082455 and 99.68061348
 * (printed to those digits). */
static void test_zemax_forum_example(void **state)
{
    sg_system *s = tu_one_surface(), *h;
    sg_surface *f = &s->surf[1];
    (void)state;
    f->type = SG_SURF_EVENASPH;
    f->radius = 100.0;
    f->tce = 8.0;
    f->thickness = 10.0;
    f->asph[0] = f->asph[1] = f->asph[2] = 100.0;
    h = hot_of(s, 60.0, 1.0);
    assert_true(rel(h->surf[1].radius, 100.032) < 1e-15);
    sg_system_free(h);
    h = hot_of(s, 100.0, 1.0);
    assert_true(rel(h->surf[1].radius, 100.064) < 1e-15);
    assert_true(fabs(h->surf[1].asph[0] - 99.93604093) < 5e-9);
    assert_true(fabs(h->surf[1].asph[1] - 99.8082455) < 5e-8);
    assert_true(fabs(h->surf[1].asph[2] - 99.68061348) < 5e-9);
    print_message("# Zemax forum example: radius 100.032 and 100.064, terms %.10g %.10g %.10g "
                  "(Zemax 99.93604093 99.8082455 99.68061348)\n", h->surf[1].asph[0],
                  h->surf[1].asph[1], h->surf[1].asph[2]);
    sg_system_free(h);
    sg_system_free(s);
}

/* Every other shape (each registered type with a shape of its own,
 * sg_shape_ops_of) on a mount of TCE 40, -20 -> 80 C: z'(s x, s y) = s
 * z(x, y), the identity the scaling must keep, by the engine's sag in
 * double; conics stay.  Each type gets every term it reads. */
static void test_shapes_scale(void **state)
{
    const sg_param *tp = sg_param_find(SG_SCOPE_SURFACE, "terms");
    int types[SG_SURF_NTYPES], nt = 0, t;
    static const double pts[][2] = {{0.0, 3.0}, {2.0, 1.0}, {-4.0, 5.0}, {6.0, -2.0},
                                    {1.5, -7.0}};
    double worst = 0.0;
    size_t i, j;
    int k;
    (void)state;
    for (t = 0; t < SG_SURF_NTYPES; t++)
        if (sg_shape_ops_of(t))
            types[nt++] = t;
    assert_true(nt >= 7);
    for (i = 0; i < (size_t)nt; i++) {
        sg_system *s = tu_one_surface(), *h;
        sg_surface *f = &s->surf[1];
        double sc;
        f->type = (sg_surf_type)types[i];
        f->radius = 60.0;
        f->conic = -0.3;
        f->tce = 40.0;
        f->thickness = 50.0;
        s->temperature = -20.0;
        for (k = 0; k < 7; k++)
            f->asph[k] = pow(10.0, -3 * k - 4) * (k % 2 ? -1 : 1);
        for (k = 0; k < SG_NODD; k++)
            f->odd[k] = 2e-3 * pow(10.0, -2 * k) * (k % 2 ? -1 : 1);
        f->radius_x = 45.0;
        f->conic_x = 0.2;
        f->norm_radius = 8.0;
        f->zern_dx = 0.3;
        f->zern_dy = -0.2;
        for (k = 0; k < SG_NTERMS; k++)
            f->terms[k] = sg_param_used(tp, k, types[i]) ? 1e-3 / (k + 1) : 0.0;
        h = hot_of(s, 80.0, 1.0);
        sc = 1.0 + 40e-6 * 100.0;
        assert_true(h->surf[1].conic == f->conic && h->surf[1].conic_x == f->conic_x);
        for (j = 0; j < sizeof pts / sizeof pts[0]; j++) {
            double z0 = sg_surface_sag(f, pts[j][0], pts[j][1]);
            double z1 = sg_surface_sag(&h->surf[1], sc * pts[j][0], sc * pts[j][1]);
            double e = fabs(z1 - sc * z0) / fabs(sc * z0);
            assert_true(isfinite(z0) && isfinite(z1));
            if (e > worst)
                worst = e;
            if (e > 1e-12)
                fail_msg("type %d at (%g, %g): z'(s p) %.17g, s z(p) %.17g", types[i],
                         pts[j][0], pts[j][1], z1, sc * z0);
        }
        sg_system_free(h);
        sg_system_free(s);
    }
    print_message("# %d shapes (odd asphere, toroid, biconic, Zernike Fringe and Standard, XY "
                  "polynomial, Q-type asphere): z'(s x, s y) = s z(x, y) to %.2g relative\n", nt,
                  worst);
}

/* Which TCE each value takes (sagitta-design(5), THERMAL EXPANSION). */
static void test_rules(void **state)
{
    sg_system *s = sg_system_new(), *h;
    sg_thermal_tce t[12];
    sg_diag d;
    double bk7 = glass_tce("N-BK7"), sf5 = glass_tce("N-SF5"), dt = 60.0;
    int i;
    (void)state;
    assert_int_equal(sg_system_reset(s, 12), SG_OK);
    s->surf[0].thickness = INFINITY;
    s->stop = 1;
    for (i = 1; i < 11; i++) {
        s->surf[i].thickness = 5.0;
        s->surf[i].radius = 100.0 * (i % 2 ? 1 : -1);
        s->surf[i].tce = 10.0 + i;
    }
    /* 1 front of a cemented doublet, 2 its interface, 3 its rear face. */
    s->surf[1].mat.kind = SG_MAT_GLASS;
    snprintf(s->surf[1].mat.name, SG_GLASS_NAME, "N-BK7");
    s->surf[2].mat.kind = SG_MAT_GLASS;
    snprintf(s->surf[2].mat.name, SG_GLASS_NAME, "N-SF5");
    /* 4 an air dummy; 5 a front-surface mirror in air (thickness -5). */
    s->surf[5].mat.kind = SG_MAT_MIRROR;
    s->surf[5].thickness = -5.0;
    /* 6 a coordinate break, decentred and tilted. */
    s->surf[6].type = SG_SURF_COORDBRK;
    s->surf[6].radius = INFINITY;
    s->surf[6].before.dx = 2.0;
    s->surf[6].before.dy = -1.0;
    s->surf[6].before.tx = 3.0;
    s->surf[6].thickness = -5.0;
    /* 7 into a fixed index; 8 a back-surface (Mangin) mirror inside it. */
    s->surf[7].mat.kind = SG_MAT_INDEX;
    s->surf[7].mat.index = 1.6;
    s->surf[7].thickness = -5.0;
    s->surf[8].mat.kind = SG_MAT_MIRROR;
    s->surf[8].thickness = 5.0;
    /* 9 out of the index into air, decentred after. */
    s->surf[9].after.dx = 0.5;
    s->surf[10].thickness = 10.0;
    sg_diag_clear(&d);
    assert_int_equal(sg_thermal_tces(s, cat, t, &d), SG_OK);
    /* Shapes: the glass after, else before, else the mount. */
    assert_true(t[1].shape == bk7 && t[2].shape == sf5 && t[3].shape == sf5);
    assert_true(t[4].shape == 14.0 && t[5].shape == 15.0);
    assert_true(t[7].shape == 17.0 && t[8].shape == 17.0 && t[9].shape == 17.0);
    /* Spaces: inside a solid its TCE, in air the mount where it starts. */
    assert_true(t[1].solid && t[1].space == bk7 && t[2].solid && t[2].space == sf5);
    assert_true(!t[3].solid && t[3].space == 13.0 && !t[5].solid && t[5].space == 15.0);
    assert_true(!t[6].solid && t[6].space == 16.0);
    assert_true(t[7].solid && t[7].space == 17.0 && t[8].solid && t[8].space == 17.0);
    assert_true(!t[9].solid && t[9].space == 19.0);
    /* Placements: the surface's own. */
    assert_true(t[6].place == 16.0 && t[9].place == 19.0);

    /* The factor 1 + TCE 1e-6 dT, as documented. */
#define F(tce) (1.0 + (tce) * 1e-6 * dt)
    h = hot_of(s, 80.0, 1.0);
    assert_true(h->surf[6].before.dx == 2.0 * F(16.0) && h->surf[6].before.dy == -1.0 * F(16.0) &&
                h->surf[6].before.tx == 3.0);
    assert_true(h->surf[9].after.dx == 0.5 * F(19.0));
    assert_true(h->surf[2].radius == -100.0 * F(sf5));
    assert_true(h->surf[8].thickness == 5.0 * F(17.0));
    sg_system_free(h);

    /* At the design's own temperature nothing moves, bit for bit. */
    h = hot_of(s, 20.0, 1.0);
    h->adjust_index = s->adjust_index;
    assert_true(sg_system_equal(h, s));
    /* In place. */
    sg_diag_clear(&d);
    assert_int_equal(sg_thermal(s, cat, 80.0, 1.0, s, &d), SG_OK);
    assert_true(s->surf[8].thickness == 5.0 * F(17.0) && s->temperature == 80.0);
    sg_system_free(h);
    sg_system_free(s);

    /* A coordinate break inside a glass keeps the glass around it; a
     * solve is frozen with a warning; an aperture grows with its surface. */
    s = singlet(50.0, -50.0, 4.0, 10.0, 90.0, 23.6);
    assert_int_equal(sg_system_insert(s, 2), SG_OK);
    s->surf[1].thickness = 2.0;
    s->surf[2].type = SG_SURF_COORDBRK;
    s->surf[2].thickness = 2.0;
    s->surf[2].tce = 30.0;
    s->surf[3].aperture = SG_APERTURE_CIRCULAR;
    s->surf[3].ap_rmin = 1.0;
    s->surf[3].ap_rmax = 9.0;
    s->surf[3].ap_xdec = 0.25;
    s->surf[3].ap_ydec = -0.5;
    s->surf[3].ap_xhalf = 3.0;
    s->surf[3].ap_yhalf = 4.0;
    s->surf[3].solve[SG_SOLVE_THICKNESS].kind = SG_SOLVE_MARGINAL_HEIGHT;
    sg_diag_clear(&d);
    assert_int_equal(sg_thermal_tces(s, cat, t, &d), SG_OK);
    assert_true(t[2].solid && t[2].space == bk7);
    sg_diag_clear(&d);
    h = sg_system_new();
    assert_int_equal(sg_thermal(s, cat, 80.0, 1.0, h, &d), SG_OK);
    assert_true(h->surf[2].thickness == 2.0 * F(bk7));
    assert_int_equal(h->surf[3].solve[SG_SOLVE_THICKNESS].kind, SG_SOLVE_NONE);
    assert_true(d.nwarn >= 1 && strstr(d.warn[0], "1 solve and pickup frozen"));
    assert_true(h->surf[3].ap_rmin == 1.0 * F(bk7) && h->surf[3].ap_rmax == 9.0 * F(bk7) &&
                h->surf[3].ap_xdec == 0.25 * F(bk7) && h->surf[3].ap_ydec == -0.5 * F(bk7) &&
                h->surf[3].ap_xhalf == 3.0 * F(bk7) && h->surf[3].ap_yhalf == 4.0 * F(bk7));
#undef F
    print_message("# TCE rules: cemented, rear face, dummy, mirror, coordinate breaks, fixed "
                  "index and Mangin mirror as documented; no change at the own temperature; "
                  "solves frozen; apertures scaled\n");
    sg_system_free(h);
    sg_system_free(s);
}

/* A material its catalog marks to ignore thermal expansion (the ED line's
 * fifth field, a liquid's or gas's) expands with its surface's tce, as the
 * OpticStudio help's TCE topic says; the same glass unmarked keeps its ED
 * figure. */
static void test_ignore_expansion(void **state)
{
    static const char agf[] =
        "CC test catalog\n"
        "NM LIQ 2 517642 1.5168 64.17 0 1\n"
        "ED 7.1 8.3 2.51 -0.0009 1\n"
        "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0\n"
        "LD 0.3 2.5\n"
        "NM SOLID 2 517642 1.5168 64.17 0 1\n"
        "ED 7.1 8.3 2.51 -0.0009 0\n"
        "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653 0 0 0 0\n"
        "LD 0.3 2.5\n";
    char path[] = "/tmp/sg-thermal-XXXXXX";
    sg_catalog *c = sg_catalog_new();
    sg_system *s = singlet(50.0, -50.0, 4.0, 0.0, 90.0, 0.0);
    sg_thermal_tce t[4];
    sg_diag d;
    int fd = mkstemp(path);
    FILE *f;
    (void)state;
    assert_true(fd >= 0 && c);
    f = fdopen(fd, "w");
    assert_non_null(f);
    fputs(agf, f);
    fclose(f);
    sg_diag_clear(&d);
    assert_int_equal(sg_catalog_load_agf(c, path, &d), SG_OK);
    unlink(path);
    assert_true(sg_catalog_find(c, "LIQ")->ignore_expansion == 1);
    assert_true(sg_catalog_find(c, "SOLID")->ignore_expansion == 0);
    s->surf[1].tce = 300.0;
    snprintf(s->surf[1].mat.name, SG_GLASS_NAME, "LIQ");
    sg_diag_clear(&d);
    assert_int_equal(sg_thermal_tces(s, c, t, &d), SG_OK);
    assert_true(t[1].shape == 300.0 && t[1].space == 300.0 && t[2].shape == 300.0);
    snprintf(s->surf[1].mat.name, SG_GLASS_NAME, "SOLID");
    assert_int_equal(sg_thermal_tces(s, c, t, &d), SG_OK);
    assert_true(t[1].shape == 7.1 && t[1].space == 7.1 && t[2].shape == 7.1);
    sg_system_free(s);
    sg_catalog_free(c);
}

static void expect_refusal(const sg_system *s, double temp, double pres, int code,
                           const char *want)
{
    sg_system *out = sg_system_new(), *before;
    sg_diag d;
    int rc;
    assert_non_null(out);
    before = sg_system_clone(out);
    sg_diag_clear(&d);
    rc = sg_thermal(s, cat, temp, pres, out, &d);
    if (rc != code || !strstr(d.msg, want))
        fail_msg("expected %s with \"%s\", got %s: %s", sg_err_name(code), want,
                 sg_err_name(rc), d.msg);
    /* out is left as it was. */
    assert_true(sg_system_equal(out, before));
    sg_system_free(before);
    sg_system_free(out);
}

/* Bad input is refused with the field or surface named. */
static void test_refusals(void **state)
{
    static const char json[] = "{\"surfaces\": [{}, {\"stop\": true, \"tce\": 1000.5}, {}]}";
    sg_system *s = singlet(50.0, -50.0, 4.0, 10.0, 90.0, 23.6);
    sg_diag d;
    (void)state;
    expect_refusal(s, 1000.5, 1.0, SG_ERANGE, "temperature: 1000.5 C is outside -250 to 1000");
    expect_refusal(s, NAN, 1.0, SG_ERANGE, "temperature");
    expect_refusal(s, 40.0, -0.5, SG_ERANGE, "pressure: -0.5 atm is outside 0 to 100");
    snprintf(s->surf[1].mat.name, SG_GLASS_NAME, "NO-SUCH-GLASS");
    expect_refusal(s, 40.0, 1.0, SG_ENOGLASS, "surface 1: material \"NO-SUCH-GLASS\"");
    snprintf(s->surf[1].mat.name, SG_GLASS_NAME, "N-BK7");
    /* An expansion factor of 1 - 1000e-6 x 1250 < 0. */
    s->temperature = -250.0;
    s->surf[2].tce = -1000.0;
    expect_refusal(s, 1000.0, 1.0, SG_ERANGE, "surface 2: the expansion factor");
    s->temperature = 20.0;
    s->surf[2].tce = 23.6;
    /* A spacer touching a sphere beyond its radius. */
    s->surf[2].radius = -8.0;
    expect_refusal(s, 40.0, 1.0, SG_ERANGE, "surface 2: no sag at the spacer's contact");
    sg_system_free(s);
    /* A TCE beyond its limit: the file loads, validation names it. */
    s = sg_system_new();
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(s, json, strlen(json), "t.json", &d), SG_OK);
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(s, cat, &d), SG_ERANGE);
    assert_string_equal(d.msg, "surface 1: TCE 1000.5 is beyond 1000");
    expect_refusal(s, 40.0, 1.0, SG_ERANGE, "surface 1: TCE 1000.5 is beyond 1000");
    sg_system_free(s);
}

/* tce in JSON: written only when not 0, read back bit for bit; a design
 * at its temperature round-trips too. */
static void test_json(void **state)
{
    sg_system *s = singlet(50.0, -50.0, 4.0, 10.0, 90.0, 23.6), *b = sg_system_new(), *h;
    char *text;
    sg_diag d;
    (void)state;
    text = sg_design_to_json(s);
    assert_non_null(text);
    assert_non_null(strstr(text, "\"tce\": 23.6"));
    assert_non_null(strstr(text, "\"version\": 3"));
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(b, text, strlen(text), "t.json", &d), SG_OK);
    assert_true(sg_system_equal(s, b));
    free(text);
    s->surf[2].tce = 0.0;
    text = sg_design_to_json(s);
    assert_null(strstr(text, "tce"));
    assert_non_null(strstr(text, "\"version\": 1"));
    free(text);
    s->surf[2].tce = 11.5;
    h = hot_of(s, -30.0, 0.8);
    text = sg_design_to_json(h);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(b, text, strlen(text), "t.json", &d), SG_OK);
    assert_true(sg_system_equal(h, b));
    free(text);
    sg_system_free(h);
    sg_system_free(b);
    sg_system_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_singlet),
        cmocka_unit_test(test_thin_lens_defocus),
        cmocka_unit_test(test_asphere_mpfr),
        cmocka_unit_test(test_zemax_forum_example),
        cmocka_unit_test(test_shapes_scale),
        cmocka_unit_test(test_rules),
        cmocka_unit_test(test_ignore_expansion),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_json),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
