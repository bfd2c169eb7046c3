/*
 * slope_vec.h - w = sag'(r) / r of a conic and even asphere and dw/d(r^2),
 * in double on SG_VL lanes: the Newton slopes and residual weights that
 * the precise and the classic vector traces share.  Included by both, so
 * each instruction set gets its own copy.
 */
#ifndef SG_SLOPE_VEC_H
#define SG_SLOPE_VEC_H

#include "trace_int.h"
#include "vdd.h"

/* w = sag'(r) / r and the bound on |dw/dr^2| r^2 for an even asphere;
 * powers by running product, the same rounding in both traces. */
static inline void slope_v(const sg_sprep *s, vd r2, vd *w, vd *dw)
{
    vd ww = vd_set(0.0), dd2 = vd_set(0.0), rk = vd_set(1.0);
    int k;
    if (isfinite(s->R)) {
        vd q = s->R * s->R - s->k1.hi * r2;
        vd sq = vd_sqrt(vd_abs(q));
        ww = (s->R < 0 ? -1.0 : 1.0) / sq;
        dd2 = fabs(s->k1.hi) / (2.0 * vd_abs(q) * sq) * r2;
    }
    for (k = 1; k < s->nasph; k++) {
        vd p;
        rk = rk * r2;
        p = (double)(2 * (k + 1)) * s->a[k] * rk;
        ww += p;
        dd2 += vd_abs(p) * (double)(k);
    }
    if (s->nasph)
        ww += 2.0 * s->a[0];
    *w = ww;
    *dw = dd2;
}

/* At the point (x, y, z): F = z - sag and F' along d for an even asphere
 * in double, with w and dw as slope_v gives them; *neg marks the lanes
 * outside the conic (their numbers are NaN).  The Newton step of both
 * vector traces. */
static inline void asph_F_v(const sg_sprep *s, vd x, vd y, vd z, const vd d[3], vd *F, vd *Fp,
                            vd *w, vd *dw, vm *neg)
{
    vd r2 = x * x + y * y, sag = vd_set(0.0), pp = vd_set(0.0);
    int k;
    *neg = vm_set(0);
    if (isfinite(s->R)) {
        vd q = s->R * s->R - s->k1.hi * r2;
        *neg = (vm)(q < 0.0);
        sag = r2 / (s->R + vd_copysign(vd_sqrt(q), vd_set(s->R)));
    }
    for (k = s->nasph - 1; k >= 0; k--)
        pp = pp * r2 + s->a[k];
    sag += pp * r2;
    slope_v(s, r2, w, dw);
    *F = z - sag;
    *Fp = d[2] - *w * (x * d[0] + y * d[1]);
}

#endif
