/* semidiam.c - "sagitta semidiam": Zemax's automatic semi-diameters of a
 * design (sg_semi_diameters) beside the ones it sets. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <math.h>

#include "cli.h"
#include "numfmt.h"
#include "report.h"


static void semidiam_help(FILE *f)
{
    fputs(
"Usage: sagitta semidiam DESIGN.json [OPTIONS]\n"
"Print each surface's automatic semi-diameter: the largest height of the real\n"
"rays through the edge of the pupil, over every field and wavelength, as Zemax\n"
"computes it, beside the semi-diameter the design sets.\n"
"\n"
"Options:\n"
"  --method M               precise (default), classic or mpfr\n"
"  --zemax                  Zemax's figure: the highest of the rays at the top\n"
"                           and bottom of the pupil's edge (and its sides for a\n"
"                           field off the axis in a system that is not centred)\n"
"  --format F               text (default) or json\n"
"  -o, --output FILE        write to FILE instead of standard output\n"
"  -h, --help               show this help\n", f);
}

/* An automatic semi-diameter in the table: the marginal rays are aimed to
 * 1e-13 of the stop radius, so 12 significant digits are all it has
 * ("1500", not "1500.0000000000002"); positional, as Zemax's editor. */
static const char *sd_text(double v, char *buf)
{
    char t[40];
    snprintf(t, sizeof t, "%.12g", v);
    numfmt_shortest_f(strtod(t, NULL), buf);
    return buf;
}

int cmd_semidiam(int argc, char **argv)
{
    cli_iter it;
    const char *design = NULL, *output = NULL;
    int rc, fmt = REPORT_TEXT, method = SG_METHOD_PRECISE, i, zemax = 0;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_semidiam_opts o;
    double *sd = NULL;
    sg_diag d;
    FILE *f;
    const cli_opt opts[] = {CLI_OPT_HELP, CLI_OPT_METHOD(method), CLI_OPT_FORMAT(fmt),
                            CLI_OPT_OUTPUT(output), CLI_OPT_FLAG("--zemax", 0, zemax), CLI_END};

    cli_iter_init(&it, "semidiam", argc, argv);
    rc = cli_parse(&it, opts, &design, semidiam_help);
    if (rc != CLI_EXIT_OK)
        return rc == CLI_DONE ? CLI_EXIT_OK : rc;
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    sg_semidiam_opts_init(&o);
    o.trace.method = (sg_method)method;
    o.zemax = zemax;
    sd = calloc((size_t)sys->nsurf, sizeof *sd);
    if (!sd) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    sg_diag_clear(&d);
    rc = sg_semi_diameters(sys, cat, &o, sd, &d);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    cli_print_warnings(&d, design);
    f = cli_open_output(output);
    if (!f) {
        rc = CLI_EXIT_FILE;
        goto done;
    }
    if (fmt == REPORT_JSON) {
        cJSON *js = cJSON_CreateString(design);
        char *q = js ? cJSON_PrintUnformatted(js) : NULL;
        cJSON_Delete(js);
        fprintf(f, "{\n  \"design\": %s", q ? q : "null");
        cJSON_free(q);
        fprintf(f, ",\n  \"method\": \"%s\",\n  \"surfaces\": [", sg_method_name((sg_method)method));
        for (i = 1; i < sys->nsurf; i++) {
            char a[40], b[40];
            fprintf(f, "%s\n    {\"surface\": %d, \"auto\": %s, \"set\": %s, \"fixed\": %s}",
                    i > 1 ? "," : "", i, cli_shortest(sd[i], a, sizeof a),
                    cli_shortest(sys->surf[i].semi_diameter, b, sizeof b),
                    sys->surf[i].sd_fixed ? "true" : "false");
        }
        fputs("\n  ]\n}\n", f);
    } else {
        if (zemax)
            fputs("Automatic semi-diameters as Zemax stores them: the largest height of the\n"
                  "rays at the top and bottom of the pupil's edge (and its sides, for a field\n"
                  "off the axis in a system that is not centred) over every field and\n"
                  "wavelength; lengths in lens units.\n", f);
        else
            fputs("Automatic semi-diameters: the largest height of the rays through the pupil's\n"
                  "edge over every field and wavelength (Zemax's rule); lengths in lens units.\n", f);
        fprintf(f, "%-8s %24s %24s  %s\n", "Surface", "Automatic", "Set", "");
        for (i = 1; i < sys->nsurf; i++) {
            const sg_surface *s = &sys->surf[i];
            char a[NUMFMT_SHORTEST_MAX], b[NUMFMT_SHORTEST_MAX];
            const char *note = "";
            if (s->type == SG_SURF_COORDBRK)
                note = "coordinate break";
            else if (s->sd_fixed && s->semi_diameter < sd[i] * (1.0 - 1e-12))
                note = "fixed below the rays: vignettes";
            else if (s->sd_fixed)
                note = "fixed";
            fprintf(f, "%-8d %24s %24s  %s\n", i, sd_text(sd[i], a),
                    s->semi_diameter > 0.0 ? (numfmt_shortest_f(s->semi_diameter, b), b) : "-",
                    note);
        }
    }
    rc = cli_close_output(f, output);
done:
    free(sd);
    cli_design_free(cat, sys);
    return rc;
}
