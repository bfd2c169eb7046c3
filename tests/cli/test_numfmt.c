/* test_numfmt.c - ui/numfmt.c against the C library it must equal:
 * numfmt_g17 against glibc's snprintf("%.17g") byte for byte, numfmt_parse
 * against glibc's strtod bit for bit (both exact, the independent source);
 * and numfmt_shortest_decimal (Schubfach) against an exact search in GMP
 * rationals for the decimal with the fewest digits in the rounding
 * interval, the closest to v of those, and its texts against strtod.
 * Random bit patterns, 2e6 a direction by default; NUMFMT_COUNT sets the
 * count for a long run. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include <gmp.h>

#include "numfmt.h"

static uint64_t rng = UINT64_C(0x9e3779b97f4a7c15);

/* xorshift64*: a fixed seed, so a failure repeats. */
static uint64_t next(void)
{
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return rng * UINT64_C(2685821657736338717);
}

static double from_bits(uint64_t b)
{
    double v;
    memcpy(&v, &b, sizeof v);
    return v;
}

static long count(void)
{
    const char *e = getenv("NUMFMT_COUNT");
    long n = e && e[0] ? atol(e) : 2000000;
    return n > 0 ? n : 2000000;
}

static long fmt_failures;

static void check_fmt(double v)
{
    char want[64], got[NUMFMT_G17_MAX + 8];
    size_t n;
    snprintf(want, sizeof want, "%.17g", v);
    memset(got, 'X', sizeof got);
    n = numfmt_g17(v, got);
    if (strcmp(want, got) != 0 || n != strlen(want)) {
        if (fmt_failures++ < 10)
            print_error("%%.17g of %a: want \"%s\", got \"%s\"\n", v, want, got);
    }
}

static long parse_failures, parse_fast;

/* The text must read as strtod reads it, or be handed back (0); and
 * followed by a comma and more (a CSV row), numfmt_parse_to must stop at
 * the comma with the same value, or hand it back too. */
static void check_parse(const char *s)
{
    double want = strtod(s, NULL), got, got2;
    size_t n = strlen(s);
    char row[128];
    const char *stop;
    int fast = numfmt_parse(s, n, &got);
    if (fast) {
        parse_fast++;
        if (memcmp(&want, &got, sizeof got) != 0 && parse_failures++ < 10)
            print_error("\"%s\": strtod %a, numfmt_parse %a\n", s, want, got);
    }
    if (n + 8 > sizeof row)
        return;
    memcpy(row, s, n);
    memcpy(row + n, ",0.5,x", 7);
    /* Where it stops elsewhere, the caller sees no comma there (or a
     * comma inside the text, which a CSV field cannot hold). */
    stop = numfmt_parse_to(row, row + n + 6, &got2);
    if ((stop == row + n) != fast && parse_failures++ < 10)
        print_error("\"%s\": numfmt_parse %d, numfmt_parse_to stops at %d of %zu\n", s, fast,
                    stop ? (int)(stop - row) : -1, n);
    if (fast && stop == row + n && memcmp(&want, &got2, sizeof got2) != 0 &&
        parse_failures++ < 10)
        print_error("\"%s,0.5,x\": numfmt_parse_to %a, strtod %a\n", s, got2, want);
}

