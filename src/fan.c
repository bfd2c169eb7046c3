/*
 * fan.c - transverse ray fans: ey against Py and ex against Px on the
 * image surface, relative to the reference wavelength's chief ray, or
 * OPD fans against each field's reference sphere.  Every fan of a
 * wavelength goes through the batch in one call, keeping only the image
 * surface.
 */
#include <stdlib.h>
#include <string.h>

#include "analysis_internal.h"

void sg_fan_opts_init(sg_fan_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->npts = 21;
    o->wave = -1;
    o->field = -1;
}

void sg_fan_free(sg_fan *f)
{
    int k;
    if (!f)
        return;
    for (k = 0; k < f->nfield * f->nwave; k++) {
        if (f->tan) {
            free(f->tan[k].p);
            free(f->tan[k].e);
            free(f->tan[k].status);
        }
        if (f->sag) {
            free(f->sag[k].p);
            free(f->sag[k].e);
            free(f->sag[k].status);
        }
    }
    free(f->tan);
    free(f->sag);
    f->tan = f->sag = NULL;
}

static int curve_alloc(sg_fan_curve *c, int n)
{
    c->p = calloc((size_t)n, sizeof *c->p);
    c->e = calloc((size_t)n, sizeof *c->e);
    c->status = calloc((size_t)n, sizeof *c->status);
    return c->p && c->e && c->status ? SG_OK : SG_ENOMEM;
}

/* One ray's OPD into *e, or its failure (the reference's first) into *st. */
static void opd_value(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *row,
                      int *st, double *e)
{
    sg_opd r;
    *e = 0.0;
    if (ref->status != SG_OK) {
        *st = ref->status;
        return;
    }
    if (*st != SG_OK)
        return;
    sg_opd_of_ray(t, ref, row, &r);
    *st = r.status;
    if (r.status == SG_OK)
        *e = r.opd_waves;
}

