/*
 * test_telecentric.c - object-space telecentric systems (issue 16): the
 * entrance pupil at infinity, chief rays parallel to the axis, the
 * aperture an object NA.
 *
 * The system: an object 300 mm in front of a concave paraboloid of radius
 * 200 (focal length f = 100), with the stop in its focal plane.  Every ray
 * parallel to a paraboloid's axis passes through its focus, so each
 * field's chief ray must cross the stop at its centre exactly: a closed
 * form for all three methods.  The paraxial marginal ray leaves the axial
 * object point at slope u = tan(asin(NA)) and meets the focal plane at
 * height u f (1/s + 1/s' = 1/f with s = 300), the stop radius.  The launch
 * directions are checked against MPFR at 256 bits.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gmp.h>
#include <mpfr.h>

#include "testutil.h"

#define NA 0.1
#define F 100.0

static sg_system *paraboloid(int telecentric)
{
    sg_system *s = sg_system_new();
    assert_non_null(s);
    assert_int_equal(sg_system_reset(s, 4), SG_OK);
    s->surf[0].thickness = 300.0;
    s->surf[1].radius = -2.0 * F;
    s->surf[1].conic = -1.0;
    s->surf[1].mat.kind = SG_MAT_MIRROR;
    s->surf[1].thickness = -F;
    s->surf[2].thickness = -50.0; /* the image, 150 from the mirror */
    s->stop = 2;
    s->aper_type = SG_APER_OBJECT_NA;
    s->aper_value = NA;
    s->field_type = SG_FIELD_OBJECT_HEIGHT;
    s->nfield = 3;
    s->field[0].y = 0.0;
    s->field[1].y = 5.0;
    s->field[2].x = 3.0;
    s->field[2].y = 10.0;
    s->field[1].weight = s->field[2].weight = 1.0;
    s->telecentric = telecentric;
    return s;
}

/* The paraxial data: the pupil at infinity, the object NA as given, the
 * stop radius u f, the magnification -s'/s = -0.5. */
static void test_paraxial(void **state)
{
    sg_system *s = paraboloid(1), *n = paraboloid(0);
    sg_catalog *cat = tu_catalog();
    sg_paraxial p;
    sg_diag d;
    double u = tan(asin(NA));
    (void)state;
    sg_diag_clear(&d);
    if (sg_paraxial_compute(s, cat, -1, &p, &d) != SG_OK)
        fail_msg("%s", d.msg);
    print_message("# enp %g, epd %g, NA %.17g, stop radius %.17g (u f %.17g), m %.17g\n",
                  p.enp_pos, p.epd, p.object_na, p.stop_radius, u * F, p.magnification);
    assert_true(isinf(p.enp_pos) && isinf(p.epd));
    assert_true(fabs(p.object_na - NA) <= 2e-16);
    assert_true(fabs(p.stop_radius - u * F) <= 4e-16 * u * F);
    assert_true(fabs(p.magnification + 0.5) <= 4e-16);
    /* The exit pupil, the image of a pupil at infinity, is the focal plane:
     * the stop, 50 before the image, of the stop's diameter; the largest
     * field, sqrt(109) high, is imaged at m times that. */
    print_message("# exit pupil %.17g from the image, diameter %.17g; image height %.17g\n",
                  p.exp_pos, p.exp_diam, p.parax_image_height);
    assert_true(fabs(p.exp_pos - 50.0) <= 1e-13);
    assert_true(fabs(p.exp_diam - 2.0 * u * F) <= 1e-14 * u * F);
    assert_true(fabs(p.parax_image_height + 0.5 * sqrt(109.0)) <= 1e-14);
    /* The image-space slope is u / |m| = 2 u: working F/# 1 / (4 u). */
    assert_true(fabs(p.working_fnum - 1.0 / (4.0 * u)) <= 1e-14 * p.working_fnum);
    /* Without the flag the same system has its entrance pupil at
     * infinity too, which only the telecentric setting can launch. */
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(n, cat, -1, &p, &d), SG_ENONPHYS);
    assert_non_null(strstr(d.msg, "entrance pupil is at infinity"));
    sg_system_free(s);
    sg_system_free(n);
    sg_catalog_free(cat);
}

/* Every field's chief ray leaves the object parallel to the axis and
 * crosses the stop at the paraboloid's focus; every ray leaves its object
 * point in the direction (Px t, Py t, 1) / |...|, t = tan(asin(NA)). */
