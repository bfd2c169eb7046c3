/*
 * convert.c - "sagitta import" and "sagitta export": Zemax .zmx lens files
 * to and from sagitta's JSON designs.
 *
 * Both load through cli_load_design, which reads either format and checks
 * the design against the glass catalog, so nothing is written unless the
 * whole input was understood; the output is written atomically.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

enum { OPT_SUBST = 1 };

#define MAX_SUBST 64

static void convert_help(FILE *f, int to_zmx)
{
    if (to_zmx)
        fputs("Usage: sagitta export DESIGN.json -o FILE.zmx\n"
              "Write a design as a Zemax lens file (sagitta-design(5), ZEMAX FILES).\n"
              "-o - writes to standard output.\n", f);
    else
        fputs("Usage: sagitta import [--substitute NAME=GLASS]... [--substitute-nearest]\n"
              "                      FILE.zmx|FILE.zar -o DESIGN.json\n"
              "Read a Zemax lens file (or the one in a Zemax archive) and write it as a\n"
              "sagitta design.  What sagitta\n"
              "cannot represent is refused with the file, line, surface and keyword;\n"
              "solves are kept at their stored values, with a warning.  -o - writes to\n"
              "standard output.  A glass the catalogs lack is refused unless\n"
              "--substitute NAME=GLASS (repeatable) names its substitute, or\n"
              "--substitute-nearest takes the nearest by the nd and vd the file stores\n"
              "(.zmx files only); each substitution is reported.  See sagitta-design(5),\n"
              "ZEMAX FILES.\n", f);
}

static int convert(int argc, char **argv, int to_zmx)
{
    const char *cmd = to_zmx ? "export" : "import";
    const char *val, *in = NULL, *out = NULL;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    cli_iter it;
    sg_diag d;
    int id, rc;
    const char *pairs[MAX_SUBST];
    sg_zmx_subst sub = {0, pairs, 0};
    const cli_opt opts[] = {CLI_OPT_HELP, CLI_OPT_OUTPUT(out),
                            CLI_ID("--substitute", 0, 1, OPT_SUBST),
                            CLI_OPT_FLAG_FOR("--substitute-nearest", sub.nearest, "import"),
                            CLI_END};

    cli_iter_init(&it, cmd, argc, argv);
    while ((id = cli_next_opt(&it, opts, &val)) != -1) {
        switch (id) {
        case 0:
            if (in)
                return cli_usage_error(cmd, "unexpected argument \"%s\"", val);
            in = val;
            break;
        case CLI_HELP:
            convert_help(stdout, to_zmx);
            return CLI_EXIT_OK;
        case OPT_SUBST:
            if (to_zmx)
                return cli_usage_error(cmd, "--substitute is an option of import only");
            if (!strchr(val, '=') || val[0] == '=' || !strchr(val, '=')[1])
                return cli_usage_error(cmd, "--substitute \"%s\": give NAME=GLASS", val);
            if (sub.n == MAX_SUBST)
                return cli_usage_error(cmd, "more than %d --substitute options", MAX_SUBST);
            pairs[sub.n++] = val;
            break;
        default:
            return -id;
        }
    }
    if (!in)
        return cli_usage_error(cmd, "missing %s", to_zmx ? "DESIGN.json" : "FILE.zmx");
    if (!out)
        return cli_usage_error(cmd, "missing -o %s", to_zmx ? "FILE.zmx" : "DESIGN.json");
    if ((sub.n || sub.nearest) && (sg_zar_detect(in, NULL, 0) || !sg_zmx_detect(in, NULL, 0)))
        return cli_usage_error(cmd, "--substitute and --substitute-nearest apply to .zmx files");
    rc = cli_load_design_subst(in, sub.n || sub.nearest ? &sub : NULL, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    sg_diag_clear(&d);
    if (strcmp(out, "-") == 0) {
        char *text = to_zmx ? sg_zmx_to_text(sys, cat, &d) : sg_design_to_json(sys);
        if (!text) {
            cli_error("%s: %s", in, d.msg[0] ? d.msg : "cannot write the design");
            cli_design_free(cat, sys);
            return CLI_EXIT_FILE;
        }
        fputs(text, stdout);
        free(text);
        cli_print_warnings(&d, NULL);
        cli_design_free(cat, sys);
        return cli_close_output(stdout, NULL);
    }
    if (cli_output_is_input(out)) {
        cli_design_free(cat, sys);
        return CLI_EXIT_FILE;
    }
    rc = to_zmx ? sg_zmx_save(sys, out, cat, &d) : sg_design_save(sys, out, &d);
    cli_design_free(cat, sys);
    if (rc != SG_OK) {
        cli_error("%s", d.msg[0] ? d.msg : sg_strerror(rc));
        return rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_FILE;
    }
    cli_print_warnings(&d, NULL);
    return CLI_EXIT_OK;
}

int cmd_import(int argc, char **argv)
{
    return convert(argc, argv, 0);
}

int cmd_export(int argc, char **argv)
{
    return convert(argc, argv, 1);
}
