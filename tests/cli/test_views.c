/*
 * test_views.c - the Seidel diagram and the field curvature / distortion
 * figure of ui/views.c, and the bars and category axis they draw with
 * (ui/plot.c).  The figures are built from the engine on a concave mirror
 * R = -200 with its stop at the centre of curvature (EPD 10, field 5 deg,
 * 0.55 um), whose values are known in closed form (Welford):
 *   SI = -2 c^3 y^4, SII = SIII = SV = 0, SIV = H^2 (n' - n) c / (n n')
 *   with H = y tan(5 deg), no colour (a mirror);
 *   the focus of field theta lies R/2 from C along the chief ray, so
 *   100 (cos theta - 1) from the paraxial image plane, with no
 *   astigmatism and no distortion.
 * The bars must carry these numbers, not the engine's output pasted back.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "views.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const char MIRROR[] =
    "{\"format\": \"sagitta-design\", \"version\": 1, \"title\": \"mirror\",\n"
    " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
    " \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
    "   \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1}, {\"x\": 0, \"y\": 5, \"weight\": 1}]},\n"
    " \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
    " \"ray_aiming\": \"off\",\n"
    " \"surfaces\": [\n"
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": \"inf\", \"thickness\": 200, \"stop\": true},\n"
    "    {\"radius\": -200, \"thickness\": -100, \"material\": \"MIRROR\"},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}]}\n";

static sg_catalog *cat;
static sg_system *sys;

static int setup(void **state)
{
    sg_diag d;
    (void)state;
    sg_diag_clear(&d);
    cat = sg_catalog_new();
    sys = sg_system_new();
    if (!cat || !sys || sg_catalog_load_default(cat, &d) != SG_OK ||
        sg_design_parse(sys, MIRROR, strlen(MIRROR), "mirror.json", &d) != SG_OK) {
        fprintf(stderr, "# setup: %s\n", d.msg);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    sg_system_free(sys);
    sg_catalog_free(cat);
    return 0;
}

/* The closed-form sums of surface j (1..3) or the total (4), index k. */
static double want_sum(int j, int k)
{
    double c = -1.0 / 200.0, y = 5.0, H = y * tan(5.0 * M_PI / 180.0);
    if (j != 2 && j != 4)
        return 0.0;
    if (k == 0)
        return -2.0 * c * c * c * y * y * y * y;
    if (k == 3)
        return H * H * 2.0 * c; /* (n' - n) / (n n') = (-1 - 1) / -1 */
    return 0.0;
}

static void close_to(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: %.17g, expected %.17g (tolerance %g)", what, got, want, tol);
}

static void test_seidel_grouped(void **state)
{
    sg_seidel s;
    sg_diag d;
    plot_figure f;
    int j, k;
    (void)state;
    sg_diag_clear(&d);
    assert_int_equal(sg_seidel_compute(sys, cat, &s, &d), SG_OK);
    assert_int_equal(view_seidel_figure(sys, &s, 1, &f), 0);
    assert_int_equal(f.npanel, 1);
    assert_int_equal(f.nlegend, SG_SEIDEL_N);
    assert_string_equal(f.legend[0].label, "SI");
    assert_string_equal(f.legend[6].label, "CII");
    /* Surfaces 1..3 and the total. */
    assert_int_equal(f.panel[0].ncat, 4);
    assert_string_equal(f.panel[0].cat[1], "2");
    assert_string_equal(f.panel[0].cat[3], "TOT");
    for (k = 0; k < SG_SEIDEL_N; k++) {
        const plot_series *b = &f.panel[0].s[k];
        assert_int_equal(b->kind, PLOT_BARS);
        assert_int_equal((int)b->n, 4);
        /* One colour per sum. */
        if (k > 0)
            assert_int_not_equal(b->color, f.panel[0].s[k - 1].color);
        for (j = 1; j <= 4; j++) {
            char what[32];
            snprintf(what, sizeof what, "sum %d of %d", k, j);
            close_to(b->y[j - 1], want_sum(j, k), 1e-14, what);
            /* Inside its surface's slot, in the order SI .. CII. */
            assert_true(fabs(b->x[j - 1] - j) < 0.5);
            if (k > 0)
                assert_true(b->x[j - 1] > f.panel[0].s[k - 1].x[j - 1]);
        }
    }
    /* The limits hold every bar and zero. */
    assert_true(f.panel[0].ymin < want_sum(4, 0) && f.panel[0].ymax > want_sum(4, 3));
    plot_figure_free(&f);
    /* The terminal's form: one panel per sum, the same numbers. */
    assert_int_equal(view_seidel_figure(sys, &s, 0, &f), 0);
    assert_int_equal(f.npanel, SG_SEIDEL_N);
    for (k = 0; k < SG_SEIDEL_N; k++)
        for (j = 1; j <= 4; j++) {
            assert_true(f.panel[k].s[0].x[j - 1] == j);
            close_to(f.panel[k].s[0].y[j - 1], want_sum(j, k), 1e-14, "panel sum");
        }
    plot_figure_free(&f);
    sg_seidel_free(&s);
}

