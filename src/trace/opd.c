/*
 * opd.c - the reference sphere and the optical path difference.
 *
 * Zemax's convention (sagitta(1)): the sphere is centred on the primary
 * wavelength's chief ray's point on the image surface and passes through
 * the axial point of the paraxial exit pupil.  A ray's point on it lies on
 * the ray's last segment, extended backwards where the pupil is virtual.
 * OPD = (chief's optical path to the sphere - the ray's) / lambda, in waves
 * of the ray's own wavelength: positive where the wavefront is ahead of
 * the sphere.
 *
 * Everything is formed from the rows' doubles and the double-double
 * optical path, in double-double: an object 500 km away gives paths of
 * 5e8 mm, where one rounding of a double is 1e-4 waves.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trace_int.h"

/* One micrometre in lens units. */
double sg_um_in_units(const sg_system *sys)
{
    if (strcmp(sys->units, "cm") == 0)
        return 1e-4;
    if (strcmp(sys->units, "in") == 0)
        return 1e-3 / 25.4;
    if (strcmp(sys->units, "m") == 0)
        return 1e-6;
    return 1e-3;
}

double sg_tracer_wavelength(const sg_tracer *t)
{
    return t->sys->wave[t->wave].um;
}

/* Bounds on each coordinate's error of a row's point whose error_bound
 * is eb.  The precise and mpfr methods round a more precise point to
 * double, and eb is the larger coordinate's half ulp plus the rest (exact
 * to subtract, by Sterbenz's lemma); each coordinate errs by its own half
 * ulp plus that rest.  The classic method's estimate is kept whole. */
void sg_point_errors(const sg_tracer *t, double x, double y, double z, double eb,
                     double e[3])
{
    double c[3] = {x, y, z}, half = 0.5 * sg_ulp_of(sg_max_abs3(x, y, z)), rest;
    int k;
    rest = t->o.method == SG_METHOD_CLASSIC || !(eb >= half) ? eb : (eb - half) * (1.0 + 4.0 * U53);
    for (k = 0; k < 3; k++)
        e[k] = t->o.method == SG_METHOD_CLASSIC ? eb
                                                : fmin(eb, rest + 0.5 * sg_ulp_of(c[k]));
}

/* The exact difference a - b as a pair. */
static dd diff(double a, double b)
{
    return dd_two_sum(a, -b);
}

static dd dot3(const dd a[3], const dd b[3])
{
    return dd_add(dd_add(dd_mul(a[0], b[0]), dd_mul(a[1], b[1])), dd_mul(a[2], b[2]));
}

