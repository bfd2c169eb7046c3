/*
 * json_write.c - the JSON design format written (sagitta-design(5)): the
 * checks a design must pass to be written, the text, and the save;
 * design_json.c reads it.
 *
 * Numbers are written in the shortest %.Ng form that reads back to the
 * same double, because a design must survive any number of load/save
 * cycles bit for bit.
 */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <locale.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "formats_int.h"
#include "design.h"

#define FORMAT_NAME "sagitta-design"

/* The names of an enumeration or a closed set of texts, from the table. */
static const sg_param *sysp(const char *key)
{
    return sg_param_find(SG_SCOPE_SYSTEM, key);
}
#define units_names (sysp("units")->names)
#define field_type_names (sysp("fields.type")->names)
#define field_norm_names (sysp("fields.normalization")->names)
#define aper_type_names (sysp("aperture.type")->names)
#define aim_names (sysp("ray_aiming")->names)
#define surf_type_names (sg_param_find(SG_SCOPE_SURFACE, "type")->names)
#define NELEM(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* ------------------------------------------------------------------------
 * Number formatting
 * ------------------------------------------------------------------------ */

/* Writes x in the shortest of %.15g, %.16g and %.17g that strtod reads back
 * to the same bits; %.17g always does.  The locale's decimal point becomes
 * '.', so a UI that called setlocale() still writes valid JSON. */
void sg_json_fmt_double(char out[40], double x)
{
    const char *dp;
    char *p;
    int prec;
    if (isnan(x)) {
        strcpy(out, "nan");
        return;
    }
    if (isinf(x)) {
        strcpy(out, x < 0 ? "-inf" : "inf");
        return;
    }
    for (prec = 15; prec <= 17; prec++) {
        double back;
        snprintf(out, 40, "%.*g", prec, x);
        back = strtod(out, NULL);
        if (memcmp(&back, &x, sizeof x) == 0)
            break;
    }
    dp = localeconv()->decimal_point;
    if (dp && dp[0] && strcmp(dp, ".") != 0 && (p = strstr(out, dp)) != NULL) {
        size_t n = strlen(dp);
        *p = '.';
        memmove(p + 1, p + n, strlen(p + n) + 1);
    }
}

/* ------------------------------------------------------------------------
 * Writing
 * ------------------------------------------------------------------------ */

typedef struct sbuf {
    char *p;
    size_t len, cap;
    int oom;
} sbuf;

static void sb_add(sbuf *b, const char *s, size_t n)
{
    if (b->oom)
        return;
    if (b->len + n + 1 > b->cap) {
        size_t ncap = b->cap ? b->cap : 4096;
        char *p;
        while (ncap < b->len + n + 1)
            ncap *= 2;
        p = realloc(b->p, ncap);
        if (!p) {
            b->oom = 1;
            return;
        }
        b->p = p;
        b->cap = ncap;
    }
    memcpy(b->p + b->len, s, n);
    b->len += n;
    b->p[b->len] = '\0';
}

static void sb_puts(sbuf *b, const char *s)
{
    sb_add(b, s, strlen(s));
}

static void sb_num(sbuf *b, double x)
{
    char t[40];
    sg_json_fmt_double(t, x);
    sb_puts(b, t);
}

/* A radius or thickness: a number, or "inf"/"-inf". */
static void sb_len(sbuf *b, double x)
{
    if (isinf(x))
        sb_puts(b, x < 0 ? "\"-inf\"" : "\"inf\"");
    else
        sb_num(b, x);
}

/* A quoted, escaped JSON string; cJSON does the escaping. */
static void sb_str(sbuf *b, const char *s)
{
    cJSON *item = cJSON_CreateString(s);
    char *q = item ? cJSON_PrintUnformatted(item) : NULL;
    if (q)
        sb_puts(b, q);
    else
        b->oom = 1;
    if (q)
        cJSON_free(q);
    cJSON_Delete(item);
}

static int terminated(const char *s, size_t cap)
{
    return memchr(s, '\0', cap) != NULL;
}

/* Refuses a value of the table that the loader would refuse: where names
 * the object ("surface 3"), isurf the surface or -1. */
