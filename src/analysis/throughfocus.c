/*
 * throughfocus.c - the MTF at chosen frequencies and the Strehl ratio of each
 * field against a shift of the image plane (Zemax's Through Focus MTF):
 * the design copied with the last gap before the image lengthened by the
 * shift, and sg_mtf_compute and sg_psf_compute run on the copy.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "analysis_int.h"

void sg_tf_opts_init(sg_tf_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_mtf_opts_init(&o->mtf);
    o->steps = 11;
}

void sg_tf_free(sg_tf *t)
{
    if (!t)
        return;
    free(t->field);
    free(t->shift);
    free(t->tan);
    free(t->sag);
    free(t->strehl);
    free(t->freq);
    memset(t, 0, sizeof *t);
}

int sg_tf_compute(const sg_system *sys, const sg_catalog *cat, const sg_tf_opts *o, sg_tf *out,
                  sg_diag *d)
{
    int fields[SG_MAX_FIELDS], nf, k, f, q, nq, rc = SG_OK, ns;
    double freq[SG_TF_MAX_FREQS];
    sg_system *s = NULL;
    size_t cells;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "through focus: no system, options or result");
    memset(out, 0, sizeof *out);
    if (o->nfrequency < 0 || o->nfrequency > SG_TF_MAX_FREQS)
        return sg_diag_set(d, SG_ERANGE, "through focus: %d frequencies; from 1 to %d are "
                                         "allowed", o->nfrequency, SG_TF_MAX_FREQS);
    nq = o->nfrequency ? o->nfrequency : 1;
    for (q = 0; q < nq; q++) {
        freq[q] = o->nfrequency ? o->frequencies[q] : o->frequency;
        if (!(freq[q] > 0.0) || !isfinite(freq[q]))
            return sg_diag_set(d, SG_ERANGE, "through focus: frequency %g; it must be a "
                                             "positive number of cycles/mm", freq[q]);
    }
    if (!(o->range > 0.0) || !isfinite(o->range))
        return sg_diag_set(d, SG_ERANGE, "through focus: focus range %g; it must be a positive "
                                         "length in lens units", o->range);
    ns = o->steps;
    if (ns < 2 || ns > SG_TF_MAX_STEPS)
        return sg_diag_set(d, SG_ERANGE, "through focus: %d steps; from 2 to %d are allowed", ns,
                           SG_TF_MAX_STEPS);
    if (sys->nsurf < 3)
        return sg_diag_set(d, SG_EINVAL, "through focus: no gap before the image to shift");
    nf = sg_an_select(o->mtf.field, sys->nfield, "field", fields, d);
    if (!nf)
        return SG_ERANGE;
    cells = (size_t)nf * (size_t)ns;
    out->nfield = nf;
    out->nsteps = ns;
    out->nfreq = nq;
    out->frequency = freq[0];
    out->field = malloc((size_t)nf * sizeof *out->field);
    out->shift = malloc((size_t)ns * sizeof *out->shift);
    out->freq = malloc((size_t)nq * sizeof *out->freq);
    out->tan = malloc(cells * nq * sizeof *out->tan);
    out->sag = malloc(cells * nq * sizeof *out->sag);
    out->strehl = malloc(cells * sizeof *out->strehl);
    s = sg_system_clone(sys);
    if (!out->field || !out->shift || !out->freq || !out->tan || !out->sag || !out->strehl ||
        !s) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    for (f = 0; f < nf; f++)
        out->field[f] = fields[f];
    for (q = 0; q < nq; q++)
        out->freq[q] = freq[q];
    for (k = 0; k < ns; k++) {
        out->shift[k] = -o->range + 2.0 * o->range * k / (ns - 1);
        /* The image plane moves along the axis: the gap before it grows. */
        s->surf[s->nsurf - 2].thickness = sys->surf[sys->nsurf - 2].thickness + out->shift[k];
        /* One MTF a frequency, whose last point is that frequency, so
         * each frequency's values are those of a run at it alone. */
        for (q = 0; q < nq; q++) {
            sg_mtf_opts mo = o->mtf;
            sg_mtf m;
            mo.max_frequency = freq[q];
            if ((rc = sg_mtf_compute(s, cat, &mo, &m, d)) != SG_OK)
                goto fail;
            for (f = 0; f < nf; f++) {
                size_t c = ((size_t)f * nq + q) * ns + k;
                out->tan[c] = m.tan[(size_t)f * m.npts + m.npts - 1];
                out->sag[c] = m.sag[(size_t)f * m.npts + m.npts - 1];
            }
            sg_mtf_free(&m);
        }
        for (f = 0; f < nf; f++) {
            sg_psf_opts po;
            sg_psf p;
            sg_psf_opts_init(&po);
            po.trace = o->mtf.trace;
            po.field = fields[f];
            po.wave = o->mtf.wave;
            po.sampling = o->mtf.sampling;
            po.nthreads = o->mtf.nthreads;
            if ((rc = sg_psf_compute(s, cat, &po, &p, d)) != SG_OK)
                goto fail;
            out->strehl[(size_t)f * ns + k] = p.strehl;
            sg_psf_free(&p);
        }
    }
    sg_system_free(s);
    return SG_OK;
fail:
    sg_system_free(s);
    sg_tf_free(out);
    return rc;
}
