/*
 * psf_internal.h - what the FFT PSF (psf.c) and MTF (mtf.c) share: one
 * field's traced pupil at one wavelength and its intensity.
 */
#ifndef SG_PSF_INTERNAL_H
#define SG_PSF_INTERNAL_H

#include "sagitta.h"

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
