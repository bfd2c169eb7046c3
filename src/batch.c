/*
 * batch.c - many rays on every core.
 *
 * Each thread owns a tracer (tracers carry per-ray scratch and caches) and
 * a contiguous slice of the rays, so results land straight in the caller's
 * arrays and equal the single-ray calls bit for bit.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <unistd.h>

#include "trace_internal.h"
#include "vdd.h"

typedef struct job {
    sg_tracer *t;
    sg_ray_kind kind;
    const sg_ray_in *rays;
    size_t first, count;
    int nsurf;
    sg_ray_surface *out;
    int *status;
} job;

/* One ray by the tracer's method, for methods without a vector trace. */
static void run_scalar(job *j)
{
    size_t r;
    for (r = j->first; r < j->first + j->count; r++) {
        const double *v = j->rays[r].v;
        sg_ray_surface *o = j->out + r * (size_t)j->nsurf;
        int rc;
        if (j->kind == SG_RAYS_NORMALIZED)
            rc = sg_trace_normalized(j->t, v[0], v[1], v[2], v[3], o);
        else
            rc = sg_trace_start(j->t, v, v + 3, o);
        if (j->status)
            j->status[r] = rc;
    }
}

/* The precise method: each ray is launched alone (aiming is per ray), then
 * SG_VL launched rays at a time go through the vector trace. */
static void run_precise(job *j)
{
    sg_tracer *t = j->t;
    sg_pray st[SG_VL];
    double path0[SG_VL];
    sg_ray_surface *o[SG_VL];
    size_t idx[SG_VL], r, end = j->first + j->count;
    int rc[SG_VL], nl = 0, k;
    for (r = j->first; r < end; r++) {
        const double *v = j->rays[r].v;
        sg_ray_surface *out = j->out + r * (size_t)j->nsurf;
        int prc;
        if (j->kind == SG_RAYS_NORMALIZED) {
            if (!isfinite(v[0]) || !isfinite(v[1]) || !isfinite(v[2]) || !isfinite(v[3])) {
                sg_fail_rest(out, 0, t->n, SG_EINVAL);
                prc = SG_EINVAL;
            } else {
                prc = sg_launch_precise_prep(t, v[0], v[1], v[2], v[3], out, &st[nl],
                                             &path0[nl]);
            }
        } else {
            path0[nl] = 0.0;
            prc = sg_start_precise_prep(t, v, v + 3, out, &st[nl]);
        }
        if (prc != SG_OK) {
            if (j->status)
                j->status[r] = prc;
        } else {
            o[nl] = out;
            idx[nl++] = r;
        }
        if (nl == SG_VL || (r + 1 == end && nl > 0)) {
            sg_precise_run_block(t, st, path0, o, nl, t->n - 1, rc);
            for (k = 0; k < nl; k++)
                if (j->status)
                    j->status[idx[k]] = rc[k];
            nl = 0;
        }
    }
}

static void run_job(job *j)
{
    if (j->t->o.method == SG_METHOD_PRECISE)
        run_precise(j);
    else
        run_scalar(j);
}

static void *thread_main(void *arg)
{
    run_job(arg);
    /* MPFR caches constants such as pi per thread; a worker frees its own. */
    mpfr_free_cache2(MPFR_FREE_LOCAL_CACHE);
    return NULL;
}

int sg_trace_batch(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                   sg_ray_kind kind, const sg_ray_in *rays, size_t nray, int nthreads,
                   sg_ray_surface *out, int *status, sg_diag *d)
{
    job *jobs;
    pthread_t *tid;
    size_t per, done = 0;
    int k, nt, rc = SG_OK, started = 0;
    if (kind != SG_RAYS_NORMALIZED && kind != SG_RAYS_START_DIR)
        return sg_diag_set(d, SG_EINVAL, "batch: unknown ray kind %d", (int)kind);
    if (nray == 0)
        return SG_OK;
    if (!rays || !out)
        return sg_diag_set(d, SG_EINVAL, "batch: no ray or output array");
    nt = nthreads;
    if (nt <= 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        nt = c > 0 ? (int)c : 1;
    }
    if (nt > 256)
        nt = 256;
    if ((size_t)nt > nray)
        nt = (int)nray;
    jobs = calloc((size_t)nt, sizeof *jobs);
    tid = calloc((size_t)nt, sizeof *tid);
    if (!jobs || !tid) {
        free(jobs);
        free(tid);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    per = nray / (size_t)nt;
    for (k = 0; k < nt; k++) {
        jobs[k].t = sg_tracer_new(sys, cat, opts, d);
        if (!jobs[k].t) {
            rc = d && d->code ? d->code : SG_ENOMEM;
            goto out;
        }
        jobs[k].kind = kind;
        jobs[k].rays = rays;
        jobs[k].first = done;
        jobs[k].count = k == nt - 1 ? nray - done : per;
        jobs[k].nsurf = sys->nsurf;
        jobs[k].out = out;
        jobs[k].status = status;
        done += jobs[k].count;
    }
    /* The calling thread takes the last slice itself. */
    for (k = 0; k < nt - 1; k++) {
        if (pthread_create(&tid[k], NULL, thread_main, &jobs[k]) != 0)
            break;
        started++;
    }
    for (k = started; k < nt; k++)
        run_job(&jobs[k]);
    for (k = 0; k < started; k++)
        pthread_join(tid[k], NULL);
out:
    for (k = 0; k < nt; k++)
        sg_tracer_free(jobs[k].t);
    free(jobs);
    free(tid);
    return rc;
}
