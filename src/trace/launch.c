/*
 * launch.c - rays from normalized field and pupil coordinates.
 *
 * A ray is launched as an object-space part (a direction for an object at
 * infinity, an object point otherwise) and the point Q where it crosses
 * surface 1's vertex tangent plane.  Carrying Q rather than a direction
 * times a 5e8 mm path keeps a far object from costing digits at surface 1:
 * the direction is derived from two exact points, not the other way round.
 *
 * Aiming off puts the ray through (Px, Py) times the paraxial entrance
 * pupil radius.  Paraxial and real aiming solve for Q with a 2-D Newton
 * iteration until the ray lands on (Px, Py) times the stop radius.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trace_int.h"
#include "vdd.h"

static int inf_object(const sg_tracer *t)
{
    return !isfinite(t->sys->surf[0].thickness);
}

/* Rays go where the pupil coordinates point, without iterating: aiming is
 * off, or the object space is telecentric, where it does not apply (as in
 * Zemax, the rays are fixed in object space). */
static int aim_off(const sg_tracer *t)
{
    return t->sys->aim == SG_AIM_OFF || t->ln.tele;
}

/* Object point or direction from object-space field values (vx, vy):
 * tangents for an object at infinity, heights for a finite object, or
 * degrees when deg is set.  As in Zemax, an angle is the chief ray's slope
 * towards the entrance pupil's centre, also from a finite object, whose
 * point is then -tan (enp + T0) from the axis. */
static void osp_from_values(const sg_tracer *t, dd vx, dd vy, int deg, osp *o)
{
    memset(o, 0, sizeof *o);
    if (deg || inf_object(t)) {
        dd tx = vx, ty = vy, len;
        if (deg) {
            mpfr_t a, pi, tmp;
            mpfr_inits2(128, a, pi, tmp, (mpfr_ptr)0);
            mpfr_const_pi(pi, MPFR_RNDN);
            mpfr_set_d(a, vx.hi, MPFR_RNDN);
            mpfr_add_d(a, a, vx.lo, MPFR_RNDN);
            mpfr_mul(a, a, pi, MPFR_RNDN);
            mpfr_div_ui(a, a, 180, MPFR_RNDN);
            mpfr_tan(a, a, MPFR_RNDN);
            tx = dd_from_mpfr(a, tmp);
            mpfr_set_d(a, vy.hi, MPFR_RNDN);
            mpfr_add_d(a, a, vy.lo, MPFR_RNDN);
            mpfr_mul(a, a, pi, MPFR_RNDN);
            mpfr_div_ui(a, a, 180, MPFR_RNDN);
            mpfr_tan(a, a, MPFR_RNDN);
            ty = dd_from_mpfr(a, tmp);
            mpfr_clears(a, pi, tmp, (mpfr_ptr)0);
        }
        if (!inf_object(t)) {
            dd dist = dd_add(t->ln.enp, t->ln.T0);
            /* 0 - v, so that an axis gets +0, not -0. */
            osp_from_values(t, dd_sub(dd_from(0.0), dd_mul(tx, dist)),
                            dd_sub(dd_from(0.0), dd_mul(ty, dist)), 0, o);
            return;
        }
        len = dd_sqrt(dd_add(dd_add(dd_sqr(tx), dd_sqr(ty)), dd_from(1.0)));
        o->inf = 1;
        o->dir.x = dd_div(tx, len);
        o->dir.y = dd_div(ty, len);
        o->dir.z = dd_div(dd_from(1.0), len);
        o->lam = dd_div(t->ln.enp, o->dir.z);
        o->n0 = fabs(t->nsigned[0]);
    } else {
        const sg_surface *s0 = &t->sys->surf[0];
        double R = s0->radius;
        o->inf = 0;
        o->obj.x = vx;
        o->obj.y = vy;
        o->obj.z = dd_neg(t->ln.T0);
        if ((R != 0.0 && isfinite(R)) || t->sp[0].shp) {
            /* A curved or shaped object surface (a tilted plane is an XY
             * polynomial): the point lies on its sag. */
            double sag = t->sp[0].shp ? sg_shape_sag(t->sp[0].shp, vx.hi, vy.hi)
                                      : sg_surface_sag(s0, vx.hi, vy.hi);
            if (isfinite(sag))
                o->obj.z = dd_add_d(o->obj.z, sag);
        }
        o->lam = t->ln.tele ? dd_neg(o->obj.z)
                            : dd_div(dd_neg(o->obj.z), dd_sub(t->ln.enp, o->obj.z));
        o->n0 = fabs(t->nsigned[0]);
    }
}

/* Q for aiming off, on every lane: the line through the paraxial pupil
 * point (px, py). */
static void q_aim_off_v(const sg_tracer *t, const osp *o, vd px, vd py, vdd q[2])
{
    vdd ex, ey, lam = vdd_set(o->lam);
    if (t->ln.tele) {
        /* The object point plus its distance times the slopes. */
        ex = vdd_mul_d(vdd_set(t->ln.tslope), px);
        ey = vdd_mul_d(vdd_set(t->ln.tslope), py);
        q[0] = vdd_add(vdd_set(o->obj.x), vdd_mul(lam, ex));
        q[1] = vdd_add(vdd_set(o->obj.y), vdd_mul(lam, ey));
        return;
    }
    ex = vdd_mul_d(vdd_set(t->ln.epr), px);
    ey = vdd_mul_d(vdd_set(t->ln.epr), py);
    if (o->inf) {
        q[0] = vdd_sub(ex, vdd_mul(lam, vdd_set(o->dir.x)));
        q[1] = vdd_sub(ey, vdd_mul(lam, vdd_set(o->dir.y)));
    } else {
        /* The point lam of the way from O to the pupil point E. */
        vdd ox = vdd_set(o->obj.x), oy = vdd_set(o->obj.y);
        q[0] = vdd_add(ox, vdd_mul(lam, vdd_sub(ex, ox)));
        q[1] = vdd_add(oy, vdd_mul(lam, vdd_sub(ey, oy)));
    }
}

/* The start of aiming at target (tg) on the stop, on every lane.  When
 * every surface before the stop leaves a ray straight, the ray through
 * the stop's point S = (target, sag) is the line from the object to S,
 * and Q is where that line meets surface 1's tangent plane: the first
 * landing is then on target to about the rounding of double-double, and
 * the iteration only confirms it.  Q is formed as S + mu (O - S) with
 * mu = z_S / (z_S - O_z), small for a far object, so the object's large
 * coordinates do not cancel.  Otherwise, or where the stop has no such
 * point, the paraxial guess. */
static void q_aim_start_v(const sg_tracer *t, const osp *o, vd px, vd py, const vdd tg[2],
                          vdd q[2])
{
    vdd z, qs[2];
    vm bad;
    if (!t->ln.straight) {
        q_aim_off_v(t, o, px, py, q);
        return;
    }
    z = sg_sag_xy_v(&t->sp[t->sys->stop], tg[0], tg[1], &bad);
    z = vdd_add(z, vdd_set(t->ln.zstop));
    if (o->inf) {
        vdd s = vdd_mul(z, vdd_recip(vdd_set(o->dir.z)));
        qs[0] = vdd_sub(tg[0], vdd_mul(s, vdd_set(o->dir.x)));
        qs[1] = vdd_sub(tg[1], vdd_mul(s, vdd_set(o->dir.y)));
    } else {
        vdd mu = vdd_mul(z, vdd_recip(vdd_sub(z, vdd_set(o->obj.z))));
        qs[0] = vdd_add(tg[0], vdd_mul(mu, vdd_sub(vdd_set(o->obj.x), tg[0])));
        qs[1] = vdd_add(tg[1], vdd_mul(mu, vdd_sub(vdd_set(o->obj.y), tg[1])));
    }
    bad |= ~vd_isfinite(z.hi) | ~vd_isfinite(qs[0].hi) | ~vd_isfinite(qs[1].hi);
    q[0] = qs[0];
    q[1] = qs[1];
    if (vm_any(bad)) {
        vdd off[2];
        q_aim_off_v(t, o, px, py, off);
        q[0] = vdd_sel(bad, off[0], qs[0]);
        q[1] = vdd_sel(bad, off[1], qs[1]);
    }
}

