/*
 * figure_cairo.c - figures as PNG, SVG or PDF through cairo: a title, the
 * panels in a grid (each with a frame, grid lines, ticks, labels and the
 * data clipped to it), a colour bar for maps, and the legend.
 */
#include <cairo-pdf.h>
#include <cairo-svg.h>
#include <cairo.h>
#include <math.h>
#include <string.h>
#include <strings.h>

#include "plot.h"

#define M_PI_  3.14159265358979323846

/* The smallest panel whose labels stay apart (points). */
#define MIN_PANEL_W 160
#define MIN_PANEL_H 120

int plot_file_format(const char *s)
{
    if (!s)
        return -1;
    if (strcasecmp(s, "png") == 0)
        return PLOT_PNG;
    if (strcasecmp(s, "svg") == 0)
        return PLOT_SVG;
    if (strcasecmp(s, "pdf") == 0)
        return PLOT_PDF;
    return -1;
}

static void set_colour(cairo_t *cr, int c)
{
    double rgb[3];
    plot_colour_rgb(c, rgb);
    cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
}

/* s cut with an ellipsis to at most maxpx wide in the current font. */
static void fit_px(cairo_t *cr, const char *s, double maxpx, char *out, size_t n)
{
    cairo_text_extents_t e;
    int m = 0;
    const unsigned char *u;
    snprintf(out, n, "%s", s);
    cairo_text_extents(cr, out, &e);
    if (e.x_advance <= maxpx)
        return;
    for (u = (const unsigned char *)s; *u; u++)
        m += (*u & 0xC0) != 0x80;
    for (m--; m > 1; m--) {
        plot_fit_text(s, m, out, n);
        cairo_text_extents(cr, out, &e);
        if (e.x_advance <= maxpx)
            return;
    }
    out[0] = '\0';
}

/* A perceptually even map from dark blue through green to yellow (five
 * stops of viridis), for t in 0..1. */
static void map_colour(double t, double rgb[3])
{
    static const double stop[5][3] = {{0.267, 0.005, 0.329}, {0.229, 0.322, 0.546},
                                      {0.128, 0.567, 0.551}, {0.369, 0.789, 0.383},
                                      {0.993, 0.906, 0.144}};
    double u = fmin(1.0, fmax(0.0, t)) * 4.0;
    int k = (int)fmin(3.0, floor(u)), j;
    for (j = 0; j < 3; j++)
        rgb[j] = stop[k][j] + (u - k) * (stop[k + 1][j] - stop[k][j]);
}

static void text_at(cairo_t *cr, double x, double y, const char *s, double ax, double ay)
{
    cairo_text_extents_t e;
    cairo_text_extents(cr, s, &e);
    cairo_move_to(cr, x - ax * e.width - e.x_bearing, y - ay * e.height - e.y_bearing);
    cairo_show_text(cr, s);
}

