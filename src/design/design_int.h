/*
 * design_int.h - what only design/'s own files share: the optimizer's
 * damped least squares on an objective other than the merit function
 * (the tolerancing's compensators, tolerance.c).
 */
#ifndef SG_DESIGN_INT_H
#define SG_DESIGN_INT_H

#include "design.h"
#include "model.h"

/* Fills f[0..nres-1] with the residuals at sys (solves applied); their sum
 * of squares is minimized.  Called from several threads at once. */
typedef int (*sg_lsq_fn)(void *ctx, const sg_system *sys, double *f, int nres, sg_diag *d);

/* Damped least squares (sg_optimize's) on the nvar parameters at vars,
 * each within [lo[j], hi[j]] (absolute; a radius is varied as its
 * curvature, and its bounds must lie on one side of 0), against fn's nres
 * residuals; rel is their relative rounding (it sets the Jacobian's
 * steps).  sys gets the best point found; res->merit0 and merit are the
 * root sums of squares before and after. */
int sg_lsq_optimize(sg_system *sys, const sg_catalog *cat, const sg_paddr *vars,
                    const double *lo, const double *hi, int nvar, int nres, double rel,
                    sg_lsq_fn fn, void *ctx, const sg_opt_opts *o, sg_opt_result *res,
                    sg_diag *d);

#endif
