/*
 * vdd.h - double-double arithmetic on SG_VL rays at once.
 *
 * Each operation is the lane-by-lane transcription of the one of the same
 * name in dd.h, rounding for rounding, so vector and scalar double-double
 * code give the same bits.  The sloppy sum and the forms built on it
 * (vdd_add_m, vdd_sub_m, vdd_dot3, vdd3_axpy), the reciprocal vdd_recip
 * and the quotient by a reciprocal vdd_div_dr have no scalar twin: the
 * precise trace runs in this file's arithmetic alone, one ray as one lane.
 * Only correctly rounded operations are used (add, mul, div, sqrt, fma),
 * which is why the result does not depend on whether the compiler maps a
 * vector to AVX-512, AVX2, SSE2 or plain scalar code.
 */
#ifndef SG_VDD_H
#define SG_VDD_H

#include <math.h>
#include <stdint.h>

#include "dd.h"

#if defined(__AVX__)
#include <immintrin.h>
#endif

/* Eight lanes where the registers hold eight doubles (AVX-512: 32 of
 * them, so a block's state stays in registers), four elsewhere.  The
 * double-double chains are long and dependent, so wider blocks give the
 * core independent work; a lane's bits do not depend on the width. */
#if defined(__AVX512F__)
#define SG_VL 8
#else
#define SG_VL 4
#endif

typedef double vd __attribute__((vector_size(SG_VL * sizeof(double))));
/* Comparison results: all bits set in a lane where the comparison holds. */
typedef int64_t vm __attribute__((vector_size(SG_VL * sizeof(double))));

#define VM_SIGN INT64_MIN /* the sign bit of a double, as an integer lane */

static inline vd vd_set(double a)
{
    vd r;
    int k;
    for (k = 0; k < SG_VL; k++)
        r[k] = a;
    return r;
}

static inline vm vm_set(int64_t a)
{
    vm r;
    int k;
    for (k = 0; k < SG_VL; k++)
        r[k] = a;
    return r;
}

static inline vd vsel(vm m, vd a, vd b)
{
    return (vd)(((vm)a & m) | ((vm)b & ~m));
}

static inline int vm_any(vm m)
{
#if defined(__AVX512F__)
    return _mm512_test_epi64_mask((__m512i)m, (__m512i)m) != 0;
#elif defined(__AVX__) && SG_VL == 4
    /* One vptest: GCC otherwise extracts each lane into a general
     * register and ORs them, a chain of some ten instructions on every
     * test of the trace's masks. */
    return !_mm256_testz_si256((__m256i)m, (__m256i)m);
#else
    int64_t any = 0;
    int k;
    for (k = 0; k < SG_VL; k++)
        any |= m[k];
    return any != 0;
#endif
}

static inline vd vd_abs(vd a)
{
    return (vd)((vm)a & ~vm_set(VM_SIGN));
}

static inline vd vd_neg(vd a)
{
    return (vd)((vm)a ^ vm_set(VM_SIGN));
}

/* copysign(a, b) */
static inline vd vd_copysign(vd a, vd b)
{
    return (vd)(((vm)a & ~vm_set(VM_SIGN)) | ((vm)b & vm_set(VM_SIGN)));
}

/* A lane that is neither infinite nor NaN. */
static inline vm vd_isfinite(vd a)
{
    return (vm)(vd_abs(a) <= vd_set(1.79769313486231570815e+308));
}

static inline vm vd_isnan(vd a)
{
    return (vm)(a != a);
}

/* fmax with C's treatment of NaN: the other operand wins. */
static inline vd vd_fmax(vd a, vd b)
{
    return vsel((vm)(a > b) | vd_isnan(b), a, b);
}

/* fmin with C's treatment of NaN, and glibc's choice of b when equal. */
static inline vd vd_fmin(vd a, vd b)
{
    return vsel((vm)(a < b) | vd_isnan(b), a, b);
}

