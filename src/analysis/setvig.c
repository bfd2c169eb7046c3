/*
 * setvig.c - Zemax's "Set Vignetting": for each field, the vignetting
 * factors (VDX, VDY, VCX, VCY) whose compressed and decentred pupil has
 * its four edge rays (top, bottom, left and right) just passing every
 * aperture, at the primary wavelength.
 *
 * As Zemax describes its own algorithm: a grid of rays over the unit pupil
 * finds the rays that pass, their centroid is the centre of the pupil that
 * passes, and each edge is then found along the lines through the centroid
 * parallel to the axes.  Here each edge is first bracketed by samples
 * along its line (so a central obscuration, whose centroid does not pass,
 * still has outer edges) and then found by bisection, to a tolerance the
 * caller sets.  The edges give the factors in closed form:
 *   VDY = (top + bottom) / 2, VCY = 1 - (top - bottom) / 2,
 * and the same in x, since a traced pupil coordinate is VDY + Py (1 - VCY).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"

void sg_setvig_opts_init(sg_setvig_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->grid = 64;
    o->line = 256;
    o->tol = 1e-12;
}

/* Whether the ray through pupil point (px, py) passes every surface. */
static int passes(sg_tracer *t, double hx, double hy, double px, double py, sg_ray_surface *row,
                  int n)
{
    sg_trace_normalized(t, hx, hy, px, py, row);
    return row[n - 1].status == SG_OK;
}

/* The edge of the passing pupil along the line c + s u (u a unit axis),
 * for s from 0 towards the unit circle's edge smax in direction sign:
 * the passing sample farthest out is bracketed with the failing one past
 * it, then bisected.  *found is 0 when no sample of the line passes. */
static double edge(sg_tracer *t, double hx, double hy, double cx, double cy, int xaxis,
                   double sign, double smax, const sg_setvig_opts *o, sg_ray_surface *row, int n,
                   int *found)
{
    double lo = 0.0, hi, s;
    int k, last = -1;
#define AT(s_) (xaxis ? passes(t, hx, hy, cx + sign * (s_), cy, row, n)   \
                      : passes(t, hx, hy, cx, cy + sign * (s_), row, n))
    *found = 0;
    /* The line's far end first: a pupil not clipped there is the whole. */
    if (AT(smax)) {
        *found = 1;
        return smax;
    }
    /* Samples from the far end inwards to the line's other end: the first
     * that passes is the outermost passing sample. */
    for (k = o->line; k >= 0; k--) {
        s = smax * (2.0 * k / o->line - 1.0);
        if (AT(s)) {
            last = k;
            break;
        }
    }
    if (last < 0)
        return 0.0;
    *found = 1;
    lo = smax * (2.0 * last / o->line - 1.0);
    hi = last == o->line ? smax : smax * (2.0 * (last + 1) / o->line - 1.0);
    while (hi - lo > o->tol) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi)
            break;
        if (AT(mid))
            lo = mid;
        else
            hi = mid;
    }
#undef AT
    return lo;
}

