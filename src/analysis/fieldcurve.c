/*
 * fieldcurve.c - tangential and sagittal focus against field, by
 * differential real rays about the real chief ray, and distortion against
 * the paraxial image height.
 *
 * At each field two rays a pupil step +-delta from the chief ray, in the
 * tangential (Py) and then the sagittal (Px) direction, are traced to the
 * image surface and continued as straight lines; where each pair crosses
 * is that fan's focus, in the limit delta -> 0 the point Coddington's
 * equations give.  The pair is symmetric about the chief ray, so the
 * error is even in delta; two steps (delta and delta/2) remove its
 * delta^2 term (Richardson).  The focus is reported as its z distance
 * from the chief ray's intercept with the image surface (Zemax's field
 * curvature plot).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

/* z where the lines (a + s da / dn, z_a) and (b ...) cross in the plane of
 * coordinate k (0: x, 1: y). */
static double crossing(const sg_ray_surface *p, const sg_ray_surface *q, int k)
{
    double ta = (k ? p->m : p->l) / p->n, tb = (k ? q->m : q->l) / q->n;
    double a = k ? p->y : p->x, b = k ? q->y : q->x;
    /* a + ta (z - za) = b + tb (z - zb) */
    return (b - a + ta * p->z - tb * q->z) / (ta - tb);
}

/* Zemax's recipe: one ray at pupil step delta in direction k (0: Px,
 * 1: Py) against the chief ray c, both lines taken from the chief ray's
 * z (the ray's own z on a curved image is not used), so the focus is
 * the chief ray's z plus (a - c) / (tc - ta) in that plane. */
static int zemax_focus(sg_tracer *t, sg_ray_surface *buf, int n, double hy, int k,
                       double delta, const sg_ray_surface *c, double *out)
{
    double ta, tc, a, cc;
    int st = sg_trace_normalized(t, 0.0, hy, k ? 0.0 : delta, k ? delta : 0.0, buf);
    if (st != SG_OK)
        return st;
    ta = (k ? buf[n - 1].m : buf[n - 1].l) / buf[n - 1].n;
    tc = (k ? c->m : c->l) / c->n;
    a = k ? buf[n - 1].y : buf[n - 1].x;
    cc = k ? c->y : c->x;
    *out = (a - cc) / (tc - ta);
    return SG_OK;
}

/* The focus of the pair at pupil step delta in direction k (0: Px,
 * 1: Py), less the chief ray's z on the image surface. */
static int pair_focus(sg_tracer *t, sg_ray_surface *buf, int n, double hy, int k,
                      double delta, double zc, double *out)
{
    sg_ray_surface a, b;
    int st;
    st = sg_trace_normalized(t, 0.0, hy, k ? 0.0 : delta, k ? delta : 0.0, buf);
    if (st != SG_OK)
        return st;
    a = buf[n - 1];
    st = sg_trace_normalized(t, 0.0, hy, k ? 0.0 : -delta, k ? -delta : 0.0, buf);
    if (st != SG_OK)
        return st;
    b = buf[n - 1];
    *out = crossing(&a, &b, k) - zc;
    return SG_OK;
}

int sg_fieldcurve(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                  int npts, double delta, sg_fieldcurve_pt *out, sg_diag *d)
{
    return sg_fieldcurve_recipe(sys, cat, opts, npts, delta, SG_FIELDCURVE_EXACT, out, d);
}

