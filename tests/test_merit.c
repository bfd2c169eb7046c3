/*
 * test_merit.c - the merit function's operands against independent
 * values: EFFL against the thick-lens formula, TOTR and TTHI against hand
 * sums, edge thickness against the sag formula, the boundary operands at,
 * below and above their limits, REAY/REAZ against the sphere's equation,
 * TRAY of a spherical mirror against its exact closed form, RSCE against
 * sg_spot_compute (what `sagitta spot` prints) on a dense pupil, the
 * arithmetic operands, MF^2 = sum w (v - t)^2 / sum w, the Gauss-Legendre
 * rings against their published nodes, failures naming the row, and the
 * JSON round trip of variables and the merit object.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

static sg_system *parse(const char *text)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    int rc;
    assert_non_null(sys);
    sg_diag_clear(&d);
    rc = sg_design_parse(sys, text, strlen(text), "t", &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

/* A singlet of index n (no dispersion): radii R1, R2, thickness T, then
 * air B to the image; semi-diameters sd1, sd2 (fixed); the merit's
 * operands given as JSON. */
static sg_system *singlet(double n, double R1, double R2, double T, double B, double sd1,
                          double sd2, const char *ops)
{
    char text[8192];
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 2}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
             "\"surfaces\": ["
             "{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": %.17g, \"thickness\": %.17g, \"material\": %.17g, \"stop\": true,"
             " \"semi_diameter\": %.17g},"
             "{\"radius\": %.17g, \"thickness\": %.17g, \"semi_diameter\": %.17g},"
             "{\"radius\": \"inf\", \"thickness\": 0}],"
             "\"merit\": {\"operands\": [%s]}}",
             R1, T, n, sd1, R2, B, sd2, ops);
    return parse(text);
}

static void eval(const sg_system *sys, sg_merit_result *r)
{
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    rc = sg_merit_eval(sys, NULL, r, &d);
    if (rc != SG_OK)
        fail_msg("%s", d.msg);
}

static void near(double got, double want, double rtol, const char *what)
{
    if (!(fabs(got - want) <= rtol * fmax(fabs(want), 1e-300)))
        fail_msg("%s: %.17g, expected %.17g (rtol %g)", what, got, want, rtol);
}

