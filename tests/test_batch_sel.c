/*
 * test_batch_sel.c - a batch that keeps a chosen set of surfaces (the
 * image alone, a list in any order, repeats) gives, for every kept
 * surface, the rows and status of the full batch bit for bit; a kept
 * batch object traced block after block gives the same as one call.
 * The reference is sg_trace_batch, which test_batch holds to the
 * single-ray calls.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static void same_row(const sg_ray_surface *a, const sg_ray_surface *b)
{
    const double fa[10] = {a->x, a->y, a->z, a->l, a->m, a->n, a->residual,
                           a->error_bound, a->dir_error_bound, a->path};
    const double fb[10] = {b->x, b->y, b->z, b->l, b->m, b->n, b->residual,
                           b->error_bound, b->dir_error_bound, b->path};
    assert_memory_equal(fa, fb, sizeof fa);
    assert_int_equal(a->status, b->status);
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

/* Seeded rays: fields in runs (as the precise batch groups them), pupils
 * beyond the rim so some fail, a non-finite ray, or start/direction rays
 * some of which miss. */
static size_t make_rays(sg_ray_kind kind, sg_ray_in *r, size_t n, uint64_t seed)
{
    size_t k;
    for (k = 0; k < n; k++) {
        memset(&r[k], 0, sizeof r[k]);
        if (kind == SG_RAYS_NORMALIZED) {
            r[k].v[0] = 0.0;
            r[k].v[1] = (double)((k / 13) % 3) * 0.5;
            r[k].v[2] = uni(&seed, -1.1, 1.1);
            r[k].v[3] = uni(&seed, -1.1, 1.1);
        } else {
            r[k].v[0] = uni(&seed, -20, 20);
            r[k].v[1] = uni(&seed, -20, 20);
            r[k].v[2] = -5.0;
            r[k].v[3] = uni(&seed, -0.3, 0.3);
            r[k].v[4] = uni(&seed, -0.3, 0.3);
            r[k].v[5] = 1.0;
        }
    }
    if (kind == SG_RAYS_NORMALIZED && n > 40)
        r[40].v[2] = NAN;
    return n;
}

static void check(const char *file, sg_method m, sg_ray_kind kind, size_t nray)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    int ns = sys->nsurf, threads[3] = {1, 2, 3}, th, k;
    int image[1] = {ns - 1};
    int list[5] = {ns - 1, 0, 1, 1, ns / 2};
    const int *sels[2] = {image, list};
    const int nsels[2] = {1, 5};
    sg_trace_opts o;
    sg_diag d;
    sg_ray_in *rays = calloc(nray, sizeof *rays);
    sg_ray_surface *full = calloc(nray * (size_t)ns, sizeof *full);
    sg_ray_surface *part = calloc(nray * 5, sizeof *part);
    int *st = calloc(nray, sizeof *st), *st2 = calloc(nray, sizeof *st2);
    size_t r;
    assert_non_null(rays);
    assert_non_null(full);
    assert_non_null(part);
    make_rays(kind, rays, nray, 20261124u + (uint64_t)m);
    sg_trace_opts_init(&o);
    o.method = m;
    sg_diag_clear(&d);
    assert_int_equal(sg_trace_batch(sys, cat, &o, kind, rays, nray, 2, full, st, &d), SG_OK);
    for (th = 0; th < 3; th++) {
        sg_batch *b = sg_batch_new(sys, cat, &o, threads[th], &d);
        assert_non_null(b);
        assert_int_equal(sg_batch_nsurf(b), ns);
        for (k = 0; k < 2; k++) {
            /* Three calls on one kept batch, of uneven sizes. */
            size_t cut[4] = {0, 7, nray / 2 + 3, nray}, c;
            memset(part, 0xA5, nray * 5 * sizeof *part);
            for (c = 0; c < 3; c++)
                assert_int_equal(sg_batch_trace(b, kind, rays + cut[c], cut[c + 1] - cut[c],
                                                sels[k], nsels[k], part + cut[c] * nsels[k],
                                                st2 + cut[c], &d),
                                 SG_OK);
            assert_memory_equal(st, st2, nray * sizeof *st);
            for (r = 0; r < nray; r++) {
                int i;
                for (i = 0; i < nsels[k]; i++)
                    same_row(&part[r * (size_t)nsels[k] + (size_t)i],
                             &full[r * (size_t)ns + (size_t)sels[k][i]]);
            }
        }
        /* Every surface, through the kept object. */
        {
            sg_ray_surface *all = calloc(nray * (size_t)ns, sizeof *all);
            assert_non_null(all);
            assert_int_equal(sg_batch_trace(b, kind, rays, nray, NULL, 0, all, st2, &d), SG_OK);
            assert_memory_equal(st, st2, nray * sizeof *st);
            for (r = 0; r < nray * (size_t)ns; r++)
                same_row(&all[r], &full[r]);
            free(all);
        }
        sg_batch_free(b);
    }
    print_message("# %s %s %s: %zu rays, image only and a list of 5, 1-3 threads\n", file,
                  sg_method_name(m), kind == SG_RAYS_NORMALIZED ? "normalized" : "start/dir",
                  nray);
    free(rays);
    free(full);
    free(part);
    free(st);
    free(st2);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void precise(void **state)
{
    (void)state;
    check("double_gauss.json", SG_METHOD_PRECISE, SG_RAYS_NORMALIZED, 3001);
    check("cassegrain.json", SG_METHOD_PRECISE, SG_RAYS_START_DIR, 3001);
    check("tma.json", SG_METHOD_PRECISE, SG_RAYS_NORMALIZED, 1001);
}

static void classic(void **state)
{
    (void)state;
    check("double_gauss.json", SG_METHOD_CLASSIC, SG_RAYS_NORMALIZED, 2001);
    check("cassegrain.json", SG_METHOD_CLASSIC, SG_RAYS_START_DIR, 2001);
}

static void mpfr(void **state)
{
    (void)state;
    check("cooke_triplet.json", SG_METHOD_MPFR, SG_RAYS_NORMALIZED, 150);
    check("cassegrain.json", SG_METHOD_MPFR, SG_RAYS_START_DIR, 150);
}

/* A surface outside the system is refused with a message naming it. */
static void bad_selection(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("singlet.json");
    sg_trace_opts o;
    sg_diag d;
    sg_batch *b;
    sg_ray_in ray = {{0, 0, 0, 0.5, 0, 0}};
    sg_ray_surface row;
    int st, bad[1] = {sys->nsurf};
    (void)state;
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    b = sg_batch_new(sys, cat, &o, 1, &d);
    assert_non_null(b);
    assert_int_equal(sg_batch_trace(b, SG_RAYS_NORMALIZED, &ray, 1, bad, 1, &row, &st, &d),
                     SG_EINVAL);
    assert_non_null(strstr(d.msg, "selected surface"));
    sg_diag_clear(&d);
    assert_int_equal(sg_batch_trace(b, SG_RAYS_NORMALIZED, &ray, 1, bad, 0, &row, &st, &d),
                     SG_EINVAL);
    sg_batch_free(b);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(precise),
        cmocka_unit_test(classic),
        cmocka_unit_test(mpfr),
        cmocka_unit_test(bad_selection),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
