/*
 * trace_mpfr.c - the reference method: every operation in MPFR.
 *
 * It follows the same geometry as the precise method (vertex frames,
 * tangent-plane start, the vertex-sheet root, a Newton polish), because at
 * 256 bits the formulas' own rounding is some 60 digits below anything a
 * double can show.  Glass indices, the paraxial pupil, field tangents and
 * ray aiming are all computed at the same precision, so the reference
 * includes them.  All MPFR variables live in the context and are reused;
 * nothing is allocated per ray.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trace_int.h"

enum { NT = 48, NA = 16 };

typedef struct msurf {
    int xf;           /* the transfer into it turns or moves the frame */
    int k1one;        /* k1 is exactly 1 (a sphere): a product by it is skipped,
                       * which gives the product's bits */
    double bmax;      /* its largest offset, which the point's bound must cover */
    mpfr_t A[3][3], b[3]; /* that transfer (frame.c), only where xf */
    mpfr_t R, k1, T, mu;
    mpfr_t mu2; /* mu squared, as the bend squares it */
    mpfr_t nb; /* |index| before the surface */
    mpfr_t a[SG_NASPH];
    mpfr_t *mc; /* SHAPE_GEN: its coefficients (SG_SHAPE_MPC), else NULL */
} msurf;

typedef struct mvec {
    mpfr_t x, y, z;
} mvec;

struct sg_mpfr_ctx {
    mpfr_prec_t prec;
    int n;
    unsigned long nrescue; /* roots found by sg_mpfr_rescue_root */
    msurf *s;
    /* launch constants */
    mpfr_t T0, enp, epr, stop_r, fx, fy, pimg_slope, pi;
    /* Object-space telecentric: the marginal slope tan(asin(NA / n0)),
     * as in the precise launch (sg_launch). */
    int tele;
    mpfr_t tslope;
    /* ray state and scratch */
    mvec P, D, G, obj, dir, sv_P, sv_D;
    mpfr_t q[2], t[NT];
    mpfr_t path;
    /* The optical path so far; at infinity, the start plane (the primary
     * chief ray's point on surface 1 dotted with the direction) of the
     * field (plane_hx, plane_hy), and c1dot, that product for the ray
     * last traced through surface 1. */
    mpfr_t opl, plane, c1dot;
    int plane_ok, plane_busy;
    double plane_hx, plane_hy;
    /* aiming: the field values before m_osp, the target, the last good Q,
     * the step, and the paraxial Q the continuation moves with */
    mpfr_t fv[2], tgt[2], qb[2], dq[2], qo[2];
    mpfr_t a[NA]; /* aiming's scratch: the landings reuse every t[] */
    int fdeg;
    /* The limbs of every surface's R, k1, T, mu, mu2, nb and a[] (MSV a
     * surface), one allocation (sg_mp_block_new). */
    void *arena;
};

enum { MSV = 6 + SG_NASPH };

/* Whether |a| = |b| for two regular numbers of one precision, from their
 * exponents and limbs (MPFR keeps the bits past the precision zero, so
 * equal values have equal limbs): 1 or 0; -1 when either is zero, NaN or
 * infinite or the precisions differ, for the caller to ask MPFR. */
static int same_limbs(mpfr_srcptr a, mpfr_srcptr b)
{
    size_t nl;
    if (!mpfr_regular_p(a) || !mpfr_regular_p(b) || mpfr_get_prec(a) != mpfr_get_prec(b))
        return -1;
    nl = ((size_t)mpfr_get_prec(a) + (size_t)mp_bits_per_limb - 1) / (size_t)mp_bits_per_limb;
    return a->_mpfr_exp == b->_mpfr_exp &&
           memcmp(a->_mpfr_d, b->_mpfr_d, nl * sizeof(mp_limb_t)) == 0;
}

static void mvec_init(mvec *v, mpfr_prec_t p)
{
    mpfr_inits2(p, v->x, v->y, v->z, (mpfr_ptr)0);
}

static void mvec_clear(mvec *v)
{
    mpfr_clears(v->x, v->y, v->z, (mpfr_ptr)0);
}

static void mvec_set(mvec *a, const mvec *b)
{
    mpfr_set(a->x, b->x, MPFR_RNDN);
    mpfr_set(a->y, b->y, MPFR_RNDN);
    mpfr_set(a->z, b->z, MPFR_RNDN);
}

static void dot(mpfr_t out, const mvec *a, const mvec *b, mpfr_t tmp)
{
    mpfr_mul(out, a->x, b->x, MPFR_RNDN);
    mpfr_mul(tmp, a->y, b->y, MPFR_RNDN);
    mpfr_add(out, out, tmp, MPFR_RNDN);
    mpfr_mul(tmp, a->z, b->z, MPFR_RNDN);
    mpfr_add(out, out, tmp, MPFR_RNDN);
}

/* v = v + s * d */
static void axpy(mvec *v, const mpfr_t s, const mvec *d, mpfr_t tmp)
{
    mpfr_mul(tmp, s, d->x, MPFR_RNDN);
    mpfr_add(v->x, v->x, tmp, MPFR_RNDN);
    mpfr_mul(tmp, s, d->y, MPFR_RNDN);
    mpfr_add(v->y, v->y, tmp, MPFR_RNDN);
    mpfr_mul(tmp, s, d->z, MPFR_RNDN);
    mpfr_add(v->z, v->z, tmp, MPFR_RNDN);
}

static void normalize(mvec *v, mpfr_t tmp, mpfr_t len)
{
    dot(len, v, v, tmp);
    mpfr_sqrt(len, len, MPFR_RNDN);
    mpfr_div(v->x, v->x, len, MPFR_RNDN);
    mpfr_div(v->y, v->y, len, MPFR_RNDN);
    mpfr_div(v->z, v->z, len, MPFR_RNDN);
}

void sg_mpfr_free(sg_mpfr_ctx *m)
{
    int i, k;
    if (!m)
        return;
    if (m->s) {
        for (i = 0; i < m->n; i++) {
            if (m->s[i].xf) {
                int j, k2;
                for (j = 0; j < 3; j++) {
                    for (k2 = 0; k2 < 3; k2++)
                        mpfr_clear(m->s[i].A[j][k2]);
                    mpfr_clear(m->s[i].b[j]);
                }
            }
            if (m->s[i].mc) {
                sg_shape_mp_clear(m->s[i].mc);
                free(m->s[i].mc);
            }
        }
        free(m->s);
    }
    free(m->arena);
    mpfr_clears(m->T0, m->enp, m->epr, m->stop_r, m->fx, m->fy, m->pimg_slope, m->pi, m->tslope,
                m->q[0], m->q[1], m->path, m->opl, m->plane, m->c1dot, (mpfr_ptr)0);
    for (k = 0; k < 2; k++)
        mpfr_clears(m->fv[k], m->tgt[k], m->qb[k], m->dq[k], m->qo[k], (mpfr_ptr)0);
    for (k = 0; k < NA; k++)
        mpfr_clear(m->a[k]);
    for (k = 0; k < NT; k++)
        mpfr_clear(m->t[k]);
    mvec_clear(&m->P);
    mvec_clear(&m->D);
    mvec_clear(&m->G);
    mvec_clear(&m->obj);
    mvec_clear(&m->dir);
    mvec_clear(&m->sv_P);
    mvec_clear(&m->sv_D);
    free(m);
}

/* A context of n surfaces at precision prec, every variable initialized;
 * NULL when out of memory. */
static sg_mpfr_ctx *ctx_new(mpfr_prec_t prec, int n)
{
    sg_mpfr_ctx *m = calloc(1, sizeof *m);
    /* Not zeroed whole: a surface's transfer is set up only where it has
     * one (xf), and zeroing some 800 bytes a surface for nothing costs a
     * long design more than the rest of this function. */
    msurf *s = malloc((size_t)(n > 0 ? n : 1) * sizeof *s);
    size_t sz = sg_mp_limb_bytes(prec);
    char *ar = malloc((size_t)n * MSV * sz + 1);
    int i, k;
    if (!m || !s || !ar) {
        free(m);
        free(s);
        free(ar);
        return NULL;
    }
    m->arena = ar;
    m->prec = prec;
    m->n = n;
    m->s = s;
    mpfr_inits2(prec, m->T0, m->enp, m->epr, m->stop_r, m->fx, m->fy, m->pimg_slope, m->pi, m->tslope,
                m->q[0], m->q[1], m->path, m->opl, m->plane, m->c1dot, (mpfr_ptr)0);
    mpfr_set_zero(m->opl, 1);
    mpfr_set_zero(m->plane, 1);
    mpfr_set_zero(m->c1dot, 1);
    for (k = 0; k < 2; k++)
        mpfr_inits2(prec, m->fv[k], m->tgt[k], m->qb[k], m->dq[k], m->qo[k], (mpfr_ptr)0);
    for (k = 0; k < NA; k++)
        mpfr_init2(m->a[k], prec);
    for (k = 0; k < NT; k++)
        mpfr_init2(m->t[k], prec);
    mvec_init(&m->P, prec);
    mvec_init(&m->D, prec);
    mvec_init(&m->G, prec);
    mvec_init(&m->obj, prec);
    mvec_init(&m->dir, prec);
    mvec_init(&m->sv_P, prec);
    mvec_init(&m->sv_D, prec);
    for (i = 0; i < n; i++) {
        char *b = ar + (size_t)i * MSV * sz;
        s[i].xf = 0;
        s[i].k1one = 0;
        s[i].bmax = 0.0;
        s[i].mc = NULL;
        sg_mp_place(s[i].R, b, prec);
        sg_mp_place(s[i].k1, b + sz, prec);
        sg_mp_place(s[i].T, b + 2 * sz, prec);
        sg_mp_place(s[i].mu, b + 3 * sz, prec);
        sg_mp_place(s[i].nb, b + 4 * sz, prec);
        mpfr_set_ui(s[i].nb, 1, MPFR_RNDN);
        sg_mp_place(s[i].mu2, b + 5 * sz, prec);
        for (k = 0; k < SG_NASPH; k++)
            sg_mp_place(s[i].a[k], b + (size_t)(6 + k) * sz, prec);
    }
    return m;
}

/* ------------------------------------------------------------------------
 * Surfaces.
 * ------------------------------------------------------------------------ */

/* sag(r2) and w = sag'(r)/r at r2 into sag and w; returns 0 outside the
 * conic's domain. */
