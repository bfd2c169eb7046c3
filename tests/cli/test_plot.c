/*
 * test_plot.c - the picture code of ui/plot.c and ui/figure_cairo.c: the
 * braille dot numbering of Unicode, dots landing in the cell and bit the
 * mapping says, ticks, and PNG, SVG and PDF files rendered at a fixed size
 * with their headers read back (the PNG's IHDR width and height).
 */
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include <cairo.h>

#include "plot.h"

static int has(const char *s, size_t len, const char *needle)
{
    size_t n = strlen(needle), k;
    for (k = 0; k + n <= len; k++)
        if (memcmp(s + k, needle, n) == 0)
            return 1;
    return 0;
}

/* Unicode's braille block: dots 1-2-3-7 down the left column, 4-5-6-8 down
 * the right, dot k at bit k - 1 of U+2800 + bits. */
static void test_braille_bits(void **state)
{
    static const int dotnum[4][2] = {{1, 4}, {2, 5}, {3, 6}, {7, 8}};
    char out[5];
    int r, c;
    (void)state;
    for (r = 0; r < 4; r++)
        for (c = 0; c < 2; c++)
            assert_int_equal(plot_braille_bit(c, r), 1u << (dotnum[r][c] - 1));
    assert_int_equal(plot_braille_bit(2, 0), 0);
    plot_braille_utf8(0, out);
    assert_string_equal(out, "\xe2\xa0\x80"); /* U+2800, blank */
    plot_braille_utf8(0xff, out);
    assert_string_equal(out, "\xe2\xa3\xbf"); /* U+28FF, all eight dots */
    plot_braille_utf8(0x01, out);
    assert_string_equal(out, "\xe2\xa0\x81"); /* U+2801, dot 1 */
}

/* Finds the first braille cell of the grid: its position and bits. */
static int find_braille(const plot_grid *g, int *x, int *y, unsigned *bits)
{
    int k;
    for (k = 0; k < g->w * g->h; k++) {
        const unsigned char *s = (const unsigned char *)g->c[k].ch;
        if (s[0] == 0xE2 && (s[1] & 0xFC) == 0xA0) {
            unsigned cp = ((unsigned)(s[0] & 0x0F) << 12) | ((unsigned)(s[1] & 0x3F) << 6) |
                          (s[2] & 0x3F);
            *x = k % g->w;
            *y = k / g->w;
            *bits = cp - 0x2800;
            return 1;
        }
    }
    return 0;
}

/* One point at the top-left and one at the bottom-right corner of the
 * limits land on the first and last dot of the plotting area. */
static void test_points_to_cells(void **state)
{
    plot_figure f;
    plot_panel *p;
    plot_grid g;
    double x[1] = {0.0}, y[1] = {10.0};
    int cx = -1, cy = -1, k, last = -1; /* set by find_braille; the release build cannot tell */
    unsigned bits;
    (void)state;
    plot_figure_init(&f, NULL);
    p = plot_add_panel(&f, "t", "x", "y");
    assert_non_null(p);
    p->xmin = 0;
    p->xmax = 10;
    p->ymin = 0;
    p->ymax = 10;
    assert_int_equal(plot_add_series(p, PLOT_POINTS, 2, x, y, 1), 0);
    assert_int_equal(plot_grid_init(&g, 40, 12), 0);
    plot_draw_cells(&f, &g, 0, 0, 40, 12);
    assert_true(find_braille(&g, &cx, &cy, &bits));
    assert_int_equal(bits, plot_braille_bit(0, 0)); /* the top-left dot */
    assert_int_equal(cy, 1);                        /* first row under the title */
    assert_int_equal(g.c[cy * g.w + cx].color, 2);
    /* The y axis (a line, or a tick on it) is the cell left of it. */
    assert_true(strcmp(g.c[cy * g.w + cx - 1].ch, "\xe2\x94\x82") == 0 ||
                strcmp(g.c[cy * g.w + cx - 1].ch, "\xe2\x94\xa4") == 0);
    plot_grid_free(&g);
    /* Now the bottom-right corner. */
    p->s[0].x[0] = 10.0;
    p->s[0].y[0] = 0.0;
    assert_int_equal(plot_grid_init(&g, 40, 12), 0);
    plot_draw_cells(&f, &g, 0, 0, 40, 12);
    assert_true(find_braille(&g, &cx, &cy, &bits));
    assert_int_equal(bits, plot_braille_bit(1, 3));
    assert_int_equal(cy, 12 - 4); /* the last row above the x axis (then ticks, labels) */
    for (k = 0; k < g.w; k++)
        if (strcmp(g.c[(cy + 1) * g.w + k].ch, "\xe2\x94\x80") == 0 ||
            strcmp(g.c[(cy + 1) * g.w + k].ch, "\xe2\x94\xac") == 0)
            last = k;
    assert_int_equal(cx, last); /* the last column of the x axis */
    plot_grid_free(&g);
    plot_figure_free(&f);
}

