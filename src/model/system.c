/* system.c - the optical system model: surfaces, edits, validation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model_int.h"
#include "shape.h"

void sg_surface_init(sg_surface *s)
{
    memset(s, 0, sizeof *s);
    sg_param_defaults(SG_SCOPE_SURFACE, s);
}

static int grow(sg_system *sys, int need)
{
    sg_surface *p;
    int cap;
    if (need <= sys->capsurf)
        return SG_OK;
    if (need > SG_MAX_SURFACES)
        return SG_ERANGE;
    cap = sys->capsurf ? sys->capsurf : 8;
    while (cap < need)
        cap *= 2;
    if (cap > SG_MAX_SURFACES)
        cap = SG_MAX_SURFACES;
    p = realloc(sys->surf, (size_t)cap * sizeof *p);
    if (!p)
        return SG_ENOMEM;
    sys->surf = p;
    sys->capsurf = cap;
    return SG_OK;
}

int sg_system_reset(sg_system *sys, int nsurf)
{
    sg_surface *keep = sys->surf;
    int keepcap = sys->capsurf;
    int rc, i;
    if (nsurf < 0 || nsurf > SG_MAX_SURFACES)
        return SG_ERANGE;
    sg_zmx_origin_release(sys->zmx);
    sg_configs_release(sys->configs);
    memset(sys, 0, sizeof *sys);
    sys->surf = keep;
    sys->capsurf = keepcap;
    rc = grow(sys, nsurf < 3 ? 3 : nsurf);
    if (rc != SG_OK)
        return rc;
    sg_strlcpy(sys->units, "mm", sizeof sys->units);
    sys->nwave = 1;
    sys->primary_wave = 0;
    sys->wave[0].um = 0.5875618;
    sys->wave[0].weight = 1.0;
    sys->field_type = SG_FIELD_ANGLE;
    sys->field_norm = SG_NORM_RADIAL;
    sys->nfield = 1;
    sys->field[0].weight = 1.0;
    sys->aper_type = SG_APER_EPD;
    sys->aper_value = 10.0;
    sys->aim = SG_AIM_OFF;
    sys->temperature = 20.0;
    sys->pressure = 1.0;
    sys->nsurf = nsurf;
    for (i = 0; i < nsurf; i++)
        sg_surface_init(&sys->surf[i]);
    if (nsurf > 0)
        sys->surf[0].thickness = INFINITY;
    sys->stop = nsurf > 2 ? 1 : 0;
    return SG_OK;
}

sg_system *sg_system_new(void)
{
    sg_system *sys = calloc(1, sizeof *sys);
    if (!sys)
        return NULL;
    if (sg_system_reset(sys, 3) != SG_OK) {
        free(sys);
        return NULL;
    }
    sys->surf[1].thickness = 10.0;
    return sys;
}

void sg_system_free(sg_system *sys)
{
    if (!sys)
        return;
    sg_zmx_origin_release(sys->zmx);
    sg_configs_release(sys->configs);
    free(sys->surf);
    free(sys);
}

int sg_system_assign(sg_system *dst, const sg_system *src)
{
    sg_surface *keep;
    int keepcap, rc;
    if (dst == src)
        return SG_OK;
    rc = grow(dst, src->nsurf);
    if (rc != SG_OK)
        return rc;
    keep = dst->surf;
    keepcap = dst->capsurf;
    /* The .zmx origin is shared: the copy holds a count of its own. */
    sg_zmx_origin_retain(src->zmx);
    sg_zmx_origin_release(dst->zmx);
    sg_configs_retain(src->configs);
    sg_configs_release(dst->configs);
    *dst = *src;
    dst->surf = keep;
    dst->capsurf = keepcap;
    if (src->nsurf > 0)
        memcpy(dst->surf, src->surf, (size_t)src->nsurf * sizeof *src->surf);
    return SG_OK;
}

sg_system *sg_system_clone(const sg_system *sys)
{
    sg_system *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    if (sg_system_assign(c, sys) != SG_OK) {
        free(c->surf);
        free(c);
        return NULL;
    }
    return c;
}

/* After inserting (dir 1) or deleting (dir -1) surface at: pickups and
 * position solves naming later surfaces follow them; one naming the
 * deleted surface becomes a plain value, as it holds. */
static void renumber_pickups(sg_system *sys, int at, int dir)
{
    int i, t;
    for (i = 0; i < sys->nsurf; i++)
        for (t = 0; t < SG_SOLVE_NTARGETS; t++) {
            sg_solve *v = &sys->surf[i].solve[t];
            if (!sg_solve_has_from(v->kind))
                continue;
            if (dir < 0 && v->from == at)
                memset(v, 0, sizeof *v);
            else if (v->from >= at + (dir < 0))
                v->from += dir;
        }
}

