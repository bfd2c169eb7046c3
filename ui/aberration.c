/*
 * aberration.c - the "seidel" and "fieldcurve" subcommands: the engine's
 * sg_seidel_compute and sg_fieldcurve written as text, CSV, JSON or a
 * picture (views.c), with the options and output every analysis command
 * shares (ancmd.c).
 *
 * Text output passes the design's name through safe_fputs; files are
 * written through outfile, so a failed write leaves an old file whole.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ancmd.h"
#include "numfmt.h"
#include "report.h"
#include "safetext.h"
#include "views.h"


#define seidel_names view_seidel_names
static const char *const wave_names[SG_NWCOEF] = { "W040", "W131", "W222",  "W220P", "W311",
                                                   "W020", "W111", "W220S", "W220M", "W220T" };
static const char *const trans_names[SG_NTCOEF] = { "TSPH", "TSCO", "TTCO", "TAST", "TPFC",
                                                    "TSFC", "TTFC", "TDIS", "TAXC", "TLAC" };

/* A JSON string with the escapes RFC 8259 requires. */
static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20 || c == 0x7f)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

/* v with a negative zero made +0: a sum that cancels exactly is 0, and
 * "-0.000000e+00" in a table reads as a tiny negative value. */
static double nz(double v)
{
    return v == 0.0 ? 0.0 : v;
}

/* The shortest decimal that reads back to the same double (so nothing is
 * lost), -0 written 0; or null (JSON) / empty (CSV) for a value that is not
 * finite. */
static void num(FILE *f, double v, int json)
{
    char b[NUMFMT_SHORTEST_MAX];
    if (isfinite(v))
        fwrite(b, 1, numfmt_shortest_g(nz(v), b), f);
    else if (json)
        fputs("null", f);
}

/* ------------------------------------------------------------------- seidel */

static void seidel_help(FILE *f)
{
    fputs(
"Usage: sagitta seidel DESIGN.json [OPTIONS]\n"
"Print the Seidel sums of every surface and their totals: SI (spherical),\n"
"SII (coma), SIII (astigmatism), SIV (Petzval), SV (distortion), CI (axial\n"
"colour), CII (lateral colour) in lens units; Zemax's wavefront coefficients\n"
"in waves (W040 ... W220T); and the transverse aberrations TSPH ... TLAC.\n"
"Taken at the primary wavelength, the full aperture and the largest field;\n"
"colour between the shortest and the longest wavelength.  See sagitta(1).\n"
"\n"
"A picture (png, svg, pdf) is Zemax's Seidel diagram: SI to CII of each\n"
"surface and the total as bars; text on a terminal adds one braille panel\n"
"per sum.\n"
"\n"
"Options:\n"
AN_COMMON_HELP
"  -h, --help         show this help\n", f);
}

static const cli_opt seidel_opts[] = {
    AN_COMMON_OPTS,
    CLI_END
};

/* The three sets of row j (surface j, or the total at j == nsurf), each
 * value within its error bound printed as 0: rounding noise, such as the
 * distortion of a mirror at the stop, is not an aberration. */
static void seidel_row(const sg_seidel *s, int j, double *sums, double *w, double *t)
{
    const double *in = j < s->nsurf ? s->surf + (size_t)j * SG_SEIDEL_N : s->total;
    const double *eb = j < s->nsurf ? s->surf_bound + (size_t)j * SG_SEIDEL_N : s->total_bound;
    double wb[SG_NWCOEF], tb[SG_NTCOEF];
    int k;
    sg_seidel_waves(in, s->wave_lens, w);
    sg_seidel_transverse(in, s->nu_image, t);
    /* The sets are the sums times positive constants (the transverse
     * ones by 1 / (2 n'u'), taken in magnitude), so are their bounds. */
    sg_seidel_waves(eb, s->wave_lens, wb);
    sg_seidel_transverse(eb, fabs(s->nu_image), tb);
    for (k = 0; k < SG_SEIDEL_N; k++)
        sums[k] = fabs(in[k]) <= eb[k] ? 0.0 : in[k];
    for (k = 0; k < SG_NWCOEF; k++)
        w[k] = fabs(w[k]) <= wb[k] ? 0.0 : w[k];
    for (k = 0; k < SG_NTCOEF; k++)
        t[k] = fabs(t[k]) <= tb[k] ? 0.0 : t[k];
}

