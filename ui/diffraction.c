/*
 * diffraction.c - the "psf", "mtf" and "encircled" subcommands: the
 * engine's FFT PSF with its Strehl ratio (sg_psf_compute), FFT MTF
 * (sg_mtf_compute) and encircled energy (sg_ee_compute)
 * as text, CSV, JSON or a picture (views.c), with the options and output
 * every analysis command shares (ancmd.c).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ancmd.h"
#include "args.h"
#include "numfmt.h"
#include "safetext.h"
#include "views.h"

enum { D_METHOD = 1, D_FREQ };
/* throughfocus is mtf --through-focus under Zemax's own name. */
enum { K_PSF, K_MTF, K_EE, K_TF };

static const int ee_kinds[] = {SG_EE_ENCIRCLED, SG_EE_ENSQUARED};

/* Cross-sections reach 16 lambda F# either side (8 dark rings), or the
 * grid's edge. */
#define PSF_CROSS_REACH 16.0

static void diff_help(int kind, FILE *f)
{
    if (kind == K_TF)
        fputs(
"Usage: sagitta throughfocus DESIGN.json --range R --frequency F[,F...] [OPTIONS]\n"
"Print the MTF at each F cycles/mm, tangential and sagittal, and the Strehl ratio\n"
"of each field against a shift of the image plane from -R to +R lens units,\n"
"as Zemax's Through Focus MTF: the same as sagitta mtf --through-focus R\n"
"--frequency F.  See sagitta(1), mtf.\n"
"\n"
"Options:\n"
"  --range R          the image plane from -R to +R (lens units)\n"
"  --frequency F,...  cycles/mm, 1 to 8 of them\n"
"  --steps K          shifts, 2 to 1001 (default 11)\n"
"  --field N          one field (default: every field)\n"
"  --wave N           one wavelength (default: every one, by weight)\n"
"  --sampling N       pupil grid points across, 32 to 2048 (default 64)\n"
"  --method M         fft (default) or geometric; and the trace: precise\n"
"                     (default), classic or mpfr (the option may be given\n"
"                     twice)\n"
AN_COMMON_HELP
"  -h, --help         show this help\n", f);
    else if (kind == K_EE)
        fputs(
"Usage: sagitta encircled DESIGN.json [OPTIONS]\n"
"Print the fraction of each field's energy within a radius of the chief\n"
"ray's point (or, with --type ensquared, within a square of that\n"
"half-width): diffraction (the FFT PSF, see sagitta psf, integrated over\n"
"the circle or square), geometric (a square grid of rays) and the\n"
"diffraction limit (the same pupil unaberrated), radii in micrometres.\n"
"Every wavelength by its weight unless --wave is given.  See sagitta(1),\n"
"MTF AND PSF.\n"
"\n"
"Options:\n"
"  --field N          one field (default: every field)\n"
"  --wave N           one wavelength (default: every one, by weight)\n"
"  --type T           encircled (default) or ensquared\n"
"  --sampling N       pupil grid points across, 32 to 2048 (default 64)\n"
"  --rays N           geometric: rays across a square pupil grid (default 2N)\n"
"  --max-radius R     micrometres (default: the farthest ray or 5 lambda F#,\n"
"                     whichever is wider, within half the PSF grid)\n"
"  --method M         precise (default), classic or mpfr\n"
AN_COMMON_HELP
"  -h, --help         show this help\n", f);
    else if (kind == K_MTF)
        fputs(
"Usage: sagitta mtf DESIGN.json [OPTIONS]\n"
"Print the FFT (geometric or Huygens) MTF of each field, tangential (along y) and sagittal (along\n"
"x), in cycles/mm from 0 to the maximum frequency, with the diffraction\n"
"limit of the first field's pupil unaberrated.  The MTF is the modulus of\n"
"the Fourier transform of the FFT PSF (see sagitta psf): the pupil's\n"
"autocorrelation.  Every wavelength by its weight unless --wave is given.\n"
"See sagitta(1), MTF AND PSF.\n"
"\n"
"Options:\n"
"  --field N          one field (default: every field)\n"
"  --wave N           one wavelength (default: every one, by weight)\n"
"  --sampling N       pupil grid points across, 32 to 2048 (default 64)\n"
"  --max-frequency F  cycles/mm (default: the cutoff 1 / (lambda F#) of\n"
"                     the shortest wavelength)\n"
"  --method M         fft (default), geometric (the rays' MTF, from an\n"
"                     N x N grid of rays) or huygens (the Huygens PSF's\n"
"                     transform); and the trace: precise (default),\n"
"                     classic or mpfr (the option may be given twice)\n"
"  --image-size K     huygens: image points across, 3 to 1024 (default N)\n"
"  --image-delta D    huygens: their spacing in um (default: the FFT PSF's,\n"
"                     which samples up to the cutoff)\n"
"  --through-focus R  the MTF at --frequency and the Strehl ratio against\n"
"                     the image plane shifted from -R to +R (lens units)\n"
"  --frequency F,...  cycles/mm (1 to 8), with --through-focus\n"
"  --steps K          shifts, 2 to 1001 (default 11), with --through-focus\n"
AN_COMMON_HELP
"  -h, --help         show this help\n", f);
    else
        fputs(
"Usage: sagitta psf DESIGN.json [OPTIONS]\n"
"Print the FFT (or Huygens) PSF of each field: its Strehl ratio (the PSF at the chief\n"
"ray's point, the unaberrated pupil of the same shape having peak 1), its\n"
"peak, the grid (2N x 2N points, spacing lambda F# (N - 1) / 2N) and the\n"
"cross-sections along x and y through the chief ray's point.  Every\n"
"wavelength by its weight unless --wave is given.  See sagitta(1), MTF AND\n"
"PSF.\n"
"\n"
"Options:\n"
"  --field N          one field (default: every field)\n"
"  --wave N           one wavelength (default: every one, by weight)\n"
"  --sampling N       pupil grid points across, 32 to 2048 (default 64)\n"
"  --method M         fft (default) or huygens (wavelets from the reference\n"
"                     sphere summed at each image point); and the trace:\n"
"                     precise (default), classic or mpfr (the option may be\n"
"                     given twice)\n"
"  --image-size K     huygens: image points across, 3 to 1024 (default N)\n"
"  --image-delta D    huygens: their spacing in um (default: the FFT's)\n"
AN_COMMON_HELP
"  -h, --help         show this help\n", f);
}

