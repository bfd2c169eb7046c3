/*
 * cmd_ray.c - the ray and the trace's options: ray, chief, marginal, wave,
 * method, bits, digits, clip, global, view, goto and bench.
 */
#include "cmd_int.h"

/* ------------------------------------------------------------------------
 * The ray and the trace options (not part of the design)
 * ------------------------------------------------------------------------ */

static int ray_msg(ed *e)
{
    char s[4][NUMFMT_MAX];
    int i;
    for (i = 0; i < 4; i++)
        numfmt_shortest(e->ray[i], s[i], sizeof s[i]);
    e->dirty = 1;
    ed_msg(e, 0, "ray Hx %s Hy %s Px %s Py %s", s[0], s[1], s[2], s[3]);
    return OK_VIEW;
}

int c_ray(ed *e, args *a)
{
    double v[4];
    int i, bad;
    if (a->n == 2) {
        int rc = args_double_list(a->v[1], 0, v, 4, &bad);
        if (rc != ARGS_OK)
            return ec_fail(e, "ray: \"%s\": %s; give Hx,Hy,Px,Py", a->v[1], args_strerror(rc));
    } else {
        if (!ec_need(e, a, 4, 4, "ray HX HY PX PY"))
            return ED_HANDLED | ED_ERROR;
        for (i = 0; i < 4; i++)
            if (!ec_parse_num(e, a->v[i + 1], "ray", &v[i]))
                return ED_HANDLED | ED_ERROR;
    }
    memcpy(e->ray, v, sizeof v);
    return ray_msg(e);
}

int c_raycoord(ed *e, args *a)
{
    static const char *const n[] = {"hx", "hy", "px", "py"};
    int i;
    double v;
    for (i = 0; i < 4; i++)
        if (strcasecmp(a->v[0], n[i]) == 0)
            break;
    if (!ec_need(e, a, 1, 1, "hx|hy|px|py VALUE") || !ec_parse_num(e, a->v[1], n[i], &v))
        return ED_HANDLED | ED_ERROR;
    e->ray[i] = v;
    return ray_msg(e);
}

int c_chief(ed *e, args *a)
{
    e->ray[2] = e->ray[3] = 0.0;
    return ray_msg(e);
}

int c_marginal(ed *e, args *a)
{
    static const struct {
        const char *n1, *n2;
        double px, py;
    } m[] = {
        {"top", "+y", 0, 1}, {"bottom", "-y", 0, -1}, {"right", "+x", 1, 0}, {"left", "-x", -1, 0},
    };
    size_t i;
    if (!ec_need(e, a, 1, 1, "marginal top|bottom|left|right"))
        return ED_HANDLED | ED_ERROR;
    for (i = 0; i < 4; i++)
        if (strcasecmp(a->v[1], m[i].n1) == 0 || strcasecmp(a->v[1], m[i].n2) == 0) {
            e->ray[2] = m[i].px;
            e->ray[3] = m[i].py;
            return ray_msg(e);
        }
    return ec_fail(e, "marginal: \"%s\" is not top, bottom, left or right", a->v[1]);
}

int c_wave(ed *e, args *a)
{
    const sg_system *s = e->doc.sys;
    int k;
    double um;
    if (!ec_need(e, a, 1, 1, "wave N|UM|LINE"))
        return ED_HANDLED | ED_ERROR;
    if (args_int(a->v[1], INT_MIN, INT_MAX, &k) != ARGS_OK) {
        /* Not a number of the list: a wavelength in um or a line's letter,
         * which must be one of the design's (a trace is at one of them). */
        char list[512];
        size_t len = 0;
        int i;
        if (!ec_parse_um(e, a->v[1], &um))
            return ec_fail(e, "wave: \"%s\" is not a wavelength number (1 to %d), a wavelength "
                           "in um or a line (F, d, C ...)", a->v[1], s->nwave);
        for (i = 0; i < s->nwave; i++)
            if (fabs(s->wave[i].um - um) <= 1e-9 * um)
                break;
        if (i == s->nwave) {
            for (k = 0; k < s->nwave && len + 32 < sizeof list; k++)
                len += (size_t)snprintf(list + len, sizeof list - len, "%s%d: %.10g", k ? ", " : "",
                                        k + 1, s->wave[k].um);
            return ec_fail(e, "wave: %.10g um is not a wavelength of the design (%s um); "
                           ":wavelength add %s adds it", um, list, a->v[1]);
        }
        k = i + 1;
    } else if (!ec_parse_int(e, a->v[1], "wavelength", 1, s->nwave, &k)) {
        return ED_HANDLED | ED_ERROR;
    }
    e->wave = k - 1;
    e->dirty = 1;
    ed_msg(e, 0, "tracing at wavelength %d (%.10g um)", k, e->doc.sys->wave[k - 1].um);
    return OK_VIEW;
}

#define BITS_MIN 53
#define BITS_MAX 100000

int c_method(ed *e, args *a)
{
    int m, bits = e->bits;
    if (!ec_need(e, a, 1, 2, "method precise|classic|mpfr [BITS]"))
        return ED_HANDLED | ED_ERROR;
    m = sg_method_parse(a->v[1]);
    if (m < 0)
        return ec_fail(e, "method: \"%s\" is not precise, classic or mpfr", a->v[1]);
    if (a->n > 2 && !ec_parse_int(e, a->v[2], "mpfr bits", BITS_MIN, BITS_MAX, &bits))
        return ED_HANDLED | ED_ERROR;
    e->method = (sg_method)m;
    e->bits = bits;
    e->dirty = 1;
    if (m == SG_METHOD_MPFR)
        ed_msg(e, 0, "method mpfr, %d bits", bits);
    else
        ed_msg(e, 0, "method %s", sg_method_name((sg_method)m));
    return OK_VIEW;
}

