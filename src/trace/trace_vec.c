/*
 * trace_vec.c - the precise method, on SG_VL rays at once.
 *
 * The paper's four measures in double-double (see sagitta(1), METHODS):
 * the transfer into the vertex frame and onto the tangent plane, unit
 * directions, the eq. 27 root, and Newton steps along the ray with the
 * surface equation in double-double.  Every operation acts on each lane
 * alone and branches that depend on the ray are masks, so a ray gets the
 * same bits whether it is traced alone (sg_precise_run_from, with idle
 * lanes) or with others (the batch).  A lane that stops at a surface
 * (a miss, total internal reflection, clipping, an asphere that does not
 * converge) gets its status there and drops out of the block.  Sums whose
 * error bound is taken over the magnitudes of their terms (the surface
 * function, the transfers, the bent direction) use the sloppy sum
 * vdd_add_m, which costs half as much as the accurate one.
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "shape_vd.h"
#include "shape_vdd.h"
#include "slope_vec.h"
#include "trace_int.h"
#include "vdd.h"

/* ------------------------------------------------------------------------
 * Surface functions in double-double, and the double estimates that start
 * their Newton steps.
 * ------------------------------------------------------------------------ */

/* (1 + conic) a; the product by an exact 1 is a itself. */
static vdd k1_mul(const sg_sprep *s, vdd a)
{
    return sg_sprep_sphere(s) ? a : vdd_mul(vdd_set(s->k1), a);
}

/* Sag in double-double; *bad marks lanes outside the conic's domain. */
static vdd sag_v(const sg_sprep *s, vdd r2, vm *bad)
{
    vdd z = vdd_from(vd_set(0.0));
    int k;
    *bad = vm_set(0);
    if (isfinite(s->R)) {
        vdd R = vdd_from(vd_set(s->R));
        vdd disc = vdd_sub(vdd_sqr(R), k1_mul(s, r2));
        vdd root;
        *bad = (vm)(disc.hi < 0.0);
        root = vdd_sqrt(disc);
        if (s->R < 0)
            root = vdd_neg(root);
        z = vdd_mul(r2, vdd_recip(vdd_add(R, root)));
        z.hi = vsel(*bad, vd_set(NAN), z.hi);
        z.lo = vsel(*bad, vd_set(0.0), z.lo);
    }
    if (s->nasph) {
        vdd p = vdd_from(vd_set(0.0));
        for (k = s->nasph - 1; k >= 0; k--)
            p = vdd_add_d(vdd_mul(p, r2), vd_set(s->a[k]));
        z = vdd_add(z, vdd_mul(p, r2));
    }
    return z;
}

vdd sg_sag_v(const sg_sprep *s, vdd r2, vm *bad)
{
    return sag_v(s, r2, bad);
}

/* ------------------------------------------------------------------------
 * Shapes of their own (shape.h), lane by lane through their ops: each
 * lane's arithmetic is its own, so a ray gets the same bits alone or in a
 * batch.
 * ------------------------------------------------------------------------ */

static inline dd lane_dd(vdd a, int k)
{
    dd r = {a.hi[k], a.lo[k]};
    return r;
}

/* A shape's double-double sag on every lane (shape_vdd.h), for a shape
 * svd_handles: one copy of the shapes' code for the four callers. */
__attribute__((noinline)) static void gen_sag_v(const sg_shape *s, vdd x, vdd y, vdd *z,
                                                vdd g[2], vd *ez, vd *eg, vm *bad)
{
    svd_sag(s, x, y, z, g, ez, eg, bad);
}

/* A shape's double sag_d on every lane (shape_vd.h): the Newton seeds,
 * slopes and second-derivative bounds, the scalar bits on each lane. */
__attribute__((noinline)) static void gen_sag_dv(const sg_shape *s, vd x, vd y, vm live, vd *z,
                                                 vd g[2], vd *h, vm *bad)
{
    sv_sag_d_live(s, x, y, live, z, g, h, bad);
}

/* F = z - f(x, y) in double-double and the bound on its rounding. */
__attribute__((noinline)) static void gen_F_v(const sg_sprep *s, vdd3 p, vdd *F, vd *err, vm *bad)
{
    int k;
    if (svd_handles(s->shp)) {
        vdd f, g[2], Fk;
        vd ez, eg;
        gen_sag_v(s->shp, p.x, p.y, &f, g, &ez, &eg, bad);
        Fk = vdd_sub(p.z, f);
        F->hi = vsel(*bad, vd_set(NAN), Fk.hi);
        F->lo = vsel(*bad, vd_set(0.0), Fk.lo);
        *err = vsel(*bad, vd_set(INFINITY), ez + 4.0 * DD_U * (vd_abs(p.z.hi) + vd_abs(f.hi)));
        return;
    }
    for (k = 0; k < SG_VL; k++) {
        dd z = lane_dd(p.z, k), f, g[2], Fk;
        double ez, eg;
        if (!s->shp->ops->sag_dd(s->shp, lane_dd(p.x, k), lane_dd(p.y, k), &f, g, &ez, &eg)) {
            (*bad)[k] = -1;
            F->hi[k] = NAN;
            F->lo[k] = 0.0;
            (*err)[k] = INFINITY;
            continue;
        }
        Fk = dd_sub(z, f);
        (*bad)[k] = 0;
        F->hi[k] = Fk.hi;
        F->lo[k] = Fk.lo;
        (*err)[k] = ez + 4.0 * DD_U * (fabs(z.hi) + fabs(f.hi));
    }
}

/* F' along d at the double point p, the size of its terms, and a bound on
 * F'' from the bound on f's second derivatives. */
__attribute__((noinline)) static vd gen_Fp_v(const sg_sprep *s, const vd p[3], const vd d[3], vd *mag, vd *fpp)
{
    vd f, g[2], h, Fp;
    vm bad;
    gen_sag_dv(s->shp, p[0], p[1], vm_set(-1), &f, g, &h, &bad);
    Fp = d[2] - g[0] * d[0] - g[1] * d[1];
    *mag = vsel(bad, vd_set(0.0), vd_abs(d[2]) + vd_abs(g[0] * d[0]) + vd_abs(g[1] * d[1]));
    *fpp = vsel(bad, vd_set(INFINITY), h * (d[0] * d[0] + d[1] * d[1]) + 1e-300);
    return vsel(bad, vd_set(NAN), Fp);
}

/* Newton in double from s0 for the active lanes, with the rules of
 * asph_root_v: a step long beside F' / F'' grows a difference in the
 * iterate, and past a growth of 4 (or near a double root, or where F'
 * turned sign on the way) the root is left to the rescue. */
__attribute__((noinline)) static vd gen_root_v(const sg_sprep *s, const vd p[3], const vd d[3],
                                                vd s0, int max_iter, vm active, vm *fail,
                                                vm *noconv, vm *wild)
{
    vd sv = s0, growth = vd_set(1.0), hprev = vd_set(0.0), dd2 = d[0] * d[0] + d[1] * d[1];
    vd fp0 = vd_set(0.0);
    int it;
    *fail = vm_set(0);
    *wild = vm_set(0);
    for (it = 0; it < max_iter && vm_any(active); it++) {
        vd x = p[0] + sv * d[0], y = p[1] + sv * d[1], z = p[2] + sv * d[2];
        vd f, g[2], hh, F, Fp, step, snew, h;
        vm bad, conv;
        gen_sag_dv(s->shp, x, y, active, &f, g, &hh, &bad);
        F = z - f;
        Fp = d[2] - g[0] * d[0] - g[1] * d[1];
        if (it == 0)
            fp0 = Fp;
        bad |= (vm)(Fp == 0.0) | ~vd_isfinite(Fp);
        step = F / Fp;
        snew = sv - step;
        bad |= ~vd_isfinite(snew);
        bad &= active;
        *fail |= bad;
        active &= ~bad;
        h = hh * dd2 * vd_abs(step) / vd_abs(Fp);
        growth = vsel(active, growth * vd_fmax(vd_set(1.0), h), growth);
        conv = (vm)(vd_abs(step) <= 4.0 * U53 * (vd_abs(snew) + vd_abs(x) + vd_abs(y) + vd_abs(z)));
        *wild |= active & ((vm)(growth > 4.0) | (conv & (vm)(vd_fmax(h, hprev) > 0.25)) |
                           (vm)(Fp * fp0 < 0.0));
        hprev = vsel(active, h, hprev);
        sv = vsel(active, snew, sv);
        active &= ~conv & ~*wild;
    }
    *noconv = active;
    return sv;
}

/* The gradient of F = z - f in double-double, (-f_x, -f_y, 1), with the
 * bound on f's second derivatives (how fast the normal turns) and each
 * component's rounding. */
