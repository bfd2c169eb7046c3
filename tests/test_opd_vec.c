/*
 * test_opd_vec.c - sg_opd_of_rays (vector lanes) against sg_opd_of_ray
 * (one ray), bit for bit.
 *
 * The vector form must give every ray the scalar form's bits, so the
 * scalar function is the reference here (its own truth is test_opd's).
 * Rays: every example, precise and classic, fields on and off axis, a
 * pupil grid through and beyond the rim (vignetted and missing rays,
 * grazing ones at the rim), in runs of every length from 1 to 19 (the
 * lanes past a run's end); then the same image rows made hard by hand:
 * huge and tiny coordinates, subnormals, zeros of both signs, NaN and
 * infinities, zero and unnormalized directions, paths of 5e8, error
 * bounds from zero to huge; and references made hard too (the sphere
 * behind the image, tiny and huge radii, a subnormal centre).
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

/* The same bits, or both NaN (a NaN's sign and payload depend on the
 * order of an operation's operands, which the compiler may choose; no
 * report writes a NaN's bits). */
static int same(double a, double b)
{
    if (isnan(a) && isnan(b))
        return 1;
    return memcmp(&a, &b, sizeof a) == 0;
}

static int same_opd(const sg_opd *a, const sg_opd *b)
{
    return a->status == b->status && same(a->opd_waves, b->opd_waves) &&
           same(a->error_bound, b->error_bound) && same(a->ex, b->ex) && same(a->ey, b->ey) &&
           same(a->sphere_x, b->sphere_x) && same(a->sphere_y, b->sphere_y) &&
           same(a->sphere_z, b->sphere_z) && same(a->opl, b->opl) && same(a->opl_lo, b->opl_lo);
}

/* Compares sg_opd_of_rays on rows[r * stride], r < n, in runs of every
 * length up to 19, with sg_opd_of_ray; returns the OK results seen. */
static size_t check_rows(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *rows,
                         size_t stride, size_t n, const char *what)
{
    sg_opd *v = malloc(n * sizeof *v), s;
    size_t run, at, r, ok = 0;
    assert_non_null(v);
    for (run = 1; run <= 19; run++) {
        for (at = 0; at < n; at += run) {
            size_t m = n - at < run ? n - at : run;
            assert_int_equal(sg_opd_of_rays(t, ref, rows + at * stride, stride, m, v + at),
                             SG_OK);
        }
        for (r = 0; r < n; r++) {
            sg_opd_of_ray(t, ref, &rows[r * stride], &s);
            if (!same_opd(&s, &v[r])) {
                fprintf(stderr,
                        "%s: ray %zu (runs of %zu): vector status %d opd %.17g bound %.17g "
                        "opl %.17g %.17g, scalar status %d opd %.17g bound %.17g opl %.17g "
                        "%.17g\n",
                        what, r, run, v[r].status, v[r].opd_waves, v[r].error_bound, v[r].opl,
                        v[r].opl_lo, s.status, s.opd_waves, s.error_bound, s.opl, s.opl_lo);
                fail();
            }
            ok += run == 1 && s.status == SG_OK;
        }
    }
    free(v);
    return ok;
}

/* The image rows of a pupil grid of field (hx, hy), traced by t. */
static size_t grid_rows(sg_tracer *t, double hx, double hy, sg_ray_surface *img, size_t cap)
{
    int nsurf = sg_tracer_nsurf(t), i, j;
    sg_ray_surface *rows = malloc((size_t)nsurf * sizeof *rows);
    size_t n = 0;
    assert_non_null(rows);
    for (i = -13; i <= 13; i++)
        for (j = -13; j <= 13; j++) {
            /* Beyond the rim to 1.3; (0.6, 0.8) and kin lie on it. */
            double px = i / 10.0, py = j / 10.0;
            if (n == cap)
                break;
            sg_trace_normalized(t, hx, hy, px, py, rows);
            img[n++] = rows[nsurf - 1];
        }
    {
        const double rim[][2] = { { 0.6, 0.8 }, { -0.8, 0.6 }, { 1, 0 }, { 0, -1 },
                                  { 0.70710678118654757, 0.70710678118654746 } };
        for (i = 0; i < 5 && n < cap; i++) {
            sg_trace_normalized(t, hx, hy, rim[i][0], rim[i][1], rows);
            img[n++] = rows[nsurf - 1];
        }
    }
    free(rows);
    return n;
}