static void draw_panel(cairo_t *cr, const plot_panel *src, double x, double y, double w,
                       double h)
{
    plot_panel p = *src;
    double L = 62, R = p.map ? 90 : 12, T = 22, B = 42, bx, by, bw, bh, t[16], step;
    int n, k;
    size_t i;
    char lab[32], fit[256];
    bx = x + L;
    by = y + T;
    bw = w - L - R;
    bh = h - T - B;
    if (bw < 20 || bh < 20)
        return;
    plot_panel_limits(&p, bw / bh);
    cairo_set_font_size(cr, 12);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    set_colour(cr, PLOT_FG);
    fit_px(cr, p.title, w - 8, fit, sizeof fit);
    text_at(cr, x + w / 2, y + 4, fit, 0.5, 0.0);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 10);
    if (p.map && p.mw > 0 && p.mh > 0 && p.map_hi > p.map_lo) {
        double mx0 = p.map_x0, mx1 = p.map_x1, my0 = p.map_y0, my1 = p.map_y1, rgb[3];
        double ox, oy, cw, ch;
        int r, c;
        if (!(mx0 < mx1 && my0 < my1)) {
            mx0 = p.xmin;
            mx1 = p.xmax;
            my0 = p.ymin;
            my1 = p.ymax;
        }
        /* The raster over its own extent: on an equal panel a square
         * pupil stays square. */
        ox = bx + (mx0 - p.xmin) / (p.xmax - p.xmin) * bw;
        oy = by + (p.ymax - my1) / (p.ymax - p.ymin) * bh;
        cw = (mx1 - mx0) / (p.xmax - p.xmin) * bw / p.mw;
        ch = (my1 - my0) / (p.ymax - p.ymin) * bh / p.mh;
        for (r = 0; r < p.mh; r++)
            for (c = 0; c < p.mw; c++) {
                double v = p.map[r * p.mw + c];
                if (!isfinite(v))
                    continue;
                map_colour((v - p.map_lo) / (p.map_hi - p.map_lo), rgb);
                cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
                /* Overlapping by a fraction of a pixel, so no seams show. */
                cairo_rectangle(cr, ox + c * cw, oy + r * ch, cw + 0.5, ch + 0.5);
                cairo_fill(cr);
            }
        /* The colour bar, with its scale. */
        for (k = 0; k < 100; k++) {
            map_colour(k / 99.0, rgb);
            cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
            cairo_rectangle(cr, bx + bw + 10, by + bh - (k + 1) * bh / 100.0, 12, bh / 100.0 + 0.5);
            cairo_fill(cr);
        }
        n = plot_ticks(p.map_lo, p.map_hi, 5, t, 16);
        step = n > 1 ? t[1] - t[0] : 1.0;
        set_colour(cr, PLOT_FG);
        for (k = 0; k < n; k++) {
            plot_tick_label(t[k], step, lab, sizeof lab);
            text_at(cr, bx + bw + 25, by + bh - (t[k] - p.map_lo) / (p.map_hi - p.map_lo) * bh,
                    lab, 0.0, 0.5);
        }
        if (p.map_label[0] || p.map_unit[0]) {
            snprintf(fit, sizeof fit, p.map_unit[0] ? "%s (%s)" : "%s", p.map_label, p.map_unit);
            cairo_save(cr);
            cairo_translate(cr, x + w - 10, by + bh / 2);
            cairo_rotate(cr, -M_PI_ / 2);
            cairo_set_font_size(cr, 11);
            text_at(cr, 0, 0, fit, 0.5, 0.5);
            cairo_restore(cr);
        }
    }
    /* Grid lines and ticks. */
    cairo_set_line_width(cr, 0.5);
    /* About one tick label per 70 points, so they never touch. */
    n = plot_xticks(&p, p.ncat ? (int)(bw / 60) : (int)fmax(2, fmin(6, bw / 70)), t, 16);
    step = n > 1 ? t[1] - t[0] : 1.0;
    for (k = 0; k < n; k++) {
        double px = bx + (t[k] - p.xmin) / (p.xmax - p.xmin) * bw;
        cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
        cairo_move_to(cr, px, by);
        cairo_line_to(cr, px, by + bh);
        cairo_stroke(cr);
        set_colour(cr, PLOT_FG);
        plot_xtick_label(&p, t[k], step, lab, sizeof lab);
        text_at(cr, px, by + bh + 4, lab, 0.5, 0.0);
    }
    n = plot_ticks(p.ymin, p.ymax, (int)fmax(2, fmin(6, bh / 50)), t, 16);
    step = n > 1 ? t[1] - t[0] : 1.0;
    for (k = 0; k < n; k++) {
        double py = by + (p.ymax - t[k]) / (p.ymax - p.ymin) * bh;
        cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
        cairo_move_to(cr, bx, py);
        cairo_line_to(cr, bx + bw, py);
        cairo_stroke(cr);
        set_colour(cr, PLOT_FG);
        plot_tick_label(t[k], step, lab, sizeof lab);
        text_at(cr, bx - 4, py, lab, 1.0, 0.5);
    }
    set_colour(cr, PLOT_FG);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, bx, by, bw, bh);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 11);
    fit_px(cr, p.xlabel, bw, fit, sizeof fit);
    text_at(cr, bx + bw / 2, by + bh + 20, fit, 0.5, 0.0);
    cairo_save(cr);
    cairo_translate(cr, x + 12, by + bh / 2);
    cairo_rotate(cr, -M_PI_ / 2);
    fit_px(cr, p.ylabel, bh, fit, sizeof fit);
    text_at(cr, 0, 0, fit, 0.5, 0.5);
    cairo_restore(cr);
    /* The data, clipped to the frame. */
    cairo_save(cr);
    cairo_rectangle(cr, bx, by, bw, bh);
    cairo_clip(cr);
    for (k = 0; k < p.nseries; k++) {
        const plot_series *s = &p.s[k];
        int have = 0;
        set_colour(cr, s->color);
        cairo_set_line_width(cr, 1.2);
        if (s->kind == PLOT_BARS) {
            for (i = 0; i < s->n; i++) {
                double xa = bx + (s->x[i] - 0.5 * s->width - p.xmin) / (p.xmax - p.xmin) * bw;
                double xb = bx + (s->x[i] + 0.5 * s->width - p.xmin) / (p.xmax - p.xmin) * bw;
                double y0 = by + p.ymax / (p.ymax - p.ymin) * bh;
                double y1 = by + (p.ymax - s->y[i]) / (p.ymax - p.ymin) * bh;
                if (!isfinite(xa) || !isfinite(xb) || !isfinite(y0) || !isfinite(y1))
                    continue;
                /* Clamped, so a huge bar stays a finite rectangle. */
                y0 = fmin(by + bh + 1, fmax(by - 1, y0));
                y1 = fmin(by + bh + 1, fmax(by - 1, y1));
                cairo_rectangle(cr, xa, fmin(y0, y1), fmax(xb - xa, 0.5), fabs(y1 - y0));
                cairo_fill(cr);
            }
            continue;
        }
        for (i = 0; i < s->n; i++) {
            double px = bx + (s->x[i] - p.xmin) / (p.xmax - p.xmin) * bw;
            double py = by + (p.ymax - s->y[i]) / (p.ymax - p.ymin) * bh;
            if (!isfinite(px) || !isfinite(py) || fabs(px) > 1e7 || fabs(py) > 1e7) {
                if (have && s->kind == PLOT_LINES)
                    cairo_stroke(cr);
                have = 0;
                continue;
            }
            if (s->kind == PLOT_POINTS) {
                cairo_arc(cr, px, py, 1.3, 0, 2 * M_PI_);
                cairo_fill(cr);
            } else if (have) {
                cairo_line_to(cr, px, py);
            } else {
                cairo_move_to(cr, px, py);
                have = 1;
            }
        }
        if (have && s->kind == PLOT_LINES)
            cairo_stroke(cr);
    }
    if (p.scalebar > 0.0) {
        /* The scale bar, bottom left, on white so the data cannot hide it. */
        double len = p.scalebar / (p.xmax - p.xmin) * bw, sx = bx + 10, sy = by + bh - 10;
        cairo_text_extents_t e;
        cairo_set_font_size(cr, 10);
        cairo_text_extents(cr, p.scalebar_label, &e);
        cairo_set_source_rgb(cr, 1, 1, 1);
        cairo_rectangle(cr, bx + 1, sy - e.height - 14, fmax(len, e.x_advance) + 18,
                        e.height + 23);
        cairo_fill(cr);
        set_colour(cr, PLOT_FG);
        cairo_set_line_width(cr, 2.0);
        cairo_move_to(cr, sx, sy);
        cairo_line_to(cr, sx + len, sy);
        /* The end marks inside the bar, so it is len long overall. */
        cairo_move_to(cr, sx + 1, sy - 4);
        cairo_line_to(cr, sx + 1, sy + 4);
        cairo_move_to(cr, sx + len - 1, sy - 4);
        cairo_line_to(cr, sx + len - 1, sy + 4);
        cairo_stroke(cr);
        text_at(cr, sx, sy - 6, p.scalebar_label, 0.0, 1.0);
    }
    cairo_restore(cr);
}

