/*
 * bench.c - "sagitta bench": trace throughput, the cost of one MPFR ray and
 * of one live recompute of the editor, as figures to read, never to assert.
 *
 * Throughput is measured through the library's batch (sg_batch_new, then
 * sg_batch_trace on every surface), the path a spot diagram or the editor
 * takes, so it includes what such a caller pays: one tracer per thread and
 * the thread start-up.  The set is made and traced block by block into
 * one block's arrays, allocated and touched before the clock starts, so
 * page faults are not counted and memory does not grow with the set.
 *
 * Ray sets are field-major: every pupil point of one field point, then the
 * next field point.  The tracer keeps the last field point's object-space
 * launch (and, with ray aiming, its aimed chief ray), so this order is what
 * a real spot diagram costs; a pupil-major order would pay for the field on
 * every ray.
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli.h"
#ifdef SG_HAVE_EDITOR
#include "editor/view.h"
#endif
#include "lean.h"
#include "report.h"
#include "safetext.h"
#include "sg_config.h"

/* Short measurements (one ray, one recompute) take at least this many
 * samples, since each lasts only milliseconds. */
#define SHORT_MIN_SAMPLES 25
/* The editor's ray and the single MPFR ray: top of the field, top of the
 * pupil, the ray that usually has the largest angles. */
static const double edge_ray[4] = { 0.0, 1.0, 0.0, 1.0 };

enum { BENCH_TEXT = 0, BENCH_JSON = 1 };
enum { NMETHOD = 2, NTHR = 2, MAXSIZES = 3 };
static const sg_method methods[NMETHOD] = { SG_METHOD_PRECISE, SG_METHOD_CLASSIC };

typedef struct stat3 {
    double med, min, max;
} stat3;

/* One throughput measurement: a method, a thread count, a ray-set size. */
typedef struct tp_cell {
    int rc;           /* the batch's return */
    char msg[SG_DIAG_MSG];
    int threads;      /* threads used */
    size_t nok;       /* rays that reached the image */
    stat3 sec;        /* wall time of one batch */
    stat3 rs;         /* ray-surfaces per second */
} tp_cell;

typedef struct tp_size {
    size_t nray;
    int skipped; /* out of memory for the arrays */
    tp_cell c[NMETHOD][NTHR];
} tp_size;

/* A short measurement: median time of an operation, or why it failed. */
typedef struct short_res {
    int rc;
    char msg[SG_DIAG_MSG];
    int status; /* trace status of the ray, for the MPFR ray */
    int samples;
    stat3 sec;
} short_res;

typedef struct design_res {
    const char *path;
    char title[128];
    int nsurf, nfield, aim;
    int load_rc; /* CLI exit status of loading */
    int trace_rc; /* first engine error of a measurement, SG_OK if none */
    char trace_msg[SG_DIAG_MSG + 32]; /* why no tracer could be made, or "" */
    size_t nsizes;
    tp_size sz[MAXSIZES];
    short_res mpfr_ray, recompute, recompute_digits;
} design_res;

typedef struct bench_cfg {
    int fmt;
    int repeat;
    int quick;
    int threads; /* the multi-threaded runs; 0 means every core */
    int cores;
    int nthr_all; /* threads that "all cores" resolves to */
    int progress; /* report progress on stderr */
    int cpu_clock; /* time by the process's CPU time, not the wall clock */
    int edit_surf; /* the surface the recompute's edits change; 0: surface 1 */
    size_t sizes[MAXSIZES];
    size_t nsizes;
} bench_cfg;

/* ------------------------------------------------------------ utilities */

/* The wall clock, or with cpu the CPU time of the whole process (every
 * thread's summed): on a shared machine a process's CPU time moves far
 * less with the others' load than the wall time does. */
static double now_s(int cpu)
{
    struct timespec ts;
    clock_gettime(cpu ? CLOCK_PROCESS_CPUTIME_ID : CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Sorts v in place. */
static stat3 stats(double *v, int n)
{
    stat3 s;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    s.min = v[0];
    s.max = v[n - 1];
    s.med = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    return s;
}

static int count_cores(void)
{
    long c = sysconf(_SC_NPROCESSORS_ONLN);
    return c > 0 ? (int)c : 1;
}

/* "model name" from /proc/cpuinfo, or "" when it cannot be read. */
static void cpu_model(char *buf, size_t len)
{
    char line[512];
    FILE *f = fopen("/proc/cpuinfo", "r");
    buf[0] = '\0';
    if (!f)
        return;
    while (fgets(line, sizeof line, f)) {
        char *colon = strchr(line, ':');
        if (strncmp(line, "model name", 10) == 0 && colon) {
            colon++;
            while (*colon == ' ' || *colon == '\t')
                colon++;
            colon[strcspn(colon, "\n")] = '\0';
            snprintf(buf, len, "%s", colon);
            break;
        }
    }
    fclose(f);
}

/* The 1-minute load average, or -1: a busy machine explains slow figures. */
static double load_average(void)
{
    double la = -1.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f)
        return -1.0;
    if (fscanf(f, "%lf", &la) != 1)
        la = -1.0;
    fclose(f);
    return la;
}

/* The build type, as far as the compiler's macros reveal it. */
static const char *build_type(void)
{
#if defined(__OPTIMIZE__) && defined(NDEBUG)
    return "release (optimized, NDEBUG)";
#elif defined(__OPTIMIZE__)
    return "optimized, assertions on (debugoptimized)";
#else
    return "not optimized (debug)";
#endif
}

static int have_fma(void)
{
#if defined(__FMA__)
    return 1;
#else
    return 0;
#endif
}

/* ------------------------------------------------------------ examples */

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* A bundled example's path, for the runs that default to one. */
static void example_path(const char *name, char *buf, size_t n)
{
    char found[4096];
    const char *dir = sg_data_dir("examples", found, sizeof found);

    snprintf(buf, n, "%s/%s", dir ? dir : SG_INSTALL_EXAMPLES, name);
}

/* Finds the bundled examples: $SAGITTA_EXAMPLES, else sg_data_dir's (the
 * source tree's from the build tree, else the installed copy).  Returns the
 * exit status; *paths is a sorted list of malloc'd strings. */
static int find_examples(char ***paths, size_t *n)
{
    const char *env = getenv("SAGITTA_EXAMPLES");
    const char *dir = NULL;
    char found[4096];
    DIR *d;
    struct dirent *e;
    char **v = NULL;
    size_t cnt = 0, cap = 0;

    *paths = NULL;
    *n = 0;
    if (env && env[0])
        dir = env;
    else if (!(dir = sg_data_dir("examples", found, sizeof found)))
        dir = SG_INSTALL_EXAMPLES;
    d = opendir(dir);
    if (!d) {
        cli_error("bench: examples directory %s: %s (name designs on the command "
                  "line, or set SAGITTA_EXAMPLES)", dir, strerror(errno));
        return CLI_EXIT_FILE;
    }
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        char *p;
        if (len <= 5 || strcmp(e->d_name + len - 5, ".json") != 0 || e->d_name[0] == '.')
            continue;
        if (cnt == cap) {
            char **nv = realloc(v, (cap ? 2 * cap : 16) * sizeof *v);
            if (!nv)
                goto nomem;
            v = nv;
            cap = cap ? 2 * cap : 16;
        }
        p = malloc(strlen(dir) + len + 2);
        if (!p)
            goto nomem;
        sprintf(p, "%s/%s", dir, e->d_name);
        v[cnt++] = p;
    }
    closedir(d);
    if (cnt == 0) {
        cli_error("bench: no *.json designs in %s", dir);
        free(v);
        return CLI_EXIT_FILE;
    }
    qsort(v, cnt, sizeof *v, cmp_str);
    *paths = v;
    *n = cnt;
    return CLI_EXIT_OK;
nomem:
    closedir(d);
    while (cnt)
        free(v[--cnt]);
    free(v);
    cli_error("out of memory");
    return CLI_EXIT_INTERNAL;
}

/* ------------------------------------------------------------ ray sets */

/* Rays first..first+n-1 of a set of nray rays over the design's field
 * points and the unit pupil, field-major, into rays[0..n-1].  Pupil points
 * follow Vogel's spiral (radius sqrt((i + 1/2) / m), golden angle steps),
 * a deterministic low-discrepancy cover of the disc, so every size samples
 * the whole pupil evenly.  Any block of the set can be made on its own, so
 * the set is never held whole. */
static void make_rays(const sg_system *sys, size_t nray, size_t first, size_t n,
                      sg_ray_in *rays)
{
    const double golden = 3.14159265358979323846 * (3.0 - sqrt(5.0));
    double sx = 0.0, sy = 0.0;
    size_t off = 0;
    int f, nf = sys->nfield > 0 ? sys->nfield : 1;

    for (f = 0; f < sys->nfield; f++) {
        double x = fabs(sys->field[f].x), y = fabs(sys->field[f].y);
        if (sys->field_norm == SG_NORM_RADIAL) {
            double h = hypot(x, y);
            sx = h > sx ? h : sx;
            sy = sx;
        } else {
            sx = x > sx ? x : sx;
            sy = y > sy ? y : sy;
        }
    }
    for (f = 0; f < nf; f++) {
        size_t m = nray / (size_t)nf + ((size_t)f < nray % (size_t)nf), i;
        double hx = 0.0, hy = 0.0;
        if (sys->nfield > 0) {
            hx = sx > 0.0 ? sys->field[f].x / sx : 0.0;
            hy = sy > 0.0 ? sys->field[f].y / sy : 0.0;
        }
        for (i = first > off ? first - off : 0; i < m && off + i < first + n; i++) {
            sg_ray_in *ray = &rays[off + i - first];
            double rad = sqrt(((double)i + 0.5) / (double)m);
            double th = golden * (double)i;
            memset(ray, 0, sizeof *ray);
            ray->v[0] = hx;
            ray->v[1] = hy;
            ray->v[2] = rad * cos(th);
            ray->v[3] = rad * sin(th);
        }
        off += m;
    }
}

