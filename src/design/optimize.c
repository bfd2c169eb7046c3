/*
 * optimize.c - damped least squares on a design's variables against its
 * merit function (sagitta(1), OPTIMIZATION): GSL's trust-region
 * Levenberg-Marquardt with More's scaling (gsl_multifit_nlinear).
 *
 * The residuals are sqrt(w / sum w) (v - t), so their sum of squares is
 * MF^2.  A radius is varied as its curvature (a flat surface can bend);
 * bounds are kept by a change of variable (MINUIT's): the solver moves z
 * freely and the parameter is lo + (hi - lo) (1 + sin z) / 2, or lo - 1 +
 * sqrt(z^2 + 1) with one bound.  After each change the solves and pickups
 * are applied, so they stay live.  The Jacobian is central differences of
 * the precise trace, each step from the traced values' error bounds.
 */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_blas.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>

#include "model.h"
#include "design_int.h"

#define OPT_MAX_VARS 256
#define OPT_DEFAULT_CYCLES 500

typedef struct ovar {
    sg_paddr a;
    int curv;          /* varied as the curvature 1 / R */
    double lo, hi;     /* bounds on what is varied (the curvature for a radius) */
} ovar;

typedef struct octx {
    const sg_system *base;
    const sg_catalog *cat;
    sg_system *work;
    int nvar, nres;    /* nres: rows of nonzero weight, padded to nvar */
    ovar v[OPT_MAX_VARS];
    int *rowmap;       /* result row of each residual */
    double bad;        /* residual given to a failed trial: its step is rejected */
    double rel;        /* relative rounding of the residuals, from the bounds */
    int nthreads;
    sg_diag err;       /* the first failure the solver met */
    sg_lsq_fn fn;      /* residuals of another objective (sg_lsq_optimize), or NULL */
    void *fnctx;
    int nfn;           /* fn's residuals; the rest of nres are 0 */
} octx;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The parameter from the solver's z, and back. */
static double from_z(const ovar *v, double z)
{
    if (isfinite(v->lo) && isfinite(v->hi))
        return v->lo + (v->hi - v->lo) * (1.0 + sin(z)) / 2.0;
    if (isfinite(v->lo))
        return v->lo - 1.0 + sqrt(z * z + 1.0);
    if (isfinite(v->hi))
        return v->hi + 1.0 - sqrt(z * z + 1.0);
    return z;
}

static double to_z(const ovar *v, double p)
{
    if (isfinite(v->lo) && isfinite(v->hi)) {
        double s = 2.0 * (p - v->lo) / (v->hi - v->lo) - 1.0;
        return asin(s > 1.0 ? 1.0 : s < -1.0 ? -1.0 : s);
    }
    if (isfinite(v->lo))
        return sqrt((p - v->lo + 1.0) * (p - v->lo + 1.0) - 1.0);
    if (isfinite(v->hi))
        return sqrt((v->hi - p + 1.0) * (v->hi - p + 1.0) - 1.0);
    return p;
}

/* sys = base with the variables at z, solves applied. */
static int set_vars(const octx *o, sg_system *sys, const double *z, sg_diag *d)
{
    int j, rc;
    if ((rc = sg_system_assign(sys, o->base)) != SG_OK)
        return sg_diag_set(d, rc, "out of memory");
    for (j = 0; j < o->nvar; j++) {
        double p = from_z(&o->v[j], z[j]);
        if (o->v[j].curv)
            p = p == 0.0 ? INFINITY : 1.0 / p;
        sg_paddr_set(sys, &o->v[j].a, p);
    }
    return sg_system_apply_solves(sys, o->cat, d);
}

