/*
 * material_mpfr.c - the dispersion formulas of material.c in MPFR.
 *
 * This is the reference for the double version: the same formula (see the
 * table at the top of material.c), every coefficient taken exactly as the
 * double stored in the catalog, evaluated with 32 guard bits beyond the
 * precision of the result and rounded once into it.
 */
#include <math.h>
#include <mpfr.h>

#include "model_int.h"

typedef struct mp_work {
    mpfr_t l2, inv, t, u, v;
} mp_work;

/* acc += c * x, with c taken exactly. */
static void add_cx(mp_work *w, mpfr_t acc, double c, const mpfr_t x)
{
    mpfr_set_d(w->v, c, MPFR_RNDN);
    mpfr_mul(w->v, w->v, x, MPFR_RNDN);
    mpfr_add(acc, acc, w->v, MPFR_RNDN);
}

/* acc += sum_{i} c[2i] * l2 / (l2 - c[2i+1]) over nterm terms. */
static void sellmeier_terms(mp_work *w, mpfr_t acc, const double *c, int nterm)
{
    int i;
    for (i = 0; i < nterm; i++) {
        mpfr_set_d(w->u, c[2 * i + 1], MPFR_RNDN);
        mpfr_sub(w->u, w->l2, w->u, MPFR_RNDN);
        mpfr_set_d(w->v, c[2 * i], MPFR_RNDN);
        mpfr_mul(w->v, w->v, w->l2, MPFR_RNDN);
        mpfr_div(w->v, w->v, w->u, MPFR_RNDN);
        mpfr_add(acc, acc, w->v, MPFR_RNDN);
    }
}

/* acc += c[0] x + c[1] x^2 + ... + c[n-1] x^n, by Horner's rule as in the
 * double version. */
static void poly_no_const(mp_work *w, mpfr_t acc, const double *c, int n,
                          const mpfr_t x)
{
    int i;
    mpfr_set_zero(w->u, 1);
    for (i = n - 1; i >= 0; i--) {
        mpfr_set_d(w->v, c[i], MPFR_RNDN);
        mpfr_add(w->u, w->u, w->v, MPFR_RNDN);
        mpfr_mul(w->u, w->u, x, MPFR_RNDN);
    }
    mpfr_add(acc, acc, w->u, MPFR_RNDN);
}

/* Leaves n (is_n2 = 0) or n^2 (is_n2 = 1) in w->t; returns 0 for an
 * unknown formula. */