/* Rays of one block of a throughput run: its rows (every surface of every
 * ray, as a spot diagram's caller gets them) stay near 11 MB, so memory
 * does not grow with the ray count. */
#define BENCH_BLOCK_ROWS ((size_t)1 << 17)

static size_t block_rays(int nsurf, int nthr)
{
    size_t b = BENCH_BLOCK_ROWS / (size_t)(nsurf > 0 ? nsurf : 1);
    /* Every thread gets at least one run of 64 rays (batch.c). */
    if (b < 64 * (size_t)nthr)
        b = 64 * (size_t)nthr;
    return b;
}

/* ------------------------------------------------------------ measuring */

/* What is being measured, on stderr, so a long JSON run shows it is alive. */
static void progress(const bench_cfg *cfg, const char *path, const char *what, size_t n)
{
    if (!cfg->progress)
        return;
    char safe[1024];
    safe_text(path, safe, sizeof safe);
    if (n)
        fprintf(stderr, "sagitta: bench: %s: %zu %s\n", safe, n, what);
    else
        fprintf(stderr, "sagitta: bench: %s: %s\n", safe, what);
}

/* One timed run: a kept batch (one tracer per thread, as sg_trace_batch
 * makes), then the set block by block, every surface of every ray written
 * to the block's rows.  Only the batch's making and its trace calls are
 * timed; making the next block's rays is not.  Returns the engine's code;
 * *sec is the time, *nok the rays that reached the image. */
static int timed_run(int cpu, const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *o,
                     int nt, size_t nray, size_t blk, sg_ray_in *rays,
                     sg_ray_surface *out, int *status, double *sec, size_t *nok,
                     sg_diag *d)
{
    sg_batch *b;
    size_t first, k;
    double t0 = now_s(cpu), t;
    int rc = SG_OK;
    /* No more threads than runs of rays to give them, as sg_trace_batch. */
    if ((size_t)nt > (nray + 63) / 64)
        nt = (int)((nray + 63) / 64);
    b = sg_batch_new(sys, cat, o, nt, d);
    if (!b)
        return d->code ? d->code : SG_ENOMEM;
    *nok = 0;
    t = now_s(cpu) - t0;
    for (first = 0; first < nray && rc == SG_OK; first += blk) {
        size_t n = nray - first < blk ? nray - first : blk;
        make_rays(sys, nray, first, n, rays);
        t0 = now_s(cpu);
        rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, n, NULL, 0, out, status, d);
        t += now_s(cpu) - t0;
        for (k = 0; rc == SG_OK && k < n; k++)
            *nok += status[k] == SG_OK;
    }
    t0 = now_s(cpu);
    sg_batch_free(b);
    *sec = t + (now_s(cpu) - t0);
    return rc;
}

/* Runs every method and thread count on one ray-set size.  Repeats are
 * interleaved (precise, classic, precise, ...) so that a change in machine
 * load shifts both methods alike and their ratio stays fair. */
static void bench_size(const bench_cfg *cfg, const sg_system *sys, const sg_catalog *cat,
                       tp_size *ts)
{
    size_t nray = ts->nray, blk;
    int nsurf = sys->nsurf, m, h, rep, nthr = cfg->nthr_all > 1 ? NTHR : 1;
    sg_ray_in *rays;
    sg_ray_surface *out;
    int *status;
    double *sec[NMETHOD][NTHR] = { { NULL } };

    blk = block_rays(nsurf, cfg->nthr_all);
    if (blk > nray)
        blk = nray;
    rays = malloc(blk * sizeof *rays);
    out = malloc(blk * (size_t)nsurf * sizeof *out);
    status = malloc(blk * sizeof *status);
    if (!rays || !out || !status)
        goto nomem;
    for (m = 0; m < NMETHOD; m++)
        for (h = 0; h < nthr; h++) {
            sec[m][h] = malloc((size_t)cfg->repeat * sizeof(double));
            if (!sec[m][h])
                goto nomem;
        }
    /* Touch every page now so the first timed run pays no page faults.
     * The fill is not zero: the compiler may turn malloc and a zero
     * memset into calloc, whose fresh pages stay untouched. */
    memset(out, 0xff, blk * (size_t)nsurf * sizeof *out);
    memset(status, 0xff, blk * sizeof *status);
    memset(rays, 0xff, blk * sizeof *rays);

    for (rep = -1; rep < cfg->repeat; rep++) {
        for (m = 0; m < NMETHOD; m++) {
            for (h = 0; h < nthr; h++) {
                tp_cell *c = &ts->c[m][h];
                int nt = h == 0 ? 1 : cfg->threads;
                sg_trace_opts o;
                sg_diag d;
                double t;
                size_t nok;
                int rc;
                /* A warm-up run (rep -1) only for small sets, where caches
                 * and the allocator's first calls would show. */
                if (rep < 0 && nray > 100000)
                    continue;
                if (c->rc != SG_OK)
                    continue;
                sg_trace_opts_init(&o);
                o.method = methods[m];
                sg_diag_clear(&d);
                if (nt <= 0)
                    nt = cfg->nthr_all;
                rc = timed_run(cfg->cpu_clock, sys, cat, &o, nt, nray, blk, rays, out, status, &t, &nok,
                               &d);
                if (rc != SG_OK) {
                    c->rc = rc;
                    snprintf(c->msg, sizeof c->msg, "%s", d.msg[0] ? d.msg : sg_strerror(rc));
                    continue;
                }
                if (rep < 0)
                    continue;
                sec[m][h][rep] = t;
                if (rep == cfg->repeat - 1)
                    c->nok = nok;
            }
        }
    }
    for (m = 0; m < NMETHOD; m++) {
        for (h = 0; h < nthr; h++) {
            tp_cell *c = &ts->c[m][h];
            double *rs = sec[m][h];
            double work;
            int i;
            c->threads = h == 0 ? 1 : cfg->nthr_all;
            if ((size_t)c->threads > nray)
                c->threads = (int)nray;
            if (c->rc != SG_OK)
                continue;
            work = (double)c->nok * (double)(nsurf - 1);
            c->sec = stats(rs, cfg->repeat);
            /* Throughput of each run, from the sorted times. */
            for (i = 0; i < cfg->repeat; i++)
                rs[i] = rs[i] > 0.0 ? work / rs[i] : 0.0;
            c->rs = stats(rs, cfg->repeat);
        }
    }
    goto done;
nomem:
    ts->skipped = 1;
done:
    for (m = 0; m < NMETHOD; m++)
        for (h = 0; h < NTHR; h++)
            free(sec[m][h]);
    free(rays);
    free(out);
    free(status);
}

static void set_err(short_res *r, int rc, const sg_diag *d)
{
    r->rc = rc;
    snprintf(r->msg, sizeof r->msg, "%s", d && d->msg[0] ? d->msg : sg_strerror(rc));
}

/* One MPFR trace of the edge ray: one tracer, the same ray timed again and
 * again (the MPFR method keeps no field cache, so every call is a full
 * trace with its ray aiming). */
static void bench_mpfr_ray(const bench_cfg *cfg, const sg_system *sys, const sg_catalog *cat,
                           short_res *r)
{
    int n = cfg->repeat > SHORT_MIN_SAMPLES ? cfg->repeat : SHORT_MIN_SAMPLES, i, rc;
    sg_ray_surface *out = malloc((size_t)sys->nsurf * sizeof *out);
    double *sec = malloc((size_t)n * sizeof *sec);
    sg_trace_opts o;
    sg_tracer *t;
    sg_diag d;

    memset(r, 0, sizeof *r);
    if (!out || !sec) {
        set_err(r, SG_ENOMEM, NULL);
        goto done;
    }
    sg_trace_opts_init(&o);
    o.method = SG_METHOD_MPFR;
    o.mpfr_bits = 256;
    sg_diag_clear(&d);
    rc = sg_tracer_open(sys, cat, &o, &t, &d);
    if (rc != SG_OK) {
        set_err(r, rc, &d);
        goto done;
    }
    for (i = 0; i < n; i++) {
        double t0 = now_s(cfg->cpu_clock);
        r->status = sg_trace_normalized(t, edge_ray[0], edge_ray[1], edge_ray[2],
                                        edge_ray[3], out);
        sec[i] = now_s(cfg->cpu_clock) - t0;
    }
    sg_tracer_free(t);
    r->samples = n;
    r->sec = stats(sec, n);
done:
    free(out);
    free(sec);
}

/* The editor's recompute after an edit, as ui/editor/compute.c does it:
 * a new precise tracer, the edge ray, the paraxial data (the tracer's);
 * with digits,
 * also an MPFR tracer and its trace of the same ray.  Each sample makes a
 * real edit first (surface 1's radius, or its thickness when flat, scaled
 * by 1 + 1e-9 and back in turn), and the glass indices come from a cache
 * kept across the samples, as the editor keeps one across edits.
 * Freeing the tracers is left out of the timing, as the editor frees the
 * old ones only when the next edit replaces them. */