int sg_fan_compute(const sg_system *sys, const sg_catalog *cat, const sg_fan_opts *o,
                   sg_fan *out, sg_diag *d)
{
    int waves[SG_MAX_WAVES], fields[SG_MAX_FIELDS], order[SG_MAX_WAVES];
    int nw, nf, np, refw, w, f, k, j, rc, last;
    size_t nray, r;
    sg_ray_in *rays = NULL;
    sg_ray_surface *rows = NULL;
    int *st = NULL;
    sg_batch *b = NULL;
    sg_tracer *tw = NULL;
    sg_opd_ref *ref = NULL;
    double c0 = 0.0;
    int c0st = SG_OK;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "fan: no system, options or result");
    memset(out, 0, sizeof *out);
    if (o->npts < 2 || o->npts > 1000000)
        return sg_diag_set(d, SG_ERANGE, "fan: %d points is not one of 2 to 1000000", o->npts);
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    nw = sg_an_select(o->wave, sys->nwave, "wavelength", waves, d);
    nf = sg_an_select(o->field, sys->nfield, "field", fields, d);
    if (!nw || !nf)
        return SG_ERANGE;
    np = o->npts;
    refw = o->wave >= 0 ? o->wave : sys->primary_wave;
    out->nfield = nf;
    out->nwave = nw;
    out->npts = np;
    out->opd = o->opd != 0;
    sg_an_wave_order(sys, waves, nw, refw, out->wave_index, out->wave_um, order);
    nray = (size_t)nf * (size_t)(2 * np + 1);
    out->tan = calloc((size_t)nf * (size_t)nw, sizeof *out->tan);
    out->sag = calloc((size_t)nf * (size_t)nw, sizeof *out->sag);
    rays = malloc(nray * sizeof *rays);
    rows = malloc(nray * sizeof *rows);
    st = malloc(nray * sizeof *st);
    ref = calloc((size_t)nf, sizeof *ref);
    if (!out->tan || !out->sag || !rays || !rows || !st || !ref) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (k = 0; k < nf * nw; k++)
        if (curve_alloc(&out->tan[k], np) != SG_OK || curve_alloc(&out->sag[k], np) != SG_OK) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto done;
        }
    /* Per field: the chief ray, then the tangential and sagittal fans. */
    for (f = 0; f < nf; f++) {
        double hx, hy;
        out->field_index[f] = fields[f];
        sg_field_normalized(sys, fields[f], &hx, &hy);
        out->hx[f] = hx;
        out->hy[f] = hy;
        r = (size_t)f * (size_t)(2 * np + 1);
        rays[r].v[0] = hx;
        rays[r].v[1] = hy;
        rays[r].v[2] = rays[r].v[3] = 0.0;
        for (j = 0; j < np; j++) {
            double p = -1.0 + 2.0 * (double)j / (double)(np - 1);
            sg_ray_in *t = &rays[r + 1 + (size_t)j], *s = &rays[r + 1 + (size_t)(np + j)];
            t->v[0] = s->v[0] = hx;
            t->v[1] = s->v[1] = hy;
            t->v[2] = 0.0;
            t->v[3] = p;
            s->v[2] = p;
            s->v[3] = 0.0;
        }
    }
    last = sys->nsurf - 1;
    for (k = 0; k < nw; k++) {
        sg_trace_opts to = o->trace;
        w = order[k];
        to.wave = waves[w];
        b = sg_batch_new(sys, cat, &to, o->nthreads, d);
        if (!b) {
            rc = d && d->code ? d->code : SG_ENOMEM;
            goto done;
        }
        if ((rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, nray, &last, 1, rows, st, d)) !=
            SG_OK)
            goto done;
        /* The chief rays again, past the apertures and obscurations: the
         * curve is measured from them (Zemax's reference) even where an
         * obscuration stops the pupil's centre.  A chief ray that passed
         * gets the same bits. */
        sg_batch_set_reference(b, 1);
        for (f = 0; f < nf && rc == SG_OK; f++) {
            r = (size_t)f * (size_t)(2 * np + 1);
            if (st[r] != SG_OK)
                rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, &rays[r], 1, &last, 1, &rows[r],
                                    &st[r], d);
        }
        if (rc != SG_OK)
            goto done;
        sg_batch_free(b);
        b = NULL;
        if (o->opd) {
            /* A tracer at this wavelength, for the OPD in its waves; the
             * spheres are the primary wavelength's whichever traces them. */
            sg_tracer_free(tw);
            if (!(tw = sg_tracer_new(sys, cat, &to, d))) {
                rc = d && d->code ? d->code : SG_ENOMEM;
                goto done;
            }
            if (k == 0)
                for (f = 0; f < nf; f++)
                    if ((rc = sg_opd_reference(tw, out->hx[f], out->hy[f], &ref[f], d)) !=
                        SG_OK)
                        goto done;
        }
        for (f = 0; f < nf; f++) {
            sg_fan_curve *t = &out->tan[f * nw + w], *s = &out->sag[f * nw + w];
            r = (size_t)f * (size_t)(2 * np + 1);
            if (k == 0) {
                out->status[f] = st[r];
                out->ref_x[f] = st[r] == SG_OK ? rows[r].x : 0.0;
                out->ref_y[f] = st[r] == SG_OK ? rows[r].y : 0.0;
            }
            if (o->opd) {
                /* This wavelength's chief ray: its OPD is the curve's zero. */
                c0st = out->status[f] != SG_OK ? out->status[f] : st[r];
                opd_value(tw, &ref[f], &rows[r], &c0st, &c0);
            }
            for (j = 0; j < np; j++) {
                size_t it = r + 1 + (size_t)j, is = r + 1 + (size_t)(np + j);
                t->p[j] = rays[it].v[3];
                s->p[j] = rays[is].v[2];
                /* Without the reference chief ray there is nothing to measure from. */
                t->status[j] = out->status[f] != SG_OK ? out->status[f] : st[it];
                s->status[j] = out->status[f] != SG_OK ? out->status[f] : st[is];
                if (o->opd) {
                    if (c0st != SG_OK)
                        t->status[j] = s->status[j] = c0st;
                    opd_value(tw, &ref[f], &rows[it], &t->status[j], &t->e[j]);
                    opd_value(tw, &ref[f], &rows[is], &s->status[j], &s->e[j]);
                    if (t->status[j] == SG_OK)
                        t->e[j] -= c0;
                    if (s->status[j] == SG_OK)
                        s->e[j] -= c0;
                    continue;
                }
                t->e[j] = t->status[j] == SG_OK ? rows[it].y - out->ref_y[f] : 0.0;
                s->e[j] = s->status[j] == SG_OK ? rows[is].x - out->ref_x[f] : 0.0;
            }
        }
    }
    rc = SG_OK;
done:
    sg_batch_free(b);
    sg_tracer_free(tw);
    free(ref);
    free(rays);
    free(rows);
    free(st);
    if (rc != SG_OK)
        sg_fan_free(out);
    return rc;
}
