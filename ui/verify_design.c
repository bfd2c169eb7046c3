/*
 * verify_design.c - "sagitta verify DESIGN": precise and classic rays of a
 * design against the mpfr trace of the same double inputs.
 */
#include "verify_int.h"

/* ------------------------------------------------------ verify on a design */

typedef struct vray {
    double h[4];       /* hx, hy, px, py */
    int st[NMETHOD];   /* trace return per method */
    int fs[NMETHOD];   /* surface where it stopped, -1 if it reached the image */
    sg_opd opd[NMETHOD]; /* each method's OPD against its own reference sphere */
} vray;

typedef struct mstat {
    size_t n;                     /* rays compared at this surface */
    double dmin, dmed, dirmin;    /* point digits min, median; direction min */
    double maxerr;                /* largest max |coordinate difference| */
} mstat;

typedef struct sstat {
    mstat m[2];
    double rmin, rmed; /* precise bound / error over rays with an error */
    size_t nexact;     /* rays where precise equals the reference exactly */
    size_t nratio;
    double scale;      /* largest reference coordinate on the surface */
} sstat;

typedef struct worst {
    long ray; /* -1: none compared */
    int surf;
    double digits;
    double err; /* max |coordinate - mpfr| there; ties in digits go to the larger */
} worst;

typedef struct violation {
    size_t ray;
    int surf;
    int dir; /* 0: point, 1: direction */
    double err, bound, refbound;
} violation;

typedef struct vdesign {
    const char *path;
    const sg_system *sys;
    int wave0, bits, nsurf;
    size_t nray, nfield, npupil;
    vray *rays;
    /* Traced a block at a time; kept per surface are only the digits of
     * each compared ray (dig[m][i * nray + k]) and precise's bound/error
     * (ratio, likewise), for the exact medians. */
    double *dig[2], *ratio;
    sg_ray_surface *ray0;         /* NMETHOD * nsurf rows of ray 0 */
    sstat *ss;                    /* per surface */
    worst w[2];
    sg_ray_surface wrow[2][2];    /* the worst's rows: the method's, mpfr's */
    violation *viol;
    size_t nviol;
    size_t ncmp[2];
    size_t nfail_ref;     /* rays the reference does not trace */
    size_t nref_broken;   /* of those, where the reference itself failed
                           * (aiming or convergence) rather than the ray */
    size_t ndis[2];       /* disagreements per method */
    /* OPD against mpfr's, over rays all three methods give one for: the
     * largest |difference| in waves, the fewest digits (-log10 of that
     * difference over max(|OPD|, 1e-3 waves)), and the rays where the
     * precise bound plus mpfr's falls short of the difference. */
    size_t nopd;
    double opd_maxdiff[2], opd_digits[2];
    size_t opd_viol;
} vdesign;


/* Normalized field coordinates of every distinct field point. */
static size_t field_points(const sg_system *sys, double (*h)[2])
{
    double fx = 0.0, fy = 0.0;
    size_t n = 0, j;
    int k;
    for (k = 0; k < sys->nfield; k++) {
        if (sys->field_norm == SG_NORM_RADIAL) {
            double r = hypot(sys->field[k].x, sys->field[k].y);
            fx = fmax(fx, r);
            fy = fmax(fy, r);
        } else {
            fx = fmax(fx, fabs(sys->field[k].x));
            fy = fmax(fy, fabs(sys->field[k].y));
        }
    }
    for (k = 0; k < sys->nfield; k++) {
        double hx = fx > 0.0 ? sys->field[k].x / fx : 0.0;
        double hy = fy > 0.0 ? sys->field[k].y / fy : 0.0;
        for (j = 0; j < n; j++)
            if (h[j][0] == hx && h[j][1] == hy)
                break;
        if (j == n) {
            h[n][0] = hx;
            h[n][1] = hy;
            n++;
        }
    }
    return n;
}

/* The pupil grid clipped to the unit circle, plus the chief and marginal
 * rays when the grid lacks them.  p needs room for grid^2 + 5 points. */
static size_t pupil_points(int grid, double (*p)[2])
{
    static const double extra[5][2] = { { 0, 0 }, { 0, 1 }, { 0, -1 }, { 1, 0 }, { -1, 0 } };
    size_t n = 0, j;
    int i, k;
    for (i = 0; i < grid; i++)
        for (k = 0; k < grid; k++) {
            double px = grid == 1 ? 0.0 : (2.0 * k - (grid - 1)) / (double)(grid - 1);
            double py = grid == 1 ? 0.0 : (2.0 * i - (grid - 1)) / (double)(grid - 1);
            if (px * px + py * py <= 1.0 + 1e-12) {
                p[n][0] = px;
                p[n][1] = py;
                n++;
            }
        }
    for (k = 0; k < 5; k++) {
        for (j = 0; j < n; j++)
            if (p[j][0] == extra[k][0] && p[j][1] == extra[k][1])
                break;
        if (j == n) {
            p[n][0] = extra[k][0];
            p[n][1] = extra[k][1];
            n++;
        }
    }
    return n;
}

static void vdesign_free(vdesign *v)
{
    int m;
    free(v->rays);
    for (m = 0; m < 2; m++)
        free(v->dig[m]);
    free(v->ratio);
    free(v->ray0);
    free(v->ss);
    free(v->viol);
}

