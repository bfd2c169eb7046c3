/* vtest.c - running the built sagitta binary from cmocka tests. */
#include "vtest.h"

#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

#define VT_MAXFILES 64

static const char *exe_path;
static char tmpdir[512];
static char *files[VT_MAXFILES];
static int nfiles;

void vt_init(int argc, char **argv)
{
    const char *base = getenv("TMPDIR");
    if (argc < 2) {
        fprintf(stderr, "usage: %s PATH-TO-SAGITTA\n", argv[0]);
        exit(1);
    }
    exe_path = argv[1];
    snprintf(tmpdir, sizeof tmpdir, "%s/sagitta-verify-XXXXXX",
             base && *base ? base : "/tmp");
    if (!mkdtemp(tmpdir)) {
        fprintf(stderr, "mkdtemp %s: %s\n", tmpdir, strerror(errno));
        exit(1);
    }
}

void vt_cleanup(void)
{
    int k;
    for (k = 0; k < nfiles; k++) {
        remove(files[k]);
        free(files[k]);
    }
    nfiles = 0;
    rmdir(tmpdir);
}

static const char *vt_path(const char *name)
{
    char buf[1024];
    int k;
    snprintf(buf, sizeof buf, "%s/%s", tmpdir, name);
    for (k = 0; k < nfiles; k++)
        if (strcmp(files[k], buf) == 0)
            return files[k];
    assert_true(nfiles < VT_MAXFILES);
    files[nfiles] = strdup(buf);
    assert_non_null(files[nfiles]);
    return files[nfiles++];
}

const char *vt_file(const char *name, const char *text)
{
    const char *p = vt_path(name);
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, strlen(text), f), strlen(text));
    assert_int_equal(fclose(f), 0);
    return p;
}

const char *vt_source(const char *rel, char *buf, size_t n)
{
    const char *root = getenv("SAGITTA_SOURCE_ROOT");
    snprintf(buf, n, "%s/%s", root && *root ? root : ".", rel);
    return buf;
}

static char *slurp(const char *path)
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

void vt_run(vt_result *r, ...)
{
    const char *argv[32];
    const char *outp = vt_path("stdout.txt"), *errp = vt_path("stderr.txt");
    posix_spawn_file_actions_t fa;
    va_list ap;
    pid_t pid;
    int n = 0, st, rc;

    argv[n++] = exe_path;
    va_start(ap, r);
    for (;;) {
        const char *a = va_arg(ap, const char *);
        assert_true(n < 31);
        argv[n++] = a;
        if (!a)
            break;
    }
    va_end(ap);
    assert_int_equal(posix_spawn_file_actions_init(&fa), 0);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, outp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    posix_spawn_file_actions_addopen(&fa, 2, errp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    rc = posix_spawn(&pid, exe_path, &fa, NULL, (char *const *)argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0)
        fail_msg("cannot run %s: %s", exe_path, strerror(rc));
    while (waitpid(pid, &st, 0) < 0)
        assert_int_equal(errno, EINTR);
    r->code = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    r->out = slurp(outp);
    r->err = slurp(errp);
    r->json = cJSON_Parse(r->out);
}

void vt_free(vt_result *r)
{
    free(r->out);
    free(r->err);
    cJSON_Delete(r->json);
    memset(r, 0, sizeof *r);
}

static cJSON *vget(const cJSON *j, va_list ap)
{
    const char *name;
    cJSON *cur = (cJSON *)j;
    assert_non_null(cur);
    while ((name = va_arg(ap, const char *)) != NULL) {
        cJSON *next = cJSON_GetObjectItemCaseSensitive(cur, name);
        if (!next)
            fail_msg("JSON member \"%s\" missing", name);
        cur = next;
    }
    return cur;
}

cJSON *vt_get(const cJSON *j, ...)
{
    va_list ap;
    cJSON *r;
    va_start(ap, j);
    r = vget(j, ap);
    va_end(ap);
    return r;
}

double vt_num(const cJSON *j, ...)
{
    va_list ap;
    cJSON *r;
    va_start(ap, j);
    r = vget(j, ap);
    va_end(ap);
    if (!cJSON_IsNumber(r))
        fail_msg("JSON member \"%s\" is not a number", r->string ? r->string : "?");
    return r->valuedouble;
}
