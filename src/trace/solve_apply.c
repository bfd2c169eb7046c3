/*
 * solve_apply.c - solves and pickups applied (sagitta-design(5), SOLVES);
 * model/solve.c names and checks them.
 *
 * The marginal-ray solves follow the y-nu trace of paraxial.c in 128-bit
 * MPFR, so a solved value is rounded once when it is stored.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shape.h"
#include "trace.h"

/* Passes before the pupil-dependent solves are declared not to settle. */
#define SOLVE_MAX_PASSES 64
#define SOLVE_PREC 128

/* The parameter a target names. */
static double *target_ptr(sg_surface *s, sg_solve_target t)
{
    switch (t) {
    case SG_SOLVE_RADIUS: return &s->radius;
    case SG_SOLVE_THICKNESS: return &s->thickness;
    default: return &s->conic;
    }
}

/* How a stored value moved: not at all, by a few units in the last place
 * (rounding of a pupil computed from values still settling), or more. */
#define MOVED_LITTLE 1
#define MOVED_MORE 3
#define SETTLE_ULPS 4.0

static int moved(double v, double old)
{
    if (memcmp(&v, &old, sizeof v) == 0)
        return 0;
    if (isfinite(v) && isfinite(old) && fabs(v - old) <= SETTLE_ULPS * DBL_EPSILON * fabs(v))
        return MOVED_LITTLE;
    return MOVED_MORE;
}

/* Stores x rounded once; a radius of 0 or beyond the limits is flat, as
 * the reader reads it.  Returns how the stored value moved. */
static int store(double *p, const mpfr_t x, sg_solve_target t)
{
    double v = mpfr_get_d(x, MPFR_RNDN), old = *p;
    if (t == SG_SOLVE_RADIUS && (v == 0.0 || !(fabs(v) <= SG_MAX_LEN)))
        v = INFINITY;
    *p = v;
    return moved(v, old);
}

/* The pickup: scale * source + offset; an infinite radius stays infinite
 * unless the scale is 0. */
static int pickup(sg_system *sys, int i, sg_solve_target t, mpfr_t a, int *changed)
{
    const sg_solve *v = &sys->surf[i].solve[t];
    double src = *target_ptr(&sys->surf[v->from], t);
    double *dst = target_ptr(&sys->surf[i], t);
    if (isinf(src)) {
        if (v->scale == 0.0)
            mpfr_set_d(a, v->offset, MPFR_RNDN);
        else if (t == SG_SOLVE_RADIUS)
            mpfr_set_inf(a, src > 0 ? (v->scale > 0 ? 1 : -1) : (v->scale > 0 ? -1 : 1));
        else
            return SG_ENONPHYS;
    } else {
        mpfr_set_d(a, src, MPFR_RNDN);
        mpfr_mul_d(a, a, v->scale, MPFR_RNDN);
        mpfr_add_d(a, a, v->offset, MPFR_RNDN);
    }
    if (!mpfr_number_p(a)) {
        double x = mpfr_get_d(a, MPFR_RNDN);
        *changed |= moved(x, *dst);
        *dst = x;
        return SG_OK;
    }
    *changed |= store(dst, a, t);
    return SG_OK;
}

/* Zemax's curvature pickup: c = scale * c_from + offset, so the radius is
 * 1 / (scale / R_from + offset), rounded once; a flat source has c = 0,
 * and c = 0 is flat. */
static void curv_pickup(sg_system *sys, int i, mpfr_t a, int *changed)
{
    const sg_solve *v = &sys->surf[i].solve[SG_SOLVE_RADIUS];
    double src = sys->surf[v->from].radius;
    if (isinf(src) || src == 0.0) {
        mpfr_set_zero(a, 1);
    } else {
        mpfr_set_d(a, src, MPFR_RNDN);
        mpfr_d_div(a, v->scale, a, MPFR_RNDN);
    }
    mpfr_add_d(a, a, v->offset, MPFR_RNDN);
    if (mpfr_zero_p(a))
        mpfr_set_inf(a, 1);
    else
        mpfr_ui_div(a, 1, a, MPFR_RNDN);
    *changed |= store(&sys->surf[i].radius, a, SG_SOLVE_RADIUS);
}

/* The paraxial marginal ray at surface 1, before it refracts: height y and
 * reduced slope w = n u, from the current system's entrance pupil; and the
 * chief ray of the largest field (cy, cw), as paraxial.c launches it per
 * unit field and scales it to the paraxial image height it gives. */
