/*
 * seidel.c - third-order (Seidel) and first-order colour sums, surface by
 * surface, from the paraxial marginal and chief rays.
 *
 * The formulas are Welford's (Aberrations of Optical Systems, 1986, ch. 8):
 * with A = n i and Abar = n ibar the refraction invariants of the marginal
 * and chief rays, H = A ybar - Abar y the Lagrange invariant and
 * D(x) = x' - x across the surface,
 *   SI   = -A^2 y D(u/n)          SII = -A Abar y D(u/n)
 *   SIII = -Abar^2 y D(u/n)       SIV = -H^2 c D(1/n)
 *   SV   = (Abar/A)(SIII + SIV)   CI = A y D(dn/n)   CII = Abar y D(dn/n)
 * SV is evaluated in a form without the division by A (derived from
 * D(u/n) = A D(1/n^2) - y c D(1/n)), so a surface where the marginal ray
 * meets the normal (A = 0) still gets its distortion.  The quartic part of
 * an even asphere, G r^4 with G = k c^3 / 8 + A4, adds 8 G (n' - n) y^4
 * (ybar / y)^j to SI, SII, SIII and SV (j = 0, 1, 2, 3), the stop-shift
 * form of a thin aspheric plate at the surface.  Mirrors use n' = -n.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shape.h"
#include "trace.h"

/* Signed indices after every surface at wavelength wave, as doubles. */
static int indices(const sg_system *sys, const sg_catalog *cat, int wave, double *out,
                   sg_diag *d)
{
    mpfr_t *idx;
    int i, n = sys->nsurf, rc;
    idx = calloc((size_t)n, sizeof *idx);
    if (!idx)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (i = 0; i < n; i++)
        mpfr_init2(idx[i], 64);
    rc = sg_indices_mpfr(sys, cat, wave, idx, d);
    for (i = 0; i < n; i++) {
        if (rc == SG_OK)
            out[i] = mpfr_get_d(idx[i], MPFR_RNDN);
        mpfr_clear(idx[i]);
    }
    free(idx);
    return rc;
}

double sg_lens_unit_mm(const sg_system *sys)
{
    if (strcmp(sys->units, "cm") == 0)
        return 10.0;
    if (strcmp(sys->units, "in") == 0)
        return 25.4;
    if (strcmp(sys->units, "m") == 0)
        return 1000.0;
    return 1.0;
}

/* A value and a bound on its error, to first order in the roundings, as
 * GSL's gsl_sf_result: so a sum that cancels to rounding noise (the
 * distortion of a mirror at the stop) can be told from a small one.
 * The inputs are the design's values (exact), curvatures and indices
 * rounded once, and the paraxial data, rounded once from MPFR. */
typedef struct ve {
    double v, e;
} ve;

#define VE_U 0x1p-53

static ve ve_exact(double v)
{
    ve r = { v, 0.0 };
    return r;
}

static ve ve_rounded(double v)
{
    ve r = { v, VE_U * fabs(v) };
    return r;
}

static ve ve_add(ve a, ve b)
{
    ve r;
    r.v = a.v + b.v;
    r.e = a.e + b.e + VE_U * fabs(r.v);
    return r;
}

static ve ve_sub(ve a, ve b)
{
    ve r;
    r.v = a.v - b.v;
    r.e = a.e + b.e + VE_U * fabs(r.v);
    return r;
}

static ve ve_mul(ve a, ve b)
{
    ve r;
    r.v = a.v * b.v;
    r.e = fabs(a.v) * b.e + fabs(b.v) * a.e + a.e * b.e + VE_U * fabs(r.v);
    return r;
}

/* a / b; an infinite bound where b's bound reaches zero. */
static ve ve_div(ve a, ve b)
{
    ve r;
    r.v = a.v / b.v;
    r.e = fabs(b.v) > b.e ? (a.e + fabs(r.v) * b.e) / (fabs(b.v) - b.e) + VE_U * fabs(r.v)
                          : INFINITY;
    return r;
}

static ve ve_neg(ve a)
{
    a.v = -a.v;
    return a;
}

