/*
 * material.c - glass catalogs (Zemax AGF files) and dispersion formulas.
 *
 * The dispersion formulas follow the numbering and coefficient order of the
 * Zemax OpticStudio glass catalog ("Using Material Catalogs" / "The Glass
 * Dispersion Formulas" in the OpticStudio user guide); lambda is the vacuum
 * wavelength in micrometres and n is relative to air at the catalog's
 * reference temperature and pressure.
 *
 *   1 Schott        n^2 = a0 + a1 L^2 + a2 L^-2 + a3 L^-4 + a4 L^-6 + a5 L^-8
 *   2 Sellmeier 1   n^2 - 1 = sum_{i=1..3} K_i L^2 / (L^2 - L_i)
 *                   (CD order K1 L1 K2 L2 K3 L3)
 *   3 Herzberger    n = A + B H + C H^2 + D L^2 + E L^4 + F L^6,
 *                   H = 1 / (L^2 - 0.028)
 *   4 Sellmeier 2   n^2 - 1 = A + B1 L^2 / (L^2 - l1^2) + B2 / (L^2 - l2^2)
 *                   (CD order A B1 l1 B2 l2; l1, l2 are wavelengths)
 *   5 Conrady       n = n0 + A / L + B / L^3.5
 *   6 Sellmeier 3   as Sellmeier 1 with four terms (K1 L1 .. K4 L4)
 *   7 Handbook 1    n^2 = A + B / (L^2 - C) - D L^2
 *   8 Handbook 2    n^2 = A + B L^2 / (L^2 - C) - D L^2
 *   9 Sellmeier 4   n^2 = A + B L^2 / (L^2 - C) + D L^2 / (L^2 - E)
 *  10 Extended      n^2 = a0 + a1 L^2 + a2 L^-2 + ... + a7 L^-12
 *  11 Sellmeier 5   as Sellmeier 1 with five terms (K1 L1 .. K5 L5)
 *  12 Extended 2    n^2 = a0 + a1 L^2 + a2 L^-2 + a3 L^-4 + a4 L^-6
 *                         + a5 L^-8 + a6 L^4 + a7 L^6
 *  13 Extended 3    n^2 = a0 + a1 L^2 + a2 L^4 + a3 L^-2 + a4 L^-4
 *                         + a5 L^-6 + a6 L^-8 + a7 L^-10 + a8 L^-12
 *
 * (L stands for lambda above.)  The same formulas are written out in the
 * FRED "Formula Glass" reference and in the refractiveindex.info database
 * documentation; src/material_mpfr.c evaluates them in MPFR.
 */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "dd.h"
#include "model_int.h"
#include "sg_config.h"

/* Catalog files larger than this are refused: real catalogs are a few
 * hundred kilobytes, and the limit bounds the memory a bad path can take. */
#define AGF_MAX_BYTES ((size_t)16 << 20)
/* Longest numeric token accepted; real catalogs use at most ~20 chars. */
#define AGF_MAX_NUMBER 64

/* More glasses than any real catalog file holds; the limit keeps a
 * pathological file from taking gigabytes. */
#define AGF_MAX_GLASSES 65536

/* Glasses in load order, with two open-addressing hashes so that loading
 * and lookup stay linear in the catalog size: one keyed by catalog and
 * name (every glass), one keyed by name alone (the glass an unqualified
 * name means: the one whose catalog comes first in the search order). */
struct sg_catalog {
    sg_glass *glass;
    int *rank;     /* search-order rank of each glass's catalog */
    size_t n, cap;
    size_t *slot;  /* by name: index + 1 into glass, 0 when empty */
    size_t *qslot; /* by catalog and name */
    size_t nslot;  /* size of both, a power of two, at least twice n */
    char (*cats)[SG_GLASS_NAME]; /* catalog names in load order */
    size_t ncats, capcats;
    char *dir; /* set by sg_catalog_load_default() */
};

/* The order in which an unqualified glass name searches the shipped
 * catalogs, as a lens file's GCAT line orders them in Zemax.  Where two
 * vendors use one name, the glass the name has always meant in sagitta
 * comes first: SCHOTT's old names before HOYA's, SUMITA's, CDGM's and
 * HIKARI's; MISC's fitted CaF2 and sapphire before INFRARED's; INFRARED's
 * barium fluoride before HOYA's and CDGM's glass BAF2.  Other catalogs
 * follow in the order they were loaded. */
static const char *const search_order[] = {
    "SCHOTT", "OHARA", "MISC", "INFRARED", "HOYA", "SUMITA", "CDGM", "HIKARI",
};
#define NSEARCH ((int)(sizeof search_order / sizeof search_order[0]))

/* ------------------------------------------------------------------------
 * Catalog container
 * ------------------------------------------------------------------------ */

sg_catalog *sg_catalog_new(void)
{
    return calloc(1, sizeof(sg_catalog));
}

void sg_catalog_free(sg_catalog *cat)
{
    if (!cat)
        return;
    free(cat->glass);
    free(cat->rank);
    free(cat->slot);
    free(cat->qslot);
    free(cat->cats);
    free(cat->dir);
    free(cat);
}

const char *sg_catalog_dir(const sg_catalog *cat)
{
    return cat ? cat->dir : NULL;
}

size_t sg_catalog_count(const sg_catalog *cat)
{
    return cat ? cat->n : 0;
}

const sg_glass *sg_catalog_at(const sg_catalog *cat, size_t i)
{
    if (!cat || i >= cat->n)
        return NULL;
    return &cat->glass[i];
}

/* ASCII-only case folding, so glass names compare the same in any locale. */
static int ascii_upper(int c)
{
    return (c >= 'a' && c <= 'z') ? c - 'a' + 'A' : c;
}

static int name_equal(const char *a, const char *b)
{
    for (; *a && *b; a++, b++)
        if (ascii_upper((unsigned char)*a) != ascii_upper((unsigned char)*b))
            return 0;
    return *a == *b;
}

/* FNV-1a of the upper-cased text, continued from h. */
static uint64_t fnv_upper(uint64_t h, const char *s)
{
    for (; *s; s++) {
        h ^= (uint64_t)ascii_upper((unsigned char)*s);
        h *= 1099511628211ull;
    }
    return h;
}

#define FNV_START 14695981039346656037ull

/* The slot holding name's unqualified glass, or the empty slot where it
 * would go. */
static size_t *find_slot(const sg_catalog *cat, const char *name)
{
    size_t mask = cat->nslot - 1, i = (size_t)fnv_upper(FNV_START, name) & mask;
    while (cat->slot[i] && !name_equal(cat->glass[cat->slot[i] - 1].name, name))
        i = (i + 1) & mask;
    return &cat->slot[i];
}

