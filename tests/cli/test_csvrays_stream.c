/* test_csvrays_stream.c - the ray list read a block at a time.
 *
 * A file of several MiB, whose lines straddle the reader's 1 MiB buffer at
 * every offset (their lengths vary), read in blocks of 1 to 7 rays, gives
 * exactly the rays that the values written into it hold (the reference:
 * the doubles the test printed with %.17g, which strtod reads back
 * exactly), and csvrays_count counts them.  A line longer than the 16 MiB
 * limit is refused naming its line, and /dev/zero is refused at line 1 as
 * a NUL byte, in bounded memory, instead of being read until memory runs
 * out. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "csvrays.h"

static uint64_t next(uint64_t *s)
{
    uint64_t z = (*s += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

static char path[64];

static void test_blocks(void **state)
{
    const size_t nray = 60000;
    double (*want)[4] = malloc(nray * sizeof *want);
    sg_ray_in got[7];
    uint64_t seed = 42;
    size_t k, r, blk;
    FILE *f;
    int fd;
    (void)state;
    assert_non_null(want);
    strcpy(path, "/tmp/sg-csvstream-XXXXXX");
    fd = mkstemp(path);
    assert_true(fd >= 0);
    f = fdopen(fd, "w");
    assert_non_null(f);
    fputs("# a list\n\n  PX , hx,hy ,\"py\"\n", f);
    for (k = 0; k < nray; k++) {
        int j, pad = (int)(next(&seed) % 40);
        for (j = 0; j < 4; j++)
            want[k][j] = (double)(int64_t)next(&seed) * 0x1.0p-70;
        /* Columns in the header's order: px, hx, hy, py; blanks vary. */
        fprintf(f, "%.17g,%*s%.17g,%.17g,%.17g\n", want[k][2], pad, "", want[k][0],
                want[k][1], want[k][3]);
        if (k % 1000 == 7)
            fputs("# note\n\n", f);
    }
    fclose(f);
    for (blk = 1; blk <= 7; blk += 3) {
        csvrays_reader *rd;
        sg_diag d;
        size_t n, total = 0;
        sg_diag_clear(&d);
        assert_int_equal(csvrays_open(path, &rd, &d), SG_OK);
        assert_int_equal(csvrays_kind(rd), SG_RAYS_NORMALIZED);
        r = 0;
        for (;;) {
            assert_int_equal(csvrays_next(rd, got, blk, &n, &d), SG_OK);
            if (n == 0)
                break;
            for (k = 0; k < n; k++, r++)
                assert_memory_equal(got[k].v, want[r], sizeof want[r]);
        }
        assert_int_equal(r, nray);
        csvrays_close(rd);
        assert_int_equal(csvrays_open(path, &rd, &d), SG_OK);
        assert_int_equal(csvrays_count(rd, &total, &d), SG_OK);
        assert_int_equal(total, nray);
        csvrays_close(rd);
    }
    print_message("# %zu rays over the 1 MiB buffer's seams, blocks of 1, 4, 7: exact\n", nray);
    unlink(path);
    free(want);
}

/* Parsing on threads: the same rays as one by one, and a file with two
 * bad rows deep in a block reports the first of them, as the serial reader
 * does (the second lies in another thread's share). */
