/* test_args.c - the strict number parsers of ui/args.c.  Expected values
 * come from the C compiler's own (correctly rounded) reading of the same
 * literals, and from the definitions of the error classes. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "args.h"

static void test_double_ok(void **state)
{
    static const struct {
        const char *s;
        double v;
    } cases[] = {
        { "1.5", 1.5 },
        { "  -2.25\t", -2.25 },
        { "0.1", 0.1 },
        { "+7", 7.0 },
        { "1e-3", 1e-3 },
        { "0x1p-3", 0.125 },
        { "2.2250738585072014e-308", 2.2250738585072014e-308 },
        { "1.7976931348623157e308", 1.7976931348623157e308 },
        { "4.9406564584124654e-324", 4.9406564584124654e-324 },
        /* Halfway between 1 and its successor, one digit past: rounds up. */
        { "1.00000000000000011102230246251565404236316680908203126",
          1.0000000000000002220446049250313 },
        { "-0", -0.0 },
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        double v = 12345;
        assert_int_equal(args_double(cases[k].s, 0, &v), ARGS_OK);
        if (memcmp(&v, &cases[k].v, sizeof v) != 0)
            fail_msg("\"%s\" read as %.17g, expected %.17g", cases[k].s, v, cases[k].v);
    }
    print_message("# %zu decimal and hex literals read bit-identical to the "
                  "compiler's conversion (worst difference 0)\n", k);
}

static void test_double_errors(void **state)
{
    static const struct {
        const char *s;
        int flags, rc;
    } cases[] = {
        { "", 0, ARGS_EMPTY },
        { "   ", 0, ARGS_EMPTY },
        { "abc", 0, ARGS_SYNTAX },
        { "1.5x", 0, ARGS_SYNTAX },
        { "1.5 2", 0, ARGS_SYNTAX },
        { "1,5", 0, ARGS_SYNTAX },
        { "e5", 0, ARGS_SYNTAX },
        { "--1", 0, ARGS_SYNTAX },
        { "nan", 0, ARGS_NONFINITE },
        { "NaN", ARGS_ALLOW_INF, ARGS_NONFINITE },
        { "inf", 0, ARGS_NONFINITE },
        { "-Infinity", 0, ARGS_NONFINITE },
        { "1e400", 0, ARGS_RANGE },
        { "-1e400", ARGS_ALLOW_INF, ARGS_RANGE },
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        double v = 42;
        int rc = args_double(cases[k].s, cases[k].flags, &v);
        if (rc != cases[k].rc)
            fail_msg("\"%s\": code %d (%s), expected %d", cases[k].s, rc,
                     args_strerror(rc), cases[k].rc);
        assert_true(v == 42); /* untouched on error */
    }
    assert_null(strstr(args_strerror(ARGS_SYNTAX), "%"));
    print_message("# %zu malformed values refused with the expected class\n", k);
}

static void test_double_inf_allowed(void **state)
{
    double v = 0;
    (void)state;
    assert_int_equal(args_double("inf", ARGS_ALLOW_INF, &v), ARGS_OK);
    assert_true(isinf(v) && v > 0);
    assert_int_equal(args_double(" -Infinity ", ARGS_ALLOW_INF, &v), ARGS_OK);
    assert_true(isinf(v) && v < 0);
    print_message("# spelled-out infinities accepted only with ARGS_ALLOW_INF\n");
}

static void test_list(void **state)
{
    double v[4] = { 0 };
    int bad = 7;
    (void)state;
    assert_int_equal(args_double_list("0, 1,-0.5 ,1e0", 0, v, 4, &bad), ARGS_OK);
    assert_true(v[0] == 0 && v[1] == 1 && v[2] == -0.5 && v[3] == 1);
    assert_int_equal(bad, -1);

    assert_int_equal(args_double_list("0,1,x", 0, v, 4, &bad), ARGS_COUNT);
    assert_int_equal(bad, -1);
    assert_int_equal(args_double_list("0,1,2,3,4", 0, v, 4, &bad), ARGS_COUNT);
    assert_int_equal(args_double_list("0,1,2,", 0, v, 4, &bad), ARGS_EMPTY);
    assert_int_equal(bad, 3);
    assert_int_equal(args_double_list("0,,2,3", 0, v, 4, &bad), ARGS_EMPTY);
    assert_int_equal(bad, 1);
    assert_int_equal(args_double_list("0,1,x,3", 0, v, 4, &bad), ARGS_SYNTAX);
    assert_int_equal(bad, 2);
    assert_int_equal(args_double_list("0,1,2,nan", 0, v, 4, &bad), ARGS_NONFINITE);
    assert_int_equal(bad, 3);
    assert_int_equal(args_double_list("", 0, v, 1, &bad), ARGS_EMPTY);
    assert_int_equal(args_double_list("2.5", 0, v, 1, NULL), ARGS_OK);
    assert_true(v[0] == 2.5);
    print_message("# lists: count, empty item, bad item index and values checked\n");
}

static void test_int(void **state)
{
    int v = -1;
    long l = 0;
    (void)state;
    assert_int_equal(args_int("53", 53, 100000, &v), ARGS_OK);
    assert_int_equal(v, 53);
    assert_int_equal(args_int(" +100000 ", 53, 100000, &v), ARGS_OK);
    assert_int_equal(v, 100000);
    assert_int_equal(args_int("52", 53, 100000, &v), ARGS_RANGE);
    assert_int_equal(args_int("100001", 53, 100000, &v), ARGS_RANGE);
    assert_int_equal(args_int("99999999999999999999999", 0, INT_MAX, &v), ARGS_RANGE);
    assert_int_equal(args_int("7.0", 0, 10, &v), ARGS_SYNTAX);
    assert_int_equal(args_int("1e3", 0, 10000, &v), ARGS_SYNTAX);
    assert_int_equal(args_int("0x10", 0, 100, &v), ARGS_SYNTAX);
    assert_int_equal(args_int("", 0, 10, &v), ARGS_EMPTY);
    assert_int_equal(args_int("- 3", -10, 10, &v), ARGS_SYNTAX);
    assert_int_equal(v, 100000);
    assert_int_equal(args_long("-9", -10, 10, &l), ARGS_OK);
    assert_true(l == -9);
    print_message("# integers: bounds 53..100000 inclusive, overflow and syntax\n");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_double_ok),
        cmocka_unit_test(test_double_errors),
        cmocka_unit_test(test_double_inf_allowed),
        cmocka_unit_test(test_list),
        cmocka_unit_test(test_int),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
