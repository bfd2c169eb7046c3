/*
 * paddr.c - parameter addresses: one numeric parameter of a design, named
 * by the parameter table's scope and key, the wavelength, field or surface,
 * and the element.  The optimizer's variables go through these, so every
 * row of the table can be varied without a second list.
 */
#include <stdio.h>
#include <string.h>

#include "model_int.h"

static const char *const scope_words[SG_SCOPE_COUNT] = {"system", "wavelength", "field",
                                                         "surface"};

/* The struct a scope's rows live in. */
static void *object(sg_system *sys, sg_param_scope scope, int index)
{
    switch (scope) {
    case SG_SCOPE_SYSTEM: return sys;
    case SG_SCOPE_WAVE: return &sys->wave[index];
    case SG_SCOPE_FIELD: return &sys->field[index];
    case SG_SCOPE_SURFACE: return &sys->surf[index];
    default: return NULL;
    }
}

static int scope_count(const sg_system *sys, sg_param_scope scope)
{
    switch (scope) {
    case SG_SCOPE_SYSTEM: return 1;
    case SG_SCOPE_WAVE: return sys->nwave;
    case SG_SCOPE_FIELD: return sys->nfield;
    case SG_SCOPE_SURFACE: return sys->nsurf;
    default: return 0;
    }
}

int sg_paddr_make(const sg_system *sys, sg_param_scope scope, int index, const char *key,
                  int elem, sg_paddr *a, sg_diag *d)
{
    const sg_param *p;
    int n;
    if ((int)scope < 0 || scope >= SG_SCOPE_COUNT)
        return sg_diag_set(d, SG_ERANGE, "parameter: scope %d is not one of 0 to %d",
                           (int)scope, SG_SCOPE_COUNT - 1);
    n = scope_count(sys, scope);
    if (index < 0 || index >= n)
        return sg_diag_set(d, SG_ERANGE, "parameter %s: %s %d is not one of 0 to %d", key,
                           scope_words[scope], index, n - 1);
    p = sg_param_find(scope, key);
    if (!p)
        return sg_diag_set(d, SG_ERANGE, "%s %d: no parameter \"%s\"", scope_words[scope], index,
                           key);
    if (p->kind != SG_PARAM_REAL)
        return sg_diag_set(d, SG_ERANGE, "%s %d: %s is not a real number", scope_words[scope],
                           index, key);
    if (elem < 0 || elem >= p->count)
        return sg_diag_set(d, SG_ERANGE, "%s %d: %s has no element %d (0 to %d)",
                           scope_words[scope], index, key, elem, p->count - 1);
    /* A model glass's nd and vd exist on a model glass alone. */
    if (sg_param_material_part(p) && sys->surf[index].mat.kind != SG_MAT_MODEL)
        return sg_diag_set(d, SG_ERANGE, "surface %d: %s: the material is not a model glass",
                           index, p->label);
    a->scope = scope;
    a->index = index;
    a->param = p;
    a->elem = elem;
    return SG_OK;
}

double sg_paddr_get(const sg_system *sys, const sg_paddr *a)
{
    return sg_param_get(a->param, object((sg_system *)sys, a->scope, a->index), a->elem);
}

void sg_paddr_set(sg_system *sys, const sg_paddr *a, double v)
{
    sg_param_set(a->param, object(sys, a->scope, a->index), a->elem, v);
}

int sg_paddr_check(const sg_system *sys, const sg_paddr *a, double v, sg_diag *d)
{
    char msg[160], name[96];
    int object_surf = a->scope == SG_SCOPE_SURFACE && a->index == 0;
    (void)sys;
    if (sg_param_check(a->param, a->elem, v, object_surf, msg, sizeof msg) == SG_OK)
        return SG_OK;
    sg_paddr_name(a, name, sizeof name);
    return sg_diag_set(d, SG_ERANGE, "%s: %s", name, msg);
}

void sg_paddr_name(const sg_paddr *a, char *buf, size_t n)
{
    char lab[64];
    sg_param_label(a->param, a->elem, lab, sizeof lab);
    if (a->scope == SG_SCOPE_SYSTEM)
        snprintf(buf, n, "%s", lab);
    else
        snprintf(buf, n, "%s %d %s", scope_words[a->scope], a->index, lab);
}

int sg_paddr_solve_target(const sg_paddr *a)
{
    int t;
    if (a->scope != SG_SCOPE_SURFACE)
        return -1;
    for (t = 0; t < SG_SOLVE_NTARGETS; t++)
        if (strcmp(a->param->key, sg_solve_target_name((sg_solve_target)t)) == 0)
            return t;
    return -1;
}

