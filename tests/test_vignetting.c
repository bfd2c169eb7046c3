/*
 * test_vignetting.c - Zemax's vignetting factors (VDX, VDY, VCX, VCY, VAN)
 * on fields, in all three methods and the batch.
 *
 * The truth is the closed form, evaluated here in long double: a field's
 * pupil point (px, py) is traced at
 *   a = px (1 - VCX), b = py (1 - VCY),
 *   px' = VDX + a cos(VAN) - b sin(VAN), py' = VDY + a sin(VAN) + b cos(VAN).
 * The system is a flat stop on surface 1 with the object at infinity and
 * EPD 20, so the entrance pupil is surface 1 itself and a ray aimed at pupil
 * point (px', py') crosses surface 1 at (10 px', 10 py') for every field.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};
static const char *const method_names[] = {"precise", "classic", "mpfr"};

static sg_system *vig_system(sg_aim aim)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].thickness = 5.0;
    sys->surf[2].radius = 40.0;
    sys->surf[2].thickness = 30.0;
    sys->surf[2].mat.kind = SG_MAT_INDEX;
    sys->surf[2].mat.index = 1.5;
    sys->stop = 1;
    sys->aper_value = 20.0;
    sys->aim = aim;
    sys->field_type = SG_FIELD_ANGLE;
    sys->nfield = 3;
    sys->field[0] = (sg_field){0.0, 0.0, 1.0, 0.1, -0.2, 0.25, 0.5, 30.0};
    sys->field[1] = (sg_field){0.0, 5.0, 1.0, 0.0, 0.3, 0.4, 0.0, 0.0};
    sys->field[2] = (sg_field){3.0, 10.0, 1.0, -0.125, 0.0, 0.0, 0.2, 90.0};
    sg_diag_clear(&d);
    assert_int_equal(sg_system_validate(sys, NULL, &d), SG_OK);
    return sys;
}

/* The closed form in long double. */
static void truth(const sg_field *f, double px, double py, long double *x, long double *y)
{
    const long double pi = 3.141592653589793238462643383279502884L;
    long double a = (long double)px * (1.0L - f->vcx), b = (long double)py * (1.0L - f->vcy);
    long double th = (long double)f->van * pi / 180.0L;
    long double c = cosl(th), s = sinl(th);
    if (f->van == 90.0) {
        c = 0.0L;
        s = 1.0L;
    }
    *x = f->vdx + a * c - b * s;
    *y = f->vdy + a * s + b * c;
}

static const double pupils[][2] = {
    {0.0, 0.0}, {1.0, 0.0}, {0.0, 1.0}, {-1.0, 0.0}, {0.0, -1.0},
    {0.6, 0.7}, {-0.3, 0.9}, {0.25, -0.5}, {-0.7071, -0.7071},
};
#define NPUP ((int)(sizeof pupils / sizeof pupils[0]))

static double worst_err;

static void check_point(const sg_ray_surface *row, const sg_field *f, double px, double py,
                        const char *what)
{
    long double x, y;
    double ex, ey;
    truth(f, px, py, &x, &y);
    ex = fabs((double)(row->x - 10.0L * x));
    ey = fabs((double)(row->y - 10.0L * y));
    if (ex > worst_err)
        worst_err = ex;
    if (ey > worst_err)
        worst_err = ey;
    /* The launch's own roundings, a few ulp of the 10 mm pupil. */
    if (ex > 1e-14 || ey > 1e-14)
        fail_msg("%s: pupil (%g, %g) at surface 1 (%.17g, %.17g), closed form (%.17Lg, %.17Lg)",
                 what, px, py, row->x, row->y, 10.0L * x, 10.0L * y);
}