/* The slot holding catalog's glass name, or the empty slot for it.  The
 * separator keeps "AB"+"C" and "A"+"BC" apart. */
static size_t *find_qslot(const sg_catalog *cat, const char *catalog, const char *name)
{
    size_t mask = cat->nslot - 1, i;
    uint64_t h = fnv_upper(FNV_START, catalog);
    h = (h ^ (uint64_t)':') * 1099511628211ull;
    i = (size_t)fnv_upper(h, name) & mask;
    while (cat->qslot[i]) {
        const sg_glass *g = &cat->glass[cat->qslot[i] - 1];
        if (name_equal(g->name, name) && name_equal(g->catalog, catalog))
            break;
        i = (i + 1) & mask;
    }
    return &cat->qslot[i];
}

const sg_glass *sg_catalog_find(const sg_catalog *cat, const char *name)
{
    size_t *s;
    if (!cat || !name || cat->nslot == 0)
        return NULL;
    s = find_slot(cat, name);
    return *s ? &cat->glass[*s - 1] : NULL;
}

const sg_glass *sg_catalog_find_in(const sg_catalog *cat, const char *catalog,
                                   const char *name)
{
    size_t *s;
    if (!catalog || !catalog[0])
        return sg_catalog_find(cat, name);
    if (!cat || !name || cat->nslot == 0)
        return NULL;
    s = find_qslot(cat, catalog, name);
    return *s ? &cat->glass[*s - 1] : NULL;
}

const sg_glass *sg_material_glass(const sg_catalog *cat, const sg_material *m)
{
    if (!m || m->kind != SG_MAT_GLASS)
        return NULL;
    return sg_catalog_find_in(cat, m->catalog, m->name);
}

void sg_material_where(const sg_catalog *cat, const sg_material *m, char *buf, size_t n)
{
    size_t i;
    if (!m->catalog[0]) {
        if (n)
            buf[0] = '\0';
        return;
    }
    for (i = 0; cat && i < cat->ncats && !name_equal(cat->cats[i], m->catalog); i++)
        ;
    snprintf(buf, n, cat && i < cat->ncats ? " (catalog %s)" : " (catalog %s, which is not loaded)",
             m->catalog);
}

size_t sg_catalog_ncatalogs(const sg_catalog *cat)
{
    return cat ? cat->ncats : 0;
}

const char *sg_catalog_catalog_at(const sg_catalog *cat, size_t i)
{
    return cat && i < cat->ncats ? cat->cats[i] : NULL;
}

/* Records g's catalog as newly seen (load order) and gives its rank in the
 * search order. */
static int catalog_rank(sg_catalog *cat, const char *catalog, int *rank)
{
    size_t i;
    int k;
    for (i = 0; i < cat->ncats && !name_equal(cat->cats[i], catalog); i++)
        ;
    if (i == cat->ncats) {
        if (cat->ncats == cat->capcats) {
            size_t ncap = cat->capcats ? 2 * cat->capcats : 16;
            char(*p)[SG_GLASS_NAME] = realloc(cat->cats, ncap * sizeof *p);
            if (!p)
                return SG_ENOMEM;
            cat->cats = p;
            cat->capcats = ncap;
        }
        sg_strlcpy(cat->cats[cat->ncats++], catalog, SG_GLASS_NAME);
    }
    for (k = 0; k < NSEARCH; k++)
        if (name_equal(search_order[k], catalog)) {
            *rank = k;
            return SG_OK;
        }
    *rank = NSEARCH + (int)i;
    return SG_OK;
}

/* Enters glass i into both hashes. */
static void index_glass(sg_catalog *cat, size_t i)
{
    size_t *q = find_qslot(cat, cat->glass[i].catalog, cat->glass[i].name);
    size_t *s = find_slot(cat, cat->glass[i].name);
    *q = i + 1;
    if (!*s || cat->rank[i] < cat->rank[*s - 1])
        *s = i + 1;
}

static int rehash(sg_catalog *cat, size_t nslot)
{
    size_t *old = cat->slot, *oldq = cat->qslot, i;
    if (nslot > SIZE_MAX / sizeof *old)
        return SG_ENOMEM;
    cat->slot = calloc(nslot, sizeof *old);
    cat->qslot = calloc(nslot, sizeof *old);
    if (!cat->slot || !cat->qslot) {
        free(cat->slot);
        free(cat->qslot);
        cat->slot = old;
        cat->qslot = oldq;
        return SG_ENOMEM;
    }
    cat->nslot = nslot;
    for (i = 0; i < cat->n; i++)
        index_glass(cat, i);
    free(old);
    free(oldq);
    return SG_OK;
}

/* Adds g, or overwrites the glass of the same name in the same catalog so
 * that the last file loaded wins, as in Zemax. */
