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
 * method: global coordinates, the direct quadratic formula, no reprojection.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "trace_internal.h"


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

/* w = sag'(r)/r in double, and a bound on |d w / d r^2| times r^2, used for
 * Newton steps and for the normal's sensitivity. */
static void slope_d(const sg_sprep *s, double r2, double *w, double *dw)
{
    double ww = 0.0, dd2 = 0.0, rk = 1.0;
    int k;
    if (isfinite(s->R)) {
        double q = s->R * s->R - s->k1.hi * r2;
        double sq = sqrt(fabs(q));
        ww = (s->R < 0 ? -1.0 : 1.0) / sq;
        dd2 = fabs(s->k1.hi) / (2.0 * fabs(q) * sq) * r2;
    }
    /* Powers by running product, the same rounding as the vector trace. */
    for (k = 1; k < s->nasph; k++) {
        double p;
        rk = rk * r2;
        p = (double)(2 * (k + 1)) * s->a[k] * rk;
        ww += p;
        dd2 += fabs(p) * (double)(k);
    }
    if (s->nasph)
        ww += 2.0 * s->a[0];
    *w = ww;
    *dw = dd2;
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
 * Surface functions in double, shared with the classic method.  The
 * precise method itself is in trace_vec.c.
 * ------------------------------------------------------------------------ */

/* Newton in double on F(s) = z(s) - sag(r(s)) for an even asphere, or
 * z(s) - f(x(s), y(s)) for a shape of its own (shape.h), whose bound on
 * f's second derivatives at the root goes to *h. */
static int asph_root_d(const sg_sprep *s, const double p[3], const double d[3],
                       double s0, int max_iter, double *sout, double *h)
{
    double sv = s0;
    int it;
    for (it = 0; it < max_iter; it++) {
        double x = p[0] + sv * d[0], y = p[1] + sv * d[1], z = p[2] + sv * d[2];
        double r2 = x * x + y * y;
        double sag = 0.0, w, dw, F, Fp, step;
        if (s->shape == SHAPE_GEN) {
            double g[2];
            if (!s->shp->ops->sag_d(s->shp, x, y, &sag, g, h))
                return 0;
            F = z - sag;
            Fp = d[2] - g[0] * d[0] - g[1] * d[1];
            goto step;
        }
        if (isfinite(s->R)) {
            double q = s->R * s->R - s->k1.hi * r2;
            if (q < 0.0)
                return 0;
            sag = r2 / (s->R + copysign(sqrt(q), s->R));
        }
        {
            double pp = 0.0;
            int k;
            for (k = s->nasph - 1; k >= 0; k--)
                pp = pp * r2 + s->a[k];
            sag += pp * r2;
        }
        slope_d(s, r2, &w, &dw);
        F = z - sag;
        Fp = d[2] - w * (x * d[0] + y * d[1]);
    step:
        if (Fp == 0.0 || !isfinite(Fp))
            return 0;
        step = F / Fp;
        sv -= step;
        if (!isfinite(sv))
            return 0;
        if (fabs(step) <= 4.0 * U53 * (fabs(sv) + fabs(x) + fabs(y) + fabs(z)))
            break;
    }
    if (it == max_iter)
        return -1;
    *sout = sv;
    return 1;
}

/* Surface gradient direction at p, in double: (x, y, k1 z - R) for a
 * conic, (-w x, -w y, 1) for an asphere, -z for a plane. */
static void grad_d(const sg_sprep *s, const double p[3], double g[3])
{
    if (s->shape == SHAPE_PLANE) {
        g[0] = 0.0;
        g[1] = 0.0;
        g[2] = -1.0;
    } else if (s->shape == SHAPE_CONIC) {
        g[0] = p[0];
        g[1] = p[1];
        g[2] = s->k1.hi * p[2] - s->R;
    } else if (s->shape == SHAPE_GEN) {
        double f, gg[2], h;
        if (!s->shp->ops->sag_d(s->shp, p[0], p[1], &f, gg, &h))
            gg[0] = gg[1] = NAN;
        g[0] = -gg[0];
        g[1] = -gg[1];
        g[2] = 1.0;
    } else {
        double w, dw;
        slope_d(s, p[0] * p[0] + p[1] * p[1], &w, &dw);
        g[0] = -w * p[0];
        g[1] = -w * p[1];
        g[2] = 1.0;
    }
}

/* Cosine between a unit ray and the surface normal at p, in double. */
static double surf_cos_d(const sg_sprep *s, const double p[3], const double d[3])
{
    double g[3], gn;
    grad_d(s, p, g);
    gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!isfinite(gn) || gn < 0x1p-500) {
        /* Squares out of range (|R| above about 1e154): scale first. */
        double gm = fmax(fabs(g[0]), fmax(fabs(g[1]), fabs(g[2])));
        if (gm > 0.0 && isfinite(gm)) {
            g[0] /= gm;
            g[1] /= gm;
            g[2] /= gm;
            gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        }
    }
    return gn > 0.0 ? fabs(g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn : 0.0;
}

int sg_past_clip(const sg_tracer *t, const sg_sprep *s, double x, double y)
{
    return t->o.clip && !t->unclipped && sg_clip_point(s, x, y, t->o.clip_rtol);
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
 * Classic method.
 * ------------------------------------------------------------------------ */

/* Refracts or reflects d at p; *gain is how much a direction error grows
 * (see precise_bend). */
static int classic_bend(const sg_sprep *s, const double p[3], double d[3], double *gain)
{
    double g[3], gg, cosI, nd[3], len;
    len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    d[0] /= len;
    d[1] /= len;
    d[2] /= len;
    grad_d(s, p, g);
    gg = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!isfinite(gg) || gg < 0x1p-500) {
        /* The squares over- or underflow (|R| above about 1e154): scale
         * first.  Ordinary normals keep the textbook arithmetic. */
        double gm = fmax(fabs(g[0]), fmax(fabs(g[1]), fabs(g[2])));
        if (gm > 0.0 && isfinite(gm)) {
            g[0] /= gm;
            g[1] /= gm;
            g[2] /= gm;
            gg = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        }
    }
    g[0] /= gg;
    g[1] /= gg;
    g[2] /= gg;
    cosI = d[0] * g[0] + d[1] * g[1] + d[2] * g[2];
    if (s->mirror) {
        nd[0] = d[0] - 2.0 * cosI * g[0];
        nd[1] = d[1] - 2.0 * cosI * g[1];
        nd[2] = d[2] - 2.0 * cosI * g[2];
        *gain = 1.0;
    } else {
        double mu = s->mu.hi;
        double k = 1.0 - mu * mu * (1.0 - cosI * cosI);
        double gam, sinI = sqrt(fmax(0.0, 1.0 - cosI * cosI));
        if (k < 0.0)
            return SG_ETIR;
        *gain = mu + mu * fabs(mu * fabs(cosI) - sqrt(k)) / sqrt(fmax(k, 1e-300)) * sinI;
        gam = copysign(sqrt(k), cosI) - mu * cosI;
        nd[0] = mu * d[0] + gam * g[0];
        nd[1] = mu * d[1] + gam * g[1];
        nd[2] = mu * d[2] + gam * g[2];
    }
    d[0] = nd[0];
    d[1] = nd[1];
    d[2] = nd[2];
    return SG_OK;
}

int sg_classic_run_to(const sg_tracer *t, const double S[3], const double D[3],
                      sg_ray_surface *out, int upto)
{
    double P[3] = {S[0], S[1], S[2]}, d[3] = {D[0], D[1], D[2]};
    double eP = 0.0, eD = 0.0, opl = 0.0, eO = 0.0;
    int i;
    for (i = 1; i <= upto; i++) {
        const sg_sprep *s = &t->sp[i];
        sg_ray_surface *o = &out[i];
        double zl;
        if (s->xf) {
            /* Into this surface's frame, which classic then keeps: the
             * rotation in double, as a textbook trace would do it. */
            const sg_xfer *x = s->xf;
            double q[3] = {P[0] - x->bd[0], P[1] - x->bd[1], (P[2] - t->sp[i - 1].zg) - x->bd[2]};
            double dq[3] = {d[0], d[1], d[2]}, big;
            int j;
            big = fmax(fabs(P[0]), fmax(fabs(P[1]), fabs(P[2]))) + fabs(t->sp[i - 1].zg) +
                  fmax(fabs(x->bd[0]), fmax(fabs(x->bd[1]), fabs(x->bd[2])));
            for (j = 0; j < 3; j++) {
                P[j] = x->Atd[j][0] * q[0] + x->Atd[j][1] * q[1] + x->Atd[j][2] * q[2];
                d[j] = x->Atd[j][0] * dq[0] + x->Atd[j][1] * dq[1] + x->Atd[j][2] * dq[2];
            }
            eP = x->grow * (eP + 3.0 * U53 * big) + 4.0 * U53 * x->grow * big;
            eD = x->grow * eD + 4.0 * U53 * x->grow;
        }
        zl = P[2] - s->zg;
        double c = s->c, k1 = s->k1.hi, tt, x, y, z, dn;
        double A = c * (d[0] * d[0] + d[1] * d[1] + k1 * d[2] * d[2]);
        double B = 2.0 * c * (P[0] * d[0] + P[1] * d[1] + k1 * zl * d[2]) - 2.0 * d[2];
        double C = c * (P[0] * P[0] + P[1] * P[1] + k1 * zl * zl) - 2.0 * zl;
        double sigA, sigB, sigC, eta_t, dlen, hgen = 0.0;
        if (A == 0.0) {
            if (B == 0.0)
                goto miss;
            tt = -C / B;
        } else {
            double disc = B * B - 4.0 * A * C;
            double t1, t2, tl = B != 0.0 ? -C / B : 0.0;
            int ok1, ok2;
            if (disc < 0.0)
                goto miss;
            if (fabs(4.0 * A * C) <= 0x1p-20 * (B * B)) {
                /* A nearly flat surface (|R| of 1e15 and more on a lens):
                 * the textbook near root -B + sqrt(disc) would cancel
                 * more than 20 bits, and from |R| = 1e18 on cancel to
                 * nothing, putting the hit at the ray's start.  There the
                 * cancellation-free form gives both roots. */
                double q = -0.5 * (B + copysign(sqrt(disc), B));
                t1 = q / A;
                t2 = q != 0.0 ? C / q : tl;
            } else {
                t1 = (-B + sqrt(disc)) / (2.0 * A);
                t2 = (-B - sqrt(disc)) / (2.0 * A);
            }
            ok1 = k1 * c * (zl + t1 * d[2]) <= 1.0;
            ok2 = k1 * c * (zl + t2 * d[2]) <= 1.0;
            if (ok1 && ok2)
                tt = fabs(t1 - tl) <= fabs(t2 - tl) ? t1 : t2;
            else if (ok1)
                tt = t1;
            else if (ok2)
                tt = t2;
            else
                goto miss;
        }
        if (0) {
        miss:
            /* A shape of its own may meet a ray its base conic misses:
             * Newton starts on the tangent plane. */
            if (s->shape != SHAPE_GEN || d[2] == 0.0) {
                sg_fail_rest(out, i, t->n, SG_EMISS);
                return SG_EMISS;
            }
            tt = -zl / d[2];
        }
        if (s->shape == SHAPE_ASPH || s->shape == SHAPE_GEN) {
            double pl[3] = {P[0], P[1], zl};
            int rc2 = asph_root_d(s, pl, d, tt, t->o.max_iter, &tt, &hgen);
            if (rc2 <= 0) {
                sg_fail_rest(out, i, t->n, rc2 < 0 ? SG_ENOCONV : SG_EMISS);
                return rc2 < 0 ? SG_ENOCONV : SG_EMISS;
            }
        }
        /* The paper's eqs. 11 and 17 with the coefficients actually used;
         * the root's relative error follows from the coefficient errors. */
        sigA = 8.0 * U53 * fabs(c) * (d[0] * d[0] + d[1] * d[1]) + 9.0 * U53 * fabs(c) * d[2] * d[2] +
               10.0 * U53 * fabs(c * (k1 - 1.0)) * d[2] * d[2];
        sigB = 16.0 * U53 * fabs(c) * (fabs(P[0] * d[0]) + fabs(P[1] * d[1])) +
               20.0 * U53 * fabs(c * zl * d[2]) + 22.0 * U53 * fabs(c * (k1 - 1.0) * zl * d[2]) +
               6.0 * U53 * fabs(d[2]);
        sigC = 8.0 * U53 * fabs(c) * (P[0] * P[0] + P[1] * P[1]) + 9.0 * U53 * fabs(c) * zl * zl +
               10.0 * U53 * fabs(c * (k1 - 1.0)) * zl * zl + 6.0 * U53 * fabs(zl) +
               3.0 * U53 * fabs(P[2]);
        {
            double slope = fabs(2.0 * A * tt + B);
            double num = sigA * tt * tt + sigB * fabs(tt) + sigC;
            eta_t = slope > 0.0 ? num / slope : INFINITY;
            if (s->shape == SHAPE_ASPH || s->shape == SHAPE_GEN)
                eta_t += 8.0 * U53 * fabs(tt);
        }
        dlen = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        x = P[0] + tt * d[0];
        y = P[1] + tt * d[1];
        z = P[2] + tt * d[2];
        {
            double kappa, pl[3] = {x, y, z - s->zg}, dl[3] = {d[0] / dlen, d[1] / dlen, d[2] / dlen};
            double cg = surf_cos_d(s, pl, dl);
            kappa = cg > 0.0 ? 1.0 / cg : 1e300;
            eP = kappa * (eP + fabs(tt) * dlen * eD) + eta_t * dlen +
                 4.0 * U53 * (fabs(tt) * dlen + fmax(fabs(x), fmax(fabs(y), fabs(z)))) +
                 3.0 * U53 * fmax(fabs(P[0]), fmax(fabs(P[1]), fabs(P[2])));
        }
        P[0] = x;
        P[1] = y;
        P[2] = z;
        o->x = x;
        o->y = y;
        o->z = z - s->zg;
        /* Converting to the local frame rounds once more. */
        eP += U53 * fabs(o->z);
        if (isnan(eP))
            eP = INFINITY;
        /* Signed, as in the other methods: negative for a surface behind
         * the ray's start. */
        o->path = tt * dlen;
        {
            /* The textbook optical path: |n| times each step, summed in
             * double; its estimate from the roundings of the step and the
             * sum (a point's error off the ray's own path moves the path
             * only to second order, by Fermat's principle). */
            double nb = fabs(t->nsigned[i - 1]);
            opl += nb * o->path;
            eO += nb * (eta_t * dlen + 4.0 * U53 * fabs(o->path)) + 2.0 * U53 * fabs(opl);
            o->opl = opl;
            o->opl_lo = 0.0;
            o->opl_error_bound = sg_bound_up(eO);
        }
        o->residual = sg_sprep_sag_resid(s, o->x, o->y, o->z);
        o->error_bound = sg_bound_up(eP);
        o->status = SG_OK;
        if (sg_past_clip(t, s, o->x, o->y)) {
            sg_fail_rest(out, i, t->n, SG_EVIGNETTED);
            return SG_EVIGNETTED;
        }
        if (i < upto) {
            double pl[3] = {o->x, o->y, o->z};
            double gsens = s->shape == SHAPE_CONIC ? fmax(1.0, fabs(k1)) * fabs(c) : 0.0;
            int rc;
            if (s->shape == SHAPE_ASPH) {
                double w, dw;
                slope_d(s, x * x + y * y, &w, &dw);
                gsens = fabs(w) + 2.0 * dw;
            }
            if (s->shape == SHAPE_GEN)
                gsens = hgen;
            rc = classic_bend(s, pl, d, &dn);
            if (rc != SG_OK) {
                sg_fail_rest(out, i, t->n, rc);
                return rc;
            }
            eD = dn * (eD / (dlen > 0 ? dlen : 1.0)) + 4.0 * gsens * eP + 24.0 * U53 * (s->mu.hi + 2.0);
            if (isnan(eD))
                eD = INFINITY;
        }
        o->l = d[0];
        o->m = d[1];
        o->n = d[2];
        o->dir_error_bound = sg_bound_up(eD);
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * The tracer.
 * ------------------------------------------------------------------------ */

int sg_indices_mpfr(const sg_system *sys, const sg_catalog *cat, int wave,
                    mpfr_t *idx, sg_diag *d)
{
    return sg_indices_mpfr_cached(sys, cat, wave, idx, NULL, d);
}

int sg_indices_mpfr_cached(const sg_system *sys, const sg_catalog *cat, int wave,
                           mpfr_t *idx, sg_index_cache *cache, sg_diag *d)
{
    mpfr_t um;
    int i, sign = 1, rc = SG_OK;
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
                                : cat ? sg_catalog_find(cat, s->mat.name) : NULL;
            if (!g && s->mat.kind == SG_MAT_MODEL) {
                rc = sg_diag_set(d, SG_ERANGE, "surface %d: model glass nd %g, vd %g, dPgF %g "
                                 "is outside the model's limits", i, s->mat.index, s->mat.vd,
                                 s->mat.dpgf);
                goto out;
            }
            if (!g) {
                rc = sg_diag_set(d, SG_ENOGLASS,
                                 "surface %d: material \"%s\" is not in the catalog", i,
                                 s->mat.name);
                goto out;
            }
            if (sg_index_cache_glass(cache, sys, g, idx[i], um) != SG_OK) {
                rc = sg_diag_set(d, SG_ERANGE,
                                 "surface %d: glass %s has no real index at %g um", i,
                                 g->name, sys->wave[wave].um);
                goto out;
            }
            if (sign < 0)
                mpfr_neg(idx[i], idx[i], MPFR_RNDN);
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

static int prepare_surfaces(sg_tracer *t, mpfr_t *idx, sg_diag *d)
{
    const sg_system *sys = t->sys;
    mpfr_t q, tmp;
    double zg = 0.0;
    int i, k;
    mpfr_init2(q, 256);
    mpfr_init2(tmp, 256);
    for (i = 0; i < t->n; i++) {
        const sg_surface *s = &sys->surf[i];
        sg_sprep *p = &t->sp[i];
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
            if (rc != SG_OK) {
                mpfr_clear(q);
                mpfr_clear(tmp);
                return rc;
            }
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
        p->xf = i >= 2 && sg_xfer_moves(sys, i) ? prepare_xfer(t, i) : NULL;
        /* Classic traces in the frame of the last surface a transfer
         * turned or moved (surface 1's until then): zg is the vertex's z
         * there. */
        if (p->xf)
            zg = 0.0;
        else if (i >= 2)
            zg += p->T;
        p->zg = i >= 1 ? zg : -p->T;
        t->nsigned[i] = mpfr_get_d(idx[i], MPFR_RNDN);
        if (i > 0) {
            mpfr_abs(q, idx[i - 1], MPFR_RNDN);
            mpfr_abs(tmp, idx[i], MPFR_RNDN);
            if (mpfr_zero_p(tmp)) {
                mpfr_clear(q);
                mpfr_clear(tmp);
                return sg_diag_set(d, SG_ENONPHYS, "surface %d: index is zero", i);
            }
            mpfr_div(q, q, tmp, MPFR_RNDN);
            p->mu = dd_from_mpfr(q, tmp);
            p->mu2 = dd_sqr(p->mu);
        }
    }
    mpfr_clear(q);
    mpfr_clear(tmp);
    return SG_OK;
}

sg_tracer *sg_tracer_new(const sg_system *sys, const sg_catalog *cat,
                         const sg_trace_opts *opts, sg_diag *d)
{
    return sg_tracer_new_cached(sys, cat, opts, NULL, d);
}

static int tracer_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                       sg_index_cache *cache, sg_tracer **out, sg_diag *d);

sg_tracer *sg_tracer_new_cached(const sg_system *sys, const sg_catalog *cat,
                                const sg_trace_opts *opts, sg_index_cache *cache,
                                sg_diag *d)
{
    sg_tracer *t = NULL;
    sg_diag own;
    /* The code must reach a caller who passed no diagnostic only through
     * sg_tracer_open; here NULL says it failed. */
    if (!d) {
        sg_diag_clear(&own);
        d = &own;
    }
    return tracer_open(sys, cat, opts, cache, &t, d) == SG_OK ? t : NULL;
}

int sg_tracer_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                   sg_tracer **out, sg_diag *d)
{
    return tracer_open(sys, cat, opts, NULL, out, d);
}

static int tracer_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                       sg_index_cache *cache, sg_tracer **out, sg_diag *d)
{
    sg_tracer *t;
    mpfr_t *idx = NULL;
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
    rc = sg_system_check(sys, cat, d);
    if (rc != SG_OK)
        return rc;
    t = calloc(1, sizeof *t);
    if (!t)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
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
    t->sys = sg_system_clone(sys);
    t->sp = calloc((size_t)n, sizeof *t->sp);
    t->nsigned = calloc((size_t)n, sizeof *t->nsigned);
    idx = sg_mp_block_new((size_t)n, 256);
    if (!t->sys || !t->sp || !t->nsigned || !idx) {
        sg_diag_set(d, SG_ENOMEM, "out of memory");
        free(idx);
        goto fail;
    }
    for (i = 2; i < n; i++)
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
        if (sg_shape_ops_of(sys->surf[i].type)) {
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
        rc = prepare_surfaces(t, idx, d);
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
        t->prim = sg_tracer_new_cached(sys, cat, &po, cache, &pd);
        if (!t->prim) {
            sg_diag_set(d, pd.code != SG_OK ? pd.code : SG_ENOMEM,
                        "primary wavelength %d, which defines the pupil and fields: %s",
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

int sg_tracer_fork(const sg_tracer *m, sg_tracer **out, sg_diag *d)
{
    sg_tracer *t = calloc(1, sizeof *t);
    int rc;
    *out = NULL;
    if (!t)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    /* The prepared model, shared; the workspace starts empty. */
    t->model = m->model ? m->model : m;
    t->sys = m->sys;
    t->o = m->o;
    t->wave = m->wave;
    t->n = m->n;
    t->sp = m->sp;
    t->xf = m->xf;
    t->shp = m->shp;
    t->nsigned = m->nsigned;
    t->px = m->px;
    t->ln = m->ln;
    t->cat = m->cat;
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

sg_tracer *sg_tracer_new_method(const sg_tracer *m, sg_method method, int mpfr_bits,
                                sg_index_cache *cache, sg_diag *d)
{
    sg_trace_opts o = m->o;
    sg_tracer *t;
    sg_diag own;
    if (!d) {
        sg_diag_clear(&own);
        d = &own;
    }
    o.method = method;
    o.mpfr_bits = mpfr_bits;
    /* Classic lands the real-aim stop radius its own way (launch.c), and
     * the precision's range is tracer_open's to check. */
    if (m->o.method == SG_METHOD_CLASSIC || method == SG_METHOD_CLASSIC ||
        mpfr_bits < 53 || mpfr_bits > 100000)
        return sg_tracer_new_cached(m->sys, m->cat, &o, cache, d);
    t = calloc(1, sizeof *t);
    if (!t) {
        sg_diag_set(d, SG_ENOMEM, "out of memory");
        return NULL;
    }
    /* The prepared model, shared as a fork shares it; only the options'
     * method and precision differ, which the model does not read. */
    t->model = m->model ? m->model : m;
    t->sys = m->sys;
    t->o = o;
    t->wave = m->wave;
    t->n = m->n;
    t->sp = m->sp;
    t->xf = m->xf;
    t->shp = m->shp;
    t->nsigned = m->nsigned;
    t->px = m->px;
    t->ln = m->ln;
    t->cat = m->cat;
    if (m->prim) {
        /* Named as tracer_open names the primary wavelength's failure. */
        sg_diag pd;
        sg_diag_clear(&pd);
        t->prim = sg_tracer_new_method(m->prim, method, mpfr_bits, cache, &pd);
        if (!t->prim) {
            sg_diag_set(d, pd.code != SG_OK ? pd.code : SG_ENOMEM,
                        "primary wavelength %d, which defines the pupil and fields: %s",
                        t->sys->primary_wave + 1, pd.msg);
            goto fail;
        }
    }
    t->scratch = calloc((size_t)t->n, sizeof *t->scratch);
    if (!t->scratch || !(t->rescue = sg_mpfr_rescue_new())) {
        sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    t->icache = cache;
    if (t->o.method == SG_METHOD_MPFR && sg_mpfr_prepare(t, d) != SG_OK)
        goto fail;
    t->icache = NULL;
    return t;
fail:
    if (d->code == SG_OK)
        sg_diag_set(d, SG_ENOMEM, "out of memory");
    sg_tracer_free(t);
    return NULL;
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
static int start_invalid(const sg_tracer *t, const double start[3], const double dir[3],
                         sg_ray_surface *out)
{
    double len2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    int k;
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

int sg_start_precise_prep(const sg_tracer *t, const double start[3], const double dir[3],
                          sg_ray_surface *out, sg_pray *r)
{
    dd len;
    double u[3];
    int rc = start_invalid(t, start, dir, out);
    if (rc != SG_OK)
        return rc;
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

int sg_trace_start(sg_tracer *t, const double start[3], const double dir[3],
                   sg_ray_surface *out)
{
    double len2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    int rc;
    if (t->o.method == SG_METHOD_PRECISE) {
        /* The preparation checks the ray, as it does for the batch. */
        sg_pray r;
        rc = sg_start_precise_prep(t, start, dir, out, &r);
        return rc != SG_OK ? rc : sg_guard_rows(t, out, sg_precise_run_to(t, &r, 0.0, out, t->n - 1));
    }
    rc = start_invalid(t, start, dir, out);
    if (rc != SG_OK)
        return rc;
    switch (t->o.method) {
    case SG_METHOD_CLASSIC: {
        double len = sqrt(len2), u[3];
        u[0] = dir[0] / len;
        u[1] = dir[1] / len;
        u[2] = dir[2] / len;
        sg_set_start_row(&out[0], start, u);
        return sg_guard_rows(t, out, sg_classic_run_to(t, start, dir, out, t->n - 1));
    }
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