/* The residuals at z into f (nres); SG_OK, or the failure in d. */
static int residuals(const octx *o, sg_system *sys, const double *z, double *f, double *bound,
                     sg_diag *d)
{
    sg_merit_result r;
    int k, rc;
    if ((rc = set_vars(o, sys, z, d)) != SG_OK)
        return rc;
    if (o->fn) {
        if (bound)
            *bound = 0.0;
        for (k = o->nfn; k < o->nres; k++)
            f[k] = 0.0;
        return o->fn(o->fnctx, sys, f, o->nfn, d);
    }
    if ((rc = sg_merit_eval(sys, o->cat, &r, d)) != SG_OK)
        return rc;
    for (k = 0; k < o->nres; k++) {
        int i = o->rowmap[k];
        f[k] = i < 0 ? 0.0
                     : sqrt(r.row[i].weight / r.wsum) * (r.row[i].value - r.row[i].target);
    }
    if (bound)
        *bound = r.bound;
    sg_merit_result_free(&r);
    return SG_OK;
}

static int gsl_f(const gsl_vector *x, void *params, gsl_vector *f)
{
    octx *o = params;
    double z[OPT_MAX_VARS];
    sg_diag d;
    int j, k;
    for (j = 0; j < o->nvar; j++)
        z[j] = gsl_vector_get(x, j);
    sg_diag_clear(&d);
    if (residuals(o, o->work, z, f->data, NULL, &d) != SG_OK) {
        /* A trial the design cannot take (a ray misses): a large residual,
         * so the trust region shrinks and the step is rejected. */
        for (k = 0; k < o->nres; k++)
            gsl_vector_set(f, k, o->bad);
        if (!o->err.code)
            o->err = d;
    }
    return GSL_SUCCESS;
}

/* One Jacobian column: central differences at z, step h in z. */
typedef struct colwork {
    octx *o;
    const double *z;
    gsl_matrix *J;
    const double *f0;
    int j0, j1;       /* columns [j0, j1) */
    int rc;
    sg_diag d;
} colwork;

static void *columns(void *arg)
{
    colwork *w = arg;
    octx *o = w->o;
    sg_system *sys = sg_system_clone(o->base);
    double *fp = malloc((size_t)o->nres * sizeof *fp), *fm = malloc((size_t)o->nres * sizeof *fm);
    double z[OPT_MAX_VARS];
    int j, k;
    w->rc = SG_OK;
    if (!sys || !fp || !fm) {
        w->rc = sg_diag_set(&w->d, SG_ENOMEM, "out of memory");
        goto out;
    }
    memcpy(z, w->z, (size_t)o->nvar * sizeof *z);
    for (j = w->j0; j < w->j1; j++) {
        /* Central differences: truncation h^2, rounding rel / h, so h =
         * cbrt(rel) times the variable's scale (at least 1e-3 of a unit
         * of z, which is the parameter itself when unbounded). */
        double zj = z[j], h = cbrt(o->rel) * fmax(fabs(zj), 1e-3), hp, hm;
        int okp, okm;
        z[j] = zj + h;
        hp = z[j] - zj;
        okp = residuals(o, sys, z, fp, NULL, &w->d) == SG_OK;
        z[j] = zj - h;
        hm = zj - z[j];
        okm = residuals(o, sys, z, fm, NULL, &w->d) == SG_OK;
        z[j] = zj;
        if (okp && okm) {
            for (k = 0; k < o->nres; k++)
                gsl_matrix_set(w->J, k, j, (fp[k] - fm[k]) / (hp + hm));
        } else if (okp || okm) {
            /* One side fails (a ray misses there): the one-sided difference. */
            for (k = 0; k < o->nres; k++)
                gsl_matrix_set(w->J, k, j, okp ? (fp[k] - w->f0[k]) / hp
                                               : (w->f0[k] - fm[k]) / hm);
        } else {
            w->rc = SG_ENONPHYS;
            goto out;
        }
    }
    sg_diag_clear(&w->d);
out:
    free(fp);
    free(fm);
    sg_system_free(sys);
    return NULL;
}

/* A worker thread's columns; MPFR caches constants such as pi per thread,
 * and a worker frees its own before it ends (as the batch's do). */
static void *column_thread(void *arg)
{
    columns(arg);
    mpfr_free_cache2(MPFR_FREE_LOCAL_CACHE);
    return NULL;
}

