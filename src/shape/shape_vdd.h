/*
 * shape_vdd.h - the double-double sags of the shapes beyond the even
 * asphere (odd asphere, toroid, biconic, Zernike, XY polynomial) on
 * SG_VL lanes at once.
 *
 * Each function repeats its scalar twin (shape.c's sg_rot_dd, sg_p2_dd,
 * sg_rot_p2_dd; the odd asphere's sag_dd; the toroid's and biconic's are
 * compiled here from shape_toroid_k.h and shape_biconic_k.h) operation for operation in the vector twins of dd.h's
 * operations, branches becoming selections, so every lane gets the bits
 * the scalar code gives it: the precise trace takes them from here
 * instead of calling the shape's ops lane by lane.  A lane outside the
 * shape's domain is marked in *bad and its numbers are not to be read,
 * as the scalar code returns 0 there.  tests/test_shapes.c compares the
 * two bit for bit.  Included by the vector trace only, so each
 * instruction set gets its own copy.
 */
#ifndef SG_SHAPE_VDD_H
#define SG_SHAPE_VDD_H

#include "shape.h"
#include "shape_vd.h"
#include "vdd.h"

/* dd_div_d. */
static inline vdd svd_div_d(vdd a, double b)
{
    vd bv = vd_set(b), q1 = a.hi / bv, r;
    vdd p = vdd_two_prod(q1, bv);
    r = ((a.hi - p.hi) - p.lo) + a.lo;
    return vdd_fast_two_sum(q1, r / bv);
}

/* sg_rot_dd. */
static inline void svd_rot(const sg_shape *s, vdd r2, vdd *z, vdd *w, vd *ez, vd *ew, vm *bad)
{
    vdd zz = vdd_from(vd_set(0.0)), ww = vdd_from(vd_set(0.0)), rk = vdd_from(vd_set(1.0));
    vd mz = vd_set(0.0), mw = vd_set(0.0), r2d = r2.hi;
    int k, n = s->na + s->nodd;
    *ez = vd_set(0.0);
    *ew = vd_set(0.0);
    *bad = vm_set(0);
    if (isfinite(s->R)) {
        vdd R = vdd_from(vd_set(s->R)), q, sq;
        vd cond;
        q = vdd_sub(vdd_sqr(R), vdd_mul_d(r2, vd_set(s->k1)));
        *bad = (vm)(q.hi < 0.0);
        sq = vdd_sqrt(q);
        if (s->R < 0)
            sq = vdd_neg(sq);
        zz = vdd_div(r2, vdd_add(R, sq));
        ww = vdd_div(vdd_from(vd_set(1.0)), sq);
        cond = 1.0 + (s->R * s->R + fabs(s->k1) * r2d) / q.hi;
        *ez = 16.0 * DD_U * vd_abs(zz.hi) * cond;
        *ew = 16.0 * DD_U * vd_abs(ww.hi) * cond;
    }
    for (k = 0; k < s->na; k++) {
        vdd t = vdd_mul_d(rk, vd_set(s->a[k]));
        zz = vdd_add(zz, vdd_mul(t, r2));
        ww = vdd_add(ww, vdd_mul_d(t, vd_set(2.0 * k + 2.0)));
        mz += vd_abs(t.hi * r2d);
        mw += vd_abs(t.hi) * (2.0 * k + 2.0);
        rk = vdd_mul(rk, r2);
    }
    if (s->nodd) {
        /* The scalar code's branch on r^2 > 0 is a selection per lane;
         * 1 / r^2 is formed everywhere and kept only there. */
        vdd r = vdd_sqrt(r2), rp = vdd_from(vd_set(1.0)),
            rm = vdd_from(vd_set(0.0));
        vm pos = (vm)(r2d > 0.0);
        rm = vdd_sel(pos, vdd_div(vdd_from(vd_set(1.0)), r2), rm);
        for (k = 0; k < s->nodd; k++) {
            vdd t, tw, wz;
            vd mwz;
            rp = vdd_mul(rp, r);
            t = vdd_mul_d(rp, vd_set(s->odd[k]));
            zz = vdd_add(zz, t);
            mz += vd_abs(t.hi);
            tw = vdd_mul(vdd_mul_d(t, vd_set(k + 1.0)), rm);
            /* At r = 0 only the r^2 term has a slope over r. */
            wz = ww;
            mwz = mw;
            if (k == 1) {
                wz = vdd_add(ww, vdd_from(vd_set(2.0 * s->odd[k])));
                mwz = mw + fabs(2.0 * s->odd[k]);
            }
            ww = vdd_sel(pos, vdd_add(ww, tw), wz);
            mw = vsel(pos, mw + vd_abs(tw.hi), mwz);
        }
    }
    *ez += (16.0 + 6.0 * n) * DD_U * mz;
    *ew += (16.0 + 6.0 * n) * DD_U * mw;
    *z = zz;
    *w = ww;
}

