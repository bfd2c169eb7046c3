/*
 * trace_classic_vec.c - the classic method on SG_VL rays at once.
 *
 * The classic method is the textbook trace the paper (Wu et al., Acta
 * Phys. Sin. 72, 084201, 2023) calls the original method: the ray in
 * double in the frame of the last transfer, the direct quadratic formula
 * (with the cancellation-free form on nearly flat surfaces), Newton in
 * double on aspheres and shapes of their own, no reprojection; with
 * running estimates of the point, direction and path errors.  It runs
 * here as precise does in trace_vec.c: one ray a lane, every lane the
 * scalar expression written in the same order, so that a lane's bits do
 * not depend on the other lanes nor on the vector width (the build uses
 * -ffp-contract=off and only correctly rounded operations).  A branch
 * that differs between lanes is taken by all of them and the result
 * selected per lane.  A ray alone is a block with one live lane.
 *
 * Shapes of their own (SHAPE_GEN) take their double sag from shape_vd.h
 * and their residual's double-double sag from shape_vdd.h, the vector
 * twins of each shape's sag_d and sag_dd, on all lanes at once.  The clip
 * test runs lane by lane through the scalar function, as before.
 */
#include <math.h>
#include <string.h>

#include "shape_vd.h"
#include "shape_vdd.h"
#include "slope_vec.h"
#include "trace_int.h"

/* A shape's sag_d on every lane (shape_vd.h): one copy of the shapes'
 * code for the two callers. */
__attribute__((noinline)) static void gen_sag_dv(const sg_shape *sh, vd x, vd y, vm live, vd *z,
                                                 vd g[2], vd *h, vm *bad)
{
    sv_sag_d_live(sh, x, y, live, z, g, h, bad);
}

/* Newton in double on the lanes of run, from the step *svp along d from
 * p: F(s) = z(s) - sag(x(s), y(s)) for an even asphere, or for a shape of
 * its own with f's bound on its second derivatives at the last point to
 * *h.  Lanes that leave the surface's domain or whose step goes wrong get
 * *bad, lanes out of iterations *slow; the others have their root in
 * *svp.  Each lane takes the steps the one-ray Newton of before took. */
static void root_v(const sg_sprep *s, const vd p[3], const vd d[3], vd *svp, int max_iter,
                   vm run, vd *h, vm *bad, vm *slow)
{
    vd sv = *svp, hh = vd_set(0.0);
    vm b = vm_set(0);
    int it;
    for (it = 0; it < max_iter && vm_any(run); it++) {
        vd x = p[0] + sv * d[0], y = p[1] + sv * d[1], z = p[2] + sv * d[2];
        vd F, Fp, step, nsv;
        vm m;
        if (s->shape == SHAPE_GEN) {
            vd sag, g[2], hk;
            gen_sag_dv(s->shp, x, y, run, &sag, g, &hk, &m);
            F = z - sag;
            Fp = d[2] - g[0] * d[0] - g[1] * d[1];
            hh = vsel(run & ~m, hk, hh);
        } else {
            vd w, dw;
            asph_F_v(s, x, y, z, d, &F, &Fp, &w, &dw, &m);
        }
        m &= run;
        b |= m;
        run &= ~m;
        m = run & ((Fp == 0.0) | ~vd_isfinite(Fp));
        b |= m;
        run &= ~m;
        step = F / Fp;
        nsv = sv - step;
        m = run & ~vd_isfinite(nsv);
        b |= m;
        run &= ~m;
        sv = vsel(run, nsv, sv);
        run &= ~(vm)(vd_abs(step) <= 4.0 * U53 * (vd_abs(sv) + vd_abs(x) + vd_abs(y) + vd_abs(z)));
    }
    *svp = sv;
    *h = hh;
    *bad = b;
    *slow = run;
}

/* The surface's gradient direction at (x, y, z) in its frame: (x, y, k1 z
 * - R) for a conic, (-w x, -w y, 1) for an asphere, (-f_x, -f_y, 1) for a
 * shape of its own on the lanes of live (NaN where it has no sag), -z for
 * a plane. */
