/* cli.c - the "trace" and "paraxial" subcommands and the helpers that every
 * subcommand shares. */
#include "cli.h"
#include "numfmt.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include "args.h"
#include "csvrays.h"
#include "h5rays.h"
#include "report.h"
#include "outfile.h"
#include "progress.h"
#include "safetext.h"

/* ---------------------------------------------------------------- messages */

/* Messages quote names and values from files, which may hold control
 * bytes; written raw they could drive the user's terminal, so they are
 * shown as \xNN instead. */
static void put_escaped(const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t left = strlen(s);
    while (left > 0) {
        size_t k = safe_char_len(p, left);
        if (k)
            fwrite(p, 1, k, stderr);
        else
            fprintf(stderr, "\\x%02x", *p);
        k = k ? k : 1;
        p += k;
        left -= k;
    }
}

static void vmsg(const char *prefix, const char *fmt, va_list ap)
{
    char buf[2048];
    fputs(prefix, stderr);
    vsnprintf(buf, sizeof buf, fmt, ap);
    put_escaped(buf);
    fputc('\n', stderr);
}

void cli_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vmsg("sagitta: ", fmt, ap);
    va_end(ap);
}

void cli_warn(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vmsg("sagitta: warning: ", fmt, ap);
    va_end(ap);
}

void cli_print_warnings(const sg_diag *d, const char *where)
{
    int k, n = d->nwarn < SG_DIAG_MAXWARN ? d->nwarn : SG_DIAG_MAXWARN;
    for (k = 0; k < n; k++) {
        if (where && !strstr(d->warn[k], where))
            cli_warn("%s: %s", where, d->warn[k]);
        else
            cli_warn("%s", d->warn[k]);
    }
    if (d->nwarn > n)
        cli_warn("%d more warnings not shown", d->nwarn - n);
}

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    char buf[2048];
    fputs("sagitta: ", stderr);
    if (cmd)
        fprintf(stderr, "%s: ", cmd);
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    /* An argument quoted back may hold control bytes, as in vmsg. */
    put_escaped(buf);
    if (cmd)
        fprintf(stderr, "\nTry 'sagitta %s --help'.\n", cmd);
    else
        fputs("\nTry 'sagitta --help'.\n", stderr);
    return CLI_EXIT_USAGE;
}

/* ------------------------------------------------------------------ options */

void cli_iter_init(cli_iter *it, const char *cmd, int argc, char **argv)
{
    memset(it, 0, sizeof *it);
    it->argc = argc;
    it->argv = argv;
    it->i = 1;
    it->cmd = cmd;
}

/* --config N, which every command that reads a design takes: the design
 * is configuration N of its configurations (0: as stored). */
static int cli_config_n;

static int next_raw(cli_iter *it, const cli_opt *opts, const char **val, const cli_opt **row)
{
    const char *a, *eq;
    const cli_opt *o;
    size_t nlen;

again:
    *val = NULL;
    if (it->i >= it->argc)
        return -1;
    a = it->argv[it->i++];
    if (!it->only_positional && strncmp(a, "--config", 8) == 0 && (!a[8] || a[8] == '=')) {
        const char *v = a[8] ? a + 9 : it->i < it->argc ? it->argv[it->i++] : NULL;
        long n;
        char *end;
        if (!v || !v[0])
            return -cli_usage_error(it->cmd, "--config needs a configuration number");
        n = strtol(v, &end, 10);
        if (*end || n < 1 || n > SG_MAX_CONFIGS)
            return -cli_usage_error(it->cmd, "--config \"%s\": give a configuration number "
                                    "from 1 to %d", v, SG_MAX_CONFIGS);
        cli_config_n = (int)n;
        goto again;
    }
    if (!it->only_positional && strcmp(a, "--") == 0) {
        it->only_positional = 1;
        if (it->i >= it->argc)
            return -1;
        a = it->argv[it->i++];
    }
    /* "-" alone names standard input or output, so it is an argument. */
    if (it->only_positional || a[0] != '-' || a[1] == '\0') {
        *val = a;
        return 0;
    }
    if (a[1] == '-') {
        eq = strchr(a, '=');
        nlen = eq ? (size_t)(eq - a) : strlen(a);
        snprintf(it->opt, sizeof it->opt, "%.*s", (int)(nlen < 60 ? nlen : 60), a);
        for (o = opts; o->name; o++)
            if (strlen(o->name) == nlen && strncmp(o->name, a, nlen) == 0)
                break;
        if (!o->name)
            return -cli_usage_error(it->cmd, "unknown option %s", it->opt);
        if (!o->has_arg) {
            if (eq)
                return -cli_usage_error(it->cmd, "%s takes no value", o->name);
            return *row = o, o->id;
        }
        if (eq) {
            *val = eq + 1;
            return *row = o, o->id;
        }
        if (o->has_arg == CLI_OPT_NUM) {
            const char *n = it->i < it->argc ? it->argv[it->i] : NULL;
            if (n && n[0] && strspn(n, "0123456789") == strlen(n))
                *val = it->argv[it->i++];
            return *row = o, o->id;
        }
    } else {
        snprintf(it->opt, sizeof it->opt, "-%c", a[1]);
        for (o = opts; o->name; o++)
            if (o->shortc && o->shortc == a[1])
                break;
        if (!o->name)
            return -cli_usage_error(it->cmd, "unknown option %s", it->opt);
        if (!o->has_arg) {
            if (a[2])
                return -cli_usage_error(it->cmd, "%s takes no value", it->opt);
            return *row = o, o->id;
        }
        if (a[2]) {
            *val = a + 2;
            return *row = o, o->id;
        }
    }
    if (it->i >= it->argc)
        return -cli_usage_error(it->cmd, "%s needs a value", it->opt);
    *val = it->argv[it->i++];
    return *row = o, o->id;
}