static int catalog_put(sg_catalog *cat, const sg_glass *g)
{
    size_t *q;
    int rank, rc;
    if (2 * (cat->n + 1) > cat->nslot) {
        rc = rehash(cat, cat->nslot ? 2 * cat->nslot : 256);
        if (rc)
            return rc;
    }
    q = find_qslot(cat, g->catalog, g->name);
    if (*q) {
        cat->glass[*q - 1] = *g;
        return SG_OK;
    }
    if ((rc = catalog_rank(cat, g->catalog, &rank)) != SG_OK)
        return rc;
    if (cat->n == cat->cap) {
        size_t ncap = cat->cap ? 2 * cat->cap : 64;
        sg_glass *p;
        int *r;
        if (ncap > SIZE_MAX / sizeof *p)
            return SG_ENOMEM;
        p = realloc(cat->glass, ncap * sizeof *p);
        if (!p)
            return SG_ENOMEM;
        cat->glass = p;
        r = realloc(cat->rank, ncap * sizeof *r);
        if (!r)
            return SG_ENOMEM;
        cat->rank = r;
        cat->cap = ncap;
    }
    cat->glass[cat->n] = *g;
    cat->rank[cat->n] = rank;
    index_glass(cat, cat->n++);
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Dispersion formulas.  The index is evaluated in double-double (dd.h,
 * about 106 bits) and rounded once, so the double result is within an ulp
 * of the exact value of the formula for the stored coefficients.  fma() is
 * correctly rounded whether or not the hardware has it, so results do not
 * depend on -march.
 * ------------------------------------------------------------------------ */

/* a + b*c with the coefficient b taken exactly. */
static dd dd_axpy(dd a, double b, dd c)
{
    return dd_add(a, dd_mul_d(c, b));
}

/* sum_{i} c[2i] * l2 / (l2 - c[2i+1]) over nterm terms. */
static dd sellmeier_terms(const double *c, int nterm, dd l2)
{
    dd s = dd_from(0.0);
    int i;
    for (i = 0; i < nterm; i++) {
        dd num = dd_mul_d(l2, c[2 * i]);
        dd den = dd_sub(l2, dd_from(c[2 * i + 1]));
        s = dd_add(s, dd_div(num, den));
    }
    return s;
}

/* c[0] x + c[1] x^2 + ... + c[n-1] x^n by Horner's rule. */
static dd poly_no_const(const double *c, int n, dd x)
{
    dd t = dd_from(0.0);
    int i;
    for (i = n - 1; i >= 0; i--)
        t = dd_mul(dd_add(t, dd_from(c[i])), x);
    return t;
}

/* Computes n (when *is_n2 is 0) or n^2 (when 1) in double-double.  Returns
 * 0 for an unknown formula. */
static int glass_eval_dd(const sg_glass *g, double um, dd *out, int *is_n2)
{
    const double *c = g->c;
    dd l2 = dd_two_prod(um, um); /* exact */
    dd inv, t, h;

    *is_n2 = 1;
    switch (g->formula) {
    case SG_FORMULA_SCHOTT:
        inv = dd_div(dd_from(1.0), l2);
        t = dd_add(dd_from(c[0]), poly_no_const(c + 2, 4, inv));
        *out = dd_axpy(t, c[1], l2);
        return 1;
    case SG_FORMULA_SELLMEIER1:
        *out = dd_add(dd_from(1.0), sellmeier_terms(c, 3, l2));
        return 1;
    case SG_FORMULA_HERZBERGER:
        /* 0.028 is a decimal constant of the formula, so take it as the
         * double-double nearest 28/1000 rather than as a double. */
        h = dd_div_d(dd_from(28.0), 1000.0);
        h = dd_div(dd_from(1.0), dd_sub(l2, h));
        t = dd_add(dd_from(c[0]), poly_no_const(c + 1, 2, h));
        *out = dd_add(t, poly_no_const(c + 3, 3, l2));
        *is_n2 = 0;
        return 1;
    case SG_FORMULA_SELLMEIER2: {
        dd a1 = dd_two_prod(c[2], c[2]), a2 = dd_two_prod(c[4], c[4]);
        t = dd_add(dd_from(1.0), dd_from(c[0]));
        t = dd_add(t, dd_div(dd_mul_d(l2, c[1]), dd_sub(l2, a1)));
        *out = dd_add(t, dd_div(dd_from(c[3]), dd_sub(l2, a2)));
        return 1;
    }
    case SG_FORMULA_CONRADY: {
        /* lambda^3.5 = lambda^3 * sqrt(lambda). */
        dd l = dd_from(um);
        dd l35 = dd_mul(dd_mul(l2, l), dd_sqrt(l));
        t = dd_add(dd_from(c[0]), dd_div(dd_from(c[1]), l));
        *out = dd_add(t, dd_div(dd_from(c[2]), l35));
        *is_n2 = 0;
        return 1;
    }
    case SG_FORMULA_SELLMEIER3:
        *out = dd_add(dd_from(1.0), sellmeier_terms(c, 4, l2));
        return 1;
    case SG_FORMULA_HANDBOOK1:
        t = dd_div(dd_from(c[1]), dd_sub(l2, dd_from(c[2])));
        t = dd_add(dd_from(c[0]), t);
        *out = dd_sub(t, dd_mul_d(l2, c[3]));
        return 1;
    case SG_FORMULA_HANDBOOK2:
        t = dd_div(dd_mul_d(l2, c[1]), dd_sub(l2, dd_from(c[2])));
        t = dd_add(dd_from(c[0]), t);
        *out = dd_sub(t, dd_mul_d(l2, c[3]));
        return 1;
    case SG_FORMULA_SELLMEIER4:
        *out = dd_add(dd_from(c[0]), sellmeier_terms(c + 1, 2, l2));
        return 1;
    case SG_FORMULA_EXTENDED1:
        inv = dd_div(dd_from(1.0), l2);
        t = dd_add(dd_from(c[0]), poly_no_const(c + 2, 6, inv));
        *out = dd_axpy(t, c[1], l2);
        return 1;
    case SG_FORMULA_SELLMEIER5:
        *out = dd_add(dd_from(1.0), sellmeier_terms(c, 5, l2));
        return 1;
    case SG_FORMULA_EXTENDED2: {
        /* The positive powers are a1 L^2 + a6 L^4 + a7 L^6. */
        double pos[3];
        pos[0] = c[1];
        pos[1] = c[6];
        pos[2] = c[7];
        inv = dd_div(dd_from(1.0), l2);
        t = dd_add(dd_from(c[0]), poly_no_const(c + 2, 4, inv));
        *out = dd_add(t, poly_no_const(pos, 3, l2));
        return 1;
    }
    case SG_FORMULA_EXTENDED3:
        inv = dd_div(dd_from(1.0), l2);
        t = dd_add(dd_from(c[0]), poly_no_const(c + 3, 6, inv));
        *out = dd_add(t, poly_no_const(c + 1, 2, l2));
        return 1;
    default:
        return 0;
    }
}

double sg_glass_index(const sg_glass *g, double um)
{
    dd v;
    int is_n2;
    if (!g || !(um > 0.0) || !isfinite(um))
        return NAN;
    if (!glass_eval_dd(g, um, &v, &is_n2))
        return NAN;
    /* A pole of the formula gives an infinite or NaN sum; both are as
     * unusable as a negative n^2. */
    if (!isfinite(v.hi) || !isfinite(v.lo) || !(v.hi > 0.0))
        return NAN;
    if (is_n2)
        v = dd_sqrt(v);
    return v.hi + v.lo;
}

/* The air formula's decimal constants, as the dd nearest each. */
static dd dd_dec(double num, double den)
{
    return dd_div_d(dd_from(num), den);
}

/* n_air - 1 in double-double (see sagitta.h). */
static dd air_minus_one(double um, double temp, double pres)
{
    dd l2 = dd_two_prod(um, um), t, f;
    t = dd_div(dd_mul_d(l2, 2949810.0), dd_sub(dd_mul_d(l2, 146.0), dd_from(1.0)));
    t = dd_add(t, dd_div(dd_mul_d(l2, 25540.0), dd_sub(dd_mul_d(l2, 41.0), dd_from(1.0))));
    t = dd_add(t, dd_dec(64328.0, 10.0));
    t = dd_div_d(t, 1e8);
    /* 1 + 3.4785e-3 (T - 15) */
    f = dd_add(dd_from(1.0), dd_mul(dd_dec(34785.0, 1e7), dd_sub(dd_from(temp), dd_from(15.0))));
    return dd_div(dd_mul_d(t, pres), f);
}

double sg_air_index(double um, double temp, double pres)
{
    dd v;
    if (!(um > 0.0) || !isfinite(um) || !isfinite(temp) || !isfinite(pres))
        return NAN;
    v = dd_add(dd_from(1.0), air_minus_one(um, temp, pres));
    return v.hi + v.lo;
}

double sg_glass_index_env(const sg_glass *g, double um, double temp, double pres)
{
    dd air_sys, air_ref, n, nabs, dt, s, e, dn, l2r;
    double lref;
    if (!g)
        return NAN;
    if (temp == g->tref && pres == 1.0)
        return sg_glass_index(g, um);
    if (!(um > 0.0) || !isfinite(um) || !isfinite(temp) || !isfinite(pres))
        return NAN;
    air_sys = dd_add(dd_from(1.0), air_minus_one(um, temp, pres));
    air_ref = dd_add(dd_from(1.0), air_minus_one(um, g->tref, 1.0));
    /* The wavelength in the catalog's reference air. */
    lref = dd_div(dd_mul_d(air_sys, um), air_ref).hi;
    n = dd_from(sg_glass_index(g, lref));
    if (!isfinite(n.hi))
        return NAN;
    nabs = dd_mul(n, air_ref);
    dt = dd_sub(dd_from(temp), dd_from(g->tref));
    /* D0 dT + D1 dT^2 + D2 dT^3 */
    s = dd_mul(dd_add(dd_mul(dd_add(dd_mul_d(dt, g->td[2]), dd_from(g->td[1])), dt),
                      dd_from(g->td[0])),
               dt);
    /* (E0 dT + E1 dT^2) / (L^2 - Ltk^2) */
    e = dd_mul(dd_add(dd_mul_d(dt, g->td[4]), dd_from(g->td[3])), dt);
    l2r = dd_two_prod(lref, lref);
    e = dd_div(e, dd_sub(l2r, dd_two_prod(g->td[5], g->td[5])));
    dn = dd_div(dd_sub(dd_mul(n, n), dd_from(1.0)), dd_mul_d(n, 2.0));
    dn = dd_mul(dn, dd_add(s, e));
    n = dd_div(dd_add(nabs, dn), air_sys);
    if (!isfinite(n.hi) || !(n.hi > 0.0))
        return NAN;
    return n.hi + n.lo;
}

int sg_model_glass(double nd, double vd, double dpgf, sg_glass *out)
{
    /* The g, F, d and C lines (um), as Zemax and SCHOTT take them. */
    static const double lg = 0.4358343, lf = 0.4861327, ld = 0.5875618, lc = 0.6562725;
    double dfc, dgf, u1, v1, u2, v2, det, a, b;
    if (!out)
        return SG_EINVAL;
    if (!(nd >= SG_MODEL_ND_MIN && nd <= SG_MODEL_ND_MAX) ||
        !(vd >= SG_MODEL_VD_MIN && vd <= SG_MODEL_VD_MAX) || !(fabs(dpgf) <= SG_MODEL_DPGF_MAX))
        return SG_ERANGE;
    dfc = (nd - 1.0) / vd;
    dgf = (0.6438 - 0.001682 * vd + dpgf) * dfc;
    /* A (1/L_F - 1/L_C) + B (L_F^-3.5 - L_C^-3.5) = n(F) - n(C), and the
     * same for g and F; then n0 from n(d). */
    u1 = 1.0 / lf - 1.0 / lc;
    v1 = 1.0 / (lf * lf * lf * sqrt(lf)) - 1.0 / (lc * lc * lc * sqrt(lc));
    u2 = 1.0 / lg - 1.0 / lf;
    v2 = 1.0 / (lg * lg * lg * sqrt(lg)) - 1.0 / (lf * lf * lf * sqrt(lf));
    det = u1 * v2 - u2 * v1;
    a = (dfc * v2 - dgf * v1) / det;
    b = (u1 * dgf - u2 * dfc) / det;
    memset(out, 0, sizeof *out);
    sg_strlcpy(out->name, "MODEL", sizeof out->name);
    sg_strlcpy(out->catalog, "MODEL", sizeof out->catalog);
    out->formula = SG_FORMULA_CONRADY;
    out->c[0] = nd - a / ld - b / (ld * ld * ld * sqrt(ld));
    out->c[1] = a;
    out->c[2] = b;
    /* The model is fitted in the visible and meant for it. */
    out->lmin = 0.4;
    out->lmax = 0.75;
    out->nd = nd;
    out->vd = vd;
    out->ed[3] = dpgf;
    out->tref = 20.0;
    return SG_OK;
}

int sg_glass_in_range(const sg_glass *g, double um)
{
    if (!g)
        return 0;
    return um >= g->lmin && um <= g->lmax;
}

/* ------------------------------------------------------------------------
 * AGF reader
 * ------------------------------------------------------------------------ */

/* One line split into whitespace-separated tokens (pointers into the
 * decoded text, not NUL-terminated). */
#define AGF_MAX_TOKENS 24

typedef struct agf_line {
    int ntok; /* may exceed AGF_MAX_TOKENS; only that many are stored */
    const char *tok[AGF_MAX_TOKENS];
    size_t len[AGF_MAX_TOKENS];
} agf_line;

typedef struct agf_ctx {
    const char *path;
    long line;
    sg_diag *d;
} agf_ctx;

static int is_space(int c)
{
    return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == 0x1A;
}

static void split_line(const char *s, size_t n, agf_line *ln)
{
    size_t i = 0;
    ln->ntok = 0;
    while (i < n) {
        size_t start;
        while (i < n && is_space((unsigned char)s[i]))
            i++;
        if (i >= n)
            break;
        start = i;
        while (i < n && !is_space((unsigned char)s[i]))
            i++;
        if (ln->ntok < AGF_MAX_TOKENS) {
            ln->tok[ln->ntok] = s + start;
            ln->len[ln->ntok] = i - start;
        }
        ln->ntok++;
    }
}

static int tok_is(const agf_line *ln, int k, const char *kw)
{
    size_t n = strlen(kw), i;
    if (k >= ln->ntok || ln->len[k] != n)
        return 0;
    for (i = 0; i < n; i++)
        if (ascii_upper((unsigned char)ln->tok[k][i]) != kw[i])
            return 0;
    return 1;
}

/* Quotes at most 40 characters of a token for a message. */
static void tok_quote(const agf_line *ln, int k, char *buf, size_t n)
{
    size_t len = ln->len[k], i, j = 0;
    if (len > 40)
        len = 40;
    for (i = 0; i < len && j + 1 < n; i++) {
        unsigned char c = (unsigned char)ln->tok[k][i];
        buf[j++] = (c >= 0x20 && c < 0x7F) ? (char)c : '?';
    }
    buf[j] = '\0';
    if (ln->len[k] > 40 && j + 4 < n)
        strcat(buf, "...");
}

/* Strict decimal syntax: [+-]digits[.digits][(e|E)[+-]digits], at least one
 * mantissa digit.  strtod alone would also take "nan", "inf" and hex. */
static int decimal_syntax_ok(const char *s)
{
    int digits = 0;
    if (*s == '+' || *s == '-')
        s++;
    while (isdigit((unsigned char)*s)) {
        s++;
        digits++;
    }
    if (*s == '.') {
        s++;
        while (isdigit((unsigned char)*s)) {
            s++;
            digits++;
        }
    }
    if (!digits)
        return 0;
    if (*s == 'e' || *s == 'E') {
        int ed = 0;
        s++;
        if (*s == '+' || *s == '-')
            s++;
        while (isdigit((unsigned char)*s)) {
            s++;
            ed++;
        }
        if (!ed)
            return 0;
    }
    return *s == '\0';
}

static int agf_err(agf_ctx *cx, const char *what)
{
    return sg_diag_set(cx->d, SG_EPARSE, "%s:%ld: %s", cx->path, cx->line,
                       what);
}

/* Parses token k as a finite decimal number; what names the field. */
static int tok_number(agf_ctx *cx, const agf_line *ln, int k, const char *what,
                      double *out)
{
    char buf[AGF_MAX_NUMBER + 1], q[48];
    char *end;
    double v;
    if (k >= ln->ntok || k >= AGF_MAX_TOKENS)
        return sg_diag_set(cx->d, SG_EPARSE, "%s:%ld: missing %s", cx->path,
                           cx->line, what);
    tok_quote(ln, k, q, sizeof q);
    if (ln->len[k] > AGF_MAX_NUMBER)
        return sg_diag_set(cx->d, SG_EPARSE, "%s:%ld: %s: number too long: %s",
                           cx->path, cx->line, what, q);
    memcpy(buf, ln->tok[k], ln->len[k]);
    buf[ln->len[k]] = '\0';
    if (!decimal_syntax_ok(buf))
        return sg_diag_set(cx->d, SG_EPARSE, "%s:%ld: %s: not a number: '%s'",
                           cx->path, cx->line, what, q);
    v = strtod(buf, &end);
    if (*end != '\0' || !isfinite(v))
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: %s: number out of range: %s", cx->path,
                           cx->line, what, q);
    *out = v;
    return SG_OK;
}

