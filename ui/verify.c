/*
 * verify.c - "sagitta verify": the precise and classic traces of a design,
 * or of the paper's two experiments, checked against an MPFR trace of the
 * same double inputs.
 *
 * The reference is the engine's mpfr method, so all three methods see
 * exactly the same rays; what differs is only the arithmetic.  A point's
 * digits are judged against the point's own size (see point_digits), so a
 * coordinate that is zero in exact arithmetic does not read as 0 digits
 * because of an error of 1e-17.
 */
#include "verify_int.h"

static void verify_help(FILE *f)
{
    fputs(
"Usage: sagitta verify DESIGN.json [--ray Hx,Hy,Px,Py | --grid N] [OPTIONS]\n"
"       sagitta verify --experiment table1|table2 [OPTIONS]\n"
"Trace rays with the precise and the classic method and compare both with an\n"
"MPFR trace of the same double inputs.\n"
"\n"
"Ray set (default: every field point of the design times a 7 x 7 pupil grid\n"
"clipped to the unit circle, plus the chief and the four marginal rays):\n"
"  --ray Hx,Hy,Px,Py        check this one ray only\n"
"  --grid N                 N x N pupil grid, 1 to 101\n"
"\n"
"Experiments (no design file):\n"
"  --experiment table1      the paper's Table 1: a sphere of radius 8 and ray\n"
"                           starts from 1e0 to 1e9 mm away\n"
"  --experiment table2      the paper's Table 2: rays from the centre of the\n"
"                           unit sphere with scaled, random directions\n"
"  --count N                rays of table2 (10000)\n"
"  --seed S                 random seed of table2 (20230421)\n"
"\n"
"Options:\n"
"  --bits N                 precision of the MPFR reference, 128 to 100000 (256)\n"
"  --wave N                 wavelength number, from 1 (default: the primary)\n"
"  --format F               text (default) or json\n"
"  -o, --output FILE        write to FILE instead of standard output\n"
"  -h, --help               show this help\n"
"\n"
"Digits of a coordinate a against the reference b are\n"
"-log10(|a - b| / max(|b|, 1e-6 * max|b_k|)), 17 when equal; a point has the\n"
"least of its three.  The exit status is 6 when the precise method's error\n"
"bound is below its actual error, or when it fails a ray the reference\n"
"traces; see sagitta(1).\n", f);
}

/* ----------------------------------------------------------------- command */

int cmd_verify(int argc, char **argv)
{
    cli_iter it;
    const char *val, *design = NULL, *output = NULL, *experiment = NULL;
    int id, bits = 256, wave1 = 0, grid = 0, count = 0, fmt = REPORT_TEXT, table = -1;
    int have_ray, have_seed, seed = -1; /* -1: not given */
    double ray4[4] = {NAN, 0, 0, 0};    /* NaN: not given */
    const cli_opt opts[] = {CLI_OPT_HELP,
                            CLI_OPT_NUMS("--ray", ray4, 4, "Hx,Hy,Px,Py"),
                            CLI_OPT_INT("--grid", 0, grid, 1, 101),
                            CLI_OPT_INT("--bits", 0, bits, 53, 100000),
                            CLI_OPT_INT("--wave", 0, wave1, 1, SG_MAX_WAVES),
                            CLI_OPT_FORMAT(fmt),
                            CLI_OPT_OUTPUT(output),
                            CLI_OPT_WORD("--experiment", table, "table1|table2", NULL),
                            CLI_OPT_INT("--count", 0, count, 1, 10000000),
                            CLI_OPT_INT("--seed", 0, seed, 0, 2147483647),
                            CLI_END};

    cli_iter_init(&it, "verify", argc, argv);
    while ((id = cli_next_opt(&it, opts, &val)) != -1) {
        if (id == 0) {
            if (design)
                return cli_usage_error("verify", "unexpected argument \"%s\"", val);
            design = val;
        } else if (id == CLI_HELP) {
            verify_help(stdout);
            return fflush(stdout) == 0 ? CLI_EXIT_OK : CLI_EXIT_FILE;
        } else {
            return -id;
        }
    }
    if (bits < VERIFY_MIN_BITS) {
        /* The precise method carries 106 bits; a reference with fewer
         * than about twice a double's cannot judge it, and would report
         * its own error as precise's. */
        return cli_usage_error("verify",
                               "--bits %d: a reference of fewer than %d bits is no "
                               "reference for a method that carries 106; use %d "
                               "or more", bits, VERIFY_MIN_BITS, VERIFY_MIN_BITS);
    }
    have_ray = !isnan(ray4[0]);
    have_seed = seed >= 0;
    if (!have_seed)
        seed = DEFAULT_SEED;
    if (table >= 0)
        experiment = table == 0 ? "table1" : "table2";

    if (experiment) {
        if (design)
            return cli_usage_error("verify", "--experiment takes no design file (got \"%s\")",
                                   design);
        if (have_ray || grid || wave1)
            return cli_usage_error("verify", "--ray, --grid and --wave apply to a design, "
                                             "not to --experiment");
        if (strcmp(experiment, "table1") == 0) {
            if (count || have_seed)
                return cli_usage_error("verify", "--count and --seed apply to "
                                                 "--experiment table2 only");
            return experiment_table1(bits, fmt, output);
        }
        return experiment_table2(bits, count ? (size_t)count : DEFAULT_COUNT,
                                 (uint64_t)seed, fmt, output);
    }
    if (!design)
        return cli_usage_error("verify", "missing DESIGN.json (or --experiment table1|table2)");
    if (count || have_seed)
        return cli_usage_error("verify", "--count and --seed apply to --experiment table2 "
                                         "only");
    if (have_ray && grid)
        return cli_usage_error("verify", "give only one of --ray and --grid");
    return verify_design(design, have_ray ? ray4 : NULL, grid ? grid : DEFAULT_GRID, bits,
                         wave1, fmt, output);
}