/* words "a|b|c" as "a, b or c", for messages. */
static void word_list(const char *words, char *buf, size_t n)
{
    size_t len = 0;
    const char *p = words;
    buf[0] = '\0';
    while (*p && len + 1 < n) {
        size_t w = strcspn(p, "|");
        const char *sep = p[w] ? (strchr(p + w + 1, '|') ? ", " : " or ") : "";
        len += (size_t)snprintf(buf + len, n - len, "%.*s%s", (int)w, p, sep);
        p += w + (p[w] != '\0');
    }
}

/* Whether the command cmd is one of only's space-separated names. */
static int row_is_for(const char *only, const char *cmd)
{
    size_t n = cmd ? strlen(cmd) : 0;
    const char *p = only;
    while ((p = strstr(p, cmd)) != NULL) {
        if ((p == only || p[-1] == ' ') && (p[n] == '\0' || p[n] == ' '))
            return 1;
        p += n;
    }
    return 0;
}

/* Stores a declarative row's value; CLI_EXIT_OK or, after a message,
 * CLI_EXIT_USAGE. */
static int store_row(const cli_iter *it, const cli_opt *o, const char *val)
{
    if (o->only && !row_is_for(o->only, it->cmd))
        return cli_usage_error(it->cmd, "%s is an option of %s only", o->name, o->only);
    switch (o->kind) {
    case CLI_INT:
        return cli_int_value(o->name, val, o->lo, o->hi, (int *)o->dest);
    case CLI_FLAG:
        *(int *)o->dest = 1;
        return CLI_EXIT_OK;
    case CLI_TEXT:
        *(const char **)o->dest = val;
        return CLI_EXIT_OK;
    case CLI_NUMS:
        return cli_doubles_value(o->name, val, o->lo, o->words, (double *)o->dest);
    case CLI_POS: {
        double v;
        if (cli_doubles_value(o->name, val, 1, o->words, &v))
            return CLI_EXIT_USAGE;
        if (!(v > 0.0) || !isfinite(v))
            return cli_usage_error(it->cmd, "%s: %g is not a positive number%s", o->name, v,
                                   o->unit ? o->unit : "");
        *(double *)o->dest = v;
        return CLI_EXIT_OK;
    }
    case CLI_WORD: {
        const char *p = o->words;
        size_t n = strlen(val);
        int k = 0;
        char list[256];
        while (*p) {
            size_t w = strcspn(p, "|");
            if (w == n && strncmp(p, val, n) == 0) {
                *(int *)o->dest = o->values ? o->values[k] : k;
                return CLI_EXIT_OK;
            }
            p += w + (p[w] != '\0');
            k++;
        }
        word_list(o->words, list, sizeof list);
        return cli_usage_error(it->cmd, "%s: expected %s, got \"%s\"", o->name, list, val);
    }
    default:
        return cli_usage_error(it->cmd, "%s: no way to read it", o->name);
    }
}

int cli_next_opt(cli_iter *it, const cli_opt *opts, const char **val)
{
    for (;;) {
        const cli_opt *row = NULL;
        int id = next_raw(it, opts, val, &row);
        if (id <= 0 || !row || !row->dest)
            return id;
        if (store_row(it, row, *val) != CLI_EXIT_OK)
            return -CLI_EXIT_USAGE;
    }
}

int cli_format_value(const char *s, int allow_csv, int *fmt)
{
    int f = report_parse_fmt(s);
    if (f < 0 || (f == REPORT_CSV && !allow_csv)) {
        cli_error("--format: expected text%s or json, got \"%s\"",
                  allow_csv ? ", csv" : "", s);
        return CLI_EXIT_USAGE;
    }
    *fmt = f;
    return CLI_EXIT_OK;
}

int cli_int_value(const char *opt, const char *s, int lo, int hi, int *out)
{
    if (args_int(s, lo, hi, out) != ARGS_OK) {
        cli_error("%s: expected an integer from %d to %d, got \"%s\"", opt, lo, hi, s);
        return CLI_EXIT_USAGE;
    }
    return CLI_EXIT_OK;
}

int cli_doubles_value(const char *opt, const char *s, int n, const char *what,
                      double *out)
{
    int bad, rc = args_double_list(s, 0, out, n, &bad);
    const char *p = what;
    int k;

    if (rc == ARGS_OK)
        return CLI_EXIT_OK;
    if (bad < 0) {
        cli_error("%s: expected %d comma-separated numbers %s, got \"%s\"", opt, n,
                  what, s);
        return CLI_EXIT_USAGE;
    }
    /* Name the item at fault, taking its name from the list in what. */
    for (k = 0; k < bad && p; k++) {
        p = strchr(p, ',');
        if (p)
            p++;
    }
    cli_error("%s: expected %d comma-separated numbers %s, got \"%s\" (%.*s: %s)",
              opt, n, what, s, p ? (int)strcspn(p, ",") : 1, p ? p : "?",
              args_strerror(rc));
    return CLI_EXIT_USAGE;
}

/* ------------------------------------------------------------------ designs */

int cli_exit_for(int err)
{
    switch (err) {
    case SG_OK:
        return CLI_EXIT_OK;
    case SG_ENOMEM:
        return CLI_EXIT_INTERNAL;
    case SG_EINVAL:
    case SG_ERANGE:
    case SG_ENOGLASS:
    case SG_ENOSTOP:
    case SG_ETWOSTOPS:
    case SG_ENOSYS:
    case SG_ENONPHYS:
    case SG_EUNSUPPORTED:
    case SG_EWAVERANGE:
    case SG_EAIM: /* the tracer could not size the stop for aiming */
        return CLI_EXIT_DESIGN;
    default:
        return CLI_EXIT_INTERNAL;
    }
}

void cli_print_diag(const char *path, const sg_diag *d, int rc)
{
    const char *msg = d->msg[0] ? d->msg : sg_strerror(rc);
    if (path && !strstr(msg, path))
        cli_error("%s: %s", path, msg);
    else
        cli_error("%s", msg);
}

void cli_design_free(sg_catalog *cat, sg_system *sys)
{
    sg_system_free(sys);
    sg_catalog_free(cat);
}

