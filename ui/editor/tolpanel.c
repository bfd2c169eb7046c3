/* tolpanel.c - the Tolerance Data Editor (Ctrl-T, :tol show): the
 * design's tolerance rows as Zemax's editor lists them (Type, Int1, Int2,
 * Int3, Min, Max), with the last :tol run's criterion at each row's min
 * and max while the document is the one it ran on.  Keys move a cursor;
 * every change is a "tol" command, so it is undoable and works the same
 * in batch mode; s runs the sensitivity analysis (:tol). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

static const struct {
    const char *head;
    int w;
} col[] = {{"Row", 4},  {"Type", 5},  {"Int1", 5},           {"Int2", 5},
           {"Int3", 5}, {"Min", 11},  {"Max", 11},           {"Crit(min)", 12},
           {"Crit(max)", 12}};
#define NCOL ((int)(sizeof col / sizeof col[0]))

static void put(const ui *u, int y, int style, const char *s)
{
    char fit[1024];
    ui_fit(s, u->cols, u->ell, fit, sizeof fit);
    term_text(y, 0, u->cols, style, 1, fit);
}

/* The last run, if it is the document's. */
static const sg_tol_result *current(const ui *u)
{
    return u->e->tol_have && u->e->tol_id == u->e->doc.id ? &u->e->tol_res : NULL;
}

/* The text of screen column k for row i. */
static void cell(const ui *u, const sg_tol_result *r, int i, int k, char *buf, size_t n)
{
    const sg_tol_operand *o = &u->e->doc.sys->tol.op[i];
    buf[0] = '\0';
    if (k == 0) {
        snprintf(buf, n, "%d", i + 1);
    } else if (k == 1) {
        snprintf(buf, n, "%s", sg_tol_name(o->type));
    } else if (k <= 6) {
        if (tol_col_used(o, k - 1))
            numfmt_cell(tol_col_value(o, k - 1), col[k].w, u->ell, buf, n);
    } else if (r && i < r->nsens) {
        const sg_tol_value *v = k == 7 ? &r->sens[i].at_min : &r->sens[i].at_max;
        if (v->status == SG_OK)
            numfmt_cell(v->criterion, col[k].w, u->ell, buf, n);
        else
            snprintf(buf, n, "%s", sg_err_name(v->status));
    } else {
        snprintf(buf, n, "-");
    }
}

