/*
 * test_classic_vec.c - the classic method's vector kernel
 * (src/trace/trace_classic_vec.c) gives, lane by lane, the bits of the scalar
 * one-ray trace it replaced (tests/classic_ref.c, the code of before), and
 * a ray alone the bits it gets inside a batch.
 *
 * The reference is an independent program in the sense that matters here:
 * the textbook trace written ray by ray in scalar C, which the kernel must
 * reproduce rounding for rounding.  Rays: seeded random sets through every
 * bundled example under every aiming mode, random systems with shapes of
 * their own (SHAPE_GEN), with tilts and decenters, and with even
 * aspheres, and hard rays (grazing, near-tangent, huge and tiny values,
 * rays that miss, reflect totally, are vignetted or run out of Newton
 * iterations in the middle of a block of live lanes).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "classic_ref.h"
#include "testutil.h"

static uint64_t rng_state;

static double urand(void)
{
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng_state >> 11) * 0x1p-53;
}

static double srand1(double a)
{
    return a * (2.0 * urand() - 1.0);
}

static const char *const examples[] = {"cassegrain.json", "cooke_triplet.json",
                                       "double_gauss.json", "singlet.json", "tma.json"};
#define NEX ((int)(sizeof examples / sizeof examples[0]))

/* What the comparisons saw, so a test that compares nothing fails. */
typedef struct tally {
    long lanes, ok, miss, tir, vig, noconv, other, blocks, mixed;
} tally;

static void count(tally *c, int rc)
{
    c->lanes++;
    if (rc == SG_OK)
        c->ok++;
    else if (rc == SG_EMISS)
        c->miss++;
    else if (rc == SG_ETIR)
        c->tir++;
    else if (sg_err_is_stopped(rc))
        c->vig++;
    else if (rc == SG_ENOCONV)
        c->noconv++;
    else
        c->other++;
}

/* Rows filled with the same junk before either trace writes them, so a
 * row one trace leaves alone and the other writes shows. */
static void junk(sg_ray_surface *o, int n)
{
    memset(o, 0x5a, (size_t)n * sizeof *o);
}

/* Traces the nl rays (S, D) as one block to upto and each alone by the
 * reference, and compares every row of every lane bit for bit; then each
 * alone through sg_classic_run_to, the kernel with one live lane. */
static void check_block(const sg_tracer *t, int n, const double (*S)[3], const double (*D)[3],
                        int nl, int upto, tally *c, const char *what)
{
    sg_ray_surface *got[SG_VL], *ref = calloc((size_t)n, sizeof *ref),
                                *one = calloc((size_t)n, sizeof *one);
    int rc[SG_VL], k, i, seen_ok = 0, seen_bad = 0;
    assert_non_null(ref);
    assert_non_null(one);
    for (k = 0; k < SG_VL; k++) {
        got[k] = calloc((size_t)n, sizeof *got[k]);
        assert_non_null(got[k]);
        junk(got[k], n);
        rc[k] = -12345;
    }
    sg_classic_block(t, S, D, got, nl, upto, rc);
    for (k = 0; k < nl; k++) {
        int rr, r1;
        junk(ref, n);
        junk(one, n);
        rr = classic_ref_run_to(t, S[k], D[k], ref, upto);
        r1 = sg_classic_run_to(t, S[k], D[k], one, upto);
        if (rc[k] != rr || r1 != rr)
            fail_msg("%s lane %d of %d: status %d in the block, %d alone, %d by the reference "
                     "(S %.17g %.17g %.17g D %.17g %.17g %.17g)",
                     what, k, nl, rc[k], r1, rr, S[k][0], S[k][1], S[k][2], D[k][0], D[k][1],
                     D[k][2]);
        for (i = 1; i < n; i++) {
            if (memcmp(&got[k][i], &ref[i], sizeof ref[i]) != 0 ||
                memcmp(&one[i], &ref[i], sizeof ref[i]) != 0)
                fail_msg("%s lane %d of %d, surface %d: block x %.17g y %.17g z %.17g l %.17g "
                         "eP %.17g eD %.17g opl %.17g res %.17g st %d; reference x %.17g "
                         "y %.17g z %.17g l %.17g eP %.17g eD %.17g opl %.17g res %.17g st %d",
                         what, k, nl, i, got[k][i].x, got[k][i].y, got[k][i].z, got[k][i].l,
                         got[k][i].error_bound, got[k][i].dir_error_bound, got[k][i].opl,
                         got[k][i].residual, got[k][i].status, ref[i].x, ref[i].y, ref[i].z,
                         ref[i].l, ref[i].error_bound, ref[i].dir_error_bound, ref[i].opl,
                         ref[i].residual, ref[i].status);
        }
        count(c, rr);
        if (rr == SG_OK)
            seen_ok = 1;
        else
            seen_bad = 1;
    }
    /* Lanes past nl are neither written nor given a status. */
    for (k = nl; k < SG_VL; k++) {
        unsigned char j[sizeof(sg_ray_surface)];
        memset(j, 0x5a, sizeof j);
        assert_int_equal(rc[k], -12345);
        for (i = 0; i < n; i++)
            assert_memory_equal(&got[k][i], j, sizeof j);
    }
    c->blocks++;
    if (seen_ok && seen_bad)
        c->mixed++;
    for (k = 0; k < SG_VL; k++)
        free(got[k]);
    free(ref);
    free(one);
}

