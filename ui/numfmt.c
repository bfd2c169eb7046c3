/* numfmt.c - doubles to and from decimal text, fast and exact.
 *
 * Both directions multiply a 64-bit significand by a 128-bit truncation of
 * a power of ten (table built by gen_pow10.c in GMP) and keep the top 128
 * bits of the product.  That product is below the exact one by less than
 * two units in its last place, so the digit or bit that decides rounding is
 * certain unless the dropped part lies within two units of one half; those
 * rare cases go to snprintf or strtod.  This is the decision of
 * D. Lemire, "Number parsing at a gigabyte per second", Software: Practice
 * and Experience 51(8), 2021 (the Eisel-Lemire algorithm), with the
 * fallback taken whenever the error interval touches the halfway point,
 * and the exact fast path of W. D. Clinger, "How to read floating point
 * numbers accurately", PLDI 1990, for small significands and exponents.
 * The printing direction uses the same bound the other way round: 17
 * correctly rounded digits of v 10^q, as in U. Adams, "Ryu printf",
 * PLDI 2019, but with a fallback in place of its exactness proof.
 *
 * Where 10^q is a double (10^-6 <= |v| < 10^17, most of a ray file),
 * printing forms v 10^q exactly as a product and its fused multiply-add
 * remainder instead, which decides every rounding (round17_fma).
 * numfmt_g17_n does that on eight lanes at once on AVX-512, further down
 * (to q = 47) with 10^q as two doubles, handing a lane within its error
 * bound of a tie to numfmt_g17.  The digits come eight at a time from
 * multiplies and shifts in one word (digits8_word), never a division. */
#include "numfmt.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

typedef struct numfmt_pow10 {
    uint64_t hi, lo;
    int32_t t; /* 10^q ~ (hi 2^64 + lo) 2^t */
} numfmt_pow10;

#include "numfmt_pow10.h"

__extension__ typedef unsigned __int128 u128;

/* floor(w P / 2^64) for P the table's 10^q: w must be below 2^64. */
static u128 mul_pow10(uint64_t w, int q, int *t)
{
    const numfmt_pow10 *p = &numfmt_pow10_tab[q - NUMFMT_QMIN];
    u128 hi = (u128)w * p->hi;
    u128 lo = (u128)w * p->lo;
    *t = p->t + 64;
    return hi + (lo >> 64);
}

static int clz128(u128 h)
{
    uint64_t hi = (uint64_t)(h >> 64);
    return hi ? __builtin_clzll(hi) : 64 + __builtin_clzll((uint64_t)h);
}

/* The eight digits of x < 10^8 as ASCII bytes in a word, first digit in
 * the lowest byte (memory order on a little-endian machine), with no
 * division: each step splits every lane by a multiply and shift that is
 * exact for the lane's range (v / 100 = v 10486 >> 20 for v < 10^4,
 * v / 10 = v 103 >> 10 for v < 100).  D. Lemire, "Converting integers to
 * fixed-digit representations quickly" (2021); test_numfmt checks every
 * x below 10^8.  Inlined: a call would cost as much as the work. */
static inline __attribute__((always_inline)) uint64_t digits8_word(uint32_t x)
{
    /* x / 10^4 as x ceil(2^40 / 10^4) >> 40, which the 8-lane path
     * uses too (it has no division). */
    uint64_t q4 = ((uint64_t)x * 109951163) >> 40;
    uint64_t merged = q4 | (((uint64_t)x - 10000 * q4) << 32);
    uint64_t top = ((merged * 10486) >> 20) & ((UINT64_C(0x7f) << 32) | UINT64_C(0x7f));
    uint64_t bot = merged - 100 * top;
    uint64_t hundreds = (bot << 16) + top;
    uint64_t tens = (hundreds * 103) >> 10;
    tens &= (UINT64_C(0xf) << 48) | (UINT64_C(0xf) << 32) | (UINT64_C(0xf) << 16) | 0xf;
    tens += (hundreds - 10 * tens) << 8;
    return tens;
}

void numfmt_digits8(uint32_t x, char out[8])
{
    uint64_t w = digits8_word(x) + UINT64_C(0x3030303030303030);
    memcpy(out, &w, 8);
}

static size_t fallback_g17(double v, char *buf)
{
    int n = snprintf(buf, NUMFMT_G17_MAX, "%.17g", v);
    return n > 0 ? (size_t)n : 0;
}

