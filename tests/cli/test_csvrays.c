/* test_csvrays.c - the --rays CSV reader.  Expected values are the numbers
 * written into each test's own CSV text; expected messages follow the
 * format promised in ui/csvrays.h and man/sagitta.1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "csvrays.h"

static int parse(const char *text, sg_ray_kind *kind, sg_ray_in **rays,
                 size_t *n, sg_diag *d)
{
    sg_diag_clear(d);
    return csvrays_parse(text, strlen(text), "rays.csv", kind, rays, n, d);
}

static void test_normalized_any_order(void **state)
{
    const char *text =
        "# a comment before the header\n"
        "\n"
        " Py , \"HX\",px,hy\r\n"
        "0.25, 1, -0.5, 0\r\n"
        "   # a comment between rays\n"
        "\t\n"
        "1,0,0,-1\n"
        "0x1p-2,1e-3,+2,-0";
    sg_ray_kind kind = SG_RAYS_START_DIR;
    sg_ray_in *rays = NULL;
    size_t n = 0;
    sg_diag d;
    (void)state;
    assert_int_equal(parse(text, &kind, &rays, &n, &d), SG_OK);
    assert_int_equal(kind, SG_RAYS_NORMALIZED);
    assert_int_equal(n, 3);
    /* Columns were py,hx,px,hy; the rays hold hx,hy,px,py. */
    assert_true(rays[0].v[0] == 1 && rays[0].v[1] == 0 && rays[0].v[2] == -0.5 &&
                rays[0].v[3] == 0.25);
    assert_true(rays[1].v[0] == 0 && rays[1].v[1] == -1 && rays[1].v[2] == 0 &&
                rays[1].v[3] == 1);
    assert_true(rays[2].v[0] == 1e-3 && rays[2].v[1] == 0 && rays[2].v[2] == 2 &&
                rays[2].v[3] == 0.25);
    free(rays);
    print_message("# 3 rays, permuted quoted header, CRLF, comments: all 12 values exact\n");
}

static void test_start_dir(void **state)
{
    const char *text = "n,m,l,z,y,x\n1,0,0.1,-5,2,3\n0.5,0.5,0,0,0,0\n";
    sg_ray_kind kind = SG_RAYS_NORMALIZED;
    sg_ray_in *rays = NULL;
    size_t n = 0;
    sg_diag d;
    (void)state;
    assert_int_equal(parse(text, &kind, &rays, &n, &d), SG_OK);
    assert_int_equal(kind, SG_RAYS_START_DIR);
    assert_int_equal(n, 2);
    assert_true(rays[0].v[0] == 3 && rays[0].v[1] == 2 && rays[0].v[2] == -5 &&
                rays[0].v[3] == 0.1 && rays[0].v[4] == 0 && rays[0].v[5] == 1);
    assert_true(rays[1].v[3] == 0 && rays[1].v[4] == 0.5 && rays[1].v[5] == 0.5);
    free(rays);
    print_message("# start/direction columns n,m,l,z,y,x mapped to x,y,z,l,m,n exactly\n");
}

/* Parses text and expects a failure whose message contains every needle. */
static void expect_error(const char *text, int code, const char *n1,
                         const char *n2)
{
    sg_ray_kind kind;
    sg_ray_in *rays = (sg_ray_in *)1;
    size_t n = 99;
    sg_diag d;
    int rc = parse(text, &kind, &rays, &n, &d);
    if (rc != code)
        fail_msg("expected code %d, got %d (%s) for:\n%s", code, rc, d.msg, text);
    assert_null(rays);
    assert_int_equal(n, 0);
    if (!strstr(d.msg, n1) || (n2 && !strstr(d.msg, n2)))
        fail_msg("message \"%s\" lacks \"%s\"%s%s%s", d.msg, n1, n2 ? " or \"" : "",
                 n2 ? n2 : "", n2 ? "\"" : "");
    print_message("# refused: %s\n", d.msg);
}

