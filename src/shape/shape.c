/*
 * shape.c - the registry of surface shapes and what they share: the
 * rotational conic with even and odd polynomials, and polynomials in
 * x and y (see shape.h).
 */
#include <math.h>
#include <string.h>

#include "shape.h"

/* The registry: each type's record, in the order of SG_SURF_TYPES. */
#define SG_SHAPE_REC_(name, json, zmx, rec) [SG_SURF_##name] = &sg_shape_##rec##_type,
static const sg_shape_type *const registry[SG_SURF_NTYPES] = {SG_SURF_TYPES(SG_SHAPE_REC_)};
#undef SG_SHAPE_REC_

/* The values files and users of the library have always seen. */
typedef char surf_values_kept[SG_SURF_STANDARD == 0 && SG_SURF_EVENASPH == 1 &&
                                      SG_SURF_COORDBRK == 2 && SG_SURF_ODDASPH == 3 &&
                                      SG_SURF_TOROIDAL == 4 && SG_SURF_BICONIC == 5 &&
                                      SG_SURF_ZERNIKE_FRINGE == 6 &&
                                      SG_SURF_ZERNIKE_STANDARD == 7 && SG_SURF_XYPOLY == 8
                                  ? 1
                                  : -1];

const sg_shape_type *sg_shape_type_of(int type)
{
    return type >= 0 && type < SG_SURF_NTYPES ? registry[type] : NULL;
}

int sg_shape_reads(int type, const char *key)
{
    const sg_shape_type *t = sg_shape_type_of(type);
    const sg_shape_key *e;
    for (e = t ? t->keys : NULL; e && e->key; e++)
        if (strcmp(e->key, key) == 0)
            return 1;
    return 0;
}

const sg_shape_ops *sg_shape_ops_of(int type)
{
    const sg_shape_type *t = sg_shape_type_of(type);
    return t ? t->ops : NULL;
}

/* The types the methods trace with kernels of their own: they have no
 * ops, and design_zmx.c reads their blocks itself. */
static const sg_shape_key no_keys[] = {{NULL, 0, 0, 0}};
const sg_shape_type sg_shape_standard_type = {
    .type = SG_SURF_STANDARD, .name = "standard", .keys = no_keys};

/* a_k on r^(2k+2) is in lens units^-(2k+1). */
static const sg_shape_key even_keys[] = {{"asphere", 0, -1, -2}, {NULL, 0, 0, 0}};
const sg_shape_type sg_shape_even_type = {
    .type = SG_SURF_EVENASPH, .name = "even asphere", .keys = even_keys};

/* A coordinate break is its before change (Zemax's Decenter X ... Order)
 * and a thickness; no optics, no after change. */
static const sg_shape_key coordbrk_keys[] = {{"type", 0, 0, 0},      {"comment", 0, 0, 0},
                                             {"thickness", 0, 0, 0}, {"before.", 0, 0, 0},
                                             {"tce", 0, 0, 0},       {NULL, 0, 0, 0}};
const sg_shape_type sg_shape_coordbrk_type = {
    .type = SG_SURF_COORDBRK, .name = "coordinate break", .keys = coordbrk_keys, .only = 1};

double sg_shape_sag(const sg_shape *s, double x, double y)
{
    double z, g[2], h;
    return s->ops->sag_d(s, x, y, &z, g, &h) ? z : NAN;
}

static double flat_inf(double r)
{
    return r == 0.0 || isinf(r) ? INFINITY : r;
}

int sg_shape_prepare(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d)
{
    int k;
    memset(s, 0, sizeof *s);
    s->ops = sg_shape_ops_of(f->type);
    s->type = f->type;
    s->src = f;
    s->R = flat_inf(f->radius);
    s->k1 = 1.0 + f->conic;
    s->Rx = flat_inf(f->radius_x);
    s->kx1 = 1.0 + f->conic_x;
    s->norm = f->norm_radius;
    if (sg_shape_reads(f->type, "asphere"))
        for (k = 0; k < SG_NASPH; k++) {
            s->a[k] = f->asph[k];
            if (f->asph[k] != 0.0)
                s->na = k + 1;
        }
    if (sg_shape_reads(f->type, "odd"))
        for (k = 0; k < SG_NODD; k++) {
            s->odd[k] = f->odd[k];
            if (f->odd[k] != 0.0)
                s->nodd = k + 1;
        }
    return s->ops && s->ops->prepare ? s->ops->prepare(f, s, isurf, d) : SG_OK;
}

