/*
 * plot.c - figures and their terminal rendering: braille dots (2 x 4 per
 * cell) in a frame with ticks and labels, one colour per series.
 */
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "plot.h"

void plot_figure_init(plot_figure *f, const char *title)
{
    memset(f, 0, sizeof *f);
    snprintf(f->title, sizeof f->title, "%s", title ? title : "");
}

void plot_figure_free(plot_figure *f)
{
    int k, j;
    for (k = 0; k < f->npanel; k++) {
        plot_panel *p = &f->panel[k];
        for (j = 0; j < p->nseries; j++) {
            free(p->s[j].x);
            free(p->s[j].y);
        }
        free(p->s);
        free(p->map);
        free(p->cat);
    }
    free(f->panel);
    memset(f, 0, sizeof *f);
}

plot_panel *plot_add_panel(plot_figure *f, const char *title, const char *xlabel,
                           const char *ylabel)
{
    plot_panel *p;
    if (f->npanel == f->cap) {
        int cap = f->cap ? 2 * f->cap : 4;
        plot_panel *np = realloc(f->panel, (size_t)cap * sizeof *np);
        if (!np)
            return NULL;
        f->panel = np;
        f->cap = cap;
    }
    p = &f->panel[f->npanel++];
    memset(p, 0, sizeof *p);
    snprintf(p->title, sizeof p->title, "%s", title ? title : "");
    snprintf(p->xlabel, sizeof p->xlabel, "%s", xlabel ? xlabel : "");
    snprintf(p->ylabel, sizeof p->ylabel, "%s", ylabel ? ylabel : "");
    return p;
}

int plot_add_series(plot_panel *p, int kind, int color, const double *x, const double *y,
                    size_t n)
{
    plot_series *s;
    if (p->nseries == p->cap) {
        int cap = p->cap ? 2 * p->cap : 8;
        plot_series *ns = realloc(p->s, (size_t)cap * sizeof *ns);
        if (!ns)
            return -1;
        p->s = ns;
        p->cap = cap;
    }
    s = &p->s[p->nseries];
    s->kind = kind;
    s->color = color;
    s->width = 0.0;
    s->n = n;
    s->x = malloc((n ? n : 1) * sizeof *s->x);
    s->y = malloc((n ? n : 1) * sizeof *s->y);
    if (!s->x || !s->y) {
        free(s->x);
        free(s->y);
        return -1;
    }
    if (n) {
        memcpy(s->x, x, n * sizeof *x);
        memcpy(s->y, y, n * sizeof *y);
    }
    p->nseries++;
    return 0;
}

int plot_add_bars(plot_panel *p, int color, const double *x, const double *y, size_t n,
                  double width)
{
    if (plot_add_series(p, PLOT_BARS, color, x, y, n))
        return -1;
    p->s[p->nseries - 1].width = width;
    return 0;
}

int plot_panel_categories(plot_panel *p, int n, const char *const *labels)
{
    int k;
    free(p->cat);
    p->ncat = 0;
    p->cat = malloc((size_t)(n > 0 ? n : 1) * sizeof *p->cat);
    if (!p->cat)
        return -1;
    for (k = 0; k < n; k++)
        snprintf(p->cat[k], sizeof p->cat[k], "%s", labels[k]);
    p->ncat = n;
    return 0;
}

int plot_xticks(const plot_panel *p, int n, double *t, int max)
{
    int k, m = 0, every;
    if (!p->ncat)
        return plot_ticks(p->xmin, p->xmax, n, t, max);
    if (n < 1)
        n = 1;
    /* Every category when they fit, else every second, third, ...; the
     * last one (a total) always. */
    every = (p->ncat + 2 * n - 1) / (2 * n);
    if (max > 1 && every < (p->ncat + max - 2) / (max - 1))
        every = (p->ncat + max - 2) / (max - 1); /* room for the last */
    if (every < 1)
        every = 1;
    for (k = 1; k <= p->ncat && m < max; k++)
        if ((k - 1) % every == 0 || k == p->ncat) {
            if (k == p->ncat && m > 0 && k - t[m - 1] < every)
                m--; /* the total replaces a tick too close to it */
            t[m++] = k;
        }
    return m;
}

