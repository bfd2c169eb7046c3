/*
 * test_dd.c - the double-double sums, reciprocal, quotient and square root
 * of the precise trace against exact values in MPFR.
 *
 * The error analysis in src/trace/trace_vec.c rests on two claims: the accurate
 * sum vdd_add errs by at most DD_U |a + b|, and the sloppy sum vdd_add_m
 * by at most DD_U (|a| + |b|).  The truth here is the exact sum of the four
 * doubles, which 600 bits hold for the exponents drawn.  The cases lean on
 * cancellation, where the two sums differ and the sloppy one's
 * renormalization may meet a low part larger than the high part.
 */
#include <math.h>
#include <mpfr.h>
#include <stdint.h>

#include "testutil.h"
#include "vdd.h"

static uint64_t state_ = 0x9E3779B97F4A7C15ULL;

static double urand(void)
{
    state_ ^= state_ >> 12;
    state_ ^= state_ << 25;
    state_ ^= state_ >> 27;
    return ((double)((state_ * 2685821657736338717ULL) >> 11) + 0.5) * 0x1.0p-53;
}

/* A normalized pair: hi with a random exponent in [-30, 30], and a low
 * part anywhere within half an ulp of it. */
static dd rand_dd(void)
{
    dd a;
    a.hi = ldexp(1.0 + urand(), (int)(urand() * 61.0) - 30);
    if (urand() < 0.5)
        a.hi = -a.hi;
    a.lo = (urand() - 0.5) * tu_ulp(a.hi);
    return dd_fast_two_sum(a.hi, a.lo);
}

/* b close to -a, so the sum cancels k bits, k from 0 to 110. */
static dd near_neg(dd a)
{
    dd b;
    double k = floor(urand() * 111.0);
    b = dd_add(dd_neg(a), dd_from(ldexp(urand() - 0.5, -(int)k) * a.hi));
    if (urand() < 0.3)
        b.lo = -a.lo; /* the high parts then cancel exactly */
    return dd_fast_two_sum(b.hi, b.lo);
}

/* |computed - exact| of the sum a + b, and the exact sum. */
static double sum_error(dd a, dd b, vdd got, mpfr_t exact)
{
    mpfr_t g;
    double e;
    mpfr_init2(g, 600);
    mpfr_set_d(exact, a.hi, MPFR_RNDN);
    mpfr_add_d(exact, exact, a.lo, MPFR_RNDN);
    mpfr_add_d(exact, exact, b.hi, MPFR_RNDN);
    mpfr_add_d(exact, exact, b.lo, MPFR_RNDN);
    mpfr_set_d(g, got.hi[0], MPFR_RNDN);
    mpfr_add_d(g, g, got.lo[0], MPFR_RNDN);
    mpfr_sub(g, g, exact, MPFR_RNDN);
    mpfr_abs(g, g, MPFR_RNDN);
    e = mpfr_get_d(g, MPFR_RNDU);
    mpfr_clear(g);
    return e;
}

static vdd lane0(dd a)
{
    vdd v = vdd_set(a);
    return v;
}

static void sums_within_bounds(void **state)
{
    enum { N = 200000 };
    double worst_acc = 0.0, worst_m = 0.0, worst_m_rel = 0.0;
    long cancel = 0, i;
    mpfr_t exact;
    (void)state;
    mpfr_init2(exact, 600);
    for (i = 0; i < N; i++) {
        dd a = rand_dd(), b = (i % 2) ? near_neg(a) : rand_dd();
        vdd acc = vdd_add(lane0(a), lane0(b)), m = vdd_add_m(lane0(a), lane0(b));
        double e_acc = sum_error(a, b, acc, exact), e_m = sum_error(a, b, m, exact);
        double s = fabs(mpfr_get_d(exact, MPFR_RNDN));
        double mag = fabs(a.hi) + fabs(b.hi);
        if (s < 0x1p-40 * mag)
            cancel++;
        /* Relative to the sum for the accurate one, to the terms for the
         * sloppy one. */
        if (e_acc > 0.0) {
            assert_true(e_acc <= DD_U * s);
            worst_acc = fmax(worst_acc, e_acc / (DD_U * s));
        }
        if (e_m > 0.0) {
            assert_true(e_m <= DD_U * mag);
            worst_m = fmax(worst_m, e_m / (DD_U * mag));
            if (s > 0.0)
                worst_m_rel = fmax(worst_m_rel, e_m / (DD_U * s));
        }
        /* Every lane gives the same bits. */
        assert_true(m.hi[SG_VL - 1] == m.hi[0] && m.lo[SG_VL - 1] == m.lo[0]);
    }
    mpfr_clear(exact);
    print_message("# %d sums, %ld cancelling more than 40 bits; exact sums in 600-bit MPFR\n",
                  N, cancel);
    print_message("# vdd_add: worst error / (DD_U |a + b|) = %.3f (bound 1)\n", worst_acc);
    print_message("# vdd_add_m: worst error / (DD_U (|a| + |b|)) = %.3f (bound 1)\n", worst_m);
    /* Why the accurate sum stays wherever a bound is relative to the sum. */
    print_message("# vdd_add_m: worst error / (DD_U |a + b|) = %.3g (no bound)\n", worst_m_rel);
}

