/* kernel_speed.c - the precise batch trace alone, one thread, CPU clock.
 *
 *   kernel_speed DESIGN.json [RAYS [REPEAT [ROWS.bin]]]
 *
 * Traces RAYS normalized rays (default 4000: three fields, Hy = 0, 0.7
 * and 1 in that order, pupil points drawn uniformly in the unit disc by a
 * fixed xorshift generator) with sg_trace_batch on one thread, once to
 * warm up and then REPEAT times (default 50), and prints the minimum CPU
 * time, the figure in million ray-surfaces per second and the count of
 * rays traced to the image.  ROWS.bin, when given, receives the rows and
 * statuses, so two builds' bits can be compared with cmp.
 *
 * It uses only calls that every build since dcb8a76 has, so it links
 * against an old build's library as well (bench/kernel_ab.sh builds it
 * against two builds and alternates them). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "sagitta.h"

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t seed = 88172645463325252ull;

static double uniform(void)
{
    seed ^= seed << 13;
    seed ^= seed >> 7;
    seed ^= seed << 17;
    return (double)(seed >> 11) * 0x1p-53;
}

int main(int argc, char **argv)
{
    sg_catalog *cat = sg_catalog_new();
    sg_system *sys = sg_system_new();
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    sg_ray_in *rays;
    sg_ray_surface *out;
    int *st, ns, rep, k;
    size_t n, i, ok = 0;
    double best = -1.0;
    static const double hy[3] = {0.0, 0.7, 1.0};

    if (argc < 2 || argc > 5) {
        fprintf(stderr, "usage: kernel_speed DESIGN.json [RAYS [REPEAT [ROWS.bin]]]\n");
        return 2;
    }
    n = argc > 2 ? strtoul(argv[2], NULL, 10) : 4000;
    rep = argc > 3 ? atoi(argv[3]) : 50;
    if (n < 1 || rep < 1) {
        fprintf(stderr, "kernel_speed: RAYS and REPEAT must be positive\n");
        return 2;
    }
    sg_diag_clear(&d);
    sg_catalog_load_default(cat, &d);
    sg_diag_clear(&d);
    if (sg_design_load(sys, argv[1], &d) != SG_OK) {
        fprintf(stderr, "kernel_speed: %s\n", d.msg);
        return 1;
    }
    sg_trace_opts_init(&o);
    t = sg_tracer_new(sys, cat, &o, &d);
    if (!t) {
        fprintf(stderr, "kernel_speed: %s\n", d.msg);
        return 1;
    }
    ns = sg_tracer_nsurf(t);
    rays = malloc(n * sizeof *rays);
    out = malloc(n * (size_t)ns * sizeof *out);
    st = malloc(n * sizeof *st);
    if (!rays || !out || !st) {
        fprintf(stderr, "kernel_speed: out of memory\n");
        return 1;
    }
    for (i = 0; i < n; i++) {
        double px, py;
        do {
            px = 2.0 * uniform() - 1.0;
            py = 2.0 * uniform() - 1.0;
        } while (px * px + py * py > 1.0);
        rays[i].v[0] = 0.0;
        rays[i].v[1] = hy[i * 3 / n];
        rays[i].v[2] = px;
        rays[i].v[3] = py;
        rays[i].v[4] = rays[i].v[5] = 0.0;
    }
    for (k = 0; k <= rep; k++) {
        double c0 = cpu_now(), c;
        if (sg_trace_batch(sys, cat, &o, SG_RAYS_NORMALIZED, rays, n, 1, out, st, &d) != SG_OK) {
            fprintf(stderr, "kernel_speed: %s\n", d.msg);
            return 1;
        }
        c = cpu_now() - c0;
        if (k > 0 && (best < 0.0 || c < best))
            best = c;
    }
    for (i = 0; i < n; i++)
        ok += st[i] == SG_OK;
    printf("%.6f s %.2f M ray-surfaces/s %zu of %zu rays\n", best,
           (double)n * ns / best * 1e-6, ok, n);
    if (argc > 4) {
        FILE *f = fopen(argv[4], "wb");
        if (!f || fwrite(out, sizeof *out, n * (size_t)ns, f) != n * (size_t)ns ||
            fwrite(st, sizeof *st, n, f) != n || fclose(f) != 0) {
            fprintf(stderr, "kernel_speed: cannot write %s\n", argv[4]);
            return 1;
        }
    }
    sg_tracer_free(t);
    free(rays);
    free(out);
    free(st);
    sg_system_free(sys);
    sg_catalog_free(cat);
    return 0;
}
