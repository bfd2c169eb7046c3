/*
 * huygens.c - the Huygens PSF of one field: spherical wavelets from each
 * traced ray's point on the reference sphere (the exit pupil), summed
 * with their exact path lengths at each point of an image grid, as
 * Zemax's Huygens PSF sums them.
 *
 * The rays are the FFT PSF's: the N x N grid over the normalized pupil,
 * those inside the unit circle that reach the image, each of equal
 * amplitude (a uniform entrance pupil: each ray carries the same power).
 * A ray k meets the reference sphere (centre C, the chief ray's image
 * point, radius R) at S_k with OPD W_k; its wavelet reaches the image
 * point P with the phase 2 pi (-W_k + n (|S_k - P| - R) / lambda) (the
 * sphere before the image; the sign turns for one behind it).  Unlike the
 * FFT PSF this keeps the exact distance (no Fraunhofer approximation), the
 * rays' true places on the sphere (pupil distortion) and the image plane
 * itself (the image surface's tangent plane at C, not the sphere's).
 * |S_k - P| - R is formed as q / (|S_k - P| + R), q = |S_k - C|^2 - R^2
 * - 2 (S_k - C).(P - C) + |P - C|^2, so no phase is lost to cancellation.
 */
#include <complex.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "analysis_int.h"
#include "trace.h"

#define HY_TWO_PI 6.283185307179586476925286766559

/* Minutes: a core sums some 2.4e7 wavelets a second (the double Gauss's
 * default Huygens PSF, 1.2e8 of them, takes 4.9 s). */
#define SG_HUYGENS_MAX_TERMS 1e10

/* One wavelength's wavelets: per ray, its place on the sphere relative to
 * C (lens units), |S - C|^2 - R^2, and its OPD (waves). */
typedef struct hy_rays {
    size_t n;
    double *sx, *sy, *sz, *e, *w;
    double radius, side, n_image, lambda; /* lambda in lens units */
    double strehl_exact;
} hy_rays;

static void hy_free(hy_rays *h)
{
    free(h->sx);
    free(h->sy);
    free(h->sz);
    free(h->e);
    free(h->w);
    memset(h, 0, sizeof *h);
}

/* Traces the grid's rays of one field at one wavelength to the reference
 * sphere. */