static inline vd vd_sqrt(vd a)
{
#if defined(__AVX512F__)
    return _mm512_sqrt_pd(a);
#elif defined(__AVX__)
    return _mm256_sqrt_pd(a);
#else
    vd r;
    int k;
    for (k = 0; k < SG_VL; k++)
        r[k] = sqrt(a[k]);
    return r;
#endif
}

/* a * b - c with one rounding. */
static inline vd vd_fms(vd a, vd b, vd c)
{
#if defined(__AVX512F__)
    return _mm512_fmsub_pd(a, b, c);
#elif defined(__FMA__)
    return _mm256_fmsub_pd(a, b, c);
#else
    vd r;
    int k;
    for (k = 0; k < SG_VL; k++)
        r[k] = fma(a[k], b[k], -c[k]);
    return r;
#endif
}

/* Clears the upper halves of the vector registers before a long call into
 * code built for the baseline instruction set (the classic trace in
 * trace.c): its SSE instructions would otherwise run with false
 * dependencies on those halves, at half speed or worse.  A no-op without
 * AVX. */
static inline void vd_leave(void)
{
#if defined(__AVX__)
    _mm256_zeroupper();
#endif
}

typedef struct vdd {
    vd hi, lo;
} vdd;

static inline vdd vdd_from(vd a)
{
    vdd r = {a, vd_set(0.0)};
    return r;
}

static inline vdd vdd_set(dd a)
{
    vdd r = {vd_set(a.hi), vd_set(a.lo)};
    return r;
}

static inline vdd vdd_sel(vm m, vdd a, vdd b)
{
    vdd r = {vsel(m, a.hi, b.hi), vsel(m, a.lo, b.lo)};
    return r;
}

static inline vdd vdd_two_sum(vd a, vd b)
{
    vdd r;
    vd s = a + b;
    vd bb = s - a;
    r.hi = s;
    r.lo = (a - (s - bb)) + (b - bb);
    return r;
}

static inline vdd vdd_fast_two_sum(vd a, vd b)
{
    vdd r;
    vd s = a + b;
    r.hi = s;
    r.lo = b - (s - a);
    return r;
}

static inline vdd vdd_two_prod(vd a, vd b)
{
    vdd r;
    r.hi = a * b;
    r.lo = vd_fms(a, b, r.hi);
    return r;
}

static inline vdd vdd_add(vdd a, vdd b)
{
    vdd s = vdd_two_sum(a.hi, b.hi);
    vdd t = vdd_two_sum(a.lo, b.lo);
    s.lo += t.hi;
    s = vdd_fast_two_sum(s.hi, s.lo);
    s.lo += t.lo;
    return vdd_fast_two_sum(s.hi, s.lo);
}

/* a + b with one two-sum: its error is at most DD_U (|a| + |b|) instead of
 * DD_U |a + b| (Joldes, Muller and Popescu's sloppy sum), which costs half
 * as much.  It serves sums whose error bound is taken over the magnitudes
 * of their terms, and sums of terms of one sign. */
static inline vdd vdd_add_m(vdd a, vdd b)
{
    vdd s = vdd_two_sum(a.hi, b.hi);
    s.lo += a.lo + b.lo;
    return vdd_fast_two_sum(s.hi, s.lo);
}

static inline vdd vdd_neg(vdd a)
{
    vdd r = {-a.hi, -a.lo};
    return r;
}

static inline vdd vdd_sub(vdd a, vdd b)
{
    return vdd_add(a, vdd_neg(b));
}

static inline vdd vdd_sub_m(vdd a, vdd b)
{
    return vdd_add_m(a, vdd_neg(b));
}

static inline vdd vdd_add_d(vdd a, vd b)
{
    vdd s = vdd_two_sum(a.hi, b);
    s.lo += a.lo;
    return vdd_fast_two_sum(s.hi, s.lo);
}

static inline vdd vdd_mul(vdd a, vdd b)
{
    vdd p = vdd_two_prod(a.hi, b.hi);
    p.lo += a.hi * b.lo;
    p.lo += a.lo * b.hi;
    return vdd_fast_two_sum(p.hi, p.lo);
}

