/* cells.c - text in and out of the lens data spreadsheet's cells. */
#include "cells.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "../args.h"
#include "numfmt.h"

/* The columns, made once from the engine's parameter table. */
typedef struct colinfo {
    const sg_param *p;
    int k;
    char heading[24];
    char name[24];
} colinfo;

static colinfo cols[COL_MAX];
static int ncols = -1;

static void build(void)
{
    int i, k, n = 0;
    if (ncols >= 0)
        return;
    for (i = 0; i < sg_param_count(SG_SCOPE_SURFACE); i++) {
        const sg_param *p = sg_param_at(SG_SCOPE_SURFACE, i);
        if (!p->heading)
            continue;
        for (k = 0; k < p->count && n < COL_MAX; k++, n++) {
            cols[n].p = p;
            cols[n].k = k;
            sg_param_heading(p, k, cols[n].heading, sizeof cols[n].heading);
            sg_param_cell(p, k, cols[n].name, sizeof cols[n].name);
        }
    }
    ncols = n;
}

int cell_count(void)
{
    build();
    return ncols;
}

const sg_param *cell_param(int col, int *k)
{
    build();
    if (col < 0 || col >= ncols)
        return NULL;
    if (k)
        *k = cols[col].k;
    return cols[col].p;
}

static const struct {
    const char *alias;
    int col;
} aliases[] = {
    {"r", COL_RADIUS},       {"rad", COL_RADIUS},     {"t", COL_THICKNESS},
    {"thick", COL_THICKNESS}, {"glass", COL_MATERIAL}, {"mat", COL_MATERIAL},
    {"sd", COL_SEMI},        {"semi-diameter", COL_SEMI}, {"semidia", COL_SEMI},
    {"k", COL_CONIC},        {"c", COL_COMMENT},      {"note", COL_COMMENT},
};

const char *cell_heading(int col)
{
    build();
    return col >= 0 && col < ncols ? cols[col].heading : "?";
}

const char *cell_name(int col)
{
    build();
    return col >= 0 && col < ncols ? cols[col].name : "?";
}

int cell_parse_name(const char *s)
{
    size_t i;
    build();
    for (i = 0; i < (size_t)ncols; i++)
        if (strcasecmp(s, cols[i].name) == 0)
            return (int)i;
    for (i = 0; i < sizeof aliases / sizeof aliases[0]; i++)
        if (strcasecmp(s, aliases[i].alias) == 0)
            return aliases[i].col;
    /* "r4" as well as "a4" names the r^4 term. */
    if ((s[0] == 'r' || s[0] == 'R') && isdigit((unsigned char)s[1])) {
        char buf[8];
        snprintf(buf, sizeof buf, "a%s", s + 1);
        for (i = COL_ASPH0; i < (size_t)ncols; i++)
            if (strcasecmp(buf, cols[i].name) == 0)
                return (int)i;
    }
    return -1;
}

/* Whether some name in names[0..n) (or shown[]) begins with c, ignoring
 * case. */
static int names_begin(const char *const *names, int n, int c)
{
    int k;
    for (k = 0; names && k < n; k++)
        if (names[k] && tolower((unsigned char)names[k][0]) == c)
            return 1;
    return 0;
}

int cell_key_begins(int col, int key)
{
    /* The type's aliases cell_type_parse reads beyond the table's names. */
    static const char *const type_alias[] = {"std", "asph", "even", "cb", "break"};
    const sg_param *p = cell_param(col, NULL);
    int c;
    if (!p || key < 0x20 || key == 0x7f || key == ':')
        return 0;
    /* Text takes any character but the leading ':', which is the command
     * line's. */
    if (p->kind == SG_PARAM_TEXT || p->kind == SG_PARAM_MATERIAL)
        return 1;
    if (key >= 0x80)
        return 0;
    c = tolower(key);
    if (p->kind == SG_PARAM_REAL)
        /* What strtod reads first: a digit, sign or point, or the i of
         * inf and infinity and the n of nan (refused, but a value's
         * spelling, never a command). */
        return (c >= '0' && c <= '9') || c == '+' || c == '-' || c == '.' || c == 'i' ||
               c == 'n';
    if (p->kind == SG_PARAM_ENUM)
        return names_begin(p->names, p->nnames, c) || names_begin(p->shown, p->nnames, c) ||
               (col == COL_TYPE &&
                names_begin(type_alias, (int)(sizeof type_alias / sizeof type_alias[0]), c));
    return 0;
}

