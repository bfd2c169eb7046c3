/*
 * lean.c - a lean double trace for bench: the baseline precise is
 * measured against (issue 35, section 4), not a method users get.
 *
 * The textbook trace in double on LEAN_VL rays at once: planes, conics and
 * even aspheres on their vertex planes, refraction and reflection, no
 * frame changes, apertures, error bounds or residuals.  Each surface's
 * row (x, y, z, l, m, n, path, opl and three unused doubles: 88 bytes, as
 * a precise row's numbers) is written for every ray, so memory traffic is
 * a real trace's.  The lane loops are plain C that the compiler
 * vectorizes, once per instruction set (target_clones).
 */
#include "lean.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LEAN_VL 8
/* Newton steps on an even asphere from the conic's point: far more than
 * a smooth surface needs to reach double rounding. */
#define LEAN_NEWTON 4

typedef struct lean_surf {
    double c, k1;            /* curvature, 1 + conic */
    double a[SG_NASPH];      /* r^2 ... r^16 */
    int nasph;               /* terms in use */
    double t;                /* thickness before this surface's vertex */
    double mu;               /* |n before| / |n after| */
    double n;                /* |n before|, for the optical path */
    int mirror;
} lean_surf;

struct lean {
    int n;
    lean_surf *s;
};

lean *lean_new(const sg_system *sys, const sg_tracer *t)
{
    lean *L;
    int i, k, n = sys->nsurf;
    for (i = 1; i < n; i++) {
        const sg_surface *s = &sys->surf[i];
        const sg_frame_change *fc[2] = {&s->before, &s->after};
        if (s->type != SG_SURF_STANDARD && s->type != SG_SURF_EVENASPH)
            return NULL;
        for (k = 0; k < 2; k++)
            if (fc[k]->dx != 0.0 || fc[k]->dy != 0.0 || fc[k]->tx != 0.0 ||
                fc[k]->ty != 0.0 || fc[k]->tz != 0.0)
                return NULL;
    }
    L = calloc(1, sizeof *L);
    if (!L || !(L->s = calloc((size_t)n, sizeof *L->s))) {
        free(L);
        return NULL;
    }
    L->n = n;
    for (i = 1; i < n; i++) {
        const sg_surface *s = &sys->surf[i];
        lean_surf *e = &L->s[i];
        double n0 = fabs(sg_tracer_index(t, i - 1)), n1 = fabs(sg_tracer_index(t, i));
        e->c = isfinite(s->radius) && s->radius != 0.0 ? 1.0 / s->radius : 0.0;
        e->k1 = 1.0 + s->conic;
        if (s->type == SG_SURF_EVENASPH)
            for (k = 0; k < SG_NASPH; k++)
                if ((e->a[k] = s->asph[k]) != 0.0)
                    e->nasph = k + 1;
        e->t = i > 1 ? sys->surf[i - 1].thickness : 0.0;
        e->mirror = s->mat.kind == SG_MAT_MIRROR;
        e->mu = n0 / n1;
        e->n = n0;
    }
    return L;
}

void lean_free(lean *L)
{
    if (L) {
        free(L->s);
        free(L);
    }
}

int lean_nsurf(const lean *L)
{
    return L->n;
}

/* The asphere's polynomial and its derivative in r^2. */
static inline void poly(const lean_surf *e, double r2, double *p, double *dp)
{
    double v = 0.0, d = 0.0;
    int k;
    for (k = e->nasph - 1; k >= 0; k--) {
        d = d * r2 + v;
        v = v * r2 + e->a[k];
    }
    /* sum a_k r^(2k+2) = r2 * v(r2); its r2-derivative v + r2 v'. */
    *p = r2 * v;
    *dp = v + r2 * d;
}

/* LEAN_VL rays from points on surface 1 (its frame) with directions after
 * it, through surfaces 2 .. n - 1; rows[(r * n + i) * LEAN_ROW + j]. */
