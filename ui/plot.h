/*
 * plot.h - pictures of analyses, drawn once as a figure and rendered
 * either as terminal cells (Unicode braille, one colour per series) or as
 * a PNG, SVG or PDF file through cairo (figure_cairo.c).
 *
 * A figure holds panels; a panel holds axes (limits, labels, units
 * already applied to the data) and series of points or lines.  A series'
 * colour is a palette index (a wavelength's index, so every picture gives
 * a wavelength the same colour) or PLOT_FG.  Spot diagrams, ray fans and
 * layouts build figures in ui/views.c; an OPD fan is a figure of line
 * series in waves, a wavefront map a panel with a raster (plot_panel_map).
 */
#ifndef SG_UI_PLOT_H
#define SG_UI_PLOT_H

#include <stddef.h>
#include <stdio.h>

/* PLOT_BARS: a bar from y = 0 to each y, width wide about each x. */
enum { PLOT_POINTS = 0, PLOT_LINES = 1, PLOT_BARS = 2 };
#define PLOT_FG (-1)     /* the foreground colour */
#define PLOT_NPALETTE 6  /* a terminal's basic colours (ANSI 31 to 36) */
#define PLOT_NCOLOURS 64 /* distinct series colours (as many as fields) */
#define PLOT_MAXLEGEND 32

typedef struct plot_series {
    int kind;     /* PLOT_POINTS, PLOT_LINES (a NaN in x or y breaks the line), PLOT_BARS */
    int color;    /* palette index, or PLOT_FG */
    double width; /* a bar's width in x's units (PLOT_BARS) */
    size_t n;
    double *x, *y; /* owned by the panel */
} plot_series;

typedef struct plot_panel {
    char title[96];
    char xlabel[64], ylabel[64];
    double xmin, xmax, ymin, ymax; /* set by plot_panel_limits */
    int equal;     /* one unit is as long on both axes (spots, layouts, maps) */
    /* A scale bar this long in x's units (0: none), labelled with its length
     * and unit (spots, as Zemax draws them). */
    double scalebar;
    char scalebar_label[32];
    int nseries, cap;
    plot_series *s;
    /* A raster over the limits, for maps (wavefront): mw x mh values, row 0
     * at ymax; NaN is no data.  Drawn with a colour map and a scale. */
    int mw, mh;
    double *map, map_lo, map_hi;
    double map_x0, map_x1, map_y0, map_y1; /* the raster's extent (unset: the limits) */
    char map_label[24], map_unit[16];       /* what the colour bar shows, in what unit */
    /* Categories on x (bar charts): ticks at x = 1 .. ncat, labelled cat[k-1]
     * instead of by number. */
    int ncat;
    char (*cat)[12];
} plot_panel;

typedef struct plot_figure {
    char title[256];
    int ncol; /* panels per row (fans: a field's pair); 0 for the roomiest */
    int npanel, cap;
    plot_panel *panel;
    int nlegend;
    struct {
        int color;
        char label[48];
    } legend[PLOT_MAXLEGEND];
} plot_figure;

void plot_figure_init(plot_figure *f, const char *title);
void plot_figure_free(plot_figure *f);
/* A new panel (NULL when out of memory); limits from the data unless set. */
plot_panel *plot_add_panel(plot_figure *f, const char *title, const char *xlabel,
                           const char *ylabel);
/* Copies n points; 0, or -1 when out of memory. */
int plot_add_series(plot_panel *p, int kind, int color, const double *x, const double *y,
                    size_t n);
/* Bars of the given width about each x; 0, or -1 when out of memory. */
int plot_add_bars(plot_panel *p, int color, const double *x, const double *y, size_t n,
                  double width);
/* Names the x positions 1 .. n (copied, cut to 11 bytes); 0, or -1. */
int plot_panel_categories(plot_panel *p, int n, const char *const *labels);
/* The tick values and step of an x axis: the categories, or plot_ticks. */
int plot_xticks(const plot_panel *p, int n, double *t, int max);
/* A tick's label on the x axis: a category's name, or plot_tick_label. */
void plot_xtick_label(const plot_panel *p, double v, double step, char *buf, size_t n);
void plot_add_legend(plot_figure *f, int color, const char *label);
/* Series colour c (0 .. PLOT_NCOLOURS - 1 all differ; PLOT_FG black) as
 * red, green and blue from 0 to 1. */
void plot_colour_rgb(int c, double rgb[3]);
/* s cut to at most maxw characters: whole words and an ellipsis when it
 * does not fit (UTF-8, into out of n bytes). */
void plot_fit_text(const char *s, int maxw, char *out, size_t n);
/* Sets the panel's limits from its data with a margin (or to lo..hi when
 * lo < hi), widening the shorter axis of an equal panel. */
void plot_panel_limits(plot_panel *p, double aspect);
/* Round tick values covering lo..hi: about n of 1, 2 or 5 times 10^k.
 * Returns how many (at most max) in t. */
int plot_ticks(double lo, double hi, int n, double *t, int max);
/* A tick's label, with no more digits than the step needs. */
void plot_tick_label(double v, double step, char *buf, size_t n);

/* ---- terminal cells ---------------------------------------------------- */

typedef struct plot_cell {
    char ch[5];   /* one UTF-8 character */
    signed char color; /* palette index, or PLOT_FG */
} plot_cell;

typedef struct plot_grid {
    int w, h;
    plot_cell *c; /* row by row */
} plot_grid;

int plot_grid_init(plot_grid *g, int w, int h);
void plot_grid_free(plot_grid *g);
/* Writes UTF-8 text from column x of row y, cut at the grid's edge. */
void plot_grid_text(plot_grid *g, int x, int y, const char *s, int color);
/* The same, at most maxw characters. */
void plot_grid_text_n(plot_grid *g, int x, int y, const char *s, int color, int maxw);
/* The braille character of a 2 x 4 dot pattern: bit (col, row) is dot
 * (col 0..1, row 0..3), numbered as Unicode numbers them. */
unsigned plot_braille_bit(int col, int row);
/* The UTF-8 of U+2800 + bits into out (4 bytes and a NUL). */
void plot_braille_utf8(unsigned bits, char out[5]);
/* Draws the figure into the rectangle (x0, y0, w, h) of the grid: panels
 * side by side or in rows, each with a frame, ticks and labels, and the
 * legend on the last row.  Too small a rectangle gets a short note. */
void plot_draw_cells(const plot_figure *f, plot_grid *g, int x0, int y0, int w, int h);
/* Prints the grid; colour as ANSI escapes when colour is nonzero. */
int plot_grid_print(const plot_grid *g, FILE *out, int colour);
/* Whether to colour output to f: a terminal and NO_COLOR unset or empty. */
int plot_use_colour(FILE *f);

/* ---- files (figure_cairo.c) --------------------------------------------- */

enum { PLOT_PNG = 0, PLOT_SVG = 1, PLOT_PDF = 2 };
/* Parses "png", "svg" or "pdf"; -1 otherwise. */
int plot_file_format(const char *s);
/* The smallest size (pixels or points) at which a file of the figure
 * shows every panel with its labels apart, for a width of at least w. */
void plot_min_size(const plot_figure *fig, int w, int *minw, int *minh);
/* Renders the figure at width x height (pixels for PNG, points for SVG and
 * PDF) and writes it to f.  0, or -1 with a message in err (a size below
 * plot_min_size's is refused, naming the size it needs). */
int plot_write(const plot_figure *fig, int format, int width, int height, FILE *f, char *err,
               size_t nerr);

#endif