static int eval(mp_work *w, const sg_glass *g, const mpfr_t um, int *is_n2)
{
    const double *c = g->c;
    mpfr_sqr(w->l2, um, MPFR_RNDN);
    *is_n2 = 1;
    switch (g->formula) {
    case SG_FORMULA_SCHOTT:
    case SG_FORMULA_EXTENDED1:
        mpfr_ui_div(w->inv, 1, w->l2, MPFR_RNDN);
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        poly_no_const(w, w->t, c + 2,
                      g->formula == SG_FORMULA_SCHOTT ? 4 : 6, w->inv);
        add_cx(w, w->t, c[1], w->l2);
        return 1;
    case SG_FORMULA_SELLMEIER1:
        mpfr_set_ui(w->t, 1, MPFR_RNDN);
        sellmeier_terms(w, w->t, c, 3);
        return 1;
    case SG_FORMULA_HERZBERGER:
        /* H = 1 / (lambda^2 - 28/1000), the constant taken as a decimal. */
        mpfr_set_ui(w->inv, 28, MPFR_RNDN);
        mpfr_div_ui(w->inv, w->inv, 1000, MPFR_RNDN);
        mpfr_sub(w->inv, w->l2, w->inv, MPFR_RNDN);
        mpfr_ui_div(w->inv, 1, w->inv, MPFR_RNDN);
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        poly_no_const(w, w->t, c + 1, 2, w->inv);
        poly_no_const(w, w->t, c + 3, 3, w->l2);
        *is_n2 = 0;
        return 1;
    case SG_FORMULA_SELLMEIER2:
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        mpfr_add_ui(w->t, w->t, 1, MPFR_RNDN);
        /* B1 lambda^2 / (lambda^2 - l1^2) */
        mpfr_set_d(w->u, c[2], MPFR_RNDN);
        mpfr_sqr(w->u, w->u, MPFR_RNDN);
        mpfr_sub(w->u, w->l2, w->u, MPFR_RNDN);
        mpfr_set_d(w->v, c[1], MPFR_RNDN);
        mpfr_mul(w->v, w->v, w->l2, MPFR_RNDN);
        mpfr_div(w->v, w->v, w->u, MPFR_RNDN);
        mpfr_add(w->t, w->t, w->v, MPFR_RNDN);
        /* B2 / (lambda^2 - l2^2) */
        mpfr_set_d(w->u, c[4], MPFR_RNDN);
        mpfr_sqr(w->u, w->u, MPFR_RNDN);
        mpfr_sub(w->u, w->l2, w->u, MPFR_RNDN);
        mpfr_set_d(w->v, c[3], MPFR_RNDN);
        mpfr_div(w->v, w->v, w->u, MPFR_RNDN);
        mpfr_add(w->t, w->t, w->v, MPFR_RNDN);
        return 1;
    case SG_FORMULA_CONRADY:
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        mpfr_set_d(w->v, c[1], MPFR_RNDN);
        mpfr_div(w->v, w->v, um, MPFR_RNDN);
        mpfr_add(w->t, w->t, w->v, MPFR_RNDN);
        /* lambda^3.5 = lambda^3 sqrt(lambda) */
        mpfr_sqrt(w->u, um, MPFR_RNDN);
        mpfr_mul(w->u, w->u, w->l2, MPFR_RNDN);
        mpfr_mul(w->u, w->u, um, MPFR_RNDN);
        mpfr_set_d(w->v, c[2], MPFR_RNDN);
        mpfr_div(w->v, w->v, w->u, MPFR_RNDN);
        mpfr_add(w->t, w->t, w->v, MPFR_RNDN);
        *is_n2 = 0;
        return 1;
    case SG_FORMULA_SELLMEIER3:
        mpfr_set_ui(w->t, 1, MPFR_RNDN);
        sellmeier_terms(w, w->t, c, 4);
        return 1;
    case SG_FORMULA_HANDBOOK1:
    case SG_FORMULA_HANDBOOK2:
        mpfr_set_d(w->u, c[2], MPFR_RNDN);
        mpfr_sub(w->u, w->l2, w->u, MPFR_RNDN);
        mpfr_set_d(w->v, c[1], MPFR_RNDN);
        if (g->formula == SG_FORMULA_HANDBOOK2)
            mpfr_mul(w->v, w->v, w->l2, MPFR_RNDN);
        mpfr_div(w->v, w->v, w->u, MPFR_RNDN);
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        mpfr_add(w->t, w->t, w->v, MPFR_RNDN);
        add_cx(w, w->t, -c[3], w->l2);
        return 1;
    case SG_FORMULA_SELLMEIER4:
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        sellmeier_terms(w, w->t, c + 1, 2);
        return 1;
    case SG_FORMULA_SELLMEIER5:
        mpfr_set_ui(w->t, 1, MPFR_RNDN);
        sellmeier_terms(w, w->t, c, 5);
        return 1;
    case SG_FORMULA_EXTENDED2: {
        double pos[3];
        pos[0] = c[1];
        pos[1] = c[6];
        pos[2] = c[7];
        mpfr_ui_div(w->inv, 1, w->l2, MPFR_RNDN);
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        poly_no_const(w, w->t, c + 2, 4, w->inv);
        poly_no_const(w, w->t, pos, 3, w->l2);
        return 1;
    }
    case SG_FORMULA_EXTENDED3:
        mpfr_ui_div(w->inv, 1, w->l2, MPFR_RNDN);
        mpfr_set_d(w->t, c[0], MPFR_RNDN);
        poly_no_const(w, w->t, c + 3, 6, w->inv);
        poly_no_const(w, w->t, c + 1, 2, w->l2);
        return 1;
    default:
        return 0;
    }
}

