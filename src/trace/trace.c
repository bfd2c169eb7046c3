/*
 * trace.c - the precise and classic trace methods and the tracer.
 *
 * The precise method follows Wu et al. (Acta Phys. Sin. 72, 084201, 2023),
 * section 3, and carries the ray in double-double between surfaces:
 *   1. the ray moves into the next surface's vertex frame and onto its
 *      vertex tangent plane before any equation is solved (sec. 3.3);
 *   2. directions are unit vectors (sec. 3.2);
 *   3. the intersection comes from the cancellation-free roots of eq. 27,
 *      taking the root on the sheet through the vertex;
 *   4. the point is then put back on the surface.  The paper scales the
 *      point radially (eqs. 19, 21), which leaves it off the ray; here one
 *      Newton step along the ray, with the surface equation evaluated in
 *      double-double, lands on both the surface and the ray.
 * Double-double is needed because a direction rounded to double moves the
 * next intersection by about 1e-16 times the path, several ulp on a
 * telescope; carrying 106 bits keeps every reported digit.
 *
 * The classic method is the textbook one the paper calls the original
 * method: global coordinates, the direct quadratic formula, no reprojection
 * (trace_classic_vec.c).
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "trace_int.h"


const char *sg_method_name(sg_method m)
{
    switch (m) {
    case SG_METHOD_PRECISE: return "precise";
    case SG_METHOD_CLASSIC: return "classic";
    case SG_METHOD_MPFR: return "mpfr";
    }
    return "unknown";
}

int sg_method_parse(const char *s)
{
    if (!s)
        return -1;
    if (!strcmp(s, "precise"))
        return SG_METHOD_PRECISE;
    if (!strcmp(s, "classic"))
        return SG_METHOD_CLASSIC;
    if (!strcmp(s, "mpfr"))
        return SG_METHOD_MPFR;
    return -1;
}

void sg_trace_opts_init(sg_trace_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = SG_METHOD_PRECISE;
    o->mpfr_bits = 256;
    o->wave = -1;
    o->clip = 1;
    o->clip_rtol = 1e-9;
    o->max_iter = 50;
    o->aim_max_iter = 50;
    o->aim_rtol = 1e-13;
}

/* ------------------------------------------------------------------------
 * Surface functions in double-double.
 * ------------------------------------------------------------------------ */

/* Conic sag in the form r^2 / (R + sgn(R) sqrt(R^2 - k1 r^2)), which uses
 * R itself rather than a rounded 1/R. */
static dd conic_sag_dd(const sg_sprep *s, dd r2, int *ok)
{
    dd R = dd_from(s->R);
    dd disc = dd_sub(dd_sqr(R), dd_mul(s->k1, r2));
    dd root;
    *ok = 1;
    if (disc.hi < 0.0) {
        *ok = 0;
        return dd_from(NAN);
    }
    root = dd_sqrt(disc);
    if (s->R < 0)
        root = dd_neg(root);
    return dd_div(r2, dd_add(R, root));
}

static dd poly_dd(const sg_sprep *s, dd r2)
{
    dd p = dd_from(0.0);
    int k;
    for (k = s->nasph - 1; k >= 0; k--)
        p = dd_add_d(dd_mul(p, r2), s->a[k]);
    return dd_mul(p, r2);
}

/* Sag of an even asphere (or plane/conic base) at r^2. */
static dd sag_dd(const sg_sprep *s, dd r2, int *ok)
{
    dd z = dd_from(0.0);
    *ok = 1;
    if (isfinite(s->R))
        z = conic_sag_dd(s, r2, ok);
    if (s->nasph)
        z = dd_add(z, poly_dd(s, r2));
    return z;
}

double sg_sprep_sag_resid(const sg_sprep *s, double x, double y, double z)
{
    dd r2, sag;
    int ok;
    if (s->shape == SHAPE_PLANE)
        return fabs(z);
    r2 = dd_add(dd_two_prod(x, x), dd_two_prod(y, y));
    if (s->shape == SHAPE_CONIC) {
        /* G = r^2 + k1 z^2 - 2 R z is exact enough in double-double, and
         * z - sag = G / dG/dz to first order; the second-order term is the
         * residual squared over R, far below what is reported. */
        dd G = dd_add(r2, dd_mul(s->k1, dd_two_prod(z, z)));
        double gz = 2.0 * (s->k1.hi * z - s->R);
        G = dd_sub(G, dd_two_prod(z, 2.0 * s->R));
        if (gz != 0.0)
            return fabs(dd_to_d(G) / gz);
        /* At the rim of the vertex sheet (dG/dz = 0, a sphere's equator)
         * z - sag has no first-order form: the distance along the normal,
         * |G| / |grad G|, is what is left to report. */
        return fabs(dd_to_d(G)) / (2.0 * sqrt(x * x + y * y));
    }
    if (s->shape == SHAPE_GEN) {
        dd g[2];
        double ez, eg;
        ok = s->shp->ops->sag_dd(s->shp, dd_from(x), dd_from(y), &sag, g, &ez, &eg);
    } else {
        sag = sag_dd(s, r2, &ok);
    }
    if (!ok)
        return NAN;
    return fabs(dd_to_d(dd_sub(dd_from(z), sag)));
}

/* ------------------------------------------------------------------------
 * Shared by the methods.  The precise method itself is in trace_vec.c,
 * the classic one in trace_classic_vec.c.
 * ------------------------------------------------------------------------ */

