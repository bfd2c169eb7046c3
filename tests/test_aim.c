/*
 * test_aim.c - ray aiming.  Real aiming must land (Px, Py) on (Px, Py)
 * times the stop radius; that target is the independent truth.  A system
 * no ray can aim through must say so.
 */
#include <math.h>

#include "testutil.h"

/* The Cassegrain aims for real onto its 1500 mm stop (the primary). */
static void stop_edge(void **state)
{
    static const double fields[][2] = {{0, 0}, {0, 0.5}, {0, 1}, {0.7, -0.7}, {-1, 0}};
    static const double pupils[][2] = {{0, 1}, {0, -1}, {1, 0}, {-1, 0}, {0.6, 0.8}, {0, 0}};
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cassegrain.json");
    sg_method methods[3] = {SG_METHOD_PRECISE, SG_METHOD_MPFR, SG_METHOD_CLASSIC};
    int m, f, p;
    (void)state;
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, cat, methods[m]);
        sg_ray_surface out[16];
        double worst = 0.0;
        for (f = 0; f < 5; f++)
            for (p = 0; p < 6; p++) {
                double tx = 1500.0 * pupils[p][0], ty = 1500.0 * pupils[p][1], e;
                int rc = sg_trace_normalized(t, fields[f][0], fields[f][1], pupils[p][0],
                                             pupils[p][1], out);
                assert_int_equal(rc, SG_OK);
                e = fmax(fabs(out[2].x - tx), fabs(out[2].y - ty)) / 1500.0;
                worst = fmax(worst, e);
            }
        print_message("# %s: worst stop landing error %.3g of the stop radius over 30 rays\n",
                      sg_method_name(methods[m]), worst);
        /* The 1e-12, for classic too: its aiming lands within
         * 2.3e-13 of the stop radius over these rays (measured). */
        assert_true(worst <= 1e-12);
        if (methods[m] != SG_METHOD_CLASSIC)
            assert_true(worst <= 2.3e-16);
        sg_tracer_free(t);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A paraboloid mirror as the stop behind a dummy plane, object at
 * infinity: the ray through a stop point is a straight line from infinity,
 * so aiming starts from where it lands.  Truths: each ray lands on its
 * target, (Px, Py) times the stop's 100 mm, correctly rounded; a
 * paraboloid images an axial point at infinity perfectly, so the on-axis
 * rays all meet its focus, 1000 mm in front of it, at (0, 0); and the
 * mpfr trace of the same system agrees within the precise bound. */
static void straight_to_stop(void **state)
{
    static const double pupils[][2] = {{0.6, 0.8}, {0.3, -0.2}, {-0.9, 0.1}, {0.5, 0.5},
                                       {0, 1}, {-0.25, 0}, {0.7071, -0.7071}};
    sg_system *sys = sg_system_new();
    sg_tracer *tp, *tm;
    sg_ray_surface op[4], om[4];
    double worst_focus = 0.0, worst_ratio = INFINITY;
    int f, p, i, n = 0;
    (void)state;
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].thickness = 300.0;
    sys->surf[2].radius = -2000.0;
    sys->surf[2].conic = -1.0;
    sys->surf[2].thickness = -1000.0;
    sys->surf[2].mat.kind = SG_MAT_MIRROR;
    sys->surf[2].semi_diameter = 100.0;
    sys->stop = 2;
    sys->field_type = SG_FIELD_ANGLE;
    sys->nfield = 2;
    sys->field[1].x = 0.0;
    sys->field[1].y = 0.5;
    sys->field[1].weight = 1.0;
    sys->aper_type = SG_APER_FLOAT_STOP;
    sys->aim = SG_AIM_REAL;
    tp = tu_tracer(sys, NULL, SG_METHOD_PRECISE);
    tm = tu_tracer(sys, NULL, SG_METHOD_MPFR);
    for (f = 0; f < 2; f++)
        for (p = 0; p < 7; p++) {
            double px = pupils[p][0], py = pupils[p][1];
            assert_int_equal(sg_trace_normalized(tp, 0, f, px, py, op), SG_OK);
            assert_int_equal(sg_trace_normalized(tm, 0, f, px, py, om), SG_OK);
            n++;
            /* 100 px in double is the exact target correctly rounded. */
            assert_true(op[2].x == 100.0 * px && op[2].y == 100.0 * py);
            if (f == 0) {
                worst_focus = fmax(worst_focus, fmax(fabs(op[3].x), fabs(op[3].y)));
                assert_true(fabs(op[3].x) <= op[3].error_bound);
                assert_true(fabs(op[3].y) <= op[3].error_bound);
            }
            for (i = 1; i < 4; i++) {
                double e = fmax(fabs(op[i].x - om[i].x),
                                fmax(fabs(op[i].y - om[i].y), fabs(op[i].z - om[i].z)));
                assert_true(e <= op[i].error_bound);
                if (e > 0.0)
                    worst_ratio = fmin(worst_ratio, op[i].error_bound / e);
            }
        }
    print_message("# paraboloid stop, object at infinity: %d aimed rays land on (Px, Py) x 100 "
                  "mm exactly rounded\n", n);
    print_message("# on axis, worst distance from the focus %.3g mm; smallest bound/error "
                  "against mpfr %.3g\n", worst_focus, worst_ratio);
    sg_tracer_free(tp);
    sg_tracer_free(tm);
    sg_system_free(sys);
}