int cell_numeric(int col)
{
    const sg_param *p = cell_param(col, NULL);
    return p && p->kind == SG_PARAM_REAL;
}

/* Where a frame change may not stand (as sg_system_validate says): the
 * object moves nothing and nothing follows the image.  NULL where it may. */
static const char *frame_refused(const sg_system *sys, int row, const sg_param *p)
{
    if (!(p->flags & SG_PARAM_NESTED))
        return NULL;
    if (row == 0)
        return "the object cannot be tilted or decentered";
    if (row == sys->nsurf - 1 && strncmp(p->key, "after.", 6) == 0)
        return "nothing follows the image, so it takes no after change";
    return NULL;
}

int cell_used(const sg_system *sys, int row, int col)
{
    int k;
    const sg_param *p = cell_param(col, &k);
    const sg_surface *s = &sys->surf[row];
    if (!p || frame_refused(sys, row, p))
        return 0;
    /* A reverse after change is computed, not typed: its values and
     * order are dim, the mode itself not. */
    if (s->after_mode == SG_AFTER_REVERSE && (p->flags & SG_PARAM_NESTED) &&
        p->offset != offsetof(sg_surface, after_mode) && strncmp(p->key, "after.", 6) == 0)
        return 0;
    return sg_param_used(p, k, s->type);
}

/* Copies s without surrounding blanks into buf; 0 when it does not fit. */
static int trimmed(const char *s, char *buf, size_t n)
{
    size_t len;
    while (isspace((unsigned char)*s))
        s++;
    len = strlen(s);
    while (len > 0 && isspace((unsigned char)s[len - 1]))
        len--;
    if (len >= n)
        return 0;
    memcpy(buf, s, len);
    buf[len] = '\0';
    return 1;
}

const char *cell_type_name(int type)
{
    const sg_param *p = sg_param_find(SG_SCOPE_SURFACE, "type");
    return type >= 0 && type < p->nnames ? p->shown[type] : "STANDARD";
}

int cell_type_parse(const char *s)
{
    const sg_param *p = sg_param_find(SG_SCOPE_SURFACE, "type");
    char buf[64];
    int k;
    while (isspace((unsigned char)*s))
        s++;
    if (strcasecmp(s, "standard") == 0 || strcasecmp(s, "std") == 0 ||
        strcasecmp(s, "s") == 0)
        return SG_SURF_STANDARD;
    if (strcasecmp(s, "evenasph") == 0 || strcasecmp(s, "evenasphere") == 0 ||
        strcasecmp(s, "asph") == 0 || strcasecmp(s, "asphere") == 0 ||
        strcasecmp(s, "even") == 0 || strcasecmp(s, "e") == 0)
        return SG_SURF_EVENASPH;
    if (!trimmed(s, buf, sizeof buf))
        return -1;
    if (strcasecmp(buf, "cb") == 0 || strcasecmp(buf, "break") == 0)
        return SG_SURF_COORDBRK;
    /* The other types by their .zmx or JSON name. */
    for (k = SG_SURF_COORDBRK; k < p->nnames; k++)
        if (strcasecmp(buf, p->names[k]) == 0 || strcasecmp(buf, p->shown[k]) == 0)
            return k;
    return -1;
}

static void mat_text(const sg_material *m, char *buf, size_t n)
{
    switch (m->kind) {
    case SG_MAT_AIR: snprintf(buf, n, "%s", ""); break;
    case SG_MAT_MIRROR: snprintf(buf, n, "MIRROR"); break;
    case SG_MAT_GLASS:
        /* CATALOG:NAME, as typed, when the glass is not the one the name
         * alone means. */
        if (m->catalog[0])
            snprintf(buf, n, "%s:%s", m->catalog, m->name);
        else
            snprintf(buf, n, "%s", m->name);
        break;
    case SG_MAT_INDEX: numfmt_shortest(m->index, buf, n); break;
    default: snprintf(buf, n, "?"); break;
    }
}

/* Whether element k of p is one of the surface's other variables; the
 * material cell is marked when its model glass's nd or vd is. */
static int is_var(const sg_surface *s, const sg_param *p, int k)
{
    int j;
    for (j = 0; j < s->nvar; j++)
        if ((s->var[j].param == p && s->var[j].elem == k) ||
            (p->kind == SG_PARAM_MATERIAL && sg_param_material_part(s->var[j].param)))
            return 1;
    return 0;
}