void plot_xtick_label(const plot_panel *p, double v, double step, char *buf, size_t n)
{
    long k = lround(v);
    if (p->ncat && k >= 1 && k <= p->ncat)
        snprintf(buf, n, "%s", p->cat[k - 1]);
    else
        plot_tick_label(v, step, buf, n);
}

void plot_add_legend(plot_figure *f, int color, const char *label)
{
    if (f->nlegend >= PLOT_MAXLEGEND)
        return;
    f->legend[f->nlegend].color = color;
    snprintf(f->legend[f->nlegend].label, sizeof f->legend[0].label, "%s", label);
    f->nlegend++;
}

void plot_colour_rgb(int c, double rgb[3])
{
    /* Twelve that a reader tells apart (the first six are the terminal's
     * blue, green, red, yellow, magenta and cyan), then, one at a time,
     * the point of a 6 x 6 x 6 grid of colours farthest from all chosen
     * and from black (none too light to see on white).  Made once; every caller computes
     * the same table, so a race only writes the same numbers. */
    static const double base[12][3] = {
        {0.00, 0.35, 0.85}, {0.00, 0.60, 0.20}, {0.85, 0.10, 0.10}, {0.90, 0.55, 0.00},
        {0.65, 0.20, 0.70}, {0.00, 0.60, 0.70}, {0.55, 0.34, 0.16}, {0.95, 0.40, 0.70},
        {0.45, 0.45, 0.45}, {0.60, 0.60, 0.10}, {0.10, 0.10, 0.45}, {0.40, 0.75, 1.00}};
    static double table[PLOT_NCOLOURS][3];
    static volatile int made;
    if (c < 0) {
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        return;
    }
    if (!made) {
        int k, j, g;
        memcpy(table, base, sizeof base);
        for (k = 12; k < PLOT_NCOLOURS; k++) {
            double best = -1.0, cand[3];
            for (g = 0; g < 216; g++) {
                double q[3] = {g / 36 * 0.2, g / 6 % 6 * 0.2, g % 6 * 0.2};
                double dmin = q[0] * q[0] + q[1] * q[1] + q[2] * q[2]; /* from black, the axes' */
                if (0.299 * q[0] + 0.587 * q[1] + 0.114 * q[2] > 0.75)
                    continue;
                for (j = 0; j < k; j++) {
                    double dr = q[0] - table[j][0], dg = q[1] - table[j][1],
                           db = q[2] - table[j][2];
                    dmin = fmin(dmin, dr * dr + dg * dg + db * db);
                }
                if (dmin > best) {
                    best = dmin;
                    memcpy(cand, q, sizeof q);
                }
            }
            memcpy(table[k], cand, sizeof cand);
        }
        made = 1;
    }
    memcpy(rgb, table[c % PLOT_NCOLOURS], 3 * sizeof *rgb);
}

void plot_fit_text(const char *s, int maxw, char *out, size_t n)
{
    size_t len = 0, cut = 0, space = 0, k;
    const unsigned char *u = (const unsigned char *)s;
    int chars = 0;
    if (n == 0)
        return;
    for (k = 0; u[k]; k++)
        chars += (u[k] & 0xC0) != 0x80;
    if (chars <= maxw || maxw < 2) {
        snprintf(out, n, "%s", chars <= maxw ? s : "");
        return;
    }
    /* The bytes of the first maxw - 1 characters, and the last space in them. */
    chars = 0;
    for (k = 0; u[k]; k++) {
        if ((u[k] & 0xC0) != 0x80) {
            if (chars == maxw - 1)
                break;
            chars++;
            if (u[k] == ' ')
                space = k;
        }
    }
    cut = k;
    /* A whole word when one ends past the middle (the cut may fall just
     * after one); else cut the word, unless it holds a digit: a number is
     * never cut short ("GEO 1911 um" may become "GEO…", never "GEO 19…"). */
    if (u[cut] != ' ' && space > 0 && 2 * space >= cut)
        cut = space;
    else if (u[cut] != ' ') {
        size_t w0 = space > 0 ? space + 1 : 0, i;
        for (i = w0; i < cut; i++)
            if (isdigit(u[i])) {
                cut = space;
                break;
            }
    }
    while (cut > 0 && (u[cut - 1] == ' ' || u[cut - 1] == ',' || u[cut - 1] == ':'))
        cut--;
    len = cut < n - 4 ? cut : n - 4;
    while (len > 0 && (u[len] & 0xC0) == 0x80)
        len--; /* never half a character */
    memcpy(out, s, len);
    memcpy(out + len, "\xe2\x80\xa6", 4); /* U+2026, the ellipsis, and the NUL */
}

