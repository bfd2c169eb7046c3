/* tolerance.c - "sagitta tolerance": sensitivity and Monte Carlo of a
 * design's tolerances (sagitta(1), TOLERANCING), as text, JSON or CSV. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ancmd.h"
#include "args.h"
#include "cli.h"
#include "outfile.h"
#include "report.h"
#include "safetext.h"
#include "tolview.h"
#include "tolh5.h"
#include "tolmpi.h"

static void tolerance_help(FILE *f)
{
    fputs(
"Usage: sagitta tolerance DESIGN.json [--sensitivity] [--monte-carlo N] [--seed S]\n"
"                         [--threads N] [--method M] [--format text|json|csv|hdf5]\n"
"                         [-o FILE] [--force] [--resume] [--save-worst K]\n"
"                         [--inverse LIMIT] [--size WxH] [--plot]\n"
"                         [--default-tolerances] [--save-tolerances FILE.json]\n"
"Tolerance the design (its \"tolerances\" object): each operand at its min\n"
"and max with the compensators re-optimized (sensitivity), and N systems\n"
"with every operand drawn (Monte Carlo), on every core.  Without\n"
"--sensitivity or --monte-carlo, sensitivity runs, and Monte Carlo too when\n"
"the design asks for trials.  Ctrl-C stops and reports what is done.  See\n"
"sagitta(1), TOLERANCING.\n"
"\n"
"Options:\n"
"  --sensitivity            each operand at its min and max\n"
"  --inverse LIMIT          each operand's changes at which the criterion grows\n"
"                           by LIMIT (inverse sensitivity)\n"
"  --monte-carlo N          N trials (0: none)\n"
"  --seed S                 the trials' seed (default: the design's, else 1)\n"
"  --threads N              systems at once (default: every core)\n"
"  --method M               the criterion's traces: precise (default), classic, mpfr\n"
"  --no-compensators        leave the compensators at their nominal values\n"
"  --format FMT             text (default), json, csv, hdf5 (the Monte Carlo\n"
"                           table, with -o FILE), or png, svg or pdf (the\n"
"                           sensitivity chart and the Monte Carlo histogram)\n"
"  --size WxH               picture size in pixels (png) or points (svg, pdf);\n"
"                           default 1000x750, grown to hold the bars\n"
"  --plot                   the pictures after the text also when it does not\n"
"                           go to a terminal\n"
"  -o, --output FILE        write the report to FILE (not over an existing file\n"
"                           without --force)\n"
"  --force                  overwrite FILE\n"
"  --resume                 continue the Monte Carlo table in FILE (CSV: from its\n"
"                           last whole trial; HDF5: a run stopped by Ctrl-C)\n"
"  --save-worst K           write the K worst Monte Carlo systems as\n"
"                           DESIGN-worst1.json ... (not over files without --force)\n"
"  --default-tolerances     tolerance the default set Zemax's Tolerance Wizard\n"
"                           makes (radii 1 fringe, thicknesses, decenters and\n"
"                           tilts 0.2, irregularity 0.2 fringes, index 0.001,\n"
"                           Abbe 1 %, the back focus compensating) instead of\n"
"                           the design's operands\n"
"  --save-tolerances FILE   write the design with that set to FILE.json and stop\n"
"  -h, --help               show this help\n", f);
}

/* --inverse's rows: n of them done, at limit. */
typedef struct inv_out {
    sg_tol_inv *v;
    int n;
    double limit;
} inv_out;
/* This run's, for the writers (NULL: not asked). */
static const inv_out *inv_report;

/* --save-worst's largest K. */
#define MAX_WORST 100

/* --format hdf5 and the pictures, beside report.h's formats. */
#define FMT_HDF5 1000
#define FMT_PNG 1001
#define FMT_SVG 1002
#define FMT_PDF 1003
#define IS_PICTURE(f) ((f) >= FMT_PNG && (f) <= FMT_PDF)

enum { TO_SEED = 1, TO_SIZE };

static const int tol_formats[] = {REPORT_TEXT, REPORT_CSV, REPORT_JSON, FMT_HDF5,
                                  FMT_PNG,     FMT_SVG,    FMT_PDF};

/* Help from rank 0 alone under mpirun. */
static void tolerance_help_rank0(FILE *f)
{
    if (tolmpi_rank() == 0)
        tolerance_help(f);
}
static volatile sig_atomic_t stop_flag;
static volatile int stop_int;

static void on_sigint(int sig)
{
    (void)sig;
    stop_flag = 1;
    stop_int = 1;
}

typedef struct prog {
    int on, shown;
    double t0, last;
    int base, total; /* Monte Carlo: trials before this block, and all */
} prog;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* On a terminal (not under CI), a line on standard error that counts the
 * systems done, four times a second. */
static int progress(void *ctx, int done, int total)
{
    prog *p = ctx;
    double t;
    if (!p->on)
        return 0;
    t = now_s();
    if (t - p->last < 0.25 && done < total)
        return 0;
    p->last = t;
    p->shown = 1;
    if (p->total) {
        done += p->base;
        total = p->total;
    }
    fprintf(stderr, "\rsagitta: tolerance: %d of %d systems, %.0f s", done, total, t - p->t0);
    fflush(stderr);
    return 0;
}

static const char *status_text(int st)
{
    return st == SG_OK ? "ok" : sg_err_name(st);
}

/* The operand's place: "surface 3" or "surfaces 3-4". */
static void op_place(const sg_tol_operand *op, char *buf, size_t n)
{
    if (op->type >= SG_TOL_TEDX && op->type <= SG_TOL_TETZ)
        snprintf(buf, n, "%d-%d", op->surface, op->last);
    else if (op->type == SG_TOL_TPAR)
        snprintf(buf, n, "%d %s[%d]", op->surface, op->param, op->elem);
    else
        snprintf(buf, n, "%d", op->surface);
}

static double change(const sg_tol_value *v, double c0)
{
    return v->status == SG_OK ? v->criterion - c0 : NAN;
}

static double worst_change(const sg_tol_sens *s, double c0)
{
    double a = change(&s->at_min, c0), b = change(&s->at_max, c0);
    if (isnan(a))
        return isnan(b) ? INFINITY : b;
    if (isnan(b))
        return a;
    return a > b ? a : b;
}

static void print_num(FILE *f, double v)
{
    if (isnan(v))
        fputs("null", f);
    else
        fprintf(f, "%.17g", v);
}