static void grad_v(const sg_sprep *s, vd x, vd y, vd z, vm live, vd g[3])
{
    if (s->shape == SHAPE_PLANE) {
        g[0] = vd_set(0.0);
        g[1] = vd_set(0.0);
        g[2] = vd_set(-1.0);
    } else if (s->shape == SHAPE_CONIC) {
        g[0] = x;
        g[1] = y;
        g[2] = s->k1.hi * z - s->R;
    } else if (s->shape == SHAPE_GEN) {
        vd f, gg[2], h;
        vm bad;
        gen_sag_dv(s->shp, x, y, live, &f, gg, &h, &bad);
        g[0] = vsel(live, -vsel(bad, vd_set(NAN), gg[0]), vd_set(0.0));
        g[1] = vsel(live, -vsel(bad, vd_set(NAN), gg[1]), vd_set(0.0));
        g[2] = vd_set(1.0);
    } else {
        vd w, dw;
        slope_v(s, x * x + y * y, &w, &dw);
        g[0] = -w * x;
        g[1] = -w * y;
        g[2] = vd_set(1.0);
    }
}

/* A gradient whose squares over- or underflow (|R| above about 1e154)
 * is scaled first; ordinary normals keep the textbook arithmetic.
 * Returns the gradient's length. */
static vd grad_len(vd g[3])
{
    vd gn = vd_sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    vm odd = ~vd_isfinite(gn) | (vm)(gn < 0x1p-500);
    if (vm_any(odd)) {
        vd gm = vd_fmax(vd_abs(g[0]), vd_fmax(vd_abs(g[1]), vd_abs(g[2])));
        int j;
        odd &= (vm)(gm > 0.0) & vd_isfinite(gm);
        for (j = 0; j < 3; j++)
            g[j] = vsel(odd, g[j] / gm, g[j]);
        gn = vsel(odd, vd_sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), gn);
    }
    return gn;
}

/* dd_div of dd.h, lane by lane: three quotients, the same roundings. */
static vdd div_tw(vdd a, vdd b)
{
    vd q1 = a.hi / b.hi, q2, q3;
    vdd r = vdd_sub(a, vdd_mul_d(b, q1));
    q2 = r.hi / b.hi;
    r = vdd_sub(r, vdd_mul_d(b, q2));
    q3 = r.hi / b.hi;
    return vdd_add_d(vdd_fast_two_sum(q1, q2), q3);
}

/* |z - sag| at the lanes' points, as sg_sprep_sag_resid gives it: on a
 * plane, a conic or an even asphere here, in vdd.h's double-double (the
 * same roundings as dd.h's), on shapes of their own through shape_vdd.h's
 * twin of their sag_dd, on the lanes of live. */
static vd resid_v(const sg_sprep *s, vd x, vd y, vd z, vm live)
{
    vd r = vd_set(0.0);
    int k;
    if (s->shape == SHAPE_PLANE)
        return vd_abs(z);
    if (s->shape == SHAPE_CONIC) {
        vdd r2 = vdd_add(vdd_two_prod(x, x), vdd_two_prod(y, y));
        vdd G = vdd_add(r2, vdd_mul(vdd_set(s->k1), vdd_two_prod(z, z)));
        vd gz = 2.0 * (s->k1.hi * z - s->R), g;
        G = vdd_sub(G, vdd_two_prod(z, vd_set(2.0 * s->R)));
        g = G.hi + G.lo;
        /* At the rim of the vertex sheet, the distance along the normal. */
        return vsel((vm)(gz != 0.0), vd_abs(g / gz), vd_abs(g) / (2.0 * vd_sqrt(x * x + y * y)));
    }
    if (s->shape == SHAPE_ASPH) {
        vdd r2 = vdd_add(vdd_two_prod(x, x), vdd_two_prod(y, y)), sag = vdd_from(vd_set(0.0));
        vm bad = vm_set(0);
        if (isfinite(s->R)) {
            vdd R = vdd_from(vd_set(s->R));
            vdd disc = vdd_sub(vdd_sqr(R), vdd_mul(vdd_set(s->k1), r2));
            vdd root = vdd_sqrt(disc);
            bad = (vm)(disc.hi < 0.0);
            if (s->R < 0)
                root = vdd_neg(root);
            sag = div_tw(r2, vdd_add(R, root));
        }
        if (s->nasph) {
            vdd p = vdd_from(vd_set(0.0));
            for (k = s->nasph - 1; k >= 0; k--)
                p = vdd_add_d(vdd_mul(p, r2), vd_set(s->a[k]));
            sag = vdd_add(sag, vdd_mul(p, r2));
        }
        sag = vdd_sub(vdd_from(z), sag);
        return vsel(bad, vd_set(NAN), vd_abs(sag.hi + sag.lo));
    }
    if (svd_handles(s->shp)) {
        /* sg_sprep_sag_resid's double-double sag, on every lane at once. */
        vdd f, g[2], df;
        vd ez, eg;
        vm bad;
        svd_sag(s->shp, vdd_from(x), vdd_from(y), &f, g, &ez, &eg, &bad);
        df = vdd_sub(vdd_from(z), f);
        return vsel(live, vsel(bad, vd_set(NAN), vd_abs(df.hi + df.lo)), r);
    }
    for (k = 0; k < SG_VL; k++)
        if (live[k])
            r[k] = sg_sprep_sag_resid(s, x[k], y[k], z[k]);
    return r;
}

