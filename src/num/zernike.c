/*
 * zernike.c - Zernike polynomials on the unit pupil: Fringe (the 37 terms
 * of the University of Arizona ordering that Zemax calls Fringe, not
 * normalized) and Standard (Noll's ordering and normalization, which
 * Zemax calls Standard); evaluation, least-squares fits and the RMS and
 * P-V of a wavefront with piston and tilt removed.
 *
 * The angle is measured from the x axis: Z2 = rho cos(theta) is x tilt in
 * both sets (Noll: Z2 = 2 rho cos(theta)).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "num.h"
#include "dd.h"

int sg_zernike_nm(sg_zernike_kind kind, int j, int *n, int *m)
{
    int k, mm, idx = 1;
    if (j < 1)
        return SG_ERANGE;
    if (kind == SG_ZERNIKE_FRINGE) {
        if (j > SG_ZERNIKE_FRINGE_MAX)
            return SG_ERANGE;
        if (j == 37) {
            *n = 12;
            *m = 0;
            return SG_OK;
        }
        /* Groups of equal (n + |m|) / 2, |m| descending, cosine before sine. */
        for (k = 0;; k++)
            for (mm = k; mm >= 0; mm--) {
                int nn = 2 * k - mm, s;
                for (s = 0; s < (mm ? 2 : 1); s++, idx++)
                    if (idx == j) {
                        *n = nn;
                        *m = s ? -mm : mm;
                        return SG_OK;
                    }
            }
    }
    if (kind != SG_ZERNIKE_STANDARD || j > SG_ZERNIKE_STANDARD_MAX)
        return SG_ERANGE;
    /* Noll: rows of equal n, |m| ascending; of a pair, the even j is the
     * cosine (m > 0) and the odd j the sine. */
    for (k = 0;; k++)
        for (mm = k % 2; mm <= k; mm += 2) {
            if (mm == 0) {
                if (idx == j) {
                    *n = k;
                    *m = 0;
                    return SG_OK;
                }
                idx++;
            } else {
                if (idx == j || idx + 1 == j) {
                    *n = k;
                    *m = (j % 2 == 0) ? mm : -mm;
                    return SG_OK;
                }
                idx += 2;
            }
        }
}

/* One term as a polynomial: Z = norm * Q(rho^2) * Re or Im of (x + iy)^|m|,
 * where R_n^|m|(rho) = rho^|m| Q(rho^2).  No angle, power or factorial is
 * evaluated per point, so a fit over millions of points stays cheap. */
typedef struct zterm {
    int am, sine, deg;      /* |m|; 1 for m < 0; degree of Q */
    double norm;
    double q[11];           /* Q's coefficients, highest power first */
    double eps;             /* bound on the rounding of one evaluation */
} zterm;

static int zterm_init(sg_zernike_kind kind, int j, zterm *t)
{
    int n, m, s;
    if (sg_zernike_nm(kind, j, &n, &m) != SG_OK)
        return SG_ERANGE;
    t->am = m < 0 ? -m : m;
    t->sine = m < 0;
    t->deg = (n - t->am) / 2;
    /* The explicit sum's integer coefficients; n <= 20 keeps the
     * factorials' ratio within a rounding of an integer below 2^53. */
    for (s = 0; s <= t->deg; s++) {
        double c = round(tgamma(n - s + 1.0) /
                         (tgamma(s + 1.0) * tgamma((n + t->am) / 2 - s + 1.0) *
                          tgamma((n - t->am) / 2 - s + 1.0)));
        t->q[s] = (s & 1) ? -c : c;
    }
    t->norm = kind == SG_ZERNIKE_STANDARD ? (m == 0 ? sqrt(n + 1.0) : sqrt(2.0 * (n + 1.0)))
                                          : 1.0;
    /* Horner on rho^2 <= 1 errs by at most gamma_2deg sum |q|; the
     * complex power by gamma_(4|m|) of |x + iy|^|m| <= 1; the products
     * by two more roundings (Higham, Accuracy and Stability, 5.1, 3.5). */
    {
        double qa = 0.0, k = 2.0 * t->deg + 4.0 * t->am + 4.0;
        for (s = 0; s <= t->deg; s++)
            qa += fabs(t->q[s]);
        t->eps = t->norm * qa * (k * 0x1p-53 / (1.0 - k * 0x1p-53)) * (1.0 + 0x1p-50);
    }
    return SG_OK;
}

