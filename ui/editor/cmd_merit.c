/*
 * cmd_merit.c - the Merit Function Editor's commands: merit (show or
 * list), merit insert, delete, set and default.  Each edit is one undo
 * step, checked against the design as the file's merit object would be.
 */
#include "cmd_int.h"

/* The columns of an operand row, as the Merit Function Editor shows them
 * and "merit set" names them (Zemax's Type, Int1, Int2, Hx, Hy, Px, Py,
 * Target, Weight). */
const char *const merit_cols[MERIT_NCOLS] = {"type", "int1", "int2", "hx", "hy",
                                              "px", "py", "target", "weight"};

int merit_col_parse(const char *s)
{
    int k;
    for (k = 0; s && k < MERIT_NCOLS; k++)
        if (strcasecmp(s, merit_cols[k]) == 0)
            return k;
    return -1;
}

/* The number in column col of operand o. */
double merit_col_value(const sg_operand *o, int col)
{
    switch (col) {
    case 1: return o->i1;
    case 2: return o->i2;
    case 3: return o->hx;
    case 4: return o->hy;
    case 5: return o->px;
    case 6: return o->py;
    case 7: return o->target;
    case 8: return o->weight;
    default: return 0.0;
    }
}

/* Checks the edited merit function against the design: a row naming a
 * surface or wavelength the design lacks cancels the edit, with why. */
static int checked_end(ed *e, const char *what)
{
    sg_diag d;
    char why[SG_DIAG_MSG + 32];
    sg_diag_clear(&d);
    if (sg_merit_check(e->doc.sys, &d) != SG_OK) {
        snprintf(why, sizeof why, "%s; nothing changed",
                 d.msg[0] ? d.msg : "merit: a row is out of range");
        return ec_cancel(e, why);
    }
    return ec_end(e, "%s", what);
}

/* merit list, in batch mode: every row with its value, as sagitta merit. */
static int merit_list(ed *e)
{
    sg_merit_result r;
    sg_diag d;
    int i;
    FILE *f = e->out ? e->out : stdout;
    memset(&r, 0, sizeof r);
    sg_diag_clear(&d);
    if (sg_merit_eval(e->doc.sys, e->cat, &r, &d) != SG_OK)
        return ec_fail(e, "merit: %s", d.msg);
    for (i = 0; i < r.nrow; i++)
        fprintf(f, "%d %s %.17g %.17g %.17g %.17g\n", r.row[i].row, sg_op_name(r.row[i].type),
                r.row[i].target, r.row[i].weight, r.row[i].value, r.row[i].contribution);
    fprintf(f, "merit %.17g\n", r.merit);
    sg_merit_result_free(&r);
    return ED_HANDLED;
}

