/*
 * analysis_int.h - what only analysis/'s own files share: the choice and
 * order of fields and wavelengths, and the FFT PSF's and MTF's traced
 * pupil.  analysis/ has no interface header of its own: what it offers
 * the rest (sg_spot_compute, sg_psf_compute, ...) is public (sagitta.h).
 */
#ifndef SG_ANALYSIS_INT_H
#define SG_ANALYSIS_INT_H

#include "num.h"
#include "sagitta.h"

/* The chosen indices (one, or all of n when sel < 0) into idx; returns how
 * many, or 0 with d filled when sel is out of range. */
int sg_an_select(int sel, int n, const char *what, int *idx, sg_diag *d);
/* The nw chosen wavelengths waves[] as an analysis reports them (design
 * index and micrometres), and the order they are traced in: the reference
 * wavelength refw first, whose chief rays every other is measured from. */
void sg_an_wave_order(const sg_system *sys, const int *waves, int nw, int refw,
                      int *wave_index, double *wave_um, int *order);
/* One micrometre in the design's lens units. */
double sg_an_um_to_units(const sg_system *sys);
/* Where a ray lands in the image's measure: its point, or in afocal image
 * space its direction cosines (sg_system.afocal). */
static inline double sg_an_img_x(const sg_system *sys, const sg_ray_surface *r)
{
    return sys->afocal ? r->l : r->x;
}
static inline double sg_an_img_y(const sg_system *sys, const sg_ray_surface *r)
{
    return sys->afocal ? r->m : r->y;
}

/* What the FFT PSF (psf.c) and MTF (mtf.c) share: one field's traced
 * pupil at one wavelength and its intensity. */
typedef struct sg_pupil {
    int n;                  /* grid points across the pupil (the sampling) */
    double *opd;            /* n * n, waves; row py, column px, -1 to 1 */
    unsigned char *ok;      /* 1 where the ray reaches the image */
    size_t nvalid;
    double um;              /* the wavelength */
    double fnum;            /* the working F/# the grid is scaled by */
    double scale_x, scale_y; /* 1 - vcx, 1 - vcy */
    double max_step;        /* largest OPD change between neighbours, waves */
} sg_pupil;

int sg_psf_check_common(const sg_system *sys, int sampling, const char *what, sg_diag *d);
/* The primary wavelength's paraxial working F/#. */
int sg_psf_working_fnum(const sg_system *sys, const sg_catalog *cat, double *fnum, sg_diag *d);
int sg_pupil_trace(const sg_system *sys, const sg_catalog *cat, const sg_trace_opts *trace,
                   int field, int wave, int sampling, double fnum, int nthreads,
                   sg_pupil *out, sg_diag *d);
void sg_pupil_free(sg_pupil *p);
/* |FFT|^2 of the pupil zero-padded to m x m (m >= 2n), centred at
 * (m/2, m/2); with aberrated 0 the phase is left out (the same pupil,
 * unaberrated). */
int sg_pupil_intensity(const sg_pupil *p, int aberrated, int m, double **intensity, sg_diag *d);
/* The Huygens PSF (huygens.c) of the chosen wavelengths, lmin the
 * shortest. */
int sg_psf_huygens(const sg_system *sys, const sg_catalog *cat, const sg_psf_opts *o,
                   const int *waves, int nw, double fnum, double lmin, sg_psf *out, sg_diag *d);
/* |mean over the pupil of exp(i 2 pi W)|^2. */
double sg_pupil_strehl_exact(const sg_pupil *p);

#endif