static void test_fieldcurve_figure(void **state)
{
    sg_fieldcurve_pt pt[6];
    sg_trace_opts o;
    sg_diag d;
    plot_figure f;
    int i;
    (void)state;
    sg_trace_opts_init(&o);
    sg_diag_clear(&d);
    assert_int_equal(sg_fieldcurve(sys, cat, &o, 6, 0.01, pt, &d), SG_OK);
    assert_int_equal(view_fieldcurve_figure(sys, pt, 6, 0.55, &f), 0);
    assert_int_equal(f.npanel, 2);
    assert_int_equal(f.nlegend, 3);
    assert_int_equal(f.panel[0].nseries, 2);
    assert_int_equal(f.panel[1].nseries, 1);
    assert_non_null(strstr(f.panel[0].ylabel, "deg"));
    assert_non_null(strstr(f.panel[0].xlabel, "mm"));
    assert_non_null(strstr(f.panel[1].xlabel, "%"));
    assert_int_not_equal(f.panel[0].s[0].color, f.panel[0].s[1].color);
    for (i = 0; i < 6; i++) {
        double th = i * M_PI / 180.0, want = 100.0 * (cos(th) - 1.0);
        /* Field up the side, as Zemax draws it: 0 to 5 degrees. */
        close_to(f.panel[0].s[0].y[i], (double)i, 1e-12, "field");
        close_to(f.panel[0].s[0].x[i], want, 1e-6, "tangential focus");
        close_to(f.panel[0].s[1].x[i], want, 1e-6, "sagittal focus");
        close_to(f.panel[1].s[0].x[i], 0.0, 1e-10, "distortion");
        close_to(f.panel[1].s[0].y[i], (double)i, 1e-12, "distortion's field");
    }
    plot_figure_free(&f);
    /* Which curve is which: made-up foci that differ. */
    for (i = 0; i < 6; i++) {
        pt[i].tan_focus = 0.25 * i;
        pt[i].sag_focus = -0.5 * i;
        pt[i].distortion = 2.0 * i;
    }
    assert_int_equal(view_fieldcurve_figure(sys, pt, 6, 0.55, &f), 0);
    for (i = 0; i < 6; i++) {
        assert_true(f.panel[0].s[0].x[i] == 0.25 * i);
        assert_true(f.panel[0].s[1].x[i] == -0.5 * i);
        assert_true(f.panel[1].s[0].x[i] == 2.0 * i);
    }
    assert_string_equal(f.legend[0].label, "tangential");
    assert_int_equal(f.legend[0].color, f.panel[0].s[0].color);
    assert_int_equal(f.legend[1].color, f.panel[0].s[1].color);
    plot_figure_free(&f);
    /* A failed field breaks the curves. */
    pt[3].status = SG_EMISS;
    assert_int_equal(view_fieldcurve_figure(sys, pt, 6, 0.55, &f), 0);
    assert_true(isnan(f.panel[0].s[0].x[3]) && isnan(f.panel[1].s[0].x[3]));
    plot_figure_free(&f);
}