/* ------------------------------------------------------------------------
 * The rotational part: conic, even terms on r^2 ..., odd terms on r^1 ...
 * ------------------------------------------------------------------------ */

/* sg_rot_d, written once with its lane form (shape_vd.h's sv_rot_d). */
#define SG_TMPL 1 /* SG_TMPL_D */
#include "shape_tmpl_on.h"
#include "shape_rot_k.h"
#include "shape_tmpl_off.h"

int sg_rot_dd(const sg_shape *s, dd r2, dd *z, dd *w, double *ez, double *ew)
{
    dd zz = dd_from(0.0), ww = dd_from(0.0), rk = dd_from(1.0);
    double mz = 0.0, mw = 0.0, r2d = r2.hi;
    int k, n = s->na + s->nodd;
    *ez = 0.0;
    *ew = 0.0;
    if (isfinite(s->R)) {
        dd R = dd_from(s->R), q, sq;
        double cond;
        q = dd_sub(dd_sqr(R), dd_mul_d(r2, s->k1));
        if (q.hi < 0.0)
            return 0;
        sq = dd_sqrt(q);
        if (s->R < 0)
            sq = dd_neg(sq);
        zz = dd_div(r2, dd_add(R, sq));
        ww = dd_div(dd_from(1.0), sq);
        /* q = R^2 - k1 r^2 may cancel: its rounding, relative to q, grows
         * by (R^2 + |k1| r^2) / q, and sqrt halves it. */
        cond = 1.0 + (s->R * s->R + fabs(s->k1) * r2d) / q.hi;
        *ez = 16.0 * DD_U * fabs(zz.hi) * cond;
        *ew = 16.0 * DD_U * fabs(ww.hi) * cond;
    }
    for (k = 0; k < s->na; k++) {
        dd t = dd_mul_d(rk, s->a[k]);
        zz = dd_add(zz, dd_mul(t, r2));
        ww = dd_add(ww, dd_mul_d(t, 2.0 * k + 2.0));
        mz += fabs(t.hi * r2d);
        mw += fabs(t.hi) * (2.0 * k + 2.0);
        rk = dd_mul(rk, r2);
    }
    if (s->nodd) {
        dd r = dd_sqrt(r2), rp = dd_from(1.0), rm = dd_from(0.0);
        if (r2d > 0.0)
            rm = dd_div(dd_from(1.0), r2); /* 1 / r^2 */
        for (k = 0; k < s->nodd; k++) {
            dd t;
            rp = dd_mul(rp, r);
            t = dd_mul_d(rp, s->odd[k]);
            zz = dd_add(zz, t);
            mz += fabs(t.hi);
            if (r2d > 0.0) {
                dd tw = dd_mul(dd_mul_d(t, k + 1.0), rm);
                ww = dd_add(ww, tw);
                mw += fabs(tw.hi);
            } else if (k == 1) {
                ww = dd_add(ww, dd_from(2.0 * s->odd[k]));
                mw += fabs(2.0 * s->odd[k]);
            }
        }
    }
    /* Each term's product chain and the sum: a few roundings per term. */
    *ez += (16.0 + 6.0 * n) * DD_U * mz;
    *ew += (16.0 + 6.0 * n) * DD_U * mw;
    *z = zz;
    *w = ww;
    return 1;
}