/* %.17g, or null (JSON) / empty (CSV) for a value that is not finite. */
static void num(FILE *f, double v, int json)
{
    if (isfinite(v))
        fprintf(f, "%.17g", v);
    else if (json)
        fputs("null", f);
}

typedef struct diff_ctx {
    const an_cmd *a;
    int kind;
    int wave0;         /* -1: every wavelength */
    const sg_mtf *m;
    const sg_psf *p;   /* one per field */
    int np;
    const sg_ee *e;
    const sg_tf *tf;
} diff_ctx;

/* The half-width of the cross-sections, in grid points. */
static int psf_reach(const sg_psf *p)
{
    double lf = p->wave_um * p->fnum;
    int r = (int)ceil(PSF_CROSS_REACH * lf / fmin(p->spacing_x_um, p->spacing_y_um));
    return r < p->size / 2 ? r : p->size / 2 - 1;
}

static double psf_at(const sg_psf *p, int i, int j)
{
    int c = p->size / 2;
    return p->psf[(size_t)(c + j) * (size_t)p->size + (size_t)(c + i)];
}

static void wave_text(FILE *f, const sg_system *sys, int wave0)
{
    if (wave0 >= 0 || sys->nwave == 1)
        fprintf(f, "wavelength %d (%.6g um)", wave0 + 1 + (wave0 < 0),
                sys->wave[wave0 >= 0 ? wave0 : 0].um);
    else
        fprintf(f, "%d wavelengths by weight", sys->nwave);
}