/* Where draw puts things: the panels' grid and the bands above and below. */
typedef struct fig_layout {
    double top, bottom; /* the panels between */
    int nc, nr, legend_rows;
} fig_layout;

/* The legend's rows at width W, entries left to right. */
static int legend_rows(cairo_t *cr, const plot_figure *f, double W)
{
    double x = 20;
    int k, rows = 1;
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 11);
    for (k = 0; k < f->nlegend; k++) {
        cairo_text_extents_t e;
        double adv;
        cairo_text_extents(cr, f->legend[k].label, &e);
        adv = fmin(e.x_advance, W - 60) + 34;
        if (x > 20 && x + adv - 20 > W - 10) {
            rows++;
            x = 20;
        }
        x += adv;
    }
    return f->nlegend ? rows : 0;
}

static void layout(cairo_t *cr, const plot_figure *f, double W, double H, fig_layout *l)
{
    int nc;
    double score = -1;
    l->top = 8 + (f->title[0] ? 24 : 0);
    l->legend_rows = legend_rows(cr, f, W);
    l->bottom = H - (l->legend_rows ? 18.0 * l->legend_rows + 8 : 0);
    l->nc = 1;
    if (f->npanel == 0) {
        l->nr = 0;
        return;
    }
    if (f->ncol > 0)
        l->nc = f->ncol < f->npanel ? f->ncol : f->npanel;
    else
        for (nc = 1; nc <= f->npanel; nc++) {
            int nr = (f->npanel + nc - 1) / nc;
            double pw = W / nc, ph = (l->bottom - l->top) / nr;
            /* The roomiest panels, among those big enough if any are. */
            double sc = fmin(pw, ph) + (pw >= MIN_PANEL_W && ph >= MIN_PANEL_H ? 1e9 : 0.0);
            if (sc > score) {
                score = sc;
                l->nc = nc;
            }
        }
    l->nr = (f->npanel + l->nc - 1) / l->nc;
}