__attribute__((noinline)) static vdd3 gen_grad_v(const sg_sprep *s, vdd3 p, vd *gsens, vd *gerr)
{
    vdd3 g;
    int k;
    if (svd_handles(s->shp)) {
        vdd f, gg[2];
        vd ez, eg;
        vm bad;
        gen_sag_v(s->shp, p.x, p.y, &f, gg, &ez, &eg, &bad);
        g.x.hi = vsel(bad, vd_set(NAN), vd_neg(gg[0].hi));
        g.x.lo = vsel(bad, vd_set(0.0), vd_neg(gg[0].lo));
        g.y.hi = vsel(bad, vd_set(NAN), vd_neg(gg[1].hi));
        g.y.lo = vsel(bad, vd_set(0.0), vd_neg(gg[1].lo));
        *gerr = vsel(bad, vd_set(INFINITY), eg);
        {
            vd fd, gd[2], h;
            vm bd;
            gen_sag_dv(s->shp, p.x.hi, p.y.hi, vm_set(-1), &fd, gd, &h, &bd);
            *gsens = vsel(bd, vd_set(INFINITY), h);
        }
        g.z = vdd_from(vd_set(1.0));
        return g;
    }
    for (k = 0; k < SG_VL; k++) {
        dd f, gg[2];
        double ez, eg, fd, gd[2], h = INFINITY;
        if (!s->shp->ops->sag_dd(s->shp, lane_dd(p.x, k), lane_dd(p.y, k), &f, gg, &ez, &eg)) {
            gg[0] = gg[1] = dd_from(NAN);
            eg = INFINITY;
        }
        if (!s->shp->ops->sag_d(s->shp, p.x.hi[k], p.y.hi[k], &fd, gd, &h))
            h = INFINITY;
        g.x.hi[k] = -gg[0].hi;
        g.x.lo[k] = -gg[0].lo;
        g.y.hi[k] = -gg[1].hi;
        g.y.lo[k] = -gg[1].lo;
        (*gsens)[k] = h;
        (*gerr)[k] = eg;
    }
    g.z = vdd_from(vd_set(1.0));
    return g;
}

/* The normal's direction (-f_x, -f_y, 1) at the double point p. */
__attribute__((noinline)) static void gen_normal_v(const sg_sprep *s, const vd p[3],
                                                         vd g[3])
{
    vd f, gg[2], h;
    vm bad;
    gen_sag_dv(s->shp, p[0], p[1], vm_set(-1), &f, gg, &h, &bad);
    g[0] = -vsel(bad, vd_set(NAN), gg[0]);
    g[1] = -vsel(bad, vd_set(NAN), gg[1]);
    g[2] = vd_set(1.0);
}

/* |Z - f(X, Y)| of the reported point, in double-double.  The point comes
 * by address: a vdd3 by value is copied to the stack before the caller
 * even knows it has a shape of its own. */
__attribute__((noinline)) static vd gen_resid_v(const sg_sprep *s, const vdd3 *p)
{
    vd r;
    int k;
    if (svd_handles(s->shp)) {
        vdd f, g[2], df;
        vd ez, eg;
        vm bad;
        gen_sag_v(s->shp, vdd_from(p->x.hi), vdd_from(p->y.hi), &f, g, &ez, &eg, &bad);
        df = vdd_sub(vdd_from(p->z.hi), f);
        return vsel(bad, vd_set(NAN), vd_abs(df.hi + df.lo));
    }
    for (k = 0; k < SG_VL; k++) {
        dd f, g[2];
        double ez, eg;
        if (!s->shp->ops->sag_dd(s->shp, dd_from(p->x.hi[k]), dd_from(p->y.hi[k]), &f, g, &ez,
                                 &eg))
            r[k] = NAN;
        else
            r[k] = fabs(dd_to_d(dd_sub(dd_from(p->z.hi[k]), f)));
    }
    return r;
}

vdd sg_sag_xy_v(const sg_sprep *s, vdd x, vdd y, vm *bad)
{
    vdd z;
    int k;
    if (s->shape != SHAPE_GEN)
        return sg_sag_v(s, vdd_add(vdd_sqr(x), vdd_sqr(y)), bad);
    if (svd_handles(s->shp)) {
        vdd g[2];
        vd ez, eg;
        gen_sag_v(s->shp, x, y, &z, g, &ez, &eg, bad);
        z.hi = vsel(*bad, vd_set(NAN), z.hi);
        z.lo = vsel(*bad, vd_set(0.0), z.lo);
        return z;
    }
    for (k = 0; k < SG_VL; k++) {
        dd f, g[2];
        double ez, eg;
        int ok = s->shp->ops->sag_dd(s->shp, lane_dd(x, k), lane_dd(y, k), &f, g, &ez, &eg);
        (*bad)[k] = ok ? 0 : -1;
        z.hi[k] = ok ? f.hi : NAN;
        z.lo[k] = ok ? f.lo : 0.0;
    }
    return z;
}

/* |Z - sag(X, Y)| of the reported point, P = hi + lo rounded to hi.  P
 * lies on the surface within the root's bound, far below that rounding,
 * so the residual is what the rounding moved the point off the surface:
 * to first order w (x lo_x + y lo_y) - lo_z, with w = sag'(r) / r, and the
 * rest is of the order of DD_U times the point. */
static inline __attribute__((always_inline)) vd resid_v(const sg_sprep *s, const vdd3 *p)
{
    vd x = p->x.hi, y = p->y.hi, w, dw;
    if (s->shape == SHAPE_PLANE)
        return vd_abs(p->z.hi);
    if (__builtin_expect(s->shape == SHAPE_GEN, 0))
        return gen_resid_v(s, p);
    slope_v(s, x * x + y * y, &w, &dw);
    return vd_abs(w * (x * p->x.lo + y * p->y.lo) - p->z.lo);
}

/* A point at the rim of a conic's vertex sheet, where the sag's slope is
 * infinite (a sphere's equator), has no first-order residual: its lanes
 * take the double-double one of sg_sprep_sag_resid instead.  Rare, so one
 * lane at a time. */
static __attribute__((noinline, cold)) vd resid_rim(const sg_sprep *s, vd res, const vd pd[3],
                                                   vm m)
{
    int k;
    for (k = 0; k < SG_VL; k++)
        if (m[k] && !isfinite(res[k]))
            res[k] = sg_sprep_sag_resid(s, pd[0][k], pd[1][k], pd[2][k]);
    return res;
}

/* The eq. 27 root from the seed point p, in double: of the roots on the
 * vertex sheet, the one nearest the step tgt (the tangent plane's, so
 * that a seed from the entry point picks the root a seed from the plane
 * would).  *miss marks lanes it misses; *unsure those whose discriminant
 * lies within its own rounding of zero, which only double-double can
 * decide. */
static inline __attribute__((always_inline)) vd conic_root_v(const sg_sprep *s, const vd p[3],
                                                             const vd d[3], vd tgt, vd eseed,
                                                             vm *miss, vm *unsure)
{
    double c = s->c, k1 = s->k1.hi, ac = fabs(c), ak = fabs(k1);
    vd A = c * (d[0] * d[0] + d[1] * d[1] + k1 * d[2] * d[2]);
    vd b = c * (p[0] * d[0] + p[1] * d[1] + k1 * p[2] * d[2]) - d[2];
    vd C = c * (p[0] * p[0] + p[1] * p[1] + k1 * p[2] * p[2]) - 2.0 * p[2];
    vd disc = b * b - A * C;
    vd q = vd_neg(b + vd_copysign(vd_sqrt(disc), b));
    vd s1 = vsel((vm)(q != 0.0), C / q, vd_set(0.0));
    vd s2 = vsel((vm)(A != 0.0), q / A, vd_set(INFINITY));
    vm ok1 = vd_isfinite(s1) & (vm)(k1 * c * (p[2] + s1 * d[2]) <= 1.0);
    vm ok2 = vd_isfinite(s2) & (vm)(k1 * c * (p[2] + s2 * d[2]) <= 1.0);
    vm in = (vm)(disc >= 0.0), first;
    /* Each of A, b, C errs by a few u of the magnitude of its terms (the
     * rounded 1 / R included), so b^2 - AC errs by well under 64u of
     * Mb^2 + Ma Mc.  The seed point itself lies up to eseed off the ray,
     * which moves b by (1 + k) |c| eseed and C by |grad C| eseed.  With
     * K = |c| (1 + |k|), a unit direction and m = |p|_1, the magnitudes
     * are at most Ma = K, Mb = K m + |d_z|, Mc = K m^2 + 2 |p_z| and
     * |grad C| = 2 (K m + 1): bounds that cost a few operations. */
    double K = ac * (1.0 + ak);
    vd m = vd_abs(p[0]) + vd_abs(p[1]) + vd_abs(p[2]);
    vd Mb = K * m + vd_abs(d[2]);
    vd Mc = K * m * m + 2.0 * vd_abs(p[2]);
    vd err = 64.0 * U53 * (Mb * Mb + K * Mc) + 4.0 * K * (Mb + 2.0 * (K * m + 1.0)) * eseed;
    *unsure = (vm)(vd_abs(disc) <= err) | vd_isnan(disc);
    *miss = ~(in & (ok1 | ok2));
    first = ok1 & (~ok2 | (vm)(vd_abs(s1 - tgt) <= vd_abs(s2 - tgt)));
    return vsel(in & first, s1, vsel(in & ok2, s2, vd_set(0.0)));
}

