/*
 * num.h - the interface of num/, the engine's arithmetic: double-double
 * (dd.h), its vector lanes (vdd.h), the names of the per-instruction-set
 * kernels (isa.h), each a header of its own since the vector code includes
 * them in a fixed order, and the Zernike polynomials (zernike.c), whose
 * public part is in sagitta.h.  num/ includes no other subsystem.
 */
#ifndef SG_NUM_H
#define SG_NUM_H

#include <stddef.h>

#include "sagitta.h"

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
