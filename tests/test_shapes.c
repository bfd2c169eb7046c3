/*
 * test_shapes.c - the conformance test of every surface shape behind the
 * surface-kernel interface (src/shape/shape.h), against each shape's definition
 * written here again in 512-bit MPFR.
 *
 * The reference follows the definitions as sagitta-design(5) states them,
 * not the engine's forms: the toroid as a curve turned about its axis
 * (z = Rr - sgn sqrt((Rr - zy)^2 - x^2)), Zernike terms in polar form
 * from their own (n, m) tables and the factorial formula of the radial
 * polynomial with cos and sin of atan2, XY terms by their monomials.  Its
 * gradients are central differences at 2^-150; its intersections Newton
 * in 512 bits; its refraction the vector law.
 *
 * The shapes come from the registry (sg_shape_ops_of over SG_SURF_TYPES);
 * each gives its reference and its random surfaces in one row of
 * shape_cases, and a registered shape without a row fails the test.
 *
 * Checked for every registered shape:
 *   - the kernel: at random points, the double-double sag and gradient
 *     within the bounds the shape reports, its second-derivative bound
 *     not below the Hessian's row sums, and the MPFR sag to 2^-400;
 *   - the trace: random rays (ordinary, grazing, at 1e-3 and 1e4 mm),
 *     where precise and mpfr points and directions lie within their
 *     bounds of the reference, precise's ordinary rays are the reference
 *     rounded, and no method marks a non-finite row OK;
 *   - reductions: a Zernike or XY surface with no terms, a biconic with
 *     equal sections and a toroid whose radius of rotation is its radius
 *     trace bit for bit as the conic or sphere they are.
 *
 * Half the random Zernike surfaces are decentred (their terms about
 * Zemax's Decenter X, Y; the reference shifts the point before its polar
 * form).  A closed form: Fringe Z1 + Z4 decentred is a paraboloid off the
 * vertex, whose sag and slope are checked against the formula in MPFR and
 * whose focus every axial ray must reach.
 */
#include <math.h>
#include <mpfr.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "shape_vd.h"
#include "shape_vdd.h"
#include "testutil.h"
#include "trace_int.h"

#define PREC 512

static uint64_t rng_state;

static double urand(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * 0x1.0p-53;
}

static double srand1(double a)
{
    return a * (2.0 * urand() - 1.0);
}

/* ------------------------------------------------------------------------
 * The reference sag, from the definitions.
 * ------------------------------------------------------------------------ */

/* Fringe (n, m): the University of Arizona table; m < 0 is the sine. */
static const int fringe_nm[37][2] = {
    {0, 0},  {1, 1},  {1, -1}, {2, 0},  {2, 2},  {2, -2}, {3, 1},  {3, -1}, {4, 0},  {3, 3},
    {3, -3}, {4, 2},  {4, -2}, {5, 1},  {5, -1}, {6, 0},  {4, 4},  {4, -4}, {5, 3},  {5, -3},
    {6, 2},  {6, -2}, {7, 1},  {7, -1}, {8, 0},  {5, 5},  {5, -5}, {6, 4},  {6, -4}, {7, 3},
    {7, -3}, {8, 2},  {8, -2}, {9, 1},  {9, -1}, {10, 0}, {12, 0}};

/* Noll's j to (n, m): row n holds j = n(n+1)/2 + 1 ... ; even j the
 * cosine. */
static void noll_nm(int j, int *n, int *m)
{
    int nn = 0, p, am;
    while ((nn + 1) * (nn + 2) / 2 < j)
        nn++;
    p = j - nn * (nn + 1) / 2;
    am = nn % 2 == 0 ? 2 * (p / 2) : 2 * ((p - 1) / 2) + 1;
    *n = nn;
    *m = am == 0 ? 0 : (j % 2 == 0 ? am : -am);
}

static void mfact(mpfr_t r, int n)
{
    mpfr_fac_ui(r, (unsigned long)n, MPFR_RNDN);
}

/* Zernike term (n, m) at (rho, theta) into z. */
static void zern_ref(mpfr_t z, int n, int m, const mpfr_t rho, const mpfr_t th)
{
    mpfr_t a, b, c, p;
    int am = abs(m), s;
    mpfr_inits2(PREC, a, b, c, p, (mpfr_ptr)0);
    mpfr_set_zero(z, 1);
    for (s = 0; s <= (n - am) / 2; s++) {
        mfact(a, n - s);
        mfact(b, s);
        mpfr_div(a, a, b, MPFR_RNDN);
        mfact(b, (n + am) / 2 - s);
        mpfr_div(a, a, b, MPFR_RNDN);
        mfact(b, (n - am) / 2 - s);
        mpfr_div(a, a, b, MPFR_RNDN);
        mpfr_pow_ui(p, rho, (unsigned long)(n - 2 * s), MPFR_RNDN);
        mpfr_mul(a, a, p, MPFR_RNDN);
        if (s % 2)
            mpfr_sub(z, z, a, MPFR_RNDN);
        else
            mpfr_add(z, z, a, MPFR_RNDN);
    }
    if (m != 0) {
        mpfr_mul_si(c, th, am, MPFR_RNDN);
        if (m > 0)
            mpfr_cos(c, c, MPFR_RNDN);
        else
            mpfr_sin(c, c, MPFR_RNDN);
        mpfr_mul(z, z, c, MPFR_RNDN);
    }
    mpfr_clears(a, b, c, p, (mpfr_ptr)0);
}

/* The conic section c r^2 / (1 + sqrt(1 - (1 + k) c^2 r^2)) at r2, with c
 * = 1 / R; returns 0 outside it. */
static int conic_ref(mpfr_t z, double R, double k, const mpfr_t r2)
{
    mpfr_t c, q;
    int ok = 1;
    if (!isfinite(R) || R == 0.0) {
        mpfr_set_zero(z, 1);
        return 1;
    }
    mpfr_inits2(PREC, c, q, (mpfr_ptr)0);
    mpfr_set_ui(c, 1, MPFR_RNDN);
    mpfr_div_d(c, c, R, MPFR_RNDN);
    mpfr_sqr(q, c, MPFR_RNDN);
    mpfr_mul(q, q, r2, MPFR_RNDN);
    mpfr_mul_d(q, q, 1.0 + k, MPFR_RNDN); /* 1 + k exact for the k used here */
    mpfr_ui_sub(q, 1, q, MPFR_RNDN);
    if (mpfr_sgn(q) < 0)
        ok = 0;
    else {
        mpfr_sqrt(q, q, MPFR_RNDN);
        mpfr_add_ui(q, q, 1, MPFR_RNDN);
        mpfr_mul(z, c, r2, MPFR_RNDN);
        mpfr_div(z, z, q, MPFR_RNDN);
    }
    mpfr_clears(c, q, (mpfr_ptr)0);
    return ok;
}

/* The even polynomial a_k r^(2k+2) added to z. */
static void even_ref(mpfr_t z, const double *a, int n, const mpfr_t r2)
{
    mpfr_t p, t;
    int k;
    mpfr_inits2(PREC, p, t, (mpfr_ptr)0);
    mpfr_set(p, r2, MPFR_RNDN);
    for (k = 0; k < n; k++) {
        mpfr_mul_d(t, p, a[k], MPFR_RNDN);
        mpfr_add(z, z, t, MPFR_RNDN);
        mpfr_mul(p, p, r2, MPFR_RNDN);
    }
    mpfr_clears(p, t, (mpfr_ptr)0);
}

/* ------------------------------------------------------------------------
 * Each shape's reference sag, from its definition, at (x, y) with r2 =
 * x^2 + y^2 (0 outside the shape), and its random surfaces, scaled by s
 * (lengths times s; the sag scales with them).  random_shape has set a
 * base radius and conic and zeroed the rest.
 * ------------------------------------------------------------------------ */

static int odd_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2, mpfr_t z)
{
    mpfr_t t, u;
    int ok, k;
    (void)x;
    (void)y;
    mpfr_inits2(PREC, t, u, (mpfr_ptr)0);
    ok = conic_ref(z, f->radius, f->conic, r2);
    mpfr_sqrt(u, r2, MPFR_RNDN);
    for (k = 0; k < SG_NODD; k++) {
        mpfr_pow_ui(t, u, (unsigned long)(k + 1), MPFR_RNDN);
        mpfr_mul_d(t, t, f->odd[k], MPFR_RNDN);
        mpfr_add(z, z, t, MPFR_RNDN);
    }
    mpfr_clears(t, u, (mpfr_ptr)0);
    return ok;
}

static void odd_random(sg_surface *f, double s)
{
    int k;
    /* b_i r^i at r = 10 s stays below about 0.05 s. */
    for (k = 0; k < SG_NODD; k++)
        f->odd[k] = srand1(0.05) * s / pow(10.0 * s, k + 1);
}

static int tor_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2, mpfr_t z)
{
    mpfr_t y2, zy, t, u, x2;
    int ok;
    (void)r2;
    mpfr_inits2(PREC, y2, zy, t, u, x2, (mpfr_ptr)0);
    mpfr_sqr(y2, y, MPFR_RNDN);
    ok = conic_ref(zy, f->radius, f->conic, y2);
    even_ref(zy, f->asph, 7, y2);
    if (!isfinite(f->radius_x) || f->radius_x == 0.0) {
        mpfr_set(z, zy, MPFR_RNDN);
    } else {
        /* Turned about the axis at Rr: z = Rr - sgn(Rr - zy) sqrt((Rr - zy)^2 - x^2). */
        mpfr_d_sub(u, f->radius_x, zy, MPFR_RNDN);
        mpfr_sqr(t, u, MPFR_RNDN);
        mpfr_sqr(x2, x, MPFR_RNDN);
        mpfr_sub(t, t, x2, MPFR_RNDN);
        if (mpfr_sgn(t) < 0)
            ok = 0;
        else {
            mpfr_sqrt(t, t, MPFR_RNDN);
            if (mpfr_sgn(u) < 0)
                mpfr_neg(t, t, MPFR_RNDN);
            mpfr_d_sub(z, f->radius_x, t, MPFR_RNDN);
        }
    }
    mpfr_clears(y2, zy, t, u, x2, (mpfr_ptr)0);
    return ok;
}