static int sag_w(sg_mpfr_ctx *m, const sg_sprep *sp, const msurf *s, const mpfr_t r2,
                 mpfr_t sag, mpfr_t w)
{
    mpfr_t *t = m->t + 24;
    int k;
    mpfr_set_zero(sag, 1);
    mpfr_set_zero(w, 1);
    if (isfinite(sp->R)) {
        mpfr_sqr(t[0], s->R, MPFR_RNDN);
        mpfr_mul(t[1], s->k1, r2, MPFR_RNDN);
        mpfr_sub(t[0], t[0], t[1], MPFR_RNDN);
        if (mpfr_sgn(t[0]) < 0)
            return 0;
        mpfr_sqrt(t[0], t[0], MPFR_RNDN);
        if (sp->R < 0)
            mpfr_neg(t[0], t[0], MPFR_RNDN);
        mpfr_add(t[1], s->R, t[0], MPFR_RNDN);
        mpfr_div(sag, r2, t[1], MPFR_RNDN);
        mpfr_ui_div(w, 1, t[0], MPFR_RNDN);
    }
    if (sp->nasph) {
        mpfr_set_zero(t[2], 1);
        mpfr_set_zero(t[3], 1);
        for (k = sp->nasph - 1; k >= 0; k--) {
            mpfr_mul(t[2], t[2], r2, MPFR_RNDN);
            mpfr_add(t[2], t[2], s->a[k], MPFR_RNDN);
            mpfr_mul(t[3], t[3], r2, MPFR_RNDN);
            mpfr_mul_ui(t[1], s->a[k], (unsigned long)(2 * (k + 1)), MPFR_RNDN);
            mpfr_add(t[3], t[3], t[1], MPFR_RNDN);
        }
        mpfr_mul(t[2], t[2], r2, MPFR_RNDN);
        mpfr_add(sag, sag, t[2], MPFR_RNDN);
        mpfr_add(w, w, t[3], MPFR_RNDN);
    }
    return 1;
}

/* F at P and dF/ds along D; returns 0 outside the domain. */
static int eval_F(sg_mpfr_ctx *m, const sg_sprep *sp, const msurf *s, mpfr_t F, mpfr_t Fp)
{
    mpfr_t *t = m->t;
    if (sp->shape == SHAPE_PLANE) {
        mpfr_set(F, m->P.z, MPFR_RNDN);
        mpfr_set(Fp, m->D.z, MPFR_RNDN);
        return 1;
    }
    if (sp->shape == SHAPE_CONIC) {
        /* x^2 + y^2 + k1 z^2 - 2 R z and its derivative */
        mpfr_sqr(F, m->P.x, MPFR_RNDN);
        mpfr_sqr(t[0], m->P.y, MPFR_RNDN);
        mpfr_add(F, F, t[0], MPFR_RNDN);
        mpfr_sqr(t[0], m->P.z, MPFR_RNDN);
        if (!s->k1one)
            mpfr_mul(t[0], t[0], s->k1, MPFR_RNDN);
        mpfr_add(F, F, t[0], MPFR_RNDN);
        mpfr_mul(t[0], m->P.z, s->R, MPFR_RNDN);
        mpfr_mul_2ui(t[0], t[0], 1, MPFR_RNDN);
        mpfr_sub(F, F, t[0], MPFR_RNDN);
        mpfr_mul(Fp, m->P.x, m->D.x, MPFR_RNDN);
        mpfr_mul(t[0], m->P.y, m->D.y, MPFR_RNDN);
        mpfr_add(Fp, Fp, t[0], MPFR_RNDN);
        if (s->k1one) {
            mpfr_sub(t[0], m->P.z, s->R, MPFR_RNDN);
        } else {
            mpfr_mul(t[0], s->k1, m->P.z, MPFR_RNDN);
            mpfr_sub(t[0], t[0], s->R, MPFR_RNDN);
        }
        mpfr_mul(t[0], t[0], m->D.z, MPFR_RNDN);
        mpfr_add(Fp, Fp, t[0], MPFR_RNDN);
        mpfr_mul_2ui(Fp, Fp, 1, MPFR_RNDN);
        return 1;
    }
    if (sp->shape == SHAPE_GEN) {
        /* z - f(x, y), and F' = D_z - f_x D_x - f_y D_y. */
        if (!sp->shp->ops->sag_mp(sp->shp, s->mc, m->P.x, m->P.y, t[1], t[2], t[3], m->t + 28))
            return 0;
        mpfr_sub(F, m->P.z, t[1], MPFR_RNDN);
        mpfr_mul(Fp, t[2], m->D.x, MPFR_RNDN);
        mpfr_mul(t[0], t[3], m->D.y, MPFR_RNDN);
        mpfr_add(Fp, Fp, t[0], MPFR_RNDN);
        mpfr_sub(Fp, m->D.z, Fp, MPFR_RNDN);
        return 1;
    }
    mpfr_sqr(t[1], m->P.x, MPFR_RNDN);
    mpfr_sqr(t[0], m->P.y, MPFR_RNDN);
    mpfr_add(t[1], t[1], t[0], MPFR_RNDN);
    if (!sag_w(m, sp, s, t[1], t[2], t[3]))
        return 0;
    mpfr_sub(F, m->P.z, t[2], MPFR_RNDN);
    mpfr_mul(Fp, m->P.x, m->D.x, MPFR_RNDN);
    mpfr_mul(t[0], m->P.y, m->D.y, MPFR_RNDN);
    mpfr_add(Fp, Fp, t[0], MPFR_RNDN);
    mpfr_mul(Fp, Fp, t[3], MPFR_RNDN);
    mpfr_sub(Fp, m->D.z, Fp, MPFR_RNDN);
    return 1;
}

/* Whether k1 (P_z + sv D_z) / R, rounded as the vertex-sheet test rounds
 * it, is certainly at most 1, from the exponents alone (x lies in
 * [2^(e-1), 2^e)): the sum is at most 2^(max(e_sv + e_Dz, e_Pz) + 1), the
 * product by k1 at most 2^e_k1 times that, and |R| at least 2^(e_R - 1),
 * each bound holding after rounding too; one more factor of 2 to spare.
 * The test then skips its MPFR products, with the same outcome. */
/* An exponent e with |x| < 2^e for a finite x: its own, or for zero (and
 * below 2^-2^40) -2^40, kept within +-2^40 so that sums cannot overflow
 * whatever exponent range the caller set (a larger e is still a bound). */
static long exp_up(mpfr_srcptr x)
{
    const long lim = 1L << 40;
    long e;
    if (!mpfr_regular_p(x))
        return -lim;
    e = (long)mpfr_get_exp(x);
    return e < -lim ? -lim : e > lim ? lim : e;
}

static int sheet_below(const sg_mpfr_ctx *m, const mpfr_t sv, const msurf *s, double R)
{
    long a, b, e, eR;
    (void)R;
    if (!mpfr_number_p(sv) || !mpfr_number_p(m->D.z) || !mpfr_number_p(m->P.z) ||
        !mpfr_number_p(s->k1) || !mpfr_regular_p(s->R))
        return 0;
    if (mpfr_zero_p(s->k1))
        return 1;
    a = exp_up(sv) + exp_up(m->D.z);
    b = exp_up(m->P.z);
    e = (a > b ? a : b) + 1 + exp_up(s->k1);
    eR = (long)mpfr_get_exp(s->R);
    return eR > -(1L << 40) && e + 2 <= eR - 1;
}

/* Moves P along D onto the surface sp (s in MPFR), from P on (or near)
 * its tangent plane.  The step is added to m->path. */
