/*
 * frame.c - frame changes between surfaces: Zemax's coordinate breaks and
 * surface tilts and decenters, composed in MPFR into one transfer per
 * surface, and the global frames built from them.
 *
 * A frame change maps a point given in the new frame to the old one:
 * p_old = A p_new + b.  The transfer into surface i composes surface i-1's
 * after change, the thickness along that frame's z, and surface i's before
 * change; the trace then takes p_i = A^T (p_{i-1} - b).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model_int.h"

int sg_frame_change_is_zero(const sg_frame_change *c)
{
    return c->dx == 0.0 && c->dy == 0.0 && c->tx == 0.0 && c->ty == 0.0 && c->tz == 0.0;
}

int sg_surface_moves_frame(const sg_surface *s)
{
    if (s->type == SG_SURF_COORDBRK)
        return !sg_frame_change_is_zero(&s->before);
    if (!sg_frame_change_is_zero(&s->before))
        return 1;
    return s->after_mode == SG_AFTER_EXPLICIT && !sg_frame_change_is_zero(&s->after);
}

typedef struct mxf {
    mpfr_t A[3][3];
    mpfr_t b[3];
} mxf;

static void mxf_init(mxf *m, mpfr_prec_t prec)
{
    int i, j;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) {
            mpfr_init2(m->A[i][j], prec);
            mpfr_set_ui(m->A[i][j], i == j, MPFR_RNDN);
        }
        mpfr_init2(m->b[i], prec);
        mpfr_set_zero(m->b[i], 1);
    }
}

static void mxf_clear(mxf *m)
{
    int i, j;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++)
            mpfr_clear(m->A[i][j]);
        mpfr_clear(m->b[i]);
    }
}

/* m = m * r for a 3x3 r (m's b untouched). */
static void mul_right(mxf *m, mpfr_t r[3][3], mpfr_t *tmp)
{
    mpfr_t *row = tmp; /* tmp[0..3] */
    int i, j, k;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) {
            mpfr_set_zero(row[j], 1);
            for (k = 0; k < 3; k++)
                mpfr_fma(row[j], m->A[i][k], r[k][j], row[j], MPFR_RNDN);
        }
        for (j = 0; j < 3; j++)
            mpfr_set(m->A[i][j], row[j], MPFR_RNDN);
    }
}

/* The right-handed rotation about axis ax (0 x, 1 y, 2 z) by deg degrees.
 * mpfr_cosu and mpfr_sinu take the angle in degrees exactly, so 90 and
 * 180 degrees give exact zeros and ones. */
static void axis_rot(mpfr_t r[3][3], int ax, double deg)
{
    mpfr_prec_t prec = mpfr_get_prec(r[0][0]);
    mpfr_t a, c, s;
    int i, j, u = (ax + 1) % 3, v = (ax + 2) % 3;
    mpfr_inits2(prec, a, c, s, (mpfr_ptr)0);
    mpfr_set_d(a, deg, MPFR_RNDN);
    mpfr_cosu(c, a, 360, MPFR_RNDN);
    mpfr_sinu(s, a, 360, MPFR_RNDN);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            mpfr_set_ui(r[i][j], i == j, MPFR_RNDN);
    /* In the (u, v) plane: [c -s; s c]. */
    mpfr_set(r[u][u], c, MPFR_RNDN);
    mpfr_set(r[v][v], c, MPFR_RNDN);
    mpfr_neg(r[u][v], s, MPFR_RNDN);
    mpfr_set(r[v][u], s, MPFR_RNDN);
    mpfr_clears(a, c, s, (mpfr_ptr)0);
}

/* m = m o change: p_old = A_m (A_c p + b_c) + b_m.  inverse applies the
 * change that undoes c. */