/* sg_p2_dd. */
static inline void svd_p2(const sg_shape *s, vdd x, vdd y, vdd *z, vdd g[2], vd *ez, vd *eg)
{
    vdd U[SG_P2_DEG + 1], V[SG_P2_DEG + 1], zz = vdd_from(vd_set(0.0)),
                                              gx = vdd_from(vd_set(0.0)),
                                              gy = vdd_from(vd_set(0.0));
    vdd u = svd_div_d(x, s->norm), v = svd_div_d(y, s->norm);
    vd mz = vd_set(0.0), mg = vd_set(0.0);
    int a, b, n = s->deg;
    U[0] = V[0] = vdd_from(vd_set(1.0));
    for (a = 1; a <= n; a++) {
        U[a] = vdd_mul(U[a - 1], u);
        V[a] = vdd_mul(V[a - 1], v);
    }
    for (a = 0; a <= n; a++)
        for (b = 0; a + b <= n; b++) {
            int at = SG_P2_AT(a, b);
            double m = s->cm[at];
            vdd c = vdd_set(s->c[at]);
            if (m == 0.0)
                continue;
            zz = vdd_add(zz, vdd_mul(c, vdd_mul(U[a], V[b])));
            mz += m * vd_abs(U[a].hi * V[b].hi);
            if (a) {
                gx = vdd_add(gx, vdd_mul(vdd_mul_d(c, vd_set((double)a)), vdd_mul(U[a - 1], V[b])));
                mg += a * m * vd_abs(U[a - 1].hi * V[b].hi);
            }
            if (b) {
                gy = vdd_add(gy, vdd_mul(vdd_mul_d(c, vd_set((double)b)), vdd_mul(U[a], V[b - 1])));
                mg += b * m * vd_abs(U[a].hi * V[b - 1].hi);
            }
        }
    {
        double k = (double)(s->nz + 4 * n + SG_P2_N + 16) * DD_U;
        *ez = k * mz;
        *eg = k * mg / s->norm + 4.0 * DD_U * (vd_abs(gx.hi) + vd_abs(gy.hi)) / s->norm;
    }
    *z = zz;
    g[0] = svd_div_d(gx, s->norm);
    g[1] = svd_div_d(gy, s->norm);
}