static void tor_random(sg_surface *f, double s)
{
    int k;
    f->radius_x = urand() < 0.2 ? INFINITY
                                : (urand() < 0.5 ? -1.0 : 1.0) * (15.0 + 100.0 * urand()) * s;
    for (k = 0; k < 3; k++)
        f->asph[k] = srand1(0.05) * s / pow(10.0 * s, 2 * k + 2);
}

static int bic_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2, mpfr_t z)
{
    mpfr_t cx, cy, N, Q, t;
    int ok = 1;
    (void)r2;
    mpfr_inits2(PREC, cx, cy, N, Q, t, (mpfr_ptr)0);
    mpfr_set_ui(cx, 1, MPFR_RNDN);
    mpfr_set_ui(cy, 1, MPFR_RNDN);
    if (isfinite(f->radius_x) && f->radius_x != 0.0)
        mpfr_div_d(cx, cx, f->radius_x, MPFR_RNDN);
    else
        mpfr_set_zero(cx, 1);
    if (isfinite(f->radius) && f->radius != 0.0)
        mpfr_div_d(cy, cy, f->radius, MPFR_RNDN);
    else
        mpfr_set_zero(cy, 1);
    mpfr_sqr(t, x, MPFR_RNDN);
    mpfr_mul(N, cx, t, MPFR_RNDN);
    mpfr_mul(Q, N, cx, MPFR_RNDN);
    mpfr_mul_d(Q, Q, 1.0 + f->conic_x, MPFR_RNDN);
    mpfr_sqr(t, y, MPFR_RNDN);
    mpfr_mul(t, t, cy, MPFR_RNDN);
    mpfr_add(N, N, t, MPFR_RNDN);
    mpfr_mul(t, t, cy, MPFR_RNDN);
    mpfr_mul_d(t, t, 1.0 + f->conic, MPFR_RNDN);
    mpfr_add(Q, Q, t, MPFR_RNDN);
    mpfr_ui_sub(Q, 1, Q, MPFR_RNDN);
    if (mpfr_sgn(Q) < 0)
        ok = 0;
    else {
        mpfr_sqrt(Q, Q, MPFR_RNDN);
        mpfr_add_ui(Q, Q, 1, MPFR_RNDN);
        mpfr_div(z, N, Q, MPFR_RNDN);
    }
    mpfr_clears(cx, cy, N, Q, t, (mpfr_ptr)0);
    return ok;
}

static void bic_random(sg_surface *f, double s)
{
    f->radius_x = urand() < 0.2 ? INFINITY
                                : (urand() < 0.5 ? -1.0 : 1.0) * (20.0 + 80.0 * urand()) * s;
    f->conic_x = srand1(2.0);
}

static int zern_sag_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2,
                        mpfr_t z)
{
    mpfr_t rho, th, zt, t, u;
    int ok, k;
    mpfr_inits2(PREC, rho, th, zt, t, u, (mpfr_ptr)0);
    ok = conic_ref(z, f->radius, f->conic, r2);
    even_ref(z, f->asph, SG_NASPH, r2);
    /* The terms about the decenter (Zemax's Decenter X, Y), the conic and
     * r^n terms about the vertex. */
    mpfr_sub_d(u, x, f->zern_dx, MPFR_RNDN);
    mpfr_sub_d(t, y, f->zern_dy, MPFR_RNDN);
    mpfr_hypot(rho, u, t, MPFR_RNDN);
    mpfr_div_d(rho, rho, f->norm_radius, MPFR_RNDN);
    mpfr_atan2(th, t, u, MPFR_RNDN);
    for (k = 0; k < SG_NTERMS; k++) {
        int n, m;
        if (f->terms[k] == 0.0)
            continue;
        if (f->type == SG_SURF_ZERNIKE_FRINGE) {
            n = fringe_nm[k][0];
            m = fringe_nm[k][1];
        } else {
            noll_nm(k + 1, &n, &m);
        }
        zern_ref(zt, n, m, rho, th);
        if (f->type == SG_SURF_ZERNIKE_STANDARD) {
            mpfr_set_ui(t, (unsigned long)(m == 0 ? n + 1 : 2 * (n + 1)), MPFR_RNDN);
            mpfr_sqrt(t, t, MPFR_RNDN);
            mpfr_mul(zt, zt, t, MPFR_RNDN);
        }
        mpfr_mul_d(zt, zt, f->terms[k], MPFR_RNDN);
        mpfr_add(z, z, zt, MPFR_RNDN);
    }
    mpfr_clears(rho, th, zt, t, u, (mpfr_ptr)0);
    return ok;
}

static void zern_random(sg_surface *f, double s)
{
    int k;
    f->norm_radius = (8.0 + 4.0 * urand()) * s;
    for (k = 0; k < (f->type == SG_SURF_ZERNIKE_FRINGE ? 37 : SG_NTERMS); k++)
        if (urand() < 0.5)
            f->terms[k] = srand1(0.02) * s / (1.0 + k);
    f->asph[1] = srand1(1e-6) / (s * s * s);
    /* Half of them decentred: the terms about (dx, dy), the conic and r^n
     * terms about the vertex. */
    if (urand() < 0.5) {
        f->zern_dx = srand1(2.0) * s;
        f->zern_dy = srand1(2.0) * s;
    }
}

static int xy_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2, mpfr_t z)
{
    mpfr_t uu, vv, pa, pb;
    int n = 1, ok, k;
    mpfr_inits2(PREC, uu, vv, pa, pb, (mpfr_ptr)0);
    ok = conic_ref(z, f->radius, f->conic, r2);
    mpfr_div_d(uu, x, f->norm_radius, MPFR_RNDN);
    mpfr_div_d(vv, y, f->norm_radius, MPFR_RNDN);
    for (k = 0; k < SG_NTERMS; k++) {
        /* Term k + 1: order n holds terms n(n+1)/2 ... n(n+1)/2 + n. */
        int j = k + 1, i;
        while ((n + 1) * (n + 2) / 2 <= j)
            n++;
        i = j - n * (n + 1) / 2;
        if (f->terms[k] == 0.0)
            continue;
        mpfr_pow_ui(pa, uu, (unsigned long)(n - i), MPFR_RNDN);
        mpfr_pow_ui(pb, vv, (unsigned long)i, MPFR_RNDN);
        mpfr_mul(pa, pa, pb, MPFR_RNDN);
        mpfr_mul_d(pa, pa, f->terms[k], MPFR_RNDN);
        mpfr_add(z, z, pa, MPFR_RNDN);
    }
    mpfr_clears(uu, vv, pa, pb, (mpfr_ptr)0);
    return ok;
}

static void xy_random(sg_surface *f, double s)
{
    int k;
    f->norm_radius = (8.0 + 4.0 * urand()) * s;
    for (k = 0; k < 65; k++)
        if (urand() < 0.5)
            f->terms[k] = srand1(0.02) * s / (1.0 + k);
}

/* The Q-type asphere (Forbes' Qcon): the conic plus u^4 sum a_m
 * P_m^(0,4)(2 u^2 - 1), u = r / rn, each Jacobi polynomial from its
 * explicit sum (Abramowitz and Stegun 22.3.2: P_m^(0,4)(t) = sum_s C(m,
 * m - s) C(m + 4, s) ((t - 1) / 2)^s ((t + 1) / 2)^(m - s)), not the
 * engine's recurrence. */
/* C(n, k), exact in double for the n used here. */
static double choose(int n, int k)
{
    double r = 1.0;
    int i;
    for (i = 1; i <= k; i++)
        r = r * (n - k + i) / i;
    return r;
}

static int qcon_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2,
                    mpfr_t z)
{
    mpfr_t u2, u2m, P, t, q;
    int ok, m, k;
    (void)x;
    (void)y;
    mpfr_inits2(PREC, u2, u2m, P, t, q, (mpfr_ptr)0);
    ok = conic_ref(z, f->radius, f->conic, r2);
    mpfr_div_d(u2, r2, f->norm_radius, MPFR_RNDN);
    mpfr_div_d(u2, u2, f->norm_radius, MPFR_RNDN);
    mpfr_sub_ui(u2m, u2, 1, MPFR_RNDN);
    for (m = 0; m < SG_NTERMS; m++) {
        if (f->terms[m] == 0.0)
            continue;
        mpfr_set_zero(P, 1);
        for (k = 0; k <= m; k++) {
            /* C(m, m - k) C(m + 4, k) (u^2 - 1)^k u^(2(m - k)) */
            mpfr_set_d(t, choose(m, m - k) * choose(m + 4, k), MPFR_RNDN);
            mpfr_pow_ui(q, u2m, (unsigned long)k, MPFR_RNDN);
            mpfr_mul(t, t, q, MPFR_RNDN);
            mpfr_pow_ui(q, u2, (unsigned long)(m - k), MPFR_RNDN);
            mpfr_mul(t, t, q, MPFR_RNDN);
            mpfr_add(P, P, t, MPFR_RNDN);
        }
        mpfr_sqr(q, u2, MPFR_RNDN);
        mpfr_mul(P, P, q, MPFR_RNDN);
        mpfr_mul_d(P, P, f->terms[m], MPFR_RNDN);
        mpfr_add(z, z, P, MPFR_RNDN);
    }
    mpfr_clears(u2, u2m, P, t, q, (mpfr_ptr)0);
    return ok;
}

static void qcon_random(sg_surface *f, double s)
{
    int k;
    f->norm_radius = (8.0 + 4.0 * urand()) * s;
    /* Up to a_7: beyond the normalization radius (the points reach 1.6
     * of it) P_m grows as 7.9^m. */
    for (k = 0; k < 8; k++)
        if (urand() < 0.6)
            f->terms[k] = srand1(0.02) * s / ((1.0 + k) * (1.0 + k));
}