static int intersect_s(sg_mpfr_ctx *m, const sg_sprep *sp, const msurf *s, int max_iter)
{
    mpfr_t *t = m->t;
    mpfr_ptr sv = t[4], F = t[5], Fp = t[6], A = t[7], b = t[8], C = t[9];
    int it, conv = 0, below;
    mpfr_exp_t es_prev = 0;
    double growth = 1.0, dstep = 0.0;
    mpfr_set_zero(sv, 1);
    if (sp->shape == SHAPE_PLANE) {
        if (mpfr_zero_p(m->P.z))
            return SG_OK;
        if (mpfr_zero_p(m->D.z))
            return SG_EMISS;
        mpfr_div(sv, m->P.z, m->D.z, MPFR_RNDN);
        mpfr_neg(sv, sv, MPFR_RNDN);
    } else {
        /* Base conic: A s^2 + 2 b s + C = 0 in the R form. */
        mpfr_sqr(A, m->D.x, MPFR_RNDN);
        mpfr_sqr(t[0], m->D.y, MPFR_RNDN);
        mpfr_add(A, A, t[0], MPFR_RNDN);
        mpfr_sqr(t[0], m->D.z, MPFR_RNDN);
        if (!s->k1one)
            mpfr_mul(t[0], t[0], s->k1, MPFR_RNDN);
        mpfr_add(A, A, t[0], MPFR_RNDN);
        if (isfinite(sp->R)) {
            eval_F(m, &(sg_sprep){.shape = SHAPE_CONIC, .R = sp->R, .k1 = sp->k1}, s, C, b);
            mpfr_div_2ui(b, b, 1, MPFR_RNDN);
            mpfr_sqr(t[0], b, MPFR_RNDN);
            mpfr_mul(t[1], A, C, MPFR_RNDN);
            mpfr_sub(t[0], t[0], t[1], MPFR_RNDN);
            if (mpfr_sgn(t[0]) < 0) {
                if (sp->shape == SHAPE_CONIC)
                    return SG_EMISS;
                mpfr_set_zero(sv, 1);
            } else {
                mpfr_sqrt(t[0], t[0], MPFR_RNDN);
                if (mpfr_sgn(b) < 0)
                    mpfr_neg(t[0], t[0], MPFR_RNDN);
                mpfr_add(t[0], t[0], b, MPFR_RNDN);
                mpfr_neg(t[0], t[0], MPFR_RNDN); /* q */
                /* The root C/q lies on the vertex sheet unless the ray only
                 * meets the other sheet; then q/A. */
                if (!mpfr_zero_p(t[0]))
                    mpfr_div(sv, C, t[0], MPFR_RNDN);
                below = !mpfr_zero_p(t[0]) && sheet_below(m, sv, s, sp->R);
                if (!below) {
                    mpfr_mul(t[1], sv, m->D.z, MPFR_RNDN);
                    mpfr_add(t[1], t[1], m->P.z, MPFR_RNDN);
                    mpfr_mul(t[1], t[1], s->k1, MPFR_RNDN);
                    mpfr_div(t[1], t[1], s->R, MPFR_RNDN);
                }
                if (!below && (mpfr_cmp_ui(t[1], 1) > 0 || mpfr_zero_p(t[0]))) {
                    if (mpfr_zero_p(A))
                        return SG_EMISS;
                    mpfr_div(sv, t[0], A, MPFR_RNDN);
                    mpfr_mul(t[1], sv, m->D.z, MPFR_RNDN);
                    mpfr_add(t[1], t[1], m->P.z, MPFR_RNDN);
                    mpfr_mul(t[1], t[1], s->k1, MPFR_RNDN);
                    mpfr_div(t[1], t[1], s->R, MPFR_RNDN);
                    if (mpfr_cmp_ui(t[1], 1) > 0 && sp->shape == SHAPE_CONIC)
                        return SG_EMISS;
                }
            }
        } else if (!mpfr_zero_p(m->D.z)) {
            mpfr_div(sv, m->P.z, m->D.z, MPFR_RNDN);
            mpfr_neg(sv, sv, MPFR_RNDN);
        }
    }
    axpy(&m->P, sv, &m->D, t[0]);
    mpfr_add(m->path, m->path, sv, MPFR_RNDN);
    if (sp->shape == SHAPE_PLANE)
        return SG_OK;
    /* Newton along the ray until the step is below the precision. */
    /* Near a double root (a ray touching the surface) Newton only halves
     * its error each step, so the limit grows with the precision. */
    for (it = 0; it < max_iter + 4 + (int)m->prec; it++) {
        if (!eval_F(m, sp, s, F, Fp))
            return SG_EMISS;
        if (mpfr_zero_p(F)) {
            conv = 1;
            break;
        }
        if (mpfr_zero_p(Fp))
            return SG_EMISS;
        mpfr_div(sv, F, Fp, MPFR_RNDN);
        mpfr_neg(sv, sv, MPFR_RNDN);
        axpy(&m->P, sv, &m->D, t[0]);
        mpfr_add(m->path, m->path, sv, MPFR_RNDN);
        if (!mpfr_number_p(sv))
            return SG_EMISS;
        /* Where a step is longer than the one before, a difference in the
         * start grows by about their ratio.  Past 2^20 in all, the end of
         * the path depends on rounding, not on the ray: the root is not
         * certified (the precise method's MPFR rescue follows the same
         * rule, and its inputs differ by 2^-100 of the ray's). */
        {
            double ds = fabs(mpfr_get_d(sv, MPFR_RNDN));
            if (it > 0 && ds > dstep)
                growth *= ds / dstep;
            if (growth > 0x1p20)
                return SG_ENOCONV;
            dstep = ds;
        }
        /* Converged when the step is below 2^(8 - prec) of the path scale. */
        {
            mpfr_exp_t es = mpfr_zero_p(sv) ? mpfr_get_emin() : mpfr_get_exp(sv);
            mpfr_exp_t ep = mpfr_get_exp(m->P.z);
            mpfr_exp_t ex = mpfr_get_exp(m->P.x), ey = mpfr_get_exp(m->P.y);
            if (mpfr_zero_p(m->P.z))
                ep = mpfr_get_emin();
            if (!mpfr_zero_p(m->P.x) && ex > ep)
                ep = ex;
            if (!mpfr_zero_p(m->P.y) && ey > ep)
                ep = ey;
            if (mpfr_zero_p(sv) || es < ep - (mpfr_exp_t)m->prec + 8) {
                conv = 1;
                break;
            }
            /* A ray that grazes the surface has an ill-conditioned root:
             * the rounding of F at this precision, divided by a small F',
             * keeps the steps from shrinking further.  Steps that stop
             * shrinking below half the precision are that noise. */
            if (it > 0 && es < ep - (mpfr_exp_t)m->prec / 2 && es >= es_prev - 1) {
                conv = 1;
                break;
            }
            es_prev = es;
        }
    }
    if (!conv)
        return SG_ENOCONV;
    return SG_OK;
}

/* Moves P along D onto the surface from its vertex frame: onto the
 * tangent plane first, as the precise method does, then to the surface.
 * The steps are added to m->path. */
static int onto_surface(sg_mpfr_ctx *m, const sg_sprep *sp, const msurf *s, int max_iter)
{
    mpfr_t *t = m->t;
    if (!mpfr_zero_p(m->D.z) && !mpfr_zero_p(m->P.z)) {
        mpfr_div(t[11], m->P.z, m->D.z, MPFR_RNDN);
        mpfr_neg(t[11], t[11], MPFR_RNDN);
        /* x and y move along; z is the plane's, zero. */
        mpfr_mul(t[0], t[11], m->D.x, MPFR_RNDN);
        mpfr_add(m->P.x, m->P.x, t[0], MPFR_RNDN);
        mpfr_mul(t[0], t[11], m->D.y, MPFR_RNDN);
        mpfr_add(m->P.y, m->P.y, t[0], MPFR_RNDN);
        mpfr_set_zero(m->P.z, 1);
        mpfr_add(m->path, m->path, t[11], MPFR_RNDN);
    }
    return intersect_s(m, sp, s, max_iter);
}

/* ------------------------------------------------------------------------
 * The precise method's rescue: the intersection of a double-double ray,
 * found as the reference finds it, for the rare rays whose root the
 * precise method cannot certify in double-double.
 * ------------------------------------------------------------------------ */

#define RESCUE_PREC 320

sg_mpfr_ctx *sg_mpfr_rescue_new(void)
{
    return ctx_new(RESCUE_PREC, 1);
}

static void mpfr_set_dd(mpfr_t x, dd a)
{
    mpfr_set_d(x, a.hi, MPFR_RNDN);
    mpfr_add_d(x, x, a.lo, MPFR_RNDN);
}

int sg_mpfr_rescue_root(sg_mpfr_ctx *m, const sg_sprep *sp, dd3 P, dd3 D, int max_iter,
                        dd *step)
{
    msurf *s = &m->s[0];
    mpfr_t mc[SG_SHAPE_MPC];
    int k, rc;
    m->nrescue++;
    /* Every input is a double or a double-double: exact at 320 bits. */
    mpfr_set_d(s->R, sp->R, MPFR_RNDN);
    mpfr_set_dd(s->k1, sp->k1);
    s->k1one = 0;
    for (k = 0; k < SG_NASPH; k++)
        mpfr_set_d(s->a[k], sp->a[k], MPFR_RNDN);
    /* A shape of its own brings its coefficients at this precision. */
    if (sp->shp)
        sg_shape_mp_coefs(sp->shp, mc, m->prec);
    s->mc = sp->shp ? mc : NULL;
    mpfr_set_dd(m->P.x, P.x);
    mpfr_set_dd(m->P.y, P.y);
    mpfr_set_dd(m->P.z, P.z);
    mpfr_set_dd(m->D.x, D.x);
    mpfr_set_dd(m->D.y, D.y);
    mpfr_set_dd(m->D.z, D.z);
    mpfr_set_zero(m->path, 1);
    rc = onto_surface(m, sp, s, max_iter);
    if (rc == SG_OK)
        *step = dd_from_mpfr(m->path, m->t[0]);
    if (sp->shp) {
        s->mc = NULL;
        sg_shape_mp_clear(mc);
    }
    return rc;
}

/* Refraction or reflection at surface i, in place on D. */
static int bend(sg_tracer *tr, int i)
{
    sg_mpfr_ctx *m = tr->mp;
    const sg_sprep *sp = &tr->sp[i];
    const msurf *s = &m->s[i];
    mpfr_t *t = m->t;
    mpfr_ptr gg = t[4], dg = t[5], cosI = t[6], k = t[7], gam = t[8];
    if (sp->grating) {
        /* A diffraction grating (shape_dgrating.c). */
        mpfr_ptr P[3] = {m->P.x, m->P.y, m->P.z}, D[3] = {m->D.x, m->D.y, m->D.z};
        return sg_grating_bend_mp(sp, s->mu, s->R, s->k1, P, D, m->opl, t + 9) ? SG_EEVANESCENT
                                                                              : SG_OK;
    }
    if (sp->phase) {
        /* A phase surface (shape_phase.c): its coefficients in s->mc. */
        mpfr_ptr P[3] = {m->P.x, m->P.y, m->P.z}, D[3] = {m->D.x, m->D.y, m->D.z};
        return sg_phase_bend_mp(sp, s->mc, s->mu, s->R, s->k1, P, D, m->opl, t + 9)
                   ? SG_EEVANESCENT
                   : SG_OK;
    }
    if (sp->ideal) {
        /* A paraxial surface (shape_paraxial.c). */
        mpfr_ptr P[3] = {m->P.x, m->P.y, m->P.z}, D[3] = {m->D.x, m->D.y, m->D.z};
        sg_ideal_bend_mp(sp, s->mu, P, D, m->opl, t + 9);
        return SG_OK;
    }
    if (sp->shape == SHAPE_PLANE) {
        mpfr_set_zero(m->G.x, 1);
        mpfr_set_zero(m->G.y, 1);
        mpfr_set_si(m->G.z, -1, MPFR_RNDN);
    } else if (sp->shape == SHAPE_CONIC) {
        mpfr_set(m->G.x, m->P.x, MPFR_RNDN);
        mpfr_set(m->G.y, m->P.y, MPFR_RNDN);
        if (s->k1one) {
            mpfr_sub(m->G.z, m->P.z, s->R, MPFR_RNDN);
        } else {
            mpfr_mul(m->G.z, s->k1, m->P.z, MPFR_RNDN);
            mpfr_sub(m->G.z, m->G.z, s->R, MPFR_RNDN);
        }
    } else if (sp->shape == SHAPE_GEN) {
        if (!sp->shp->ops->sag_mp(sp->shp, s->mc, m->P.x, m->P.y, t[1], m->G.x, m->G.y,
                                  m->t + 28))
            return SG_EMISS;
        mpfr_neg(m->G.x, m->G.x, MPFR_RNDN);
        mpfr_neg(m->G.y, m->G.y, MPFR_RNDN);
        mpfr_set_ui(m->G.z, 1, MPFR_RNDN);
    } else {
        mpfr_sqr(t[1], m->P.x, MPFR_RNDN);
        mpfr_sqr(t[0], m->P.y, MPFR_RNDN);
        mpfr_add(t[1], t[1], t[0], MPFR_RNDN);
        if (!sag_w(m, sp, s, t[1], t[2], t[3]))
            return SG_EMISS;
        mpfr_mul(m->G.x, t[3], m->P.x, MPFR_RNDN);
        mpfr_neg(m->G.x, m->G.x, MPFR_RNDN);
        mpfr_mul(m->G.y, t[3], m->P.y, MPFR_RNDN);
        mpfr_neg(m->G.y, m->G.y, MPFR_RNDN);
        mpfr_set_ui(m->G.z, 1, MPFR_RNDN);
    }
    dot(gg, &m->G, &m->G, t[0]);
    dot(dg, &m->D, &m->G, t[0]);
    if (sp->mirror) {
        mpfr_div(t[1], dg, gg, MPFR_RNDN);
        mpfr_mul_2ui(t[1], t[1], 1, MPFR_RNDN);
        mpfr_neg(t[1], t[1], MPFR_RNDN);
        axpy(&m->D, t[1], &m->G, t[0]);
        return SG_OK;
    }
    mpfr_sqrt(gg, gg, MPFR_RNDN);
    mpfr_div(cosI, dg, gg, MPFR_RNDN);
    mpfr_sqr(k, cosI, MPFR_RNDN);
    mpfr_ui_sub(k, 1, k, MPFR_RNDN);
    mpfr_mul(k, k, s->mu2, MPFR_RNDN);
    mpfr_ui_sub(k, 1, k, MPFR_RNDN);
    if (mpfr_sgn(k) < 0)
        return SG_ETIR;
    mpfr_sqrt(gam, k, MPFR_RNDN);
    if (mpfr_sgn(cosI) < 0)
        mpfr_neg(gam, gam, MPFR_RNDN);
    mpfr_mul(t[1], s->mu, cosI, MPFR_RNDN);
    mpfr_sub(gam, gam, t[1], MPFR_RNDN);
    mpfr_div(gam, gam, gg, MPFR_RNDN);
    mpfr_mul(m->D.x, m->D.x, s->mu, MPFR_RNDN);
    mpfr_mul(m->D.y, m->D.y, s->mu, MPFR_RNDN);
    mpfr_mul(m->D.z, m->D.z, s->mu, MPFR_RNDN);
    axpy(&m->D, gam, &m->G, t[0]);
    return SG_OK;
}