static void seidel_text(FILE *f, const char *design, const sg_system *sys, const sg_seidel *s)
{
    int j, k, set;
    double w[SG_NWCOEF], t[SG_NTCOEF];
    fputs("Design      : ", f);
    safe_fputs(design, f);
    fprintf(f, "\nWavelength  : %.10g um (primary); colour from %.10g to %.10g um\n",
            s->wave_um, s->short_um, s->long_um);
    fprintf(f, "Units       : %s; waves of %.10g %s\n", sys->units, s->wave_lens, sys->units);
    fprintf(f, "Lagrange H  : %.12g\nn'u' image  : %.12g\n", s->lagrange, s->nu_image);
    for (set = 0; set < 3; set++) {
        int ncol = set == 0 ? SG_SEIDEL_N : set == 1 ? SG_NWCOEF : SG_NTCOEF;
        const char *const *names = set == 0 ? seidel_names : set == 1 ? wave_names : trans_names;
        fprintf(f, "\n%s\n%-5s", set == 0   ? "Seidel sums (lens units)"
                                 : set == 1 ? "Wavefront coefficients (waves)"
                                            : "Transverse aberrations (lens units)",
                "Surf");
        for (k = 0; k < ncol; k++)
            fprintf(f, " %14s", names[k]);
        fputc('\n', f);
        for (j = 1; j <= s->nsurf; j++) {
            double row[SG_SEIDEL_N];
            const double *v = row;
            seidel_row(s, j, row, w, t);
            if (set == 1)
                v = w;
            else if (set == 2)
                v = t;
            if (j < s->nsurf)
                fprintf(f, "%-5d", j);
            else
                fprintf(f, "%-5s", "TOT");
            for (k = 0; k < ncol; k++)
                fprintf(f, " %14.6e", nz(v[k]));
            fputc('\n', f);
        }
    }
}

static void seidel_csv(FILE *f, const sg_seidel *s)
{
    int j, k;
    double w[SG_NWCOEF], t[SG_NTCOEF];
    fputs("surface", f);
    for (k = 0; k < SG_SEIDEL_N; k++)
        fprintf(f, ",%s", seidel_names[k]);
    for (k = 0; k < SG_NWCOEF; k++)
        fprintf(f, ",%s", wave_names[k]);
    for (k = 0; k < SG_NTCOEF; k++)
        fprintf(f, ",%s", trans_names[k]);
    fputc('\n', f);
    for (j = 1; j <= s->nsurf; j++) {
        double row[SG_SEIDEL_N];
        seidel_row(s, j, row, w, t);
        if (j < s->nsurf)
            fprintf(f, "%d", j);
        else
            fputs("total", f);
        for (k = 0; k < SG_SEIDEL_N; k++) {
            fputc(',', f);
            num(f, row[k], 0);
        }
        for (k = 0; k < SG_NWCOEF; k++) {
            fputc(',', f);
            num(f, w[k], 0);
        }
        for (k = 0; k < SG_NTCOEF; k++) {
            fputc(',', f);
            num(f, t[k], 0);
        }
        fputc('\n', f);
    }
}

static void json_set(FILE *f, const char *const *names, const double *v, int n)
{
    int k;
    fputc('{', f);
    for (k = 0; k < n; k++) {
        fprintf(f, "%s\"%s\": ", k ? ", " : "", names[k]);
        num(f, v[k], 1);
    }
    fputc('}', f);
}

static void seidel_json_row(FILE *f, const sg_seidel *s, int j)
{
    double row[SG_SEIDEL_N], w[SG_NWCOEF], t[SG_NTCOEF];
    seidel_row(s, j, row, w, t);
    fputs("\"sums\": ", f);
    json_set(f, seidel_names, row, SG_SEIDEL_N);
    fputs(", \"waves\": ", f);
    json_set(f, wave_names, w, SG_NWCOEF);
    fputs(", \"transverse\": ", f);
    json_set(f, trans_names, t, SG_NTCOEF);
}

