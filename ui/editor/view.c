/*
 * view.c - the analysis behind the editor's view, rebuilt on change.
 */
#include <string.h>
#include <strings.h>

#include "compute.h"
#include "view.h"
#include "views.h"

static const char *const names[VIEW_COUNT] = {"off", "layout", "spot", "fan", "opd",
                                               "wave", "mtf", "psf", "encircled"};

const char *view_name(int kind)
{
    return kind >= 0 && kind < VIEW_COUNT ? names[kind] : "?";
}

int view_parse(const char *s)
{
    int k;
    for (k = 0; s && k < VIEW_COUNT; k++)
        if (strcasecmp(s, names[k]) == 0)
            return k;
    return -1;
}

void edview_init(edview *v)
{
    memset(v, 0, sizeof *v);
}

void edview_free(edview *v)
{
    if (v->have_fig)
        plot_figure_free(&v->fig);
    v->have_fig = 0;
    v->id = 0;
}

void edview_invalidate(edview *v)
{
    v->id = 0;
}

int edview_update(edview *v, const sg_system *sys, unsigned long id, const sg_catalog *cat,
                  const sg_trace_opts *o, int field)
{
    sg_diag d;
    double t0;
    int rc, fr = 0;
    if (v->kind == VIEW_OFF)
        return SG_EOK;
    if (field < 0 || field >= sys->nfield)
        field = sys->nfield - 1;
    if (v->kind != VIEW_FAN && v->kind != VIEW_OPD && v->kind != VIEW_WAVE && v->kind != VIEW_PSF)
        field = -1;
    if (v->id == id && v->id != 0 && v->built_kind == v->kind && v->field == field &&
        memcmp(&v->opts, o, sizeof *o) == 0)
        return v->rc;
    t0 = compute_now_ms();
    edview_free(v);
    sg_diag_clear(&d);
    v->msg[0] = '\0';
    if (v->kind == VIEW_SPOT) {
        sg_spot s;
        sg_spot_opts so;
        sg_spot_opts_init(&so);
        so.trace = *o;
        so.density = 6;
        so.max_points = 2000;
        so.nthreads = 1;
        rc = sg_spot_compute(sys, cat, &so, &s, &d);
        if (rc == SG_EOK) {
            fr = view_spot_figure(sys, &s, &v->fig);
            sg_spot_free(&s);
        }
    } else if (v->kind == VIEW_WAVE) {
        sg_wavefront w;
        sg_wavefront_opts wo;
        sg_opd_ref ref;
        sg_wavefront_opts_init(&wo);
        wo.trace = *o;
        wo.field = field;
        wo.grid = 32;
        wo.nterms = 9;
        wo.nthreads = 1;
        rc = sg_wavefront_trace(sys, cat, &wo, &w, &ref, &d);
        if (rc == SG_EOK) {
            int wv = o->wave >= 0 && o->wave < sys->nwave ? o->wave : sys->primary_wave;
            fr = view_wavefront_figure(sys, &w, &ref, field, sys->wave[wv].um, &v->fig);
            sg_wavefront_free(&w);
        }
    } else if (v->kind == VIEW_MTF) {
        sg_mtf m;
        sg_mtf_opts mo;
        memset(&m, 0, sizeof m);
        sg_mtf_opts_init(&mo);
        mo.trace = *o;
        mo.wave = o->wave;
        mo.nthreads = 1;
        rc = sg_mtf_compute(sys, cat, &mo, &m, &d);
        if (rc == SG_EOK)
            fr = view_mtf_figure(sys, &m, &v->fig);
        sg_mtf_free(&m);
    } else if (v->kind == VIEW_PSF) {
        sg_psf p;
        sg_psf_opts po;
        memset(&p, 0, sizeof p);
        sg_psf_opts_init(&po);
        po.trace = *o;
        po.wave = o->wave;
        po.nthreads = 1;
        po.field = field;
        rc = sg_psf_compute(sys, cat, &po, &p, &d);
        if (rc == SG_EOK)
            fr = view_psf_figure(sys, &p, 1, &v->fig);
        sg_psf_free(&p);
    } else if (v->kind == VIEW_EE) {
        sg_ee e;
        sg_ee_opts eo;
        memset(&e, 0, sizeof e);
        sg_ee_opts_init(&eo);
        eo.trace = *o;
        eo.wave = o->wave;
        eo.nthreads = 1;
        rc = sg_ee_compute(sys, cat, &eo, &e, &d);
        if (rc == SG_EOK)
            fr = view_ee_figure(sys, &e, &v->fig);
        sg_ee_free(&e);
    } else if (v->kind == VIEW_FAN || v->kind == VIEW_OPD) {
        sg_fan f;
        sg_fan_opts fo;
        sg_fan_opts_init(&fo);
        fo.trace = *o;
        fo.nthreads = 1;
        fo.field = field;
        fo.opd = v->kind == VIEW_OPD;
        rc = sg_fan_compute(sys, cat, &fo, &f, &d);
        if (rc == SG_EOK) {
            fr = view_fan_figure(sys, &f, &v->fig);
            sg_fan_free(&f);
        }
    } else {
        sg_layout l;
        sg_layout_opts lo;
        sg_layout_opts_init(&lo);
        lo.trace = *o;
        lo.nthreads = 1;
        rc = sg_layout_compute(sys, cat, &lo, &l, &d);
        if (rc == SG_EOK) {
            fr = view_layout_figure(sys, &l, &v->fig);
            sg_layout_free(&l);
        }
    }
    if (rc == SG_EOK && fr)
        rc = SG_ENOMEM;
    if (rc == SG_EOK || fr)
        v->have_fig = 1; /* a half-built figure is freed with the next */
    if (rc != SG_EOK)
        snprintf(v->msg, sizeof v->msg, "%s: %s", names[v->kind],
                 d.msg[0] ? d.msg : sg_strerror(rc));
    v->rc = rc;
    v->id = id;
    v->built_kind = v->kind;
    v->opts = *o;
    v->field = field;
    v->ms_last = compute_now_ms() - t0;
    return rc;
}