/* 10^0 .. 10^22, each exact in a double. */
static const double exact_pow10[23] = {
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};

/* The same for 10^-6 <= v < 10^17 (q = 16 - k in 0..22), where 10^q is
 * a double: v 10^q = hi + lo exactly (hi = v 10^q rounded, lo by one fused
 * multiply-add, |lo| <= ulp(hi) / 2), and hi >= 2^53 is an even integer,
 * so N = hi + lo rounded half to even = hi + (lo rounded half to even):
 * exact, with no case left undecided.  0 outside that range. */
static int round17_fma(double v, int kk, uint64_t *n, int *k)
{
    int q = 16 - kk;
    while (q >= 0 && q <= 22) {
        double hi = v * exact_pow10[q], lo = fma(v, exact_pow10[q], -hi);
        /* lo to the nearest integer, ties to even (|lo| <= 8 << 2^51). */
        double r = (lo + 0x1.8p52) - 0x1.8p52;
        uint64_t nn = (uint64_t)hi + (uint64_t)(int64_t)r;
        if (nn > UINT64_C(100000000000000000)) {
            /* v >= 10^(k+1): one digit more before the point. */
            q--;
            continue;
        }
        if (nn == UINT64_C(100000000000000000)) {
            /* Rounded up to 10^17: 1 followed by zeros, one place on. */
            *n = UINT64_C(10000000000000000);
            *k = 16 - q + 1;
            return 1;
        }
        *n = nn;
        *k = 16 - q;
        return 1;
    }
    return 0;
}

/* The 17 correctly rounded digits N (10^16 <= N < 10^17) and decimal
 * exponent k of v = W 2^e (W >= 2^63), v = N 10^(k-16) rounded; 0 when
 * the product cannot decide the rounding. */
static int round17(uint64_t w, int e, int kk, uint64_t *n, int *k)
{
    int guard;
    for (guard = 0; guard < 4; guard++) {
        int q = 16 - kk, t, sh;
        u128 h, rem, half;
        uint64_t n0;
        if (q < NUMFMT_QMIN || q > NUMFMT_QMAX)
            return 0;
        h = mul_pow10(w, q, &t);
        /* v 10^q = h 2^(e + t), to less than 2 units of h. */
        sh = -(e + t);
        if (sh < 2 || sh > 120)
            return 0;
        n0 = (uint64_t)(h >> sh);
        if (n0 < UINT64_C(10000000000000000)) {
            kk--;
            continue;
        }
        if (n0 >= UINT64_C(100000000000000000)) {
            kk++;
            continue;
        }
        rem = h & (((u128)1 << sh) - 1);
        half = (u128)1 << (sh - 1);
        /* The exact remainder lies in [rem, rem + 2). */
        if (rem + 2 <= half) {
            *n = n0;
        } else if (rem > half) {
            *n = n0 + 1;
        } else {
            return 0;
        }
        if (*n == UINT64_C(100000000000000000)) {
            *n = UINT64_C(10000000000000000);
            kk++;
        }
        *k = kk;
        return 1;
    }
    return 0;
}

/* The text of N = d0 w1 w2 (one digit, two words of eight digit values,
 * first digit in the lowest byte) times 10^(k-16), as %.17g writes it,
 * at p (after any sign); returns the end, where it puts a NUL. */