void plot_panel_limits(plot_panel *p, double aspect)
{
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY, dx, dy;
    int k;
    size_t i;
    if (p->xmin < p->xmax && p->ymin < p->ymax)
        goto fit;
    for (k = 0; k < p->nseries; k++)
        for (i = 0; i < p->s[k].n; i++) {
            double x = p->s[k].x[i], y = p->s[k].y[i], hw = 0.0;
            if (!isfinite(x) || !isfinite(y))
                continue;
            if (p->s[k].kind == PLOT_BARS) {
                /* A bar stands on zero. */
                hw = 0.5 * p->s[k].width;
                y0 = fmin(y0, 0.0);
                y1 = fmax(y1, 0.0);
            }
            x0 = fmin(x0, x - hw);
            x1 = fmax(x1, x + hw);
            y0 = fmin(y0, y);
            y1 = fmax(y1, y);
        }
    if (!(x0 <= x1)) {
        x0 = y0 = -1.0;
        x1 = y1 = 1.0;
    }
    dx = x1 - x0;
    dy = y1 - y0;
    /* A flat set (a perfect focus, one ray) still gets a visible range. */
    if (!(dx > 1e-300 * fmax(1.0, fabs(x0))))
        dx = fmax(fabs(x0), fmax(dy, 1e-9));
    if (!(dy > 1e-300 * fmax(1.0, fabs(y0))))
        dy = fmax(fabs(y0), fmax(dx, 1e-9));
    if (p->xmin < p->xmax) {
        x0 = p->xmin;
        x1 = p->xmax;
    } else {
        double c = 0.5 * (x0 + x1);
        dx = fmax(dx, x1 - x0);
        x0 = c - 0.55 * dx;
        x1 = c + 0.55 * dx;
    }
    if (p->ymin < p->ymax) {
        y0 = p->ymin;
        y1 = p->ymax;
    } else {
        double c = 0.5 * (y0 + y1);
        dy = fmax(dy, y1 - y0);
        y0 = c - 0.55 * dy;
        y1 = c + 0.55 * dy;
    }
    p->xmin = x0;
    p->xmax = x1;
    p->ymin = y0;
    p->ymax = y1;
fit:
    if (p->equal && aspect > 0.0) {
        /* aspect: the plot's width over its height, in the same measure. */
        double w = p->xmax - p->xmin, h = p->ymax - p->ymin;
        if (w / h < aspect) {
            double c = 0.5 * (p->xmin + p->xmax);
            p->xmin = c - 0.5 * h * aspect;
            p->xmax = c + 0.5 * h * aspect;
        } else {
            double c = 0.5 * (p->ymin + p->ymax);
            p->ymin = c - 0.5 * w / aspect;
            p->ymax = c + 0.5 * w / aspect;
        }
    }
}

int plot_ticks(double lo, double hi, int n, double *t, int max)
{
    double span = hi - lo, raw, mag, step, v;
    int k = 0;
    if (!(span > 0.0) || !isfinite(span) || n < 1)
        return 0;
    raw = span / n;
    mag = pow(10.0, floor(log10(raw)));
    step = raw / mag < 1.5 ? mag : raw / mag < 3.5 ? 2 * mag : raw / mag < 7.5 ? 5 * mag
                                                                                : 10 * mag;
    for (v = ceil(lo / step) * step; v <= hi + 1e-9 * step && k < max; v += step) {
        /* A tick at a rounding of zero is zero. */
        t[k++] = fabs(v) < 1e-9 * step ? 0.0 : v;
    }
    return k;
}