static void edge_values(void (*fn)(double))
{
    int e, k;
    uint64_t m;
    double p;
    const double fixed[] = { 0.0, -0.0, DBL_MIN, -DBL_MIN, DBL_MAX, -DBL_MAX,
                             DBL_TRUE_MIN, -DBL_TRUE_MIN, nextafter(DBL_MIN, 0),
                             DBL_EPSILON, 1.0, 0.1, 0.2, 0.3, 1e-5, 1e-4, 9.5e-5,
                             1e16, 1e17, 9.99999999999999999e16, 99999999999999999.0,
                             0.5, 2.5, 1e23, 5e-324, 1.7976931348623157e308,
                             INFINITY, -INFINITY };
    for (k = 0; k < (int)(sizeof fixed / sizeof fixed[0]); k++)
        fn(fixed[k]);
    /* Powers of two and their neighbours. */
    for (e = -1074; e <= 1023; e++) {
        p = ldexp(1.0, e);
        fn(p);
        fn(-p);
        fn(nextafter(p, 0));
        fn(nextafter(p, INFINITY));
    }
    /* Powers of ten and their neighbours. */
    for (e = -323; e <= 308; e++) {
        char b[32];
        snprintf(b, sizeof b, "1e%d", e);
        p = strtod(b, NULL);
        fn(p);
        fn(nextafter(p, 0));
        fn(nextafter(p, INFINITY));
    }
    /* Integers up to 2^53, where %.17g prints every digit. */
    for (m = 1; m <= (UINT64_C(1) << 53); m = m * 3 + 1) {
        fn((double)m);
        fn((double)(m - 1));
    }
    fn(9007199254740992.0);
    fn(9007199254740991.0);
    /* Subnormals: every bit length of the significand. */
    for (k = 0; k < 52; k++) {
        fn(from_bits(UINT64_C(1) << k));
        fn(from_bits((UINT64_C(1) << (k + 1)) - 1));
    }
    /* Values whose 18th digit is a 5 followed by zeros, in the digits
     * printf decides: the round-half-even ties, and their neighbours. */
    for (k = 0; k < 20000; k++) {
        uint64_t d17 = UINT64_C(10000000000000000) + next() % UINT64_C(90000000000000000);
        char b[64];
        snprintf(b, sizeof b, "%llu5e%d", (unsigned long long)d17, (int)(next() % 600) - 320);
        p = strtod(b, NULL);
        fn(p);
        fn(nextafter(p, 0));
        fn(nextafter(p, INFINITY));
    }
    /* The same where numfmt_g17 takes its fused multiply-add path
     * (10^-6 <= |v| < 10^17), where such ties and near-ties are common. */
    for (k = 0; k < 200000; k++) {
        uint64_t d17 = UINT64_C(10000000000000000) + next() % UINT64_C(90000000000000000);
        char b[64];
        snprintf(b, sizeof b, "%s%llu5e%d", k % 2 ? "-" : "", (unsigned long long)d17,
                 (int)(next() % 24) - 23);
        p = strtod(b, NULL);
        fn(p);
        fn(nextafter(p, 0));
        fn(nextafter(p, INFINITY));
    }
    /* Integers and halves near 2^53..2^57, where hi's spacing changes. */
    for (k = 0; k < 20000; k++) {
        int sh = 53 + (int)(next() % 5);
        p = ldexp(1.0, sh) + (double)(int64_t)(next() % 4096) - 2048.0;
        fn(p);
        fn(p / 10.0);
        fn(p / 1e16);
    }
}

/* Doubles v = m 2^-(j+q) whose v 10^q = m 5^q / 2^j lies 2^-j above or
 * below a half (near-ties no random draw meets), with 10^16 <= v 10^q <
 * 10^17 so that q is %.17g's own: m = (2^(j-1) +- 1) / 5^q mod 2^j, plus
 * multiples of 2^j. */
__extension__ typedef unsigned __int128 u128;

static int near_ties(double *out, int max)
{
    int q, j, sgn, n = 0;
    for (q = 17; q <= 40 && n < max; q++) {
        u128 p5 = 1;
        uint64_t inv, five;
        int i;
        for (i = 0; i < q; i++)
            p5 *= 5;
        five = (uint64_t)p5;
        /* The inverse of an odd number mod 2^64 by Newton's iteration. */
        inv = five;
        for (i = 0; i < 6; i++)
            inv *= 2 - five * inv;
        for (j = 40; j <= 62 && n < max; j++)
            for (sgn = -1; sgn <= 1; sgn += 2) {
                uint64_t mask = (UINT64_C(1) << j) - 1;
                uint64_t t0 = (((UINT64_C(1) << (j - 1)) + (uint64_t)(int64_t)sgn) * inv) & mask;
                uint64_t m;
                int got = 0;
                /* A few for each q, j and side. */
                for (m = t0; m < (UINT64_C(1) << 53) && n < max && got < 8;
                     m += UINT64_C(1) << j) {
                    long double x = (long double)m * (long double)p5 / ldexpl(1.0L, j);
                    if (m == 0 || x < 1e16L || x >= 1e17L)
                        continue;
                    out[n++] = ldexp((double)m, -(j + q));
                    got++;
                }
            }
    }
    return n;
}

static void fmt_one(double v) { check_fmt(v); }

static void test_g17_edges(void **state)
{
    static double nt[20000];
    int k, n = near_ties(nt, 20000);
    (void)state;
    fmt_failures = 0;
    edge_values(fmt_one);
    print_message("# %d constructed near-ties\n", n);
    assert_true(n > 500);
    for (k = 0; k < n; k++)
        check_fmt(nt[k]);
    assert_int_equal(fmt_failures, 0);
}

