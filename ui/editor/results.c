/* results.c - the live results: paraxial summary, per-surface ray data,
 * and the detail panel with the cursor's surface at full precision. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "../measure.h"
#include "../report.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

/* The status comes first so a failure is visible at any width; the
 * coordinates follow, then what a wider terminal has room for. */
enum { RC_STATUS = 0, RC_X, RC_Y, RC_Z, RC_L, RC_M, RC_N, RC_RESID, RC_BOUND, RC_PATH,
       RC_DX, RC_DY, RC_DZ, RC_DL, RC_DM, RC_DN, RC_COUNT };

static const char *const rc_head[RC_COUNT] = {
    "status", "x", "y", "z", "l", "m", "n", "residual", "err bound", "path",
    "dig x", "dig y", "dig z", "dig l", "dig m", "dig n"};

/* Widest %.17g-shortest text of a double: sign, 17 digits, point, e-308. */
#define FULL_W 24
/* One cell of the panel: a one-letter label, '=', a full number. */
#define CELL_W (2 + FULL_W)

/* A ray status in at most 8 columns. */
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

/* Classic's error figure is an estimate, not a bound: it says so. */
static int is_estimate(const ui *u)
{
    return u->e->method == SG_METHOD_CLASSIC;
}

static const char *head(const ui *u, int c)
{
    if (c == RC_BOUND && is_estimate(u))
        return "err est";
    return rc_head[c];
}

static int ncols(const ui *u)
{
    return u->e->digits ? RC_COUNT : RC_DX;
}

static int min_width(int c)
{
    if (c == RC_STATUS)
        return 9;
    if (c >= RC_X && c <= RC_N)
        return 11;
    if (c == RC_PATH)
        return 11;
    if (c >= RC_DX)
        return 6;
    return 10;
}

/* Width of the surface-number column: enough for the last surface. */
static int label_w(const ui *u)
{
    int n = u->e->cmp.have ? u->e->cmp.nsurf : u->e->doc.sys->nsurf, w = 1;
    while (n >= 10) {
        n /= 10;
        w++;
    }
    return w < 4 ? 5 : w + 1;
}

/* Chooses the table's columns from res_left on and their widths; returns
 * how many columns are shown.  Coordinates get the room left over, up to
 * full precision, once every column fits. */