/* Every type with a shape of its own (sg_shape_ops_of) has its row here:
 * the reference and the random surfaces; rx: it has an x radius (made
 * equal to the radius for the vector tests' rim lanes), rim_x: its domain
 * ends at the x radius rather than the radius; vec: shape_vd.h and
 * shape_vdd.h have its kernels on lanes (else the traces call its scalar
 * ones lane by lane, and the vector tests skip it). */
typedef struct shape_case {
    int type;
    int (*ref)(const sg_surface *f, const mpfr_t x, const mpfr_t y, const mpfr_t r2, mpfr_t z);
    void (*random)(sg_surface *f, double s);
    int rx, rim_x, vec;
} shape_case;

static const shape_case shape_cases[] = {
    {SG_SURF_ODDASPH, odd_ref, odd_random, 0, 0, 1},
    {SG_SURF_TOROIDAL, tor_ref, tor_random, 1, 1, 1},
    {SG_SURF_BICONIC, bic_ref, bic_random, 1, 0, 1},
    {SG_SURF_ZERNIKE_FRINGE, zern_sag_ref, zern_random, 0, 0, 1},
    {SG_SURF_ZERNIKE_STANDARD, zern_sag_ref, zern_random, 0, 0, 1},
    {SG_SURF_XYPOLY, xy_ref, xy_random, 0, 0, 1},
    {SG_SURF_QCON, qcon_ref, qcon_random, 0, 0, 0},
};

/* The row of a registered shape's type (find_shapes has checked that
 * every one has a row). */
static const shape_case *case_of(int type)
{
    size_t i;
    for (i = 0; i < sizeof shape_cases / sizeof shape_cases[0]; i++)
        if (shape_cases[i].type == type)
            return &shape_cases[i];
    return NULL;
}

/* The registered shapes, in the order of SG_SURF_TYPES: the types with
 * ops: n_shapes of them (find_shapes). */
static int shape_types[SG_SURF_NTYPES];
static int n_shapes;

static int find_shapes(void)
{
    int t;
    n_shapes = 0;
    for (t = 0; t < SG_SURF_NTYPES; t++)
        if (sg_shape_ops_of(t)) {
            if (!case_of(t)) {
                fprintf(stderr, "type %d has a shape (sg_shape_ops_of) and no row in "
                        "shape_cases\n", t);
                return 0;
            }
            shape_types[n_shapes++] = t;
        }
    return 1;
}

static int sag_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, mpfr_t z)
{
    mpfr_t r2, t;
    int ok;
    mpfr_inits2(PREC, r2, t, (mpfr_ptr)0);
    mpfr_sqr(r2, x, MPFR_RNDN);
    mpfr_sqr(t, y, MPFR_RNDN);
    mpfr_add(r2, r2, t, MPFR_RNDN);
    ok = case_of(f->type)->ref(f, x, y, r2, z);
    mpfr_clears(r2, t, (mpfr_ptr)0);
    return ok;
}

/* f and its gradient by central differences at h = 2^-150 of the scale. */
static int sag_grad_ref(const sg_surface *f, const mpfr_t x, const mpfr_t y, double scale,
                        mpfr_t z, mpfr_t gx, mpfr_t gy)
{
    mpfr_t a, b, p, h;
    int ok;
    mpfr_inits2(PREC, a, b, p, h, (mpfr_ptr)0);
    mpfr_set_d(h, ldexp(scale, -150), MPFR_RNDN);
    ok = sag_ref(f, x, y, z);
    mpfr_add(p, x, h, MPFR_RNDN);
    ok &= sag_ref(f, p, y, a);
    mpfr_sub(p, x, h, MPFR_RNDN);
    ok &= sag_ref(f, p, y, b);
    mpfr_sub(gx, a, b, MPFR_RNDN);
    mpfr_div(gx, gx, h, MPFR_RNDN);
    mpfr_div_2ui(gx, gx, 1, MPFR_RNDN);
    mpfr_add(p, y, h, MPFR_RNDN);
    ok &= sag_ref(f, x, p, a);
    mpfr_sub(p, y, h, MPFR_RNDN);
    ok &= sag_ref(f, x, p, b);
    mpfr_sub(gy, a, b, MPFR_RNDN);
    mpfr_div(gy, gy, h, MPFR_RNDN);
    mpfr_div_2ui(gy, gy, 1, MPFR_RNDN);
    mpfr_clears(a, b, p, h, (mpfr_ptr)0);
    return ok;
}

static void random_shape(sg_surface *f, int type, double s)
{
    f->type = type;
    f->radius = (urand() < 0.5 ? -1.0 : 1.0) * (20.0 + 80.0 * urand()) * s;
    /* A flat base now and then: the terms alone make the sag. */
    if (urand() < 0.2)
        f->radius = INFINITY;
    f->conic = urand() < 0.3 ? 0.0 : srand1(2.0);
    memset(f->asph, 0, sizeof f->asph);
    memset(f->odd, 0, sizeof f->odd);
    memset(f->terms, 0, sizeof f->terms);
    f->radius_x = INFINITY;
    f->conic_x = 0.0;
    f->norm_radius = 1.0;
    case_of(type)->random(f, s);
}

/* ------------------------------------------------------------------------
 * The kernel itself.
 * ------------------------------------------------------------------------ */

static void kernel_bounds(void **state)
{
    static const double scales[] = {1e-3, 1.0, 1e4};
    mpfr_t x, y, z, gx, gy, e, mz, mgx, mgy, tmp[SG_SHAPE_MPTMP], mc[SG_SHAPE_MPC];
    int it, si, ti, k, checked = 0;
    (void)state;
    rng_state = 0x5eed5eed12345ULL;
    mpfr_inits2(PREC, x, y, z, gx, gy, e, mz, mgx, mgy, (mpfr_ptr)0);
    for (k = 0; k < SG_SHAPE_MPTMP; k++)
        mpfr_init2(tmp[k], PREC);
    for (ti = 0; ti < n_shapes; ti++)
        for (si = 0; si < 3; si++)
            for (it = 0; it < 40; it++) {
                sg_surface f;
                sg_shape sh;
                double s = scales[si], px, py, zd, gd[2], h, ez, eg, H[3];
                dd zz, gg[2];
                int j;
                memset(&f, 0, sizeof f);
                random_shape(&f, shape_types[ti], s);
                assert_int_equal(sg_shape_prepare(&f, &sh, 1, NULL), SG_OK);
                assert_non_null(sh.ops);
                for (j = 0; j < 10; j++) {
                    px = srand1(9.0 * s);
                    py = srand1(9.0 * s);
                    mpfr_set_d(x, px, MPFR_RNDN);
                    mpfr_set_d(y, py, MPFR_RNDN);
                    if (!sag_grad_ref(&f, x, y, s, z, gx, gy))
                        continue;
                    assert_true(sh.ops->sag_dd(&sh, dd_from(px), dd_from(py), &zz, gg, &ez, &eg));
                    /* The sag within ez, each gradient component within eg. */
                    mpfr_set_d(e, zz.hi, MPFR_RNDN);
                    mpfr_add_d(e, e, zz.lo, MPFR_RNDN);
                    mpfr_sub(e, e, z, MPFR_RNDN);
                    if (!(fabs(mpfr_get_d(e, MPFR_RNDN)) <= ez))
                        fail_msg("%s: sag error %g above its bound %g at (%g, %g)", sh.ops->name,
                                 mpfr_get_d(e, MPFR_RNDN), ez, px, py);
                    mpfr_set_d(e, gg[0].hi, MPFR_RNDN);
                    mpfr_add_d(e, e, gg[0].lo, MPFR_RNDN);
                    mpfr_sub(e, e, gx, MPFR_RNDN);
                    if (!(fabs(mpfr_get_d(e, MPFR_RNDN)) <= eg))
                        fail_msg("%s: x slope error %g above its bound %g", sh.ops->name,
                                 mpfr_get_d(e, MPFR_RNDN), eg);
                    mpfr_set_d(e, gg[1].hi, MPFR_RNDN);
                    mpfr_add_d(e, e, gg[1].lo, MPFR_RNDN);
                    mpfr_sub(e, e, gy, MPFR_RNDN);
                    if (!(fabs(mpfr_get_d(e, MPFR_RNDN)) <= eg))
                        fail_msg("%s: y slope error %g above its bound %g", sh.ops->name,
                                 mpfr_get_d(e, MPFR_RNDN), eg);
                    /* The double kernel: its slope, and h not below the
                     * Hessian's row sums (by differences of the slope). */
                    assert_true(sh.ops->sag_d(&sh, px, py, &zd, gd, &h));
                    assert_true(fabs(gd[0] - mpfr_get_d(gx, MPFR_RNDN)) <=
                                1e-9 * (1.0 + fabs(gd[0])));
                    {
                        double dh = 1e-6 * s, za, ga[2], gb[2], ha;
                        assert_true(sh.ops->sag_d(&sh, px + dh, py, &za, ga, &ha));
                        assert_true(sh.ops->sag_d(&sh, px - dh, py, &za, gb, &ha));
                        H[0] = (ga[0] - gb[0]) / (2.0 * dh);
                        H[1] = (ga[1] - gb[1]) / (2.0 * dh);
                        assert_true(sh.ops->sag_d(&sh, px, py + dh, &za, ga, &ha));
                        assert_true(sh.ops->sag_d(&sh, px, py - dh, &za, gb, &ha));
                        H[2] = (ga[1] - gb[1]) / (2.0 * dh);
                        if (!(fabs(H[0]) + fabs(H[1]) <= h * 1.001 + 1e-12 / s &&
                              fabs(H[1]) + fabs(H[2]) <= h * 1.001 + 1e-12 / s))
                            fail_msg("%s: second-derivative bound %g below the Hessian "
                                     "(%g %g %g)", sh.ops->name, h, H[0], H[1], H[2]);
                    }
                    /* The MPFR kernel at this precision. */
                    sg_shape_mp_coefs(&sh, mc, PREC);
                    assert_true(sh.ops->sag_mp(&sh, mc, x, y, mz, mgx, mgy, tmp));
                    mpfr_sub(e, mz, z, MPFR_RNDN);
                    assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= ldexp(s, -400));
                    mpfr_sub(e, mgx, gx, MPFR_RNDN);
                    assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= ldexp(1.0, -280));
                    sg_shape_mp_clear(mc);
                    checked++;
                }
            }
    print_message("# kernel points checked: %d\n", checked);
    assert_true(checked > n_shapes * 3 * 40 * 5);
    mpfr_clears(x, y, z, gx, gy, e, mz, mgx, mgy, (mpfr_ptr)0);
    for (k = 0; k < SG_SHAPE_MPTMP; k++)
        mpfr_clear(tmp[k]);
}