static void mtf_write(FILE *f, int fmt, const diff_ctx *c)
{
    const sg_mtf *m = c->m;
    const sg_system *sys = c->a->sys;
    int j, k;
    if (fmt == AN_FMT_JSON) {
        fprintf(f, "{\n  \"method\": \"%s\",\n  \"sampling\": ",
                m->method == SG_MTF_GEOMETRIC ? "geometric"
                : m->method == SG_MTF_HUYGENS ? "huygens"
                                               : "fft");
        fprintf(f, "%d,\n  \"working_fnum\": ", m->sampling);
        num(f, m->fnum, 1);
        fputs(",\n  \"cutoff\": ", f);
        num(f, m->cutoff, 1);
        fputs(",\n  \"fields\": [", f);
        for (k = 0; k < m->nfield; k++) {
            fprintf(f, "%s\n    {\"field\": %d, \"frequency\": [", k ? "," : "", m->field[k] + 1);
            for (j = 0; j < m->npts; j++) {
                fputs(j ? ", " : "", f);
                num(f, m->freq[j], 1);
            }
            fputs("],\n     \"tangential\": [", f);
            for (j = 0; j < m->npts; j++) {
                fputs(j ? ", " : "", f);
                num(f, m->tan[(size_t)k * m->npts + j], 1);
            }
            fputs("],\n     \"sagittal\": [", f);
            for (j = 0; j < m->npts; j++) {
                fputs(j ? ", " : "", f);
                num(f, m->sag[(size_t)k * m->npts + j], 1);
            }
            fputs("]}", f);
        }
        fputs("\n  ],\n  \"diffraction_limit\": {\"frequency\": [", f);
        for (j = 0; j < m->npts; j++) {
            fputs(j ? ", " : "", f);
            num(f, m->freq[j], 1);
        }
        fputs("], \"mtf\": [", f);
        for (j = 0; j < m->npts; j++) {
            fputs(j ? ", " : "", f);
            num(f, m->dl[j], 1);
        }
        fputs("]}\n}\n", f);
        return;
    }
    if (fmt == AN_FMT_TEXT) {
        char t[160];
        fprintf(f, "%s MTF: %s\n",
                m->method == SG_MTF_GEOMETRIC ? "Geometric"
                : m->method == SG_MTF_HUYGENS ? "Huygens"
                                               : "FFT",
                safe_text(sys->title, t, sizeof t));
        fputs("  ", f);
        wave_text(f, sys, c->wave0);
        if (m->method == SG_MTF_GEOMETRIC)
            fprintf(f, "; %d x %d rays; working F/# %.6g; cutoff %.6g cycles/mm; the "
                       "diffraction limit by FFT\n\n", m->sampling, m->sampling, m->fnum,
                    m->cutoff);
        else if (m->method == SG_MTF_HUYGENS)
            fprintf(f, "; sampling %d x %d, onto an image of %d x %d points %.6g um apart; "
                       "working F/# %.6g; cutoff %.6g cycles/mm; the diffraction limit by "
                       "FFT\n\n", m->sampling, m->sampling, m->image_size, m->image_size,
                    m->image_delta_um, m->fnum, m->cutoff);
        else
            fprintf(f, "; sampling %d x %d, padded to %d x %d; working F/# %.6g; cutoff %.6g "
                       "cycles/mm\n\n", m->sampling, m->sampling, 2 * m->sampling,
                    2 * m->sampling, m->fnum, m->cutoff);
        fprintf(f, "%12s", "cycles/mm");
        for (k = 0; k < m->nfield; k++)
            fprintf(f, "  %5s %-3d T  %5s %-3d S", "field", m->field[k] + 1, "field",
                    m->field[k] + 1);
        fprintf(f, "  %12s\n", "diff. limit");
        for (j = 0; j < m->npts; j++) {
            fprintf(f, "%12.6g", m->freq[j]);
            for (k = 0; k < m->nfield; k++)
                fprintf(f, "  %13.6f  %13.6f", m->tan[(size_t)k * m->npts + j],
                        m->sag[(size_t)k * m->npts + j]);
            fprintf(f, "  %12.6f\n", m->dl[j]);
        }
        return;
    }
    fputs("frequency", f);
    for (k = 0; k < m->nfield; k++)
        fprintf(f, ",field%d_tangential,field%d_sagittal", m->field[k] + 1, m->field[k] + 1);
    fputs(",diffraction_limit\n", f);
    for (j = 0; j < m->npts; j++) {
        num(f, m->freq[j], 0);
        for (k = 0; k < m->nfield; k++) {
            fputc(',', f);
            num(f, m->tan[(size_t)k * m->npts + j], 0);
            fputc(',', f);
            num(f, m->sag[(size_t)k * m->npts + j], 0);
        }
        fputc(',', f);
        num(f, m->dl[j], 0);
        fputc('\n', f);
    }
}