/* nray rays (S, D) in blocks of random widths, to random depths (mostly
 * the image). */
static void check_rays(const sg_tracer *t, int n, double (*S)[3], double (*D)[3], int nray,
                       tally *c, const char *what)
{
    int r = 0;
    while (r < nray) {
        int nl = 1 + (int)(urand() * SG_VL), upto;
        double u = urand();
        if (nl > nray - r)
            nl = nray - r;
        upto = u < 0.7 ? n - 1 : 1 + (int)(urand() * (n - 1));
        check_block(t, n, (const double(*)[3])(S + r), (const double(*)[3])(D + r), nl, upto, c,
                    what);
        r += nl;
    }
}

/* Random start points before surface 1 and directions mostly forward,
 * with hard ones mixed in: grazing, along the axis, backwards, across,
 * unnormalized by large and tiny factors, huge and tiny coordinates. */
static void hard_rays(double L, double (*S)[3], double (*D)[3], int nray)
{
    int r;
    for (r = 0; r < nray; r++) {
        double u = urand(), f;
        S[r][0] = srand1(0.4 * L);
        S[r][1] = srand1(0.4 * L);
        S[r][2] = -L * urand();
        D[r][0] = srand1(0.3);
        D[r][1] = srand1(0.3);
        D[r][2] = 1.0;
        if (u < 0.1) { /* grazing: nearly across the axis */
            D[r][2] = 1e-3 * urand();
            D[r][0] = 1.0;
        } else if (u < 0.15) { /* exactly across */
            D[r][2] = 0.0;
            D[r][1] = 1.0;
        } else if (u < 0.2) { /* backwards */
            D[r][2] = -1.0;
        } else if (u < 0.25) { /* along the axis, on it */
            S[r][0] = S[r][1] = 0.0;
            D[r][0] = D[r][1] = 0.0;
        } else if (u < 0.3) { /* near the rim of a sphere's sheet: tangent */
            S[r][1] = L * (0.99 + 0.02 * urand());
            D[r][1] = 0.0;
        } else if (u < 0.35) { /* huge coordinates */
            S[r][0] = srand1(1e150);
            S[r][1] = srand1(1e150);
        } else if (u < 0.4) { /* tiny coordinates */
            S[r][0] = srand1(1e-300);
            S[r][1] = srand1(1e-300);
            S[r][2] = -1e-300 * urand();
        } else if (u < 0.45) { /* far off axis: vignetted or missing */
            S[r][0] = srand1(5.0 * L);
            S[r][1] = srand1(5.0 * L);
        } else if (u < 0.5) { /* steep: total reflection on the way */
            D[r][0] = srand1(3.0);
            D[r][1] = srand1(3.0);
        }
        /* Unnormalized directions, by large and tiny factors. */
        f = urand() < 0.2 ? ldexp(1.0, (int)srand1(500.0)) : 1.0 + urand();
        D[r][0] *= f;
        D[r][1] *= f;
        D[r][2] *= f;
    }
}

/* The start points and directions the launch gives normalized rays (with
 * the system's aiming), pupil points past the edge included. */