/* Rays traced at once: their rows of the three methods stay near 9 MB
 * (VERIFY_BLOCK_ROWS rows each), whatever the grid. */
#define VERIFY_BLOCK_ROWS 32768

/* A compared point whose reference is the origin: its digits borrow the
 * surface's scale, known only once every ray is traced. */
typedef struct deferred {
    size_t ray;
    int surf, m;
    sg_ray_surface a, b;
} deferred;

static int ref_broken(const vray *ray)
{
    return ref_broken_status(ray->st[M_MPFR]);
}

static int add_violation(vdesign *v, size_t r, int i, int dir, double err,
                         double bound, double refbound)
{
    violation *nv = realloc(v->viol, (v->nviol + 1) * sizeof *nv);
    if (!nv)
        return -1;
    v->viol = nv;
    nv[v->nviol].ray = r;
    nv[v->nviol].surf = i;
    nv[v->nviol].dir = dir;
    nv[v->nviol].err = err;
    nv[v->nviol].bound = bound;
    nv[v->nviol].refbound = refbound;
    v->nviol++;
    return 0;
}

/* The worst point so far: the fewest digits, then the largest error, then
 * the first by surface and ray, the order a whole-set scan would meet it
 * in, so the blocks' order does not matter. */
static void take_worst(vdesign *v, int m, double dg, double err, size_t r, int i,
                       const sg_ray_surface *a, const sg_ray_surface *b)
{
    worst *w = &v->w[m];
    if (dg < w->digits ||
        (dg == w->digits &&
         (err > w->err ||
          (err == w->err && (i < w->surf || (i == w->surf && (long)r < w->ray)))))) {
        w->digits = dg;
        w->err = err;
        w->ray = (long)r;
        w->surf = i;
        v->wrow[m][0] = *a;
        v->wrow[m][1] = *b;
    }
}

static int cmp_violation(const void *pa, const void *pb)
{
    const violation *a = pa, *b = pb;
    if (a->surf != b->surf)
        return a->surf < b->surf ? -1 : 1;
    if (a->ray != b->ray)
        return a->ray < b->ray ? -1 : 1;
    return a->dir - b->dir;
}

/* One ray's rows (the three methods, out[m] + k * nsurf) into the
 * statistics.  Returns 0, or -1 when memory runs out. */
static int vdesign_take(vdesign *v, sg_ray_surface *const out[NMETHOD], size_t k, size_t r,
                        deferred **dfr, size_t *ndfr)
{
    const vray *ray = &v->rays[r];
    size_t ns = (size_t)v->nsurf;
    int i, m;
    if (ray->st[M_MPFR] != SG_OK)
        v->nfail_ref++;
    /* A reference that could not aim or converge says nothing about the
     * ray, so the methods are not judged on it. */
    if (ref_broken(ray)) {
        v->nref_broken++;
    } else {
        for (m = 0; m < 2; m++) {
            if (ray->st[m] != ray->st[M_MPFR] || ray->fs[m] != ray->fs[M_MPFR])
                v->ndis[m]++;
            else if (ray->st[m] == SG_OK)
                v->ncmp[m]++;
        }
    }
    if (ray->st[M_MPFR] != SG_OK)
        return 0;
    for (i = 1; i < v->nsurf; i++) {
        sstat *s = &v->ss[i];
        const sg_ray_surface *b = &out[M_MPFR][k * ns + (size_t)i];
        double pb[3], db[3];
        point_of(b, pb);
        dir_of(b, db);
        s->scale = fmax(s->scale, max_abs3(pb));
        for (m = 0; m < 2; m++) {
            mstat *ms = &s->m[m];
            const sg_ray_surface *a = &out[m][k * ns + (size_t)i];
            double pa[3], da[3], e;
            if (ray->st[m] != SG_OK)
                continue;
            point_of(a, pa);
            dir_of(a, da);
            e = max_diff3(pa, pb);
            ms->dirmin = fmin(ms->dirmin, point_digits(da, db));
            ms->maxerr = fmax(ms->maxerr, e);
            if (max_abs3(pb) > 0.0) {
                double dg = point_digits(pa, pb);
                v->dig[m][(size_t)i * v->nray + ms->n++] = dg;
                take_worst(v, m, dg, e, r, i, a, b);
            } else {
                deferred *nd = realloc(*dfr, (*ndfr + 1) * sizeof *nd);
                if (!nd)
                    return -1;
                *dfr = nd;
                nd[*ndfr].ray = r;
                nd[*ndfr].surf = i;
                nd[*ndfr].m = m;
                nd[*ndfr].a = *a;
                nd[*ndfr].b = *b;
                (*ndfr)++;
            }
            if (m == M_PRECISE) {
                double ed = max_diff3(da, db);
                if (bound_fails(e, a->error_bound, b->error_bound) &&
                    add_violation(v, r, i, 0, e, a->error_bound, b->error_bound))
                    return -1;
                if (bound_fails(ed, a->dir_error_bound, b->dir_error_bound) &&
                    add_violation(v, r, i, 1, ed, a->dir_error_bound, b->dir_error_bound))
                    return -1;
                /* Bound over error, for the rays where the precise point
                 * differs from the reference at all. */
                if (e == 0.0)
                    s->nexact++;
                else
                    v->ratio[(size_t)i * v->nray + s->nratio++] = a->error_bound / e;
            }
        }
    }
    return 0;
}