static void run_methods(sg_aim aim)
{
    sg_system *sys = vig_system(aim);
    sg_ray_surface out[4];
    int m, f, i;
    char what[96];
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, NULL, methods[m]);
        for (f = 0; f < sys->nfield; f++) {
            double hx, hy;
            assert_int_equal(sg_field_normalized(sys, f, &hx, &hy), SG_OK);
            for (i = 0; i < NPUP; i++) {
                int rc = sg_trace_normalized(t, hx, hy, pupils[i][0], pupils[i][1], out);
                snprintf(what, sizeof what, "%s, aim %d, field %d", method_names[m], (int)aim,
                         f + 1);
                if (rc != SG_OK)
                    fail_msg("%s: %s", what, sg_err_name(rc));
                check_point(&out[1], &sys->field[f], pupils[i][0], pupils[i][1], what);
            }
        }
        /* A point between the fields has no factors of its own. */
        {
            sg_field none = {0};
            assert_int_equal(sg_trace_normalized(t, 0.0, 0.25, 0.6, 0.7, out), SG_OK);
            check_point(&out[1], &none, 0.6, 0.7, "between fields");
        }
        sg_tracer_free(t);
    }
    sg_system_free(sys);
}

static void test_single_rays(void **state)
{
    (void)state;
    worst_err = 0.0;
    run_methods(SG_AIM_OFF);
    run_methods(SG_AIM_REAL);
    print_message("# 3 fields x %d pupil points x 3 methods, aiming off and real: surface 1 "
                  "within %.3g mm of 10 (px', py') of the closed form\n", NPUP, worst_err);
}

/* The batch's blocks move the pupil points as single rays do, bit for bit. */
static void test_batch(void **state)
{
    sg_system *sys = vig_system(SG_AIM_OFF);
    int nray = sys->nfield * NPUP, f, i, r = 0;
    sg_ray_in *rays = calloc((size_t)nray, sizeof *rays);
    sg_ray_surface *out = calloc((size_t)nray * 4, sizeof *out), one[4];
    int *status = calloc((size_t)nray, sizeof *status);
    sg_trace_opts o;
    sg_tracer *t = tu_tracer(sys, NULL, SG_METHOD_PRECISE);
    sg_diag d;
    (void)state;
    assert_true(rays && out && status);
    for (f = 0; f < sys->nfield; f++)
        for (i = 0; i < NPUP; i++, r++) {
            assert_int_equal(sg_field_normalized(sys, f, &rays[r].v[0], &rays[r].v[1]), SG_OK);
            rays[r].v[2] = pupils[i][0];
            rays[r].v[3] = pupils[i][1];
        }
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    assert_int_equal(sg_trace_batch(sys, NULL, &o, SG_RAYS_NORMALIZED, rays, (size_t)nray, 2,
                                    out, status, &d),
                     SG_OK);
    for (r = 0; r < nray; r++) {
        assert_int_equal(status[r], SG_OK);
        check_point(&out[(size_t)r * 4 + 1], &sys->field[r / NPUP], rays[r].v[2], rays[r].v[3],
                    "batch");
        assert_int_equal(sg_trace_normalized(t, rays[r].v[0], rays[r].v[1], rays[r].v[2],
                                             rays[r].v[3], one),
                         SG_OK);
        assert_true(tu_same_row(&one[3], &out[(size_t)r * 4 + 3]));
    }
    sg_tracer_free(t);
    free(rays);
    free(out);
    free(status);
    sg_system_free(sys);
}

