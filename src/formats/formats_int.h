/*
 * formats_int.h - what only formats/'s own files share: reading and
 * writing whole files (fileio.c), which every format uses and none owns.
 * formats/ has no interface header of its own: what it offers the rest is
 * public (sagitta.h: sg_design_load, sg_design_save, sg_zmx_*).
 */
#ifndef SG_FORMATS_INT_H
#define SG_FORMATS_INT_H

#include <stddef.h>

#include "model.h"

/* Writes x in the shortest of %.15g, %.16g and %.17g that reads back to
 * the same bits, with '.' whatever the locale (json_write.c). */
void sg_json_fmt_double(char out[40], double x);

/* Reads a whole file of at most max bytes into *out (free() it). */
int sg_read_file(const char *path, size_t max, char **out, size_t *len, sg_diag *d);

/* Writes text atomically: a temporary file beside path, fsync, rename. */
int sg_save_text_atomic(const char *path, const char *text, size_t len, sg_diag *d);

#endif
