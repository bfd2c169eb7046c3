/*
 * consumer.c - a program outside the tree, built against the installed
 * libsagitta through pkg-config (tests/install/run.sh), as a user's would be.
 *
 * It checks what only an install can get wrong: the header compiles alone,
 * the library loads by its soname, the catalogs and examples are found in
 * the install's own data directory, and a real ray through the installed
 * singlet example lands where closed-form geometry puts it.
 *
 * Usage: consumer DATADIR  (the installed share/sagitta, under DESTDIR)
 */
#include <sagitta.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int fails;

static void check(int ok, const char *what)
{
    printf("%s - %s\n", ok ? "ok" : "not ok", what);
    if (!ok)
        fails++;
}

/* Refraction of unit direction d at unit normal nrm (pointing against d's
 * side or not: the sign is fixed here) from index n1 to n2, Snell's law in
 * vector form, in long double. */
static void refract(long double d[3], const long double nrm[3], long double n1, long double n2)
{
    long double c = -(d[0] * nrm[0] + d[1] * nrm[1] + d[2] * nrm[2]);
    long double nn[3] = { nrm[0], nrm[1], nrm[2] }, mu = n1 / n2, k;
    int i;

    if (c < 0) {
        c = -c;
        for (i = 0; i < 3; i++)
            nn[i] = -nn[i];
    }
    k = sqrtl(1 - mu * mu * (1 - c * c));
    for (i = 0; i < 3; i++)
        d[i] = mu * d[i] + (mu * c - k) * nn[i];
}

int main(int argc, char **argv)
{
    char buf[4096], want[4096], path[4200];
    const char *dir;
    sg_catalog *cat = sg_catalog_new();
    sg_system *sys = sg_system_new();
    const sg_glass *bk7;
    sg_diag d;
    sg_paraxial px;
    sg_trace_opts o;
    sg_tracer *t;
    sg_ray_surface rows[8];
    double n, start[3] = { 0, 3.0, 0 }, dir3[3] = { 0, 0, 1 };
    long double R = 51.5L, tc = 3.6L, bfl = 97.278L, h = 3.0L, p[3], dv[3], nrm[3], s;
    int rc;

    if (argc != 2) {
        fprintf(stderr, "usage: consumer DATADIR\n");
        return 2;
    }
    printf("TAP version 13\n1..6\n");
    sg_diag_clear(&d);

    /* The data directory is the install's, found beside the library. */
    dir = sg_data_dir("lensdb", buf, sizeof buf);
    snprintf(want, sizeof want, "%s/lensdb", argv[1]);
    check(dir && realpath(want, path) && strcmp(dir, path) == 0,
          "sg_data_dir finds the installed lensdb beside the library");

    rc = sg_catalog_load_default(cat, &d);
    bk7 = rc == SG_OK ? sg_catalog_find(cat, "N-BK7") : NULL;
    n = bk7 ? sg_glass_index(bk7, 0.5875618) : 0;
    /* Schott's data sheet: N-BK7 nd = 1.51680 (5 decimals printed). */
    check(bk7 && fabs(n - 1.51680) < 5e-6, "N-BK7 nd from the installed SCHOTT catalog");

    dir = sg_data_dir("examples", buf, sizeof buf);
    snprintf(path, sizeof path, "%s/singlet.json", dir ? dir : "");
    rc = dir ? sg_design_load(sys, path, &d) : SG_EIO;
    check(rc == SG_OK, "the installed singlet example loads");
    if (rc != SG_OK) {
        fprintf(stderr, "%s\n", d.msg);
        return 1;
    }

    /* A plano-convex lens: the plane adds no power whatever the thickness,
     * so EFL = R / (n - 1). */
    rc = sg_paraxial_compute(sys, cat, 1, &px, &d); /* 0-based: d line */
    check(rc == SG_OK && fabs(px.efl - 51.5 / (n - 1)) < 1e-9 * px.efl,
          "paraxial EFL is R / (n - 1)");
    printf("# EFL %.17g, R / (n - 1) %.17g, n %.17g\n", px.efl, 51.5 / (n - 1), n);

    /* A real ray 3 mm above the axis, parallel to it: the sphere's hit,
     * Snell's law twice, and the image plane, in long double. */
    sg_trace_opts_init(&o);
    o.wave = 1;
    t = sg_tracer_new(sys, cat, &o, &d);
    rc = t ? sg_trace_start(t, start, dir3, rows) : SG_ENOMEM;
    check(rc == SG_OK, "a real ray reaches the image");
    p[0] = 0;
    p[1] = h;
    p[2] = R - sqrtl(R * R - h * h);
    nrm[0] = 0;
    nrm[1] = -p[1] / R;
    nrm[2] = (R - p[2]) / R;
    dv[0] = 0, dv[1] = 0, dv[2] = 1;
    refract(dv, nrm, 1.0L, (long double)n);
    s = (tc - p[2]) / dv[2];
    p[1] += s * dv[1];
    nrm[0] = 0, nrm[1] = 0, nrm[2] = 1;
    refract(dv, nrm, (long double)n, 1.0L);
    /* Indices are relative to air (Zemax's convention), so air's is 1. */
    p[1] += bfl * dv[1] / dv[2];
    check(rc == SG_OK && fabsl(rows[3].y - p[1]) < 1e-12L,
          "image height of the ray matches closed-form refraction");
    printf("# image y %.17g, closed form %.17Lg\n", rows[3].y, p[1]);

    sg_tracer_free(t);
    sg_system_free(sys);
    sg_catalog_free(cat);
    return fails ? 1 : 0;
}