static void test_errors(void **state)
{
    (void)state;
    expect_error("hx,hy,px,weight\n0,0,0,1\n", SG_EPARSE, "rays.csv:1:", "\"weight\"");
    expect_error("#c\nhx,hy,px,py,foo,bar\n", SG_EPARSE, "rays.csv:2:", "\"foo\", \"bar\"");
    expect_error("hx,hy,px\n0,0,0\n", SG_EPARSE, "rays.csv:1:", "missing column \"py\"");
    expect_error("x,y,z,l,m\n", SG_EPARSE, "rays.csv:1:", "\"n\"");
    expect_error("hx,hy,px,py,x\n", SG_EPARSE, "rays.csv:1:", "mixes");
    expect_error("hx,hx,px,py\n", SG_EPARSE, "rays.csv:1:", "\"hx\" appears twice");
    expect_error("hx,,px,py\n", SG_EPARSE, "rays.csv:1:", "column 2");
    expect_error("hx,hy,px,py\n0,0,0,0\n\n0,0,0\n", SG_EPARSE, "rays.csv:4:",
                 "expected 4 fields, got 3");
    expect_error("hx,hy,px,py\n0,0,0,0,0\n", SG_EPARSE, "rays.csv:2:", "got 5");
    expect_error("hx,hy,px,py\n0,0,0,0\n0,0,abc,0\n", SG_EPARSE,
                 "rays.csv:3: column \"px\"", "\"abc\"");
    expect_error("hx,hy,px,py\n0,0,0,1.5.2\n", SG_EPARSE, "rays.csv:2: column \"py\"", NULL);
    /* A number run into the next one without its comma: the one-pass
     * reader must not take the stray byte for a separator. */
    expect_error("hx,hy,px,py\n0,0.5x0.25,0\n", SG_EPARSE, "rays.csv:2:",
                 "expected 4 fields, got 3");
    expect_error("hx,hy,px,py\n0,0.5x0.25,0,0\n", SG_EPARSE, "rays.csv:2: column \"hy\"",
                 "\"0.5x0.25\"");
    expect_error("hx,hy,px,py\n0,0.5;0.25,0\n", SG_EPARSE, "rays.csv:2:",
                 "expected 4 fields, got 3");
    expect_error("hx,hy,px,py\n0,nan,0,0\n", SG_EPARSE, "rays.csv:2: column \"hy\"", NULL);
    expect_error("hx,hy,px,py\n0,inf,0,0\n", SG_EPARSE, "rays.csv:2: column \"hy\"", NULL);
    expect_error("hx,hy,px,py\n0,0,,0\n", SG_EPARSE, "rays.csv:2: column \"px\"", "empty");
    expect_error("x,y,z,l,m,n\n0,0,0,0,0,0\n", SG_EPARSE, "rays.csv:2:", "zero");
    expect_error("# only a comment\n\n", SG_EPARSE, "rays.csv:", "no header");
    expect_error("hx,hy,px,py\n# nothing\n", SG_EPARSE, "rays.csv:", "no rays");
    expect_error("", SG_EPARSE, "rays.csv", "no header");
}

static void test_nul_byte(void **state)
{
    static const char text[] = "hx,hy,px,py\n0,0\0,0,0\n";
    sg_ray_kind kind;
    sg_ray_in *rays = NULL;
    size_t n = 0;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(csvrays_parse(text, sizeof text - 1, "rays.csv", &kind, &rays,
                                   &n, &d),
                     SG_EPARSE);
    assert_non_null(strstr(d.msg, "rays.csv:2:"));
    print_message("# refused: %s\n", d.msg);
}

static void test_read_missing(void **state)
{
    sg_ray_kind kind;
    sg_ray_in *rays = NULL;
    size_t n = 0;
    sg_diag d;
    const char *path = "/nonexistent-dir-for-sagitta/rays.csv";
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(csvrays_read(path, &kind, &rays, &n, &d), SG_EIO);
    assert_non_null(strstr(d.msg, path));
    print_message("# refused: %s\n", d.msg);
}

static void test_many_rays(void **state)
{
    /* Enough rows to make the array grow several times. */
    size_t k, nrow = 5000, n = 0;
    char *text = malloc(nrow * 40 + 32), *p = text;
    sg_ray_kind kind;
    sg_ray_in *rays = NULL;
    sg_diag d;
    (void)state;
    assert_non_null(text);
    p += sprintf(p, "hx,hy,px,py\n");
    for (k = 0; k < nrow; k++)
        p += sprintf(p, "%zu,0,0,%zu\n", k, nrow - k);
    assert_int_equal(parse(text, &kind, &rays, &n, &d), SG_OK);
    assert_int_equal(n, nrow);
    for (k = 0; k < nrow; k++)
        assert_true(rays[k].v[0] == (double)k && rays[k].v[3] == (double)(nrow - k));
    free(rays);
    free(text);
    print_message("# %zu rows read in order, every value exact\n", nrow);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_normalized_any_order),
        cmocka_unit_test(test_start_dir),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_nul_byte),
        cmocka_unit_test(test_read_missing),
        cmocka_unit_test(test_many_rays),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