static int gsl_df(const gsl_vector *x, void *params, gsl_matrix *J)
{
    octx *o = params;
    double z[OPT_MAX_VARS], *f0;
    colwork w[16];
    pthread_t th[16];
    int j, t, nt = o->nthreads, started[16] = {0};
    sg_diag d;
    for (j = 0; j < o->nvar; j++)
        z[j] = gsl_vector_get(x, j);
    f0 = malloc((size_t)o->nres * sizeof *f0);
    if (!f0)
        return GSL_ENOMEM;
    sg_diag_clear(&d);
    if (residuals(o, o->work, z, f0, NULL, &d) != SG_OK) {
        free(f0);
        if (!o->err.code)
            o->err = d;
        return GSL_EBADFUNC;
    }
    if (nt < 1)
        nt = 1;
    if (nt > 16)
        nt = 16;
    if (nt > o->nvar)
        nt = o->nvar;
    for (t = 0; t < nt; t++) {
        w[t].o = o;
        w[t].z = z;
        w[t].J = J;
        w[t].f0 = f0;
        w[t].j0 = o->nvar * t / nt;
        w[t].j1 = o->nvar * (t + 1) / nt;
        sg_diag_clear(&w[t].d);
        if (t > 0 && pthread_create(&th[t], NULL, column_thread, &w[t]) == 0)
            started[t] = 1;
        else if (t > 0)
            columns(&w[t]);
    }
    columns(&w[0]);
    for (t = 1; t < nt; t++)
        if (started[t])
            pthread_join(th[t], NULL);
    free(f0);
    for (t = 0; t < nt; t++)
        if (w[t].rc != SG_OK) {
            if (!o->err.code)
                o->err = w[t].d;
            return GSL_EBADFUNC;
        }
    return GSL_SUCCESS;
}

void sg_opt_opts_init(sg_opt_opts *o)
{
    memset(o, 0, sizeof *o);
}

static int run_lsq(octx *op, sg_system *sys, const double *z0, const sg_opt_opts *opts,
                   sg_opt_result *res, sg_diag *d);

/* The variables and their bounds in what the solver varies. */
static int collect(octx *o, const sg_system *sys, sg_diag *d)
{
    sg_paddr a[OPT_MAX_VARS];
    int n = sg_variables(sys, a, OPT_MAX_VARS), j;
    char name[96];
    if (n > OPT_MAX_VARS)
        return sg_diag_set(d, SG_ERANGE, "%d variables; the limit is %d", n, OPT_MAX_VARS);
    for (j = 0; j < n; j++) {
        ovar *v = &o->v[j];
        int t = sg_paddr_solve_target(&a[j]);
        sg_solve bounds, *s = &bounds;
        double p = sg_paddr_get(sys, &a[j]);
        sg_variable_bounds(sys, &a[j], &bounds.lo, &bounds.hi);
        v->a = a[j];
        v->curv = t == SG_SOLVE_RADIUS;
        v->lo = s->lo;
        v->hi = s->hi;
        sg_paddr_name(&a[j], name, sizeof name);
        if (!(p >= s->lo && p <= s->hi) && !(v->curv && isinf(p)))
            return sg_diag_set(d, SG_ERANGE, "%s: the value %.17g is outside the variable's "
                               "min %g and max %g", name, p, s->lo, s->hi);
        if (!isfinite(p) && !v->curv)
            return sg_diag_set(d, SG_ERANGE, "%s: an infinite value cannot vary", name);
        if (v->curv) {
            /* Bounds on a radius of one sign bound the curvature. */
            if (isfinite(s->lo) || isfinite(s->hi)) {
                if (!(s->lo > 0.0 || s->hi < 0.0))
                    return sg_diag_set(d, SG_ERANGE, "%s: a radius variable's min and max "
                                       "must not enclose 0 (a flat surface's radius is "
                                       "infinite); bound it on one side of 0", name);
                /* R in [lo, hi] of one sign is c in [1 / hi, 1 / lo], an
                 * infinite bound giving a curvature of 0 (flat). */
                v->lo = 1.0 / s->hi;
                v->hi = 1.0 / s->lo;
            }
        }
    }
    o->nvar = n;
    return SG_OK;
}