static int check_param(const sg_param *p, const void *obj, const char *where, int isurf,
                       sg_diag *d)
{
    const void *q = sg_param_cptr(p, obj);
    int k;
    switch (p->kind) {
    case SG_PARAM_ENUM:
        if ((unsigned)*(const int *)q >= (unsigned)p->nnames)
            return sg_diag_set(d, SG_EINVAL, "%s: unknown %s %d", where, p->key, *(const int *)q);
        return SG_OK;
    case SG_PARAM_TEXT:
        if (!terminated(q, p->size))
            return sg_diag_set(d, SG_EINVAL, "%s: %s is not a terminated string", where, p->key);
        return SG_OK;
    case SG_PARAM_BOOL:
        return SG_OK;
    case SG_PARAM_MATERIAL: {
        const sg_material *m = q;
        switch (m->kind) {
        case SG_MAT_AIR:
        case SG_MAT_MIRROR:
            return SG_OK;
        case SG_MAT_GLASS:
            if (!terminated(m->name, sizeof m->name) || m->name[0] == '\0')
                return sg_diag_set(d, SG_EINVAL, "%s: material: glass has no name", where);
            if (!terminated(m->catalog, sizeof m->catalog))
                return sg_diag_set(d, SG_EINVAL, "%s: material: catalog is not a terminated "
                                   "string", where);
            return SG_OK;
        case SG_MAT_INDEX:
            if (!isfinite(m->index))
                return sg_diag_set(d, SG_EINVAL, "%s: material: index is %g", where, m->index);
            return SG_OK;
        case SG_MAT_MODEL:
            if (!isfinite(m->index) || !isfinite(m->vd) || !isfinite(m->dpgf))
                return sg_diag_set(d, SG_EINVAL, "%s: material: model glass nd %g, vd %g, "
                                   "dpgf %g", where, m->index, m->vd, m->dpgf);
            return SG_OK;
        default:
            return sg_diag_set(d, SG_EINVAL, "%s: material: unknown kind %d", where,
                               (int)m->kind);
        }
    }
    case SG_PARAM_REAL:
        break;
    }
    for (k = 0; k < p->count; k++) {
        double v = ((const double *)q)[k];
        char key[48], head[24];
        if (p->count > 1) {
            sg_param_heading(p, k, head, sizeof head);
            snprintf(key, sizeof key, "%s[%d] (%s)", p->key, k, head);
        } else
            snprintf(key, sizeof key, "%s", p->key);
        if (isnan(v) && (p->flags & (SG_PARAM_INF | SG_PARAM_OBJ_INF)))
            return sg_diag_set(d, SG_EINVAL, "%s: %s is NaN", where, key);
        if (p->flags & SG_PARAM_INF)
            continue;
        if ((p->flags & SG_PARAM_OBJ_INF) && isinf(v)) {
            if (isurf != 0 || v < 0)
                return sg_diag_set(d, SG_EINVAL, "%s: %s is %g; only the object's "
                                   "%s may be +inf", where, key, v, key);
            continue;
        }
        if ((p->flags & SG_PARAM_POSITIVE) && !(isfinite(v) && v > 0.0))
            return sg_diag_set(d, SG_EINVAL, "%s: %s is %g; it must be positive and finite",
                               where, key, v);
        if ((p->flags & SG_PARAM_NONNEG) && !(isfinite(v) && v >= 0.0))
            return sg_diag_set(d, SG_EINVAL,
                               "%s: %s is %g; it must be finite and not negative", where, key, v);
        if (!isfinite(v))
            return sg_diag_set(d, SG_EINVAL, "%s: %s is %g", where, key, v);
    }
    return SG_OK;
}

static int check_scope(sg_param_scope scope, const void *obj, const char *where, int isurf,
                       sg_diag *d)
{
    int i, rc;
    for (i = 0; i < sg_param_count(scope); i++)
        if ((rc = check_param(sg_param_at(scope, i), obj, where, isurf, d)) != SG_OK)
            return rc;
    return SG_OK;
}