void plot_tick_label(double v, double step, char *buf, size_t n)
{
    int dec = step > 0.0 ? (int)ceil(-log10(step) - 1e-9) : 0;
    if (dec < 0)
        dec = 0;
    if (fabs(v) >= 1e6 || (v != 0.0 && fabs(v) < 1e-4) || dec > 6)
        snprintf(buf, n, "%.3g", v);
    else
        snprintf(buf, n, "%.*f", dec, v);
}

/* ---- cells ------------------------------------------------------------- */

int plot_grid_init(plot_grid *g, int w, int h)
{
    int k;
    g->w = w > 0 ? w : 0;
    g->h = h > 0 ? h : 0;
    g->c = malloc((size_t)(g->w * g->h > 0 ? g->w * g->h : 1) * sizeof *g->c);
    if (!g->c)
        return -1;
    for (k = 0; k < g->w * g->h; k++) {
        strcpy(g->c[k].ch, " ");
        g->c[k].color = PLOT_FG;
    }
    return 0;
}

void plot_grid_free(plot_grid *g)
{
    free(g->c);
    g->c = NULL;
}

static plot_cell *cell_at(plot_grid *g, int x, int y)
{
    if (x < 0 || y < 0 || x >= g->w || y >= g->h)
        return NULL;
    return &g->c[y * g->w + x];
}

void plot_grid_text(plot_grid *g, int x, int y, const char *s, int color)
{
    plot_grid_text_n(g, x, y, s, color, 1 << 30);
}

void plot_grid_text_n(plot_grid *g, int x, int y, const char *s, int color, int maxw)
{
    const unsigned char *u = (const unsigned char *)s;
    while (*u && maxw-- > 0) {
        size_t len = *u < 0x80 ? 1 : (*u >> 5) == 6 ? 2 : (*u >> 4) == 14 ? 3 : 4;
        plot_cell *c = cell_at(g, x, y);
        size_t i;
        for (i = 1; i < len; i++)
            if (!u[i])
                return;
        if (c) {
            memcpy(c->ch, u, len);
            c->ch[len] = '\0';
            c->color = (signed char)color;
        }
        u += len;
        x++;
    }
}

unsigned plot_braille_bit(int col, int row)
{
    static const unsigned bits[4][2] = {{0x01, 0x08}, {0x02, 0x10}, {0x04, 0x20}, {0x40, 0x80}};
    if (col < 0 || col > 1 || row < 0 || row > 3)
        return 0;
    return bits[row][col];
}

void plot_braille_utf8(unsigned bits, char out[5])
{
    unsigned cp = 0x2800 + (bits & 0xff);
    out[0] = (char)(0xE0 | (cp >> 12));
    out[1] = (char)(0x80 | ((cp >> 6) & 0x3F));
    out[2] = (char)(0x80 | (cp & 0x3F));
    out[3] = '\0';
}

/* The dots of one panel's plotting area. */
typedef struct dots {
    int w, h; /* in cells */
    unsigned char *bits;
    signed char *color;
} dots;

static void dot(dots *d, long px, long py, int color)
{
    long cx = px / 2, cy = py / 4;
    if (px < 0 || py < 0 || cx >= d->w || cy >= d->h)
        return;
    d->bits[cy * d->w + cx] |= (unsigned char)plot_braille_bit((int)(px % 2), (int)(py % 4));
    d->color[cy * d->w + cx] = (signed char)color;
}

