/*
 * test_seidel.c - Seidel sums against closed forms written out here
 * (Welford, Aberrations of Optical Systems, 1986: the thin lens in terms of
 * its shape and conjugate factors, the stop-shift equations, the Petzval
 * sum) and against real rays traced at small aperture and field.
 */
#include <math.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <string.h>

#include "testutil.h"

static void seidel(const sg_system *sys, const sg_catalog *cat, sg_seidel *s)
{
    sg_diag d;
    sg_diag_clear(&d);
    if (sg_seidel_compute(sys, cat, s, &d) != SG_OK)
        fail_msg("seidel: %s", d.msg);
}

/* |a - b| within tol of scale. */
static void near(const char *what, double a, double b, double tol, double scale)
{
    print_message("# %-28s %.15g  expected %.15g\n", what, a, b);
    if (!(fabs(a - b) <= tol * fabs(scale)))
        fail_msg("%s: %.17g, expected %.17g (tolerance %g of %g)", what, a, b, tol, scale);
}

/* Object (infinite unless obj_dist is finite), n surfaces after it (the
 * last the image), air everywhere, one wavelength. */
static sg_system *blank(int nsurf_after, double obj_dist)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, nsurf_after + 1), SG_OK);
    sys->surf[0].thickness = obj_dist;
    sys->stop = 1;
    return sys;
}

/* A thin lens (zero thickness, index n) in air with the stop at the lens:
 * Welford's eqs. for SI..SV in terms of the power K, shape factor
 * X = (c1 + c2)/(c1 - c2) and conjugate factor Y = (u + u')/(u - u'). */
static void thin_lens_case(double n, double R1, double R2, double obj, double field)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = blank(3, obj);
    sg_seidel s;
    double c1 = 1.0 / R1, c2 = 1.0 / R2, K = (n - 1.0) * (c1 - c2);
    double X = (c1 + c2) / (c1 - c2), y, u, up, Y, H, ub, SI, SII, scale;
    sys->surf[1].radius = R1;
    sys->surf[1].thickness = 0.0;
    sys->surf[1].mat.kind = SG_MAT_INDEX;
    sys->surf[1].mat.index = n;
    sys->surf[2].radius = R2;
    sys->surf[2].thickness = 100.0;
    sys->aper_value = 8.0;
    sys->nfield = 2;
    sys->field[1].y = field;
    sys->field[1].weight = 1.0;
    y = 4.0;
    if (isfinite(obj)) {
        sys->field_type = SG_FIELD_OBJECT_HEIGHT;
        u = y / obj;
        ub = -field / obj; /* the chief ray from the object point through the lens's centre */
    } else {
        u = 0.0;
        ub = tan(field * M_PI / 180.0);
    }
    up = u - y * K;
    Y = (u + up) / (u - up);
    H = -ub * y; /* n (u ybar - ubar y) with ybar = 0 at the lens */
    seidel(sys, cat, &s);
    SI = pow(y, 4) * K * K * K / 4.0 *
         (pow(n / (n - 1.0), 2) + (n + 2.0) / (n * pow(n - 1.0, 2)) * X * X +
          4.0 * (n + 1.0) / (n * (n - 1.0)) * X * Y + (3.0 * n + 2.0) / n * Y * Y);
    SII = -y * y * K * K * H / 2.0 * ((n + 1.0) / (n * (n - 1.0)) * X + (2.0 * n + 1.0) / n * Y);
    scale = fabs(SI) + fabs(SII) + H * H * fabs(K);
    near("thin lens H", s.lagrange, H, 1e-13, H);
    near("thin lens SI", s.total[SG_SEIDEL_SI], SI, 1e-12, scale);
    near("thin lens SII", s.total[SG_SEIDEL_SII], SII, 1e-12, scale);
    near("thin lens SIII", s.total[SG_SEIDEL_SIII], H * H * K, 1e-12, scale);
    near("thin lens SIV", s.total[SG_SEIDEL_SIV], H * H * K / n, 1e-12, scale);
    near("thin lens SV", s.total[SG_SEIDEL_SV], 0.0, 1e-12, scale);
    near("thin lens CI (no dispersion)", s.total[SG_SEIDEL_CI], 0.0, 0.0, 1.0);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void thin_lens(void **state)
{
    (void)state;
    /* Biconvex, plano-convex both ways, a meniscus; at infinity and at
     * finite conjugates. */
    thin_lens_case(1.5, 100.0, -100.0, INFINITY, 3.0);
    thin_lens_case(1.5168, 51.5, INFINITY, INFINITY, 5.0);
    thin_lens_case(1.5168, INFINITY, -51.5, INFINITY, 5.0);
    thin_lens_case(1.7, 40.0, 120.0, INFINITY, 2.0);
    thin_lens_case(1.5, 100.0, -100.0, 300.0, 10.0);
    thin_lens_case(1.6, 60.0, -300.0, 150.0, 4.0);
}