static const char *crit_key(const sg_system *sys)
{
    return sys->tol.criterion == SG_TOLC_MERIT            ? "merit"
           : sys->tol.criterion == SG_TOLC_RMS_WAVEFRONT ? "rms_wavefront"
                                                          : "rms_spot";
}

static const char *dist_key(const sg_system *sys)
{
    return sys->tol.distribution == SG_TOLD_UNIFORM     ? "uniform"
           : sys->tol.distribution == SG_TOLD_PARABOLIC ? "parabolic"
                                                        : "normal";
}

static void write_json(FILE *f, const sg_system *sys, const sg_tol_result *r, int sens, int mc,
                       const double *crit)
{
    static const char *const pk[5] = {"90", "80", "50", "20", "10"};
    int k, j;
    fprintf(f, "{\"criterion\": \"%s\", \"nominal\": ",
            sys->tol.criterion == SG_TOLC_MERIT            ? "merit"
            : sys->tol.criterion == SG_TOLC_RMS_WAVEFRONT ? "rms_wavefront"
                                                           : "rms_spot");
    print_num(f, r->nominal.criterion);
    fprintf(f, ", \"nominal_fields\": [");
    for (j = 0; j < r->nominal.nfield; j++) {
        fputs(j ? ", " : "", f);
        print_num(f, r->nominal.field[j]);
    }
    fprintf(f, "]");
    if (sens) {
        fprintf(f, ",\n\"sensitivity\": [");
        for (k = 0; k < r->nsens; k++) {
            const sg_tol_operand *op = &sys->tol.op[k];
            const sg_tol_sens *s = &r->sens[k];
            fprintf(f, "%s\n  {\"row\": %d, \"type\": \"%s\", ", k ? "," : "", k + 1,
                    sg_tol_name(op->type));
            if (op->type >= SG_TOL_TEDX && op->type <= SG_TOL_TETZ)
                fprintf(f, "\"first\": %d, \"last\": %d", op->surface, op->last);
            else
                fprintf(f, "\"surface\": %d", op->surface);
            fprintf(f, ", \"min\": %.17g, \"max\": %.17g, \"criterion_min\": ", op->min, op->max);
            print_num(f, s->at_min.status == SG_OK ? s->at_min.criterion : NAN);
            fputs(", \"criterion_max\": ", f);
            print_num(f, s->at_max.status == SG_OK ? s->at_max.criterion : NAN);
            fputs(", \"change_min\": ", f);
            print_num(f, change(&s->at_min, r->nominal.criterion));
            fputs(", \"change_max\": ", f);
            print_num(f, change(&s->at_max, r->nominal.criterion));
            fprintf(f, ", \"status_min\": \"%s\", \"status_max\": \"%s\"",
                    status_text(s->at_min.status), status_text(s->at_max.status));
            if (sys->tol.ncomp) {
                fputs(", \"compensators_min\": [", f);
                for (j = 0; j < sys->tol.ncomp; j++) {
                    fputs(j ? ", " : "", f);
                    print_num(f, s->at_min.comp[j]);
                }
                fputs("], \"compensators_max\": [", f);
                for (j = 0; j < sys->tol.ncomp; j++) {
                    fputs(j ? ", " : "", f);
                    print_num(f, s->at_max.comp[j]);
                }
                fputs("]", f);
            }
            fputs("}", f);
        }
        fprintf(f, "%s],\n\"rss_change\": %.17g", r->nsens ? "\n" : "", r->rss);
    }
    if (inv_report) {
        fprintf(f, ",\n\"inverse\": {\"limit\": %.17g, \"rows\": [", inv_report->limit);
        for (k = 0; k < inv_report->n; k++) {
            const sg_tol_operand *op = &sys->tol.op[k];
            const sg_tol_inv *v = &inv_report->v[k];
            fprintf(f, "%s\n  {\"row\": %d, \"type\": \"%s\", ", k ? "," : "", k + 1,
                    sg_tol_name(op->type));
            if (op->type >= SG_TOL_TEDX && op->type <= SG_TOL_TETZ)
                fprintf(f, "\"first\": %d, \"last\": %d", op->surface, op->last);
            else
                fprintf(f, "\"surface\": %d", op->surface);
            fputs(", \"min\": ", f);
            print_num(f, v->at_min.limit);
            fputs(", \"max\": ", f);
            print_num(f, v->at_max.limit);
            fputs(", \"criterion_min\": ", f);
            print_num(f, v->at_min.criterion);
            fputs(", \"criterion_max\": ", f);
            print_num(f, v->at_max.criterion);
            fprintf(f, ", \"status_min\": \"%s\", \"status_max\": \"%s\"}",
                    status_text(v->at_min.status), status_text(v->at_max.status));
        }
        fprintf(f, "%s]}", inv_report->n ? "\n" : "");
    }
    if (mc) {
        fprintf(f, ",\n\"monte_carlo\": {\"trials\": %d, \"done\": %d, \"seed\": %llu, "
                "\"distribution\": \"%s\", \"criteria\": [", r->trials, r->done,
                (unsigned long long)r->seed,
                sys->tol.distribution == SG_TOLD_UNIFORM ? "uniform"
                : sys->tol.distribution == SG_TOLD_PARABOLIC ? "parabolic" : "normal");
        for (k = 0; k < r->done; k++) {
            fputs(k ? (k % 8 ? ", " : ",\n  ") : "\n  ", f);
            print_num(f, crit[k]);
        }
        fprintf(f, "],\n  \"failed\": %d, \"best\": ", r->done - r->stats.n);
        print_num(f, r->stats.best);
        fputs(", \"worst\": ", f);
        print_num(f, r->stats.worst);
        fputs(", \"mean\": ", f);
        print_num(f, r->stats.mean);
        fputs(", \"std\": ", f);
        print_num(f, r->stats.std);
        fputs(", \"percentiles\": {", f);
        for (j = 0; j < 5; j++) {
            fprintf(f, "%s\"%s\": ", j ? ", " : "", pk[j]);
            print_num(f, r->stats.pct[j]);
        }
        fputs("}}", f);
    }
    fprintf(f, ",\n\"stopped\": %s}\n", r->stopped ? "true" : "false");
}

