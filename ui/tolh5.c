/* tolh5.c - the Monte Carlo table as HDF5 (tolh5.h), in the manner of
 * h5rays.c's ray tables. */
#include "tolh5.h"

#include <errno.h>
#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "h5util.h"
#include "outfile.h"

enum { D_TRIAL, D_CRIT, D_STATUS, D_MAX };

struct tolh5 {
    hid_t file, ds[D_MAX], status_type;
    char path[4096], tmp[4096 + 32];
    int slot;
    hsize_t rows;
};

/* The status words of the CSV ("ok", "MISS", ...), the library's codes as
 * their values. */
static const char *status_word(int code)
{
    return code == SG_OK ? "ok" : sg_err_name(code);
}

static void close_all(tolh5 *h)
{
    h5u_close(h->ds, D_MAX, &h->status_type, &h->file);
}

void tolh5_abort(tolh5 *h)
{
    sigset_t old;
    if (!h)
        return;
    close_all(h);
    outfile_block_signals(&old);
    if (h->tmp[0])
        unlink(h->tmp);
    outfile_untrack(h->slot);
    outfile_restore_signals(&old);
    free(h);
}

tolh5 *tolh5_open(const char *path, const char *criterion, const char *distribution,
                  double nominal, uint64_t seed, int trials, char *err, size_t errlen)
{
    tolh5 *h = calloc(1, sizeof *h);
    unsigned long long sd = seed;
    hid_t fcpl;
    sigset_t old;
    int ok;
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
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    fcpl = H5Pcreate(H5P_FILE_CREATE);
    outfile_block_signals(&old);
    h->slot = outfile_track(h->tmp);
    h->file = fcpl >= 0 ? H5Fcreate(h->tmp, H5F_ACC_TRUNC, fcpl, H5P_DEFAULT) : -1;
    outfile_restore_signals(&old);
    if (fcpl >= 0)
        H5Pclose(fcpl);
    if (h->file < 0) {
        snprintf(err, errlen, "cannot create %s: %s", h->tmp, strerror(errno ? errno : EIO));
        h->tmp[0] = '\0';
        tolh5_abort(h);
        return NULL;
    }
    h->status_type = h5u_status_type(status_word);
    ok = h->status_type >= 0;
    if (ok)
        ok = (h->ds[D_TRIAL] = h5u_column(h->file, "trial", H5T_STD_I32LE, NULL,
                                           "trial number, from 1", 1024, 1)) >= 0 &&
             (h->ds[D_CRIT] = h5u_column(h->file, "criterion", H5T_IEEE_F64LE, NULL,
                                          "the compensated criterion; NaN where the system "
                                          "could not be evaluated", 1024, 1)) >= 0 &&
             (h->ds[D_STATUS] = h5u_column(h->file, "status", h->status_type, NULL,
                                            "ok, or why the system could not be evaluated",
                                            1024, 1)) >= 0;
    if (ok)
        ok = h5u_attr_str(h->file, "criterion", criterion) >= 0 &&
             h5u_attr_str(h->file, "distribution", distribution) >= 0 &&
             h5u_attr(h->file, "nominal", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &nominal, 0) >= 0 &&
             h5u_attr(h->file, "seed", H5T_STD_U64LE, H5T_NATIVE_ULLONG, &sd, 0) >= 0 &&
             h5u_attr(h->file, "trials", H5T_STD_I32LE, H5T_NATIVE_INT, &trials, 0) >= 0;
    if (!ok) {
        h5u_fail(err, errlen, "HDF5 write failed");
        tolh5_abort(h);
        return NULL;
    }
    return h;
}

int tolh5_write(tolh5 *h, int first, int n, const sg_tol_value *v, char *err, size_t errlen)
{
    int *trial, *st, k, rc;
    double *c;
    if (n <= 0)
        return 0;
    trial = malloc((size_t)n * sizeof *trial);
    st = malloc((size_t)n * sizeof *st);
    c = malloc((size_t)n * sizeof *c);
    rc = trial && st && c ? 0 : h5u_fail(err, errlen, "out of memory");
    for (k = 0; !rc && k < n; k++) {
        trial[k] = first + k + 1;
        st[k] = v[k].status;
        c[k] = v[k].status == SG_OK ? v[k].criterion : NAN;
    }
    if (!rc && (h5u_append(h->ds[D_TRIAL], h->rows, H5T_NATIVE_INT, trial, (hsize_t)n) < 0 ||
                h5u_append(h->ds[D_CRIT], h->rows, H5T_NATIVE_DOUBLE, c, (hsize_t)n) < 0 ||
                h5u_append(h->ds[D_STATUS], h->rows, h->status_type, st, (hsize_t)n) < 0))
        rc = h5u_fail(err, errlen, "HDF5 write failed");
    if (!rc)
        h->rows += (hsize_t)n;
    free(trial);
    free(st);
    free(c);
    return rc;
}

