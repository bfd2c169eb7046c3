/*
 * test_tolerance.c - tolerancing (src/design/tolerance.c): the "tolerances"
 * object read, checked and written back; each operand's perturbed design
 * against the same design changed by hand (values, surface tilts and
 * decenters, and an element's coordinate breaks, whose global vertices are
 * checked against the rigid motion's closed form); a paraboloid's back
 * focus compensated to R/2 (exact for a paraboloid); the sampler's and
 * aggregator's mean and variance of sums of uniform, truncated normal and
 * parabolic draws against their closed forms; runs identical on one and
 * two threads; the Cassegrain's change for a 1 um decenter of its
 * secondary against the mpfr method at 256 bits.
 */
#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

static sg_system *parse(const char *text, int expect_ok, char *msg, size_t n)
{
    sg_system *sys = sg_system_new();
    sg_diag d;
    int rc;
    assert_non_null(sys);
    sg_diag_clear(&d);
    rc = sg_design_parse(sys, text, strlen(text), "t.json", &d);
    if (msg)
        snprintf(msg, n, "%s", d.msg);
    if (expect_ok && rc != SG_OK)
        fail_msg("%s", d.msg);
    if (!expect_ok && rc == SG_OK)
        fail_msg("accepted a bad tolerances object");
    return sys;
}

/* A singlet design of index 1.5 with the tolerances given. */
static const char *singlet_fmt =
    "{\"format\": \"sagitta-design\", \"units\": \"mm\","
    "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
    "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 3}]},"
    "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
    "\"surfaces\": ["
    "{\"radius\": \"inf\", \"thickness\": \"inf\"},"
    "{\"radius\": 50, \"thickness\": 4, \"material\": 1.5, \"stop\": true},"
    "{\"radius\": -50, \"thickness\": 2, \"material\": \"AIR\"},"
    "{\"radius\": 80, \"thickness\": 3, \"material\": 1.6},"
    "{\"radius\": \"inf\", \"thickness\": 40},"
    "{\"radius\": \"inf\", \"thickness\": 0}],"
    "\"tolerances\": %s}";

static sg_system *singlet(const char *tol, int ok, char *msg, size_t n)
{
    char text[8192];
    snprintf(text, sizeof text, singlet_fmt, tol);
    return parse(text, ok, msg, n);
}

static void must_say(const char *tol, const char *want)
{
    char msg[SG_DIAG_MSG];
    sg_system *s = singlet(tol, 0, msg, sizeof msg);
    if (!strstr(msg, want))
        fail_msg("message \"%s\" lacks \"%s\"", msg, want);
    sg_system_free(s);
}

/* The example reads, writes and reads back the same; bad rows are
 * refused naming the row and key. */