/* A growable list of the glasses of one file, merged into the catalog only
 * when the whole file has parsed. */
typedef struct glass_list {
    sg_glass *g;
    size_t n, cap;
    long *nm_line; /* NM line of each glass, for messages */
} glass_list;

static int list_push(glass_list *l)
{
    if (l->n >= AGF_MAX_GLASSES)
        return SG_ERANGE;
    if (l->n == l->cap) {
        size_t ncap = l->cap ? 2 * l->cap : 64;
        sg_glass *p;
        long *q;
        if (ncap > SIZE_MAX / sizeof *p)
            return SG_ENOMEM;
        p = realloc(l->g, ncap * sizeof *p);
        if (!p)
            return SG_ENOMEM;
        l->g = p;
        q = realloc(l->nm_line, ncap * sizeof *q);
        if (!q)
            return SG_ENOMEM;
        l->nm_line = q;
        l->cap = ncap;
    }
    memset(&l->g[l->n], 0, sizeof l->g[0]);
    l->n++;
    return SG_OK;
}

static int parse_nm(agf_ctx *cx, const agf_line *ln, glass_list *l,
                    const char *catname, int *has_cd)
{
    sg_glass *g;
    double f;
    size_t i;
    char q[48];
    int rc;

    if (ln->ntok < 2)
        return agf_err(cx, "NM line without a glass name");
    if (ln->len[1] >= SG_GLASS_NAME) {
        tok_quote(ln, 1, q, sizeof q);
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass name longer than %d characters: %s",
                           cx->path, cx->line, SG_GLASS_NAME - 1, q);
    }
    rc = list_push(l);
    if (rc == SG_ERANGE)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: more than %d glasses in one file",
                           cx->path, cx->line, AGF_MAX_GLASSES);
    if (rc)
        return sg_diag_set(cx->d, rc, "%s: out of memory", cx->path);
    g = &l->g[l->n - 1];
    l->nm_line[l->n - 1] = cx->line;
    for (i = 0; i < ln->len[1]; i++)
        g->name[i] = (char)ascii_upper((unsigned char)ln->tok[1][i]);
    g->name[i] = '\0';
    sg_strlcpy(g->catalog, catname, sizeof g->catalog);
    g->lmin = 0.0;
    g->lmax = INFINITY;
    g->tref = 20.0;

    rc = tok_number(cx, ln, 2, "formula number", &f);
    if (rc)
        return rc;
    if (f != floor(f) || f < SG_FORMULA_SCHOTT || f > SG_FORMULA_EXTENDED3) {
        tok_quote(ln, 2, q, sizeof q);
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: unknown dispersion formula %s "
                           "(expected 1..13)",
                           cx->path, cx->line, g->name, q);
    }
    g->formula = (int)f;
    /* Field 3 is the MIL code, which may carry text; it is not needed. */
    if (ln->ntok < 4)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: missing MIL code", cx->path,
                           cx->line, g->name);
    rc = tok_number(cx, ln, 4, "nd", &g->nd);
    if (rc)
        return rc;
    rc = tok_number(cx, ln, 5, "vd", &g->vd);
    if (rc)
        return rc;
    *has_cd = 0;
    return SG_OK;
}