int sg_fieldcurve_recipe(const sg_system *sys, const sg_catalog *cat,
                         const sg_trace_opts *opts, int npts, double delta, int recipe,
                         sg_fieldcurve_pt *out, sg_diag *d)
{
    sg_tracer *t;
    sg_ray_surface *buf;
    sg_paraxial p;
    double fmax = 0.0;
    int n, i, k, rc, wave;

    if (npts < 2 || npts > 100000)
        return sg_diag_set(d, SG_ERANGE, "fieldcurve: %d field points; from 2 to 100000 "
                                         "are allowed", npts);
    if (!(delta > 0.0 && delta <= 0.1))
        return sg_diag_set(d, SG_ERANGE, "fieldcurve: pupil step %g; it must be above 0 and "
                                         "at most 0.1", delta);
    if (recipe != SG_FIELDCURVE_EXACT && recipe != SG_FIELDCURVE_ZEMAX)
        return sg_diag_set(d, SG_EINVAL, "fieldcurve: unknown recipe %d", recipe);
    if (sys->field_type == SG_FIELD_REAL_IMAGE_HEIGHT)
        return sg_diag_set(d, SG_EUNSUPPORTED,
                           "fieldcurve: fields given as real image height have no paraxial "
                           "reference for distortion; use angle, object height or "
                           "paraxial image height");
    if ((rc = sg_tracer_open(sys, cat, opts, &t, d)) != SG_OK)
        return rc;
    wave = opts && opts->wave >= 0 ? opts->wave : sys->primary_wave;
    rc = sg_paraxial_compute(sys, cat, wave, &p, d);
    if (rc != SG_OK) {
        sg_tracer_free(t);
        return rc;
    }
    /* Every ray here is a reference ray (the chief ray and its
     * neighbours), traced past apertures and obscurations as Zemax does:
     * a central obscuration does not hide the field's focus. */
    sg_tracer_set_reference(t, 1);
    n = sg_tracer_nsurf(t);
    buf = malloc(sizeof *buf * (size_t)n);
    if (!buf) {
        sg_tracer_free(t);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    for (k = 0; k < sys->nfield; k++) {
        double r = sys->field_norm == SG_NORM_RADIAL ? hypot(sys->field[k].x, sys->field[k].y)
                                                     : fabs(sys->field[k].y);
        fmax = r > fmax ? r : fmax;
    }
    for (i = 0; i < npts; i++) {
        sg_fieldcurve_pt *o = &out[i];
        double hy = (double)i / (npts - 1), f1, f2, zc;
        memset(o, 0, sizeof *o);
        o->hy = hy;
        o->field = hy * fmax;
        if (sys->field_type == SG_FIELD_ANGLE) {
            double a = fmax * 3.14159265358979323846 / 180.0;
            o->parax_y = hy == 0.0 ? 0.0 : p.parax_image_height * tan(hy * a) / tan(a);
        } else {
            o->parax_y = p.parax_image_height * hy;
        }
        o->status = sg_trace_normalized(t, 0.0, hy, 0.0, 0.0, buf);
        if (o->status != SG_OK)
            continue;
        o->real_y = buf[n - 1].y;
        zc = buf[n - 1].z;
        o->distortion = o->parax_y == 0.0 ? 0.0
                                          : 100.0 * (o->real_y - o->parax_y) / o->parax_y;
        for (k = 0; k < 2 && recipe == SG_FIELDCURVE_ZEMAX; k++) {
            sg_ray_surface c = buf[n - 1];
            o->status = zemax_focus(t, buf, n, hy, k, delta, &c, k ? &o->tan_focus
                                                                   : &o->sag_focus);
            buf[n - 1] = c;
            if (o->status != SG_OK)
                break;
        }
        for (k = 0; k < 2 && recipe == SG_FIELDCURVE_EXACT; k++) {
            o->status = pair_focus(t, buf, n, hy, k, delta, zc, &f1);
            if (o->status == SG_OK)
                o->status = pair_focus(t, buf, n, hy, k, delta / 2, zc, &f2);
            if (o->status != SG_OK)
                break;
            /* f(delta) = f0 + c delta^2: f0 = (4 f(delta/2) - f(delta)) / 3. */
            if (k)
                o->tan_focus = (4.0 * f2 - f1) / 3.0;
            else
                o->sag_focus = (4.0 * f2 - f1) / 3.0;
        }
        if (o->status == SG_OK && !(isfinite(o->tan_focus) && isfinite(o->sag_focus) &&
                                    isfinite(o->distortion)))
            o->status = SG_ERANGE; /* parallel rays: a focus at infinity */
    }
    free(buf);
    sg_tracer_free(t);
    return SG_OK;
}
