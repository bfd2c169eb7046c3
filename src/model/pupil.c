/*
 * pupil.c - pupil sampling patterns (hexapolar, square, Vogel) made block by
 * block, and the normalized coordinates of a design's fields.
 */
#include <math.h>
#include <string.h>
#include <strings.h>

#include "sagitta.h"

#define PI_ 3.14159265358979323846

static const char *const pattern_names[] = {"hexapolar", "square", "vogel"};

const char *sg_pupil_pattern_name(int pattern)
{
    return pattern >= 0 && pattern < 3 ? pattern_names[pattern] : "?";
}

int sg_pupil_pattern_parse(const char *s)
{
    int k;
    for (k = 0; s && k < 3; k++)
        if (strcasecmp(s, pattern_names[k]) == 0)
            return k;
    return -1;
}

/* Rings beyond this would give more rays than SG_PUPIL_MAX_DENSITY. */
#define MAX_RINGS 5773

int sg_pupil_check(int pattern, int density, sg_diag *d)
{
    int hi = pattern == SG_PUPIL_HEXAPOLAR ? MAX_RINGS
             : pattern == SG_PUPIL_SQUARE  ? 11284 /* N^2 pi/4 rays at most the limit */
                                           : SG_PUPIL_MAX_DENSITY;
    if (pattern < 0 || pattern > 2)
        return sg_diag_set(d, SG_EINVAL, "pupil: unknown sampling pattern %d", pattern);
    if (density < 1 || density > hi)
        return sg_diag_set(d, SG_ERANGE, "pupil: %s density %d is not one of 1 to %d",
                           pattern_names[pattern], density, hi);
    return SG_OK;
}

/* Whether grid cell j of n lies in the unit circle; exact in integers:
 * (2j+1-n)^2 + (2i+1-n)^2 <= n^2 is Px^2 + Py^2 <= 1 without rounding. */
static int square_in(long long i, long long j, long long n)
{
    long long a = 2 * i + 1 - n, b = 2 * j + 1 - n;
    return a * a + b * b <= n * n;
}

size_t sg_pupil_count(int pattern, int density)
{
    long long n = density, i, j, c = 0;
    if (sg_pupil_check(pattern, density, NULL) != SG_OK)
        return 0;
    switch (pattern) {
    case SG_PUPIL_HEXAPOLAR:
        return (size_t)(1 + 3 * n * (n + 1));
    case SG_PUPIL_SQUARE:
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++)
                c += square_in(i, j, n);
        return (size_t)c;
    default:
        return (size_t)n;
    }
}

size_t sg_pupil_fill(int pattern, int density, size_t *cursor, double (*p)[2], size_t cap)
{
    size_t k = 0, c = *cursor;
    long long n = density;
    if (sg_pupil_check(pattern, density, NULL) != SG_OK)
        return 0;
    if (pattern == SG_PUPIL_HEXAPOLAR) {
        size_t total = (size_t)(1 + 3 * n * (n + 1));
        for (; k < cap && c < total; c++, k++) {
            /* Ray c lies in ring i where 1 + 3i(i-1) <= c < 1 + 3i(i+1). */
            long long i, j;
            double r, a;
            if (c == 0) {
                p[k][0] = p[k][1] = 0.0;
                continue;
            }
            i = (long long)floor((3.0 + sqrt(9.0 + 12.0 * (double)(c - 1))) / 6.0);
            while (1 + 3 * i * (i - 1) > (long long)c)
                i--;
            while (1 + 3 * i * (i + 1) <= (long long)c)
                i++;
            j = (long long)c - (1 + 3 * i * (i - 1));
            r = (double)i / (double)n;
            a = 2.0 * PI_ * (double)j / (double)(6 * i);
            p[k][0] = r * cos(a);
            p[k][1] = r * sin(a);
        }
    } else if (pattern == SG_PUPIL_SQUARE) {
        size_t total = (size_t)(n * n);
        for (; k < cap && c < total; c++) {
            long long i = (long long)c / n, j = (long long)c % n;
            if (!square_in(i, j, n))
                continue;
            p[k][0] = -1.0 + (double)(2 * j + 1) / (double)n;
            p[k][1] = -1.0 + (double)(2 * i + 1) / (double)n;
            k++;
        }
    } else {
        double golden = PI_ * (3.0 - sqrt(5.0));
        for (; k < cap && c < (size_t)n; c++, k++) {
            double r = sqrt(((double)c + 0.5) / (double)n), a = golden * (double)c;
            p[k][0] = r * cos(a);
            p[k][1] = r * sin(a);
        }
    }
    *cursor = c;
    return k;
}

int sg_field_normalized(const sg_system *sys, int k, double *hx, double *hy)
{
    double fx = 0.0, fy = 0.0;
    int i;
    if (!sys || k < 0 || k >= sys->nfield)
        return SG_EINVAL;
    for (i = 0; i < sys->nfield; i++) {
        if (sys->field_norm == SG_NORM_RADIAL) {
            double r = hypot(sys->field[i].x, sys->field[i].y);
            if (r > fx)
                fx = fy = r;
        } else {
            if (fabs(sys->field[i].x) > fx)
                fx = fabs(sys->field[i].x);
            if (fabs(sys->field[i].y) > fy)
                fy = fabs(sys->field[i].y);
        }
    }
    *hx = fx > 0.0 ? sys->field[k].x / fx : 0.0;
    *hy = fy > 0.0 ? sys->field[k].y / fy : 0.0;
    return SG_OK;
}

void sg_field_vignette(const sg_system *sys, double hx, double hy, double px, double py,
                       double *vpx, double *vpy)
{
    int k;
    *vpx = px;
    *vpy = py;
    for (k = 0; k < sys->nfield; k++) {
        const sg_field *f = &sys->field[k];
        double fx, fy, a, b, c, s;
        if (f->vdx == 0.0 && f->vdy == 0.0 && f->vcx == 0.0 && f->vcy == 0.0 && f->van == 0.0)
            continue;
        if (sg_field_normalized(sys, k, &fx, &fy) != SG_OK || fx != hx || fy != hy)
            continue;
        a = px * (1.0 - f->vcx);
        b = py * (1.0 - f->vcy);
        if (f->van == 0.0) {
            *vpx = f->vdx + a;
            *vpy = f->vdy + b;
        } else {
            /* Degrees reduced first, so that 90 and 180 turn exactly. */
            double r = fmod(f->van, 360.0) * (3.14159265358979323846 / 180.0);
            c = cos(r);
            s = sin(r);
            if (fmod(f->van, 90.0) == 0.0) {
                int q = ((int)(fmod(f->van, 360.0) / 90.0) + 4) % 4;
                c = q == 0 ? 1.0 : q == 2 ? -1.0 : 0.0;
                s = q == 1 ? 1.0 : q == 3 ? -1.0 : 0.0;
            }
            *vpx = f->vdx + (a * c - b * s);
            *vpy = f->vdy + (a * s + b * c);
        }
        return;
    }
}
