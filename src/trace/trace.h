/*
 * trace.h - the interface of trace/ (the tracer, its three methods, the
 * launch, the batch, the OPD, the paraxial trace and the caches of a
 * tracer) to the other subsystems, beside sagitta.h: the first-order
 * trace in MPFR and the indices it reads (solve_apply.c applies the
 * solves through them: sg_system_apply_solves, public).
 */
#ifndef SG_TRACE_H
#define SG_TRACE_H

#include <mpfr.h>

#include "model.h"

/* Paraxial data at MPFR precision prec, in paraxial.c.  idx holds the
 * signed index after every surface (n entries, at least prec bits). */
typedef struct sg_parax_mp {
    mpfr_t efl, bfl, image_dist, epd, enp, exp_diam, exp_pos, image_fnum,
        working_fnum, object_na, pimg_h, mag, track, stop_r;
    mpfr_t pimg_slope; /* paraxial image height per unit tan(field) or object height */
    /* The same at the paraxial image plane (the image surface's when the
     * image is afocal): Zemax's paraxial-image-height fields are defined
     * there, while its distortion is referred to the image surface. */
    mpfr_t pimg_slope_f;
} sg_parax_mp;

void sg_parax_mp_init(sg_parax_mp *p, mpfr_prec_t prec);
void sg_parax_mp_clear(sg_parax_mp *p);
void sg_parax_to_double(const sg_parax_mp *p, sg_paraxial *o);
/* The axial object point's marginal slope for an object NA or cone angle
 * aperture (paraxial.c). */
int sg_object_slope_mpfr(const sg_system *sys, const mpfr_t n0, mpfr_t out, sg_diag *d);
int sg_paraxial_mpfr(const sg_system *sys, mpfr_t *idx, int wave, mpfr_prec_t prec,
                     sg_parax_mp *out, sg_diag *d);
/* The same, resuming each y-nu trace after the last surface whose inputs
 * (radius, thickness, index, and the one before) and the trace's start
 * are those memo last saw: the same bits.  memo may be NULL. */
typedef struct sg_parax_memo sg_parax_memo;
int sg_paraxial_mpfr_memo(const sg_system *sys, mpfr_t *idx, int wave, mpfr_prec_t prec,
                          sg_parax_mp *out, sg_diag *d, sg_parax_memo *memo);
sg_parax_memo *sg_parax_memo_new(void);
void sg_parax_memo_free(sg_parax_memo *memo);
unsigned long sg_parax_memo_resumes(const sg_parax_memo *memo);
/* Signed indices after every surface at wavelength wave, into idx[0..n-1]. */
int sg_indices_mpfr(const sg_system *sys, const sg_catalog *cat, int wave,
                    mpfr_t *idx, sg_diag *d);

/* The code-returning constructors beside the public sg_tracer_open: *out
 * and SG_OK, or NULL in *out and the failure's code (also in d when
 * given).  sg_tracer_new_cached, sg_tracer_new_method and sg_batch_new
 * (sagitta.h) are these with the code dropped. */
int sg_tracer_open_cached(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                          sg_index_cache *cache, sg_tracer **out, sg_diag *d);
int sg_tracer_open_method(const sg_tracer *t, sg_method method, int mpfr_bits,
                          sg_index_cache *cache, sg_tracer **out, sg_diag *d);
int sg_batch_open(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *opts,
                  int nthreads, sg_batch **out, sg_diag *d);

#endif
