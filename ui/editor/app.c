/*
 * app.c - the editor's entry point and its single event loop: read a key,
 * hand it to the panel that owns it, act on the flags it returns.
 */
#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include "editor.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

#define MIN_ROWS 14
#define MIN_COLS 50

int ui_run(ui *u, const char *fmt, ...)
{
    char line[ED_LINE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    return cmd_exec(u->e, line);
}

void ui_prompt(ui *u, const char *text)
{
    le_set(&u->le, text);
    u->back_mode = u->mode == MODE_COMMAND ? MODE_NORMAL : u->mode;
    u->mode = MODE_COMMAND;
    u->hist_pos = u->nhist;
}

void ui_layout(ui *u)
{
    int n = u->e->doc.sys->nsurf, avail;
    term_size(&u->rows, &u->cols);
    u->too_small = u->rows < MIN_ROWS || u->cols < MIN_COLS;
    /* Title, sheet heading, ray, paraxial, results heading and status take
     * a line each, the detail panel its own height; the surfaces share the
     * rest. */
    if (u->e->view.kind != VIEW_OFF) {
        /* The view takes the results' place: the sheet keeps up to a third
         * of the rows (at least 3), the view the rest below the ray and
         * paraxial lines. */
        avail = u->rows - 5;
        u->sheet_h = avail / 3 < 3 ? 3 : avail / 3;
        if (u->sheet_h > n)
            u->sheet_h = n;
        u->sheet_y = 1;
        u->ray_y = u->sheet_y + 1 + u->sheet_h;
        u->parax_y = u->ray_y + 1;
        u->res_y = u->parax_y;
        u->res_h = 0;
        u->view_y = u->parax_y + 1;
        u->status_y = u->rows - 1;
        u->view_h = u->status_y - u->view_y;
        u->detail_y = u->status_y;
        goto widths;
    }
    avail = u->rows - 6 - results_panel_height(u);
    if (avail < 2)
        avail = 2;
    u->sheet_h = avail / 2 > avail - n ? avail / 2 : avail - n;
    if (u->sheet_h > n)
        u->sheet_h = n;
    u->res_h = avail - u->sheet_h;
    u->sheet_y = 1;
    u->ray_y = u->sheet_y + 1 + u->sheet_h;
    u->parax_y = u->ray_y + 1;
    u->res_y = u->parax_y + 1;
    u->detail_y = u->rows - 1 - results_panel_height(u);
    u->status_y = u->rows - 1;
    u->view_y = u->view_h = 0;
widths:
    /* At 80 columns Radius, Thickness, Semi-Dia and Conic all fit. */
    u->numw = (u->cols - 8 - 9 - 13 - 10) / 4;
    if (u->numw < 10)
        u->numw = 10;
    if (u->numw > 22)
        u->numw = 22;
    u->resw = (u->cols - 8 - 10 - 10 - 10) / 6;
    if (u->resw < 11)
        u->resw = 11;
    if (u->resw > 24)
        u->resw = 24;
}

/* Cuts s (UTF-8) to at most w columns at the end of a word, marking the
 * cut with ell; a single word longer than w is cut where it must be. */
static void cut_at_word(char *s, int w, const char *ell)
{
    int cols = 0, lastw = -1;
    size_t i = 0, lastb = 0, cut = 0;
    if (w < 2 || numfmt_width(s) <= w)
        return;
    while (s[i]) {
        size_t j = i + 1;
        while (((unsigned char)s[j] & 0xC0) == 0x80)
            j++;
        if (cols + 1 > w - 1)
            break;
        cols++;
        if (s[i] != ' ' && (s[j] == ' ' || s[j] == '\0')) {
            lastb = j;
            lastw = cols;
        }
        i = j;
        cut = i;
    }
    /* A word boundary not too far back; else the hard cut. */
    if (lastw > 0 && lastw >= (w - 1) / 2)
        cut = lastb;
    snprintf(s + cut, 8, "%s", ell);
}

void title_draw(ui *u)
{
    const ed *e = u->e;
    const char *p = doc_path(&e->doc);
    char left[600], right[200];
    const char *base = p ? strrchr(p, '/') : NULL;
    char conf[48] = "";
    /* The configuration every panel shows (Zemax's current one). */
    if (e->doc.sys->configs)
        snprintf(conf, sizeof conf, "  config %d/%d", e->doc.sys->configs->current,
                 e->doc.sys->configs->n);
    snprintf(left, sizeof left, " sagitta  %s%s%s%s%s", p ? (base ? base + 1 : p) : "[new design]",
             doc_modified(&e->doc) ? " [+]" : "", conf, e->doc.sys->title[0] ? "  - " : "",
             e->doc.sys->title);
    if (e->method == SG_METHOD_MPFR)
        snprintf(right, sizeof right, "mpfr %d bits  %.2f ms  F1 help ", e->bits, e->cmp.ms_last);
    else
        snprintf(right, sizeof right, "%s  %.2f ms  F1 help ", sg_method_name(e->method),
                 e->cmp.ms_last);
    term_fill(0, 0, u->cols, T_TITLE);
    /* The right side (method, timing, help) wins over a long title, which
     * is cut at a word, never inside one. */
    if ((int)strlen(right) + 20 < u->cols) {
        cut_at_word(left, u->cols - (int)strlen(right) - 2, u->ell);
        term_text(0, 0, u->cols - (int)strlen(right) - 1, T_TITLE, 1, left);
        term_text(0, u->cols - (int)strlen(right), (int)strlen(right), T_TITLE, 0, right);
    } else {
        cut_at_word(left, u->cols - 1, u->ell);
        term_text(0, 0, u->cols, T_TITLE, 1, left);
    }
}

int ui_fit(const char *s, int w, const char *ell, char *out, size_t n)
{
    size_t i = 0;
    int c = 0;
    if (numfmt_width(s) <= w) {
        snprintf(out, n, "%s", s);
        return 0;
    }
    while (s[i] && c < w - 1) {
        i++;
        while (((unsigned char)s[i] & 0xC0) == 0x80)
            i++;
        c++;
    }
    snprintf(out, n, "%.*s%s", (int)i, s, w > 0 ? ell : "");
    return 1;
}

int ui_fit_words(const char *s, int w, const char *ell, const char *more, char *out, size_t n)
{
    size_t i, cut = 0;
    int cols = 0, room = w - 1 - numfmt_width(more);
    if (numfmt_width(s) <= w) {
        snprintf(out, n, "%s", s);
        return 0;
    }
    for (i = 0; s[i]; i++) {
        if (((unsigned char)s[i] & 0xC0) == 0x80)
            continue;
        if (s[i] == ' ' && cols <= room)
            cut = i;
        cols++;
    }
    while (cut > 0 && strchr(" ,:;", s[cut - 1]))
        cut--;
    if (room < 0)
        return ui_fit(s, w, ell, out, n);
    snprintf(out, n, "%.*s%s%s", (int)cut, s, ell, more);
    return 1;
}

/* A message on the status line from x on: whole when it fits, else cut
 * with an ellipsis and the way to read it whole. */
static void status_msg(ui *u, int x, int style, const char *s)
{
    static const char more[] = " :messages";
    char buf[ED_MSG + SG_DIAG_MSG + 32];
    int w = u->cols - x;
    if (numfmt_width(s) <= w || w < 2 * (int)sizeof more) {
        ui_fit(s, w, u->ell, buf, sizeof buf);
        term_text(u->status_y, x, w, style, 1, buf);
        return;
    }
    ui_fit(s, w - (int)strlen(more), u->ell, buf, sizeof buf);
    x += term_text(u->status_y, x, w - (int)strlen(more), style, 0, buf);
    term_text(u->status_y, x, u->cols - x, T_DIM, 1, more);
}

void status_draw(ui *u)
{
    const ed *e = u->e;
    int y = u->status_y;
    term_fill(y, 0, u->cols, T_NORMAL);
    if (u->mode == MODE_COMMAND) {
        size_t start;
        int cur;
        term_text(y, 0, 1, T_NORMAL, 0, ":");
        le_view(&u->le, u->cols - 2, &start, &cur);
        term_text(y, 1, u->cols - 2, T_NORMAL, 1, u->le.buf + start);
        term_cursor(y, 1 + cur);
        return;
    }
    if (u->mode == MODE_CONFIRM) {
        const char *q = e->confirm == CONFIRM_QUIT
                            ? "Unsaved changes. Save before quitting? (y)es (n)o (c)ancel"
                        : e->confirm == CONFIRM_RECOVER && u->rec_delete
                            ? "Delete the recovery file and its unsaved changes for good? "
                              "D (capital) deletes / (b)ack"
                        : e->confirm == CONFIRM_RECOVER || e->confirm == CONFIRM_ASK
                            ? ((int)strlen(e->question) <= u->cols ? e->question
                                                                    : e->question_short)
                        : e->confirm == CONFIRM_WRITE ? e->question
                            : "Unsaved changes will be lost. Continue? (y)es (n)o";
        /* A question wider than the line is never cut silently: where
         * its answers come first (the recovery question), its start and an
         * ellipsis; where they end it, its start, an ellipsis and the
         * answers after its last question mark. */
        if (numfmt_width(q) > u->cols && u->cols > 2) {
            const char *ell = term_utf8() ? "\xe2\x80\xa6" : ".", *close = strrchr(q, ')');
            const char *t;
            char head[ED_MSG];
            int x;
            size_t hn = close ? (size_t)(close - q) + 1 : 0;
            if (close && close[1] && hn < sizeof head) {
                memcpy(head, q, hn);
                head[hn] = '\0';
                if (numfmt_width(head) <= u->cols - 1) {
                    x = term_text(y, 0, u->cols - 1, T_EDIT, 0, q);
                    term_text(y, x, u->cols - x, T_EDIT, 1, ell);
                    return;
                }
            }
            /* The last sentence, the question itself, if it is short. */
            t = strrchr(q, '?');
            if (t) {
                const char *p = q, *dot = NULL;
                while ((p = strstr(p, ". ")) && p < t)
                    dot = p++;
                t = dot ? dot + 2 : t + 1;
            } else {
                t = q;
            }
            while (*t && numfmt_width(t) > u->cols / 2)
                do
                    t++;
                while (((unsigned char)*t & 0xC0) == 0x80);
            x = term_text(y, 0, u->cols - 1 - numfmt_width(t), T_EDIT, 0, q);
            x += term_text(y, x, 1, T_EDIT, 0, ell);
            term_text(y, x, u->cols - x, T_EDIT, 1, t);
            return;
        }
        term_text(y, 0, u->cols, T_EDIT, 1, q);
        return;
    }
    if (e->msg[0]) {
        /* A warning of the design (a glass beyond its range) stays in
         * view after the message of the command that caused it. */
        if (!e->msg_err && e->cmp.warn[0]) {
            char m[ED_MSG + SG_DIAG_MSG + 16];
            int w;
            snprintf(m, sizeof m, "%s  ", e->msg);
            if (numfmt_width(m) + 12 > u->cols) {
                /* No room for both: the message, cut where it must be. */
                status_msg(u, 0, T_NORMAL, e->msg);
                return;
            }
            w = term_text(y, 0, u->cols, T_NORMAL, 0, m);
            snprintf(m, sizeof m, "warning: %s", e->cmp.warn);
            status_msg(u, w, T_ERROR, m);
            return;
        }
        status_msg(u, 0, e->msg_err ? T_ERROR : T_NORMAL, e->msg);
        return;
    }
    if (u->mode == MODE_SETTINGS || u->mode == MODE_EXAMPLES || u->mode == MODE_SYSDATA ||
        u->mode == MODE_GLASSES)
        return;
    if (u->cmd_key) {
        term_text(y, 0, u->cols, T_EDIT, 1, "Esc: the next key is a command (Esc again: none)");
        return;
    }
    if (e->cmp.warn[0]) {
        /* A glass used beyond its range, say: the numbers are suspect. */
        char w[SG_DIAG_MSG + 16];
        snprintf(w, sizeof w, "warning: %s", e->cmp.warn);
        status_msg(u, 0, T_ERROR, w);
        return;
    }
    {
        /* A hint too long for the line ends at a word, in an ellipsis;
         * F1 lists every key. */
        char hint[256];
        ui_fit_words(u->focus == FOCUS_SHEET && sheet_text_col(e->col)
                         ? "Typing edits this text cell; : command line; Esc then a key runs a "
                           "command  F1 help"
                     : u->focus == FOCUS_RAY
                         ? "Ray: Left/Right choose  Up/Down step  Enter edit  c chief  F6-F9 "
                           "marginal  f back  F1 help"
                         : "? help  : command  Enter edit  Ins/d insert/delete  s stop  u/r "
                           "undo/redo  f ray  t settings  w save  q quit",
                     u->cols, u->ell, "", hint, sizeof hint);
        term_text(y, 0, u->cols, T_DIM, 1, hint);
    }
}

/* Draws s from line y on, wrapped at blanks to cols columns; returns the
 * lines used. */
static int wrap_text(int y, int rows, int cols, int style, const char *s)
{
    int n = 0;
    while (*s && y + n < rows) {
        int len = (int)strlen(s), take = len;
        if (len > cols) {
            take = cols;
            while (take > 0 && s[take] != ' ')
                take--;
            if (take == 0)
                take = cols;
        }
        term_text(y + n, 0, take, style, 1, s);
        s += take;
        while (*s == ' ')
            s++;
        n++;
    }
    return n;
}

/* The lens data editor's screen: the sheet, the ray selector, and the
 * analysis view or the results under them. */
static void main_draw(ui *u)
{
    sheet_draw(u);
    ray_draw(u);
    if (u->e->view.kind != VIEW_OFF)
        view_draw(u);
    else
        results_draw(u);
}

static const ui_panel *panel_of(int mode);

static void draw(ui *u)
{
    const ui_panel *p;
    term_erase();
    term_cursor(-1, -1);
    ui_layout(u);
    if (u->too_small) {
        char buf[128];
        int y = 0;
        /* Short lines, the size first, so a narrow terminal still shows
         * what it needs. */
        snprintf(buf, sizeof buf, "Need %dx%d,", MIN_COLS, MIN_ROWS);
        y += wrap_text(y, u->rows, u->cols, T_ERROR, buf);
        snprintf(buf, sizeof buf, "have %dx%d.", u->cols, u->rows);
        y += wrap_text(y, u->rows, u->cols, T_ERROR, buf);
        wrap_text(y, u->rows, u->cols, T_NORMAL, "Enlarge the terminal, or press q to quit.");
        term_flush();
        return;
    }
    title_draw(u);
    p = panel_of(u->mode);
    if (u->mode == MODE_COMMAND) {
        /* The ':' line stays over a panel that takes commands, else over
         * the sheet; the status line carries it. */
        p = panel_of(u->back_mode);
        if (!p->cmdline)
            p = panel_of(MODE_NORMAL);
        p->draw(u);
        status_draw(u);
    } else {
        p->draw(u);
        /* The Merit Function Editor shows the last command's message in
         * place of its keys. */
        if (p->status == UI_STATUS_ALWAYS || (p->status == UI_STATUS_MSG && u->e->msg[0]))
            status_draw(u);
    }
    term_flush();
}

static void hist_add(ui *u, const char *line)
{
    char *s;
    if (!line[0] || (u->nhist > 0 && strcmp(u->hist[u->nhist - 1], line) == 0))
        return;
    s = malloc(strlen(line) + 1);
    if (!s)
        return;
    strcpy(s, line);
    if (u->nhist == HIST_MAX) {
        free(u->hist[0]);
        memmove(u->hist, u->hist + 1, (HIST_MAX - 1) * sizeof u->hist[0]);
        u->nhist--;
    }
    u->hist[u->nhist++] = s;
}

static int command_key(ui *u, int key)
{
    char line[LE_MAX];
    if (key == K_UP || key == K_DOWN) {
        int p = u->hist_pos + (key == K_UP ? -1 : 1);
        if (p >= 0 && p <= u->nhist) {
            u->hist_pos = p;
            le_set(&u->le, p < u->nhist ? u->hist[p] : "");
        }
        return ED_HANDLED | ED_REDRAW;
    }
    switch (le_key(&u->le, key)) {
    case LE_ENTER:
        snprintf(line, sizeof line, "%s", u->le.buf);
        hist_add(u, line);
        u->mode = u->back_mode;
        return cmd_exec(u->e, line);
    case LE_CANCEL:
        u->mode = u->back_mode;
        return ED_HANDLED | ED_REDRAW;
    case LE_IGNORED: return ED_HANDLED;
    default: return ED_HANDLED | ED_REDRAW;
    }
}

static int confirm_key(ui *u, int key)
{
    ed *e = u->e;
    int kind = e->confirm, f;
    if (kind == CONFIRM_RECOVER) {
        /* Each answer has its own letter, so no key means one thing here
         * and the opposite in the next question.  Deleting takes a second,
         * deliberate capital D, asked after the keys typed so far are
         * dropped; any other key is ignored. */
        if (u->rec_delete) {
            if (key == 'D') {
                u->rec_delete = 0;
                e->confirm = CONFIRM_NONE;
                u->mode = MODE_NORMAL;
                return cmd_exec(e, e->pending2);
            }
            if (key == 'b' || key == 'B' || key == K_ESC) {
                u->rec_delete = 0;
                term_flush_input();
                return ED_HANDLED | ED_REDRAW;
            }
            return ED_HANDLED;
        }
        if (key == 'd' || key == 'D') {
            u->rec_delete = 1;
            term_flush_input();
            return ED_HANDLED | ED_REDRAW;
        }
        if (key == 'r' || key == 'R') {
            e->confirm = CONFIRM_NONE;
            u->mode = MODE_NORMAL;
            return cmd_exec(e, e->pending);
        }
        if (key != 'l' && key != 'L' && key != K_ESC)
            return ED_HANDLED;
        e->confirm = CONFIRM_NONE;
        u->mode = MODE_NORMAL;
        ed_msg(e, 0, "the recovery file is kept for later: :recover lists it");
        return ED_HANDLED | ED_REDRAW;
    }
    if (kind == CONFIRM_ASK) {
        if (key != 'y' && key != 'Y' && key != 'n' && key != 'N' && key != K_ESC &&
            key != 'c' && key != 'C')
            return ED_HANDLED;
        e->confirm = CONFIRM_NONE;
        u->mode = MODE_NORMAL;
        if (key == 'y' || key == 'Y')
            return cmd_exec(e, e->pending);
        ed_msg(e, 0, "not saved");
        return ED_HANDLED | ED_REDRAW;
    }
    if (key == K_ESC || key == 'c' || key == 'C' ||
        ((kind == CONFIRM_DISCARD || kind == CONFIRM_WRITE) && (key == 'n' || key == 'N'))) {
        e->confirm = CONFIRM_NONE;
        u->mode = MODE_NORMAL;
        ed_msg(e, 0, "cancelled");
        return ED_HANDLED | ED_REDRAW;
    }
    if (kind == CONFIRM_QUIT && (key == 'n' || key == 'N')) {
        e->confirm = CONFIRM_NONE;
        u->mode = MODE_NORMAL;
        return cmd_exec(e, "quit!");
    }
    if (key == 'y' || key == 'Y') {
        e->confirm = CONFIRM_NONE;
        u->mode = MODE_NORMAL;
        if (kind == CONFIRM_DISCARD || kind == CONFIRM_WRITE)
            return cmd_exec(e, e->pending);
        /* wq asks for a name when there is none, and itself asks before
         * replacing a file; it quits only once the design is saved. */
        f = cmd_exec(e, "wq");
        if (f & (ED_PROMPT | ED_CONFIRM | ED_ERROR))
            return f;
        return f | ED_QUIT;
    }
    return ED_HANDLED;
}

/* Progress of a long export on the status line, from half a second on,
 * at most ten times a second; Esc (read without waiting) cancels it.
 * Other keys typed meanwhile are dropped. */
static int export_progress(void *ctx, const char *what, size_t done, size_t total)
{
    ui *u = ctx;
    struct timespec ts;
    double t;
    char line[ED_MSG];
    int key;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    t = (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
    if (done == 0 || u->prog_t0 == 0.0 || t < u->prog_t0) {
        u->prog_t0 = t;
        u->prog_last = 0.0;
    }
    if (done >= total) {
        u->prog_t0 = 0.0;
        return 0;
    }
    if (t - u->prog_t0 >= 0.5 && t - u->prog_last >= 0.1) {
        u->prog_last = t;
        snprintf(line, sizeof line, "exporting %s: %.0f%% (%zu of %zu rays); Esc cancels",
                 what, 100.0 * (double)done / (double)total, done, total);
        term_text(u->status_y, 0, u->cols, T_EDIT, 1, line);
        term_flush();
    }
    while ((key = term_key(0)) != K_NONE)
        if (key == K_ESC || key == K_SIGNAL) {
            u->prog_t0 = 0.0;
            return 1;
        }
    return 0;
}

/* Each cycle of :opt on the status line; Esc or Ctrl-C (the key or
 * SIGINT) stops it, keeping the best design so far.  Another signal stops
 * it too and is handed to the loop, which then ends as for that signal.
 * Other keys typed meanwhile are dropped. */
static int opt_progress(void *ctx, int cycle, double merit, double step, double seconds)
{
    ui *u = ctx;
    char line[ED_MSG];
    int key;
    snprintf(line, sizeof line, "optimizing: cycle %d, merit %.6g, step %.3g, %.1f s; Esc stops",
             cycle, merit, step, seconds);
    term_text(u->status_y, 0, u->cols, T_EDIT, 1, line);
    term_flush();
    while ((key = term_key(0)) != K_NONE) {
        if (key == K_SIGNAL) {
            int sig = term_signal();
            if (sig != SIGINT)
                u->late_signal = sig;
            return 1;
        }
        if (key == K_ESC || key == K_CTRL('c'))
            return 1;
    }
    return 0;
}

/* :tol's systems on the status line, drawn and Esc read by the loop's
 * own thread only (the run's other threads report into it, as curses is
 * not theirs); Esc or Ctrl-C stops the run, which keeps the rows done. */
static pthread_t loop_thread;
static int tol_progress(void *ctx, int done, int total)
{
    ui *u = ctx;
    char line[ED_MSG];
    int key;
    if (!pthread_equal(pthread_self(), loop_thread))
        return 0;
    snprintf(line, sizeof line, "tolerancing: %d of %d systems; Esc stops, keeping the rows done",
             done, total);
    term_text(u->status_y, 0, u->cols, T_EDIT, 1, line);
    term_flush();
    while ((key = term_key(0)) != K_NONE) {
        if (key == K_SIGNAL) {
            int sig = term_signal();
            if (sig != SIGINT)
                u->late_signal = sig;
            return 1;
        }
        if (key == K_CTRL('c') || key == K_ESC)
            return 1;
    }
    return 0;
}

/* Keys that work whatever has the focus: the table in keys.c. */
static int global_key(ui *u, int key)
{
    const ui_key *k = ui_key_find(key);
    return k ? ui_key_run(u, k, key) : 0;
}

static int mouse(ui *u)
{
    int y, x, kind;
    term_mouse(&y, &x, &kind);
    if (u->mode != MODE_NORMAL)
        return ED_HANDLED;
    if (y > u->sheet_y && y <= u->sheet_y + u->sheet_h)
        return sheet_click(u, y, x, kind);
    if (y == u->ray_y)
        return ray_click(u, x, kind);
    if (y > u->res_y && y <= u->res_y + u->res_h)
        return results_click(u, y, kind);
    return ED_HANDLED;
}

/* A key in the lens data editor's screen itself. */
static int normal_key(ui *u, int key)
{
    int f;
    /* A fresh key clears the last message; the key's own command may set a
     * new one. */
    u->e->msg[0] = '\0';
    u->e->msg_err = 0;
    if (key == K_MOUSE)
        return mouse(u);
    /* Esc, then a key: that key is a command wherever the cursor is, so
     * commands stay one key away from a text cell, where every printable
     * key types.  (A terminal sends Alt-key as Esc, key: the same.) */
    if (u->cmd_key) {
        u->cmd_key = 0;
        if (key == K_ESC)
            return ED_HANDLED | ED_REDRAW;
        f = u->focus == FOCUS_RAY ? ray_key(u, key) : sheet_key_command(u, key);
        if (f)
            return f;
        return global_key(u, key);
    }
    if (key == K_ESC && u->focus == FOCUS_SHEET) {
        u->cmd_key = 1;
        return ED_HANDLED | ED_REDRAW;
    }
    f = u->focus == FOCUS_RAY ? ray_key(u, key) : sheet_key(u, key);
    if (f)
        return f;
    return global_key(u, key);
}

/* The settings take ':' for the command line, as the sheet does. */
static int settings_panel_key(ui *u, int key)
{
    if (key == ':') {
        ui_prompt(u, "");
        return ED_HANDLED | ED_REDRAW;
    }
    return settings_key(u, key);
}

/* Each mode's panel, as htop's PanelClass: how it draws, whether the
 * status line shows under it, what reads its keys, whether the ':' line
 * may open over it, and whether it ignores the mouse.  The ':' line's own
 * row draws the panel it opened over (draw()). */
static const ui_panel panels[] = {
    [MODE_NORMAL] = {main_draw, UI_STATUS_ALWAYS, normal_key, 0, 0},
    [MODE_EDIT_CELL] = {main_draw, UI_STATUS_ALWAYS, sheet_edit_key, 0, 1},
    [MODE_EDIT_RAY] = {main_draw, UI_STATUS_ALWAYS, ray_edit_key, 0, 1},
    [MODE_COMMAND] = {main_draw, UI_STATUS_ALWAYS, command_key, 0, 1},
    [MODE_CONFIRM] = {main_draw, UI_STATUS_ALWAYS, confirm_key, 0, 0},
    [MODE_HELP] = {help_draw, UI_STATUS_NONE, help_key, 0, 0},
    [MODE_SETTINGS] = {settings_draw, UI_STATUS_ALWAYS, settings_panel_key, 1, 0},
    [MODE_EXAMPLES] = {examples_draw, UI_STATUS_ALWAYS, examples_key, 0, 0},
    [MODE_SYSDATA] = {sysdata_draw, UI_STATUS_NONE, sysdata_key, 0, 0},
    [MODE_GLASSES] = {glasses_draw, UI_STATUS_NONE, glasses_key, 0, 0},
    [MODE_MESSAGES] = {messages_draw, UI_STATUS_NONE, messages_key, 0, 0},
    [MODE_MERIT] = {merit_draw, UI_STATUS_MSG, merit_key, 1, 0},
    [MODE_TOL] = {tol_draw, UI_STATUS_MSG, tol_key, 1, 0},
};

static const ui_panel *panel_of(int mode)
{
    return mode >= 0 && mode < (int)(sizeof panels / sizeof panels[0]) && panels[mode].draw
               ? &panels[mode]
               : &panels[MODE_NORMAL];
}

static int dispatch(ui *u, int key)
{
    const ui_panel *p;
    if (key == K_RESIZE) {
        /* The old scroll fitted the old width; the cursor's cell stays in
         * view from a fresh start. */
        u->left = 0;
        u->res_left = 0;
        return ED_HANDLED | ED_REDRAW;
    }
    if (u->too_small && u->mode == MODE_NORMAL)
        return key == 'q' || key == K_CTRL('c') ? ui_run(u, "quit") : ED_HANDLED;
    p = panel_of(u->mode);
    if (key == K_MOUSE && p->no_mouse)
        return ED_HANDLED;
    return p->key(u, key);
}

/* Acts on what a key or command asked for.  Returns 1 to leave the loop. */
static int act(ui *u, int f)
{
    if (f & ED_QUIT)
        return 1;
    if (f & ED_ERROR)
        term_beep();
    if (f & ED_CONFIRM) {
        /* A question is answered by keys pressed after it shows. */
        term_flush_input();
        u->mode = MODE_CONFIRM;
    }
    if (f & ED_PROMPT) {
        int back = u->mode == MODE_SETTINGS ? MODE_SETTINGS : MODE_NORMAL;
        ui_prompt(u, u->e->prompt_init);
        u->back_mode = back;
    }
    if (f & ED_SHOW_HELP)
        u->mode = MODE_HELP;
    if (f & ED_SHOW_SETTINGS)
        u->mode = MODE_SETTINGS;
    if (f & ED_SHOW_EXAMPLES)
        examples_open(u);
    if (f & ED_SHOW_SYSDATA) {
        u->sys_top = 0;
        u->mode = MODE_SYSDATA;
    }
    if (f & ED_SHOW_MERIT)
        u->mode = MODE_MERIT;
    if (f & ED_SHOW_TOL)
        u->mode = MODE_TOL;
    if (f & ED_SHOW_MESSAGES) {
        u->msg_top = -1;
        u->mode = MODE_MESSAGES;
    }
    if (f & ED_SHOW_GLASSES) {
        u->glass_top = 0;
        u->mode = MODE_GLASSES;
    }
    if (f & ED_RECOMPUTE)
        u->e->dirty = 1;
    return 0;
}

static int loop(ui *u)
{
    int redraw = 1;
    for (;;) {
        int key, f, due;
        if (u->e->dirty) {
            ed_recompute(u->e);
            redraw = 1;
        }
        /* What the status line shows goes into the history whole. */
        ed_msg_log(u->e);
        if (strcmp(u->warn_seen, u->e->cmp.warn) != 0) {
            snprintf(u->warn_seen, sizeof u->warn_seen, "%s", u->e->cmp.warn);
            if (u->warn_seen[0]) {
                char w[SG_DIAG_MSG + 16];
                snprintf(w, sizeof w, "warning: %s", u->warn_seen);
                ed_hist_add(u->e, 1, w);
            }
        }
        if (strcmp(u->fail_seen, u->e->cmp.build_msg) != 0) {
            snprintf(u->fail_seen, sizeof u->fail_seen, "%s", u->e->cmp.build_msg);
            if (u->fail_seen[0]) {
                char w[SG_DIAG_MSG + 16];
                snprintf(w, sizeof w, "cannot trace: %s", u->fail_seen);
                ed_hist_add(u->e, 1, w);
            }
        }
        if (redraw)
            draw(u);
        redraw = 0;
        /* The timeout bounds how long a signal can go unnoticed, and wakes
         * the loop when a delayed recovery write falls due. */
        due = rec_sync(u->e, 0);
        key = term_key(due >= 0 && due < 500 ? due : 500);
        if (key == K_NONE)
            continue;
        redraw = 1;
        if (key == K_SIGNAL) {
            int sig = term_signal();
            if (sig == SIGINT) {
                /* Ctrl-C from another process acts like the quit key. */
                if (u->mode != MODE_CONFIRM && act(u, ui_run(u, "quit")))
                    return 0;
                continue;
            }
            /* Not from the handler: here writing the file is safe.  It
             * already holds every change unless one is still delayed. */
            rec_sync(u->e, 1);
            return 128 + sig;
        }
        f = dispatch(u, key);
        if (act(u, f))
            return 0;
        if (u->late_signal) {
            rec_sync(u->e, 1);
            return 128 + u->late_signal;
        }
    }
}

static void usage(FILE *f)
{
    fputs("Usage: sagitta [edit] [FILE.json | FILE.zmx | FILE.zar] [--batch SCRIPT]\n"
          "The lens data editor.  A Zemax lens file or archive opens as a design (an\n"
          "archive is saved under another name).  Without --batch it needs a terminal;\n"
          "press F1 or ? inside for every key.  --batch runs the commands in SCRIPT\n"
          "(one a line, '-' for standard input) without a screen and stops at the\n"
          "first error.\n"
          "\n"
          "While a design has unsaved changes the editor keeps a copy in\n"
          "$XDG_STATE_HOME/sagitta/ (default ~/.local/state/sagitta/), removed when the\n"
          "design is saved or the editor quits normally.  After a crash, a signal or a\n"
          "lost terminal the next start offers to recover it; --batch only warns.\n",
          f);
}

/* Looks for recovery files that editors which died left for this design
 * (without a file: for any design).  Batch mode warns and goes on; the
 * screen asks about the newest one. */
static void offer_recovery(ed *e, const char *file, int batch)
{
    char dir[REC_PATH], abs[REC_PATH], when[64], q[ED_LINE / 2];
    rec_info *v;
    int n, i;
    if (rec_dir(dir, sizeof dir) != 0 || (file && rec_abspath(file, abs, sizeof abs) != 0))
        return;
    if (!batch)
        rec_sweep_temps(dir);
    n = rec_orphans(dir, file ? abs : NULL, NULL, &v);
    if (n <= 0)
        return;
    if (batch) {
        for (i = 0; i < n && i < 5; i++) {
            rec_time_text(v[i].time, when, sizeof when);
            fprintf(stderr,
                    "sagitta edit: warning: %s holds unsaved changes to %s from %s; "
                    "run the editor without --batch to recover them\n",
                    v[i].file, v[i].path[0] ? v[i].path : "an untitled design", when);
        }
        if (n > 5)
            fprintf(stderr, "sagitta edit: warning: %d more recovery files in %s\n", n - 5, dir);
    } else {
        const char *name = file ? file : v[0].path[0] ? v[0].path : "an untitled design";
        /* The answers must fit on the status line, so a long name shrinks
         * to its last component. */
        if (strlen(name) > 60 && strrchr(name, '/'))
            name = strrchr(name, '/') + 1;
        rec_time_text(v[0].time, when, sizeof when);
        snprintf(e->question, sizeof e->question,
                 "Recover unsaved changes to %.300s from %s? (r)ecover / (d)iscard / (l)ater%s",
                 name, when, n > 1 ? "  (more: :recover)" : "");
        snprintf(e->question_short, sizeof e->question_short,
                 "Recover unsaved changes? (r)ecover / (d)iscard / (l)ater: %.300s, %s", name,
                 when);
        cmd_quote(v[0].file, q, sizeof q);
        snprintf(e->pending, sizeof e->pending, "recover! %s", q);
        snprintf(e->pending2, sizeof e->pending2, "recover delete %s", q);
        e->confirm = CONFIRM_RECOVER;
    }
    free(v);
}

/* A design that cannot be opened may still have a recovery file. */
static void note_recovery(const char *file)
{
    char dir[REC_PATH], abs[REC_PATH], when[64];
    rec_info *v;
    int n;
    if (rec_dir(dir, sizeof dir) != 0 || rec_abspath(file, abs, sizeof abs) != 0)
        return;
    n = rec_orphans(dir, abs, NULL, &v);
    if (n > 0) {
        rec_time_text(v[0].time, when, sizeof when);
        fprintf(stderr,
                "sagitta edit: %s holds unsaved changes to it from %s; start the editor "
                "without a file and type :recover to load them\n",
                v[0].file, when);
    }
    free(v);
}

int sg_editor_main(int argc, char **argv)
{
    const char *file = NULL, *script = NULL;
    static ed e;
    static ui u;
    int i, status;
    struct stat st;

    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--batch") == 0 || strcmp(argv[i], "-b") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sagitta edit: --batch needs a script file\n");
                return 2;
            }
            script = argv[++i];
        } else if (strncmp(argv[i], "--batch=", 8) == 0) {
            script = argv[i] + 8;
        } else if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            fprintf(stderr, "sagitta edit: unknown option %s\n", argv[i]);
            usage(stderr);
            return 2;
        } else if (!file) {
            file = argv[i];
        } else {
            fprintf(stderr, "sagitta edit: one design at a time (%s and %s)\n", file, argv[i]);
            return 2;
        }
    }

    if (ed_init(&e) != SG_EOK) {
        fprintf(stderr, "sagitta edit: out of memory\n");
        return 1;
    }
    /* A script's load warnings go to stderr, as its errors do. */
    e.batch = script != NULL;
    if (e.cat && e.cat_msg[0]) {
        if (script)
            fprintf(stderr, "sagitta edit: warning: %s\n", e.cat_msg);
        else
            ed_msg(&e, 1, "%s", e.cat_msg);
    }
    if (file) {
        if (stat(file, &st) != 0 && errno == ENOENT) {
            /* Like vi: a new file under the name given. */
            doc_set_path(&e.doc, file);
            ed_msg(&e, 0, "%s: new file", file);
        } else {
            sg_diag d;
            sg_diag_clear(&d);
            if (doc_load(&e.doc, file, &d) != SG_EOK) {
                fprintf(stderr, "sagitta edit: %s\n", d.msg[0] ? d.msg : sg_strerror(d.code));
                note_recovery(file);
                ed_free(&e);
                return 1;
            }
            e.wave = e.doc.sys->primary_wave;
            ed_load_warnings(&e, file, &d);
            /* Solved values follow the design as it is opened. */
            sg_diag_clear(&d);
            if (sg_system_apply_solves(e.doc.sys, e.cat, &d) != SG_OK)
                ed_msg(&e, 1, "solves: %s", d.msg);
        }
    }
    /* A script is its own record of the edits, so batch mode writes no
     * recovery file; it only warns about those it finds. */
    e.rec.enabled = !script;
    offer_recovery(&e, file, script != NULL);
    /* Another editor on the file matters when this one may save over it;
     * a script is checked by the save itself (the file changed on disk). */
    if (file && !script)
        ed_note_holders(&e, file);
    if (script) {
        status = ed_batch(&e, script);
        ed_free(&e);
        return status;
    }
    if (!isatty(STDIN_FILENO) || !isatty(STDOUT_FILENO)) {
        fprintf(stderr, "sagitta edit: the editor needs a terminal; use --batch SCRIPT "
                        "to run commands without one\n");
        ed_free(&e);
        return 1;
    }
    if (!e.msg[0] && !e.cat)
        ed_msg(&e, 1, "%s", e.cat_msg);
    else if (!e.msg[0])
        ed_msg(&e, 0, "%s%s: %d surfaces.  Press ? for help.",
               doc_path(&e.doc) ? "" : "new design",
               doc_path(&e.doc) ? doc_path(&e.doc) : "", e.doc.sys->nsurf);

    memset(&u, 0, sizeof u);
    u.e = &e;
    u.step_exp = 1;
    u.ray_item = RAY_HX;
    e.progress = export_progress;
    e.opt_progress = opt_progress;
    e.tol_progress = tol_progress;
    loop_thread = pthread_self();
    e.progress_ctx = &u;
    if (term_init() != 0) {
        ed_free(&e);
        return 1;
    }
    u.ell = term_utf8() ? "\xe2\x80\xa6" : "~";
    e.col = COL_RADIUS;
    if (e.confirm == CONFIRM_RECOVER) {
        /* Keys typed before the question showed are not its answer. */
        term_flush_input();
        u.mode = MODE_CONFIRM;
    }
    status = loop(&u);
    term_end();
    /* Quitting is a clean end; a signal keeps the file for the next start. */
    if (status == 0)
        rec_finish(&e);
    for (i = 0; i < u.nhist; i++)
        free(u.hist[i]);
    if (u.ex)
        ed_examples_free(u.ex, u.nex);
    merit_free(&u);
    ed_free(&e);
    return status;
}
