/*
 * test_zmx37.c - Zemax files that issue 37 opens: the Jones matrix surface
 * (JONESMAT), read as the plane Zemax makes it; the pupil shift (PUSH)
 * under ray aiming.
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
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_jonesmat_plane),
        cmocka_unit_test(test_push_aimed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
