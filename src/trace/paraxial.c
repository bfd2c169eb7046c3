/*
 * paraxial.c - the y-nu paraxial trace.
 *
 * It runs in MPFR at a chosen precision.  The launch of every real ray
 * depends on the entrance pupil's place and size, so the precise method
 * takes them from a 128-bit run and the mpfr method from a run at its own
 * precision; a double y-nu trace would put a rounding error into the very
 * first surface.  Mirrors follow the signed-index convention n' = -n, with
 * negative thicknesses after them, so one set of formulas serves both.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trace_int.h"

typedef struct yn {
    mpfr_t y, w; /* height and reduced angle n u */
} yn;

/* The paraxial memo: for each of a few precisions and designs (the
 * launch's 128 bits, the mpfr method's, other wavelengths), the inputs of
 * every surface's step, the tree of step products (ptree), and, for each
 * trace to the stop in the order sg_paraxial_mpfr makes them (the two
 * unit rays, and a telecentric system's marginal ray), its start and its
 * state after every surface.  A step reads the surface's radius and index
 * and the thickness and index before it. */
enum { PM_SETS = 4, PM_SLOTS = 3 };

typedef struct pm_slot {
    int used, good; /* states kept after surfaces 1..good */
    int touched;    /* traced in the current computation */
    mpfr_t y0, w0;
    mpfr_t *y, *w;
} pm_slot;

/* The product of the steps after surface 1 as a tree (see steps()). */
typedef struct ptree {
    int L, size;      /* leaves in use (steps 2..last), a power of two >= L */
    mpfr_t (*m)[4];   /* 2 size nodes, node 1 the root, leaf i at size + i */
    char *ident;      /* the node is the identity (leaves past L only) */
} ptree;

typedef struct pm_set {
    mpfr_prec_t prec; /* 0: empty */
    int n;
    unsigned long stamp;
    double *R, *T;
    mpfr_t *ix;
    pm_slot s[PM_SLOTS];
    ptree tree;
    int dlo, dhi; /* leaves to recompute (dlo > dhi: none) */
    /* The track's running sums: trk[j] the thicknesses of surfaces 1..j
     * added in order, kept for j <= tgood (they read only T[1..j]). */
    mpfr_t *trk;
    int tgood;
} pm_set;

struct sg_parax_memo {
    pm_set set[PM_SETS];
    unsigned long clock;
    unsigned long resumes; /* traces resumed after surface 1 */
};

typedef struct pctx {
    const sg_system *sys;
    mpfr_t *idx;
    double um; /* the wavelength of idx, for a phase surface's power */
    mpfr_t *phi; /* power of each surface, made when a step needs it */
    char *phi_ok;
    mpfr_prec_t prec;
    mpfr_t a, b;
    sg_parax_memo *memo;
    pm_set *pm; /* NULL: no memo */
    int kf;     /* steps 1..kf-1 read what the memo saw */
    int kl;     /* the memo's keys differ from sys's on kf..kl at most */
    int slot;   /* the next trace's slot */
    ptree own;  /* the tree when there is no memo */
    ptree *tree; /* built: c->pm's or own; NULL until a trace needs it */
} pctx;

static void tree_free(ptree *t)
{
    int k;
    if (t->m)
        for (k = 0; k < 2 * t->size; k++)
            mpfr_clears(t->m[k][0], t->m[k][1], t->m[k][2], t->m[k][3], (mpfr_ptr)0);
    free(t->m);
    free(t->ident);
    memset(t, 0, sizeof *t);
}

/* A tree for the steps 2..last at prec; 0 when out of memory. */
static int tree_make(ptree *t, int last, mpfr_prec_t prec)
{
    int k;
    memset(t, 0, sizeof *t);
    t->L = last >= 2 ? last - 1 : 0;
    for (t->size = 1; t->size < t->L; t->size *= 2)
        ;
    t->m = calloc((size_t)(2 * t->size), sizeof *t->m);
    t->ident = calloc((size_t)(2 * t->size), 1);
    if (!t->m || !t->ident) {
        free(t->m);
        free(t->ident);
        memset(t, 0, sizeof *t);
        return 0;
    }
    for (k = 0; k < 2 * t->size; k++)
        mpfr_inits2(prec, t->m[k][0], t->m[k][1], t->m[k][2], t->m[k][3], (mpfr_ptr)0);
    return 1;
}

static void set_clear(pm_set *st)
{
    int j, k;
    if (st->prec) {
        for (k = 0; k < PM_SLOTS; k++) {
            pm_slot *sl = &st->s[k];
            mpfr_clears(sl->y0, sl->w0, (mpfr_ptr)0);
            for (j = 0; j < st->n; j++)
                mpfr_clears(sl->y[j], sl->w[j], (mpfr_ptr)0);
            free(sl->y);
            free(sl->w);
        }
        for (j = 0; j < st->n; j++)
            mpfr_clears(st->ix[j], st->trk[j], (mpfr_ptr)0);
    }
    tree_free(&st->tree);
    free(st->trk);
    free(st->R);
    free(st->T);
    free(st->ix);
    memset(st, 0, sizeof *st);
}

sg_parax_memo *sg_parax_memo_new(void)
{
    return calloc(1, sizeof(struct sg_parax_memo));
}

unsigned long sg_parax_memo_resumes(const sg_parax_memo *memo)
{
    return memo ? memo->resumes : 0;
}

void sg_parax_memo_free(sg_parax_memo *memo)
{
    int k;
    if (!memo)
        return;
    for (k = 0; k < PM_SETS; k++)
        set_clear(&memo->set[k]);
    free(memo);
}

