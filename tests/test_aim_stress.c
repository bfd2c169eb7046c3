/*
 * test_aim_stress.c - ray aiming in every mode, every method and at every
 * MPFR precision, against a 512-bit MPFR trace computed here.
 *
 * - Every example in every aiming mode: precise and the 512-bit trace
 *   agree on which rays trace, and where both do, precise is within its
 *   bound plus the reference's at every surface (what `sagitta verify`
 *   checks).  Before the stop radius of real aiming kept its double-double
 *   digits, the Cooke triplet's real aiming was up to 52 times outside.
 * - The mpfr method aims at 53 to 4096 bits and agrees with the 512-bit
 *   trace to about its own precision.
 * - A wide-angle lens (the Fisheye-Nikkor 10.5 mm of US 7,161,746 B2 in
 *   tests/data/) aims its chief and marginal rays to its 80 degree full
 *   field in paraxial and real aiming, with each method; the 512-bit
 *   landing on the stop is (Px, Py) times the stop radius, which comes from
 *   the paraxial module or from an unaimed 512-bit on-axis ray.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

enum { MAXS = 32 };

static const char *const examples[] = {"singlet.json", "cooke_triplet.json",
                                       "double_gauss.json", "cassegrain.json", "tma.json"};
static const char *const mode_name[] = {"off", "paraxial", "real"};

static sg_tracer *tracer_bits(const sg_system *sys, const sg_catalog *cat, sg_method m,
                              int bits)
{
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    sg_trace_opts_init(&o);
    o.method = m;
    o.mpfr_bits = bits;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    if (!t)
        fail_msg("tracer (%s, %d bits): %s", sg_method_name(m), bits, d.msg);
    return t;
}

static sg_system *load_data(const char *rel)
{
    char path[4096];
    sg_diag d;
    sg_system *sys = sg_system_new();
    sg_diag_clear(&d);
    if (sg_design_load(sys, tu_path(rel, path, sizeof path), &d) != SG_OK)
        fail_msg("%s: %s", rel, d.msg);
    return sys;
}

/* Largest difference of a's points (or directions) from b's over
 * surfaces 1.., and whether each is within a's bound plus b's. */
static int within_bounds(const sg_ray_surface *a, const sg_ray_surface *b, int n,
                         double *worst_ratio)
{
    int i, ok = 1;
    for (i = 1; i < n; i++) {
        double e = fmax(fabs(a[i].x - b[i].x), fmax(fabs(a[i].y - b[i].y), fabs(a[i].z - b[i].z)));
        double ed = fmax(fabs(a[i].l - b[i].l), fmax(fabs(a[i].m - b[i].m), fabs(a[i].n - b[i].n)));
        double bb = a[i].error_bound + b[i].error_bound;
        double bd = a[i].dir_error_bound + b[i].dir_error_bound;
        if (!(e <= bb) || !(ed <= bd))
            ok = 0;
        if (e > 0.0)
            *worst_ratio = fmax(*worst_ratio, e / bb);
    }
    return ok;
}

/* Rays of the verify grid: the field points at 0, 0.5, 0.7071 and 1 of
 * the field along y and one off the axis, times a pupil of 13 points. */
static const double fields[][2] = {{0, 0}, {0, 0.5}, {0, 0.7071}, {0, 1}, {0.6, -0.8}};
static const double pupils[][2] = {{0, 0},     {0, 1},       {0, -1},     {1, 0},    {-1, 0},
                                   {0.6, 0.8}, {-0.6, -0.8}, {0, 0.5},    {0, -0.5}, {0.5, 0},
                                   {0.35, -0.35}, {-0.7071, 0.7071}, {0.2, 0.9}};
enum { NF = sizeof fields / sizeof fields[0], NP = sizeof pupils / sizeof pupils[0] };

/* Every example in every aiming mode, precise against 512-bit mpfr; the
 * batch gives the single-ray results bit for bit. */
