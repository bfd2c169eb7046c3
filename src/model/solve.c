/*
 * solve.c - solves and pickups: a radius, thickness or conic computed from
 * the rest of the design (sagitta-design(5), SOLVES): their names, where
 * each may sit, and their checks.  trace/solve_apply.c applies them.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model_int.h"

static const char *const kind_names[SG_SOLVE_NKINDS] = {
    "none", "pickup", "marginal_height", "marginal_angle", "fnum", "chief_height",
    "curvature_pickup", "position", "variable"};
static const char *const target_names[SG_SOLVE_NTARGETS] = {"radius", "thickness", "conic"};

/* Bit k: kind k may sit on the target. */
static const unsigned allowed[SG_SOLVE_NTARGETS] = {
    [SG_SOLVE_RADIUS] = 1u << SG_SOLVE_NONE | 1u << SG_SOLVE_PICKUP |
                        1u << SG_SOLVE_MARGINAL_ANGLE | 1u << SG_SOLVE_FNUM |
                        1u << SG_SOLVE_CURV_PICKUP | 1u << SG_SOLVE_VARIABLE,
    [SG_SOLVE_THICKNESS] = 1u << SG_SOLVE_NONE | 1u << SG_SOLVE_PICKUP |
                           1u << SG_SOLVE_MARGINAL_HEIGHT | 1u << SG_SOLVE_CHIEF_HEIGHT |
                           1u << SG_SOLVE_POSITION | 1u << SG_SOLVE_VARIABLE,
    [SG_SOLVE_CONIC] = 1u << SG_SOLVE_NONE | 1u << SG_SOLVE_PICKUP | 1u << SG_SOLVE_VARIABLE,
};

const char *sg_solve_kind_name(sg_solve_kind k)
{
    return (int)k >= 0 && k < SG_SOLVE_NKINDS ? kind_names[k] : NULL;
}

const char *sg_solve_target_name(sg_solve_target t)
{
    return (int)t >= 0 && t < SG_SOLVE_NTARGETS ? target_names[t] : NULL;
}

int sg_solve_is_pickup(sg_solve_kind k)
{
    return k == SG_SOLVE_PICKUP || k == SG_SOLVE_CURV_PICKUP;
}

int sg_solve_has_from(sg_solve_kind k)
{
    return sg_solve_is_pickup(k) || k == SG_SOLVE_POSITION;
}

int sg_solve_allowed(sg_solve_target t, sg_solve_kind k)
{
    if ((int)t < 0 || t >= SG_SOLVE_NTARGETS || (int)k < 0 || k >= SG_SOLVE_NKINDS)
        return 0;
    return (allowed[t] >> k) & 1u;
}

int sg_system_has_solves(const sg_system *sys)
{
    int i, t;
    /* A variable holds its value: nothing to evaluate. */
    for (i = 0; i < sys->nsurf; i++)
        for (t = 0; t < SG_SOLVE_NTARGETS; t++)
            if (sys->surf[i].solve[t].kind != SG_SOLVE_NONE &&
                sys->surf[i].solve[t].kind != SG_SOLVE_VARIABLE)
                return 1;
    return 0;
}

int sg_solve_check(const sg_system *sys, int i, sg_solve_target t, sg_diag *d)
{
    const sg_solve *v = &sys->surf[i].solve[t];
    const char *tn = sg_solve_target_name(t);
    if (v->kind == SG_SOLVE_NONE)
        return SG_OK;
    if (v->kind == SG_SOLVE_VARIABLE) {
        if (isnan(v->lo) || isnan(v->hi) || v->lo > v->hi || v->lo == INFINITY ||
            v->hi == -INFINITY)
            return sg_diag_set(d, SG_ERANGE, "surface %d: %s: the variable's min %g and max %g "
                               "do not bound a range", i, tn, v->lo, v->hi);
        return SG_OK;
    }
    if (!sg_solve_allowed(t, v->kind))
        return sg_diag_set(d, SG_ERANGE, "surface %d: %s: a %s solve cannot sit on the %s", i,
                           tn, sg_solve_kind_name(v->kind) ? sg_solve_kind_name(v->kind) : "?",
                           tn);
    if (sg_solve_is_pickup(v->kind)) {
        if (v->from < 0 || v->from >= i)
            return sg_diag_set(d, SG_ERANGE, "surface %d: %s: the pickup's source surface %d is "
                               "not an earlier surface (0 to %d)", i, tn, v->from, i - 1);
        if (!isfinite(v->scale) || !isfinite(v->offset))
            return sg_diag_set(d, SG_ERANGE, "surface %d: %s: the pickup's scale and offset "
                               "must be finite", i, tn);
        return SG_OK;
    }
    if (v->kind == SG_SOLVE_POSITION) {
        if (i < 1 || i > sys->nsurf - 2)
            return sg_diag_set(d, SG_ERANGE, "surface %d: thickness: a position solve needs a "
                               "surface after the object and before the image", i);
        if (v->from < 0 || v->from > i)
            return sg_diag_set(d, SG_ERANGE, "surface %d: thickness: the position solve's "
                               "reference surface %d is not this or an earlier surface (0 to "
                               "%d)", i, v->from, i);
        if (!isfinite(v->value))
            return sg_diag_set(d, SG_ERANGE, "surface %d: thickness: the position solve's "
                               "length must be finite", i);
        return SG_OK;
    }
    /* The marginal-ray solves act on a surface between object and image. */
    if (i < 1 || i > sys->nsurf - 2 + (t == SG_SOLVE_RADIUS))
        return sg_diag_set(d, SG_ERANGE, "surface %d: %s: a %s solve needs a surface "
                           "after the object%s", i, tn, sg_solve_kind_name(v->kind),
                           t == SG_SOLVE_THICKNESS ? " and before the image" : "");
    if (sys->surf[i].type == SG_SURF_COORDBRK)
        return sg_diag_set(d, SG_ERANGE, "surface %d: %s: a coordinate break holds no %s "
                           "solve", i, tn, sg_solve_kind_name(v->kind));
    if (!isfinite(v->value) || (v->kind == SG_SOLVE_FNUM && v->value == 0.0))
        return sg_diag_set(d, SG_ERANGE, "surface %d: %s: the %s solve's value %g must be "
                           "finite%s", i, tn, sg_solve_kind_name(v->kind), v->value,
                           v->kind == SG_SOLVE_FNUM ? " and not zero" : "");
    return SG_OK;
}