int sg_variables(const sg_system *sys, sg_paddr *out, int cap)
{
    int i, t, k, n = 0;
    for (i = 0; i < sys->nsurf; i++) {
        for (t = 0; t < SG_SOLVE_NTARGETS; t++)
            if (sys->surf[i].solve[t].kind == SG_SOLVE_VARIABLE) {
                if (n < cap &&
                    sg_paddr_make(sys, SG_SCOPE_SURFACE, i,
                                  sg_solve_target_name((sg_solve_target)t), 0, &out[n],
                                  NULL) != SG_OK)
                    continue;
                n++;
            }
        /* The surface's other variables, in the order they were made. */
        for (k = 0; k < sys->surf[i].nvar; k++) {
            const sg_pvar *v = &sys->surf[i].var[k];
            if (n < cap && sg_paddr_make(sys, SG_SCOPE_SURFACE, i, v->param->key, v->elem,
                                         &out[n], NULL) != SG_OK)
                continue;
            n++;
        }
    }
    return n;
}

/* The var entry of surface s for (param, elem), or -1. */
static int var_index(const sg_surface *s, const sg_param *p, int elem)
{
    int k;
    for (k = 0; k < s->nvar; k++)
        if (s->var[k].param == p && s->var[k].elem == elem)
            return k;
    return -1;
}

int sg_variable_bounds(const sg_system *sys, const sg_paddr *a, double *lo, double *hi)
{
    const sg_surface *s;
    int t = sg_paddr_solve_target(a), k;
    if (a->scope != SG_SCOPE_SURFACE || a->index < 0 || a->index >= sys->nsurf)
        return 0;
    s = &sys->surf[a->index];
    if (t >= 0) {
        if (s->solve[t].kind != SG_SOLVE_VARIABLE)
            return 0;
        *lo = s->solve[t].lo;
        *hi = s->solve[t].hi;
        return 1;
    }
    if ((k = var_index(s, a->param, a->elem)) < 0)
        return 0;
    *lo = s->var[k].lo;
    *hi = s->var[k].hi;
    return 1;
}

int sg_variable_set(sg_system *sys, int surf, const char *key, int elem, int on, double lo,
                    double hi, sg_diag *d)
{
    sg_paddr a;
    sg_surface *s;
    char name[96];
    int rc, t, k;
    if ((rc = sg_paddr_make(sys, SG_SCOPE_SURFACE, surf, key, elem, &a, d)) != SG_OK)
        return rc;
    s = &sys->surf[surf];
    sg_paddr_name(&a, name, sizeof name);
    t = sg_paddr_solve_target(&a);
    k = t >= 0 ? -1 : var_index(s, a.param, elem);
    if (!on) {
        if (t >= 0 ? s->solve[t].kind != SG_SOLVE_VARIABLE : k < 0)
            return sg_diag_set(d, SG_ERANGE, "%s is not a variable", name);
        if (t >= 0) {
            memset(&s->solve[t], 0, sizeof s->solve[t]);
        } else {
            memmove(&s->var[k], &s->var[k + 1], (size_t)(s->nvar - k - 1) * sizeof s->var[0]);
            s->nvar--;
        }
        return SG_OK;
    }
    if (!(lo <= hi))
        return sg_diag_set(d, SG_ERANGE, "%s: the variable's min %g is above its max %g", name,
                           lo, hi);
    /* A row the surface's type does not read would vary nothing. */
    if (!sg_param_used(a.param, elem, s->type))
        return sg_diag_set(d, SG_ERANGE, "%s: a %s surface does not use it", name,
                           sg_param_find(SG_SCOPE_SURFACE, "type")->names[s->type]);
    /* A model glass's nd and vd vary within the model's limits, outside
     * which it has no index. */
    if (sg_param_material_part(a.param)) {
        lo = lo > a.param->min ? lo : a.param->min;
        hi = hi < a.param->max ? hi : a.param->max;
        if (!(lo <= hi))
            return sg_diag_set(d, SG_ERANGE, "%s: min and max lie outside the model's %g to %g",
                               name, a.param->min, a.param->max);
    }
    if (t >= 0) {
        memset(&s->solve[t], 0, sizeof s->solve[t]);
        s->solve[t].kind = SG_SOLVE_VARIABLE;
        s->solve[t].lo = lo;
        s->solve[t].hi = hi;
        return SG_OK;
    }
    if (k < 0) {
        if (s->nvar >= SG_SURF_MAXVARS)
            return sg_diag_set(d, SG_ERANGE, "%s: surface %d has %d variables already, the "
                               "limit", name, surf, SG_SURF_MAXVARS);
        k = s->nvar++;
    }
    s->var[k].param = a.param;
    s->var[k].elem = elem;
    s->var[k].lo = lo;
    s->var[k].hi = hi;
    return SG_OK;
}