static int marginal_launch(const sg_system *sys, mpfr_t *idx, mpfr_t y, mpfr_t w, mpfr_t cy,
                           mpfr_t cw, sg_diag *d)
{
    sg_parax_mp p;
    mpfr_t u0, t;
    int rc, inf_obj = !isfinite(sys->surf[0].thickness);
    double T0 = sys->surf[0].thickness;
    sg_parax_mp_init(&p, SOLVE_PREC);
    mpfr_inits2(SOLVE_PREC, u0, t, (mpfr_ptr)0);
    rc = sg_paraxial_mpfr(sys, idx, sys->primary_wave, SOLVE_PREC, &p, d);
    if (rc == SG_OK) {
        if (sys->telecentric && !inf_obj) {
            mpfr_set_ui(cy, 1, MPFR_RNDN);
            mpfr_set_zero(cw, 1);
        } else if (inf_obj) {
            mpfr_neg(cy, p.enp, MPFR_RNDN);
            mpfr_set(cw, idx[0], MPFR_RNDN);
        } else {
            mpfr_add_d(t, p.enp, T0, MPFR_RNDN);
            mpfr_si_div(t, -1, t, MPFR_RNDN);
            mpfr_mul_d(cy, t, T0, MPFR_RNDN);
            mpfr_add_ui(cy, cy, 1, MPFR_RNDN);
            mpfr_mul(cw, t, idx[0], MPFR_RNDN);
        }
        /* The field scale: image height over image height per unit. */
        if (mpfr_zero_p(p.pimg_slope) || mpfr_zero_p(p.pimg_slope_f)) {
            mpfr_set_zero(cy, 1);
            mpfr_set_zero(cw, 1);
        } else {
            /* A paraxial-image-height field is defined at the paraxial
             * image plane (sg_parax_mp); the others' pimg_h is on the
             * image surface. */
            mpfr_div(t, p.pimg_h,
                     sys->field_type == SG_FIELD_PARAX_IMAGE_HEIGHT ? p.pimg_slope_f
                                                                   : p.pimg_slope,
                     MPFR_RNDN);
            mpfr_mul(cy, cy, t, MPFR_RNDN);
            mpfr_mul(cw, cw, t, MPFR_RNDN);
        }
        if (sys->telecentric && !inf_obj) {
            rc = sg_object_slope_mpfr(sys, idx[0], u0, d);
        } else if (inf_obj) {
            mpfr_div_2ui(y, p.epd, 1, MPFR_RNDN);
            mpfr_set_zero(w, 1);
        } else {
            mpfr_add_d(t, p.enp, T0, MPFR_RNDN);
            mpfr_div_2ui(u0, p.epd, 1, MPFR_RNDN);
            mpfr_div(u0, u0, t, MPFR_RNDN);
        }
        if (rc == SG_OK && !inf_obj) {
            mpfr_mul_d(y, u0, T0, MPFR_RNDN);
            mpfr_mul(w, u0, idx[0], MPFR_RNDN);
        }
    }
    mpfr_clears(u0, t, (mpfr_ptr)0);
    sg_parax_mp_clear(&p);
    return rc;
}

