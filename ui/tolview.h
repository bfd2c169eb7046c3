/*
 * tolview.h - tolerancing's pictures (sagitta tolerance; sagitta(1),
 * TOLERANCING): the sensitivity bar chart, each operand's change of the
 * criterion at its min and at its max, worst first, as Zemax's tolerance
 * report ranks them; and the Monte Carlo histogram beside the cumulative
 * probability, with the 90, 80, 50, 20 and 10 % points marked.
 */
#ifndef SG_UI_TOLVIEW_H
#define SG_UI_TOLVIEW_H

#include "plot.h"
#include "sagitta.h"

/* The series colours: the bars at min and at max, the histogram, the
 * cumulative curve, its marked points and the nominal. */
enum { TOLV_MIN = 0, TOLV_MAX = 1, TOLV_HIST = 2, TOLV_CUM = 3, TOLV_PCT = 4, TOLV_NOM = 5 };
/* The most bars a file's chart shows (each one labelled: plot_xticks
 * labels every one of 15 categories). */
#define TOLV_FILE_BARS 15

/* ord[0 .. r->nsens-1]: the rows worst first, by the larger of the two
 * changes (a side that failed counts as worst), ties in row order. */
void tolv_worst_order(const sg_tol_result *r, int *ord);
/* "TRAD 2", "TEDX 3-4": a row's type and place, as the chart labels it. */
void tolv_row_label(const sg_tol_operand *op, char *buf, size_t n);
/* The criterion's name and the unit the pictures show it in (lens units
 * times *scale): "RMS spot radius" in micrometres or the lens unit,
 * "RMS wavefront" in waves, "merit function" (no unit, ""). extent: the
 * largest value to show. */
const char *tolv_criterion(const sg_system *sys, double extent, const char **unit,
                           double *scale);
/* The sensitivity chart as a panel of f (plot_figure_init'ed by the
 * caller) with its legend: the worst rows, as many as cols terminal
 * columns label apart (cols 0: a file's, TOLV_FILE_BARS).  0, or -1. */
int tolv_sens_panel(const sg_system *sys, const sg_tol_result *r, int cols, plot_figure *f);
/* The Monte Carlo's two panels: the histogram of crit[0 .. n-1] (NaN: a
 * failed trial, left out) and its cumulative probability, on one x
 * range, with the nominal and the percentiles of r->stats.  0, or -1. */
int tolv_mc_panels(const sg_system *sys, const sg_tol_result *r, const double *crit, int n,
                   plot_figure *f);
/* The histogram's bins for m values from lo to hi: ceil(sqrt(m)), from 5
 * to 50. */
int tolv_bins(int m);

#endif