/* The k-th point (k >= 1) of the Halton set in base b: the radical
 * inverse of k. */
static double halton(unsigned long k, unsigned b)
{
    double f = 1.0, r = 0.0;
    while (k > 0) {
        f /= b;
        r += f * (double)(k % b);
        k /= b;
    }
    return r;
}

static int local_opt(sg_system *sys, const sg_catalog *cat, const sg_opt_opts *opts,
                     sg_opt_result *res, sg_diag *d);

/* Multi-start damped least squares: the start as given, then the Halton
 * points inside the variables' boxes (a radius's box taken in curvature),
 * each run to convergence; the lowest merit wins (the first on a tie). */
static int global_opt(sg_system *sys, const sg_catalog *cat, const sg_opt_opts *opts,
                      sg_opt_result *res, sg_diag *d)
{
    static const unsigned primes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47,
                                      53, 59, 61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107,
                                      109, 113, 127, 131};
    sg_paddr a[OPT_MAX_VARS];
    double lo[OPT_MAX_VARS], hi[OPT_MAX_VARS], t0 = now();
    int n = sg_variables(sys, a, OPT_MAX_VARS), j, rc, k;
    sg_opt_opts lo_opts = *opts;
    sg_opt_result r;
    sg_system *best, *trial;
    char name[96];
    if (n > (int)(sizeof primes / sizeof primes[0]))
        return sg_diag_set(d, SG_ERANGE, "--global: %d variables; the Halton set here has %d "
                           "dimensions", n, (int)(sizeof primes / sizeof primes[0]));
    for (j = 0; j < n; j++) {
        sg_variable_bounds(sys, &a[j], &lo[j], &hi[j]);
        sg_paddr_name(&a[j], name, sizeof name);
        if (!isfinite(lo[j]) || !isfinite(hi[j]))
            return sg_diag_set(d, SG_ERANGE, "%s: a global search needs every variable's min "
                               "and max", name);
        if (sg_paddr_solve_target(&a[j]) == SG_SOLVE_RADIUS) {
            double l = lo[j], h = hi[j];
            if (!(l > 0.0 || h < 0.0))
                return sg_diag_set(d, SG_ERANGE, "%s: a radius variable's min and max must not "
                                   "enclose 0", name);
            lo[j] = 1.0 / h;
            hi[j] = 1.0 / l;
        }
    }
    lo_opts.global_seconds = 0.0;
    lo_opts.progress = NULL;
    memset(res, 0, sizeof *res);
    if ((rc = local_opt(sys, cat, &lo_opts, res, d)) != SG_OK)
        return rc;
    best = sg_system_clone(sys);
    trial = sg_system_clone(sys);
    if (!best || !trial) {
        sg_system_free(best);
        sg_system_free(trial);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    for (k = 1; opts->global_starts <= 0 || k < opts->global_starts; k++) {
        sg_diag dd;
        if ((opts->stop && *opts->stop) || now() - t0 >= opts->global_seconds) {
            res->stopped = opts->stop && *opts->stop;
            break;
        }
        sg_system_assign(trial, sys);
        for (j = 0; j < n; j++) {
            double u = halton((unsigned long)opts->seed + (unsigned long)k, primes[j]);
            double p = lo[j] + (hi[j] - lo[j]) * u;
            if (sg_paddr_solve_target(&a[j]) == SG_SOLVE_RADIUS)
                p = p == 0.0 ? INFINITY : 1.0 / p;
            sg_paddr_set(trial, &a[j], p);
        }
        sg_diag_clear(&dd);
        /* A start the design cannot take (a ray misses there) is passed. */
        if (sg_system_apply_solves(trial, cat, &dd) != SG_OK ||
            local_opt(trial, cat, &lo_opts, &r, &dd) != SG_OK)
            continue;
        res->cycles += r.cycles;
        if (r.merit < res->merit) {
            res->merit = r.merit;
            res->converged = r.converged;
            sg_system_assign(best, trial);
        }
        if (opts->progress && opts->progress(opts->ctx, k, res->merit, 0.0, now() - t0)) {
            res->stopped = 1;
            break;
        }
    }
    sg_system_assign(sys, best);
    sg_system_free(best);
    sg_system_free(trial);
    return SG_OK;
}