/* The OPD of precise and classic against mpfr's, each against its own
 * reference sphere. */
static void opd_stats(vdesign *v)
{
    size_t r;
    int m;
    v->nopd = 0;
    v->opd_viol = 0;
    for (m = 0; m < 2; m++) {
        v->opd_maxdiff[m] = 0.0;
        v->opd_digits[m] = 17.0;
    }
    for (r = 0; r < v->nray; r++) {
        const vray *ray = &v->rays[r];
        const sg_opd *ref = &ray->opd[M_MPFR];
        if (ref->status != SG_OK || ray->opd[M_PRECISE].status != SG_OK ||
            ray->opd[M_CLASSIC].status != SG_OK)
            continue;
        v->nopd++;
        for (m = 0; m < 2; m++) {
            double e = fabs(ray->opd[m].opd_waves - ref->opd_waves);
            double dg = e > 0.0 ? -log10(e / fmax(fabs(ref->opd_waves), 1e-3)) : 17.0;
            v->opd_maxdiff[m] = fmax(v->opd_maxdiff[m], e);
            v->opd_digits[m] = fmin(v->opd_digits[m], fmin(17.0, fmax(0.0, dg)));
            if (m == M_PRECISE && !(e <= ray->opd[m].error_bound + ref->error_bound))
                v->opd_viol++;
        }
    }
}

/* Traces every ray with the three methods, a block at a time, and takes
 * the digits, bounds and worst rays as it goes.  Returns the exit status. */
static int vdesign_run(vdesign *v, const sg_catalog *cat)
{
    sg_tracer *t[NMETHOD] = { NULL, NULL, NULL };
    sg_ray_surface *out[NMETHOD] = { NULL, NULL, NULL };
    deferred *dfr = NULL;
    size_t ndfr = 0, blk, r0, k, ns = (size_t)v->nsurf;
    sg_opd_ref ref[NMETHOD];
    int have_ref[NMETHOD] = { 0, 0, 0 };
    sg_trace_opts o;
    sg_diag d;
    int i, m, rc = CLI_EXIT_OK;

    blk = VERIFY_BLOCK_ROWS / ns;
    /* As for trace --rays: a test sets the block to see its seams. */
    {
        const char *env = getenv("SAGITTA_RAYS_BLOCK");
        long b = env && env[0] ? strtol(env, NULL, 10) : 0;
        if (b >= 1 && b <= (1L << 24))
            blk = (size_t)b;
    }
    if (blk < 1)
        blk = 1;
    if (blk > v->nray)
        blk = v->nray;
    v->ss = calloc(ns, sizeof *v->ss);
    v->ray0 = calloc(NMETHOD * ns, sizeof *v->ray0);
    v->ratio = malloc(ns * v->nray * sizeof *v->ratio);
    for (m = 0; m < NMETHOD; m++)
        out[m] = malloc(blk * ns * sizeof *out[m]);
    for (m = 0; m < 2; m++)
        v->dig[m] = malloc(ns * v->nray * sizeof *v->dig[m]);
    if (!v->ss || !v->ray0 || !v->ratio || !out[0] || !out[1] || !out[2] || !v->dig[0] ||
        !v->dig[1])
        goto nomem;
    for (m = 0; m < 2; m++) {
        v->w[m].ray = -1;
        v->w[m].digits = INFINITY;
        v->w[m].err = -1.0;
    }
    for (i = 0; i < v->nsurf; i++)
        for (m = 0; m < 2; m++)
            v->ss[i].m[m].dirmin = DIGITS_CAP;

    for (m = 0; m < NMETHOD; m++) {
        sg_trace_opts_init(&o);
        o.method = mcode[m];
        o.mpfr_bits = v->bits;
        o.wave = v->wave0;
        sg_diag_clear(&d);
        int err = sg_tracer_open(v->sys, cat, &o, &t[m], &d);
        if (err != SG_OK) {
            const char *msg = d.msg[0] ? d.msg : sg_strerror(err);
            if (strstr(msg, v->path))
                cli_error("%s (%s method)", msg, mname[m]);
            else
                cli_error("%s: %s (%s method)", v->path, msg, mname[m]);
            rc = cli_exit_for(err);
            if (rc == CLI_EXIT_OK)
                rc = CLI_EXIT_INTERNAL;
            goto done;
        }
        /* The three tracers see the same design, so one set of warnings
         * is enough. */
        if (m == 0)
            cli_print_warnings(&d, v->path);
    }
    for (r0 = 0; r0 < v->nray; r0 += blk) {
        size_t nb = v->nray - r0 < blk ? v->nray - r0 : blk;
        for (k = 0; k < nb; k++) {
            vray *ray = &v->rays[r0 + k];
            for (m = 0; m < NMETHOD; m++) {
                sg_ray_surface *o1 = out[m] + k * ns;
                int st = sg_trace_normalized(t[m], ray->h[0], ray->h[1], ray->h[2],
                                             ray->h[3], o1);
                if (!sg_err_is_ray_status(st)) {
                    cli_error("%s: ray %g,%g,%g,%g: %s trace failed: %s", v->path,
                              ray->h[0], ray->h[1], ray->h[2], ray->h[3], mname[m],
                              sg_strerror(st));
                    rc = cli_exit_for(st);
                    if (rc == CLI_EXIT_OK)
                        rc = CLI_EXIT_INTERNAL;
                    goto done;
                }
                ray->st[m] = st;
                ray->fs[m] = st == SG_OK ? -1 : fail_surface(o1, v->nsurf);
                /* The OPD, each method against the sphere of its own chief ray. */
                if (!have_ref[m] || ref[m].hx != ray->h[0] || ref[m].hy != ray->h[1]) {
                    sg_opd_reference(t[m], ray->h[0], ray->h[1], &ref[m], NULL);
                    have_ref[m] = 1;
                }
                sg_opd_of_ray(t[m], &ref[m], &o1[v->nsurf - 1], &ray->opd[m]);
            }
        }
        if (r0 == 0)
            for (m = 0; m < NMETHOD; m++)
                memcpy(v->ray0 + (size_t)m * ns, out[m], ns * sizeof *out[m]);
        for (k = 0; k < nb; k++)
            if (vdesign_take(v, out, k, r0 + k, &dfr, &ndfr))
                goto nomem;
    }
    /* Points at the vertex, now that each surface's scale is known. */
    for (k = 0; k < ndfr; k++) {
        const deferred *x = &dfr[k];
        double pa[3], pb[3], dg;
        point_of(&x->a, pa);
        point_of(&x->b, pb);
        dg = point_digits_s(pa, pb, v->ss[x->surf].scale);
        v->dig[x->m][(size_t)x->surf * v->nray + v->ss[x->surf].m[x->m].n++] = dg;
        take_worst(v, x->m, dg, max_diff3(pa, pb), x->ray, x->surf, &x->a, &x->b);
    }
    for (i = 1; i < v->nsurf; i++) {
        sstat *s = &v->ss[i];
        double *ratio = v->ratio + (size_t)i * v->nray;
        for (m = 0; m < 2; m++) {
            mstat *ms = &s->m[m];
            double *dig = v->dig[m] + (size_t)i * v->nray;
            ms->dmin = min_of(dig, ms->n);
            ms->dmed = median(dig, ms->n);
            if (ms->n == 0)
                ms->dirmin = NAN;
        }
        s->rmin = min_of(ratio, s->nratio);
        s->rmed = median(ratio, s->nratio);
    }
    /* In the order a surface-by-surface scan finds them. */
    if (v->nviol > 1)
        qsort(v->viol, v->nviol, sizeof *v->viol, cmp_violation);
    opd_stats(v);
    goto done;
nomem:
    cli_error("out of memory for the statistics of %zu rays", v->nray);
    rc = CLI_EXIT_INTERNAL;
done:
    for (m = 0; m < NMETHOD; m++) {
        sg_tracer_free(t[m]);
        free(out[m]);
    }
    free(dfr);
    return rc;
}