static inline __attribute__((always_inline)) char *layout17(char *p, uint32_t d0, uint64_t w1,
                                                            uint64_t w2, int k)
{
    int last;
    /* The last non-zero digit: a zero digit is a zero byte, and the
     * word's high bytes are its last digits. */
    if (w2)
        last = 16 - __builtin_clzll(w2) / 8;
    else if (w1)
        last = 8 - __builtin_clzll(w1) / 8;
    else
        last = 0;
    w1 += UINT64_C(0x3030303030303030);
    w2 += UINT64_C(0x3030303030303030);
    /* Stores only, each word written whole (no reload of bytes just
     * stored); bytes past the end are scratch within NUMFMT_G17_MAX. */
    if (k < -4 || k >= 17) {
        unsigned x = (unsigned)(k < 0 ? -k : k);
        uint64_t ex;
        p[0] = (char)('0' + d0);
        p[1] = '.';
        memcpy(p + 2, &w1, 8);
        memcpy(p + 10, &w2, 8);
        p += last > 0 ? last + 2 : 1;
        /* "e-dd" or "e-ddd" in one word, first byte lowest. */
        ex = (uint64_t)'e' | (uint64_t)(k < 0 ? '-' : '+') << 8;
        if (x >= 100) {
            ex |= (uint64_t)('0' + x / 100) << 16 | (uint64_t)('0' + x / 10 % 10) << 24 |
                  (uint64_t)('0' + x % 10) << 32;
            memcpy(p, &ex, 8);
            p += 5;
        } else {
            ex |= (uint64_t)('0' + x / 10) << 16 | (uint64_t)('0' + x % 10) << 24;
            memcpy(p, &ex, 8);
            p += 4;
        }
    } else if (k >= 0) {
        p[0] = (char)('0' + d0);
        memcpy(p + 1, &w1, 8);
        memcpy(p + 9, &w2, 8);
        if (last > k) {
            /* The digits after the point move one place on; k < 16. */
            if (k < 8) {
                uint64_t t = w1 >> (8 * k);
                memcpy(p + k + 2, &t, 8);
                memcpy(p + 10, &w2, 8);
            } else {
                uint64_t t = w2 >> (8 * (k - 8));
                memcpy(p + k + 2, &t, 8);
            }
            p[k + 1] = '.';
            p += last + 2;
        } else {
            p += k + 1;
        }
    } else {
        memcpy(p, "0.000000", 8);
        p[1 - k] = (char)('0' + d0);
        memcpy(p + 2 - k, &w1, 8);
        memcpy(p + 10 - k, &w2, 8);
        p += 1 - k + last + 1;
    }
    *p = '\0';
    return p;
}

size_t numfmt_g17(double v, char *buf)
{
    uint64_t bits, m, n, w1, w2;
    int e, k, lz;
    uint32_t d0, hi8, lo8;
    char *p = buf;

    memcpy(&bits, &v, sizeof bits);
    m = bits & ((UINT64_C(1) << 52) - 1);
    e = (int)((bits >> 52) & 0x7ff);
    if (e == 0x7ff) {
        if (m == 0) {
            /* glibc's %.17g of an infinity, without its cost. */
            if (bits >> 63) {
                memcpy(buf, "-inf", 5);
                return 4;
            }
            memcpy(buf, "inf", 4);
            return 3;
        }
        return fallback_g17(v, buf);
    }
    if (bits >> 63)
        *p++ = '-';
    if (e == 0) {
        if (m == 0) {
            *p++ = '0';
            *p = '\0';
            return (size_t)(p - buf);
        }
        e = -1074;
    } else {
        m |= UINT64_C(1) << 52;
        e -= 1075;
    }
    lz = __builtin_clzll(m);
    m <<= lz;
    e -= lz;
    {
        /* floor((e + 63) log10 2) (exact for |e + 63| < 1650): the decimal
         * exponent of 2^(e+63) <= |v|; |v|'s own is that or one more. */
        int kk = ((e + 63) * 78913) >> 18;
        if (!round17_fma(fabs(v), kk, &n, &k) && !round17(m, e, kk, &n, &k))
            return fallback_g17(v, buf);
    }
    /* The digits: one, then two words of eight. */
    d0 = (uint32_t)(n / UINT64_C(10000000000000000));
    n -= (uint64_t)d0 * UINT64_C(10000000000000000);
    hi8 = (uint32_t)(n / 100000000);
    lo8 = (uint32_t)(n - (uint64_t)hi8 * 100000000);
    w1 = digits8_word(hi8);
    w2 = digits8_word(lo8);
    return (size_t)(layout17(p, d0, w1, w2, k) - buf);
}

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define NUMFMT_X8 1

#define X8_TARGET __attribute__((target("avx512f,avx512dq")))

/* digits8_word on eight lanes of 64 bits, by the same multiplies. */
X8_TARGET static inline __m512i digits8_x8(__m512i x)
{
    const __m512i m7 = _mm512_set1_epi64((INT64_C(0x7f) << 32) | 0x7f);
    const __m512i m4 = _mm512_set1_epi64((INT64_C(0xf) << 48) | (INT64_C(0xf) << 32) |
                                         (INT64_C(0xf) << 16) | 0xf);
    __m512i q4 = _mm512_srli_epi64(_mm512_mullo_epi64(x, _mm512_set1_epi64(109951163)), 40);
    __m512i r4 = _mm512_sub_epi64(x, _mm512_mullo_epi64(q4, _mm512_set1_epi64(10000)));
    __m512i merged = _mm512_or_si512(q4, _mm512_slli_epi64(r4, 32));
    __m512i top = _mm512_and_si512(
        _mm512_srli_epi64(_mm512_mullo_epi64(merged, _mm512_set1_epi64(10486)), 20), m7);
    __m512i bot = _mm512_sub_epi64(merged, _mm512_mullo_epi64(top, _mm512_set1_epi64(100)));
    __m512i hundreds = _mm512_add_epi64(_mm512_slli_epi64(bot, 16), top);
    __m512i tens = _mm512_and_si512(
        _mm512_srli_epi64(_mm512_mullo_epi64(hundreds, _mm512_set1_epi64(103)), 10), m4);
    __m512i ones = _mm512_sub_epi64(hundreds, _mm512_mullo_epi64(tens, _mm512_set1_epi64(10)));
    return _mm512_add_epi64(tens, _mm512_slli_epi64(ones, 8));
}