int sg_glass_index_mpfr(const sg_glass *g, mpfr_t out, const mpfr_t um)
{
    mp_work w;
    mpfr_prec_t prec = mpfr_get_prec(out), wp;
    int is_n2, rc = SG_OK;

    if (!g || !mpfr_number_p(um) || mpfr_sgn(um) <= 0) {
        mpfr_set_nan(out);
        return SG_EINVAL;
    }
    /* Coefficients enter exactly as long as wp >= 53. */
    wp = (prec > 53 ? prec : 53) + 32;
    mpfr_inits2(wp, w.l2, w.inv, w.t, w.u, w.v, (mpfr_ptr)0);
    if (!eval(&w, g, um, &is_n2)) {
        mpfr_set_nan(out);
        rc = SG_EINVAL;
    } else if (!mpfr_number_p(w.t) || mpfr_sgn(w.t) <= 0) {
        /* A pole of the formula or a non-positive n^2 (or n). */
        mpfr_set_nan(out);
        rc = SG_ERANGE;
    } else if (is_n2) {
        mpfr_sqrt(out, w.t, MPFR_RNDN);
    } else {
        mpfr_set(out, w.t, MPFR_RNDN);
    }
    mpfr_clears(w.l2, w.inv, w.t, w.u, w.v, (mpfr_ptr)0);
    return rc;
}

/* out = n_air - 1 at wavelength um (see sg_air_index), in out's precision
 * plus the caller's guard bits; the decimal constants are exact decimals. */
static void air_minus_one(mpfr_t out, const mpfr_t um, double temp, double pres)
{
    mpfr_prec_t p = mpfr_get_prec(out);
    mpfr_t l2, a, b;
    mpfr_inits2(p, l2, a, b, (mpfr_ptr)0);
    mpfr_sqr(l2, um, MPFR_RNDN);
    /* 2949810 L^2 / (146 L^2 - 1) */
    mpfr_mul_ui(a, l2, 146, MPFR_RNDN);
    mpfr_sub_ui(a, a, 1, MPFR_RNDN);
    mpfr_mul_ui(b, l2, 2949810, MPFR_RNDN);
    mpfr_div(out, b, a, MPFR_RNDN);
    /* + 25540 L^2 / (41 L^2 - 1) */
    mpfr_mul_ui(a, l2, 41, MPFR_RNDN);
    mpfr_sub_ui(a, a, 1, MPFR_RNDN);
    mpfr_mul_ui(b, l2, 25540, MPFR_RNDN);
    mpfr_div(b, b, a, MPFR_RNDN);
    mpfr_add(out, out, b, MPFR_RNDN);
    /* + 6432.8, then 1e-8 */
    mpfr_set_str(a, "6432.8", 10, MPFR_RNDN);
    mpfr_add(out, out, a, MPFR_RNDN);
    mpfr_div_ui(out, out, 100000000, MPFR_RNDN);
    /* P / (1 + 3.4785e-3 (T - 15)) */
    mpfr_mul_d(out, out, pres, MPFR_RNDN);
    mpfr_set_d(a, temp, MPFR_RNDN);
    mpfr_sub_ui(a, a, 15, MPFR_RNDN);
    mpfr_set_str(b, "3.4785e-3", 10, MPFR_RNDN);
    mpfr_mul(a, a, b, MPFR_RNDN);
    mpfr_add_ui(a, a, 1, MPFR_RNDN);
    mpfr_div(out, out, a, MPFR_RNDN);
    mpfr_clears(l2, a, b, (mpfr_ptr)0);
}

int sg_air_index_mpfr(mpfr_t out, const mpfr_t um, double temp, double pres)
{
    mpfr_t t;
    if (!mpfr_number_p(um) || mpfr_sgn(um) <= 0 || !isfinite(temp) || !isfinite(pres)) {
        mpfr_set_nan(out);
        return SG_EINVAL;
    }
    mpfr_init2(t, mpfr_get_prec(out) + 32);
    air_minus_one(t, um, temp, pres);
    mpfr_add_ui(out, t, 1, MPFR_RNDN);
    mpfr_clear(t);
    return SG_OK;
}

