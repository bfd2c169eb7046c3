/*
 * test_zernike.c - the Fringe and Standard sets against published tables,
 * their orthogonality by exact quadrature over the disc, fits that return
 * the coefficients a wavefront was built from, and RMS/P-V with piston and
 * tilt removed against a direct computation.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "num.h"
#include "testutil.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The 37 Fringe terms as published (J. C. Wyant and K. Creath, "Basic
 * Wavefront Aberration Theory for Optical Metrology", Applied Optics and
 * Optical Engineering XI, 1992, Table 2; the same list is Zemax's "Zernike
 * Fringe" table): m (negative: sine) and the radial polynomial's
 * coefficients of rho^0, rho^1, ... rho^12. */
static const struct {
    int m;
    double r[13];
} fringe[37] = {
    { 0, { 1 } },
    { 1, { 0, 1 } },
    { -1, { 0, 1 } },
    { 0, { -1, 0, 2 } },
    { 2, { 0, 0, 1 } },
    { -2, { 0, 0, 1 } },
    { 1, { 0, -2, 0, 3 } },
    { -1, { 0, -2, 0, 3 } },
    { 0, { 1, 0, -6, 0, 6 } },
    { 3, { 0, 0, 0, 1 } },
    { -3, { 0, 0, 0, 1 } },
    { 2, { 0, 0, -3, 0, 4 } },
    { -2, { 0, 0, -3, 0, 4 } },
    { 1, { 0, 3, 0, -12, 0, 10 } },
    { -1, { 0, 3, 0, -12, 0, 10 } },
    { 0, { -1, 0, 12, 0, -30, 0, 20 } },
    { 4, { 0, 0, 0, 0, 1 } },
    { -4, { 0, 0, 0, 0, 1 } },
    { 3, { 0, 0, 0, -4, 0, 5 } },
    { -3, { 0, 0, 0, -4, 0, 5 } },
    { 2, { 0, 0, 6, 0, -20, 0, 15 } },
    { -2, { 0, 0, 6, 0, -20, 0, 15 } },
    { 1, { 0, -4, 0, 30, 0, -60, 0, 35 } },
    { -1, { 0, -4, 0, 30, 0, -60, 0, 35 } },
    { 0, { 1, 0, -20, 0, 90, 0, -140, 0, 70 } },
    { 5, { 0, 0, 0, 0, 0, 1 } },
    { -5, { 0, 0, 0, 0, 0, 1 } },
    { 4, { 0, 0, 0, 0, -5, 0, 6 } },
    { -4, { 0, 0, 0, 0, -5, 0, 6 } },
    { 3, { 0, 0, 0, 10, 0, -30, 0, 21 } },
    { -3, { 0, 0, 0, 10, 0, -30, 0, 21 } },
    { 2, { 0, 0, -10, 0, 60, 0, -105, 0, 56 } },
    { -2, { 0, 0, -10, 0, 60, 0, -105, 0, 56 } },
    { 1, { 0, 5, 0, -60, 0, 210, 0, -280, 0, 126 } },
    { -1, { 0, 5, 0, -60, 0, 210, 0, -280, 0, 126 } },
    { 0, { -1, 0, 30, 0, -210, 0, 560, 0, -630, 0, 252 } },
    { 0, { 1, 0, -42, 0, 420, 0, -1680, 0, 3150, 0, -2772, 0, 924 } },
};

/* Noll's Table 1 (R. J. Noll, "Zernike polynomials and atmospheric
 * turbulence", J. Opt. Soc. Am. 66, 207 (1976)): n and m of j = 1..22,
 * with the sine terms (odd j, m != 0) given m < 0 here. */
static const int noll[22][2] = {
    { 0, 0 }, { 1, 1 }, { 1, -1 }, { 2, 0 }, { 2, -2 }, { 2, 2 }, { 3, -1 }, { 3, 1 },
    { 3, -3 }, { 3, 3 }, { 4, 0 }, { 4, 2 }, { 4, -2 }, { 4, 4 }, { 4, -4 }, { 5, 1 },
    { 5, -1 }, { 5, 3 }, { 5, -3 }, { 5, 5 }, { 5, -5 }, { 6, 0 },
};

