/*
 * test_cli_tolerance.c - "sagitta tolerance" as a user runs it: the
 * nominal criterion against "sagitta spot"'s per-field RMS combined by the
 * field weights, sqrt(sum w c^2 / sum w); a paraboloid's TRAD rows
 * compensated to a perfect focus again; the JSON's shape; reports that are
 * the same bytes on one and two threads; -o refused over an existing file
 * without --force; a design without tolerances refused; Ctrl-C mid-run
 * writing the trials done, in order, marked stopped.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/wait.h>

#include <cjson/cJSON.h>

#include "clitest.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const char *exe;

/* Two lenses of index 1.5 and 1.6; fields 0, 2 and 3 degrees weighted 1,
 * 2 and 3. */
static const char *doublet(const char *name, const char *tol)
{
    char text[8192];
    snprintf(text, sizeof text,
             "{\"format\": \"sagitta-design\", \"units\": \"mm\","
             "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618, \"weight\": 1},"
             " {\"um\": 0.48, \"weight\": 0.5}]},"
             "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0, \"weight\": 1},"
             " {\"y\": 2, \"weight\": 2}, {\"y\": 3, \"weight\": 3}]},"
             "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
             "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
             "{\"radius\": 50, \"thickness\": 4, \"material\": 1.5, \"stop\": true},"
             "{\"radius\": -50, \"thickness\": 2},"
             "{\"radius\": 80, \"thickness\": 3, \"material\": 1.6},"
             "{\"radius\": \"inf\", \"thickness\": 30},"
             "{\"radius\": \"inf\", \"thickness\": 0}]%s}",
             tol);
    return ct_file(name, text);
}

#define TOL                                                                                    \
    ", \"tolerances\": {\"operands\": ["                                                        \
    "{\"type\": \"TRAD\", \"surface\": 1, \"min\": -0.5, \"max\": 0.5},"                       \
    "{\"type\": \"TEDX\", \"first\": 3, \"last\": 3, \"min\": -0.05, \"max\": 0.05},"          \
    "{\"type\": \"TSTY\", \"surface\": 2, \"min\": -0.1, \"max\": 0.1}],"                      \
    "\"compensators\": [{\"surface\": 4, \"parameter\": \"thickness\", \"min\": -3,"           \
    " \"max\": 3}],"                                                                           \
    "\"criterion\": {\"type\": \"rms_spot\", \"reference\": \"centroid\","                     \
    " \"sampling\": {\"pattern\": \"hexapolar\", \"density\": 4}},"                            \
    "\"monte_carlo\": {\"trials\": 6, \"seed\": 5, \"distribution\": \"uniform\"}}"

static double num(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItem(o, k);
    if (!cJSON_IsNumber(v))
        fail_msg("no number \"%s\"", k);
    return v->valuedouble;
}

/* Without compensators the nominal is the design as given: its criterion
 * is spot's per-field RMS (same sampling and reference) combined by the
 * field weights. */
static void nominal_is_spot(void **state)
{
    const char *d = doublet("n.json", TOL);
    ct_result r;
    cJSON *root, *fields;
    double acc = 0.0, wsum = 0.0;
    const double w[3] = {1, 2, 3};
    int k;
    (void)state;
    ct_run(&r, "spot", d, "--reference", "centroid", "--density", "4", "--format", "json",
           NULL);
    assert_int_equal(r.code, 0);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    fields = cJSON_GetObjectItem(root, "fields");
    assert_int_equal(cJSON_GetArraySize(fields), 3);
    for (k = 0; k < 3; k++) {
        double c = num(cJSON_GetArrayItem(fields, k), "rms");
        acc += w[k] * c * c;
        wsum += w[k];
    }
    cJSON_Delete(root);
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--sensitivity", "--no-compensators", "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    ct_close(num(root, "nominal"), sqrt(acc / wsum), 1e-15, 0, "nominal");
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(root, "sensitivity")), 3);
    assert_null(cJSON_GetObjectItem(root, "monte_carlo"));
    cJSON_Delete(root);
    ct_free(&r);
}

/* The wavefront criterion: each field's RMS over the wavelengths, as
 * sagitta wavefront gives them (same grid, about the centroid), combined
 * by the wavelength weights and then the field weights. */
static void wavefront_criterion(void **state)
{
    const char *d = doublet("w.json",
        ", \"tolerances\": {\"operands\": [{\"type\": \"TCON\", \"surface\": 1, \"min\": -0.1,"
        " \"max\": 0.1}], \"criterion\": {\"type\": \"rms_wavefront\", \"reference\":"
        " \"centroid\", \"sampling\": {\"grid\": 16}}}");
    static const char *const fn[3] = {"1", "2", "3"}, *const wn[2] = {"1", "2"};
    const double fw[3] = {1, 2, 3}, ww[2] = {1, 0.5};
    double acc = 0.0, wsum = 0.0;
    ct_result r;
    cJSON *root;
    int f, w;
    (void)state;
    for (f = 0; f < 3; f++) {
        double s2 = 0.0;
        for (w = 0; w < 2; w++) {
            double c;
            ct_run(&r, "wavefront", d, "--field", fn[f], "--wave", wn[w], "--grid", "16",
                   "--format", "json", NULL);
            assert_int_equal(r.code, 0);
            root = cJSON_Parse(r.out);
            assert_non_null(root);
            c = num(root, "rms_centroid");
            s2 += ww[w] * c * c;
            cJSON_Delete(root);
            ct_free(&r);
        }
        acc += fw[f] * s2 / 1.5;
        wsum += fw[f];
    }
    ct_run(&r, "tolerance", d, "--sensitivity", "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    assert_string_equal(cJSON_GetObjectItem(root, "criterion")->valuestring, "rms_wavefront");
    ct_close(num(root, "nominal"), sqrt(acc / wsum), 1e-14, 0, "nominal wavefront");
    cJSON_Delete(root);
    ct_free(&r);
}

/* A paraboloid images the axial point at infinity perfectly at R / 2 for
 * any R: with the back focus compensating, both TRAD rows are perfect
 * again, and the compensator moved by dR / 2. */
static void paraboloid_refocus(void **state)
{
    const char *d = ct_file("p.json",
        "{\"format\": \"sagitta-design\", \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 20},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": -200, \"conic\": -1, \"thickness\": -100, \"material\": \"MIRROR\","
        " \"stop\": true}, {\"radius\": \"inf\", \"thickness\": 0}],"
        "\"tolerances\": {\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, \"min\": -0.4,"
        " \"max\": 0.6}], \"compensators\": [{\"surface\": 1, \"parameter\": \"thickness\","
        " \"min\": -1, \"max\": 1}]}}");
    ct_result r;
    cJSON *root, *row;
    (void)state;
    ct_run(&r, "tolerance", d, "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    row = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "sensitivity"), 0);
    assert_non_null(row);
    assert_string_equal(cJSON_GetObjectItem(row, "type")->valuestring, "TRAD");
    assert_int_equal((int)num(row, "row"), 1);
    assert_int_equal((int)num(row, "surface"), 1);
    assert_true(num(row, "criterion_min") < 1e-8 && num(row, "criterion_max") < 1e-8);
    ct_close(cJSON_GetArrayItem(cJSON_GetObjectItem(row, "compensators_min"), 0)->valuedouble,
             -0.2, 1e-7, 1, "compensator at min");
    ct_close(cJSON_GetArrayItem(cJSON_GetObjectItem(row, "compensators_max"), 0)->valuedouble,
             0.3, 1e-7, 1, "compensator at max");
    cJSON_Delete(root);
    ct_free(&r);
}

/* Monte Carlo's report: the JSON shape, and the same bytes on one
 * and two threads in every format. */
static void threads_same_bytes(void **state)
{
    const char *d = doublet("t.json", TOL);
    static const char *const fmts[3] = {"json", "text", "csv"};
    ct_result r1, r2;
    cJSON *root, *mc, *pct;
    int k;
    (void)state;
    for (k = 0; k < 3; k++) {
        ct_run(&r1, "tolerance", d, "--threads", "1", "--format", fmts[k], NULL);
        ct_run(&r2, "tolerance", d, "--threads", "2", "--format", fmts[k], NULL);
        if (r1.code != 0)
            fail_msg("exit %d: %s", r1.code, r1.err);
        assert_int_equal(r2.code, 0);
        assert_string_equal(r1.out, r2.out);
        if (k == 0) {
            root = cJSON_Parse(r1.out);
            assert_non_null(root);
            mc = cJSON_GetObjectItem(root, "monte_carlo");
            assert_non_null(mc);
            assert_int_equal((int)num(mc, "trials"), 6);
            assert_int_equal((int)num(mc, "seed"), 5);
            assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(mc, "criteria")), 6);
            pct = cJSON_GetObjectItem(mc, "percentiles");
            assert_true(num(pct, "90") >= num(pct, "50") && num(pct, "50") >= num(pct, "10"));
            assert_true(num(mc, "worst") >= num(mc, "mean") && num(mc, "mean") >= num(mc, "best"));
            assert_true(num(mc, "std") > 0);
            assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(root, "sensitivity")), 3);
            assert_true(num(root, "rss_change") > 0);
            cJSON_Delete(root);
        }
        ct_free(&r1);
        ct_free(&r2);
    }
    /* Another seed, other trials. */
    ct_run(&r1, "tolerance", d, "--monte-carlo", "3", "--seed", "5", "--format", "csv", NULL);
    ct_run(&r2, "tolerance", d, "--monte-carlo", "3", "--seed", "6", "--format", "csv", NULL);
    assert_int_equal(r1.code, 0);
    assert_true(strcmp(r1.out, r2.out) != 0);
    ct_free(&r1);
    ct_free(&r2);
}

