/*
 * cmd_int.h - what the editor's command files share: the tokens of a
 * command line, the checks that report into the status line, the
 * bracketing of a change as one undo step, and every command's handler.
 */
#ifndef SG_ED_CMD_INT_H
#define SG_ED_CMD_INT_H

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../args.h"
#include "../h5rays.h"
#include "../outfile.h"
#include "../plot.h"
#include "../report.h"
#include "cells.h"
#include "cmd.h"
#include "ed.h"
#include "numfmt.h"

#define MAXTOK 16

typedef struct args {
    int n;
    char *v[MAXTOK];         /* unquoted tokens */
    const char *raw[MAXTOK]; /* where each token starts in the line */
    char buf[ED_LINE];
} args;

/* A change that the view and the trace follow. */
#define OK_VIEW (ED_HANDLED | ED_REDRAW | ED_RECOMPUTE)

/* Reports an error in the status line; returns ED_HANDLED | ED_ERROR. */
int ec_fail(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* The words from token i on, as typed. */
void ec_rest_of(const args *a, int i, char *out, size_t n);
/* Whether a has lo to hi arguments after its name; else says usage. */
int ec_need(ed *e, const args *a, int lo, int hi, const char *usage);
int ec_parse_row(ed *e, const char *s, int lo, int hi, int *row);
int ec_parse_num(ed *e, const char *s, const char *what, double *v);
int ec_parse_int(ed *e, const char *s, const char *what, int lo, int hi, int *v);
int ec_parse_switch(ed *e, const char *s, int cur, int *out, const char *what);
int ec_parse_onoff(ed *e, const args *a, int cur, int *out, const char *what);
/* A change to the design, one undo step: ec_begin, the edit, then ec_end
 * with its message (solves follow) or ec_cancel. */
int ec_begin(ed *e, int row);
int ec_end(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
int ec_cancel(ed *e, const char *msg);
/* A wavelength in micrometres, or a spectral line's name (d, F, C ...). */
int ec_parse_um(ed *e, const char *s, double *um);

/* The handlers, by family. */
int c_var(ed *e, args *a);
int c_novar(ed *e, args *a);
int c_opt(ed *e, args *a);
int c_solve(ed *e, args *a);
int c_set(ed *e, args *a);
int c_insert(ed *e, args *a);
int c_delete(ed *e, args *a);
int c_stop(ed *e, args *a);
int c_undo(ed *e, args *a);
int c_redo(ed *e, args *a);
int c_title(ed *e, args *a);
int c_units(ed *e, args *a);
int c_wavelength(ed *e, args *a);
int c_field(ed *e, args *a);
int c_aperture(ed *e, args *a);
int c_aim(ed *e, args *a);
int c_telecentric(ed *e, args *a);
int c_temperature(ed *e, args *a);
int c_thermal(ed *e, args *a);
int c_semidiam(ed *e, args *a);
int c_pressure(ed *e, args *a);
int c_adjust(ed *e, args *a);
int c_glasses(ed *e, args *a);
int c_pick(ed *e, args *a);
int c_open(ed *e, args *a, int bang);
int c_new(ed *e, args *a, int bang);
int c_example(ed *e, args *a, int bang);
int c_save(ed *e, args *a);
int c_save1(ed *e, args *a);
int c_quit(ed *e, args *a, int bang);
int c_wq(ed *e, args *a);
int c_wq1(ed *e, args *a);
int c_recover(ed *e, args *a, int bang);
int c_export_any(ed *e, args *a, int bang);
int c_export(ed *e, args *a);
int c_export1(ed *e, args *a);
int c_print(ed *e, args *a);
int c_ray(ed *e, args *a);
int c_raycoord(ed *e, args *a);
int c_chief(ed *e, args *a);
int c_marginal(ed *e, args *a);
int c_wave(ed *e, args *a);
int c_method(ed *e, args *a);
int c_bits(ed *e, args *a);
int c_digits(ed *e, args *a);
int c_clip(ed *e, args *a);
int c_global(ed *e, args *a);
int c_view(ed *e, args *a);
int c_goto(ed *e, args *a);
int c_bench(ed *e, args *a);
int c_merit(ed *e, args *a);
int c_tol(ed *e, args *a);

#endif