static void write_csv(FILE *f, const sg_system *sys, const sg_tol_result *r, int sens)
{
    int k;
    char place[64];
    fprintf(f, "kind,row,type,place,min,max,criterion_min,criterion_max,status_min,"
            "status_max\n");
    fprintf(f, "nominal,,,,,,%.17g,%.17g,%s,%s\n", r->nominal.criterion, r->nominal.criterion,
            "ok", "ok");
    if (sens)
        for (k = 0; k < r->nsens; k++) {
            const sg_tol_operand *op = &sys->tol.op[k];
            const sg_tol_sens *s = &r->sens[k];
            op_place(op, place, sizeof place);
            fprintf(f, "sensitivity,%d,%s,%s,%.17g,%.17g,%.17g,%.17g,%s,%s\n", k + 1,
                    sg_tol_name(op->type), place, op->min, op->max, s->at_min.criterion,
                    s->at_max.criterion, status_text(s->at_min.status),
                    status_text(s->at_max.status));
        }
    for (k = 0; inv_report && k < inv_report->n; k++) {
        const sg_tol_operand *op = &sys->tol.op[k];
        const sg_tol_inv *v = &inv_report->v[k];
        op_place(op, place, sizeof place);
        fprintf(f, "inverse,%d,%s,%s,%.17g,%.17g,%.17g,%.17g,%s,%s\n", k + 1,
                sg_tol_name(op->type), place, v->at_min.limit, v->at_max.limit,
                v->at_min.criterion, v->at_max.criterion, status_text(v->at_min.status),
                status_text(v->at_max.status));
    }
}

/* Trials first + 1 .. first + n as the CSV's rows. */
static void csv_trials(FILE *f, int first, int n, const sg_tol_value *v)
{
    int k;
    for (k = 0; k < n; k++)
        fprintf(f, "trial,%d,,,,,%.17g,%.17g,%s,%s\n", first + k + 1, v[k].criterion,
                v[k].criterion, status_text(v[k].status), status_text(v[k].status));
}

static void write_text(FILE *f, const sg_system *sys, const sg_tol_result *r, int sens, int mc)
{
    static const char *const pk[5] = {"90", "80", "50", "20", "10"};
    const char *crit = sys->tol.criterion == SG_TOLC_MERIT            ? "merit function"
                       : sys->tol.criterion == SG_TOLC_RMS_WAVEFRONT ? "RMS wavefront (waves)"
                                                                      : "RMS spot radius";
    char place[64];
    int k, j;
    fprintf(f, "Criterion: %s; nominal %.10g\n", crit, r->nominal.criterion);
    for (j = 0; j < r->nominal.nfield; j++)
        fprintf(f, "  field %d: %.10g\n", j + 1, r->nominal.field[j]);
    if (sens) {
        int *ord = malloc((size_t)(r->nsens > 0 ? r->nsens : 1) * sizeof *ord);
        fprintf(f, "\nSensitivity (each operand at its min and max%s):\n",
                sys->tol.ncomp ? ", compensated" : "");
        fprintf(f, "%4s %-5s %-14s %12s %12s %16s %16s %14s %14s\n", "Row", "Type", "Surface",
                "Min", "Max", "Criterion(min)", "Criterion(max)", "Change(min)",
                "Change(max)");
        for (k = 0; k < r->nsens; k++) {
            const sg_tol_operand *op = &sys->tol.op[k];
            const sg_tol_sens *s = &r->sens[k];
            op_place(op, place, sizeof place);
            fprintf(f, "%4d %-5s %-14s %12.6g %12.6g ", k + 1, sg_tol_name(op->type), place,
                    op->min, op->max);
            if (s->at_min.status == SG_OK)
                fprintf(f, "%16.10g ", s->at_min.criterion);
            else
                fprintf(f, "%16s ", sg_err_name(s->at_min.status));
            if (s->at_max.status == SG_OK)
                fprintf(f, "%16.10g ", s->at_max.criterion);
            else
                fprintf(f, "%16s ", sg_err_name(s->at_max.status));
            fprintf(f, "%14.6g %14.6g\n", change(&s->at_min, r->nominal.criterion),
                    change(&s->at_max, r->nominal.criterion));
        }
        if (ord) {
            tolv_worst_order(r, ord);
            fprintf(f, "\nWorst offenders:\n");
            for (k = 0; k < r->nsens && k < 10; k++) {
                const sg_tol_operand *op = &sys->tol.op[ord[k]];
                op_place(op, place, sizeof place);
                fprintf(f, "%4d %-5s %-14s change %.6g\n", ord[k] + 1, sg_tol_name(op->type),
                        place, worst_change(&r->sens[ord[k]], r->nominal.criterion));
            }
            free(ord);
        }
        fprintf(f, "\nEstimated change (RSS): %.6g; estimated criterion %.10g\n", r->rss,
                r->nominal.criterion + r->rss);
    }
    if (inv_report) {
        fprintf(f, "\nInverse sensitivity (the changes at which the criterion grows by %.6g):\n",
                inv_report->limit);
        fprintf(f, "%4s %-5s %-14s %16s %16s %16s %16s\n", "Row", "Type", "Surface", "Min",
                "Max", "Criterion(min)", "Criterion(max)");
        for (k = 0; k < inv_report->n; k++) {
            const sg_tol_operand *op = &sys->tol.op[k];
            const sg_tol_inv_side *sd[2] = {&inv_report->v[k].at_min, &inv_report->v[k].at_max};
            op_place(op, place, sizeof place);
            fprintf(f, "%4d %-5s %-14s", k + 1, sg_tol_name(op->type), place);
            for (j = 0; j < 2; j++)
                if (sd[j]->status == SG_OK)
                    fprintf(f, " %16.10g", sd[j]->limit);
                else
                    fprintf(f, " %16s", sd[j]->status == SG_ERANGE ? "not reached"
                                                                    : sg_err_name(sd[j]->status));
            for (j = 0; j < 2; j++)
                if (sd[j]->status == SG_OK)
                    fprintf(f, " %16.10g", sd[j]->criterion);
                else
                    fprintf(f, " %16s", "-");
            fputc('\n', f);
        }
    }
    if (mc) {
        fprintf(f, "\nMonte Carlo: %d of %d trials, seed %llu, %s distribution\n", r->done,
                r->trials, (unsigned long long)r->seed,
                sys->tol.distribution == SG_TOLD_UNIFORM ? "uniform"
                : sys->tol.distribution == SG_TOLD_PARABOLIC ? "parabolic" : "normal");
        if (r->done > r->stats.n)
            fprintf(f, "  failed:  %d (left out)\n", r->done - r->stats.n);
        fprintf(f, "  nominal: %.10g\n  best:    %.10g\n  worst:   %.10g\n  mean:    %.10g\n"
                "  std:     %.10g\n", r->nominal.criterion, r->stats.best, r->stats.worst,
                r->stats.mean, r->stats.std);
        for (j = 0; j < 5; j++)
            fprintf(f, "  %s%% <= %.10g\n", pk[j], r->stats.pct[j]);
    }
    if (r->stopped)
        fprintf(f, "\nStopped: the report holds what was done.\n");
}