static void test_ticks(void **state)
{
    double t[16];
    char b[32];
    int n;
    (void)state;
    n = plot_ticks(-0.93, 1.07, 4, t, 16);
    assert_int_equal(n, 4);
    assert_true(t[0] == -0.5 && t[1] == 0.0 && t[3] == 1.0);
    n = plot_ticks(0.0, 1e-3, 5, t, 16);
    assert_true(n >= 5 && fabs(t[1] - 2e-4) < 1e-18);
    plot_tick_label(0.0002, 0.0002, b, sizeof b);
    assert_string_equal(b, "0.0002");
    plot_tick_label(-40.0, 20.0, b, sizeof b);
    assert_string_equal(b, "-40");
    assert_int_equal(plot_ticks(1.0, 1.0, 4, t, 16), 0);
}

static void sample(plot_figure *f)
{
    double x[50], y[50];
    int k;
    plot_panel *p;
    plot_figure_init(f, "A test figure");
    for (k = 0; k < 50; k++) {
        x[k] = cos(k * 0.3) * 10;
        y[k] = sin(k * 0.3) * 5;
    }
    p = plot_add_panel(f, "points", "x (µm)", "y (µm)");
    p->equal = 1;
    plot_add_series(p, PLOT_POINTS, 0, x, y, 50);
    p = plot_add_panel(f, "lines", "Py", "ey (µm)");
    y[3] = NAN;
    plot_add_series(p, PLOT_LINES, 1, x, y, 50);
    plot_add_legend(f, 0, "0.4861 µm");
    plot_add_legend(f, 1, "0.5876 µm");
    p = plot_add_panel(f, "map", "Px", "Py");
    p->mw = p->mh = 8;
    p->map = malloc(64 * sizeof *p->map);
    for (k = 0; k < 64; k++)
        p->map[k] = k == 9 ? NAN : k;
    p->map_lo = 0;
    p->map_hi = 63;
    p->xmin = p->ymin = -1;
    p->xmax = p->ymax = 1;
}

static unsigned long be32(const unsigned char *b)
{
    return ((unsigned long)b[0] << 24) | ((unsigned long)b[1] << 16) |
           ((unsigned long)b[2] << 8) | b[3];
}

static void test_files(void **state)
{
    plot_figure f;
    char err[256];
    unsigned char buf[64];
    FILE *t;
    size_t n;
    (void)state;
    sample(&f);
    /* PNG: signature, then IHDR with the width and height asked for. */
    t = tmpfile();
    assert_int_equal(plot_write(&f, PLOT_PNG, 640, 480, t, err, sizeof err), 0);
    rewind(t);
    n = fread(buf, 1, 24, t);
    assert_int_equal(n, 24);
    assert_memory_equal(buf, "\x89PNG\r\n\x1a\n", 8);
    assert_memory_equal(buf + 12, "IHDR", 4);
    assert_int_equal(be32(buf + 16), 640);
    assert_int_equal(be32(buf + 20), 480);
    fclose(t);
    /* SVG: XML with an svg element of that size in points. */
    t = tmpfile();
    assert_int_equal(plot_write(&f, PLOT_SVG, 640, 480, t, err, sizeof err), 0);
    {
        long len = ftell(t);
        char *s = malloc((size_t)len + 1);
        rewind(t);
        assert_int_equal(fread(s, 1, (size_t)len, t), (size_t)len);
        s[len] = '\0';
        assert_true(strncmp(s, "<?xml", 5) == 0);
        assert_non_null(strstr(s, "<svg"));
        assert_non_null(strstr(s, "width=\"640pt\""));
        assert_non_null(strstr(s, "height=\"480pt\""));
        assert_non_null(strstr(s, "</svg>"));
        free(s);
    }
    fclose(t);
    /* PDF: the header, one page of 640 x 480 points, and the end marker. */
    t = tmpfile();
    assert_int_equal(plot_write(&f, PLOT_PDF, 640, 480, t, err, sizeof err), 0);
    {
        long len = ftell(t);
        char *s = malloc((size_t)len + 1);
        rewind(t);
        assert_int_equal(fread(s, 1, (size_t)len, t), (size_t)len);
        s[len] = '\0';
        assert_true(strncmp(s, "%PDF-", 5) == 0);
        assert_true(has(s, (size_t)len, "/MediaBox [ 0 0 640 480 ]"));
        assert_true(has(s, (size_t)len, "%%EOF"));
        free(s);
    }
    fclose(t);
    /* Refused sizes say why. */
    t = tmpfile();
    assert_int_equal(plot_write(&f, PLOT_PNG, 10, 480, t, err, sizeof err), -1);
    assert_non_null(strstr(err, "100 to 20000"));
    fclose(t);
    assert_int_equal(plot_file_format("SVG"), PLOT_SVG);
    assert_int_equal(plot_file_format("gif"), -1);
    plot_figure_free(&f);
}

