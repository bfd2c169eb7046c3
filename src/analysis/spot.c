/*
 * spot.c - spot diagrams: rays of a pupil pattern traced to the image only
 * (the batch's surface selection), block by block, into running sums, so
 * a million-ray spot needs one block of memory.  RMS and centroid come
 * from sums taken relative to the reference chief ray, which keeps them
 * free of cancellation; the GEO radius about the centroid, not known until
 * the end, comes from the convex hull of the points, kept as it grows.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "analysis_int.h"
#include "trace.h"

int sg_an_select(int sel, int n, const char *what, int *idx, sg_diag *d)
{
    int k;
    if (sel >= n || sel < -1) {
        sg_diag_set(d, SG_ERANGE, "%s %d is not one of 1 to %d", what, sel + 1, n);
        return 0;
    }
    if (sel >= 0) {
        idx[0] = sel;
        return 1;
    }
    for (k = 0; k < n; k++)
        idx[k] = k;
    return n;
}

void sg_an_wave_order(const sg_system *sys, const int *waves, int nw, int refw,
                      int *wave_index, double *wave_um, int *order)
{
    int w, k, ri = 0;
    for (w = 0; w < nw; w++) {
        wave_index[w] = waves[w];
        wave_um[w] = sys->wave[waves[w]].um;
        if (waves[w] == refw)
            ri = w;
    }
    order[0] = ri;
    for (w = 0, k = 1; w < nw; w++)
        if (w != ri)
            order[k++] = w;
}

double sg_an_um_to_units(const sg_system *sys)
{
    if (strcmp(sys->units, "cm") == 0)
        return 1e-4;
    if (strcmp(sys->units, "in") == 0)
        return 1e-3 / 25.4;
    if (strcmp(sys->units, "m") == 0)
        return 1e-6;
    return 1e-3;
}

void sg_spot_opts_init(sg_spot_opts *o)
{
    memset(o, 0, sizeof *o);
    sg_trace_opts_init(&o->trace);
    o->pattern = SG_PUPIL_HEXAPOLAR;
    o->density = 6;
    o->reference = SG_SPOT_REF_CHIEF;
    o->wave = -1;
    o->field = -1;
    o->block = 65536;
    o->max_points = 0;
}

void sg_spot_free(sg_spot *s)
{
    int k;
    if (!s)
        return;
    for (k = 0; s->cell && k < s->nfield * s->nwave; k++)
        free(s->cell[k].pts);
    free(s->cell);
    s->cell = NULL;
}

/* ---- the convex hull, grown block by block ---------------------------- */

typedef struct hull {
    double (*p)[2];
    size_t n, cap;
} hull;

static int cmp_pt(const void *a, const void *b)
{
    const double *p = a, *q = b;
    if (p[0] != q[0])
        return p[0] < q[0] ? -1 : 1;
    return (p[1] > q[1]) - (p[1] < q[1]);
}

