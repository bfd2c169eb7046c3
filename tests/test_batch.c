/*
 * test_batch.c - the batch driver equals single-ray calls bit for bit, for
 * every method and thread count.  The reference is the single-ray API.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "trace_int.h"

/* Every field bit for bit (struct padding is not a result). */
static void same_rows(const sg_ray_surface *a, const sg_ray_surface *b, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        const double fa[10] = {a[i].x, a[i].y, a[i].z, a[i].l, a[i].m, a[i].n, a[i].residual,
                               a[i].error_bound, a[i].dir_error_bound, a[i].path};
        const double fb[10] = {b[i].x, b[i].y, b[i].z, b[i].l, b[i].m, b[i].n, b[i].residual,
                               b[i].error_bound, b[i].dir_error_bound, b[i].path};
        assert_memory_equal(fa, fb, sizeof fa);
        assert_int_equal(a[i].status, b[i].status);
    }
}

static void compare(const char *file, sg_method m, int nx, void (*tweak)(sg_system *))
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    size_t nray = 0, r, ns = (size_t)sys->nsurf;
    sg_ray_in *rays = calloc((size_t)(3 * nx * nx), sizeof *rays);
    sg_ray_surface *one = calloc((size_t)(3 * nx * nx) * ns, sizeof *one);
    sg_ray_surface *many = calloc((size_t)(3 * nx * nx) * ns, sizeof *many);
    int *st1 = calloc((size_t)(3 * nx * nx), sizeof *st1);
    int *st2 = calloc((size_t)(3 * nx * nx), sizeof *st2);
    int h, i, j, threads[3] = {1, 2, 3}, k, failed = 0;
    assert_non_null(rays);
    assert_non_null(one);
    assert_non_null(many);
    if (tweak)
        tweak(sys);
    for (h = 0; h < 3; h++)
        for (i = 0; i < nx; i++)
            for (j = 0; j < nx; j++) {
                /* Includes pupil corners beyond the unit circle, which may
                 * fail, so failures are compared too. */
                rays[nray].v[0] = 0.0;
                rays[nray].v[1] = 0.5 * h;
                rays[nray].v[2] = -1.2 + 2.4 * i / (nx - 1);
                rays[nray].v[3] = -1.2 + 2.4 * j / (nx - 1);
                nray++;
            }
    sg_trace_opts_init(&o);
    o.method = m;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    assert_non_null(t);
    for (r = 0; r < nray; r++) {
        st1[r] = sg_trace_normalized(t, rays[r].v[0], rays[r].v[1], rays[r].v[2], rays[r].v[3],
                                     one + r * ns);
        failed += st1[r] != SG_OK;
    }
    sg_tracer_free(t);
    for (k = 0; k < 3; k++) {
        memset(many, 0xA5, nray * ns * sizeof *many);
        assert_int_equal(sg_trace_batch(sys, cat, &o, SG_RAYS_NORMALIZED, rays, nray,
                                        threads[k], many, st2, &d),
                         SG_OK);
        assert_memory_equal(st1, st2, nray * sizeof *st1);
        same_rows(one, many, nray * ns);
    }
    print_message("# %s%s %s: %zu rays (%d failing) identical for 1, 2 and 3 threads\n", file,
                  tweak ? " (real aiming, a fixed aperture before the stop)" : "",
                  sg_method_name(m), nray, failed);
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
    compare("cassegrain.json", SG_METHOD_PRECISE, 15, NULL);
    compare("tma.json", SG_METHOD_PRECISE, 15, NULL);
    compare("double_gauss.json", SG_METHOD_PRECISE, 15, NULL);
}

/* Real aiming with the stop deep in the lens: the batch starts a ray's
 * final trace from its last aiming trace, after checking the apertures
 * that trace ignored; one of them is made to vignette. */
static void deep_stop(sg_system *sys)
{
    sys->aim = SG_AIM_REAL;
    sys->surf[2].semi_diameter = 48.0;
    sys->surf[2].sd_fixed = 1;
}

static void precise_deep_stop(void **state)
{
    (void)state;
    compare("double_gauss.json", SG_METHOD_PRECISE, 15, deep_stop);
}

static void classic(void **state)
{
    (void)state;
    compare("cassegrain.json", SG_METHOD_CLASSIC, 15, NULL);
    compare("tma.json", SG_METHOD_CLASSIC, 15, NULL);
}

