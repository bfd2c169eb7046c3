/*
 * thermal.c - thermal expansion of a design, as Zemax's thermal analysis
 * (Make Thermal, thermal pickups) applies it: sg_thermal_tces says which
 * TCE each value of each surface takes, sg_thermal builds the design at
 * another temperature and pressure (sagitta-design(5), THERMAL EXPANSION).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "shape.h"

/* A glass, a model glass or a fixed index: a solid body that expands as
 * a whole.  Air and mirrors do not. */
static int solid(const sg_material *m)
{
    return m->kind == SG_MAT_GLASS || m->kind == SG_MAT_MODEL || m->kind == SG_MAT_INDEX;
}

/* The surface whose material fills the space after surface i: a mirror
 * and a coordinate break keep the medium before them. */
static int medium_of(const sg_system *sys, int i)
{
    while (i > 0 && (sys->surf[i].type == SG_SURF_COORDBRK ||
                     sys->surf[i].mat.kind == SG_MAT_MIRROR))
        i--;
    return i;
}

/* The catalog glass of a glass material: the one place thermal.c looks
 * a glass up. */
static const sg_glass *glass_of(const sg_catalog *cat, const sg_material *m)
{
    return cat ? sg_material_glass(cat, m) : NULL;
}

/* The TCE of the solid that surface j's material is: a catalog glass's ED
 * figure; for a model glass or fixed index (no expansion data), or a
 * material its catalog marks to ignore expansion (a liquid or gas, whose
 * shape its mount sets), the surface's own tce. */
static int solid_tce(const sg_system *sys, const sg_catalog *cat, int j, double *tce,
                     sg_diag *d)
{
    const sg_surface *s = &sys->surf[j];
    const sg_glass *g;
    if (s->mat.kind != SG_MAT_GLASS) {
        *tce = s->tce;
        return SG_OK;
    }
    g = glass_of(cat, &s->mat);
    if (!g)
        return sg_diag_set(d, SG_ENOGLASS,
                           "surface %d: material \"%s\" is not in the catalog, so its "
                           "expansion is not known", j, s->mat.name);
    *tce = g->ignore_expansion ? s->tce : g->has_ed ? g->ed[0] : 0.0;
    return SG_OK;
}

int sg_thermal_tces(const sg_system *sys, const sg_catalog *cat, sg_thermal_tce *out,
                    sg_diag *d)
{
    int i, rc;
    for (i = 0; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        int after = medium_of(sys, i), before = i > 0 ? medium_of(sys, i - 1) : -1;
        sg_thermal_tce *t = &out[i];
        t->place = s->tce;
        /* The space after: a glass expands with itself, air with the mount
         * of the surface where the space starts. */
        t->solid = solid(&sys->surf[after].mat);
        if (t->solid) {
            if ((rc = solid_tce(sys, cat, after, &t->space, d)) != SG_OK)
                return rc;
        } else {
            t->space = s->tce;
        }
        /* The shape belongs to the glass after it, else to the glass before
         * (a lens's rear face, a back-surface mirror), else to the mount
         * (a mirror's substrate, a dummy). */
        if (s->type != SG_SURF_COORDBRK && s->mat.kind != SG_MAT_MIRROR && solid(&s->mat))
            rc = solid_tce(sys, cat, i, &t->shape, d);
        else if (s->type != SG_SURF_COORDBRK && before >= 0 && solid(&sys->surf[before].mat))
            rc = solid_tce(sys, cat, before, &t->shape, d);
        else {
            t->shape = s->tce;
            rc = SG_OK;
        }
        if (rc != SG_OK)
            return rc;
    }
    return SG_OK;
}

/* The factor of an expansion, refused unless positive. */
static int factor(double tce, double dt, int i, double *s, sg_diag *d)
{
    *s = 1.0 + tce * 1e-6 * dt;
    if (!(*s > 0.0) || !isfinite(*s))
        return sg_diag_set(d, SG_ERANGE,
                           "surface %d: the expansion factor 1 + %g e-6/K x %g K = %g is not "
                           "positive", i, tce, dt, *s);
    return SG_OK;
}

/* Every parameter in lens units to the power k takes s^k: z'(x, y) = s
 * z(x / s, y / s).  Only the values the surface's type reads change, so
 * the others keep their defaults (and stay out of the file). */
static void scale_shape(sg_surface *f, double s)
{
    const sg_shape_type *t = sg_shape_type_of(f->type);
    const sg_shape_key *e;
    if (f->type == SG_SURF_COORDBRK || !t)
        return;
    if (isfinite(f->radius))
        f->radius *= s;
    /* The conic is a ratio and stays; the type's own values follow its
     * record's rule, every element of each (those past what the type
     * reads are 0). */
    for (e = t->keys; e->key; e++) {
        const sg_param *p = sg_param_find(SG_SCOPE_SURFACE, e->key);
        double *v;
        int k;
        if (!p || p->kind != SG_PARAM_REAL)
            continue;
        v = sg_param_ptr(p, f);
        for (k = 0; k < p->count; k++) {
            int pw = e->p0 + e->pk * k;
            if (pw == 1)
                v[k] *= s;
            else if (pw > 1)
                v[k] *= pow(s, pw);
            else if (pw < 0)
                v[k] /= pow(s, -pw);
        }
    }
    f->semi_diameter *= s;
    f->ap_rmin *= s;
    f->ap_rmax *= s;
    f->ap_xhalf *= s;
    f->ap_yhalf *= s;
    f->ap_xdec *= s;
    f->ap_ydec *= s;
}

/* Where a spacer touches surface i: its semi-diameter, on a lens surface
 * between the object and the image that does not move the frame; the
 * vertex (0) elsewhere. */
