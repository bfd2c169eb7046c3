/* clitest.c - running the built sagitta binary from cmocka tests. */
/* wait4, for the child's peak resident set. */
#define _DEFAULT_SOURCE
#include "clitest.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

#define CT_MAXFILES 256

static const char *exe_path;
static char tmpdir[512];
static char *files[CT_MAXFILES];
static int nfiles;

void ct_init(int argc, char **argv)
{
    const char *base = getenv("TMPDIR");
    if (argc < 2) {
        fprintf(stderr, "usage: %s PATH-TO-SAGITTA\n", argv[0]);
        exit(1);
    }
    exe_path = argv[1];
    snprintf(tmpdir, sizeof tmpdir, "%s/sagitta-cli-XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(tmpdir)) {
        fprintf(stderr, "mkdtemp %s: %s\n", tmpdir, strerror(errno));
        exit(1);
    }
}

void ct_cleanup(void)
{
    int k;
    for (k = 0; k < nfiles; k++) {
        remove(files[k]);
        free(files[k]);
    }
    nfiles = 0;
    rmdir(tmpdir);
}

const char *ct_path(const char *name)
{
    char buf[1024];
    int k;
    snprintf(buf, sizeof buf, "%s/%s", tmpdir, name);
    for (k = 0; k < nfiles; k++)
        if (strcmp(files[k], buf) == 0)
            return files[k];
    assert_true(nfiles < CT_MAXFILES);
    files[nfiles] = strdup(buf);
    assert_non_null(files[nfiles]);
    return files[nfiles++];
}

const char *ct_file(const char *name, const char *text)
{
    const char *p = ct_path(name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, strlen(text), f), strlen(text));
    assert_int_equal(fclose(f), 0);
    return p;
}

const char *ct_design(const char *name, const char *surfaces)
{
    static const char head[] =
        "{\n"
        "  \"format\": \"sagitta-design\",\n"
        "  \"version\": 1,\n"
        "  \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
        "  \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
        "             \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1},\n"
        "                      {\"x\": 0, \"y\": 5, \"weight\": 1}]},\n"
        "  \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"
        "  \"ray_aiming\": \"off\",\n"
        "  \"surfaces\": [\n";
    size_t n = sizeof head + strlen(surfaces) + 16;
    char *text = malloc(n);
    const char *p;
    assert_non_null(text);
    snprintf(text, n, "%s%s\n  ]\n}\n", head, surfaces);
    p = ct_file(name, text);
    free(text);
    return p;
}

char *ct_read(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    size_t len = 0, cap = 0, got;
    assert_non_null(f);
    do {
        if (cap - len < 4096) {
            cap = cap ? 2 * cap : 65536;
            buf = realloc(buf, cap + 1);
            assert_non_null(buf);
        }
        got = fread(buf + len, 1, cap - len, f);
        len += got;
    } while (got > 0);
    fclose(f);
    buf[len] = '\0';
    return buf;
}

void ct_runv(ct_result *r, const char *const *args)
{
    const char *argv[64];
    const char *outp = ct_path("stdout.txt"), *errp = ct_path("stderr.txt");
    posix_spawn_file_actions_t fa;
    pid_t pid;
    int n = 0, st, rc;

    argv[n++] = exe_path;
    while (args[n - 1]) {
        assert_true(n < 63);
        argv[n] = args[n - 1];
        n++;
    }
    argv[n] = NULL;
    assert_int_equal(posix_spawn_file_actions_init(&fa), 0);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, outp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    posix_spawn_file_actions_addopen(&fa, 2, errp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    rc = posix_spawn(&pid, exe_path, &fa, NULL, (char *const *)argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0)
        fail_msg("cannot run %s: %s", exe_path, strerror(rc));
    {
        struct rusage ru;
        memset(&ru, 0, sizeof ru);
        while (wait4(pid, &st, 0, &ru) < 0)
            assert_int_equal(errno, EINTR);
        r->maxrss_kb = ru.ru_maxrss;
    }
    r->code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    r->out = ct_read(outp);
    r->err = ct_read(errp);
}

void ct_run(ct_result *r, ...)
{
    const char *args[64];
    va_list ap;
    int n = 0;
    va_start(ap, r);
    do {
        assert_true(n < 63);
        args[n] = va_arg(ap, const char *);
    } while (args[n++]);
    va_end(ap);
    ct_runv(r, args);
}

void ct_free(ct_result *r)
{
    free(r->out);
    free(r->err);
    r->out = r->err = NULL;
}

/* Field k of the line starting at p (up to its newline), into buf. */
static int field(const char *p, int k, char *buf, size_t n)
{
    int i = 0;
    while (i < k) {
        while (*p && *p != ',' && *p != '\n')
            p++;
        if (*p != ',')
            return -1;
        p++;
        i++;
    }
    i = 0;
    while (*p && *p != ',' && *p != '\n' && *p != '\r' && (size_t)i + 1 < n)
        buf[i++] = *p++;
    buf[i] = '\0';
    return 0;
}

const char *ct_csv(const char *text, int row, const char *col, char *buf, size_t n)
{
    char name[64];
    const char *p = text;
    int k, c = -1;
    for (k = 0; field(text, k, name, sizeof name) == 0; k++)
        if (strcmp(name, col) == 0) {
            c = k;
            break;
        }
    if (c < 0)
        return NULL;
    for (k = 0; k <= row; k++) {
        p = strchr(p, '\n');
        if (!p || !p[1])
            return NULL;
        p++;
    }
    return field(p, c, buf, n) == 0 ? buf : NULL;
}

double ct_csv_num(const char *text, int row, const char *col)
{
    char buf[64], *end;
    double v;
    if (!ct_csv(text, row, col, buf, sizeof buf))
        fail_msg("CSV has no row %d column %s:\n%s", row, col, text);
    v = strtod(buf, &end);
    if (end == buf || *end)
        fail_msg("CSV row %d column %s is not a number: \"%s\"", row, col, buf);
    return v;
}

int ct_contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle), k;
    for (; *hay; hay++) {
        for (k = 0; k < n; k++) {
            char a = hay[k], b = needle[k];
            if (a >= 'A' && a <= 'Z')
                a = (char)(a - 'A' + 'a');
            if (b >= 'A' && b <= 'Z')
                b = (char)(b - 'A' + 'a');
            if (a != b)
                break;
        }
        if (k == n)
            return 1;
    }
    return 0;
}

double ct_close(double a, double b, double tol, double scale, const char *what)
{
    double s = fabs(b) > scale ? fabs(b) : scale;
    double e = fabs(a - b) / s;
    if (!(e <= tol))
        fail_msg("%s: got %.17g, expected %.17g (scaled error %.3g > %.3g)", what, a,
                 b, e, tol);
    return e;
}
