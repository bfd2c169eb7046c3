/*
 * keys.c - the keys that work anywhere, as one table.
 *
 * The event loop dispatches from it and the help screen lists it, so a
 * key cannot be bound without being documented; tests/ui/test_keys.c
 * holds sagitta(1)'s "Keys anywhere" to the same table.
 */
#include <stddef.h>

#include "term.h"
#include "ui.h"

static int show_help(ui *u, int key)
{
    (void)key;
    u->mode = MODE_HELP;
    return ED_HANDLED | ED_REDRAW;
}

static int show_settings(ui *u, int key)
{
    (void)key;
    u->mode = MODE_SETTINGS;
    return ED_HANDLED | ED_REDRAW;
}

static int show_sysdata(ui *u, int key)
{
    (void)key;
    u->sys_top = 0;
    u->mode = MODE_SYSDATA;
    return ED_HANDLED | ED_REDRAW;
}

static int show_merit(ui *u, int key)
{
    (void)key;
    u->mode = MODE_MERIT;
    return ED_HANDLED | ED_REDRAW;
}

static int show_tol(ui *u, int key)
{
    (void)key;
    u->mode = MODE_TOL;
    return ED_HANDLED | ED_REDRAW;
}

/* The method and the wavelength step from the current ones. */
static int next_method(ui *u, int key)
{
    static const char *const methods[] = {"classic", "mpfr", "precise"};
    (void)key;
    return ui_run(u, "method %s", methods[u->e->method % 3]);
}

static int next_wave(ui *u, int key)
{
    (void)key;
    return ui_run(u, "wave %d", (u->e->wave + 1) % u->e->doc.sys->nwave + 1);
}

static int toggle_focus(ui *u, int key)
{
    (void)key;
    u->focus = u->focus == FOCUS_SHEET ? FOCUS_RAY : FOCUS_SHEET;
    return ED_HANDLED | ED_REDRAW;
}

static int repaint(ui *u, int key)
{
    (void)key;
    term_repaint();
    return ED_HANDLED | ED_REDRAW;
}

static int suspend(ui *u, int key)
{
    (void)u;
    (void)key;
    term_suspend();
    return ED_HANDLED | ED_REDRAW;
}

#define RUN(text) UI_KEY_RUN, text, NULL
#define PROMPT(text) UI_KEY_PROMPT, text, NULL
#define ACT(fn) UI_KEY_ACT, NULL, fn
#define DOC UI_KEY_DOC, NULL, NULL

/* In the help screen's order; a '\n' in the help starts a line of its own
 * under the text.  DOC rows are keys the loop reads before this table
 * (Esc, the mouse): listed here so the help and the man page show them. */
const ui_key ui_keys[] = {
    {{K_F(1), '?'}, "F1 ?", "this help (Esc or q closes it)", ACT(show_help)},
    {{':'}, ":", "command line, from any cell (Up/Down: history; Esc cancels)\n"
                 "(a cell text that begins with ':' is typed after Enter or F2)", PROMPT("")},
    {{'q', K_F(10), K_CTRL('q'), K_CTRL('c')}, "q F10 Ctrl-C",
     "quit (asks first when there are unsaved changes)", RUN("quit")},
    {{'u'}, "u", "undo", RUN("undo")},
    {{'r', K_CTRL('r')}, "r Ctrl-R", "redo", RUN("redo")},
    {{'w', K_CTRL('s')}, "w Ctrl-S", "save (asks for a name when the design has none)", RUN("save")},
    {{K_CTRL('w')}, "Ctrl-W", "save as", PROMPT("save ")},
    {{'o'}, "o", "open a design file", PROMPT("open ")},
    {{'e'}, "e", "open a bundled example", RUN("example")},
    {{'n'}, "n", "new design", RUN("new")},
    {{'x'}, "x", "export the ray table (:export FILE [csv|json|text|hdf5] [ray|fan N|xfan N|grid N])\n"
                 "or the analysis view on show (:export FILE.png|svg|pdf)", PROMPT("export ")},
    {{'g'}, "g", "analysis view below the sheet (layout, spot, fan, opd, wave, mtf,\n"
                 "psf, encircled; :view NAME|off); it follows every edit", RUN("view next")},
    {{'t', K_F(4)}, "t F4", "system settings: wavelengths, fields, aperture, aiming, method",
     ACT(show_settings)},
    {{'m'}, "m", "next trace method (precise, classic, mpfr)", ACT(next_method)},
    {{'#'}, "#", "digits of agreement with an MPFR trace, on or off", RUN("digits toggle")},
    {{K_F(3)}, "F3", "system data: pupils, image height, NA, working F/#, magnification",
     ACT(show_sysdata)},
    {{K_CTRL('e')}, "Ctrl-E", "Merit Function Editor: rows and values, live; Enter edits (:merit)",
     ACT(show_merit)},
    {{K_CTRL('t')}, "Ctrl-T", "Tolerance Data Editor: rows and the last :tol run; s runs it (:tol)",
     ACT(show_tol)},
    {{K_CTRL('a')}, "Ctrl-A", "the next configuration of a multi-configuration design (:config N)",
     RUN("config next")},
    {{0}, "Esc, then a key", "run that key's command even in a text cell (Alt-key does the same)",
     DOC},
    {{'v'}, "v", "next wavelength for the ray", ACT(next_wave)},
    {{'c', K_F(5)}, "c F5", "chief ray (Px = Py = 0)", ACT(ray_quick)},
    {{K_F(6), K_F(7), K_F(8), K_F(9)}, "F6 F7 F8 F9", "marginal ray: top, bottom, right, left",
     ACT(ray_quick)},
    {{'p'}, "p", "next marginal ray", ACT(ray_quick)},
    {{'f'}, "f", "move between the spreadsheet and the ray selector", ACT(toggle_focus)},
    {{'{', '}'}, "{ }", "scroll the results left and right", ACT(results_key)},
    {{K_CTRL('l')}, "Ctrl-L", "repaint the screen", ACT(repaint)},
    {{K_CTRL('z')}, "Ctrl-Z", "suspend", ACT(suspend)},
    {{0}, "mouse", "click selects a cell or ray item, double-click edits, wheel scrolls", DOC},
    {{0}, NULL, NULL, DOC},
};

const ui_key *ui_key_find(int key)
{
    const ui_key *k;
    int i;
    for (k = ui_keys; k->label; k++)
        for (i = 0; i < UI_KEY_MAX && k->keys[i]; i++)
            if (k->keys[i] == key)
                return k;
    return NULL;
}

int ui_key_run(ui *u, const ui_key *k, int key)
{
    switch (k->kind) {
    case UI_KEY_RUN: return ui_run(u, "%s", k->text);
    case UI_KEY_PROMPT: ui_prompt(u, k->text); return ED_HANDLED | ED_REDRAW;
    case UI_KEY_ACT: return k->act(u, key);
    default: return 0;
    }
}
