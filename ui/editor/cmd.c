/*
 * cmd.c - the one command path.  Keys, the ':' line and batch scripts all
 * end up here, so every edit can be tested without a screen.
 */
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

/* Splits line into blank-separated tokens; "..." groups words and \" or \\
 * escape inside quotes.  Returns 0, or -1 for an unterminated quote or too
 * many tokens. */
static int tokenize(const char *line, args *a)
{
    const char *p = line;
    char *o = a->buf, *end = a->buf + sizeof a->buf - 1;
    a->n = 0;
    for (;;) {
        while (isspace((unsigned char)*p))
            p++;
        if (!*p)
            return 0;
        if (a->n == MAXTOK)
            return -1;
        a->raw[a->n] = p;
        a->v[a->n++] = o;
        while (*p && !isspace((unsigned char)*p)) {
            if (*p == '"') {
                p++;
                while (*p && *p != '"') {
                    if (*p == '\\' && (p[1] == '"' || p[1] == '\\'))
                        p++;
                    if (o < end)
                        *o++ = *p;
                    p++;
                }
                if (*p != '"')
                    return -1;
                p++;
            } else {
                if (o < end)
                    *o++ = *p;
                p++;
            }
        }
        *o++ = '\0';
        if (o >= end)
            return -1;
    }
}

void cmd_quote(const char *s, char *buf, size_t n)
{
    size_t k = 0;
    int plain = *s != '\0';
    const char *p;
    for (p = s; *p; p++)
        if (isspace((unsigned char)*p) || *p == '"' || *p == '\\' || *p == '#')
            plain = 0;
    if (plain) {
        snprintf(buf, n, "%s", s);
        return;
    }
    if (n < 3) {
        if (n)
            buf[0] = '\0';
        return;
    }
    buf[k++] = '"';
    for (p = s; *p && k + 3 < n; p++) {
        if (*p == '"' || *p == '\\')
            buf[k++] = '\\';
        buf[k++] = *p;
    }
    buf[k++] = '"';
    buf[k] = '\0';
}

/* The text after token i: one quoted token if it is just that, else the
 * raw text with trailing blanks removed. */
static void rest_of(const args *a, int i, char *out, size_t n)
{
    const char *r = a->raw[i];
    size_t len;
    if (i == a->n - 1 && *r == '"') {
        snprintf(out, n, "%s", a->v[i]);
        return;
    }
    len = strlen(r);
    while (len > 0 && isspace((unsigned char)r[len - 1]))
        len--;
    if (len >= n)
        len = n - 1;
    memcpy(out, r, len);
    out[len] = '\0';
}