/* A figure drawn in cells at a fixed size, printed without colour: the
 * title, the legend and no escape sequences. */
static void test_cells_print(void **state)
{
    plot_figure f;
    plot_grid g;
    FILE *t = tmpfile();
    char buf[8192];
    size_t n;
    (void)state;
    sample(&f);
    assert_int_equal(plot_grid_init(&g, 80, 24), 0);
    plot_draw_cells(&f, &g, 0, 0, 80, 24);
    assert_int_equal(plot_grid_print(&g, t, 0), 0);
    rewind(t);
    n = fread(buf, 1, sizeof buf - 1, t);
    buf[n] = '\0';
    assert_non_null(strstr(buf, "A test figure"));
    assert_non_null(strstr(buf, "0.5876 µm"));
    assert_null(strchr(buf, '\033'));
    fclose(t);
    t = tmpfile();
    assert_int_equal(plot_grid_print(&g, t, 1), 0);
    rewind(t);
    n = fread(buf, 1, sizeof buf - 1, t);
    buf[n] = '\0';
    assert_non_null(strstr(buf, "\033[34m")); /* palette 0 is blue */
    fclose(t);
    plot_grid_free(&g);
    plot_figure_free(&f);
}

/* A panel title too wide for its panel is cut at a blank and ends in an
 * ellipsis: the number after GEO is shown whole or not at all (issue 30,
 * item 19: "GEO 19" where the value was 1911). */
static void test_title_cut(void **state)
{
    static const struct {
        int w;
        const char *title, *want;
    } cases[] = {
        {40, "RMS 12.3, GEO 1911 um", "RMS 12.3, GEO 1911 um"}, /* fits: whole */
        {20, "RMS 12.3, GEO 1911 um", "RMS 12.3, GEO 1911…"},   /* the unit goes */
        {16, "RMS 12.3, GEO 1911 um", "RMS 12.3, GEO…"},        /* never "GEO 19" */
        {20, "RMS 12.3, GEO 191100 um", "RMS 12.3, GEO…"},      /* never "GEO 1911" */
        {14, "GEO 1911000000 um", "GEO…"},      /* no blank past the middle */
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        plot_figure f;
        plot_grid g;
        plot_panel *p;
        double x[2] = {0, 1}, y[2] = {0, 1};
        FILE *t = tmpfile();
        char buf[8192], *row, *end;
        size_t n;
        plot_figure_init(&f, "");
        p = plot_add_panel(&f, cases[i].title, "x", "y");
        plot_add_series(p, PLOT_LINES, 0, x, y, 2);
        assert_int_equal(plot_grid_init(&g, cases[i].w, 12), 0);
        plot_draw_cells(&f, &g, 0, 0, cases[i].w, 12);
        assert_int_equal(plot_grid_print(&g, t, 0), 0);
        rewind(t);
        n = fread(buf, 1, sizeof buf - 1, t);
        buf[n] = '\0';
        /* The first row, without the centring's blanks. */
        end = strchr(buf, '\n');
        assert_non_null(end);
        *end = '\0';
        for (row = buf; *row == ' '; row++)
            ;
        while (end > row && end[-1] == ' ')
            *--end = '\0';
        assert_string_equal(row, cases[i].want);
        fclose(t);
        plot_grid_free(&g);
        plot_figure_free(&f);
    }
}

