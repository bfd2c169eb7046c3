/* test_cli_signals.c - a signal that ends "sagitta trace --rays -o FILE"
 * while it writes leaves no hidden partial file beside FILE (issue 30,
 * item 4), and an existing FILE keeps its bytes.
 *
 * The child reads its ray list from a pipe this test holds open, in
 * blocks of 64 rays (SAGITTA_RAYS_BLOCK), so it is certain to be
 * mid-table, its temporary file open, when the signal is sent: the test
 * waits for the temporary to appear, sends the signal, and checks with
 * waitpid() that the signal ended the child (its default action, as
 * without the handler) and with readdir() that no temporary is left.
 * Independent references: the kernel's wait status and the directory's
 * entries. */
#define _XOPEN_SOURCE 700
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "clitest.h"

static const char *exe;

/* Entries of dir whose name holds tag; the first goes to first. */
static int count_named(const char *dir, const char *tag, char *first, size_t n)
{
    DIR *dp = opendir(dir);
    struct dirent *de;
    int k = 0;
    if (first)
        first[0] = '\0';
    assert_non_null(dp);
    while ((de = readdir(dp)) != NULL)
        if (strstr(de->d_name, tag)) {
            if (k++ == 0 && first)
                snprintf(first, n, "%s", de->d_name);
        }
    closedir(dp);
    return k;
}

static void sleep_ms(long ms)
{
    struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR)
        ;
}

/* Starts sagitta trace DESIGN --rays - --format FMT -o OUT in dir, its
 * standard input the write end returned in *in. */
static pid_t start(const char *design, const char *fmt, const char *out, int *in)
{
    int p[2], k;
    pid_t pid;
    fflush(NULL);
    assert_int_equal(pipe(p), 0);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        struct rlimit no_core = {0, 0};
        int null = open("/dev/null", O_WRONLY);
        /* SIGQUIT and SIGXFSZ dump core by default: not here. */
        setrlimit(RLIMIT_CORE, &no_core);
        /* An ignored signal stays so across exec, and sagitta rightly
         * leaves an inherited SIG_IGN alone (as nohup expects): the test
         * ignores SIGPIPE, and a shell's background job ignores SIGINT
         * and SIGQUIT, so every catchable signal gets its default here. */
        for (k = 1; k < 32; k++) /* the standard signals */
            if (k != SIGKILL && k != SIGSTOP)
                signal(k, SIG_DFL);
        dup2(p[0], 0);
        close(p[0]);
        close(p[1]);
        if (null >= 0) {
            dup2(null, 1);
            dup2(null, 2);
        }
        setenv("SAGITTA_RAYS_BLOCK", "64", 1);
        unsetenv("CI");
        execl(exe, exe, "trace", design, "--rays", "-", "--format", fmt, "--threads", "1", "-o",
              out, (char *)NULL);
        _exit(127);
    }
    close(p[0]);
    *in = p[1];
    return pid;
}

/* One run: the signal sig arrives mid-table.  tag names the temporary
 * (".sagitta-" for CSV, ".tmp" for HDF5). */
static void one(const char *design, const char *fmt, const char *out, const char *tag, int sig,
                const char *keep)
{
    char dir[1024], first[256];
    static char rows[1 << 16];
    const char *slash = strrchr(out, '/');
    size_t len = 0, sent = 0;
    int in, st, k;
    pid_t pid;
    snprintf(dir, sizeof dir, "%.*s", (int)(slash - out), out);
    assert_int_equal(count_named(dir, tag, NULL, 0), 0);
    pid = start(design, fmt, out, &in);
    for (k = 0; len + 32 < sizeof rows; k++)
        len += (size_t)snprintf(rows + len, sizeof rows - len, "0,0.%03d,0,0.5\n", k % 1000);
    signal(SIGPIPE, SIG_IGN);
    assert_int_equal(write(in, "hx,hy,px,py\n", 12), 12);
    /* The reader takes its list a megabyte at a time: rays are sent until
     * the first blocks are traced and the table's temporary is open. */
    while (count_named(dir, tag, first, sizeof first) == 0) {
        if (sent > ((size_t)256 << 20))
            fail_msg("%s: no temporary file appeared in %s after %zu bytes", fmt, dir, sent);
        assert_int_equal(write(in, rows, len), (ssize_t)len);
        sent += len;
    }
    /* The child now waits on the pipe with its temporary open. */
    sleep_ms(50);
    assert_int_equal(kill(pid, sig), 0);
    /* A child that outlives the signal is a failure, not a hang. */
    for (k = 0; waitpid(pid, &st, WNOHANG) == 0; k++) {
        if (k == 6000) {
            kill(pid, SIGKILL);
            waitpid(pid, &st, 0);
            close(in);
            fail_msg("%s: signal %d (%s) did not end the child in 60 s", fmt, sig,
                     strsignal(sig));
        }
        sleep_ms(10);
    }
    close(in);
    if (!WIFSIGNALED(st) || WTERMSIG(st) != sig)
        fail_msg("%s: signal %d: the child ended with status 0x%x", fmt, sig, st);
    if (count_named(dir, tag, first, sizeof first) != 0)
        fail_msg("%s: after signal %d (%s) %s is left in %s", fmt, sig, strsignal(sig), first,
                 dir);
    if (keep) {
        char *now = ct_read(out);
        assert_string_equal(now, keep);
        free(now);
    } else {
        struct stat sb;
        assert_int_not_equal(stat(out, &sb), 0);
    }
    print_message("# %s, %s: ended by it, no %s* left, %s\n", fmt, strsignal(sig), tag,
                  keep ? "the existing file as it was" : "no file");
}

static const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGUSR1, SIGALRM, SIGXFSZ};

static void test_signals_csv(void **state)
{
    const char *design;
    char path[1024];
    size_t k;
    (void)state;
    design = ct_design("sig.json", "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
                                   "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, "
                                   "\"stop\": true},\n"
                                   "    {\"radius\": -50, \"thickness\": 45},\n"
                                   "    {\"radius\": \"inf\", \"thickness\": 0}");
    for (k = 0; k < sizeof sigs / sizeof sigs[0]; k++) {
        snprintf(path, sizeof path, "%s", ct_path("new.csv"));
        one(design, "csv", path, ".sagitta-", sigs[k], NULL);
    }
    /* An existing file keeps its bytes. */
    snprintf(path, sizeof path, "%s", ct_file("old.csv", "old table\n"));
    one(design, "csv", path, ".sagitta-", SIGTERM, "old table\n");
    one(design, "csv", path, ".sagitta-", SIGINT, "old table\n");
}

static void test_signals_hdf5(void **state)
{
    const char *design;
    char path[1024];
    (void)state;
    design = ct_design("sig5.json", "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
                                    "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, "
                                    "\"stop\": true},\n"
                                    "    {\"radius\": -50, \"thickness\": 45},\n"
                                    "    {\"radius\": \"inf\", \"thickness\": 0}");
    snprintf(path, sizeof path, "%s", ct_path("new.h5"));
    one(design, "hdf5", path, ".h5.tmp", SIGTERM, NULL);
    one(design, "hdf5", path, ".h5.tmp", SIGHUP, NULL);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_signals_csv),
        cmocka_unit_test(test_signals_hdf5),
    };
    int rc;
    ct_init(argc, argv);
    exe = argv[1];
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
