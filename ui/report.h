/*
 * report.h - ray-trace and paraxial results as text, CSV or JSON.
 *
 * Shared by "sagitta trace" and the editor's export, so a file written by
 * either reads the same.  Numbers in CSV and JSON are printed with %.17g,
 * which a reader converts back to the identical double.
 */
#ifndef SG_UI_REPORT_H
#define SG_UI_REPORT_H

#include <stdio.h>

#include "sagitta.h"

typedef enum { REPORT_TEXT = 0, REPORT_CSV = 1, REPORT_JSON = 2 } report_fmt;

/* "text", "csv" or "json"; -1 if unknown. */
int report_parse_fmt(const char *s);

/* A --surface list of a design of nsurf surfaces (stop: its stop):
 * comma-separated items, each a surface number, OBJ (0), STO, IMA
 * (nsurf - 1) or a range A-B of them, into sel (room for nsurf) in
 * surface order, each once, and *nsel.  Returns 0, or -1 with a message
 * naming the item in err. */
int report_parse_surfaces(const char *list, int nsurf, int stop, int *sel, int *nsel,
                          char *err, size_t errlen);

typedef struct report_meta {
    const char *design; /* file name or title */
    const char *method; /* "precise" | "classic" | "mpfr" */
    int bits;           /* mpfr bits, 0 if not mpfr */
    double wave_um;     /* wavelength used */
    int wave_index;     /* 1-based */
    int csv_inputs;     /* CSV: each row starts with its ray's launch
                           (hx,hy,px,py or x0,y0,z0,l0,m0,n0) */
    int opd;            /* each ray comes with an sg_opd (report_rays_opd):
                           its OPD and transverse aberration are written */
    int global;         /* rows are in the global frame of surface
                           global_ref (trace --global), not local ones */
    int global_ref;
    const sg_system *sys; /* when set, a stopped ray's status names what
                             stopped it (sg_ray_stop_text) */
    /* When set, the rows written of each ray are those of surfaces
     * surfaces[0 .. nsurfaces - 1] (increasing), of the nsurf a ray's
     * rows hold (trace --surface); the status and OPD stay the ray's. */
    const int *surfaces;
    int nsurfaces;
} report_meta;

/* The error column is error_bound (text: ErrBound) for precise and mpfr;
 * for m->method "classic" it is error_estimate (ErrEst), since classic's
 * figure is not a bound.
 * Writes nray rays (each nsurf consecutive sg_ray_surface entries in out;
 * ray r's launch in rays[r], kind as in sg_trace_batch, may be NULL).
 * status[r] is the sg_trace_* return of ray r (may be NULL when nray == 1).
 * Returns 0, or -1 on a write error (errno set). */
int report_write(FILE *f, report_fmt fmt, const report_meta *m, int nsurf,
                 const sg_ray_surface *out, const int *status, size_t nray,
                 sg_ray_kind kind, const sg_ray_in *rays);
/* The OPD of n normalized rays (launches rays[r], rows out[r * nsurf]
 * from a trace at t's wavelength) into opd[r], each against its field's
 * reference sphere from sg_opd_reference; *ref carries the last field's
 * sphere from block to block (ref->status = SG_EINVAL before the first). */
void report_opd_block(sg_tracer *t, sg_opd_ref *ref, const sg_ray_in *rays, size_t n,
                      const sg_ray_surface *out, int nsurf, sg_opd *opd);
/* The same on threads (0: every core): the spheres are found in order,
 * then each ray's OPD in contiguous shares; the same values. */
void report_opd_block_mt(sg_tracer *t, sg_opd_ref *ref, const sg_ray_in *rays, size_t n,
                         const sg_ray_surface *out, int nsurf, sg_opd *opd, int threads);
/* report_write with each ray's OPD (see report_rays_opd). */
int report_write_opd(FILE *f, report_fmt fmt, const report_meta *m, int nsurf,
                     const sg_ray_surface *out, const int *status, size_t nray,
                     sg_ray_kind kind, const sg_ray_in *rays, const sg_opd *opd);

/* The same report written a block of rays at a time, so a long list
 * streams through bounded memory: report_begin, report_rays any number of
 * times (rays numbered on from the last call), report_end.  multi chooses
 * the list form (nray != 1 in report_write); total is the ray count that
 * the text form's header states (unused by CSV and JSON).  The bytes equal
 * report_write's for the same rays. */
typedef struct report_stream {
    FILE *f;
    report_fmt fmt;
    const report_meta *m;
    int nsurf, multi;
    sg_ray_kind kind;
    size_t next; /* number of the next ray */
    int threads; /* threads report_rays formats on; 0 or 1: the caller's */
} report_stream;

int report_begin(report_stream *s, FILE *f, report_fmt fmt, const report_meta *m,
                 int nsurf, sg_ray_kind kind, int multi, size_t total);
/* n rays: rows out[r * nsurf], status[r] (may be NULL), launch rays[r]
 * (may be NULL). */
int report_rays(report_stream *s, const sg_ray_surface *out, const int *status, size_t n,
                const sg_ray_in *rays);
/* The same with each ray's OPD in opd[r] (may be NULL), written when the
 * stream's meta asks for it: text, a line after the status; CSV, the
 * columns opd_waves, opd_error_bound, ex, ey on the image row; JSON, keys
 * of the ray's object. */
int report_rays_opd(report_stream *s, const sg_ray_surface *out, const int *status, size_t n,
                    const sg_ray_in *rays, const sg_opd *opd);
int report_end(report_stream *s);
/* Lets report_rays format a list's blocks on threads (0: every core),
 * each share into memory, written in order: the bytes are the same. */
void report_set_threads(report_stream *s, int threads);

/* Writes every field of a paraxial computation.  Returns 0, or -1 on a
 * write error (errno set). */
int report_write_paraxial(FILE *f, report_fmt fmt, const report_meta *m,
                          const sg_paraxial *p);

/* The name a report gives a ray status: "OK", "MISS", "TIR", "VIGNETTED",
 * "NOCONV", "NOT REACHED", "AIM FAILED", or the code's symbolic name
 * without its "SG_E" prefix for any other code.  Never NULL. */
const char *report_status_name(int status);

#endif
