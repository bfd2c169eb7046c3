/*
 * cli.h - the command-line subcommands of sagitta and what they share.
 *
 * A subcommand is a function int cmd_NAME(int argc, char **argv) that gets
 * argv[0] == "NAME" and returns the process exit status; main.c lists them
 * in one table.  The helpers below give every subcommand the same option
 * syntax, the same messages and the same exit codes.
 */
#ifndef SG_UI_CLI_H
#define SG_UI_CLI_H

#include <stdio.h>

#include "sagitta.h"

/* Exit statuses, documented in man/sagitta.1 (EXIT STATUS). */
enum {
    CLI_EXIT_OK = 0,       /* success; a ray that misses or TIRs is a result */
    CLI_EXIT_USAGE = 2,    /* bad command line or option value */
    CLI_EXIT_FILE = 3,     /* cannot read, parse or write a file */
    CLI_EXIT_DESIGN = 4,   /* the design cannot be traced */
    CLI_EXIT_INTERNAL = 5, /* out of memory or internal error */
    CLI_EXIT_VERIFY = 6    /* reserved for "sagitta verify" */
};

typedef struct cli_command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary; /* one line for "sagitta --help" */
} cli_command;

int cmd_trace(int argc, char **argv);
int cmd_paraxial(int argc, char **argv);
/* The shortest %g text that reads back as v, in buf. */
const char *cli_shortest(double v, char *buf, size_t n);
int cmd_semidiam(int argc, char **argv);
int cmd_vignetting(int argc, char **argv);
int cmd_thermal(int argc, char **argv); /* thermal.c */
int cmd_merit(int argc, char **argv);    /* optimize.c */
int cmd_optimize(int argc, char **argv); /* optimize.c */
int cmd_tolerance(int argc, char **argv); /* tolerance.c */
int cmd_psf(int argc, char **argv);     /* diffraction.c */
int cmd_mtf(int argc, char **argv);     /* diffraction.c */
int cmd_throughfocus(int argc, char **argv); /* diffraction.c */
int cmd_encircled(int argc, char **argv); /* diffraction.c */
/* Further subcommands live in their own files. */
int cmd_verify(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_import(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_spot(int argc, char **argv);
int cmd_fan(int argc, char **argv);
int cmd_wavefront(int argc, char **argv);
int cmd_layout(int argc, char **argv);
int cmd_seidel(int argc, char **argv);     /* aberration.c */
int cmd_fieldcurve(int argc, char **argv); /* aberration.c */

/* "sagitta: " + message + newline on stderr. */
void cli_error(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* "sagitta: warning: " + message + newline on stderr. */
void cli_warn(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* Prints the warnings an sg_diag collected, prefixed by where (may be NULL). */
void cli_print_warnings(const sg_diag *d, const char *where);
/* Prints an engine failure rc with d's message, adding the file name path
 * when the message does not already carry it. */
void cli_print_diag(const char *path, const sg_diag *d, int rc);
/* Prints "sagitta: CMD: MESSAGE" and the hint to run CMD --help; returns
 * CLI_EXIT_USAGE. */
int cli_usage_error(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* ---- options ---------------------------------------------------------- */

/* A long option whose value may be left out: "--name=N", or "--name N"
 * when N is a whole number (so "--global 3" and "--global design.json"
 * both read as meant); *val is NULL when it is left out. */
#define CLI_OPT_NUM 2

/* What cli_next_opt stores for a row that has a dest. */
enum {
    CLI_INT = 1, /* int *dest, from lo to hi */
    CLI_FLAG,    /* int *dest set to 1; the row takes no value */
    CLI_TEXT,    /* const char **dest: the value as given */
    CLI_WORD,    /* int *dest: values[k] (or k) for the k-th of words "a|b|c" */
    CLI_NUMS,    /* double *dest: lo comma-separated numbers named by words */
    CLI_POS      /* double *dest: one positive finite number named by words, in unit */
};

typedef struct cli_opt {
    const char *name; /* "--ray", or NULL to end the table */
    char shortc;      /* 'o' for -o, or 0 */
    int has_arg;      /* 0 none, 1 one, CLI_OPT_NUM an optional number */
    int id;           /* positive; returned by cli_next_opt */
    /* A row with a dest is stored by cli_next_opt itself, which goes on to
     * the next argument: a command's switch keeps only what needs logic of
     * its own, and every command reads a value with the same message. */
    int kind;          /* CLI_INT ... CLI_NUMS */
    void *dest;
    int lo, hi;        /* CLI_INT: the range; CLI_NUMS: lo numbers */
    const char *words; /* CLI_WORD: "chief|centroid"; CLI_NUMS: their names */
    const int *values; /* CLI_WORD: each word's value (NULL: its index) */
    const char *only;  /* the commands the row is for ("spot"), NULL: all */
    const char *unit;  /* CLI_POS: " of micrometres", for messages */
} cli_opt;

/* A row the command's switch handles, and the table's end. */
#define CLI_ID(name, sc, has_arg, id) {name, sc, has_arg, id, 0, NULL, 0, 0, NULL, NULL, NULL, NULL}
#define CLI_END {NULL, 0, 0, 0, 0, NULL, 0, 0, NULL, NULL, NULL, NULL}
/* Table rows: an option stored in a local, with the value's checks. */
#define CLI_OPT_INT(name, sc, var, lo, hi) {name, sc, 1, 1, CLI_INT, &(var), lo, hi, NULL, NULL, NULL, NULL}
#define CLI_OPT_FLAG(name, sc, var) {name, sc, 0, 1, CLI_FLAG, &(var), 0, 0, NULL, NULL, NULL, NULL}
#define CLI_OPT_TEXT(name, sc, var) {name, sc, 1, 1, CLI_TEXT, &(var), 0, 0, NULL, NULL, NULL, NULL}
#define CLI_OPT_WORD(name, var, words, values) {name, 0, 1, 1, CLI_WORD, &(var), 0, 0, words, values, NULL, NULL}
#define CLI_OPT_NUMS(name, var, n, what) {name, 0, 1, 1, CLI_NUMS, var, n, 0, what, NULL, NULL, NULL}
#define CLI_OPT_POS(name, var, what, unit) {name, 0, 1, 1, CLI_POS, &(var), 1, 0, what, NULL, NULL, unit}
#define CLI_OPT_POS_FOR(name, var, what, unit, only) {name, 0, 1, 1, CLI_POS, &(var), 1, 0, what, NULL, only, unit}
/* Rows for some of the commands that share a table: "--grid is for wavefront". */
#define CLI_OPT_INT_FOR(name, var, lo, hi, only) {name, 0, 1, 1, CLI_INT, &(var), lo, hi, NULL, NULL, only, NULL}
#define CLI_OPT_FLAG_FOR(name, var, only) {name, 0, 0, 1, CLI_FLAG, &(var), 0, 0, NULL, NULL, only, NULL}
#define CLI_OPT_WORD_FOR(name, var, words, values, only) {name, 0, 1, 1, CLI_WORD, &(var), 0, 0, words, values, only, NULL}
/* --method precise|classic|mpfr, into an int holding an sg_method. */
#define CLI_OPT_METHOD(var) CLI_OPT_WORD("--method", var, "precise|classic|mpfr", cli_method_values)
extern const int cli_method_values[3];
/* --format text|json, or text|csv|json, into an int holding a report_fmt. */
#define CLI_OPT_FORMAT(var) CLI_OPT_WORD("--format", var, "text|json", cli_format_values)
#define CLI_OPT_FORMAT_CSV(var) CLI_OPT_WORD("--format", var, "text|csv|json", cli_format_csv_values)
extern const int cli_format_values[2], cli_format_csv_values[3];
/* -h, --help, which cli_parse answers with the command's help. */
enum { CLI_HELP = 999 };
#define CLI_OPT_HELP CLI_ID("--help", 'h', 0, CLI_HELP)
/* -o, --output FILE. */
#define CLI_OPT_OUTPUT(var) CLI_OPT_TEXT("--output", 'o', var)

typedef struct cli_iter {
    int argc;
    char **argv;
    int i;
    int only_positional; /* after "--" */
    const char *cmd;
    char opt[64]; /* the last option as typed, for messages */
} cli_iter;

void cli_iter_init(cli_iter *it, const char *cmd, int argc, char **argv);
/* Returns the id of the next option, with its value in *val when it takes
 * one; 0 for a positional argument (in *val); -1 at the end; or
 * -CLI_EXIT_USAGE after printing the error.  Accepts "--name value",
 * "--name=value", "-x value", "-xvalue" and "--" before positionals. */
int cli_next_opt(cli_iter *it, const cli_opt *opts, const char **val);

/* Reads the whole command line of a command whose table is declarative
 * but for CLI_OPT_HELP: one positional DESIGN argument goes to *design
 * (missing or a second one is an error).  Returns CLI_EXIT_OK to go on,
 * CLI_EXIT_USAGE after a message, or CLI_DONE after printing help. */
enum { CLI_DONE = -1 };
int cli_parse(cli_iter *it, const cli_opt *opts, const char **design, void (*help)(FILE *));

/* Option values.  Each prints a message naming the option and returns
 * CLI_EXIT_USAGE on a bad value, CLI_EXIT_OK otherwise. */
int cli_int_value(const char *opt, const char *s, int lo, int hi, int *out);
/* Exactly n comma-separated finite numbers; what names them, e.g.
 * "Hx,Hy,Px,Py"; item names are taken from it for messages. */
int cli_doubles_value(const char *opt, const char *s, int n, const char *what,
                      double *out);

/* --format: "text" or "json", and "csv" too when allow_csv; sets *fmt to a
 * report_fmt value. */
int cli_format_value(const char *s, int allow_csv, int *fmt);
/* --method: precise, classic or mpfr; sets *method to an sg_method. */
int cli_method_value(const char *s, int *method);

/* ---- designs ---------------------------------------------------------- */

/* Loads the default catalog, the design at path and validates it.  Returns
 * the exit status; on success *cat and *sys are set (free them with
 * cli_design_free), otherwise both are NULL and a message was printed. */
int cli_load_design(const char *path, sg_catalog **cat, sg_system **sys);
/* cli_load_design for a .zmx file read with glass substitutions
 * (sagitta import --substitute); sub NULL: cli_load_design. */
int cli_load_design_subst(const char *path, const sg_zmx_subst *sub, sg_catalog **catp,
                          sg_system **sysp);
void cli_design_free(sg_catalog *cat, sg_system *sys);
/* Exit status for an engine error while preparing or running a trace. */
int cli_exit_for(int err);
/* Checks a 1-based --wave against the design (0 means "not given") and
 * returns the 0-based index in *wave0, or prints and returns CLI_EXIT_USAGE. */
int cli_check_wave(const char *path, const sg_system *sys, int wave1, int *wave0);

/* Remembers a file the command reads (its design, its ray list), so that
 * no output replaces it. */
void cli_note_input(const char *path);
/* Nonzero, after a message naming it, when path is a file the command
 * reads (the same device and inode, whatever the name): an output never
 * replaces its own input.  "-" and NULL (standard output) are never one. */
int cli_output_is_input(const char *path);

/* Opens the output ("-" or NULL is standard output).  Returns NULL after
 * printing a message; refuses an input (cli_output_is_input). */
FILE *cli_open_output(const char *path);
/* Closes an output opened by cli_open_output; returns the exit status. */
int cli_close_output(FILE *f, const char *path);

#endif
