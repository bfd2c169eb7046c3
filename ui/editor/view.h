/*
 * view.h - the analysis view beside the spreadsheet: a layout, spot
 * diagram, ray fan, OPD fan, wavefront map, FFT MTF, FFT PSF or encircled
 * energy of the design, kept as a figure (ui/plot.h) that is
 * rebuilt whenever the document or the trace options change.  No terminal
 * here: the panel (viewpanel.c) draws the figure, export writes it.
 */
#ifndef SG_ED_VIEW_H
#define SG_ED_VIEW_H

#include "plot.h"
#include "sagitta.h"

enum {
    VIEW_OFF = 0, VIEW_LAYOUT, VIEW_SPOT, VIEW_FAN, VIEW_OPD, VIEW_WAVE, VIEW_MTF, VIEW_PSF,
    VIEW_EE, VIEW_COUNT
};

typedef struct edview {
    int kind;                 /* VIEW_* on show */
    plot_figure fig;
    int have_fig;
    int built_kind;           /* what fig shows */
    unsigned long id;         /* document state fig was built for; 0: none */
    sg_trace_opts opts;       /* and the options */
    int field;                /* and the fan's or map's field */
    int rc;                   /* SG_EOK, or why there is no figure */
    char msg[SG_DIAG_MSG + 16];
    double ms_last;           /* wall time of the last rebuild */
} edview;

/* "off", "layout", "spot", "fan", "opd", "wave", "mtf", "psf", "encircled". */
const char *view_name(int kind);
/* The kind named s, or -1. */
int view_parse(const char *s);
void edview_init(edview *v);
void edview_free(edview *v);
/* Forgets the figure so the next update rebuilds it (for the benchmark). */
void edview_invalidate(edview *v);
/* Rebuilds the figure if the kind, document state id, options or field
 * changed: the editor's sampling (spot: hexapolar, 6 rings, every field
 * and wavelength; fan: 21 points of field `field` (0-based), every
 * wavelength, since a terminal has room for one field's two fans; opd: the
 * same as OPD fans; wave: the wavefront map of field `field` at the
 * editor's wavelength (the primary when none), 32 points across; layout:
 * 7 rays a field; mtf: the FFT MTF of every field at pupil sampling 64, to
 * the cutoff; psf: the FFT PSF's cross-sections of field `field`; encircled:
 * the encircled energy of every field), traced with the editor's method
 * (the diffraction views at the editor's wavelength, polychromatic when
 * none).  Returns SG_EOK or the
 * error (also in msg). */
int edview_update(edview *v, const sg_system *sys, unsigned long id, const sg_catalog *cat,
                  const sg_trace_opts *o, int field);

#endif
