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