/* The root of the base conic along P + s D in double-double, for the rare
 * lanes whose double discriminant was too close to zero to trust.  The
 * surface function is R times the conic's, x^2 + y^2 + k1 z^2 - 2 R z,
 * so every coefficient is formed without 1 / R.  *miss marks lanes that
 * certainly miss, *unsure those whose discriminant is still within its
 * error bound (the rounding here and the ray's own errors eP, eD) of
 * zero.  The root is the one nearest tgt among those on the vertex sheet,
 * as in conic_root_v. */
static vdd conic_root_dd(const sg_sprep *s, vdd3 P, vdd3 D, vd eP, vd eD, vd tgt, vm *miss,
                         vm *unsure)
{
    vdd R = vdd_from(vd_set(s->R));
    vdd A = vdd_add(vdd_add(vdd_sqr(D.x), vdd_sqr(D.y)), k1_mul(s, vdd_sqr(D.z)));
    vdd b = vdd_sub(vdd_add(vdd_add(vdd_mul(P.x, D.x), vdd_mul(P.y, D.y)),
                            k1_mul(s, vdd_mul(P.z, D.z))),
                    vdd_mul(R, D.z));
    vdd C = vdd_sub(vdd_add(vdd_add(vdd_sqr(P.x), vdd_sqr(P.y)), k1_mul(s, vdd_sqr(P.z))),
                    vdd_mul_d(vdd_mul(R, P.z), vd_set(2.0)));
    vdd disc = vdd_sub(vdd_sqr(b), vdd_mul(A, C)), q, r1, r2;
    double ak = fabs(s->k1.hi), aR = fabs(s->R);
    vd px = vd_abs(P.x.hi), py = vd_abs(P.y.hi), pz = vd_abs(P.z.hi);
    vd Ma = D.x.hi * D.x.hi + D.y.hi * D.y.hi + ak * D.z.hi * D.z.hi;
    vd Mb = px * vd_abs(D.x.hi) + py * vd_abs(D.y.hi) + ak * pz * vd_abs(D.z.hi) +
            aR * vd_abs(D.z.hi);
    vd Mc = px * px + py * py + ak * pz * pz + 2.0 * aR * pz;
    /* A move of the ray by e (at the closest approach, lever away) moves b
     * by up to (1 + k) e and C by up to |grad C| e. */
    vd lever = vd_abs(tgt) + vd_abs(b.hi) / vd_fmax(Ma, vd_set(1e-300));
    vd e = eP + lever * eD;
    vd grad = 2.0 * (px + py + ak * pz + aR);
    vd err = 64.0 * DD_U * (Mb * Mb + Ma * Mc) +
             4.0 * (vd_abs(b.hi) * (1.0 + ak) + Ma * grad) * e;
    vd x1, x2;
    vm in = (vm)(disc.hi >= 0.0), ok1, ok2, first;
    *unsure = (vm)(vd_abs(disc.hi) <= err) | vd_isnan(disc.hi);
    q = vdd_sqrt(vdd_sel(in, disc, vdd_from(vd_set(0.0))));
    q = vdd_sel((vm)(b.hi < 0.0), vdd_neg(q), q);
    q = vdd_neg(vdd_add(b, q));
    r1 = vdd_mul(C, vdd_recip(q));
    r2 = vdd_mul(q, vdd_recip(A));
    x1 = r1.hi;
    x2 = r2.hi;
    ok1 = (vm)(q.hi != 0.0) & vd_isfinite(x1) &
          (vm)(s->k1.hi * s->c * (P.z.hi + x1 * D.z.hi) <= 1.0);
    ok2 = (vm)(A.hi != 0.0) & vd_isfinite(x2) &
          (vm)(s->k1.hi * s->c * (P.z.hi + x2 * D.z.hi) <= 1.0);
    *miss = ~(in & (ok1 | ok2));
    first = ok1 & (~ok2 | (vm)(vd_abs(x1 - tgt) <= vd_abs(x2 - tgt)));
    return vdd_sel(in & first, r1, vdd_sel(in & ok2, r2, vdd_from(vd_set(0.0))));
}

/* Newton in double for an even asphere; *fail marks lanes that miss and
 * *noconv lanes that run out of iterations. */
static vd asph_root_v(const sg_sprep *s, const vd p[3], const vd d[3], vd s0, int max_iter,
                      vm active, vm *fail, vm *noconv, vm *wild)
{
    vd sv = s0, growth = vd_set(1.0), hprev = vd_set(0.0), fp0 = vd_set(0.0);
    int it;
    *fail = vm_set(0);
    *wild = vm_set(0);
    for (it = 0; it < max_iter && vm_any(active); it++) {
        vd x = p[0] + sv * d[0], y = p[1] + sv * d[1], z = p[2] + sv * d[2];
        vd w, dw, F, Fp, step, snew, h;
        vm bad, conv;
        asph_F_v(s, x, y, z, d, &F, &Fp, &w, &dw, &bad);
        if (it == 0)
            fp0 = Fp;
        bad |= (vm)(Fp == 0.0) | ~vd_isfinite(Fp);
        step = F / Fp;
        snew = sv - step;
        bad |= ~vd_isfinite(snew);
        bad &= active;
        *fail |= bad;
        active &= ~bad;
        /* Where a step is long beside F' / F'' (h = F'' |step| / |F'| > 1),
         * a difference in the iterate grows by about h in the next one;
         * past a growth of 4, another arithmetic from the same seed could
         * end on another root.  And where two roots lie closer than double
         * resolves (a ray touching the surface), h stays near 1/2 down to
         * the rounding of F, and which of the two Newton ends on is
         * rounding's choice.  Such roots are not certified here.  Nor is
         * one where F' has turned sign since the seed: the iterate has
         * crossed an extremum of F between two roots (wandering there
         * while F was rounding noise) and may end on the farther one. */
        h = (vd_abs(w) + 2.0 * dw) * vd_abs(step) / vd_abs(Fp);
        growth = vsel(active, growth * vd_fmax(vd_set(1.0), h), growth);
        conv = (vm)(vd_abs(step) <= 4.0 * U53 * (vd_abs(snew) + vd_abs(x) + vd_abs(y) + vd_abs(z)));
        *wild |= active & ((vm)(growth > 4.0) | (conv & (vm)(vd_fmax(h, hprev) > 0.25)) |
                           (vm)(Fp * fp0 < 0.0));
        hprev = vsel(active, h, hprev);
        sv = vsel(active, snew, sv);
        active &= ~conv & ~*wild;
    }
    *noconv = active;
    return sv;
}

/* Inlined, as are surf_Fp_v, surf_sec_v and conic_root_v, so that their
 * results stay in registers: out of line, F and its bound went through
 * memory on the Newton step's path, and the lenses' precise trace ran 5
 * to 7% slower (docs/performance.md, issue 18). */
static inline __attribute__((always_inline)) void surf_F_v(const sg_sprep *s, vdd3 p, vdd *F,
                                                           vd *err, vm *bad)
{
    if (__builtin_expect(s->shape == SHAPE_GEN, 0)) {
        /* Through locals, so that the caller's F, err and bad never have
         * their address taken by an out-of-line call (they stay in
         * registers on the other shapes' path). */
        vdd f;
        vd e;
        vm b;
        gen_F_v(s, p, &f, &e, &b);
        *F = f;
        *err = e;
        *bad = b;
        return;
    }
    if (s->shape == SHAPE_CONIC) {
        vdd xx = vdd_sqr(p.x), yy = vdd_sqr(p.y), zz = k1_mul(s, vdd_sqr(p.z));
        vdd rz = vdd_mul_d(p.z, vd_set(2.0 * s->R));
        *F = vdd_sub_m(vdd_add_m(vdd_add_m(xx, yy), zz), rz);
        *err = 8.0 * DD_U *
               (vd_abs(xx.hi) + vd_abs(yy.hi) + vd_abs(zz.hi) + vd_abs(rz.hi));
        *bad = vm_set(0);
    } else {
        vdd r2 = vdd_add_m(vdd_sqr(p.x), vdd_sqr(p.y));
        vdd sag = sag_v(s, r2, bad);
        vd mag = vd_abs(p.z.hi) + vd_abs(sag.hi), rk = vd_set(1.0);
        int k;
        for (k = 0; k < s->nasph; k++) {
            rk = rk * r2.hi;
            mag += fabs(s->a[k]) * rk;
        }
        *err = (16.0 + 4.0 * s->nasph) * DD_U * mag;
        *F = vdd_sub(p.z, sag);
    }
}