int sg_past_clip(const sg_tracer *t, const sg_sprep *s, double x, double y)
{
    /* 0 where the ray goes on, else the code of what stops it. */
    return t->o.clip && !t->unclipped ? sg_clip_point(s, x, y, t->o.clip_rtol) : 0;
}

void sg_fail_rest(sg_ray_surface *out, int from, int n, int status)
{
    int i;
    for (i = from; i < n; i++) {
        memset(&out[i], 0, sizeof out[i]);
        out[i].x = out[i].y = out[i].z = NAN;
        out[i].l = out[i].m = out[i].n = NAN;
        out[i].residual = out[i].error_bound = out[i].dir_error_bound = NAN;
        out[i].path = NAN;
        out[i].opl = out[i].opl_lo = out[i].opl_error_bound = NAN;
        out[i].status = i == from ? status : SG_ENOTREACHED;
    }
}

/* ------------------------------------------------------------------------
 * The tracer.
 * ------------------------------------------------------------------------ */

int sg_indices_mpfr(const sg_system *sys, const sg_catalog *cat, int wave,
                    mpfr_t *idx, sg_diag *d)
{
    return sg_indices_mpfr_cached(sys, cat, wave, idx, NULL, d);
}

/* Whether two materials carry the same tolerancing change. */
static int glass_change_same(const sg_material *a, const sg_material *b)
{
    return memcmp(&a->dn, &b->dn, sizeof a->dn) == 0 &&
           memcmp(&a->disp, &b->disp, sizeof a->disp) == 0;
}

/* A catalog glass's index n changed as tolerancing asks (TABB, TIND):
 * n(d) + disp (n - n(d)) + dn, n(d) at the d line by the same formula. */
static int glass_change(sg_index_cache *cache, const sg_system *sys, const sg_glass *g,
                        const sg_material *m, mpfr_t n, int i, sg_diag *d)
{
    if (m->disp != 0.0) {
        mpfr_t nd, ud;
        int rc;
        mpfr_init2(nd, mpfr_get_prec(n));
        mpfr_init2(ud, mpfr_get_prec(n));
        mpfr_set_d(ud, 0.5875618, MPFR_RNDN);
        rc = sg_index_cache_glass(cache, sys, g, nd, ud);
        if (rc == SG_OK) {
            mpfr_sub(n, n, nd, MPFR_RNDN);
            mpfr_mul_d(n, n, m->disp, MPFR_RNDN);
            mpfr_add(n, n, nd, MPFR_RNDN);
        }
        mpfr_clear(nd);
        mpfr_clear(ud);
        if (rc != SG_OK)
            return sg_diag_set(d, SG_ERANGE, "surface %d: glass %s has no real index at the "
                               "d line", i, g->name);
    }
    mpfr_add_d(n, n, m->dn, MPFR_RNDN);
    return SG_OK;
}

int sg_indices_mpfr_cached(const sg_system *sys, const sg_catalog *cat, int wave,
                           mpfr_t *idx, sg_index_cache *cache, sg_diag *d)
{
    mpfr_t um;
    /* Catalog glasses met before in this call, with the surface whose
     * index holds theirs: a design uses few glasses on many surfaces, and
     * within one call a glass is one pointer with one index. */
    enum { SEEN = 8 };
    const sg_glass *seen_g[SEEN];
    int seen_at[SEEN], seen_sign[SEEN], nseen = 0, k;
    int i, sign = 1, rc = SG_OK;
    sg_glass_seen found;
    memset(&found, 0, sizeof found);
    mpfr_init2(um, mpfr_get_prec(idx[0]));
    mpfr_set_d(um, sys->wave[wave].um, MPFR_RNDN);
    for (i = 0; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        if (s->type == SG_SURF_COORDBRK && i > 0) {
            /* A coordinate break keeps the medium before it. */
            mpfr_set(idx[i], idx[i - 1], MPFR_RNDN);
            continue;
        }
        switch (s->mat.kind) {
        case SG_MAT_AIR:
            mpfr_set_si(idx[i], sign, MPFR_RNDN);
            break;
        case SG_MAT_INDEX:
            mpfr_set_d(idx[i], s->mat.index, MPFR_RNDN);
            if (sign < 0)
                mpfr_neg(idx[i], idx[i], MPFR_RNDN);
            break;
        case SG_MAT_MIRROR:
            /* The medium after a mirror is the one before it, travelled
             * backwards, hence the sign flip. */
            if (i == 0) {
                rc = sg_diag_set(d, SG_ENONPHYS, "surface 0: the object cannot be a mirror");
                goto out;
            }
            sign = -sign;
            mpfr_neg(idx[i], idx[i - 1], MPFR_RNDN);
            break;
        case SG_MAT_GLASS:
        case SG_MAT_MODEL: {
            sg_glass model;
            const sg_glass *g = s->mat.kind == SG_MAT_MODEL
                                    ? (sg_model_glass(s->mat.index, s->mat.vd, s->mat.dpgf,
                                                      &model) == SG_OK ? &model : NULL)
                                : cat ? sg_glass_seen_find(&found, cat, &s->mat) : NULL;
            if (!g && s->mat.kind == SG_MAT_MODEL) {
                rc = sg_diag_set(d, SG_ERANGE, "surface %d: model glass nd %g, vd %g, dPgF %g "
                                 "is outside the model's limits", i, s->mat.index, s->mat.vd,
                                 s->mat.dpgf);
                goto out;
            }
            if (!g) {
                char where[96];
                sg_material_where(cat, &s->mat, where, sizeof where);
                rc = sg_diag_set(d, SG_ENOGLASS,
                                 "surface %d: material \"%s\"%s is not in the catalog", i,
                                 s->mat.name, where);
                goto out;
            }
            for (k = 0; s->mat.kind == SG_MAT_GLASS && k < nseen &&
                        (seen_g[k] != g || !glass_change_same(&sys->surf[seen_at[k]].mat,
                                                              &s->mat));
                 k++)
                ;
            if (s->mat.kind == SG_MAT_GLASS && k < nseen) {
                /* The same bits the cache or the formula gave there. */
                if (seen_sign[k] == sign)
                    mpfr_set(idx[i], idx[seen_at[k]], MPFR_RNDN);
                else
                    mpfr_neg(idx[i], idx[seen_at[k]], MPFR_RNDN);
                break;
            }
            if (sg_index_cache_glass(cache, sys, g, idx[i], um) != SG_OK) {
                rc = sg_diag_set(d, SG_ERANGE,
                                 "surface %d: glass %s has no real index at %g um", i,
                                 g->name, sys->wave[wave].um);
                goto out;
            }
            if (s->mat.kind == SG_MAT_GLASS && (s->mat.dn != 0.0 || s->mat.disp != 0.0) &&
                (rc = glass_change(cache, sys, g, &s->mat, idx[i], i, d)) != SG_OK)
                goto out;
            if (sign < 0)
                mpfr_neg(idx[i], idx[i], MPFR_RNDN);
            if (s->mat.kind == SG_MAT_GLASS && nseen < SEEN) {
                seen_g[nseen] = g;
                seen_at[nseen] = i;
                seen_sign[nseen++] = sign;
            }
            break;
        }
        }
    }
out:
    mpfr_clear(um);
    return rc;
}