static void bench_recompute(const bench_cfg *cfg, const sg_system *sys0,
                            const sg_catalog *cat, int digits, short_res *r)
{
    int n = cfg->repeat > SHORT_MIN_SAMPLES ? cfg->repeat : SHORT_MIN_SAMPLES, i, s1;
    sg_system *sys = sg_system_clone(sys0);
    sg_index_cache *ic = sg_index_cache_new();
    sg_mpfr_memo *memo = sg_mpfr_memo_new();
    sg_ray_surface *out = malloc((size_t)sys0->nsurf * sizeof *out);
    sg_ray_surface *ref = malloc((size_t)sys0->nsurf * sizeof *ref);
    double *sec = malloc((size_t)n * sizeof *sec), *val;
    sg_trace_opts o, mo;
    sg_diag d;

    memset(r, 0, sizeof *r);
    if (!sys || !ic || !memo || !out || !ref || !sec) {
        set_err(r, SG_ENOMEM, NULL);
        goto done;
    }
    s1 = sys->nsurf > 2 ? 1 : 0;
    if (cfg->edit_surf > 0 && cfg->edit_surf < sys->nsurf - 1)
        s1 = cfg->edit_surf;
    val = isfinite(sys->surf[s1].radius) && sys->surf[s1].radius != 0.0
              ? &sys->surf[s1].radius
              : &sys->surf[s1].thickness;
    sg_trace_opts_init(&o);
    mo = o;
    mo.method = SG_METHOD_MPFR;
    mo.mpfr_bits = 256;
    /* One round before the samples, so they see the cache an earlier
     * edit left, as every edit after the editor's first does. */
    for (i = -1; i < n; i++) {
        sg_tracer *t, *mt = NULL;
        double t0;
        int rc;
        if (i >= 0)
            *val *= i % 2 ? 1.0 / (1.0 + 1e-9) : 1.0 + 1e-9;
        sg_diag_clear(&d);
        t0 = now_s(cfg->cpu_clock);
        t = sg_tracer_new_cached(sys, cat, &o, ic, &d);
        if (!t) {
            set_err(r, d.code ? d.code : SG_ENOMEM, &d);
            goto done;
        }
        r->status = sg_trace_normalized(t, edge_ray[0], edge_ray[1], edge_ray[2],
                                        edge_ray[3], out);
        /* The editor copies the primary wavelength's paraxial data from
         * its tracer's launch, which computed them. */
        rc = sg_tracer_paraxial(t) ? SG_OK : SG_EINVAL;
        if (rc == SG_OK && digits) {
            /* As the editor: from the precise tracer's prepared model,
             * and the reference ray's states kept across edits. */
            mt = sg_tracer_new_method(t, mo.method, mo.mpfr_bits, ic, &d);
            sg_tracer_use_memo(mt, memo);
            if (mt)
                sg_trace_normalized(mt, edge_ray[0], edge_ray[1], edge_ray[2], edge_ray[3],
                                    ref);
            else
                rc = d.code ? d.code : SG_ENOMEM;
        }
        if (i >= 0)
            sec[i] = now_s(cfg->cpu_clock) - t0;
        sg_tracer_free(mt);
        sg_tracer_free(t);
        if (rc != SG_OK) {
            set_err(r, rc, &d);
            goto done;
        }
    }
    r->samples = n;
    r->sec = stats(sec, n);
done:
    sg_system_free(sys);
    sg_index_cache_free(ic);
    sg_mpfr_memo_free(memo);
    free(out);
    free(ref);
    free(sec);
}

/* ------------------------------------------------------------ text output */

static const char *size_label(size_t n, char *buf, size_t len)
{
    int e = 0;
    size_t m = n;
    while (m >= 10 && m % 10 == 0) {
        m /= 10;
        e++;
    }
    if (m == 1 && e >= 3)
        snprintf(buf, len, "1e%d", e);
    else
        snprintf(buf, len, "%zu", n);
    return buf;
}

static void text_cell(FILE *f, const tp_cell *c, size_t nray)
{
    if (c->rc != SG_OK) {
        fprintf(f, "  %-34s", "failed (see below)");
        return;
    }
    fprintf(f, "  %7.2f (%7.2f-%7.2f)  %5.1f%%", c->rs.med / 1e6, c->rs.min / 1e6,
            c->rs.max / 1e6, 100.0 * (double)(nray - c->nok) / (double)nray);
}

static void text_short(FILE *f, const char *what, const short_res *r)
{
    fprintf(f, "  %-44s", what);
    if (r->rc != SG_OK) {
        fprintf(f, "failed: %s\n", r->msg);
        return;
    }
    fprintf(f, "%9.3f ms  (min %.3f, max %.3f, %d runs)", 1e3 * r->sec.med, 1e3 * r->sec.min,
            1e3 * r->sec.max, r->samples);
    if (r->status != SG_OK)
        fprintf(f, "  ray: %s", sg_err_name(r->status));
    fputc('\n', f);
}

static void text_header(FILE *f, const bench_cfg *cfg)
{
    char cpu[256];
    double la = load_average();
    char sizes[64] = "", lab[16];
    size_t k;
    cpu_model(cpu, sizeof cpu);
    for (k = 0; k < cfg->nsizes; k++) {
        strcat(sizes, k ? ", " : "");
        strcat(sizes, size_label(cfg->sizes[k], lab, sizeof lab));
    }
    fprintf(f, "sagitta %s bench\n", SG_VERSION_STRING);
    fprintf(f, "machine: %d core%s, %s\n", cfg->cores, cfg->cores == 1 ? "" : "s",
            cpu[0] ? cpu : "CPU model unknown");
    fprintf(f, "build:   %s, FMA %s\n", build_type(), have_fma() ? "on" : "off");
    if (la >= 0.0)
        fprintf(f, "load:    %.2f (1-minute average before the runs)\n", la);
    fprintf(f, "runs:    median (min-max) of %d; rays %s; all cores = %d thread%s\n",
            cfg->repeat, sizes, cfg->nthr_all, cfg->nthr_all == 1 ? "" : "s");
    fprintf(f, "clock:   %s\n", cfg->cpu_clock ? "cpu (the process's CPU time, every thread's summed)"
                                                : "wall");
    fprintf(f, "Throughput in millions of ray-surfaces per second: rays that reached\n"
          "the image times (surfaces - 1) over %s time; 'fail' is the share of\n"
          "rays that did not reach it.  Rays are field-major, as in a spot diagram.\n",
          cfg->cpu_clock ? "CPU" : "wall");
}

static void text_design(FILE *f, const bench_cfg *cfg, const design_res *r)
{
    static const char *aim[] = { "off", "paraxial", "real" };
    size_t s;
    int h, m, nthr = cfg->nthr_all > 1 ? NTHR : 1;
    char lab[16];

    /* The path and the design's title are the user's text: no escape
     * code in them reaches the terminal. */
    fputc('\n', f);
    safe_fputs(r->path, f);
    fputc('\n', f);
    if (r->load_rc != CLI_EXIT_OK) {
        fputs("  not measured: the design did not load (see the message above)\n", f);
        return;
    }
    fputs("  ", f);
    safe_fputs(r->title, f);
    fprintf(f, "\n  %d surfaces, %d field point%s, ray aiming %s\n", r->nsurf,
            r->nfield, r->nfield == 1 ? "" : "s",
            r->aim >= 0 && r->aim <= 2 ? aim[r->aim] : "?");
    if (r->trace_msg[0]) {
        fprintf(f, "  not measured: the %s\n", r->trace_msg);
        return;
    }
    fprintf(f, "  %5s %3s  %-27s %5s  %-27s %5s  %s\n", "rays", "thr", "precise Mrs/s", "fail",
            "classic Mrs/s", "fail", "p/c");
    for (s = 0; s < r->nsizes; s++) {
        const tp_size *ts = &r->sz[s];
        if (ts->skipped) {
            fprintf(f, "  %5s      not measured: out of memory for the arrays\n",
                    size_label(ts->nray, lab, sizeof lab));
            continue;
        }
        for (h = 0; h < nthr; h++) {
            const tp_cell *p = &ts->c[0][h], *c = &ts->c[1][h];
            fprintf(f, "  %5s %3d", size_label(ts->nray, lab, sizeof lab), p->threads);
            text_cell(f, p, ts->nray);
            text_cell(f, c, ts->nray);
            if (p->rc == SG_OK && c->rc == SG_OK && c->rs.med > 0.0)
                fprintf(f, "  %.2f", p->rs.med / c->rs.med);
            fputc('\n', f);
        }
    }
    for (s = 0; s < r->nsizes; s++)
        for (m = 0; m < NMETHOD; m++)
            for (h = 0; h < nthr; h++)
                if (!r->sz[s].skipped && r->sz[s].c[m][h].rc != SG_OK)
                    fprintf(f, "  %s, %s rays, %d thread%s: %s\n", sg_method_name(methods[m]),
                            size_label(r->sz[s].nray, lab, sizeof lab),
                            r->sz[s].c[m][h].threads, r->sz[s].c[m][h].threads == 1 ? "" : "s",
                            r->sz[s].c[m][h].msg);
    if (nthr > 1 && r->nsizes > 0 && !r->sz[r->nsizes - 1].skipped) {
        const tp_size *ts = &r->sz[r->nsizes - 1];
        const char *sep = "";
        for (m = 0; m < NMETHOD; m++) {
            const tp_cell *one = &ts->c[m][0], *all = &ts->c[m][1];
            if (one->rc != SG_OK || all->rc != SG_OK || !(one->rs.med > 0.0))
                continue;
            if (!sep[0])
                fprintf(f, "  %d-thread scaling at %s rays:", cfg->nthr_all,
                        size_label(ts->nray, lab, sizeof lab));
            fprintf(f, "%s %s %.2fx", sep, sg_method_name(methods[m]),
                    all->rs.med / one->rs.med);
            sep = ",";
        }
        /* Other load on a shared machine slows a run on every core more
         * often than one on one core; the fastest runs show the scaling
         * itself. */
        if (sep[0]) {
            sep = "";
            fprintf(f, "\n  %*s fastest runs:", (int)strlen(lab) + 12, "");
            for (m = 0; m < NMETHOD; m++) {
                const tp_cell *one = &ts->c[m][0], *all = &ts->c[m][1];
                if (one->rc != SG_OK || all->rc != SG_OK || !(one->rs.max > 0.0))
                    continue;
                fprintf(f, "%s %s %.2fx", sep, sg_method_name(methods[m]),
                        all->rs.max / one->rs.max);
                sep = ",";
            }
            fputc('\n', f);
        }
    }
    text_short(f, "mpfr single ray (0,1,0,1), 256 bits:", &r->mpfr_ray);
    text_short(f, "live recompute (precise):", &r->recompute);
    text_short(f, "live recompute with mpfr digits check:", &r->recompute_digits);
    fflush(f);
}

