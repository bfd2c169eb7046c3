/* help.c - the help screen: every key, then every command. */
#include <stdio.h>
#include <string.h>

#include "cmd.h"
#include "recover.h"
#include "term.h"
#include "ui.h"

const char *const ui_key_help[] = {
    "#Anywhere",
    "F1 ?            this help (Esc or q closes it)",
    ":               command line, from any cell (Up/Down: history; Esc cancels)",
    "                (a cell text that begins with ':' is typed after Enter or F2)",
    "q F10 Ctrl-C    quit (asks first when there are unsaved changes)",
    "u               undo",
    "r Ctrl-R        redo",
    "w Ctrl-S        save (asks for a name when the design has none)",
    "Ctrl-W          save as",
    "o               open a design file",
    "e               open a bundled example",
    "n               new design",
    "x               export the ray table (:export FILE [csv|json|text|hdf5] [ray|fan N|xfan N|grid N])",
    "                or the analysis view on show (:export FILE.png|svg|pdf)",
    "g               analysis view below the sheet (layout, spot, fan, opd, wave, mtf,",
    "                psf, encircled; :view NAME|off); it follows every edit",
    "t F4            system settings: wavelengths, fields, aperture, aiming, method",
    "m               next trace method (precise, classic, mpfr)",
    "#               digits of agreement with an MPFR trace, on or off",
    "F3              system data: pupils, image height, NA, working F/#, magnification",
    "Ctrl-E          Merit Function Editor: rows and values, live; Enter edits (:merit)",
    "Ctrl-A          the next configuration of a multi-configuration design (:config N)",
    "Esc, then a key run that key's command even in a text cell (Alt-key does the same)",
    "v               next wavelength for the ray",
    "c F5            chief ray (Px = Py = 0)",
    "F6 F7 F8 F9     marginal ray: top, bottom, right, left",
    "p               next marginal ray",
    "f               move between the spreadsheet and the ray selector",
    "{ }             scroll the results left and right",
    "Ctrl-L          repaint the screen",
    "Ctrl-Z          suspend",
    "mouse           click selects a cell or ray item, double-click edits, wheel scrolls",
    "",
    "#Spreadsheet",
    "arrows hjkl     move",
    "Tab Shift-Tab   next / previous cell",
    "PgUp PgDn       page up / down",
    "Home End        first / last column",
    "< >             first / last surface",
    "Enter F2        edit the cell (Enter sets, Esc cancels; Tab, Up, Down move)",
    "0-9 + - . i n   number cell: type a value (i n: inf, infinity, nan); a key",
    "                that can begin the cell's value never runs a command there",
    "a-z             Type, Aperture, Order, After: a choice's first letter types it",
    "any character   Comment, Material: type (any character but a leading ':')",
    "A-Z             type, in any cell (upper case never names a command)",
    "Esc, then a key run that key's command from any cell (function keys work too)",
    "Backspace       edit the cell starting from empty",
    "Space           Semi-Dia: fix or free the aperture (U); Type: switch standard/asphere;",
    "                Order, Aft Ord: 0/1; After: explicit/reverse",
    "i Insert        insert a surface before this one (number cells: Insert)",
    "a               insert a surface after this one",
    "d Delete        delete this surface",
    "s               make this surface the stop",
    "",
    "#Cells",
    "Radius          a number; Infinity or 0 is flat",
    "Material        empty or AIR, MIRROR, a catalog glass (N-BK7), or a fixed index (1.5)",
    "Semi-Dia        a number; a trailing U fixes it so rays beyond it are vignetted",
    "Type            STANDARD or EVENASPH; an r^n term makes a surface EVENASPH",
    "",
    "#Ray selector (f)",
    "Left Right Tab  choose Fld (field of the design), Hx, Hy, Px, Py or Wave",
    "Up Down k j     step the value in decimal (Fld, Wave: next / previous)",
    "[ ]             smaller / larger step (1, 0.1 ... 0.000001)",
    "Home            set the value to 0",
    "Enter 0-9 . - + type a value",
    "Esc f           back to the spreadsheet",
    "",
    "#Settings (t)",
    "Up Down         choose an item",
    "Enter           edit it (as a command on the ':' line)",
    "Left Right Spc  cycle a choice",
    "a d p           add, delete a wavelength or field; make a wavelength primary",
    "< >             move a wavelength up / down the list",
    "F               wavelengths F, d, C (primary d), as :wavelength preset FdC",
    "Esc q t         close",
    "",
    "#Results",
    "x y z           intersection in the surface's local frame (:global, in surface S's)",
    "l m n           direction cosines after the surface",
    "residual        |z - sag(x, y)| of the reported point",
    "err bound       bound on the coordinate error against exact arithmetic",
    "err est         classic's figure instead: an estimate, not a bound",
    "path            distance from the previous surface",
    "Panel           the cursor's surface whole: every digit of x..n, residual, bound",
    "status          OK, MISS, TIR, VIGNETTED, NOT REACHED ...",
    "dig x ...       digits agreeing with the MPFR trace (with #)",
    "",
    "#Recovery",
    "While the design has unsaved changes, a copy is kept up to date after every change in",
    "  $XDG_STATE_HOME/sagitta/ (default ~/.local/state/sagitta/), one FILE-HASH-PID.sgrec",
    "  (or untitled-PID.sgrec) per session.  Saving, or quitting with q or :quit!, removes it.",
    "=recdir",
    "After a crash, kill, SIGHUP, SIGTERM or a closed terminal the copy stays, and the next",
    "  start on that file (or without a file: the newest copy of any) asks: r (recover) loads",
    "  it as unsaved changes to the original file, l (later, or Esc) keeps it, d (discard)",
    "  asks again and only a capital D then deletes it (b or Esc goes back).  Other keys,",
    "  y and n among them, and keys typed before the question are ignored.",
    ":recover         lists the copies left by editors that died; :recover N loads one",
    "--batch          never asks; it prints a warning naming the copy and goes on",
    "",
    NULL,
};

