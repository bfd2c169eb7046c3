/*
 * views.c - analyses as figures: spots per field with the Airy circle,
 * tangential and sagittal fans per field, and the layout.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "safetext.h"
#include "views.h"

#define PI_ 3.14159265358979323846

const char *view_length_unit(const sg_system *sys, double extent, double *scale)
{
    double um = 1e3; /* micrometres per lens unit */
    /* Afocal image space: the spot and fans are angles (sg_system.afocal). */
    if (sys->afocal) {
        (void)extent;
        *scale = 1e3;
        return "mrad";
    }
    if (strcmp(sys->units, "cm") == 0)
        um = 1e4;
    else if (strcmp(sys->units, "in") == 0)
        um = 25.4e3;
    else if (strcmp(sys->units, "m") == 0)
        um = 1e6;
    if (extent * um < 2000.0) {
        *scale = um;
        return "µm";
    }
    *scale = 1.0;
    return sys->units[0] ? sys->units : "mm";
}

void view_wave_label(double um, char *buf, size_t n)
{
    snprintf(buf, n, "%.4g µm", um);
}

void view_field_label(const sg_system *sys, int k, char *buf, size_t n)
{
    snprintf(buf, n, "field %d (%.4g, %.4g %s)", k + 1, sys->field[k].x, sys->field[k].y,
             sys->field_type == SG_FIELD_ANGLE ? "deg" : sys->units);
}

static void legend_waves(plot_figure *f, int nwave, const int *index, const double *um)
{
    int w;
    for (w = 0; w < nwave; w++) {
        char lab[48];
        view_wave_label(um[w], lab, sizeof lab);
        plot_add_legend(f, index[w], lab);
    }
}

/* A scale bar's length: 1, 2 or 5 times a power of ten, about a quarter
 * of span and never more than 0.4 of it. */
static double scalebar_length(double span)
{
    double raw = 0.25 * span, mag = pow(10.0, floor(log10(raw))), m = raw / mag;
    double len = (m < 1.5 ? 1.0 : m < 3.5 ? 2.0 : m < 7.5 ? 5.0 : 10.0) * mag;
    while (len > 0.4 * span)
        len = len == 2.0 * mag || len == 10.0 * mag ? len / 2.0 : len * 0.4;
    return len;
}

