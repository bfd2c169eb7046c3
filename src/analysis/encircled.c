/*
 * encircled.c - encircled and ensquared energy of each field: diffraction
 * (from the FFT PSF of psf.c), geometric (from the rays of a spot
 * diagram), and the diffraction limit (the same pupil unaberrated).
 *
 * The FFT PSF on its M x M grid (M = 2N) is a trigonometric polynomial:
 * I(x) = sum_k C_k exp(i 2 pi nu_k . x), nu_k = k / T, with T = M times the
 * grid spacing the period, and C_k the pupil's discrete autocorrelation
 * (the OTF, the FFT of the PSF).  Its integral over a circle of radius r
 * is then exact: sum_k C_k r J1(2 pi r |nu_k|) / |nu_k| (pi r^2 at k = 0),
 * and over a square of half-width a, sum_k C_k (2a sinc(2a nu_x))
 * (2a sinc(2a nu_y)); divided by the period's energy C_0 T^2 it is the
 * fraction.  No pixel is cut by the circle's edge, so the curve is smooth
 * and reaches the Airy pattern's energy within the grid's sampling of the
 * pupil.  It holds for r up to T/2, half the PSF grid's width; beyond it
 * the periodic PSF's next copy would enter, and no value is given.
 */
#define _XOPEN_SOURCE 700 /* j1 */
#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <fftw3.h>

#include "analysis_int.h"

static const double EE_PI = 3.14159265358979323846;

/* Radii when none is asked for. */
#define EE_NPTS 101

void sg_ee_opts_init(sg_ee_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->field = -1;
    o->wave = -1;
    o->sampling = 64;
    o->kind = SG_EE_ENCIRCLED;
}

void sg_ee_free(sg_ee *e)
{
    if (!e)
        return;
    free(e->field);
    free(e->radius_um);
    free(e->diffraction);
    free(e->geometric);
    free(e->limit);
    memset(e, 0, sizeof *e);
}

/* The OTF of one pupil, C_k for k = (kx, ky) with kx, ky in 0 .. n - 1
 * (the other quadrants folded onto it: the PSF is real, so C_-k is the
 * conjugate of C_k, and the kernels are even in each axis), real parts,
 * normalized by C_0, into otf[ky * n + kx]. */
static int pupil_otf(const sg_pupil *p, int aberrated, double *otf, sg_diag *d)
{
    int n = p->n, m = 2 * n, i, j, rc;
    double *inten, c0;
    fftw_complex *c;
    fftw_plan plan;

    if ((rc = sg_pupil_intensity(p, aberrated, m, &inten, d)) != SG_OK)
        return rc;
    c = fftw_alloc_complex((size_t)m * (size_t)(m / 2 + 1));
    if (!c) {
        free(inten);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    plan = fftw_plan_dft_r2c_2d(m, m, inten, c, FFTW_ESTIMATE);
    if (!plan) {
        free(inten);
        fftw_free(c);
        return sg_diag_set(d, SG_ENOMEM, "FFTW could not plan a %d x %d transform", m, m);
    }
    fftw_execute(plan);
    fftw_destroy_plan(plan);
    c0 = creal(c[0]);
    /* The PSF's centre is index m/2 on each axis: (-1)^(kx + ky) moves the
     * transform's origin there.  Row ky of the r2c output holds columns
     * 0 .. m/2; -ky is row m - ky, and C(-kx, ky) = conj C(kx, -ky). */
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            double s = ((i + j) & 1) ? -1.0 : 1.0, v;
            size_t r1 = (size_t)j * (size_t)(m / 2 + 1) + (size_t)i;
            size_t r2 = (size_t)((m - j) % m) * (size_t)(m / 2 + 1) + (size_t)i;
            /* C(kx, ky) + C(-kx, -ky) + C(-kx, ky) + C(kx, -ky), real parts. */
            v = creal(c[r1]) + creal(c[r2]);
            v *= (i == 0 ? 1.0 : 2.0) / (j == 0 ? 2.0 : 1.0);
            otf[(size_t)j * (size_t)n + (size_t)i] = s * v / c0;
        }
    /* At kx = 0 the two row entries are the ky and -ky ones, summed once;
     * at ky = 0 they are one entry counted twice, halved above. */
    fftw_free(c);
    free(inten);
    return SG_OK;
}