/* The figure of what ran (what: 1 the sensitivity chart, 2 the Monte
 * Carlo's panels, 3 both), for a terminal of cols columns or (0) a file. */
static int tol_figure(const sg_system *sys, const sg_tol_result *r, int what, const double *crit,
                      int cols, plot_figure *f)
{
    char title[256], lab[160];
    if (sys->title[0])
        snprintf(title, sizeof title, "Tolerancing: %s", safe_text(sys->title, lab, sizeof lab));
    else
        snprintf(title, sizeof title, "Tolerancing");
    plot_figure_init(f, title);
    if ((what & 1) && r->nsens > 0 && tolv_sens_panel(sys, r, cols, f))
        return -1;
    if ((what & 2) && crit && r->done > 0 && tolv_mc_panels(sys, r, crit, r->done, f))
        return -1;
    /* The chart above the histogram and the curve, each the full width. */
    f->ncol = f->npanel > 2 ? 1 : 0;
    return 0;
}

/* After the text: the chart, then the histogram, each its own 24 rows. */
static int text_pictures(FILE *f, const sg_system *sys, const sg_tol_result *r, int sens,
                         int mc, const double *crit)
{
    int cols = an_terminal_width(f), colour = plot_use_colour(f), k, rc = 0;
    for (k = 1; k <= 2 && !rc; k++) {
        plot_figure fig;
        if ((k == 1 && !sens) || (k == 2 && !mc))
            continue;
        rc = tol_figure(sys, r, k, crit, cols, &fig);
        if (!rc && fig.npanel)
            rc = an_terminal_picture(&fig, f, colour);
        plot_figure_free(&fig);
    }
    return rc;
}

/* --format png, svg or pdf: one figure of every panel.  Exit status. */
static int write_picture(FILE *f, const char *where, int fmt, int width, int height,
                         int size_given, const sg_system *sys, const sg_tol_result *r, int sens,
                         int mc, const double *crit)
{
    plot_figure fig;
    char msg[256];
    int rc = CLI_EXIT_OK;
    if (tol_figure(sys, r, (sens ? 1 : 0) | (mc ? 2 : 0), crit, 0, &fig)) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
    } else if (fig.npanel == 0) {
        cli_error("%s: nothing to draw (no sensitivity row and no Monte Carlo trial done)",
                  where);
        rc = CLI_EXIT_DESIGN;
    } else {
        if (!size_given) {
            /* Room for every bar's label (about 64 points each), and for
             * the panels' own minimum. */
            int bars = r->nsens < TOLV_FILE_BARS ? r->nsens : TOLV_FILE_BARS, mw, mh;
            if (sens && 74 + 64 * bars > width)
                width = 74 + 64 * bars;
            if (fig.npanel > 2 && height < 900)
                height = 900; /* three panels stacked */
            plot_min_size(&fig, width, &mw, &mh);
            width = mw > width ? mw : width;
            height = mh > height ? mh : height;
        }
        if (plot_write(&fig, fmt - FMT_PNG, width, height, f, msg, sizeof msg)) {
            cli_error("%s: %s", where, msg);
            rc = CLI_EXIT_FILE;
        }
    }
    plot_figure_free(&fig);
    return rc;
}

/* Rank 0's end of the Monte Carlo: the trials in order, into the CSV's
 * rows as they come and the criteria the statistics need. */
typedef struct mc_sink {
    FILE *f;
    int csv;
    double *crit;   /* the criteria (NaN: failed), for the statistics; NULL for CSV */
    tolh5 *h5;
    int done;
    prog *p;
    /* The worst trials (--save-worst), worst first, ties in trial order. */
    int kworst, nworst, worst_trial[MAX_WORST];
    double worst_crit[MAX_WORST];
} mc_sink;

static int take_trials(void *ctx, int first, int n, const sg_tol_value *v)
{
    mc_sink *s = ctx;
    int k;
    if (s->csv) {
        csv_trials(s->f, first, n, v);
        /* A killed run keeps the rows written (--resume). */
        if (fflush(s->f) != 0 || ferror(s->f)) {
            cli_error("writing the trials: %s", strerror(errno));
            return CLI_EXIT_FILE;
        }
    }
    if (s->h5) {
        char err[512];
        if (tolh5_write(s->h5, first, n, v, err, sizeof err) != 0) {
            cli_error("writing the trials: %s", err);
            return CLI_EXIT_FILE;
        }
    }
    for (k = 0; k < n && s->kworst; k++) {
        int j;
        if (v[k].status != SG_OK || isnan(v[k].criterion) ||
            (s->nworst == s->kworst && !(v[k].criterion > s->worst_crit[s->nworst - 1])))
            continue;
        j = s->nworst < s->kworst ? s->nworst++ : s->nworst - 1;
        for (; j > 0 && v[k].criterion > s->worst_crit[j - 1]; j--) {
            s->worst_crit[j] = s->worst_crit[j - 1];
            s->worst_trial[j] = s->worst_trial[j - 1];
        }
        s->worst_crit[j] = v[k].criterion;
        s->worst_trial[j] = first + k;
    }
    if (s->crit)
        for (k = 0; k < n; k++)
            s->crit[first + k] = v[k].status == SG_OK ? v[k].criterion : NAN;
    s->done = first + n;
    s->p->base = s->done;
    return 0;
}

/* DESIGN-worstN.json beside DESIGN (its .json, if any, replaced), N = k + 1. */
static void worst_path(const char *design, int k, char *buf, size_t n)
{
    size_t len = strlen(design);
    if (len > 5 && strcmp(design + len - 5, ".json") == 0)
        len -= 5;
    snprintf(buf, n, "%.*s-worst%d.json", (int)len, design, k + 1);
}

/* --save-worst: each of the worst trials' systems built again, perturbed
 * and compensated, and saved. */