/* F' along the ray at the double point p, the magnitude of its terms in
 * *mag, and in *fpp a bound on F''; an asphere's slope serves both. */
static inline __attribute__((always_inline)) vd surf_Fp_v(const sg_sprep *s, const vd p[3],
                                                          const vd d[3], vd *mag, vd *fpp)
{
    if (__builtin_expect(s->shape == SHAPE_GEN, 0)) {
        vd m, f, Fp = gen_Fp_v(s, p, d, &m, &f);
        *mag = m;
        *fpp = f;
        return Fp;
    }
    if (s->shape == SHAPE_CONIC) {
        vd a = p[0] * d[0], b = p[1] * d[1], c = s->k1.hi * p[2] * d[2], e = s->R * d[2];
        *mag = 2.0 * (vd_abs(a) + vd_abs(b) + vd_abs(c) + vd_abs(e));
        *fpp = vd_set(2.0 * (1.0 + fabs(s->k1.hi)));
        return 2.0 * (a + b + c - e);
    }
    {
        vd w, dw, a = p[0] * d[0], b = p[1] * d[1];
        slope_v(s, p[0] * p[0] + p[1] * p[1], &w, &dw);
        *mag = vd_abs(d[2]) + vd_abs(w) * (vd_abs(a) + vd_abs(b)) * 2.0;
        *fpp = vd_abs(w) + 2.0 * dw + 1e-300;
        return d[2] - w * (a + b);
    }
}

/* 1 / cos of the angle between the ray and the normal, which scales the
 * ray's error along the surface into the point's; 1e300 where the ray
 * grazes or the normal vanishes. */
static inline __attribute__((always_inline)) vd surf_sec_v(const sg_sprep *s, const vd p[3],
                                                           const vd d[3])
{
    vd g[3], gn, gd;
    if (s->shape == SHAPE_PLANE) {
        g[0] = vd_set(0.0);
        g[1] = vd_set(0.0);
        g[2] = vd_set(-1.0);
    } else if (s->shape == SHAPE_CONIC) {
        g[0] = p[0];
        g[1] = p[1];
        g[2] = s->k1.hi * p[2] - s->R;
    } else if (__builtin_expect(s->shape == SHAPE_GEN, 0)) {
        gen_normal_v(s, p, g);
    } else {
        vd w, dw;
        slope_v(s, p[0] * p[0] + p[1] * p[1], &w, &dw);
        g[0] = vd_neg(w) * p[0];
        g[1] = vd_neg(w) * p[1];
        g[2] = vd_set(1.0);
    }
    gn = vd_sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    gd = vd_abs(g[0] * d[0] + g[1] * d[1] + g[2] * d[2]);
    return vsel((vm)(gn > 0.0) & (vm)(gd > 0.0), gn / gd, vd_set(1e300));
}

static vdd3 surf_grad_v(const sg_sprep *s, vdd3 p, vd *gsens)
{
    vdd3 g;
    if (s->shape == SHAPE_PLANE) {
        g.x = vdd_from(vd_set(0.0));
        g.y = vdd_from(vd_set(0.0));
        g.z = vdd_from(vd_set(-1.0));
        *gsens = vd_set(0.0);
    } else if (s->shape == SHAPE_CONIC) {
        g.x = p.x;
        g.y = p.y;
        g.z = vdd_sub(k1_mul(s, p.z), vdd_from(vd_set(s->R)));
        *gsens = vd_set(fmax(1.0, fabs(s->k1.hi)));
    } else {
        vdd r2 = vdd_add(vdd_sqr(p.x), vdd_sqr(p.y));
        vdd w = vdd_from(vd_set(0.0)), pp = vdd_from(vd_set(0.0));
        vd wd, dwd;
        int k;
        if (isfinite(s->R)) {
            vdd q = vdd_sub(vdd_sqr(vdd_from(vd_set(s->R))), k1_mul(s, r2));
            w = vdd_recip(vdd_sqrt(q));
            if (s->R < 0)
                w = vdd_neg(w);
        }
        for (k = s->nasph - 1; k >= 0; k--)
            pp = vdd_add(vdd_mul(pp, r2),
                         vdd_two_prod(vd_set(s->a[k]), vd_set((double)(2 * (k + 1)))));
        w = vdd_add(w, pp);
        g.x = vdd_neg(vdd_mul(w, p.x));
        g.y = vdd_neg(vdd_mul(w, p.y));
        g.z = vdd_from(vd_set(1.0));
        slope_v(s, r2.hi, &wd, &dwd);
        *gsens = vd_abs(wd) + 2.0 * dwd;
    }
    return g;
}

/* Refracts or reflects r->d at the point r->p of surface s, in dd.  Lanes
 * whose normal vanishes go to *nonphys, those reflected totally to *tir. */
static void bend_v(const sg_sprep *s, sg_vray *r, vm *nonphys, vm *tir, vm *unsure, vm *evan)
{
    vd gsens, gn, cosI, dN, gerr = vd_set(0.0);
    vdd3 g, nd;
    vdd gg, rgg, dg;
    int flat;
    *nonphys = vm_set(0);
    *tir = vm_set(0);
    *unsure = vm_set(0);
    *evan = vm_set(0);
    if (sg_sprep_passes(s))
        return;
    if (__builtin_expect(s->grating, 0)) {
        /* A diffraction grating, rare: lane by lane (shape_dgrating.c). */
        int k;
        for (k = 0; k < SG_VL; k++) {
            sg_pray one;
            sg_vray_get(r, k, &one);
            if (sg_grating_bend_dd(s, &one) != 0)
                (*evan)[k] = -1;
            else
                sg_vray_put(r, k, &one);
        }
        return;
    }
    if (__builtin_expect(s->phase != NULL, 0)) {
        /* A phase surface, rare: lane by lane (shape_phase.c). */
        int k;
        for (k = 0; k < SG_VL; k++) {
            sg_pray one;
            sg_vray_get(r, k, &one);
            if (sg_phase_bend_dd(s, &one) != 0)
                (*evan)[k] = -1;
            else
                sg_vray_put(r, k, &one);
        }
        return;
    }
    if (__builtin_expect(s->ideal, 0)) {
        /* A paraxial surface, rare: lane by lane (shape_paraxial.c). */
        int k;
        for (k = 0; k < SG_VL; k++) {
            sg_pray one;
            sg_vray_get(r, k, &one);
            sg_ideal_bend_dd(s, &one);
            sg_vray_put(r, k, &one);
        }
        return;
    }
    if (__builtin_expect(s->shape == SHAPE_GEN, 0)) {
        vd gs, ge;
        g = gen_grad_v(s, r->p, &gs, &ge);
        gsens = gs;
        gerr = ge;
    } else {
        g = surf_grad_v(s, r->p, &gsens);
    }
    /* A flat surface's normal (0, 0, -1) has g.g = 1 exactly and d.g =
     * -d.z exactly, and a product by exactly 1 is its other factor: all
     * three are skipped there.  Elsewhere 1 / g.g is formed as soon as g
     * is known, beside the chain from d.g to the new direction, which then
     * takes a product instead of a quotient; reciprocal and product err by
     * at most 9u^2 + 4u^2, within the 15u^2 of the quotient that the
     * rounding bounds below were counted with. */
    flat = s->shape == SHAPE_PLANE;
    gg = flat ? vdd_from(vd_set(1.0)) : vdd_dot3(g, g);
    rgg = flat ? gg : vdd_recip(gg);
    dg = flat ? vdd_neg(r->d.z) : vdd_dot3(r->d, g);
    *nonphys = (vm)(gg.hi <= 0.0);
    gn = vd_sqrt(gg.hi);
    cosI = dg.hi / gn;
    dN = gsens * r->eP / gn;
    /* A shape of its own also rounds its gradient by up to gerr a
     * component. */
    if (__builtin_expect(s->shape == SHAPE_GEN, 0))
        dN = (gsens * r->eP + 2.0 * gerr) / gn;
    if (s->mirror) {
        vdd f = vdd_mul_d(dg, vd_set(2.0));
        if (!flat)
            f = vdd_mul(f, rgg);
        nd.x = vdd_sub_m(r->d.x, vdd_mul(f, g.x));
        nd.y = vdd_sub_m(r->d.y, vdd_mul(f, g.y));
        nd.z = vdd_sub_m(r->d.z, vdd_mul(f, g.z));
        r->eD = r->eD + 4.0 * dN + 40.0 * DD_U;
    } else {
        vdd mu = vdd_set(s->mu);
        vdd mu2 = vdd_set(s->mu2);
        vdd kb = vdd_sub(gg, vdd_mul(mu2, vdd_sub(gg, vdd_sqr(dg))));
        vdd sq, gam;
        vd J, k, sk, sinI, m = vd_set(s->mu.hi);
        *tir = (vm)(kb.hi < 0.0);
        if (s->mu2.hi > 1.0) {
            /* Into a lower index, kb = gg (1 - mu^2) + mu^2 dg^2 can change
             * sign.  Within twice its own rounding of zero, whether the
             * carried ray is reflected totally is not certain.  (The ray's
             * carried error is not counted here: on long systems its bound
             * grows far past the true error, and would leave every later
             * refraction uncertain; the printed bound shows it instead.) */
            double m2 = s->mu2.hi;
            vd dgh = vd_abs(dg.hi);
            vd ekb = 64.0 * DD_U * (gg.hi * (1.0 + m2) + m2 * dgh * dgh);
            *unsure = (vm)(vd_abs(kb.hi) <= ekb);
            *tir &= ~*unsure;
        }
        if (fabs(s->mu.hi) == 1.0 && s->mu.lo == 0.0)
            return;
        sq = vdd_sqrt(kb);
        sq = vdd_sel((vm)(dg.hi < 0.0), vdd_neg(sq), sq);
        gam = vdd_sub(sq, vdd_mul(mu, dg));
        if (!flat)
            gam = vdd_mul(gam, rgg);
        if (flat) {
            /* gam times the normal's zero components adds nothing. */
            nd.x = vdd_mul(mu, r->d.x);
            nd.y = vdd_mul(mu, r->d.y);
            nd.z = vdd_sub_m(vdd_mul(mu, r->d.z), gam);
        } else {
            nd.x = vdd_add_m(vdd_mul(mu, r->d.x), vdd_mul(gam, g.x));
            nd.y = vdd_add_m(vdd_mul(mu, r->d.y), vdd_mul(gam, g.y));
            nd.z = vdd_add_m(vdd_mul(mu, r->d.z), vdd_mul(gam, g.z));
        }
        k = kb.hi / gg.hi;
        /* sqrt(max(k, 1e-300)) is max(sqrt(max(k, 0)), sqrt(1e-300)), as
         * sqrt is monotonic: one root serves both. */
        sk = vd_sqrt(vd_fmax(k, vd_set(0.0)));
        J = m * vd_abs(m * cosI - vd_copysign(sk, cosI)) / vd_fmax(sk, vd_set(sqrt(1e-300)));
        sinI = vd_sqrt(vd_fmax(vd_set(0.0), 1.0 - cosI * cosI));
        r->eD = (m + J * sinI) * r->eD + (J * sinI + vd_abs(gam.hi) * gn) * dN +
                60.0 * DD_U * (m + J + 1.0);
    }
    r->d = nd;
}