static int hy_trace(const sg_system *sys, const sg_catalog *cat, const sg_psf_opts *o, int wave,
                    hy_rays *h, sg_diag *d)
{
    sg_trace_opts to = o->trace;
    sg_tracer *t = NULL;
    sg_batch *b = NULL;
    sg_opd_ref ref;
    sg_ray_in *rays = NULL;
    sg_ray_surface *rows = NULL;
    sg_opd *res = NULL;
    int *st = NULL, last = sys->nsurf - 1, n = o->sampling, rc, i, j;
    size_t cap = (size_t)n * (size_t)n, nr = 0, k;
    double hx, hy, re = 0.0, im = 0.0;

    memset(h, 0, sizeof *h);
    sg_field_normalized(sys, o->field, &hx, &hy);
    to.wave = wave;
    if ((rc = sg_tracer_open(sys, cat, &to, &t, d)) != SG_OK)
        return rc;
    if ((rc = sg_opd_reference(t, hx, hy, &ref, d)) != SG_OK)
        goto done;
    if (ref.status != SG_OK) {
        rc = sg_diag_set(d, ref.status, "psf: field %d: the chief ray fails: %s", o->field + 1,
                         sg_strerror(ref.status));
        goto done;
    }
    rays = malloc(cap * sizeof *rays);
    rows = malloc(cap * sizeof *rows);
    st = malloc(cap * sizeof *st);
    res = malloc(cap * sizeof *res);
    h->sx = malloc(cap * sizeof *h->sx);
    h->sy = malloc(cap * sizeof *h->sy);
    h->sz = malloc(cap * sizeof *h->sz);
    h->e = malloc(cap * sizeof *h->e);
    h->w = malloc(cap * sizeof *h->w);
    if (!rays || !rows || !st || !res || !h->sx || !h->sy || !h->sz || !h->e || !h->w) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    /* The FFT PSF's pupil points: the grid inside the unit circle. */
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            double px = -1.0 + 2.0 * i / (n - 1), py = -1.0 + 2.0 * j / (n - 1);
            if (px * px + py * py > 1.0)
                continue;
            rays[nr].v[0] = hx;
            rays[nr].v[1] = hy;
            rays[nr].v[2] = px;
            rays[nr].v[3] = py;
            rays[nr].v[4] = rays[nr].v[5] = 0.0;
            nr++;
        }
    if ((rc = sg_batch_open(sys, cat, &to, o->nthreads, &b, d)) != SG_OK)
        goto done;
    if ((rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, nr, &last, 1, rows, st, d)) != SG_OK)
        goto done;
    sg_opd_of_rays(t, &ref, rows, 1, nr, res);
    h->radius = ref.radius;
    h->side = ref.side;
    h->n_image = ref.n_image;
    h->lambda = sys->wave[wave].um * sg_an_um_to_units(sys);
    for (k = 0; k < nr; k++) {
        const sg_opd *r = &res[k];
        double sx, sy, sz;
        if (st[k] != SG_OK || r->status != SG_OK || !isfinite(r->opd_waves))
            continue;
        sx = r->sphere_x - ref.cx;
        sy = r->sphere_y - ref.cy;
        sz = r->sphere_z - ref.cz;
        h->sx[h->n] = sx;
        h->sy[h->n] = sy;
        h->sz[h->n] = sz;
        h->e[h->n] = (sx * sx + sy * sy + sz * sz) - ref.radius * ref.radius;
        h->w[h->n] = r->opd_waves;
        re += cos(HY_TWO_PI * r->opd_waves);
        im += sin(HY_TWO_PI * r->opd_waves);
        h->n++;
    }
    if (h->n == 0) {
        rc = sg_diag_set(d, SG_EMISS, "psf: field %d, wavelength %d: no ray of the pupil "
                                      "reaches the image", o->field + 1, wave + 1);
        goto done;
    }
    re /= (double)h->n;
    im /= (double)h->n;
    h->strehl_exact = re * re + im * im;
    rc = SG_OK;
done:
    if (rc != SG_OK)
        hy_free(h);
    sg_batch_free(b);
    sg_tracer_free(t);
    free(rays);
    free(rows);
    free(st);
    free(res);
    return rc;
}

/* |sum of the wavelets|^2 / n^2 at image point (x, y) (lens units, from C,
 * in the image surface's plane). */
static double hy_at(const hy_rays *h, double x, double y)
{
    double re = 0.0, im = 0.0, p2 = x * x + y * y, r = h->radius, r2 = r * r;
    double k = -h->side * HY_TWO_PI * h->n_image / h->lambda;
    size_t i;
    for (i = 0; i < h->n; i++) {
        double q = h->e[i] - 2.0 * (h->sx[i] * x + h->sy[i] * y) + p2;
        double dist = sqrt(r2 + q), ph = -HY_TWO_PI * h->w[i] + k * (q / (dist + r));
        re += cos(ph);
        im += sin(ph);
    }
    return (re * re + im * im) / ((double)h->n * (double)h->n);
}

/* Rows j0 .. j1 - 1 of one wavelength's image, added with weight s. */
typedef struct hy_job {
    const hy_rays *h;
    double *acc, s, step;
    int g, c, j0, j1;
} hy_job;

static void *hy_rows(void *arg)
{
    hy_job *b = arg;
    int i, j;
    for (j = b->j0; j < b->j1; j++)
        for (i = 0; i < b->g; i++)
            b->acc[(size_t)j * b->g + i] +=
                b->s * hy_at(b->h, (i - b->c) * b->step, (j - b->c) * b->step);
    return NULL;
}