int sg_glass_index_env_mpfr(const sg_glass *g, mpfr_t out, const mpfr_t um, double temp,
                            double pres)
{
    mpfr_prec_t prec = mpfr_get_prec(out), wp;
    mpfr_t as, ar, lr, n, dt, s, e, t;
    int rc, k;

    if (!g || !mpfr_number_p(um) || mpfr_sgn(um) <= 0 || !isfinite(temp) || !isfinite(pres)) {
        mpfr_set_nan(out);
        return SG_EINVAL;
    }
    if (temp == g->tref && pres == 1.0)
        return sg_glass_index_mpfr(g, out, um);
    wp = (prec > 53 ? prec : 53) + 32;
    mpfr_inits2(wp, as, ar, lr, n, dt, s, e, t, (mpfr_ptr)0);
    air_minus_one(as, um, temp, pres);
    mpfr_add_ui(as, as, 1, MPFR_RNDN);
    air_minus_one(ar, um, g->tref, 1.0);
    mpfr_add_ui(ar, ar, 1, MPFR_RNDN);
    /* The wavelength in the catalog's reference air. */
    mpfr_mul(lr, um, as, MPFR_RNDN);
    mpfr_div(lr, lr, ar, MPFR_RNDN);
    rc = sg_glass_index_mpfr(g, n, lr);
    if (rc == SG_OK) {
        /* dT and D0 dT + D1 dT^2 + D2 dT^3 by Horner's rule */
        mpfr_set_d(dt, temp, MPFR_RNDN);
        mpfr_sub_d(dt, dt, g->tref, MPFR_RNDN);
        mpfr_set_d(s, g->td[2], MPFR_RNDN);
        for (k = 1; k >= 0; k--) {
            mpfr_mul(s, s, dt, MPFR_RNDN);
            mpfr_add_d(s, s, g->td[k], MPFR_RNDN);
        }
        mpfr_mul(s, s, dt, MPFR_RNDN);
        /* (E0 dT + E1 dT^2) / (L^2 - Ltk^2) */
        mpfr_mul_d(e, dt, g->td[4], MPFR_RNDN);
        mpfr_add_d(e, e, g->td[3], MPFR_RNDN);
        mpfr_mul(e, e, dt, MPFR_RNDN);
        mpfr_set_d(t, g->td[5], MPFR_RNDN);
        mpfr_sqr(t, t, MPFR_RNDN);
        mpfr_neg(t, t, MPFR_RNDN);
        mpfr_fma(t, lr, lr, t, MPFR_RNDN);
        mpfr_div(e, e, t, MPFR_RNDN);
        mpfr_add(s, s, e, MPFR_RNDN);
        /* dn = (n^2 - 1) / (2 n) * s */
        mpfr_sqr(t, n, MPFR_RNDN);
        mpfr_sub_ui(t, t, 1, MPFR_RNDN);
        mpfr_div(t, t, n, MPFR_RNDN);
        mpfr_div_2ui(t, t, 1, MPFR_RNDN);
        mpfr_mul(t, t, s, MPFR_RNDN);
        /* (n n_air(ref) + dn) / n_air(system) */
        mpfr_fma(t, n, ar, t, MPFR_RNDN);
        mpfr_div(t, t, as, MPFR_RNDN);
        if (!mpfr_number_p(t) || mpfr_sgn(t) <= 0) {
            mpfr_set_nan(out);
            rc = SG_ERANGE;
        } else {
            mpfr_set(out, t, MPFR_RNDN);
        }
    } else {
        mpfr_set_nan(out);
    }
    mpfr_clears(as, ar, lr, n, dt, s, e, t, (mpfr_ptr)0);
    return rc;
}

int sg_system_glass_index_mpfr(const sg_system *sys, const sg_glass *g, mpfr_t out,
                               const mpfr_t um)
{
    if (sys && sys->adjust_index)
        return sg_glass_index_env_mpfr(g, out, um, sys->temperature, sys->pressure);
    return sg_glass_index_mpfr(g, out, um);
}