static const char *surf_label(const vdesign *v, int i, char *buf, size_t n)
{
    if (i == v->nsurf - 1)
        snprintf(buf, n, "IMA");
    else if (i == 0)
        snprintf(buf, n, "OBJ");
    else if (i == v->sys->stop)
        snprintf(buf, n, "STO %d", i);
    else
        snprintf(buf, n, "%d", i);
    return buf;
}

static int precise_passes(const vdesign *v)
{
    return v->nviol == 0 && v->ndis[M_PRECISE] == 0;
}

/* Every ray was checked: the reference traced or truly stopped each one. */
static int complete(const vdesign *v)
{
    return v->nref_broken == 0;
}

static void text_fmt_num(char *buf, size_t n, double v, const char *fmt)
{
    if (isnan(v))
        snprintf(buf, n, "-");
    else if (isinf(v))
        snprintf(buf, n, "inf");
    else
        snprintf(buf, n, fmt, v);
}

static void text_ray(FILE *f, const vray *ray)
{
    fprintf(f, "Hx,Hy,Px,Py = %.17g,%.17g,%.17g,%.17g", ray->h[0], ray->h[1], ray->h[2],
            ray->h[3]);
}

static void text_status(FILE *f, const char *what, int st, int fs)
{
    if (st == SG_OK)
        fprintf(f, "%s OK", what);
    else if (fs >= 0)
        fprintf(f, "%s %s at surface %d", what, report_status_name(st), fs);
    else
        fprintf(f, "%s %s", what, report_status_name(st));
}

