/*
 * config.c - configurations, as Zemax's Multi-Configuration Editor holds
 * them: operands that give one parameter of the design a value in each
 * configuration.  Configuration k's design is the design with every
 * operand's k-th value set (sg_config_apply), so every analysis runs on it
 * unchanged.  sagitta-design(5), CONFIGURATIONS.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_int.h"

/* The operands sagitta applies: Zemax's names and what they address. */
typedef enum { CO_SURF, CO_SYS, CO_FIELD, CO_WAVE } co_scope;
static const struct {
    const char *type;
    co_scope scope;
} co_types[] = {
    {"THIC", CO_SURF}, {"CRVT", CO_SURF}, {"CONI", CO_SURF}, {"SDIA", CO_SURF},
    {"GLSS", CO_SURF}, {"PRAM", CO_SURF}, {"APER", CO_SYS},   {"STPS", CO_SYS},
    {"TEMP", CO_SYS},  {"PRES", CO_SYS},  {"XFIE", CO_FIELD}, {"YFIE", CO_FIELD},
    {"FLWT", CO_FIELD}, {"WAVE", CO_WAVE}, {"WLWT", CO_WAVE},
};
#define CO_NTYPES ((int)(sizeof co_types / sizeof *co_types))

static int co_find(const char *type)
{
    int i;
    for (i = 0; i < CO_NTYPES; i++)
        if (strcmp(co_types[i].type, type) == 0)
            return i;
    return -1;
}

sg_configs *sg_configs_new(int n)
{
    sg_configs *c;
    if (n < 2 || n > SG_MAX_CONFIGS)
        return NULL;
    c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    c->refs = 1;
    c->n = n;
    c->current = 1;
    return c;
}

int sg_configs_add(sg_configs *c, const char *type, int num, int num2, sg_diag *d)
{
    sg_config_op *o;
    int t;
    if (!c || !type)
        return sg_diag_set(d, SG_EINVAL, "configurations: no table or no operand type");
    t = co_find(type);
    if (t < 0)
        return sg_diag_set(d, SG_ERANGE, "configuration operand %.8s: sagitta applies THIC, "
                           "CRVT, CONI, SDIA, GLSS, PRAM, APER, STPS, TEMP, PRES, XFIE, YFIE, "
                           "FLWT, WAVE and WLWT", type);
    if (c->nop == SG_MAX_CONFIG_OPS)
        return sg_diag_set(d, SG_ERANGE, "configurations: more than %d operands",
                           SG_MAX_CONFIG_OPS);
    o = &c->op[c->nop];
    memset(o, 0, sizeof *o);
    o->value = calloc((size_t)c->n, sizeof *o->value);
    if (!o->value)
        return sg_diag_set(d, SG_ENOMEM, "configurations: out of memory");
    if (strcmp(type, "GLSS") == 0) {
        o->mat = calloc((size_t)c->n, sizeof *o->mat);
        if (!o->mat) {
            free(o->value);
            return sg_diag_set(d, SG_ENOMEM, "configurations: out of memory");
        }
    }
    strcpy(o->type, co_types[t].type);
    o->num = num;
    o->num2 = num2;
    c->nop++;
    return SG_OK;
}

void sg_configs_retain(sg_configs *c)
{
    if (c)
        __atomic_add_fetch(&c->refs, 1, __ATOMIC_RELAXED);
}

void sg_configs_release(sg_configs *c)
{
    int i;
    if (!c || __atomic_sub_fetch(&c->refs, 1, __ATOMIC_ACQ_REL) != 0)
        return;
    for (i = 0; i < c->nop; i++) {
        free(c->op[i].value);
        free(c->op[i].mat);
    }
    free(c);
}

/* The table after inserting (dir 1) or deleting (dir -1) surface at, as
 * Zemax renumbers its Multi-Configuration Editor: a surface operand (and
 * each STPS value) naming a later surface follows it; an operand of the
 * deleted surface goes with it.  A new table in *out (refs 1), or NULL
 * when nothing names a surface that moves. */
