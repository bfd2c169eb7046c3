/*
 * recover.h - the recovery file: a copy of the document with unsaved
 * changes, kept on disk while the editor runs so that a crash, a signal or
 * a dead terminal loses nothing.
 *
 * Where: $XDG_STATE_HOME/sagitta/ (default ~/.local/state/sagitta/),
 * created with mode 0700.  One file per editing session and document,
 * named BASENAME-HASH-PID.sgrec (HASH: FNV-1a of the absolute path) or
 * untitled-PID.sgrec, mode 0600.  Its first line is a JSON header (the
 * design's absolute path, the writer's pid, process start time, boot id and
 * host, the time of writing, and "disk": the design's file as the editor
 * last read or wrote it, doc_stamp's fields as strings); the rest is the
 * design exactly as sg_design_to_json() writes it, so "tail -n +2" gives a
 * loadable design.
 *
 * Every write is atomic (temporary file in the same directory, fsync,
 * rename), so the signal handlers never need to touch the file: it is
 * already current when a signal arrives.
 */
#ifndef SG_ED_RECOVER_H
#define SG_ED_RECOVER_H

#include <stddef.h>

#include "doc.h"
#include "sagitta.h"

#define REC_PATH 4096
#define REC_SUFFIX ".sgrec"
/* A lock: the header line alone, kept while an editor has a design open,
 * so a second editor on the same file can warn. */
#define REC_LOCK_SUFFIX ".sglock"
/* Each write costs an fsync, so writes are spaced by REC_COST_FACTOR times
 * what the last one took, and never more than REC_DEBOUNCE_MS: a small
 * design is written after every change, a huge one or a slow disk at most
 * twice a second.  The event loop wakes to write the last change when the
 * gap has passed. */
#define REC_DEBOUNCE_MS 500.0
#define REC_COST_FACTOR 8.0

typedef struct rec_info {
    char file[REC_PATH];      /* the recovery file */
    char path[REC_PATH];      /* the design's absolute path; "" when untitled */
    long pid;                 /* the editor that wrote it */
    unsigned long long start; /* its start time in clock ticks after boot; 0: unknown */
    char boot[40];            /* the kernel's boot id then; "": unknown */
    char host[256];
    long long time;           /* when it was written, seconds since the epoch */
    int orphan;               /* the editor that wrote it is gone */
    /* The design's file as that editor last read or wrote it (have = 0:
     * unknown, or a file written before sagitta kept it), so a save after
     * recovery still sees a change made on disk since. */
    doc_stamp disk;
} rec_info;

/* The editor's side: which file it owns and what that file holds. */
typedef struct recov {
    int enabled;              /* write recovery files (not in batch mode) */
    int closed;               /* the session ended cleanly: write nothing more */
    char file[REC_PATH];      /* our file, "" when none is on disk */
    char key[REC_PATH];       /* the absolute path our file is for */
    unsigned long written_id; /* the document state it holds */
    double last_ms;           /* when it was written (compute_now_ms) */
    double gap_ms;            /* the least time before the next write */
    int pending;              /* a change waits for the debounce interval */
    int failing;              /* the last write failed (reported once) */
    char adopted[REC_PATH];   /* an orphan this session loaded: removed once safe */
    char lock[REC_PATH];      /* our lock file, "" when none */
    char lock_for[REC_PATH];  /* the document name it was made for */
} recov;

/* The directory for recovery files into buf: $XDG_STATE_HOME/sagitta when
 * that is an absolute path, else $HOME/.local/state/sagitta.  Returns 0,
 * or -1 when neither variable gives one. */
int rec_dir(char *buf, size_t n);

/* The absolute, symlink-free form of path, whether or not the file exists
 * yet (its directory is resolved instead).  Returns 0 or -1. */
int rec_abspath(const char *path, char *buf, size_t n);

/* Writes a recovery file for the design sys atomically: a header naming
 * abspath (NULL or "": an untitled design), this process, the time and
 * disk (the design's file as the editor last read or wrote it; NULL: none),
 * then the design.  The directory must exist.  Returns SG_OK or an error
 * with d filled. */
int rec_write_file(const char *file, const char *abspath, const sg_system *sys,
                   const doc_stamp *disk, sg_diag *d);

/* Reads a recovery file's header into info and, when sys is not NULL, its
 * design into sys.  info->orphan is set.  Returns SG_OK or an error. */
int rec_read_file(const char *file, rec_info *info, sg_system *sys, sg_diag *d);

/* Nonzero when the process that wrote info is gone: its pid no longer
 * exists, or now belongs to a process that started at another time, or
 * the machine has rebooted since.  A file from another host counts as
 * alive, since its process cannot be checked from here. */
int rec_is_orphan(const rec_info *info);

/* The orphaned recovery files in dir, newest first: those for abspath, or
 * every one when abspath is NULL.  The file named skip (our own; may be
 * NULL) is left out.  *out is malloc'ed (NULL when none); returns the
 * count, or -1 when dir cannot be read (a missing dir gives 0). */
int rec_orphans(const char *dir, const char *abspath, const char *skip, rec_info **out);

/* How many live editors other than this one have the design abspath open
 * (a lock or a recovery file of a running process names it); the first
 * goes to *first (may be NULL).  Locks left by dead editors are removed. */
int rec_holders(const char *dir, const char *abspath, rec_info *first);

/* Removes temporary files (NAME.sgrec.tmpXXXXXX) older than a minute from
 * dir: a live editor's exist for milliseconds, so these were left by an
 * editor killed in the middle of a write.  Also removes the locks of
 * editors that are gone. */
void rec_sweep_temps(const char *dir);

/* "YYYY-MM-DD HH:MM:SS" in local time. */
void rec_time_text(long long t, char *buf, size_t n);

/* ------------------------------------------------------------------------
 * The editor's recovery file.  These take the editor state (ed.h).
 * ------------------------------------------------------------------------ */
struct ed;

/* Brings our recovery file in line with the document: writes it when the
 * document has changes it does not hold (once gap_ms has passed since the
 * last write, or at once with force), removes it when the document has no
 * unsaved changes or has changed name.  Returns the milliseconds until a
 * delayed write is due, or -1 when nothing waits. */
int rec_sync(struct ed *e, int force);
/* A clean end (quit): removes our file and writes no more. */
void rec_finish(struct ed *e);
/* The document was saved: an adopted orphan is no longer needed. */
void rec_saved(struct ed *e);

#endif