/* ------------------------------------------------------------------------
 * The trace.
 * ------------------------------------------------------------------------ */

/* x as hi + lo. */
static void split(const mpfr_t x, double hl[2])
{
    mpfr_t r;
    mpfr_init2(r, PREC);
    hl[0] = mpfr_get_d(x, MPFR_RNDN);
    mpfr_sub_d(r, x, hl[0], MPFR_RNDN);
    hl[1] = mpfr_get_d(r, MPFR_RNDN);
    mpfr_clear(r);
}

/* |a - (hl[0] + hl[1])|, and whether a is hl rounded. */
static double err_of(double a, const double hl[2])
{
    return fabs((a - hl[0]) - hl[1]);
}

/* The reference crossing of the ray S + t D (D unit) near t0, its point
 * and the direction after refraction from n1 = 1 into n2 (or reflection
 * for a mirror); 0 when Newton does not settle. */
static int ray_ref(const sg_surface *f, const double S[3], const double D[3], double t0,
                   double scale, int mirror, double n2, double P[3][2], double Dout[3][2],
                   mpfr_t *Pm)
{
    mpfr_t t, x, y, z, gx, gy, F, Fp, a, d[3], g[3], gg, dg, k;
    int it, ok = 0, j;
    mpfr_inits2(PREC, t, x, y, z, gx, gy, F, Fp, a, d[0], d[1], d[2], g[0], g[1], g[2], gg, dg,
                k, (mpfr_ptr)0);
    mpfr_set_d(t, t0, MPFR_RNDN);
    for (j = 0; j < 3; j++)
        mpfr_set_d(d[j], D[j], MPFR_RNDN);
    /* D as given is the unit direction rounded: normalise it again. */
    mpfr_sqr(a, d[0], MPFR_RNDN);
    mpfr_fma(a, d[1], d[1], a, MPFR_RNDN);
    mpfr_fma(a, d[2], d[2], a, MPFR_RNDN);
    mpfr_sqrt(a, a, MPFR_RNDN);
    for (j = 0; j < 3; j++)
        mpfr_div(d[j], d[j], a, MPFR_RNDN);
    for (it = 0; it < 200; it++) {
        mpfr_mul(x, t, d[0], MPFR_RNDN);
        mpfr_add_d(x, x, S[0], MPFR_RNDN);
        mpfr_mul(y, t, d[1], MPFR_RNDN);
        mpfr_add_d(y, y, S[1], MPFR_RNDN);
        if (!sag_grad_ref(f, x, y, scale, z, gx, gy))
            break;
        mpfr_mul(F, t, d[2], MPFR_RNDN);
        mpfr_add_d(F, F, S[2], MPFR_RNDN);
        mpfr_sub(F, F, z, MPFR_RNDN);
        mpfr_mul(Fp, gx, d[0], MPFR_RNDN);
        mpfr_fma(Fp, gy, d[1], Fp, MPFR_RNDN);
        mpfr_sub(Fp, d[2], Fp, MPFR_RNDN);
        mpfr_div(a, F, Fp, MPFR_RNDN);
        mpfr_sub(t, t, a, MPFR_RNDN);
        if (mpfr_zero_p(a) || mpfr_get_exp(a) < -460 + (mpfr_exp_t)ilogb(scale)) {
            ok = 1;
            break;
        }
    }
    if (ok) {
        mpfr_mul(x, t, d[0], MPFR_RNDN);
        mpfr_add_d(x, x, S[0], MPFR_RNDN);
        mpfr_mul(y, t, d[1], MPFR_RNDN);
        mpfr_add_d(y, y, S[1], MPFR_RNDN);
        mpfr_mul(z, t, d[2], MPFR_RNDN);
        mpfr_add_d(z, z, S[2], MPFR_RNDN);
        split(x, P[0]);
        split(y, P[1]);
        split(z, P[2]);
        if (Pm) {
            mpfr_set(Pm[0], x, MPFR_RNDN);
            mpfr_set(Pm[1], y, MPFR_RNDN);
            mpfr_set(Pm[2], z, MPFR_RNDN);
        }
        sag_grad_ref(f, x, y, scale, a, gx, gy);
        /* The normal (-f_x, -f_y, 1) and the vector law. */
        mpfr_neg(g[0], gx, MPFR_RNDN);
        mpfr_neg(g[1], gy, MPFR_RNDN);
        mpfr_set_ui(g[2], 1, MPFR_RNDN);
        mpfr_sqr(gg, g[0], MPFR_RNDN);
        mpfr_fma(gg, g[1], g[1], gg, MPFR_RNDN);
        mpfr_fma(gg, g[2], g[2], gg, MPFR_RNDN);
        mpfr_sqrt(gg, gg, MPFR_RNDN);
        for (j = 0; j < 3; j++)
            mpfr_div(g[j], g[j], gg, MPFR_RNDN);
        mpfr_mul(dg, d[0], g[0], MPFR_RNDN);
        mpfr_fma(dg, d[1], g[1], dg, MPFR_RNDN);
        mpfr_fma(dg, d[2], g[2], dg, MPFR_RNDN);
        if (mirror) {
            for (j = 0; j < 3; j++) {
                mpfr_mul(a, dg, g[j], MPFR_RNDN);
                mpfr_mul_2ui(a, a, 1, MPFR_RNDN);
                mpfr_sub(d[j], d[j], a, MPFR_RNDN);
            }
        } else {
            /* d' = mu d + (sgn(cos) sqrt(1 - mu^2 (1 - cos^2)) - mu cos) g,
             * mu = 1 / n2 at this precision. */
            mpfr_t mu;
            mpfr_init2(mu, PREC);
            mpfr_set_ui(mu, 1, MPFR_RNDN);
            mpfr_div_d(mu, mu, n2, MPFR_RNDN);
            mpfr_sqr(k, dg, MPFR_RNDN);
            mpfr_ui_sub(k, 1, k, MPFR_RNDN);
            mpfr_mul(k, k, mu, MPFR_RNDN);
            mpfr_mul(k, k, mu, MPFR_RNDN);
            mpfr_ui_sub(k, 1, k, MPFR_RNDN);
            if (mpfr_sgn(k) < 0)
                ok = 0;
            else {
                mpfr_sqrt(k, k, MPFR_RNDN);
                if (mpfr_sgn(dg) < 0)
                    mpfr_neg(k, k, MPFR_RNDN);
                mpfr_mul(a, dg, mu, MPFR_RNDN);
                mpfr_sub(k, k, a, MPFR_RNDN);
                for (j = 0; j < 3; j++) {
                    mpfr_mul(d[j], d[j], mu, MPFR_RNDN);
                    mpfr_fma(d[j], k, g[j], d[j], MPFR_RNDN);
                }
            }
            mpfr_clear(mu);
        }
        for (j = 0; j < 3; j++)
            split(d[j], Dout[j]);
    }
    mpfr_clears(t, x, y, z, gx, gy, F, Fp, a, d[0], d[1], d[2], g[0], g[1], g[2], gg, dg, k,
                (mpfr_ptr)0);
    return ok;
}

/* A system of the shape f on surface 1 (refracting into 1.5, or a
 * mirror) and an image 10 scale behind. */
static sg_system *one_shape(const sg_surface *f, int mirror, double scale)
{
    sg_system *sys = tu_one_surface();
    sg_surface *s = &sys->surf[1];
    s->type = f->type;
    s->radius = f->radius;
    s->conic = f->conic;
    memcpy(s->asph, f->asph, sizeof s->asph);
    memcpy(s->odd, f->odd, sizeof s->odd);
    memcpy(s->terms, f->terms, sizeof s->terms);
    s->radius_x = f->radius_x;
    s->conic_x = f->conic_x;
    s->norm_radius = f->norm_radius;
    s->zern_dx = f->zern_dx;
    s->zern_dy = f->zern_dy;
    s->thickness = (mirror ? -10.0 : 10.0) * scale;
    if (mirror) {
        s->mat.kind = SG_MAT_MIRROR;
    } else {
        s->mat.kind = SG_MAT_INDEX;
        s->mat.index = 1.5;
    }
    sys->aper_value = 2.0 * scale;
    return sys;
}

typedef struct tally {
    long rays, ok, exact, dir_ok, mpfr_exact, disagree, classic_lost;
} tally;

/* Traces S, D through f in every method and holds precise and mpfr to the
 * reference.  ordinary: the ray is no hard case, and precise must be the
 * reference rounded. */