static void test_rays(void **state)
{
    sg_system *s = paraboloid(1);
    sg_catalog *cat = tu_catalog();
    static const double pupil[][2] = {{0, 0}, {0, 1}, {1, 0}, {0.6, -0.8}, {-0.3, 0.5},
                                      {0.25, 0.125}, {-1, 0}};
    mpfr_t t, a, b, c;
    int m, f, k;
    double worst_stop[3] = {0, 0, 0}, worst_dir = 0.0;
    (void)state;
    mpfr_inits2(256, t, a, b, c, (mpfr_ptr)0);
    mpfr_set_d(t, NA, MPFR_RNDN);
    mpfr_asin(t, t, MPFR_RNDN);
    mpfr_tan(t, t, MPFR_RNDN);
    for (m = 0; m < 3; m++) {
        sg_tracer *tr = tu_tracer(s, cat, (sg_method)m);
        sg_ray_surface o[4];
        for (f = 0; f <= 4; f++) {
            double hx = f == 4 ? 1.0 : 0.0, hy = f / 4.0;
            for (k = 0; k < (int)(sizeof pupil / sizeof *pupil); k++) {
                double px = pupil[k][0], py = pupil[k][1], want[3], e;
                int j;
                if (sg_trace_normalized(tr, hx, hy, px, py, o) != SG_OK)
                    fail_msg("method %d field (%g, %g) pupil (%g, %g): %s", m, hx, hy, px, py,
                             sg_strerror(o[3].status));
                /* The object point: the field's height (the radial scale
                 * is the largest field's radius, sqrt(109)). */
                assert_true(fabs(o[0].x - hx * sqrt(109.0)) <= 2e-15 &&
                            fabs(o[0].y - hy * sqrt(109.0)) <= 2e-15 && o[0].z == 0.0);
                /* The direction from MPFR: (Px t, Py t, 1) normalized. */
                mpfr_mul_d(a, t, px, MPFR_RNDN);
                mpfr_mul_d(b, t, py, MPFR_RNDN);
                mpfr_sqr(c, a, MPFR_RNDN);
                mpfr_fma(c, b, b, c, MPFR_RNDN);
                mpfr_add_ui(c, c, 1, MPFR_RNDN);
                mpfr_rec_sqrt(c, c, MPFR_RNDN);
                mpfr_mul(a, a, c, MPFR_RNDN);
                mpfr_mul(b, b, c, MPFR_RNDN);
                want[0] = mpfr_get_d(a, MPFR_RNDN);
                want[1] = mpfr_get_d(b, MPFR_RNDN);
                want[2] = mpfr_get_d(c, MPFR_RNDN);
                e = fmax(fabs(o[0].l - want[0]), fmax(fabs(o[0].m - want[1]),
                                                      fabs(o[0].n - want[2])));
                worst_dir = fmax(worst_dir, e);
                if (e > 4e-16)
                    fail_msg("method %d pupil (%g, %g): direction (%.17g, %.17g, %.17g), want "
                             "(%.17g, %.17g, %.17g)", m, px, py, o[0].l, o[0].m, o[0].n,
                             want[0], want[1], want[2]);
                /* A marginal ray leaves at the object NA. */
                if (px * px + py * py == 1.0)
                    assert_true(fabs(hypot(o[0].l, o[0].m) - NA) <= 4e-16);
                if (px == 0.0 && py == 0.0) {
                    /* The chief ray: parallel to the axis, through the
                     * focus, within the method's bound. */
                    e = fmax(fabs(o[2].x), fabs(o[2].y));
                    worst_stop[m] = fmax(worst_stop[m], e);
                    assert_true(o[0].l == 0.0 && o[0].m == 0.0 && o[0].n == 1.0);
                    if (m != SG_METHOD_CLASSIC && e > o[2].error_bound)
                        fail_msg("method %d field %d: chief ray at (%.3g, %.3g) on the stop, "
                                 "bound %.3g", m, f, o[2].x, o[2].y, o[2].error_bound);
                    assert_true(e < 1e-12);
                }
                for (j = 1; j < 4; j++)
                    assert_int_equal(o[j].status, SG_OK);
            }
        }
        sg_tracer_free(tr);
    }
    print_message("# chief rays at the focus: worst %.3g precise, %.3g classic, %.3g mpfr; "
                  "launch directions within %.3g of MPFR\n",
                  worst_stop[0], worst_stop[1], worst_stop[2], worst_dir);
    mpfr_clears(t, a, b, c, (mpfr_ptr)0);
    sg_system_free(s);
    sg_catalog_free(cat);
}