/* x / d and its remainder *r, from an estimate q of the quotient off by
 * at most one, put right by the remainder's sign and size. */
X8_TARGET static inline __m512i divmod_x8(__m512i x, __m512i q, __m512i d, __m512i *r)
{
    const __m512i zero = _mm512_setzero_si512(), one = _mm512_set1_epi64(1);
    __m512i rem = _mm512_sub_epi64(x, _mm512_mullo_epi64(q, d));
    __mmask8 lo = _mm512_cmp_epi64_mask(rem, zero, _MM_CMPINT_LT), hi;
    q = _mm512_mask_sub_epi64(q, lo, q, one);
    rem = _mm512_mask_add_epi64(rem, lo, rem, d);
    /* rem == d would need an exact multiple estimated one low, which no
     * multiple of 10^16 or 10^8 formed here is (checked for all of them);
     * >= keeps the step right regardless. */
    hi = _mm512_cmp_epi64_mask(rem, d, _MM_CMPINT_GE);
    q = _mm512_mask_add_epi64(q, hi, q, one);
    *r = _mm512_mask_sub_epi64(rem, hi, rem, d);
    return q;
}

/* N = v 10^q rounded, for eight lanes with 0 <= q <= 47: hi = v P1
 * rounded and t = v P2 + (v P1 - hi) by fused multiply-adds, where
 * 10^q = P1 + P2 + d (gen_pow10.c).  For q <= 22, P2 = d = 0 and t is
 * exact, as in round17_fma.  Beyond, |v 10^q - hi - t| <= v |d| + ulp(t)/2
 * < 4e-14 (v 10^q < 10^18, |d| <= 2^-106 10^q, |t| < 2^8), and *unsure
 * marks the lanes whose t lies that close to a half. */
X8_TARGET static inline __m512i n17_x8(__m512d a, __m512i q, __mmask8 *unsure)
{
    const __m512d magic = _mm512_set1_pd(0x1.8p52);
    __m512d p1 = _mm512_i64gather_pd(q, numfmt_pow10_dd[0], 8);
    __m512d p2 = _mm512_i64gather_pd(q, numfmt_pow10_dd[1], 8);
    __m512d hi = _mm512_mul_pd(a, p1);
    __m512d t = _mm512_fmadd_pd(a, p2, _mm512_fmsub_pd(a, p1, hi));
    __m512d r = _mm512_sub_pd(_mm512_add_pd(t, magic), magic);
    /* |t - r| is 1/2 within the bound: the rounding is not known. */
    __m512d off = _mm512_abs_pd(_mm512_sub_pd(_mm512_abs_pd(_mm512_sub_pd(t, r)),
                                              _mm512_set1_pd(0.5)));
    *unsure = _mm512_cmp_epu64_mask(q, _mm512_set1_epi64(22), _MM_CMPINT_GT) &
              _mm512_cmp_pd_mask(off, _mm512_set1_pd(4e-14), _CMP_LE_OQ);
    return _mm512_add_epi64(_mm512_cvttpd_epu64(hi), _mm512_cvttpd_epi64(r));
}

/* Eight numbers into eight slots: the lanes with about 10^-31 <= |v| <
 * 10^17 (0 <= q <= 47) by n17_x8 on all eight at once, the others and the
 * few it is unsure of by numfmt_g17; the digits of all by digits8_x8; the text by layout17. */
