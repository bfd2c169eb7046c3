/* test_index_cache.c - a tracer or paraxial computation given an
 * sg_index_cache gives the bits a fresh one gives (the independent
 * source: the same computation without the cache).  Random edits of
 * radius, thickness, glass, model glass, wavelength, temperature,
 * pressure and the adjust setting on the bundled designs; after each,
 * tracers of every method at several wavelengths are made with the cache
 * the earlier edits filled and without it, and their rows, indices and
 * paraxial data compared bit for bit; and a tracer's paraxial data at the
 * primary wavelength, which the editor uses, with sg_paraxial_compute's.
 * The cache also keeps each surface's validation and prepared surface:
 * edits of the conic, frame changes, apertures (some invalid), clipping,
 * asphere terms and wavelengths beyond a glass's range check that a
 * cached tracer's error, message and warnings are sg_system_validate's
 * and its rows a fresh tracer's.  The paraxial memo's running sums of the
 * track are checked after thickness edits against the exact sum. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "trace_int.h"
#include "model_int.h"
#include "testutil.h"

static uint64_t rng = UINT64_C(0x2545f4914f6cdd1d);

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

static const char *const glasses[] = { "N-BK7", "N-SF5", "N-LAK9", "F2", "N-SK16", "N-SF6" };

/* One random edit that keeps the design traceable most of the time. */
static void edit(sg_system *sys)
{
    int i = 1 + (int)(next() % (uint64_t)(sys->nsurf - 2));
    sg_surface *s = &sys->surf[i];
    switch (next() % 14) {
    case 8:
        s->conic = next() % 3 ? -0.5 + uniform() : 0.0;
        break;
    case 9:
        /* A frame change before (from surface 2 on) or after. */
        if (i >= 2 && next() % 2)
            s->before.tx = next() % 3 ? 0.5 * (uniform() - 0.5) : 0.0;
        else
            s->after.dy = next() % 3 ? 0.1 * (uniform() - 0.5) : 0.0;
        break;
    case 10:
        /* A circular aperture, invalid one time in four (rmax <= rmin). */
        s->aperture = next() % 3 ? SG_APERTURE_CIRCULAR : SG_APERTURE_NONE;
        s->ap_rmin = next() % 4 ? 0.0 : 50.0;
        s->ap_rmax = 20.0 + 10.0 * uniform();
        break;
    case 11:
        s->sd_fixed = !s->sd_fixed;
        s->semi_diameter = 5.0 + 20.0 * uniform();
        break;
    case 12:
        s->type = next() % 2 ? SG_SURF_EVENASPH : SG_SURF_STANDARD;
        s->asph[1] = 1e-7 * (uniform() - 0.5);
        break;
    case 13:
        /* Beyond every glass's range: warnings, then back. */
        sys->wave[next() % (uint64_t)sys->nwave].um = next() % 2 ? 3.0 : 0.55;
        break;
    case 0:
        if (isfinite(s->radius) && s->radius != 0.0)
            s->radius *= 1.0 + 0.01 * (uniform() - 0.5);
        break;
    case 1:
        s->thickness *= 1.0 + 0.01 * (uniform() - 0.5);
        break;
    case 2:
        if (s->mat.kind == SG_MAT_GLASS)
            snprintf(s->mat.name, sizeof s->mat.name, "%s",
                     glasses[next() % (sizeof glasses / sizeof glasses[0])]);
        break;
    case 3:
        if (s->mat.kind == SG_MAT_GLASS || s->mat.kind == SG_MAT_MODEL) {
            s->mat.kind = SG_MAT_MODEL;
            s->mat.index = 1.5 + 0.2 * uniform();
            s->mat.vd = 40.0 + 20.0 * uniform();
            s->mat.dpgf = 0.0;
        }
        break;
    case 4:
        sys->wave[next() % (uint64_t)sys->nwave].um *= 1.0 + 0.02 * (uniform() - 0.5);
        break;
    case 5:
        sys->temperature = 20.0 + 30.0 * (uniform() - 0.5);
        break;
    case 6:
        sys->pressure = 1.0 + 0.2 * (uniform() - 0.5);
        break;
    default:
        sys->adjust_index = !sys->adjust_index;
        break;
    }
}