/* The paraxial marginal and chief rays at each surface: heights y, yb
 * and reduced slopes w = n u, wb before the surface (index 0 unused). */
typedef struct prays {
    ve *y, *w, *yb, *wb;
} prays;

static void launch(const sg_system *sys, const sg_paraxial *p, ve n0, ve *y, ve *w, ve *yb,
                   ve *wb)
{
    ve epr = ve_rounded(0.5 * p->epd), T0 = ve_exact(sys->surf[0].thickness);
    if (sys->telecentric && isfinite(T0.v)) {
        /* The pupil at infinity: the marginal ray at the object NA's
         * slope, the chief ray a unit height parallel to the axis. */
        double u = sys->aper_type == SG_APER_OBJECT_CONE
                       ? tan(sys->aper_value * 3.14159265358979323846 / 180.0)
                       : tan(asin(sys->aper_value / fabs(n0.v)));
        ve u0 = { u, 4.0 * VE_U * fabs(u) }; /* the library's tan and asin, a few ulps */
        *y = ve_mul(u0, T0);
        *w = ve_mul(u0, n0);
        *yb = ve_exact(1.0);
        *wb = ve_exact(0.0);
    } else if (!isfinite(T0.v)) {
        *y = epr;
        *w = ve_exact(0.0);
        /* Unit slope through the pupil's centre. */
        *yb = ve_neg(ve_rounded(p->enp_pos));
        *wb = n0;
    } else {
        ve D = ve_add(ve_rounded(p->enp_pos), T0);
        ve u0 = ve_div(epr, D), ub = ve_div(ve_exact(-1.0), D);
        *y = ve_mul(u0, T0);
        *w = ve_mul(u0, n0);
        /* Unit object height, through the pupil's centre. */
        *yb = ve_add(ve_exact(1.0), ve_mul(ub, T0));
        *wb = ve_mul(ub, n0);
    }
}

/* Traces both rays from surface 1 to the image; returns the chief ray's
 * image height for the unit launch (the scale of the field). */
static ve trace_rays(const sg_system *sys, const ve *idx, const ve *phi, prays *r, ve y, ve w,
                     ve yb, ve wb)
{
    int j, n = sys->nsurf;
    for (j = 1; j < n; j++) {
        if (j > 1) {
            ve t = ve_div(ve_exact(sys->surf[j - 1].thickness), idx[j - 1]);
            y = ve_add(y, ve_mul(t, w));
            yb = ve_add(yb, ve_mul(t, wb));
        }
        r->y[j] = y;
        r->w[j] = w;
        r->yb[j] = yb;
        r->wb[j] = wb;
        w = ve_sub(w, ve_mul(y, phi[j]));
        wb = ve_sub(wb, ve_mul(yb, phi[j]));
    }
    return yb;
}

static int frame_moves(const sg_frame_change *f)
{
    return f->dx != 0.0 || f->dy != 0.0 || f->tx != 0.0 || f->ty != 0.0 || f->tz != 0.0;
}

/* The first surface whose frame is tilted or decentred, or -1. */
static int first_decentred(const sg_system *sys)
{
    int j;
    for (j = 0; j < sys->nsurf; j++) {
        const sg_surface *s = &sys->surf[j];
        if (frame_moves(&s->before) ||
            (s->after_mode == SG_AFTER_EXPLICIT && frame_moves(&s->after)))
            return j;
    }
    return -1;
}

/* x times an exact power of two. */
static ve ve_scale(ve a, double k)
{
    a.v *= k;
    a.e *= fabs(k);
    return a;
}

