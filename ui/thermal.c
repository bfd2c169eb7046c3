/* thermal.c - "sagitta thermal": the design as built at another
 * temperature and pressure (sg_thermal, Zemax's thermal analysis), saved,
 * with the TCE each surface took and its radius and thickness before and
 * after. */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>

#include "cli.h"

static void thermal_help(FILE *f)
{
    fputs(
"Usage: sagitta thermal DESIGN.json --temperature T [--pressure P] -o OUT.json\n"
"Write the design as built at T degrees C and P atm, by Zemax's thermal\n"
"analysis: from the design's own temperature, every radius, thickness,\n"
"semi-diameter, aperture and shape term expands with the TCE of its glass\n"
"(catalog ED line) or of its mount (the surface's tce), air spaces by their\n"
"spacers touching the surfaces at their semi-diameters; temperature and\n"
"pressure are set and adjust_index turned on.  Solves are frozen.  See\n"
"sagitta-design(5), THERMAL EXPANSION.\n"
"\n"
"Options:\n"
"  --temperature T          the temperature, C (required)\n"
"  --pressure P             the air pressure, atm (default: the design's)\n"
"  -o, --output FILE        the design at T (.json or .zmx; required)\n"
"  -h, --help               show this help\n", f);
}

int cmd_thermal(int argc, char **argv)
{
    cli_iter it;
    const char *design = NULL, *output = NULL;
    int rc, i, have_t, have_p;
    double temp = NAN, pres = NAN; /* NaN: not given */
    sg_catalog *cat = NULL;
    sg_system *sys = NULL, *hot = NULL;
    sg_thermal_tce *tc = NULL;
    sg_diag d;
    const cli_opt opts[] = {CLI_OPT_HELP,
                            CLI_OPT_NUMS("--temperature", &temp, 1, "temperature"),
                            CLI_OPT_NUMS("--pressure", &pres, 1, "pressure"),
                            CLI_OPT_OUTPUT(output),
                            CLI_END};

    cli_iter_init(&it, "thermal", argc, argv);
    rc = cli_parse(&it, opts, &design, thermal_help);
    if (rc != CLI_EXIT_OK)
        return rc == CLI_DONE ? CLI_EXIT_OK : rc;
    have_t = !isnan(temp);
    have_p = !isnan(pres);
    if (have_t && !(temp >= SG_TEMP_MIN && temp <= SG_TEMP_MAX))
        return cli_usage_error("thermal", "--temperature %g: outside %g to %g C", temp,
                               SG_TEMP_MIN, SG_TEMP_MAX);
    if (have_p && !(pres >= 0.0 && pres <= SG_PRES_MAX))
        return cli_usage_error("thermal", "--pressure %g: outside 0 to %g atm", pres,
                               SG_PRES_MAX);
    if (!have_t)
        return cli_usage_error("thermal", "missing --temperature");
    if (!output)
        return cli_usage_error("thermal", "missing -o OUT.json (the design at the temperature)");
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    if (!have_p)
        pres = sys->pressure;
    hot = sg_system_new();
    tc = malloc((size_t)sys->nsurf * sizeof *tc);
    if (!hot || !tc) {
        cli_error("out of memory");
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    sg_diag_clear(&d);
    rc = sg_thermal_tces(sys, cat, tc, &d);
    if (rc == SG_OK)
        rc = sg_thermal(sys, cat, temp, pres, hot, &d);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
        goto done;
    }
    cli_print_warnings(&d, design);
    sg_diag_clear(&d);
    if (cli_output_is_input(output)) {
        rc = CLI_EXIT_FILE;
        goto done;
    }
    if ((rc = sg_design_save(hot, output, &d)) != SG_OK) {
        cli_error("%s", d.msg[0] ? d.msg : sg_strerror(rc));
        rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_FILE;
        goto done;
    }
    cli_print_warnings(&d, output);
    printf("Thermal expansion from %g C to %g C (%g atm); TCE in 1e-6/K\n", sys->temperature,
           temp, pres);
    printf("%-5s %9s %9s %-5s %22s %22s %22s %22s\n", "Surf", "TCE shape", "TCE space", "in",
           "radius", "at T", "thickness", "at T");
    for (i = 0; i < sys->nsurf; i++)
        printf("%-5d %9.4g %9.4g %-5s %22.15g %22.15g %22.15g %22.15g\n", i, tc[i].shape,
               tc[i].space, tc[i].solid ? "glass" : "air", sys->surf[i].radius,
               hot->surf[i].radius, sys->surf[i].thickness, hot->surf[i].thickness);
    printf("Saved: %s\n", output);
    rc = CLI_EXIT_OK;
done:
    free(tc);
    sg_system_free(hot);
    cli_design_free(cat, sys);
    return rc;
}
