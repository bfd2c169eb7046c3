/* test_cli_stream.c - "sagitta trace --rays" streams: it reads, traces and
 * writes a block of rays at a time.
 *
 * The bytes must not depend on where the blocks end: the same list is
 * traced in one block and in blocks of 1, 2 and 7 rays (SAGITTA_RAYS_BLOCK)
 * on 1 to 3 threads, by every method, as text, CSV and JSON, normalized
 * and start/direction; JSON must parse (cJSON) and hold every ray.  A
 * list long enough for several rounds of the threads' formatting must
 * give the one thread's bytes, to standard output and to a file.  A bad
 * row far into the list must leave an existing output file untouched.
 * Memory must not grow with the list: a run under an address-space cap
 * that the whole-list reader exceeds (it needed nray * nsurf * 88 bytes of
 * rows at once: 60 MB here) must succeed; so must verify's table2 and
 * bench. */
#include <cjson/cJSON.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "clitest.h"

static char examples[1024];

static const char *example(const char *file)
{
    static char buf[4][1200];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", examples, file);
    return buf[k];
}

static uint64_t next(uint64_t *s)
{
    uint64_t z = (*s += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

static double uni(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(next(s) >> 11) * 0x1.0p-53);
}

/* n rays, seeded: normalized in runs of one field with pupils past the
 * rim (some fail), with comments and blank lines between; or start and
 * direction rays, the last line without its newline. */
static const char *ray_file(const char *name, int normalized, int n, uint64_t seed)
{
    size_t cap = (size_t)n * 100 + 200, len = 0;
    char *t = malloc(cap);
    const char *p;
    int k;
    assert_non_null(t);
    len += (size_t)snprintf(t + len, cap - len, normalized ? "# rays\nhx,hy,px,py\n"
                                                           : "x,y,z,l,m,n\n");
    for (k = 0; k < n; k++) {
        if (normalized) {
            len += (size_t)snprintf(t + len, cap - len, "0,%.17g,%.17g,%.17g\n",
                                    0.5 * ((k / 5) % 3), uni(&seed, -1.1, 1.1),
                                    uni(&seed, -1.1, 1.1));
            if (k % 9 == 4)
                len += (size_t)snprintf(t + len, cap - len, "\n# a comment\n");
        } else {
            len += (size_t)snprintf(t + len, cap - len, "%.17g,%.17g,-5,%.17g,%.17g,1%s",
                                    uni(&seed, -20, 20), uni(&seed, -20, 20),
                                    uni(&seed, -0.3, 0.3), uni(&seed, -0.3, 0.3),
                                    k + 1 < n ? "\n" : "");
        }
    }
    p = ct_file(name, t);
    free(t);
    return p;
}

static void set_block(int n)
{
    char b[32];
    if (n <= 0) {
        unsetenv("SAGITTA_RAYS_BLOCK");
        return;
    }
    snprintf(b, sizeof b, "%d", n);
    setenv("SAGITTA_RAYS_BLOCK", b, 1);
}

static void check_json(const char *text, int nray)
{
    cJSON *j = cJSON_Parse(text);
    cJSON *rays;
    assert_non_null(j);
    rays = cJSON_GetObjectItem(j, "rays");
    if (nray == 1) {
        assert_null(rays);
        assert_non_null(cJSON_GetObjectItem(j, "surfaces"));
    } else {
        assert_non_null(rays);
        assert_int_equal(cJSON_GetArraySize(rays), nray);
        assert_int_equal(
            cJSON_GetObjectItem(cJSON_GetArrayItem(rays, nray - 1), "ray")->valueint,
            nray - 1);
    }
    cJSON_Delete(j);
}

static void same_any_block(const char *design, const char *rays, int nray,
                           const char *method)
{
    static const char *const fmts[3] = { "text", "csv", "json" };
    static const int blocks[3] = { 1, 2, 7 };
    static const char *const threads[3] = { "1", "2", "3" };
    int f, b, t;
    for (f = 0; f < 3; f++) {
        ct_result ref;
        set_block(0);
        ct_run(&ref, "trace", design, "--rays", rays, "--method", method, "--format",
               fmts[f], "--threads", "2", NULL);
        assert_int_equal(ref.code, 0);
        if (f == 2)
            check_json(ref.out, nray);
        for (t = 0; t < 3; t++)
            for (b = 0; b < 3; b++) {
                ct_result r;
                set_block(blocks[b]);
                ct_run(&r, "trace", design, "--rays", rays, "--method", method, "--format",
                       fmts[f], "--threads", threads[t], NULL);
                assert_int_equal(r.code, 0);
                if (strcmp(r.out, ref.out) != 0)
                    fail_msg("%s %s %s: blocks of %d on %s threads differ from one block",
                             rays, method, fmts[f], blocks[b], threads[t]);
                ct_free(&r);
            }
        ct_free(&ref);
    }
    set_block(0);
    print_message("# %s %s: %d rays, text/csv/json identical in blocks of 1, 2, 7 on 1-3 "
                  "threads\n", design, method, nray);
}

static void test_blocks_precise(void **state)
{
    (void)state;
    same_any_block(example("double_gauss.json"), ray_file("n.csv", 1, 61, 1), 61, "precise");
    same_any_block(example("cassegrain.json"), ray_file("s.csv", 0, 43, 2), 43, "precise");
    same_any_block(example("tma.json"), ray_file("one.csv", 1, 1, 3), 1, "precise");
}

static void test_blocks_classic(void **state)
{
    (void)state;
    same_any_block(example("double_gauss.json"), ray_file("n.csv", 1, 37, 4), 37, "classic");
    same_any_block(example("cassegrain.json"), ray_file("s.csv", 0, 29, 5), 29, "classic");
}

static void test_blocks_mpfr(void **state)
{
    (void)state;
    same_any_block(example("cooke_triplet.json"), ray_file("n.csv", 1, 11, 6), 11, "mpfr");
    same_any_block(example("cassegrain.json"), ray_file("s.csv", 0, 9, 7), 9, "mpfr");
}

/* A bad row after several blocks have been written: the message names its
 * line, the status is 3, and an existing output file keeps its bytes (no
 * temporary file is left beside it). */
static void test_bad_row_keeps_file(void **state)
{
    const int n = 200;
    size_t cap = (size_t)n * 20 + 64, len = 0;
    char *t = malloc(cap);
    const char *rays, *outp;
    ct_result r;
    FILE *f;
    char buf[160] = "";
    int k;
    (void)state;
    assert_non_null(t);
    len += (size_t)snprintf(t + len, cap - len, "hx,hy,px,py\n");
    for (k = 0; k < n; k++)
        len += (size_t)snprintf(t + len, cap - len, "0,0,0.1,%d.5e-3\n", k);
    snprintf(t + len, cap - len, "0,0,x,0\n");
    rays = ct_file("bad.csv", t);
    free(t);
    outp = ct_file("kept.txt", "keep me\n");
    set_block(10);
    ct_run(&r, "trace", example("singlet.json"), "--rays", rays, "-o", outp, NULL);
    set_block(0);
    assert_int_equal(r.code, 3);
    assert_non_null(strstr(r.err, "bad.csv:202: column \"px\""));
    f = fopen(outp, "r");
    assert_non_null(f);
    assert_non_null(fgets(buf, sizeof buf, f));
    fclose(f);
    assert_string_equal(buf, "keep me\n");
    ct_free(&r);
    /* The same list, good, replaces the file. */
    rays = ray_file("good.csv", 1, 30, 8);
    set_block(4);
    ct_run(&r, "trace", example("singlet.json"), "--rays", rays, "-o", outp, "--format",
           "csv", NULL);
    set_block(0);
    assert_int_equal(r.code, 0);
    f = fopen(outp, "r");
    assert_non_null(f);
    assert_non_null(fgets(buf, sizeof buf, f));
    fclose(f);
    /* Normalized rays: each row says which ray it is (sagitta(1), trace). */
    assert_string_equal(buf, "ray,hx,hy,px,py,surface,x,y,z,l,m,n,residual,error_bound,path,"
                             "status,opl,opl_error_bound,opd_waves,opd_error_bound,ex,ey\n");
    ct_free(&r);
}

/* Whether this build runs under AddressSanitizer, whose shadow memory and
 * thread stacks do not fit any cap that measures the program itself (a
 * capped run can pass with one ray and fail on the threads of many). */
static int sanitized(void)
{
#if defined(__SANITIZE_ADDRESS__)
    return 1;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return 1;
#else
    return 0;
#endif
#else
    return 0;
#endif
}

/* Runs sagitta; returns its peak resident set in MiB, failing the test
 * unless it exits 0.  Peak RSS, not an address-space cap: the libraries
 * the program links (HDF5, cairo) and each thread's malloc arena reserve
 * address space that says nothing about memory used. */
static double peak_mib(const char *const *args)
{
    ct_result r;
    double mib;
    ct_runv(&r, args);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    mib = (double)r.maxrss_kb / 1024.0;
    ct_free(&r);
    return mib;
}

/* How much more the run of many needed than the run of one, in MiB, with
 * the message the test prints. */
static double growth(const char *what, const char *const *one, const char *const *many,
                     double budget)
{
    double a = peak_mib(one), b = peak_mib(many);
    print_message("# %s: peak RSS %.1f MiB against %.1f MiB for one ray (budget %.0f MiB more)\n",
                  what, b, a, budget);
    return b - a;
}

static void test_memory_flat(void **state)
{
    const char *design = example("double_gauss.json");
    const char *one_f, *many_f;
    (void)state;
    /* Under a sanitizer freed memory is held in quarantine: growth there
     * says nothing about the program. */
    if (sanitized()) {
        print_message("# SKIP: a sanitizer build\n");
        return;
    }
    one_f = ray_file("one_ray.csv", 1, 1, 9);
    /* 40,000 rays of 17 surfaces: 60 MB of rows held at once before. */
    many_f = ray_file("many.csv", 1, 40000, 10);
    {
        /* One thread: the test measures the stream, not thread arenas. */
        const char *const one[] = { "trace", design, "--rays", one_f, "--threads", "1",
                                    "--format", "csv", "-o", "/dev/null", NULL };
        const char *const many[] = { "trace", design, "--rays", many_f, "--threads", "1",
                                     "--format", "csv", "-o", "/dev/null", NULL };
        assert_true(growth("trace --rays, 40000 rays of 17 surfaces", one, many, 16.0) <= 16.0);
    }
}

/* verify --experiment table2 keeps nothing per ray: its medians come from
 * passes over the seeded rays (ui/xquant.c).  Keeping two numbers a ray
 * and method, as before, 500,000 rays needed 16 MB more than one ray. */
static void test_table2_memory(void **state)
{
    const char *const one[] = { "verify", "--experiment", "table2", "--count", "1", "-o",
                                "/dev/null", NULL };
    const char *const many[] = { "verify", "--experiment", "table2", "--count", "500000",
                                 "-o", "/dev/null", NULL };
    (void)state;
    if (sanitized()) {
        print_message("# SKIP: a sanitizer build\n");
        return;
    }
    assert_true(growth("verify --experiment table2 --count 500000", one, many, 6.0) <= 6.0);
}

/* verify --grid traces a block of rays at a time and keeps, a ray-surface,
 * 24 bytes for its exact medians and, a ray, each method's OPD.  The grid
 * of 101 on the double Gauss (23,535 rays of 17 surfaces) held every row
 * of the three methods at once before, 105 MB. */
static void test_grid_memory(void **state)
{
    const char *design = example("double_gauss.json");
    const char *const one[] = { "verify", design, "--grid", "1", "-o", "/dev/null", NULL };
    const char *const many[] = { "verify", design, "--grid", "101", "-o", "/dev/null", NULL };
    (void)state;
    if (sanitized()) {
        print_message("# SKIP: a sanitizer build\n");
        return;
    }
    assert_true(growth("verify --grid 101 on the double Gauss", one, many, 40.0) <= 40.0);
}

/* verify on a design gives the same bytes whatever its blocks: a grid on
 * three designs, text and JSON, in blocks of 1, 2 and 7 rays against one
 * block of every ray (their vertex points, worst rays and first ray's
 * rows are settled across the seams). */
static void test_grid_blocks(void **state)
{
    static const char *const designs[] = { "double_gauss.json", "cassegrain.json",
                                           "tma.json" };
    static const int blocks[] = { 1, 2, 7 };
    static const char *const fmts[] = { "text", "json" };
    size_t k, b, f;
    (void)state;
    for (k = 0; k < 3; k++)
        for (f = 0; f < 2; f++) {
            ct_result whole, part;
            set_block(1000000);
            ct_run(&whole, "verify", example(designs[k]), "--grid", "4", "--format", fmts[f],
                   NULL);
            assert_int_equal(whole.code, 0);
            for (b = 0; b < 3; b++) {
                set_block(blocks[b]);
                ct_run(&part, "verify", example(designs[k]), "--grid", "4", "--format",
                       fmts[f], NULL);
                assert_int_equal(part.code, whole.code);
                assert_string_equal(part.out, whole.out);
                ct_free(&part);
            }
            ct_free(&whole);
        }
    set_block(0);
    print_message("# verify --grid 4: the same bytes in blocks of 1, 2, 7 and all rays\n");
}

/* Runs bench on one thread, as JSON; returns the rays that reached the
 * image in its one ray set's runs (-1 if one was not measured), and its
 * peak RSS in MiB in *mib. */
static long bench_run(const char *design, const char *nray, double *mib)
{
    const char *const args[] = { "bench", design, "--rays", nray, "--repeat", "1",
                                 "--threads", "1", "--format", "json", NULL };
    ct_result r;
    cJSON *root, *d, *tp, *e;
    long ok = 0;
    ct_runv(&r, args);
    if (r.code != 0)
        fail_msg("bench: exit %d: %s", r.code, r.err);
    *mib = (double)r.maxrss_kb / 1024.0;
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    d = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "designs"), 0);
    tp = cJSON_GetObjectItem(d, "throughput");
    assert_true(cJSON_GetArraySize(tp) == 2); /* precise and classic */
    cJSON_ArrayForEach(e, tp) {
        cJSON *n = cJSON_GetObjectItem(e, "rays_reached_image");
        if (!cJSON_IsNumber(n)) {
            ok = -1;
            break;
        }
        ok += (long)n->valuedouble;
    }
    cJSON_Delete(root);
    ct_free(&r);
    return ok;
}

