/*
 * test_merit_ops.c - the first-order, edge, real-ray, image-quality,
 * Seidel, arithmetic and physical-optics operands against independent
 * values: thick-lens formulas (EFL, back focus, principal planes, the
 * exit pupil by the refraction equation), hand paraxial traces, the sag
 * formula, Snell's law, a paraboloid's focal property, a spherical
 * mirror's W040 = h^4 / (4 R^3) and Petzval term, the monocentric
 * mirror's curved focus, the circular pupil's MTF 2/pi (phi - cos phi
 * sin phi), the defocused pupil's Strehl ratio (sin(pi W) / (pi W))^2, and
 * failures that name their row.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define PI 3.14159265358979323846

static sg_system *parse(const char *text)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "t", &d) != SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

static void eval(const sg_system *sys, const sg_catalog *cat, sg_merit_result *r)
{
    sg_diag d;
    sg_diag_clear(&d);
    if (sg_merit_eval(sys, cat, r, &d) != SG_OK)
        fail_msg("%s", d.msg);
}

static void near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol * fmax(fabs(want), 1e-300)))
        fail_msg("%s: %.17g, expected %.17g (rtol %g)", what, got, want, tol);
}

static void near_abs(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: %.17g, expected %.17g (atol %g)", what, got, want, tol);
}

/* A singlet of index n: radii R1, R2 (0: flat), thickness T, air B to the
 * image; object at distance T0 (0: infinity); field angle or object
 * height fmax; every semi-diameter sd; EPD epd or image F/# fno. */
static sg_system *singlet(double R1, double R2, double T, double B, double T0, double fmax,
                          double sd, const char *aper, const char *ops)
{
    static char text[16384];
    char r1[32], r2[32], t0[32];
    snprintf(r1, sizeof r1, R1 == 0 ? "\"inf\"" : "%.17g", R1);
    snprintf(r2, sizeof r2, R2 == 0 ? "\"inf\"" : "%.17g", R2);
    snprintf(t0, sizeof t0, T0 == 0 ? "\"inf\"" : "%.17g", T0);
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
             "\"fields\": {\"type\": \"%s\", \"list\": [{\"y\": 0}, {\"y\": %.17g}]},"
             "\"aperture\": %s,"
             "\"surfaces\": ["
             "{\"radius\": \"inf\", \"thickness\": %s},"
             "{\"radius\": %s, \"thickness\": %.17g, \"material\": 1.5, \"stop\": true,"
             " \"semi_diameter\": %.17g},"
             "{\"radius\": %s, \"thickness\": %.17g, \"semi_diameter\": %.17g},"
             "{\"radius\": \"inf\", \"thickness\": 0, \"semi_diameter\": %.17g}],"
             "\"merit\": {\"operands\": [%s]}}",
             T0 == 0 ? "angle" : "object_height", fmax, aper, t0, r1, T, sd, r2, B, sd, sd, ops);
    return parse(text);
}

static double thick_efl(double n, double R1, double R2, double T)
{
    double c1 = 1 / R1, c2 = 1 / R2;
    return 1 / ((n - 1) * (c1 - c2 + (n - 1) * T * c1 * c2 / n));
}