static void line(dots *d, long x0, long y0, long x1, long y1, int color)
{
    long dx = labs(x1 - x0), dy = -labs(y1 - y0), sx = x0 < x1 ? 1 : -1,
         sy = y0 < y1 ? 1 : -1, err = dx + dy, n = 0, e2;
    /* Bresenham; long lines far outside are cut by the step limit.  Both
     * tests read the error before either step, or the walk can pass its end
     * and streak on to the step limit. */
    while (n++ < 100000) {
        dot(d, x0, y0, color);
        if (x0 == x1 && y0 == y1)
            break;
        e2 = 2 * err;
        if (e2 >= dy) {
            err += dy;
            x0 += sx;
        }
        if (e2 <= dx) {
            err += dx;
            y0 += sy;
        }
    }
}

/* Each bar as every dot between zero and its top, at least one dot wide. */
static void bars(dots *d, const plot_panel *p, const plot_series *s, int W, int H)
{
    size_t i;
    for (i = 0; i < s->n; i++) {
        double sx = (2.0 * W - 1) / (p->xmax - p->xmin), sy = (4.0 * H - 1) / (p->ymax - p->ymin);
        double fa = (s->x[i] - 0.5 * s->width - p->xmin) * sx,
               fb = (s->x[i] + 0.5 * s->width - p->xmin) * sx;
        double f0 = (p->ymax - fmax(p->ymin, fmin(p->ymax, 0.0))) * sy,
               f1 = (p->ymax - fmax(p->ymin, fmin(p->ymax, s->y[i]))) * sy;
        long xa, xb, ya, yb, x, y;
        if (!isfinite(fa) || !isfinite(fb) || !isfinite(f0) || !isfinite(f1))
            continue;
        xa = lround(fmax(-1.0, fa));
        xb = lround(fmin(2.0 * W, fb)) - 1;
        if (xb < xa)
            xb = xa;
        ya = lround(fmin(f0, f1));
        yb = lround(fmax(f0, f1));
        for (x = xa; x <= xb; x++)
            for (y = ya; y <= yb; y++)
                dot(d, x, y, s->color);
    }
}

/* Centred in w columns; a longer text ends in an ellipsis. */
static void center_text(plot_grid *g, int x, int w, int y, const char *s, int color)
{
    size_t len = 0;
    char fit[256];
    const unsigned char *u;
    plot_fit_text(s, w, fit, sizeof fit);
    for (u = (const unsigned char *)fit; *u; u++)
        len += (*u & 0xC0) != 0x80;
    plot_grid_text_n(g, x + (w > (int)len ? (w - (int)len) / 2 : 0), y, fit, color, w);
}

static size_t text_len(const char *s)
{
    size_t len = 0;
    for (; *s; s++)
        len += ((unsigned char)*s & 0xC0) != 0x80;
    return len;
}