/* The batch (lanes of one field at once) gives the single-ray results
 * bit for bit, as for every other system. */
static void test_batch(void **state)
{
    sg_system *s = paraboloid(1);
    sg_catalog *cat = tu_catalog();
    sg_trace_opts o;
    sg_ray_in in[40];
    sg_ray_surface *out = calloc(40 * 4, sizeof *out), one[4];
    int st[40], k, m;
    sg_diag d;
    (void)state;
    for (k = 0; k < 40; k++) {
        in[k].v[0] = 0.0;
        in[k].v[1] = (k / 10) / 3.0;
        in[k].v[2] = cos(0.7 * k) * (k % 10) / 9.0;
        in[k].v[3] = sin(0.7 * k) * (k % 10) / 9.0;
    }
    for (m = 0; m < 2; m++) {
        sg_tracer *t = tu_tracer(s, cat, (sg_method)m);
        sg_trace_opts_init(&o);
        o.method = (sg_method)m;
        sg_diag_clear(&d);
        if (sg_trace_batch(s, cat, &o, SG_RAYS_NORMALIZED, in, 40, 2, out, st, &d) != SG_OK)
            fail_msg("%s", d.msg);
        for (k = 0; k < 40; k++) {
            int j;
            assert_int_equal(sg_trace_normalized(t, in[k].v[0], in[k].v[1], in[k].v[2],
                                                 in[k].v[3], one), st[k]);
            for (j = 0; j < 4; j++)
                if (!tu_same_row(&one[j], &out[k * 4 + j]))
                    fail_msg("method %d ray %d surface %d: batch and single ray differ", m, k, j);
        }
        sg_tracer_free(t);
    }
    free(out);
    sg_system_free(s);
    sg_catalog_free(cat);
}

/* Zemax's object cone angle (OBNA v 1): the half angle of the axial object
 * point's cone, in degrees.  The marginal ray leaves at exactly that angle
 * (checked in MPFR), telecentric or not, and the paraxial object NA is its
 * sine; the aperture reads from and goes back to .zmx and JSON as written. */
static void test_cone_angle(void **state)
{
    static const char zmx[] = "MODE SEQ\nOBNA 6 1\nFTYP 1 1 1 1 0 0 0\nXFLN 0\nYFLN 0\nWAVM 1 0.55 1\n"
                              "PWAV 1\nSURF 0\n  DISZ 300\nSURF 1\n  STOP\n  DISZ 10\nSURF 2\n";
    sg_catalog *cat = tu_catalog();
    mpfr_t a, pi;
    double sn, tn;
    int tele;
    sg_diag d;
    (void)state;
    mpfr_inits2(256, a, pi, (mpfr_ptr)0);
    mpfr_const_pi(pi, MPFR_RNDN);
    mpfr_mul_ui(a, pi, 6, MPFR_RNDN);
    mpfr_div_ui(a, a, 180, MPFR_RNDN);
    mpfr_sin(pi, a, MPFR_RNDN);
    sn = mpfr_get_d(pi, MPFR_RNDN);
    mpfr_tan(pi, a, MPFR_RNDN);
    tn = mpfr_get_d(pi, MPFR_RNDN);
    for (tele = 0; tele < 2; tele++) {
        sg_system *s = paraboloid(tele);
        sg_paraxial p;
        sg_ray_surface o[4];
        sg_tracer *t;
        int m;
        s->aper_type = SG_APER_OBJECT_CONE;
        s->aper_value = 6.0;
        if (!tele)
            s->stop = 1; /* the pupil on the mirror, at a finite place */
        sg_diag_clear(&d);
        if (sg_paraxial_compute(s, cat, -1, &p, &d) != SG_OK)
            fail_msg("%s", d.msg);
        assert_true(fabs(p.object_na - sn) <= 2e-16);
        if (tele)
            assert_true(fabs(p.stop_radius - tn * F) <= 4e-16 * F);
        for (m = 0; m < 3; m++) {
            t = tu_tracer(s, cat, (sg_method)m);
            assert_int_equal(sg_trace_normalized(t, 0, 0, 0, 1, o), SG_OK);
            print_message("# cone 6 degrees, %s, method %d: marginal direction m %.17g "
                          "(sin 6 = %.17g)\n", tele ? "telecentric" : "pupil on the mirror", m,
                          o[0].m, sn);
            assert_true(fabs(o[0].m - sn) <= 4e-16 && o[0].l == 0.0);
            sg_tracer_free(t);
        }
        sg_system_free(s);
    }
    {
        sg_system *s = sg_system_new(), *b = sg_system_new();
        char *z, *j;
        sg_diag_clear(&d);
        if (sg_zmx_parse(s, zmx, strlen(zmx), "cone.zmx", cat, &d) != SG_OK)
            fail_msg("%s", d.msg);
        assert_int_equal(s->aper_type, SG_APER_OBJECT_CONE);
        assert_true(s->aper_value == 6.0 && s->telecentric == 1);
        z = sg_zmx_to_text(s, cat, &d);
        assert_non_null(z);
        assert_non_null(strstr(z, "OBNA 6 1\n"));
        assert_non_null(strstr(z, "FTYP 1 1 1 1 0 0 0\n"));
        free(z);
        j = sg_design_to_json(s);
        assert_non_null(strstr(j, "\"object_cone_angle\""));
        assert_non_null(strstr(j, "\"version\": 3"));
        sg_diag_clear(&d);
        assert_int_equal(sg_design_parse(b, j, strlen(j), "cone.json", &d), SG_OK);
        assert_true(sg_system_equal(s, b));
        free(j);
        s->aper_value = 90.0;
        sg_diag_clear(&d);
        assert_int_equal(sg_system_validate(s, NULL, &d), SG_ERANGE);
        assert_non_null(strstr(d.msg, "object cone angle 90 must be below 90 degrees"));
        sg_system_free(s);
        sg_system_free(b);
    }
    mpfr_clears(a, pi, (mpfr_ptr)0);
    sg_catalog_free(cat);
}