/* The axis labels share the line under a narrow panel: the x label (with
 * its unit) whole, the y label cut with an ellipsis, never one written
 * over the other (the editor's encircled view showed "fraction oradius
 * (um)"). */
static void test_axis_labels_narrow(void **state)
{
    static const struct {
        int w;
        const char *want;
    } cases[] = {
        {60, "↑ fraction of encircled energy"}, /* room for both: whole */
        {26, "↑ fraction…"},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        plot_figure f;
        plot_grid g;
        plot_panel *p;
        double x[2] = {0, 40}, y[2] = {0, 1};
        FILE *t = tmpfile();
        char buf[8192], *row;
        size_t n;
        plot_figure_init(&f, "");
        p = plot_add_panel(&f, NULL, "radius (um)", "fraction of encircled energy");
        plot_add_series(p, PLOT_LINES, 0, x, y, 2);
        assert_int_equal(plot_grid_init(&g, cases[i].w, 12), 0);
        plot_draw_cells(&f, &g, 0, 0, cases[i].w, 12);
        assert_int_equal(plot_grid_print(&g, t, 0), 0);
        rewind(t);
        n = fread(buf, 1, sizeof buf - 1, t);
        buf[n] = '\0';
        row = strstr(buf, "↑");
        assert_non_null(row);
        if (strchr(row, '\n'))
            *strchr(row, '\n') = '\0';
        print_message("# width %d: \"%s\"\n", cases[i].w, row);
        assert_non_null(strstr(row, cases[i].want));
        assert_non_null(strstr(row, "radius (um) →"));
        fclose(t);
        plot_grid_free(&g);
        plot_figure_free(&f);
    }
}

/* Every dot of a figure's first panel in dot coordinates (2 across and 4
 * down per cell, from the grid's corner); how many, at most max. */
static int grid_dots(const plot_grid *g, int (*xy)[2], int max)
{
    int k, n = 0, r, c;
    for (k = 0; k < g->w * g->h; k++) {
        const unsigned char *s = (const unsigned char *)g->c[k].ch;
        unsigned bits;
        if (!(s[0] == 0xE2 && (s[1] & 0xFC) == 0xA0))
            continue;
        bits = (((unsigned)(s[1] & 0x3F) << 6) | (s[2] & 0x3F)) - 0x800;
        for (r = 0; r < 4; r++)
            for (c = 0; c < 2; c++)
                if ((bits & plot_braille_bit(c, r)) && n < max) {
                    xy[n][0] = 2 * (k % g->w) + c;
                    xy[n][1] = 4 * (k / g->w) + r;
                    n++;
                }
    }
    return n;
}

/* A closed circle drawn as a line (the spot's Airy circle) stays on the
 * circle: its vertices drawn as points give the circle's centre and radius
 * in dots (braille dots are square on an equal panel), and every dot of the
 * line lies within two dots of that radius.  The line walk once passed its
 * end and streaked across the panel. */
static void test_circle_line(void **state)
{
    static int pts[20000][2], lin[20000][2];
    double x[73], y[73], cx, cy, r;
    int kind, np = 0, nl = 0, k, x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1;
    (void)state;
    for (k = 0; k < 73; k++) {
        x[k] = 4.0 * cos(2 * 3.14159265358979323846 * k / 72);
        y[k] = 4.0 * sin(2 * 3.14159265358979323846 * k / 72);
    }
    for (kind = 0; kind < 2; kind++) {
        plot_figure f;
        plot_panel *p;
        plot_grid g;
        plot_figure_init(&f, NULL);
        p = plot_add_panel(&f, "", "x", "y");
        assert_non_null(p);
        p->equal = 1;
        p->xmin = p->ymin = -5;
        p->xmax = p->ymax = 5;
        assert_int_equal(plot_add_series(p, kind ? PLOT_LINES : PLOT_POINTS, 0, x, y, 73), 0);
        assert_int_equal(plot_grid_init(&g, 60, 24), 0);
        plot_draw_cells(&f, &g, 0, 0, 60, 24);
        if (kind)
            nl = grid_dots(&g, lin, 20000);
        else
            np = grid_dots(&g, pts, 20000);
        plot_grid_free(&g);
        plot_figure_free(&f);
    }
    assert_true(np > 20 && nl > np);
    for (k = 0; k < np; k++) {
        x0 = pts[k][0] < x0 ? pts[k][0] : x0;
        x1 = pts[k][0] > x1 ? pts[k][0] : x1;
        y0 = pts[k][1] < y0 ? pts[k][1] : y0;
        y1 = pts[k][1] > y1 ? pts[k][1] : y1;
    }
    cx = 0.5 * (x0 + x1);
    cy = 0.5 * (y0 + y1);
    r = 0.25 * ((x1 - x0) + (y1 - y0));
    for (k = 0; k < nl; k++) {
        double d = hypot(lin[k][0] - cx, lin[k][1] - cy);
        if (fabs(d - r) > 2.0)
            fail_msg("dot (%d, %d) is %.1f dots from the centre; the circle's radius is %.1f",
                     lin[k][0], lin[k][1], d, r);
    }
}