static void test_g17_random(void **state)
{
    long i, n = count();
    (void)state;
    fmt_failures = 0;
    for (i = 0; i < n; i++) {
        uint64_t b = next();
        check_fmt(from_bits(b));
        /* Doubles of ordinary size, the numbers ray files hold. */
        check_fmt(from_bits((b & ~(UINT64_C(0x7ff) << 52)) |
                            ((UINT64_C(1023) - 20 + (b >> 58)) << 52)));
        /* From 2^-24 to 2^63: every binade of the fused multiply-add path. */
        check_fmt(from_bits((b & ~(UINT64_C(0x7ff) << 52)) |
                            ((UINT64_C(1023) - 24 + (b >> 57) % 88) << 52)));
    }
    print_message("# %ld random doubles, %ld failures\n", 3 * n, fmt_failures);
    assert_int_equal(fmt_failures, 0);
}

/* numfmt_g17_n, eight at a time where the processor has AVX-512, against
 * snprintf: runs of 1 to 40 numbers (the padded tail too) mixing every
 * kind of value, so lanes of both paths meet in one call. */
static double mixed(void)
{
    uint64_t b = next();
    char t[64];
    switch (next() % 9) {
    case 0:
        return from_bits(b);
    case 1:
        return from_bits((b & ~(UINT64_C(0x7ff) << 52)) |
                         ((UINT64_C(1023) - 24 + (b >> 57) % 88) << 52));
    case 2: {
        uint64_t d17 = UINT64_C(10000000000000000) + b % UINT64_C(90000000000000000);
        double p;
        snprintf(t, sizeof t, "%llu5e%d", (unsigned long long)d17, (int)(next() % 60) - 58);
        p = strtod(t, NULL);
        return next() % 3 == 0 ? p : nextafter(p, next() % 2 ? 0 : INFINITY);
    }
    case 3: {
        static const double special[] = { 0.0, -0.0, INFINITY, -INFINITY, NAN, 1e-6, 1e17,
                                          1e-7, 99999999999999999.0, 1e16, 0.1, DBL_MIN,
                                          DBL_TRUE_MIN, DBL_MAX, 1.0, -1.0 };
        double p = special[b % (sizeof special / sizeof special[0])];
        return next() % 2 || isnan(p) || isinf(p) || p == 0.0 ? p : nextafter(p, 0);
    }
    case 4:
        return ldexp((double)(b >> 11), -(int)(next() % 150));
    case 7:
        /* The only exact ties of 17 digits below 10^-6: m 2^-24 and m 2^-25
         * for odd m (m 5^23 / 2 and m 5^24 / 2), and other small powers
         * of two. */
        if (next() % 2)
            return ldexp((double)(2 * (next() % 16) + 1), -24 - (int)(next() % 2));
        return ldexp(next() % 2 ? 1.0 : 3.0, -(int)(next() % 120));
    case 5:
        return (double)(int64_t)(b >> (next() % 64));
    default:
        return from_bits((b & ~(UINT64_C(0x7ff) << 52)) |
                         ((UINT64_C(1023) - 20 + (b >> 58)) << 52));
    }
}

static void test_g17_n(void **state)
{
    long i, n = count() / 8, bad = 0, total = 0;
    (void)state;
    for (i = 0; i < n; i++) {
        double v[40];
        char slot[40 * NUMFMT_G17_MAX + 8];
        unsigned char len[40];
        size_t m = 1 + next() % 40, j;
        for (j = 0; j < m; j++)
            v[j] = mixed();
        memset(slot, 'X', sizeof slot);
        numfmt_g17_n(v, m, slot, len);
        for (j = 0; j < m; j++) {
            char want[64];
            const char *got = slot + j * NUMFMT_G17_MAX;
            snprintf(want, sizeof want, "%.17g", v[j]);
            total++;
            if ((strcmp(want, got) != 0 || len[j] != strlen(want)) && bad++ < 10)
                print_error("%%.17g of %a (%zu of %zu): want \"%s\", got \"%.32s\"\n", v[j],
                            j, m, want, got);
        }
        /* Nothing written past the last slot. */
        if (slot[m * NUMFMT_G17_MAX] != 'X' && bad++ < 10)
            print_error("written past %zu slots\n", m);
    }
    /* The constructed near-ties, where the 8-lane path must hand over. */
    {
        static double nt[20000];
        static char slot[20000 * NUMFMT_G17_MAX];
        static unsigned char len[20000];
        int m = near_ties(nt, 20000), k;
        numfmt_g17_n(nt, (size_t)m, slot, len);
        for (k = 0; k < m; k++) {
            char want[64];
            snprintf(want, sizeof want, "%.17g", nt[k]);
            total++;
            if (strcmp(want, slot + (size_t)k * NUMFMT_G17_MAX) != 0 && bad++ < 10)
                print_error("near-tie %a: want \"%s\", got \"%s\"\n", nt[k], want,
                            slot + (size_t)k * NUMFMT_G17_MAX);
        }
    }
    print_message("# %ld numbers in runs, %ld failures\n", total, bad);
    assert_int_equal(bad, 0);
}