static void q_lane(const vdd q[2], int k, dd out[2])
{
    out[0].hi = q[0].hi[k];
    out[0].lo = q[0].lo[k];
    out[1].hi = q[1].hi[k];
    out[1].lo = q[1].lo[k];
}

/* q_aim_off for one pupil point. */
static void q_aim_off(const sg_tracer *t, const osp *o, double px, double py, dd q[2])
{
    vdd v[2];
    q_aim_off_v(t, o, vd_set(px), vd_set(py), v);
    q_lane(v, 0, q);
}

/* How far Q for aiming off may lie from the exact line through the
 * paraxial pupil point: a few double-double roundings of each term of
 * E - lam dir (object at infinity) or O + lam (E - O), which cancel when a
 * far object's large coordinates give a small Q (the Cassegrain's object
 * 4e6 mm off the axis lands 36 mm from surface 1's vertex). */
static vd aim_off_err_v(const sg_tracer *t, const osp *o, vd px, vd py)
{
    vd ex = vd_abs(t->ln.epr.hi * px), ey = vd_abs(t->ln.epr.hi * py), s;
    double lam = fabs(o->lam.hi);
    if (t->ln.tele) {
        vd sx = vd_abs(t->ln.tslope.hi * px), sy = vd_abs(t->ln.tslope.hi * py);
        s = vd_set(fabs(o->obj.x.hi) + fabs(o->obj.y.hi)) + lam * (sx + sy);
    } else if (o->inf) {
        s = ex + ey + vd_set(lam * (fabs(o->dir.x.hi) + fabs(o->dir.y.hi)));
    } else {
        vd ox = vd_set(fabs(o->obj.x.hi)), oy = vd_set(fabs(o->obj.y.hi));
        s = ox + oy + lam * (ex + ox + ey + oy);
    }
    return vd_set(16.0 * DD_U) * s;
}

/* The launch state of aiming off carries that error: the start moves by
 * it, and from a finite object the direction turns by it over the
 * distance. */
static void add_aim_off_err_v(const sg_tracer *t, const osp *o, vd px, vd py, sg_vray *r,
                              vd path0)
{
    vd e = aim_off_err_v(t, o, px, py);
    r->eP = r->eP + e;
    if (!o->inf)
        r->eD = r->eD + e / path0;
}

/* Precise ray states from the object-space part and Q, lane by lane.  A
 * relative error of the direction moves surface 1's point by nothing: the
 * ray starts on Q itself. */
static void pray_from_v(const osp *o, const vdd q[2], sg_vray *r, vd *path0)
{
    r->p.x = q[0];
    r->p.y = q[1];
    r->p.z = vdd_from(vd_set(0.0));
    r->eP = DD_U * (vd_abs(q[0].hi) + vd_abs(q[1].hi));
    r->eD = vd_set(8.0 * DD_U);
    if (o->inf) {
        vdd a;
        r->d.x = vdd_set(o->dir.x);
        r->d.y = vdd_set(o->dir.y);
        r->d.z = vdd_set(o->dir.z);
        *path0 = vd_set(0.0);
        /* The optical path from the field's start plane to Q. */
        a = vdd_add_m(vdd_mul(q[0], r->d.x), vdd_mul(q[1], r->d.y));
        r->opl = vdd_mul_d(vdd_sub(a, vdd_set(o->plane)), vd_set(o->n0));
        r->eO = 8.0 * DD_U * o->n0 *
                (vd_abs(q[0].hi) + vd_abs(q[1].hi) + vd_set(fabs(o->plane.hi)));
    } else {
        vdd3 v;
        vdd len, inv;
        v.x = vdd_sub(q[0], vdd_set(o->obj.x));
        v.y = vdd_sub(q[1], vdd_set(o->obj.y));
        v.z = vdd_set(dd_neg(o->obj.z));
        len = vdd_sqrt(vdd_dot3(v, v));
        /* A reciprocal and three products: within eD's 8 DD_U. */
        inv = vdd_recip(len);
        r->d.x = vdd_mul(v.x, inv);
        r->d.y = vdd_mul(v.y, inv);
        r->d.z = vdd_mul(v.z, inv);
        *path0 = len.hi + len.lo;
        /* The optical path from the object point; the length errs by a
         * few roundings of the pair. */
        r->opl = vdd_mul_d(len, vd_set(o->n0));
        r->eO = 16.0 * DD_U * o->n0 * len.hi;
    }
}

/* The same for one ray. */
static void pray_from(const osp *o, const dd q[2], sg_pray *r, double *path0)
{
    vdd qv[2] = {vdd_set(q[0]), vdd_set(q[1])};
    sg_vray v;
    vd p0;
    pray_from_v(o, qv, &v, &p0);
    sg_vray_get(&v, 0, r);
    *path0 = p0[0];
}

static void object_row(const sg_tracer *t, const osp *o, const sg_pray *r, sg_ray_surface *out)
{
    double S[3], u[3];
    u[0] = r->d.x.hi;
    u[1] = r->d.y.hi;
    u[2] = r->d.z.hi;
    if (o->inf) {
        /* The object point is at infinity back along the ray. */
        S[0] = u[0] == 0.0 ? 0.0 : copysign(INFINITY, -u[0]);
        S[1] = u[1] == 0.0 ? 0.0 : copysign(INFINITY, -u[1]);
        S[2] = copysign(INFINITY, -u[2]);
    } else {
        S[0] = o->obj.x.hi;
        S[1] = o->obj.y.hi;
        S[2] = dd_to_d(dd_add(o->obj.z, t->ln.T0));
    }
    sg_set_start_row(out, S, u);
}

/* ------------------------------------------------------------------------
 * Aiming: Newton on Q.
 * ------------------------------------------------------------------------ */

/* Lands the ray through Q on the stop; noise bounds the landing's own
 * error, below which no aiming can go. */
typedef int (*land_fn)(sg_tracer *t, const osp *o, const dd q[2], dd at[2], double *noise,
                       sg_ray_surface *scratch);

static int land_precise(sg_tracer *t, const osp *o, const dd q[2], dd at[2], double *noise,
                        sg_ray_surface *scratch)
{
    sg_pray r;
    double path0;
    int rc;
    pray_from(o, q, &r, &path0);
    rc = sg_precise_run_to(t, &r, path0, scratch, t->sys->stop);
    at[0] = r.p.x;
    at[1] = r.p.y;
    *noise = r.eP;
    return rc;
}

static void classic_start(const osp *o, const dd q[2], double S[3], double D[3])
{
    if (o->inf) {
        S[0] = q[0].hi;
        S[1] = q[1].hi;
        S[2] = 0.0;
        D[0] = o->dir.x.hi;
        D[1] = o->dir.y.hi;
        D[2] = o->dir.z.hi;
    } else {
        /* The textbook launch: from the object point, with the unscaled
         * difference vector as the direction. */
        S[0] = o->obj.x.hi;
        S[1] = o->obj.y.hi;
        S[2] = o->obj.z.hi;
        D[0] = q[0].hi - S[0];
        D[1] = q[1].hi - S[1];
        D[2] = -S[2];
    }
}

static int land_classic(sg_tracer *t, const osp *o, const dd q[2], dd at[2], double *noise,
                        sg_ray_surface *scratch)
{
    double S[3], D[3];
    int rc, stop = t->sys->stop;
    classic_start(o, q, S, D);
    vd_leave();
    rc = sg_classic_run_to(t, S, D, scratch, stop);
    at[0] = dd_from(scratch[stop].x);
    at[1] = dd_from(scratch[stop].y);
    *noise = scratch[stop].error_bound;
    return rc;
}

/* The landing map's Jacobian at Q by central differences, with a step far
 * above rounding and far below the map's curvature: its own error only
 * slows Newton's last digits, and the residual, evaluated in full
 * precision, decides when to stop. */
