/*
 * h5rays.h - ray tables as HDF5 files ("sagitta trace --format hdf5").
 *
 * The rows are CSV's: one per ray and surface.  Each column is its own
 * one-dimensional dataset in the root group, chunked and extended block by
 * block, so memory stays bounded however many rays.  man/sagitta.1 lists
 * the layout.
 */
#ifndef SG_UI_H5RAYS_H
#define SG_UI_H5RAYS_H

#include <stddef.h>

#include "report.h"
#include "sagitta.h"

typedef struct h5rays h5rays;

/* Creates path (replacing a file there only when h5rays_close succeeds:
 * the data go to a temporary name beside it first).  units is the
 * design's lens unit ("mm", ...); rows_hint the rows of the first block
 * (a table that short gets chunks no longer; 0 for the default).  NULL on failure, with a message in
 * err. */
h5rays *h5rays_open(const char *path, const report_meta *m, const char *units,
                    int nsurf, sg_ray_kind kind, size_t rows_hint, char *err,
                    size_t errlen);
/* Appends n rays (rows out[r * nsurf], status[r], launch rays[r]), with
 * each ray's OPD opd[r] on its image row when the file has OPD columns
 * (m->opd at open; opd may be NULL otherwise). */
int h5rays_write(h5rays *h, const sg_ray_surface *out, const int *status, size_t n,
                 const sg_ray_in *rays, const sg_opd *opd, char *err, size_t errlen);
/* Writes the row count, closes and renames into place; 0, or -1 with err.
 * The handle is freed either way. */
int h5rays_close(h5rays *h, char *err, size_t errlen);
/* Closes and removes the temporary; the handle is freed. */
void h5rays_abort(h5rays *h);

#endif