/* (x + iy)^k for k = 0..kmax into re[], im[]. */
static void cpowers(double x, double y, int kmax, double *re, double *im)
{
    int k;
    re[0] = 1.0;
    im[0] = 0.0;
    for (k = 1; k <= kmax; k++) {
        re[k] = re[k - 1] * x - im[k - 1] * y;
        im[k] = re[k - 1] * y + im[k - 1] * x;
    }
}

static double zterm_eval(const zterm *t, double rho2, const double *re, const double *im)
{
    double v = t->q[0];
    int s;
    for (s = 1; s <= t->deg; s++)
        v = v * rho2 + t->q[s];
    return t->norm * v * (t->sine ? im[t->am] : re[t->am]);
}

#define ZMAX_M 20

double sg_zernike_eval(sg_zernike_kind kind, int j, double x, double y)
{
    zterm t;
    double re[ZMAX_M + 1], im[ZMAX_M + 1];
    if (zterm_init(kind, j, &t) != SG_OK)
        return NAN;
    cpowers(x, y, t.am, re, im);
    return zterm_eval(&t, x * x + y * y, re, im);
}

/* The first nterms terms' records, and the largest |m| among them. */
static int zterms_init(sg_zernike_kind kind, int nterms, zterm *t)
{
    int i, mmax = 0;
    for (i = 0; i < nterms; i++) {
        zterm_init(kind, i + 1, &t[i]);
        mmax = t[i].am > mmax ? t[i].am : mmax;
    }
    return mmax;
}

static void zterms_eval(const zterm *t, int nterms, int mmax, double x, double y, double *z)
{
    double re[ZMAX_M + 1], im[ZMAX_M + 1], rho2 = x * x + y * y;
    int i;
    cpowers(x, y, mmax, re, im);
    for (i = 0; i < nterms; i++)
        z[i] = zterm_eval(&t[i], rho2, re, im);
}

/* Solves the symmetric positive definite k x k system a c = b by
 * Cholesky, in place; SG_ENONPHYS when a is singular to working precision. */
/* Solves with the factor that cholesky_solve left in a's lower triangle. */
static void cholesky_resolve(const double *a, double *b, int k)
{
    int i, l;
    for (i = 0; i < k; i++) {
        double s = b[i];
        for (l = 0; l < i; l++)
            s -= a[i * k + l] * b[l];
        b[i] = s / a[i * k + i];
    }
    for (i = k - 1; i >= 0; i--) {
        double s = b[i];
        for (l = i + 1; l < k; l++)
            s -= a[l * k + i] * b[l];
        b[i] = s / a[i * k + i];
    }
}

static int cholesky_solve(double *a, double *b, int k)
{
    int i, j, l;
    for (j = 0; j < k; j++) {
        double d = a[j * k + j];
        for (l = 0; l < j; l++)
            d -= a[j * k + l] * a[j * k + l];
        if (!(d > 1e-13 * a[j * k + j]) || !(d > 0.0))
            return SG_ENONPHYS;
        d = sqrt(d);
        a[j * k + j] = d;
        for (i = j + 1; i < k; i++) {
            double s = a[i * k + j];
            for (l = 0; l < j; l++)
                s -= a[i * k + l] * a[j * k + l];
            a[i * k + j] = s / d;
        }
    }
    cholesky_resolve(a, b, k);
    return SG_OK;
}

