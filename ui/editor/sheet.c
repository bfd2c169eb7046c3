/* sheet.c - the lens data spreadsheet: one row per surface. */
#include <ctype.h>
#include <stdio.h>
#include <string.h>

#include "numfmt.h"
#include "term.h"
#include "ui.h"

#define LABEL_W 8

/* The label column: "IMA" and the surface number with a blank between
 * them however many digits the number has (IMA 1001, not IMA1001). */
static int label_w(const ui *u)
{
    int n = u->e->doc.sys->nsurf - 1, d = 1;
    while (n >= 10) {
        n /= 10;
        d++;
    }
    return d <= 3 ? LABEL_W : 3 + 1 + d + 1;
}

static int col_width(const ui *u, int c)
{
    switch (c) {
    /* Compact enough that Conic fits at 80 columns; wider terminals add
     * the asphere terms. */
    case COL_TYPE: return 9;
    case COL_COMMENT: return u->cols >= 140 ? 20 : 13;
    case COL_MATERIAL: return u->cols >= 100 ? 11 : 10;
    default: return u->numw;
    }
}

/* Cuts text to w columns (one per character), marking a cut with ell. */
static void fit_text(const char *s, int w, const char *ell, char *out, size_t n)
{
    int cols = numfmt_width(s);
    size_t i = 0;
    int c = 0;
    if (cols <= w) {
        snprintf(out, n, "%s", s);
        return;
    }
    if (w <= 0) {
        out[0] = '\0';
        return;
    }
    while (s[i] && c < w - 1) {
        i++;
        while (((unsigned char)s[i] & 0xC0) == 0x80)
            i++;
        c++;
    }
    snprintf(out, n, "%.*s%s", (int)i, s, ell);
}

static void cell_show(const ui *u, int row, int col, int w, char *out, size_t n)
{
    const sg_surface *s = &u->e->doc.sys->surf[row];
    char full[LE_MAX];
    if (col == COL_SEMI) {
        char num[NUMFMT_MAX * 2];
        numfmt_cell(s->semi_diameter, s->sd_fixed ? w - 2 : w, u->ell, num, sizeof num);
        snprintf(out, n, "%s%s", num, s->sd_fixed ? " U" : "");
        return;
    }
    cell_text(u->e->doc.sys, row, col, full, sizeof full);
    if (cell_numeric(col)) {
        /* A solve's letter (Zemax's M, P, F ...) stays when the number is
         * cut: the number gives up the room. */
        size_t len = strlen(full);
        char mark = 0, num[NUMFMT_MAX * 2];
        if (len > 2 && full[len - 2] == ' ' && full[len - 1] >= 'A' && full[len - 1] <= 'Z') {
            mark = full[len - 1];
            full[len - 2] = '\0';
        }
        if (col == COL_RADIUS && strcmp(full, "Infinity") == 0)
            fit_text(full, mark ? w - 2 : w, u->ell, num, sizeof num);
        else
            numfmt_fit(full, mark ? w - 2 : w, u->ell, num, sizeof num);
        if (mark)
            snprintf(out, n, "%s %c", num, mark);
        else
            snprintf(out, n, "%s", num);
        return;
    }
    fit_text(full, w, u->ell, out, n);
}

/* Places the visible columns from u->left on. */
static void place(ui *u)
{
    int x = label_w(u), c;
    for (c = 0; c < cell_count(); c++) {
        u->colx[c] = 0;
        u->colw[c] = 0;
    }
    for (c = u->left; c < cell_count(); c++) {
        int w = col_width(u, c);
        if (x + w > u->cols)
            break;
        u->colx[c] = x;
        u->colw[c] = w;
        x += w;
    }
}

void sheet_follow(ui *u)
{
    ed *e = u->e;
    int n = e->doc.sys->nsurf;
    if (e->row >= n)
        e->row = n - 1;
    if (e->row < 0)
        e->row = 0;
    if (e->col < 0)
        e->col = 0;
    if (e->col >= cell_count())
        e->col = cell_count() - 1;
    if (u->top > e->row)
        u->top = e->row;
    if (u->sheet_h > 0 && e->row >= u->top + u->sheet_h)
        u->top = e->row - u->sheet_h + 1;
    if (u->top > n - u->sheet_h)
        u->top = n - u->sheet_h;
    if (u->top < 0)
        u->top = 0;
    if (u->left > e->col)
        u->left = e->col;
    for (;;) {
        place(u);
        if (u->colw[e->col] > 0 || u->left >= e->col)
            break;
        u->left++;
    }
}

static void label(const sg_system *s, int r, int w, char *buf, size_t n)
{
    const char *tag = r == 0 ? "OBJ" : r == s->nsurf - 1 ? "IMA" : r == s->stop ? "STO" : "";
    snprintf(buf, n, "%-3s%*d ", tag, w > 4 && w < 16 ? w - 4 : 4, r);
}

