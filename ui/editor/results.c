/* results.c - the live results: paraxial summary, per-surface ray data. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../report.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

#define LABEL_W 8

/* The status comes first so a failure is visible at any width. */
enum { RC_STATUS = 0, RC_X, RC_Y, RC_Z, RC_L, RC_M, RC_N, RC_RESID, RC_BOUND,
       RC_DX, RC_DY, RC_DZ, RC_DL, RC_DM, RC_DN, RC_COUNT };

static const char *const rc_head[RC_COUNT] = {
    "status", "x", "y", "z", "l", "m", "n", "residual", "err bound",
    "dig x", "dig y", "dig z", "dig l", "dig m", "dig n"};

/* A ray status in at most 9 columns. */
static const char *status_word(int st)
{
    switch (st) {
    case SG_EOK: return "OK";
    case SG_ENOTREACHED: return "-";
    case SG_EAIM: return "AIM FAIL";
    case SG_ERANGE: return "RANGE";
    default: return report_status_name(st);
    }
}

static int ncols(const ui *u)
{
    return u->e->digits ? RC_COUNT : RC_DX;
}

static int rc_width(const ui *u, int c)
{
    if (c >= RC_X && c <= RC_N)
        return u->resw;
    if (c == RC_STATUS)
        return 10;
    if (c >= RC_DX)
        return 6;
    return 10;
}

static double coord(const sg_ray_surface *r, int c)
{
    switch (c) {
    case RC_X: return r->x;
    case RC_Y: return r->y;
    case RC_Z: return r->z;
    case RC_L: return r->l;
    case RC_M: return r->m;
    default: return r->n;
    }
}

static void paraxial_line(ui *u)
{
    const compute *c = &u->e->cmp;
    char buf[SG_DIAG_MSG + 64];
    int y = u->parax_y;
    term_fill(y, 0, u->cols, T_NORMAL);
    if (!c->par_ok) {
        snprintf(buf, sizeof buf, "cannot trace: %s", c->build_msg);
        term_text(y, 0, u->cols, T_ERROR, 1, buf);
        return;
    }
    /* Eight digits are plenty for a summary; exact numbers are one export
     * away. */
    snprintf(buf, sizeof buf, "EFL %.8g   F/# %.6g   EPD %.8g   BFL %.8g   track %.8g",
             c->par.efl, c->par.image_fnum, c->par.epd, c->par.bfl, c->par.total_track);
    term_text(y, 0, u->cols, T_NORMAL, 1, buf);
    if (c->warn[0] && (int)strlen(buf) + 4 < u->cols)
        term_text(y, (int)strlen(buf) + 3, u->cols - (int)strlen(buf) - 3, T_DIM, 0, c->warn);
}

static void detail_line(ui *u)
{
    const ed *e = u->e;
    const compute *c = &e->cmp;
    char buf[1024], v[6][NUMFMT_MAX];
    int i, y = u->detail_y;
    const sg_ray_surface *r;
    term_fill(y, 0, u->cols, T_NORMAL);
    if (!c->have || e->row >= c->nsurf)
        return;
    r = &c->res[e->row];
    if (r->status == SG_ENOTREACHED) {
        snprintf(buf, sizeof buf, "Surface %d: not reached", e->row);
    } else {
        for (i = 0; i < 6; i++) {
            double x = coord(r, RC_X + i);
            if (isfinite(x))
                numfmt_shortest(x, v[i], sizeof v[i]);
            else
                snprintf(v[i], sizeof v[i], "-");
        }
        snprintf(buf, sizeof buf, "Surface %d:  x=%s  y=%s  z=%s  l=%s  m=%s  n=%s", e->row,
                 v[0], v[1], v[2], v[3], v[4], v[5]);
    }
    term_text(y, 0, u->cols, T_DIM, 1, buf);
}