X8_TARGET static void g17_x8(const double *v, char *out, unsigned char *len)
{
    const __m512i e16 = _mm512_set1_epi64(INT64_C(10000000000000000));
    const __m512i e17 = _mm512_set1_epi64(INT64_C(100000000000000000));
    const __m512i e8 = _mm512_set1_epi64(100000000);
    const __m512i zero = _mm512_setzero_si512(), one = _mm512_set1_epi64(1);
    __m512d x = _mm512_loadu_pd(v), a = _mm512_abs_pd(x);
    __m512i e2, kk, q, n, d0, r, hi8, lo8, k;
    __mmask8 ok, big, top, unsure;
    uint64_t W1[8], W2[8], D0[8];
    int64_t K[8];
    int i;

    /* The ordered compares leave out NaN, infinities, zeros, subnormals. */
    ok = _mm512_cmp_pd_mask(a, _mm512_set1_pd(1e-33), _CMP_GE_OQ) &
         _mm512_cmp_pd_mask(a, _mm512_set1_pd(1e18), _CMP_LT_OQ);
    e2 = _mm512_sub_epi64(_mm512_srli_epi64(_mm512_castpd_si512(a), 52),
                          _mm512_set1_epi64(1023));
    kk = _mm512_srai_epi64(_mm512_mullo_epi64(e2, _mm512_set1_epi64(78913)), 18);
    q = _mm512_sub_epi64(_mm512_set1_epi64(16), kk);
    ok &= _mm512_cmp_epu64_mask(q, _mm512_set1_epi64(NUMFMT_DDMAX), _MM_CMPINT_LE);
    if (!ok) {
        /* None on this path (a run of error bounds, say). */
        for (i = 0; i < 8; i++)
            len[i] = (unsigned char)numfmt_g17(v[i], out + (size_t)i * NUMFMT_G17_MAX);
        return;
    }
    q = _mm512_maskz_mov_epi64(ok, q);
    n = n17_x8(a, q, &unsure);
    /* v >= 10^(k+1): one place on, as round17_fma's loop. */
    big = _mm512_cmp_epu64_mask(n, e17, _MM_CMPINT_GT) & ok;
    ok &= ~(unsure & ~big);
    if (big) {
        ok &= ~(big & _mm512_cmp_epi64_mask(q, zero, _MM_CMPINT_EQ));
        q = _mm512_mask_sub_epi64(q, big & ok, q, one);
        n = _mm512_mask_mov_epi64(n, big & ok, n17_x8(a, q, &unsure));
        ok &= ~(big & unsure);
        ok &= ~_mm512_cmp_epu64_mask(n, e17, _MM_CMPINT_GT);
    }
    k = _mm512_sub_epi64(_mm512_set1_epi64(16), q);
    /* Rounded up to 10^17: 1 followed by zeros, one place on. */
    top = _mm512_cmp_epu64_mask(n, e17, _MM_CMPINT_EQ);
    n = _mm512_mask_mov_epi64(n, top, e16);
    k = _mm512_mask_add_epi64(k, top, k, one);
    /* d0 = n / 10^16 and hi8 = r / 10^8, each estimated by a double
     * product. */
    d0 = divmod_x8(n, _mm512_cvttpd_epi64(_mm512_mul_pd(_mm512_cvtepu64_pd(n),
                                                         _mm512_set1_pd(1e-16))),
                   e16, &r);
    hi8 = divmod_x8(r, _mm512_cvttpd_epi64(_mm512_mul_pd(_mm512_cvtepi64_pd(r),
                                                         _mm512_set1_pd(1e-8))),
                    e8, &lo8);
    /* Lanes outside the path hold anything: keep their digit words sane. */
    hi8 = _mm512_maskz_mov_epi64(ok, hi8);
    lo8 = _mm512_maskz_mov_epi64(ok, lo8);
    _mm512_storeu_si512(W1, digits8_x8(hi8));
    _mm512_storeu_si512(W2, digits8_x8(lo8));
    _mm512_storeu_si512(D0, d0);
    _mm512_storeu_si512(K, k);
    for (i = 0; i < 8; i++) {
        char *p = out + (size_t)i * NUMFMT_G17_MAX;
        if (ok >> i & 1) {
            char *q0 = p;
            if (v[i] < 0)
                *p++ = '-';
            len[i] = (unsigned char)(layout17(p, (uint32_t)D0[i], W1[i], W2[i], (int)K[i]) - q0);
        } else {
            len[i] = (unsigned char)numfmt_g17(v[i], p);
        }
    }
}
#endif