/* bench traces its ray set in blocks: 200,000 rays through the singlet's
 * 4 surfaces took 80 MB of rows and rays at once before.  Every ray of
 * the singlet's set reaches the image (its field and pupil are within the
 * lens), so both methods count 200,000. */
/* Enough rays for several formatting rounds in one block (a round is
 * about 8192 rows a thread, report.c); the bytes must be the serial ones,
 * on standard output and in a file (which has a buffer of its own), and
 * in blocks that end inside a round. */
static void test_many_rounds(void **state)
{
    static const char *const fmts[3] = { "csv", "json", "text" };
    static const char *const threads[2] = { "2", "3" };
    const char *design = example("cooke_triplet.json");
    const char *rays = ray_file("rounds.csv", 1, 9000, 11);
    const char *outpath = ct_path("rounds.out");
    int f, t;
    (void)state;
    for (f = 0; f < 3; f++) {
        ct_result ref;
        set_block(0);
        ct_run(&ref, "trace", design, "--rays", rays, "--format", fmts[f], "--threads", "1",
               NULL);
        assert_int_equal(ref.code, 0);
        assert_true(strlen(ref.out) > (size_t)9000 * 8 * 50);
        for (t = 0; t < 2; t++) {
            ct_result r;
            char *text;
            set_block(t ? 5003 : 0);
            ct_run(&r, "trace", design, "--rays", rays, "--format", fmts[f], "--threads",
                   threads[t], NULL);
            assert_int_equal(r.code, 0);
            if (strcmp(r.out, ref.out) != 0)
                fail_msg("%s on %s threads: standard output differs from one thread's",
                         fmts[f], threads[t]);
            ct_free(&r);
            ct_run(&r, "trace", design, "--rays", rays, "--format", fmts[f], "--threads",
                   threads[t], "-o", outpath, NULL);
            assert_int_equal(r.code, 0);
            ct_free(&r);
            text = ct_read(outpath);
            assert_non_null(text);
            if (strcmp(text, ref.out) != 0)
                fail_msg("%s on %s threads: the file differs from one thread's output",
                         fmts[f], threads[t]);
            free(text);
        }
        ct_free(&ref);
    }
    set_block(0);
    print_message("# cooke_triplet: 9000 rays, csv/json/text on 2 and 3 threads, to standard "
                  "output and a file, identical to one thread's\n");
}

static void test_bench_memory(void **state)
{
    const char *design = example("singlet.json");
    double a, b;
    (void)state;
    if (sanitized()) {
        print_message("# SKIP: a sanitizer build\n");
        return;
    }
    assert_int_equal(bench_run(design, "1", &a), 2);
    assert_int_equal(bench_run(design, "200000", &b), 400000);
    print_message("# bench of 200000 rays: peak RSS %.1f MiB against %.1f MiB for one ray "
                  "(budget 24 MiB more)\n", b, a);
    assert_true(b - a <= 24.0);
}

int main(int argc, char **argv)
{
    const char *e = getenv("SAGITTA_EXAMPLES");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_blocks_precise),
        cmocka_unit_test(test_blocks_classic),
        cmocka_unit_test(test_blocks_mpfr),
        cmocka_unit_test(test_bad_row_keeps_file),
        cmocka_unit_test(test_memory_flat),
        cmocka_unit_test(test_table2_memory),
        cmocka_unit_test(test_bench_memory),
        cmocka_unit_test(test_grid_memory),
        cmocka_unit_test(test_grid_blocks),
        cmocka_unit_test(test_many_rounds),
    };
    int rc;
    snprintf(examples, sizeof examples, "%s", e && *e ? e : "examples");
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