/* The factors are read and written as field keys of format version 2. */
static void test_json(void **state)
{
    sg_system *sys = vig_system(SG_AIM_OFF), *back = sg_system_new();
    char *json = sg_design_to_json(sys);
    sg_diag d;
    (void)state;
    assert_non_null(json);
    assert_non_null(strstr(json, "\"version\": 2,"));
    assert_non_null(strstr(json, "{ \"x\": 0, \"y\": 0, \"weight\": 1, \"vdx\": 0.1, "
                                 "\"vdy\": -0.2, \"vcx\": 0.25, \"vcy\": 0.5, \"van\": 30 }"));
    /* Factors at zero are not written. */
    assert_non_null(strstr(json, "{ \"x\": 0, \"y\": 5, \"weight\": 1, \"vdy\": 0.3, "
                                 "\"vcx\": 0.4 }"));
    sg_diag_clear(&d);
    assert_int_equal(sg_design_parse(back, json, strlen(json), "back", &d), SG_OK);
    assert_true(sg_system_equal(sys, back));
    free(json);
    /* The .zmx writer writes VDXN ... VANN, and the reader takes every
     * field's factors back unchanged. */
    {
        char *z;
        int k;
        sg_diag_clear(&d);
        z = sg_zmx_to_text(sys, NULL, &d);
        assert_non_null(z);
        assert_non_null(strstr(z, "VCXN "));
        sg_diag_clear(&d);
        assert_int_equal(sg_zmx_parse(back, z, strlen(z), "back.zmx", NULL, &d), SG_OK);
        assert_int_equal(back->nfield, sys->nfield);
        for (k = 0; k < sys->nfield; k++)
            assert_true(back->field[k].vdx == sys->field[k].vdx &&
                        back->field[k].vdy == sys->field[k].vdy &&
                        back->field[k].vcx == sys->field[k].vcx &&
                        back->field[k].vcy == sys->field[k].vcy &&
                        back->field[k].van == sys->field[k].van);
        free(z);
    }
    /* A bad factor names the field and the key. */
    {
        static const char bad[] = "{\"fields\": {\"list\": [{\"y\": 1, \"vcx\": \"x\"}]},"
                                  " \"surfaces\": [{}, {\"stop\": true}, {}]}";
        sg_diag_clear(&d);
        assert_int_not_equal(sg_design_parse(back, bad, strlen(bad), "t.json", &d), SG_OK);
        assert_non_null(strstr(d.msg, "t.json: fields: list[0].vcx: expected a number"));
    }
    sys->field[1].vcy = 2e6;
    sg_diag_clear(&d);
    assert_int_not_equal(sg_system_validate(sys, NULL, &d), SG_OK);
    assert_non_null(strstr(d.msg, "field 2: vignetting compression y 2e+06 is beyond 1e+06"));
    sg_system_free(sys);
    sg_system_free(back);
}

/* Set Vignetting (sg_set_vignetting) against the closed form.  The stop is
 * flat on surface 1 (object at infinity, EPD 10, so the pupil is surface 1
 * itself), and a flat surface L = 20 behind it has a fixed semi-diameter
 * A.  A ray of field angle t through pupil point (px, py) meets it at
 * (5 px, 5 py + L tan t): the pupil that passes is the disc of radius A/5
 * about (0, -L tan t / 5).  Inside the unit pupil, its top and bottom are
 * that centre plus and minus A/5, and along the horizontal line through
 * the centroid y = cy the function reports, its half-width is
 * sqrt((A/5)^2 - (cy - c0)^2); the factors follow from the edges. */
