/*
 * main.c - the sagitta program: dispatches to a subcommand or the editor.
 *
 *   sagitta                     the editor, empty design
 *   sagitta FILE.json           the editor on FILE.json
 *   sagitta edit [FILE] [...]   the same, spelled out
 *   sagitta COMMAND [ARGS]      a subcommand from the table below
 *
 * The editor gets an argv whose argv[1], if present, is the design file:
 * "sagitta edit F" passes {argv[0], F}, and "sagitta F" passes argv as is.
 */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "outfile.h"
#ifdef SG_HAVE_EDITOR
#include "editor/editor.h"
#endif

/* A new subcommand is one line here plus its cmd_NAME function, which
 * handles its own --help (used by "sagitta help NAME"). */
static const cli_command commands[] = {
    { "trace", cmd_trace, "trace rays and print every surface crossing" },
    { "paraxial", cmd_paraxial, "print first-order (paraxial) data" },
    { "spot", cmd_spot, "spot diagrams: RMS and GEO radii, centroid, Airy radius" },
    { "fan", cmd_fan, "transverse ray fans, tangential and sagittal" },
    { "wavefront", cmd_wavefront, "OPD map, RMS and P-V, Zernike coefficients" },
    { "layout", cmd_layout, "a y-z cross-section of surfaces and rays" },
    { "verify", cmd_verify, "check a design's traces against the MPFR reference" },
    { "bench", cmd_bench, "measure trace throughput" },
    { "import", cmd_import, "read a Zemax .zmx lens file or .zar archive into a JSON design" },
    { "export", cmd_export, "write a design as a Zemax .zmx lens file" },
    { "seidel", cmd_seidel, "print Seidel sums: per surface, in waves and transverse" },
    { "fieldcurve", cmd_fieldcurve, "print field curvature and distortion against field" },
    { "semidiam", cmd_semidiam, "automatic semi-diameters, as Zemax computes them" },
    { "vignetting", cmd_vignetting, "vignetting factors from the apertures (Zemax's Set Vignetting)" },
    { "thermal", cmd_thermal, "the design as built at another temperature (thermal expansion)" },
    { "merit", cmd_merit, "print every row of the design's merit function and its value" },
    { "optimize", cmd_optimize, "damped least squares on the design's variables" },
    { "tolerance", cmd_tolerance, "sensitivity and Monte Carlo of the tolerances, compensated" },
    { "psf", cmd_psf, "FFT or Huygens point spread function and Strehl ratio" },
    { "mtf", cmd_mtf, "FFT, Huygens or geometric MTF, with the diffraction limit" },
    { "throughfocus", cmd_throughfocus, "MTF at chosen frequencies and Strehl ratio against focus" },
    { "encircled", cmd_encircled, "encircled and ensquared energy: diffraction and geometric" },
};
#define NCOMMANDS (sizeof commands / sizeof commands[0])

static void usage(FILE *f)
{
    size_t k;
    fputs("Usage: sagitta [FILE.json | FILE.zmx | FILE.zar]\n"
          "       sagitta edit [FILE.json | FILE.zmx | FILE.zar]\n"
          "       sagitta COMMAND [ARGS]\n"
          "       sagitta help COMMAND | --help | --version\n"
          "\n"
          "Without a command, or with a design file, sagitta opens the lens data\n"
          "editor.  Commands:\n", f);
    fprintf(f, "  %-12s %s\n", "edit", "open the lens data editor");
    for (k = 0; k < NCOMMANDS; k++)
        fprintf(f, "  %-12s %s\n", commands[k].name, commands[k].summary);
    fputs("\nRun 'sagitta help COMMAND' for a command's options; see sagitta(1).\n", f);
}

static const cli_command *find_command(const char *name)
{
    size_t k;
    for (k = 0; k < NCOMMANDS; k++)
        if (strcmp(commands[k].name, name) == 0)
            return &commands[k];
    return NULL;
}

static int run_editor(int argc, char **argv)
{
#ifdef SG_HAVE_EDITOR
    return sg_editor_main(argc, argv);
#else
    (void)argc;
    (void)argv;
    fputs("sagitta: editor not built (it needs ncursesw); the commands still "
          "work, see 'sagitta --help'\n", stderr);
    return CLI_EXIT_USAGE;
#endif
}

/* An argument that is not a command opens the editor when it looks like a
 * design file; otherwise it is far more likely a mistyped command. */
static int looks_like_file(const char *a)
{
    struct stat st;
    size_t n = strlen(a);
    return strchr(a, '/') != NULL || (n > 5 && strcmp(a + n - 5, ".json") == 0) ||
           sg_zmx_detect(a, NULL, 0) || sg_zar_detect(a, NULL, 0) || stat(a, &st) == 0;
}

int main(int argc, char **argv)
{
    const cli_command *c;
    const char *a;

    /* The engine's saves list their temporary files with ours, so a
     * signal that ends the program removes them too. */
    sg_set_temp_hook(outfile_temp_hook);
    if (argc < 2)
        return run_editor(argc, argv);
    a = argv[1];
    if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
        usage(stdout);
        return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FILE;
    }
    if (strcmp(a, "--version") == 0) {
        printf("sagitta %s\n", SG_VERSION_STRING);
        return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FILE;
    }
    if (strcmp(a, "help") == 0) {
        char *hargv[3];
        if (argc < 3) {
            usage(stdout);
            return CLI_EXIT_OK;
        }
        if (argc > 3)
            return cli_usage_error(NULL, "help: expected one command name");
        if (strcmp(argv[2], "edit") == 0) {
#ifdef SG_HAVE_EDITOR
            hargv[0] = argv[2];
            hargv[1] = (char *)"--help";
            hargv[2] = NULL;
            return sg_editor_main(2, hargv);
#endif
            fputs("Usage: sagitta edit [FILE.json]\n"
                  "Open the lens data editor on FILE.json, or on a new design.\n"
                  "'sagitta FILE.json' does the same.  See sagitta(1), EDITOR.\n",
                  stdout);
            return CLI_EXIT_OK;
        }
        c = find_command(argv[2]);
        if (!c)
            return cli_usage_error(NULL, "help: unknown command \"%s\"", argv[2]);
        hargv[0] = argv[2];
        hargv[1] = (char *)"--help";
        hargv[2] = NULL;
        return c->run(2, hargv);
    }
    if (strcmp(a, "edit") == 0) {
        /* Drop "edit" so that argv[1] is the file, as for "sagitta FILE". */
        argv[1] = argv[0];
        return run_editor(argc - 1, argv + 1);
    }
    c = find_command(a);
    if (c) {
        /* Into a pipe or file, a command's output (a ray table can be a
         * gigabyte) goes out in writes as large as a file's (outfile.h);
         * stdio's 4 KiB default would make the kernel's part of the time
         * larger than the trace's.  A terminal keeps its line buffering.
         * Nothing is written yet. */
        static char out_buf[OUTFILE_BUF];
        if (!isatty(STDOUT_FILENO))
            setvbuf(stdout, out_buf, _IOFBF, sizeof out_buf);
        return c->run(argc - 1, argv + 1);
    }
    if (a[0] == '-' && a[1] != '\0')
        return cli_usage_error(NULL, "unknown option %s", a);
    if (looks_like_file(a))
        return run_editor(argc, argv);
    return cli_usage_error(NULL, "unknown command \"%s\"", a);
}
