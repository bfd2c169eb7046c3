/*
 * test_examples.c - the paper's two space cameras.
 *
 * Independent sources: the Zemax values printed in Tables 4 and 6 of Wu et
 * al. (2023), to their 11 significant digits, and the mpfr method at 256
 * bits for every digit beyond that.  The paper's own values are printed
 * beside ours so the gain is visible.
 *
 * The bundled double Gauss against its patent: Angenieux, US 2,701,982
 * (EFL 100, back focus 55.742, as tabulated in W. J. Smith, Modern Lens
 * Design, 1992), by a y-nu trace written here from the catalog indices.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

typedef struct row {
    int surf;
    double y, z;         /* Zemax, as printed */
    double py, pz;       /* the paper's method, as printed (0 where none) */
} row;

static const row cassegrain_rows[] = {
    {1, 1.53512783170000e3, 0, 1.53512783172994e3, 0},
    {2, 1.50000000000000e3, -1.07335208170000e2, 1.49999999999948e3, -1.07335208171627e2},
    {3, 4.16656071440000e2, -2.24707333700000e1, 4.16656071439095e2, -2.24707333697088e1},
    {4, 1.25622942630000e2, 0, 1.25622942628122e2, 0},
    {5, 6.23424396090000e1, 0, 6.23424396084419e1, 0},
    {6, -1.49943013290000e2, 7.22185051870000e0, -1.49943013287087e2, 7.22185051869110e0},
    {7, -1.53288434560000e2, 2.17676371440000e0, -1.53288434563366e2, 2.17676371435573e0},
    {8, -1.62777534960000e2, -4.82758062840000e0, -1.62777534965079e2, -4.82758062839639e0},
    {9, -1.68760549770000e2, 3.15420842640000e0, -1.68760549772527e2, 3.15420842636740e0},
    {10, -1.84834455040000e2, -6.12729217780000e0, -1.84834455036683e2, -6.12729217781634e0},
    {11, -1.94567071100000e2, 1.03295178760000e1, -1.94567071101658e2, 1.03295178756579e1},
    {12, -2.18853927910000e2, 0, -2.18853927906069e2, 0},
    {13, -2.18933499090000e2, 0, -2.18933499087856e2, 0},
    {14, -2.19063914210000e2, 0, -2.19063914207259e2, 0},
};

static const row tma_rows[] = {
    {1, -2.01651556350000e2, 0, -2.01651556349517e2, 0},
    {2, -1.03337392020000e2, -1.98221886410000e0, -1.03337392022989e2, -1.98221886405031e0},
    {3, 4.55199992300000e1, -1.07580474620000e0, 4.55199992296308e1, -1.07580474621568e0},
    {4, 2.52430579520000e2, -2.17467853090000e1, 2.52430579518327e2, -2.17467853091218e1},
    {5, 2.32101258960000e2, 0, 2.32101258958268e2, 0},
};

/* True when a rounded to 11 significant digits prints as b does. */
static int same11(double a, double b)
{
    char sa[64], sb[64];
    snprintf(sa, sizeof sa, "%.10e", a);
    snprintf(sb, sizeof sb, "%.10e", b);
    if (a == 0.0 && b == 0.0)
        return 1;
    return strcmp(sa, sb) == 0;
}

/* Digits of one coordinate.  A coordinate far smaller than its point (a
 * meridional x of 1e-14, say) is judged against 1e-6 of the point's size,
 * since its relative error says nothing about the trace. */
static double coord_digits(double a, double b, double pscale)
{
    double den = fmax(fabs(b), 1e-6 * pscale);
    if (a == b)
        return 17.0;
    if (den == 0.0)
        return 0.0;
    return fmin(17.0, fmax(0.0, -log10(fabs(a - b) / den)));
}

static double point_digits(const sg_ray_surface *a, const sg_ray_surface *b)
{
    double sc = fmax(fabs(b->x), fmax(fabs(b->y), fabs(b->z)));
    return fmin(coord_digits(a->x, b->x, sc),
                fmin(coord_digits(a->y, b->y, sc), coord_digits(a->z, b->z, sc)));
}

