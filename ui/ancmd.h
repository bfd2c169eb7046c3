/*
 * ancmd.h - what the analysis commands (spot, fan, layout, wavefront,
 * seidel, fieldcurve) share: the design argument, --format
 * text|csv|json|png|svg|pdf, -o FILE and --size WxH, loading the design,
 * and writing the result through outfile: a picture file, or text, CSV or
 * JSON, with a braille picture after text that goes to a terminal.
 */
#ifndef SG_UI_ANCMD_H
#define SG_UI_ANCMD_H

#include <stdio.h>

#include "cli.h"
#include "plot.h"

enum { AN_FMT_TEXT, AN_FMT_CSV, AN_FMT_JSON, AN_FMT_PNG, AN_FMT_SVG, AN_FMT_PDF };

/* Option ids the shared options take; a command's own ids stay below. */
enum { AN_OPT_HELP = 1000, AN_OPT_FORMAT, AN_OPT_OUTPUT, AN_OPT_SIZE };

/* The shared rows of a command's option table. */
#define AN_COMMON_OPTS                                                                      \
    CLI_ID("--help", 'h', 0, AN_OPT_HELP), CLI_ID("--format", 0, 1, AN_OPT_FORMAT),                 \
        CLI_ID("--output", 'o', 1, AN_OPT_OUTPUT), CLI_ID("--size", 0, 1, AN_OPT_SIZE)

/* The shared lines of a command's help. */
#define AN_COMMON_HELP                                                                      \
    "  --format F         text (default), csv, json, png, svg or pdf\n"                     \
    "  -o, --output FILE  write to FILE (default: standard output)\n"                       \
    "  --size WxH         picture size in pixels (png) or points (svg, pdf);\n"             \
    "                     default 1000x750\n"

typedef struct an_cmd {
    const char *cmd;    /* "spot", for messages */
    const char *design; /* the path given */
    const char *output; /* -o, or NULL */
    int fmt;            /* AN_FMT_* */
    int width, height;  /* --size */
    int size_given;     /* --size was given (else a picture grows to hold its panels) */
    /* Text carries its picture even when it does not go to a terminal. */
    int text_picture;
    sg_catalog *cat;
    sg_system *sys;
} an_cmd;

void an_cmd_init(an_cmd *a, const char *cmd);
/* The next option of the command's table (which includes AN_COMMON_OPTS).
 * The shared ones are handled here; --help, the command's own options and
 * their values are returned as by cli_next_opt; -1 at the end;
 * -CLI_EXIT_USAGE after an error was printed. */
int an_cmd_next(an_cmd *a, cli_iter *it, const cli_opt *opts, const char **val);
/* After the options: the design was given, a picture is not bound for a
 * terminal; then loads the design into a->cat, a->sys.  Exit status. */
int an_cmd_load(an_cmd *a);
/* Prints an engine failure and returns its exit status (never OK). */
int an_cmd_engine_error(const an_cmd *a, const sg_diag *d, int rc);

/* How a command writes its result: fig fills a figure (plot_figure_init
 * is its job; 0, or -1 out of memory); text writes text, CSV or JSON
 * (fmt) to f (0, or -1 out of memory). */
typedef struct an_writer {
    int (*fig)(void *ctx, plot_figure *f);
    int (*text)(void *ctx, FILE *f, int fmt);
    void *ctx;
} an_writer;
/* Writes to -o or standard output; the exit status. */
int an_cmd_write(const an_cmd *a, const an_writer *w);
void an_cmd_free(an_cmd *a);

/* The width pictures on f take: COLUMNS, else the terminal's (80 when
 * neither tells), from 40 to 160. */
int an_terminal_width(FILE *f);
/* The braille picture of fig for a terminal of the width COLUMNS or the
 * terminal gives (at most 160), after a blank line; 0, or -1. */
int an_terminal_picture(const plot_figure *fig, FILE *f, int colour);

#endif
