/*
 * csvrays.h - the ray list read by "sagitta trace --rays FILE.csv".
 *
 * The first row that is not blank or a '#' comment names the columns, in any
 * order: either hx,hy,px,py (normalized field and pupil coordinates) or
 * x,y,z,l,m,n (a start point and direction in surface 1's frame).  Each
 * following row is one ray.  Names are case-insensitive and may be quoted.
 */
#ifndef SG_UI_CSVRAYS_H
#define SG_UI_CSVRAYS_H

#include <stddef.h>

#include "sagitta.h"

/* Parses a CSV text held in memory; name ("FILE") prefixes messages, which
 * read "FILE:LINE: column \"px\": ...".  On success *rays is a malloc'd
 * array of *nray rays (free() it) and the return is SG_OK; otherwise
 * SG_EPARSE or SG_ENOMEM, with *rays NULL and d filled. */
int csvrays_parse(const char *text, size_t len, const char *name,
                  sg_ray_kind *kind, sg_ray_in **rays, size_t *nray,
                  sg_diag *d);

/* Reads and parses a file; "-" reads standard input.  Adds SG_EIO, with a
 * message naming the file, to the codes above. */
/* Largest ray file read: about 5 million rays at full precision. */
#define CSVRAYS_MAX_BYTES ((size_t)1 << 30)

int csvrays_read(const char *path, sg_ray_kind *kind, sg_ray_in **rays,
                 size_t *nray, sg_diag *d);

#endif
