/* glasspick.c - the glass picker: the search (no terminal) and its panel
 * (drawn through term.h), whose Enter runs "pick N" on the command path. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "glasspick.h"
#include "numfmt.h"
#include "term.h"
#include "ui.h"

static int contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; *hay; hay++)
        if (strncasecmp(hay, needle, n) == 0)
            return 1;
    return n == 0;
}

static int by_dist(const void *a, const void *b)
{
    const gp_hit *x = a, *y = b;
    if (x->dist != y->dist)
        return x->dist < y->dist ? -1 : 1;
    return strcmp(x->g->name, y->g->name);
}

static int by_name(const void *a, const void *b)
{
    const gp_hit *x = a, *y = b;
    int c = strcmp(x->g->name, y->g->name);
    return c ? c : strcmp(x->g->catalog, y->g->catalog);
}

/* Two numbers and nothing else: "1.5168 64.17". */
static int two_numbers(const char *q, double *nd, double *vd)
{
    char *end;
    *nd = strtod(q, &end);
    if (end == q || !isfinite(*nd))
        return 0;
    q = end;
    *vd = strtod(q, &end);
    if (end == q || !isfinite(*vd))
        return 0;
    while (*end == ' ' || *end == '\t')
        end++;
    return *end == '\0';
}

int gp_search(const sg_catalog *cat, const sg_system *sys, double um, const char *query,
              gp_list *out)
{
    size_t i, count = cat ? sg_catalog_count(cat) : 0;
    double nd = 0.0, vd = 0.0;
    int near = two_numbers(query, &nd, &vd), n = 0;
    gp_hit *h;
    gp_free(out);
    snprintf(out->query, sizeof out->query, "%s", query);
    out->um = um;
    h = malloc((count ? count : 1) * sizeof *h);
    if (!h)
        return -1;
    for (i = 0; i < count; i++) {
        const sg_glass *g = sg_catalog_at(cat, i);
        if (!near && !contains_nocase(g->name, query))
            continue;
        h[n].g = g;
        h[n].dist = fabs(g->nd - nd) / 0.01 + fabs(g->vd - vd);
        h[n].n = sys && sys->adjust_index
                     ? sg_glass_index_env(g, um, sys->temperature, sys->pressure)
                     : sg_glass_index(g, um);
        n++;
    }
    qsort(h, (size_t)n, sizeof *h, near ? by_dist : by_name);
    if (n > GP_MAX)
        n = GP_MAX;
    out->hit = h;
    out->n = n;
    return n;
}

void gp_free(gp_list *l)
{
    free(l->hit);
    l->hit = NULL;
    l->n = 0;
}

/* ------------------------------------------------------------------------
 * The panel: one glass a line, the cursor on e->glass_sel.
 * ------------------------------------------------------------------------ */

void glasses_draw(ui *u)
{
    ed *e = u->e;
    const gp_list *l = &e->glasses;
    int h = u->rows - 3, i;
    char line[256], nb[NUMFMT_MAX];
    if (h < 1)
        h = 1;
    if (e->glass_sel >= l->n)
        e->glass_sel = l->n - 1;
    if (e->glass_sel < 0)
        e->glass_sel = 0;
    if (e->glass_sel < u->glass_top)
        u->glass_top = e->glass_sel;
    if (e->glass_sel >= u->glass_top + h)
        u->glass_top = e->glass_sel - h + 1;
    for (i = 1; i < u->rows - 1; i++)
        term_fill(i, 0, u->cols, T_NORMAL);
    snprintf(line, sizeof line, "Glasses for \"%s\": %d; n at %g um.  Enter: material of "
             "surface %d; Esc: back", l->query, l->n, l->um, e->row);
    term_text(1, 0, u->cols, T_HEADER, 1, line);
    for (i = 0; i < h - 1 && u->glass_top + i < l->n; i++) {
        const gp_hit *g = &l->hit[u->glass_top + i];
        if (isfinite(g->n))
            snprintf(nb, sizeof nb, "%.6f", g->n);
        else
            snprintf(nb, sizeof nb, "-");
        snprintf(line, sizeof line, "%4d  %-20s %-10s nd %.5f  vd %6.2f  n %s",
                 u->glass_top + i + 1, g->g->name, g->g->catalog, g->g->nd, g->g->vd, nb);
        term_text(2 + i, 0, u->cols, u->glass_top + i == e->glass_sel ? T_CURSOR : T_NORMAL, 1,
                  line);
    }
    if (l->n == 0)
        term_text(2, 0, u->cols, T_NORMAL, 1, "(none)");
    term_fill(u->rows - 1, 0, u->cols, T_NORMAL);
}

int glasses_key(ui *u, int key)
{
    ed *e = u->e;
    switch (key) {
    case K_UP:
    case 'k': e->glass_sel--; break;
    case K_DOWN:
    case 'j': e->glass_sel++; break;
    case K_PGUP: e->glass_sel -= u->rows - 4; break;
    case K_PGDN:
    case ' ': e->glass_sel += u->rows - 4; break;
    case K_ENTER:
        u->mode = MODE_NORMAL;
        if (e->glasses.n > 0)
            return ui_run(u, "pick %d", e->glass_sel + 1) | ED_REDRAW;
        break;
    case K_ESC:
    case 'q': u->mode = MODE_NORMAL; break;
    default: return ED_HANDLED;
    }
    if (e->glass_sel >= e->glasses.n)
        e->glass_sel = e->glasses.n - 1;
    if (e->glass_sel < 0)
        e->glass_sel = 0;
    return ED_HANDLED | ED_REDRAW;
}