int sg_rot_mp(const sg_shape *s, mpfr_srcptr r2, mpfr_ptr z, mpfr_ptr w, mpfr_t *t)
{
    int k;
    mpfr_set_zero(z, 1);
    mpfr_set_zero(w, 1);
    if (isfinite(s->R)) {
        mpfr_set_d(t[0], s->R, MPFR_RNDN);
        mpfr_sqr(t[1], t[0], MPFR_RNDN);
        mpfr_set_d(t[2], s->src->conic, MPFR_RNDN);
        mpfr_add_ui(t[2], t[2], 1, MPFR_RNDN);
        mpfr_mul(t[2], t[2], r2, MPFR_RNDN);
        mpfr_sub(t[1], t[1], t[2], MPFR_RNDN);
        if (mpfr_sgn(t[1]) < 0)
            return 0;
        mpfr_sqrt(t[1], t[1], MPFR_RNDN);
        if (s->R < 0)
            mpfr_neg(t[1], t[1], MPFR_RNDN);
        mpfr_ui_div(w, 1, t[1], MPFR_RNDN);
        mpfr_add(t[1], t[1], t[0], MPFR_RNDN);
        mpfr_div(z, r2, t[1], MPFR_RNDN);
    }
    mpfr_set_ui(t[0], 1, MPFR_RNDN); /* r^(2k) */
    for (k = 0; k < s->na; k++) {
        mpfr_mul_d(t[1], t[0], s->a[k], MPFR_RNDN);
        mpfr_mul_ui(t[2], t[1], (unsigned long)(2 * k + 2), MPFR_RNDN);
        mpfr_add(w, w, t[2], MPFR_RNDN);
        mpfr_mul(t[1], t[1], r2, MPFR_RNDN);
        mpfr_add(z, z, t[1], MPFR_RNDN);
        mpfr_mul(t[0], t[0], r2, MPFR_RNDN);
    }
    if (s->nodd) {
        mpfr_sqrt(t[3], r2, MPFR_RNDN);
        mpfr_set_ui(t[0], 1, MPFR_RNDN); /* r^i */
        for (k = 0; k < s->nodd; k++) {
            mpfr_mul(t[0], t[0], t[3], MPFR_RNDN);
            mpfr_mul_d(t[1], t[0], s->odd[k], MPFR_RNDN);
            mpfr_add(z, z, t[1], MPFR_RNDN);
            if (!mpfr_zero_p(r2)) {
                mpfr_mul_ui(t[1], t[1], (unsigned long)(k + 1), MPFR_RNDN);
                mpfr_div(t[1], t[1], r2, MPFR_RNDN);
                mpfr_add(w, w, t[1], MPFR_RNDN);
            } else if (k == 1) {
                mpfr_set_d(t[1], s->odd[k], MPFR_RNDN);
                mpfr_mul_2ui(t[1], t[1], 1, MPFR_RNDN);
                mpfr_add(w, w, t[1], MPFR_RNDN);
            }
        }
    }
    return 1;
}

/* ------------------------------------------------------------------------
 * Polynomials in u = x / norm, v = y / norm.
 * ------------------------------------------------------------------------ */

void sg_p2_d(const sg_shape *s, double x, double y, double *z, double g[2], double *h)
{
    double U[SG_P2_DEG + 1], V[SG_P2_DEG + 1], zz = 0.0, gx = 0.0, gy = 0.0, hh = 0.0;
    double u = x / s->norm, v = y / s->norm;
    int a, b, n = s->deg;
    U[0] = V[0] = 1.0;
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
                hh += a * (a - 1) * m * fabs(U[a - 2] * V[b]);
            if (a && b)
                hh += 2.0 * a * b * m * fabs(U[a - 1] * V[b - 1]);
            if (b > 1)
                hh += b * (b - 1) * m * fabs(U[a] * V[b - 2]);
        }
    *z = zz;
    g[0] = gx / s->norm;
    g[1] = gy / s->norm;
    *h = hh / (s->norm * s->norm);
}

void sg_p2_dd(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg)
{
    dd U[SG_P2_DEG + 1], V[SG_P2_DEG + 1], zz = dd_from(0.0), gx = dd_from(0.0),
                                             gy = dd_from(0.0);
    dd u = dd_div_d(x, s->norm), v = dd_div_d(y, s->norm);
    double mz = 0.0, mg = 0.0;
    int a, b, n = s->deg;
    U[0] = V[0] = dd_from(1.0);
    for (a = 1; a <= n; a++) {
        U[a] = dd_mul(U[a - 1], u);
        V[a] = dd_mul(V[a - 1], v);
    }
    for (a = 0; a <= n; a++)
        for (b = 0; a + b <= n; b++) {
            int at = SG_P2_AT(a, b);
            double m = s->cm[at];
            dd c = s->c[at];
            if (m == 0.0)
                continue;
            zz = dd_add(zz, dd_mul(c, dd_mul(U[a], V[b])));
            mz += m * fabs(U[a].hi * V[b].hi);
            if (a) {
                gx = dd_add(gx, dd_mul(dd_mul_d(c, (double)a), dd_mul(U[a - 1], V[b])));
                mg += a * m * fabs(U[a - 1].hi * V[b].hi);
            }
            if (b) {
                gy = dd_add(gy, dd_mul(dd_mul_d(c, (double)b), dd_mul(U[a], V[b - 1])));
                mg += b * m * fabs(U[a].hi * V[b - 1].hi);
            }
        }
    /* Each coefficient is a sum of nz terms rounded to double-double; each
     * monomial a product chain of up to 2 deg + 2 roundings; then a sum of
     * up to SG_P2_N terms.  The magnitudes use cm, so cancellation between
     * a coefficient's terms is covered. */
    {
        double k = (double)(s->nz + 4 * n + SG_P2_N + 16) * DD_U;
        *ez = k * mz;
        *eg = k * mg / s->norm + 4.0 * DD_U * (fabs(gx.hi) + fabs(gy.hi)) / s->norm;
    }
    *z = zz;
    g[0] = dd_div_d(gx, s->norm);
    g[1] = dd_div_d(gy, s->norm);
}