/* A stop no marginal ray can reach: rays above about 3.3 mm in a glass
 * block are totally reflected at its curved exit face, but the stop's
 * semi-diameter asks for 20 mm. */
static void impossible(void **state)
{
    sg_system *sys = sg_system_new();
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    sg_ray_surface out[8];
    int rc, i;
    (void)state;
    assert_int_equal(sg_system_reset(sys, 5), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].thickness = 2.0;
    sys->surf[1].mat.kind = SG_MAT_INDEX;
    sys->surf[1].mat.index = 1.5;
    sys->surf[2].radius = -5.0;
    sys->surf[2].thickness = 3.0;
    sys->surf[3].thickness = 10.0;
    sys->surf[3].semi_diameter = 20.0;
    sys->stop = 3;
    sys->aper_type = SG_APER_FLOAT_STOP;
    sys->aim = SG_AIM_REAL;
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, NULL, &o, &d);
    assert_non_null(t);
    rc = sg_trace_normalized(t, 0, 0, 0, 1, out);
    print_message("# impossible stop: %s (%s)\n", sg_err_name(rc), sg_strerror(rc));
    assert_int_equal(rc, SG_EAIM);
    assert_int_equal(out[0].status, SG_EAIM);
    for (i = 1; i < sys->nsurf; i++)
        assert_int_equal(out[i].status, SG_ENOTREACHED);
    /* The chief ray still aims: the failure is the ray's, not the system's. */
    assert_int_equal(sg_trace_normalized(t, 0, 0, 0, 0, out), SG_OK);
    sg_tracer_free(t);
    sg_system_free(sys);
}

/* Paraxial aiming lands Py = 1 on the paraxial stop radius (the Cooke
 * triplet's stop sits between its lenses). */
