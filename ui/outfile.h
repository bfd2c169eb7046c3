/*
 * outfile.h - a report file that appears whole or not at all.
 *
 * A regular file is written under a temporary name beside it and renamed
 * at the end, so a write that fails or is cancelled half-way (a bad row
 * deep in a ray list, Esc during a long export) leaves an existing file as
 * it was.  Standard output ("-" or NULL), a device, a pipe, or a file with
 * other hard links (which a rename would break) are written in place.  A
 * symbolic link stays and the file it names is replaced, keeping its mode.
 */
#ifndef SG_UI_OUTFILE_H
#define SG_UI_OUTFILE_H

#include <stdio.h>

/* The stream's buffer: stdio's default is the file system's block, 4 KiB,
 * which makes a ray table of a gigabyte a quarter of a million writes. */
#define OUTFILE_BUF (1 << 16)

typedef struct outfile {
    FILE *f;
    char *buf; /* OUTFILE_BUF bytes for a file we opened, or NULL */
    const char *path; /* NULL for standard output */
    char target[4096], tmp[4096 + 32];
} outfile;

/* Opens path for writing; 0, or an errno value. */
int outfile_open(outfile *o, const char *path, FILE *std);
/* Flushes, closes and renames into place; 0, or an errno value (the
 * temporary is then removed). */
int outfile_commit(outfile *o);
/* Drops what was written: the temporary goes, an existing file stays. */
void outfile_abort(outfile *o);

#endif