static void text_worst(FILE *f, const vdesign *v, int m)
{
    const worst *w = &v->w[m];
    const sg_ray_surface *a, *b;
    double pa[3], pb[3];
    char lab[32];
    if (w->ray < 0) {
        fprintf(f, "worst %s ray: none compared\n", mname[m]);
        return;
    }
    if (w->err == 0.0) {
        fprintf(f, "worst %s ray: none; every compared point equals mpfr's\n", mname[m]);
        return;
    }
    a = &v->wrow[m][0];
    b = &v->wrow[m][1];
    point_of(a, pa);
    point_of(b, pb);
    fprintf(f, "worst %s ray: ", mname[m]);
    text_ray(f, &v->rays[w->ray]);
    fprintf(f, ", surface %s, %.2f digits\n", surf_label(v, w->surf, lab, sizeof lab),
            w->digits);
    fprintf(f, "  %-8s x %-24.17g y %-24.17g z %.17g\n", mname[m], pa[0], pa[1], pa[2]);
    fprintf(f, "  %-8s x %-24.17g y %-24.17g z %.17g\n", "mpfr", pb[0], pb[1], pb[2]);
    fprintf(f, "  error %.3g", max_diff3(pa, pb));
    if (m == M_PRECISE)
        fprintf(f, ", bound %.3g", a->error_bound);
    else
        fprintf(f, ", estimate %.3g (not a bound)", a->error_bound);
    fputc('\n', f);
}

static void vdesign_text(FILE *f, const vdesign *v)
{
    char lab[32], c[8][32];
    size_t r, shown;
    int i, m;

    fputs("sagitta verify: ", f);
    safe_fputs(v->path, f);
    fputc('\n', f);
    fprintf(f, "wavelength %d (%.10g um); reference: mpfr at %d bits, same double inputs\n",
            v->wave0 + 1, v->sys->wave[v->wave0].um, v->bits);
    if (v->nfield)
        fprintf(f, "rays: %zu (%zu field point%s x %zu pupil points)", v->nray, v->nfield,
                v->nfield == 1 ? "" : "s", v->npupil);
    else
        fprintf(f, "rays: %zu", v->nray);
    fprintf(f, "; compared: precise %zu, classic %zu; failed in mpfr: %zu; "
               "disagreements: precise %zu, classic %zu\n",
            v->ncmp[0], v->ncmp[1], v->nfail_ref, v->ndis[0], v->ndis[1]);
    fputs("digits per coordinate: -log10(|a-b| / max(|b|, 1e-6 max|b_k|)), 17 when equal;\n"
          "a point's digits are the least over x, y, z (direction: l, m, n); a point at\n"
          "the vertex itself uses 1e-6 of the largest point on its surface instead.\n"
          "bound/error: the precise error bound over max |coordinate - mpfr|, over rays\n"
          "that differ from mpfr at all; 'exact' counts rays identical to mpfr.\n\n",
          f);
    fprintf(f, "%-8s | %-25s | %-25s | %s\n", "", "precise digits", "classic digits",
            "precise bound/error");
    fprintf(f, "%-8s | %7s %7s %9s | %7s %7s %9s | %9s %9s %6s\n", "surface", "min",
            "median", "dir min", "min", "median", "dir min", "min", "median", "exact");
    for (i = 1; i < v->nsurf; i++) {
        const sstat *s = &v->ss[i];
        for (m = 0; m < 2; m++) {
            text_fmt_num(c[3 * m], sizeof c[0], s->m[m].dmin, "%.2f");
            text_fmt_num(c[3 * m + 1], sizeof c[0], s->m[m].dmed, "%.2f");
            text_fmt_num(c[3 * m + 2], sizeof c[0], s->m[m].dirmin, "%.2f");
        }
        text_fmt_num(c[6], sizeof c[0], s->rmin, "%.3g");
        text_fmt_num(c[7], sizeof c[0], s->rmed, "%.3g");
        fprintf(f, "%-8s | %7s %7s %9s | %7s %7s %9s | %9s %9s %6zu\n",
                surf_label(v, i, lab, sizeof lab), c[0], c[1], c[2], c[3], c[4], c[5],
                c[6], c[7], s->nexact);
    }
    fputc('\n', f);
    text_worst(f, v, M_PRECISE);
    text_worst(f, v, M_CLASSIC);
    if (v->nopd) {
        /* The OPD of each method against mpfr's, in waves. */
        fprintf(f, "OPD (waves) over %zu rays: precise within %.3g of mpfr (%.2f digits), "
                   "classic within %.3g (%.2f digits)",
                v->nopd, v->opd_maxdiff[M_PRECISE], v->opd_digits[M_PRECISE],
                v->opd_maxdiff[M_CLASSIC], v->opd_digits[M_CLASSIC]);
        /* Not part of the verdict: precise's OPD bound covers its own
         * arithmetic on the double indices, and mpfr computes the indices
         * in MPFR; a glass path of 100 mm moves by 1e-14 mm with them. */
        fprintf(f, "; the precise OPD bound plus mpfr's falls short of it on %zu ray%s "
                   "(the bounds do not cover the indices' rounding to double)\n",
                v->opd_viol, v->opd_viol == 1 ? "" : "s");
    }

    if (v->nfail_ref) {
        fprintf(f, "\nrays the mpfr reference does not trace (not compared): %zu\n",
                v->nfail_ref);
        if (v->nref_broken)
            fprintf(f, "of these, the reference itself failed (it could not aim or "
                       "converge) on %zu; the methods were not checked there\n",
                    v->nref_broken);
        for (r = 0, shown = 0; r < v->nray; r++) {
            const vray *ray = &v->rays[r];
            if (ray->st[M_MPFR] == SG_OK)
                continue;
            if (shown++ == TEXT_LIST_MAX) {
                fprintf(f, "  ... and %zu more (see --format json)\n",
                        v->nfail_ref - TEXT_LIST_MAX);
                break;
            }
            fputs("  ", f);
            text_ray(f, ray);
            fputs(": ", f);
            text_status(f, "mpfr", ray->st[M_MPFR], ray->fs[M_MPFR]);
            fputs(", ", f);
            text_status(f, "precise", ray->st[M_PRECISE], ray->fs[M_PRECISE]);
            fputs(", ", f);
            text_status(f, "classic", ray->st[M_CLASSIC], ray->fs[M_CLASSIC]);
            fputc('\n', f);
        }
    }
    for (m = 0; m < 2; m++) {
        if (!v->ndis[m])
            continue;
        fprintf(f, "\n%s disagrees with mpfr on whether or where %zu ray%s stop:\n",
                mname[m], v->ndis[m], v->ndis[m] == 1 ? "" : "s");
        for (r = 0, shown = 0; r < v->nray; r++) {
            const vray *ray = &v->rays[r];
            if (ref_broken(ray) ||
                (ray->st[m] == ray->st[M_MPFR] && ray->fs[m] == ray->fs[M_MPFR]))
                continue;
            if (shown++ == TEXT_LIST_MAX) {
                fprintf(f, "  ... and %zu more (see --format json)\n",
                        v->ndis[m] - TEXT_LIST_MAX);
                break;
            }
            fputs("  ", f);
            text_ray(f, ray);
            fputs(": ", f);
            text_status(f, mname[m], ray->st[m], ray->fs[m]);
            fputs(", ", f);
            text_status(f, "mpfr", ray->st[M_MPFR], ray->fs[M_MPFR]);
            fputc('\n', f);
        }
    }
    if (v->nviol) {
        fprintf(f, "\nthe precise error bound is below the actual error %zu time%s:\n",
                v->nviol, v->nviol == 1 ? "" : "s");
        for (r = 0; r < v->nviol && r < TEXT_LIST_MAX; r++) {
            const violation *x = &v->viol[r];
            fprintf(f, "  surface %s, ", surf_label(v, x->surf, lab, sizeof lab));
            text_ray(f, &v->rays[x->ray]);
            fprintf(f, ": %s error %.3g > bound %.3g + reference bound %.3g\n",
                    x->dir ? "direction" : "point", x->err, x->bound, x->refbound);
        }
        if (v->nviol > TEXT_LIST_MAX)
            fprintf(f, "  ... and %zu more (see --format json)\n", v->nviol - TEXT_LIST_MAX);
    }
    if (!precise_passes(v))
        fputs("\nresult: FAIL: see above\n", f);
    else if (!complete(v))
        fprintf(f, "\nresult: INCOMPLETE: the precise error bound covers the actual error "
                   "on every ray checked, but the mpfr reference (%d bits) itself failed on "
                   "%zu ray%s, which %s not checked; that is the reference's failure, not "
                   "precise's\n",
                v->bits, v->nref_broken, v->nref_broken == 1 ? "" : "s",
                v->nref_broken == 1 ? "was" : "were");
    else
        fputs("\nresult: PASS: the precise error bound covers the actual error at every "
              "surface of every ray\n", f);
}

