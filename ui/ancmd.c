/*
 * ancmd.c - the option handling, design loading and output every analysis
 * command shares (ancmd.h).
 */
/* TIOCGWINSZ, for the terminal's width (the build defines _DEFAULT_SOURCE). */
#include <sys/ioctl.h>

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ancmd.h"
#include "args.h"
#include "outfile.h"

void an_cmd_init(an_cmd *a, const char *cmd)
{
    memset(a, 0, sizeof *a);
    a->cmd = cmd;
    a->fmt = AN_FMT_TEXT;
    a->width = 1000;
    a->height = 750;
}

static int parse_format(const char *s, int *fmt)
{
    static const char *const names[] = {"text", "csv", "json", "png", "svg", "pdf"};
    int k;
    for (k = 0; k < 6; k++)
        if (strcmp(s, names[k]) == 0) {
            *fmt = k;
            return CLI_EXIT_OK;
        }
    cli_error("--format: expected text, csv, json, png, svg or pdf, got \"%s\"", s);
    return CLI_EXIT_USAGE;
}

static int parse_size(const an_cmd *a, const char *val, int *w, int *h)
{
    const char *x = strchr(val, 'x');
    char s[32];
    if (!x || (size_t)(x - val) >= sizeof s)
        return cli_usage_error(a->cmd, "--size: expected WIDTHxHEIGHT, got \"%s\"", val);
    memcpy(s, val, (size_t)(x - val));
    s[x - val] = '\0';
    if (args_int(s, 100, 20000, w) != ARGS_OK || args_int(x + 1, 100, 20000, h) != ARGS_OK)
        return cli_usage_error(a->cmd, "--size: expected WIDTHxHEIGHT, each from 100 to "
                                       "20000, got \"%s\"", val);
    return CLI_EXIT_OK;
}

int an_cmd_next(an_cmd *a, cli_iter *it, const cli_opt *opts, const char **val)
{
    int id;
    while ((id = cli_next_opt(it, opts, val)) != -1) {
        switch (id) {
        case 0:
            if (a->design)
                return -cli_usage_error(a->cmd, "unexpected argument \"%s\"", *val);
            a->design = *val;
            break;
        case AN_OPT_FORMAT:
            if (parse_format(*val, &a->fmt))
                return -CLI_EXIT_USAGE;
            break;
        case AN_OPT_OUTPUT:
            a->output = *val;
            break;
        case AN_OPT_SIZE:
            if (parse_size(a, *val, &a->width, &a->height))
                return -CLI_EXIT_USAGE;
            a->size_given = 1;
            break;
        default:
            return id;
        }
    }
    return -1;
}

int an_cmd_load(an_cmd *a)
{
    if (!a->design)
        return cli_usage_error(a->cmd, "missing DESIGN.json");
    if (a->fmt >= AN_FMT_PNG && (!a->output || strcmp(a->output, "-") == 0) &&
        isatty(STDOUT_FILENO))
        return cli_usage_error(a->cmd, "a %s picture needs -o FILE (standard output is a "
                                       "terminal)",
                               a->fmt == AN_FMT_PNG ? "PNG" : a->fmt == AN_FMT_SVG ? "SVG" : "PDF");
    return cli_load_design(a->design, &a->cat, &a->sys);
}

int an_cmd_engine_error(const an_cmd *a, const sg_diag *d, int rc)
{
    cli_print_diag(a->design, d, rc);
    rc = cli_exit_for(rc);
    return rc == CLI_EXIT_OK ? CLI_EXIT_INTERNAL : rc;
}

int an_terminal_width(FILE *f)
{
    const char *cols = getenv("COLUMNS");
    struct winsize ws;
    int w = 80;
    long c;
    /* COLUMNS first (a user's choice), then the terminal's own width. */
    if (cols && args_long(cols, 40, 1000, &c) == ARGS_OK)
        w = (int)c;
    else if (ioctl(fileno(f), TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 40)
        w = ws.ws_col;
    return w > 160 ? 160 : w;
}

int an_terminal_picture(const plot_figure *fig, FILE *f, int colour)
{
    plot_grid g;
    int w = an_terminal_width(f), h, rc;
    h = fig->npanel > 2 ? 40 : 24;
    if (plot_grid_init(&g, w - 1, h))
        return -1;
    plot_draw_cells(fig, &g, 0, 0, w - 1, h);
    fputc('\n', f);
    rc = plot_grid_print(&g, f, colour);
    plot_grid_free(&g);
    return rc;
}

int an_cmd_write(const an_cmd *a, const an_writer *w)
{
    const char *where = a->output && strcmp(a->output, "-") ? a->output : "standard output";
    plot_figure fig;
    outfile of;
    int err, pic, have_fig = 0, rc = CLI_EXIT_OK;
    if (cli_output_is_input(a->output))
        return CLI_EXIT_FILE;
    if ((err = outfile_open(&of, a->output && strcmp(a->output, "-") ? a->output : NULL,
                            stdout)) != 0) {
        cli_error("%s: %s", a->output, strerror(err));
        return CLI_EXIT_FILE;
    }
    pic = a->fmt >= AN_FMT_PNG ||
          (a->fmt == AN_FMT_TEXT && w->fig && (a->text_picture || isatty(fileno(of.f))));
    if (pic) {
        if (!w->fig) {
            cli_error("%s: no picture of this analysis", a->cmd);
            outfile_abort(&of);
            return CLI_EXIT_USAGE;
        }
        have_fig = 1;
        if (w->fig(w->ctx, &fig))
            goto oom;
    }
    if (a->fmt >= AN_FMT_PNG) {
        char msg[256];
        int wd = a->width, ht = a->height, mw, mh;
        if (!a->size_given) {
            /* The default size grows to hold every panel (nine fields' fans). */
            plot_min_size(&fig, wd, &mw, &mh);
            wd = mw > wd ? mw : wd;
            ht = mh > ht ? mh : ht;
        }
        if (plot_write(&fig, a->fmt - AN_FMT_PNG, wd, ht, of.f, msg, sizeof msg)) {
            cli_error("%s: %s", where, msg);
            outfile_abort(&of);
            rc = CLI_EXIT_FILE;
            goto done;
        }
    } else {
        if (w->text(w->ctx, of.f, a->fmt))
            goto oom;
        if (pic && an_terminal_picture(&fig, of.f, plot_use_colour(of.f)))
            goto oom;
    }
    if ((err = outfile_commit(&of)) != 0) {
        cli_error("%s: %s", where, strerror(err));
        rc = CLI_EXIT_FILE;
    }
    goto done;
oom:
    cli_error("out of memory");
    outfile_abort(&of);
    rc = CLI_EXIT_INTERNAL;
done:
    if (have_fig)
        plot_figure_free(&fig);
    return rc;
}

void an_cmd_free(an_cmd *a)
{
    cli_design_free(a->cat, a->sys);
    a->cat = NULL;
    a->sys = NULL;
}
