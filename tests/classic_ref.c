/*
 * classic_ref.c - the classic method as it was before it became a vector
 * kernel (src/trace/trace_classic_vec.c): the scalar, one-ray trace of
 * src/trace.c (now src/trace/trace.c) at commit 84d7042, copied unchanged but for its name, so
 * that test_classic_vec can check the kernel against it bit for bit.
 */
#include <math.h>
#include <string.h>

#include "classic_ref.h"

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

int classic_ref_run_to(const sg_tracer *t, const double S[3], const double D[3],
                       sg_ray_surface *out, int upto)
{
    double P[3] = {S[0], S[1], S[2]}, d[3] = {D[0], D[1], D[2]};
    double eP = 0.0, eD = 0.0, opl = 0.0, eO = 0.0;
    int i, rc;
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
        if ((rc = sg_past_clip(t, s, o->x, o->y)) != 0) {
            sg_fail_rest(out, i, t->n, rc);
            return rc;
        }
        if (i < upto) {
            double pl[3] = {o->x, o->y, o->z};
            double gsens = s->shape == SHAPE_CONIC ? fmax(1.0, fabs(k1)) * fabs(c) : 0.0;
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

