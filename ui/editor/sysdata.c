/* sysdata.c - the system data view: the first-order data "sagitta
 * paraxial" prints, from the same writer, with the design's units,
 * wavelengths and fields beside them. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../report.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

static int add(char ***v, int *n, const char *s, size_t len)
{
    char **nv = realloc(*v, (size_t)(*n + 1) * sizeof *nv);
    char *line;
    if (!nv)
        return -1;
    *v = nv;
    line = malloc(len + 1);
    if (!line)
        return -1;
    memcpy(line, s, len);
    line[len] = '\0';
    (*v)[(*n)++] = line;
    return 0;
}

static int addf(char ***v, int *n, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int addf(char ***v, int *n, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return add(v, n, buf, strlen(buf));
}

int sysdata_lines(const ed *e, char ***lines)
{
    const sg_system *s = e->doc.sys;
    const compute *c = &e->cmp;
    char **v = NULL, *text = NULL, a[NUMFMT_MAX], b[NUMFMT_MAX], w[NUMFMT_MAX];
    size_t len = 0;
    int n = 0, i;
    FILE *f;
    report_meta m;

    *lines = NULL;
    if (!c->par_ok) {
        addf(&v, &n, "No paraxial data: %s", c->build_msg[0] ? c->build_msg : "no trace");
    } else {
        memset(&m, 0, sizeof m);
        m.design = doc_path(&e->doc) ? doc_path(&e->doc)
                                     : s->title[0] ? s->title : "(new design)";
        m.wave_index = c->par_wave + 1;
        m.wave_um = s->wave[c->par_wave].um;
        f = open_memstream(&text, &len);
        if (f) {
            report_write_paraxial(f, REPORT_TEXT, &m, &c->par);
            fclose(f);
        }
        if (text) {
            const char *p = text, *nl;
            while (*p && (nl = strchr(p, '\n')) != NULL) {
                add(&v, &n, p, (size_t)(nl - p));
                p = nl + 1;
            }
            free(text);
        }
    }
    addf(&v, &n, "%s", "");
    addf(&v, &n, "%-24s:  %s (lengths, diameters, positions and heights above; F/#, NA "
                 "and magnification have none)", "Lens units", s->units);
    addf(&v, &n, "%-24s:  %s, %s normalization", "Fields", ed_field_type_name(s->field_type),
         ed_field_norm_name(s->field_norm));
    for (i = 0; i < s->nfield; i++) {
        numfmt_shortest(s->field[i].x, a, sizeof a);
        numfmt_shortest(s->field[i].y, b, sizeof b);
        numfmt_shortest(s->field[i].weight, w, sizeof w);
        addf(&v, &n, "  field %-2d               :  x %s %s, y %s %s, weight %s", i + 1, a,
             ed_field_unit(s), b, ed_field_unit(s), w);
    }
    for (i = 0; i < s->nwave; i++) {
        numfmt_shortest(s->wave[i].um, a, sizeof a);
        numfmt_shortest(s->wave[i].weight, w, sizeof w);
        addf(&v, &n, "  wavelength %-2d          :  %s um, weight %s%s", i + 1, a, w,
             i == s->primary_wave ? " (primary)" : "");
    }
    numfmt_shortest(s->aper_value, a, sizeof a);
    addf(&v, &n, "%-24s:  %s %s", "Aperture", ed_aper_name(s->aper_type), a);
    addf(&v, &n, "%-24s:  %s", "Ray aiming", ed_aim_name(s->aim));
    if (c->warn[0])
        addf(&v, &n, "warning: %s", c->warn);
    *lines = v;
    return n;
}

void sysdata_draw(ui *u)
{
    char **v;
    int n = sysdata_lines(u->e, &v), h = u->rows - 2, i, rows = 0;
    const int W = u->cols;
    term_fill(0, 0, u->cols, T_TITLE);
    term_text(0, 0, u->cols, T_TITLE, 1,
              " System data (first order, at the primary wavelength)   Up/Down scroll, Esc "
              "closes");
    /* Long lines wrap, so nothing is cut at any width. */
    for (i = 0; i < n; i++)
        rows += v[i][0] ? ((int)strlen(v[i]) + W - 1) / W : 1;
    if (u->sys_top > rows - h)
        u->sys_top = rows - h;
    if (u->sys_top < 0)
        u->sys_top = 0;
    {
        int r = 0, y;
        for (i = 0; i < n; i++) {
            int len = (int)strlen(v[i]), off = 0;
            do {
                y = 1 + r - u->sys_top;
                if (y >= 1 && y <= h)
                    term_text(y, 0, u->cols,
                              strncmp(v[i], "warning", 7) == 0 ? T_ERROR : T_NORMAL, 1,
                              v[i] + off);
                off += W;
                r++;
            } while (off < len);
        }
    }
    for (i = 0; i < n; i++)
        free(v[i]);
    free(v);
    term_fill(u->rows - 1, 0, u->cols, T_NORMAL);
}

int sysdata_key(ui *u, int key)
{
    switch (key) {
    case K_UP:
    case 'k': u->sys_top--; break;
    case K_DOWN:
    case 'j': u->sys_top++; break;
    case K_PGUP: u->sys_top -= u->rows - 3; break;
    case K_PGDN:
    case ' ': u->sys_top += u->rows - 3; break;
    case K_ESC:
    case 'q':
    case K_F(3):
    case K_ENTER: u->mode = MODE_NORMAL; break;
    default: return ED_HANDLED;
    }
    return ED_HANDLED | ED_REDRAW;
}
