/*
 * cmd.c - the one command path.  Keys, the ':' line and batch scripts all
 * end up here, so every edit can be tested without a screen.  This file has
 * the tokenizer, the shared checks, the optimizer's commands and the table;
 * the other families live in cmd_edit.c, cmd_system.c, cmd_file.c,
 * cmd_export.c and cmd_ray.c, as sc-im splits its commands.
 */
#include "cmd_int.h"


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
void ec_rest_of(const args *a, int i, char *out, size_t n)
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

int ec_fail(ed *e, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    e->msg_err = 1;
    return ED_HANDLED | ED_ERROR | ED_REDRAW;
}

int ec_need(ed *e, const args *a, int lo, int hi, const char *usage)
{
    if (a->n - 1 < lo || a->n - 1 > hi) {
        ec_fail(e, "usage: %s", usage);
        return 0;
    }
    return 1;
}

/* A surface number, or obj / ima / stop / "." (the cursor's row). */
int ec_parse_row(ed *e, const char *s, int lo, int hi, int *row)
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
        ec_fail(e, "\"%s\" is not a surface number", s);
        return 0;
    }
    if (r < lo || r > hi) {
        if (lo > hi)
            ec_fail(e, "the design has too few surfaces");
        else
            ec_fail(e, "surface %d is not one of %d to %d", r, lo, hi);
        return 0;
    }
    *row = r;
    return 1;
}

int ec_parse_num(ed *e, const char *s, const char *what, double *v)
{
    int rc = args_double(s, 0, v);
    if (rc != ARGS_OK) {
        ec_fail(e, "%s: \"%s\": %s", what, s, args_strerror(rc));
        return 0;
    }
    return 1;
}

int ec_parse_int(ed *e, const char *s, const char *what, int lo, int hi, int *v)
{
    int rc = args_int(s, lo, hi, v);
    if (rc != ARGS_OK) {
        if (rc == ARGS_RANGE)
            ec_fail(e, "%s: %s is not in %d to %d", what, s, lo, hi);
        else
            ec_fail(e, "%s: \"%s\": %s", what, s, args_strerror(rc));
        return 0;
    }
    return 1;
}

/* on, off or toggle (also the default when s is NULL). */
int ec_parse_switch(ed *e, const char *s, int cur, int *out, const char *what)
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
    ec_fail(e, "%s: \"%s\" is not on, off or toggle", what, s);
    return 0;
}

int ec_parse_onoff(ed *e, const args *a, int cur, int *out, const char *what)
{
    return ec_parse_switch(e, a->n > 1 ? a->v[1] : NULL, cur, out, what);
}

/* ------------------------------------------------------------------------
 * Changes to the design: each is one undo step.
 * ------------------------------------------------------------------------ */

int ec_begin(ed *e, int row)
{
    if (doc_begin(&e->doc, row) != SG_EOK) {
        ec_fail(e, "out of memory: the change was not made");
        return 0;
    }
    return 1;
}

/* Ends a change and reports it; "unchanged" when the value was the same. */
int ec_end(ed *e, const char *fmt, ...)
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

int ec_cancel(ed *e, const char *msg)
{
    doc_cancel(&e->doc);
    return ec_fail(e, "%s", msg);
}

/* A parameter's name as var and novar take it: a key of the surface
 * table, with [ELEMENT] (from 0) for an array, e.g. asphere[1]. */
static int parse_pname(ed *e, const char *s, char *key, size_t n, int *elem)
{
    const char *br = strchr(s, '[');
    size_t len = br ? (size_t)(br - s) : strlen(s);
    *elem = 0;
    if (len == 0 || len >= n)
        return ec_fail(e, "'%s' is not a parameter name", s), 0;
    memcpy(key, s, len);
    key[len] = '\0';
    if (br) {
        char *end;
        long v = strtol(br + 1, &end, 10);
        if (end == br + 1 || strcmp(end, "]") != 0 || v < 0 || v > 1000)
            return ec_fail(e, "'%s': expected NAME[ELEMENT], the element a number from 0", s), 0;
        *elem = (int)v;
    }
    return 1;
}

/* var SURFACE NAME [MIN MAX]: the value becomes a variable of the
 * optimizer, Zemax's V (sagitta-design(5), SOLVES); NAME any real
 * parameter of the surface table (radius, conic, asphere[1], before.tx,
 * radius_x ...). */