int view_spot_figure(const sg_system *sys, const sg_spot *s, plot_figure *f)
{
    double ext = s->airy_radius, scale, half = s->airy_radius;
    const char *u;
    char title[256], lab[160], xl[32], yl[32];
    int fi, w, k;
    for (fi = 0; fi < s->nfield; fi++)
        ext = fmax(ext, s->field[fi].geo);
    u = view_length_unit(sys, ext, &scale);
    /* One scale for every field, as Zemax draws them: the farthest point
     * from the reference over all fields and wavelengths. */
    for (k = 0; k < s->nfield * s->nwave; k++) {
        const sg_spot_cell *c = &s->cell[k];
        size_t i;
        for (i = 0; i < c->npts; i++)
            if (isfinite(c->pts[i][0]) && isfinite(c->pts[i][1]))
                half = fmax(half, fmax(fabs(c->pts[i][0]), fabs(c->pts[i][1])));
    }
    half *= scale;
    if (!(half > 0.0))
        half = 1.0;
    snprintf(title, sizeof title, "Spot diagram: %s", safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    snprintf(xl, sizeof xl, "x (%s)", u);
    snprintf(yl, sizeof yl, "y (%s)", u);
    for (fi = 0; fi < s->nfield; fi++) {
        const sg_spot_field *fd = &s->field[fi];
        char fl[64], pt[96];
        plot_panel *p;
        view_field_label(sys, s->field_index[fi], fl, sizeof fl);
        /* The radii first, so a narrow panel still shows them. */
        if (fd->status == SG_OK)
            snprintf(pt, sizeof pt, "field %d: RMS %.4g, GEO %.4g %s  %s",
                     s->field_index[fi] + 1, fd->rms * scale, fd->geo * scale, u,
                     strchr(fl, '(') ? strchr(fl, '(') : "");
        else
            snprintf(pt, sizeof pt, "%s: chief ray %s", fl, sg_strerror(fd->status));
        p = plot_add_panel(f, pt, xl, yl);
        if (!p)
            return -1;
        p->equal = 1;
        for (w = 0; w < s->nwave; w++) {
            const sg_spot_cell *c = &s->cell[fi * s->nwave + w];
            double *x = malloc((c->npts + 1) * sizeof *x), *y = malloc((c->npts + 1) * sizeof *y);
            size_t i;
            int rc;
            if (!x || !y) {
                free(x);
                free(y);
                return -1;
            }
            for (i = 0; i < c->npts; i++) {
                x[i] = c->pts[i][0] * scale;
                y[i] = c->pts[i][1] * scale;
            }
            rc = plot_add_series(p, PLOT_POINTS, s->wave_index[w], x, y, c->npts);
            free(x);
            free(y);
            if (rc)
                return -1;
        }
        if (s->airy_radius > 0.0 && fd->status == SG_OK) {
            /* The Airy circle about the reference point, as Zemax draws it. */
            double x[73], y[73];
            for (k = 0; k < 73; k++) {
                x[k] = s->airy_radius * scale * cos(2 * PI_ * k / 72);
                y[k] = s->airy_radius * scale * sin(2 * PI_ * k / 72);
            }
            if (plot_add_series(p, PLOT_LINES, PLOT_FG, x, y, 73))
                return -1;
        }
        p->xmin = p->ymin = -1.1 * half;
        p->xmax = p->ymax = 1.1 * half;
        p->scalebar = scalebar_length(2.2 * half);
        snprintf(p->scalebar_label, sizeof p->scalebar_label, "%g %s", p->scalebar, u);
    }
    legend_waves(f, s->nwave, s->wave_index, s->wave_um);
    return 0;
}

int view_fan_figure(const sg_system *sys, const sg_fan *fan, plot_figure *f)
{
    double ext = 0.0, scale;
    const char *u;
    char title[256], lab[160], yt[32], ys[32];
    int fi, w, j, side, n = fan->npts;
    double *x, *y;
    /* The longest curve (a refined fan has more samples than npts). */
    for (j = 0; j < fan->nfield * fan->nwave; j++)
        n = fan->tan[j].n > n ? fan->tan[j].n : fan->sag[j].n > n ? fan->sag[j].n : n;
    x = malloc((size_t)n * sizeof *x);
    y = malloc((size_t)n * sizeof *y);
    if (!x || !y) {
        free(x);
        free(y);
        return -1;
    }
    for (j = 0; j < fan->nfield * fan->nwave; j++)
        for (side = 0; side < 2; side++) {
            const sg_fan_curve *c = side ? &fan->sag[j] : &fan->tan[j];
            int i;
            for (i = 0; i < c->n; i++)
                if (c->status[i] == SG_OK)
                    ext = fmax(ext, fabs(c->e[i]));
        }
    u = view_length_unit(sys, ext, &scale);
    if (fan->opd) {
        /* OPD in waves of each curve's wavelength, as Zemax plots it. */
        u = "waves";
        scale = 1.0;
    }
    snprintf(title, sizeof title, "%s: %s", fan->opd ? "OPD fans" : "Transverse ray fans",
             safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    /* One row per field: its tangential and sagittal fans side by side. */
    f->ncol = 2;
    snprintf(yt, sizeof yt, "%s (%s)", fan->opd ? "W" : "ey", u);
    snprintf(ys, sizeof ys, "%s (%s)", fan->opd ? "W" : "ex", u);
    for (fi = 0; fi < fan->nfield; fi++)
        for (side = 0; side < 2; side++) {
            char fl[64], pt[96];
            plot_panel *p;
            view_field_label(sys, fan->field_index[fi], fl, sizeof fl);
            snprintf(pt, sizeof pt, "%s %s", fl, side ? "sagittal" : "tangential");
            p = plot_add_panel(f, pt, side ? "Px" : "Py", side ? ys : yt);
            if (!p)
                goto oom;
            for (w = 0; w < fan->nwave; w++) {
                const sg_fan_curve *c = side ? &fan->sag[fi * fan->nwave + w]
                                             : &fan->tan[fi * fan->nwave + w];
                for (j = 0; j < c->n; j++) {
                    x[j] = c->p[j];
                    y[j] = c->status[j] == SG_OK ? c->e[j] * scale : NAN;
                }
                if (plot_add_series(p, PLOT_LINES, fan->wave_index[w], x, y, (size_t)c->n))
                    goto oom;
            }
            p->xmin = -1.0;
            p->xmax = 1.0;
            /* Both fans of a field on one scale, symmetric about zero. */
            p->ymin = -(ext > 0 ? ext * scale * 1.1 : 1.0);
            p->ymax = -p->ymin;
        }
    legend_waves(f, fan->nwave, fan->wave_index, fan->wave_um);
    free(x);
    free(y);
    return 0;
oom:
    free(x);
    free(y);
    return -1;
}

int view_layout_figure(const sg_system *sys, const sg_layout *l, plot_figure *f)
{
    char title[256], lab[160], xl[32], yl[32];
    const char *u = sys->units[0] ? sys->units : "mm";
    plot_panel *p;
    int i, fi, coaxial = 1;
    snprintf(title, sizeof title, "Layout: %s", safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    snprintf(xl, sizeof xl, "z (%s)", u);
    snprintf(yl, sizeof yl, "y (%s)", u);
    p = plot_add_panel(f, "", xl, yl);
    if (!p)
        return -1;
    p->equal = 1;
    for (i = 1; i < sys->nsurf && coaxial; i++)
        coaxial = !sg_surface_moves_frame(&sys->surf[i]);
    for (i = 0; i < l->nsurf - 1; i++) {
        const sg_layout_surface *s = &l->surf[i];
        if (plot_add_series(p, PLOT_LINES, PLOT_FG, s->z, s->y, (size_t)s->npts))
            return -1;
        /* A lens's edges: its two surfaces' rims joined.  On the axis, as
         * Zemax draws them, the smaller surface goes on flat to the larger
         * one's height and a cylinder joins them; in a tilted system the
         * rims are joined straight. */
        if (s->glass_after && i + 1 < l->nsurf - 1 && s->npts && l->surf[i + 1].npts) {
            const sg_layout_surface *t = &l->surf[i + 1];
            double z[5] = {s->z[0], t->z[0], NAN, s->z[s->npts - 1], t->z[t->npts - 1]};
            double y[5] = {s->y[0], t->y[0], NAN, s->y[s->npts - 1], t->y[t->npts - 1]};
            if (coaxial) {
                double ez[8], ey[8];
                int side;
                for (side = 0; side < 2; side++) {
                    /* Rim points: s's (zs, ys) and t's (zt, yt). */
                    double zs = z[3 * side], ys = y[3 * side], zt = z[3 * side + 1],
                           yt = y[3 * side + 1], *oz = ez + 4 * side, *oy = ey + 4 * side;
                    oz[0] = zs;
                    oy[0] = ys;
                    if (fabs(ys) < fabs(yt)) {
                        oz[1] = zs;
                        oy[1] = yt;
                    } else {
                        oz[1] = zt;
                        oy[1] = ys;
                    }
                    oz[2] = zt;
                    oy[2] = yt;
                    oz[3] = oy[3] = NAN; /* a break between the two edges */
                }
                if (plot_add_series(p, PLOT_LINES, PLOT_FG, ez, ey, 7))
                    return -1;
                continue;
            }
            if (plot_add_series(p, PLOT_LINES, PLOT_FG, z, y, 5))
                return -1;
        }
    }
    for (i = 0; i < l->nray; i++)
        if (plot_add_series(p, PLOT_LINES, l->ray[i].field, l->ray[i].z, l->ray[i].y,
                            (size_t)l->ray[i].npts))
            return -1;
    for (fi = 0; fi < l->nfield; fi++) {
        char fl[64];
        view_field_label(sys, l->field_index[fi], fl, sizeof fl);
        plot_add_legend(f, fi, fl);
    }
    plot_panel_limits(p, 0.0);
    return 0;
}

#define VIEW_MAP_MAX 1024

int view_wavefront_figure(const sg_system *sys, const sg_wavefront *w, const sg_opd_ref *ref,
                          int field, double um, plot_figure *f)
{
    char title[256], lab[160], fl[64], pt[256], wl[32];
    double lo = INFINITY, hi = -INFINITY;
    plot_panel *p;
    int g = w->grid, i, j, fac, r;
    snprintf(title, sizeof title, "Wavefront map: %s", safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    if (field >= 0)
        view_field_label(sys, field, fl, sizeof fl);
    else
        snprintf(fl, sizeof fl, "Hx %.4g, Hy %.4g", ref->hx, ref->hy);
    view_wave_label(um, wl, sizeof wl);
    snprintf(pt, sizeof pt, "%s %s: RMS %.4g, P-V %.4g waves", fl, wl, w->rms_centroid,
             w->pv_centroid);
    p = plot_add_panel(f, pt, "Px", "Py");
    if (!p)
        return -1;
    /* A circular pupil is a circle: equal units, the raster on -1..1. */
    p->equal = 1;
    p->map_x0 = p->map_y0 = -1.0;
    p->map_x1 = p->map_y1 = 1.0;
    snprintf(p->map_label, sizeof p->map_label, "OPD");
    snprintf(p->map_unit, sizeof p->map_unit, "waves");
    /* A picture shows at most VIEW_MAP_MAX cells across: a finer grid is
     * averaged in blocks (its valid cells), so the raster stays small
     * (8 MB) where the grid goes to 4096 (134 MB). */
    fac = (g + VIEW_MAP_MAX - 1) / VIEW_MAP_MAX;
    r = (g + fac - 1) / fac;
    p->map = malloc((size_t)r * (size_t)r * sizeof *p->map);
    if (!p->map)
        return -1;
    p->mw = p->mh = r;
    /* Row 0 of the picture is Py = +1, the top. */
    for (j = 0; j < r; j++)
        for (i = 0; i < r; i++) {
            double sum = 0.0;
            int cnt = 0, a, b;
            for (b = j * fac; b < (j + 1) * fac && b < g; b++)
                for (a = i * fac; a < (i + 1) * fac && a < g; a++) {
                    size_t k = (size_t)b * (size_t)g + (size_t)a;
                    if (w->valid[k]) {
                        sum += w->map[k];
                        cnt++;
                        lo = fmin(lo, w->map[k]);
                        hi = fmax(hi, w->map[k]);
                    }
                }
            p->map[(size_t)(r - 1 - j) * (size_t)r + (size_t)i] =
                cnt ? sum / cnt : NAN;
        }
    if (!(lo <= hi))
        lo = hi = 0.0;
    /* A flat wavefront (a perfect system) still gets a scale. */
    if (!(hi - lo > 1e-12)) {
        lo -= 1e-6;
        hi += 1e-6;
    }
    p->map_lo = lo;
    p->map_hi = hi;
    p->xmin = p->ymin = -1.0;
    p->xmax = p->ymax = 1.0;
    return 0;
}

const char *const view_seidel_names[SG_SEIDEL_N] = {"SI", "SII", "SIII", "SIV",
                                                   "SV", "CI", "CII"};

/* One colour per sum. */
static int seidel_colour(int k)
{
    return k;
}

int view_seidel_figure(const sg_system *sys, const sg_seidel *s, int grouped, plot_figure *f)
{
    static const char *const what[SG_SEIDEL_N] = {
        "SI spherical", "SII coma", "SIII astigmatism", "SIV Petzval",
        "SV distortion", "CI axial colour", "CII lateral colour"};
    char title[256], lab[160], yl[32], (*cats)[12];
    const char **cp;
    const char *u = sys->units[0] ? sys->units : "mm";
    int ng = s->nsurf, j, k, rc = -1; /* surfaces 1 .. nsurf-1 and the total */
    double *x = malloc((size_t)ng * sizeof *x), *y = malloc((size_t)ng * sizeof *y);
    cats = malloc((size_t)ng * sizeof *cats);
    cp = malloc((size_t)ng * sizeof *cp);
    snprintf(title, sizeof title, "Seidel diagram: %s", safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    if (!x || !y || !cats || !cp || ng < 2)
        goto out;
    for (j = 1; j <= ng; j++) {
        if (j < ng)
            snprintf(cats[j - 1], sizeof cats[0], "%d", j);
        else
            snprintf(cats[j - 1], sizeof cats[0], "TOT");
        cp[j - 1] = cats[j - 1];
    }
    snprintf(yl, sizeof yl, "sum (%s)", u);
    for (k = 0; k < SG_SEIDEL_N; k++)
        plot_add_legend(f, seidel_colour(k), view_seidel_names[k]);
    if (grouped) {
        /* Seven bars in 0.8 of each surface's unit of x, as Zemax groups them. */
        plot_panel *p = plot_add_panel(f, "", "surface (TOT: the sum)", yl);
        double zx[2] = {0.5, ng + 0.5}, zy[2] = {0.0, 0.0};
        if (!p || plot_panel_categories(p, ng, cp))
            goto out;
        for (k = 0; k < SG_SEIDEL_N; k++) {
            for (j = 1; j <= ng; j++) {
                const double *row = j < ng ? s->surf + (size_t)j * SG_SEIDEL_N : s->total;
                x[j - 1] = j - 0.4 + (k + 0.5) * 0.8 / SG_SEIDEL_N;
                y[j - 1] = row[k];
            }
            if (plot_add_bars(p, seidel_colour(k), x, y, (size_t)ng, 0.8 / SG_SEIDEL_N))
                goto out;
        }
        if (plot_add_series(p, PLOT_LINES, PLOT_FG, zx, zy, 2))
            goto out;
        plot_panel_limits(p, 0.0);
        p->xmin = 0.5;
        p->xmax = ng + 0.5;
    } else {
        for (k = 0; k < SG_SEIDEL_N; k++) {
            plot_panel *p = plot_add_panel(f, what[k], "surface", yl);
            if (!p || plot_panel_categories(p, ng, cp))
                goto out;
            for (j = 1; j <= ng; j++) {
                const double *row = j < ng ? s->surf + (size_t)j * SG_SEIDEL_N : s->total;
                x[j - 1] = j;
                y[j - 1] = row[k];
            }
            if (plot_add_bars(p, seidel_colour(k), x, y, (size_t)ng, 0.6))
                goto out;
            plot_panel_limits(p, 0.0);
            p->xmin = 0.5;
            p->xmax = ng + 0.5;
        }
    }
    rc = 0;
out:
    free(x);
    free(y);
    free(cats);
    free(cp);
    return rc;
}

int view_fieldcurve_figure(const sg_system *sys, const sg_fieldcurve_pt *pt, int n, double um,
                           plot_figure *f)
{
    char title[256], lab[160], wl[32], fl[32], xl[32];
    const char *u = sys->units[0] ? sys->units : "mm";
    double *yv = malloc((size_t)(n > 0 ? n : 1) * sizeof *yv),
           *xv = malloc((size_t)(n > 0 ? n : 1) * sizeof *xv);
    plot_panel *p;
    int i, side, rc = -1;
    view_wave_label(um, wl, sizeof wl);
    snprintf(title, sizeof title, "Field curvature and distortion: %s, %s",
             safe_text(sys->title, lab, sizeof lab), wl);
    plot_figure_init(f, title);
    if (!yv || !xv)
        goto out;
    if (sys->field_type == SG_FIELD_ANGLE)
        snprintf(fl, sizeof fl, "field (deg)");
    else
        snprintf(fl, sizeof fl, "field (%s)", u);
    for (i = 0; i < n; i++)
        yv[i] = pt[i].field;
    snprintf(xl, sizeof xl, "focus (%s)", u);
    p = plot_add_panel(f, "Field curvature", xl, fl);
    if (!p)
        goto out;
    for (side = 0; side < 2; side++) {
        for (i = 0; i < n; i++)
            xv[i] = pt[i].status != SG_OK ? NAN : side ? pt[i].sag_focus : pt[i].tan_focus;
        if (plot_add_series(p, PLOT_LINES, side, xv, yv, (size_t)n))
            goto out;
    }
    plot_panel_limits(p, 0.0);
    p = plot_add_panel(f, "Distortion", "distortion (%)", fl);
    if (!p)
        goto out;
    for (i = 0; i < n; i++)
        xv[i] = pt[i].status != SG_OK ? NAN : pt[i].distortion;
    if (plot_add_series(p, PLOT_LINES, 2, xv, yv, (size_t)n))
        goto out;
    plot_panel_limits(p, 0.0);
    plot_add_legend(f, 0, "tangential");
    plot_add_legend(f, 1, "sagittal");
    plot_add_legend(f, 2, "distortion");
    rc = 0;
out:
    free(xv);
    free(yv);
    return rc;
}

int view_mtf_figure(const sg_system *sys, const sg_mtf *m, plot_figure *f)
{
    char title[200], lab[160], leg[48];
    plot_panel *p;
    int k;
    snprintf(title, sizeof title, "%s MTF: %s", m->method == SG_MTF_GEOMETRIC ? "Geometric"
             : m->method == SG_MTF_HUYGENS ? "Huygens"
                                            : "FFT",
             safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    p = plot_add_panel(f, NULL, "spatial frequency (cycles/mm)", "modulus of the OTF");
    if (!p)
        return -1;
    if (plot_add_series(p, PLOT_LINES, PLOT_FG, m->freq, m->dl, (size_t)m->npts))
        return -1;
    plot_add_legend(f, PLOT_FG, "diffraction limit");
    for (k = 0; k < m->nfield; k++) {
        if (plot_add_series(p, PLOT_LINES, 2 * k, m->freq, m->tan + (size_t)k * m->npts,
                            (size_t)m->npts) ||
            plot_add_series(p, PLOT_LINES, 2 * k + 1, m->freq, m->sag + (size_t)k * m->npts,
                            (size_t)m->npts))
            return -1;
        snprintf(leg, sizeof leg, "field %d T", m->field[k] + 1);
        plot_add_legend(f, 2 * k, leg);
        snprintf(leg, sizeof leg, "field %d S", m->field[k] + 1);
        plot_add_legend(f, 2 * k + 1, leg);
    }
    plot_panel_limits(p, 0.0);
    return 0;
}

int view_psf_figure(const sg_system *sys, const sg_psf *ps, int n, plot_figure *f)
{
    char title[200], lab[160], pt[64];
    int k, rc = -1;
    snprintf(title, sizeof title, "%s PSF cross-sections: %s",
             n > 0 && ps[0].method == SG_PSF_HUYGENS ? "Huygens" : "FFT",
             safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    for (k = 0; k < n; k++) {
        const sg_psf *q = &ps[k];
        double lf = q->wave_um * q->fnum;
        int r = (int)ceil(16.0 * lf / fmin(q->spacing_x_um, q->spacing_y_um)), i, c = q->size / 2;
        double *x, *vx, *vy;
        plot_panel *p;
        if (r >= c)
            r = c - 1;
        x = malloc((size_t)(2 * r + 1) * sizeof *x);
        vx = malloc((size_t)(2 * r + 1) * sizeof *vx);
        vy = malloc((size_t)(2 * r + 1) * sizeof *vy);
        snprintf(pt, sizeof pt, "field %d: Strehl %.4f", q->field + 1, q->strehl);
        p = x && vx && vy ? plot_add_panel(f, pt, "offset (um)", "PSF") : NULL;
        if (p) {
            for (i = -r; i <= r; i++) {
                x[i + r] = i * q->spacing_x_um;
                vx[i + r] = q->psf[(size_t)c * q->size + (size_t)(c + i)];
                vy[i + r] = q->psf[(size_t)(c + i) * q->size + (size_t)c];
            }
            if (!plot_add_series(p, PLOT_LINES, 0, x, vx, (size_t)(2 * r + 1))) {
                for (i = -r; i <= r; i++)
                    x[i + r] = i * q->spacing_y_um;
                if (!plot_add_series(p, PLOT_LINES, 1, x, vy, (size_t)(2 * r + 1))) {
                    plot_panel_limits(p, 0.0);
                    p = (plot_panel *)1;
                }
            }
        }
        free(x);
        free(vx);
        free(vy);
        if (p != (plot_panel *)1)
            return rc;
    }
    plot_add_legend(f, 0, "along x");
    plot_add_legend(f, 1, "along y");
    return 0;
}

int view_ee_figure(const sg_system *sys, const sg_ee *e, plot_figure *f)
{
    char title[200], lab[160], pt[32];
    int k, sq = e->kind == SG_EE_ENSQUARED;
    snprintf(title, sizeof title, "%s energy: %s", sq ? "Ensquared" : "Encircled",
             safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    for (k = 0; k < e->nfield; k++) {
        size_t o = (size_t)k * e->npts;
        plot_panel *p;
        snprintf(pt, sizeof pt, "field %d", e->field[k] + 1);
        p = plot_add_panel(f, pt, sq ? "half-width (um)" : "radius (um)", "fraction of energy");
        if (!p ||
            plot_add_series(p, PLOT_LINES, PLOT_FG, e->radius_um, e->limit + o,
                            (size_t)e->npts) ||
            plot_add_series(p, PLOT_LINES, 0, e->radius_um, e->diffraction + o,
                            (size_t)e->npts) ||
            plot_add_series(p, PLOT_LINES, 1, e->radius_um, e->geometric + o, (size_t)e->npts))
            return -1;
        plot_panel_limits(p, 0.0);
    }
    plot_add_legend(f, PLOT_FG, "diffraction limit");
    plot_add_legend(f, 0, "diffraction");
    plot_add_legend(f, 1, "geometric");
    return 0;
}

int view_tf_figure(const sg_system *sys, const sg_tf *t, plot_figure *f)
{
    char title[200], lab[160], pt[32], ax[48], fr[96], lg[48];
    int k, q, nq = t->nfreq > 0 ? t->nfreq : 1;
    size_t used = 0;
    fr[0] = '\0';
    for (q = 0; q < nq && used < sizeof fr; q++)
        used += (size_t)snprintf(fr + used, sizeof fr - used, "%s%.4g",
                                 q == 0 ? "" : q == nq - 1 ? " and " : ", ",
                                 t->freq ? t->freq[q] : t->frequency);
    snprintf(title, sizeof title, "Through-focus MTF at %s cycles/mm: %s", fr,
             safe_text(sys->title, lab, sizeof lab));
    plot_figure_init(f, title);
    snprintf(ax, sizeof ax, "focus shift (%s)", sys->units);
    for (k = 0; k < t->nfield; k++) {
        plot_panel *p;
        snprintf(pt, sizeof pt, "field %d", t->field[k] + 1);
        p = plot_add_panel(f, pt, ax, "MTF, Strehl ratio");
        if (!p)
            return -1;
        /* One frequency keeps its two colours; several take a pair each. */
        for (q = 0; q < nq; q++) {
            size_t o = ((size_t)k * nq + q) * t->nsteps;
            if (plot_add_series(p, PLOT_LINES, 2 * q, t->shift, t->tan + o, (size_t)t->nsteps) ||
                plot_add_series(p, PLOT_LINES, 2 * q + 1, t->shift, t->sag + o,
                                (size_t)t->nsteps))
                return -1;
        }
        if (plot_add_series(p, PLOT_LINES, PLOT_FG, t->shift, t->strehl + (size_t)k * t->nsteps,
                            (size_t)t->nsteps))
            return -1;
        plot_panel_limits(p, 0.0);
    }
    for (q = 0; q < nq; q++) {
        if (nq == 1) {
            plot_add_legend(f, 0, "tangential");
            plot_add_legend(f, 1, "sagittal");
            break;
        }
        snprintf(lg, sizeof lg, "T %.4g cycles/mm", t->freq[q]);
        plot_add_legend(f, 2 * q, lg);
        snprintf(lg, sizeof lg, "S %.4g cycles/mm", t->freq[q]);
        plot_add_legend(f, 2 * q + 1, lg);
    }
    plot_add_legend(f, PLOT_FG, "Strehl ratio");
    return 0;
}