static int fail(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int fail(ed *e, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    e->msg_err = 1;
    return ED_HANDLED | ED_ERROR | ED_REDRAW;
}

#define OK_VIEW (ED_HANDLED | ED_REDRAW | ED_RECOMPUTE)

static int need(ed *e, const args *a, int lo, int hi, const char *usage)
{
    if (a->n - 1 < lo || a->n - 1 > hi) {
        fail(e, "usage: %s", usage);
        return 0;
    }
    return 1;
}

/* A surface number, or obj / ima / stop / "." (the cursor's row). */
static int parse_row(ed *e, const char *s, int lo, int hi, int *row)
{
    const sg_system *sys = e->doc.sys;
    int r, rc;
    if (strcasecmp(s, "obj") == 0)
        r = 0;
    else if (strcasecmp(s, "ima") == 0 || strcasecmp(s, "img") == 0 ||
             strcasecmp(s, "image") == 0)
        r = sys->nsurf - 1;
    else if (strcasecmp(s, "stop") == 0 || strcasecmp(s, "sto") == 0)
        r = sys->stop;
    else if (strcmp(s, ".") == 0)
        r = e->row;
    else if ((rc = args_int(s, INT_MIN, INT_MAX, &r)) != ARGS_OK) {
        fail(e, "\"%s\" is not a surface number", s);
        return 0;
    }
    if (r < lo || r > hi) {
        if (lo > hi)
            fail(e, "the design has too few surfaces");
        else
            fail(e, "surface %d is not one of %d to %d", r, lo, hi);
        return 0;
    }
    *row = r;
    return 1;
}

static int parse_num(ed *e, const char *s, const char *what, double *v)
{
    int rc = args_double(s, 0, v);
    if (rc != ARGS_OK) {
        fail(e, "%s: \"%s\": %s", what, s, args_strerror(rc));
        return 0;
    }
    return 1;
}

static int parse_int(ed *e, const char *s, const char *what, int lo, int hi, int *v)
{
    int rc = args_int(s, lo, hi, v);
    if (rc != ARGS_OK) {
        if (rc == ARGS_RANGE)
            fail(e, "%s: %s is not in %d to %d", what, s, lo, hi);
        else
            fail(e, "%s: \"%s\": %s", what, s, args_strerror(rc));
        return 0;
    }
    return 1;
}

/* on, off or toggle (also the default when s is NULL). */
static int parse_switch(ed *e, const char *s, int cur, int *out, const char *what)
{
    if (!s || strcasecmp(s, "toggle") == 0) {
        *out = !cur;
        return 1;
    }
    if (strcasecmp(s, "on") == 0 || strcmp(s, "1") == 0 || strcasecmp(s, "yes") == 0) {
        *out = 1;
        return 1;
    }
    if (strcasecmp(s, "off") == 0 || strcmp(s, "0") == 0 || strcasecmp(s, "no") == 0) {
        *out = 0;
        return 1;
    }
    fail(e, "%s: \"%s\" is not on, off or toggle", what, s);
    return 0;
}

static int parse_onoff(ed *e, const args *a, int cur, int *out, const char *what)
{
    return parse_switch(e, a->n > 1 ? a->v[1] : NULL, cur, out, what);
}

/* ------------------------------------------------------------------------
 * Changes to the design: each is one undo step.
 * ------------------------------------------------------------------------ */

static int begin(ed *e, int row)
{
    if (doc_begin(&e->doc, row) != SG_EOK) {
        fail(e, "out of memory: the change was not made");
        return 0;
    }
    return 1;
}

/* Ends a change and reports it; "unchanged" when the value was the same. */
static int end(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int end(ed *e, const char *fmt, ...)
{
    va_list ap;
    sg_diag d;
    int changed, src;
    /* Solved values follow every edit, in the same undo step. */
    sg_diag_clear(&d);
    src = sg_system_apply_solves(e->doc.sys, e->cat, &d);
    changed = doc_end(&e->doc);
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    if (!changed) {
        size_t len = strlen(e->msg);
        snprintf(e->msg + len, sizeof e->msg - len, " (unchanged)");
    }
    e->msg_err = 0;
    if (src != SG_OK) {
        size_t len = strlen(e->msg);
        snprintf(e->msg + len, sizeof e->msg - len, "; solves: %s", d.msg);
        e->msg_err = 1;
    }
    e->dirty = 1;
    return OK_VIEW;
}

static int cancel(ed *e, const char *msg)
{
    doc_cancel(&e->doc);
    return fail(e, "%s", msg);
}

static int c_set(ed *e, args *a)
{
    char val[ED_LINE], err[ED_MSG], info[256], shown[ED_LINE];
    int row, col, rc;
    if (!need(e, a, 2, MAXTOK, "set SURFACE COLUMN VALUE"))
        return ED_HANDLED | ED_ERROR;
    if (!parse_row(e, a->v[1], 0, e->doc.sys->nsurf - 1, &row))
        return ED_HANDLED | ED_ERROR;
    col = cell_parse_name(a->v[2]);
    if (strcasecmp(a->v[2], "fixed") == 0) {
        int on;
        if (a->n > 4)
            return fail(e, "usage: set SURFACE fixed on|off|toggle");
        if (!parse_switch(e, a->n > 3 ? a->v[3] : NULL, e->doc.sys->surf[row].sd_fixed, &on,
                          "fixed"))
            return ED_HANDLED | ED_ERROR;
        if (!begin(e, row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->surf[row].sd_fixed = on;
        e->row = row;
        e->col = COL_SEMI;
        return end(e, "surface %d semi-diameter %s", row, on ? "fixed" : "free");
    }
    if (col < 0)
        return fail(e, "no column \"%s\" (type, comment, radius, thickness, material, "
                       "semi, conic, a2 ... a16, aperture, ap_rmin, ap_rmax, ap_xhalf, "
                       "ap_yhalf, ap_xdec, ap_ydec, norm, zdx, zdy, t1 ..., dx, dy, tx, ty, tz, order, "
                       "after, adx, ady, atx, aty, atz, aorder)", a->v[2]);
    if (a->n > 3)
        rest_of(a, 3, val, sizeof val);
    else
        val[0] = '\0';
    if (!begin(e, row))
        return ED_HANDLED | ED_ERROR;
    rc = cell_set(e->doc.sys, e->cat, row, col, val, err, sizeof err, info, sizeof info);
    if (rc != SG_EOK)
        return cancel(e, err);
    e->row = row;
    e->col = col;
    cell_text(e->doc.sys, row, col, shown, sizeof shown);
    return end(e, "surface %d %s = %s%s%s", row, cell_name(col), shown,
               info[0] ? "; " : "", info);
}

static int c_insert(ed *e, args *a)
{
    int at = e->row < 1 ? 1 : e->row;
    if (!need(e, a, 0, 1, "insert [SURFACE]"))
        return ED_HANDLED | ED_ERROR;
    if (at > e->doc.sys->nsurf - 1)
        at = e->doc.sys->nsurf - 1;
    if (a->n > 1 && !parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 1, &at))
        return ED_HANDLED | ED_ERROR;
    if (e->doc.sys->nsurf >= SG_MAX_SURFACES)
        return fail(e, "a design holds at most %d surfaces", SG_MAX_SURFACES);
    if (!begin(e, at))
        return ED_HANDLED | ED_ERROR;
    if (sg_system_insert(e->doc.sys, at) != SG_EOK)
        return cancel(e, "out of memory: no surface inserted");
    e->row = at;
    return end(e, "inserted surface %d", at);
}

static int c_delete(ed *e, args *a)
{
    int at = e->row;
    if (!need(e, a, 0, 1, "delete [SURFACE]"))
        return ED_HANDLED | ED_ERROR;
    if (e->doc.sys->nsurf <= 3)
        return fail(e, "cannot delete: a design needs an object, a surface and an image");
    if (a->n > 1) {
        if (!parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 2, &at))
            return ED_HANDLED | ED_ERROR;
    } else if (at < 1 || at > e->doc.sys->nsurf - 2) {
        return fail(e, "the object and the image surfaces cannot be deleted");
    }
    if (!begin(e, at))
        return ED_HANDLED | ED_ERROR;
    if (sg_system_delete(e->doc.sys, at) != SG_EOK)
        return cancel(e, "cannot delete that surface");
    e->row = at;
    return end(e, "deleted surface %d", at);
}

static int c_stop(ed *e, args *a)
{
    int at = e->row;
    if (!need(e, a, 0, 1, "stop [SURFACE]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 1) {
        if (!parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 2, &at))
            return ED_HANDLED | ED_ERROR;
    } else if (at < 1 || at > e->doc.sys->nsurf - 2) {
        return fail(e, "the stop must be one of surfaces 1 to %d", e->doc.sys->nsurf - 2);
    }
    if (!begin(e, at))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->stop = at;
    e->row = at;
    return end(e, "surface %d is the stop", at);
}

/* A solve target by name: radius, thickness or conic. */
static int parse_target(ed *e, const char *s, int *t)
{
    for (*t = 0; *t < SG_SOLVE_NTARGETS; (*t)++)
        if (strcasecmp(s, sg_solve_target_name((sg_solve_target)*t)) == 0)
            return 1;
    fail(e, "'%s' is not radius, thickness or conic", s);
    return 0;
}

/* var SURFACE radius|thickness|conic [MIN MAX]: the value becomes a
 * variable of the optimizer, Zemax's V (sagitta-design(5), SOLVES). */
static int c_var(ed *e, args *a)
{
    static const char usage[] = "var SURFACE radius|thickness|conic [MIN MAX]";
    int row, t;
    double lo = -INFINITY, hi = INFINITY;
    sg_solve v;
    if (!need(e, a, 2, 4, usage) || a->n == 4)
        return a->n == 4 ? fail(e, "usage: %s", usage) : (ED_HANDLED | ED_ERROR);
    if (!parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 1, &row) || !parse_target(e, a->v[2], &t))
        return ED_HANDLED | ED_ERROR;
    if (a->n == 5 && (!parse_num(e, a->v[3], "min", &lo) || !parse_num(e, a->v[4], "max", &hi)))
        return ED_HANDLED | ED_ERROR;
    if (lo > hi)
        return fail(e, "var: min %g is above max %g", lo, hi);
    memset(&v, 0, sizeof v);
    v.kind = SG_SOLVE_VARIABLE;
    v.lo = lo;
    v.hi = hi;
    if (!begin(e, row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->surf[row].solve[t] = v;
    e->row = row;
    return end(e, "surface %d: the %s is a variable", row, a->v[2]);
}

/* novar SURFACE radius|thickness|conic, or novar all: clears variables. */
static int c_novar(ed *e, args *a)
{
    sg_system *sys = e->doc.sys;
    int row, t, n = 0;
    if (a->n == 2 && strcasecmp(a->v[1], "all") == 0) {
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        for (row = 0; row < sys->nsurf; row++)
            for (t = 0; t < SG_SOLVE_NTARGETS; t++)
                if (sys->surf[row].solve[t].kind == SG_SOLVE_VARIABLE) {
                    memset(&sys->surf[row].solve[t], 0, sizeof sys->surf[row].solve[t]);
                    n++;
                }
        return end(e, "%d variable%s cleared", n, n == 1 ? "" : "s");
    }
    if (!need(e, a, 2, 2, "novar SURFACE radius|thickness|conic | novar all"))
        return ED_HANDLED | ED_ERROR;
    if (!parse_row(e, a->v[1], 0, sys->nsurf - 1, &row) || !parse_target(e, a->v[2], &t))
        return ED_HANDLED | ED_ERROR;
    if (sys->surf[row].solve[t].kind != SG_SOLVE_VARIABLE)
        return fail(e, "surface %d: the %s is not a variable", row, a->v[2]);
    if (!begin(e, row))
        return ED_HANDLED | ED_ERROR;
    memset(&e->doc.sys->surf[row].solve[t], 0, sizeof e->doc.sys->surf[row].solve[t]);
    e->row = row;
    return end(e, "surface %d: the %s is no longer a variable", row, a->v[2]);
}

/* opt [CYCLES]: damped least squares on the variables against the merit
 * function, as one undoable change. */
static int c_opt(ed *e, args *a)
{
    sg_opt_opts o;
    sg_opt_result res;
    sg_diag d;
    int cycles = 0, rc;
    if (!need(e, a, 0, 1, "opt [CYCLES]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n == 2 && !parse_int(e, a->v[1], "cycles", 1, 1000000, &cycles))
        return ED_HANDLED | ED_ERROR;
    sg_opt_opts_init(&o);
    o.cycles = cycles;
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    sg_diag_clear(&d);
    rc = sg_optimize(e->doc.sys, e->cat, &o, &res, &d);
    if (rc != SG_OK)
        return cancel(e, d.msg);
    return end(e, "optimized: merit %.6g (from %.6g) after %d cycle%s%s", res.merit, res.merit0,
               res.cycles, res.cycles == 1 ? "" : "s", res.converged ? ", converged" : "");
}

/* solve SURFACE radius|thickness|conic TYPE [ARGS]: sets or clears a solve
 * (sagitta-design(5), Solves and pickups). */
static int c_solve(ed *e, args *a)
{
    static const char usage[] = "solve SURFACE radius|thickness|conic none|pickup FROM [SCALE "
                                "[OFFSET]]|curvature_pickup FROM [SCALE [OFFSET]]|"
                                "marginal_height H|chief_height H|position FROM L|"
                                "marginal_angle U|fnum F|variable [MIN MAX]";
    sg_solve v;
    sg_diag d;
    int row, t, k, rc;
    double x;
    if (!need(e, a, 3, 6, usage))
        return ED_HANDLED | ED_ERROR;
    if (!parse_row(e, a->v[1], 0, e->doc.sys->nsurf - 1, &row))
        return ED_HANDLED | ED_ERROR;
    for (t = 0; t < SG_SOLVE_NTARGETS; t++)
        if (strcasecmp(a->v[2], sg_solve_target_name((sg_solve_target)t)) == 0)
            break;
    if (t == SG_SOLVE_NTARGETS)
        return fail(e, "solve: '%s' is not radius, thickness or conic", a->v[2]);
    for (k = 0; k < SG_SOLVE_NKINDS; k++)
        if (strcasecmp(a->v[3], sg_solve_kind_name((sg_solve_kind)k)) == 0)
            break;
    if (k == SG_SOLVE_NKINDS)
        return fail(e, "solve: '%s' is not none, pickup, curvature_pickup, marginal_height, "
                    "chief_height, position, marginal_angle or fnum", a->v[3]);
    if (!sg_solve_allowed((sg_solve_target)t, (sg_solve_kind)k))
        return fail(e, "solve: a %s solve cannot sit on the %s", a->v[3], a->v[2]);
    memset(&v, 0, sizeof v);
    v.kind = (sg_solve_kind)k;
    if (sg_solve_is_pickup((sg_solve_kind)k)) {
        v.scale = 1.0;
        if (a->n < 5 || !parse_row(e, a->v[4], 0, e->doc.sys->nsurf - 1, &v.from))
            return a->n < 5 ? fail(e, "usage: %s", usage) : (ED_HANDLED | ED_ERROR);
        if (a->n > 5 && !parse_num(e, a->v[5], "scale", &v.scale))
            return ED_HANDLED | ED_ERROR;
        if (a->n > 6 && !parse_num(e, a->v[6], "offset", &v.offset))
            return ED_HANDLED | ED_ERROR;
    } else if (k == SG_SOLVE_VARIABLE) {
        v.lo = -INFINITY;
        v.hi = INFINITY;
        if (a->n != 4 && a->n != 6)
            return fail(e, "usage: solve SURFACE radius|thickness|conic variable [MIN MAX]");
        if (a->n == 6 && (!parse_num(e, a->v[4], "min", &v.lo) ||
                          !parse_num(e, a->v[5], "max", &v.hi)))
            return ED_HANDLED | ED_ERROR;
    } else if (k == SG_SOLVE_POSITION) {
        if (a->n != 6)
            return fail(e, "usage: %s", usage);
        if (!parse_row(e, a->v[4], 0, e->doc.sys->nsurf - 1, &v.from) ||
            !parse_num(e, a->v[5], "length", &v.value))
            return ED_HANDLED | ED_ERROR;
    } else if (k != SG_SOLVE_NONE) {
        if (a->n != 5)
            return fail(e, "usage: %s", usage);
        if (!parse_num(e, a->v[4], "value", &x))
            return ED_HANDLED | ED_ERROR;
        v.value = x;
    } else if (a->n != 4) {
        return fail(e, "usage: %s", usage);
    }
    if (!begin(e, row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->surf[row].solve[t] = v;
    sg_diag_clear(&d);
    if ((rc = sg_solve_check(e->doc.sys, row, (sg_solve_target)t, &d)) != SG_OK)
        return cancel(e, d.msg);
    e->row = row;
    if (k == SG_SOLVE_NONE)
        return end(e, "surface %d: the %s holds no solve", row, a->v[2]);
    return end(e, "surface %d: %s solve on the %s", row, sg_solve_kind_name(v.kind),
               sg_solve_target_name((sg_solve_target)t));
}

static int undo_redo(ed *e, args *a, int redo)
{
    int n = 1, i, row = -1, rc = SG_EOK;
    if (!need(e, a, 0, 1, redo ? "redo [N]" : "undo [N]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 1 && !parse_int(e, a->v[1], "count", 1, 1000000, &n))
        return ED_HANDLED | ED_ERROR;
    for (i = 0; i < n; i++) {
        rc = redo ? doc_redo(&e->doc, &row) : doc_undo(&e->doc, &row);
        if (rc != SG_EOK)
            break;
    }
    if (i == 0)
        return fail(e, rc == SG_ERANGE ? "nothing to %s" : "out of memory: cannot %s",
                    redo ? "redo" : "undo");
    if (row >= 0)
        e->row = row;
    e->dirty = 1;
    ed_msg(e, 0, "%s %d change%s (%zu more to undo, %zu to redo)", redo ? "redid" : "undid",
           i, i == 1 ? "" : "s", doc_undo_depth(&e->doc), doc_redo_depth(&e->doc));
    return OK_VIEW;
}

static int c_undo(ed *e, args *a)
{
    return undo_redo(e, a, 0);
}

static int c_redo(ed *e, args *a)
{
    return undo_redo(e, a, 1);
}

static int c_title(ed *e, args *a)
{
    char t[ED_LINE];
    if (a->n > 1)
        rest_of(a, 1, t, sizeof t);
    else
        t[0] = '\0';
    if (strlen(t) >= sizeof e->doc.sys->title)
        return fail(e, "title: longer than %zu bytes", sizeof e->doc.sys->title - 1);
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    memset(e->doc.sys->title, 0, sizeof e->doc.sys->title);
    memcpy(e->doc.sys->title, t, strlen(t));
    return end(e, "title \"%s\"", t);
}

static int c_units(ed *e, args *a)
{
    static const char *const u[] = {"mm", "cm", "in", "m"};
    size_t i;
    if (!need(e, a, 1, 1, "units mm|cm|in|m"))
        return ED_HANDLED | ED_ERROR;
    for (i = 0; i < 4; i++)
        if (strcasecmp(a->v[1], u[i]) == 0)
            break;
    if (i == 4)
        return fail(e, "units: \"%s\" is not mm, cm, in or m", a->v[1]);
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    memset(e->doc.sys->units, 0, sizeof e->doc.sys->units);
    memcpy(e->doc.sys->units, u[i], strlen(u[i]));
    return end(e, "units %s", u[i]);
}

static int wl_check(ed *e, double um, double w)
{
    if (!(um > 0.0) || !isfinite(um))
        return fail(e, "wavelength: %g um is not positive", um), 0;
    if (!(um >= 0.1 && um <= 100.0))
        return fail(e, "wavelength: %g um is outside 0.1 to 100 um; it is in micrometres",
                    um), 0;
    if (!(w >= 0.0))
        return fail(e, "wavelength: weight %g is negative", w), 0;
    return 1;
}

/* Spectral lines by their Fraunhofer letters, in micrometres, as Schott's
 * catalog lists them (TIE-29; the d, F and C of Abbe numbers). */
static const struct line_name {
    const char *name;
    double um;
} spectral_lines[] = {
    {"i", 0.3650146}, {"h", 0.4046561}, {"g", 0.4358343}, {"F'", 0.4799914},
    {"F", 0.4861327}, {"e", 0.5460740}, {"d", 0.5875618}, {"D", 0.5892938},
    {"C'", 0.6438469}, {"C", 0.6562725}, {"r", 0.7065188}, {"s", 0.85211},
    {"t", 1.01398},
};
#define NLINES (sizeof spectral_lines / sizeof spectral_lines[0])

/* A wavelength in um, or a line's letter (case matters: d is not D). */
static int parse_um(ed *e, const char *s, double *um)
{
    size_t i;
    for (i = 0; i < NLINES; i++)
        if (strcmp(s, spectral_lines[i].name) == 0) {
            *um = spectral_lines[i].um;
            return 1;
        }
    return parse_num(e, s, "wavelength", um);
}

/* Presets as Zemax's wavelength dialog offers them; the primary is the
 * line in the middle, as there. */
static const struct preset {
    const char *name;
    const char *lines[3];
    int primary;
} presets[] = {
    {"FdC", {"F", "d", "C"}, 1},
    {"F'eC'", {"F'", "e", "C'"}, 1},
    {"d", {"d", NULL, NULL}, 0},
    {"e", {"e", NULL, NULL}, 0},
};

static int c_wavelength(ed *e, args *a)
{
    sg_system *s = e->doc.sys;
    const char *usage = "wavelength add UM|LINE [WEIGHT] | set N UM|LINE [WEIGHT] | delete N | "
                        "primary N | move N TO | preset FdC|F'eC'|d|e";
    const char *sub = a->n > 1 ? a->v[1] : "";
    double um, w = 1.0;
    int k;
    if (strcasecmp(sub, "preset") == 0) {
        size_t p, j;
        if (!need(e, a, 2, 2, usage))
            return ED_HANDLED | ED_ERROR;
        for (p = 0; p < sizeof presets / sizeof presets[0]; p++)
            if (strcasecmp(a->v[2], presets[p].name) == 0)
                break;
        if (p == sizeof presets / sizeof presets[0])
            return fail(e, "wavelength preset: \"%s\" is not FdC, F'eC', d or e", a->v[2]);
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        memset(s->wave, 0, sizeof s->wave);
        for (j = 0; j < 3 && presets[p].lines[j]; j++) {
            parse_um(e, presets[p].lines[j], &s->wave[j].um);
            s->wave[j].weight = 1.0;
        }
        s->nwave = (int)j;
        s->primary_wave = presets[p].primary;
        e->wave = s->primary_wave;
        return end(e, "wavelengths %s (primary %s)", presets[p].name,
                   presets[p].lines[presets[p].primary]);
    }
    if (strcasecmp(sub, "move") == 0) {
        int to, i;
        sg_wave moved;
        if (!need(e, a, 3, 3, usage) ||
            !parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k) ||
            !parse_int(e, a->v[3], "to", 1, s->nwave, &to))
            return ED_HANDLED | ED_ERROR;
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        k--;
        to--;
        moved = s->wave[k];
        /* The primary and the traced wavelength stay the same light. */
        {
            int prim = s->primary_wave, cur = e->wave;
            if (k < to) {
                for (i = k; i < to; i++)
                    s->wave[i] = s->wave[i + 1];
            } else {
                for (i = k; i > to; i--)
                    s->wave[i] = s->wave[i - 1];
            }
            s->wave[to] = moved;
#define FOLLOW(x) ((x) == k ? to : k < to && (x) > k && (x) <= to ? (x) - 1 \
                   : to < k && (x) >= to && (x) < k ? (x) + 1 : (x))
            s->primary_wave = FOLLOW(prim);
            e->wave = FOLLOW(cur);
#undef FOLLOW
        }
        return end(e, "wavelength %d is now %d", k + 1, to + 1);
    }
    if (strcasecmp(sub, "add") == 0) {
        if (!need(e, a, 2, 3, usage) || !parse_um(e, a->v[2], &um) ||
            (a->n > 3 && !parse_num(e, a->v[3], "weight", &w)) || !wl_check(e, um, w))
            return ED_HANDLED | ED_ERROR;
        if (s->nwave >= SG_MAX_WAVES)
            return fail(e, "a design holds at most %d wavelengths", SG_MAX_WAVES);
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        s->wave[s->nwave].um = um;
        s->wave[s->nwave].weight = w;
        s->nwave++;
        return end(e, "wavelength %d: %.10g um", s->nwave, um);
    }
    if (strcasecmp(sub, "set") == 0) {
        if (!need(e, a, 3, 4, usage) ||
            !parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k) ||
            !parse_um(e, a->v[3], &um))
            return ED_HANDLED | ED_ERROR;
        w = s->wave[k - 1].weight;
        if ((a->n > 4 && !parse_num(e, a->v[4], "weight", &w)) || !wl_check(e, um, w))
            return ED_HANDLED | ED_ERROR;
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->wave[k - 1].um = um;
        e->doc.sys->wave[k - 1].weight = w;
        return end(e, "wavelength %d: %.10g um", k, um);
    }
    if (strcasecmp(sub, "delete") == 0 || strcasecmp(sub, "del") == 0) {
        int i;
        if (!need(e, a, 2, 2, usage) ||
            !parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k))
            return ED_HANDLED | ED_ERROR;
        if (s->nwave == 1)
            return fail(e, "the only wavelength cannot be deleted");
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = k - 1; i + 1 < s->nwave; i++)
            s->wave[i] = s->wave[i + 1];
        s->nwave--;
        memset(&s->wave[s->nwave], 0, sizeof s->wave[0]);
        /* The primary stays the same wavelength when it survives. */
        if (s->primary_wave > k - 1)
            s->primary_wave--;
        if (s->primary_wave >= s->nwave)
            s->primary_wave = s->nwave - 1;
        if (e->wave > k - 1)
            e->wave--;
        return end(e, "deleted wavelength %d", k);
    }
    if (strcasecmp(sub, "primary") == 0) {
        if (!need(e, a, 2, 2, usage) ||
            !parse_int(e, a->v[2], "wavelength", 1, s->nwave, &k))
            return ED_HANDLED | ED_ERROR;
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->primary_wave = k - 1;
        return end(e, "primary wavelength %d", k);
    }
    return fail(e, "usage: %s", usage);
}

static int parse_field_type(const char *s)
{
    if (strcasecmp(s, "angle") == 0)
        return SG_FIELD_ANGLE;
    if (strcasecmp(s, "object") == 0 || strcasecmp(s, "object_height") == 0 ||
        strcasecmp(s, "height") == 0)
        return SG_FIELD_OBJECT_HEIGHT;
    if (strcasecmp(s, "paraximage") == 0 || strcasecmp(s, "paraxial_image_height") == 0)
        return SG_FIELD_PARAX_IMAGE_HEIGHT;
    if (strcasecmp(s, "realimage") == 0 || strcasecmp(s, "real_image_height") == 0)
        return SG_FIELD_REAL_IMAGE_HEIGHT;
    return -1;
}

static int field_check(ed *e, int type, double x, double y, double w)
{
    if (type == SG_FIELD_ANGLE && (fabs(x) >= 90.0 || fabs(y) >= 90.0))
        return fail(e, "field: angle (%g, %g) must be below 90 degrees", x, y), 0;
    if (!(w >= 0.0))
        return fail(e, "field: weight %g is negative", w), 0;
    return 1;
}

static int c_field(ed *e, args *a)
{
    sg_system *s = e->doc.sys;
    const char *usage = "field type angle|object|paraximage|realimage | norm radial|rect | "
                        "add X Y [WEIGHT] | set N X Y [WEIGHT] | delete N | "
                        "vignette N VDX VDY VCX VCY [VAN] | setvig | clearvig";
    const char *sub = a->n > 1 ? a->v[1] : "";
    double x, y, w = 1.0;
    int k, i;
    if (a->n == 2 && isdigit((unsigned char)sub[0])) {
        /* field N: the ray of Zemax's ray trace dialog, at field N. */
        double fx, fy;
        if (!parse_int(e, sub, "field", 1, s->nfield, &k))
            return ED_HANDLED | ED_ERROR;
        ed_field_scale(s, &fx, &fy);
        e->ray[0] = fx > 0.0 ? s->field[k - 1].x / fx : 0.0;
        e->ray[1] = fy > 0.0 ? s->field[k - 1].y / fy : 0.0;
        e->dirty = 1;
        {
            char hx[NUMFMT_MAX], hy[NUMFMT_MAX], fxs[NUMFMT_MAX], fys[NUMFMT_MAX];
            numfmt_shortest(e->ray[0], hx, sizeof hx);
            numfmt_shortest(e->ray[1], hy, sizeof hy);
            numfmt_shortest(s->field[k - 1].x, fxs, sizeof fxs);
            numfmt_shortest(s->field[k - 1].y, fys, sizeof fys);
            ed_msg(e, 0, "field %d (%s, %s %s): Hx %s Hy %s", k, fxs, fys,
                   ed_field_unit(s), hx, hy);
        }
        return OK_VIEW;
    }
    if (strcasecmp(sub, "type") == 0) {
        if (!need(e, a, 2, 2, usage))
            return ED_HANDLED | ED_ERROR;
        k = parse_field_type(a->v[2]);
        if (k < 0)
            return fail(e, "field type: \"%s\" is not angle, object, paraximage or realimage",
                        a->v[2]);
        if (k == SG_FIELD_ANGLE && s->telecentric)
            return fail(e, "field type: a telecentric object space has height fields, not "
                        "angles (telecentric off first)");
        if (k == SG_FIELD_ANGLE)
            for (i = 0; i < s->nfield; i++)
                if (!field_check(e, k, s->field[i].x, s->field[i].y, 1.0))
                    return ED_HANDLED | ED_ERROR;
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->field_type = (sg_field_type)k;
        return end(e, "field type %s", ed_field_type_name(k));
    }
    if (strcasecmp(sub, "norm") == 0 || strcasecmp(sub, "normalization") == 0) {
        if (!need(e, a, 2, 2, usage))
            return ED_HANDLED | ED_ERROR;
        if (strcasecmp(a->v[2], "radial") == 0)
            k = SG_NORM_RADIAL;
        else if (strcasecmp(a->v[2], "rect") == 0 || strcasecmp(a->v[2], "rectangular") == 0)
            k = SG_NORM_RECT;
        else
            return fail(e, "field norm: \"%s\" is not radial or rect", a->v[2]);
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->field_norm = (sg_field_norm)k;
        return end(e, "field normalization %s", ed_field_norm_name(k));
    }
    if (strcasecmp(sub, "add") == 0) {
        if (!need(e, a, 3, 4, usage) || !parse_num(e, a->v[2], "field x", &x) ||
            !parse_num(e, a->v[3], "field y", &y) ||
            (a->n > 4 && !parse_num(e, a->v[4], "weight", &w)) ||
            !field_check(e, s->field_type, x, y, w))
            return ED_HANDLED | ED_ERROR;
        if (s->nfield >= SG_MAX_FIELDS)
            return fail(e, "a design holds at most %d fields", SG_MAX_FIELDS);
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        sg_param_defaults(SG_SCOPE_FIELD, &s->field[s->nfield]);
        s->field[s->nfield].x = x;
        s->field[s->nfield].y = y;
        s->field[s->nfield].weight = w;
        s->nfield++;
        return end(e, "field %d: (%s, %s)", s->nfield, a->v[2], a->v[3]);
    }
    if (strcasecmp(sub, "set") == 0) {
        if (!need(e, a, 4, 5, usage) || !parse_int(e, a->v[2], "field", 1, s->nfield, &k) ||
            !parse_num(e, a->v[3], "field x", &x) || !parse_num(e, a->v[4], "field y", &y))
            return ED_HANDLED | ED_ERROR;
        w = s->field[k - 1].weight;
        if ((a->n > 5 && !parse_num(e, a->v[5], "weight", &w)) ||
            !field_check(e, s->field_type, x, y, w))
            return ED_HANDLED | ED_ERROR;
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        s->field[k - 1].x = x;
        s->field[k - 1].y = y;
        s->field[k - 1].weight = w;
        return end(e, "field %d: (%s, %s)", k, a->v[3], a->v[4]);
    }
    if (strcasecmp(sub, "vignette") == 0 || strcasecmp(sub, "vig") == 0) {
        /* Zemax's VDX VDY VCX VCY VAN, rows of the engine's field table. */
        static const char *const keys[] = {"vdx", "vdy", "vcx", "vcy", "van"};
        double v[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        char msg[160];
        if (!need(e, a, 6, 7, usage) || !parse_int(e, a->v[2], "field", 1, s->nfield, &k))
            return ED_HANDLED | ED_ERROR;
        for (i = 0; i < 5 && 3 + i < a->n; i++) {
            const sg_param *p = sg_param_find(SG_SCOPE_FIELD, keys[i]);
            if (!parse_num(e, a->v[3 + i], keys[i], &v[i]))
                return ED_HANDLED | ED_ERROR;
            if (sg_param_check(p, 0, v[i], 0, msg, sizeof msg) != SG_OK)
                return fail(e, "field %d: %s", k, msg);
        }
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = 0; i < 5; i++)
            sg_param_set(sg_param_find(SG_SCOPE_FIELD, keys[i]), &s->field[k - 1], 0, v[i]);
        return end(e, "field %d: vignetting VDX %g VDY %g VCX %g VCY %g VAN %g", k, v[0], v[1],
                   v[2], v[3], v[4]);
    }
    if (strcasecmp(sub, "setvig") == 0) {
        /* Zemax's Set Vignetting: every field's factors from the apertures,
         * as one edit (one undo). */
        sg_vigfactors vf[SG_MAX_FIELDS];
        sg_setvig_opts o;
        sg_diag d;
        if (!need(e, a, 1, 1, usage))
            return ED_HANDLED | ED_ERROR;
        if (!e->cat)
            return fail(e, "no glass catalog: %s", e->cat_msg);
        sg_setvig_opts_init(&o);
        sg_diag_clear(&d);
        if (sg_set_vignetting(s, e->cat, &o, vf, &d) != SG_OK)
            return fail(e, "field setvig: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        sg_set_vignetting_apply(s, vf);
        return end(e, "vignetting factors set for %d field%s from the apertures (field N shows "
                   "them)", s->nfield, s->nfield == 1 ? "" : "s");
    }
    if (strcasecmp(sub, "clearvig") == 0) {
        if (!need(e, a, 1, 1, usage))
            return ED_HANDLED | ED_ERROR;
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = 0; i < s->nfield; i++)
            s->field[i].vdx = s->field[i].vdy = s->field[i].vcx = s->field[i].vcy =
                s->field[i].van = 0.0;
        return end(e, "vignetting factors cleared");
    }
    if (strcasecmp(sub, "delete") == 0 || strcasecmp(sub, "del") == 0) {
        if (!need(e, a, 2, 2, usage) || !parse_int(e, a->v[2], "field", 1, s->nfield, &k))
            return ED_HANDLED | ED_ERROR;
        if (s->nfield == 1)
            return fail(e, "the only field cannot be deleted");
        if (!begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        s = e->doc.sys;
        for (i = k - 1; i + 1 < s->nfield; i++)
            s->field[i] = s->field[i + 1];
        s->nfield--;
        memset(&s->field[s->nfield], 0, sizeof s->field[0]);
        return end(e, "deleted field %d", k);
    }
    return fail(e, "usage: %s", usage);
}

static int parse_aper(const char *s)
{
    static const char *const n[][3] = {
        {"epd", "entrance", NULL},
        {"fnum", "image_fnum", "f/#"},
        {"na", "object_na", "objna"},
        {"float", "float_by_stop", "stop"},
        {"pwfnum", "paraxial_working_fnum", "working"},
        {"cone", "object_cone_angle", "coneangle"},
    };
    int i, j;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 3; j++)
            if (n[i][j] && strcasecmp(s, n[i][j]) == 0)
                return i;
    return -1;
}

static int c_aperture(ed *e, args *a)
{
    const char *usage = "aperture epd|fnum|na|float|pwfnum|cone [VALUE] | aperture VALUE";
    int type = e->doc.sys->aper_type, vi = 1;
    double v = e->doc.sys->aper_value;
    char shown[NUMFMT_MAX];
    if (!need(e, a, 1, 2, usage))
        return ED_HANDLED | ED_ERROR;
    if (parse_aper(a->v[1]) >= 0) {
        type = parse_aper(a->v[1]);
        vi = 2;
    } else if (a->n > 2) {
        return fail(e, "aperture: \"%s\" is not epd, fnum, na, float, pwfnum or cone", a->v[1]);
    }
    if (vi < a->n && !parse_num(e, a->v[vi], "aperture value", &v))
        return ED_HANDLED | ED_ERROR;
    if (type != SG_APER_FLOAT_STOP && !(v > 0.0))
        return fail(e, "aperture: value %g must be positive", v);
    if (type == SG_APER_OBJECT_NA && !(v < 1.0))
        return fail(e, "aperture: object NA %g must be below 1", v);
    if (type == SG_APER_OBJECT_CONE && !(v < 90.0))
        return fail(e, "aperture: object cone angle %g must be below 90 degrees", v);
    if ((type == SG_APER_OBJECT_NA || type == SG_APER_OBJECT_CONE) &&
        isinf(e->doc.sys->surf[0].thickness))
        return fail(e, "aperture: an object %s needs a finite object distance",
                    type == SG_APER_OBJECT_NA ? "NA" : "cone angle");
    if (type != SG_APER_OBJECT_NA && type != SG_APER_OBJECT_CONE && e->doc.sys->telecentric)
        return fail(e, "aperture: a telecentric object space's aperture is the object NA or "
                    "cone angle (telecentric off first)");
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->aper_type = (sg_aper_type)type;
    e->doc.sys->aper_value = v;
    numfmt_shortest(v, shown, sizeof shown);
    return end(e, "aperture %s %s", ed_aper_name(type), shown);
}

static int c_aim(ed *e, args *a)
{
    int k;
    if (!need(e, a, 1, 1, "aim off|paraxial|real"))
        return ED_HANDLED | ED_ERROR;
    for (k = 0; k < 3; k++)
        if (strcasecmp(a->v[1], ed_aim_name(k)) == 0)
            break;
    if (k == 3)
        return fail(e, "aim: \"%s\" is not off, paraxial or real", a->v[1]);
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->aim = (sg_aim)k;
    return end(e, "ray aiming %s", ed_aim_name(k));
}

/* Zemax's "Telecentric Object Space": the entrance pupil at infinity.  It
 * needs an object NA, a finite object and height fields, as in Zemax. */
static int c_telecentric(ed *e, args *a)
{
    const sg_system *s = e->doc.sys;
    int on;
    if (!need(e, a, 0, 1, "telecentric on|off|toggle") ||
        !parse_switch(e, a->n > 1 ? a->v[1] : NULL, s->telecentric, &on, "telecentric"))
        return ED_HANDLED | ED_ERROR;
    if (on && s->aper_type != SG_APER_OBJECT_NA && s->aper_type != SG_APER_OBJECT_CONE)
        return fail(e, "telecentric: the aperture must be the object NA or cone angle "
                    "(aperture na VALUE, aperture cone DEGREES)");
    if (on && isinf(s->surf[0].thickness))
        return fail(e, "telecentric: the object must be at a finite distance");
    if (on && s->field_type == SG_FIELD_ANGLE)
        return fail(e, "telecentric: the fields must be heights (field type object, "
                    "paraximage or realimage)");
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->telecentric = on;
    return end(e, "object space %s", on ? "telecentric: the entrance pupil at infinity"
                                        : "not telecentric");
}

/* The environment: Zemax's system temperature and pressure, and whether
 * glass indices follow them (sagitta-design(5), GLASS INDICES). */
static int c_temperature(ed *e, args *a)
{
    double t;
    if (!need(e, a, 1, 1, "temperature CELSIUS") ||
        !parse_num(e, a->v[1], "temperature", &t))
        return ED_HANDLED | ED_ERROR;
    if (!(t >= SG_TEMP_MIN && t <= SG_TEMP_MAX))
        return fail(e, "temperature: %g C is outside %g to %g C", t, SG_TEMP_MIN, SG_TEMP_MAX);
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->temperature = t;
    return end(e, "temperature %g C%s", t,
               e->doc.sys->adjust_index ? "" : " (glass indices follow it after \"adjust on\")");
}

/* Zemax's thermal analysis on the design: the lens as built at another
 * temperature (sg_thermal), one edit and one undo. */
static int c_thermal(ed *e, args *a)
{
    double t, p;
    sg_system *hot;
    sg_diag d;
    double from;
    if (!need(e, a, 1, 2, "thermal CELSIUS [ATM]") ||
        !parse_num(e, a->v[1], "temperature", &t))
        return ED_HANDLED | ED_ERROR;
    p = e->doc.sys->pressure;
    if (a->n == 3 && !parse_num(e, a->v[2], "pressure", &p))
        return ED_HANDLED | ED_ERROR;
    if (!(t >= SG_TEMP_MIN && t <= SG_TEMP_MAX))
        return fail(e, "thermal: temperature %g C is outside %g to %g C", t, SG_TEMP_MIN,
                    SG_TEMP_MAX);
    if (!(p >= 0.0 && p <= SG_PRES_MAX))
        return fail(e, "thermal: pressure %g atm is outside 0 to %g atm", p, SG_PRES_MAX);
    if (!e->cat)
        return fail(e, "no glass catalog: %s", e->cat_msg);
    if (!(hot = sg_system_new()))
        return fail(e, "out of memory: the change was not made");
    sg_diag_clear(&d);
    if (sg_thermal(e->doc.sys, e->cat, t, p, hot, &d) != SG_OK) {
        sg_system_free(hot);
        return fail(e, "thermal: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
    }
    from = e->doc.sys->temperature;
    if (!begin(e, e->row) || sg_system_assign(e->doc.sys, hot) != SG_OK) {
        if (e->doc.open_change)
            doc_cancel(&e->doc);
        sg_system_free(hot);
        return fail(e, "out of memory: the change was not made");
    }
    sg_system_free(hot);
    return end(e, "thermal: the lens as built at %g C, %g atm (from %g C)%s%s", t, p, from,
               d.nwarn ? "; " : "", d.nwarn ? d.warn[0] : "");
}

/* Zemax's automatic semi-diameters: every surface whose semi-diameter is
 * not fixed gets the highest edge ray's height there, as one edit (one
 * undo).  A surface no ray reaches keeps its value. */
static int c_semidiam(ed *e, args *a)
{
    double *sd;
    sg_diag d;
    sg_system *s;
    int i, set = 0, kept = 0;
    if (!need(e, a, 0, 0, "semidiam"))
        return ED_HANDLED | ED_ERROR;
    if (!e->cat)
        return fail(e, "no glass catalog: %s", e->cat_msg);
    if (!(sd = calloc((size_t)e->doc.sys->nsurf, sizeof *sd)))
        return fail(e, "out of memory: the change was not made");
    sg_diag_clear(&d);
    if (sg_semi_diameters(e->doc.sys, e->cat, NULL, sd, &d) != SG_OK) {
        free(sd);
        return fail(e, "semidiam: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
    }
    if (!begin(e, e->row)) {
        free(sd);
        return ED_HANDLED | ED_ERROR;
    }
    s = e->doc.sys;
    for (i = 1; i < s->nsurf; i++) {
        if (s->surf[i].sd_fixed)
            continue;
        if (sd[i] > 0.0) {
            s->surf[i].semi_diameter = sd[i];
            set++;
        } else
            kept++;
    }
    free(sd);
    return end(e, "semidiam: %d automatic semi-diameter%s set from the edge rays%s", set,
               set == 1 ? "" : "s",
               kept ? " (surfaces no ray reaches kept theirs)" : "");
}

static int c_pressure(ed *e, args *a)
{
    double p;
    if (!need(e, a, 1, 1, "pressure ATM") || !parse_num(e, a->v[1], "pressure", &p))
        return ED_HANDLED | ED_ERROR;
    if (!(p >= 0.0 && p <= SG_PRES_MAX))
        return fail(e, "pressure: %g atm is outside 0 to %g atm", p, SG_PRES_MAX);
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->pressure = p;
    return end(e, "pressure %g atm", p);
}

static int c_adjust(ed *e, args *a)
{
    int on;
    if (!need(e, a, 0, 1, "adjust on|off|toggle") ||
        !parse_switch(e, a->n > 1 ? a->v[1] : NULL, e->doc.sys->adjust_index, &on, "adjust"))
        return ED_HANDLED | ED_ERROR;
    if (!begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->adjust_index = on;
    return end(e, "glass indices %s", on ? "follow the temperature and pressure"
                                         : "are the catalog's");
}

/* The glass picker: "glasses N-BK" by name, "glasses 1.5168 64.17" by nd
 * and vd; "pick N" makes hit N the material of the cursor's surface. */
static int c_glasses(ed *e, args *a)
{
    char q[ED_LINE];
    const sg_system *s = e->doc.sys;
    double um = s->wave[s->primary_wave].um;
    int n, i;
    if (!e->cat)
        return fail(e, "no glass catalog: %s", e->cat_msg);
    if (a->n > 1)
        rest_of(a, 1, q, sizeof q);
    else
        q[0] = '\0';
    n = gp_search(e->cat, s, um, q, &e->glasses);
    if (n < 0)
        return fail(e, "glasses: out of memory");
    e->glass_sel = 0;
    if (e->batch) {
        for (i = 0; i < n; i++) {
            const gp_hit *h = &e->glasses.hit[i];
            fprintf(e->out, "%d %s %s %.17g %.17g %.17g\n", i + 1, h->g->name, h->g->catalog,
                    h->g->nd, h->g->vd, h->n);
        }
        fflush(e->out);
    }
    ed_msg(e, 0, "%d glass%s for \"%s\", n at %g um; \"pick N\" sets surface %d's material", n,
           n == 1 ? "" : "es", q, um, e->row);
    return ED_HANDLED | ED_REDRAW | (e->batch || n == 0 ? 0 : ED_SHOW_GLASSES);
}

static int c_pick(ed *e, args *a)
{
    double k;
    char line[ED_LINE];
    const sg_glass *g;
    if (!need(e, a, 1, 1, "pick N") || !parse_num(e, a->v[1], "pick", &k))
        return ED_HANDLED | ED_ERROR;
    if (e->glasses.n == 0)
        return fail(e, "pick: no glasses listed; search with \"glasses NAME\" or "
                       "\"glasses ND VD\" first");
    if (k != floor(k) || k < 1 || k > e->glasses.n)
        return fail(e, "pick: %g is not one of 1 to %d", k, e->glasses.n);
    if (e->row < 1 || e->row >= e->doc.sys->nsurf - 1)
        return fail(e, "pick: the cursor is on surface %d; a glass goes on surfaces 1 to %d",
                     e->row, e->doc.sys->nsurf - 2);
    /* Through "set", so undo, messages and checks are the cell's; the
     * catalog is named when the name alone means another's glass. */
    g = e->glasses.hit[(int)k - 1].g;
    if (g == sg_catalog_find(e->cat, g->name))
        snprintf(line, sizeof line, "set %d material %s", e->row, g->name);
    else
        snprintf(line, sizeof line, "set %d material %s:%s", e->row, g->catalog, g->name);
    return cmd_exec(e, line);
}

/* ------------------------------------------------------------------------
 * Files
 * ------------------------------------------------------------------------ */

/* Checks for unsaved changes before the document is replaced.  Returns 1
 * to go ahead; otherwise flags for the caller to return. */
static int may_discard(ed *e, const args *a, int bang, int *flags)
{
    char q[ED_LINE / 2];
    int i;
    size_t len;
    if (bang || !doc_modified(&e->doc))
        return 1;
    if (e->batch) {
        *flags = fail(e, "unsaved changes: save first, or use %s!", a->v[0]);
        return 0;
    }
    snprintf(e->pending, sizeof e->pending, "%s!", a->v[0]);
    for (i = 1; i < a->n; i++) {
        cmd_quote(a->v[i], q, sizeof q);
        len = strlen(e->pending);
        snprintf(e->pending + len, sizeof e->pending - len, " %s", q);
    }
    e->confirm = CONFIRM_DISCARD;
    ed_msg(e, 0, "unsaved changes will be lost");
    *flags = ED_HANDLED | ED_CONFIRM | ED_REDRAW;
    return 0;
}

static int opened(ed *e, const char *what)
{
    e->row = 0;
    e->col = COL_RADIUS;
    e->wave = e->doc.sys->primary_wave;
    e->dirty = 1;
    ed_msg(e, 0, "%s: %d surfaces", what, e->doc.sys->nsurf);
    return OK_VIEW;
}

/* Says so when an editor that died left unsaved changes to this file. */
static void note_orphans(ed *e, const char *path)
{
    char dir[REC_PATH], abs[REC_PATH], when[64];
    rec_info *v;
    size_t len;
    if (rec_dir(dir, sizeof dir) != 0 || rec_abspath(path, abs, sizeof abs) != 0 ||
        rec_orphans(dir, abs, e->rec.file[0] ? e->rec.file : NULL, &v) <= 0)
        return;
    rec_time_text(v[0].time, when, sizeof when);
    len = strlen(e->msg);
    snprintf(e->msg + len, sizeof e->msg - len,
             "; unsaved changes to it from %s are in a recovery file (:recover)", when);
    free(v);
}

int ed_note_holders(ed *e, const char *path)
{
    char dir[REC_PATH], abs[REC_PATH], when[64];
    rec_info first;
    size_t len;
    int n;
    if (rec_dir(dir, sizeof dir) != 0 || rec_abspath(path, abs, sizeof abs) != 0 ||
        (n = rec_holders(dir, abs, &first)) <= 0)
        return 0;
    rec_time_text(first.time, when, sizeof when);
    len = strlen(e->msg);
    snprintf(e->msg + len, sizeof e->msg - len,
             "%swarning: %s is open in %s editor (pid %ld%s%s, since %s); a save may "
             "overwrite its changes", len ? "; " : "", path, n > 1 ? "more than one" : "another",
             first.pid, first.host[0] ? " on " : "", first.host, when);
    e->msg_err = 1;
    return n;
}

static int open_path(ed *e, const char *path)
{
    sg_diag d;
    int f;
    sg_diag_clear(&d);
    if (doc_load(&e->doc, path, &d) != SG_EOK)
        return fail(e, "%s", d.msg[0] ? d.msg : sg_strerror(d.code));
    f = opened(e, path);
    ed_load_warnings(e, path, &d);
    /* Solved values follow the design as it is opened. */
    sg_diag_clear(&d);
    if (sg_system_apply_solves(e->doc.sys, e->cat, &d) != SG_OK)
        ed_msg(e, 1, "solves: %s", d.msg);
    note_orphans(e, path);
    ed_note_holders(e, path);
    return f;
}

static int c_open(ed *e, args *a, int bang)
{
    char path[ED_LINE];
    int flags;
    if (a->n < 2) {
        if (e->batch)
            return fail(e, "usage: open FILE");
        snprintf(e->prompt_init, sizeof e->prompt_init, "open ");
        return ED_HANDLED | ED_PROMPT;
    }
    rest_of(a, 1, path, sizeof path);
    if (!may_discard(e, a, bang, &flags))
        return flags;
    return open_path(e, path);
}

static int c_new(ed *e, args *a, int bang)
{
    int flags;
    if (!need(e, a, 0, 1, "new [FILE]"))
        return ED_HANDLED | ED_ERROR;
    if (!may_discard(e, a, bang, &flags))
        return flags;
    if (doc_new(&e->doc, a->n > 1 ? a->v[1] : NULL) != SG_EOK)
        return fail(e, "out of memory");
    return opened(e, "new design");
}

static int c_example(ed *e, args *a, int bang)
{
    const char *dir = ed_examples_dir();
    char path[ED_LINE];
    char **names;
    int n, i, flags;
    if (a->n < 2) {
        if (!e->batch)
            return ED_HANDLED | ED_SHOW_EXAMPLES;
        n = ed_examples_list(&names);
        if (n < 0)
            return fail(e, "no examples directory (set SAGITTA_EXAMPLES)");
        for (i = 0; i < n; i++)
            fprintf(e->out, "%s\n", names[i]);
        ed_examples_free(names, n);
        return ED_HANDLED;
    }
    if (!need(e, a, 1, 1, "example NAME"))
        return ED_HANDLED | ED_ERROR;
    if (!dir)
        return fail(e, "no examples directory (set SAGITTA_EXAMPLES)");
    if (strchr(a->v[1], '/'))
        return fail(e, "example: \"%s\": give a name from the list, not a path", a->v[1]);
    n = (int)strlen(a->v[1]);
    snprintf(path, sizeof path, "%s/%s%s", dir, a->v[1],
             n > 5 && strcmp(a->v[1] + n - 5, ".json") == 0 ? "" : ".json");
    if (!may_discard(e, a, bang, &flags))
        return flags;
    /* An example opens as a new file so that "save" cannot overwrite the
     * bundled copy by accident. */
    flags = open_path(e, path);
    if (!(flags & ED_ERROR)) {
        doc_set_path(&e->doc, NULL);
        ed_msg(e, 0, "example %s: %d surfaces (save it under a name of your own)",
               a->v[1], e->doc.sys->nsurf);
    }
    return flags;
}

static int save_as(ed *e, const char *path, int bang, const char *cmd)
{
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    /* A failure leaves the old file whole (see doc_save); the document
     * stays as it was, modified.  A .zmx file that cannot hold the edits
     * faithfully is written only after a yes (or with "!"). */
    rc = doc_save_flags(&e->doc, path, bang ? SG_ZMX_ALLOW_LOSS : 0, &d);
    if (rc == SG_ELOSSY && !bang) {
        if (e->batch)
            return fail(e, "not saved: %s; %s writes it all the same", d.msg, cmd);
        snprintf(e->pending, sizeof e->pending, "%s", cmd);
        snprintf(e->question, sizeof e->question, "%.900s. Write it all the same? (y)es (n)o",
                 d.msg);
        snprintf(e->question_short, sizeof e->question_short,
                 "Write all the same? (y)es (n)o: %.900s", d.msg);
        e->confirm = CONFIRM_ASK;
        ed_msg(e, 0, "%s", d.msg);
        return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
    }
    if (rc != SG_EOK)
        return fail(e, "not saved: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
    rec_saved(e);
    if (d.nwarn)
        ed_msg(e, 0, "saved %s: %s", doc_path(&e->doc), d.warn[0]);
    else
        ed_msg(e, 0, "saved %s", doc_path(&e->doc));
    return ED_HANDLED | ED_REDRAW;
}

/* Asks before a save that would replace work: yes runs cmd (the same save
 * with "!").  In batch mode nobody can answer, so it fails, naming cmd. */
static int ask(ed *e, const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int ask(ed *e, const char *cmd, const char *fmt, ...)
{
    char why[ED_MSG];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    if (e->batch)
        return fail(e, "%s: not saved; %s overwrites it", why, cmd);
    snprintf(e->pending, sizeof e->pending, "%s", cmd);
    snprintf(e->question, sizeof e->question, "%.900s. Overwrite it? (y)es (n)o", why);
    snprintf(e->question_short, sizeof e->question_short, "Overwrite? (y)es (n)o: %.900s", why);
    e->confirm = CONFIRM_ASK;
    ed_msg(e, 0, "%s", why);
    return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
}

/* save, save!, wq and wq!: a new name that holds another file, or our own
 * file changed on disk by someone else, is not overwritten unasked. */
static int save_cmd(ed *e, args *a, int bang, int quit)
{
    char path[ED_LINE], q[ED_LINE], cmd[ED_LINE + 8];
    const char *target;
    int f;
    cmd[0] = '\0';
    if (a->n > 1) {
        rest_of(a, 1, path, sizeof path);
        target = path;
    } else {
        target = doc_path(&e->doc);
        if (!target) {
            if (e->batch)
                return fail(e, "no file name: use save FILE");
            snprintf(e->prompt_init, sizeof e->prompt_init, quit ? "wq " : "save ");
            ed_msg(e, 0, "save as: type a file name");
            return ED_HANDLED | ED_PROMPT;
        }
    }
    if (!bang) {
        int t = doc_target(target, NULL), own = doc_is_own_file(&e->doc, target);
        cmd_quote(target, q, sizeof q);
        snprintf(cmd, sizeof cmd, "%s! %s", quit ? "wq" : "save", q);
        if (t == DOC_TARGET_READONLY)
            return fail(e, "not saved: %s is read-only (save under another name, or make it "
                           "writable)", target);
        if (t == DOC_TARGET_NOTFILE)
            return fail(e, "not saved: %s is not a regular file", target);
        if (t != DOC_TARGET_NEW && !own)
            return ask(e, cmd, "%s already exists", target);
        if (own && doc_disk_changed(&e->doc))
            return ask(e, cmd, e->doc.disk.have ? "%s changed on disk since it was read"
                                                : "%s already exists", target);
    }
    if (!cmd[0]) {
        cmd_quote(target, q, sizeof q);
        snprintf(cmd, sizeof cmd, "%s! %s", quit ? "wq" : "save", q);
    }
    f = save_as(e, a->n > 1 ? path : NULL, bang, cmd);
    if (!quit || (f & (ED_ERROR | ED_CONFIRM)))
        return f;
    rec_finish(e);
    e->quit = 1;
    return f | ED_QUIT;
}

static int c_save(ed *e, args *a)
{
    return save_cmd(e, a, 0, 0);
}

static int c_save1(ed *e, args *a)
{
    return save_cmd(e, a, 1, 0);
}

static int c_quit(ed *e, args *a, int bang)
{
    if (bang || !doc_modified(&e->doc)) {
        /* A clean end: nothing is left to recover. */
        rec_finish(e);
        e->quit = 1;
        return ED_HANDLED | ED_QUIT;
    }
    if (e->batch)
        return fail(e, "unsaved changes: save first, or use quit!");
    e->confirm = CONFIRM_QUIT;
    ed_msg(e, 0, "unsaved changes");
    return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
}

static int c_wq(ed *e, args *a)
{
    return save_cmd(e, a, 0, 1);
}

static int c_wq1(ed *e, args *a)
{
    return save_cmd(e, a, 1, 1);
}

/* ------------------------------------------------------------------------
 * Recovery files left by editors that crashed or were killed
 * ------------------------------------------------------------------------ */

/* Finds the orphan a token names: its number in the list, or its file. */
static int pick_orphan(ed *e, const rec_info *v, int n, const char *tok)
{
    char want[REC_PATH], have[REC_PATH];
    rec_info info;
    sg_diag d;
    int i, k;
    if (args_int(tok, 1, INT_MAX, &k) == ARGS_OK) {
        if (k > n)
            return fail(e, "recover: there %s %d recovery file%s; see recover list",
                        n == 1 ? "is" : "are", n, n == 1 ? "" : "s"), -1;
        return k - 1;
    }
    for (i = 0; i < n; i++)
        if (strcmp(v[i].file, tok) == 0)
            return i;
    /* The same file under another spelling (relative, through a link). */
    if (rec_abspath(tok, want, sizeof want) == 0)
        for (i = 0; i < n; i++)
            if (rec_abspath(v[i].file, have, sizeof have) == 0 && strcmp(want, have) == 0)
                return i;
    sg_diag_clear(&d);
    if (rec_read_file(tok, &info, NULL, &d) != SG_OK)
        return fail(e, "recover: %s", d.msg), -1;
    if (!info.orphan)
        return fail(e, "recover: %s belongs to an editor still running (pid %ld%s%s)", tok,
                    info.pid, info.host[0] ? " on " : "", info.host), -1;
    return fail(e, "recover: %s is not in the list of recovery files", tok), -1;
}

static int c_recover(ed *e, args *a, int bang)
{
    const char *usage = "recover [list | N | FILE | delete N|FILE]";
    const char *sub = a->n > 1 ? a->v[1] : "list";
    char dir[REC_PATH], when[64];
    rec_info *v = NULL, got;
    sg_system *sys;
    sg_diag d;
    int n, i, k, flags;

    if (rec_dir(dir, sizeof dir) != 0)
        return fail(e, "recover: set XDG_STATE_HOME or HOME to say where recovery files live");
    n = rec_orphans(dir, NULL, e->rec.file[0] ? e->rec.file : NULL, &v);
    if (n < 0)
        return fail(e, "recover: cannot read %s: %s", dir, strerror(errno));
    if (strcmp(sub, "list") == 0) {
        size_t len;
        if (!need(e, a, 0, 1, usage)) {
            free(v);
            return ED_HANDLED | ED_ERROR;
        }
        if (n == 0) {
            ed_msg(e, 0, "no recovery files in %s", dir);
            free(v);
            return ED_HANDLED | ED_REDRAW;
        }
        ed_msg(e, 0, "%d recovery file%s (recover N loads, recover delete N removes):", n,
               n == 1 ? "" : "s");
        for (i = 0; i < n; i++) {
            rec_time_text(v[i].time, when, sizeof when);
            if (e->batch)
                fprintf(e->out, "%d  %s  %s  %s\n", i + 1, when,
                        v[i].path[0] ? v[i].path : "(untitled)", v[i].file);
            len = strlen(e->msg);
            snprintf(e->msg + len, sizeof e->msg - len, "  %d) %s, %s", i + 1,
                     v[i].path[0] ? v[i].path : "untitled", when);
        }
        free(v);
        return ED_HANDLED | ED_REDRAW;
    }
    if (strcmp(sub, "delete") == 0) {
        if (!need(e, a, 2, 2, usage) || (k = pick_orphan(e, v, n, a->v[2])) < 0) {
            free(v);
            return ED_HANDLED | ED_ERROR;
        }
        if (unlink(v[k].file) != 0) {
            flags = fail(e, "recover: cannot delete %s: %s", v[k].file, strerror(errno));
            free(v);
            return flags;
        }
        ed_msg(e, 0, "deleted %s (unsaved changes to %s)", v[k].file,
               v[k].path[0] ? v[k].path : "an untitled design");
        free(v);
        return ED_HANDLED | ED_REDRAW;
    }
    if (!need(e, a, 1, 1, usage) || (k = pick_orphan(e, v, n, a->v[1])) < 0) {
        free(v);
        return ED_HANDLED | ED_ERROR;
    }
    if (!may_discard(e, a, bang, &flags)) {
        free(v);
        return flags;
    }
    sys = sg_system_new();
    if (!sys) {
        free(v);
        return fail(e, "out of memory");
    }
    sg_diag_clear(&d);
    if (rec_read_file(v[k].file, &got, sys, &d) != SG_OK) {
        sg_system_free(sys);
        flags = fail(e, "recover: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
        free(v);
        return flags;
    }
    /* The recovered design keeps its file name, so save writes the file it
     * came from; it differs from that file until then. */
    free(v);
    doc_replace(&e->doc, sys, got.path[0] ? got.path : NULL, 1, &got.disk);
    snprintf(e->rec.adopted, sizeof e->rec.adopted, "%s", got.file);
    opened(e, "recovered");
    rec_time_text(got.time, when, sizeof when);
    if (got.path[0])
        ed_msg(e, 0, "recovered unsaved changes to %s from %s; save writes them there", got.path,
               when);
    else
        ed_msg(e, 0, "recovered an untitled design from %s; save FILE keeps it", when);
    return OK_VIEW;
}

/* ------------------------------------------------------------------------
 * Export and print
 * ------------------------------------------------------------------------ */

static int fmt_from_name(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (dot && strcasecmp(dot, ".csv") == 0)
        return REPORT_CSV;
    if (dot && strcasecmp(dot, ".json") == 0)
        return REPORT_JSON;
    return REPORT_TEXT;
}

static void meta_of(ed *e, report_meta *m)
{
    const char *p = doc_path(&e->doc);
    m->design = p ? p : (e->doc.sys->title[0] ? e->doc.sys->title : "(new design)");
    m->method = sg_method_name(e->method);
    m->bits = e->method == SG_METHOD_MPFR ? e->bits : 0;
    m->wave_um = e->doc.sys->wave[e->wave].um;
    m->wave_index = e->wave + 1;
    m->opd = 0;
    m->global = e->global >= 0;
    m->global_ref = e->global;
    /* Every surface's rows (trace --surface chooses some). */
    m->surfaces = NULL;
    m->nsurfaces = 0;
}

/* The rays of a set, made a block at a time so that a grid of a million
 * rays takes no more memory than one of a hundred: the current ray; a y or
 * x fan of n rays from -1 to 1 across the pupil at the current field; or
 * an n by n grid.  The grid divides the square around the pupil into n by
 * n equal cells and takes the centre of each, (2j + 1 - n) / n, keeping
 * those inside the pupil: every ray then stands for the same area (as a
 * spot diagram wants), grid 1 is the chief ray and grid 2 the four rays at
 * (+-0.5, +-0.5).  A grid of odd n holds the chief ray; the rim is the
 * fans' to sample. */
enum { SET_RAY, SET_FAN, SET_XFAN, SET_GRID };

typedef struct rayset {
    int kind, n;
    double hx, hy, px, py; /* the current ray */
    long next;             /* fan index, or grid cell i * n + j */
} rayset;

static int grid_point(const rayset *s, long cell, double *px, double *py)
{
    long i = cell / s->n, j = cell % s->n;
    *px = (2.0 * (double)j + 1.0 - s->n) / s->n;
    *py = (2.0 * (double)i + 1.0 - s->n) / s->n;
    return *px * *px + *py * *py <= 1.0;
}

static size_t rayset_next(rayset *s, sg_ray_in *r, size_t max)
{
    size_t k = 0;
    long end = s->kind == SET_RAY ? 1 : s->kind == SET_GRID ? (long)s->n * s->n : s->n;
    while (k < max && s->next < end) {
        double px, py;
        long i = s->next++;
        memset(&r[k], 0, sizeof r[k]);
        r[k].v[0] = s->hx;
        r[k].v[1] = s->hy;
        if (s->kind == SET_RAY) {
            px = s->px;
            py = s->py;
        } else if (s->kind == SET_GRID) {
            if (!grid_point(s, i, &px, &py))
                continue;
        } else {
            double t = s->n == 1 ? 0.0 : -1.0 + 2.0 * (double)i / (s->n - 1);
            px = s->kind == SET_XFAN ? t : 0.0;
            py = s->kind == SET_XFAN ? 0.0 : t;
        }
        r[k].v[2] = px;
        r[k].v[3] = py;
        k++;
    }
    return k;
}

static size_t rayset_count(const rayset *s)
{
    long c;
    size_t n = 0;
    double px, py;
    if (s->kind == SET_RAY)
        return 1;
    if (s->kind != SET_GRID)
        return (size_t)s->n;
    for (c = 0; c < (long)s->n * s->n; c++)
        n += (size_t)grid_point(s, c, &px, &py);
    return n;
}

/* Exports larger than this ask first (batch mode: need export!). */
#define EXPORT_ASK_BYTES 100e6

static void human_size(double b, char *buf, size_t n)
{
    if (b >= 1e9)
        snprintf(buf, n, "%.1f GB", b / 1e9);
    else if (b >= 1e6)
        snprintf(buf, n, "%.1f MB", b / 1e6);
    else if (b >= 1e3)
        snprintf(buf, n, "%.0f kB", b / 1e3);
    else
        snprintf(buf, n, "%.0f bytes", b);
}

/* Bytes of the report of the first ray, written to memory: the size of an
 * export is about that times the number of rays. */
static double bytes_per_ray(const report_meta *m, report_fmt fmt, int nsurf,
                            const sg_ray_surface *out, const int *status, const sg_ray_in *ray,
                            int multi)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    report_stream rs;
    double b = 0.0;
    if (!f)
        return 0.0;
    if (report_begin(&rs, f, fmt, m, nsurf, SG_RAYS_NORMALIZED, multi, 1) == 0) {
        size_t head;
        fflush(f);
        head = len;
        report_rays(&rs, out, status, 1, ray);
        fflush(f);
        b = (double)(len - head);
    }
    fclose(f);
    free(buf);
    return b;
}

static int export_picture(ed *e, args *a, const char *path, int format, int bang);

/* What an export would replace at path. */
enum { EXPORT_NEW = 0, EXPORT_REPLACES, EXPORT_OWN };

/* The open design's file, whatever the name (device and inode), is never
 * an export's target; another regular file is replaced only when asked.  A
 * device or pipe (/dev/null) holds nothing to lose. */
static int export_target(ed *e, const char *path)
{
    struct stat t, own;
    const char *dp = doc_path(&e->doc);
    if (strcmp(path, "-") == 0 || stat(path, &t) != 0)
        return EXPORT_NEW;
    if (dp && stat(dp, &own) == 0 && own.st_dev == t.st_dev && own.st_ino == t.st_ino)
        return EXPORT_OWN;
    /* The file as the design was read, should its name now lead elsewhere. */
    if (e->doc.disk.have && e->doc.disk.dev == (unsigned long long)t.st_dev &&
        e->doc.disk.ino == (unsigned long long)t.st_ino)
        return EXPORT_OWN;
    return S_ISREG(t.st_mode) ? EXPORT_REPLACES : EXPORT_NEW;
}

static int export_own_file(ed *e, const char *path)
{
    return fail(e, "export: %s is the open design's file; not written (export to another "
                   "name)", path);
}

/* Asks the question (yes runs the same export with "!"); in batch mode,
 * where nobody can answer, fails naming export!. */
static int export_ask(ed *e, args *a, const char *path, const char *what)
{
    char q[ED_LINE / 2];
    size_t len;
    int i;
    if (e->batch)
        return fail(e, "export: %s; not written (export! %s replaces it)", what, path);
    snprintf(e->pending, sizeof e->pending, "export!");
    for (i = 1; i < a->n; i++) {
        cmd_quote(a->v[i], q, sizeof q);
        len = strlen(e->pending);
        snprintf(e->pending + len, sizeof e->pending - len, " %s", q);
    }
    snprintf(e->question, sizeof e->question, "export: %.900s. Replace it? (y)es (n)o", what);
    e->confirm = CONFIRM_WRITE;
    ed_msg(e, 0, "export: %s", what);
    return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
}

static int c_export_any(ed *e, args *a, int bang)
{
    const char *usage = "export FILE [csv|json|text|hdf5] [ray | fan [N] | xfan [N] | grid N] | "
                        "export FILE png|svg|pdf";
    const char *path, *set = "ray";
    int fmt = -1, n = 0, i, rc, tostd, nsurf, multi, err;
    size_t nray, block, got, done = 0;
    sg_ray_in *rays = NULL;
    sg_ray_surface *out = NULL;
    int *status = NULL;
    sg_batch *b = NULL;
    sg_tracer *rt = NULL;
    sg_opd *opd = NULL;
    sg_opd_ref ref;
    sg_diag d;
    report_meta m;
    report_stream rs;
    rayset rset;
    const sg_frame *gf = NULL; /* ed_global_frames', not freed here */
    outfile of;
    int flags, hdf5 = 0, target;
    h5rays *h5 = NULL;
    char size[32], h5err[256];

    if (a->n < 2) {
        if (e->batch)
            return fail(e, "usage: %s", usage);
        snprintf(e->prompt_init, sizeof e->prompt_init, "export ");
        return ED_HANDLED | ED_PROMPT;
    }
    path = a->v[1];
    /* A picture format (named, or the file's extension) writes the view. */
    {
        int pf = a->n > 2 ? plot_file_format(a->v[2]) : -1;
        const char *dot = strrchr(path, '.');
        if (pf < 0 && a->n == 2 && dot)
            pf = plot_file_format(dot + 1);
        if (pf >= 0) {
            if (a->n > 3)
                return fail(e, "export: a picture takes no ray set; usage: export FILE "
                               "[png|svg|pdf]");
            return export_picture(e, a, path, pf, bang);
        }
    }
    target = export_target(e, path);
    if (target == EXPORT_OWN)
        return export_own_file(e, path);
    for (i = 2; i < a->n; i++) {
        int f2 = report_parse_fmt(a->v[i]);
        if (f2 < 0 && strcasecmp(a->v[i], "txt") == 0)
            f2 = REPORT_TEXT;
        if (strcasecmp(a->v[i], "hdf5") == 0) {
            hdf5 = 1;
        } else if (f2 >= 0) {
            fmt = f2;
        } else if (strcmp(a->v[i], "ray") == 0 || strcmp(a->v[i], "fan") == 0 ||
                   strcmp(a->v[i], "xfan") == 0 || strcmp(a->v[i], "grid") == 0) {
            set = a->v[i];
            if (i + 1 < a->n && isdigit((unsigned char)a->v[i + 1][0])) {
                if (!parse_int(e, a->v[++i], set, 1, 1001, &n))
                    return ED_HANDLED | ED_ERROR;
            }
        } else {
            return fail(e, "export: \"%s\" is not a format or a ray set; usage: %s",
                        a->v[i], usage);
        }
    }
    if (strcmp(set, "grid") == 0 && n == 0)
        return fail(e, "export: grid needs a size, e.g. grid 11");
    if (n == 0)
        n = 11;
    {
        const char *dot = strrchr(path, '.');
        if (fmt < 0 && dot && (strcasecmp(dot, ".h5") == 0 || strcasecmp(dot, ".hdf5") == 0))
            hdf5 = 1;
    }
    if (fmt < 0)
        fmt = fmt_from_name(path);
    tostd = strcmp(path, "-") == 0;
    if (tostd && !e->batch)
        return fail(e, "export: \"-\" (standard output) works only in batch mode");
    /* HDF5 seeks about its file, as in sagitta trace. */
    if (tostd && hdf5)
        return fail(e, "export: an HDF5 table needs a file, not \"-\"");
    if (hdf5)
        fmt = REPORT_CSV; /* for the size estimate: about the same bytes */

    ed_opts(e);
    if (e->global >= 0) {
        sg_diag gd;
        sg_diag_clear(&gd);
        if (!(gf = ed_global_frames(e, e->global, &gd)))
            return fail(e, "export: global frame: %s", gd.msg);
    }
    memset(&rset, 0, sizeof rset);
    rset.kind = strcmp(set, "ray") == 0    ? SET_RAY
                : strcmp(set, "fan") == 0  ? SET_FAN
                : strcmp(set, "xfan") == 0 ? SET_XFAN
                                           : SET_GRID;
    rset.n = n;
    rset.hx = e->ray[0];
    rset.hy = e->ray[1];
    rset.px = e->ray[2];
    rset.py = e->ray[3];
    nray = rayset_count(&rset);
    if (nray == 0)
        return fail(e, "export: the ray set is empty");
    multi = nray != 1;
    nsurf = e->doc.sys->nsurf;
    /* About 16 MiB of rows a block, and blocks small enough that progress
     * and Esc are seen often. */
    block = ((size_t)16 << 20) / ((size_t)nsurf * sizeof *out);
    block = block < 16 ? 16 : block > 4096 ? 4096 : block;
    rays = malloc(block * sizeof *rays);
    out = malloc(block * (size_t)nsurf * sizeof *out);
    status = malloc(block * sizeof *status);
    if (!rays || !out || !status) {
        flags = fail(e, "out of memory: %zu rays of %d surfaces", block, nsurf);
        goto done;
    }
    sg_diag_clear(&d);
    b = sg_batch_new(e->doc.sys, e->cat, &e->opts, 0, &d);
    if (!b) {
        flags = fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
        goto done;
    }
    meta_of(e, &m);
    /* Each row says which ray it is, the single ray's as a fan's. */
    m.csv_inputs = 1;
    /* Every ray's OPD, as sagitta trace writes it, from a tracer of the
     * batch's options for the reference spheres. */
    opd = malloc(block * sizeof *opd);
    rt = sg_tracer_new(e->doc.sys, e->cat, &e->opts, &d);
    if (!opd || !rt) {
        flags = fail(e, "export: %s", rt ? "out of memory" : d.msg[0] ? d.msg : sg_strerror(d.code));
        goto done;
    }
    m.opd = 1;
    memset(&ref, 0, sizeof ref);
    ref.status = SG_EINVAL;

    got = rayset_next(&rset, rays, block);
    rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, got, NULL, 0, out, status, &d);
    if (rc != SG_EOK) {
        flags = fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(rc));
        goto done;
    }
    {
        double est = bytes_per_ray(&m, (report_fmt)fmt, nsurf, out, status, rays, multi) *
                     (double)nray;
        human_size(est, size, sizeof size);
        if (target == EXPORT_REPLACES && !bang && est <= EXPORT_ASK_BYTES) {
            char what[ED_LINE];
            snprintf(what, sizeof what, "%.900s already exists", path);
            flags = export_ask(e, a, path, what);
            goto done;
        }
        if (est > EXPORT_ASK_BYTES && !bang && !tostd) {
            char q[ED_LINE / 2];
            size_t len;
            if (e->batch) {
                flags = fail(e, "export: %s would take about %s (%zu rays); use export! "
                                "to write it",
                             path, size, nray);
                goto done;
            }
            snprintf(e->pending, sizeof e->pending, "export!");
            for (i = 1; i < a->n; i++) {
                cmd_quote(a->v[i], q, sizeof q);
                len = strlen(e->pending);
                snprintf(e->pending + len, sizeof e->pending - len, " %s", q);
            }
            snprintf(e->question, sizeof e->question,
                     target == EXPORT_REPLACES
                         ? "export: %zu rays, about %s, to %s, which exists. Replace it? (y)es "
                           "(n)o"
                         : "export: %zu rays, about %s, to %s. Write it? (y)es (n)o",
                     nray, size, path);
            e->confirm = CONFIRM_WRITE;
            flags = ED_HANDLED | ED_CONFIRM | ED_REDRAW;
            goto done;
        }
    }
    if (hdf5) {
        /* The same table as sagitta trace --format hdf5, OPD included. */
        h5 = h5rays_open(path, &m, e->doc.sys->units, nsurf, SG_RAYS_NORMALIZED,
                         got * (size_t)nsurf, h5err, sizeof h5err);
        if (!h5) {
            flags = fail(e, "export: %s: %s", path, h5err);
            goto done;
        }
    } else {
        err = outfile_open(&of, tostd ? NULL : path, e->out);
        if (err != 0) {
            flags = fail(e, "export: %s: %s", path, strerror(err));
            goto done;
        }
        if (report_begin(&rs, of.f, (report_fmt)fmt, &m, nsurf, SG_RAYS_NORMALIZED, multi,
                         nray) != 0)
            goto write_error;
    }
    if (e->progress)
        e->progress(e->progress_ctx, path, 0, nray);
    for (;;) {
        report_opd_block(rt, &ref, rays, got, out, nsurf, opd);
        /* :global: after the OPD, which is taken in the image's own frame. */
        if (gf)
            sg_rows_to_global(gf, out, got, nsurf, 0);

        if (h5) {
            if (h5rays_write(h5, out, status, got, rays, opd, h5err, sizeof h5err) != 0) {
                flags = fail(e, "export: %s: %s", path, h5err);
                goto done;
            }
        } else if (report_rays_opd(&rs, out, status, got, rays, opd) != 0)
            goto write_error;
        done += got;
        if (e->progress && e->progress(e->progress_ctx, path, done, nray)) {
            if (h5) {
                h5rays_abort(h5);
                h5 = NULL;
            } else
                outfile_abort(&of);
            ed_msg(e, 0, "export cancelled after %zu of %zu rays; %s not written", done,
                   nray, path);
            flags = ED_HANDLED | ED_REDRAW;
            goto done;
        }
        got = rayset_next(&rset, rays, block);
        if (got == 0)
            break;
        rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, got, NULL, 0, out, status, &d);
        if (rc != SG_EOK) {
            if (!h5)
                outfile_abort(&of);
            flags = fail(e, "export: %s", d.msg[0] ? d.msg : sg_strerror(rc));
            goto done;
        }
    }
    if (h5) {
        rc = h5rays_close(h5, h5err, sizeof h5err);
        h5 = NULL;
        if (rc != 0) {
            flags = fail(e, "export: %s: %s", path, h5err);
            goto done;
        }
    } else {
        if (report_end(&rs) != 0)
            goto write_error;
        err = outfile_commit(&of);
        if (err != 0) {
            flags = fail(e, "export: %s: %s", path, strerror(err));
            goto done;
        }
    }
    ed_msg(e, 0, "exported %zu ray%s (%s) to %s", nray, nray == 1 ? "" : "s", size,
           tostd ? "standard output" : path);
    flags = ED_HANDLED | ED_REDRAW;
    goto done;
write_error:
    err = errno;
    outfile_abort(&of);
    flags = fail(e, "export: %s: %s", path, strerror(err));
done:
    h5rays_abort(h5);
    sg_batch_free(b);
    sg_tracer_free(rt);
    free(opd);
    free(rays);
    free(out);
    free(status);
    return flags;
}

static int c_export(ed *e, args *a)
{
    return c_export_any(e, a, 0);
}

static int c_export1(ed *e, args *a)
{
    return c_export_any(e, a, 1);
}

static int c_print(ed *e, args *a)
{
    char buf[ED_LINE];
    const char *what = a->n > 1 ? a->v[1] : "ray";
    report_meta m;
    if (strcmp(what, "cell") == 0) {
        int row, col;
        if (!need(e, a, 3, 3, "print cell SURFACE COLUMN") ||
            !parse_row(e, a->v[2], 0, e->doc.sys->nsurf - 1, &row))
            return ED_HANDLED | ED_ERROR;
        col = cell_parse_name(a->v[3]);
        if (col < 0)
            return fail(e, "no column \"%s\"", a->v[3]);
        cell_text(e->doc.sys, row, col, buf, sizeof buf);
        if (e->batch)
            fprintf(e->out, "%s\n", buf);
        ed_msg(e, 0, "surface %d %s: %s", row, cell_name(col), buf);
        return ED_HANDLED | ED_REDRAW;
    }
    if (strcmp(what, "ray") != 0 && strcmp(what, "paraxial") != 0)
        return fail(e, "usage: print ray | paraxial | cell SURFACE COLUMN");
    ed_recompute(e);
    if (strcmp(what, "paraxial") == 0 && !e->batch)
        return ED_HANDLED | ED_SHOW_SYSDATA;
    if (strcmp(what, "paraxial") == 0 && !e->cmp.par_ok)
        return fail(e, "no paraxial data: %s", e->cmp.build_msg);
    if (strcmp(what, "paraxial") != 0 && !e->cmp.have)
        return fail(e, "no trace: %s", e->cmp.build_msg);
    if (!e->batch) {
        const sg_ray_surface *r = &e->cmp.res[e->row];
        char x[NUMFMT_MAX], y[NUMFMT_MAX], z[NUMFMT_MAX];
        numfmt_shortest(r->x, x, sizeof x);
        numfmt_shortest(r->y, y, sizeof y);
        numfmt_shortest(r->z, z, sizeof z);
        ed_msg(e, 0, "surface %d: x %s  y %s  z %s", e->row, x, y, z);
        return ED_HANDLED | ED_REDRAW;
    }
    meta_of(e, &m);
    if (strcmp(what, "paraxial") == 0) {
        /* At the primary wavelength, as "sagitta paraxial" computes it. */
        m.wave_um = e->doc.sys->wave[e->doc.sys->primary_wave].um;
        m.wave_index = e->doc.sys->primary_wave + 1;
        report_write_paraxial(e->out, REPORT_TEXT, &m, &e->cmp.par);
    }
    else
        report_write(e->out, REPORT_TEXT, &m, e->cmp.nsurf, e->cmp.res, &e->cmp.rc, 1,
                     SG_RAYS_NORMALIZED, NULL);
    fflush(e->out);
    return ED_HANDLED;
}

/* ------------------------------------------------------------------------
 * The ray and the trace options (not part of the design)
 * ------------------------------------------------------------------------ */

static int ray_msg(ed *e)
{
    char s[4][NUMFMT_MAX];
    int i;
    for (i = 0; i < 4; i++)
        numfmt_shortest(e->ray[i], s[i], sizeof s[i]);
    e->dirty = 1;
    ed_msg(e, 0, "ray Hx %s Hy %s Px %s Py %s", s[0], s[1], s[2], s[3]);
    return OK_VIEW;
}

static int c_ray(ed *e, args *a)
{
    double v[4];
    int i, bad;
    if (a->n == 2) {
        int rc = args_double_list(a->v[1], 0, v, 4, &bad);
        if (rc != ARGS_OK)
            return fail(e, "ray: \"%s\": %s; give Hx,Hy,Px,Py", a->v[1], args_strerror(rc));
    } else {
        if (!need(e, a, 4, 4, "ray HX HY PX PY"))
            return ED_HANDLED | ED_ERROR;
        for (i = 0; i < 4; i++)
            if (!parse_num(e, a->v[i + 1], "ray", &v[i]))
                return ED_HANDLED | ED_ERROR;
    }
    memcpy(e->ray, v, sizeof v);
    return ray_msg(e);
}

static int c_raycoord(ed *e, args *a)
{
    static const char *const n[] = {"hx", "hy", "px", "py"};
    int i;
    double v;
    for (i = 0; i < 4; i++)
        if (strcasecmp(a->v[0], n[i]) == 0)
            break;
    if (!need(e, a, 1, 1, "hx|hy|px|py VALUE") || !parse_num(e, a->v[1], n[i], &v))
        return ED_HANDLED | ED_ERROR;
    e->ray[i] = v;
    return ray_msg(e);
}

static int c_chief(ed *e, args *a)
{
    e->ray[2] = e->ray[3] = 0.0;
    return ray_msg(e);
}

static int c_marginal(ed *e, args *a)
{
    static const struct {
        const char *n1, *n2;
        double px, py;
    } m[] = {
        {"top", "+y", 0, 1}, {"bottom", "-y", 0, -1}, {"right", "+x", 1, 0}, {"left", "-x", -1, 0},
    };
    size_t i;
    if (!need(e, a, 1, 1, "marginal top|bottom|left|right"))
        return ED_HANDLED | ED_ERROR;
    for (i = 0; i < 4; i++)
        if (strcasecmp(a->v[1], m[i].n1) == 0 || strcasecmp(a->v[1], m[i].n2) == 0) {
            e->ray[2] = m[i].px;
            e->ray[3] = m[i].py;
            return ray_msg(e);
        }
    return fail(e, "marginal: \"%s\" is not top, bottom, left or right", a->v[1]);
}

static int c_wave(ed *e, args *a)
{
    const sg_system *s = e->doc.sys;
    int k;
    double um;
    if (!need(e, a, 1, 1, "wave N|UM|LINE"))
        return ED_HANDLED | ED_ERROR;
    if (args_int(a->v[1], INT_MIN, INT_MAX, &k) != ARGS_OK) {
        /* Not a number of the list: a wavelength in um or a line's letter,
         * which must be one of the design's (a trace is at one of them). */
        char list[512];
        size_t len = 0;
        int i;
        if (!parse_um(e, a->v[1], &um))
            return fail(e, "wave: \"%s\" is not a wavelength number (1 to %d), a wavelength "
                           "in um or a line (F, d, C ...)", a->v[1], s->nwave);
        for (i = 0; i < s->nwave; i++)
            if (fabs(s->wave[i].um - um) <= 1e-9 * um)
                break;
        if (i == s->nwave) {
            for (k = 0; k < s->nwave && len + 32 < sizeof list; k++)
                len += (size_t)snprintf(list + len, sizeof list - len, "%s%d: %.10g", k ? ", " : "",
                                        k + 1, s->wave[k].um);
            return fail(e, "wave: %.10g um is not a wavelength of the design (%s um); "
                           ":wavelength add %s adds it", um, list, a->v[1]);
        }
        k = i + 1;
    } else if (!parse_int(e, a->v[1], "wavelength", 1, s->nwave, &k)) {
        return ED_HANDLED | ED_ERROR;
    }
    e->wave = k - 1;
    e->dirty = 1;
    ed_msg(e, 0, "tracing at wavelength %d (%.10g um)", k, e->doc.sys->wave[k - 1].um);
    return OK_VIEW;
}

#define BITS_MIN 53
#define BITS_MAX 100000

static int c_method(ed *e, args *a)
{
    int m, bits = e->bits;
    if (!need(e, a, 1, 2, "method precise|classic|mpfr [BITS]"))
        return ED_HANDLED | ED_ERROR;
    m = sg_method_parse(a->v[1]);
    if (m < 0)
        return fail(e, "method: \"%s\" is not precise, classic or mpfr", a->v[1]);
    if (a->n > 2 && !parse_int(e, a->v[2], "mpfr bits", BITS_MIN, BITS_MAX, &bits))
        return ED_HANDLED | ED_ERROR;
    e->method = (sg_method)m;
    e->bits = bits;
    e->dirty = 1;
    if (m == SG_METHOD_MPFR)
        ed_msg(e, 0, "method mpfr, %d bits", bits);
    else
        ed_msg(e, 0, "method %s", sg_method_name((sg_method)m));
    return OK_VIEW;
}

static int c_bits(ed *e, args *a)
{
    int bits;
    if (!need(e, a, 1, 1, "bits N") ||
        !parse_int(e, a->v[1], "mpfr bits", BITS_MIN, BITS_MAX, &bits))
        return ED_HANDLED | ED_ERROR;
    e->bits = bits;
    e->dirty = 1;
    ed_msg(e, 0, "mpfr precision %d bits", bits);
    return OK_VIEW;
}

static int c_digits(ed *e, args *a)
{
    int on;
    if (!need(e, a, 0, 1, "digits [on|off|toggle]") ||
        !parse_onoff(e, a, e->digits, &on, "digits"))
        return ED_HANDLED | ED_ERROR;
    e->digits = on;
    e->dirty = 1;
    ed_msg(e, 0, "digits of agreement with mpfr %s", on ? "on" : "off");
    return OK_VIEW;
}

static int c_clip(ed *e, args *a)
{
    int on;
    if (!need(e, a, 0, 1, "clip [on|off|toggle]") ||
        !parse_onoff(e, a, e->clip, &on, "clip"))
        return ED_HANDLED | ED_ERROR;
    e->clip = on;
    e->dirty = 1;
    ed_msg(e, 0, "vignetting at fixed semi-diameters %s", on ? "on" : "off");
    return OK_VIEW;
}

static int c_global(ed *e, args *a)
{
    const char *usage = "global [on|off|SURFACE]";
    int ref;
    if (!need(e, a, 0, 1, usage))
        return ED_HANDLED | ED_ERROR;
    if (a->n < 2 || strcasecmp(a->v[1], "toggle") == 0)
        ref = e->global >= 0 ? -1 : 1;
    else if (strcasecmp(a->v[1], "on") == 0)
        ref = 1;
    else if (strcasecmp(a->v[1], "off") == 0)
        ref = -1;
    else if (args_int(a->v[1], 0, e->doc.sys->nsurf - 1, &ref) != ARGS_OK)
        return fail(e, "global: \"%s\" is not on, off or a surface from 0 to %d", a->v[1],
                    e->doc.sys->nsurf - 1);
    if (ref >= 0) {
        sg_diag d;
        sg_diag_clear(&d);
        if (!ed_global_frames(e, ref, &d))
            return fail(e, "global: %s", d.msg);
    }
    e->global = ref;
    e->dirty = 1;
    if (ref >= 0)
        ed_msg(e, 0, "rows in the global frame of surface %d", ref);
    else
        ed_msg(e, 0, "rows in each surface's local frame");
    return OK_VIEW;
}

static int c_view(ed *e, args *a)
{
    const char *usage = "view layout|spot|fan|opd|wave|off|next";
    int k;
    if (!need(e, a, 0, 1, usage))
        return ED_HANDLED | ED_ERROR;
    if (a->n < 2 || strcasecmp(a->v[1], "next") == 0)
        k = (e->view.kind + 1) % VIEW_COUNT;
    else if ((k = view_parse(a->v[1])) < 0)
        return fail(e, "view: \"%s\" is not one of layout, spot, fan, opd, wave, off, next", a->v[1]);
    e->view.kind = k;
    e->dirty = 1;
    if (k == VIEW_OFF)
        ed_msg(e, 0, "view off: the ray's table is back");
    else
        ed_msg(e, 0, "view %s (g: next view; export FILE.png|svg|pdf writes it)",
               view_name(k));
    return OK_VIEW;
}

/* Writes the view on show as a picture (format: plot.h's PLOT_*). */
static int export_picture(ed *e, args *a, const char *path, int format, int bang)
{
    outfile of;
    char msg[256];
    int err, rc, target;
    if (e->view.kind == VIEW_OFF)
        return fail(e, "export: no view on show to draw; choose one with g or "
                       ":view layout|spot|fan|opd|wave");
    if (strcmp(path, "-") == 0 && !e->batch)
        return fail(e, "export: \"-\" (standard output) works only in batch mode");
    target = export_target(e, path);
    if (target == EXPORT_OWN)
        return export_own_file(e, path);
    if (target == EXPORT_REPLACES && !bang) {
        snprintf(msg, sizeof msg, "%.200s already exists", path);
        return export_ask(e, a, path, msg);
    }
    ed_opts(e);
    rc = edview_update(&e->view, e->doc.sys, e->doc.id, e->cat, &e->opts, ed_view_field(e));
    if (rc != SG_EOK || !e->view.have_fig)
        return fail(e, "export: %s", e->view.msg[0] ? e->view.msg : sg_strerror(rc));
    if ((err = outfile_open(&of, strcmp(path, "-") == 0 ? NULL : path, e->out ? e->out : stdout)))
        return fail(e, "export: %s: %s", path, strerror(err));
    if (plot_write(&e->view.fig, format, 1000, 750, of.f, msg, sizeof msg)) {
        outfile_abort(&of);
        return fail(e, "export: %s: %s", path, msg);
    }
    if ((err = outfile_commit(&of)))
        return fail(e, "export: %s: %s", path, strerror(err));
    ed_msg(e, 0, "exported the %s view to %s", view_name(e->view.kind), path);
    return ED_HANDLED | ED_REDRAW;
}

static int c_goto(ed *e, args *a)
{
    int row;
    if (!need(e, a, 1, 2, "goto SURFACE [COLUMN]") ||
        !parse_row(e, a->v[1], 0, e->doc.sys->nsurf - 1, &row))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 2) {
        int col = cell_parse_name(a->v[2]);
        if (col < 0)
            return fail(e, "no column \"%s\"", a->v[2]);
        e->col = col;
    }
    e->row = row;
    e->msg[0] = '\0';
    return ED_HANDLED | ED_REDRAW;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static int c_bench(ed *e, args *a)
{
    int n = 20, i;
    double *t, t0;
    if (!need(e, a, 0, 1, "bench [N]") ||
        (a->n > 1 && !parse_int(e, a->v[1], "count", 1, 100000, &n)))
        return ED_HANDLED | ED_ERROR;
    t = malloc((size_t)n * sizeof *t);
    if (!t)
        return fail(e, "out of memory");
    for (i = 0; i < n; i++) {
        /* What a keystroke costs: the tracers rebuilt, the ray traced. */
        compute_invalidate(&e->cmp);
        t0 = compute_now_ms();
        ed_recompute(e);
        t[i] = compute_now_ms() - t0;
    }
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    ed_msg(e, 0,
           "recompute of %d surfaces (%s%s): %d runs, min %.3f ms, median %.3f ms, max %.3f ms%s",
           e->doc.sys->nsurf, sg_method_name(e->method), e->digits ? " + mpfr digits" : "", n,
           t[0], t[n / 2], t[n - 1], e->cmp.have ? "" : " (no trace: the design is invalid)");
    free(t);
    if (e->batch)
        fprintf(e->out, "%s\n", e->msg);
    return OK_VIEW;
}

/* ------------------------------------------------------------------------
 * The table
 * ------------------------------------------------------------------------ */

typedef int (*handler)(ed *, args *);

typedef struct command {
    const char *name;
    const char *alias;
    handler fn;
    const char *usage;
    const char *help;
} command;

static int c_open0(ed *e, args *a) { return c_open(e, a, 0); }
static int c_open1(ed *e, args *a) { return c_open(e, a, 1); }
static int c_new0(ed *e, args *a) { return c_new(e, a, 0); }
static int c_new1(ed *e, args *a) { return c_new(e, a, 1); }
static int c_example0(ed *e, args *a) { return c_example(e, a, 0); }
static int c_example1(ed *e, args *a) { return c_example(e, a, 1); }
static int c_recover0(ed *e, args *a) { return c_recover(e, a, 0); }
static int c_recover1(ed *e, args *a) { return c_recover(e, a, 1); }
static int c_quit0(ed *e, args *a) { return c_quit(e, a, 0); }
static int c_quit1(ed *e, args *a) { return c_quit(e, a, 1); }
static int c_help(ed *e, args *a);
static int c_settings(ed *e, args *a) { return ED_HANDLED | ED_SHOW_SETTINGS; }
static int c_redraw(ed *e, args *a) { return ED_HANDLED | ED_REDRAW; }
/* The messages so far, whole: on the screen a page of them, in batch mode
 * on standard output. */
static int c_messages(ed *e, args *a)
{
    int i;
    if (!e->batch)
        return ED_HANDLED | ED_SHOW_MESSAGES;
    for (i = 0; i < e->nhist; i++)
        fprintf(e->out, "%s\n", e->hist[i] + 1);
    return ED_HANDLED;
}
static int c_sysdata(ed *e, args *a)
{
    args b = *a;
    b.n = 2;
    b.v[1] = (char *)"paraxial";
    return c_print(e, &b);
}

static const command commands[] = {
    {"set", NULL, c_set, "set SURFACE COLUMN VALUE",
     "set a cell; COLUMN is type comment radius thickness material semi conic a2..a16 "
     "aperture ap_rmin ap_rmax ap_xhalf ap_yhalf ap_xdec ap_ydec or fixed; SURFACE may be "
     "obj, ima, stop or ."},
    {"insert", "i", c_insert, "insert [SURFACE]", "insert a flat air surface before SURFACE"},
    {"delete", "d", c_delete, "delete [SURFACE]", "delete a surface"},
    {"stop", NULL, c_stop, "stop [SURFACE]", "make a surface the aperture stop"},
    {"solve", NULL, c_solve,
     "solve SURFACE radius|thickness|conic TYPE [ARGS]",
     "set a solve: none, pickup FROM [SCALE [OFFSET]], marginal_height H, chief_height H "
     "or position FROM L (thickness), curvature_pickup FROM [SCALE [OFFSET]], marginal_angle U "
     "or fnum F (radius), variable [MIN MAX] (any)"},
    {"var", NULL, c_var, "var SURFACE radius|thickness|conic [MIN MAX]",
     "make a value a variable of the optimizer (V), optionally bounded"},
    {"novar", NULL, c_novar, "novar SURFACE radius|thickness|conic | novar all",
     "clear a variable, or every one"},
    {"opt", NULL, c_opt, "opt [CYCLES]",
     "damped least squares on the variables against the merit function (one undo step)"},
    {"undo", "u", c_undo, "undo [N]", "undo the last change(s)"},
    {"redo", NULL, c_redo, "redo [N]", "redo undone change(s)"},
    {"open", "e", c_open0, "open FILE", "open a design (open! discards changes)"},
    {"open!", "e!", c_open1, "open! FILE", "open a design, discarding unsaved changes"},
    {"new", NULL, c_new0, "new [FILE]", "start a new design"},
    {"new!", NULL, c_new1, "new! [FILE]", "start a new design, discarding changes"},
    {"example", "examples", c_example0, "example [NAME]",
     "open a bundled example; without NAME list them"},
    {"example!", NULL, c_example1, "example! NAME", "open an example, discarding changes"},
    {"save", "w", c_save, "save [FILE]",
     "save; with FILE, save as FILE (asks before replacing another file or one changed on "
     "disk)"},
    {"save!", "w!", c_save1, "save! [FILE]", "save, replacing FILE or changes on disk"},
    {"saveas", NULL, c_save, "saveas FILE", "save under a new name"},
    {"wq", "x", c_wq, "wq [FILE]", "save and quit"},
    {"wq!", "x!", c_wq1, "wq! [FILE]", "save and quit, replacing FILE or changes on disk"},
    {"recover", NULL, c_recover0, "recover [list | N | FILE | delete N|FILE]",
     "list the recovery files of editors that died, load one, or delete one"},
    {"recover!", NULL, c_recover1, "recover! N|FILE", "load a recovery file, discarding changes"},
    {"quit", "q", c_quit0, "quit", "quit (asks about unsaved changes)"},
    {"quit!", "q!", c_quit1, "quit!", "quit, discarding unsaved changes"},
    {"export", NULL, c_export, "export FILE [csv|json|text|hdf5] [ray|fan N|xfan N|grid N]",
     "write the ray table of the current ray or a ray set"},
    {"export!", NULL, c_export1, "export! FILE ...", "export without asking about its size or a file it replaces"},
    {"print", NULL, c_print, "print [ray|paraxial|cell SURFACE COLUMN]",
     "show a result (batch: on standard output; paraxial: the system data view)"},
    {"sysdata", NULL, c_sysdata, "sysdata",
     "the system data: what sagitta paraxial prints (F3)"},
    {"ray", NULL, c_ray, "ray HX HY PX PY", "choose the ray (also HX,HY,PX,PY)"},
    {"hx", NULL, c_raycoord, "hx VALUE", "set the normalized field x"},
    {"hy", NULL, c_raycoord, "hy VALUE", "set the normalized field y"},
    {"px", NULL, c_raycoord, "px VALUE", "set the normalized pupil x"},
    {"py", NULL, c_raycoord, "py VALUE", "set the normalized pupil y"},
    {"chief", NULL, c_chief, "chief", "the chief ray of the current field (Px = Py = 0)"},
    {"marginal", NULL, c_marginal, "marginal top|bottom|left|right",
     "a marginal ray of the current field"},
    {"wave", NULL, c_wave, "wave N|UM|LINE",
     "trace at wavelength N of the design (or the one of UM micrometres, or line F, d, C ...)"},
    {"method", NULL, c_method, "method precise|classic|mpfr [BITS]", "choose the trace method"},
    {"bits", NULL, c_bits, "bits N", "MPFR precision for the mpfr method and digits"},
    {"digits", NULL, c_digits, "digits [on|off]", "show agreement with an MPFR trace"},
    {"view", NULL, c_view, "view layout|spot|fan|opd|wave|off|next",
     "show an analysis below the sheet, live (g: next); export FILE.png|svg|pdf writes it"},
    {"clip", NULL, c_clip, "clip [on|off]", "vignette rays at fixed semi-diameters"},
    {"global", NULL, c_global, "global [on|off|SURFACE]",
     "rows in the global frame of SURFACE (on: 1, Zemax's reference) or each local frame"},
    {"wavelength", "wl", c_wavelength,
     "wavelength add UM [W] | set N UM [W] | delete N | primary N | move N TO | preset P",
     "edit the wavelengths; UM may be a line (F d C e g h i F' C' D r s t); presets FdC F'eC' d e"},
    {"field", NULL, c_field, "field N", "trace the ray at field N of the design (sets Hx, Hy)"},
    {"field", NULL, c_field,
     "field type T | norm radial|rect | add X Y [W] | set N X Y [W] | delete N | "
     "vignette N VDX VDY VCX VCY [VAN] | setvig | clearvig",
     "edit the fields; vignette sets Zemax's vignetting factors, setvig computes them "
     "from the apertures (Set Vignetting), clearvig clears them"},
    {"aperture", NULL, c_aperture, "aperture [epd|fnum|na|float|pwfnum|cone] [VALUE]",
     "set the system aperture"},
    {"aim", NULL, c_aim, "aim off|paraxial|real", "set ray aiming"},
    {"telecentric", NULL, c_telecentric, "telecentric on|off|toggle",
     "object space telecentric: the entrance pupil at infinity (object NA, height fields)"},
    {"temperature", NULL, c_temperature, "temperature CELSIUS",
     "set the system temperature (default 20)"},
    {"pressure", NULL, c_pressure, "pressure ATM", "set the air pressure (default 1)"},
    {"thermal", NULL, c_thermal, "thermal CELSIUS [ATM]",
     "the design as built at CELSIUS: radii, thicknesses, semi-diameters and shape terms "
     "expand by the glasses' and mounts' TCE (Zemax's thermal analysis; column tce), "
     "solves frozen"},
    {"semidiam", NULL, c_semidiam, "semidiam",
     "set every semi-diameter that is not fixed to Zemax's automatic one (the highest ray of "
     "the pupil's edge over fields and wavelengths), as one undoable edit"},
    {"adjust", NULL, c_adjust, "adjust on|off|toggle",
     "make glass indices follow temperature and pressure (Zemax's thermal model)"},
    {"glasses", NULL, c_glasses, "glasses [NAME | ND VD]",
     "find catalog glasses by name, or nearest by nd and vd"},
    {"pick", NULL, c_pick, "pick N", "make glass N of the last search the cursor's material"},
    {"title", NULL, c_title, "title TEXT", "set the design's title"},
    {"units", NULL, c_units, "units mm|cm|in|m", "set the lens units"},
    {"goto", "g", c_goto, "goto SURFACE [COLUMN]", "move the cursor"},
    {"bench", NULL, c_bench, "bench [N]", "time N live recomputes"},
    {"settings", NULL, c_settings, "settings", "open the system settings"},
    {"help", "h", c_help, "help", "list keys and commands"},
    {"messages", "mes", c_messages, "messages",
     "every message and warning shown so far, whole (as vim's :messages)"},
    {"redraw", NULL, c_redraw, "redraw", "repaint the screen"},
};

#define NCOMMANDS (sizeof commands / sizeof commands[0])

static int c_help(ed *e, args *a)
{
    size_t i;
    if (!e->batch)
        return ED_HANDLED | ED_SHOW_HELP;
    for (i = 0; i < NCOMMANDS; i++)
        fprintf(e->out, "%-58s %s\n", commands[i].usage, commands[i].help);
    return ED_HANDLED;
}

int cmd_count(void)
{
    return (int)NCOMMANDS;
}

const char *cmd_usage(int i)
{
    return i >= 0 && i < (int)NCOMMANDS ? commands[i].usage : NULL;
}

const char *cmd_help(int i)
{
    return i >= 0 && i < (int)NCOMMANDS ? commands[i].help : NULL;
}

const char *cmd_name(int i)
{
    return i >= 0 && i < (int)NCOMMANDS ? commands[i].name : NULL;
}

static int exec_line(ed *e, const char *line)
{
    args a;
    size_t i;
    while (isspace((unsigned char)*line) || *line == ':')
        line++;
    if (*line == '\0' || *line == '#')
        return ED_HANDLED;
    if (tokenize(line, &a) != 0)
        return fail(e, "cannot read the command: an unclosed quote, or too many words");
    for (i = 0; i < NCOMMANDS; i++)
        if (strcmp(a.v[0], commands[i].name) == 0 ||
            (commands[i].alias && strcmp(a.v[0], commands[i].alias) == 0))
            return commands[i].fn(e, &a);
    return fail(e, "unknown command \"%s\" (try help)", a.v[0]);
}

int cmd_exec(ed *e, const char *line)
{
    int f = exec_line(e, line);
    /* The history holds each command's message whole (:messages). */
    ed_msg_log(e);
    /* Every change reaches the recovery file here, before the editor
     * waits for the next key. */
    rec_sync(e, 0);
    return f;
}