static void json_ray(jb *b, cJSON *obj, const vray *ray)
{
    cJSON *o = jobj(b, obj, "ray");
    static const char *const nm[4] = { "hx", "hy", "px", "py" };
    int k;
    if (!o)
        return;
    for (k = 0; k < 4; k++)
        jnum(b, o, nm[k], ray->h[k]);
}

static void json_status(jb *b, cJSON *obj, const char *name, int st, int fs)
{
    cJSON *o = jobj(b, obj, name);
    if (!o)
        return;
    jstr(b, o, "status", report_status_name(st));
    if (fs >= 0)
        jint(b, o, "surface", fs);
    else
        jput(b, o, "surface", cJSON_CreateNull());
}

static void json_worst(jb *b, cJSON *obj, const vdesign *v, int m)
{
    const worst *w = &v->w[m];
    const sg_ray_surface *a, *r;
    double pa[3], pb[3], da[3], db[3];
    cJSON *o;
    if (w->ray < 0) {
        jput(b, obj, mname[m], cJSON_CreateNull());
        return;
    }
    o = jobj(b, obj, mname[m]);
    if (!o)
        return;
    a = &v->wrow[m][0];
    r = &v->wrow[m][1];
    point_of(a, pa);
    point_of(r, pb);
    dir_of(a, da);
    dir_of(r, db);
    json_ray(b, o, &v->rays[w->ray]);
    jint(b, o, "surface", w->surf);
    jnum(b, o, "digits", w->digits);
    jnum(b, o, "dir_digits", point_digits(da, db));
    jvec3(b, o, "point", pa);
    jvec3(b, o, "reference", pb);
    jnum(b, o, "error", max_diff3(pa, pb));
    /* Classic's figure is an estimate, not a bound. */
    jnum(b, o, m == M_PRECISE ? "bound" : "estimate", a->error_bound);
    jnum(b, o, "reference_bound", r->error_bound);
}