static double ulp_d(double x)
{
    x = fabs(x);
    if (!(x > 0.0) || !isfinite(x))
        return 0.0;
    return nextafter(x, INFINITY) - x;
}

/* How far the unit normal of sp turns per unit move of the point (x, y,
 * z) (a bound on the normal's derivative over |grad F|), and in *cos the
 * cosine between the normal and the unit direction d; in double, since it
 * only scales a bound. */
static double normal_turn(const sg_sprep *sp, double x, double y, double z, const double d[3],
                          double *cos)
{
    double g[3], gn, sens, r2 = x * x + y * y;
    int k;
    if (sp->shape == SHAPE_PLANE) {
        *cos = fabs(d[2]);
        return 0.0;
    }
    if (sp->shape == SHAPE_CONIC) {
        g[0] = x;
        g[1] = y;
        g[2] = sp->k1.hi * z - sp->R;
        sens = 2.0 * fmax(1.0, fabs(sp->k1.hi));
    } else if (sp->shape == SHAPE_GEN) {
        double f, gg[2], h;
        if (!sp->shp->ops->sag_d(sp->shp, x, y, &f, gg, &h)) {
            *cos = 0.0;
            return INFINITY;
        }
        g[0] = -gg[0];
        g[1] = -gg[1];
        g[2] = 1.0;
        sens = 2.0 * h;
    } else {
        /* w = sag'(r) / r and its derivative in r^2, conic and polynomial. */
        double w = 0.0, dw = 0.0, rk = 1.0;
        if (isfinite(sp->R)) {
            double q = sp->R * sp->R - sp->k1.hi * r2;
            q = q > 0.0 ? q : 0.0;
            w = copysign(1.0, sp->R) / sqrt(q);
            dw = fabs(sp->k1.hi) / (2.0 * q * sqrt(q));
        }
        for (k = 0; k < sp->nasph; k++) {
            w += 2.0 * (k + 1) * sp->a[k] * rk;
            if (k > 0)
                dw += fabs(2.0 * (k + 1) * k * sp->a[k]) * (rk / r2);
            rk *= r2;
        }
        g[0] = -w * x;
        g[1] = -w * y;
        g[2] = 1.0;
        sens = 2.0 * (fabs(w) + 2.0 * dw * r2);
    }
    gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!(gn > 0.0) || !isfinite(gn)) {
        *cos = 0.0;
        return INFINITY;
    }
    *cos = fabs(g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn;
    return sens / gn;
}

/* Traces surfaces 1..upto from P, D (unit) in frame 1; path is preset to
 * the distance already travelled.  The bounds: the point errs by the
 * roundings of some 2^16 operations of the path's size; the direction by
 * as much, plus the turn of each normal by its point's error, carried on
 * through later bends (a refraction scales it by up to 1 + mu / cos of the
 * refracted angle). */
/* Into a surface's frame through a transfer that turns or moves it:
 * P = A^T (P - b), D = A^T D, at the context's precision (A and b come
 * from frame.c 32 bits finer). */
static void xfer_m(sg_mpfr_ctx *m, const msurf *s)
{
    mpfr_t *q = m->t + 40, *v = m->t + 43;
    mpfr_ptr P[3] = {m->P.x, m->P.y, m->P.z}, D[3] = {m->D.x, m->D.y, m->D.z};
    int j, k;
    for (j = 0; j < 3; j++)
        mpfr_sub(q[j], P[j], s->b[j], MPFR_RNDN);
    for (j = 0; j < 3; j++) {
        mpfr_set_zero(P[j], 1);
        mpfr_set_zero(v[j], 1);
        for (k = 0; k < 3; k++) {
            mpfr_fma(P[j], s->A[k][j], q[k], P[j], MPFR_RNDN);
            mpfr_fma(v[j], s->A[k][j], D[k], v[j], MPFR_RNDN);
        }
    }
    for (j = 0; j < 3; j++)
        mpfr_set(D[j], v[j], MPFR_RNDN);
}

static void memo_save(sg_mpfr_memo *mm, const sg_mpfr_ctx *m, int i, double dD,
                      const sg_ray_surface *o);

/* From surface `from` on, with the direction's error bound dD so far; a
 * memo, when given, keeps the state after each surface. */
static int run_from(sg_tracer *tr, sg_ray_surface *out, int from, int upto, double dD,
                    sg_mpfr_memo *save)
{
    sg_mpfr_ctx *m = tr->mp;
    int i, rc;
    for (i = from; i <= upto; i++) {
        const sg_sprep *sp = &tr->sp[i];
        sg_ray_surface *o = &out[i];
        double big;
        if (i > 1) {
            if (m->s[i].xf)
                xfer_m(m, &m->s[i]);
            else
                mpfr_sub(m->P.z, m->P.z, m->s[i].T, MPFR_RNDN);
            mpfr_set_zero(m->path, 1);
        } else if (m->s[i].xf) {
            /* From the launch frame through surface 1's own change; the
             * path from the object keeps running. */
            xfer_m(m, &m->s[i]);
        }
        rc = onto_surface(m, sp, &m->s[i], tr->o.max_iter);
        if (rc != SG_OK) {
            sg_fail_rest(out, i, tr->n, rc);
            return rc;
        }
        o->x = mpfr_get_d(m->P.x, MPFR_RNDN);
        o->y = mpfr_get_d(m->P.y, MPFR_RNDN);
        o->z = mpfr_get_d(m->P.z, MPFR_RNDN);
        o->path = mpfr_get_d(m->path, MPFR_RNDN);
        if (i == 1)
            dot(m->c1dot, &m->P, &m->D, m->t[0]);
        mpfr_mul(m->t[0], m->path, m->s[i].nb, MPFR_RNDN);
        mpfr_add(m->opl, m->opl, m->t[0], MPFR_RNDN);
        {
            dd o2 = dd_from_mpfr(m->opl, m->t[0]);
            o->opl = o2.hi;
            o->opl_lo = o2.lo;
        }
        o->residual = sg_sprep_sag_resid(sp, o->x, o->y, o->z);
        big = fmax(fabs(o->x), fmax(fabs(o->y), fabs(o->z)));
        o->error_bound = 0.5 * ulp_d(big) +
                         ldexp(big + fabs(o->path) + m->s[i].bmax, 16 - (int)m->prec);
        /* As the point's: some 2^16 roundings of the path's size a surface. */
        o->opl_error_bound =
            sg_bound_up(ldexp((double)i * (big + fabs(o->opl) + fabs(o->path)), 16 - (int)m->prec));
        o->status = SG_OK;
        if (tr->o.clip && !tr->unclipped &&
            (rc = sg_clip_point(sp, o->x, o->y, tr->o.clip_rtol)) != 0) {
            sg_fail_rest(out, i, tr->n, rc);
            return rc;
        }
        if (i < upto) {
            rc = bend(tr, i);
            if (rc != SG_OK) {
                sg_fail_rest(out, i, tr->n, rc);
                return rc;
            }
        }
        o->l = mpfr_get_d(m->D.x, MPFR_RNDN);
        o->m = mpfr_get_d(m->D.y, MPFR_RNDN);
        o->n = mpfr_get_d(m->D.z, MPFR_RNDN);
        if (i < upto) {
            double dout[3] = {o->l, o->m, o->n}, cos_t, turn, gain;
            double ep = ldexp(big + fabs(o->path), 16 - (int)m->prec);
            turn = normal_turn(sp, o->x, o->y, o->z, dout, &cos_t);
            gain = sp->mirror ? 2.0 : 1.0 + fabs(sp->mu.hi) / fmax(cos_t, 1e-300);
            dD = gain * (dD + 2.0 * turn * ep) + ldexp(1.0, 16 - (int)m->prec);
        }
        o->dir_error_bound = sg_bound_up(
            0.5 * ulp_d(fmax(fabs(o->l), fmax(fabs(o->m), fabs(o->n)))) +
            fmax(dD, ldexp(1.0, 16 - (int)m->prec)));
        if (save && i < upto)
            memo_save(save, m, i, dD, o);
    }
    return SG_OK;
}

static int run(sg_tracer *tr, sg_ray_surface *out, int upto)
{
    return run_from(tr, out, 1, upto, 0.0, NULL);
}

/* ------------------------------------------------------------------------
 * The ray memo (sg_mpfr_memo): the state after each surface of the last
 * ray, and what it was computed from.
 * ------------------------------------------------------------------------ */

enum { MS = 7 }; /* P, D and the optical path after a surface */

struct sg_mpfr_memo {
    mpfr_prec_t prec; /* 0: nothing kept */
    int cap;          /* surfaces allocated */
    int n;            /* surfaces of the system last traced */
    int good;         /* states kept for surfaces 1..good */
    int max_iter, clip, unclipped;
    double clip_rtol;
    mpfr_t launch[8]; /* P, D, opl and path entering surface 1 */
    mpfr_t c1dot;
    sg_surface *surf; /* each surface as it was */
    dd *mu;           /* the prepared mu and mu2 of each surface */
    mpfr_t *ix;       /* the mpfr mu and nb of each surface */
    mpfr_t *st;       /* MS a surface */
    double *dD;
    sg_ray_surface *row;
    int last;
    unsigned long resumes;
};

