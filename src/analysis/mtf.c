/*
 * mtf.c - the FFT MTF: the modulus of the Fourier transform of the FFT
 * PSF (psf.c), which is the pupil's autocorrelation, cut along x
 * (sagittal) and y (tangential), per field, with the diffraction limit of
 * the same pupil unaberrated.
 *
 * A cut of the 2-D transform of the PSF is the 1-D transform of the PSF
 * summed across the cut (the line spread function), so each cut costs one
 * transform of 2N points after the PSF's own 2N x 2N one.  Bin k of a
 * wavelength lies at k / (lambda F# (N - 1)) (cycles per unit of lambda),
 * times (1 - vc) where the field's pupil is compressed: the cutoff
 * 1 / (lambda F#) is bin N - 1, the pupil's full width.  The wavelengths
 * are summed as complex OTFs, each linearly interpolated between its bins
 * onto the common frequencies and weighted by its wavelength weight (each
 * wavelength's PSF carrying unit energy).
 */
#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <fftw3.h>

#include "analysis_int.h"

#define SG_MTF_PI 3.14159265358979323846

void sg_mtf_opts_init(sg_mtf_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->field = -1;
    o->wave = -1;
    o->sampling = 64;
}

void sg_mtf_free(sg_mtf *m)
{
    if (!m)
        return;
    free(m->field);
    free(m->freq);
    free(m->tan);
    free(m->sag);
    free(m->dl);
    memset(m, 0, sizeof *m);
}

/* The OTF cuts of one pupil: sag[k] along x, tan[k] along y, k = 0 .. n,
 * normalized to 1 at k = 0, with the phase about the chief ray's point. */
