/*
 * cmd_tol.c - the Tolerance Data Editor's commands: tol (run the
 * sensitivity analysis and show it), tol show, list, insert, delete and
 * set.  Each edit is one undo step, checked against the design as the
 * file's tolerances object would be; a run changes nothing in the design.
 */
#include "cmd_int.h"

/* The columns of a tolerance row, as the editor shows them and "tol set"
 * names them: Zemax's Type, Int1, Int2, Int3 (TEZI's first term), Min,
 * Max. */
const char *const tol_cols[TOL_NCOLS] = {"type", "int1", "int2", "int3", "min", "max"};

int tol_col_parse(const char *s)
{
    int k;
    for (k = 0; s && k < TOL_NCOLS; k++)
        if (strcasecmp(s, tol_cols[k]) == 0)
            return k;
    return -1;
}

static int is_elem(int t)
{
    return t >= SG_TOL_TEDX && t <= SG_TOL_TETZ;
}

/* Whether column col means anything for the row (an element's Int2 is its
 * last surface, TTHI's the adjusting one, TEZI's its last term). */
int tol_col_used(const sg_tol_operand *o, int col)
{
    if (col == 2)
        return is_elem(o->type) || o->type == SG_TOL_TTHI || o->type == SG_TOL_TEZI;
    if (col == 3)
        return o->type == SG_TOL_TEZI;
    return 1;
}

/* The number in column col of row o, as Zemax's editor shows it (TTHI's
 * Int2 is its own surface when nothing adjusts). */
double tol_col_value(const sg_tol_operand *o, int col)
{
    switch (col) {
    case 1: return o->surface;
    case 2:
        return is_elem(o->type)          ? o->last
               : o->type == SG_TOL_TTHI ? (o->adjust >= 0 ? o->adjust : o->surface)
               : o->type == SG_TOL_TEZI ? o->zmax
                                        : 0;
    case 3: return o->type == SG_TOL_TEZI ? o->zmin : 0;
    case 4: return o->min;
    case 5: return o->max;
    default: return 0.0;
    }
}

/* The tolerances' defaults, as a design file without the keys gets them. */
static void tol_defaults(sg_tolerances *t)
{
    if (t->present)
        return;
    memset(t, 0, sizeof *t);
    t->present = 1;
    t->pattern = SG_PUPIL_HEXAPOLAR;
    t->density = 6;
    t->grid = 64;
    t->seed = 1.0;
}

static int checked_end(ed *e, const char *what)
{
    sg_diag d;
    char why[SG_DIAG_MSG + 32];
    sg_diag_clear(&d);
    if (sg_tol_check(e->doc.sys, &d) != SG_OK) {
        snprintf(why, sizeof why, "%s; nothing changed",
                 d.msg[0] ? d.msg : "tolerances: a row is out of range");
        return ec_cancel(e, why);
    }
    return ec_end(e, "%s", what);
}

/* The last run's result, if it was made on the document as it is. */
static const sg_tol_result *current(const ed *e)
{
    return e->tol_have && e->tol_id == e->doc.id ? &e->tol_res : NULL;
}

/* tol list: every row, with the last run's criteria when they are the
 * document's, as sagitta tolerance's table. */
static int tol_list(ed *e)
{
    const sg_tolerances *t = &e->doc.sys->tol;
    const sg_tol_result *r = current(e);
    FILE *f = e->out ? e->out : stdout;
    int k, c;
    if (r)
        fprintf(f, "nominal %.17g\n", r->nominal.criterion);
    for (k = 0; k < t->nop; k++) {
        const sg_tol_operand *o = &t->op[k];
        fprintf(f, "%d %s", k + 1, sg_tol_name(o->type));
        for (c = 1; c < TOL_NCOLS; c++)
            if (tol_col_used(o, c))
                fprintf(f, " %s %.17g", tol_cols[c], tol_col_value(o, c));
        if (r && k < r->nsens)
            fprintf(f, " criterion_min %.17g criterion_max %.17g", r->sens[k].at_min.criterion,
                    r->sens[k].at_max.criterion);
        fputc('\n', f);
    }
    for (k = 0; k < t->ncomp; k++)
        fprintf(f, "comp %d %s %.17g %.17g\n", t->comp[k].surface, t->comp[k].param,
                t->comp[k].min, t->comp[k].max);
    if (r)
        fprintf(f, "rss %.17g%s\n", r->rss, r->stopped ? " stopped" : "");
    return ED_HANDLED;
}

