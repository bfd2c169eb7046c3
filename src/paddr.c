/*
 * paddr.c - parameter addresses: one numeric parameter of a design, named
 * by the parameter table's scope and key, the wavelength, field or surface,
 * and the element.  The optimizer's variables go through these, so every
 * row of the table can be varied without a second list.
 */
#include <stdio.h>
#include <string.h>

#include "internal.h"

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
    int i, t, n = 0;
    for (i = 0; i < sys->nsurf; i++)
        for (t = 0; t < SG_SOLVE_NTARGETS; t++)
            if (sys->surf[i].solve[t].kind == SG_SOLVE_VARIABLE) {
                if (n < cap &&
                    sg_paddr_make(sys, SG_SCOPE_SURFACE, i,
                                  sg_solve_target_name((sg_solve_target)t), 0, &out[n],
                                  NULL) != SG_OK)
                    continue;
                n++;
            }
    return n;
}