static int pupil_cuts(const sg_pupil *p, int aberrated, double complex *sag, double complex *tan,
                      sg_diag *d)
{
    int m = 2 * p->n, i, j, k, rc;
    double *inten, *lsf;
    fftw_complex *c;
    fftw_plan plan;

    if ((rc = sg_pupil_intensity(p, aberrated, m, &inten, d)) != SG_OK)
        return rc;
    lsf = fftw_alloc_real((size_t)m);
    c = fftw_alloc_complex((size_t)m / 2 + 1);
    if (!lsf || !c) {
        free(inten);
        fftw_free(lsf);
        fftw_free(c);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    plan = fftw_plan_dft_r2c_1d(m, lsf, c, FFTW_ESTIMATE);
    for (int axis = 0; axis < 2; axis++) {
        double complex *out = axis == 0 ? sag : tan;
        double c0;
        for (k = 0; k < m; k++)
            lsf[k] = 0.0;
        for (j = 0; j < m; j++)
            for (i = 0; i < m; i++)
                lsf[axis == 0 ? i : j] += inten[(size_t)j * (size_t)m + (size_t)i];
        fftw_execute(plan);
        c0 = creal(c[0]);
        /* The PSF's centre is index m/2: the factor (-1)^k moves the
         * transform's origin there. */
        for (k = 0; k <= p->n; k++)
            out[k] = (k & 1 ? -c[k] : c[k]) / c0;
    }
    fftw_destroy_plan(plan);
    fftw_free(lsf);
    fftw_free(c);
    free(inten);
    return SG_OK;
}

/* The Huygens MTF of one field at the frequencies freq (cycles/mm): the
 * Huygens PSF (every chosen wavelength, as sg_psf_compute sums them)
 * summed across each cut into its line spread function, whose transform
 * is taken at each frequency directly (a sum over the grid's M points),
 * so the frequencies need not fall on an FFT's bins. */
static int huygens_mtf(const sg_system *sys, const sg_catalog *cat, const sg_mtf_opts *o,
                       int field, const double *freq, int np, double *tan, double *sag,
                       int *size, double *delta, sg_diag *d)
{
    sg_psf_opts po;
    sg_psf p;
    double *lx = NULL, *ly = NULL, tot = 0.0, nyq;
    int rc, m, i, j, k;

    sg_psf_opts_init(&po);
    po.trace = o->trace;
    po.field = field;
    po.wave = o->wave;
    po.sampling = o->sampling;
    po.nthreads = o->nthreads;
    po.method = SG_PSF_HUYGENS;
    po.image_size = o->image_size;
    po.image_delta_um = o->image_delta_um;
    if ((rc = sg_psf_compute(sys, cat, &po, &p, d)) != SG_OK)
        return rc;
    m = p.size;
    *size = m;
    *delta = p.spacing_x_um;
    /* A grid of spacing D samples frequencies below 1 / (2 D): beyond,
     * the transform aliases, so the request is refused, not answered. */
    nyq = 1000.0 / (2.0 * (p.spacing_x_um > p.spacing_y_um ? p.spacing_x_um : p.spacing_y_um));
    if (freq[np - 1] > nyq * (1.0 + 1e-12)) {
        rc = sg_diag_set(d, SG_ERANGE, "mtf: the Huygens PSF's image spacing %.6g um samples "
                                       "frequencies up to %.6g cycles/mm, below the %.6g asked "
                                       "for: give a smaller image spacing or a lower maximum "
                                       "frequency", p.spacing_x_um, nyq, freq[np - 1]);
        goto done;
    }
    lx = calloc((size_t)m, sizeof *lx);
    ly = calloc((size_t)m, sizeof *ly);
    if (!lx || !ly) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (j = 0; j < m; j++)
        for (i = 0; i < m; i++) {
            double v = p.psf[(size_t)j * (size_t)m + (size_t)i];
            lx[i] += v;
            ly[j] += v;
            tot += v;
        }
    if (!(tot > 0.0)) {
        rc = sg_diag_set(d, SG_EMISS, "mtf: field %d: the Huygens PSF is empty", field + 1);
        goto done;
    }
    {
        /* A PSF cut by its grid loses energy, and the MTF's low
         * frequencies rise: said when the grid's edge is brighter than a
         * tenth of its mean (an Airy pattern's edge at 16 lambda F# is
         * below 1e-3 of it; a uniform blur wider than the grid is at 1). */
        double edge = 0.0;
        for (i = 0; i < m; i++)
            edge += p.psf[i] + p.psf[(size_t)(m - 1) * (size_t)m + (size_t)i] +
                    p.psf[(size_t)i * (size_t)m] + p.psf[(size_t)i * (size_t)m + (size_t)(m - 1)];
        edge /= 4.0 * m;
        if (edge > 0.1 * tot / ((double)m * m))
            sg_diag_warn(d, "mtf: field %d: the Huygens PSF reaches the edge of its %d x %d "
                            "image grid (its edge at %.3g of its mean): energy outside is lost "
                            "and the MTF's low frequencies rise; give a larger image size or "
                            "spacing", field + 1, m, m, edge / (tot / ((double)m * m)));
    }
    for (k = 0; k < np; k++) {
        /* Positions from the grid's centre, the chief ray's point. */
        double ax = 2.0 * SG_MTF_PI * freq[k] * 1e-3 * p.spacing_x_um;
        double ay = 2.0 * SG_MTF_PI * freq[k] * 1e-3 * p.spacing_y_um;
        double complex sx = 0.0, sy = 0.0;
        for (i = 0; i < m; i++) {
            sx += lx[i] * cexp(-I * ax * (i - m / 2));
            sy += ly[i] * cexp(-I * ay * (i - m / 2));
        }
        sag[k] = cabs(sx) / tot;
        tan[k] = cabs(sy) / tot;
    }
    rc = SG_OK;
done:
    free(lx);
    free(ly);
    sg_psf_free(&p);
    return rc;
}

/* The cut at frequency nu (cycles/mm) of a wavelength whose bin width is
 * bin (cycles/mm): linear between bins, 0 beyond the last. */
static double complex cut_at(const double complex *cut, int n, double bin, double nu)
{
    double u = nu / bin, f;
    int k = (int)floor(u);
    if (k >= n)
        return k == n && u == n ? cut[n] : 0.0;
    f = u - k;
    return (1.0 - f) * cut[k] + f * cut[k + 1];
}

/* The geometric MTF of one field at the frequencies freq (cycles/mm):
 * the modulus of the rays' mean exp(i 2 pi nu y) (tangential) and
 * exp(i 2 pi nu x) (sagittal), the transform of their line spread
 * function; each wavelength's rays that reach the image share its weight,
 * all measured from the spot's reference (the primary wavelength's chief
 * ray), so lateral colour shows as it does in the FFT MTF. */
static int geometric_mtf(const sg_system *sys, const sg_catalog *cat, const sg_mtf_opts *o,
                         int field, const double *freq, int np, double *tan, double *sag,
                         sg_diag *d)
{
    sg_spot_opts so;
    sg_spot s;
    double mm = 1e3 * sg_an_um_to_units(sys), wsum = 0.0;
    double complex *at = NULL, *as = NULL;
    int rc, w, j;

    sg_spot_opts_init(&so);
    so.trace = o->trace;
    so.pattern = SG_PUPIL_SQUARE;
    so.density = o->sampling;
    so.reference = SG_SPOT_REF_CHIEF;
    so.wave = o->wave;
    so.field = field;
    so.nthreads = o->nthreads;
    so.max_points = sg_pupil_count(SG_PUPIL_SQUARE, o->sampling);
    if ((rc = sg_spot_compute(sys, cat, &so, &s, d)) != SG_OK)
        return rc;
    if (s.field[0].status != SG_OK) {
        rc = sg_diag_set(d, s.field[0].status, "mtf: field %d: the chief ray fails: %s",
                         field + 1, sg_strerror(s.field[0].status));
        goto done;
    }
    at = calloc((size_t)np, sizeof *at);
    as = calloc((size_t)np, sizeof *as);
    if (!at || !as) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (w = 0; w < s.nwave; w++) {
        const sg_spot_cell *c = &s.cell[w];
        double wt = s.nwave > 1 ? sys->wave[s.wave_index[w]].weight : 1.0;
        size_t k;
        if (wt <= 0.0 || c->status != SG_OK || c->npts == 0)
            continue;
        /* The frequencies are j times the first step: exp(i 2 pi nu_j y)
         * is the j-th power of one rotation, made by products (the
         * rounding grows as j times the unit's, far below the MTF's). */
        double a = 2.0 * SG_MTF_PI * (freq[1] - freq[0]) / mm, sc = wt / (double)c->npts;
        for (k = 0; k < c->npts; k++) {
            double complex zt = cexp(I * a * c->pts[k][1]), zs = cexp(I * a * c->pts[k][0]);
            double complex et = sc, es = sc;
            for (j = 0; j < np; j++) {
                at[j] += et;
                as[j] += es;
                et *= zt;
                es *= zs;
            }
        }
        wsum += wt;
    }
    if (wsum <= 0.0) {
        rc = sg_diag_set(d, SG_EMISS, "mtf: field %d: no ray reaches the image", field + 1);
        goto done;
    }
    for (j = 0; j < np; j++) {
        tan[j] = cabs(at[j]) / wsum;
        sag[j] = cabs(as[j]) / wsum;
    }
    rc = SG_OK;
done:
    free(at);
    free(as);
    sg_spot_free(&s);
    return rc;
}

int sg_mtf_compute(const sg_system *sys, const sg_catalog *cat, const sg_mtf_opts *o,
                   sg_mtf *out, sg_diag *d)
{
    int waves[SG_MAX_WAVES], fields[SG_MAX_FIELDS], nw, nf, w, f, rc, n, np, j;
    double fnum, fmax = 0.0, wsum = 0.0;
    double complex *sag = NULL, *tan = NULL, *acc_s = NULL, *acc_t = NULL, *acc_d = NULL;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "mtf: no system, options or result");
    memset(out, 0, sizeof *out);
    if ((rc = sg_psf_check_common(sys, o->sampling, "mtf", d)) != SG_OK)
        return rc;
    if (!(o->max_frequency >= 0.0) || !isfinite(o->max_frequency))
        return sg_diag_set(d, SG_ERANGE, "mtf: maximum frequency %g; it must be a positive "
                                         "number of cycles/mm, or 0 for the cutoff",
                           o->max_frequency);
    if (o->method != SG_MTF_FFT && o->method != SG_MTF_GEOMETRIC &&
        o->method != SG_MTF_HUYGENS)
        return sg_diag_set(d, SG_EINVAL, "mtf: unknown method %d", o->method);
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    nw = sg_an_select(o->wave, sys->nwave, "wavelength", waves, d);
    nf = sg_an_select(o->field, sys->nfield, "field", fields, d);
    if (!nw || !nf)
        return SG_ERANGE;
    if ((rc = sg_psf_working_fnum(sys, cat, &fnum, d)) != SG_OK)
        return rc;
    for (w = 0; w < nw; w++) {
        double wt = nw > 1 ? sys->wave[waves[w]].weight : 1.0;
        double cut = 1000.0 / (sys->wave[waves[w]].um * fnum);
        if (wt <= 0.0)
            continue;
        wsum += wt;
        if (cut > fmax)
            fmax = cut;
    }
    if (wsum <= 0.0)
        return sg_diag_set(d, SG_ERANGE, "mtf: every chosen wavelength has weight 0");
    out->cutoff = fmax;
    if (o->max_frequency > 0.0)
        fmax = o->max_frequency;
    n = o->sampling;
    np = n;
    out->nfield = nf;
    out->npts = np;
    out->fnum = fnum;
    out->sampling = n;
    out->method = o->method;
    out->field = malloc((size_t)nf * sizeof *out->field);
    out->freq = malloc((size_t)np * sizeof *out->freq);
    out->tan = malloc((size_t)nf * np * sizeof *out->tan);
    out->sag = malloc((size_t)nf * np * sizeof *out->sag);
    out->dl = malloc((size_t)np * sizeof *out->dl);
    sag = malloc(((size_t)n + 1) * sizeof *sag);
    tan = malloc(((size_t)n + 1) * sizeof *tan);
    acc_s = malloc((size_t)np * sizeof *acc_s);
    acc_t = malloc((size_t)np * sizeof *acc_t);
    acc_d = calloc((size_t)np, sizeof *acc_d);
    if (!out->field || !out->freq || !out->tan || !out->sag || !out->dl || !sag || !tan ||
        !acc_s || !acc_t || !acc_d) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    for (j = 0; j < np; j++)
        out->freq[j] = fmax * j / (np - 1);
    for (f = 0; f < nf; f++) {
        out->field[f] = fields[f];
        for (j = 0; j < np; j++)
            acc_s[j] = acc_t[j] = 0.0;
        for (w = 0; w < nw; w++) {
            double wt = nw > 1 ? sys->wave[waves[w]].weight : 1.0, bin_x, bin_y;
            sg_pupil p;
            if (wt <= 0.0)
                continue;
            /* The Huygens MTF traces its own rays: the pupils here serve
             * the diffraction limit alone. */
            if (o->method == SG_MTF_HUYGENS && f > 0)
                continue;
            rc = sg_pupil_trace(sys, cat, &o->trace, fields[f], waves[w], n, fnum, o->nthreads,
                                &p, d);
            if (rc != SG_OK)
                goto fail;
            bin_x = 1000.0 * p.scale_x / (p.um * fnum * (n - 1));
            bin_y = 1000.0 * p.scale_y / (p.um * fnum * (n - 1));
            rc = o->method == SG_MTF_FFT ? pupil_cuts(&p, 1, sag, tan, d) : SG_OK;
            if (rc == SG_OK && o->method == SG_MTF_FFT)
                for (j = 0; j < np; j++) {
                    acc_s[j] += wt * cut_at(sag, n, bin_x, out->freq[j]);
                    acc_t[j] += wt * cut_at(tan, n, bin_y, out->freq[j]);
                }
            /* The diffraction limit: the first field's pupil, unaberrated. */
            if (rc == SG_OK && f == 0) {
                rc = pupil_cuts(&p, 0, sag, tan, d);
                if (rc == SG_OK)
                    for (j = 0; j < np; j++)
                        acc_d[j] += wt * cut_at(tan, n, bin_y, out->freq[j]);
            }
            sg_pupil_free(&p);
            if (rc != SG_OK)
                goto fail;
        }
        if (o->method == SG_MTF_HUYGENS) {
            rc = huygens_mtf(sys, cat, o, fields[f], out->freq, np, out->tan + (size_t)f * np,
                             out->sag + (size_t)f * np, &out->image_size, &out->image_delta_um,
                             d);
            if (rc != SG_OK)
                goto fail;
        } else if (o->method == SG_MTF_GEOMETRIC) {
            rc = geometric_mtf(sys, cat, o, fields[f], out->freq, np,
                               out->tan + (size_t)f * np, out->sag + (size_t)f * np, d);
            if (rc != SG_OK)
                goto fail;
        } else
            for (j = 0; j < np; j++) {
                out->sag[(size_t)f * np + j] = cabs(acc_s[j]) / wsum;
                out->tan[(size_t)f * np + j] = cabs(acc_t[j]) / wsum;
            }
    }
    for (j = 0; j < np; j++)
        out->dl[j] = cabs(acc_d[j]) / wsum;
    free(sag);
    free(tan);
    free(acc_s);
    free(acc_t);
    free(acc_d);
    return SG_OK;
fail:
    free(sag);
    free(tan);
    free(acc_s);
    free(acc_t);
    free(acc_d);
    sg_mtf_free(out);
    return rc;
}