static void check_ray(const sg_surface *f, int mirror, double scale, sg_tracer *tp,
                      sg_tracer *tm, sg_tracer *tc, const double S[3], const double D[3],
                      double t0, int ordinary, tally *ty)
{
    sg_ray_surface op[3], om[3], oc[3];
    double P[3][2], Dr[3][2];
    int rp, rm, rc, ref, j;
    rp = sg_trace_start(tp, S, D, op);
    rm = sg_trace_start(tm, S, D, om);
    rc = sg_trace_start(tc, S, D, oc);
    ty->rays++;
    /* No method marks a non-finite row OK. */
    for (j = 1; j < 3; j++) {
        const sg_ray_surface *o[3] = {&op[j], &om[j], &oc[j]};
        int q;
        for (q = 0; q < 3; q++)
            if (o[q]->status == SG_OK)
                assert_true(isfinite(o[q]->x) && isfinite(o[q]->y) && isfinite(o[q]->z) &&
                            isfinite(o[q]->l) && isfinite(o[q]->error_bound));
    }
    if (op[1].status != SG_OK && om[1].status != SG_OK)
        return;
    ref = ray_ref(f, S, D, op[1].status == SG_OK ? op[1].path : om[1].path, scale, mirror, 1.5,
                  P, Dr, NULL);
    if (!ref)
        return;
    if (op[1].status == SG_OK) {
        double e = fmax(err_of(op[1].x, P[0]), fmax(err_of(op[1].y, P[1]), err_of(op[1].z, P[2])));
        double ed = fmax(err_of(op[1].l, Dr[0]), fmax(err_of(op[1].m, Dr[1]), err_of(op[1].n, Dr[2])));
        if (!(e <= op[1].error_bound))
            fail_msg("precise point error %g above its bound %g (type %d, scale %g, S %.17g "
                     "%.17g %.17g, D %.17g %.17g %.17g)", e, op[1].error_bound, f->type, scale,
                     S[0], S[1], S[2], D[0], D[1], D[2]);
        if (!(ed <= op[1].dir_error_bound))
            fail_msg("precise direction error %g above its bound %g (type %d, scale %g)", ed,
                     op[1].dir_error_bound, f->type, scale);
        ty->ok++;
        if (op[1].x == P[0][0] && op[1].y == P[1][0] && op[1].z == P[2][0])
            ty->exact++;
        else if (ordinary)
            fail_msg("precise point of an ordinary ray is not the reference rounded: "
                     "(%.17g %.17g %.17g) against (%.17g %.17g %.17g), type %d, R %g, Rx %g, "
                     "S %a %a %a, D %a %a %a", op[1].x, op[1].y, op[1].z, P[0][0], P[1][0],
                     P[2][0], f->type, f->radius, f->radius_x, S[0], S[1], S[2], D[0], D[1], D[2]);
        if (op[1].l == Dr[0][0] && op[1].m == Dr[1][0] && op[1].n == Dr[2][0])
            ty->dir_ok++;
    }
    if (om[1].status == SG_OK) {
        double e = fmax(err_of(om[1].x, P[0]), fmax(err_of(om[1].y, P[1]), err_of(om[1].z, P[2])));
        assert_true(e <= om[1].error_bound);
        if (om[1].x == P[0][0] && om[1].y == P[1][0] && om[1].z == P[2][0])
            ty->mpfr_exact++;
    }
    if (rp != rm && (rp == SG_OK || rm == SG_OK) && rp != SG_EUNCERT)
        ty->disagree++;
    if (rc != SG_OK && rp == SG_OK)
        ty->classic_lost++;
}

static void trace_sets(void **state)
{
    static const double scales[] = {1e-3, 1.0, 1e4};
    sg_catalog *cat = tu_catalog();
    int ti, si, it, k;
    tally all = {0};
    (void)state;
    rng_state = 0xface0ff5eedULL;
    for (ti = 0; ti < n_shapes; ti++)
        for (si = 0; si < 3; si++)
            for (it = 0; it < 6; it++) {
                double s = scales[si];
                int mirror = it % 3 == 2;
                sg_surface f;
                sg_system *sys;
                sg_tracer *tp, *tm, *tc;
                tally ty = {0};
                memset(&f, 0, sizeof f);
                random_shape(&f, shape_types[ti], s);
                sys = one_shape(&f, mirror, s);
                tp = tu_tracer(sys, cat, SG_METHOD_PRECISE);
                tm = tu_tracer(sys, cat, SG_METHOD_MPFR);
                tc = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
                for (k = 0; k < 30; k++) {
                    /* Ordinary rays: from 5 scale in front, within 6 scale of
                     * the axis, within about 11 degrees of it. */
                    /* The start's z is not a round number: a plane 5 units
                     * ahead along D_z = 1 would put x = S_x + 5 D_x exactly
                     * on a rounding tie now and then, where the last bit of
                     * double-double decides (a flat base with no terms is a
                     * plane, which the standard surface traces exactly). */
                    double S[3] = {srand1(6.0 * s), srand1(6.0 * s),
                                   -5.0 * s * (1.0 + 0.1 * urand())};
                    double D[3] = {srand1(0.2), srand1(0.2), 1.0};
                    check_ray(&f, mirror, s, tp, tm, tc, S, D, 0.0, 1, &ty);
                }
                for (k = 0; k < 30; k++) {
                    /* Grazing rays: through a point of the surface, nearly
                     * along its tangent plane, tilted off it by 1e-9 to 1e-2. */
                    mpfr_t x, y, z, gx, gy;
                    double P[3], n[3], t[3], D[3], S[3], eps = pow(10.0, -2.0 - 7.0 * urand()), nn;
                    mpfr_inits2(PREC, x, y, z, gx, gy, (mpfr_ptr)0);
                    P[0] = srand1(6.0 * s);
                    P[1] = srand1(6.0 * s);
                    mpfr_set_d(x, P[0], MPFR_RNDN);
                    mpfr_set_d(y, P[1], MPFR_RNDN);
                    if (sag_grad_ref(&f, x, y, s, z, gx, gy)) {
                        P[2] = mpfr_get_d(z, MPFR_RNDN);
                        n[0] = -mpfr_get_d(gx, MPFR_RNDN);
                        n[1] = -mpfr_get_d(gy, MPFR_RNDN);
                        n[2] = 1.0;
                        nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                        /* A tangent: n x (a random direction). */
                        {
                            double r[3] = {srand1(1.0), srand1(1.0), srand1(1.0)};
                            t[0] = n[1] * r[2] - n[2] * r[1];
                            t[1] = n[2] * r[0] - n[0] * r[2];
                            t[2] = n[0] * r[1] - n[1] * r[0];
                        }
                        {
                            double tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
                            if (t[2] < 0.0)
                                tl = -tl;
                            for (int j = 0; j < 3; j++)
                                D[j] = t[j] / tl + eps * n[j] / nn;
                        }
                        for (int j = 0; j < 3; j++)
                            S[j] = P[j] - 5.0 * s * D[j];
                        if (D[2] > 0.05)
                            check_ray(&f, mirror, s, tp, tm, tc, S, D, 0.0, 0, &ty);
                    }
                    mpfr_clears(x, y, z, gx, gy, (mpfr_ptr)0);
                }
                all.rays += ty.rays;
                all.ok += ty.ok;
                all.exact += ty.exact;
                all.dir_ok += ty.dir_ok;
                all.mpfr_exact += ty.mpfr_exact;
                all.disagree += ty.disagree;
                all.classic_lost += ty.classic_lost;
                sg_tracer_free(tp);
                sg_tracer_free(tm);
                sg_tracer_free(tc);
                sg_system_free(sys);
            }
    print_message("# rays %ld: precise OK %ld, point the reference rounded %ld, direction %ld; "
                  "mpfr rounded %ld; status disagreements %ld; classic lost %ld\n",
                  all.rays, all.ok, all.exact, all.dir_ok, all.mpfr_exact, all.disagree,
                  all.classic_lost);
    assert_true(all.ok > all.rays / 2);
    assert_int_equal(all.disagree, 0);
    sg_catalog_free(cat);
}

/* The state precise carries to the next surface, before it is rounded to
 * the printed double: the double-double point within its bound eP of the
 * reference.  On surfaces whose terms cancel (a paraboloid whose r^2 term
 * nearly undoes it, a Zernike defocus that nearly flattens its base, an XY
 * x^2 + y^2 that nearly cancels the conic) the sag in double-double
 * carries the rounding of the large terms, and the root's own error,
 * ferr / |F'|, is what the bound must cover: rounded to doubles, it
 * vanishes under the half ulp of the printed bound. */
static void carried_error(void **state)
{
    mpfr_t Pm[3], e;
    int it, j, n = 0;
    double worst = 0.0;
    (void)state;
    rng_state = 0x0ddba11c0ffeeULL;
    mpfr_inits2(PREC, Pm[0], Pm[1], Pm[2], e, (mpfr_ptr)0);
    for (it = 0; it < 900; it++) {
        int kind = it % 3;
        double R = pow(10.0, -3.0 + 4.0 * urand()) * (urand() < 0.5 ? -1.0 : 1.0);
        double delta = pow(10.0, -1.0 - 6.0 * urand()), S[3], D[3], P[3][2], Dr[3][2], gap;
        sg_surface f;
        sg_system *sys;
        sg_tracer *tp;
        sg_ray_surface out[3];
        sg_pray r;
        memset(&f, 0, sizeof f);
        f.conic = -1.0;
        f.radius = R;
        f.radius_x = INFINITY;
        f.norm_radius = 1.0;
        if (kind == 0) {
            /* sag = r^2 / 2R + b2 r^2 = delta r^2 / 2R */
            f.type = SG_SURF_ODDASPH;
            f.odd[1] = -(1.0 - delta) / (2.0 * R);
        } else if (kind == 1) {
            /* Fringe Z4 = 2 rho^2 - 1 with norm 1: A4 (2 r^2 - 1) */
            f.type = SG_SURF_ZERNIKE_FRINGE;
            f.terms[3] = -(1.0 - delta) / (4.0 * R);
        } else {
            f.type = SG_SURF_XYPOLY;
            f.terms[2] = -(1.0 - delta) / (2.0 * R);
            f.terms[4] = f.terms[2];
        }
        sys = one_shape(&f, it % 2, 1.0);
        tp = tu_tracer(sys, NULL, SG_METHOD_PRECISE);
        S[0] = srand1(0.5);
        S[1] = srand1(0.5);
        S[2] = it % 4 < 2 ? 0.0 : -pow(10.0, -2.0 * urand());
        D[0] = srand1(0.5);
        D[1] = srand1(0.5);
        D[2] = 1.0;
        if (sg_start_precise_prep(tp, S, D, out, &r) == SG_OK &&
            sg_precise_run_to(tp, &r, 0.0, out, 1) == SG_OK && out[1].status == SG_OK &&
            ray_ref(&f, S, D, out[1].path, 1.0, it % 2, 1.5, P, Dr, Pm)) {
            const dd *c[3] = {&r.p.x, &r.p.y, &r.p.z};
            for (j = 0; j < 3; j++) {
                mpfr_set_d(e, c[j]->hi, MPFR_RNDN);
                mpfr_add_d(e, e, c[j]->lo, MPFR_RNDN);
                mpfr_sub(e, e, Pm[j], MPFR_RNDN);
                gap = fabs(mpfr_get_d(e, MPFR_RNDN));
                if (!(gap <= r.eP))
                    fail_msg("kind %d, delta %g: carried error %g above eP %g (coordinate %d)",
                             kind, delta, gap, r.eP, j);
                if (r.eP > 0.0 && gap / r.eP > worst)
                    worst = gap / r.eP;
            }
            n++;
        }
        sg_tracer_free(tp);
        sg_system_free(sys);
    }
    print_message("# cancelling shapes: %d rays; carried error at most %.3g of eP\n", n, worst);
    assert_true(n > 600);
    mpfr_clears(Pm[0], Pm[1], Pm[2], e, (mpfr_ptr)0);
}