/* Every x below 10^8 against snprintf's "%08u". */
static void test_digits8_all(void **state)
{
    uint32_t x;
    long bad = 0;
    (void)state;
    for (x = 0; x < 100000000u; x++) {
        char want[16], got[8];
        numfmt_digits8(x, got);
        snprintf(want, sizeof want, "%08u", (unsigned)x);
        if (memcmp(want, got, 8) != 0 && bad++ < 10)
            print_error("%u: want %s, got %.8s\n", (unsigned)x, want, got);
    }
    assert_int_equal(bad, 0);
}

static void parse_forms(double v)
{
    char b[64];
    int prec;
    snprintf(b, sizeof b, "%.17g", v);
    check_parse(b);
    snprintf(b, sizeof b, "%.16g", v);
    check_parse(b);
    snprintf(b, sizeof b, "%.15e", v);
    check_parse(b);
    prec = (int)(next() % 25);
    snprintf(b, sizeof b, "%.*g", prec, v);
    check_parse(b);
    snprintf(b, sizeof b, "%.*f", (int)(next() % 30), v);
    if (strlen(b) < 60)
        check_parse(b);
}

static void test_parse_edges(void **state)
{
    static const char *const texts[] = {
        "0", "-0", "+0", "0.0", "-0.0e5", "00000000000000000000001", ".5", "5.", "-.5e-3",
        "1e308", "1.7976931348623157e308", "1.7976931348623158e308", "1e309", "2e-308",
        "2.2250738585072014e-308", "2.2250738585072011e-308", "4.9e-324", "2.4e-324",
        "1e-400", "1e400", "1e999999999999", "1e-999999999999", "123456789012345678901234",
        "1234567890123456789", "12345678901234567890", "9007199254740993",
        "9007199254740992.5", "0.1000000000000000055511151231257827021181583404541015625",
        "0.10000000000000000555111512312578270211815834045410156250000000001",
        "1.00000000000000011102230246251565404236316680908203125",
        "1.000000000000000111022302462515654042363166809082031250000000000",
        "7.2057594037927933e16", "4503599627370496.5", "4503599627370497.5",
        "1e", "1e+", "e5", ".", "-", "+", "", "1.2.3", "1,5", "0x1p3", "inf", "nan",
        "1e5x", " 1", "1 ", "--1", "1e-5", "1E5", "1e+05",
    };
    size_t k;
    (void)state;
    parse_failures = parse_fast = 0;
    for (k = 0; k < sizeof texts / sizeof texts[0]; k++)
        check_parse(texts[k]);
    edge_values(parse_forms);
    /* Text that is not a plain decimal must be handed back, not misread. */
    {
        static const char *const bad[] = { "", "1e", "1e+", ".", "-", "0x1p3", "inf", "nan",
                                           "1,5", " 1", "1 ", "1.2.3", "e5", "--1" };
        double v;
        for (k = 0; k < sizeof bad / sizeof bad[0]; k++)
            if (numfmt_parse(bad[k], strlen(bad[k]), &v))
                parse_failures++, print_error("\"%s\" was read\n", bad[k]);
    }
    assert_int_equal(parse_failures, 0);
    assert_true(parse_fast > 1000);
}

static void test_parse_random(void **state)
{
    long i, n = count();
    (void)state;
    parse_failures = parse_fast = 0;
    for (i = 0; i < n; i++) {
        uint64_t b = next();
        char t[64];
        snprintf(t, sizeof t, "%.17g", from_bits(b));
        check_parse(t);
        /* Random digit strings of 1 to 19 digits (exactly in w) and to 25
         * (beyond it) with random exponents. */
        {
            int nd = 1 + (int)(next() % 25), k, pos = 0, dot = (int)(next() % 27);
            for (k = 0; k < nd; k++) {
                if (k == dot)
                    t[pos++] = '.';
                t[pos++] = (char)('0' + next() % 10);
            }
            pos += snprintf(t + pos, sizeof t - (size_t)pos, "e%d",
                            (int)(next() % 700) - 350);
            check_parse(t);
        }
    }
    print_message("# %ld random texts, %ld read fast, %ld failures\n", 2 * n, parse_fast,
                  parse_failures);
    assert_int_equal(parse_failures, 0);
}

