/*
 * ui.h - the screen: layout, modes and the panels drawn through term.h.
 *
 * Each panel has a draw function and a key handler that returns ED_*
 * flags; the event loop in app.c is the only place that acts on them.
 */
#ifndef SG_ED_UI_H
#define SG_ED_UI_H

#include "cells.h"
#include "ed.h"
#include "lineedit.h"

enum { FOCUS_SHEET = 0, FOCUS_RAY };

enum {
    MODE_NORMAL = 0,
    MODE_EDIT_CELL,  /* typing into a spreadsheet cell */
    MODE_EDIT_RAY,   /* typing a ray coordinate */
    MODE_COMMAND,    /* the ':' line */
    MODE_CONFIRM,    /* a yes/no question on the status line */
    MODE_HELP,
    MODE_SETTINGS,
    MODE_EXAMPLES,
    MODE_SYSDATA,    /* the system data view */
    MODE_GLASSES,    /* the glass picker */
    MODE_MESSAGES,   /* the message history (:messages) */
    MODE_MERIT,      /* the Merit Function Editor (Ctrl-E, :merit) */
    MODE_TOL         /* the Tolerance Data Editor (Ctrl-T, :tol) */
};

/* A panel that takes the screen in a mode (app.c's table, as htop's
 * PanelClass): how it draws, when the status line shows under it, what
 * reads its keys, whether the ':' line may open over it, and whether it
 * ignores the mouse. */
enum { UI_STATUS_NONE = 0, UI_STATUS_ALWAYS, UI_STATUS_MSG /* when there is a message */ };
struct ui;
typedef struct ui_panel {
    void (*draw)(struct ui *u);
    int status;
    int (*key)(struct ui *u, int key);
    int cmdline;
    int no_mouse;
} ui_panel;

/* Items of the ray selector. */
enum { RAY_FIELD = 0, RAY_HX, RAY_HY, RAY_PX, RAY_PY, RAY_WAVE, RAY_NITEMS };

#define HIST_MAX 100

typedef struct ui {
    ed *e;
    int rows, cols;
    int focus, mode;
    int back_mode;       /* where the ':' line returns to */
    int cmd_key;         /* Esc was pressed: the next key is a command, even in a text cell */
    int rec_delete;      /* the recovery question asks to confirm deleting the file */
    double prog_t0, prog_last; /* a long export's start and last progress line */
    int late_signal;     /* a SIGTERM or SIGHUP that stopped :opt, for the loop */
    lineedit le;
    const char *ell;     /* ellipsis */

    /* Layout, set by ui_layout(). */
    int sheet_y, sheet_h, ray_y, parax_y, res_y, res_h, detail_y, status_y;
    int view_y, view_h;  /* the analysis view, when one is on (res_h is then 0) */
    int numw, resw;      /* numeric column widths */
    int too_small;

    /* Spreadsheet. */
    int top, left;       /* first row and first column on show */
    int colx[COL_MAX], colw[COL_MAX]; /* screen x and width; w 0: hidden */

    /* Ray selector. */
    int ray_item;
    int step_exp;        /* the step is 10^-step_exp, so steps stay decimal */
    int rayx[RAY_NITEMS], rayw[RAY_NITEMS];

    /* Results. */
    int res_top, res_left;

    /* Overlays. */
    int help_top;
    int sys_top;
    int glass_top;
    int msg_top;         /* the message history's first row; -1: the newest */
    int mf_sel, mf_top, mf_col; /* the Merit Function Editor's row (0-based), first row shown, column */
    int tol_sel, tol_top, tol_col; /* the same for the Tolerance Data Editor */
    /* Its values, kept for the document state mf_id (0: none), so moving
     * the cursor redraws without evaluating the merit function again. */
    sg_merit_result mf_res;
    int mf_ok;
    char mf_why[SG_DIAG_MSG];
    unsigned long mf_id;
    char warn_seen[SG_DIAG_MSG]; /* the design warning last put in the history */
    char fail_seen[SG_DIAG_MSG]; /* the same for why the design cannot be traced */
    int set_sel, set_top;
    char **ex;
    int nex, ex_sel, ex_top;

    /* ':' history, oldest first. */
    char *hist[HIST_MAX];
    int nhist, hist_pos;
} ui;