static void refusals(void **state)
{
    const char *d = doublet("f.json", TOL), *none = doublet("none.json", "");
    const char *out = ct_file("exists.txt", "keep me\n");
    ct_result r;
    char *kept;
    (void)state;
    ct_run(&r, "tolerance", d, "--monte-carlo", "0", "-o", out, NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "exists; use --force"));
    ct_free(&r);
    kept = ct_read(out);
    assert_string_equal(kept, "keep me\n");
    free(kept);
    ct_run(&r, "tolerance", d, "--sensitivity", "--no-compensators", "-o", out, "--force",
           NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    kept = ct_read(out);
    assert_non_null(strstr(kept, "Sensitivity"));
    free(kept);
    ct_run(&r, "tolerance", none, NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "no tolerance operands"));
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--seed", "-3", NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "--seed"));
    ct_free(&r);
}

/* SIGINT during a long Monte Carlo run: the report holds the trials
 * done from the first, says stopped, and the program ends with 0. */
static void interrupted(void **state)
{
    const char *d = doublet("i.json", TOL), *out = ct_path("i_out.json");
    struct timespec ts = {1, 500000000L};
    cJSON *root, *mc;
    char *text;
    int st, done;
    pid_t pid;
    (void)state;
    fflush(NULL);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        unsetenv("CI");
        execl(exe, exe, "tolerance", d, "--monte-carlo", "1000000", "--threads", "2",
              "--format", "json", "-o", out, (char *)NULL);
        _exit(127);
    }
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
        ;
    assert_int_equal(kill(pid, SIGINT), 0);
    assert_int_equal(waitpid(pid, &st, 0), pid);
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0)
        fail_msg("the run ended with status 0x%x", st);
    text = ct_read(out);
    root = cJSON_Parse(text);
    assert_non_null(root);
    assert_true(cJSON_IsTrue(cJSON_GetObjectItem(root, "stopped")));
    mc = cJSON_GetObjectItem(root, "monte_carlo");
    assert_non_null(mc);
    done = (int)num(mc, "done");
    assert_true(done < 1000000);
    assert_int_equal(cJSON_GetArraySize(cJSON_GetObjectItem(mc, "criteria")), done);
    print_message("# stopped after %d trials\n", done);
    cJSON_Delete(root);
    free(text);
}

