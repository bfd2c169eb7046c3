/*
 * cmd_file.c - files: open, new, example, save, quit and recover.
 */
#include "cmd_int.h"

/* ------------------------------------------------------------------------
 * Files
 * ------------------------------------------------------------------------ */

/* Checks for unsaved changes before the document is replaced.  Returns 1
 * to go ahead; otherwise flags for the caller to return. */
static int may_discard(ed *e, const args *a, int bang, int *flags)
{
    char q[ED_LINE / 2];
    int i;
    size_t len;
    if (bang || !doc_modified(&e->doc))
        return 1;
    if (e->batch) {
        *flags = ec_fail(e, "unsaved changes: save first, or use %s!", a->v[0]);
        return 0;
    }
    snprintf(e->pending, sizeof e->pending, "%s!", a->v[0]);
    for (i = 1; i < a->n; i++) {
        cmd_quote(a->v[i], q, sizeof q);
        len = strlen(e->pending);
        snprintf(e->pending + len, sizeof e->pending - len, " %s", q);
    }
    e->confirm = CONFIRM_DISCARD;
    ed_msg(e, 0, "unsaved changes will be lost");
    *flags = ED_HANDLED | ED_CONFIRM | ED_REDRAW;
    return 0;
}

static int opened(ed *e, const char *what)
{
    e->row = 0;
    e->col = COL_RADIUS;
    e->wave = e->doc.sys->primary_wave;
    e->dirty = 1;
    ed_msg(e, 0, "%s: %d surfaces", what, e->doc.sys->nsurf);
    return OK_VIEW;
}

/* Says so when an editor that died left unsaved changes to this file. */
static void note_orphans(ed *e, const char *path)
{
    char dir[REC_PATH], abs[REC_PATH], when[64];
    rec_info *v;
    size_t len;
    if (rec_dir(dir, sizeof dir) != 0 || rec_abspath(path, abs, sizeof abs) != 0 ||
        rec_orphans(dir, abs, e->rec.file[0] ? e->rec.file : NULL, &v) <= 0)
        return;
    rec_time_text(v[0].time, when, sizeof when);
    len = strlen(e->msg);
    snprintf(e->msg + len, sizeof e->msg - len,
             "; unsaved changes to it from %s are in a recovery file (:recover)", when);
    free(v);
}

int ed_note_holders(ed *e, const char *path)
{
    char dir[REC_PATH], abs[REC_PATH], when[64];
    rec_info first;
    size_t len;
    int n;
    if (rec_dir(dir, sizeof dir) != 0 || rec_abspath(path, abs, sizeof abs) != 0 ||
        (n = rec_holders(dir, abs, &first)) <= 0)
        return 0;
    rec_time_text(first.time, when, sizeof when);
    len = strlen(e->msg);
    snprintf(e->msg + len, sizeof e->msg - len,
             "%swarning: %s is open in %s editor (pid %ld%s%s, since %s); a save may "
             "overwrite its changes", len ? "; " : "", path, n > 1 ? "more than one" : "another",
             first.pid, first.host[0] ? " on " : "", first.host, when);
    e->msg_err = 1;
    return n;
}

static int open_path(ed *e, const char *path)
{
    sg_diag d;
    int f;
    sg_diag_clear(&d);
    if (doc_load(&e->doc, path, &d) != SG_EOK)
        return ec_fail(e, "%s", d.msg[0] ? d.msg : sg_strerror(d.code));
    f = opened(e, path);
    ed_load_warnings(e, path, &d);
    /* Solved values follow the design as it is opened. */
    sg_diag_clear(&d);
    if (sg_system_apply_solves(e->doc.sys, e->cat, &d) != SG_OK)
        ed_msg(e, 1, "solves: %s", d.msg);
    note_orphans(e, path);
    ed_note_holders(e, path);
    return f;
}

int c_open(ed *e, args *a, int bang)
{
    char path[ED_LINE];
    int flags;
    if (a->n < 2) {
        if (e->batch)
            return ec_fail(e, "usage: open FILE");
        snprintf(e->prompt_init, sizeof e->prompt_init, "open ");
        return ED_HANDLED | ED_PROMPT;
    }
    ec_rest_of(a, 1, path, sizeof path);
    if (!may_discard(e, a, bang, &flags))
        return flags;
    return open_path(e, path);
}

