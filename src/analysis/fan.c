/*
 * fan.c - transverse ray fans: ey against Py and ex against Px on the
 * image surface, relative to the reference wavelength's chief ray, or
 * OPD fans against each field's reference sphere.  Every fan of a
 * wavelength goes through the batch in one call, keeping only the image
 * surface.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "analysis_int.h"
#include "trace.h"

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
    c->n = n;
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

/* One sample's value from its image row: the transverse aberration from
 * the reference chief ray, or the OPD less this wavelength's chief ray's. */
static void sample_value(const sg_system *sys, const sg_fan *out, int f, int sag,
                         const sg_tracer *tw,
                         const sg_opd_ref *ref, double c0, int c0st, const sg_ray_surface *row,
                         int st, int *status, double *e)
{
    *status = out->status[f] != SG_OK ? out->status[f] : st;
    if (out->opd) {
        if (c0st != SG_OK)
            *status = c0st;
        opd_value(tw, ref, row, status, e);
        if (*status == SG_OK)
            *e -= c0;
        return;
    }
    *e = *status == SG_OK ? (sag ? sg_an_img_x(sys, row) - out->ref_x[f]
                                 : sg_an_img_y(sys, row) - out->ref_y[f])
                          : 0.0;
}

/* A curve's interval j..j+1 needs its midpoint: both ends traced and the
 * bend beyond tol, or one end failed (the edge of what passes lies there). */
static int wants_mid(const sg_fan_curve *c, int j, const double *mid_e, const int *mid_st,
                     double tol)
{
    if (c->status[j] != SG_OK || c->status[j + 1] != SG_OK)
        return c->status[j] != c->status[j + 1];
    if (*mid_st != SG_OK)
        return 1;
    return fabs(*mid_e - 0.5 * (c->e[j] + c->e[j + 1])) > tol;
}

/* Inserts sample (p, e, st) after index j. */
static int curve_insert(sg_fan_curve *c, int j, double p, double e, int st)
{
    double *np = realloc(c->p, (size_t)(c->n + 1) * sizeof *np), *ne;
    int *ns;
    if (!np)
        return SG_ENOMEM;
    c->p = np;
    if (!(ne = realloc(c->e, (size_t)(c->n + 1) * sizeof *ne)))
        return SG_ENOMEM;
    c->e = ne;
    if (!(ns = realloc(c->status, (size_t)(c->n + 1) * sizeof *ns)))
        return SG_ENOMEM;
    c->status = ns;
    memmove(c->p + j + 2, c->p + j + 1, (size_t)(c->n - j - 1) * sizeof *c->p);
    memmove(c->e + j + 2, c->e + j + 1, (size_t)(c->n - j - 1) * sizeof *c->e);
    memmove(c->status + j + 2, c->status + j + 1, (size_t)(c->n - j - 1) * sizeof *c->status);
    c->p[j + 1] = p;
    c->e[j + 1] = e;
    c->status[j + 1] = st;
    c->n++;
    return SG_OK;
}

/* The refinement of one wavelength's curves (index w of each field): rounds
 * of every interval's midpoint, traced together in b, kept where
 * wants_mid says; an interval whose midpoint is kept is split and its
 * halves looked at next round. */