int tolh5_close(tolh5 *h, int done, int stopped, const sg_tol_stats *s, char *err,
                size_t errlen)
{
    static const double levels[5] = {90, 80, 50, 20, 10};
    int rc = 0, failed = s ? done - s->n : 0;
    sigset_t old;
    if (h5u_attr(h->file, "done", H5T_STD_I32LE, H5T_NATIVE_INT, &done, 0) < 0 ||
        h5u_attr(h->file, "stopped", H5T_STD_I32LE, H5T_NATIVE_INT, &stopped, 0) < 0 ||
        h5u_attr(h->file, "failed", H5T_STD_I32LE, H5T_NATIVE_INT, &failed, 0) < 0)
        rc = h5u_fail(err, errlen, "HDF5 write failed");
    if (!rc && s && s->n > 0 &&
        (h5u_attr(h->file, "best", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &s->best, 0) < 0 ||
         h5u_attr(h->file, "worst", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &s->worst, 0) < 0 ||
         h5u_attr(h->file, "mean", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &s->mean, 0) < 0 ||
         h5u_attr(h->file, "std", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &s->std, 0) < 0 ||
         h5u_attr(h->file, "percentile_levels", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, levels, 5) <
             0 ||
         h5u_attr(h->file, "percentiles", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, s->pct, 5) < 0))
        rc = h5u_fail(err, errlen, "HDF5 write failed");
    if (!rc && H5Fflush(h->file, H5F_SCOPE_GLOBAL) < 0)
        rc = h5u_fail(err, errlen, "HDF5 write failed");
    close_all(h);
    outfile_block_signals(&old);
    if (rc == 0 && rename(h->tmp, h->path) != 0) {
        snprintf(err, errlen, "%s: %s", h->path, strerror(errno));
        rc = -1;
    }
    if (rc != 0)
        unlink(h->tmp);
    outfile_untrack(h->slot);
    outfile_restore_signals(&old);
    free(h);
    return rc;
}

/* A string attribute of the root group into buf; -1 when absent. */
static int attr_text(hid_t file, const char *name, char *buf, size_t n)
{
    hid_t a = H5Aopen(file, name, H5P_DEFAULT), t = -1, m = -1;
    int rc = -1;
    size_t sz;
    if (a < 0)
        return -1;
    t = H5Aget_type(a);
    sz = t >= 0 ? H5Tget_size(t) : 0;
    if (sz > 0 && sz < n && (m = H5Tcopy(H5T_C_S1)) >= 0 && H5Tset_size(m, sz) >= 0 &&
        H5Aread(a, m, buf) >= 0) {
        buf[sz] = '\0';
        rc = 0;
    }
    if (m >= 0)
        H5Tclose(m);
    if (t >= 0)
        H5Tclose(t);
    H5Aclose(a);
    return rc;
}

/* A scalar attribute of memory type mtype into v; -1 when absent. */
static int attr_num(hid_t file, const char *name, hid_t mtype, void *v)
{
    hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    int rc;
    if (a < 0)
        return -1;
    rc = H5Aread(a, mtype, v) >= 0 ? 0 : -1;
    H5Aclose(a);
    return rc;
}

/* The extent of a one-dimensional dataset, or -1. */
static long long extent(hid_t ds)
{
    hid_t sp = H5Dget_space(ds);
    hsize_t n = 0;
    long long r = -1;
    if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 1 &&
        H5Sget_simple_extent_dims(sp, &n, NULL) == 1)
        r = (long long)n;
    if (sp >= 0)
        H5Sclose(sp);
    return r;
}

/* Rows at .. at + n - 1 of a one-dimensional dataset, as memory type m. */
static int read_rows(hid_t ds, hid_t m, hsize_t at, hsize_t n, void *buf)
{
    hid_t fs = H5Dget_space(ds), ms = H5Screate_simple(1, &n, NULL);
    int rc = -1;
    if (fs >= 0 && ms >= 0 &&
        H5Sselect_hyperslab(fs, H5S_SELECT_SET, &at, NULL, &n, NULL) >= 0 &&
        H5Dread(ds, m, ms, fs, H5P_DEFAULT, buf) >= 0)
        rc = 0;
    if (ms >= 0)
        H5Sclose(ms);
    if (fs >= 0)
        H5Sclose(fs);
    return rc;
}

enum { RESUME_BLOCK = 4096 };

