/*
 * fuzz_csvrays.c - libFuzzer harness for the CSV ray list reader
 * (ui/csvrays.c, "sagitta trace --rays").
 *
 * The bytes go to csvrays_parse().  On success there is at least one ray,
 * every value is finite and a start/direction ray has a nonzero direction;
 * on failure there are no rays and a terminated message that names the
 * input.  The input is also parsed a second time from a copy with a
 * trailing newline added, which must not change the verdict when the input
 * already ended a line.  Accepted rays, written back with %.17g under the
 * header of their kind, must read back bit for bit.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csvrays.h"

#define NAME "fuzz.csv"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void die(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_csvrays: %s\n%s\n", what, detail ? detail : "");
    abort();
}

static int parse_checked(const char *text, size_t len, sg_ray_kind *kind, size_t *nray,
                         sg_ray_in **keep)
{
    sg_ray_in *rays = (sg_ray_in *)&rays; /* must be overwritten */
    sg_diag d;
    size_t k;
    int rc, j, ncol;

    sg_diag_clear(&d);
    rc = csvrays_parse(text, len, NAME, kind, &rays, nray, &d);
    if (!memchr(d.msg, '\0', sizeof d.msg))
        die("message not terminated", NULL);
    if (rc != SG_OK) {
        if (rays != NULL || *nray != 0)
            die("failure left rays behind", d.msg);
        if (d.code != rc || !strstr(d.msg, NAME))
            die("failure without a message naming the input", d.msg);
        *keep = NULL;
        return rc;
    }
    if (!rays || *nray == 0)
        die("success without rays", NULL);
    if (*kind != SG_RAYS_NORMALIZED && *kind != SG_RAYS_START_DIR)
        die("unknown ray kind", NULL);
    ncol = *kind == SG_RAYS_NORMALIZED ? 4 : 6;
    for (k = 0; k < *nray; k++) {
        for (j = 0; j < ncol; j++)
            if (!isfinite(rays[k].v[j]))
                die("a ray value that is not finite", NULL);
        if (*kind == SG_RAYS_START_DIR && rays[k].v[3] == 0.0 && rays[k].v[4] == 0.0 &&
            rays[k].v[5] == 0.0)
            die("a zero direction was accepted", NULL);
    }
    *keep = rays;
    return rc;
}

/* Writes the rays as a CSV text and reads them back. */
static void round_trip(sg_ray_kind kind, const sg_ray_in *rays, size_t n)
{
    int ncol = kind == SG_RAYS_NORMALIZED ? 4 : 6, j;
    size_t k, len = 0, cap = 64 + n * (size_t)ncol * 26;
    char *t = malloc(cap);
    sg_ray_kind k2;
    sg_ray_in *r2;
    size_t n2;
    if (!t)
        die("out of memory", NULL);
    len += (size_t)snprintf(t, cap, "%s\n",
                            kind == SG_RAYS_NORMALIZED ? "hx,hy,px,py" : "x,y,z,l,m,n");
    for (k = 0; k < n; k++)
        for (j = 0; j < ncol; j++)
            len += (size_t)snprintf(t + len, cap - len, "%.17g%s", rays[k].v[j],
                                    j + 1 < ncol ? "," : "\n");
    if (len >= cap)
        die("round-trip buffer too small", NULL);
    if (parse_checked(t, len, &k2, &n2, &r2) != SG_OK)
        die("rays written back with %.17g do not parse", t);
    if (k2 != kind || n2 != n || memcmp(r2, rays, n * sizeof *rays) != 0)
        die("rays written back with %.17g read back differently", t);
    free(r2);
    free(t);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sg_ray_kind k1, k2;
    sg_ray_in *r1, *r2;
    size_t n1, n2;
    char *copy;
    int rc1, rc2;

    rc1 = parse_checked((const char *)data, size, &k1, &n1, &r1);
    if (rc1 == SG_OK)
        round_trip(k1, r1, n1);
    if (size > 0 && data[size - 1] == '\n') {
        /* A blank line at the end is skipped, so the result is the same. */
        copy = malloc(size + 1);
        if (!copy)
            die("out of memory", NULL);
        memcpy(copy, data, size);
        copy[size] = '\n';
        rc2 = parse_checked(copy, size + 1, &k2, &n2, &r2);
        if (rc1 != rc2)
            die("a trailing blank line changed the verdict", NULL);
        if (rc1 == SG_OK &&
            (k1 != k2 || n1 != n2 || memcmp(r1, r2, n1 * sizeof *r1) != 0))
            die("a trailing blank line changed the rays", NULL);
        free(r2);
        free(copy);
    }
    free(r1);
    return 0;
}