static void against_zemax(const char *file, const row *rows, size_t nrows, int exception_surf)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_tracer *tp = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    sg_tracer *tc = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
    sg_tracer *tm = tu_tracer(sys, cat, SG_METHOD_MPFR);
    sg_ray_surface op[32], oc[32], om[32];
    size_t k;
    int agree = 0, total = 0;
    assert_int_equal(sg_trace_normalized(tp, 0, 1, 0, 1, op), SG_OK);
    assert_int_equal(sg_trace_normalized(tc, 0, 1, 0, 1, oc), SG_OK);
    assert_int_equal(sg_trace_normalized(tm, 0, 1, 0, 1, om), SG_OK);
    print_message("# %s, ray (0,1,0,1): digits against the mpfr method (256 bits)\n", file);
    print_message("# surf  y (precise)              z (precise)              precise classic "
                  "paper\n");
    for (k = 0; k < nrows; k++) {
        const row *r = &rows[k];
        const sg_ray_surface *p = &op[r->surf], *m = &om[r->surf];
        double dp = point_digits(p, m), dc = point_digits(&oc[r->surf], m);
        sg_ray_surface paper = *m;
        double dpaper;
        paper.y = r->py;
        paper.z = r->pz == 0 ? m->z : r->pz;
        dpaper = point_digits(&paper, m);
        print_message("# %4d  %.17g  %.17g  %5.1f  %5.1f  %5.1f\n", r->surf, p->y, p->z, dp, dc,
                      dpaper);
        /* Zemax prints 11 significant digits. */
        total += 2;
        if (r->surf == exception_surf) {
            /* paper-notes: Zemax's last digit of surface 8 y is one unit
             * off; the exact value is -162.777534965071. */
            assert_true(same11(p->y, -162.777534965071));
            assert_false(same11(p->y, r->y));
            agree++;
        } else if (same11(p->y, r->y)) {
            agree++;
        } else {
            fail_msg("surface %d y: %.17g does not round to Zemax's %.11g", r->surf, p->y, r->y);
        }
        if (same11(p->z, r->z))
            agree++;
        else
            fail_msg("surface %d z: %.17g does not round to Zemax's %.11g", r->surf, p->z, r->z);
        assert_true(p->x == 0.0);
        /* Beat the paper: 15 digits or more at every surface. */
        assert_true(dp >= 15.0);
        assert_true(fabs(p->y - m->y) <= p->error_bound);
        assert_true(fabs(p->z - m->z) <= p->error_bound);
    }
    print_message("# %d of %d Zemax values agree to 11 digits (surface-8 y as noted)\n", agree,
                  total);
    sg_tracer_free(tp);
    sg_tracer_free(tc);
    sg_tracer_free(tm);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void cassegrain_table4(void **state)
{
    (void)state;
    against_zemax("cassegrain.json", cassegrain_rows,
                  sizeof cassegrain_rows / sizeof cassegrain_rows[0], 8);
}

static void tma_table6(void **state)
{
    (void)state;
    against_zemax("tma.json", tma_rows, sizeof tma_rows / sizeof tma_rows[0], -1);
}

static int same_d(double a, double b, double scale)
{
    return a == b || fabs(a - b) <= ldexp(scale, -200);
}

/* A grid over field and pupil: precise against mpfr at every surface, and
 * the bound never below the difference. */
static void grid(const char *file, int n)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_tracer *tp = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    sg_tracer *tc = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
    sg_tracer *tm = tu_tracer(sys, cat, SG_METHOD_MPFR);
    sg_ray_surface op[32], oc[32], om[32];
    double minp[32], minc[32], cerr[32] = {0}, worst_ratio = INFINITY;
    int i, hx, hy, px, py, nrays = 0, ns = sys->nsurf;
    for (i = 0; i < ns; i++)
        minp[i] = minc[i] = 17.0;
    for (hx = 0; hx < 3; hx++)
        for (hy = 0; hy < 3; hy++)
            for (px = 0; px < n; px++)
                for (py = 0; py < n; py++) {
                    double Hx = (hx - 1) * 0.7, Hy = (hy - 1) * 1.0;
                    double Px = -1.0 + 2.0 * px / (n - 1), Py = -1.0 + 2.0 * py / (n - 1);
                    int rp, rm;
                    if (Px * Px + Py * Py > 1.0)
                        continue;
                    rm = sg_trace_normalized(tm, Hx, Hy, Px, Py, om);
                    rp = sg_trace_normalized(tp, Hx, Hy, Px, Py, op);
                    assert_int_equal(rp, rm);
                    if (rm != SG_OK)
                        continue;
                    nrays++;
                    if (sg_trace_normalized(tc, Hx, Hy, Px, Py, oc) != SG_OK)
                        memset(oc, 0, sizeof oc);
                    else
                        for (i = 1; i < ns; i++)
                            cerr[i] = fmax(cerr[i], fmax(fabs(oc[i].x - om[i].x),
                                                         fmax(fabs(oc[i].y - om[i].y),
                                                              fabs(oc[i].z - om[i].z))));
                    for (i = 1; i < ns; i++) {
                        double e = fmax(fabs(op[i].x - om[i].x),
                                        fmax(fabs(op[i].y - om[i].y), fabs(op[i].z - om[i].z)));
                        minp[i] = fmin(minp[i], point_digits(&op[i], &om[i]));
                        minc[i] = fmin(minc[i], point_digits(&oc[i], &om[i]));
                        /* docs/precision.md: precise equals the 256-bit mpfr trace in
                         * every digit at every surface: the same doubles,
                         * except a coordinate that is zero in one and the
                         * 256-bit aiming's residue (below 2^-200 of the
                         * point's size) in the other. */
                        double sc = fmax(fabs(om[i].x), fmax(fabs(om[i].y), fabs(om[i].z)));
                        if (!same_d(op[i].x, om[i].x, sc) || !same_d(op[i].y, om[i].y, sc) ||
                            !same_d(op[i].z, om[i].z, sc) || !same_d(op[i].l, om[i].l, 1.0) ||
                            !same_d(op[i].m, om[i].m, 1.0) || !same_d(op[i].n, om[i].n, 1.0))
                            fail_msg("%s ray (%g,%g,%g,%g) surface %d: precise differs from "
                                     "mpfr (y %.17g vs %.17g, m %.17g vs %.17g)", file, Hx, Hy,
                                     Px, Py, i, op[i].y, om[i].y, op[i].m, om[i].m);
                        if (e > op[i].error_bound)
                            fail_msg("%s ray (%g,%g,%g,%g) surface %d: error %.3g above bound "
                                     "%.3g", file, Hx, Hy, Px, Py, i, e, op[i].error_bound);
                        if (e > 0)
                            worst_ratio = fmin(worst_ratio, op[i].error_bound / e);
                    }
                }
    print_message("# %s: %d rays over field and pupil; min digits against mpfr per surface\n",
                  file, nrays);
    for (i = 1; i < ns; i++) {
        print_message("#   surface %2d  precise %5.1f  classic %5.1f (largest classic error "
                      "%.3g mm)\n", i, minp[i], minc[i], cerr[i]);
        /* Classic's points stay within 1e-8 mm of the reference (measured
         * 3.5e-10 on the Cassegrain, 6.8e-13 on the TMA): a mirror
         * reflection off by 5e-7 moves the Cassegrain's image 5.5 um. */
        assert_true(cerr[i] <= 1e-8);
        assert_true(minp[i] >= 15.0);
    }
    print_message("# smallest bound/error ratio: %.3g\n", worst_ratio);
    assert_true(nrays > 20);
    sg_tracer_free(tp);
    sg_tracer_free(tc);
    sg_tracer_free(tm);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void cassegrain_grid(void **state)
{
    (void)state;
    grid("cassegrain.json", 7);
}

