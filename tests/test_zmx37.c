/*
 * test_zmx37.c - Zemax files that issue 37 opens: the Jones matrix surface
 * (JONESMAT), read as the plane Zemax makes it; the pupil shift (PUSH)
 * under ray aiming; afocal image space (FTYP's afocal flag).
 *
 * tests/data/zmx/zospy_jonesmat.zmx is a file OpticStudio 25.1.1 saved for
 * ZOSPy's polarization tests (README there): ZOSPy's simple system with
 * the lens's front surface made a Jones matrix surface (a quarter-wave
 * retarder at 45 degrees), back radius -20, model glass n = 1.5, 1 mm.
 * Expected values: Zemax's Knowledge Base ("How to Use the Jones Matrix
 * Surface") says the surface does not use the radius column, it is always
 * a plane, so the lens is plano-convex and its focal length is
 * -R2 / (n - 1) = 40 exactly (the thick-lens formula with R1 infinite);
 * and the same file edited to a standard surface traces the same rays.
 */
#define _GNU_SOURCE /* mkdtemp */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

static char *slurp_utf8(const char *rel, size_t *n)
{
    char path[1024];
    FILE *f = fopen(tu_path(rel, path, sizeof path), "rb");
    unsigned char *b;
    char *t;
    long m, i, j = 0;
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    m = ftell(f);
    fseek(f, 0, SEEK_SET);
    b = malloc((size_t)m);
    t = malloc((size_t)m + 1);
    assert_non_null(b);
    assert_non_null(t);
    assert_int_equal(fread(b, 1, (size_t)m, f), (size_t)m);
    fclose(f);
    /* UTF-16LE with a BOM, every character ASCII. */
    assert_true(m > 2 && b[0] == 0xFF && b[1] == 0xFE);
    for (i = 2; i + 1 < m; i += 2) {
        assert_int_equal(b[i + 1], 0);
        t[j++] = (char)b[i];
    }
    t[j] = '\0';
    free(b);
    *n = (size_t)j;
    return t;
}

/* The text with TYPE JONESMAT made STANDARD and its PARM lines removed. */
static char *as_standard(const char *text)
{
    char *out = malloc(strlen(text) + 1), *o = out;
    const char *p = text;
    assert_non_null(out);
    while (*p) {
        const char *e = strchr(p, '\n');
        size_t n = e ? (size_t)(e - p + 1) : strlen(p);
        if (strncmp(p, "  PARM ", 7) == 0) {
            p += n;
            continue;
        }
        if (strncmp(p, "  TYPE JONESMAT", 15) == 0) {
            memcpy(o, "  TYPE STANDARD", 15);
            memcpy(o + 15, p + 15, n - 15);
        } else {
            memcpy(o, p, n);
        }
        o += n;
        p += n;
    }
    *o = '\0';
    return out;
}