static const double rays[][4] = {
    { 0, 0, 0, 0 }, { 0, 1, 0, 1 }, { 0, 0.7, 0.3, -0.5 }, { 0, -0.4, -0.8, 0.1 },
};

/* Fresh and cached tracers of sys agree; returns how many were compared. */
static int compare(const sg_system *sys, const sg_catalog *cat, sg_index_cache *ic)
{
    static const sg_method methods[] = { SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR };
    sg_ray_surface a[64], b[64];
    int m, w, r, i, n = 0;
    for (m = 0; m < 3; m++) {
        for (w = 0; w < sys->nwave; w++) {
            sg_trace_opts o;
            sg_tracer *tf, *tc;
            sg_diag df, dc;
            sg_trace_opts_init(&o);
            o.method = methods[m];
            o.wave = w;
            sg_diag_clear(&df);
            sg_diag_clear(&dc);
            tf = sg_tracer_new(sys, cat, &o, &df);
            tc = sg_tracer_new_cached(sys, cat, &o, ic, &dc);
            /* The same success or failure, with the same message. */
            assert_int_equal(tf != NULL, tc != NULL);
            assert_int_equal(df.code, dc.code);
            assert_string_equal(df.msg, dc.msg);
            {
                /* With a cache the validation's warnings come too, as
                 * sg_system_validate gives them. */
                sg_diag dv;
                int k;
                sg_diag_clear(&dv);
                if (sg_system_validate(sys, cat, &dv) != SG_OK)
                    assert_string_equal(dv.msg, dc.msg);
                assert_int_equal(dv.nwarn, dc.nwarn);
                for (k = 0; k < dv.nwarn && k < SG_DIAG_MAXWARN; k++)
                    assert_string_equal(dv.warn[k], dc.warn[k]);
            }
            if (!tf)
                continue;
            assert_int_equal(sg_tracer_nsurf(tf), sg_tracer_nsurf(tc));
            assert_true(sg_tracer_nsurf(tf) <= 64);
            for (i = 0; i < sg_tracer_nsurf(tf); i++) {
                double x = sg_tracer_index(tf, i), y = sg_tracer_index(tc, i);
                assert_memory_equal(&x, &y, sizeof x);
            }
            assert_memory_equal(sg_tracer_paraxial(tf), sg_tracer_paraxial(tc),
                                sizeof(sg_paraxial));
            /* The editor takes the primary wavelength's paraxial data from
             * its tracer: they are sg_paraxial_compute's. */
            if (w == sys->primary_wave) {
                sg_paraxial p;
                memset(&p, 0, sizeof p);
                assert_int_equal(sg_paraxial_compute(sys, cat, w, &p, &df), SG_OK);
                assert_memory_equal(&p, sg_tracer_paraxial(tf), sizeof p);
            }
            for (r = 0; r < (int)(sizeof rays / sizeof rays[0]); r++) {
                int ra = sg_trace_normalized(tf, rays[r][0], rays[r][1], rays[r][2],
                                             rays[r][3], a);
                int rb = sg_trace_normalized(tc, rays[r][0], rays[r][1], rays[r][2],
                                             rays[r][3], b);
                assert_int_equal(ra, rb);
                for (i = 0; i < sg_tracer_nsurf(tf); i++)
                    assert_true(tu_same_row(&a[i], &b[i]));
            }
            sg_tracer_free(tf);
            sg_tracer_free(tc);
            n++;
        }
    }
    for (w = 0; w < sys->nwave; w++) {
        sg_paraxial pf, pc;
        sg_diag df, dc;
        int rf, rcc;
        memset(&pf, 0, sizeof pf);
        memset(&pc, 0, sizeof pc);
        sg_diag_clear(&df);
        sg_diag_clear(&dc);
        rf = sg_paraxial_compute(sys, cat, w, &pf, &df);
        rcc = sg_paraxial_compute_cached(sys, cat, w, ic, &pc, &dc);
        assert_int_equal(rf, rcc);
        assert_memory_equal(&pf, &pc, sizeof pf);
    }
    return n;
}

