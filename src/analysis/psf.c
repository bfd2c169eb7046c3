/*
 * psf.c - the FFT point spread function and Strehl ratio of one field,
 * from sagitta's own traced wavefront (sg_wavefront_trace).
 *
 * The pupil is the wavefront's N x N grid over the normalized pupil
 * [-1, 1]^2 (N = the sampling): amplitude 1 where the grid point lies in
 * the unit circle and its ray reaches the image, 0 elsewhere (vignetted,
 * obscured, failed), phase 2 pi W with W the OPD in waves against the
 * chief ray's reference sphere.  It is zero-padded to M = 2N points, so
 * the PSF grid spacing is lambda F# (N - 1) / M, about lambda F# / 2, and
 * the pupil's autocorrelation (extent 2N - 1 samples) does not alias.
 * Several wavelengths share the shortest one's grid: a longer wavelength
 * is padded further, in proportion to its wavelength.
 */
#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <fftw3.h>

#include "analysis_int.h"

/* 2 pi, the phase of one wave. */
#define SG_TWO_PI 6.283185307179586476925286766559

void sg_psf_opts_init(sg_psf_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->field = 0;
    o->wave = -1;
    o->sampling = 64;
}

void sg_psf_free(sg_psf *p)
{
    if (!p)
        return;
    free(p->psf);
    p->psf = NULL;
}

void sg_pupil_free(sg_pupil *p)
{
    free(p->opd);
    free(p->ok);
    p->opd = NULL;
    p->ok = NULL;
}

int sg_psf_check_common(const sg_system *sys, int sampling, const char *what, sg_diag *d)
{
    if (sampling < SG_PSF_SAMPLING_MIN || sampling > SG_PSF_SAMPLING_MAX)
        return sg_diag_set(d, SG_ERANGE, "%s: sampling %d; from %d to %d pupil points across "
                                         "are allowed", what, sampling, SG_PSF_SAMPLING_MIN,
                           SG_PSF_SAMPLING_MAX);
    (void)sys;
    return SG_OK;
}

int sg_pupil_trace(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *trace,
                   int field, int wave, int sampling, double fnum, int nthreads,
                   sg_pupil *out, sg_diag *d)
{
    sg_wavefront_opts wo;
    sg_wavefront w;
    const sg_field *f = &sys->field[field];
    int rc;

    memset(out, 0, sizeof *out);
    if (f->van != 0.0)
        return sg_diag_set(d, SG_EUNSUPPORTED, "field %d: a turned vignetted pupil (van %g) "
                                               "is not supported by the FFT PSF and MTF",
                           field + 1, f->van);
    sg_wavefront_opts_init(&wo);
    wo.trace = *trace;
    wo.trace.wave = wave;
    wo.field = field;
    wo.grid = sampling;
    /* Only the map is used: one Zernike term keeps the fit cheap. */
    wo.nterms = 1;
    wo.nthreads = nthreads;
    if ((rc = sg_wavefront_trace(sys, cat, &wo, &w, NULL, d)) != SG_OK)
        return rc;
    out->n = sampling;
    out->opd = w.map;
    out->ok = w.valid;
    out->nvalid = w.nvalid;
    w.map = NULL;
    w.valid = NULL;
    sg_wavefront_free(&w);
    if (out->nvalid == 0) {
        sg_pupil_free(out);
        return sg_diag_set(d, SG_EMISS, "field %d, wavelength %d: no ray of the pupil reaches "
                                        "the image", field + 1, wave + 1);
    }
    out->um = sys->wave[wave].um;
    /* The sampling rule: the PSF grid spans N lambda F#, so a pupil whose
     * OPD changes by more than half a wave between neighbouring samples
     * spreads light beyond it, and the FFT wraps that light around. */
    {
        int n = sampling, i, j;
        double step = 0.0;
        for (j = 0; j < n; j++)
            for (i = 0; i < n; i++) {
                size_t k = (size_t)j * (size_t)n + (size_t)i;
                if (!out->ok[k])
                    continue;
                if (i + 1 < n && out->ok[k + 1])
                    step = fmax(step, fabs(out->opd[k + 1] - out->opd[k]));
                if (j + 1 < n && out->ok[k + (size_t)n])
                    step = fmax(step, fabs(out->opd[k + (size_t)n] - out->opd[k]));
            }
        out->max_step = step;
        if (step > 0.5)
            sg_diag_warn(d, "field %d, wavelength %d: the OPD changes by up to %.3g waves "
                            "between neighbouring pupil samples, more than 0.5: the PSF is "
                            "wider than its grid and aliases; a sampling of about %.0f or "
                            "more is needed", field + 1, wave + 1, step,
                         ceil(sampling * step / 0.5));
    }
    /* The vignetting factors compress the traced pupil: its samples lie
     * closer in the physical pupil by (1 - vc), so the PSF grid is wider
     * by 1 / (1 - vc) along that axis. */
    out->scale_x = 1.0 - f->vcx;
    out->scale_y = 1.0 - f->vcy;
    out->fnum = fnum;
    return SG_OK;
}