/* The transfer into surface i when it is more than a step along z: in
 * double-double and double from 288-bit MPFR. */
static const sg_xfer *prepare_xfer(sg_tracer *t, int i)
{
    sg_xfer *x = &t->xf[i];
    mpfr_t A[3][3], b[3], e;
    int j, k;
    for (j = 0; j < 3; j++) {
        for (k = 0; k < 3; k++)
            mpfr_init2(A[j][k], 256);
        mpfr_init2(b[j], 256);
    }
    mpfr_init2(e, 256);
    sg_xfer_mpfr(t->sys, i, A, b);
    x->grow = 0.0;
    for (j = 0; j < 3; j++) {
        double row = 0.0;
        for (k = 0; k < 3; k++) {
            /* Stored transposed: row j of A^T gives coordinate j. */
            x->At[j][k] = dd_from_mpfr(A[k][j], e);
            x->Atd[j][k] = x->At[j][k].hi;
            row += fabs(x->Atd[j][k]);
        }
        x->b[j] = dd_from_mpfr(b[j], e);
        x->bd[j] = x->b[j].hi;
        x->grow = fmax(x->grow, row);
    }
    /* A max-norm error grows by at most A^T's largest row sum; rounded
     * up, with room for the rounding of the entries themselves. */
    x->grow = x->grow * (1.0 + 0x1p-50);
    for (j = 0; j < 3; j++) {
        for (k = 0; k < 3; k++)
            mpfr_clear(A[j][k]);
        mpfr_clear(b[j]);
    }
    mpfr_clear(e);
    return x;
}

/* Surface i's sg_sprep but zg, its transfer and its signed index, from
 * surfaces i - 1 and i and their indices only (sg_prep_memo relies on it). */