static void draw_panel(const plot_panel *src, plot_grid *g, int x0, int y0, int w, int h)
{
    plot_panel p = *src;
    double yt[16], xt[16], ystep, xstep;
    int nyt, nxt, lw = 0, k, W = 0, H, ax, ay, pass;
    char lab[32];
    dots d;
    size_t i;
    if (w < 12 || h < 6) {
        plot_grid_text(g, x0, y0, "(too small)", PLOT_FG);
        return;
    }
    /* A map keeps a row for its shade scale. */
    H = h - 4 - (p.map != NULL);
    /* The labels' width sets the plot's, which sets an equal panel's
     * limits and so the labels: twice round is enough, as the widest
     * label only widens. */
    for (pass = 0; pass < 2; pass++) {
        W = w - lw - 1;
        if (W < 4) {
            plot_grid_text(g, x0, y0, "(too small)", PLOT_FG);
            return;
        }
        p = *src;
        /* Braille dots are about square: 2 per cell across, 4 down. */
        plot_panel_limits(&p, (2.0 * W) / (4.0 * H));
        nyt = plot_ticks(p.ymin, p.ymax, H >= 8 ? 4 : 3, yt, 16);
        ystep = nyt > 1 ? yt[1] - yt[0] : p.ymax - p.ymin;
        for (k = 0; k < nyt; k++) {
            plot_tick_label(yt[k], ystep, lab, sizeof lab);
            if ((int)strlen(lab) > lw)
                lw = (int)strlen(lab);
        }
    }
    nxt = plot_xticks(&p, W >= 40 ? 5 : 3, xt, 16);
    xstep = nxt > 1 ? xt[1] - xt[0] : p.xmax - p.xmin;
    center_text(g, x0, w, y0, p.title, PLOT_FG);
    ax = x0 + lw;     /* the y axis's column */
    ay = y0 + 1 + H;  /* the x axis's row */
    for (k = 0; k < H; k++)
        plot_grid_text(g, ax, y0 + 1 + k, "│", PLOT_FG);
    for (k = 1; k <= W; k++)
        plot_grid_text(g, ax + k, ay, "─", PLOT_FG);
    plot_grid_text(g, ax, ay, "└", PLOT_FG);
    for (k = 0; k < nyt; k++) {
        int row = y0 + 1 + (int)lround((p.ymax - yt[k]) / (p.ymax - p.ymin) * (H - 1));
        plot_tick_label(yt[k], ystep, lab, sizeof lab);
        plot_grid_text(g, ax - (int)strlen(lab), row, lab, PLOT_FG);
        plot_grid_text(g, ax, row, "┤", PLOT_FG);
    }
    {
        int nextfree = x0;
        for (k = 0; k < nxt; k++) {
            int col = ax + 1 + (int)lround((xt[k] - p.xmin) / (p.xmax - p.xmin) * (W - 1));
            int len, at;
            plot_xtick_label(&p, xt[k], xstep, lab, sizeof lab);
            len = (int)strlen(lab);
            at = col - len / 2;
            plot_grid_text(g, col, ay, "┬", PLOT_FG);
            if (at + len > x0 + w)
                at = x0 + w - len; /* the last tick's label, moved in */
            if (at < nextfree)
                continue;
            plot_grid_text(g, at, ay + 1, lab, PLOT_FG);
            nextfree = at + len + 1;
        }
    }
    {
        /* "↑ y label" at the left and "x label →" at the right share the
         * line, cut with an ellipsis so neither overwrites the other: the
         * x label (it carries the unit of the ticks above it) keeps its
         * width while the y label keeps 6 columns, else each gets half. */
        char yl[160], xl[160], fit[160];
        int yw, xw, room = w - 1;
        snprintf(yl, sizeof yl, "↑ %s", p.ylabel);
        snprintf(xl, sizeof xl, "%s →", p.xlabel);
        yw = (int)text_len(yl);
        xw = (int)text_len(xl);
        if (yw + xw > room) {
            if (xw + 6 <= room) {
                yw = room - xw;
            } else if (yw <= room / 2) {
                xw = room - yw;
            } else {
                yw = room / 2;
                xw = room - yw;
            }
        }
        plot_fit_text(yl, yw, fit, sizeof fit);
        plot_grid_text_n(g, x0, ay + 2, fit, PLOT_FG, yw);
        plot_fit_text(xl, xw, fit, sizeof fit);
        plot_grid_text_n(g, x0 + w - (int)text_len(fit), ay + 2, fit, PLOT_FG, xw);
    }
    d.w = W;
    d.h = H;
    d.bits = calloc((size_t)(W * H), 1);
    d.color = calloc((size_t)(W * H), 1);
    if (!d.bits || !d.color) {
        free(d.bits);
        free(d.color);
        return;
    }
    memset(d.color, PLOT_FG, (size_t)(W * H));
    if (p.map && p.mw > 0 && p.mh > 0) {
        /* A map in shades: each cell takes the value under its centre; the
         * lowest is a dot, so a blank is a point with no data. */
        static const char *const shade[] = {"·", "░", "▒", "▓", "█"};
        double mx0 = p.map_x0, mx1 = p.map_x1, my0 = p.map_y0, my1 = p.map_y1;
        char sl[160], a[32], b[32];
        int r, c;
        if (!(mx0 < mx1 && my0 < my1)) {
            mx0 = p.xmin;
            mx1 = p.xmax;
            my0 = p.ymin;
            my1 = p.ymax;
        }
        for (r = 0; r < H; r++)
            for (c = 0; c < W; c++) {
                /* The cell's centre in the data, then in the raster. */
                double xv = p.xmin + (c + 0.5) / W * (p.xmax - p.xmin);
                double yv = p.ymax - (r + 0.5) / H * (p.ymax - p.ymin);
                double fx = (xv - mx0) / (mx1 - mx0) * p.mw, fy = (my1 - yv) / (my1 - my0) * p.mh;
                int mx, my;
                double v, t;
                if (!(fx >= 0 && fx < p.mw && fy >= 0 && fy < p.mh))
                    continue;
                mx = (int)fx;
                my = (int)fy;
                v = p.map[my * p.mw + mx];
                if (!isfinite(v) || !(p.map_hi > p.map_lo))
                    continue;
                t = (v - p.map_lo) / (p.map_hi - p.map_lo);
                plot_grid_text(g, ax + 1 + c, y0 + 1 + r, shade[(int)fmin(4, fmax(0, t * 4.999))],
                               PLOT_FG);
            }
        /* The shade scale, on the terminal only (files have a colour bar). */
        snprintf(a, sizeof a, "%.3g", p.map_lo);
        snprintf(b, sizeof b, "%.3g", p.map_hi);
        snprintf(sl, sizeof sl, "%s from · %s to █ %s %s", p.map_label[0] ? p.map_label : "value",
                 a, b, p.map_unit);
        plot_grid_text_n(g, x0, ay + 3, sl, PLOT_FG, w);
    }
    for (k = 0; k < p.nseries; k++) {
        const plot_series *s = &p.s[k];
        long lx = 0, ly = 0;
        int have = 0;
        if (s->kind == PLOT_BARS) {
            bars(&d, &p, s, W, H);
            continue;
        }
        for (i = 0; i < s->n; i++) {
            double fx = (s->x[i] - p.xmin) / (p.xmax - p.xmin) * (2.0 * W - 1);
            double fy = (p.ymax - s->y[i]) / (p.ymax - p.ymin) * (4.0 * H - 1);
            long px, py;
            if (!isfinite(fx) || !isfinite(fy) || fabs(fx) > 1e6 || fabs(fy) > 1e6) {
                have = 0;
                continue;
            }
            px = lround(fx);
            py = lround(fy);
            if (s->kind == PLOT_LINES && have)
                line(&d, lx, ly, px, py, s->color);
            else
                dot(&d, px, py, s->color);
            lx = px;
            ly = py;
            have = 1;
        }
    }
    for (k = 0; k < W * H; k++)
        if (d.bits[k]) {
            char ch[5];
            plot_braille_utf8(d.bits[k], ch);
            plot_grid_text(g, ax + 1 + k % W, y0 + 1 + k / W, ch, d.color[k]);
        }
    free(d.bits);
    free(d.color);
}

