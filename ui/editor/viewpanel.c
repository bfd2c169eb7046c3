/*
 * viewpanel.c - draws the analysis view below the ray line: the figure in
 * braille cells, one colour per wavelength (plain under NO_COLOR).
 */
#include <stdio.h>
#include <string.h>

#include "term.h"
#include "ui.h"
#include "view.h"

void view_draw(ui *u)
{
    ed *e = u->e;
    edview *v = &e->view;
    plot_grid g;
    int y, x;
    char head[256];
    paraxial_draw(u);
    snprintf(head, sizeof head, " %s  (g: next view, :view off)  %.1f ms", view_name(v->kind),
             v->ms_last);
    term_text(u->view_y, 0, u->cols, T_HEADER, 1, head);
    if (v->rc != SG_EOK || !v->have_fig) {
        term_text(u->view_y + 1, 0, u->cols, T_ERROR, 1,
                  v->msg[0] ? v->msg : "no picture: the design cannot be traced");
        return;
    }
    if (u->view_h < 2 || plot_grid_init(&g, u->cols, u->view_h - 1))
        return;
    plot_draw_cells(&v->fig, &g, 0, 0, u->cols, u->view_h - 1);
    for (y = 0; y < g.h; y++)
        for (x = 0; x < g.w; x++) {
            const plot_cell *c = &g.c[y * g.w + x];
            int st = c->color < 0 ? T_NORMAL : T_PLOT0 + c->color % PLOT_NPALETTE;
            if (strcmp(c->ch, " ") != 0)
                term_text(u->view_y + 1 + y, x, 1, st, 0, c->ch);
        }
    plot_grid_free(&g);
}