int cli_load_design(const char *path, sg_catalog **catp, sg_system **sysp)
{
    return cli_load_design_subst(path, NULL, catp, sysp);
}

int cli_load_design_subst(const char *path, const sg_zmx_subst *sub, sg_catalog **catp,
                          sg_system **sysp)
{
    sg_catalog *cat;
    sg_system *sys;
    sg_diag d;
    int rc;

    *catp = NULL;
    *sysp = NULL;
    cat = sg_catalog_new();
    sys = sg_system_new();
    if (!cat || !sys) {
        cli_design_free(cat, sys);
        cli_error("out of memory");
        return CLI_EXIT_INTERNAL;
    }
    /* A design of fixed indices needs no catalog, so a missing or broken
     * one is only a warning; a glass it lacks is reported by name below. */
    sg_diag_clear(&d);
    rc = sg_catalog_load_default(cat, &d);
    if (rc == SG_ENOMEM) {
        cli_design_free(cat, sys);
        cli_error("out of memory loading the glass catalog");
        return CLI_EXIT_INTERNAL;
    }
    if (rc != SG_OK)
        cli_warn("glass catalog: %s", d.msg[0] ? d.msg : sg_strerror(rc));
    /* A SAGITTA_LENSDB that is not a directory is said, even though the
     * bundled catalogs stand in for it. */
    cli_print_warnings(&d, NULL);

    sg_diag_clear(&d);
    cli_note_input(path);
    rc = sub ? sg_zmx_load_subst(sys, path, cat, sub, &d) : sg_design_load(sys, path, &d);
    if (rc != SG_OK) {
        cli_print_diag(path, &d, rc);
        cli_design_free(cat, sys);
        /* A file that parses but describes an untraceable system (too few
         * surfaces, no stop, two stops) is a design error, as documented. */
        if (rc == SG_ENOSYS || rc == SG_ENOSTOP || rc == SG_ETWOSTOPS || rc == SG_ENOGLASS)
            return CLI_EXIT_DESIGN;
        return rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_FILE;
    }
    cli_print_warnings(&d, path);

    /* Every configuration must be a design (a JSON design's operands are
     * checked here; a .zmx file's when it is read). */
    sg_diag_clear(&d);
    if (sys->configs && (rc = sg_configs_check(sys, cat, &d)) != SG_OK) {
        cli_print_diag(path, &d, rc);
        cli_design_free(cat, sys);
        return rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
    }
    /* --config N: configuration N's design (sagitta-design(5), CONFIGURATIONS). */
    sg_diag_clear(&d);
    if (cli_config_n && (rc = sg_config_apply(sys, cli_config_n, &d)) != SG_OK) {
        cli_print_diag(path, &d, rc);
        cli_design_free(cat, sys);
        return CLI_EXIT_USAGE;
    }

    sg_diag_clear(&d);
    rc = sg_system_validate(sys, cat, &d);
    if (rc != SG_OK) {
        cli_print_diag(path, &d, rc);
        cli_design_free(cat, sys);
        return rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
    }
    cli_print_warnings(&d, path);
    /* Solved values follow the design they are solved on. */
    sg_diag_clear(&d);
    rc = sg_system_apply_solves(sys, cat, &d);
    if (rc != SG_OK) {
        cli_print_diag(path, &d, rc);
        cli_design_free(cat, sys);
        return rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_DESIGN;
    }
    *catp = cat;
    *sysp = sys;
    return CLI_EXIT_OK;
}

int cli_check_wave(const char *path, const sg_system *sys, int wave1, int *wave0)
{
    if (wave1 == 0) {
        *wave0 = sys->primary_wave;
        return CLI_EXIT_OK;
    }
    if (wave1 > sys->nwave) {
        cli_error("--wave %d: %s has %d wavelength%s", wave1, path, sys->nwave,
                  sys->nwave == 1 ? "" : "s");
        return CLI_EXIT_USAGE;
    }
    *wave0 = wave1 - 1;
    return CLI_EXIT_OK;
}

/* The files this run reads; a command reads two at most (design, rays). */
static struct {
    dev_t dev;
    ino_t ino;
} inputs[8];
static int ninputs;

void cli_note_input(const char *path)
{
    struct stat st;
    if (path && strcmp(path, "-") != 0 && ninputs < 8 && stat(path, &st) == 0) {
        inputs[ninputs].dev = st.st_dev;
        inputs[ninputs].ino = st.st_ino;
        ninputs++;
    }
}