/* ---- pictures read back: the PNG's pixels through cairo ---------------- */

static cairo_status_t read_file(void *closure, unsigned char *data, unsigned int len)
{
    return fread(data, 1, len, (FILE *)closure) == len ? CAIRO_STATUS_SUCCESS
                                                       : CAIRO_STATUS_READ_ERROR;
}

/* The figure as a PNG of w x h, read back as an image. */
static cairo_surface_t *render(const plot_figure *f, int w, int h)
{
    char err[256];
    FILE *t = tmpfile();
    cairo_surface_t *img;
    assert_non_null(t);
    if (plot_write(f, PLOT_PNG, w, h, t, err, sizeof err))
        fail_msg("plot_write: %s", err);
    rewind(t);
    img = cairo_image_surface_create_from_png_stream(read_file, t);
    fclose(t);
    assert_int_equal(cairo_surface_status(img), CAIRO_STATUS_SUCCESS);
    assert_int_equal(cairo_image_surface_get_width(img), w);
    return img;
}

static void pixel(cairo_surface_t *img, int x, int y, int rgb[3])
{
    const unsigned char *d = cairo_image_surface_get_data(img);
    uint32_t v;
    memcpy(&v, d + (size_t)y * (size_t)cairo_image_surface_get_stride(img) + 4 * (size_t)x, 4);
    rgb[0] = (int)(v >> 16 & 255);
    rgb[1] = (int)(v >> 8 & 255);
    rgb[2] = (int)(v & 255);
}

static int dark(cairo_surface_t *img, int x, int y, int level)
{
    int c[3];
    pixel(img, x, y, c);
    /* Grey or black, not a dark colour (a colour bar's end). */
    return c[0] < level && c[1] < level && c[2] < level && abs(c[0] - c[1]) < 30 &&
           abs(c[1] - c[2]) < 30;
}

/* The plot frame: the columns and rows with dark runs over half the
 * picture's height or width (left, right, top, bottom). */
static void frame_of(cairo_surface_t *img, double fr[4])
{
    int w = cairo_image_surface_get_width(img), h = cairo_image_surface_get_height(img);
    int x, y, n;
    double sx = 0, sy = 0;
    int nx = 0, ny = 0;
    fr[0] = fr[2] = 1e9;
    fr[1] = fr[3] = -1;
    for (x = 0; x < w; x++) {
        for (n = 0, y = 0; y < h; y++)
            n += dark(img, x, y, 200);
        if (n > h / 2) {
            fr[0] = fmin(fr[0], x);
            fr[1] = fmax(fr[1], x);
            sx += x;
            nx++;
        }
    }
    for (y = 0; y < h; y++) {
        for (n = 0, x = 0; x < w; x++)
            n += dark(img, x, y, 200);
        if (n > w / 2) {
            fr[2] = fmin(fr[2], y);
            fr[3] = fmax(fr[3], y);
            sy += y;
            ny++;
        }
    }
    assert_true(nx >= 2 && ny >= 2);
    (void)sx;
    (void)sy;
}

/* A scale bar is as long in pixels as its labelled length times the
 * plot's pixels per unit, which the frame's width in pixels over the
 * axis range (0 to 100, not equal) gives. */