static void psf_write(FILE *f, int fmt, const diff_ctx *c)
{
    const sg_system *sys = c->a->sys;
    int k, i;
    if (fmt == AN_FMT_JSON) {
        fputs("{\n  \"fields\": [", f);
        for (k = 0; k < c->np; k++) {
            const sg_psf *p = &c->p[k];
            int r = psf_reach(p);
            fprintf(f, "%s\n    {\"field\": %d, \"method\": \"%s\", \"strehl\": ", k ? "," : "",
                    p->field + 1, p->method == SG_PSF_HUYGENS ? "huygens" : "fft");
            num(f, p->strehl, 1);
            fputs(", \"strehl_exact\": ", f);
            num(f, p->strehl_exact, 1);
            fputs(", \"peak\": ", f);
            num(f, p->peak, 1);
            fputs(", \"spacing_um\": ", f);
            num(f, p->spacing_x_um, 1);
            fputs(", \"spacing_y_um\": ", f);
            num(f, p->spacing_y_um, 1);
            fprintf(f, ", \"size\": %d, \"sampling\": %d, \"wavelength_um\": ", p->size,
                    p->sampling);
            num(f, p->wave_um, 1);
            fputs(", \"working_fnum\": ", f);
            num(f, p->fnum, 1);
            fputs(",\n     \"offset\": [", f);
            for (i = -r; i <= r; i++)
                fprintf(f, "%s%d", i > -r ? ", " : "", i);
            fputs("],\n     \"x_section\": [", f);
            for (i = -r; i <= r; i++) {
                fputs(i > -r ? ", " : "", f);
                num(f, psf_at(p, i, 0), 1);
            }
            fputs("],\n     \"y_section\": [", f);
            for (i = -r; i <= r; i++) {
                fputs(i > -r ? ", " : "", f);
                num(f, psf_at(p, 0, i), 1);
            }
            fputs("]}", f);
        }
        fputs("\n  ]\n}\n", f);
        return;
    }
    if (fmt == AN_FMT_TEXT) {
        char t[160];
        fprintf(f, "%s PSF: %s\n  ",
                c->np && c->p[0].method == SG_PSF_HUYGENS ? "Huygens" : "FFT",
                safe_text(sys->title, t, sizeof t));
        wave_text(f, sys, c->wave0);
        fputs("\n", f);
        for (k = 0; k < c->np; k++) {
            const sg_psf *p = &c->p[k];
            fprintf(f, "\nfield %d: Strehl ratio %.6f (|mean exp(i 2 pi W)|^2 %.6f), peak "
                       "%.6f\n  pupil %d x %d %s %d x %d; image delta %.6g x %.6g um "
                       "(at %.6g um, working F/# %.6g)\n",
                    p->field + 1, p->strehl, p->strehl_exact, p->peak, p->sampling,
                    p->sampling, p->method == SG_PSF_HUYGENS ? "onto an image of" : "padded to",
                    p->size, p->size, p->spacing_x_um, p->spacing_y_um, p->wave_um, p->fnum);
        }
        fputs("\n", f);
    }
    fputs(fmt == AN_FMT_TEXT ? "  field       x (um)   along x       y (um)   along y\n"
                             : "field,x_um,psf_x,y_um,psf_y\n", f);
    for (k = 0; k < c->np; k++) {
        const sg_psf *p = &c->p[k];
        int r = psf_reach(p);
        for (i = -r; i <= r; i++) {
            if (fmt == AN_FMT_TEXT)
                fprintf(f, "%7d %12.6g %9.6f %12.6g %9.6f\n", p->field + 1, i * p->spacing_x_um,
                        psf_at(p, i, 0), i * p->spacing_y_um, psf_at(p, 0, i));
            else {
                fprintf(f, "%d,", p->field + 1);
                num(f, i * p->spacing_x_um, 0);
                fputc(',', f);
                num(f, psf_at(p, i, 0), 0);
                fputc(',', f);
                num(f, i * p->spacing_y_um, 0);
                fputc(',', f);
                num(f, psf_at(p, 0, i), 0);
                fputc('\n', f);
            }
        }
    }
}

static void ee_series(FILE *f, const char *key, const double *v, int n)
{
    int j;
    fprintf(f, "\"%s\": [", key);
    for (j = 0; j < n; j++) {
        fputs(j ? ", " : "", f);
        num(f, v[j], 1);
    }
    fputc(']', f);
}

static void ee_write(FILE *f, int fmt, const diff_ctx *c)
{
    const sg_ee *e = c->e;
    const sg_system *sys = c->a->sys;
    const char *kind = e->kind == SG_EE_ENSQUARED ? "ensquared" : "encircled";
    int j, k;
    if (fmt == AN_FMT_JSON) {
        fprintf(f, "{\n  \"type\": \"%s\",\n  \"sampling\": %d,\n  \"rays\": %d,\n"
                   "  \"working_fnum\": ", kind, e->sampling, e->rays);
        num(f, e->fnum, 1);
        fputs(",\n  \"fields\": [", f);
        for (k = 0; k < e->nfield; k++) {
            size_t o = (size_t)k * e->npts;
            fprintf(f, "%s\n    {\"field\": %d, ", k ? "," : "", e->field[k] + 1);
            ee_series(f, "radius_um", e->radius_um, e->npts);
            fputs(",\n     ", f);
            ee_series(f, "fraction", e->diffraction + o, e->npts);
            fputs(",\n     ", f);
            ee_series(f, "geometric", e->geometric + o, e->npts);
            fputs(",\n     ", f);
            ee_series(f, "diffraction_limit", e->limit + o, e->npts);
            fputc('}', f);
        }
        fputs("\n  ]\n}\n", f);
        return;
    }
    if (fmt == AN_FMT_TEXT) {
        char t[160];
        fprintf(f, "%s energy: %s\n  ", e->kind == SG_EE_ENSQUARED ? "Ensquared" : "Encircled",
                safe_text(sys->title, t, sizeof t));
        wave_text(f, sys, c->wave0);
        fprintf(f, "; FFT PSF from a %d x %d pupil; %d x %d rays; working F/# %.6g\n"
                   "  D: diffraction, G: geometric, L: diffraction limit\n\n", e->sampling,
                e->sampling, e->rays, e->rays, e->fnum);
        fprintf(f, "%15s", e->kind == SG_EE_ENSQUARED ? "half-width (um)" : "radius (um)");
        for (k = 0; k < e->nfield; k++)
            fprintf(f, "  field %-3d D  field %-3d G  field %-3d L", e->field[k] + 1,
                    e->field[k] + 1, e->field[k] + 1);
        fputc('\n', f);
        for (j = 0; j < e->npts; j++) {
            fprintf(f, "%15.6g", e->radius_um[j]);
            for (k = 0; k < e->nfield; k++) {
                size_t o = (size_t)k * e->npts + j;
                fprintf(f, "  %11.6f  %11.6f  %11.6f", e->diffraction[o], e->geometric[o],
                        e->limit[o]);
            }
            fputc('\n', f);
        }
        return;
    }
    fputs(e->kind == SG_EE_ENSQUARED ? "half_width_um" : "radius_um", f);
    for (k = 0; k < e->nfield; k++)
        fprintf(f, ",field%d_diffraction,field%d_geometric,field%d_limit", e->field[k] + 1,
                e->field[k] + 1, e->field[k] + 1);
    fputc('\n', f);
    for (j = 0; j < e->npts; j++) {
        num(f, e->radius_um[j], 0);
        for (k = 0; k < e->nfield; k++) {
            size_t o = (size_t)k * e->npts + j;
            fputc(',', f);
            num(f, e->diffraction[o], 0);
            fputc(',', f);
            num(f, e->geometric[o], 0);
            fputc(',', f);
            num(f, e->limit[o], 0);
        }
        fputc('\n', f);
    }
}