static int nlines(void)
{
    int n = 0;
    while (ui_key_help[n])
        n++;
    return n + 2 + cmd_count();
}

/* Line i of the help text into buf; returns its style. */
static int line(int i, char *buf, size_t n)
{
    int k = 0;
    while (ui_key_help[k])
        k++;
    if (i < k) {
        const char *s = ui_key_help[i];
        if (strcmp(s, "=recdir") == 0) {
            /* Where the copies go on this system, with the variables read. */
            char dir[REC_PATH];
            if (rec_dir(dir, sizeof dir) == 0)
                snprintf(buf, n, "    Here: %.400s/", dir);
            else
                snprintf(buf, n, "    Here: nowhere, since neither XDG_STATE_HOME nor HOME is set");
            return T_DIM;
        }
        /* "#Name" is a heading; "#   ..." is the line of the # key. */
        if (s[0] == '#' && s[1] != ' ') {
            snprintf(buf, n, "%s", s + 1);
            return T_HEADER;
        }
        snprintf(buf, n, "  %s", s);
        return T_NORMAL;
    }
    i -= k;
    if (i == 0) {
        snprintf(buf, n, "Commands (type after ':'; a batch script holds one per line)");
        return T_HEADER;
    }
    if (i == 1) {
        snprintf(buf, n, "  %-44s %s", "SURFACE: a number, obj, ima, stop or .", "");
        return T_DIM;
    }
    i -= 2;
    snprintf(buf, n, "  %-44s %s", cmd_usage(i), cmd_help(i));
    return T_NORMAL;
}

/* Where the next row of text s ends at width w: at the last blank that
 * fits, or at w when a word is longer than that. */
static int row_end(const char *s, int w)
{
    int len = (int)strlen(s), k;
    if (len <= w)
        return len;
    for (k = w; k > w / 2; k--)
        if (s[k] == ' ')
            return k;
    return w;
}

/* Lays out line buf at width cols: calls out for each row (its offset and
 * length, continuation rows indented by 6) and returns the rows. */
static int wrap(const char *buf, int cols, void (*out)(void *, int, const char *, int, int),
                void *arg)
{
    int off = 0, len = (int)strlen(buf), r = 0;
    do {
        int ind = r == 0 ? 0 : 6, w = cols - ind, n;
        if (w < 10)
            w = cols, ind = 0;
        n = row_end(buf + off, w);
        if (out)
            out(arg, r, buf + off, n, ind);
        off += n;
        while (buf[off] == ' ')
            off++;
        r++;
    } while (off < len);
    return r;
}

static int total_rows(int w)
{
    char buf[512];
    int i, n = nlines(), r = 0;
    for (i = 0; i < n; i++) {
        line(i, buf, sizeof buf);
        r += wrap(buf, w, NULL, NULL);
    }
    return r;
}

typedef struct drawing {
    ui *u;
    int first, h, style;
} drawing;

static void put_row(void *arg, int r, const char *s, int n, int ind)
{
    drawing *d = arg;
    int y = 1 + d->first + r - d->u->help_top;
    char buf[512];
    if (y < 1 || y > d->h)
        return;
    snprintf(buf, sizeof buf, "%*s%.*s", ind, "", n, s);
    term_text(y, 0, d->u->cols, d->style, 1, buf);
}

void help_draw(ui *u)
{
    char buf[512];
    int h = u->rows - 2, i, n = nlines(), total = total_rows(u->cols), r = 0;
    drawing d;
    if (u->help_top > total - h)
        u->help_top = total - h;
    if (u->help_top < 0)
        u->help_top = 0;
    term_fill(0, 0, u->cols, T_TITLE);
    term_text(0, 0, u->cols, T_TITLE, 1,
              " sagitta help   Up/Down PgUp/PgDn scroll, Esc closes");
    for (i = 1; i <= h; i++)
        term_fill(i, 0, u->cols, T_NORMAL);
    d.u = u;
    d.h = h;
    /* Long lines wrap at a blank, so every word can be read at any width. */
    for (i = 0; i < n && r < u->help_top + h; i++) {
        d.style = line(i, buf, sizeof buf);
        d.first = r;
        r += wrap(buf, u->cols, put_row, &d);
    }
    snprintf(buf, sizeof buf, " lines %d-%d of %d", u->help_top + 1,
             u->help_top + h < total ? u->help_top + h : total, total);
    term_text(u->rows - 1, 0, u->cols, T_DIM, 1, buf);
}

int ui_page_key(int *top, int h, int key, int end)
{
    switch (key) {
    case K_UP:
    case 'k': (*top)--; return 1;
    case K_DOWN:
    case 'j': (*top)++; return 1;
    case K_PGUP: *top -= h - 1; return 1;
    case K_PGDN:
    case ' ': *top += h - 1; return 1;
    case K_HOME:
    case '<': *top = 0; return 1;
    case K_END:
    case '>': *top = end; return 1;
    default: return 0;
    }
}

int help_key(ui *u, int key)
{
    if (ui_page_key(&u->help_top, u->rows - 2, key, total_rows(u->cols)))
        return ED_HANDLED | ED_REDRAW;
    switch (key) {
    case K_ESC:
    case 'q':
    case '?':
    case K_F(1):
    case K_ENTER: u->mode = MODE_NORMAL; return ED_HANDLED | ED_REDRAW;
    default: return ED_HANDLED;
    }
}