__attribute__((target_clones("avx512f", "avx2", "default")))
static void block(const lean *L, const double *in, double *rows, size_t first)
{
    double x[LEAN_VL], y[LEAN_VL], z[LEAN_VL], l[LEAN_VL], m[LEAN_VL], nn[LEAN_VL];
    double opl[LEAN_VL];
    int i, k, it;
    for (k = 0; k < LEAN_VL; k++) {
        const double *v = in + 6 * k;
        x[k] = v[0];
        y[k] = v[1];
        z[k] = v[2];
        l[k] = v[3];
        m[k] = v[4];
        nn[k] = v[5];
        opl[k] = 0.0;
    }
    for (i = 2; i < L->n; i++) {
        const lean_surf *e = &L->s[i];
        double s[LEAN_VL], nx[LEAN_VL], ny[LEAN_VL], nz[LEAN_VL];
        for (k = 0; k < LEAN_VL; k++) {
            /* Onto this vertex's tangent plane, then the conic's root
             * nearest it, in the stable form. */
            double s0 = (e->t - z[k]) / nn[k], px = x[k] + s0 * l[k], py = y[k] + s0 * m[k];
            double A = e->c * (l[k] * l[k] + m[k] * m[k] + e->k1 * nn[k] * nn[k]);
            double B = e->c * (px * l[k] + py * m[k]) - nn[k];
            double C = e->c * (px * px + py * py);
            double q = -B + copysign(sqrt(B * B - A * C), -B);
            s[k] = s0 + C / q;
            z[k] -= e->t;
        }
        if (e->nasph) {
            /* Newton along the ray on z - sag(x, y). */
            for (it = 0; it < LEAN_NEWTON; it++)
                for (k = 0; k < LEAN_VL; k++) {
                    double px = x[k] + s[k] * l[k], py = y[k] + s[k] * m[k];
                    double pz = z[k] + s[k] * nn[k], r2 = px * px + py * py, p, dp;
                    double w = sqrt(1.0 - e->k1 * e->c * e->c * r2);
                    double sag = e->c * r2 / (1.0 + w), dsag = e->c / w; /* d sag / d(r^2/2) */
                    double f, fp;
                    poly(e, r2, &p, &dp);
                    f = pz - sag - p;
                    fp = nn[k] - (dsag + 2.0 * dp) * (px * l[k] + py * m[k]);
                    s[k] -= f / fp;
                }
        }
        for (k = 0; k < LEAN_VL; k++) {
            double px = x[k] + s[k] * l[k], py = y[k] + s[k] * m[k], pz = z[k] + s[k] * nn[k];
            double g, inv, cosi, d;
            if (e->nasph) {
                double r2 = px * px + py * py, p, dp;
                double w = sqrt(1.0 - e->k1 * e->c * e->c * r2);
                poly(e, r2, &p, &dp);
                g = e->c / w + 2.0 * dp;
                nx[k] = -g * px;
                ny[k] = -g * py;
                nz[k] = 1.0;
            } else {
                nx[k] = -e->c * px;
                ny[k] = -e->c * py;
                nz[k] = 1.0 - e->c * e->k1 * pz;
            }
            inv = 1.0 / sqrt(nx[k] * nx[k] + ny[k] * ny[k] + nz[k] * nz[k]);
            nx[k] *= inv;
            ny[k] *= inv;
            nz[k] *= inv;
            cosi = l[k] * nx[k] + m[k] * ny[k] + nn[k] * nz[k];
            if (e->mirror) {
                d = 2.0 * cosi;
            } else {
                /* Snell in vector form: D' = mu D + (cos r - mu cos i) N,
                 * cos r with the sign of cos i. */
                double cr = sqrt(1.0 - e->mu * e->mu * (1.0 - cosi * cosi));
                d = e->mu * cosi - copysign(cr, cosi);
                l[k] *= e->mu;
                m[k] *= e->mu;
                nn[k] *= e->mu;
            }
            l[k] -= d * nx[k];
            m[k] -= d * ny[k];
            nn[k] -= d * nz[k];
            opl[k] += e->n * fabs(s[k]);
            x[k] = px;
            y[k] = py;
            z[k] = pz;
        }
        for (k = 0; k < LEAN_VL; k++) {
            double *o = rows + ((first + (size_t)k) * (size_t)L->n + (size_t)i) * LEAN_ROW;
            o[0] = x[k];
            o[1] = y[k];
            o[2] = z[k];
            o[3] = l[k];
            o[4] = m[k];
            o[5] = nn[k];
            o[6] = fabs(s[k]);
            o[7] = opl[k];
            o[8] = o[9] = o[10] = 0.0;
        }
    }
}

size_t lean_trace(const lean *L, const double *in, size_t nray, double *rows)
{
    size_t r, ok = 0;
    double pad[6 * LEAN_VL];
    for (r = 0; r + LEAN_VL <= nray; r += LEAN_VL)
        block(L, in + 6 * r, rows, r);
    if (r < nray) {
        /* The last rays, with idle lanes repeating the first. */
        size_t k;
        for (k = 0; k < LEAN_VL; k++)
            memcpy(pad + 6 * k, in + 6 * (r + (r + k < nray ? k : 0)), 6 * sizeof(double));
        {
            double *tmp = malloc((size_t)LEAN_VL * (size_t)L->n * LEAN_ROW * sizeof *tmp);
            if (!tmp)
                return 0;
            block(L, pad, tmp, 0);
            memcpy(rows + r * (size_t)L->n * LEAN_ROW, tmp,
                   (nray - r) * (size_t)L->n * LEAN_ROW * sizeof *tmp);
            free(tmp);
        }
    }
    for (r = 0; r < nray; r++)
        ok += isfinite(rows[(r * (size_t)L->n + (size_t)L->n - 1) * LEAN_ROW]);
    return ok;
}
