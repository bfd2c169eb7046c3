/*
 * h5util.h - what the HDF5 writers (h5rays.c: ray tables; tolh5.c: the
 * Monte Carlo table) share: attributes, the status enumeration, columns
 * that grow a block at a time.
 */
#ifndef SG_UI_H5UTIL_H
#define SG_UI_H5UTIL_H

#include <stddef.h>

#include <hdf5.h>

/* Puts what into err (n bytes); returns -1. */
int h5u_fail(char *err, size_t n, const char *what);
/* A string attribute. */
herr_t h5u_attr_str(hid_t obj, const char *name, const char *v);
/* n values of file type ftype from memory type mtype (n 0: a scalar). */
herr_t h5u_attr(hid_t obj, const char *name, hid_t ftype, hid_t mtype, const void *v,
                hsize_t n);
/* An enumeration of the library's status codes, each named by name(code). */
hid_t h5u_status_type(const char *(*name)(int code));
/* An empty one-dimensional column that grows in chunks of chunk rows, with
 * its units (may be NULL) and description as attributes; no_times leaves
 * out the creation and change times, so the file's bytes depend on its data
 * alone. */
hid_t h5u_column(hid_t file, const char *name, hid_t type, const char *units,
                 const char *what, hsize_t chunk, int no_times);
/* Closes n datasets, a type and a file (each where above 0) and zeroes
 * them. */
void h5u_close(hid_t *ds, int n, hid_t *type, hid_t *file);
/* Writes n values of memtype at rows at to at + n - 1, growing ds; 0 or -1. */
int h5u_append(hid_t ds, hsize_t at, hid_t memtype, const void *buf, hsize_t n);

#endif