static int table_layout(const ui *u, int first, int w[RC_COUNT])
{
    int nc = ncols(u), x = label_w(u), k, last = first, spare, grow;
    for (k = 0; k < RC_COUNT; k++)
        w[k] = 0;
    for (k = first; k < nc; k++) {
        if (x + min_width(k) > u->cols)
            break;
        w[k] = min_width(k);
        x += w[k];
        last = k + 1;
    }
    spare = u->cols - x;
    /* Wider coordinates only when nothing further is hidden. */
    if (last < nc)
        return last - first;
    for (grow = 1; grow && spare > 0;) {
        grow = 0;
        for (k = first; k < last && spare > 0; k++)
            if (((k >= RC_X && k <= RC_N) || k == RC_PATH) && w[k] < FULL_W + 1) {
                w[k]++;
                spare--;
                grow = 1;
            }
    }
    return last - first;
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

/* The residual as defined, |z - sag(x, y)| of the reported point: the
 * engine's figure is a first-order form that reads 0 where the point is
 * only very nearly on the surface. */
static double residual(const ui *u, int row, const sg_ray_surface *r)
{
    const sg_system *s = u->e->doc.sys;
    if (row <= 0 || row >= s->nsurf || u->e->cmp.nsurf != s->nsurf)
        return r->residual;
    return meas_residual(&s->surf[row], r->x, r->y, r->z);
}

/* The size a point at the origin is judged against: the largest reference
 * coordinate of the ray anywhere, else the entrance pupil radius. */
static double ref_scale(const compute *c)
{
    double s = 0.0;
    int i, k;
    for (i = 0; i < c->nsurf; i++) {
        const sg_ray_surface *r = &c->ref_res[i];
        if (r->status != SG_EOK)
            continue;
        for (k = RC_X; k <= RC_Z; k++)
            if (isfinite(coord(r, k)))
                s = fmax(s, fabs(coord(r, k)));
    }
    if (!(s > 0.0) && c->par_ok && isfinite(c->par.epd))
        s = 0.5 * c->par.epd;
    return s;
}

/* Digits of coordinate c (RC_X..RC_N) against the reference, judged as
 * verify judges them (see measure.h); NaN when there is nothing to judge. */
static double digits_of(const compute *c, const sg_ray_surface *r, const sg_ray_surface *ref,
                        int k, double scale)
{
    double a = coord(r, k), b = coord(ref, k), size = 0.0;
    int j, base = k <= RC_Z ? RC_X : RC_L;
    if (!isfinite(a) || !isfinite(b))
        return NAN;
    for (j = base; j < base + 3; j++)
        if (isfinite(coord(ref, j)))
            size = fmax(size, fabs(coord(ref, j)));
    if (!(size > 0.0))
        size = base == RC_X ? scale : 1.0;
    (void)c;
    return meas_coord_digits(a, b, size);
}

static int digits_style(double d)
{
    return d >= 15.0 ? T_GOOD : d >= 10.0 ? T_NORMAL : T_ERROR;
}

/* A value that is not a finite number reads as the reports write it. */
static const char *nonfinite(double x)
{
    return isnan(x) ? "undefined" : x > 0 ? "Infinity" : "-Infinity";
}

static void paraxial_line(ui *u)
{
    const compute *c = &u->e->cmp;
    char buf[SG_DIAG_MSG + 64], buf2[SG_DIAG_MSG + 64];
    int y = u->parax_y;
    term_fill(y, 0, u->cols, T_NORMAL);
    if (!c->par_ok) {
        snprintf(buf, sizeof buf, "cannot trace: %s", c->build_msg);
        ui_fit_words(buf, u->cols, u->ell, "", buf2, sizeof buf2);
        term_text(y, 0, u->cols, T_ERROR, 1, buf2);
        return;
    }
    /* Eight digits are plenty for a summary; exact numbers are one export
     * away. */
    {
        /* The lens unit once, and the wavelength the data belong to. */
        const sg_system *s = u->e->doc.sys;
        char v[5][NUMFMT_MAX];
        double x[5] = {c->par.efl, c->par.image_fnum, c->par.epd, c->par.bfl,
                       c->par.total_track};
        int i, w = c->par_wave >= 0 && c->par_wave < s->nwave ? c->par_wave : 0;
        for (i = 0; i < 5; i++)
            if (isfinite(x[i]))
                snprintf(v[i], sizeof v[i], i == 1 ? "%.6g" : "%.8g", x[i]);
            else
                snprintf(v[i], sizeof v[i], "%s", nonfinite(x[i]));
        /* The wavelength and the unit lead, so a narrow screen cuts a
         * number rather than what the numbers mean. */
        snprintf(buf, sizeof buf, "at %d: %.7gum, %s:  EFL %s  F/# %s  EPD %s  BFL %s  track %s",
                 w + 1, s->wave[w].um, s->units, v[0], v[1], v[2], v[3], v[4]);
        if (numfmt_width(buf) > u->cols) {
            /* Narrower: single blanks; still too wide, cut before a
             * number, with F3 (the system data) to read it all. */
            char narrow[sizeof buf];
            snprintf(narrow, sizeof narrow, "%d: %.7gum, %s: EFL %s F/# %s EPD %s BFL %s track %s",
                     w + 1, s->wave[w].um, s->units, v[0], v[1], v[2], v[3], v[4]);
            ui_fit_words(narrow, u->cols, u->ell, " F3", buf, sizeof buf);
        }
    }
    term_text(y, 0, u->cols, T_NORMAL, 1, buf);
    if (c->warn[0] && (int)strlen(buf) + 4 < u->cols)
        term_text(y, (int)strlen(buf) + 3, u->cols - (int)strlen(buf) - 3, T_DIM, 0, c->warn);
}

/* ------------------------------------------------------------ the panel */

/* Cells of the panel across the screen: three at 80 columns. */
static int panel_cells(const ui *u, int *cw)
{
    int n = (u->cols + 1) / (CELL_W + 1);
    if (n > 6)
        n = 6;
    if (n >= 2) {
        *cw = CELL_W;
        return n;
    }
    /* Below 53 columns two cells share the width, numbers cut. */
    *cw = (u->cols - 1) / 2;
    return 2;
}

/* The panel's bounds: "residual=R   bound=B   dir bound=D" on one line
 * where it fits whole, else the direction's bound on a line of its own
 * (a number too wide even there is cut with an ellipsis).  Returns the
 * lines; line2 is empty for one. */
static int bound_lines(const ui *u, char *line1, char *line2, size_t n)
{
    const compute *c = &u->e->cmp;
    const sg_ray_surface *r;
    char num[3][NUMFMT_MAX], dir[NUMFMT_MAX + 32];
    const char *what = is_estimate(u) ? "estimate" : "bound";
    line1[0] = line2[0] = '\0';
    if (!c->have || u->e->row >= c->nsurf || c->res[u->e->row].status != SG_EOK)
        return 1;
    r = &c->res[u->e->row];
    numfmt_shortest(residual(u, u->e->row, r), num[0], sizeof num[0]);
    numfmt_shortest(r->error_bound, num[1], sizeof num[1]);
    numfmt_shortest(r->dir_error_bound, num[2], sizeof num[2]);
    snprintf(line1, n, "residual=%s   %s=%s", num[0], what, num[1]);
    snprintf(dir, sizeof dir, "dir %s=%s", what, num[2]);
    if ((int)(strlen(line1) + 3 + strlen(dir)) <= u->cols) {
        size_t len = strlen(line1);
        snprintf(line1 + len, n - len, "   %s", dir);
        return 1;
    }
    snprintf(line2, n, "%s", dir);
    return 2;
}

int results_panel_height(const ui *u)
{
    int cw, n = panel_cells(u, &cw);
    char a[256], b[256];
    return 1 + (6 + n - 1) / n + bound_lines(u, a, b, sizeof a) + (u->e->digits ? 1 : 0);
}

/* Draws "label=value" in a cell; the value is cut (never rounded) to fit. */
static void panel_item(ui *u, int y, int x, int w, const char *label, double v, int style)
{
    char num[NUMFMT_MAX], cut[NUMFMT_MAX + 8], buf[NUMFMT_MAX + 16];
    int lw = (int)strlen(label) + 1;
    if (isfinite(v))
        numfmt_shortest(v, num, sizeof num);
    else
        snprintf(num, sizeof num, "%s", nonfinite(v));
    numfmt_fit(num, w - lw, u->ell, cut, sizeof cut);
    snprintf(buf, sizeof buf, "%s=%s", label, cut);
    term_text(y, x, w, style, 1, buf);
}

/* A line of the panel, ending in an ellipsis where it is cut. */
static void fit_line(ui *u, int y, int style, const char *s)
{
    char cut[600];
    ui_fit(s, u->cols, u->ell, cut, sizeof cut);
    term_text(y, 0, u->cols, style, 1, cut);
}

static void panel_draw(ui *u)
{
    static const char *const name[6] = { "x", "y", "z", "l", "m", "n" };
    const ed *e = u->e;
    const compute *c = &e->cmp;
    int h = results_panel_height(u), i, cw, n = panel_cells(u, &cw), y = u->detail_y;
    char buf[512], num[3][NUMFMT_MAX];
    const sg_ray_surface *r;

    for (i = 0; i < h; i++)
        term_fill(y + i, 0, u->cols, T_NORMAL);
    if (!c->have || e->row >= c->nsurf)
        return;
    r = &c->res[e->row];
    if (r->status == SG_ENOTREACHED) {
        snprintf(buf, sizeof buf, "Surface %d: not reached (the ray stopped earlier: %s)",
                 e->row, report_status_name(c->rc));
        fit_line(u, y, T_DIM, buf);
        return;
    }
    if (r->status != SG_EOK) {
        snprintf(buf, sizeof buf, "Surface %d: %s (%s)", e->row,
                 report_status_name(r->status), sg_strerror(r->status));
        fit_line(u, y, T_ERROR, buf);
        return;
    }
    numfmt_shortest(r->path, num[0], sizeof num[0]);
    if (e->global >= 0)
        snprintf(buf, sizeof buf, "Surface %d:  OK   path=%s   (global, surface %d's frame)",
                 e->row, num[0], e->global);
    else
        snprintf(buf, sizeof buf, "Surface %d:  OK   path=%s", e->row, num[0]);
    fit_line(u, y, T_GOOD, buf);

    for (i = 0; i < 6; i++)
        panel_item(u, y + 1 + i / n, (i % n) * (cw + 1), cw, name[i], coord(r, RC_X + i),
                   T_NORMAL);
    y += 1 + (6 + n - 1) / n;

    {
        char l1[256], l2[256], cut[256];
        if (bound_lines(u, l1, l2, sizeof l1) == 2) {
            ui_fit(l2, u->cols, u->ell, cut, sizeof cut);
            term_text(y + 1, 0, u->cols, T_NORMAL, 1, cut);
        }
        ui_fit(l1, u->cols, u->ell, cut, sizeof cut);
        term_text(y, 0, u->cols, T_NORMAL, 1, cut);
        if (l2[0])
            y++;
    }

    if (!e->digits)
        return;
    y++;
    if (!c->ref_have) {
        term_text(y, 0, u->cols, T_ERROR, 1, "digits: the mpfr reference could not be built");
        return;
    }
    {
        const sg_ray_surface *ref = &c->ref_res[e->row];
        double scale = ref_scale(c);
        int x;
        if (ref->status != SG_EOK) {
            /* The reference failed, not the method shown: say which. */
            snprintf(buf, sizeof buf, "digits: the mpfr reference (%d bits) failed: %s",
                     c->ref_opts.mpfr_bits, report_status_name(c->ref_rc));
            term_text(y, 0, u->cols, T_ERROR, 1, buf);
            return;
        }
        snprintf(buf, sizeof buf, "digits vs mpfr %d bits:", c->ref_opts.mpfr_bits);
        term_text(y, 0, u->cols, T_DIM, 1, buf);
        x = (int)strlen(buf) + 1;
        for (i = 0; i < 6 && x + 7 <= u->cols; i++) {
            double d = digits_of(c, r, ref, RC_X + i, scale);
            snprintf(buf, sizeof buf, "%s %.1f", name[i], d);
            term_text(y, x, 7, isnan(d) ? T_DIM : digits_style(d), 1, buf);
            x += 8;
        }
    }
}

/* Nonzero when surface row's glass does not cover the traced wavelength:
 * its index there is an extrapolation, as the CLI warns. */
static int out_of_range(const ui *u, int row)
{
    const ed *e = u->e;
    const sg_surface *s;
    const sg_glass *g;
    if (!e->cat || row < 0 || row >= e->doc.sys->nsurf)
        return 0;
    s = &e->doc.sys->surf[row];
    if (s->mat.kind != SG_MAT_GLASS || !(g = sg_material_glass(e->cat, &s->mat)))
        return 0;
    return !sg_glass_in_range(g, e->doc.sys->wave[e->wave].um);
}

/* ------------------------------------------------------------ the table */

static void cell(const ui *u, int row, int c, const sg_ray_surface *r,
                 const sg_ray_surface *ref, double scale, int w, char *out, size_t n,
                 int *style)
{
    double x;
    *style = T_NORMAL;
    out[0] = '\0';
    if (c == RC_STATUS) {
        snprintf(out, n, "%s", status_word(r->status));
        *style = r->status == SG_EOK ? T_GOOD : T_ERROR;
        if (out_of_range(u, row)) {
            /* The glass is used beyond its range: the numbers are suspect. */
            snprintf(out, n, "%s range!", status_word(r->status));
            *style = T_ERROR;
        }
        return;
    }
    /* Nothing was computed past a failure, so nothing is shown. */
    if (r->status != SG_EOK)
        return;
    if (c <= RC_N || c == RC_PATH) {
        x = c == RC_PATH ? r->path : coord(r, c);
        if (!isnan(x))
            numfmt_cell(x, w, u->ell, out, n);
        else
            snprintf(out, n, "%s", nonfinite(x));
        return;
    }
    if (c == RC_RESID || c == RC_BOUND) {
        x = c == RC_RESID ? residual(u, row, r) : r->error_bound;
        if (!isnan(x))
            snprintf(out, n, "%.2g", x);
        else
            snprintf(out, n, "%s", nonfinite(x));
        return;
    }
    if (!ref || ref->status != SG_EOK)
        return;
    {
        double d = digits_of(&u->e->cmp, r, ref, c - RC_DX + RC_X, scale);
        if (!isnan(d)) {
            snprintf(out, n, "%.1f", d);
            *style = digits_style(d);
        }
    }
}

void paraxial_draw(ui *u)
{
    paraxial_line(u);
}

void results_draw(ui *u)
{
    const ed *e = u->e;
    const compute *c = &e->cmp;
    int nc = ncols(u), i, k, x, y, w[RC_COUNT], shown, lw = label_w(u);
    double scale = 0.0;
    char buf[256];

    paraxial_line(u);
    panel_draw(u);
    if (u->res_left >= nc)
        u->res_left = nc - 1;
    if (u->res_left < 0)
        u->res_left = 0;
    shown = table_layout(u, u->res_left, w);
    if (c->have && c->ref_have)
        scale = ref_scale(c);

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
    term_text(y, 0, lw, T_HEADER, 1, u->res_left > 0 ? "S {" : "Surf");
    x = lw;
    for (k = u->res_left; k < u->res_left + shown; k++) {
        const char *h = head(u, k);
        int hw = (int)strlen(h);
        if (k == RC_STATUS || hw >= w[k])
            term_text(y, x, w[k] - 1, T_HEADER, 1, h);
        else
            term_text(y, x + w[k] - 1 - hw, hw, T_HEADER, 0, h);
        x += w[k];
    }
    if (u->res_left + shown < nc)
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
        snprintf(buf, sizeof buf, "%d", r);
        term_fill(y, 0, lw, r == e->row ? T_ROWSEL : T_DIM);
        term_text(y, lw - 1 - (int)strlen(buf), (int)strlen(buf), r == e->row ? T_ROWSEL : T_DIM,
                  1, buf);
        x = lw;
        for (k = u->res_left; k < u->res_left + shown; k++) {
            int style, tw;
            cell(u, r, k, &c->res[r], c->ref_have ? &c->ref_res[r] : NULL, scale, w[k] - 1,
                 buf, sizeof buf, &style);
            tw = numfmt_width(buf);
            if (k != RC_STATUS && tw < w[k] - 1)
                term_text(y, x + (w[k] - 1 - tw), tw, style, 0, buf);
            else
                term_text(y, x, w[k] - 1, style, 1, buf);
            x += w[k];
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
    if (y > u->res_y && y <= u->res_y + u->res_h && r < e->doc.sys->nsurf) {
        e->row = r;
        sheet_follow(u);
    }
    return ED_HANDLED | ED_REDRAW;
}