/* Parses the numbers of a CD line (first = 1) or of a line continuing one
 * (first = 0) into g->c from *nc on; *nc counts the coefficients so far.
 * NIKON's 2019 catalog wraps one CD line (LAF11) onto a second line. */
static int parse_cd(agf_ctx *cx, const agf_line *ln, sg_glass *g, int first, int *nc)
{
    int k, rc, n = ln->ntok - first;
    if (first) {
        memset(g->c, 0, sizeof g->c);
        *nc = 0;
    }
    if (*nc + n > SG_GLASS_NCOEF)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: %d coefficients, at most %d "
                           "allowed",
                           cx->path, cx->line, g->name, *nc + n, SG_GLASS_NCOEF);
    for (k = first; k < ln->ntok; k++) {
        char what[40];
        snprintf(what, sizeof what, "CD coefficient %d", *nc + 1);
        rc = tok_number(cx, ln, k, what, &g->c[*nc]);
        if (rc)
            return rc;
        (*nc)++;
    }
    return SG_OK;
}

/* Zemax reads the coefficients a CD line leaves out as zeros (NIKON's
 * catalog writes 8 numbers for its formula 13 glasses), so a short line is
 * kept; but one that stops inside a term (a Sellmeier K without its L), or
 * before the formula depends on the wavelength at all, is a line cut off:
 * no glass has a constant index.  Per formula (index: sg_formula): the
 * fewest coefficients a line may have, and where its pairs begin (-1:
 * none). */