static int fd_jacobian(sg_tracer *t, land_fn land, const osp *o, const dd q[2],
                       double J[2][2], sg_ray_surface *scratch)
{
    double h = 1e-6 * fmax(t->ln.epr.hi, fmax(fabs(q[0].hi), fabs(q[1].hi)));
    double noise, det;
    int k, rc;
    for (k = 0; k < 2; k++) {
        dd qp[2] = {q[0], q[1]}, qm[2] = {q[0], q[1]}, ap[2], am[2];
        qp[k] = dd_add_d(qp[k], h);
        qm[k] = dd_add_d(qm[k], -h);
        rc = land(t, o, qp, ap, &noise, scratch);
        if (rc != SG_OK && !sg_err_is_stopped(rc))
            return SG_EAIM;
        rc = land(t, o, qm, am, &noise, scratch);
        if (rc != SG_OK && !sg_err_is_stopped(rc))
            return SG_EAIM;
        J[0][k] = (ap[0].hi - am[0].hi) / (2.0 * h);
        J[1][k] = (ap[1].hi - am[1].hi) / (2.0 * h);
    }
    det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    return fabs(det) > 0.0 && isfinite(det) ? SG_OK : SG_EAIM;
}

/* The Newton iteration on Q of SG_VL rays, lane by lane, shared by the
 * one-ray aiming (one lane) and the batch (a lane per ray), so that both
 * take the same steps.  Every operation is the lane's own, in the order
 * the scalar double and double-double arithmetic would take it. */
typedef struct vaim {
    vd J[2][2], det; /* the Jacobian in use */
    vd best;         /* the smallest residual so far */
    vd noise;        /* the last landing's error bound */
    vd dx, dy;       /* the last step, for Broyden's update */
    vm stepped;      /* a step was taken with this Jacobian */
    vm fresh;        /* the Jacobian was taken at this Q */
    vdd q[2];        /* the point on surface 1's tangent plane */
} vaim;

static vd det2(const vaim *a)
{
    return a->J[0][0] * a->J[1][1] - a->J[0][1] * a->J[1][0];
}

/* Every lane starts from Jacobian J and its own Q in q. */
static void aim_start(vaim *a, const double J[2][2], int fresh, const vdd q[2])
{
    int i, j;
    for (i = 0; i < 2; i++)
        for (j = 0; j < 2; j++)
            a->J[i][j] = vd_set(J[i][j]);
    a->det = det2(a);
    a->best = vd_set(INFINITY);
    a->noise = vd_set(0.0);
    a->dx = a->dy = vd_set(0.0);
    a->stepped = vm_set(0);
    a->fresh = vm_set(fresh ? -1 : 0);
    a->q[0] = q[0];
    a->q[1] = q[1];
}

/* A Jacobian of lane k's own, taken at its current Q. */
static void aim_set_jacobian(vaim *a, int k, const double J[2][2])
{
    int i, j;
    for (i = 0; i < 2; i++)
        for (j = 0; j < 2; j++)
            a->J[i][j][k] = J[i][j];
    a->det = det2(a);
    a->stepped[k] = 0;
    a->fresh[k] = -1;
}

/* Judges the landings at (at0, at1) with error bounds noise in the lanes
 * of act.  *done gets the lanes that need no further step: a residual
 * within the landing's error bound and below 2^-96 of both target
 * coordinates, about where double-double rounding leaves it anyway (a
 * zero target coordinate never qualifies, so a ray meant to cross the
 * stop on an axis iterates until the residual stops shrinking), or one
 * that stopped shrinking within the landing's own error bound, or within
 * the tolerance with a fresh Jacobian.  *stalled gets the lanes whose
 * residual stopped shrinking otherwise: the Jacobian has stopped helping
 * (a borrowed one, or its own near a turning point of the landing map)
 * and a fresh one is needed.  res and nr get the residuals for
 * aim_step. */
static void aim_judge(vaim *a, vm act, vdd at0, vdd at1, vd noise, const vdd target[2],
                      double tol, vdd res[2], vd *nr, vm *done, vm *stalled)
{
    vd m = vd_fmin(vd_abs(target[0].hi), vd_abs(target[1].hi));
    vm landed, still;
    a->noise = vsel(act, noise, a->noise);
    res[0] = vdd_sub(at0, target[0]);
    res[1] = vdd_sub(at1, target[1]);
    *nr = vd_fmax(vd_abs(res[0].hi), vd_abs(res[1].hi));
    landed = (vm)(*nr == 0.0) | ((vm)(*nr <= noise) & (vm)(*nr <= 0x1p-96 * m));
    still = ~landed & ~(vm)(*nr < 0.5 * a->best);
    *done = act & (landed | (still & ((vm)(*nr <= noise) |
                                      (a->fresh & (vm)(*nr <= tol + noise)))));
    *stalled = act & still & ~*done;
    a->fresh &= ~(act & ~*done & ~*stalled);
}

/* Broyden's update after the step (-dx, -dy) left the residual (r0, r1)
 * in the lanes of m: the borrowed Jacobian learns the map along each step
 * it takes, so a ray far from the chief still converges superlinearly. */
static void broyden(vaim *a, vm m, vd r0, vd r1)
{
    vd s2 = a->dx * a->dx + a->dy * a->dy;
    m &= (vm)(s2 > 0.0);
    a->J[0][0] = vsel(m, a->J[0][0] - r0 * a->dx / s2, a->J[0][0]);
    a->J[0][1] = vsel(m, a->J[0][1] - r0 * a->dy / s2, a->J[0][1]);
    a->J[1][0] = vsel(m, a->J[1][0] - r1 * a->dx / s2, a->J[1][0]);
    a->J[1][1] = vsel(m, a->J[1][1] - r1 * a->dy / s2, a->J[1][1]);
    a->det = vsel(m, det2(a), a->det);
}

/* The Newton step from residual res in the lanes of m; returns the lanes
 * whose Q left the doubles. */
static vm aim_step(vaim *a, vm m, const vdd res[2], vd nr)
{
    vd r0 = res[0].hi + res[0].lo, r1 = res[1].hi + res[1].lo, dx, dy;
    vdd q0, q1;
    a->best = vsel(m, vd_fmin(a->best, nr), a->best);
    broyden(a, m & a->stepped, r0, r1);
    a->stepped |= m;
    dx = (a->J[1][1] * r0 - a->J[0][1] * r1) / a->det;
    dy = (vd_neg(a->J[1][0]) * r0 + a->J[0][0] * r1) / a->det;
    a->dx = vsel(m, dx, a->dx);
    a->dy = vsel(m, dy, a->dy);
    q0 = vdd_add_d(a->q[0], vd_neg(dx));
    q1 = vdd_add_d(a->q[1], vd_neg(dy));
    a->q[0] = vdd_sel(m, q0, a->q[0]);
    a->q[1] = vdd_sel(m, q1, a->q[1]);
    return m & ~(vd_isfinite(q0.hi) & vd_isfinite(q1.hi));
}

/* How far from the exact solution a Q with residual r may lie, by lane
 * 0's Jacobian: 2 |J^-1|, the factor 2 for the Jacobian's own error. */
static double aim_error(const vaim *a, double r)
{
    double n0 = fabs(a->J[1][1][0]) + fabs(a->J[0][1][0]);
    double n1 = fabs(a->J[1][0][0]) + fabs(a->J[0][0][0]);
    double e = 2.0 * fmax(n0, n1) / fabs(a->det[0]) * r;
    return isfinite(e) ? e : INFINITY;
}

/* Backtracking steps one aim may take in all: each halves the step, so
 * 40 reach far below any step that still changes Q. */
enum { AIM_CUTS = 40 };

/* Solves land(Q) = target by Newton, from Q.  J0, when given, is the
 * field's Jacobian at its chief ray: most rays converge with it, and a ray
 * for which it stops helping gets its own, so the result depends on the
 * ray alone, never on which rays came before.
 *
 * The iteration is globalised by a line search on the landing residual: a
 * step whose ray fails to land, or lands no closer than the best Q so far,
 * is taken again from that Q, first with a Jacobian of its own (a borrowed
 * or Broyden-updated one may point the wrong way) and then halved until
 * the residual drops.  A ray that converges without ever backtracking
 * takes exactly the steps of the batch's vector iteration, which hands
 * every other ray to this one.
 *
 * A ray accepted short of its landing's error bound (within the aiming
 * tolerance, with a fresh Jacobian or out of steps) starts its trace that
 * far from the exactly aimed ray: *eaim gets twice |J^-1| times the
 * residual and the landing's bound, for the launch's bound; 0 otherwise. */
