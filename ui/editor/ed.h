/*
 * ed.h - the editor's state, shared by the command path and the panels.
 *
 * Nothing here touches the terminal: the command path runs the same way
 * from a key, the ':' line and a batch script.
 */
#ifndef SG_ED_H
#define SG_ED_H

#include <stddef.h>
#include <stdio.h>

#include "compute.h"
#include "doc.h"
#include "glasspick.h"
#include "recover.h"
#include "sagitta.h"
#include "view.h"

/* What a command or a key handler asks the event loop to do. */
enum {
    ED_HANDLED = 1 << 0,
    ED_REDRAW = 1 << 1,
    ED_RECOMPUTE = 1 << 2,
    ED_QUIT = 1 << 3,
    ED_CONFIRM = 1 << 4,       /* ask the user; see ed.confirm */
    ED_ERROR = 1 << 5,         /* the command failed; ed.msg says why */
    ED_SHOW_HELP = 1 << 6,
    ED_SHOW_SETTINGS = 1 << 7,
    ED_SHOW_EXAMPLES = 1 << 8,
    ED_PROMPT = 1 << 9,        /* open the ':' line with ed.prompt_init */
    ED_SHOW_SYSDATA = 1 << 10, /* the system data (paraxial) view */
    ED_SHOW_GLASSES = 1 << 11, /* the glass picker (ed.glasses) */
    ED_SHOW_MESSAGES = 1 << 12, /* the message history (ed.hist) */
    ED_SHOW_MERIT = 1 << 13,    /* the Merit Function Editor */
    ED_SHOW_TOL = 1 << 14       /* the Tolerance Data Editor */
};

/* What a confirmation asks. */
enum {
    CONFIRM_NONE = 0,
    CONFIRM_QUIT,     /* unsaved changes: save, discard or cancel */
    CONFIRM_DISCARD,  /* unsaved changes: run ed.pending anyway? */
    CONFIRM_RECOVER,  /* ed.question: recover (ed.pending), discard (ed.pending2) or later */
    CONFIRM_ASK,      /* ed.question, yes or no: yes runs ed.pending */
    CONFIRM_WRITE     /* ed.question: a large export; run ed.pending (y) or not (n) */
};

#define ED_MSG 1024
#define ED_LINE 4096
/* Messages the history keeps, oldest dropped first. */
#define ED_HIST_MAX 200

typedef struct ed {
    doc doc;
    sg_catalog *cat;           /* NULL when no catalog could be loaded */
    char cat_msg[ED_MSG];     /* why not */

    /* The ray on show and how it is traced; not part of the design. */
    double ray[4];             /* Hx, Hy, Px, Py */
    int wave;                  /* 0-based wavelength index */
    sg_method method;
    int bits;                  /* MPFR precision, for the method and the digits */
    int clip;
    int digits;                /* also trace with MPFR and show agreement */
    int global;                /* -1: each surface's local frame; else the
                                  rows are in this surface's frame (:global) */
    sg_frame *gframes;         /* ed_global_frames' frames, kept for ... */
    unsigned long gframes_id;  /* ... this document state (0: none) */
    int gframes_ref, gframes_n; /* ... reference surface and surface count */
    sg_trace_opts opts;        /* built from the above by ed_opts() */

    compute cmp;
    int dirty;                 /* results are stale */
    edview view;               /* the analysis view beside the sheet */

    int row, col;              /* the spreadsheet's cursor */

    char msg[ED_MSG];          /* the last message for the status line */
    int msg_err;
    /* Every message shown, whole, oldest first (:messages), each led by
     * '!' for an error or warning and ' ' else. */
    char *hist[ED_HIST_MAX];
    int nhist;
    int confirm;               /* CONFIRM_* pending */
    char pending[ED_LINE];     /* command to run when confirmed */
    char pending2[ED_LINE];    /* CONFIRM_RECOVER: the command for "no" */
    char question[ED_MSG];     /* CONFIRM_RECOVER: the question asked */
    char question_short[ED_MSG]; /* the same, answers first, for a narrow screen */
    char prompt_init[ED_LINE]; /* text to start the ':' line with */

    int batch;                 /* no screen: print to out, never ask */
    FILE *out;
    int quit;                  /* set by quit in batch mode */

    recov rec;                 /* the recovery file (recover.h) */

    gp_list glasses;           /* the last "glasses" search */
    int glass_sel;             /* the picker's cursor in it */

    /* Long work (an export) reports done of total rays to the screen; a
     * nonzero return cancels it (Esc).  NULL in batch mode. */
    int (*progress)(void *ctx, const char *what, size_t done, size_t total);
    void *progress_ctx;
    /* :opt reports each cycle's merit (sg_opt_opts.progress, with
     * progress_ctx); a nonzero return stops it (Esc, Ctrl-C) and the best
     * design so far is kept.  NULL in batch mode. */
    int (*opt_progress)(void *ctx, int cycle, double merit, double step, double seconds);
    /* :tol reports systems done of total (sg_tol_opts.progress, with
     * progress_ctx, from the threads that run them); a nonzero return
     * stops it and the rows done are kept.  NULL in batch mode. */
    int (*tol_progress)(void *ctx, int done, int total);
    /* The last :tol run and the document state it was made on. */
    sg_tol_result tol_res;
    int tol_have;
    unsigned long tol_id;
} ed;

