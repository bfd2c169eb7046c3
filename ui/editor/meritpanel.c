/* meritpanel.c - the Merit Function Editor (Ctrl-E, :merit): the design's
 * operand rows as Zemax's editor lists them (Type, Int1, Int2, Hx, Hy, Px,
 * Py, Target, Weight, Value, % Contrib) with the default part as one line,
 * values live after every edit.  Keys move a cursor; every change is a
 * "merit" command, so it is undoable and works the same in batch mode. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cmd.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

/* Screen columns: label, width, and whether it shows below 110 columns
 * (Hx to Py then live in the detail line under the table). */
static const struct {
    const char *head;
    int w, narrow;
} col[] = {{"Row", 4, 1},    {"Type", 5, 1},    {"Int1", 5, 1},   {"Int2", 5, 1},
           {"Hx", 7, 0},     {"Hy", 7, 0},      {"Px", 7, 0},     {"Py", 7, 0},
           {"Target", 12, 1}, {"Weight", 8, 1}, {"Value", 14, 1}, {"% Contrib", 9, 1}};
#define NCOL ((int)(sizeof col / sizeof col[0]))
/* Screen column k shows merit_cols[k - 1] for k 1 to 9. */

/* A line at y, cut with an ellipsis when the screen is narrower. */
static void put(const ui *u, int y, int style, const char *s)
{
    char fit[1024];
    ui_fit(s, u->cols, u->ell, fit, sizeof fit);
    term_text(y, 0, u->cols, style, 1, fit);
}

/* The same on two lines, broken at a blank; cut only past the second. */
static void put2(const ui *u, int y, int style, const char *s)
{
    int w = u->cols, len = (int)strlen(s), k = len;
    char first[1024];
    if (len > w) {
        for (k = w; k > w / 2 && s[k] != ' '; k--)
            ;
        if (k <= w / 2)
            k = w;
    }
    snprintf(first, sizeof first, "%.*s", k, s);
    put(u, y, style, first);
    while (s[k] == ' ')
        k++;
    put(u, y + 1, style, s + (k < len ? k : len));
}

/* The merit function of the document as it is now: evaluated once per
 * document state. */
static void evaluate(ui *u)
{
    sg_diag d;
    if (u->mf_id != 0 && u->mf_id == u->e->doc.id)
        return;
    merit_free(u);
    sg_diag_clear(&d);
    u->mf_ok = sg_merit_eval(u->e->doc.sys, u->e->cat, &u->mf_res, &d) == SG_OK;
    if (!u->mf_ok)
        snprintf(u->mf_why, sizeof u->mf_why, "%s", d.msg[0] ? d.msg : "cannot be evaluated");
    u->mf_id = u->e->doc.id;
}

void merit_free(ui *u)
{
    sg_merit_result_free(&u->mf_res);
    memset(&u->mf_res, 0, sizeof u->mf_res);
    u->mf_ok = 0;
    u->mf_why[0] = '\0';
    u->mf_id = 0;
}

static void num(double v, int w, const ui *u, char *buf, size_t n)
{
    numfmt_cell(v, w, u->ell, buf, n);
}

/* The text of screen column k for operand i (row in the result r). */
static void cell(const ui *u, int i, int k, char *buf, size_t n)
{
    const sg_operand *o = &u->e->doc.sys->merit.op[i];
    buf[0] = '\0';
    if (k == 0)
        snprintf(buf, n, "%d", i + 1);
    else if (k == 1)
        snprintf(buf, n, "%s", sg_op_name(o->type));
    else if (k <= 9)
        num(merit_col_value(o, k - 1), col[k].w, u, buf, n);
    else if (u->mf_ok && i < u->mf_res.nrow)
        num(k == 10 ? u->mf_res.row[i].value : u->mf_res.row[i].contribution, col[k].w, u, buf,
            n);
    else
        snprintf(buf, n, "-");
}

static int shown(const ui *u, int k)
{
    return col[k].narrow || u->cols >= 110;
}

