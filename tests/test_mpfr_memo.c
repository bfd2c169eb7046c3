/* test_mpfr_memo.c - an mpfr tracer given an sg_mpfr_memo, which resumes
 * its ray after the surfaces an edit left alone, gives the bits of a full
 * trace (the independent source: a fresh mpfr tracer without a memo,
 * traced from the object).  Random edits of radius, thickness, conic,
 * glass, model glass, clipping, tilts, wavelength, field, stop, ray
 * aiming and inserted or deleted surfaces, on a long chain of menisci (as
 * bench/many_surfaces.py writes), the Cooke triplet with real aiming and
 * the three-mirror anastigmat; after each, every ray's rows and return
 * code are compared bit for bit.  The memo's tracer is made as the editor
 * makes it, by sg_tracer_new_method from a precise (or classic) tracer,
 * so its bits are checked against a fresh mpfr tracer's too.  The memo must also have been used: an
 * edit of one radius behind the stop resumes at that surface. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#define MAXS 64

static uint64_t rng = UINT64_C(0x9e3779b97f4a7c15);

static uint64_t next(void)
{
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return rng * UINT64_C(2685821657736338717);
}

static double uniform(void)
{
    return (double)(next() >> 11) * 0x1p-53;
}

static const char *const glasses[] = { "N-BK7", "N-SF5", "N-LAK9", "F2", "N-SK16" };

/* The rays: normalized (hx, hy, px, py), and one started (a point in
 * surface 1's frame and a direction) as the last. */
static const double rays[][4] = {
    { 0, 1, 0, 1 }, { 0, 0.7, 0.3, -0.5 }, { 0, 0, 0, 0.9 },
};
#define NRAY ((int)(sizeof rays / sizeof rays[0]) + 1)

/* Alternate weak menisci in five glasses and air, stop on surface 1, as
 * bench/many_surfaces.py writes them, n surfaces in all. */
static sg_system *many(int n)
{
    sg_system *sys = tu_example("singlet.json");
    int i;
    assert_non_null(sys);
    while (sys->nsurf < n)
        assert_int_equal(sg_system_insert(sys, 1), SG_OK);
    for (i = 1; i < n - 1; i++) {
        sg_surface *s = &sys->surf[i];
        memset(s->asph, 0, sizeof s->asph);
        s->conic = 0.0;
        if (i % 2 == 1) {
            s->radius = (i / 2) % 2 == 0 ? 400.0 : -400.0;
            s->thickness = 2.0;
            s->mat.kind = SG_MAT_GLASS;
            snprintf(s->mat.name, sizeof s->mat.name, "%s", glasses[(i / 2) % 5]);
        } else {
            s->radius = (i / 2) % 2 == 0 ? 450.0 : -380.0;
            s->thickness = 1.0;
            s->mat.kind = SG_MAT_AIR;
        }
        s->semi_diameter = 20.0;
        s->sd_fixed = 0;
    }
    sys->stop = 1;
    return sys;
}

/* One random edit; returns the surface when it changed one radius only,
 * else 0. */
static int edit(sg_system *sys)
{
    int i = 1 + (int)(next() % (uint64_t)(sys->nsurf - 2));
    sg_surface *s = &sys->surf[i];
    switch (next() % 14) {
    case 0:
    case 1:
    case 2:
        if (isfinite(s->radius) && s->radius != 0.0) {
            s->radius *= 1.0 + 0.01 * (uniform() - 0.5);
            return i;
        }
        break;
    case 3:
        s->thickness *= 1.0 + 0.01 * (uniform() - 0.5);
        break;
    case 4:
        s->conic = uniform() - 0.5;
        break;
    case 5:
        if (s->mat.kind == SG_MAT_GLASS)
            snprintf(s->mat.name, sizeof s->mat.name, "%s", glasses[next() % 5]);
        else if (s->mat.kind == SG_MAT_MODEL)
            s->mat.index = 1.5 + 0.2 * uniform();
        break;
    case 6:
        s->sd_fixed = !s->sd_fixed;
        break;
    case 7:
        s->before.tx = 0.05 * (uniform() - 0.5);
        break;
    case 8:
        sys->wave[next() % (uint64_t)sys->nwave].um *= 1.0 + 0.02 * (uniform() - 0.5);
        break;
    case 9:
        sys->field[next() % (uint64_t)sys->nfield].y *= 1.0 + 0.1 * (uniform() - 0.5);
        break;
    case 10:
        if (sys->nsurf < MAXS)
            sg_system_insert(sys, i);
        break;
    case 11:
        if (sys->nsurf > 6 && sys->stop != i)
            sg_system_delete(sys, i);
        break;
    case 12:
        sys->aim = (sg_aim)(next() % 3);
        break;
    default:
        sys->stop = i;
        break;
    }
    return 0;
}

/* Rows of the memo's tracer against a fresh one's for every ray; counts
 * the rays compared into *n.  mem holds a memo a ray. */