static int launched_rays(sg_tracer *t, double (*S)[3], double (*D)[3], int nray, int n)
{
    sg_ray_surface *o = calloc((size_t)n, sizeof *o);
    int r, got = 0;
    assert_non_null(o);
    for (r = 0; r < nray; r++) {
        double off;
        int inf;
        double hx = urand() < 0.3 ? 0.0 : srand1(1.0), hy = srand1(1.0);
        double px = srand1(1.2), py = srand1(1.2);
        if (sg_launch_classic_prep(t, hx, hy, px, py, o, S[got], D[got], &off, &inf) == SG_OK)
            got++;
    }
    free(o);
    return got;
}

static sg_tracer *classic_tracer(const sg_system *sys, const sg_catalog *cat, int max_iter)
{
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    sg_trace_opts_init(&o);
    o.method = SG_METHOD_CLASSIC;
    if (max_iter > 0)
        o.max_iter = max_iter;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    if (!t)
        fail_msg("tracer: %s", d.msg);
    return t;
}

enum { NRAY = 400 };

static void check_tally(const tally *c, const char *what)
{
    print_message("# %s: %ld lanes in %ld blocks (%ld mixed): ok %ld, miss %ld, TIR %ld, "
                  "vignetted %ld, no convergence %ld, other %ld\n",
                  what, c->lanes, c->blocks, c->mixed, c->ok, c->miss, c->tir, c->vig,
                  c->noconv, c->other);
    assert_true(c->ok > 0);
    assert_true(c->mixed > 0);
}

/* Every example under every aiming mode: launched rays and hard ones. */
static void examples_match(void **state)
{
    sg_catalog *cat = tu_catalog();
    static const sg_aim aims[] = {SG_AIM_OFF, SG_AIM_PARAXIAL, SG_AIM_REAL};
    double(*S)[3] = calloc(NRAY, sizeof *S), (*D)[3] = calloc(NRAY, sizeof *D);
    tally c = {0};
    int e, a;
    (void)state;
    rng_state = 18;
    for (e = 0; e < NEX; e++) {
        sg_system *sys = tu_example(examples[e]);
        for (a = 0; a < 3; a++) {
            sg_tracer *t;
            char what[96];
            int got;
            sys->aim = aims[a];
            t = classic_tracer(sys, cat, 0);
            got = launched_rays(t, S, D, NRAY / 2, sys->nsurf);
            snprintf(what, sizeof what, "%s aim %d launched", examples[e], (int)aims[a]);
            check_rays(t, sys->nsurf, S, D, got, &c, what);
            sg_tracer_free(t);
        }
        {
            sg_tracer *t = classic_tracer(sys, cat, 0);
            double L = fabs(sys->surf[1].radius) < 1e6 ? fabs(sys->surf[1].radius) : 50.0;
            char what[96];
            hard_rays(L, S, D, NRAY);
            snprintf(what, sizeof what, "%s hard rays", examples[e]);
            check_rays(t, sys->nsurf, S, D, NRAY, &c, what);
            sg_tracer_free(t);
        }
        sg_system_free(sys);
    }
    check_tally(&c, "examples");
    assert_true(c.miss > 0 && c.vig > 0);
    free(S);
    free(D);
    sg_catalog_free(cat);
}

/* A lens of two surfaces: surface 1 of the given type with random terms,
 * surface 2 a sphere; with tilts and decenters after surface 1 and before
 * surface 2 when tilt is set (rays start in surface 1's frame). */
