/*
 * test_files.c - the editor never loses or overwrites work, and its
 * wavelength and field commands do what a Zemax user expects; all through
 * the command path (cmd_exec, batch mode) without a screen.
 *
 * Independent references: the bytes written by another "program" (this
 * test, with plain stdio), stat() of the files, the spectral lines of
 * Schott's TIE-29 / ISO 7944 (F 0.4861327, d 0.5875618, C 0.6562725 um),
 * and Zemax's field normalization written out here as a closed form
 * (Hx = x / max|field|, with sqrt(6^2 + 6.5^2) = sqrt(78.25) exact in IEEE
 * arithmetic).
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"

#include "doc.h"
#include "ed.h"

static char tmpdir[256];

static const char *tmp_path(const char *name, char *buf, size_t n)
{
    if (!tmpdir[0]) {
        snprintf(tmpdir, sizeof tmpdir, "%s/sg-files-test-XXXXXX",
                 getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
        assert_non_null(mkdtemp(tmpdir));
    }
    snprintf(buf, n, "%s/%s", tmpdir, name);
    return buf;
}

static ed *new_ed(void)
{
    ed *e = calloc(1, sizeof *e);
    assert_non_null(e);
    assert_int_equal(ed_init(e), SG_OK);
    e->batch = 1;
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

static int run(ed *e, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int run(ed *e, const char *fmt, ...)
{
    char line[ED_LINE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    return cmd_exec(e, line);
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
}

static void put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(fputs(text, f) >= 0, 1);
    assert_int_equal(fclose(f), 0);
}

static char *get_file(const char *path)
{
    FILE *f = fopen(path, "r");
    char *buf = calloc(1, 1 << 20);
    assert_non_null(f);
    assert_non_null(buf);
    fread(buf, 1, (1 << 20) - 1, f);
    fclose(f);
    return buf;
}

/* Save-as onto an unrelated file that exists asks (in batch: refuses,
 * naming save!) and leaves it alone; save! replaces it. */
static void test_saveas_existing(void **state)
{
    char other[512];
    ed *e = new_ed();
    char *back;
    int f;
    (void)state;
    tmp_path("other.txt", other, sizeof other);
    put_file(other, "someone else's notes\n");
    ok(e, "set 1 radius 50");
    f = run(e, "save %s", other);
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "already exists"));
    assert_non_null(strstr(e->msg, "save!"));
    back = get_file(other);
    assert_string_equal(back, "someone else's notes\n");
    free(back);
    assert_true(doc_modified(&e->doc));
    /* wq is save too. */
    f = run(e, "wq %s", other);
    assert_true(f & ED_ERROR);
    assert_false(f & ED_QUIT);
    ok(e, "save! %s", other);
    assert_false(doc_modified(&e->doc));
    back = get_file(other);
    assert_non_null(strstr(back, "sagitta-design"));
    free(back);
    /* Saving again to its own file asks nothing. */
    ok(e, "set 1 radius 60");
    ok(e, "save %s", other);
    /* A new design named after a file that exists does not replace it
     * unasked either. */
    put_file(other, "notes again\n");
    ok(e, "new! %s", other);
    ok(e, "set 1 radius 70");
    f = run(e, "save");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "already exists"));
    back = get_file(other);
    assert_string_equal(back, "notes again\n");
    free(back);
    free_ed(e);
}

/* Another program rewrites the file after it was loaded: save refuses
 * until save!.  Touching it (new mtime, same bytes) is no change. */
/* The editor opens a Zemax file (UTF-16, no TYPE lines, from
 * tests/data/zmx) and saves a name ending in .zmx as a lens file, which
 * opens again to the same design (issue 17), in the file's encoding
 * (issue 30). */
static void test_open_zmx(void **state)
{
    char src[1024], out[512];
    char *j1, *j2, *back;
    ed *e = new_ed();
    (void)state;
    tu_path("tests/data/zmx/zmax_55278.zmx", src, sizeof src);
    ok(e, "open %s", src);
    assert_int_equal(e->doc.sys->nsurf, 8);
    assert_string_equal(e->doc.sys->surf[1].mat.name, "SF5");
    j1 = sg_design_to_json(e->doc.sys);
    tmp_path("copy.zmx", out, sizeof out);
    ok(e, "saveas %s", out);
    back = get_file(out);
    /* Written losslessly: the file's own encoding, UTF-16LE with its mark. */
    assert_true((unsigned char)back[0] == 0xFF && (unsigned char)back[1] == 0xFE);
    free(back);
    ok(e, "open! %s", out);
    j2 = sg_design_to_json(e->doc.sys);
    assert_string_equal(j1, j2);
    free(j1);
    free(j2);
    unlink(out);
    free_ed(e);
}

