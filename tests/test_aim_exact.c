/*
 * test_aim_exact.c - paraxial ray aiming lands every ray on its target,
 * (Px, Py) times the paraxial stop radius, to the last bit the trace can
 * show, for every method and asymmetric rays (Hx, Hy, Px, Py random).
 *
 * The target comes from sg_paraxial_compute (the paraxial marginal ray's
 * height on the stop) and the ray's own pupil coordinates; the aiming
 * iteration never sees this test's arithmetic.  The stop lies inside the
 * Cooke triplet and the double Gauss, so the aim really iterates.
 */
#include <math.h>
#include <stdint.h>

#include "testutil.h"

static uint64_t rng_state = 0x2545F4914F6CDD1DULL;

static double urand(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * 0x1.0p-53;
}

static void aim(const char *file)
{
    static const sg_method methods[3] = {SG_METHOD_PRECISE, SG_METHOD_MPFR, SG_METHOD_CLASSIC};
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_paraxial p;
    sg_diag d;
    int m, i, n[3] = {0, 0, 0};
    double worst[3] = {0, 0, 0};
    sys->aim = SG_AIM_PARAXIAL;
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, cat, methods[m]);
        sg_ray_surface out[64];
        assert_true(sys->nsurf <= 64);
        rng_state = 0x2545F4914F6CDD1DULL;
        for (i = 0; i < (methods[m] == SG_METHOD_MPFR ? 60 : 400); i++) {
            double hx = 2.0 * urand() - 1.0, hy = 2.0 * urand() - 1.0;
            double px = 2.0 * urand() - 1.0, py = 2.0 * urand() - 1.0, e;
            if (px * px + py * py > 1.0 || hx * hx + hy * hy > 1.0)
                continue;
            if (sg_trace_normalized(t, hx, hy, px, py, out) != SG_OK &&
                out[sys->stop].status != SG_OK)
                continue; /* vignetted or missed before the stop */
            e = fmax(fabs(out[sys->stop].x - px * p.stop_radius),
                     fabs(out[sys->stop].y - py * p.stop_radius)) / p.stop_radius;
            worst[m] = fmax(worst[m], e);
            n[m]++;
        }
        sg_tracer_free(t);
    }
    print_message("# %s, paraxial aiming onto stop radius %.17g: worst landing error of the "
                  "radius: precise %.3g (%d rays), mpfr %.3g (%d), classic %.3g (%d)\n", file,
                  p.stop_radius, worst[0], n[0], worst[1], n[1], worst[2], n[2]);
    for (m = 0; m < 3; m++)
        assert_true(n[m] >= 20);
    /* Precise and mpfr: within the rounding of the landing and of the
     * target's product, two ulp of the radius.  Classic: its aim stops at
     * the 1e-13 tolerance of its own noisy trace; held to 1e-12. */
    assert_true(worst[0] <= 0x1p-51);
    assert_true(worst[1] <= 0x1p-51);
    assert_true(worst[2] <= 1e-12);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void cooke(void **state)
{
    (void)state;
    aim("cooke_triplet.json");
}

static void double_gauss(void **state)
{
    (void)state;
    aim("double_gauss.json");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(cooke),
        cmocka_unit_test(double_gauss),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
