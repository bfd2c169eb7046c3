/*
 * layout.c - a y-z cross-section of the system: each surface's profile at
 * its vertex's global z, and fans of rays in y.  In a system without
 * tilts, decenters or breaks the local frames are parallel to the global
 * one, so a point's global z is its local z plus the sum of the
 * thicknesses before it (surface 1 at 0); otherwise each point goes
 * through its surface's global frame (sg_global_frames, surface 1 the
 * reference, as in Zemax's layouts) and is drawn projected on y-z.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "analysis_int.h"
#include "shape.h"

void sg_layout_opts_init(sg_layout_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->nrays = 7;
    o->field = -1;
    o->profile_pts = 41;
}

void sg_layout_free(sg_layout *l)
{
    int k;
    if (!l)
        return;
    for (k = 0; l->surf && k < l->nsurf - 1; k++) {
        free(l->surf[k].y);
        free(l->surf[k].z);
    }
    for (k = 0; l->ray && k < l->nray; k++) {
        free(l->ray[k].y);
        free(l->ray[k].z);
    }
    free(l->surf);
    free(l->ray);
    l->surf = NULL;
    l->ray = NULL;
}

/* A local point of surface i as drawn: global y and z. */
static void to_yz(const sg_frame *gf, const double *z0, int i, double x, double y, double z,
                  double *gy, double *gz)
{
    if (!gf) {
        *gy = y;
        *gz = z + z0[i];
        return;
    }
    *gy = gf[i].R[1][0] * x + gf[i].R[1][1] * y + gf[i].R[1][2] * z + gf[i].o[1];
    *gz = gf[i].R[2][0] * x + gf[i].R[2][1] * y + gf[i].R[2][2] * z + gf[i].o[2];
}

static void extend(sg_layout *l, double y, double z, int *first)
{
    if (*first) {
        l->ymin = l->ymax = y;
        l->zmin = l->zmax = z;
        *first = 0;
        return;
    }
    l->ymin = fmin(l->ymin, y);
    l->ymax = fmax(l->ymax, y);
    l->zmin = fmin(l->zmin, z);
    l->zmax = fmax(l->zmax, z);
}