static void json_roundtrip(void **state)
{
    const char *tol =
        "{\"operands\": [{\"type\": \"TRAD\", \"surface\": 2, \"min\": -0.05, \"max\": 0.05},"
        " {\"type\": \"TEDX\", \"first\": 3, \"last\": 4, \"min\": -0.01, \"max\": 0.01},"
        " {\"type\": \"TTHI\", \"surface\": 1, \"adjust\": 2, \"min\": -0.1, \"max\": 0.2},"
        " {\"type\": \"TPAR\", \"surface\": 1, \"parameter\": \"conic\", \"min\": -1e-3,"
        "  \"max\": 1e-3},"
        " {\"type\": \"TIND\", \"surface\": 3, \"min\": -1e-3, \"max\": 1e-3}],"
        " \"compensators\": [{\"surface\": 4, \"parameter\": \"thickness\", \"min\": -1,"
        "  \"max\": 1}],"
        " \"criterion\": {\"type\": \"rms_spot\", \"reference\": \"centroid\","
        "  \"sampling\": {\"pattern\": \"square\", \"density\": 12}},"
        " \"monte_carlo\": {\"trials\": 1000, \"seed\": 17, \"distribution\": \"parabolic\"}}";
    sg_system *a = singlet(tol, 1, NULL, 0), *b;
    char *text;
    sg_diag d;
    (void)state;
    assert_int_equal(a->tol.nop, 5);
    assert_int_equal(a->tol.op[1].type, SG_TOL_TEDX);
    assert_int_equal(a->tol.op[1].surface, 3);
    assert_int_equal(a->tol.op[1].last, 4);
    assert_int_equal(a->tol.op[2].adjust, 2);
    assert_string_equal(a->tol.op[3].param, "conic");
    assert_true(a->tol.op[0].min == -0.05 && a->tol.op[0].max == 0.05);
    assert_int_equal(a->tol.ncomp, 1);
    assert_int_equal(a->tol.comp[0].surface, 4);
    assert_int_equal(a->tol.reference, SG_SPOT_REF_CENTROID);
    assert_int_equal(a->tol.pattern, SG_PUPIL_SQUARE);
    assert_int_equal(a->tol.density, 12);
    assert_int_equal(a->tol.trials, 1000);
    assert_true(a->tol.seed == 17.0);
    assert_int_equal(a->tol.distribution, SG_TOLD_PARABOLIC);
    text = sg_design_to_json(a);
    assert_non_null(text);
    assert_non_null(strstr(text, "\"version\": 7"));
    b = sg_system_new();
    sg_diag_clear(&d);
    if (sg_design_parse(b, text, strlen(text), "back.json", &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_memory_equal(&a->tol, &b->tol, sizeof a->tol);
    free(text);
    sg_system_free(a);
    sg_system_free(b);

    must_say("{\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, \"min\": 0, \"max\": 1},"
             " {\"type\": \"TEDX\", \"first\": 3, \"min\": 0, \"max\": 1}]}",
             "tolerances: operand 2: an element operand needs \"first\" and \"last\"");
    must_say("{\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, \"min\": 1, \"max\": 0}]}",
             "tolerances: operand 1: min");
    must_say("{\"operands\": [{\"type\": \"TRAD\", \"surface\": 4, \"min\": 0, \"max\": 1}]}",
             "tolerances: operand 1 (TRAD): surface 4 is flat");
    must_say("{\"operands\": [{\"type\": \"TXYZ\", \"surface\": 1, \"min\": 0, \"max\": 1}]}",
             "tolerances: operand 1: type: \"TXYZ\" is not a tolerance operand");
    must_say("{\"operands\": [{\"type\": \"TCUR\", \"surface\": 9, \"min\": 0, \"max\": 1}]}",
             "tolerances: operand 1 (TCUR): surface 9 is not a surface");
    must_say("{\"operands\": [{\"type\": \"TPAR\", \"surface\": 1, \"parameter\": \"nope\","
             " \"min\": 0, \"max\": 1}]}", "tolerances: operand 1 (TPAR): surface 1: no parameter");
    must_say("{\"operands\": [{\"type\": \"TEDX\", \"first\": 1, \"last\": 2, \"min\": 0,"
             " \"max\": 1}, {\"type\": \"TEDY\", \"first\": 2, \"last\": 3, \"min\": 0,"
             " \"max\": 1}]}", "tolerances: operand 2 (TEDY): the element overlaps operand 1");
    must_say("{\"operands\": [{\"type\": \"TABB\", \"surface\": 1, \"min\": 0, \"max\": 1}]}",
             "tolerances: operand 1 (TABB): surface 1: only a glass");
    must_say("{\"operands\": [], \"compensators\": [{\"surface\": 4, \"parameter\": "
             "\"thickness\", \"min\": 0}]}", "tolerances: compensator 1: a compensator needs");
    must_say("{\"monte_carlo\": {\"seed\": -1}}", "tolerances: monte_carlo: seed");
    must_say("{\"criterion\": {\"type\": \"mtf\"}}", "tolerances: criterion: type");
    must_say("{\"test_wavelength\": 0.01}", "tolerances: test_wavelength");
    {
        sg_system *ta = singlet("{\"test_wavelength\": 0.55}", 1, NULL, 0), *tb;
        char *j = sg_design_to_json(ta);
        assert_true(ta->tol.test_wave == 0.55);
        assert_non_null(strstr(j, "\"test_wavelength\": 0.55"));
        tb = parse(j, 1, NULL, 0);
        assert_true(sg_system_equal(ta, tb));
        tb->tol.test_wave = 0.6328;
        assert_false(sg_system_equal(ta, tb));
        free(j);
        sg_system_free(ta);
        sg_system_free(tb);
    }
}

/* Every image row of the two systems' traces, bit for bit, over a few
 * fields and pupil points. */
static void same_traces(const sg_system *a, const sg_system *b, const sg_catalog *cat)
{
    static const double pts[][4] = {{0, 0, 0, 0}, {0, 1, 0, 1}, {0, 1, 0.3, -0.7},
                                    {0, 0.5, -1, 0}, {0, 0, 0.6, 0.6}};
    sg_tracer *ta = tu_tracer(a, cat, SG_METHOD_PRECISE), *tb = tu_tracer(b, cat,
                                                                          SG_METHOD_PRECISE);
    sg_ray_surface *ra = calloc((size_t)a->nsurf, sizeof *ra);
    sg_ray_surface *rb = calloc((size_t)b->nsurf, sizeof *rb);
    size_t k;
    for (k = 0; k < sizeof pts / sizeof pts[0]; k++) {
        int sa = sg_trace_normalized(ta, pts[k][0], pts[k][1], pts[k][2], pts[k][3], ra);
        int sb = sg_trace_normalized(tb, pts[k][0], pts[k][1], pts[k][2], pts[k][3], rb);
        assert_int_equal(sa, sb);
        assert_int_equal(sa, SG_OK);
        if (!tu_same_row(&ra[a->nsurf - 1], &rb[b->nsurf - 1]))
            fail_msg("ray %zu: image rows differ: %.17g %.17g against %.17g %.17g", k,
                     ra[a->nsurf - 1].x, ra[a->nsurf - 1].y, rb[b->nsurf - 1].x,
                     rb[b->nsurf - 1].y);
    }
    free(ra);
    free(rb);
    sg_tracer_free(ta);
    sg_tracer_free(tb);
}

/* Applies one operand row k by delta to nom into out. */
static void apply_one(const sg_system *nom, const sg_catalog *cat, int k, double delta,
                      sg_system *out, int *map)
{
    double dv[SG_MAX_TOL_OPERANDS] = {0};
    sg_diag d;
    dv[k] = delta;
    sg_diag_clear(&d);
    if (sg_tol_apply(nom, cat, dv, out, map, &d) != SG_OK)
        fail_msg("%s", d.msg);
}

/* Each value operand changes the value it names by delta, as Zemax's does,
 * and nothing else. */
static void operands_by_hand(void **state)
{
    const char *tol =
        "{\"operands\": ["
        " {\"type\": \"TRAD\", \"surface\": 1, \"min\": -0.5, \"max\": 0.5},"
        " {\"type\": \"TCUR\", \"surface\": 2, \"min\": -1e-3, \"max\": 1e-3},"
        " {\"type\": \"TTHI\", \"surface\": 1, \"adjust\": 2, \"min\": -0.1, \"max\": 0.1},"
        " {\"type\": \"TCON\", \"surface\": 3, \"min\": -0.1, \"max\": 0.1},"
        " {\"type\": \"TPAR\", \"surface\": 2, \"parameter\": \"radius\", \"min\": -1,"
        "  \"max\": 1},"
        " {\"type\": \"TSDX\", \"surface\": 2, \"min\": -0.01, \"max\": 0.01},"
        " {\"type\": \"TSDY\", \"surface\": 2, \"min\": -0.01, \"max\": 0.01},"
        " {\"type\": \"TSTX\", \"surface\": 3, \"min\": -0.1, \"max\": 0.1},"
        " {\"type\": \"TSTY\", \"surface\": 3, \"min\": -0.1, \"max\": 0.1},"
        " {\"type\": \"TIND\", \"surface\": 3, \"min\": -1e-3, \"max\": 1e-3},"
        " {\"type\": \"TFRN\", \"surface\": 3, \"min\": -2, \"max\": 2}]}";
    sg_system *nom = singlet(tol, 1, NULL, 0), *out = sg_system_new(), *hand;
    int k;
    (void)state;
    nom->surf[3].semi_diameter = 6.0; /* TFRN counts over it */
    for (k = 0; k < nom->tol.nop; k++) {
        double v = nom->tol.op[k].max;
        sg_surface *s;
        apply_one(nom, NULL, k, v, out, NULL);
        hand = sg_system_clone(nom);
        switch (k) {
        case 0: hand->surf[1].radius = 50.5; break;
        case 1: hand->surf[2].radius = 1.0 / (1.0 / -50.0 + 1e-3); break;
        case 2: hand->surf[1].thickness = 4.1; hand->surf[2].thickness = 1.9; break;
        case 3: hand->surf[3].conic = 0.1; break;
        case 4: hand->surf[2].radius = -49.0; break;
        case 5: hand->surf[2].before.dx = 0.01; hand->surf[2].after_mode = SG_AFTER_REVERSE;
                break;
        case 6: hand->surf[2].before.dy = 0.01; hand->surf[2].after_mode = SG_AFTER_REVERSE;
                break;
        case 7: hand->surf[3].before.tx = 0.1; hand->surf[3].after_mode = SG_AFTER_REVERSE;
                break;
        case 8: hand->surf[3].before.ty = 0.1; hand->surf[3].after_mode = SG_AFTER_REVERSE;
                break;
        case 9: hand->surf[3].mat.index = 1.601; break;
        case 10:
            /* 2 fringes at 0.6328 um over a 6 mm semi-diameter: a sag
             * change of one wavelength at the edge, dc = 2 lambda / r^2. */
            s = &hand->surf[3];
            s->radius = 1.0 / (1.0 / 80.0 + 2 * 0.6328e-3 / 36.0);
            break;
        }
        if (!sg_system_equal(out, hand))
            fail_msg("operand %d (%s): the perturbed design is not the one made by hand", k + 1,
                     sg_tol_name(nom->tol.op[k].type));
        same_traces(out, hand, NULL);
        sg_system_free(hand);
    }
    /* The nominal is untouched. */
    hand = singlet(tol, 1, NULL, 0);
    hand->surf[3].semi_diameter = 6.0;
    assert_true(sg_system_equal(nom, hand));
    sg_system_free(hand);
    /* Zemax's TWAV: fringes counted at another test wavelength. */
    nom->tol.test_wave = 0.55;
    apply_one(nom, NULL, 10, 2.0, out, NULL);
    assert_true(out->surf[3].radius == 1.0 / (1.0 / 80.0 + 2 * (0.55 * 1e-3) / 36.0));
    sg_system_free(out);
    sg_system_free(nom);
}

/* TIRR: W fringes (double pass at 0.6328 um) at the semi-diameter r are
 * Zemax's Irregular surface's Zs rho^4 + Za rho_y^2 with Zs = Za = W
 * lambda / 4, half spherical, half astigmatism; against the same
 * surface typed by hand as an XY polynomial over x / r, y / r
 * (rho^4 = x^4 + 2 x^2 y^2 + y^4), and the sag at the rim: W half waves
 * along y, half that along x. */
static void tirr_by_hand(void **state)
{
    const char *tol = "{\"operands\": [{\"type\": \"TIRR\", \"surface\": 3, \"min\": -2,"
                      " \"max\": 2}]}";
    sg_system *nom = singlet(tol, 1, NULL, 0), *out = sg_system_new(), *hand;
    /* lambda in micrometres times 1e-3 mm, as the operand rounds it. */
    const double W = 2.0, lam = 0.6328e-3, z = W * 0.6328 * 1e-3 / 4;
    sg_surface *s;
    sg_diag d;
    (void)state;
    nom->surf[3].semi_diameter = 6.0;
    apply_one(nom, NULL, 0, W, out, NULL);
    hand = sg_system_clone(nom);
    s = &hand->surf[3];
    s->type = SG_SURF_XYPOLY;
    s->norm_radius = 6.0;
    s->terms[4] = z;      /* y^2 */
    s->terms[9] = z;      /* x^4 */
    s->terms[11] = 2 * z; /* x^2 y^2 */
    s->terms[13] = z;     /* y^4 */
    if (!sg_system_equal(out, hand))
        fail_msg("TIRR: the perturbed design is not the one made by hand");
    same_traces(out, hand, NULL);
    assert_true(fabs(sg_surface_sag(&out->surf[3], 0, 6) - sg_surface_sag(&nom->surf[3], 0, 6) -
                     W * lam / 2) < 1e-15);
    assert_true(fabs(sg_surface_sag(&out->surf[3], 6, 0) - sg_surface_sag(&nom->surf[3], 6, 0) -
                     W * lam / 4) < 1e-15);
    sg_system_free(hand);
    sg_system_free(out);
    sg_system_free(nom);
    /* A surface that is not standard is refused, naming it. */
    nom = singlet(tol, 1, NULL, 0);
    nom->surf[3].type = SG_SURF_ODDASPH;
    sg_diag_clear(&d);
    assert_int_not_equal(sg_tol_check(nom, &d), SG_OK);
    assert_non_null(strstr(d.msg, "surface 3 is not a standard surface"));
    sg_system_free(nom);
}

/* Nodes and weights of Gauss-Legendre on [0, 1], by Newton on P_n. */
static void gauss_legendre01(int n, double *x, double *w)
{
    int i, k;
    for (i = 0; i < n; i++) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), p0, p1, dp;
        for (k = 0; k < 100; k++) {
            int j;
            double dz;
            p0 = 1.0;
            p1 = z;
            for (j = 2; j <= n; j++) {
                double p2 = ((2 * j - 1) * z * p1 - (j - 1) * p0) / j;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        p0 = 1.0;
        p1 = z;
        for (k = 2; k <= n; k++) {
            double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1.0);
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
}

/* TEZI (Zemax's manual: Int1 the surface, Int2 the last and Int3 the
 * first Standard Zernike term, max the RMS of the surface error): the
 * surface as a Zernike Standard Sag over its semi-diameter with every
 * term the same coefficient, against the same surface typed by hand, and
 * the sag's change integrated over the disc (Gauss-Legendre in r, exact
 * for the polynomial, uniform in theta) has the RMS max, the closed form
 * of Noll's unit-RMS orthogonal terms. */
static void tezi_by_hand(void **state)
{
    const char *tol = "{\"operands\": [{\"type\": \"TEZI\", \"surface\": 3, \"max_term\": 11,"
                      " \"min_term\": 4, \"min\": -1e-4, \"max\": 1e-4}]}";
    sg_system *nom = singlet(tol, 1, NULL, 0), *out = sg_system_new(), *hand;
    const double rms = 1e-4, r0 = 6.0;
    double xr[16], wr[16], sum = 0.0, area = 0.0, got;
    sg_surface *s;
    sg_diag d;
    int j, i, t;
    (void)state;
    assert_int_equal(nom->tol.op[0].zmin, 4);
    assert_int_equal(nom->tol.op[0].zmax, 11);
    nom->surf[3].semi_diameter = r0;
    apply_one(nom, NULL, 0, -rms, out, NULL);
    hand = sg_system_clone(nom);
    s = &hand->surf[3];
    s->type = SG_SURF_ZERNIKE_STANDARD;
    s->norm_radius = r0;
    for (j = 4; j <= 11; j++)
        s->terms[j - 1] = -rms / sqrt(8.0);
    if (!sg_system_equal(out, hand))
        fail_msg("TEZI: the perturbed design is not the one made by hand");
    same_traces(out, hand, NULL);
    gauss_legendre01(16, xr, wr);
    for (i = 0; i < 16; i++)
        for (t = 0; t < 64; t++) {
            double r = r0 * xr[i], th = 2 * M_PI * t / 64.0, x = r * cos(th), y = r * sin(th);
            double dz = sg_surface_sag(&out->surf[3], x, y) - sg_surface_sag(&nom->surf[3], x, y);
            sum += wr[i] * xr[i] * dz * dz;
            area += wr[i] * xr[i];
        }
    got = sqrt(sum / area);
    if (!(fabs(got - rms) < 1e-9 * rms))
        fail_msg("TEZI: the sag's RMS over the disc is %.17g, not %.17g", got, rms);
    sg_system_free(hand);
    sg_system_free(out);
    sg_system_free(nom);
    /* min_term defaults to 2, Zemax's lowest; bad rows are refused. */
    nom = singlet("{\"operands\": [{\"type\": \"TEZI\", \"surface\": 3, \"max_term\": 6, "
                  "\"min\": -1e-4, \"max\": 1e-4}]}", 1, NULL, 0);
    assert_int_equal(nom->tol.op[0].zmin, 2);
    nom->tol.op[0].zmax = 67;
    sg_diag_clear(&d);
    assert_int_not_equal(sg_tol_check(nom, &d), SG_OK);
    assert_non_null(strstr(d.msg, "terms 2 to 67"));
    nom->tol.op[0].zmax = 6;
    nom->tol.op[0].min = -2e-4;
    sg_diag_clear(&d);
    assert_int_not_equal(sg_tol_check(nom, &d), SG_OK);
    assert_non_null(strstr(d.msg, "min must be -max"));
    nom->tol.op[0].min = -1e-4;
    nom->surf[3].type = SG_SURF_ODDASPH;
    sg_diag_clear(&d);
    assert_int_not_equal(sg_tol_check(nom, &d), SG_OK);
    assert_non_null(strstr(d.msg, "not a standard or even asphere"));
    sg_system_free(nom);
    must_say("{\"operands\": [{\"type\": \"TEZI\", \"surface\": 3, \"min\": -1, \"max\": 1}]}",
             "TEZI needs a \"max_term\"");
    must_say("{\"operands\": [{\"type\": \"TRAD\", \"surface\": 3, \"max_term\": 5, \"min\": -1,"
             " \"max\": 1}]}", "only TEZI takes");
}

/* TIND and TABB on a catalog glass: the traces of a fixed index equal to
 * the catalog's formula changed by hand, n + dn, and n(d) + (n - n(d)) vd
 * / (vd + dv), at the F line. */
static void glass_changes(void **state)
{
    const char *tol =
        "{\"operands\": [{\"type\": \"TIND\", \"surface\": 3, \"min\": -2e-3, \"max\": 2e-3},"
        " {\"type\": \"TABB\", \"surface\": 3, \"min\": -3, \"max\": 3}]}";
    sg_catalog *cat = tu_catalog();
    const sg_glass *g = sg_catalog_find(cat, "N-BK7");
    sg_system *nom, *out = sg_system_new(), *hand;
    const double uf = 0.4861327;
    char text[8192], fmt[4096], *at;
    int k, j;
    (void)state;
    assert_non_null(g);
    /* The singlet with N-BK7 for its second lens. */
    snprintf(fmt, sizeof fmt, "%s", singlet_fmt);
    at = strstr(fmt, "\"material\": 1.6}");
    assert_non_null(at);
    memcpy(at, "\"material\": \"N-BK7\"}", strlen("\"material\": \"N-BK7\"}"));
    snprintf(fmt + (at - fmt) + strlen("\"material\": \"N-BK7\"}"),
             sizeof fmt - (size_t)(at - fmt) - strlen("\"material\": \"N-BK7\"}"), "%s",
             strstr(singlet_fmt, "\"material\": 1.6}") + strlen("\"material\": 1.6}"));
    snprintf(text, sizeof text, fmt, tol);
    nom = parse(text, 1, NULL, 0);
    nom->wave[0].um = uf;
    for (k = 0; k < 2; k++) {
        double n = sg_glass_index(g, uf), nd = sg_glass_index(g, 0.5875618);
        static const double pts[][4] = {{0, 0, 0, 1}, {0, 1, 0.5, -0.5}};
        sg_tracer *ta, *tb;
        sg_ray_surface ra[6], rb[6];
        apply_one(nom, cat, k, nom->tol.op[k].max, out, NULL);
        hand = sg_system_clone(nom);
        hand->surf[3].mat.kind = SG_MAT_INDEX;
        hand->surf[3].mat.index = k == 0 ? n + 2e-3 : nd + (n - nd) * g->vd / (g->vd + 3.0);
        ta = tu_tracer(out, cat, SG_METHOD_PRECISE);
        tb = tu_tracer(hand, cat, SG_METHOD_PRECISE);
        for (j = 0; j < 2; j++) {
            assert_int_equal(sg_trace_normalized(ta, pts[j][0], pts[j][1], pts[j][2], pts[j][3],
                                                 ra), SG_OK);
            assert_int_equal(sg_trace_normalized(tb, pts[j][0], pts[j][1], pts[j][2], pts[j][3],
                                                 rb), SG_OK);
            /* The hand's index is the double nearest; the change's is
             * rounded once from MPFR: a few ulps of the index apart. */
            if (fabs(ra[5].y - rb[5].y) > 1e-12 || fabs(ra[5].x - rb[5].x) > 1e-12)
                fail_msg("%s ray %d: image %.17g %.17g against %.17g %.17g",
                         sg_tol_name(nom->tol.op[k].type), j, ra[5].x, ra[5].y, rb[5].x,
                         rb[5].y);
        }
        sg_tracer_free(ta);
        sg_tracer_free(tb);
        sg_system_free(hand);
    }
    sg_system_free(out);
    sg_system_free(nom);
    sg_catalog_free(cat);
}

/* An element's decenter and tilt: coordinate breaks around it, as they
 * would be typed in; the element moves rigidly about its first vertex and
 * the surfaces after it stay where they were. */
static void element_by_hand(void **state)
{
    const char *tol =
        "{\"operands\": ["
        " {\"type\": \"TEDX\", \"first\": 1, \"last\": 2, \"min\": -0.02, \"max\": 0.02},"
        " {\"type\": \"TETX\", \"first\": 1, \"last\": 2, \"min\": -0.2, \"max\": 0.2},"
        " {\"type\": \"TEDY\", \"first\": 3, \"last\": 3, \"min\": -0.02, \"max\": 0.02}]}";
    sg_system *nom = singlet(tol, 1, NULL, 0), *out = sg_system_new(), *hand;
    sg_frame *gn, *go;
    double dv[SG_MAX_TOL_OPERANDS] = {0};
    int map[6], i;
    sg_diag d;
    (void)state;
    /* TEDX 0.02 and TETX 0.2 on surfaces 1-2, TEDY -0.02 on surface 3. */
    dv[0] = 0.02;
    dv[1] = 0.2;
    dv[2] = -0.02;
    sg_diag_clear(&d);
    if (sg_tol_apply(nom, NULL, dv, out, map, &d) != SG_OK)
        fail_msg("%s", d.msg);
    hand = sg_system_clone(nom);
    /* Surface 3 first (the higher element), then 1-2, as a user would:
     * a break, the element with its last thickness going back to the
     * first vertex, the break undone, the original thickness onward. */
    assert_int_equal(sg_system_insert(hand, 3), SG_OK);
    hand->surf[3].type = SG_SURF_COORDBRK;
    hand->surf[3].thickness = 0;
    hand->surf[3].before.dy = -0.02;
    hand->surf[4].thickness = 0.0;
    assert_int_equal(sg_system_insert(hand, 5), SG_OK);
    hand->surf[5].type = SG_SURF_COORDBRK;
    hand->surf[5].before.dy = 0.02;
    hand->surf[5].before.order = 1;
    hand->surf[5].thickness = 3;
    /* Rays start in surface 1's frame, so a plane of the object's medium
     * comes first and the break after it. */
    assert_int_equal(sg_system_insert(hand, 1), SG_OK);
    hand->surf[1].thickness = 0;
    hand->surf[1].mat = hand->surf[0].mat;
    assert_int_equal(sg_system_insert(hand, 2), SG_OK);
    hand->surf[2].type = SG_SURF_COORDBRK;
    hand->surf[2].thickness = 0;
    hand->surf[2].before.dx = 0.02;
    hand->surf[2].before.tx = 0.2;
    hand->surf[4].thickness = -4;
    assert_int_equal(sg_system_insert(hand, 5), SG_OK);
    hand->surf[5].type = SG_SURF_COORDBRK;
    hand->surf[5].before.dx = -0.02;
    hand->surf[5].before.tx = -0.2;
    hand->surf[5].before.order = 1;
    hand->surf[5].thickness = 6;
    assert_int_equal(out->nsurf, 11);
    if (!sg_system_equal(out, hand)) {
        for (i = 0; i < out->nsurf && i < hand->nsurf; i++)
            if (!sg_param_equal(SG_SCOPE_SURFACE, &out->surf[i], &hand->surf[i]))
                print_message("# surface %d differs\n", i);
        fail_msg("the element's coordinate breaks are not the ones made by hand (stop %d, %d)",
                 out->stop, hand->stop);
    }
    same_traces(out, hand, NULL);
    /* The map: nominal 1 -> 3, 2 -> 4, 3 -> 7, 4 -> 9, 5 (image) -> 10. */
    assert_int_equal(map[1], 3);
    assert_int_equal(map[2], 4);
    assert_int_equal(map[3], 7);
    assert_int_equal(map[4], 9);
    assert_int_equal(map[5], 10);
    /* The rigid motion, in the global frame: surface 1's vertex moves by
     * 0.02 in x; surface 2's is 4 along the axis turned 0.2 degrees about
     * x from there; surface 3 moves by -0.02 in y; surface 4 and the image
     * stay. */
    gn = calloc(6, sizeof *gn);
    go = calloc(11, sizeof *go);
    sg_diag_clear(&d);
    /* Both against the image, which stays. */
    assert_int_equal(sg_global_frames(nom, 5, gn, &d), SG_OK);
    assert_int_equal(sg_global_frames(out, 10, go, &d), SG_OK);
    {
        double t = 0.2 * M_PI / 180.0;
        const double want1[3] = {gn[1].o[0] + 0.02, gn[1].o[1], gn[1].o[2]};
        /* Zemax's tilt about x turns +z towards -y. */
        const double want2[3] = {gn[1].o[0] + 0.02, gn[1].o[1] - 4 * sin(t),
                                 gn[1].o[2] + 4 * cos(t)};
        const double want3[3] = {gn[3].o[0], gn[3].o[1] - 0.02, gn[3].o[2]};
        for (i = 0; i < 3; i++) {
            if (fabs(go[map[1]].o[i] - want1[i]) > 1e-14)
                fail_msg("surface 1 vertex %d: %.17g, expected %.17g", i, go[map[1]].o[i],
                         want1[i]);
            if (fabs(go[map[2]].o[i] - want2[i]) > 1e-14)
                fail_msg("surface 2 vertex %d: %.17g, expected %.17g", i, go[map[2]].o[i],
                         want2[i]);
            if (fabs(go[map[3]].o[i] - want3[i]) > 1e-14)
                fail_msg("surface 3 vertex %d: %.17g, expected %.17g", i, go[map[3]].o[i],
                         want3[i]);
            if (fabs(go[map[4]].o[i] - gn[4].o[i]) > 1e-13 ||
                fabs(go[map[5]].o[i] - gn[5].o[i]) > 1e-13)
                fail_msg("the surfaces after the elements moved (axis %d)", i);
        }
        /* The axes after the element are the nominal's. */
        for (i = 0; i < 9; i++)
            if (fabs(go[map[4]].R[i / 3][i % 3] - gn[4].R[i / 3][i % 3]) > 1e-15)
                fail_msg("surface 4's axes turned");
    }
    free(gn);
    free(go);
    sg_system_free(hand);
    sg_system_free(out);
    sg_system_free(nom);
}

/* A paraboloid mirror images an axial point at infinity perfectly at
 * R / 2, whatever R: after TRAD dR, the compensated back focus is
 * (R + dR) / 2. */
static void compensated_focus(void **state)
{
    static const double drs[] = {0.5, -0.8, 0.05};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof drs / sizeof drs[0]; i++) {
        char text[4096];
        double dv[SG_MAX_TOL_OPERANDS] = {0};
        sg_system *nom, *sys = sg_system_new();
        sg_tol_value v;
        sg_tol_opts o;
        sg_diag d;
        int map[3];
        snprintf(text, sizeof text,
                 "{\"format\": \"sagitta-design\", \"units\": \"mm\","
                 "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
                 "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
                 "\"aperture\": {\"type\": \"epd\", \"value\": 20},"
                 "\"surfaces\": ["
                 "{\"radius\": \"inf\", \"thickness\": \"inf\"},"
                 "{\"radius\": -200, \"conic\": -1, \"thickness\": -100, \"material\": "
                 "\"MIRROR\", \"stop\": true},"
                 "{\"radius\": \"inf\", \"thickness\": 0}],"
                 "\"tolerances\": {\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, "
                 "\"min\": -1, \"max\": 1}], \"compensators\": [{\"surface\": 1, "
                 "\"parameter\": \"thickness\", \"min\": -1, \"max\": 1}]}}");
        nom = parse(text, 1, NULL, 0);
        dv[0] = drs[i];
        sg_diag_clear(&d);
        if (sg_tol_apply(nom, NULL, dv, sys, map, &d) != SG_OK)
            fail_msg("%s", d.msg);
        sg_tol_opts_init(&o);
        o.nthreads = 1;
        if (sg_tol_compensate(sys, nom, map, NULL, &o, &v, &d) != SG_OK)
            fail_msg("%s", d.msg);
        /* At a perfect focus the RMS is a cone in the defocus, which the
         * Jacobian's differences blunt: 1e-7 mm of 0.25 mm. */
        if (fabs(sys->surf[1].thickness - (-200.0 + drs[i]) / 2.0) > 1e-7)
            fail_msg("dR %g: back focus %.17g, expected %.17g", drs[i], sys->surf[1].thickness,
                     (-200.0 + drs[i]) / 2.0);
        if (fabs(v.comp[0] - drs[i] / 2.0) > 1e-7)
            fail_msg("dR %g: compensator change %.17g, expected %.17g", drs[i], v.comp[0],
                     drs[i] / 2.0);
        assert_true(v.criterion < 1e-9);
        sg_system_free(sys);
        sg_system_free(nom);
    }
    /* A run compensates the nominal too: 1 mm out of focus, it comes back
     * to R / 2, and so do the rows. */
    {
        sg_system *nom = parse(
            "{\"format\": \"sagitta-design\", \"units\": \"mm\","
            "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
            "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
            "\"aperture\": {\"type\": \"epd\", \"value\": 20},"
            "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
            "{\"radius\": -200, \"conic\": -1, \"thickness\": -99, \"material\": \"MIRROR\","
            " \"stop\": true}, {\"radius\": \"inf\", \"thickness\": 0}],"
            "\"tolerances\": {\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, "
            "\"min\": -0.3, \"max\": 0.3}], \"compensators\": [{\"surface\": 1, "
            "\"parameter\": \"thickness\", \"min\": -2, \"max\": 2}]}}", 1, NULL, 0);
        sg_tol_result r;
        sg_tol_opts o;
        sg_diag d;
        sg_tol_opts_init(&o);
        o.nthreads = 1;
        sg_diag_clear(&d);
        if (sg_tolerance_run(nom, NULL, &o, 1, 0, 1, &r, &d) != SG_OK)
            fail_msg("%s", d.msg);
        if (!(r.nominal.criterion < 1e-8))
            fail_msg("the nominal was not compensated: %.17g", r.nominal.criterion);
        assert_true(r.sens[0].at_min.criterion < 1e-8 && r.sens[0].at_max.criterion < 1e-8);
        /* The design itself is untouched. */
        assert_true(nom->surf[1].thickness == -99.0);
        sg_tol_result_free(&r);
        sg_system_free(nom);
    }
}

/* Turning a round element about its axis changes nothing on axis: with
 * the back focus after it compensating (the return break's thickness in
 * the perturbed design), the result is the nominal's. */
static void round_element_turned(void **state)
{
    const char *tol =
        "{\"operands\": [{\"type\": \"TETZ\", \"first\": 1, \"last\": 2, \"min\": -30,"
        "  \"max\": 30}],"
        " \"compensators\": [{\"surface\": 2, \"parameter\": \"thickness\", \"min\": -3,"
        "  \"max\": 3}]}";
    char text[8192];
    sg_system *nom, *sys = sg_system_new(), *ref;
    double dv[SG_MAX_TOL_OPERANDS] = {0};
    sg_tol_value v0, v1;
    sg_tol_opts o;
    sg_diag d;
    int map[4];
    (void)state;
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
             "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": 50, \"thickness\": 4, \"material\": 1.5, \"stop\": true},"
             "{\"radius\": -50, \"thickness\": 49},"
             "{\"radius\": \"inf\", \"thickness\": 0}], \"tolerances\": %s}", tol);
    nom = parse(text, 1, NULL, 0);
    ref = sg_system_clone(nom);
    sg_tol_opts_init(&o);
    o.nthreads = 1;
    sg_diag_clear(&d);
    if (sg_tol_compensate(nom, ref, NULL, NULL, &o, &v0, &d) != SG_OK)
        fail_msg("%s", d.msg);
    dv[0] = 30;
    if (sg_tol_apply(nom, NULL, dv, sys, map, &d) != SG_OK)
        fail_msg("%s", d.msg);
    /* The break after the element carries the thickness to the image. */
    assert_int_equal(sys->surf[map[2] + 1].type, SG_SURF_COORDBRK);
    if (sg_tol_compensate(sys, ref, map, NULL, &o, &v1, &d) != SG_OK)
        fail_msg("%s", d.msg);
    if (fabs(v1.comp[0]) > 1e-9)
        fail_msg("the compensator moved by %.17g", v1.comp[0]);
    if (fabs(v1.criterion - v0.criterion) > 1e-12 * v0.criterion)
        fail_msg("criterion %.17g, nominal %.17g", v1.criterion, v0.criterion);
    if (fabs(sys->surf[map[2] + 1].thickness - (4.0 + nom->surf[2].thickness)) > 1e-12)
        fail_msg("the return's thickness %.17g, expected %.17g",
                 sys->surf[map[2] + 1].thickness, 4.0 + nom->surf[2].thickness);
    sg_system_free(ref);
    sg_system_free(sys);
    sg_system_free(nom);
}

/* Mean and variance of the sum of a uniform, a normal (limits at +-2
 * sigma) and a parabolic draw of each trial, against their closed forms;
 * the aggregator's percentiles of 1..100. */
static void sampler_statistics(void **state)
{
    const int n = 200000;
    const double lo = -1.0, hi = 3.0, c = 1.0, h = 2.0;
    /* Uniform: h^2 / 3.  Normal cut at +-2 sigma, sigma = h / 2:
     * sigma^2 (1 - 2 * 2 phi(2) / (2 Phi(2) - 1)).  Parabolic, density
     * 3 x^2 / 2 on [-1, 1]: 3 h^2 / 5. */
    const double phi2 = exp(-2.0) / sqrt(2.0 * M_PI), big = erf(2.0 / sqrt(2.0));
    const double vu = h * h / 3.0, vn = (h / 2) * (h / 2) * (1.0 - 4.0 * phi2 / big),
                 vp = 3.0 * h * h / 5.0, var = vu + vn + vp, mean = 3.0 * c;
    double *s = malloc((size_t)n * sizeof *s), v[100];
    sg_tol_stats st;
    int t, k;
    (void)state;
    for (t = 0; t < n; t++) {
        double u = sg_tol_draw(42, (uint64_t)t, 0, SG_TOLD_UNIFORM, lo, hi);
        double g = sg_tol_draw(42, (uint64_t)t, 1, SG_TOLD_NORMAL, lo, hi);
        double p = sg_tol_draw(42, (uint64_t)t, 2, SG_TOLD_PARABOLIC, lo, hi);
        assert_true(u >= lo && u <= hi && g >= lo && g <= hi && p >= lo && p <= hi);
        s[t] = u + g + p;
    }
    sg_tol_statistics(s, n, &st);
    assert_int_equal(st.n, n);
    /* Five standard errors: of the mean sqrt(var / n), of the variance
     * about var sqrt(2 / n) (the sum is nearly normal). */
    if (fabs(st.mean - mean) > 5.0 * sqrt(var / n))
        fail_msg("mean %.8g, expected %.8g", st.mean, mean);
    if (fabs(st.std * st.std - var) > 5.0 * var * sqrt(2.0 / n))
        fail_msg("variance %.8g, expected %.8g", st.std * st.std, var);
    /* Each distribution alone. */
    {
        const int dist[3] = {SG_TOLD_UNIFORM, SG_TOLD_NORMAL, SG_TOLD_PARABOLIC};
        const double want[3] = {vu, vn, vp};
        for (k = 0; k < 3; k++) {
            for (t = 0; t < n; t++)
                s[t] = sg_tol_draw(7, (uint64_t)t, 3, dist[k], lo, hi);
            sg_tol_statistics(s, n, &st);
            if (fabs(st.mean - c) > 5.0 * sqrt(want[k] / n))
                fail_msg("distribution %d: mean %.8g, expected %.8g", dist[k], st.mean, c);
            if (fabs(st.std * st.std - want[k]) > 0.02 * want[k])
                fail_msg("distribution %d: variance %.8g, expected %.8g", dist[k],
                         st.std * st.std, want[k]);
        }
    }
    /* A draw depends on (seed, trial, operand) alone. */
    assert_true(sg_tol_draw(5, 9, 2, SG_TOLD_NORMAL, lo, hi) ==
                sg_tol_draw(5, 9, 2, SG_TOLD_NORMAL, lo, hi));
    assert_true(sg_tol_draw(5, 9, 2, SG_TOLD_NORMAL, lo, hi) !=
                sg_tol_draw(5, 10, 2, SG_TOLD_NORMAL, lo, hi));
    assert_true(sg_tol_draw(5, 9, 2, SG_TOLD_NORMAL, lo, hi) !=
                sg_tol_draw(6, 9, 2, SG_TOLD_NORMAL, lo, hi));
    /* Percentiles: the smallest value that p % of 1..100 do not exceed;
     * a NaN (a failed system) left out. */
    for (k = 0; k < 100; k++)
        v[k] = 100 - k;
    sg_tol_statistics(v, 100, &st);
    assert_true(st.pct[0] == 90 && st.pct[1] == 80 && st.pct[2] == 50 && st.pct[3] == 20 &&
                st.pct[4] == 10);
    assert_true(st.best == 1 && st.worst == 100 && st.mean == 50.5);
    /* The sample deviation of 1..100: sqrt(100 * 101 / 12). */
    if (fabs(st.std - sqrt(100.0 * 101.0 / 12.0)) > 1e-13)
        fail_msg("std of 1..100: %.17g", st.std);
    v[0] = NAN;
    sg_tol_statistics(v, 100, &st);
    assert_int_equal(st.n, 99);
    assert_true(st.worst == 99);
    free(s);
}

/* The same run on one and two threads: the same numbers, bit for bit. */
static void threads_identical(void **state)
{
    const char *tol =
        "{\"operands\": ["
        " {\"type\": \"TRAD\", \"surface\": 1, \"min\": -0.5, \"max\": 0.5},"
        " {\"type\": \"TEDY\", \"first\": 1, \"last\": 2, \"min\": -0.05, \"max\": 0.05},"
        " {\"type\": \"TSTX\", \"surface\": 3, \"min\": -0.2, \"max\": 0.2}],"
        " \"compensators\": [{\"surface\": 4, \"parameter\": \"thickness\", \"min\": -2,"
        "  \"max\": 2}],"
        " \"criterion\": {\"reference\": \"centroid\", \"sampling\": {\"density\": 3}}}";
    sg_system *sys = singlet(tol, 1, NULL, 0);
    sg_tol_result r1, r2;
    sg_tol_opts o;
    sg_diag d;
    int k;
    (void)state;
    sg_tol_opts_init(&o);
    o.nthreads = 1;
    sg_diag_clear(&d);
    if (sg_tolerance_run(sys, NULL, &o, 1, 7, 3, &r1, &d) != SG_OK)
        fail_msg("%s", d.msg);
    o.nthreads = 2;
    if (sg_tolerance_run(sys, NULL, &o, 1, 7, 3, &r2, &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_equal(r1.nsens, 3);
    assert_int_equal(r1.done, 7);
    assert_int_equal(r2.done, 7);
    assert_memory_equal(&r1.nominal, &r2.nominal, sizeof r1.nominal);
    for (k = 0; k < 3; k++) {
        assert_int_equal(r1.sens[k].at_min.status, SG_OK);
        assert_memory_equal(&r1.sens[k], &r2.sens[k], sizeof r1.sens[k]);
    }
    for (k = 0; k < 7; k++) {
        assert_int_equal(r1.mc[k].status, SG_OK);
        assert_memory_equal(&r1.mc[k], &r2.mc[k], sizeof r1.mc[k]);
    }
    assert_memory_equal(&r1.stats, &r2.stats, sizeof r1.stats);
    /* The RSS estimate: each row's larger |change|, root sum of squares. */
    {
        double acc = 0.0;
        for (k = 0; k < 3; k++) {
            double a = fabs(r1.sens[k].at_min.criterion - r1.nominal.criterion);
            double b = fabs(r1.sens[k].at_max.criterion - r1.nominal.criterion);
            acc += (a > b ? a : b) * (a > b ? a : b);
        }
        if (fabs(r1.rss - sqrt(acc)) > 1e-15 * sqrt(acc))
            fail_msg("rss %.17g, expected %.17g", r1.rss, sqrt(acc));
    }
    /* A change of the criterion: the compensated TRAD rows move it. */
    assert_true(r1.sens[0].at_max.criterion != r1.nominal.criterion);
    sg_tol_result_free(&r1);
    sg_tol_result_free(&r2);
    sg_system_free(sys);
}

/* The Cassegrain's RMS spot changes for a 1 um decenter of its
 * secondary, a 1 urad tilt of it and a 1e-6 relative change of its
 * radius: the precise trace against the mpfr method at 256 bits, to 8
 * digits (the classic trace's are printed beside them). */
static void cassegrain_mpfr(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *sys = tu_example("cassegrain.json");
    sg_system *pert = sg_system_new();
    const int types[3] = {SG_TOL_TSDX, SG_TOL_TSTX, SG_TOL_TRAD};
    const double deltas[3] = {1e-3, 1e-6 * 180.0 / M_PI, 1e-6 * 3846.0};
    double dc[3];
    sg_tol_value v0, v1;
    sg_tol_opts o;
    sg_diag d;
    int m, k;
    (void)state;
    memset(&sys->tol, 0, sizeof sys->tol);
    sys->tol.present = 1;
    sys->tol.nop = 3;
    for (k = 0; k < 3; k++) {
        sys->tol.op[k].type = (sg_tol_type)types[k];
        sys->tol.op[k].surface = 3;
        sys->tol.op[k].adjust = -1;
        sys->tol.op[k].min = -deltas[k];
        sys->tol.op[k].max = deltas[k];
    }
    sys->tol.pattern = SG_PUPIL_HEXAPOLAR;
    sys->tol.density = 3;
    sys->tol.reference = SG_SPOT_REF_CENTROID;
    for (k = 0; k < 3; k++) {
        double dv[SG_MAX_TOL_OPERANDS] = {0};
        dv[k] = deltas[k];
        sg_diag_clear(&d);
        if (sg_tol_apply(sys, cat, dv, pert, NULL, &d) != SG_OK)
            fail_msg("%s", d.msg);
        for (m = 0; m < 3; m++) {
            static const int methods[3] = {SG_METHOD_PRECISE, SG_METHOD_MPFR,
                                           SG_METHOD_CLASSIC};
            sg_tol_opts_init(&o);
            o.nthreads = 1;
            o.method = methods[m];
            o.mpfr_bits = 256;
            if (sg_tol_criterion(sys, cat, &o, &v0, &d) != SG_OK ||
                sg_tol_criterion(pert, cat, &o, &v1, &d) != SG_OK)
                fail_msg("%s", d.msg);
            if (m < 2)
                dc[m] = v1.criterion - v0.criterion;
            print_message("# %s %s: nominal %.17g, perturbed %.17g, change %.17g\n",
                          sg_tol_name((sg_tol_type)types[k]), sg_method_name(methods[m]),
                          v0.criterion, v1.criterion, v1.criterion - v0.criterion);
        }
        assert_true(dc[1] != 0.0);
        if (!(fabs(dc[0] - dc[1]) <= 1e-8 * fabs(dc[1])))
            fail_msg("%s: precise change %.17g against mpfr %.17g",
                     sg_tol_name((sg_tol_type)types[k]), dc[0], dc[1]);
    }
    sg_system_free(pert);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Zemax's own tolerance rows: sc_tol_cooke.zmx (tests/data/zmx/README.md),
 * its TOL lines 165-221 as they read by hand: the compensator on surface
 * 6's thickness (code 0, the back focus of its comment) from -2 to 2, the
 * test wavelength 0.6328, then 41 operands.  TTHI's Int2 equals Int1, so
 * no surface adjusts; the element operands are Int1..Int2. */
static void zmx_tol_rows(void **state)
{
    static const struct {
        const char *type;
        int first, last;
        double lim;
    } want[] = {
        {"TRAD", 1, 1, 0.2}, {"TRAD", 2, 2, 0.2}, {"TRAD", 3, 3, 0.2}, {"TRAD", 4, 4, 0.2},
        {"TRAD", 5, 5, 0.2}, {"TRAD", 6, 6, 0.2}, {"TTHI", 1, 1, 0.2}, {"TTHI", 2, 2, 0.2},
        {"TTHI", 3, 3, 0.2}, {"TTHI", 4, 4, 0.2}, {"TTHI", 5, 5, 0.2}, {"TEDX", 1, 2, 0.2},
        {"TEDY", 1, 2, 0.2}, {"TETX", 1, 2, 0.2}, {"TETY", 1, 2, 0.2}, {"TEDX", 3, 4, 0.2},
        {"TEDY", 3, 4, 0.2}, {"TETX", 3, 4, 0.2}, {"TETY", 3, 4, 0.2}, {"TEDX", 5, 6, 0.2},
        {"TEDY", 5, 6, 0.2}, {"TETX", 5, 6, 0.2}, {"TETY", 5, 6, 0.2}, {"TSDX", 1, 1, 0.2},
        {"TSDY", 1, 1, 0.2}, {"TSDX", 3, 3, 0.2}, {"TSDY", 3, 3, 0.2}, {"TSDX", 5, 5, 0.2},
        {"TSDY", 5, 5, 0.2}, {"TIRR", 1, 1, 0.2}, {"TIRR", 2, 2, 0.2}, {"TIRR", 3, 3, 0.2},
        {"TIRR", 4, 4, 0.2}, {"TIRR", 5, 5, 0.2}, {"TIRR", 6, 6, 0.2}, {"TIND", 1, 1, 0.0002},
        {"TIND", 3, 3, 0.0002}, {"TIND", 5, 5, 0.0002}, {"TABB", 1, 1, 0.01},
        {"TABB", 3, 3, 0.01}, {"TABB", 5, 5, 0.01}};
    /* Rows with a sensitivity run below: one of each kind. */
    static const int pick[] = {3, 6, 12, 13, 23, 25, 31, 35, 38};
    const int npick = (int)(sizeof pick / sizeof *pick);
    char path[1024];
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new(), *sub;
    sg_tol_opts o;
    sg_tol_result r;
    sg_diag d;
    int k;
    (void)state;
    sg_diag_clear(&d);
    if (sg_zmx_load(sys, tu_path("tests/data/zmx/sc_tol_cooke.zmx", path, sizeof path), cat,
                    &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_true(sys->tol.present);
    assert_int_equal(sys->tol.nop, (int)(sizeof want / sizeof *want));
    for (k = 0; k < sys->tol.nop; k++) {
        const sg_tol_operand *op = &sys->tol.op[k];
        int elem = strcmp(want[k].type, "TE") > 0 && strncmp(want[k].type, "TE", 2) == 0;
        if (strcmp(sg_tol_name(op->type), want[k].type) != 0 || op->surface != want[k].first ||
            (elem && op->last != want[k].last) || op->adjust != -1 ||
            op->min != -want[k].lim || op->max != want[k].lim)
            fail_msg("row %d: %s %d..%d adjust %d, %.17g to %.17g; the file has %s %d %d", k + 1,
                     sg_tol_name(op->type), op->surface, op->last, op->adjust, op->min, op->max,
                     want[k].type, want[k].first, want[k].last);
    }
    assert_int_equal(sys->tol.ncomp, 1);
    assert_int_equal(sys->tol.comp[0].surface, 6);
    assert_string_equal(sys->tol.comp[0].param, "thickness");
    assert_true(sys->tol.comp[0].min == -2.0 && sys->tol.comp[0].max == 2.0);
    assert_true(sys->tol.test_wave == 0.6328);
    /* A sensitivity run on one row of each kind, compensated by the back
     * focus: every system is evaluated (TSDX on surface 1, where rays
     * start, too), and a decenter's min and max give the same criterion
     * within rounding, since the lens and its fields (0, +-8.63, +-12.2
     * in y, weighted alike) are symmetric under x -> -x and y -> -y. */
    sub = sg_system_clone(sys);
    sub->tol.nop = npick;
    for (k = 0; k < npick; k++)
        sub->tol.op[k] = sys->tol.op[pick[k]];
    sg_tol_opts_init(&o);
    sg_diag_clear(&d);
    if (sg_tolerance_run(sub, cat, &o, 1, 0, 1, &r, &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_int_equal(r.nsens, npick);
    assert_int_equal(r.nominal.status, SG_OK);
    for (k = 0; k < npick; k++) {
        const sg_tol_sens *e = &r.sens[k];
        sg_tol_type t = sub->tol.op[k].type;
        if (e->at_min.status != SG_OK || e->at_max.status != SG_OK ||
            !isfinite(e->at_min.criterion) || !isfinite(e->at_max.criterion))
            fail_msg("row %d (%s %d): status %d / %d", pick[k] + 1, sg_tol_name(t),
                     sub->tol.op[k].surface, e->at_min.status, e->at_max.status);
        if ((t == SG_TOL_TEDX || t == SG_TOL_TEDY || t == SG_TOL_TSDX || t == SG_TOL_TSDY) &&
            !(fabs(e->at_min.criterion - e->at_max.criterion) <= 1e-9 * e->at_max.criterion))
            fail_msg("row %d (%s): %.17g at min, %.17g at max", pick[k] + 1, sg_tol_name(t),
                     e->at_min.criterion, e->at_max.criterion);
        /* A decenter of 0.2 mm degrades a lens in focus. */
        if ((t == SG_TOL_TEDY || t == SG_TOL_TSDX) &&
            !(e->at_max.criterion > r.nominal.criterion))
            fail_msg("row %d (%s): no change", pick[k] + 1, sg_tol_name(t));
    }
    sg_tol_result_free(&r);
    sg_system_free(sub);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* A TOL row sagitta cannot take is warned about with its line and left
 * out; the rest are read; the lossless save keeps every line and refuses
 * to drop an edit of the tolerances. */
static void zmx_tol_refusals(void **state)
{
    const char *text =
        "VERS 190513 80 123457\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 10\n"
        "FTYP 0 0 1 1 0 0 0\nXFLN 0\nYFLN 0\nFWGN 1\nWAVM 1 0.55 1\nPWAV 1\n"
        "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  CURV 0.02\n  DISZ 4\n  GLAS N-BK7 0 0 "
        "1.5168 64.17\nSURF 2\n  CURV 0.0\n  DISZ 95\nSURF 3\n  DISZ 0\n"
        "TOL TOFF   0   0              0              0   0 0 0\n"
        "TOL TWAV   0   0          0.55              0   0 0 0\n"
        "TOL COMP   2   0             -1              1   0 0 0\n"
        "TOL COMP   1   1           -0.1            0.1   0 0 0\n"
        "TOL TRAD   1   0           -0.5            0.5   0 0 0\n"
        "TOL TRAD   2   0           -0.5            0.5   0 0 0\n"
        "TOL TXYZ   1   0             -1              1   0 0 0\n"
        "TOL TTHI   1   2           -0.1            0.1   0 0 0\n"
        "TOL TEDX   1   7           -0.1            0.1   0 0 0\n"
        "TOL TPAR   1   3           -0.1            0.1   0 0 0\n"
        "TOL TIND   1   0          -1e-3           1e-3   0 0 0\n";
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new();
    sg_diag d;
    int i, k;
    static const char *const warned[][2] = {
        {"t.zmx:26:", "compensator code 1"},
        {"t.zmx:28:", "TRAD: tolerances: operand 2 (TRAD): surface 2 is flat"},
        {"t.zmx:29:", "TXYZ: not a tolerance operand sagitta knows"},
        {"t.zmx:31:", "TEDX: tolerances: operand 3 (TEDX): last: surface 7"},
        {"t.zmx:32:", "TPAR: Zemax's TPAR numbers the parameter columns"}};
    (void)state;
    sg_diag_clear(&d);
    if (sg_zmx_parse(sys, text, strlen(text), "t.zmx", cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    for (k = 0; k < (int)(sizeof warned / sizeof *warned); k++) {
        int found = 0;
        for (i = 0; i < d.nwarn && i < SG_DIAG_MAXWARN; i++)
            found |= strstr(d.warn[i], warned[k][0]) && strstr(d.warn[i], warned[k][1]);
        if (!found)
        {
            for (i = 0; i < d.nwarn && i < SG_DIAG_MAXWARN; i++)
                fprintf(stderr, "warning: %s\n", d.warn[i]);
            fail_msg("no warning \"%s ... %s\"", warned[k][0], warned[k][1]);
        }
    }
    assert_true(sys->tol.present);
    assert_true(sys->tol.test_wave == 0.55);
    assert_int_equal(sys->tol.ncomp, 1);
    assert_int_equal(sys->tol.comp[0].surface, 2);
    assert_int_equal(sys->tol.nop, 3);
    assert_int_equal(sys->tol.op[0].type, SG_TOL_TRAD);
    assert_int_equal(sys->tol.op[1].type, SG_TOL_TTHI);
    assert_int_equal(sys->tol.op[1].adjust, 2);
    assert_int_equal(sys->tol.op[2].type, SG_TOL_TIND);
    assert_true(sys->tol.op[2].min == -1e-3 && sys->tol.op[2].max == 1e-3);
    {
        char dir[] = "/tmp/sg_tolzmxXXXXXX", file[64];
        FILE *f;
        char buf[4096];
        size_t n;
        assert_non_null(mkdtemp(dir));
        snprintf(file, sizeof file, "%s/t.zmx", dir);
        /* No edit: the same bytes, every TOL line kept. */
        sg_diag_clear(&d);
        if (sg_zmx_save(sys, file, cat, &d) != SG_OK)
            fail_msg("%s", d.msg);
        f = fopen(file, "rb");
        assert_non_null(f);
        n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        assert_int_equal(n, strlen(text));
        assert_memory_equal(buf, text, n);
        /* An edited tolerance is not lost silently. */
        sys->tol.op[0].max = 0.25;
        sg_diag_clear(&d);
        assert_int_equal(sg_zmx_save(sys, file, cat, &d), SG_ELOSSY);
        if (!strstr(d.msg, "cannot be written faithfully") || !strstr(d.msg, "0.25"))
            fail_msg("%s", d.msg);
        unlink(file);
        rmdir(dir);
    }
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(json_roundtrip),
        cmocka_unit_test(operands_by_hand),
        cmocka_unit_test(tirr_by_hand),
        cmocka_unit_test(tezi_by_hand),
        cmocka_unit_test(glass_changes),
        cmocka_unit_test(element_by_hand),
        cmocka_unit_test(compensated_focus),
        cmocka_unit_test(round_element_turned),
        cmocka_unit_test(sampler_statistics),
        cmocka_unit_test(threads_identical),
        cmocka_unit_test(cassegrain_mpfr),
        cmocka_unit_test(zmx_tol_rows),
        cmocka_unit_test(zmx_tol_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