static int vdesign_json(FILE *f, const vdesign *v)
{
    jb b = { 0 };
    cJSON *root = cJSON_CreateObject(), *o, *a, *e, *mo;
    size_t r;
    int i, m;

    if (!root) {
        cli_error("out of memory writing JSON");
        return CLI_EXIT_INTERNAL;
    }
    jstr(&b, root, "command", "verify");
    jstr(&b, root, "design", v->path);
    jint(&b, root, "wave_index", v->wave0 + 1);
    jnum(&b, root, "wave_um", v->sys->wave[v->wave0].um);
    o = jobj(&b, root, "reference");
    if (o) {
        jstr(&b, o, "method", "mpfr");
        jint(&b, o, "bits", v->bits);
    }
    jstr(&b, root, "digits_definition",
         "per coordinate -log10(|a-b| / max(|b|, 1e-6 * max_k |b_k|)), capped at 17 "
         "(equal); a point's digits are the minimum over x, y, z; direction digits "
         "likewise over l, m, n; a reference point at the origin (a vertex) uses "
         "1e-6 * the largest reference coordinate on its surface instead");
    o = jobj(&b, root, "rays");
    if (o) {
        jint(&b, o, "total", (long)v->nray);
        jint(&b, o, "field_points", (long)v->nfield);
        jint(&b, o, "pupil_points", (long)v->npupil);
        jint(&b, o, "compared_precise", (long)v->ncmp[0]);
        jint(&b, o, "compared_classic", (long)v->ncmp[1]);
        jint(&b, o, "failed_in_mpfr", (long)v->nfail_ref);
        jint(&b, o, "reference_failed", (long)v->nref_broken);
        jint(&b, o, "disagreements_precise", (long)v->ndis[0]);
        jint(&b, o, "disagreements_classic", (long)v->ndis[1]);
    }
    a = jarr(&b, root, "surfaces");
    for (i = 1; a && i < v->nsurf; i++) {
        const sstat *s = &v->ss[i];
        e = jput(&b, a, NULL, cJSON_CreateObject());
        if (!e)
            break;
        jint(&b, e, "surface", i);
        jbool(&b, e, "image", i == v->nsurf - 1);
        jbool(&b, e, "stop", i == v->sys->stop);
        for (m = 0; m < 2; m++) {
            mo = jobj(&b, e, mname[m]);
            if (!mo)
                continue;
            jint(&b, mo, "rays", (long)s->m[m].n);
            jnum(&b, mo, "digits_min", s->m[m].dmin);
            jnum(&b, mo, "digits_median", s->m[m].dmed);
            jnum(&b, mo, "dir_digits_min", s->m[m].dirmin);
            jnum(&b, mo, "max_error", s->m[m].n ? s->m[m].maxerr : NAN);
            if (m == M_PRECISE) {
                jnum(&b, mo, "bound_ratio_min", s->rmin);
                jnum(&b, mo, "bound_ratio_median", s->rmed);
                jint(&b, mo, "rays_with_error", (long)s->nratio);
                jint(&b, mo, "exact", (long)s->nexact);
            }
        }
    }
    o = jobj(&b, root, "worst");
    if (o) {
        json_worst(&b, o, v, M_PRECISE);
        json_worst(&b, o, v, M_CLASSIC);
    }
    o = jobj(&b, root, "opd");
    if (o) {
        jint(&b, o, "rays", (long)v->nopd);
        for (m = 0; m < 2; m++) {
            mo = jobj(&b, o, mname[m]);
            if (!mo)
                continue;
            jnum(&b, mo, "max_diff_waves", v->nopd ? v->opd_maxdiff[m] : NAN);
            jnum(&b, mo, "digits_min", v->nopd ? v->opd_digits[m] : NAN);
        }
        jint(&b, o, "precise_bound_violations", (long)v->opd_viol);
    }
    a = jarr(&b, root, "failed_in_mpfr");
    for (r = 0; a && r < v->nray; r++) {
        const vray *ray = &v->rays[r];
        if (ray->st[M_MPFR] == SG_OK)
            continue;
        e = jput(&b, a, NULL, cJSON_CreateObject());
        if (!e)
            break;
        json_ray(&b, e, ray);
        for (m = 0; m < NMETHOD; m++)
            json_status(&b, e, mname[m], ray->st[m], ray->fs[m]);
    }
    a = jarr(&b, root, "disagreements");
    for (r = 0; a && r < v->nray; r++) {
        const vray *ray = &v->rays[r];
        for (m = 0; m < 2; m++) {
            if (ref_broken(ray) ||
                (ray->st[m] == ray->st[M_MPFR] && ray->fs[m] == ray->fs[M_MPFR]))
                continue;
            e = jput(&b, a, NULL, cJSON_CreateObject());
            if (!e)
                break;
            jstr(&b, e, "method", mname[m]);
            json_ray(&b, e, ray);
            json_status(&b, e, mname[m], ray->st[m], ray->fs[m]);
            json_status(&b, e, "mpfr", ray->st[M_MPFR], ray->fs[M_MPFR]);
        }
    }
    a = jarr(&b, root, "bound_violations");
    for (r = 0; a && r < v->nviol; r++) {
        const violation *x = &v->viol[r];
        e = jput(&b, a, NULL, cJSON_CreateObject());
        if (!e)
            break;
        json_ray(&b, e, &v->rays[x->ray]);
        jint(&b, e, "surface", x->surf);
        jstr(&b, e, "what", x->dir ? "direction" : "point");
        jnum(&b, e, "error", x->err);
        jnum(&b, e, "bound", x->bound);
        jnum(&b, e, "reference_bound", x->refbound);
    }
    /* One ray is worth showing whole, so a user can see the numbers. */
    if (v->nray == 1) {
        a = jarr(&b, root, "points");
        for (i = 1; a && i < v->nsurf; i++) {
            e = jput(&b, a, NULL, cJSON_CreateObject());
            if (!e)
                break;
            jint(&b, e, "surface", i);
            for (m = 0; m < NMETHOD; m++) {
                const sg_ray_surface *s = &v->ray0[(size_t)m * (size_t)v->nsurf + (size_t)i];
                double p3[3];
                mo = jobj(&b, e, mname[m]);
                if (!mo)
                    continue;
                jstr(&b, mo, "status", report_status_name(s->status));
                point_of(s, p3);
                jvec3(&b, mo, "point", p3);
                dir_of(s, p3);
                jvec3(&b, mo, "direction", p3);
                jnum(&b, mo, "error_bound", s->error_bound);
            }
        }
    }
    jbool(&b, root, "pass", precise_passes(v) && complete(v));
    jbool(&b, root, "complete", complete(v));
    return jemit(&b, root, f);
}

