/*
 * batch.c - many rays on every core.
 *
 * Each thread owns a tracer (tracers carry per-ray scratch and caches) and
 * takes runs of consecutive rays from a shared counter until none are left,
 * so a thread slowed by the machine's other load takes fewer of them.
 * Results land in the caller's arrays (or, for a selection of surfaces,
 * in a thread's scratch first) and equal the single-ray
 * calls bit for bit, whichever thread traced them.
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "trace_int.h"
#include "vdd.h"

_Static_assert(SG_VL <= SG_BATCH_LANES, "a thread's scratch holds SG_BATCH_LANES rays");

typedef struct job {
    sg_tracer *t;
    sg_ray_kind kind;
    const sg_ray_in *rays;
    size_t first, count; /* the run being traced */
    size_t nray, chunk;
    atomic_size_t *next; /* the first ray no thread has taken */
    int nsurf;
    sg_ray_surface *out;
    int *status;
    /* With a selection, rays are traced into scratch (SG_VL full rows of
     * nsurf surfaces) and only surfaces sel[0..nsel-1] are copied out. */
    const int *sel;
    int nsel;
    sg_ray_surface *scratch;
} job;

/* Where lane k's trace of ray r writes its nsurf rows. */
static sg_ray_surface *rows(const job *j, size_t r, int k)
{
    if (j->sel)
        return j->scratch + (size_t)k * (size_t)j->nsurf;
    return j->out + r * (size_t)j->nsurf;
}

/* Copies the chosen surfaces of ray r from lane k's scratch. */
static void keep(const job *j, size_t r, int k)
{
    const sg_ray_surface *s;
    sg_ray_surface *o;
    int i;
    if (!j->sel)
        return;
    s = j->scratch + (size_t)k * (size_t)j->nsurf;
    o = j->out + r * (size_t)j->nsel;
    for (i = 0; i < j->nsel; i++)
        o[i] = s[j->sel[i]];
}

/* One ray by the tracer's method, for methods without a vector trace. */
static void run_one_by_one(job *j)
{
    size_t r;
    for (r = j->first; r < j->first + j->count; r++) {
        const double *v = j->rays[r].v;
        sg_ray_surface *o = rows(j, r, 0);
        int rc;
        vd_leave();
        if (j->kind == SG_RAYS_NORMALIZED)
            rc = sg_trace_normalized(j->t, v[0], v[1], v[2], v[3], o);
        else
            rc = sg_trace_start(j->t, v, v + 3, o);
        keep(j, r, 0);
        if (j->status)
            j->status[r] = rc;
    }
}

static int finite4(const double *v)
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]) && isfinite(v[3]);
}

/* Whether the rows after the object row that are marked OK hold only
 * finite numbers, SG_VL of a row's thirteen at a time (x .. opl_error_bound lie first and
 * in order).  The rows are summed lane by lane and the sum tested once:
 * an infinity or NaN in any row makes its lane of the sum an infinity or
 * NaN, and 0 * v is NaN exactly for those.  A sum of finite numbers that
 * overflows fails too, which only sends the ray to sg_guard_rows, whose
 * exact test of every row decides; so the common, finite ray costs a load
 * and an add per vector of a row. */
_Static_assert(offsetof(sg_ray_surface, opl_error_bound) == 12 * sizeof(double),
               "a row's thirteen doubles come first, in order");
static int rows_finite(const sg_ray_surface *out, int n)
{
    vd acc = vd_set(0.0);
    int i, off;
    for (i = 1; i < n && out[i].status == SG_OK; i++) {
        const char *row = (const char *)&out[i];
        for (off = 0; off < 13; off += SG_VL) {
            vd v;
            int at = off + SG_VL <= 13 ? off : 13 - SG_VL;
            memcpy(&v, row + (size_t)at * sizeof(double), sizeof v);
            acc += v;
        }
    }
    acc = acc * 0.0;
    return !vm_any((vm)(acc != acc));
}

/* The object row: finite, but for the infinite point of an object at
 * infinity, which must still not be NaN. */
static int row0_finite(const sg_tracer *t, const sg_ray_surface *o)
{
    double s = 0.0 * o->l + 0.0 * o->m + 0.0 * o->n + 0.0 * o->residual +
               0.0 * o->error_bound + 0.0 * o->dir_error_bound + 0.0 * o->path +
               0.0 * o->opl + 0.0 * o->opl_lo + 0.0 * o->opl_error_bound;
    if (t->ln.obj_inf)
        return s == s && o->x == o->x && o->y == o->y && o->z == o->z;
    s += 0.0 * o->x + 0.0 * o->y + 0.0 * o->z;
    return s == s;
}

/* A vector trace's lane k done with ray r: the guard on rows that claim
 * OK (the cheap finiteness test first), the chosen surfaces kept, the
 * status stored. */
static void finish(const job *j, const sg_tracer *t, sg_ray_surface *o, size_t r, int k, int rc)
{
    if (o[0].status == SG_OK && !(row0_finite(t, o) && rows_finite(o, t->n)))
        rc = sg_guard_rows(t, o, rc);
    keep(j, r, k);
    if (j->status)
        j->status[r] = rc;
}