/* The frequencies as "20, 40 and 60" (%.6g each). */
static void tf_freqs_text(FILE *f, const sg_tf *t)
{
    int q;
    for (q = 0; q < t->nfreq; q++)
        fprintf(f, "%s%.6g", q == 0 ? "" : q == t->nfreq - 1 ? " and " : ", ", t->freq[q]);
}

static void tf_write(FILE *f, int fmt, const diff_ctx *c)
{
    const sg_tf *t = c->tf;
    const sg_system *sys = c->a->sys;
    int j, k, q, nq = t->nfreq;
    char g[NUMFMT_G17_MAX];
    if (fmt == AN_FMT_JSON) {
        fputs("{\n  \"frequency\": ", f);
        num(f, t->frequency, 1);
        fputs(",\n  \"frequencies\": [", f);
        for (q = 0; q < nq; q++) {
            fputs(q ? ", " : "", f);
            num(f, t->freq[q], 1);
        }
        fprintf(f, "],\n  \"units\": \"%s\",\n  \"fields\": [", sys->units);
        for (k = 0; k < t->nfield; k++) {
            size_t o = (size_t)k * nq * t->nsteps;
            fprintf(f, "%s\n    {\"field\": %d, ", k ? "," : "", t->field[k] + 1);
            ee_series(f, "shift", t->shift, t->nsteps);
            /* The first frequency's, as a one-frequency run writes them. */
            fputs(",\n     ", f);
            ee_series(f, "tangential", t->tan + o, t->nsteps);
            fputs(",\n     ", f);
            ee_series(f, "sagittal", t->sag + o, t->nsteps);
            fputs(",\n     ", f);
            ee_series(f, "strehl", t->strehl + (size_t)k * t->nsteps, t->nsteps);
            fputs(",\n     \"mtf\": [", f);
            for (q = 0; q < nq; q++) {
                size_t oq = ((size_t)k * nq + q) * t->nsteps;
                fputs(q ? ",\n       {\"frequency\": " : "\n       {\"frequency\": ", f);
                num(f, t->freq[q], 1);
                fputs(", ", f);
                ee_series(f, "tangential", t->tan + oq, t->nsteps);
                fputs(", ", f);
                ee_series(f, "sagittal", t->sag + oq, t->nsteps);
                fputc('}', f);
            }
            fputs("]}", f);
        }
        fputs("\n  ]\n}\n", f);
        return;
    }
    if (fmt == AN_FMT_TEXT) {
        char tt[160];
        fputs("Through-focus MTF at ", f);
        tf_freqs_text(f, t);
        fprintf(f, " cycles/mm and Strehl ratio: %s\n  ", safe_text(sys->title, tt, sizeof tt));
        wave_text(f, sys, c->wave0);
        fprintf(f, "; focus shift of the image plane in %s\n", sys->units);
        if (nq == 1) {
            fprintf(f, "\n%14s", "shift");
            for (k = 0; k < t->nfield; k++)
                fprintf(f, "  field %-3d T  field %-3d S  field %-3d Strehl", t->field[k] + 1,
                        t->field[k] + 1, t->field[k] + 1);
            fputc('\n', f);
            for (j = 0; j < t->nsteps; j++) {
                fprintf(f, "%14.6g", t->shift[j]);
                for (k = 0; k < t->nfield; k++) {
                    size_t o = (size_t)k * t->nsteps + j;
                    fprintf(f, "  %11.6f  %11.6f  %16.6f", t->tan[o], t->sag[o], t->strehl[o]);
                }
                fputc('\n', f);
            }
            return;
        }
        /* Several frequencies: a table a field, T and S a frequency. */
        for (k = 0; k < t->nfield; k++) {
            fprintf(f, "\nfield %d\n%14s", t->field[k] + 1, "shift");
            for (q = 0; q < nq; q++)
                fprintf(f, "  T %-9.6g  S %-9.6g", t->freq[q], t->freq[q]);
            fprintf(f, "  %11s\n", "Strehl");
            for (j = 0; j < t->nsteps; j++) {
                fprintf(f, "%14.6g", t->shift[j]);
                for (q = 0; q < nq; q++) {
                    size_t o = ((size_t)k * nq + q) * t->nsteps + j;
                    fprintf(f, "  %11.6f  %11.6f", t->tan[o], t->sag[o]);
                }
                fprintf(f, "  %11.6f\n", t->strehl[(size_t)k * t->nsteps + j]);
            }
        }
        return;
    }
    fputs("shift", f);
    for (k = 0; k < t->nfield; k++) {
        for (q = 0; q < nq; q++) {
            /* One frequency keeps its plain names; several are named by
             * their frequency in full. */
            if (nq == 1)
                g[0] = '\0';
            else
                numfmt_shortest_f(t->freq[q], g);
            fprintf(f, ",field%d_tangential%s%s,field%d_sagittal%s%s", t->field[k] + 1,
                    nq > 1 ? "_" : "", g, t->field[k] + 1, nq > 1 ? "_" : "", g);
        }
        fprintf(f, ",field%d_strehl", t->field[k] + 1);
    }
    fputc('\n', f);
    for (j = 0; j < t->nsteps; j++) {
        num(f, t->shift[j], 0);
        for (k = 0; k < t->nfield; k++) {
            for (q = 0; q < nq; q++) {
                size_t o = ((size_t)k * nq + q) * t->nsteps + j;
                fputc(',', f);
                num(f, t->tan[o], 0);
                fputc(',', f);
                num(f, t->sag[o], 0);
            }
            fputc(',', f);
            num(f, t->strehl[(size_t)k * t->nsteps + j], 0);
        }
        fputc('\n', f);
    }
}