/* ------------------------------------------------------------ JSON output */

static cJSON *json_stat(const stat3 *s)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "median", s->med);
    cJSON_AddNumberToObject(o, "min", s->min);
    cJSON_AddNumberToObject(o, "max", s->max);
    return o;
}

static cJSON *json_short(const short_res *r, int with_status)
{
    cJSON *o = cJSON_CreateObject();
    if (r->rc != SG_OK) {
        cJSON_AddStringToObject(o, "error", sg_err_name(r->rc));
        cJSON_AddStringToObject(o, "message", r->msg);
        return o;
    }
    cJSON_AddNumberToObject(o, "samples", r->samples);
    cJSON_AddItemToObject(o, "seconds", json_stat(&r->sec));
    if (with_status)
        cJSON_AddStringToObject(o, "ray_status", sg_err_name(r->status));
    return o;
}

static cJSON *json_design(const bench_cfg *cfg, const design_res *r)
{
    static const char *aim[] = { "off", "paraxial", "real" };
    cJSON *o = cJSON_CreateObject(), *tp, *ratio, *scal, *ray;
    size_t s;
    int m, h, nthr = cfg->nthr_all > 1 ? NTHR : 1;

    cJSON_AddStringToObject(o, "path", r->path);
    if (r->load_rc != CLI_EXIT_OK) {
        cJSON_AddStringToObject(o, "error", "the design did not load");
        return o;
    }
    cJSON_AddStringToObject(o, "title", r->title);
    cJSON_AddNumberToObject(o, "surfaces", r->nsurf);
    cJSON_AddNumberToObject(o, "field_points", r->nfield);
    cJSON_AddStringToObject(o, "ray_aiming", r->aim >= 0 && r->aim <= 2 ? aim[r->aim] : "?");
    if (r->trace_msg[0]) {
        cJSON_AddStringToObject(o, "error", sg_err_name(r->trace_rc));
        cJSON_AddStringToObject(o, "message", r->trace_msg);
        return o;
    }
    tp = cJSON_AddArrayToObject(o, "throughput");
    ratio = cJSON_AddArrayToObject(o, "precise_over_classic");
    for (s = 0; s < r->nsizes; s++) {
        const tp_size *ts = &r->sz[s];
        for (h = 0; h < nthr; h++) {
            for (m = 0; m < NMETHOD; m++) {
                const tp_cell *c = &ts->c[m][h];
                cJSON *e = cJSON_CreateObject();
                cJSON_AddStringToObject(e, "method", sg_method_name(methods[m]));
                cJSON_AddNumberToObject(e, "rays", (double)ts->nray);
                if (ts->skipped) {
                    cJSON_AddStringToObject(e, "error", "SG_ENOMEM");
                    cJSON_AddItemToArray(tp, e);
                    continue;
                }
                cJSON_AddNumberToObject(e, "threads", c->threads);
                if (c->rc != SG_OK) {
                    cJSON_AddStringToObject(e, "error", sg_err_name(c->rc));
                    cJSON_AddStringToObject(e, "message", c->msg);
                } else {
                    cJSON_AddNumberToObject(e, "rays_reached_image", (double)c->nok);
                    cJSON_AddNumberToObject(e, "failed_fraction",
                                            (double)(ts->nray - c->nok) / (double)ts->nray);
                    cJSON_AddItemToObject(e, "ray_surfaces_per_second", json_stat(&c->rs));
                    cJSON_AddItemToObject(e, "seconds", json_stat(&c->sec));
                }
                cJSON_AddItemToArray(tp, e);
            }
            if (!ts->skipped && ts->c[0][h].rc == SG_OK && ts->c[1][h].rc == SG_OK &&
                ts->c[1][h].rs.med > 0.0) {
                cJSON *e = cJSON_CreateObject();
                cJSON_AddNumberToObject(e, "rays", (double)ts->nray);
                cJSON_AddNumberToObject(e, "threads", ts->c[0][h].threads);
                cJSON_AddNumberToObject(e, "ratio", ts->c[0][h].rs.med / ts->c[1][h].rs.med);
                cJSON_AddItemToArray(ratio, e);
            }
        }
    }
    scal = cJSON_AddArrayToObject(o, "scaling");
    if (nthr > 1 && r->nsizes > 0 && !r->sz[r->nsizes - 1].skipped) {
        const tp_size *ts = &r->sz[r->nsizes - 1];
        for (m = 0; m < NMETHOD; m++) {
            const tp_cell *one = &ts->c[m][0], *all = &ts->c[m][1];
            if (one->rc == SG_OK && all->rc == SG_OK && one->rs.med > 0.0) {
                cJSON *e = cJSON_CreateObject();
                cJSON_AddStringToObject(e, "method", sg_method_name(methods[m]));
                cJSON_AddNumberToObject(e, "rays", (double)ts->nray);
                cJSON_AddNumberToObject(e, "threads", all->threads);
                cJSON_AddNumberToObject(e, "ratio", all->rs.med / one->rs.med);
                if (one->rs.max > 0.0)
                    cJSON_AddNumberToObject(e, "ratio_fastest", all->rs.max / one->rs.max);
                cJSON_AddItemToArray(scal, e);
            }
        }
    }
    ray = cJSON_AddArrayToObject(o, "edge_ray");
    for (m = 0; m < 4; m++)
        cJSON_AddItemToArray(ray, cJSON_CreateNumber(edge_ray[m]));
    cJSON_AddItemToObject(o, "mpfr_single_ray", json_short(&r->mpfr_ray, 1));
    cJSON_AddNumberToObject(cJSON_GetObjectItem(o, "mpfr_single_ray"), "bits", 256);
    cJSON_AddItemToObject(o, "live_recompute", json_short(&r->recompute, 1));
    cJSON_AddItemToObject(o, "live_recompute_with_digits", json_short(&r->recompute_digits, 1));
    return o;
}

static cJSON *json_top(const bench_cfg *cfg, double load0, double load1)
{
    cJSON *o = cJSON_CreateObject(), *mach, *set, *sizes;
    char cpu[256];
    size_t k;
    cpu_model(cpu, sizeof cpu);
    cJSON_AddStringToObject(o, "program", "sagitta bench");
    cJSON_AddStringToObject(o, "version", SG_VERSION_STRING);
    mach = cJSON_AddObjectToObject(o, "machine");
    cJSON_AddNumberToObject(mach, "cores", cfg->cores);
    if (cpu[0])
        cJSON_AddStringToObject(mach, "cpu", cpu);
    else
        cJSON_AddNullToObject(mach, "cpu");
    cJSON_AddStringToObject(mach, "build", build_type());
#if defined(__OPTIMIZE__)
    cJSON_AddTrueToObject(mach, "optimized");
#else
    cJSON_AddFalseToObject(mach, "optimized");
#endif
    cJSON_AddBoolToObject(mach, "fma", have_fma());
    if (load0 >= 0.0)
        cJSON_AddNumberToObject(mach, "load_average_before", load0);
    if (load1 >= 0.0)
        cJSON_AddNumberToObject(mach, "load_average_after", load1);
    set = cJSON_AddObjectToObject(o, "settings");
    cJSON_AddNumberToObject(set, "repeat", cfg->repeat);
    cJSON_AddBoolToObject(set, "quick", cfg->quick);
    cJSON_AddStringToObject(set, "clock", cfg->cpu_clock ? "cpu" : "wall");
    cJSON_AddNumberToObject(set, "edit_surface", cfg->edit_surf > 0 ? cfg->edit_surf : 1);
    cJSON_AddNumberToObject(set, "threads_all", cfg->nthr_all);
    cJSON_AddNumberToObject(set, "short_samples_min", SHORT_MIN_SAMPLES);
    cJSON_AddStringToObject(set, "ray_order", "field-major");
    cJSON_AddStringToObject(set, "pupil_pattern", "Vogel spiral");
    sizes = cJSON_AddArrayToObject(set, "rays");
    for (k = 0; k < cfg->nsizes; k++)
        cJSON_AddItemToArray(sizes, cJSON_CreateNumber((double)cfg->sizes[k]));
    return o;
}

/* ------------------------------------------------------------ command */