sg_mpfr_memo *sg_mpfr_memo_new(void)
{
    return calloc(1, sizeof(sg_mpfr_memo));
}

static void memo_clear(sg_mpfr_memo *mm)
{
    int i, k;
    if (mm->prec) {
        for (k = 0; k < 8; k++)
            mpfr_clear(mm->launch[k]);
        mpfr_clear(mm->c1dot);
        for (i = 0; i < mm->cap; i++) {
            mpfr_clear(mm->ix[2 * i]);
            mpfr_clear(mm->ix[2 * i + 1]);
            for (k = 0; k < MS; k++)
                mpfr_clear(mm->st[i * MS + k]);
        }
    }
    free(mm->surf);
    free(mm->mu);
    free(mm->ix);
    free(mm->st);
    free(mm->dD);
    free(mm->row);
    mm->surf = NULL;
    mm->mu = NULL;
    mm->ix = mm->st = NULL;
    mm->dD = NULL;
    mm->row = NULL;
    mm->prec = 0;
    mm->cap = mm->n = mm->good = 0;
}

void sg_mpfr_memo_free(sg_mpfr_memo *memo)
{
    if (!memo)
        return;
    memo_clear(memo);
    free(memo);
}

void sg_tracer_use_memo(sg_tracer *t, sg_mpfr_memo *memo)
{
    if (t)
        t->memo = memo;
}

int sg_mpfr_memo_last_resume(const sg_mpfr_memo *memo)
{
    return memo ? memo->last : 0;
}

unsigned long sg_mpfr_memo_resumes(const sg_mpfr_memo *memo)
{
    return memo ? memo->resumes : 0;
}

/* Room for n surfaces at precision prec, keeping what is there when the
 * precision is the same (a changed one empties the memo); 0 when out of
 * memory, and the memo is then empty. */
static int memo_fit(sg_mpfr_memo *mm, int n, mpfr_prec_t prec)
{
    int i, k;
    if (mm->prec != prec) {
        memo_clear(mm);
        mm->prec = prec;
        for (k = 0; k < 8; k++)
            mpfr_init2(mm->launch[k], prec);
        mpfr_init2(mm->c1dot, prec);
    }
    if (n > mm->cap) {
        sg_surface *sf = realloc(mm->surf, (size_t)n * sizeof *sf);
        dd *mu;
        mpfr_t *ix, *st;
        double *dD;
        sg_ray_surface *row;
        if (sf)
            mm->surf = sf;
        mu = realloc(mm->mu, (size_t)n * 2 * sizeof *mu);
        if (mu)
            mm->mu = mu;
        dD = realloc(mm->dD, (size_t)n * sizeof *dD);
        if (dD)
            mm->dD = dD;
        row = realloc(mm->row, (size_t)n * sizeof *row);
        if (row)
            mm->row = row;
        /* An mpfr_t holds a pointer to its limbs, so it may move. */
        ix = realloc(mm->ix, (size_t)n * 2 * sizeof *ix);
        if (ix)
            mm->ix = ix;
        st = ix ? realloc(mm->st, (size_t)n * MS * sizeof *st) : NULL;
        if (st)
            mm->st = st;
        if (!sf || !mu || !dD || !row || !ix || !st) {
            /* Only the first cap entries of ix and st are initialised. */
            memo_clear(mm);
            return 0;
        }
        for (i = mm->cap; i < n; i++) {
            mpfr_init2(mm->ix[2 * i], prec);
            mpfr_init2(mm->ix[2 * i + 1], prec);
            for (k = 0; k < MS; k++)
                mpfr_init2(mm->st[i * MS + k], prec);
        }
        mm->cap = n;
    }
    return 1;
}

/* The same number with the same sign, NaN never. */
static int same_mp(mpfr_srcptr a, mpfr_srcptr b)
{
    int r = same_limbs(a, b);
    if (r >= 0)
        return r && a->_mpfr_sign == b->_mpfr_sign;
    return mpfr_equal_p(a, b) && mpfr_signbit(a) == mpfr_signbit(b);
}

static int same_dd(dd a, dd b)
{
    return memcmp(&a.hi, &b.hi, sizeof a.hi) == 0 && memcmp(&a.lo, &b.lo, sizeof a.lo) == 0;
}

/* The ray state entering surface 1, as the memo keys it. */
static void launch_vars(sg_mpfr_ctx *m, mpfr_ptr v[8])
{
    v[0] = m->P.x;
    v[1] = m->P.y;
    v[2] = m->P.z;
    v[3] = m->D.x;
    v[4] = m->D.y;
    v[5] = m->D.z;
    v[6] = m->opl;
    v[7] = m->path;
}

/* The first surface whose state the memo cannot give: 1 for a full
 * trace, else k with the states after surfaces 1..k-1 unchanged.  A
 * surface's step reads the surface, the one before it (the transfer and
 * thickness), the indices on both sides and the options; the state
 * entering it is the launch's and the steps' before. */
static int memo_resume(const sg_tracer *tr, mpfr_ptr L[8])
{
    const sg_mpfr_memo *mm = tr->memo;
    const sg_mpfr_ctx *m = tr->mp;
    int i, k, lim = mm->good < tr->n - 2 ? mm->good : tr->n - 2;
    if (lim < 1 || mm->max_iter != tr->o.max_iter || mm->clip != tr->o.clip ||
        mm->unclipped != tr->unclipped ||
        memcmp(&mm->clip_rtol, &tr->o.clip_rtol, sizeof mm->clip_rtol) != 0)
        return 1;
    for (k = 0; k < 8; k++)
        if (!same_mp(mm->launch[k], L[k]))
            return 1;
    for (i = 0; i <= lim; i++) {
        if (memcmp(&mm->surf[i], &tr->sys->surf[i], sizeof mm->surf[i]) != 0)
            break;
        if (i >= 1 && (!same_mp(mm->ix[2 * i], m->s[i].mu) ||
                       !same_mp(mm->ix[2 * i + 1], m->s[i].nb) ||
                       !same_dd(mm->mu[2 * i], tr->sp[i].mu) ||
                       !same_dd(mm->mu[2 * i + 1], tr->sp[i].mu2)))
            break;
    }
    /* A change in surface i changes its own step and, through the
     * thickness and transfer, the next one's. */
    return i >= 2 ? i : 1;
}

static void memo_save(sg_mpfr_memo *mm, const sg_mpfr_ctx *m, int i, double dD,
                      const sg_ray_surface *o)
{
    mpfr_t *st = mm->st + (size_t)i * MS;
    mpfr_set(st[0], m->P.x, MPFR_RNDN);
    mpfr_set(st[1], m->P.y, MPFR_RNDN);
    mpfr_set(st[2], m->P.z, MPFR_RNDN);
    mpfr_set(st[3], m->D.x, MPFR_RNDN);
    mpfr_set(st[4], m->D.y, MPFR_RNDN);
    mpfr_set(st[5], m->D.z, MPFR_RNDN);
    mpfr_set(st[6], m->opl, MPFR_RNDN);
    if (i == 1)
        mpfr_set(mm->c1dot, m->c1dot, MPFR_RNDN);
    mm->dD[i] = dD;
    mm->row[i] = *o;
    mm->good = i;
}

/* The whole system from the launch in P, D, opl and path, through the
 * memo when the tracer has one: the states it keeps up to the first
 * changed surface, then a trace from there that it keeps in turn. */
static int run_memo(sg_tracer *tr, sg_ray_surface *out)
{
    sg_mpfr_memo *mm = tr->memo;
    sg_mpfr_ctx *m = tr->mp;
    mpfr_ptr L[8];
    int i, k, upto = tr->n - 1;
    double dD = 0.0;
    if (!mm || m->plane_busy || !memo_fit(mm, tr->n, m->prec))
        return run(tr, out, upto);
    launch_vars(m, L);
    k = memo_resume(tr, L);
    if (k >= 2) {
        mpfr_t *st = mm->st + (size_t)(k - 1) * MS;
        for (i = 1; i < k; i++)
            out[i] = mm->row[i];
        mpfr_set(m->P.x, st[0], MPFR_RNDN);
        mpfr_set(m->P.y, st[1], MPFR_RNDN);
        mpfr_set(m->P.z, st[2], MPFR_RNDN);
        mpfr_set(m->D.x, st[3], MPFR_RNDN);
        mpfr_set(m->D.y, st[4], MPFR_RNDN);
        mpfr_set(m->D.z, st[5], MPFR_RNDN);
        mpfr_set(m->opl, st[6], MPFR_RNDN);
        mpfr_set(m->c1dot, mm->c1dot, MPFR_RNDN);
        dD = mm->dD[k - 1];
        mm->resumes++;
    } else {
        k = 1;
        for (i = 0; i < 8; i++)
            mpfr_set(mm->launch[i], L[i], MPFR_RNDN);
        mm->max_iter = tr->o.max_iter;
        mm->clip = tr->o.clip;
        mm->clip_rtol = tr->o.clip_rtol;
        mm->unclipped = tr->unclipped;
    }
    mm->last = k;
    mm->good = k - 1;
    mm->n = tr->n;
    /* The keys of the surfaces from k on, as this trace sees them (the
     * ones before are equal). */
    for (i = k > 1 ? k : 0; i < tr->n; i++) {
        mm->surf[i] = tr->sys->surf[i];
        if (i >= 1) {
            mpfr_set(mm->ix[2 * i], m->s[i].mu, MPFR_RNDN);
            mpfr_set(mm->ix[2 * i + 1], m->s[i].nb, MPFR_RNDN);
            mm->mu[2 * i] = tr->sp[i].mu;
            mm->mu[2 * i + 1] = tr->sp[i].mu2;
        }
    }
    return run_from(tr, out, k, upto, dD, mm);
}