/* EFFL against 1/f = (n-1) (c1 - c2 + (n-1) T c1 c2 / n). */
static void effl_thick_lens(void **state)
{
    const double n = 1.5, R1 = 50.0, R2 = -80.0, T = 6.0;
    double c1 = 1 / R1, c2 = 1 / R2, f = 1 / ((n - 1) * (c1 - c2 + (n - 1) * T * c1 * c2 / n));
    sg_system *sys = singlet(n, R1, R2, T, 40, 8, 8,
                             "{\"type\": \"EFFL\", \"wave\": 1, \"target\": 0}");
    sg_merit_result r;
    (void)state;
    eval(sys, &r);
    near(r.row[0].value, f, 1e-13, "EFFL");
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* EFFL at another wavelength: N-BK7 by Schott's published Sellmeier
 * coefficients (datasheet: B1 1.03961212, B2 0.231792344, B3 1.01046945,
 * C1 0.00600069867, C2 0.0200179144, C3 103.560653), the thick-lens
 * formula at the d line, the second wavelength (the F line is the
 * first and the primary). */
static void effl_wavelength(void **state)
{
    const double l2 = 0.5875618 * 0.5875618, R1 = 50, R2 = -80, T = 6;
    double n = sqrt(1 + 1.03961212 * l2 / (l2 - 0.00600069867) +
                    0.231792344 * l2 / (l2 - 0.0200179144) + 1.01046945 * l2 / (l2 - 103.560653));
    double c1 = 1 / R1, c2 = 1 / R2, f = 1 / ((n - 1) * (c1 - c2 + (n - 1) * T * c1 * c2 / n));
    const char *text =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.4861327}, {\"um\": 0.5875618}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": 30},"
        "{\"radius\": 50, \"thickness\": 6, \"material\": \"N-BK7\", \"stop\": true},"
        "{\"radius\": -80, \"thickness\": 40}, {\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"EFFL\", \"wave\": 2},"
        "{\"type\": \"TOTR\"}]}}";
    sg_system *sys = parse(text);
    sg_catalog *cat = tu_catalog();
    sg_merit_result r;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    if (sg_merit_eval(sys, cat, &r, &d) != SG_OK)
        fail_msg("%s", d.msg);
    /* The catalog's Sellmeier in double against the datasheet's: 1e-12. */
    near(r.row[0].value, f, 1e-12, "EFFL at d");
    /* TOTR leaves out the object distance. */
    assert_true(r.row[1].value == 46.0);
    sg_merit_result_free(&r);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* TOTR, TTHI and CTVA against hand sums; MF against its definition. */
static void lengths_and_mf(void **state)
{
    sg_system *sys = singlet(1.5, 50, -80, 6, 40, 8, 8,
                             "{\"type\": \"TOTR\", \"target\": 1, \"weight\": 1},"
                             "{\"type\": \"TTHI\", \"surf1\": 1, \"surf2\": 2, \"target\": 0, "
                             "\"weight\": 3},"
                             "{\"type\": \"CTVA\", \"surf\": 1, \"target\": 2, \"weight\": 0},"
                             "{\"type\": \"TTHI\", \"surf1\": 2, \"surf2\": 2, \"target\": 0, "
                             "\"weight\": 0}");
    sg_merit_result r;
    (void)state;
    eval(sys, &r);
    assert_true(r.row[0].value == 46.0);
    assert_true(r.row[1].value == 46.0);
    assert_true(r.row[2].value == 6.0);
    assert_true(r.row[3].value == 40.0);
    /* (1 * 45^2 + 3 * 46^2) / (1 + 3); the zero weights do not count. */
    near(r.merit, sqrt((45.0 * 45.0 + 3.0 * 46.0 * 46.0) / 4.0), 1e-15, "MF");
    near(r.row[0].contribution, 100.0 * 45.0 * 45.0 / (45.0 * 45.0 + 3 * 46.0 * 46.0), 1e-13,
         "contribution");
    assert_true(r.row[2].contribution == 0.0);
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* The boundary operands are the target when kept, the value when not. */
static void boundaries(void **state)
{
    /* Thicknesses: 6 (glass), 40 (air). */
    static const struct { const char *op; double target, want; } t[] = {
        {"{\"type\": \"CTGT\", \"surf\": 1, \"target\": %g}", 5, 5},
        {"{\"type\": \"CTGT\", \"surf\": 1, \"target\": %g}", 6, 6},
        {"{\"type\": \"CTGT\", \"surf\": 1, \"target\": %g}", 7, 6},
        {"{\"type\": \"CTLT\", \"surf\": 1, \"target\": %g}", 5, 6},
        {"{\"type\": \"CTLT\", \"surf\": 1, \"target\": %g}", 6, 6},
        {"{\"type\": \"CTLT\", \"surf\": 1, \"target\": %g}", 7, 7},
        /* MNCT over both: 40 keeps 10, 6 falls short by 4. */
        {"{\"type\": \"MNCT\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 10, 6},
        {"{\"type\": \"MNCT\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 6, 6},
        {"{\"type\": \"MNCT\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 5, 5},
        /* Both below 50: the target less the root sum square of 44, 10. */
        {"{\"type\": \"MNCT\", \"surf1\": 0, \"surf2\": 0, \"target\": %g}", 50,
         50 - 45.122056690713910},
        {"{\"type\": \"MXCT\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 30, 40},
        {"{\"type\": \"MXCT\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 40, 40},
        {"{\"type\": \"MXCT\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 41, 41},
        /* Air (surface 2, 40) and glass (surface 1, 6) separately. */
        {"{\"type\": \"MNCA\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 30, 30},
        {"{\"type\": \"MNCA\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 41, 40},
        {"{\"type\": \"MXCA\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 39, 40},
        {"{\"type\": \"MXCA\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 40, 40},
        {"{\"type\": \"MNCG\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 7, 6},
        {"{\"type\": \"MNCG\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 6, 6},
        {"{\"type\": \"MXCG\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 5, 6},
        {"{\"type\": \"MXCG\", \"surf1\": 1, \"surf2\": 2, \"target\": %g}", 7, 7},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof t / sizeof t[0]; i++) {
        char op[256], what[64];
        sg_system *sys;
        sg_merit_result r;
        snprintf(op, sizeof op, t[i].op, t[i].target);
        sys = singlet(1.5, 50, -80, 6, 40, 8, 8, op);
        eval(sys, &r);
        snprintf(what, sizeof what, "case %zu", i);
        near(r.row[0].value, t[i].want, 1e-15, what);
        sg_merit_result_free(&r);
        sg_system_free(sys);
    }
}

/* Sag of a sphere of radius R at height h. */
static double sphere_sag(double R, double h)
{
    return h * h / R / (1.0 + sqrt(1.0 - h * h / (R * R)));
}

/* Edge thickness from the sag formula, at the larger semi-diameter. */
static void edge_thickness(void **state)
{
    const double R1 = 50, R2 = -80, T = 6, h = 9;
    double et = T + sphere_sag(R2, h) - sphere_sag(R1, h);
    char ops[512];
    sg_system *sys;
    sg_merit_result r;
    (void)state;
    snprintf(ops, sizeof ops,
             "{\"type\": \"ETVA\", \"surf\": 1, \"target\": 0},"
             "{\"type\": \"ETGT\", \"surf\": 1, \"target\": %.17g},"
             "{\"type\": \"ETGT\", \"surf\": 1, \"target\": %.17g},"
             "{\"type\": \"ETLT\", \"surf\": 1, \"target\": %.17g},"
             "{\"type\": \"ETLT\", \"surf\": 1, \"target\": %.17g},"
             "{\"type\": \"MNET\", \"surf1\": 1, \"surf2\": 1, \"target\": %.17g}",
             et - 1, et + 1, et - 1, et + 1, et + 0.5);
    sys = singlet(1.5, R1, R2, T, 40, 8, h, ops);
    eval(sys, &r);
    near(r.row[0].value, et, 1e-14, "ETVA");
    near(r.row[1].value, et - 1, 1e-15, "ETGT kept");
    near(r.row[2].value, et, 1e-14, "ETGT broken");
    near(r.row[3].value, et, 1e-14, "ETLT broken");
    near(r.row[4].value, et + 1, 1e-15, "ETLT kept");
    near(r.row[5].value, et, 1e-14, "MNET broken");
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* REAY and REAZ of the marginal ray on surface 1, the stop with the
 * entrance pupil on it: y = EPD / 2 and z the sphere's sag there. */
static void real_rays(void **state)
{
    sg_system *sys = singlet(1.5, 50, -80, 6, 40, 8, 8,
                             "{\"type\": \"REAY\", \"surf\": 1, \"wave\": 1, \"py\": 1},"
                             "{\"type\": \"REAZ\", \"surf\": 1, \"wave\": 1, \"py\": 1},"
                             "{\"type\": \"REAX\", \"surf\": 1, \"wave\": 1, \"px\": -1},"
                             "{\"type\": \"REAX\", \"surf\": 1, \"wave\": 1, \"py\": 1},"
                             "{\"type\": \"TRAX\", \"wave\": 1, \"hx\": 1},"
                             "{\"type\": \"REAX\", \"surf\": 3, \"wave\": 1, \"hx\": 1}");
    sg_merit_result r;
    (void)state;
    eval(sys, &r);
    /* The chief ray's own transverse aberration is 0 by definition, off
     * the axis too, where its image x is not. */
    assert_true(r.row[4].value == 0.0);
    assert_true(fabs(r.row[5].value) > 1.0);
    near(r.row[0].value, 5.0, 1e-15, "REAY");
    near(r.row[1].value, sphere_sag(50, 5), 1e-14, "REAZ");
    near(r.row[2].value, -5.0, 1e-15, "REAX");
    assert_true(fabs(r.row[3].value) <= 1e-15);
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* A concave spherical mirror of radius R, the image at the paraxial
 * focus R/2: a ray at height h parallel to the axis (sin t = h / R)
 * crosses the axis R / (2 cos t) from the centre, so at the focus it is
 * (R/2)(1/cos t - 1) tan 2t from the axis, on the other side. */
static void tray_spherical_mirror(void **state)
{
    const double R = 200, epd = 40;
    char text[2048];
    sg_system *sys;
    sg_merit_result r;
    double h = epd / 2 * 0.7, t = asin(h / R), want = R / 2 * (1 / cos(t) - 1) * tan(2 * t);
    (void)state;
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": %g},"
             "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": %g, \"thickness\": %g, \"material\": \"MIRROR\", \"stop\": true},"
             "{\"radius\": \"inf\", \"thickness\": 0}],"
             "\"merit\": {\"operands\": [{\"type\": \"TRAY\", \"wave\": 1, \"py\": 0.7},"
             "{\"type\": \"TRAR\", \"wave\": 1, \"px\": 0.7},"
             "{\"type\": \"TRAX\", \"wave\": 1, \"px\": 0.7}]}}",
             epd, -R, -R / 2);
    sys = parse(text);
    eval(sys, &r);
    near(fabs(r.row[0].value), want, 1e-12, "TRAY");
    near(r.row[1].value, want, 1e-12, "TRAR");
    near(fabs(r.row[2].value), want, 1e-12, "TRAX");
    /* Beyond the focus the ray is on the other side of the axis. */
    assert_true(r.row[0].value < 0);
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* RSCE against the RMS about the centroid that sg_spot_compute (sagitta
 * spot) gives on a dense hexapolar pupil: the same integral, two
 * samplings; RSCH likewise about the chief ray.  A hexapolar sum of N
 * rings errs by about 1/N (its edge ring is a whole ring), so the mean
 * square of 100 and 200 rings is extrapolated to N = inf (Richardson:
 * 2 s200^2 - s100^2), leaving an error of order 1/N^2 (2.5e-5): the 12
 * Gauss rings must land within 5e-5 of it, and within 5e-3 of the 200
 * rings alone. */
static double spot_rms(const sg_system *sys, int rings, int ref, int field)
{
    sg_spot_opts o;
    sg_spot s;
    sg_diag d;
    double v;
    sg_spot_opts_init(&o);
    o.pattern = SG_PUPIL_HEXAPOLAR;
    o.density = rings;
    o.reference = ref ? SG_SPOT_REF_CENTROID : SG_SPOT_REF_CHIEF;
    o.wave = 0;
    o.field = field;
    sg_diag_clear(&d);
    if (sg_spot_compute(sys, NULL, &o, &s, &d) != SG_OK)
        fail_msg("%s", d.msg);
    v = s.cell[0].rms;
    sg_spot_free(&s);
    return v;
}

static void rsce_against_spot(void **state)
{
    sg_system *sys = singlet(1.5, 50, -80, 6, 40, 8, 8,
                             "{\"type\": \"RSCE\", \"rings\": 12, \"wave\": 1, \"hy\": 1},"
                             "{\"type\": \"RSCH\", \"rings\": 12, \"wave\": 1, \"hy\": 1},"
                             "{\"type\": \"RSCE\", \"rings\": 12, \"wave\": 1, \"hy\": 0}");
    static const struct { int row, ref, field; } t[] = {{0, 1, 1}, {1, 0, 1}, {2, 1, 0}};
    sg_merit_result r;
    int i;
    (void)state;
    eval(sys, &r);
    for (i = 0; i < 3; i++) {
        double a = spot_rms(sys, 100, t[i].ref, t[i].field);
        double b = spot_rms(sys, 200, t[i].ref, t[i].field);
        double ext = sqrt(2 * b * b - a * a);
        char what[64];
        snprintf(what, sizeof what, "row %d against 200 rings", t[i].row + 1);
        near(r.row[t[i].row].value, b, 5e-3, what);
        snprintf(what, sizeof what, "row %d against the extrapolation", t[i].row + 1);
        near(r.row[t[i].row].value, ext, 5e-5, what);
    }
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* The default part alone: MF = RSCE / sqrt 2 (x and y rows, one weight a
 * ray) when it samples as RSCE does (3 rings, 2 * 3 + 4 arms), about the
 * centroid and, as RSCH, the chief ray; and RSCE of a field along x equals
 * it along y (the lens is round and the 28 arms turn into themselves). */
static void default_part(void **state)
{
    static const char *const refs[] = {"centroid", "chief"};
    int k;
    (void)state;
    for (k = 0; k < 2; k++) {
        char text[4096];
        sg_system *sys;
        sg_merit_result r, q;
        snprintf(text, sizeof text,
                 "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
                 "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
                 "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 3}]},"
                 "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
                 "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
                 "{\"radius\": 50, \"thickness\": 6, \"material\": 1.5, \"stop\": true},"
                 "{\"radius\": -80, \"thickness\": 40}, {\"radius\": \"inf\", \"thickness\": 0}],"
                 "\"merit\": {\"default\": {\"reference\": \"%s\", \"rings\": 3, \"arms\": 10}}}",
                 refs[k]);
        sys = parse(text);
        eval(sys, &r);
        sys->merit.has_default = 0;
        sys->merit.nop = 2;
        memset(sys->merit.op, 0, 2 * sizeof sys->merit.op[0]);
        sys->merit.op[0].type = k ? SG_OP_RSCH : SG_OP_RSCE;
        sys->merit.op[0].i1 = 3;
        sys->merit.op[0].i2 = 1;
        sys->merit.op[0].hy = 1;
        sys->merit.op[0].weight = 1;
        sys->merit.op[1] = sys->merit.op[0];
        sys->merit.op[1].hy = 0;
        sys->merit.op[1].hx = 1;
        eval(sys, &q);
        near(r.merit * sqrt(2.0), q.row[0].value, 1e-12, refs[k]);
        near(q.row[1].value, q.row[0].value, 1e-12, "x field against y field");
        assert_true(r.merit > 1e-3);
        sg_merit_result_free(&r);
        sg_merit_result_free(&q);
        sg_system_free(sys);
    }
}

/* The arithmetic operands on constants. */
static void arithmetic(void **state)
{
    sg_system *sys = singlet(1.5, 50, -80, 6, 40, 8, 8,
                             "{\"type\": \"CONS\", \"target\": 3},"
                             "{\"type\": \"CONS\", \"target\": -4},"
                             "{\"type\": \"SUMM\", \"op1\": 1, \"op2\": 2},"
                             "{\"type\": \"DIFF\", \"op1\": 1, \"op2\": 2},"
                             "{\"type\": \"PROD\", \"op1\": 1, \"op2\": 2},"
                             "{\"type\": \"DIVI\", \"op1\": 1, \"op2\": 2},"
                             "{\"type\": \"ABSO\", \"op1\": 2},"
                             "{\"type\": \"OPGT\", \"op1\": 1, \"target\": 5},"
                             "{\"type\": \"OPGT\", \"op1\": 1, \"target\": 2},"
                             "{\"type\": \"OPLT\", \"op1\": 1, \"target\": 5},"
                             "{\"type\": \"OPLT\", \"op1\": 1, \"target\": 2},"
                             "{\"type\": \"BLNK\", \"target\": 7, \"weight\": 5},"
                             "{\"type\": \"TOTR\", \"target\": 45}");
    sg_merit_result r;
    static const double want[] = {3, -4, -1, 7, -12, -0.75, 4, 3, 2, 5, 3, 0, 46};
    int i;
    (void)state;
    eval(sys, &r);
    for (i = 0; i < 13; i++)
        if (r.row[i].value != want[i])
            fail_msg("row %d: %.17g, expected %g", i + 1, r.row[i].value, want[i]);
    /* Twelve rows of weight 1 (BLNK has none); targets 0 but where given:
     * SUMM 1, DIFF 49, PROD 144, DIVI 0.5625, ABSO 16, OPGT at 5 4, OPLT
     * at 2 1, TOTR 1. */
    near(r.merit, sqrt(216.5625 / 12.0), 1e-15, "MF");
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* Gauss-Legendre on [0, 1]: the 3-point rule's nodes 1/2 and 1/2 +-
 * sqrt(15)/10, weights 4/9 and 5/18 (Abramowitz and Stegun 25.4.29). */
static void quadrature_rings(void **state)
{
    double rho[3], w[3];
    (void)state;
    assert_int_equal(sg_merit_rings(3, rho, w), SG_OK);
    near(rho[0] * rho[0], 0.5 - sqrt(15.0) / 10, 1e-15, "u1");
    near(rho[1] * rho[1], 0.5, 1e-15, "u2");
    near(rho[2] * rho[2], 0.5 + sqrt(15.0) / 10, 1e-15, "u3");
    near(w[0], 5.0 / 18, 1e-15, "w1");
    near(w[1], 4.0 / 9, 1e-15, "w2");
    near(w[2], 5.0 / 18, 1e-15, "w3");
}

/* A ray beyond a fixed semi-diameter: the row and why, never a NaN. */
static void failure_names_row(void **state)
{
    sg_system *sys = singlet(1.5, 50, -80, 6, 40, 4, 8,
                             "{\"type\": \"TOTR\", \"target\": 0},"
                             "{\"type\": \"REAY\", \"surf\": 3, \"wave\": 1, \"py\": 1}");
    sg_merit_result r;
    sg_diag d;
    int rc;
    (void)state;
    sys->surf[1].sd_fixed = 1;
    sg_diag_clear(&d);
    rc = sg_merit_eval(sys, NULL, &r, &d);
    assert_int_not_equal(rc, SG_OK);
    assert_non_null(strstr(d.msg, "operand 2 (REAY)"));
    assert_non_null(strstr(d.msg, "surface 1"));
    sg_system_free(sys);
}

/* Variables and the merit object read, write and read back the same. */
static void json_round_trip(void **state)
{
    const char *text =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true,"
        " \"solves\": {\"radius\": {\"type\": \"variable\"},"
        " \"thickness\": {\"type\": \"variable\", \"min\": 2, \"max\": 20}}},"
        "{\"radius\": -50, \"thickness\": 40, \"solves\": {\"conic\": {\"type\": \"variable\","
        " \"max\": 0}}},"
        "{\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"default\": {\"criterion\": \"spot\", \"reference\": \"chief\","
        " \"rings\": 4, \"arms\": 8},"
        " \"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 100, \"weight\": 2},"
        " {\"type\": \"REAY\", \"surf\": 2, \"wave\": 1, \"hx\": 0.5, \"hy\": 1, \"px\": 0.25,"
        " \"py\": -1, \"target\": 0.125, \"weight\": 0.5}]}}";
    sg_system *a = parse(text), *b;
    char *out = sg_design_to_json(a);
    sg_paddr v[8];
    (void)state;
    assert_non_null(out);
    assert_non_null(strstr(out, "\"version\": 6"));
    b = parse(out);
    assert_true(sg_system_equal(a, b));
    assert_int_equal(b->surf[1].solve[SG_SOLVE_RADIUS].kind, SG_SOLVE_VARIABLE);
    assert_true(isinf(b->surf[1].solve[SG_SOLVE_RADIUS].lo));
    assert_true(b->surf[1].solve[SG_SOLVE_THICKNESS].lo == 2);
    assert_true(b->surf[1].solve[SG_SOLVE_THICKNESS].hi == 20);
    assert_true(b->surf[2].solve[SG_SOLVE_CONIC].hi == 0);
    assert_int_equal(b->merit.nop, 2);
    assert_int_equal(b->merit.reference, SG_MERIT_CHIEF);
    assert_int_equal(b->merit.rings, 4);
    assert_true(b->merit.op[1].py == -1 && b->merit.op[1].target == 0.125);
    /* The variables, addressed through the parameter table. */
    assert_int_equal(sg_variables(b, v, 8), 3);
    assert_string_equal(v[0].param->key, "radius");
    assert_int_equal(v[1].index, 1);
    assert_string_equal(v[2].param->key, "conic");
    assert_true(sg_paddr_get(b, &v[1]) == 5.0);
    sg_paddr_set(b, &v[1], 7.0);
    assert_true(b->surf[1].thickness == 7.0);
    assert_false(sg_system_equal(a, b));
    free(out);
    sg_system_free(a);
    sg_system_free(b);
}

/* Parameter addresses reach array elements and refuse what is not there. */
static void addresses(void **state)
{
    sg_system *sys = singlet(1.5, 50, -80, 6, 40, 8, 8, "");
    sg_paddr a;
    sg_diag d;
    char name[96];
    (void)state;
    assert_int_equal(sg_paddr_make(sys, SG_SCOPE_SURFACE, 2, "asphere", 1, &a, NULL), SG_OK);
    sg_paddr_set(sys, &a, 1e-5);
    assert_true(sys->surf[2].asph[1] == 1e-5);
    sg_paddr_name(&a, name, sizeof name);
    assert_string_equal(name, "surface 2 asphere term r^4");
    assert_int_equal(sg_paddr_make(sys, SG_SCOPE_FIELD, 1, "y", 0, &a, NULL), SG_OK);
    assert_true(sg_paddr_get(sys, &a) == 2.0);
    sg_diag_clear(&d);
    assert_int_equal(sg_paddr_make(sys, SG_SCOPE_SURFACE, 4, "radius", 0, &a, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, "surface 4"));
    sg_diag_clear(&d);
    assert_int_equal(sg_paddr_make(sys, SG_SCOPE_SURFACE, 1, "material", 0, &a, &d), SG_ERANGE);
    sg_diag_clear(&d);
    assert_int_equal(sg_paddr_make(sys, SG_SCOPE_SURFACE, 1, "asphere", 8, &a, &d), SG_ERANGE);
    sg_system_free(sys);
}

/* Bad merit objects are refused naming the place. */
static void bad_input(void **state)
{
    static const struct { const char *merit, *want; } t[] = {
        {"{\"operands\": [{\"type\": \"NOPE\"}]}", "merit: operand 1: type"},
        {"{\"operands\": [{\"target\": 1}]}", "merit: operand 1"},
        {"{\"operands\": [{\"type\": \"EFFL\", \"weight\": -1}]}", "weight"},
        {"{\"default\": {\"rings\": 0}}", "rings"},
        {"{\"default\": {\"criterion\": \"wavefront\"}}", "criterion"},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof t / sizeof t[0]; i++) {
        char text[2048];
        sg_system *sys = sg_system_new();
        sg_diag d;
        snprintf(text, sizeof text,
                 "{\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
                 "{\"radius\": 50, \"thickness\": 5, \"stop\": true},"
                 "{\"radius\": \"inf\", \"thickness\": 0}], \"merit\": %s}", t[i].merit);
        sg_diag_clear(&d);
        assert_int_not_equal(sg_design_parse(sys, text, strlen(text), "t", &d), SG_OK);
        if (!strstr(d.msg, t[i].want))
            fail_msg("case %zu: %s", i, d.msg);
        sg_system_free(sys);
    }
    {
        /* A variable's min above its max. */
        const char *text = "{\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
                           "{\"radius\": 50, \"thickness\": 5, \"stop\": true, \"solves\": "
                           "{\"thickness\": {\"type\": \"variable\", \"min\": 3, \"max\": 2}}},"
                           "{\"radius\": \"inf\", \"thickness\": 0}]}";
        sg_system *sys = sg_system_new();
        sg_diag d;
        sg_diag_clear(&d);
        assert_int_not_equal(sg_design_parse(sys, text, strlen(text), "t", &d), SG_OK);
        assert_non_null(strstr(d.msg, "min"));
        sg_system_free(sys);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(effl_thick_lens),
        cmocka_unit_test(effl_wavelength),
        cmocka_unit_test(lengths_and_mf),
        cmocka_unit_test(boundaries),
        cmocka_unit_test(edge_thickness),
        cmocka_unit_test(real_rays),
        cmocka_unit_test(tray_spherical_mirror),
        cmocka_unit_test(rsce_against_spot),
        cmocka_unit_test(default_part),
        cmocka_unit_test(arithmetic),
        cmocka_unit_test(quadrature_rings),
        cmocka_unit_test(failure_names_row),
        cmocka_unit_test(json_round_trip),
        cmocka_unit_test(addresses),
        cmocka_unit_test(bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
