/* optimize.c - "sagitta merit" (every row of a design's merit function)
 * and "sagitta optimize" (damped least squares on its variables). */
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "report.h"

static void merit_help(FILE *f)
{
    fputs(
"Usage: sagitta merit DESIGN.json [--format text|json|csv]\n"
"Print every row of the design's merit function (its \"merit\" object):\n"
"number, type, parameters, target, weight, value and contribution (%), then\n"
"the merit, MF^2 = sum w (v - t)^2 / sum w.  See sagitta(1), OPTIMIZATION.\n"
"\n"
"Options:\n"
"  --format FMT             text (default), json or csv\n"
"  -h, --help               show this help\n", f);
}

static void optimize_help(FILE *f)
{
    fputs(
"Usage: sagitta optimize DESIGN.json -o OUT.json [--cycles N] [--threads N] [--force]\n"
"                        [--global SECONDS [--starts N] [--seed N]]\n"
"Damped least squares (trust-region Levenberg-Marquardt) on the design's\n"
"variables (solves of type \"variable\") against its merit function; writes\n"
"the best design to OUT.json, also when stopped by Ctrl-C.  One line per\n"
"cycle: merit, step, time.  See sagitta(1), OPTIMIZATION.\n"
"\n"
"Options:\n"
"  -o, --output FILE        the optimized design (required; never the input)\n"
"  --cycles N               at most N cycles (default: until converged, 500)\n"
"  --threads N              threads for the derivatives (default: every core)\n"
"  --force                  overwrite OUT.json if it exists\n"
"  --global SECONDS         multi-start damped least squares from a Halton set\n"
"                           inside the variables' min and max, keeping the best\n"
"  --starts N               at most N starts (the design's own the first)\n"
"  --seed N                 the Halton set from index N + 1 (default 0)\n"
"  -h, --help               show this help\n", f);
}

/* The parameters an operand row shows: its type's keys and values. */
static void row_params(const sg_system *sys, const sg_merit_row *r, char *buf, size_t n)
{
    const sg_operand *o;
    const char *keys[6];
    double dv[4];
    size_t m = 0;
    int k;
    buf[0] = '\0';
    if (r->row > sys->merit.nop) {
        snprintf(buf, n, "default");
        return;
    }
    o = &sys->merit.op[r->row - 1];
    sg_op_keys(o->type, keys);
    dv[0] = o->hx;
    dv[1] = o->hy;
    dv[2] = o->px;
    dv[3] = o->py;
    if (keys[0])
        m += (size_t)snprintf(buf + m, n - m, "%s=%d ", keys[0], o->i1);
    if (m < n && keys[1])
        m += (size_t)snprintf(buf + m, n - m, "%s=%d ", keys[1], o->i2);
    for (k = 0; k < 4; k++)
        if (m < n && keys[2 + k])
            m += (size_t)snprintf(buf + m, n - m, "%s=%g ", keys[2 + k], dv[k]);
    if (m > 0 && m < n)
        buf[m - 1] = '\0';
}


int cmd_merit(int argc, char **argv)
{
    cli_iter it;
    const char *design = NULL;
    int rc, i, fmt = REPORT_TEXT;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_merit_result r;
    sg_diag d;
    char par[128];
    const cli_opt opts[] = {CLI_OPT_HELP, CLI_OPT_FORMAT_CSV(fmt), CLI_END};

    cli_iter_init(&it, "merit", argc, argv);
    rc = cli_parse(&it, opts, &design, merit_help);
    if (rc != CLI_EXIT_OK)
        return rc == CLI_DONE ? CLI_EXIT_OK : rc;
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    sg_diag_clear(&d);
    rc = sg_merit_eval(sys, cat, &r, &d);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
        goto done;
    }
    if (fmt == REPORT_JSON) {
        printf("{\"merit\": %.17g, \"operands\": [", r.merit);
        for (i = 0; i < r.nrow; i++) {
            const sg_merit_row *w = &r.row[i];
            printf("%s\n  {\"row\": %d, \"type\": \"%s\", \"target\": %.17g, \"weight\": %.17g, "
                   "\"value\": %.17g, \"contribution\": %.17g}", i ? "," : "", w->row,
                   sg_op_name(w->type), w->target, w->weight, w->value, w->contribution);
        }
        printf("\n]}\n");
    } else if (fmt == REPORT_CSV) {
        printf("row,type,parameters,target,weight,value,contribution\n");
        for (i = 0; i < r.nrow; i++) {
            const sg_merit_row *w = &r.row[i];
            row_params(sys, w, par, sizeof par);
            printf("%d,%s,%s,%.17g,%.17g,%.17g,%.17g\n", w->row, sg_op_name(w->type), par,
                   w->target, w->weight, w->value, w->contribution);
        }
        printf("merit,,,,,%.17g,100\n", r.merit);
    } else {
        printf("%5s %-5s %-36s %14s %12s %22s %8s\n", "Row", "Type", "Parameters", "Target",
               "Weight", "Value", "Contrib%");
        for (i = 0; i < r.nrow; i++) {
            const sg_merit_row *w = &r.row[i];
            row_params(sys, w, par, sizeof par);
            printf("%5d %-5s %-36s %14.8g %12.6g %22.15g %8.4f\n", w->row, sg_op_name(w->type),
                   par, w->target, w->weight, w->value, w->contribution);
        }
        printf("Merit function: %.15g\n", r.merit);
    }
    sg_merit_result_free(&r);
    rc = CLI_EXIT_OK;
