/*
 * aperture.c - whether a ray meeting a surface at (x, y) in its local frame
 * goes on: the fixed clear semi-diameter and the surface aperture or
 * obscuration (sagitta-design(5), APERTURES).  The precise, classic and
 * mpfr methods all ask this one function, with the rounded point.
 */
#include <math.h>
#include <stdio.h>

#include "trace_int.h"

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

/* 0 where the ray passes, else what stops it: SG_EVIGNETTED (the fixed
 * semi-diameter), SG_EAPERTURE or SG_EOBSCURED. */
int sg_clip_point(const sg_sprep *s, double x, double y, double rtol)
{
    double u, v, q, r, grow = 1.0 + rtol, shrink = 1.0 - rtol;
    if (s->sd > 0.0 && beyond(x, y, s->sd * grow))
        return SG_EVIGNETTED;
    if (s->aper == SG_APERTURE_NONE)
        return 0;
    /* The tolerance favours the ray: an aperture grows by it, an
     * obscuration shrinks by it. */
    u = x - s->ap_dx;
    v = y - s->ap_dy;
    switch (s->aper) {
    case SG_APERTURE_CIRCULAR:
        r = hypot(u, v);
        return r > s->ap_b * grow || r < s->ap_a * shrink ? SG_EAPERTURE : 0;
    case SG_OBSCURATION_CIRCULAR:
        r = hypot(u, v);
        return r <= s->ap_b * shrink && r >= s->ap_a * grow ? SG_EOBSCURED : 0;
    case SG_APERTURE_RECTANGULAR:
        return fabs(u) > s->ap_a * grow || fabs(v) > s->ap_b * grow ? SG_EAPERTURE : 0;
    case SG_OBSCURATION_RECTANGULAR:
        return fabs(u) < s->ap_a * shrink && fabs(v) < s->ap_b * shrink ? SG_EOBSCURED : 0;
    case SG_APERTURE_ELLIPTICAL:
        q = (u / s->ap_a) * (u / s->ap_a) + (v / s->ap_b) * (v / s->ap_b);
        return q > grow * grow ? SG_EAPERTURE : 0;
    case SG_OBSCURATION_ELLIPTICAL:
        q = (u / s->ap_a) * (u / s->ap_a) + (v / s->ap_b) * (v / s->ap_b);
        return q < shrink * shrink ? SG_EOBSCURED : 0;
    default:
        return 0;
    }
}

char *sg_ray_stop_text(const sg_system *sys, int surf, int status, char *buf, size_t len)
{
    static const char *const kind[] = {"aperture", "circular aperture", "circular obscuration",
                                       "rectangular aperture", "rectangular obscuration",
                                       "elliptical aperture", "elliptical obscuration"};
    const sg_surface *s = sys && surf >= 0 && surf < sys->nsurf ? &sys->surf[surf] : NULL;
    int a = s ? (int)s->aperture : 0;
    if (!buf || !len)
        return buf;
    if (a < 0 || a >= (int)(sizeof kind / sizeof kind[0]))
        a = 0;
    if (s && status == SG_EVIGNETTED && s->sd_fixed)
        snprintf(buf, len, "ray outside the clear semi-diameter %.17g of surface %d",
                 s->semi_diameter, surf);
    else if (s && status == SG_EAPERTURE)
        snprintf(buf, len, "ray outside the %s of surface %d", kind[a], surf);
    else if (s && status == SG_EOBSCURED)
        snprintf(buf, len, "ray stopped by the %s of surface %d", a ? kind[a] : "obscuration",
                 surf);
    else if (s)
        snprintf(buf, len, "%s at surface %d", sg_strerror(status), surf);
    else
        snprintf(buf, len, "%s", sg_strerror(status));
    return buf;
}
