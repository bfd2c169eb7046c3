/* settings.c - the system settings dialog and the examples menu. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "numfmt.h"
#include "term.h"
#include "ui.h"

enum {
    IT_TITLE, IT_UNITS, IT_APER_TYPE, IT_APER_VALUE, IT_FIELD_TYPE, IT_FIELD_NORM,
    IT_AIM, IT_METHOD, IT_BITS, IT_CLIP, IT_DIGITS, IT_WAVE, IT_WAVE_ADD, IT_FIELD,
    IT_FIELD_ADD
};

typedef struct item {
    int kind, idx;
} item;

#define MAX_ITEMS (IT_WAVE + SG_MAX_WAVES + 2 + SG_MAX_FIELDS + 1)

static int items(const ui *u, item *v)
{
    const sg_system *s = u->e->doc.sys;
    int n = 0, k;
    for (k = IT_TITLE; k < IT_WAVE; k++) {
        v[n].kind = k;
        v[n++].idx = 0;
    }
    for (k = 0; k < s->nwave; k++) {
        v[n].kind = IT_WAVE;
        v[n++].idx = k;
    }
    v[n].kind = IT_WAVE_ADD;
    v[n++].idx = 0;
    for (k = 0; k < s->nfield; k++) {
        v[n].kind = IT_FIELD;
        v[n++].idx = k;
    }
    v[n].kind = IT_FIELD_ADD;
    v[n++].idx = 0;
    return n;
}

static void text(const ui *u, item it, char *label, char *val, size_t n)
{
    const ed *e = u->e;
    const sg_system *s = e->doc.sys;
    char a[NUMFMT_MAX], b[NUMFMT_MAX], c[NUMFMT_MAX];
    val[0] = '\0';
    switch (it.kind) {
    case IT_TITLE: snprintf(label, n, "Title"); snprintf(val, n, "%s", s->title); break;
    case IT_UNITS: snprintf(label, n, "Lens units"); snprintf(val, n, "%s", s->units); break;
    case IT_APER_TYPE:
        snprintf(label, n, "Aperture type");
        snprintf(val, n, "%s%s", ed_aper_name(s->aper_type),
                 s->telecentric ? " (telecentric object space)" : "");
        break;
    case IT_APER_VALUE:
        snprintf(label, n, "Aperture value");
        numfmt_shortest(s->aper_value, val, n);
        break;
    case IT_FIELD_TYPE:
        snprintf(label, n, "Field type");
        snprintf(val, n, "%s", ed_field_type_name(s->field_type));
        break;
    case IT_FIELD_NORM:
        snprintf(label, n, "Field normalization");
        snprintf(val, n, "%s", ed_field_norm_name(s->field_norm));
        break;
    case IT_AIM: snprintf(label, n, "Ray aiming"); snprintf(val, n, "%s", ed_aim_name(s->aim)); break;
    case IT_METHOD:
        snprintf(label, n, "Trace method (not saved)");
        snprintf(val, n, "%s", sg_method_name(e->method));
        break;
    case IT_BITS: snprintf(label, n, "MPFR bits (not saved)"); snprintf(val, n, "%d", e->bits); break;
    case IT_CLIP:
        snprintf(label, n, "Vignette at fixed semi-diameters");
        snprintf(val, n, "%s", e->clip ? "on" : "off");
        break;
    case IT_DIGITS:
        snprintf(label, n, "Digits vs MPFR");
        snprintf(val, n, "%s", e->digits ? "on" : "off");
        break;
    case IT_WAVE:
        snprintf(label, n, "Wavelength %d%s", it.idx + 1,
                 it.idx == s->primary_wave ? " (primary)" : "");
        numfmt_shortest(s->wave[it.idx].um, a, sizeof a);
        numfmt_shortest(s->wave[it.idx].weight, b, sizeof b);
        snprintf(val, n, "%s um   weight %s", a, b);
        break;
    case IT_WAVE_ADD: snprintf(label, n, "  add a wavelength"); break;
    case IT_FIELD:
        snprintf(label, n, "Field %d", it.idx + 1);
        numfmt_shortest(s->field[it.idx].x, a, sizeof a);
        numfmt_shortest(s->field[it.idx].y, b, sizeof b);
        numfmt_shortest(s->field[it.idx].weight, c, sizeof c);
        snprintf(val, n, "x %s   y %s   weight %s", a, b, c);
        break;
    case IT_FIELD_ADD: snprintf(label, n, "  add a field"); break;
    default: label[0] = '\0'; break;
    }
}

void settings_draw(ui *u)
{
    item v[MAX_ITEMS];
    char label[128], val[512], line[700];
    int n = items(u, v), h = u->rows - 3, i;
    if (u->set_sel >= n)
        u->set_sel = n - 1;
    if (u->set_sel < 0)
        u->set_sel = 0;
    if (u->set_top > u->set_sel)
        u->set_top = u->set_sel;
    if (u->set_sel >= u->set_top + h)
        u->set_top = u->set_sel - h + 1;
    term_text(1, 0, u->cols, T_FRAME, 1,
              " System settings   Enter edit  Left/Right change  a add  d delete  "
              "p primary  < > move  F FdC  Esc close");
    for (i = 0; i < h; i++) {
        int k = u->set_top + i, y = 2 + i;
        term_fill(y, 0, u->cols, T_NORMAL);
        if (k >= n)
            continue;
        text(u, v[k], label, val, sizeof val);
        snprintf(line, sizeof line, "  %-34s %s", label, val);
        term_text(y, 0, u->cols, k == u->set_sel ? T_CURSOR : T_NORMAL, 1, line);
    }
}

static int cycle(ui *u, item it, int dir)
{
    const ed *e = u->e;
    const sg_system *s = e->doc.sys;
    static const char *const units[] = {"mm", "cm", "in", "m"};
    static const char *const methods[] = {"precise", "classic", "mpfr"};
    int k;
    switch (it.kind) {
    case IT_UNITS:
        for (k = 0; k < 4 && strcmp(units[k], s->units) != 0; k++)
            ;
        return ui_run(u, "units %s", units[((k % 4) + dir + 4) % 4]);
    case IT_APER_TYPE: {
        /* The value is kept when the new type can take it; otherwise (an
         * NA of 9, an F/# of 0 after "float") the new type starts from the
         * design's own paraxial value, so the system stays as it is, and a
         * type that cannot apply (an NA with the object at infinity) is
         * skipped: the cycle never sticks. */
        int i, f = ED_HANDLED;
        for (i = 1; i < 6; i++) {
            int t = (((int)s->aper_type + dir * i) % 6 + 6) % 6;
            double v = s->aper_value, par = 0.0;
            if (e->cmp.par_ok)
                par = t == SG_APER_EPD           ? e->cmp.par.epd
                      : t == SG_APER_IMAGE_FNUM  ? e->cmp.par.image_fnum
                      : t == SG_APER_OBJECT_NA   ? e->cmp.par.object_na
                      : t == SG_APER_PARAX_WORKING_FNUM ? e->cmp.par.working_fnum
                                                 : 0.0;
            if (t != SG_APER_FLOAT_STOP &&
                !(v > 0.0 && (t != SG_APER_OBJECT_NA || v < 1.0) &&
                  (t != SG_APER_OBJECT_CONE || v < 90.0))) {
                if (!(par > 0.0 && isfinite(par) && (t != SG_APER_OBJECT_NA || par < 1.0)))
                    continue;
                v = par;
            }
            f = ui_run(u, "aperture %s %.17g", ed_aper_name(t), v);
            if (!(f & ED_ERROR))
                return f;
        }
        return f;
    }
    case IT_FIELD_TYPE:
        return ui_run(u, "field type %s", ed_field_type_name(((int)s->field_type + dir + 4) % 4));
    case IT_FIELD_NORM:
        return ui_run(u, "field norm %s", ed_field_norm_name(s->field_norm == SG_NORM_RADIAL));
    case IT_AIM: return ui_run(u, "aim %s", ed_aim_name(((int)s->aim + dir + 3) % 3));
    case IT_METHOD: return ui_run(u, "method %s", methods[((int)e->method + dir + 3) % 3]);
    case IT_CLIP: return ui_run(u, "clip toggle");
    case IT_DIGITS: return ui_run(u, "digits toggle");
    default: return ED_HANDLED;
    }
}

