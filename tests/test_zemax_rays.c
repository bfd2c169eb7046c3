/*
 * test_zemax_rays.c - published Zemax single-ray results (issue 17).
 *
 * Two sources, each named with its files and commits in a README next to
 * its data:
 *
 * - ZOSPy (MREYE-LUMC/ZOSPy) keeps, as reference data for its own tests,
 *   what OpticStudio printed for a Single Ray Trace and returned for a Ray
 *   Fan of its "simple_system" fixture (tests/data/zospy).  Every number
 *   of the two reports is matched within half a unit of its last printed
 *   digit; the fan, stored as OpticStudio's doubles, within a bound set by
 *   Zemax's own double arithmetic (test_ray_fan says why).
 * - optiland lists the image rows and first-order data OpticStudio 2023
 *   R1.02 gave for optiland's Hubble sample (tests/data/optiland); the
 *   tests below say how each published digit is reproduced.
 *
 * The designs are the prescriptions those projects give.  Expected values
 * are read from the data files; the surface normals and angles of
 * incidence Zemax lists are computed here from sagitta's intersection
 * points by the sphere's closed-form gradient.
 */
#define _USE_MATH_DEFINES
#include <ctype.h>
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#define NCOL 11 /* X Y Z, L M N, normal x y z, angle in, path length */

/* One row of Zemax's "Real Ray Trace Data": the values and, for each, half
 * a unit of the last digit printed; has[] is 0 where Zemax prints none. */
typedef struct zrow {
    int surf;
    double v[NCOL];
    double half[NCOL];
    int has[NCOL];
} zrow;

typedef struct zreport {
    double hx, hy, px, py, um;
    int global; /* "Global coordinates relative to surface 1" */
    int nrow;
    zrow row[8];
} zreport;

static char *slurp(const char *rel)
{
    char path[1024];
    FILE *f = fopen(tu_path(rel, path, sizeof path), "rb");
    char *buf;
    long n;
    if (!f)
        fail_msg("cannot open %s", path);
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = malloc((size_t)n + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, f), (size_t)n);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

/* A number as Zemax prints it, with a decimal comma (the report was made
 * under a Dutch locale) or point; *half gets half a unit of its last
 * digit.  Returns 0 when the token is not a number ("Infinity", "-"). */
static int zemax_number(const char *tok, double *v, double *half)
{
    char buf[64], *end;
    const char *mant, *e;
    size_t n = strlen(tok), i;
    int decimals = 0, exp10 = 0;
    if (n == 0 || n >= sizeof buf)
        return 0;
    for (i = 0; i <= n; i++)
        buf[i] = tok[i] == ',' ? '.' : tok[i];
    if (!isdigit((unsigned char)buf[buf[0] == '-' || buf[0] == '+']))
        return 0;
    *v = strtod(buf, &end);
    if (*end != '\0')
        return 0;
    mant = strchr(buf, '.');
    e = strpbrk(buf, "eE");
    if (mant)
        decimals = (int)((e ? e : buf + n) - mant - 1);
    if (e)
        exp10 = atoi(e + 1);
    *half = 0.5 * pow(10.0, exp10 - decimals);
    return 1;
}

/* The number after the first ':' that follows key in the header. */
static double header_value(const char *text, const char *key)
{
    const char *p = strstr(text, key);
    double v = 0, half;
    char tok[64];
    if (!p)
        fail_msg("no \"%s\" in the report", key);
    p = strchr(p, ':');
    assert_non_null(p);
    if (sscanf(p + 1, " %63s", tok) != 1 || !zemax_number(tok, &v, &half))
        fail_msg("no number after \"%s\"", key);
    return v;
}

/* Parses the report's real ray rows (the section between "Real Ray Trace
 * Data:" and "Paraxial Ray Trace Data:"), the OBJ row left out. */
