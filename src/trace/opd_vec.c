/*
 * opd_vec.c - sg_opd_of_rays: sg_opd_of_ray (opd.c) on SG_VL rays at once.
 *
 * Built once per instruction set in a build for no one processor, as
 * batch.c is (isa.h, dispatch.c): eight lanes with AVX-512, four with
 * AVX2, two with SSE2.  Every operation is the scalar one's, in its order,
 * and correctly rounded, so each variant gives each lane the scalar bits.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "trace_int.h"
#include "vdd.h"

/* Each operation is vdd.h's transcription of dd.h's, and dot3 and the
 * quotients are written out in opd.c's order.  A lane the vector form
 * does not cover (a failed ray, a line that misses the sphere, a
 * coordinate whose ulp is not a plain exponent shift) is handed to
 * sg_opd_of_ray itself. */

static inline vdd vdot3(vdd a0, vdd a1, vdd a2, vdd b0, vdd b1, vdd b2)
{
    return vdd_add(vdd_add(vdd_mul(a0, b0), vdd_mul(a1, b1)), vdd_mul(a2, b2));
}

/* sg_ulp_of where |x| is zero, subnormal or from 2^-969 to below
 * DBL_MAX (the exponent shift); *odd marks the other lanes. */
static inline vd vulp(vd x, vm *odd)
{
    vd a = vd_abs(x);
    vm bits = (vm)a, tiny = (vm)(a < vd_set(DBL_MIN));
    vd u = (vd)(((bits >> 52) - 52) << 52);
    *odd |= ~(tiny | ((vm)(a >= vd_set(0x1p-969)) & (vm)(a < vd_set(DBL_MAX))));
    return vsel(tiny, vd_set(DBL_TRUE_MIN), u);
}

/* point_errors on lanes. */
static inline void vpoint_errors(int classic, vd x, vd y, vd z, vd eb, vd e[3], vm *odd)
{
    vd A = vd_abs(x), B = vd_abs(y), C = vd_abs(z), m, half, rest;
    vd c[3] = { x, y, z };
    int k;
    m = vsel((vm)(B > C) | vd_isnan(C), B, C);
    m = vsel((vm)(A > m) | vd_isnan(m), A, m);
    half = vd_set(0.5) * vulp(m, odd);
    rest = classic ? eb
                   : vsel(~(vm)(eb >= half), eb, (eb - half) * vd_set(1.0 + 4.0 * U53));
    for (k = 0; k < 3; k++)
        e[k] = classic ? eb : vd_fmin(eb, rest + vd_set(0.5) * vulp(c[k], odd));
}