static void seidel_json(FILE *f, const char *design, const sg_system *sys, const sg_seidel *s)
{
    int j;
    fputs("{\n  \"design\": ", f);
    json_str(f, design);
    fputs(",\n  \"units\": ", f);
    json_str(f, sys->units);
    fputs(",\n  \"wavelength_um\": ", f);
    num(f, s->wave_um, 1);
    fputs(",\n  \"wave_lens_units\": ", f);
    num(f, s->wave_lens, 1);
    fputs(",\n  \"colour_short_um\": ", f);
    num(f, s->short_um, 1);
    fputs(",\n  \"colour_long_um\": ", f);
    num(f, s->long_um, 1);
    fputs(",\n  \"lagrange\": ", f);
    num(f, s->lagrange, 1);
    fputs(",\n  \"nu_image\": ", f);
    num(f, s->nu_image, 1);
    fputs(",\n  \"surfaces\": [", f);
    for (j = 1; j < s->nsurf; j++) {
        fprintf(f, "%s\n    {\"surface\": %d, ", j > 1 ? "," : "", j);
        seidel_json_row(f, s, j);
        fputc('}', f);
    }
    fputs("\n  ],\n  \"total\": {", f);
    seidel_json_row(f, s, s->nsurf);
    fputs("}\n}\n", f);
}

typedef struct seidel_ctx {
    const an_cmd *a;
    const sg_seidel *s;
} seidel_ctx;

static int seidel_fig(void *ctx, plot_figure *f)
{
    const seidel_ctx *c = ctx;
    /* Files get the grouped chart; a terminal one panel per sum. */
    return view_seidel_figure(c->a->sys, c->s, c->a->fmt >= AN_FMT_PNG, f);
}

static int seidel_write(void *ctx, FILE *f, int fmt)
{
    const seidel_ctx *c = ctx;
    if (fmt == AN_FMT_CSV)
        seidel_csv(f, c->s);
    else if (fmt == AN_FMT_JSON)
        seidel_json(f, c->a->design, c->a->sys, c->s);
    else
        seidel_text(f, c->a->design, c->a->sys, c->s);
    return 0;
}

int cmd_seidel(int argc, char **argv)
{
    cli_iter it;
    const char *val;
    int id, rc;
    sg_seidel s;
    sg_diag d;
    an_cmd a;
    seidel_ctx c = {&a, &s};
    an_writer w = {seidel_fig, seidel_write, &c};

    an_cmd_init(&a, "seidel");
    cli_iter_init(&it, "seidel", argc, argv);
    while ((id = an_cmd_next(&a, &it, seidel_opts, &val)) >= 0) {
        if (id != AN_OPT_HELP)
            return CLI_EXIT_USAGE;
        seidel_help(stdout);
        return CLI_EXIT_OK;
    }
    if (id < -1)
        return -id;
    rc = an_cmd_load(&a);
    if (rc != CLI_EXIT_OK)
        return rc;
    sg_diag_clear(&d);
    rc = sg_seidel_compute(a.sys, a.cat, &s, &d);
    if (rc != SG_OK) {
        rc = an_cmd_engine_error(&a, &d, rc);
        goto done;
    }
    cli_print_warnings(&d, a.design);
    rc = an_cmd_write(&a, &w);
    sg_seidel_free(&s);
done:
    an_cmd_free(&a);
    return rc;
}

/* --------------------------------------------------------------- fieldcurve */