void tol_draw(ui *u)
{
    const sg_tolerances *t = &u->e->doc.sys->tol;
    const sg_tol_result *r = current(u);
    char line[1024], buf[64], head[160];
    int h = u->rows - 6, y, i, k, x, nrows = t->nop + 1;
    if (u->tol_sel > t->nop)
        u->tol_sel = t->nop;
    if (u->tol_sel < 0)
        u->tol_sel = 0;
    if (u->tol_sel < u->tol_top)
        u->tol_top = u->tol_sel;
    if (u->tol_sel >= u->tol_top + h)
        u->tol_top = u->tol_sel - h + 1;
    term_fill(0, 0, u->cols, T_TITLE);
    if (r) {
        numfmt_shortest(r->nominal.criterion, buf, sizeof buf);
        snprintf(head, sizeof head, " Tolerance Data Editor   nominal %s%s", buf,
                 r->stopped ? "   (stopped: the rows done)" : "");
    } else {
        snprintf(head, sizeof head, " Tolerance Data Editor   s: sensitivity (:tol)");
    }
    put(u, 0, T_TITLE, head);
    term_fill(1, 0, u->cols, T_HEADER);
    for (k = 0, x = 0; k < NCOL; k++) {
        snprintf(buf, sizeof buf, k <= 1 ? "%-*s" : "%*s", col[k].w, col[k].head);
        term_text(1, x, u->cols - x > 0 ? u->cols - x : 0, T_HEADER, 0, buf);
        x += col[k].w + 1;
    }
    for (y = 2; y < 2 + h; y++)
        term_fill(y, 0, u->cols, T_NORMAL);
    for (i = u->tol_top, y = 2; i < nrows && y < 2 + h; i++, y++) {
        if (i == t->nop) {
            put(u, y, i == u->tol_sel ? T_ROWSEL : T_DIM,
                "     (end; i: a row here)");
            continue;
        }
        for (k = 0, x = 0; k < NCOL; k++) {
            int style = T_NORMAL;
            cell(u, r, i, k, line, sizeof line);
            snprintf(buf, sizeof buf, k <= 1 ? "%-*s" : "%*s", col[k].w, line);
            if (i == u->tol_sel)
                style = k >= 1 && k <= 6 && k - 1 == u->tol_col ? T_CURSOR : T_ROWSEL;
            term_text(y, x, u->cols - x > 0 ? u->cols - x : 0, style, 0, buf);
            x += col[k].w + 1;
        }
    }
    /* The compensators and the run's RSS. */
    term_fill(u->rows - 4, 0, u->cols, T_NORMAL);
    term_fill(u->rows - 3, 0, u->cols, T_NORMAL);
    {
        size_t len = (size_t)snprintf(line, sizeof line, "compensators:");
        for (k = 0; k < t->ncomp && len < sizeof line; k++)
            len += (size_t)snprintf(line + len, sizeof line - len, " surface %d %s %g to %g%s",
                                    t->comp[k].surface, t->comp[k].param, t->comp[k].min,
                                    t->comp[k].max, k + 1 < t->ncomp ? "," : "");
        if (!t->ncomp && len < sizeof line)
            snprintf(line + len, sizeof line - len, " none");
    }
    put(u, u->rows - 4, T_DIM, line);
    if (r) {
        numfmt_shortest(r->rss, buf, sizeof buf);
        snprintf(line, sizeof line, "%d of %d rows done; RSS change %s", r->nsens, t->nop, buf);
    } else {
        snprintf(line, sizeof line, "%s", u->e->tol_have ? "the last run was made on another "
                                                           "state of the design; s runs again"
                                                         : "no run yet; s runs the sensitivity");
    }
    put(u, u->rows - 3, T_DIM, line);
    term_fill(u->rows - 2, 0, u->cols, T_NORMAL);
    snprintf(line, sizeof line, " %d tolerance row%s; column %s", t->nop,
             t->nop == 1 ? "" : "s", tol_cols[u->tol_col]);
    put(u, u->rows - 2, T_DIM, line);
    term_fill(u->rows - 1, 0, u->cols, T_NORMAL);
    put(u, u->rows - 1, T_NORMAL,
        "s sensitivity  Enter edit  i insert  d delete  u undo  r redo  : command  Esc closes");
}

int tol_key(ui *u, int key)
{
    const sg_tolerances *t = &u->e->doc.sys->tol;
    char line[128], buf[64];
    switch (key) {
    case K_UP:
    case 'k': u->tol_sel--; break;
    case K_DOWN:
    case 'j': u->tol_sel++; break;
    case K_LEFT:
    case 'h': u->tol_col = u->tol_col > 0 ? u->tol_col - 1 : 0; break;
    case K_RIGHT:
    case 'l': u->tol_col = u->tol_col < TOL_NCOLS - 1 ? u->tol_col + 1 : TOL_NCOLS - 1; break;
    case K_PGUP: u->tol_sel -= u->rows - 6; break;
    case K_PGDN: u->tol_sel += u->rows - 6; break;
    case 's': return ui_run(u, "tol");
    case 'i':
    case K_INS: return ui_run(u, "tol insert %d", u->tol_sel + 1);
    case 'd':
    case K_DEL:
        if (u->tol_sel >= t->nop)
            return ED_HANDLED;
        return ui_run(u, "tol delete %d", u->tol_sel + 1);
    case 'u': return ui_run(u, "undo");
    case 'r': return ui_run(u, "redo");
    case K_ENTER:
        /* Edit the cell on the ':' line, its value ready to change. */
        if (u->tol_sel >= t->nop)
            return ui_run(u, "tol insert %d", u->tol_sel + 1);
        if (u->tol_col == 0)
            snprintf(buf, sizeof buf, "%s", sg_tol_name(t->op[u->tol_sel].type));
        else
            numfmt_shortest(tol_col_value(&t->op[u->tol_sel], u->tol_col), buf, sizeof buf);
        snprintf(line, sizeof line, "tol set %d %s %s", u->tol_sel + 1, tol_cols[u->tol_col],
                 buf);
        ui_prompt(u, line);
        return ED_HANDLED | ED_REDRAW;
    case ':': ui_prompt(u, ""); return ED_HANDLED | ED_REDRAW;
    case K_ESC:
    case 'q':
    case K_CTRL('t'): u->mode = MODE_NORMAL; break;
    default: return ED_HANDLED;
    }
    return ED_HANDLED | ED_REDRAW;
}