/* Lane k of the block fails at surface i with status st. */
static void fail_lane(const sg_tracer *t, sg_ray_surface *const *out, int k, int i, int st,
                      int *rc, vm *act)
{
    sg_fail_rest(out[k], i, t->n, st);
    rc[k] = st;
    (*act)[k] = 0;
}

void sg_classic_block(const sg_tracer *t, const double (*S)[3], const double (*D)[3],
                      sg_ray_surface *const *out, int nl, int upto, int *rc)
{
    vd P[3], d[3], eP = vd_set(0.0), eD = vd_set(0.0), opl = vd_set(0.0), eO = vd_set(0.0);
    vm act;
    int i, j, k, clipped;
    /* Idle lanes repeat lane 0, so they compute on real numbers. */
    for (k = 0; k < SG_VL; k++) {
        int from = k < nl ? k : 0;
        for (j = 0; j < 3; j++) {
            P[j][k] = S[from][j];
            d[j][k] = D[from][j];
        }
        act[k] = k < nl ? -1 : 0;
        if (k < nl)
            rc[k] = SG_OK;
    }
    for (i = 1; i <= upto && vm_any(act); i++) {
        const sg_sprep *s = &t->sp[i];
        const double c = s->c, k1 = s->k1.hi;
        const int newton = s->shape == SHAPE_ASPH || s->shape == SHAPE_GEN;
        vd zl, A, B, C, tt, sigA, sigB, sigC, eta_t, dlen, x, y, z, oz, path, dn, res;
        vd hgen = vd_set(0.0);
        vm miss;
        if (s->xf) {
            /* Into this surface's frame, which classic then keeps: the
             * rotation in double, as a textbook trace would do it. */
            const sg_xfer *xf = s->xf;
            const double zp = t->sp[i - 1].zg;
            vd q[3], dq[3], big;
            q[0] = P[0] - xf->bd[0];
            q[1] = P[1] - xf->bd[1];
            q[2] = (P[2] - zp) - xf->bd[2];
            for (j = 0; j < 3; j++)
                dq[j] = d[j];
            big = vd_fmax(vd_abs(P[0]), vd_fmax(vd_abs(P[1]), vd_abs(P[2]))) + fabs(zp) +
                  fmax(fabs(xf->bd[0]), fmax(fabs(xf->bd[1]), fabs(xf->bd[2])));
            for (j = 0; j < 3; j++) {
                P[j] = xf->Atd[j][0] * q[0] + xf->Atd[j][1] * q[1] + xf->Atd[j][2] * q[2];
                d[j] = xf->Atd[j][0] * dq[0] + xf->Atd[j][1] * dq[1] + xf->Atd[j][2] * dq[2];
            }
            eP = xf->grow * (eP + 3.0 * U53 * big) + 4.0 * U53 * xf->grow * big;
            eD = xf->grow * eD + 4.0 * U53 * xf->grow;
        }
        zl = P[2] - s->zg;
        A = c * (d[0] * d[0] + d[1] * d[1] + k1 * d[2] * d[2]);
        B = 2.0 * c * (P[0] * d[0] + P[1] * d[1] + k1 * zl * d[2]) - 2.0 * d[2];
        C = c * (P[0] * P[0] + P[1] * P[1] + k1 * zl * zl) - 2.0 * zl;
        {
            /* Every lane takes every form of the root; each keeps the one
             * its own coefficients choose. */
            vm a0 = (vm)(A == 0.0), near, ok1, ok2;
            vd disc = B * B - 4.0 * A * C;
            vd tl = vsel((vm)(B != 0.0), -C / B, vd_set(0.0));
            vd sq = vd_sqrt(disc), qn, t1, t2, tq;
            /* A nearly flat surface (|R| of 1e15 and more on a lens): the
             * textbook near root -B + sqrt(disc) would cancel more than 20
             * bits, and from |R| = 1e18 on cancel to nothing, putting the
             * hit at the ray's start.  There the cancellation-free form
             * gives both roots. */
            near = (vm)(vd_abs(4.0 * A * C) <= 0x1p-20 * (B * B));
            qn = -0.5 * (B + vd_copysign(sq, B));
            t1 = vsel(near, qn / A, (-B + sq) / (2.0 * A));
            t2 = vsel(near, vsel((vm)(qn != 0.0), C / qn, tl), (-B - sq) / (2.0 * A));
            ok1 = (vm)(k1 * c * (zl + t1 * d[2]) <= 1.0);
            ok2 = (vm)(k1 * c * (zl + t2 * d[2]) <= 1.0);
            tq = vsel(ok1 & ok2, vsel((vm)(vd_abs(t1 - tl) <= vd_abs(t2 - tl)), t1, t2),
                      vsel(ok1, t1, t2));
            tt = vsel(a0, -C / B, tq);
            miss = (a0 & (vm)(B == 0.0)) | (~a0 & ((vm)(disc < 0.0) | (~ok1 & ~ok2)));
        }
        miss &= act;
        if (vm_any(miss)) {
            /* A shape of its own may meet a ray its base conic misses:
             * Newton starts on the tangent plane. */
            vm lost = s->shape != SHAPE_GEN ? miss : miss & (vm)(d[2] == 0.0);
            for (k = 0; k < nl; k++)
                if (lost[k])
                    fail_lane(t, out, k, i, SG_EMISS, rc, &act);
            tt = vsel(miss & ~lost, -zl / d[2], tt);
        }
        if (newton) {
            vd pl[3] = {P[0], P[1], zl};
            vm bad, slow;
            root_v(s, pl, d, &tt, t->o.max_iter, act, &hgen, &bad, &slow);
            for (k = 0; k < nl; k++)
                if (act[k] && (bad[k] || slow[k]))
                    fail_lane(t, out, k, i, slow[k] ? SG_ENOCONV : SG_EMISS, rc, &act);
        }
        if (!vm_any(act))
            break;
        /* The paper's eqs. 11 and 17 with the coefficients actually used;
         * the root's relative error follows from the coefficient errors. */
        sigA = 8.0 * U53 * fabs(c) * (d[0] * d[0] + d[1] * d[1]) +
               9.0 * U53 * fabs(c) * d[2] * d[2] + 10.0 * U53 * fabs(c * (k1 - 1.0)) * d[2] * d[2];
        sigB = 16.0 * U53 * fabs(c) * (vd_abs(P[0] * d[0]) + vd_abs(P[1] * d[1])) +
               20.0 * U53 * vd_abs(c * zl * d[2]) +
               22.0 * U53 * vd_abs(c * (k1 - 1.0) * zl * d[2]) + 6.0 * U53 * vd_abs(d[2]);
        sigC = 8.0 * U53 * fabs(c) * (P[0] * P[0] + P[1] * P[1]) + 9.0 * U53 * fabs(c) * zl * zl +
               10.0 * U53 * fabs(c * (k1 - 1.0)) * zl * zl + 6.0 * U53 * vd_abs(zl) +
               3.0 * U53 * vd_abs(P[2]);
        {
            vd slope = vd_abs(2.0 * A * tt + B);
            vd num = sigA * tt * tt + sigB * vd_abs(tt) + sigC;
            eta_t = vsel((vm)(slope > 0.0), num / slope, vd_set(INFINITY));
            if (newton)
                eta_t += 8.0 * U53 * vd_abs(tt);
        }
        dlen = vd_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        x = P[0] + tt * d[0];
        y = P[1] + tt * d[1];
        z = P[2] + tt * d[2];
        oz = z - s->zg;
        {
            vd g[3], gn, cg, kappa;
            grad_v(s, x, y, oz, act, g);
            gn = grad_len(g);
            cg = vsel((vm)(gn > 0.0),
                      vd_abs(g[0] * (d[0] / dlen) + g[1] * (d[1] / dlen) + g[2] * (d[2] / dlen)) / gn,
                      vd_set(0.0));
            kappa = vsel((vm)(cg > 0.0), 1.0 / cg, vd_set(1e300));
            eP = kappa * (eP + vd_abs(tt) * dlen * eD) + eta_t * dlen +
                 4.0 * U53 * (vd_abs(tt) * dlen + vd_fmax(vd_abs(x), vd_fmax(vd_abs(y), vd_abs(z)))) +
                 3.0 * U53 * vd_fmax(vd_abs(P[0]), vd_fmax(vd_abs(P[1]), vd_abs(P[2])));
        }
        P[0] = x;
        P[1] = y;
        P[2] = z;
        /* Converting to the local frame rounds once more. */
        eP += U53 * vd_abs(oz);
        eP = vsel(vd_isnan(eP), vd_set(INFINITY), eP);
        /* Signed, as in the other methods: negative for a surface behind
         * the ray's start. */
        path = tt * dlen;
        {
            /* The textbook optical path: |n| times each step, summed in
             * double; its estimate from the roundings of the step and the
             * sum (a point's error off the ray's own path moves the path
             * only to second order, by Fermat's principle). */
            double nb = fabs(t->nsigned[i - 1]);
            opl += nb * path;
            eO += nb * (eta_t * dlen + 4.0 * U53 * vd_abs(path)) + 2.0 * U53 * vd_abs(opl);
        }
        res = resid_v(s, x, y, oz, act);
        for (k = 0; k < nl; k++) {
            sg_ray_surface *o = &out[k][i];
            if (!act[k])
                continue;
            o->x = x[k];
            o->y = y[k];
            o->z = oz[k];
            o->path = path[k];
            o->opl = opl[k];
            o->opl_lo = 0.0;
            o->opl_error_bound = sg_bound_up(eO[k]);
            o->residual = res[k];
            o->error_bound = sg_bound_up(eP[k]);
            o->status = SG_OK;
            if ((clipped = sg_past_clip(t, s, o->x, o->y)) != 0)
                fail_lane(t, out, k, i, clipped, rc, &act);
        }
        if (i < upto && vm_any(act) && s->grating) {
            /* A diffraction grating (shape_dgrating.c), lane by lane. */
            vd len = vd_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (k = 0; k < nl; k++) {
                double pk[3] = {x[k], y[k], oz[k]}, dk[3], ok = opl[k];
                if (!act[k])
                    continue;
                for (j = 0; j < 3; j++)
                    dk[j] = d[j][k] / len[k];
                if (sg_grating_bend_d(s, pk, dk, &ok) != 0) {
                    fail_lane(t, out, k, i, SG_EEVANESCENT, rc, &act);
                    continue;
                }
                for (j = 0; j < 3; j++)
                    d[j][k] = dk[j];
                opl[k] = ok;
            }
            eD = 4.0 * (s->mu.hi + 1.0) * (eD + 2.0 * fmax(1.0, fabs(k1)) * fabs(c) * eP) +
                 64.0 * U53 * (s->mu.hi + 2.0);
            eO += 4.0 * U53 * fabs(s->gk) * (vd_abs(y) + 1.0);
            eD = vsel(vd_isnan(eD), vd_set(INFINITY), eD);
        } else if (i < upto && vm_any(act) && s->phase) {
            /* A phase surface (shape_phase.c), lane by lane; its
             * direction errs as the grating's, with the kick's size and
             * how far it moves with the point. */
            vd len = vd_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), kick = vd_set(0.0),
               turn = vd_set(0.0), big = vd_set(0.0);
            double q = fabs(s->pk / s->na);
            for (k = 0; k < nl; k++) {
                double pk[3] = {x[k], y[k], oz[k]}, dk[3], ok = opl[k], ph, gr[2], h;
                if (!act[k])
                    continue;
                sg_p2_d(s->phase, x[k], y[k], &ph, gr, &h);
                kick[k] = q * (fabs(gr[0]) + fabs(gr[1]));
                turn[k] = q * h;
                big[k] = fabs(s->pk) * (fabs(ph) + 1.0);
                for (j = 0; j < 3; j++)
                    dk[j] = d[j][k] / len[k];
                if (sg_phase_bend_d(s, pk, dk, &ok) != 0) {
                    fail_lane(t, out, k, i, SG_EEVANESCENT, rc, &act);
                    continue;
                }
                for (j = 0; j < 3; j++)
                    d[j][k] = dk[j];
                opl[k] = ok;
            }
            eD = 4.0 * (s->mu.hi + 1.0 + kick) * (eD + 2.0 * fmax(1.0, fabs(k1)) * fabs(c) * eP) +
                 4.0 * turn * eP + 64.0 * U53 * (s->mu.hi + 2.0 + kick);
            eO += 4.0 * U53 * big + 2.0 * kick * s->na * eP;
            eD = vsel(vd_isnan(eD), vd_set(INFINITY), eD);
        } else if (i < upto && vm_any(act) && s->ideal) {
            /* A paraxial surface (shape_paraxial.c), lane by lane; its
             * direction errs as a refraction's would. */
            vd len = vd_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (k = 0; k < nl; k++) {
                double pk[3] = {x[k], y[k], oz[k]}, dk[3], ok = opl[k];
                for (j = 0; j < 3; j++)
                    dk[j] = d[j][k] / len[k];
                sg_ideal_bend_d(s, pk, dk, &ok);
                for (j = 0; j < 3; j++)
                    d[j][k] = dk[j];
                opl[k] = ok;
            }
            eD = (s->mu.hi + fabs(s->ic) * (vd_abs(x) + vd_abs(y))) * 4.0 * eD +
                 4.0 * fabs(s->ic) * eP + 24.0 * U53 * (s->mu.hi + 2.0);
            eO += 16.0 * U53 * (s->nb + s->na) * (vd_abs(x) + vd_abs(y) + 1.0);
            eD = vsel(vd_isnan(eD), vd_set(INFINITY), eD);
        } else if (i < upto && vm_any(act)) {
            /* The bend: refraction or reflection of d at the point. */
            vd g[3], gg, cosI, nd[3], len, gsens;
            vm tir = vm_set(0);
            if (s->shape == SHAPE_ASPH) {
                vd w, dw;
                slope_v(s, x * x + y * y, &w, &dw);
                gsens = vd_abs(w) + 2.0 * dw;
            } else if (s->shape == SHAPE_GEN) {
                gsens = hgen;
            } else {
                gsens = vd_set(s->shape == SHAPE_CONIC ? fmax(1.0, fabs(k1)) * fabs(c) : 0.0);
            }
            len = vd_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (j = 0; j < 3; j++)
                d[j] /= len;
            grad_v(s, x, y, oz, act, g);
            gg = grad_len(g);
            for (j = 0; j < 3; j++)
                g[j] /= gg;
            cosI = d[0] * g[0] + d[1] * g[1] + d[2] * g[2];
            if (s->mirror) {
                nd[0] = d[0] - 2.0 * cosI * g[0];
                nd[1] = d[1] - 2.0 * cosI * g[1];
                nd[2] = d[2] - 2.0 * cosI * g[2];
                dn = vd_set(1.0);
            } else {
                double mu = s->mu.hi;
                vd kk = 1.0 - mu * mu * (1.0 - cosI * cosI);
                vd gam, sinI = vd_sqrt(vd_fmax(vd_set(0.0), 1.0 - cosI * cosI));
                tir = act & (vm)(kk < 0.0);
                dn = mu + mu * vd_abs(mu * vd_abs(cosI) - vd_sqrt(kk)) /
                              vd_sqrt(vd_fmax(kk, vd_set(1e-300))) * sinI;
                gam = vd_copysign(vd_sqrt(kk), cosI) - mu * cosI;
                nd[0] = mu * d[0] + gam * g[0];
                nd[1] = mu * d[1] + gam * g[1];
                nd[2] = mu * d[2] + gam * g[2];
            }
            for (k = 0; k < nl; k++)
                if (tir[k])
                    fail_lane(t, out, k, i, SG_ETIR, rc, &act);
            for (j = 0; j < 3; j++)
                d[j] = nd[j];
            eD = dn * (eD / vsel((vm)(dlen > 0), dlen, vd_set(1.0))) + 4.0 * gsens * eP +
                 24.0 * U53 * (s->mu.hi + 2.0);
            eD = vsel(vd_isnan(eD), vd_set(INFINITY), eD);
        }
        for (k = 0; k < nl; k++) {
            sg_ray_surface *o = &out[k][i];
            if (!act[k])
                continue;
            o->l = d[0][k];
            o->m = d[1][k];
            o->n = d[2][k];
            o->dir_error_bound = sg_bound_up(eD[k]);
        }
    }
}

int sg_classic_run_to(const sg_tracer *t, const double S[3], const double D[3],
                      sg_ray_surface *out, int upto)
{
    int rc;
    sg_classic_block(t, (const double(*)[3])S, (const double(*)[3])D, &out, 1, upto, &rc);
    return rc;
}