static void fieldcurve_help(FILE *f)
{
    fputs(
"Usage: sagitta fieldcurve DESIGN.json [OPTIONS]\n"
"Print the tangential and sagittal focus (z from the chief ray's point on\n"
"the image surface, lens units) and the distortion (%, real chief ray height\n"
"against the paraxial image height) at fields from 0 to the largest, along\n"
"+y.  The foci come from real rays a small pupil step either side of the\n"
"chief ray.  See sagitta(1).\n"
"\n"
"A picture (png, svg, pdf; braille after text on a terminal) shows both\n"
"foci against field beside the distortion against field.\n"
"\n"
"Options:\n"
"  --points N         number of fields, 2 to 100000 (default 21)\n"
"  --step D           normalized pupil step, (0, 0.1] (default 0.01;\n"
"                     0.001 with --method zemax)\n"
"  --wave N           wavelength number, from 1 (default: the primary)\n"
"  --method M         precise (default), classic or mpfr; or zemax:\n"
"                     Zemax's recipe (one ray at the step against the\n"
"                     chief ray, both from the chief ray's z), traced by\n"
"                     precise\n"
AN_COMMON_HELP
"  -h, --help         show this help\n", f);
}

static void fieldcurve_write(FILE *f, int fmt, const char *design, const sg_system *sys,
                             int wave0, const sg_fieldcurve_pt *p, int n)
{
    int i;
    const char *fu = sys->field_type == SG_FIELD_ANGLE ? "deg" : sys->units;
    if (fmt == AN_FMT_CSV) {
        fputs("hy,field,tan_focus,sag_focus,real_y,parax_y,distortion_pct,status\n", f);
        for (i = 0; i < n; i++) {
            int ok = p[i].status == SG_OK;
            num(f, p[i].hy, 0);
            fputc(',', f);
            num(f, p[i].field, 0);
            fputc(',', f);
            num(f, ok ? p[i].tan_focus : NAN, 0);
            fputc(',', f);
            num(f, ok ? p[i].sag_focus : NAN, 0);
            fputc(',', f);
            num(f, ok ? p[i].real_y : NAN, 0);
            fputc(',', f);
            num(f, p[i].parax_y, 0);
            fputc(',', f);
            num(f, ok ? p[i].distortion : NAN, 0);
            fprintf(f, ",%s\n", report_status_name(p[i].status));
        }
        return;
    }
    if (fmt == AN_FMT_JSON) {
        fputs("{\n  \"design\": ", f);
        json_str(f, design);
        fputs(",\n  \"units\": ", f);
        json_str(f, sys->units);
        fputs(",\n  \"field_units\": ", f);
        json_str(f, fu);
        fputs(",\n  \"wavelength_um\": ", f);
        num(f, sys->wave[wave0].um, 1);
        fputs(",\n  \"fields\": [", f);
        for (i = 0; i < n; i++) {
            int ok = p[i].status == SG_OK;
            fprintf(f, "%s\n    {\"hy\": ", i ? "," : "");
            num(f, p[i].hy, 1);
            fputs(", \"field\": ", f);
            num(f, p[i].field, 1);
            fputs(", \"tan_focus\": ", f);
            num(f, ok ? p[i].tan_focus : NAN, 1);
            fputs(", \"sag_focus\": ", f);
            num(f, ok ? p[i].sag_focus : NAN, 1);
            fputs(", \"real_y\": ", f);
            num(f, ok ? p[i].real_y : NAN, 1);
            fputs(", \"parax_y\": ", f);
            num(f, p[i].parax_y, 1);
            fputs(", \"distortion_pct\": ", f);
            num(f, ok ? p[i].distortion : NAN, 1);
            fputs(", \"status\": ", f);
            json_str(f, report_status_name(p[i].status));
            fputc('}', f);
        }
        fputs("\n  ]\n}\n", f);
        return;
    }
    fputs("Design      : ", f);
    safe_fputs(design, f);
    fprintf(f, "\nWavelength  : %.10g um (wave %d)\n", sys->wave[wave0].um, wave0 + 1);
    fprintf(f, "Focus       : z from the chief ray's image point, %s\n\n", sys->units);
    fprintf(f, "%10s %12s %16s %16s %16s %16s %14s  %s\n", "Hy", fu, "Tangential",
            "Sagittal", "Real y", "Paraxial y", "Distortion %", "Status");
    for (i = 0; i < n; i++) {
        fprintf(f, "%10.6f %12.6g ", p[i].hy, p[i].field);
        if (p[i].status == SG_OK)
            fprintf(f, "%16.9e %16.9e %16.9e %16.9e %14.6e  OK\n", nz(p[i].tan_focus),
                    nz(p[i].sag_focus), nz(p[i].real_y), nz(p[i].parax_y),
                    nz(p[i].distortion));
        else
            fprintf(f, "%16s %16s %16s %16.9e %14s  %s\n", "-", "-", "-", p[i].parax_y, "-",
                    report_status_name(p[i].status));
    }
}