static int aim_newton(sg_tracer *t, land_fn land, const osp *o, dd q[2],
                      const dd target[2], const double (*J0)[2], sg_ray_surface *scratch,
                      double *eaim)
{
    double tol = t->o.aim_rtol * fmax(t->ln.stop_r.hi, 1e-300), J[2][2], noise;
    double sdx = 0.0, sdy = 0.0, bres[2] = {0.0, 0.0}, bnr = INFINITY;
    vdd tg[2] = {vdd_set(target[0]), vdd_set(target[1])}, res[2];
    vdd qv[2] = {vdd_set(q[0]), vdd_set(q[1])}, qb[2];
    vm one = vm_set(0), done, stalled;
    vd nr;
    dd at[2];
    vaim a;
    int it, rc, cuts = 0, have_best = 0, bfresh = 0;
    one[0] = -1;
    if (eaim)
        *eaim = 0.0;
    if (J0 == NULL) {
        if (fd_jacobian(t, land, o, q, J, scratch) != SG_OK)
            return SG_EAIM;
        aim_start(&a, (const double(*)[2])J, 1, qv);
    } else {
        aim_start(&a, J0, 0, qv);
    }
    qb[0] = qv[0];
    qb[1] = qv[1];
    for (it = 0; it < t->o.aim_max_iter + cuts; it++) {
        int failed, worse;
        q_lane(a.q, 0, q);
        rc = land(t, o, q, at, &noise, scratch);
        failed = rc != SG_OK && !sg_err_is_stopped(rc);
        worse = 0;
        if (!failed) {
            aim_judge(&a, one, vdd_set(at[0]), vdd_set(at[1]), vd_set(noise), tg, tol, res,
                      &nr, &done, &stalled);
            if (done[0]) {
                if (eaim && !(nr[0] <= noise))
                    *eaim = aim_error(&a, nr[0] + noise);
                return SG_OK;
            }
            worse = have_best && !(nr[0] < bnr);
        }
        if (failed || worse) {
            /* Back to the best Q: first a Jacobian of its own and the
             * full step, then half the step each time. */
            if (!have_best || cuts++ >= AIM_CUTS)
                return SG_EAIM;
            if (!bfresh) {
                dd qq[2];
                q_lane(qb, 0, qq);
                if (fd_jacobian(t, land, o, qq, J, scratch) != SG_OK)
                    return SG_EAIM;
                sdx = (J[1][1] * bres[0] - J[0][1] * bres[1]) /
                      (J[0][0] * J[1][1] - J[0][1] * J[1][0]);
                sdy = (-J[1][0] * bres[0] + J[0][0] * bres[1]) /
                      (J[0][0] * J[1][1] - J[0][1] * J[1][0]);
                aim_set_jacobian(&a, 0, (const double(*)[2])J);
                bfresh = 1;
            } else {
                sdx *= 0.5;
                sdy *= 0.5;
            }
            if (!(isfinite(sdx) && isfinite(sdy)))
                return SG_EAIM;
            a.q[0] = vdd_add_d(qb[0], vd_set(-sdx));
            a.q[1] = vdd_add_d(qb[1], vd_set(-sdy));
            /* The next step starts afresh: no secant update across a cut. */
            a.stepped[0] = 0;
            a.fresh[0] = -1;
            continue;
        }
        if (stalled[0]) {
            if (fd_jacobian(t, land, o, q, J, scratch) != SG_OK)
                return SG_EAIM;
            aim_set_jacobian(&a, 0, (const double(*)[2])J);
        }
        /* This Q is the best so far: the line search returns here. */
        have_best = 1;
        bnr = nr[0];
        bfresh = a.fresh[0] != 0;
        bres[0] = res[0].hi[0] + res[0].lo[0];
        bres[1] = res[1].hi[0] + res[1].lo[0];
        qb[0] = a.q[0];
        qb[1] = a.q[1];
        if (aim_step(&a, one, res, nr)[0])
            return SG_EAIM;
        sdx = a.dx[0];
        sdy = a.dy[0];
    }
    q_lane(a.q, 0, q);
    if (!(a.best[0] <= tol + a.noise[0]))
        return SG_EAIM;
    if (eaim)
        *eaim = aim_error(&a, a.best[0] + a.noise[0]);
    return SG_OK;
}

/* The object-space part of field o scaled by s, 0 <= s < 1: tangents for
 * an object at infinity, heights otherwise. */
static void osp_scaled(const sg_tracer *t, const osp *o, double s, osp *out)
{
    if (o->inf)
        osp_from_values(t, dd_mul_d(dd_div(o->dir.x, o->dir.z), s),
                        dd_mul_d(dd_div(o->dir.y, o->dir.z), s), 0, out);
    else
        osp_from_values(t, dd_mul_d(o->obj.x, s), dd_mul_d(o->obj.y, s), 0, out);
}

/* Aims pupil point (px, py) of field o at target by continuation in field
 * when Newton alone does not converge: the same pupil point is aimed at
 * field fraction 0, where the paraxial guess is good, and the field is
 * stepped up to 1, each aim starting from the last converged Q moved as
 * the paraxial Q moves.  A step that fails is retried shorter; a
 * successful one lets the next grow.  The last aim is Newton's at field o
 * itself, so the result is the ray's own solution. */
static int aim_continue(sg_tracer *t, land_fn land, const osp *o, double px, double py,
                        const dd target[2], dd q[2], sg_ray_surface *scratch, double *eaim)
{
    vdd tg[2] = {vdd_set(target[0]), vdd_set(target[1])}, v[2];
    double s = 0.0, ds = 0.25;
    dd qs[2], off0[2];
    osp os;
    int steps;
    osp_scaled(t, o, 0.0, &os);
    q_aim_start_v(t, &os, vd_set(px), vd_set(py), tg, v);
    q_lane(v, 0, qs);
    if (aim_newton(t, land, &os, qs, target, NULL, scratch, eaim) != SG_OK)
        return SG_EAIM;
    q_aim_off(t, &os, px, py, off0);
    for (steps = 0; s < 1.0 && steps < 64; steps++) {
        double sn = s + ds >= 1.0 ? 1.0 : s + ds;
        dd qn[2], off1[2];
        osp on;
        if (sn == 1.0)
            on = *o;
        else
            osp_scaled(t, o, sn, &on);
        q_aim_off(t, &on, px, py, off1);
        qn[0] = dd_add(qs[0], dd_sub(off1[0], off0[0]));
        qn[1] = dd_add(qs[1], dd_sub(off1[1], off0[1]));
        if (aim_newton(t, land, &on, qn, target, NULL, scratch, eaim) == SG_OK) {
            s = sn;
            qs[0] = qn[0];
            qs[1] = qn[1];
            off0[0] = off1[0];
            off0[1] = off1[1];
            ds *= 2.0;
        } else {
            ds *= 0.25;
            if (ds < 1e-4)
                return SG_EAIM;
        }
    }
    if (s < 1.0)
        return SG_EAIM;
    q[0] = qs[0];
    q[1] = qs[1];
    return SG_OK;
}

/* Newton from Q, and continuation in field when that fails. */
static int aim_robust(sg_tracer *t, land_fn land, const osp *o, double px, double py,
                      const dd target[2], const double (*J0)[2], dd q[2],
                      sg_ray_surface *scratch, double *eaim)
{
    if (aim_newton(t, land, o, q, target, J0, scratch, eaim) == SG_OK)
        return SG_OK;
    return aim_continue(t, land, o, px, py, target, q, scratch, eaim);
}

/* The field's Jacobian at its chief ray, for every ray of the field: at
 * the paraxial chief ray's Q, or where that ray does not land (a wide
 * field), at the aimed chief ray's.  have_aimJ becomes 1, or -1 when
 * neither lands, so that rays aim on their own without asking again. */