/* Refuses what the loader would refuse, so that every saved file loads. */
static int check_writable(const sg_system *sys, sg_diag *d)
{
    char where[32];
    int i, k, rc;
    if (!sys)
        return sg_diag_set(d, SG_EINVAL, "save: no system");
    if (!terminated(sys->title, sizeof sys->title))
        return sg_diag_set(d, SG_EINVAL, "title: not a terminated string");
    for (k = 0; k < sysp("units")->nnames; k++)
        if (terminated(sys->units, sizeof sys->units) && strcmp(sys->units, units_names[k]) == 0)
            break;
    if (k == sysp("units")->nnames)
        return sg_diag_set(d, SG_EINVAL, "units: must be mm, cm, in or m");
    if (sys->nwave < 1 || sys->nwave > SG_MAX_WAVES)
        return sg_diag_set(d, SG_EINVAL, "wavelengths: %d given, 1 to %d allowed", sys->nwave,
                           SG_MAX_WAVES);
    if (sys->primary_wave < 0 || sys->primary_wave >= sys->nwave)
        return sg_diag_set(d, SG_EINVAL, "wavelengths: primary %d is not one of 1 to %d",
                           sys->primary_wave + 1, sys->nwave);
    for (k = 0; k < sys->nwave; k++) {
        snprintf(where, sizeof where, "wavelength %d", k + 1);
        if ((rc = check_scope(SG_SCOPE_WAVE, &sys->wave[k], where, -1, d)) != SG_OK)
            return rc;
    }
    if ((unsigned)sys->field_type >= (unsigned)sysp("fields.type")->nnames ||
        (unsigned)sys->field_norm >= (unsigned)sysp("fields.normalization")->nnames)
        return sg_diag_set(d, SG_EINVAL, "fields: unknown field type or normalization");
    if (sys->nfield < 1 || sys->nfield > SG_MAX_FIELDS)
        return sg_diag_set(d, SG_EINVAL, "fields: %d given, 1 to %d allowed", sys->nfield,
                           SG_MAX_FIELDS);
    for (k = 0; k < sys->nfield; k++) {
        snprintf(where, sizeof where, "field %d", k + 1);
        if ((rc = check_scope(SG_SCOPE_FIELD, &sys->field[k], where, -1, d)) != SG_OK)
            return rc;
    }
    if ((unsigned)sys->aper_type >= (unsigned)sysp("aperture.type")->nnames)
        return sg_diag_set(d, SG_EINVAL, "aperture: unknown type %d", (int)sys->aper_type);
    if (!isfinite(sys->aper_value) || !(sys->aper_value >= 0.0))
        return sg_diag_set(d, SG_EINVAL, "aperture: value is %g; it must be finite and not negative",
                           sys->aper_value);
    if ((unsigned)sys->aim >= (unsigned)sysp("ray_aiming")->nnames)
        return sg_diag_set(d, SG_EINVAL, "ray_aiming: unknown mode %d", (int)sys->aim);
    if (!(sys->temperature >= SG_TEMP_MIN && sys->temperature <= SG_TEMP_MAX))
        return sg_diag_set(d, SG_EINVAL, "temperature: %g C is outside %g to %g C",
                           sys->temperature, SG_TEMP_MIN, SG_TEMP_MAX);
    if (!(sys->pressure >= 0.0 && sys->pressure <= SG_PRES_MAX))
        return sg_diag_set(d, SG_EINVAL, "pressure: %g atm is outside 0 to %g atm",
                           sys->pressure, SG_PRES_MAX);
    if (sys->nsurf < 3 || sys->nsurf > SG_MAX_SURFACES || !sys->surf)
        return sg_diag_set(d, SG_EINVAL, "surfaces: %d given, 3 to %d allowed", sys->nsurf,
                           SG_MAX_SURFACES);
    if (sys->stop < 1 || sys->stop > sys->nsurf - 2)
        return sg_diag_set(d, SG_EINVAL, "surfaces: the stop (%d) must be one of surfaces 1 to %d",
                           sys->stop, sys->nsurf - 2);
    for (i = 0; i < sys->nsurf; i++) {
        snprintf(where, sizeof where, "surface %d", i);
        if ((rc = check_scope(SG_SCOPE_SURFACE, &sys->surf[i], where, i, d)) != SG_OK)
            return rc;
    }
    return SG_OK;
}

/* One value of the table as JSON. */
static void sb_param(sbuf *b, const sg_param *p, const void *obj)
{
    const void *q = sg_param_cptr(p, obj);
    int k;
    switch (p->kind) {
    case SG_PARAM_ENUM:
        sb_str(b, p->names[*(const int *)q]);
        return;
    case SG_PARAM_TEXT:
        sb_str(b, q);
        return;
    case SG_PARAM_BOOL:
        sb_puts(b, *(const int *)q ? "true" : "false");
        return;
    case SG_PARAM_MATERIAL: {
        const sg_material *m = q;
        switch (m->kind) {
        case SG_MAT_MIRROR: sb_puts(b, "\"MIRROR\""); break;
        case SG_MAT_GLASS:
            if (!m->catalog[0]) {
                sb_str(b, m->name);
                break;
            }
            sb_puts(b, "{ \"glass\": ");
            sb_str(b, m->name);
            sb_puts(b, ", \"catalog\": ");
            sb_str(b, m->catalog);
            sb_puts(b, " }");
            break;
        case SG_MAT_INDEX: sb_num(b, m->index); break;
        case SG_MAT_MODEL:
            sb_puts(b, "{ \"nd\": ");
            sb_num(b, m->index);
            sb_puts(b, ", \"vd\": ");
            sb_num(b, m->vd);
            sb_puts(b, ", \"dpgf\": ");
            sb_num(b, m->dpgf);
            sb_puts(b, " }");
            break;
        default: sb_puts(b, "\"AIR\""); break;
        }
        return;
    }
    case SG_PARAM_REAL:
        break;
    }
    if (p->count > 1) {
        sb_puts(b, "[");
        for (k = 0; k < p->count; k++) {
            if (k)
                sb_puts(b, ", ");
            sb_num(b, ((const double *)q)[k]);
        }
        sb_puts(b, "]");
    } else if (p->flags & SG_PARAM_INF) {
        double v = *(const double *)q;
        /* 0 means flat in C as on input; write it the way it reads back. */
        sb_len(b, v == 0.0 ? INFINITY : v);
    } else if (p->flags & SG_PARAM_OBJ_INF) {
        sb_len(b, *(const double *)q);
    } else {
        sb_num(b, *(const double *)q);
    }
}