done:
    cli_design_free(cat, sys);
    return rc;
}

static volatile int stop_flag;

static void on_sigint(int sig)
{
    (void)sig;
    stop_flag = 1;
}

static int progress(void *ctx, int cycle, double merit, double step, double seconds)
{
    (void)ctx;
    printf("cycle %4d  merit %-22.15g  step %-12.4g  time %.3f s\n", cycle, merit, step, seconds);
    fflush(stdout);
    return 0;
}

/* The global search's line: one a start. */
static int progress_global(void *ctx, int start, double merit, double step, double seconds)
{
    (void)ctx;
    (void)step;
    printf("start %4d  best merit %-22.15g  time %.3f s\n", start, merit, seconds);
    fflush(stdout);
    return 0;
}


/* Whether a and b name the same file (both exist). */
static int same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

int cmd_optimize(int argc, char **argv)
{
    cli_iter it;
    const char *design = NULL, *output = NULL;
    int rc, force = 0;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_opt_opts o;
    sg_opt_result res;
    struct sigaction sa, old;
    struct stat st;
    sg_diag d;

    sg_opt_opts_init(&o);
    {
        double gsec = 0.0;
        int seed = -1;
        const cli_opt opts[] = {CLI_OPT_HELP,
                                CLI_OPT_OUTPUT(output),
                                CLI_OPT_INT("--cycles", 0, o.cycles, 1, 1000000),
                                CLI_OPT_INT("--threads", 0, o.nthreads, 1, 16),
                                CLI_OPT_FLAG("--force", 0, force),
                                CLI_OPT_POS("--global", gsec, "seconds", " of seconds"),
                                CLI_OPT_INT("--starts", 0, o.global_starts, 1, 100000000),
                                CLI_OPT_INT("--seed", 0, seed, 0, 1000000000),
                                CLI_END};
        cli_iter_init(&it, "optimize", argc, argv);
        rc = cli_parse(&it, opts, &design, optimize_help);
        if (rc != CLI_EXIT_OK)
            return rc == CLI_DONE ? CLI_EXIT_OK : rc;
        if (gsec > 1e6)
            return cli_usage_error("optimize", "--global %g: at most 1e6 seconds", gsec);
        if (gsec > 0.0)
            o.global_seconds = gsec;
        if (seed >= 0)
            o.seed = (unsigned)seed;
    }
    if (!output)
        return cli_usage_error("optimize", "missing -o OUT.json (the optimized design)");
    if ((o.global_starts || o.seed) && !(o.global_seconds > 0.0))
        return cli_usage_error("optimize", "--starts and --seed belong to --global SECONDS");
    if (strcmp(output, design) == 0 || same_file(output, design))
        return cli_usage_error("optimize", "-o %s is the input design; write the result to "
                               "another file", output);
    if (!force && stat(output, &st) == 0)
        return cli_usage_error("optimize", "%s exists; use --force to overwrite it", output);
    if (o.nthreads == 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        o.nthreads = n < 1 ? 1 : n > 16 ? 16 : (int)n;
    }
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old);
    stop_flag = 0;
    o.stop = &stop_flag;
    o.progress = o.global_seconds > 0.0 ? progress_global : progress;
    sg_diag_clear(&d);
    rc = sg_optimize(sys, cat, &o, &res, &d);
    sigaction(SIGINT, &old, NULL);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
        goto done;
    }
    sg_diag_clear(&d);
    if ((rc = sg_design_save(sys, output, &d)) != SG_OK) {
        cli_error("%s", d.msg[0] ? d.msg : sg_strerror(rc));
        rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_FILE;
        goto done;
    }
    printf("%s after %d cycles: merit %.15g (from %.15g)\n",
           res.stopped ? "Stopped" : res.converged ? "Converged" : "Stopped at the cycle limit",
           res.cycles, res.merit, res.merit0);
    printf("Saved: %s\n", output);
    rc = CLI_EXIT_OK;
done:
    cli_design_free(cat, sys);
    return rc;
}