static int prompt(ui *u, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int prompt(ui *u, const char *fmt, ...)
{
    char buf[LE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    ui_prompt(u, buf);
    u->back_mode = MODE_SETTINGS;
    return ED_HANDLED | ED_REDRAW;
}

static int enter(ui *u, item it)
{
    const ed *e = u->e;
    const sg_system *s = e->doc.sys;
    char a[NUMFMT_MAX], b[NUMFMT_MAX], c[NUMFMT_MAX], q[300];
    switch (it.kind) {
    case IT_TITLE:
        cmd_quote(s->title, q, sizeof q);
        return prompt(u, "title %s", q);
    case IT_APER_VALUE:
        numfmt_shortest(s->aper_value, a, sizeof a);
        return prompt(u, "aperture %s", a);
    case IT_BITS: return prompt(u, "bits %d", e->bits);
    case IT_WAVE:
        numfmt_shortest(s->wave[it.idx].um, a, sizeof a);
        numfmt_shortest(s->wave[it.idx].weight, b, sizeof b);
        return prompt(u, "wavelength set %d %s %s", it.idx + 1, a, b);
    case IT_WAVE_ADD: return prompt(u, "wavelength add ");
    case IT_FIELD:
        numfmt_shortest(s->field[it.idx].x, a, sizeof a);
        numfmt_shortest(s->field[it.idx].y, b, sizeof b);
        numfmt_shortest(s->field[it.idx].weight, c, sizeof c);
        return prompt(u, "field set %d %s %s %s", it.idx + 1, a, b, c);
    case IT_FIELD_ADD: return prompt(u, "field add ");
    default: return cycle(u, it, 1);
    }
}

int settings_key(ui *u, int key)
{
    item v[MAX_ITEMS];
    int n = items(u, v);
    item it;
    if (u->set_sel >= n)
        u->set_sel = n - 1;
    it = v[u->set_sel];
    switch (key) {
    case K_UP:
    case 'k':
        if (u->set_sel > 0)
            u->set_sel--;
        return ED_HANDLED | ED_REDRAW;
    case K_DOWN:
    case 'j':
        if (u->set_sel + 1 < n)
            u->set_sel++;
        return ED_HANDLED | ED_REDRAW;
    case K_PGUP: u->set_sel = 0; return ED_HANDLED | ED_REDRAW;
    case K_PGDN: u->set_sel = n - 1; return ED_HANDLED | ED_REDRAW;
    case K_ENTER:
    case K_F(2): return enter(u, it);
    case K_RIGHT:
    case 'l':
    case ' ': return cycle(u, it, 1);
    case K_LEFT:
    case 'h': return cycle(u, it, -1);
    case 'a':
        if (it.kind == IT_FIELD || it.kind == IT_FIELD_ADD)
            return prompt(u, "field add ");
        return prompt(u, "wavelength add ");
    case 'd':
    case K_DEL:
        if (it.kind == IT_WAVE)
            return ui_run(u, "wavelength delete %d", it.idx + 1);
        if (it.kind == IT_FIELD)
            return ui_run(u, "field delete %d", it.idx + 1);
        return ED_HANDLED;
    case 'p':
        if (it.kind == IT_WAVE)
            return ui_run(u, "wavelength primary %d", it.idx + 1);
        return ED_HANDLED;
    case '<':
    case '>':
        /* Reorders the wavelengths; the selection moves with the line. */
        if (it.kind == IT_WAVE) {
            int to = it.idx + (key == '<' ? -1 : 1), f;
            if (to < 0 || to >= u->e->doc.sys->nwave)
                return ED_HANDLED;
            f = ui_run(u, "wavelength move %d %d", it.idx + 1, to + 1);
            if (!(f & ED_ERROR))
                u->set_sel += to - it.idx;
            return f;
        }
        return ED_HANDLED;
    case 'F': return ui_run(u, "wavelength preset FdC");
    case K_ESC:
    case 'q':
    case 't':
    case K_F(4): u->mode = MODE_NORMAL; return ED_HANDLED | ED_REDRAW;
    default: return ED_HANDLED;
    }
}

void examples_open(ui *u)
{
    if (u->ex)
        ed_examples_free(u->ex, u->nex);
    u->nex = ed_examples_list(&u->ex);
    if (u->nex <= 0) {
        ed_examples_free(u->ex, u->nex > 0 ? u->nex : 0);
        u->ex = NULL;
        u->nex = 0;
        ed_msg(u->e, 1, "no bundled examples found (set SAGITTA_EXAMPLES)");
        u->mode = MODE_NORMAL;
        return;
    }
    u->ex_sel = u->ex_top = 0;
    u->mode = MODE_EXAMPLES;
}

void examples_draw(ui *u)
{
    int h = u->rows - 3, i;
    char line[300];
    if (u->ex_sel < u->ex_top)
        u->ex_top = u->ex_sel;
    if (u->ex_sel >= u->ex_top + h)
        u->ex_top = u->ex_sel - h + 1;
    term_text(1, 0, u->cols, T_FRAME, 1, " Bundled examples   Enter open  Esc close");
    for (i = 0; i < h; i++) {
        int k = u->ex_top + i;
        term_fill(2 + i, 0, u->cols, T_NORMAL);
        if (k >= u->nex)
            continue;
        snprintf(line, sizeof line, "  %s", u->ex[k]);
        term_text(2 + i, 0, u->cols, k == u->ex_sel ? T_CURSOR : T_NORMAL, 1, line);
    }
}

int examples_key(ui *u, int key)
{
    char q[300];
    switch (key) {
    case K_UP:
    case 'k':
        if (u->ex_sel > 0)
            u->ex_sel--;
        return ED_HANDLED | ED_REDRAW;
    case K_DOWN:
    case 'j':
        if (u->ex_sel + 1 < u->nex)
            u->ex_sel++;
        return ED_HANDLED | ED_REDRAW;
    case K_ENTER:
        u->mode = MODE_NORMAL;
        cmd_quote(u->ex[u->ex_sel], q, sizeof q);
        return ui_run(u, "example %s", q);
    case K_ESC:
    case 'q':
    case 'e': u->mode = MODE_NORMAL; return ED_HANDLED | ED_REDRAW;
    default: return ED_HANDLED;
    }
}