static int solve_target(const sg_param *p)
{
    int t;
    for (t = 0; t < SG_SOLVE_NTARGETS; t++)
        if (strcmp(p->key, sg_solve_target_name((sg_solve_target)t)) == 0)
            return t;
    return -1;
}

static void text(const sg_system *sys, int row, int col, int edit, char *buf, size_t n)
{
    const sg_surface *s = &sys->surf[row];
    char num[NUMFMT_MAX];
    int k, v;
    const sg_param *p = cell_param(col, &k);
    buf[0] = '\0';
    if (!p)
        return;
    switch (p->kind) {
    case SG_PARAM_ENUM:
        v = *(const int *)sg_param_cptr(p, s);
        if (v >= 0 && v < p->nnames)
            snprintf(buf, n, "%s", p->shown ? p->shown[v] : p->names[v]);
        break;
    case SG_PARAM_TEXT: snprintf(buf, n, "%s", (const char *)sg_param_cptr(p, s)); break;
    case SG_PARAM_MATERIAL:
        mat_text(sg_param_cptr(p, s), buf, n);
        if (!edit && is_var(s, p, 0) && strlen(buf) + 2 < n)
            strcat(buf, " V");
        break;
    case SG_PARAM_BOOL: snprintf(buf, n, "%s", sg_param_get(p, s, 0) != 0.0 ? "on" : "off"); break;
    case SG_PARAM_REAL: {
        double x = sg_param_get(p, s, k);
        int t = solve_target(p);
        if (t >= 0 && !edit && s->solve[t].kind != SG_SOLVE_NONE) {
            /* Zemax marks a solved cell with a letter after the value. */
            static const char mark[SG_SOLVE_NKINDS] = {' ', 'P', 'M', 'A', 'F', 'C', 'P', 'T', 'V'};
            if ((p->flags & SG_PARAM_INF) && (x == 0.0 || isinf(x)))
                snprintf(num, sizeof num, "Infinity");
            else
                numfmt_shortest(x, num, sizeof num);
            snprintf(buf, n, "%s %c", num, mark[s->solve[t].kind]);
        } else if (!edit && t < 0 && is_var(s, p, k)) {
            /* A variable on another parameter is marked V alike. */
            numfmt_shortest(x, num, sizeof num);
            snprintf(buf, n, "%s V", num);
        } else if ((p->flags & SG_PARAM_INF) && !edit && (x == 0.0 || isinf(x))) {
            snprintf(buf, n, "Infinity");
        } else if (col == COL_SEMI) {
            /* Zemax marks a fixed semi-diameter with a U. */
            numfmt_shortest(x, num, sizeof num);
            snprintf(buf, n, "%s%s", num, s->sd_fixed ? " U" : "");
        } else {
            numfmt_shortest(x, buf, n);
        }
        break;
    }
    }
}

void cell_text(const sg_system *sys, int row, int col, char *buf, size_t n)
{
    text(sys, row, col, 0, buf, n);
}

void cell_edit_text(const sg_system *sys, int row, int col, char *buf, size_t n)
{
    text(sys, row, col, 1, buf, n);
}

/* A number for a cell: finite unless inf_ok.  The message names the
 * surface and the column. */
static int number(const char *s, int inf_ok, int row, int col, double *v,
                  char *err, size_t errn)
{
    int rc = args_double(s, inf_ok ? ARGS_ALLOW_INF : 0, v);
    if (rc == ARGS_OK)
        return SG_EOK;
    snprintf(err, errn, "surface %d %s: \"%s\": %s%s", row, cell_name(col), s,
             args_strerror(rc),
             rc == ARGS_NONFINITE && !inf_ok ? " (a finite value is needed)" : "");
    return rc == ARGS_RANGE ? SG_ERANGE : SG_EPARSE;
}