static const struct {
    signed char min, pairs;
} cd_shape[14] = {
    {0, -1}, {2, -1}, {2, 0}, {2, -1}, {3, 1}, {2, -1}, {2, 0}, {3, -1},
    {3, -1}, {3, 1}, {2, -1}, {2, 0}, {2, -1}, {2, -1},
};

static int cd_complete(agf_ctx *cx, const sg_glass *g, int nc, long cd_line)
{
    int f = g->formula >= 1 && g->formula <= 13 ? g->formula : 0;
    int min = cd_shape[f].min, pairs = cd_shape[f].pairs;
    if (nc >= min && (pairs < 0 || nc <= pairs || (nc - pairs) % 2 == 0))
        return SG_OK;
    return sg_diag_set(cx->d, SG_EPARSE,
                       "%s:%ld: glass %s: CD line has %d coefficient%s, which cuts a term of "
                       "dispersion formula %d short (it needs at least %d%s; coefficients left "
                       "out at the end count as zero, as in Zemax)",
                       cx->path, cd_line, g->name, nc, nc == 1 ? "" : "s", f, min,
                       pairs < 0 ? "" : pairs == 0 ? ", in pairs" : ", then pairs");
}

/* Nonzero when token k is a decimal number, as a continuation line's
 * first token is. */
static int tok_is_number(const agf_line *ln, int k)
{
    char buf[AGF_MAX_NUMBER + 1];
    if (k >= ln->ntok || k >= AGF_MAX_TOKENS || ln->len[k] > AGF_MAX_NUMBER)
        return 0;
    memcpy(buf, ln->tok[k], ln->len[k]);
    buf[ln->len[k]] = '\0';
    return decimal_syntax_ok(buf);
}

static int parse_ld(agf_ctx *cx, const agf_line *ln, sg_glass *g)
{
    double a, b;
    int rc;
    if (ln->ntok != 3)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: LD line needs 2 numbers, has %d",
                           cx->path, cx->line, g->name, ln->ntok - 1);
    rc = tok_number(cx, ln, 1, "LD minimum wavelength", &a);
    if (rc)
        return rc;
    rc = tok_number(cx, ln, 2, "LD maximum wavelength", &b);
    if (rc)
        return rc;
    if (!(a >= 0.0 && a <= b))
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: LD range %g..%g is not an "
                           "interval of wavelengths",
                           cx->path, cx->line, g->name, a, b);
    /* "LD 0 0" (in NHG's catalog) gives no range at all. */
    g->lmin = a;
    g->lmax = b > 0.0 ? b : INFINITY;
    return SG_OK;
}

/* TD D0 D1 D2 E0 E1 Ltk Tref.  Vendors' files also carry TD lines with
 * fewer numbers (SCHOTT 2018 has an empty one, NIKON 2019 four): as in
 * Zemax, a missing coefficient is 0 and a missing Tref 20 C. */
static int parse_td(agf_ctx *cx, const agf_line *ln, sg_glass *g)
{
    static const char *const what[7] = {"TD D0", "TD D1", "TD D2", "TD E0", "TD E1",
                                        "TD lambda_tk", "TD reference temperature"};
    int k, rc;
    if (ln->ntok > 8)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: TD line has %d numbers, at most 7 allowed",
                           cx->path, cx->line, g->name, ln->ntok - 1);
    memset(g->td, 0, sizeof g->td);
    g->tref = 20.0;
    for (k = 0; k + 1 < ln->ntok; k++)
        if ((rc = tok_number(cx, ln, k + 1, what[k], k < 6 ? &g->td[k] : &g->tref)) != SG_OK)
            return rc;
    if (!(g->tref >= SG_TEMP_MIN && g->tref <= SG_TEMP_MAX))
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: TD reference temperature %g C is outside "
                           "%g to %g C",
                           cx->path, cx->line, g->name, g->tref, SG_TEMP_MIN, SG_TEMP_MAX);
    g->has_td = 1;
    return SG_OK;
}

/* ED TCE(-30..70) TCE(100..300) density dPgF [ignore-thermal-expansion
 * flag ...]: the first four numbers (0 for a "-") and the flag are kept;
 * vendors append one or two flags. */
static int parse_ed(agf_ctx *cx, const agf_line *ln, sg_glass *g)
{
    static const char *const what[4] = {"ED expansion -30..70 C", "ED expansion 100..300 C",
                                        "ED density", "ED dPgF"};
    int k, rc;
    if (ln->ntok < 5)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: glass %s: ED line needs at least 4 numbers, has %d",
                           cx->path, cx->line, g->name, ln->ntok - 1);
    for (k = 0; k < 4; k++) {
        /* SCHOTT writes "-" for a figure it does not give. */
        if (ln->len[k + 1] == 1 && ln->tok[k + 1][0] == '-') {
            g->ed[k] = 0.0;
            continue;
        }
        if ((rc = tok_number(cx, ln, k + 1, what[k], &g->ed[k])) != SG_OK)
            return rc;
    }
    g->ignore_expansion = 0;
    if (ln->ntok > 5 && !(ln->len[5] == 1 && ln->tok[5][0] == '-')) {
        double flag;
        if ((rc = tok_number(cx, ln, 5, "ED ignore-thermal-expansion flag", &flag)) != SG_OK)
            return rc;
        g->ignore_expansion = flag != 0.0;
    }
    g->has_ed = 1;
    return SG_OK;
}

/* Rejects bytes that never occur in a text catalog.  Bytes >= 0x80 are
 * allowed: comment lines often carry Latin-1 or UTF-8 text. */