static void compare(const sg_system *sys, const sg_catalog *cat, sg_mpfr_memo **mem, int bits,
                    int wave, int *n)
{
    sg_ray_surface a[MAXS], b[MAXS];
    sg_trace_opts o;
    sg_tracer *tp, *tm, *tf;
    sg_diag dm, df;
    int r, i;
    sg_trace_opts_init(&o);
    o.wave = wave;
    /* The memo's tracer is made as the editor makes it, from the live
     * (precise, now and then classic) tracer's model. */
    o.method = next() % 6 == 0 ? SG_METHOD_CLASSIC : SG_METHOD_PRECISE;
    sg_diag_clear(&dm);
    sg_diag_clear(&df);
    tp = sg_tracer_new(sys, cat, &o, &dm);
    tm = tp ? sg_tracer_new_method(tp, SG_METHOD_MPFR, bits, NULL, &dm) : NULL;
    o.method = SG_METHOD_MPFR;
    o.mpfr_bits = bits;
    tf = sg_tracer_new(sys, cat, &o, &df);
    assert_int_equal(tm != NULL, tf != NULL);
    if (!tm) {
        /* The same failure. */
        assert_int_equal(dm.code, df.code);
        assert_string_equal(dm.msg, df.msg);
        sg_tracer_free(tp);
        return;
    }
    assert_true(sg_tracer_nsurf(tm) <= MAXS);
    for (r = 0; r < NRAY; r++) {
        int ra, rb;
        sg_tracer_use_memo(tm, mem[r]);
        if (r < NRAY - 1) {
            ra = sg_trace_normalized(tm, rays[r][0], rays[r][1], rays[r][2], rays[r][3], a);
            rb = sg_trace_normalized(tf, rays[r][0], rays[r][1], rays[r][2], rays[r][3], b);
        } else {
            static const double S[3] = { 0.0, 2.0, -10.0 }, D[3] = { 0.0, -0.03, 1.0 };
            ra = sg_trace_start(tm, S, D, a);
            rb = sg_trace_start(tf, S, D, b);
        }
        assert_int_equal(ra, rb);
        for (i = 0; i < sg_tracer_nsurf(tm); i++)
            if (!tu_same_row(&a[i], &b[i]))
                fail_msg("ray %d, surface %d of %d: the memo's row differs (resumed at %d)", r,
                         i, sg_tracer_nsurf(tm), sg_mpfr_memo_last_resume(mem[r]));
        (*n)++;
    }
    sg_tracer_free(tm);
    sg_tracer_free(tp);
    sg_tracer_free(tf);
}

static void run(sg_system *sys, int nedit, int check_resume)
{
    sg_catalog *cat = tu_catalog();
    sg_mpfr_memo *mem[NRAY];
    unsigned long resumes = 0;
    int k, r, n = 0, exact = 0;
    for (r = 0; r < NRAY; r++)
        assert_non_null(mem[r] = sg_mpfr_memo_new());
    compare(sys, cat, mem, 256, -1, &n);
    for (k = 0; k < nedit; k++) {
        int s = edit(sys);
        /* Mostly the primary wavelength at 256 bits, as the editor; now
         * and then another wavelength or precision, which the memo must
         * tell apart. */
        int bits = next() % 8 == 0 ? 160 : 256;
        int wave = next() % 8 == 0 ? (int)(next() % (uint64_t)sys->nwave) : -1;
        compare(sys, cat, mem, bits, wave, &n);
        if (check_resume && s > sys->stop && bits == 256 && wave < 0 &&
            sg_mpfr_memo_last_resume(mem[0]) > 1) {
            /* An edit behind the stop leaves the launch: the ray resumes
             * at the edited surface. */
            assert_int_equal(sg_mpfr_memo_last_resume(mem[0]), s);
            exact++;
        }
    }
    for (r = 0; r < NRAY; r++) {
        resumes += sg_mpfr_memo_resumes(mem[r]);
        sg_mpfr_memo_free(mem[r]);
    }
    print_message("# %d edits, %d rays compared, %lu resumed, %d at the edited surface\n",
                  nedit, n, resumes, exact);
    /* The memo was used, or the comparison proved nothing. */
    assert_true(resumes > (unsigned long)n / 4);
    if (check_resume)
        assert_true(exact > 0);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_many(void **state)
{
    (void)state;
    run(many(40), 120, 1);
}

static void test_cooke_aimed(void **state)
{
    sg_system *sys = tu_example("cooke_triplet.json");
    (void)state;
    sys->aim = SG_AIM_REAL;
    run(sys, 40, 0);
}

static void test_tma(void **state)
{
    (void)state;
    run(tu_example("tma.json"), 30, 0);
}

/* The ray resumes from the surface an edit changed, without the edit and
 * the memo at the stop before it. */
static void test_resume_point(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = many(30);
    sg_mpfr_memo *mem[NRAY];
    int r, k, n = 0;
    (void)state;
    for (r = 0; r < NRAY; r++)
        assert_non_null(mem[r] = sg_mpfr_memo_new());
    compare(sys, cat, mem, 256, -1, &n);
    assert_int_equal(sg_mpfr_memo_last_resume(mem[0]), 1);
    for (k = 28; k >= 2; k -= 3) {
        sys->surf[k].radius *= 1.0 + 1e-6;
        compare(sys, cat, mem, 256, -1, &n);
        assert_int_equal(sg_mpfr_memo_last_resume(mem[0]), k);
    }
    /* Nothing changed: the whole chain is reused but for the image. */
    compare(sys, cat, mem, 256, -1, &n);
    assert_int_equal(sg_mpfr_memo_last_resume(mem[0]), 29);
    /* A new field moves the launch: from the object again. */
    sys->field[sys->nfield - 1].y *= 1.01;
    compare(sys, cat, mem, 256, -1, &n);
    assert_int_equal(sg_mpfr_memo_last_resume(mem[0]), 1);
    for (r = 0; r < NRAY; r++)
        sg_mpfr_memo_free(mem[r]);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resume_point),
        cmocka_unit_test(test_many),
        cmocka_unit_test(test_cooke_aimed),
        cmocka_unit_test(test_tma),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