/* First order against the thick-lens formulas and hand traces. */
static void first_order(void **state)
{
    const double n = 1.5, R1 = 50, R2 = -80, T = 6, B = 40, fno = 4;
    double f = thick_efl(n, R1, R2, T), epd = f / fno, c1 = 1 / R1, c2 = 1 / R2;
    /* The exit pupil: the stop (surface 1) imaged by surface 2. */
    double sp = 1 / (n / -T + (1 - n) * c2), expp = sp - B;
    /* A hand paraxial trace (y, u) of the chief ray at 2 degrees through
     * the vertex of surface 1 (the stop), and of the marginal ray. */
    double u = tan(2 * PI / 180), u1 = u / n, y2 = T * u1, phi2 = (1 - n) * c2;
    double u2 = n * u1 - y2 * phi2, y3 = y2 + B * u2;
    double ym2 = epd / 2 * (1 - T * (n - 1) * c1 / n);
    sg_system *sys = singlet(R1, R2, T, B, 0, 2, 12, "{\"type\": \"image_fnum\", \"value\": 4}",
                             "{\"type\": \"ISFN\", \"wave\": 1},"
                             "{\"type\": \"EPDI\"},"
                             "{\"type\": \"EXPP\"},"
                             "{\"type\": \"PARY\", \"surf\": 3, \"wave\": 1, \"hy\": 1},"
                             "{\"type\": \"PARX\", \"surf\": 3, \"wave\": 0, \"hx\": 1},"
                             "{\"type\": \"PARY\", \"surf\": 2, \"wave\": 1, \"py\": 1},"
                             "{\"type\": \"PANA\", \"surf\": 1, \"wave\": 1, \"px\": 1},"
                             "{\"type\": \"PARY\", \"surf\": 2, \"wave\": 1, \"hy\": 0.5,"
                             " \"py\": -0.5}");
    sg_merit_result r;
    (void)state;
    eval(sys, NULL, &r);
    near(r.row[0].value, fno, 1e-13, "ISFN");
    near(r.row[1].value, epd, 1e-13, "EPDI");
    near(r.row[2].value, expp, 1e-13, "EXPP");
    near(r.row[3].value, y3, 1e-13, "PARY chief");
    near(r.row[4].value, y3, 1e-13, "PARX chief");
    near(r.row[5].value, ym2, 1e-13, "PARY marginal");
    near(r.row[6].value, -c1 * epd / 2, 1e-13, "PANA");
    /* Paraxial rays add: half the field, minus half the aperture; the
     * chief ray at half the angle has slope tan(1 degree). */
    near(r.row[7].value, tan(PI / 180) / u * y2 - ym2 / 2, 1e-12, "PARY sum");
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* PMAG at a finite object against the principal planes of the thick
 * lens: h1 = -f (n-1) T / (n R2) from the first vertex, then Newton's
 * 1/s' - 1/s = 1/f from it. */
static void pmag(void **state)
{
    const double n = 1.5, R1 = 50, R2 = -80, T = 6, L = 200;
    double f = thick_efl(n, R1, R2, T), h1 = -f * (n - 1) * T / (n * R2), s = -(L + h1);
    double sp = 1 / (1 / f + 1 / s), m = sp / s;
    sg_system *sys = singlet(R1, R2, T, 60, L, 3, 12, "{\"type\": \"epd\", \"value\": 10}",
                             "{\"type\": \"PMAG\", \"wave\": 1}");
    sg_system *inf = singlet(R1, R2, T, 60, 0, 3, 12, "{\"type\": \"epd\", \"value\": 10}",
                             "{\"type\": \"PMAG\", \"wave\": 1}");
    sg_merit_result r;
    sg_diag d;
    (void)state;
    eval(sys, NULL, &r);
    near(r.row[0].value, m, 1e-13, "PMAG");
    sg_merit_result_free(&r);
    /* At infinity it has no value: an error naming the row. */
    sg_diag_clear(&d);
    assert_int_not_equal(sg_merit_eval(inf, NULL, &r, &d), SG_OK);
    assert_non_null(strstr(d.msg, "operand 1 (PMAG)"));
    sg_system_free(sys);
    sg_system_free(inf);
}

static sg_system *mirror(double R, double conic, double epd, double stop_dist, double image,
                         double fmax, const char *ops)
{
    if (strlen(ops) > 16000)
        fail_msg("mirror: the operands are too long");
    static char text[20000];
    if (stop_dist > 0)
        snprintf(text, sizeof text,
                 "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
                 "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
                 "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": %.17g}]},"
                 "\"aperture\": {\"type\": \"epd\", \"value\": %.17g},"
                 "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
                 "{\"radius\": \"inf\", \"thickness\": %.17g, \"stop\": true},"
                 "{\"radius\": %.17g, \"conic\": %.17g, \"thickness\": %.17g, \"material\":"
                 " \"MIRROR\"},"
                 "{\"radius\": \"inf\", \"thickness\": 0}],"
                 "\"merit\": {\"operands\": [%s]}}",
                 fmax, epd, stop_dist, -R, conic, image, ops);
    else
        snprintf(text, sizeof text,
                 "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
                 "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
                 "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": %.17g}]},"
                 "\"aperture\": {\"type\": \"epd\", \"value\": %.17g},"
                 "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
                 "{\"radius\": %.17g, \"conic\": %.17g, \"thickness\": %.17g, \"material\":"
                 " \"MIRROR\", \"stop\": true},"
                 "{\"radius\": \"inf\", \"thickness\": 0}],"
                 "\"merit\": {\"operands\": [%s]}}",
                 fmax, epd, -R, conic, image, ops);
    return parse(text);
}

/* WFNO of a paraboloid of focal length f at infinity: the marginal ray at
 * height h meets the focus from f + h^2 / (4 f) away (the focal
 * property), so sin theta = h / (f + h^2 / (4 f)); ISFN is f / EPD. */