static int save_worst(const char *design, sg_tol_mc *m, const mc_sink *s)
{
    char path[4096];
    sg_system *w;
    sg_tol_value v;
    sg_diag d;
    int k, rc;
    for (k = 0; k < s->nworst; k++) {
        if (!(w = sg_system_new())) {
            cli_error("out of memory");
            return CLI_EXIT_INTERNAL;
        }
        worst_path(design, k, path, sizeof path);
        sg_diag_clear(&d);
        rc = sg_tol_mc_system(m, s->worst_trial[k], w, &v, &d);
        /* The tolerance rows name the nominal's surfaces, which the
         * element operands' coordinate breaks renumber: the built lens is
         * saved without them. */
        memset(&w->tol, 0, sizeof w->tol);
        if (rc == SG_OK)
            rc = sg_design_save(w, path, &d);
        sg_system_free(w);
        if (rc != SG_OK) {
            cli_print_diag(path, &d, rc);
            return CLI_EXIT_FILE;
        }
        fprintf(stderr, "sagitta: tolerance: %s: trial %d, criterion %.10g\n", path,
                s->worst_trial[k] + 1, s->worst_crit[k]);
    }
    return CLI_EXIT_OK;
}

/* The trials on this process alone, in blocks as the ranks take them. */
static int local_trials(sg_tol_mc *m, int start, int trials, int block, mc_sink *s)
{
    sg_tol_value *v = malloc((size_t)block * sizeof *v);
    int first, rc = 0;
    if (!v) {
        cli_error("out of memory");
        return CLI_EXIT_INTERNAL;
    }
    for (first = start; first < trials && !rc; first += block) {
        int n = trials - first < block ? trials - first : block, done;
        if (sg_tol_mc_run(m, first, n, v, &done) != SG_OK) {
            cli_error("out of memory");
            rc = CLI_EXIT_INTERNAL;
            break;
        }
        if ((rc = take_trials(s, first, done, v)) == 0 && done < n)
            rc = 1;
    }
    free(v);
    return rc;
}

/* The line of f where a and b (n bytes) first differ, 1-based. */
static int differing_line(const char *a, const char *b, size_t n)
{
    size_t i;
    int line = 1;
    for (i = 0; i < n && a[i] == b[i]; i++)
        line += a[i] == '\n';
    return line;
}

/* --resume: FILE's head (the header, nominal and sensitivity rows) must be
 * this run's, byte for byte, and its trial rows 1 .. K in order, the last
 * whole one the same as this run's trial K computed again (so the seed,
 * distribution, method and design are the same); a torn last line is
 * dropped.  FILE is cut after row K and left open to append; *start = K. */
static int resume_open(const char *path, const sg_system *sys, const sg_tol_result *r,
                       int sens, sg_tol_mc *m, int trials, FILE **out, int *start)
{
    char *head = NULL, *got = NULL, *line = NULL, *last = NULL, *again = NULL;
    size_t hn = 0, cap = 0, an = 0;
    FILE *mem, *f = NULL;
    off_t end;
    ssize_t len;
    int k = 0, lineno, nhead = 0, done, rc = CLI_EXIT_FILE;
    sg_tol_value v;
    *out = NULL;
    if (!(mem = open_memstream(&head, &hn)))
        goto nomem;
    write_csv(mem, sys, r, sens);
    if (fclose(mem) != 0 || !(got = malloc(hn + 1)))
        goto nomem;
    if (!(f = fopen(path, "r+"))) {
        cli_error("%s: %s (--resume continues a table written before)", path, strerror(errno));
        goto out;
    }
    if (fread(got, 1, hn, f) != hn || memcmp(got, head, hn) != 0) {
        cli_error("%s: line %d is not this run's (--resume continues a table of the same "
                  "design and options)", path, differing_line(got, head, hn));
        goto out;
    }
    for (lineno = 0; lineno < (int)hn; lineno++)
        nhead += head[lineno] == '\n';
    end = (off_t)hn;
    for (lineno = nhead + 1; (len = getline(&line, &cap, f)) > 0; lineno++) {
        char expect[32];
        int n = snprintf(expect, sizeof expect, "trial,%d,", k + 1);
        /* A row cut short by the kill is dropped and computed again. */
        if (line[len - 1] != '\n')
            break;
        if (strncmp(line, expect, (size_t)n) != 0) {
            cli_error("%s: line %d is not trial %d's row", path, lineno, k + 1);
            goto out;
        }
        free(last);
        if (!(last = strdup(line)))
            goto nomem;
        k++;
        end += (off_t)len;
    }
    if (ferror(f)) {
        cli_error("%s: %s", path, strerror(errno));
        goto out;
    }
    if (k > trials) {
        cli_error("%s: holds %d trials, more than the %d asked", path, k, trials);
        rc = CLI_EXIT_USAGE;
        goto out;
    }
    if (k > 0) {
        if (sg_tol_mc_run(m, k - 1, 1, &v, &done) != SG_OK || !(mem = open_memstream(&again,
                                                                                    &an)))
            goto nomem;
        if (done == 1)
            csv_trials(mem, k - 1, 1, &v);
        if (fclose(mem) != 0)
            goto nomem;
        if (done != 1) {
            cli_error("%s: stopped before its last trial was checked; the file is as it was",
                      path);
            goto out;
        }
        if (strcmp(again, last) != 0) {
            cli_error("%s: trial %d is not this run's (another seed, distribution, method or "
                      "design); --resume continues a table of the same options", path, k);
            goto out;
        }
    }
    if (fflush(f) != 0 || ftruncate(fileno(f), end) != 0 || fseeko(f, end, SEEK_SET) != 0) {
        cli_error("%s: %s", path, strerror(errno));
        goto out;
    }
    *out = f;
    *start = k;
    f = NULL;
    rc = CLI_EXIT_OK;
    goto out;
nomem:
    cli_error("out of memory");
    rc = CLI_EXIT_INTERNAL;
out:
    if (f)
        fclose(f);
    free(head);
    free(got);
    free(line);
    free(last);
    free(again);
    return rc;
}

/* --resume --format hdf5: FILE must be this run's table (its settings,
 * trials 1 .. K, trial K computed again equal to its row, status and
 * criterion bit for bit).  HDF5 is not written in place: a new table is
 * made beside FILE, its K rows copied and their criteria put in crit,
 * and the run goes on from K (*start); FILE is replaced when the run
 * ends, and stays as it was on any error.  With all trials there,
 * *start is trials and the new table is dropped (*h5 NULL). */