int sg_mpfr_trace_start(sg_tracer *tr, const double S[3], const double Dv[3],
                        sg_ray_surface *out)
{
    sg_mpfr_ctx *m = tr->mp;
    double u[3];
    mpfr_set_d(m->P.x, S[0], MPFR_RNDN);
    mpfr_set_d(m->P.y, S[1], MPFR_RNDN);
    mpfr_set_d(m->P.z, S[2], MPFR_RNDN);
    mpfr_set_d(m->D.x, Dv[0], MPFR_RNDN);
    mpfr_set_d(m->D.y, Dv[1], MPFR_RNDN);
    mpfr_set_d(m->D.z, Dv[2], MPFR_RNDN);
    normalize(&m->D, m->t[0], m->t[1]);
    u[0] = mpfr_get_d(m->D.x, MPFR_RNDN);
    u[1] = mpfr_get_d(m->D.y, MPFR_RNDN);
    u[2] = mpfr_get_d(m->D.z, MPFR_RNDN);
    sg_set_start_row(&out[0], S, u);
    mpfr_set_zero(m->path, 1);
    mpfr_set_zero(m->opl, 1);
    return run_memo(tr, out);
}

/* ------------------------------------------------------------------------
 * Normalized rays.
 * ------------------------------------------------------------------------ */

/* Object-space part from field values (vx, vy) in m->t[12], m->t[13]:
 * tangents or degrees for an infinite object, heights otherwise. */
static void m_osp(sg_tracer *tr, int deg)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_t *t = m->t;
    if (deg) {
        mpfr_mul(t[12], t[12], m->pi, MPFR_RNDN);
        mpfr_div_ui(t[12], t[12], 180, MPFR_RNDN);
        mpfr_tan(t[12], t[12], MPFR_RNDN);
        mpfr_mul(t[13], t[13], m->pi, MPFR_RNDN);
        mpfr_div_ui(t[13], t[13], 180, MPFR_RNDN);
        mpfr_tan(t[13], t[13], MPFR_RNDN);
        if (isfinite(tr->sys->surf[0].thickness)) {
            /* From a finite object, as in Zemax, the chief ray's slope
             * towards the entrance pupil's centre: the object point is
             * -tan (enp + T0) from the axis. */
            mpfr_add(t[14], m->enp, m->T0, MPFR_RNDN);
            mpfr_mul(t[12], t[12], t[14], MPFR_RNDN);
            mpfr_neg(t[12], t[12], MPFR_RNDN);
            mpfr_mul(t[13], t[13], t[14], MPFR_RNDN);
            mpfr_neg(t[13], t[13], MPFR_RNDN);
            /* An axis gets +0, as in the precise launch. */
            if (mpfr_zero_p(t[12]))
                mpfr_set_zero(t[12], 1);
            if (mpfr_zero_p(t[13]))
                mpfr_set_zero(t[13], 1);
        }
    }
    if (!isfinite(tr->sys->surf[0].thickness)) {
        mpfr_set(m->dir.x, t[12], MPFR_RNDN);
        mpfr_set(m->dir.y, t[13], MPFR_RNDN);
        mpfr_set_ui(m->dir.z, 1, MPFR_RNDN);
        normalize(&m->dir, t[0], t[1]);
    } else {
        const sg_surface *s0 = &tr->sys->surf[0];
        mpfr_set(m->obj.x, t[12], MPFR_RNDN);
        mpfr_set(m->obj.y, t[13], MPFR_RNDN);
        mpfr_neg(m->obj.z, m->T0, MPFR_RNDN);
        if (s0->radius != 0.0 && isfinite(s0->radius)) {
            double ox = mpfr_get_d(t[12], MPFR_RNDN), oy = mpfr_get_d(t[13], MPFR_RNDN);
            double sag = tr->sp[0].shp ? sg_shape_sag(tr->sp[0].shp, ox, oy)
                                       : sg_surface_sag(s0, ox, oy);
            if (isfinite(sag))
                mpfr_add_d(m->obj.z, m->obj.z, sag, MPFR_RNDN);
        }
    }
}

/* P, D and path from the object-space part and Q = m->q. */
static void m_start(sg_tracer *tr)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_set(m->P.x, m->q[0], MPFR_RNDN);
    mpfr_set(m->P.y, m->q[1], MPFR_RNDN);
    mpfr_set_zero(m->P.z, 1);
    if (!isfinite(tr->sys->surf[0].thickness)) {
        mvec_set(&m->D, &m->dir);
        mpfr_set_zero(m->path, 1);
        /* The optical path from the field's start plane to Q. */
        mpfr_mul(m->t[0], m->q[0], m->dir.x, MPFR_RNDN);
        mpfr_mul(m->t[1], m->q[1], m->dir.y, MPFR_RNDN);
        mpfr_add(m->t[0], m->t[0], m->t[1], MPFR_RNDN);
        mpfr_sub(m->t[0], m->t[0], m->plane, MPFR_RNDN);
        mpfr_mul(m->opl, m->t[0], m->s[1].nb, MPFR_RNDN);
    } else {
        mpfr_set_zero(m->opl, 1);
        mpfr_sub(m->D.x, m->q[0], m->obj.x, MPFR_RNDN);
        mpfr_sub(m->D.y, m->q[1], m->obj.y, MPFR_RNDN);
        mpfr_neg(m->D.z, m->obj.z, MPFR_RNDN);
        normalize(&m->D, m->t[0], m->path);
    }
}

/* Q for aiming off through pupil point (px, py). */
static void m_q_off(sg_tracer *tr, double px, double py)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_t *t = m->t;
    if (m->tele) {
        /* The object point plus its distance to surface 1 times the
         * slopes. */
        mpfr_neg(t[2], m->obj.z, MPFR_RNDN);
        mpfr_mul_d(t[14], m->tslope, px, MPFR_RNDN);
        mpfr_mul_d(t[15], m->tslope, py, MPFR_RNDN);
        mpfr_mul(t[3], t[2], t[14], MPFR_RNDN);
        mpfr_add(m->q[0], m->obj.x, t[3], MPFR_RNDN);
        mpfr_mul(t[3], t[2], t[15], MPFR_RNDN);
        mpfr_add(m->q[1], m->obj.y, t[3], MPFR_RNDN);
        return;
    }
    mpfr_mul_d(t[14], m->epr, px, MPFR_RNDN);
    mpfr_mul_d(t[15], m->epr, py, MPFR_RNDN);
    if (!isfinite(tr->sys->surf[0].thickness)) {
        mpfr_div(t[2], m->enp, m->dir.z, MPFR_RNDN);
        mpfr_mul(t[3], t[2], m->dir.x, MPFR_RNDN);
        mpfr_sub(m->q[0], t[14], t[3], MPFR_RNDN);
        mpfr_mul(t[3], t[2], m->dir.y, MPFR_RNDN);
        mpfr_sub(m->q[1], t[15], t[3], MPFR_RNDN);
    } else {
        mpfr_sub(t[2], m->enp, m->obj.z, MPFR_RNDN);
        mpfr_neg(t[3], m->obj.z, MPFR_RNDN);
        mpfr_div(t[2], t[3], t[2], MPFR_RNDN); /* lambda */
        mpfr_sub(t[3], t[14], m->obj.x, MPFR_RNDN);
        mpfr_mul(t[3], t[3], t[2], MPFR_RNDN);
        mpfr_add(m->q[0], m->obj.x, t[3], MPFR_RNDN);
        mpfr_sub(t[3], t[15], m->obj.y, MPFR_RNDN);
        mpfr_mul(t[3], t[3], t[2], MPFR_RNDN);
        mpfr_add(m->q[1], m->obj.y, t[3], MPFR_RNDN);
    }
}

/* Landing (x, y) on surface `upto` of the ray through m->q; into a, b. */
static int m_land(sg_tracer *tr, int upto, mpfr_t a, mpfr_t b)
{
    sg_mpfr_ctx *m = tr->mp;
    int rc, clip = tr->unclipped;
    m_start(tr);
    tr->unclipped = 1;
    rc = run(tr, tr->scratch, upto);
    tr->unclipped = clip;
    mpfr_set(a, m->P.x, MPFR_RNDN);
    mpfr_set(b, m->P.y, MPFR_RNDN);
    return rc;
}

/* The larger of |x| and |y|, as a power of two: the exponent, or
 * mpfr_get_emin() when both are zero. */
static mpfr_exp_t m_mag(const mpfr_t x, const mpfr_t y)
{
    mpfr_exp_t e = mpfr_get_emin();
    if (mpfr_regular_p(x) && mpfr_get_exp(x) > e)
        e = mpfr_get_exp(x);
    if (mpfr_regular_p(y) && mpfr_get_exp(y) > e)
        e = mpfr_get_exp(y);
    return e;
}

/* The landing residual of Q = m->q into ra, rb, with its size in *mag;
 * nonzero when the ray does not reach the stop. */
static int m_resid(sg_tracer *tr, mpfr_t ra, mpfr_t rb, mpfr_exp_t *mag)
{
    sg_mpfr_ctx *m = tr->mp;
    if (m_land(tr, tr->sys->stop, ra, rb) != SG_OK || !mpfr_number_p(ra) ||
        !mpfr_number_p(rb))
        return 1;
    mpfr_sub(ra, ra, m->tgt[0], MPFR_RNDN);
    mpfr_sub(rb, rb, m->tgt[1], MPFR_RNDN);
    *mag = m_mag(ra, rb);
    return 0;
}

/* Newton on Q = m->q for landing on m->tgt, globalised by a line search:
 * the Jacobian is taken afresh by central differences at every Q (its
 * step h = 2^(-prec/3) of the pupil balances difference and rounding
 * errors, so near the root each step gains about 2 prec / 3 bits), and a
 * step that fails to land, or does not lower the residual, is halved.
 * Converged when Q moves by less than 2^(6 - prec) of the pupil, or when
 * no step lowers a residual already within 2^(20 - prec) of the stop's
 * scale, the landing's own rounding.  The limit grows with the bits,
 * since each doubling of the precision can cost one more step. */