/* The reference: the decimals m 10^E inside v's rounding interval (both
 * ends in when v's significand is even, as round-half-even reads a tie
 * back), found with exact rationals.  The largest E that has one gives
 * the fewest digits; of its m, the closest to v, the even one at a tie.
 * v is finite and positive. */
static void exact_shortest(double v, uint64_t *fo, int *eo)
{
    mpq_t x, lo, hi, gap, p10, q;
    mpz_t mmin, mmax, m, best, r;
    uint64_t bits;
    int even, E, X;
    double below = nextafter(v, 0.0), above = nextafter(v, INFINITY);
    memcpy(&bits, &v, sizeof bits);
    even = (bits & 1) == 0;
    mpq_inits(x, lo, hi, gap, p10, q, NULL);
    mpz_inits(mmin, mmax, m, best, r, NULL);
    mpq_set_d(x, v);
    mpq_set_d(gap, below);
    mpq_sub(gap, x, gap);
    mpq_div_2exp(gap, gap, 1);
    mpq_sub(lo, x, gap);
    if (isinf(above)) {
        mpq_set_d(gap, below);
        mpq_sub(gap, x, gap); /* the gap above DBL_MAX is the one below */
    } else {
        mpq_set_d(gap, above);
        mpq_sub(gap, gap, x);
    }
    mpq_div_2exp(gap, gap, 1);
    mpq_add(hi, x, gap);
    X = (int)floor(log10(v));
    for (E = X + 2;; E--) {
        /* 10^E as a rational. */
        mpz_ui_pow_ui(r, 10, (unsigned long)(E < 0 ? -E : E));
        if (E >= 0) {
            mpq_set_z(p10, r);
        } else {
            mpq_set_ui(p10, 1, 1);
            mpz_set(mpq_denref(p10), r);
            mpq_canonicalize(p10);
        }
        /* mmin = ceil(lo / 10^E), one more where lo is out and exact. */
        mpq_div(q, lo, p10);
        mpz_cdiv_q(mmin, mpq_numref(q), mpq_denref(q));
        if (!even && mpz_cmp_ui(mpq_denref(q), 1) == 0)
            mpz_add_ui(mmin, mmin, 1);
        mpq_div(q, hi, p10);
        mpz_fdiv_q(mmax, mpq_numref(q), mpq_denref(q));
        if (!even && mpz_cmp_ui(mpq_denref(q), 1) == 0)
            mpz_sub_ui(mmax, mmax, 1);
        if (mpz_cmp(mmin, mmax) <= 0)
            break;
    }
    /* The closest m 10^E to v: |m 10^E - v| compared in rationals. */
    {
        mpq_t d, dbest;
        int first = 1;
        mpq_inits(d, dbest, NULL);
        for (mpz_set(m, mmin); mpz_cmp(m, mmax) <= 0; mpz_add_ui(m, m, 1)) {
            int c;
            mpq_set_z(d, m);
            mpq_mul(d, d, p10);
            mpq_sub(d, d, x);
            mpq_abs(d, d);
            c = first ? -1 : mpq_cmp(d, dbest);
            if (c < 0 || (c == 0 && mpz_even_p(m))) {
                mpz_set(best, m);
                mpq_set(dbest, d);
            }
            first = 0;
        }
        mpq_clears(d, dbest, NULL);
    }
    while (mpz_divisible_ui_p(best, 10)) {
        mpz_divexact_ui(best, best, 10);
        E++;
    }
    *fo = mpz_get_ui(best);
    *eo = E;
    mpq_clears(x, lo, hi, gap, p10, q, NULL);
    mpz_clears(mmin, mmax, m, best, r, NULL);
}

static long shortest_checked, shorter_than_search, shortest_exact;
/* Every how many values the exact search runs on (it is slow); the texts'
 * checks run on all. */
static int exact_every = 1;

/* Schubfach's decimal is the reference's; both texts read back as v; the
 * %g text has as many digits as the printf search for the fewest finds,
 * or fewer, and is that search's text where they have as many. */