/* Points for a fit: arrays of x, y and w, or a wavefront map (its valid
 * cells at the grid's pupil coordinates), so a map is fitted without
 * copies of its points. */
typedef struct zpts {
    size_t n;
    const double *x, *y, *w;
    int grid;
    const double *map;
    const unsigned char *valid;
} zpts;

/* The next point from *cur; 0 at the end. */
static int zpts_next(const zpts *P, size_t *cur, double *x, double *y, double *w)
{
    if (!P->map) {
        if (*cur >= P->n)
            return 0;
        *x = P->x[*cur];
        *y = P->y[*cur];
        *w = P->w[*cur];
        ++*cur;
        return 1;
    }
    for (; *cur < (size_t)P->grid * (size_t)P->grid; ++*cur)
        if (P->valid[*cur]) {
            size_t k = (*cur)++;
            int i = (int)(k % (size_t)P->grid), j = (int)(k / (size_t)P->grid);
            /* The same coordinates as the map's rays (sg_wavefront_trace). */
            *x = -1.0 + 2.0 * i / (P->grid - 1);
            *y = -1.0 + 2.0 * j / (P->grid - 1);
            *w = P->map[k];
            return 1;
        }
    return 0;
}

/* Points a block of the normal equations' sums takes. */
#define ZB 64

/* Bounds on the coefficients' errors, to first order in the roundings.
 * Data wrong by at most e at each of the N points move c_j by at most
 * e sqrt(N G_jj), G = (A^T A)^-1, by Cauchy-Schwarz on the row of G A^T.
 * The normal equations A c = b are off by dA and db: each block sum
 * carries gamma_(ZB/4+3) of its terms' magnitudes and the double-double
 * accumulation of the blocks almost nothing, and each basis value z_i
 * errs by at most eps_i; sums of |z_i z_k|, |z_i| and |z_i w| are bounded
 * by Cauchy-Schwarz from A's diagonal, N and sum w^2.  Then
 * |dc| <= |G| (|dA| |c| + |db|).  The factor 2 covers the Cholesky
 * solve's own roundings on the small, well-conditioned system. */
static void fit_bounds(const double *chol, const double *diag, const zterm *t,
                       const double *c, int k, size_t n, double e, double sw2, double *g,
                       double *out)
{
    double kb = ZB / 4 + 3.0, gam = kb * 0x1p-53 / (1.0 - kb * 0x1p-53) +
                                     ((double)n / ZB + 2.0) * 4.0 * 0x1p-106;
    double r[SG_ZERNIKE_STANDARD_MAX], sc = 0.0, sn = sqrt((double)n), sw = sqrt(sw2);
    double se = 0.0;
    int i, j;
    for (i = 0; i < k; i++) {
        sc += sqrt(diag[i]) * fabs(c[i]);
        se += t[i].eps * fabs(c[i]);
    }
    for (i = 0; i < k; i++) {
        double ai = sqrt(diag[i]);
        r[i] = gam * ai * (sc + sw) + sn * ai * se + sn * t[i].eps * (sc + sw);
    }
    for (j = 0; j < k; j++) {
        double s = 0.0;
        /* Row j of G, by a solve against the unit vector. */
        memset(g, 0, (size_t)k * sizeof *g);
        g[j] = 1.0;
        cholesky_resolve(chol, g, k);
        for (i = 0; i < k; i++)
            s += fabs(g[i]) * r[i];
        out[j] = 2.0 * (e * sqrt((double)n * fabs(g[j])) + s);
    }
}