/* A bar from 0 to 1 over x in [0.5, 1.5] on limits [0, 2] x [-1, 1]: every
 * dot of the middle half of the columns in the upper half of the rows, and
 * none in the outer quarters; a bar to -1 fills the lower half. */
static void test_bars_in_cells(void **state)
{
    plot_figure f;
    plot_panel *p;
    plot_grid g;
    double x[1] = {1.0}, y[1] = {1.0};
    const char *labels[2] = {"1", "TOT"};
    int r, c, x0 = -1, y0 = -1, w = 0, h = 0, full, empty, found = 0;
    (void)state;
    plot_figure_init(&f, NULL);
    p = plot_add_panel(&f, "", "", "");
    assert_non_null(p);
    assert_int_equal(plot_add_bars(p, 3, x, y, 1, 1.0), 0);
    assert_int_equal(p->s[0].kind, PLOT_BARS);
    assert_int_equal(plot_panel_categories(p, 2, labels), 0);
    p->xmin = 0;
    p->xmax = 2;
    p->ymin = -1;
    p->ymax = 1;
    assert_int_equal(plot_grid_init(&g, 40, 20), 0);
    plot_draw_cells(&f, &g, 0, 0, 40, 20);
    /* The plotting area: right of the y axis, above the x axis. */
    for (r = 0; r < g.h && y0 < 0; r++)
        for (c = 0; c < g.w; c++)
            if (strcmp(g.c[r * g.w + c].ch, "\xe2\x94\x94") == 0) { /* └ */
                x0 = c + 1;
                y0 = r;
                break;
            }
    assert_true(x0 > 0);
    for (c = x0; c < g.w && (strcmp(g.c[y0 * g.w + c].ch, "\xe2\x94\x80") == 0 ||
                             strcmp(g.c[y0 * g.w + c].ch, "\xe2\x94\xac") == 0);
         c++)
        w++;
    for (r = y0 - 1; r >= 0 && (strcmp(g.c[r * g.w + x0 - 1].ch, "\xe2\x94\x82") == 0 ||
                                strcmp(g.c[r * g.w + x0 - 1].ch, "\xe2\x94\xa4") == 0);
         r--)
        h++;
    assert_true(w >= 20 && h >= 8);
    full = empty = 0;
    for (r = y0 - h; r < y0; r++)
        for (c = x0; c < x0 + w; c++) {
            const plot_cell *cell = &g.c[r * g.w + c];
            int mid = c - x0 >= w / 4 + 1 && c - x0 < 3 * w / 4 - 1;
            int upper = r - (y0 - h) < h / 2 - 1;
            int outer = c - x0 < w / 4 - 1 || c - x0 > 3 * w / 4;
            if (mid && upper) {
                full += strcmp(cell->ch, "\xe2\xa3\xbf") == 0 && cell->color == 3; /* ⣿ */
            } else if (outer) {
                empty += strcmp(cell->ch, " ") == 0;
                if (strcmp(cell->ch, " ") != 0)
                    fail_msg("a dot outside the bar at column %d, row %d", c - x0, r);
            }
        }
    assert_true(full >= (w / 2 - 2) * (h / 2 - 1));
    assert_true(empty > 0);
    /* The category axis names its ticks. */
    for (c = 0; c + 3 <= g.w; c++)
        if (strcmp(g.c[(y0 + 1) * g.w + c].ch, "T") == 0 &&
            strcmp(g.c[(y0 + 1) * g.w + c + 1].ch, "O") == 0)
            found = 1;
    assert_true(found);
    plot_grid_free(&g);
    /* The bar downwards: now the lower half is full and the upper empty. */
    p->s[0].y[0] = -1.0;
    assert_int_equal(plot_grid_init(&g, 40, 20), 0);
    plot_draw_cells(&f, &g, 0, 0, 40, 20);
    c = x0 + w / 2;
    assert_string_equal(g.c[(y0 - 1) * g.w + c].ch, "\xe2\xa3\xbf");
    assert_string_equal(g.c[(y0 - h) * g.w + c].ch, " ");
    plot_grid_free(&g);
    plot_figure_free(&f);
}