int c_bits(ed *e, args *a)
{
    int bits;
    if (!ec_need(e, a, 1, 1, "bits N") ||
        !ec_parse_int(e, a->v[1], "mpfr bits", BITS_MIN, BITS_MAX, &bits))
        return ED_HANDLED | ED_ERROR;
    e->bits = bits;
    e->dirty = 1;
    ed_msg(e, 0, "mpfr precision %d bits", bits);
    return OK_VIEW;
}

int c_digits(ed *e, args *a)
{
    int on;
    if (!ec_need(e, a, 0, 1, "digits [on|off|toggle]") ||
        !ec_parse_onoff(e, a, e->digits, &on, "digits"))
        return ED_HANDLED | ED_ERROR;
    e->digits = on;
    e->dirty = 1;
    ed_msg(e, 0, "digits of agreement with mpfr %s", on ? "on" : "off");
    return OK_VIEW;
}

int c_clip(ed *e, args *a)
{
    int on;
    if (!ec_need(e, a, 0, 1, "clip [on|off|toggle]") ||
        !ec_parse_onoff(e, a, e->clip, &on, "clip"))
        return ED_HANDLED | ED_ERROR;
    e->clip = on;
    e->dirty = 1;
    ed_msg(e, 0, "vignetting at fixed semi-diameters %s", on ? "on" : "off");
    return OK_VIEW;
}

int c_global(ed *e, args *a)
{
    const char *usage = "global [on|off|SURFACE]";
    int ref;
    if (!ec_need(e, a, 0, 1, usage))
        return ED_HANDLED | ED_ERROR;
    if (a->n < 2 || strcasecmp(a->v[1], "toggle") == 0)
        ref = e->global >= 0 ? -1 : 1;
    else if (strcasecmp(a->v[1], "on") == 0)
        ref = 1;
    else if (strcasecmp(a->v[1], "off") == 0)
        ref = -1;
    else if (args_int(a->v[1], 0, e->doc.sys->nsurf - 1, &ref) != ARGS_OK)
        return ec_fail(e, "global: \"%s\" is not on, off or a surface from 0 to %d", a->v[1],
                    e->doc.sys->nsurf - 1);
    if (ref >= 0) {
        sg_diag d;
        sg_diag_clear(&d);
        if (!ed_global_frames(e, ref, &d))
            return ec_fail(e, "global: %s", d.msg);
    }
    e->global = ref;
    e->dirty = 1;
    if (ref >= 0)
        ed_msg(e, 0, "rows in the global frame of surface %d", ref);
    else
        ed_msg(e, 0, "rows in each surface's local frame");
    return OK_VIEW;
}

int c_view(ed *e, args *a)
{
    const char *usage = "view layout|spot|fan|opd|wave|mtf|psf|encircled|off|next";
    int k;
    if (!ec_need(e, a, 0, 1, usage))
        return ED_HANDLED | ED_ERROR;
    if (a->n < 2 || strcasecmp(a->v[1], "next") == 0)
        k = (e->view.kind + 1) % VIEW_COUNT;
    else if ((k = view_parse(a->v[1])) < 0)
        return ec_fail(e, "view: \"%s\" is not one of layout, spot, fan, opd, wave, mtf, psf, "
                       "encircled, off, next", a->v[1]);
    e->view.kind = k;
    e->dirty = 1;
    if (k == VIEW_OFF)
        ed_msg(e, 0, "view off: the ray's table is back");
    else
        ed_msg(e, 0, "view %s (g: next view; export FILE.png|svg|pdf writes it)",
               view_name(k));
    return OK_VIEW;
}

int c_goto(ed *e, args *a)
{
    int row;
    if (!ec_need(e, a, 1, 2, "goto SURFACE [COLUMN]") ||
        !ec_parse_row(e, a->v[1], 0, e->doc.sys->nsurf - 1, &row))
        return ED_HANDLED | ED_ERROR;
    if (a->n > 2) {
        int col = cell_parse_name(a->v[2]);
        if (col < 0)
            return ec_fail(e, "no column \"%s\"", a->v[2]);
        e->col = col;
    }
    e->row = row;
    e->msg[0] = '\0';
    return ED_HANDLED | ED_REDRAW;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int c_bench(ed *e, args *a)
{
    int n = 20, i;
    double *t, t0;
    if (!ec_need(e, a, 0, 1, "bench [N]") ||
        (a->n > 1 && !ec_parse_int(e, a->v[1], "count", 1, 100000, &n)))
        return ED_HANDLED | ED_ERROR;
    t = malloc((size_t)n * sizeof *t);
    if (!t)
        return ec_fail(e, "out of memory");
    for (i = 0; i < n; i++) {
        /* What a keystroke costs: the tracers rebuilt, the ray traced. */
        compute_invalidate(&e->cmp);
        t0 = compute_now_ms();
        ed_recompute(e);
        t[i] = compute_now_ms() - t0;
    }
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    ed_msg(e, 0,
           "recompute of %d surfaces (%s%s): %d runs, min %.3f ms, median %.3f ms, max %.3f ms%s",
           e->doc.sys->nsurf, sg_method_name(e->method), e->digits ? " + mpfr digits" : "", n,
           t[0], t[n / 2], t[n - 1], e->cmp.have ? "" : " (no trace: the design is invalid)");
    free(t);
    if (e->batch)
        fprintf(e->out, "%s\n", e->msg);
    return OK_VIEW;
}
