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

#include "trace_internal.h"

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

/* The paraxial marginal and chief rays at each surface: heights y, yb
 * and reduced slopes w = n u, wb before the surface (index 0 unused). */
typedef struct prays {
    double *y, *w, *yb, *wb;
} prays;

static void launch(const sg_system *sys, const sg_paraxial *p, double n0, double *y,
                   double *w, double *yb, double *wb)
{
    double epr = 0.5 * p->epd, T0 = sys->surf[0].thickness;
    if (sys->telecentric && isfinite(T0)) {
        /* The pupil at infinity: the marginal ray at the object NA's
         * slope, the chief ray a unit height parallel to the axis. */
        double u0 = sys->aper_type == SG_APER_OBJECT_CONE
                        ? tan(sys->aper_value * 3.14159265358979323846 / 180.0)
                        : tan(asin(sys->aper_value / fabs(n0)));
        *y = u0 * T0;
        *w = u0 * n0;
        *yb = 1.0;
        *wb = 0.0;
    } else if (!isfinite(T0)) {
        *y = epr;
        *w = 0.0;
        /* Unit slope through the pupil's centre. */
        *yb = -p->enp_pos;
        *wb = n0;
    } else {
        double u0 = epr / (p->enp_pos + T0), ub = -1.0 / (p->enp_pos + T0);
        *y = u0 * T0;
        *w = u0 * n0;
        /* Unit object height, through the pupil's centre. */
        *yb = 1.0 + ub * T0;
        *wb = ub * n0;
    }
}

/* Traces both rays from surface 1 to the image; returns the chief ray's
 * image height for the unit launch (the scale of the field). */