/* One pass over the surfaces; *changed collects how stored values moved. */
static int pass(sg_system *sys, mpfr_t *idx, int need_ray, int *changed, sg_diag *d)
{
    mpfr_t y, w, cy, cw, a, b;
    int i, t, rc = SG_OK, n = sys->nsurf;
    mpfr_inits2(SOLVE_PREC, y, w, cy, cw, a, b, (mpfr_ptr)0);
    if (need_ray && (rc = marginal_launch(sys, idx, y, w, cy, cw, d)) != SG_OK)
        goto out;
    for (i = 1; i < n; i++) {
        sg_surface *s = &sys->surf[i];
        /* The radius and conic, then the refraction, then the thickness. */
        for (t = SG_SOLVE_RADIUS; t <= SG_SOLVE_CONIC; t += 2) {
            sg_solve *v = &s->solve[t];
            if (v->kind == SG_SOLVE_PICKUP) {
                if (pickup(sys, i, (sg_solve_target)t, a, changed) != SG_OK) {
                    rc = sg_diag_set(d, SG_ENONPHYS, "surface %d: %s: the pickup from "
                                     "surface %d is of an infinite value", i,
                                     sg_solve_target_name((sg_solve_target)t), v->from);
                    goto out;
                }
            } else if (v->kind == SG_SOLVE_CURV_PICKUP) {
                curv_pickup(sys, i, a, changed);
            } else if (v->kind == SG_SOLVE_MARGINAL_ANGLE || v->kind == SG_SOLVE_FNUM) {
                /* n' u' = n u - y c (n' - n), so c = (w - n' u') / (y (n' - n)). */
                mpfr_sub(b, idx[i], idx[i - 1], MPFR_RNDN);
                if (mpfr_zero_p(y) || mpfr_zero_p(b)) {
                    rc = sg_diag_set(d, SG_ENONPHYS, "surface %d: radius: the %s solve has no "
                                     "solution: %s", i, sg_solve_kind_name(v->kind),
                                     mpfr_zero_p(y) ? "the paraxial marginal ray meets the "
                                     "surface on the axis" : "the index does not change there");
                    goto out;
                }
                if (v->kind == SG_SOLVE_FNUM) {
                    /* u' = -1 / (2 F), unrounded. */
                    mpfr_set_d(a, v->value, MPFR_RNDN);
                    mpfr_d_div(a, -0.5, a, MPFR_RNDN);
                } else {
                    mpfr_set_d(a, v->value, MPFR_RNDN);
                }
                mpfr_mul(a, a, idx[i], MPFR_RNDN);
                mpfr_sub(a, w, a, MPFR_RNDN);
                mpfr_mul(b, b, y, MPFR_RNDN);
                /* The radius: y (n' - n) / (w - n' u'). */
                if (mpfr_zero_p(a))
                    mpfr_set_inf(a, 1);
                else
                    mpfr_div(a, b, a, MPFR_RNDN);
                *changed |= store(&s->radius, a, SG_SOLVE_RADIUS);
            }
        }
        if (need_ray && ((s->type != SG_SURF_COORDBRK && s->type != SG_SURF_PARAXIAL &&
                          isfinite(s->radius) && s->radius != 0.0) ||
                         s->type == SG_SURF_PARAXIAL || sg_phase_type(s->type))) {
            if (s->type == SG_SURF_PARAXIAL) {
                /* An ideal lens's power is 1 / f (shape_paraxial.c). */
                mpfr_set_d(a, s->focal_length, MPFR_RNDN);
                mpfr_ui_div(a, 1, a, MPFR_RNDN);
            } else if (isfinite(s->radius) && s->radius != 0.0) {
                mpfr_sub(a, idx[i], idx[i - 1], MPFR_RNDN);
                mpfr_div_d(a, a, s->radius, MPFR_RNDN);
            } else {
                mpfr_set_zero(a, 1);
            }
            /* A phase surface's own power (shape_phase.c), at the primary
             * wavelength the solves use. */
            if (sg_phase_type(s->type))
                mpfr_add_d(a, a, sg_phase_power(sys, i, sys->wave[sys->primary_wave].um),
                           MPFR_RNDN);
            mpfr_mul(b, a, cy, MPFR_RNDN);
            mpfr_sub(cw, cw, b, MPFR_RNDN);
            mpfr_mul(a, a, y, MPFR_RNDN);
            mpfr_sub(w, w, a, MPFR_RNDN);
        }
        if (s->solve[SG_SOLVE_THICKNESS].kind == SG_SOLVE_PICKUP) {
            if (pickup(sys, i, SG_SOLVE_THICKNESS, a, changed) != SG_OK ||
                !isfinite(s->thickness)) {
                rc = sg_diag_set(d, SG_ENONPHYS, "surface %d: thickness: the pickup from "
                                 "surface %d is not finite", i,
                                 s->solve[SG_SOLVE_THICKNESS].from);
                goto out;
            }
        } else if (s->solve[SG_SOLVE_THICKNESS].kind == SG_SOLVE_POSITION) {
            /* t = L - (the thicknesses from the reference to here), in
             * 128 bits and rounded once. */
            const sg_solve *v = &s->solve[SG_SOLVE_THICKNESS];
            int j;
            mpfr_set_d(a, v->value, MPFR_RNDN);
            for (j = v->from; j < i && mpfr_number_p(a); j++)
                mpfr_sub_d(a, a, sys->surf[j].thickness, MPFR_RNDN);
            if (!mpfr_number_p(a) || !(fabs(mpfr_get_d(a, MPFR_RNDN)) <= SG_MAX_LEN)) {
                rc = sg_diag_set(d, SG_ENONPHYS, "surface %d: thickness: the position solve "
                                 "from surface %d gives %g, not a finite length within %g "
                                 "lens units", i, v->from, mpfr_get_d(a, MPFR_RNDN),
                                 SG_MAX_LEN);
                goto out;
            }
            *changed |= store(&s->thickness, a, SG_SOLVE_THICKNESS);
        } else if (s->solve[SG_SOLVE_THICKNESS].kind == SG_SOLVE_MARGINAL_HEIGHT ||
                   s->solve[SG_SOLVE_THICKNESS].kind == SG_SOLVE_CHIEF_HEIGHT) {
            /* y + t w / n' = h, so t = (h - y) n' / w. */
            int chief = s->solve[SG_SOLVE_THICKNESS].kind == SG_SOLVE_CHIEF_HEIGHT;
            if (mpfr_zero_p(chief ? cw : w)) {
                rc = sg_diag_set(d, SG_ENONPHYS, "surface %d: thickness: the %s solve has no "
                                 "solution: the paraxial %s ray leaves the surface parallel to "
                                 "the axis", i, chief ? "chief_height" : "marginal_height",
                                 chief ? "chief" : "marginal");
                goto out;
            }
            mpfr_set_d(a, s->solve[SG_SOLVE_THICKNESS].value, MPFR_RNDN);
            mpfr_sub(a, a, chief ? cy : y, MPFR_RNDN);
            mpfr_mul(a, a, idx[i], MPFR_RNDN);
            mpfr_div(a, a, chief ? cw : w, MPFR_RNDN);
            if (!(fabs(mpfr_get_d(a, MPFR_RNDN)) <= SG_MAX_LEN)) {
                rc = sg_diag_set(d, SG_ENONPHYS, "surface %d: thickness: the %s solve gives "
                                 "%g, beyond %g lens units", i, chief ? "chief_height" :
                                 "marginal_height", mpfr_get_d(a, MPFR_RNDN), SG_MAX_LEN);
                goto out;
            }
            *changed |= store(&s->thickness, a, SG_SOLVE_THICKNESS);
        }
        if (need_ray && i < n - 1) {
            mpfr_mul_d(a, w, s->thickness, MPFR_RNDN);
            mpfr_div(a, a, idx[i], MPFR_RNDN);
            mpfr_add(y, y, a, MPFR_RNDN);
            mpfr_mul_d(a, cw, s->thickness, MPFR_RNDN);
            mpfr_div(a, a, idx[i], MPFR_RNDN);
            mpfr_add(cy, cy, a, MPFR_RNDN);
        }
    }
out:
    mpfr_clears(y, w, cy, cw, a, b, (mpfr_ptr)0);
    return rc;
}

