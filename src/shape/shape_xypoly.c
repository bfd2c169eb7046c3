/*
 * shape_xypoly.c - Zemax's XY polynomial: a conic plus sum A_j x^m y^n
 * over the terms x, y, x^2, xy, y^2, x^3, ... with x and y divided by
 * the normalization radius (sagitta-design(5), SURFACE TYPES).  The
 * freeform of off-axis reflective systems.
 */
#include <math.h>

#include "shape.h"

/* Term j is the coefficient of index j: order n's terms x^n, x^(n-1) y,
 * ..., y^n follow those of order n - 1, as SG_P2_AT counts them. */
static int xy_prepare(const sg_surface *f, sg_shape *s, int isurf, sg_diag *d)
{
    int k, rc = sg_p2_terms(f, s, isurf, d);
    if (rc != SG_OK)
        return rc;
    for (k = 0; k < s->nz; k++)
        if (f->terms[k] != 0.0)
            sg_p2_add(s, k + 1, dd_from(f->terms[k]), fabs(f->terms[k]));
    return SG_OK;
}

static void xy_mp_coefs(const sg_shape *s, mpfr_t *mc)
{
    int k;
    for (k = 0; k < s->nz; k++)
        mpfr_set_d(mc[k + 1], s->src->terms[k], MPFR_RNDN);
}

const sg_shape_ops sg_shape_xypoly_ops = {"XY polynomial", xy_prepare, xy_mp_coefs, sg_rot_p2_d,
                                          sg_rot_p2_dd, sg_rot_p2_mp};

/* The terms are in lens units over coordinates divided by the
 * normalization radius, which grows with the part.  In .zmx: no PARM;
 * XDAT 1 the number of terms (x, y, x^2, ... : at most 65), 2 the
 * normalization radius, 3 on the terms. */
static const sg_shape_key xy_keys[] = {{"norm_radius", 0, 1, 0}, {"terms", 0, 1, 0}, {NULL, 0, 0, 0}};
static const sg_zmx_map xy_zmx[] = {{0, 0, NULL, 0, 0, 0}};
const sg_shape_type sg_shape_xypoly_type = {
    .type = SG_SURF_XYPOLY, .name = "XY polynomial", .ops = &sg_shape_xypoly_ops, .keys = xy_keys,
    .parm_lo = 1, .parm_hi = 0, .parm_what = "an XY polynomial has no parameters", .zmx = xy_zmx,
    .zmx_terms = SG_NTERMS - 1};