/* tol: the sensitivity analysis of the design's tolerances, each row at
 * its min and max, compensated.  Stopped (Esc, Ctrl-C through
 * e->tol_progress), the rows done are kept and shown. */
static int tol_run(ed *e)
{
    sg_tol_opts o;
    sg_tol_result r;
    sg_diag d;
    const sg_tolerances *t = &e->doc.sys->tol;
    int rc;
    if (!t->present || t->nop == 0)
        return ec_fail(e, "tol: the design has no tolerance rows (tol insert, or sagitta "
                          "tolerance --default-tolerances)");
    sg_tol_opts_init(&o);
    o.progress = e->tol_progress;
    o.ctx = e->progress_ctx;
    memset(&r, 0, sizeof r);
    sg_diag_clear(&d);
    rc = sg_tolerance_run(e->doc.sys, e->cat, &o, 1, 0, 1, &r, &d);
    if (rc != SG_OK) {
        sg_tol_result_free(&r);
        return ec_fail(e, "tol: %s", d.msg);
    }
    if (e->tol_have)
        sg_tol_result_free(&e->tol_res);
    e->tol_res = r;
    e->tol_have = 1;
    e->tol_id = e->doc.id;
    if (e->batch)
        tol_list(e);
    if (r.stopped)
        ed_msg(e, 0, "tolerancing stopped: %d of %d rows done, kept; nominal %.6g", r.nsens,
               t->nop, r.nominal.criterion);
    else
        ed_msg(e, 0, "sensitivity: %d rows, nominal %.6g, RSS change %.6g", r.nsens,
               r.nominal.criterion, r.rss);
    return ED_HANDLED | ED_REDRAW | (e->batch ? 0 : ED_SHOW_TOL);
}

