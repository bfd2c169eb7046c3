/*
 * test_recovery.c - the editor's recovery file: it holds the edited design
 * bit for bit, it is written as edits happen and removed when nothing is
 * left to recover, a file whose editor died is found (and one whose editor
 * lives is not), the recover command brings it back, and a save that fails
 * leaves both the file on disk and the document as they were.
 *
 * Independent references: strtod() of the typed text (the C library's
 * correctly rounded conversion), the operating system's own process ids
 * (fork, waitpid, waitid), stat() for modes, realpath() for names, and the
 * bytes of files read back with read().
 */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* realpath, waitid */
#endif

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#include "doc.h"
#include "ed.h"
#include "recover.h"

/* Short enough that any name built from them fits a PATH_MAX buffer. */
static char tmpdir[512];
static char recdir[600];

/* A fresh scratch directory per test, with XDG_STATE_HOME inside it, so
 * the user's own state directory is never touched. */
static int setup(void **state)
{
    char st[sizeof tmpdir + 16];
    const char *t = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%.400s/sg-rec-test-XXXXXX", t && strlen(t) < 400 ? t : "/tmp");
    if (!mkdtemp(tmpdir))
        return -1;
    snprintf(st, sizeof st, "%s/state", tmpdir);
    setenv("XDG_STATE_HOME", st, 1);
    snprintf(recdir, sizeof recdir, "%s/sagitta", st);
    return 0;
}

static void rm_tree(const char *dir)
{
    DIR *dp = opendir(dir);
    struct dirent *de;
    char p[PATH_MAX * 2];
    struct stat st;
    if (!dp)
        return;
    while ((de = readdir(dp)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode)) {
            chmod(p, 0700);
            rm_tree(p);
        } else {
            unlink(p);
        }
    }
    closedir(dp);
    rmdir(dir);
}

static int teardown(void **state)
{
    rm_tree(tmpdir);
    return 0;
}

static void make_recdir(void)
{
    char st[sizeof tmpdir + 16];
    snprintf(st, sizeof st, "%s/state", tmpdir);
    assert_int_equal(mkdir(st, 0700), 0);
    assert_int_equal(mkdir(recdir, 0700), 0);
}

static const char *tmp(const char *name, char *buf, size_t n)
{
    snprintf(buf, n, "%s/%s", tmpdir, name);
    return buf;
}

static ed *new_ed(void)
{
    ed *e = calloc(1, sizeof *e);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    /* Batch mode keeps commands from asking; the recovery file is switched
     * on as the interactive editor does it. */
    e->batch = 1;
    e->rec.enabled = 1;
    e->out = tmpfile();
    assert_non_null(e->out);
    return e;
}

static void free_ed(ed *e)
{
    fclose(e->out);
    ed_free(e);
    free(e);
}

/* What the event loop does while it waits for a key: a write delayed to
 * space writes out falls due (test_debounce tests the delay itself). */
static void idle(ed *e)
{
    rec_sync(e, 1);
}