/* Limits from bars stand on zero and hold each bar's width. */
static void test_bar_limits(void **state)
{
    plot_figure f;
    plot_panel *p;
    double x[2] = {1.0, 2.0}, y[2] = {3.0, 5.0};
    (void)state;
    plot_figure_init(&f, NULL);
    p = plot_add_panel(&f, "", "", "");
    assert_int_equal(plot_add_bars(p, 0, x, y, 2, 0.5), 0);
    plot_panel_limits(p, 0.0);
    assert_true(p->ymin < 0.0 && p->ymax > 5.0);
    assert_true(p->xmin < 0.75 && p->xmax > 2.25);
    plot_figure_free(&f);
}

/* Spot panels share one scale: the same limits in every field, holding
 * every point of every field; each has a scale bar of 1, 2 or 5 times a
 * power of ten, a tenth to four tenths of the span, labelled with its
 * length in the axes' unit.  A fan figure puts a field's tangential and
 * sagittal fans side by side: two columns, panel 2k tangential and 2k + 1
 * sagittal of field k + 1. */
static void test_spot_fan_layout(void **state)
{
    sg_spot sp;
    sg_spot_opts so;
    sg_fan fan;
    sg_fan_opts fo;
    plot_figure f;
    int k, j;
    sg_system *off = sg_system_new();
    double w0 = 0.0, w1 = 0.0;
    (void)state;
    /* The stop 150 before the mirror, not at its centre: field 2 gains
     * coma, so its spot is larger than field 1's. */
    assert_non_null(off);
    assert_int_equal(sg_system_assign(off, sys), SG_OK);
    off->surf[1].thickness = 150;
    sg_spot_opts_init(&so);
    so.max_points = 100000;
    assert_int_equal(sg_spot_compute(off, cat, &so, &sp, NULL), SG_OK);
    assert_true(sp.field[1].geo > 1.5 * sp.field[0].geo);
    assert_int_equal(view_spot_figure(off, &sp, &f), 0);
    assert_int_equal(f.npanel, 2);
    for (k = 0; k < f.npanel; k++) {
        const plot_panel *p = &f.panel[k];
        double span = p->xmax - p->xmin, m, mant;
        char want[32];
        assert_true(p->xmin == f.panel[0].xmin && p->xmax == f.panel[0].xmax &&
                    p->ymin == f.panel[0].ymin && p->ymax == f.panel[0].ymax);
        for (j = 0; j < p->nseries; j++) {
            size_t i;
            for (i = 0; i < p->s[j].n; i++) {
                assert_true(p->s[j].x[i] >= p->xmin && p->s[j].x[i] <= p->xmax &&
                            p->s[j].y[i] >= p->ymin && p->s[j].y[i] <= p->ymax);
                double r = fmax(fabs(p->s[j].x[i]), fabs(p->s[j].y[i]));
                if (p->s[j].kind != PLOT_POINTS)
                    continue; /* the Airy circle, the same in both */
                if (k == 0)
                    w0 = fmax(w0, r);
                else
                    w1 = fmax(w1, r);
            }
        }
        m = pow(10.0, floor(log10(p->scalebar)));
        mant = p->scalebar / m;
        assert_true(fabs(mant - 1) < 1e-9 || fabs(mant - 2) < 1e-9 || fabs(mant - 5) < 1e-9);
        assert_true(p->scalebar >= 0.1 * span && p->scalebar <= 0.4 * span);
        snprintf(want, sizeof want, "%g %s", p->scalebar, strchr(p->xlabel, '(') + 1);
        want[strlen(want) - 1] = '\0'; /* the label's closing parenthesis */
        assert_string_equal(p->scalebar_label, want);
    }
    print_message("# spot: field 1 reaches %g, field 2 %g\n", w0, w1);
    assert_true(w1 > w0); /* the fields differ, their scale does not */
    plot_figure_free(&f);
    sg_spot_free(&sp);
    sg_system_free(off);
    sg_fan_opts_init(&fo);
    assert_int_equal(sg_fan_compute(sys, cat, &fo, &fan, NULL), SG_OK);
    assert_int_equal(view_fan_figure(sys, &fan, &f), 0);
    assert_int_equal(f.ncol, 2);
    assert_int_equal(f.npanel, 4);
    for (k = 0; k < 2; k++) {
        char field[16];
        snprintf(field, sizeof field, "field %d ", k + 1);
        assert_non_null(strstr(f.panel[2 * k].title, "tangential"));
        assert_non_null(strstr(f.panel[2 * k + 1].title, "sagittal"));
        assert_true(strncmp(f.panel[2 * k].title, field, strlen(field)) == 0);
        assert_true(strncmp(f.panel[2 * k + 1].title, field, strlen(field)) == 0);
    }
    plot_figure_free(&f);
    sg_fan_free(&fan);
}