static void bench_help(FILE *f)
{
    fputs(
"Usage: sagitta bench [DESIGN.json ...] [OPTIONS]\n"
"Measure trace throughput, the cost of one MPFR ray and of one live\n"
"recompute of the editor, on the given designs or on every bundled example.\n"
"\n"
"Options:\n"
"  --format F      text (default) or json\n"
"  --repeat N      runs per measurement, 1 to 1000 (5); the median, minimum and\n"
"                  maximum are printed; single-ray timings take at least 25\n"
"  --quick         ray sets of 1e3 and 1e4 rays instead of 1e3, 1e5 and 1e6\n"
"  --rays N        one ray set of N rays, 1 to 1e9, instead\n"
"  --threads N     threads of the multi-threaded runs; 0 (default) is every core\n"
"  --clock C       wall (default) or cpu: time by the process's CPU time, the\n"
"                  sum over its threads, which a shared machine's load moves\n"
"                  far less than the wall time\n"
"  --edit-surface S  the surface whose radius (or thickness) the live\n"
"                  recompute's edits change (default 1)\n"
"  --spot          instead: a spot diagram of 1e6 rays (1e5 with --quick) on\n"
"                  the designs (default: the Cassegrain) against the batch\n"
"                  trace of the same rays to the image, and their ratio\n"
"  --baseline      instead: precise (one thread) against a lean double trace\n"
"                  of the same rays from surface 1, and the batch (every\n"
"                  thread) on the same rays field-major and in random field\n"
"                  order, on the designs (default: the Cassegrain, the\n"
"                  double Gauss); 5e4 rays a field (1e4 with --quick)\n"
"  --merit         instead: the merit function's evaluations per second (the\n"
"                  design's, or Zemax's default RMS spot one) on the designs\n"
"                  (default: every example), the optimizer's evaluation\n"
"  --view V        instead: the editor's view V (spot, fan, opd, wave, layout\n"
"                  or all) rebuilt after an edit, with its default sampling,\n"
"                  on the designs (default: the double Gauss); --repeat\n"
"                  edits (at least 25)\n"
"  -h, --help      show this help\n"
"\n"
"Throughput is in ray-surfaces per second: rays that reached the image times\n"
"(surfaces - 1), over the time of one batch trace of the set.  Each design\n"
"is traced with the precise and the classic method, on one thread and on\n"
"all, and the ratio precise/classic of the same run is printed; both trace\n"
"blocks of rays in vector registers, classic in double, precise in\n"
"double-double.  Rays are ordered field by field, as a spot diagram traces\n"
"them.  A set is made and\n"
"traced in blocks of about 131072 ray-surfaces, every surface of each ray\n"
"written, so memory does not grow with N.  Timings vary with the\n"
"machine's load; the bench never fails on a slow figure.  See sagitta(1).\n",
          f);
}

/* The option bench's switch reads itself: --view needs the editor. */
enum { OPT_VIEW = 1 };

/* ------------------------------------------------------------ spot mode */

/* One spot diagram of nray Vogel rays (every field, the primary
 * wavelength, about the chief ray) against sg_batch_trace of the same
 * pupil points, all in one call that keeps the image only: the analysis's
 * own cost (pupil points, blocks, sums) is the difference.  The two are
 * timed alternately so that a change in the machine's load falls on both. */
