/* rays_speed.c - "trace --rays" against the batch trace of the same rays.
 *
 *   rays_speed SAGITTA DESIGN.json RAYS.csv FORMAT|none [REPEAT [SURFACES]]
 *
 * Each round traces the rays in memory with sg_batch_trace, in the blocks
 * trace --rays uses, on every core, and then runs SAGITTA trace DESIGN
 * --rays RAYS --format FORMAT into a scratch file (/dev/null for text
 * formats), alternating so both see the same load.  It prints the medians
 * of wall time and of CPU time, and their ratios.  FORMAT none times the
 * batch trace alone (the minimum CPU time is the figure to compare under
 * load).  SURFACES, when given, is trace's --surface list; the batch then
 * keeps the same rows. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "csvrays.h"
#include "sagitta.h"

static double now(clockid_t c)
{
    struct timespec ts;
    clock_gettime(c, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double children_cpu(void)
{
    struct rusage ru;
    getrusage(RUSAGE_CHILDREN, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
           (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int main(int argc, char **argv)
{
    sg_catalog *cat = sg_catalog_new();
    sg_system *sys = sg_system_new();
    sg_trace_opts opts;
    sg_batch *b;
    sg_tracer *t;
    sg_ray_in *rays;
    sg_ray_surface *out;
    sg_ray_kind kind;
    int *status, nsurf, only, rep, nrep = argc > 5 ? atoi(argv[5]) : 3, k;
    size_t nray, block, at;
    double tw[1000], tc[1000], cw[1000], cc[1000];
    char outpath[] = "/tmp/rays_speed_XXXXXX";
    sg_diag d;

    if (argc < 5 || nrep < 1 || nrep > 1000) {
        fprintf(stderr, "usage: rays_speed SAGITTA DESIGN.json RAYS.csv FORMAT|none [REPEAT "
                        "[SURFACES]]\n");
        return 2;
    }
    sg_diag_clear(&d);
    sg_catalog_load_default(cat, &d);
    sg_diag_clear(&d);
    if (sg_design_load(sys, argv[2], &d) != SG_OK ||
        csvrays_read(argv[3], &kind, &rays, &nray, &d) != SG_OK) {
        fprintf(stderr, "rays_speed: %s\n", d.msg);
        return 1;
    }
    sg_trace_opts_init(&opts);
    t = sg_tracer_new(sys, cat, &opts, &d);
    b = t ? sg_batch_new(sys, cat, &opts, 0, &d) : NULL;
    if (!b) {
        fprintf(stderr, "rays_speed: %s\n", d.msg);
        return 1;
    }
    nsurf = sg_tracer_nsurf(t);
    /* The block of ui/cli.c's rays_block. */
    block = ((size_t)16 << 20) / ((size_t)nsurf * sizeof(sg_ray_surface));
    block = block < 16 ? 16 : block > 65536 ? 65536 : block;
    out = malloc(block * (size_t)nsurf * sizeof *out);
    status = malloc(block * sizeof *status);
    if (!out || !status)
        return 1;
    if (strcmp(argv[4], "hdf5") == 0) {
        int fd = mkstemp(outpath);
        if (fd < 0)
            return 1;
        close(fd);
    } else {
        strcpy(outpath, "/dev/null");
    }
    only = strcmp(argv[4], "none") == 0;
    for (rep = 0; rep < nrep; rep++) {
        double w0 = now(CLOCK_MONOTONIC), c0 = now(CLOCK_PROCESS_CPUTIME_ID);
        pid_t pid;
        int ws;
        for (at = 0; at < nray; at += block) {
            size_t n = nray - at < block ? nray - at : block;
            if (sg_batch_trace(b, kind, rays + at, n, NULL, 0, out, status, &d) != SG_OK) {
                fprintf(stderr, "rays_speed: %s\n", d.msg);
                return 1;
            }
        }
        tw[rep] = now(CLOCK_MONOTONIC) - w0;
        tc[rep] = now(CLOCK_PROCESS_CPUTIME_ID) - c0;
        if (only)
            continue;
        w0 = now(CLOCK_MONOTONIC);
        c0 = children_cpu();
        pid = fork();
        if (pid == 0) {
            if (argc > 6)
                execl(argv[1], argv[1], "trace", argv[2], "--rays", argv[3], "--format", argv[4],
                      "-o", outpath, "--surface", argv[6], (char *)NULL);
            else
                execl(argv[1], argv[1], "trace", argv[2], "--rays", argv[3], "--format", argv[4],
                      "-o", outpath, (char *)NULL);
            _exit(127);
        }
        if (pid < 0 || waitpid(pid, &ws, 0) < 0 || !WIFEXITED(ws) || WEXITSTATUS(ws) != 0) {
            fprintf(stderr, "rays_speed: %s trace failed\n", argv[1]);
            return 1;
        }
        cw[rep] = now(CLOCK_MONOTONIC) - w0;
        cc[rep] = children_cpu() - c0;
    }
    if (strcmp(outpath, "/dev/null") != 0)
        unlink(outpath);
    k = nrep;
    {
        double a = median(tw, k), bc = median(tc, k), c = only ? 0 : median(cw, k),
               e = only ? 0 : median(cc, k);
        char load[64] = "?";
        FILE *f = fopen("/proc/loadavg", "r");
        if (f) {
            if (!fgets(load, sizeof load, f))
                strcpy(load, "?");
            load[strcspn(load, "\n")] = '\0';
            fclose(f);
        }
        printf("%zu rays, %d surfaces, %d rounds, load average %s\n", nray, nsurf, nrep, load);
        double mc = tc[0];
        for (rep = 1; rep < nrep; rep++)
            mc = tc[rep] < mc ? tc[rep] : mc;
        printf("batch trace:          wall %.3f s, cpu %.3f s (medians), cpu %.3f s (minimum)\n",
               a, bc, mc);
        if (only)
            return 0;
        printf("trace --rays %-8s: wall %.3f s, cpu %.3f s (medians)\n", argv[4], c, e);
        printf("ratio:                wall %.2f, cpu %.2f\n", c / a, e / bc);
    }
    return 0;
}