static int check_text(agf_ctx *cx, const char *s, size_t n)
{
    size_t i;
    long line = 1;
    for (i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '\n' || (c == '\r' && (i + 1 >= n || s[i + 1] != '\n')))
            line++;
        else if (c < 0x20 && c != '\t' && c != '\r' && !is_space(c))
            return sg_diag_set(cx->d, SG_EPARSE,
                               "%s:%ld: binary byte 0x%02X: not a text AGF "
                               "catalog",
                               cx->path, line, c);
        else if (c == 0x7F)
            return sg_diag_set(cx->d, SG_EPARSE,
                               "%s:%ld: binary byte 0x7F: not a text AGF "
                               "catalog",
                               cx->path, line);
    }
    return SG_OK;
}

/* Turns UTF-16 text (after its byte-order mark) into ASCII in place; code
 * units outside ASCII become '?', which only comments contain. */
static int utf16_to_ascii(agf_ctx *cx, char *buf, size_t *len, int little)
{
    size_t i, n = *len, j = 0;
    if (n % 2)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s: odd number of bytes in a UTF-16 file",
                           cx->path);
    for (i = 2; i + 1 < n; i += 2) {
        unsigned lo = (unsigned char)buf[i + (little ? 0 : 1)];
        unsigned hi = (unsigned char)buf[i + (little ? 1 : 0)];
        unsigned u = lo | hi << 8;
        buf[j++] = u < 0x80 ? (char)u : '?';
    }
    *len = j;
    return SG_OK;
}

static int read_file(const char *path, char **out, size_t *outlen, sg_diag *d)
{
    FILE *f;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int err;

    *out = NULL;
    *outlen = 0;
    f = fopen(path, "rb");
    if (!f)
        return sg_diag_set(d, SG_EIO, "%s: cannot open: %s", path,
                           strerror(errno));
    for (;;) {
        size_t got;
        if (len == cap) {
            /* The buffer stops one byte past the limit, so a file that
             * fills it is too large without reading any further. */
            size_t ncap = cap ? 2 * cap : 65536;
            char *p;
            if (ncap > AGF_MAX_BYTES + 1)
                ncap = AGF_MAX_BYTES + 1;
            if (cap > AGF_MAX_BYTES) {
                free(buf);
                fclose(f);
                return sg_diag_set(d, SG_EIO,
                                   "%s: larger than %zu MiB; not a glass "
                                   "catalog",
                                   path, AGF_MAX_BYTES >> 20);
            }
            p = realloc(buf, ncap + 1);
            if (!p) {
                free(buf);
                fclose(f);
                return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
            }
            buf = p;
            cap = ncap;
        }
        got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0)
            break;
    }
    err = ferror(f) ? errno : 0;
    fclose(f);
    if (err || len > AGF_MAX_BYTES) {
        free(buf);
        if (err)
            return sg_diag_set(d, SG_EIO, "%s: read error: %s", path,
                               strerror(err));
        return sg_diag_set(d, SG_EIO,
                           "%s: larger than %zu MiB; not a glass catalog",
                           path, AGF_MAX_BYTES >> 20);
    }
    buf[len] = '\0';
    *out = buf;
    *outlen = len;
    return SG_OK;
}

/* The file stem, upper-cased: "/x/Schott.agf" gives "SCHOTT". */
static void catalog_name(const char *path, char *name, size_t n)
{
    const char *base = strrchr(path, '/');
    const char *dot;
    size_t len, i;
    base = base ? base + 1 : path;
    dot = strrchr(base, '.');
    len = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    if (len >= n)
        len = n - 1;
    for (i = 0; i < len; i++)
        name[i] = (char)ascii_upper((unsigned char)base[i]);
    name[len] = '\0';
}

static int parse_text(agf_ctx *cx, const char *s, size_t n, glass_list *l,
                      const char *catname)
{
    size_t pos = 0;
    int has_cd = 0, rc, in_cd = 0, ncd = 0;
    long cd_line = 0;
    agf_line ln;

    cx->line = 0;
    while (pos < n) {
        size_t start = pos, end;
        while (pos < n && s[pos] != '\n' && s[pos] != '\r')
            pos++;
        end = pos;
        /* A line ends at LF, CRLF or a lone CR. */
        if (pos < n && s[pos] == '\r') {
            pos++;
            if (pos < n && s[pos] == '\n')
                pos++;
        } else if (pos < n) {
            pos++;
        }
        cx->line++;

        split_line(s + start, end - start, &ln);
        if (ln.ntok == 0)
            continue;
        /* A line of numbers right after a CD line continues it. */
        if (in_cd && tok_is_number(&ln, 0)) {
            rc = parse_cd(cx, &ln, &l->g[l->n - 1], 0, &ncd);
            if (rc)
                return rc;
            continue;
        }
        in_cd = tok_is(&ln, 0, "CD");
        if (tok_is(&ln, 0, "NM")) {
            if (l->n > 0 && !has_cd)
                return sg_diag_set(cx->d, SG_EPARSE,
                                   "%s:%ld: glass %s has no CD line",
                                   cx->path, l->nm_line[l->n - 1],
                                   l->g[l->n - 1].name);
            if (l->n > 0 && (rc = cd_complete(cx, &l->g[l->n - 1], ncd, cd_line)) != SG_OK)
                return rc;
            rc = parse_nm(cx, &ln, l, catname, &has_cd);
        } else if (tok_is(&ln, 0, "CD")) {
            if (l->n == 0)
                return agf_err(cx, "CD line before any NM line");
            rc = parse_cd(cx, &ln, &l->g[l->n - 1], 1, &ncd);
            has_cd = 1;
            cd_line = cx->line;
        } else if (tok_is(&ln, 0, "LD")) {
            if (l->n == 0)
                return agf_err(cx, "LD line before any NM line");
            rc = parse_ld(cx, &ln, &l->g[l->n - 1]);
        } else if (tok_is(&ln, 0, "TD")) {
            if (l->n == 0)
                return agf_err(cx, "TD line before any NM line");
            rc = parse_td(cx, &ln, &l->g[l->n - 1]);
        } else if (tok_is(&ln, 0, "ED")) {
            if (l->n == 0)
                return agf_err(cx, "ED line before any NM line");
            rc = parse_ed(cx, &ln, &l->g[l->n - 1]);
        } else {
            /* CC, GC, OD, IT, BD, '!' comments and anything newer carry
             * data the ray trace does not use. */
            rc = SG_OK;
        }
        if (rc)
            return rc;
    }
    if (l->n == 0)
        return sg_diag_set(cx->d, SG_EPARSE,
                           "%s:%ld: no NM line: not an AGF glass catalog",
                           cx->path, cx->line > 0 ? cx->line : 1L);
    if (!has_cd)
        return sg_diag_set(cx->d, SG_EPARSE, "%s:%ld: glass %s has no CD line",
                           cx->path, l->nm_line[l->n - 1], l->g[l->n - 1].name);
    return cd_complete(cx, &l->g[l->n - 1], ncd, cd_line);
}