/* A frame change as get_change reads it. */
static void sb_change(sbuf *b, const sg_frame_change *f)
{
    sb_puts(b, "{\"decenter\": [");
    sb_num(b, f->dx);
    sb_puts(b, ", ");
    sb_num(b, f->dy);
    sb_puts(b, "], \"tilt\": [");
    sb_num(b, f->tx);
    sb_puts(b, ", ");
    sb_num(b, f->ty);
    sb_puts(b, ", ");
    sb_num(b, f->tz);
    sb_puts(b, "], \"order\": \"");
    sb_puts(b, f->order ? "tilt_then_decenter" : "decenter_then_tilt");
    sb_puts(b, "\"}");
}

/* A surface's solves as get_solves reads them; nothing without one. */
static void sb_solves(sbuf *b, const sg_surface *s)
{
    int t, n = 0;
    char buf[80];
    for (t = 0; t < SG_SOLVE_NTARGETS; t++) {
        const sg_solve *v = &s->solve[t];
        if (v->kind == SG_SOLVE_NONE)
            continue;
        sb_puts(b, n++ ? ", \"" : ",\n      \"solves\": { \"");
        sb_puts(b, sg_solve_target_name((sg_solve_target)t));
        sb_puts(b, "\": {\"type\": \"");
        sb_puts(b, sg_solve_kind_name(v->kind));
        if (v->kind == SG_SOLVE_VARIABLE) {
            sb_puts(b, "\"");
            if (isfinite(v->lo)) {
                sb_puts(b, ", \"min\": ");
                sb_num(b, v->lo);
            }
            if (isfinite(v->hi)) {
                sb_puts(b, ", \"max\": ");
                sb_num(b, v->hi);
            }
        } else if (sg_solve_is_pickup(v->kind)) {
            snprintf(buf, sizeof buf, "\", \"from\": %d", v->from);
            sb_puts(b, buf);
            sb_puts(b, ", \"scale\": ");
            sb_num(b, v->scale);
            sb_puts(b, ", \"offset\": ");
            sb_num(b, v->offset);
        } else {
            if (v->kind == SG_SOLVE_POSITION) {
                snprintf(buf, sizeof buf, "\", \"from\": %d", v->from);
                sb_puts(b, buf);
                sb_puts(b, ", \"value\": ");
            } else {
                sb_puts(b, "\", \"value\": ");
            }
            sb_num(b, v->value);
        }
        sb_puts(b, "}");
    }
    /* The other variables, an array where one key has several. */
    for (t = 0; t < s->nvar; t++) {
        const sg_pvar *v = &s->var[t];
        int k, same = 0, first = 1;
        for (k = 0; k < s->nvar; k++)
            if (s->var[k].param == v->param) {
                same++;
                if (k < t)
                    first = 0;
            }
        if (!first)
            continue;
        sb_puts(b, n++ ? ", \"" : ",\n      \"solves\": { \"");
        sb_puts(b, v->param->key);
        sb_puts(b, same > 1 ? "\": [" : "\": ");
        for (k = t, same = 0; k < s->nvar; k++) {
            const sg_pvar *w = &s->var[k];
            if (w->param != v->param)
                continue;
            snprintf(buf, sizeof buf, "%s{\"type\": \"variable\", \"element\": %d",
                     same++ ? ", " : "", w->elem);
            sb_puts(b, buf);
            if (isfinite(w->lo)) {
                sb_puts(b, ", \"min\": ");
                sb_num(b, w->lo);
            }
            if (isfinite(w->hi)) {
                sb_puts(b, ", \"max\": ");
                sb_num(b, w->hi);
            }
            sb_puts(b, "}");
        }
        if (same > 1)
            sb_puts(b, "]");
    }
    if (n)
        sb_puts(b, " }");
}

