/*
 * merit.c - Zemax's merit function: its operands and its default part
 * (sagitta-design(5), MERIT FUNCTION; sagitta(1), OPTIMIZATION).
 *
 * MF^2 = sum w (v - t)^2 / sum w over the rows of nonzero weight.  The
 * default part is transverse x and y of rays about the centroid or the
 * chief ray, the pupil sampled by Gaussian quadrature in rings and arms
 * (Forbes, JOSA A 5, 1943 (1988)).  A row that cannot be computed is an
 * error naming it, never a NaN.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"
#include "merit.h"

#define PI 3.14159265358979323846

static const sg_op_info ops[SG_OP_NTYPES] = {
    [SG_OP_BLNK] = {"BLNK", NULL, NULL, 0, 0},
    [SG_OP_EFFL] = {"EFFL", NULL, "wave", 0, 0},
    [SG_OP_TOTR] = {"TOTR", NULL, NULL, 0, 0},
    [SG_OP_TTHI] = {"TTHI", "surf1", "surf2", 0, 0},
    [SG_OP_CTGT] = {"CTGT", "surf", NULL, 0, 0},
    [SG_OP_CTLT] = {"CTLT", "surf", NULL, 0, 0},
    [SG_OP_CTVA] = {"CTVA", "surf", NULL, 0, 0},
    [SG_OP_ETGT] = {"ETGT", "surf", NULL, 0, 0},
    [SG_OP_ETLT] = {"ETLT", "surf", NULL, 0, 0},
    [SG_OP_ETVA] = {"ETVA", "surf", NULL, 0, 0},
    [SG_OP_MNCT] = {"MNCT", "surf1", "surf2", 0, 0},
    [SG_OP_MXCT] = {"MXCT", "surf1", "surf2", 0, 0},
    [SG_OP_MNET] = {"MNET", "surf1", "surf2", 0, 0},
    [SG_OP_MNCA] = {"MNCA", "surf1", "surf2", 0, 0},
    [SG_OP_MXCA] = {"MXCA", "surf1", "surf2", 0, 0},
    [SG_OP_MNCG] = {"MNCG", "surf1", "surf2", 0, 0},
    [SG_OP_MXCG] = {"MXCG", "surf1", "surf2", 0, 0},
    [SG_OP_REAX] = {"REAX", "surf", "wave", 1, 1},
    [SG_OP_REAY] = {"REAY", "surf", "wave", 1, 1},
    [SG_OP_REAZ] = {"REAZ", "surf", "wave", 1, 1},
    [SG_OP_TRAX] = {"TRAX", NULL, "wave", 1, 1},
    [SG_OP_TRAY] = {"TRAY", NULL, "wave", 1, 1},
    [SG_OP_TRAR] = {"TRAR", NULL, "wave", 1, 1},
    [SG_OP_RSCE] = {"RSCE", "rings", "wave", 1, 0},
    [SG_OP_RSCH] = {"RSCH", "rings", "wave", 1, 0},
    [SG_OP_SUMM] = {"SUMM", "op1", "op2", 0, 0},
    [SG_OP_DIFF] = {"DIFF", "op1", "op2", 0, 0},
    [SG_OP_PROD] = {"PROD", "op1", "op2", 0, 0},
    [SG_OP_DIVI] = {"DIVI", "op1", "op2", 0, 0},
    [SG_OP_CONS] = {"CONS", NULL, NULL, 0, 0},
    [SG_OP_OPGT] = {"OPGT", "op1", NULL, 0, 0},
    [SG_OP_OPLT] = {"OPLT", "op1", NULL, 0, 0},
    [SG_OP_ABSO] = {"ABSO", "op1", NULL, 0, 0},
};

const sg_op_info *sg_op_info_of(sg_op_type t)
{
    return (int)t >= 0 && t < SG_OP_NTYPES ? &ops[t] : &ops[SG_OP_BLNK];
}

const char *sg_op_name(sg_op_type t)
{
    return (int)t >= 0 && t < SG_OP_NTYPES ? ops[t].name : NULL;
}

int sg_op_parse(const char *name)
{
    int t;
    for (t = 0; t < SG_OP_NTYPES; t++)
        if (strcmp(ops[t].name, name) == 0)
            return t;
    return -1;
}

/* The arms of RSCE and RSCH with n rings: enough that the angular sum is
 * exact for the trigonometric terms of a spot's square up to 2n + 3. */
