/*
 * test_plot.c - the picture code of ui/plot.c and ui/figure_cairo.c: the
 * braille dot numbering of Unicode, dots landing in the cell and bit the
 * mapping says, ticks, and PNG, SVG and PDF files rendered at a fixed size
 * with their headers read back (the PNG's IHDR width and height).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_braille_bits),
        cmocka_unit_test(test_points_to_cells),
        cmocka_unit_test(test_ticks),
        cmocka_unit_test(test_files),
        cmocka_unit_test(test_cells_print),
        cmocka_unit_test(test_circle_line),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