static void cell(const ui *u, int c, const sg_ray_surface *r, const sg_ray_surface *ref,
                 int w, char *out, size_t n, int *style)
{
    double x;
    *style = T_NORMAL;
    out[0] = '\0';
    if (c == RC_STATUS) {
        snprintf(out, n, "%s", status_word(r->status));
        *style = r->status == SG_EOK ? T_GOOD : T_ERROR;
        return;
    }
    /* Nothing was computed past a failure, so nothing is shown. */
    if (r->status == SG_ENOTREACHED)
        return;
    if (c <= RC_N) {
        x = coord(r, c);
        if (isfinite(x))
            numfmt_cell(x, w, u->ell, out, n);
        return;
    }
    if (c == RC_RESID || c == RC_BOUND) {
        x = c == RC_RESID ? r->residual : r->error_bound;
        if (isfinite(x))
            snprintf(out, n, "%.2g", x);
        return;
    }
    if (!ref || ref->status == SG_ENOTREACHED)
        return;
    {
        double a = coord(r, c - RC_DX + RC_X), b = coord(ref, c - RC_DX + RC_X);
        if (isfinite(a) && isfinite(b)) {
            double d = sg_digits(a, b);
            snprintf(out, n, "%.1f", d);
            *style = d >= 15.0 ? T_GOOD : d >= 10.0 ? T_NORMAL : T_ERROR;
        }
    }
}

void results_draw(ui *u)
{
    const ed *e = u->e;
    const compute *c = &e->cmp;
    int nc = ncols(u), i, k, x, y;
    char buf[256];

    paraxial_line(u);
    detail_line(u);
    if (u->res_left >= nc)
        u->res_left = nc - 1;
    if (u->res_left < 0)
        u->res_left = 0;

    /* The results follow the spreadsheet's cursor. */
    if (u->res_top > e->row)
        u->res_top = e->row;
    if (u->res_h > 0 && e->row >= u->res_top + u->res_h)
        u->res_top = e->row - u->res_h + 1;
    if (c->have && u->res_top > c->nsurf - u->res_h)
        u->res_top = c->nsurf - u->res_h;
    if (u->res_top < 0)
        u->res_top = 0;

    y = u->res_y;
    term_fill(y, 0, u->cols, T_HEADER);
    term_text(y, 0, LABEL_W, T_HEADER, 1, u->res_left > 0 ? "Surf  {" : "Surf");
    x = LABEL_W;
    for (k = u->res_left; k < nc; k++) {
        int w = rc_width(u, k);
        if (x + w > u->cols)
            break;
        if (k == RC_STATUS)
            term_text(y, x, w - 1, T_HEADER, 1, rc_head[k]);
        else
            term_text(y, x + w - 1 - (int)strlen(rc_head[k]), (int)strlen(rc_head[k]), T_HEADER,
                      0, rc_head[k]);
        x += w;
    }
    if (k < nc)
        term_text(y, u->cols - 1, 1, T_HEADER, 0, "}");

    for (i = 0; i < u->res_h; i++) {
        int r = u->res_top + i;
        y = u->res_y + 1 + i;
        term_fill(y, 0, u->cols, T_NORMAL);
        if (!c->have) {
            if (i == 0)
                term_text(y, 0, u->cols, T_ERROR, 1,
                          c->build_msg[0] ? c->build_msg : "no trace");
            continue;
        }
        if (r >= c->nsurf)
            continue;
        snprintf(buf, sizeof buf, "%7d ", r);
        term_text(y, 0, LABEL_W, r == e->row ? T_ROWSEL : T_DIM, 1, buf);
        x = LABEL_W;
        for (k = u->res_left; k < nc; k++) {
            int w = rc_width(u, k), style, tw;
            if (x + w > u->cols)
                break;
            cell(u, k, &c->res[r], c->ref_have ? &c->ref_res[r] : NULL, w - 1, buf,
                 sizeof buf, &style);
            tw = numfmt_width(buf);
            if (k != RC_STATUS && tw < w - 1)
                term_text(y, x + (w - 1 - tw), tw, style, 0, buf);
            else
                term_text(y, x, w - 1, style, 1, buf);
            x += w;
        }
    }
}

int results_key(ui *u, int key)
{
    switch (key) {
    case '{':
        if (u->res_left > 0)
            u->res_left--;
        return ED_HANDLED | ED_REDRAW;
    case '}':
        if (u->res_left + 1 < ncols(u))
            u->res_left++;
        return ED_HANDLED | ED_REDRAW;
    default: return 0;
    }
}

int results_click(ui *u, int y, int kind)
{
    ed *e = u->e;
    int r = u->res_top + (y - u->res_y - 1);
    if (kind == M_WHEEL_UP || kind == M_WHEEL_DOWN) {
        e->row += kind == M_WHEEL_UP ? -3 : 3;
        sheet_follow(u);
        return ED_HANDLED | ED_REDRAW;
    }
    if (y > u->res_y && r < e->doc.sys->nsurf) {
        e->row = r;
        sheet_follow(u);
    }
    return ED_HANDLED | ED_REDRAW;
}
