/*
 * outfile.h - a report file that appears whole or not at all.
 *
 * A regular file is written under a temporary name beside it and renamed
 * at the end, so a write that fails or is cancelled half-way (a bad row
 * deep in a ray list, Esc during a long export) leaves an existing file as
 * it was.  Standard output ("-" or NULL), a device, a pipe, or a file with
 * other hard links (which a rename would break) are written in place.  A
 * symbolic link stays and the file it names is replaced (or made, for a
 * dangling one), keeping its owner, group and mode; a file whose owner a
 * new file could not keep is written in place.
 */
#ifndef SG_UI_OUTFILE_H
#define SG_UI_OUTFILE_H

#include <signal.h>
#include <stdio.h>

/* The stream's buffer: stdio's default is the file system's block, 4 KiB,
 * which makes a ray table of a gigabyte a quarter of a million writes. */
#define OUTFILE_BUF (1 << 16)

typedef struct outfile {
    FILE *f;
    char *buf; /* OUTFILE_BUF bytes for a file we opened, or NULL */
    const char *path; /* NULL for standard output */
    char target[4096], tmp[4096 + 32];
    int slot; /* the temporary's outfile_track slot, or -1 */
} outfile;

/* Opens path for writing; 0, or an errno value. */
int outfile_open(outfile *o, const char *path, FILE *std);
/* Flushes, closes and renames into place; 0, or an errno value (the
 * temporary is then removed). */
int outfile_commit(outfile *o);
/* Drops what was written: the temporary goes, an existing file stays. */
void outfile_abort(outfile *o);

/* Temporary files beside their targets are listed while they exist, and a
 * signal that ends the program (SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGPIPE,
 * SIGALRM, SIGUSR1, SIGUSR2, SIGXCPU, SIGXFSZ, SIGVTALRM, SIGPROF) removes
 * them before it ends the program with its default action.  The handler
 * is installed for the signals whose action is the default when the first
 * temporary is made: one a program handles (the editor's) or ignores
 * (nohup) is left so.  SIGKILL cannot be caught.
 *
 * outfile_track lists path (copied) and returns its slot, or -1 when all
 * OUTFILE_TEMPS are taken; outfile_untrack(slot) drops it (-1: nothing).
 * Call both with outfile_block_signals in force, so a signal arriving
 * between creating and listing (or renaming and unlisting) waits. */
#define OUTFILE_TEMPS 16
int outfile_track(const char *path);
void outfile_untrack(int slot);
/* Blocks the signals above in this thread (old receives the mask to
 * restore with outfile_restore_signals). */
void outfile_block_signals(sigset_t *old);
void outfile_restore_signals(const sigset_t *old);
/* sg_set_temp_hook's callback: the engine's atomic saves list their
 * temporary files here too. */
void outfile_temp_hook(const char *path, int add);

#endif