static int resume_h5(const char *path, const sg_system *sys, const sg_tol_result *r,
                     sg_tol_mc *m, int trials, uint64_t seed, double *crit, tolh5 **h5,
                     int *start)
{
    char err[512];
    sg_tol_value last, again;
    int k = 0, done = 0, rc = CLI_EXIT_FILE;
    /* One pass: the rows are checked as they are copied into the new
     * table, which is dropped (FILE untouched) on any refusal. */
    if (!(*h5 = tolh5_open(path, crit_key(sys), dist_key(sys), r->nominal.criterion, seed,
                           trials, err, sizeof err))) {
        cli_error("%s: %s", path, err);
        return CLI_EXIT_FILE;
    }
    if (tolh5_resume(path, crit_key(sys), dist_key(sys), r->nominal.criterion, seed, trials,
                     *h5, crit, &k, &last, err, sizeof err) != 0) {
        cli_error("%s: %s; --resume continues a table of the same design and options", path,
                  err);
        goto fail;
    }
    if (k > 0) {
        if (sg_tol_mc_run(m, k - 1, 1, &again, &done) != SG_OK) {
            cli_error("out of memory");
            rc = CLI_EXIT_INTERNAL;
            goto fail;
        }
        if (done != 1) {
            cli_error("%s: stopped before its last trial was checked; the file is as it was",
                      path);
            goto fail;
        }
        /* NaN is stored for a failed system, whatever it computed. */
        if (again.status != last.status ||
            (again.status == SG_OK &&
             memcmp(&again.criterion, &last.criterion, sizeof last.criterion) != 0)) {
            cli_error("%s: trial %d is not this run's (another seed, distribution, method or "
                      "design); --resume continues a table of the same options", path, k);
            goto fail;
        }
    }
    *start = k;
    /* A whole table is left as it was. */
    if (k >= trials) {
        tolh5_abort(*h5);
        *h5 = NULL;
    }
    return CLI_EXIT_OK;
fail:
    tolh5_abort(*h5);
    *h5 = NULL;
    return rc;
}

