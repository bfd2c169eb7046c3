/*
 * dd.h - double-double arithmetic for the precise trace.
 *
 * A dd value is hi + lo with |lo| <= ulp(hi)/2, about 106 significant bits.
 * The algorithms are the error-free transformations of Knuth (two-sum) and
 * the FMA two-product, with the accurate addition and the division and
 * square-root refinements of Joldes, Muller and Popescu (ACM TOMS 44, 2017).
 * They are exact only when every rounding happens as written, which is why
 * the project builds with -ffp-contract=off.
 *
 * DD_U bounds the relative error of any one operation below; the running
 * error analysis multiplies it by operation counts.
 */
#ifndef SG_DD_H
#define SG_DD_H

#include <math.h>

typedef struct dd {
    double hi, lo;
} dd;

/* 2^-104: four times the unit roundoff of the pair, enough for every
 * operation here (JMP 2017 prove 3u^2 for add, 4u^2 mul, 15u^2 div). */
#define DD_U 4.930380657631324e-32

static inline dd dd_from(double a)
{
    dd r = {a, 0.0};
    return r;
}

static inline dd dd_two_sum(double a, double b)
{
    dd r;
    double s = a + b;
    double bb = s - a;
    r.hi = s;
    r.lo = (a - (s - bb)) + (b - bb);
    return r;
}

static inline dd dd_fast_two_sum(double a, double b)
{
    dd r;
    double s = a + b;
    r.hi = s;
    r.lo = b - (s - a);
    return r;
}

static inline dd dd_two_prod(double a, double b)
{
    dd r;
    r.hi = a * b;
    r.lo = fma(a, b, -r.hi);
    return r;
}

static inline dd dd_add(dd a, dd b)
{
    dd s = dd_two_sum(a.hi, b.hi);
    dd t = dd_two_sum(a.lo, b.lo);
    s.lo += t.hi;
    s = dd_fast_two_sum(s.hi, s.lo);
    s.lo += t.lo;
    return dd_fast_two_sum(s.hi, s.lo);
}

static inline dd dd_neg(dd a)
{
    dd r = {-a.hi, -a.lo};
    return r;
}

static inline dd dd_sub(dd a, dd b)
{
    return dd_add(a, dd_neg(b));
}

static inline dd dd_add_d(dd a, double b)
{
    dd s = dd_two_sum(a.hi, b);
    s.lo += a.lo;
    return dd_fast_two_sum(s.hi, s.lo);
}

static inline dd dd_mul(dd a, dd b)
{
    dd p = dd_two_prod(a.hi, b.hi);
    p.lo += a.hi * b.lo;
    p.lo += a.lo * b.hi;
    return dd_fast_two_sum(p.hi, p.lo);
}

static inline dd dd_mul_d(dd a, double b)
{
    dd p = dd_two_prod(a.hi, b);
    p.lo += a.lo * b;
    return dd_fast_two_sum(p.hi, p.lo);
}

static inline dd dd_sqr(dd a)
{
    dd p = dd_two_prod(a.hi, a.hi);
    p.lo += 2.0 * a.hi * a.lo;
    return dd_fast_two_sum(p.hi, p.lo);
}

static inline dd dd_div(dd a, dd b)
{
    double q1 = a.hi / b.hi;
    dd r = dd_sub(a, dd_mul_d(b, q1));
    double q2 = r.hi / b.hi;
    r = dd_sub(r, dd_mul_d(b, q2));
    {
        double q3 = r.hi / b.hi;
        dd q = dd_fast_two_sum(q1, q2);
        return dd_add_d(q, q3);
    }
}

static inline dd dd_div_d(dd a, double b)
{
    double q1 = a.hi / b;
    dd p = dd_two_prod(q1, b);
    double r = ((a.hi - p.hi) - p.lo) + a.lo;
    double q2 = r / b;
    return dd_fast_two_sum(q1, q2);
}

static inline dd dd_sqrt(dd a)
{
    double x, h;
    dd r;
    if (a.hi <= 0.0)
        return dd_from(a.hi == 0.0 ? 0.0 : NAN);
    x = sqrt(a.hi);
    /* One Newton step from the double root doubles the digits.  Its
     * correction r / 2x, at most 1.25u x (u = 2^-53), is a product by
     * 1 / 2x, which is formed while r is: that errs by 2.5u^2 x, the
     * step's truncation by 0.8u^2 x more, within DD_U = 4u^2. */
    h = 0.5 / x;
    r = dd_sub(a, dd_two_prod(x, x));
    return dd_fast_two_sum(x, r.hi * h);
}

static inline double dd_abs_hi(dd a)
{
    return fabs(a.hi);
}

/* Three-vectors of dd, the state of a ray. */
typedef struct dd3 {
    dd x, y, z;
} dd3;

#endif