int sg_opd_reference(sg_tracer *t, double hx, double hy, sg_opd_ref *ref, sg_diag *d)
{
    sg_tracer *p;
    sg_ray_surface *rows, *c;
    dd ec[3];
    double ez;
    int n, rc;
    if (!t || !ref)
        return sg_diag_set(d, SG_EINVAL, "opd reference: no tracer or no result");
    memset(ref, 0, sizeof *ref);
    ref->hx = hx;
    ref->hy = hy;
    p = t->prim ? t->prim : t;
    n = p->n;
    ez = p->px.exp_pos;
    ref->um = sg_tracer_wavelength(p);
    ref->n_image = fabs(p->nsigned[n - 1]);
    ref->status = SG_OK;
    if (!isfinite(ez)) {
        ref->status = SG_EUNSUPPORTED;
        return sg_diag_set(d, SG_EUNSUPPORTED,
                           "opd reference: the paraxial exit pupil is at infinity (an "
                           "image-space telecentric system); the reference sphere is not defined");
    }
    rows = malloc((size_t)n * sizeof *rows);
    if (!rows) {
        ref->status = SG_ENOMEM;
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    /* The chief ray is the reference whatever stops it: traced past the
     * apertures and obscurations, as Zemax does. */
    {
        int unclipped = p->unclipped;
        p->unclipped = 1;
        rc = sg_trace_normalized(p, hx, hy, 0.0, 0.0, rows);
        p->unclipped = unclipped;
    }
    if (rc != SG_OK) {
        free(rows);
        /* A chief ray that does not reach the image leaves no sphere. */
        ref->status = rc;
        if (!sg_err_is_ray_status(rc))
            return sg_diag_set(d, rc, "opd reference: the chief ray of field (%g, %g): %s", hx,
                               hy, sg_strerror(rc));
        return SG_OK;
    }
    c = &rows[n - 1];
    ref->cx = c->x;
    ref->cy = c->y;
    ref->cz = c->z;
    ref->ez = ez;
    ref->chief_l = c->l;
    ref->chief_m = c->m;
    ref->chief_n = c->n;
    ref->centre_error_bound = c->error_bound;
    /* The sphere's radius, and the side of the image point it lies on
     * along the chief ray. */
    ec[0] = diff(0.0, c->x);
    ec[1] = diff(0.0, c->y);
    ec[2] = diff(ez, c->z);
    {
        dd r2 = dot3(ec, ec), rr = dd_sqrt(r2);
        double side = ec[0].hi * c->l + ec[1].hi * c->m + ec[2].hi * c->n;
        dd os;
        ref->radius = rr.hi;
        ref->radius_lo = rr.lo;
        ref->side = side < 0.0 ? -1.0 : 1.0;
        /* The chief ray meets the sphere its radius from the centre. */
        os = dd_add(dd_add_d(dd_from(c->opl), c->opl_lo),
                    dd_mul_d(rr, ref->side * ref->n_image));
        ref->chief_opl = os.hi;
        ref->chief_opl_lo = os.lo;
        ref->chief_opl_error_bound =
            sg_bound_up(c->opl_error_bound + 8.0 * DD_U * (fabs(os.hi) + fabs(rr.hi)));
    }
    free(rows);
    return SG_OK;
}

int sg_opd_of_ray(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *img,
                  sg_opd *out)
{
    dd w[3], dv[3], a, b, c, disc, s, dist, osr, opd;
    double nimg, lam, cosphi, tanphi, sx, sy, sz, e, nr[3], nc[3];
    if (!t || !ref || !img || !out)
        return SG_EINVAL;
    memset(out, 0, sizeof *out);
    out->opd_waves = out->error_bound = out->ex = out->ey = NAN;
    out->sphere_x = out->sphere_y = out->sphere_z = out->opl = out->opl_lo = NAN;
    if (ref->status != SG_OK) {
        out->status = ref->status;
        return SG_OK;
    }
    if (img->status != SG_OK) {
        out->status = img->status;
        return SG_OK;
    }
    nimg = fabs(t->nsigned[t->n - 1]);
    lam = sg_tracer_wavelength(t) * sg_um_in_units(t->sys);
    out->ex = img->x - ref->cx;
    out->ey = img->y - ref->cy;
    /* The point P + s D on the sphere |X - C| = R, with D the row's
     * direction as it is (its length differs from 1 by a rounding, which
     * over a radius of metres would be 1e-13 mm): a s^2 + 2 b s + c = 0
     * with W = P - C, a = D.D, b = W.D, c = W.W - R^2. */
    w[0] = diff(img->x, ref->cx);
    w[1] = diff(img->y, ref->cy);
    w[2] = diff(img->z, ref->cz);
    dv[0] = dd_from(img->l);
    dv[1] = dd_from(img->m);
    dv[2] = dd_from(img->n);
    a = dot3(dv, dv);
    b = dot3(w, dv);
    {
        dd rr = {ref->radius, ref->radius_lo};
        c = dd_sub(dot3(w, w), dd_sqr(rr));
    }
    disc = dd_sub(dd_sqr(b), dd_mul(a, c));
    if (!(disc.hi >= 0.0)) {
        /* The ray's line passes the sphere by: no point to compare. */
        out->status = SG_EMISS;
        return SG_OK;
    }
    /* The root on the sphere's side, formed without cancellation: the
     * other root's partner q / a or c / q. */
    {
        dd sq = dd_sqrt(disc), q;
        sq.hi *= ref->side;
        sq.lo *= ref->side;
        if (ref->side * b.hi <= 0.0) {
            q = dd_sub(sq, b); /* -b + side sqrt: no cancellation */
            s = dd_div(q, a);
        } else {
            q = dd_sub(dd_neg(b), sq);
            s = q.hi != 0.0 ? dd_div(c, q) : dd_from(0.0);
        }
    }
    dist = dd_mul(s, dd_sqrt(a));
    osr = dd_add(dd_add_d(dd_from(img->opl), img->opl_lo), dd_mul_d(dist, nimg));
    opd = dd_sub(dd_add_d(dd_from(ref->chief_opl), ref->chief_opl_lo), osr);
    out->opd_waves = (opd.hi + opd.lo) / lam;
    out->opl = osr.hi;
    out->opl_lo = osr.lo;
    sx = img->x + s.hi * img->l;
    sy = img->y + s.hi * img->m;
    sz = img->z + s.hi * img->n;
    out->sphere_x = sx;
    out->sphere_y = sy;
    out->sphere_z = sz;
    /* The sphere's unit normals where the ray and the chief ray meet it,
     * and the angle between the ray and its normal. */
    {
        double gx = w[0].hi + s.hi * img->l, gy = w[1].hi + s.hi * img->m,
               gz = w[2].hi + s.hi * img->n;
        double g = sqrt(gx * gx + gy * gy + gz * gz), dl = sqrt(a.hi);
        if (!(g > 0.0))
            g = 1.0;
        nr[0] = gx / g;
        nr[1] = gy / g;
        nr[2] = gz / g;
        /* The unit vector from the centre to the pupil's point. */
        nc[0] = -ref->cx / ref->radius;
        nc[1] = -ref->cy / ref->radius;
        nc[2] = (ref->ez - ref->cz) / ref->radius;
        cosphi = fabs(nr[0] * img->l + nr[1] * img->m + nr[2] * img->n) / dl;
        if (cosphi > 1.0)
            cosphi = 1.0;
        tanphi = cosphi > 0.0 ? sqrt(fmax(0.0, 1.0 - cosphi * cosphi)) / cosphi : INFINITY;
    }
    /* The bound, in lens units.  First both optical paths' own bounds.
     * The ray's point, off by e_k in coordinate k, moves the sphere point
     * along the ray by sum e_k |N_k| / cos(phi); the direction, off by
     * e_D, turns it by |s| sqrt(3) e_D, which moves it along the ray by
     * that times tan(phi).  The centre is the chief ray's point rounded to
     * double: off by c_k, it changes the difference of the two paths by
     * n (N . dC / cos(phi) + U . dC (1 / cos(phi) - 1)), U the unit vector
     * from the centre to the pupil's point (the derivative of the sphere's
     * crossing and radius in C).  Then the roundings of the pairs. */
    {
        double ep[3], ec[3], sec = 1.0 / cosphi, pt = 0.0, ct = 0.0, dr = 0.0;
        int k;
        sg_point_errors(t, img->x, img->y, img->z, img->error_bound, ep);
        sg_point_errors(t, ref->cx, ref->cy, ref->cz, ref->centre_error_bound, ec);
        for (k = 0; k < 3; k++) {
            pt += ep[k] * fabs(nr[k]);
            ct += ec[k] * fabs(nr[k]) * sec;
            dr += ec[k] * fabs(nc[k]);
        }
        e = ref->chief_opl_error_bound + img->opl_error_bound +
            nimg * (pt * sec +
                    fabs(s.hi) * SG_SQRT3 * img->dir_error_bound *
                        (tanphi + SG_SQRT3 * img->dir_error_bound) +
                    ct + dr * (sec - 1.0)) +
            16.0 * DD_U * (fabs(osr.hi) + fabs(ref->chief_opl) + ref->radius);
    }
    out->error_bound = sg_bound_up(e / lam + 4.0 * U53 * fabs(out->opd_waves));
    out->status = isfinite(out->opd_waves) && isfinite(out->error_bound) ? SG_OK : SG_ERANGE;
    return SG_OK;
}

int sg_trace_opd(sg_tracer *t, const sg_opd_ref *ref, double px, double py, sg_ray_surface *out,
                 sg_opd *res)
{
    int rc;
    if (!t || !ref || !out || !res)
        return SG_EINVAL;
    rc = sg_trace_normalized(t, ref->hx, ref->hy, px, py, out);
    sg_opd_of_ray(t, ref, &out[t->n - 1], res);
    return rc;
}