int sg_pupil_intensity(const sg_pupil *p, int aberrated, int m, double **intensity, sg_diag *d)
{
    int n = p->n, i, j;
    size_t mm = (size_t)m * (size_t)m;
    fftw_complex *a = fftw_alloc_complex(mm);
    fftw_plan plan;
    double *out;

    *intensity = NULL;
    out = malloc(mm * sizeof *out);
    if (!a || !out) {
        fftw_free(a);
        free(out);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    /* Planned before the data is written: FFTW_ESTIMATE does not touch it,
     * but the rule is the same for every flag. */
    plan = fftw_plan_dft_2d(m, m, a, a, FFTW_FORWARD, FFTW_ESTIMATE);
    if (!plan) {
        fftw_free(a);
        free(out);
        return sg_diag_set(d, SG_ENOMEM, "FFTW could not plan a %d x %d transform", m, m);
    }
    memset(a, 0, mm * sizeof *a);
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            size_t k = (size_t)j * (size_t)n + (size_t)i;
            double ph;
            if (!p->ok[k])
                continue;
            /* The wave reaching an image point x carries the phase of its
             * path, -2 pi W less 2 pi (pupil point . x) / (lambda R): the
             * forward transform of exp(-i 2 pi W), or the PSF comes out
             * turned through the chief ray's point. */
            ph = aberrated ? -SG_TWO_PI * p->opd[k] : 0.0;
            a[(size_t)j * (size_t)m + (size_t)i] = cos(ph) + I * sin(ph);
        }
    fftw_execute(plan);
    fftw_destroy_plan(plan);
    /* Centred: the zero frequency, the chief ray's point, at (m/2, m/2). */
    for (j = 0; j < m; j++)
        for (i = 0; i < m; i++) {
            fftw_complex v = a[(size_t)j * (size_t)m + (size_t)i];
            size_t oi = (size_t)((i + m / 2) % m), oj = (size_t)((j + m / 2) % m);
            out[oj * (size_t)m + oi] = creal(v) * creal(v) + cimag(v) * cimag(v);
        }
    fftw_free(a);
    *intensity = out;
    return SG_OK;
}

double sg_pupil_strehl_exact(const sg_pupil *p)
{
    size_t k, nn = (size_t)p->n * (size_t)p->n;
    double re = 0.0, im = 0.0;
    for (k = 0; k < nn; k++)
        if (p->ok[k]) {
            re += cos(SG_TWO_PI * p->opd[k]);
            im += sin(SG_TWO_PI * p->opd[k]);
        }
    re /= (double)p->nvalid;
    im /= (double)p->nvalid;
    return re * re + im * im;
}

int sg_psf_working_fnum(const sg_system *sys, const sg_catalog *cat, double *fnum, sg_diag *d)
{
    sg_paraxial px;
    int rc = sg_paraxial_compute(sys, cat, sys->primary_wave, &px, d);
    if (rc != SG_OK)
        return rc;
    if (!isfinite(px.working_fnum) || px.working_fnum <= 0.0)
        return sg_diag_set(d, SG_EUNSUPPORTED, "the working F/# is %g: an afocal image "
                                               "space has no FFT PSF or MTF", px.working_fnum);
    *fnum = px.working_fnum;
    return SG_OK;
}