int sg_optimize(sg_system *sys, const sg_catalog *cat, const sg_opt_opts *opts,
                sg_opt_result *res, sg_diag *d)
{
    if (opts && opts->global_seconds > 0.0)
        return global_opt(sys, cat, opts, res, d);
    return local_opt(sys, cat, opts, res, d);
}

static int local_opt(sg_system *sys, const sg_catalog *cat, const sg_opt_opts *opts,
                     sg_opt_result *res, sg_diag *d)
{
    octx o;
    sg_opt_opts def;
    sg_merit_result r0;
    double z0[OPT_MAX_VARS], bound = 0.0;
    int j, k, rc, nz = 0;

    memset(res, 0, sizeof *res);
    if (!opts) {
        sg_opt_opts_init(&def);
        opts = &def;
    }
    memset(&o, 0, sizeof o);
    o.base = sys;
    o.cat = cat;
    o.nthreads = opts->nthreads;
    if (!sys->merit.present || (sys->merit.nop == 0 && !sys->merit.has_default))
        return sg_diag_set(d, SG_ENOSYS, "the design has no merit function (a \"merit\" object; "
                           "sagitta-design(5), MERIT FUNCTION)");
    if ((rc = collect(&o, sys, d)) != SG_OK)
        return rc;
    if (o.nvar == 0)
        return sg_diag_set(d, SG_ENOSYS, "the design has no variables (a solve of type "
                           "\"variable\"; sagitta-design(5), SOLVES)");
    for (j = 0; j < o.nvar; j++) {
        double p = sg_paddr_get(sys, &o.v[j].a);
        if (o.v[j].curv)
            p = isinf(p) || p == 0.0 ? 0.0 : 1.0 / p;
        z0[j] = to_z(&o.v[j], p);
    }
    o.work = sg_system_clone(sys);
    if (!o.work)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    /* The start: which rows count, and the rounding of their values. */
    if ((rc = set_vars(&o, o.work, z0, d)) != SG_OK ||
        (rc = sg_merit_eval(o.work, cat, &r0, d)) != SG_OK) {
        sg_system_free(o.work);
        return rc;
    }
    for (k = 0; k < r0.nrow; k++)
        nz += r0.row[k].weight != 0.0;
    o.nres = nz > o.nvar ? nz : o.nvar;
    o.rowmap = malloc((size_t)o.nres * sizeof *o.rowmap);
    if (!o.rowmap) {
        sg_merit_result_free(&r0);
        sg_system_free(o.work);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    for (k = 0, j = 0; k < r0.nrow; k++)
        if (r0.row[k].weight != 0.0)
            o.rowmap[j++] = k;
    for (; j < o.nres; j++)
        o.rowmap[j] = -1;
    {
        /* rel: the largest error bound over the largest traced value,
         * never below a double's rounding (the values that are not traced:
         * EFL, thicknesses, are rounded once). */
        double vmax = 0.0;
        for (k = 0; k < r0.nrow; k++)
            vmax = fmax(vmax, fabs(r0.row[k].value));
        bound = r0.bound;
        o.rel = vmax > 0.0 ? bound / vmax : 0.0;
        if (o.rel < DBL_EPSILON)
            o.rel = DBL_EPSILON;
    }
    res->merit0 = r0.merit;
    o.bad = 1e3 * (r0.merit + 1.0);
    sg_merit_result_free(&r0);
    rc = run_lsq(&o, sys, z0, opts, res, d);
    free(o.rowmap);
    sg_system_free(o.work);
    return rc;
}

/* GSL's error handler is one for the process: it is off while any run
 * is under way (compensators run on several threads at once), and back
 * when the last one ends. */
static pthread_mutex_t gsl_handler_lock = PTHREAD_MUTEX_INITIALIZER;
static int gsl_handler_users;
static gsl_error_handler_t *gsl_handler_old;

static void gsl_handler_enter(void)
{
    pthread_mutex_lock(&gsl_handler_lock);
    if (gsl_handler_users++ == 0)
        gsl_handler_old = gsl_set_error_handler_off();
    pthread_mutex_unlock(&gsl_handler_lock);
}

static void gsl_handler_leave(void)
{
    pthread_mutex_lock(&gsl_handler_lock);
    if (--gsl_handler_users == 0)
        gsl_set_error_handler(gsl_handler_old);
    pthread_mutex_unlock(&gsl_handler_lock);
}

/* The damped least squares from z0; sys gets the best point found. */
static int run_lsq(octx *op, sg_system *sys, const double *z0, const sg_opt_opts *opts,
                   sg_opt_result *res, sg_diag *d)
{
    gsl_multifit_nlinear_fdf fdf;
    gsl_multifit_nlinear_parameters par;
    gsl_multifit_nlinear_workspace *w = NULL;
    gsl_vector *x = NULL;
    double best[OPT_MAX_VARS], bestmf, t0 = now();
    int j, rc, cycle, maxc;

    gsl_handler_enter();
    fdf.f = gsl_f;
    fdf.df = gsl_df;
    fdf.fvv = NULL;
    fdf.n = (size_t)op->nres;
    fdf.p = (size_t)op->nvar;
    fdf.params = op;
    par = gsl_multifit_nlinear_default_parameters();
    par.trs = gsl_multifit_nlinear_trs_lm;
    par.scale = gsl_multifit_nlinear_scale_more;
    w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &par, fdf.n, fdf.p);
    x = gsl_vector_alloc(fdf.p);
    if (!w || !x) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (j = 0; j < op->nvar; j++)
        gsl_vector_set(x, j, z0[j]);
    if (gsl_multifit_nlinear_init(x, &fdf, w) != GSL_SUCCESS) {
        rc = sg_diag_set(d, op->err.code ? op->err.code : SG_ENONPHYS,
                         "optimize: the start cannot be evaluated: %s",
                         op->err.code ? op->err.msg : "the Jacobian failed");
        goto done;
    }
    memcpy(best, z0, (size_t)op->nvar * sizeof *best);
    bestmf = res->merit0;
    maxc = opts->cycles > 0 ? opts->cycles : OPT_DEFAULT_CYCLES;
    for (cycle = 1; cycle <= maxc; cycle++) {
        double mf, step = 0.0, prev[OPT_MAX_VARS];
        int info = 0, st;
        for (j = 0; j < op->nvar; j++)
            prev[j] = gsl_vector_get(gsl_multifit_nlinear_position(w), j);
        if (opts->stop && *opts->stop) {
            res->stopped = 1;
            break;
        }
        st = gsl_multifit_nlinear_iterate(w);
        {
            gsl_vector *f = gsl_multifit_nlinear_residual(w), *xn = gsl_multifit_nlinear_position(w);
            mf = gsl_blas_dnrm2(f);
            for (j = 0; j < op->nvar; j++)
                step = hypot(step, gsl_vector_get(xn, j) - prev[j]);
            if (mf < bestmf) {
                bestmf = mf;
                for (j = 0; j < op->nvar; j++)
                    best[j] = gsl_vector_get(xn, j);
            }
        }
        res->cycles = cycle;
        if (opts->progress && opts->progress(opts->ctx, cycle, bestmf, step, now() - t0)) {
            res->stopped = 1;
            break;
        }
        if (st == GSL_ENOPROG || st == GSL_EBADFUNC) {
            /* No step lowers the merit (or the Jacobian cannot be formed
             * there): a minimum as far as the trace can tell. */
            res->converged = st == GSL_ENOPROG;
            break;
        }
        if (st != GSL_SUCCESS)
            break;
        if (gsl_multifit_nlinear_test(1e-12, 1e-14, 0.0, &info, w) == GSL_SUCCESS) {
            res->converged = 1;
            break;
        }
    }
    /* The best design, evaluated again, into sys; a start never bettered
     * stays as it was, bit for bit (z and back may round). */
    res->merit = bestmf;
    if (!(bestmf < res->merit0)) {
        rc = SG_OK;
        goto done;
    }
    if ((rc = set_vars(op, op->work, best, d)) != SG_OK)
        goto done;
    if ((rc = sg_system_assign(sys, op->work)) != SG_OK) {
        rc = sg_diag_set(d, rc, "out of memory");
        goto done;
    }
    res->merit = bestmf;
    rc = SG_OK;
done:
    gsl_handler_leave();
    if (w)
        gsl_multifit_nlinear_free(w);
    if (x)
        gsl_vector_free(x);
    return rc;
}

