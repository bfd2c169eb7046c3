/*
 * doc.h - the document the editor works on: one optical system, its file
 * name, whether it differs from that file, and the undo/redo history.
 *
 * Every change is bracketed by doc_begin() and doc_end() (or doc_cancel()),
 * which snapshot the whole system.  Snapshots are simple and cannot drift
 * out of step with new kinds of edit the way inverse operations can; the
 * history is trimmed by the memory it holds, not by a count.
 */
#ifndef SG_ED_DOC_H
#define SG_ED_DOC_H

#include <stddef.h>

#include "sagitta.h"

typedef struct doc_snap {
    sg_system *sys;
    unsigned long id; /* the state's identity (see doc.id) */
    int row;          /* the row the change touched, to put the cursor back */
} doc_snap;

typedef struct doc_stack {
    doc_snap *v;
    size_t n, cap;
} doc_stack;

/* What the file on disk was when the document last read or wrote it, so a
 * save can tell that another program changed it meanwhile. */
typedef struct doc_stamp {
    int have;                 /* 0: no file was read or written yet */
    unsigned long long dev, ino, size;
    long long mtime_s;
    long mtime_ns;
    unsigned long long hash;  /* FNV-1a of the content */
} doc_stamp;

typedef struct doc {
    sg_system *sys;
    char *path;               /* NULL for a design never saved */
    /* Each distinct state gets a fresh id; the file matches the document
     * exactly when id equals saved_id, so undoing back to the saved state
     * clears the modified flag. */
    unsigned long id, saved_id, next_id;
    doc_stack undo, redo;
    size_t hist_bytes;        /* memory held by both stacks */
    size_t hist_limit;        /* trim the oldest undo steps beyond this */
    int open_change;          /* doc_begin() called, doc_end() not yet */
    doc_stamp disk;           /* the file at path as last loaded or saved */
} doc;

/* A new design (sg_system_new()), no file name, unmodified.  Returns SG_EOK
 * or SG_ENOMEM. */
int doc_init(doc *d);
void doc_free(doc *d);

int doc_modified(const doc *d);
/* The file name, or NULL. */
const char *doc_path(const doc *d);
int doc_set_path(doc *d, const char *path);

/* Starts a change that touches row (for the cursor after undo).  Returns
 * SG_EOK or SG_ENOMEM. */
int doc_begin(doc *d, int row);
/* Ends it.  Returns 1 when the system changed (a new undo step), 0 when it
 * is bit for bit what it was (no step, no modified flag). */
int doc_end(doc *d);
/* Abandons it and restores the system as it was at doc_begin(). */
void doc_cancel(doc *d);

/* Steps back or forward.  Return SG_EOK, SG_ERANGE when there is nothing
 * to undo or redo, or SG_ENOMEM.  *row (may be NULL) receives the row the
 * step touched. */
int doc_undo(doc *d, int *row);
int doc_redo(doc *d, int *row);
size_t doc_undo_depth(const doc *d);
size_t doc_redo_depth(const doc *d);

/* Replaces the document by the design in path.  On failure the document is
 * untouched.  The history is cleared. */
int doc_load(doc *d, const char *path, sg_diag *dg);
/* Replaces the document by a new design with the given file name (NULL for
 * none); the history is cleared. */
int doc_new(doc *d, const char *path);
/* Replaces the document by sys, which it takes over, under the file name
 * path (NULL: none); the history is cleared.  With modified set the
 * document counts as differing from its file (a design recovered after a
 * crash), and no undo step leads back to an unmodified state.  read is the
 * file as the design's editor last read or wrote it (NULL or not have:
 * unknown, and a save asks before replacing whatever is there). */
void doc_replace(doc *d, sg_system *sys, const char *path, int modified,
                 const doc_stamp *read);
/* Saves to path (NULL: the current file name); on success the document
 * takes that name and is unmodified.  A file with one link is replaced
 * atomically (sg_design_save: a temporary file renamed over it).  A file
 * with more hard links is written in place so every name keeps seeing it:
 * first its old bytes are copied to a backup beside it, then it is
 * rewritten and synced, then the backup goes; should the rewrite fail the
 * old bytes are put back and, failing that, the message names the backup.
 * On failure the document is as it was. */
int doc_save(doc *d, const char *path, sg_diag *dg);
/* doc_save with sg_design_save_flags's flags (SG_ZMX_ALLOW_LOSS). */
int doc_save_flags(doc *d, const char *path, unsigned flags, sg_diag *dg);

/* Stamps the file at path: returns 0, or -1 with errno set (ENOENT: no
 * such file). */
int doc_stamp_file(const char *path, doc_stamp *st);
/* 1 when the document's file differs from what it last loaded or saved
 * (size or content; a new modification time alone with the same bytes
 * does not count) or exists though the document never read it; 0 when it
 * is the same, or there is no such file. */
int doc_disk_changed(const doc *d);
/* How a save to path would go.  Returns DOC_TARGET_* and, for an existing
 * file, its link count in *nlink (may be NULL). */
enum { DOC_TARGET_NEW = 0, DOC_TARGET_FILE, DOC_TARGET_READONLY, DOC_TARGET_NOTFILE };
int doc_target(const char *path, unsigned long *nlink);
/* 1 when path names the document's own file (the same inode, whatever the
 * spelling), 0 otherwise. */
int doc_is_own_file(const doc *d, const char *path);

/* Bitwise equality of two systems (every field that a design holds). */
int doc_system_equal(const sg_system *a, const sg_system *b);

#endif