static sg_system *shape_system(int type, int tilt)
{
    sg_system *sys = sg_system_new();
    sg_surface *f;
    int k;
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 4), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->stop = 1;
    sys->aper_value = 8.0;
    f = &sys->surf[1];
    f->type = type;
    f->radius = (urand() < 0.5 ? -1.0 : 1.0) * (20.0 + 80.0 * urand());
    if (urand() < 0.2)
        f->radius = INFINITY;
    /* Nearly flat spheres (|R| from 1e15 to 1e19), where the root takes
     * its cancellation-free form. */
    if (type == SG_SURF_STANDARD && urand() < 0.5)
        f->radius = (urand() < 0.5 ? -1.0 : 1.0) * pow(10.0, 15.0 + 4.0 * urand());
    f->conic = urand() < 0.3 ? 0.0 : srand1(2.0);
    f->radius_x = INFINITY;
    f->norm_radius = 1.0;
    switch (type) {
    case SG_SURF_EVENASPH:
        for (k = 0; k < 4; k++)
            f->asph[k] = srand1(0.05) / pow(10.0, 2 * k + 2);
        break;
    case SG_SURF_ODDASPH:
        for (k = 0; k < SG_NODD; k++)
            f->odd[k] = srand1(0.05) / pow(10.0, k + 1);
        break;
    case SG_SURF_TOROIDAL:
        f->radius_x = (urand() < 0.5 ? -1.0 : 1.0) * (15.0 + 100.0 * urand());
        for (k = 0; k < 3; k++)
            f->asph[k] = srand1(0.05) / pow(10.0, 2 * k + 2);
        break;
    case SG_SURF_BICONIC:
        f->radius_x = (urand() < 0.5 ? -1.0 : 1.0) * (20.0 + 80.0 * urand());
        f->conic_x = srand1(2.0);
        break;
    case SG_SURF_ZERNIKE_FRINGE:
    case SG_SURF_ZERNIKE_STANDARD:
        f->norm_radius = 8.0 + 4.0 * urand();
        for (k = 0; k < 37; k++)
            if (urand() < 0.5)
                f->terms[k] = srand1(0.02) / (1.0 + k);
        break;
    case SG_SURF_XYPOLY:
        f->norm_radius = 8.0 + 4.0 * urand();
        for (k = 0; k < 65; k++)
            if (urand() < 0.5)
                f->terms[k] = srand1(0.02) / (1.0 + k);
        break;
    }
    f->thickness = 6.0;
    f->mat.kind = urand() < 0.3 ? SG_MAT_MIRROR : SG_MAT_INDEX;
    if (f->mat.kind == SG_MAT_MIRROR)
        f->thickness = -6.0;
    f->mat.index = 1.5 + 0.3 * urand();
    /* A fixed clip on surface 2 vignettes some rays. */
    sys->surf[2].radius = -(30.0 + 50.0 * urand()) * (f->mat.kind == SG_MAT_MIRROR ? -1.0 : 1.0);
    sys->surf[2].thickness = f->thickness * 5.0;
    sys->surf[2].semi_diameter = 6.0;
    sys->surf[2].sd_fixed = 1;
    if (tilt) {
        sg_frame_change *b = &sys->surf[1].after, *a = &sys->surf[2].before;
        b->dx = srand1(1.0);
        b->dy = srand1(1.0);
        b->tx = srand1(5.0);
        b->ty = srand1(5.0);
        b->tz = srand1(20.0);
        b->order = urand() < 0.5;
        a->dx = srand1(0.5);
        a->tx = srand1(3.0);
        a->order = urand() < 0.5;
    }
    return sys;
}

/* Shapes of their own, aspheres, tilts and decenters, and Newton cut
 * short so that lanes run out of iterations beside lanes that converge. */
static void shapes_match(void **state)
{
    static const int types[] = {SG_SURF_STANDARD, SG_SURF_EVENASPH, SG_SURF_ODDASPH,
                                SG_SURF_TOROIDAL, SG_SURF_BICONIC, SG_SURF_ZERNIKE_FRINGE,
                                SG_SURF_ZERNIKE_STANDARD, SG_SURF_XYPOLY};
    sg_catalog *cat = tu_catalog();
    double(*S)[3] = calloc(NRAY, sizeof *S), (*D)[3] = calloc(NRAY, sizeof *D);
    tally c = {0};
    int q, m;
    (void)state;
    rng_state = 1818;
    for (q = 0; q < 48; q++) {
        int type = types[q % 8], tilt = (q / 8) % 2;
        sg_system *sys = shape_system(type, tilt);
        sg_diag d;
        sg_diag_clear(&d);
        if (sg_system_validate(sys, cat, &d) != SG_OK)
            fail_msg("system %d: %s", q, d.msg);
        for (m = 0; m < 2; m++) {
            /* max_iter 3: Newton stops short on some lanes only. */
            sg_tracer *t = classic_tracer(sys, cat, m ? 3 : 0);
            char what[96];
            hard_rays(20.0, S, D, NRAY / 2);
            snprintf(what, sizeof what, "system %d (type %d%s, max_iter %s)", q, type,
                     tilt ? ", tilted" : "", m ? "3" : "default");
            check_rays(t, sys->nsurf, S, D, NRAY / 2, &c, what);
            sg_tracer_free(t);
        }
        sg_system_free(sys);
    }
    check_tally(&c, "shapes");
    assert_true(c.miss > 0 && c.vig > 0 && c.tir > 0 && c.noconv > 0);
    free(S);
    free(D);
    sg_catalog_free(cat);
}