int c_var(ed *e, args *a)
{
    static const char usage[] = "var SURFACE NAME [MIN MAX]";
    int row, elem;
    double lo = -INFINITY, hi = INFINITY;
    char key[64];
    sg_diag d;
    if (!ec_need(e, a, 2, 4, usage) || a->n == 4)
        return a->n == 4 ? ec_fail(e, "usage: %s", usage) : (ED_HANDLED | ED_ERROR);
    if (!ec_parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 1, &row) ||
        !parse_pname(e, a->v[2], key, sizeof key, &elem))
        return ED_HANDLED | ED_ERROR;
    if (a->n == 5 && (!ec_parse_num(e, a->v[3], "min", &lo) || !ec_parse_num(e, a->v[4], "max", &hi)))
        return ED_HANDLED | ED_ERROR;
    if (lo > hi)
        return ec_fail(e, "var: min %g is above max %g", lo, hi);
    if (!ec_begin(e, row))
        return ED_HANDLED | ED_ERROR;
    sg_diag_clear(&d);
    if (sg_variable_set(e->doc.sys, row, key, elem, 1, lo, hi, &d) != SG_OK)
        return ec_cancel(e, d.msg);
    e->row = row;
    return ec_end(e, "surface %d: the %s is a variable", row, a->v[2]);
}

/* novar SURFACE radius|thickness|conic, or novar all: clears variables. */
int c_novar(ed *e, args *a)
{
    sg_system *sys = e->doc.sys;
    int row, t, n = 0;
    if (a->n == 2 && strcasecmp(a->v[1], "all") == 0) {
        if (!ec_begin(e, e->row))
            return ED_HANDLED | ED_ERROR;
        for (row = 0; row < sys->nsurf; row++) {
            for (t = 0; t < SG_SOLVE_NTARGETS; t++)
                if (sys->surf[row].solve[t].kind == SG_SOLVE_VARIABLE) {
                    memset(&sys->surf[row].solve[t], 0, sizeof sys->surf[row].solve[t]);
                    n++;
                }
            n += sys->surf[row].nvar;
            sys->surf[row].nvar = 0;
        }
        return ec_end(e, "%d variable%s cleared", n, n == 1 ? "" : "s");
    }
    if (!ec_need(e, a, 2, 2, "novar SURFACE NAME | novar all"))
        return ED_HANDLED | ED_ERROR;
    {
        char key[64];
        int elem;
        sg_paddr pa;
        double lo, hi;
        if (!ec_parse_row(e, a->v[1], 0, sys->nsurf - 1, &row) ||
            !parse_pname(e, a->v[2], key, sizeof key, &elem))
            return ED_HANDLED | ED_ERROR;
        if (sg_paddr_make(sys, SG_SCOPE_SURFACE, row, key, elem, &pa, NULL) != SG_OK ||
            !sg_variable_bounds(sys, &pa, &lo, &hi))
            return ec_fail(e, "surface %d: the %s is not a variable", row, a->v[2]);
        if (!ec_begin(e, row))
            return ED_HANDLED | ED_ERROR;
        sg_variable_set(e->doc.sys, row, key, elem, 0, 0.0, 0.0, NULL);
    }
    e->row = row;
    return ec_end(e, "surface %d: the %s is no longer a variable", row, a->v[2]);
}

/* opt [CYCLES]: damped least squares on the variables against the merit
 * function, as one undoable change; stopped (e->opt_progress), it keeps
 * the best design so far, still one change. */