/* Runs a command built from a format; returns its flags. */
int ui_run(ui *u, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

void ui_layout(ui *u);
/* Opens the ':' line with text. */
void ui_prompt(ui *u, const char *text);

/* Panels. */
void sheet_draw(ui *u);
int sheet_key(ui *u, int key);
/* A key as a command (after Esc): never starts typing into a cell. */
int sheet_key_command(ui *u, int key);
int sheet_click(ui *u, int y, int x, int kind);
void sheet_follow(ui *u);
int sheet_edit_key(ui *u, int key);
void sheet_begin_edit(ui *u, const char *init);

void ray_draw(ui *u);
int ray_key(ui *u, int key);
int ray_edit_key(ui *u, int key);
int ray_click(ui *u, int x, int kind);
int ray_quick(ui *u, int key); /* chief and marginal keys; 0 if not one */

void results_draw(ui *u);
/* The analysis view (viewpanel.c), in place of the results when on. */
void view_draw(ui *u);
/* The paraxial summary line alone (results.c), for the view mode. */
void paraxial_draw(ui *u);
int results_key(ui *u, int key);
int results_click(ui *u, int y, int kind);
/* Lines the detail panel below the results takes at this width. */
int results_panel_height(const ui *u);

void title_draw(ui *u);
void status_draw(ui *u);

void glasses_draw(ui *u);
int glasses_key(ui *u, int key);

void sysdata_draw(ui *u);
int sysdata_key(ui *u, int key);
/* The lines of the system data view, malloc'ed; the caller frees them. */
int sysdata_lines(const ed *e, char ***lines);
/* Nonzero for the columns where any printable key types text. */
int sheet_text_col(int col);

void messages_draw(ui *u);
int messages_key(ui *u, int key);

void merit_draw(ui *u);
int merit_key(ui *u, int key);
/* Frees the Merit Function Editor's kept values. */
void merit_free(ui *u);

void tol_draw(ui *u);
int tol_key(ui *u, int key);

/* Cuts UTF-8 s to at most w columns, the cut marked with ell; returns
 * nonzero when it cut. */
int ui_fit(const char *s, int w, const char *ell, char *out, size_t n);
/* The same, cut at a blank so no number or word is cut, then ell and more
 * (where to see it whole, e.g. " F3"). */
int ui_fit_words(const char *s, int w, const char *ell, const char *more, char *out, size_t n);

void help_draw(ui *u);
int help_key(ui *u, int key);
/* The scrolling keys of a page (help, messages): moves *top, h rows a
 * screen, to end on End; 1 when key was one of them. */
int ui_page_key(int *top, int h, int key, int end);

void settings_draw(ui *u);
int settings_key(ui *u, int key);

void examples_open(ui *u);
void examples_draw(ui *u);
int examples_key(ui *u, int key);

/* Text of the help screen after the keys that work anywhere, one line
 * per entry; NULL ends. */
extern const char *const ui_key_help[];

/* The keys that work anywhere (keys.c), in the help screen's order; the
 * row with a NULL label ends the table.  A row runs a command, opens the
 * ':' line with a text, or calls an action; a DOC row names keys the
 * event loop reads before the table (Esc, the mouse). */
enum { UI_KEY_DOC = 0, UI_KEY_RUN, UI_KEY_PROMPT, UI_KEY_ACT };
#define UI_KEY_MAX 4
typedef struct ui_key {
    int keys[UI_KEY_MAX];  /* key codes; 0 ends the list */
    const char *label;     /* the keys as the help screen and sagitta(1) name them */
    const char *help;      /* the help screen's text; '\n' starts a line under it */
    int kind;
    const char *text;      /* UI_KEY_RUN: the command; UI_KEY_PROMPT: the ':' line's text */
    int (*act)(ui *u, int key);
} ui_key;
extern const ui_key ui_keys[];
/* The row that binds key, or NULL. */
const ui_key *ui_key_find(int key);
/* Does what row k says for key; its ED_* flags. */
int ui_key_run(ui *u, const ui_key *k, int key);

#endif