/* A ray alone (sg_trace_normalized, sg_trace_start) and the same ray in a
 * batch of one and two threads, which traces blocks of SG_VL lanes. */
static void alone_as_in_batch(void **state)
{
    static const sg_aim aims[] = {SG_AIM_OFF, SG_AIM_PARAXIAL, SG_AIM_REAL};
    enum { NB = 203 };
    sg_catalog *cat = tu_catalog();
    sg_ray_in *rays = calloc(NB, sizeof *rays);
    double(*S)[3] = calloc(NB, sizeof *S), (*D)[3] = calloc(NB, sizeof *D);
    long compared = 0, failed = 0;
    int e, a, kind, th, r, i;
    (void)state;
    rng_state = 180;
    for (e = 0; e < NEX; e++) {
        sg_system *sys = tu_example(examples[e]);
        int n = sys->nsurf;
        sg_ray_surface *one = calloc((size_t)n, sizeof *one),
                       *all = calloc((size_t)NB * (size_t)n, sizeof *all);
        int *st = calloc(NB, sizeof *st);
        for (a = 0; a < 3; a++) {
            sg_tracer *t;
            sg_trace_opts o;
            sys->aim = aims[a];
            sg_trace_opts_init(&o);
            o.method = SG_METHOD_CLASSIC;
            t = classic_tracer(sys, cat, 0);
            for (kind = 0; kind < 2; kind++) {
                if (kind == 0) {
                    /* Runs of one field, pupil points past the edge. */
                    for (r = 0; r < NB; r++) {
                        rays[r].v[0] = r % 17 == 0 ? srand1(1.0) : (r / 11) * 0.1 - 0.5;
                        rays[r].v[1] = (r / 11) * 0.07 - 0.4;
                        rays[r].v[2] = srand1(1.15);
                        rays[r].v[3] = srand1(1.15);
                    }
                    rays[5].v[2] = NAN; /* a bad ray in a block */
                } else {
                    double L = fabs(sys->surf[1].radius) < 1e6 ? fabs(sys->surf[1].radius) : 50.0;
                    hard_rays(L, S, D, NB);
                    for (r = 0; r < NB; r++)
                        for (i = 0; i < 3; i++) {
                            rays[r].v[i] = S[r][i];
                            rays[r].v[3 + i] = D[r][i];
                        }
                    rays[7].v[4] = INFINITY;
                }
                for (th = 1; th <= 2; th++) {
                    sg_diag d;
                    sg_diag_clear(&d);
                    junk(all, NB * n);
                    assert_int_equal(sg_trace_batch(sys, cat, &o, kind ? SG_RAYS_START_DIR
                                                                       : SG_RAYS_NORMALIZED,
                                                    rays, NB, th, all, st, &d),
                                     SG_OK);
                    for (r = 0; r < NB; r++) {
                        const double *v = rays[r].v;
                        int rc;
                        junk(one, n);
                        rc = kind ? sg_trace_start(t, v, v + 3, one)
                                  : sg_trace_normalized(t, v[0], v[1], v[2], v[3], one);
                        if (rc != st[r])
                            fail_msg("%s aim %d kind %d threads %d ray %d: status %d alone, %d "
                                     "in the batch",
                                     examples[e], (int)aims[a], kind, th, r, rc, st[r]);
                        for (i = 0; i < n; i++)
                            if (memcmp(&one[i], &all[(size_t)r * n + i], sizeof one[i]) != 0)
                                fail_msg("%s aim %d kind %d threads %d ray %d surface %d: "
                                         "x %.17g alone, %.17g in the batch",
                                         examples[e], (int)aims[a], kind, th, r, i, one[i].x,
                                         all[(size_t)r * n + i].x);
                        compared++;
                        failed += rc != SG_OK;
                    }
                }
            }
            sg_tracer_free(t);
        }
        free(one);
        free(all);
        free(st);
        sg_system_free(sys);
    }
    print_message("# alone vs batch: %ld rays compared, %ld failed alike\n", compared, failed);
    assert_true(compared > 0 && failed > 0 && failed < compared);
    free(rays);
    free(S);
    free(D);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(examples_match),
        cmocka_unit_test(shapes_match),
        cmocka_unit_test(alone_as_in_batch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