static void test_set_vignetting(void **state)
{
    const long double pi = 3.141592653589793238462643383279502884L;
    const double L = 20.0, R = 5.0;
    sg_catalog *cat = tu_catalog();
    size_t m;
    (void)state;
    for (m = 0; m < sizeof methods / sizeof *methods; m++) {
        int big;
        for (big = 0; big < 2; big++) {
            sg_system *sys = sg_system_new();
            sg_setvig_opts o;
            sg_vigfactors vf[2];
            double A = big ? 7.0 : 2.0;
            sg_diag d;
            int f;
            assert_int_equal(sg_system_reset(sys, 4), SG_OK);
            sys->surf[0].thickness = INFINITY;
            sys->surf[1].thickness = L;
            sys->surf[2].thickness = 10.0;
            sys->surf[2].semi_diameter = A;
            sys->surf[2].sd_fixed = 1;
            sys->stop = 1;
            sys->aper_value = 2.0 * R;
            sys->field_type = SG_FIELD_ANGLE;
            sys->nfield = 2;
            sys->field[0] = (sg_field){0.0, 0.0, 1.0, 0.3, 0.1, 0.2, 0.1, 10.0};
            sys->field[1] = (sg_field){0.0, (double)(atanl(0.075L) * 180.0L / pi), 1.0, 0, 0, 0, 0, 0};
            sg_setvig_opts_init(&o);
            o.trace.method = methods[m];
            sg_diag_clear(&d);
            if (sg_set_vignetting(sys, cat, &o, vf, &d) != SG_OK)
                fail_msg("%s: %s", method_names[m], d.msg);
            for (f = 0; f < 2; f++) {
                long double t = (long double)sys->field[f].y * pi / 180.0L;
                long double c0 = -(long double)L * tanl(t) / R, a = (long double)A / R;
                long double half = sqrtl(a * a - ((long double)vf[f].cy - c0) * ((long double)vf[f].cy - c0));
                double tol = 2e-9;
                if (big) {
                    /* A 7 mm aperture clears the whole pupil (1.5 + 5 < 7):
                     * no factor, exactly. */
                    assert_true(vf[f].vdx == 0.0 && vf[f].vdy == 0.0 && vf[f].vcx == 0.0 &&
                                vf[f].vcy == 0.0 && vf[f].van == 0.0);
                    continue;
                }
                if (fabsl(vf[f].cy - c0) > 0.01 || fabs(vf[f].cx) > 1e-15)
                    fail_msg("%s field %d: centroid (%g, %g), disc centre (0, %Lg)",
                             method_names[m], f + 1, vf[f].cx, vf[f].cy, c0);
                if (fabsl(vf[f].vdy - c0) > tol || fabsl(vf[f].vcy - (1.0L - a)) > tol ||
                    fabs(vf[f].vdx) > tol || fabsl(vf[f].vcx - (1.0L - half)) > tol)
                    fail_msg("%s field %d: VDX %.12g VDY %.12g VCX %.12g VCY %.12g; closed form "
                             "0 %.12Lg %.12Lg %.12Lg", method_names[m], f + 1, vf[f].vdx,
                             vf[f].vdy, vf[f].vcx, vf[f].vcy, c0, 1.0L - half, 1.0L - a);
                /* The factors found, set on the field, put its four edge rays
                 * on the aperture's rim. */
                sys->field[f].vdx = vf[f].vdx;
                sys->field[f].vdy = vf[f].vdy;
                sys->field[f].vcx = vf[f].vcx;
                sys->field[f].vcy = vf[f].vcy;
                sys->field[f].van = 0.0;
            }
            if (!big) {
                sg_trace_opts to;
                sg_tracer *t;
                sg_ray_surface row[4];
                sg_trace_opts_init(&to);
                to.method = methods[m];
                to.clip = 0;
                t = sg_tracer_new(sys, cat, &to, &d);
                assert_non_null(t);
                for (f = 0; f < 2; f++) {
                    double hx, hy, e[4][2] = {{0, 1}, {0, -1}, {1, 0}, {-1, 0}};
                    int k;
                    sg_field_normalized(sys, f, &hx, &hy);
                    for (k = 0; k < 4; k++) {
                        double r;
                        assert_int_equal(sg_trace_normalized(t, hx, hy, e[k][0], e[k][1], row), SG_OK);
                        r = hypot(row[2].x, row[2].y);
                        if (fabs(r - A) > 1e-8 * A && !(k >= 2 && r < A))
                            fail_msg("%s field %d edge ray %d meets the aperture at radius %.12g, "
                                     "not %g", method_names[m], f + 1, k, r, A);
                    }
                }
                sg_tracer_free(t);
            }
            sg_system_free(sys);
        }
    }
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_single_rays),
        cmocka_unit_test(test_batch),
        cmocka_unit_test(test_json),
        cmocka_unit_test(test_set_vignetting),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