void sheet_draw(ui *u)
{
    ed *e = u->e;
    const sg_system *s = e->doc.sys;
    char buf[LE_MAX];
    int c, i;

    sheet_follow(u);
    term_fill(u->sheet_y, 0, u->cols, T_HEADER);
    term_text(u->sheet_y, 0, label_w(u), T_HEADER, 1, u->left > 0 ? "Surf  <" : "Surf");
    for (c = u->left; c < cell_count() && u->colw[c] > 0; c++) {
        const char *h = cell_heading(c);
        int w = u->colw[c] - 1, hw = (int)strlen(h);
        /* Headings sit over their numbers, which line up on the right. */
        if (cell_numeric(c) && hw < w)
            term_text(u->sheet_y, u->colx[c] + w - hw, hw, T_HEADER, 0, h);
        else
            term_text(u->sheet_y, u->colx[c], w, T_HEADER, 1, h);
    }
    if (c < cell_count())
        term_text(u->sheet_y, u->cols - 1, 1, T_HEADER, 0, ">");

    for (i = 0; i < u->sheet_h; i++) {
        int r = u->top + i, y = u->sheet_y + 1 + i;
        term_fill(y, 0, u->cols, T_NORMAL);
        if (r >= s->nsurf)
            continue;
        label(s, r, label_w(u), buf, sizeof buf);
        term_text(y, 0, label_w(u), r == e->row ? T_ROWSEL : r == s->stop ? T_STOP : T_DIM, 1,
                  buf);
        for (c = u->left; c < cell_count() && u->colw[c] > 0; c++) {
            int w = u->colw[c] - 1, style = T_NORMAL, x = u->colx[c];
            char cell[LE_MAX];
            cell_show(u, r, c, w, cell, sizeof cell);
            /* A surface ignores the parameters of other shapes (a STANDARD
             * surface its r^n terms): shown, but dim. */
            if (!cell_used(s, r, c))
                style = T_DIM;
            if (r == e->row && c == e->col)
                style = u->focus == FOCUS_SHEET ? T_CURSOR : T_ROWSEL;
            if (cell_numeric(c)) {
                /* Numbers line up on the right, as in any spreadsheet. */
                int tw = numfmt_width(cell);
                if (tw < w) {
                    term_fill(y, x, w - tw, style);
                    x += w - tw;
                    w = tw;
                }
            }
            term_text(y, x, w, style, 1, cell);
        }
    }

    if (u->mode == MODE_EDIT_CELL && e->row >= u->top && e->row < u->top + u->sheet_h) {
        /* The field grows to the right edge so long text stays visible. */
        int y = u->sheet_y + 1 + e->row - u->top;
        int x = u->colx[e->col], w = u->cols - x - 1, cur;
        size_t start;
        if (w < 4)
            w = 4;
        le_view(&u->le, w, &start, &cur);
        term_text(y, x, w, T_EDIT, 1, u->le.buf + start);
        term_cursor(y, x + cur);
    }
}

void sheet_begin_edit(ui *u, const char *init)
{
    le_set(&u->le, init);
    u->mode = MODE_EDIT_CELL;
    ed_msg(u->e, 0, "surface %d %s: Enter sets, Esc cancels", u->e->row,
           cell_name(u->e->col));
}

static int move(ui *u, int dr, int dc)
{
    ed *e = u->e;
    e->row += dr;
    e->col += dc;
    sheet_follow(u);
    return ED_HANDLED | ED_REDRAW;
}

/* Tab walks the cells in reading order. */
static int tab(ui *u, int dir)
{
    ed *e = u->e;
    int n = e->doc.sys->nsurf;
    e->col += dir;
    if (e->col >= cell_count()) {
        if (e->row + 1 < n) {
            e->col = 0;
            e->row++;
        } else {
            e->col = cell_count() - 1;
        }
    } else if (e->col < 0) {
        if (e->row > 0) {
            e->col = cell_count() - 1;
            e->row--;
        } else {
            e->col = 0;
        }
    }
    sheet_follow(u);
    return ED_HANDLED | ED_REDRAW;
}

int sheet_text_col(int col)
{
    return col == COL_COMMENT || col == COL_MATERIAL;
}

static int starts_edit(int col, int key)
{
    if (key >= K_BASE || key < 0x20 || key == 0x7f || key == ':')
        return 0;
    /* A key that can begin a value of the cell (any in a text cell, the i
     * of inf in a number) types, so typing a value never runs a command;
     * ':' alone opens the command line from any cell. */
    if (cell_key_begins(col, key))
        return 1;
    /* Upper case never names a command, so it can start any text:
     * glass names, comments, INF. */
    if (key >= 'A' && key <= 'Z')
        return 1;
    return 0;
}

static int key_impl(ui *u, int key, int typing);

int sheet_key(ui *u, int key)
{
    /* A key that can begin the cell's value types, before any command
     * sees it. */
    if (starts_edit(u->e->col, key)) {
        sheet_begin_edit(u, "");
        le_key(&u->le, key);
        return ED_HANDLED | ED_REDRAW;
    }
    return key_impl(u, key, 1);
}

int sheet_key_command(ui *u, int key)
{
    return key_impl(u, key, 0);
}

