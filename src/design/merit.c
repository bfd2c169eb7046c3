/*
 * merit.c - Zemax's merit function: its operands and its default part
 * (sagitta-design(5), MERIT FUNCTION; sagitta(1), OPTIMIZATION).
 *
 * MF^2 = sum w (v - t)^2 / sum w over the rows of nonzero weight.  The
 * default part is transverse x and y of rays about the centroid or the
 * chief ray, the pupil sampled by Gaussian quadrature in rings and arms
 * (Forbes, JOSA A 5, 1943 (1988)).  A row that cannot be computed is an
 * error naming it, never a NaN.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "design.h"
#include "trace.h"

#define PI 3.14159265358979323846

#define FP {"hx", "hy", "px", "py"}
#define F_ {"hx", "hy", NULL, NULL}
#define NO {NULL, NULL, NULL, NULL}
static const sg_op_info ops[SG_OP_NTYPES] = {
    [SG_OP_BLNK] = {"BLNK", NULL, NULL, NO},
    [SG_OP_EFFL] = {"EFFL", NULL, "wave", NO},
    [SG_OP_TOTR] = {"TOTR", NULL, NULL, NO},
    [SG_OP_TTHI] = {"TTHI", "surf1", "surf2", NO},
    [SG_OP_CTGT] = {"CTGT", "surf", NULL, NO},
    [SG_OP_CTLT] = {"CTLT", "surf", NULL, NO},
    [SG_OP_CTVA] = {"CTVA", "surf", NULL, NO},
    [SG_OP_ETGT] = {"ETGT", "surf", NULL, NO},
    [SG_OP_ETLT] = {"ETLT", "surf", NULL, NO},
    [SG_OP_ETVA] = {"ETVA", "surf", NULL, NO},
    [SG_OP_MNCT] = {"MNCT", "surf1", "surf2", NO},
    [SG_OP_MXCT] = {"MXCT", "surf1", "surf2", NO},
    [SG_OP_MNET] = {"MNET", "surf1", "surf2", NO},
    [SG_OP_MNCA] = {"MNCA", "surf1", "surf2", NO},
    [SG_OP_MXCA] = {"MXCA", "surf1", "surf2", NO},
    [SG_OP_MNCG] = {"MNCG", "surf1", "surf2", NO},
    [SG_OP_MXCG] = {"MXCG", "surf1", "surf2", NO},
    [SG_OP_REAX] = {"REAX", "surf", "wave", FP},
    [SG_OP_REAY] = {"REAY", "surf", "wave", FP},
    [SG_OP_REAZ] = {"REAZ", "surf", "wave", FP},
    [SG_OP_TRAX] = {"TRAX", NULL, "wave", FP},
    [SG_OP_TRAY] = {"TRAY", NULL, "wave", FP},
    [SG_OP_TRAR] = {"TRAR", NULL, "wave", FP},
    [SG_OP_RSCE] = {"RSCE", "rings", "wave", F_},
    [SG_OP_RSCH] = {"RSCH", "rings", "wave", F_},
    [SG_OP_SUMM] = {"SUMM", "op1", "op2", NO},
    [SG_OP_DIFF] = {"DIFF", "op1", "op2", NO},
    [SG_OP_PROD] = {"PROD", "op1", "op2", NO},
    [SG_OP_DIVI] = {"DIVI", "op1", "op2", NO},
    [SG_OP_CONS] = {"CONS", NULL, NULL, NO},
    [SG_OP_OPGT] = {"OPGT", "op1", NULL, NO},
    [SG_OP_OPLT] = {"OPLT", "op1", NULL, NO},
    [SG_OP_ABSO] = {"ABSO", "op1", NULL, NO},
    [SG_OP_PMAG] = {"PMAG", NULL, "wave", NO},
    [SG_OP_WFNO] = {"WFNO", NULL, "wave", NO},
    [SG_OP_ISFN] = {"ISFN", NULL, "wave", NO},
    [SG_OP_EPDI] = {"EPDI", NULL, NULL, NO},
    [SG_OP_EXPP] = {"EXPP", NULL, NULL, NO},
    [SG_OP_PARX] = {"PARX", "surf", "wave", FP},
    [SG_OP_PARY] = {"PARY", "surf", "wave", FP},
    [SG_OP_PANA] = {"PANA", "surf", "wave", FP},
    [SG_OP_MXET] = {"MXET", "surf1", "surf2", NO},
    [SG_OP_MNEA] = {"MNEA", "surf1", "surf2", NO},
    [SG_OP_MXEA] = {"MXEA", "surf1", "surf2", NO},
    [SG_OP_MNEG] = {"MNEG", "surf1", "surf2", NO},
    [SG_OP_MXEG] = {"MXEG", "surf1", "surf2", NO},
    [SG_OP_REAR] = {"REAR", "surf", "wave", FP},
    [SG_OP_RANG] = {"RANG", "surf", "wave", FP},
    [SG_OP_TRAC] = {"TRAC", NULL, "wave", FP},
    [SG_OP_OPDC] = {"OPDC", NULL, "wave", FP},
    [SG_OP_OPDX] = {"OPDX", NULL, "wave", FP},
    [SG_OP_RSRE] = {"RSRE", "grid", "wave", F_},
    [SG_OP_RSRH] = {"RSRH", "grid", "wave", F_},
    [SG_OP_RWCE] = {"RWCE", "rings", "wave", F_},
    [SG_OP_RWRE] = {"RWRE", "grid", "wave", F_},
    [SG_OP_DIST] = {"DIST", "surf", "wave", {"absolute", NULL, NULL, NULL}},
    [SG_OP_DIMX] = {"DIMX", "field", "wave", {"absolute", NULL, NULL, NULL}},
    [SG_OP_FCGS] = {"FCGS", NULL, "wave", F_},
    [SG_OP_FCGT] = {"FCGT", NULL, "wave", F_},
    [SG_OP_ZERN] = {"ZERN", "term", "wave", {"sampling", "field", "kind", "epsilon"}},
    [SG_OP_SPHA] = {"SPHA", "surf", "wave", NO},
    [SG_OP_COMA] = {"COMA", "surf", "wave", NO},
    [SG_OP_ASTI] = {"ASTI", "surf", "wave", NO},
    [SG_OP_FCUR] = {"FCUR", "surf", "wave", NO},
    [SG_OP_AXCL] = {"AXCL", "wave1", "wave2", {"zone", NULL, NULL, NULL}},
    [SG_OP_LACL] = {"LACL", "wave1", "wave2", NO},
    [SG_OP_SQRT] = {"SQRT", "op1", NULL, NO},
    [SG_OP_MTFT] = {"MTFT", "sampling", "wave", {"field", "frequency", NULL, NULL}},
    [SG_OP_MTFS] = {"MTFS", "sampling", "wave", {"field", "frequency", NULL, NULL}},
    [SG_OP_MTFA] = {"MTFA", "sampling", "wave", {"field", "frequency", NULL, NULL}},
    [SG_OP_GMTT] = {"GMTT", "sampling", "wave", {"field", "frequency", NULL, NULL}},
    [SG_OP_GMTS] = {"GMTS", "sampling", "wave", {"field", "frequency", NULL, NULL}},
    [SG_OP_GMTA] = {"GMTA", "sampling", "wave", {"field", "frequency", NULL, NULL}},
    [SG_OP_STRH] = {"STRH", "sampling", "wave", {"field", NULL, NULL, NULL}},
    [SG_OP_CONF] = {"CONF", "config", NULL, NO},
};

const sg_op_info *sg_op_info_of(sg_op_type t)
{
    return (int)t >= 0 && t < SG_OP_NTYPES ? &ops[t] : &ops[SG_OP_BLNK];
}

void sg_op_keys(sg_op_type t, const char *keys[6])
{
    const sg_op_info *inf = sg_op_info_of(t);
    int k;
    keys[0] = inf->k1;
    keys[1] = inf->k2;
    for (k = 0; k < 4; k++)
        keys[2 + k] = inf->d[k];
}

static int is_surf_key(const char *k)
{
    return k && (!strcmp(k, "surf") || !strcmp(k, "surf1") || !strcmp(k, "surf2"));
}

void sg_merit_renumber(sg_merit *m, int at, int dir)
{
    int i;
    for (i = 0; m && i < m->nop; i++) {
        sg_operand *o = &m->op[i];
        const sg_op_info *inf = sg_op_info_of(o->type);
        if (is_surf_key(inf->k1) && o->i1 >= at + (dir < 0))
            o->i1 += dir;
        if (is_surf_key(inf->k2) && o->i2 >= at + (dir < 0))
            o->i2 += dir;
    }
}

const char *sg_op_name(sg_op_type t)
{
    return (int)t >= 0 && t < SG_OP_NTYPES ? ops[t].name : NULL;
}

int sg_op_parse(const char *name)
{
    int t;
    for (t = 0; t < SG_OP_NTYPES; t++)
        if (strcmp(ops[t].name, name) == 0)
            return t;
    return -1;
}

/* The arms of RSCE and RSCH with n rings: enough that the angular sum is
 * exact for the trigonometric terms of a spot's square up to 2n + 3. */
static int rs_arms(int rings)
{
    return 2 * rings + 4;
}

