/* cells.c - text in and out of the lens data spreadsheet's cells. */
#include "cells.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "../args.h"
#include "numfmt.h"

static const char *const headings[COL_COUNT] = {
    "Type", "Comment", "Radius", "Thickness", "Material", "Semi-Dia", "Conic",
    "r^2", "r^4", "r^6", "r^8", "r^10", "r^12", "r^14", "r^16",
};

static const char *const names[COL_COUNT] = {
    "type", "comment", "radius", "thickness", "material", "semi", "conic",
    "a2", "a4", "a6", "a8", "a10", "a12", "a14", "a16",
};

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
    return col >= 0 && col < COL_COUNT ? headings[col] : "?";
}

const char *cell_name(int col)
{
    return col >= 0 && col < COL_COUNT ? names[col] : "?";
}

int cell_parse_name(const char *s)
{
    size_t i;
    for (i = 0; i < COL_COUNT; i++)
        if (strcasecmp(s, names[i]) == 0)
            return (int)i;
    for (i = 0; i < sizeof aliases / sizeof aliases[0]; i++)
        if (strcasecmp(s, aliases[i].alias) == 0)
            return aliases[i].col;
    /* "r4" as well as "a4" names the r^4 term. */
    if ((s[0] == 'r' || s[0] == 'R') && isdigit((unsigned char)s[1])) {
        char buf[8];
        snprintf(buf, sizeof buf, "a%s", s + 1);
        for (i = COL_ASPH0; i < COL_COUNT; i++)
            if (strcasecmp(buf, names[i]) == 0)
                return (int)i;
    }
    return -1;
}

int cell_numeric(int col)
{
    return col == COL_RADIUS || col == COL_THICKNESS || col == COL_SEMI ||
           col == COL_CONIC || (col >= COL_ASPH0 && col < COL_COUNT);
}

const char *cell_type_name(int type)
{
    return type == SG_SURF_EVENASPH ? "EVENASPH" : "STANDARD";
}

int cell_type_parse(const char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    if (strcasecmp(s, "standard") == 0 || strcasecmp(s, "std") == 0 ||
        strcasecmp(s, "s") == 0)
        return SG_SURF_STANDARD;
    if (strcasecmp(s, "evenasph") == 0 || strcasecmp(s, "evenasphere") == 0 ||
        strcasecmp(s, "asph") == 0 || strcasecmp(s, "asphere") == 0 ||
        strcasecmp(s, "even") == 0 || strcasecmp(s, "e") == 0)
        return SG_SURF_EVENASPH;
    return -1;
}

static void mat_text(const sg_material *m, char *buf, size_t n)
{
    switch (m->kind) {
    case SG_MAT_AIR: snprintf(buf, n, "%s", ""); break;
    case SG_MAT_MIRROR: snprintf(buf, n, "MIRROR"); break;
    case SG_MAT_GLASS: snprintf(buf, n, "%s", m->name); break;
    case SG_MAT_INDEX: numfmt_shortest(m->index, buf, n); break;
    default: snprintf(buf, n, "?"); break;
    }
}

