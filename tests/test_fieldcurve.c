/*
 * test_fieldcurve.c - field curvature and distortion against the exact
 * image of a spherical mirror with its stop at the centre of curvature,
 * and against the Seidel sums (themselves checked against closed forms and
 * real rays in test_seidel) at small field.
 */
#include <math.h>
#include <string.h>

#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void run(const sg_system *sys, const sg_catalog *cat, int npts, sg_fieldcurve_pt *o)
{
    sg_trace_opts opts;
    sg_diag d;
    sg_trace_opts_init(&opts);
    sg_diag_clear(&d);
    if (sg_fieldcurve(sys, cat, &opts, npts, 0.01, o, &d) != SG_OK)
        fail_msg("fieldcurve: %s", d.msg);
}

/* A concave mirror R = -200 with the stop at its centre C: every chief ray
 * is an axis of symmetry, so there is no astigmatism and no distortion,
 * and the focus of the field at angle theta lies on the chief ray R/2 from
 * C, which is 100 (cos theta - 1) from the paraxial image plane along z.
 * The chief ray meets that plane 100 tan(theta) from the axis, the
 * paraxial f tan(theta). */
static void mirror_at_centre(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new();
    sg_fieldcurve_pt o[11];
    int i;
    (void)state;
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->stop = 1;
    sys->surf[1].thickness = 200.0;
    sys->surf[2].radius = -200.0;
    sys->surf[2].thickness = -100.0;
    sys->surf[2].mat.kind = SG_MAT_MIRROR;
    sys->aper_value = 20.0;
    sys->nfield = 2;
    sys->field[1].y = 20.0;
    sys->field[1].weight = 1.0;
    run(sys, cat, 11, o);
    for (i = 0; i < 11; i++) {
        double th = o[i].field * M_PI / 180.0, want = 100.0 * (cos(th) - 1.0);
        print_message("# %5.1f deg: T %.15g S %.15g (exact %.15g), distortion %.3g %%\n",
                      o[i].field, o[i].tan_focus, o[i].sag_focus, want, o[i].distortion);
        assert_int_equal(o[i].status, SG_OK);
        assert_true(fabs(o[i].field - 2.0 * i) < 1e-13);
        assert_true(fabs(o[i].tan_focus - want) < 1e-8);
        assert_true(fabs(o[i].sag_focus - want) < 1e-8);
        assert_true(fabs(o[i].real_y - o[i].parax_y) < 1e-12 * 100.0);
        assert_true(fabs(fabs(o[i].parax_y) - 100.0 * tan(th)) < 1e-12 * 100.0);
        assert_true(fabs(o[i].distortion) < 1e-10);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* At small field the foci and distortion follow the Seidel sums: a ray
 * whose transverse aberration is TSFC p at pupil height p crosses the
 * chief ray -TSFC n' / (n'u') from the image plane (less the axial
 * focus), and the distortion is TDIS / h'. */
static void seidel_limit_case(const char *file, double field)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_fieldcurve_pt o[3];
    sg_seidel s;
    sg_paraxial p;
    sg_diag d;
    double t[SG_NTCOEF], nimg = 1.0, dzt, dzs, dist;
    int k;
    sys->nfield = 2;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[1].x = 0.0;
    sys->field[1].y = field;
    sys->field_norm = SG_NORM_RADIAL;
    sys->aim = SG_AIM_OFF;
    for (k = 1; k < sys->nsurf; k++)
        sys->surf[k].sd_fixed = 0;
    /* Distortion in the Seidel sense is that of the paraxial image plane;
     * on a defocused plane the chief ray's own angle error adds to it. */
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    sys->surf[sys->nsurf - 2].thickness = p.image_dist;
    assert_int_equal(sg_seidel_compute(sys, cat, &s, &d), SG_OK);
    sg_seidel_transverse(s.total, s.nu_image, t);
    run(sys, cat, 3, o);
    dzt = -t[SG_TTFC] * nimg / s.nu_image;
    dzs = -t[SG_TSFC] * nimg / s.nu_image;
    dist = 100.0 * t[SG_TDIS] / o[2].parax_y;
    print_message("# %s %g deg: T %.10g (Seidel %.10g), S %.10g (Seidel %.10g), "
                  "distortion %.10g %% (Seidel %.10g)\n",
                  file, field, o[2].tan_focus - o[0].tan_focus, dzt,
                  o[2].sag_focus - o[0].sag_focus, dzs, o[2].distortion, dist);
    assert_true(fabs(o[0].tan_focus - o[0].sag_focus) < 1e-9);
    assert_true(fabs(o[2].tan_focus - o[0].tan_focus - dzt) < 2e-3 * fabs(dzt));
    assert_true(fabs(o[2].sag_focus - o[0].sag_focus - dzs) < 2e-3 * fabs(dzs));
    assert_true(fabs(o[2].distortion - dist) < 2e-3 * fabs(dist));
    /* Third order: a quarter of the effect at half the field. */
    assert_true(fabs(o[1].tan_focus - o[0].tan_focus - dzt / 4) < 2e-3 * fabs(dzt));
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void seidel_limit(void **state)
{
    (void)state;
    seidel_limit_case("singlet.json", 0.5);
    seidel_limit_case("cooke_triplet.json", 0.5);
    seidel_limit_case("double_gauss.json", 0.25);
}

static void bad_args(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("singlet.json");
    sg_fieldcurve_pt o[4];
    sg_trace_opts opts;
    sg_diag d;
    (void)state;
    sg_trace_opts_init(&opts);
    sg_diag_clear(&d);
    assert_int_equal(sg_fieldcurve(sys, cat, &opts, 1, 0.01, o, &d), SG_ERANGE);
    sg_diag_clear(&d);
    assert_int_equal(sg_fieldcurve(sys, cat, &opts, 4, 0.0, o, &d), SG_ERANGE);
    sg_diag_clear(&d);
    assert_int_equal(sg_fieldcurve(sys, cat, &opts, 4, NAN, o, &d), SG_ERANGE);
    sys->field_type = SG_FIELD_REAL_IMAGE_HEIGHT;
    sg_diag_clear(&d);
    assert_int_equal(sg_fieldcurve(sys, cat, &opts, 4, 0.01, o, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "real image height"));
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mirror_at_centre),
        cmocka_unit_test(seidel_limit),
        cmocka_unit_test(bad_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