int sg_merit_rings(int n, double *rho, double *w)
{
    int i, k;
    if (n < 1 || n > 32)
        return SG_ERANGE;
    /* Gauss-Legendre on [-1, 1] by Newton from the Chebyshev guess, then
     * mapped to u = (x + 1) / 2 in [0, 1], weights halved. */
    for (i = 0; i < n; i++) {
        double x = cos(PI * (i + 0.75) / (n + 0.5)), p0, p1, dp = 1.0;
        int it;
        for (it = 0; it < 100; it++) {
            double dx;
            p0 = 1.0;
            p1 = x;
            for (k = 2; k <= n; k++) {
                double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (x * p1 - p0) / (x * x - 1.0);
            dx = p1 / dp;
            x -= dx;
            if (fabs(dx) <= 1e-16)
                break;
        }
        /* Recompute the derivative at the root for the weight. */
        p0 = 1.0;
        p1 = x;
        for (k = 2; k <= n; k++) {
            double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        dp = n * (x * p1 - p0) / (x * x - 1.0);
        /* Rings from the centre outwards. */
        rho[n - 1 - i] = sqrt((x + 1.0) / 2.0);
        w[n - 1 - i] = 1.0 / ((1.0 - x * x) * dp * dp);
    }
    return SG_OK;
}

static int check_surf(const sg_system *sys, int row, const char *key, int s, int lo, int hi,
                      sg_diag *d)
{
    if (s < lo || s > hi)
        return sg_diag_set(d, SG_ERANGE, "merit: operand %d: %s %d is not a surface %d to %d",
                           row, key, s, lo, hi);
    (void)sys;
    return SG_OK;
}

int sg_merit_check(const sg_system *sys, sg_diag *d)
{
    int i, rc, ns = sys->nsurf;
    const sg_merit *m = &sys->merit;
    if (m->has_default && (m->rings < 1 || m->rings > 20 || m->arms < 1 || m->arms > 64))
        return sg_diag_set(d, SG_ERANGE, "merit: default: rings %d or arms %d out of range "
                           "(1 to 20, 1 to 64)", m->rings, m->arms);
    for (i = 0; i < m->nop; i++) {
        const sg_operand *o = &m->op[i];
        const sg_op_info *inf = sg_op_info_of(o->type);
        int row = i + 1;
        if ((int)o->type < 0 || o->type >= SG_OP_NTYPES)
            return sg_diag_set(d, SG_ERANGE, "merit: operand %d: unknown type", row);
        if (!(o->weight >= 0.0) || !isfinite(o->weight) || !isfinite(o->target))
            return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): the target and weight "
                               "must be finite, the weight not negative", row, inf->name);
        if (inf->k2 && strcmp(inf->k2, "wave") == 0 && (o->i2 < 0 || o->i2 > sys->nwave))
            return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): wave %d is not 0 to %d", row,
                               inf->name, o->i2, sys->nwave);
        switch (o->type) {
        case SG_OP_TTHI:
            if ((rc = check_surf(sys, row, "surf1", o->i1, 0, ns - 1, d)) != SG_OK ||
                (rc = check_surf(sys, row, "surf2", o->i2, o->i1, ns - 1, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_CTGT: case SG_OP_CTLT: case SG_OP_CTVA:
        case SG_OP_ETGT: case SG_OP_ETLT: case SG_OP_ETVA:
            if ((rc = check_surf(sys, row, "surf", o->i1, 1, ns - 2, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_MNCT: case SG_OP_MXCT: case SG_OP_MNET: case SG_OP_MNCA: case SG_OP_MXCA:
        case SG_OP_MNCG: case SG_OP_MXCG:
            /* 0 and 0: every surface between object and image. */
            if (o->i1 == 0 && o->i2 == 0)
                break;
            if ((rc = check_surf(sys, row, "surf1", o->i1, 1, ns - 2, d)) != SG_OK ||
                (rc = check_surf(sys, row, "surf2", o->i2, o->i1, ns - 2, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_REAX: case SG_OP_REAY: case SG_OP_REAZ:
            if ((rc = check_surf(sys, row, "surf", o->i1, 1, ns - 1, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_CONF:
            if (o->i1 < 1 || o->i1 > sg_config_count(sys))
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (CONF): configuration %d "
                                   "is not 1 to %d", row, o->i1, sg_config_count(sys));
            break;
        case SG_OP_RSCE: case SG_OP_RSCH:
            if (o->i1 < 1 || o->i1 > 20)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): rings %d is not 1 to "
                                   "20", row, inf->name, o->i1);
            break;
        case SG_OP_SUMM: case SG_OP_DIFF: case SG_OP_PROD: case SG_OP_DIVI:
            if (o->i2 < 1 || o->i2 >= row)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): op2 %d is not an "
                                   "earlier operand (1 to %d)", row, inf->name, o->i2, row - 1);
            /* fall through */
        case SG_OP_OPGT: case SG_OP_OPLT: case SG_OP_ABSO: case SG_OP_SQRT:
            if (o->i1 < 1 || o->i1 >= row)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): op1 %d is not an "
                                   "earlier operand (1 to %d)", row, inf->name, o->i1, row - 1);
            break;
        case SG_OP_MXET: case SG_OP_MNEA: case SG_OP_MXEA: case SG_OP_MNEG: case SG_OP_MXEG:
            if (o->i1 == 0 && o->i2 == 0)
                break;
            if ((rc = check_surf(sys, row, "surf1", o->i1, 1, ns - 2, d)) != SG_OK ||
                (rc = check_surf(sys, row, "surf2", o->i2, o->i1, ns - 2, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_REAR: case SG_OP_RANG: case SG_OP_PARX: case SG_OP_PARY: case SG_OP_PANA:
            if ((rc = check_surf(sys, row, "surf", o->i1, 1, ns - 1, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_SPHA: case SG_OP_COMA: case SG_OP_ASTI: case SG_OP_FCUR: case SG_OP_DIST:
            if ((rc = check_surf(sys, row, "surf", o->i1, 0, ns - 1, d)) != SG_OK)
                return rc;
            break;
        case SG_OP_RSRE: case SG_OP_RSRH: case SG_OP_RWRE:
            if (o->i1 < 1 || o->i1 > 256)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): grid %d is not 1 to "
                                   "256", row, inf->name, o->i1);
            break;
        case SG_OP_RWCE:
            if (o->i1 < 1 || o->i1 > 20)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): rings %d is not 1 to "
                                   "20", row, inf->name, o->i1);
            break;
        case SG_OP_DIMX:
            if (o->i1 < 0 || o->i1 > sys->nfield)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): field %d is not 0 to "
                                   "%d", row, inf->name, o->i1, sys->nfield);
            break;
        case SG_OP_AXCL: case SG_OP_LACL:
            if (o->i1 < 1 || o->i1 > sys->nwave || o->i2 < 1 || o->i2 > sys->nwave)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): wave1 %d and wave2 %d "
                                   "must be wavelengths 1 to %d", row, inf->name, o->i1, o->i2,
                                   sys->nwave);
            if (o->type == SG_OP_AXCL && !(o->hx >= 0.0 && o->hx <= 1.0))
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (AXCL): zone %g is not 0 to "
                                   "1", row, o->hx);
            break;
        case SG_OP_ZERN: {
            int maxt = SG_WAVEFRONT_MAXTERMS;
            if (o->i1 < 1 || o->i1 > maxt)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (ZERN): term %d is not 1 to "
                                   "%d", row, o->i1, maxt);
            if (!(o->hx >= 1 && o->hx <= 6 && o->hx == floor(o->hx)))
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (ZERN): sampling %g is not "
                                   "1 to 6 (32 to 1024 points across)", row, o->hx);
            if (!(o->hy >= 1 && o->hy <= sys->nfield && o->hy == floor(o->hy)))
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (ZERN): field %g is not 1 "
                                   "to %d", row, o->hy, sys->nfield);
            if (o->px != 0.0 && o->px != 1.0)
                return sg_diag_set(d, SG_EUNSUPPORTED, "merit: operand %d (ZERN): kind %g is "
                                   "not 0 (Fringe) or 1 (Standard); annular Zernikes are not "
                                   "supported", row, o->px);
            if (o->py != 0.0)
                return sg_diag_set(d, SG_EUNSUPPORTED, "merit: operand %d (ZERN): epsilon %g: "
                                   "annular Zernikes are not supported (0 only)", row, o->py);
            break;
        }
        case SG_OP_MTFT: case SG_OP_MTFS: case SG_OP_MTFA: case SG_OP_GMTT: case SG_OP_GMTS:
        case SG_OP_GMTA: case SG_OP_STRH:
            if (o->i1 < 1 || o->i1 > 7)
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): sampling %d is not 1 "
                                   "to 7 (32 to 2048 points across)", row, inf->name, o->i1);
            if (!(o->hx >= 1 && o->hx <= sys->nfield && o->hx == floor(o->hx)))
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): field %g is not 1 to "
                                   "%d", row, inf->name, o->hx, sys->nfield);
            if (o->type != SG_OP_STRH && !(o->hy >= 0.0))
                return sg_diag_set(d, SG_ERANGE, "merit: operand %d (%s): frequency %g is "
                                   "negative", row, inf->name, o->hy);
            break;
        default: break;
        }
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Evaluation
 * ------------------------------------------------------------------------ */

