/*
 * shape_vdd.h - the Zernike and XY polynomial shapes (a rotational conic
 * and even polynomial plus a polynomial in x and y) in double-double on
 * SG_VL lanes at once.
 *
 * Each function repeats shape.c's scalar one (sg_rot_dd, sg_p2_dd,
 * sg_rot_p2_dd) operation for operation in the vector twins of dd.h's
 * operations, so every lane gets the bits the scalar code gives it: the
 * precise trace takes them from here instead of calling the shape's ops
 * lane by lane.  A lane outside the conic is marked in *bad and its
 * numbers are not to be read, as the scalar code returns 0 there.
 * tests/test_shapes.c compares the two bit for bit.  Included by the
 * vector trace only, so each instruction set gets its own copy.
 */
#ifndef SG_SHAPE_VDD_H
#define SG_SHAPE_VDD_H

#include "shape.h"
#include "vdd.h"

/* dd_div: three quotients, as there. */
static inline vdd svd_div(vdd a, vdd b)
{
    vd q1 = a.hi / b.hi, q2, q3;
    vdd r = vdd_sub(a, vdd_mul_d(b, q1)), q;
    q2 = r.hi / b.hi;
    r = vdd_sub(r, vdd_mul_d(b, q2));
    q3 = r.hi / b.hi;
    q = vdd_fast_two_sum(q1, q2);
    return vdd_add_d(q, q3);
}

/* dd_div_d. */
static inline vdd svd_div_d(vdd a, double b)
{
    vd bv = vd_set(b), q1 = a.hi / bv, r;
    vdd p = vdd_two_prod(q1, bv);
    r = ((a.hi - p.hi) - p.lo) + a.lo;
    return vdd_fast_two_sum(q1, r / bv);
}

/* Whether a shape's double-double sag is sg_rot_p2_dd with nothing this
 * file lacks (odd terms). */
static inline int svd_handles(const sg_shape *s)
{
    return s->ops && s->ops->sag_dd == sg_rot_p2_dd && s->nodd == 0;
}

/* sg_rot_dd without odd terms. */
static inline void svd_rot(const sg_shape *s, vdd r2, vdd *z, vdd *w, vd *ez, vd *ew, vm *bad)
{
    vdd zz = vdd_from(vd_set(0.0)), ww = vdd_from(vd_set(0.0)), rk = vdd_from(vd_set(1.0));
    vd mz = vd_set(0.0), mw = vd_set(0.0), r2d = r2.hi;
    int k, n = s->na;
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
        zz = svd_div(r2, vdd_add(R, sq));
        ww = svd_div(vdd_from(vd_set(1.0)), sq);
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
         * kernel, lane by lane. */
        vdd xs = vdd_add_d(x, vd_set(-s->px)), ys = vdd_add_d(y, vd_set(-s->py));
        vd ex = 2.0 * DD_U * (vd_abs(x.hi) + fabs(s->px)),
           ey = 2.0 * DD_U * (vd_abs(y.hi) + fabs(s->py)), hd;
        int k;
        svd_p2(s, xs, ys, &zp, gp, &ezp, &egp);
        for (k = 0; k < SG_VL; k++) {
            double zd, gd[2], h;
            sg_p2_d(s, xs.hi[k], ys.hi[k], &zd, gd, &h);
            hd[k] = h;
        }
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

#endif
