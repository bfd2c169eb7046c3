/*
 * test_isa.c - in a build for no one processor, the three instruction-set
 * variants of the vector trace (src/num/isa.h, src/trace/dispatch.c) give the same
 * bits.
 *
 * The reference is the baseline (SSE2) variant; the AVX2 and AVX-512 ones
 * are compared with it on every bundled example, for the precise and the
 * classic method, on a grid of rays across field and pupil that includes
 * pupil corners which fail, and on the Cassegrain with its primary made
 * each shape of src/shape/shape.h in turn; the classic kernel alone on hard
 * start points and directions; and the OPD of runs of rays (opd_vec.c)
 * against sg_opd_of_ray, the scalar form, with image rows made hard.  A
 * variant this processor cannot run is
 * reported and skipped.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "trace_int.h"

/* The per-variant batch cores (batch.c, named by src/num/isa.h). */
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

/* Every variant against the baseline on one system, both methods; adds
 * the rows compared to *compared. */
static void compare_system(const sg_system *sys, const char *what, const sg_catalog *cat,
                           size_t *compared)
{
    static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC};
    enum { NX = 13, NRAY = 3 * NX * NX };
    size_t ns = (size_t)sys->nsurf, m, v, k;
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
        assert_int_equal(
            run_variant(sg_batch_run_base, sys, cat, &o, rays, NRAY, 1, NULL, 0, ref, sr), SG_OK);
        for (v = 0; v < sizeof variants / sizeof variants[0]; v++) {
            if (!runs(variants[v].level))
                continue;
            memset(got, 0, NRAY * ns * sizeof *got);
            assert_int_equal(
                run_variant(variants[v].fn, sys, cat, &o, rays, NRAY, 2, NULL, 0, got, sg),
                SG_OK);
            for (k = 0; k < NRAY * ns; k++) {
                if (!tu_same_row(&ref[k], &got[k]))
                    fail_msg("%s, %s, %s: ray %zu surface %zu differs from the baseline", what,
                             sg_method_name(methods[m]), variants[v].name, k / ns, k % ns);
            }
            assert_memory_equal(sr, sg, NRAY * sizeof *sr);
            *compared += NRAY * ns;
            /* The image and the object alone, through the selection path. */
            {
                const int sel[2] = {(int)ns - 1, 0};
                memset(got, 0, NRAY * 2 * sizeof *got);
                assert_int_equal(run_variant(variants[v].fn, sys, cat, &o, rays, NRAY, 2, sel, 2,
                                             got, sg),
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
}

static void report_variants(size_t compared)
{
    size_t v;
    for (v = 0; v < sizeof variants / sizeof variants[0]; v++)
        print_message("# %s: %s\n", variants[v].name,
                      runs(variants[v].level) ? "compared with the baseline"
                                              : "not run: this processor lacks it");
    print_message("# %zu rows (ray x surface) equal the baseline's in every field and status\n",
                  compared);
}

static void same_bits(void **state)
{
    static const char *const files[] = {"cassegrain.json", "cooke_triplet.json",
                                        "double_gauss.json", "singlet.json", "tma.json"};
    sg_catalog *cat = tu_catalog();
    size_t f, compared = 0;
    (void)state;
    for (f = 0; f < sizeof files / sizeof files[0]; f++) {
        sg_system *sys = tu_example(files[f]);
        compare_system(sys, files[f], cat, &compared);
        sg_system_free(sys);
    }
    report_variants(compared);
    sg_catalog_free(cat);
}

/* The shapes beyond the even asphere, whose double-double sags the
 * vector trace evaluates on all lanes at once (src/shape/shape_vdd.h): the
 * Cassegrain's primary made each of them in turn, with terms that move
 * the sag by micrometres to a millimetre at its rim. */
static void shapes_same_bits(void **state)
{
    static const int types[] = {SG_SURF_ODDASPH, SG_SURF_TOROIDAL, SG_SURF_BICONIC,
                                SG_SURF_ZERNIKE_FRINGE, SG_SURF_ZERNIKE_STANDARD,
                                SG_SURF_XYPOLY};
    sg_catalog *cat = tu_catalog();
    size_t t, compared = 0;
    (void)state;
    for (t = 0; t < sizeof types / sizeof types[0]; t++) {
        sg_system *sys = tu_example("cassegrain.json");
        sg_surface *p = &sys->surf[2];
        char what[64];
        sg_diag d;
        p->type = (sg_surf_type)types[t];
        switch (types[t]) {
        case SG_SURF_ODDASPH:
            p->odd[2] = 2e-13;
            p->odd[3] = -1e-17;
            p->odd[4] = 1e-21;
            break;
        case SG_SURF_TOROIDAL:
            p->radius_x = -10400.0;
            p->asph[1] = 1e-16;
            break;
        case SG_SURF_BICONIC:
            p->radius_x = -10450.0;
            p->conic_x = -1.0;
            break;
        default:
            p->norm_radius = 1500.0;
            p->terms[3] = 1e-3;
            p->terms[4] = -5e-4;
            p->terms[7] = 2e-4;
            p->terms[8] = -2e-4;
            p->zern_dx = types[t] == SG_SURF_ZERNIKE_STANDARD ? 3.0 : 0.0;
            break;
        }
        sg_diag_clear(&d);
        if (sg_system_validate(sys, cat, &d) != SG_OK)
            fail_msg("primary of type %d: %s", types[t], d.msg);
        snprintf(what, sizeof what, "cassegrain, primary of type %d", types[t]);
        compare_system(sys, what, cat, &compared);
        sg_system_free(sys);
    }
    report_variants(compared);
    sg_catalog_free(cat);
}

/* The classic kernel of each variant (trace_classic_vec.c, named by
 * src/num/isa.h) on start points and directions, hard ones among them, in
 * blocks of up to four lanes (every variant has at least four). */
typedef void classic_fn(const sg_tracer *t, const double (*S)[3], const double (*D)[3],
                        sg_ray_surface *const *out, int nl, int upto, int *rc);
classic_fn sg_classic_block_base, sg_classic_block_v3, sg_classic_block_v4;

static void classic_blocks(void **state)
{
    static const char *const files[] = {"cassegrain.json", "cooke_triplet.json",
                                        "double_gauss.json", "singlet.json", "tma.json"};
    static const struct {
        const char *level;
        classic_fn *fn;
    } cv[] = {{"x86-64-v3", sg_classic_block_v3}, {"x86-64-v4", sg_classic_block_v4}};
    enum { NB = 300, W = 4 };
    sg_catalog *cat = tu_catalog();
    uint64_t rng = 7;
    size_t f, compared = 0;
    (void)state;
    for (f = 0; f < sizeof files / sizeof files[0]; f++) {
        sg_system *sys = tu_example(files[f]);
        sg_tracer *t = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
        int ns = sys->nsurf, b, k, i, v;
        double S[W][3], D[W][3];
        sg_ray_surface *ref[W], *got[W];
        for (k = 0; k < W; k++) {
            ref[k] = calloc((size_t)ns, sizeof *ref[k]);
            got[k] = calloc((size_t)ns, sizeof *got[k]);
            assert_true(ref[k] && got[k]);
        }
        for (b = 0; b < NB; b++) {
            int nl = 1 + b % W, rr[W], rg[W];
            for (k = 0; k < nl; k++) {
                double u[6];
                for (i = 0; i < 6; i++) {
                    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
                    u[i] = (double)(rng >> 11) * 0x1p-53;
                }
                S[k][0] = 60.0 * (u[0] - 0.5);
                S[k][1] = 60.0 * (u[1] - 0.5);
                S[k][2] = -10.0 * u[2];
                D[k][0] = u[3] - 0.5;
                D[k][1] = u[4] - 0.5;
                /* Grazing, across and backwards now and then; huge and
                 * tiny unnormalized directions. */
                D[k][2] = u[5] < 0.1 ? 1e-3 * u[5] : u[5] < 0.15 ? -1.0 : 1.0;
                if (b % 7 == 3)
                    for (i = 0; i < 3; i++)
                        D[k][i] *= (b % 2 ? 0x1p-520 : 0x1p+500);
                if (b % 11 == 5)
                    S[k][0] *= 1e150;
            }
            for (k = 0; k < nl; k++)
                memset(ref[k], 0x33, (size_t)ns * sizeof *ref[k]);
            sg_classic_block_base(t, (const double(*)[3])S, (const double(*)[3])D, ref, nl,
                                  ns - 1, rr);
            for (v = 0; v < 2; v++) {
                if (!runs(cv[v].level))
                    continue;
                for (k = 0; k < nl; k++)
                    memset(got[k], 0x33, (size_t)ns * sizeof *got[k]);
                cv[v].fn(t, (const double(*)[3])S, (const double(*)[3])D, got, nl, ns - 1, rg);
                for (k = 0; k < nl; k++) {
                    if (rg[k] != rr[k] ||
                        memcmp(ref[k], got[k], (size_t)ns * sizeof *ref[k]) != 0)
                        fail_msg("%s, classic block %d lane %d: %s differs from the baseline",
                                 files[f], b, k, cv[v].level);
                    compared += (size_t)ns;
                }
            }
        }
        for (k = 0; k < W; k++) {
            free(ref[k]);
            free(got[k]);
        }
        sg_tracer_free(t);
        sg_system_free(sys);
    }
    print_message("# classic kernel: %zu rows equal the baseline's\n", compared);
    sg_catalog_free(cat);
}

/* The OPD on lanes (opd_vec.c, named by src/num/isa.h): every variant, the
 * baseline too, against sg_opd_of_ray on each example's pupil grid
 * through and beyond the rim, in runs of 1 to 9 rays, and on the same
 * rows with a coordinate made huge, tiny, subnormal, zero or NaN. */
typedef int opd_fn(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *rows,
                   size_t stride, size_t n, sg_opd *out);
opd_fn sg_opd_of_rays_base, sg_opd_of_rays_v3, sg_opd_of_rays_v4;

static int same_d(double a, double b)
{
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

static void opd_runs(void **state)
{
    static const char *const files[] = {"cassegrain.json", "cooke_triplet.json",
                                        "double_gauss.json", "singlet.json", "tma.json"};
    static const sg_method methods[] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC};
    static const double odd[] = {1e200, -1e-300, 4.9406564584124654e-324, -0.0, NAN, 5e8};
    static const struct {
        const char *level;
        opd_fn *fn;
    } ov[] = {{NULL, sg_opd_of_rays_base},
              {"x86-64-v3", sg_opd_of_rays_v3},
              {"x86-64-v4", sg_opd_of_rays_v4}};
    enum { NG = 11, NODD = sizeof odd / sizeof odd[0], CAP = NG * NG * (1 + 3 * NODD) };
    sg_catalog *cat = tu_catalog();
    sg_ray_surface *img = malloc(CAP * sizeof *img);
    sg_opd *got = malloc(CAP * sizeof *got), want;
    size_t f, compared = 0, okrays = 0;
    (void)state;
    assert_true(img && got);
    for (f = 0; f < sizeof files / sizeof files[0]; f++) {
        sg_system *sys = tu_example(files[f]);
        size_t m;
        for (m = 0; m < 2; m++) {
            sg_tracer *t = tu_tracer(sys, cat, methods[m]);
            int ns = sg_tracer_nsurf(t), i, j, k, c;
            sg_ray_surface *rows = malloc((size_t)ns * sizeof *rows);
            sg_opd_ref ref;
            sg_diag d;
            size_t n = 0, g, v, at, run, r;
            assert_non_null(rows);
            sg_diag_clear(&d);
            assert_int_equal(sg_opd_reference(t, 0.0, 0.7, &ref, &d), SG_OK);
            for (i = 0; i < NG; i++)
                for (j = 0; j < NG; j++) {
                    sg_trace_normalized(t, 0.0, 0.7, 1.3 * (2.0 * i / (NG - 1) - 1.0),
                                        1.3 * (2.0 * j / (NG - 1) - 1.0), rows);
                    img[n++] = rows[ns - 1];
                }
            g = n;
            for (r = 0; r < g; r++)
                for (k = 0; k < NODD; k++)
                    for (c = 0; c < 3; c++) {
                        img[n] = img[r];
                        if (c == 0)
                            img[n].x = odd[k];
                        else if (c == 1)
                            img[n].m = odd[k];
                        else
                            img[n].path = odd[k];
                        n++;
                    }
            for (v = 0; v < 3; v++) {
                if (ov[v].level && !runs(ov[v].level))
                    continue;
                for (run = 1; run <= 9; run++) {
                    for (at = 0; at < n; at += run)
                        assert_int_equal(ov[v].fn(t, &ref, img + at, 1,
                                                  n - at < run ? n - at : run, got + at),
                                         SG_OK);
                    for (r = 0; r < n; r++) {
                        sg_opd_of_ray(t, &ref, &img[r], &want);
                        if (want.status != got[r].status ||
                            !same_d(want.opd_waves, got[r].opd_waves) ||
                            !same_d(want.error_bound, got[r].error_bound) ||
                            !same_d(want.ex, got[r].ex) || !same_d(want.ey, got[r].ey) ||
                            !same_d(want.opl, got[r].opl) || !same_d(want.opl_lo, got[r].opl_lo))
                            fail_msg("%s %s, ray %zu in runs of %zu: %s differs from the "
                                     "scalar OPD (%.17g against %.17g)",
                                     files[f], m ? "classic" : "precise", r, run,
                                     ov[v].level ? ov[v].level : "baseline",
                                     got[r].opd_waves, want.opd_waves);
                        compared++;
                        okrays += want.status == SG_OK;
                    }
                }
            }
            free(rows);
            sg_tracer_free(t);
        }
        sg_system_free(sys);
    }
    assert_true(okrays > compared / 4);
    print_message("# opd on lanes: %zu results equal the scalar ones (%zu OK)\n", compared,
                  okrays);
    free(img);
    free(got);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(same_bits),
        cmocka_unit_test(shapes_same_bits),
        cmocka_unit_test(classic_blocks),
        cmocka_unit_test(opd_runs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