static int merit_insert(ed *e, args *a)
{
    sg_merit *m = &e->doc.sys->merit;
    int row = m->nop + 1, type = SG_OP_BLNK, k;
    char msg[96];
    if (!ec_need(e, a, 1, 3, "merit insert [ROW] [TYPE]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 2 && !ec_parse_int(e, a->v[2], "merit insert: row", 1, m->nop + 1, &row))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 3 && (type = sg_op_parse(a->v[3])) < 0)
        return ec_fail(e, "merit insert: \"%s\" is not an operand sagitta knows "
                          "(sagitta(1), MERIT FUNCTION)", a->v[3]);
    if (m->nop >= SG_MAX_OPERANDS)
        return ec_fail(e, "merit insert: the merit function has its %d rows",
                       SG_MAX_OPERANDS);
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    for (k = m->nop; k >= row; k--)
        m->op[k] = m->op[k - 1];
    memset(&m->op[row - 1], 0, sizeof m->op[row - 1]);
    m->op[row - 1].type = (sg_op_type)type;
    m->nop++;
    m->present = 1;
    {
        /* Int1 and Int2 start at the first values the design accepts for
         * the operand (0, else 1, else surface 1 to the last): a new row
         * is never refused for numbers the user has not typed yet. */
        static const int try1[] = {0, 1, 1, 1};
        int t, last = e->doc.sys->nsurf - 1;
        sg_diag d;
        for (t = 0; t < 4; t++) {
            m->op[row - 1].i1 = try1[t];
            m->op[row - 1].i2 = t == 0 ? 0 : t == 1 ? 1 : t == 2 ? 2 : last;
            sg_diag_clear(&d);
            if (sg_merit_check(e->doc.sys, &d) == SG_OK)
                break;
        }
    }
    snprintf(msg, sizeof msg, "merit row %d: %s inserted", row, sg_op_name((sg_op_type)type));
    return checked_end(e, msg);
}

static int merit_delete(ed *e, args *a)
{
    sg_merit *m = &e->doc.sys->merit;
    int row, k;
    char msg[96];
    if (!ec_need(e, a, 2, 2, "merit delete ROW"))
        return ED_HANDLED | ED_ERROR;
    if (m->nop == 0)
        return ec_fail(e, "merit delete: the merit function has no operand rows");
    if (!ec_parse_int(e, a->v[2], "merit delete: row", 1, m->nop, &row))
        return ED_HANDLED | ED_ERROR;
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    snprintf(msg, sizeof msg, "merit row %d (%s) deleted", row, sg_op_name(m->op[row - 1].type));
    for (k = row - 1; k + 1 < m->nop; k++)
        m->op[k] = m->op[k + 1];
    m->nop--;
    memset(&m->op[m->nop], 0, sizeof m->op[m->nop]);
    return checked_end(e, msg);
}

/* Reads "COLUMN VALUE" at a->v[i], a->v[i + 1] into *col, and *iv or *v. */
static int read_pair(ed *e, args *a, int i, int *col, int *iv, double *v)
{
    *iv = 0;
    *v = 0.0;
    if ((*col = merit_col_parse(a->v[i])) < 0)
        return ec_fail(e, "merit set: \"%s\" is not one of type, int1, int2, hx, hy, px, py, "
                          "target, weight", a->v[i]), 0;
    if (*col == 0) {
        if ((*iv = sg_op_parse(a->v[i + 1])) < 0)
            return ec_fail(e, "merit set: \"%s\" is not an operand sagitta knows "
                              "(sagitta(1), MERIT FUNCTION)", a->v[i + 1]), 0;
    } else if (*col <= 2) {
        if (!ec_parse_int(e, a->v[i + 1], a->v[i], -1000000, 1000000, iv))
            return 0;
    } else {
        if (!ec_parse_num(e, a->v[i + 1], a->v[i], v))
            return 0;
        if (*col == 8 && !(*v >= 0.0))
            return ec_fail(e, "merit set: a weight of %g; weights are 0 or more", *v), 0;
    }
    return 1;
}

/* merit set ROW COLUMN VALUE [COLUMN VALUE]...: one undo step, so a row
 * whose two surfaces must change together is never refused half-way. */
static int merit_set(ed *e, args *a)
{
    sg_merit *m = &e->doc.sys->merit;
    sg_operand *o;
    int row, col[8], iv[8], k, np;
    double v[8];
    char msg[160];
    size_t len;
    if (a->n < 5 || (a->n - 3) % 2 != 0 || a->n > 3 + 2 * 6)
        return ec_fail(e, "usage: merit set ROW COLUMN VALUE [COLUMN VALUE]... (COLUMN: type, "
                          "int1, int2, hx, hy, px, py, target, weight)");
    if (m->nop == 0)
        return ec_fail(e, "merit set: the merit function has no operand rows (merit insert)");
    if (!ec_parse_int(e, a->v[2], "merit set: row", 1, m->nop, &row))
        return ED_HANDLED | ED_ERROR;
    np = (a->n - 3) / 2;
    for (k = 0; k < np; k++)
        if (!read_pair(e, a, 3 + 2 * k, &col[k], &iv[k], &v[k]))
            return ED_HANDLED | ED_ERROR;
    {
        /* A field or pupil coordinate is normalized, as Zemax's; Data1 to
         * Data4 of other types (a frequency, a term) are the type's own. */
        const char *keys[6];
        int type = m->op[row - 1].type;
        for (k = 0; k < np; k++)
            if (col[k] == 0)
                type = iv[k];
        sg_op_keys((sg_op_type)type, keys);
        for (k = 0; k < np; k++)
            if (col[k] >= 3 && col[k] <= 6 && keys[col[k] - 1] &&
                strlen(keys[col[k] - 1]) == 2 && strchr("hp", keys[col[k] - 1][0]) &&
                !(v[k] >= -1.0 && v[k] <= 1.0))
                return ec_fail(e, "merit set: %s %g is outside -1 to 1 (normalized)",
                               keys[col[k] - 1], v[k]);
    }
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    o = &m->op[row - 1];
    len = (size_t)snprintf(msg, sizeof msg, "merit row %d:", row);
    for (k = 0; k < np; k++) {
        switch (col[k]) {
        case 0: o->type = (sg_op_type)iv[k]; break;
        case 1: o->i1 = iv[k]; break;
        case 2: o->i2 = iv[k]; break;
        case 3: o->hx = v[k]; break;
        case 4: o->hy = v[k]; break;
        case 5: o->px = v[k]; break;
        case 6: o->py = v[k]; break;
        case 7: o->target = v[k]; break;
        default: o->weight = v[k]; break;
        }
        if (len < sizeof msg)
            len += (size_t)snprintf(msg + len, sizeof msg - len, " %s %s", a->v[3 + 2 * k],
                                    a->v[4 + 2 * k]);
    }
    return checked_end(e, msg);
}

/* merit default off | centroid|chief [RINGS [ARMS]]: the generated part. */
static int merit_default(ed *e, args *a)
{
    sg_merit *m = &e->doc.sys->merit;
    int ref = m->reference, rings = m->rings > 0 ? m->rings : 3, arms = m->arms > 0 ? m->arms : 6;
    int on = 1;
    if (!ec_need(e, a, 2, 4, "merit default off|centroid|chief [RINGS [ARMS]]"))
        return ED_HANDLED | ED_ERROR;
    if (strcasecmp(a->v[2], "off") == 0)
        on = 0;
    else if (strcasecmp(a->v[2], "centroid") == 0)
        ref = SG_MERIT_CENTROID;
    else if (strcasecmp(a->v[2], "chief") == 0)
        ref = SG_MERIT_CHIEF;
    else
        return ec_fail(e, "merit default: \"%s\" is not off, centroid or chief", a->v[2]);
    if (a->n > 3 && (!on || !ec_parse_int(e, a->v[3], "merit default: rings", 1, 20, &rings)))
        return on ? ED_HANDLED | ED_ERROR : ec_fail(e, "merit default off takes nothing more");
    /* The design format's limits (Zemax's dialog offers 6 to 12 arms). */
    if (a->n > 4 && !ec_parse_int(e, a->v[4], "merit default: arms", 1, 64, &arms))
        return ED_HANDLED | ED_ERROR;
    if (!ec_begin(e, e->row))
        return ED_HANDLED | ED_ERROR;
    m->has_default = on;
    if (on) {
        m->reference = ref;
        m->rings = rings;
        m->arms = arms;
    }
    m->present = 1;
    if (!on)
        return checked_end(e, "merit: no default part");
    return ec_end(e, "merit: default part, RMS spot about the %s, %d rings, %d arms",
                  ref == SG_MERIT_CHIEF ? "chief ray" : "centroid", rings, arms);
}

int c_merit(ed *e, args *a)
{
    if (a->n < 2)
        return e->batch ? merit_list(e) : ED_HANDLED | ED_SHOW_MERIT;
    if (strcasecmp(a->v[1], "list") == 0)
        return merit_list(e);
    if (strcasecmp(a->v[1], "insert") == 0)
        return merit_insert(e, a);
    if (strcasecmp(a->v[1], "delete") == 0)
        return merit_delete(e, a);
    if (strcasecmp(a->v[1], "set") == 0)
        return merit_set(e, a);
    if (strcasecmp(a->v[1], "default") == 0)
        return merit_default(e, a);
    return ec_fail(e, "merit: \"%s\" is not list, insert, delete, set or default", a->v[1]);
}
