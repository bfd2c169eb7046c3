/*
 * views.h - pictures of the analyses: a spot diagram, ray fans or a layout
 * made into a plot_figure (plot.h), shared by the commands and the editor.
 */
#ifndef SG_UI_VIEWS_H
#define SG_UI_VIEWS_H

#include "plot.h"
#include "sagitta.h"

/* The unit to show lengths of up to extent lens units in: micrometres for
 * small ones (as Zemax shows spots and fans), else the lens unit; *scale
 * converts lens units to it. */
const char *view_length_unit(const sg_system *sys, double extent, double *scale);
/* "0.588 µm" for a wavelength. */
void view_wave_label(double um, char *buf, size_t n);
/* A field's label, "field 2 (0, 14 deg)". */
void view_field_label(const sg_system *sys, int k, char *buf, size_t n);

/* Each fills f (plot_figure_init'ed here; free with plot_figure_free);
 * 0, or -1 when out of memory. */
int view_spot_figure(const sg_system *sys, const sg_spot *s, plot_figure *f);
int view_fan_figure(const sg_system *sys, const sg_fan *fan, plot_figure *f);
int view_layout_figure(const sg_system *sys, const sg_layout *l, plot_figure *f);
/* The OPD map of one field (design field index, or -1 for a field given by
 * its normalized coordinates in ref) at wavelength um, in waves, with a
 * colour bar (files) or shades and their scale (terminal). */
int view_wavefront_figure(const sg_system *sys, const sg_wavefront *w, const sg_opd_ref *ref,
                          int field, double um, plot_figure *f);

/* The Seidel sums SI..SV, CI, CII (lens units) of every surface and their
 * total.  grouped: one chart with the seven bars side by side at each
 * surface, as Zemax's Seidel diagram (files); otherwise one small panel
 * per sum (a terminal cell holds one colour). */
extern const char *const view_seidel_names[SG_SEIDEL_N];
int view_seidel_figure(const sg_system *sys, const sg_seidel *s, int grouped, plot_figure *f);
/* Tangential and sagittal focus against field beside distortion (%)
 * against field, field on the vertical axis as Zemax draws them; failed
 * fields break the curves. */
int view_fieldcurve_figure(const sg_system *sys, const sg_fieldcurve_pt *p, int n, double um,
                           plot_figure *f);
/* The FFT MTF against frequency: each field's tangential and sagittal
 * curves and the diffraction limit. */
int view_mtf_figure(const sg_system *sys, const sg_mtf *m, plot_figure *f);
/* The FFT PSF's cross-sections along x and y through the chief ray's
 * point, one panel per field, out to 16 lambda F#. */
int view_psf_figure(const sg_system *sys, const sg_psf *p, int n, plot_figure *f);
/* Encircled or ensquared energy: a panel per field, diffraction, geometric
 * and the diffraction limit. */
int view_ee_figure(const sg_system *sys, const sg_ee *e, plot_figure *f);
/* Through-focus MTF and Strehl ratio: a panel per field. */
int view_tf_figure(const sg_system *sys, const sg_tf *t, plot_figure *f);

#endif