int sg_configs_renumbered(const sg_configs *c, int at, int dir, sg_configs **out)
{
    sg_configs *n;
    int i, k, moves = 0;
    *out = NULL;
    if (!c)
        return SG_OK;
    for (i = 0; i < c->nop; i++) {
        const sg_config_op *o = &c->op[i];
        if (co_types[co_find(o->type)].scope == CO_SURF && o->num >= at)
            moves = 1;
        if (!strcmp(o->type, "STPS"))
            for (k = 0; k < c->n; k++)
                moves |= o->value[k] >= at;
    }
    if (!moves)
        return SG_OK;
    if (!(n = sg_configs_new(c->n)))
        return SG_ENOMEM;
    n->current = c->current;
    for (i = 0; i < c->nop; i++) {
        const sg_config_op *o = &c->op[i];
        sg_config_op *p;
        int num = o->num;
        if (co_types[co_find(o->type)].scope == CO_SURF) {
            if (dir < 0 && num == at)
                continue;
            if (num >= at + (dir < 0))
                num += dir;
        }
        if (sg_configs_add(n, o->type, num, o->num2, NULL) != SG_OK) {
            sg_configs_release(n);
            return SG_ENOMEM;
        }
        p = &n->op[n->nop - 1];
        memcpy(p->value, o->value, (size_t)c->n * sizeof *p->value);
        if (o->mat)
            memcpy(p->mat, o->mat, (size_t)c->n * sizeof *p->mat);
        if (!strcmp(o->type, "STPS"))
            for (k = 0; k < c->n; k++)
                if (p->value[k] >= at + (dir < 0))
                    p->value[k] += dir;
    }
    *out = n;
    return SG_OK;
}

static int mat_same(const sg_material *a, const sg_material *b)
{
    return a->kind == b->kind && strcmp(a->name, b->name) == 0 &&
           strcmp(a->catalog, b->catalog) == 0 &&
           memcmp(&a->index, &b->index, sizeof a->index) == 0 &&
           memcmp(&a->vd, &b->vd, sizeof a->vd) == 0 &&
           memcmp(&a->dpgf, &b->dpgf, sizeof a->dpgf) == 0;
}

int sg_configs_equal(const sg_configs *a, const sg_configs *b)
{
    int i, k;
    if (a == b)
        return 1;
    if (!a || !b || a->n != b->n || a->nop != b->nop || a->current != b->current)
        return 0;
    for (i = 0; i < a->nop; i++) {
        const sg_config_op *x = &a->op[i], *y = &b->op[i];
        if (strcmp(x->type, y->type) != 0 || x->num != y->num || x->num2 != y->num2 ||
            memcmp(x->value, y->value, (size_t)a->n * sizeof *x->value) != 0 ||
            (!x->mat) != (!y->mat))
            return 0;
        for (k = 0; x->mat && k < a->n; k++)
            if (!mat_same(&x->mat[k], &y->mat[k]))
                return 0;
    }
    return 1;
}

int sg_config_count(const sg_system *sys)
{
    return sys && sys->configs ? sys->configs->n : 1;
}

/* Zemax's PRAM n of a surface, where sagitta holds it: a coordinate
 * break's decenters, tilts and order (1 to 6), an even asphere's r^2 to
 * r^16 terms (1 to 8); NULL for any other. */
static double *pram_ptr(sg_surface *s, int n, int *is_order)
{
    *is_order = 0;
    if (s->type == SG_SURF_COORDBRK) {
        switch (n) {
        case 1: return &s->before.dx;
        case 2: return &s->before.dy;
        case 3: return &s->before.tx;
        case 4: return &s->before.ty;
        case 5: return &s->before.tz;
        case 6: *is_order = 1; return NULL;
        default: return NULL;
        }
    }
    if (s->type == SG_SURF_EVENASPH && n >= 1 && n <= SG_NASPH)
        return &s->asph[n - 1];
    return NULL;
}