static void test_threads(void **state)
{
    const size_t nray = 20000, blk = 5000;
    sg_ray_in *a = malloc(blk * sizeof *a), *b = malloc(blk * sizeof *b);
    uint64_t seed = 7;
    size_t k, n1, n2;
    char tpath[64], msg1[SG_DIAG_MSG];
    FILE *f;
    int fd, pass;
    (void)state;
    assert_non_null(a);
    assert_non_null(b);
    for (pass = 0; pass < 2; pass++) {
        csvrays_reader *r1, *r2;
        sg_diag d1, d2;
        int rc1, rc2;
        strcpy(tpath, "/tmp/sg-csvthreads-XXXXXX");
        fd = mkstemp(tpath);
        assert_true(fd >= 0);
        f = fdopen(fd, "w");
        assert_non_null(f);
        fputs("x,y,z,l,m,n\n", f);
        for (k = 0; k < nray; k++) {
            if (pass == 1 && (k == 12345 || k == 14999))
                fputs(k == 12345 ? "1,2,3,0,0,zz\n" : "1,2\n", f);
            else
                fprintf(f, "%.17g,%.17g,%.17g, 0x1p-3 ,%.6e,%.17g\n",
                        (double)(int64_t)next(&seed) * 0x1.0p-60, 1e-300 * (double)k,
                        (double)k, (double)(int64_t)next(&seed) * 0x1.0p-62,
                        (double)(int64_t)next(&seed) * 0x1.0p-50 + 1.0);
        }
        fclose(f);
        sg_diag_clear(&d1);
        sg_diag_clear(&d2);
        assert_int_equal(csvrays_open(tpath, &r1, &d1), SG_OK);
        assert_int_equal(csvrays_open(tpath, &r2, &d2), SG_OK);
        csvrays_set_threads(r2, 4);
        for (;;) {
            rc1 = csvrays_next(r1, a, blk, &n1, &d1);
            rc2 = csvrays_next(r2, b, blk, &n2, &d2);
            assert_int_equal(rc1, rc2);
            if (rc1 != SG_OK)
                break;
            assert_int_equal(n1, n2);
            if (n1 == 0)
                break;
            assert_memory_equal(a, b, n1 * sizeof *a);
        }
        if (pass == 1) {
            snprintf(msg1, sizeof msg1, "%s", d1.msg);
            assert_string_equal(d1.msg, d2.msg);
            /* Line 12347: the header and 12345 rows before it. */
            assert_non_null(strstr(d2.msg, ":12347: column \"n\""));
        } else {
            assert_int_equal(rc1, SG_OK);
        }
        csvrays_close(r1);
        csvrays_close(r2);
        unlink(tpath);
    }
    free(a);
    free(b);
}

static void test_long_line(void **state)
{
    csvrays_reader *rd;
    sg_ray_in ray;
    sg_diag d;
    size_t n, k;
    FILE *f;
    int fd;
    char *chunk = malloc(1 << 20);
    (void)state;
    assert_non_null(chunk);
    memset(chunk, ' ', 1 << 20);
    strcpy(path, "/tmp/sg-csvstream-XXXXXX");
    fd = mkstemp(path);
    assert_true(fd >= 0);
    f = fdopen(fd, "w");
    fputs("hx,hy,px,py\n0,0,0,0\n", f);
    for (k = 0; k < 17; k++)
        fwrite(chunk, 1, 1 << 20, f);
    fputs("0,0,0,0\n", f);
    fclose(f);
    free(chunk);
    sg_diag_clear(&d);
    assert_int_equal(csvrays_open(path, &rd, &d), SG_OK);
    assert_int_equal(csvrays_next(rd, &ray, 1, &n, &d), SG_OK);
    assert_int_equal(n, 1);
    assert_int_equal(csvrays_next(rd, &ray, 1, &n, &d), SG_EPARSE);
    assert_non_null(strstr(d.msg, ":3: line longer than 16 MiB"));
    print_message("# %s\n", d.msg);
    csvrays_close(rd);
    unlink(path);
}

static void test_dev_zero(void **state)
{
    csvrays_reader *rd = NULL;
    sg_diag d;
    (void)state;
    if (access("/dev/zero", R_OK) != 0) {
        print_message("# SKIP /dev/zero cannot be read\n");
        return;
    }
    sg_diag_clear(&d);
    assert_int_equal(csvrays_open("/dev/zero", &rd, &d), SG_EPARSE);
    assert_null(rd);
    assert_non_null(strstr(d.msg, "/dev/zero:1: NUL byte"));
    print_message("# %s\n", d.msg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_blocks),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_long_line),
        cmocka_unit_test(test_dev_zero),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