static int set_material(sg_system *sys, const sg_catalog *cat, int row,
                        const char *text, char *err, size_t errn)
{
    sg_surface *s = &sys->surf[row];
    char buf[128], *colon;
    double v;
    const sg_glass *g;
    if (!trimmed(text, buf, sizeof buf)) {
        snprintf(err, errn, "surface %d material: name is too long", row);
        return SG_ERANGE;
    }
    if (buf[0] == '\0' || strcasecmp(buf, "air") == 0) {
        s->mat.kind = SG_MAT_AIR;
        memset(s->mat.name, 0, sizeof s->mat.name);
        memset(s->mat.catalog, 0, sizeof s->mat.catalog);
        s->mat.index = 0.0;
        return SG_EOK;
    }
    if (strcasecmp(buf, "mirror") == 0) {
        if (row == 0 || row == sys->nsurf - 1) {
            snprintf(err, errn, "surface %d: the %s cannot be a mirror", row,
                     row == 0 ? "object" : "image");
            return SG_ENONPHYS;
        }
        s->mat.kind = SG_MAT_MIRROR;
        memset(s->mat.name, 0, sizeof s->mat.name);
        memset(s->mat.catalog, 0, sizeof s->mat.catalog);
        s->mat.index = 0.0;
        return SG_EOK;
    }
    if (args_double(buf, 0, &v) == ARGS_OK) {
        if (!(v >= 1e-3 && v < 100.0)) {
            snprintf(err, errn, "surface %d material: index %s is not physical", row, buf);
            return SG_ERANGE;
        }
        s->mat.kind = SG_MAT_INDEX;
        memset(s->mat.name, 0, sizeof s->mat.name);
        memset(s->mat.catalog, 0, sizeof s->mat.catalog);
        s->mat.index = v;
        return SG_EOK;
    }
    if (!cat) {
        snprintf(err, errn,
                 "surface %d material: cannot check \"%s\": no glass catalog is loaded "
                 "(set SAGITTA_LENSDB)", row, buf);
        return SG_ENOGLASS;
    }
    /* "HOYA:BAF2" names a catalog's glass; "BAF2" the one the name alone
     * means (sg_catalog_find's search order). */
    colon = strchr(buf, ':');
    if (colon) {
        *colon = '\0';
        g = sg_catalog_find_in(cat, buf, colon + 1);
        if (!g) {
            snprintf(err, errn, "surface %d material: catalog %s has no glass \"%s\"", row, buf,
                     colon + 1);
            return SG_ENOGLASS;
        }
    } else if (!(g = sg_catalog_find(cat, buf))) {
        snprintf(err, errn, "surface %d material: \"%s\" is not in the catalog", row, buf);
        return SG_ENOGLASS;
    }
    s->mat.kind = SG_MAT_GLASS;
    memset(s->mat.name, 0, sizeof s->mat.name);
    memset(s->mat.catalog, 0, sizeof s->mat.catalog);
    snprintf(s->mat.name, sizeof s->mat.name, "%s", g->name);
    if (g != sg_catalog_find(cat, g->name))
        snprintf(s->mat.catalog, sizeof s->mat.catalog, "%s", g->catalog);
    s->mat.index = 0.0;
    return SG_EOK;
}

/* Whether a frame change's cell may be typed into: a coordinate break has
 * no after change, and a reverse after change takes no values of its own.
 * Else 0 with a message naming the surface and column. */
static int frame_ok(const sg_system *sys, int row, int col, const sg_param *p, char *err,
                    size_t errn)
{
    const sg_surface *s = &sys->surf[row];
    int after = strncmp(p->key, "after.", 6) == 0;
    const char *why = frame_refused(sys, row, p);
    if (why) {
        snprintf(err, errn, "surface %d %s: %s", row, cell_name(col), why);
        return 0;
    }
    if (!(p->flags & SG_PARAM_NESTED) || !after)
        return 1;
    if (s->type == SG_SURF_COORDBRK) {
        snprintf(err, errn, "surface %d %s: a coordinate break has no after change; "
                            "use another break", row, cell_name(col));
        return 0;
    }
    if (s->after_mode == SG_AFTER_REVERSE && p->offset != offsetof(sg_surface, after_mode)) {
        snprintf(err, errn, "surface %d %s: the after change is \"reverse\" (it undoes the "
                            "before change); set after to explicit first", row, cell_name(col));
        return 0;
    }
    return 1;
}

/* A surface made a coordinate break (Zemax's COORDBRK): a plane in the
 * medium before it, with no aperture and no after change.  What it cannot
 * hold is cleared and said; undo brings it back. */