void numfmt_g17_n(const double *v, size_t n, char *out, unsigned char *len)
{
    size_t i = 0;
#ifdef NUMFMT_X8
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")) {
        for (; i + 8 <= n; i += 8)
            g17_x8(v + i, out + i * NUMFMT_G17_MAX, len + i);
        if (i < n) {
            /* The last few through a padded copy. */
            double t[8] = { 1, 1, 1, 1, 1, 1, 1, 1 };
            char slot[8 * NUMFMT_G17_MAX];
            unsigned char tl[8];
            size_t j;
            memcpy(t, v + i, (n - i) * sizeof *t);
            g17_x8(t, slot, tl);
            for (j = 0; i + j < n; j++) {
                memcpy(out + (i + j) * NUMFMT_G17_MAX, slot + j * NUMFMT_G17_MAX,
                       NUMFMT_G17_MAX);
                len[i + j] = tl[j];
            }
            i = n;
        }
    }
#endif
    for (; i < n; i++)
        len[i] = (unsigned char)numfmt_g17(v[i], out + i * NUMFMT_G17_MAX);
}


/* ------------------------------------------------------------------------
 * The shortest decimal that reads back as v: R. Giulietti, "The Schubfach
 * way to render doubles" (2020), the algorithm of Java's Double.toString
 * since JDK 19.  The rounding interval of v = c 2^q is scaled by 4 and by
 * g ~ 10^-k 2^-r, a 126-bit upper approximation of a power of ten (here
 * floor(P / 4) + 1 from gen_pow10.c's truncation P); rop() keeps the top
 * 64 bits of each product with a sticky bit, which the paper proves
 * enough to decide, without a fallback, which of the candidates s, s + 1
 * (and their multiples of ten) lie in the interval.  Of those, the one
 * with fewer digits wins, then the one closer to v, then an even last
 * digit.  tests/cli/test_numfmt.c checks it against an exact search in GMP
 * rationals on edge and random bit patterns.
 * ------------------------------------------------------------------------ */

#define SF_MASK63 ((UINT64_C(1) << 63) - 1)

static inline uint64_t mulhi64(uint64_t a, uint64_t b)
{
    return (uint64_t)(((u128)a * b) >> 64);
}

/* floor(g cp / 2^127) with a sticky bit for what the floor dropped. */
static uint64_t rop(uint64_t g1, uint64_t g0, uint64_t cp)
{
    uint64_t x1 = mulhi64(g0, cp);
    uint64_t y0 = g1 * cp;
    uint64_t y1 = mulhi64(g1, cp);
    uint64_t z = (y0 >> 1) + x1;
    uint64_t vbp = y1 + (z >> 63);
    return vbp | (((z & SF_MASK63) + SF_MASK63) >> 63);
}

/* floor(q log10 2), floor(log10(3/4 2^q)) and floor(e log2 10), exact on
 * the ranges used (the paper's constants; GCC shifts a negative value
 * arithmetically). */
static inline int flog10pow2(int q)
{
    return (int)(((int64_t)q * INT64_C(661971961083)) >> 41);
}

static inline int flog10three_quarters_pow2(int q)
{
    return (int)(((int64_t)q * INT64_C(661971961083) - INT64_C(274743187321)) >> 41);
}

static inline int flog2pow10(int e)
{
    return (int)(((int64_t)e * INT64_C(913124641741)) >> 38);
}