static inline vdd vdd_mul_d(vdd a, vd b)
{
    vdd p = vdd_two_prod(a.hi, b);
    p.lo += a.lo * b;
    return vdd_fast_two_sum(p.hi, p.lo);
}

static inline vdd vdd_sqr(vdd a)
{
    vdd p = vdd_two_prod(a.hi, a.hi);
    p.lo += vd_set(2.0) * a.hi * a.lo;
    return vdd_fast_two_sum(p.hi, p.lo);
}

/* 1 / b: the double reciprocal y and one Newton step y + y e, e = 1 - b y,
 * whose part 1 - b.hi y the FMA forms exactly.  With |e| below 2u
 * (u = 2^-53) the step leaves e^2 <= 4u^2 and its three roundings at most
 * 5u^2 more: 9u^2 relative, below dd_div's 15u^2, in one quotient
 * instead of three. */
static inline vdd vdd_recip(vdd b)
{
    vd y = vd_set(1.0) / b.hi;
    vd e = vd_neg(vd_fms(b.hi, y, vd_set(1.0))) - b.lo * y;
    return vdd_fast_two_sum(y, y * e);
}

/* a / b from r = 1 / b rounded: the quotient q = a.hi r, and the
 * remainder a - q b, formed exactly as far as it cancels, times r as its
 * correction.  With q within 2u of a.hi / b, the remainder's roundings
 * stay below 7u^2 |a| and the correction's below 8u^2 |a / b|: 15u^2
 * relative, as dd_div would take, without a quotient on the path from a
 * when r is formed beforehand. */
static inline vdd vdd_div_dr(vdd a, vd b, vd r)
{
    vd q1 = a.hi * r;
    vdd p = vdd_two_prod(q1, b);
    vd rem = ((a.hi - p.hi) - p.lo) + a.lo;
    return vdd_fast_two_sum(q1, rem * r);
}

static inline vdd vdd_sqrt(vdd a)
{
    /* As dd_sqrt: zero for zero, NaN for a negative argument; a NaN goes
     * through the arithmetic as it does there. */
    vm le = (vm)(a.hi <= vd_set(0.0));
    vd x = vd_sqrt(vsel(le, vd_set(1.0), a.hi));
    vd h = vd_set(0.5) / x;
    vdd r = vdd_sub(a, vdd_two_prod(x, x));
    vdd root = vdd_fast_two_sum(x, r.hi * h);
    vd other = vsel((vm)(a.hi == vd_set(0.0)), vd_set(0.0), vd_set(NAN));
    root.hi = vsel(le, other, root.hi);
    root.lo = vsel(le, vd_set(0.0), root.lo);
    return root;
}

typedef struct vdd3 {
    vdd x, y, z;
} vdd3;

/* Dot product and a + s b with the sloppy sum: errors bounded by DD_U times
 * the sum of the magnitudes of the products. */
static inline vdd vdd_dot3(vdd3 a, vdd3 b)
{
    return vdd_add_m(vdd_add_m(vdd_mul(a.x, b.x), vdd_mul(a.y, b.y)), vdd_mul(a.z, b.z));
}

static inline vdd3 vdd3_axpy(vdd3 a, vdd s, vdd3 b)
{
    vdd3 r;
    r.x = vdd_add_m(a.x, vdd_mul(s, b.x));
    r.y = vdd_add_m(a.y, vdd_mul(s, b.y));
    r.z = vdd_add_m(a.z, vdd_mul(s, b.z));
    return r;
}

/* dd_div on lanes: three quotients, as there, so each lane gets its bits. */
static inline vdd vdd_div(vdd a, vdd b)
{
    vd q1 = a.hi / b.hi, q2, q3;
    vdd r = vdd_sub(a, vdd_mul_d(b, q1)), q;
    q2 = r.hi / b.hi;
    r = vdd_sub(r, vdd_mul_d(b, q2));
    q3 = r.hi / b.hi;
    q = vdd_fast_two_sum(q1, q2);
    return vdd_add_d(q, q3);
}

#endif