int sg_opd_of_rays(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *rows,
                   size_t stride, size_t n, sg_opd *out)
{
    double nimg, lam, ecs[3], nc[3], drc = 0.0;
    int classic, k;
    size_t r0;
    dd chief;
    if (!t || !ref || (n > 0 && (!rows || !out)))
        return SG_EINVAL;
    if (ref->status != SG_OK) {
        for (r0 = 0; r0 < n; r0++)
            sg_opd_of_ray(t, ref, &rows[r0 * stride], &out[r0]);
        return SG_OK;
    }
    classic = t->o.method == SG_METHOD_CLASSIC;
    nimg = fabs(t->nsigned[t->n - 1]);
    lam = sg_tracer_wavelength(t) * sg_um_in_units(t->sys);
    chief = dd_add_d(dd_from(ref->chief_opl), ref->chief_opl_lo);
    /* What depends on the sphere alone, as sg_opd_of_ray forms it. */
    sg_point_errors(t, ref->cx, ref->cy, ref->cz, ref->centre_error_bound, ecs);
    nc[0] = -ref->cx / ref->radius;
    nc[1] = -ref->cy / ref->radius;
    nc[2] = (ref->ez - ref->cz) / ref->radius;
    for (k = 0; k < 3; k++)
        drc += ecs[k] * fabs(nc[k]);
    for (r0 = 0; r0 < n; r0 += SG_VL) {
        vd x, y, z, l, m, nn, opl, opl_lo, eb, deb, oeb;
        vm fall = vm_set(0);
        vdd w0, w1, w2, d0, d1, d2, a, b, c, disc, s, dist, osr, opd;
        vd cosphi, tanphi, nr[3], ep[3], sec, pt, ct, e, waves, bound, sx, sy, sz;
        int nl = n - r0 < SG_VL ? (int)(n - r0) : SG_VL, j;
        for (j = 0; j < SG_VL; j++) {
            /* Lanes past the end repeat the first ray. */
            const sg_ray_surface *g = &rows[(r0 + (size_t)(j < nl ? j : 0)) * stride];
            x[j] = g->x;
            y[j] = g->y;
            z[j] = g->z;
            l[j] = g->l;
            m[j] = g->m;
            nn[j] = g->n;
            opl[j] = g->opl;
            opl_lo[j] = g->opl_lo;
            eb[j] = g->error_bound;
            deb[j] = g->dir_error_bound;
            oeb[j] = g->opl_error_bound;
            fall[j] = g->status != SG_OK ? -1 : 0;
        }
        w0 = vdd_two_sum(x, vd_set(-ref->cx));
        w1 = vdd_two_sum(y, vd_set(-ref->cy));
        w2 = vdd_two_sum(z, vd_set(-ref->cz));
        d0 = vdd_from(l);
        d1 = vdd_from(m);
        d2 = vdd_from(nn);
        a = vdot3(d0, d1, d2, d0, d1, d2);
        b = vdot3(w0, w1, w2, d0, d1, d2);
        {
            dd rr = { ref->radius, ref->radius_lo };
            c = vdd_sub(vdot3(w0, w1, w2, w0, w1, w2), vdd_set(dd_sqr(rr)));
        }
        disc = vdd_sub(vdd_sqr(b), vdd_mul(a, c));
        fall |= ~(vm)(disc.hi >= vd_set(0.0));
        {
            vdd sq = vdd_sqrt(disc), q1, q2, s1, s2;
            vm first;
            sq.hi *= vd_set(ref->side);
            sq.lo *= vd_set(ref->side);
            first = (vm)(vd_set(ref->side) * b.hi <= vd_set(0.0));
            q1 = vdd_sub(sq, b);
            s1 = vdd_div(q1, a);
            q2 = vdd_sub(vdd_neg(b), sq);
            s2 = vdd_div(c, q2);
            s2 = vdd_sel((vm)(q2.hi != vd_set(0.0)), s2, vdd_from(vd_set(0.0)));
            s = vdd_sel(first, s1, s2);
        }
        dist = vdd_mul(s, vdd_sqrt(a));
        osr = vdd_add(vdd_add_d(vdd_from(opl), opl_lo), vdd_mul_d(dist, vd_set(nimg)));
        opd = vdd_sub(vdd_set(chief), osr);
        waves = (opd.hi + opd.lo) / vd_set(lam);
        sx = x + s.hi * l;
        sy = y + s.hi * m;
        sz = z + s.hi * nn;
        {
            vd gx = w0.hi + s.hi * l, gy = w1.hi + s.hi * m, gz = w2.hi + s.hi * nn;
            vd g = vd_sqrt(gx * gx + gy * gy + gz * gz), dl = vd_sqrt(a.hi);
            vd one = vd_set(1.0);
            g = vsel((vm)(g > vd_set(0.0)), g, one);
            nr[0] = gx / g;
            nr[1] = gy / g;
            nr[2] = gz / g;
            cosphi = vd_abs(nr[0] * l + nr[1] * m + nr[2] * nn) / dl;
            cosphi = vsel((vm)(cosphi > one), one, cosphi);
            tanphi = vsel((vm)(cosphi > vd_set(0.0)),
                          vd_sqrt(vd_fmax(vd_set(0.0), one - cosphi * cosphi)) / cosphi,
                          vd_set(INFINITY));
        }
        vpoint_errors(classic, x, y, z, eb, ep, &fall);
        sec = vd_set(1.0) / cosphi;
        pt = vd_set(0.0);
        ct = vd_set(0.0);
        for (k = 0; k < 3; k++) {
            pt += ep[k] * vd_abs(nr[k]);
            ct += vd_set(ecs[k]) * vd_abs(nr[k]) * sec;
        }
        e = vd_set(ref->chief_opl_error_bound) + oeb +
            vd_set(nimg) *
                (pt * sec +
                 vd_abs(s.hi) * vd_set(SG_SQRT3) * deb * (tanphi + vd_set(SG_SQRT3) * deb) + ct +
                 vd_set(drc) * (sec - vd_set(1.0))) +
            vd_set(16.0 * DD_U) *
                (vd_abs(osr.hi) + vd_set(fabs(ref->chief_opl)) + vd_set(ref->radius));
        bound = (e / vd_set(lam) + vd_set(4.0 * U53) * vd_abs(waves)) *
                vd_set(1.0 + 8.0 * U53);
        for (j = 0; j < nl; j++) {
            const sg_ray_surface *g = &rows[(r0 + (size_t)j) * stride];
            sg_opd *o = &out[r0 + (size_t)j];
            if (fall[j]) {
                sg_opd_of_ray(t, ref, g, o);
                continue;
            }
            memset(o, 0, sizeof *o);
            o->opd_waves = waves[j];
            o->error_bound = bound[j];
            o->ex = x[j] - ref->cx;
            o->ey = y[j] - ref->cy;
            o->sphere_x = sx[j];
            o->sphere_y = sy[j];
            o->sphere_z = sz[j];
            o->opl = osr.hi[j];
            o->opl_lo = osr.lo[j];
            o->status = isfinite(waves[j]) && isfinite(bound[j]) ? SG_OK : SG_ERANGE;
        }
    }
    return SG_OK;
}