/* sg_rot_p2_dd, with a Zernike sag's decenter as there. */
static inline void svd_rot_p2(const sg_shape *s, vdd x, vdd y, vdd *z, vdd g[2], vd *ez, vd *eg,
                              vm *bad)
{
    vdd r2 = vdd_add(vdd_sqr(x), vdd_sqr(y)), w, zp, gp[2];
    vd ew, ezp, egp, m = vd_fmax(vd_abs(x.hi), vd_abs(y.hi));
    svd_rot(s, r2, z, &w, ez, &ew, bad);
    *ez += 4.0 * DD_U * vd_abs(w.hi) * r2.hi;
    if (s->px != 0.0 || s->py != 0.0) {
        /* A Zernike sag's decenter, with the scalar code's bounds on the
         * shift; the second-derivative bound comes from the double
         * kernel (shape_vd.h). */
        vdd xs = vdd_add_d(x, vd_set(-s->px)), ys = vdd_add_d(y, vd_set(-s->py));
        vd ex = 2.0 * DD_U * (vd_abs(x.hi) + fabs(s->px)),
           ey = 2.0 * DD_U * (vd_abs(y.hi) + fabs(s->py)), hd, zd, gd[2];
        svd_p2(s, xs, ys, &zp, gp, &ezp, &egp);
        sv_p2_d(s, xs.hi, ys.hi, &zd, gd, &hd);
        ezp += 2.0 * (vd_abs(gp[0].hi) * ex + vd_abs(gp[1].hi) * ey);
        egp += 2.0 * hd * vd_fmax(ex, ey);
    } else {
        svd_p2(s, x, y, &zp, gp, &ezp, &egp);
    }
    *z = vdd_add(*z, zp);
    g[0] = vdd_add(vdd_mul(w, x), gp[0]);
    g[1] = vdd_add(vdd_mul(w, y), gp[1]);
    *ez += ezp + 2.0 * DD_U * (vd_abs(z->hi) + vd_abs(zp.hi));
    *eg = (ew + 8.0 * DD_U * vd_abs(w.hi)) * m + egp +
          2.0 * DD_U * (vd_abs(g[0].hi) + vd_abs(g[1].hi) + vd_abs(gp[0].hi) + vd_abs(gp[1].hi));
}

/* shape_odd.c's odd_dd. */
static inline void svd_odd(const sg_shape *s, vdd x, vdd y, vdd *z, vdd g[2], vd *ez, vd *eg,
                           vm *bad)
{
    vdd r2 = vdd_add(vdd_sqr(x), vdd_sqr(y)), w;
    vd ew, m = vd_fmax(vd_abs(x.hi), vd_abs(y.hi));
    svd_rot(s, r2, z, &w, ez, &ew, bad);
    *ez += 4.0 * DD_U * vd_abs(w.hi) * r2.hi;
    g[0] = vdd_mul(w, x);
    g[1] = vdd_mul(w, y);
    *eg = (ew + 8.0 * DD_U * vd_abs(w.hi)) * m;
}

/* shape_toroid.c's tor_dd: the one text of shape_toroid_k.h on lanes. */
#define SG_TMPL 4 /* SG_TMPL_VDD */
#include "shape_tmpl_on.h"
#include "shape_toroid_k.h"
#include "shape_tmpl_off.h"

/* shape_biconic.c's bic_dd: the one text of shape_biconic_k.h on lanes. */
#define SG_TMPL 4 /* SG_TMPL_VDD */
#include "shape_tmpl_on.h"
#include "shape_biconic_k.h"
#include "shape_tmpl_off.h"

/* Whether this file has the shape's double-double sag. */
static inline int svd_handles(const sg_shape *s)
{
    return s->ops && (s->ops->sag_dd == sg_rot_p2_dd || s->ops == &sg_shape_odd_ops ||
                      s->ops == &sg_shape_toroid_ops || s->ops == &sg_shape_biconic_ops);
}

/* The shape's sag_dd on every lane, for a shape svd_handles. */
static inline void svd_sag(const sg_shape *s, vdd x, vdd y, vdd *z, vdd g[2], vd *ez, vd *eg,
                           vm *bad)
{
    if (s->ops == &sg_shape_odd_ops)
        svd_odd(s, x, y, z, g, ez, eg, bad);
    else if (s->ops == &sg_shape_toroid_ops)
        svd_tor(s, x, y, z, g, ez, eg, bad);
    else if (s->ops == &sg_shape_biconic_ops)
        svd_bic(s, x, y, z, g, ez, eg, bad);
    else
        svd_rot_p2(s, x, y, z, g, ez, eg, bad);
}

#endif