int ed_init(ed *e);
void ed_free(ed *e);
/* Sets e->opts from the ray and method choices and clamps them to the
 * design (a deleted wavelength, say). */
void ed_opts(ed *e);
/* The global frames of the design relative to surface ref, made in MPFR
 * only when the design or ref changed since the last call; NULL with d
 * set when the design refuses ref.  Owned by e. */
const sg_frame *ed_global_frames(ed *e, int ref, sg_diag *d);
/* Recomputes the live trace if anything changed. */
void ed_recompute(ed *e);

/* Records a message for the status line (batch mode: errors go to
 * stderr by the caller). */
void ed_msg(ed *e, int err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Adds the message on the status line to the history, unless it is the
 * newest entry already. */
void ed_msg_log(ed *e);
/* Adds a line to the history (err: an error or a warning). */
void ed_hist_add(ed *e, int err, const char *text);
/* Puts a design file's load warnings (a .zmx import's frozen pickups and
 * kept solves) into the history, each whole, and says on the status line
 * how many there are and where to read them; batch mode prints them to
 * stderr.  Nothing without warnings. */
void ed_load_warnings(ed *e, const char *path, const sg_diag *d);

/* Runs one command line.  Returns ED_* flags; on failure ED_ERROR is set,
 * e->msg says why and nothing changed. */
int cmd_exec(ed *e, const char *line);

/* Quotes s for a command line when it needs it. */
void cmd_quote(const char *s, char *buf, size_t n);

/* The directory of the bundled examples, or NULL. */
const char *ed_examples_dir(void);
/* Lists the bundled examples (file names without ".json"), sorted; the
 * caller frees each and the array.  Returns the count, or -1. */
int ed_examples_list(char ***names);
void ed_examples_free(char **names, int n);

/* Names of the choices, as shown and typed. */
const char *ed_aper_name(int t);
const char *ed_field_type_name(int t);
const char *ed_field_norm_name(int t);
const char *ed_aim_name(int a);

/* The field scales of Zemax's normalization: the largest radial field
 * (both), or the largest |x| and |y| (rectangular); a field (x, y) is
 * traced at Hx = x / fx, Hy = y / fy. */
void ed_field_scale(const sg_system *s, double *fx, double *fy);
/* The design's field the ray's Hx, Hy pick (1-based), or 0 for none. */
int ed_ray_field(const ed *e);
/* The field the fan view shows (0-based): the ray's, else the last. */
int ed_view_field(const ed *e);
/* The unit of the field values: "deg" or the lens unit. */
const char *ed_field_unit(const sg_system *s);

/* Appends a warning to the message when other live editors have the
 * design at path open; returns how many. */
int ed_note_holders(ed *e, const char *path);

/* Runs a script of commands without a screen; returns the exit status.
 * Errors print as "SCRIPT:LINE: message" on stderr. */
int ed_batch(ed *e, const char *script);

#endif