static void test_changed_on_disk(void **state)
{
    char a[512];
    ed *e = new_ed(), *other = new_ed();
    struct timespec ts[2];
    char *back;
    int f;
    (void)state;
    tmp_path("a.json", a, sizeof a);
    unlink(a);
    ok(e, "save %s", a);
    ok(e, "open %s", a);
    ok(e, "set 1 radius 50");

    /* A touch alone. */
    clock_gettime(CLOCK_REALTIME, &ts[0]);
    ts[0].tv_sec += 100;
    ts[1] = ts[0];
    assert_int_equal(utimensat(AT_FDCWD, a, ts, 0), 0);
    ok(e, "save");

    /* A second editor saves its own change. */
    ok(other, "open %s", a);
    ok(other, "title written by the other editor");
    ok(other, "save");
    ok(e, "set 1 radius 70");
    f = run(e, "save");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "changed on disk"));
    back = get_file(a);
    assert_non_null(strstr(back, "written by the other editor"));
    free(back);
    ok(e, "save!");
    back = get_file(a);
    assert_null(strstr(back, "written by the other editor"));
    free(back);
    free_ed(other);
    free_ed(e);
}

/* A read-only file is refused with a message, by save and save! alike, and
 * stays as it was. */
static void test_readonly(void **state)
{
    char a[512];
    ed *e = new_ed();
    char *before, *after;
    int f;
    (void)state;
    tmp_path("ro.json", a, sizeof a);
    unlink(a);
    ok(e, "save %s", a);
    assert_int_equal(chmod(a, 0444), 0);
    before = get_file(a);
    ok(e, "set 1 radius 50");
    f = run(e, "save");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "read-only"));
    f = run(e, "save!");
    assert_true(f & ED_ERROR);
    assert_non_null(strstr(e->msg, "read-only"));
    after = get_file(a);
    assert_string_equal(before, after);
    assert_true(doc_modified(&e->doc));
    free(before);
    free(after);
    chmod(a, 0644);
    free_ed(e);
}

/* A file with two hard links is saved in place: both names see the new
 * design, the inode and the link count stay, and no backup is left. */
static void test_hard_link(void **state)
{
    char a[512], b[512];
    ed *e = new_ed();
    struct stat sa0, sa, sb;
    char *ta, *tb;
    (void)state;
    tmp_path("linked.json", a, sizeof a);
    tmp_path("link2.json", b, sizeof b);
    unlink(a);
    ok(e, "save %s", a);
    unlink(b);
    assert_int_equal(link(a, b), 0);
    assert_int_equal(stat(a, &sa0), 0);
    ok(e, "title saved through a hard link");
    ok(e, "save");
    assert_int_equal(stat(a, &sa), 0);
    assert_int_equal(stat(b, &sb), 0);
    assert_true(sa.st_ino == sa0.st_ino);
    assert_true(sb.st_ino == sa.st_ino);
    assert_int_equal((int)sa.st_nlink, 2);
    ta = get_file(a);
    tb = get_file(b);
    assert_non_null(strstr(tb, "saved through a hard link"));
    assert_string_equal(ta, tb);
    free(ta);
    free(tb);
    {
        /* No backup or temporary file stays beside it. */
        char cmdline[700];
        snprintf(cmdline, sizeof cmdline, "ls -A '%s' | grep -q '^\\.sagitta'", tmpdir);
        assert_int_not_equal(system(cmdline), 0);
    }
    free_ed(e);
}

/* A .zmx file with two hard links is saved in place as a lens file, not
 * as JSON: both names see the edit, and every other line of the file is
 * as Zemax wrote it (issue 30, item 1: the editor's hard-link path wrote
 * JSON under the .zmx name). */