static int key_impl(ui *u, int key, int typing)
{
    ed *e = u->e;
    const sg_system *s = e->doc.sys;
    char buf[LE_MAX];
    switch (key) {
    case K_UP:
    case 'k': return move(u, -1, 0);
    case K_DOWN:
    case 'j': return move(u, 1, 0);
    case K_LEFT:
    case 'h': return move(u, 0, -1);
    case K_RIGHT:
    case 'l': return move(u, 0, 1);
    case K_TAB: return tab(u, 1);
    case K_BTAB: return tab(u, -1);
    case K_PGUP: return move(u, -(u->sheet_h > 1 ? u->sheet_h - 1 : 1), 0);
    case K_PGDN: return move(u, u->sheet_h > 1 ? u->sheet_h - 1 : 1, 0);
    case K_HOME: e->col = 0; return move(u, 0, 0);
    case K_END: e->col = cell_count() - 1; return move(u, 0, 0);
    case '<': e->row = 0; return move(u, 0, 0);
    case '>': e->row = s->nsurf - 1; return move(u, 0, 0);
    case K_ENTER:
    case K_F(2):
        cell_edit_text(s, e->row, e->col, buf, sizeof buf);
        sheet_begin_edit(u, buf);
        return ED_HANDLED | ED_REDRAW;
    case K_BACKSPACE:
        sheet_begin_edit(u, "");
        return ED_HANDLED | ED_REDRAW;
    case 'i':
    case K_INS: return ui_run(u, "insert %d", e->row < 1 ? 1 : e->row);
    case 'a':
        return ui_run(u, "insert %d", e->row + 1 > s->nsurf - 1 ? s->nsurf - 1 : e->row + 1);
    case 'd':
    case K_DEL: return ui_run(u, "delete %d", e->row);
    case 's': return ui_run(u, "stop %d", e->row);
    case ' ':
        if (e->col == COL_SEMI)
            return ui_run(u, "set %d fixed toggle", e->row);
        if (e->col == COL_TYPE)
            return ui_run(u, "set %d type %s", e->row,
                          s->surf[e->row].type == SG_SURF_STANDARD ? "evenasph" : "standard");
        {
            /* A frame change's order (0, 1) and after mode (explicit,
             * reverse) toggle. */
            const sg_param *p = cell_param(e->col, NULL);
            if (p && p->kind == SG_PARAM_ENUM && (p->flags & SG_PARAM_NESTED) && p->nnames == 2)
                return ui_run(u, "set %d %s %s", e->row, cell_name(e->col),
                              p->names[!*(const int *)sg_param_cptr(p, &s->surf[e->row])]);
        }
        return ED_HANDLED;
    default:
        if (typing && starts_edit(e->col, key)) {
            /* Through the line editor, so any character, UTF-8 too. */
            sheet_begin_edit(u, "");
            le_key(&u->le, key);
            return ED_HANDLED | ED_REDRAW;
        }
        return 0;
    }
}

/* Commits the cell being edited; on success the cursor may move on. */
static int commit(ui *u, int dr, int dc)
{
    ed *e = u->e;
    char q[LE_MAX + 8];
    int f;
    cmd_quote(u->le.buf, q, sizeof q);
    f = ui_run(u, "set %d %s %s", e->row, cell_name(e->col), q);
    if (f & ED_ERROR)
        return f; /* stay in the field so the text can be fixed */
    u->mode = MODE_NORMAL;
    if (dr || dc) {
        if (dc)
            tab(u, dc);
        else
            move(u, dr, 0);
    }
    return f;
}

int sheet_edit_key(ui *u, int key)
{
    switch (key) {
    case K_TAB: return commit(u, 0, 1);
    case K_BTAB: return commit(u, 0, -1);
    case K_UP: return commit(u, -1, 0);
    case K_DOWN: return commit(u, 1, 0);
    default: break;
    }
    switch (le_key(&u->le, key)) {
    case LE_ENTER: return commit(u, 0, 0);
    case LE_CANCEL:
        u->mode = MODE_NORMAL;
        ed_msg(u->e, 0, "edit cancelled");
        return ED_HANDLED | ED_REDRAW;
    case LE_IGNORED: return ED_HANDLED;
    default: return ED_HANDLED | ED_REDRAW;
    }
}

int sheet_click(ui *u, int y, int x, int kind)
{
    ed *e = u->e;
    int r = u->top + (y - u->sheet_y - 1), c;
    if (kind == M_WHEEL_UP)
        return move(u, -3, 0);
    if (kind == M_WHEEL_DOWN)
        return move(u, 3, 0);
    if (y <= u->sheet_y || r >= e->doc.sys->nsurf)
        return ED_HANDLED;
    e->row = r;
    for (c = u->left; c < cell_count() && u->colw[c] > 0; c++)
        if (x >= u->colx[c] && x < u->colx[c] + u->colw[c])
            e->col = c;
    u->focus = FOCUS_SHEET;
    sheet_follow(u);
    if (kind == M_DOUBLE)
        return sheet_key(u, K_ENTER);
    return ED_HANDLED | ED_REDRAW;
}
