/* testutil.c - helpers shared by the cmocka tests. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/fsuid.h>
#endif

#include "testutil.h"

const char *tu_path(const char *rel, char *buf, size_t n)
{
    const char *root = getenv("SAGITTA_SOURCE_ROOT");
    snprintf(buf, n, "%s/%s", root ? root : ".", rel);
    return buf;
}

sg_catalog *tu_catalog(void)
{
    sg_diag d;
    sg_catalog *cat = sg_catalog_new();
    sg_diag_clear(&d);
    assert_non_null(cat);
    if (sg_catalog_load_default(cat, &d) != SG_OK)
        fail_msg("cannot load the catalog: %s", d.msg);
    return cat;
}

sg_system *tu_example(const char *file)
{
    char rel[512], path[1024];
    sg_diag d;
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    sg_diag_clear(&d);
    snprintf(rel, sizeof rel, "examples/%s", file);
    if (sg_design_load(sys, tu_path(rel, path, sizeof path), &d) != SG_OK)
        fail_msg("cannot load %s: %s", path, d.msg);
    return sys;
}

double tu_ulp(double x)
{
    x = fabs(x);
    if (x < DBL_MIN)
        return DBL_TRUE_MIN;
    return nextafter(x, INFINITY) - x;
}

double tu_ulps(double a, double b, double ref_scale)
{
    double s = fmax(fabs(ref_scale), fmax(fabs(a), fabs(b)));
    return fabs(a - b) / tu_ulp(s);
}

sg_tracer *tu_tracer_bits(const sg_system *sys, const sg_catalog *cat, sg_method m, int bits)
{
    sg_trace_opts o;
    sg_diag d;
    sg_tracer *t;
    sg_trace_opts_init(&o);
    o.method = m;
    if (bits)
        o.mpfr_bits = bits;
    sg_diag_clear(&d);
    t = sg_tracer_new(sys, cat, &o, &d);
    if (!t)
        fail_msg("tracer: %s", d.msg);
    return t;
}

sg_tracer *tu_tracer(const sg_system *sys, const sg_catalog *cat, sg_method m)
{
    return tu_tracer_bits(sys, cat, m, 0);
}

sg_system *tu_one_surface(void)
{
    sg_system *sys = sg_system_new();
    assert_non_null(sys);
    assert_int_equal(sg_system_reset(sys, 3), SG_OK);
    sys->surf[0].thickness = INFINITY;
    sys->stop = 1;
    return sys;
}

int tu_ci(void)
{
    const char *ci = getenv("CI");
    return ci && *ci && strcmp(ci, "0") != 0 && strcmp(ci, "false") != 0 &&
           strcmp(ci, "no") != 0;
}

int tu_unpriv_begin(void)
{
    if (geteuid() != 0)
        return 0;
#ifdef __linux__
    /* Group first: once the user id is nobody's, changing it is refused. */
    setfsgid(TU_NOBODY);
    setfsuid(TU_NOBODY);
    /* setfsuid reports the previous id, never an error: ask again. */
    if (setfsuid(TU_NOBODY) != TU_NOBODY)
        fail_msg("setfsuid(%d) did not take effect", TU_NOBODY);
    return 1;
#else
    fail_msg("running as root, and this system has no setfsuid to drop it");
    return 0;
#endif
}

void tu_unpriv_end(void)
{
#ifdef __linux__
    if (geteuid() == 0) {
        setfsuid(0);
        setfsgid(0);
    }
#endif
}

int tu_same_row(const sg_ray_surface *a, const sg_ray_surface *b)
{
    const double fa[13] = {a->x, a->y, a->z, a->l, a->m, a->n, a->residual, a->error_bound,
                           a->dir_error_bound, a->path, a->opl, a->opl_lo, a->opl_error_bound};
    const double fb[13] = {b->x, b->y, b->z, b->l, b->m, b->n, b->residual, b->error_bound,
                           b->dir_error_bound, b->path, b->opl, b->opl_lo, b->opl_error_bound};
    return memcmp(fa, fb, sizeof fa) == 0 && a->status == b->status;
}