/* The decimal f 10^e for v = c 2^q (c >= 3). */
static void sf_decimal(int q, uint64_t c, uint64_t *f, int *e)
{
    const uint64_t c_min = UINT64_C(1) << 52;
    uint64_t out = c & 1, cb = c << 2, cbr = cb + 2, cbl, g1, g0, vb, vbl, vbr, s, t;
    const numfmt_pow10 *p;
    int k, h;
    if (c != c_min || q == -1074) {
        cbl = cb - 2;
        k = flog10pow2(q);
    } else {
        cbl = cb - 1;
        k = flog10three_quarters_pow2(q);
    }
    h = q + flog2pow10(-k) + 2;
    p = &numfmt_pow10_tab[-k - NUMFMT_QMIN];
    /* g = floor(10^-k / 2^r) + 1 in [2^125, 2^126): the table's 128-bit
     * floor of 10^-k / 2^t, shifted by two more. */
    {
        u128 gg = ((((u128)p->hi << 64) | p->lo) >> 2) + 1;
        g1 = (uint64_t)(gg >> 63);
        g0 = (uint64_t)gg & SF_MASK63;
    }
    vb = rop(g1, g0, cb << h);
    vbl = rop(g1, g0, cbl << h);
    vbr = rop(g1, g0, cbr << h);
    s = vb >> 2;
    /* Java tries one digit fewer only from s >= 100, since its toString
     * shows two digits at least; a small subnormal's s can be shorter. */
    if (s >= 10) {
        /* s rounded down to a multiple of ten, and the next one. */
        uint64_t sp10 = 10 * mulhi64(s, UINT64_C(115292150460684698) << 4);
        uint64_t tp10 = sp10 + 10;
        int upin = vbl + out <= sp10 << 2;
        int wpin = (tp10 << 2) + out <= vbr;
        if (upin != wpin) {
            *f = upin ? sp10 : tp10;
            *e = k;
            return;
        }
    }
    t = s + 1;
    {
        int uin = vbl + out <= s << 2;
        int win = (t << 2) + out <= vbr;
        if (uin != win) {
            *f = uin ? s : t;
            *e = k;
            return;
        }
    }
    {
        /* Both in: the closer, or the even one at a tie. */
        int64_t cmp = (int64_t)(vb - ((s + t) << 1));
        *f = cmp < 0 || (cmp == 0 && (s & 1) == 0) ? s : t;
        *e = k;
    }
}

int numfmt_shortest_decimal(double v, uint64_t *f, int *e)
{
    uint64_t bits, t, c;
    int bq, mq;
    memcpy(&bits, &v, sizeof bits);
    t = bits & ((UINT64_C(1) << 52) - 1);
    bq = (int)((bits >> 52) & 0x7ff);
    if (bq == 0x7ff)
        return 0;
    if (bq != 0) {
        mq = 1075 - bq;
        c = (UINT64_C(1) << 52) | t;
        /* An integer below 2^53 is its own shortest decimal. */
        if (mq > 0 && mq < 53 && (c >> mq) << mq == c) {
            *f = c >> mq;
            *e = 0;
        } else {
            sf_decimal(-mq, c, f, e);
        }
    } else if (t >= 3) {
        sf_decimal(-1074, t, f, e);
    } else if (t != 0) {
        /* The two smallest subnormals lie below the scaled powers' range;
         * Java scales their c by ten and prints two digits (4.9E-324),
         * but one reads back: 5e-324 and 1e-323, the closest of each's
         * one-digit decimals. */
        *f = t == 1 ? 5 : 1;
        *e = t == 1 ? -324 : -323;
        return 1;
    } else {
        *f = 0;
        *e = 0;
        return 1;
    }
    while (*f % 10 == 0) {
        *f /= 10;
        (*e)++;
    }
    return 1;
}

/* The digits of f (no trailing zeros, 1 to 17 of them) into d; returns
 * their count. */
static int sf_digits(uint64_t f, char d[20])
{
    char tmp[20];
    int n = 0, i;
    do {
        tmp[n++] = (char)('0' + f % 10);
        f /= 10;
    } while (f);
    for (i = 0; i < n; i++)
        d[i] = tmp[n - 1 - i];
    return n;
}

/* The shortest decimal of v as text: in %g's layout (an exponent below
 * 1e-4 or from as many digits as it has), or with plain set, positional
 * at any size.  An infinity or NaN is %g's. */
static size_t shortest_text(double v, char *buf, int plain)
{
    uint64_t f;
    int e, n, x, i;
    char d[20], *p = buf;
    if (isnan(v) || isinf(v))
        return (size_t)snprintf(buf, NUMFMT_SHORTEST_MAX, "%g", v);
    if (signbit(v))
        *p++ = '-';
    numfmt_shortest_decimal(v, &f, &e);
    if (f == 0) {
        *p++ = '0';
        *p = '\0';
        return (size_t)(p - buf);
    }
    n = sf_digits(f, d);
    x = e + n - 1; /* the exponent of the first digit */
    if (!plain && (x < -4 || x >= n)) {
        /* %.{n}g's exponent form: d[.ddd]e+XX, at least two digits. */
        int ax = x < 0 ? -x : x;
        *p++ = d[0];
        if (n > 1) {
            *p++ = '.';
            for (i = 1; i < n; i++)
                *p++ = d[i];
        }
        *p++ = 'e';
        *p++ = x < 0 ? '-' : '+';
        if (ax >= 100)
            *p++ = (char)('0' + ax / 100);
        *p++ = (char)('0' + ax / 10 % 10);
        *p++ = (char)('0' + ax % 10);
    } else if (x >= 0) {
        /* Integer digits (zeros past the last significant one), then any
         * fraction. */
        for (i = 0; i <= x; i++)
            *p++ = i < n ? d[i] : '0';
        if (n > x + 1) {
            *p++ = '.';
            for (i = x + 1; i < n; i++)
                *p++ = d[i];
        }
    } else {
        *p++ = '0';
        *p++ = '.';
        for (i = 0; i < -x - 1; i++)
            *p++ = '0';
        for (i = 0; i < n; i++)
            *p++ = d[i];
    }
    *p = '\0';
    return (size_t)(p - buf);
}