/* A surface number after an insert (dir 1) or a delete (dir -1) at at:
 * one on the deleted surface keeps its number, as a merit operand does,
 * so that a .zmx save can name it; unused fields (0, -1) stay. */
static int renumbered(int n, int at, int dir)
{
    return n >= at + (dir < 0) ? n + dir : n;
}

/* The configurations, the merit function and the tolerances follow the
 * surfaces they name, as Zemax's editors do (sagitta-design(5), ZEMAX
 * FILES). */
static void renumber_rest(sg_system *sys, int at, int dir, sg_configs *cf)
{
    int k;
    if (cf) {
        sg_configs_release(sys->configs);
        sys->configs = cf;
    }
    sg_merit_renumber(&sys->merit, at, dir);
    for (k = 0; k < sys->tol.nop; k++) {
        sg_tol_operand *o = &sys->tol.op[k];
        o->surface = renumbered(o->surface, at, dir);
        o->last = renumbered(o->last, at, dir);
        o->adjust = renumbered(o->adjust, at, dir);
    }
    for (k = 0; k < sys->tol.ncomp; k++)
        sys->tol.comp[k].surface = renumbered(sys->tol.comp[k].surface, at, dir);
}

int sg_system_insert(sg_system *sys, int at)
{
    sg_configs *cf = NULL;
    int rc;
    if (at < 1 || at > sys->nsurf - 1)
        return SG_EINVAL;
    rc = grow(sys, sys->nsurf + 1);
    if (rc == SG_OK)
        rc = sg_configs_renumbered(sys->configs, at, 1, &cf);
    if (rc != SG_OK)
        return rc;
    memmove(&sys->surf[at + 1], &sys->surf[at],
            (size_t)(sys->nsurf - at) * sizeof *sys->surf);
    sg_surface_init(&sys->surf[at]);
    sys->nsurf++;
    /* A pickup follows its source surface. */
    renumber_pickups(sys, at, 1);
    renumber_rest(sys, at, 1, cf);
    /* The stop is a property of a physical surface, so it follows it. */
    if (sys->stop >= at)
        sys->stop++;
    return SG_OK;
}

int sg_system_delete(sg_system *sys, int at)
{
    sg_configs *cf = NULL;
    if (at < 1 || at > sys->nsurf - 2 || sys->nsurf <= 3)
        return SG_EINVAL;
    if (sg_configs_renumbered(sys->configs, at, -1, &cf) != SG_OK)
        return SG_ENOMEM;
    memmove(&sys->surf[at], &sys->surf[at + 1],
            (size_t)(sys->nsurf - at - 1) * sizeof *sys->surf);
    sys->nsurf--;
    renumber_pickups(sys, at, -1);
    renumber_rest(sys, at, -1, cf);
    /* Deleting the stop leaves the stop on the surface that took its row. */
    if (sys->stop > at)
        sys->stop--;
    if (sys->stop > sys->nsurf - 2)
        sys->stop = sys->nsurf - 2;
    return SG_OK;
}

double sg_surface_curvature(const sg_surface *s)
{
    if (s->type == SG_SURF_COORDBRK || s->type == SG_SURF_PARAXIAL || isinf(s->radius) ||
        s->radius == 0.0)
        return 0.0;
    return 1.0 / s->radius;
}

double sg_surface_sag(const sg_surface *s, double x, double y)
{
    /* Prepared for one point: callers with many prepare the shape once
     * and ask sg_shape_sag. */
    if (sg_shape_ops_of(s->type)) {
        sg_shape sh;
        return sg_shape_prepare(s, &sh, 0, NULL) == SG_OK ? sg_shape_sag(&sh, x, y) : NAN;
    }
    double c = sg_surface_curvature(s);
    double r2 = x * x + y * y;
    double arg = 1.0 - (1.0 + s->conic) * c * c * r2;
    double z;
    if (arg < 0.0)
        return NAN;
    z = c * r2 / (1.0 + sqrt(arg));
    if (s->type == SG_SURF_EVENASPH) {
        double p = 0.0;
        int k;
        for (k = SG_NASPH - 1; k >= 0; k--)
            p = p * r2 + s->asph[k];
        z += p * r2;
    }
    return z;
}

/* Lengths a trace squares (radii, thicknesses, pupil and field sizes) must
 * keep their squares and products inside the doubles. */
#define SG_MAX_LEN 1e150