int c_new(ed *e, args *a, int bang)
{
    int flags;
    if (!ec_need(e, a, 0, 1, "new [FILE]"))
        return ED_HANDLED | ED_ERROR;
    if (!may_discard(e, a, bang, &flags))
        return flags;
    if (doc_new(&e->doc, a->n > 1 ? a->v[1] : NULL) != SG_EOK)
        return ec_fail(e, "out of memory");
    return opened(e, "new design");
}

int c_example(ed *e, args *a, int bang)
{
    const char *dir = ed_examples_dir();
    char path[ED_LINE];
    char **names;
    int n, i, flags;
    if (a->n < 2) {
        if (!e->batch)
            return ED_HANDLED | ED_SHOW_EXAMPLES;
        n = ed_examples_list(&names);
        if (n < 0)
            return ec_fail(e, "no examples directory (set SAGITTA_EXAMPLES)");
        for (i = 0; i < n; i++)
            fprintf(e->out, "%s\n", names[i]);
        ed_examples_free(names, n);
        return ED_HANDLED;
    }
    if (!ec_need(e, a, 1, 1, "example NAME"))
        return ED_HANDLED | ED_ERROR;
    if (!dir)
        return ec_fail(e, "no examples directory (set SAGITTA_EXAMPLES)");
    if (strchr(a->v[1], '/'))
        return ec_fail(e, "example: \"%s\": give a name from the list, not a path", a->v[1]);
    n = (int)strlen(a->v[1]);
    snprintf(path, sizeof path, "%s/%s%s", dir, a->v[1],
             n > 5 && strcmp(a->v[1] + n - 5, ".json") == 0 ? "" : ".json");
    if (!may_discard(e, a, bang, &flags))
        return flags;
    /* An example opens as a new file so that "save" cannot overwrite the
     * bundled copy by accident. */
    flags = open_path(e, path);
    if (!(flags & ED_ERROR)) {
        doc_set_path(&e->doc, NULL);
        ed_msg(e, 0, "example %s: %d surfaces (save it under a name of your own)",
               a->v[1], e->doc.sys->nsurf);
    }
    return flags;
}

