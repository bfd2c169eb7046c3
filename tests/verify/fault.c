/*
 * fault.c - a fault-injecting wrapper of the engine's trace calls, linked
 * into a test-only copy of the program (sagitta_faulty) so that "sagitta
 * verify" can be shown designs that must fail.  The program's sources are
 * compiled unchanged except that -D renames their calls to these wrappers.
 *
 * $SAGITTA_TEST_FAULT picks the fault, applied to the precise method only:
 *   point  every surface's y moved by 4 times (bound + 1 ulp)
 *   dir    every surface's m moved by 4 times (dir bound + 1 ulp)
 *   fail   the ray stops at the last surface with SG_ENOCONV
 * and, applied to the mpfr method (the reference) only:
 *   reffail  the ray is not aimed: SG_EAIM, every surface not reached
 * Unset (or anything else), the wrappers change nothing.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

enum { MAXT = 64 };

/* The method of each live tracer, which sagitta.h does not expose. */
static struct {
    const sg_tracer *t;
    sg_method m;
} known[MAXT];

sg_tracer *fault_tracer_new(const sg_system *sys, const sg_catalog *cat,
                            const sg_trace_opts *opts, sg_diag *d);
int fault_tracer_open(const sg_system *sys, const sg_catalog *cat,
                      const sg_trace_opts *opts, sg_tracer **out, sg_diag *d);
int fault_trace_start(sg_tracer *t, const double start[3], const double dir[3],
                      sg_ray_surface *out);
int fault_trace_normalized(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out);

sg_tracer *fault_tracer_new(const sg_system *sys, const sg_catalog *cat,
                            const sg_trace_opts *opts, sg_diag *d)
{
    sg_tracer *t = sg_tracer_new(sys, cat, opts, d);
    int k;
    if (t)
        for (k = 0; k < MAXT; k++)
            if (!known[k].t || known[k].t == t) {
                known[k].t = t;
                known[k].m = opts ? opts->method : SG_METHOD_PRECISE;
                break;
            }
    return t;
}

int fault_tracer_open(const sg_system *sys, const sg_catalog *cat,
                      const sg_trace_opts *opts, sg_tracer **out, sg_diag *d)
{
    int rc = sg_tracer_open(sys, cat, opts, out, d), k;
    if (rc == SG_OK)
        for (k = 0; k < MAXT; k++)
            if (!known[k].t || known[k].t == *out) {
                known[k].t = *out;
                known[k].m = opts ? opts->method : SG_METHOD_PRECISE;
                break;
            }
    return rc;
}

static double ulp1(double x)
{
    x = fabs(x);
    return nextafter(x, INFINITY) - x;
}

static int inject(const sg_tracer *t, int rc, sg_ray_surface *out)
{
    const char *f = getenv("SAGITTA_TEST_FAULT");
    int k, i, last = sg_tracer_nsurf(t) - 1;
    sg_ray_surface *o = &out[last];
    for (k = 0; k < MAXT; k++)
        if (known[k].t == t)
            break;
    if (f && k < MAXT && known[k].m == SG_METHOD_MPFR && strcmp(f, "reffail") == 0) {
        for (i = 0; i <= last; i++) {
            out[i].x = out[i].y = out[i].z = out[i].l = out[i].m = out[i].n = NAN;
            out[i].residual = out[i].error_bound = out[i].dir_error_bound = NAN;
            out[i].path = NAN;
            out[i].status = i == 0 ? SG_EAIM : SG_ENOTREACHED;
        }
        return SG_EAIM;
    }
    if (!f || k == MAXT || known[k].m != SG_METHOD_PRECISE || rc != SG_OK)
        return rc;
    if (strcmp(f, "point") == 0) {
        for (i = 1; i <= last; i++)
            out[i].y += 4.0 * (out[i].error_bound + ulp1(fmax(fabs(out[i].y), fabs(out[i].z))));
    } else if (strcmp(f, "dir") == 0) {
        for (i = 1; i <= last; i++)
            out[i].m += 4.0 * (out[i].dir_error_bound + ulp1(1.0));
    } else if (strcmp(f, "fail") == 0) {
        o->x = o->y = o->z = o->l = o->m = o->n = NAN;
        o->residual = o->error_bound = o->dir_error_bound = o->path = NAN;
        o->status = SG_ENOCONV;
        return SG_ENOCONV;
    }
    return rc;
}

int fault_trace_start(sg_tracer *t, const double start[3], const double dir[3],
                      sg_ray_surface *out)
{
    return inject(t, sg_trace_start(t, start, dir, out), out);
}

int fault_trace_normalized(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out)
{
    return inject(t, sg_trace_normalized(t, hx, hy, px, py, out), out);
}