/* A frame change's values: finite, within the model's lengths and one
 * turn, order 0 or 1. */
static int check_change(const sg_frame_change *c, int i, const char *which, sg_diag *d)
{
    const double v[5] = {c->dx, c->dy, c->tx, c->ty, c->tz};
    static const char *const name[5] = {"decenter x", "decenter y", "tilt about x",
                                        "tilt about y", "tilt about z"};
    int k;
    for (k = 0; k < 5; k++) {
        if (!isfinite(v[k]))
            return sg_diag_set(d, SG_ERANGE, "surface %d: %s %s is not finite", i, which,
                               name[k]);
        if (k < 2 && fabs(v[k]) > SG_MAX_LEN)
            return sg_diag_set(d, SG_ERANGE, "surface %d: %s %s %g is beyond %g lens units", i,
                               which, name[k], v[k], SG_MAX_LEN);
        if (k >= 2 && fabs(v[k]) > 360.0)
            return sg_diag_set(d, SG_ERANGE, "surface %d: %s %s %g is beyond 360 degrees", i,
                               which, name[k], v[k]);
    }
    if (c->order != 0 && c->order != 1)
        return sg_diag_set(d, SG_ERANGE,
                           "surface %d: %s order %d must be 0 (decenter, then tilt) or 1 "
                           "(tilt, then decenter)", i, which, c->order);
    return SG_OK;
}

/* Where frame changes may stand: nothing may move the object (rays start
 * in its axis's frame, and a change on surface 1 turns what follows);
 * the image has nothing after it; a coordinate break is a plane in the
 * medium before it. */
static int check_frames(const sg_system *sys, int i, sg_diag *d)
{
    const sg_surface *s = &sys->surf[i];
    const char *what = s->type == SG_SURF_COORDBRK ? "break" : "before";
    int rc, last = sys->nsurf - 1;
    if ((rc = check_change(&s->before, i, what, d)) != SG_OK ||
        (rc = check_change(&s->after, i, "after", d)) != SG_OK)
        return rc;
    if (s->after_mode != SG_AFTER_EXPLICIT && s->after_mode != SG_AFTER_REVERSE)
        return sg_diag_set(d, SG_ERANGE, "surface %d: after mode %d is not explicit or reverse",
                           i, (int)s->after_mode);
    if (s->after_mode == SG_AFTER_REVERSE && !sg_frame_change_is_zero(&s->after))
        return sg_diag_set(d, SG_EINVAL,
                           "surface %d: after: \"reverse\" undoes the before change and takes "
                           "no values of its own", i);
    if (s->type == SG_SURF_COORDBRK) {
        if (i == 0 || i == last)
            return sg_diag_set(d, SG_EINVAL, "surface %d: the %s cannot be a coordinate break",
                               i, i == 0 ? "object" : "image");
        if (i == sys->stop)
            return sg_diag_set(d, SG_EINVAL,
                               "surface %d: a coordinate break cannot be the stop", i);
        if (s->mat.kind != SG_MAT_AIR)
            return sg_diag_set(d, SG_EINVAL,
                               "surface %d: a coordinate break keeps the medium before it; "
                               "its material must be empty (AIR)", i);
        if (isfinite(s->radius) && s->radius != 0.0)
            return sg_diag_set(d, SG_EINVAL,
                               "surface %d: a coordinate break is flat; its radius must be inf",
                               i);
        if (!sg_frame_change_is_zero(&s->after) || s->after_mode != SG_AFTER_EXPLICIT)
            return sg_diag_set(d, SG_EINVAL,
                               "surface %d: a coordinate break has no after change; use "
                               "another break", i);
        if (s->aperture != SG_APERTURE_NONE)
            return sg_diag_set(d, SG_EINVAL,
                               "surface %d: a coordinate break has no aperture; put it on a "
                               "dummy surface after the break", i);
        return SG_OK;
    }
    if (i == 0 && sg_surface_moves_frame(s))
        return sg_diag_set(d, SG_EINVAL,
                           "surface 0: the object cannot be tilted or decentered");
    if (i == last && (s->after_mode == SG_AFTER_REVERSE ? 0 : !sg_frame_change_is_zero(&s->after)))
        return sg_diag_set(d, SG_EINVAL,
                           "surface %d: nothing follows the image, so it takes no after change",
                           i);
    return SG_OK;
}

static int finite_or_inf_radius(double r)
{
    return !isnan(r);
}


/* The scale of normalized field coordinate Hx (k = 0) or Hy (k = 1): the
 * largest radial field, or the largest |x| or |y|. */