/* The tolerances as get_tolerances reads them. */
static void sb_tolerances(sbuf *b, const sg_tolerances *t)
{
    static const char *const crits[] = {"rms_spot", "merit", "rms_wavefront"};
    static const char *const refs[] = {"chief", "centroid"};
    static const char *const dists[] = {"normal", "uniform", "parabolic"};
    char x[200];
    int i;
    sb_puts(b, ",\n  \"tolerances\": {\n");
    if (t->test_wave > 0.0) {
        sb_puts(b, "    \"test_wavelength\": ");
        sb_num(b, t->test_wave);
        sb_puts(b, ",\n");
    }
    sb_puts(b, "    \"operands\": [");
    for (i = 0; i < t->nop; i++) {
        const sg_tol_operand *o = &t->op[i];
        sb_puts(b, i ? ",\n      {\"type\": \"" : "\n      {\"type\": \"");
        sb_puts(b, sg_tol_name(o->type));
        if (o->type >= SG_TOL_TEDX && o->type <= SG_TOL_TETZ)
            snprintf(x, sizeof x, "\", \"first\": %d, \"last\": %d", o->surface, o->last);
        else
            snprintf(x, sizeof x, "\", \"surface\": %d", o->surface);
        sb_puts(b, x);
        if (o->type == SG_TOL_TTHI && o->adjust >= 0) {
            snprintf(x, sizeof x, ", \"adjust\": %d", o->adjust);
            sb_puts(b, x);
        }
        if (o->type == SG_TOL_TEZI) {
            snprintf(x, sizeof x, ", \"max_term\": %d, \"min_term\": %d", o->zmax, o->zmin);
            sb_puts(b, x);
        }
        if (o->type == SG_TOL_TPAR) {
            sb_puts(b, ", \"parameter\": ");
            sb_str(b, o->param);
            snprintf(x, sizeof x, ", \"element\": %d", o->elem);
            sb_puts(b, x);
        }
        sb_puts(b, ", \"min\": ");
        sb_num(b, o->min);
        sb_puts(b, ", \"max\": ");
        sb_num(b, o->max);
        sb_puts(b, "}");
    }
    sb_puts(b, t->nop ? "\n    ],\n    \"compensators\": [" : "],\n    \"compensators\": [");
    for (i = 0; i < t->ncomp; i++) {
        const sg_tol_comp *o = &t->comp[i];
        snprintf(x, sizeof x, "%s{\"surface\": %d, \"parameter\": ", i ? ",\n      " : "\n      ",
                 o->surface);
        sb_puts(b, x);
        sb_str(b, o->param);
        if (o->elem) {
            snprintf(x, sizeof x, ", \"element\": %d", o->elem);
            sb_puts(b, x);
        }
        sb_puts(b, ", \"min\": ");
        sb_num(b, o->min);
        sb_puts(b, ", \"max\": ");
        sb_num(b, o->max);
        sb_puts(b, "}");
    }
    snprintf(x, sizeof x, "%s],\n    \"criterion\": {\"type\": \"%s\", \"reference\": \"%s\", "
             "\"sampling\": {\"pattern\": \"%s\", \"density\": %d, \"grid\": %d}},\n",
             t->ncomp ? "\n    " : "",
             crits[t->criterion >= 0 && t->criterion < 3 ? t->criterion : 0],
             refs[t->reference == 1], sg_pupil_pattern_name(t->pattern), t->density, t->grid);
    sb_puts(b, x);
    snprintf(x, sizeof x, "    \"monte_carlo\": {\"trials\": %d, \"seed\": %.0f, "
             "\"distribution\": \"%s\"}\n  }", t->trials, t->seed,
             dists[t->distribution >= 0 && t->distribution < 3 ? t->distribution : 0]);
    sb_puts(b, x);
}

