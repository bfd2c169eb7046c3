/*
 * classic_ref.h - the scalar classic trace of before the vector kernel,
 * kept as the reference the kernel must match bit for bit.
 */
#ifndef CLASSIC_REF_H
#define CLASSIC_REF_H

#include "trace_int.h"

/* What sg_classic_run_to did for one ray: surfaces 1..upto from S along
 * D, into out[1..upto]; returns the ray's status. */
int classic_ref_run_to(const sg_tracer *t, const double S[3], const double D[3],
                       sg_ray_surface *out, int upto);

#endif