static void run_design(const char *file, int nedit)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_index_cache *ic = sg_index_cache_new();
    unsigned long hits, misses;
    int k, n = 0;
    assert_non_null(ic);
    n += compare(sys, cat, ic);
    for (k = 0; k < nedit; k++) {
        sg_system *before = sg_system_clone(sys);
        int got;
        assert_non_null(before);
        edit(sys);
        got = compare(sys, cat, ic);
        /* An edit that no tracer accepts is compared, then undone, so
         * that the next ones are traced. */
        if (got == 0)
            assert_int_equal(sg_system_assign(sys, before), SG_OK);
        sg_system_free(before);
        n += got;
    }
    sg_index_cache_stats(ic, &hits, &misses);
    print_message("# %s: %d edits, %d tracer pairs, %lu indices from the cache, %lu computed\n",
                  file, nedit, n, hits, misses);
    /* The cache was used, or the comparison proved nothing. */
    assert_true(hits > misses);
    {
        unsigned long prep, valid;
        sg_index_cache_reused(ic, &prep, &valid);
        print_message("# %lu prepared surfaces and %lu validations from the cache\n", prep,
                      valid);
        assert_true(prep > 0 && valid > 0);
    }
    sg_index_cache_free(ic);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void test_cooke(void **state)
{
    (void)state;
    run_design("cooke_triplet.json", 40);
}

static void test_double_gauss(void **state)
{
    (void)state;
    run_design("double_gauss.json", 30);
}

static void test_singlet(void **state)
{
    (void)state;
    run_design("singlet.json", 40);
}

/* A long chain of weak menisci, as bench/many_surfaces.py writes it (n
 * surfaces, stop on surface 1). */
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
        s->radius = i % 2 ? ((i / 2) % 2 ? -400.0 : 400.0) : ((i / 2) % 2 ? -380.0 : 450.0);
        s->thickness = i % 2 ? 2.0 : 1.0;
        s->mat.kind = i % 2 ? SG_MAT_GLASS : SG_MAT_AIR;
        if (i % 2)
            snprintf(s->mat.name, sizeof s->mat.name, "%s", glasses[(i / 2) % 5]);
        s->semi_diameter = 20.0;
        s->sd_fixed = 0;
    }
    sys->stop = 1;
    return sys;
}

/* The paraxial traces the cache keeps resume after the surfaces an edit
 * left alone, with a fresh computation's bits: random edits (and moves of
 * the stop, inserted and deleted surfaces) on a long design, every
 * method and wavelength compared as above. */