/* A closed form: Fringe Z1 + Z4 = 2 rho^2 with equal coefficients c, so
 * a flat Zernike sag decentred to (a, b) is the paraboloid z = 2c ((x -
 * a)^2 + (y - b)^2) / R^2 = -((x - a)^2 + (y - b)^2) / (4 F) with c = -R^2
 * / (8 F).  Its sag and slope in the three arithmetics against that
 * formula in MPFR here, and as a mirror: every ray along the axis meets
 * the plane at -F in the paraboloid's focus (a, b), within its bound. */
static void zernike_decenter_closed_form(void **state)
{
    const double R = 10.0, F = 25.0, a = 1.5, b = -0.75;
    mpfr_t x, y, z, gx, gy, e, w, tmp[SG_SHAPE_MPTMP], mc[SG_SHAPE_MPC];
    sg_catalog *cat = tu_catalog();
    sg_surface f;
    sg_shape sh;
    sg_system *sys;
    double worst = 0.0;
    int k, j, m, nray = 0;
    (void)state;
    rng_state = 0xdece47e5ULL;
    memset(&f, 0, sizeof f);
    f.type = SG_SURF_ZERNIKE_FRINGE;
    f.radius = INFINITY;
    f.norm_radius = R;
    f.terms[0] = f.terms[3] = -R * R / (8.0 * F);
    f.zern_dx = a;
    f.zern_dy = b;
    assert_int_equal(sg_shape_prepare(&f, &sh, 1, NULL), SG_OK);
    mpfr_inits2(PREC, x, y, z, gx, gy, e, w, (mpfr_ptr)0);
    for (k = 0; k < SG_SHAPE_MPTMP; k++)
        mpfr_init2(tmp[k], PREC);
    sg_shape_mp_coefs(&sh, mc, PREC);
    for (j = 0; j < 200; j++) {
        double px = srand1(9.0), py = srand1(9.0), zd, gd[2], h, ez, eg, want, wgx, wgy;
        dd zz, gg[2];
        /* z = -((x - a)^2 + (y - b)^2) / (4 F), slope -(x - a) / (2 F). */
        mpfr_set_d(x, px, MPFR_RNDN);
        mpfr_set_d(y, py, MPFR_RNDN);
        mpfr_sub_d(gx, x, a, MPFR_RNDN);
        mpfr_sub_d(gy, y, b, MPFR_RNDN);
        mpfr_sqr(z, gx, MPFR_RNDN);
        mpfr_sqr(w, gy, MPFR_RNDN);
        mpfr_add(z, z, w, MPFR_RNDN);
        mpfr_div_d(z, z, -4.0 * F, MPFR_RNDN);
        mpfr_div_d(gx, gx, -2.0 * F, MPFR_RNDN);
        mpfr_div_d(gy, gy, -2.0 * F, MPFR_RNDN);
        want = mpfr_get_d(z, MPFR_RNDN);
        wgx = mpfr_get_d(gx, MPFR_RNDN);
        wgy = mpfr_get_d(gy, MPFR_RNDN);
        assert_true(sh.ops->sag_d(&sh, px, py, &zd, gd, &h));
        assert_true(fabs(zd - want) <= 1e-13 && fabs(gd[0] - wgx) <= 1e-14 &&
                    fabs(gd[1] - wgy) <= 1e-14);
        /* The paraboloid's second derivatives are 1 / (2 F) on the diagonal. */
        assert_true(h >= 1.0 / (2.0 * F));
        assert_true(sh.ops->sag_dd(&sh, dd_from(px), dd_from(py), &zz, gg, &ez, &eg));
        mpfr_set_d(e, zz.hi, MPFR_RNDN);
        mpfr_add_d(e, e, zz.lo, MPFR_RNDN);
        mpfr_sub(e, e, z, MPFR_RNDN);
        if (!(fabs(mpfr_get_d(e, MPFR_RNDN)) <= ez))
            fail_msg("double-double sag error %g above its bound %g at (%g, %g)",
                     mpfr_get_d(e, MPFR_RNDN), ez, px, py);
        if (fabs(mpfr_get_d(e, MPFR_RNDN)) > worst)
            worst = fabs(mpfr_get_d(e, MPFR_RNDN));
        mpfr_set_d(e, gg[0].hi, MPFR_RNDN);
        mpfr_add_d(e, e, gg[0].lo, MPFR_RNDN);
        mpfr_sub(e, e, gx, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= eg);
        mpfr_set_d(e, gg[1].hi, MPFR_RNDN);
        mpfr_add_d(e, e, gg[1].lo, MPFR_RNDN);
        mpfr_sub(e, e, gy, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= eg);
        /* The MPFR kernel. */
        {
            mpfr_t mz, mgx, mgy;
            mpfr_inits2(PREC, mz, mgx, mgy, (mpfr_ptr)0);
            assert_true(sh.ops->sag_mp(&sh, mc, x, y, mz, mgx, mgy, tmp));
            mpfr_sub(e, mz, z, MPFR_RNDN);
            assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= 0x1p-400);
            mpfr_sub(e, mgx, gx, MPFR_RNDN);
            assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= 0x1p-400);
            mpfr_sub(e, mgy, gy, MPFR_RNDN);
            assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= 0x1p-400);
            mpfr_clears(mz, mgx, mgy, (mpfr_ptr)0);
        }
    }
    sg_shape_mp_clear(mc);

    /* The mirror: the image plane at the focus, F before it. */
    sys = one_shape(&f, 1, 1.0);
    sys->surf[1].thickness = -F;
    for (m = 0; m < 2; m++) {
        sg_tracer *t = tu_tracer(sys, cat, m == 0 ? SG_METHOD_PRECISE : SG_METHOD_MPFR);
        for (j = 0; j < 50; j++) {
            double S[3] = {srand1(6.0), srand1(6.0), -5.0}, D[3] = {0.0, 0.0, 1.0};
            sg_ray_surface o[3];
            assert_int_equal(sg_trace_start(t, S, D, o), SG_OK);
            if (!(fabs(o[2].x - a) <= o[2].error_bound && fabs(o[2].y - b) <= o[2].error_bound))
                fail_msg("method %d: ray at (%g, %g) meets the focal plane at (%.17g, %.17g), "
                         "not the focus (%g, %g) within %g", m, S[0], S[1], o[2].x, o[2].y, a,
                         b, o[2].error_bound);
            nray++;
        }
        sg_tracer_free(t);
    }
    print_message("# decentred Zernike paraboloid: 200 points within bounds (worst double-double "
                  "sag error %g); %d axial rays through the focus (%g, %g)\n", worst, nray, a, b);
    sg_system_free(sys);
    sg_catalog_free(cat);
    mpfr_clears(x, y, z, gx, gy, e, w, (mpfr_ptr)0);
    for (k = 0; k < SG_SHAPE_MPTMP; k++)
        mpfr_clear(tmp[k]);
}

/* Surfaces that are another in other words trace bit for bit as it. */
static void reductions(void **state)
{
    sg_catalog *cat = tu_catalog();
    int it, k, m;
    (void)state;
    rng_state = 0xabcdef987ULL;
    for (it = 0; it < 24; it++) {
        sg_surface f, g;
        sg_system *a, *b;
        int mirror = it % 2;
        memset(&f, 0, sizeof f);
        random_shape(&f, SG_SURF_ZERNIKE_FRINGE + it % 4 % 3, 1.0);
        memset(f.terms, 0, sizeof f.terms);
        memset(f.asph, 0, sizeof f.asph);
        /* A curved base: with no terms on a flat one, the shape is a plane,
         * whose z the standard surface gets exactly 0 and a sag function
         * to within its bound. */
        if (isinf(f.radius))
            f.radius = 60.0;
        if (it % 4 == 3) {
            /* A biconic with equal sections is the conic. */
            f.type = SG_SURF_BICONIC;
            f.radius_x = f.radius;
            f.conic_x = f.conic;
        }
        if (it % 8 == 2) {
            /* A toroid turned about its own centre is the sphere. */
            f.type = SG_SURF_TOROIDAL;
            f.conic = 0.0;
            f.radius_x = f.radius;
        }
        g = f;
        g.type = SG_SURF_STANDARD;
        a = one_shape(&f, mirror, 1.0);
        b = one_shape(&g, mirror, 1.0);
        for (m = 0; m < 3; m++) {
            sg_tracer *ta = tu_tracer(a, cat, (sg_method)m), *tb = tu_tracer(b, cat, (sg_method)m);
            for (k = 0; k < 40; k++) {
                double S[3] = {srand1(6.0), srand1(6.0), -5.0 * (1.0 + 0.1 * urand())};
                double D[3] = {srand1(0.2), srand1(0.2), 1.0};
                sg_ray_surface oa[3], ob[3];
                int ra = sg_trace_start(ta, S, D, oa), rb = sg_trace_start(tb, S, D, ob);
                assert_int_equal(ra, rb);
                if (ra != SG_OK)
                    continue;
                /* Precise and mpfr give the exact answer rounded either
                 * way; classic's arithmetic differs, so its points agree to
                 * its own estimate. */
                if (m != SG_METHOD_CLASSIC) {
                    if (oa[1].x != ob[1].x || oa[1].y != ob[1].y || oa[1].z != ob[1].z ||
                        oa[2].x != ob[2].x || oa[2].y != ob[2].y || oa[1].l != ob[1].l ||
                        oa[1].m != ob[1].m || oa[1].n != ob[1].n)
                        fail_msg("method %d, type %d: (%.17g %.17g %.17g) against the standard "
                                 "surface's (%.17g %.17g %.17g)", m, f.type, oa[1].x, oa[1].y,
                                 oa[1].z, ob[1].x, ob[1].y, ob[1].z);
                } else {
                    assert_true(fabs(oa[2].x - ob[2].x) <= oa[2].error_bound + ob[2].error_bound);
                }
            }
            sg_tracer_free(ta);
            sg_tracer_free(tb);
        }
        sg_system_free(a);
        sg_system_free(b);
    }
    sg_catalog_free(cat);
}


