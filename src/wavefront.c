/*
 * wavefront.c - a wavefront map over the pupil from any source of OPD,
 * with its RMS and P-V and its Zernike coefficients.
 *
 * The OPD comes through a callback, so the analysis does not depend on how
 * the OPD is traced: the trace's OPD (issue 15, item 1) plugs in as one
 * such function.  The grid is Zemax's: n x n points spanning the square
 * [-1, 1]^2 of normalized pupil coordinates, those outside the unit
 * circle left out.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

void sg_wavefront_free(sg_wavefront *w)
{
    if (!w)
        return;
    free(w->map);
    free(w->valid);
    w->map = NULL;
    w->valid = NULL;
}

int sg_wavefront_compute(sg_opd_fn opd, void *ctx, int grid, sg_zernike_kind kind,
                         int nterms, sg_wavefront *out, sg_diag *d)
{
    size_t n, k, m = 0;
    double *x = NULL, *y = NULL, *v = NULL;
    int i, j, rc, maxj;

    if (!out || !opd)
        return sg_diag_set(d, SG_EINVAL, "wavefront: no OPD function or no output");
    memset(out, 0, sizeof *out);
    if (grid < 3 || grid > 4096)
        return sg_diag_set(d, SG_ERANGE, "wavefront: grid %d; from 3 to 4096 points across "
                                         "are allowed", grid);
    maxj = kind == SG_ZERNIKE_FRINGE ? SG_ZERNIKE_FRINGE_MAX : SG_ZERNIKE_STANDARD_MAX;
    if (nterms < 1 || nterms > maxj || nterms > SG_WAVEFRONT_MAXTERMS)
        return sg_diag_set(d, SG_ERANGE, "wavefront: %d Zernike terms; from 1 to %d are "
                                         "allowed", nterms,
                           maxj < SG_WAVEFRONT_MAXTERMS ? maxj : SG_WAVEFRONT_MAXTERMS);
    n = (size_t)grid * (size_t)grid;
    out->grid = grid;
    out->map = calloc(n, sizeof *out->map);
    out->valid = calloc(n, 1);
    x = malloc(n * sizeof *x);
    y = malloc(n * sizeof *y);
    v = malloc(n * sizeof *v);
    if (!out->map || !out->valid || !x || !y || !v) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    for (j = 0; j < grid; j++)
        for (i = 0; i < grid; i++) {
            double px = -1.0 + 2.0 * i / (grid - 1), py = -1.0 + 2.0 * j / (grid - 1), w;
            k = (size_t)j * grid + i;
            if (px * px + py * py > 1.0)
                continue;
            /* A ray that fails (vignetted, missed) is left out, as in Zemax. */
            if (opd(ctx, px, py, &w) != SG_OK || !isfinite(w))
                continue;
            out->map[k] = w;
            out->valid[k] = 1;
            x[m] = px;
            y[m] = py;
            v[m] = w;
            m++;
        }
    out->nvalid = m;
    rc = sg_wavefront_stats(m, x, y, v, 0, &out->rms_chief, &out->pv_chief, d);
    if (rc == SG_OK)
        rc = sg_wavefront_stats(m, x, y, v, 1, &out->rms_centroid, &out->pv_centroid, d);
    if (rc == SG_OK)
        rc = sg_zernike_fit(kind, nterms, m, x, y, v, out->coef, &out->fit_rms, d);
    if (rc != SG_OK)
        goto fail;
    out->kind = kind;
    out->nterms = nterms;
    free(x);
    free(y);
    free(v);
    return SG_OK;
fail:
    free(x);
    free(y);
    free(v);
    sg_wavefront_free(out);
    return rc;
}

void sg_wavefront_opts_init(sg_wavefront_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->field = 0;
    o->grid = 64;
    o->kind = SG_ZERNIKE_FRINGE;
    o->nterms = 37;
}

/* The traced OPD of every grid point, looked up by the callback. */
typedef struct grid_opd {
    int grid;
    const double *opd;
    const unsigned char *ok;
} grid_opd;

static int grid_lookup(void *ctx, double px, double py, double *w)
{
    const grid_opd *g = ctx;
    long i = lround((px + 1.0) * 0.5 * (g->grid - 1)), j = lround((py + 1.0) * 0.5 * (g->grid - 1));
    size_t k;
    if (i < 0 || j < 0 || i >= g->grid || j >= g->grid)
        return SG_ERANGE;
    k = (size_t)j * (size_t)g->grid + (size_t)i;
    if (!g->ok[k])
        return SG_EMISS;
    *w = g->opd[k];
    return SG_OK;
}