static void compose_change(mxf *m, const sg_frame_change *c, int inverse, mpfr_t *tmp)
{
    mpfr_prec_t prec = mpfr_get_prec(m->b[0]);
    mxf ch;
    mpfr_t r[3][3], d[3];
    double ang[3] = {c->tx, c->ty, c->tz};
    int i, j, k, order = c->order ? 1 : 0;
    if (sg_frame_change_is_zero(c))
        return;
    mxf_init(&ch, prec);
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++)
            mpfr_init2(r[i][j], prec);
        mpfr_init2(d[i], prec);
    }
    if (inverse) {
        /* Undone by the other order with every value negated. */
        order = !order;
        for (i = 0; i < 3; i++)
            ang[i] = -ang[i];
    }
    mpfr_set_d(d[0], inverse ? -c->dx : c->dx, MPFR_RNDN);
    mpfr_set_d(d[1], inverse ? -c->dy : c->dy, MPFR_RNDN);
    mpfr_set_zero(d[2], 1);
    /* Order 0: A = Rx Ry Rz (x, then the new y, then the new z), b = d.
     * Order 1: A = Rz Ry Rx, and the decenter is along the new axes. */
    for (k = 0; k < 3; k++) {
        int ax = order == 0 ? k : 2 - k;
        if (ang[ax] == 0.0)
            continue;
        axis_rot(r, ax, ang[ax]);
        mul_right(&ch, r, tmp);
    }
    if (order == 0) {
        for (i = 0; i < 3; i++)
            mpfr_set(ch.b[i], d[i], MPFR_RNDN);
    } else {
        for (i = 0; i < 3; i++) {
            mpfr_set_zero(ch.b[i], 1);
            for (k = 0; k < 3; k++)
                mpfr_fma(ch.b[i], ch.A[i][k], d[k], ch.b[i], MPFR_RNDN);
        }
    }
    /* b = A_m b_c + b_m, then A = A_m A_c. */
    for (i = 0; i < 3; i++) {
        mpfr_set(tmp[i], m->b[i], MPFR_RNDN);
        for (k = 0; k < 3; k++)
            mpfr_fma(tmp[i], m->A[i][k], ch.b[k], tmp[i], MPFR_RNDN);
    }
    for (i = 0; i < 3; i++)
        mpfr_set(m->b[i], tmp[i], MPFR_RNDN);
    mul_right(m, ch.A, tmp);
    mxf_clear(&ch);
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++)
            mpfr_clear(r[i][j]);
        mpfr_clear(d[i]);
    }
}

/* m = m o (a step of t along z). */
static void compose_z(mxf *m, double t, mpfr_t *tmp)
{
    int i;
    mpfr_set_d(tmp[3], t, MPFR_RNDN);
    for (i = 0; i < 3; i++) {
        mpfr_mul(tmp[i], m->A[i][2], tmp[3], MPFR_RNDN);
        mpfr_add(m->b[i], m->b[i], tmp[i], MPFR_RNDN);
    }
}

double sg_launch_step(const sg_system *sys)
{
    return sys->surf[0].thickness == 0.0 ? 1.0 : 0.0;
}

/* The transfer into surface i (i >= 1) from surface i-1's frame.  Into
 * surface 1 it is from the launch frame, at surface 1's place before its
 * own change (rays are launched there, launch.c; sg_launch_step beyond it
 * for an object on that place): back that step, then that change, as
 * Zemax's coordinate break or tilt on surface 1 turns what follows the
 * object, not the object. */
static void xfer(const sg_system *sys, int i, mxf *m, mpfr_t *tmp)
{
    const sg_surface *p = &sys->surf[i - 1], *s = &sys->surf[i];
    if (i == 1) {
        if (sg_launch_step(sys) != 0.0)
            compose_z(m, -sg_launch_step(sys), tmp);
        compose_change(m, &s->before, 0, tmp);
        return;
    }
    if (p->type != SG_SURF_COORDBRK) {
        if (p->after_mode == SG_AFTER_REVERSE)
            compose_change(m, &p->before, 1, tmp);
        else
            compose_change(m, &p->after, 0, tmp);
    }
    compose_z(m, p->thickness, tmp);
    compose_change(m, &s->before, 0, tmp);
}

int sg_xfer_moves(const sg_system *sys, int i)
{
    const sg_surface *p = &sys->surf[i - 1], *s = &sys->surf[i];
    if (!sg_frame_change_is_zero(&s->before))
        return 1;
    if (i == 1)
        return sg_launch_step(sys) != 0.0;
    if (p->type == SG_SURF_COORDBRK)
        return 0;
    if (p->after_mode == SG_AFTER_REVERSE)
        return !sg_frame_change_is_zero(&p->before);
    return !sg_frame_change_is_zero(&p->after);
}

int sg_xfer_mpfr(const sg_system *sys, int i, mpfr_t A[3][3], mpfr_t b[3])
{
    mpfr_prec_t prec = mpfr_get_prec(b[0]) + 32;
    mxf m;
    mpfr_t tmp[4];
    int j, k;
    mxf_init(&m, prec);
    for (j = 0; j < 4; j++)
        mpfr_init2(tmp[j], prec);
    xfer(sys, i, &m, tmp);
    for (j = 0; j < 3; j++) {
        for (k = 0; k < 3; k++)
            mpfr_set(A[j][k], m.A[j][k], MPFR_RNDN);
        mpfr_set(b[j], m.b[j], MPFR_RNDN);
    }
    mxf_clear(&m);
    for (j = 0; j < 4; j++)
        mpfr_clear(tmp[j]);
    return SG_OK;
}