static int prepare_one(sg_tracer *t, int i, mpfr_t *idx, mpfr_t q, mpfr_t tmp, sg_diag *d)
{
    const sg_system *sys = t->sys;
    const sg_surface *s = &sys->surf[i];
    sg_sprep *p = &t->sp[i];
    int k;
    memset(p, 0, sizeof *p);
    p->R = (s->radius == 0.0 || isinf(s->radius)) ? INFINITY : s->radius;
    p->c = isfinite(p->R) ? 1.0 / p->R : 0.0;
    p->k1 = dd_two_sum(1.0, s->conic);
    p->T = i > 0 ? sys->surf[i - 1].thickness : 0.0;
    p->nasph = 0;
    if (s->type == SG_SURF_EVENASPH)
        for (k = 0; k < SG_NASPH; k++) {
            p->a[k] = s->asph[k];
            if (s->asph[k] != 0.0)
                p->nasph = k + 1;
        }
    if (p->nasph)
        p->shape = SHAPE_ASPH;
    else if (isfinite(p->R))
        p->shape = SHAPE_CONIC;
    else
        p->shape = SHAPE_PLANE;
    if (sg_shape_ops_of(s->type)) {
        int rc = sg_shape_prepare(s, &t->shp[i], i, d);
        if (rc != SG_OK)
            return rc;
        /* Its base conic (the y-z section's for a toroid or biconic)
         * seeds the root, as an asphere's does. */
        p->shp = &t->shp[i];
        p->shape = SHAPE_GEN;
        p->nasph = 0;
    }
    if (s->type == SG_SURF_COORDBRK) {
        p->R = INFINITY;
        p->c = 0.0;
        p->k1 = dd_from(1.0);
        p->nasph = 0;
        p->shape = SHAPE_PLANE;
    }
    p->mirror = s->type != SG_SURF_COORDBRK && s->mat.kind == SG_MAT_MIRROR;
    p->sd = s->sd_fixed && s->type != SG_SURF_COORDBRK ? s->semi_diameter : 0.0;
    p->aper = s->type == SG_SURF_COORDBRK ? 0 : (int)s->aperture;
    p->ap_a = s->aperture == SG_APERTURE_CIRCULAR || s->aperture == SG_OBSCURATION_CIRCULAR
                  ? s->ap_rmin : s->ap_xhalf;
    p->ap_b = s->aperture == SG_APERTURE_CIRCULAR || s->aperture == SG_OBSCURATION_CIRCULAR
                  ? s->ap_rmax : s->ap_yhalf;
    p->ap_dx = s->ap_xdec;
    p->ap_dy = s->ap_ydec;
    p->xf = i >= 1 && sg_xfer_moves(sys, i) ? prepare_xfer(t, i) : NULL;
    t->nsigned[i] = mpfr_get_d(idx[i], MPFR_RNDN);
    if (i > 0) {
        mpfr_abs(q, idx[i - 1], MPFR_RNDN);
        mpfr_abs(tmp, idx[i], MPFR_RNDN);
        if (mpfr_zero_p(tmp))
            return sg_diag_set(d, SG_ENONPHYS, "surface %d: index is zero", i);
        mpfr_div(q, q, tmp, MPFR_RNDN);
        p->mu = dd_from_mpfr(q, tmp);
        p->mu2 = dd_sqr(p->mu);
    }
    if (s->type == SG_SURF_DGRATING && i > 0) {
        /* Its rulings (shape_dgrating.c); m lambda T comes after. */
        p->grating = 1;
        p->nb = fabs(t->nsigned[i - 1]);
        p->na = fabs(t->nsigned[i]);
    }
    if (sg_phase_type(s->type) && i > 0) {
        /* Its phase polynomial (shape_phase.c) in the shape slot a type
         * without ops leaves free; m lambda / (2 pi) comes after. */
        int rc = sg_phase_prepare(s, &t->shp[i], i, d);
        if (rc != SG_OK)
            return rc;
        p->phase = &t->shp[i];
        p->nb = fabs(t->nsigned[i - 1]);
        p->na = fabs(t->nsigned[i]);
    }
    if (s->type == SG_SURF_PARAXIAL && i > 0) {
        /* An ideal lens on its plane (shape_paraxial.c); validation
         * keeps it flat, off mirrors and with a focal length. */
        p->ideal = 1;
        p->R = INFINITY;
        p->c = 0.0;
        p->shape = SHAPE_PLANE;
        p->ic = 1.0 / (t->nsigned[i] * s->focal_length);
        p->nb = fabs(t->nsigned[i - 1]);
        p->na = fabs(t->nsigned[i]);
    }
    return SG_OK;
}

/* The conjugates of each paraxial surface: where the paraxial marginal
 * ray's lines before and after it cross the axis (Zemax's OPD modes 0, 1
 * and 3 all make the lens perfect there; mode 2 at infinite conjugates).
 * A y-nu trace in double from the prepared indices; the methods all read
 * these same doubles, so they trace one definition. */
static void ideal_conjugates(sg_tracer *t)
{
    const sg_system *sys = t->sys;
    double y, nu;
    int i;
    if (isinf(sys->surf[0].thickness)) {
        y = 1.0;
        nu = 0.0;
    } else {
        y = 0.0;
        nu = 1.0;
    }
    for (i = 1; i < t->n; i++) {
        sg_sprep *p = &t->sp[i];
        const sg_surface *s = &sys->surf[i];
        double nb = t->nsigned[i - 1], na = t->nsigned[i], phi;
        /* A grating's m lambda T at this tracer's wavelength, which the
         * prepared-surface memo does not key. */
        if (p->grating)
            p->gk = s->grating_order * sys->wave[t->wave].um * s->grating_lines;
        /* A phase surface's m lambda / (2 pi), lambda in lens units. */
        if (p->phase)
            p->pk = s->grating_order * (sys->wave[t->wave].um * 1e-3 / sg_lens_unit_mm(sys)) /
                    (2.0 * 3.14159265358979323846);
        if (i > 1 || !isinf(sys->surf[0].thickness))
            y += sys->surf[i - 1].thickness * nu / nb;
        phi = p->ideal ? 1.0 / s->focal_length : (na - nb) * sg_surface_curvature(s);
        if (p->phase)
            phi += sg_phase_power(sys, i, sys->wave[t->wave].um);
        if (p->ideal) {
            if (s->opd_mode == 2.0) {
                p->pz = INFINITY;
                p->qz = na * s->focal_length;
            } else {
                p->pz = nu == 0.0 ? INFINITY : -y * nb / nu;
                p->qz = nu - y * phi == 0.0 ? INFINITY : -y * na / (nu - y * phi);
            }
        }
        nu -= y * phi;
    }
}

static int same_mp256(mpfr_srcptr a, mpfr_srcptr b)
{
    return mpfr_equal_p(a, b) && mpfr_signbit(a) == mpfr_signbit(b);
}

