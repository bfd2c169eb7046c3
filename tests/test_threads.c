/*
 * test_threads.c - the batch on 2 and 3 threads gives the single-ray
 * API's bits, for every method, with enough rays that each thread takes
 * several runs (the batch hands out runs of at least 64 rays, so a batch
 * of 64 rays or fewer never leaves the calling thread).
 *
 * The reference is sg_trace_normalized / sg_trace_start on one tracer.
 * Rays are asymmetric (Hx and Hy nonzero, Px != Py) so that a thread that
 * swapped coordinates or took a neighbour's row would show.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static uint64_t rng_state;

static double urand(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * 0x1.0p-53;
}

static void same_rows(const sg_ray_surface *a, const sg_ray_surface *b, size_t n, int nt)
{
    size_t i;
    for (i = 0; i < n; i++) {
        if (!tu_same_row(&a[i], &b[i]))
            fail_msg("%d threads: row %zu differs from the single-ray trace (x %.17g vs %.17g)",
                     nt, i, b[i].x, a[i].x);
    }
}

/* nray rays of the given kind through file with method m: single-ray
 * reference, then the batch on 1, 2 and 3 threads. */
static void run(const char *file, sg_method m, sg_ray_kind kind, size_t nray)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    size_t r, ns = (size_t)sys->nsurf;
    sg_ray_in *rays = calloc(nray, sizeof *rays);
    sg_ray_surface *one = calloc(nray * ns, sizeof *one);
    sg_ray_surface *many = calloc(nray * ns, sizeof *many);
    int *st1 = calloc(nray, sizeof *st1), *st2 = calloc(nray, sizeof *st2);
    int nt, failed = 0;
    assert_true(rays && one && many && st1 && st2);
    rng_state = 0x5851F42D4C957F2DULL ^ (uint64_t)nray;
    sg_trace_opts_init(&o);
    o.method = m;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    if (!t)
        fail_msg("%s: %s", file, d.msg);
    for (r = 0; r < nray; r++) {
        if (kind == SG_RAYS_NORMALIZED) {
            /* Some pupil points lie beyond the unit circle and may fail:
             * failures must match too. */
            rays[r].v[0] = 2.0 * urand() - 1.0;
            rays[r].v[1] = 2.0 * urand() - 1.0;
            rays[r].v[2] = 2.2 * urand() - 1.1;
            rays[r].v[3] = 2.2 * urand() - 1.1;
            st1[r] = sg_trace_normalized(t, rays[r].v[0], rays[r].v[1], rays[r].v[2],
                                         rays[r].v[3], one + r * ns);
        } else {
            /* From 5 mm before surface 1 of the Cooke triplet. */
            rays[r].v[0] = 12.0 * urand() - 6.0;
            rays[r].v[1] = 12.0 * urand() - 6.0;
            rays[r].v[2] = -5.0;
            rays[r].v[3] = 0.3 * urand() - 0.15;
            rays[r].v[4] = 0.3 * urand() - 0.15;
            rays[r].v[5] = 1.0;
            st1[r] = sg_trace_start(t, rays[r].v, rays[r].v + 3, one + r * ns);
        }
        failed += st1[r] != SG_OK;
    }
    sg_tracer_free(t);
    for (nt = 1; nt <= 3; nt++) {
        memset(many, 0xA5, nray * ns * sizeof *many);
        memset(st2, 0x5A, nray * sizeof *st2);
        assert_int_equal(sg_trace_batch(sys, cat, &o, kind, rays, nray, nt, many, st2, &d),
                         SG_OK);
        assert_memory_equal(st1, st2, nray * sizeof *st1);
        same_rows(one, many, nray * ns, nt);
    }
    print_message("# %s %s, %s rays: %zu (%d failing), identical to single-ray calls on 1, 2 "
                  "and 3 threads\n", file, sg_method_name(m),
                  kind == SG_RAYS_NORMALIZED ? "normalized" : "start/dir", nray, failed);
    assert_true((size_t)failed < nray);
    free(rays);
    free(one);
    free(many);
    free(st1);
    free(st2);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void precise(void **state)
{
    (void)state;
    run("cassegrain.json", SG_METHOD_PRECISE, SG_RAYS_NORMALIZED, 20000);
    run("double_gauss.json", SG_METHOD_PRECISE, SG_RAYS_NORMALIZED, 20000);
    run("cooke_triplet.json", SG_METHOD_PRECISE, SG_RAYS_START_DIR, 20000);
}

static void classic(void **state)
{
    (void)state;
    run("cassegrain.json", SG_METHOD_CLASSIC, SG_RAYS_NORMALIZED, 20000);
    run("tma.json", SG_METHOD_CLASSIC, SG_RAYS_NORMALIZED, 20000);
    run("cooke_triplet.json", SG_METHOD_CLASSIC, SG_RAYS_START_DIR, 20000);
}

static void mpfr(void **state)
{
    (void)state;
    run("cassegrain.json", SG_METHOD_MPFR, SG_RAYS_NORMALIZED, 1000);
    run("cooke_triplet.json", SG_METHOD_MPFR, SG_RAYS_START_DIR, 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(precise),
        cmocka_unit_test(classic),
        cmocka_unit_test(mpfr),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