void plot_draw_cells(const plot_figure *f, plot_grid *g, int x0, int y0, int w, int h)
{
    int top = y0, bottom = y0 + h, nc, best = 1, k;
    double score = -1.0;
    if (w < 12 || h < 7) {
        plot_grid_text(g, x0, y0, "(window too small for the picture)", PLOT_FG);
        return;
    }
    if (f->title[0]) {
        char t[256];
        snprintf(t, sizeof t, "%s", f->title);
        center_text(g, x0, w, top++, t, PLOT_FG);
    }
    if (f->nlegend) {
        /* As many rows as the entries need (at most a third of the
         * height), each entry whole or ending in an ellipsis. */
        int rows = 1, x = x0, row;
        for (k = 0; k < f->nlegend; k++) {
            int len = (int)text_len(f->legend[k].label) + 3;
            if (x > x0 && x + len > x0 + w) {
                rows++;
                x = x0;
            }
            x += len;
        }
        if (rows > h / 3)
            rows = h / 3 > 0 ? h / 3 : 1;
        bottom -= rows;
        x = x0;
        row = 0;
        for (k = 0; k < f->nlegend; k++) {
            char fit[64];
            int len = (int)text_len(f->legend[k].label) + 3;
            if (x > x0 && x + len > x0 + w) {
                if (++row == rows)
                    break;
                x = x0;
            }
            plot_fit_text(f->legend[k].label, w - 3, fit, sizeof fit);
            plot_grid_text(g, x, bottom + row, "■", f->legend[k].color);
            plot_grid_text(g, x + 1, bottom + row, " ", PLOT_FG);
            plot_grid_text_n(g, x + 2, bottom + row, fit, PLOT_FG, w - 2);
            x += len;
        }
    }
    if (f->npanel == 0)
        return;
    /* Columns that give the roomiest panels (a cell is about twice as tall
     * as it is wide). */
    for (nc = 1; nc <= f->npanel; nc++) {
        int nr = (f->npanel + nc - 1) / nc;
        double pw = (double)w / nc, ph = (double)(bottom - top) / nr;
        double sc = fmin(pw / 2.0, ph);
        if (f->ncol > 0 && nc != f->ncol && f->ncol <= f->npanel && w / f->ncol >= 14)
            continue; /* the figure's own columns, where they fit */
        if (pw >= 14 && ph >= 6 && sc > score) {
            score = sc;
            best = nc;
        }
    }
    if (score < 0.0) {
        /* Not all fit: as many rows of the widest panels as room allows,
         * and a note of the rest (a file has room for every one). */
        nc = w / 14 > 0 ? w / 14 : 1;
        if (f->ncol > 0 && w / f->ncol >= 14)
            nc = f->ncol;
        if (nc > f->npanel)
            nc = f->npanel;
        best = nc;
    }
    nc = best;
    {
        int nr = (f->npanel + nc - 1) / nc, pw = w / nc, ph, shown;
        if ((bottom - top) / nr < 6)
            nr = (bottom - top) / 6 > 0 ? (bottom - top) / 6 : 1;
        ph = (bottom - top) / nr;
        shown = nr * nc < f->npanel ? nr * nc : f->npanel;
        if (shown < f->npanel) {
            char note[64];
            snprintf(note, sizeof note, "(%d of %d panels; export shows all)", shown,
                     f->npanel);
            plot_grid_text_n(g, x0 + w - (int)strlen(note), top - 1 >= y0 ? top - 1 : y0, note,
                             PLOT_FG, w);
            nr = shown / nc;
        }
        for (k = 0; k < shown; k++)
            draw_panel(&f->panel[k], g, x0 + (k % nc) * pw, top + (k / nc) * ph, pw - 1, ph);
    }
}