/* An empty set for n surfaces at prec; 0 when out of memory. */
static int set_make(pm_set *st, int n, mpfr_prec_t prec)
{
    int j, k;
    set_clear(st);
    /* R[j] the radius, R[n + j] the focal length of a paraxial surface. */
    st->R = calloc(2 * (size_t)n, sizeof *st->R);
    st->T = calloc((size_t)n, sizeof *st->T);
    st->ix = calloc((size_t)n, sizeof *st->ix);
    st->trk = calloc((size_t)n, sizeof *st->trk);
    for (k = 0; k < PM_SLOTS; k++) {
        st->s[k].y = calloc((size_t)n, sizeof(mpfr_t));
        st->s[k].w = calloc((size_t)n, sizeof(mpfr_t));
        if (!st->s[k].y || !st->s[k].w) {
            for (; k >= 0; k--) {
                free(st->s[k].y);
                free(st->s[k].w);
            }
            free(st->R);
            free(st->T);
            free(st->ix);
            free(st->trk);
            memset(st, 0, sizeof *st);
            return 0;
        }
    }
    if (!st->R || !st->T || !st->ix || !st->trk || !tree_make(&st->tree, n - 2, prec)) {
        set_clear(st);
        return 0;
    }
    st->prec = prec;
    st->n = n;
    st->dlo = 0;
    st->dhi = st->tree.size - 1;
    st->tgood = 0;
    for (j = 0; j < n; j++) {
        mpfr_inits2(prec, st->ix[j], st->trk[j], (mpfr_ptr)0);
        /* A NaN key matches nothing until the surface is seen. */
        st->R[j] = st->R[n + j] = st->T[j] = NAN;
    }
    for (k = 0; k < PM_SLOTS; k++) {
        mpfr_inits2(prec, st->s[k].y0, st->s[k].w0, (mpfr_ptr)0);
        for (j = 0; j < n; j++)
            mpfr_inits2(prec, st->s[k].y[j], st->s[k].w[j], (mpfr_ptr)0);
    }
    return 1;
}

/* The same value and sign.  Two regular numbers of one precision are
 * equal exactly when their sign, exponent and limbs are (MPFR keeps the
 * bits past the precision zero), which is cheaper to ask of 1,000 keys. */
static int same_mp(mpfr_srcptr a, mpfr_srcptr b)
{
    if (mpfr_regular_p(a) && mpfr_regular_p(b) && mpfr_get_prec(a) == mpfr_get_prec(b)) {
        size_t nl = ((size_t)mpfr_get_prec(a) + (size_t)mp_bits_per_limb - 1) /
                    (size_t)mp_bits_per_limb;
        return a->_mpfr_sign == b->_mpfr_sign && a->_mpfr_exp == b->_mpfr_exp &&
               memcmp(a->_mpfr_d, b->_mpfr_d, nl * sizeof(mp_limb_t)) == 0;
    }
    return mpfr_equal_p(a, b) && mpfr_signbit(a) == mpfr_signbit(b);
}

