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

#include "analysis_int.h"
#include "trace.h"

void sg_wavefront_free(sg_wavefront *w)
{
    if (!w)
        return;
    free(w->map);
    free(w->valid);
    w->map = NULL;
    w->valid = NULL;
}

/* Checks a grid and a Zernike set before any work. */
static int check_grid(int grid, sg_zernike_kind kind, int nterms, sg_diag *d)
{
    int maxj;
    if (grid < 3 || grid > 4096)
        return sg_diag_set(d, SG_ERANGE, "wavefront: grid %d; from 3 to 4096 points across "
                                         "are allowed", grid);
    maxj = kind == SG_ZERNIKE_FRINGE ? SG_ZERNIKE_FRINGE_MAX : SG_ZERNIKE_STANDARD_MAX;
    if (nterms < 1 || nterms > maxj || nterms > SG_WAVEFRONT_MAXTERMS)
        return sg_diag_set(d, SG_ERANGE, "wavefront: %d Zernike terms; from 1 to %d are "
                                         "allowed", nterms,
                           maxj < SG_WAVEFRONT_MAXTERMS ? maxj : SG_WAVEFRONT_MAXTERMS);
    return SG_OK;
}

/* The map and its validity, the only memory that grows with the grid
 * (9 bytes a point: 151 MB at 4096). */
static int map_alloc(int grid, sg_wavefront *out, sg_diag *d)
{
    size_t n = (size_t)grid * (size_t)grid;
    out->grid = grid;
    out->map = calloc(n, sizeof *out->map);
    out->valid = calloc(n, 1);
    if (!out->map || !out->valid) {
        sg_wavefront_free(out);
        return sg_diag_set(d, SG_ENOMEM, "out of memory: a wavefront map of %d x %d points "
                                         "needs %zu MB", grid, grid, n * 9 >> 20);
    }
    return SG_OK;
}

/* Statistics and the Zernike fit, read from the map itself. */
static int map_finish(sg_zernike_kind kind, int nterms, double data_err, sg_wavefront *out,
                      sg_diag *d)
{
    size_t k, n = (size_t)out->grid * (size_t)out->grid, m = 0;
    int rc;
    for (k = 0; k < n; k++)
        m += out->valid[k];
    out->nvalid = m;
    rc = sg_wavefront_stats_map(out->grid, out->map, out->valid, m, 0, &out->rms_chief,
                                &out->pv_chief, d);
    if (rc == SG_OK)
        rc = sg_wavefront_stats_map(out->grid, out->map, out->valid, m, 1, &out->rms_centroid,
                                    &out->pv_centroid, d);
    if (rc == SG_OK)
        rc = sg_zernike_fit_map(kind, nterms, out->grid, out->map, out->valid, m, data_err,
                                out->coef, out->coef_bound, &out->fit_rms, d);
    if (rc != SG_OK) {
        sg_wavefront_free(out);
        return rc;
    }
    out->kind = kind;
    out->nterms = nterms;
    return SG_OK;
}

int sg_wavefront_compute(sg_opd_fn opd, void *ctx, int grid, sg_zernike_kind kind,
                         int nterms, sg_wavefront *out, sg_diag *d)
{
    size_t k;
    int i, j, rc;

    if (!out || !opd)
        return sg_diag_set(d, SG_EINVAL, "wavefront: no OPD function or no output");
    memset(out, 0, sizeof *out);
    if ((rc = check_grid(grid, kind, nterms, d)) != SG_OK ||
        (rc = map_alloc(grid, out, d)) != SG_OK)
        return rc;
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
        }
    /* A callback's values carry no bound: only the fit's rounding counts. */
    return map_finish(kind, nterms, 0.0, out, d);
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
    double hx, hy, piston = 0.0, piston_err = 0.0, emax = 0.0;
    size_t n, blk, k, q, *cell = NULL;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "wavefront: no system, options or result");
    memset(out, 0, sizeof *out);
    if ((rc = check_grid(o->grid, (sg_zernike_kind)o->kind, o->nterms, d)) != SG_OK)
        return rc;
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
    if ((rc = sg_tracer_open(sys, cat, &to, &t, d)) != SG_OK)
        return rc;
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
        piston_err = c0.error_bound;
    }
    if ((rc = map_alloc(o->grid, out, d)) != SG_OK)
        goto done;
    n = (size_t)o->grid * (size_t)o->grid;
    blk = o->block ? o->block : 65536;
    if (blk > n)
        blk = n;
    rays = malloc(blk * sizeof *rays);
    rows = malloc(blk * sizeof *rows);
    st = malloc(blk * sizeof *st);
    cell = malloc(blk * sizeof *cell);
    res = malloc(blk * sizeof *res);
    if (!rays || !rows || !st || !cell || !res) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    if ((rc = sg_batch_open(sys, cat, &to, o->nthreads, &b, d)) != SG_OK)
        goto done;
    last = sys->nsurf - 1;
    /* The grid's points inside the pupil, in blocks, straight into the
     * map; the same pupil coordinates as sg_wavefront_compute. */
    for (q = 0; q < n;) {
        size_t m = 0;
        for (; q < n && m < blk; q++) {
            int i = (int)(q % (size_t)o->grid), j = (int)(q / (size_t)o->grid);
            double px = -1.0 + 2.0 * i / (o->grid - 1), py = -1.0 + 2.0 * j / (o->grid - 1);
            if (px * px + py * py > 1.0)
                continue;
            rays[m].v[0] = hx;
            rays[m].v[1] = hy;
            rays[m].v[2] = px;
            rays[m].v[3] = py;
            rays[m].v[4] = rays[m].v[5] = 0.0;
            cell[m++] = q;
        }
        if (m && (rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, m, &last, 1, rows, st, d)) !=
                     SG_OK)
            goto done;
        /* The block's OPDs on vector lanes, each the bits sg_opd_of_ray
         * gives (tests/test_opd_vec.c); a failed ray's row only sets its
         * status. */
        if (m)
            sg_opd_of_rays(t, &ref, rows, 1, m, res);
        for (k = 0; k < m; k++) {
            const sg_opd *r = &res[k];
            if (st[k] != SG_OK || r->status != SG_OK || !isfinite(r->opd_waves))
                continue;
            double e;
            out->map[cell[k]] = r->opd_waves - piston;
            out->valid[cell[k]] = 1;
            /* The ray's bound, the piston's and the difference's rounding. */
            e = r->error_bound + piston_err + 0x1p-53 * fabs(out->map[cell[k]]);
            emax = e > emax ? e : emax;
        }
        if (o->progress && o->progress(o->progress_ctx, q, n)) {
            rc = sg_diag_set(d, SG_ESTOPPED, "wavefront: stopped after %zu of %zu grid points",
                             q, n);
            goto done;
        }
    }
    rc = map_finish((sg_zernike_kind)o->kind, o->nterms, emax, out, d);
done:
    if (rc != SG_OK)
        sg_wavefront_free(out);
    sg_batch_free(b);
    sg_tracer_free(t);
    free(cell);
    free(rays);
    free(rows);
    free(st);
    free(res);
    return rc;
}