static void field_jacobian(sg_tracer *t, land_fn land, const osp *o, sg_ray_surface *scratch)
{
    dd qc[2], zero[2] = {dd_from(0.0), dd_from(0.0)};
    vdd tg[2] = {vdd_set(zero[0]), vdd_set(zero[1])}, v[2];
    q_aim_off(t, o, 0.0, 0.0, qc);
    if (fd_jacobian(t, land, o, qc, t->aimJ, scratch) == SG_OK) {
        t->have_aimJ = 1;
        return;
    }
    q_aim_start_v(t, o, vd_set(0.0), vd_set(0.0), tg, v);
    q_lane(v, 0, qc);
    t->have_aimJ = aim_robust(t, land, o, 0.0, 0.0, zero, NULL, qc, scratch, NULL) == SG_OK &&
                           fd_jacobian(t, land, o, qc, t->aimJ, scratch) == SG_OK
                       ? 1
                       : -1;
}

/* ------------------------------------------------------------------------
 * Fields.
 * ------------------------------------------------------------------------ */

/* Q for pupil point (px, py), aimed when the system asks.  With cache set,
 * o is the tracer's current field and its chief-ray Jacobian is kept.
 * *eaim, when asked for, gets how far Q may lie from the exactly aimed
 * one beyond its landing's rounding (aim_newton). */
static int launch_q(sg_tracer *t, land_fn land, const osp *o, double px, double py,
                    dd q[2], int cache, sg_ray_surface *scratch, double *eaim)
{
    int clip, rc;
    if (eaim)
        *eaim = 0.0;
    if (aim_off(t)) {
        q_aim_off(t, o, px, py, q);
    } else {
        /* The target keeps every bit of Px times the stop radius. */
        dd target[2];
        vdd tg[2], v[2];
        target[0] = dd_mul_d(t->ln.stop_r, px);
        target[1] = dd_mul_d(t->ln.stop_r, py);
        tg[0] = vdd_set(target[0]);
        tg[1] = vdd_set(target[1]);
        q_aim_start_v(t, o, vd_set(px), vd_set(py), tg, v);
        q_lane(v, 0, q);
        /* Apertures do not bend rays, so the iteration ignores them; the
         * final trace applies them. */
        clip = t->unclipped;
        t->unclipped = 1;
        if (cache && !t->have_aimJ)
            field_jacobian(t, land, o, scratch);
        rc = aim_robust(t, land, o, px, py, target,
                        cache && t->have_aimJ > 0 ? (const double (*)[2])t->aimJ : NULL, q,
                        scratch, eaim);
        t->unclipped = clip;
        if (rc != SG_OK)
            return SG_EAIM;
    }
    return SG_OK;
}

/* Where the chief ray of object-space values v lands on the image. */
static int chief_on_image(sg_tracer *t, land_fn land, const dd v[2], osp *o, double at[2],
                          sg_ray_surface *scratch)
{
    dd q[2];
    int last = t->n - 1, rc, clip;
    osp_from_values(t, v[0], v[1], 0, o);
    if (launch_q(t, land, o, 0, 0, q, 0, scratch, NULL) != SG_OK)
        return SG_EAIM;
    /* A chief ray is a reference ray, traced past every aperture, so a
     * field does not depend on the landing mode it is first met in. */
    clip = t->unclipped;
    t->unclipped = 1;
    if (t->o.method == SG_METHOD_CLASSIC) {
        double S[3], D[3];
        classic_start(o, q, S, D);
        vd_leave();
        rc = sg_classic_run_to(t, S, D, scratch, last);
    } else {
        sg_pray r;
        double p0;
        pray_from(o, q, &r, &p0);
        rc = sg_precise_run_to(t, &r, p0, scratch, last);
    }
    t->unclipped = clip;
    at[0] = scratch[last].x;
    at[1] = scratch[last].y;
    return rc;
}

static int osp_finite(const osp *o)
{
    return isfinite(o->lam.hi) &&
           (o->inf ? isfinite(o->dir.x.hi) && isfinite(o->dir.y.hi) && isfinite(o->dir.z.hi)
                   : isfinite(o->obj.x.hi) && isfinite(o->obj.y.hi) && isfinite(o->obj.z.hi));
}

static int field_osp_at(sg_tracer *t, land_fn land, double hx, double hy, osp *o,
                        sg_ray_surface *scratch);

/* Object-space part of field (hx, hy), by the system's field type.  A
 * field that would wrap past 90 degrees or leave the doubles is refused;
 * image-height fields are found at the primary wavelength, as in Zemax. */
static int field_osp(sg_tracer *t, land_fn land, double hx, double hy, osp *o,
                     sg_ray_surface *scratch)
{
    int rc;
    if (sg_field_check(t->sys, hx, hy, NULL) != SG_OK)
        return SG_ERANGE;
    if (t->prim && t->sys->field_type == SG_FIELD_REAL_IMAGE_HEIGHT)
        rc = field_osp_at(t->prim, t->prim->o.method == SG_METHOD_CLASSIC ? land_classic
                                                                          : land_precise,
                          hx, hy, o, t->prim->scratch);
    else
        rc = field_osp_at(t, land, hx, hy, o, scratch);
    if (rc == SG_OK && !osp_finite(o))
        rc = SG_ERANGE;
    return rc;
}

static int field_osp_at(sg_tracer *t, land_fn land, double hx, double hy, osp *o,
                        sg_ray_surface *scratch)
{
    dd vx = dd_mul_d(t->ln.fx, hx), vy = dd_mul_d(t->ln.fy, hy);
    switch (t->sys->field_type) {
    case SG_FIELD_ANGLE:
        if (!(fabs(vx.hi) < 90.0) || !(fabs(vy.hi) < 90.0))
            return SG_ERANGE;
        osp_from_values(t, vx, vy, 1, o);
        return SG_OK;
    case SG_FIELD_OBJECT_HEIGHT:
        osp_from_values(t, vx, vy, 0, o);
        return SG_OK;
    case SG_FIELD_PARAX_IMAGE_HEIGHT:
        osp_from_values(t, dd_div(vx, t->ln.pimg_slope_f), dd_div(vy, t->ln.pimg_slope_f), 0,
                        o);
        return SG_OK;
    case SG_FIELD_REAL_IMAGE_HEIGHT: {
        /* Newton on the object-space value until the chief ray lands on
         * the requested image height. */
        dd v[2];
        double J[2][2], det, h, at[2], ap[2], am[2], best = INFINITY;
        double target[2] = {dd_to_d(vx), dd_to_d(vy)};
        int it, k;
        v[0] = dd_div(vx, t->ln.pimg_slope);
        v[1] = dd_div(vy, t->ln.pimg_slope);
        h = 1e-7 * (fabs(v[0].hi) + fabs(v[1].hi) + fabs(t->ln.fy.hi / t->ln.pimg_slope.hi) + 1e-12);
        for (k = 0; k < 2; k++) {
            dd vhi[2] = {v[0], v[1]}, vlo[2] = {v[0], v[1]};
            vhi[k] = dd_add_d(vhi[k], h);
            vlo[k] = dd_add_d(vlo[k], -h);
            if (chief_on_image(t, land, vhi, o, ap, scratch) != SG_OK ||
                chief_on_image(t, land, vlo, o, am, scratch) != SG_OK)
                return SG_EAIM;
            J[0][k] = (ap[0] - am[0]) / (2.0 * h);
            J[1][k] = (ap[1] - am[1]) / (2.0 * h);
        }
        det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
        if (!(fabs(det) > 0.0))
            return SG_EAIM;
        for (it = 0; it < t->o.aim_max_iter; it++) {
            double r0, r1, nr, tol = 4e-16 * (fabs(target[0]) + fabs(target[1])) + 1e-300;
            if (chief_on_image(t, land, v, o, at, scratch) != SG_OK)
                return SG_EAIM;
            r0 = at[0] - target[0];
            r1 = at[1] - target[1];
            nr = fabs(r0) + fabs(r1);
            if (nr <= tol)
                return SG_OK;
            /* A residual that stopped shrinking within the landing's own
             * noise (the classic method's, or an aimed chief ray's) is as
             * close as the method can tell. */
            if (!(nr < 0.5 * best) && nr <= tol + 8.0 * scratch[t->n - 1].error_bound)
                return SG_OK;
            best = fmin(best, nr);
            v[0] = dd_add_d(v[0], -(J[1][1] * r0 - J[0][1] * r1) / det);
            v[1] = dd_add_d(v[1], -(-J[1][0] * r0 + J[0][0] * r1) / det);
        }
        return SG_EAIM;
    }
    }
    return SG_EINVAL;
}

