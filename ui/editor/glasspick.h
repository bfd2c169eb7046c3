/*
 * glasspick.h - the glass picker: catalog glasses found by name or by nd
 * and vd, each with its index at the design's primary wavelength.  The
 * search needs no terminal; glasses_draw and glasses_key (ui.h) show it.
 */
#ifndef SG_ED_GLASSPICK_H
#define SG_ED_GLASSPICK_H

#include "sagitta.h"

/* At most this many glasses are listed for one query. */
#define GP_MAX 500

typedef struct gp_hit {
    const sg_glass *g; /* points into the catalog searched */
    double n;          /* index at the wavelength searched (NaN: none) */
    double dist;       /* by nd and vd: |dnd| / 0.01 + |dvd| */
} gp_hit;

typedef struct gp_list {
    gp_hit *hit;
    int n;
    double um;         /* the wavelength of hit[].n */
    char query[128];
} gp_list;

/* Fills out from cat: when query is two numbers "ND VD", the glasses
 * nearest by nd and vd (an nd difference of 0.01 weighs as 1 in vd),
 * nearest first; otherwise every glass whose name contains query (any
 * case; empty: all), by name.  n is each glass's index at um, at sys's
 * temperature and pressure when sys->adjust_index is set.  Returns the
 * count, or -1 out of memory. */
int gp_search(const sg_catalog *cat, const sg_system *sys, double um, const char *query,
              gp_list *out);
void gp_free(gp_list *l);

#endif
