/*
 * model_int.h - what only model/'s own files share: the dispersion
 * formulas and the air index in MPFR (the other subsystems reach them
 * through sg_system_glass_index_mpfr, model.h).
 */
#ifndef SG_MODEL_INT_H
#define SG_MODEL_INT_H

#include <mpfr.h>

#include "model.h"

/* Index of glass g at wavelength um (both MPFR), with out's precision.
 * Returns SG_OK, or SG_ERANGE when n^2 is not positive, or SG_EINVAL for an
 * unknown formula.  Every coefficient is taken exactly as its double. */
int sg_glass_index_mpfr(const sg_glass *g, mpfr_t out, const mpfr_t um);
/* sg_air_index and sg_glass_index_env in MPFR, rounded once into out. */
int sg_air_index_mpfr(mpfr_t out, const mpfr_t um, double temp, double pres);
int sg_glass_index_env_mpfr(const sg_glass *g, mpfr_t out, const mpfr_t um, double temp,
                            double pres);

/* Configurations renumbered for an inserted (dir 1) or deleted (dir -1)
 * surface at (config.c); *out NULL when nothing moves. */
int sg_configs_renumbered(const sg_configs *c, int at, int dir, sg_configs **out);

#endif
