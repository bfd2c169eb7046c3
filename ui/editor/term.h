/*
 * term.h - the editor's only door to the terminal.
 *
 * Everything curses lives in term.c: setup and teardown, drawing text in
 * a few named styles, keys, mouse, resizing and signals.  Panels draw and
 * read keys through this small interface, so they can be reasoned about
 * (and one day tested) without a terminal.
 */
#ifndef SG_ED_TERM_H
#define SG_ED_TERM_H

/* Keys: Unicode code points below K_BASE, named keys above. */
enum {
    K_NONE = -1, /* the timeout passed */
    K_BASE = 0x200000,
    K_UP, K_DOWN, K_LEFT, K_RIGHT, K_HOME, K_END, K_PGUP, K_PGDN,
    K_INS, K_DEL, K_BACKSPACE, K_ENTER, K_TAB, K_BTAB, K_ESC,
    K_RESIZE,  /* the terminal changed size */
    K_MOUSE,   /* see term_mouse() */
    K_SIGNAL,  /* see term_signal() */
    K_F0       /* K_F0 + n is function key n */
};
#define K_F(n) (K_F0 + (n))
#define K_CTRL(c) ((c) & 0x1f)

/* Styles. */
enum {
    T_NORMAL = 0,
    T_TITLE,   /* title bar */
    T_HEADER,  /* column headings */
    T_CURSOR,  /* the selected cell */
    T_ROWSEL,  /* the selected row, elsewhere */
    T_STOP,    /* the stop row's label */
    T_ERROR,   /* error messages and failed rays */
    T_GOOD,    /* a ray that arrived */
    T_DIM,     /* secondary text */
    T_EDIT,    /* a field being edited */
    T_FRAME,   /* dialog frames and titles */
    T_PLOT0,   /* pictures: palette colour 0 (blue), then green, red, yellow, */
    T_PLOT1,   /* magenta and cyan, as ui/plot.c numbers them; plain text */
    T_PLOT2,   /* under NO_COLOR */
    T_PLOT3,
    T_PLOT4,
    T_PLOT5,
    T_NSTYLES
};

/* Mouse events. */
enum { M_CLICK = 1, M_DOUBLE, M_WHEEL_UP, M_WHEEL_DOWN };

/* Starts curses.  Colours are used unless NO_COLOR is set (to anything)
 * or the terminal has none.  Returns 0, or -1 with a message on stderr. */
int term_init(void);
/* Restores the terminal; safe to call more than once and from atexit. */
void term_end(void);
/* Nonzero while the screen is in use. */
int term_active(void);

void term_size(int *rows, int *cols);
/* Nonzero when the locale can show UTF-8 (the ellipsis, say). */
int term_utf8(void);

void term_erase(void);
/* Draws UTF-8 text at (y, x) in style, cut to w columns and, when pad is
 * set, padded with blanks to w.  Returns the columns used. */
int term_text(int y, int x, int w, int style, int pad, const char *s);
/* Blanks w columns. */
void term_fill(int y, int x, int w, int style);
/* Shows the cursor at (y, x), or hides it when y < 0. */
void term_cursor(int y, int x);
void term_flush(void);
/* Forces a full repaint at the next flush (Ctrl-L). */
void term_repaint(void);
void term_beep(void);
/* Drops keys typed but not yet read, so a question is answered by keys
 * pressed after it appeared. */
void term_flush_input(void);

/* Waits up to timeout_ms (-1: forever) for a key. */
int term_key(int timeout_ms);
/* The last K_MOUSE event. */
void term_mouse(int *y, int *x, int *kind);
/* The signal behind the last K_SIGNAL (SIGINT, SIGTERM, SIGHUP), cleared. */
int term_signal(void);
/* Gives the terminal back and stops the process (Ctrl-Z); resumes after. */
void term_suspend(void);

#endif
