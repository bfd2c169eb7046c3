/* setvig.c - "sagitta vignetting": Zemax's Set Vignetting, each field's
 * vignetting factors from the design's apertures (sg_set_vignetting), and
 * the design with them set. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli.h"
#include "report.h"

static void setvig_help(FILE *f)
{
    fputs(
"Usage: sagitta vignetting DESIGN.json [OPTIONS]\n"
"Compute each field's vignetting factors (VDX, VDY, VCX, VCY) as Zemax's Set\n"
"Vignetting does: the compressed, decentred pupil whose top, bottom, left and\n"
"right edge rays just pass every aperture, at the primary wavelength.  The\n"
"design's own factors are ignored while they are found.\n"
"\n"
"Options:\n"
"  --save FILE              write the design with the factors set (.json or .zmx)\n"
"  --grid N                 rays across the pupil for the centroid (default 64)\n"
"  --method M               precise (default), classic or mpfr\n"
"  --format F               text (default) or json\n"
"  -o, --output FILE        write the table to FILE instead of standard output\n"
"  -h, --help               show this help\n", f);
}

int cmd_vignetting(int argc, char **argv)
{
    cli_iter it;
    const char *design = NULL, *output = NULL, *save = NULL;
    int rc, fmt = REPORT_TEXT, method = SG_METHOD_PRECISE, i, grid = 64;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_setvig_opts o;
    sg_vigfactors *vf = NULL;
    sg_diag d;
    FILE *f;
    const cli_opt opts[] = {CLI_OPT_HELP,
                            CLI_OPT_TEXT("--save", 0, save),
                            CLI_OPT_INT("--grid", 0, grid, 4, 4096),
                            CLI_OPT_METHOD(method),
                            CLI_OPT_FORMAT(fmt),
                            CLI_OPT_OUTPUT(output),
                            CLI_END};

    cli_iter_init(&it, "vignetting", argc, argv);
    rc = cli_parse(&it, opts, &design, setvig_help);
    if (rc != CLI_EXIT_OK)
        return rc == CLI_DONE ? CLI_EXIT_OK : rc;
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    sg_setvig_opts_init(&o);
    o.trace.method = (sg_method)method;
    o.grid = grid;
    if (!(vf = calloc((size_t)sys->nfield, sizeof *vf))) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    sg_diag_clear(&d);
    rc = sg_set_vignetting(sys, cat, &o, vf, &d);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    cli_print_warnings(&d, design);
    if (save) {
        /* The design is written first: a table on the screen for a design
         * that was not saved would mislead. */
        sg_set_vignetting_apply(sys, vf);
        sg_diag_clear(&d);
        if (cli_output_is_input(save)) {
            rc = CLI_EXIT_FILE;
            goto done;
        }
        if ((rc = sg_design_save(sys, save, &d)) != SG_OK) {
            cli_error("%s", d.msg[0] ? d.msg : sg_strerror(rc));
            rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_FILE;
            goto done;
        }
    }
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
        fprintf(f, ",\n  \"method\": \"%s\",\n  \"grid\": %d,\n  \"fields\": [",
                sg_method_name((sg_method)method), grid);
        for (i = 0; i < sys->nfield; i++) {
            char a[5][40];
            fprintf(f, "%s\n    {\"field\": %d, \"vdx\": %s, \"vdy\": %s, \"vcx\": %s, "
                       "\"vcy\": %s, \"van\": %s, \"grid_rays_passing\": %ld}",
                    i ? "," : "", i + 1, cli_shortest(vf[i].vdx, a[0], 40),
                    cli_shortest(vf[i].vdy, a[1], 40), cli_shortest(vf[i].vcx, a[2], 40),
                    cli_shortest(vf[i].vcy, a[3], 40), cli_shortest(vf[i].van, a[4], 40), vf[i].pass);
        }
        fputs("\n  ]\n}\n", f);
    } else {
        fputs("Vignetting factors (Zemax's Set Vignetting, primary wavelength): a pupil\n"
              "coordinate is traced at VDX + Px (1 - VCX), VDY + Py (1 - VCY).\n", f);
        fprintf(f, "%-6s %10s %10s %12s %12s %12s %12s %8s\n", "Field", "x", "y", "VDX", "VDY",
                "VCX", "VCY", "passing");
        for (i = 0; i < sys->nfield; i++)
            fprintf(f, "%-6d %10.4g %10.4g %12.8f %12.8f %12.8f %12.8f %8ld\n", i + 1,
                    sys->field[i].x, sys->field[i].y, vf[i].vdx, vf[i].vdy, vf[i].vcx,
                    vf[i].vcy, vf[i].pass);
        if (save)
            fprintf(f, "Saved with these factors: %s\n", save);
    }
    rc = cli_close_output(f, output);
done:
    free(vf);
    cli_design_free(cat, sys);
    return rc;
}
