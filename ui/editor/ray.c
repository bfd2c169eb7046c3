/* ray.c - the ray selector: Hx, Hy, Px, Py and the wavelength. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../report.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

static const char *const item_name[RAY_NITEMS] = {"Fld", "Hx", "Hy", "Px", "Py", "Wave"};
static const char *const item_cmd[RAY_NITEMS] = {"field", "hx", "hy", "px", "py", "wave"};

/* The design's field the ray's Hx, Hy pick (1-based), or 0 for none. */
static int ray_field(const ed *e)
{
    return ed_ray_field(e);
}

static void item_text(const ui *u, int i, char *buf, size_t n)
{
    const ed *e = u->e;
    int k;
    if (i == RAY_WAVE)
        snprintf(buf, n, "%d: %.10gum", e->wave + 1, e->doc.sys->wave[e->wave].um);
    else if (i == RAY_FIELD)
        (k = ray_field(e)) > 0 ? snprintf(buf, n, "%d", k) : snprintf(buf, n, "-");
    else
        numfmt_shortest(e->ray[i - RAY_HX], buf, n);
}

/* Hx, Hy, Px and Py take 7 columns (a cut number ends in an ellipsis),
 * or the whole shortest text where the line has room for all of them. */
static int item_width(const ui *u, int i, int whole)
{
    char buf[128];
    int w;
    if (i == RAY_FIELD)
        return u->e->doc.sys->nfield >= 10 ? 2 : 1;
    item_text(u, i, buf, sizeof buf);
    w = (int)strlen(buf);
    if (i != RAY_WAVE)
        return whole && w > 7 ? w : 7;
    return w < 8 ? 8 : w > 16 ? 16 : w;
}

/* Where the ray ends, in words, so a failure shows at any width. */
static void ray_status(const ui *u, char *buf, size_t n, int *style)
{
    const compute *c = &u->e->cmp;
    int k;
    *style = T_GOOD;
    if (!c->have) {
        snprintf(buf, n, " no trace");
        *style = T_ERROR;
    } else if (c->rc == SG_EOK) {
        snprintf(buf, n, " OK");
    } else {
        for (k = 0; k < c->nsurf && c->res[k].status != c->rc; k++)
            ;
        if (k < c->nsurf)
            snprintf(buf, n, " %s at %d", report_status_name(c->rc), k);
        else
            snprintf(buf, n, " %s", report_status_name(c->rc));
        *style = T_ERROR;
    }
}

void ray_draw(ui *u)
{
    int x = 0, i, y = u->ray_y, whole, need, room, sst;
    char buf[128], shown[128], st[96];
    term_fill(y, 0, u->cols, T_NORMAL);
    /* The status gets its room first: the items give way to it. */
    ray_status(u, st, sizeof st, &sst);
    room = u->cols - (int)strlen(st);
    for (need = 4, i = 0; i < RAY_NITEMS; i++)
        need += (int)strlen(item_name[i]) + 2 + item_width(u, i, 1);
    whole = need <= room;
    x += term_text(y, x, u->cols - x, u->focus == FOCUS_RAY ? T_FRAME : T_HEADER, 0, "Ray ");
    for (i = 0; i < RAY_NITEMS; i++) {
        int w = item_width(u, i, whole), style = T_NORMAL;
        int lab = (int)strlen(item_name[i]) + 2;
        if (i == RAY_WAVE && x + lab + w > room && x + lab + 8 <= room)
            w = room - x - lab; /* the wavelength's text, cut with an ellipsis */
        if (x + lab + w > room)
            break;
        snprintf(buf, sizeof buf, " %s ", item_name[i]);
        x += term_text(y, x, u->cols - x, T_DIM, 0, buf);
        item_text(u, i, buf, sizeof buf);
        if (i == RAY_FIELD)
            snprintf(shown, sizeof shown, "%s", buf);
        else if (i == RAY_WAVE)
            ui_fit(buf, w, u->ell, shown, sizeof shown);
        else
            numfmt_fit(buf, w, u->ell, shown, sizeof shown);
        if (u->focus == FOCUS_RAY && u->ray_item == i)
            style = T_CURSOR;
        u->rayx[i] = x;
        u->rayw[i] = w;
        if (u->mode == MODE_EDIT_RAY && u->ray_item == i) {
            size_t start;
            int cur;
            le_view(&u->le, w, &start, &cur);
            term_text(y, x, w, T_EDIT, 1, u->le.buf + start);
            term_cursor(y, x + cur);
        } else {
            term_text(y, x, w, style, 1, shown);
        }
        x += w;
    }
    if (i < RAY_NITEMS && x < room)
        x += term_text(y, x, 1, T_DIM, 0, u->ell); /* items beyond the width */
    for (; i < RAY_NITEMS; i++)
        u->rayw[i] = 0;
    ui_fit(st, u->cols - x, u->ell, shown, sizeof shown);
    x += term_text(y, x, u->cols - x, sst, 0, shown);
    if (u->focus == FOCUS_RAY && x + 14 < u->cols) {
        snprintf(buf, sizeof buf, "  step %.*f", u->step_exp, pow(10.0, -u->step_exp));
        term_text(y, x, u->cols - x, T_DIM, 0, buf);
    }
}

static int run_value(ui *u, double v)
{
    return ui_run(u, "%s %.17g", item_cmd[u->ray_item], v);
}

/* Steps in decimal: the value is a whole number of steps of 10^-step_exp
 * and goes to the command as that decimal text, so three steps of 0.1 give
 * 0.3, the double a user typing 0.3 gets. */