/* ------------------------------------------------------------------------
 * The block trace.
 * ------------------------------------------------------------------------ */

/* The bound as the one-ray code forms it: e + ulp/2 of the largest
 * coordinate, nudged up.  sg_ulp_of by its exponent bits for normal
 * values, and by sg_ulp_of itself for the rest. */
/* The ulps of the lanes of m that are subnormal-range, infinite or NaN;
 * rare, so kept out of line. */
static __attribute__((noinline, cold)) vd bound_odd(vd m, vd u, vm odd)
{
    int k;
    for (k = 0; k < SG_VL; k++)
        if (odd[k])
            u[k] = sg_ulp_of(m[k]);
    return u;
}

static inline __attribute__((always_inline)) vd bound_v(vd e, vd a, vd b, vd c)
{
    vd A = vd_abs(a), B = vd_abs(b), C = vd_abs(c), m, u;
    vm bits, odd;
    m = vsel((vm)(B > C) | vd_isnan(C), B, C);
    m = vsel((vm)(A > m) | vd_isnan(m), A, m);
    bits = (vm)m;
    u = (vd)(((bits >> 52) - 52) << 52);
    odd = ~(vm)(m >= 0x1p-969) | ~(vm)(m < DBL_MAX);
    if (__builtin_expect(vm_any(odd), 0))
        u = bound_odd(m, u, odd);
    return (e + 0.5 * u) * (1.0 + 8.0 * U53);
}

static inline vd sg_bound_up_v(vd b)
{
    return b * (1.0 + 8.0 * U53);
}

/* The point's columns of a block's rows, held until the bend has decided
 * which rays go on: a ray that stops there gets its row from
 * sg_fail_rest instead. */
typedef struct vrow {
    vd x, y, z, residual, bound, path, eO;
    vdd opl;
} vrow;

/* The first eight columns of a row, x to error_bound, are contiguous. */
_Static_assert(offsetof(sg_ray_surface, y) == 1 * sizeof(double) &&
                   offsetof(sg_ray_surface, z) == 2 * sizeof(double) &&
                   offsetof(sg_ray_surface, l) == 3 * sizeof(double) &&
                   offsetof(sg_ray_surface, m) == 4 * sizeof(double) &&
                   offsetof(sg_ray_surface, n) == 5 * sizeof(double) &&
                   offsetof(sg_ray_surface, residual) == 6 * sizeof(double) &&
                   offsetof(sg_ray_surface, error_bound) == 7 * sizeof(double),
               "sg_ray_surface begins with eight doubles, x to error_bound");
/* And path to opl_error_bound, after dir_error_bound, are four more. */
_Static_assert(offsetof(sg_ray_surface, path) == 9 * sizeof(double) &&
                   offsetof(sg_ray_surface, opl) == 10 * sizeof(double) &&
                   offsetof(sg_ray_surface, opl_lo) == 11 * sizeof(double) &&
                   offsetof(sg_ray_surface, opl_error_bound) == 12 * sizeof(double),
               "path, opl, opl_lo and opl_error_bound follow dir_error_bound");

/* Writes row i of the lanes in ok: every column when pt is given, else
 * (the stop of an aimed ray, whose point a landing wrote) the direction's.
 * With eight lanes in AVX-512 registers the first eight columns are
 * transposed into one 64-byte store per row instead of eight lane
 * extractions each. */