static void fringe_table(void **state)
{
    int j, n, m, k, t;
    (void)state;
    for (j = 1; j <= 37; j++) {
        double maxp = 0;
        assert_int_equal(sg_zernike_nm(SG_ZERNIKE_FRINGE, j, &n, &m), SG_OK);
        assert_int_equal(m, fringe[j - 1].m);
        for (k = 0; k < 13; k++)
            if (fringe[j - 1].r[k] != 0.0)
                maxp = k;
        assert_int_equal(n, (int)maxp);
        /* The values at points all over the pupil. */
        for (t = 0; t < 25; t++) {
            double rho = (t % 5 + 0.5) / 5.0, th = 0.7 + 1.3 * (t / 5), r = 0.0, v;
            for (k = 12; k >= 0; k--)
                r = r * rho + fringe[j - 1].r[k];
            v = r * (m > 0 ? cos(m * th) : m < 0 ? sin(-m * th) : 1.0);
            if (fabs(sg_zernike_eval(SG_ZERNIKE_FRINGE, j, rho * cos(th), rho * sin(th)) - v) >
                1e-12)
                fail_msg("Fringe Z%d at rho %g theta %g: %.17g, published %.17g", j, rho, th,
                         sg_zernike_eval(SG_ZERNIKE_FRINGE, j, rho * cos(th), rho * sin(th)),
                         v);
        }
    }
    assert_int_equal(sg_zernike_nm(SG_ZERNIKE_FRINGE, 38, &n, &m), SG_ERANGE);
    assert_int_equal(sg_zernike_nm(SG_ZERNIKE_FRINGE, 0, &n, &m), SG_ERANGE);
    assert_true(isnan(sg_zernike_eval(SG_ZERNIKE_FRINGE, 38, 0.1, 0.1)));
}

static void noll_table(void **state)
{
    int j, n, m;
    (void)state;
    for (j = 1; j <= 22; j++) {
        assert_int_equal(sg_zernike_nm(SG_ZERNIKE_STANDARD, j, &n, &m), SG_OK);
        if (n != noll[j - 1][0] || m != noll[j - 1][1])
            fail_msg("Noll j = %d: n %d m %d, published n %d m %d", j, n, m, noll[j - 1][0],
                     noll[j - 1][1]);
    }
    /* Two values from Noll's table written out: Z4 = sqrt3 (2 rho^2 - 1),
     * Z11 = sqrt5 (6 rho^4 - 6 rho^2 + 1). */
    assert_true(fabs(sg_zernike_eval(SG_ZERNIKE_STANDARD, 4, 0.3, 0.4) -
                     sqrt(3.0) * (2 * 0.25 - 1)) < 1e-15);
    assert_true(fabs(sg_zernike_eval(SG_ZERNIKE_STANDARD, 11, 0.3, 0.4) -
                     sqrt(5.0) * (6 * 0.0625 - 6 * 0.25 + 1)) < 1e-14);
    assert_int_equal(sg_zernike_nm(SG_ZERNIKE_STANDARD, 232, &n, &m), SG_ERANGE);
}

