/*
 * tolh5.h - the Monte Carlo table of "sagitta tolerance" as an HDF5 file
 * (--format hdf5; sagitta(1), TOLERANCING).  Three one-dimensional
 * datasets, trial, criterion and status, chunked and extended a block at
 * a time (memory stays bounded), with the run's settings and statistics
 * as attributes of the root group.  No object keeps a time, so a run
 * gives the same bytes on any number of threads and processes.
 */
#ifndef SG_UI_TOLH5_H
#define SG_UI_TOLH5_H

#include <stddef.h>
#include <stdint.h>

#include "sagitta.h"

typedef struct tolh5 tolh5;

/* Creates path's table under a temporary name beside it (renamed into
 * place by tolh5_close); NULL with a message in err. */
tolh5 *tolh5_open(const char *path, const char *criterion, const char *distribution,
                  double nominal, uint64_t seed, int trials, char *err, size_t errlen);
/* Appends trials first + 1 .. first + n (v's status and criterion). */
int tolh5_write(tolh5 *h, int first, int n, const sg_tol_value *v, char *err, size_t errlen);
/* Writes the trials done, stopped and the statistics (s may be NULL when
 * none were done), closes and renames into place; 0, or -1 with err.
 * The handle is freed either way. */
int tolh5_close(tolh5 *h, int done, int stopped, const sg_tol_stats *s, char *err,
                size_t errlen);
/* Closes and removes the temporary; the handle is freed. */
void tolh5_abort(tolh5 *h);
/* --resume: path's table must be this run's (its criterion, distribution,
 * nominal bit for bit, seed and trials; else 1, with what differs in err)
 * with its trial column 1 .. K.  Copies its K rows into the new table to
 * (when not NULL), a block at a time so memory stays bounded, their
 * criteria (NaN: failed) into crit (when not NULL), the last row into
 * *last; K into *k.  0, 1, or -1 when it cannot be read (err says why). */
int tolh5_resume(const char *path, const char *criterion, const char *distribution,
                 double nominal, uint64_t seed, int trials, tolh5 *to, double *crit, int *k,
                 sg_tol_value *last, char *err, size_t errlen);

#endif