static int tolerance_main(int argc, char **argv)
{
    cli_iter it;
    const char *val, *design = NULL, *output = NULL;
    int id, rc, force = 0, sens = 0, mc = -1, fmt = REPORT_TEXT, seed_given = 0;
    int pic_w = 1000, pic_h = 750, size_given = 0, plot_text = 0, deftol = 0;
    const char *save_tol = NULL;
    int rank = tolmpi_rank(), block, nthreads, opened = 0, start = 0, resume = 0, nworst = 0;
    int k;
    char wpath[4096];
    double inv_limit = 0;
    inv_out iv;
    long long seed = 1;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_tol_mc *mcx = NULL;
    sg_tol_opts o;
    sg_tol_result r;
    struct sigaction sa, old;
    struct stat st;
    sg_diag d;
    prog p;
    outfile of;
    mc_sink sink;
    FILE *tab = NULL; /* the Monte Carlo table, written in place */
    tolh5 *h5 = NULL;
    int inplace;
    sg_tol_opts_init(&o);
    memset(&of, 0, sizeof of);
    memset(&r, 0, sizeof r);
    memset(&sink, 0, sizeof sink);
    {
        int nocomp = 0, method = o.method;
        const cli_opt opts[] = {
            CLI_OPT_HELP,
            CLI_OPT_FLAG("--sensitivity", 0, sens),
            CLI_OPT_INT("--monte-carlo", 0, mc, 0, 100000000),
            /* Up to 2^53: an integer no int holds. */
            CLI_ID("--seed", 0, 1, TO_SEED),
            CLI_OPT_INT("--threads", 0, o.nthreads, 1, 256),
            CLI_OPT_METHOD(method),
            CLI_OPT_FLAG("--no-compensators", 0, nocomp),
            CLI_OPT_WORD("--format", fmt, "text|csv|json|hdf5|png|svg|pdf", tol_formats),
            CLI_ID("--size", 0, 1, TO_SIZE),
            CLI_OPT_FLAG("--plot", 0, plot_text),
            CLI_OPT_FLAG("--default-tolerances", 0, deftol),
            CLI_OPT_TEXT("--save-tolerances", 0, save_tol),
            CLI_OPT_OUTPUT(output),
            CLI_OPT_FLAG("--force", 0, force),
            CLI_OPT_FLAG("--resume", 0, resume),
            CLI_OPT_INT("--save-worst", 0, nworst, 1, MAX_WORST),
            CLI_OPT_POS("--inverse", inv_limit, "limit", NULL),
            CLI_END};
        cli_iter_init(&it, "tolerance", argc, argv);
        while ((id = cli_next_opt(&it, opts, &val)) != -1) {
            if (id == 0) {
                if (design)
                    return cli_usage_error("tolerance", "unexpected argument \"%s\"", val);
                design = val;
            } else if (id == CLI_HELP) {
                tolerance_help_rank0(stdout);
                return CLI_EXIT_OK;
            } else if (id == TO_SEED) {
                char *end;
                errno = 0;
                seed = strtoll(val, &end, 10);
                if (errno || end == val || *end || seed < 0 || seed > (1LL << 53))
                    return cli_usage_error("tolerance", "--seed: \"%s\" is not an integer "
                                           "from 0 to 2^53", val);
                seed_given = 1;
            } else if (id == TO_SIZE) {
                const char *x = strchr(val, 'x');
                char w[32];
                if (!x || (size_t)(x - val) >= sizeof w)
                    return cli_usage_error("tolerance", "--size: expected WIDTHxHEIGHT, got "
                                           "\"%s\"", val);
                memcpy(w, val, (size_t)(x - val));
                w[x - val] = '\0';
                if (args_int(w, 100, 20000, &pic_w) != ARGS_OK ||
                    args_int(x + 1, 100, 20000, &pic_h) != ARGS_OK)
                    return cli_usage_error("tolerance", "--size: expected WIDTHxHEIGHT, each "
                                           "from 100 to 20000, got \"%s\"", val);
                size_given = 1;
            } else {
                return -id;
            }
        }
        o.method = method;
        if (nocomp)
            o.compensate = 0;
    }
    if (!design)
        return cli_usage_error("tolerance", "missing DESIGN.json");
    if (fmt == FMT_HDF5 && (!output || strcmp(output, "-") == 0))
        return cli_usage_error("tolerance", "--format hdf5 needs -o FILE.h5");
    if (IS_PICTURE(fmt) && (!output || strcmp(output, "-") == 0) && isatty(STDOUT_FILENO))
        return cli_usage_error("tolerance", "a %s picture needs -o FILE (standard output is a "
                               "terminal)", fmt == FMT_PNG ? "PNG" : fmt == FMT_SVG ? "SVG"
                                                                                    : "PDF");
    if (resume && (!output || strcmp(output, "-") == 0 ||
                   (fmt != REPORT_CSV && fmt != FMT_HDF5)))
        return cli_usage_error("tolerance", "--resume continues a CSV or HDF5 file: give -o "
                               "FILE and --format csv or hdf5");
    if (rank == 0 && output && strcmp(output, "-") != 0 && !force && !resume &&
        stat(output, &st) == 0)
        return cli_usage_error("tolerance", "%s exists; use --force to overwrite it", output);
    if (nworst && resume)
        return cli_usage_error("tolerance", "--save-worst needs every trial: not with --resume");
    /* The worst systems' files are refused before the run, not after. */
    for (k = 0; rank == 0 && k < nworst; k++) {
        worst_path(design, k, wpath, sizeof wpath);
        if (!force && stat(wpath, &st) == 0)
            return cli_usage_error("tolerance", "%s exists; use --force to overwrite it",
                                   wpath);
    }
    if (save_tol && !deftol)
        return cli_usage_error("tolerance", "--save-tolerances writes the default set: give "
                               "--default-tolerances");
    if (save_tol && !force && stat(save_tol, &st) == 0)
        return cli_usage_error("tolerance", "%s exists; use --force to overwrite it", save_tol);
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    if (deftol) {
        sg_tol_defaults dt;
        sg_tol_defaults_init(&dt);
        sg_diag_clear(&d);
        if ((rc = sg_tol_default_set(sys, cat, &dt, &d)) == SG_OK)
            rc = sg_tol_check(sys, &d);
        if (rc == SG_OK && save_tol && rank == 0) {
            if (cli_output_is_input(save_tol) || strcmp(save_tol, design) == 0) {
                rc = cli_usage_error("tolerance", "--save-tolerances: %s is the design; "
                                     "write the set to another file", save_tol);
                goto done;
            }
            rc = sg_design_save(sys, save_tol, &d);
            if (rc != SG_OK) {
                cli_print_diag(save_tol, &d, rc);
                rc = CLI_EXIT_FILE;
                goto done;
            }
            fprintf(stderr, "sagitta: tolerance: %s: %d default tolerance rows, %d "
                    "compensator%s\n", save_tol, sys->tol.nop, sys->tol.ncomp,
                    sys->tol.ncomp == 1 ? "" : "s");
            rc = CLI_EXIT_OK;
            goto done;
        }
        if (rc != SG_OK) {
            cli_print_diag(design, &d, rc);
            rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
            goto done;
        }
        if (save_tol) {
            rc = CLI_EXIT_OK;
            goto done;
        }
    }
    if (!sys->tol.present || sys->tol.nop == 0) {
        cli_error("%s: the design has no tolerance operands (a \"tolerances\" object; "
                  "sagitta-design(5), TOLERANCES)", design);
        rc = CLI_EXIT_DESIGN;
        goto done;
    }
    if (mc < 0 && !sens) {
        sens = 1;
        mc = sys->tol.trials;
    } else if (mc < 0) {
        mc = 0;
    }
    if (!seed_given)
        seed = (long long)sys->tol.seed;
    if (IS_PICTURE(fmt) && !sens && mc == 0) {
        rc = cli_usage_error("tolerance", "the pictures show the sensitivity and the Monte "
                             "Carlo: give --sensitivity or --monte-carlo N");
        goto done;
    }
    memset(&p, 0, sizeof p);
    {
        const char *ci = getenv("CI");
        p.on = rank == 0 && isatty(STDERR_FILENO) && !(ci && ci[0]);
    }
    p.t0 = p.last = now_s();
    o.progress = progress;
    o.ctx = &p;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old);
    stop_flag = 0;
    stop_int = 0;
    o.stop = &stop_int;
    sg_diag_clear(&d);
    rc = SG_OK;
    /* Every rank compensates the nominal for its trials; rank 0 alone runs
     * the sensitivity and writes. */
    memset(&iv, 0, sizeof iv);
    inv_report = NULL;
    if (mc > 0 || (inv_limit > 0 && rank == 0))
        rc = sg_tol_mc_open(sys, cat, &o, (uint64_t)seed, &mcx, &r.nominal, &d);
    /* The nominal is the same computation there and here. */
    if (rc == SG_OK && rank == 0 && (sens || !mcx))
        rc = sg_tolerance_run(sys, cat, &o, sens, 0, (uint64_t)seed, &r, &d);
    if (p.shown)
        fputs("\r\033[K", stderr);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
        goto restore;
    }
    /* Inverse sensitivity, on rank 0 as the sensitivity. */
    if (rank == 0 && inv_limit > 0 && !r.stopped) {
        iv.limit = inv_limit;
        if (!(iv.v = calloc((size_t)sys->tol.nop, sizeof *iv.v))) {
            cli_error("out of memory");
            rc = CLI_EXIT_INTERNAL;
            goto restore;
        }
        p.total = 0;
        if ((rc = sg_tol_inverse(mcx, inv_limit, iv.v, &iv.n, &d)) != SG_OK) {
            cli_print_diag(design, &d, rc);
            rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
            goto restore;
        }
        if (iv.n < sys->tol.nop)
            r.stopped = 1;
        inv_report = &iv;
    }
    r.trials = mc;
    r.seed = (uint64_t)seed;
    if (rank == 0 && mc > 0 && !r.stopped && fmt != REPORT_CSV &&
        !(sink.crit = malloc((size_t)mc * sizeof *sink.crit))) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto restore;
    }
    if (rank == 0) {
        /* A Monte Carlo table written to a file grows there a block at a
         * time, so a killed run keeps its trials (--resume). */
        inplace = fmt == REPORT_CSV && mc > 0 && !r.stopped && output &&
                  strcmp(output, "-") != 0;
        if (fmt == FMT_HDF5 && mc == 0) {
            rc = cli_usage_error("tolerance", "--format hdf5 writes the Monte Carlo table: "
                                 "give --monte-carlo N");
            goto restore;
        }
        if (nworst && mc == 0) {
            rc = cli_usage_error("tolerance", "--save-worst keeps Monte Carlo systems: give "
                                 "--monte-carlo N");
            goto restore;
        }
        if (resume && mc == 0) {
            rc = cli_usage_error("tolerance", "--resume: no Monte Carlo trials to continue");
            goto restore;
        }
        if (resume && r.stopped) {
            cli_error("%s: stopped before the trials; the file is as it was", output);
            rc = CLI_EXIT_FILE;
            goto restore;
        }
        if (resume && fmt == FMT_HDF5) {
            if ((rc = resume_h5(output, sys, &r, mcx, mc, (uint64_t)seed, sink.crit, &h5,
                                &start)) != 0)
                goto restore;
            if (start >= mc) {
                fprintf(stderr, "sagitta: tolerance: %s holds all %d trials already\n", output,
                        mc);
                rc = CLI_EXIT_OK;
                goto restore;
            }
        } else if (resume) {
            if ((rc = resume_open(output, sys, &r, sens, mcx, mc, &tab, &start)) != 0)
                goto restore;
        } else if (fmt == FMT_HDF5) {
            char err[512];
            if (!(h5 = tolh5_open(output, crit_key(sys), dist_key(sys), r.nominal.criterion,
                                  (uint64_t)seed, mc, err, sizeof err))) {
                cli_error("%s: %s", output, err);
                rc = CLI_EXIT_FILE;
                goto restore;
            }
        } else if (inplace) {
            if (!(tab = fopen(output, "w"))) {
                cli_error("%s: %s", output, strerror(errno));
                rc = CLI_EXIT_FILE;
                goto restore;
            }
            write_csv(tab, sys, &r, sens);
        } else {
            if ((rc = outfile_open(&of, output && strcmp(output, "-") != 0 ? output : NULL,
                                   stdout))) {
                cli_error("%s: %s", output, strerror(rc));
                rc = CLI_EXIT_FILE;
                goto restore;
            }
            opened = 1;
            if (fmt == REPORT_CSV)
                write_csv(of.f, sys, &r, sens);
        }
        if (r.stopped || start >= mc)
            start = -1;
    }
    /* The workers wait here for rank 0's sensitivity and learn the first
     * trial to run (-1: none, after a stop or with every trial done). */
    if ((rc = tolmpi_agree(CLI_EXIT_OK, &start)) != CLI_EXIT_OK)
        goto restore;
    if (mc > 0 && start >= 0) {
        nthreads = o.nthreads > 0 ? o.nthreads : (int)sysconf(_SC_NPROCESSORS_ONLN);
        /* Blocks of a few systems a thread keep the threads busy to the
         * block's end; the output does not depend on the size. */
        block = 8 * (nthreads > 0 ? nthreads : 1);
        sink.f = rank == 0 ? (tab ? tab : of.f) : NULL;
        sink.csv = fmt == REPORT_CSV;
        sink.h5 = h5;
        sink.kworst = rank == 0 ? nworst : 0;
        sink.p = &p;
        sink.done = start;
        p.total = mc;
        p.base = start;
        rc = tolmpi_size() > 1
                 ? tolmpi_trials(mcx, start, mc, block, take_trials, &sink, &sink.done)
                 : local_trials(mcx, start, mc, block, &sink);
        if (p.shown)
            fputs("\r\033[K", stderr);
        if (rc == 1) {
            r.stopped = 1;
            rc = 0;
        }
        if (rc)
            goto restore;
        r.done = sink.done;
        if (sink.crit && r.done > 0)
            sg_tol_statistics(sink.crit, r.done, &r.stats);
    } else if (resume) {
        r.done = mc;
    }
    if (stop_int)
        r.stopped = 1;
    if (rank == 0 && (rc = save_worst(design, mcx, &sink)) != CLI_EXIT_OK)
        goto restore;
    if (rank == 0 && h5) {
        char err[512];
        rc = tolh5_close(h5, r.done, r.stopped, r.done > 0 ? &r.stats : NULL, err, sizeof err);
        h5 = NULL;
        if (rc) {
            cli_error("%s: %s", output, err);
            rc = CLI_EXIT_FILE;
            goto restore;
        }
        rc = CLI_EXIT_OK;
        goto restore;
    }
    if (rank == 0) {
        if (fmt == REPORT_JSON)
            write_json(of.f, sys, &r, sens, mc > 0, sink.crit);
        else if (fmt == REPORT_TEXT)
            write_text(of.f, sys, &r, sens, mc > 0);
        if (fmt == REPORT_TEXT && (plot_text || isatty(fileno(of.f))) &&
            text_pictures(of.f, sys, &r, sens, mc > 0, sink.crit)) {
            cli_error("out of memory");
            rc = CLI_EXIT_INTERNAL;
            goto restore;
        }
        if (IS_PICTURE(fmt) &&
            (rc = write_picture(of.f, output && strcmp(output, "-") ? output : "standard output",
                                fmt, pic_w, pic_h, size_given, sys, &r, sens, mc > 0,
                                sink.crit)) != CLI_EXIT_OK)
            goto restore;
        if (tab) {
            rc = fclose(tab) != 0 ? errno : 0;
            tab = NULL;
            if (rc) {
                cli_error("%s: %s", output, strerror(rc));
                rc = CLI_EXIT_FILE;
                goto restore;
            }
            if (resume && start < 0)
                fprintf(stderr, "sagitta: tolerance: %s holds all %d trials already\n", output,
                        mc);
            rc = CLI_EXIT_OK;
            goto restore;
        }
        opened = 0;
        if ((rc = outfile_commit(&of))) {
            cli_error("%s: %s", output ? output : "standard output", strerror(rc));
            rc = CLI_EXIT_FILE;
            goto restore;
        }
    }
    rc = CLI_EXIT_OK;
restore:
    sigaction(SIGINT, &old, NULL);
    if (opened)
        outfile_abort(&of);
    tolh5_abort(h5);
    /* A table that grew in place keeps its whole trials. */
    if (tab) {
        fclose(tab);
        if (rc != CLI_EXIT_OK && mc > 0)
            fprintf(stderr, "sagitta: tolerance: %s keeps the trials written; --resume "
                    "continues it\n", output);
    }
done:
    free(iv.v);
    inv_report = NULL;
    free(sink.crit);
    sg_tol_result_free(&r);
    sg_tol_mc_close(mcx);
    cli_design_free(cat, sys);
    return rc;
}

int cmd_tolerance(int argc, char **argv)
{
    int rc = tolmpi_start();
    if (rc != CLI_EXIT_OK)
        return rc;
    return tolmpi_end(tolerance_main(argc, argv));
}