static int zernike_fit(sg_zernike_kind kind, int nterms, const zpts *P, double data_err,
                       double *coef, double *coef_bound, double *rms_resid, sg_diag *d)
{
    double *a, *z, *b, ss = 0.0, sw2 = 0.0, x, y, w;
    double diag[SG_ZERNIKE_STANDARD_MAX], wb[ZB];
    double (*zt)[ZB];
    dd *A, *B;
    zterm t[SG_ZERNIKE_STANDARD_MAX];
    size_t cur = 0, p = 0;
    int i, j, rc, maxj, mmax;
    maxj = kind == SG_ZERNIKE_FRINGE ? SG_ZERNIKE_FRINGE_MAX : SG_ZERNIKE_STANDARD_MAX;
    if (nterms < 1 || nterms > maxj)
        return sg_diag_set(d, SG_ERANGE, "zernike: %d terms; from 1 to %d are allowed", nterms,
                           maxj);
    if (P->n < (size_t)nterms)
        return sg_diag_set(d, SG_ERANGE, "zernike: %zu points cannot fit %d terms", P->n,
                           nterms);
    mmax = zterms_init(kind, nterms, t);
    a = calloc((size_t)nterms * (size_t)nterms + 2 * (size_t)nterms, sizeof *a);
    if (!a)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    z = a + (size_t)nterms * nterms;
    b = z + nterms;
    zt = malloc((size_t)nterms * sizeof *zt);
    A = calloc((size_t)nterms * (size_t)nterms + (size_t)nterms, sizeof *A);
    if (!zt || !A) {
        free(a);
        free(zt);
        free(A);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    B = A + (size_t)nterms * nterms;
    /* The normal equations, ZB points at a time: memory does not grow
     * with the number of points, and each block's sums are dot products
     * of contiguous rows, which the compiler vectorizes. */
    for (;;) {
        int nb = 0;
        while (nb < ZB && zpts_next(P, &cur, &x, &y, &w)) {
            p++;
            if (!isfinite(x) || !isfinite(y) || !isfinite(w) || x * x + y * y > 1.0 + 1e-12) {
                free(a);
                free(zt);
                free(A);
                return sg_diag_set(d, SG_ERANGE,
                                   "zernike: point %zu (%g, %g, %g) is not a finite value "
                                   "inside the unit pupil", p, x, y, w);
            }
            zterms_eval(t, nterms, mmax, x, y, z);
            for (i = 0; i < nterms; i++)
                zt[i][nb] = z[i];
            wb[nb++] = w;
            sw2 += w * w;
        }
        if (!nb)
            break;
        for (i = 0; i < nterms; i++) {
            double sb = 0.0;
            int q;
            for (q = 0; q < nb; q++)
                sb += zt[i][q] * wb[q];
            B[i] = dd_add(B[i], dd_from(sb));
            for (j = 0; j <= i; j++) {
                /* Four chains, so the sums overlap in the pipeline. */
                double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
                for (q = 0; q + 4 <= nb; q += 4) {
                    s0 += zt[i][q] * zt[j][q];
                    s1 += zt[i][q + 1] * zt[j][q + 1];
                    s2 += zt[i][q + 2] * zt[j][q + 2];
                    s3 += zt[i][q + 3] * zt[j][q + 3];
                }
                for (; q < nb; q++)
                    s0 += zt[i][q] * zt[j][q];
                A[(size_t)i * nterms + j] =
                    dd_add(A[(size_t)i * nterms + j], dd_from((s0 + s1) + (s2 + s3)));
            }
        }
    }
    for (i = 0; i < nterms; i++) {
        b[i] = B[i].hi + B[i].lo;
        for (j = 0; j <= i; j++)
            a[i * nterms + j] = A[(size_t)i * nterms + j].hi + A[(size_t)i * nterms + j].lo;
    }
    free(A);
    for (i = 0; i < nterms; i++)
        for (j = i + 1; j < nterms; j++)
            a[i * nterms + j] = a[j * nterms + i];
    for (i = 0; i < nterms; i++)
        diag[i] = a[i * nterms + i];
    rc = cholesky_solve(a, b, nterms);
    if (rc != SG_OK) {
        free(a);
        free(zt);
        return sg_diag_set(d, rc, "zernike: the %zu points do not determine %d terms "
                                  "(too few, or all on a few rings or lines)", P->n, nterms);
    }
    memcpy(coef, b, (size_t)nterms * sizeof *coef);
    if (coef_bound)
        fit_bounds(a, diag, t, coef, nterms, P->n, data_err, sw2, z, coef_bound);
    /* The residual from a second pass: subtracting sums would lose it. */
    cur = 0;
    while (zpts_next(P, &cur, &x, &y, &w)) {
        double r = w;
        zterms_eval(t, nterms, mmax, x, y, z);
        for (i = 0; i < nterms; i++)
            r -= coef[i] * z[i];
        ss += r * r;
    }
    if (rms_resid)
        *rms_resid = sqrt(ss / (double)P->n);
    free(a);
    free(zt);
    return SG_OK;
}

int sg_zernike_fit(sg_zernike_kind kind, int nterms, size_t npts, const double *x,
                   const double *y, const double *w, double *coef, double *rms_resid,
                   sg_diag *d)
{
    zpts P = { npts, x, y, w, 0, NULL, NULL };
    return zernike_fit(kind, nterms, &P, 0.0, coef, NULL, rms_resid, d);
}

int sg_zernike_fit_map(sg_zernike_kind kind, int nterms, int grid, const double *map,
                       const unsigned char *valid, size_t nvalid, double data_err,
                       double *coef, double *coef_bound, double *rms_resid, sg_diag *d)
{
    zpts P = { nvalid, NULL, NULL, NULL, grid, map, valid };
    return zernike_fit(kind, nterms, &P, data_err, coef, coef_bound, rms_resid, d);
}

static int wavefront_stats(const zpts *P, int remove_tilt, double *rms, double *pv, sg_diag *d)
{
    double a[9] = { 0 }, b[3] = { 0 }, ss = 0.0, lo = INFINITY, hi = -INFINITY, x, y, w;
    size_t cur = 0, p = 0;
    int k = remove_tilt ? 3 : 1, i, j;
    if (P->n < (size_t)k)
        return sg_diag_set(d, SG_ERANGE, "wavefront: %zu points are too few", P->n);
    while (zpts_next(P, &cur, &x, &y, &w)) {
        double f[3] = { 1.0, x, y };
        p++;
        if (!isfinite(x) || !isfinite(y) || !isfinite(w))
            return sg_diag_set(d, SG_ERANGE, "wavefront: point %zu is not finite", p);
        for (i = 0; i < k; i++) {
            b[i] += f[i] * w;
            for (j = 0; j < k; j++)
                a[i * k + j] += f[i] * f[j];
        }
    }
    if (cholesky_solve(a, b, k) != SG_OK)
        return sg_diag_set(d, SG_ENONPHYS, "wavefront: the points lie on one line; tilt "
                                           "cannot be removed");
    cur = 0;
    while (zpts_next(P, &cur, &x, &y, &w)) {
        double r = w - b[0];
        if (remove_tilt)
            r -= b[1] * x + b[2] * y;
        ss += r * r;
        lo = r < lo ? r : lo;
        hi = r > hi ? r : hi;
    }
    *rms = sqrt(ss / (double)P->n);
    *pv = hi - lo;
    return SG_OK;
}

int sg_wavefront_stats(size_t npts, const double *x, const double *y, const double *w,
                       int remove_tilt, double *rms, double *pv, sg_diag *d)
{
    zpts P = { npts, x, y, w, 0, NULL, NULL };
    return wavefront_stats(&P, remove_tilt, rms, pv, d);
}

int sg_wavefront_stats_map(int grid, const double *map, const unsigned char *valid,
                           size_t nvalid, int remove_tilt, double *rms, double *pv, sg_diag *d)
{
    zpts P = { nvalid, NULL, NULL, NULL, grid, map, valid };
    return wavefront_stats(&P, remove_tilt, rms, pv, d);
}
