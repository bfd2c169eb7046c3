/*
 * tolerance.c - tolerancing as Zemax does it (sagitta(1), TOLERANCING;
 * sagitta-design(5), TOLERANCES): each operand changes a copy of the
 * nominal design, compensators are re-optimized by the optimizer's damped
 * least squares on the criterion, and the criterion is the RMS spot radius
 * over the fields as sg_spot_compute gives it (or the merit function).
 * Sensitivity takes each operand to its min and max; Monte Carlo draws
 * every operand, trial t's draws depending only on (seed, t).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "model.h"
#include "design_int.h"

static const char *const tol_names[SG_TOL_NTYPES] = {
    "TRAD", "TCUR", "TFRN", "TTHI", "TCON", "TPAR", "TSDX", "TSDY", "TSTX", "TSTY",
    "TEDX", "TEDY", "TETX", "TETY", "TETZ", "TIND", "TABB", "TIRR", "TEZI"};

/* Zemax's default test wavelength for fringes, in micrometres (TWAV). */
#define TOL_FRINGE_UM 0.6328

const char *sg_tol_name(sg_tol_type t)
{
    return (int)t >= 0 && t < SG_TOL_NTYPES ? tol_names[t] : NULL;
}

int sg_tol_parse(const char *name)
{
    int t;
    for (t = 0; name && t < SG_TOL_NTYPES; t++)
        if (strcmp(name, tol_names[t]) == 0)
            return t;
    return -1;
}

static int is_element(sg_tol_type t)
{
    return t >= SG_TOL_TEDX && t <= SG_TOL_TETZ;
}

/* Lens units per micrometre. */
static double um_to_units(const sg_system *sys)
{
    if (strcmp(sys->units, "cm") == 0)
        return 1e-4;
    if (strcmp(sys->units, "in") == 0)
        return 1e-3 / 25.4;
    if (strcmp(sys->units, "m") == 0)
        return 1e-6;
    return 1e-3;
}

/* The test wavelength of fringes in lens units. */
static double fringe_wave(const sg_system *sys)
{
    double w = sys->tol.test_wave > 0.0 ? sys->tol.test_wave : TOL_FRINGE_UM;
    return w * um_to_units(sys);
}

void sg_tol_opts_init(sg_tol_opts *o)
{
    memset(o, 0, sizeof *o);
    o->method = SG_METHOD_PRECISE;
    o->compensate = 1;
}

/* ------------------------------------------------------------------------
 * Checks
 * ------------------------------------------------------------------------ */

