/*
 * h5util.c - the HDF5 writers' shared pieces (h5util.h).
 */
#include "h5util.h"

#include <stdio.h>
#include <string.h>

#include "sagitta.h"

int h5u_fail(char *err, size_t n, const char *what)
{
    snprintf(err, n, "%s", what);
    return -1;
}

herr_t h5u_attr_str(hid_t obj, const char *name, const char *v)
{
    hid_t t = H5Tcopy(H5T_C_S1), sp = H5Screate(H5S_SCALAR), a;
    herr_t rc = -1;
    if (t >= 0 && sp >= 0 && H5Tset_size(t, strlen(v) > 0 ? strlen(v) : 1) >= 0) {
        a = H5Acreate2(obj, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
        if (a >= 0) {
            rc = H5Awrite(a, t, v);
            H5Aclose(a);
        }
    }
    if (sp >= 0)
        H5Sclose(sp);
    if (t >= 0)
        H5Tclose(t);
    return rc;
}

herr_t h5u_attr(hid_t obj, const char *name, hid_t ftype, hid_t mtype, const void *v,
                hsize_t n)
{
    hid_t sp = n ? H5Screate_simple(1, &n, NULL) : H5Screate(H5S_SCALAR), a;
    herr_t rc = -1;
    if (sp < 0)
        return -1;
    a = H5Acreate2(obj, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        rc = H5Awrite(a, mtype, v);
        H5Aclose(a);
    }
    H5Sclose(sp);
    return rc;
}

hid_t h5u_status_type(const char *(*name)(int code))
{
    hid_t t = H5Tenum_create(H5T_NATIVE_INT);
    int code;
    if (t < 0)
        return -1;
    for (code = 0; code < SG_ERRNO_COUNT; code++)
        if (H5Tenum_insert(t, name(code), &code) < 0) {
            H5Tclose(t);
            return -1;
        }
    return t;
}

hid_t h5u_column(hid_t file, const char *name, hid_t type, const char *units,
                 const char *what, hsize_t chunk, int no_times)
{
    hsize_t dims = 0, maxdims = H5S_UNLIMITED;
    hid_t sp = H5Screate_simple(1, &dims, &maxdims);
    hid_t pl = H5Pcreate(H5P_DATASET_CREATE), ds = -1;
    if (sp >= 0 && pl >= 0 && H5Pset_chunk(pl, 1, &chunk) >= 0 &&
        (!no_times || H5Pset_obj_track_times(pl, 0) >= 0))
        ds = H5Dcreate2(file, name, type, sp, H5P_DEFAULT, pl, H5P_DEFAULT);
    if (pl >= 0)
        H5Pclose(pl);
    if (sp >= 0)
        H5Sclose(sp);
    if (ds >= 0 && ((units && h5u_attr_str(ds, "units", units) < 0) ||
                    h5u_attr_str(ds, "description", what) < 0)) {
        H5Dclose(ds);
        ds = -1;
    }
    return ds;
}

int h5u_append(hid_t ds, hsize_t at, hid_t memtype, const void *buf, hsize_t n)
{
    hsize_t start = at, count = n, size = at + n;
    hid_t fs, ms;
    herr_t rc;
    if (H5Dset_extent(ds, &size) < 0)
        return -1;
    fs = H5Dget_space(ds);
    ms = H5Screate_simple(1, &count, NULL);
    rc = fs >= 0 && ms >= 0 &&
                 H5Sselect_hyperslab(fs, H5S_SELECT_SET, &start, NULL, &count, NULL) >= 0
             ? H5Dwrite(ds, memtype, ms, fs, H5P_DEFAULT, buf)
             : -1;
    if (ms >= 0)
        H5Sclose(ms);
    if (fs >= 0)
        H5Sclose(fs);
    return rc < 0 ? -1 : 0;
}

void h5u_close(hid_t *ds, int n, hid_t *type, hid_t *file)
{
    int k;
    for (k = 0; k < n; k++)
        if (ds[k] > 0)
            H5Dclose(ds[k]);
    if (*type > 0)
        H5Tclose(*type);
    if (*file > 0)
        H5Fclose(*file);
    memset(ds, 0, (size_t)n * sizeof *ds);
    *type = *file = 0;
}