static void test_hard_link_zmx(void **state)
{
    char src[1024], a[512], b[512];
    ed *e = new_ed();
    struct stat sa0, sa;
    char *orig, *ta, *tb;
    size_t i, la, lo, diff = 0;
    (void)state;
    tu_path("tests/data/zmx/lens1.zmx", src, sizeof src);
    tmp_path("linked.zmx", a, sizeof a);
    tmp_path("link2.zmx", b, sizeof b);
    unlink(a);
    unlink(b);
    orig = get_file(src);
    {
        FILE *f = fopen(a, "wb");
        assert_non_null(f);
        lo = strlen(orig);
        assert_int_equal(fwrite(orig, 1, lo, f), lo);
        fclose(f);
    }
    assert_int_equal(link(a, b), 0);
    assert_int_equal(stat(a, &sa0), 0);
    ok(e, "open %s", a);
    ok(e, "set 1 thickness 7.25");
    ok(e, "save");
    assert_int_equal(stat(a, &sa), 0);
    assert_true(sa.st_ino == sa0.st_ino);
    assert_int_equal((int)sa.st_nlink, 2);
    ta = get_file(a);
    tb = get_file(b);
    assert_string_equal(ta, tb);
    assert_true(ta[0] != '{');
    /* Every line but the edited thickness's is the file's own. */
    la = strlen(ta);
    for (i = 0; i < la && i < lo; i++)
        if (ta[i] != orig[i]) {
            diff = i;
            break;
        }
    assert_true(diff > 0);
    assert_non_null(strstr(ta + (diff > 40 ? diff - 40 : 0), "DISZ 7.25"));
    assert_string_equal(strchr(ta + diff, '\n'), strchr(orig + diff, '\n'));
    free(orig);
    free(ta);
    free(tb);
    unlink(a);
    unlink(b);
    free_ed(e);
}

/* Runs ed_batch on script with stderr captured into err. */
static int batch_capture(const char *script, char *err, size_t n)
{
    char log[512];
    ed *e = new_ed();
    int saved, fd, rc;
    FILE *f;
    size_t got;
    tmp_path("stderr.txt", log, sizeof log);
    fflush(stderr);
    saved = dup(2);
    fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    assert_true(saved >= 0 && fd >= 0);
    dup2(fd, 2);
    close(fd);
    rc = ed_batch(e, script);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    free_ed(e);
    f = fopen(log, "r");
    assert_non_null(f);
    got = fread(err, 1, n - 1, f);
    err[got] = '\0';
    fclose(f);
    return rc;
}

static long max_rss_kb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

/* /dev/zero, a line longer than any command and a NUL byte end the script
 * with status 1 and a message naming the file and line, in bounded
 * memory. */
static void test_batch_bounds(void **state)
{
    char script[512], err[4096];
    long rss0 = max_rss_kb();
    FILE *f;
    int i;
    (void)state;
    assert_int_equal(batch_capture("/dev/zero", err, sizeof err), 1);
    assert_non_null(strstr(err, "/dev/zero:1:"));
    print_message("# /dev/zero: %s", err);
    tmp_path("long.cmd", script, sizeof script);
    f = fopen(script, "w");
    assert_non_null(f);
    fputs("title short\n", f);
    for (i = 0; i < 100000; i++)
        fputc('x', f);
    fclose(f);
    assert_int_equal(batch_capture(script, err, sizeof err), 1);
    assert_non_null(strstr(err, ":2: the line is longer than"));
    print_message("# long line: %s", err);
    /* Reading never grew the process by more than a few megabytes. */
    print_message("# peak RSS grew by %ld kB\n", max_rss_kb() - rss0);
    assert_true(max_rss_kb() - rss0 < 16 * 1024);
}

static void test_wavelength_lines(void **state)
{
    ed *e = new_ed();
    const sg_system *s;
    int f;
    (void)state;
    ok(e, "wavelength preset FdC");
    s = e->doc.sys;
    assert_int_equal(s->nwave, 3);
    assert_true(s->wave[0].um == 0.4861327);
    assert_true(s->wave[1].um == 0.5875618);
    assert_true(s->wave[2].um == 0.6562725);
    assert_int_equal(s->primary_wave, 1);
    ok(e, "wavelength add e");
    assert_true(e->doc.sys->wave[3].um == 0.546074);
    ok(e, "wavelength set 4 g");
    assert_true(e->doc.sys->wave[3].um == 0.4358343);
    /* wave: by number, by micrometres, by line. */
    ok(e, "wave C");
    assert_int_equal(e->wave, 2);
    ok(e, "wave 0.4861327");
    assert_int_equal(e->wave, 0);
    f = run(e, "wave 1.5");
    assert_true(f & ED_ERROR);
    assert_null(strstr(e->msg, "not a number"));
    assert_non_null(strstr(e->msg, "wavelength add 1.5"));
    ok(e, "wavelength add 1.5");
    ok(e, "wave 1.5");
    assert_int_equal(e->wave, 4);
    ok(e, "wave 2");
    assert_int_equal(e->wave, 1);
    free_ed(e);
}