int verify_design(const char *path, const double *ray4, int grid, int bits,
                         int wave1, int fmt, const char *output)
{
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    vdesign v;
    double (*fh)[2] = NULL, (*pp)[2] = NULL;
    size_t nf, np, a, b, r;
    int rc;
    vout out = { NULL, NULL };

    memset(&v, 0, sizeof v);
    rc = cli_load_design(path, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    rc = cli_check_wave(path, sys, wave1, &v.wave0);
    if (rc != CLI_EXIT_OK)
        goto done;
    v.path = path;
    v.sys = sys;
    v.bits = bits;
    v.nsurf = sys->nsurf;

    if (ray4) {
        v.nray = 1;
        v.rays = calloc(1, sizeof *v.rays);
        if (!v.rays)
            goto nomem;
        memcpy(v.rays[0].h, ray4, sizeof v.rays[0].h);
    } else {
        fh = malloc((size_t)(sys->nfield > 0 ? sys->nfield : 1) * sizeof *fh);
        pp = malloc(((size_t)grid * (size_t)grid + 5) * sizeof *pp);
        if (!fh || !pp)
            goto nomem;
        nf = field_points(sys, fh);
        np = pupil_points(grid, pp);
        v.nfield = nf;
        v.npupil = np;
        v.nray = nf * np;
        v.rays = calloc(v.nray, sizeof *v.rays);
        if (!v.rays)
            goto nomem;
        for (a = 0, r = 0; a < nf; a++)
            for (b = 0; b < np; b++, r++) {
                v.rays[r].h[0] = fh[a][0];
                v.rays[r].h[1] = fh[a][1];
                v.rays[r].h[2] = pp[b][0];
                v.rays[r].h[3] = pp[b][1];
            }
    }
    if (v.nray * (size_t)v.nsurf > MAX_RAY_SURFACES) {
        rc = cli_usage_error("verify", "%zu rays of %d surfaces are more than %d "
                             "ray-surfaces; use a smaller --grid", v.nray, v.nsurf,
                             MAX_RAY_SURFACES);
        goto done;
    }
    rc = vdesign_run(&v, cat);
    if (rc != CLI_EXIT_OK)
        goto done;
    rc = open_out(&out, output);
    if (rc != CLI_EXIT_OK)
        goto done;
    if (fmt == REPORT_JSON)
        rc = vdesign_json(out.f, &v);
    else
        vdesign_text(out.f, &v);
    if (rc == CLI_EXIT_OK && precise_passes(&v) && !complete(&v)) {
        cli_error("verify: %s: the mpfr reference (%d bits) failed on %zu ray%s (it could "
                  "not aim or converge), left unchecked; no fault of precise", path, v.bits,
                  v.nref_broken, v.nref_broken == 1 ? "" : "s");
        rc = CLI_EXIT_VERIFY;
    }
    if (rc == CLI_EXIT_OK && !precise_passes(&v)) {
        if (v.nviol)
            cli_error("verify: %s: the precise error bound is below the actual error "
                      "(%zu case%s; first at surface %d)",
                      path, v.nviol, v.nviol == 1 ? "" : "s", v.viol[0].surf);
        if (v.ndis[M_PRECISE])
            cli_error("verify: %s: the precise method stops %zu ray%s differently "
                      "from the mpfr reference",
                      path, v.ndis[M_PRECISE], v.ndis[M_PRECISE] == 1 ? "" : "s");
        rc = CLI_EXIT_VERIFY;
    }
    rc = close_out(&out, rc);
    goto done;
nomem:
    cli_error("out of memory for the ray set");
    rc = CLI_EXIT_INTERNAL;
done:
    free(fh);
    free(pp);
    vdesign_free(&v);
    cli_design_free(cat, sys);
    return rc;
}