static void test_jonesmat_plane(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *a = sg_system_new(), *b = sg_system_new();
    size_t n;
    char *text = slurp_utf8("tests/data/zmx/zospy_jonesmat.zmx", &n), *std;
    sg_paraxial p;
    sg_trace_opts o;
    sg_tracer *ta, *tb;
    sg_ray_surface ra[8] = {{0}}, rb[8] = {{0}};
    sg_diag d;
    int i;
    (void)state;
    assert_non_null(strstr(text, "  TYPE JONESMAT"));
    assert_non_null(strstr(text, "  PARM 1 1"));
    std = as_standard(text);
    assert_null(strstr(std, "JONESMAT"));
    sg_diag_clear(&d);
    if (sg_zmx_parse(a, text, n, "zospy_jonesmat.zmx", cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    {
        int seen = 0;
        for (i = 0; i < d.nwarn && i < SG_DIAG_MAXWARN; i++)
            seen |= strstr(d.warn[i], "zospy_jonesmat.zmx:88: surface 2: TYPE JONESMAT") != NULL;
        assert_true(seen);
    }
    sg_diag_clear(&d);
    if (sg_zmx_parse(b, std, strlen(std), "standard.zmx", cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_true(sg_system_equal(a, b));
    assert_true(isinf(a->surf[2].radius));
    assert_int_equal(a->nsurf, 5);
    /* Plano-convex, n = 1.5, R2 = -20: f = 40. */
    assert_int_equal(sg_paraxial_compute(a, cat, -1, &p, &d), SG_OK);
    print_message("# EFL %.17g\n", p.efl);
    assert_true(fabs(p.efl - 40.0) <= 1e-12);
    sg_trace_opts_init(&o);
    ta = sg_tracer_new(a, cat, &o, &d);
    tb = sg_tracer_new(b, cat, &o, &d);
    assert_non_null(ta);
    assert_non_null(tb);
    assert_int_equal(sg_trace_normalized(ta, 0, 0, 0.6, 0.8, ra), SG_OK);
    assert_int_equal(sg_trace_normalized(tb, 0, 0, 0.6, 0.8, rb), SG_OK);
    assert_memory_equal(ra, rb, (size_t)a->nsurf * sizeof ra[0]);
    sg_tracer_free(ta);
    sg_tracer_free(tb);
    /* A curvature on the line is not used: Zemax's surface is a plane. */
    {
        char *cv = malloc(n + 32), *at = strstr(text, "  TYPE JONESMAT\r\n");
        const char *c0 = "  CURV 0.0 0 0.0 0.0 0\r\n";
        char *cl;
        assert_non_null(at);
        cl = strstr(at, c0);
        assert_non_null(cl);
        snprintf(cv, n + 32, "%.*s  CURV 0.05 0 0.0 0.0 0\r\n%s", (int)(cl - text), text,
                 cl + strlen(c0));
        sg_diag_clear(&d);
        assert_int_equal(sg_zmx_parse(b, cv, strlen(cv), "curved.zmx", cat, &d), SG_OK);
        assert_true(isinf(b->surf[2].radius));
        assert_int_equal(sg_paraxial_compute(b, cat, -1, &p, &d), SG_OK);
        assert_true(fabs(p.efl - 40.0) <= 1e-12);
        free(cv);
    }
    /* A parameter beyond the matrix is refused with its line. */
    {
        char *bad = malloc(n + 32), *at = strstr(text, "  PARM 8 0\r\n");
        assert_non_null(at);
        at += strlen("  PARM 8 0\r\n");
        snprintf(bad, n + 32, "%.*s  PARM 9 1\r\n%s", (int)(at - text), text, at);
        sg_diag_clear(&d);
        assert_int_equal(sg_zmx_parse(b, bad, strlen(bad), "bad.zmx", cat, &d), SG_EUNSUPPORTED);
        assert_non_null(strstr(d.msg, "bad.zmx:102: surface 2: PARM 9 is 1; a Jones matrix"));
        free(bad);
    }
    free(std);
    free(text);
    sg_system_free(a);
    sg_system_free(b);
    sg_catalog_free(cat);
}


/* Zemax's Knowledge Base ("How to Specify the Pupil Shift Factor when
 * Using Ray-Aiming", 2005): the shift is ray aiming's first guess and
 * "once ZEMAX has successfully traced a ray it needs no further help".
 * With real ray aiming a file with a shift traces as the file without
 * one; without aiming it is refused. */
static void test_push_aimed(void **state)
{
    char src[1024], *text, *buf;
    size_t n, nb;
    FILE *f;
    sg_catalog *cat = tu_catalog();
    sg_system *a = sg_system_new(), *b = sg_system_new();
    sg_trace_opts o;
    sg_tracer *ta, *tb;
    sg_ray_surface ra[16] = {{0}}, rb[16] = {{0}};
    const char *at;
    sg_diag d;
    int i;
    (void)state;
    f = fopen(tu_path("tests/data/zmx/lens1.zmx", src, sizeof src), "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    n = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    text = calloc(1, n + 1);
    assert_non_null(text);
    assert_int_equal(fread(text, 1, n, f), n);
    fclose(f);
    at = strstr(text, "PWAV 2\n");
    assert_non_null(at);
    nb = n + 128;
    buf = malloc(nb);
    assert_non_null(buf);
    /* Lines 12 and 13: real ray aiming, and a shift of the first guess. */
    snprintf(buf, nb, "%.*sRAIM 0 2 1 1 0 0 0 0 0\nPUSH 0.5 -0.25 1 0 0 0\n%s", (int)(at - text),
             text, at);
    sg_diag_clear(&d);
    if (sg_zmx_parse(a, buf, strlen(buf), "push.zmx", cat, &d) != SG_OK)
        fail_msg("%s", d.msg);
    {
        int seen = 0;
        for (i = 0; i < d.nwarn && i < SG_DIAG_MAXWARN; i++)
            seen |= strstr(d.warn[i], "push.zmx:13: PUSH: note") != NULL;
        assert_true(seen);
    }
    snprintf(buf, nb, "%.*sRAIM 0 2 1 1 0 0 0 0 0\nPUSH 0 0 0 0 0 0\n%s", (int)(at - text), text,
             at);
    sg_diag_clear(&d);
    assert_int_equal(sg_zmx_parse(b, buf, strlen(buf), "nopush.zmx", cat, &d), SG_OK);
    assert_true(a->aim == SG_AIM_REAL);
    assert_true(sg_system_equal(a, b));
    sg_trace_opts_init(&o);
    ta = sg_tracer_new(a, cat, &o, &d);
    tb = sg_tracer_new(b, cat, &o, &d);
    assert_non_null(ta);
    assert_non_null(tb);
    assert_int_equal(sg_trace_normalized(ta, 0, 1, 0, 1, ra), SG_OK);
    assert_int_equal(sg_trace_normalized(tb, 0, 1, 0, 1, rb), SG_OK);
    assert_memory_equal(ra, rb, (size_t)a->nsurf * sizeof ra[0]);
    sg_tracer_free(ta);
    sg_tracer_free(tb);
    /* Without ray aiming sagitta cannot tell what Zemax does with it. */
    snprintf(buf, nb, "%.*sPUSH 0.5 -0.25 1 0 0 0\n%s", (int)(at - text), text, at);
    sg_diag_clear(&d);
    assert_int_equal(sg_zmx_parse(b, buf, strlen(buf), "off.zmx", cat, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "off.zmx:12: PUSH: pupil shifts without ray aiming"));
    free(buf);
    free(text);
    sg_system_free(a);
    sg_system_free(b);
    sg_catalog_free(cat);
}


/* ---- afocal image space ----
 * A Keplerian telescope of two plano-convex lenses (n = 1.5, no
 * dispersion): R 50 then flat (f 100), flat then R -10 (f 20), the gap
 * making the paraxial system afocal.  The expected values come from this
 * file: the paraxial matrices (the angular magnification) and a meridional
 * ray trace through the spheres in long double (the angles). */
#define TEL_N 1.5L
static const long double tel_c[4] = {1.0L / 50, 0, 0, -1.0L / 10}; /* curvatures */
static const long double tel_t1 = 3, tel_t3 = 2; /* lens thicknesses */

/* The gap after surface 2 that makes the system afocal: the power of
 * M = R4 T3 R3 T(gap) R2 T1 R1 is zero, linear in the gap. */
static long double tel_gap(void)
{
    long double p1 = (TEL_N - 1) * tel_c[0], p4 = (1 - TEL_N) * tel_c[3];
    /* Lens 1 (R1, t1/n, R2 flat): A = 1 - t1 p1 / n, C = -p1; lens 2:
     * A' = 1, C' = -p4 (its flat face first), D' = 1 - t3 p4 / n. */
    long double A1 = 1 - tel_t1 * p1 / TEL_N, C1 = -p1, C2 = -p4, D2 = 1 - tel_t3 * p4 / TEL_N;
    /* Total C = C2 (A1 + g C1) + D2 C1 = 0. */
    return -(C2 * A1 + D2 * C1) / (C2 * C1);
}

/* A meridional ray (y, z, direction v, w) through the four surfaces at
 * z = 0, t1, t1 + gap, t1 + gap + t3: its direction cosine m after the last. */
static long double tel_trace(long double y, long double v, long double gap)
{
    long double z = -10, w = sqrtl(1 - v * v), n = 1;
    const long double zs[4] = {0, tel_t1, tel_t1 + gap, tel_t1 + gap + tel_t3};
    const long double nn[4] = {TEL_N, 1, TEL_N, 1};
    int k;
    for (k = 0; k < 4; k++) {
        long double t, ny, nz, mu, ci, ct;
        if (tel_c[k] == 0) {
            t = (zs[k] - z) / w;
            y += t * v, z += t * w;
            ny = 0, nz = 1;
        } else {
            /* The sphere's centre on the axis at zs + 1/c; the near root. */
            long double r = 1 / tel_c[k], zc = zs[k] + r, dz = z - zc;
            long double b = y * v + dz * w, q = y * y + dz * dz - r * r;
            long double disc = sqrtl(b * b - q);
            t = r > 0 ? -b - disc : -b + disc;
            y += t * v, z += t * w;
            ny = -y / r, nz = -(z - zc) / r; /* unit normal facing the incoming side, +z */
            if (nz < 0)
                ny = -ny, nz = -nz;
        }
        mu = n / nn[k];
        ci = v * ny + w * nz;
        ct = sqrtl(1 - mu * mu * (1 - ci * ci));
        v = mu * v + (ct - mu * ci) * ny;
        w = mu * w + (ct - mu * ci) * nz;
        n = nn[k];
    }
    return v;
}

static char *tel_json(long double gap)
{
    char *j = malloc(2048);
    assert_non_null(j);
    snprintf(j, 2048,
             "{ \"version\": 7, \"afocal\": true,\n"
             "  \"wavelengths\": { \"primary\": 1, \"list\": [ { \"um\": 0.55 } ] },\n"
             "  \"fields\": { \"type\": \"angle\", \"list\": [ { \"y\": 0 }, { \"y\": 0.01 } ] },\n"
             "  \"aperture\": { \"type\": \"epd\", \"value\": 10 },\n"
             "  \"surfaces\": [\n"
             "    { \"radius\": \"inf\", \"thickness\": \"inf\" },\n"
             "    { \"radius\": 50, \"thickness\": 3, \"material\": 1.5, \"stop\": true },\n"
             "    { \"radius\": \"inf\", \"thickness\": %.21Lg },\n"
             "    { \"radius\": \"inf\", \"thickness\": 2, \"material\": 1.5 },\n"
             "    { \"radius\": -10, \"thickness\": 10 },\n"
             "    { \"radius\": \"inf\", \"thickness\": 0 } ] }\n",
             gap);
    return j;
}

static void test_afocal_telescope(void **state)
{
    sg_catalog *cat = tu_catalog();
    sg_system *s = sg_system_new();
    long double gap = tel_gap(), sum = 0, geo = 0, th = 0.01L * 3.14159265358979323846L / 180;
    char *json = tel_json(gap), *back;
    sg_spot_opts so;
    sg_spot sp;
    sg_fan_opts fo;
    sg_fan fan;
    sg_diag d;
    int i, k;
    (void)state;
    sg_diag_clear(&d);
    if (sg_design_parse(s, json, strlen(json), "telescope.json", &d) != SG_OK)
        fail_msg("%s", d.msg);
    assert_true(s->afocal);
    /* The spot of the axial field: hexapolar rings k = 1..6 of 6k rays at
     * pupil radius k/6, each ray's angle from the (axial) chief ray the
     * meridional m of its radius. */
    sg_spot_opts_init(&so);
    so.field = 0;
    memset(&sp, 0, sizeof sp);
    assert_int_equal(sg_spot_compute(s, cat, &so, &sp, &d), SG_OK);
    for (k = 1; k <= 6; k++) {
        long double m = tel_trace(5.0L * k / 6, 0, gap);
        sum += 6 * k * m * m;
        geo = fmaxl(geo, fabsl(m));
    }
    print_message("# afocal spot RMS %.17g (expected %.17Lg), GEO %.17g (%.17Lg) rad\n",
                  sp.cell[0].rms, sqrtl(sum / 127), sp.cell[0].geo, geo);
    assert_true(fabsl(sp.cell[0].rms - sqrtl(sum / 127)) <= 1e-13L);
    assert_true(fabsl(sp.cell[0].geo - geo) <= 1e-13L);
    assert_true(sp.airy_radius == 0.0);
    sg_spot_free(&sp);
    /* The tangential fan of the axial field: e(Py) is m, the angle. */
    sg_fan_opts_init(&fo);
    fo.field = 0;
    fo.npts = 5;
    memset(&fan, 0, sizeof fan);
    assert_int_equal(sg_fan_compute(s, cat, &fo, &fan, &d), SG_OK);
    for (i = 0; i < fan.tan[0].n; i++) {
        long double m = tel_trace(5.0L * fan.tan[0].p[i], 0, gap);
        assert_true(fabsl(fan.tan[0].e[i] - m) <= 1e-13L);
    }
    sg_fan_free(&fan);
    /* The angular magnification: the chief ray of the 0.01 degree field
     * leaves at the angle the meridional trace gives, and its ratio to the
     * field is the paraxial matrix's D (-f1 / f2 = -5) to third order. */
    sg_spot_opts_init(&so);
    so.field = 1;
    memset(&sp, 0, sizeof sp);
    assert_int_equal(sg_spot_compute(s, cat, &so, &sp, &d), SG_OK);
    {
        /* Through the stop's centre (surface 1's vertex, 10 behind the start). */
        long double mc = tel_trace(-10 * tanl(th), sinl(th), gap);
        /* The paraxial matrix of (y, n u): R4 T3 R3 Tgap R2 T1 R1, with
         * R = [1 0; -P 1] and T = [1 t/n; 0 1]; afocal (C = 0), u' = D u. */
        long double P[4] = {(TEL_N - 1) * tel_c[0], 0, 0, (1 - TEL_N) * tel_c[3]};
        long double tn[3] = {tel_t1 / TEL_N, gap, tel_t3 / TEL_N};
        long double A = 1, B = 0, C = 0, D = 1, a, b;
        for (k = 0; k < 4; k++) {
            C -= P[k] * A, D -= P[k] * B; /* R_k times the matrix so far */
            if (k < 3) {
                a = A + tn[k] * C, b = B + tn[k] * D;
                A = a, B = b;
            }
        }
        print_message("# paraxial C %.3Lg, D %.17Lg\n", C, D);
        assert_true(fabsl(C) <= 1e-18L);
        print_message("# chief ray m %.17g (trace %.17Lg), magnification %.10Lg\n",
                      sp.cell[0].chief_y, mc, mc / sinl(th));
        assert_true(fabsl(sp.cell[0].chief_y - mc) <= 1e-15L);
        /* The real chief ray at 0.01 degrees departs from the paraxial
         * ratio by the third-order angular distortion, 3.4e-6 here. */
        assert_true(fabsl(mc / tanl(th) - D) <= 1e-5L * fabsl(D));
        assert_true(D < -4.5L && D > -5.5L);
    }
    sg_spot_free(&sp);
    /* .zmx: FTYP's seventh field, written and read back. */
    {
        char dir[] = "/tmp/sagitta_afocal_XXXXXX", path[128];
        sg_system *r = sg_system_new();
        assert_non_null(mkdtemp(dir));
        snprintf(path, sizeof path, "%s/t.zmx", dir);
        assert_int_equal(sg_design_save(s, path, &d), SG_OK);
        assert_int_equal(sg_design_load(r, path, &d), SG_OK);
        assert_true(r->afocal);
        back = sg_design_to_json(r);
        assert_non_null(strstr(back, "\"afocal\": true"));
        free(back);
        unlink(path);
        rmdir(dir);
        sg_system_free(r);
    }
    free(json);
    sg_system_free(s);
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jonesmat_plane),
        cmocka_unit_test(test_push_aimed),
        cmocka_unit_test(test_afocal_telescope),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
