/*
 * dispatch.c - the vector trace's entry points in a build for no one
 * processor.
 *
 * Such a build (meson -Dnative=false on x86-64, as a distribution makes it)
 * compiles trace_vec.c, trace_classic_vec.c, launch.c, batch.c and
 * opd_vec.c three times, see isa.h: for
 * x86-64-v4 (AVX-512, eight lanes), x86-64-v3 (AVX2 and FMA, four lanes)
 * and the baseline (SSE2).  These functions, the only ways into those
 * files from the rest of the library, call the variant that the running
 * processor can execute.  Every variant gives the same bits.
 */
#ifdef SG_DISPATCH

#include "trace_int.h"

#define SG_VARIANT(isa)                                                                       \
    int sg_launch_prepare_##isa(sg_tracer *t, sg_diag *d);                                   \
    int sg_launch_precise_##isa(sg_tracer *t, double hx, double hy, double px, double py,    \
                                sg_ray_surface *out);                                        \
    int sg_launch_classic_##isa(sg_tracer *t, double hx, double hy, double px, double py,    \
                                sg_ray_surface *out);                                        \
    int sg_classic_run_to_##isa(const sg_tracer *t, const double S[3], const double D[3],   \
                                sg_ray_surface *out, int upto);                              \
    void sg_classic_block_##isa(const sg_tracer *t, const double (*S)[3],                    \
                                const double (*D)[3], sg_ray_surface *const *out, int nl,    \
                                int upto, int *rc);                                          \
    int sg_launch_classic_prep_##isa(sg_tracer *t, double hx, double hy, double px,          \
                                     double py, sg_ray_surface *out, double S[3],            \
                                     double D[3], double *off, int *inf);                    \
    int sg_precise_run_to_##isa(const sg_tracer *t, sg_pray *r, double path0,                \
                                sg_ray_surface *out, int upto);                              \
    int sg_batch_run_##isa(sg_tracer *const *t, int nt, sg_ray_kind kind,                    \
                           const sg_ray_in *rays, size_t nray, const int *sel, int nsel,     \
                           sg_ray_surface *scratch, sg_ray_surface *out, int *status);   \
    int sg_opd_of_rays_##isa(const sg_tracer *t, const sg_opd_ref *ref,                      \
                             const sg_ray_surface *rows, size_t stride, size_t n,            \
                             sg_opd *res);
SG_VARIANT(v4)
SG_VARIANT(v3)
SG_VARIANT(base)

enum { ISA_BASE, ISA_V3, ISA_V4 };

/* Asked on every call: the answer is a read of what libgcc learned from
 * cpuid at start-up, and the library keeps no state of its own. */
static int isa(void)
{
    if (__builtin_cpu_supports("x86-64-v4"))
        return ISA_V4;
    if (__builtin_cpu_supports("x86-64-v3"))
        return ISA_V3;
    return ISA_BASE;
}

#define SG_DISPATCH_CALL(name, ...)                                                           \
    switch (isa()) {                                                                          \
    case ISA_V4:                                                                              \
        return name##_v4(__VA_ARGS__);                                                        \
    case ISA_V3:                                                                              \
        return name##_v3(__VA_ARGS__);                                                        \
    default:                                                                                  \
        return name##_base(__VA_ARGS__);                                                      \
    }

int sg_launch_prepare(sg_tracer *t, sg_diag *d)
{
    SG_DISPATCH_CALL(sg_launch_prepare, t, d)
}

int sg_launch_precise(sg_tracer *t, double hx, double hy, double px, double py,
                      sg_ray_surface *out)
{
    SG_DISPATCH_CALL(sg_launch_precise, t, hx, hy, px, py, out)
}

int sg_launch_classic(sg_tracer *t, double hx, double hy, double px, double py,
                      sg_ray_surface *out)
{
    SG_DISPATCH_CALL(sg_launch_classic, t, hx, hy, px, py, out)
}

int sg_classic_run_to(const sg_tracer *t, const double S[3], const double D[3],
                      sg_ray_surface *out, int upto)
{
    SG_DISPATCH_CALL(sg_classic_run_to, t, S, D, out, upto)
}

/* The classic kernel and launch by name, for tests/test_classic_vec.c. */
void sg_classic_block(const sg_tracer *t, const double (*S)[3], const double (*D)[3],
                      sg_ray_surface *const *out, int nl, int upto, int *rc)
{
    switch (isa()) {
    case ISA_V4:
        sg_classic_block_v4(t, S, D, out, nl, upto, rc);
        break;
    case ISA_V3:
        sg_classic_block_v3(t, S, D, out, nl, upto, rc);
        break;
    default:
        sg_classic_block_base(t, S, D, out, nl, upto, rc);
        break;
    }
}

int sg_launch_classic_prep(sg_tracer *t, double hx, double hy, double px, double py,
                           sg_ray_surface *out, double S[3], double D[3], double *off,
                           int *inf)
{
    SG_DISPATCH_CALL(sg_launch_classic_prep, t, hx, hy, px, py, out, S, D, off, inf)
}

int sg_precise_run_to(const sg_tracer *t, sg_pray *r, double path0, sg_ray_surface *out,
                      int upto)
{
    SG_DISPATCH_CALL(sg_precise_run_to, t, r, path0, out, upto)
}

int sg_batch_run(sg_tracer *const *t, int nt, sg_ray_kind kind, const sg_ray_in *rays,
                 size_t nray, const int *sel, int nsel, sg_ray_surface *scratch,
                 sg_ray_surface *out, int *status)
{
    SG_DISPATCH_CALL(sg_batch_run, t, nt, kind, rays, nray, sel, nsel, scratch, out, status)
}

int sg_opd_of_rays(const sg_tracer *t, const sg_opd_ref *ref, const sg_ray_surface *rows,
                   size_t stride, size_t n, sg_opd *res)
{
    SG_DISPATCH_CALL(sg_opd_of_rays, t, ref, rows, stride, n, res)
}

#else
/* ISO C wants something in every translation unit. */
typedef int sg_dispatch_unused;
#endif