/* 3 x 7 x 7 = 147 rays: above 128, so the batch's runs of 64 reach a third
 * thread (48 rays, as before, never left the first). */
static void mpfr(void **state)
{
    (void)state;
    compare("cassegrain.json", SG_METHOD_MPFR, 7, NULL);
    compare("tma.json", SG_METHOD_MPFR, 7, NULL);
}

static void start_dir(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    enum { N = 200 };
    sg_ray_in rays[N];
    size_t ns = (size_t)sys->nsurf;
    sg_ray_surface *one = calloc(N * ns, sizeof *one), *many = calloc(N * ns, sizeof *many);
    int st1[N], st2[N], r;
    (void)state;
    for (r = 0; r < N; r++) {
        rays[r].v[0] = 0.1 * (r % 20) - 1.0;
        rays[r].v[1] = 0.05 * (r / 20) - 0.25;
        rays[r].v[2] = -5.0;
        rays[r].v[3] = 0.01 * (r % 7);
        rays[r].v[4] = -0.02 * (r % 5);
        rays[r].v[5] = 1.0;
    }
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    assert_non_null(t);
    for (r = 0; r < N; r++)
        st1[r] = sg_trace_start(t, rays[r].v, rays[r].v + 3, one + (size_t)r * ns);
    assert_int_equal(sg_trace_batch(sys, cat, &o, SG_RAYS_START_DIR, rays, N, 2, many, st2, &d),
                     SG_OK);
    assert_memory_equal(st1, st2, sizeof st1);
    same_rows(one, many, N * ns);
    print_message("# cooke_triplet start/dir rays: %d identical on 2 threads\n", N);
    sg_tracer_free(t);
    free(one);
    free(many);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The batch traces precise rays SG_VL at a time; a lane that fails drops
 * out of its block while the others go on.  Start/dir rays over steep
 * angles and wide heights put misses, total internal reflection and good
 * rays in the same blocks; every one must equal its single-ray trace. */
static void mixed_blocks(const char *file, double z0, double hmax, int want_tir)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    enum { N = 800 };
    sg_ray_in *rays = calloc(N, sizeof *rays);
    size_t ns = (size_t)sys->nsurf;
    sg_ray_surface *one = calloc(N * ns, sizeof *one), *many = calloc(N * ns, sizeof *many);
    int st1[N], st2[N], r, k, nok = 0, nmiss = 0, ntir = 0, nother = 0, mixed = 0;
    unsigned long long seed = 12345;
    assert_non_null(rays);
    assert_non_null(one);
    assert_non_null(many);
    for (r = 0; r < N; r++) {
        double u[3], a, b;
        for (k = 0; k < 3; k++) {
            seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
            u[k] = (double)(seed >> 11) / 9007199254740992.0;
        }
        a = (u[0] - 0.5) * 2.9; /* up to 83 degrees off the axis */
        b = (u[1] - 0.5) * 2.0 * hmax;
        rays[r].v[0] = 0.1 * (u[2] - 0.5);
        rays[r].v[1] = b;
        rays[r].v[2] = z0;
        rays[r].v[3] = 0.05 * u[2];
        rays[r].v[4] = sin(a);
        rays[r].v[5] = cos(a);
    }
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    assert_non_null(t);
    for (r = 0; r < N; r++) {
        st1[r] = sg_trace_start(t, rays[r].v, rays[r].v + 3, one + (size_t)r * ns);
        nok += st1[r] == SG_OK;
        nmiss += st1[r] == SG_EMISS;
        ntir += st1[r] == SG_ETIR;
        nother += st1[r] != SG_OK && st1[r] != SG_EMISS && st1[r] != SG_ETIR;
    }
    /* Blocks as the batch forms them: SG_VL consecutive rays. */
    for (r = 0; r + SG_VL <= N; r += SG_VL) {
        int f = 0, l;
        for (l = 0; l < SG_VL; l++)
            f += st1[r + l] != SG_OK;
        mixed += f > 0 && f < SG_VL;
    }
    for (k = 1; k <= 2; k++) {
        memset(many, 0xA5, N * ns * sizeof *many);
        assert_int_equal(
            sg_trace_batch(sys, cat, &o, SG_RAYS_START_DIR, rays, N, k, many, st2, &d), SG_OK);
        assert_memory_equal(st1, st2, sizeof st1);
        same_rows(one, many, N * ns);
    }
    print_message("# %s: %d start/dir rays (%d traced, %d miss, %d TIR, %d other failures; "
                  "%d blocks of %d mix traced and failed rays) identical on 1 and 2 threads\n",
                  file, N, nok, nmiss, ntir, nother, mixed, SG_VL);
    assert_true(nok > 0 && nmiss > 0 && mixed > 10);
    if (want_tir)
        assert_true(ntir > 0);
    sg_tracer_free(t);
    free(rays);
    free(one);
    free(many);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void handoff(void **state)
{
    (void)state;
    mixed_blocks("singlet.json", -5.0, 60.0, 1);
    mixed_blocks("tma.json", -10.0, 400.0, 0);
    mixed_blocks("double_gauss.json", -5.0, 60.0, 0);
}

/* The aperture test against its definition, hypot(x, y) > sd (1 + rtol),
 * on points spread within 1e-9 to 1e-17 of the edge in every direction
 * and on overflow, underflow, infinities and NaN: the shortcut by
 * x^2 + y^2 must never decide differently. */
static void clip_edge(void **state)
{
    static const double rel[] = {1e-9, 1e-11, 1e-12, 2e-13, 1e-14, 1e-15, 1e-16, 1e-17};
    static const double odd[][2] = {{1e200, 0}, {1e-200, 1e-200}, {INFINITY, 0}, {0, -INFINITY},
                                    {NAN, 0}, {NAN, INFINITY}, {0, 0}, {-0.0, 1500.0}};
    static const double sds[] = {1500.0, 1e-3, 1e-170, 1e170};
    sg_tracer t;
    sg_sprep s;
    long n = 0;
    int i, j, k;
    (void)state;
    memset(&t, 0, sizeof t);
    memset(&s, 0, sizeof s);
    t.o.clip = 1;
    t.o.clip_rtol = 1e-9;
    srand(5);
    for (k = 0; k < 4; k++) {
        double lim;
        s.sd = sds[k];
        lim = s.sd * (1.0 + t.o.clip_rtol);
        for (i = 0; i < 8; i++)
            for (j = 0; j < 20000; j++) {
                double th = 6.283185307179586 * rand() / RAND_MAX;
                double r = lim * (1.0 + rel[i] * (2.0 * rand() / RAND_MAX - 1.0));
                double x = r * cos(th), y = r * sin(th);
                int want = hypot(x, y) > lim ? SG_EVIGNETTED : 0;
                assert_int_equal(sg_past_clip(&t, &s, x, y), want);
                n++;
            }
        for (i = 0; i < 8; i++) {
            int want = hypot(odd[i][0], odd[i][1]) > lim ? SG_EVIGNETTED : 0;
            assert_int_equal(sg_past_clip(&t, &s, odd[i][0], odd[i][1]), want);
            n++;
        }
    }
    print_message("# aperture test: %ld points near the edge and special values, all as "
                  "hypot decides\n", n);
}

/* A failure's own code, with or without a diagnostic to carry its message:
 * an unknown glass is SG_ENOGLASS, never "out of memory". */
static void error_code_without_diag(void **state)
{
    sg_system *sys = tu_example("singlet.json");
    sg_catalog *cat = tu_catalog();
    sg_trace_opts o;
    sg_ray_in ray = {{0.0, 0.0, 0.0, 0.5, 0.0, 0.0}};
    sg_ray_surface out[16];
    int st, m;
    sg_diag d;
    (void)state;
    assert_true(sys->nsurf <= 16);
    sys->surf[1].mat.kind = SG_MAT_GLASS;
    strcpy(sys->surf[1].mat.name, "NO-SUCH-GLASS");
    for (m = 0; m < 3; m++) {
        sg_trace_opts_init(&o);
        o.method = (sg_method)m;
        assert_int_equal(sg_trace_batch(sys, cat, &o, SG_RAYS_NORMALIZED, &ray, 1, 1, out, &st,
                                        NULL),
                         SG_ENOGLASS);
        sg_diag_clear(&d);
        assert_int_equal(sg_trace_batch(sys, cat, &o, SG_RAYS_NORMALIZED, &ray, 1, 1, out, &st,
                                        &d),
                         SG_ENOGLASS);
        assert_non_null(strstr(d.msg, "NO-SUCH-GLASS"));
    }
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* sg_tracer_open returns the failure's code, with or without a
 * diagnostic, and leaves NULL behind; a success gives the tracer. */
static void open_returns_codes(void **state)
{
    sg_system *sys = tu_example("singlet.json");
    sg_catalog *cat = tu_catalog();
    sg_trace_opts o;
    sg_tracer *t = (sg_tracer *)&o; /* not NULL, so the test sees it cleared */
    sg_diag d;
    (void)state;
    assert_int_equal(sg_tracer_open(sys, cat, NULL, &t, NULL), SG_OK);
    assert_non_null(t);
    sg_tracer_free(t);
    assert_int_equal(sg_tracer_open(NULL, cat, NULL, &t, NULL), SG_EINVAL);
    assert_null(t);
    sg_trace_opts_init(&o);
    o.mpfr_bits = 7;
    assert_int_equal(sg_tracer_open(sys, cat, &o, &t, NULL), SG_ERANGE);
    assert_null(t);
    sys->surf[1].mat.kind = SG_MAT_GLASS;
    strcpy(sys->surf[1].mat.name, "NO-SUCH-GLASS");
    assert_int_equal(sg_tracer_open(sys, cat, NULL, &t, NULL), SG_ENOGLASS);
    assert_null(t);
    sg_diag_clear(&d);
    assert_int_equal(sg_tracer_open(sys, cat, NULL, &t, &d), SG_ENOGLASS);
    assert_non_null(strstr(d.msg, "NO-SUCH-GLASS"));
    assert_null(sg_tracer_new(sys, cat, NULL, NULL));
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* A tracer that cannot be made fails every analysis with the tracer's own
 * code, SG_ERANGE for a precision outside 53..100000 bits (sagitta.h,
 * sg_tracer_open), even without a diagnostic: a code rebuilt from the
 * diagnostic read SG_ENOMEM there.  The internal constructors that share
 * a model or make a batch return it too. */
static void analyses_keep_codes(void **state)
{
    sg_system *sys = tu_example("singlet.json");
    sg_catalog *cat = tu_catalog();
    sg_trace_opts bad;
    sg_spot_opts so;
    sg_fan_opts fo;
    sg_wavefront_opts wo;
    sg_semidiam_opts sdo;
    sg_setvig_opts vo;
    sg_psf_opts po;
    sg_spot spot;
    sg_fan fan;
    sg_wavefront wf;
    sg_fieldcurve_pt fc[3];
    sg_vigfactors *vf = calloc((size_t)sys->nfield, sizeof *vf);
    double *sd = calloc((size_t)sys->nsurf, sizeof *sd);
    sg_psf psf;
    sg_tracer *t, *m = NULL;
    sg_batch *b = (sg_batch *)&bad;
    (void)state;
    assert_non_null(vf);
    assert_non_null(sd);
    sg_trace_opts_init(&bad);
    bad.mpfr_bits = 7;
    memset(&spot, 0, sizeof spot);
    memset(&fan, 0, sizeof fan);
    memset(&wf, 0, sizeof wf);
    memset(&psf, 0, sizeof psf);
    sg_spot_opts_init(&so);
    so.trace = bad;
    assert_int_equal(sg_spot_compute(sys, cat, &so, &spot, NULL), SG_ERANGE);
    sg_fan_opts_init(&fo);
    fo.trace = bad;
    assert_int_equal(sg_fan_compute(sys, cat, &fo, &fan, NULL), SG_ERANGE);
    fo.opd = 1;
    assert_int_equal(sg_fan_compute(sys, cat, &fo, &fan, NULL), SG_ERANGE);
    sg_wavefront_opts_init(&wo);
    wo.trace = bad;
    wo.field = 0;
    assert_int_equal(sg_wavefront_trace(sys, cat, &wo, &wf, NULL, NULL), SG_ERANGE);
    assert_int_equal(sg_fieldcurve(sys, cat, &bad, 3, 0.01, fc, NULL), SG_ERANGE);
    sg_semidiam_opts_init(&sdo);
    sdo.trace = bad;
    assert_int_equal(sg_semi_diameters(sys, cat, &sdo, sd, NULL), SG_ERANGE);
    sg_setvig_opts_init(&vo);
    vo.trace = bad;
    assert_int_equal(sg_set_vignetting(sys, cat, &vo, vf, NULL), SG_ERANGE);
    sg_psf_opts_init(&po);
    po.trace = bad;
    po.method = SG_PSF_HUYGENS;
    assert_int_equal(sg_psf_compute(sys, cat, &po, &psf, NULL), SG_ERANGE);
    assert_int_equal(sg_batch_open(sys, cat, &bad, 2, &b, NULL), SG_ERANGE);
    assert_null(b);
    assert_int_equal(sg_tracer_open(sys, cat, NULL, &m, NULL), SG_OK);
    t = m;
    assert_int_equal(sg_tracer_open_method(m, SG_METHOD_MPFR, 7, NULL, &t, NULL), SG_ERANGE);
    assert_null(t);
    assert_int_equal(sg_tracer_open_method(m, SG_METHOD_MPFR, 128, NULL, &t, NULL), SG_OK);
    assert_non_null(t);
    assert_null(sg_tracer_new_method(m, SG_METHOD_MPFR, 7, NULL, NULL));
    sg_tracer_free(t);
    sg_tracer_free(m);
    free(vf);
    free(sd);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* A fork shares the prepared model (the same arrays, not copies), keeps
 * the options as given, and traces every ray to the same bits as the
 * tracer it came from, in every method, at another wavelength than the
 * primary (so the primary's tracer is forked too), on a design with
 * real aiming and vignetting. */
static void fork_shares_model(void **state)
{
    static const char *const ex[] = {"double_gauss.json", "tma.json"};
    sg_catalog *cat = tu_catalog();
    size_t e;
    int m, k, n = 0;
    (void)state;
    for (e = 0; e < 2; e++) {
        sg_system *sys = tu_example(ex[e]);
        sys->aim = SG_AIM_REAL;
        for (m = 0; m < 3; m++) {
            sg_trace_opts o;
            sg_tracer *t, *f;
            sg_ray_surface *a, *b;
            sg_trace_opts_init(&o);
            o.method = (sg_method)m;
            o.wave = sys->nwave > 1 ? (sys->primary_wave + 1) % sys->nwave : 0;
            assert_int_equal(sg_tracer_open(sys, cat, &o, &t, NULL), SG_OK);
            assert_int_equal(sg_tracer_fork(t, &f, NULL), SG_OK);
            assert_ptr_equal(f->sp, t->sp);
            assert_ptr_equal(f->sys, t->sys);
            assert_ptr_equal(f->model, t);
            if (t->prim)
                assert_ptr_equal(f->prim->sp, t->prim->sp);
            a = calloc((size_t)t->n, sizeof *a);
            b = calloc((size_t)t->n, sizeof *b);
            for (k = 0; k < 60; k++) {
                double hy = (k % 5) / 4.0, px = ((k * 7) % 11) / 5.0 - 1.0, py = ((k * 3) % 13) / 6.0 - 1.0;
                int r1 = sg_trace_normalized(t, 0.1, hy, px, py, a);
                int r2 = sg_trace_normalized(f, 0.1, hy, px, py, b);
                assert_int_equal(r1, r2);
                assert_memory_equal(a, b, (size_t)t->n * sizeof *a);
                n++;
            }
            /* Aiming landed rays unclipped; the options did not change. */
            assert_int_equal(t->o.clip, o.clip);
            assert_int_equal(f->o.clip, o.clip);
            assert_int_equal(t->unclipped, 0);
            free(a);
            free(b);
            sg_tracer_free(f);
            sg_tracer_free(t);
        }
        sg_system_free(sys);
    }
    print_message("# %d rays: a fork traces as its model, to the bit\n", n);
    sg_catalog_free(cat);
}

/* Every double of a row, the optical path included, bit for bit. */
static void same_rows_opl(const sg_ray_surface *a, const sg_ray_surface *b, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        assert_memory_equal(&a[i], &b[i], 13 * sizeof(double));
        assert_int_equal(a[i].status, b[i].status);
    }
}

/* The double Gauss (object at infinity, so each field's optical path
 * starts on the plane through its chief ray's point on surface 1) with
 * real aiming and an obscuration on surface 1 that stops the off-axis
 * chief rays there unless apertures are ignored (sg_batch_set_reference):
 * a field's launch data then differ between the two landing modes. */
static void obscured_front(sg_system *sys)
{
    sys->aim = SG_AIM_REAL;
    sys->surf[1].aperture = SG_OBSCURATION_CIRCULAR;
    sys->surf[1].ap_rmin = 0.0;
    sys->surf[1].ap_rmax = 12.0;
}

/* Rays of five fields (two of them differing only in the sign of a zero
 * Hx) in a shuffled order, traced by a kept batch in both landing modes
 * in turn, equal the rays traced field by field on a fresh tracer for
 * each field and mode: a field's launch data, kept by a tracer across
 * blocks and calls, are those a fresh tracer computes in the mode at
 * hand. */
static void any_order_case(const char *file, sg_method m, void (*tweak)(sg_system *))
{
    static const double fields[5][2] = {{0.0, 0.0}, {0.0, 0.5}, {0.0, 1.0}, {0.3, -0.7},
                                        {-0.0, 0.5}};
    enum { NP = 9, NR = 5 * NP * NP };
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_trace_opts o;
    sg_diag d;
    sg_batch *b;
    size_t ns = (size_t)sys->nsurf, r;
    sg_ray_in *rays = calloc(NR, sizeof *rays);
    sg_ray_surface *ref = calloc(NR * ns, sizeof *ref), *got = calloc(NR * ns, sizeof *got);
    int st1[NR], st2[NR], f, i, j, call, failed = 0;
    unsigned long long lcg = 35;
    assert_non_null(rays);
    assert_non_null(ref);
    assert_non_null(got);
    if (tweak)
        tweak(sys);
    for (r = 0, f = 0; f < 5; f++)
        for (i = 0; i < NP; i++)
            for (j = 0; j < NP; j++, r++) {
                rays[r].v[0] = fields[f][0];
                rays[r].v[1] = fields[f][1];
                rays[r].v[2] = -1.0 + 2.0 * i / (NP - 1);
                rays[r].v[3] = -1.0 + 2.0 * j / (NP - 1);
            }
    /* Fisher-Yates with a fixed generator. */
    for (r = NR - 1; r > 0; r--) {
        size_t k;
        sg_ray_in tmp;
        lcg = lcg * 6364136223846793005ULL + 1442695040888963407ULL;
        k = (size_t)((lcg >> 33) % (r + 1));
        tmp = rays[r];
        rays[r] = rays[k];
        rays[k] = tmp;
    }
    sg_trace_opts_init(&o);
    o.method = m;
    sg_diag_clear(&d);
    b = sg_batch_new(sys, cat, &o, 2, &d);
    assert_non_null(b);
    for (call = 0; call < 4; call++) {
        int mode = call % 2 == 0;
        /* The reference: one fresh tracer per field, in this mode. */
        for (f = 0; f < 5; f++) {
            sg_tracer *t = sg_tracer_new(sys, cat, &o, &d);
            assert_non_null(t);
            sg_tracer_set_reference(t, mode);
            for (r = 0; r < NR; r++)
                if (memcmp(rays[r].v, fields[f], 2 * sizeof(double)) == 0) {
                    st1[r] = sg_trace_normalized(t, rays[r].v[0], rays[r].v[1], rays[r].v[2],
                                                 rays[r].v[3], ref + r * ns);
                    failed += call == 1 && st1[r] != SG_OK;
                }
            sg_tracer_free(t);
        }
        sg_batch_set_reference(b, mode);
        memset(got, 0xA5, NR * ns * sizeof *got);
        assert_int_equal(sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, NR, NULL, 0, got, st2, &d),
                         SG_OK);
        assert_memory_equal(st1, st2, sizeof st1);
        same_rows_opl(ref, got, NR * ns);
    }
    print_message("# %s%s %s: %d rays of 5 fields in shuffled order (%d failing when clipped) "
                  "as fresh tracers trace them, in both landing modes\n",
                  file, tweak ? " (real aiming, surface 1 obscured)" : "", sg_method_name(m), NR,
                  failed);
    sg_batch_free(b);
    free(rays);
    free(ref);
    free(got);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void any_order(void **state)
{
    (void)state;
    any_order_case("double_gauss.json", SG_METHOD_PRECISE, obscured_front);
    any_order_case("cassegrain.json", SG_METHOD_PRECISE, NULL);
    any_order_case("double_gauss.json", SG_METHOD_CLASSIC, obscured_front);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(precise),
        cmocka_unit_test(precise_deep_stop),
        cmocka_unit_test(classic),
        cmocka_unit_test(mpfr),
        cmocka_unit_test(start_dir),
        cmocka_unit_test(handoff),
        cmocka_unit_test(clip_edge),
        cmocka_unit_test(error_code_without_diag),
        cmocka_unit_test(open_returns_codes),
        cmocka_unit_test(analyses_keep_codes),
        cmocka_unit_test(fork_shares_model),
        cmocka_unit_test(any_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