/* Runs cmd through the shell; its exit code (128 + signal when killed). */
static int shell(const char *cmd)
{
    int st = system(cmd);
    return st == -1 ? -1 : WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

/* Nonzero when the files at a and b hold the same bytes. */
static int same_bytes(const char *a, const char *b)
{
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    int ca, cb, same = fa && fb;
    while (same) {
        ca = getc(fa);
        cb = getc(fb);
        same = ca == cb;
        if (ca == EOF)
            break;
    }
    if (fa)
        fclose(fa);
    if (fb)
        fclose(fb);
    return same;
}

/* Monte Carlo under mpirun with 3 processes (more than this machine's
 * cores, so --oversubscribe; as root where CI runs as root) writes the
 * bytes one process writes with one thread and with two, in CSV and
 * JSON; the trials were split (rank 0's note).  A build without MPI
 * refuses the launch instead, saying so, and writes nothing. */
static void mpi_same_bytes(void **state)
{
    const char *d = doublet("m.json", TOL);
    const char *ci = getenv("CI");
    static const char *const fmts[3] = {"csv", "json", "hdf5"};
    static const char *const thr[3] = {"1", "2", "1"}, *const ext[3] = {"csv", "json", "h5"};
    char cmd[8192], *err, name[32];
    ct_result r;
    int k, rc;
    (void)state;
    if (shell("mpirun --version >/dev/null 2>&1") != 0) {
        if (ci && ci[0])
            fail_msg("mpirun is not installed (Debian openmpi-bin; tools/dev.sh installs it)");
        print_message("# SKIP mpirun not installed (Debian openmpi-bin)\n");
        return;
    }
    for (k = 0; k < 3; k++) {
        const char *mout, *merr = ct_path("mpi.err"), *one, *two;
        snprintf(name, sizeof name, "mpi.%s", ext[k]);
        mout = ct_path(name);
        snprintf(name, sizeof name, "one.%s", ext[k]);
        one = ct_path(name);
        snprintf(name, sizeof name, "two.%s", ext[k]);
        two = ct_path(name);
        /* --threads 1: blocks of 8, so the 24 trials take 3 blocks, one a
         * rank; --threads 2, blocks of 16. */
        /* Under AddressSanitizer (tools/ci-extra.sh) leak checking is off
         * for the ranks: Open MPI's runtime keeps memory at exit in its
         * components, unloaded by then and built without frame pointers,
         * so LeakSanitizer can neither name nor suppress them.  The
         * single-process runs here check sagitta's own leaks. */
        snprintf(cmd, sizeof cmd,
                 "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" "
                 "mpirun --oversubscribe --allow-run-as-root -np 3 '%s' tolerance '%s' "
                 "--monte-carlo 24 --threads %s --format %s -o '%s' </dev/null >/dev/null "
                 "2>'%s'",
                 exe, d, thr[k], fmts[k], mout, merr);
        rc = shell(cmd);
        err = ct_read(merr);
        if (rc != 0 && strstr(err, "built without MPI")) {
            assert_null(fopen(mout, "r"));
            free(err);
            print_message("# SKIP this sagitta was built without MPI (-Dmpi=disabled or no "
                          "libopenmpi-dev): the launch was refused\n");
            return;
        }
        if (rc != 0)
            fail_msg("mpirun exit %d: %s", rc, err);
        if (!strstr(err, "24 trials on 3 processes (MPI)"))
            fail_msg("no split of the trials reported: %s", err);
        free(err);
        ct_run(&r, "tolerance", d, "--monte-carlo", "24", "--threads", "1", "--format",
               fmts[k], "-o", one, NULL);
        assert_int_equal(r.code, 0);
        ct_free(&r);
        ct_run(&r, "tolerance", d, "--monte-carlo", "24", "--threads", "2", "--format",
               fmts[k], "-o", two, NULL);
        assert_int_equal(r.code, 0);
        ct_free(&r);
        if (!same_bytes(mout, one) || !same_bytes(mout, two))
            fail_msg("--format %s: 3 ranks' file differs from one process's", fmts[k]);
    }
}

/* The numbers after "DATA {" in h5dump's text, up to n; their count. */
static int h5_numbers(const char *text, double *v, int n)
{
    const char *p = strstr(text, "DATA {");
    int k = 0;
    char *end;
    if (!p)
        return 0;
    p += 6;
    while (k < n) {
        while (*p == ' ' || *p == ',' || *p == '\n')
            p++;
        if (*p == '}')
            break;
        v[k] = strtod(p, &end);
        if (end == p)
            break;
        k++;
        p = end;
    }
    return k;
}

/* --format hdf5: the Monte Carlo table read back by h5dump (HDF5's own
 * tool) holds the CSV's criteria, bit for bit (17 digits), trials 1 to N
 * and the nominal; the same bytes on one and two threads (and ranks, in
 * mpi_same_bytes).  Without -o it is refused. */
static void hdf5_table(void **state)
{
    const char *d = doublet("h.json", TOL), *h5 = ct_path("t.h5"), *ci = getenv("CI");
    char cmd[8192], *text;
    double v[16], t[16];
    ct_result r;
    int k, n;
    (void)state;
    if (shell("h5dump --version >/dev/null 2>&1") != 0) {
        if (ci && ci[0])
            fail_msg("h5dump is not installed (Debian hdf5-tools)");
        print_message("# SKIP h5dump not installed (hdf5-tools)\n");
        return;
    }
    ct_run(&r, "tolerance", d, "--monte-carlo", "10", "--format", "hdf5", "-o", h5, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--monte-carlo", "10", "--format", "csv", NULL);
    assert_int_equal(r.code, 0);
    snprintf(cmd, sizeof cmd, "h5dump -d /criterion -m %%.17g -y -w 0 '%s' > '%s'", h5,
             ct_path("crit.txt"));
    assert_int_equal(shell(cmd), 0);
    text = ct_read(ct_path("crit.txt"));
    n = h5_numbers(text, v, 16);
    free(text);
    assert_int_equal(n, 10);
    for (k = 0; k < 10; k++)
        if (v[k] != ct_csv_num(r.out, k + 1, "criterion_min"))
            fail_msg("trial %d: %.17g in HDF5, %.17g in CSV", k + 1, v[k],
                     ct_csv_num(r.out, k + 1, "criterion_min"));
    snprintf(cmd, sizeof cmd, "h5dump -d /trial -y -w 0 '%s' > '%s'", h5, ct_path("tr.txt"));
    assert_int_equal(shell(cmd), 0);
    text = ct_read(ct_path("tr.txt"));
    assert_int_equal(h5_numbers(text, t, 16), 10);
    free(text);
    for (k = 0; k < 10; k++)
        assert_true(t[k] == k + 1);
    snprintf(cmd, sizeof cmd, "h5dump -a /nominal -m %%.17g '%s' > '%s'", h5,
             ct_path("nom.txt"));
    assert_int_equal(shell(cmd), 0);
    text = ct_read(ct_path("nom.txt"));
    assert_non_null(strstr(text, "(0): "));
    assert_true(strtod(strstr(text, "(0): ") + 5, NULL) == ct_csv_num(r.out, 0,
                                                                       "criterion_min"));
    free(text);
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--monte-carlo", "10", "--format", "hdf5", NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
}

/* The number of trial rows in text. */
static int trial_rows(const char *text)
{
    int n = 0;
    const char *p = text;
    for (; (p = strstr(p, "\ntrial,")) != NULL; p++)
        n++;
    return n;
}

/* A Monte Carlo table killed (SIGKILL) while it grows, its last line torn
 * as a write cut short leaves it, then --resume: the file an
 * uninterrupted run writes, byte for byte.  --resume refuses a table of
 * another seed (its last trial computed again differs) and leaves it as
 * it was, and wants -o FILE in CSV. */
static void resume_after_kill(void **state)
{
    const char *d = doublet("k.json", TOL), *full = ct_path("full.csv");
    const char *part = ct_path("part.csv");
    char *a, *b, torn[64];
    ct_result r;
    pid_t pid;
    int st, k, rows = 0;
    FILE *f;
    (void)state;
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--threads", "1", "--format", "csv",
           "-o", full, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    ct_free(&r);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(null, 2);
        execl(exe, exe, "tolerance", d, "--monte-carlo", "40", "--threads", "1", "--format",
              "csv", "-o", part, (char *)NULL);
        _exit(127);
    }
    /* Killed once a block of trials is in the file. */
    for (k = 0; k < 6000 && rows == 0; k++) {
        struct timespec ts = {0, 20000000};
        nanosleep(&ts, NULL);
        if ((f = fopen(part, "r")) != NULL) {
            fclose(f);
            a = ct_read(part);
            rows = trial_rows(a);
            free(a);
        }
    }
    kill(pid, SIGKILL);
    waitpid(pid, &st, 0);
    a = ct_read(part);
    rows = trial_rows(a);
    free(a);
    print_message("# killed after %d of 40 trials\n", rows);
    /* The rows were in the file while the run went on. */
    assert_true(rows > 0 && rows < 40);
    if (rows < 40) {
        f = fopen(part, "a");
        assert_non_null(f);
        snprintf(torn, sizeof torn, "trial,%d,,,,,0.0", rows + 1);
        fputs(torn, f);
        fclose(f);
    }
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--threads", "2", "--format", "csv",
           "-o", part, "--resume", NULL);
    if (r.code != 0)
        fail_msg("resume: exit %d: %s", r.code, r.err);
    ct_free(&r);
    a = ct_read(full);
    b = ct_read(part);
    assert_string_equal(a, b);
    free(b);
    /* A whole table with a torn line after it: the line goes. */
    f = fopen(part, "a");
    assert_non_null(f);
    fputs("trial,4", f);
    fclose(f);
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--format", "csv", "-o", part,
           "--resume", NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = ct_read(part);
    assert_string_equal(a, b);
    free(b);
    /* Another seed's trials are refused, the file untouched. */
    ct_run(&r, "tolerance", d, "--monte-carlo", "41", "--seed", "6", "--format", "csv", "-o",
           part, "--resume", NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "trial 40 is not this run's"));
    ct_free(&r);
    b = ct_read(part);
    assert_string_equal(a, b);
    free(a);
    free(b);
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--format", "json", "-o", part,
           "--resume", NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--format", "csv", "-o",
           ct_path("none.csv"), "--resume", NULL);
    assert_int_equal(r.code, 3);
    ct_free(&r);
}

