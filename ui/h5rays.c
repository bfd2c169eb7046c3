/* h5rays.c - ray tables as HDF5 files. */
#include "h5rays.h"

#include <errno.h>
#include <hdf5.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "h5util.h"
#include "outfile.h"

/* Rows a chunk holds: 64 Ki doubles, 512 KiB, the size HDF5's guide
 * suggests for sequential reading and writing. */
#define H5R_CHUNK 65536

enum { C_RAY, C_IN0, C_SURFACE = C_IN0 + 6, C_X, C_Y, C_Z, C_L, C_M, C_N, C_RESIDUAL,
       C_ERROR, C_PATH, C_OPL, C_OPLB, C_STATUS, C_OPD, C_OPDB, C_EX, C_EY, C_MAX };

struct h5rays {
    hid_t file, status_type;
    hid_t ds[C_MAX];
    int nin, nsurf;
    /* The rows kept of each ray (trace --surface): surfaces sel[0 .. nsel
     * - 1], or all (sel NULL, nsel = nsurf). */
    int *sel, nsel;
    int opd; /* the OPD columns (normalized rays) */
    size_t rows, next_ray;
    char path[4096], tmp[4096 + 32];
    int slot; /* the temporary's outfile_track slot, or -1 */
    void *buf; /* the columns of a block */
    size_t bufrows;
};

static void close_all(h5rays *h)
{
    h5u_close(h->ds, C_MAX, &h->status_type, &h->file);
}

void h5rays_abort(h5rays *h)
{
    if (!h)
        return;
    close_all(h);
    if (h->tmp[0]) {
        sigset_t old;
        outfile_block_signals(&old);
        unlink(h->tmp);
        outfile_untrack(h->slot);
        outfile_restore_signals(&old);
    }
    free(h->buf);
    free(h->sel);
    free(h);
}