static int rs_arms(int rings)
{
    return 2 * rings + 4;
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

int sg_merit_equal(const sg_merit *a, const sg_merit *b)
{
    int i;
    if (a->present != b->present || a->has_default != b->has_default ||
        a->reference != b->reference || a->rings != b->rings || a->arms != b->arms ||
        a->nop != b->nop)
        return 0;
    for (i = 0; i < a->nop; i++) {
        const sg_operand *x = &a->op[i], *y = &b->op[i];
        if (x->type != y->type || x->i1 != y->i1 || x->i2 != y->i2 || !same_bits(x->hx, y->hx) ||
            !same_bits(x->hy, y->hy) || !same_bits(x->px, y->px) || !same_bits(x->py, y->py) ||
            !same_bits(x->target, y->target) || !same_bits(x->weight, y->weight))
            return 0;
    }
    return 1;
}

int sg_merit_rings(int n, double *rho, double *w)
{
    int i, k;
    if (n < 1 || n > 32)
        return SG_ERANGE;
    /* Gauss-Legendre on [-1, 1] by Newton from the Chebyshev guess, then
     * mapped to u = (x + 1) / 2 in [0, 1], weights halved. */
    for (i = 0; i < n; i++) {
        double x = cos(PI * (i + 0.75) / (n + 0.5)), p0, p1, dp = 1.0;
        int it;
        for (it = 0; it < 100; it++) {
            double dx;
            p0 = 1.0;
            p1 = x;
            for (k = 2; k <= n; k++) {
                double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (x * p1 - p0) / (x * x - 1.0);
            dx = p1 / dp;
            x -= dx;
            if (fabs(dx) <= 1e-16)
                break;
        }
        /* Recompute the derivative at the root for the weight. */
        p0 = 1.0;
        p1 = x;
        for (k = 2; k <= n; k++) {
            double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        dp = n * (x * p1 - p0) / (x * x - 1.0);
        /* Rings from the centre outwards. */
        rho[n - 1 - i] = sqrt((x + 1.0) / 2.0);
        w[n - 1 - i] = 1.0 / ((1.0 - x * x) * dp * dp);
    }
    return SG_OK;
}

static int check_surf(const sg_system *sys, int row, const char *key, int s, int lo, int hi,
                      sg_diag *d)
{
    if (s < lo || s > hi)
        return sg_diag_set(d, SG_ERANGE, "merit: operand %d: %s %d is not a surface %d to %d",
                           row, key, s, lo, hi);
    (void)sys;
    return SG_OK;
}

int sg_merit_check(const sg_system *sys, sg_diag *d)
{
    int i, rc, ns = sys->nsurf;
    const sg_merit *m = &sys->merit;
    if (m->has_default && (m->rings < 1 || m->rings > 20 || m->arms < 1 || m->arms > 64))
        return sg_diag_set(d, SG_ERANGE, "merit: default: rings %d or arms %d out of range "
                           "(1 to 20, 1 to 64)", m->rings, m->arms);
    for (i = 0; i < m->nop; i++) {
        const sg_operand *o = &m->op[i];
        const sg_op_info *inf = sg_op_info_of(o->type);
        int row = i + 1;
        if ((int)o->type < 0 || o->type >= SG_OP_NTYPES)
            return sg_diag_set(d, SG_ERANGE, "merit: operand %d: unknown type", row);
        if (!(o->weight >= 0.0) || !isfinite(o->weight) || !isfinite(o->target))
            return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): the target and weight "
                               "must be finite, the weight not negative", row, inf->name);
        if (inf->k2 && strcmp(inf->k2, "wave") == 0 && (o->i2 < 0 || o->i2 > sys->nwave))
            return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): wave %d is not 0 to %d", row,
                               inf->name, o->i2, sys->nwave);
        switch (o->type) {
        case SG_OP_TTHI:
            if ((rc = check_surf(sys, row, "surf1", o->i1, 0, ns - 1, d)) != SG_OK ||
                (rc = check_surf(sys, row, "surf2", o->i2, o->i1, ns - 1, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_CTGT: case SG_OP_CTLT: case SG_OP_CTVA:
        case SG_OP_ETGT: case SG_OP_ETLT: case SG_OP_ETVA:
            if ((rc = check_surf(sys, row, "surf", o->i1, 1, ns - 2, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_MNCT: case SG_OP_MXCT: case SG_OP_MNET: case SG_OP_MNCA: case SG_OP_MXCA:
        case SG_OP_MNCG: case SG_OP_MXCG:
            /* 0 and 0: every surface between object and image. */
            if (o->i1 == 0 && o->i2 == 0)
                break;
            if ((rc = check_surf(sys, row, "surf1", o->i1, 1, ns - 2, d)) != SG_OK ||
                (rc = check_surf(sys, row, "surf2", o->i2, o->i1, ns - 2, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_REAX: case SG_OP_REAY: case SG_OP_REAZ:
            if ((rc = check_surf(sys, row, "surf", o->i1, 1, ns - 1, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_RSCE: case SG_OP_RSCH:
            if (o->i1 < 1 || o->i1 > 20)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): rings %d is not 1 to "
                                   "20", row, inf->name, o->i1);
            break;
        case SG_OP_SUMM: case SG_OP_DIFF: case SG_OP_PROD: case SG_OP_DIVI:
            if (o->i2 < 1 || o->i2 >= row)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): op2 %d is not an "
                                   "earlier operand (1 to %d)", row, inf->name, o->i2, row - 1);
            /* fall through */
        case SG_OP_OPGT: case SG_OP_OPLT: case SG_OP_ABSO:
            if (o->i1 < 1 || o->i1 >= row)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): op1 %d is not an "
                                   "earlier operand (1 to %d)", row, inf->name, o->i1, row - 1);
            break;
        default: break;
        }
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Evaluation
 * ------------------------------------------------------------------------ */

typedef struct ectx {
    const sg_system *sys;
    const sg_catalog *cat;
    sg_tracer *tr[SG_MAX_WAVES];
    sg_ray_surface *rows;
    int have_sd;
    double *sd;
    double bound;   /* the largest error bound of a traced value */
} ectx;

static int tracer_of(ectx *c, int w, sg_tracer **out, sg_diag *d)
{
    if (!c->tr[w]) {
        sg_trace_opts o;
        int rc;
        sg_trace_opts_init(&o);
        o.wave = w;
        if ((rc = sg_tracer_open(c->sys, c->cat, &o, &c->tr[w], d)) != SG_OK)
            return rc;
    }
    *out = c->tr[w];
    return SG_OK;
}

/* The ray (hx, hy, px, py) at wavelength w (0-based): its row at surface
 * s.  A failure names what and where; why is the ray's status. */
static int ray_at(ectx *c, int w, double hx, double hy, double px, double py, int s,
                  sg_ray_surface *out, const char *what, sg_diag *d)
{
    sg_tracer *t;
    int rc = tracer_of(c, w, &t, d), k;
    if (rc != SG_OK)
        return rc;
    rc = sg_trace_normalized(t, hx, hy, px, py, c->rows);
    if (rc != SG_OK) {
        for (k = 1; k < c->sys->nsurf && c->rows[k].status == SG_OK; k++)
            ;
        return sg_diag_set(d, rc, "%s: the ray (hx %g, hy %g, px %g, py %g) at wavelength %d "
                           "fails at surface %d: %s", what, hx, hy, px, py, w + 1, k,
                           sg_strerror(rc));
    }
    *out = c->rows[s];
    if (c->rows[s].error_bound > c->bound)
        c->bound = c->rows[s].error_bound;
    return SG_OK;
}

/* The wavelength an operand names: 1-based, 0 the primary. */
static int wave_of(const ectx *c, int w)
{
    return w >= 1 ? w - 1 : c->sys->primary_wave;
}

/* Transverse aberration at the image about the primary chief ray. */
static int transverse(ectx *c, const sg_operand *o, double *dx, double *dy, const char *what,
                      sg_diag *d)
{
    sg_ray_surface r, ch;
    int img = c->sys->nsurf - 1, rc;
    if ((rc = ray_at(c, wave_of(c, o->i2), o->hx, o->hy, o->px, o->py, img, &r, what, d)) !=
            SG_OK ||
        (rc = ray_at(c, c->sys->primary_wave, o->hx, o->hy, 0.0, 0.0, img, &ch, what, d)) !=
            SG_OK)
        return rc;
    *dx = r.x - ch.x;
    *dy = r.y - ch.y;
    return SG_OK;
}

/* RMS spot radius of field (hx, hy) by Gaussian quadrature: rings and
 * 2 rings + 4 arms, at wave w (1-based) or every wavelength (0) by its
 * weight; about the centroid or the primary chief ray. */
static int rms_spot(ectx *c, int rings, int w, double hx, double hy, int chief, double *out,
                    const char *what, sg_diag *d)
{
    double rho[32], wt[32], sx = 0, sy = 0, sw = 0, cx, cy, s2 = 0.0, (*pt)[3];
    int arms = rs_arms(rings), i, j, k, w0 = w ? w - 1 : 0, w1 = w ? w : c->sys->nwave, rc;
    int img = c->sys->nsurf - 1, np = 0;
    sg_ray_surface r;
    pt = malloc((size_t)(w1 - w0) * (size_t)rings * (size_t)arms * sizeof *pt);
    if (!pt)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    sg_merit_rings(rings, rho, wt);
    for (k = w0; k < w1; k++) {
        double ww = w ? 1.0 : c->sys->wave[k].weight;
        if (ww == 0.0)
            continue;
        for (i = 0; i < rings; i++)
            for (j = 0; j < arms; j++) {
                double th = PI * (2.0 * j + 1.0) / arms, q = ww * wt[i] / arms;
                if ((rc = ray_at(c, k, hx, hy, rho[i] * cos(th), rho[i] * sin(th), img, &r, what,
                                 d)) != SG_OK) {
                    free(pt);
                    return rc;
                }
                pt[np][0] = r.x;
                pt[np][1] = r.y;
                pt[np++][2] = q;
                sx += q * r.x;
                sy += q * r.y;
                sw += q;
            }
    }
    if (!(sw > 0.0)) {
        free(pt);
        return sg_diag_set(d, SG_ERANGE, "%s: every wavelength has weight 0", what);
    }
    if (chief) {
        if ((rc = ray_at(c, c->sys->primary_wave, hx, hy, 0.0, 0.0, img, &r, what, d)) != SG_OK) {
            free(pt);
            return rc;
        }
        cx = r.x;
        cy = r.y;
    } else {
        cx = sx / sw;
        cy = sy / sw;
    }
    /* About the reference point, not from the sums about the origin,
     * which would cancel digits. */
    for (i = 0; i < np; i++)
        s2 += pt[i][2] * ((pt[i][0] - cx) * (pt[i][0] - cx) + (pt[i][1] - cy) * (pt[i][1] - cy));
    free(pt);
    *out = sqrt(s2 / sw);
    return SG_OK;
}

/* The semi-diameters the edge operands use: the design's, or where one is
 * 0 the automatic one. */
static int semi_of(ectx *c, int s, double *h, sg_diag *d)
{
    if (c->sys->surf[s].semi_diameter > 0.0) {
        *h = c->sys->surf[s].semi_diameter;
        return SG_OK;
    }
    if (!c->have_sd) {
        int rc;
        c->sd = calloc((size_t)c->sys->nsurf, sizeof *c->sd);
        if (!c->sd)
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        if ((rc = sg_semi_diameters(c->sys, c->cat, NULL, c->sd, d)) != SG_OK)
            return rc;
        c->have_sd = 1;
    }
    *h = c->sd[s];
    return SG_OK;
}

/* Edge thickness of surface s: its thickness plus the next surface's sag
 * less its own, at the larger of the two semi-diameters, along +y. */
static int edge_thickness(ectx *c, int s, double *out, const char *what, sg_diag *d)
{
    double h1, h2, h, z1, z2;
    int rc;
    if ((rc = semi_of(c, s, &h1, d)) != SG_OK || (rc = semi_of(c, s + 1, &h2, d)) != SG_OK)
        return rc;
    h = h1 > h2 ? h1 : h2;
    z1 = sg_surface_sag(&c->sys->surf[s], 0.0, h);
    z2 = sg_surface_sag(&c->sys->surf[s + 1], 0.0, h);
    if (!isfinite(z1) || !isfinite(z2))
        return sg_diag_set(d, SG_ENONPHYS, "%s: surface %d or %d has no sag at height %g", what,
                           s, s + 1, h);
    *out = c->sys->surf[s].thickness + z2 - z1;
    return SG_OK;
}

/* Which surfaces a range operand reads: air after the surface (MNCA,
 * MXCA), glass (MNCG, MXCG), or every one. */
static int range_takes(const sg_surface *s, sg_op_type t)
{
    int air = s->mat.kind == SG_MAT_AIR, mirror = s->mat.kind == SG_MAT_MIRROR;
    if (s->type == SG_SURF_COORDBRK)
        return 0;
    switch (t) {
    case SG_OP_MNCA: case SG_OP_MXCA: return air;
    case SG_OP_MNCG: case SG_OP_MXCG: return !air && !mirror;
    default: return 1;
    }
}

/* A boundary over a range: the target when every surface keeps it, else
 * the target less (MN) or plus (MX) the root sum square of the breaches,
 * so one breach gives the offending value, as CTGT does. */
static int range_op(ectx *c, const sg_operand *o, double *v, const char *what, sg_diag *d)
{
    int a = o->i1, b = o->i2, s, rc, mn = o->type == SG_OP_MNCT || o->type == SG_OP_MNET ||
                                       o->type == SG_OP_MNCA || o->type == SG_OP_MNCG;
    double ss = 0.0;
    if (a == 0 && b == 0) {
        a = 1;
        b = c->sys->nsurf - 2;
    }
    for (s = a; s <= b; s++) {
        double t = c->sys->surf[s].thickness, e;
        if (!range_takes(&c->sys->surf[s], o->type))
            continue;
        if (o->type == SG_OP_MNET) {
            if ((rc = edge_thickness(c, s, &t, what, d)) != SG_OK)
                return rc;
        }
        e = mn ? o->target - t : t - o->target;
        if (e > 0.0)
            ss += e * e;
    }
    *v = mn ? o->target - sqrt(ss) : o->target + sqrt(ss);
    return SG_OK;
}

static int eval_operand(ectx *c, int i, const double *val, double *v, sg_diag *d)
{
    const sg_system *sys = c->sys;
    const sg_operand *o = &sys->merit.op[i];
    char what[64];
    sg_ray_surface r;
    double x, y;
    int rc, s;
    snprintf(what, sizeof what, "merit: operand %d (%s)", i + 1, sg_op_name(o->type));
    switch (o->type) {
    case SG_OP_BLNK:
    case SG_OP_CONS:
        *v = o->type == SG_OP_CONS ? o->target : 0.0;
        return SG_OK;
    case SG_OP_EFFL: {
        sg_paraxial p;
        sg_diag dd;
        sg_diag_clear(&dd);
        if ((rc = sg_paraxial_compute(sys, c->cat, wave_of(c, o->i2), &p, &dd)) != SG_OK)
            return sg_diag_set(d, rc, "%s: %s", what, dd.msg);
        if (!isfinite(p.efl))
            return sg_diag_set(d, SG_ENONPHYS, "%s: the system is afocal (no finite EFL)", what);
        *v = p.efl;
        return SG_OK;
    }
    case SG_OP_TOTR:
        x = 0.0;
        for (s = 1; s < sys->nsurf - 1; s++)
            x += sys->surf[s].thickness;
        *v = x;
        return SG_OK;
    case SG_OP_TTHI:
        x = 0.0;
        for (s = o->i1; s <= o->i2; s++) {
            if (!isfinite(sys->surf[s].thickness))
                return sg_diag_set(d, SG_ENONPHYS, "%s: surface %d's thickness is infinite",
                                   what, s);
            x += sys->surf[s].thickness;
        }
        *v = x;
        return SG_OK;
    case SG_OP_CTGT: case SG_OP_CTLT: case SG_OP_CTVA:
        x = sys->surf[o->i1].thickness;
        *v = o->type == SG_OP_CTVA ? x : o->type == SG_OP_CTGT ? (x < o->target ? x : o->target)
                                                                : (x > o->target ? x : o->target);
        return SG_OK;
    case SG_OP_ETGT: case SG_OP_ETLT: case SG_OP_ETVA:
        if ((rc = edge_thickness(c, o->i1, &x, what, d)) != SG_OK)
            return rc;
        *v = o->type == SG_OP_ETVA ? x : o->type == SG_OP_ETGT ? (x < o->target ? x : o->target)
                                                                : (x > o->target ? x : o->target);
        return SG_OK;
    case SG_OP_MNCT: case SG_OP_MXCT: case SG_OP_MNET: case SG_OP_MNCA: case SG_OP_MXCA:
    case SG_OP_MNCG: case SG_OP_MXCG:
        return range_op(c, o, v, what, d);
    case SG_OP_REAX: case SG_OP_REAY: case SG_OP_REAZ:
        if ((rc = ray_at(c, wave_of(c, o->i2), o->hx, o->hy, o->px, o->py, o->i1, &r, what, d)) !=
            SG_OK)
            return rc;
        *v = o->type == SG_OP_REAX ? r.x : o->type == SG_OP_REAY ? r.y : r.z;
        return SG_OK;
    case SG_OP_TRAX: case SG_OP_TRAY: case SG_OP_TRAR:
        if ((rc = transverse(c, o, &x, &y, what, d)) != SG_OK)
            return rc;
        *v = o->type == SG_OP_TRAX ? x : o->type == SG_OP_TRAY ? y : hypot(x, y);
        return SG_OK;
    case SG_OP_RSCE: case SG_OP_RSCH:
        return rms_spot(c, o->i1, o->i2, o->hx, o->hy, o->type == SG_OP_RSCH, v, what, d);
    case SG_OP_SUMM: *v = val[o->i1 - 1] + val[o->i2 - 1]; return SG_OK;
    case SG_OP_DIFF: *v = val[o->i1 - 1] - val[o->i2 - 1]; return SG_OK;
    case SG_OP_PROD: *v = val[o->i1 - 1] * val[o->i2 - 1]; return SG_OK;
    case SG_OP_DIVI:
        if (val[o->i2 - 1] == 0.0)
            return sg_diag_set(d, SG_ERANGE, "%s: operand %d, the divisor, is 0", what, o->i2);
        *v = val[o->i1 - 1] / val[o->i2 - 1];
        return SG_OK;
    case SG_OP_OPGT:
        x = val[o->i1 - 1];
        *v = x < o->target ? x : o->target;
        return SG_OK;
    case SG_OP_OPLT:
        x = val[o->i1 - 1];
        *v = x > o->target ? x : o->target;
        return SG_OK;
    case SG_OP_ABSO: *v = fabs(val[o->i1 - 1]); return SG_OK;
    default: break;
    }
    return sg_diag_set(d, SG_ERANGE, "%s: unknown operand", what);
}

/* The default part's rows: for each field, wavelength, ring and arm, the
 * ray's x and y about the reference, weighted by the field's and the
 * wavelength's weights times the ring's quadrature weight over the arms. */
static int eval_default(ectx *c, sg_merit_result *res, int first, sg_diag *d)
{
    const sg_system *sys = c->sys;
    const sg_merit *m = &sys->merit;
    double rho[32], wt[32];
    int f, k, i, j, rc, n = first, img = sys->nsurf - 1;
    sg_merit_rings(m->rings, rho, wt);
    for (f = 0; f < sys->nfield; f++) {
        double hx, hy, cx = 0.0, cy = 0.0, sw = 0.0;
        int start = n;
        char what[160];
        sg_field_normalized(sys, f, &hx, &hy);
        for (k = 0; k < sys->nwave; k++)
            for (i = 0; i < m->rings; i++)
                for (j = 0; j < m->arms; j++) {
                    double th = PI * (2.0 * j + 1.0) / m->arms;
                    double q = sys->field[f].weight * sys->wave[k].weight * wt[i] / m->arms;
                    sg_ray_surface r;
                    snprintf(what, sizeof what, "merit: default rows %d and %d (field %d, "
                             "wavelength %d, ring %d, arm %d)", n + 1, n + 2, f + 1, k + 1, i + 1,
                             j + 1);
                    if (q == 0.0) {
                        r.x = r.y = 0.0;
                    } else if ((rc = ray_at(c, k, hx, hy, rho[i] * cos(th), rho[i] * sin(th),
                                            img, &r, what, d)) != SG_OK) {
                        return rc;
                    }
                    res->row[n].type = SG_OP_TRAX;
                    res->row[n].value = r.x;
                    res->row[n].weight = q;
                    res->row[n + 1].type = SG_OP_TRAY;
                    res->row[n + 1].value = r.y;
                    res->row[n + 1].weight = q;
                    cx += q * r.x;
                    cy += q * r.y;
                    sw += q;
                    n += 2;
                }
        if (m->reference == SG_MERIT_CHIEF) {
            sg_ray_surface r;
            snprintf(what, sizeof what, "merit: default: field %d's chief ray", f + 1);
            if ((rc = ray_at(c, sys->primary_wave, hx, hy, 0.0, 0.0, img, &r, what, d)) != SG_OK)
                return rc;
            cx = r.x;
            cy = r.y;
        } else if (sw > 0.0) {
            cx /= sw;
            cy /= sw;
        }
        for (i = start; i < n; i += 2) {
            if (res->row[i].weight == 0.0)
                continue;
            res->row[i].value -= cx;
            res->row[i + 1].value -= cy;
        }
    }
    return SG_OK;
}

void sg_merit_result_free(sg_merit_result *r)
{
    if (r) {
        free(r->row);
        r->row = NULL;
        r->nrow = 0;
    }
}

int sg_merit_eval(const sg_system *sys, const sg_catalog *cat, sg_merit_result *out,
                  sg_diag *d)
{
    const sg_merit *m = &sys->merit;
    ectx c;
    int i, rc, ndef, nrow;
    double *val = NULL, sum = 0.0, wsum = 0.0;
    memset(out, 0, sizeof *out);
    if (!m->present || (m->nop == 0 && !m->has_default))
        return sg_diag_set(d, SG_ENOSYS, "the design has no merit function (sagitta-design(5), "
                           "MERIT FUNCTION)");
    if ((rc = sg_merit_check(sys, d)) != SG_OK)
        return rc;
    ndef = m->has_default ? 2 * sys->nfield * sys->nwave * m->rings * m->arms : 0;
    nrow = m->nop + ndef;
    memset(&c, 0, sizeof c);
    c.sys = sys;
    c.cat = cat;
    c.rows = malloc((size_t)sys->nsurf * sizeof *c.rows);
    out->row = calloc((size_t)(nrow ? nrow : 1), sizeof *out->row);
    val = calloc((size_t)(m->nop ? m->nop : 1), sizeof *val);
    if (!c.rows || !out->row || !val) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    out->nrow = nrow;
    for (i = 0; i < m->nop; i++) {
        const sg_operand *o = &m->op[i];
        if ((rc = eval_operand(&c, i, val, &val[i], d)) != SG_OK)
            goto done;
        out->row[i].type = o->type;
        out->row[i].value = val[i];
        out->row[i].target = o->target;
        out->row[i].weight = o->type == SG_OP_BLNK ? 0.0 : o->weight;
    }
    if (ndef && (rc = eval_default(&c, out, m->nop, d)) != SG_OK)
        goto done;
    for (i = 0; i < nrow; i++) {
        double e = out->row[i].value - out->row[i].target;
        out->row[i].row = i + 1;
        if (out->row[i].weight == 0.0)
            continue;
        if (!isfinite(out->row[i].value)) {
            rc = sg_diag_set(d, SG_ENONPHYS, "merit: row %d (%s): the value is not finite", i + 1,
                             sg_op_name(out->row[i].type));
            goto done;
        }
        out->row[i].contribution = out->row[i].weight * e * e;
        sum += out->row[i].contribution;
        wsum += out->row[i].weight;
    }
    for (i = 0; i < nrow; i++)
        out->row[i].contribution = sum > 0.0 ? 100.0 * out->row[i].contribution / sum : 0.0;
    if (!(wsum > 0.0)) {
        rc = sg_diag_set(d, SG_ERANGE, "merit: every row has weight 0");
        goto done;
    }
    out->wsum = wsum;
    out->merit = sqrt(sum / wsum);
    out->bound = c.bound;
    rc = SG_OK;
done:
    for (i = 0; i < SG_MAX_WAVES; i++)
        if (c.tr[i])
            sg_tracer_free(c.tr[i]);
    free(c.rows);
    free(c.sd);
    free(val);
    if (rc != SG_OK)
        sg_merit_result_free(out);
    return rc;
}