static void text(const sg_system *sys, int row, int col, int edit, char *buf, size_t n)
{
    const sg_surface *s = &sys->surf[row];
    char num[NUMFMT_MAX];
    buf[0] = '\0';
    switch (col) {
    case COL_TYPE: snprintf(buf, n, "%s", cell_type_name(s->type)); break;
    case COL_COMMENT: snprintf(buf, n, "%s", s->comment); break;
    case COL_RADIUS:
        if (!edit && (s->radius == 0.0 || isinf(s->radius)))
            snprintf(buf, n, "Infinity");
        else
            numfmt_shortest(s->radius, buf, n);
        break;
    case COL_THICKNESS: numfmt_shortest(s->thickness, buf, n); break;
    case COL_MATERIAL: mat_text(&s->mat, buf, n); break;
    case COL_SEMI:
        numfmt_shortest(s->semi_diameter, num, sizeof num);
        snprintf(buf, n, "%s%s", num, s->sd_fixed ? " U" : "");
        break;
    case COL_CONIC: numfmt_shortest(s->conic, buf, n); break;
    default:
        if (col >= COL_ASPH0 && col < COL_COUNT)
            numfmt_shortest(s->asph[col - COL_ASPH0], buf, n);
        break;
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
    char buf[128];
    double v;
    const sg_glass *g;
    if (!trimmed(text, buf, sizeof buf)) {
        snprintf(err, errn, "surface %d material: name is too long", row);
        return SG_ERANGE;
    }
    if (buf[0] == '\0' || strcasecmp(buf, "air") == 0) {
        s->mat.kind = SG_MAT_AIR;
        memset(s->mat.name, 0, sizeof s->mat.name);
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
        s->mat.index = v;
        return SG_EOK;
    }
    if (!cat) {
        snprintf(err, errn,
                 "surface %d material: cannot check \"%s\": no glass catalog is loaded "
                 "(set SAGITTA_LENSDB)", row, buf);
        return SG_ENOGLASS;
    }
    g = sg_catalog_find(cat, buf);
    if (!g) {
        snprintf(err, errn, "surface %d material: \"%s\" is not in the catalog", row, buf);
        return SG_ENOGLASS;
    }
    s->mat.kind = SG_MAT_GLASS;
    memset(s->mat.name, 0, sizeof s->mat.name);
    snprintf(s->mat.name, sizeof s->mat.name, "%s", g->name);
    s->mat.index = 0.0;
    return SG_EOK;
}

int cell_set(sg_system *sys, const sg_catalog *cat, int row, int col,
             const char *text, char *err, size_t errn, char *info, size_t infon)
{
    sg_surface *s;
    char buf[128];
    double v;
    int rc;

    if (info && infon)
        info[0] = '\0';
    if (row < 0 || row >= sys->nsurf) {
        snprintf(err, errn, "no surface %d (the design has 0 to %d)", row, sys->nsurf - 1);
        return SG_ERANGE;
    }
    if (col < 0 || col >= COL_COUNT) {
        snprintf(err, errn, "no such column");
        return SG_EINVAL;
    }
    s = &sys->surf[row];
    switch (col) {
    case COL_TYPE:
        rc = cell_type_parse(text);
        if (rc < 0) {
            snprintf(err, errn, "surface %d type: \"%s\" is not STANDARD or EVENASPH",
                     row, text);
            return SG_EPARSE;
        }
        s->type = (sg_surf_type)rc;
        if (rc == SG_SURF_STANDARD && info && infon) {
            int k;
            for (k = 0; k < SG_NASPH && s->asph[k] == 0.0; k++)
                ;
            /* Kept, so switching back restores them, but the trace of a
             * STANDARD surface does not use them: say so. */
            if (k < SG_NASPH)
                snprintf(info, infon, "its r^n terms are kept but ignored (shown dim) "
                                      "until it is EVENASPH again");
        }
        return SG_EOK;
    case COL_COMMENT: {
        const unsigned char *p;
        if (strlen(text) >= SG_COMMENT) {
            snprintf(err, errn, "surface %d comment: longer than %d bytes", row,
                     SG_COMMENT - 1);
            return SG_ERANGE;
        }
        for (p = (const unsigned char *)text; *p; p++)
            if (*p < 0x20 || *p == 0x7f) {
                snprintf(err, errn, "surface %d comment: control characters are not allowed",
                         row);
                return SG_EPARSE;
            }
        memset(s->comment, 0, sizeof s->comment);
        memcpy(s->comment, text, strlen(text));
        return SG_EOK;
    }
    case COL_RADIUS:
        rc = number(text, 1, row, col, &v, err, errn);
        if (rc != SG_EOK)
            return rc;
        s->radius = v;
        return SG_EOK;
    case COL_THICKNESS:
        rc = number(text, row == 0, row, col, &v, err, errn);
        if (rc != SG_EOK)
            return rc;
        if (row == 0 && v == 0.0) {
            snprintf(err, errn, "surface 0 thickness: the object must lie away from "
                     "surface 1 (use Infinity for an object at infinity)");
            return SG_ENONPHYS;
        }
        s->thickness = v;
        return SG_EOK;
    case COL_MATERIAL:
        return set_material(sys, cat, row, text, err, errn);
    case COL_SEMI: {
        int fixed = 0;
        size_t len;
        if (!trimmed(text, buf, sizeof buf)) {
            snprintf(err, errn, "surface %d semi: text is too long", row);
            return SG_EPARSE;
        }
        /* A trailing U fixes the aperture, as Zemax marks it. */
        len = strlen(buf);
        if (len > 0 && (buf[len - 1] == 'U' || buf[len - 1] == 'u')) {
            fixed = 1;
            buf[len - 1] = '\0';
        }
        rc = number(buf, 0, row, col, &v, err, errn);
        if (rc != SG_EOK)
            return rc;
        if (v < 0.0) {
            snprintf(err, errn, "surface %d semi: %s is negative", row, buf);
            return SG_ERANGE;
        }
        s->semi_diameter = v;
        s->sd_fixed = fixed;
        return SG_EOK;
    }
    case COL_CONIC:
        rc = number(text, 0, row, col, &v, err, errn);
        if (rc != SG_EOK)
            return rc;
        s->conic = v;
        return SG_EOK;
    default:
        rc = number(text, 0, row, col, &v, err, errn);
        if (rc != SG_EOK)
            return rc;
        s->asph[col - COL_ASPH0] = v;
        /* A standard surface ignores its polynomial, so a term typed into
         * one means the user wants an asphere. */
        if (v != 0.0 && s->type != SG_SURF_EVENASPH) {
            s->type = SG_SURF_EVENASPH;
            if (info && infon)
                snprintf(info, infon, "surface %d is now EVENASPH", row);
        }
        return SG_EOK;
    }
}
