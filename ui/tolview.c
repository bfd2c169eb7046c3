/*
 * tolview.c - tolerancing's pictures (tolview.h): the sensitivity bar
 * chart and the Monte Carlo histogram with its cumulative probability.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tolview.h"
#include "views.h"

static double change(const sg_tol_value *v, double c0)
{
    return v->status == SG_OK ? v->criterion - c0 : NAN;
}

/* The larger change of the row; a failed side is the worst there is. */
static double worst_change(const sg_tol_sens *s, double c0)
{
    double a = change(&s->at_min, c0), b = change(&s->at_max, c0);
    if (isnan(a))
        return isnan(b) ? INFINITY : b;
    if (isnan(b))
        return a;
    return a > b ? a : b;
}

void tolv_worst_order(const sg_tol_result *r, int *ord)
{
    int k, j;
    /* Insertion sort: stable, so ties keep row order (at most 200 rows). */
    for (k = 0; k < r->nsens; k++) {
        double w = worst_change(&r->sens[k], r->nominal.criterion);
        for (j = k; j > 0 && worst_change(&r->sens[ord[j - 1]], r->nominal.criterion) < w; j--)
            ord[j] = ord[j - 1];
        ord[j] = k;
    }
}

void tolv_row_label(const sg_tol_operand *op, char *buf, size_t n)
{
    if (op->type >= SG_TOL_TEDX && op->type <= SG_TOL_TETZ)
        snprintf(buf, n, "%s %d-%d", sg_tol_name(op->type), op->surface, op->last);
    else
        snprintf(buf, n, "%s %d", sg_tol_name(op->type), op->surface);
}

const char *tolv_criterion(const sg_system *sys, double extent, const char **unit,
                           double *scale)
{
    *scale = 1.0;
    if (sys->tol.criterion == SG_TOLC_MERIT) {
        *unit = "";
        return "merit function";
    }
    if (sys->tol.criterion == SG_TOLC_RMS_WAVEFRONT) {
        *unit = "waves";
        return "RMS wavefront";
    }
    *unit = view_length_unit(sys, extent, scale);
    return "RMS spot radius";
}

int tolv_bins(int m)
{
    int b = (int)ceil(sqrt((double)m));
    return b < 5 ? 5 : b > 50 ? 50 : b;
}