/* sin(pi t) / (pi t). */
static double sinc_pi(double t)
{
    double u = EE_PI * t;
    return u == 0.0 ? 1.0 : sin(u) / u;
}

/* The fraction of energy within r (radius or half-width, um) of one
 * wavelength's two OTFs (aberrated a, unaberrated u), periods tx, ty (um),
 * into fa and fu. */
static void ee_at(const double *a, const double *u, int n, double tx, double ty, int kind,
                  double r, double *fa, double *fu)
{
    double sa = 0.0, su = 0.0, lim = (double)(n - 1) * (double)(n - 1);
    int i, j;
    for (j = 0; j < n; j++) {
        double ny = j / ty, ky = 2.0 * r * sinc_pi(2.0 * r * ny);
        for (i = 0; i < n; i++) {
            size_t q = (size_t)j * (size_t)n + (size_t)i;
            double nx = i / tx, k;
            /* The pupil's autocorrelation vanishes beyond n - 1 samples. */
            if ((double)i * i + (double)j * j > lim)
                break;
            if (kind == SG_EE_ENSQUARED)
                k = 2.0 * r * sinc_pi(2.0 * r * nx) * ky;
            else if (i == 0 && j == 0)
                k = EE_PI * r * r;
            else {
                double nu = hypot(nx, ny);
                k = r * j1(2.0 * EE_PI * r * nu) / nu;
            }
            sa += a[q] * k;
            su += u[q] * k;
        }
    }
    *fa = sa / (tx * ty);
    *fu = su / (tx * ty);
}

static int ee_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One field's geometric image: each wavelength's ray radii, sorted. */
typedef struct ee_geo {
    int nw;
    double *r[SG_MAX_WAVES];
    size_t n[SG_MAX_WAVES];
    double wt[SG_MAX_WAVES];
    double rmax;           /* the farthest ray, um */
} ee_geo;

static void ee_geo_free(ee_geo *g)
{
    int w;
    for (w = 0; w < g->nw; w++)
        free(g->r[w]);
    memset(g, 0, sizeof *g);
}

/* The rays of one field: a square pupil grid traced to the image
 * (sg_spot_compute), radius or half-width from the spot's reference, the
 * chief ray of the primary (or the one chosen) wavelength, in um. */
static int ee_geometric(const sg_system *sys, const sg_catalog *cat, const sg_ee_opts *o,
                        int field, int rays, ee_geo *g, sg_diag *d)
{
    sg_spot_opts so;
    sg_spot s;
    double um = sg_an_um_to_units(sys);
    int rc, w;

    memset(g, 0, sizeof *g);
    sg_spot_opts_init(&so);
    so.trace = o->trace;
    so.pattern = SG_PUPIL_SQUARE;
    so.density = rays;
    so.reference = SG_SPOT_REF_CHIEF;
    so.wave = o->wave;
    so.field = field;
    so.nthreads = o->nthreads;
    so.max_points = sg_pupil_count(SG_PUPIL_SQUARE, rays);
    if ((rc = sg_spot_compute(sys, cat, &so, &s, d)) != SG_OK)
        return rc;
    if (s.field[0].status != SG_OK) {
        rc = sg_diag_set(d, s.field[0].status, "encircled: field %d: the chief ray fails: %s",
                         field + 1, sg_strerror(s.field[0].status));
        goto done;
    }
    for (w = 0; w < s.nwave; w++) {
        const sg_spot_cell *c = &s.cell[w];
        double wt = s.nwave > 1 ? sys->wave[s.wave_index[w]].weight : 1.0, *rr;
        size_t k;
        if (wt <= 0.0 || c->status != SG_OK || c->npts == 0)
            continue;
        rr = malloc(c->npts * sizeof *rr);
        if (!rr) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto done;
        }
        for (k = 0; k < c->npts; k++) {
            double x = c->pts[k][0] / um, y = c->pts[k][1] / um;
            rr[k] = o->kind == SG_EE_ENSQUARED ? fmax(fabs(x), fabs(y)) : hypot(x, y);
        }
        qsort(rr, c->npts, sizeof *rr, ee_cmp);
        if (rr[c->npts - 1] > g->rmax)
            g->rmax = rr[c->npts - 1];
        g->r[g->nw] = rr;
        g->n[g->nw] = c->npts;
        g->wt[g->nw] = wt;
        g->nw++;
    }
    if (g->nw == 0) {
        rc = sg_diag_set(d, SG_EMISS, "encircled: field %d: no ray reaches the image",
                         field + 1);
        goto done;
    }
    rc = SG_OK;
