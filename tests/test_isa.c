/*
 * test_isa.c - in a build for no one processor, the three instruction-set
 * variants of the vector trace (src/isa.h, src/dispatch.c) give the same
 * bits.
 *
 * The reference is the baseline (SSE2) variant; the AVX2 and AVX-512 ones
 * are compared with it on every bundled example, for the precise and the
 * classic method, on a grid of rays across field and pupil that includes
 * pupil corners which fail.  A variant this processor cannot run is
 * reported and skipped.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "trace_internal.h"

/* The per-variant batch cores (batch.c, named by src/isa.h). */
typedef int run_fn(sg_tracer *const *t, int nt, sg_ray_kind kind, const sg_ray_in *rays,
                   size_t nray, const int *sel, int nsel, sg_ray_surface *scratch,
                   sg_ray_surface *out, int *status);
run_fn sg_batch_run_base, sg_batch_run_v3, sg_batch_run_v4;

static const struct {
    const char *name, *level;
    run_fn *fn;
} variants[] = {
    {"x86-64-v3 (AVX2, FMA)", "x86-64-v3", sg_batch_run_v3},
    {"x86-64-v4 (AVX-512)", "x86-64-v4", sg_batch_run_v4},
};

/* sg_trace_batch through one variant, on nt tracers made here; with sel,
 * only those surfaces are kept (as sg_batch_trace keeps them). */
static int run_variant(run_fn *fn, const sg_system *sys, const sg_catalog *cat,
                       const sg_trace_opts *o, const sg_ray_in *rays, size_t nray, int nt,
                       const int *sel, int nsel, sg_ray_surface *out, int *status)
{
    sg_tracer *t[4];
    sg_ray_surface *scratch = NULL;
    sg_diag d;
    int k, rc;
    assert_true(nt >= 1 && nt <= 4);
    sg_diag_clear(&d);
    for (k = 0; k < nt; k++) {
        t[k] = sg_tracer_new(sys, cat, o, &d);
        assert_non_null(t[k]);
    }
    if (sel) {
        scratch = calloc((size_t)nt * SG_BATCH_LANES * (size_t)sys->nsurf, sizeof *scratch);
        assert_non_null(scratch);
    }
    rc = fn(t, nt, SG_RAYS_NORMALIZED, rays, nray, sel, nsel, scratch, out, status);
    for (k = 0; k < nt; k++)
        sg_tracer_free(t[k]);
    free(scratch);
    return rc;
}

static int runs(const char *level)
{
    return strcmp(level, "x86-64-v4") == 0 ? __builtin_cpu_supports("x86-64-v4")
                                           : __builtin_cpu_supports("x86-64-v3");
}

static void same_bits(void **state)
{
    static const char *const files[] = {"cassegrain.json", "cooke_triplet.json",
                                        "double_gauss.json", "singlet.json", "tma.json"};
    static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC};
    enum { NX = 13, NRAY = 3 * NX * NX };
    sg_catalog *cat = tu_catalog();
    size_t f, m, v, compared = 0, k;
    (void)state;
    for (f = 0; f < sizeof files / sizeof files[0]; f++) {
        sg_system *sys = tu_example(files[f]);
        size_t ns = (size_t)sys->nsurf;
        sg_ray_in *rays = calloc(NRAY, sizeof *rays);
        sg_ray_surface *ref = calloc(NRAY * ns, sizeof *ref);
        sg_ray_surface *got = calloc(NRAY * ns, sizeof *got);
        int *sr = calloc(NRAY, sizeof *sr), *sg = calloc(NRAY, sizeof *sg), h, i, j, n = 0;
        assert_true(rays && ref && got && sr && sg);
        for (h = 0; h < 3; h++)
            for (i = 0; i < NX; i++)
                for (j = 0; j < NX; j++, n++) {
                    rays[n].v[0] = 0.0;
                    rays[n].v[1] = 0.5 * h;
                    rays[n].v[2] = -1.2 + 2.4 * i / (NX - 1);
                    rays[n].v[3] = -1.2 + 2.4 * j / (NX - 1);
                }
        for (m = 0; m < sizeof methods / sizeof methods[0]; m++) {
            sg_trace_opts o;
            sg_diag d;
            sg_trace_opts_init(&o);
            o.method = methods[m];
            sg_diag_clear(&d);
            assert_int_equal(run_variant(sg_batch_run_base, sys, cat, &o, rays, NRAY, 1, NULL, 0,
                                         ref, sr),
                             SG_OK);
            for (v = 0; v < sizeof variants / sizeof variants[0]; v++) {
                if (!runs(variants[v].level))
                    continue;
                memset(got, 0, NRAY * ns * sizeof *got);
                assert_int_equal(run_variant(variants[v].fn, sys, cat, &o, rays, NRAY, 2, NULL,
                                             0, got, sg),
                                 SG_OK);
                for (k = 0; k < NRAY * ns; k++) {
                    if (!tu_same_row(&ref[k], &got[k]))
                        fail_msg("%s, %s, %s: ray %zu surface %zu differs from the baseline",
                                 files[f], sg_method_name(methods[m]), variants[v].name,
                                 k / ns, k % ns);
                }
                assert_memory_equal(sr, sg, NRAY * sizeof *sr);
                compared += NRAY * ns;
                /* The image and the object alone, through the selection path. */
                {
                    const int sel[2] = {(int)ns - 1, 0};
                    memset(got, 0, NRAY * 2 * sizeof *got);
                    assert_int_equal(run_variant(variants[v].fn, sys, cat, &o, rays, NRAY, 2,
                                                 sel, 2, got, sg),
                                     SG_OK);
                    for (k = 0; k < 2 * (size_t)NRAY; k++) {
                        const sg_ray_surface *a = &ref[(k / 2) * ns + (size_t)sel[k % 2]];
                        assert_memory_equal(&a->x, &got[k].x, 10 * sizeof(double));
                        assert_int_equal(a->status, got[k].status);
                    }
                    assert_memory_equal(sr, sg, NRAY * sizeof *sr);
                }
            }
        }
        free(rays);
        free(ref);
        free(got);
        free(sr);
        free(sg);
        sg_system_free(sys);
    }
    for (v = 0; v < sizeof variants / sizeof variants[0]; v++)
        print_message("# %s: %s\n", variants[v].name,
                      runs(variants[v].level) ? "compared with the baseline"
                                              : "not run: this processor lacks it");
    print_message("# %zu rows (ray x surface) equal the baseline's in every field and status\n",
                  compared);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(same_bits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