/* A file's bytes and their count (the file must exist). */
static char *ct_read_n(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    char *b;
    long len;
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    len = ftell(f);
    rewind(f);
    b = malloc((size_t)len + 1);
    assert_non_null(b);
    *n = fread(b, 1, (size_t)len, f);
    fclose(f);
    return b;
}

/* That path holds the n bytes a. */
static void assert_file_is(const char *path, const char *a, size_t n)
{
    size_t nb;
    char *b = ct_read_n(path, &nb);
    assert_true(nb == n && memcmp(a, b, n) == 0);
    free(b);
}

/* --resume --format hdf5: a run stopped by Ctrl-C (SIGINT) closes its
 * table with the trials done; resumed on another thread count it is the
 * file an uninterrupted run writes, byte for byte.  A table of another
 * seed or trial count is refused and left as it was; a whole one is left
 * as it was. */
static void resume_hdf5(void **state)
{
    const char *d = doublet("r5.json", TOL), *full = ct_path("full.h5");
    const char *part = ct_path("part.h5"), *ci = getenv("CI");
    char tmp[4096], cmd[8192], *a;
    size_t na;
    ct_result r;
    pid_t pid;
    int st, k;
    FILE *f;
    struct timespec t0, t1;
    double half;
    (void)state;
    if (shell("h5dump --version >/dev/null 2>&1") != 0) {
        if (ci && ci[0])
            fail_msg("h5dump is not installed (Debian hdf5-tools)");
        print_message("# SKIP h5dump not installed (hdf5-tools)\n");
        return;
    }
    clock_gettime(CLOCK_MONOTONIC, &t0);
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--threads", "1", "--format", "hdf5",
           "-o", full, NULL);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    ct_free(&r);
    /* Stopped halfway through the uninterrupted run's time, which grows
     * under a sanitizer or a loaded machine alike. */
    half = 0.5 * ((double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec));
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(null, 2);
        execl(exe, exe, "tolerance", d, "--monte-carlo", "40", "--threads", "1", "--format",
              "hdf5", "-o", part, (char *)NULL);
        _exit(127);
    }
    /* Stopped once the trials run (the table is made after the nominal). */
    snprintf(tmp, sizeof tmp, "%s.tmp%ld", part, (long)pid);
    for (k = 0; k < 6000; k++) {
        struct timespec ts = {0, 10000000};
        nanosleep(&ts, NULL);
        if ((f = fopen(tmp, "r")) != NULL) {
            fclose(f);
            break;
        }
    }
    {
        struct timespec ts = {(time_t)half, (long)(1e9 * (half - floor(half)))};
        nanosleep(&ts, NULL);
    }
    kill(pid, SIGINT);
    waitpid(pid, &st, 0);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    snprintf(cmd, sizeof cmd, "h5dump -a /done '%s' > '%s'", part, ct_path("done.txt"));
    assert_int_equal(shell(cmd), 0);
    a = ct_read(ct_path("done.txt"));
    assert_non_null(strstr(a, "(0): "));
    k = atoi(strstr(a, "(0): ") + 5);
    free(a);
    print_message("# stopped after %d of 40 trials (SIGINT after %.2f s)\n", k, half);
    assert_true(k < 40);
    /* Another seed, or another trial count: refused, the file as it was. */
    a = ct_read_n(part, &na);
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--seed", "6", "--format", "hdf5", "-o",
           part, "--resume", NULL);
    assert_int_equal(r.code, 3);
    assert_non_null(strstr(r.err, "its seed"));
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--monte-carlo", "61", "--format", "hdf5", "-o", part,
           "--resume", NULL);
    assert_int_equal(r.code, 3);
    assert_non_null(strstr(r.err, "not this run's 61"));
    ct_free(&r);
    assert_file_is(part, a, na);
    free(a);
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--threads", "2", "--format", "hdf5",
           "-o", part, "--resume", NULL);
    if (r.code != 0)
        fail_msg("resume: exit %d: %s", r.code, r.err);
    ct_free(&r);
    a = ct_read_n(full, &na);
    assert_file_is(part, a, na);
    /* Whole: left as it was. */
    ct_run(&r, "tolerance", d, "--monte-carlo", "40", "--format", "hdf5", "-o", part,
           "--resume", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.err, "holds all 40 trials"));
    ct_free(&r);
    assert_file_is(part, a, na);
    free(a);
}

/* The doublet's criterion by sagitta spot (per-field RMS about the
 * centroid, density 4) combined with the field weights 1, 2, 3. */