int sg_wavefront_trace(const sg_system *sys, const sg_catalog *cat,
                       const sg_wavefront_opts *o, sg_wavefront *out, sg_opd_ref *ref_out,
                       sg_diag *d)
{
    sg_trace_opts to;
    sg_tracer *t = NULL;
    sg_batch *b = NULL;
    sg_opd_ref ref;
    sg_ray_in *rays = NULL;
    sg_ray_surface *rows = NULL;
    sg_opd *res = NULL;
    int *st = NULL, last, rc;
    double hx, hy, *opd = NULL, piston = 0.0;
    unsigned char *ok = NULL;
    size_t n, blk, k, start;
    grid_opd g;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "wavefront: no system, options or result");
    memset(out, 0, sizeof *out);
    if (o->grid < 3 || o->grid > 4096)
        return sg_diag_set(d, SG_ERANGE, "wavefront: grid %d; from 3 to 4096 points across "
                                         "are allowed", o->grid);
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    if (o->field >= sys->nfield)
        return sg_diag_set(d, SG_ERANGE, "wavefront: field %d is not one of 1 to %d",
                           o->field + 1, sys->nfield);
    if (o->trace.wave >= sys->nwave)
        return sg_diag_set(d, SG_ERANGE, "wavefront: wavelength %d is not one of 1 to %d",
                           o->trace.wave + 1, sys->nwave);
    if (o->field >= 0)
        sg_field_normalized(sys, o->field, &hx, &hy);
    else {
        hx = o->hx;
        hy = o->hy;
    }
    to = o->trace;
    if (to.wave < 0)
        to.wave = sys->primary_wave;
    if (!(t = sg_tracer_new(sys, cat, &to, d)))
        return d && d->code ? d->code : SG_ENOMEM;
    if ((rc = sg_opd_reference(t, hx, hy, &ref, d)) != SG_OK)
        goto done;
    if (ref.status != SG_OK) {
        rc = sg_diag_set(d, ref.status, "wavefront: the chief ray of field (%.6g, %.6g) "
                                        "fails: %s", hx, hy, sg_strerror(ref.status));
        goto done;
    }
    if (ref_out)
        *ref_out = ref;
    if (to.wave != sys->primary_wave) {
        /* At another wavelength the map is referred to that wavelength's own
         * chief ray, as Zemax's map of one wavelength is to its chief ray:
         * the chief ray's OPD against the primary sphere (a chromatic
         * piston) is taken away, as the OPD fan does. */
        sg_ray_surface *cr = malloc((size_t)sys->nsurf * sizeof *cr);
        sg_opd c0;
        if (!cr) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto done;
        }
        /* This wavelength's chief ray, past the apertures and obscurations
         * as the primary one is (sg_opd_reference). */
        sg_tracer_set_reference(t, 1);
        rc = sg_trace_opd(t, &ref, 0.0, 0.0, cr, &c0);
        sg_tracer_set_reference(t, 0);
        free(cr);
        if (rc == SG_OK && c0.status != SG_OK)
            rc = c0.status;
        if (rc != SG_OK) {
            rc = sg_diag_set(d, rc, "wavefront: the chief ray of field (%.6g, %.6g) at "
                                    "wavelength %d fails: %s", hx, hy, to.wave + 1,
                             sg_strerror(rc));
            goto done;
        }
        piston = c0.opd_waves;
    }
    n = (size_t)o->grid * (size_t)o->grid;
    blk = o->block ? o->block : 65536;
    if (blk > n)
        blk = n;
    opd = malloc(n * sizeof *opd);
    ok = calloc(n, 1);
    rays = malloc(blk * sizeof *rays);
    rows = malloc(blk * sizeof *rows);
    st = malloc(blk * sizeof *st);
    res = malloc(blk * sizeof *res);
    if (!opd || !ok || !rays || !rows || !st || !res) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    if (!(b = sg_batch_new(sys, cat, &to, o->nthreads, d))) {
        rc = d && d->code ? d->code : SG_ENOMEM;
        goto done;
    }
    last = sys->nsurf - 1;
    /* Grid points in blocks; the same pupil coordinates as sg_wavefront_compute. */
    for (start = 0; start < n; start += blk) {
        size_t m = n - start < blk ? n - start : blk;
        for (k = 0; k < m; k++) {
            size_t q = start + k;
            int i = (int)(q % (size_t)o->grid), j = (int)(q / (size_t)o->grid);
            rays[k].v[0] = hx;
            rays[k].v[1] = hy;
            rays[k].v[2] = -1.0 + 2.0 * i / (o->grid - 1);
            rays[k].v[3] = -1.0 + 2.0 * j / (o->grid - 1);
            rays[k].v[4] = rays[k].v[5] = 0.0;
        }
        if ((rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, m, &last, 1, rows, st, d)) !=
            SG_OK)
            goto done;
        /* The block's OPDs on vector lanes, each the bits sg_opd_of_ray
         * gives (tests/test_opd_vec.c); a failed ray's row only sets its
         * status. */
        sg_opd_of_rays(t, &ref, rows, 1, m, res);
        for (k = 0; k < m; k++) {
            const sg_opd *r = &res[k];
            if (st[k] != SG_OK || r->status != SG_OK || !isfinite(r->opd_waves))
                continue;
            opd[start + k] = r->opd_waves - piston;
            ok[start + k] = 1;
        }
    }
    g.grid = o->grid;
    g.opd = opd;
    g.ok = ok;
    rc = sg_wavefront_compute(grid_lookup, &g, o->grid, (sg_zernike_kind)o->kind, o->nterms,
                              out, d);
done:
    sg_batch_free(b);
    sg_tracer_free(t);
    free(opd);
    free(ok);
    free(rays);
    free(rows);
    free(st);
    free(res);
    return rc;
}