int sg_layout_compute(const sg_system *sys, const sg_catalog *cat, const sg_layout_opts *o,
                      sg_layout *out, sg_diag *d)
{
    int fields[SG_MAX_FIELDS], nf, ns, i, j, f, rc, first = 1;
    size_t nray, r;
    double *z0 = NULL;
    sg_frame *gf = NULL;
    sg_ray_in *rays = NULL;
    sg_ray_surface *rows = NULL;
    int *st = NULL;
    double *autosd = NULL;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "layout: no system, options or result");
    memset(out, 0, sizeof *out);
    if (o->nrays < 1 || o->nrays > 10000)
        return sg_diag_set(d, SG_ERANGE, "layout: %d rays is not one of 1 to 10000", o->nrays);
    if (o->profile_pts < 2 || o->profile_pts > 100000)
        return sg_diag_set(d, SG_ERANGE, "layout: %d profile points is not one of 2 to 100000",
                           o->profile_pts);
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    nf = sg_an_select(o->field, sys->nfield, "field", fields, d);
    if (!nf)
        return SG_ERANGE;
    ns = sys->nsurf;
    nray = (size_t)nf * (size_t)o->nrays;
    out->nsurf = ns;
    out->nfield = nf;
    out->nray = (int)nray;
    z0 = calloc((size_t)ns, sizeof *z0);
    out->surf = calloc((size_t)(ns - 1), sizeof *out->surf);
    out->ray = calloc(nray, sizeof *out->ray);
    rays = malloc(nray * sizeof *rays);
    rows = malloc(nray * (size_t)ns * sizeof *rows);
    st = malloc(nray * sizeof *st);
    if (!z0 || !out->surf || !out->ray || !rays || !rows || !st) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (i = 2; i < ns; i++)
        z0[i] = z0[i - 1] + sys->surf[i - 1].thickness;
    /* "reverse" moves nothing unless its before change does. */
    for (i = 1; i < ns && !sg_surface_moves_frame(&sys->surf[i]); i++)
        ;
    if (i < ns) {
        if (!(gf = malloc((size_t)ns * sizeof *gf))) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto done;
        }
        if ((rc = sg_global_frames(sys, 1, gf, d)) != SG_OK)
            goto done;
        for (i = 1; i < ns; i++)
            z0[i] = gf[i].o[2];
    }
    for (f = 0; f < nf; f++) {
        double hx, hy;
        out->field_index[f] = fields[f];
        sg_field_normalized(sys, fields[f], &hx, &hy);
        for (j = 0; j < o->nrays; j++) {
            sg_ray_in *ri = &rays[(size_t)f * (size_t)o->nrays + (size_t)j];
            ri->v[0] = hx;
            ri->v[1] = hy;
            ri->v[2] = 0.0;
            ri->v[3] = o->nrays == 1 ? 0.0 : -1.0 + 2.0 * (double)j / (double)(o->nrays - 1);
        }
    }
    if ((rc = sg_trace_batch(sys, cat, &o->trace, SG_RAYS_NORMALIZED, rays, nray, o->nthreads,
                             rows, st, d)) != SG_OK)
        goto done;
    for (r = 0; r < nray; r++) {
        sg_layout_ray *lr = &out->ray[r];
        const sg_ray_surface *row = rows + r * (size_t)ns;
        lr->field = (int)(r / (size_t)o->nrays);
        lr->py = rays[r].v[3];
        lr->status = st[r];
        lr->y = malloc((size_t)ns * sizeof *lr->y);
        lr->z = malloc((size_t)ns * sizeof *lr->z);
        if (!lr->y || !lr->z) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto done;
        }
        /* From surface 1 up to the last surface reached; a vignetted ray's
         * point on the surface that stops it is real and drawn. */
        for (i = 1; i < ns; i++) {
            int ok = row[i].status == SG_OK ||
                     (sg_err_is_stopped(row[i].status) && isfinite(row[i].y) && isfinite(row[i].z));
            if (!ok)
                break;
            to_yz(gf, z0, i, row[i].x, row[i].y, row[i].z, &lr->y[lr->npts], &lr->z[lr->npts]);
            extend(out, lr->y[lr->npts], lr->z[lr->npts], &first);
            lr->npts++;
            if (row[i].status != SG_OK)
                break;
        }
    }
    /* Zemax draws a semi-diameter that is not fixed as the automatic one,
     * so no ray passes outside a lens.  Where that cannot be found (a ray
     * of the edge fails), the stored values and the rays drawn serve. */
    for (i = 1; i < ns && sys->surf[i].sd_fixed; i++)
        ;
    if (i < ns && (autosd = calloc((size_t)ns, sizeof *autosd)) != NULL) {
        sg_semidiam_opts so;
        sg_semidiam_opts_init(&so);
        so.trace.method = o->trace.method;
        if (sg_semi_diameters(sys, cat, &so, autosd, NULL) != SG_OK) {
            free(autosd);
            autosd = NULL;
        }
    }
    for (i = 1; i < ns; i++) {
        sg_layout_surface *s = &out->surf[i - 1];
        const sg_surface *su = &sys->surf[i];
        sg_shape sh;
        int gen;
        double sd = su->semi_diameter;
        if (!su->sd_fixed && autosd && autosd[i] > 0.0)
            sd = autosd[i];
        int np = o->profile_pts;
        s->z0 = z0[i];
        s->mirror = su->type != SG_SURF_COORDBRK && su->mat.kind == SG_MAT_MIRROR;
        s->glass_after = su->mat.kind == SG_MAT_GLASS || su->mat.kind == SG_MAT_INDEX ||
                         su->mat.kind == SG_MAT_MODEL;
        if (su->type == SG_SURF_COORDBRK) {
            /* A break has no profile; it still takes a place. */
            s->glass_after = 0;
            for (j = i - 1; j > 0 && sys->surf[j].type == SG_SURF_COORDBRK; j--)
                ;
            s->glass_after = sys->surf[j].mat.kind == SG_MAT_GLASS ||
                             sys->surf[j].mat.kind == SG_MAT_INDEX ||
                             sys->surf[j].mat.kind == SG_MAT_MODEL;
            continue;
        }
        if (!(sd > 0.0)) {
            /* Zemax's automatic semi-diameter: the largest ray height there. */
            sd = 0.0;
            for (r = 0; r < nray; r++) {
                const sg_ray_surface *q = rows + r * (size_t)ns + i;
                if (q->status == SG_OK)
                    sd = fmax(sd, hypot(q->x, q->y));
            }
        }
        s->sd = sd;
        s->y = malloc((size_t)np * sizeof *s->y);
        s->z = malloc((size_t)np * sizeof *s->z);
        if (!s->y || !s->z) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto done;
        }
        /* A shape of its own is prepared once for the profile's points. */
        gen = sg_shape_ops_of(su->type) && sg_shape_prepare(su, &sh, i, NULL) == SG_OK;
        for (j = 0; j < np; j++) {
            double y = -sd + 2.0 * sd * (double)j / (double)(np - 1);
            double z = gen ? sg_shape_sag(&sh, 0.0, y) : sg_surface_sag(su, 0.0, y);
            if (!isfinite(z))
                continue; /* beyond the conic's domain: nothing to draw */
            to_yz(gf, z0, i, 0.0, y, z, &s->y[s->npts], &s->z[s->npts]);
            extend(out, s->y[s->npts], s->z[s->npts], &first);
            s->npts++;
        }
    }
    rc = SG_OK;
done:
    free(autosd);
    free(z0);
    free(gf);
    free(rays);
    free(rows);
    free(st);
    if (rc != SG_OK)
        sg_layout_free(out);
    return rc;
}