static int apply_op(sg_system *sys, const sg_config_op *o, int k, sg_diag *d)
{
    double v = o->value[k];
    int t = co_find(o->type);
    sg_surface *s = NULL;
    if (t < 0)
        return sg_diag_set(d, SG_ERANGE, "configuration operand %s is not one sagitta applies",
                           o->type);
    switch (co_types[t].scope) {
    case CO_SURF:
        if (o->num < 0 || o->num >= sys->nsurf)
            return sg_diag_set(d, SG_ERANGE, "configuration operand %s %d: the design has "
                               "surfaces 0 to %d", o->type, o->num, sys->nsurf - 1);
        s = &sys->surf[o->num];
        break;
    case CO_FIELD:
        if (o->num < 1 || o->num > sys->nfield)
            return sg_diag_set(d, SG_ERANGE, "configuration operand %s %d: the design has "
                               "fields 1 to %d", o->type, o->num, sys->nfield);
        break;
    case CO_WAVE:
        if (o->num < 1 || o->num > sys->nwave)
            return sg_diag_set(d, SG_ERANGE, "configuration operand %s %d: the design has "
                               "wavelengths 1 to %d", o->type, o->num, sys->nwave);
        break;
    case CO_SYS:
        break;
    }
    if (!strcmp(o->type, "THIC")) {
        s->thickness = v;
    } else if (!strcmp(o->type, "CRVT")) {
        s->radius = v == 0.0 ? INFINITY : 1.0 / v;
    } else if (!strcmp(o->type, "CONI")) {
        s->conic = v;
    } else if (!strcmp(o->type, "SDIA")) {
        s->semi_diameter = v;
    } else if (!strcmp(o->type, "GLSS")) {
        s->mat = o->mat[k];
    } else if (!strcmp(o->type, "PRAM")) {
        int is_order;
        double *p = pram_ptr(s, o->num2, &is_order);
        if (is_order) {
            if (v != 0.0 && v != 1.0)
                return sg_diag_set(d, SG_ERANGE, "configuration %d: PRAM %d 6: the order of a "
                                   "coordinate break is 0 or 1, not %.17g", k + 1, o->num, v);
            s->before.order = (int)v;
        } else if (p) {
            *p = v;
        } else {
            return sg_diag_set(d, SG_EUNSUPPORTED, "configuration operand PRAM %d %d: "
                               "surface %d has no parameter %d sagitta holds (it reads a "
                               "coordinate break's 1 to 6 and an even asphere's 1 to 8)",
                               o->num, o->num2, o->num, o->num2);
        }
    } else if (!strcmp(o->type, "APER")) {
        sys->aper_value = v;
    } else if (!strcmp(o->type, "STPS")) {
        if (v != floor(v) || v < 1 || v > sys->nsurf - 2)
            return sg_diag_set(d, SG_ERANGE, "configuration %d: STPS %.17g: the stop must be "
                               "one of surfaces 1 to %d", k + 1, v, sys->nsurf - 2);
        sys->stop = (int)v;
    } else if (!strcmp(o->type, "TEMP")) {
        sys->temperature = v;
    } else if (!strcmp(o->type, "PRES")) {
        sys->pressure = v;
    } else if (!strcmp(o->type, "XFIE")) {
        sys->field[o->num - 1].x = v;
    } else if (!strcmp(o->type, "YFIE")) {
        sys->field[o->num - 1].y = v;
    } else if (!strcmp(o->type, "FLWT")) {
        sys->field[o->num - 1].weight = v;
    } else if (!strcmp(o->type, "WAVE")) {
        sys->wave[o->num - 1].um = v;
    } else if (!strcmp(o->type, "WLWT")) {
        sys->wave[o->num - 1].weight = v;
    }
    return SG_OK;
}

/* The value sys holds for operand o (apply_op's inverse); 0 where the
 * operand's target is not in sys (apply_op refuses it). */
