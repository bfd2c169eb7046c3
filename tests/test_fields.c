/*
 * test_fields.c - field definitions as Zemax's.  An angle field is the
 * chief ray's slope towards the entrance pupil's centre, (tan ax, tan ay, 1)
 * normalized, also from an object at a finite distance, whose point is
 * then -tan a times its distance to the pupil; normalized coordinates
 * scale the angle linearly, beyond 1 too, up to 90 degrees.
 *
 * Truths: closed forms.  The stop is on surface 1, so the entrance pupil
 * is at its vertex, 100 mm from the object.
 */
#include <math.h>

#include "testutil.h"

static void angle_from_finite_object(void **state)
{
    static const double hs[] = {0.0, 0.5, 1.0, 2.0, -3.0, 8.9};
    static const sg_method methods[3] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC,
                                         SG_METHOD_MPFR};
    sg_system *s = sg_system_new();
    int m, k;
    (void)state;
    assert_int_equal(sg_system_reset(s, 4), SG_OK);
    s->surf[0].thickness = 100.0;
    s->surf[1].radius = 50.0;
    s->surf[1].thickness = 5.0;
    s->surf[1].mat.kind = SG_MAT_INDEX;
    s->surf[1].mat.index = 1.5;
    s->surf[2].thickness = 100.0;
    s->stop = 1;
    s->aper_value = 2.0;
    s->field_type = SG_FIELD_ANGLE;
    s->nfield = 2;
    s->field[1].y = 10.0;
    {
        /* The paraxial chief ray of slope tan 10 through surface 1's vertex
         * (the stop): 5 mm at tan / 1.5 in the glass, then 100 mm at tan. */
        sg_paraxial p;
        sg_diag d;
        double want = tan(10.0 * 3.14159265358979323846 / 180.0) * (5.0 / 1.5 + 100.0);
        sg_diag_clear(&d);
        assert_int_equal(sg_paraxial_compute(s, NULL, 0, &p, &d), SG_OK);
        if (fabs(p.parax_image_height - want) > 1e-13 * want)
            fail_msg("paraxial image height %.17g, want %.17g", p.parax_image_height, want);
    }
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(s, NULL, methods[m]);
        sg_ray_surface out[4];
        for (k = 0; k < (int)(sizeof hs / sizeof hs[0]); k++) {
            double a = 10.0 * hs[k] * 3.14159265358979323846 / 180.0;
            int rc = sg_trace_normalized(t, 0.0, hs[k], 0.0, 0.0, out);
            assert_int_equal(out[0].status, SG_OK);
            (void)rc;
            /* The object point: -tan a times the 100 mm to the pupil. */
            if (fabs(out[0].y + 100.0 * tan(a)) > 1e-13 * (1.0 + 100.0 * fabs(tan(a))) ||
                out[0].x != 0.0 || out[0].z != 0.0)
                fail_msg("%s Hy %g: object point (%.17g, %.17g, %.17g), want (0, %.17g, 0)",
                         sg_method_name(methods[m]), hs[k], out[0].x, out[0].y, out[0].z,
                         -100.0 * tan(a));
            /* The direction: slope tan a. */
            if (fabs(out[0].m - sin(a)) > 4e-16 || fabs(out[0].n - cos(a)) > 4e-16)
                fail_msg("%s Hy %g: direction (%.17g, %.17g), want (%.17g, %.17g)",
                         sg_method_name(methods[m]), hs[k], out[0].m, out[0].n, sin(a), cos(a));
        }
        /* 90 degrees and beyond are refused. */
        assert_int_equal(sg_trace_normalized(t, 0.0, 9.0, 0.0, 0.0, out), SG_ERANGE);
        assert_int_equal(sg_trace_normalized(t, -9.5, 0.0, 0.0, 0.0, out), SG_ERANGE);
        sg_tracer_free(t);
    }
    sg_system_free(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(angle_from_finite_object),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