static void ok(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void ok(ed *e, const char *fmt, ...)
{
    char line[ED_LINE];
    va_list ap;
    int f;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    f = cmd_exec(e, line);
    if (f & ED_ERROR)
        fail_msg("\"%s\" failed: %s", line, e->msg);
    idle(e);
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* The recovery files in recdir; the first name into first. */
static int count_rec(char *first, size_t n)
{
    DIR *dp = opendir(recdir);
    struct dirent *de;
    int k = 0;
    size_t sl = strlen(REC_SUFFIX);
    if (first)
        first[0] = '\0';
    if (!dp)
        return 0;
    while ((de = readdir(dp)) != NULL) {
        size_t len = strlen(de->d_name);
        if (len > sl && strcmp(de->d_name + len - sl, REC_SUFFIX) == 0) {
            if (first && k == 0)
                snprintf(first, n, "%s/%s", recdir, de->d_name);
            k++;
        }
    }
    closedir(dp);
    return k;
}

/* Every file in recdir, temporary or not. */
/* Every file but the editor's lock (REC_LOCK_SUFFIX), which says who has
 * a design open and holds no work. */
static int count_all(void)
{
    DIR *dp = opendir(recdir);
    struct dirent *de;
    size_t ll = strlen(REC_LOCK_SUFFIX);
    int k = 0;
    if (!dp)
        return 0;
    while ((de = readdir(dp)) != NULL) {
        size_t len = strlen(de->d_name);
        if (de->d_name[0] != '.' &&
            !(len > ll && strcmp(de->d_name + len - ll, REC_LOCK_SUFFIX) == 0))
            k++;
    }
    closedir(dp);
    return k;
}

static char *slurp(const char *path, size_t *len)
{
    int fd = open(path, O_RDONLY);
    struct stat st;
    char *buf;
    ssize_t k;
    assert_true(fd >= 0);
    assert_int_equal(fstat(fd, &st), 0);
    buf = malloc((size_t)st.st_size + 1);
    assert_non_null(buf);
    k = read(fd, buf, (size_t)st.st_size);
    close(fd);
    assert_int_equal(k, st.st_size);
    buf[k] = '\0';
    *len = (size_t)k;
    return buf;
}

static void copy_example(const char *name, const char *to)
{
    char src[PATH_MAX], rel[128];
    size_t len;
    char *text;
    FILE *f;
    snprintf(rel, sizeof rel, "examples/%s", name);
    text = slurp(tu_path(rel, src, sizeof src), &len);
    f = fopen(to, "w");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
    free(text);
}

/* ------------------------------------------------------------------------ */

/* The typed values, each with the exact double strtod() gives it. */
static const struct {
    int row;
    const char *col, *text;
} edits[] = {
    {3, "radius", "-3846.0000000000005"},
    {2, "conic", "-1.0000000000000002"},
    {6, "a4", "1.2345678901234567e-7"},
    {6, "a16", "-4.9406564584124654e-324"},
    {7, "thickness", "210.00000000000003"},
    {8, "semi", "12.700000000000001"},
    {9, "material", "1.5168000000000001"},
};

static void test_roundtrip(void **state)
{
    char path[PATH_MAX], real[PATH_MAX], file[PATH_MAX * 2];
    ed *e = new_ed();
    sg_system *back = sg_system_new();
    rec_info info;
    struct stat st;
    sg_diag d;
    size_t i;
    long long t0 = (long long)time(NULL), t1;

    copy_example("cassegrain.json", tmp("c.json", path, sizeof path));
    assert_non_null(realpath(path, real));
    ok(e, "open %s", path);
    assert_int_equal(count_rec(NULL, 0), 0); /* nothing to recover yet */

    for (i = 0; i < sizeof edits / sizeof edits[0]; i++)
        ok(e, "set %d %s %s", edits[i].row, edits[i].col, edits[i].text);
    ok(e, "title \"a title with \\\"quotes\\\", a tab\tand UTF-8: \xc2\xb5m\"");
    t1 = (long long)time(NULL);

    assert_int_equal(count_rec(file, sizeof file), 1);
    assert_int_equal(count_all(), 1); /* no temporary file left behind */
    assert_int_equal(stat(recdir, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0700);
    assert_int_equal(stat(file, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0600);

    sg_diag_clear(&d);
    if (rec_read_file(file, &info, back, &d) != SG_OK)
        fail_msg("read back: %s", d.msg);
    assert_string_equal(info.path, real);
    assert_int_equal(info.pid, (long)getpid());
    assert_false(info.orphan);
    assert_true(info.time >= t0 && info.time <= t1);

    for (i = 0; i < sizeof edits / sizeof edits[0]; i++) {
        const sg_surface *s = &back->surf[edits[i].row];
        double want = strtod(edits[i].text, NULL), got;
        if (strcmp(edits[i].col, "radius") == 0)
            got = s->radius;
        else if (strcmp(edits[i].col, "conic") == 0)
            got = s->conic;
        else if (strcmp(edits[i].col, "a4") == 0)
            got = s->asph[1];
        else if (strcmp(edits[i].col, "a16") == 0)
            got = s->asph[7];
        else if (strcmp(edits[i].col, "thickness") == 0)
            got = s->thickness;
        else if (strcmp(edits[i].col, "semi") == 0)
            got = s->semi_diameter;
        else
            got = s->mat.index;
        if (!same_bits(got, want))
            fail_msg("surface %d %s: %.17g read back, %.17g typed", edits[i].row, edits[i].col,
                     got, want);
    }
    assert_string_equal(back->title,
                        "a title with \"quotes\", a tab\tand UTF-8: \xc2\xb5m");
    /* And every other field as the document holds it. */
    assert_true(doc_system_equal(back, e->doc.sys));
    print_message("# recovery file %s: %zu typed doubles and the whole design read back "
                  "bit-identical; dir mode 0700, file mode 0600\n",
                  strrchr(file, '/') + 1, sizeof edits / sizeof edits[0]);
    sg_system_free(back);
    free_ed(e);
}

/* The file is current after every change once the interval has passed,
 * and never before the first change. */
static void test_debounce(void **state)
{
    char file[PATH_MAX * 2];
    ed *e = new_ed();
    sg_system *back = sg_system_new();
    rec_info info;
    sg_diag d;
    int due;
    double t0;
    assert_int_equal(cmd_exec(e, "set 1 radius 10") & ED_ERROR, 0);
    assert_int_equal(count_rec(file, sizeof file), 1); /* the first change at once */
    assert_true(e->rec.gap_ms >= 0.0 && e->rec.gap_ms <= REC_DEBOUNCE_MS);
    print_message("# first write: next one spaced by %.3f ms\n", e->rec.gap_ms);
    /* As after a slow write: the next change waits for the gap. */
    e->rec.gap_ms = REC_DEBOUNCE_MS;
    t0 = compute_now_ms();
    assert_int_equal(cmd_exec(e, "set 1 radius 20") & ED_ERROR, 0);
    due = rec_sync(e, 0);
    sg_diag_clear(&d);
    assert_int_equal(rec_read_file(file, &info, back, &d), SG_OK);
    assert_true(due > 0 && due <= (int)REC_DEBOUNCE_MS + 1);
    assert_true(same_bits(back->surf[1].radius, 10.0));
    /* The event loop sleeps until then, and the write happens. */
    while ((due = rec_sync(e, 0)) > 0)
        usleep((useconds_t)due * 1000u);
    assert_int_equal(due, -1);
    assert_int_equal(rec_read_file(file, &info, back, &d), SG_OK);
    assert_true(same_bits(back->surf[1].radius, 20.0));
    print_message("# a change made just after a slow write reached the file %.0f ms later "
                  "(the gap is at most %.0f ms)\n", compute_now_ms() - t0, REC_DEBOUNCE_MS);
    /* Untitled designs are named by the pid. */
    {
        char want[64];
        snprintf(want, sizeof want, "/untitled-%ld%s", (long)getpid(), REC_SUFFIX);
        assert_non_null(strstr(file, want));
    }
    sg_system_free(back);
    free_ed(e);
}

/* Saving, undoing back to the file, quitting or discarding leave nothing;
 * an unsaved change always leaves exactly one file. */
static void test_cleanup(void **state)
{
    char path[PATH_MAX], other[PATH_MAX];
    ed *e = new_ed();
    copy_example("cassegrain.json", tmp("c.json", path, sizeof path));
    ok(e, "open %s", path);
    ok(e, "set 3 radius -3900");
    assert_int_equal(count_rec(NULL, 0), 1);
    ok(e, "save");
    assert_int_equal(count_rec(NULL, 0), 0);
    ok(e, "set 3 radius -3800");
    assert_int_equal(count_rec(NULL, 0), 1);
    ok(e, "undo");
    assert_false(doc_modified(&e->doc));
    assert_int_equal(count_rec(NULL, 0), 0);
    ok(e, "redo");
    assert_int_equal(count_rec(NULL, 0), 1);
    /* Save as another name: the copy for the old name goes. */
    ok(e, "save %s", tmp("other.json", other, sizeof other));
    assert_int_equal(count_rec(NULL, 0), 0);
    ok(e, "set 3 radius -3700");
    assert_int_equal(count_rec(NULL, 0), 1);
    ok(e, "open! %s", path);
    assert_int_equal(count_rec(NULL, 0), 0);
    ok(e, "set 3 radius -3600");
    assert_int_equal(count_rec(NULL, 0), 1);
    /* quit! is a clean end: the edits were thrown away on purpose. */
    assert_true(cmd_exec(e, "quit!") & ED_QUIT);
    assert_int_equal(count_rec(NULL, 0), 0);
    assert_int_equal(count_all(), 0);
    /* Nothing is written after the end. */
    ok(e, "set 3 radius -3500");
    assert_int_equal(count_rec(NULL, 0), 0);
    free_ed(e);

    e = new_ed();
    ok(e, "open %s", path);
    ok(e, "set 3 radius -3400");
    assert_int_equal(count_rec(NULL, 0), 1);
    assert_true(cmd_exec(e, "wq") & ED_QUIT);
    assert_int_equal(count_rec(NULL, 0), 0);
    free_ed(e);

    /* Batch mode writes none at all. */
    e = new_ed();
    e->rec.enabled = 0;
    ok(e, "set 1 radius 5");
    assert_int_equal(count_rec(NULL, 0), 0);
    free_ed(e);
    print_message("# save, undo to the saved state, save as, open!, quit! and wq each left 0 "
                  "recovery files; unsaved changes left 1\n");
}

/* A recovery file written by a child process that then exits. */
static pid_t child_writes(const char *file, const char *abspath, const sg_system *sys,
                          const doc_stamp *disk, int reap)
{
    pid_t pid;
    int st;
    fflush(NULL);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0)
        _exit(rec_write_file(file, abspath, sys, disk, NULL) == SG_OK ? 0 : 1);
    if (reap) {
        assert_int_equal(waitpid(pid, &st, 0), pid);
        assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    }
    return pid;
}

/* Rewrites the header field "key":old of file to "key":new. */
static void patch(const char *file, const char *from, const char *to)
{
    size_t len;
    char *text = slurp(file, &len), *p = strstr(text, from), *out;
    FILE *f;
    assert_non_null(p);
    out = malloc(len + strlen(to) + 1);
    assert_non_null(out);
    memcpy(out, text, (size_t)(p - text));
    strcpy(out + (p - text), to);
    strcat(out, p + strlen(from));
    f = fopen(file, "w");
    assert_non_null(f);
    fputs(out, f);
    fclose(f);
    free(out);
    free(text);
}

static void test_orphans(void **state)
{
    char dead[PATH_MAX], live[PATH_MAX], reused[PATH_MAX], other[PATH_MAX], junk[PATH_MAX];
    char zombie[PATH_MAX], older[PATH_MAX], target[PATH_MAX], abs[PATH_MAX], buf[64];
    sg_system *sys = sg_system_new();
    rec_info *v;
    pid_t dpid, zpid;
    siginfo_t si;
    int n, i, found;
    struct stat st;
    FILE *f;

    make_recdir();
    tmp("design.json", target, sizeof target);
    assert_int_equal(rec_abspath(target, abs, sizeof abs), 0);

    /* A writer that exited and was reaped: its pid no longer exists. */
    snprintf(dead, sizeof dead, "%s/dead%s", recdir, REC_SUFFIX);
    dpid = child_writes(dead, abs, sys, NULL, 1);
    assert_int_equal(kill(dpid, 0), -1);
    assert_int_equal(errno, ESRCH);
    /* This process: alive. */
    snprintf(live, sizeof live, "%s/live%s", recdir, REC_SUFFIX);
    assert_int_equal(rec_write_file(live, abs, sys, NULL, NULL), SG_OK);
    /* Our pid but another start time: a pid used again after a crash. */
    snprintf(reused, sizeof reused, "%s/reused%s", recdir, REC_SUFFIX);
    assert_int_equal(rec_write_file(reused, abs, sys, NULL, NULL), SG_OK);
    /* Another machine: its process cannot be checked, so it counts as alive. */
    snprintf(other, sizeof other, "%s/otherhost%s", recdir, REC_SUFFIX);
    assert_int_equal(rec_write_file(other, abs, sys, NULL, NULL), SG_OK);
    patch(other, "\"host\":\"", "\"host\":\"another-host-");
    /* Not a recovery file at all. */
    snprintf(junk, sizeof junk, "%s/junk%s", recdir, REC_SUFFIX);
    f = fopen(junk, "w");
    assert_non_null(f);
    fputs("{\"sagitta_recovery\": 2}\nnot json\n", f);
    fclose(f);

    if (stat("/proc/self/stat", &st) == 0) {
        char from[64];
        rec_info me;
        assert_int_equal(rec_read_file(reused, &me, NULL, NULL), SG_OK);
        assert_true(me.start > 0);
        snprintf(from, sizeof from, "\"start\":\"%llu\"", me.start);
        snprintf(buf, sizeof buf, "\"start\":\"%llu\"", me.start + 1);
        patch(reused, from, buf);
    } else {
        unlink(reused);
        print_message("# no /proc: the pid-reuse case is not tried\n");
    }

    n = rec_orphans(recdir, abs, NULL, &v);
    assert_true(n >= 1);
    /* The list is newest first, and the reused file may be a second newer
     * than the dead writer's or of the same second: either order. */
    for (i = 0, found = 0; i < n; i++)
        found += v[i].pid == (long)dpid;
    assert_int_equal(found, 1);
    for (i = 0; i < n; i++) {
        assert_true(v[i].orphan);
        assert_true(strcmp(v[i].file, live) != 0 && strcmp(v[i].file, other) != 0 &&
                    strcmp(v[i].file, junk) != 0);
    }
    assert_int_equal(n, stat("/proc/self/stat", &st) == 0 ? 2 : 1);
    print_message("# dead writer pid %ld found; live, other-host and junk files skipped; "
                  "%d orphans\n", (long)dpid, n);
    free(v);

    /* Another design's orphan is not offered for this one, only in the
     * list of all. */
    n = rec_orphans(recdir, "/no/such/design.json", NULL, &v);
    assert_int_equal(n, 0);
    free(v);
    n = rec_orphans(recdir, NULL, NULL, &v);
    assert_int_equal(n, stat("/proc/self/stat", &st) == 0 ? 2 : 1);
    free(v);

    /* A writer that has exited but is not yet reaped (a zombie). */
    snprintf(zombie, sizeof zombie, "%s/zombie%s", recdir, REC_SUFFIX);
    zpid = child_writes(zombie, abs, sys, NULL, 0);
    memset(&si, 0, sizeof si);
    assert_int_equal(waitid(P_PID, (id_t)zpid, &si, WEXITED | WNOWAIT), 0);
    assert_int_equal(kill(zpid, 0), 0); /* the pid still exists */
    {
        rec_info z;
        assert_int_equal(rec_read_file(zombie, &z, NULL, NULL), SG_OK);
        if (stat("/proc/self/stat", &st) == 0)
            assert_true(z.orphan);
        print_message("# zombie writer pid %ld: orphan %d\n", (long)zpid, z.orphan);
    }
    waitpid(zpid, NULL, 0);

    /* Newest first: a file from long ago comes after the one just made. */
    unlink(zombie);
    unlink(reused);
    snprintf(older, sizeof older, "%s/older%s", recdir, REC_SUFFIX);
    child_writes(older, abs, sys, NULL, 1);
    patch(older, "\"time\":", "\"time\":-");
    n = rec_orphans(recdir, abs, NULL, &v);
    assert_int_equal(n, 2);
    assert_true(v[0].time > v[1].time);
    assert_int_equal(v[0].pid, (long)dpid);
    free(v);

    /* A temporary file left by a writer killed mid-write goes once it is
     * old; a fresh one (a live writer's) stays. */
    {
        char oldtmp[PATH_MAX], newtmp[PATH_MAX];
        struct timespec ts[2];
        snprintf(oldtmp, sizeof oldtmp, "%s/x%s.tmpAbC123", recdir, REC_SUFFIX);
        snprintf(newtmp, sizeof newtmp, "%s/y%s.tmpXyZ789", recdir, REC_SUFFIX);
        FILE *f1 = fopen(oldtmp, "w"), *f2 = fopen(newtmp, "w");
        assert_non_null(f1);
        assert_non_null(f2);
        fclose(f1);
        fclose(f2);
        ts[0].tv_sec = ts[1].tv_sec = time(NULL) - 3600;
        ts[0].tv_nsec = ts[1].tv_nsec = 0;
        assert_int_equal(utimensat(AT_FDCWD, oldtmp, ts, 0), 0);
        rec_sweep_temps(recdir);
        assert_int_equal(access(oldtmp, F_OK), -1);
        assert_int_equal(access(newtmp, F_OK), 0);
        assert_int_equal(access(dead, F_OK), 0);
    }
    sg_system_free(sys);
}

/* :recover lists and loads an orphan; the loaded design keeps its file
 * name, counts as modified, and save writes it there. */
static void test_recover_command(void **state)
{
    char path[PATH_MAX], abs[PATH_MAX], file[PATH_MAX * 2], line[PATH_MAX * 3];
    ed *e = new_ed();
    sg_system *want, *disk = sg_system_new();
    doc_stamp read;
    sg_diag d;
    pid_t pid;
    int k;

    copy_example("cassegrain.json", tmp("c.json", path, sizeof path));
    assert_int_equal(rec_abspath(path, abs, sizeof abs), 0);
    make_recdir();
    snprintf(file, sizeof file, "%s/c-crashed%s", recdir, REC_SUFFIX);
    /* The crashed editor's design: the file with one radius changed. */
    want = sg_system_new();
    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(want, path, &d), SG_OK);
    want->surf[3].radius = strtod("-3900.0000000000005", NULL);
    /* It had read the file as it is on disk. */
    assert_int_equal(doc_stamp_file(path, &read), 0);
    pid = child_writes(file, abs, want, &read, 1);

    ok(e, "open %s", path);
    ok(e, "recover list");
    rewind(e->out);
    assert_non_null(fgets(line, sizeof line, e->out));
    print_message("# recover list: %s", line);
    assert_non_null(strstr(line, file));
    assert_non_null(strstr(line, abs));
    assert_int_equal(strncmp(line, "1  ", 3), 0);

    assert_true(cmd_exec(e, "recover 2") & ED_ERROR);
    ok(e, "recover 1");
    assert_true(doc_system_equal(e->doc.sys, want));
    assert_true(doc_modified(&e->doc));
    assert_string_equal(doc_path(&e->doc), abs);
    /* Our own copy took over; the orphan is gone. */
    assert_int_equal(count_rec(line, sizeof line), 1);
    assert_true(strcmp(line, file) != 0);
    assert_int_equal(access(file, F_OK), -1);
    assert_true(cmd_exec(e, "undo") & ED_ERROR); /* no history to undo into */
    ok(e, "save");
    assert_int_equal(count_rec(NULL, 0), 0);
    assert_int_equal(sg_design_load(disk, path, &d), SG_OK);
    assert_true(doc_system_equal(disk, want));
    assert_true(same_bits(disk->surf[3].radius, strtod("-3900.0000000000005", NULL)));
    print_message("# pid %ld's recovery file loaded and saved to %s: radius 3 = %.17g\n",
                  (long)pid, path, disk->surf[3].radius);
    free_ed(e);

    /* Without a recovery file of our own (batch), the orphan stays until
     * the design is saved; delete removes one; a live editor's file is
     * refused. */
    assert_int_equal(doc_stamp_file(path, &read), 0);
    pid = child_writes(file, abs, want, &read, 1);
    e = new_ed();
    e->rec.enabled = 0;
    ok(e, "recover %s", file);
    assert_int_equal(access(file, F_OK), 0);
    ok(e, "save");
    assert_int_equal(access(file, F_OK), -1);
    child_writes(file, abs, want, &read, 1);
    ok(e, "recover delete 1");
    assert_int_equal(access(file, F_OK), -1);
    /* A file this (live) process wrote is no orphan. */
    assert_int_equal(rec_write_file(file, abs, want, NULL, NULL), SG_OK);
    k = cmd_exec(e, "recover 1");
    assert_true(k & ED_ERROR);
    snprintf(line, sizeof line, "recover %s", file);
    assert_true(cmd_exec(e, line) & ED_ERROR);
    assert_non_null(strstr(e->msg, "still running"));
    free_ed(e);
    sg_system_free(want);
    sg_system_free(disk);
}

/* Issue 30, item 3: a recovered design carries the stamp of the file its
 * crashed editor had read, so a change another program made on disk after
 * the crash is not overwritten unasked: save in batch mode refuses naming
 * save!, the editor asks.  A recovery file without a stamp (written before
 * sagitta kept one) counts the file as unknown: save asks too. */
static void test_recover_disk_changed(void **state)
{
    char path[PATH_MAX], abs[PATH_MAX], file[PATH_MAX * 2];
    char *now, *after;
    size_t n, na;
    doc_stamp read;
    rec_info info;
    sg_system *want = sg_system_new(), *back = sg_system_new();
    sg_diag d;
    ed *e;
    FILE *f;
    int flags;

    copy_example("cassegrain.json", tmp("c.json", path, sizeof path));
    assert_int_equal(rec_abspath(path, abs, sizeof abs), 0);
    make_recdir();
    snprintf(file, sizeof file, "%s/c-crashed%s", recdir, REC_SUFFIX);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(want, path, &d), SG_OK);
    want->surf[3].radius = -3900.0;
    assert_int_equal(doc_stamp_file(path, &read), 0);
    /* An editor's own recovery file records the file it read. */
    e = new_ed();
    ok(e, "open %s", path);
    ok(e, "set 3 radius -3900");
    assert_true(e->rec.file[0] != '\0');
    assert_int_equal(rec_read_file(e->rec.file, &info, NULL, &d), SG_OK);
    assert_true(info.disk.have && info.disk.hash == read.hash && info.disk.ino == read.ino);
    ok(e, "quit!");
    free_ed(e);
    child_writes(file, abs, want, &read, 1);
    /* The header holds the stamp as stat() and the bytes gave it. */
    assert_int_equal(rec_read_file(file, &info, NULL, &d), SG_OK);
    assert_true(info.disk.have);
    assert_true(info.disk.dev == read.dev && info.disk.ino == read.ino &&
                info.disk.size == read.size && info.disk.hash == read.hash &&
                info.disk.mtime_s == read.mtime_s && info.disk.mtime_ns == read.mtime_ns);

    /* After the crash another program changes the file. */
    f = fopen(path, "a");
    assert_non_null(f);
    fputs("\n", f);
    assert_int_equal(fclose(f), 0);
    now = slurp(path, &n);

    e = new_ed();
    e->rec.enabled = 0;
    ok(e, "recover %s", file);
    assert_true(doc_system_equal(e->doc.sys, want));
    flags = cmd_exec(e, "save");
    assert_true(flags & ED_ERROR);
    assert_non_null(strstr(e->msg, "changed on disk"));
    assert_non_null(strstr(e->msg, "save!"));
    print_message("# batch: %s\n", e->msg);
    after = slurp(path, &na);
    assert_true(na == n && memcmp(after, now, n) == 0);
    free(after);
    /* The editor asks; yes runs save!. */
    e->batch = 0;
    flags = cmd_exec(e, "save");
    assert_true(flags & ED_CONFIRM);
    assert_int_equal(strncmp(e->pending, "save! ", 6), 0);
    print_message("# editor: %s\n", e->question);
    e->confirm = CONFIRM_NONE;
    e->batch = 1;
    after = slurp(path, &na);
    assert_true(na == n && memcmp(after, now, n) == 0);
    free(after);
    ok(e, "save!");
    assert_int_equal(sg_design_load(back, path, &d), SG_OK);
    assert_true(doc_system_equal(back, want));
    free_ed(e);

    /* No stamp in the header: the file's state is unknown. */
    child_writes(file, abs, want, NULL, 1);
    assert_int_equal(rec_read_file(file, &info, NULL, &d), SG_OK);
    assert_false(info.disk.have);
    e = new_ed();
    e->rec.enabled = 0;
    ok(e, "recover %s", file);
    flags = cmd_exec(e, "save");
    assert_true(flags & ED_ERROR);
    assert_non_null(strstr(e->msg, "already exists"));
    print_message("# no stamp: %s\n", e->msg);
    free_ed(e);
    free(now);
    sg_system_free(want);
    sg_system_free(back);
}

/* A save that fails leaves the old file whole and the document modified,
 * its recovery file in place, and says why on the status line. */
static void test_save_failure(void **state)
{
    char path[PATH_MAX], bad[PATH_MAX], ro[sizeof tmpdir + 8];
    char *before, *after;
    size_t nb, na;
    ed *e = new_ed();
    int i, tried = 0;
    const char *cases[3];

    copy_example("cassegrain.json", tmp("c.json", path, sizeof path));
    before = slurp(path, &nb);
    ok(e, "open %s", path);
    ok(e, "set 3 radius -3900");

    /* A name that is a directory; a directory that does not exist; a
     * "directory" that is the regular file itself. */
    assert_int_equal(mkdir(tmp("adir", bad, sizeof bad), 0700), 0);
    cases[0] = "adir";
    cases[1] = "nodir/x.json";
    cases[2] = "c.json/x.json";
    for (i = 0; i < 3; i++) {
        char line[PATH_MAX * 3];
        snprintf(line, sizeof line, "save %s/%s", tmpdir, cases[i]);
        assert_true(cmd_exec(e, line) & ED_ERROR);
        assert_true(e->msg_err);
        assert_non_null(strstr(e->msg, "not saved"));
        print_message("# save %s: %s\n", cases[i], e->msg);
        tried++;
    }
    /* A directory without write permission.  Root's writes ignore the
     * mode, so as root (CI) the saves run with nobody's filesystem ids on
     * directories nobody owns (tu_unpriv_begin). */
    snprintf(ro, sizeof ro, "%s/ro", tmpdir);
    assert_int_equal(mkdir(ro, 0500), 0);
    if (geteuid() == 0) {
        assert_int_equal(chown(ro, TU_NOBODY, TU_NOBODY), 0);
        assert_int_equal(chmod(tmpdir, 0711), 0);
    }
    {
        char line[PATH_MAX * 3];
        int r, unpriv;
        snprintf(line, sizeof line, "save %s/x.json", ro);
        unpriv = tu_unpriv_begin();
        r = cmd_exec(e, line);
        tu_unpriv_end();
        assert_true(r & ED_ERROR);
        assert_non_null(strstr(e->msg, "not saved"));
        print_message("# save into read-only %s%s: %s\n", ro,
                      unpriv ? " (as root, with nobody's filesystem ids)" : "", e->msg);
        tried++;
    }
    /* The same file, with its directory made read-only. */
    {
        int r;
        if (geteuid() == 0)
            assert_int_equal(chown(tmpdir, TU_NOBODY, TU_NOBODY), 0);
        assert_int_equal(chmod(tmpdir, 0500), 0);
        tu_unpriv_begin();
        r = cmd_exec(e, "save");
        tu_unpriv_end();
        assert_int_equal(chmod(tmpdir, 0700), 0);
        if (geteuid() == 0)
            assert_int_equal(chown(tmpdir, 0, 0), 0);
        assert_true(r & ED_ERROR);
        assert_non_null(strstr(e->msg, "not saved"));
        print_message("# save with %s read-only: %s\n", tmpdir, e->msg);
        tried++;
    }
    after = slurp(path, &na);
    assert_int_equal(na, nb);
    assert_memory_equal(before, after, nb);
    assert_true(doc_modified(&e->doc));
    assert_true(same_bits(e->doc.sys->surf[3].radius, -3900.0));
    assert_string_equal(doc_path(&e->doc), path);
    assert_int_equal(count_rec(NULL, 0), 1);
    {
        DIR *dp = opendir(tmpdir);
        struct dirent *de;
        while ((de = readdir(dp)) != NULL)
            if (strncmp(de->d_name, "adir.", 5) == 0 || strncmp(de->d_name, "c.json.", 7) == 0)
                fail_msg("temporary file %s left behind", de->d_name);
        closedir(dp);
    }
    /* And the save that then works. */
    ok(e, "save");
    assert_false(doc_modified(&e->doc));
    assert_int_equal(count_rec(NULL, 0), 0);
    print_message("# %d failing saves: %s unchanged (%zu bytes), document still modified\n",
                  tried, path, nb);
    free(before);
    free(after);
    free_ed(e);
}

/* When the recovery file cannot be written the editor says so once, and
 * goes on editing. */
static void test_write_failure(void **state)
{
    char st[sizeof tmpdir + 16], blocker[PATH_MAX];
    ed *e = new_ed();
    FILE *f = fopen(tmp("blocker", blocker, sizeof blocker), "w");
    assert_non_null(f);
    fclose(f);
    /* The state "directory" is a regular file. */
    snprintf(st, sizeof st, "%s/blocker", tmpdir);
    setenv("XDG_STATE_HOME", st, 1);
    cmd_exec(e, "set 1 radius 10");
    assert_true(e->msg_err);
    assert_non_null(strstr(e->msg, "recovery file"));
    print_message("# %s\n", e->msg);
    cmd_exec(e, "set 1 radius 20");
    assert_false(e->msg_err); /* reported once, not at every change */
    assert_true(same_bits(e->doc.sys->surf[1].radius, 20.0));
    /* A relative XDG_STATE_HOME is ignored, as the XDG rules say. */
    setenv("XDG_STATE_HOME", "relative/state", 1);
    if (getenv("HOME") && getenv("HOME")[0] == '/') {
        char dir[PATH_MAX], want[PATH_MAX];
        assert_int_equal(rec_dir(dir, sizeof dir), 0);
        snprintf(want, sizeof want, "%s/.local/state/sagitta", getenv("HOME"));
        assert_string_equal(dir, want);
    }
    free_ed(e);
}

/* A file that does not exist yet still has one absolute name. */
static void test_abspath(void **state)
{
    char a[PATH_MAX], b[PATH_MAX], real[PATH_MAX], cwd[PATH_MAX], want[PATH_MAX + 16];
    assert_non_null(realpath(tmpdir, real));
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(tmpdir), 0);
    assert_int_equal(rec_abspath("new.json", a, sizeof a), 0);
    assert_int_equal(rec_abspath("./new.json", b, sizeof b), 0);
    assert_int_equal(chdir(cwd), 0);
    snprintf(want, sizeof want, "%s/new.json", real);
    assert_string_equal(a, want);
    assert_string_equal(b, want);
    print_message("# new.json -> %s\n", a);
}