static void put_rows(sg_ray_surface *const *out, int i, const vrow *pt, const sg_vray *r,
                     vd dbound, vm ok)
{
    int k;
    if (pt) {
#if SG_VL == 8 && defined(__AVX512F__)
        {
            __m512d t0 = _mm512_unpacklo_pd(pt->x, pt->y), t1 = _mm512_unpackhi_pd(pt->x, pt->y);
            __m512d t2 = _mm512_unpacklo_pd(pt->z, r->d.x.hi);
            __m512d t3 = _mm512_unpackhi_pd(pt->z, r->d.x.hi);
            __m512d t4 = _mm512_unpacklo_pd(r->d.y.hi, r->d.z.hi);
            __m512d t5 = _mm512_unpackhi_pd(r->d.y.hi, r->d.z.hi);
            __m512d t6 = _mm512_unpacklo_pd(pt->residual, pt->bound);
            __m512d t7 = _mm512_unpackhi_pd(pt->residual, pt->bound);
            /* Lanes (0, 4), (2, 6), (1, 5) and (3, 7), column pairs 0-1 and
             * 2-3 in u, 4-5 and 6-7 in v. */
            __m512d u[4], v[4], row[8];
            u[0] = _mm512_shuffle_f64x2(t0, t2, 0x88);
            u[1] = _mm512_shuffle_f64x2(t0, t2, 0xDD);
            u[2] = _mm512_shuffle_f64x2(t1, t3, 0x88);
            u[3] = _mm512_shuffle_f64x2(t1, t3, 0xDD);
            v[0] = _mm512_shuffle_f64x2(t4, t6, 0x88);
            v[1] = _mm512_shuffle_f64x2(t4, t6, 0xDD);
            v[2] = _mm512_shuffle_f64x2(t5, t7, 0x88);
            v[3] = _mm512_shuffle_f64x2(t5, t7, 0xDD);
            row[0] = _mm512_shuffle_f64x2(u[0], v[0], 0x88);
            row[4] = _mm512_shuffle_f64x2(u[0], v[0], 0xDD);
            row[2] = _mm512_shuffle_f64x2(u[1], v[1], 0x88);
            row[6] = _mm512_shuffle_f64x2(u[1], v[1], 0xDD);
            row[1] = _mm512_shuffle_f64x2(u[2], v[2], 0x88);
            row[5] = _mm512_shuffle_f64x2(u[2], v[2], 0xDD);
            row[3] = _mm512_shuffle_f64x2(u[3], v[3], 0x88);
            row[7] = _mm512_shuffle_f64x2(u[3], v[3], 0xDD);
            for (k = 0; k < SG_VL; k++)
                if (ok[k]) {
                    sg_ray_surface *o = &out[k][i];
                    _mm512_storeu_pd(&o->x, row[k]);
                    o->dir_error_bound = dbound[k];
                    o->path = pt->path[k];
                    o->opl = pt->opl.hi[k];
                    o->opl_lo = pt->opl.lo[k];
                    o->opl_error_bound = pt->eO[k];
                    o->status = SG_OK;
                }
            return;
        }
#elif SG_VL == 4 && defined(__AVX__)
        {
            /* Four lanes: columns 0-3, 4-7 and 9-12 each as one 4 x 4
             * transpose, three 32-byte stores a row. */
            __m256d c[12] = {pt->x,       pt->y,       pt->z,     r->d.x.hi,
                             r->d.y.hi,   r->d.z.hi,   pt->residual, pt->bound,
                             pt->path,    pt->opl.hi,  pt->opl.lo, pt->eO};
            __m256d row[3][4];
            int g;
            for (g = 0; g < 3; g++) {
                __m256d t0 = _mm256_unpacklo_pd(c[4 * g], c[4 * g + 1]);
                __m256d t1 = _mm256_unpackhi_pd(c[4 * g], c[4 * g + 1]);
                __m256d t2 = _mm256_unpacklo_pd(c[4 * g + 2], c[4 * g + 3]);
                __m256d t3 = _mm256_unpackhi_pd(c[4 * g + 2], c[4 * g + 3]);
                row[g][0] = _mm256_permute2f128_pd(t0, t2, 0x20);
                row[g][1] = _mm256_permute2f128_pd(t1, t3, 0x20);
                row[g][2] = _mm256_permute2f128_pd(t0, t2, 0x31);
                row[g][3] = _mm256_permute2f128_pd(t1, t3, 0x31);
            }
            for (k = 0; k < SG_VL; k++)
                if (ok[k]) {
                    sg_ray_surface *o = &out[k][i];
                    _mm256_storeu_pd(&o->x, row[0][k]);
                    _mm256_storeu_pd(&o->m, row[1][k]);
                    o->dir_error_bound = dbound[k];
                    _mm256_storeu_pd(&o->path, row[2][k]);
                    o->status = SG_OK;
                }
            return;
        }
#else
        for (k = 0; k < SG_VL; k++)
            if (ok[k]) {
                sg_ray_surface *o = &out[k][i];
                o->x = pt->x[k];
                o->y = pt->y[k];
                o->z = pt->z[k];
                o->residual = pt->residual[k];
                o->error_bound = pt->bound[k];
                o->path = pt->path[k];
                o->opl = pt->opl.hi[k];
                o->opl_lo = pt->opl.lo[k];
                o->opl_error_bound = pt->eO[k];
                o->status = SG_OK;
            }
#endif
    }
    for (k = 0; k < SG_VL; k++)
        if (ok[k]) {
            sg_ray_surface *o = &out[k][i];
            o->l = r->d.x.hi[k];
            o->m = r->d.y.hi[k];
            o->n = r->d.z.hi[k];
            o->dir_error_bound = dbound[k];
        }
}

/* Adds the live lanes of m to bad, giving status code to those that had
 * not failed yet: a ray reports the first thing that stopped it. */
static vm fail_lanes(vm bad, vm m, vm live, int code, int *st)
{
    int k;
    m &= live;
    if (!vm_any(m))
        return bad;
    for (k = 0; k < SG_VL; k++)
        if (m[k] && !bad[k])
            st[k] = code;
    return bad | m;
}

/* The aperture of s for rays meeting it at (x, y). */
static vm clip_v(const sg_tracer *t, const sg_sprep *s, vd x, vd y, vm live, vm bad, int *st)
{
    int k, c;
    if (t->o.clip && !t->unclipped && (s->sd > 0.0 || s->aper))
        for (k = 0; k < SG_VL; k++)
            if (live[k] && !bad[k] && (c = sg_past_clip(t, s, x[k], y[k])) != 0) {
                bad[k] = -1;
                st[k] = c;
            }
    return bad;
}

/* How a ray leaves surface i: bent when bend is set, its bounds kept
 * finite, and row i written (its direction's columns only without pt). */
static vm leave_v(const sg_sprep *s, int i, int bend, sg_vray *r, sg_ray_surface *const *out,
                  const vrow *pt, vm live, vm bad, int *st)
{
    vd bnd;
    if (bend) {
        vm nonphys, tir, unsure, evan;
        bend_v(s, r, &nonphys, &tir, &unsure, &evan);
        bad = fail_lanes(bad, evan, live, SG_EEVANESCENT, st);
        bad = fail_lanes(bad, nonphys, live, SG_ENONPHYS, st);
        bad = fail_lanes(bad, tir, live, SG_ETIR, st);
        bad = fail_lanes(bad, unsure, live, SG_EUNCERT, st);
    }
    r->eP = vsel(vd_isnan(r->eP), vd_set(INFINITY), r->eP);
    r->eD = vsel(vd_isnan(r->eD), vd_set(INFINITY), r->eD);
    bnd = bound_v(r->eD, r->d.x.hi, r->d.y.hi, r->d.z.hi);
    put_rows(out, i, pt, r, bnd, live & ~bad);
    return bad;
}

/* The roots of the lanes of m, from the entry point r->p of each, by
 * sg_mpfr_rescue_root: the step into sv with its error in root_err, or
 * the lane's failure.  Rare, so one lane at a time and out of line. */
static __attribute__((noinline, cold)) vm rescue_v(const sg_tracer *t, const sg_sprep *s,
                                                  const sg_vray *r, vm m, vdd *sv, vd *root_err,
                                                  vm live, vm bad, int *st)
{
    vm miss = vm_set(0), lost = vm_set(0);
    int k;
    for (k = 0; k < SG_VL; k++) {
        sg_pray one;
        dd step;
        int rc;
        if (!m[k])
            continue;
        sg_vray_get(r, k, &one);
        rc = sg_mpfr_rescue_root(t->rescue, s, one.p, one.d, t->o.max_iter, &step);
        if (rc == SG_OK) {
            double scale = fabs(step.hi) + sg_max_abs3(one.p.x.hi, one.p.y.hi, one.p.z.hi);
            sv->hi[k] = step.hi;
            sv->lo[k] = step.lo;
            /* The MPFR root is good to half its 320 bits or better even
             * where it is ill-conditioned, and is rounded to DD_U. */
            (*root_err)[k] = ldexp(scale, -150) + DD_U * fabs(step.hi);
        } else if (rc == SG_EMISS) {
            miss[k] = -1;
        } else {
            lost[k] = -1;
        }
    }
    bad = fail_lanes(bad, miss, live, SG_EMISS, st);
    return fail_lanes(bad, lost, live, SG_EUNCERT, st);
}

/* A transfer that turns or moves the frame (frame.c), in double-double:
 * p = A^T (p - b), d = A^T d.  The rotation keeps lengths, so the carried
 * errors grow at most by A^T's row sums (in the max norm the bounds use);
 * the subtraction, three products and two sums per coordinate, and the
 * rounding of A and b to double-double, add well under 16 DD_U of the
 * terms' size.  The direction keeps its length to 2^-100, far inside eD,
 * so it is not normalised again. */
static void xfer_v(const sg_xfer *x, sg_vray *r)
{
    vdd q[3], p[3], d[3];
    vd big, grow = vd_set(x->grow);
    int j;
    q[0] = vdd_sub(r->p.x, vdd_set(x->b[0]));
    q[1] = vdd_sub(r->p.y, vdd_set(x->b[1]));
    q[2] = vdd_sub(r->p.z, vdd_set(x->b[2]));
    big = vd_fmax(vd_abs(r->p.x.hi), vd_fmax(vd_abs(r->p.y.hi), vd_abs(r->p.z.hi))) +
          vd_set(fmax(fabs(x->bd[0]), fmax(fabs(x->bd[1]), fabs(x->bd[2]))));
    for (j = 0; j < 3; j++) {
        vdd a0 = vdd_set(x->At[j][0]), a1 = vdd_set(x->At[j][1]), a2 = vdd_set(x->At[j][2]);
        p[j] = vdd_add(vdd_add(vdd_mul(a0, q[0]), vdd_mul(a1, q[1])), vdd_mul(a2, q[2]));
        d[j] = vdd_add(vdd_add(vdd_mul(a0, r->d.x), vdd_mul(a1, r->d.y)), vdd_mul(a2, r->d.z));
    }
    r->p.x = p[0];
    r->p.y = p[1];
    r->p.z = p[2];
    r->d.x = d[0];
    r->d.y = d[1];
    r->d.z = d[2];
    r->eP = grow * (r->eP + 16.0 * DD_U * big);
    r->eD = grow * (r->eD + 16.0 * DD_U);
}