int sg_seidel_compute(const sg_system *sys, const sg_catalog *cat, sg_seidel *out,
                      sg_diag *d)
{
    int n, j, k, rc, ws = 0, wl = 0;
    double *buf = NULL;
    ve *vb = NULL, *idx, *ids, *idl, *phi, hfull, scale, y0, w0, yb0, wb0, H, tot[SG_SEIDEL_N];
    prays r;
    sg_paraxial p;

    if (!out)
        return sg_diag_set(d, SG_EINVAL, "seidel: no output");
    memset(out, 0, sizeof *out);
    /* A phase surface's third-order terms (its r^4 coefficient, the
     * stop shift of its power) are not in these sums: none rather than
     * wrong ones. */
    for (j = 1; j < sys->nsurf; j++)
        if (sg_phase_type(sys->surf[j].type))
            return sg_diag_set(d, SG_EUNSUPPORTED,
                               "surface %d: the Seidel sums of a phase surface are not computed",
                               j);
    rc = sg_paraxial_compute(sys, cat, -1, &p, d);
    if (rc != SG_OK)
        return rc;
    /* Third-order theory is of a centred system: the sums are computed
     * about the axis, the tilts and decenters left out, and say so. */
    out->decentred = first_decentred(sys);
    if (out->decentred >= 0)
        sg_diag_warn(d, "seidel: surface %d is tilted or decentred; the Seidel sums assume a "
                        "centred system and leave every tilt and decenter out, so they "
                        "describe the centred system, not this one", out->decentred);
    n = sys->nsurf;
    buf = calloc((size_t)n * 3, sizeof *buf);
    vb = calloc((size_t)n * 8, sizeof *vb);
    out->surf = calloc((size_t)n * SG_SEIDEL_N, sizeof *out->surf);
    out->surf_bound = calloc((size_t)n * SG_SEIDEL_N, sizeof *out->surf_bound);
    if (!buf || !vb || !out->surf || !out->surf_bound) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    idx = vb;
    ids = vb + n;
    idl = vb + 2 * n;
    phi = vb + 3 * n;
    r.y = vb + 4 * n;
    r.w = vb + 5 * n;
    r.yb = vb + 6 * n;
    r.wb = vb + 7 * n;
    /* Colour between the shortest and the longest wavelength. */
    for (k = 1; k < sys->nwave; k++) {
        if (sys->wave[k].um < sys->wave[ws].um)
            ws = k;
        if (sys->wave[k].um > sys->wave[wl].um)
            wl = k;
    }
    rc = indices(sys, cat, sys->primary_wave, buf, d);
    if (rc == SG_OK)
        rc = indices(sys, cat, ws, buf + n, d);
    if (rc == SG_OK)
        rc = indices(sys, cat, wl, buf + 2 * n, d);
    if (rc != SG_OK)
        goto fail;
    /* Indices rounded once from MPFR. */
    for (j = 0; j < n; j++) {
        idx[j] = ve_rounded(buf[j]);
        ids[j] = ve_rounded(buf[n + j]);
        idl[j] = ve_rounded(buf[2 * n + j]);
    }
    for (j = 0; j < n; j++)
        phi[j] = j == 0 ? ve_exact(0.0)
                 : sys->surf[j].type == SG_SURF_PARAXIAL
                     ? ve_div(ve_exact(1.0), ve_exact(sys->surf[j].focal_length))
                     : ve_mul(ve_sub(idx[j], idx[j - 1]),
                              ve_rounded(sg_surface_curvature(&sys->surf[j])));

    launch(sys, &p, idx[0], &y0, &w0, &yb0, &wb0);
    hfull = trace_rays(sys, idx, phi, &r, y0, w0, yb0, wb0);
    /* A paraxial-image-height field is defined at the paraxial image
     * plane (sg_parax_mp): the chief ray's height there, image_dist after
     * the last surface rather than its thickness, sets its scale. */
    if (sys->field_type == SG_FIELD_PARAX_IMAGE_HEIGHT && isfinite(p.image_dist) && n >= 3)
        hfull = ve_add(hfull, ve_mul(ve_div(ve_sub(ve_rounded(p.image_dist),
                                                   ve_exact(sys->surf[n - 2].thickness)),
                                            idx[n - 2]),
                                     r.wb[n - 1]));
    /* The chief ray of the largest field: scaled to the paraxial image
     * height, which every field type defines. */
    if (!(fabs(hfull.v) > 0.0) || !isfinite(p.parax_image_height)) {
        rc = sg_diag_set(d, SG_ENONPHYS, "seidel: the paraxial chief ray does not reach a "
                                         "finite image height");
        goto fail;
    }
    scale = ve_div(ve_rounded(p.parax_image_height), hfull);
    for (j = 1; j < n; j++) {
        r.yb[j] = ve_mul(r.yb[j], scale);
        r.wb[j] = ve_mul(r.wb[j], scale);
    }
    /* Welford's H = n (u ybar - ubar y), at surface 1; it is the same at
     * every surface. */
    H = ve_sub(ve_mul(r.w[1], r.yb[1]), ve_mul(r.wb[1], r.y[1]));

    for (k = 0; k < SG_SEIDEL_N; k++)
        tot[k] = ve_exact(0.0);
    for (j = 1; j < n; j++) {
        const sg_surface *s = &sys->surf[j];
        ve c = ve_rounded(sg_surface_curvature(s)), nb = idx[j - 1], na = idx[j];
        ve y = r.y[j], yb = r.yb[j], one = ve_exact(1.0);
        ve A = ve_add(r.w[j], ve_mul(ve_mul(nb, y), c));
        ve Ab = ve_add(r.wb[j], ve_mul(ve_mul(nb, yb), c));
        ve ua = ve_div(ve_sub(r.w[j], ve_mul(y, phi[j])), na), ub = ve_div(r.w[j], nb);
        ve du = ve_sub(ve_div(ua, na), ve_div(ub, nb));
        ve dinv = ve_sub(ve_div(one, na), ve_div(one, nb));
        ve dinv2 = ve_sub(ve_div(one, ve_mul(na, na)), ve_div(one, ve_mul(nb, nb)));
        ve dcol = ve_sub(ve_div(ve_sub(ids[j], idl[j]), na),
                         ve_div(ve_sub(ids[j - 1], idl[j - 1]), nb));
        ve o[SG_SEIDEL_N];
        o[SG_SEIDEL_SI] = ve_mul(ve_mul(ve_mul(ve_neg(A), A), y), du);
        o[SG_SEIDEL_SII] = ve_mul(ve_mul(ve_mul(ve_neg(A), Ab), y), du);
        o[SG_SEIDEL_SIII] = ve_mul(ve_mul(ve_mul(ve_neg(Ab), Ab), y), du);
        o[SG_SEIDEL_SIV] = ve_mul(ve_mul(ve_mul(ve_neg(H), H), c), dinv);
        o[SG_SEIDEL_SV] = ve_mul(
            ve_neg(Ab),
            ve_add(ve_mul(ve_mul(ve_mul(Ab, Ab), y), dinv2),
                   ve_mul(ve_mul(ve_mul(c, dinv), yb),
                          ve_sub(ve_mul(A, yb), ve_mul(ve_scale(Ab, 2.0), y)))));
        o[SG_SEIDEL_CI] = ve_mul(ve_mul(A, y), dcol);
        o[SG_SEIDEL_CII] = ve_mul(ve_mul(Ab, y), dcol);
        {
            ve G = ve_scale(ve_mul(ve_mul(ve_mul(ve_exact(s->conic), c), c), c), 1.0 / 8.0);
            ve e;
            if (s->type == SG_SURF_EVENASPH)
                G = ve_add(G, ve_exact(s->asph[1]));
            e = ve_mul(ve_mul(ve_scale(G, 8.0), ve_sub(na, nb)), y);
            o[SG_SEIDEL_SV] = ve_add(o[SG_SEIDEL_SV], ve_mul(ve_mul(ve_mul(e, yb), yb), yb));
            e = ve_mul(e, y);
            o[SG_SEIDEL_SIII] = ve_add(o[SG_SEIDEL_SIII], ve_mul(ve_mul(e, yb), yb));
            e = ve_mul(e, y);
            o[SG_SEIDEL_SII] = ve_add(o[SG_SEIDEL_SII], ve_mul(e, yb));
            e = ve_mul(e, y);
            o[SG_SEIDEL_SI] = ve_add(o[SG_SEIDEL_SI], e);
        }
        /* An ideal lens images every plane onto its conjugate without
         * aberration or colour (shape_paraxial.c): it adds nothing. */
        if (s->type == SG_SURF_PARAXIAL)
            for (k = 0; k < SG_SEIDEL_N; k++)
                o[k] = ve_exact(0.0);
        for (k = 0; k < SG_SEIDEL_N; k++) {
            o[k].v += 0.0; /* no -0 in a report */
            out->surf[(size_t)j * SG_SEIDEL_N + k] = o[k].v;
            out->surf_bound[(size_t)j * SG_SEIDEL_N + k] = o[k].e;
            tot[k] = ve_add(tot[k], o[k]);
        }
    }
    for (k = 0; k < SG_SEIDEL_N; k++) {
        out->total[k] = tot[k].v;
        out->total_bound[k] = tot[k].e;
    }
    out->nsurf = n;
    out->lagrange = H.v;
    /* n'u' of the marginal ray after the last surface. */
    out->nu_image = r.w[n - 1].v - r.y[n - 1].v * phi[n - 1].v;
    out->wave_um = sys->wave[sys->primary_wave].um;
    out->wave_lens = out->wave_um * 1e-3 / sg_lens_unit_mm(sys);
    out->short_um = sys->wave[ws].um;
    out->long_um = sys->wave[wl].um;
    free(buf);
    free(vb);
    for (k = 0; k < SG_SEIDEL_N; k++)
        if (!isfinite(out->total[k])) {
            sg_seidel_free(out);
            return sg_diag_set(d, SG_ENONPHYS, "seidel: a sum is not finite");
        }
    return SG_OK;
fail:
    free(buf);
    free(vb);
    sg_seidel_free(out);
    return rc;
}

