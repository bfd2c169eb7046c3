/*
 * fuzz_args.c - libFuzzer harness for the parsing of numbers and command
 * lines (ui/args.c, and the option iterator and value checks of ui/cli.c
 * that "sagitta trace" uses).
 *
 * The first byte picks what is tested; the rest, up to a NUL byte (a
 * command-line argument cannot hold one), is the text:
 *   0  args_double, with and without infinities allowed
 *   1  args_double_list for every count from 1 to 6
 *   2  args_long and args_int with bounds taken from the next bytes
 *   3  a trace command line: the text split at newlines into arguments,
 *      walked with cli_next_opt and the trace option table, each value
 *      checked as cmd_trace checks it
 * Accepted numbers must be finite (unless infinities are allowed), within
 * their bounds, and print and read back to the same bits; refusals must
 * come with a code from the documented set.
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "args.h"
#include "cli.h"
#include "report.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The program's own messages go to a sink; findings go to the real
 * standard error, which sanitizers and libFuzzer write to directly. */
static FILE *report_to;

static void die(const char *what, const char *text)
{
    fprintf(report_to ? report_to : stderr, "fuzz_args: %s\ninput: \"%s\"\n", what,
            text ? text : "");
    abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    FILE *sink = fopen("/dev/null", "w");
    (void)argc;
    (void)argv;
    report_to = stderr;
    if (sink)
        stderr = sink;
    return 0;
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

static void check_code(int rc, const char *s)
{
    if (rc < ARGS_OK || rc > ARGS_COUNT)
        die("a code outside ARGS_*", s);
    if (strcmp(args_strerror(rc), "invalid value") == 0)
        die("a code without its own message", s);
}

/* %.17g reads back to the same double, through the same parser. */
static void round_trip(double v, int flags, const char *s)
{
    char buf[64];
    double back = NAN;
    snprintf(buf, sizeof buf, "%.17g", v);
    if (args_double(buf, flags, &back) != ARGS_OK || !same_bits(back, v))
        die("an accepted number does not read back from %.17g", s);
}

static void fuzz_double(const char *s)
{
    double a = 12345.0, b = 12345.0;
    int ra = args_double(s, 0, &a), rb = args_double(s, ARGS_ALLOW_INF, &b);
    check_code(ra, s);
    check_code(rb, s);
    if (ra == ARGS_OK) {
        if (!isfinite(a))
            die("a non-finite number accepted without ARGS_ALLOW_INF", s);
        if (rb != ARGS_OK || !same_bits(a, b))
            die("allowing infinities changed a finite number", s);
        round_trip(a, 0, s);
    } else if (!same_bits(a, 12345.0)) {
        die("a refused number changed the output", s);
    }
    if (rb == ARGS_OK) {
        if (isnan(b))
            die("NaN accepted", s);
        if (isinf(b) && ra != ARGS_NONFINITE)
            die("an infinity not refused as non-finite without the flag", s);
        round_trip(b, ARGS_ALLOW_INF, s);
    }
    if (ra == ARGS_OK && (rb == ARGS_EMPTY || rb == ARGS_SYNTAX))
        die("the flag made a number a syntax error", s);
}

static void fuzz_list(const char *s)
{
    double out[6], one;
    int n, bad, rc, commas = 0, k;
    const char *p;
    for (p = s; *p; p++)
        commas += *p == ',';
    for (n = 1; n <= 6; n++) {
        bad = -7;
        rc = args_double_list(s, 0, out, n, &bad);
        check_code(rc, s);
        if (rc == ARGS_OK) {
            if (commas != n - 1)
                die("a list with the wrong number of items accepted", s);
            for (k = 0; k < n; k++)
                if (!isfinite(out[k]))
                    die("a non-finite item accepted", s);
            /* Item k alone parses to the same value. */
            if (n == 1 && (args_double(s, 0, &one) != ARGS_OK || !same_bits(one, out[0])))
                die("a one-item list and a single number disagree", s);
        } else if (bad < -1 || bad >= n) {
            die("the index of the bad item is out of range", s);
        } else if (rc == ARGS_COUNT && commas == n - 1) {
            die("the right number of items reported as a wrong count", s);
        }
    }
}

static void fuzz_long(const char *s, const uint8_t *lim)
{
    long lo = (long)(int8_t)lim[0] * 1000 - 5, hi = lo + (long)lim[1] * lim[1] * 37;
    long v = -99, full;
    int iv = -99, rc;
    char *end;
    rc = args_long(s, lo, hi, &v);
    check_code(rc, s);
    if (rc == ARGS_OK) {
        if (v < lo || v > hi)
            die("an integer outside its bounds accepted", s);
        errno = 0;
        full = strtol(s, &end, 10);
        if (errno || full != v)
            die("args_long and strtol disagree", s);
    }
    rc = args_long(s, LONG_MIN, LONG_MAX, &v);
    check_code(rc, s);
    rc = args_int(s, INT_MIN, INT_MAX, &iv);
    check_code(rc, s);
    if (rc == ARGS_OK && (args_long(s, INT_MIN, INT_MAX, &v) != ARGS_OK || v != iv))
        die("args_int and args_long disagree", s);
}

/* The option table and value checks of cmd_trace (ui/cli.c). */
enum {
    OPT_HELP = 1, OPT_METHOD, OPT_BITS, OPT_WAVE, OPT_FORMAT, OPT_OUTPUT,
    OPT_START, OPT_DIR, OPT_RAY, OPT_RAYS, OPT_NOCLIP, OPT_THREADS, OPT_LAST
};

static const cli_opt trace_opts[] = {
    CLI_ID("--help", 'h', 0, OPT_HELP),
    CLI_ID("--method", 0, 1, OPT_METHOD),
    CLI_ID("--bits", 0, 1, OPT_BITS),
    CLI_ID("--wave", 0, 1, OPT_WAVE),
    CLI_ID("--format", 0, 1, OPT_FORMAT),
    CLI_ID("--output", 'o', 1, OPT_OUTPUT),
    CLI_ID("--start", 0, 1, OPT_START),
    CLI_ID("--dir", 0, 1, OPT_DIR),
    CLI_ID("--ray", 0, 1, OPT_RAY),
    CLI_ID("--rays", 0, 1, OPT_RAYS),
    CLI_ID("--no-clip", 0, 0, OPT_NOCLIP),
    CLI_ID("--threads", 0, 1, OPT_THREADS),
    CLI_END
};

static void fuzz_cmdline(char *s)
{
    char *argv[34];
    int argc = 0, id, prev, bits, rc;
    double v[4];
    const char *val;
    cli_iter it;
    char *p = s;

    argv[argc++] = (char *)"trace";
    while (argc < 33) {
        char *nl = strchr(p, '\n');
        argv[argc++] = p;
        if (!nl)
            break;
        *nl = '\0';
        p = nl + 1;
    }
    argv[argc] = NULL;
    cli_iter_init(&it, "trace", argc, argv);
    for (;;) {
        prev = it.i;
        id = cli_next_opt(&it, trace_opts, &val);
        if (id == -1)
            break;
        if (it.i <= prev || it.i > argc)
            die("the option iterator did not advance", s);
        if (id == -CLI_EXIT_USAGE)
            continue;
        if (id < 0 || id >= OPT_LAST)
            die("an option id outside the table", s);
        if (!memchr(it.opt, '\0', sizeof it.opt))
            die("the option name is not terminated", s);
        if (id == 0 || trace_opts[id - 1].has_arg) {
            if (!val)
                die("an argument without its value", s);
        }
        switch (id) {
        case OPT_METHOD:
            rc = sg_method_parse(val);
            if (rc != -1 && (rc < 0 || rc > SG_METHOD_MPFR))
                die("a method outside the list", s);
            break;
        case OPT_BITS:
        case OPT_WAVE:
        case OPT_THREADS:
            bits = -1;
            rc = cli_int_value("--bits", val, 53, 100000, &bits);
            if (rc == CLI_EXIT_OK && (bits < 53 || bits > 100000))
                die("--bits outside 53..100000 accepted", s);
            if (rc != CLI_EXIT_OK && rc != CLI_EXIT_USAGE)
                die("a value check returned neither 0 nor 2", s);
            break;
        case OPT_FORMAT:
            rc = report_parse_fmt(val);
            if (rc != -1 && (rc < REPORT_TEXT || rc > REPORT_JSON))
                die("a format outside the list", s);
            break;
        case OPT_START:
        case OPT_DIR:
            rc = cli_doubles_value("--start", val, 3, "X,Y,Z", v);
            if (rc == CLI_EXIT_OK && !(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2])))
                die("a non-finite start accepted", s);
            break;
        case OPT_RAY:
            rc = cli_doubles_value("--ray", val, 4, "Hx,Hy,Px,Py", v);
            if (rc == CLI_EXIT_OK &&
                !(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]) && isfinite(v[3])))
                die("a non-finite ray accepted", s);
            break;
        default:
            break;
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *s;
    size_t len, skip;
    uint8_t lim[2] = {0, 0};
    int sel;

    if (size < 1)
        return 0;
    sel = data[0] % 4;
    skip = 1;
    if (sel == 2 && size >= 3) {
        lim[0] = data[1];
        lim[1] = data[2];
        skip = 3;
    }
    if (size < skip)
        return 0;
    len = size - skip;
    s = malloc(len + 1);
    if (!s)
        return 0;
    memcpy(s, data + skip, len);
    s[len] = '\0';
    switch (sel) {
    case 0:
        fuzz_double(s);
        break;
    case 1:
        fuzz_list(s);
        break;
    case 2:
        fuzz_long(s, lim);
        break;
    default:
        fuzz_cmdline(s);
        break;
    }
    free(s);
    return 0;
}