typedef struct ectx {
    const sg_system *sys;   /* the design the rows read: base or own */
    const sg_system *base;  /* the design given */
    sg_system *own;         /* a configuration of it (CONF), or NULL */
    const sg_catalog *cat;
    sg_tracer *tr[SG_MAX_WAVES];
    sg_ray_surface *rows;
    int have_sd;
    double *sd;
    double bound;   /* the largest error bound of a traced value */
    double *gval;   /* TRAC and OPDX: each row's value, once its group is done */
    unsigned char *gdone;
    int have_seidel;
    sg_seidel seidel;
} ectx;

/* Drops what was computed on the current design. */
static void ectx_reset(ectx *c)
{
    int i;
    for (i = 0; i < SG_MAX_WAVES; i++)
        if (c->tr[i]) {
            sg_tracer_free(c->tr[i]);
            c->tr[i] = NULL;
        }
    free(c->sd);
    c->sd = NULL;
    c->have_sd = 0;
    if (c->have_seidel)
        sg_seidel_free(&c->seidel);
    c->have_seidel = 0;
}

/* CONF k: the rows that follow read configuration k's design (Zemax's
 * Multi-Configuration Editor): the design given with configuration k's
 * values set and its solves recomputed on them.  A design without
 * configurations is its own configuration 1. */
