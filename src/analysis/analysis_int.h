/*
 * analysis_internal.h - what the analyses (spot.c, fan.c, layout.c,
 * wavefront.c, zernike.c) share.
 */
#ifndef SG_ANALYSIS_INTERNAL_H
#define SG_ANALYSIS_INTERNAL_H

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

/* sg_zernike_fit and sg_wavefront_stats over a wavefront map's nvalid
 * valid cells (at the map's pupil coordinates), without copies of its
 * points: a 4096-point grid would need 400 MB of them.  The fit also
 * bounds each coefficient's error (coef_bound, may be NULL) from the
 * map's data_err (a bound on every value's error) and its own rounding. */
int sg_zernike_fit_map(sg_zernike_kind kind, int nterms, int grid, const double *map,
                       const unsigned char *valid, size_t nvalid, double data_err,
                       double *coef, double *coef_bound, double *rms_resid, sg_diag *d);
int sg_wavefront_stats_map(int grid, const double *map, const unsigned char *valid,
                           size_t nvalid, int remove_tilt, double *rms, double *pv, sg_diag *d);

#endif