static double read_op(const sg_system *sys, const sg_config_op *o, sg_material *mat)
{
    const sg_surface *s = o->num >= 0 && o->num < sys->nsurf ? &sys->surf[o->num] : NULL;
    int f = o->num >= 1 && o->num <= sys->nfield, w = o->num >= 1 && o->num <= sys->nwave;
    if (!strcmp(o->type, "APER"))
        return sys->aper_value;
    if (!strcmp(o->type, "STPS"))
        return sys->stop;
    if (!strcmp(o->type, "TEMP"))
        return sys->temperature;
    if (!strcmp(o->type, "PRES"))
        return sys->pressure;
    if (!strcmp(o->type, "XFIE") || !strcmp(o->type, "YFIE") || !strcmp(o->type, "FLWT"))
        return !f ? 0.0 : o->type[0] == 'X' ? sys->field[o->num - 1].x
                        : o->type[0] == 'Y' ? sys->field[o->num - 1].y
                                            : sys->field[o->num - 1].weight;
    if (!strcmp(o->type, "WAVE") || !strcmp(o->type, "WLWT"))
        return !w ? 0.0 : o->type[1] == 'A' ? sys->wave[o->num - 1].um
                                            : sys->wave[o->num - 1].weight;
    if (!s)
        return 0.0;
    if (!strcmp(o->type, "THIC"))
        return s->thickness;
    if (!strcmp(o->type, "CRVT"))
        return isinf(s->radius) ? 0.0 : 1.0 / s->radius;
    if (!strcmp(o->type, "CONI"))
        return s->conic;
    if (!strcmp(o->type, "SDIA"))
        return s->semi_diameter;
    if (!strcmp(o->type, "GLSS")) {
        *mat = s->mat;
        return 0.0;
    }
    if (!strcmp(o->type, "PRAM")) {
        int is_order;
        double *p = pram_ptr((sg_surface *)s, o->num2, &is_order);
        return is_order ? s->before.order : p ? *p : 0.0;
    }
    return 0.0;
}

sg_configs *sg_configs_switch(const sg_system *sys, int k)
{
    const sg_configs *c = sys ? sys->configs : NULL;
    sg_configs *n;
    int i, cur;
    if (!c || !(n = sg_configs_new(c->n)))
        return NULL;
    cur = c->current >= 1 && c->current <= c->n ? c->current : 1;
    for (i = 0; i < c->nop; i++) {
        const sg_config_op *o = &c->op[i];
        sg_config_op *p;
        if (sg_configs_add(n, o->type, o->num, o->num2, NULL) != SG_OK) {
            sg_configs_release(n);
            return NULL;
        }
        p = &n->op[i];
        memcpy(p->value, o->value, (size_t)c->n * sizeof *p->value);
        if (o->mat)
            memcpy(p->mat, o->mat, (size_t)c->n * sizeof *p->mat);
        p->value[cur - 1] = read_op(sys, o, p->mat ? &p->mat[cur - 1] : NULL);
    }
    n->current = k;
    return n;
}

int sg_config_apply(sg_system *sys, int k, sg_diag *d)
{
    const sg_configs *c;
    int i, rc;
    if (!sys)
        return sg_diag_set(d, SG_EINVAL, "configuration: no system");
    c = sys->configs;
    if (k < 1 || k > (c ? c->n : 1))
        return sg_diag_set(d, SG_ERANGE, "configuration %d: the design has %s %d", k,
                           c ? "configurations 1 to" : "one configuration,", c ? c->n : 1);
    for (i = 0; c && i < c->nop; i++)
        if ((rc = apply_op(sys, &c->op[i], k - 1, d)) != SG_OK)
            return rc;
    return SG_OK;
}

int sg_configs_check(const sg_system *sys, const sg_catalog *cat, sg_diag *d)
{
    sg_system *t;
    int k, rc = SG_OK;
    if (!sys || !sys->configs)
        return SG_OK;
    t = sg_system_new();
    if (!t)
        return sg_diag_set(d, SG_ENOMEM, "configurations: out of memory");
    for (k = 1; k <= sys->configs->n && rc == SG_OK; k++) {
        sg_diag e;
        sg_diag_clear(&e);
        if ((rc = sg_system_assign(t, sys)) != SG_OK) {
            sg_diag_set(d, rc, "configurations: out of memory");
            break;
        }
        /* The base design's warnings are its own; a configuration's
         * error is named with its number. */
        if ((rc = sg_config_apply(t, k, &e)) != SG_OK ||
            (rc = sg_system_validate(t, cat, &e)) != SG_OK)
            sg_diag_set(d, rc, "configuration %d: %s", k, e.msg);
    }
    sg_system_free(t);
    return rc;
}
