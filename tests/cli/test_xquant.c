/* test_xquant.c - ui/xquant.c: exact ranks of many doubles in bounded
 * memory.  The expectation is the sorted array itself, made here with
 * qsort: the k-th value of the sorted values is what xquant must give,
 * bit for bit, however many passes it takes.  The sets cover few distinct
 * values (settled in one pass), many (the histogram, then the kept keys),
 * runs of equal values larger than the keep limit (every level of the
 * histogram to the last bit), both signs, zeros, infinities and
 * subnormals. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "xquant.h"

static uint64_t next(uint64_t *s)
{
    uint64_t z = (*s += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* IEEE 754's totalOrder for numbers: -0 before +0. */
static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    if (x == y)
        return (signbit(y) != 0) - (signbit(x) != 0);
    return x < y ? -1 : 1;
}

static int same(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Feeds v (in a shuffled order each pass, as nothing may depend on it)
 * until every rank is known; checks each against the sorted copy.
 * Returns the passes taken. */
static int check(const double *v, size_t n, size_t store_max)
{
    double *s = malloc(n * sizeof *s);
    size_t *perm = malloc(n * sizeof *perm), rank[XQ_MAXRANK], i;
    uint64_t seed = n;
    xquant q;
    int k, rc, passes = 0;
    assert_non_null(s);
    assert_non_null(perm);
    memcpy(s, v, n * sizeof *s);
    qsort(s, n, sizeof *s, cmp);
    for (i = 0; i < n; i++)
        perm[i] = i;
    xq_init(&q);
    q.store_max = store_max;
    /* The median's one or two, the 99th percentile and the ends. */
    rank[0] = n / 2;
    rank[1] = n % 2 ? 0 : n / 2 - 1;
    rank[2] = (size_t)ceil(0.99 * (double)n) - 1;
    rank[3] = n - 1;
    do {
        for (i = n; i > 1; i--) {
            size_t j = (size_t)(next(&seed) % i), t = perm[i - 1];
            perm[i - 1] = perm[j];
            perm[j] = t;
        }
        for (i = 0; i < n; i++)
            xq_add(&q, v[perm[i]]);
        if (passes == 0)
            assert_int_equal(xq_count(&q), n);
        rc = xq_resolve(&q, rank, passes == 0 ? XQ_MAXRANK : 0);
        passes++;
        assert_true(rc == XQ_OK || rc == XQ_AGAIN);
        assert_true(passes <= 6);
    } while (rc == XQ_AGAIN);
    for (k = 0; k < XQ_MAXRANK; k++)
        assert_true(same(xq_value(&q, k), s[rank[k]]));
    assert_true(same(xq_min(&q), s[0]));
    assert_true(same(xq_max(&q), s[n - 1]));
    xq_free(&q);
    free(s);
    free(perm);
    return passes;
}

/* A handful of distinct values: one pass, from the table of them. */
static void test_few_distinct(void **state)
{
    static const double pick[] = { 0.0, 0.5, 1.0, 1.5, 2.0, 4.0, 256.0, 2048.0 };
    size_t n = 100001, i;
    double *v = malloc(n * sizeof *v);
    uint64_t seed = 1;
    (void)state;
    assert_non_null(v);
    for (i = 0; i < n; i++)
        v[i] = pick[next(&seed) % 8];
    assert_int_equal(check(v, n, XQ_STORE_MAX), 1);
    free(v);
}

/* Many distinct values, as verify's digits: the first histogram, then the
 * kept keys of the ranks' buckets. */
static void test_many(void **state)
{
    size_t n = 200000, i;
    double *v = malloc(n * sizeof *v);
    uint64_t seed = 2;
    (void)state;
    assert_non_null(v);
    for (i = 0; i < n; i++)
        v[i] = -log10((double)(next(&seed) >> 11) * 0x1.0p-53 + 1e-17);
    assert_int_equal(check(v, n, XQ_STORE_MAX), 2);
    /* With at most 8 keys kept, the later histograms narrow them first. */
    assert_true(check(v, n, 8) > 2);
    free(v);
}

/* Equal values, more of them than may be kept, around the ranks: only
 * the last level of the histogram tells them from their neighbours one
 * ulp away. */
static void test_runs_of_equal(void **state)
{
    size_t n = 40001, i;
    double *v = malloc(n * sizeof *v);
    uint64_t seed = 3;
    (void)state;
    assert_non_null(v);
    for (i = 0; i < n; i++) {
        uint64_t r = next(&seed);
        double base = 1.0 + (double)(r % 3) * 0x1.0p-52;
        v[i] = r % 5 == 0 ? (double)(r % 1000) : base;
    }
    check(v, n, 16);
    free(v);
}

/* Signs, zeros of both signs, infinities, subnormals and huge values. */
static void test_whole_range(void **state)
{
    size_t n = 50001, i;
    double *v = malloc(n * sizeof *v);
    uint64_t seed = 4;
    (void)state;
    assert_non_null(v);
    for (i = 0; i < n; i++) {
        uint64_t r = next(&seed);
        switch (r % 7) {
        case 0:
            v[i] = r % 2 ? INFINITY : -INFINITY;
            break;
        case 1:
            v[i] = r % 2 ? 0.0 : -0.0;
            break;
        case 2:
            v[i] = (double)(r >> 40) * 0x1.0p-1074;
            break;
        default: {
            double d;
            uint64_t u = r & ~(UINT64_C(0x7FF) << 52);
            u |= (uint64_t)(1 + r % 2046) << 52; /* any finite exponent */
            memcpy(&d, &u, sizeof d);
            v[i] = d;
        }
        }
    }
    check(v, n, XQ_STORE_MAX);
    check(v, n, 4);
    free(v);
}

/* A second pass with other values is caught, not answered. */
static void test_changed(void **state)
{
    xquant q;
    size_t rank[1] = { 500 }, i;
    int rc;
    (void)state;
    xq_init(&q);
    for (i = 0; i < 1001; i++)
        xq_add(&q, (double)i * 0.001);
    assert_int_equal(xq_resolve(&q, rank, 1), XQ_AGAIN);
    /* The median's value is gone from its bucket the second time. */
    for (i = 0; i < 1001; i++)
        xq_add(&q, i == 500 ? 0.8125 : (double)i * 0.001);
    rc = xq_resolve(&q, NULL, 0);
    assert_int_equal(rc, XQ_ECHANGED);
    xq_free(&q);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_few_distinct),
        cmocka_unit_test(test_many),
        cmocka_unit_test(test_runs_of_equal),
        cmocka_unit_test(test_whole_range),
        cmocka_unit_test(test_changed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
