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
 * PLDI 2019, but with a fallback in place of its exactness proof. */
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

static const char digit_pairs[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* The 17 digits of n (10^16 <= n < 10^17). */
static void digits17(uint64_t n, char *d)
{
    int i = 17;
    while (i > 1) {
        unsigned r = (unsigned)(n % 100);
        n /= 100;
        d[--i] = digit_pairs[2 * r + 1];
        d[--i] = digit_pairs[2 * r];
    }
    d[0] = (char)('0' + n);
}

static size_t fallback_g17(double v, char *buf)
{
    int n = snprintf(buf, NUMFMT_G17_MAX, "%.17g", v);
    return n > 0 ? (size_t)n : 0;
}

/* The 17 correctly rounded digits N (10^16 <= N < 10^17) and decimal
 * exponent k of v = W 2^e (W >= 2^63), v = N 10^(k-16) rounded; 0 when
 * the product cannot decide the rounding. */
static int round17(uint64_t w, int e, uint64_t *n, int *k)
{
    int kk = (int)floor((double)(e + 63) * 0.30102999566398120);
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

size_t numfmt_g17(double v, char *buf)
{
    uint64_t bits, m, n;
    int e, k, lz, last, i;
    char d[17], *p = buf;

    memcpy(&bits, &v, sizeof bits);
    m = bits & ((UINT64_C(1) << 52) - 1);
    e = (int)((bits >> 52) & 0x7ff);
    if (e == 0x7ff)
        return fallback_g17(v, buf);
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
    if (!round17(m, e, &n, &k))
        return fallback_g17(v, buf);
    digits17(n, d);
    for (last = 16; last > 0 && d[last] == '0'; last--)
        ;
    if (k < -4 || k >= 17) {
        unsigned x = (unsigned)(k < 0 ? -k : k);
        *p++ = d[0];
        if (last > 0) {
            *p++ = '.';
            memcpy(p, d + 1, (size_t)last);
            p += last;
        }
        *p++ = 'e';
        *p++ = k < 0 ? '-' : '+';
        if (x >= 100)
            *p++ = (char)('0' + x / 100);
        *p++ = (char)('0' + x / 10 % 10);
        *p++ = (char)('0' + x % 10);
    } else if (k >= 0) {
        memcpy(p, d, (size_t)k + 1);
        p += k + 1;
        if (last > k) {
            *p++ = '.';
            memcpy(p, d + k + 1, (size_t)(last - k));
            p += last - k;
        }
    } else {
        *p++ = '0';
        *p++ = '.';
        for (i = 0; i < -k - 1; i++)
            *p++ = '0';
        memcpy(p, d, (size_t)last + 1);
        p += last + 1;
    }
    *p = '\0';
    return (size_t)(p - buf);
}

/* 10^0 .. 10^22, each exact in a double. */
static const double exact_pow10[23] = {
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};

int numfmt_parse(const char *s, size_t n, double *out)
{
    const char *end = s + n;
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
            return 0;
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
                return 0;
            }
        }
    }
    if (!any)
        return 0;
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
            return 0;
        q += eneg ? -x : x;
    }
    if (s != end)
        return 0;
    if (w == 0) {
        *out = neg ? -0.0 : 0.0;
        return 1;
    }
    /* Clinger: w and 10^|q| are exact doubles, so one rounding. */
    if (w <= (UINT64_C(1) << 53) && q >= -22 && q <= 22) {
        double v = (double)w;
        v = q >= 0 ? v * exact_pow10[q] : v / exact_pow10[-q];
        *out = neg ? -v : v;
        return 1;
    }
    if (q < -330 || q > 310)
        return 0;
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
        return 0;
    e2 = t - lz + sh;
    if (m == (UINT64_C(1) << 53)) {
        m >>= 1;
        e2++;
    }
    /* value = m 2^e2 with 2^52 <= m < 2^53; normal range only. */
    if (e2 + 52 < -1022 || e2 + 52 > 1023)
        return 0;
    bits = ((uint64_t)(e2 + 52 + 1023) << 52) | (m & ((UINT64_C(1) << 52) - 1));
    if (neg)
        bits |= UINT64_C(1) << 63;
    memcpy(out, &bits, sizeof bits);
    return 1;
}