int sg_system_apply_solves(sg_system *sys, const sg_catalog *cat, sg_diag *d)
{
    mpfr_t *idx;
    int i, t, rc = SG_OK, need_ray = 0, npass, changed = MOVED_MORE;
    if (!sg_system_has_solves(sys))
        return SG_OK;
    for (i = 0; i < sys->nsurf; i++)
        for (t = 0; t < SG_SOLVE_NTARGETS; t++) {
            sg_solve_kind k = sys->surf[i].solve[t].kind;
            if ((rc = sg_solve_check(sys, i, (sg_solve_target)t, d)) != SG_OK)
                return rc;
            need_ray |= k != SG_SOLVE_NONE && !sg_solve_is_pickup(k) &&
                        k != SG_SOLVE_POSITION && k != SG_SOLVE_VARIABLE;
        }
    if (sys->nwave < 1 || sys->primary_wave < 0 || sys->primary_wave >= sys->nwave)
        return sg_diag_set(d, SG_ERANGE, "solves: the primary wavelength is not set");
    idx = calloc((size_t)sys->nsurf, sizeof *idx);
    if (!idx)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (i = 0; i < sys->nsurf; i++)
        mpfr_init2(idx[i], SOLVE_PREC);
    rc = sg_indices_mpfr(sys, cat, sys->primary_wave, idx, d);
    /* Pickups alone settle in one pass; the marginal ray's launch depends
     * on values solved after it, so those passes repeat until no value
     * moves by more than a few units in the last place. */
    for (npass = 0; rc == SG_OK && (changed & 2) && npass < SOLVE_MAX_PASSES; npass++) {
        changed = 0;
        rc = pass(sys, idx, need_ray, &changed, d);
        if (!need_ray)
            changed = 0;
    }
    if (rc == SG_OK && (changed & 2))
        rc = sg_diag_set(d, SG_ENONPHYS, "solves: the solved values do not settle after %d "
                         "passes", SOLVE_MAX_PASSES);
    for (i = 0; i < sys->nsurf; i++)
        mpfr_clear(idx[i]);
    free(idx);
    return rc;
}