int tolv_sens_panel(const sg_system *sys, const sg_tol_result *r, int cols, plot_figure *f)
{
    int n = r->nsens, k, K, rc = -1;
    int *ord = malloc((size_t)(n > 0 ? n : 1) * sizeof *ord);
    char (*lab)[12] = malloc((size_t)(n > 0 ? n : 1) * sizeof *lab);
    const char **lp = malloc((size_t)(n > 0 ? n : 1) * sizeof *lp);
    double *x = malloc((size_t)(n > 0 ? n : 1) * sizeof *x);
    double *y = malloc((size_t)(n > 0 ? n : 1) * sizeof *y);
    double extent = 0.0, scale, zx[2], zy[2] = {0.0, 0.0};
    const char *unit, *name;
    char title[96], yl[64];
    plot_panel *p;
    if (!ord || !lab || !lp || !x || !y)
        goto out;
    tolv_worst_order(r, ord);
    for (k = 0; k < n; k++) {
        tolv_row_label(&sys->tol.op[ord[k]], lab[k], sizeof lab[k]);
        lp[k] = lab[k];
    }
    K = n < TOLV_FILE_BARS ? n : TOLV_FILE_BARS;
    if (cols > 0) {
        /* A terminal labels every bar it shows: as many of the worst as
         * leave each label a column apart beside the y axis's labels. */
        if (K > 10)
            K = 10;
        for (; K > 1; K--) {
            size_t w = 0;
            for (k = 0; k < K; k++)
                w = strlen(lab[k]) > w ? strlen(lab[k]) : w;
            if ((int)((w + 2) * (size_t)K) <= cols - 12)
                break;
        }
    }
    for (k = 0; k < K; k++) {
        const sg_tol_sens *s = &r->sens[ord[k]];
        double a = change(&s->at_min, r->nominal.criterion);
        double b = change(&s->at_max, r->nominal.criterion);
        if (isfinite(a))
            extent = fmax(extent, fabs(a));
        if (isfinite(b))
            extent = fmax(extent, fabs(b));
    }
    name = tolv_criterion(sys, extent, &unit, &scale);
    if (K < n)
        snprintf(title, sizeof title, "Sensitivity of the %s: the %d worst of %d operands",
                 name, K, n);
    else
        snprintf(title, sizeof title, "Sensitivity of the %s, worst first", name);
    if (unit[0])
        snprintf(yl, sizeof yl, "change (%s)", unit);
    else
        snprintf(yl, sizeof yl, "change");
    if (!(p = plot_add_panel(f, title, "operand (worst first)", yl)) ||
        plot_panel_categories(p, K, lp))
        goto out;
    /* Two bars a category, a gap between them so each cell keeps one
     * colour on a terminal. */
    for (k = 0; k < K; k++) {
        x[k] = k + 1 - 0.21;
        y[k] = change(&r->sens[ord[k]].at_min, r->nominal.criterion) * scale;
    }
    if (plot_add_bars(p, TOLV_MIN, x, y, (size_t)K, 0.38))
        goto out;
    for (k = 0; k < K; k++) {
        x[k] = k + 1 + 0.21;
        y[k] = change(&r->sens[ord[k]].at_max, r->nominal.criterion) * scale;
    }
    if (plot_add_bars(p, TOLV_MAX, x, y, (size_t)K, 0.38))
        goto out;
    zx[0] = 0.5;
    zx[1] = K + 0.5;
    if (plot_add_series(p, PLOT_LINES, PLOT_FG, zx, zy, 2))
        goto out;
    plot_panel_limits(p, 0.0);
    p->xmin = 0.5;
    p->xmax = K + 0.5;
    plot_add_legend(f, TOLV_MIN, "change at min");
    plot_add_legend(f, TOLV_MAX, "change at max");
    rc = 0;
out:
    free(ord);
    free(lab);
    free(lp);
    free(x);
    free(y);
    return rc;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int tolv_mc_panels(const sg_system *sys, const sg_tol_result *r, const double *crit, int n,
                   plot_figure *f)
{
    static const double pk[5] = {90, 80, 50, 20, 10};
    int m = 0, k, nb, rc = -1, *count = NULL, top = 0;
    double *v = malloc((size_t)(n > 0 ? n : 1) * sizeof *v), *x = NULL, *y = NULL;
    double lo, hi, width, scale, xl, xh, pad, c0 = r->nominal.criterion;
    const char *unit, *name;
    char title[96], xlab[64];
    plot_panel *h, *c;
    if (!v)
        return -1;
    for (k = 0; k < n; k++)
        if (isfinite(crit[k]))
            v[m++] = crit[k];
    if (m == 0) {
        free(v);
        return 0; /* no trial to show: the report says why */
    }
    qsort(v, (size_t)m, sizeof *v, cmp_double);
    lo = v[0];
    hi = v[m - 1];
    name = tolv_criterion(sys, fmax(fabs(lo), fabs(hi)), &unit, &scale);
    nb = tolv_bins(m);
    width = (hi - lo) / nb;
    if (!(width > 0.0))
        width = fmax(fabs(lo) * 1e-6, 1e-300); /* every trial alike: one bar */
    count = calloc((size_t)nb, sizeof *count);
    x = malloc((size_t)(2 * m + 20) * sizeof *x);
    y = malloc((size_t)(2 * m + 20) * sizeof *y);
    if (!count || !x || !y)
        goto out;
    for (k = 0; k < m; k++) {
        int b = (int)((v[k] - lo) / width);
        count[b < 0 ? 0 : b >= nb ? nb - 1 : b]++;
    }
    for (k = 0; k < nb; k++)
        top = count[k] > top ? count[k] : top;
    if (unit[0])
        snprintf(xlab, sizeof xlab, "%s (%s)", name, unit);
    else
        snprintf(xlab, sizeof xlab, "%s", name);
    if (m < n)
        snprintf(title, sizeof title, "Monte Carlo: %d trials (%d failed)", n, n - m);
    else
        snprintf(title, sizeof title, "Monte Carlo: %d trials", n);
    if (!(h = plot_add_panel(f, title, xlab, "trials")))
        goto out;
    for (k = 0; k < nb; k++) {
        x[k] = (lo + (k + 0.5) * width) * scale;
        y[k] = count[k];
    }
    if (plot_add_bars(h, TOLV_HIST, x, y, (size_t)nb, 0.9 * width * scale))
        goto out;
    x[0] = x[1] = c0 * scale;
    y[0] = 0.0;
    y[1] = top;
    if (isfinite(c0) && plot_add_series(h, PLOT_LINES, TOLV_NOM, x, y, 2))
        goto out;
    if (!(c = plot_add_panel(f, "Cumulative probability", xlab, "% of trials")))
        goto out;
    /* The empirical distribution as steps: at v[k] it rises to (k+1)/m. */
    for (k = 0; k < m; k++) {
        x[2 * k] = x[2 * k + 1] = v[k] * scale;
        y[2 * k] = 100.0 * k / m;
        y[2 * k + 1] = 100.0 * (k + 1) / m;
    }
    if (plot_add_series(c, PLOT_LINES, TOLV_CUM, x, y, (size_t)(2 * m)))
        goto out;
    /* The limits both panels share, the nominal included. */
    xl = isfinite(c0) ? fmin(lo, c0) : lo;
    xh = isfinite(c0) ? fmax(hi, c0) : hi;
    pad = 0.05 * (xh - xl);
    if (!(pad > 0.0))
        pad = fmax(0.5 * width, fabs(xl) * 1e-3);
    xl = (xl - pad) * scale;
    xh = (xh + pad) * scale;
    /* Each percentile's point, with lines to both axes so it reads off. */
    for (k = 0; k < 5; k++) {
        double px = r->stats.pct[k] * scale;
        x[4 * k] = xl;
        y[4 * k] = pk[k];
        x[4 * k + 1] = px;
        y[4 * k + 1] = pk[k];
        x[4 * k + 2] = px;
        y[4 * k + 2] = 0.0;
        x[4 * k + 3] = NAN;
        y[4 * k + 3] = NAN;
    }
    if (plot_add_series(c, PLOT_LINES, TOLV_PCT, x, y, 20))
        goto out;
    h->xmin = c->xmin = xl;
    h->xmax = c->xmax = xh;
    h->ymin = c->ymin = 0.0;
    h->ymax = 1.08 * top;
    c->ymax = 100.0;
    plot_add_legend(f, TOLV_HIST, "trials");
    plot_add_legend(f, TOLV_CUM, "cumulative probability");
    plot_add_legend(f, TOLV_PCT, "90, 80, 50, 20, 10 % points");
    if (isfinite(c0))
        plot_add_legend(f, TOLV_NOM, "nominal");
    rc = 0;
out:
    free(v);
    free(count);
    free(x);
    free(y);
    return rc;
}