typedef struct fc_ctx {
    const an_cmd *a;
    int wave0, n;
    const sg_fieldcurve_pt *p;
} fc_ctx;

static int fc_fig(void *ctx, plot_figure *f)
{
    const fc_ctx *c = ctx;
    return view_fieldcurve_figure(c->a->sys, c->p, c->n, c->a->sys->wave[c->wave0].um, f);
}

static int fc_write(void *ctx, FILE *f, int fmt)
{
    const fc_ctx *c = ctx;
    fieldcurve_write(f, fmt, c->a->design, c->a->sys, c->wave0, c->p, c->n);
    return 0;
}

int cmd_fieldcurve(int argc, char **argv)
{
    cli_iter it;
    const char *val;
    int id, rc, wave1 = 0, wave0 = 0, npts = 21, m = SG_METHOD_PRECISE, stepped;
    int recipe = SG_FIELDCURVE_EXACT;
    double step = NAN; /* NaN: not given */
    sg_fieldcurve_pt *pts = NULL;
    sg_trace_opts opts;
    sg_diag d;
    an_cmd a;
    fc_ctx c;
    an_writer w = {fc_fig, fc_write, &c};
    /* zemax: Zemax's recipe for the foci, traced by precise. */
    const cli_opt fieldcurve_opts[] = {
        AN_COMMON_OPTS,
        CLI_OPT_INT("--wave", 0, wave1, 1, SG_MAX_WAVES),
        CLI_OPT_WORD("--method", m, "precise|classic|mpfr|zemax", NULL),
        CLI_OPT_INT("--points", 0, npts, 2, 100000),
        CLI_OPT_NUMS("--step", &step, 1, "step"),
        CLI_END
    };

    sg_trace_opts_init(&opts);
    an_cmd_init(&a, "fieldcurve");
    cli_iter_init(&it, "fieldcurve", argc, argv);
    while ((id = an_cmd_next(&a, &it, fieldcurve_opts, &val)) >= 0) {
        if (id != AN_OPT_HELP)
            return CLI_EXIT_USAGE;
        fieldcurve_help(stdout);
        return CLI_EXIT_OK;
    }
    if (id < -1)
        return -id;
    stepped = !isnan(step);
    if (stepped && !(step > 0.0 && step <= 0.1))
        return cli_usage_error("fieldcurve", "--step: %g is not in (0, 0.1]", step);
    if (!stepped)
        step = 0.01;
    /* The engine's methods are 0 to 2 in the words' order. */
    recipe = m == 3 ? SG_FIELDCURVE_ZEMAX : SG_FIELDCURVE_EXACT;
    opts.method = m == 3 ? SG_METHOD_PRECISE : (sg_method)m;
    rc = an_cmd_load(&a);
    if (rc != CLI_EXIT_OK)
        return rc;
    rc = cli_check_wave(a.design, a.sys, wave1, &wave0);
    if (rc != CLI_EXIT_OK)
        goto done;
    opts.wave = wave0;
    pts = calloc((size_t)npts, sizeof *pts);
    if (!pts) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    sg_diag_clear(&d);
    /* Zemax's parabasal ray is at pupil 0.001. */
    if (recipe == SG_FIELDCURVE_ZEMAX && !stepped)
        step = 0.001;
    rc = sg_fieldcurve_recipe(a.sys, a.cat, &opts, npts, step, recipe, pts, &d);
    if (rc != SG_OK) {
        rc = an_cmd_engine_error(&a, &d, rc);
        goto done;
    }
    cli_print_warnings(&d, a.design);
    c.a = &a;
    c.wave0 = wave0;
    c.n = npts;
    c.p = pts;
    rc = an_cmd_write(&a, &w);
done:
    free(pts);
    an_cmd_free(&a);
    return rc;
}