int sg_global_frames(const sg_system *sys, int ref, sg_frame *out, sg_diag *d)
{
    const mpfr_prec_t prec = 256;
    mxf *g, lf;
    mpfr_t tmp[4];
    int i, j, k, n = sys->nsurf;
    if (ref < 0 || ref >= n)
        return sg_diag_set(d, SG_ERANGE, "global reference surface %d is not one of 0 to %d",
                           ref, n - 1);
    if (ref == 0 && !isfinite(sys->surf[0].thickness))
        return sg_diag_set(d, SG_ERANGE,
                           "global reference surface 0: the object is at infinity");
    /* Surface 1 as the reference is the launch frame, at its place before
     * its own change: the object's axis, also where surface 1 is a break. */
    if (sys->surf[ref].type == SG_SURF_COORDBRK && ref != 1)
        return sg_diag_set(d, SG_ERANGE,
                           "global reference surface %d is a coordinate break", ref);
    g = calloc((size_t)n, sizeof *g);
    if (!g)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    for (j = 0; j < 4; j++)
        mpfr_init2(tmp[j], prec);
    for (i = 0; i < n; i++)
        mxf_init(&g[i], prec);
    /* Relative to the launch frame first (surface 1's, unless surface 1
     * turns or moves what follows it): G_i = G_{i-1} o X_i. */
    for (i = sg_xfer_moves(sys, 1) ? 1 : 2; i < n; i++) {
        for (j = 0; j < 3; j++) {
            for (k = 0; k < 3; k++)
                mpfr_set(g[i].A[j][k], g[i - 1].A[j][k], MPFR_RNDN);
            mpfr_set(g[i].b[j], g[i - 1].b[j], MPFR_RNDN);
        }
        xfer(sys, i, &g[i], tmp);
    }
    /* The object and surface 1's place, in the launch frame. */
    mxf_init(&lf, prec);
    mpfr_set_d(lf.b[2], -sg_launch_step(sys), MPFR_RNDN);
    if (isfinite(sys->surf[0].thickness))
        mpfr_sub_d(g[0].b[2], lf.b[2], sys->surf[0].thickness, MPFR_RNDN);
    else
        mpfr_set_inf(g[0].b[2], -1);
    for (i = 0; i < n; i++) {
        const mxf *r = ref == 1 ? &lf : &g[ref];
        for (j = 0; j < 3; j++) {
            double o;
            /* Relative to ref: R_ref^T (R_i p + o_i - o_ref). */
            mpfr_set_zero(tmp[3], 1);
            for (k = 0; k < 3; k++) {
                mpfr_sub(tmp[0], g[i].b[k], r->b[k], MPFR_RNDN);
                mpfr_fma(tmp[3], r->A[k][j], tmp[0], tmp[3], MPFR_RNDN);
            }
            o = mpfr_get_d(tmp[3], MPFR_RNDN);
            out[i].o[j] = i == 0 && !isfinite(sys->surf[0].thickness) ? NAN : o;
            for (k = 0; k < 3; k++) {
                int q;
                mpfr_set_zero(tmp[1], 1);
                for (q = 0; q < 3; q++)
                    mpfr_fma(tmp[1], r->A[q][j], g[i].A[q][k], tmp[1], MPFR_RNDN);
                out[i].R[j][k] = mpfr_get_d(tmp[1], MPFR_RNDN);
            }
        }
    }
    for (i = 0; i < n; i++)
        mxf_clear(&g[i]);
    mxf_clear(&lf);
    for (j = 0; j < 4; j++)
        mpfr_clear(tmp[j]);
    free(g);
    return SG_OK;
}

void sg_row_to_global(const sg_frame *f, sg_ray_surface *row)
{
    double p[3] = {row->x, row->y, row->z}, u[3] = {row->l, row->m, row->n};
    double q[3], v[3], grow = 0.0, big = 0.0;
    int j;
    for (j = 0; j < 3; j++) {
        double s = fabs(f->R[j][0]) + fabs(f->R[j][1]) + fabs(f->R[j][2]);
        /* Each sum in double-double-free double: R p + o with fma. */
        q[j] = fma(f->R[j][0], p[0], fma(f->R[j][1], p[1], fma(f->R[j][2], p[2], f->o[j])));
        v[j] = fma(f->R[j][0], u[0], fma(f->R[j][1], u[1], f->R[j][2] * u[2]));
        grow = fmax(grow, s);
        big = fmax(big, s * fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2]))) + fabs(f->o[j]));
    }
    row->x = q[0];
    row->y = q[1];
    row->z = q[2];
    row->l = v[0];
    row->m = v[1];
    row->n = v[2];
    /* R and o are rounded (half an ulp each entry) and the sums round at
     * each of four steps: 6u of the terms' size bounds both. */
    row->error_bound = grow * row->error_bound + 6.0 * 0x1p-53 * big;
    row->dir_error_bound = grow * row->dir_error_bound + 6.0 * 0x1p-53 * grow;
}

void sg_rows_to_global(const sg_frame *gf, sg_ray_surface *rows, size_t nray, int nsurf,
                       int start_dir)
{
    size_t r;
    int i;
    for (r = 0; r < nray; r++)
        for (i = 0; i < nsurf; i++) {
            sg_ray_surface *o = &rows[r * (size_t)nsurf + (size_t)i];
            const sg_frame *f = &gf[i == 0 && start_dir ? 1 : i];
            if (isfinite(o->x) && isfinite(o->y) && isfinite(o->z) && isfinite(f->o[2]))
                sg_row_to_global(f, o);
        }
}