static int prepare_surfaces(sg_tracer *t, mpfr_t *idx, const uint64_t *gen, sg_diag *d)
{
    sg_prep_memo *m = gen ? sg_index_cache_prep(t->icache, t->n) : NULL;
    mpfr_t q, tmp;
    double zg = 0.0;
    int i, rc = SG_OK;
    mpfr_init2(q, 256);
    mpfr_init2(tmp, 256);
    for (i = 0; i < t->n; i++) {
        sg_sprep *p = &t->sp[i];
        int same = m && m->gen[i] == gen[i] && same_mp256(m->idx[i], idx[i]);
        /* ok[i] is cleared whenever surface i - 1's bits change, so an
         * entry still marked was made from these surfaces i - 1 and i. */
        if (m && m->ok[i] && same) {
            *p = m->sp[i];
            if (m->has_xf[i]) {
                t->xf[i] = m->xf[i];
                p->xf = &t->xf[i];
            }
            t->nsigned[i] = m->nsigned[i];
            m->reused++;
        } else {
            if ((rc = prepare_one(t, i, idx, q, tmp, d)) != SG_OK)
                break;
            if (m) {
                if (!same) {
                    /* Entry i + 1 was made from the old surface i (a
                     * surface that fails below leaves its own copy old). */
                    m->gen[i] = gen[i];
                    mpfr_set(m->idx[i], idx[i], MPFR_RNDN);
                    if (i + 1 < t->n)
                        m->ok[i + 1] = 0;
                }
                m->ok[i] = !p->shp && !p->phase;
                m->sp[i] = *p;
                m->sp[i].xf = NULL;
                m->has_xf[i] = p->xf != NULL;
                if (p->xf)
                    m->xf[i] = *p->xf;
                m->nsigned[i] = t->nsigned[i];
            }
        }
        /* Classic traces in the frame of the last surface a transfer
         * turned or moved (surface 1's until then): zg is the vertex's z
         * there. */
        if (p->xf)
            zg = 0.0;
        else if (i >= 2)
            zg += p->T;
        p->zg = i >= 1 ? zg : -p->T;
    }
    mpfr_clear(q);
    mpfr_clear(tmp);
    if (rc == SG_OK)
        ideal_conjugates(t);
    return rc;
}

/* The public header's constructors that return the tracer, kept for the
 * library's ABI: each is its code-returning form with the code dropped
 * (d, when given, still holds it). */
sg_tracer *sg_tracer_new(const sg_system *sys, const sg_catalog *cat,
                         const sg_trace_opts *opts, sg_diag *d)
{
    sg_tracer *t = NULL;
    (void)sg_tracer_open(sys, cat, opts, &t, d);
    return t;
}

sg_tracer *sg_tracer_new_cached(const sg_system *sys, const sg_catalog *cat,
                                const sg_trace_opts *opts, sg_index_cache *cache,
                                sg_diag *d)
{
    sg_tracer *t = NULL;
    (void)sg_tracer_open_cached(sys, cat, opts, cache, &t, d);
    return t;
}

sg_tracer *sg_tracer_new_method(const sg_tracer *m, sg_method method, int mpfr_bits,
                                sg_index_cache *cache, sg_diag *d)
{
    sg_tracer *t = NULL;
    (void)sg_tracer_open_method(m, method, mpfr_bits, cache, &t, d);
    return t;
}

int sg_tracer_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                   sg_tracer **out, sg_diag *d)
{
    return sg_tracer_open_cached(sys, cat, opts, NULL, out, d);
}