static double field_scale(const sg_system *sys, int k)
{
    double m = 0.0;
    int i;
    for (i = 0; i < sys->nfield; i++) {
        double v = sys->field_norm == SG_NORM_RADIAL
                       ? hypot(sys->field[i].x, sys->field[i].y)
                       : fabs(k == 0 ? sys->field[i].x : sys->field[i].y);
        m = fmax(m, v);
    }
    return m;
}

int sg_field_check(const sg_system *sys, double hx, double hy, sg_diag *d)
{
    double vx, vy;
    if (!isfinite(hx) || !isfinite(hy))
        return sg_diag_set(d, SG_EINVAL, "field (Hx %g, Hy %g): not a number", hx, hy);
    /* Zemax scales the field value itself: for angle fields the angle. */
    vx = field_scale(sys, 0) * hx;
    vy = field_scale(sys, 1) * hy;
    if (sys->field_type == SG_FIELD_ANGLE) {
        if (!(fabs(vx) < 90.0) || !(fabs(vy) < 90.0))
            return sg_diag_set(d, SG_ERANGE,
                               "field (Hx %g, Hy %g): the angle (%g, %g) degrees reaches 90 "
                               "degrees; normalized coordinates scale the largest field, "
                               "(%g, %g) degrees, and an angle never wraps",
                               hx, hy, vx, vy, field_scale(sys, 0), field_scale(sys, 1));
    } else if (!(fabs(vx) <= SG_MAX_LEN) || !(fabs(vy) <= SG_MAX_LEN)) {
        return sg_diag_set(d, SG_ERANGE,
                           "field (Hx %g, Hy %g): the height (%g, %g) is beyond %g lens units",
                           hx, hy, vx, vy, SG_MAX_LEN);
    }
    return SG_OK;
}

enum { ZERO_MAX = 256 };

int sg_system_validate(const sg_system *sys, const sg_catalog *cat, sg_diag *d)
{
    return sg_system_validate_memo(sys, cat, d, NULL);
}