void sg_seidel_free(sg_seidel *s)
{
    if (!s)
        return;
    free(s->surf);
    free(s->surf_bound);
    s->surf = NULL;
    s->surf_bound = NULL;
    s->nsurf = 0;
}

void sg_seidel_waves(const double *s, double lambda, double *w)
{
    w[SG_W040] = s[SG_SEIDEL_SI] / 8.0 / lambda;
    w[SG_W131] = s[SG_SEIDEL_SII] / 2.0 / lambda;
    w[SG_W222] = s[SG_SEIDEL_SIII] / 2.0 / lambda;
    w[SG_W220P] = s[SG_SEIDEL_SIV] / 4.0 / lambda;
    w[SG_W311] = s[SG_SEIDEL_SV] / 2.0 / lambda;
    w[SG_W020] = s[SG_SEIDEL_CI] / 2.0 / lambda;
    w[SG_W111] = s[SG_SEIDEL_CII] / lambda;
    w[SG_W220S] = (s[SG_SEIDEL_SIII] + s[SG_SEIDEL_SIV]) / 4.0 / lambda;
    w[SG_W220M] = (2.0 * s[SG_SEIDEL_SIII] + s[SG_SEIDEL_SIV]) / 4.0 / lambda;
    w[SG_W220T] = (3.0 * s[SG_SEIDEL_SIII] + s[SG_SEIDEL_SIV]) / 4.0 / lambda;
}

void sg_seidel_transverse(const double *s, double nu, double *t)
{
    double h = 1.0 / (2.0 * nu);
    t[SG_TSPH] = s[SG_SEIDEL_SI] * h;
    t[SG_TSCO] = s[SG_SEIDEL_SII] * h;
    t[SG_TTCO] = 3.0 * s[SG_SEIDEL_SII] * h;
    t[SG_TAST] = 2.0 * s[SG_SEIDEL_SIII] * h;
    t[SG_TPFC] = s[SG_SEIDEL_SIV] * h;
    t[SG_TSFC] = (s[SG_SEIDEL_SIII] + s[SG_SEIDEL_SIV]) * h;
    t[SG_TTFC] = (3.0 * s[SG_SEIDEL_SIII] + s[SG_SEIDEL_SIV]) * h;
    t[SG_TDIS] = s[SG_SEIDEL_SV] * h;
    t[SG_TAXC] = 2.0 * s[SG_SEIDEL_CI] * h;
    t[SG_TLAC] = 2.0 * s[SG_SEIDEL_CII] * h;
}