static void parse_report(const char *rel, zreport *r)
{
    char *text = slurp(rel), *sec, *end, *line, *save = NULL;
    memset(r, 0, sizeof *r);
    r->hx = header_value(text, "(Hx)");
    r->hy = header_value(text, "(Hy)");
    r->px = header_value(text, "(Px)");
    r->py = header_value(text, "(Py)");
    r->um = header_value(text, "Wavelength");
    r->global = strstr(text, "Global coordinates relative to surface\t 1") != NULL;
    sec = strstr(text, "Real Ray Trace Data:");
    end = strstr(text, "Paraxial Ray Trace Data:");
    assert_non_null(sec);
    assert_non_null(end);
    *end = '\0';
    for (line = strtok_r(sec, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        char *tok, *s2 = NULL;
        zrow *z;
        int col = -1;
        while (*line == ' ')
            line++;
        if (!isdigit((unsigned char)*line))
            continue;
        assert_true(r->nrow < 8);
        z = &r->row[r->nrow++];
        for (tok = strtok_r(line, "\t", &s2); tok; tok = strtok_r(NULL, "\t", &s2)) {
            double v, half;
            while (*tok == ' ')
                tok++;
            if (col < 0) {
                z->surf = atoi(tok);
            } else if (col < NCOL && zemax_number(tok, &v, &half)) {
                z->v[col] = v;
                z->half[col] = half;
                z->has[col] = 1;
            }
            col++;
        }
        for (col = 0; col < NCOL; col++)
            if (!z->has[col])
                fail_msg("%s: surface %d: column %d has no number", rel, z->surf, col + 1);
    }
    free(text);
}

static const char *const colname[NCOL] = {"X", "Y", "Z", "X-cosine", "Y-cosine", "Z-cosine",
                                           "X-normal", "Y-normal", "Z-normal", "Angle in",
                                           "Path length"};

/* Traces the report's ray with method m and checks every printed number;
 * returns how many were checked. */
static int check_report(const sg_system *sys, const sg_catalog *cat, const zreport *zr,
                        sg_method m)
{
    sg_tracer *t = tu_tracer(sys, cat, m);
    sg_ray_surface row[8];
    sg_frame gf[8];
    sg_diag d;
    int nsurf = sys->nsurf, k, c, nchecked = 0;
    assert_true(nsurf <= 8);
    assert_int_equal(zr->nrow, nsurf - 1);
    assert_int_equal(sg_trace_normalized(t, zr->hx, zr->hy, zr->px, zr->py, row), SG_OK);
    if (zr->global) {
        sg_diag_clear(&d);
        assert_int_equal(sg_global_frames(sys, 1, gf, &d), SG_OK);
    }
    for (k = 0; k < zr->nrow; k++) {
        const zrow *z = &zr->row[k];
        int i = z->surf;
        const sg_ray_surface *r = &row[i];
        const sg_ray_surface *prev = &row[i - 1];
        const sg_surface *s = &sys->surf[i];
        double c1 = isinf(s->radius) ? 0.0 : 1.0 / s->radius, nrm[3], len, cosi, got[NCOL];
        sg_ray_surface g = *r;
        assert_int_equal(i, k + 1);
        assert_int_equal(s->type, SG_SURF_STANDARD);
        assert_true(s->conic == 0.0);
        /* The sphere's normal, c (x, y, z) - (0, 0, 1), from the local
         * point; Zemax lists the one pointing back along -z. */
        nrm[0] = c1 * r->x;
        nrm[1] = c1 * r->y;
        nrm[2] = c1 * r->z - 1.0;
        len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        /* The angle between the incoming direction (after the previous
         * surface; no rotation anywhere here) and the normal. */
        cosi = fabs(prev->l * nrm[0] + prev->m * nrm[1] + prev->n * nrm[2]) / len;
        if (zr->global)
            sg_row_to_global(&gf[i], &g);
        got[0] = g.x;
        got[1] = g.y;
        got[2] = g.z;
        got[3] = g.l;
        got[4] = g.m;
        got[5] = g.n;
        got[6] = nrm[0] / len;
        got[7] = nrm[1] / len;
        got[8] = nrm[2] / len;
        got[9] = acos(cosi > 1.0 ? 1.0 : cosi) * (180.0 / M_PI);
        got[10] = r->path;
        for (c = 0; c < NCOL; c++) {
            double diff = fabs(got[c] - z->v[c]);
            if (!(diff <= z->half[c]))
                fail_msg("%s: surface %d %s: sagitta %.17g, Zemax printed %.12g (half a digit "
                         "%.1e, off by %.2e)",
                         sg_method_name(m), i, colname[c], got[c], z->v[c], z->half[c], diff);
            nchecked++;
        }
    }
    sg_tracer_free(t);
    return nchecked;
}

/* The design: the fixture's prescription as JSON (0), or the .zmx file
 * OpticStudio 25.1.1 saved for the ray fan run (1), read by the importer. */
static const char *const design_file[2] = {
    "tests/data/zospy/simple_system.json",
    "tests/data/zospy/ray_fan_1_40_OpticStudio_25.1.1.zmx",
};

static sg_system *load_design_from(int k)
{
    char path[1024];
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    sg_diag_clear(&d);
    if (sg_design_load(sys, tu_path(design_file[k], path, sizeof path), &d) != SG_OK)
        fail_msg("%s: %s", design_file[k], d.msg);
    return sys;
}

static sg_system *load_design(void)
{
    return load_design_from(0);
}

static const sg_method methods[3] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};

