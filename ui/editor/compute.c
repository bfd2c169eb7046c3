/* compute.c - tracers kept across edits and the live trace of one ray. */
#include "compute.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

double compute_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

void compute_init(compute *c)
{
    memset(c, 0, sizeof *c);
}

void compute_invalidate(compute *c)
{
    sg_tracer_free(c->t);
    sg_tracer_free(c->ref);
    c->t = c->ref = NULL;
    c->t_id = c->ref_id = 0;
}

void compute_free(compute *c)
{
    compute_invalidate(c);
    sg_index_cache_free(c->icache);
    sg_mpfr_memo_free(c->memo);
    free(c->res);
    free(c->ref_res);
    memset(c, 0, sizeof *c);
}

static int same_opts(const sg_trace_opts *a, const sg_trace_opts *b)
{
    return a->method == b->method && a->mpfr_bits == b->mpfr_bits && a->wave == b->wave &&
           a->clip == b->clip && a->clip_rtol == b->clip_rtol && a->max_iter == b->max_iter &&
           a->aim_max_iter == b->aim_max_iter && a->aim_rtol == b->aim_rtol;
}

static int ensure(compute *c, int n)
{
    if (n > c->cap) {
        sg_ray_surface *a = realloc(c->res, (size_t)n * sizeof *a);
        sg_ray_surface *b;
        if (!a)
            return SG_ENOMEM;
        c->res = a;
        b = realloc(c->ref_res, (size_t)n * sizeof *b);
        if (!b)
            return SG_ENOMEM;
        c->ref_res = b;
        c->cap = n;
    }
    c->nsurf = n;
    return SG_EOK;
}

static sg_tracer *build(const sg_system *sys, const sg_catalog *cat,
                        const sg_trace_opts *o, compute *c)
{
    sg_diag d;
    sg_tracer *t;
    sg_diag_clear(&d);
    t = sg_tracer_new_cached(sys, cat, o, c->icache, &d);
    if (!t) {
        c->build_rc = d.code != SG_EOK ? d.code : SG_ENOMEM;
        snprintf(c->build_msg, sizeof c->build_msg, "%s",
                 d.msg[0] ? d.msg : sg_strerror(c->build_rc));
    } else if (d.nwarn > 0 && !c->warn[0]) {
        snprintf(c->warn, sizeof c->warn, "%s", d.warn[0]);
    }
    return t;
}

int compute_run(compute *c, const sg_system *sys, unsigned long id,
                const sg_catalog *cat, const sg_trace_opts *o, int ref_bits,
                const double ray[4])
{
    double t0 = compute_now_ms();
    int rc;

    if (!c->icache)
        c->icache = sg_index_cache_new();
    if (!c->t || c->t_id != id || !same_opts(&c->t_opts, o)) {
        /* The reference shares the precise tracer's prepared model. */
        sg_tracer_free(c->ref);
        c->ref = NULL;
        c->ref_id = 0;
        sg_tracer_free(c->t);
        c->t = NULL;
        c->t_id = 0;
        c->build_rc = SG_EOK;
        c->build_msg[0] = '\0';
        c->warn[0] = '\0';
        c->t = build(sys, cat, o, c);
        c->par_ok = 0;
        if (c->t) {
            sg_diag d;
            c->t_id = id;
            c->t_opts = *o;
            /* First-order data at the primary wavelength, as Zemax and
             * "sagitta paraxial" give them, whatever the ray's.  (The
             * validation's warnings came with the tracer, in build.) */
            sg_diag_clear(&d);
            c->par_wave = sys->primary_wave;
            if (o->wave < 0 || o->wave == sys->primary_wave) {
                /* The tracer's launch computed them already, the same way
                 * (test_index_cache checks they are sg_paraxial_compute's). */
                c->par = *sg_tracer_paraxial(c->t);
                c->par_ok = 1;
            } else {
                c->par_ok = sg_paraxial_compute_cached(sys, cat, c->par_wave, c->icache,
                                                       &c->par, &d) == SG_OK;
            }
        }
    }
    c->have = c->ref_have = 0;
    if (!c->t) {
        c->par_ok = 0;
        sg_tracer_free(c->ref);
        c->ref = NULL;
        c->ref_id = 0;
        c->ms_last = compute_now_ms() - t0;
        return c->build_rc;
    }
    rc = ensure(c, sg_tracer_nsurf(c->t));
    if (rc != SG_EOK) {
        c->build_rc = rc;
        snprintf(c->build_msg, sizeof c->build_msg, "%s", sg_strerror(rc));
        return rc;
    }
    c->rc = sg_trace_normalized(c->t, ray[0], ray[1], ray[2], ray[3], c->res);
    c->have = 1;

    if (ref_bits > 0) {
        sg_trace_opts ro = *o;
        ro.method = SG_METHOD_MPFR;
        ro.mpfr_bits = ref_bits;
        if (!c->ref || c->ref_id != id || !same_opts(&c->ref_opts, &ro)) {
            sg_diag d;
            sg_tracer_free(c->ref);
            /* From the live tracer: its surfaces, paraxial data and launch
             * are the reference's too (same bits as a new tracer). */
            sg_diag_clear(&d);
            c->ref = sg_tracer_new_method(c->t, ro.method, ro.mpfr_bits, c->icache, &d);
            if (!c->ref) {
                c->build_rc = d.code != SG_EOK ? d.code : SG_ENOMEM;
                snprintf(c->build_msg, sizeof c->build_msg, "%s",
                         d.msg[0] ? d.msg : sg_strerror(c->build_rc));
            }
            c->ref_id = c->ref ? id : 0;
            c->ref_opts = ro;
            if (!c->memo)
                c->memo = sg_mpfr_memo_new();
            /* Without a memo the ray is traced in full, same bits. */
            sg_tracer_use_memo(c->ref, c->memo);
        }
        if (c->ref && sg_tracer_nsurf(c->ref) == c->nsurf) {
            c->ref_rc = sg_trace_normalized(c->ref, ray[0], ray[1], ray[2], ray[3],
                                            c->ref_res);
            c->ref_have = 1;
        }
    } else if (c->ref) {
        /* An MPFR tracer holds a lot of memory; drop it with the toggle. */
        sg_tracer_free(c->ref);
        c->ref = NULL;
        c->ref_id = 0;
        sg_mpfr_memo_free(c->memo);
        c->memo = NULL;
    }
    c->ms_last = compute_now_ms() - t0;
    if (c->ms_last > c->ms_max)
        c->ms_max = c->ms_last;
    return SG_EOK;
}