/* ------------------------------------------------------------------------
 * The vector kernel (shape_vdd.h) against the scalar one, bit for bit.
 * ------------------------------------------------------------------------ */

/* Same double, NaN matching any NaN. */
static int same_bits(double a, double b)
{
    return (a != a && b != b) || memcmp(&a, &b, sizeof a) == 0;
}

/* A point's coordinate of the kinds the trace meets: ordinary, with a low
 * part; beyond the conic's edge; zero of either sign; tiny; huge. */
static void point_dd(double s, double *hi, double *lo)
{
    double u = urand();
    *lo = 0.0;
    if (u < 0.55) {
        *hi = srand1(9.0 * s);
        *lo = *hi * srand1(0x1p-54);
    } else if (u < 0.75) {
        *hi = srand1(400.0 * s);
        *lo = *hi * srand1(0x1p-54);
    } else if (u < 0.82) {
        *hi = urand() < 0.5 ? 0.0 : -0.0;
    } else if (u < 0.9) {
        *hi = srand1(1e-200 * s);
    } else if (u < 0.96) {
        *hi = srand1(1e150);
    } else {
        *hi = srand1(2.0 * s);
        *lo = srand1(0x1p-60) * s;
    }
}

/* Every lane of svd_sag gives what the shape's scalar sag_dd gives that
 * point alone: the same sag, slopes and bounds to the bit, and a lane
 * marked bad exactly where the scalar kernel leaves the shape's domain.
 * Lanes of one block mix ordinary points with failing and extreme ones;
 * the first shape of each kind and scale has power-of-two radii, so that
 * a lane on its rim meets the scalar code's exact-zero branches (q = 0 of
 * the conic, the toroid's u^2 - x^2 = 0, the biconic's S = 0), and a lane
 * at x = y = 0 of either sign the odd asphere's r = 0 branch. */
static void vector_kernel(void **state)
{
    static const double scales[] = {1e-3, 1.0, 1e4};
    const int *types = shape_types;
    enum { NT = SG_SURF_NTYPES };
    int ti, si, it, blk, k, lanes[NT] = {0}, bad_lanes[NT] = {0};
    (void)state;
    rng_state = 0x7ec7ec7ec7ULL;
    for (ti = 0; ti < n_shapes; ti++)
        for (si = 0; si < 3 && case_of(types[ti])->vec; si++)
            for (it = 0; it < 30; it++) {
                sg_surface f;
                sg_shape sh;
                double sc = scales[si], rim;
                memset(&f, 0, sizeof f);
                random_shape(&f, types[ti], sc);
                if (types[ti] == SG_SURF_XYPOLY && urand() < 0.5)
                    for (k = 0; k < 4; k++)
                        f.asph[k] = srand1(1e-6) / pow(sc, 2 * k + 1);
                if (it == 0) {
                    f.radius = ldexp(4.0, ilogb(sc));
                    f.conic = 0.0;
                    if (case_of(types[ti])->rx) {
                        f.radius_x = f.radius;
                        f.conic_x = 0.0;
                    }
                }
                rim = case_of(types[ti])->rim_x ? f.radius_x : f.radius;
                assert_int_equal(sg_shape_prepare(&f, &sh, 1, NULL), SG_OK);
                assert_int_equal(svd_handles(&sh), case_of(types[ti])->vec);
                for (blk = 0; blk < 8; blk++) {
                    vdd x, y, z, g[2];
                    vd ez, eg;
                    vm bad;
                    for (k = 0; k < SG_VL; k++) {
                        point_dd(sc, &x.hi[k], &x.lo[k]);
                        point_dd(sc, &y.hi[k], &y.lo[k]);
                    }
                    if (blk == 0) {
                        x.hi[1] = isfinite(rim) ? fabs(rim) : 0.0;
                        x.lo[1] = y.hi[1] = y.lo[1] = 0.0;
                        x.hi[2] = urand() < 0.5 ? 0.0 : -0.0;
                        y.hi[2] = urand() < 0.5 ? 0.0 : -0.0;
                        x.lo[2] = y.lo[2] = 0.0;
                    }
                    svd_sag(&sh, x, y, &z, g, &ez, &eg, &bad);
                    for (k = 0; k < SG_VL; k++) {
                        dd xs = {x.hi[k], x.lo[k]}, ys = {y.hi[k], y.lo[k]}, zs, gs[2];
                        double ezs, egs;
                        int ok = sh.ops->sag_dd(&sh, xs, ys, &zs, gs, &ezs, &egs);
                        lanes[ti]++;
                        if (!ok) {
                            bad_lanes[ti]++;
                            if (!bad[k])
                                fail_msg("%s lane %d at (%g, %g): scalar outside, vector not",
                                         sh.ops->name, k, xs.hi, ys.hi);
                            continue;
                        }
                        if (bad[k])
                            fail_msg("%s lane %d at (%g, %g): vector outside, scalar not",
                                     sh.ops->name, k, xs.hi, ys.hi);
                        if (!same_bits(zs.hi, z.hi[k]) || !same_bits(zs.lo, z.lo[k]) ||
                            !same_bits(gs[0].hi, g[0].hi[k]) || !same_bits(gs[0].lo, g[0].lo[k]) ||
                            !same_bits(gs[1].hi, g[1].hi[k]) || !same_bits(gs[1].lo, g[1].lo[k]) ||
                            !same_bits(ezs, ez[k]) || !same_bits(egs, eg[k]))
                            fail_msg("%s lane %d at (%a + %a, %a + %a): sag %a %a vs %a %a, "
                                     "slopes %a %a, %a %a vs %a %a, %a %a, "
                                     "bounds %a %a vs %a %a",
                                     sh.ops->name, k, xs.hi, xs.lo, ys.hi, ys.lo, zs.hi, zs.lo,
                                     z.hi[k], z.lo[k], gs[0].hi, gs[0].lo, gs[1].hi, gs[1].lo,
                                     g[0].hi[k], g[0].lo[k], g[1].hi[k], g[1].lo[k], ezs, egs,
                                     ez[k], eg[k]);
                    }
                }
            }
    for (ti = 0; ti < n_shapes; ti++) {
        if (!case_of(types[ti])->vec)
            continue;
        print_message("# vector kernel, type %d: %d lanes, %d outside the shape\n", types[ti],
                      lanes[ti], bad_lanes[ti]);
        assert_true(bad_lanes[ti] > lanes[ti] / 20 && bad_lanes[ti] < lanes[ti] / 2);
    }
}

/* Every lane of sv_sag_d (shape_vd.h) gives what the shape's scalar sag_d
 * gives that point alone: the same sag, slopes and second-derivative
 * bound to the bit, and a lane marked bad exactly where the scalar kernel
 * leaves the shape's domain.  The points are vector_kernel's (their high
 * parts), with its rim and axis lanes on shapes of power-of-two radii, so
 * the scalar code's exact-zero branches are met (the biconic's S = 0 with
 * its infinite slopes, the toroid's u^2 - x^2 = 0, the odd asphere's r =
 * 0 with an r^1 term); and a toroid flat in x, Zernike sags with and
 * without a decenter, XY surfaces with and without even terms. */
static void vector_kernel_d(void **state)
{
    static const double scales[] = {1e-3, 1.0, 1e4};
    const int *types = shape_types;
    enum { NT = SG_SURF_NTYPES };
    int ti, si, it, blk, k, lanes[NT] = {0}, bad_lanes[NT] = {0}, inf_lanes = 0;
    (void)state;
    rng_state = 0x5a95a95a9ULL;
    for (ti = 0; ti < n_shapes; ti++)
        for (si = 0; si < 3 && case_of(types[ti])->vec; si++)
            for (it = 0; it < 30; it++) {
                sg_surface f;
                sg_shape sh;
                double sc = scales[si], rim, lo;
                memset(&f, 0, sizeof f);
                random_shape(&f, types[ti], sc);
                if (types[ti] == SG_SURF_XYPOLY && urand() < 0.5)
                    for (k = 0; k < 4; k++)
                        f.asph[k] = srand1(1e-6) / pow(sc, 2 * k + 1);
                if (it == 0) {
                    f.radius = ldexp(4.0, ilogb(sc));
                    f.conic = 0.0;
                    if (case_of(types[ti])->rx) {
                        f.radius_x = f.radius;
                        f.conic_x = 0.0;
                    }
                }
                rim = case_of(types[ti])->rim_x ? f.radius_x : f.radius;
                assert_int_equal(sg_shape_prepare(&f, &sh, 1, NULL), SG_OK);
                assert_int_equal(sv_handles_d(&sh), case_of(types[ti])->vec);
                for (blk = 0; blk < 8; blk++) {
                    vd x, y, z, g[2], h;
                    vm bad;
                    for (k = 0; k < SG_VL; k++) {
                        point_dd(sc, &x[k], &lo);
                        point_dd(sc, &y[k], &lo);
                    }
                    if (blk == 0) {
                        x[1] = isfinite(rim) ? fabs(rim) : 0.0;
                        y[1] = 0.0;
                        x[2] = urand() < 0.5 ? 0.0 : -0.0;
                        y[2] = urand() < 0.5 ? 0.0 : -0.0;
                    }
                    sv_sag_d(&sh, x, y, &z, g, &h, &bad);
                    for (k = 0; k < SG_VL; k++) {
                        double zs, gs[2], hs;
                        int ok = sh.ops->sag_d(&sh, x[k], y[k], &zs, gs, &hs);
                        lanes[ti]++;
                        if (!ok) {
                            bad_lanes[ti]++;
                            if (!bad[k])
                                fail_msg("%s lane %d at (%a, %a): scalar outside, vector not",
                                         sh.ops->name, k, x[k], y[k]);
                            continue;
                        }
                        if (bad[k])
                            fail_msg("%s lane %d at (%a, %a): vector outside, scalar not",
                                     sh.ops->name, k, x[k], y[k]);
                        if (isinf(gs[0]) || isinf(hs))
                            inf_lanes++;
                        if (!same_bits(zs, z[k]) || !same_bits(gs[0], g[0][k]) ||
                            !same_bits(gs[1], g[1][k]) || !same_bits(hs, h[k]))
                            fail_msg("%s lane %d at (%a, %a): sag %a vs %a, slopes %a %a vs "
                                     "%a %a, bound %a vs %a",
                                     sh.ops->name, k, x[k], y[k], zs, z[k], gs[0], gs[1],
                                     g[0][k], g[1][k], hs, h[k]);
                    }
                }
            }
    for (ti = 0; ti < n_shapes; ti++) {
        if (!case_of(types[ti])->vec)
            continue;
        print_message("# vector double kernel, type %d: %d lanes, %d outside the shape\n",
                      types[ti], lanes[ti], bad_lanes[ti]);
        assert_true(bad_lanes[ti] > lanes[ti] / 20 && bad_lanes[ti] < lanes[ti] / 2);
    }
    /* The rim lanes reach the infinite slopes and bounds. */
    assert_true(inf_lanes > 0);
}