/* The merit function as get_merit reads it. */
/* The configurations as get_configs reads them. */
static void sb_configs(sbuf *b, const sg_configs *cf)
{
    const sg_param *mp = sg_param_find(SG_SCOPE_SURFACE, "material");
    char t[96];
    int i, k;
    snprintf(t, sizeof t, ",\n  \"configurations\": {\n    \"count\": %d,\n", cf->n);
    sb_puts(b, t);
    if (cf->current != 1) {
        snprintf(t, sizeof t, "    \"current\": %d,\n", cf->current);
        sb_puts(b, t);
    }
    sb_puts(b, "    \"operands\": [\n");
    for (i = 0; i < cf->nop; i++) {
        const sg_config_op *o = &cf->op[i];
        const char *ty = o->type;
        const char *nk = !strcmp(ty, "XFIE") || !strcmp(ty, "YFIE") || !strcmp(ty, "FLWT") ? "field"
                         : !strcmp(ty, "WAVE") || !strcmp(ty, "WLWT") ? "wavelength"
                         : !strcmp(ty, "APER") || !strcmp(ty, "STPS") || !strcmp(ty, "TEMP") ||
                                 !strcmp(ty, "PRES")
                             ? NULL
                             : "surface";
        sb_puts(b, "      { \"type\": ");
        sb_str(b, ty);
        if (nk) {
            snprintf(t, sizeof t, ", \"%s\": %d", nk, o->num);
            sb_puts(b, t);
        }
        if (!strcmp(ty, "PRAM")) {
            snprintf(t, sizeof t, ", \"parameter\": %d", o->num2);
            sb_puts(b, t);
        }
        sb_puts(b, ", \"values\": [");
        for (k = 0; k < cf->n; k++) {
            if (k)
                sb_puts(b, ", ");
            if (o->mat) {
                sg_surface s;
                memset(&s, 0, sizeof s);
                s.mat = o->mat[k];
                sb_param(b, mp, &s);
            } else {
                sb_num(b, o->value[k]);
            }
        }
        sb_puts(b, i + 1 < cf->nop ? "] },\n" : "] }\n");
    }
    sb_puts(b, "    ]\n  }");
}

static void sb_merit(sbuf *b, const sg_merit *m)
{
    static const char *const refs[] = {"centroid", "chief"};
    char t[96];
    int i;
    sb_puts(b, ",\n  \"merit\": {");
    if (m->has_default) {
        snprintf(t, sizeof t, "\n    \"default\": {\"criterion\": \"spot\", \"reference\": "
                 "\"%s\", \"rings\": %d, \"arms\": %d}", refs[m->reference == 1], m->rings,
                 m->arms);
        sb_puts(b, t);
    }
    sb_puts(b, m->has_default ? ",\n    \"operands\": [" : "\n    \"operands\": [");
    for (i = 0; i < m->nop; i++) {
        const sg_operand *o = &m->op[i];
        const sg_op_info *inf = sg_op_info_of(o->type);
        sb_puts(b, i ? ",\n      {\"type\": \"" : "\n      {\"type\": \"");
        sb_puts(b, inf->name);
        sb_puts(b, "\"");
        if (inf->k1) {
            snprintf(t, sizeof t, ", \"%s\": %d", inf->k1, o->i1);
            sb_puts(b, t);
        }
        if (inf->k2) {
            snprintf(t, sizeof t, ", \"%s\": %d", inf->k2, o->i2);
            sb_puts(b, t);
        }
        {
            const double dv[4] = {o->hx, o->hy, o->px, o->py};
            int k;
            for (k = 0; k < 4; k++)
                if (inf->d[k]) {
                    snprintf(t, sizeof t, ", \"%s\": ", inf->d[k]);
                    sb_puts(b, t);
                    sb_num(b, dv[k]);
                }
        }
        sb_puts(b, ", \"target\": ");
        sb_num(b, o->target);
        sb_puts(b, ", \"weight\": ");
        sb_num(b, o->weight);
        sb_puts(b, "}");
    }
    sb_puts(b, m->nop ? "\n    ]\n  }" : "]\n  }");
}

/* Whether an optional parameter is at its default, so not written. */
static int at_default(const sg_param *p, const void *obj)
{
    int k;
    if (!(p->flags & SG_PARAM_OPTIONAL))
        return 0;
    for (k = 0; k < p->count; k++) {
        double v = sg_param_get(p, obj, k), def = p->def;
        if (memcmp(&v, &def, sizeof v) != 0)
            return 0;
    }
    return 1;
}

/* The members of obj's table, each after sep (the first after first). */
static void sb_scope(sbuf *b, sg_param_scope scope, const void *obj, const char *first,
                     const char *sep)
{
    int i, n = 0;
    for (i = 0; i < sg_param_count(scope); i++) {
        const sg_param *p = sg_param_at(scope, i);
        if ((p->flags & SG_PARAM_NESTED) || at_default(p, obj))
            continue;
        sb_puts(b, n++ ? sep : first);
        sb_puts(b, "\"");
        sb_puts(b, p->key);
        sb_puts(b, "\": ");
        sb_param(b, p, obj);
    }
}

/* The format version a file needs: that of the newest key written. */
static int needed_version(sg_param_scope scope, const void *obj, int v)
{
    int i;
    for (i = 0; i < sg_param_count(scope); i++) {
        const sg_param *p = sg_param_at(scope, i);
        if (p->version > v && !(p->flags & SG_PARAM_NESTED) && !at_default(p, obj))
            v = p->version;
    }
    return v;
}