/* The skew marginal ray Px = Py = 1 (outside the unit circle's x and y
 * axes, at radius sqrt 2 on the stop) in global coordinates: 44 numbers. */
static void test_skew_ray(void **state)
{
    sg_catalog *cat = tu_catalog();
    zreport zr;
    int m, n = 0, k;
    (void)state;
    parse_report("tests/data/zospy/single_ray_0_0_1_1_global.txt", &zr);
    assert_true(zr.global);
    assert_true(zr.px == 1.0 && zr.py == 1.0 && zr.hx == 0.0 && zr.hy == 0.0);
    for (k = 0; k < 2; k++) {
        sg_system *sys = load_design_from(k);
        assert_true(zr.um == sys->wave[sys->primary_wave].um);
        for (m = 0; m < 3; m++)
            n = check_report(sys, cat, &zr, methods[m]);
        assert_int_equal(n, 44);
        print_message("# Zemax's skew ray: %d printed values matched by precise, classic and "
                      "mpfr on %s\n", n, design_file[k]);
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

/* Hx = Hy = 1 with the one field at 0 degrees: the axial ray, in local
 * coordinates; Zemax's path lengths are the thicknesses. */
static void test_axial_ray(void **state)
{
    sg_system *sys = load_design();
    sg_catalog *cat = tu_catalog();
    zreport zr;
    int m, n = 0;
    (void)state;
    parse_report("tests/data/zospy/single_ray_1_1_0_0_local.txt", &zr);
    assert_false(zr.global);
    assert_true(zr.hx == 1.0 && zr.hy == 1.0 && zr.px == 0.0 && zr.py == 0.0);
    for (m = 0; m < 3; m++)
        n = check_report(sys, cat, &zr, methods[m]);
    assert_int_equal(n, 44);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* The ray fan, 81 pupil points on each axis, in micrometres: image y of the
 * ray at Py (tangential) and x at Px (sagittal), less the chief ray's.
 * ZOSPy stores these as the doubles OpticStudio returned, 16 or 17
 * significant digits; they carry Zemax's own double rounding.  The rays'
 * coordinates on the way are up to about 1 mm, where a double's spacing
 * is 2.2e-16 mm, and the image point inherits a few such roundings: the
 * bound is 4 of them, 8.9e-13 um.  The largest difference seen is 4.3e-13
 * um (precise and mpfr, which agree, so the difference is Zemax's) and
 * 5.6e-13 um (classic), at Py = -0.875.  The pupil coordinates are ZOSPy's
 * (-1 + k / 40 as doubles, -0.9750000000000001 for instance); whether
 * Zemax rounded them the same way moves the image by under 1e-15 um. */
static void test_ray_fan(void **state)
{
    /* The file OpticStudio saved in the run that gave these numbers. */
    sg_system *sys = load_design_from(1);
    sg_catalog *cat = tu_catalog();
    char *text = slurp("tests/data/zospy/ray_fan_1_40.txt"), *line, *save = NULL;
    const double bound_um = 4.0 * 0x1p-52 * 1000.0;
    double pupil[96], tan_um[96], sag_um[96];
    int n = 0, m, k;
    (void)state;
    for (line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        if (!isdigit((unsigned char)line[line[0] == '-']))
            continue;
        assert_true(n < 96);
        assert_int_equal(sscanf(line, "%lf %lf %lf", &pupil[n], &tan_um[n], &sag_um[n]), 3);
        n++;
    }
    free(text);
    assert_int_equal(n, 81);
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, cat, methods[m]);
        sg_ray_surface row[8], chief[8];
        int img = sys->nsurf - 1;
        double worst = 0;
        assert_int_equal(sg_trace_normalized(t, 0, 0, 0, 0, chief), SG_OK);
        for (k = 0; k < n; k++) {
            double ty, sx;
            assert_int_equal(sg_trace_normalized(t, 0, 0, 0, pupil[k], row), SG_OK);
            ty = (row[img].y - chief[img].y) * 1000.0;
            assert_int_equal(sg_trace_normalized(t, 0, 0, pupil[k], 0, row), SG_OK);
            sx = (row[img].x - chief[img].x) * 1000.0;
            if (!(fabs(ty - tan_um[k]) <= bound_um && fabs(sx - sag_um[k]) <= bound_um))
                fail_msg("%s: pupil %.17g: sagitta %.17g / %.17g um, Zemax %.17g / %.17g um",
                         sg_method_name(methods[m]), pupil[k], ty, sx, tan_um[k], sag_um[k]);
            worst = fmax(worst, fmax(fabs(ty - tan_um[k]), fabs(sx - sag_um[k])));
        }
        print_message("# ray fan, %s: largest difference from Zemax %.2e um (bound %.2e)\n",
                      sg_method_name(methods[m]), worst, bound_um);
        sg_tracer_free(t);
    }
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* ------------------------------------------------------------------------
 * optiland's Hubble (tests/data/optiland): the image rows OpticStudio 2023
 * R1.02 gave for six rays, and its first-order data.
 * ------------------------------------------------------------------------ */

static sg_system *load_hubble(void)
{
    char path[1024];
    sg_system *sys = sg_system_new();
    sg_diag d;
    assert_non_null(sys);
    sg_diag_clear(&d);
    if (sg_design_load(sys, tu_path("tests/data/optiland/hubble.json", path, sizeof path), &d) !=
        SG_OK)
        fail_msg("%s", d.msg);
    return sys;
}

/* Whether the published value p (9 decimals) is v rounded to 10 decimals
 * and then to 9, a tie at the second step going either way.  printf
 * rounds the exact binary value correctly; the digits are then integers. */
static int double_rounded_to(double v, double p)
{
    char s10[64], *q, digits[64];
    long long n10, n9, want = llround(p * 1e9);
    int k = 0, neg, rem;
    snprintf(s10, sizeof s10, "%.10f", v);
    neg = s10[0] == '-';
    for (q = s10 + neg; *q; q++)
        if (*q != '.')
            digits[k++] = *q;
    digits[k] = '\0';
    n10 = atoll(digits);
    n9 = n10 / 10;
    rem = (int)(n10 % 10);
    if (neg)
        n9 = -n9;
    if (rem < 5)
        return n9 == want;
    if (rem > 5)
        return n9 + (neg ? -1 : 1) == want;
    return n9 == want || n9 + (neg ? -1 : 1) == want;
}

/* Six rays at the image of the Hubble (16 m of path, conic mirrors, a
 * curved image), as the numbers optiland's test file lists: x, y and the
 * direction cosines L, M, 9 decimals (y of the last ray 8, its ninth being
 * a 0 the listing drops).  Each is sagitta's value rounded twice, to 10
 * decimals (what OpticStudio displays) and then to 9: for 22 of the 24 that
 * is the plain rounding to 9, and the other two, y and M of the skew ray
 * (Hy = Px = 0.7), are ties at the second rounding (105.4330311205 and
 * 0.0151531825), where a plain rounding of our value differs from the
 * published one by 5.4e-10, one tenth of a digit beyond half of one.
 * precise and mpfr are held to that; classic's double arithmetic misses
 * some of these digits (printed, not asserted). */
static void test_hubble_rays(void **state)
{
    sg_system *sys = load_hubble();
    sg_catalog *cat = tu_catalog();
    char *text = slurp("tests/data/optiland/hubble_rays.txt"), *line, *save = NULL;
    static const char *const comp[4] = {"x", "y", "L", "M"};
    double ray[8][8];
    int n = 0, m, k, c;
    (void)state;
    for (line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        if (!isdigit((unsigned char)line[line[0] == '-']))
            continue;
        assert_true(n < 8);
        assert_int_equal(sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf", &ray[n][0], &ray[n][1],
                                &ray[n][2], &ray[n][3], &ray[n][4], &ray[n][5], &ray[n][6],
                                &ray[n][7]),
                         8);
        n++;
    }
    free(text);
    assert_int_equal(n, 6);
    for (m = 0; m < 3; m++) {
        sg_tracer *t = tu_tracer(sys, cat, methods[m]);
        sg_ray_surface row[8];
        int img = sys->nsurf - 1, nmiss = 0;
        double worst = 0;
        for (k = 0; k < n; k++) {
            double got[4];
            assert_int_equal(
                sg_trace_normalized(t, ray[k][0], ray[k][1], ray[k][2], ray[k][3], row), SG_OK);
            got[0] = row[img].x;
            got[1] = row[img].y;
            got[2] = row[img].l;
            got[3] = row[img].m;
            for (c = 0; c < 4; c++) {
                double want = ray[k][4 + c];
                worst = fmax(worst, fabs(got[c] - want));
                if (double_rounded_to(got[c], want))
                    continue;
                nmiss++;
                if (methods[m] != SG_METHOD_CLASSIC)
                    fail_msg("%s: ray (%g, %g, %g, %g) %s: sagitta %.17g, published %.15g",
                             sg_method_name(methods[m]), ray[k][0], ray[k][1], ray[k][2],
                             ray[k][3], comp[c], got[c], want);
            }
        }
        print_message("# Hubble, %s: %d of 24 published values reproduced, largest difference "
                      "%.2e\n",
                      sg_method_name(methods[m]), 24 - nmiss, worst);
        sg_tracer_free(t);
    }
    sg_catalog_free(cat);
    sg_system_free(sys);
}

/* OpticStudio's first-order data were read on an earlier export, written
 * with 9 significant digits (optiland's writer before its #712).  The same
 * rounding of the curvatures (a .zmx stores CURV) gives its focal length
 * to every printed digit (57600.0799477 against 57600.079948); the design
 * as given has 57600.080998.  Thicknesses and conics have 9 digits or
 * fewer already. */
static void test_hubble_first_order(void **state)
{
    sg_system *sys = load_hubble();
    sg_catalog *cat = tu_catalog();
    char *text = slurp("tests/data/optiland/hubble_first_order.txt"), *line, *save = NULL;
    sg_paraxial px;
    sg_diag d;
    int i, n = 0;
    (void)state;
    for (i = 0; i < sys->nsurf; i++) {
        char buf[64];
        if (isinf(sys->surf[i].radius))
            continue;
        snprintf(buf, sizeof buf, "%.9g", 1.0 / sys->surf[i].radius);
        sys->surf[i].radius = 1.0 / strtod(buf, NULL);
    }
    sg_diag_clear(&d);
    assert_int_equal(sg_paraxial_compute(sys, cat, 0, &px, &d), SG_OK);
    for (line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        char name[16], tok[64];
        double want, half, got = NAN;
        if (sscanf(line, "%15s %63s", name, tok) != 2 || !zemax_number(tok, &want, &half))
            continue;
        if (!strcmp(name, "f2"))
            got = px.efl;
        else if (!strcmp(name, "EPL"))
            got = px.enp_pos;
        else if (!strcmp(name, "XPD"))
            got = px.exp_diam;
        else if (!strcmp(name, "XPL"))
            got = px.exp_pos;
        else if (!strcmp(name, "FNO"))
            got = px.image_fnum;
        else
            fail_msg("unknown quantity %s", name);
        if (!(fabs(got - want) <= half))
            fail_msg("%s: sagitta %.12g, OpticStudio %s", name, got, tok);
        n++;
    }
    free(text);
    assert_int_equal(n, 5);
    sg_catalog_free(cat);
    sg_system_free(sys);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_skew_ray),
        cmocka_unit_test(test_axial_ray),
        cmocka_unit_test(test_ray_fan),
        cmocka_unit_test(test_hubble_rays),
        cmocka_unit_test(test_hubble_first_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