int c_opt(ed *e, args *a)
{
    sg_opt_opts o;
    sg_opt_result res;
    sg_diag d;
    int cycles = 0, rc;
    if (!ec_need(e, a, 0, 1, "opt [CYCLES]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n == 2 && !ec_parse_int(e, a->v[1], "cycles", 1, 1000000, &cycles))
        return ED_HANDLED | ED_ERROR;
    sg_opt_opts_init(&o);
    o.cycles = cycles;
    o.progress = e->opt_progress;
    o.ctx = e->progress_ctx;
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    sg_diag_clear(&d);
    rc = sg_optimize(e->doc.sys, e->cat, &o, &res, &d);
    if (rc != SG_OK)
        return ec_cancel(e, d.msg);
    if (res.stopped)
        return ec_end(e, "optimization stopped after %d cycle%s: merit %.6g (from %.6g), the best "
                      "so far; u undoes it", res.cycles, res.cycles == 1 ? "" : "s", res.merit,
                      res.merit0);
    return ec_end(e, "optimized: merit %.6g (from %.6g) after %d cycle%s%s", res.merit, res.merit0,
               res.cycles, res.cycles == 1 ? "" : "s", res.converged ? ", converged" : "");
}

/* config [N|next]: shows configuration N of the design's configurations
 * (Zemax's current configuration, Ctrl-A cycles): the values the design
 * holds become the configuration left's, so edits made in it are kept,
 * and configuration N's are set; one undo step.  Without N it names the
 * current one. */
static int c_config(ed *e, args *a)
{
    sg_system *sys = e->doc.sys;
    sg_configs *nc;
    sg_diag d;
    int n = sg_config_count(sys), cur = sys->configs ? sys->configs->current : 1, k;
    if (!ec_need(e, a, 0, 1, "config [N|next]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n == 1) {
        ed_msg(e, 0, "configuration %d of %d", cur, n);
        return ED_HANDLED | ED_REDRAW;
    }
    if (strcmp(a->v[1], "next") == 0)
        k = cur % n + 1;
    else if (!ec_parse_int(e, a->v[1], "configuration", 1, n, &k))
        return ED_HANDLED | ED_ERROR;
    if (!sys->configs || k == cur) {
        ed_msg(e, 0, "configuration %d of %d", cur, n);
        return ED_HANDLED | ED_REDRAW;
    }
    if (!(nc = sg_configs_switch(sys, k)))
        return ec_fail(e, "config: out of memory");
    if (!ec_begin(e, e->row)) {
        sg_configs_release(nc);
        return ED_HANDLED | ED_ERROR;
    }
    sg_configs_release(e->doc.sys->configs);
    e->doc.sys->configs = nc;
    sg_diag_clear(&d);
    if (sg_config_apply(e->doc.sys, k, &d) != SG_OK)
        return ec_cancel(e, d.msg);
    return ec_end(e, "configuration %d of %d", k, n);
}

/* solve SURFACE radius|thickness|conic TYPE [ARGS]: sets or clears a solve
 * (sagitta-design(5), Solves and pickups). */
int c_solve(ed *e, args *a)
{
    static const char usage[] = "solve SURFACE radius|thickness|conic none|pickup FROM [SCALE "
                                "[OFFSET]]|curvature_pickup FROM [SCALE [OFFSET]]|"
                                "marginal_height H|chief_height H|position FROM L|"
                                "marginal_angle U|fnum F|variable [MIN MAX]";
    sg_solve v;
    sg_diag d;
    int row, t, k, rc;
    double x;
    if (!ec_need(e, a, 3, 6, usage))
        return ED_HANDLED | ED_ERROR;
    if (!ec_parse_row(e, a->v[1], 0, e->doc.sys->nsurf - 1, &row))
        return ED_HANDLED | ED_ERROR;
    for (t = 0; t < SG_SOLVE_NTARGETS; t++)
        if (strcasecmp(a->v[2], sg_solve_target_name((sg_solve_target)t)) == 0)
            break;
    if (t == SG_SOLVE_NTARGETS)
        return ec_fail(e, "solve: '%s' is not radius, thickness or conic", a->v[2]);
    for (k = 0; k < SG_SOLVE_NKINDS; k++)
        if (strcasecmp(a->v[3], sg_solve_kind_name((sg_solve_kind)k)) == 0)
            break;
    if (k == SG_SOLVE_NKINDS)
        return ec_fail(e, "solve: '%s' is not none, pickup, curvature_pickup, marginal_height, "
                    "chief_height, position, marginal_angle or fnum", a->v[3]);
    if (!sg_solve_allowed((sg_solve_target)t, (sg_solve_kind)k))
        return ec_fail(e, "solve: a %s solve cannot sit on the %s", a->v[3], a->v[2]);
    memset(&v, 0, sizeof v);
    v.kind = (sg_solve_kind)k;
    if (sg_solve_is_pickup((sg_solve_kind)k)) {
        v.scale = 1.0;
        if (a->n < 5 || !ec_parse_row(e, a->v[4], 0, e->doc.sys->nsurf - 1, &v.from))
            return a->n < 5 ? ec_fail(e, "usage: %s", usage) : (ED_HANDLED | ED_ERROR);
        if (a->n > 5 && !ec_parse_num(e, a->v[5], "scale", &v.scale))
            return ED_HANDLED | ED_ERROR;
        if (a->n > 6 && !ec_parse_num(e, a->v[6], "offset", &v.offset))
            return ED_HANDLED | ED_ERROR;
    } else if (k == SG_SOLVE_VARIABLE) {
        v.lo = -INFINITY;
        v.hi = INFINITY;
        if (a->n != 4 && a->n != 6)
            return ec_fail(e, "usage: solve SURFACE radius|thickness|conic variable [MIN MAX]");
        if (a->n == 6 && (!ec_parse_num(e, a->v[4], "min", &v.lo) ||
                          !ec_parse_num(e, a->v[5], "max", &v.hi)))
            return ED_HANDLED | ED_ERROR;
    } else if (k == SG_SOLVE_POSITION) {
        if (a->n != 6)
            return ec_fail(e, "usage: %s", usage);
        if (!ec_parse_row(e, a->v[4], 0, e->doc.sys->nsurf - 1, &v.from) ||
            !ec_parse_num(e, a->v[5], "length", &v.value))
            return ED_HANDLED | ED_ERROR;
    } else if (k != SG_SOLVE_NONE) {
        if (a->n != 5)
            return ec_fail(e, "usage: %s", usage);
        if (!ec_parse_num(e, a->v[4], "value", &x))
            return ED_HANDLED | ED_ERROR;
        v.value = x;
    } else if (a->n != 4) {
        return ec_fail(e, "usage: %s", usage);
    }
    if (!ec_begin(e, row))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->surf[row].solve[t] = v;
    sg_diag_clear(&d);
    if ((rc = sg_solve_check(e->doc.sys, row, (sg_solve_target)t, &d)) != SG_OK)
        return ec_cancel(e, d.msg);
    e->row = row;
    if (k == SG_SOLVE_NONE)
        return ec_end(e, "surface %d: the %s holds no solve", row, a->v[2]);
    return ec_end(e, "surface %d: %s solve on the %s", row, sg_solve_kind_name(v.kind),
               sg_solve_target_name((sg_solve_target)t));
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
    {"merit", "mfe", c_merit, "merit [list | insert [ROW] [TYPE] | delete ROW | set ROW COLUMN VALUE | "
     "default off|centroid|chief [RINGS [ARMS]]]",
     "the Merit Function Editor (Ctrl-E): its rows, live; insert, delete or set an operand's "
     "type, int1, int2, hx, hy, px, py, target or weight; the default part"},
    {"tol", NULL, c_tol, "tol [show | list | insert [ROW] [TYPE] | delete ROW | set ROW COLUMN "
     "VALUE]",
     "the sensitivity analysis of the design's tolerances, shown in the Tolerance Data Editor "
     "(Ctrl-T; Esc stops it, keeping the rows done); show opens the editor; insert, delete or "
     "set a row's type, int1, int2, int3, min or max"},
    {"var", NULL, c_var, "var SURFACE NAME [MIN MAX]",
     "make a value a variable of the optimizer (V), optionally bounded"},
    {"novar", NULL, c_novar, "novar SURFACE NAME | novar all",
     "clear a variable, or every one"},
    {"opt", NULL, c_opt, "opt [CYCLES]",
     "damped least squares on the variables against the merit function (one undo step)"},
    {"config", NULL, c_config, "config [N|next]",
     "show configuration N of the design's configurations (Ctrl-A: the next); edits made in "
     "one are kept as its values"},
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
    {"view", NULL, c_view, "view layout|spot|fan|opd|wave|mtf|psf|encircled|off|next",
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
        return ec_fail(e, "cannot read the command: an unclosed quote, or too many words");
    for (i = 0; i < NCOMMANDS; i++)
        if (strcmp(a.v[0], commands[i].name) == 0 ||
            (commands[i].alias && strcmp(a.v[0], commands[i].alias) == 0))
            return commands[i].fn(e, &a);
    return ec_fail(e, "unknown command \"%s\" (try help)", a.v[0]);
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
