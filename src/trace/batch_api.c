/*
 * batch_api.c - the batch as a kept object: tracers made once, then any
 * number of calls, each tracing its rays on every thread (batch.c) and
 * keeping every surface or a chosen few.
 */
#include <stdlib.h>
#include <unistd.h>

#include "trace_int.h"

struct sg_batch {
    int nt, nsurf;
    sg_tracer **t;
    sg_ray_surface *scratch; /* nt * SG_BATCH_LANES * nsurf rows, for a selection */
};

void sg_batch_free(sg_batch *b)
{
    int k;
    if (!b)
        return;
    /* Forks first: they share the first tracer's model. */
    for (k = b->nt - 1; b->t && k >= 0; k--)
        sg_tracer_free(b->t[k]);
    free(b->t);
    free(b->scratch);
    free(b);
}

int sg_batch_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                  int nthreads, sg_batch **out, sg_diag *d)
{
    sg_batch *b;
    int k, nt = nthreads;
    if (!out)
        return sg_diag_set(d, SG_EINVAL, "batch: nowhere to put it");
    *out = NULL;
    if (!sys)
        return sg_diag_set(d, SG_EINVAL, "batch: no system");
    if (nt <= 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        nt = c > 0 ? (int)c : 1;
    }
    if (nt > 256)
        nt = 256;
    b = calloc(1, sizeof *b);
    if (b)
        b->t = calloc((size_t)nt, sizeof *b->t);
    if (!b || !b->t) {
        sg_batch_free(b);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    b->nt = nt;
    /* One tracer prepares the model (glass indices and paraxial data in
     * MPFR, aiming's stop radius); the other threads' fork it, sharing it
     * with workspaces of their own. */
    for (k = 0; k < nt; k++) {
        int rc = k == 0 ? sg_tracer_open(sys, cat, opts, &b->t[0], d)
                        : sg_tracer_fork(b->t[0], &b->t[k], d);
        if (rc != SG_OK) {
            if (d && d->code == SG_OK)
                sg_diag_set(d, rc, "%s", sg_strerror(rc));
            sg_batch_free(b);
            return rc;
        }
    }
    b->nsurf = b->t[0]->n;
    *out = b;
    return SG_OK;
}

/* sg_batch_open with the code dropped (d, when given, holds it): the
 * public header's, kept for the library's ABI. */
sg_batch *sg_batch_new(const sg_system *sys, const sg_catalog *cat,
                       const sg_trace_opts *opts, int nthreads, sg_diag *d)
{
    sg_batch *b = NULL;
    (void)sg_batch_open(sys, cat, opts, nthreads, &b, d);
    return b;
}

void sg_batch_set_reference(sg_batch *b, int on)
{
    int k;
    for (k = 0; b && k < b->nt; k++)
        sg_tracer_set_reference(b->t[k], on);
}

int sg_batch_nsurf(const sg_batch *b)
{
    return b ? b->nsurf : 0;
}

int sg_batch_trace(sg_batch *b, sg_ray_kind kind, const sg_ray_in *rays, size_t nray,
                   const int *surf, int nsel, sg_ray_surface *out, int *status,
                   sg_diag *d)
{
    int k, rc;
    if (!b)
        return sg_diag_set(d, SG_EINVAL, "batch: no batch");
    if (kind != SG_RAYS_NORMALIZED && kind != SG_RAYS_START_DIR)
        return sg_diag_set(d, SG_EINVAL, "batch: unknown ray kind %d", (int)kind);
    if (nray == 0)
        return SG_OK;
    if (!rays || !out)
        return sg_diag_set(d, SG_EINVAL, "batch: no ray or output array");
    if (surf) {
        if (nsel <= 0)
            return sg_diag_set(d, SG_EINVAL, "batch: empty surface selection");
        for (k = 0; k < nsel; k++)
            if (surf[k] < 0 || surf[k] >= b->nsurf)
                return sg_diag_set(d, SG_EINVAL,
                                   "batch: selected surface %d is not one of 0 to %d",
                                   surf[k], b->nsurf - 1);
        if (!b->scratch) {
            b->scratch = calloc((size_t)b->nt * SG_BATCH_LANES * (size_t)b->nsurf,
                                sizeof *b->scratch);
            if (!b->scratch)
                return sg_diag_set(d, SG_ENOMEM, "out of memory");
        }
    }
    rc = sg_batch_run(b->t, b->nt, kind, rays, nray, surf, surf ? nsel : 0, b->scratch,
                      out, status);
    if (rc != SG_OK)
        return sg_diag_set(d, rc, "out of memory");
    return SG_OK;
}

int sg_trace_batch(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                   sg_ray_kind kind, const sg_ray_in *rays, size_t nray, int nthreads,
                   sg_ray_surface *out, int *status, sg_diag *d)
{
    sg_batch *b;
    sg_diag own;
    int rc;
    /* The code of a failure comes back through a diagnostic, so the
     * caller who passed none still gets it (an unknown glass is not
     * "out of memory"). */
    if (!d) {
        sg_diag_clear(&own);
        d = &own;
    }
    if (kind != SG_RAYS_NORMALIZED && kind != SG_RAYS_START_DIR)
        return sg_diag_set(d, SG_EINVAL, "batch: unknown ray kind %d", (int)kind);
    if (nray == 0)
        return SG_OK;
    if (!rays || !out)
        return sg_diag_set(d, SG_EINVAL, "batch: no ray or output array");
    /* No more threads than runs of rays to give them (see batch.c). */
    if (nthreads <= 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        nthreads = c > 0 ? (int)c : 1;
    }
    if ((size_t)nthreads > (nray + 63) / 64)
        nthreads = (int)((nray + 63) / 64);
    if ((rc = sg_batch_open(sys, cat, opts, nthreads, &b, d)) != SG_OK)
        return rc;
    rc = sg_batch_trace(b, kind, rays, nray, NULL, 0, out, status, d);
    sg_batch_free(b);
    return rc;
}