/* Axial colour of a thin N-BK7 lens: CI = y^2 K / V = y^2 (c1 - c2)
 * (nF - nC), the indices taken from the catalog's formula directly. */
static void thin_lens_colour(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = blank(3, INFINITY);
    const sg_glass *g = sg_catalog_find(cat, "N-BK7");
    sg_seidel s;
    double c1 = 1.0 / 80.0, c2 = -1.0 / 120.0, y = 5.0, CI, nF, nC;
    (void)state;
    assert_non_null(g);
    sys->nwave = 3;
    sys->wave[0].um = 0.4861327;
    sys->wave[1].um = 0.5875618;
    sys->wave[2].um = 0.6562725;
    sys->wave[0].weight = sys->wave[1].weight = sys->wave[2].weight = 1.0;
    sys->primary_wave = 1;
    sys->surf[1].radius = 80.0;
    sys->surf[1].thickness = 0.0;
    sys->surf[1].mat.kind = SG_MAT_GLASS;
    strcpy(sys->surf[1].mat.name, "N-BK7");
    sys->surf[2].radius = -120.0;
    sys->surf[2].thickness = 90.0;
    sys->aper_value = 2.0 * y;
    sys->nfield = 2;
    sys->field[1].y = 4.0;
    sys->field[1].weight = 1.0;
    nF = sg_glass_index(g, 0.4861327);
    nC = sg_glass_index(g, 0.6562725);
    CI = y * y * (c1 - c2) * (nF - nC);
    seidel(sys, cat, &s);
    near("thin N-BK7 lens CI", s.total[SG_SEIDEL_CI], CI, 1e-12, CI);
    /* The stop at a thin lens: no lateral colour. */
    near("thin N-BK7 lens CII", s.total[SG_SEIDEL_CII], 0.0, 1e-12, CI);
    assert_true(s.short_um == 0.4861327 && s.long_um == 0.6562725);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A concave spherical mirror, R = -200, object at infinity, field 1 deg,
 * EPD 40.  stop_at_centre: a flat stop 200 before it, at its centre of
 * curvature.  type/conic/a4 shape the mirror. */
static sg_system *mirror(int stop_at_centre, double conic, double a4)
{
    sg_system *sys = blank(stop_at_centre ? 3 : 2, INFINITY);
    int m = stop_at_centre ? 2 : 1;
    if (stop_at_centre)
        sys->surf[1].thickness = 200.0;
    sys->surf[m].radius = -200.0;
    sys->surf[m].thickness = -100.0;
    sys->surf[m].mat.kind = SG_MAT_MIRROR;
    sys->surf[m].conic = conic;
    if (a4 != 0.0) {
        sys->surf[m].type = SG_SURF_EVENASPH;
        sys->surf[m].asph[1] = a4;
    }
    sys->aper_value = 40.0;
    sys->nfield = 2;
    sys->field[1].y = 1.0;
    sys->field[1].weight = 1.0;
    return sys;
}

static void mirror_at_centre(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = mirror(1, 0.0, 0.0);
    sg_seidel s;
    double c = -1.0 / 200.0, y = 20.0, H = -y * tan(M_PI / 180.0), SI;
    (void)state;
    seidel(sys, cat, &s);
    /* The wavefront of a sphere against the paraboloid that images a
     * point at infinity perfectly: twice the sag difference c^3 y^4 / 8,
     * so |W040| = |c|^3 y^4 / 4 and SI = 8 W040 = -2 c^3 y^4 (positive,
     * undercorrected, for the concave mirror). */
    SI = -2.0 * c * c * c * pow(y, 4);
    near("mirror at C: SI", s.total[SG_SEIDEL_SI], SI, 1e-13, SI);
    /* Every chief ray meets the mirror along its normal. */
    near("mirror at C: SII", s.total[SG_SEIDEL_SII], 0.0, 1e-13, SI);
    near("mirror at C: SIII", s.total[SG_SEIDEL_SIII], 0.0, 1e-13, SI);
    near("mirror at C: SV", s.total[SG_SEIDEL_SV], 0.0, 1e-13, SI);
    /* Petzval: H^2 phi / (n n') with phi = (n' - n) c, n = 1, n' = -1. */
    near("mirror at C: SIV", s.total[SG_SEIDEL_SIV], H * H * (-2.0 * c) / -1.0, 1e-13,
         H * H * 2.0 * c);
    near("mirror at C: H", s.lagrange, H, 1e-13, H);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The stop moved from the centre of curvature to the mirror: Welford's
 * stop-shift equations with E = (ybar* - ybar) / y at the mirror, where
 * the old chief ray (through C at slope tan 1 deg) is 200 tan 1 deg high. */
static void mirror_stop_shift(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sc = mirror(1, 0.0, 0.0), *sm = mirror(0, 0.0, 0.0);
    sg_seidel a, b;
    double E = -200.0 * tan(M_PI / 180.0) / 20.0, S1, S2, S3, S4, S5, sc_;
    (void)state;
    seidel(sc, cat, &a);
    seidel(sm, cat, &b);
    S1 = a.total[SG_SEIDEL_SI];
    S2 = a.total[SG_SEIDEL_SII];
    S3 = a.total[SG_SEIDEL_SIII];
    S4 = a.total[SG_SEIDEL_SIV];
    S5 = a.total[SG_SEIDEL_SV];
    sc_ = fabs(S1) + fabs(S4);
    near("stop shift SI", b.total[SG_SEIDEL_SI], S1, 1e-13, sc_);
    near("stop shift SII", b.total[SG_SEIDEL_SII], S2 + E * S1, 1e-13, sc_);
    near("stop shift SIII", b.total[SG_SEIDEL_SIII], S3 + 2 * E * S2 + E * E * S1, 1e-13, sc_);
    near("stop shift SIV", b.total[SG_SEIDEL_SIV], S4, 1e-13, sc_);
    near("stop shift SV", b.total[SG_SEIDEL_SV],
         S5 + E * (3 * S3 + S4) + 3 * E * E * S2 + E * E * E * S1, 1e-13, sc_);
    /* Not trivially zero: the mirror at its own stop has coma. */
    assert_true(fabs(b.total[SG_SEIDEL_SII]) > 1e-3 * sc_);
    sg_seidel_free(&a);
    sg_seidel_free(&b);
    sg_system_free(sc);
    sg_system_free(sm);
    sg_catalog_free(cat);
}

/* A paraboloid images a point at infinity perfectly: SI = 0, whether the
 * conic is k = -1 or the same quartic comes from A4 = -c^3 / 8 on a
 * sphere.  Its coma with the stop on the mirror is the sphere's. */
static void paraboloid(void **state)
{
    sg_catalog *cat = tu_catalog();
    double c = -1.0 / 200.0;
    sg_system *sp = mirror(0, 0.0, 0.0), *pk = mirror(0, -1.0, 0.0),
              *pa = mirror(0, 0.0, -c * c * c / 8.0), *pcc = mirror(1, -1.0, 0.0);
    sg_seidel s0, s1, s2, s3;
    double S1;
    (void)state;
    seidel(sp, cat, &s0);
    seidel(pk, cat, &s1);
    seidel(pa, cat, &s2);
    seidel(pcc, cat, &s3);
    S1 = s0.total[SG_SEIDEL_SI];
    near("paraboloid (k = -1) SI", s1.total[SG_SEIDEL_SI], 0.0, 1e-14, S1);
    near("paraboloid (A4) SI", s2.total[SG_SEIDEL_SI], 0.0, 1e-14, S1);
    near("paraboloid (stop at C) SI", s3.total[SG_SEIDEL_SI], 0.0, 1e-14, S1);
    near("paraboloid SII = sphere's", s1.total[SG_SEIDEL_SII], s0.total[SG_SEIDEL_SII], 1e-14,
         S1);
    near("paraboloid SIII = sphere's", s1.total[SG_SEIDEL_SIII], s0.total[SG_SEIDEL_SIII],
         1e-14, S1);
    /* With the stop at C the paraboloid's quartic brings coma: the
     * aspheric term 8 G (n' - n) y^3 ybar with G = -c^3 / 8. */
    near("paraboloid (stop at C) SII", s3.total[SG_SEIDEL_SII],
         -c * c * c * (-2.0) * pow(20.0, 3) * 200.0 * tan(M_PI / 180.0), 1e-12, S1);
    sg_seidel_free(&s0);
    sg_seidel_free(&s1);
    sg_seidel_free(&s2);
    sg_seidel_free(&s3);
    sg_system_free(sp);
    sg_system_free(pk);
    sg_system_free(pa);
    sg_system_free(pcc);
    sg_catalog_free(cat);
}

/* The Petzval sum of the Cooke triplet: SIV = H^2 sum phi / (n n'), with
 * H = (EPD / 2) tan(field) at the entrance pupil and the indices from the
 * glass formulas. */
static void petzval_triplet(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_seidel s;
    sg_paraxial p;
    sg_diag d;
    double um = sys->wave[sys->primary_wave].um, sum = 0.0, nb = 1.0, H, fmax = 0.0;
    int j, k;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    assert_int_equal(sys->field_type, SG_FIELD_ANGLE);
    for (k = 0; k < sys->nfield; k++)
        fmax = fmax > hypot(sys->field[k].x, sys->field[k].y)
                   ? fmax
                   : hypot(sys->field[k].x, sys->field[k].y);
    for (j = 1; j < sys->nsurf; j++) {
        const sg_surface *sf = &sys->surf[j];
        double na = 1.0, c = sg_surface_curvature(sf);
        if (sf->mat.kind == SG_MAT_GLASS)
            na = sg_glass_index(sg_catalog_find(cat, sf->mat.name), um);
        else if (sf->mat.kind == SG_MAT_INDEX)
            na = sf->mat.index;
        sum += (na - nb) * c / (na * nb);
        nb = na;
    }
    H = p.epd / 2.0 * tan(fmax * M_PI / 180.0);
    seidel(sys, cat, &s);
    near("triplet H", fabs(s.lagrange), H, 1e-12, H);
    near("triplet SIV", s.total[SG_SEIDEL_SIV], H * H * sum, 1e-12, H * H * sum);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* ---- against real rays ------------------------------------------------ */

typedef struct rr {
    sg_tracer *t;
    sg_ray_surface *out;
    int n;
} rr;

static void image_xy(rr *r, double hy, double px, double py, double *x, double *y)
{
    int st = sg_trace_normalized(r->t, 0.0, hy, px, py, r->out);
    if (st != SG_OK)
        fail_msg("real ray (%g, %g, %g) failed: %d", hy, px, py, st);
    *x = r->out[r->n - 1].x;
    *y = r->out[r->n - 1].y;
}

static double ey(rr *r, double hy, double px, double py)
{
    double x, y;
    image_xy(r, hy, px, py, &x, &y);
    return y;
}

static double ex(rr *r, double hy, double px, double py)
{
    double x, y;
    image_xy(r, hy, px, py, &x, &y);
    return x;
}

/* The coefficient of p^k in f(p) = a p^k + b p^(k+2) + c p^(k+4), from
 * f at p = 1, 1/2 and 1/4 (Cramer's rule), so that the fifth and seventh
 * orders do not enter the third-order term. */
static double lead(int k, double f1, double fh, double fq)
{
    double p[3] = { 1.0, 0.5, 0.25 }, f[3] = { f1, fh, fq }, m[3][3], det, num;
    int i;
    for (i = 0; i < 3; i++) {
        m[i][0] = pow(p[i], k);
        m[i][1] = pow(p[i], k + 2);
        m[i][2] = pow(p[i], k + 4);
    }
#define DET3(a00, a01, a02, a10, a11, a12, a20, a21, a22)                                  \
    ((a00) * ((a11) * (a22) - (a12) * (a21)) - (a01) * ((a10) * (a22) - (a12) * (a20)) +      \
     (a02) * ((a10) * (a21) - (a11) * (a20)))
    det = DET3(m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2]);
    num = DET3(f[0], m[0][1], m[0][2], f[1], m[1][1], m[1][2], f[2], m[2][1], m[2][2]);
#undef DET3
    return num / det;
}

/* The p^3 coefficient of f(p) = L p + C p^3 + F p^5 + G p^7 (four points). */
static double cubic(double f1, double fh, double fq, double fe)
{
    /* g(p) = f(p) / p = L + C p^2 + F p^4 + G p^6; g(p) - L removes L by
     * differences: (g(p) - g(p/2)) / p^2 ... solved as a 3x3 system of
     * the differences g(1) - g(1/8), g(1/2) - g(1/8), g(1/4) - g(1/8). */
    double g1 = f1, gh = fh / 0.5, gq = fq / 0.25, ge = fe / 0.125, e2 = 0.125 * 0.125;
    double a[3][3], b[3], det;
    int i;
    double pp[3] = { 1.0, 0.25, 0.0625 };
    b[0] = g1 - ge;
    b[1] = gh - ge;
    b[2] = gq - ge;
    for (i = 0; i < 3; i++) {
        a[i][0] = pp[i] - e2;
        a[i][1] = pp[i] * pp[i] - e2 * e2;
        a[i][2] = pp[i] * pp[i] * pp[i] - e2 * e2 * e2;
    }
    det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
          a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
          a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    return (b[0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
            a[0][1] * (b[1] * a[2][2] - a[1][2] * b[2]) +
            a[0][2] * (b[1] * a[2][1] - a[1][1] * b[2])) /
           det;
}

/* A design scaled to small aperture and field so that fifth-order terms
 * fall far below the third-order ones; each transverse value is measured
 * on real rays (precise method) with the lower orders cancelled. */
static void real_rays_case(const char *file, double epd, double field, double tol)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example(file);
    sg_seidel s;
    sg_paraxial p;
    sg_diag d;
    rr r;
    double t[SG_NTCOEF], chief, L0, LT, LS, scale, ps[3] = { 1.0, 0.5, 0.25 }, ev[3], od[3],
        sy[3], sx[3];
    int k;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = epd;
    sys->aim = SG_AIM_OFF;
    sys->nfield = 2;
    sys->field[0].x = sys->field[0].y = 0.0;
    sys->field[1].x = 0.0;
    sys->field[1].y = field;
    sys->field_norm = SG_NORM_RADIAL;
    for (k = 1; k < sys->nsurf; k++)
        sys->surf[k].sd_fixed = 0;
    /* The sums describe the paraxial image plane; a defocused plane would
     * add a cubic term of its own (the defocus times the cube of the
     * slope). */
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    sys->surf[sys->nsurf - 2].thickness = p.image_dist;
    assert_int_equal(sg_paraxial_compute(sys, cat, -1, &p, &d), SG_OK);
    seidel(sys, cat, &s);
    sg_seidel_transverse(s.total, s.nu_image, t);
    r.t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    r.n = sg_tracer_nsurf(r.t);
    r.out = test_malloc(sizeof *r.out * (size_t)r.n);
    scale = fabs(t[SG_TSPH]) + fabs(t[SG_TTCO]) + fabs(t[SG_TTFC]) + fabs(t[SG_TSFC]) +
            fabs(t[SG_TDIS]);
    print_message("# %s at EPD %g, field %g, scale %g\n", file, epd, field, scale);

    /* Spherical: the cubic term of the axial fan. */
    near("TSPH vs real rays",
         cubic(ey(&r, 0, 0, 1), ey(&r, 0, 0, 0.5), ey(&r, 0, 0, 0.25), ey(&r, 0, 0, 0.125)),
         t[SG_TSPH], tol, scale);
    L0 = lead(1, ey(&r, 0, 0, 1), ey(&r, 0, 0, 0.5), ey(&r, 0, 0, 0.25));
    /* Tangential coma: the even part of the tangential fan at full field. */
    chief = ey(&r, 1, 0, 0);
    for (k = 0; k < 3; k++) {
        double q = ps[k];
        ev[k] = (ey(&r, 1, 0, q) + ey(&r, 1, 0, -q)) / 2.0 - chief;
        od[k] = (ey(&r, 1, 0, q) - ey(&r, 1, 0, -q)) / 2.0;
        sy[k] = ey(&r, 1, q, 0) - chief;
        sx[k] = ex(&r, 1, q, 0);
    }
    near("TTCO vs real rays", lead(2, ev[0], ev[1], ev[2]), t[SG_TTCO], tol, scale);
    /* Sagittal coma: the y of the sagittal rays. */
    near("TSCO vs real rays", lead(2, sy[0], sy[1], sy[2]), t[SG_TSCO], tol, scale);
    /* Field curvature: the linear terms of the fans at full field less
     * the axial one (the image plane's defocus). */
    LT = lead(1, od[0], od[1], od[2]);
    LS = lead(1, sx[0], sx[1], sx[2]);
    near("TTFC vs real rays", LT - L0, t[SG_TTFC], tol, scale);
    near("TSFC vs real rays", LS - L0, t[SG_TSFC], tol, scale);
    near("TAST vs real rays", LT - LS, t[SG_TAST], tol, scale);
    /* Distortion: the chief ray against the paraxial image height. */
    near("TDIS vs real rays", chief - p.parax_image_height, t[SG_TDIS], tol, scale);

    test_free(r.out);
    sg_tracer_free(r.t);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

static void real_rays(void **state)
{
    (void)state;
    real_rays_case("singlet.json", 0.25, 0.25, 1e-4);
    real_rays_case("cooke_triplet.json", 0.25, 0.25, 1e-4);
    real_rays_case("double_gauss.json", 0.25, 0.25, 1e-4);
    real_rays_case("cassegrain.json", 20.0, 0.02, 1e-4);
}

/* The even asphere's quartic against real rays: a mirror whose sphere is
 * corrected by A4 (to SI = 0 at third order) and then over-corrected. */
static void asphere_real_rays(void **state)
{
    sg_catalog *cat = tu_catalog();
    double c = -1.0 / 200.0;
    sg_system *sys = mirror(1, 0.0, -3.0 * c * c * c / 8.0);
    sg_seidel s;
    rr r;
    double t[SG_NTCOEF], chief, ev[3];
    int k;
    (void)state;
    sys->aper_value = 2.0;
    sys->field[1].y = 0.05;
    seidel(sys, cat, &s);
    sg_seidel_transverse(s.total, s.nu_image, t);
    r.t = tu_tracer(sys, cat, SG_METHOD_PRECISE);
    r.n = sg_tracer_nsurf(r.t);
    r.out = test_malloc(sizeof *r.out * (size_t)r.n);
    near("asphere TSPH vs real rays",
         cubic(ey(&r, 0, 0, 1), ey(&r, 0, 0, 0.5), ey(&r, 0, 0, 0.25), ey(&r, 0, 0, 0.125)),
         t[SG_TSPH], 1e-6, t[SG_TSPH]);
    chief = ey(&r, 1, 0, 0);
    for (k = 0; k < 3; k++) {
        double q = 1.0 / (1 << k);
        ev[k] = (ey(&r, 1, 0, q) + ey(&r, 1, 0, -q)) / 2.0 - chief;
    }
    near("asphere TTCO vs real rays", lead(2, ev[0], ev[1], ev[2]), t[SG_TTCO], 1e-5,
         t[SG_TTCO]);
    test_free(r.out);
    sg_tracer_free(r.t);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* The conversions are Zemax's formulas, written out again here. */
static void conversions(void **state)
{
    double s[SG_SEIDEL_N] = { 1.0, 2.0, 3.0, 5.0, 7.0, 11.0, 13.0 }, w[SG_NWCOEF],
           t[SG_NTCOEF], lam = 0.5e-3, nu = -0.1;
    (void)state;
    sg_seidel_waves(s, lam, w);
    sg_seidel_transverse(s, nu, t);
    assert_true(w[SG_W040] == 1.0 / 8 / lam && w[SG_W131] == 2.0 / 2 / lam);
    assert_true(w[SG_W222] == 3.0 / 2 / lam && w[SG_W220P] == 5.0 / 4 / lam);
    assert_true(w[SG_W311] == 7.0 / 2 / lam && w[SG_W020] == 11.0 / 2 / lam);
    assert_true(w[SG_W111] == 13.0 / lam && w[SG_W220S] == 8.0 / 4 / lam);
    assert_true(w[SG_W220M] == 11.0 / 4 / lam && w[SG_W220T] == 14.0 / 4 / lam);
    assert_true(t[SG_TSPH] == 1.0 / (2 * nu) && t[SG_TSCO] == 2.0 / (2 * nu));
    assert_true(t[SG_TTCO] == 6.0 / (2 * nu) && fabs(t[SG_TAST] - 3.0 / nu) < 1e-15);
    assert_true(t[SG_TPFC] == 5.0 / (2 * nu) && t[SG_TSFC] == 8.0 / (2 * nu));
    assert_true(t[SG_TTFC] == 14.0 / (2 * nu) && t[SG_TDIS] == 7.0 / (2 * nu));
    assert_true(fabs(t[SG_TAXC] - 11.0 / nu) < 1e-13 && fabs(t[SG_TLAC] - 13.0 / nu) < 1e-13);
}

/* Third-order theory is of a centred system: a tilt or decenter anywhere
 * is named (the field and a warning), a centred system gets neither. */
static void decentred(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cooke_triplet.json");
    sg_seidel s;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_seidel_compute(sys, cat, &s, &d), SG_OK);
    assert_int_equal(s.decentred, -1);
    assert_int_equal(d.nwarn, 0);
    sg_seidel_free(&s);
    /* A tilt of surface 4 before it. */
    sys->surf[4].before.tx = 0.5;
    sg_diag_clear(&d);
    assert_int_equal(sg_seidel_compute(sys, cat, &s, &d), SG_OK);
    assert_int_equal(s.decentred, 4);
    assert_int_equal(d.nwarn, 1);
    assert_non_null(strstr(d.warn[0], "surface 4 is tilted or decentred"));
    sg_seidel_free(&s);
    /* And a decenter after surface 2, given explicitly. */
    sys->surf[2].after_mode = SG_AFTER_EXPLICIT;
    sys->surf[2].after.dy = 0.1;
    sg_diag_clear(&d);
    assert_int_equal(sg_seidel_compute(sys, cat, &s, &d), SG_OK);
    assert_int_equal(s.decentred, 2);
    sg_seidel_free(&s);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(thin_lens),
        cmocka_unit_test(thin_lens_colour),
        cmocka_unit_test(mirror_at_centre),
        cmocka_unit_test(mirror_stop_shift),
        cmocka_unit_test(paraboloid),
        cmocka_unit_test(petzval_triplet),
        cmocka_unit_test(real_rays),
        cmocka_unit_test(asphere_real_rays),
        cmocka_unit_test(conversions),
        cmocka_unit_test(decentred),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
