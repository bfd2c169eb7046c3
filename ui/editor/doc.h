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
 * crash), and no undo step leads back to an unmodified state. */
void doc_replace(doc *d, sg_system *sys, const char *path, int modified);
/* Saves to path (NULL: the current file name) atomically; on success the
 * document takes that name and is unmodified.  On failure the file on disk
 * and the document are both as they were. */
int doc_save(doc *d, const char *path, sg_diag *dg);

/* Bitwise equality of two systems (every field that a design holds). */
int doc_system_equal(const sg_system *a, const sg_system *b);

#endif