void sg_shape_mp_coefs(const sg_shape *s, mpfr_t *mc, mpfr_prec_t prec)
{
    int j;
    for (j = 0; j < SG_SHAPE_MPC; j++) {
        mpfr_init2(mc[j], prec);
        mpfr_set_zero(mc[j], 1);
    }
    if (s->ops && s->ops->mp_coefs)
        s->ops->mp_coefs(s, mc);
}

/* Adds coefficient A to u^i v^j's, at index at. */
void sg_p2_add(sg_shape *s, int at, dd A, double mag)
{
    int deg = 0;
    while ((deg + 1) * (deg + 2) / 2 <= at)
        deg++;
    s->c[at] = dd_add(s->c[at], A);
    s->cm[at] += mag;
    if (deg > s->deg)
        s->deg = deg;
}

/* The normalization radius and the number of terms in use, checked. */
int sg_p2_terms(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d)
{
    int k, nt = 0;
    if (!(s->norm > 0.0) || !isfinite(s->norm))
        return sg_diag_set(d, SG_ERANGE,
                           "surface %d: normalization radius %g must be finite and positive",
                           isurf, s->norm);
    for (k = 0; k < SG_NTERMS; k++)
        if (f->terms[k] != 0.0)
            nt = k + 1;
    s->nz = nt;
    return SG_OK;
}

void sg_shape_mp_clear(mpfr_t *mc)
{
    int j;
    for (j = 0; j < SG_SHAPE_MPC; j++)
        mpfr_clear(mc[j]);
}

void sg_p2_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
              mpfr_ptr gx, mpfr_ptr gy, mpfr_t *t)
{
    mpfr_t *U = mc + SG_P2_N, *V = mc + SG_P2_N + SG_P2_DEG + 1;
    int a, b, n = s->deg;
    mpfr_set_ui(U[0], 1, MPFR_RNDN);
    mpfr_set_ui(V[0], 1, MPFR_RNDN);
    mpfr_div_d(t[0], x, s->norm, MPFR_RNDN);
    mpfr_div_d(t[1], y, s->norm, MPFR_RNDN);
    for (a = 1; a <= n; a++) {
        mpfr_mul(U[a], U[a - 1], t[0], MPFR_RNDN);
        mpfr_mul(V[a], V[a - 1], t[1], MPFR_RNDN);
    }
    mpfr_set_zero(z, 1);
    mpfr_set_zero(gx, 1);
    mpfr_set_zero(gy, 1);
    for (a = 0; a <= n; a++)
        for (b = 0; a + b <= n; b++) {
            int at = SG_P2_AT(a, b);
            if (mpfr_zero_p(mc[at]))
                continue;
            mpfr_mul(t[2], U[a], V[b], MPFR_RNDN);
            mpfr_mul(t[2], t[2], mc[at], MPFR_RNDN);
            mpfr_add(z, z, t[2], MPFR_RNDN);
            if (a) {
                mpfr_mul(t[2], U[a - 1], V[b], MPFR_RNDN);
                mpfr_mul(t[2], t[2], mc[at], MPFR_RNDN);
                mpfr_mul_ui(t[2], t[2], (unsigned long)a, MPFR_RNDN);
                mpfr_add(gx, gx, t[2], MPFR_RNDN);
            }
            if (b) {
                mpfr_mul(t[2], U[a], V[b - 1], MPFR_RNDN);
                mpfr_mul(t[2], t[2], mc[at], MPFR_RNDN);
                mpfr_mul_ui(t[2], t[2], (unsigned long)b, MPFR_RNDN);
                mpfr_add(gy, gy, t[2], MPFR_RNDN);
            }
        }
    mpfr_div_d(gx, gx, s->norm, MPFR_RNDN);
    mpfr_div_d(gy, gy, s->norm, MPFR_RNDN);
}