static int diff_text(void *ctx, FILE *f, int fmt)
{
    const diff_ctx *c = ctx;
    if (c->tf)
        tf_write(f, fmt, c);
    else if (c->kind == K_EE)
        ee_write(f, fmt, c);
    else if (c->kind == K_MTF)
        mtf_write(f, fmt, c);
    else
        psf_write(f, fmt, c);
    return 0;
}

static int diff_fig(void *ctx, plot_figure *f)
{
    const diff_ctx *c = ctx;
    if (c->tf)
        return view_tf_figure(c->a->sys, c->tf, f);
    if (c->kind == K_EE)
        return view_ee_figure(c->a->sys, c->e, f);
    if (c->kind == K_MTF)
        return view_mtf_figure(c->a->sys, c->m, f);
    return view_psf_figure(c->a->sys, c->p, c->np, f);
}

/* --frequency F[,F...]: 1 to SG_TF_MAX_FREQS positive numbers of
 * cycles/mm. */
static int freq_list(const char *cmd, const char *s, double *out, int *n)
{
    int m = 1, k, bad, rc;
    const char *p;
    for (p = s; *p; p++)
        m += *p == ',';
    if (m > SG_TF_MAX_FREQS)
        return cli_usage_error(cmd, "--frequency: %d frequencies; at most %d in one run", m,
                               SG_TF_MAX_FREQS);
    rc = args_double_list(s, 0, out, m, &bad);
    if (rc != ARGS_OK)
        return cli_usage_error(cmd, "--frequency: \"%s\" is not a comma-separated list of "
                                    "numbers of cycles/mm (%s)", s, args_strerror(rc));
    for (k = 0; k < m; k++)
        if (!(out[k] > 0.0))
            return cli_usage_error(cmd, "--frequency: %.17g is not a positive number of "
                                        "cycles/mm", out[k]);
    *n = m;
    return CLI_EXIT_OK;
}