static int save_as(ed *e, const char *path, int bang, const char *cmd)
{
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    /* A failure leaves the old file whole (see doc_save); the document
     * stays as it was, modified.  A .zmx file that cannot hold the edits
     * faithfully is written only after a yes (or with "!"). */
    rc = doc_save_flags(&e->doc, path, bang ? SG_ZMX_ALLOW_LOSS : 0, &d);
    if (rc == SG_ELOSSY && !bang) {
        if (e->batch)
            return ec_fail(e, "not saved: %s; %s writes it all the same", d.msg, cmd);
        snprintf(e->pending, sizeof e->pending, "%s", cmd);
        snprintf(e->question, sizeof e->question, "%.900s. Write it all the same? (y)es (n)o",
                 d.msg);
        snprintf(e->question_short, sizeof e->question_short,
                 "Write all the same? (y)es (n)o: %.900s", d.msg);
        e->confirm = CONFIRM_ASK;
        ed_msg(e, 0, "%s", d.msg);
        return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
    }
    if (rc != SG_EOK)
        return ec_fail(e, "not saved: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
    rec_saved(e);
    if (d.nwarn)
        ed_msg(e, 0, "saved %s: %s", doc_path(&e->doc), d.warn[0]);
    else
        ed_msg(e, 0, "saved %s", doc_path(&e->doc));
    return ED_HANDLED | ED_REDRAW;
}

/* Asks before a save that would replace work: yes runs cmd (the same save
 * with "!").  In batch mode nobody can answer, so it fails, naming cmd. */
static int ask(ed *e, const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static int ask(ed *e, const char *cmd, const char *fmt, ...)
{
    char why[ED_MSG];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    if (e->batch)
        return ec_fail(e, "%s: not saved; %s overwrites it", why, cmd);
    snprintf(e->pending, sizeof e->pending, "%s", cmd);
    snprintf(e->question, sizeof e->question, "%.900s. Overwrite it? (y)es (n)o", why);
    snprintf(e->question_short, sizeof e->question_short, "Overwrite? (y)es (n)o: %.900s", why);
    e->confirm = CONFIRM_ASK;
    ed_msg(e, 0, "%s", why);
    return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
}

/* save, save!, wq and wq!: a new name that holds another file, or our own
 * file changed on disk by someone else, is not overwritten unasked. */
static int save_cmd(ed *e, args *a, int bang, int quit)
{
    char path[ED_LINE], q[ED_LINE], cmd[ED_LINE + 8];
    const char *target;
    int f;
    cmd[0] = '\0';
    if (a->n > 1) {
        ec_rest_of(a, 1, path, sizeof path);
        target = path;
    } else {
        target = doc_path(&e->doc);
        if (!target) {
            if (e->batch)
                return ec_fail(e, "no file name: use save FILE");
            snprintf(e->prompt_init, sizeof e->prompt_init, quit ? "wq " : "save ");
            ed_msg(e, 0, "save as: type a file name");
            return ED_HANDLED | ED_PROMPT;
        }
    }
    if (!bang) {
        int t = doc_target(target, NULL), own = doc_is_own_file(&e->doc, target);
        cmd_quote(target, q, sizeof q);
        snprintf(cmd, sizeof cmd, "%s! %s", quit ? "wq" : "save", q);
        if (t == DOC_TARGET_READONLY)
            return ec_fail(e, "not saved: %s is read-only (save under another name, or make it "
                           "writable)", target);
        if (t == DOC_TARGET_NOTFILE)
            return ec_fail(e, "not saved: %s is not a regular file", target);
        if (t != DOC_TARGET_NEW && !own)
            return ask(e, cmd, "%s already exists", target);
        if (own && doc_disk_changed(&e->doc))
            return ask(e, cmd, e->doc.disk.have ? "%s changed on disk since it was read"
                                                : "%s already exists", target);
    }
    if (!cmd[0]) {
        cmd_quote(target, q, sizeof q);
        snprintf(cmd, sizeof cmd, "%s! %s", quit ? "wq" : "save", q);
    }
    f = save_as(e, a->n > 1 ? path : NULL, bang, cmd);
    if (!quit || (f & (ED_ERROR | ED_CONFIRM)))
        return f;
    rec_finish(e);
    e->quit = 1;
    return f | ED_QUIT;
}

int c_save(ed *e, args *a)
{
    return save_cmd(e, a, 0, 0);
}

int c_save1(ed *e, args *a)
{
    return save_cmd(e, a, 1, 0);
}

int c_quit(ed *e, args *a, int bang)
{
    if (bang || !doc_modified(&e->doc)) {
        /* A clean end: nothing is left to recover. */
        rec_finish(e);
        e->quit = 1;
        return ED_HANDLED | ED_QUIT;
    }
    if (e->batch)
        return ec_fail(e, "unsaved changes: save first, or use quit!");
    e->confirm = CONFIRM_QUIT;
    ed_msg(e, 0, "unsaved changes");
    return ED_HANDLED | ED_CONFIRM | ED_REDRAW;
}

int c_wq(ed *e, args *a)
{
    return save_cmd(e, a, 0, 1);
}

int c_wq1(ed *e, args *a)
{
    return save_cmd(e, a, 1, 1);
}

/* ------------------------------------------------------------------------
 * Recovery files left by editors that crashed or were killed
 * ------------------------------------------------------------------------ */

/* Finds the orphan a token names: its number in the list, or its file. */
static int pick_orphan(ed *e, const rec_info *v, int n, const char *tok)
{
    char want[REC_PATH], have[REC_PATH];
    rec_info info;
    sg_diag d;
    int i, k;
    if (args_int(tok, 1, INT_MAX, &k) == ARGS_OK) {
        if (k > n)
            return ec_fail(e, "recover: there %s %d recovery file%s; see recover list",
                        n == 1 ? "is" : "are", n, n == 1 ? "" : "s"), -1;
        return k - 1;
    }
    for (i = 0; i < n; i++)
        if (strcmp(v[i].file, tok) == 0)
            return i;
    /* The same file under another spelling (relative, through a link). */
    if (rec_abspath(tok, want, sizeof want) == 0)
        for (i = 0; i < n; i++)
            if (rec_abspath(v[i].file, have, sizeof have) == 0 && strcmp(want, have) == 0)
                return i;
    sg_diag_clear(&d);
    if (rec_read_file(tok, &info, NULL, &d) != SG_OK)
        return ec_fail(e, "recover: %s", d.msg), -1;
    if (!info.orphan)
        return ec_fail(e, "recover: %s belongs to an editor still running (pid %ld%s%s)", tok,
                    info.pid, info.host[0] ? " on " : "", info.host), -1;
    return ec_fail(e, "recover: %s is not in the list of recovery files", tok), -1;
}

int c_recover(ed *e, args *a, int bang)
{
    const char *usage = "recover [list | N | FILE | delete N|FILE]";
    const char *sub = a->n > 1 ? a->v[1] : "list";
    char dir[REC_PATH], when[64];
    rec_info *v = NULL, got;
    sg_system *sys;
    sg_diag d;
    int n, i, k, flags;

    if (rec_dir(dir, sizeof dir) != 0)
        return ec_fail(e, "recover: set XDG_STATE_HOME or HOME to say where recovery files live");
    n = rec_orphans(dir, NULL, e->rec.file[0] ? e->rec.file : NULL, &v);
    if (n < 0)
        return ec_fail(e, "recover: cannot read %s: %s", dir, strerror(errno));
    if (strcmp(sub, "list") == 0) {
        size_t len;
        if (!ec_need(e, a, 0, 1, usage)) {
            free(v);
            return ED_HANDLED | ED_ERROR;
        }
        if (n == 0) {
            ed_msg(e, 0, "no recovery files in %s", dir);
            free(v);
            return ED_HANDLED | ED_REDRAW;
        }
        ed_msg(e, 0, "%d recovery file%s (recover N loads, recover delete N removes):", n,
               n == 1 ? "" : "s");
        for (i = 0; i < n; i++) {
            rec_time_text(v[i].time, when, sizeof when);
            if (e->batch)
                fprintf(e->out, "%d  %s  %s  %s\n", i + 1, when,
                        v[i].path[0] ? v[i].path : "(untitled)", v[i].file);
            len = strlen(e->msg);
            snprintf(e->msg + len, sizeof e->msg - len, "  %d) %s, %s", i + 1,
                     v[i].path[0] ? v[i].path : "untitled", when);
        }
        free(v);
        return ED_HANDLED | ED_REDRAW;
    }
    if (strcmp(sub, "delete") == 0) {
        if (!ec_need(e, a, 2, 2, usage) || (k = pick_orphan(e, v, n, a->v[2])) < 0) {
            free(v);
            return ED_HANDLED | ED_ERROR;
        }
        if (unlink(v[k].file) != 0) {
            flags = ec_fail(e, "recover: cannot delete %s: %s", v[k].file, strerror(errno));
            free(v);
            return flags;
        }
        ed_msg(e, 0, "deleted %s (unsaved changes to %s)", v[k].file,
               v[k].path[0] ? v[k].path : "an untitled design");
        free(v);
        return ED_HANDLED | ED_REDRAW;
    }
    if (!ec_need(e, a, 1, 1, usage) || (k = pick_orphan(e, v, n, a->v[1])) < 0) {
        free(v);
        return ED_HANDLED | ED_ERROR;
    }
    if (!may_discard(e, a, bang, &flags)) {
        free(v);
        return flags;
    }
    sys = sg_system_new();
    if (!sys) {
        free(v);
        return ec_fail(e, "out of memory");
    }
    sg_diag_clear(&d);
    if (rec_read_file(v[k].file, &got, sys, &d) != SG_OK) {
        sg_system_free(sys);
        flags = ec_fail(e, "recover: %s", d.msg[0] ? d.msg : sg_strerror(d.code));
        free(v);
        return flags;
    }
    /* The recovered design keeps its file name, so save writes the file it
     * came from; it differs from that file until then. */
    free(v);
    doc_replace(&e->doc, sys, got.path[0] ? got.path : NULL, 1, &got.disk);
    snprintf(e->rec.adopted, sizeof e->rec.adopted, "%s", got.file);
    opened(e, "recovered");
    rec_time_text(got.time, when, sizeof when);
    if (got.path[0])
        ed_msg(e, 0, "recovered unsaved changes to %s from %s; save writes them there", got.path,
               when);
    else
        ed_msg(e, 0, "recovered an untitled design from %s; save FILE keeps it", when);
    return OK_VIEW;
}