static void examples_every_mode(void **state)
{
    sg_catalog *cat = tu_catalog();
    int e, mode, f, p, bad = 0, disagree = 0, total = 0;
    (void)state;
    for (e = 0; e < 5; e++) {
        sg_system *sys = tu_example(examples[e]);
        for (mode = 0; mode < 3; mode++) {
            static sg_ray_surface single[NF * NP * MAXS], many[NF * NP * MAXS];
            static sg_ray_in rays[NF * NP];
            int st[NF * NP], k;
            sg_trace_opts o;
            sg_diag d;
            sg_tracer *tp, *tm;
            double worst = 0.0;
            int n;
            sys->aim = (sg_aim)mode;
            tp = tracer_bits(sys, cat, SG_METHOD_PRECISE, 512);
            tm = tracer_bits(sys, cat, SG_METHOD_MPFR, 512);
            n = sg_tracer_nsurf(tp);
            assert_true(n <= MAXS);
            for (f = 0; f < NF; f++)
                for (p = 0; p < NP; p++) {
                    sg_ray_surface op[MAXS], om[MAXS];
                    int rp = sg_trace_normalized(tp, fields[f][0], fields[f][1], pupils[p][0],
                                                 pupils[p][1], op);
                    int rm = sg_trace_normalized(tm, fields[f][0], fields[f][1], pupils[p][0],
                                                 pupils[p][1], om);
                    k = f * NP + p;
                    memset(&rays[k], 0, sizeof rays[k]);
                    rays[k].v[0] = fields[f][0];
                    rays[k].v[1] = fields[f][1];
                    rays[k].v[2] = pupils[p][0];
                    rays[k].v[3] = pupils[p][1];
                    memcpy(&single[k * n], op, (size_t)n * sizeof *op);
                    total++;
                    if (rp != rm) {
                        print_message("# %s aim %s (%g,%g,%g,%g): precise %s, mpfr %s\n",
                                      examples[e], mode_name[mode], fields[f][0], fields[f][1],
                                      pupils[p][0], pupils[p][1], sg_err_name(rp),
                                      sg_err_name(rm));
                        disagree++;
                        continue;
                    }
                    /* Aimed rays of these designs all aim. */
                    if (mode != 0)
                        assert_int_not_equal(rm, SG_EAIM);
                    /* Aiming off too: the Cassegrain's chief rays cross the
                     * stop 2.4e-26 from its vertex, 2.8 times the bound before
                     * the launch counted the rounding of Q = O + lam (E - O),
                     * which cancels from the object's 4e6 mm to 36 mm. */
                    if (rp == SG_OK && !within_bounds(op, om, n, &worst)) {
                        print_message("# %s aim %s (%g,%g,%g,%g): outside the bound\n",
                                      examples[e], mode_name[mode], fields[f][0],
                                      fields[f][1], pupils[p][0], pupils[p][1]);
                        bad++;
                    }
                }
            print_message("# %-18s aim %-8s: largest error / (bound + reference bound) %.3g\n",
                          examples[e], mode_name[mode], worst);
            sg_trace_opts_init(&o);
            sg_diag_clear(&d);
            assert_int_equal(sg_trace_batch(sys, cat, &o, SG_RAYS_NORMALIZED, rays, NF * NP, 2,
                                            many, st, &d),
                             SG_OK);
            for (k = 0; k < NF * NP * n; k++)
                if (!tu_same_row(&single[k], &many[k]))
                    fail_msg("%s aim %s: ray %d surface %d differs in the batch", examples[e],
                             mode_name[mode], k / n, k % n);
            sg_tracer_free(tp);
            sg_tracer_free(tm);
        }
        sg_system_free(sys);
    }
    print_message("# %d rays: %d disagree on status, %d outside the bound\n", total, disagree,
                  bad);
    assert_int_equal(disagree, 0);
    assert_int_equal(bad, 0);
    sg_catalog_free(cat);
}

/* The mpfr method at b bits against itself at 512: every ray that traces
 * at 512 bits (all of them must) traces at b, and agrees to about b bits (2^(12 - b) of the
 * ray's largest coordinate, or one ulp of the double, whichever is more:
 * above 53 bits both round to the same double but for ties). */