/* Gauss-Legendre nodes and weights on [0, 1], by Newton on P_N. */
static void gauss(int N, double *x, double *w)
{
    int i, k;
    for (i = 0; i < N; i++) {
        double z = cos(M_PI * (i + 0.75) / (N + 0.5)), p0, p1, dp;
        for (k = 0; k < 100; k++) {
            int l;
            double dz;
            p0 = 1.0;
            p1 = z;
            for (l = 2; l <= N; l++) {
                double p2 = ((2.0 * l - 1.0) * z * p1 - (l - 1.0) * p0) / l;
                p0 = p1;
                p1 = p2;
            }
            dp = N * (z * p1 - p0) / (z * z - 1.0);
            dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        x[i] = 0.5 * (1.0 + z);
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
}

/* (1/pi) times the integral over the disc of Zi Zj, exact for these
 * polynomials: Gauss-Legendre in rho (degree up to 2*14-1 with rho dr)
 * and the trapezoid rule in theta (exact below 2 * 30 cycles). */
static void orthogonality(sg_zernike_kind kind, int nt)
{
    enum { NR = 14, NT = 60 };
    double xr[NR], wr[NR], g[37][37];
    int a, b, i, k;
    memset(g, 0, sizeof g);
    gauss(NR, xr, wr);
    for (i = 0; i < NR; i++)
        for (k = 0; k < NT; k++) {
            double th = 2.0 * M_PI * k / NT, x = xr[i] * cos(th), y = xr[i] * sin(th);
            double z[37], wt = wr[i] * xr[i] * 2.0 / NT;
            for (a = 0; a < nt; a++)
                z[a] = sg_zernike_eval(kind, a + 1, x, y);
            for (a = 0; a < nt; a++)
                for (b = 0; b < nt; b++)
                    g[a][b] += wt * z[a] * z[b];
        }
    for (a = 0; a < nt; a++)
        for (b = 0; b < nt; b++) {
            int n, m;
            double want = 0.0;
            assert_int_equal(sg_zernike_nm(kind, a + 1, &n, &m), SG_OK);
            if (a == b)
                want = kind == SG_ZERNIKE_STANDARD ? 1.0
                                                   : (m == 0 ? 1.0 : 0.5) / (n + 1.0);
            if (fabs(g[a][b] - want) > 1e-12)
                fail_msg("%s <Z%d, Z%d> = %.17g, expected %g",
                         kind == SG_ZERNIKE_STANDARD ? "Standard" : "Fringe", a + 1, b + 1,
                         g[a][b], want);
        }
}

static void orthogonal(void **state)
{
    (void)state;
    orthogonality(SG_ZERNIKE_FRINGE, 37);
    orthogonality(SG_ZERNIKE_STANDARD, 37);
}

/* Points spread over the disc by a fixed linear congruential sequence. */
static size_t disc_points(size_t n, double *x, double *y)
{
    unsigned long long s = 12345;
    size_t k = 0;
    while (k < n) {
        double u, v;
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        u = (double)(s >> 11) / 9007199254740992.0 * 2.0 - 1.0;
        s = s * 6364136223846793005ULL + 1442695040888963407ULL;
        v = (double)(s >> 11) / 9007199254740992.0 * 2.0 - 1.0;
        if (u * u + v * v <= 1.0) {
            x[k] = u;
            y[k] = v;
            k++;
        }
    }
    return k;
}

static void fit_case(sg_zernike_kind kind, int nt)
{
    enum { N = 3000 };
    double *x = test_malloc(N * sizeof *x), *y = test_malloc(N * sizeof *y),
           *w = test_malloc(N * sizeof *w), c[37], got[37], rms = -1, worst = 0;
    sg_diag d;
    int j;
    size_t p;
    disc_points(N, x, y);
    for (j = 0; j < nt; j++)
        c[j] = 0.37 * sin(1.0 + 2.3 * j) / (1.0 + 0.1 * j);
    for (p = 0; p < N; p++) {
        w[p] = 0.0;
        for (j = 0; j < nt; j++)
            w[p] += c[j] * sg_zernike_eval(kind, j + 1, x[p], y[p]);
    }
    sg_diag_clear(&d);
    assert_int_equal(sg_zernike_fit(kind, nt, N, x, y, w, got, &rms, &d), SG_OK);
    for (j = 0; j < nt; j++)
        worst = fmax(worst, fabs(got[j] - c[j]));
    print_message("# %s %d terms: worst coefficient error %.3g, residual RMS %.3g\n",
                  kind == SG_ZERNIKE_STANDARD ? "Standard" : "Fringe", nt, worst, rms);
    assert_true(worst < 1e-12);
    assert_true(rms >= 0.0 && rms < 1e-13);
    test_free(x);
    test_free(y);
    test_free(w);
}

static void fit(void **state)
{
    (void)state;
    fit_case(SG_ZERNIKE_FRINGE, 37);
    fit_case(SG_ZERNIKE_STANDARD, 37);
    fit_case(SG_ZERNIKE_FRINGE, 9);
    fit_case(SG_ZERNIKE_STANDARD, 22);
}

/* The residual of a fit that leaves a term out: Z9 (Fringe spherical)
 * plus piston and tilt on rings symmetric in theta, fitted by Z1..Z3,
 * leaves Z9 less its mean over the sample. */
static void fit_residual(void **state)
{
    enum { NR = 10, NT = 24 };
    double xr[NR], wr[NR], x[NR * NT], y[NR * NT], w[NR * NT], c[4], rms, pv;
    int i, k;
    sg_diag d;
    (void)state;
    gauss(NR, xr, wr);
    for (i = 0; i < NR; i++)
        for (k = 0; k < NT; k++) {
            double th = 2.0 * M_PI * (k + 0.5) / NT;
            x[i * NT + k] = xr[i] * cos(th);
            y[i * NT + k] = xr[i] * sin(th);
            w[i * NT + k] = sg_zernike_eval(SG_ZERNIKE_FRINGE, 9, x[i * NT + k],
                                            y[i * NT + k]) +
                            2.0 + 0.5 * x[i * NT + k] - 0.25 * y[i * NT + k];
        }
    sg_diag_clear(&d);
    assert_int_equal(sg_zernike_fit(SG_ZERNIKE_FRINGE, 3, NR * NT, x, y, w, c, &rms, &d),
                     SG_OK);
    /* Rings symmetric in theta: tilt is found exactly; piston is 2 plus
     * the mean of Z9 over the sample. */
    {
        double mean = 0, ss = 0, lo = INFINITY, hi = -INFINITY;
        for (i = 0; i < NR * NT; i++)
            mean += sg_zernike_eval(SG_ZERNIKE_FRINGE, 9, x[i], y[i]);
        mean /= NR * NT;
        for (i = 0; i < NR * NT; i++) {
            double r = sg_zernike_eval(SG_ZERNIKE_FRINGE, 9, x[i], y[i]) - mean;
            ss += r * r;
            lo = fmin(lo, r);
            hi = fmax(hi, r);
        }
        assert_true(fabs(c[0] - (2.0 + mean)) < 1e-13);
        assert_true(fabs(c[1] - 0.5) < 1e-13 && fabs(c[2] + 0.25) < 1e-13);
        assert_true(fabs(rms - sqrt(ss / (NR * NT))) < 1e-13);
        /* The statistics with piston and tilt removed are the same. */
        assert_int_equal(sg_wavefront_stats(NR * NT, x, y, w, 1, &rms, &pv, &d), SG_OK);
        assert_true(fabs(rms - sqrt(ss / (NR * NT))) < 1e-13);
        assert_true(fabs(pv - (hi - lo)) < 1e-13);
        /* Piston alone leaves the tilt in (orthogonal to Z9 on these rings). */
        assert_int_equal(sg_wavefront_stats(NR * NT, x, y, w, 0, &rms, &pv, &d), SG_OK);
        for (i = 0; i < NR * NT; i++)
            ss += (0.5 * x[i] - 0.25 * y[i]) * (0.5 * x[i] - 0.25 * y[i]);
        assert_true(fabs(rms - sqrt(ss / (NR * NT))) < 1e-13);
    }
}

static void bad_input(void **state)
{
    double x[3] = { 0.1, 2.0, 0.3 }, y[3] = { 0, 0, 0 }, w[3] = { 1, 2, 3 }, c[3], rms, pv;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_zernike_fit(SG_ZERNIKE_FRINGE, 3, 3, x, y, w, c, &rms, &d),
                     SG_ERANGE);
    assert_non_null(strstr(d.msg, "point 2"));
    sg_diag_clear(&d);
    assert_int_equal(sg_zernike_fit(SG_ZERNIKE_FRINGE, 38, 3, x, y, w, c, &rms, &d),
                     SG_ERANGE);
    /* Points on one line cannot give y tilt. */
    x[1] = 0.2;
    sg_diag_clear(&d);
    assert_int_equal(sg_zernike_fit(SG_ZERNIKE_FRINGE, 3, 3, x, y, w, c, &rms, &d),
                     SG_ENONPHYS);
    sg_diag_clear(&d);
    assert_int_equal(sg_wavefront_stats(3, x, y, w, 1, &rms, &pv, &d), SG_ENONPHYS);
    w[2] = NAN;
    sg_diag_clear(&d);
    assert_int_equal(sg_wavefront_stats(3, x, y, w, 0, &rms, &pv, &d), SG_ERANGE);
}

/* ---- the wavefront map from an OPD function ------------------------------ */

typedef struct synth {
    double cut; /* rays with px above this fail */
} synth;

/* 0.3 + 0.2 px - 0.1 py + 0.05 Z9 - 0.02 Z5 (Fringe), in waves. */
static double synth_w(double px, double py)
{
    return 0.3 + 0.2 * px - 0.1 * py +
           0.05 * (6 * pow(px * px + py * py, 2) - 6 * (px * px + py * py) + 1) -
           0.02 * (px * px - py * py);
}

static int synth_opd(void *ctx, double px, double py, double *w)
{
    const synth *s = ctx;
    if (px > s->cut)
        return SG_EVIGNETTED;
    *w = synth_w(px, py);
    return SG_OK;
}

static void wavefront_map(void **state)
{
    synth s = { 2.0 };
    sg_wavefront w;
    sg_diag d;
    double mean = 0, ss = 0, sc = 0, lo = INFINITY, hi = -INFINITY;
    size_t cnt = 0;
    int i, j, g = 33;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_wavefront_compute(synth_opd, &s, g, SG_ZERNIKE_FRINGE, 37, &w, &d),
                     SG_OK);
    /* Direct sums over the same grid: the grid is symmetric, so the even
     * part has no tilt and the piston is its mean. */
    for (j = 0; j < g; j++)
        for (i = 0; i < g; i++) {
            double px = -1.0 + 2.0 * i / (g - 1), py = -1.0 + 2.0 * j / (g - 1);
            if (px * px + py * py > 1.0)
                continue;
            mean += synth_w(px, py) - 0.2 * px + 0.1 * py;
            cnt++;
        }
    mean /= cnt;
    for (j = 0; j < g; j++)
        for (i = 0; i < g; i++) {
            double px = -1.0 + 2.0 * i / (g - 1), py = -1.0 + 2.0 * j / (g - 1), r;
            if (px * px + py * py > 1.0)
                continue;
            r = synth_w(px, py) - 0.2 * px + 0.1 * py - mean;
            ss += r * r;
            sc += (r + 0.2 * px - 0.1 * py) * (r + 0.2 * px - 0.1 * py);
            lo = fmin(lo, r);
            hi = fmax(hi, r);
        }
    assert_int_equal(w.nvalid, cnt);
    assert_true(fabs(w.rms_centroid - sqrt(ss / cnt)) < 1e-13);
    assert_true(fabs(w.pv_centroid - (hi - lo)) < 1e-13);
    assert_true(fabs(w.rms_chief - sqrt(sc / cnt)) < 1e-13);
    assert_true(fabs(w.coef[1] - 0.2) < 1e-12 && fabs(w.coef[2] + 0.1) < 1e-12);
    assert_true(fabs(w.coef[8] - 0.05) < 1e-12 && fabs(w.coef[4] + 0.02) < 1e-12);
    assert_true(fabs(w.coef[0] - 0.3) < 1e-12 && fabs(w.coef[3]) < 1e-12);
    assert_true(w.fit_rms < 1e-13);
    sg_wavefront_free(&w);

    /* Failed rays are left out of the map and the statistics. */
    s.cut = 0.5;
    assert_int_equal(sg_wavefront_compute(synth_opd, &s, g, SG_ZERNIKE_STANDARD, 15, &w, &d),
                     SG_OK);
    for (j = 0, cnt = 0; j < g; j++)
        for (i = 0; i < g; i++) {
            double px = -1.0 + 2.0 * i / (g - 1), py = -1.0 + 2.0 * j / (g - 1);
            int in = px * px + py * py <= 1.0 && px <= 0.5;
            cnt += in;
            assert_int_equal(w.valid[(size_t)j * g + i], in);
        }
    assert_int_equal(w.nvalid, cnt);
    sg_wavefront_free(&w);
    sg_diag_clear(&d);
    assert_int_equal(sg_wavefront_compute(synth_opd, &s, 2, SG_ZERNIKE_FRINGE, 37, &w, &d),
                     SG_ERANGE);
    sg_diag_clear(&d);
    assert_int_equal(sg_wavefront_compute(synth_opd, &s, 9, SG_ZERNIKE_STANDARD, 38, &w, &d),
                     SG_ERANGE);
}