static void paraxial_aiming(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_paraxial p;
    sg_diag d;
    sg_tracer *t;
    sg_ray_surface out[16];
    double worst = 0.0;
    int f;
    (void)state;
    sys->aim = SG_AIM_PARAXIAL;
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    for (f = 0; f <= 4; f++) {
        double hy = 0.25 * f;
        assert_int_equal(sg_trace_normalized(t, 0, hy, 0, 1, out), SG_OK);
        worst = fmax(worst, fabs(out[sys->stop].y - p.stop_radius) / p.stop_radius);
        assert_int_equal(sg_trace_normalized(t, 0, hy, -1, 0, out), SG_OK);
        worst = fmax(worst, fabs(out[sys->stop].x + p.stop_radius) / p.stop_radius);
    }
    print_message("# Cooke triplet, paraxial aiming: worst landing error %.3g of the paraxial "
                  "stop radius %.17g\n", worst, p.stop_radius);
    assert_true(worst <= 1e-12);
    sg_tracer_free(t);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A real-image-height field puts the chief ray on the requested height. */
static void real_image_height(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_tracer *t;
    sg_ray_surface out[16];
    int last = sys->nsurf - 1;
    (void)state;
    sys->field_type = SG_FIELD_REAL_IMAGE_HEIGHT;
    sys->field_norm = SG_NORM_RADIAL;
    sys->nfield = 2;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[1].x = 0.0;
    sys->field[1].y = 12.5;
    t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    assert_int_equal(sg_trace_normalized(t, 0, 1, 0, 0, out), SG_OK);
    print_message("# real image height 12.5: chief ray lands at y = %.17g\n", out[last].y);
    assert_true(fabs(out[last].y - 12.5) <= 1e-12 * 12.5);
    assert_true(fabs(out[last].x) <= 1e-12);
    assert_int_equal(sg_trace_normalized(t, 0.6, 0.8, 0, 0, out), SG_OK);
    print_message("# at (0.6, 0.8): (%.17g, %.17g)\n", out[last].x, out[last].y);
    assert_true(fabs(out[last].x - 7.5) <= 1e-12 * 12.5);
    assert_true(fabs(out[last].y - 10.0) <= 1e-12 * 12.5);
    sg_tracer_free(t);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The aperture types that derive the pupil: working F/# and object NA
 * give back the value asked for; a paraxial image height field equals the
 * paraxial chief ray's height. */
static void aperture_types(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("singlet.json");
    sg_paraxial p;
    sg_diag d;
    (void)state;
    sys->aper_type = SG_APER_PARAX_WORKING_FNUM;
    sys->aper_value = 5.0;
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    print_message("# working F/5: EPD %.17g, EFL/5 = %.17g, working F/# %.17g\n", p.epd,
                  p.efl / 5.0, p.working_fnum);
    assert_true(fabs(p.working_fnum - 5.0) <= 1e-14 * 5.0);
    /* In air at infinity the paraxial working F/# is EFL / EPD. */
    assert_true(fabs(p.epd - p.efl / 5.0) <= 1e-13 * p.epd);

    sys->surf[0].thickness = 400.0;
    sys->field_type = SG_FIELD_OBJECT_HEIGHT;
    sys->aper_type = SG_APER_OBJECT_NA;
    sys->aper_value = 0.02;
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    print_message("# object NA 0.02: paraxial marginal ray NA %.17g\n", p.object_na);
    assert_true(fabs(p.object_na - 0.02) <= 1e-15);

    sys->surf[0].thickness = INFINITY;
    sys->field_type = SG_FIELD_PARAX_IMAGE_HEIGHT;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = 10.0;
    sys->nfield = 2;
    sys->field[1].x = 0.0;
    sys->field[1].y = 3.0;
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    assert_true(p.parax_image_height == 3.0);
    {
        /* A tiny field is paraxial, so the real chief ray, carried on from
         * the image surface to the paraxial image plane (where Zemax
         * defines a paraxial image height: test_zemax_semidiam), lands on
         * it. */
        sg_tracer *t;
        sg_ray_surface out[8];
        const sg_ray_surface *im;
        double h = 1e-6, dz, yp;
        sys->field[1].y = h;
        t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
        assert_int_equal(sg_trace_normalized(t, 0, 1, 0, 0, out), SG_OK);
        im = &out[sys->nsurf - 1];
        dz = p.image_dist - sys->surf[sys->nsurf - 2].thickness;
        yp = im->y + dz * im->m / im->n;
        print_message("# paraxial image height %g: real chief ray at %.17g on the image, "
                      "%.17g at the paraxial image plane %g beyond it\n", h, im->y, yp, dz);
        assert_true(fabs(yp - h) <= 1e-9 * h);
        sg_tracer_free(t);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(stop_edge),
        cmocka_unit_test(straight_to_stop),
        cmocka_unit_test(impossible),
        cmocka_unit_test(paraxial_aiming),
        cmocka_unit_test(real_image_height),
        cmocka_unit_test(aperture_types),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