static int run(int kind, int argc, char **argv)
{
    const char *cmd = kind == K_EE    ? "encircled"
                      : kind == K_MTF ? "mtf"
                      : kind == K_TF  ? "throughfocus"
                                      : "psf",
               *val;
    int id, rc, field1 = 0, wave1 = 0, sampling = 64, method = SG_METHOD_PRECISE, k, nf;
    int eekind = SG_EE_ENCIRCLED, rays = 0, dmethod = 0, isize = 0, steps = 11;
    double maxf = 0.0, maxr = 0.0, idelta = 0.0, tfrange = 0.0, tffreq = 0.0;
    double tffreqs[SG_TF_MAX_FREQS];
    int ntf = 0;
    cli_iter it;
    an_cmd a;
    sg_diag d;
    sg_trace_opts to;
    sg_mtf m;
    sg_ee ee;
    sg_tf tf;
    sg_psf *psf = NULL;
    diff_ctx c;
    an_writer w = {diff_fig, diff_text, &c};
    const cli_opt diff_opts[] = {
        AN_COMMON_OPTS,
        CLI_OPT_INT("--field", 0, field1, 1, SG_MAX_FIELDS),
        CLI_OPT_INT("--wave", 0, wave1, 1, SG_MAX_WAVES),
        CLI_OPT_INT("--sampling", 0, sampling, SG_PSF_SAMPLING_MIN, SG_PSF_SAMPLING_MAX),
        CLI_OPT_POS_FOR("--max-frequency", maxf, "frequency", " of cycles/mm", "mtf"),
        CLI_OPT_POS_FOR("--range", tfrange, "range", NULL, "throughfocus"),
        CLI_ID("--method", 0, 1, D_METHOD),
        CLI_OPT_WORD_FOR("--type", eekind, "encircled|ensquared", ee_kinds, "encircled"),
        CLI_OPT_INT_FOR("--rays", rays, 1, 20000, "encircled"),
        CLI_OPT_POS_FOR("--max-radius", maxr, "radius", " of micrometres", "encircled"),
        CLI_OPT_INT_FOR("--image-size", isize, 3, SG_PSF_IMAGE_MAX, "psf mtf"),
        CLI_OPT_POS_FOR("--image-delta", idelta, "spacing", " of micrometres", "psf mtf"),
        CLI_OPT_POS_FOR("--through-focus", tfrange, "range", NULL, "mtf"),
        /* A list of frequencies: parsed below. */
        {"--frequency", 0, 1, D_FREQ, 0, NULL, 0, 0, NULL, NULL, NULL, NULL},
        CLI_OPT_INT_FOR("--steps", steps, 2, SG_TF_MAX_STEPS, "mtf throughfocus"),
        CLI_END
    };

    memset(&m, 0, sizeof m);
    memset(&ee, 0, sizeof ee);
    memset(&tf, 0, sizeof tf);
    memset(&c, 0, sizeof c);
    an_cmd_init(&a, cmd);
    cli_iter_init(&it, cmd, argc, argv);
    while ((id = an_cmd_next(&a, &it, diff_opts, &val)) >= 0) {
        switch (id) {
        case AN_OPT_HELP:
            diff_help(kind, stdout);
            return CLI_EXIT_OK;
        case D_METHOD:
            /* The diffraction method's names and the trace's are apart. */
            if (strcmp(val, "fft") == 0)
                dmethod = 0;
            else if (strcmp(val, "huygens") == 0 && kind == K_PSF)
                dmethod = SG_PSF_HUYGENS;
            else if (strcmp(val, "geometric") == 0 && (kind == K_MTF || kind == K_TF))
                dmethod = SG_MTF_GEOMETRIC;
            else if (strcmp(val, "huygens") == 0 && kind == K_MTF)
                dmethod = SG_MTF_HUYGENS;
            else if ((k = sg_method_parse(val)) >= 0)
                method = k;
            else
                return cli_usage_error(cmd, "--method: \"%s\" is not %s, or the trace's "
                                            "precise, classic or mpfr", val,
                                       kind == K_PSF   ? "fft or huygens"
                                       : kind == K_MTF ? "fft, geometric or huygens"
                                       : kind == K_TF  ? "fft or geometric"
                                                       : "one of");
            break;
        case D_FREQ:
            if (kind != K_MTF && kind != K_TF)
                return cli_usage_error(cmd, "--frequency is an option of mtf throughfocus only");
            if ((rc = freq_list(cmd, val, tffreqs, &ntf)) != CLI_EXIT_OK)
                return rc;
            tffreq = tffreqs[0];
            break;
        default:
            return CLI_EXIT_USAGE;
        }
    }
    if (id < -1)
        return -id;
    if (kind == K_TF && !(tfrange > 0.0 && tffreq > 0.0))
        return cli_usage_error(cmd, "give the focus range with --range R and the frequency "
                                    "with --frequency F");
    if (kind == K_TF)
        kind = K_MTF;
    if (kind == K_MTF && (tfrange > 0.0) != (tffreq > 0.0))
        return cli_usage_error(cmd, "--through-focus and --frequency go together");
    if (kind == K_MTF && tfrange == 0.0 && steps != 11)
        return cli_usage_error(cmd, "--steps is an option of --through-focus");
    if (kind == K_MTF && tfrange > 0.0 && dmethod == SG_MTF_HUYGENS)
        return cli_usage_error(cmd, "--through-focus takes --method fft or geometric");
    if (kind == K_MTF && tfrange > 0.0 && maxf > 0.0)
        return cli_usage_error(cmd, "--max-frequency does not go with --through-focus "
                                    "(--frequency gives its frequency)");
    if (((kind == K_PSF && dmethod != SG_PSF_HUYGENS) ||
         (kind == K_MTF && dmethod != SG_MTF_HUYGENS)) && (isize || idelta > 0.0))
        return cli_usage_error(cmd, "--image-size and --image-delta are options of "
                                    "--method huygens");
    rc = an_cmd_load(&a);
    if (rc != CLI_EXIT_OK)
        return rc;
    if (wave1 > a.sys->nwave || field1 > a.sys->nfield) {
        rc = cli_usage_error(cmd, "%s: %s %d is not one of 1 to %d", a.design,
                             wave1 > a.sys->nwave ? "--wave" : "--field",
                             wave1 > a.sys->nwave ? wave1 : field1,
                             wave1 > a.sys->nwave ? a.sys->nwave : a.sys->nfield);
        goto done;
    }
    sg_trace_opts_init(&to);
    to.method = (sg_method)method;
    c.a = &a;
    c.kind = kind;
    c.wave0 = wave1 - 1;
    sg_diag_clear(&d);
    if (kind == K_EE) {
        sg_ee_opts o;
        sg_ee_opts_init(&o);
        o.trace = to;
        o.field = field1 - 1;
        o.wave = wave1 - 1;
        o.sampling = sampling;
        o.rays = rays;
        o.kind = eekind;
        o.max_radius_um = maxr;
        rc = sg_ee_compute(a.sys, a.cat, &o, &ee, &d);
        c.e = &ee;
    } else if (kind == K_MTF) {
        sg_mtf_opts o;
        sg_mtf_opts_init(&o);
        o.trace = to;
        o.field = field1 - 1;
        o.wave = wave1 - 1;
        o.sampling = sampling;
        o.max_frequency = maxf;
        o.method = dmethod;
        o.image_size = isize;
        o.image_delta_um = idelta;
        if (tfrange > 0.0) {
            sg_tf_opts to2;
            sg_tf_opts_init(&to2);
            to2.mtf = o;
            to2.frequency = tffreq;
            to2.nfrequency = ntf;
            memcpy(to2.frequencies, tffreqs, (size_t)ntf * sizeof *tffreqs);
            to2.range = tfrange;
            to2.steps = steps;
            rc = sg_tf_compute(a.sys, a.cat, &to2, &tf, &d);
            c.tf = &tf;
        } else {
            rc = sg_mtf_compute(a.sys, a.cat, &o, &m, &d);
            c.m = &m;
        }
    } else {
        sg_psf_opts o;
        nf = field1 ? 1 : a.sys->nfield;
        psf = calloc((size_t)nf, sizeof *psf);
        if (!psf) {
            cli_error("out of memory");
            rc = CLI_EXIT_INTERNAL;
            goto done;
        }
        sg_psf_opts_init(&o);
        o.trace = to;
        o.wave = wave1 - 1;
        o.sampling = sampling;
        o.method = dmethod;
        o.image_size = isize;
        o.image_delta_um = idelta;
        rc = SG_OK;
        for (k = 0; k < nf && rc == SG_OK; k++) {
            o.field = field1 ? field1 - 1 : k;
            rc = sg_psf_compute(a.sys, a.cat, &o, &psf[k], &d);
            if (rc == SG_OK)
                c.np++;
        }
        c.p = psf;
    }
    if (rc != SG_OK) {
        rc = an_cmd_engine_error(&a, &d, rc);
        goto done;
    }
    cli_print_warnings(&d, a.design);
    rc = an_cmd_write(&a, &w);
done:
    if (psf)
        for (k = 0; k < c.np; k++)
            sg_psf_free(&psf[k]);
    free(psf);
    sg_mtf_free(&m);
    sg_ee_free(&ee);
    sg_tf_free(&tf);
    an_cmd_free(&a);
    return rc;
}

int cmd_mtf(int argc, char **argv)
{
    return run(K_MTF, argc, argv);
}

int cmd_throughfocus(int argc, char **argv)
{
    return run(K_TF, argc, argv);
}

int cmd_psf(int argc, char **argv)
{
    return run(K_PSF, argc, argv);
}

int cmd_encircled(int argc, char **argv)
{
    return run(K_EE, argc, argv);
}