int sg_tracer_open_cached(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                          sg_index_cache *cache, sg_tracer **out, sg_diag *d)
{
    sg_tracer *t;
    mpfr_t *idx = NULL;
    const uint64_t *gen = NULL;
    sg_system *copy = NULL;
    int i, rc, n;
    sg_diag own;
    if (!out)
        return sg_diag_set(d, SG_EINVAL, "tracer: nowhere to put it");
    *out = NULL;
    /* Every failure below sets a code; without the caller's diagnostic it
     * is kept here so that the right one is returned. */
    if (!d) {
        sg_diag_clear(&own);
        d = &own;
    }
    if (!sys)
        return sg_diag_set(d, SG_EINVAL, "tracer: no system");
    /* With a cache (the editor, which validates nowhere else) the
     * warnings go to the caller too; others validated before. */
    if (cache && sys->nsurf >= 1) {
        /* Both memos know an unchanged surface by its generation. */
        sg_valid_memo *vmemo = sg_index_cache_valid(cache, sys->nsurf);
        gen = sg_index_cache_gens(cache, sys, &copy);
        if (vmemo)
            vmemo->cur = gen;
        rc = sg_system_validate_memo(sys, cat, d, gen ? vmemo : NULL);
        if (vmemo)
            vmemo->cur = NULL;
    } else {
        rc = cache ? sg_system_validate_memo(sys, cat, d, NULL) : sg_system_check(sys, cat, d);
    }
    if (rc != SG_OK) {
        sg_system_free(copy);
        return rc;
    }
    t = calloc(1, sizeof *t);
    if (!t) {
        sg_system_free(copy);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    t->sys = copy; /* the tracer's from here, freed with it */
    if (opts)
        t->o = *opts;
    else
        sg_trace_opts_init(&t->o);
    if (t->o.mpfr_bits < 53 || t->o.mpfr_bits > 100000) {
        sg_diag_set(d, SG_ERANGE, "mpfr bits %d outside 53..100000", t->o.mpfr_bits);
        goto fail;
    }
    t->wave = t->o.wave < 0 ? sys->primary_wave : t->o.wave;
    if (t->wave >= sys->nwave) {
        sg_diag_set(d, SG_ERANGE, "wavelength %d is not one of 1 to %d", t->wave + 1,
                    sys->nwave);
        goto fail;
    }
    n = t->n = sys->nsurf;
    t->cat = cat;
    if (!t->sys)
        t->sys = sg_system_clone(sys);
    t->sp = calloc((size_t)n, sizeof *t->sp);
    t->nsigned = calloc((size_t)n, sizeof *t->nsigned);
    idx = sg_mp_block_new((size_t)n, 256);
    if (!t->sys || !t->sp || !t->nsigned || !idx) {
        sg_diag_set(d, SG_ENOMEM, "out of memory");
        free(idx);
        goto fail;
    }
    for (i = 1; i < n; i++)
        if (sg_xfer_moves(sys, i)) {
            t->xf = calloc((size_t)n, sizeof *t->xf);
            if (!t->xf) {
                sg_diag_set(d, SG_ENOMEM, "out of memory");
                free(idx);
                goto fail;
            }
            break;
        }
    for (i = 0; i < n; i++)
        if (sg_shape_ops_of(sys->surf[i].type) || sg_phase_type(sys->surf[i].type)) {
            t->shp = calloc((size_t)n, sizeof *t->shp);
            if (!t->shp) {
                sg_diag_set(d, SG_ENOMEM, "out of memory");
                free(idx);
                goto fail;
            }
            break;
        }
    /* Only while it is made: the caller owns the cache. */
    t->icache = cache;
    rc = sg_indices_mpfr_cached(sys, cat, t->wave, idx, cache, d);
    if (rc == SG_OK)
        rc = prepare_surfaces(t, idx, gen, d);
    free(idx);
    if (rc != SG_OK)
        goto fail;
    if (t->wave != sys->primary_wave) {
        /* Its warnings would repeat this tracer's; only a failure counts,
         * named as the primary wavelength's. */
        sg_trace_opts po = t->o;
        sg_diag pd;
        po.wave = sys->primary_wave;
        sg_diag_clear(&pd);
        rc = sg_tracer_open_cached(sys, cat, &po, cache, &t->prim, &pd);
        if (rc != SG_OK) {
            sg_diag_set(d, rc, "primary wavelength %d, which defines the pupil and fields: %s",
                        sys->primary_wave + 1, pd.msg);
            goto fail;
        }
    }
    /* Every method's launch may trace precisely (the real-aim stop radius),
     * so every tracer has the precise method's rescue, before the launch. */
    if (!(t->rescue = sg_mpfr_rescue_new())) {
        sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    if (sg_launch_prepare(t, d) != SG_OK)
        goto fail;
    if (t->o.method == SG_METHOD_MPFR && sg_mpfr_prepare(t, d) != SG_OK)
        goto fail;
    t->icache = NULL;
    *out = t;
    return SG_OK;
fail:
    sg_tracer_free(t);
    return d->code != SG_OK ? d->code : SG_ENOMEM;
}

/* t takes m's prepared model (never written again, so shared) with
 * options o; its workspace is its own. */
static void share_model(sg_tracer *t, const sg_tracer *m, const sg_trace_opts *o)
{
    t->model = m->model ? m->model : m;
    t->sys = m->sys;
    t->o = *o;
    t->wave = m->wave;
    t->n = m->n;
    t->sp = m->sp;
    t->xf = m->xf;
    t->shp = m->shp;
    t->nsigned = m->nsigned;
    t->px = m->px;
    t->ln = m->ln;
    t->cat = m->cat;
}

int sg_tracer_fork(const sg_tracer *m, sg_tracer **out, sg_diag *d)
{
    sg_tracer *t = calloc(1, sizeof *t);
    int rc;
    *out = NULL;
    if (!t)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    /* The prepared model, shared; the workspace starts empty. */
    share_model(t, m, &m->o);
    if (m->prim && (rc = sg_tracer_fork(m->prim, &t->prim, d)) != SG_OK)
        goto fail;
    t->scratch = calloc((size_t)t->n, sizeof *t->scratch);
    if (!t->scratch || !(t->rescue = sg_mpfr_rescue_new())) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    /* The mpfr method's context holds its own prepared values and its
     * scratch together: each fork makes one. */
    if (t->o.method == SG_METHOD_MPFR && (rc = sg_mpfr_prepare(t, d)) != SG_OK)
        goto fail;
    *out = t;
    return SG_OK;
fail:
    sg_tracer_free(t);
    return rc;
}

int sg_tracer_open_method(const sg_tracer *m, sg_method method, int mpfr_bits,
                          sg_index_cache *cache, sg_tracer **out, sg_diag *d)
{
    sg_trace_opts o;
    sg_tracer *t;
    sg_diag own;
    int rc;
    if (!out)
        return sg_diag_set(d, SG_EINVAL, "tracer: nowhere to put it");
    *out = NULL;
    if (!m)
        return sg_diag_set(d, SG_EINVAL, "tracer: no tracer to share");
    if (!d) {
        sg_diag_clear(&own);
        d = &own;
    }
    o = m->o;
    o.method = method;
    o.mpfr_bits = mpfr_bits;
    /* Classic lands the real-aim stop radius its own way (launch.c), and
     * the precision's range is sg_tracer_open_cached's to check. */
    if (m->o.method == SG_METHOD_CLASSIC || method == SG_METHOD_CLASSIC ||
        mpfr_bits < 53 || mpfr_bits > 100000)
        return sg_tracer_open_cached(m->sys, m->cat, &o, cache, out, d);
    t = calloc(1, sizeof *t);
    if (!t)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    /* The prepared model, shared as a fork shares it; only the options'
     * method and precision differ, which the model does not read. */
    share_model(t, m, &o);
    if (m->prim) {
        /* Named as sg_tracer_open_cached names the primary wavelength's
         * failure. */
        sg_diag pd;
        sg_diag_clear(&pd);
        rc = sg_tracer_open_method(m->prim, method, mpfr_bits, cache, &t->prim, &pd);
        if (rc != SG_OK) {
            sg_diag_set(d, rc, "primary wavelength %d, which defines the pupil and fields: %s",
                        t->sys->primary_wave + 1, pd.msg);
            goto fail;
        }
    }
    t->scratch = calloc((size_t)t->n, sizeof *t->scratch);
    if (!t->scratch || !(t->rescue = sg_mpfr_rescue_new())) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    t->icache = cache;
    if (t->o.method == SG_METHOD_MPFR && (rc = sg_mpfr_prepare(t, d)) != SG_OK)
        goto fail;
    t->icache = NULL;
    *out = t;
    return SG_OK;
fail:
    sg_tracer_free(t);
    return rc;
}

void sg_tracer_free(sg_tracer *t)
{
    if (!t)
        return;
    if (t->mp)
        sg_mpfr_free(t->mp);
    if (t->rescue)
        sg_mpfr_free(t->rescue);
    sg_tracer_free(t->prim);
    if (!t->model) {
        sg_system_free(t->sys);
        free(t->sp);
        free(t->xf);
        free(t->shp);
        free(t->nsigned);
    }
    free(t->scratch);
    free(t);
}

void sg_tracer_set_reference(sg_tracer *t, int on)
{
    if (t)
        t->unclipped = on != 0;
}

int sg_tracer_nsurf(const sg_tracer *t)
{
    return t->n;
}

const sg_paraxial *sg_tracer_paraxial(const sg_tracer *t)
{
    return &t->px;
}

double sg_tracer_index(const sg_tracer *t, int i)
{
    if (i < 0 || i >= t->n)
        return NAN;
    return t->nsigned[i];
}

unsigned long sg_tracer_rescues(const sg_tracer *t)
{
    if (!t)
        return 0;
    /* The primary wavelength's tracer aims this one's rays. */
    return sg_mpfr_rescues(t->rescue) + (t->prim ? sg_tracer_rescues(t->prim) : 0);
}

/* Bit 63 of the result is set when v is an infinity or NaN: its exponent
 * field is all ones, and adding one to it carries into bit 63. */
static inline uint64_t nonfinite_bit(double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    return (u & 0x7ff0000000000000ull) + 0x0010000000000000ull;
}

/* The row's thirteen numbers, each read once and ORed as a tree with integer
 * operations: no branch and no long chain, so the common, finite ray
 * costs a few instructions a row. */
static inline uint64_t row_bits(const sg_ray_surface *o)
{
    return ((nonfinite_bit(o->x) | nonfinite_bit(o->y)) |
            (nonfinite_bit(o->z) | nonfinite_bit(o->l))) |
           ((nonfinite_bit(o->m) | nonfinite_bit(o->n)) |
            (nonfinite_bit(o->residual) | nonfinite_bit(o->error_bound))) |
           ((nonfinite_bit(o->dir_error_bound) | nonfinite_bit(o->path)) |
            (nonfinite_bit(o->opl) | nonfinite_bit(o->opl_lo) | nonfinite_bit(o->opl_error_bound)));
}

static int row_bad(const sg_tracer *t, const sg_ray_surface *o, int i)
{
    if (i == 0 && isinf(t->sys->surf[0].thickness)) {
        /* The object at infinity lies infinitely far back along the ray;
         * its row says so with infinite coordinates, never NaN. */
        sg_ray_surface c = *o;
        if (isnan(c.x) || isnan(c.y) || isnan(c.z))
            return 1;
        c.x = c.y = c.z = 0.0;
        return (int)(row_bits(&c) >> 63);
    }
    return (int)(row_bits(o) >> 63);
}

int sg_guard_rows(const sg_tracer *t, sg_ray_surface *out, int rc)
{
    uint64_t acc = 0;
    int i;
    if (out[0].status != SG_OK)
        return rc;
    for (i = 1; i < t->n && out[i].status == SG_OK; i++)
        acc |= row_bits(&out[i]);
    if (!(acc >> 63) && !row_bad(t, &out[0], 0))
        return rc;
    for (i = 0; i < t->n && out[i].status == SG_OK; i++)
        if (row_bad(t, &out[i], i)) {
            sg_fail_rest(out, i, t->n, SG_ERANGE);
            return SG_ERANGE;
        }
    return rc;
}

void sg_set_start_row(sg_ray_surface *o, const double S[3], const double u[3])
{
    memset(o, 0, sizeof *o);
    o->x = S[0];
    o->y = S[1];
    o->z = S[2];
    o->l = u[0];
    o->m = u[1];
    o->n = u[2];
    o->status = SG_OK;
}

/* Rejects a start point or direction that no method can trace. */
void sg_dir_scale(const double in[3], double out[3])
{
    double m = fmax(fabs(in[0]), fmax(fabs(in[1]), fabs(in[2])));
    int k, e;
    if (!isfinite(m) || m == 0.0 || (m >= 0x1p-400 && m <= 0x1p400)) {
        for (k = 0; k < 3; k++)
            out[k] = in[k];
        return;
    }
    e = ilogb(m);
    /* A component more than 2^1074 below the largest becomes 0 (or keeps
     * its last bits as a subnormal): its square is below the largest's
     * rounding either way. */
    for (k = 0; k < 3; k++)
        out[k] = ldexp(in[k], -e);
}

static int start_invalid(const sg_tracer *t, const double start[3], const double dir_in[3],
                         sg_ray_surface *out)
{
    double dir[3], len2;
    int k;
    sg_dir_scale(dir_in, dir);
    len2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    for (k = 0; k < 3; k++)
        if (!isfinite(start[k]) || !isfinite(dir[k])) {
            sg_fail_rest(out, 0, t->n, SG_EINVAL);
            return SG_EINVAL;
        }
    if (!(len2 > 0.0) || !isfinite(len2)) {
        sg_fail_rest(out, 0, t->n, SG_EINVAL);
        return SG_EINVAL;
    }
    return SG_OK;
}

int sg_start_precise_prep(const sg_tracer *t, const double start[3], const double dir_in[3],
                          sg_ray_surface *out, sg_pray *r)
{
    dd len;
    double u[3], dir[3];
    int rc = start_invalid(t, start, dir_in, out);
    if (rc != SG_OK)
        return rc;
    sg_dir_scale(dir_in, dir);
    len = dd_sqrt(dd_add(dd_add(dd_sqr(dd_from(dir[0])), dd_sqr(dd_from(dir[1]))),
                         dd_sqr(dd_from(dir[2]))));
    r->p.x = dd_from(start[0]);
    r->p.y = dd_from(start[1]);
    r->p.z = dd_from(start[2]);
    r->d.x = dd_div(dd_from(dir[0]), len);
    r->d.y = dd_div(dd_from(dir[1]), len);
    r->d.z = dd_div(dd_from(dir[2]), len);
    r->eP = 0.0;
    r->eD = 4.0 * DD_U;
    r->opl = dd_from(0.0);
    r->eO = 0.0;
    u[0] = r->d.x.hi;
    u[1] = r->d.y.hi;
    u[2] = r->d.z.hi;
    sg_set_start_row(&out[0], start, u);
    return SG_OK;
}

int sg_start_classic_prep(const sg_tracer *t, const double start[3], const double dir_in[3],
                          sg_ray_surface *out)
{
    double len2, len, u[3], dir[3];
    int rc = start_invalid(t, start, dir_in, out);
    if (rc != SG_OK)
        return rc;
    sg_dir_scale(dir_in, dir);
    len2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    len = sqrt(len2);
    u[0] = dir[0] / len;
    u[1] = dir[1] / len;
    u[2] = dir[2] / len;
    sg_set_start_row(&out[0], start, u);
    return SG_OK;
}

int sg_trace_start(sg_tracer *t, const double start[3], const double dir_in[3],
                   sg_ray_surface *out)
{
    int rc;
    double dir[3];
    sg_dir_scale(dir_in, dir);
    if (t->o.method == SG_METHOD_PRECISE) {
        /* The preparation checks the ray, as it does for the batch. */
        sg_pray r;
        rc = sg_start_precise_prep(t, start, dir, out, &r);
        return rc != SG_OK ? rc : sg_guard_rows(t, out, sg_precise_run_to(t, &r, 0.0, out, t->n - 1));
    }
    if (t->o.method == SG_METHOD_CLASSIC) {
        rc = sg_start_classic_prep(t, start, dir, out);
        return rc != SG_OK ? rc : sg_guard_rows(t, out, sg_classic_run_to(t, start, dir, out, t->n - 1));
    }
    rc = start_invalid(t, start, dir, out);
    if (rc != SG_OK)
        return rc;
    switch (t->o.method) {
    case SG_METHOD_CLASSIC:
        break; /* traced above */
    case SG_METHOD_MPFR:
        return sg_guard_rows(t, out, sg_mpfr_trace_start(t, start, dir, out));
    case SG_METHOD_PRECISE:
        break; /* traced above */
    }
    return SG_EINVAL;
}

int sg_trace_normalized(sg_tracer *t, double hx, double hy, double px, double py,
                        sg_ray_surface *out)
{
    if (!isfinite(hx) || !isfinite(hy) || !isfinite(px) || !isfinite(py)) {
        sg_fail_rest(out, 0, t->n, SG_EINVAL);
        return SG_EINVAL;
    }
    /* A field's vignetting factors move its pupil point, for every method. */
    sg_field_vignette(t->sys, hx, hy, px, py, &px, &py);
    switch (t->o.method) {
    case SG_METHOD_PRECISE:
        return sg_guard_rows(t, out, sg_launch_precise(t, hx, hy, px, py, out));
    case SG_METHOD_CLASSIC:
        return sg_guard_rows(t, out, sg_launch_classic(t, hx, hy, px, py, out));
    case SG_METHOD_MPFR:
        return sg_guard_rows(t, out, sg_mpfr_trace_normalized(t, hx, hy, px, py, out));
    }
    return SG_EINVAL;
}