/* The design's text, or NULL with *rc set to the reason. */
static char *build_json(const sg_system *sys, sg_diag *d, int *rc)
{
    sbuf b = {NULL, 0, 0, 0};
    char t[96];
    int i, k, version;

    *rc = check_writable(sys, d);
    if (*rc != SG_OK)
        return NULL;
    sb_puts(&b, "{\n  \"format\": \"" FORMAT_NAME "\",\n");
    version = 1;
    for (k = 0; k < sys->nwave; k++)
        version = needed_version(SG_SCOPE_WAVE, &sys->wave[k], version);
    for (k = 0; k < sys->nfield; k++)
        version = needed_version(SG_SCOPE_FIELD, &sys->field[k], version);
    for (i = 0; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        version = needed_version(SG_SCOPE_SURFACE, s, version);
        /* The shapes beyond the even asphere came with version 3. */
        if (s->type >= SG_SURF_ODDASPH)
            version = version < 3 ? 3 : version;
        /* Coordinate breaks, tilts and model glasses came with version 2. */
        if (s->type == SG_SURF_COORDBRK || sg_surface_moves_frame(s) || s->before.order ||
            s->after.order || s->after_mode != SG_AFTER_EXPLICIT || s->mat.kind == SG_MAT_MODEL)
            version = version < 2 ? 2 : version;
    }
    /* System keys newer than version 1 (object-space telecentric), and
     * the object cone angle, version 3's aperture type. */
    version = needed_version(SG_SCOPE_SYSTEM, sys, version);
    if (sys->aper_type == SG_APER_OBJECT_CONE)
        version = version < 3 ? 3 : version;
    /* A glass named with its catalog came with version 4. */
    for (i = 0; i < sys->nsurf; i++)
        if (sys->surf[i].mat.kind == SG_MAT_GLASS && sys->surf[i].mat.catalog[0])
            version = version < 4 ? 4 : version;
    /* So did the environment: a version-1 reader would trace at 20 C. */
    if (sys->temperature != 20.0 || sys->pressure != 1.0 || sys->adjust_index)
        version = version < 2 ? 2 : version;
    /* The curvature pickup and the position solve came with version 5. */
    for (i = 0; i < sys->nsurf; i++)
        if (sys->surf[i].solve[SG_SOLVE_RADIUS].kind == SG_SOLVE_CURV_PICKUP ||
            sys->surf[i].solve[SG_SOLVE_THICKNESS].kind == SG_SOLVE_POSITION)
            version = version < 5 ? 5 : version;
    /* Variables and the merit function came with version 6. */
    for (i = 0; i < sys->nsurf; i++)
        for (k = 0; k < SG_SOLVE_NTARGETS; k++)
            if (sys->surf[i].solve[k].kind == SG_SOLVE_VARIABLE || sys->surf[i].nvar)
                version = version < 6 ? 6 : version;
    if (sys->merit.present)
        version = version < 6 ? 6 : version;
    /* Configurations and tolerances came with version 7. */
    if (sys->configs || sys->tol.present)
        version = version < 7 ? 7 : version;
    /* A file says the oldest format that reads it, so designs without the
     * newer keys stay readable by older programs. */
    snprintf(t, sizeof t, "  \"version\": %d,\n", version);
    sb_puts(&b, t);
    sb_puts(&b, "  \"title\": ");
    sb_str(&b, sys->title);
    sb_puts(&b, ",\n  \"units\": ");
    sb_str(&b, sys->units);

    snprintf(t, sizeof t, ",\n  \"wavelengths\": {\n    \"primary\": %d,\n", sys->primary_wave + 1);
    sb_puts(&b, t);
    sb_puts(&b, "    \"list\": [\n");
    for (k = 0; k < sys->nwave; k++) {
        sb_scope(&b, SG_SCOPE_WAVE, &sys->wave[k], "      { ", ", ");
        sb_puts(&b, k + 1 < sys->nwave ? " },\n" : " }\n");
    }
    sb_puts(&b, "    ]\n  },\n");

    sb_puts(&b, "  \"fields\": {\n    \"type\": ");
    sb_str(&b, field_type_names[sys->field_type]);
    sb_puts(&b, ",\n    \"normalization\": ");
    sb_str(&b, field_norm_names[sys->field_norm]);
    sb_puts(&b, ",\n    \"list\": [\n");
    for (k = 0; k < sys->nfield; k++) {
        sb_scope(&b, SG_SCOPE_FIELD, &sys->field[k], "      { ", ", ");
        sb_puts(&b, k + 1 < sys->nfield ? " },\n" : " }\n");
    }
    sb_puts(&b, "    ]\n  },\n");

    sb_puts(&b, "  \"aperture\": { \"type\": ");
    sb_str(&b, aper_type_names[sys->aper_type]);
    sb_puts(&b, ", \"value\": ");
    sb_num(&b, sys->aper_value);
    if (sys->telecentric)
        sb_puts(&b, ", \"telecentric\": true");
    sb_puts(&b, " },\n  \"ray_aiming\": ");
    sb_str(&b, aim_names[sys->aim]);
    if (sys->afocal)
        sb_puts(&b, ",\n  \"afocal\": true");
    /* Written only away from the defaults, so older files save unchanged. */
    if (sys->temperature != 20.0 || sys->pressure != 1.0 || sys->adjust_index) {
        sb_puts(&b, ",\n  \"temperature\": ");
        sb_num(&b, sys->temperature);
        sb_puts(&b, ",\n  \"pressure\": ");
        sb_num(&b, sys->pressure);
        sb_puts(&b, ",\n  \"adjust_index\": ");
        sb_puts(&b, sys->adjust_index ? "true" : "false");
    }
    sb_puts(&b, ",\n  \"surfaces\": [\n");

    for (i = 0; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        sb_scope(&b, SG_SCOPE_SURFACE, s, "    {\n      ", ",\n      ");
        if (s->type == SG_SURF_COORDBRK) {
            sb_puts(&b, ",\n      \"break\": ");
            sb_change(&b, &s->before);
        } else {
            /* An order alone moves nothing but is the user's setting:
             * it is written, or a save and load would lose it. */
            if (!sg_frame_change_is_zero(&s->before) || s->before.order) {
                sb_puts(&b, ",\n      \"before\": ");
                sb_change(&b, &s->before);
            }
            if (s->after_mode == SG_AFTER_REVERSE) {
                sb_puts(&b, ",\n      \"after\": \"reverse\"");
            } else if (!sg_frame_change_is_zero(&s->after) || s->after.order) {
                sb_puts(&b, ",\n      \"after\": ");
                sb_change(&b, &s->after);
            }
        }
        sb_solves(&b, s);
        sb_puts(&b, i == sys->stop ? ",\n      \"stop\": true\n" : ",\n      \"stop\": false\n");
        sb_puts(&b, i + 1 < sys->nsurf ? "    },\n" : "    }\n");
    }
    sb_puts(&b, "  ]");
    if (sys->merit.present)
        sb_merit(&b, &sys->merit);
    if (sys->configs)
        sb_configs(&b, sys->configs);
    if (sys->tol.present)
        sb_tolerances(&b, &sys->tol);
    sb_puts(&b, "\n}\n");
    if (b.oom) {
        free(b.p);
        *rc = sg_diag_set(d, SG_ENOMEM, "out of memory while writing the design");
        return NULL;
    }
    return b.p;
}