static void test_scalebar_pixels(void **state)
{
    plot_figure f;
    plot_panel *p;
    cairo_surface_t *img;
    double x[1] = {90}, y[1] = {70}, fr[4], want, best = 0;
    int row, col;
    (void)state;
    plot_figure_init(&f, "scale");
    p = plot_add_panel(&f, "a spot", "x (µm)", "y (µm)");
    assert_non_null(p);
    p->xmin = 0;
    p->xmax = 100;
    p->ymin = 0;
    p->ymax = 75;
    p->scalebar = 20;
    snprintf(p->scalebar_label, sizeof p->scalebar_label, "20 µm");
    assert_int_equal(plot_add_series(p, PLOT_POINTS, 0, x, y, 1), 0);
    img = render(&f, 500, 400);
    frame_of(img, fr);
    want = 20.0 * (fr[1] - fr[0]) / 100.0;
    /* The longest dark run in the frame's bottom 30 rows. */
    for (row = (int)fr[3] - 30; row < (int)fr[3] - 2; row++) {
        int run = 0;
        for (col = (int)fr[0] + 3; col < (int)fr[1] - 3; col++) {
            run = dark(img, col, row, 128) ? run + 1 : 0;
            best = fmax(best, run);
        }
    }
    print_message("# scale bar: %.0f px, 20 units x %.3f px per unit = %.1f px\n", best,
                  (fr[1] - fr[0]) / 100.0, want);
    assert_true(fabs(best - want) <= 1.5);
    cairo_surface_destroy(img);
    plot_figure_free(&f);
}

/* A circular pupil's map on an equal panel in a wide picture is as wide as
 * it is tall in pixels. */
static void test_map_circle(void **state)
{
    plot_figure f;
    plot_panel *p;
    cairo_surface_t *img;
    double fr[4];
    int k, x, y, x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1, g = 32;
    (void)state;
    plot_figure_init(&f, "map");
    p = plot_add_panel(&f, "pupil", "Px", "Py");
    assert_non_null(p);
    p->equal = 1;
    /* Limits past the raster, so the frame does not cut it. */
    p->xmin = p->ymin = -1.25;
    p->xmax = p->ymax = 1.25;
    p->map_x0 = p->map_y0 = -1;
    p->map_x1 = p->map_y1 = 1;
    p->mw = p->mh = g;
    p->map = malloc((size_t)(g * g) * sizeof *p->map);
    assert_non_null(p->map);
    for (k = 0; k < g * g; k++) {
        double px = -1 + (k % g + 0.5) * 2.0 / g, py = 1 - (k / g + 0.5) * 2.0 / g;
        p->map[k] = px * px + py * py <= 1.0 ? px * px + py * py : NAN;
    }
    p->map_lo = 0;
    p->map_hi = 1;
    img = render(&f, 900, 400);
    frame_of(img, fr);
    /* Coloured pixels (not white, grey or black) inside the frame. */
    for (y = (int)fr[2] + 2; y < (int)fr[3] - 1; y++)
        for (x = (int)fr[0] + 2; x < (int)fr[1] - 1; x++) {
            int c[3];
            pixel(img, x, y, c);
            if (abs(c[0] - c[1]) + abs(c[1] - c[2]) + abs(c[0] - c[2]) > 60) {
                x0 = x < x0 ? x : x0;
                x1 = x > x1 ? x : x1;
                y0 = y < y0 ? y : y0;
                y1 = y > y1 ? y : y1;
            }
        }
    print_message("# pupil map: %d x %d px in a 900 x 400 picture\n", x1 - x0 + 1, y1 - y0 + 1);
    assert_true(y1 - y0 > 100);
    assert_true(abs((x1 - x0) - (y1 - y0)) <= 2);
    cairo_surface_destroy(img);
    plot_figure_free(&f);
}

/* Sixty-four series colours, every two far apart (a fifth of the RGB
 * cube's edge) and none black (the axes' colour); nine series in cells
 * print nine different escapes. */