void merit_draw(ui *u)
{
    const sg_merit *mf = &u->e->doc.sys->merit;
    const sg_merit_result *r = &u->mf_res;
    char line[1024], buf[64], head[96];
    int h = u->rows - 6, y, i, k, x, nrows = mf->nop + 1;
    evaluate(u);
    if (u->mf_sel > mf->nop)
        u->mf_sel = mf->nop;
    if (u->mf_sel < 0)
        u->mf_sel = 0;
    if (u->mf_sel < u->mf_top)
        u->mf_top = u->mf_sel;
    if (u->mf_sel >= u->mf_top + h)
        u->mf_top = u->mf_sel - h + 1;
    term_fill(0, 0, u->cols, T_TITLE);
    if (u->mf_ok)
        numfmt_shortest(r->merit, buf, sizeof buf);
    snprintf(head, sizeof head, " Merit Function Editor   MF %s", u->mf_ok ? buf : "-");
    put(u, 0, T_TITLE, head);
    /* The headings. */
    term_fill(1, 0, u->cols, T_HEADER);
    for (k = 0, x = 0; k < NCOL; k++) {
        if (!shown(u, k))
            continue;
        snprintf(buf, sizeof buf, k <= 1 ? "%-*s" : "%*s", col[k].w, col[k].head);
        term_text(1, x, u->cols - x > 0 ? u->cols - x : 0, T_HEADER, 0, buf);
        x += col[k].w + 1;
    }
    /* The operand rows, then one line for the default part, then the
     * place to append. */
    for (y = 2; y < 2 + h; y++)
        term_fill(y, 0, u->cols, T_NORMAL);
    for (i = u->mf_top, y = 2; i < nrows && y < 2 + h; i++, y++) {
        if (i == mf->nop) {
            double c = 0.0;
            int j, nd = u->mf_ok ? r->nrow - mf->nop : 0;
            for (j = mf->nop; u->mf_ok && j < r->nrow; j++)
                c += r->row[j].contribution;
            if (mf->has_default)
                snprintf(line, sizeof line, "%-4s DMFS  default: spot about the %s, %d x %d: "
                         "%d rows, %.4g %%", "",
                         mf->reference == SG_MERIT_CHIEF ? "chief" : "centroid", mf->rings,
                         mf->arms, nd, c);
            else
                snprintf(line, sizeof line, "%-4s (end; i: a row here; :merit default "
                         "centroid adds the default part)", "");
            put(u, y, i == u->mf_sel ? T_ROWSEL : T_DIM, line);
            continue;
        }
        for (k = 0, x = 0; k < NCOL; k++) {
            int style = T_NORMAL;
            if (!shown(u, k))
                continue;
            cell(u, i, k, line, sizeof line);
            snprintf(buf, sizeof buf, k <= 1 ? "%-*s" : "%*s", col[k].w, line);
            if (i == u->mf_sel)
                style = k >= 1 && k <= 9 && k - 1 == u->mf_col ? T_CURSOR : T_ROWSEL;
            term_text(y, x, u->cols - x > 0 ? u->cols - x : 0, style, 0, buf);
            x += col[k].w + 1;
        }
    }
    /* The selected row whole (Hx to Py included at any width), or why the
     * merit function cannot be evaluated, on two lines. */
    term_fill(u->rows - 4, 0, u->cols, T_NORMAL);
    term_fill(u->rows - 3, 0, u->cols, T_NORMAL);
    line[0] = '\0';
    if (!u->mf_ok) {
        snprintf(line, sizeof line, "the merit function cannot be evaluated: %s", u->mf_why);
    } else if (u->mf_sel < mf->nop) {
        const sg_operand *o = &mf->op[u->mf_sel];
        const char *keys[6];
        size_t len = 0;
        len += (size_t)snprintf(line + len, sizeof line - len, "row %d %s:", u->mf_sel + 1,
                                sg_op_name(o->type));
        /* Each cell by the type's own name for it (Zemax's Int1 "wave" of
         * EFFL); a cell the type does not read is left out. */
        sg_op_keys(o->type, keys);
        for (k = 1; k < MERIT_NCOLS; k++) {
            if (k <= 6 && !keys[k - 1])
                continue;
            numfmt_shortest(merit_col_value(o, k), buf, sizeof buf);
            if (k <= 6 && strcmp(keys[k - 1], merit_cols[k]) != 0)
                len += (size_t)snprintf(line + len, sizeof line - len, " %s (%s) %s",
                                        merit_cols[k], keys[k - 1], buf);
            else
                len += (size_t)snprintf(line + len, sizeof line - len, " %s %s", merit_cols[k],
                                        buf);
        }
        if (u->mf_sel < r->nrow) {
            numfmt_shortest(r->row[u->mf_sel].value, buf, sizeof buf);
            len += (size_t)snprintf(line + len, sizeof line - len, "; value %s", buf);
            numfmt_shortest(r->row[u->mf_sel].contribution, buf, sizeof buf);
            snprintf(line + len, sizeof line - len, ", %s %% of the merit", buf);
        }
    }
    put2(u, u->rows - 4, u->mf_ok ? T_DIM : T_ERROR, line);
    term_fill(u->rows - 2, 0, u->cols, T_NORMAL);
    snprintf(line, sizeof line, " %d operand row%s%s; column %s", mf->nop,
             mf->nop == 1 ? "" : "s", mf->has_default ? " and the default part" : "",
             merit_cols[u->mf_col]);
    put(u, u->rows - 2, T_DIM, line);
    term_fill(u->rows - 1, 0, u->cols, T_NORMAL);
    put(u, u->rows - 1, T_NORMAL,
        "Enter edit  i insert  d delete  u undo  r redo  : command  Esc closes");
}