/* What Zemax refuses with telecentric object space is refused: an aperture
 * other than the object NA, angle fields, an object at infinity; the flag
 * goes out to JSON (format version 3) and back. */
static void test_rules(void **state)
{
    sg_system *s = paraboloid(1), *b = sg_system_new();
    sg_diag d;
    char *j;
    (void)state;
    s->aper_type = SG_APER_EPD;
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(s, NULL, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "its aperture is an object NA or cone angle, not an entrance pupil"));
    s->aper_type = SG_APER_OBJECT_NA;
    s->field_type = SG_FIELD_ANGLE;
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(s, NULL, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "heights, not angles"));
    s->field_type = SG_FIELD_OBJECT_HEIGHT;
    s->surf[0].thickness = INFINITY;
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(s, NULL, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "an object at a finite distance"));
    s->surf[0].thickness = 300.0;
    {
        /* Ray aiming does not apply: the rays are fixed in object space. */
        sg_catalog *cat = tu_catalog();
        sg_ray_surface r0[4], r1[4];
        sg_tracer *t0 = tu_tracer(s, cat, SG_METHOD_PRECISE), *t1;
        int k;
        s->aim = SG_AIM_REAL;
        t1 = tu_tracer(s, cat, SG_METHOD_PRECISE);
        assert_int_equal(sg_trace_normalized(t0, 0, 1, 0.5, -0.5, r0), SG_OK);
        assert_int_equal(sg_trace_normalized(t1, 0, 1, 0.5, -0.5, r1), SG_OK);
        for (k = 0; k < 4; k++)
            assert_true(tu_same_row(&r0[k], &r1[k]));
        s->aim = SG_AIM_OFF;
        sg_tracer_free(t0);
        sg_tracer_free(t1);
        sg_catalog_free(cat);
    }
    j = sg_design_to_json(s);
    assert_non_null(j);
    assert_non_null(strstr(j, "\"telecentric\": true"));
    assert_non_null(strstr(j, "\"version\": 3"));
    sg_diag_clear(&d);
    if (sg_design_parse(b, j, strlen(j), "t.json", &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_equal(b->telecentric, 1);
    assert_true(sg_system_equal(s, b));
    free(j);
    s->telecentric = 0;
    j = sg_design_to_json(s);
    assert_null(strstr(j, "telecentric"));
    free(j);
    sg_system_free(s);
    sg_system_free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_paraxial),
        cmocka_unit_test(test_rays),
        cmocka_unit_test(test_batch),
        cmocka_unit_test(test_cone_angle),
        cmocka_unit_test(test_rules),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