static void check_bits(const char *name, sg_system *sys, const sg_catalog *cat,
                       const double (*rays)[4], int nray, const int *bits, int nbits)
{
    int mode, r, k, i;
    for (mode = 1; mode < 3; mode++) {
        sg_tracer *ref;
        sys->aim = (sg_aim)mode;
        ref = tracer_bits(sys, cat, SG_METHOD_MPFR, 512);
        for (k = 0; k < nbits; k++) {
            sg_tracer *t = tracer_bits(sys, cat, SG_METHOD_MPFR, bits[k]);
            int n = sg_tracer_nsurf(t);
            double worst = 0.0;
            for (r = 0; r < nray; r++) {
                sg_ray_surface a[MAXS], b[MAXS];
                double big = 0.0;
                int rb = sg_trace_normalized(ref, rays[r][0], rays[r][1], rays[r][2],
                                             rays[r][3], b);
                int ra = sg_trace_normalized(t, rays[r][0], rays[r][1], rays[r][2], rays[r][3],
                                             a);
                if (ra != rb)
                    fail_msg("%s aim %s ray (%g,%g,%g,%g): %s at %d bits, %s at 512",
                             name, mode_name[mode], rays[r][0], rays[r][1], rays[r][2],
                             rays[r][3], sg_err_name(ra), bits[k], sg_err_name(rb));
                /* Every one of these rays aims. */
                if (rb != SG_OK)
                    fail_msg("%s aim %s ray (%g,%g,%g,%g): %s at 512 bits", name,
                             mode_name[mode], rays[r][0], rays[r][1], rays[r][2], rays[r][3],
                             sg_err_name(rb));
                for (i = 1; i < n; i++)
                    big = fmax(big, fmax(fabs(b[i].x), fmax(fabs(b[i].y), fabs(b[i].z))));
                for (i = 1; i < n; i++) {
                    double tol = fmax(ldexp(big, 12 - bits[k]), tu_ulp(big));
                    double e = fmax(fabs(a[i].x - b[i].x),
                                    fmax(fabs(a[i].y - b[i].y), fabs(a[i].z - b[i].z)));
                    if (!(e <= tol))
                        fail_msg("%s aim %s ray (%g,%g,%g,%g) at %d bits, surface %d: "
                                 "differs by %.3g from 512 bits (tolerance %.3g)",
                                 name, mode_name[mode], rays[r][0], rays[r][1], rays[r][2],
                                 rays[r][3], bits[k], i, e, tol);
                    worst = fmax(worst, e / big);
                }
            }
            print_message("# %-18s aim %-8s %4d bits: largest difference from 512 bits "
                          "%.3g of the ray's scale\n", name, mode_name[mode], bits[k], worst);
            sg_tracer_free(t);
        }
        sg_tracer_free(ref);
    }
}

