/*
 * cmd_edit.c - the commands that change surfaces: set, insert, delete, stop,
 * undo and redo.
 */
#include "cmd_int.h"

int c_set(ed *e, args *a)
{
    char val[ED_LINE], err[ED_MSG], info[256], shown[ED_LINE];
    int row, col, rc;
    if (!ec_need(e, a, 2, MAXTOK, "set SURFACE COLUMN VALUE"))
        return ED_HANDLED | ED_ERROR;
    if (!ec_parse_row(e, a->v[1], 0, e->doc.sys->nsurf - 1, &row))
        return ED_HANDLED | ED_ERROR;
    col = cell_parse_name(a->v[2]);
    if (strcasecmp(a->v[2], "fixed") == 0) {
        int on;
        if (a->n > 4)
            return ec_fail(e, "usage: set SURFACE fixed on|off|toggle");
        if (!ec_parse_switch(e, a->n > 3 ? a->v[3] : NULL, e->doc.sys->surf[row].sd_fixed, &on,
                          "fixed"))
            return ED_HANDLED | ED_ERROR;
        if (!ec_begin(e, row))
            return ED_HANDLED | ED_ERROR;
        e->doc.sys->surf[row].sd_fixed = on;
        e->row = row;
        e->col = COL_SEMI;
        return ec_end(e, "surface %d semi-diameter %s", row, on ? "fixed" : "free");
    }
    if (col < 0)
        return ec_fail(e, "no column \"%s\" (type, comment, radius, thickness, material, "
                       "semi, conic, a2 ... a16, aperture, ap_rmin, ap_rmax, ap_xhalf, "
                       "ap_yhalf, ap_xdec, ap_ydec, norm, zdx, zdy, t1 ..., dx, dy, tx, ty, tz, order, "
                       "after, adx, ady, atx, aty, atz, aorder)", a->v[2]);
    if (a->n > 3)
        ec_rest_of(a, 3, val, sizeof val);
    else
        val[0] = '\0';
    if (!ec_begin(e, row))
        return ED_HANDLED | ED_ERROR;
    rc = cell_set(e->doc.sys, e->cat, row, col, val, err, sizeof err, info, sizeof info);
    if (rc != SG_EOK)
        return ec_cancel(e, err);
    e->row = row;
    e->col = col;
    cell_text(e->doc.sys, row, col, shown, sizeof shown);
    return ec_end(e, "surface %d %s = %s%s%s", row, cell_name(col), shown,
               info[0] ? "; " : "", info);
}

int c_insert(ed *e, args *a)
{
    int at = e->row < 1 ? 1 : e->row;
    if (!ec_need(e, a, 0, 1, "insert [SURFACE]"))
        return ED_HANDLED | ED_ERROR;
    if (at > e->doc.sys->nsurf - 1)
        at = e->doc.sys->nsurf - 1;
    if (a->n > 1 && !ec_parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 1, &at))
        return ED_HANDLED | ED_ERROR;
    if (e->doc.sys->nsurf >= SG_MAX_SURFACES)
        return ec_fail(e, "a design holds at most %d surfaces", SG_MAX_SURFACES);
    if (!ec_begin(e, at))
        return ED_HANDLED | ED_ERROR;
    if (sg_system_insert(e->doc.sys, at) != SG_EOK)
        return ec_cancel(e, "out of memory: no surface inserted");
    e->row = at;
    return ec_end(e, "inserted surface %d", at);
}

int c_delete(ed *e, args *a)
{
    int at = e->row;
    if (!ec_need(e, a, 0, 1, "delete [SURFACE]"))
        return ED_HANDLED | ED_ERROR;
    if (e->doc.sys->nsurf <= 3)
        return ec_fail(e, "cannot delete: a design needs an object, a surface and an image");
    if (a->n > 1) {
        if (!ec_parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 2, &at))
            return ED_HANDLED | ED_ERROR;
    } else if (at < 1 || at > e->doc.sys->nsurf - 2) {
        return ec_fail(e, "the object and the image surfaces cannot be deleted");
    }
    if (!ec_begin(e, at))
        return ED_HANDLED | ED_ERROR;
    if (sg_system_delete(e->doc.sys, at) != SG_EOK)
        return ec_cancel(e, "cannot delete that surface");
    e->row = at;
    return ec_end(e, "deleted surface %d", at);
}

int c_stop(ed *e, args *a)
{
    int at = e->row;
    if (!ec_need(e, a, 0, 1, "stop [SURFACE]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 1) {
        if (!ec_parse_row(e, a->v[1], 1, e->doc.sys->nsurf - 2, &at))
            return ED_HANDLED | ED_ERROR;
    } else if (at < 1 || at > e->doc.sys->nsurf - 2) {
        return ec_fail(e, "the stop must be one of surfaces 1 to %d", e->doc.sys->nsurf - 2);
    }
    if (!ec_begin(e, at))
        return ED_HANDLED | ED_ERROR;
    e->doc.sys->stop = at;
    e->row = at;
    return ec_end(e, "surface %d is the stop", at);
}

static int undo_redo(ed *e, args *a, int redo)
{
    int n = 1, i, row = -1, rc = SG_EOK;
    if (!ec_need(e, a, 0, 1, redo ? "redo [N]" : "undo [N]"))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 1 && !ec_parse_int(e, a->v[1], "count", 1, 1000000, &n))
        return ED_HANDLED | ED_ERROR;
    for (i = 0; i < n; i++) {
        rc = redo ? doc_redo(&e->doc, &row) : doc_undo(&e->doc, &row);
        if (rc != SG_EOK)
            break;
    }
    if (i == 0)
        return ec_fail(e, rc == SG_ERANGE ? "nothing to %s" : "out of memory: cannot %s",
                    redo ? "redo" : "undo");
    if (row >= 0)
        e->row = row;
    e->dirty = 1;
    ed_msg(e, 0, "%s %d change%s (%zu more to undo, %zu to redo)", redo ? "redid" : "undid",
           i, i == 1 ? "" : "s", doc_undo_depth(&e->doc), doc_redo_depth(&e->doc));
    return OK_VIEW;
}

int c_undo(ed *e, args *a)
{
    return undo_redo(e, a, 0);
}

int c_redo(ed *e, args *a)
{
    return undo_redo(e, a, 1);
}