static void test_palette_distinct(void **state)
{
    double a[PLOT_NCOLOURS][3];
    plot_figure f;
    plot_panel *p;
    plot_grid g;
    FILE *t;
    char buf[65536], seen[16][24];
    int i, j, nseen = 0;
    size_t n;
    (void)state;
    for (i = 0; i < PLOT_NCOLOURS; i++) {
        plot_colour_rgb(i, a[i]);
        assert_true(a[i][0] + a[i][1] + a[i][2] > 0.2);
        for (j = 0; j < i; j++)
            assert_true(hypot(hypot(a[i][0] - a[j][0], a[i][1] - a[j][1]), a[i][2] - a[j][2]) >
                        0.2);
    }
    plot_figure_init(&f, NULL);
    p = plot_add_panel(&f, "", "x", "y");
    p->xmin = p->ymin = 0;
    p->xmax = p->ymax = 10;
    for (i = 0; i < 9; i++) {
        double x = 1 + i, y = 1 + i;
        plot_add_series(p, PLOT_POINTS, i, &x, &y, 1);
    }
    assert_int_equal(plot_grid_init(&g, 60, 24), 0);
    plot_draw_cells(&f, &g, 0, 0, 60, 24);
    t = tmpfile();
    assert_int_equal(plot_grid_print(&g, t, 1), 0);
    rewind(t);
    n = fread(buf, 1, sizeof buf - 1, t);
    buf[n] = '\0';
    fclose(t);
    for (i = 0; buf[i]; i++)
        if (buf[i] == '\033') {
            int len = (int)strcspn(buf + i, "m") + 1, k, have = 0;
            if (len > 23 || strncmp(buf + i, "\033[0m", 4) == 0)
                continue;
            for (k = 0; k < nseen; k++)
                have |= strncmp(seen[k], buf + i, (size_t)len) == 0 && seen[k][len] == '\0';
            if (!have && nseen < 16) {
                memcpy(seen[nseen], buf + i, (size_t)len);
                seen[nseen++][len] = '\0';
            }
        }
    assert_int_equal(nseen, 9);
    plot_grid_free(&g);
    plot_figure_free(&f);
}

/* A size too small for the panels is refused, naming a size that works. */
static void test_size_refused(void **state)
{
    plot_figure f;
    plot_panel *p;
    char err[256];
    double x[2] = {0, 1}, y[2] = {0, 1};
    int k, w, h, mw, mh;
    FILE *t;
    (void)state;
    plot_figure_init(&f, "six panels");
    f.ncol = 2;
    for (k = 0; k < 6; k++) {
        p = plot_add_panel(&f, "a fan", "Py", "ey (µm)");
        plot_add_series(p, PLOT_LINES, 0, x, y, 2);
    }
    plot_add_legend(&f, 0, "0.5876 µm");
    t = tmpfile();
    assert_int_equal(plot_write(&f, PLOT_PNG, 300, 200, t, err, sizeof err), -1);
    fclose(t);
    assert_non_null(strstr(err, "300x200"));
    assert_non_null(strstr(err, "--size "));
    assert_int_equal(sscanf(strstr(err, "--size ") + 7, "%dx%d", &w, &h), 2);
    plot_min_size(&f, 300, &mw, &mh);
    assert_int_equal(w, mw);
    assert_int_equal(h, mh);
    assert_true(h > 200);
    t = tmpfile();
    if (plot_write(&f, PLOT_PNG, w, h, t, err, sizeof err))
        fail_msg("the size named (%dx%d) is refused: %s", w, h, err);
    fclose(t);
    plot_figure_free(&f);
}

/* Text that does not fit ends in an ellipsis after a whole word. */
static void test_fit_text(void **state)
{
    char out[64];
    (void)state;
    plot_fit_text("field 1: RMS 7.558, GEO 8.883 µm", 20, out, sizeof out);
    assert_string_equal(out, "field 1: RMS 7.558\xe2\x80\xa6");
    plot_fit_text("short", 20, out, sizeof out);
    assert_string_equal(out, "short");
    plot_fit_text("Spot diagram: Off-axis", 10, out, sizeof out);
    assert_string_equal(out, "Spot diag\xe2\x80\xa6"); /* no word ends past the middle */
    plot_fit_text("abcdefghijklmnop", 6, out, sizeof out);
    assert_string_equal(out, "abcde\xe2\x80\xa6");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_braille_bits),
        cmocka_unit_test(test_points_to_cells),
        cmocka_unit_test(test_ticks),
        cmocka_unit_test(test_files),
        cmocka_unit_test(test_cells_print),
        cmocka_unit_test(test_title_cut),
        cmocka_unit_test(test_circle_line),
        cmocka_unit_test(test_scalebar_pixels),
        cmocka_unit_test(test_map_circle),
        cmocka_unit_test(test_palette_distinct),
        cmocka_unit_test(test_size_refused),
        cmocka_unit_test(test_fit_text),
        cmocka_unit_test(test_axis_labels_narrow),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