static int m_newton(sg_tracer *tr)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_t *t = m->a;
    mpfr_ptr h = t[0], J00 = t[1], J01 = t[2], J10 = t[3], J11 = t[4], det = t[5];
    mpfr_ptr ra = t[6], rb = t[7], sa = t[8], sb = t[9], ua = t[10], ub = t[11];
    mpfr_exp_t eq = mpfr_get_exp(m->epr), nr, nt, scale = m_mag(m->stop_r, m->epr);
    long prec = (long)m->prec, lim = tr->o.aim_max_iter, it, cut;
    for (it = prec; it > 1; it >>= 1)
        lim++;
    if (mpfr_zero_p(m->epr))
        eq = scale;
    if (m_resid(tr, ra, rb, &nr))
        return SG_EAIM;
    for (it = 0; it < lim; it++) {
        int k;
        if (mpfr_zero_p(ra) && mpfr_zero_p(rb))
            return SG_OK;
        mpfr_mul_2si(h, m->epr, -(long)(m->prec / 3), MPFR_RNDN);
        if (mpfr_zero_p(h))
            mpfr_set_ui_2exp(h, 1, scale - (long)(m->prec / 3), MPFR_RNDN);
        mpfr_set(m->qb[0], m->q[0], MPFR_RNDN);
        mpfr_set(m->qb[1], m->q[1], MPFR_RNDN);
        for (k = 0; k < 2; k++) {
            mpfr_add(m->q[k], m->qb[k], h, MPFR_RNDN);
            if (m_land(tr, tr->sys->stop, sa, sb) != SG_OK)
                return SG_EAIM;
            mpfr_sub(m->q[k], m->qb[k], h, MPFR_RNDN);
            if (m_land(tr, tr->sys->stop, ua, ub) != SG_OK)
                return SG_EAIM;
            mpfr_set(m->q[k], m->qb[k], MPFR_RNDN);
            mpfr_sub(sa, sa, ua, MPFR_RNDN);
            mpfr_sub(sb, sb, ub, MPFR_RNDN);
            mpfr_div(sa, sa, h, MPFR_RNDN);
            mpfr_div(sb, sb, h, MPFR_RNDN);
            mpfr_div_2ui(k == 0 ? J00 : J01, sa, 1, MPFR_RNDN);
            mpfr_div_2ui(k == 0 ? J10 : J11, sb, 1, MPFR_RNDN);
        }
        mpfr_mul(det, J00, J11, MPFR_RNDN);
        mpfr_mul(sa, J01, J10, MPFR_RNDN);
        mpfr_sub(det, det, sa, MPFR_RNDN);
        if (mpfr_zero_p(det) || !mpfr_number_p(det))
            return SG_EAIM;
        /* dq = J^-1 r */
        mpfr_mul(sa, J11, ra, MPFR_RNDN);
        mpfr_mul(sb, J01, rb, MPFR_RNDN);
        mpfr_sub(m->dq[0], sa, sb, MPFR_RNDN);
        mpfr_div(m->dq[0], m->dq[0], det, MPFR_RNDN);
        mpfr_mul(sa, J00, rb, MPFR_RNDN);
        mpfr_mul(sb, J10, ra, MPFR_RNDN);
        mpfr_sub(m->dq[1], sa, sb, MPFR_RNDN);
        mpfr_div(m->dq[1], m->dq[1], det, MPFR_RNDN);
        /* The line search. */
        for (cut = 0; cut < 30; cut++) {
            mpfr_sub(m->q[0], m->qb[0], m->dq[0], MPFR_RNDN);
            mpfr_sub(m->q[1], m->qb[1], m->dq[1], MPFR_RNDN);
            if (!m_resid(tr, ua, ub, &nt) &&
                (nt < nr || (mpfr_zero_p(ua) && mpfr_zero_p(ub)) ||
                 (nt == nr && mpfr_cmpabs(ua, ra) <= 0 && mpfr_cmpabs(ub, rb) <= 0 &&
                  (mpfr_cmpabs(ua, ra) < 0 || mpfr_cmpabs(ub, rb) < 0))))
                break;
            mpfr_div_2ui(m->dq[0], m->dq[0], 1, MPFR_RNDN);
            mpfr_div_2ui(m->dq[1], m->dq[1], 1, MPFR_RNDN);
        }
        if (cut == 30) {
            /* No step lowers the residual: converged if it is rounding. */
            mpfr_set(m->q[0], m->qb[0], MPFR_RNDN);
            mpfr_set(m->q[1], m->qb[1], MPFR_RNDN);
            return nr <= scale + 20 - prec ? SG_OK : SG_EAIM;
        }
        mpfr_swap(ra, ua);
        mpfr_swap(rb, ub);
        nr = nt;
        /* Converged when the correction is below the precision of Q. */
        if (m_mag(m->dq[0], m->dq[1]) < eq - prec + 6)
            return SG_OK;
    }
    return SG_EAIM;
}

/* Sets the object-space part for field fraction s of the values in m->fv
 * and the paraxial Q of pupil point (px, py) into m->qo. */
static void m_field_at(sg_tracer *tr, double s, double px, double py)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_mul_d(m->t[12], m->fv[0], s, MPFR_RNDN);
    mpfr_mul_d(m->t[13], m->fv[1], s, MPFR_RNDN);
    m_osp(tr, m->fdeg);
    m_q_off(tr, px, py);
    mpfr_set(m->qo[0], m->q[0], MPFR_RNDN);
    mpfr_set(m->qo[1], m->q[1], MPFR_RNDN);
}

/* Aims pupil point (px, py) from the paraxial Q in m->q: Newton, and
 * where that fails, continuation in field as in the precise launch (the
 * same pupil point aimed at field fraction 0, then the field stepped up to
 * 1 from each converged Q moved as the paraxial Q moves).  The last aim
 * is Newton's at the ray's own field. */
static int m_aim(sg_tracer *tr, double px, double py)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_ptr qs0 = m->a[12], qs1 = m->a[13];
    double s = 0.0, ds = 0.25;
    int steps;
    mpfr_mul_d(m->tgt[0], m->stop_r, px, MPFR_RNDN);
    mpfr_mul_d(m->tgt[1], m->stop_r, py, MPFR_RNDN);
    if (m_newton(tr) == SG_OK)
        return SG_OK;
    m_field_at(tr, 0.0, px, py);
    if (m_newton(tr) != SG_OK)
        return SG_EAIM;
    for (steps = 0; s < 1.0 && steps < 64; steps++) {
        double sn = s + ds >= 1.0 ? 1.0 : s + ds;
        mpfr_set(qs0, m->q[0], MPFR_RNDN);
        mpfr_set(qs1, m->q[1], MPFR_RNDN);
        /* The start: the last Q plus the paraxial Q's move. */
        mpfr_sub(m->a[14], qs0, m->qo[0], MPFR_RNDN);
        mpfr_sub(m->a[15], qs1, m->qo[1], MPFR_RNDN);
        m_field_at(tr, sn, px, py);
        mpfr_add(m->q[0], m->q[0], m->a[14], MPFR_RNDN);
        mpfr_add(m->q[1], m->q[1], m->a[15], MPFR_RNDN);
        if (m_newton(tr) == SG_OK) {
            s = sn;
            ds *= 2.0;
        } else {
            /* Back to fraction s and its Q; a shorter step. */
            m_field_at(tr, s, px, py);
            mpfr_set(m->q[0], qs0, MPFR_RNDN);
            mpfr_set(m->q[1], qs1, MPFR_RNDN);
            ds *= 0.25;
            if (ds < 1e-4)
                return SG_EAIM;
        }
    }
    return s == 1.0 ? SG_OK : SG_EAIM;
}

int sg_mpfr_trace_normalized(sg_tracer *tr, double hx, double hy, double px, double py,
                             sg_ray_surface *out)
{
    sg_mpfr_ctx *m = tr->mp;
    mpfr_t *t = m->t;
    int inf = !isfinite(tr->sys->surf[0].thickness), deg = 0;
    double S[3], u[3];
    /* A field that would wrap past 90 degrees or leave the doubles. */
    if (sg_field_check(tr->sys, hx, hy, NULL) != SG_OK) {
        sg_fail_rest(out, 0, tr->n, SG_ERANGE);
        return SG_ERANGE;
    }
    if (inf && !m->plane_busy &&
        (!m->plane_ok || m->plane_hx != hx || m->plane_hy != hy)) {
        /* The field's optical paths start on the plane through the primary
         * wavelength's chief ray's point on surface 1, normal to the
         * field's direction; it is traced first, once a field. */
        sg_tracer *pt = tr->prim ? tr->prim : tr;
        int rc;
        pt->mp->plane_busy = 1;
        rc = sg_mpfr_trace_normalized(pt, hx, hy, 0.0, 0.0, pt->scratch);
        pt->mp->plane_busy = 0;
        if (rc == SG_OK || pt->scratch[1].status == SG_OK)
            mpfr_set(m->plane, pt->mp->c1dot, MPFR_RNDN);
        else
            mpfr_set_zero(m->plane, 1);
        m->plane_ok = 1;
        m->plane_hx = hx;
        m->plane_hy = hy;
    }
    mpfr_mul_d(t[12], m->fx, hx, MPFR_RNDN);
    mpfr_mul_d(t[13], m->fy, hy, MPFR_RNDN);
    switch (tr->sys->field_type) {
    case SG_FIELD_ANGLE:
        deg = 1;
        break;
    case SG_FIELD_OBJECT_HEIGHT:
        break;
    case SG_FIELD_PARAX_IMAGE_HEIGHT:
        mpfr_div(t[12], t[12], m->pimg_slope, MPFR_RNDN);
        mpfr_div(t[13], t[13], m->pimg_slope, MPFR_RNDN);
        break;
    case SG_FIELD_REAL_IMAGE_HEIGHT: {
        /* The precise method finds the object-space value to double-double
         * accuracy, at the primary wavelength as Zemax defines the field;
         * the reference then traces that launch exactly. */
        sg_tracer *ft = tr->prim ? tr->prim : tr;
        sg_ray_surface *o0 = ft->scratch;
        sg_method keep = ft->o.method;
        int rc;
        ft->o.method = SG_METHOD_PRECISE;
        sg_field_forget(ft);
        rc = sg_launch_precise(ft, hx, hy, 0.0, 0.0, o0);
        ft->o.method = keep;
        sg_field_forget(ft);
        if (rc == SG_EAIM || rc == SG_ERANGE) {
            sg_fail_rest(out, 0, tr->n, rc);
            return rc;
        }
        if (inf) {
            mpfr_set_d(t[12], ft->field.dir.x.hi, MPFR_RNDN);
            mpfr_add_d(t[12], t[12], ft->field.dir.x.lo, MPFR_RNDN);
            mpfr_set_d(t[13], ft->field.dir.y.hi, MPFR_RNDN);
            mpfr_add_d(t[13], t[13], ft->field.dir.y.lo, MPFR_RNDN);
            mpfr_set_d(t[14], ft->field.dir.z.hi, MPFR_RNDN);
            mpfr_add_d(t[14], t[14], ft->field.dir.z.lo, MPFR_RNDN);
            mpfr_div(t[12], t[12], t[14], MPFR_RNDN);
            mpfr_div(t[13], t[13], t[14], MPFR_RNDN);
        } else {
            mpfr_set_d(t[12], ft->field.obj.x.hi, MPFR_RNDN);
            mpfr_add_d(t[12], t[12], ft->field.obj.x.lo, MPFR_RNDN);
            mpfr_set_d(t[13], ft->field.obj.y.hi, MPFR_RNDN);
            mpfr_add_d(t[13], t[13], ft->field.obj.y.lo, MPFR_RNDN);
        }
        break;
    }
    }
    mpfr_set(m->fv[0], t[12], MPFR_RNDN);
    mpfr_set(m->fv[1], t[13], MPFR_RNDN);
    m->fdeg = deg;
    m_osp(tr, deg);
    m_q_off(tr, px, py);
    if (tr->sys->aim != SG_AIM_OFF && !m->tele && m_aim(tr, px, py) != SG_OK) {
        sg_fail_rest(out, 0, tr->n, SG_EAIM);
        return SG_EAIM;
    }
    m_start(tr);
    u[0] = mpfr_get_d(m->D.x, MPFR_RNDN);
    u[1] = mpfr_get_d(m->D.y, MPFR_RNDN);
    u[2] = mpfr_get_d(m->D.z, MPFR_RNDN);
    if (inf) {
        S[0] = u[0] == 0.0 ? 0.0 : copysign(INFINITY, -u[0]);
        S[1] = u[1] == 0.0 ? 0.0 : copysign(INFINITY, -u[1]);
        S[2] = copysign(INFINITY, -u[2]);
    } else {
        S[0] = mpfr_get_d(m->obj.x, MPFR_RNDN);
        S[1] = mpfr_get_d(m->obj.y, MPFR_RNDN);
        mpfr_add(t[0], m->obj.z, m->T0, MPFR_RNDN);
        S[2] = mpfr_get_d(t[0], MPFR_RNDN);
    }
    sg_set_start_row(&out[0], S, u);
    /* The plane's chief ray needs only its point on surface 1 (c1dot and
     * the row's status there). */
    if (m->plane_busy)
        return run(tr, out, 1);
    return run_memo(tr, out);
}