static int same_d(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* What a step reads beside the radius: a paraxial surface's focal length
 * (0 for every other type, whatever its unused field holds). */
static double focal_key(const sg_system *sys, int j, double um)
{
    const sg_surface *s = &sys->surf[j];
    /* A phase surface's power, at the wavelength the memo's set is for. */
    if (sg_phase_type(s->type))
        return sg_phase_power(sys, j, um);
    return s->type == SG_SURF_PARAXIAL ? s->focal_length : 0.0;
}

/* The first surface whose inputs differ from the set's. */
static int set_first_change(const pm_set *st, const sg_system *sys, mpfr_t *idx, double um)
{
    int j, n = st->n < sys->nsurf ? st->n : sys->nsurf;
    for (j = 0; j < n; j++)
        if (!same_d(st->R[j], sys->surf[j].radius) ||
            !same_d(st->R[st->n + j], focal_key(sys, j, um)) ||
            !same_d(st->T[j], sys->surf[j].thickness) || !same_mp(st->ix[j], idx[j]))
            break;
    return j;
}

/* The last surface whose inputs differ from the set's (-1: none). */
static int set_last_change(const pm_set *st, const sg_system *sys, mpfr_t *idx, double um)
{
    int j;
    for (j = st->n - 1; j >= 0; j--)
        if (!same_d(st->R[j], sys->surf[j].radius) ||
            !same_d(st->R[st->n + j], focal_key(sys, j, um)) ||
            !same_d(st->T[j], sys->surf[j].thickness) || !same_mp(st->ix[j], idx[j]))
            break;
    return j;
}

/* Picks the set that shares the most surfaces with sys, or makes one. */
static pm_set *memo_pick(sg_parax_memo *pm, const sg_system *sys, mpfr_t *idx, double um,
                         mpfr_prec_t prec, int *kf, int *kl)
{
    pm_set *best = NULL, *old = NULL;
    int k, bk = 0;
    for (k = 0; k < PM_SETS; k++) {
        pm_set *st = &pm->set[k];
        if (!old || st->stamp < old->stamp)
            old = st;
        if (st->prec == prec && st->n == sys->nsurf) {
            int f = set_first_change(st, sys, idx, um);
            if (!best || f > bk) {
                best = st;
                bk = f;
            }
        }
    }
    if (!best || bk == 0) {
        /* Nothing in common: the least recently used set, afresh. */
        if (!set_make(old, sys->nsurf, prec))
            return NULL;
        best = old;
    }
    best->stamp = ++pm->clock;
    *kf = bk;
    *kl = bk < best->n ? set_last_change(best, sys, idx, um) : -1;
    if (bk < best->n) {
        /* Step j reads surface j and the gap before it: a change on
         * surfaces kf..kl reaches steps kf..kl + 1, leaves j - 2. */
        int lo = bk - 2, hi = *kl + 1 - 2;
        if (lo < 0)
            lo = 0;
        if (hi > best->tree.size - 1)
            hi = best->tree.size - 1;
        if (lo <= hi) {
            if (best->dlo > best->dhi) {
                best->dlo = lo;
                best->dhi = hi;
            } else {
                best->dlo = lo < best->dlo ? lo : best->dlo;
                best->dhi = hi > best->dhi ? hi : best->dhi;
            }
        }
    }
    return best;
}

/* After a computation: the keys become sys's, and the states of traces
 * not made this time stay only where the keys did not change. */
static void memo_done(pctx *c)
{
    pm_set *st = c->pm;
    int j, k;
    for (k = 0; k < PM_SLOTS; k++) {
        pm_slot *sl = &st->s[k];
        if (!sl->touched && sl->good > c->kf - 1)
            sl->good = c->kf - 1 > 0 ? c->kf - 1 : 0;
        sl->touched = 0;
    }
    /* Past kl the keys hold sys's bits already. */
    for (j = c->kf; j <= c->kl && j < st->n; j++) {
        st->R[j] = c->sys->surf[j].radius;
        st->R[st->n + j] = focal_key(c->sys, j, c->um);
        st->T[j] = c->sys->surf[j].thickness;
        mpfr_set(st->ix[j], c->idx[j], MPFR_RNDN);
    }
}

static mpfr_srcptr phi_of(pctx *c, int j)
{
    if (!c->phi_ok[j]) {
        double R = c->sys->surf[j].radius;
        mpfr_init2(c->phi[j], c->prec);
        if (j > 0 && c->sys->surf[j].type == SG_SURF_PARAXIAL) {
            /* An ideal lens: n' u' = n u - y / f. */
            mpfr_set_d(c->phi[j], c->sys->surf[j].focal_length, MPFR_RNDN);
            mpfr_ui_div(c->phi[j], 1, c->phi[j], MPFR_RNDN);
        } else if (j == 0 || R == 0.0 || isinf(R)) {
            mpfr_set_zero(c->phi[j], 1);
        } else {
            mpfr_sub(c->phi[j], c->idx[j], c->idx[j - 1], MPFR_RNDN);
            mpfr_div_d(c->phi[j], c->phi[j], R, MPFR_RNDN);
        }
        /* A phase surface adds the power of its phase's v^2 term. */
        if (j > 0 && sg_phase_type(c->sys->surf[j].type))
            mpfr_add_d(c->phi[j], c->phi[j], sg_phase_power(c->sys, j, c->um), MPFR_RNDN);
        c->phi_ok[j] = 1;
    }
    return c->phi[j];
}

static void yn_init(yn *r, mpfr_prec_t p)
{
    mpfr_init2(r->y, p);
    mpfr_init2(r->w, p);
}

static void yn_clear(yn *r)
{
    mpfr_clear(r->y);
    mpfr_clear(r->w);
}

/* Refracts at surfaces first..last and transfers between them; the ray
 * ends just after surface last, at its vertex plane. */
static void trace(pctx *c, yn *r, int first, int last)
{
    pm_slot *sl = NULL;
    int j, from = first;
    if (c->pm && first == 1 && c->slot < PM_SLOTS) {
        sl = &c->pm->s[c->slot++];
        if (sl->used && same_mp(sl->y0, r->y) && same_mp(sl->w0, r->w)) {
            /* The states after the surfaces whose steps read what they
             * read before. */
            int k = sl->good;
            if (k > c->kf - 1)
                k = c->kf - 1;
            if (k > last)
                k = last;
            if (k >= 1) {
                mpfr_set(r->y, sl->y[k], MPFR_RNDN);
                mpfr_set(r->w, sl->w[k], MPFR_RNDN);
                from = k + 1;
                c->memo->resumes++;
            }
            /* What stays valid: the kept states before the change. */
            if (sl->good > c->kf - 1)
                sl->good = c->kf - 1 > 0 ? c->kf - 1 : 0;
        } else {
            mpfr_set(sl->y0, r->y, MPFR_RNDN);
            mpfr_set(sl->w0, r->w, MPFR_RNDN);
            sl->used = 1;
            sl->good = 0;
        }
        sl->touched = 1;
    }
    for (j = from; j <= last; j++) {
        if (j > first) {
            /* y += t w / n over the gap from j-1 to j */
            mpfr_mul_d(c->a, r->w, c->sys->surf[j - 1].thickness, MPFR_RNDN);
            mpfr_div(c->a, c->a, c->idx[j - 1], MPFR_RNDN);
            mpfr_add(r->y, r->y, c->a, MPFR_RNDN);
        }
        mpfr_mul(c->a, r->y, phi_of(c, j), MPFR_RNDN);
        mpfr_sub(r->w, r->w, c->a, MPFR_RNDN);
        if (sl) {
            mpfr_set(sl->y[j], r->y, MPFR_RNDN);
            mpfr_set(sl->w[j], r->w, MPFR_RNDN);
        }
    }
    if (sl && last > sl->good)
        sl->good = last;
}

/* The y-nu step of surface j (the gap from j - 1, then the surface) is
 * linear: S[j] = [[1, tau], [-phi, q]], tau = t[j-1] / n[j-1] and
 * q = 1 - phi tau.  A trace from surface 1 to the last is surface 1's
 * refraction and then the product S[last] ... S[2], made as a balanced
 * tree over the steps: each node the product of its two halves, higher
 * steps on the left.  An edit of surfaces k..l changes the leaves of
 * steps k..l + 1 and their ancestors only, and the memo keeps the rest;
 * the tree's shape depends on the surface count alone, so a product from
 * the memo has the bits of one made afresh. */
static void leaf(pctx *c, mpfr_t *m, int j)
{
    mpfr_srcptr phi = phi_of(c, j);
    mpfr_set_ui(m[0], 1, MPFR_RNDN);
    mpfr_d_div(m[1], c->sys->surf[j - 1].thickness, c->idx[j - 1], MPFR_RNDN);
    mpfr_neg(m[2], phi, MPFR_RNDN);
    /* q = 1 - phi tau, rounded once */
    mpfr_fms(m[3], phi, m[1], m[0], MPFR_RNDN);
    mpfr_neg(m[3], m[3], MPFR_RNDN);
}

/* Node k of t from its children: the higher steps' product times the
 * lower's; an identity child leaves the other one's bits. */
static void combine(ptree *t, int k, mpfr_t tmp)
{
    mpfr_t *hi = t->m[2 * k + 1], *lo = t->m[2 * k], *m = t->m[k];
    int i;
    t->ident[k] = t->ident[2 * k] && t->ident[2 * k + 1];
    if (t->ident[k])
        return;
    if (t->ident[2 * k + 1] || t->ident[2 * k]) {
        mpfr_t *src = t->ident[2 * k + 1] ? lo : hi;
        for (i = 0; i < 4; i++)
            mpfr_set(m[i], src[i], MPFR_RNDN);
        return;
    }
    /* [a b; c d] = hi lo, each entry one product and one fused step */
    mpfr_mul(tmp, hi[1], lo[2], MPFR_RNDN);
    mpfr_fma(m[0], hi[0], lo[0], tmp, MPFR_RNDN);
    mpfr_mul(tmp, hi[1], lo[3], MPFR_RNDN);
    mpfr_fma(m[1], hi[0], lo[1], tmp, MPFR_RNDN);
    mpfr_mul(tmp, hi[3], lo[2], MPFR_RNDN);
    mpfr_fma(m[2], hi[2], lo[0], tmp, MPFR_RNDN);
    mpfr_mul(tmp, hi[3], lo[3], MPFR_RNDN);
    mpfr_fma(m[3], hi[2], lo[1], tmp, MPFR_RNDN);
}

/* Recomputes leaves lo..hi of t and their ancestors. */
static void tree_update(pctx *c, ptree *t, int lo, int hi)
{
    mpfr_t tmp;
    int i, a, b;
    mpfr_init2(tmp, c->prec);
    for (i = lo; i <= hi; i++) {
        t->ident[t->size + i] = i >= t->L;
        if (i < t->L)
            leaf(c, t->m[t->size + i], i + 2);
    }
    for (a = (t->size + lo) / 2, b = (t->size + hi) / 2; a >= 1; a /= 2, b /= 2)
        for (i = a; i <= b; i++)
            combine(t, i, tmp);
    mpfr_clear(tmp);
}

/* The tree of this system's steps, brought up to date. */
static ptree *steps(pctx *c)
{
    if (c->tree)
        return c->tree;
    if (c->pm) {
        pm_set *st = c->pm;
        if (st->dlo <= st->dhi) {
            tree_update(c, &st->tree, st->dlo, st->dhi);
            if (st->dlo > 0 || st->dhi < st->tree.size - 1)
                c->memo->resumes++;
            st->dlo = 1;
            st->dhi = 0;
        } else {
            c->memo->resumes++;
        }
        c->tree = &st->tree;
    } else {
        if (!tree_make(&c->own, c->sys->nsurf - 2, c->prec))
            return NULL;
        tree_update(c, &c->own, 0, c->own.size - 1);
        c->tree = &c->own;
    }
    return c->tree;
}

/* trace(c, r, 1, last) as surface 1 and the product of the rest; 0 when
 * out of memory. */
static int trace_all(pctx *c, yn *r)
{
    ptree *t = steps(c);
    if (!t)
        return 0;
    mpfr_mul(c->a, r->y, phi_of(c, 1), MPFR_RNDN);
    mpfr_sub(r->w, r->w, c->a, MPFR_RNDN);
    if (t->ident[1])
        return 1;
    mpfr_mul(c->a, t->m[1][1], r->w, MPFR_RNDN);
    mpfr_fma(c->a, t->m[1][0], r->y, c->a, MPFR_RNDN);
    mpfr_mul(c->b, t->m[1][3], r->w, MPFR_RNDN);
    mpfr_fma(r->w, t->m[1][2], r->y, c->b, MPFR_RNDN);
    mpfr_swap(r->y, c->a);
    return 1;
}

/* Height after moving the ray that left surface j by distance dist. */
static void transfer(pctx *c, mpfr_t out, const yn *r, int j, const mpfr_t dist)
{
    mpfr_mul(c->a, r->w, dist, MPFR_RNDN);
    mpfr_div(c->a, c->a, c->idx[j], MPFR_RNDN);
    mpfr_add(out, r->y, c->a, MPFR_RNDN);
}

void sg_parax_mp_init(sg_parax_mp *p, mpfr_prec_t prec)
{
    mpfr_inits2(prec, p->efl, p->bfl, p->image_dist, p->epd, p->enp, p->exp_diam,
                p->exp_pos, p->image_fnum, p->working_fnum, p->object_na, p->pimg_h,
                p->mag, p->track, p->stop_r, p->pimg_slope, p->pimg_slope_f, (mpfr_ptr)0);
}

void sg_parax_mp_clear(sg_parax_mp *p)
{
    mpfr_clears(p->efl, p->bfl, p->image_dist, p->epd, p->enp, p->exp_diam, p->exp_pos,
                p->image_fnum, p->working_fnum, p->object_na, p->pimg_h, p->mag, p->track,
                p->stop_r, p->pimg_slope, p->pimg_slope_f, (mpfr_ptr)0);
}

/* The axial object point's marginal slope: tan(asin(NA / |n0|)) for an
 * object NA, the tangent of the cone's half angle for an object cone angle
 * (no NA between them, so no rounding of one), at out's precision. */
int sg_object_slope_mpfr(const sg_system *sys, const mpfr_t n0, mpfr_t out, sg_diag *d)
{
    mpfr_t a;
    int rc = SG_OK;
    mpfr_init2(a, mpfr_get_prec(out));
    mpfr_set_d(out, sys->aper_value, MPFR_RNDN);
    if (sys->aper_type == SG_APER_OBJECT_CONE) {
        if (!(sys->aper_value > 0.0 && sys->aper_value < 90.0)) {
            rc = sg_diag_set(d, SG_ERANGE, "aperture: object cone angle %g is not between 0 "
                             "and 90 degrees", sys->aper_value);
        } else {
            mpfr_const_pi(a, MPFR_RNDN);
            mpfr_mul(out, out, a, MPFR_RNDN);
            mpfr_div_ui(out, out, 180, MPFR_RNDN);
            mpfr_tan(out, out, MPFR_RNDN);
        }
    } else {
        mpfr_abs(a, n0, MPFR_RNDN);
        mpfr_div(out, out, a, MPFR_RNDN);
        if (sys->aper_type != SG_APER_OBJECT_NA || mpfr_cmp_ui(out, 1) >= 0) {
            rc = sg_diag_set(d, SG_ERANGE, "aperture: object NA %g exceeds the object index",
                             sys->aper_value);
        } else {
            mpfr_asin(out, out, MPFR_RNDN);
            mpfr_tan(out, out, MPFR_RNDN);
        }
    }
    mpfr_clear(a);
    return rc;
}

/* Largest field in the system's normalization, for the y direction. */
static void field_max(const sg_system *sys, mpfr_t out)
{
    mpfr_t t;
    int k;
    mpfr_init2(t, mpfr_get_prec(out));
    mpfr_set_zero(out, 1);
    for (k = 0; k < sys->nfield; k++) {
        if (sys->field_norm == SG_NORM_RADIAL) {
            mpfr_set_d(t, sys->field[k].x, MPFR_RNDN);
            mpfr_sqr(t, t, MPFR_RNDN);
            {
                mpfr_t v;
                mpfr_init2(v, mpfr_get_prec(out));
                mpfr_set_d(v, sys->field[k].y, MPFR_RNDN);
                mpfr_sqr(v, v, MPFR_RNDN);
                mpfr_add(t, t, v, MPFR_RNDN);
                mpfr_sqrt(t, t, MPFR_RNDN);
                mpfr_clear(v);
            }
        } else {
            mpfr_set_d(t, fabs(sys->field[k].y), MPFR_RNDN);
        }
        mpfr_max(out, out, t, MPFR_RNDN);
    }
    mpfr_clear(t);
}

int sg_paraxial_mpfr(const sg_system *sys, mpfr_t *idx, int wave, mpfr_prec_t prec,
                     sg_parax_mp *o, sg_diag *d)
{
    return sg_paraxial_mpfr_memo(sys, idx, wave, prec, o, d, NULL);
}

int sg_paraxial_mpfr_memo(const sg_system *sys, mpfr_t *idx, int wave, mpfr_prec_t prec,
                          sg_parax_mp *o, sg_diag *d, sg_parax_memo *memo)
{
    pctx c;
    yn r, m, ch;
    mpfr_t A, B, T0, t1, t2, epr, u0;
    int n = sys->nsurf, last = n - 2, stop = sys->stop, j, rc = SG_OK;
    int inf_obj = !isfinite(sys->surf[0].thickness);
    /* Object-space telecentric: the entrance pupil is at infinity whatever
     * the stop; the marginal ray leaves the axial object point at the
     * object NA's slope, the chief ray a unit height parallel to the axis. */
    int tele = sys->telecentric && !inf_obj;
    double tlast = sys->surf[n - 2].thickness;

    c.sys = sys;
    c.idx = idx;
    c.um = wave >= 0 && wave < sys->nwave ? sys->wave[wave].um : 0.0;
    c.prec = prec;
    c.phi = calloc((size_t)n, sizeof *c.phi);
    c.phi_ok = calloc((size_t)n, 1);
    if (!c.phi || !c.phi_ok) {
        free(c.phi);
        free(c.phi_ok);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    c.memo = memo;
    c.pm = memo ? memo_pick(memo, sys, idx, c.um, prec, &c.kf, &c.kl) : NULL;
    if (c.pm) {
        /* The track's sums up to the first changed thickness stay. */
        pm_set *st = c.pm;
        for (j = c.kf > 1 ? c.kf : 1; j <= st->tgood; j++)
            if (!same_d(st->T[j], sys->surf[j].thickness))
                break;
        if (j - 1 < st->tgood)
            st->tgood = j - 1;
    }
    c.slot = 0;
    c.tree = NULL;
    memset(&c.own, 0, sizeof c.own);
    mpfr_inits2(prec, c.a, c.b, A, B, T0, t1, t2, epr, u0, (mpfr_ptr)0);
    yn_init(&r, prec);
    yn_init(&m, prec);
    yn_init(&ch, prec);
    if (!inf_obj)
        mpfr_set_d(T0, sys->surf[0].thickness, MPFR_RNDN);

    /* A and B: stop heights of (y=1, u=0) and (y=0, u=1) from surface 1. */
    mpfr_set_ui(r.y, 1, MPFR_RNDN);
    mpfr_set_zero(r.w, 1);
    trace(&c, &r, 1, stop);
    mpfr_set(A, r.y, MPFR_RNDN);
    mpfr_set_zero(r.y, 1);
    mpfr_set(r.w, idx[0], MPFR_RNDN);
    trace(&c, &r, 1, stop);
    mpfr_set(B, r.y, MPFR_RNDN);
    if (tele) {
        mpfr_set_inf(o->enp, 1);
    } else if (mpfr_zero_p(A)) {
        rc = sg_diag_set(d, SG_ENONPHYS,
                         "the entrance pupil is at infinity (the stop on surface %d is "
                         "imaged to infinity in object space)", stop);
        goto out;
    }
    if (!tele)
        mpfr_div(o->enp, B, A, MPFR_RNDN);
    if (!inf_obj && !tele) {
        mpfr_add(t1, o->enp, T0, MPFR_RNDN);
        if (mpfr_zero_p(t1)) {
            rc = sg_diag_set(d, SG_ENONPHYS,
                             "the entrance pupil lies on the object surface, so no ray "
                             "from an object point can be aimed through it");
            goto out;
        }
    }

    /* EFL and BFL from a unit parallel ray. */
    mpfr_set_ui(r.y, 1, MPFR_RNDN);
    mpfr_set_zero(r.w, 1);
    if (!trace_all(&c, &r)) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto out;
    }
    if (mpfr_zero_p(r.w)) {
        mpfr_set_inf(o->efl, 1);
        mpfr_set_inf(o->bfl, 1);
    } else {
        mpfr_ui_div(o->efl, 1, r.w, MPFR_RNDN);
        mpfr_neg(o->efl, o->efl, MPFR_RNDN);
        /* bfl = -y / u with u = w / n */
        mpfr_mul(o->bfl, r.y, idx[last], MPFR_RNDN);
        mpfr_div(o->bfl, o->bfl, r.w, MPFR_RNDN);
        mpfr_neg(o->bfl, o->bfl, MPFR_RNDN);
    }

    /* Entrance pupil radius from the aperture definition. */
    if (tele) {
        /* Validation allows the object NA and cone angle alone; the pupil
         * is infinite and u0 is the marginal slope. */
        if ((rc = sg_object_slope_mpfr(sys, idx[0], u0, d)) != SG_OK)
            goto out;
        mpfr_set_inf(epr, 1);
    } else switch (sys->aper_type) {
    case SG_APER_EPD:
        mpfr_set_d(epr, sys->aper_value, MPFR_RNDN);
        mpfr_div_2ui(epr, epr, 1, MPFR_RNDN);
        break;
    case SG_APER_IMAGE_FNUM:
        if (!mpfr_number_p(o->efl)) {
            rc = sg_diag_set(d, SG_ENONPHYS, "aperture: image F/# needs a finite focal length");
            goto out;
        }
        mpfr_abs(epr, o->efl, MPFR_RNDN);
        mpfr_div_d(epr, epr, 2.0 * sys->aper_value, MPFR_RNDN);
        break;
    case SG_APER_OBJECT_NA:
    case SG_APER_OBJECT_CONE:
        if (inf_obj) {
            rc = sg_diag_set(d, SG_ENONPHYS, "aperture: object-space %s needs an object at a "
                             "finite distance",
                             sys->aper_type == SG_APER_OBJECT_NA ? "NA" : "cone angle");
            goto out;
        }
        /* epr = (enp + T0) tan(asin(NA / n0)), or tan of the cone angle */
        if ((rc = sg_object_slope_mpfr(sys, idx[0], t1, d)) != SG_OK)
            goto out;
        mpfr_add(t2, o->enp, T0, MPFR_RNDN);
        mpfr_abs(t2, t2, MPFR_RNDN);
        mpfr_mul(epr, t1, t2, MPFR_RNDN);
        break;
    case SG_APER_FLOAT_STOP:
        if (!(sys->surf[stop].semi_diameter > 0.0)) {
            rc = sg_diag_set(d, SG_ERANGE,
                             "aperture: float by stop size needs a semi-diameter on the stop "
                             "(surface %d)", stop);
            goto out;
        }
        mpfr_set_d(epr, sys->surf[stop].semi_diameter, MPFR_RNDN);
        mpfr_abs(t1, A, MPFR_RNDN);
        mpfr_div(epr, epr, t1, MPFR_RNDN);
        break;
    case SG_APER_PARAX_WORKING_FNUM:
        /* Working F/# is inversely proportional to the pupil radius. */
        if (inf_obj) {
            mpfr_set_ui(m.y, 1, MPFR_RNDN);
            mpfr_set_zero(m.w, 1);
        } else {
            mpfr_add(t2, o->enp, T0, MPFR_RNDN);
            mpfr_ui_div(u0, 1, t2, MPFR_RNDN);
            mpfr_mul(m.y, u0, T0, MPFR_RNDN);
            mpfr_mul(m.w, u0, idx[0], MPFR_RNDN);
        }
        if (!trace_all(&c, &m)) {
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto out;
        }
        if (mpfr_zero_p(m.w)) {
            rc = sg_diag_set(d, SG_ENONPHYS, "aperture: the system is afocal; working F/# "
                                             "is undefined");
            goto out;
        }
        mpfr_abs(t1, m.w, MPFR_RNDN);
        mpfr_mul_2ui(t1, t1, 1, MPFR_RNDN);
        mpfr_ui_div(t1, 1, t1, MPFR_RNDN); /* W at unit pupil radius */
        mpfr_div_d(epr, t1, sys->aper_value, MPFR_RNDN);
        break;
    }
    if (!tele && !(mpfr_number_p(epr) && mpfr_sgn(epr) > 0)) {
        rc = sg_diag_set(d, SG_ENONPHYS, "aperture: the entrance pupil diameter is not "
                                         "positive and finite");
        goto out;
    }
    mpfr_mul_2ui(o->epd, epr, 1, MPFR_RNDN);
    if (tele) {
        /* The stop radius is the marginal ray's height there. */
        mpfr_mul(m.y, u0, T0, MPFR_RNDN);
        mpfr_mul(m.w, u0, idx[0], MPFR_RNDN);
        trace(&c, &m, 1, stop);
        mpfr_abs(o->stop_r, m.y, MPFR_RNDN);
    } else {
        mpfr_mul(o->stop_r, epr, A, MPFR_RNDN);
        mpfr_abs(o->stop_r, o->stop_r, MPFR_RNDN);
    }

    /* The marginal ray. */
    if (tele) {
        mpfr_mul(m.y, u0, T0, MPFR_RNDN);
        mpfr_mul(m.w, u0, idx[0], MPFR_RNDN);
    } else if (inf_obj) {
        mpfr_set(m.y, epr, MPFR_RNDN);
        mpfr_set_zero(m.w, 1);
        mpfr_set_zero(u0, 1);
    } else {
        mpfr_add(t2, o->enp, T0, MPFR_RNDN);
        mpfr_div(u0, epr, t2, MPFR_RNDN);
        mpfr_mul(m.y, u0, T0, MPFR_RNDN);
        mpfr_mul(m.w, u0, idx[0], MPFR_RNDN);
    }
    {
        mpfr_t w0;
        mpfr_init2(w0, prec);
        mpfr_set(w0, m.w, MPFR_RNDN);
        if (!trace_all(&c, &m)) {
            mpfr_clear(w0);
            rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
            goto out;
        }
        if (mpfr_zero_p(m.w)) {
            mpfr_set_inf(o->image_dist, 1);
            mpfr_set_inf(o->working_fnum, 1);
            mpfr_set_zero(o->mag, 1);
        } else {
            mpfr_mul(o->image_dist, m.y, idx[last], MPFR_RNDN);
            mpfr_div(o->image_dist, o->image_dist, m.w, MPFR_RNDN);
            mpfr_neg(o->image_dist, o->image_dist, MPFR_RNDN);
            mpfr_abs(t1, m.w, MPFR_RNDN);
            mpfr_mul_2ui(t1, t1, 1, MPFR_RNDN);
            mpfr_ui_div(o->working_fnum, 1, t1, MPFR_RNDN);
            if (inf_obj)
                mpfr_set_zero(o->mag, 1);
            else
                mpfr_div(o->mag, w0, m.w, MPFR_RNDN);
        }
        mpfr_clear(w0);
    }
    if (inf_obj) {
        mpfr_set_zero(o->object_na, 1);
    } else {
        mpfr_atan(t1, u0, MPFR_RNDN);
        mpfr_sin(t1, t1, MPFR_RNDN);
        mpfr_abs(t1, t1, MPFR_RNDN);
        mpfr_abs(t2, idx[0], MPFR_RNDN);
        mpfr_mul(o->object_na, t1, t2, MPFR_RNDN);
    }
    if (mpfr_number_p(o->efl)) {
        /* EFL over the entrance pupil diameter: 0 when that is infinite. */
        mpfr_abs(t1, o->efl, MPFR_RNDN);
        mpfr_div(o->image_fnum, t1, o->epd, MPFR_RNDN);
    } else {
        mpfr_set_inf(o->image_fnum, 1);
    }

    /* The chief ray through the pupil centre with unit slope (or from a
     * unit object height), for the exit pupil and image heights. */
    if (tele) {
        mpfr_set_ui(ch.y, 1, MPFR_RNDN);
        mpfr_set_zero(ch.w, 1);
    } else if (inf_obj) {
        mpfr_neg(ch.y, o->enp, MPFR_RNDN);
        mpfr_set(ch.w, idx[0], MPFR_RNDN);
    } else {
        /* From (h = 1, z = -T0) towards (0, enp): slope -1 / (enp + T0). */
        mpfr_add(t2, o->enp, T0, MPFR_RNDN);
        mpfr_si_div(t1, -1, t2, MPFR_RNDN);
        mpfr_mul(ch.y, t1, T0, MPFR_RNDN);
        mpfr_add_ui(ch.y, ch.y, 1, MPFR_RNDN);
        mpfr_mul(ch.w, t1, idx[0], MPFR_RNDN);
    }
    if (!trace_all(&c, &ch)) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto out;
    }
    mpfr_set_d(t1, tlast, MPFR_RNDN);
    transfer(&c, o->pimg_slope, &ch, last, t1);
    /* A paraxial-image-height field is Zemax's at the paraxial image plane,
     * not on the image surface (they differ where the image is defocused:
     * Zemax's automatic semi-diameters of sc_dblgauss2.zmx, 0.29 mm inside
     * focus, agree only this way); an afocal image keeps the surface. */
    if (mpfr_number_p(o->image_dist))
        mpfr_set(t1, o->image_dist, MPFR_RNDN);
    transfer(&c, o->pimg_slope_f, &ch, last, t1);
    if (mpfr_zero_p(ch.w)) {
        mpfr_set_inf(o->exp_pos, 1);
        mpfr_set_inf(o->exp_diam, 1);
    } else {
        /* z of the axis crossing after the last surface */
        mpfr_mul(t2, ch.y, idx[last], MPFR_RNDN);
        mpfr_div(t2, t2, ch.w, MPFR_RNDN);
        mpfr_neg(t2, t2, MPFR_RNDN);
        transfer(&c, o->exp_diam, &m, last, t2);
        mpfr_abs(o->exp_diam, o->exp_diam, MPFR_RNDN);
        mpfr_mul_2ui(o->exp_diam, o->exp_diam, 1, MPFR_RNDN);
        mpfr_sub_d(o->exp_pos, t2, tlast, MPFR_RNDN);
    }

    /* Paraxial image height of the largest field. */
    field_max(sys, t1);
    switch (sys->field_type) {
    case SG_FIELD_ANGLE:
        mpfr_const_pi(t2, MPFR_RNDN);
        mpfr_mul(t1, t1, t2, MPFR_RNDN);
        mpfr_div_ui(t1, t1, 180, MPFR_RNDN);
        mpfr_tan(t1, t1, MPFR_RNDN);
        if (!inf_obj) {
            /* The object height of that slope towards the pupil's centre. */
            mpfr_add(t2, o->enp, T0, MPFR_RNDN);
            mpfr_mul(t1, t1, t2, MPFR_RNDN);
            mpfr_neg(t1, t1, MPFR_RNDN);
        }
        mpfr_mul(o->pimg_h, t1, o->pimg_slope, MPFR_RNDN);
        break;
    case SG_FIELD_OBJECT_HEIGHT:
        mpfr_mul(o->pimg_h, t1, o->pimg_slope, MPFR_RNDN);
        break;
    default:
        mpfr_set(o->pimg_h, t1, MPFR_RNDN);
        break;
    }

    {
        /* Each thickness added in order, rounded once at prec; a 53-bit
         * copy of it makes mpfr_add the same correctly rounded sum as
         * mpfr_add_d, without its temporary. */
        pm_set *st = c.pm;
        mpfr_t tj;
        int j0 = st && st->tgood <= last ? st->tgood : st ? last : 0;
        mpfr_init2(tj, 53);
        if (j0 >= 1)
            mpfr_set(o->track, st->trk[j0], MPFR_RNDN);
        else
            mpfr_set_zero(o->track, 1);
        for (j = j0 + 1; j <= last; j++) {
            mpfr_set_d(tj, sys->surf[j].thickness, MPFR_RNDN);
            mpfr_add(o->track, o->track, tj, MPFR_RNDN);
            if (st)
                mpfr_set(st->trk[j], o->track, MPFR_RNDN);
        }
        if (st)
            st->tgood = last;
        mpfr_clear(tj);
    }

out:
    if (c.pm)
        memo_done(&c);
    for (j = 0; j < n; j++)
        if (c.phi_ok[j])
            mpfr_clear(c.phi[j]);
    tree_free(&c.own);
    free(c.phi);
    free(c.phi_ok);
    yn_clear(&r);
    yn_clear(&m);
    yn_clear(&ch);
    mpfr_clears(c.a, c.b, A, B, T0, t1, t2, epr, u0, (mpfr_ptr)0);
    return rc;
}