int sg_system_validate_memo(const sg_system *sys, const sg_catalog *cat, sg_diag *d,
                            sg_valid_memo *m)
{
    double track;
    int i, k, p, src, np;
    unsigned char zero_ok[ZERO_MAX][2];
    sg_glass_seen found;
    memset(&found, 0, sizeof found);
    if (sys->nsurf < 3)
        return sg_diag_set(d, SG_ENOSYS,
                           "the system has %d surfaces; it needs an object, "
                           "at least one surface and an image",
                           sys->nsurf);
    if (sys->stop < 1 || sys->stop > sys->nsurf - 2)
        return sg_diag_set(d, SG_ENOSTOP,
                           "the stop must be one of surfaces 1 to %d",
                           sys->nsurf - 2);
    if (sys->nwave < 1 || sys->nwave > SG_MAX_WAVES)
        return sg_diag_set(d, SG_ERANGE, "wavelengths: %d given, 1 to %d allowed",
                           sys->nwave, SG_MAX_WAVES);
    if (sys->primary_wave < 0 || sys->primary_wave >= sys->nwave)
        return sg_diag_set(d, SG_ERANGE, "wavelengths: primary %d is not one of 1 to %d",
                           sys->primary_wave + 1, sys->nwave);
    /* sg_solve_check passes a cell without a solve at once; most have none. */
    for (i = 0; i < sys->nsurf; i++)
        for (k = 0; k < SG_SOLVE_NTARGETS; k++)
            if (sys->surf[i].solve[k].kind != SG_SOLVE_NONE &&
                (src = sg_solve_check(sys, i, (sg_solve_target)k, d)) != SG_OK)
                return src;
    for (k = 0; k < sys->nwave; k++)
        if (!(sys->wave[k].um > 0.0) || !isfinite(sys->wave[k].um))
            return sg_diag_set(d, SG_ERANGE,
                               "wavelength %d: %g um is not a positive finite value",
                               k + 1, sys->wave[k].um);
    /* The air formula's temperature factor stays positive down to about
     * -272 C; the limits keep it well clear of that. */
    if (!(sys->temperature >= SG_TEMP_MIN && sys->temperature <= SG_TEMP_MAX))
        return sg_diag_set(d, SG_ERANGE, "temperature: %g C is outside %g to %g C",
                           sys->temperature, SG_TEMP_MIN, SG_TEMP_MAX);
    if (!(sys->pressure >= 0.0 && sys->pressure <= SG_PRES_MAX))
        return sg_diag_set(d, SG_ERANGE, "pressure: %g atm is outside 0 to %g atm",
                           sys->pressure, SG_PRES_MAX);
    if (sys->nfield < 1 || sys->nfield > SG_MAX_FIELDS)
        return sg_diag_set(d, SG_ERANGE, "fields: %d given, 1 to %d allowed",
                           sys->nfield, SG_MAX_FIELDS);
    for (k = 0; k < sys->nfield; k++) {
        const sg_field *f = &sys->field[k];
        if (!isfinite(f->x) || !isfinite(f->y))
            return sg_diag_set(d, SG_ERANGE, "field %d: coordinates must be finite", k + 1);
        if (sys->field_type == SG_FIELD_ANGLE && (fabs(f->x) >= 90.0 || fabs(f->y) >= 90.0))
            return sg_diag_set(d, SG_ERANGE, "field %d: angle (%g, %g) must be below 90 degrees",
                               k + 1, f->x, f->y);
        /* The table's other numbers (the vignetting factors). */
        for (p = 0; p < sg_param_count(SG_SCOPE_FIELD); p++) {
            const sg_param *pp = sg_param_at(SG_SCOPE_FIELD, p);
            char msg[160];
            if (pp->kind == SG_PARAM_REAL && (pp->flags & SG_PARAM_OPTIONAL) &&
                sg_param_check(pp, 0, sg_param_get(pp, f, 0), 0, msg, sizeof msg) != SG_OK)
                return sg_diag_set(d, SG_ERANGE, "field %d: %s", k + 1, msg);
        }
    }
    if (!(sys->aper_value > 0.0) || !isfinite(sys->aper_value))
        if (sys->aper_type != SG_APER_FLOAT_STOP)
            return sg_diag_set(d, SG_ERANGE, "aperture: value %g must be positive and finite",
                               sys->aper_value);
    if (sys->aper_type == SG_APER_OBJECT_NA && !(sys->aper_value < 1.0))
        return sg_diag_set(d, SG_ERANGE, "aperture: object NA %g must be below 1",
                           sys->aper_value);
    if (sys->aper_type == SG_APER_OBJECT_CONE && !(sys->aper_value < 90.0))
        return sg_diag_set(d, SG_ERANGE, "aperture: object cone angle %g must be below 90 "
                           "degrees", sys->aper_value);
    if (sys->aper_type != SG_APER_FLOAT_STOP && sys->aper_value > SG_MAX_LEN)
        return sg_diag_set(d, SG_ERANGE, "aperture: value %g is beyond %g", sys->aper_value,
                           SG_MAX_LEN);
    if (sys->telecentric) {
        /* Zemax's rules for telecentric object space: the pupil is at
         * infinity, so the aperture is an object NA and the field a height
         * on an object at a finite distance. */
        if (sys->telecentric != 1)
            return sg_diag_set(d, SG_ERANGE, "aperture: telecentric is %d; it is 0 or 1",
                               sys->telecentric);
        if (sys->aper_type != SG_APER_OBJECT_NA && sys->aper_type != SG_APER_OBJECT_CONE)
            return sg_diag_set(d, SG_EUNSUPPORTED, "aperture: an object-space telecentric "
                               "system has its entrance pupil at infinity, so its aperture is "
                               "an object NA or cone angle, not %s",
                               sys->aper_type == SG_APER_EPD          ? "an entrance pupil diameter"
                               : sys->aper_type == SG_APER_IMAGE_FNUM ? "an image F/#"
                               : sys->aper_type == SG_APER_FLOAT_STOP ? "the stop's size"
                                                                      : "a working F/#");
        if (!isfinite(sys->surf[0].thickness))
            return sg_diag_set(d, SG_EUNSUPPORTED, "aperture: an object-space telecentric "
                               "system needs an object at a finite distance (surface 0's "
                               "thickness is infinite)");
        if (sys->field_type == SG_FIELD_ANGLE)
            return sg_diag_set(d, SG_EUNSUPPORTED, "fields: an object-space telecentric "
                               "system's chief rays are parallel to the axis, so its fields "
                               "are heights, not angles");
    }
    for (k = 0; k < sys->nfield; k++)
        if (sys->field_type != SG_FIELD_ANGLE &&
            (fabs(sys->field[k].x) > SG_MAX_LEN || fabs(sys->field[k].y) > SG_MAX_LEN))
            return sg_diag_set(d, SG_ERANGE, "field %d: height (%g, %g) is beyond %g lens units",
                               k + 1, sys->field[k].x, sys->field[k].y, SG_MAX_LEN);
    /* Whether a zero passes each surface number, on the object and
     * elsewhere: the check of a real number reads only its value (the
     * element only names it in a message), and most elements are zero
     * (unused terms), so a zero is checked once a number, not a surface. */
    np = sg_param_count(SG_SCOPE_SURFACE);
    if (np > ZERO_MAX)
        np = 0;
    for (p = 0; p < np; p++) {
        const sg_param *pp = sg_param_at(SG_SCOPE_SURFACE, p);
        zero_ok[p][0] = pp->kind == SG_PARAM_REAL &&
                        sg_param_check(pp, 0, 0.0, 0, NULL, 0) == SG_OK;
        zero_ok[p][1] = pp->kind == SG_PARAM_REAL &&
                        sg_param_check(pp, 0, 0.0, 1, NULL, 0) == SG_OK;
    }
    track = 0.0;
    if (m && (m->n != sys->nsurf || !m->cur))
        m = NULL;
    for (i = 0; i < sys->nsurf; i++) {
        const sg_surface *s = &sys->surf[i];
        /* Its own checks passed before for these bits at this place (a
         * memo is for one number of surfaces, so i is the object, the
         * image or neither as it was): they pass again, and what else
         * can fail comes in the same order. */
        int known = m && m->ok[i] && m->gen[i] == m->cur[i];
        if (known) {
            m->reused++;
            goto frames;
        }
        if (!finite_or_inf_radius(s->radius))
            return sg_diag_set(d, SG_ERANGE, "surface %d: radius is not a number", i);
        if ((int)s->type < SG_SURF_STANDARD || (int)s->type >= SG_SURF_NTYPES)
            return sg_diag_set(d, SG_ERANGE, "surface %d: type %d is unknown", i, (int)s->type);
        if (sg_phase_type(s->type)) {
            /* A phase surface (shape_phase.c): its terms within the
             * polynomial's degree. */
            int t, max = s->type == SG_SURF_BINARY_2 ? SG_P2_DEG / 2 : SG_ZERNIKE_FRINGE_MAX;
            if (!(s->norm_radius > 0.0) || !isfinite(s->norm_radius))
                return sg_diag_set(d, SG_ERANGE, "surface %d: norm_radius %g must be finite and "
                                   "positive", i, s->norm_radius);
            if (!isfinite(s->grating_order))
                return sg_diag_set(d, SG_ERANGE, "surface %d: the diffraction order %g must be "
                                   "finite", i, s->grating_order);
            for (t = 0; t < SG_NTERMS; t++) {
                if (s->terms[t] == 0.0)
                    continue;
                if (t >= max)
                    return sg_diag_set(d, SG_EUNSUPPORTED, "surface %d: phase term %d is set; "
                                       "sagitta reads terms 1 to %d of this type", i, t + 1, max);
            }
        }
        if (s->type == SG_SURF_PARAXIAL) {
            /* An ideal lens on a plane (shape_paraxial.c). */
            if (isfinite(s->radius) && s->radius != 0.0)
                return sg_diag_set(d, SG_ERANGE, "surface %d: a paraxial surface is flat; its "
                                   "radius must be inf, not %g", i, s->radius);
            if (!(s->focal_length != 0.0) || !isfinite(s->focal_length))
                return sg_diag_set(d, SG_ERANGE, "surface %d: a paraxial surface needs a "
                                   "nonzero, finite focal length (focal_length is %g)", i,
                                   s->focal_length);
            if (!(s->opd_mode == 0.0 || s->opd_mode == 1.0 || s->opd_mode == 2.0 ||
                  s->opd_mode == 3.0))
                return sg_diag_set(d, SG_ERANGE, "surface %d: opd_mode %g is not one of "
                                   "Zemax's OPD modes 0, 1, 2, 3", i, s->opd_mode);
            if (s->mat.kind == SG_MAT_MIRROR)
                return sg_diag_set(d, SG_EUNSUPPORTED, "surface %d: a paraxial surface "
                                   "cannot be a mirror in sagitta", i);
            if (i == 0 || i == sys->nsurf - 1)
                return sg_diag_set(d, SG_EUNSUPPORTED, "surface %d: the object and the image "
                                   "cannot be paraxial surfaces", i);
        }
        if (sg_shape_ops_of(s->type)) {
            /* What only the shape itself knows: its normalization radius
             * and terms. */
            sg_shape sh;
            int rc = sg_shape_prepare(s, &sh, i, d);
            if (rc != SG_OK)
                return rc;
        }
    frames:
        {
            int rc = check_frames(sys, i, d);
            if (rc != SG_OK)
                return rc;
        }
        if (known)
            goto track;
        /* Beyond this a trace's squares overflow: such a surface is flat
         * to every digit, and "inf" says so. */
        if (isfinite(s->radius) && fabs(s->radius) > SG_MAX_LEN)
            return sg_diag_set(d, SG_ERANGE,
                               "surface %d: radius %g is beyond %g lens units; write \"inf\" "
                               "for a flat surface", i, s->radius, SG_MAX_LEN);
        if (isfinite(s->thickness) && fabs(s->thickness) > SG_MAX_LEN)
            return sg_diag_set(d, SG_ERANGE,
                               "surface %d: thickness %g is beyond %g lens units", i,
                               s->thickness, SG_MAX_LEN);
    track:
        if (i > 0 && i < sys->nsurf - 1) {
            /* Decenters move the rays as far as thicknesses do. */
            track += fabs(s->thickness) + fabs(s->before.dx) + fabs(s->before.dy) +
                     fabs(s->after.dx) + fabs(s->after.dy);
            if (track > SG_MAX_LEN)
                return sg_diag_set(d, SG_ERANGE,
                                   "surface %d: thickness: the system is longer than %g lens "
                                   "units from surface 1 to here", i, SG_MAX_LEN);
        }
        if (known)
            goto warnings;
        if (i > 0 && i < sys->nsurf - 1 && !isfinite(s->thickness))
            return sg_diag_set(d, SG_ERANGE, "surface %d: thickness must be finite", i);
        if (i == 0 && isnan(s->thickness))
            return sg_diag_set(d, SG_ERANGE, "surface 0: thickness is not a number");
        /* The table's plain numbers: finite, within their limits. */
        for (p = 0; p < sg_param_count(SG_SCOPE_SURFACE); p++) {
            const sg_param *pp = sg_param_at(SG_SCOPE_SURFACE, p);
            char msg[160];
            const double *v;
            /* Frame changes are checked by check_frames, by their JSON names. */
            if (pp->kind != SG_PARAM_REAL ||
                (pp->flags & (SG_PARAM_INF | SG_PARAM_OBJ_INF | SG_PARAM_NESTED)))
                continue;
            v = sg_param_cptr(pp, s);
            for (k = 0; k < pp->count; k++) {
                if (v[k] == 0.0 && p < np && zero_ok[p][i == 0])
                    continue;
                if (sg_param_check(pp, k, v[k], i == 0, msg, sizeof msg) != SG_OK)
                    return sg_diag_set(d, SG_ERANGE, "surface %d: %s", i, msg);
            }
        }
        switch (s->aperture) {
        case SG_APERTURE_NONE:
            break;
        case SG_APERTURE_CIRCULAR:
        case SG_OBSCURATION_CIRCULAR:
            if (!(s->ap_rmax > s->ap_rmin))
                return sg_diag_set(d, SG_ERANGE,
                                   "surface %d: aperture: the maximum radius %g must be above "
                                   "the minimum radius %g", i, s->ap_rmax, s->ap_rmin);
            break;
        case SG_APERTURE_RECTANGULAR:
        case SG_OBSCURATION_RECTANGULAR:
        case SG_APERTURE_ELLIPTICAL:
        case SG_OBSCURATION_ELLIPTICAL:
            if (!(s->ap_xhalf > 0.0 && s->ap_yhalf > 0.0))
                return sg_diag_set(d, SG_ERANGE,
                                   "surface %d: aperture: the x and y half widths (%g, %g) must "
                                   "be positive", i, s->ap_xhalf, s->ap_yhalf);
            break;
        default:
            return sg_diag_set(d, SG_ERANGE, "surface %d: aperture: unknown type %d", i,
                               (int)s->aperture);
        }
        if (s->mat.kind == SG_MAT_INDEX && !(s->mat.index >= 1e-3 && s->mat.index < 100.0))
            return sg_diag_set(d, SG_ERANGE,
                               "surface %d: material index %g is not physical", i, s->mat.index);
        if (s->mat.kind == SG_MAT_MODEL &&
            !(s->mat.index >= SG_MODEL_ND_MIN && s->mat.index <= SG_MODEL_ND_MAX &&
              s->mat.vd >= SG_MODEL_VD_MIN && s->mat.vd <= SG_MODEL_VD_MAX &&
              fabs(s->mat.dpgf) <= SG_MODEL_DPGF_MAX))
            return sg_diag_set(d, SG_ERANGE,
                               "surface %d: model glass nd %g, vd %g, dPgF %g: nd must be %g to "
                               "%g, vd %g to %g and |dPgF| at most %g",
                               i, s->mat.index, s->mat.vd, s->mat.dpgf, SG_MODEL_ND_MIN,
                               SG_MODEL_ND_MAX, SG_MODEL_VD_MIN, SG_MODEL_VD_MAX,
                               SG_MODEL_DPGF_MAX);
        for (k = 0; k < s->nvar; k++)
            if (sg_param_material_part(s->var[k].param) && s->mat.kind != SG_MAT_MODEL)
                return sg_diag_set(d, SG_ERANGE, "surface %d: its %s is a variable, but its "
                                   "material is not a model glass (novar %d %s clears it)", i,
                                   s->var[k].param->label, i, s->var[k].param->key);
    warnings:
        if (s->mat.kind == SG_MAT_MODEL)
            for (k = 0; k < sys->nwave; k++)
                if (!(sys->wave[k].um >= 0.4 && sys->wave[k].um <= 0.75))
                    sg_diag_warn(d,
                                 "surface %d: wavelength %g um is outside 0.4 to 0.75 um, "
                                 "where the model glass is fitted",
                                 i, sys->wave[k].um);
        if (!known && s->mat.kind == SG_MAT_MIRROR && (i == 0 || i == sys->nsurf - 1))
            return sg_diag_set(d, SG_ENONPHYS,
                               "surface %d: the %s cannot be a mirror", i,
                               i == 0 ? "object" : "image");
        if (m && !known) {
            /* Its own checks passed (the catalog's is the loop's last). */
            m->gen[i] = m->cur[i];
            m->ok[i] = 1;
        }
        if (s->mat.kind == SG_MAT_GLASS && cat) {
            const sg_glass *g = sg_glass_seen_find(&found, cat, &s->mat);
            if (!g) {
                char where[96];
                sg_material_where(cat, &s->mat, where, sizeof where);
                return sg_diag_set(d, SG_ENOGLASS,
                                   "surface %d: material \"%s\"%s is not in the catalog",
                                   i, s->mat.name, where);
            }
            for (k = 0; k < sys->nwave; k++)
                if (!sg_glass_in_range(g, sys->wave[k].um))
                    sg_diag_warn(d,
                                 "surface %d: wavelength %g um is outside the range "
                                 "%g to %g um of %s",
                                 i, sys->wave[k].um, g->lmin, g->lmax, g->name);
        }
    }
    return SG_OK;
}