/* A second editor (a child process) with the design open holds a lock
 * that names it: rec_holders() sees it while the child lives, and once the
 * child is killed the lock counts for nothing and goes.  Quitting removes
 * one's own lock. */
static void test_holders(void **state)
{
    char path[PATH_MAX], abs[PATH_MAX];
    int p2c[2], c2p[2];
    rec_info first;
    pid_t child;
    char c = 0;
    ed *e;
    (void)state;
    tmp("held.json", path, sizeof path);
    e = new_ed();
    ok(e, "save %s", path);
    rec_finish(e);
    free_ed(e);
    assert_int_equal(rec_abspath(path, abs, sizeof abs), 0);
    assert_int_equal(rec_holders(recdir, abs, NULL), 0);
    assert_int_equal(pipe(p2c), 0);
    assert_int_equal(pipe(c2p), 0);
    child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        /* The other editor: opens the file, as the screen does, then waits. */
        ed *o = new_ed();
        {
            char line[PATH_MAX + 8];
            snprintf(line, sizeof line, "open %s", path);
            cmd_exec(o, line);
        }
        rec_sync(o, 1);
        if (write(c2p[1], "r", 1) != 1)
            _exit(2);
        if (read(p2c[0], &c, 1) != 1)
            _exit(2);
        rec_finish(o);
        _exit(0);
    }
    assert_int_equal(read(c2p[0], &c, 1), 1);
    assert_int_equal(rec_holders(recdir, abs, &first), 1);
    assert_int_equal(first.pid, (long)child);
    assert_string_equal(first.path, abs);
    /* This process's own lock never counts. */
    e = new_ed();
    ok(e, "open %s", path);
    idle(e);
    assert_int_equal(rec_holders(recdir, abs, NULL), 1);
    /* The child quits cleanly: its lock goes with it. */
    assert_int_equal(write(p2c[1], "q", 1), 1);
    assert_int_equal(waitpid(child, NULL, 0), child);
    assert_int_equal(rec_holders(recdir, abs, NULL), 0);
    rec_finish(e);
    free_ed(e);
    {
        /* Killed: the lock stays on disk but is a dead editor's. */
        DIR *dp;
        struct dirent *de;
        int locks = 0;
        child = fork();
        assert_true(child >= 0);
        if (child == 0) {
            ed *o = new_ed();
            char line[PATH_MAX + 8];
            snprintf(line, sizeof line, "open %s", path);
            cmd_exec(o, line);
            rec_sync(o, 1);
            if (write(c2p[1], "r", 1) != 1)
                _exit(2);
            for (;;)
                pause();
        }
        assert_int_equal(read(c2p[0], &c, 1), 1);
        assert_int_equal(rec_holders(recdir, abs, NULL), 1);
        kill(child, SIGKILL);
        assert_int_equal(waitpid(child, NULL, 0), child);
        assert_int_equal(rec_holders(recdir, abs, NULL), 0);
        dp = opendir(recdir);
        assert_non_null(dp);
        while ((de = readdir(dp)) != NULL)
            if (strstr(de->d_name, REC_LOCK_SUFFIX))
                locks++;
        closedir(dp);
        assert_int_equal(locks, 0);
    }
    close(p2c[0]);
    close(p2c[1]);
    close(c2p[0]);
    close(c2p[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_abspath, setup, teardown),
        cmocka_unit_test_setup_teardown(test_roundtrip, setup, teardown),
        cmocka_unit_test_setup_teardown(test_debounce, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cleanup, setup, teardown),
        cmocka_unit_test_setup_teardown(test_orphans, setup, teardown),
        cmocka_unit_test_setup_teardown(test_recover_command, setup, teardown),
        cmocka_unit_test_setup_teardown(test_recover_disk_changed, setup, teardown),
        cmocka_unit_test_setup_teardown(test_save_failure, setup, teardown),
        cmocka_unit_test_setup_teardown(test_write_failure, setup, teardown),
        cmocka_unit_test_setup_teardown(test_holders, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
