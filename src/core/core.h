/*
 * core.h - the interface of core/: what every subsystem of the engine may
 * use beside the public header (the error table and sg_diag are there).
 * core/ is the bottom of the engine; it includes no other subsystem.
 */
#ifndef SG_CORE_H
#define SG_CORE_H

#include <stddef.h>

#include "sagitta.h"

/* Lengths a trace squares (radii, thicknesses, pupil and field sizes) must
 * keep their squares and products inside the doubles. */
#define SG_MAX_LEN 1e150

/* Copies at most n-1 bytes and always terminates. */
void sg_strlcpy(char *dst, const char *src, size_t n);

#endif