/* Rows made hard by hand from real ones. */
static size_t hard_rows(const sg_ray_surface *src, size_t nsrc, sg_ray_surface *out)
{
    static const double odd[] = { 1e200,  -1e200, 1e-300, 4.9406564584124654e-324,
                                  -1e-310, 0.0,   -0.0,   DBL_MAX,
                                  DBL_MIN, 5e8,   -7e-20, 3.0e-292 };
    size_t n = 0, k, r;
    const size_t nodd = sizeof odd / sizeof odd[0];
    for (r = 0; r < nsrc; r++) {
        const sg_ray_surface *g = &src[r];
        if (g->status != SG_OK)
            continue;
        for (k = 0; k < nodd; k++) {
            double v = odd[k];
            sg_ray_surface h;
            int f;
            for (f = 0; f < 12; f++) {
                h = *g;
                switch (f) {
                case 0: h.x = v; break;
                case 1: h.y = v; break;
                case 2: h.z = v; break;
                case 3: h.l = v; h.m = v; break;
                case 4: h.n = v; break;
                case 5: h.opl = v; h.opl_lo = v * 1e-17; break;
                case 6: h.error_bound = v; break;
                case 7: h.dir_error_bound = fabs(v); break;
                case 8: h.opl_error_bound = fabs(v); break;
                case 9: h.x *= 1 + v; h.y = h.x * v; break;
                case 10: h.l = h.m = h.n = 0.0; h.x = v; break;
                default: h.x = NAN; h.l = k % 2 ? INFINITY : -INFINITY; break;
                }
                out[n++] = h;
            }
        }
    }
    return n;
}

/* The references made hard. */
static int hard_ref(const sg_opd_ref *base, int k, sg_opd_ref *r)
{
    *r = *base;
    switch (k) {
    case 0: return 1;
    case 1: r->side = -r->side; return 1;
    case 2: r->radius *= 1e-290; r->radius_lo = 0; return 1;
    case 3: r->radius *= 1e250; return 1;
    case 4: r->cx = 1e-310; r->cy = -0.0; return 1;
    case 5: r->cz += 1e3; r->ez = -r->ez; return 1;
    case 6: r->chief_opl = 5e8; r->chief_opl_lo = 1e-9; return 1;
    case 7: r->centre_error_bound = 1e-300; return 1;
    case 8: r->status = SG_EMISS; return 1;
    default: return 0;
    }
}

static void examples_bit_for_bit(void **state)
{
    const char *const ex[] = { "singlet.json", "cooke_triplet.json", "double_gauss.json",
                               "cassegrain.json", "tma.json" };
    const double fields[][2] = { { 0, 0 }, { 0, 0.7 }, { -0.5, 1 }, { 0, 1.2 } };
    const sg_method methods[] = { SG_METHOD_PRECISE, SG_METHOD_CLASSIC };
    sg_catalog *cat = tu_catalog();
    enum { CAP = 27 * 27 + 8 };
    sg_ray_surface *img = malloc(CAP * sizeof *img);
    sg_ray_surface *hard = malloc(CAP * 12 * 12 * sizeof *hard);
    size_t e, f, m, okays = 0, hards = 0;
    (void)state;
    assert_non_null(img);
    assert_non_null(hard);
    for (e = 0; e < sizeof ex / sizeof ex[0]; e++) {
        sg_system *sys = tu_example(ex[e]);
        for (m = 0; m < 2; m++) {
            sg_tracer *t = tu_tracer(sys, cat, methods[m]);
            for (f = 0; f < sizeof fields / sizeof fields[0]; f++) {
                sg_opd_ref ref, hr;
                char what[160];
                size_t n, nh;
                int k;
                if (sg_opd_reference(t, fields[f][0], fields[f][1], &ref, NULL) != SG_OK)
                    continue;
                n = grid_rows(t, fields[f][0], fields[f][1], img, CAP);
                snprintf(what, sizeof what, "%s %s field (%g, %g)", ex[e],
                         sg_method_name(methods[m]), fields[f][0], fields[f][1]);
                okays += check_rows(t, &ref, img, 1, n, what);
                /* A stride, as trace --rays passes its image rows. */
                {
                    sg_ray_surface *wide = calloc(n * 3, sizeof *wide);
                    size_t r;
                    assert_non_null(wide);
                    for (r = 0; r < n; r++)
                        wide[3 * r + 2] = img[r];
                    check_rows(t, &ref, wide + 2, 3, n, what);
                    free(wide);
                }
                /* The hard rows on every hard reference, from a few rays. */
                nh = hard_rows(img + n / 2, n - n / 2 < 6 ? n - n / 2 : 6, hard);
                for (k = 0; hard_ref(&ref, k, &hr); k++) {
                    snprintf(what, sizeof what, "%s %s field (%g, %g) hard reference %d",
                             ex[e], sg_method_name(methods[m]), fields[f][0], fields[f][1], k);
                    hards += check_rows(t, &hr, hard, 1, nh, what);
                }
            }
            sg_tracer_free(t);
        }
        sg_system_free(sys);
    }
    /* The vector path must have been taken, not only the hand-over. */
    assert_true(okays > 1000);
    assert_true(hards > 100);
    free(img);
    free(hard);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(examples_bit_for_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