/* Terms of one sign: the sloppy sum is then as accurate as the other,
 * which is what r2 = x^2 + y^2 and |g|^2 rely on. */
static void same_sign_relative(void **state)
{
    enum { N = 100000 };
    double worst = 0.0;
    long i;
    mpfr_t exact;
    (void)state;
    mpfr_init2(exact, 600);
    for (i = 0; i < N; i++) {
        dd a = rand_dd(), b = rand_dd();
        vdd m;
        double e, s;
        if ((a.hi < 0) != (b.hi < 0))
            b = dd_neg(b);
        m = vdd_add_m(lane0(a), lane0(b));
        e = sum_error(a, b, m, exact);
        s = fabs(mpfr_get_d(exact, MPFR_RNDN));
        assert_true(e <= DD_U * s);
        worst = fmax(worst, e / (DD_U * s));
    }
    mpfr_clear(exact);
    print_message("# %d same-sign sloppy sums: worst error / (DD_U |a + b|) = %.3f (bound 1)\n",
                  N, worst);
}

/* |hi + lo - exact| / |exact| of got against the exact value in e. */
static double rel_error(vdd got, mpfr_t e)
{
    mpfr_t g;
    double r;
    mpfr_init2(g, 600);
    mpfr_set_d(g, got.hi[0], MPFR_RNDN);
    mpfr_add_d(g, g, got.lo[0], MPFR_RNDN);
    mpfr_sub(g, g, e, MPFR_RNDN);
    mpfr_div(g, g, e, MPFR_RNDN);
    mpfr_abs(g, g, MPFR_RNDN);
    r = mpfr_get_d(g, MPFR_RNDU);
    mpfr_clear(g);
    return r;
}

/* vdd_recip's claim of 9u^2 (u = 2^-53), vdd_div_dr's of 15u^2 and
 * vdd_sqrt's of DD_U = 4u^2, the figures the bend's 1 / g.g, a flat
 * surface's step, the Newton step and the refracted direction are counted
 * with, against 1 / b, a / b and sqrt|b| in 600-bit MPFR. */
static void reciprocal_quotient_root(void **state)
{
    enum { N = 200000 };
    const double u2 = 0x1p-106;
    double worst_r = 0.0, worst_q = 0.0, worst_s = 0.0;
    long i;
    mpfr_t e, t;
    (void)state;
    mpfr_inits2(600, e, t, (mpfr_ptr)0);
    for (i = 0; i < N; i++) {
        dd a = rand_dd(), b = rand_dd();
        vdd r, q, sq;
        double rb, er, eq, es;
        /* Low parts at the edge of their range make the residual largest. */
        if (i % 4 == 0)
            b = dd_fast_two_sum(b.hi, (i % 8 ? 0.5 : -0.5) * tu_ulp(b.hi));
        r = vdd_recip(lane0(b));
        rb = 1.0 / b.hi;
        q = vdd_div_dr(lane0(a), vd_set(b.hi), vd_set(rb));
        mpfr_set_d(e, b.hi, MPFR_RNDN);
        mpfr_add_d(e, e, b.lo, MPFR_RNDN);
        mpfr_ui_div(e, 1, e, MPFR_RNDN);
        er = rel_error(r, e);
        mpfr_set_d(e, a.hi, MPFR_RNDN);
        mpfr_add_d(e, e, a.lo, MPFR_RNDN);
        mpfr_set_d(t, b.hi, MPFR_RNDN);
        mpfr_div(e, e, t, MPFR_RNDN);
        eq = rel_error(q, e);
        sq = vdd_sqrt(lane0(b.hi < 0 ? dd_neg(b) : b));
        mpfr_set_d(e, fabs(b.hi), MPFR_RNDN);
        mpfr_add_d(e, e, b.hi < 0 ? -b.lo : b.lo, MPFR_RNDN);
        mpfr_sqrt(e, e, MPFR_RNDN);
        es = rel_error(sq, e);
        if (es > DD_U)
            fail_msg("sqrt(%a + %a): relative error %.3g u^2 above 4", b.hi, b.lo, es / u2);
        worst_s = fmax(worst_s, es);
        if (er > 9.0 * u2)
            fail_msg("1 / (%a + %a): relative error %.3g u^2 above 9", b.hi, b.lo, er / u2);
        if (eq > 15.0 * u2)
            fail_msg("(%a + %a) / %a: relative error %.3g u^2 above 15", a.hi, a.lo, b.hi,
                     eq / u2);
        worst_r = fmax(worst_r, er);
        worst_q = fmax(worst_q, eq);
        assert_true(r.hi[SG_VL - 1] == r.hi[0] && r.lo[SG_VL - 1] == r.lo[0]);
    }
    mpfr_clears(e, t, (mpfr_ptr)0);
    print_message("# %d cases against 600-bit MPFR, u = 2^-53\n", N);
    print_message("# vdd_recip: worst relative error %.3f u^2 (bound 9)\n", worst_r / u2);
    print_message("# vdd_div_dr: worst relative error %.3f u^2 (bound 15)\n", worst_q / u2);
    print_message("# vdd_sqrt: worst relative error %.3f u^2 (bound 4)\n", worst_s / u2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sums_within_bounds),
        cmocka_unit_test(same_sign_relative),
        cmocka_unit_test(reciprocal_quotient_root),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
