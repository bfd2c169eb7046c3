/*
 * test_table2.c - the paper's Table 2 experiment (section 4.2): rays from
 * the centre of a unit sphere toward random points on it, with directions
 * scaled by 100 + xi, as eq. 28 generates them.
 *
 * The truth is exact: a ray from the centre meets the sphere at d / |d|,
 * which this test computes in MPFR from the same double direction.
 */
#include <math.h>
#include <mpfr.h>
#include <stdint.h>
#include <stdlib.h>

#include "testutil.h"

#define PI_D 3.14159265358979323846

static uint64_t state_ = 0x243F6A8885A308D3ULL;

static double urand(void)
{
    state_ ^= state_ >> 12;
    state_ ^= state_ << 25;
    state_ ^= state_ >> 27;
    return ((double)((state_ * 2685821657736338717ULL) >> 11) + 0.5) * 0x1.0p-53;
}

/* A unit sphere whose vertex hemisphere faces the ray: radius +1 with the
 * centre at z = +1 for rays going to -z, radius -1 for rays going to +z. */
static sg_tracer *sphere(double R, sg_method m, sg_system **keep)
{
    sg_trace_opts o;
    sg_diag d;
    sg_system *sys = sg_system_new();
    sg_tracer *t;
    assert_int_equal(sg_system_reset(sys, 3), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->surf[1].radius = R;
    sys->surf[1].thickness = 1.0;
    sys->surf[1].mat.kind = SG_MAT_INDEX;
    sys->surf[1].mat.index = 1.5;
    sys->stop = 1;
    sg_trace_opts_init(&o);
    o.method = m;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, NULL, &o, &d);
    assert_non_null(t);
    *keep = sys;
    return t;
}

static int cmpd(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void table2(void **state)
{
    enum { N = 5000 };
    static double ep[N], ec[N];
    sg_system *s[4];
    sg_tracer *tp[2], *tc[2];
    mpfr_t len, v, w;
    int i, k;
    double worst = 0.0, min_ratio = INFINITY;
    int nexact_miss = 0;
    (void)state;
    tp[0] = sphere(1.0, SG_METHOD_PRECISE, &s[0]);
    tp[1] = sphere(-1.0, SG_METHOD_PRECISE, &s[1]);
    tc[0] = sphere(1.0, SG_METHOD_CLASSIC, &s[2]);
    tc[1] = sphere(-1.0, SG_METHOD_CLASSIC, &s[3]);
    mpfr_inits2(300, len, v, w, (mpfr_ptr)0);
    for (i = 0; i < N; i++) {
        double x1 = urand(), x2 = urand(), x3 = urand();
        double r = 2.0 * sqrt(x1 * (1.0 - x1));
        double p[3] = {r * cos(2.0 * PI_D * x2), r * sin(2.0 * PI_D * x2), 1.0 - 2.0 * x1};
        double sc = 100.0 + x3, D[3], S[3], tr[3], tl[3], scale, e = 0.0, ec_i = 0.0;
        sg_ray_surface op[3], oc[3];
        int h;
        for (k = 0; k < 3; k++)
            D[k] = sc * p[k];
        /* The hemisphere the ray goes to decides which sheet is traced. */
        h = D[2] < 0.0 ? 0 : 1;
        S[0] = 0.0;
        S[1] = 0.0;
        S[2] = h == 0 ? 1.0 : -1.0;
        /* Truth: S + D / |D| exactly, rounded once, and its low part. */
        mpfr_set_zero(len, 1);
        for (k = 0; k < 3; k++) {
            mpfr_set_d(v, D[k], MPFR_RNDN);
            mpfr_sqr(v, v, MPFR_RNDN);
            mpfr_add(len, len, v, MPFR_RNDN);
        }
        mpfr_sqrt(len, len, MPFR_RNDN);
        for (k = 0; k < 3; k++) {
            mpfr_set_d(v, D[k], MPFR_RNDN);
            mpfr_div(v, v, len, MPFR_RNDN);
            mpfr_add_d(v, v, S[k], MPFR_RNDN);
            tr[k] = mpfr_get_d(v, MPFR_RNDN);
            mpfr_sub_d(w, v, tr[k], MPFR_RNDN);
            tl[k] = mpfr_get_d(w, MPFR_RNDN);
        }
        assert_int_equal(sg_trace_start(tp[h], S, D, op), SG_OK);
        /* docs/precision.md: precise equals the truth (rounded once) on every ray. */
        if (op[1].x != tr[0] || op[1].y != tr[1] || op[1].z != tr[2])
            nexact_miss++;
        scale = fmax(fabs(tr[0]), fmax(fabs(tr[1]), fabs(tr[2])));
        e = fmax(fabs((op[1].x - tr[0]) - tl[0]),
                 fmax(fabs((op[1].y - tr[1]) - tl[1]), fabs((op[1].z - tr[2]) - tl[2])));
        if (e > op[1].error_bound)
            fail_msg("ray %d: error %.3g above bound %.3g", i, e, op[1].error_bound);
        if (e > 0)
            min_ratio = fmin(min_ratio, op[1].error_bound / e);
        ep[i] = e / tu_ulp(scale);
        worst = fmax(worst, ep[i]);
        if (sg_trace_start(tc[h], S, D, oc) == SG_OK)
            ec_i = fmax(fabs((oc[1].x - tr[0]) - tl[0]),
                        fmax(fabs((oc[1].y - tr[1]) - tl[1]), fabs((oc[1].z - tr[2]) - tl[2]))) /
                   tu_ulp(scale);
        else
            ec_i = INFINITY;
        ec[i] = ec_i;
    }
    qsort(ep, N, sizeof ep[0], cmpd);
    qsort(ec, N, sizeof ec[0], cmpd);
    print_message("# Table 2: %d rays from the centre of a unit sphere, directions scaled by "
                  "100 + xi; truth MPFR of d/|d|\n", N);
    print_message("# precise error: median %.3f ulp, max %.3f ulp; min bound/error %.3g\n",
                  ep[N / 2], worst, min_ratio);
    print_message("# classic error: median %.3g ulp, p99 %.3g ulp\n", ec[N / 2],
                  ec[(N * 99) / 100]);
    print_message("# precise differs from the correctly rounded truth on %d rays\n",
                  nexact_miss);
    print_message("# classic error: max %.3g ulp\n", ec[N - 1]);
    assert_int_equal(nexact_miss, 0);
    assert_true(worst <= 0.5 + 1e-9);
    /* The paper reports its original method losing 8 digits here.  With
     * the start at the centre nothing cancels, so the textbook formulas in
     * IEEE double traced every ray within docs/precision.md's 256 ulp (median about
     * half an ulp); a classic that lost digits would fail these. */
    assert_true(ec[N - 1] <= 256.0);
    assert_true(ec[N / 2] <= 1.0);
    assert_true(ec[(N * 99) / 100] <= 16.0);
    mpfr_clears(len, v, w, (mpfr_ptr)0);
    for (k = 0; k < 2; k++) {
        sg_tracer_free(tp[k]);
        sg_tracer_free(tc[k]);
    }
    for (k = 0; k < 4; k++)
        sg_system_free(s[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(table2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