int sg_lsq_optimize(sg_system *sys, const sg_catalog *cat, const sg_paddr *vars,
                    const double *lo, const double *hi, int nvar, int nres, double rel,
                    sg_lsq_fn fn, void *ctx, const sg_opt_opts *opts, sg_opt_result *res,
                    sg_diag *d)
{
    octx o;
    sg_opt_opts def;
    double z0[OPT_MAX_VARS], *f;
    int j, k, rc;
    char name[96];

    memset(res, 0, sizeof *res);
    if (!opts) {
        sg_opt_opts_init(&def);
        opts = &def;
    }
    if (nvar < 1 || nvar > OPT_MAX_VARS || nres < 1)
        return sg_diag_set(d, SG_ERANGE, "%d variables and %d residuals", nvar, nres);
    memset(&o, 0, sizeof o);
    o.base = sys;
    o.cat = cat;
    o.nthreads = opts->nthreads;
    o.fn = fn;
    o.fnctx = ctx;
    o.nvar = nvar;
    o.nres = nres > nvar ? nres : nvar;
    o.nfn = nres;
    o.rel = rel > DBL_EPSILON ? rel : DBL_EPSILON;
    for (j = 0; j < nvar; j++) {
        ovar *v = &o.v[j];
        double p = sg_paddr_get(sys, &vars[j]);
        v->a = vars[j];
        v->curv = sg_paddr_solve_target(&vars[j]) == SG_SOLVE_RADIUS;
        v->lo = lo[j];
        v->hi = hi[j];
        sg_paddr_name(&vars[j], name, sizeof name);
        if (v->curv) {
            if (!(lo[j] > 0.0 || hi[j] < 0.0))
                return sg_diag_set(d, SG_ERANGE, "%s: a radius's min and max must not "
                                   "enclose 0", name);
            v->lo = 1.0 / hi[j];
            v->hi = 1.0 / lo[j];
            p = isinf(p) || p == 0.0 ? 0.0 : 1.0 / p;
        }
        if (!(p >= v->lo && p <= v->hi))
            return sg_diag_set(d, SG_ERANGE, "%s: the value %.17g is outside its range", name,
                               sg_paddr_get(sys, &vars[j]));
        z0[j] = to_z(v, p);
    }
    o.work = sg_system_clone(sys);
    f = malloc((size_t)o.nres * sizeof *f);
    if (!o.work || !f) {
        free(f);
        sg_system_free(o.work);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    if ((rc = residuals(&o, o.work, z0, f, NULL, d)) != SG_OK) {
        free(f);
        sg_system_free(o.work);
        return rc;
    }
    for (k = 0; k < o.nres; k++)
        res->merit0 = hypot(res->merit0, k < nres ? f[k] : 0.0);
    o.bad = 1e3 * (res->merit0 + 1.0);
    free(f);
    rc = run_lsq(&o, sys, z0, opts, res, d);
    sg_system_free(o.work);
    return rc;
}
