/*
 * aperture.c - whether a ray meeting a surface at (x, y) in its local frame
 * goes on: the fixed clear semi-diameter and the surface aperture or
 * obscuration (sagitta-design(5), APERTURES).  The precise, classic and
 * mpfr methods all ask this one function, with the rounded point.
 */
#include <math.h>

#include "trace_internal.h"

/* Beyond radius lim: x^2 + y^2 against lim^2 (a few roundings, far below
 * 1e-12) settles every point but those within 1e-12 of the edge, and
 * overflow, NaN and underflow fail both tests; those ask hypot, whose
 * answer this is. */
static int beyond(double x, double y, double lim)
{
    double r2 = x * x + y * y, l2 = lim * lim;
    if (r2 < l2 * (1.0 - 1e-12))
        return 0;
    if (r2 > l2 * (1.0 + 1e-12) && isfinite(l2))
        return 1;
    return hypot(x, y) > lim;
}

int sg_clip_point(const sg_sprep *s, double x, double y, double rtol)
{
    double u, v, q, r, grow = 1.0 + rtol, shrink = 1.0 - rtol;
    if (s->sd > 0.0 && beyond(x, y, s->sd * grow))
        return 1;
    if (s->aper == SG_APERTURE_NONE)
        return 0;
    /* The tolerance favours the ray: an aperture grows by it, an
     * obscuration shrinks by it. */
    u = x - s->ap_dx;
    v = y - s->ap_dy;
    switch (s->aper) {
    case SG_APERTURE_CIRCULAR:
        r = hypot(u, v);
        return r > s->ap_b * grow || r < s->ap_a * shrink;
    case SG_OBSCURATION_CIRCULAR:
        r = hypot(u, v);
        return r <= s->ap_b * shrink && r >= s->ap_a * grow;
    case SG_APERTURE_RECTANGULAR:
        return fabs(u) > s->ap_a * grow || fabs(v) > s->ap_b * grow;
    case SG_OBSCURATION_RECTANGULAR:
        return fabs(u) < s->ap_a * shrink && fabs(v) < s->ap_b * shrink;
    case SG_APERTURE_ELLIPTICAL:
        q = (u / s->ap_a) * (u / s->ap_a) + (v / s->ap_b) * (v / s->ap_b);
        return q > grow * grow;
    case SG_OBSCURATION_ELLIPTICAL:
        q = (u / s->ap_a) * (u / s->ap_a) + (v / s->ap_b) * (v / s->ap_b);
        return q < shrink * shrink;
    default:
        return 0;
    }
}