static int to_break(sg_system *sys, int row, char *err, size_t errn, char *info, size_t infon)
{
    sg_surface *s = &sys->surf[row];
    char lost[160] = "";
    if (row <= 1 || row == sys->nsurf - 1 || row == sys->stop) {
        snprintf(err, errn, "surface %d type: the %s cannot be a coordinate break", row,
                 row == 0 ? "object" : row == 1 ? "first surface" :
                 row == sys->stop ? "stop" : "image");
        return SG_EINVAL;
    }
#define LOST(what) snprintf(lost + strlen(lost), sizeof lost - strlen(lost), "%s%s", \
                            lost[0] ? ", " : "", what)
    if (isfinite(s->radius) && s->radius != 0.0)
        LOST("radius");
    if (s->mat.kind != SG_MAT_AIR)
        LOST("material");
    if (s->aperture != SG_APERTURE_NONE)
        LOST("aperture");
    if (!sg_frame_change_is_zero(&s->after) || s->after_mode != SG_AFTER_EXPLICIT)
        LOST("after change");
    if (s->solve[SG_SOLVE_RADIUS].kind != SG_SOLVE_NONE ||
        s->solve[SG_SOLVE_CONIC].kind != SG_SOLVE_NONE)
        LOST("radius or conic solve");
#undef LOST
    s->type = SG_SURF_COORDBRK;
    s->radius = INFINITY;
    memset(&s->mat, 0, sizeof s->mat);
    s->mat.kind = SG_MAT_AIR;
    s->aperture = SG_APERTURE_NONE;
    memset(&s->after, 0, sizeof s->after);
    s->after_mode = SG_AFTER_EXPLICIT;
    memset(&s->solve[SG_SOLVE_RADIUS], 0, sizeof s->solve[SG_SOLVE_RADIUS]);
    memset(&s->solve[SG_SOLVE_CONIC], 0, sizeof s->solve[SG_SOLVE_CONIC]);
    if (lost[0] && info && infon)
        snprintf(info, infon, "a coordinate break holds no %s: cleared", lost);
    return SG_EOK;
}