static double trace_rays(const sg_system *sys, const double *idx, const double *phi,
                         prays *r, double y, double w, double yb, double wb)
{
    int j, n = sys->nsurf;
    for (j = 1; j < n; j++) {
        if (j > 1) {
            double t = sys->surf[j - 1].thickness / idx[j - 1];
            y += t * w;
            yb += t * wb;
        }
        r->y[j] = y;
        r->w[j] = w;
        r->yb[j] = yb;
        r->wb[j] = wb;
        w -= y * phi[j];
        wb -= yb * phi[j];
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

int sg_seidel_compute(const sg_system *sys, const sg_catalog *cat, sg_seidel *out,
                      sg_diag *d)
{
    int n, j, k, rc, ws = 0, wl = 0;
    double *buf = NULL, *idx, *ids, *idl, *phi, hfull, scale, y0, w0, yb0, wb0, H;
    prays r;
    sg_paraxial p;

    if (!out)
        return sg_diag_set(d, SG_EINVAL, "seidel: no output");
    memset(out, 0, sizeof *out);
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
    buf = calloc((size_t)n * 8, sizeof *buf);
    out->surf = calloc((size_t)n * SG_SEIDEL_N, sizeof *out->surf);
    if (!buf || !out->surf) {
        free(buf);
        free(out->surf);
        out->surf = NULL;
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    idx = buf;
    ids = buf + n;
    idl = buf + 2 * n;
    phi = buf + 3 * n;
    r.y = buf + 4 * n;
    r.w = buf + 5 * n;
    r.yb = buf + 6 * n;
    r.wb = buf + 7 * n;
    /* Colour between the shortest and the longest wavelength. */
    for (k = 1; k < sys->nwave; k++) {
        if (sys->wave[k].um < sys->wave[ws].um)
            ws = k;
        if (sys->wave[k].um > sys->wave[wl].um)
            wl = k;
    }
    rc = indices(sys, cat, sys->primary_wave, idx, d);
    if (rc == SG_OK)
        rc = indices(sys, cat, ws, ids, d);
    if (rc == SG_OK)
        rc = indices(sys, cat, wl, idl, d);
    if (rc != SG_OK)
        goto fail;
    for (j = 0; j < n; j++)
        phi[j] = j == 0 ? 0.0 : (idx[j] - idx[j - 1]) * sg_surface_curvature(&sys->surf[j]);

    launch(sys, &p, idx[0], &y0, &w0, &yb0, &wb0);
    hfull = trace_rays(sys, idx, phi, &r, y0, w0, yb0, wb0);
    /* The chief ray of the largest field: scaled to the paraxial image
     * height, which every field type defines. */
    if (!(fabs(hfull) > 0.0) || !isfinite(p.parax_image_height)) {
        rc = sg_diag_set(d, SG_ENONPHYS, "seidel: the paraxial chief ray does not reach a "
                                         "finite image height");
        goto fail;
    }
    scale = p.parax_image_height / hfull;
    for (j = 1; j < n; j++) {
        r.yb[j] *= scale;
        r.wb[j] *= scale;
    }
    /* Welford's H = n (u ybar - ubar y), at surface 1; it is the same at
     * every surface. */
    H = r.w[1] * r.yb[1] - r.wb[1] * r.y[1];

    for (j = 1; j < n; j++) {
        const sg_surface *s = &sys->surf[j];
        double c = sg_surface_curvature(s), nb = idx[j - 1], na = idx[j];
        double y = r.y[j], yb = r.yb[j];
        double A = r.w[j] + nb * y * c, Ab = r.wb[j] + nb * yb * c;
        double ua = (r.w[j] - y * phi[j]) / na, ub = r.w[j] / nb;
        double du = ua / na - ub / nb;
        double dinv = 1.0 / na - 1.0 / nb, dinv2 = 1.0 / (na * na) - 1.0 / (nb * nb);
        double dcol = (ids[j] - idl[j]) / na - (ids[j - 1] - idl[j - 1]) / nb;
        double *o = out->surf + (size_t)j * SG_SEIDEL_N;
        o[SG_SEIDEL_SI] = -A * A * y * du;
        o[SG_SEIDEL_SII] = -A * Ab * y * du;
        o[SG_SEIDEL_SIII] = -Ab * Ab * y * du;
        o[SG_SEIDEL_SIV] = -H * H * c * dinv;
        o[SG_SEIDEL_SV] = -Ab * (Ab * Ab * y * dinv2 + c * dinv * yb * (A * yb - 2.0 * Ab * y));
        o[SG_SEIDEL_CI] = A * y * dcol;
        o[SG_SEIDEL_CII] = Ab * y * dcol;
        {
            double G = s->conic * c * c * c / 8.0;
            double e;
            if (s->type == SG_SURF_EVENASPH)
                G += s->asph[1];
            e = 8.0 * G * (na - nb) * y;
            o[SG_SEIDEL_SV] += e * yb * yb * yb;
            e *= y;
            o[SG_SEIDEL_SIII] += e * yb * yb;
            e *= y;
            o[SG_SEIDEL_SII] += e * yb;
            e *= y;
            o[SG_SEIDEL_SI] += e;
        }
        for (k = 0; k < SG_SEIDEL_N; k++) {
            o[k] += 0.0; /* no -0 in a report */
            out->total[k] += o[k];
        }
    }
    out->nsurf = n;
    out->lagrange = H;
    /* n'u' of the marginal ray after the last surface. */
    out->nu_image = r.w[n - 1] - r.y[n - 1] * phi[n - 1];
    out->wave_um = sys->wave[sys->primary_wave].um;
    out->wave_lens = out->wave_um * 1e-3 / sg_lens_unit_mm(sys);
    out->short_um = sys->wave[ws].um;
    out->long_um = sys->wave[wl].um;
    free(buf);
    for (k = 0; k < SG_SEIDEL_N; k++)
        if (!isfinite(out->total[k])) {
            sg_seidel_free(out);
            return sg_diag_set(d, SG_ENONPHYS, "seidel: a sum is not finite");
        }
    return SG_OK;
fail:
    free(buf);
    free(out->surf);
    out->surf = NULL;
    return rc;
}

void sg_seidel_free(sg_seidel *s)
{
    if (!s)
        return;
    free(s->surf);
    s->surf = NULL;
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