static int step(ui *u, int dir)
{
    ed *e = u->e;
    double p10 = pow(10.0, u->step_exp), k;
    if (u->ray_item == RAY_WAVE) {
        int n = e->doc.sys->nwave;
        return ui_run(u, "wave %d", (e->wave + dir + n) % n + 1);
    }
    if (u->ray_item == RAY_FIELD) {
        int n = e->doc.sys->nfield, f = ray_field(e);
        /* From no field, up goes to the first and down to the last. */
        f = f == 0 ? (dir > 0 ? 1 : n) : (f - 1 + dir + n) % n + 1;
        return ui_run(u, "field %d", f);
    }
    k = nearbyint(e->ray[u->ray_item - RAY_HX] * p10 + dir);
    if (k > p10)
        k = p10;
    if (k < -p10)
        k = -p10;
    if (k == 0.0)
        k = 0.0; /* not -0 */
    return ui_run(u, "%s %.*f", item_cmd[u->ray_item], u->step_exp, k / p10);
}

static void begin_edit(ui *u, const char *init)
{
    le_set(&u->le, init);
    u->mode = MODE_EDIT_RAY;
    ed_msg(u->e, 0, "%s: Enter sets, Esc cancels", item_name[u->ray_item]);
}

int ray_key(ui *u, int key)
{
    char buf[64];
    switch (key) {
    case K_LEFT:
    case 'h':
    case K_BTAB:
        u->ray_item = (u->ray_item + RAY_NITEMS - 1) % RAY_NITEMS;
        return ED_HANDLED | ED_REDRAW;
    case K_RIGHT:
    case 'l':
    case K_TAB:
        u->ray_item = (u->ray_item + 1) % RAY_NITEMS;
        return ED_HANDLED | ED_REDRAW;
    case K_UP:
    case 'k': return step(u, 1);
    case K_DOWN:
    case 'j': return step(u, -1);
    case '[':
        if (u->step_exp < 6)
            u->step_exp++;
        return ED_HANDLED | ED_REDRAW;
    case ']':
        if (u->step_exp > 0)
            u->step_exp--;
        return ED_HANDLED | ED_REDRAW;
    case K_HOME:
        return u->ray_item == RAY_WAVE || u->ray_item == RAY_FIELD ? ED_HANDLED
                                                                   : run_value(u, 0.0);
    case K_ENTER:
    case K_F(2):
        if (u->ray_item == RAY_WAVE)
            snprintf(buf, sizeof buf, "%d", u->e->wave + 1);
        else if (u->ray_item == RAY_FIELD)
            item_text(u, RAY_FIELD, buf, sizeof buf);
        else
            numfmt_shortest(u->e->ray[u->ray_item - RAY_HX], buf, sizeof buf);
        begin_edit(u, buf);
        return ED_HANDLED | ED_REDRAW;
    case K_ESC:
    case 'f':
        u->focus = FOCUS_SHEET;
        return ED_HANDLED | ED_REDRAW;
    default:
        /* What a value may begin with types it; + too, so "+0.5" is never a
         * step and then text. */
        if ((key >= '0' && key <= '9') || key == '.' || key == '-' || key == '+') {
            buf[0] = (char)key;
            buf[1] = '\0';
            begin_edit(u, buf);
            return ED_HANDLED | ED_REDRAW;
        }
        return 0;
    }
}

int ray_edit_key(ui *u, int key)
{
    int f;
    switch (le_key(&u->le, key)) {
    case LE_ENTER: {
        char q[LE_MAX + 8];
        cmd_quote(u->le.buf, q, sizeof q);
        f = ui_run(u, "%s %s", item_cmd[u->ray_item], q);
        if (!(f & ED_ERROR))
            u->mode = MODE_NORMAL;
        return f;
    }
    case LE_CANCEL:
        u->mode = MODE_NORMAL;
        ed_msg(u->e, 0, "edit cancelled");
        return ED_HANDLED | ED_REDRAW;
    case LE_IGNORED: return ED_HANDLED;
    default: return ED_HANDLED | ED_REDRAW;
    }
}

int ray_click(ui *u, int x, int kind)
{
    int i;
    for (i = 0; i < RAY_NITEMS; i++)
        if (u->rayw[i] > 0 && x >= u->rayx[i] - 4 && x < u->rayx[i] + u->rayw[i]) {
            u->focus = FOCUS_RAY;
            u->ray_item = i;
            if (kind == M_WHEEL_UP)
                return step(u, 1);
            if (kind == M_WHEEL_DOWN)
                return step(u, -1);
            if (kind == M_DOUBLE)
                return ray_key(u, K_ENTER);
            return ED_HANDLED | ED_REDRAW;
        }
    return ED_HANDLED;
}

int ray_quick(ui *u, int key)
{
    static const char *const cycle[] = {"top", "bottom", "right", "left"};
    const double *r = u->e->ray;
    int i;
    switch (key) {
    case 'c':
    case K_F(5): return ui_run(u, "chief");
    case K_F(6): return ui_run(u, "marginal top");
    case K_F(7): return ui_run(u, "marginal bottom");
    case K_F(8): return ui_run(u, "marginal right");
    case K_F(9): return ui_run(u, "marginal left");
    case 'p':
        /* Steps through the four marginal rays, starting with the top. */
        if (r[2] == 0.0 && r[3] == 1.0)
            i = 1;
        else if (r[2] == 0.0 && r[3] == -1.0)
            i = 2;
        else if (r[2] == 1.0 && r[3] == 0.0)
            i = 3;
        else
            i = 0;
        return ui_run(u, "marginal %s", cycle[i]);
    default: return 0;
    }
}