/* One surface for every live lane; returns the lanes that stop here, with
 * their status in st[].  Out of line, so that its own helpers inline into
 * one copy of the surface's code whatever calls it. */
static __attribute__((noinline)) vm surface_v(const sg_tracer *t, int i, int upto, sg_vray *r,
                                              vd path0, sg_ray_surface *const *out, vm live,
                                              int *st)
{
    const sg_sprep *s = &t->sp[i];
    int flat = s->shape == SHAPE_PLANE;
    vd dz = r->d.z.hi, ps[3], ds[3], sd = vd_set(0.0), eP0, root_err = vd_set(0.0);
    vd pd[3], kappa, s0d = vd_set(0.0), s0t = vd_set(0.0), lever;
    vm cert = vm_set(-1);
    vrow row;
    vdd s0 = vdd_from(vd_set(0.0)), sv, exact = vdd_from(vd_set(0.0));
    vm seeded = vm_set(0), resc = vm_set(0);
    int it_max = t->o.max_iter > 4 ? t->o.max_iter : 4;
    vdd3 base;
    vm bad = vm_set(0), tp, act;
    vd ePin = r->eP;
    int it;

    /* Measure 1: into this surface's frame and onto its tangent plane. */
    if (s->xf) {
        xfer_v(s->xf, r);
        dz = r->d.z.hi;
    } else if (i > 1)
        r->p.z = vdd_add_d(r->p.z, vd_set(-s->T));
    base = r->p;
    eP0 = r->eP + DD_U * vd_abs(r->p.z.hi);
    tp = (vm)(dz != 0.0) & (vm)(r->p.z.hi != 0.0);
    ps[0] = r->p.x.hi;
    ps[1] = r->p.y.hi;
    ps[2] = r->p.z.hi;
    if (vm_any(tp)) {
        vd step0, ePt;
        if (flat) {
            /* The tangent plane is the surface: the step to it puts the
             * point on z = 0 exactly, and Newton starts there.  The step is
             * a product by 1 / D_z (9u^2 + 4u^2, within the 15u^2 of a
             * quotient), whose Newton step can start before P_z is known. */
            vdd s0f = vdd_neg(vdd_mul(r->p.z, vdd_recip(r->d.z)));
            vdd3 pt;
            pt.x = vdd_add_m(r->p.x, vdd_mul(s0f, r->d.x));
            pt.y = vdd_add_m(r->p.y, vdd_mul(s0f, r->d.y));
            pt.z = vdd_from(vd_set(0.0));
            s0 = vdd_sel(tp, s0f, s0);
            base.x = vdd_sel(tp, pt.x, base.x);
            base.y = vdd_sel(tp, pt.y, base.y);
            base.z = vdd_sel(tp, pt.z, base.z);
            ps[0] = base.x.hi;
            ps[1] = base.y.hi;
            ps[2] = base.z.hi;
            step0 = s0f.hi;
        } else {
            /* The tangent-plane point only seeds the root in double;
             * Newton below works on the whole step from the entry point
             * in double-double, so a point is always P + s D, two terms
             * that an aimed ray can cancel exactly.  A ray nearly parallel
             * to the plane would meet it far beyond the surface, where the
             * double seed is lost to cancellation: it seeds from its entry
             * point instead, aiming at the same root. */
            vd tx, ty, tz;
            vm near;
            s0t = vsel(tp, vd_neg(r->p.z.hi) / dz, vd_set(0.0));
            tx = r->p.x.hi + s0t * r->d.x.hi;
            ty = r->p.y.hi + s0t * r->d.y.hi;
            tz = r->p.z.hi + s0t * dz;
            near = tp & (vm)(vd_fmax(vd_abs(tx), vd_abs(ty)) <=
                             vd_fmax(vd_abs(r->p.x.hi), vd_fmax(vd_abs(r->p.y.hi), vd_abs(r->p.z.hi))));
            s0d = vsel(near, s0t, vd_set(0.0));
            ps[0] = vsel(near, tx, ps[0]);
            ps[1] = vsel(near, ty, ps[1]);
            ps[2] = vsel(near, tz, ps[2]);
            tp = near;
            step0 = s0d;
        }
        ePt = (eP0 + vd_abs(step0) * r->eD) / vd_abs(dz) +
              8.0 * DD_U * (vd_abs(r->p.x.hi) + vd_abs(r->p.y.hi) + vd_abs(step0));
        eP0 = vsel(tp, ePt, eP0);
    }
    ds[0] = r->d.x.hi;
    ds[1] = r->d.y.hi;
    ds[2] = r->d.z.hi;

    /* Measure 3: the eq. 27 root (and Newton for aspheres) in double. */
    if (flat) {
        vm off = (vm)(ps[2] != 0.0);
        bad = fail_lanes(bad, off & (vm)(dz == 0.0), live, SG_EMISS, st);
        sd = vsel(off, vd_neg(ps[2]) / dz, vd_set(0.0));
    } else {
        vm miss, unsure = vm_set(0);
        /* The tangent plane's step, from the seed point. */
        vd tgt = s0t - s0d;
        if (s->c != 0.0) {
            /* The seed point's distance from the ray: its rounding to
             * double, and the transfer to the plane in double. */
            vd eseed = 4.0 * U53 *
                       (vd_abs(r->p.x.hi) + vd_abs(r->p.y.hi) + vd_abs(r->p.z.hi) + vd_abs(s0d));
            sd = conic_root_v(s, ps, ds, tgt, eseed, &miss, &unsure);
        } else {
            /* A base curvature below the smallest double: the plane's root. */
            miss = (vm)(dz == 0.0);
            sd = vsel(miss | (vm)(ps[2] == 0.0), vd_set(0.0), vd_neg(ps[2]) / dz);
        }
        unsure &= live & ~bad;
        if (__builtin_expect(vm_any(unsure), 0)) {
            /* Decided in double-double from the entry point: a conic's
             * hit or miss, and an asphere's seed, which must be the root
             * that the exact conic gives, or Newton may end elsewhere. */
            vm miss2, unsure2;
            vdd rt = conic_root_dd(s, r->p, r->d, r->eP, r->eD, s0t, &miss2, &unsure2);
            resc |= unsure & unsure2;
            miss = (unsure & miss2) | (~unsure & miss);
            if (s->shape == SHAPE_ASPH || s->shape == SHAPE_GEN) {
                sd = vsel(unsure, rt.hi - s0d, sd);
            } else {
                exact = vdd_sel(unsure, rt, exact);
                seeded = unsure;
            }
        }
        if (s->shape == SHAPE_ASPH || s->shape == SHAPE_GEN) {
            vm nohit, noconv, wild;
            /* Where the base conic misses, Newton starts on the plane. */
            if (__builtin_expect(s->shape == SHAPE_GEN, 0)) {
                vm a, b, c;
                sd = gen_root_v(s, ps, ds, vsel(miss, tgt, sd), t->o.max_iter,
                                live & ~bad & ~resc, &a, &b, &c);
                nohit = a;
                noconv = b;
                wild = c;
            } else
                sd = asph_root_v(s, ps, ds, vsel(miss, tgt, sd), t->o.max_iter,
                                 live & ~bad & ~resc, &nohit, &noconv, &wild);
            /* Newton from the tangent plane, where the base conic
             * missed, that fails on the way says nothing of the asphere:
             * its terms can raise the surface into a ray that passes the
             * conic (near the conic's rim, say).  The rescue decides. */
            resc |= (noconv | wild | (nohit & miss)) & live & ~bad;
            bad = fail_lanes(bad, nohit & ~resc, live, SG_EMISS, st);
        } else {
            bad = fail_lanes(bad, miss & ~resc, live, SG_EMISS, st);
        }
    }

    /* Measure 4: Newton along the ray with F in double-double.  The step
     * starts as the exact sum of the tangent-plane step and the root, or
     * as the double-double root where that was needed. */
    sv = flat ? vdd_from(sd) : vdd_sel(seeded, exact, vdd_two_sum(s0d, sd));
    act = live & ~bad & ~resc;
    if (flat)
        act &= (vm)(ps[2] != 0.0);
    /* Most rays converge within two steps; rays that touch the surface
     * converge slowly, and may take up to max_iter. */
    for (it = 0; it < it_max && vm_any(act); it++) {
        vdd3 p = vdd3_axpy(base, sv, r->d);
        vd ferr, step, Fp, rFp, Fmag, Fpp, re, trunc;
        vdd F, snew;
        vm fbad;
        pd[0] = p.x.hi;
        pd[1] = p.y.hi;
        pd[2] = p.z.hi;
        if (flat) {
            F = p.z;
            ferr = vd_set(0.0);
            Fp = dz;
            Fmag = vd_abs(dz);
            Fpp = vd_set(0.0);
            fbad = vm_set(0);
        } else {
            surf_F_v(s, p, &F, &ferr, &fbad);
            Fp = surf_Fp_v(s, pd, ds, &Fmag, &Fpp);
        }
        /* 1 / Fp is formed from the double point while F is still being
         * summed in double-double, and the step takes products with it;
         * its error, below 15u^2 |F / Fp|, is far inside the step's
         * 8 U53 Fmag / |Fp| term of the root's bound. */
        rFp = 1.0 / Fp;
        fbad |= (vm)(Fp == 0.0) | ~vd_isfinite(Fp);
        fbad &= act;
        bad = fail_lanes(bad, fbad, live, SG_EMISS, st);
        act &= ~fbad;
        step = F.hi * rFp;
        snew = vdd_sub(sv, vdd_div_dr(F, Fp, rFp));
        re = (Fpp * step * step + ferr + vd_abs(step) * 8.0 * U53 * Fmag) * vd_abs(rFp) +
             4.0 * DD_U * vd_abs(snew.hi);
        /* The quadratic model behind re holds only where the step is small
         * beside F' / F'' (Kantorovich's h <= 1/2, with room to spare). */
        cert = (act & (vm)(Fpp * vd_abs(step) * vd_abs(rFp) <= 0.25)) | (~act & cert);
        sv = vdd_sel(act, snew, sv);
        root_err = vsel(act, re, root_err);
        /* Done when the root is known to 2^-100 of the point's scale, or
         * when Newton's own error has fallen far below what the rounding
         * of F leaves (a ray that grazes the surface has a root that is
         * ill-conditioned, and its bound says so). */
        trunc = Fpp * step * step * vd_abs(rFp);
        act &= ~((vm)(re <= 0x1p-100 * (vd_abs(snew.hi) + vd_abs(ps[0]) + vd_abs(ps[1]))) |
                 (vm)(trunc <= 0x1p-20 * (re - trunc)));
    }
    /* A root that Newton could not certify in double-double is found as
     * the reference finds it, in MPFR; a ray whose root not even that
     * finds is reported as such, never as a point. */
    if (!flat) {
        resc |= (act | ~cert) & live & ~bad;
        if (__builtin_expect(vm_any(resc), 0))
            bad = rescue_v(t, s, r, resc, &sv, &root_err, live, bad, st);
    }
    /* A flat surface's step from the tangent plane is zero in every lane
     * that goes on, and base + 0 D is base. */
    if (!flat || vm_any((vm)(sv.hi != 0.0) | (vm)(sv.lo != 0.0)))
        r->p = vdd3_axpy(base, sv, r->d);
    else
        r->p = base;
    pd[0] = r->p.x.hi;
    pd[1] = r->p.y.hi;
    pd[2] = r->p.z.hi;
    kappa = surf_sec_v(s, pd, ds);
    /* The ray's own error carried from the tangent plane, the root's, and
     * the rounding of the point; a curved surface's point is formed from
     * the entry point, whose coordinates enter that rounding too. */
    lever = vd_abs(sv.hi - s0d);
    eP0 = kappa * (eP0 + lever * r->eD) + root_err +
          8.0 * DD_U * (vd_abs(ps[0]) + vd_abs(ps[1]) + lever);
    if (!flat)
        eP0 += 8.0 * DD_U *
               (vd_abs(base.x.hi) + vd_abs(base.y.hi) + vd_abs(base.z.hi) + vd_abs(sv.hi));
    r->eP = eP0;

    {
        vdd sp = vdd_add_m(s0, sv), seg;
        double nb = fabs(t->nsigned[i - 1]);
        row.path = sp.hi + sp.lo;
        /* The optical path adds |n| times the signed step in double-double.
         * The step errs by at most both points' errors (each up to sqrt(3)
         * times eP) and the direction's over its length; then the
         * roundings of the product and the sum. */
        seg = nb == 1.0 ? sp : vdd_mul_d(sp, vd_set(nb));
        r->opl = vdd_add(r->opl, seg);
        r->eO = sg_bound_up_v(r->eO + nb * 2.0 * (ePin + r->eP + vd_abs(sp.hi) * r->eD) +
                              4.0 * DD_U * (vd_abs(r->opl.hi) + vd_abs(seg.hi)));
        row.opl = r->opl;
        row.eO = r->eO;
    }
    if (i == 1)
        row.path = path0 + row.path;
    row.x = pd[0];
    row.y = pd[1];
    row.z = pd[2];
    row.residual = resid_v(s, &r->p);
    if (__builtin_expect(vm_any(~vd_isfinite(row.residual) & live & ~bad), 0))
        row.residual = resid_rim(s, row.residual, pd, live & ~bad);
    row.bound = bound_v(r->eP, pd[0], pd[1], pd[2]);
    bad = clip_v(t, s, pd[0], pd[1], live, bad, st);
    return leave_v(s, i, i < upto, r, out, &row, live, bad, st) & live;
}