static int op_err(sg_diag *d, int k, const sg_tol_operand *op, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static int op_err(sg_diag *d, int k, const sg_tol_operand *op, const char *fmt, ...)
{
    char msg[SG_DIAG_MSG];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sg_diag_set(d, SG_ERANGE, "tolerances: operand %d (%s): %s", k + 1,
                       tol_names[op->type], msg);
}

/* Whether the surfaces first..last hold a rigid element the return of
 * sg_tol_apply can undo: no coordinate break, no mirror, no frame change
 * that does not come back on its own surface. */
static int element_ok(const sg_system *sys, int first, int last, int *bad)
{
    int i;
    for (i = first; i <= last; i++) {
        const sg_surface *s = &sys->surf[i];
        if (s->type == SG_SURF_COORDBRK || s->mat.kind == SG_MAT_MIRROR ||
            (sg_surface_moves_frame(s) && s->after_mode != SG_AFTER_REVERSE) ||
            !isfinite(s->thickness)) {
            *bad = i;
            return 0;
        }
    }
    return 1;
}

int sg_tol_check(const sg_system *sys, sg_diag *d)
{
    const sg_tolerances *t = &sys->tol;
    int k, j, bad;
    int last_img = sys->nsurf - 1;
    if (!(t->test_wave == 0.0 || (t->test_wave >= 0.1 && t->test_wave <= 100.0)))
        return sg_diag_set(d, SG_ERANGE, "tolerances: test_wavelength: %.17g um is not 0.1 to "
                           "100 um", t->test_wave);
    for (k = 0; k < t->nop; k++) {
        const sg_tol_operand *op = &t->op[k];
        const sg_surface *s;
        int lo = op->type == SG_TOL_TTHI ? 0 : 1;
        if ((int)op->type < 0 || op->type >= SG_TOL_NTYPES)
            return sg_diag_set(d, SG_ERANGE, "tolerances: operand %d: unknown type", k + 1);
        if (!(isfinite(op->min) && isfinite(op->max) && op->min <= op->max))
            return op_err(d, k, op, "min must not exceed max (both finite)");
        if (op->surface < lo || op->surface > last_img - 1)
            return op_err(d, k, op, "surface %d is not a surface between the object and the "
                          "image", op->surface);
        s = &sys->surf[op->surface];
        switch (op->type) {
        case SG_TOL_TRAD:
            if (!isfinite(s->radius) || s->radius == 0.0)
                return op_err(d, k, op, "surface %d is flat, so its radius has no change; "
                              "use TCUR or TFRN", op->surface);
            /* fall through */
        case SG_TOL_TCUR:
        case SG_TOL_TFRN:
        case SG_TOL_TCON:
            if (s->type == SG_SURF_COORDBRK)
                return op_err(d, k, op, "surface %d is a coordinate break", op->surface);
            break;
        case SG_TOL_TTHI:
            if (!isfinite(s->thickness))
                return op_err(d, k, op, "the thickness of surface %d is infinite", op->surface);
            if (op->adjust >= 0 && (op->adjust > last_img - 1 || op->adjust == op->surface ||
                                    !isfinite(sys->surf[op->adjust].thickness)))
                return op_err(d, k, op, "adjust: surface %d cannot take the change", op->adjust);
            break;
        case SG_TOL_TPAR: {
            sg_paddr a;
            sg_diag d2;
            sg_diag_clear(&d2);
            if (sg_paddr_make(sys, SG_SCOPE_SURFACE, op->surface, op->param, op->elem, &a,
                              &d2) != SG_OK)
                return op_err(d, k, op, "%s", d2.msg);
            break;
        }
        case SG_TOL_TSDX: case SG_TOL_TSDY: case SG_TOL_TSTX: case SG_TOL_TSTY:
            if (s->type == SG_SURF_COORDBRK)
                return op_err(d, k, op, "surface %d is a coordinate break", op->surface);
            if (!sg_frame_change_is_zero(&s->before) &&
                (s->after_mode != SG_AFTER_REVERSE || s->before.order != 0))
                return op_err(d, k, op, "surface %d has a frame change that is not undone "
                              "after it (\"after\": \"reverse\", order 0); Zemax's surface "
                              "decenter and tilt need one", op->surface);
            if (sg_frame_change_is_zero(&s->before) && s->after_mode != SG_AFTER_REVERSE &&
                !sg_frame_change_is_zero(&s->after))
                return op_err(d, k, op, "surface %d has an after change of its own", op->surface);
            break;
        case SG_TOL_TEDX: case SG_TOL_TEDY: case SG_TOL_TETX: case SG_TOL_TETY:
        case SG_TOL_TETZ:
            if (op->last < op->surface || op->last > last_img - 1)
                return op_err(d, k, op, "last: surface %d is not from first to the surface "
                              "before the image", op->last);
            if (!element_ok(sys, op->surface, op->last, &bad))
                return op_err(d, k, op, "surface %d of the element is a coordinate break, a "
                              "mirror, moves the frame or has an infinite thickness", bad);
            for (j = 0; j < k; j++) {
                const sg_tol_operand *o2 = &t->op[j];
                if (is_element(o2->type) &&
                    !(o2->surface == op->surface && o2->last == op->last) &&
                    !(o2->last < op->surface || o2->surface > op->last))
                    return op_err(d, k, op, "the element overlaps operand %d's; elements "
                                  "must be the same surfaces or apart", j + 1);
            }
            break;
        case SG_TOL_TIRR:
            /* Zemax's TIRR takes a Standard surface alone. */
            if (s->type != SG_SURF_STANDARD)
                return op_err(d, k, op, "surface %d is not a standard surface", op->surface);
            break;
        case SG_TOL_TEZI:
            /* Zemax's TEZI: a Standard or Even Asphere surface becomes a
             * Zernike Standard Sag; terms 2 (no piston) up to sagitta's. */
            if (s->type != SG_SURF_STANDARD && s->type != SG_SURF_EVENASPH)
                return op_err(d, k, op, "surface %d is not a standard or even asphere "
                              "surface", op->surface);
            if (!(op->zmin >= 2 && op->zmin <= op->zmax && op->zmax <= SG_NTERMS))
                return op_err(d, k, op, "terms %d to %d: the first must be 2 or more, the last "
                              "not below it nor above %d (Zernike Standard terms to radial "
                              "order 10)", op->zmin, op->zmax, SG_NTERMS);
            if (op->min != -op->max)
                return op_err(d, k, op, "min must be -max: the RMS is max, and min gives the "
                              "terms their other sign, as Zemax sets it");
            break;
        case SG_TOL_TIND:
        case SG_TOL_TABB:
            if (s->mat.kind == SG_MAT_MODEL || s->mat.kind == SG_MAT_GLASS)
                break;
            if (s->mat.kind == SG_MAT_INDEX && op->type == SG_TOL_TIND)
                break;
            return op_err(d, k, op, "surface %d: only a glass (or, for TIND, a fixed index) "
                          "takes this operand", op->surface);
        default:
            break;
        }
    }
    for (k = 0; k < t->ncomp; k++) {
        const sg_tol_comp *c = &t->comp[k];
        sg_paddr a;
        sg_diag d2;
        double v;
        sg_diag_clear(&d2);
        if (sg_paddr_make(sys, SG_SCOPE_SURFACE, c->surface, c->param, c->elem, &a, &d2) !=
            SG_OK)
            return sg_diag_set(d, SG_ERANGE, "tolerances: compensator %d: %s", k + 1, d2.msg);
        if (!(isfinite(c->min) && isfinite(c->max) && c->min <= c->max))
            return sg_diag_set(d, SG_ERANGE, "tolerances: compensator %d: min must not exceed "
                               "max (both finite)", k + 1);
        v = sg_paddr_get(sys, &a);
        if (!isfinite(v))
            return sg_diag_set(d, SG_ERANGE, "tolerances: compensator %d: surface %d's %s is "
                               "infinite", k + 1, c->surface, c->param);
        if (sg_paddr_solve_target(&a) == SG_SOLVE_RADIUS && !(v + c->min > 0.0) &&
            !(v + c->max < 0.0))
            return sg_diag_set(d, SG_ERANGE, "tolerances: compensator %d: the radius's range "
                               "%g to %g encloses 0", k + 1, v + c->min, v + c->max);
    }
    if (t->criterion == SG_TOLC_MERIT) {
        if (!sys->merit.present)
            return sg_diag_set(d, SG_ERANGE, "tolerances: criterion: the design has no merit "
                               "function");
        for (k = 0; k < t->nop; k++)
            if (is_element(t->op[k].type))
                return sg_diag_set(d, SG_ERANGE, "tolerances: criterion: the merit function's "
                                   "surface numbers do not follow the coordinate breaks of "
                                   "operand %d (%s); use rms_spot", k + 1,
                                   tol_names[t->op[k].type]);
    }
    return SG_OK;
}

int sg_tol_nominal(const sg_system *sys, const sg_catalog *cat, sg_system *out, sg_diag *d)
{
    int i, k, rc, need_sd = 0;
    if ((rc = sg_tol_check(sys, d)) != SG_OK)
        return rc;
    if ((rc = sg_system_assign(out, sys)) != SG_OK)
        return sg_diag_set(d, rc, "out of memory");
    if ((rc = sg_system_apply_solves(out, cat, d)) != SG_OK)
        return rc;
    for (i = 0; i < out->nsurf; i++)
        for (k = 0; k < SG_SOLVE_NTARGETS; k++) {
            sg_solve *v = &out->surf[i].solve[k];
            if (v->kind != SG_SOLVE_PICKUP && v->kind != SG_SOLVE_CURV_PICKUP)
                memset(v, 0, sizeof *v);
        }
    /* Fringes are counted over the clear aperture: an automatic one is
     * found once, on the nominal. */
    for (k = 0; k < sys->tol.nop; k++)
        if ((sys->tol.op[k].type == SG_TOL_TFRN || sys->tol.op[k].type == SG_TOL_TIRR ||
             sys->tol.op[k].type == SG_TOL_TEZI) &&
            !(out->surf[sys->tol.op[k].surface].semi_diameter > 0.0))
            need_sd = 1;
    if (need_sd) {
        double *sd = malloc((size_t)out->nsurf * sizeof *sd);
        if (!sd)
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        if ((rc = sg_semi_diameters(out, cat, NULL, sd, d)) != SG_OK) {
            free(sd);
            return rc;
        }
        for (i = 0; i < out->nsurf; i++)
            if (!(out->surf[i].semi_diameter > 0.0))
                out->surf[i].semi_diameter = sd[i];
        free(sd);
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Perturbations
 * ------------------------------------------------------------------------ */

int sg_tol_apply(const sg_system *nom, const sg_catalog *cat, const double *delta,
                 sg_system *out, int *map, sg_diag *d)
{
    const sg_tolerances *t = &nom->tol;
    int k, i, rc;
    int done[SG_MAX_TOL_OPERANDS];
    if ((rc = sg_system_assign(out, nom)) != SG_OK)
        return sg_diag_set(d, rc, "out of memory");
    if (map)
        for (i = 0; i < nom->nsurf; i++)
            map[i] = i;
    /* Values first, in the nominal's numbering. */
    for (k = 0; k < t->nop; k++) {
        const sg_tol_operand *op = &t->op[k];
        sg_surface *s = &out->surf[op->surface];
        double v = delta[k];
        if (v == 0.0)
            continue;
        switch (op->type) {
        case SG_TOL_TRAD: s->radius += v; break;
        case SG_TOL_TCUR: {
            double c = sg_surface_curvature(s) + v;
            s->radius = c == 0.0 ? INFINITY : 1.0 / c;
            break;
        }
        case SG_TOL_TFRN: {
            /* N fringes of power over the semi-diameter r: a sag change of
             * N half waves at r, dc = N lambda / r^2. */
            double r = s->semi_diameter;
            double c = sg_surface_curvature(s) + v * fringe_wave(nom) / (r * r);
            s->radius = c == 0.0 ? INFINITY : 1.0 / c;
            break;
        }
        case SG_TOL_TTHI:
            s->thickness += v;
            if (op->adjust >= 0)
                out->surf[op->adjust].thickness -= v;
            break;
        case SG_TOL_TCON: s->conic += v; break;
        case SG_TOL_TPAR: {
            sg_paddr a;
            if ((rc = sg_paddr_make(out, SG_SCOPE_SURFACE, op->surface, op->param, op->elem, &a,
                                    d)) != SG_OK)
                return rc;
            sg_paddr_set(out, &a, sg_paddr_get(out, &a) + v);
            break;
        }
        case SG_TOL_TSDX: case SG_TOL_TSDY: case SG_TOL_TSTX: case SG_TOL_TSTY:
            /* Zemax's surface decenter and tilt: before the surface, undone
             * after it. */
            if (op->type == SG_TOL_TSDX) s->before.dx += v;
            if (op->type == SG_TOL_TSDY) s->before.dy += v;
            if (op->type == SG_TOL_TSTX) s->before.tx += v;
            if (op->type == SG_TOL_TSTY) s->before.ty += v;
            s->after_mode = SG_AFTER_REVERSE;
            break;
        case SG_TOL_TIND:
            /* A catalog glass's curve moves by v at every wavelength; a
             * fixed index, or a model glass's nd, by v. */
            if (s->mat.kind == SG_MAT_GLASS)
                s->mat.dn += v;
            else
                s->mat.index += v;
            break;
        case SG_TOL_TIRR: {
            /* Zemax's irregularity: v fringes (double pass, at the test
             * wavelength) at the semi-diameter r, half spherical and half
             * astigmatism, Zs rho^4 + Za rho_y^2 with Zs = Za = v lambda /
             * 4 (Zemax's Irregular surface); made an XY polynomial over
             * x / r and y / r. */
            double z = v * fringe_wave(nom) / 4.0;
            if (s->type == SG_SURF_STANDARD) {
                s->type = SG_SURF_XYPOLY;
                s->norm_radius = s->semi_diameter;
                memset(s->terms, 0, sizeof s->terms);
            }
            s->terms[4] += z;       /* y^2 */
            s->terms[9] += z;       /* x^4 */
            s->terms[11] += 2 * z;  /* x^2 y^2 */
            s->terms[13] += z;      /* y^4 */
            break;
        }
        case SG_TOL_TEZI: {
            /* Zemax's TEZI: the surface as a Zernike Standard Sag over its
             * semi-diameter, every term zmin..zmax the same coefficient,
             * v / sqrt(N), so the sag's RMS over the disc is |v| (Noll's
             * terms have unit RMS and are orthogonal). */
            int j, nt = op->zmax - op->zmin + 1;
            double a = v / sqrt((double)nt);
            if (s->type == SG_SURF_STANDARD || s->type == SG_SURF_EVENASPH) {
                s->type = SG_SURF_ZERNIKE_STANDARD;
                s->norm_radius = s->semi_diameter;
                memset(s->terms, 0, sizeof s->terms);
                s->zern_dx = s->zern_dy = 0.0;
            }
            for (j = op->zmin; j <= op->zmax; j++)
                s->terms[j - 1] += a;
            break;
        }
        case SG_TOL_TABB:
            if (s->mat.kind == SG_MAT_GLASS) {
                /* nd held, n(F) - n(C) = (nd - 1) / vd: the dispersion
                 * about the d line scales by vd / (vd + v). */
                const sg_glass *g = cat ? sg_material_glass(cat, &s->mat) : NULL;
                double f = s->mat.disp != 0.0 ? s->mat.disp : 1.0;
                if (!g || !(g->vd + v > 0.0))
                    return sg_diag_set(d, SG_ENOGLASS, "tolerances: operand %d (TABB): "
                                       "surface %d: %s", k + 1, op->surface,
                                       g ? "the Abbe number would not be positive"
                                         : "the glass is not in the catalog");
                s->mat.disp = f * g->vd / (g->vd + v);
            } else {
                s->mat.vd += v;
            }
            break;
        default: break;
        }
    }
    if (sg_system_has_solves(out) && (rc = sg_system_apply_solves(out, cat, d)) != SG_OK)
        return rc;
    /* Elements last, from the highest first surface down, so the
     * insertions leave the lower numbers as they are. */
    memset(done, 0, sizeof done);
    for (;;) {
        int best = -1, first, last, at;
        sg_frame_change c;
        double T = 0.0, Tl;
        for (k = 0; k < t->nop; k++)
            if (is_element(t->op[k].type) && !done[k] && delta[k] != 0.0 &&
                (best < 0 || t->op[k].surface > t->op[best].surface))
                best = k;
        if (best < 0)
            break;
        first = t->op[best].surface;
        last = t->op[best].last;
        memset(&c, 0, sizeof c);
        for (k = 0; k < t->nop; k++) {
            const sg_tol_operand *op = &t->op[k];
            if (!is_element(op->type) || done[k] || op->surface != first || op->last != last)
                continue;
            done[k] = 1;
            if (op->type == SG_TOL_TEDX) c.dx += delta[k];
            if (op->type == SG_TOL_TEDY) c.dy += delta[k];
            if (op->type == SG_TOL_TETX) c.tx += delta[k];
            if (op->type == SG_TOL_TETY) c.ty += delta[k];
            if (op->type == SG_TOL_TETZ) c.tz += delta[k];
        }
        /* The element is the surfaces first..last, here unnumbered yet. */
        for (i = first; i < last; i++)
            T += out->surf[i].thickness;
        Tl = out->surf[last].thickness;
        /* Rays start in surface 1's frame, which no break may precede:
         * an element there gets a dummy plane of the object's medium in
         * front, at its vertex, and the break after that. */
        if (first == 1) {
            if ((rc = sg_system_insert(out, 1)) != SG_OK)
                return sg_diag_set(d, rc, "out of memory");
            out->surf[1].mat = out->surf[0].mat;
            out->surf[1].thickness = 0.0;
            if (map)
                for (i = 0; i < nom->nsurf; i++)
                    if (map[i] >= 1)
                        map[i]++;
            first++;
            last++;
        }
        /* A break before the element: decenter, then tilt about its first
         * vertex. */
        if ((rc = sg_system_insert(out, first)) != SG_OK)
            return sg_diag_set(d, rc, "out of memory");
        out->surf[first].type = SG_SURF_COORDBRK;
        out->surf[first].before = c;
        out->surf[first].thickness = 0.0;
        at = last + 2;
        /* Back along the element's axis to that vertex, the break undone
         * there (order toggled, values negated), then on to where the next
         * surface was. */
        out->surf[at - 1].thickness = 0.0 - T; /* +0 for a single surface */
        if ((rc = sg_system_insert(out, at)) != SG_OK)
            return sg_diag_set(d, rc, "out of memory");
        out->surf[at].type = SG_SURF_COORDBRK;
        out->surf[at].before.dx = 0.0 - c.dx;
        out->surf[at].before.dy = 0.0 - c.dy;
        out->surf[at].before.tx = 0.0 - c.tx;
        out->surf[at].before.ty = 0.0 - c.ty;
        out->surf[at].before.tz = 0.0 - c.tz;
        out->surf[at].before.order = 1;
        out->surf[at].thickness = T + Tl;
        if (map)
            for (i = 0; i < nom->nsurf; i++) {
                if (map[i] >= first)
                    map[i]++;
                if (map[i] >= at)
                    map[i]++;
            }
    }
    /* Rays start in surface 1's frame, which nothing may move: a surface
     * decenter or tilt there (TSDX ... TSTY) gets a plane of the object's
     * medium in front, at its vertex, as an element there does. */
    if (out->nsurf > 2 && !sg_frame_change_is_zero(&out->surf[1].before)) {
        if ((rc = sg_system_insert(out, 1)) != SG_OK)
            return sg_diag_set(d, rc, "out of memory");
        out->surf[1].mat = out->surf[0].mat;
        out->surf[1].thickness = 0.0;
        if (map)
            for (i = 0; i < nom->nsurf; i++)
                if (map[i] >= 1)
                    map[i]++;
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * The criterion and the compensators
 * ------------------------------------------------------------------------ */

/* Each field's value and its share sqrt(w / sum w): the criterion is the
 * root sum of squares of the shares times the values. */
static int field_values(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                        int nthreads, sg_tol_value *out, double *share, sg_diag *d)
{
    const sg_tolerances *t = &sys->tol;
    int f, rc;
    memset(out, 0, sizeof *out);
    if (t->criterion == SG_TOLC_MERIT) {
        sg_merit_result r;
        if ((rc = sg_merit_eval(sys, cat, &r, d)) != SG_OK)
            return rc;
        out->criterion = r.merit;
        out->nfield = 0;
        if (share)
            share[0] = 1.0;
        sg_merit_result_free(&r);
        return SG_OK;
    } else if (t->criterion == SG_TOLC_RMS_WAVEFRONT) {
        /* Each field's RMS wavefront error in waves, as sagitta wavefront
         * gives it at each wavelength (about the centroid: piston and tilt
         * removed; about the chief ray: piston), combined over the
         * wavelengths as sqrt(sum w r^2 / sum w). */
        double wsum = 0.0, acc = 0.0;
        int w;
        for (f = 0; f < sys->nfield; f++) {
            double s2 = 0.0, ww = 0.0;
            for (w = 0; w < sys->nwave; w++) {
                sg_wavefront_opts wo;
                sg_wavefront wf;
                sg_opd_ref ref;
                sg_wavefront_opts_init(&wo);
                wo.trace.method = (sg_method)o->method;
                if (o->mpfr_bits > 0)
                    wo.trace.mpfr_bits = o->mpfr_bits;
                wo.trace.wave = w;
                wo.field = f;
                wo.grid = t->grid > 0 ? t->grid : 64;
                wo.nterms = 1;
                wo.nthreads = nthreads;
                if ((rc = sg_wavefront_trace(sys, cat, &wo, &wf, &ref, d)) != SG_OK)
                    return rc;
                if (wf.nvalid == 0) {
                    sg_wavefront_free(&wf);
                    return sg_diag_set(d, SG_EMISS, "field %d: no ray reaches the image",
                                       f + 1);
                }
                {
                    double r = t->reference == SG_SPOT_REF_CENTROID ? wf.rms_centroid
                                                                    : wf.rms_chief;
                    s2 += sys->wave[w].weight * r * r;
                    ww += sys->wave[w].weight;
                }
                sg_wavefront_free(&wf);
            }
            out->field[f] = ww > 0.0 ? sqrt(s2 / ww) : 0.0;
            wsum += sys->field[f].weight;
        }
        out->nfield = sys->nfield;
        if (!(wsum > 0.0))
            wsum = 1.0;
        for (f = 0; f < sys->nfield; f++) {
            double s = sqrt(sys->field[f].weight / wsum);
            if (share)
                share[f] = s;
            acc = hypot(acc, s * out->field[f]);
        }
        out->criterion = acc;
        return SG_OK;
    } else {
        sg_spot_opts so;
        sg_spot sp;
        double wsum = 0.0, acc = 0.0;
        sg_spot_opts_init(&so);
        so.trace.method = (sg_method)o->method;
        if (o->mpfr_bits > 0)
            so.trace.mpfr_bits = o->mpfr_bits;
        so.pattern = t->pattern;
        so.density = t->density;
        so.reference = t->reference;
        so.nthreads = nthreads;
        if ((rc = sg_spot_compute(sys, cat, &so, &sp, d)) != SG_OK)
            return rc;
        for (f = 0; f < sp.nfield; f++) {
            const sg_spot_field *fl = &sp.field[f];
            int w;
            size_t nok = 0;
            for (w = 0; w < sp.nwave; w++)
                nok += sp.cell[f * sp.nwave + w].nok;
            if (fl->status != SG_OK || nok == 0 || !isfinite(fl->rms)) {
                rc = sg_diag_set(d, fl->status != SG_OK ? fl->status : SG_EMISS,
                                 "field %d: %s", sp.field_index[f] + 1,
                                 fl->status != SG_OK ? "the chief ray fails"
                                                     : "no ray reaches the image");
                sg_spot_free(&sp);
                return rc;
            }
            out->field[f] = fl->rms;
            wsum += sys->field[sp.field_index[f]].weight;
        }
        out->nfield = sp.nfield;
        if (!(wsum > 0.0))
            wsum = 1.0;
        for (f = 0; f < sp.nfield; f++) {
            double s = sqrt(sys->field[sp.field_index[f]].weight / wsum);
            if (share)
                share[f] = s;
            acc = hypot(acc, s * out->field[f]);
        }
        out->criterion = acc;
        sg_spot_free(&sp);
    }
    return SG_OK;
}

int sg_tol_criterion(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                     sg_tol_value *out, sg_diag *d)
{
    sg_tol_opts def;
    if (!o) {
        sg_tol_opts_init(&def);
        o = &def;
    }
    return field_values(sys, cat, o, o->nthreads, out, NULL, d);
}

typedef struct comp_ctx {
    const sg_catalog *cat;
    const sg_tol_opts *o;
} comp_ctx;

/* The residuals whose sum of squares is the criterion squared. */
static int comp_resid(void *ctx, const sg_system *sys, double *f, int nres, sg_diag *d)
{
    comp_ctx *c = ctx;
    sg_tol_value v;
    double share[SG_MAX_FIELDS];
    int k, rc;
    if ((rc = field_values(sys, c->cat, c->o, 1, &v, share, d)) != SG_OK)
        return rc;
    if (v.nfield == 0)
        f[0] = v.criterion;
    else
        for (k = 0; k < nres && k < v.nfield; k++)
            f[k] = share[k] * v.field[k];
    return SG_OK;
}

int sg_tol_compensate(sg_system *sys, const sg_system *nominal, const int *map,
                      const sg_catalog *cat, const sg_tol_opts *o, sg_tol_value *out,
                      sg_diag *d)
{
    const sg_tolerances *t = &nominal->tol;
    sg_paddr a[SG_MAX_COMPENSATORS];
    double lo[SG_MAX_COMPENSATORS], hi[SG_MAX_COMPENSATORS], v0[SG_MAX_COMPENSATORS];
    sg_opt_opts oo;
    sg_opt_result res;
    comp_ctx cc;
    sg_tol_opts def;
    int k, rc, nres;
    if (!o) {
        sg_tol_opts_init(&def);
        o = &def;
    }
    for (k = 0; k < t->ncomp; k++) {
        const sg_tol_comp *c = &t->comp[k];
        int s = map ? map[c->surface] : c->surface;
        double nv, off = 0.0;
        /* The thickness after an element's last surface is, in the
         * perturbed design, the return break's, T longer (its last surface
         * goes back T to the first vertex). */
        if (map && strcmp(c->param, "thickness") == 0 && c->surface + 1 < nominal->nsurf &&
            map[c->surface + 1] > s + 1 && sys->surf[s + 1].type == SG_SURF_COORDBRK &&
            sys->surf[s + 1].before.order == 1) {
            off = -sys->surf[s].thickness;
            s++;
        }
        if ((rc = sg_paddr_make(sys, SG_SCOPE_SURFACE, s, c->param, c->elem, &a[k], d)) != SG_OK)
            return rc;
        /* The range is about the nominal's value. */
        {
            sg_paddr an;
            if ((rc = sg_paddr_make(nominal, SG_SCOPE_SURFACE, c->surface, c->param, c->elem,
                                    &an, d)) != SG_OK)
                return rc;
            nv = sg_paddr_get(nominal, &an);
        }
        v0[k] = sg_paddr_get(sys, &a[k]);
        lo[k] = nv + off + c->min;
        hi[k] = nv + off + c->max;
        /* A perturbation may move the compensator's own value out. */
        if (v0[k] < lo[k] || v0[k] > hi[k])
            sg_paddr_set(sys, &a[k], v0[k] < lo[k] ? lo[k] : hi[k]);
    }
    if (t->ncomp > 0 && o->compensate) {
        sg_opt_opts_init(&oo);
        oo.cycles = o->cycles > 0 ? o->cycles : 50;
        oo.nthreads = 1;
        oo.stop = o->stop;
        cc.cat = cat;
        cc.o = o;
        nres = t->criterion == SG_TOLC_MERIT ? 1 : sys->nfield;
        if ((rc = sg_lsq_optimize(sys, cat, a, lo, hi, t->ncomp, nres, 1e-13, comp_resid, &cc,
                                  &oo, &res, d)) != SG_OK)
            return rc;
    }
    if ((rc = field_values(sys, cat, o, 1, out, NULL, d)) != SG_OK)
        return rc;
    for (k = 0; k < t->ncomp; k++)
        out->comp[k] = sg_paddr_get(sys, &a[k]) - v0[k];
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Draws and statistics
 * ------------------------------------------------------------------------ */

/* SplitMix64's finalizer (Steele, Lea and Flood 2014): a bijection that
 * mixes every bit, so a hash of a counter is a stream. */
static uint64_t mix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* The j-th uniform of (seed, trial, operand k), in (0, 1). */
static double uniform01(uint64_t seed, uint64_t trial, int k, uint32_t j)
{
    uint64_t x = mix64(mix64(mix64(seed) ^ trial) ^ (((uint64_t)(uint32_t)k << 32) | j));
    return ((double)(x >> 11) + 0.5) * 0x1p-53;
}

double sg_tol_draw(uint64_t seed, uint64_t trial, int k, int dist, double min, double max)
{
    double c = 0.5 * (min + max), h = 0.5 * (max - min), u;
    uint32_t j;
    switch (dist) {
    case SG_TOLD_UNIFORM:
        return min + (max - min) * uniform01(seed, trial, k, 0);
    case SG_TOLD_PARABOLIC:
        /* |x| = cbrt(u) has P(|x| <= s) = s^3: density 3 x^2 / 2 on [-1, 1]. */
        u = 2.0 * uniform01(seed, trial, k, 0) - 1.0;
        return c + h * cbrt(u);
    default:
        /* Box-Muller, drawn again outside +-2 sigma (min and max). */
        for (j = 0; j < 2000; j += 2) {
            double u1 = uniform01(seed, trial, k, j), u2 = uniform01(seed, trial, k, j + 1);
            double z = sqrt(-2.0 * log(u1)) * cos(6.283185307179586477 * u2);
            if (fabs(z) <= 2.0)
                return c + h * z / 2.0;
        }
        return c;
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

void sg_tol_statistics(const double *v, int n, sg_tol_stats *out)
{
    static const double ps[5] = {90, 80, 50, 20, 10};
    double *s = malloc((size_t)(n > 0 ? n : 1) * sizeof *s), sum = 0.0, ss = 0.0, mean;
    int i, m = 0;
    memset(out, 0, sizeof *out);
    if (!s)
        return;
    for (i = 0; i < n; i++)
        if (!isnan(v[i]))
            s[m++] = v[i];
    out->n = m;
    if (m == 0) {
        free(s);
        out->best = out->worst = out->mean = out->std = NAN;
        for (i = 0; i < 5; i++)
            out->pct[i] = NAN;
        return;
    }
    qsort(s, (size_t)m, sizeof *s, cmp_double);
    for (i = 0; i < m; i++)
        sum += s[i];
    mean = sum / m;
    for (i = 0; i < m; i++)
        ss += (s[i] - mean) * (s[i] - mean);
    out->mean = mean;
    out->std = m > 1 ? sqrt(ss / (m - 1)) : 0.0;
    out->best = s[0];
    out->worst = s[m - 1];
    for (i = 0; i < 5; i++) {
        long r = (long)ceil(ps[i] / 100.0 * m) - 1;
        out->pct[i] = s[r < 0 ? 0 : r >= m ? m - 1 : r];
    }
    free(s);
}

/* ------------------------------------------------------------------------
 * The runs
 * ------------------------------------------------------------------------ */

typedef struct run_ctx {
    const sg_system *nom;   /* compensated: where every perturbation starts */
    const sg_system *ref;   /* as given: the compensators' ranges are about it */
    const sg_catalog *cat;
    const sg_tol_opts *o;
    int nsensjob, ntrial, njob;
    int first;              /* the trial of the first Monte Carlo job */
    uint64_t seed;
    sg_tol_result *r;       /* mc[i] is trial first + i */
    unsigned char *finished;
    int next, ndone;
    pthread_mutex_t lock;
} run_ctx;

/* One system: job < nsensjob is row job / 2 at its min (even) or max,
 * else Monte Carlo trial job - nsensjob. */
static void run_job(run_ctx *c, int job, sg_system *work, int *map)
{
    const sg_tolerances *t = &c->nom->tol;
    double delta[SG_MAX_TOL_OPERANDS];
    sg_tol_value *v;
    sg_diag d;
    int k, rc;
    memset(delta, 0, sizeof delta);
    if (job < c->nsensjob) {
        const sg_tol_operand *op = &t->op[job / 2];
        delta[job / 2] = job % 2 ? op->max : op->min;
        v = job % 2 ? &c->r->sens[job / 2].at_max : &c->r->sens[job / 2].at_min;
    } else {
        uint64_t trial = (uint64_t)c->first + (uint64_t)(job - c->nsensjob);
        for (k = 0; k < t->nop; k++)
            delta[k] = sg_tol_draw(c->seed, trial, k, t->distribution, t->op[k].min,
                                   t->op[k].max);
        v = &c->r->mc[job - c->nsensjob];
    }
    sg_diag_clear(&d);
    rc = sg_tol_apply(c->nom, c->cat, delta, work, map, &d);
    if (rc == SG_OK)
        rc = sg_tol_compensate(work, c->ref, map, c->cat, c->o, v, &d);
    if (rc != SG_OK) {
        memset(v, 0, sizeof *v);
        v->criterion = NAN;
    }
    v->status = rc;
}

static void *worker(void *arg)
{
    run_ctx *c = arg;
    sg_system *work = sg_system_new();
    int *map = malloc((size_t)c->nom->nsurf * sizeof *map);
    for (;;) {
        int job, stop;
        pthread_mutex_lock(&c->lock);
        stop = (c->o->stop && *c->o->stop) || c->r->stopped || !work || !map;
        job = stop ? c->njob : c->next++;
        pthread_mutex_unlock(&c->lock);
        if (job >= c->njob)
            break;
        run_job(c, job, work, map);
        pthread_mutex_lock(&c->lock);
        /* A stop may have cut this system's compensation short: a system
         * that ends after it is not counted. */
        if (!((c->o->stop && *c->o->stop) || c->r->stopped)) {
            c->finished[job] = 1;
            c->ndone++;
        }
        if (c->o->progress && c->o->progress(c->o->ctx, c->ndone, c->njob))
            c->r->stopped = 1;
        pthread_mutex_unlock(&c->lock);
    }
    free(map);
    sg_system_free(work);
    return NULL;
}

/* A worker thread; MPFR caches constants per thread, freed at its end. */
static void *worker_thread(void *arg)
{
    worker(arg);
    mpfr_free_cache2(MPFR_FREE_LOCAL_CACHE);
    return NULL;
}

/* c's jobs on o->nthreads threads (the calling one among them). */
static void run_jobs(run_ctx *c)
{
    pthread_t th[256];
    int started[256];
    int nt, i;
    pthread_mutex_init(&c->lock, NULL);
    nt = c->o->nthreads > 0 ? c->o->nthreads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (nt < 1)
        nt = 1;
    if (nt > 256)
        nt = 256;
    if (nt > c->njob)
        nt = c->njob > 0 ? c->njob : 1;
    for (i = 1; i < nt; i++)
        started[i] = pthread_create(&th[i], NULL, worker_thread, c) == 0;
    worker(c);
    for (i = 1; i < nt; i++)
        if (started[i])
            pthread_join(th[i], NULL);
    pthread_mutex_destroy(&c->lock);
}

/* The nominal prepared and compensated (nom), and as given (ref). */
static int prepare_nominal(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                           sg_system **nom_out, sg_system **ref_out, sg_tol_value *nominal,
                           sg_diag *d)
{
    sg_system *nom, *ref = NULL;
    int rc;
    *nom_out = *ref_out = NULL;
    if (!sys->tol.present || sys->tol.nop == 0)
        return sg_diag_set(d, SG_ENOSYS, "the design has no tolerance operands (a "
                           "\"tolerances\" object; sagitta-design(5), TOLERANCES)");
    nom = sg_system_new();
    if (!nom)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    if ((rc = sg_tol_nominal(sys, cat, nom, d)) != SG_OK)
        goto fail;
    /* The nominal with its compensators at their best, so a change is the
     * operand's alone. */
    if (!(ref = sg_system_clone(nom))) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    if ((rc = sg_tol_compensate(nom, ref, NULL, cat, o, nominal, d)) != SG_OK) {
        char msg[SG_DIAG_MSG];
        snprintf(msg, sizeof msg, "%s", d ? d->msg : "");
        rc = sg_diag_set(d, rc, "the nominal design: %s", msg);
        goto fail;
    }
    *nom_out = nom;
    *ref_out = ref;
    return SG_OK;
fail:
    sg_system_free(nom);
    sg_system_free(ref);
    return rc;
}

struct sg_tol_mc {
    sg_system *nom, *ref;
    const sg_catalog *cat;
    sg_tol_opts o;
    uint64_t seed;
    double c0;              /* the compensated nominal's criterion */
};

int sg_tol_mc_open(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *o,
                   uint64_t seed, sg_tol_mc **out, sg_tol_value *nominal, sg_diag *d)
{
    sg_tol_mc *m;
    sg_tol_value nv;
    int rc;
    *out = NULL;
    if (!(m = calloc(1, sizeof *m)))
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    if (o)
        m->o = *o;
    else
        sg_tol_opts_init(&m->o);
    if ((rc = prepare_nominal(sys, cat, &m->o, &m->nom, &m->ref, &nv, d)) != SG_OK) {
        free(m);
        return rc;
    }
    m->cat = cat;
    m->seed = seed;
    m->c0 = nv.criterion;
    if (nominal)
        *nominal = nv;
    *out = m;
    return SG_OK;
}

int sg_tol_mc_run(sg_tol_mc *m, int first, int n, sg_tol_value *out, int *done)
{
    sg_tol_result r;
    run_ctx c;
    int k;
    *done = 0;
    if (n <= 0)
        return SG_OK;
    memset(&r, 0, sizeof r);
    r.mc = out;
    memset(&c, 0, sizeof c);
    c.nom = m->nom;
    c.ref = m->ref;
    c.cat = m->cat;
    c.o = &m->o;
    c.ntrial = c.njob = n;
    c.first = first;
    c.seed = m->seed;
    c.r = &r;
    if (!(c.finished = calloc((size_t)n, 1)))
        return SG_ENOMEM;
    run_jobs(&c);
    for (k = 0; k < n && c.finished[k]; k++)
        ;
    *done = k;
    free(c.finished);
    return SG_OK;
}

int sg_tol_mc_system(sg_tol_mc *m, int trial, sg_system *out, sg_tol_value *v, sg_diag *d)
{
    const sg_tolerances *t = &m->nom->tol;
    double delta[SG_MAX_TOL_OPERANDS];
    int *map = malloc((size_t)m->nom->nsurf * sizeof *map), k, rc;
    if (!map)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    memset(delta, 0, sizeof delta);
    /* As run_job draws and builds trial's system. */
    for (k = 0; k < t->nop; k++)
        delta[k] = sg_tol_draw(m->seed, (uint64_t)trial, k, t->distribution, t->op[k].min,
                               t->op[k].max);
    rc = sg_tol_apply(m->nom, m->cat, delta, out, map, d);
    if (rc == SG_OK)
        rc = sg_tol_compensate(out, m->ref, map, m->cat, &m->o, v, d);
    free(map);
    return rc;
}

/* The change of the compensated criterion from the nominal's with
 * operand k alone at x. */
static int inv_change(sg_tol_mc *m, sg_system *work, int *map, int k, double x, double c0,
                      double *change, sg_tol_value *v)
{
    double delta[SG_MAX_TOL_OPERANDS];
    sg_diag d;
    int rc;
    memset(delta, 0, sizeof delta);
    delta[k] = x;
    sg_diag_clear(&d);
    rc = sg_tol_apply(m->nom, m->cat, delta, work, map, &d);
    if (rc == SG_OK)
        rc = sg_tol_compensate(work, m->ref, map, m->cat, &m->o, v, &d);
    if (rc == SG_OK && isnan(v->criterion))
        rc = SG_ERANGE;
    *change = rc == SG_OK ? v->criterion - c0 : NAN;
    return rc;
}

/* One side of operand k: from 0 (change 0) outward along dir, the
 * bracket [a, b] with change(a) < limit <= change(b) found by doubling
 * (or halving) from x0, then the Illinois method (regula falsi with the
 * stuck end's value halved) to a relative width of 1e-12. */
static void inv_side(sg_tol_mc *m, sg_system *work, int *map, int k, double x0, double c0,
                     double limit, sg_tol_inv_side *out)
{
    double a = 0.0, fa = -limit, b = x0, fb, x, fx;
    sg_tol_value v;
    int it, side = 0, rc;
    memset(out, 0, sizeof *out);
    out->limit = NAN;
    out->criterion = NAN;
    if ((rc = inv_change(m, work, map, k, b, c0, &fb, &v)) != SG_OK) {
        out->status = rc;
        return;
    }
    fb -= limit;
    /* Out until the change reaches the limit, in until it does not. */
    for (it = 0; fb < 0 && it < 40; it++) {
        a = b;
        fa = fb;
        b *= 2.0;
        if ((rc = inv_change(m, work, map, k, b, c0, &fb, &v)) != SG_OK) {
            out->status = rc;
            return;
        }
        fb -= limit;
    }
    if (fb < 0) {
        out->status = SG_ERANGE;
        return;
    }
    for (it = 0; a == 0.0 && it < 60; it++) {
        x = 0.5 * b;
        if ((rc = inv_change(m, work, map, k, x, c0, &fx, &v)) != SG_OK) {
            out->status = rc;
            return;
        }
        fx -= limit;
        if (fx >= 0) {
            b = x;
            fb = fx;
        } else {
            a = x;
            fa = fx;
        }
    }
    for (it = 0; it < 200 && fabs(b - a) > 1e-12 * fabs(b); it++) {
        x = (a * fb - b * fa) / (fb - fa);
        if (!(x > fmin(a, b) && x < fmax(a, b)))
            x = 0.5 * (a + b);
        if ((rc = inv_change(m, work, map, k, x, c0, &fx, &v)) != SG_OK) {
            out->status = rc;
            return;
        }
        fx -= limit;
        if (fx == 0) {
            a = b = x;
            fb = 0;
            break;
        }
        if (fx > 0) {
            b = x;
            fb = fx;
            if (side == 1)
                fa *= 0.5;
            side = 1;
        } else {
            a = x;
            fa = fx;
            if (side == -1)
                fb *= 0.5;
            side = -1;
        }
    }
    /* The end where the change has reached the limit. */
    out->limit = b;
    if ((rc = inv_change(m, work, map, k, b, c0, &fx, &v)) != SG_OK) {
        out->status = rc;
        return;
    }
    out->criterion = v.criterion;
    out->status = SG_OK;
}

int sg_tol_inverse(sg_tol_mc *m, double limit, sg_tol_inv *out, int *done, sg_diag *d)
{
    const sg_tolerances *t = &m->nom->tol;
    sg_system *work = sg_system_new();
    int *map = malloc((size_t)m->nom->nsurf * sizeof *map), k;
    *done = 0;
    if (!work || !map) {
        sg_system_free(work);
        free(map);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    if (!(limit > 0) || !isfinite(limit)) {
        sg_system_free(work);
        free(map);
        return sg_diag_set(d, SG_ERANGE, "the inverse limit %g is not a positive number",
                           limit);
    }
    for (k = 0; k < t->nop; k++) {
        const sg_tol_operand *op = &t->op[k];
        double span = fmax(fabs(op->min), fabs(op->max));
        /* Each side starts at the operand's own limit on it (or the other
         * side's size when that is 0). */
        double hi = op->max > 0 ? op->max : span, lo = op->min < 0 ? op->min : -span;
        if (m->o.stop && *m->o.stop)
            break;
        if (span == 0) {
            memset(&out[k], 0, sizeof out[k]);
            out[k].at_min.status = out[k].at_max.status = SG_ERANGE;
            out[k].at_min.limit = out[k].at_max.limit = NAN;
            out[k].at_min.criterion = out[k].at_max.criterion = NAN;
            continue;
        }
        inv_side(m, work, map, k, lo, m->c0, limit, &out[k].at_min);
        inv_side(m, work, map, k, hi, m->c0, limit, &out[k].at_max);
    }
    sg_system_free(work);
    free(map);
    *done = k;
    return SG_OK;
}

void sg_tol_mc_close(sg_tol_mc *m)
{
    if (!m)
        return;
    sg_system_free(m->nom);
    sg_system_free(m->ref);
    free(m);
}

int sg_tolerance_run(const sg_system *sys, const sg_catalog *cat, const sg_tol_opts *opts,
                     int sens, int trials, uint64_t seed, sg_tol_result *out, sg_diag *d)
{
    sg_tol_opts def;
    sg_system *nom = NULL, *ref = NULL;
    run_ctx c;
    int k, rc;
    memset(out, 0, sizeof *out);
    if (!opts) {
        sg_tol_opts_init(&def);
        opts = &def;
    }
    if (trials < 0)
        return sg_diag_set(d, SG_ERANGE, "%d Monte Carlo trials", trials);
    if ((rc = prepare_nominal(sys, cat, opts, &nom, &ref, &out->nominal, d)) != SG_OK)
        return rc;
    out->trials = trials;
    out->seed = seed;
    out->sens = sens ? calloc((size_t)sys->tol.nop, sizeof *out->sens) : NULL;
    out->mc = trials ? calloc((size_t)trials, sizeof *out->mc) : NULL;
    memset(&c, 0, sizeof c);
    c.nom = nom;
    c.ref = ref;
    c.cat = cat;
    c.o = opts;
    c.nsensjob = sens ? 2 * sys->tol.nop : 0;
    c.ntrial = trials;
    c.njob = c.nsensjob + trials;
    c.seed = seed;
    c.r = out;
    c.finished = calloc((size_t)(c.njob > 0 ? c.njob : 1), 1);
    if ((sens && !out->sens) || (trials && !out->mc) || !c.finished) {
        free(c.finished);
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto fail;
    }
    run_jobs(&c);
    if (opts->stop && *opts->stop)
        out->stopped = 1;
    /* What is done is what a run stopped there keeps: the rows, and the
     * trials, from the first on without a gap. */
    for (k = 0; k < c.nsensjob / 2 && c.finished[2 * k] && c.finished[2 * k + 1]; k++)
        out->sens[k].row = k + 1;
    out->nsens = k;
    for (k = 0; k < trials && c.finished[c.nsensjob + k]; k++)
        ;
    out->done = k;
    free(c.finished);
    out->rss = 0.0;
    for (k = 0; k < out->nsens; k++) {
        const sg_tol_sens *s = &out->sens[k];
        double a = s->at_min.status == SG_OK ? fabs(s->at_min.criterion - out->nominal.criterion)
                                             : 0.0;
        double b = s->at_max.status == SG_OK ? fabs(s->at_max.criterion - out->nominal.criterion)
                                             : 0.0;
        out->rss = hypot(out->rss, fmax(a, b));
    }
    if (out->done > 0) {
        double *v = malloc((size_t)out->done * sizeof *v);
        if (v) {
            for (k = 0; k < out->done; k++)
                v[k] = out->mc[k].status == SG_OK ? out->mc[k].criterion : NAN;
            sg_tol_statistics(v, out->done, &out->stats);
            free(v);
        }
    }
    sg_system_free(nom);
    sg_system_free(ref);
    return SG_OK;
fail:
    sg_system_free(nom);
    sg_system_free(ref);
    sg_tol_result_free(out);
    return rc;
}

void sg_tol_result_free(sg_tol_result *r)
{
    if (!r)
        return;
    free(r->sens);
    free(r->mc);
    r->sens = NULL;
    r->mc = NULL;
}

/* ------------------------------------------------------------------------
 * The default tolerance set (Zemax's Tolerance Wizard)
 * ------------------------------------------------------------------------ */

void sg_tol_defaults_init(sg_tol_defaults *o)
{
    memset(o, 0, sizeof *o);
    o->fringes = 1.0;
    o->thickness = 0.2;
    o->sdecenter = 0.2;
    o->stilt_tir = 0.2;
    o->irregularity = 0.2;
    o->edecenter = 0.2;
    o->etilt = 0.2;
    o->index = 0.001;
    o->abbe_pct = 1.0;
    o->focus = 1;
}

/* The medium after surface i is air (or a fixed index of 1). */
static int air_after(const sg_system *sys, int i)
{
    const sg_material *m = &sys->surf[i].mat;
    return m->kind == SG_MAT_AIR || (m->kind == SG_MAT_INDEX && m->index == 1.0);
}

/* The same medium on both sides of surface i: a dummy surface, no power. */
static int same_medium(const sg_system *sys, int i)
{
    const sg_material *a = &sys->surf[i - 1].mat, *b = &sys->surf[i].mat;
    if (b->kind == SG_MAT_MIRROR)
        return 0;
    if (air_after(sys, i - 1) && air_after(sys, i))
        return 1;
    if (a->kind != b->kind)
        return 0;
    if (a->kind == SG_MAT_GLASS)
        return strcmp(a->name, b->name) == 0 && strcmp(a->catalog, b->catalog) == 0;
    return a->index == b->index && a->vd == b->vd;
}

static int add_op(sg_tolerances *t, int *n, sg_tol_type type, int first, int last, int adjust,
                  double lim)
{
    sg_tol_operand *op;
    if (*n >= SG_MAX_TOL_OPERANDS) {
        (*n)++;
        return 0;
    }
    op = &t->op[(*n)++];
    memset(op, 0, sizeof *op);
    op->type = type;
    op->surface = first;
    op->last = last;
    op->adjust = adjust;
    op->min = -lim;
    op->max = lim;
    return 1;
}

int sg_tol_default_set(sg_system *sys, const sg_catalog *cat, const sg_tol_defaults *o,
                       sg_diag *d)
{
    sg_tolerances *t;
    double *sd = NULL;
    int img = sys->nsurf - 1, i, j, n = 0, rc = SG_OK, focus;
    if (!(t = malloc(sizeof *t)))
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    *t = sys->tol;
    if (!t->present) {
        /* The settings a "tolerances" object without them has. */
        memset(t, 0, sizeof *t);
        t->present = 1;
        t->pattern = SG_PUPIL_HEXAPOLAR;
        t->density = 6;
        t->grid = 64;
        t->seed = 1.0;
    }
    t->nop = 0;
    if (img < 2) {
        free(t);
        return sg_diag_set(d, SG_ERANGE, "tolerances: no surface between the object and the "
                           "image to tolerance");
    }
    /* The thickness before the image focuses (Zemax's paraxial focus
     * compensator), so it takes no thickness tolerance of its own. */
    focus = o->focus && isfinite(sys->surf[img - 1].thickness) ? img - 1 : -1;
    for (i = 1; i < img; i++)
        if (o->stilt_tir > 0 && !(sys->surf[i].semi_diameter > 0.0))
            break;
    if (i < img) {
        if (!(sd = malloc((size_t)sys->nsurf * sizeof *sd))) {
            free(t);
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        }
        if ((rc = sg_semi_diameters(sys, cat, NULL, sd, d)) != SG_OK)
            goto out;
    }
    /* Radii: fringes of power, or lens units on a curved surface. */
    for (i = 1; i < img; i++) {
        const sg_surface *s = &sys->surf[i];
        if (s->type == SG_SURF_COORDBRK || same_medium(sys, i))
            continue;
        if (o->radius > 0 && isfinite(s->radius) && s->radius != 0.0)
            add_op(t, &n, SG_TOL_TRAD, i, i, -1, o->radius);
        else if (o->fringes > 0)
            add_op(t, &n, SG_TOL_TFRN, i, i, -1, o->fringes);
    }
    /* Thicknesses, the first air space after each taking the change
     * (Zemax's TTHI adjust), so the surfaces beyond stay put. */
    for (i = 1; o->thickness > 0 && i < img; i++) {
        int adj = -1;
        if (i == focus || sys->surf[i].type == SG_SURF_COORDBRK ||
            !isfinite(sys->surf[i].thickness))
            continue;
        for (j = i + 1; j < img; j++)
            if (air_after(sys, j) && sys->surf[j].type != SG_SURF_COORDBRK &&
                isfinite(sys->surf[j].thickness)) {
                adj = j;
                break;
            }
        add_op(t, &n, SG_TOL_TTHI, i, i, adj, o->thickness);
    }
    /* Elements: from a surface with glass after it to the next with air
     * after it (a cemented group is one element). */
    for (i = 1; i < img; i++) {
        int bad;
        if (air_after(sys, i) || sys->surf[i].mat.kind == SG_MAT_MIRROR ||
            sys->surf[i].type == SG_SURF_COORDBRK)
            continue;
        for (j = i; j < img && !air_after(sys, j); j++)
            ;
        if (j < img && element_ok(sys, i, j, &bad)) {
            if (o->edecenter > 0) {
                add_op(t, &n, SG_TOL_TEDX, i, j, -1, o->edecenter);
                add_op(t, &n, SG_TOL_TEDY, i, j, -1, o->edecenter);
            }
            if (o->etilt > 0) {
                add_op(t, &n, SG_TOL_TETX, i, j, -1, o->etilt);
                add_op(t, &n, SG_TOL_TETY, i, j, -1, o->etilt);
            }
        }
        i = j;
    }
    /* Each surface's own decenter and tilt (a runout T across the
     * diameter D is a tilt of atan(T / D)); from surface 2, as rays
     * start in surface 1's frame. */
    for (i = 2; i < img; i++) {
        const sg_surface *s = &sys->surf[i];
        double r = s->semi_diameter > 0.0 ? s->semi_diameter : sd ? sd[i] : 0.0;
        if (s->type == SG_SURF_COORDBRK || same_medium(sys, i) ||
            sg_surface_moves_frame(s))
            continue;
        if (o->sdecenter > 0) {
            add_op(t, &n, SG_TOL_TSDX, i, i, -1, o->sdecenter);
            add_op(t, &n, SG_TOL_TSDY, i, i, -1, o->sdecenter);
        }
        if (o->stilt_tir > 0 && r > 0.0) {
            double deg = atan(o->stilt_tir / (2.0 * r)) * (180.0 / 3.14159265358979323846);
            add_op(t, &n, SG_TOL_TSTX, i, i, -1, deg);
            add_op(t, &n, SG_TOL_TSTY, i, i, -1, deg);
        }
    }
    /* Irregularity: TIRR, on the standard surfaces Zemax's takes. */
    for (i = 1; o->irregularity > 0 && i < img; i++)
        if (sys->surf[i].type == SG_SURF_STANDARD && !same_medium(sys, i))
            add_op(t, &n, SG_TOL_TIRR, i, i, -1, o->irregularity);
    /* Glasses: the index, and the Abbe number by a percentage of its own. */
    for (i = 1; i < img; i++) {
        const sg_material *m = &sys->surf[i].mat;
        double vd = 0.0;
        if (m->kind == SG_MAT_MODEL)
            vd = m->vd;
        else if (m->kind == SG_MAT_GLASS) {
            const sg_glass *g = cat ? sg_material_glass(cat, m) : NULL;
            vd = g ? g->vd : 0.0;
        } else if (m->kind != SG_MAT_INDEX || m->index == 1.0)
            continue; /* air and mirrors; a fixed index takes TIND alone */
        if (o->index > 0)
            add_op(t, &n, SG_TOL_TIND, i, i, -1, o->index);
        if (o->abbe_pct > 0 && vd > 0)
            add_op(t, &n, SG_TOL_TABB, i, i, -1, o->abbe_pct / 100.0 * vd);
    }
    if (n > SG_MAX_TOL_OPERANDS) {
        rc = sg_diag_set(d, SG_ERANGE, "tolerances: the default set has %d rows, more than "
                         "the %d a design holds; leave some kinds out", n,
                         SG_MAX_TOL_OPERANDS);
        goto out;
    }
    t->nop = n;
    if (t->ncomp == 0 && focus >= 0) {
        /* Wide enough to refocus: the larger of 1 lens unit and half the
         * back focus. */
        double w = fmax(1.0, 0.5 * fabs(sys->surf[focus].thickness));
        memset(&t->comp[0], 0, sizeof t->comp[0]);
        t->comp[0].surface = focus;
        snprintf(t->comp[0].param, sizeof t->comp[0].param, "thickness");
        t->comp[0].min = -w;
        t->comp[0].max = w;
        t->ncomp = 1;
    }
    sys->tol = *t;
out:
    free(sd);
    free(t);
    return rc;
}
