/*
 * shape_vd.h - the double sags of the shapes beyond the even asphere (odd
 * asphere, toroid, biconic, Zernike, XY polynomial) on SG_VL lanes at
 * once: each shape's sag_d, its value, gradient and second-derivative
 * bound.
 *
 * Each function repeats its scalar twin (shape.c's sg_rot_d, sg_p2_d,
 * sg_rot_p2_d; the odd asphere's sag_d; the toroid's and biconic's are
 * compiled here from the one text both share, shape_toroid_k.h and
 * shape_biconic_k.h) operation for operation and in the same order, its
 * constants formed in scalar as there, branches becoming selections, so
 * every lane gets the bits the scalar code gives it (the build uses
 * -ffp-contract=off and only correctly rounded operations): the classic
 * trace takes them from here instead of calling the shape's sag_d lane by
 * lane.  A lane outside the shape's domain is marked in *bad and its
 * numbers are not to be read, as the scalar code returns 0 there.
 * tests/test_shapes.c compares the two bit for bit.  Included by the
 * vector trace only, so each instruction set gets its own copy.
 */
#ifndef SG_SHAPE_VD_H
#define SG_SHAPE_VD_H

#include "shape.h"
#include "vdd.h"

/* shape.c's sg_rot_d: the one text of shape_rot_k.h on lanes. */
#define SG_TMPL 2 /* SG_TMPL_VD */
#include "shape_tmpl_on.h"
#include "shape_rot_k.h"
#include "shape_tmpl_off.h"

/* sg_p2_d: the polynomial in u = x / norm, v = y / norm. */
static inline void sv_p2_d(const sg_shape *s, vd x, vd y, vd *z, vd g[2], vd *h)
{
    vd U[SG_P2_DEG + 1], V[SG_P2_DEG + 1], zz = vd_set(0.0), gx = vd_set(0.0),
                                           gy = vd_set(0.0), hh = vd_set(0.0);
    vd u = x / s->norm, v = y / s->norm;
    int a, b, n = s->deg;
    U[0] = V[0] = vd_set(1.0);
    for (a = 1; a <= n; a++) {
        U[a] = U[a - 1] * u;
        V[a] = V[a - 1] * v;
    }
    for (a = 0; a <= n; a++)
        for (b = 0; a + b <= n; b++) {
            int at = SG_P2_AT(a, b);
            double c = s->c[at].hi, m = s->cm[at];
            if (m == 0.0)
                continue;
            zz += c * U[a] * V[b];
            if (a)
                gx += a * c * U[a - 1] * V[b];
            if (b)
                gy += b * c * U[a] * V[b - 1];
            if (a > 1)
                hh += a * (a - 1) * m * vd_abs(U[a - 2] * V[b]);
            if (a && b)
                hh += 2.0 * a * b * m * vd_abs(U[a - 1] * V[b - 1]);
            if (b > 1)
                hh += b * (b - 1) * m * vd_abs(U[a] * V[b - 2]);
        }
    *z = zz;
    g[0] = gx / s->norm;
    g[1] = gy / s->norm;
    *h = hh / (s->norm * s->norm);
}

/* sg_rot_p2_d: the rotational part plus the polynomial about (px, py). */
static inline void sv_rot_p2_d(const sg_shape *s, vd x, vd y, vd *z, vd g[2], vd *h, vm *bad)
{
    vd r2 = x * x + y * y, w, dw, zp, gp[2], hp;
    sv_rot_d(s, r2, z, &w, &dw, bad);
    sv_p2_d(s, x - s->px, y - s->py, &zp, gp, &hp);
    *z += zp;
    g[0] = w * x + gp[0];
    g[1] = w * y + gp[1];
    *h = 1.5 * (vd_abs(w) + 4.0 * dw * r2 + hp);
}

/* shape_odd.c's odd_d: the one text of shape_rot_k.h on lanes. */
#define SG_TMPL 2 /* SG_TMPL_VD */
#define SG_ROT_K_ODD
#include "shape_tmpl_on.h"
#include "shape_rot_k.h"
#include "shape_tmpl_off.h"
#undef SG_ROT_K_ODD

/* shape_toroid.c's tor_d: the one text of shape_toroid_k.h on lanes. */
#define SG_TMPL 2 /* SG_TMPL_VD */
#include "shape_tmpl_on.h"
#include "shape_toroid_k.h"
#include "shape_tmpl_off.h"

/* shape_biconic.c's bic_d: the one text of shape_biconic_k.h on lanes. */
#define SG_TMPL 2 /* SG_TMPL_VD */
#include "shape_tmpl_on.h"
#include "shape_biconic_k.h"
#include "shape_tmpl_off.h"

/* Whether this file has the shape's double sag. */
static inline int sv_handles_d(const sg_shape *s)
{
    return s->ops && (s->ops->sag_d == sg_rot_p2_d || s->ops == &sg_shape_odd_ops ||
                      s->ops == &sg_shape_toroid_ops || s->ops == &sg_shape_biconic_ops);
}

/* The shape's sag_d on every lane, for a shape sv_handles_d. */
static inline void sv_sag_d(const sg_shape *s, vd x, vd y, vd *z, vd g[2], vd *h, vm *bad)
{
    if (s->ops == &sg_shape_odd_ops)
        sv_odd_d(s, x, y, z, g, h, bad);
    else if (s->ops == &sg_shape_toroid_ops)
        sv_tor_d(s, x, y, z, g, h, bad);
    else if (s->ops == &sg_shape_biconic_ops)
        sv_bic_d(s, x, y, z, g, h, bad);
    else
        sv_rot_p2_d(s, x, y, z, g, h, bad);
}

/* The shape's sag_d on every lane: sv_sag_d for a shape sv_handles_d,
 * else the scalar sag_d lane by lane on the lanes of live (z, g and h 0
 * elsewhere). */
static inline void sv_sag_d_live(const sg_shape *s, vd x, vd y, vm live, vd *z, vd g[2], vd *h,
                                 vm *bad)
{
    int k;
    if (sv_handles_d(s)) {
        sv_sag_d(s, x, y, z, g, h, bad);
        return;
    }
    *z = *h = g[0] = g[1] = vd_set(0.0);
    *bad = vm_set(0);
    for (k = 0; k < SG_VL; k++) {
        double zk, gk[2], hk;
        if (!live[k])
            continue;
        if (!s->ops->sag_d(s, x[k], y[k], &zk, gk, &hk)) {
            (*bad)[k] = -1;
            continue;
        }
        (*z)[k] = zk;
        g[0][k] = gk[0];
        g[1][k] = gk[1];
        (*h)[k] = hk;
    }
}

#endif
