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
#include <stdio.h>

#include "sagitta.h"

/* Parses a CSV text held in memory; name ("FILE") prefixes messages, which
 * read "FILE:LINE: column \"px\": ...".  On success *rays is a malloc'd
 * array of *nray rays (free() it) and the return is SG_OK; otherwise
 * SG_EPARSE or SG_ENOMEM, with *rays NULL and d filled. */
int csvrays_parse(const char *text, size_t len, const char *name,
                  sg_ray_kind *kind, sg_ray_in **rays, size_t *nray,
                  sg_diag *d);

/* Reads and parses a whole file into memory; "-" reads standard input.
 * Adds SG_EIO, with a message naming the file, to the codes above.  The
 * trace command streams instead (below); this is for small lists. */
int csvrays_read(const char *path, sg_ray_kind *kind, sg_ray_in **rays,
                 size_t *nray, sg_diag *d);

/* The longest line read; a longer one is refused with its line number, so
 * /dev/zero or a runaway pipe cannot exhaust memory. */
#define CSVRAYS_MAX_LINE ((size_t)16 << 20)

/* A ray list read a block of rays at a time, in memory bounded by the
 * longest line, whatever the file's length. */
typedef struct csvrays_reader csvrays_reader;

/* Opens a file ("-" is standard input) and reads up to its header row. */
int csvrays_open(const char *path, csvrays_reader **r, sg_diag *d);
/* The same over an open stream, which stays the caller's to close. */
int csvrays_open_stream(FILE *f, const char *name, csvrays_reader **r, sg_diag *d);
/* Counts the rows left without parsing them (lines that are neither blank
 * nor comments), reading to the end: for a header that states the count. */
int csvrays_count(csvrays_reader *r, size_t *n, sg_diag *d);
/* The same over text in memory, which must outlive the reader. */
int csvrays_open_text(const char *text, size_t len, const char *name,
                      csvrays_reader **r, sg_diag *d);
sg_ray_kind csvrays_kind(const csvrays_reader *r);
/* Reads up to max rays into rays; *n is 0 at the end.  A file without a
 * single ray is SG_EPARSE ("no rays after the header"). */
int csvrays_next(csvrays_reader *r, sg_ray_in *rays, size_t max, size_t *n,
                 sg_diag *d);
/* Lets csvrays_next parse a block's rows on threads (0: every core; the
 * default is 1).  The rays and messages are the same. */
void csvrays_set_threads(csvrays_reader *r, int threads);
/* Bytes read so far and the file's size (0 when unknown, as for a pipe). */
void csvrays_progress(const csvrays_reader *r, unsigned long long *done,
                      unsigned long long *total);
void csvrays_close(csvrays_reader *r);

#endif