static void tma_grid(void **state)
{
    (void)state;
    grid("tma.json", 7);
}

/* The patent's glasses put the paraxial focus on the image surface: a y-nu
 * trace of the marginal ray from the catalog's d-line indices lands within
 * 0.5 um of the axis (the design's glass substitutes once left it 1 mm off,
 * 2.1 mm out of focus), and the EFL and back focus are the patent's to its
 * printed digits (EFL 100 within 0.1%, BFL 55.742 within 0.001). */
static void double_gauss_patent(void **state)
{
    sg_system *sys = tu_example("double_gauss.json");
    sg_catalog *cat = tu_catalog();
    const double um = 0.5875618, h = 45.45;
    double y = h, nu = 0.0, n = 1.0, efl, bfl, yimg = 0.0;
    sg_paraxial p;
    sg_diag d;
    int i;
    (void)state;
    assert_int_equal(sys->nsurf, 17);
    assert_true(sys->wave[sys->primary_wave].um == um);
    for (i = 1; i < sys->nsurf - 1; i++) {
        const sg_surface *s = &sys->surf[i];
        double c = isinf(s->radius) ? 0.0 : 1.0 / s->radius, n2 = 1.0;
        if (s->mat.kind == SG_MAT_GLASS) {
            const sg_glass *g = sg_catalog_find(cat, s->mat.name);
            assert_non_null(g);
            n2 = sg_glass_index(g, um);
        } else {
            assert_int_equal(s->mat.kind, SG_MAT_AIR);
        }
        nu -= y * c * (n2 - n);
        n = n2;
        if (i < sys->nsurf - 2)
            y += s->thickness * nu / n;
        else
            yimg = y + s->thickness * nu / n;
    }
    efl = -h / nu;
    bfl = -y / nu;
    assert_int_equal(sg_paraxial_compute(sys, cat, sys->primary_wave, &p, &d), SG_OK);
    print_message("# double Gauss: EFL %.9g (patent 100), BFL %.9g (patent 55.742, surface 15 "
                  "%.9g), marginal ray at the image %.3g mm; engine EFL %.17g BFL %.17g\n",
                  efl, bfl, sys->surf[sys->nsurf - 2].thickness, yimg, p.efl, p.bfl);
    assert_true(fabs(efl - 100.0) < 0.1);
    assert_true(fabs(bfl - 55.742) < 0.001);
    assert_true(fabs(yimg) < 5e-4);
    assert_true(fabs(p.efl - efl) < 1e-9 * efl);
    assert_true(fabs(p.bfl - bfl) < 1e-9 * bfl);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(cassegrain_table4),
        cmocka_unit_test(tma_table6),
        cmocka_unit_test(cassegrain_grid),
        cmocka_unit_test(tma_grid),
        cmocka_unit_test(double_gauss_patent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