static int ectx_config(ectx *c, int k, const char *what, sg_diag *d)
{
    sg_diag de;
    int rc;
    ectx_reset(c);
    sg_system_free(c->own);
    c->own = NULL;
    c->sys = c->base;
    if (!c->base->configs)
        return SG_OK;
    if (!(c->own = sg_system_clone(c->base)))
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    sg_diag_clear(&de);
    if ((rc = sg_config_apply(c->own, k, &de)) != SG_OK ||
        (rc = sg_system_apply_solves(c->own, c->cat, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: configuration %d: %s", what, k, de.msg);
    c->sys = c->own;
    return SG_OK;
}

static int tracer_of(ectx *c, int w, sg_tracer **out, sg_diag *d)
{
    if (!c->tr[w]) {
        sg_trace_opts o;
        int rc;
        sg_trace_opts_init(&o);
        o.wave = w;
        if ((rc = sg_tracer_open(c->sys, c->cat, &o, &c->tr[w], d)) != SG_OK)
            return rc;
    }
    *out = c->tr[w];
    return SG_OK;
}

/* The ray (hx, hy, px, py) at wavelength w (0-based): its row at surface
 * s.  A failure names what and where; why is the ray's status. */
static int ray_at(ectx *c, int w, double hx, double hy, double px, double py, int s,
                  sg_ray_surface *out, const char *what, sg_diag *d)
{
    sg_tracer *t;
    int rc = tracer_of(c, w, &t, d), k;
    if (rc != SG_OK)
        return rc;
    rc = sg_trace_normalized(t, hx, hy, px, py, c->rows);
    if (rc != SG_OK) {
        for (k = 1; k < c->sys->nsurf && c->rows[k].status == SG_OK; k++)
            ;
        return sg_diag_set(d, rc, "%s: the ray (hx %g, hy %g, px %g, py %g) at wavelength %d "
                           "fails at surface %d: %s", what, hx, hy, px, py, w + 1, k,
                           sg_strerror(rc));
    }
    *out = c->rows[s];
    if (c->rows[s].error_bound > c->bound)
        c->bound = c->rows[s].error_bound;
    return SG_OK;
}

/* The wavelength an operand names: 1-based, 0 the primary. */
static int wave_of(const ectx *c, int w)
{
    return w >= 1 ? w - 1 : c->sys->primary_wave;
}

/* Transverse aberration at the image about the primary chief ray. */
static int transverse(ectx *c, const sg_operand *o, double *dx, double *dy, const char *what,
                      sg_diag *d)
{
    sg_ray_surface r, ch;
    int img = c->sys->nsurf - 1, rc;
    if ((rc = ray_at(c, wave_of(c, o->i2), o->hx, o->hy, o->px, o->py, img, &r, what, d)) !=
            SG_OK ||
        (rc = ray_at(c, c->sys->primary_wave, o->hx, o->hy, 0.0, 0.0, img, &ch, what, d)) !=
            SG_OK)
        return rc;
    *dx = r.x - ch.x;
    *dy = r.y - ch.y;
    return SG_OK;
}

/* RMS spot radius of field (hx, hy) by Gaussian quadrature: rings and
 * 2 rings + 4 arms, at wave w (1-based) or every wavelength (0) by its
 * weight; about the centroid or the primary chief ray. */
static int rms_spot(ectx *c, int rings, int w, double hx, double hy, int chief, double *out,
                    const char *what, sg_diag *d)
{
    double rho[32], wt[32], sx = 0, sy = 0, sw = 0, cx, cy, s2 = 0.0, (*pt)[3];
    int arms = rs_arms(rings), i, j, k, w0 = w ? w - 1 : 0, w1 = w ? w : c->sys->nwave, rc;
    int img = c->sys->nsurf - 1, np = 0;
    sg_ray_surface r;
    pt = malloc((size_t)(w1 - w0) * (size_t)rings * (size_t)arms * sizeof *pt);
    if (!pt)
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    sg_merit_rings(rings, rho, wt);
    for (k = w0; k < w1; k++) {
        double ww = w ? 1.0 : c->sys->wave[k].weight;
        if (ww == 0.0)
            continue;
        for (i = 0; i < rings; i++)
            for (j = 0; j < arms; j++) {
                double th = PI * (2.0 * j + 1.0) / arms, q = ww * wt[i] / arms;
                if ((rc = ray_at(c, k, hx, hy, rho[i] * cos(th), rho[i] * sin(th), img, &r, what,
                                 d)) != SG_OK) {
                    free(pt);
                    return rc;
                }
                pt[np][0] = r.x;
                pt[np][1] = r.y;
                pt[np++][2] = q;
                sx += q * r.x;
                sy += q * r.y;
                sw += q;
            }
    }
    if (!(sw > 0.0)) {
        free(pt);
        return sg_diag_set(d, SG_ERANGE, "%s: every wavelength has weight 0", what);
    }
    if (chief) {
        if ((rc = ray_at(c, c->sys->primary_wave, hx, hy, 0.0, 0.0, img, &r, what, d)) != SG_OK) {
            free(pt);
            return rc;
        }
        cx = r.x;
        cy = r.y;
    } else {
        cx = sx / sw;
        cy = sy / sw;
    }
    /* About the reference point, not from the sums about the origin,
     * which would cancel digits. */
    for (i = 0; i < np; i++)
        s2 += pt[i][2] * ((pt[i][0] - cx) * (pt[i][0] - cx) + (pt[i][1] - cy) * (pt[i][1] - cy));
    free(pt);
    *out = sqrt(s2 / sw);
    return SG_OK;
}

/* The semi-diameters the edge operands use: the design's, or where one is
 * 0 the automatic one. */
static int semi_of(ectx *c, int s, double *h, sg_diag *d)
{
    if (c->sys->surf[s].semi_diameter > 0.0) {
        *h = c->sys->surf[s].semi_diameter;
        return SG_OK;
    }
    if (!c->have_sd) {
        int rc;
        c->sd = calloc((size_t)c->sys->nsurf, sizeof *c->sd);
        if (!c->sd)
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        if ((rc = sg_semi_diameters(c->sys, c->cat, NULL, c->sd, d)) != SG_OK)
            return rc;
        c->have_sd = 1;
    }
    *h = c->sd[s];
    return SG_OK;
}

/* Edge thickness of surface s: its thickness plus the next surface's sag
 * less its own, at the larger of the two semi-diameters, along +y. */
static int edge_thickness(ectx *c, int s, double *out, const char *what, sg_diag *d)
{
    double h1, h2, h, z1, z2;
    int rc;
    if ((rc = semi_of(c, s, &h1, d)) != SG_OK || (rc = semi_of(c, s + 1, &h2, d)) != SG_OK)
        return rc;
    h = h1 > h2 ? h1 : h2;
    z1 = sg_surface_sag(&c->sys->surf[s], 0.0, h);
    z2 = sg_surface_sag(&c->sys->surf[s + 1], 0.0, h);
    if (!isfinite(z1) || !isfinite(z2))
        return sg_diag_set(d, SG_ENONPHYS, "%s: surface %d or %d has no sag at height %g", what,
                           s, s + 1, h);
    *out = c->sys->surf[s].thickness + z2 - z1;
    return SG_OK;
}

/* Which surfaces a range operand reads: air after the surface (MNCA,
 * MXCA), glass (MNCG, MXCG), or every one. */
static int range_takes(const sg_surface *s, sg_op_type t)
{
    int air = s->mat.kind == SG_MAT_AIR, mirror = s->mat.kind == SG_MAT_MIRROR;
    if (s->type == SG_SURF_COORDBRK)
        return 0;
    switch (t) {
    case SG_OP_MNCA: case SG_OP_MXCA: case SG_OP_MNEA: case SG_OP_MXEA: return air;
    case SG_OP_MNCG: case SG_OP_MXCG: case SG_OP_MNEG: case SG_OP_MXEG: return !air && !mirror;
    default: return 1;
    }
}

/* A boundary over a range: the target when every surface keeps it, else
 * the target less (MN) or plus (MX) the root sum square of the breaches,
 * so one breach gives the offending value, as CTGT does. */
static int range_op(ectx *c, const sg_operand *o, double *v, const char *what, sg_diag *d)
{
    int a = o->i1, b = o->i2, s, rc, mn = o->type == SG_OP_MNCT || o->type == SG_OP_MNET ||
                                       o->type == SG_OP_MNCA || o->type == SG_OP_MNCG ||
                                       o->type == SG_OP_MNEA || o->type == SG_OP_MNEG;
    int edge = o->type == SG_OP_MNET || o->type == SG_OP_MXET || o->type == SG_OP_MNEA ||
               o->type == SG_OP_MXEA || o->type == SG_OP_MNEG || o->type == SG_OP_MXEG;
    double ss = 0.0;
    if (a == 0 && b == 0) {
        a = 1;
        b = c->sys->nsurf - 2;
    }
    for (s = a; s <= b; s++) {
        double t = c->sys->surf[s].thickness, e;
        if (!range_takes(&c->sys->surf[s], o->type))
            continue;
        if (edge) {
            if ((rc = edge_thickness(c, s, &t, what, d)) != SG_OK)
                return rc;
        }
        e = mn ? o->target - t : t - o->target;
        if (e > 0.0)
            ss += e * e;
    }
    *v = mn ? o->target - sqrt(ss) : o->target + sqrt(ss);
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * First order: paraxial rays
 * ------------------------------------------------------------------------ */

/* The largest field in x and y, as sg_field_normalized scales them. */
static void field_scale(const sg_system *sys, double *fx, double *fy)
{
    int i;
    *fx = *fy = 0.0;
    for (i = 0; i < sys->nfield; i++) {
        if (sys->field_norm == SG_NORM_RADIAL) {
            double r = hypot(sys->field[i].x, sys->field[i].y);
            if (r > *fx)
                *fx = *fy = r;
        } else {
            *fx = fmax(*fx, fabs(sys->field[i].x));
            *fy = fmax(*fy, fabs(sys->field[i].y));
        }
    }
}

/* The paraxial ray (hx, hy, px, py) at wavelength w (0-based) on surface
 * s: its heights x, y there and its slopes u = w / n after the surface.
 * Its marginal part goes through the primary wavelength's entrance pupil
 * at (px, py) of its radius, its chief part through the pupil's centre at
 * the slope tan(h theta) of an angle field or from the object height h;
 * x and y are traced apart, as a centred system's paraxial rays are. */
static int parax_ray(ectx *c, int w, const sg_operand *o, int s, double *x, double *y,
                     double *ux, double *uy, const char *what, sg_diag *d)
{
    const sg_system *sys = c->sys;
    int n = sys->nsurf, j, k, rc;
    double *idx, fmx, fmy, T0 = sys->surf[0].thickness, h[2], pp[2], out[2][2];
    mpfr_t *mi;
    sg_paraxial p0;
    sg_diag de;
    sg_diag_clear(&de);
    if (sys->telecentric)
        return sg_diag_set(d, SG_EUNSUPPORTED, "%s: the object space is telecentric", what);
    if (sys->field_type != SG_FIELD_ANGLE && sys->field_type != SG_FIELD_OBJECT_HEIGHT)
        return sg_diag_set(d, SG_EUNSUPPORTED, "%s: the paraxial ray operands take angle or "
                           "object height fields", what);
    if (!isfinite(T0) && sys->field_type != SG_FIELD_ANGLE)
        return sg_diag_set(d, SG_EUNSUPPORTED, "%s: an object at infinity needs angle fields",
                           what);
    if ((rc = sg_paraxial_compute(sys, c->cat, sys->primary_wave, &p0, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    idx = malloc((size_t)n * sizeof *idx);
    mi = malloc((size_t)n * sizeof *mi);
    if (!idx || !mi) {
        free(idx);
        free(mi);
        return sg_diag_set(d, SG_ENOMEM, "out of memory");
    }
    for (j = 0; j < n; j++)
        mpfr_init2(mi[j], 64);
    rc = sg_indices_mpfr(sys, c->cat, w, mi, &de);
    for (j = 0; j < n; j++) {
        idx[j] = mpfr_get_d(mi[j], MPFR_RNDN);
        mpfr_clear(mi[j]);
    }
    free(mi);
    if (rc != SG_OK) {
        free(idx);
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    }
    field_scale(sys, &fmx, &fmy);
    h[0] = o->hx * fmx;
    h[1] = o->hy * fmy;
    pp[0] = o->px;
    pp[1] = o->py;
    for (k = 0; k < 2; k++) {
        /* The marginal part (yp, wp) and the chief part (yc, wc), w = n u,
         * at surface 1. */
        double r = 0.5 * p0.epd * pp[k], yp, wp, yc, wc, u;
        if (!isfinite(T0)) {
            u = tan(h[k] * PI / 180.0);
            yp = r;
            wp = 0.0;
            yc = -p0.enp_pos * u;
            wc = idx[0] * u;
        } else {
            double D = p0.enp_pos + T0;
            u = sys->field_type == SG_FIELD_ANGLE ? tan(h[k] * PI / 180.0) : -h[k] / D;
            yp = r / D * T0;
            wp = r / D * idx[0];
            yc = -p0.enp_pos * u;
            wc = idx[0] * u;
        }
        for (j = 1; j <= s; j++) {
            double ph = (idx[j] - idx[j - 1]) * sg_surface_curvature(&sys->surf[j]);
            if (j > 1) {
                double t = sys->surf[j - 1].thickness / idx[j - 1];
                yp += t * wp;
                yc += t * wc;
            }
            wp -= yp * ph;
            wc -= yc * ph;
        }
        out[k][0] = yp + yc;
        out[k][1] = (wp + wc) / idx[s];
    }
    free(idx);
    *x = out[0][0];
    *y = out[1][0];
    *ux = out[0][1];
    *uy = out[1][1];
    if (!isfinite(*x) || !isfinite(*y) || !isfinite(*ux) || !isfinite(*uy))
        return sg_diag_set(d, SG_ENONPHYS, "%s: the paraxial ray does not reach surface %d", what,
                           s);
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Rays against the reference sphere; pupil samples; groups of rows
 * ------------------------------------------------------------------------ */

/* The OPD in waves of ray (hx, hy, px, py) at wavelength w (0-based),
 * against the field's reference sphere (sg_opd_reference). */
static int opd_at(ectx *c, int w, double hx, double hy, double px, double py, double *out,
                  const char *what, sg_diag *d)
{
    sg_tracer *t;
    sg_opd_ref ref;
    sg_opd res;
    sg_diag de;
    int rc = tracer_of(c, w, &t, d);
    if (rc != SG_OK)
        return rc;
    sg_diag_clear(&de);
    if ((rc = sg_opd_reference(t, hx, hy, &ref, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    if (ref.status != SG_OK)
        return sg_diag_set(d, ref.status, "%s: the chief ray of field (hx %g, hy %g) fails: %s",
                           what, hx, hy, sg_strerror(ref.status));
    rc = sg_trace_opd(t, &ref, px, py, c->rows, &res);
    if (rc != SG_OK || res.status != SG_OK)
        return sg_diag_set(d, rc != SG_OK ? rc : res.status, "%s: the ray (hx %g, hy %g, px %g, "
                           "py %g) at wavelength %d fails: %s", what, hx, hy, px, py, w + 1,
                           sg_strerror(rc != SG_OK ? rc : res.status));
    if (res.error_bound > c->bound)
        c->bound = res.error_bound;
    *out = res.opd_waves;
    return SG_OK;
}

/* Pupil samples (px, py, weight): Gaussian quadrature in rings and
 * 2 rings + 4 arms (as RSCE), or a grid x grid square of cell centres
 * inside the unit circle, of equal weight. */
static int pupil_samples(int quad, int n, double (**out)[3], int *np, sg_diag *d)
{
    double (*p)[3];
    int i, j, k = 0;
    if (quad) {
        double rho[32], wt[32];
        int arms = rs_arms(n);
        p = malloc((size_t)n * (size_t)arms * sizeof *p);
        if (!p)
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        sg_merit_rings(n, rho, wt);
        for (i = 0; i < n; i++)
            for (j = 0; j < arms; j++) {
                double th = PI * (2.0 * j + 1.0) / arms;
                p[k][0] = rho[i] * cos(th);
                p[k][1] = rho[i] * sin(th);
                p[k++][2] = wt[i] / arms;
            }
    } else {
        p = malloc((size_t)n * (size_t)n * sizeof *p);
        if (!p)
            return sg_diag_set(d, SG_ENOMEM, "out of memory");
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++) {
                double x = -1.0 + (2.0 * j + 1.0) / n, y = -1.0 + (2.0 * i + 1.0) / n;
                if (x * x + y * y > 1.0)
                    continue;
                p[k][0] = x;
                p[k][1] = y;
                p[k++][2] = 1.0;
            }
    }
    *out = p;
    *np = k;
    return SG_OK;
}

/* v less its weighted least-squares fit a + b px + c py (piston and
 * tilt: Zemax's reference "to the centroid" of a wavefront); where the
 * samples cannot fix a tilt, the piston alone. */
static void remove_tilt(int n, const double (*p)[3], const double *wq, double *v)
{
    double m[3][4] = {{0}}, det, a = 0.0, b = 0.0, cc = 0.0;
    int i, r, k;
    for (i = 0; i < n; i++) {
        double f[3] = {1.0, p[i][0], p[i][1]};
        for (r = 0; r < 3; r++) {
            for (k = 0; k < 3; k++)
                m[r][k] += wq[i] * f[r] * f[k];
            m[r][3] += wq[i] * f[r] * v[i];
        }
    }
    if (!(m[0][0] > 0.0))
        return;
    det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
          m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
          m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (fabs(det) > 1e-12 * m[0][0] * m[0][0] * m[0][0] + 1e-300) {
        a = (m[0][3] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
             m[0][1] * (m[1][3] * m[2][2] - m[1][2] * m[2][3]) +
             m[0][2] * (m[1][3] * m[2][1] - m[1][1] * m[2][3])) / det;
        b = (m[0][0] * (m[1][3] * m[2][2] - m[1][2] * m[2][3]) -
             m[0][3] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
             m[0][2] * (m[1][0] * m[2][3] - m[1][3] * m[2][0])) / det;
        cc = (m[0][0] * (m[1][1] * m[2][3] - m[1][3] * m[2][1]) -
              m[0][1] * (m[1][0] * m[2][3] - m[1][3] * m[2][0]) +
              m[0][3] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / det;
    } else {
        a = m[0][3] / m[0][0];
    }
    for (i = 0; i < n; i++)
        v[i] -= a + b * p[i][0] + cc * p[i][1];
}

/* RMS spot radius on a grid (RSRE about the centroid, RSRH about the
 * primary chief ray), or RMS wavefront in waves, piston and tilt removed,
 * by quadrature rings (RWCE) or on a grid (RWRE); wave w 1-based, 0 every
 * wavelength by its weight. */
static int rms_of(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    int wf = o->type == SG_OP_RWCE || o->type == SG_OP_RWRE, quad = o->type == SG_OP_RWCE;
    int w0 = o->i2 ? o->i2 - 1 : 0, w1 = o->i2 ? o->i2 : c->sys->nwave, np = 0, i, k, m = 0, rc;
    int img = c->sys->nsurf - 1;
    double (*p)[3] = NULL, (*q)[3] = NULL, *v = NULL, *vy = NULL, *wq = NULL, sw = 0.0, s2 = 0.0;
    double cx = 0.0, cy = 0.0;
    sg_ray_surface r;
    if ((rc = pupil_samples(quad, o->i1, &p, &np, d)) != SG_OK)
        return rc;
    q = malloc((size_t)(np * (w1 - w0) + 1) * sizeof *q);
    v = malloc((size_t)(np * (w1 - w0) + 1) * sizeof *v);
    vy = malloc((size_t)(np * (w1 - w0) + 1) * sizeof *vy);
    wq = malloc((size_t)(np * (w1 - w0) + 1) * sizeof *wq);
    if (!q || !v || !vy || !wq) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto out;
    }
    for (k = w0; k < w1; k++) {
        double ww = o->i2 ? 1.0 : c->sys->wave[k].weight;
        if (ww == 0.0)
            continue;
        for (i = 0; i < np; i++) {
            if (wf)
                rc = opd_at(c, k, o->hx, o->hy, p[i][0], p[i][1], &v[m], what, d);
            else if ((rc = ray_at(c, k, o->hx, o->hy, p[i][0], p[i][1], img, &r, what, d)) ==
                     SG_OK) {
                v[m] = r.x;
                vy[m] = r.y;
            }
            if (rc != SG_OK)
                goto out;
            q[m][0] = p[i][0];
            q[m][1] = p[i][1];
            wq[m] = ww * p[i][2];
            sw += wq[m];
            cx += wq[m] * v[m];
            cy += wq[m] * (wf ? 0.0 : vy[m]);
            m++;
        }
    }
    if (!(sw > 0.0)) {
        rc = sg_diag_set(d, SG_ERANGE, "%s: every wavelength has weight 0", what);
        goto out;
    }
    if (wf) {
        remove_tilt(m, (const double (*)[3])q, wq, v);
        for (i = 0; i < m; i++)
            s2 += wq[i] * v[i] * v[i];
    } else {
        if (o->type == SG_OP_RSRH) {
            if ((rc = ray_at(c, c->sys->primary_wave, o->hx, o->hy, 0.0, 0.0, img, &r, what, d)) !=
                SG_OK)
                goto out;
            cx = r.x;
            cy = r.y;
        } else {
            cx = cx / sw;
            cy = cy / sw;
        }
        for (i = 0; i < m; i++)
            s2 += wq[i] * ((v[i] - cx) * (v[i] - cx) + (vy[i] - cy) * (vy[i] - cy));
    }
    *out = sqrt(s2 / sw);
    rc = SG_OK;
out:
    free(p);
    free(q);
    free(v);
    free(vy);
    free(wq);
    return rc;
}

/* TRAC and OPDX are relative to their group: the run of rows of the same
 * type and field (and, for OPDX, wavelength) that holds row i.  TRAC is
 * the radial distance from the group's centroid (weighted by the rows'
 * weights, equal where all are 0); OPDX the OPD less the group's weighted
 * least-squares piston and tilt.  The whole group is computed at once. */
static int group_op(ectx *c, int i, double *v, const char *what, sg_diag *d)
{
    const sg_merit *m = &c->sys->merit;
    const sg_operand *o = &m->op[i];
    int g0 = i, g1 = i + 1, n, k, rc, img = c->sys->nsurf - 1, allzero = 1;
    double (*p)[3] = NULL, *x = NULL, *y = NULL, *wq = NULL, sw = 0.0, cx = 0.0, cy = 0.0;
#define SAME(a) (m->op[a].type == o->type && m->op[a].hx == o->hx && m->op[a].hy == o->hy && \
                 (o->type == SG_OP_TRAC || m->op[a].i2 == o->i2))
    if (c->gdone[i]) {
        *v = c->gval[i];
        return SG_OK;
    }
    while (g0 > 0 && SAME(g0 - 1))
        g0--;
    while (g1 < m->nop && SAME(g1))
        g1++;
#undef SAME
    n = g1 - g0;
    p = malloc((size_t)n * sizeof *p);
    x = malloc((size_t)n * sizeof *x);
    y = malloc((size_t)n * sizeof *y);
    wq = calloc((size_t)n, sizeof *wq);
    if (!p || !x || !y || !wq) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto out;
    }
    for (k = 0; k < n; k++)
        if (m->op[g0 + k].weight > 0.0)
            allzero = 0;
    for (k = 0; k < n; k++) {
        const sg_operand *q = &m->op[g0 + k];
        char w2[96];
        snprintf(w2, sizeof w2, "merit: operand %d (%s)", g0 + k + 1, sg_op_name(q->type));
        p[k][0] = q->px;
        p[k][1] = q->py;
        wq[k] = allzero ? 1.0 : q->weight;
        if (o->type == SG_OP_OPDX) {
            rc = opd_at(c, wave_of(c, q->i2), q->hx, q->hy, q->px, q->py, &x[k], w2, d);
        } else {
            sg_ray_surface r;
            rc = ray_at(c, wave_of(c, q->i2), q->hx, q->hy, q->px, q->py, img, &r, w2, d);
            x[k] = r.x;
            y[k] = r.y;
        }
        if (rc != SG_OK)
            goto out;
        sw += wq[k];
        cx += wq[k] * x[k];
        cy += wq[k] * (o->type == SG_OP_OPDX ? 0.0 : y[k]);
    }
    if (o->type == SG_OP_OPDX) {
        remove_tilt(n, (const double (*)[3])p, wq, x);
    } else {
        cx /= sw;
        cy /= sw;
        for (k = 0; k < n; k++)
            x[k] = hypot(x[k] - cx, y[k] - cy);
    }
    for (k = 0; k < n; k++) {
        c->gval[g0 + k] = x[k];
        c->gdone[g0 + k] = 1;
    }
    *v = c->gval[i];
    rc = SG_OK;
out:
    (void)what;
    free(p);
    free(x);
    free(y);
    free(wq);
    return rc;
}

/* ------------------------------------------------------------------------
 * Image quality: field curvature, distortion, Zernikes, MTF, Strehl
 * ------------------------------------------------------------------------ */

/* The crossing of the rays p and q projected on the direction (ex, ey),
 * as z on the image surface's frame. */
static double crossing_dir(const sg_ray_surface *p, const sg_ray_surface *q, double ex,
                           double ey)
{
    double ta = (p->l * ex + p->m * ey) / p->n, tb = (q->l * ex + q->m * ey) / q->n;
    double a = p->x * ex + p->y * ey, b = q->x * ex + q->y * ey;
    return (b - a + ta * p->z - tb * q->z) / (ta - tb);
}

/* FCGT and FCGS: the tangential (along the field's direction) or sagittal
 * focus of field (hx, hy), as z from the chief ray's point on the image
 * surface: the crossing of the rays a pupil step delta either side of the
 * chief ray, taken to delta -> 0 by Richardson's step (as sg_fieldcurve). */
static int gen_fieldcurve(ectx *c, const sg_operand *o, double *out, const char *what,
                          sg_diag *d)
{
    double hr = hypot(o->hx, o->hy), ux = hr > 0.0 ? o->hx / hr : 0.0,
           uy = hr > 0.0 ? o->hy / hr : 1.0, ex, ey, f[2], delta = 0.01, zc;
    int w = wave_of(c, o->i2), img = c->sys->nsurf - 1, k, rc;
    sg_ray_surface ch, a, b;
    if (o->type == SG_OP_FCGT) {
        ex = ux;
        ey = uy;
    } else {
        ex = -uy;
        ey = ux;
    }
    if ((rc = ray_at(c, w, o->hx, o->hy, 0.0, 0.0, img, &ch, what, d)) != SG_OK)
        return rc;
    zc = ch.z;
    for (k = 0; k < 2; k++) {
        double s = k ? delta / 2 : delta;
        if ((rc = ray_at(c, w, o->hx, o->hy, s * ex, s * ey, img, &a, what, d)) != SG_OK ||
            (rc = ray_at(c, w, o->hx, o->hy, -s * ex, -s * ey, img, &b, what, d)) != SG_OK)
            return rc;
        f[k] = crossing_dir(&a, &b, ex, ey) - zc;
    }
    *out = (4.0 * f[1] - f[0]) / 3.0;
    if (!isfinite(*out))
        return sg_diag_set(d, SG_ENONPHYS, "%s: the rays about the chief ray leave parallel (a "
                           "focus at infinity)", what);
    return SG_OK;
}

/* DIMX: the real distortion, percent, of largest size at 20 fields
 * evenly along +y up to the field named (0: the largest), against the
 * paraxial image height (f tan theta for angles), as sg_fieldcurve. */
static int dist_max(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    const sg_system *sys = c->sys;
    int w = wave_of(c, o->i2), img = sys->nsurf - 1, k, rc;
    double fmx, fmy, fmax, hf = 1.0, best = 0.0;
    sg_paraxial p;
    sg_diag de;
    sg_diag_clear(&de);
    if (sys->field_type == SG_FIELD_REAL_IMAGE_HEIGHT)
        return sg_diag_set(d, SG_EUNSUPPORTED, "%s: fields given as real image height have no "
                           "distortion", what);
    if ((rc = sg_paraxial_compute(sys, c->cat, w, &p, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    field_scale(sys, &fmx, &fmy);
    fmax = fmy;
    if (!(fmax > 0.0))
        return sg_diag_set(d, SG_ERANGE, "%s: every field is on the axis", what);
    if (o->i1 > 0) {
        double hx, hy;
        sg_field_normalized(sys, o->i1 - 1, &hx, &hy);
        hf = hypot(hx, hy);
    }
    for (k = 1; k <= 20; k++) {
        double hy = hf * k / 20.0, py, dist;
        sg_ray_surface r;
        if (sys->field_type == SG_FIELD_ANGLE) {
            double a = fmax * PI / 180.0;
            py = p.parax_image_height * tan(hy * a) / tan(a);
        } else {
            py = p.parax_image_height * hy;
        }
        if ((rc = ray_at(c, w, 0.0, hy, 0.0, 0.0, img, &r, what, d)) != SG_OK)
            return rc;
        if (py == 0.0)
            continue;
        dist = 100.0 * (r.y - py) / py;
        if (fabs(dist) > fabs(best))
            best = dist;
    }
    *out = o->hx != 0.0 ? fabs(best) : best;
    return SG_OK;
}

/* The pupil grid of a sampling number: 32 points across, doubled per step. */
static int grid_of(int samp)
{
    return 32 << (samp - 1);
}

static int zern(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    sg_wavefront_opts wo;
    sg_wavefront wf;
    sg_diag de;
    int rc;
    sg_wavefront_opts_init(&wo);
    wo.trace.wave = o->i2 ? o->i2 - 1 : -1;
    wo.field = (int)o->hy - 1;
    wo.grid = grid_of((int)o->hx);
    wo.kind = o->px == 1.0 ? SG_ZERNIKE_STANDARD : SG_ZERNIKE_FRINGE;
    wo.nterms = SG_WAVEFRONT_MAXTERMS;
    wo.nthreads = 1;
    sg_diag_clear(&de);
    memset(&wf, 0, sizeof wf);
    if ((rc = sg_wavefront_trace(c->sys, c->cat, &wo, &wf, NULL, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    *out = wf.coef[o->i1 - 1];
    sg_wavefront_free(&wf);
    return SG_OK;
}

/* MTFT, MTFS, MTFA (the FFT MTF) and GMTT, GMTS, GMTA (the geometric MTF)
 * at one frequency in cycles/mm: the last point of sg_mtf_compute's curve
 * from 0 to it.  At frequency 0 the MTF is 1 by definition. */
static int mtf_op(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    sg_mtf_opts mo;
    sg_mtf m;
    sg_diag de;
    int rc, geo = o->type == SG_OP_GMTT || o->type == SG_OP_GMTS || o->type == SG_OP_GMTA;
    int tan_ = o->type == SG_OP_MTFT || o->type == SG_OP_GMTT;
    int sag_ = o->type == SG_OP_MTFS || o->type == SG_OP_GMTS;
    if (o->hy == 0.0) {
        *out = 1.0;
        return SG_OK;
    }
    sg_mtf_opts_init(&mo);
    mo.field = (int)o->hx - 1;
    mo.wave = o->i2 ? o->i2 - 1 : -1;
    mo.sampling = grid_of(o->i1);
    mo.max_frequency = o->hy;
    mo.nthreads = 1;
    mo.method = geo ? SG_MTF_GEOMETRIC : SG_MTF_FFT;
    sg_diag_clear(&de);
    memset(&m, 0, sizeof m);
    if ((rc = sg_mtf_compute(c->sys, c->cat, &mo, &m, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    {
        double t = m.tan[m.npts - 1], s = m.sag[m.npts - 1];
        *out = tan_ ? t : sag_ ? s : 0.5 * (t + s);
    }
    sg_mtf_free(&m);
    if (!isfinite(*out))
        return sg_diag_set(d, SG_ENONPHYS, "%s: the MTF is not finite", what);
    return SG_OK;
}

/* STRH: the Strehl ratio of the FFT PSF's pupil, |mean exp(i 2 pi W)|^2
 * (sg_psf's strehl_exact), at one wavelength or all by weight. */
static int strehl(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    sg_psf_opts po;
    sg_psf p;
    sg_diag de;
    int rc;
    sg_psf_opts_init(&po);
    po.field = (int)o->hx - 1;
    po.wave = o->i2 ? o->i2 - 1 : -1;
    po.sampling = grid_of(o->i1);
    po.nthreads = 1;
    sg_diag_clear(&de);
    memset(&p, 0, sizeof p);
    if ((rc = sg_psf_compute(c->sys, c->cat, &po, &p, &de)) != SG_OK)
        return sg_diag_set(d, rc, "%s: %s", what, de.msg);
    *out = p.strehl_exact;
    sg_psf_free(&p);
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Seidel
 * ------------------------------------------------------------------------ */

/* SPHA, COMA, ASTI, FCUR: W040, W131, W222 and W220P (Petzval) in waves
 * of the primary wavelength, of surface surf or (0) the sum; DIST of a
 * surface W311 in waves, of the system (0) the third-order distortion of
 * the largest field in percent, TDIS / h'.  The sums are the primary
 * wavelength's (sg_seidel_compute): wave must be 0 or the primary. */
static int seidel_op(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    const double *s;
    double w[SG_NWCOEF];
    sg_diag de;
    int rc;
    if (o->i2 != 0 && o->i2 - 1 != c->sys->primary_wave)
        return sg_diag_set(d, SG_EUNSUPPORTED, "%s: Seidel sums are taken at the primary "
                           "wavelength (%d); wave %d is another", what,
                           c->sys->primary_wave + 1, o->i2);
    if (!c->have_seidel) {
        sg_diag_clear(&de);
        if ((rc = sg_seidel_compute(c->sys, c->cat, &c->seidel, &de)) != SG_OK)
            return sg_diag_set(d, rc, "%s: %s", what, de.msg);
        c->have_seidel = 1;
    }
    s = o->i1 == 0 ? c->seidel.total : &c->seidel.surf[o->i1 * SG_SEIDEL_N];
    sg_seidel_waves(s, c->seidel.wave_lens, w);
    switch (o->type) {
    case SG_OP_SPHA: *out = w[SG_W040]; break;
    case SG_OP_COMA: *out = w[SG_W131]; break;
    case SG_OP_ASTI: *out = w[SG_W222]; break;
    case SG_OP_FCUR: *out = w[SG_W220P]; break;
    default:
        if (o->i1 != 0) {
            *out = w[SG_W311];
        } else {
            double t[SG_NTCOEF];
            sg_paraxial p;
            sg_diag_clear(&de);
            if ((rc = sg_paraxial_compute(c->sys, c->cat, -1, &p, &de)) != SG_OK)
                return sg_diag_set(d, rc, "%s: %s", what, de.msg);
            sg_seidel_transverse(s, c->seidel.nu_image, t);
            if (!(p.parax_image_height != 0.0) || !isfinite(p.parax_image_height))
                return sg_diag_set(d, SG_ENONPHYS, "%s: the paraxial image height is %g, so "
                                   "the distortion in percent has no value", what,
                                   p.parax_image_height);
            *out = 100.0 * t[SG_TDIS] / p.parax_image_height;
        }
        if (o->hx != 0.0)
            *out = fabs(*out);
        break;
    }
    if (!isfinite(*out))
        return sg_diag_set(d, SG_ENONPHYS, "%s: the Seidel sum is not finite", what);
    return SG_OK;
}

/* AXCL: the axial colour, the focus of wave2 less that of wave1 along the
 * axis, in lens units: the paraxial image distances (zone 0), or where
 * the real marginal ray at py = zone crosses the axis.  LACL: the lateral
 * colour, the real chief ray's y on the image surface at the largest
 * field (hy 1), wave2's less wave1's. */
static int colour(ectx *c, const sg_operand *o, double *out, const char *what, sg_diag *d)
{
    double z[2];
    int k, rc, img = c->sys->nsurf - 1, wv[2] = {o->i1 - 1, o->i2 - 1};
    for (k = 0; k < 2; k++) {
        sg_ray_surface r;
        if (o->type == SG_OP_LACL) {
            if ((rc = ray_at(c, wv[k], 0.0, 1.0, 0.0, 0.0, img, &r, what, d)) != SG_OK)
                return rc;
            z[k] = r.y;
        } else if (o->hx == 0.0) {
            sg_paraxial p;
            sg_diag de;
            sg_diag_clear(&de);
            if ((rc = sg_paraxial_compute(c->sys, c->cat, wv[k], &p, &de)) != SG_OK)
                return sg_diag_set(d, rc, "%s: %s", what, de.msg);
            z[k] = p.image_dist;
        } else {
            if ((rc = ray_at(c, wv[k], 0.0, 0.0, 0.0, o->hx, img, &r, what, d)) != SG_OK)
                return rc;
            /* Where y + (m / n) t = 0 along the ray, from the image surface. */
            z[k] = r.z - r.y * r.n / r.m;
        }
    }
    *out = z[1] - z[0];
    if (!isfinite(*out))
        return sg_diag_set(d, SG_ENONPHYS, "%s: a focus is at infinity", what);
    return SG_OK;
}

static int eval_operand(ectx *c, int i, const double *val, double *v, sg_diag *d)
{
    const sg_system *sys = c->sys;
    const sg_operand *o = &sys->merit.op[i];
    char what[64];
    sg_ray_surface r;
    double x, y;
    int rc, s;
    snprintf(what, sizeof what, "merit: operand %d (%s)", i + 1, sg_op_name(o->type));
    switch (o->type) {
    case SG_OP_BLNK:
    case SG_OP_CONS:
        *v = o->type == SG_OP_CONS ? o->target : 0.0;
        return SG_OK;
    case SG_OP_CONF:
        *v = o->i1;
        return ectx_config(c, o->i1, what, d);
    case SG_OP_EFFL: {
        sg_paraxial p;
        sg_diag de;
        sg_diag_clear(&de);
        if ((rc = sg_paraxial_compute(sys, c->cat, wave_of(c, o->i2), &p, &de)) != SG_OK)
            return sg_diag_set(d, rc, "%s: %s", what, de.msg);
        if (!isfinite(p.efl))
            return sg_diag_set(d, SG_ENONPHYS, "%s: the system is afocal (no finite EFL)", what);
        *v = p.efl;
        return SG_OK;
    }
    case SG_OP_TOTR:
        x = 0.0;
        for (s = 1; s < sys->nsurf - 1; s++)
            x += sys->surf[s].thickness;
        *v = x;
        return SG_OK;
    case SG_OP_TTHI:
        x = 0.0;
        for (s = o->i1; s <= o->i2; s++) {
            if (!isfinite(sys->surf[s].thickness))
                return sg_diag_set(d, SG_ENONPHYS, "%s: surface %d's thickness is infinite",
                                   what, s);
            x += sys->surf[s].thickness;
        }
        *v = x;
        return SG_OK;
    case SG_OP_CTGT: case SG_OP_CTLT: case SG_OP_CTVA:
        x = sys->surf[o->i1].thickness;
        *v = o->type == SG_OP_CTVA ? x : o->type == SG_OP_CTGT ? (x < o->target ? x : o->target)
                                                                : (x > o->target ? x : o->target);
        return SG_OK;
    case SG_OP_ETGT: case SG_OP_ETLT: case SG_OP_ETVA:
        if ((rc = edge_thickness(c, o->i1, &x, what, d)) != SG_OK)
            return rc;
        *v = o->type == SG_OP_ETVA ? x : o->type == SG_OP_ETGT ? (x < o->target ? x : o->target)
                                                                : (x > o->target ? x : o->target);
        return SG_OK;
    case SG_OP_MNCT: case SG_OP_MXCT: case SG_OP_MNET: case SG_OP_MNCA: case SG_OP_MXCA:
    case SG_OP_MNCG: case SG_OP_MXCG: case SG_OP_MXET: case SG_OP_MNEA: case SG_OP_MXEA:
    case SG_OP_MNEG: case SG_OP_MXEG:
        return range_op(c, o, v, what, d);
    case SG_OP_PMAG: case SG_OP_WFNO: case SG_OP_ISFN: case SG_OP_EPDI: case SG_OP_EXPP: {
        sg_paraxial p;
        sg_diag de;
        int w = o->type == SG_OP_EPDI || o->type == SG_OP_EXPP ? sys->primary_wave
                                                               : wave_of(c, o->i2);
        sg_diag_clear(&de);
        if ((rc = sg_paraxial_compute(sys, c->cat, w, &p, &de)) != SG_OK)
            return sg_diag_set(d, rc, "%s: %s", what, de.msg);
        if (o->type == SG_OP_PMAG) {
            if (!isfinite(sys->surf[0].thickness))
                return sg_diag_set(d, SG_ENONPHYS, "%s: the object is at infinity, so the "
                                   "magnification has no value", what);
            x = p.magnification;
        } else if (o->type == SG_OP_WFNO) {
            /* Zemax's working F/#: 1 / (2 n' sin theta') of the real
             * marginal ray of the axial field in image space. */
            int img = sys->nsurf - 1;
            double sn;
            if ((rc = ray_at(c, w, 0.0, 0.0, 0.0, 1.0, img, &r, what, d)) != SG_OK)
                return rc;
            sn = hypot(r.l, r.m);
            {
                mpfr_t *mi = malloc(sizeof *mi * (size_t)sys->nsurf);
                double nimg;
                sg_diag d2;
                int j;
                if (!mi)
                    return sg_diag_set(d, SG_ENOMEM, "out of memory");
                for (j = 0; j < sys->nsurf; j++)
                    mpfr_init2(mi[j], 64);
                sg_diag_clear(&d2);
                rc = sg_indices_mpfr(sys, c->cat, w, mi, &d2);
                nimg = fabs(mpfr_get_d(mi[sys->nsurf - 2], MPFR_RNDN));
                for (j = 0; j < sys->nsurf; j++)
                    mpfr_clear(mi[j]);
                free(mi);
                if (rc != SG_OK)
                    return sg_diag_set(d, rc, "%s: %s", what, d2.msg);
                if (!(sn > 0.0))
                    return sg_diag_set(d, SG_ENONPHYS, "%s: the marginal ray leaves parallel "
                                       "to the axis (an afocal system)", what);
                x = 1.0 / (2.0 * nimg * sn);
            }
        } else if (o->type == SG_OP_ISFN) {
            x = p.image_fnum;
        } else if (o->type == SG_OP_EPDI) {
            x = p.epd;
        } else {
            x = p.exp_pos;
        }
        if (!isfinite(x))
            return sg_diag_set(d, SG_ENONPHYS, "%s: the value is infinite (an afocal system or "
                               "a pupil at infinity)", what);
        *v = x;
        return SG_OK;
    }
    case SG_OP_PARX: case SG_OP_PARY: case SG_OP_PANA: {
        double ux, uy;
        if ((rc = parax_ray(c, wave_of(c, o->i2), o, o->i1, &x, &y, &ux, &uy, what, d)) !=
            SG_OK)
            return rc;
        /* PANA: the x direction cosine of the base sphere's normal, (-c x,
         * -c y, 1 - c z), at the paraxial ray's point. */
        *v = o->type == SG_OP_PARX ? x : o->type == SG_OP_PARY
                                             ? y
                                             : -sg_surface_curvature(&sys->surf[o->i1]) * x;
        return SG_OK;
    }
    case SG_OP_REAR: case SG_OP_RANG:
        if ((rc = ray_at(c, wave_of(c, o->i2), o->hx, o->hy, o->px, o->py, o->i1, &r, what, d)) !=
            SG_OK)
            return rc;
        /* RANG: the angle in radians from the surface's z axis, after it. */
        *v = o->type == SG_OP_REAR ? hypot(r.x, r.y) : atan2(hypot(r.l, r.m), r.n);
        return SG_OK;
    case SG_OP_TRAC: case SG_OP_OPDX:
        return group_op(c, i, v, what, d);
    case SG_OP_OPDC:
        return opd_at(c, wave_of(c, o->i2), o->hx, o->hy, o->px, o->py, v, what, d);
    case SG_OP_RSRE: case SG_OP_RSRH: case SG_OP_RWCE: case SG_OP_RWRE:
        return rms_of(c, o, v, what, d);
    case SG_OP_DIMX:
        return dist_max(c, o, v, what, d);
    case SG_OP_FCGS: case SG_OP_FCGT:
        return gen_fieldcurve(c, o, v, what, d);
    case SG_OP_ZERN:
        return zern(c, o, v, what, d);
    case SG_OP_SPHA: case SG_OP_COMA: case SG_OP_ASTI: case SG_OP_FCUR: case SG_OP_DIST:
        return seidel_op(c, o, v, what, d);
    case SG_OP_AXCL: case SG_OP_LACL:
        return colour(c, o, v, what, d);
    case SG_OP_MTFT: case SG_OP_MTFS: case SG_OP_MTFA: case SG_OP_GMTT: case SG_OP_GMTS:
    case SG_OP_GMTA:
        return mtf_op(c, o, v, what, d);
    case SG_OP_STRH:
        return strehl(c, o, v, what, d);
    case SG_OP_SQRT:
        x = val[o->i1 - 1];
        if (x < 0.0)
            return sg_diag_set(d, SG_ERANGE, "%s: operand %d is %g, negative, and has no square "
                               "root", what, o->i1, x);
        *v = sqrt(x);
        return SG_OK;
    case SG_OP_REAX: case SG_OP_REAY: case SG_OP_REAZ:
        if ((rc = ray_at(c, wave_of(c, o->i2), o->hx, o->hy, o->px, o->py, o->i1, &r, what, d)) !=
            SG_OK)
            return rc;
        *v = o->type == SG_OP_REAX ? r.x : o->type == SG_OP_REAY ? r.y : r.z;
        return SG_OK;
    case SG_OP_TRAX: case SG_OP_TRAY: case SG_OP_TRAR:
        if ((rc = transverse(c, o, &x, &y, what, d)) != SG_OK)
            return rc;
        *v = o->type == SG_OP_TRAX ? x : o->type == SG_OP_TRAY ? y : hypot(x, y);
        return SG_OK;
    case SG_OP_RSCE: case SG_OP_RSCH:
        return rms_spot(c, o->i1, o->i2, o->hx, o->hy, o->type == SG_OP_RSCH, v, what, d);
    case SG_OP_SUMM: *v = val[o->i1 - 1] + val[o->i2 - 1]; return SG_OK;
    case SG_OP_DIFF: *v = val[o->i1 - 1] - val[o->i2 - 1]; return SG_OK;
    case SG_OP_PROD: *v = val[o->i1 - 1] * val[o->i2 - 1]; return SG_OK;
    case SG_OP_DIVI:
        if (val[o->i2 - 1] == 0.0)
            return sg_diag_set(d, SG_ERANGE, "%s: operand %d, the divisor, is 0", what, o->i2);
        *v = val[o->i1 - 1] / val[o->i2 - 1];
        return SG_OK;
    case SG_OP_OPGT:
        x = val[o->i1 - 1];
        *v = x < o->target ? x : o->target;
        return SG_OK;
    case SG_OP_OPLT:
        x = val[o->i1 - 1];
        *v = x > o->target ? x : o->target;
        return SG_OK;
    case SG_OP_ABSO: *v = fabs(val[o->i1 - 1]); return SG_OK;
    default: break;
    }
    return sg_diag_set(d, SG_ERANGE, "%s: unknown operand", what);
}

/* The default part's rows: for each field, wavelength, ring and arm, the
 * ray's x and y about the reference, weighted by the field's and the
 * wavelength's weights times the ring's quadrature weight over the arms. */
static int eval_default(ectx *c, sg_merit_result *res, int first, sg_diag *d)
{
    const sg_system *sys = c->sys;
    const sg_merit *m = &sys->merit;
    double rho[32], wt[32];
    int f, k, i, j, rc, n = first, img = sys->nsurf - 1;
    sg_merit_rings(m->rings, rho, wt);
    for (f = 0; f < sys->nfield; f++) {
        double hx, hy, cx = 0.0, cy = 0.0, sw = 0.0;
        int start = n;
        char what[160];
        sg_field_normalized(sys, f, &hx, &hy);
        for (k = 0; k < sys->nwave; k++)
            for (i = 0; i < m->rings; i++)
                for (j = 0; j < m->arms; j++) {
                    double th = PI * (2.0 * j + 1.0) / m->arms;
                    double q = sys->field[f].weight * sys->wave[k].weight * wt[i] / m->arms;
                    sg_ray_surface r;
                    snprintf(what, sizeof what, "merit: default rows %d and %d (field %d, "
                             "wavelength %d, ring %d, arm %d)", n + 1, n + 2, f + 1, k + 1, i + 1,
                             j + 1);
                    if (q == 0.0) {
                        r.x = r.y = 0.0;
                    } else if ((rc = ray_at(c, k, hx, hy, rho[i] * cos(th), rho[i] * sin(th),
                                            img, &r, what, d)) != SG_OK) {
                        return rc;
                    }
                    res->row[n].type = SG_OP_TRAX;
                    res->row[n].value = r.x;
                    res->row[n].weight = q;
                    res->row[n + 1].type = SG_OP_TRAY;
                    res->row[n + 1].value = r.y;
                    res->row[n + 1].weight = q;
                    cx += q * r.x;
                    cy += q * r.y;
                    sw += q;
                    n += 2;
                }
        if (m->reference == SG_MERIT_CHIEF) {
            sg_ray_surface r;
            snprintf(what, sizeof what, "merit: default: field %d's chief ray", f + 1);
            if ((rc = ray_at(c, sys->primary_wave, hx, hy, 0.0, 0.0, img, &r, what, d)) != SG_OK)
                return rc;
            cx = r.x;
            cy = r.y;
        } else if (sw > 0.0) {
            cx /= sw;
            cy /= sw;
        }
        for (i = start; i < n; i += 2) {
            if (res->row[i].weight == 0.0)
                continue;
            res->row[i].value -= cx;
            res->row[i + 1].value -= cy;
        }
    }
    return SG_OK;
}

void sg_merit_result_free(sg_merit_result *r)
{
    if (r) {
        free(r->row);
        r->row = NULL;
        r->nrow = 0;
    }
}

int sg_merit_eval(const sg_system *sys, const sg_catalog *cat, sg_merit_result *out,
                  sg_diag *d)
{
    const sg_merit *m = &sys->merit;
    ectx c;
    int i, rc, ndef, nrow, nconf;
    double *val = NULL, sum = 0.0, wsum = 0.0;
    memset(out, 0, sizeof *out);
    if (!m->present || (m->nop == 0 && !m->has_default))
        return sg_diag_set(d, SG_ENOSYS, "the design has no merit function (sagitta-design(5), "
                           "MERIT FUNCTION)");
    if ((rc = sg_merit_check(sys, d)) != SG_OK)
        return rc;
    /* With configurations the default part is each configuration's, after
     * a CONF row (Zemax's default merit function over all of them). */
    nconf = sys->configs ? sg_config_count(sys) : 0;
    ndef = m->has_default ? 2 * sys->nfield * sys->nwave * m->rings * m->arms : 0;
    nrow = m->nop + (nconf && ndef ? nconf * (1 + ndef) : ndef);
    memset(&c, 0, sizeof c);
    c.sys = sys;
    c.base = sys;
    c.cat = cat;
    c.rows = malloc((size_t)sys->nsurf * sizeof *c.rows);
    c.gval = calloc((size_t)(m->nop ? m->nop : 1), sizeof *c.gval);
    c.gdone = calloc((size_t)(m->nop ? m->nop : 1), 1);
    out->row = calloc((size_t)(nrow ? nrow : 1), sizeof *out->row);
    val = calloc((size_t)(m->nop ? m->nop : 1), sizeof *val);
    if (!c.rows || !out->row || !val || !c.gval || !c.gdone) {
        rc = sg_diag_set(d, SG_ENOMEM, "out of memory");
        goto done;
    }
    out->nrow = nrow;
    for (i = 0; i < m->nop; i++) {
        const sg_operand *o = &m->op[i];
        if ((rc = eval_operand(&c, i, val, &val[i], d)) != SG_OK)
            goto done;
        out->row[i].type = o->type;
        out->row[i].value = val[i];
        out->row[i].target = o->target;
        out->row[i].weight = o->type == SG_OP_BLNK || o->type == SG_OP_CONF ? 0.0 : o->weight;
    }
    if (ndef && nconf) {
        int k, at = m->nop;
        for (k = 1; k <= nconf; k++) {
            out->row[at].type = SG_OP_CONF;
            out->row[at].value = k;
            if ((rc = ectx_config(&c, k, "merit: default", d)) != SG_OK ||
                (rc = eval_default(&c, out, at + 1, d)) != SG_OK)
                goto done;
            at += 1 + ndef;
        }
    } else if (ndef && (rc = eval_default(&c, out, m->nop, d)) != SG_OK) {
        goto done;
    }
    for (i = 0; i < nrow; i++) {
        double e = out->row[i].value - out->row[i].target;
        out->row[i].row = i + 1;
        /* A row of weight 0 still shows its value and feeds others: never
         * a NaN either. */
        if (out->row[i].weight == 0.0 && isfinite(out->row[i].value))
            continue;
        if (!isfinite(out->row[i].value)) {
            rc = sg_diag_set(d, SG_ENONPHYS, "merit: row %d (%s): the value is not finite", i + 1,
                             sg_op_name(out->row[i].type));
            goto done;
        }
        out->row[i].contribution = out->row[i].weight * e * e;
        sum += out->row[i].contribution;
        wsum += out->row[i].weight;
    }
    for (i = 0; i < nrow; i++)
        out->row[i].contribution = sum > 0.0 ? 100.0 * out->row[i].contribution / sum : 0.0;
    if (!(wsum > 0.0)) {
        rc = sg_diag_set(d, SG_ERANGE, "merit: every row has weight 0");
        goto done;
    }
    out->wsum = wsum;
    out->merit = sqrt(sum / wsum);
    out->bound = c.bound;
    rc = SG_OK;
done:
    ectx_reset(&c);
    sg_system_free(c.own);
    free(c.rows);
    free(c.gval);
    free(c.gdone);
    free(val);
    if (rc != SG_OK)
        sg_merit_result_free(out);
    return rc;
}