int sg_catalog_load_agf(sg_catalog *cat, const char *path, sg_diag *d)
{
    char *buf = NULL;
    size_t len = 0, i;
    char catname[SG_GLASS_NAME];
    glass_list l = {NULL, 0, 0, NULL};
    agf_ctx cx;
    const char *text;
    locale_t cloc, old = (locale_t)0;
    int rc;

    if (!cat || !path)
        return sg_diag_set(d, SG_EINVAL, "sg_catalog_load_agf: NULL argument");
    cx.path = path;
    cx.line = 0;
    cx.d = d;

    rc = read_file(path, &buf, &len, d);
    if (rc)
        return rc;
    text = buf;
    if (len >= 2 && (unsigned char)buf[0] == 0xFF &&
        (unsigned char)buf[1] == 0xFE)
        rc = utf16_to_ascii(&cx, buf, &len, 1);
    else if (len >= 2 && (unsigned char)buf[0] == 0xFE &&
             (unsigned char)buf[1] == 0xFF)
        rc = utf16_to_ascii(&cx, buf, &len, 0);
    else if (len >= 3 && (unsigned char)buf[0] == 0xEF &&
             (unsigned char)buf[1] == 0xBB && (unsigned char)buf[2] == 0xBF) {
        text = buf + 3;
        len -= 3;
    }
    if (!rc)
        rc = check_text(&cx, text, len);
    if (rc) {
        free(buf);
        return rc;
    }

    /* Catalog numbers use '.', whatever LC_NUMERIC the program set; the
     * C locale is installed for this thread only while parsing. */
    cloc = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (cloc)
        old = uselocale(cloc);
    catalog_name(path, catname, sizeof catname);
    rc = parse_text(&cx, text, len, &l, catname);
    if (cloc) {
        uselocale(old);
        freelocale(cloc);
    }
    free(buf);

    for (i = 0; rc == SG_OK && i < l.n; i++) {
        rc = catalog_put(cat, &l.g[i]);
        if (rc)
            sg_diag_set(d, rc, "%s: out of memory", path);
    }
    free(l.g);
    free(l.nm_line);
    return rc;
}

static int has_agf_suffix(const char *name)
{
    size_t n = strlen(name);
    return n > 4 && name[n - 4] == '.' &&
           ascii_upper((unsigned char)name[n - 3]) == 'A' &&
           ascii_upper((unsigned char)name[n - 2]) == 'G' &&
           ascii_upper((unsigned char)name[n - 1]) == 'F';
}

static int cmp_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static char *dup_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = malloc(n);
    if (p)
        memcpy(p, s, n);
    return p;
}

int sg_catalog_load_dir(sg_catalog *cat, const char *dir, sg_diag *d)
{
    DIR *dp;
    struct dirent *e;
    char **names = NULL;
    size_t n = 0, cap = 0, i;
    int rc = SG_OK;

    if (!cat || !dir)
        return sg_diag_set(d, SG_EINVAL, "sg_catalog_load_dir: NULL argument");
    dp = opendir(dir);
    if (!dp)
        return sg_diag_set(d, SG_EIO, "%s: cannot open directory: %s", dir,
                           strerror(errno));
    while ((e = readdir(dp)) != NULL) {
        if (!has_agf_suffix(e->d_name))
            continue;
        if (n == cap) {
            size_t ncap = cap ? 2 * cap : 16;
            char **p = realloc(names, ncap * sizeof *p);
            if (!p) {
                rc = SG_ENOMEM;
                break;
            }
            names = p;
            cap = ncap;
        }
        names[n] = dup_string(e->d_name);
        if (!names[n]) {
            rc = SG_ENOMEM;
            break;
        }
        n++;
    }
    closedir(dp);
    if (rc)
        sg_diag_set(d, rc, "%s: out of memory", dir);
    else
        qsort(names, n, sizeof *names, cmp_names);

    for (i = 0; rc == SG_OK && i < n; i++) {
        size_t len = strlen(dir) + strlen(names[i]) + 2;
        char *path = malloc(len);
        struct stat st;
        if (!path) {
            rc = sg_diag_set(d, SG_ENOMEM, "%s: out of memory", dir);
            break;
        }
        snprintf(path, len, "%s/%s", dir, names[i]);
        /* A directory or device that happens to end in .agf is skipped. */
        if (stat(path, &st) == 0 && S_ISREG(st.st_mode))
            rc = sg_catalog_load_agf(cat, path, d);
        free(path);
    }
    for (i = 0; i < n; i++)
        free(names[i]);
    free(names);
    if (rc == SG_OK && n == 0)
        sg_diag_warn(d, "%s: no .agf catalog files", dir);
    return rc;
}

static int is_dir(const char *p)
{
    struct stat st;
    return p && *p && stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

int sg_catalog_load_default(sg_catalog *cat, sg_diag *d)
{
    const char *env, *use = NULL;
    char *copy, found[4096];

    if (!cat)
        return sg_diag_set(d, SG_EINVAL,
                           "sg_catalog_load_default: NULL catalog");
    env = getenv("SAGITTA_LENSDB");
    if (env && *env && is_dir(env))
        use = env;
    if (!use)
        use = sg_data_dir("lensdb", found, sizeof found);
    /* The user asked for other catalogs: say that these are not them. */
    if (env && *env && use != env && use)
        sg_diag_warn(d, "SAGITTA_LENSDB=%s is not a directory; using the bundled catalogs "
                        "in %s instead", env, use);
    else if (env && *env && use != env)
        sg_diag_warn(d, "SAGITTA_LENSDB=%s is not a directory", env);
    if (!use)
        return sg_diag_set(d, SG_EIO,
                           "no glass catalog directory found (tried "
                           "$SAGITTA_LENSDB=%s, the lensdb beside the program, %s)",
                           env && *env ? env : "(unset)", SG_INSTALL_LENSDB);
    copy = dup_string(use);
    if (!copy)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    free(cat->dir);
    cat->dir = copy;
    return sg_catalog_load_dir(cat, use, d);
}