/* ------------------------------------------------------------------------
 * A rotational part plus a polynomial in x and y (Zernike and XY shapes).
 * ------------------------------------------------------------------------ */

/* The conic and the polynomial add, and so do their derivatives.  The
 * polynomial is centred on (px, py), the conic on the vertex; a shift
 * leaves the polynomial's derivatives as they are at the shifted point. */
int sg_rot_p2_d(const sg_shape *s, double x, double y, double *z, double g[2], double *h)
{
    double r2 = x * x + y * y, w, dw, zp, gp[2], hp;
    if (!sg_rot_d(s, r2, z, &w, &dw))
        return 0;
    sg_p2_d(s, x - s->px, y - s->py, &zp, gp, &hp);
    *z += zp;
    g[0] = w * x + gp[0];
    g[1] = w * y + gp[1];
    *h = 1.5 * (fabs(w) + 4.0 * dw * r2 + hp);
    return 1;
}

int sg_rot_p2_dd(const sg_shape *s, dd x, dd y, dd *z, dd g[2], double *ez, double *eg)
{
    dd r2 = dd_add(dd_sqr(x), dd_sqr(y)), w, zp, gp[2];
    double ew, ezp, egp, m = fmax(fabs(x.hi), fabs(y.hi));
    if (!sg_rot_dd(s, r2, z, &w, ez, &ew))
        return 0;
    *ez += 4.0 * DD_U * fabs(w.hi) * r2.hi;
    if (s->px != 0.0 || s->py != 0.0) {
        /* The shifted point is rounded by at most ex, ey (one sum each,
         * bounded by its operands since they may cancel): the polynomial
         * then moves by its gradient times that, and its gradient by the
         * second derivatives' bound times that. */
        dd xs = dd_add_d(x, -s->px), ys = dd_add_d(y, -s->py);
        double ex = 2.0 * DD_U * (fabs(x.hi) + fabs(s->px)),
               ey = 2.0 * DD_U * (fabs(y.hi) + fabs(s->py)), zd, gd[2], hd;
        sg_p2_dd(s, xs, ys, &zp, gp, &ezp, &egp);
        sg_p2_d(s, xs.hi, ys.hi, &zd, gd, &hd);
        ezp += 2.0 * (fabs(gp[0].hi) * ex + fabs(gp[1].hi) * ey);
        egp += 2.0 * hd * fmax(ex, ey);
    } else {
        sg_p2_dd(s, x, y, &zp, gp, &ezp, &egp);
    }
    *z = dd_add(*z, zp);
    g[0] = dd_add(dd_mul(w, x), gp[0]);
    g[1] = dd_add(dd_mul(w, y), gp[1]);
    *ez += ezp + 2.0 * DD_U * (fabs(z->hi) + fabs(zp.hi));
    *eg = (ew + 8.0 * DD_U * fabs(w.hi)) * m + egp +
          2.0 * DD_U * (fabs(g[0].hi) + fabs(g[1].hi) + fabs(gp[0].hi) + fabs(gp[1].hi));
    return 1;
}

int sg_rot_p2_mp(const sg_shape *s, mpfr_t *mc, mpfr_srcptr x, mpfr_srcptr y, mpfr_ptr z,
                 mpfr_ptr gx, mpfr_ptr gy, mpfr_t *t)
{
    mpfr_sqr(t[8], x, MPFR_RNDN);
    mpfr_sqr(t[9], y, MPFR_RNDN);
    mpfr_add(t[8], t[8], t[9], MPFR_RNDN);
    if (!sg_rot_mp(s, t[8], z, t[10], t))
        return 0;
    /* r2 is used: t[8] and t[9] take the polynomial's shifted point. */
    mpfr_sub_d(t[8], x, s->px, MPFR_RNDN);
    mpfr_sub_d(t[9], y, s->py, MPFR_RNDN);
    sg_p2_mp(s, mc, t[8], t[9], t[4], t[5], t[6], t);
    mpfr_add(z, z, t[4], MPFR_RNDN);
    mpfr_mul(gx, t[10], x, MPFR_RNDN);
    mpfr_add(gx, gx, t[5], MPFR_RNDN);
    mpfr_mul(gy, t[10], y, MPFR_RNDN);
    mpfr_add(gy, gy, t[6], MPFR_RNDN);
    return 1;
}