static void wfno_paraboloid(void **state)
{
    const double f = 100, h = 20;
    sg_system *sys = mirror(2 * f, -1, 2 * h, 0, -f, 1,
                            "{\"type\": \"WFNO\", \"wave\": 1}, {\"type\": \"ISFN\"}");
    sg_merit_result r;
    (void)state;
    eval(sys, NULL, &r);
    near(r.row[0].value, (f + h * h / (4 * f)) / (2 * h), 1e-13, "WFNO");
    near(r.row[1].value, f / (2 * h), 1e-13, "ISFN");
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

static double sphere_sag(double R, double h)
{
    return h * h / R / (1.0 + sqrt(1.0 - h * h / (R * R)));
}

/* The edge boundaries against the sag formula, at, below and above their
 * limits: surface 1 is glass, surface 2 air, both at height 9. */
static void edge_boundaries(void **state)
{
    const double R1 = 50, R2 = -80, T = 6, B = 40, h = 9;
    double eg = T + sphere_sag(R2, h) - sphere_sag(R1, h), ea = B - sphere_sag(R2, h);
    static const struct { const char *type; int which; double dt, want; } t[] = {
        /* which: 0 glass, 1 air, 2 both; want: 0 target, 1 the value,
         * 2 the target plus (MX) or less (MN) the root sum square. */
        {"MXET", 2, 1.0, 0}, {"MXET", 1, -1.0, 1}, {"MXET", 1, 0.0, 0},
        {"MNEG", 0, 1.0, 1}, {"MNEG", 0, 0.0, 0}, {"MNEG", 0, -1.0, 0},
        {"MXEG", 0, -1.0, 1}, {"MXEG", 0, 1.0, 0},
        {"MNEA", 1, 1.0, 1}, {"MNEA", 1, -1.0, 0},
        {"MXEA", 1, -1.0, 1}, {"MXEA", 1, 1.0, 0}, {"MXEA", 1, 0.0, 0},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof t / sizeof t[0]; i++) {
        double base = t[i].which == 1 ? ea : t[i].which == 0 ? eg : ea;
        double target = base + t[i].dt, want = t[i].want == 0 ? target : base;
        char op[256], what[64];
        sg_system *sys;
        sg_merit_result r;
        snprintf(op, sizeof op, "{\"type\": \"%s\", \"surf1\": 1, \"surf2\": 2, \"target\": "
                 "%.17g}", t[i].type, target);
        sys = singlet(R1, R2, T, B, 0, 2, h, "{\"type\": \"epd\", \"value\": 10}", op);
        eval(sys, NULL, &r);
        snprintf(what, sizeof what, "case %zu (%s)", i, t[i].type);
        near(r.row[0].value, want, 1e-13, what);
        sg_merit_result_free(&r);
        sg_system_free(sys);
    }
    {
        /* MXET over both, each above 4: 4 plus the root sum square. */
        sg_system *sys = singlet(R1, R2, T, B, 0, 2, h, "{\"type\": \"epd\", \"value\": 10}",
                                 "{\"type\": \"MXET\", \"surf1\": 0, \"surf2\": 0, "
                                 "\"target\": 4}");
        sg_merit_result r;
        eval(sys, NULL, &r);
        assert_true(eg > 4 && ea > 4);
        near(r.row[0].value, 4 + hypot(eg - 4, ea - 4), 1e-13, "MXET all");
        sg_merit_result_free(&r);
        sg_system_free(sys);
    }
}

/* REAR on the stop, where the pupil lies: the pupil radius times rho;
 * RANG after a flat glass surface: Snell's asin(sin t / n). */
static void rear_rang(void **state)
{
    sg_system *sys = singlet(0, -80, 6, 40, 0, 10, 12, "{\"type\": \"epd\", \"value\": 10}",
                             "{\"type\": \"REAR\", \"surf\": 1, \"wave\": 1, \"px\": 0.6,"
                             " \"py\": 0.8},"
                             "{\"type\": \"RANG\", \"surf\": 1, \"wave\": 1, \"hy\": 1},"
                             "{\"type\": \"RANG\", \"surf\": 1, \"wave\": 1, \"hy\": 0}");
    sg_merit_result r;
    (void)state;
    eval(sys, NULL, &r);
    near(r.row[0].value, 5.0, 1e-15, "REAR");
    near(r.row[1].value, asin(sin(10 * PI / 180) / 1.5), 1e-14, "RANG");
    assert_true(r.row[2].value == 0.0);
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* A slow spherical mirror at infinity, stop on it, image at the paraxial
 * focus: its wavefront is W040 rho^4 with W040 = h^4 / (4 R^3) to a few
 * parts in (h / R)^2.  SPHA is that in waves (third order, exactly);
 * RWCE the RMS of rho^4 less its mean, W040 sqrt(1/5 - 1/9); OPDX of a
 * quadrature group the same RMS; RWRE the same on its grid (the test sums
 * rho^4 over the grid's points); ZERN's Fringe Z9 W040 / 6 and Z4 three
 * times that; TRAC's group the RMS spot that RSCE gives. */
static void spherical_mirror_wavefront(void **state)
{
    const double R = 400, h = 10, lam = 0.55e-3;
    double w040 = h * h * h * h / (4 * R * R * R) / lam, rho[32], wt[32];
    char ops[16384];
    size_t m = 0;
    int i, j, arms = 10, grid = 40, nops;
    sg_system *sys;
    sg_merit_result r;
    double s1 = 0, s2 = 0, cnt = 0, sw = 0, sq = 0, strac = 0;
    (void)state;
    sg_merit_rings(3, rho, wt);
    m += (size_t)snprintf(ops + m, sizeof ops - m,
                          "{\"type\": \"SPHA\", \"surf\": 0, \"wave\": 0},"
                          "{\"type\": \"RWCE\", \"rings\": 3, \"wave\": 1},"
                          "{\"type\": \"RWRE\", \"grid\": %d, \"wave\": 1},"
                          "{\"type\": \"ZERN\", \"term\": 9, \"wave\": 1, \"sampling\": 2,"
                          " \"field\": 1},"
                          "{\"type\": \"ZERN\", \"term\": 4, \"wave\": 1, \"sampling\": 2,"
                          " \"field\": 1},"
                          "{\"type\": \"RSCE\", \"rings\": 3, \"wave\": 1, \"hy\": 0.5},"
                          "{\"type\": \"OPDX\", \"wave\": 1, \"py\": 0.3, \"hy\": 1}",
                          grid);
    nops = 7;
    /* The OPDX group and the TRAC group on RSCE's quadrature (3 rings,
     * 2 * 3 + 4 arms), weighted by it. */
    for (i = 0; i < 3; i++)
        for (j = 0; j < arms; j++) {
            double th = PI * (2.0 * j + 1.0) / arms;
            m += (size_t)snprintf(ops + m, sizeof ops - m,
                                  ",{\"type\": \"OPDX\", \"wave\": 1, \"px\": %.17g, \"py\": "
                                  "%.17g, \"weight\": %.17g}",
                                  rho[i] * cos(th), rho[i] * sin(th), wt[i] / arms);
        }
    for (i = 0; i < 3; i++)
        for (j = 0; j < arms; j++) {
            double th = PI * (2.0 * j + 1.0) / arms;
            m += (size_t)snprintf(ops + m, sizeof ops - m,
                                  ",{\"type\": \"TRAC\", \"wave\": 1, \"hy\": 0.5, \"px\": "
                                  "%.17g, \"py\": %.17g, \"weight\": %.17g}",
                                  rho[i] * cos(th), rho[i] * sin(th), wt[i] / arms);
        }
    sys = mirror(R, 0, 2 * h, 0, -R / 2, 0.5, ops);
    eval(sys, NULL, &r);
    near(fabs(r.row[0].value), w040, 1e-12, "SPHA");
    near(r.row[1].value, w040 * sqrt(1.0 / 5 - 1.0 / 9), 3e-3, "RWCE");
    /* The grid's own mean and variance of rho^4. */
    for (i = 0; i < grid; i++)
        for (j = 0; j < grid; j++) {
            double x = -1.0 + (2.0 * j + 1.0) / grid, y = -1.0 + (2.0 * i + 1.0) / grid;
            double q = (x * x + y * y) * (x * x + y * y);
            if (x * x + y * y > 1.0)
                continue;
            s1 += q;
            s2 += q * q;
            cnt++;
        }
    near(r.row[2].value, w040 * sqrt(s2 / cnt - (s1 / cnt) * (s1 / cnt)), 3e-3, "RWRE");
    near(fabs(r.row[3].value), w040 / 6, 3e-3, "ZERN 9");
    near(r.row[4].value / r.row[3].value, 3.0, 3e-3, "ZERN 4 / ZERN 9");
    /* A group of one OPDX: its piston is all there is. */
    assert_true(r.row[6].value == 0.0);
    for (i = 0; i < 3 * arms; i++) {
        sw += r.row[nops + i].weight;
        sq += r.row[nops + i].weight * r.row[nops + i].value * r.row[nops + i].value;
        strac += r.row[nops + 3 * arms + i].weight * r.row[nops + 3 * arms + i].value *
                 r.row[nops + 3 * arms + i].value;
    }
    near(sqrt(sq / sw), r.row[1].value, 1e-9, "OPDX group");
    near(sqrt(strac / sw), r.row[5].value, 1e-12, "TRAC group");
    /* OPDC at the pupil's edge: the whole W040, less nothing. */
    sg_merit_result_free(&r);
    sg_system_free(sys);
    sys = mirror(R, 0, 2 * h, 0, -R / 2, 0.5,
                 "{\"type\": \"OPDC\", \"wave\": 1, \"py\": 1},"
                 "{\"type\": \"OPDC\", \"wave\": 1, \"px\": 0.5}");
    eval(sys, NULL, &r);
    near(fabs(r.row[0].value), w040, 3e-3, "OPDC edge");
    near(r.row[1].value / r.row[0].value, 1.0 / 16, 3e-3, "OPDC half");
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* A spherical mirror with its stop at the centre of curvature: no coma,
 * astigmatism or distortion (every chief ray meets the mirror normally),
 * FCUR its Petzval term H^2 / (2 R) in waves (H = h tan t, the Lagrange
 * invariant), and the tangential and sagittal foci of a field at t on
 * the sphere of radius R / 2 about the centre: -(R/2)(1 - cos t) from the
 * flat image plane at R / 2 along z (the image space runs toward -z). */
static void monocentric_mirror(void **state)
{
    const double R = 200, h = 5, t = 10 * PI / 180, lam = 0.55e-3;
    sg_system *sys = mirror(R, 0, 2 * h, R, -R / 2, 10,
                            "{\"type\": \"COMA\", \"surf\": 0},"
                            "{\"type\": \"ASTI\", \"surf\": 0},"
                            "{\"type\": \"DIST\", \"surf\": 0},"
                            "{\"type\": \"FCUR\", \"surf\": 0},"
                            "{\"type\": \"FCGT\", \"wave\": 1, \"hy\": 1},"
                            "{\"type\": \"FCGS\", \"wave\": 1, \"hy\": 1},"
                            "{\"type\": \"FCGT\", \"wave\": 1, \"hx\": -1},"
                            "{\"type\": \"DIMX\", \"field\": 0, \"wave\": 1},"
                            "{\"type\": \"FCUR\", \"surf\": 2}");
    sg_merit_result r;
    double H = h * tan(t), fc = -R / 2 * (1 - cos(t));
    (void)state;
    eval(sys, NULL, &r);
    assert_true(fabs(r.row[0].value) < 1e-9);
    assert_true(fabs(r.row[1].value) < 1e-9);
    assert_true(fabs(r.row[2].value) < 1e-9);
    near(fabs(r.row[3].value), H * H / (2 * R) / lam, 1e-12, "FCUR");
    near(r.row[4].value, fc, 1e-7, "FCGT");
    near(r.row[5].value, fc, 1e-7, "FCGS");
    near(r.row[6].value, fc, 1e-7, "FCGT along x");
    /* The chief ray through the centre lands at (R/2) tan t: f tan t. */
    assert_true(fabs(r.row[7].value) < 1e-9);
    assert_true(r.row[8].value == r.row[3].value);
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* DIMX against the real chief ray (REAY) and the thick lens's f tan t, at
 * the paraxial focus (the back focal length f (1 - (n-1) T / (n R1)));
 * DIST (Seidel, percent) is its third-order limit: at 1 degree within
 * a few parts in t^2. */
static void distortion(void **state)
{
    const double n = 1.5, R1 = 50, R2 = -80, T = 6;
    double f = thick_efl(n, R1, R2, T), bfl = f * (1 - (n - 1) * T / (n * R1));
    sg_system *sys = singlet(R1, R2, T, bfl, 0, 10, 20, "{\"type\": \"epd\", \"value\": 10}",
                             "{\"type\": \"DIMX\", \"field\": 0, \"wave\": 1},"
                             "{\"type\": \"REAY\", \"surf\": 3, \"wave\": 1, \"hy\": 1},"
                             "{\"type\": \"DIMX\", \"field\": 0, \"wave\": 1, \"absolute\": 1},"
                             "{\"type\": \"FCGT\", \"wave\": 1, \"hy\": 1},"
                             "{\"type\": \"FCGS\", \"wave\": 1, \"hy\": 1}");
    sg_system *small = singlet(R1, R2, T, bfl, 0, 1, 20, "{\"type\": \"epd\", \"value\": 10}",
                               "{\"type\": \"DIMX\", \"field\": 2, \"wave\": 1},"
                               "{\"type\": \"DIST\", \"surf\": 0, \"wave\": 1},"
                               "{\"type\": \"DIST\", \"surf\": 0, \"wave\": 1, \"absolute\": 1}");
    sg_merit_result r;
    double yp = f * tan(10 * PI / 180), want;
    (void)state;
    eval(sys, NULL, &r);
    want = 100 * (r.row[1].value - yp) / yp;
    assert_true(fabs(want) > 0.1);
    near(r.row[0].value, want, 1e-10, "DIMX");
    near(r.row[2].value, fabs(want), 1e-10, "DIMX absolute");
    {
        /* FCGT and FCGS beside sg_fieldcurve (sagitta fieldcurve), which
         * takes its pairs along y and x by its own code: astigmatic here. */
        sg_fieldcurve_pt fc[2];
        sg_trace_opts o;
        sg_diag d;
        sg_trace_opts_init(&o);
        sg_diag_clear(&d);
        if (sg_fieldcurve(sys, NULL, &o, 2, 0.01, fc, &d) != SG_OK)
            fail_msg("%s", d.msg);
        assert_true(fabs(fc[1].tan_focus - fc[1].sag_focus) > 0.1);
        near(r.row[3].value, fc[1].tan_focus, 1e-9, "FCGT");
        near(r.row[4].value, fc[1].sag_focus, 1e-9, "FCGS");
    }
    sg_merit_result_free(&r);
    eval(small, NULL, &r);
    near(r.row[1].value, r.row[0].value, 2e-3, "DIST against DIMX at 1 degree");
    near(r.row[2].value, fabs(r.row[1].value), 0, "DIST absolute");
    sg_merit_result_free(&r);
    sg_system_free(sys);
    sg_system_free(small);
}

/* AXCL against the thick lens's back focus at each wavelength (N-BK7 by
 * Schott's published Sellmeier coefficients), paraxially and by a real
 * marginal ray of a small zone; LACL against two REAY rows. */
static double bk7(double um)
{
    double l2 = um * um;
    return sqrt(1 + 1.03961212 * l2 / (l2 - 0.00600069867) +
                0.231792344 * l2 / (l2 - 0.0200179144) + 1.01046945 * l2 / (l2 - 103.560653));
}

static void colour(void **state)
{
    const double R1 = 50, R2 = -80, T = 6, l1 = 0.4861327, l2 = 0.6562725;
    double b[2], ls[2] = {l1, l2};
    const char *text =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.4861327}, {\"um\": 0.6562725}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 5}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 50, \"thickness\": 6, \"material\": \"N-BK7\", \"stop\": true},"
        "{\"radius\": -80, \"thickness\": 60}, {\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"AXCL\", \"wave1\": 1, \"wave2\": 2},"
        "{\"type\": \"AXCL\", \"wave1\": 1, \"wave2\": 2, \"zone\": 0.001},"
        "{\"type\": \"LACL\", \"wave1\": 1, \"wave2\": 2},"
        "{\"type\": \"REAY\", \"surf\": 3, \"wave\": 1, \"hy\": 1},"
        "{\"type\": \"REAY\", \"surf\": 3, \"wave\": 2, \"hy\": 1}]}}";
    sg_system *sys = parse(text);
    sg_catalog *cat = tu_catalog();
    sg_merit_result r;
    int k;
    (void)state;
    for (k = 0; k < 2; k++) {
        double n = bk7(ls[k]), f = thick_efl(n, R1, R2, T);
        b[k] = f * (1 - (n - 1) * T / (n * R1));
    }
    eval(sys, cat, &r);
    near(r.row[0].value, b[1] - b[0], 1e-10, "AXCL paraxial");
    near(r.row[1].value, b[1] - b[0], 1e-4, "AXCL zone");
    near_abs(r.row[2].value, r.row[4].value - r.row[3].value, 1e-15, "LACL");
    sg_merit_result_free(&r);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* A paraboloid on axis is perfect: its FFT MTF the circular pupil's
 * 2/pi (phi - cos phi sin phi), cos phi = nu / nu_c, nu_c = 1 / (lambda
 * F#); its geometric MTF 1; its Strehl ratio 1.  Defocused by dz, its
 * pupil has W = W020 rho^2 with W020 = dz NA^2 / 2 (to (NA)^2 of it), and
 * the Strehl ratio (sin(pi W020) / (pi W020))^2. */
static void physical_optics(void **state)
{
    const double f = 400, epd = 40, lam = 0.55e-3;
    double nuc = 1 / (lam * f / epd), nu = 0.3 * nuc, phi = acos(nu / nuc);
    double mtf = 2 / PI * (phi - cos(phi) * sin(phi)), na, w020, dz = 0.2, st;
    char ops[1024];
    sg_system *sys;
    sg_merit_result r;
    (void)state;
    snprintf(ops, sizeof ops,
             "{\"type\": \"MTFT\", \"sampling\": 2, \"wave\": 1, \"field\": 1, \"frequency\": %.17g},"
             "{\"type\": \"MTFS\", \"sampling\": 2, \"wave\": 1, \"field\": 1, \"frequency\": %.17g},"
             "{\"type\": \"MTFA\", \"sampling\": 2, \"wave\": 1, \"field\": 1, \"frequency\": %.17g},"
             "{\"type\": \"GMTT\", \"sampling\": 1, \"wave\": 1, \"field\": 1, \"frequency\": %.17g},"
             "{\"type\": \"GMTS\", \"sampling\": 1, \"wave\": 1, \"field\": 1, \"frequency\": %.17g},"
             "{\"type\": \"GMTA\", \"sampling\": 1, \"wave\": 1, \"field\": 1, \"frequency\": 0},"
             "{\"type\": \"STRH\", \"sampling\": 2, \"wave\": 1, \"field\": 1}",
             nu, nu, nu, nu, nu);
    sys = mirror(2 * f, -1, epd, 0, -f, 1, ops);
    eval(sys, NULL, &r);
    near_abs(r.row[0].value, mtf, 1e-2, "MTFT");
    near_abs(r.row[1].value, mtf, 1e-2, "MTFS");
    near_abs(r.row[2].value, 0.5 * (r.row[0].value + r.row[1].value), 1e-15, "MTFA");
    near_abs(r.row[3].value, 1.0, 1e-9, "GMTT");
    near_abs(r.row[4].value, 1.0, 1e-9, "GMTS");
    assert_true(r.row[5].value == 1.0);
    near_abs(r.row[6].value, 1.0, 1e-9, "STRH");
    sg_merit_result_free(&r);
    sg_system_free(sys);
    /* Defocused. */
    sys = mirror(2 * f, -1, epd, 0, -f - dz, 1,
                 "{\"type\": \"STRH\", \"sampling\": 3, \"wave\": 1, \"field\": 1}");
    eval(sys, NULL, &r);
    na = (epd / 2) / (f + epd * epd / 16 / f);
    w020 = dz * na * na / 2 / lam;
    st = sin(PI * w020) / (PI * w020);
    near_abs(r.row[0].value, st * st, 1e-2, "STRH defocused");
    assert_true(r.row[0].value < 0.95);
    sg_merit_result_free(&r);
    sg_system_free(sys);
}

/* SQRT of an earlier row; rows that cannot be computed name themselves
 * and why, and no value is a NaN. */
static void sqrt_and_failures(void **state)
{
    static const struct { const char *ops, *want; } t[] = {
        {"{\"type\": \"CONS\", \"target\": -4}, {\"type\": \"SQRT\", \"op1\": 1}",
         "operand 2 (SQRT): operand 1 is -4"},
        {"{\"type\": \"STRH\", \"sampling\": 1, \"wave\": 1, \"field\": 3}",
         "operand 1 (STRH): field 3"},
        {"{\"type\": \"ZERN\", \"term\": 4, \"wave\": 1, \"sampling\": 1, \"field\": 1,"
         " \"kind\": 2}", "operand 1 (ZERN): kind 2"},
        {"{\"type\": \"ZERN\", \"term\": 40, \"wave\": 1, \"sampling\": 1, \"field\": 1}",
         "operand 1 (ZERN): term 40"},
        {"{\"type\": \"MTFT\", \"sampling\": 1, \"wave\": 1, \"field\": 1, \"frequency\": -1}",
         "operand 1 (MTFT): frequency -1"},
        {"{\"type\": \"SPHA\", \"surf\": 0, \"wave\": 2}", "operand 1 (SPHA): Seidel"},
        {"{\"type\": \"REAR\", \"surf\": 1, \"wave\": 1, \"py\": 30}", "operand 1 (REAR)"},
        {"{\"type\": \"OPDC\", \"wave\": 1, \"py\": 30}", "operand 1 (OPDC)"},
        {"{\"type\": \"AXCL\", \"wave1\": 1, \"wave2\": 3}", "operand 1 (AXCL): wave1 1"},
        {"{\"type\": \"RSRE\", \"grid\": 0, \"wave\": 1}", "operand 1 (RSRE): grid 0"},
        {"{\"type\": \"DIMX\", \"field\": 3, \"wave\": 1}", "operand 1 (DIMX): field 3"},
        {"{\"type\": \"FCGT\", \"wave\": 1, \"hy\": 60}", "operand 1 (FCGT)"},
        {"{\"type\": \"RWCE\", \"rings\": 3, \"wave\": 1, \"hy\": 40}", "operand 1 (RWCE)"},
        {"{\"type\": \"TRAC\", \"wave\": 1, \"py\": 30}", "operand 1 (TRAC)"},
        {"{\"type\": \"CONS\"}, {\"type\": \"OPDX\", \"wave\": 1, \"py\": 0.5},"
         " {\"type\": \"OPDX\", \"wave\": 1, \"py\": 30}", "operand 3 (OPDX)"},
        {"{\"type\": \"LACL\", \"wave1\": 1, \"wave2\": 2, \"target\": 0},"
         " {\"type\": \"REAY\", \"surf\": 3, \"wave\": 1, \"py\": 30}", "operand 2 (REAY)"},
    };
    size_t i;
    (void)state;
    {
        sg_system *sys = singlet(50, -80, 6, 40, 0, 2, 12, "{\"type\": \"epd\", \"value\": 10}",
                                 "{\"type\": \"CONS\", \"target\": 16},"
                                 "{\"type\": \"SQRT\", \"op1\": 1, \"target\": 3}");
        sg_merit_result r;
        eval(sys, NULL, &r);
        assert_true(r.row[1].value == 4.0);
        sg_merit_result_free(&r);
        sg_system_free(sys);
    }
    for (i = 0; i < sizeof t / sizeof t[0]; i++) {
        const char *text =
            "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
            "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}, {\"um\": 0.65}]},"
            "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 2}]},"
            "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
            "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
            "{\"radius\": 10, \"thickness\": 3, \"material\": 1.5, \"stop\": true},"
            "{\"radius\": -30, \"thickness\": 15}, {\"radius\": \"inf\", \"thickness\": 0}],"
            "\"merit\": {\"operands\": [%s]}}";
        char buf[4096];
        sg_system *sys;
        sg_merit_result r;
        sg_diag d;
        snprintf(buf, sizeof buf, text, t[i].ops);
        sys = parse(buf);
        sg_diag_clear(&d);
        assert_int_not_equal(sg_merit_eval(sys, NULL, &r, &d), SG_OK);
        if (!strstr(d.msg, t[i].want))
            fail_msg("case %zu: \"%s\" lacks \"%s\"", i, d.msg, t[i].want);
        sg_system_free(sys);
    }
}

/* PARY refuses fields given as paraxial image height; WFNO and ISFN of
 * an afocal system (two confocal mirrors' worth of power: a flat plate)
 * name their row, never a NaN. */
static void first_order_refusals(void **state)
{
    const char *text =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
        "\"fields\": {\"type\": \"paraxial_image_height\", \"list\": [{\"y\": 0}, {\"y\": 1}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 50, \"thickness\": 6, \"material\": 1.5, \"stop\": true},"
        "{\"radius\": -80, \"thickness\": 40}, {\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"PARY\", \"surf\": 2, \"hy\": 1}]}}";
    const char *flat =
        "{\"format\": \"sagitta-design\", \"version\": 6, \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": \"inf\", \"thickness\": 6, \"material\": 1.5, \"stop\": true},"
        "{\"radius\": \"inf\", \"thickness\": 40}, {\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"WFNO\"}]}}";
    sg_system *sys = sg_system_new();
    sg_merit_result r;
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    if (sg_design_parse(sys, text, strlen(text), "t", &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_not_equal(sg_merit_eval(sys, NULL, &r, &d), SG_OK);
    assert_non_null(strstr(d.msg, "operand 1 (PARY)"));
    assert_non_null(strstr(d.msg, "angle or object height"));
    sg_system_free(sys);
    sys = sg_system_new();
    sg_diag_clear(&d);
    if (sg_design_parse(sys, flat, strlen(flat), "t", &d) != SG_OK)
        fail_msg("%s", d.msg);
    sg_diag_clear(&d);
    assert_int_not_equal(sg_merit_eval(sys, NULL, &r, &d), SG_OK);
    assert_non_null(strstr(d.msg, "operand 1 (WFNO)"));
    sg_system_free(sys);
}

/* The operands' own keys survive a JSON round trip, bit for bit. */
static void json_keys(void **state)
{
    sg_system *a = singlet(50, -80, 6, 40, 0, 2, 12, "{\"type\": \"epd\", \"value\": 10}",
                           "{\"type\": \"ZERN\", \"term\": 9, \"wave\": 1, \"sampling\": 2,"
                           " \"field\": 2, \"kind\": 1, \"target\": 0.1},"
                           "{\"type\": \"MTFS\", \"sampling\": 3, \"wave\": 0, \"field\": 2,"
                           " \"frequency\": 30.5},"
                           "{\"type\": \"AXCL\", \"wave1\": 1, \"wave2\": 1, \"zone\": 0.7},"
                           "{\"type\": \"OPDX\", \"wave\": 1, \"hx\": 0.25, \"hy\": 0.5,"
                           " \"px\": -0.3, \"py\": 0.1, \"weight\": 2}");
    sg_system *b;
    char *out = sg_design_to_json(a);
    (void)state;
    assert_non_null(out);
    assert_non_null(strstr(out, "\"frequency\": 30.5"));
    b = parse(out);
    assert_true(sg_merit_equal(&a->merit, &b->merit));
    assert_true(b->merit.op[0].px == 1.0 && b->merit.op[1].hy == 30.5 &&
                b->merit.op[2].hx == 0.7);
    free(out);
    sg_system_free(a);
    sg_system_free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(first_order),
        cmocka_unit_test(pmag),
        cmocka_unit_test(wfno_paraboloid),
        cmocka_unit_test(edge_boundaries),
        cmocka_unit_test(rear_rang),
        cmocka_unit_test(spherical_mirror_wavefront),
        cmocka_unit_test(monocentric_mirror),
        cmocka_unit_test(distortion),
        cmocka_unit_test(colour),
        cmocka_unit_test(physical_optics),
        cmocka_unit_test(sqrt_and_failures),
        cmocka_unit_test(first_order_refusals),
        cmocka_unit_test(json_keys),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