int sg_set_vignetting(const sg_system *sys, const sg_catalog *cat, const sg_setvig_opts *o,
                      sg_vigfactors *out, sg_diag *d)
{
    sg_setvig_opts def;
    sg_system *plain = NULL;
    sg_tracer *t = NULL;
    sg_ray_surface *row = NULL;
    sg_trace_opts to;
    int f, i, j, n, rc = SG_OK;

    if (!sys || !out)
        return sg_diag_set(d, SG_EINVAL, "set vignetting: no system or no output");
    if (!o) {
        sg_setvig_opts_init(&def);
        o = &def;
    }
    if (o->grid < 4 || o->grid > 4096)
        return sg_diag_set(d, SG_ERANGE, "set vignetting: a grid of %d is not one of 4 to 4096",
                           o->grid);
    if (o->line < 4 || o->line > 1000000)
        return sg_diag_set(d, SG_ERANGE, "set vignetting: %d samples a line is not one of 4 to "
                           "1000000", o->line);
    if (!(o->tol >= 1e-15 && o->tol <= 1e-2))
        return sg_diag_set(d, SG_ERANGE, "set vignetting: the tolerance %g is not between 1e-15 "
                           "and 1e-2", o->tol);
    if ((rc = sg_system_check(sys, cat, d)) != SG_OK)
        return rc;
    /* The factors found are of the unvignetted pupil: trace without any. */
    if (!(plain = sg_system_clone(sys)))
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (f = 0; f < plain->nfield; f++)
        plain->field[f].vdx = plain->field[f].vdy = plain->field[f].vcx =
            plain->field[f].vcy = plain->field[f].van = 0.0;
    to = o->trace;
    to.wave = -1;
    n = plain->nsurf;
    if (!(row = malloc((size_t)n * sizeof *row))) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    if ((rc = sg_tracer_open(plain, cat, &to, &t, d)) != SG_OK)
        goto done;
    for (f = 0; f < plain->nfield; f++) {
        double hx, hy, sx = 0.0, sy = 0.0, cx, cy, top, bot, rgt, lft, w;
        long cnt = 0;
        int f1, f2, f3, f4;
        sg_field_normalized(plain, f, &hx, &hy);
        /* The grid: cell centres inside the unit circle. */
        for (i = 0; i < o->grid; i++)
            for (j = 0; j < o->grid; j++) {
                double px = (2.0 * j + 1.0) / o->grid - 1.0, py = (2.0 * i + 1.0) / o->grid - 1.0;
                if (px * px + py * py > 1.0)
                    continue;
                if (passes(t, hx, hy, px, py, row, n)) {
                    sx += px;
                    sy += py;
                    cnt++;
                }
            }
        if (cnt == 0) {
            rc = sg_diag_set(d, SG_EVIGNETTED,
                             "set vignetting: field %d: none of the grid's rays passes the "
                             "apertures (%d by %d over the pupil)",
                             f + 1, o->grid, o->grid);
            goto done;
        }
        cx = sx / (double)cnt;
        cy = sy / (double)cnt;
        /* Each line runs across the unit circle through the centroid. */
        w = sqrt(fmax(0.0, 1.0 - cx * cx));
        top = edge(t, hx, hy, cx, 0.0, 0, 1.0, w, o, row, n, &f1);
        bot = -edge(t, hx, hy, cx, 0.0, 0, -1.0, w, o, row, n, &f2);
        w = sqrt(fmax(0.0, 1.0 - cy * cy));
        rgt = edge(t, hx, hy, 0.0, cy, 1, 1.0, w, o, row, n, &f3);
        lft = -edge(t, hx, hy, 0.0, cy, 1, -1.0, w, o, row, n, &f4);
        if (!f1 || !f2 || !f3 || !f4) {
            rc = sg_diag_set(d, SG_EVIGNETTED,
                             "set vignetting: field %d: no ray passes along the pupil's %s line "
                             "through the centroid (%.6g, %.6g)",
                             f + 1, !f1 || !f2 ? "vertical" : "horizontal", cx, cy);
            goto done;
        }
        out[f].vdy = 0.5 * (top + bot);
        out[f].vcy = 1.0 - 0.5 * (top - bot);
        out[f].vdx = 0.5 * (rgt + lft);
        out[f].vcx = 1.0 - 0.5 * (rgt - lft);
        out[f].van = 0.0;
        out[f].pass = cnt;
        out[f].cx = cx;
        out[f].cy = cy;
    }
done:
    sg_tracer_free(t);
    free(row);
    sg_system_free(plain);
    return rc;
}

void sg_set_vignetting_apply(sg_system *sys, const sg_vigfactors *vf)
{
    int i;
    for (i = 0; i < sys->nfield; i++) {
        sys->field[i].vdx = vf[i].vdx;
        sys->field[i].vdy = vf[i].vdy;
        sys->field[i].vcx = vf[i].vcx;
        sys->field[i].vcy = vf[i].vcy;
        sys->field[i].van = vf[i].van;
    }
}