static int refine_curves(const sg_system *sys, const sg_fan_opts *o, sg_fan *out, int w,
                         sg_batch *b, const sg_tracer *tw, const sg_opd_ref *ref,
                         const double *c0, const int *c0st, double *ext, sg_diag *d)
{
    int nf = out->nfield, nw = out->nwave, round, f, side, j, last = sys->nsurf - 1, rc;
    double minstep = 2.0 / (double)(out->npts - 1) / 128.0 * 1.0000001;
    double tol = o->refine_tol > 0.0 ? o->refine_tol : 1e-3;
    for (round = 0; round < 7; round++) {
        size_t nray = 0, cap = 0, r;
        sg_ray_in *rays = NULL;
        sg_ray_surface *rows = NULL;
        int *st = NULL, added = 0;
        /* Every interval wider than the smallest step. */
        for (f = 0; f < nf; f++)
            for (side = 0; side < 2; side++) {
                const sg_fan_curve *c = side ? &out->sag[f * nw + w] : &out->tan[f * nw + w];
                for (j = 0; j + 1 < c->n; j++)
                    if (c->p[j + 1] - c->p[j] > minstep)
                        cap++;
            }
        if (cap == 0)
            return SG_OK;
        rays = malloc(cap * sizeof *rays);
        rows = malloc(cap * sizeof *rows);
        st = malloc(cap * sizeof *st);
        if (!rays || !rows || !st) {
            free(rays);
            free(rows);
            free(st);
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        }
        for (f = 0; f < nf; f++)
            for (side = 0; side < 2; side++) {
                const sg_fan_curve *c = side ? &out->sag[f * nw + w] : &out->tan[f * nw + w];
                for (j = 0; j + 1 < c->n; j++)
                    if (c->p[j + 1] - c->p[j] > minstep) {
                        double p = 0.5 * (c->p[j] + c->p[j + 1]);
                        sg_ray_in *t = &rays[nray++];
                        t->v[0] = out->hx[f];
                        t->v[1] = out->hy[f];
                        t->v[2] = side ? p : 0.0;
                        t->v[3] = side ? 0.0 : p;
                    }
            }
        rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, nray, &last, 1, rows, st, d);
        if (rc == SG_OK) {
            double tolabs = tol * *ext;
            r = 0;
            for (f = 0; f < nf; f++)
                for (side = 0; side < 2 && rc == SG_OK; side++) {
                    sg_fan_curve *c = side ? &out->sag[f * nw + w] : &out->tan[f * nw + w];
                    /* Walk the old intervals, inserting as we go. */
                    for (j = 0; j + 1 < c->n && rc == SG_OK; j++) {
                        double e;
                        int s2;
                        if (!(c->p[j + 1] - c->p[j] > minstep))
                            continue;
                        sample_value(sys, out, f, side, tw, &ref[f], c0[f], c0st[f], &rows[r], st[r],
                                     &s2, &e);
                        r++;
                        if (wants_mid(c, j, &e, &s2, tolabs)) {
                            rc = curve_insert(c, j, 0.5 * (c->p[j] + c->p[j + 1]), e, s2);
                            if (s2 == SG_OK)
                                *ext = fmax(*ext, fabs(e));
                            j++; /* past the new sample: its halves wait for the next round */
                            added++;
                        }
                    }
                }
        }
        free(rays);
        free(rows);
        free(st);
        if (rc != SG_OK)
            return rc == SG_ENOMEM ? sg_diag_set(d, SG_ENOMEM, "out of memory") : rc;
        if (!added)
            return SG_OK;
    }
    return SG_OK;
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
    double c0 = 0.0, c0v[SG_MAX_FIELDS], ext = 0.0;
    int c0st = SG_OK, c0stv[SG_MAX_FIELDS];

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
        if ((rc = sg_batch_open(sys, cat, &to, o->nthreads, &b, d)) != SG_OK)
            goto done;
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
        /* The refinement's rays are the pupil's, stopped as usual. */
        sg_batch_set_reference(b, 0);
        if (rc != SG_OK)
            goto done;
        if (o->opd) {
            /* A tracer at this wavelength, for the OPD in its waves; the
             * spheres are the primary wavelength's whichever traces them. */
            sg_tracer_free(tw);
            if ((rc = sg_tracer_open(sys, cat, &to, &tw, d)) != SG_OK)
                goto done;
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
                out->ref_x[f] = st[r] == SG_OK ? sg_an_img_x(sys, &rows[r]) : 0.0;
                out->ref_y[f] = st[r] == SG_OK ? sg_an_img_y(sys, &rows[r]) : 0.0;
            }
            if (o->opd) {
                /* This wavelength's chief ray: its OPD is the curve's zero. */
                c0st = out->status[f] != SG_OK ? out->status[f] : st[r];
                opd_value(tw, &ref[f], &rows[r], &c0st, &c0);
            }
            c0v[f] = c0;
            c0stv[f] = c0st;
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
                t->e[j] = t->status[j] == SG_OK ? sg_an_img_y(sys, &rows[it]) - out->ref_y[f] : 0.0;
                s->e[j] = s->status[j] == SG_OK ? sg_an_img_x(sys, &rows[is]) - out->ref_x[f] : 0.0;
            }
            for (j = 0; j < np; j++) {
                if (t->status[j] == SG_OK)
                    ext = fmax(ext, fabs(t->e[j]));
                if (s->status[j] == SG_OK)
                    ext = fmax(ext, fabs(s->e[j]));
            }
        }
        if (o->refine && (rc = refine_curves(sys, o, out, w, b, tw, ref, c0v, c0stv, &ext, d)) !=
                             SG_OK)
            goto done;
        sg_batch_free(b);
        b = NULL;
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