void plot_min_size(const plot_figure *fig, int w, int *minw, int *minh)
{
    cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1);
    cairo_t *cr = cairo_create(s);
    fig_layout l;
    int nc = fig->ncol > 0 ? fig->ncol : 1;
    double W;
    if (fig->ncol <= 0)
        /* As many columns as the width holds. */
        while (nc < fig->npanel && (nc + 1) * MIN_PANEL_W <= w)
            nc++;
    if (nc > fig->npanel && fig->npanel > 0)
        nc = fig->npanel;
    W = fmax(w, nc * MIN_PANEL_W);
    layout(cr, fig, W, 1e6, &l);
    *minw = (int)ceil(W);
    *minh = (int)ceil(l.top + (fig->npanel + nc - 1) / nc * MIN_PANEL_H + (1e6 - l.bottom));
    cairo_destroy(cr);
    cairo_surface_destroy(s);
}

/* The figure, or -1 with a message when the size cannot hold its panels. */
static int draw(cairo_t *cr, const plot_figure *f, double W, double H, char *err, size_t nerr)
{
    fig_layout l;
    double x, y;
    int k;
    char fit[256];
    layout(cr, f, W, H, &l);
    if (f->npanel && (W / l.nc < MIN_PANEL_W || (l.bottom - l.top) / l.nr < MIN_PANEL_H)) {
        int mw, mh;
        plot_min_size(f, (int)W, &mw, &mh);
        snprintf(err, nerr,
                 "picture size %.0fx%.0f is too small for %d panel%s with their labels: "
                 "--size %dx%d or larger",
                 W, H, f->npanel, f->npanel > 1 ? "s" : "", mw, mh);
        return -1;
    }
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    if (f->title[0]) {
        cairo_set_font_size(cr, 14);
        set_colour(cr, PLOT_FG);
        fit_px(cr, f->title, W - 16, fit, sizeof fit);
        text_at(cr, W / 2, 8, fit, 0.5, 0.0);
    }
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                           CAIRO_FONT_WEIGHT_NORMAL);
    if (f->nlegend) {
        /* Rows of entries, wrapped as legend_rows counted them. */
        x = 20;
        y = l.bottom + 4;
        cairo_set_font_size(cr, 11);
        for (k = 0; k < f->nlegend; k++) {
            cairo_text_extents_t e;
            double adv;
            fit_px(cr, f->legend[k].label, W - 60, fit, sizeof fit);
            cairo_text_extents(cr, fit, &e);
            adv = e.x_advance + 34;
            if (x > 20 && x + adv - 20 > W - 10) {
                x = 20;
                y += 18;
            }
            set_colour(cr, f->legend[k].color);
            cairo_rectangle(cr, x, y + 3, 10, 10);
            cairo_fill(cr);
            set_colour(cr, PLOT_FG);
            text_at(cr, x + 14, y + 8, fit, 0.0, 0.5);
            x += adv;
        }
    }
    if (f->npanel == 0)
        return 0;
    {
        double pw = W / l.nc, ph = (l.bottom - l.top) / l.nr;
        for (k = 0; k < f->npanel; k++)
            draw_panel(cr, &f->panel[k], (k % l.nc) * pw, l.top + (k / l.nc) * ph, pw, ph);
    }
    return 0;
}

static cairo_status_t to_file(void *closure, const unsigned char *data, unsigned int len)
{
    return fwrite(data, 1, len, (FILE *)closure) == len ? CAIRO_STATUS_SUCCESS
                                                         : CAIRO_STATUS_WRITE_ERROR;
}

int plot_write(const plot_figure *fig, int format, int width, int height, FILE *f, char *err,
               size_t nerr)
{
    cairo_surface_t *s;
    cairo_t *cr;
    cairo_status_t st;
    if (width < 100 || height < 100 || width > 20000 || height > 20000) {
        snprintf(err, nerr, "picture size %dx%d is not within 100 to 20000 on each side", width,
                 height);
        return -1;
    }
    if (format == PLOT_PNG)
        s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
    else if (format == PLOT_SVG)
        s = cairo_svg_surface_create_for_stream(to_file, f, width, height);
    else if (format == PLOT_PDF)
        s = cairo_pdf_surface_create_for_stream(to_file, f, width, height);
    else {
        snprintf(err, nerr, "unknown picture format %d", format);
        return -1;
    }
    cr = cairo_create(s);
    if (draw(cr, fig, width, height, err, nerr)) {
        cairo_destroy(cr);
        cairo_surface_destroy(s);
        return -1;
    }
    cairo_show_page(cr);
    st = cairo_status(cr);
    cairo_destroy(cr);
    if (st == CAIRO_STATUS_SUCCESS && format == PLOT_PNG)
        st = cairo_surface_write_to_png_stream(s, to_file, f);
    cairo_surface_finish(s);
    if (st == CAIRO_STATUS_SUCCESS)
        st = cairo_surface_status(s);
    cairo_surface_destroy(s);
    if (st != CAIRO_STATUS_SUCCESS) {
        snprintf(err, nerr, "cairo: %s", cairo_status_to_string(st));
        return -1;
    }
    return 0;
}