int plot_grid_print(const plot_grid *g, FILE *out, int colour)
{
    static const int ansi[PLOT_NPALETTE] = {34, 32, 31, 33, 35, 36};
    double rgb[3];
    int x, y;
    for (y = 0; y < g->h; y++) {
        int cur = PLOT_FG, end = g->w;
        while (end > 0 && strcmp(g->c[y * g->w + end - 1].ch, " ") == 0)
            end--;
        for (x = 0; x < end; x++) {
            const plot_cell *c = &g->c[y * g->w + x];
            /* A blank needs no colour: no escape for it. */
            if (colour && c->color != cur && strcmp(c->ch, " ") != 0) {
                if (c->color == PLOT_FG)
                    fputs("\033[0m", out);
                else if (c->color < PLOT_NPALETTE)
                    fprintf(out, "\033[%dm", ansi[c->color]);
                else {
                    /* Beyond the six: the nearest of the 256-colour cube. */
                    plot_colour_rgb(c->color, rgb);
                    fprintf(out, "\033[38;5;%dm",
                            16 + 36 * (int)lround(rgb[0] * 5) + 6 * (int)lround(rgb[1] * 5) +
                                (int)lround(rgb[2] * 5));
                }
                cur = c->color;
            }
            fputs(c->ch, out);
        }
        if (colour && cur != PLOT_FG)
            fputs("\033[0m", out);
        if (fputc('\n', out) == EOF)
            return -1;
    }
    return ferror(out) ? -1 : 0;
}

int plot_use_colour(FILE *f)
{
    const char *nc = getenv("NO_COLOR");
    if (nc && *nc)
        return 0;
    return isatty(fileno(f));
}