static double spot_criterion(const char *design)
{
    const double w[3] = {1, 2, 3};
    double acc = 0.0, wsum = 0.0;
    ct_result r;
    cJSON *root, *fields;
    int k;
    ct_run(&r, "spot", design, "--reference", "centroid", "--density", "4", "--format", "json",
           NULL);
    if (r.code != 0)
        fail_msg("spot %s: exit %d: %s", design, r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    fields = cJSON_GetObjectItem(root, "fields");
    assert_int_equal(cJSON_GetArraySize(fields), 3);
    for (k = 0; k < 3; k++) {
        double c = num(cJSON_GetArrayItem(fields, k), "rms");
        acc += w[k] * c * c;
        wsum += w[k];
    }
    cJSON_Delete(root);
    ct_free(&r);
    return sqrt(acc / wsum);
}

/* --save-worst 2: the two largest criteria of the CSV (sorted here), and
 * sagitta spot on each saved design (a perturbed, compensated lens)
 * gives that criterion; the files are not overwritten without --force,
 * which the run refuses before it starts. */
static void save_worst(void **state)
{
    const char *d = doublet("s.json", TOL), *w1 = ct_path("s-worst1.json");
    const char *w2 = ct_path("s-worst2.json"), *csv = ct_path("s.csv");
    double c[10], top[2] = {-1, -1};
    int k, it[2] = {-1, -1};
    ct_result r;
    char *text, *again;
    (void)state;
    ct_run(&r, "tolerance", d, "--monte-carlo", "10", "--format", "csv", "--save-worst", "2",
           "-o", csv, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    ct_free(&r);
    text = ct_read(csv);
    for (k = 0; k < 10; k++) {
        c[k] = ct_csv_num(text, k + 1, "criterion_min");
        if (c[k] > top[0]) {
            top[1] = top[0];
            it[1] = it[0];
            top[0] = c[k];
            it[0] = k;
        } else if (c[k] > top[1]) {
            top[1] = c[k];
            it[1] = k;
        }
    }
    free(text);
    print_message("# worst trials %d and %d\n", it[0] + 1, it[1] + 1);
    ct_close(spot_criterion(w1), top[0], 1e-13, 0, "worst 1");
    ct_close(spot_criterion(w2), top[1], 1e-13, 0, "worst 2");
    text = ct_read(w1);
    ct_run(&r, "tolerance", d, "--monte-carlo", "10", "--save-worst", "1", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "exists"));
    ct_free(&r);
    again = ct_read(w1);
    assert_string_equal(text, again);
    free(text);
    free(again);
}

/* --inverse on a thin lens (zero thickness, n = 1.5, R1 = 50, R2 = -50,
 * f = 50) whose criterion is the merit function |EFFL - 50|: TRAD on R1
 * reaches a change of L = 0.5 where the lensmaker's equation
 * 1/f = (n - 1)(1/R1 - 1/R2) gives f = 50 +- 0.5, R1 = 1 / (1/((n - 1) f)
 * + 1/R2). */
static void inverse_thin_lens(void **state)
{
    const char *d = ct_file("thin.json",
        "{\"format\": \"sagitta-design\", \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618, \"weight\": 1}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0, \"weight\": 1}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 50, \"thickness\": 0, \"material\": 1.5, \"stop\": true},"
        "{\"radius\": -50, \"thickness\": 50}, {\"radius\": \"inf\", \"thickness\": 0}],"
        "\"merit\": {\"operands\": [{\"type\": \"EFFL\", \"wave\": 1, \"target\": 50,"
        " \"weight\": 1}]},"
        "\"tolerances\": {\"operands\": [{\"type\": \"TRAD\", \"surface\": 1, \"min\": -1,"
        " \"max\": 1}], \"criterion\": {\"type\": \"merit\"}}}");
    const double n1 = 0.5, r2 = -50;
    double lo = 1.0 / (1.0 / (n1 * 49.5) + 1.0 / r2) - 50;
    double hi = 1.0 / (1.0 / (n1 * 50.5) + 1.0 / r2) - 50;
    ct_result r;
    cJSON *root, *inv, *row;
    (void)state;
    ct_run(&r, "tolerance", d, "--inverse", "0.5", "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    inv = cJSON_GetObjectItem(root, "inverse");
    assert_non_null(inv);
    ct_close(num(inv, "limit"), 0.5, 0, 0, "limit");
    row = cJSON_GetArrayItem(cJSON_GetObjectItem(inv, "rows"), 0);
    assert_non_null(row);
    assert_string_equal(cJSON_GetObjectItem(row, "status_min")->valuestring, "ok");
    ct_close(num(row, "min"), lo, 1e-10, 0, "inverse min");
    ct_close(num(row, "max"), hi, 1e-10, 0, "inverse max");
    ct_close(num(row, "criterion_max"), num(root, "nominal") + 0.5, 1e-10, 0, "criterion");
    cJSON_Delete(root);
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--inverse", "-1", NULL);
    assert_int_equal(r.code, 2);
    ct_free(&r);
}

/* ---- pictures ---------------------------------------------------------- */

#define TOL8                                                                                   \
    ", \"tolerances\": {\"operands\": ["                                                        \
    "{\"type\": \"TRAD\", \"surface\": 1, \"min\": -0.5, \"max\": 0.5},"                       \
    "{\"type\": \"TEDX\", \"first\": 3, \"last\": 3, \"min\": -0.05, \"max\": 0.05},"          \
    "{\"type\": \"TSTY\", \"surface\": 2, \"min\": -0.1, \"max\": 0.1},"                       \
    "{\"type\": \"TTHI\", \"surface\": 1, \"min\": -0.1, \"max\": 0.1},"                       \
    "{\"type\": \"TRAD\", \"surface\": 2, \"min\": -0.5, \"max\": 0.5},"                       \
    "{\"type\": \"TEDY\", \"first\": 1, \"last\": 2, \"min\": -0.05, \"max\": 0.05},"          \
    "{\"type\": \"TRAD\", \"surface\": 3, \"min\": -1, \"max\": 1},"                           \
    "{\"type\": \"TIND\", \"surface\": 3, \"min\": -0.001, \"max\": 0.001}],"                  \
    "\"compensators\": [{\"surface\": 4, \"parameter\": \"thickness\", \"min\": -3,"           \
    " \"max\": 3}],"                                                                           \
    "\"criterion\": {\"type\": \"rms_spot\", \"reference\": \"centroid\","                     \
    " \"sampling\": {\"pattern\": \"hexapolar\", \"density\": 4}},"                            \
    "\"monte_carlo\": {\"trials\": 30, \"seed\": 5, \"distribution\": \"uniform\"}}"

/* The rows of a run's JSON, worst first as Zemax ranks them (the larger
 * of the two changes, descending; ties in row order): their indices. */
static int json_worst_order(const cJSON *sens, int *ord)
{
    int n = cJSON_GetArraySize(sens), k, j;
    for (k = 0; k < n; k++) {
        const cJSON *row = cJSON_GetArrayItem(sens, k);
        double w = fmax(num(row, "change_min"), num(row, "change_max"));
        for (j = k; j > 0; j--) {
            const cJSON *o = cJSON_GetArrayItem(sens, ord[j - 1]);
            if (!(fmax(num(o, "change_min"), num(o, "change_max")) < w))
                break;
            ord[j] = ord[j - 1];
        }
        ord[j] = k;
    }
    return n;
}

/* A row's label as the chart prints it: "TRAD 2", "TEDX 3-3". */
static void json_label(const cJSON *row, char *buf, size_t n)
{
    const cJSON *first = cJSON_GetObjectItem(row, "first");
    const char *type = cJSON_GetObjectItem(row, "type")->valuestring;
    if (first)
        snprintf(buf, n, "%s %d-%d", type, (int)num(row, "first"), (int)num(row, "last"));
    else
        snprintf(buf, n, "%s %d", type, (int)num(row, "surface"));
}

/* The filled rectangles and stroked lines of an SVG that cairo wrote, by
 * colour (its "rgb(R%,G%,B%)"), in drawing order. */
typedef struct svg_rect {
    double x0, y0, x1, y1;
} svg_rect;

static int svg_rects(const char *svg, const char *fill, svg_rect *out, int max)
{
    char key[64];
    const char *p = strstr(svg, "</defs>");
    int n = 0;
    snprintf(key, sizeof key, "fill:%s;", fill);
    for (p = p ? p : svg; (p = strstr(p, "<path style=\"")) != NULL; p++) {
        const char *end = strchr(p, '>'), *d = strstr(p, " d=\"");
        svg_rect r;
        double xb, yb;
        if (!end || !d || d > end)
            continue;
        {
            char style[256];
            size_t len = (size_t)(d - p) < sizeof style - 1 ? (size_t)(d - p) : sizeof style - 1;
            memcpy(style, p, len);
            style[len] = '\0';
            if (!strstr(style, key))
                continue;
        }
        if (sscanf(d, " d=\"M %lf %lf L %lf %lf L %lf %lf", &r.x0, &r.y0, &xb, &yb, &r.x1,
                   &r.y1) == 6 && n < max)
            out[n++] = r;
    }
    return n;
}

static int svg_lines(const char *svg, const char *stroke, double (*pt)[6], int max)
{
    char key[64];
    const char *p = strstr(svg, "</defs>");
    int n = 0;
    snprintf(key, sizeof key, "stroke:%s;", stroke);
    for (p = p ? p : svg; (p = strstr(p, key)) != NULL; p++) {
        const char *d = strstr(p, " d=\"");
        if (d && n < max &&
            sscanf(d, " d=\"M %lf %lf L %lf %lf L %lf %lf", &pt[n][0], &pt[n][1], &pt[n][2],
                   &pt[n][3], &pt[n][4], &pt[n][5]) == 6)
            n++;
    }
    return n;
}

/* A bar's signed height in SVG units (up is positive) about the zero line
 * at y = zero. */
static double bar_height(const svg_rect *r, double zero)
{
    double a = fmin(r->y0, r->y1), b = fmax(r->y0, r->y1);
    return fabs(b - zero) < 0.01 ? b - a : -(b - a); /* cairo rounds to 1/256 */
}

/* The pictures carry the run's own numbers (its JSON): the chart's bars
 * one pair a row, worst first, their heights proportional to the JSON's
 * changes at min and max; the histogram's bars the trials' criteria
 * binned (ceil(sqrt(m)) equal bins, best to worst); the percentile marks
 * where the JSON's percentiles are.  The colours are plot.c's palette:
 * blue at min, green at max, red the histogram, magenta the marks.  PNG,
 * SVG and PDF by their magic; the terminal picture within 80 x 24 with
 * every shown bar labelled in the JSON's worst-first order. */
static void pictures(void **state)
{
    const char *d = doublet("pic.json", TOL8), *svg = ct_path("pic.svg");
    const char *png = ct_path("pic.png"), *pdf = ct_path("pic.pdf");
    ct_result r;
    cJSON *root, *sens, *mc, *crit, *pct;
    int ord[16], n, k, nb, nr, m = 0, counts[64] = {0};
    svg_rect rmin[64], rmax[64], hist[128];
    double lines[16][6], sc, num_, den, zero, lo = INFINITY, hi = -INFINITY, v[64];
    char *b, lab[32];
    (void)state;
    ct_run(&r, "tolerance", d, "--format", "json", NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    root = cJSON_Parse(r.out);
    assert_non_null(root);
    ct_free(&r);
    sens = cJSON_GetObjectItem(root, "sensitivity");
    mc = cJSON_GetObjectItem(root, "monte_carlo");
    crit = cJSON_GetObjectItem(mc, "criteria");
    pct = cJSON_GetObjectItem(mc, "percentiles");
    n = json_worst_order(sens, ord);
    assert_int_equal(n, 8);

    ct_run(&r, "tolerance", d, "--format", "svg", "-o", svg, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    ct_free(&r);
    b = ct_read(svg);
    assert_true(strncmp(b, "<?xml", 5) == 0 && strstr(b, "</svg>"));
    /* The legend's square first, then a bar a row. */
    assert_int_equal(svg_rects(b, "rgb(0%,35%,85%)", rmin, 64), n + 1);
    assert_int_equal(svg_rects(b, "rgb(0%,60%,20%)", rmax, 64), n + 1);
    /* The zero line: the edge every bar shares. */
    zero = fabs(fmin(rmin[1].y0, rmin[1].y1) - fmin(rmin[2].y0, rmin[2].y1)) < 0.01 ||
                   fabs(fmin(rmin[1].y0, rmin[1].y1) - fmax(rmin[2].y0, rmin[2].y1)) < 0.01
               ? fmin(rmin[1].y0, rmin[1].y1)
               : fmax(rmin[1].y0, rmin[1].y1);
    num_ = den = 0.0;
    for (k = 0; k < n; k++) {
        const cJSON *row = cJSON_GetArrayItem(sens, ord[k]);
        double a = num(row, "change_min"), c = num(row, "change_max");
        /* Left to right in the JSON's worst-first order. */
        if (k > 0)
            assert_true(rmin[k + 1].x0 > rmin[k].x0 && rmax[k + 1].x0 > rmax[k].x0);
        assert_true(rmin[k + 1].x0 < rmax[k + 1].x0);
        num_ += bar_height(&rmin[k + 1], zero) * a + bar_height(&rmax[k + 1], zero) * c;
        den += a * a + c * c;
    }
    sc = num_ / den;
    assert_true(sc > 0);
    for (k = 0; k < n; k++) {
        const cJSON *row = cJSON_GetArrayItem(sens, ord[k]);
        double ha = bar_height(&rmin[k + 1], zero), hc = bar_height(&rmax[k + 1], zero);
        if (fabs(ha - sc * num(row, "change_min")) > 0.01 ||
            fabs(hc - sc * num(row, "change_max")) > 0.01)
            fail_msg("row %d: bars %g, %g against the JSON's %g, %g (scale %g)", ord[k] + 1, ha,
                     hc, sc * num(row, "change_min"), sc * num(row, "change_max"), sc);
    }
    /* The histogram from the JSON's criteria. */
    for (k = 0; k < cJSON_GetArraySize(crit); k++) {
        v[m] = cJSON_GetArrayItem(crit, k)->valuedouble;
        lo = fmin(lo, v[m]);
        hi = fmax(hi, v[m]);
        m++;
    }
    assert_int_equal(m, 30);
    nb = (int)ceil(sqrt((double)m));
    for (k = 0; k < m; k++) {
        int j = (int)((v[k] - lo) / ((hi - lo) / nb));
        counts[j >= nb ? nb - 1 : j]++;
    }
    nr = svg_rects(b, "rgb(85%,10%,10%)", hist, 128);
    {
        int j = 0, top = 0;
        double htop = 0.0;
        for (k = 0; k < nb; k++)
            top = counts[k] > top ? counts[k] : top;
        for (k = 1; k < nr; k++)
            htop = fmax(htop, fabs(hist[k].y1 - hist[k].y0));
        /* Each bar that has height, in order, is the next bin with trials. */
        for (k = 1; k < nr; k++) {
            double h = fabs(hist[k].y1 - hist[k].y0);
            if (h < 1e-6)
                continue;
            while (j < nb && counts[j] == 0)
                j++;
            assert_true(j < nb);
            if (fabs(h / htop - (double)counts[j] / top) > 3e-4)
                fail_msg("bin %d: bar %g of %g, the JSON's %d of %d", j, h, htop, counts[j],
                         top);
            j++;
        }
        while (j < nb && counts[j] == 0)
            j++;
        assert_int_equal(j, nb);
    }
    /* The percentile marks: five, at x proportional to the JSON's values
     * and y to 90 .. 10 % (an affine map on each axis). */
    assert_int_equal(svg_lines(b, "rgb(65%,20%,70%)", lines, 16), 5);
    {
        static const char *const pk[5] = {"90", "80", "50", "20", "10"};
        static const double pv[5] = {90, 80, 50, 20, 10};
        double p0 = num(pct, pk[0]), p4 = num(pct, pk[4]);
        /* Each a level line to its point, then down to the axis. */
        for (k = 0; k < 5; k++)
            assert_true(fabs(lines[k][1] - lines[k][3]) < 0.01 &&
                        fabs(lines[k][2] - lines[k][4]) < 0.01 && lines[k][5] > lines[k][3]);
        for (k = 1; k < 4; k++) {
            double tx = (lines[k][2] - lines[4][2]) / (lines[0][2] - lines[4][2]);
            double ty = (lines[k][1] - lines[4][1]) / (lines[0][1] - lines[4][1]);
            assert_true(fabs(tx - (num(pct, pk[k]) - p4) / (p0 - p4)) < 5e-4);
            assert_true(fabs(ty - (pv[k] - 10) / 80) < 5e-4);
        }
    }
    free(b);

    /* PNG and PDF by their magic; the PNG 1000 wide (its bars fit). */
    ct_run(&r, "tolerance", d, "--format", "png", "-o", png, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = ct_read(png);
    assert_memory_equal(b, "\x89PNG\r\n\x1a\n", 8);
    assert_int_equal(((unsigned char)b[16] << 24 | (unsigned char)b[17] << 16 |
                      (unsigned char)b[18] << 8 | (unsigned char)b[19]), 1000);
    free(b);
    ct_run(&r, "tolerance", d, "--format", "pdf", "--size", "800x900", "-o", pdf, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    b = ct_read(pdf);
    assert_memory_equal(b, "%PDF-", 5);
    free(b);
    /* Too small a size is refused with the size it needs. */
    ct_run(&r, "tolerance", d, "--format", "png", "--size", "200x200", "-o", ct_path("s.png"),
           NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "--size"));
    ct_free(&r);

    /* The terminal: two pictures of 24 rows in 80 columns. */
    setenv("COLUMNS", "80", 1);
    ct_run(&r, "tolerance", d, "--plot", NULL);
    unsetenv("COLUMNS");
    assert_int_equal(r.code, 0);
    {
        char *pic = strstr(r.out, "Tolerancing\n"), *line, *nl;
        int rows = 0, shown = 0;
        const char *title;
        /* Back to the blank line before the picture's title. */
        assert_non_null(pic);
        while (pic > r.out && !(pic[0] == '\n' && pic[-1] == '\n'))
            pic--;
        pic--;
        for (line = pic + 2; *line; line = nl + 1) {
            size_t w = 0;
            const unsigned char *u;
            nl = strchr(line, '\n');
            assert_non_null(nl);
            for (u = (const unsigned char *)line; u < (const unsigned char *)nl; u++)
                w += (*u & 0xC0) != 0x80;
            assert_true(w <= 80);
            rows++;
        }
        /* 24 rows, a blank line, 24 rows. */
        assert_int_equal(rows, 49);
        title = strstr(pic, ": the ");
        assert_non_null(title);
        assert_int_equal(sscanf(title, ": the %d worst of 8 operands", &shown), 1);
        assert_true(shown >= 4 && shown < 8);
    }
    {
        /* The label row names the shown bars in the JSON's order. */
        const char *p = strstr(r.out, "Tolerancing\n");
        for (k = 0; k < 8; k++) {
            const char *at;
            json_label(cJSON_GetArrayItem(sens, ord[k]), lab, sizeof lab);
            at = strstr(p, lab);
            if (k < 4) {
                assert_non_null(at);
                p = at;
            }
        }
    }
    ct_free(&r);
    cJSON_Delete(root);
}

/* ---- the default tolerance set ------------------------------------------ */

/* The Cooke triplet of examples/cooke_triplet.json (Sasian, OPTI 517):
 * N-LAK9, N-SF5, N-LAK9 in air, stop on surface 4. */
static const char *triplet(const char *name)
{
    return ct_file(name,
        "{\"format\": \"sagitta-design\", \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 2, \"list\": [{\"um\": 0.4861327, \"weight\": 0.5},"
        " {\"um\": 0.5875618, \"weight\": 1}, {\"um\": 0.6562725, \"weight\": 0.5}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 14.14}, {\"y\": 20}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 12.5}, \"ray_aiming\": \"off\","
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 23.713, \"thickness\": 4.831, \"material\": \"N-LAK9\"},"
        "{\"radius\": 7331.288, \"thickness\": 5.86},"
        "{\"radius\": -24.456, \"thickness\": 0.975, \"material\": \"N-SF5\", \"stop\": true},"
        "{\"radius\": 21.896, \"thickness\": 4.822},"
        "{\"radius\": 86.759, \"thickness\": 3.127, \"material\": \"N-LAK9\"},"
        "{\"radius\": -20.4942, \"thickness\": 41.2365},"
        "{\"radius\": \"inf\", \"thickness\": 0}]}");
}

/* The set Zemax's Tolerance Wizard makes, counted by hand for the
 * triplet: 6 surfaces with power (TFRN 1 fringe); thicknesses 1 to 5
 * (6 focuses) at 0.2 mm, each adjusted by the first air space after it
 * (2, 4, 4, 6, 6); 3 elements (1-2, 3-4, 5-6) with TEDX, TEDY 0.2 mm and
 * TETX, TETY 0.2 deg; surfaces 2 to 6 with TSDX, TSDY 0.2 mm and TSTX,
 * TSTY of a 0.2 mm runout across the automatic diameter, atan(0.2 / D);
 * TIRR of 0.2 fringes on the 6 (standard) surfaces with power;
 * glasses on 1, 3 and 5 with TIND 0.001 and TABB 1 % of the catalog's
 * Abbe numbers (Schott: N-LAK9 54.71, N-SF5 32.25); the back focus (41.2365)
 * compensating within half of it.  55 rows. */
static void default_tolerances(void **state)
{
    const char *d = triplet("tri.json"), *out = ct_path("tri_tol.json");
    static const int adjust[6] = {0, 2, 4, 4, 6, 6};
    ct_result r;
    cJSON *root, *sd, *ops, *comp, *op;
    double D[8] = {0};
    int k, n = 0, nfrn = 0, nthi = 0, nel = 0, nsurf = 0, nglass = 0, nirr = 0;
    (void)state;
    ct_run(&r, "semidiam", d, "--format", "json", NULL);
    assert_int_equal(r.code, 0);
    root = cJSON_Parse(r.out);
    sd = cJSON_GetObjectItem(root, "surfaces");
    for (k = 0; k < cJSON_GetArraySize(sd); k++) {
        const cJSON *row = cJSON_GetArrayItem(sd, k);
        D[(int)num(row, "surface")] = 2 * num(row, "auto");
    }
    cJSON_Delete(root);
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--default-tolerances", "--save-tolerances", out, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    assert_non_null(strstr(r.err, "55 default tolerance rows, 1 compensator"));
    ct_free(&r);
    {
        char *text = ct_read(out);
        root = cJSON_Parse(text);
        free(text);
    }
    assert_non_null(root);
    ops = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "tolerances"), "operands");
    comp = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "tolerances"), "compensators");
    n = cJSON_GetArraySize(ops);
    assert_int_equal(n, 55);
    cJSON_ArrayForEach(op, ops) {
        const char *t = cJSON_GetObjectItem(op, "type")->valuestring;
        int s = cJSON_GetObjectItem(op, "surface") ? (int)num(op, "surface")
                                                   : (int)num(op, "first");
        double lim = num(op, "max");
        assert_true(num(op, "min") == -lim);
        if (strcmp(t, "TFRN") == 0) {
            assert_int_equal(s, ++nfrn);
            assert_true(lim == 1);
        } else if (strcmp(t, "TTHI") == 0) {
            assert_int_equal(s, ++nthi);
            assert_int_equal((int)num(op, "adjust"), adjust[s]);
            assert_true(lim == 0.2);
        } else if (strcmp(t, "TIRR") == 0) {
            assert_int_equal(s, ++nirr);
            assert_true(lim == 0.2);
            assert_int_equal(nsurf, 20); /* after the surfaces' decenters and tilts */
        } else if (t[1] == 'E') {
            /* TEDX, TEDY, TETX, TETY of element 1-2, then 3-4, 5-6. */
            static const char *const kinds[4] = {"TEDX", "TEDY", "TETX", "TETY"};
            assert_string_equal(t, kinds[nel % 4]);
            assert_int_equal(s, 1 + 2 * (nel / 4));
            assert_int_equal((int)num(op, "last"), 2 + 2 * (nel / 4));
            assert_true(lim == 0.2);
            nel++;
        } else if (t[1] == 'S') {
            static const char *const kinds[4] = {"TSDX", "TSDY", "TSTX", "TSTY"};
            assert_string_equal(t, kinds[nsurf % 4]);
            assert_int_equal(s, 2 + nsurf / 4);
            if (nsurf % 4 < 2)
                assert_true(lim == 0.2);
            else
                ct_close(lim, atan(0.2 / D[s]) * 180 / M_PI, 1e-12, 0, "surface tilt");
            nsurf++;
        } else if (strcmp(t, "TIND") == 0 || strcmp(t, "TABB") == 0) {
            assert_int_equal(s, 1 + 2 * (nglass / 2));
            if (t[1] == 'I')
                assert_true(lim == 0.001);
            else
                ct_close(lim, (s == 3 ? 32.25 : 54.71) / 100, 1e-12, 0, "TABB");
            nglass++;
        } else {
            fail_msg("unexpected row %s", t);
        }
    }
    assert_int_equal(nfrn, 6);
    assert_int_equal(nthi, 5);
    assert_int_equal(nel, 12);
    assert_int_equal(nsurf, 20);
    assert_int_equal(nglass, 6);
    assert_int_equal(nirr, 6);
    assert_int_equal(cJSON_GetArraySize(comp), 1);
    op = cJSON_GetArrayItem(comp, 0);
    assert_int_equal((int)num(op, "surface"), 6);
    assert_string_equal(cJSON_GetObjectItem(op, "parameter")->valuestring, "thickness");
    ct_close(num(op, "max"), 41.2365 / 2, 1e-15, 0, "compensator");
    cJSON_Delete(root);
    /* Refused: over the file, or without --default-tolerances. */
    ct_run(&r, "tolerance", d, "--default-tolerances", "--save-tolerances", out, NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "exists"));
    ct_free(&r);
    ct_run(&r, "tolerance", d, "--save-tolerances", ct_path("x.json"), NULL);
    assert_int_not_equal(r.code, 0);
    assert_non_null(strstr(r.err, "--default-tolerances"));
    ct_free(&r);
    /* A cemented doublet is one element, 1-3; the thicknesses 1 and 2
     * are adjusted by the air space 3, which focuses: TFRN 1-3, TTHI 1-2,
     * TEDX..TETY 1-3, TSDX..TSTY on 2 and 3, TIRR 1-3, TIND and TABB on 1
     * and 2. */
    d = ct_file("cem.json",
        "{\"format\": \"sagitta-design\", \"units\": \"mm\","
        "\"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.5875618}]},"
        "\"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 2}]},"
        "\"aperture\": {\"type\": \"epd\", \"value\": 10},"
        "\"surfaces\": [{\"radius\": \"inf\", \"thickness\": \"inf\"},"
        "{\"radius\": 60, \"thickness\": 4, \"material\": \"N-LAK9\", \"stop\": true},"
        "{\"radius\": -40, \"thickness\": 2, \"material\": \"N-SF5\"},"
        "{\"radius\": -200, \"thickness\": 90},"
        "{\"radius\": \"inf\", \"thickness\": 0}]}");
    out = ct_path("cem_tol.json");
    ct_run(&r, "tolerance", d, "--default-tolerances", "--save-tolerances", out, NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    assert_non_null(strstr(r.err, "24 default tolerance rows, 1 compensator"));
    ct_free(&r);
    {
        char *text = ct_read(out);
        static const char *const want[24] = {
            "TFRN 1", "TFRN 2", "TFRN 3", "TTHI 1 3", "TTHI 2 3", "TEDX 1-3", "TEDY 1-3",
            "TETX 1-3", "TETY 1-3", "TSDX 2", "TSDY 2", "TSTX 2", "TSTY 2", "TSDX 3",
            "TSDY 3", "TSTX 3", "TSTY 3", "TIRR 1", "TIRR 2", "TIRR 3", "TIND 1", "TABB 1",
            "TIND 2", "TABB 2"};
        root = cJSON_Parse(text);
        free(text);
        ops = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "tolerances"), "operands");
        assert_int_equal(cJSON_GetArraySize(ops), 24);
        for (k = 0; k < 24; k++) {
            char got[32];
            op = cJSON_GetArrayItem(ops, k);
            json_label(op, got, sizeof got);
            if (cJSON_GetObjectItem(op, "adjust"))
                snprintf(got + strlen(got), sizeof got - strlen(got), " %d",
                         (int)num(op, "adjust"));
            assert_string_equal(got, want[k]);
        }
        op = cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetObjectItem(root, "tolerances"),
                                                    "compensators"), 0);
        assert_int_equal((int)num(op, "surface"), 3);
        cJSON_Delete(root);
    }
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(nominal_is_spot),
        cmocka_unit_test(wavefront_criterion),
        cmocka_unit_test(paraboloid_refocus),
        cmocka_unit_test(threads_same_bytes),
        cmocka_unit_test(refusals),
        cmocka_unit_test(interrupted),
        cmocka_unit_test(mpi_same_bytes),
        cmocka_unit_test(resume_after_kill),
        cmocka_unit_test(resume_hdf5),
        cmocka_unit_test(hdf5_table),
        cmocka_unit_test(save_worst),
        cmocka_unit_test(inverse_thin_lens),
        cmocka_unit_test(pictures),
        cmocka_unit_test(default_tolerances),
    };
    int rc;
    ct_init(argc, argv);
    exe = argv[1];
    /* CT_ONLY=resume_hdf5 runs the tests so named (a mutant's check). */
    if (getenv("CT_ONLY"))
        cmocka_set_test_filter(getenv("CT_ONLY"));
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