static void check_shortest(double v)
{
    uint64_t f, rf;
    int e, re, p;
    char g[NUMFMT_SHORTEST_MAX], fx[NUMFMT_SHORTEST_MAX], search[64];
    if (!isfinite(v))
        return;
    assert_int_equal(numfmt_shortest_decimal(v, &f, &e), 1);
    if (v != 0.0 && shortest_checked % exact_every == 0) {
        shortest_exact++;
        exact_shortest(fabs(v), &rf, &re);
        if (f != rf || e != re)
            fail_msg("shortest of %a (%.17g): %llue%d, the exact search %llue%d", v, v,
                     (unsigned long long)f, e, (unsigned long long)rf, re);
    } else if (v == 0.0) {
        assert_true(f == 0);
    }
    numfmt_shortest_g(v, g);
    numfmt_shortest_f(v, fx);
    if (strtod(g, NULL) != v || signbit(strtod(g, NULL)) != signbit(v))
        fail_msg("%a: \"%s\" reads back as %a", v, g, strtod(g, NULL));
    if (strtod(fx, NULL) != v || signbit(strtod(fx, NULL)) != signbit(v))
        fail_msg("%a: \"%s\" reads back as %a", v, fx, strtod(fx, NULL));
    for (p = 1; p <= 17; p++) {
        snprintf(search, sizeof search, "%.*g", p, v);
        if (strtod(search, NULL) == v)
            break;
    }
    {
        /* Digits of f, against p. */
        int n = 0;
        uint64_t t = f;
        do {
            n++;
            t /= 10;
        } while (t);
        if (n > p)
            fail_msg("%a: %d digits, the printf search found %d", v, n, p);
        if (n == p && strcmp(g, search) != 0)
            fail_msg("%a: \"%s\", the printf search wrote \"%s\"", v, g, search);
        shorter_than_search += n < p;
    }
    shortest_checked++;
}

static void test_shortest_edges(void **state)
{
    int ex, k;
    (void)state;
    /* The shared edge set is large: the exact search takes every fifth. */
    exact_every = 5;
    edge_values(check_shortest);
    exact_every = 1;
    /* Every power of two, where the interval below is half the one above
     * (the three-quarters exponent), and its neighbours. */
    for (ex = -1074; ex <= 1023; ex++) {
        double v = ldexp(1.0, ex);
        check_shortest(v);
        check_shortest(nextafter(v, 0.0));
        check_shortest(nextafter(v, INFINITY));
        check_shortest(-v);
    }
    /* The smallest subnormals (Schubfach scales c < 3 by ten), integers
     * around 2^53, powers of ten and their neighbours. */
    for (k = 1; k <= 20000; k++)
        check_shortest(from_bits((uint64_t)k));
    for (k = -40; k <= 40; k++) {
        double v = ldexp(1.0, 53) + k;
        check_shortest(v);
        check_shortest((double)k);
    }
    {
        char t[16];
        for (k = -323; k <= 308; k++) {
            double v;
            snprintf(t, sizeof t, "1e%d", k);
            v = strtod(t, NULL);
            check_shortest(v);
            check_shortest(nextafter(v, 0.0));
            check_shortest(nextafter(v, INFINITY));
            snprintf(t, sizeof t, "9.5e%d", k);
            check_shortest(strtod(t, NULL));
        }
    }
    print_message("# shortest: %ld edge values read back, %ld equal the exact search; %ld "
                  "have fewer digits than the printf search finds\n",
                  shortest_checked, shortest_exact, shorter_than_search);
}

static void test_shortest_random(void **state)
{
    long n = count() / 20, i;
    (void)state;
    shortest_checked = shorter_than_search = shortest_exact = 0;
    for (i = 0; i < n; i++) {
        uint64_t b = next();
        double v = from_bits(b);
        check_shortest(v);
        /* Short decimals, the values people type. */
        if (i % 4 == 0) {
            char t[32];
            snprintf(t, sizeof t, "%.*g", 1 + (int)(b % 8), v);
            check_shortest(strtod(t, NULL));
        }
    }
    print_message("# shortest: %ld random values equal the exact search; %ld have fewer "
                  "digits than the printf search finds\n",
                  shortest_exact, shorter_than_search);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_g17_edges),
        cmocka_unit_test(test_g17_random),
        cmocka_unit_test(test_digits8_all),
        cmocka_unit_test(test_g17_n),
        cmocka_unit_test(test_parse_edges),
        cmocka_unit_test(test_parse_random),
        cmocka_unit_test(test_shortest_edges),
        cmocka_unit_test(test_shortest_random),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