/* Rays of one field waiting for a full block of the precise trace. */
typedef struct fgroup {
    double hx, hy;
    int n;
    size_t idx[SG_VL];
} fgroup;

/* Open groups a thread keeps: rays of up to this many fields wait for
 * their blocks to fill, so a run of rays in any field order is traced in
 * full blocks. */
enum { NGROUP = 8 };

static int same_field(const double *v, const fgroup *g)
{
    return memcmp(&v[0], &g->hx, sizeof g->hx) == 0 && memcmp(&v[1], &g->hy, sizeof g->hy) == 0;
}

/* The precise method on the normalized rays of group g: launched (and
 * aimed) together, then traced together in vector form. */
static void precise_group(job *j, fgroup *g)
{
    sg_tracer *t = j->t;
    sg_vray vs;
    vd p0;
    double pupil[SG_VL][2];
    sg_ray_surface *o[SG_VL];
    int rc[SG_VL], start[SG_VL], nl = g->n, k;
    for (k = 0; k < nl; k++) {
        pupil[k][0] = j->rays[g->idx[k]].v[2];
        pupil[k][1] = j->rays[g->idx[k]].v[3];
        o[k] = rows(j, g->idx[k], k);
    }
    sg_launch_precise_block(t, g->hx, g->hy, (const double(*)[2])pupil, nl, o, &vs, &p0, start,
                            rc);
    for (k = nl; k < SG_VL; k++)
        o[k] = o[0];
    sg_precise_block(t, &vs, p0, o, nl, start, t->n - 1, rc);
    for (k = 0; k < nl; k++)
        finish(j, t, o[k], g->idx[k], k, rc[k]);
    g->n = 0;
}

/* The precise method on normalized rays: each ray joins the open group of
 * its field (its Hx and Hy bit for bit), and a group is traced when it
 * holds SG_VL rays, when its place is needed for another field, or at the
 * end of the run.  A ray's result does not depend on the rays beside it,
 * so this order gives every ray the bits of the single-ray call. */
static void run_precise_normalized(job *j)
{
    fgroup g[NGROUP];
    size_t r, end = j->first + j->count;
    int ng = 0, i;
    for (r = j->first; r < end; r++) {
        const double *v = j->rays[r].v;
        if (!finite4(v)) {
            /* The single-ray call reports a bad ray. */
            sg_ray_surface *out = rows(j, r, 0);
            int prc = sg_trace_normalized(j->t, v[0], v[1], v[2], v[3], out);
            keep(j, r, 0);
            if (j->status)
                j->status[r] = prc;
            continue;
        }
        for (i = 0; i < ng && !same_field(v, &g[i]); i++)
            ;
        if (i == ng) {
            if (ng < NGROUP) {
                ng++;
            } else {
                /* The fullest group is traced to make room. */
                int k;
                for (i = 0, k = 1; k < NGROUP; k++)
                    if (g[k].n > g[i].n)
                        i = k;
                precise_group(j, &g[i]);
            }
            g[i].hx = v[0];
            g[i].hy = v[1];
            g[i].n = 0;
        }
        g[i].idx[g[i].n++] = r;
        if (g[i].n == SG_VL)
            precise_group(j, &g[i]);
    }
    for (i = 0; i < ng; i++)
        if (g[i].n > 0)
            precise_group(j, &g[i]);
}

/* The precise method: up to SG_VL rays (of one field, when normalized)
 * are launched (and aimed) together, then traced together in vector
 * form. */
static void run_precise(job *j)
{
    sg_tracer *t = j->t;
    sg_vray vs;
    vd p0;
    sg_ray_surface *o[SG_VL];
    size_t idx[SG_VL], r = j->first, end = j->first + j->count;
    int rc[SG_VL], start[SG_VL], nl, k;
    if (j->kind == SG_RAYS_NORMALIZED) {
        run_precise_normalized(j);
        return;
    }
    while (r < end) {
        nl = 0;
        for (; r < end && nl < SG_VL; r++) {
            sg_ray_surface *out = rows(j, r, nl);
            sg_pray pr;
            int prc = sg_start_precise_prep(t, j->rays[r].v, j->rays[r].v + 3, out, &pr);
            if (prc != SG_OK) {
                keep(j, r, nl);
                if (j->status)
                    j->status[r] = prc;
                continue;
            }
            sg_vray_put(&vs, nl, &pr);
            p0[nl] = 0.0;
            start[nl] = 1;
            o[nl] = out;
            idx[nl++] = r;
        }
        if (nl == 0)
            continue;
        /* Idle lanes repeat lane 0, so they compute on real numbers. */
        for (k = nl; k < SG_VL; k++) {
            sg_pray pr;
            sg_vray_get(&vs, 0, &pr);
            sg_vray_put(&vs, k, &pr);
            p0[k] = p0[0];
        }
        for (k = nl; k < SG_VL; k++)
            o[k] = o[0];
        sg_precise_block(t, &vs, p0, o, nl, start, t->n - 1, rc);
        for (k = 0; k < nl; k++)
            finish(j, t, o[k], idx[k], k, rc[k]);
    }
}