char *sg_design_to_json(const sg_system *sys)
{
    int rc;
    return build_json(sys, NULL, &rc);
}

int sg_design_save(const sg_system *sys, const char *path, sg_diag *d)
{
    return sg_design_save_flags(sys, path, 0, d);
}

int sg_design_save_flags(const sg_system *sys, const char *path, unsigned flags, sg_diag *d)
{
    char *text;
    int rc, kept;

    if (!sys || !path || !path[0])
        return sg_diag_set(d, SG_EINVAL, "save: no system or no path");
    /* An archive is read, never written: its other members (catalogs,
     * coatings) would be lost. */
    if (sg_zar_detect(path, NULL, 0))
        return sg_diag_set(d, SG_EUNSUPPORTED,
                           "%s: sagitta reads Zemax archives but does not write them; save as "
                           ".json or .zmx", path);
    /* A name ending in .zmx is written as a Zemax lens file. */
    if (sg_zmx_detect(path, NULL, 0))
        return sg_zmx_save_flags(sys, path, NULL, flags, d);
    text = build_json(sys, d, &rc);
    if (!text)
        return rc;
    rc = sg_save_text_atomic(path, text, strlen(text), d);
    free(text);
    /* A JSON design holds the model only (sagitta-design(5), ZEMAX FILES). */
    kept = sg_zmx_kept_lines(sys);
    if (rc == SG_OK && kept)
        sg_diag_warn(d, "%s: %d line%s of the Zemax file the design was read from (tolerances, "
                     "merit function, display settings ...) %s not kept in a JSON design; save "
                     "as .zmx to keep them", path, kept, kept == 1 ? "" : "s",
                     kept == 1 ? "is" : "are");
    return rc;
}