done:
    if (rc != SG_OK)
        ee_geo_free(g);
    sg_spot_free(&s);
    return rc;
}

/* Each wavelength's fraction of rays within each radius (which rise),
 * weighted by its weight. */
static void ee_geo_frac(const ee_geo *g, const double *radius, int npts, double *frac)
{
    double wsum = 0.0;
    int w, j;
    for (j = 0; j < npts; j++)
        frac[j] = 0.0;
    for (w = 0; w < g->nw; w++) {
        size_t lo = 0;
        for (j = 0; j < npts; j++) {
            while (lo < g->n[w] && g->r[w][lo] <= radius[j])
                lo++;
            frac[j] += g->wt[w] * (double)lo / (double)g->n[w];
        }
        wsum += g->wt[w];
    }
    for (j = 0; j < npts; j++)
        frac[j] /= wsum;
}

int sg_ee_compute(const sg_system *sys, const sg_catalog *cat, const sg_ee_opts *o,
                  sg_ee *out, sg_diag *d)
{
    int waves[SG_MAX_WAVES], fields[SG_MAX_FIELDS], nw, nf, w, f, rc, n, np, j, rays;
    double fnum, lmin = 0.0, lmax = 0.0, rlim, rmax, wsum = 0.0;
    double *otf_a = NULL, *otf_u = NULL;
    ee_geo *geo = NULL;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "encircled: no system, options or result");
    memset(out, 0, sizeof *out);
    if ((rc = sg_psf_check_common(sys, o->sampling, "encircled", d)) != SG_OK)
        return rc;
    if (o->kind != SG_EE_ENCIRCLED && o->kind != SG_EE_ENSQUARED)
        return sg_diag_set(d, SG_EINVAL, "encircled: unknown kind %d", o->kind);
    if (!(o->max_radius_um >= 0.0) || !isfinite(o->max_radius_um))
        return sg_diag_set(d, SG_ERANGE, "encircled: maximum radius %g; it must be a positive "
                                         "number of micrometres, or 0 for automatic",
                           o->max_radius_um);
    np = o->npts ? o->npts : EE_NPTS;
    if (np < 2 || np > SG_EE_MAX_NPTS)
        return sg_diag_set(d, SG_ERANGE, "encircled: %d radii; from 2 to %d are allowed", np,
                           SG_EE_MAX_NPTS);
    n = o->sampling;
    rays = o->rays ? o->rays : 2 * n;
    if ((rc = sg_pupil_check(SG_PUPIL_SQUARE, rays, d)) != SG_OK)
        return rc;
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    nw = sg_an_select(o->wave, sys->nwave, "wavelength", waves, d);
    nf = sg_an_select(o->field, sys->nfield, "field", fields, d);
    if (!nw || !nf)
        return SG_ERANGE;
    if ((rc = sg_psf_working_fnum(sys, cat, &fnum, d)) != SG_OK)
        return rc;
    for (w = 0; w < nw; w++) {
        double um = sys->wave[waves[w]].um;
        if (nw > 1 && sys->wave[waves[w]].weight <= 0.0)
            continue;
        wsum += nw > 1 ? sys->wave[waves[w]].weight : 1.0;
        if (lmin == 0.0 || um < lmin)
            lmin = um;
        if (um > lmax)
            lmax = um;
    }
    if (wsum <= 0.0)
        return sg_diag_set(d, SG_ERANGE, "encircled: every chosen wavelength has weight 0");
    /* Half the shortest wavelength's PSF period: a compressed pupil's
     * period is only longer. */
    rlim = 0.5 * lmin * fnum * (n - 1);
    geo = calloc((size_t)nf, sizeof *geo);
    if (!geo)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    rmax = 0.0;
    for (f = 0; f < nf; f++) {
        if ((rc = ee_geometric(sys, cat, o, fields[f], rays, &geo[f], d)) != SG_OK)
            goto fail;
        if (geo[f].rmax > rmax)
            rmax = geo[f].rmax;
    }
    if (o->max_radius_um > 0.0) {
        if (o->max_radius_um > rlim) {
            double need = ceil(2.0 * o->max_radius_um / (lmin * fnum)) + 1.0;
            if (need <= SG_PSF_SAMPLING_MAX)
                rc = sg_diag_set(d, SG_ERANGE, "encircled: maximum radius %g um is beyond half "
                                               "the PSF grid, %.6g um at sampling %d: a "
                                               "sampling of %.0f or more reaches it",
                                 o->max_radius_um, rlim, n, need);
            else
                rc = sg_diag_set(d, SG_ERANGE, "encircled: maximum radius %g um is beyond half "
                                               "the PSF grid, %.6g um at sampling %d, and %.6g "
                                               "um at the largest, %d", o->max_radius_um, rlim,
                                 n, 0.5 * lmin * fnum * (SG_PSF_SAMPLING_MAX - 1),
                                 SG_PSF_SAMPLING_MAX);
            goto fail;
        }
        rmax = o->max_radius_um;
    } else {
        /* The farthest ray, or five Airy rings of the longest wavelength,
         * whichever is wider, within the PSF grid. */
        double g = rmax;
        rmax = fmax(1.05 * g, 5.0 * lmax * fnum);
        if (rmax > rlim) {
            if (g > rlim)
                sg_diag_warn(d, "encircled: rays land up to %.6g um from the chief ray, beyond "
                                "half the PSF grid (%.6g um at sampling %d): the curves stop "
                                "there; a larger sampling widens the grid", g, rlim, n);
            rmax = rlim;
        }
    }
    out->nfield = nf;
    out->npts = np;
    out->sampling = n;
    out->rays = rays;
    out->kind = o->kind;
    out->fnum = fnum;
    out->wave_um = lmin;
    out->field = malloc((size_t)nf * sizeof *out->field);
    out->radius_um = malloc((size_t)np * sizeof *out->radius_um);
    out->diffraction = calloc((size_t)nf * np, sizeof *out->diffraction);
    out->geometric = malloc((size_t)nf * np * sizeof *out->geometric);
    out->limit = calloc((size_t)nf * np, sizeof *out->limit);
    otf_a = malloc((size_t)n * n * sizeof *otf_a);
    otf_u = malloc((size_t)n * n * sizeof *otf_u);
    if (!out->field || !out->radius_um || !out->diffraction || !out->geometric ||
        !out->limit || !otf_a || !otf_u) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    for (j = 0; j < np; j++)
        out->radius_um[j] = rmax * j / (np - 1);
    for (f = 0; f < nf; f++) {
        double *fd = out->diffraction + (size_t)f * np, *fl = out->limit + (size_t)f * np;
        out->field[f] = fields[f];
        ee_geo_frac(&geo[f], out->radius_um, np, out->geometric + (size_t)f * np);
        for (w = 0; w < nw; w++) {
            double wt = nw > 1 ? sys->wave[waves[w]].weight : 1.0, tx, ty;
            sg_pupil p;
            if (wt <= 0.0)
                continue;
            rc = sg_pupil_trace(sys, cat, &o->trace, fields[f], waves[w], n, fnum, o->nthreads,
                                &p, d);
            if (rc != SG_OK)
                goto fail;
            rc = pupil_otf(&p, 1, otf_a, d);
            if (rc == SG_OK)
                rc = pupil_otf(&p, 0, otf_u, d);
            /* The PSF's period: M grid spacings of psf.c. */
            tx = p.um * fnum * (n - 1) / p.scale_x;
            ty = p.um * fnum * (n - 1) / p.scale_y;
            sg_pupil_free(&p);
            if (rc != SG_OK)
                goto fail;
            for (j = 0; j < np; j++) {
                double fa, fu;
                ee_at(otf_a, otf_u, n, tx, ty, o->kind, out->radius_um[j], &fa, &fu);
                fd[j] += wt * fa;
                fl[j] += wt * fu;
            }
        }
        for (j = 0; j < np; j++) {
            fd[j] /= wsum;
            fl[j] /= wsum;
        }
    }
    for (f = 0; f < nf; f++)
        ee_geo_free(&geo[f]);
    free(geo);
    free(otf_a);
    free(otf_u);
    return SG_OK;
fail:
    for (f = 0; f < nf; f++)
        ee_geo_free(&geo[f]);
    free(geo);
    free(otf_a);
    free(otf_u);
    sg_ee_free(out);
    return rc;
}
