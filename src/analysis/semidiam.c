/*
 * semidiam.c - automatic semi-diameters: on each surface, the largest
 * radial height of the real rays through the edge of the pupil, over
 * every field and wavelength, as Zemax computes the clear semi-diameter
 * of a surface whose semi-diameter is not fixed.
 *
 * A ring of rays on the pupil's edge finds each surface's highest ray;
 * a golden-section search along the edge then refines each maximum, so the
 * figure does not depend on how finely the ring was sampled.
 *
 * Zemax's stored figures (o->zemax) are the highest of the rays at the top
 * and bottom of the pupil, and at its sides only for a field off the axis
 * that lies off the y axis or in a system that is not rotationally
 * symmetric (zemax_asymmetric): where a surface's highest ray lies between
 * them (sc_vfac1.zmx's stop, pupil angle 40 degrees) Zemax's figure is
 * below the edge's, and where a side ray of a centred system is highest
 * (the image of US05331467-1.zmx), or of the axial field of a cylinder
 * lens (thorlabs_lj1598l1.zmx), too (tests/test_semidiam.c,
 * tests/data/zmx/README.md).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"

#define TWO_PI 6.283185307179586

/* The height on surface i of the ray through the pupil edge at angle a
 * (Px = sin a, Py = cos a, so a = 0 is the top of the pupil); -1 when the
 * ray does not reach it. */
static double height(sg_tracer *t, double hx, double hy, double a, int i, sg_ray_surface *row)
{
    sg_trace_normalized(t, hx, hy, sin(a), cos(a), row);
    if (row[i].status != SG_OK)
        return -1.0;
    return hypot(row[i].x, row[i].y);
}

/* Whether the system is not rotationally symmetric, for Zemax's rays: a
 * tilt, decenter or coordinate break, or a sag or phase that is not (the
 * apertures, of which its files say nothing, are left out). */
static int zemax_asymmetric(const sg_system *sys)
{
    int i;
    for (i = 1; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        switch (s->type) {
        case SG_SURF_COORDBRK:
        case SG_SURF_TOROIDAL:
        case SG_SURF_BICONIC:
        case SG_SURF_ZERNIKE_FRINGE:
        case SG_SURF_ZERNIKE_STANDARD:
        case SG_SURF_XYPOLY:
        case SG_SURF_DGRATING:
        case SG_SURF_ZERNIKE_PHASE:
            return 1;
        default:
            break;
        }
        if (!sg_frame_change_is_zero(&s->before) ||
            (s->after_mode == SG_AFTER_EXPLICIT && !sg_frame_change_is_zero(&s->after)))
            return 1;
    }
    return 0;
}

void sg_semidiam_opts_init(sg_semidiam_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->trace.clip = 0;
    o->ring = 64;
    o->refine = 40;
}

int sg_semi_diameters(const sg_system *sys, const sg_catalog *cat, const sg_semidiam_opts *o,
                      double *sd, sg_diag *d)
{
    sg_semidiam_opts def;
    int n, w, f, k, i, rc = SG_OK, asym;
    sg_ray_surface *row = NULL;
    double *best = NULL, *besta = NULL;
    if (!o) {
        sg_semidiam_opts_init(&def);
        o = &def;
    }
    if (o->ring < 4 || o->ring > 1000000)
        return sg_diag_set(d, SG_ERANGE, "semi-diameters: a ring of %d rays is not one of 4 "
                           "to 1000000", o->ring);
    if (o->refine < 0 || o->refine > 200)
        return sg_diag_set(d, SG_ERANGE, "semi-diameters: %d refinement steps is not one of "
                           "0 to 200", o->refine);
    if ((rc = sg_system_check(sys, cat, d)) != SG_OK)
        return rc;
    asym = zemax_asymmetric(sys);
    n = sys->nsurf;
    row = malloc((size_t)n * sizeof *row);
    best = malloc((size_t)n * sizeof *best);
    besta = malloc((size_t)n * sizeof *besta);
    if (!row || !best || !besta) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (i = 0; i < n; i++)
        sd[i] = 0.0;
    for (w = 0; w < sys->nwave; w++) {
        sg_trace_opts to = o->trace;
        sg_tracer *t;
        to.wave = w;
        if ((rc = sg_tracer_open(sys, cat, &to, &t, d)) != SG_OK)
            goto done;
        for (f = 0; f < sys->nfield; f++) {
            double hx, hy;
            sg_field_normalized(sys, f, &hx, &hy);
            for (i = 0; i < n; i++) {
                best[i] = -1.0;
                besta[i] = 0.0;
            }
            if (o->zemax) {
                /* Zemax's rays, at exact pupil coordinates: top and
                 * bottom, then the sides. */
                static const double px[4] = {0.0, 0.0, 1.0, -1.0}, py[4] = {1.0, -1.0, 0.0, 0.0};
                int nr = (hx != 0.0 || (hy != 0.0 && asym)) ? 4 : 2;
                for (k = 0; k < nr; k++) {
                    sg_trace_normalized(t, hx, hy, px[k], py[k], row);
                    for (i = 1; i < n; i++) {
                        if (row[i].status != SG_OK)
                            break;
                        sd[i] = fmax(sd[i], hypot(row[i].x, row[i].y));
                    }
                }
                continue;
            }
            for (k = 0; k < o->ring; k++) {
                double a = TWO_PI * (double)k / (double)o->ring;
                sg_trace_normalized(t, hx, hy, sin(a), cos(a), row);
                for (i = 1; i < n; i++) {
                    double h;
                    if (row[i].status != SG_OK)
                        break;
                    h = hypot(row[i].x, row[i].y);
                    if (h > best[i]) {
                        best[i] = h;
                        besta[i] = a;
                    }
                }
            }
            /* Golden-section search for the maximum between the ring's
             * neighbours of the best ray; a ray lost inside the bracket
             * leaves the ring's figure. */
            for (i = 1; i < n; i++) {
                const double g = 0.6180339887498949;
                double lo = besta[i] - TWO_PI / o->ring, hi = besta[i] + TWO_PI / o->ring;
                double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1, f2;
                if (best[i] < 0.0)
                    continue;
                f1 = height(t, hx, hy, x1, i, row);
                f2 = height(t, hx, hy, x2, i, row);
                for (k = 0; k < o->refine; k++) {
                    if (f1 >= f2) {
                        hi = x2;
                        x2 = x1;
                        f2 = f1;
                        x1 = hi - g * (hi - lo);
                        f1 = height(t, hx, hy, x1, i, row);
                    } else {
                        lo = x1;
                        x1 = x2;
                        f1 = f2;
                        x2 = lo + g * (hi - lo);
                        f2 = height(t, hx, hy, x2, i, row);
                    }
                    best[i] = fmax(best[i], fmax(f1, f2));
                }
                sd[i] = fmax(sd[i], best[i]);
            }
        }
        sg_tracer_free(t);
    }
done:
    free(row);
    free(best);
    free(besta);
    return rc;
}