/* ------------------------------------------------------------------------
 * Preparation.
 * ------------------------------------------------------------------------ */

int sg_mpfr_prepare(sg_tracer *tr, sg_diag *d)
{
    const sg_system *sys = tr->sys;
    mpfr_prec_t prec = tr->o.mpfr_bits;
    sg_mpfr_ctx *m = ctx_new(prec, tr->n);
    mpfr_t *idx;
    sg_parax_mp p;
    int i, k, rc;
    if (!m)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    tr->mp = m;
    idx = sg_mp_block_new((size_t)tr->n, prec);
    if (!idx)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (i = 0; i < tr->n; i++) {
        msurf *s = &m->s[i];
        mpfr_set_d(s->R, tr->sp[i].R, MPFR_RNDN);
        /* 1 + conic; a zero conic (either sign) gives 1 exactly. */
        if (sys->surf[i].conic == 0.0) {
            mpfr_set_ui(s->k1, 1, MPFR_RNDN);
        } else {
            mpfr_set_d(s->k1, sys->surf[i].conic, MPFR_RNDN);
            mpfr_add_ui(s->k1, s->k1, 1, MPFR_RNDN);
        }
        s->k1one = mpfr_cmp_ui(s->k1, 1) == 0;
        mpfr_set_d(s->T, tr->sp[i].T, MPFR_RNDN);
        if (tr->sp[i].xf) {
            int j, k2;
            for (j = 0; j < 3; j++) {
                for (k2 = 0; k2 < 3; k2++)
                    mpfr_init2(s->A[j][k2], prec);
                mpfr_init2(s->b[j], prec);
            }
            s->xf = 1;
            sg_xfer_mpfr(sys, i, s->A, s->b);
            for (j = 0; j < 3; j++)
                s->bmax = fmax(s->bmax, fabs(mpfr_get_d(s->b[j], MPFR_RNDU)));
        }
        for (k = 0; k < SG_NASPH; k++) {
            double a = tr->sp[i].a[k];
            /* As mpfr_set_d gives a zero: with its sign. */
            if (a == 0.0)
                mpfr_set_zero(s->a[k], signbit(a) ? -1 : 1);
            else
                mpfr_set_d(s->a[k], a, MPFR_RNDN);
        }
        if (tr->sp[i].shp || tr->sp[i].phase) {
            s->mc = malloc(SG_SHAPE_MPC * sizeof *s->mc);
            if (!s->mc) {
                free(idx);
                return sg_diag_set(d, SG_ENOMEM, "out of memory");
            }
            /* A shape's sag coefficients, or a phase surface's phase. */
            if (tr->sp[i].shp)
                sg_shape_mp_coefs(tr->sp[i].shp, s->mc, prec);
            else
                sg_phase_mp_coefs(tr->sp[i].phase, s->mc, prec);
        }
    }
    mpfr_const_pi(m->pi, MPFR_RNDN);
    rc = sg_indices_mpfr_cached(sys, tr->cat, tr->wave, idx, tr->icache, d);
    if (rc == SG_OK) {
        /* A design repeats a few pairs of media: the ratio of a pair met
         * on an earlier surface is copied, the same bits as dividing. */
        enum { PAIRS = 16 };
        int pair[PAIRS], npair = 0, next = 0;
        for (i = 1; i < tr->n; i++) {
            int j = -1;
            mpfr_abs(m->t[0], idx[i - 1], MPFR_RNDN);
            mpfr_abs(m->t[1], idx[i], MPFR_RNDN);
            /* Only regular numbers are kept, so same_limbs answers. */
            if (mpfr_regular_p(m->t[0]) && mpfr_regular_p(m->t[1]))
                for (k = 0; k < npair && j < 0; k++)
                    if (same_limbs(m->s[pair[k]].nb, m->t[0]) == 1 &&
                        same_limbs(idx[pair[k]], m->t[1]) == 1)
                        j = pair[k];
            if (j >= 0) {
                mpfr_set(m->s[i].mu, m->s[j].mu, MPFR_RNDN);
                mpfr_set(m->s[i].mu2, m->s[j].mu2, MPFR_RNDN);
            } else {
                mpfr_div(m->s[i].mu, m->t[0], m->t[1], MPFR_RNDN);
                mpfr_sqr(m->s[i].mu2, m->s[i].mu, MPFR_RNDN);
                if (mpfr_regular_p(m->t[0]) && mpfr_regular_p(m->t[1])) {
                    pair[next] = i;
                    next = (next + 1) % PAIRS;
                    if (npair < PAIRS)
                        npair++;
                }
            }
            mpfr_set(m->s[i].nb, m->t[0], MPFR_RNDN);
        }
        sg_parax_mp_init(&p, prec);
        rc = sg_paraxial_mpfr_memo(sys, idx, tr->wave, prec, &p, d,
                                   sg_index_cache_parax(tr->icache));
        if (rc == SG_OK) {
            /* From the launch plane, as the precise launch. */
            if (isfinite(sys->surf[0].thickness)) {
                mpfr_set_d(m->T0, sys->surf[0].thickness, MPFR_RNDN);
                mpfr_add_d(m->T0, m->T0, sg_launch_step(sys), MPFR_RNDN);
            }
            mpfr_sub_d(m->enp, p.enp, sg_launch_step(sys), MPFR_RNDN);
            mpfr_div_2ui(m->epr, p.epd, 1, MPFR_RNDN);
            mpfr_set(m->stop_r, p.stop_r, MPFR_RNDN);
            /* Only paraxial-image-height fields use it: at the paraxial
             * image plane, as the precise launch (sg_parax_mp). */
            mpfr_set(m->pimg_slope, p.pimg_slope_f, MPFR_RNDN);
            m->tele = sys->telecentric && isfinite(sys->surf[0].thickness);
            if (m->tele)
                rc = sg_object_slope_mpfr(sys, idx[0], m->tslope, d);
        }
        sg_parax_mp_clear(&p);
    }
    free(idx);
    if (rc != SG_OK)
        return rc;
    /* Field scales, as in the precise launch. */
    mpfr_set_zero(m->fx, 1);
    mpfr_set_zero(m->fy, 1);
    for (k = 0; k < sys->nfield; k++) {
        if (sys->field_norm == SG_NORM_RADIAL) {
            mpfr_set_d(m->t[0], sys->field[k].x, MPFR_RNDN);
            mpfr_sqr(m->t[0], m->t[0], MPFR_RNDN);
            mpfr_set_d(m->t[1], sys->field[k].y, MPFR_RNDN);
            mpfr_sqr(m->t[1], m->t[1], MPFR_RNDN);
            mpfr_add(m->t[0], m->t[0], m->t[1], MPFR_RNDN);
            mpfr_sqrt(m->t[0], m->t[0], MPFR_RNDN);
            mpfr_max(m->fx, m->fx, m->t[0], MPFR_RNDN);
            mpfr_max(m->fy, m->fy, m->t[0], MPFR_RNDN);
        } else {
            mpfr_set_d(m->t[0], fabs(sys->field[k].x), MPFR_RNDN);
            mpfr_max(m->fx, m->fx, m->t[0], MPFR_RNDN);
            mpfr_set_d(m->t[0], fabs(sys->field[k].y), MPFR_RNDN);
            mpfr_max(m->fy, m->fy, m->t[0], MPFR_RNDN);
        }
    }
    if (tr->prim) {
        /* The pupil, aperture and fields of the primary wavelength, as in
         * the precise launch. */
        sg_mpfr_ctx *pm = tr->prim->mp;
        mpfr_set(m->enp, pm->enp, MPFR_RNDN);
        mpfr_set(m->epr, pm->epr, MPFR_RNDN);
        mpfr_set(m->stop_r, pm->stop_r, MPFR_RNDN);
        mpfr_set(m->pimg_slope, pm->pimg_slope, MPFR_RNDN);
        mpfr_set(m->tslope, pm->tslope, MPFR_RNDN);
        return SG_OK;
    }
    /* Real aiming with a pupil not set by the stop: the stop radius is
     * where the real on-axis marginal ray meets the stop. */
    if (sys->aim == SG_AIM_REAL && sys->aper_type != SG_APER_FLOAT_STOP && !m->tele) {
        mpfr_set_zero(m->t[12], 1);
        mpfr_set_zero(m->t[13], 1);
        m_osp(tr, 0);
        m_q_off(tr, 0.0, 1.0);
        /* m_land lands unvignetted, as the precise launch does. */
        if (m_land(tr, sys->stop, m->t[14], m->t[15]) != SG_OK)
            return sg_diag_set(d, SG_EAIM,
                               "ray aiming: the on-axis marginal ray does not reach the stop "
                               "(surface %d)", sys->stop);
        mpfr_hypot(m->stop_r, m->t[14], m->t[15], MPFR_RNDN);
    }
    return SG_OK;
}

unsigned long sg_mpfr_rescues(const sg_mpfr_ctx *m)
{
    return m ? m->nrescue : 0;
}