static const char LENS[] =
    "{\"format\": \"sagitta-design\", \"version\": 1, \"title\": \"lens\",\n"
    " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
    " \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
    "   \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1}, {\"x\": 0, \"y\": 10, \"weight\": 1}]},\n"
    " \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
    " \"ray_aiming\": \"off\",\n"
    " \"surfaces\": [\n"
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": \"inf\", \"thickness\": 10, \"stop\": true},\n"
    "    {\"radius\": 50, \"thickness\": 5, \"material\": \"N-BK7\"},\n"
    "    {\"radius\": -50, \"thickness\": 45},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}]}\n";

/* A lens's edge as Zemax draws it on the axis: the smaller surface goes
 * on flat (at its rim's z) to the larger one's height, and a cylinder
 * parallel to the axis (one height) joins the larger rim.  The stop 10
 * before the lens and a 10 degree field make the rear surface's automatic
 * semi-diameter larger than the front's. */
static void test_layout_edges(void **state)
{
    sg_system *lens = sg_system_new();
    sg_layout l;
    sg_layout_opts lo;
    plot_figure f;
    sg_diag d;
    int j, found = 0;
    (void)state;
    sg_diag_clear(&d);
    assert_non_null(lens);
    assert_int_equal(sg_design_parse(lens, LENS, strlen(LENS), "lens.json", &d), SG_OK);
    sg_layout_opts_init(&lo);
    assert_int_equal(sg_layout_compute(lens, cat, &lo, &l, &d), SG_OK);
    assert_true(l.surf[2].sd > l.surf[1].sd + 0.1); /* surface 3 (rear) larger than 2 */
    assert_int_equal(view_layout_figure(lens, &l, &f), 0);
    for (j = 0; j < f.panel[0].nseries; j++) {
        const plot_series *e = &f.panel[0].s[j];
        int side;
        if (e->n != 7)
            continue;
        found++;
        for (side = 0; side < 2; side++) {
            const double *y = e->y;
            /* From the front rim, out flat at its z to the rear's height,
             * then along the axis at that height to the rear rim. */
            assert_true(e->x[4 * side] == e->x[4 * side + 1]);
            assert_true(fabs(y[4 * side + 1]) > fabs(y[4 * side]));
            assert_true(y[4 * side + 1] == y[4 * side + 2]);
        }
        assert_true(isnan(e->y[3]));
    }
    assert_int_equal(found, 1);
    plot_figure_free(&f);
    sg_layout_free(&l);
    sg_system_free(lens);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_seidel_grouped),
        cmocka_unit_test(test_fieldcurve_figure),
        cmocka_unit_test(test_bars_in_cells),
        cmocka_unit_test(test_bar_limits),
        cmocka_unit_test(test_spot_fan_layout),
        cmocka_unit_test(test_layout_edges),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