int sg_system_check(const sg_system *sys, const sg_catalog *cat, sg_diag *d)
{
    /* The caller validated the system already and has its warnings; here
     * only an error matters, so warnings go to a scratch record. */
    sg_diag scratch;
    int rc;
    sg_diag_clear(&scratch);
    rc = sg_system_validate(sys, cat, &scratch);
    if (rc != SG_OK)
        sg_diag_set(d, rc, "%s", scratch.msg);
    return rc;
}

double sg_digits(double a, double b)
{
    double e;
    if (a == b)
        return 17.0;
    if (isnan(a) || isnan(b))
        return 0.0;
    if (b == 0.0)
        return fabs(a) < 1e-300 ? 17.0 : 0.0;
    e = fabs(a - b) / fabs(b);
    e = -log10(e);
    if (e > 17.0)
        e = 17.0;
    return e < 0.0 ? 0.0 : e;
}

const sg_glass *sg_glass_seen_find(sg_glass_seen *gs, const sg_catalog *cat,
                                   const sg_material *m)
{
    const sg_glass *g;
    int k;
    if (!m || m->kind != SG_MAT_GLASS)
        return sg_material_glass(cat, m);
    /* Whole arrays, a few instructions: equal arrays hold equal names
     * (bytes after a name that differ only cost a look-up). */
    for (k = 0; k < gs->n; k++)
        if (memcmp(gs->mat[k]->name, m->name, sizeof m->name) == 0 &&
            memcmp(gs->mat[k]->catalog, m->catalog, sizeof m->catalog) == 0)
            return gs->g[k];
    g = sg_material_glass(cat, m);
    /* Full: the oldest entry goes. */
    k = gs->n < SG_GLASS_SEEN ? gs->n++ : (gs->next++ % SG_GLASS_SEEN);
    gs->mat[k] = m;
    gs->g[k] = g;
    return g;
}

void sg_zmx_origin_retain(struct sg_zmx_origin *o)
{
    if (o)
        __atomic_add_fetch(&((sg_origin_head *)o)->refs, 1, __ATOMIC_RELAXED);
}

void sg_zmx_origin_release(struct sg_zmx_origin *o)
{
    sg_origin_head *h = (sg_origin_head *)o;
    if (!o || __atomic_sub_fetch(&h->refs, 1, __ATOMIC_ACQ_REL) != 0)
        return;
    h->free(o);
}