/* Moving a wavelength keeps the primary and the traced wavelength on the
 * same light, and undo puts the list back. */
static void test_wavelength_move(void **state)
{
    ed *e = new_ed();
    const sg_system *s;
    (void)state;
    ok(e, "wavelength preset FdC");
    ok(e, "wave 3"); /* C */
    ok(e, "wavelength move 3 1");
    s = e->doc.sys;
    assert_true(s->wave[0].um == 0.6562725);
    assert_true(s->wave[1].um == 0.4861327);
    assert_true(s->wave[2].um == 0.5875618);
    assert_int_equal(s->primary_wave, 2); /* d */
    assert_int_equal(e->wave, 0);         /* C */
    ok(e, "wavelength move 1 2");
    s = e->doc.sys;
    assert_true(s->wave[0].um == 0.4861327);
    assert_true(s->wave[1].um == 0.6562725);
    assert_int_equal(s->primary_wave, 2);
    assert_int_equal(e->wave, 1);
    ok(e, "undo 2");
    s = e->doc.sys;
    assert_true(s->wave[0].um == 0.4861327 && s->wave[2].um == 0.6562725);
    assert_int_equal(s->primary_wave, 1);
    free_ed(e);
}

/* field N sets Hx, Hy to field N of the design as Zemax normalizes it. */
static void test_field_pick(void **state)
{
    char path[512];
    ed *e = new_ed();
    int f;
    (void)state;
    tu_path("examples/tma.json", path, sizeof path);
    ok(e, "open %s", path);
    ok(e, "field 2");
    assert_true(e->ray[0] == 6.0 / sqrt(78.25));
    assert_true(e->ray[1] == 6.5 / sqrt(78.25));
    assert_non_null(strstr(e->msg, "deg"));
    ok(e, "field 1");
    assert_true(e->ray[0] == 0.0 && e->ray[1] == 0.0);
    ok(e, "field norm rect");
    ok(e, "field 2");
    assert_true(e->ray[0] == 1.0 && e->ray[1] == 1.0);
    f = run(e, "field 3");
    assert_true(f & ED_ERROR);
    free_ed(e);
}

/* print paraxial prints the first-order data at the primary wavelength,
 * as "sagitta paraxial" does, whatever wavelength the ray uses. */
static void test_print_paraxial(void **state)
{
    ed *e = new_ed();
    char buf[8192];
    size_t got;
    (void)state;
    ok(e, "wavelength set 1 0.4861327");
    ok(e, "wavelength add 0.5875618");
    ok(e, "wavelength add 0.6562725");
    ok(e, "wavelength primary 2");
    ok(e, "wave 3");
    ok(e, "print paraxial");
    fflush(e->out);
    rewind(e->out);
    got = fread(buf, 1, sizeof buf - 1, e->out);
    buf[got] = '\0';
    assert_non_null(strstr(buf, "Entrance pupil position"));
    assert_non_null(strstr(buf, "Exit pupil diameter"));
    assert_non_null(strstr(buf, "Paraxial working F/#"));
    assert_non_null(strstr(buf, "Paraxial magnification"));
    assert_non_null(strstr(buf, "0.5875618 um (wave 2)"));
    free_ed(e);
}

/* Making a surface with r^n terms STANDARD says that they are ignored. */
static void test_standard_note(void **state)
{
    ed *e = new_ed();
    (void)state;
    ok(e, "set 1 a4 1e-5");
    assert_int_equal(e->doc.sys->surf[1].type, SG_SURF_EVENASPH);
    ok(e, "set 1 type standard");
    assert_non_null(strstr(e->msg, "ignored"));
    ok(e, "set 1 a4 0");
    ok(e, "set 1 type standard");
    assert_null(strstr(e->msg, "ignored"));
    free_ed(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_saveas_existing),
        cmocka_unit_test(test_changed_on_disk),
        cmocka_unit_test(test_open_zmx),
        cmocka_unit_test(test_readonly),
        cmocka_unit_test(test_hard_link),
        cmocka_unit_test(test_hard_link_zmx),
        cmocka_unit_test(test_batch_bounds),
        cmocka_unit_test(test_wavelength_lines),
        cmocka_unit_test(test_wavelength_move),
        cmocka_unit_test(test_field_pick),
        cmocka_unit_test(test_print_paraxial),
        cmocka_unit_test(test_standard_note),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    if (tmpdir[0]) {
        char cmd[400];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
        if (system(cmd) != 0)
            fprintf(stderr, "# could not remove %s\n", tmpdir);
    }
    return rc;
}
