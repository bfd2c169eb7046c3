/*
 * compute.h - the live trace behind the results pane.
 *
 * A tracer is kept between changes and rebuilt only when the document or
 * the trace options change, so moving the ray costs one trace.  With the
 * digits toggle a second, MPFR tracer gives the reference the chosen
 * method is compared with.
 */
#ifndef SG_ED_COMPUTE_H
#define SG_ED_COMPUTE_H

#include "sagitta.h"

typedef struct compute {
    sg_tracer *t, *ref;
    unsigned long t_id, ref_id; /* document state each was built for; 0: none */
    sg_trace_opts t_opts, ref_opts;
    int build_rc;               /* SG_EOK, or why the tracer could not be built */
    char build_msg[SG_DIAG_MSG];
    char warn[SG_DIAG_MSG];     /* first warning of the build, or "" */
    int nsurf;                  /* entries in res and ref_res */
    int cap;
    sg_ray_surface *res, *ref_res;
    int have, ref_have;         /* res / ref_res hold the current ray */
    int rc, ref_rc;             /* what the traces returned */
    sg_paraxial par;            /* at the primary wavelength */
    int par_ok;
    int par_wave;               /* 0-based: the primary when it was computed */
    double ms_last, ms_max;     /* wall time of recomputes */
    /* Glass indices kept across edits (NULL: none could be made); the
     * tracers and paraxial data take them from here, same bits. */
    sg_index_cache *icache;
    /* The reference ray's state after each surface, kept across edits so
     * the digits check resumes at the first changed surface (NULL: none
     * yet, or the check is off). */
    sg_mpfr_memo *memo;
} compute;

void compute_init(compute *c);
void compute_free(compute *c);

/* Brings the results up to date for system sys in state id: rebuilds the
 * tracers when id or the options changed, then traces ray (hx, hy, px, py)
 * with both.  ref_bits > 0 asks for the MPFR reference at that precision.
 * Returns SG_EOK, or the build error (also in build_msg). */
int compute_run(compute *c, const sg_system *sys, unsigned long id,
                const sg_catalog *cat, const sg_trace_opts *o, int ref_bits,
                const double ray[4]);

/* Forgets the tracers so the next run rebuilds them (for the benchmark);
 * the glass indices stay, as after an edit. */
void compute_invalidate(compute *c);

/* Monotonic clock in milliseconds. */
double compute_now_ms(void);

#endif