/* The coefficients' error bounds on a map built from known coefficients
 * plus data errors of at most e (a deterministic sequence in [-e, e]):
 * every fitted coefficient lies within its bound of the true one, and the
 * bound is a few e, not a vacuous one.  Exact data (e = 0) get the fit's
 * rounding and the basis values' alone, below 1e-9 waves
 * (worst-case bounds: the errors themselves are near 1e-16). */
static void coef_bounds(void **state)
{
    static const double truth[8] = { 0.3, 0.0, 0.0, -0.02, 0.0, 0.0, 0.0, 0.0 };
    const int g = 257, nt = 37;
    double *map = malloc((size_t)g * g * sizeof *map), coef[37], bound[37], rms;
    unsigned char *valid = calloc((size_t)g * g, 1);
    double es[2] = { 0.0, 1e-9 };
    unsigned long long seed = 12345;
    size_t n = 0;
    int i, j, t, k;
    sg_diag d;
    (void)state;
    assert_non_null(map);
    assert_non_null(valid);
    for (k = 0; k < 2; k++) {
        double e = es[k];
        n = 0;
        for (j = 0; j < g; j++)
            for (i = 0; i < g; i++) {
                double px = -1.0 + 2.0 * i / (g - 1), py = -1.0 + 2.0 * j / (g - 1), r2, v, u;
                size_t q = (size_t)j * g + i;
                r2 = px * px + py * py;
                if (r2 > 1.0)
                    continue;
                /* Z1 = 1, Z4 = 2 r^2 - 1 (Fringe), and Z9 = 6 r^4 - 6 r^2 + 1,
                 * written out here, not through the library. */
                v = truth[0] + truth[3] * (2.0 * r2 - 1.0) +
                    0.05 * (6.0 * r2 * r2 - 6.0 * r2 + 1.0);
                seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
                u = (double)(seed >> 11) * 0x1p-53 * 2.0 - 1.0;
                map[q] = v + e * u;
                valid[q] = 1;
                n++;
            }
        sg_diag_clear(&d);
        assert_int_equal(sg_zernike_fit_map(SG_ZERNIKE_FRINGE, nt, g, map, valid, n, e, coef,
                                            bound, &rms, &d),
                         SG_OK);
        for (t = 0; t < nt; t++) {
            double want = t == 8 ? 0.05 : t < 8 ? truth[t] : 0.0;
            if (!(fabs(coef[t] - want) <= bound[t]))
                fail_msg("e %g: Z%d = %.17g, want %.17g within %g", e, t + 1, coef[t], want,
                         bound[t]);
            if (e > 0.0 ? !(bound[t] < 20.0 * e) : !(bound[t] < 1e-9))
                fail_msg("e %g: Z%d's bound %g is vacuous", e, t + 1, bound[t]);
        }
    }
    free(map);
    free(valid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(fringe_table), cmocka_unit_test(noll_table),
        cmocka_unit_test(orthogonal),   cmocka_unit_test(fit),
        cmocka_unit_test(fit_residual), cmocka_unit_test(bad_input),
        cmocka_unit_test(wavefront_map), cmocka_unit_test(coef_bounds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