int cell_set(sg_system *sys, const sg_catalog *cat, int row, int col,
             const char *text, char *err, size_t errn, char *info, size_t infon)
{
    sg_surface *s;
    const sg_param *p;
    char buf[128], msg[160];
    double v;
    int rc, k, fixed = 0;

    if (info && infon)
        info[0] = '\0';
    if (row < 0 || row >= sys->nsurf) {
        snprintf(err, errn, "no surface %d (the design has 0 to %d)", row, sys->nsurf - 1);
        return SG_ERANGE;
    }
    p = cell_param(col, &k);
    if (!p) {
        snprintf(err, errn, "no such column");
        return SG_EINVAL;
    }
    s = &sys->surf[row];
    switch (p->kind) {
    case SG_PARAM_ENUM:
        if (col != COL_TYPE) {
            /* Any other choice: its JSON name or the name shown. */
            if (!trimmed(text, buf, sizeof buf))
                buf[0] = '\0';
            for (k = 0; k < p->nnames; k++)
                if (strcasecmp(buf, p->names[k]) == 0 ||
                    (p->shown && strcasecmp(buf, p->shown[k]) == 0))
                    break;
            if (k == p->nnames) {
                snprintf(err, errn, "surface %d %s: \"%s\" is not one of", row, cell_name(col),
                         text);
                for (k = 0; k < p->nnames; k++) {
                    size_t len = strlen(err);
                    snprintf(err + len, errn - len, "%s %s", k ? "," : "",
                             p->shown ? p->shown[k] : p->names[k]);
                }
                return SG_EPARSE;
            }
            if (!frame_ok(sys, row, col, p, err, errn))
                return SG_EINVAL;
            sg_param_set(p, s, 0, k);
            if (p->offset == offsetof(sg_surface, after_mode) && k == SG_AFTER_REVERSE &&
                (!sg_frame_change_is_zero(&s->after) || s->after.order)) {
                /* Reverse computes the after change; values of its own
                 * would contradict it. */
                memset(&s->after, 0, sizeof s->after);
                if (info && infon)
                    snprintf(info, infon, "its after values were cleared: reverse undoes the "
                                          "before change");
            }
            return SG_EOK;
        }
        rc = cell_type_parse(text);
        if (rc < 0) {
            /* The names from the one list of types (SG_SURF_TYPES). */
            char names[256] = "";
            size_t len = 0;
            for (k = 0; k < p->nnames && len < sizeof names; k++)
                len += (size_t)snprintf(names + len, sizeof names - len, "%s%s",
                                        k == 0                ? ""
                                        : k == p->nnames - 1 ? " or "
                                                              : ", ",
                                        p->shown[k]);
            snprintf(err, errn, "surface %d type: \"%s\" is not %s", row, text, names);
            return SG_EPARSE;
        }
        if (rc == SG_SURF_COORDBRK && s->type != SG_SURF_COORDBRK)
            return to_break(sys, row, err, errn, info, infon);
        s->type = (sg_surf_type)rc;
        if (rc == SG_SURF_STANDARD && info && infon) {
            for (k = 0; k < SG_NASPH && s->asph[k] == 0.0; k++)
                ;
            /* Kept, so switching back restores them, but the trace of a
             * STANDARD surface does not use them: say so. */
            if (k < SG_NASPH)
                snprintf(info, infon, "its r^n terms are kept but ignored (shown dim) "
                                      "until it is EVENASPH again");
        }
        return SG_EOK;
    case SG_PARAM_TEXT: {
        const unsigned char *c;
        char *dst = sg_param_ptr(p, s);
        if (strlen(text) >= p->size) {
            snprintf(err, errn, "surface %d %s: longer than %d bytes", row, cell_name(col),
                     (int)p->size - 1);
            return SG_ERANGE;
        }
        for (c = (const unsigned char *)text; *c; c++)
            if (*c < 0x20 || *c == 0x7f) {
                snprintf(err, errn, "surface %d %s: control characters are not allowed",
                         row, cell_name(col));
                return SG_EPARSE;
            }
        memset(dst, 0, p->size);
        memcpy(dst, text, strlen(text));
        return SG_EOK;
    }
    case SG_PARAM_MATERIAL:
        return set_material(sys, cat, row, text, err, errn);
    case SG_PARAM_BOOL:
        snprintf(err, errn, "surface %d %s: not a column", row, cell_name(col));
        return SG_EINVAL;
    case SG_PARAM_REAL:
        break;
    }
    if (!frame_ok(sys, row, col, p, err, errn))
        return SG_EINVAL;
    if (!trimmed(text, buf, sizeof buf)) {
        snprintf(err, errn, "surface %d %s: text is too long", row, cell_name(col));
        return SG_EPARSE;
    }
    if (col == COL_SEMI) {
        /* A trailing U fixes the aperture, as Zemax marks it. */
        size_t len = strlen(buf);
        if (len > 0 && (buf[len - 1] == 'U' || buf[len - 1] == 'u')) {
            fixed = 1;
            buf[len - 1] = '\0';
        }
    }
    rc = number(col == COL_SEMI ? buf : text,
                (p->flags & SG_PARAM_INF) || ((p->flags & SG_PARAM_OBJ_INF) && row == 0), row,
                col, &v, err, errn);
    if (rc != SG_EOK)
        return rc;
    if ((p->flags & SG_PARAM_NONNEG) && v < 0.0) {
        snprintf(err, errn, "surface %d %s: %s is negative", row, cell_name(col), buf);
        return SG_ERANGE;
    }
    /* The table's limits; radius and thickness are left to validation,
     * which knows the whole system. */
    if (!(p->flags & (SG_PARAM_INF | SG_PARAM_OBJ_INF)) &&
        sg_param_check(p, k, v, row == 0, msg, sizeof msg) != SG_OK) {
        snprintf(err, errn, "surface %d %s: %s", row, cell_name(col), msg);
        return SG_ERANGE;
    }
    sg_param_set(p, s, k, v);
    if (col == COL_SEMI)
        s->sd_fixed = fixed;
    /* A value typed over a solve replaces it, as in Zemax. */
    k = solve_target(p);
    if (k >= 0 && s->solve[k].kind != SG_SOLVE_NONE) {
        if (info && infon)
            snprintf(info, infon, "surface %d %s: the %s solve was removed", row, cell_name(col),
                     sg_solve_kind_name(s->solve[k].kind));
        memset(&s->solve[k], 0, sizeof s->solve[k]);
    }
    /* A standard surface ignores its polynomial, so a term typed into
     * one means the user wants an asphere. */
    if (col >= COL_ASPH0 && col < COL_ASPH0 + SG_NASPH && v != 0.0 &&
        s->type == SG_SURF_STANDARD) {
        s->type = SG_SURF_EVENASPH;
        if (info && infon)
            snprintf(info, infon, "surface %d is now EVENASPH", row);
    }
    return SG_EOK;
}
