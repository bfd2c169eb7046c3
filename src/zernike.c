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

#include "sagitta.h"

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

/* R_n^|m|(rho) by its explicit sum (n is at most 12 for Fringe and small
 * for Standard's range, where the factorials are exact in double). */
static double radial(int n, int m, double rho)
{
    int s, am = m < 0 ? -m : m;
    double sum = 0.0;
    for (s = 0; s <= (n - am) / 2; s++) {
        double c = tgamma(n - s + 1.0) /
                   (tgamma(s + 1.0) * tgamma((n + am) / 2 - s + 1.0) *
                    tgamma((n - am) / 2 - s + 1.0));
        sum += ((s & 1) ? -c : c) * pow(rho, n - 2 * s);
    }
    return sum;
}

double sg_zernike_eval(sg_zernike_kind kind, int j, double x, double y)
{
    int n, m;
    double rho, th, v;
    if (sg_zernike_nm(kind, j, &n, &m) != SG_OK)
        return NAN;
    rho = hypot(x, y);
    th = atan2(y, x);
    v = radial(n, m, rho);
    if (m > 0)
        v *= cos(m * th);
    else if (m < 0)
        v *= sin(-m * th);
    if (kind == SG_ZERNIKE_STANDARD)
        v *= m == 0 ? sqrt(n + 1.0) : sqrt(2.0 * (n + 1.0));
    return v;
}

/* Solves the symmetric positive definite k x k system a c = b by
 * Cholesky, in place; SG_ENONPHYS when a is singular to working precision. */
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
    return SG_OK;
}

int sg_zernike_fit(sg_zernike_kind kind, int nterms, size_t npts, const double *x,
                   const double *y, const double *w, double *coef, double *rms_resid,
                   sg_diag *d)
{
    double *a, *z, *b, ss = 0.0;
    size_t p;
    int i, j, rc, maxj;
    maxj = kind == SG_ZERNIKE_FRINGE ? SG_ZERNIKE_FRINGE_MAX : SG_ZERNIKE_STANDARD_MAX;
    if (nterms < 1 || nterms > maxj)
        return sg_diag_set(d, SG_ERANGE, "zernike: %d terms; from 1 to %d are allowed", nterms,
                           maxj);
    if (npts < (size_t)nterms)
        return sg_diag_set(d, SG_ERANGE, "zernike: %zu points cannot fit %d terms", npts,
                           nterms);
    a = calloc((size_t)nterms * (size_t)nterms + 2 * (size_t)nterms, sizeof *a);
    if (!a)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    z = a + (size_t)nterms * nterms;
    b = z + nterms;
    /* The normal equations, one point at a time: memory does not grow
     * with the number of points. */
    for (p = 0; p < npts; p++) {
        if (!isfinite(x[p]) || !isfinite(y[p]) || !isfinite(w[p]) ||
            x[p] * x[p] + y[p] * y[p] > 1.0 + 1e-12) {
            free(a);
            return sg_diag_set(d, SG_ERANGE,
                               "zernike: point %zu (%g, %g, %g) is not a finite value "
                               "inside the unit pupil", p + 1, x[p], y[p], w[p]);
        }
        for (i = 0; i < nterms; i++)
            z[i] = sg_zernike_eval(kind, i + 1, x[p], y[p]);
        for (i = 0; i < nterms; i++) {
            b[i] += z[i] * w[p];
            for (j = 0; j <= i; j++)
                a[i * nterms + j] += z[i] * z[j];
        }
    }
    for (i = 0; i < nterms; i++)
        for (j = i + 1; j < nterms; j++)
            a[i * nterms + j] = a[j * nterms + i];
    rc = cholesky_solve(a, b, nterms);
    if (rc != SG_OK) {
        free(a);
        return sg_diag_set(d, rc, "zernike: the %zu points do not determine %d terms "
                                  "(too few, or all on a few rings or lines)", npts, nterms);
    }
    memcpy(coef, b, (size_t)nterms * sizeof *coef);
    /* The residual from a second pass: subtracting sums would lose it. */
    for (p = 0; p < npts; p++) {
        double r = w[p];
        for (i = 0; i < nterms; i++)
            r -= coef[i] * sg_zernike_eval(kind, i + 1, x[p], y[p]);
        ss += r * r;
    }
    if (rms_resid)
        *rms_resid = sqrt(ss / (double)npts);
    free(a);
    return SG_OK;
}

int sg_wavefront_stats(size_t npts, const double *x, const double *y, const double *w,
                       int remove_tilt, double *rms, double *pv, sg_diag *d)
{
    double a[9] = { 0 }, b[3] = { 0 }, ss = 0.0, lo = INFINITY, hi = -INFINITY;
    size_t p;
    int k = remove_tilt ? 3 : 1, i, j;
    if (npts < (size_t)k)
        return sg_diag_set(d, SG_ERANGE, "wavefront: %zu points are too few", npts);
    for (p = 0; p < npts; p++) {
        double f[3] = { 1.0, x[p], y[p] };
        if (!isfinite(x[p]) || !isfinite(y[p]) || !isfinite(w[p]))
            return sg_diag_set(d, SG_ERANGE, "wavefront: point %zu is not finite", p + 1);
        for (i = 0; i < k; i++) {
            b[i] += f[i] * w[p];
            for (j = 0; j < k; j++)
                a[i * k + j] += f[i] * f[j];
        }
    }
    if (cholesky_solve(a, b, k) != SG_OK)
        return sg_diag_set(d, SG_ENONPHYS, "wavefront: the points lie on one line; tilt "
                                           "cannot be removed");
    for (p = 0; p < npts; p++) {
        double r = w[p] - b[0];
        if (remove_tilt)
            r -= b[1] * x[p] + b[2] * y[p];
        ss += r * r;
        lo = r < lo ? r : lo;
        hi = r > hi ? r : hi;
    }
    *rms = sqrt(ss / (double)npts);
    *pv = hi - lo;
    return SG_OK;
}