static int tol_insert(ed *e, args *a)
{
    sg_tolerances *t = &e->doc.sys->tol;
    int row = t->nop + 1, type = SG_TOL_TTHI, k, s, last = e->doc.sys->nsurf - 2;
    char msg[96];
    sg_diag d;
    if (!ec_need(e, a, 1, 3, "tol insert [ROW] [TYPE]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 2 && !ec_parse_int(e, a->v[2], "tol insert: row", 1, t->nop + 1, &row))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 3 && (type = sg_tol_parse(a->v[3])) < 0)
        return ec_fail(e, "tol insert: \"%s\" is not a tolerance operand sagitta knows "
                          "(sagitta-design(5), TOLERANCES)", a->v[3]);
    if (type == SG_TOL_TPAR)
        return ec_fail(e, "tol insert: TPAR names a parameter by its key; add it in the design "
                          "file (sagitta-design(5), TOLERANCES)");
    if (t->present && t->nop >= SG_MAX_TOL_OPERANDS)
        return ec_fail(e, "tol insert: the design has its %d tolerance rows",
                       SG_MAX_TOL_OPERANDS);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    tol_defaults(t);
    for (k = t->nop; k >= row; k--)
        t->op[k] = t->op[k - 1];
    t->nop++;
    /* The first surface the design accepts for the type, limits 0: a new
     * row is never refused for numbers not typed yet. */
    for (s = 1; s <= last; s++) {
        sg_tol_operand *o = &t->op[row - 1];
        memset(o, 0, sizeof *o);
        o->type = (sg_tol_type)type;
        o->surface = s;
        o->last = s;
        o->adjust = -1;
        o->zmin = 2;
        o->zmax = type == SG_TOL_TEZI ? 11 : 0;
        sg_diag_clear(&d);
        if (sg_tol_check(e->doc.sys, &d) == SG_OK)
            break;
    }
    snprintf(msg, sizeof msg, "tolerance row %d: %s inserted", row,
             sg_tol_name((sg_tol_type)type));
    return checked_end(e, msg);
}

static int tol_delete(ed *e, args *a)
{
    sg_tolerances *t = &e->doc.sys->tol;
    int row, k;
    char msg[96];
    if (!ec_need(e, a, 2, 2, "tol delete ROW"))
        return ED_HANDLED | ED_ERROR;
    if (t->nop == 0)
        return ec_fail(e, "tol delete: the design has no tolerance rows");
    if (!ec_parse_int(e, a->v[2], "tol delete: row", 1, t->nop, &row))
        return ED_HANDLED | ED_ERROR;
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    snprintf(msg, sizeof msg, "tolerance row %d (%s) deleted", row,
             sg_tol_name(t->op[row - 1].type));
    for (k = row - 1; k + 1 < t->nop; k++)
        t->op[k] = t->op[k + 1];
    t->nop--;
    memset(&t->op[t->nop], 0, sizeof t->op[t->nop]);
    return checked_end(e, msg);
}

/* tol set ROW COLUMN VALUE [COLUMN VALUE]...: one undo step. */
static int tol_set(ed *e, args *a)
{
    sg_tolerances *t = &e->doc.sys->tol;
    sg_tol_operand *o, was;
    int row, k, np, col[6], iv[6];
    double v[6];
    char msg[160];
    size_t len;
    if (a->n < 5 || (a->n - 3) % 2 != 0 || a->n > 3 + 2 * 6)
        return ec_fail(e, "usage: tol set ROW COLUMN VALUE [COLUMN VALUE]... (COLUMN: type, "
                          "int1, int2, int3, min, max)");
    if (t->nop == 0)
        return ec_fail(e, "tol set: the design has no tolerance rows (tol insert)");
    if (!ec_parse_int(e, a->v[2], "tol set: row", 1, t->nop, &row))
        return ED_HANDLED | ED_ERROR;
    np = (a->n - 3) / 2;
    for (k = 0; k < np; k++) {
        const char *s = a->v[3 + 2 * k], *val = a->v[4 + 2 * k];
        iv[k] = 0;
        v[k] = 0.0;
        if ((col[k] = tol_col_parse(s)) < 0)
            return ec_fail(e, "tol set: \"%s\" is not one of type, int1, int2, int3, min, max",
                           s);
        if (col[k] == 0) {
            if ((iv[k] = sg_tol_parse(val)) < 0)
                return ec_fail(e, "tol set: \"%s\" is not a tolerance operand sagitta knows",
                               val);
            if (iv[k] == SG_TOL_TPAR)
                return ec_fail(e, "tol set: TPAR names a parameter by its key; set it in the "
                                  "design file");
        } else if (col[k] <= 3) {
            if (!ec_parse_int(e, val, s, 0, 1000000, &iv[k]))
                return ED_HANDLED | ED_ERROR;
        } else if (!ec_parse_num(e, val, s, &v[k])) {
            return ED_HANDLED | ED_ERROR;
        }
    }
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    o = &t->op[row - 1];
    was = *o;
    len = (size_t)snprintf(msg, sizeof msg, "tolerance row %d:", row);
    for (k = 0; k < np; k++) {
        switch (col[k]) {
        case 0:
            o->type = (sg_tol_type)iv[k];
            if (o->type == SG_TOL_TEZI && was.type != SG_TOL_TEZI) {
                o->zmin = 2;
                o->zmax = 11;
            }
            if (is_elem(o->type) && !is_elem(was.type))
                o->last = o->surface;
            break;
        case 1: o->surface = iv[k]; break;
        case 2:
            /* As Zemax's Int2: TTHI's own surface adjusts nothing. */
            if (is_elem(o->type))
                o->last = iv[k];
            else if (o->type == SG_TOL_TTHI)
                o->adjust = iv[k] == o->surface ? -1 : iv[k];
            else if (o->type == SG_TOL_TEZI)
                o->zmax = iv[k];
            break;
        case 3:
            if (o->type == SG_TOL_TEZI)
                o->zmin = iv[k];
            break;
        case 4: o->min = v[k]; break;
        default: o->max = v[k]; break;
        }
        if (len < sizeof msg)
            len += (size_t)snprintf(msg + len, sizeof msg - len, " %s %s", a->v[3 + 2 * k],
                                    a->v[4 + 2 * k]);
    }
    return checked_end(e, msg);
}

int c_tol(ed *e, args *a)
{
    if (a->n < 2)
        return tol_run(e);
    if (strcasecmp(a->v[1], "show") == 0)
        return e->batch ? tol_list(e) : ED_HANDLED | ED_SHOW_TOL;
    if (strcasecmp(a->v[1], "list") == 0)
        return tol_list(e);
    if (strcasecmp(a->v[1], "insert") == 0)
        return tol_insert(e, a);
    if (strcasecmp(a->v[1], "delete") == 0)
        return tol_delete(e, a);
    if (strcasecmp(a->v[1], "set") == 0)
        return tol_set(e, a);
    return ec_fail(e, "tol: \"%s\" is not show, list, insert, delete or set", a->v[1]);
}