h5rays *h5rays_open(const char *path, const report_meta *m, const char *units,
                    int nsurf, sg_ray_kind kind, size_t rows_hint, char *err, size_t errlen)
{
    /* A short table gets chunks its own size: HDF5 stores whole chunks. */
    hsize_t chunk = rows_hint > 0 && rows_hint < H5R_CHUNK ? rows_hint : H5R_CHUNK;
    static const char *const norm[4] = { "hx", "hy", "px", "py" };
    static const char *const sd[6] = { "x0", "y0", "z0", "l0", "m0", "n0" };
    static const char *const out_name[11] = { "x", "y", "z", "l", "m", "n",
                                              "residual", NULL, "path", "opl", NULL };
    static const char *const out_what[11] = {
        "intersection point x in the surface's local frame",
        "intersection point y in the surface's local frame",
        "intersection point z in the surface's local frame",
        "direction cosine l after the surface", "direction cosine m after the surface",
        "direction cosine n after the surface", "|z - sag(x, y)| of the reported point",
        NULL, "geometric distance from the previous surface",
        "optical path from the start of the path (sagitta(1), OPTICAL PATH DIFFERENCE)", NULL
    };
    h5rays *h;
    int k, ok = 1, v;
    double w;
    const char *u = units && units[0] ? units : "mm";

    h = calloc(1, sizeof *h);
    if (!h) {
        h5u_fail(err, errlen, "out of memory");
        return NULL;
    }
    h->slot = -1;
    if (strlen(path) >= sizeof h->path) {
        free(h);
        h5u_fail(err, errlen, "file name too long");
        return NULL;
    }
    strcpy(h->path, path);
    snprintf(h->tmp, sizeof h->tmp, "%s.tmp%ld", path, (long)getpid());
    h->nsurf = nsurf;
    h->nsel = nsurf;
    if (m && m->surfaces) {
        h->sel = malloc((size_t)(m->nsurfaces > 0 ? m->nsurfaces : 1) * sizeof *h->sel);
        if (!h->sel) {
            free(h);
            h5u_fail(err, errlen, "out of memory");
            return NULL;
        }
        memcpy(h->sel, m->surfaces, (size_t)m->nsurfaces * sizeof *h->sel);
        h->nsel = m->nsurfaces;
    }
    h->nin = kind == SG_RAYS_NORMALIZED ? 4 : 6;
    /* The library's own messages would go to stderr unasked. */
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    {
        /* Listed from its creation on, so a signal that ends the program
         * removes it (outfile.h). */
        sigset_t old;
        outfile_block_signals(&old);
        h->slot = outfile_track(h->tmp);
        h->file = H5Fcreate(h->tmp, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
        if (h->file < 0) {
            outfile_untrack(h->slot);
            h->slot = -1;
        }
        outfile_restore_signals(&old);
    }
    if (h->file < 0) {
        snprintf(err, errlen, "cannot create %s: %s", h->tmp, strerror(errno ? errno : EIO));
        h->tmp[0] = '\0';
        h5rays_abort(h);
        return NULL;
    }
    h->status_type = h5u_status_type(report_status_name);
    ok = h->status_type >= 0;
    if (ok)
        h->ds[C_RAY] = h5u_column(h->file, "ray", H5T_STD_U64LE, NULL,
                                   "ray number, from 0 in the input's order", chunk, 0);
    for (k = 0; ok && k < h->nin; k++) {
        const char *nm = kind == SG_RAYS_NORMALIZED ? norm[k] : sd[k];
        char what[96];
        snprintf(what, sizeof what, "the ray's launch: %s", nm);
        h->ds[C_IN0 + k] = h5u_column(h->file, nm, H5T_IEEE_F64LE,
                                       kind == SG_RAYS_NORMALIZED ? "1" : k < 3 ? u : "1",
                                       what, chunk, 0);
    }
    if (ok)
        h->ds[C_SURFACE] = h5u_column(h->file, "surface", H5T_STD_I32LE, NULL,
                                       "surface number, 0 the object", chunk, 0);
    for (k = 0; ok && k < 11; k++) {
        int est = m && m->method && strcmp(m->method, "classic") == 0;
        const char *nm = k == 7    ? (est ? "error_estimate" : "error_bound")
                         : k == 10 ? (est ? "opl_error_estimate" : "opl_error_bound")
                                   : out_name[k];
        const char *what = k == 7    ? (est ? "classic's error estimate of the point (not a bound)"
                                            : "bound on the point's largest coordinate error")
                           : k == 10 ? (est ? "classic's error estimate of opl (not a bound)"
                                            : "bound on opl's error")
                                     : out_what[k];
        h->ds[C_X + k] = h5u_column(h->file, nm, H5T_IEEE_F64LE,
                                     k >= 3 && k <= 5 ? "1" : u, what, chunk, 0);
    }
    if (ok)
        h->ds[C_STATUS] = h5u_column(h->file, "status", h->status_type, NULL,
                                      "the ray's state at the surface", chunk, 0);
    h->opd = m && m->opd;
    if (ok && h->opd) {
        int est = m->method && strcmp(m->method, "classic") == 0;
        /* As CSV: the ray's OPD and transverse aberration on its image
         * row, NaN on the others. */
        h->ds[C_OPD] = h5u_column(h->file, "opd_waves", H5T_IEEE_F64LE, "waves",
                                   "OPD against the field's reference sphere, in waves of "
                                   "the ray's wavelength (image row only)", chunk, 0);
        h->ds[C_OPDB] = h5u_column(h->file, est ? "opd_error_estimate" : "opd_error_bound",
                                    H5T_IEEE_F64LE, "waves",
                                    est ? "classic's error estimate of opd_waves (not a bound)"
                                        : "bound on opd_waves' error", chunk, 0);
        h->ds[C_EX] = h5u_column(h->file, "ex", H5T_IEEE_F64LE, u,
                                  "transverse aberration x: image point minus the primary "
                                  "chief ray's (image row only)", chunk, 0);
        h->ds[C_EY] = h5u_column(h->file, "ey", H5T_IEEE_F64LE, u,
                                  "transverse aberration y: image point minus the primary "
                                  "chief ray's (image row only)", chunk, 0);
    }
    for (k = 0; ok && k < C_MAX; k++)
        if ((k < C_IN0 + h->nin || (k >= C_SURFACE && k <= C_STATUS) || (h->opd && k > C_STATUS)) &&
            h->ds[k] <= 0)
            ok = 0;
    if (ok) {
        hid_t root = h->file;
        v = nsurf;
        ok = h5u_attr_str(root, "design", m && m->design ? m->design : "") >= 0 &&
             h5u_attr_str(root, "method", m && m->method ? m->method : "") >= 0 &&
             h5u_attr_str(root, "sagitta_version", SG_VERSION_STRING) >= 0 &&
             h5u_attr_str(root, "units", u) >= 0 &&
             h5u_attr_str(root, "rays", kind == SG_RAYS_NORMALIZED ? "normalized"
                                                                   : "start_dir") >= 0 &&
             h5u_attr(root, "surfaces", H5T_NATIVE_INT, H5T_NATIVE_INT, &v, 0) >= 0;
        if (ok && m) {
            w = m->wave_um;
            v = m->wave_index;
            ok = h5u_attr(root, "wavelength_um", H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, &w, 0) >= 0 &&
                 h5u_attr(root, "wave", H5T_NATIVE_INT, H5T_NATIVE_INT, &v, 0) >= 0;
            if (ok && m->bits > 0) {
                v = m->bits;
                ok = h5u_attr(root, "bits", H5T_NATIVE_INT, H5T_NATIVE_INT, &v, 0) >= 0;
            }
        }
    }
    if (!ok) {
        h5u_fail(err, errlen, "cannot lay out the HDF5 file");
        h5rays_abort(h);
        return NULL;
    }
    return h;
}

int h5rays_write(h5rays *h, const sg_ray_surface *out, const int *status, size_t n,
                 const sg_ray_in *rays, const sg_opd *opd, char *err, size_t errlen)
{
    size_t rows = n * (size_t)h->nsel, r, k2, j;
    size_t nsurf = (size_t)h->nsurf;
    double *col[C_MAX];
    int k;
    (void)status;
    if (rows == 0)
        return 0;
    /* Every column of the block at once (a uint64_t or int column in a
     * double's room), filled in one pass over the rows: a pass a column
     * would read the block's rows once for every column. */
    if (rows > h->bufrows) {
        void *b = rows > SIZE_MAX / (C_MAX * sizeof(double))
                  ? NULL : realloc(h->buf, rows * C_MAX * sizeof(double));
        if (!b)
            return h5u_fail(err, errlen, "out of memory");
        h->buf = b;
        h->bufrows = rows;
    }
    for (k = 0; k < C_MAX; k++)
        col[k] = (double *)h->buf + (size_t)k * rows;
    {
        uint64_t *ray = (uint64_t *)col[C_RAY];
        int *surface = (int *)col[C_SURFACE], *st = (int *)col[C_STATUS];
        for (r = 0, j = 0; r < n; r++)
            for (k2 = 0; k2 < (size_t)h->nsel; k2++, j++) {
                size_t i = h->sel ? (size_t)h->sel[k2] : k2;
                const sg_ray_surface *e = &out[r * nsurf + i];
                int c;
                ray[j] = h->next_ray + r;
                surface[j] = (int)i;
                st[j] = e->status;
                for (c = 0; c < h->nin; c++)
                    col[C_IN0 + c][j] = rays ? rays[r].v[c] : NAN;
                /* A failed surface's numbers mean nothing: NaN, as CSV
                 * leaves the fields empty. */
                if (e->status == SG_OK) {
                    col[C_X][j] = e->x;
                    col[C_Y][j] = e->y;
                    col[C_Z][j] = e->z;
                    col[C_L][j] = e->l;
                    col[C_M][j] = e->m;
                    col[C_N][j] = e->n;
                    col[C_RESIDUAL][j] = e->residual;
                    col[C_ERROR][j] = e->error_bound;
                    col[C_PATH][j] = e->path;
                    col[C_OPL][j] = e->opl;
                    col[C_OPLB][j] = e->opl_error_bound;
                } else {
                    for (c = C_X; c <= C_OPLB; c++)
                        col[c][j] = NAN;
                }
                if (h->opd) {
                    /* As CSV: on the image row of a ray whose OPD is known. */
                    int known = opd && i == nsurf - 1 && opd[r].status == SG_OK;
                    col[C_OPD][j] = known ? opd[r].opd_waves : NAN;
                    col[C_OPDB][j] = known ? opd[r].error_bound : NAN;
                    col[C_EX][j] = known ? opd[r].ex : NAN;
                    col[C_EY][j] = known ? opd[r].ey : NAN;
                }
            }
    }
    /* The type is taken once a column: each H5T_NATIVE_* is a call into
     * HDF5 (H5open) behind its lock. */
    for (k = 0; k < C_MAX; k++) {
        hid_t mt;
        if ((k >= C_IN0 + h->nin && k < C_SURFACE) || (k > C_STATUS && !h->opd))
            continue;
        mt = k == C_RAY       ? H5T_NATIVE_UINT64
             : k == C_SURFACE ? H5T_NATIVE_INT
             : k == C_STATUS  ? h->status_type
                              : H5T_NATIVE_DOUBLE;
        if (h5u_append(h->ds[k], h->rows, mt, col[k], rows) < 0)
            return h5u_fail(err, errlen, "HDF5 write failed");
    }
    h->rows += rows;
    h->next_ray += n;
    return 0;
}

int h5rays_close(h5rays *h, char *err, size_t errlen)
{
    unsigned long long nrows = h->rows;
    int rc = 0;
    if (h5u_attr(h->file, "rows", H5T_NATIVE_ULLONG, H5T_NATIVE_ULLONG, &nrows, 0) < 0 ||
        H5Fflush(h->file, H5F_SCOPE_GLOBAL) < 0)
        rc = h5u_fail(err, errlen, "HDF5 write failed");
    close_all(h);
    {
        sigset_t old;
        outfile_block_signals(&old);
        if (rc == 0 && rename(h->tmp, h->path) != 0) {
            snprintf(err, errlen, "%s: %s", h->path, strerror(errno));
            rc = -1;
        }
        if (rc != 0)
            unlink(h->tmp);
        outfile_untrack(h->slot);
        outfile_restore_signals(&old);
    }
    free(h->buf);
    free(h->sel);
    free(h);
    return rc;
}