/* A figure in double; a zero is +0, since -y/u at a height of exactly
 * zero (a surface at the focus) would otherwise print as "-0". */
static double pd(mpfr_srcptr x)
{
    return mpfr_get_d(x, MPFR_RNDN) + 0.0;
}

void sg_parax_to_double(const sg_parax_mp *p, sg_paraxial *o)
{
    o->efl = pd(p->efl);
    o->bfl = pd(p->bfl);
    o->image_dist = pd(p->image_dist);
    o->epd = pd(p->epd);
    o->enp_pos = pd(p->enp);
    o->exp_diam = pd(p->exp_diam);
    o->exp_pos = pd(p->exp_pos);
    o->image_fnum = pd(p->image_fnum);
    o->working_fnum = pd(p->working_fnum);
    o->object_na = pd(p->object_na);
    o->parax_image_height = pd(p->pimg_h);
    o->magnification = pd(p->mag);
    o->total_track = pd(p->track);
    o->stop_radius = pd(p->stop_r);
}

int sg_paraxial_compute(const sg_system *sys, const sg_catalog *cat, int wave,
                        sg_paraxial *out, sg_diag *d)
{
    return sg_paraxial_compute_cached(sys, cat, wave, NULL, out, d);
}

int sg_paraxial_compute_cached(const sg_system *sys, const sg_catalog *cat, int wave,
                               sg_index_cache *cache, sg_paraxial *out, sg_diag *d)
{
    mpfr_t *idx;
    sg_parax_mp p;
    int i, rc;
    rc = sg_system_check(sys, cat, d);
    if (rc != SG_OK)
        return rc;
    if (wave < 0)
        wave = sys->primary_wave;
    if (wave >= sys->nwave)
        return sg_diag_set(d, SG_ERANGE, "wavelength %d is not one of 1 to %d", wave + 1,
                           sys->nwave);
    idx = calloc((size_t)sys->nsurf, sizeof *idx);
    if (!idx)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (i = 0; i < sys->nsurf; i++)
        mpfr_init2(idx[i], 128);
    rc = sg_indices_mpfr_cached(sys, cat, wave, idx, cache, d);
    if (rc == SG_OK) {
        sg_parax_mp_init(&p, 128);
        rc = sg_paraxial_mpfr_memo(sys, idx, wave, 128, &p, d, sg_index_cache_parax(cache));
        if (rc == SG_OK)
            sg_parax_to_double(&p, out);
        sg_parax_mp_clear(&p);
    }
    for (i = 0; i < sys->nsurf; i++)
        mpfr_clear(idx[i]);
    free(idx);
    return rc;
}