int cli_output_is_input(const char *path)
{
    struct stat st;
    int k;
    if (!path || strcmp(path, "-") == 0 || stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return 0;
    for (k = 0; k < ninputs; k++)
        if (inputs[k].dev == st.st_dev && inputs[k].ino == st.st_ino) {
            cli_error("%s: the output is a file this command reads; not written (give "
                      "another name)", path);
            return 1;
        }
    return 0;
}

FILE *cli_open_output(const char *path)
{
    FILE *f;
    if (!path || strcmp(path, "-") == 0)
        return stdout;
    if (cli_output_is_input(path))
        return NULL;
    f = fopen(path, "w");
    if (!f)
        cli_error("%s: %s", path, strerror(errno));
    return f;
}

int cli_close_output(FILE *f, const char *path)
{
    int failed;
    if (f == stdout) {
        failed = fflush(f) != 0 || ferror(f);
        if (failed)
            cli_error("standard output: %s", strerror(errno ? errno : EIO));
        return failed ? CLI_EXIT_FILE : CLI_EXIT_OK;
    }
    failed = ferror(f) != 0;
    if (fclose(f) != 0)
        failed = 1;
    if (failed) {
        cli_error("%s: %s", path, strerror(errno ? errno : EIO));
        return CLI_EXIT_FILE;
    }
    return CLI_EXIT_OK;
}

/* -------------------------------------------------------------------- trace */

static void trace_help(FILE *f)
{
    fputs(
"Usage: sagitta trace DESIGN.json RAY [OPTIONS]\n"
"Trace rays through a design and print where they cross every surface.\n"
"\n"
"RAY is exactly one of:\n"
"  --ray Hx,Hy,Px,Py        normalized field and pupil coordinates\n"
"  --start X,Y,Z --dir L,M,N\n"
"                           a start point and direction in surface 1's frame\n"
"  --rays FILE.csv          many rays; the header names the columns hx,hy,px,py\n"
"                           or x,y,z,l,m,n (\"-\" reads standard input)\n"
"\n"
"Options:\n"
"  --method M               precise (default), classic or mpfr\n"
"  --bits N                 precision of the mpfr method, 53 to 100000 (256)\n"
"  --wave N                 wavelength number, from 1 (default: the primary)\n"
"  --format F               text (default), csv, json, or with --rays and\n"
"                           --output FILE: hdf5 (one dataset per column)\n"
"  -o, --output FILE        write to FILE instead of standard output\n"
"  --no-clip                do not vignette rays outside fixed semi-diameters\n"
"  --global [S]             rows in the global frame of surface S (default 1),\n"
"                           Zemax's global coordinate reference surface\n"
"  --surface LIST           write only these surfaces' rows: numbers, ranges\n"
"                           A-B, OBJ, STO, IMA, comma-separated (default all)\n"
"  --threads N              threads for --rays; 0 (default) uses every core\n"
"  -h, --help               show this help\n"
"\n"
"A ray that misses a surface or is totally internally reflected is a result:\n"
"its status is printed and the exit status is 0.  See sagitta(1).\n", f);
}

/* The options trace's switch reads itself: the ones that go together or
 * whose value is checked against another. */
enum { OPT_START = 1, OPT_DIR, OPT_RAY, OPT_GLOBAL };

/* ---- a ray list, streamed ---- */

/* --format hdf5: a ray table only, not one of report.c's text forms. */
#define FMT_HDF5 100
static const int trace_format_values[4] = {REPORT_TEXT, REPORT_CSV, REPORT_JSON, FMT_HDF5};

/* The frames of --global, or NULL (with the message printed) when the
 * design refuses the reference surface. */
static sg_frame *global_frames(const char *design, const sg_system *sys, int ref)
{
    sg_frame *gf = malloc((size_t)sys->nsurf * sizeof *gf);
    sg_diag d;
    sg_diag_clear(&d);
    if (!gf) {
        cli_error("out of memory");
        return NULL;
    }
    if (sg_global_frames(sys, ref, gf, &d) != SG_OK) {
        cli_error("--global: %s: %s", design, d.msg);
        free(gf);
        return NULL;
    }
    return gf;
}

/* Why a single ray's trace stopped with a status that is not a ray's own
 * fate (sagitta(1), STATUSES). */
static const char *stop_reason(int rc)
{
    switch (rc) {
    case SG_ENONPHYS:
        return "the surface's normal at the ray's point vanishes in double-double (the "
               "square of a radius below about 1e-162 underflows to 0), so the precise "
               "method cannot bend the ray within its bound; the classic and mpfr methods "
               "trace it";
    case SG_EINVAL:
        return "the ray's numbers are not finite or its direction is zero";
    default:
        return NULL;
    }
}

/* Reports a trace that failed for a reason other than the ray's own fate,
 * and returns the exit status for it; rows (nsurf of them, or NULL) name
 * the surface where a single ray stopped. */
static int trace_failed_at(const char *design, const sg_diag *d, int rc,
                           const sg_ray_surface *rows, int nsurf)
{
    int i = 0;
    if (rows)
        for (i = 0; i < nsurf && rows[i].status != rc; i++)
            ;
    if (d->msg[0])
        cli_print_diag(design, d, rc);
    else if (rows && i < nsurf)
        cli_error("%s: trace failed on surface %d: %s (status %s)%s%s", design, i,
                  sg_strerror(rc), report_status_name(rc), stop_reason(rc) ? ": " : "",
                  stop_reason(rc) ? stop_reason(rc) : "");
    else
        cli_error("%s: trace failed: %s", design, sg_strerror(rc));
    rc = cli_exit_for(rc);
    return rc == CLI_EXIT_OK ? CLI_EXIT_INTERNAL : rc;
}

static int trace_failed(const char *design, const sg_diag *d, int rc)
{
    return trace_failed_at(design, d, rc, NULL, 0);
}

/* Rays a block holds: about 16 MiB of result rows, from 16 to 65536
 * rays.  SAGITTA_RAYS_BLOCK sets it (from 1), for tests of the seams. */
static size_t rays_block(int nsurf)
{
    const char *env = getenv("SAGITTA_RAYS_BLOCK");
    size_t b = ((size_t)16 << 20) / ((size_t)nsurf * sizeof(sg_ray_surface));
    if (env && env[0]) {
        long v = strtol(env, NULL, 10);
        if (v >= 1 && v <= (1L << 24))
            return (size_t)v;
    }
    return b < 16 ? 16 : b > 65536 ? 65536 : b;
}

/* A ray list from standard input is kept in a temporary file when the
 * count must be known first (the text report states it). */
static FILE *spool_stdin(void)
{
    FILE *t = tmpfile();
    char buf[65536];
    size_t n;
    if (!t) {
        cli_error("<stdin>: cannot make a temporary file: %s", strerror(errno));
        return NULL;
    }
    while ((n = fread(buf, 1, sizeof buf, stdin)) > 0)
        if (fwrite(buf, 1, n, t) != n) {
            cli_error("<stdin>: writing a temporary file: %s", strerror(errno));
            fclose(t);
            return NULL;
        }
    if (ferror(stdin) || fflush(t) != 0) {
        cli_error("<stdin>: %s", strerror(errno ? errno : EIO));
        fclose(t);
        return NULL;
    }
    rewind(t);
    return t;
}

static int open_rays(const char *path, FILE *spool, csvrays_reader **rd, sg_diag *d)
{
    if (spool) {
        rewind(spool);
        return csvrays_open_stream(spool, "<stdin>", rd, d);
    }
    cli_note_input(path);
    return csvrays_open(path, rd, d);
}

/* trace --rays: read a block of rays, trace it on every thread, write it,
 * and go on, so memory stays the same however long the list.  The output
 * is byte for byte what tracing the whole list at once wrote.  Each step
 * runs on every thread: the reader parses a block's rows in shares
 * (csvrays.c), sg_batch_trace traces it, and report_rays formats it in
 * rounds of shares and writes each round in order (report.c). */
/* The rows --surface LIST keeps, into *sel (NULL without a list); 0, or
 * a usage error with the message printed. */
static int surface_list(const char *design, const char *list, const sg_system *sys, int nsurf,
                        int **sel, int *nsel)
{
    char err[256];
    *sel = NULL;
    *nsel = 0;
    if (!list)
        return CLI_EXIT_OK;
    *sel = malloc((size_t)nsurf * sizeof **sel);
    if (!*sel) {
        cli_error("out of memory");
        return CLI_EXIT_INTERNAL;
    }
    if (report_parse_surfaces(list, nsurf, sys->stop, *sel, nsel, err, sizeof err) != 0) {
        cli_error("%s: %s", design, err);
        free(*sel);
        *sel = NULL;
        return CLI_EXIT_USAGE;
    }
    return CLI_EXIT_OK;
}

static int trace_rays(const char *design, const char *rays_path, const char *output, int fmt,
                      const sg_trace_opts *opts_in, int wave1, int threads, int global,
                      const char *surfaces)
{
    csvrays_reader *rd = NULL;
    FILE *spool = NULL;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_tracer *t = NULL;
    sg_batch *b = NULL;
    sg_trace_opts opts = *opts_in;
    sg_ray_in *rays = NULL;
    sg_ray_surface *out = NULL;
    int *status = NULL, nsurf, rc, wave0 = 0, multi, opened = 0, *sel = NULL, nsel = 0;
    size_t total = 0, block, cap, n, done = 0;
    sg_opd *opd = NULL;
    sg_opd_ref ref;
    unsigned long long pos, size;
    report_meta meta;
    report_stream rs;
    outfile ro;
    ui_progress pg;
    sg_diag d;
    h5rays *h5 = NULL;
    char h5err[512];
    sg_frame *gf = NULL;

    memset(&ro, 0, sizeof ro);
    sg_diag_clear(&d);
    /* The text report states the number of rays before the first one. */
    if (fmt == REPORT_TEXT) {
        if (strcmp(rays_path, "-") == 0 && !(spool = spool_stdin()))
            return CLI_EXIT_FILE;
        rc = open_rays(rays_path, spool, &rd, &d);
        if (rc == SG_OK)
            rc = csvrays_count(rd, &total, &d);
        csvrays_close(rd);
        rd = NULL;
        if (rc == SG_OK && total == 0)
            rc = sg_diag_set(&d, SG_EPARSE, "%s: no rays after the header",
                             spool ? "<stdin>" : rays_path);
        if (rc != SG_OK)
            goto bad_rays;
    }
    rc = open_rays(rays_path, spool, &rd, &d);
    if (rc != SG_OK)
        goto bad_rays;
    csvrays_set_threads(rd, threads);

    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        goto done;
    rc = cli_check_wave(design, sys, wave1, &wave0);
    if (rc != CLI_EXIT_OK)
        goto done;
    opts.wave = wave0;
    if (global >= 0 && !(gf = global_frames(design, sys, global))) {
        rc = CLI_EXIT_USAGE;
        goto done;
    }

    /* One tracer first, so a design the tracer refuses fails here once
     * and its warnings are printed once, not once a thread. */
    sg_diag_clear(&d);
    rc = sg_tracer_open(sys, cat, &opts, &t, &d);
    if (rc == SG_OK) {
        cli_print_warnings(&d, design);
        sg_diag_clear(&d);
        b = sg_batch_new(sys, cat, &opts, threads, &d);
        /* The batch's constructor has no code of its own to return. */
        if (!b)
            rc = d.code != SG_OK ? d.code : SG_ENOMEM;
    }
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    nsurf = sg_tracer_nsurf(t);
    rc = surface_list(design, surfaces, sys, nsurf, &sel, &nsel);
    if (rc != CLI_EXIT_OK)
        goto done;
    /* The tracer stays for the reference spheres of normalized rays. */
    if (csvrays_kind(rd) != SG_RAYS_NORMALIZED) {
        sg_tracer_free(t);
        t = NULL;
    }

    block = rays_block(nsurf);
    cap = block < 2 ? 2 : block;
    rays = malloc(cap * sizeof *rays);
    out = malloc(cap * (size_t)nsurf * sizeof *out);
    status = malloc(cap * sizeof *status);
    opd = t ? malloc(cap * sizeof *opd) : NULL;
    if (!rays || !out || !status || (t && !opd)) {
        cli_error("out of memory for %zu rays of %d surfaces", cap, nsurf);
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }

    /* The first block decides between the one-ray and the list form: a
     * reader returns fewer rays than asked only at the end. */
    sg_diag_clear(&d);
    rc = csvrays_next(rd, rays, cap, &n, &d);
    if (rc != SG_OK)
        goto bad_rays;
    multi = !(n == 1 && cap > 1);

    memset(&meta, 0, sizeof meta);
    meta.design = design;
    meta.method = sg_method_name(opts.method);
    meta.bits = opts.method == SG_METHOD_MPFR ? opts.mpfr_bits : 0;
    meta.wave_um = sys->wave[wave0].um;
    meta.wave_index = wave0 + 1;
    meta.opd = t != NULL;
    meta.global = gf != NULL;
    meta.global_ref = global;
    meta.surfaces = sel;
    meta.nsurfaces = nsel;
    /* A CSV row of a normalized ray says which ray it is, as a fan's or
     * grid's export and the JSON's "input" do. */
    meta.csv_inputs = csvrays_kind(rd) == SG_RAYS_NORMALIZED;
    memset(&ref, 0, sizeof ref);
    ref.status = SG_EINVAL;

    ui_progress_init(&pg, "trace", "rays");
    while (n > 0) {
        sg_diag_clear(&d);
        rc = sg_batch_trace(b, csvrays_kind(rd), rays, n, NULL, 0, out, status, &d);
        if (rc != SG_OK) {
            ui_progress_end(&pg);
            rc = trace_failed(design, &d, rc);
            goto done;
        }
        /* The output is opened only after the first block traced, so a
         * design that cannot be traced leaves an existing file as it was. */
        if (!opened && !h5 && output && cli_output_is_input(output)) {
            rc = CLI_EXIT_FILE;
            goto done;
        }
        if (fmt == FMT_HDF5) {
            if (!h5) {
                h5 = h5rays_open(output, &meta, sys->units, nsurf, csvrays_kind(rd),
                                 n * (size_t)nsurf, h5err, sizeof h5err);
                if (!h5)
                    goto h5_error;
            }
            if (t)
                report_opd_block_mt(t, &ref, rays, n, out, nsurf, opd, threads);
            /* After the OPD, which is taken in the image surface's own frame. */
            if (gf)
                sg_rows_to_global(gf, out, n, nsurf, csvrays_kind(rd) == SG_RAYS_START_DIR);
            if (h5rays_write(h5, out, status, n, rays, t ? opd : NULL, h5err, sizeof h5err) != 0)
                goto h5_error;
        } else if (!opened) {
            int err = outfile_open(&ro, output, stdout);
            if (err != 0) {
                cli_error("%s: %s", output, strerror(err));
                rc = CLI_EXIT_FILE;
                goto done;
            }
            opened = 1;
            if (report_begin(&rs, ro.f, (report_fmt)fmt, &meta, nsurf, csvrays_kind(rd),
                             multi, total) != 0)
                goto write_error;
            report_set_threads(&rs, threads);
        }
        if (t && fmt != FMT_HDF5)
            report_opd_block_mt(t, &ref, rays, n, out, nsurf, opd, threads);
        if (gf && fmt != FMT_HDF5)
            sg_rows_to_global(gf, out, n, nsurf, csvrays_kind(rd) == SG_RAYS_START_DIR);
        if (fmt != FMT_HDF5 && report_rays_opd(&rs, out, status, n, rays, opd) != 0)
            goto write_error;
        done += n;
        csvrays_progress(rd, &pos, &size);
        ui_progress_show(&pg, done, pos, size);
        sg_diag_clear(&d);
        rc = csvrays_next(rd, rays, block, &n, &d);
        if (rc != SG_OK) {
            ui_progress_end(&pg);
            goto bad_rays;
        }
    }
    ui_progress_end(&pg);
    if (fmt == FMT_HDF5) {
        rc = h5rays_close(h5, h5err, sizeof h5err);
        h5 = NULL;
        if (rc != 0) {
            cli_error("%s: %s", output, h5err);
            rc = CLI_EXIT_FILE;
        } else {
            rc = CLI_EXIT_OK;
        }
        goto done;
    }
    if (report_end(&rs) != 0)
        goto write_error;
    {
        int err = outfile_commit(&ro);
        opened = 0;
        rc = CLI_EXIT_OK;
        if (err != 0) {
            cli_error("%s: %s", ro.path ? ro.path : "standard output", strerror(err));
            rc = CLI_EXIT_FILE;
        }
    }
    goto done;

h5_error:
    ui_progress_end(&pg);
    cli_error("%s: %s", output, h5err);
    rc = CLI_EXIT_FILE;
    goto done;
write_error:
    ui_progress_end(&pg);
    cli_error("%s: %s", output && strcmp(output, "-") ? output : "standard output",
              strerror(errno));
    rc = CLI_EXIT_FILE;
    goto done;
bad_rays:
    cli_error("%s", d.msg[0] ? d.msg : sg_strerror(rc));
    rc = rc == SG_ENOMEM ? CLI_EXIT_INTERNAL : CLI_EXIT_FILE;
done:
    if (opened && rc != CLI_EXIT_OK)
        outfile_abort(&ro);
    h5rays_abort(h5);
    csvrays_close(rd);
    if (spool)
        fclose(spool);
    free(rays);
    free(out);
    free(status);
    free(opd);
    free(gf);
    free(sel);
    sg_tracer_free(t);
    sg_batch_free(b);
    cli_design_free(cat, sys);
    return rc;
}

int cmd_trace(int argc, char **argv)
{
    cli_iter it;
    const char *val, *design = NULL, *output = NULL, *rays_path = NULL, *surfaces = NULL;
    int id, rc, method = SG_METHOD_PRECISE, bits = 0, wave1 = 0, wave0 = 0;
    int fmt = REPORT_TEXT, clip = 1, threads = 0;
    int have_start = 0, have_dir = 0, have_ray = 0, global = -1;
    double start[3] = { 0 }, dir[3] = { 0 }, ray4[4] = { 0 };
    sg_frame *gf = NULL;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_tracer *t = NULL;
    sg_trace_opts opts;
    sg_ray_in one;
    sg_ray_kind kind = SG_RAYS_NORMALIZED;
    const size_t nray = 1;
    sg_ray_surface *out = NULL;
    int *status = NULL, nsurf, *sel = NULL, nsel = 0;
    report_meta meta;
    sg_opd opd1;
    sg_diag d;
    FILE *f;

    int noclip = 0;
    /* Its table: the rows with a variable are stored as they are read. */
    const cli_opt trace_opts[] = {
        CLI_OPT_HELP,
        CLI_OPT_METHOD(method),
        CLI_OPT_INT("--bits", 0, bits, 53, 100000),
        CLI_OPT_INT("--wave", 0, wave1, 1, SG_MAX_WAVES),
        CLI_OPT_WORD("--format", fmt, "text|csv|json|hdf5", trace_format_values),
        CLI_OPT_OUTPUT(output),
        CLI_ID("--start", 0, 1, OPT_START),
        CLI_ID("--dir", 0, 1, OPT_DIR),
        CLI_ID("--ray", 0, 1, OPT_RAY),
        CLI_OPT_TEXT("--rays", 0, rays_path),
        CLI_OPT_FLAG("--no-clip", 0, noclip),
        CLI_OPT_INT("--threads", 0, threads, 0, 4096),
        CLI_ID("--global", 0, CLI_OPT_NUM, OPT_GLOBAL),
        CLI_OPT_TEXT("--surface", 0, surfaces),
        CLI_END
    };

    memset(&opd1, 0, sizeof opd1);
    cli_iter_init(&it, "trace", argc, argv);
    while ((id = cli_next_opt(&it, trace_opts, &val)) != -1) {
        switch (id) {
        case 0:
            if (design)
                return cli_usage_error("trace", "unexpected argument \"%s\"", val);
            design = val;
            break;
        case CLI_HELP:
            trace_help(stdout);
            return CLI_EXIT_OK;
        case OPT_START:
            if (cli_doubles_value("--start", val, 3, "X,Y,Z", start))
                return CLI_EXIT_USAGE;
            have_start = 1;
            break;
        case OPT_DIR:
            if (cli_doubles_value("--dir", val, 3, "L,M,N", dir))
                return CLI_EXIT_USAGE;
            if (dir[0] == 0 && dir[1] == 0 && dir[2] == 0) {
                cli_error("--dir: the direction %s is zero", val);
                return CLI_EXIT_USAGE;
            }
            have_dir = 1;
            break;
        case OPT_RAY:
            if (cli_doubles_value("--ray", val, 4, "Hx,Hy,Px,Py", ray4))
                return CLI_EXIT_USAGE;
            have_ray = 1;
            break;
        case OPT_GLOBAL:
            global = 1;
            if (val && cli_int_value("--global", val, 0, SG_MAX_SURFACES, &global))
                return CLI_EXIT_USAGE;
            break;
        default:
            return -id;
        }
    }
    clip = !noclip;
    if (!design)
        return cli_usage_error("trace", "missing DESIGN.json");
    if (have_start != have_dir)
        return cli_usage_error("trace", "--start and --dir go together");
    if (have_ray + have_start + (rays_path != NULL) != 1)
        return cli_usage_error("trace", have_ray || have_start || rays_path
                               ? "give only one of --ray, --start/--dir and --rays"
                               : "give a ray with --ray, --start/--dir or --rays");
    if (bits && method != SG_METHOD_MPFR)
        cli_warn("--bits only applies to --method mpfr; ignored");
    /* An HDF5 file is written by seeking about it, so it needs a name. */
    if (fmt == FMT_HDF5 && !rays_path)
        return cli_usage_error("trace", "--format hdf5 writes a ray table: give --rays");
    if (fmt == FMT_HDF5 && (!output || strcmp(output, "-") == 0))
        return cli_usage_error("trace", "--format hdf5 needs --output FILE.h5");

    if (rays_path) {
        sg_trace_opts_init(&opts);
        opts.method = (sg_method)method;
        if (bits)
            opts.mpfr_bits = bits;
        opts.clip = clip;
        return trace_rays(design, rays_path, output, fmt, &opts, wave1, threads, global,
                          surfaces);
    }
    memset(&one, 0, sizeof one);
    if (have_ray) {
        kind = SG_RAYS_NORMALIZED;
        memcpy(one.v, ray4, sizeof ray4);
    } else {
        kind = SG_RAYS_START_DIR;
        memcpy(one.v, start, sizeof start);
        memcpy(one.v + 3, dir, sizeof dir);
    }

    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        goto done;
    rc = cli_check_wave(design, sys, wave1, &wave0);
    if (rc != CLI_EXIT_OK)
        goto done;
    /* A field past 90 degrees is the command line's mistake, not a ray's
     * result. */
    sg_diag_clear(&d);
    if (have_ray && sg_field_check(sys, ray4[0], ray4[1], &d) != SG_OK) {
        cli_error("--ray: %s: %s", design, d.msg);
        rc = CLI_EXIT_USAGE;
        goto done;
    }

    sg_trace_opts_init(&opts);
    opts.method = (sg_method)method;
    if (bits)
        opts.mpfr_bits = bits;
    opts.wave = wave0;
    opts.clip = clip;

    sg_diag_clear(&d);
    rc = sg_tracer_open(sys, cat, &opts, &t, &d);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    cli_print_warnings(&d, design);
    nsurf = sg_tracer_nsurf(t);
    rc = surface_list(design, surfaces, sys, nsurf, &sel, &nsel);
    if (rc != CLI_EXIT_OK)
        goto done;

    out = calloc(nray, (size_t)nsurf * sizeof *out);
    status = calloc(nray, sizeof *status);
    if (!out || !status) {
        cli_error("out of memory for %zu rays of %d surfaces", nray, nsurf);
        rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    if (kind == SG_RAYS_NORMALIZED) {
        sg_opd_ref ref;
        rc = sg_trace_normalized(t, ray4[0], ray4[1], ray4[2], ray4[3], out);
        status[0] = rc;
        sg_diag_clear(&d);
        if (sg_err_is_ray_status(rc)) {
            /* The reference sphere of the ray's field; its failure is the
             * OPD's status, not the trace's. */
            sg_opd_reference(t, ray4[0], ray4[1], &ref, NULL);
            sg_opd_of_ray(t, &ref, &out[nsurf - 1], &opd1);
        }
    } else {
        rc = sg_trace_start(t, start, dir, out);
        status[0] = rc;
        sg_diag_clear(&d);
    }
    if (!sg_err_is_ray_status(rc)) {
        rc = trace_failed_at(design, &d, rc, out, nsurf);
        goto done;
    }
    cli_print_warnings(&d, design);
    if (global >= 0) {
        if (!(gf = global_frames(design, sys, global))) {
            rc = CLI_EXIT_USAGE;
            goto done;
        }
        sg_rows_to_global(gf, out, 1, nsurf, kind == SG_RAYS_START_DIR);
    }

    memset(&meta, 0, sizeof meta);
    meta.design = design;
    meta.method = sg_method_name((sg_method)method);
    meta.bits = method == SG_METHOD_MPFR ? opts.mpfr_bits : 0;
    meta.wave_um = sys->wave[wave0].um;
    meta.wave_index = wave0 + 1;
    meta.opd = kind == SG_RAYS_NORMALIZED;
    meta.global = gf != NULL;
    meta.global_ref = global;
    meta.sys = sys;
    meta.surfaces = sel;
    meta.nsurfaces = nsel;
    /* Its CSV rows begin with the launch, as the editor's export of it. */
    meta.csv_inputs = kind == SG_RAYS_NORMALIZED;

    /* The output is opened only now, so a failed trace leaves an existing
     * file as it was. */
    f = cli_open_output(output);
    if (!f) {
        rc = CLI_EXIT_FILE;
        goto done;
    }
    if (report_write_opd(f, (report_fmt)fmt, &meta, nsurf, out, status, nray, kind, &one,
                         kind == SG_RAYS_NORMALIZED ? &opd1 : NULL) != 0) {
        cli_error("%s: %s", output && strcmp(output, "-") ? output : "standard output",
                  strerror(errno));
        if (f != stdout)
            fclose(f);
        rc = CLI_EXIT_FILE;
        goto done;
    }
    rc = cli_close_output(f, output);
done:
    free(out);
    free(status);
    free(gf);
    free(sel);
    sg_tracer_free(t);
    cli_design_free(cat, sys);
    return rc;
}

/* ----------------------------------------------------------------- paraxial */

static void paraxial_help(FILE *f)
{
    fputs(
"Usage: sagitta paraxial DESIGN.json [OPTIONS]\n"
"Print the first-order (paraxial) data of a design.\n"
"\n"
"Options:\n"
"  --wave N                 wavelength number, from 1 (default: the primary)\n"
"  --format F               text (default) or json\n"
"  -o, --output FILE        write to FILE instead of standard output\n"
"  -h, --help               show this help\n", f);
}

int cmd_paraxial(int argc, char **argv)
{
    cli_iter it;
    const char *design = NULL, *output = NULL;
    int rc, wave1 = 0, wave0 = 0, fmt = REPORT_TEXT;
    sg_catalog *cat = NULL;
    sg_system *sys = NULL;
    sg_paraxial p;
    report_meta meta;
    sg_diag d;
    FILE *f;
    const cli_opt opts[] = {CLI_OPT_HELP, CLI_OPT_INT("--wave", 0, wave1, 1, SG_MAX_WAVES),
                            CLI_OPT_FORMAT(fmt), CLI_OPT_OUTPUT(output), CLI_END};

    cli_iter_init(&it, "paraxial", argc, argv);
    rc = cli_parse(&it, opts, &design, paraxial_help);
    if (rc != CLI_EXIT_OK)
        return rc == CLI_DONE ? CLI_EXIT_OK : rc;
    rc = cli_load_design(design, &cat, &sys);
    if (rc != CLI_EXIT_OK)
        return rc;
    rc = cli_check_wave(design, sys, wave1, &wave0);
    if (rc != CLI_EXIT_OK)
        goto done;
    sg_diag_clear(&d);
    memset(&p, 0, sizeof p);
    rc = sg_paraxial_compute(sys, cat, wave0, &p, &d);
    if (rc != SG_OK) {
        cli_print_diag(design, &d, rc);
        rc = cli_exit_for(rc);
        if (rc == CLI_EXIT_OK)
            rc = CLI_EXIT_INTERNAL;
        goto done;
    }
    cli_print_warnings(&d, design);

    memset(&meta, 0, sizeof meta);
    meta.design = design;
    meta.wave_um = sys->wave[wave0].um;
    meta.wave_index = wave0 + 1;
    f = cli_open_output(output);
    if (!f) {
        rc = CLI_EXIT_FILE;
        goto done;
    }
    if (report_write_paraxial(f, (report_fmt)fmt, &meta, &p) != 0) {
        cli_error("%s: %s", output && strcmp(output, "-") ? output : "standard output",
                  strerror(errno));
        if (f != stdout)
            fclose(f);
        rc = CLI_EXIT_FILE;
        goto done;
    }
    rc = cli_close_output(f, output);
done:
    cli_design_free(cat, sys);
    return rc;
}

const char *cli_shortest(double v, char *buf, size_t n)
{
    char g[NUMFMT_SHORTEST_MAX];
    numfmt_shortest_g(v, g);
    snprintf(buf, n, "%s", g);
    return buf;
}

const int cli_format_values[2] = {REPORT_TEXT, REPORT_JSON};
const int cli_format_csv_values[3] = {REPORT_TEXT, REPORT_CSV, REPORT_JSON};

int cli_parse(cli_iter *it, const cli_opt *opts, const char **design, void (*help)(FILE *))
{
    const char *val;
    int id;
    while ((id = cli_next_opt(it, opts, &val)) != -1) {
        if (id == 0) {
            if (*design)
                return cli_usage_error(it->cmd, "unexpected argument \"%s\"", val);
            *design = val;
        } else if (id == CLI_HELP) {
            help(stdout);
            return CLI_DONE;
        } else {
            return id < 0 ? -id : cli_usage_error(it->cmd, "%s: not handled", it->opt);
        }
    }
    if (!*design)
        return cli_usage_error(it->cmd, "missing DESIGN.json");
    return CLI_EXIT_OK;
}

const int cli_method_values[3] = {SG_METHOD_PRECISE, SG_METHOD_CLASSIC, SG_METHOD_MPFR};

int cli_method_value(const char *s, int *method)
{
    int m = sg_method_parse(s);
    if (m < 0) {
        cli_error("--method: expected precise, classic or mpfr, got \"%s\"", s);
        return CLI_EXIT_USAGE;
    }
    *method = m;
    return CLI_EXIT_OK;
}