void sg_precise_block(const sg_tracer *t, sg_vray *v, vd p0, sg_ray_surface *const *out, int nl,
                      const int *start, int upto, int *rc)
{
    sg_vray snap, stopped;
    vm live = vm_set(0), pending = vm_set(0), dead = vm_set(0);
    int i, k, first = upto + 1, st[SG_VL], wait;

    for (k = 0; k < nl; k++)
        if (start[k] <= upto) {
            pending[k] = -1;
            rc[k] = SG_OK;
            if (start[k] < first)
                first = start[k];
        }
    snap = stopped = *v;
    for (i = first; i <= upto && vm_any(live | pending); i++) {
        vm bad;
        for (k = 0; k < nl; k++)
            if (pending[k] && start[k] == i) {
                pending[k] = 0;
                live[k] = -1;
            }
        wait = vm_any(pending);
        if (wait)
            snap = *v;
        /* A batch writes its rows into fresh memory, whose cache lines a
         * store must first fetch: asking for the next surface's rows now
         * lets that fetch run while this surface is traced (no result
         * depends on it). */
        if (i < upto)
            for (k = 0; k < nl; k++) {
                const char *o = (const char *)&out[k][i + 1];
                __builtin_prefetch(o, 1, 3);
                __builtin_prefetch(o + 64, 1, 3);
                __builtin_prefetch(o + sizeof(sg_ray_surface) - 1, 1, 3);
            }
        bad = surface_v(t, i, upto, v, p0, out, live, st);
        /* Lanes that start further on keep their state. */
        if (wait)
            sg_vray_sel(pending, &snap, v);
        if (vm_any(bad)) {
            /* A ray that stops keeps the state it stopped in. */
            sg_vray_sel(bad, v, &stopped);
            dead |= bad;
            for (k = 0; k < nl; k++)
                if (bad[k]) {
                    sg_fail_rest(out[k], i, t->n, st[k]);
                    rc[k] = st[k];
                }
        }
        live &= ~bad;
    }
    if (vm_any(dead))
        sg_vray_sel(dead, &stopped, v);
}

void sg_precise_finish(const sg_tracer *t, int i, sg_vray *v, sg_ray_surface *const *out, vm m,
                       int *rc)
{
    sg_vray w = *v;
    vd x = w.p.x.hi, y = w.p.y.hi;
    vm bad;
    int k, st[SG_VL];
    /* As surface_v goes on after the intersection. */
    bad = clip_v(t, &t->sp[i], x, y, m, vm_set(0), st);
    bad = leave_v(&t->sp[i], i, 1, &w, out, NULL, m, bad, st);
    /* The state of a lane outside m is not this surface's to bend. */
    sg_vray_sel(m, &w, v);
    for (k = 0; k < SG_VL; k++)
        if (m[k]) {
            rc[k] = bad[k] ? st[k] : SG_OK;
            if (bad[k])
                sg_fail_rest(out[k], i, t->n, st[k]);
        }
}

int sg_precise_run_from(const sg_tracer *t, sg_pray *r, double path0, sg_ray_surface *out,
                        int from, int upto)
{
    sg_vray v;
    sg_ray_surface *o[SG_VL];
    int rc, k;
    /* Idle lanes repeat the ray and are never written. */
    for (k = 0; k < SG_VL; k++) {
        sg_vray_put(&v, k, r);
        o[k] = out;
    }
    sg_precise_block(t, &v, vd_set(path0), o, 1, &from, upto, &rc);
    sg_vray_get(&v, 0, r);
    return rc;
}

int sg_precise_run_to(const sg_tracer *t, sg_pray *r, double path0, sg_ray_surface *out,
                      int upto)
{
    return sg_precise_run_from(t, r, path0, out, 1, upto);
}