/* The classic method: up to SG_VL consecutive rays are launched (and
 * aimed) one by one, as the single-ray call launches them, then traced
 * together by the vector kernel. */
static void run_classic(job *j)
{
    sg_tracer *t = j->t;
    double S[SG_VL][3], D[SG_VL][3], off[SG_VL];
    sg_ray_surface *o[SG_VL];
    size_t idx[SG_VL], r = j->first, end = j->first + j->count;
    int rc[SG_VL], inf[SG_VL], nl, k;
    while (r < end) {
        nl = 0;
        for (; r < end && nl < SG_VL; r++) {
            const double *v = j->rays[r].v;
            sg_ray_surface *out = rows(j, r, nl);
            int prc;
            inf[nl] = 0;
            if (j->kind == SG_RAYS_START_DIR) {
                prc = sg_start_classic_prep(t, v, v + 3, out);
                for (k = 0; k < 3; k++)
                    S[nl][k] = v[k];
                sg_dir_scale(v + 3, D[nl]);
            } else if (!finite4(v)) {
                /* The single-ray call reports a bad ray. */
                prc = sg_trace_normalized(t, v[0], v[1], v[2], v[3], out);
            } else {
                double px, py;
                sg_field_vignette(t->sys, v[0], v[1], v[2], v[3], &px, &py);
                prc = sg_launch_classic_prep(t, v[0], v[1], px, py, out, S[nl], D[nl], &off[nl],
                                             &inf[nl]);
                if (prc != SG_OK)
                    prc = sg_guard_rows(t, out, prc);
            }
            if (prc != SG_OK) {
                keep(j, r, nl);
                if (j->status)
                    j->status[r] = prc;
                continue;
            }
            o[nl] = out;
            idx[nl++] = r;
        }
        if (nl == 0)
            continue;
        sg_classic_block(t, (const double(*)[3])S, (const double(*)[3])D, o, nl, t->n - 1, rc);
        for (k = 0; k < nl; k++) {
            if (inf[k])
                sg_launch_classic_path(t, off[k], o[k]);
            finish(j, t, o[k], idx[k], k, rc[k]);
        }
    }
}

static void run_job(job *j)
{
    for (;;) {
        size_t first = atomic_fetch_add(j->next, j->chunk);
        if (first >= j->nray)
            break;
        j->first = first;
        j->count = j->nray - first < j->chunk ? j->nray - first : j->chunk;
        if (j->t->o.method == SG_METHOD_PRECISE)
            run_precise(j);
        else if (j->t->o.method == SG_METHOD_CLASSIC)
            run_classic(j);
        else
            run_one_by_one(j);
    }
}

static void *thread_main(void *arg)
{
    run_job(arg);
    /* MPFR caches constants such as pi per thread; a worker frees its own. */
    mpfr_free_cache2(MPFR_FREE_LOCAL_CACHE);
    return NULL;
}

int sg_batch_run(sg_tracer *const *t, int nt, sg_ray_kind kind, const sg_ray_in *rays,
                 size_t nray, const int *sel, int nsel, sg_ray_surface *scratch,
                 sg_ray_surface *out, int *status)
{
    job *jobs;
    pthread_t *tid;
    atomic_size_t next;
    size_t chunk;
    int k, started = 0;
    if (nray == 0)
        return SG_OK;
    /* Runs of about an eighth of a thread's share, from 64 to 4096 rays:
     * long enough that taking one costs nothing, short enough that the
     * threads finish close together. */
    chunk = nray / (8 * (size_t)nt);
    chunk = chunk < 64 ? 64 : chunk > 4096 ? 4096 : chunk;
    if ((size_t)nt > (nray + chunk - 1) / chunk)
        nt = (int)((nray + chunk - 1) / chunk);
    jobs = calloc((size_t)nt, sizeof *jobs);
    tid = calloc((size_t)nt, sizeof *tid);
    if (!jobs || !tid) {
        free(jobs);
        free(tid);
        return SG_ENOMEM;
    }
    atomic_init(&next, 0);
    for (k = 0; k < nt; k++) {
        jobs[k].t = t[k];
        jobs[k].kind = kind;
        jobs[k].rays = rays;
        jobs[k].nray = nray;
        jobs[k].chunk = chunk;
        jobs[k].next = &next;
        jobs[k].nsurf = t[k]->n;
        jobs[k].out = out;
        jobs[k].status = status;
        jobs[k].sel = sel;
        jobs[k].nsel = nsel;
        if (sel)
            jobs[k].scratch = scratch + (size_t)k * SG_BATCH_LANES * (size_t)t[k]->n;
    }
    /* The calling thread works beside the others. */
    for (k = 0; k < nt - 1; k++) {
        if (pthread_create(&tid[k], NULL, thread_main, &jobs[k]) != 0)
            break;
        started++;
    }
    for (k = started; k < nt; k++)
        run_job(&jobs[k]);
    for (k = 0; k < started; k++)
        pthread_join(tid[k], NULL);
    free(jobs);
    free(tid);
    return SG_OK;
}