/* The image's rows on nt threads (each row's sum in the same order
 * whatever the threads, so the bits do not depend on them). */
static void hy_image(const hy_rays *h, double *acc, double s, double step, int g, int nt)
{
    hy_job jobs[64];
    pthread_t tid[64];
    int started[64] = {0}, t;
    if (nt < 1) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        nt = n > 0 ? (int)n : 1;
    }
    if (nt > 64)
        nt = 64;
    if (nt > g)
        nt = g;
    for (t = 0; t < nt; t++) {
        jobs[t] = (hy_job){h, acc, s, step, g, g / 2, g * t / nt, g * (t + 1) / nt};
        if (t > 0 && pthread_create(&tid[t], NULL, hy_rows, &jobs[t]) == 0)
            started[t] = 1;
        else if (t > 0)
            hy_rows(&jobs[t]);
    }
    hy_rows(&jobs[0]);
    for (t = 1; t < nt; t++)
        if (started[t])
            pthread_join(tid[t], NULL);
}

int sg_psf_huygens(const sg_system *sys, const sg_catalog *cat, const sg_psf_opts *o,
                   const int *waves, int nw, double fnum, double lmin, sg_psf *out, sg_diag *d)
{
    int g = o->image_size ? o->image_size : o->sampling, w, c = g / 2, rc;
    double delta = o->image_delta_um > 0.0 ? o->image_delta_um
                                           : lmin * fnum * (o->sampling - 1) / (2.0 * o->sampling);
    double units = sg_an_um_to_units(sys), norm = 0.0, snum = 0.0, *acc;
    double cost = (double)g * g * 0.785 * o->sampling * o->sampling * nw;
    size_t gg = (size_t)g * (size_t)g;

    /* Each image point sums every ray: a grid that would take hours is
     * refused rather than left running. */
    if (cost > SG_HUYGENS_MAX_TERMS)
        return sg_diag_set(d, SG_ERANGE, "psf: a Huygens PSF of %d x %d image points from a "
                                         "%d x %d pupil at %d wavelength(s) sums %.3g wavelets, "
                                         "more than %.3g: use fewer image points or a smaller "
                                         "sampling", g, g, o->sampling, o->sampling, nw, cost,
                           SG_HUYGENS_MAX_TERMS);
    acc = calloc(gg, sizeof *acc);
    if (!acc)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (w = 0; w < nw; w++) {
        double wt = nw > 1 ? sys->wave[waves[w]].weight : 1.0, um = sys->wave[waves[w]].um, s;
        hy_rays h;
        if (nw > 1 && wt <= 0.0)
            continue;
        if ((rc = hy_trace(sys, cat, o, waves[w], &h, d)) != SG_OK) {
            free(acc);
            return rc;
        }
        /* As the FFT PSF weighs them: unit energy times the weight, whose
         * unaberrated peak goes as the rays over lambda^2. */
        s = wt * (double)h.n / (um * um);
        norm += s;
        snum += s * h.strehl_exact;
        hy_image(&h, acc, s, delta * units, g, o->nthreads);
        hy_free(&h);
    }
    if (norm <= 0.0) {
        free(acc);
        return sg_diag_set(d, SG_ERANGE, "psf: every chosen wavelength has weight 0");
    }
    out->peak = 0.0;
    for (size_t k = 0; k < gg; k++) {
        acc[k] /= norm;
        if (acc[k] > out->peak)
            out->peak = acc[k];
    }
    out->field = o->field;
    out->sampling = o->sampling;
    out->method = SG_PSF_HUYGENS;
    out->size = g;
    out->spacing_x_um = out->spacing_y_um = delta;
    out->fnum = fnum;
    out->wave_um = lmin;
    out->strehl = acc[(size_t)c * g + c];
    out->strehl_exact = snum / norm;
    out->psf = acc;
    return SG_OK;
}