int sg_psf_compute(const sg_system *sys, const sg_catalog *cat, const sg_psf_opts *o,
                   sg_psf *out, sg_diag *d)
{
    int waves[SG_MAX_WAVES], nw, w, rc, m, i, j;
    double fnum, wsum = 0.0, sx0, sy0, strehl_num = 0.0, dl_peak = 0.0, lmin;
    double *acc = NULL;
    size_t mm;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "psf: no system, options or result");
    memset(out, 0, sizeof *out);
    if ((rc = sg_psf_check_common(sys, o->sampling, "psf", d)) != SG_OK)
        return rc;
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    if (o->method != SG_PSF_FFT && o->method != SG_PSF_HUYGENS)
        return sg_diag_set(d, SG_EINVAL, "psf: unknown method %d", o->method);
    if (o->image_size != 0 && (o->image_size < 3 || o->image_size > SG_PSF_IMAGE_MAX))
        return sg_diag_set(d, SG_ERANGE, "psf: %d image points across; from 3 to %d are "
                                         "allowed", o->image_size, SG_PSF_IMAGE_MAX);
    if (!(o->image_delta_um >= 0.0) || !isfinite(o->image_delta_um))
        return sg_diag_set(d, SG_ERANGE, "psf: image spacing %g um; it must be positive, or 0 "
                                         "for the FFT's", o->image_delta_um);
    if (o->field < 0 || o->field >= sys->nfield)
        return sg_diag_set(d, SG_ERANGE, "psf: field %d is not one of 1 to %d", o->field + 1,
                           sys->nfield);
    if (!(nw = sg_an_select(o->wave, sys->nwave, "wavelength", waves, d)))
        return SG_ERANGE;
    if ((rc = sg_psf_working_fnum(sys, cat, &fnum, d)) != SG_OK)
        return rc;
    m = 2 * o->sampling;
    mm = (size_t)m * (size_t)m;
    /* The output grid is the shortest wavelength's, padded to 2N; a longer
     * wavelength is padded to 2N lambda / lambda_min points (rounded), so
     * its grid is the same to 1 part in 4N and its centre M x M is taken
     * as it is, with no interpolation, and nothing aliases. */
    lmin = 0.0;
    for (w = 0; w < nw; w++) {
        double um = sys->wave[waves[w]].um;
        if ((nw == 1 || sys->wave[waves[w]].weight > 0.0) && (lmin == 0.0 || um < lmin))
            lmin = um;
    }
    if (lmin == 0.0)
        return sg_diag_set(d, SG_ERANGE, "psf: every chosen wavelength has weight 0");
    if (o->method == SG_PSF_HUYGENS)
        return sg_psf_huygens(sys, cat, o, waves, nw, fnum, lmin, out, d);
    {
        const sg_field *f = &sys->field[o->field];
        double base = lmin * fnum * (o->sampling - 1) / m;
        sx0 = base / (1.0 - f->vcx);
        sy0 = base / (1.0 - f->vcy);
        out->wave_um = lmin;
    }
    acc = calloc(mm, sizeof *acc);
    if (!acc)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (w = 0; w < nw; w++) {
        int wi = waves[w], mi, off;
        double wt = nw > 1 ? sys->wave[wi].weight : 1.0, sx, sy, energy, s, scale, *inten;
        sg_pupil p;
        if (nw > 1 && wt <= 0.0)
            continue;
        rc = sg_pupil_trace(sys, cat, &o->trace, o->field, wi, o->sampling, fnum, o->nthreads,
                            &p, d);
        if (rc != SG_OK)
            goto fail;
        mi = (int)lround(m * p.um / lmin);
        if (mi < m)
            mi = m;
        rc = sg_pupil_intensity(&p, 1, mi, &inten, d);
        if (rc != SG_OK) {
            sg_pupil_free(&p);
            goto fail;
        }
        sx = p.um * fnum * (o->sampling - 1) / mi / p.scale_x;
        sy = p.um * fnum * (o->sampling - 1) / mi / p.scale_y;
        /* Each wavelength carries unit energy (Parseval: its grid sums to
         * mi^2 nvalid) over its own cells sx * sy, times its weight. */
        energy = (double)mi * (double)mi * (double)p.nvalid * sx * sy;
        scale = wt / energy;
        s = sg_pupil_strehl_exact(&p);
        /* The unaberrated peak of this wavelength is nvalid^2 at the centre. */
        dl_peak += scale * (double)p.nvalid * (double)p.nvalid;
        strehl_num += scale * (double)p.nvalid * (double)p.nvalid * s;
        off = mi / 2 - m / 2;
        for (j = 0; j < m; j++)
            for (i = 0; i < m; i++)
                acc[(size_t)j * m + i] += scale * inten[(size_t)(j + off) * mi + (i + off)];
        wsum += wt;
        free(inten);
        sg_pupil_free(&p);
    }
    if (wsum <= 0.0 || dl_peak <= 0.0) {
        rc = sg_diag_set(d, SG_ERANGE, "psf: every chosen wavelength has weight 0");
        goto fail;
    }
    out->peak = 0.0;
    for (size_t k = 0; k < mm; k++) {
        acc[k] /= dl_peak;
        if (acc[k] > out->peak)
            out->peak = acc[k];
    }
    out->field = o->field;
    out->sampling = o->sampling;
    out->size = m;
    out->spacing_x_um = sx0;
    out->spacing_y_um = sy0;
    out->fnum = fnum;
    out->strehl = acc[(size_t)(m / 2) * m + m / 2];
    out->strehl_exact = strehl_num / dl_peak;
    out->psf = acc;
    return SG_OK;
fail:
    free(acc);
    return rc;
}