static void test_many_surfaces(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = many(40);
    sg_index_cache *ic = sg_index_cache_new();
    unsigned long r0;
    int k, n = 0;
    (void)state;
    n += compare(sys, cat, ic);
    for (k = 0; k < 30; k++) {
        int i = 1 + (int)(next() % (uint64_t)(sys->nsurf - 2));
        switch (next() % 6) {
        case 0:
            sys->stop = i;
            break;
        case 1:
            if (sys->nsurf < 60)
                sg_system_insert(sys, i);
            break;
        case 2:
            if (sys->stop != i)
                sg_system_delete(sys, i);
            break;
        default:
            edit(sys);
            break;
        }
        n += compare(sys, cat, ic);
    }
    /* An edit far behind the stop: the traces resume. */
    sys->stop = 1;
    n += compare(sys, cat, ic);
    r0 = sg_index_cache_resumes(ic);
    sys->surf[sys->nsurf - 3].radius *= 1.0 + 1e-6;
    n += compare(sys, cat, ic);
    print_message("# %d tracer pairs, %lu paraxial traces resumed\n", n,
                  sg_index_cache_resumes(ic));
    assert_true(sg_index_cache_resumes(ic) > r0);
    sg_index_cache_free(ic);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The paraxial memo keeps the track's running sums up to the first
 * changed thickness, and the mpfr tracer copies the index ratio of a pair
 * of media met on an earlier surface.  Thickness edits at random places
 * (and radius edits, which keep every sum, and undos) on a long chain: cached and
 * fresh agree bit for bit (compare), the total track is the exact sum of
 * the thicknesses (MPFR at 2,000 bits in the test) to within its last
 * bit, and the mpfr method's rows stay within the precise method's bounds
 * of the precise rows (the two methods share no code for the ratios). */
static void test_track_edits(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = many(40);
    sg_index_cache *ic = sg_index_cache_new();
    sg_ray_surface a[40], b[40];
    mpfr_t sum;
    double *undo = NULL, was = 0.0;
    int k, j, n = 0;
    (void)state;
    /* One wavelength: the 128- and 256-bit sets stay in the memo, so the
     * edits resume from it. */
    sys->nwave = 1;
    sys->primary_wave = 0;
    mpfr_init2(sum, 2000);
    n += compare(sys, cat, ic);
    for (k = 0; k < 24; k++) {
        int i = 1 + (int)(next() % (uint64_t)(sys->nsurf - 2));
        sg_paraxial p;
        sg_diag d;
        double want;
        /* Every fourth edit undoes the one before: the keys must be the
         * values last computed from, not the ones before them. */
        if (k % 4 == 3) {
            *undo = was;
        } else {
            undo = k % 3 == 2 && isfinite(sys->surf[i].radius) ? &sys->surf[i].radius
                                                                 : &sys->surf[i].thickness;
            was = *undo;
            *undo *= 1.0 + 0.01 * (uniform() - 0.5);
        }
        n += compare(sys, cat, ic);
        sg_diag_clear(&d);
        assert_int_equal(sg_paraxial_compute_cached(sys, cat, sys->primary_wave, ic, &p, &d),
                         SG_OK);
        mpfr_set_zero(sum, 1);
        for (j = 1; j <= sys->nsurf - 2; j++)
            mpfr_add_d(sum, sum, sys->surf[j].thickness, MPFR_RNDN);
        want = mpfr_get_d(sum, MPFR_RNDN);
        if (!(fabs(p.total_track - want) <= nextafter(want, INFINITY) - want))
            fail_msg("edit %d: track %.17g, exact sum %.17g", k, p.total_track, want);
    }
    for (k = 0; k < 2; k++) {
        sg_trace_opts o;
        sg_tracer *tp, *tm;
        sg_diag d;
        sg_trace_opts_init(&o);
        sg_diag_clear(&d);
        tp = sg_tracer_new_cached(sys, cat, &o, ic, &d);
        o.method = SG_METHOD_MPFR;
        tm = sg_tracer_new_cached(sys, cat, &o, ic, &d);
        assert_non_null(tp);
        assert_non_null(tm);
        assert_int_equal(sg_trace_normalized(tp, 0, k, 0, 1, a), SG_OK);
        assert_int_equal(sg_trace_normalized(tm, 0, k, 0, 1, b), SG_OK);
        for (j = 1; j < sys->nsurf; j++) {
            double e = a[j].error_bound + b[j].error_bound;
            if (!(fabs(a[j].x - b[j].x) <= e && fabs(a[j].y - b[j].y) <= e &&
                  fabs(a[j].z - b[j].z) <= e))
                fail_msg("field %d, surface %d: precise (%.17g, %.17g) and mpfr (%.17g, "
                         "%.17g) differ beyond %.3g", k, j, a[j].x, a[j].y, b[j].x, b[j].y, e);
        }
        sg_tracer_free(tp);
        sg_tracer_free(tm);
    }
    print_message("# %d tracer pairs after thickness and radius edits\n", n);
    mpfr_clear(sum);
    sg_index_cache_free(ic);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The cache's own bound: past its limit it starts again, and still gives
 * fresh bits. */
static void test_many_wavelengths(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_index_cache *ic = sg_index_cache_new();
    int k;
    (void)state;
    for (k = 0; k < 2500; k++) {
        sg_trace_opts o;
        sg_tracer *tf, *tc;
        sg_diag d;
        sys->wave[0].um = 0.45 + 0.2 * uniform();
        sg_trace_opts_init(&o);
        o.wave = 0;
        sg_diag_clear(&d);
        tf = sg_tracer_new(sys, cat, &o, &d);
        tc = sg_tracer_new_cached(sys, cat, &o, ic, &d);
        assert_non_null(tf);
        assert_non_null(tc);
        {
            int i;
            for (i = 0; i < sg_tracer_nsurf(tf); i++) {
                double x = sg_tracer_index(tf, i), y = sg_tracer_index(tc, i);
                assert_memory_equal(&x, &y, sizeof x);
            }
        }
        sg_tracer_free(tf);
        sg_tracer_free(tc);
    }
    sg_index_cache_free(ic);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A glass met again on a later surface takes the index the first one got,
 * with the sign of its own side of a mirror: N-BK7 before a fold mirror
 * and again after it (travelled backwards, so negative), and F2 between.
 * Each index is checked against the glass's own MPFR formula. */
static void test_repeated_glass_signs(void **state)
{
    static const char text[] =
        "{ \"format\": \"sagitta-design\", \"surfaces\": [ { \"thickness\": \"inf\" },\n"
        "  { \"radius\": 50, \"thickness\": 5, \"stop\": true, \"material\": \"N-BK7\" },\n"
        "  { \"radius\": -50, \"thickness\": 2, \"material\": \"F2\" },\n"
        "  { \"thickness\": 20 },\n"
        "  { \"thickness\": -10, \"material\": \"MIRROR\" },\n"
        "  { \"radius\": -40, \"thickness\": -4, \"material\": \"N-BK7\" },\n"
        "  { \"radius\": 40, \"thickness\": -3, \"material\": \"F2\" },\n"
        "  { \"thickness\": -30 }, {} ] }\n";
    static const struct {
        int surf;
        const char *glass;
        int sign;
    } want[] = {{1, "N-BK7", 1}, {2, "F2", 1}, {5, "N-BK7", -1}, {6, "F2", -1}};
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new();
    sg_index_cache *ic = sg_index_cache_new();
    mpfr_t idx[9], n, um;
    sg_diag d;
    int i, pass;
    (void)state;
    assert_int_equal(sg_design_parse(sys, text, strlen(text), "fold.json", &d), SG_OK);
    assert_int_equal(sys->nsurf, 9);
    mpfr_inits2(128, n, um, (mpfr_ptr)0);
    for (i = 0; i < 9; i++)
        mpfr_init2(idx[i], 128);
    mpfr_set_d(um, sys->wave[sys->primary_wave].um, MPFR_RNDN);
    /* Without a cache, then with one (twice: the second from its entries). */
    for (pass = 0; pass < 3; pass++) {
        sg_diag_clear(&d);
        assert_int_equal(sg_indices_mpfr_cached(sys, cat, sys->primary_wave, idx,
                                                pass ? ic : NULL, &d),
                         SG_OK);
        for (i = 0; i < 4; i++) {
            assert_int_equal(sg_glass_index_mpfr(sg_catalog_find(cat, want[i].glass), n, um), 0);
            if (want[i].sign < 0)
                mpfr_neg(n, n, MPFR_RNDN);
            if (!mpfr_equal_p(idx[want[i].surf], n))
                fail_msg("pass %d: surface %d: index %.20g, want %.20g", pass, want[i].surf,
                         mpfr_get_d(idx[want[i].surf], MPFR_RNDN), mpfr_get_d(n, MPFR_RNDN));
        }
        assert_true(mpfr_cmp_si(idx[3], 1) == 0 && mpfr_cmp_si(idx[4], -1) == 0 &&
                    mpfr_cmp_si(idx[7], -1) == 0);
    }
    for (i = 0; i < 9; i++)
        mpfr_clear(idx[i]);
    mpfr_clears(n, um, (mpfr_ptr)0);
    sg_index_cache_free(ic);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* One glass name in three catalogs on three surfaces: each surface takes
 * its own catalog's glass (the look-ups of one pass are kept by both
 * names), with the cache and without, checked against each glass's own
 * MPFR formula. */
static void test_same_name_catalogs(void **state)
{
    static const char text[] =
        "{ \"format\": \"sagitta-design\", \"surfaces\": [ { \"thickness\": \"inf\" },\n"
        "  { \"radius\": 50, \"thickness\": 5, \"stop\": true,\n"
        "    \"material\": { \"glass\": \"F7\", \"catalog\": \"CDGM\" } },\n"
        "  { \"radius\": -50, \"thickness\": 2,\n"
        "    \"material\": { \"glass\": \"F7\", \"catalog\": \"HOYA\" } },\n"
        "  { \"radius\": -80, \"thickness\": 3, \"material\": \"F7\" },\n"
        "  { \"thickness\": 30 }, {} ] }\n";
    static const char *const cats[] = { "CDGM", "HOYA", "" };
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new();
    sg_index_cache *ic = sg_index_cache_new();
    mpfr_t idx[6], n, um;
    sg_diag d;
    int i, pass, differ = 0;
    (void)state;
    assert_int_equal(sg_design_parse(sys, text, strlen(text), "f7.json", &d), SG_OK);
    assert_int_equal(sys->nsurf, 6);
    mpfr_inits2(128, n, um, (mpfr_ptr)0);
    for (i = 0; i < 6; i++)
        mpfr_init2(idx[i], 128);
    mpfr_set_d(um, sys->wave[sys->primary_wave].um, MPFR_RNDN);
    for (pass = 0; pass < 3; pass++) {
        sg_diag_clear(&d);
        assert_int_equal(sg_indices_mpfr_cached(sys, cat, sys->primary_wave, idx,
                                                pass ? ic : NULL, &d),
                         SG_OK);
        for (i = 0; i < 3; i++) {
            const sg_glass *g = sg_catalog_find_in(cat, cats[i], "F7");
            assert_non_null(g);
            assert_int_equal(sg_glass_index_mpfr(g, n, um), 0);
            if (!mpfr_equal_p(idx[1 + i], n))
                fail_msg("pass %d: surface %d (F7 of \"%s\"): index %.20g, want %.20g", pass,
                         1 + i, cats[i], mpfr_get_d(idx[1 + i], MPFR_RNDN),
                         mpfr_get_d(n, MPFR_RNDN));
        }
        differ = !mpfr_equal_p(idx[1], idx[2]) && !mpfr_equal_p(idx[2], idx[3]);
    }
    /* Otherwise the test could not tell the catalogs apart. */
    assert_true(differ);
    for (i = 0; i < 6; i++)
        mpfr_clear(idx[i]);
    mpfr_clears(n, um, (mpfr_ptr)0);
    sg_index_cache_free(ic);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cooke),
        cmocka_unit_test(test_double_gauss),
        cmocka_unit_test(test_singlet),
        cmocka_unit_test(test_many_wavelengths),
        cmocka_unit_test(test_many_surfaces),
        cmocka_unit_test(test_track_edits),
        cmocka_unit_test(test_repeated_glass_signs),
        cmocka_unit_test(test_same_name_catalogs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