static int bench_spot(const bench_cfg *cfg, const char *path, cJSON *arr)
{
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    size_t nray = cfg->quick ? 100000 : 1000000, cur, k, nall;
    int rc, f, last, rep;
    double *ts = NULL, *tb = NULL, *ratio = NULL, la0 = -1.0, la1;
    sg_ray_in *rays = NULL;
    sg_ray_surface *rows = NULL;
    int *st = NULL;
    double (*pup)[2] = NULL;
    sg_spot_opts so;
    sg_diag d;
    stat3 a, b, r;

    rc = cli_load_design(path, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    nall = nray * (size_t)sys->nfield;
    pup = malloc(nray * sizeof *pup);
    rays = malloc(nall * sizeof *rays);
    rows = malloc(nall * sizeof *rows);
    st = malloc(nall * sizeof *st);
    ts = calloc((size_t)cfg->repeat, sizeof *ts);
    tb = calloc((size_t)cfg->repeat, sizeof *tb);
    ratio = calloc((size_t)cfg->repeat, sizeof *ratio);
    if (!pup || !rays || !rows || !st || !ts || !tb || !ratio) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    cur = 0;
    sg_pupil_fill(SG_PUPIL_VOGEL, (int)nray, &cur, pup, nray);
    for (f = 0; f < sys->nfield; f++) {
        double hx, hy;
        sg_field_normalized(sys, f, &hx, &hy);
        for (k = 0; k < nray; k++) {
            sg_ray_in *ri = &rays[(size_t)f * nray + k];
            ri->v[0] = hx;
            ri->v[1] = hy;
            ri->v[2] = pup[k][0];
            ri->v[3] = pup[k][1];
        }
    }
    memset(rows, 0, nall * sizeof *rows);
    memset(st, 0, nall * sizeof *st);
    sg_spot_opts_init(&so);
    so.pattern = SG_PUPIL_VOGEL;
    so.density = (int)nray;
    so.wave = sys->primary_wave;
    so.nthreads = cfg->threads;
    last = sys->nsurf - 1;
    la0 = load_average();
    for (rep = 0; rep < cfg->repeat; rep++) {
        sg_spot spot;
        sg_batch *bt;
        sg_trace_opts to;
        double t0;
        sg_diag_clear(&d);
        t0 = now_s(cfg->cpu_clock);
        rc = sg_spot_compute(sys, cat, &so, &spot, &d);
        ts[rep] = now_s(cfg->cpu_clock) - t0;
        if (rc != SG_OK)
            break;
        sg_spot_free(&spot);
        sg_trace_opts_init(&to);
        t0 = now_s(cfg->cpu_clock);
        bt = sg_batch_new(sys, cat, &to, cfg->threads, &d);
        rc = bt ? sg_batch_trace(bt, SG_RAYS_NORMALIZED, rays, nall, &last, 1, rows, st, &d)
                : (d.code ? d.code : SG_ENOMEM);
        sg_batch_free(bt);
        tb[rep] = now_s(cfg->cpu_clock) - t0;
        if (rc != SG_OK)
            break;
        ratio[rep] = ts[rep] / tb[rep];
    }
    if (rc != SG_OK) {
        cli_error("%s: %s", path, d.msg[0] ? d.msg : sg_strerror(rc));
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    la1 = load_average();
    a = stats(ts, cfg->repeat);
    b = stats(tb, cfg->repeat);
    r = stats(ratio, cfg->repeat);
    if (cfg->fmt == BENCH_TEXT) {
        char t[96];
        printf("%s\n  %s\n", path, safe_text(sys->title, t, sizeof t));
        printf("  spot diagram, %zu rays x %d fields, %d threads: %.4f s (min %.4f, max %.4f)\n",
               nray, sys->nfield, cfg->nthr_all, a.med, a.min, a.max);
        printf("  batch trace of the same rays to the image:       %.4f s (min %.4f, max %.4f)\n",
               b.med, b.min, b.max);
        printf("  spot / batch: %.3f (median of %d alternating pairs; min %.3f, max %.3f)\n",
               r.med, cfg->repeat, r.min, r.max);
        printf("  load: %.2f before, %.2f after (1-minute average); clock %s\n", la0, la1,
               cfg->cpu_clock ? "cpu" : "wall");
    } else {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "design", path);
        cJSON_AddNumberToObject(o, "rays_per_field", (double)nray);
        cJSON_AddNumberToObject(o, "fields", sys->nfield);
        cJSON_AddNumberToObject(o, "threads", cfg->nthr_all);
        cJSON_AddItemToObject(o, "spot_s", json_stat(&a));
        cJSON_AddItemToObject(o, "batch_s", json_stat(&b));
        cJSON_AddItemToObject(o, "ratio", json_stat(&r));
        cJSON_AddNumberToObject(o, "load_before", la0);
        cJSON_AddNumberToObject(o, "load_after", la1);
        cJSON_AddStringToObject(o, "clock", cfg->cpu_clock ? "cpu" : "wall");
        cJSON_AddItemToArray(arr, o);
    }
    rc = CLI_EXIT_OK;
done:
    free(pup);
    free(rays);
    free(rows);
    free(st);
    free(ts);
    free(tb);
    free(ratio);
    cli_design_free(cat, sys);
    return rc;
}

/* --------------------------------------------------------------- merit mode */

/* The merit function's evaluations per second: the design's own, or
 * Zemax's default one (RMS spot about the centroid, 3 rings, 6 arms) for a
 * design with none, evaluated --repeat times (at least 5) on the
 * optimizer's path (sg_merit_eval: the rays traced and every row). */
static int bench_merit(const bench_cfg *cfg, const char *path, cJSON *arr)
{
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    int rc, rep, n = cfg->repeat < 5 ? 5 : cfg->repeat, nrow = 0, own;
    double *t = NULL, merit = 0.0;
    sg_diag d;
    stat3 a;

    rc = cli_load_design(path, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    own = sys->merit.present;
    if (!own) {
        sys->merit.present = 1;
        sys->merit.has_default = 1;
        sys->merit.reference = SG_MERIT_CENTROID;
        sys->merit.rings = 3;
        sys->merit.arms = 6;
    }
    if (!(t = calloc((size_t)n, sizeof *t))) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    for (rep = 0; rep < n; rep++) {
        sg_merit_result mr;
        double t0;
        sg_diag_clear(&d);
        memset(&mr, 0, sizeof mr);
        t0 = now_s(cfg->cpu_clock);
        rc = sg_merit_eval(sys, cat, &mr, &d);
        t[rep] = now_s(cfg->cpu_clock) - t0;
        nrow = mr.nrow;
        merit = mr.merit;
        sg_merit_result_free(&mr);
        if (rc != SG_OK) {
            cli_error("%s: %s", path, d.msg[0] ? d.msg : sg_strerror(rc));
            rc = cli_exit_for(rc);
            goto done;
        }
    }
    a = stats(t, n);
    if (cfg->fmt == BENCH_TEXT) {
        char tt[96];
        printf("%s\n  %s\n", path, safe_text(sys->title, tt, sizeof tt));
        printf("  merit function: %s, %d rows, MF %.6g\n",
               own ? "the design's" : "default (RMS spot, centroid, 3 rings, 6 arms)", nrow,
               merit);
        printf("  %.6f s an evaluation (min %.6f, max %.6f): %.1f evaluations/s; clock %s\n",
               a.med, a.min, a.max, a.min > 0 ? 1.0 / a.min : 0.0,
               cfg->cpu_clock ? "cpu" : "wall");
    } else {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "design", path);
        cJSON_AddStringToObject(o, "merit", own ? "design" : "default");
        cJSON_AddNumberToObject(o, "rows", nrow);
        cJSON_AddNumberToObject(o, "value", merit);
        cJSON_AddItemToObject(o, "evaluation_s", json_stat(&a));
        cJSON_AddNumberToObject(o, "evaluations_per_s", a.min > 0 ? 1.0 / a.min : 0.0);
        cJSON_AddStringToObject(o, "clock", cfg->cpu_clock ? "cpu" : "wall");
        cJSON_AddItemToArray(arr, o);
    }
    rc = CLI_EXIT_OK;
done:
    free(t);
    cli_design_free(cat, sys);
    return rc;
}

/* ------------------------------------------------------------ baseline mode */

/* The same rays as in bench_spot's set, field-major (Vogel points in each
 * field), nray a field. */
static void field_major_rays(const sg_system *sys, size_t nray, double (*pup)[2],
                             sg_ray_in *rays)
{
    size_t cur = 0, k;
    int f;
    sg_pupil_fill(SG_PUPIL_VOGEL, (int)nray, &cur, pup, nray);
    for (f = 0; f < sys->nfield; f++) {
        double hx, hy;
        sg_field_normalized(sys, f, &hx, &hy);
        for (k = 0; k < nray; k++) {
            sg_ray_in *ri = &rays[(size_t)f * nray + k];
            memset(ri, 0, sizeof *ri);
            ri->v[0] = hx;
            ri->v[1] = hy;
            ri->v[2] = pup[k][0];
            ri->v[3] = pup[k][1];
        }
    }
}

/* Precise against two baselines on one design, each pair timed
 * alternately: (1) the lean double trace (lean.c) of the rays precise
 * traced, from their points on surface 1, one thread each: ray-surfaces
 * per second and their ratio, with the largest distance between the two
 * image points; (2) the batch trace on every thread of the same rays
 * field-major and in a shuffled order (random field order), with the
 * design's ray aiming, and their ratio. */
static int bench_baseline(const bench_cfg *cfg, const char *path, cJSON *arr)
{
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    size_t nray = cfg->quick ? 10000 : 50000, nall, k, nok = 0, lok = 0;
    int rc = CLI_EXIT_OK, erc = SG_OK, rep, ns, last;
    double *tp = NULL, *tl = NULL, *ts = NULL, *tr = NULL, *lin = NULL, *lrows = NULL;
    double (*pup)[2] = NULL, dmax = 0.0, scale = 0.0, la0, la1;
    sg_ray_in *rays = NULL, *shuf = NULL;
    sg_ray_surface *rows = NULL;
    int *st = NULL;
    sg_tracer *t = NULL;
    sg_batch *b1 = NULL, *ball = NULL;
    lean *L = NULL;
    sg_trace_opts to;
    sg_diag d;
    stat3 sp, sl, ss, sr;
    unsigned long long lcg = 35;

    rc = cli_load_design(path, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    ns = sys->nsurf;
    last = ns - 1;
    nall = nray * (size_t)(sys->nfield > 0 ? sys->nfield : 1);
    pup = malloc(nray * sizeof *pup);
    rays = malloc(nall * sizeof *rays);
    shuf = malloc(nall * sizeof *shuf);
    rows = malloc(nall * (size_t)ns * sizeof *rows);
    st = malloc(nall * sizeof *st);
    lin = malloc(nall * 6 * sizeof *lin);
    lrows = malloc(nall * (size_t)ns * LEAN_ROW * sizeof *lrows);
    tp = calloc((size_t)cfg->repeat, sizeof *tp);
    tl = calloc((size_t)cfg->repeat, sizeof *tl);
    ts = calloc((size_t)cfg->repeat, sizeof *ts);
    tr = calloc((size_t)cfg->repeat, sizeof *tr);
    if (!pup || !rays || !shuf || !rows || !st || !lin || !lrows || !tp || !tl || !ts || !tr) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    field_major_rays(sys, nray, pup, rays);
    memcpy(shuf, rays, nall * sizeof *rays);
    for (k = nall - 1; k > 0; k--) {
        size_t j;
        sg_ray_in x;
        lcg = lcg * 6364136223846793005ULL + 1442695040888963407ULL;
        j = (size_t)((lcg >> 33) % (k + 1));
        x = shuf[k];
        shuf[k] = shuf[j];
        shuf[j] = x;
    }
    memset(rows, 0xff, nall * (size_t)ns * sizeof *rows);
    memset(lrows, 0xff, nall * (size_t)ns * LEAN_ROW * sizeof *lrows);
    sg_trace_opts_init(&to);
    sg_diag_clear(&d);
    erc = sg_tracer_open(sys, cat, &to, &t, &d);
    b1 = erc == SG_OK ? sg_batch_new(sys, cat, &to, 1, &d) : NULL;
    ball = b1 ? sg_batch_new(sys, cat, &to, cfg->threads, &d) : NULL;
    if (!ball) {
        /* The batch's constructor has no code of its own to return. */
        if (erc == SG_OK)
            erc = d.code ? d.code : SG_ENOMEM;
        goto failed;
    }
    L = lean_new(sys, t);
    la0 = load_average();
    for (rep = 0; rep < cfg->repeat; rep++) {
        double t0 = now_s(1);
        erc = sg_batch_trace(b1, SG_RAYS_NORMALIZED, rays, nall, NULL, 0, rows, st, &d);
        tp[rep] = now_s(1) - t0;
        if (erc != SG_OK)
            goto failed;
        if (rep == 0) {
            /* The lean trace starts where precise met surface 1, with the
             * direction after it, on the rays precise brought to the image. */
            for (k = 0; k < nall; k++) {
                const sg_ray_surface *o = &rows[k * (size_t)ns + 1];
                if (st[k] != SG_OK)
                    continue;
                lin[6 * nok] = o->x;
                lin[6 * nok + 1] = o->y;
                lin[6 * nok + 2] = o->z;
                lin[6 * nok + 3] = o->l;
                lin[6 * nok + 4] = o->m;
                lin[6 * nok + 5] = o->n;
                nok++;
            }
        }
        if (L) {
            t0 = now_s(1);
            lok = lean_trace(L, lin, nok, lrows);
            tl[rep] = now_s(1) - t0;
        }
        t0 = now_s(1);
        erc = sg_batch_trace(ball, SG_RAYS_NORMALIZED, rays, nall, &last, 1, rows, st, &d);
        ts[rep] = now_s(1) - t0;
        if (erc != SG_OK)
            goto failed;
        t0 = now_s(1);
        erc = sg_batch_trace(ball, SG_RAYS_NORMALIZED, shuf, nall, &last, 1, rows, st, &d);
        tr[rep] = now_s(1) - t0;
        if (erc != SG_OK)
            goto failed;
    }
    la1 = load_average();
    if (L) {
        /* The lean image points against precise's (traced again, the rows
         * above hold the shuffled image rows). */
        size_t j = 0;
        erc = sg_batch_trace(b1, SG_RAYS_NORMALIZED, rays, nall, NULL, 0, rows, st, &d);
        if (erc != SG_OK)
            goto failed;
        for (k = 0; k < nall; k++) {
            const sg_ray_surface *o = &rows[k * (size_t)ns + (size_t)last];
            const double *q = &lrows[(j * (size_t)ns + (size_t)last) * LEAN_ROW];
            if (st[k] != SG_OK)
                continue;
            dmax = fmax(dmax, fmax(fabs(q[0] - o->x), fabs(q[1] - o->y)));
            scale = fmax(scale, fmax(fabs(o->x), fabs(o->y)));
            j++;
        }
    }
    sp = stats(tp, cfg->repeat);
    sl = stats(tl, cfg->repeat);
    ss = stats(ts, cfg->repeat);
    sr = stats(tr, cfg->repeat);
    {
        /* Ray-surfaces: precise from the launch through every surface;
         * lean from surface 1 on. */
        double wp = (double)nok * (double)(ns - 1), wl = (double)nok * (double)(ns - 2);
        double rp = sp.min > 0.0 ? wp / sp.min : 0.0, rl = L && sl.min > 0.0 ? wl / sl.min : 0.0;
        if (cfg->fmt == BENCH_TEXT) {
            char tt[96];
            printf("%s\n  %s\n", path, safe_text(sys->title, tt, sizeof tt));
            printf("  %zu rays (%zu reached the image), %d surfaces, ray aiming %s; CPU time, "
                   "fastest of %d\n", nall, nok, ns,
                   sys->aim == SG_AIM_REAL ? "real" : sys->aim == SG_AIM_OFF ? "off" : "paraxial",
                   cfg->repeat);
            printf("  precise, 1 thread:      %8.2f M ray-surfaces/s (%.4f s)\n", rp * 1e-6,
                   sp.min);
            if (L)
                printf("  lean double, 1 thread:  %8.2f M ray-surfaces/s (%.4f s), lean/precise "
                       "%.2f; image points within %.3g of precise's (largest |x|, |y| %.3g)\n",
                       rl * 1e-6, sl.min, rp > 0.0 ? rl / rp : 0.0, dmax, scale);
            else
                printf("  lean double: not measured (a surface it does not trace)\n");
            printf("  batch, %d threads, image only: field-major %.4f s, random field order "
                   "%.4f s, random/sorted %.2f\n", cfg->nthr_all, ss.min, sr.min,
                   ss.min > 0.0 ? sr.min / ss.min : 0.0);
            printf("  load: %.2f before, %.2f after (1-minute average)\n", la0, la1);
        } else {
            cJSON *o = cJSON_CreateObject(), *p;
            cJSON_AddStringToObject(o, "design", path);
            cJSON_AddNumberToObject(o, "rays", (double)nall);
            cJSON_AddNumberToObject(o, "rays_reached_image", (double)nok);
            cJSON_AddNumberToObject(o, "surfaces", ns);
            cJSON_AddStringToObject(o, "clock", "cpu");
            p = cJSON_AddObjectToObject(o, "precise_one_thread");
            cJSON_AddNumberToObject(p, "ray_surfaces_per_second", rp);
            cJSON_AddItemToObject(p, "seconds", json_stat(&sp));
            if (L) {
                p = cJSON_AddObjectToObject(o, "lean_double_one_thread");
                cJSON_AddNumberToObject(p, "ray_surfaces_per_second", rl);
                cJSON_AddItemToObject(p, "seconds", json_stat(&sl));
                cJSON_AddNumberToObject(p, "rays_reached_image", (double)lok);
                cJSON_AddNumberToObject(p, "image_max_difference", dmax);
                cJSON_AddNumberToObject(p, "image_largest_coordinate", scale);
                cJSON_AddNumberToObject(o, "lean_over_precise", rp > 0.0 ? rl / rp : 0.0);
            }
            p = cJSON_AddObjectToObject(o, "random_field_order");
            cJSON_AddNumberToObject(p, "threads", cfg->nthr_all);
            cJSON_AddItemToObject(p, "field_major_s", json_stat(&ss));
            cJSON_AddItemToObject(p, "random_order_s", json_stat(&sr));
            cJSON_AddNumberToObject(p, "ratio_fastest", ss.min > 0.0 ? sr.min / ss.min : 0.0);
            cJSON_AddNumberToObject(o, "load_before", la0);
            cJSON_AddNumberToObject(o, "load_after", la1);
            cJSON_AddItemToArray(arr, o);
        }
    }
    rc = CLI_EXIT_OK;
    goto done;
failed:
    cli_error("%s: %s", path, d.msg[0] ? d.msg : sg_strerror(erc));
    rc = cli_exit_for(erc);
    if (rc == CLI_EXIT_OK)
        rc = CLI_EXIT_INTERNAL;
done:
    lean_free(L);
    sg_batch_free(b1);
    sg_batch_free(ball);
    sg_tracer_free(t);
    free(pup);
    free(rays);
    free(shuf);
    free(rows);
    free(st);
    free(lin);
    free(lrows);
    free(tp);
    free(tl);
    free(ts);
    free(tr);
    cli_design_free(cat, sys);
    return rc;
}

static void bench_design(const bench_cfg *cfg, const char *path, design_res *r)
{
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    size_t s;

    memset(r, 0, sizeof *r);
    r->path = path;
    r->load_rc = cli_load_design(path, &cat, &sys);
    if (r->load_rc != CLI_EXIT_OK)
        return;
    snprintf(r->title, sizeof r->title, "%s", sys->title);
    r->nsurf = sys->nsurf;
    r->nfield = sys->nfield;
    r->aim = (int)sys->aim;
    /* A design the tracer refuses (say, ray aiming that cannot reach the
     * stop) is reported once, not once per measurement. */
    for (s = 0; s < NMETHOD + 1; s++) {
        sg_trace_opts o;
        sg_tracer *t;
        sg_diag d;
        sg_trace_opts_init(&o);
        o.method = s < NMETHOD ? methods[s] : SG_METHOD_MPFR;
        sg_diag_clear(&d);
        r->trace_rc = sg_tracer_open(sys, cat, &o, &t, &d);
        if (r->trace_rc != SG_OK) {
            snprintf(r->trace_msg, sizeof r->trace_msg, "%s method: %s",
                     sg_method_name(o.method), d.msg[0] ? d.msg : sg_strerror(r->trace_rc));
            cli_design_free(cat, sys);
            return;
        }
        sg_tracer_free(t);
    }
    r->nsizes = cfg->nsizes;
    for (s = 0; s < cfg->nsizes; s++) {
        r->sz[s].nray = cfg->sizes[s];
        progress(cfg, path, "rays", cfg->sizes[s]);
        bench_size(cfg, sys, cat, &r->sz[s]);
    }
    progress(cfg, path, "single rays and recomputes", 0);
    bench_mpfr_ray(cfg, sys, cat, &r->mpfr_ray);
    bench_recompute(cfg, sys, cat, 0, &r->recompute);
    bench_recompute(cfg, sys, cat, 1, &r->recompute_digits);
    cli_design_free(cat, sys);
    /* A design that loads but cannot be traced is a failure of the design,
     * like in "sagitta trace"; running out of memory for the largest ray
     * set only leaves that size out. */
    for (s = 0; s < r->nsizes; s++) {
        int m, h;
        for (m = 0; m < NMETHOD; m++)
            for (h = 0; h < NTHR; h++)
                if (!r->trace_rc && r->sz[s].c[m][h].rc != SG_OK)
                    r->trace_rc = r->sz[s].c[m][h].rc;
    }
    if (!r->trace_rc)
        r->trace_rc = r->mpfr_ray.rc ? r->mpfr_ray.rc
                    : r->recompute.rc ? r->recompute.rc : r->recompute_digits.rc;
}

/* ------------------------------------------------------------ view mode */

#ifdef SG_HAVE_EDITOR
/* The editor's view rebuilt after an edit, as the editor does it
 * (ui/editor/view.c, its default sampling, precise, one thread): each
 * sample makes a real edit (surface 1's radius, or its thickness when
 * flat, scaled by 1 + 1e-9 and back in turn), then times edview_update.
 * The figure is built, not drawn; drawing is the terminal's. */
static int bench_view(const bench_cfg *cfg, const char *path, int kind, int first, cJSON *arr)
{
    int n = cfg->repeat > SHORT_MIN_SAMPLES ? cfg->repeat : SHORT_MIN_SAMPLES, i, rc, s1;
    double *ms = calloc((size_t)n, sizeof *ms), la0, la1, *val;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_trace_opts o;
    edview v;
    stat3 st;

    if (!ms) {
        cli_error("out of memory");
        return CLI_EXIT_INTERNAL;
    }
    rc = cli_load_design(path, &cat, &sys);
    if (rc != CLI_EXIT_OK) {
        free(ms);
        return rc;
    }
    s1 = sys->nsurf > 2 ? 1 : 0;
    val = isfinite(sys->surf[s1].radius) && sys->surf[s1].radius != 0.0
              ? &sys->surf[s1].radius
              : &sys->surf[s1].thickness;
    sg_trace_opts_init(&o);
    edview_init(&v);
    v.kind = kind;
    la0 = load_average();
    /* One build first, so the samples see a warm cache, as edits after
     * the first do. */
    rc = edview_update(&v, sys, 1, cat, &o, sys->nfield - 1);
    for (i = 0; i < n && rc == SG_OK; i++) {
        double t0;
        *val *= i % 2 ? 1.0 / (1.0 + 1e-9) : 1.0 + 1e-9;
        t0 = now_s(cfg->cpu_clock);
        rc = edview_update(&v, sys, (unsigned long)i + 2, cat, &o, sys->nfield - 1);
        ms[i] = 1e3 * (now_s(cfg->cpu_clock) - t0);
    }
    la1 = load_average();
    if (rc != SG_OK) {
        cli_error("%s: view %s: %s", path, view_name(kind), v.msg);
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    st = stats(ms, n);
    if (cfg->fmt == BENCH_TEXT) {
        char t[96];
        if (first)
            printf("%s\n  %s\n", path, safe_text(sys->title, t, sizeof t));
        printf("  view %-7s rebuilt after an edit: median %.3f ms (min %.3f, max %.3f; "
               "%d edits; load %.2f before, %.2f after)\n",
               view_name(kind), st.med, st.min, st.max, n, la0, la1);
    } else {
        cJSON *jo = cJSON_CreateObject();
        cJSON_AddStringToObject(jo, "design", path);
        cJSON_AddStringToObject(jo, "view", view_name(kind));
        cJSON_AddNumberToObject(jo, "edits", n);
        cJSON_AddItemToObject(jo, "ms", json_stat(&st));
        cJSON_AddNumberToObject(jo, "load_before", la0);
        cJSON_AddNumberToObject(jo, "load_after", la1);
        cJSON_AddStringToObject(jo, "clock", cfg->cpu_clock ? "cpu" : "wall");
        cJSON_AddItemToArray(arr, jo);
    }
    rc = CLI_EXIT_OK;
done:
    edview_free(&v);
    free(ms);
    cli_design_free(cat, sys);
    return rc;
}
#endif

/* Runs a mode's fn on each design, its JSON rows under key (text: fn
 * prints); the exit status is the worst of the designs' and the output's. */
static int each_design(const bench_cfg *cfg, const char **designs, size_t ndesign,
                       const char *key, int (*fn)(const bench_cfg *, const char *, cJSON *))
{
    cJSON *root = NULL, *arr = NULL;
    size_t k;
    int rc, worst = CLI_EXIT_OK;
    if (cfg->fmt == BENCH_JSON) {
        root = cJSON_CreateObject();
        arr = root ? cJSON_AddArrayToObject(root, key) : NULL;
        if (!arr) {
            cJSON_Delete(root);
            cli_error("out of memory");
            return CLI_EXIT_INTERNAL;
        }
    }
    for (k = 0; k < ndesign; k++) {
        rc = fn(cfg, designs[k], arr);
        if (rc > worst)
            worst = rc;
    }
    if (root) {
        char *txt = cJSON_Print(root);
        if (txt)
            puts(txt);
        free(txt);
        cJSON_Delete(root);
    }
    rc = cli_close_output(stdout, NULL);
    return rc == CLI_EXIT_OK ? worst : rc;
}

int cmd_bench(int argc, char **argv)
{
    cli_iter it;
    const char *val;
    const char **designs = NULL;
    char **examples = NULL;
    size_t ndesign = 0, nex = 0, k;
    int id, rc = CLI_EXIT_OK, worst = CLI_EXIT_OK, nrays = 0, spot_mode = 0, view_kind = -1;
    int base_mode = 0, merit_mode = 0;
    bench_cfg cfg;
    design_res *res = NULL;
    cJSON *root = NULL, *arr = NULL;
    double load0;

    memset(&cfg, 0, sizeof cfg);
    cfg.repeat = 5;
    designs = calloc((size_t)(argc > 0 ? argc : 1), sizeof *designs);
    if (!designs) {
        cli_error("out of memory");
        return CLI_EXIT_INTERNAL;
    }
    {
        int fmt = REPORT_TEXT;
        /* Its table: the rows with a variable are stored as they are read. */
        const cli_opt bench_opts[] = {
            CLI_OPT_HELP,
            CLI_OPT_FORMAT(fmt),
            CLI_OPT_INT("--repeat", 0, cfg.repeat, 1, 1000),
            CLI_OPT_FLAG("--quick", 0, cfg.quick),
            CLI_OPT_INT("--threads", 0, cfg.threads, 0, 256),
            CLI_OPT_INT("--rays", 0, nrays, 1, 1000000000),
            CLI_OPT_FLAG("--spot", 0, spot_mode),
            CLI_OPT_FLAG("--baseline", 0, base_mode),
            CLI_OPT_FLAG("--merit", 0, merit_mode),
            CLI_ID("--view", 0, 1, OPT_VIEW),
            CLI_OPT_WORD("--clock", cfg.cpu_clock, "wall|cpu", NULL),
            CLI_OPT_INT("--edit-surface", 0, cfg.edit_surf, 1, 1000000),
            CLI_END
        };
        cli_iter_init(&it, "bench", argc, argv);
        while ((id = cli_next_opt(&it, bench_opts, &val)) != -1) {
            switch (id) {
            case 0:
                designs[ndesign++] = val;
                break;
            case CLI_HELP:
                bench_help(stdout);
                free(designs);
                return CLI_EXIT_OK;
            case OPT_VIEW:
#ifdef SG_HAVE_EDITOR
                view_kind = strcmp(val, "all") == 0 ? VIEW_COUNT : view_parse(val);
                if (view_kind <= VIEW_OFF) {
                    free(designs);
                    return cli_usage_error("bench", "--view: expected spot, fan, opd, wave, "
                                                    "layout or all, got \"%s\"", val);
                }
                break;
#else
                free(designs);
                return cli_usage_error("bench", "--view: this build has no editor");
#endif
            default:
                free(designs);
                return -id;
            }
        }
        cfg.fmt = fmt == REPORT_JSON ? BENCH_JSON : BENCH_TEXT;
    }

#ifdef SG_HAVE_EDITOR
    if (view_kind > VIEW_OFF) {
        static char dg[4096];
        cJSON *varr = NULL;
        int kind;
        if (ndesign == 0) {
            example_path("double_gauss.json", dg, sizeof dg);
            designs[ndesign++] = dg;
        }
        if (cfg.fmt == BENCH_JSON) {
            root = cJSON_CreateObject();
            varr = root ? cJSON_AddArrayToObject(root, "views") : NULL;
            if (!varr) {
                cli_error("out of memory");
                rc = CLI_EXIT_INTERNAL;
                goto done;
            }
        } else {
            printf("build:   %s; one thread, as the editor; figures built, not drawn\n"
                   "clock:   %s\n",
                   build_type(), cfg.cpu_clock ? "cpu" : "wall");
        }
        for (k = 0; k < ndesign; k++)
            for (kind = VIEW_LAYOUT; kind < VIEW_COUNT; kind++) {
                if (view_kind != VIEW_COUNT && kind != view_kind)
                    continue;
                rc = bench_view(&cfg, designs[k], kind,
                                kind == VIEW_LAYOUT || kind == view_kind, varr);
                if (rc > worst)
                    worst = rc;
            }
        if (root) {
            char *txt = cJSON_Print(root);
            if (txt)
                puts(txt);
            free(txt);
        }
        rc = cli_close_output(stdout, NULL);
        if (rc == CLI_EXIT_OK)
            rc = worst;
        goto done;
    }
#endif
    if (base_mode) {
        static char cass[4096], dg[4096];
        cfg.cores = count_cores();
        cfg.nthr_all = cfg.threads > 0 ? cfg.threads : cfg.cores;
        if (ndesign == 0) {
            example_path("cassegrain.json", cass, sizeof cass);
            example_path("double_gauss.json", dg, sizeof dg);
            designs[ndesign++] = cass;
            designs[ndesign++] = dg;
        }
        rc = each_design(&cfg, designs, ndesign, "baseline", bench_baseline);
        goto done;
    }
    if (merit_mode) {
        if (ndesign == 0) {
            rc = find_examples(&examples, &nex);
            if (rc != CLI_EXIT_OK)
                goto done;
            for (k = 0; k < nex; k++)
                designs[ndesign++] = examples[k];
        }
        rc = each_design(&cfg, designs, ndesign, "merit", bench_merit);
        goto done;
    }
    if (spot_mode) {
        static char cass[4096];
        cfg.cores = count_cores();
        cfg.nthr_all = cfg.threads > 0 ? cfg.threads : cfg.cores;
        if (ndesign == 0) {
            example_path("cassegrain.json", cass, sizeof cass);
            designs[ndesign++] = cass;
        }
        rc = each_design(&cfg, designs, ndesign, "spot", bench_spot);
        goto done;
    }
    if (ndesign == 0) {
        rc = find_examples(&examples, &nex);
        if (rc != CLI_EXIT_OK) {
            free(designs);
            return rc;
        }
        free(designs);
        designs = (const char **)examples;
        ndesign = nex;
    }

    cfg.cores = count_cores();
    /* sg_trace_batch caps its threads at 256, so the label does too. */
    cfg.nthr_all = cfg.threads > 0 ? cfg.threads : cfg.cores;
    if (cfg.nthr_all > 256)
        cfg.nthr_all = 256;
    cfg.progress = cfg.fmt == BENCH_JSON && isatty(2);
    if (nrays > 0) {
        cfg.sizes[0] = (size_t)nrays;
        cfg.nsizes = 1;
    } else if (cfg.quick) {
        cfg.sizes[0] = 1000;
        cfg.sizes[1] = 10000;
        cfg.nsizes = 2;
    } else {
        cfg.sizes[0] = 1000;
        cfg.sizes[1] = 100000;
        cfg.sizes[2] = 1000000;
        cfg.nsizes = 3;
    }

    res = calloc(ndesign, sizeof *res);
    if (!res) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    load0 = load_average();
    if (cfg.fmt == BENCH_TEXT) {
        text_header(stdout, &cfg);
        fflush(stdout);
    }
    for (k = 0; k < ndesign; k++) {
        bench_design(&cfg, designs[k], &res[k]);
        if (res[k].load_rc > worst)
            worst = res[k].load_rc;
        if (res[k].trace_rc != SG_OK) {
            int st = res[k].trace_rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
            if (st > worst)
                worst = st;
        }
        if (cfg.fmt == BENCH_TEXT)
            text_design(stdout, &cfg, &res[k]);
    }
    if (cfg.fmt == BENCH_JSON) {
        char *txt;
        root = json_top(&cfg, load0, load_average());
        arr = root ? cJSON_AddArrayToObject(root, "designs") : NULL;
        for (k = 0; arr && k < ndesign; k++)
            cJSON_AddItemToArray(arr, json_design(&cfg, &res[k]));
        txt = arr ? cJSON_Print(root) : NULL;
        if (!txt) {
            cli_error("out of memory");
            rc = CLI_EXIT_INTERNAL;
            goto done;
        }
        fputs(txt, stdout);
        fputc('\n', stdout);
        free(txt);
    } else {
        double la = load_average();
        if (la >= 0.0)
            printf("\nload: %.2f (1-minute average after the runs)\n", la);
    }
    rc = cli_close_output(stdout, NULL);
    /* A design that did not load or trace is reported in the figures and
     * in the exit status; a slow figure never is. */
    if (rc == CLI_EXIT_OK)
        rc = worst;
done:
    cJSON_Delete(root);
    free(res);
    if ((void *)designs != (void *)examples)
        free(designs);
    for (k = 0; k < nex; k++)
        free(examples[k]);
    free(examples);
    return rc;
}