int merit_key(ui *u, int key)
{
    const sg_merit *mf = &u->e->doc.sys->merit;
    char line[128], buf[64];
    switch (key) {
    case K_UP:
    case 'k': u->mf_sel--; break;
    case K_DOWN:
    case 'j': u->mf_sel++; break;
    case K_LEFT:
    case 'h': u->mf_col = u->mf_col > 0 ? u->mf_col - 1 : 0; break;
    case K_RIGHT:
    case 'l': u->mf_col = u->mf_col < MERIT_NCOLS - 1 ? u->mf_col + 1 : MERIT_NCOLS - 1; break;
    case K_PGUP: u->mf_sel -= u->rows - 6; break;
    case K_PGDN: u->mf_sel += u->rows - 6; break;
    case 'i':
    case K_INS: return ui_run(u, "merit insert %d", u->mf_sel + 1);
    case 'd':
    case K_DEL:
        if (u->mf_sel >= mf->nop)
            return ED_HANDLED;
        return ui_run(u, "merit delete %d", u->mf_sel + 1);
    case 'u': return ui_run(u, "undo");
    case 'r': return ui_run(u, "redo");
    case K_ENTER:
        /* Edit the cell on the ':' line, its value ready to change. */
        if (u->mf_sel >= mf->nop)
            return ui_run(u, "merit insert %d", u->mf_sel + 1);
        if (u->mf_col == 0)
            snprintf(buf, sizeof buf, "%s", sg_op_name(mf->op[u->mf_sel].type));
        else
            numfmt_shortest(merit_col_value(&mf->op[u->mf_sel], u->mf_col), buf, sizeof buf);
        snprintf(line, sizeof line, "merit set %d %s %s", u->mf_sel + 1, merit_cols[u->mf_col],
                 buf);
        ui_prompt(u, line);
        return ED_HANDLED | ED_REDRAW;
    case ':': ui_prompt(u, ""); return ED_HANDLED | ED_REDRAW;
    case K_ESC:
    case 'q':
    case K_CTRL('e'): u->mode = MODE_NORMAL; break;
    default: return ED_HANDLED;
    }
    return ED_HANDLED | ED_REDRAW;
}