/* ------------------------------------------------------------------------
 * Entry points.
 * ------------------------------------------------------------------------ */

/* An object at infinity's optical paths start on the plane through the
 * chief ray's point on surface 1, normal to the field's direction (as in
 * Zemax); the chief ray is the primary wavelength's, whose tracer aims it
 * as the rays of the primary wavelength are aimed.  Returns that point
 * dotted with the direction, or 0 where the chief ray fails. */
static dd chief_plane(sg_tracer *t, const osp *o)
{
    sg_tracer *p = t->prim ? t->prim : t;
    int classic = p->o.method == SG_METHOD_CLASSIC;
    land_fn land = classic ? land_classic : land_precise;
    dd q[2], zero = dd_from(0.0), plane = zero;
    int clip, rc;
    if (launch_q(p, land, o, 0.0, 0.0, q, 0, p->scratch, NULL) != SG_OK)
        return zero;
    /* The chief ray is a reference ray, traced past every aperture (an
     * obscured surface 1 does not move the plane), so a field does not
     * depend on the landing mode it is first met in. */
    clip = p->unclipped;
    p->unclipped = 1;
    if (classic) {
        double S[3], D[3];
        classic_start(o, q, S, D);
        vd_leave();
        rc = sg_classic_run_to(p, S, D, p->scratch, 1);
        if (rc == SG_OK)
            plane = dd_add(dd_add(dd_two_prod(p->scratch[1].x, o->dir.x.hi),
                                  dd_two_prod(p->scratch[1].y, o->dir.y.hi)),
                           dd_two_prod(p->scratch[1].z, o->dir.z.hi));
    } else {
        sg_pray r;
        double p0;
        pray_from(o, q, &r, &p0);
        rc = sg_precise_run_to(p, &r, p0, p->scratch, 1);
        if (rc == SG_OK)
            plane = dd_add(dd_add(dd_mul(r.p.x, o->dir.x), dd_mul(r.p.y, o->dir.y)),
                           dd_mul(r.p.z, o->dir.z));
    }
    p->unclipped = clip;
    return plane;
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* The object-space part of field (hx, hy), cached for the next ray of the
 * same field; on failure every surface is marked.  A field met before
 * comes back from fmemo with the Jacobian it had gained: a field's data
 * depend on its Hx and Hy alone (its chief rays are traced past the
 * apertures, whatever the landing mode), so a kept field has the bits a
 * fresh computation gives, and rays in any field order pay for a field
 * once. */
static int field_cached(sg_tracer *t, land_fn land, double hx, double hy, osp *o,
                        sg_ray_surface *out)
{
    if (!t->have_field || !same_bits(t->last_hx, hx) || !same_bits(t->last_hy, hy)) {
        int rc, i;
        sg_field_memo *e;
        if (t->have_field && t->field_slot >= 0) {
            /* The Jacobian the current field gained since it was kept. */
            e = &t->fmemo[t->field_slot];
            e->have_aimJ = t->have_aimJ;
            memcpy(e->aimJ, t->aimJ, sizeof e->aimJ);
        }
        for (i = 0; i < SG_FIELD_MEMO; i++) {
            e = &t->fmemo[i];
            if (e->used && same_bits(e->hx, hx) && same_bits(e->hy, hy)) {
                t->field = e->field;
                t->have_aimJ = e->have_aimJ;
                memcpy(t->aimJ, e->aimJ, sizeof t->aimJ);
                t->have_field = 1;
                t->field_slot = i;
                t->last_hx = hx;
                t->last_hy = hy;
                *o = t->field;
                return SG_OK;
            }
        }
        t->have_aimJ = 0;
        t->field_slot = -1;
        rc = field_osp(t, land, hx, hy, o, t->scratch);
        if (rc != SG_OK) {
            /* A field out of range, or an image height not reached. */
            rc = rc == SG_ERANGE ? SG_ERANGE : SG_EAIM;
            t->have_field = 0;
            sg_fail_rest(out, 0, t->n, rc);
            return rc;
        }
        if (o->inf)
            o->plane = chief_plane(t, o);
        t->field = *o;
        t->have_field = 1;
        t->have_aimJ = 0;
        t->last_hx = hx;
        t->last_hy = hy;
        i = t->fmemo_next;
        t->fmemo_next = (i + 1) % SG_FIELD_MEMO;
        e = &t->fmemo[i];
        e->used = 1;
        e->hx = hx;
        e->hy = hy;
        e->field = *o;
        e->have_aimJ = 0;
        t->field_slot = i;
    }
    *o = t->field;
    return SG_OK;
}

int sg_launch_precise_prep(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out, sg_pray *r, double *path0)
{
    dd q[2];
    double eaim;
    osp o;
    int rc = field_cached(t, land_precise, hx, hy, &o, out);
    if (rc != SG_OK)
        return rc;
    if (launch_q(t, land_precise, &o, px, py, q, 1, t->scratch, &eaim) != SG_OK) {
        sg_fail_rest(out, 0, t->n, SG_EAIM);
        return SG_EAIM;
    }
    if (aim_off(t)) {
        /* As the batch does it, lane by lane. */
        sg_vray v;
        vdd qv[2] = {vdd_set(q[0]), vdd_set(q[1])};
        vd p0;
        pray_from_v(&o, qv, &v, &p0);
        add_aim_off_err_v(t, &o, vd_set(px), vd_set(py), &v, p0);
        sg_vray_get(&v, 0, r);
        *path0 = p0[0];
    } else {
        pray_from(&o, q, r, path0);
    }
    if (eaim > 0.0) {
        /* The aim's own error moves the start, and from a finite object
         * turns the direction by at most that over the distance. */
        r->eP += eaim;
        if (!o.inf)
            r->eD += eaim / *path0;
    }
    object_row(t, &o, r, &out[0]);
    return SG_OK;
}

int sg_launch_precise(sg_tracer *t, double hx, double hy, double px, double py,
                      sg_ray_surface *out)
{
    sg_pray r;
    double path0;
    int rc = sg_launch_precise_prep(t, hx, hy, px, py, out, &r, &path0);
    return rc != SG_OK ? rc : sg_precise_run_to(t, &r, path0, out, t->n - 1);
}

int sg_launch_classic_prep(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out, double S[3], double D[3], double *off,
                           int *inf)
{
    double u[3], len;
    dd q[2];
    osp o;
    int rc = field_cached(t, land_classic, hx, hy, &o, out);
    *inf = 0;
    *off = 0.0;
    if (rc != SG_OK)
        return rc;
    if (launch_q(t, land_classic, &o, px, py, q, 1, t->scratch, NULL) != SG_OK) {
        sg_fail_rest(out, 0, t->n, SG_EAIM);
        return SG_EAIM;
    }
    classic_start(&o, q, S, D);
    len = sqrt(D[0] * D[0] + D[1] * D[1] + D[2] * D[2]);
    u[0] = D[0] / len;
    u[1] = D[1] / len;
    u[2] = D[2] / len;
    if (o.inf) {
        sg_pray r;
        r.d = o.dir;
        object_row(t, &o, &r, &out[0]);
        /* The optical path from the field's start plane to Q. */
        *inf = 1;
        *off = o.n0 * (q[0].hi * o.dir.x.hi + q[1].hi * o.dir.y.hi - o.plane.hi);
    } else {
        sg_set_start_row(&out[0], S, u);
        out[0].z = S[2] + t->ln.T0.hi;
    }
    return SG_OK;
}

void sg_launch_classic_path(const sg_tracer *t, double off, sg_ray_surface *out)
{
    int i;
    for (i = 1; i < t->n && out[i].status == SG_OK; i++) {
        out[i].opl += off;
        out[i].opl_error_bound += sg_bound_up(4.0 * U53 * (fabs(off) + fabs(out[i].opl)));
    }
}

int sg_launch_classic(sg_tracer *t, double hx, double hy, double px, double py,
                      sg_ray_surface *out)
{
    double S[3], D[3], off;
    int inf, rc = sg_launch_classic_prep(t, hx, hy, px, py, out, S, D, &off, &inf);
    if (rc != SG_OK)
        return rc;
    rc = sg_classic_run_to(t, S, D, out, t->n - 1);
    if (inf)
        sg_launch_classic_path(t, off, out);
    return rc;
}

/* ------------------------------------------------------------------------
 * SG_VL rays of one field at once, for the batch trace.  Each lane repeats
 * the single-ray launch operation for operation; a lane that would leave
 * the common path (a landing that fails, a Jacobian that stops helping) is
 * launched again on its own by sg_launch_precise_prep, so every ray gets
 * the single-ray result bit for bit.
 * ------------------------------------------------------------------------ */

/* aim_newton from the field's Jacobian for nl lanes at once, on Q in qv.
 * done[k] is set for lanes that converged as the single-ray iteration
 * would; lane k of at is then the state their last landing left on the
 * stop (not bent), of launch and launch_path the state and path it was
 * launched with, and rows 1..stop of out[k] are that landing's.  A lane
 * that would need a Jacobian of its own, or whose landing fails, is left
 * with done[k] = 0 for the one-ray launch.  qv ends with the final Q. */
static void aim_newton_vec(sg_tracer *t, const osp *o, vdd qv[2], const vdd tg[2], int nl,
                           sg_ray_surface *const *out, int *done, sg_vray *at, sg_vray *launch,
                           vd *launch_path)
{
    double tol = t->o.aim_rtol * fmax(t->ln.stop_r.hi, 1e-300);
    vaim a;
    vm live = vm_set(0), fin = vm_set(0);
    int start[SG_VL], rc[SG_VL], k, it;
    aim_start(&a, (const double(*)[2])t->aimJ, 0, qv);
    for (k = 0; k < nl; k++)
        live[k] = -1;
    for (it = 0; it < t->o.aim_max_iter && vm_any(live); it++) {
        sg_vray v, v0;
        vd p0, nr;
        vdd res[2];
        vm landed = vm_set(0), ok, stalled;
        /* Only lanes still iterating are traced, each into its own output
         * rows, so that its last landing can start the final trace. */
        pray_from_v(o, a.q, &v, &p0);
        v0 = v;
        for (k = 0; k < nl; k++)
            start[k] = live[k] ? 1 : t->n;
        sg_precise_block(t, &v, p0, out, nl, start, t->sys->stop, rc);
        for (k = 0; k < nl; k++)
            if (live[k] && rc[k] == SG_OK)
                landed[k] = -1;
        /* In lanes that stop here, at belongs to the final Q, and so do
         * the launched state and path. */
        sg_vray_sel(landed, &v, at);
        sg_vray_sel(landed, &v0, launch);
        *launch_path = vsel(landed, p0, *launch_path);
        /* A landing that fails, stalls or leaves the doubles is the
         * one-ray launch's to handle. */
        aim_judge(&a, landed, v.p.x, v.p.y, v.eP, tg, tol, res, &nr, &ok, &stalled);
        fin |= ok;
        live &= landed & ~ok & ~stalled;
        /* A step in no lane changes nothing. */
        if (vm_any(live))
            live &= ~aim_step(&a, live, res, nr);
    }
    qv[0] = a.q[0];
    qv[1] = a.q[1];
    /* A lane out of iterations is the one-ray launch's, which adds the
     * aim's remaining error to its bound. */
    for (k = 0; k < nl; k++)
        done[k] = fin[k] ? 1 : 0;
}

/* Whether lane k's final trace may go on from its last landing, which left
 * the ray on the stop: the landing ran with clipping off, so the apertures
 * before the stop are checked here (the stop's own when it is bent), and a
 * bound that overflowed is left to the full trace, which meets the
 * overflow in the same order as a ray traced alone. */
static int resumable(const sg_tracer *t, const sg_ray_surface *rows, const sg_vray *at, int k)
{
    int i;
    if (t->sys->stop >= t->n - 1 || !isfinite(at->eP[k]) || !isfinite(at->eD[k]))
        return 0;
    for (i = 1; i < t->sys->stop; i++)
        if (sg_past_clip(t, &t->sp[i], rows[i].x, rows[i].y))
            return 0;
    return 1;
}

void sg_launch_precise_block(sg_tracer *t, double hx, double hy, const double (*pupil_in)[2],
                             int nl, sg_ray_surface *const *out, sg_vray *v, vd *path0,
                             int *start, int *rc)
{
    double pupil[SG_VL][2];
    vd px = vd_set(0.0), py = vd_set(0.0), p0 = vd_set(0.0);
    vdd qv[2], tg[2];
    sg_vray at, launch;
    vm resume = vm_set(0);
    int done[SG_VL], k, clip, aimed = 0, all;
    osp o;
    for (k = 0; k < nl; k++)
        start[k] = t->n;
    /* A field's vignetting factors move its pupil points, as for one ray. */
    for (k = 0; k < nl; k++)
        sg_field_vignette(t->sys, hx, hy, pupil_in[k][0], pupil_in[k][1], &pupil[k][0],
                          &pupil[k][1]);
    rc[0] = field_cached(t, land_precise, hx, hy, &o, out[0]);
    if (rc[0] != SG_OK) {
        for (k = 0; k < nl; k++) {
            sg_fail_rest(out[k], 0, t->n, rc[0]);
            rc[k] = rc[0];
        }
        return;
    }
    for (k = 0; k < SG_VL; k++) {
        px[k] = pupil[k < nl ? k : 0][0];
        py[k] = pupil[k < nl ? k : 0][1];
    }
    if (aim_off(t)) {
        q_aim_off_v(t, &o, px, py, qv);
    } else {
        /* The targets keep every bit of Px times the stop radius. */
        tg[0] = vdd_mul_d(vdd_set(t->ln.stop_r), px);
        tg[1] = vdd_mul_d(vdd_set(t->ln.stop_r), py);
        q_aim_start_v(t, &o, px, py, tg, qv);
    }
    for (k = 0; k < nl; k++)
        done[k] = aim_off(t);
    if (!aim_off(t)) {
        /* Apertures do not bend rays, so the iteration ignores them; the
         * final trace applies them. */
        clip = t->unclipped;
        t->unclipped = 1;
        if (!t->have_aimJ)
            field_jacobian(t, land_precise, &o, t->scratch);
        if (t->have_aimJ > 0) {
            /* Lanes that never land take neither. */
            memset(&at, 0, sizeof at);
            launch = at;
            aim_newton_vec(t, &o, qv, tg, nl, out, done, &at, &launch, &p0);
            aimed = 1;
        }
        t->unclipped = clip;
    }
    /* Lanes whose last landing was at their final Q already have its
     * launch; the rest are launched here. */
    for (k = 0, all = aimed; k < nl; k++)
        all = all && done[k] == 1;
    if (!all)
        pray_from_v(&o, qv, &launch, &p0);
    if (aim_off(t))
        add_aim_off_err_v(t, &o, px, py, &launch, p0);
    for (k = 0; k < nl; k++) {
        if (done[k]) {
            sg_pray r;
            sg_vray_get(&launch, k, &r);
            object_row(t, &o, &r, &out[k][0]);
            rc[k] = SG_OK;
            start[k] = 1;
            /* The last landing traced this very ray onto the stop, into
             * rows 1 .. stop. */
            if (aimed && done[k] == 1 && resumable(t, out[k], &at, k))
                resume[k] = -1;
        } else {
            sg_pray r;
            double pk;
            rc[k] = sg_launch_precise_prep(t, hx, hy, pupil[k][0], pupil[k][1], out[k], &r, &pk);
            if (rc[k] == SG_OK) {
                sg_vray_put(&launch, k, &r);
                p0[k] = pk;
                start[k] = 1;
            }
        }
    }
    *v = launch;
    *path0 = p0;
    if (vm_any(resume)) {
        sg_vray_sel(resume, &at, v);
        sg_precise_finish(t, t->sys->stop, v, out, resume, rc);
        for (k = 0; k < nl; k++)
            if (resume[k])
                start[k] = rc[k] == SG_OK ? t->sys->stop + 1 : t->n;
    }
}

static const char *const aper_names[6] = {"entrance pupil diameter", "image F/#", "object NA",
                                          "stop size", "paraxial working F/#",
                                          "object cone angle"};

/* Launch constants from a 128-bit paraxial trace. */
int sg_launch_prepare(sg_tracer *t, sg_diag *d)
{
    const sg_system *sys = t->sys;
    mpfr_t *idx, tmp, fx, fy, v;
    sg_parax_mp p;
    int i, k, rc;
    idx = sg_mp_block_new((size_t)t->n, 128);
    t->scratch = calloc((size_t)t->n, sizeof *t->scratch);
    if (!idx || !t->scratch) {
        free(idx);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    mpfr_inits2(128, tmp, fx, fy, v, (mpfr_ptr)0);
    sg_parax_mp_init(&p, 128);
    rc = sg_indices_mpfr_cached(sys, t->cat, t->wave, idx, t->icache, d);
    if (rc == SG_OK)
        rc = sg_paraxial_mpfr_memo(sys, idx, t->wave, 128, &p, d,
                                   sg_index_cache_parax(t->icache));
    if (rc == SG_OK && inf_object(t) && sys->field_type == SG_FIELD_OBJECT_HEIGHT)
        rc = sg_diag_set(d, SG_ENONPHYS,
                         "fields: object heights need an object at a finite distance "
                         "(surface 0 thickness is infinite)");
    if (rc == SG_OK) {
        sg_parax_to_double(&p, &t->px);
        t->ln.obj_inf = inf_object(t);
        /* Distances from the launch plane (sg_launch_step after surface
         * 1's place), exact sums of doubles in 128 bits. */
        if (!t->ln.obj_inf) {
            mpfr_set_d(v, sys->surf[0].thickness, MPFR_RNDN);
            mpfr_add_d(v, v, sg_launch_step(sys), MPFR_RNDN);
            t->ln.T0 = dd_from_mpfr(v, tmp);
        }
        mpfr_sub_d(v, p.enp, sg_launch_step(sys), MPFR_RNDN);
        t->ln.enp = dd_from_mpfr(v, tmp);
        mpfr_div_2ui(v, p.epd, 1, MPFR_RNDN);
        t->ln.epr = dd_from_mpfr(v, tmp);
        t->ln.tele = sys->telecentric && !t->ln.obj_inf;
        if (t->ln.tele) {
            /* The marginal slope, as the paraxial trace takes it (which has
             * checked the aperture). */
            rc = sg_object_slope_mpfr(sys, idx[0], v, d);
            t->ln.tslope = dd_from_mpfr(v, tmp);
        }
        t->ln.stop_r = dd_from_mpfr(p.stop_r, tmp);
        t->ln.pimg_slope = dd_from_mpfr(p.pimg_slope, tmp);
        t->ln.pimg_slope_f = dd_from_mpfr(p.pimg_slope_f, tmp);
        if ((sys->field_type == SG_FIELD_PARAX_IMAGE_HEIGHT ||
             sys->field_type == SG_FIELD_REAL_IMAGE_HEIGHT) &&
            !(t->ln.pimg_slope.hi != 0.0 && isfinite(t->ln.pimg_slope.hi) &&
              t->ln.pimg_slope_f.hi != 0.0 && isfinite(t->ln.pimg_slope_f.hi)))
            rc = sg_diag_set(d, SG_ENONPHYS,
                             "fields: image heights cannot define fields in this system: the "
                             "paraxial chief ray meets the image at height %g whatever the "
                             "field", t->ln.pimg_slope.hi);
        /* Field scales: the largest radius, or the largest |x| and |y|. */
        mpfr_set_zero(fx, 1);
        mpfr_set_zero(fy, 1);
        for (k = 0; k < sys->nfield; k++) {
            if (sys->field_norm == SG_NORM_RADIAL) {
                mpfr_set_d(v, sys->field[k].x, MPFR_RNDN);
                mpfr_sqr(v, v, MPFR_RNDN);
                mpfr_set_d(tmp, sys->field[k].y, MPFR_RNDN);
                mpfr_sqr(tmp, tmp, MPFR_RNDN);
                mpfr_add(v, v, tmp, MPFR_RNDN);
                mpfr_sqrt(v, v, MPFR_RNDN);
                mpfr_max(fx, fx, v, MPFR_RNDN);
                mpfr_max(fy, fy, v, MPFR_RNDN);
            } else {
                mpfr_set_d(v, fabs(sys->field[k].x), MPFR_RNDN);
                mpfr_max(fx, fx, v, MPFR_RNDN);
                mpfr_set_d(v, fabs(sys->field[k].y), MPFR_RNDN);
                mpfr_max(fy, fy, v, MPFR_RNDN);
            }
        }
        t->ln.fx = dd_from_mpfr(fx, tmp);
        t->ln.fy = dd_from_mpfr(fy, tmp);
    }
    /* The stop's vertex in surface 1's frame, and whether the surfaces
     * before it leave a ray straight. */
    t->ln.straight = !t->sp[1].xf;
    t->ln.zstop = dd_from(0.0);
    for (i = 1; i < sys->stop; i++) {
        t->ln.straight = t->ln.straight && sg_sprep_passes(&t->sp[i]);
        t->ln.zstop = dd_add_d(t->ln.zstop, t->sp[i + 1].T);
    }
    sg_parax_mp_clear(&p);
    mpfr_clears(tmp, fx, fy, v, (mpfr_ptr)0);
    free(idx);
    if (rc != SG_OK)
        return rc;
    if (!t->ln.tele && (!(fabs(t->ln.enp.hi) <= 1e150) || !(t->ln.epr.hi <= 1e150) ||
                        !(fabs(t->ln.stop_r.hi) <= 1e150)))
        return sg_diag_set(d, SG_ERANGE,
                           "aperture: %s %g gives an entrance pupil of radius %g at %g "
                           "from surface 1, beyond 1e+150 lens units (a trace squares it)",
                           aper_names[sys->aper_type < 6 ? sys->aper_type : 0],
                           sys->aper_value, t->ln.epr.hi, t->ln.enp.hi);
    if (t->prim) {
        /* As in Zemax, the pupil's position and size, the aperture and the
         * fields belong to the primary wavelength: every wavelength's rays
         * launch through the primary's pupil, towards its stop radius. */
        t->ln.enp = t->prim->ln.enp;
        t->ln.epr = t->prim->ln.epr;
        t->ln.tslope = t->prim->ln.tslope;
        t->ln.stop_r = t->prim->ln.stop_r;
        t->ln.pimg_slope = t->prim->ln.pimg_slope;
        t->ln.pimg_slope_f = t->prim->ln.pimg_slope_f;
        return SG_OK;
    }

    /* Real aiming with a pupil set by anything but the stop size lands the
     * marginal ray where the real on-axis marginal ray meets the stop. */
    if (sys->aim == SG_AIM_REAL && sys->aper_type != SG_APER_FLOAT_STOP && !t->ln.tele) {
        osp o;
        dd q[2], at[2];
        int saved = t->o.method == SG_METHOD_CLASSIC;
        double noise;
        osp_from_values(t, dd_from(0.0), dd_from(0.0), 0, &o);
        if (sys->field_type == SG_FIELD_ANGLE && t->ln.obj_inf)
            osp_from_values(t, dd_from(0.0), dd_from(0.0), 1, &o);
        int clip = t->unclipped;
        q_aim_off(t, &o, 0.0, 1.0, q);
        /* The stop's size is the unvignetted marginal ray's, as in every
         * other landing: an off-axis system's apertures may stop the
         * on-axis beam. */
        t->unclipped = 1;
        rc = saved ? land_classic(t, &o, q, at, &noise, t->scratch)
                   : land_precise(t, &o, q, at, &noise, t->scratch);
        t->unclipped = clip;
        if (rc != SG_OK)
            return sg_diag_set(d, SG_EAIM,
                               "ray aiming: the on-axis marginal ray does not reach the stop "
                               "(surface %d): %s", sys->stop, sg_strerror(rc));
        t->ln.stop_r = dd_sqrt(dd_add(dd_sqr(at[0]), dd_sqr(at[1])));
    }
    return SG_OK;
}
