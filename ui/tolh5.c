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