static double cross(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

/* Andrew's monotone chain over pts[0..n-1] (sorted in place); the hull goes
 * to out (room for n + 1 points); returns its size. */
static size_t monotone(double (*pts)[2], size_t n, double (*out)[2])
{
    size_t k = 0, i, lo;
    if (n < 3) {
        memcpy(out, pts, n * sizeof *pts);
        return n;
    }
    qsort(pts, n, sizeof *pts, cmp_pt);
    for (i = 0; i < n; i++) {
        while (k >= 2 && cross(out[k - 2], out[k - 1], pts[i]) <= 0.0)
            k--;
        memcpy(out[k++], pts[i], sizeof *pts);
    }
    lo = k + 1;
    for (i = n - 1; i-- > 0;) {
        while (k >= lo && cross(out[k - 2], out[k - 1], pts[i]) <= 0.0)
            k--;
        memcpy(out[k++], pts[i], sizeof *pts);
    }
    return k - 1;
}

/* Adds pts[0..n-1] to h, using work (room for n + h->n + 1 points twice).
 * Points strictly inside the octagon of the block's extreme points cannot
 * be on the hull and are dropped first (Akl and Toussaint), which leaves
 * little to sort. */
static int hull_add(hull *h, double (*pts)[2], size_t n, double (*work)[2])
{
    static const double dir[8][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1},
                                     {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    size_t ext[8] = {0}, i, m = 0, nh;
    int k;
    double (*out)[2];
    if (n == 0)
        return SG_OK;
    for (i = 1; i < n; i++)
        for (k = 0; k < 8; k++)
            if (dir[k][0] * pts[i][0] + dir[k][1] * pts[i][1] >
                dir[k][0] * pts[ext[k]][0] + dir[k][1] * pts[ext[k]][1])
                ext[k] = i;
    for (i = 0; i < n; i++) {
        int inside = 1;
        for (k = 0; k < 8 && inside; k++) {
            const double *a = pts[ext[k]], *b = pts[ext[(k + 1) % 8]];
            if (a[0] == b[0] && a[1] == b[1])
                continue;
            inside = cross(a, b, pts[i]) > 0.0;
        }
        if (!inside)
            memcpy(work[m++], pts[i], sizeof *pts);
    }
    if (h->n > 0) /* no hull yet: h->p may be NULL */
        memcpy(work + m, h->p, h->n * sizeof *h->p);
    m += h->n;
    out = work + m;
    nh = monotone(work, m, out);
    if (nh > h->cap) {
        size_t cap = nh * 2 + 16;
        double (*np)[2] = realloc(h->p, cap * sizeof *np);
        if (!np)
            return SG_ENOMEM;
        h->p = np;
        h->cap = cap;
    }
    memcpy(h->p, out, nh * sizeof *out);
    h->n = nh;
    return SG_OK;
}

/* ---- running sums ------------------------------------------------------ */

typedef struct acc {
    double sx, sy, s2; /* sums of dx, dy, dx^2 + dy^2 about the field's origin */
    double sb, sax, say; /* sums of the rays' error bounds, |dx| and |dy| */
    double max2;       /* largest dx^2 + dy^2 */
    size_t n;
    hull h;
} acc;

static size_t cell_index(const sg_spot *s, int f, int w)
{
    return (size_t)f * (size_t)s->nwave + (size_t)w;
}

int sg_spot_compute(const sg_system *sys, const sg_catalog *cat, const sg_spot_opts *o,
                    sg_spot *out, sg_diag *d)
{
    int waves[SG_MAX_WAVES], fields[SG_MAX_FIELDS], order[SG_MAX_WAVES];
    int nw, nf, refw, w, f, k, rc = SG_OK, last;
    size_t count, block, stride, i, traced = 0;
    sg_paraxial px;
    sg_ray_in *rays = NULL;
    sg_ray_surface *rows = NULL;
    int *st = NULL;
    double (*pup)[2] = NULL, (*pts)[2] = NULL, (*work)[2] = NULL;
    double origin[SG_MAX_FIELDS][2];
    acc *a = NULL;
    sg_batch *b = NULL;

    if (!sys || !o || !out)
        return sg_diag_set(d, SG_EINVAL, "spot: no system, options or result");
    memset(out, 0, sizeof *out);
    if (sg_pupil_check(o->pattern, o->density, d) != SG_OK)
        return d ? d->code : SG_ERANGE;
    if (o->reference != SG_SPOT_REF_CHIEF && o->reference != SG_SPOT_REF_CENTROID)
        return sg_diag_set(d, SG_EINVAL, "spot: unknown reference %d", o->reference);
    if ((rc = sg_system_validate(sys, cat, d)) != SG_OK)
        return rc;
    nw = sg_an_select(o->wave, sys->nwave, "wavelength", waves, d);
    nf = sg_an_select(o->field, sys->nfield, "field", fields, d);
    if (!nw || !nf)
        return SG_ERANGE;
    refw = o->wave >= 0 ? o->wave : sys->primary_wave;
    if ((rc = sg_paraxial_compute(sys, cat, refw, &px, d)) != SG_OK)
        return rc;
    count = sg_pupil_count(o->pattern, o->density);
    block = o->block ? o->block : 65536;
    stride = o->max_points ? (count + o->max_points - 1) / o->max_points : 0;

    out->nfield = nf;
    out->nwave = nw;
    out->nray_per_cell = count;
    /* An afocal image has no Airy disc on the image surface. */
    out->airy_radius = sys->afocal ? 0.0
                                   : 1.22 * sys->wave[refw].um * sg_an_um_to_units(sys) *
                                         px.working_fnum;
    /* The reference wavelength first: its chief rays are every cell's origin. */
    sg_an_wave_order(sys, waves, nw, refw, out->wave_index, out->wave_um, order);
    out->cell = calloc((size_t)nf * (size_t)nw, sizeof *out->cell);
    a = calloc((size_t)nf * (size_t)nw, sizeof *a);
    rays = malloc(block * sizeof *rays);
    rows = malloc(block * sizeof *rows);
    st = malloc(block * sizeof *st);
    pup = malloc(block * sizeof *pup);
    pts = malloc(block * sizeof *pts);
    if (!out->cell || !a || !rays || !rows || !st || !pup || !pts) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    for (f = 0; f < nf; f++) {
        out->field_index[f] = fields[f];
        sg_field_normalized(sys, fields[f], &out->field[f].hx, &out->field[f].hy);
        for (w = 0; w < nw && stride; w++) {
            sg_spot_cell *c = &out->cell[cell_index(out, f, w)];
            c->pts = malloc((count / stride + 1) * sizeof *c->pts);
            if (!c->pts) {
                rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
                goto done;
            }
        }
    }
    last = sys->nsurf - 1;
    for (k = 0; k < nw; k++) {
        sg_trace_opts to = o->trace;
        w = order[k];
        to.wave = waves[w];
        if ((rc = sg_batch_open(sys, cat, &to, o->nthreads, &b, d)) != SG_OK)
            goto done;
        /* Chief rays of every field at this wavelength, traced past the
         * apertures and obscurations as Zemax's reference is: a central
         * obscuration stops the pupil's centre, not the measure. */
        for (f = 0; f < nf; f++) {
            rays[f].v[0] = out->field[f].hx;
            rays[f].v[1] = out->field[f].hy;
            rays[f].v[2] = rays[f].v[3] = 0.0;
        }
        sg_batch_set_reference(b, 1);
        rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, (size_t)nf, &last, 1, rows, st, d);
        sg_batch_set_reference(b, 0);
        if (rc != SG_OK)
            goto done;
        for (f = 0; f < nf; f++) {
            sg_spot_cell *c = &out->cell[cell_index(out, f, w)];
            c->chief_x = st[f] == SG_OK ? sg_an_img_x(sys, &rows[f]) : 0.0;
            c->chief_y = st[f] == SG_OK ? sg_an_img_y(sys, &rows[f]) : 0.0;
            c->status = st[f];
            if (k == 0) {
                out->field[f].status = st[f];
                out->field[f].fail_surface = -1;
                origin[f][0] = c->chief_x;
                origin[f][1] = c->chief_y;
            }
        }
        /* A reference chief ray that fails is traced again to every
         * surface, so that the report can name where it failed. */
        for (f = 0; k == 0 && f < nf; f++)
            if (st[f] != SG_OK && (size_t)sys->nsurf <= block) {
                sg_diag d1;
                int s1, st1;
                sg_diag_clear(&d1);
                sg_batch_set_reference(b, 1);
                if (sg_batch_trace(b, SG_RAYS_NORMALIZED, &rays[f], 1, NULL, 0, rows, &st1,
                                   &d1) == SG_OK)
                    for (s1 = 0; s1 < sys->nsurf; s1++)
                        if (rows[s1].status != SG_OK) {
                            out->field[f].fail_surface = s1;
                            break;
                        }
                sg_batch_set_reference(b, 0);
            }
        for (f = 0; f < nf; f++) {
            sg_spot_cell *c = &out->cell[cell_index(out, f, w)];
            acc *ac = &a[cell_index(out, f, w)];
            size_t cursor = 0, got, seq = 0;
            if (out->field[f].status != SG_OK) {
                c->status = out->field[f].status;
                continue;
            }
            c->status = SG_OK;
            while ((got = sg_pupil_fill(o->pattern, o->density, &cursor, pup, block)) > 0) {
                size_t m = 0;
                double bx = 0.0, by = 0.0, b2 = 0.0;
                for (i = 0; i < got; i++) {
                    rays[i].v[0] = out->field[f].hx;
                    rays[i].v[1] = out->field[f].hy;
                    rays[i].v[2] = pup[i][0];
                    rays[i].v[3] = pup[i][1];
                }
                if ((rc = sg_batch_trace(b, SG_RAYS_NORMALIZED, rays, got, &last, 1, rows, st,
                                         d)) != SG_OK)
                    goto done;
                for (i = 0; i < got; i++, seq++) {
                    double dx, dy, r2;
                    c->nray++;
                    if (st[i] != SG_OK)
                        continue;
                    dx = sg_an_img_x(sys, &rows[i]) - origin[f][0];
                    dy = sg_an_img_y(sys, &rows[i]) - origin[f][1];
                    r2 = dx * dx + dy * dy;
                    bx += dx;
                    by += dy;
                    ac->sb += sys->afocal ? rows[i].dir_error_bound : rows[i].error_bound;
                    ac->sax += fabs(dx);
                    ac->say += fabs(dy);
                    b2 += r2;
                    if (r2 > ac->max2)
                        ac->max2 = r2;
                    pts[m][0] = dx;
                    pts[m][1] = dy;
                    m++;
                    if (stride && seq % stride == 0) {
                        c->pts[c->npts][0] = dx;
                        c->pts[c->npts][1] = dy;
                        c->npts++;
                    }
                }
                /* Sums of a block first, then into the total: less rounding. */
                ac->sx += bx;
                ac->sy += by;
                ac->s2 += b2;
                ac->n += m;
                traced += got;
                if (o->progress &&
                    o->progress(o->progress_ctx, traced, count * (size_t)nf * (size_t)nw)) {
                    rc = sg_diag_set(d, SG_ESTOPPED, "spot: stopped after %zu of %zu rays",
                                     traced, count * (size_t)nf * (size_t)nw);
                    goto done;
                }
                if (o->reference == SG_SPOT_REF_CENTROID) {
                    double (*nw2)[2] = realloc(work, 2 * (m + ac->h.n + 1) * sizeof *work);
                    if (!nw2) {
                        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
                        goto done;
                    }
                    work = nw2;
                    if ((rc = hull_add(&ac->h, pts, m, work)) != SG_OK) {
                        sg_diag_set(d, rc, "out of memory");
                        goto done;
                    }
                }
            }
            c->nok = ac->n;
        }
        sg_batch_free(b);
        b = NULL;
    }

    /* Centroids, the reference point and the radii about it. */
    for (f = 0; f < nf; f++) {
        sg_spot_field *fd = &out->field[f];
        double wsum = 0.0, wsx = 0.0, wsy = 0.0, cx = 0.0, cy = 0.0, w2 = 0.0;
        double wbx = 0.0, wby = 0.0;
        int equal = 1;
        if (fd->status != SG_OK)
            continue;
        for (w = 0; w < nw; w++)
            if (sys->wave[waves[w]].weight > 0.0)
                equal = 0;
        for (w = 0; w < nw; w++) {
            acc *ac = &a[cell_index(out, f, w)];
            sg_spot_cell *c = &out->cell[cell_index(out, f, w)];
            double wt = equal ? 1.0 : sys->wave[waves[w]].weight;
            if (ac->n) {
                /* The rays' mean error, and the rounding of each difference,
                 * sum (at most n + 2 roundings of |dx| each, Higham's
                 * gamma_n), division and the origin's addition. */
                double n = (double)ac->n, g = (n + 4.0) * 0x1p-53 / (1.0 - (n + 4.0) * 0x1p-53);
                c->centroid_x = origin[f][0] + ac->sx / n;
                c->centroid_y = origin[f][1] + ac->sy / n;
                c->centroid_bound_x = (ac->sb + g * ac->sax) / n * (1.0 + 0x1p-50) +
                                      0x1p-52 * fabs(c->centroid_x);
                c->centroid_bound_y = (ac->sb + g * ac->say) / n * (1.0 + 0x1p-50) +
                                      0x1p-52 * fabs(c->centroid_y);
            }
            wsum += wt * (double)ac->n;
            wsx += wt * ac->sx;
            wsy += wt * ac->sy;
            wbx += wt * (ac->sb + ac->sax * (double)(ac->n + 4) * 0x1p-53);
            wby += wt * (ac->sb + ac->say * (double)(ac->n + 4) * 0x1p-53);
        }
        if (wsum > 0.0) {
            cx = wsx / wsum;
            cy = wsy / wsum;
        }
        fd->centroid_x = origin[f][0] + cx;
        fd->centroid_y = origin[f][1] + cy;
        /* The weighted sums add nw more roundings of terms already counted. */
        if (wsum > 0.0) {
            fd->centroid_bound_x = (wbx * (1.0 + (nw + 4) * 0x1p-52)) / wsum * (1.0 + 0x1p-50) +
                                   0x1p-52 * (fabs(fd->centroid_x) + fabs(cx));
            fd->centroid_bound_y = (wby * (1.0 + (nw + 4) * 0x1p-52)) / wsum * (1.0 + 0x1p-50) +
                                   0x1p-52 * (fabs(fd->centroid_y) + fabs(cy));
        }
        if (o->reference == SG_SPOT_REF_CHIEF)
            cx = cy = 0.0;
        fd->ref_x = origin[f][0] + cx;
        fd->ref_y = origin[f][1] + cy;
        for (w = 0; w < nw; w++) {
            acc *ac = &a[cell_index(out, f, w)];
            sg_spot_cell *c = &out->cell[cell_index(out, f, w)];
            double wt = equal ? 1.0 : sys->wave[waves[w]].weight, s2, g2 = 0.0;
            /* sum |p - c|^2 = sum |p|^2 - 2 c.sum p + n |c|^2, all about the origin. */
            s2 = ac->s2 - 2.0 * (cx * ac->sx + cy * ac->sy) +
                 (double)ac->n * (cx * cx + cy * cy);
            if (s2 < 0.0)
                s2 = 0.0;
            if (o->reference == SG_SPOT_REF_CHIEF) {
                g2 = ac->max2;
            } else {
                for (i = 0; i < ac->h.n; i++) {
                    double dx = ac->h.p[i][0] - cx, dy = ac->h.p[i][1] - cy;
                    if (dx * dx + dy * dy > g2)
                        g2 = dx * dx + dy * dy;
                }
            }
            c->rms = ac->n ? sqrt(s2 / (double)ac->n) : 0.0;
            c->geo = sqrt(g2);
            for (i = 0; i < c->npts; i++) {
                c->pts[i][0] -= cx;
                c->pts[i][1] -= cy;
            }
            w2 += wt * s2;
            if (c->geo > fd->geo)
                fd->geo = c->geo;
        }
        fd->rms = wsum > 0.0 ? sqrt(w2 / wsum) : 0.0;
    }

done:
    sg_batch_free(b);
    for (i = 0; a && i < (size_t)nf * (size_t)nw; i++)
        free(a[i].h.p);
    free(a);
    free(rays);
    free(rows);
    free(st);
    free(pup);
    free(pts);
    free(work);
    if (rc != SG_OK)
        sg_spot_free(out);
    return rc;
}