int tolh5_resume(const char *path, const char *criterion, const char *distribution,
                 double nominal, uint64_t seed, int trials, tolh5 *to, double *crit, int *k,
                 sg_tol_value *last, char *err, size_t errlen)
{
    hid_t file, ds[D_MAX] = {-1, -1, -1}, st = -1;
    char text[256];
    unsigned long long sd = 0;
    double nom = 0, *c = NULL;
    int tr = 0, rc = -1, i, *trial = NULL, *status = NULL;
    long long n = -1, n1, n2, at;
    sg_tol_value *v = NULL;
    *k = 0;
    memset(last, 0, sizeof *last);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    if ((file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT)) < 0) {
        snprintf(err, errlen, "cannot be opened as HDF5 (--resume continues a table written "
                 "before)");
        return -1;
    }
    /* The run's settings: the same, or another run's table. */
    rc = 1;
    if (attr_text(file, "criterion", text, sizeof text) != 0 || strcmp(text, criterion) != 0) {
        snprintf(err, errlen, "its criterion is not this run's %s", criterion);
        goto out;
    }
    if (attr_text(file, "distribution", text, sizeof text) != 0 ||
        strcmp(text, distribution) != 0) {
        snprintf(err, errlen, "its distribution is not this run's %s", distribution);
        goto out;
    }
    if (attr_num(file, "nominal", H5T_NATIVE_DOUBLE, &nom) != 0 ||
        memcmp(&nom, &nominal, sizeof nom) != 0) {
        snprintf(err, errlen, "its nominal criterion %.17g is not this run's %.17g (another "
                 "design or method)", nom, nominal);
        goto out;
    }
    if (attr_num(file, "seed", H5T_NATIVE_ULLONG, &sd) != 0 || sd != (unsigned long long)seed) {
        snprintf(err, errlen, "its seed %llu is not this run's %llu", sd,
                 (unsigned long long)seed);
        goto out;
    }
    if (attr_num(file, "trials", H5T_NATIVE_INT, &tr) != 0 || tr != trials) {
        snprintf(err, errlen, "it is a table of %d trials, not this run's %d", tr, trials);
        goto out;
    }
    ds[D_TRIAL] = H5Dopen2(file, "trial", H5P_DEFAULT);
    ds[D_CRIT] = H5Dopen2(file, "criterion", H5P_DEFAULT);
    ds[D_STATUS] = H5Dopen2(file, "status", H5P_DEFAULT);
    if (ds[D_TRIAL] >= 0 && ds[D_CRIT] >= 0 && ds[D_STATUS] >= 0) {
        n = extent(ds[D_TRIAL]);
        n1 = extent(ds[D_CRIT]);
        n2 = extent(ds[D_STATUS]);
        if (n != n1 || n != n2)
            n = -1;
    }
    if (n < 0 || n > trials) {
        snprintf(err, errlen, "its trial, criterion and status columns are not one table of "
                 "at most %d rows", trials);
        goto out;
    }
    rc = -1;
    trial = malloc(RESUME_BLOCK * sizeof *trial);
    status = malloc(RESUME_BLOCK * sizeof *status);
    c = malloc(RESUME_BLOCK * sizeof *c);
    v = malloc(RESUME_BLOCK * sizeof *v);
    st = h5u_status_type(status_word);
    if (!trial || !status || !c || !v || st < 0) {
        snprintf(err, errlen, "out of memory");
        goto out;
    }
    for (at = 0; at < n; at += RESUME_BLOCK) {
        int m = (int)(n - at < RESUME_BLOCK ? n - at : RESUME_BLOCK);
        if (read_rows(ds[D_TRIAL], H5T_NATIVE_INT, (hsize_t)at, (hsize_t)m, trial) != 0 ||
            read_rows(ds[D_CRIT], H5T_NATIVE_DOUBLE, (hsize_t)at, (hsize_t)m, c) != 0 ||
            read_rows(ds[D_STATUS], st, (hsize_t)at, (hsize_t)m, status) != 0) {
            snprintf(err, errlen, "its columns cannot be read");
            goto out;
        }
        memset(v, 0, (size_t)m * sizeof *v);
        for (i = 0; i < m; i++) {
            if (trial[i] != at + i + 1) {
                snprintf(err, errlen, "row %lld holds trial %d", at + i + 1, trial[i]);
                rc = 1;
                goto out;
            }
            v[i].status = status[i];
            v[i].criterion = c[i];
            if (crit)
                crit[at + i] = status[i] == SG_OK ? c[i] : NAN;
        }
        if (to && tolh5_write(to, (int)at, m, v, err, errlen) != 0)
            goto out;
        *last = v[m - 1];
    }
    *k = (int)n;
    rc = 0;
out:
    free(trial);
    free(status);
    free(c);
    free(v);
    h5u_close(ds, D_MAX, &st, &file);
    return rc;
}