size_t numfmt_shortest_g(double v, char *buf)
{
    return shortest_text(v, buf, 0);
}

size_t numfmt_shortest_f(double v, char *buf)
{
    /* Past 1e300 the digits would outgrow NUMFMT_SHORTEST_MAX. */
    return shortest_text(v, buf, fabs(v) < 1e300);
}

int numfmt_parse(const char *s, size_t n, double *out)
{
    double v;
    if (numfmt_parse_to(s, s + n, &v) != s + n)
        return 0;
    *out = v;
    return 1;
}

const char *numfmt_parse_to(const char *s, const char *end, double *out)
{
    uint64_t w = 0, bits, m;
    int neg = 0, nd = 0, any = 0, e2, lz, t, sh;
    long q = 0;
    u128 h, rem, half;

    if (s < end && (*s == '+' || *s == '-'))
        neg = *s++ == '-';
    /* Up to 19 significant digits fit w exactly; a later non-zero digit
     * would make w a truncation, so that text goes to strtod. */
    for (; s < end && *s >= '0' && *s <= '9'; s++) {
        any = 1;
        if (w == 0 && *s == '0')
            continue;
        if (nd < 19) {
            w = w * 10 + (uint64_t)(*s - '0');
            nd++;
        } else if (*s != '0') {
            return NULL;
        } else {
            q++;
        }
    }
    if (s < end && *s == '.') {
        for (s++; s < end && *s >= '0' && *s <= '9'; s++) {
            any = 1;
            if (w == 0 && *s == '0') {
                q--;
                continue;
            }
            if (nd < 19) {
                w = w * 10 + (uint64_t)(*s - '0');
                nd++;
                q--;
            } else if (*s != '0') {
                return NULL;
            }
        }
    }
    if (!any)
        return NULL;
    if (s < end && (*s == 'e' || *s == 'E')) {
        int eneg = 0, edig = 0;
        long x = 0;
        s++;
        if (s < end && (*s == '+' || *s == '-'))
            eneg = *s++ == '-';
        for (; s < end && *s >= '0' && *s <= '9'; s++, edig++)
            if (x < 100000)
                x = x * 10 + (*s - '0');
        if (!edig)
            return NULL;
        q += eneg ? -x : x;
    }
    if (w == 0) {
        *out = neg ? -0.0 : 0.0;
        return s;
    }
    /* Clinger: w and 10^|q| are exact doubles, so one rounding. */
    if (w <= (UINT64_C(1) << 53) && q >= -22 && q <= 22) {
        double v = (double)w;
        v = q >= 0 ? v * exact_pow10[q] : v / exact_pow10[-q];
        *out = neg ? -v : v;
        return s;
    }
    if (q < -330 || q > 310)
        return NULL;
    lz = __builtin_clzll(w);
    h = mul_pow10(w << lz, (int)q, &t);
    /* w 10^q = h 2^(t - lz), to less than 2 units of h; keep 53 bits. */
    sh = 128 - clz128(h) - 53;
    m = (uint64_t)(h >> sh);
    rem = h & (((u128)1 << sh) - 1);
    half = (u128)1 << (sh - 1);
    if (rem + 2 <= half)
        ;
    else if (rem > half)
        m++;
    else
        return NULL;
    e2 = t - lz + sh;
    if (m == (UINT64_C(1) << 53)) {
        m >>= 1;
        e2++;
    }
    /* value = m 2^e2 with 2^52 <= m < 2^53; normal range only. */
    if (e2 + 52 < -1022 || e2 + 52 > 1023)
        return NULL;
    bits = ((uint64_t)(e2 + 52 + 1023) << 52) | (m & ((UINT64_C(1) << 52) - 1));
    if (neg)
        bits |= UINT64_C(1) << 63;
    memcpy(out, &bits, sizeof bits);
    return s;
}
