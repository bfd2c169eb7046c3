/* lean.h - a lean double trace for bench's baseline (lean.c). */
#ifndef SG_UI_LEAN_H
#define SG_UI_LEAN_H

#include <stddef.h>

#include "sagitta.h"

/* Doubles in a row: x, y, z, l, m, n, path, opl and three unused. */
#define LEAN_ROW 11

typedef struct lean lean;

/* The design as the lean trace sees it, with t's indices (its
 * wavelength); NULL when a surface is not a standard or even asphere, or
 * has a frame change. */
lean *lean_new(const sg_system *sys, const sg_tracer *t);
void lean_free(lean *L);
int lean_nsurf(const lean *L);
/* nray rays from in[6 r ..]: a point on surface 1 in its frame and the
 * direction after it, through surfaces 2 .. nsurf - 1 into rows
 * (nray * nsurf * LEAN_ROW doubles; rows 0 and 1 are left alone).
 * Returns the rays whose image x is finite. */
size_t lean_trace(const lean *L, const double *in, size_t nray, double *rows);

#endif