static void mpfr_every_precision(void **state)
{
    static const int bits[] = {53, 64, 113, 256, 1024, 2048, 4096};
    static const double rays[][4] = {{0, 1, 0, 1}, {0, 1, 0, -1}, {0, 0.7, 0.6, -0.8},
                                     {0, 0, 0, 1}};
    sg_catalog *cat = tu_catalog();
    int e;
    (void)state;
    for (e = 0; e < 5; e++) {
        sg_system *sys = tu_example(examples[e]);
        check_bits(examples[e], sys, cat, rays, 4, bits, 7);
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

#define FISHEYE "tests/data/fisheye_nikkor_10_5mm.json"

/* The wide-angle lens's aimed rays, 0 to 80 degrees. */
static void wide_angle(void **state)
{
    static const double pup[][2] = {{0, 0}, {0, 1}, {0, -1}, {1, 0}, {-0.6, 0.8}};
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load_data(FISHEYE);
    sg_method methods[2] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC};
    int stop = sys->stop, mode, f, p, m, n;
    (void)state;
    assert_true(sys->nfield == 4 && sys->field[3].y == 80.0);
    for (mode = 1; mode < 3; mode++) {
        sg_tracer *tm, *tt[2];
        double R, worst_land = 0.0, worst_ratio = 0.0, worst_classic = 0.0;
        sys->aim = (sg_aim)mode;
        tm = tracer_bits(sys, cat, SG_METHOD_MPFR, 512);
        n = sg_tracer_nsurf(tm);
        /* The stop radius aimed at, from no aiming code: the paraxial
         * module's, or where the unaimed on-axis marginal ray meets the
         * stop (the design's entrance pupil is set by its diameter). */
        if (mode == SG_AIM_PARAXIAL) {
            sg_paraxial px;
            sg_diag d;
            sg_diag_clear(&d);
            assert_int_equal(sg_paraxial_compute(sys, cat, -1, &px, &d), SG_OK);
            R = px.stop_radius;
        } else {
            sg_ray_surface o[MAXS];
            sg_tracer *off;
            sys->aim = SG_AIM_OFF;
            off = tracer_bits(sys, cat, SG_METHOD_MPFR, 512);
            assert_int_equal(sg_trace_normalized(off, 0, 0, 0, 1, o), SG_OK);
            R = hypot(o[stop].x, o[stop].y);
            sg_tracer_free(off);
            sys->aim = SG_AIM_REAL;
        }
        for (m = 0; m < 2; m++)
            tt[m] = tracer_bits(sys, cat, methods[m], 512);
        for (f = 0; f <= 8; f++) {
            double hy = f / 8.0;
            for (p = 0; p < 5; p++) {
                sg_ray_surface om[MAXS], o[MAXS];
                double px = pup[p][0], py = pup[p][1], e;
                int rc = sg_trace_normalized(tm, 0, hy, px, py, om);
                if (rc != SG_OK)
                    fail_msg("fisheye aim %s, %g deg, pupil (%g, %g): mpfr %s", mode_name[mode],
                             80.0 * hy, px, py, sg_err_name(rc));
                /* The landing is the target to the double's rounding. */
                e = fmax(fabs(om[stop].x - px * R), fabs(om[stop].y - py * R));
                worst_land = fmax(worst_land, e / R);
                if (!(e <= 4.0 * tu_ulp(R)))
                    fail_msg("fisheye aim %s, %g deg, pupil (%g, %g): lands %.3g from "
                             "(Px, Py) x %.17g", mode_name[mode], 80.0 * hy, px, py, e, R);
                for (m = 0; m < 2; m++) {
                    rc = sg_trace_normalized(tt[m], 0, hy, px, py, o);
                    if (rc != SG_OK)
                        fail_msg("fisheye aim %s, %g deg, pupil (%g, %g): %s %s",
                                 mode_name[mode], 80.0 * hy, px, py,
                                 sg_method_name(methods[m]), sg_err_name(rc));
                    if (methods[m] == SG_METHOD_PRECISE) {
                        if (!within_bounds(o, om, n, &worst_ratio))
                            fail_msg("fisheye aim %s, %g deg, pupil (%g, %g): precise outside "
                                     "its bound", mode_name[mode], 80.0 * hy, px, py);
                    } else {
                        /* Classic's noise, from its aim tolerance and its
                         * double arithmetic: 1e-9 of the stop radius. */
                        e = fmax(fabs(o[stop].x - px * R), fabs(o[stop].y - py * R));
                        worst_classic = fmax(worst_classic, e / R);
                        assert_true(e <= 1e-9 * R);
                    }
                }
            }
        }
        print_message("# fisheye aim %-8s stop radius %.17g: 45 rays to 80 deg; mpfr landing "
                      "%.3g of R, classic %.3g; precise error / bound %.3g\n", mode_name[mode], R,
                      worst_land, worst_classic, worst_ratio);
        for (m = 0; m < 2; m++)
            sg_tracer_free(tt[m]);
        sg_tracer_free(tm);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The wide-angle lens at every precision, chief and marginal rays at full
 * field. */
static void wide_angle_bits(void **state)
{
    static const int bits[] = {53, 64, 113, 256, 1024, 2048, 4096};
    static const double rays[][4] = {{0, 1, 0, 0}, {0, 1, 0, 1}, {0, 1, 0, -1}};
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load_data(FISHEYE);
    (void)state;
    check_bits("fisheye", sys, cat, rays, 3, bits, 7);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The batch gives the wide-angle lens's rays, most of which need the
 * line search or the continuation, bit for bit as the single-ray calls. */
static void wide_angle_batch(void **state)
{
    enum { NR = 9 * 9 };
    sg_catalog *cat = tu_catalog();
    sg_system *sys = load_data(FISHEYE);
    static sg_ray_in rays[NR];
    static sg_ray_surface one[NR * MAXS], many[NR * MAXS];
    int st[NR], mode, m, r, i, n = sys->nsurf;
    sg_method methods[2] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC};
    (void)state;
    assert_true(n <= MAXS);
    for (r = 0; r < NR; r++) {
        double a = 0.7 * (r % 9);
        memset(&rays[r], 0, sizeof rays[r]);
        rays[r].v[0] = 0.1 * ((r / 9) % 3) - 0.1;
        rays[r].v[1] = (r / 9) / 8.0;
        rays[r].v[2] = (r % 9) ? 0.95 * cos(a) : 0.0;
        rays[r].v[3] = (r % 9) ? 0.95 * sin(a) : 0.0;
    }
    for (mode = 1; mode < 3; mode++)
        for (m = 0; m < 2; m++) {
            sg_trace_opts o;
            sg_diag d;
            sg_tracer *t;
            int fails = 0;
            sys->aim = (sg_aim)mode;
            t = tracer_bits(sys, cat, methods[m], 256);
            for (r = 0; r < NR; r++) {
                if (sg_trace_normalized(t, rays[r].v[0], rays[r].v[1], rays[r].v[2],
                                        rays[r].v[3], &one[r * n]) != SG_OK)
                    fails++;
            }
            sg_tracer_free(t);
            sg_trace_opts_init(&o);
            o.method = methods[m];
            sg_diag_clear(&d);
            assert_int_equal(sg_trace_batch(sys, cat, &o, SG_RAYS_NORMALIZED, rays, NR, 2, many,
                                            st, &d),
                             SG_OK);
            for (i = 0; i < NR * n; i++)
                if (!tu_same_row(&one[i], &many[i]))
                    fail_msg("fisheye aim %s %s: ray %d surface %d differs in the batch",
                             mode_name[mode], sg_method_name(methods[m]), i / n, i % n);
            print_message("# fisheye aim %-8s %-7s: %d rays (%d not OK) identical in the "
                          "batch\n", mode_name[mode], sg_method_name(methods[m]), NR, fails);
            /* All of them aim (31 did not before the line search and the
             * continuation). */
            assert_int_equal(fails, 0);
        }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A ray accepted within a loose aiming tolerance, out of Newton steps,
 * starts short of the exactly aimed ray: its bound must carry that.  The
 * reference aims fully (its own step limit is aim_max_iter plus log2 of
 * its bits). */
static void loose_tolerance(void **state)
{
    static const double rays[][4] = {{0, 1, 0, 1}, {0, 1, 0, -1}, {0, 0.7, 0.6, -0.8},
                                     {0, 1, 1, 0}};
    sg_catalog *cat = tu_catalog();
    int e, r, mode, checked = 0;
    (void)state;
    for (e = 1; e < 3; e++) {
        sg_system *sys = tu_example(examples[e]);
        for (mode = 1; mode < 3; mode++) {
            sg_trace_opts o;
            sg_diag d;
            sg_tracer *tp, *tm;
            double worst = 0.0;
            int n, nok = 0;
            sys->aim = (sg_aim)mode;
            sg_trace_opts_init(&o);
            o.aim_max_iter = 1;
            o.aim_rtol = 0.1;
            sg_diag_clear(&d);
            tp = sg_tracer_new(sys, cat, &o, &d);
            assert_non_null(tp);
            o.method = SG_METHOD_MPFR;
            o.mpfr_bits = 512;
            tm = sg_tracer_new(sys, cat, &o, &d);
            assert_non_null(tm);
            n = sg_tracer_nsurf(tp);
            for (r = 0; r < 4; r++) {
                sg_ray_surface op[MAXS], om[MAXS];
                int rp = sg_trace_normalized(tp, rays[r][0], rays[r][1], rays[r][2], rays[r][3],
                                             op);
                assert_int_equal(sg_trace_normalized(tm, rays[r][0], rays[r][1], rays[r][2],
                                                     rays[r][3], om),
                                 SG_OK);
                if (rp != SG_OK)
                    continue;
                checked++;
                nok++;
                if (!within_bounds(op, om, n, &worst))
                    fail_msg("%s aim %s ray %d, one aiming step: precise outside its bound",
                             examples[e], mode_name[mode], r);
            }
            print_message("# %-18s aim %-8s one step, tolerance 0.1: %d of 4 rays aim; "
                          "largest error / bound %.3g\n", examples[e], mode_name[mode], nok,
                          worst);
            sg_tracer_free(tp);
            sg_tracer_free(tm);
        }
        sg_system_free(sys);
    }
    assert_true(checked >= 8);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(examples_every_mode),
        cmocka_unit_test(mpfr_every_precision),
        cmocka_unit_test(wide_angle),
        cmocka_unit_test(wide_angle_bits),
        cmocka_unit_test(wide_angle_batch),
        cmocka_unit_test(loose_tolerance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