/* On the axis, r = 0, of shapes whose curve has even polynomial terms
 * (a toroid's y^4 term, an odd asphere's r^4 term): the second-derivative
 * bound once took r^(2k) / r^2 = 0 / 0 there, so the precise and classic
 * traces refused the chief ray (OUT OF RANGE) and every ray with y = 0 on
 * the toroid.  Each method must now trace them, and precise must give the
 * 256-bit MPFR trace rounded, within its bound. */
static void axis_terms(void **state)
{
    sg_catalog *cat = tu_catalog();
    static const double rays[][4] = {{0, 0, 0, 0}, {0, 0, 0.3, 0}, {0, 0, -0.7, 0}};
    int shape;
    (void)state;
    for (shape = 0; shape < 2; shape++) {
        sg_system *sys = tu_example("cassegrain.json");
        sg_surface *p = &sys->surf[2];
        sg_tracer *tp, *tc, *tm;
        size_t r;
        if (shape == 0) {
            p->type = SG_SURF_TOROIDAL;
            p->radius_x = p->radius;
        } else {
            p->type = SG_SURF_ODDASPH;
            p->odd[2] = 1e-13; /* r^3 */
        }
        p->asph[0] = 0.0;
        p->asph[1] = 1e-16; /* y^4 or r^4 */
        tp = tu_tracer(sys, cat, SG_METHOD_PRECISE);
        tc = tu_tracer(sys, cat, SG_METHOD_CLASSIC);
        tm = tu_tracer(sys, cat, SG_METHOD_MPFR);
        for (r = 0; r < sizeof rays / sizeof *rays; r++) {
            sg_ray_surface a[16], b[16], c[16];
            int i, n = sys->nsurf;
            assert_true(n <= 16);
            sg_trace_normalized(tp, rays[r][0], rays[r][1], rays[r][2], rays[r][3], a);
            sg_trace_normalized(tc, rays[r][0], rays[r][1], rays[r][2], rays[r][3], b);
            sg_trace_normalized(tm, rays[r][0], rays[r][1], rays[r][2], rays[r][3], c);
            for (i = 1; i < n; i++) {
                if (a[i].status != SG_OK || b[i].status != SG_OK || c[i].status != SG_OK)
                    fail_msg("shape %d ray %zu surface %d: precise %s, classic %s, mpfr %s", shape,
                             r, i, sg_err_name(a[i].status), sg_err_name(b[i].status),
                             sg_err_name(c[i].status));
                if (!(fabs(a[i].x - c[i].x) <= a[i].error_bound &&
                      fabs(a[i].y - c[i].y) <= a[i].error_bound &&
                      fabs(a[i].z - c[i].z) <= a[i].error_bound && isfinite(a[i].dir_error_bound)))
                    fail_msg("shape %d ray %zu surface %d: precise (%.17g, %.17g, %.17g) bound %g, "
                             "mpfr (%.17g, %.17g, %.17g)", shape, r, i, a[i].x, a[i].y, a[i].z,
                             a[i].error_bound, c[i].x, c[i].y, c[i].z);
            }
        }
        sg_tracer_free(tp);
        sg_tracer_free(tc);
        sg_tracer_free(tm);
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* The Q-type asphere against values from another program: its sag and
 * slopes from mpmath's Jacobi polynomials at 50 digits
 * (tests/data/qcon_ref.py), at points inside and beyond the normalization
 * radius. */
static void qcon_forbes_values(void **state)
{
    static const double a[] = {2e-3, -5e-4, 1e-4, -3e-5, 1e-5, 4e-6};
    static const struct {
        double x, y;
        const char *z, *gx, *gy;
    } pt[] = {
        {3.0, 4.0, "0.3131561411031732675226880287391475775896",
         "0.07528383130332571843302405081689009787925",
         "0.1003784417377676245773654010891867971723"},
        {0.0, 9.5, "1.134395241294212756851286858729953547665", "0.0",
         "0.2397834173728828904334280918752569645722"},
        {7.125, -6.25, "1.129071194950235952807322795619092820032",
         "0.1798313589410181212253998800349735511489",
         "-0.1577468060886123870398244561710294308324"},
    };
    mpfr_t x, y, z, gx, gy, ref, e, tmp[SG_SHAPE_MPTMP], mc[SG_SHAPE_MPC];
    sg_surface f;
    sg_shape sh;
    size_t i;
    int k;
    (void)state;
    memset(&f, 0, sizeof f);
    f.type = SG_SURF_QCON;
    f.radius = 40.0;
    f.conic = -0.7;
    f.norm_radius = 10.0;
    for (k = 0; k < 6; k++)
        f.terms[k] = a[k];
    assert_int_equal(sg_shape_prepare(&f, &sh, 1, NULL), SG_OK);
    mpfr_inits2(PREC, x, y, z, gx, gy, ref, e, (mpfr_ptr)0);
    for (k = 0; k < SG_SHAPE_MPTMP; k++)
        mpfr_init2(tmp[k], PREC);
    sg_shape_mp_coefs(&sh, mc, PREC);
    for (i = 0; i < sizeof pt / sizeof pt[0]; i++) {
        dd zz, gg[2];
        double ez, eg, zd, gd[2], h, ref_d[3];
        const char *want[3] = {pt[i].z, pt[i].gx, pt[i].gy};
        for (k = 0; k < 3; k++) {
            mpfr_set_str(ref, want[k], 10, MPFR_RNDN);
            ref_d[k] = mpfr_get_d(ref, MPFR_RNDN);
        }
        /* MPFR: to the reference's 40 digits. */
        mpfr_set_d(x, pt[i].x, MPFR_RNDN);
        mpfr_set_d(y, pt[i].y, MPFR_RNDN);
        assert_true(sh.ops->sag_mp(&sh, mc, x, y, z, gx, gy, tmp));
        mpfr_set_str(ref, pt[i].z, 10, MPFR_RNDN);
        mpfr_sub(e, z, ref, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= 1e-38);
        mpfr_set_str(ref, pt[i].gx, 10, MPFR_RNDN);
        mpfr_sub(e, gx, ref, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= 1e-38);
        mpfr_set_str(ref, pt[i].gy, 10, MPFR_RNDN);
        mpfr_sub(e, gy, ref, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= 1e-38);
        /* Double-double: within its bounds, which are near its precision. */
        assert_true(sh.ops->sag_dd(&sh, dd_from(pt[i].x), dd_from(pt[i].y), &zz, gg, &ez, &eg));
        mpfr_set_str(ref, pt[i].z, 10, MPFR_RNDN);
        mpfr_set_d(e, zz.hi, MPFR_RNDN);
        mpfr_add_d(e, e, zz.lo, MPFR_RNDN);
        mpfr_sub(e, e, ref, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= ez);
        assert_true(ez < 1e-28);
        mpfr_set_str(ref, pt[i].gy, 10, MPFR_RNDN);
        mpfr_set_d(e, gg[1].hi, MPFR_RNDN);
        mpfr_add_d(e, e, gg[1].lo, MPFR_RNDN);
        mpfr_sub(e, e, ref, MPFR_RNDN);
        assert_true(fabs(mpfr_get_d(e, MPFR_RNDN)) <= eg);
        assert_true(eg < 1e-28);
        /* Double: to a few ulps. */
        assert_true(sh.ops->sag_d(&sh, pt[i].x, pt[i].y, &zd, gd, &h));
        assert_true(fabs(zd - ref_d[0]) <= 1e-15 * fabs(ref_d[0]));
        assert_true(fabs(gd[0] - ref_d[1]) <= 1e-15 * (fabs(ref_d[1]) + fabs(ref_d[2])));
        assert_true(fabs(gd[1] - ref_d[2]) <= 1e-15 * (fabs(ref_d[1]) + fabs(ref_d[2])));
    }
    sg_shape_mp_clear(mc);
    mpfr_clears(x, y, z, gx, gy, ref, e, (mpfr_ptr)0);
    for (k = 0; k < SG_SHAPE_MPTMP; k++)
        mpfr_clear(tmp[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(kernel_bounds),
        cmocka_unit_test(trace_sets),
        cmocka_unit_test(carried_error),
        cmocka_unit_test(reductions),
        cmocka_unit_test(vector_kernel),
        cmocka_unit_test(vector_kernel_d),
        cmocka_unit_test(zernike_decenter_closed_form),
        cmocka_unit_test(axis_terms),
        cmocka_unit_test(qcon_forbes_values),
    };
    if (!find_shapes())
        return 1;
    return cmocka_run_group_tests(tests, NULL, NULL);
}