static double contact(const sg_system *sys, int i)
{
    const sg_surface *s = &sys->surf[i];
    if (i < 1 || i > sys->nsurf - 2 || s->type == SG_SURF_COORDBRK ||
        sg_surface_moves_frame(s))
        return 0.0;
    return s->semi_diameter;
}

static int sag_at(const sg_surface *s, double h, int i, double *z, sg_diag *d)
{
    *z = h == 0.0 ? 0.0 : sg_surface_sag(s, 0.0, h);
    if (!isfinite(*z))
        return sg_diag_set(d, SG_ERANGE,
                           "surface %d: no sag at the spacer's contact height %g (its "
                           "semi-diameter)", i, h);
    return SG_OK;
}

int sg_thermal(const sg_system *sys, const sg_catalog *cat, double temp, double pres,
               sg_system *out, sg_diag *d)
{
    sg_thermal_tce *t = NULL;
    double *sm = NULL, dt;
    sg_system *w = NULL;
    int i, k, rc, nsolve = 0, nbare = 0;
    char bare[SG_GLASS_NAME] = "";

    if (!(temp >= SG_TEMP_MIN && temp <= SG_TEMP_MAX))
        return sg_diag_set(d, SG_ERANGE, "temperature: %g C is outside %g to %g C", temp,
                           SG_TEMP_MIN, SG_TEMP_MAX);
    if (!(pres >= 0.0 && pres <= SG_PRES_MAX))
        return sg_diag_set(d, SG_ERANGE, "pressure: %g atm is outside 0 to %g atm", pres,
                           SG_PRES_MAX);
    if ((rc = sg_system_check(sys, cat, d)) != SG_OK)
        return rc;
    dt = temp - sys->temperature;
    t = malloc((size_t)sys->nsurf * sizeof *t);
    sm = malloc((size_t)sys->nsurf * sizeof *sm);
    w = sg_system_clone(sys);
    if (!t || !sm || !w) {
        rc = sg_diag_set(d, SG_ENOMEM, "thermal: out of memory");
        goto done;
    }
    if ((rc = sg_thermal_tces(sys, cat, t, d)) != SG_OK)
        goto done;

    /* The shapes and placements first: the air spaces read the scaled
     * surfaces at their spacers' contacts. */
    for (i = 0; i < sys->nsurf; i++) {
        sg_surface *f = &w->surf[i];
        double s, sp;
        if ((rc = factor(t[i].shape, dt, i, &s, d)) != SG_OK ||
            (rc = factor(t[i].place, dt, i, &sp, d)) != SG_OK ||
            (rc = factor(t[i].space, dt, i, &sm[i], d)) != SG_OK)
            goto done;
        scale_shape(f, s);
        /* Tilts are angles and stay; decenters move with the mount. */
        f->before.dx *= sp;
        f->before.dy *= sp;
        f->after.dx *= sp;
        f->after.dy *= sp;
        for (k = 0; k < SG_SOLVE_NTARGETS; k++)
            if (f->solve[k].kind != SG_SOLVE_NONE) {
                f->solve[k].kind = SG_SOLVE_NONE;
                nsolve++;
            }
        if (sys->surf[i].type != SG_SURF_COORDBRK && sys->surf[i].mat.kind == SG_MAT_GLASS) {
            const sg_glass *g = glass_of(cat, &sys->surf[i].mat);
            if (g && !g->ignore_expansion && !(g->has_ed && g->ed[0] != 0.0)) {
                nbare++;
                sg_strlcpy(bare, g->name, sizeof bare);
            }
        }
    }
    for (i = 0; i + 1 < sys->nsurf; i++) {
        double th = sys->surf[i].thickness, ha, hb, za, zb, za1, zb1;
        if (!isfinite(th))
            continue;
        if (t[i].solid) {
            w->surf[i].thickness = th * sm[i];
            continue;
        }
        /* The spacer runs from surface i at its semi-diameter ha to
         * surface i + 1 at hb; it grows in length and radius, and the
         * scaled surfaces meet it at the radii ha sm, hb sm. */
        ha = contact(sys, i);
        hb = contact(sys, i + 1);
        if ((rc = sag_at(&sys->surf[i], ha, i, &za, d)) != SG_OK ||
            (rc = sag_at(&sys->surf[i + 1], hb, i + 1, &zb, d)) != SG_OK ||
            (rc = sag_at(&w->surf[i], ha * sm[i], i, &za1, d)) != SG_OK ||
            (rc = sag_at(&w->surf[i + 1], hb * sm[i], i + 1, &zb1, d)) != SG_OK)
            goto done;
        /* (th + zb - za) sm - zb1 + za1, as a change to th: exact where
         * nothing moves, and without the sags' cancellation. */
        w->surf[i].thickness = th + ((th + zb - za) * (sm[i] - 1.0) + (zb - zb1) + (za1 - za));
    }
    w->temperature = temp;
    w->pressure = pres;
    w->adjust_index = 1;
    if ((rc = sg_system_check(w, cat, d)) != SG_OK)
        goto done;
    if ((rc = sg_system_assign(out, w)) != SG_OK) {
        rc = sg_diag_set(d, rc, "thermal: out of memory");
        goto done;
    }
    if (nsolve)
        sg_diag_warn(d, "thermal: %d solve%s and pickup%s frozen at their values (the lens "
                     "as built at %g C does not refocus)", nsolve, nsolve == 1 ? "" : "s",
                     nsolve == 1 ? "" : "s", temp);
    if (nbare)
        sg_diag_warn(d, "thermal: %d surface%s of a glass without an expansion coefficient "
                     "(TCE 0 in its ED line, or none), e.g. %s, do not expand", nbare,
                     nbare == 1 ? "" : "s", bare);
done:
    free(t);
    free(sm);
    sg_system_free(w);
    return rc;
}
