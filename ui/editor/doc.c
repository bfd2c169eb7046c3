/* doc.c - the edited system with its file name and undo history. */
#include "doc.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* 64 MiB keeps hundreds of steps of a large design and a few of a huge one. */
#define DOC_HIST_LIMIT ((size_t)64 << 20)

static size_t snap_bytes(const sg_system *s)
{
    return sizeof *s + (size_t)s->capsurf * sizeof *s->surf;
}

static char *dupstr(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = malloc(n);
    if (p)
        memcpy(p, s, n);
    return p;
}

static void stack_clear(doc *d, doc_stack *st)
{
    size_t i;
    for (i = 0; i < st->n; i++) {
        d->hist_bytes -= snap_bytes(st->v[i].sys);
        sg_system_free(st->v[i].sys);
    }
    st->n = 0;
}

static int stack_push(doc *d, doc_stack *st, sg_system *sys, unsigned long id, int row)
{
    if (st->n == st->cap) {
        size_t cap = st->cap ? st->cap * 2 : 32;
        doc_snap *v = realloc(st->v, cap * sizeof *v);
        if (!v)
            return SG_ENOMEM;
        st->v = v;
        st->cap = cap;
    }
    st->v[st->n].sys = sys;
    st->v[st->n].id = id;
    st->v[st->n].row = row;
    st->n++;
    d->hist_bytes += snap_bytes(sys);
    return SG_EOK;
}

/* Drops the oldest undo steps while the history is over its budget, but
 * always keeps the newest one so the last change can be undone. */
static void trim(doc *d)
{
    size_t drop = 0, i;
    while (d->hist_bytes > d->hist_limit && drop + 1 < d->undo.n) {
        d->hist_bytes -= snap_bytes(d->undo.v[drop].sys);
        sg_system_free(d->undo.v[drop].sys);
        drop++;
    }
    if (drop == 0)
        return;
    for (i = drop; i < d->undo.n; i++)
        d->undo.v[i - drop] = d->undo.v[i];
    d->undo.n -= drop;
}

int doc_init(doc *d)
{
    memset(d, 0, sizeof *d);
    d->sys = sg_system_new();
    if (!d->sys)
        return SG_ENOMEM;
    d->id = d->saved_id = 1;
    d->next_id = 2;
    d->hist_limit = DOC_HIST_LIMIT;
    return SG_EOK;
}

void doc_free(doc *d)
{
    stack_clear(d, &d->undo);
    stack_clear(d, &d->redo);
    free(d->undo.v);
    free(d->redo.v);
    sg_system_free(d->sys);
    free(d->path);
    memset(d, 0, sizeof *d);
}

int doc_modified(const doc *d)
{
    return d->id != d->saved_id;
}

const char *doc_path(const doc *d)
{
    return d->path;
}

int doc_set_path(doc *d, const char *path)
{
    char *p = NULL;
    if (path && !(p = dupstr(path)))
        return SG_ENOMEM;
    free(d->path);
    d->path = p;
    return SG_EOK;
}

int doc_begin(doc *d, int row)
{
    sg_system *snap = sg_system_clone(d->sys);
    if (!snap)
        return SG_ENOMEM;
    if (stack_push(d, &d->undo, snap, d->id, row) != SG_EOK) {
        sg_system_free(snap);
        return SG_ENOMEM;
    }
    d->open_change = 1;
    return SG_EOK;
}

static doc_snap pop(doc *d, doc_stack *st)
{
    doc_snap s = st->v[--st->n];
    d->hist_bytes -= snap_bytes(s.sys);
    return s;
}

int doc_end(doc *d)
{
    doc_snap *top;
    if (!d->open_change || d->undo.n == 0)
        return 0;
    d->open_change = 0;
    top = &d->undo.v[d->undo.n - 1];
    if (doc_system_equal(top->sys, d->sys)) {
        doc_snap s = pop(d, &d->undo);
        sg_system_free(s.sys);
        return 0;
    }
    d->id = d->next_id++;
    stack_clear(d, &d->redo);
    trim(d);
    return 1;
}

void doc_cancel(doc *d)
{
    doc_snap s;
    if (!d->open_change || d->undo.n == 0)
        return;
    d->open_change = 0;
    s = pop(d, &d->undo);
    /* The snapshot becomes the document, so nothing needs copying. */
    sg_system_free(d->sys);
    d->sys = s.sys;
}

/* Moves the document onto one stack and the top of the other into the
 * document: the common step of undo and redo. */
static int step(doc *d, doc_stack *from, doc_stack *to, int *row)
{
    doc_snap s;
    if (from->n == 0)
        return SG_ERANGE;
    if (stack_push(d, to, d->sys, d->id, from->v[from->n - 1].row) != SG_EOK)
        return SG_ENOMEM;
    s = pop(d, from);
    d->sys = s.sys;
    d->id = s.id;
    if (row)
        *row = s.row;
    return SG_EOK;
}

int doc_undo(doc *d, int *row)
{
    return step(d, &d->undo, &d->redo, row);
}

int doc_redo(doc *d, int *row)
{
    return step(d, &d->redo, &d->undo, row);
}

size_t doc_undo_depth(const doc *d)
{
    return d->undo.n;
}

size_t doc_redo_depth(const doc *d)
{
    return d->redo.n;
}

static void replace(doc *d, sg_system *sys)
{
    stack_clear(d, &d->undo);
    stack_clear(d, &d->redo);
    sg_system_free(d->sys);
    d->sys = sys;
    d->id = d->saved_id = d->next_id++;
    d->open_change = 0;
}

int doc_load(doc *d, const char *path, sg_diag *dg)
{
    sg_system *sys = sg_system_new();
    int rc;
    char *p;
    if (!sys || !(p = dupstr(path))) {
        sg_system_free(sys);
        return sg_diag_set(dg, SG_ENOMEM, "%s: out of memory", path);
    }
    rc = sg_design_load(sys, path, dg);
    if (rc != SG_EOK) {
        sg_system_free(sys);
        free(p);
        return rc;
    }
    replace(d, sys);
    free(d->path);
    d->path = p;
    if (doc_stamp_file(path, &d->disk) != 0)
        d->disk.have = 0;
    return SG_EOK;
}

int doc_new(doc *d, const char *path)
{
    sg_system *sys = sg_system_new();
    char *p = NULL;
    if (!sys || (path && !(p = dupstr(path)))) {
        sg_system_free(sys);
        return SG_ENOMEM;
    }
    replace(d, sys);
    free(d->path);
    d->path = p;
    d->disk.have = 0;
    return SG_EOK;
}

void doc_replace(doc *d, sg_system *sys, const char *path, int modified,
                 const doc_stamp *read)
{
    char *p = path ? dupstr(path) : NULL;
    replace(d, sys);
    /* Out of memory for the name leaves the design unnamed rather than
     * lost: save then asks for a name. */
    free(d->path);
    d->path = p;
    /* A recovered design keeps the stamp of the file its crashed editor
     * read: a change made on disk since then is still a change, and saving
     * asks before replacing it. */
    if (p && read && read->have)
        d->disk = *read;
    else
        memset(&d->disk, 0, sizeof d->disk);
    /* Ids start at 1, so 0 is a saved state no document ever reaches. */
    if (modified)
        d->saved_id = 0;
}

/* FNV-1a, 64 bits: enough to tell an edited file from the one we read. */
static unsigned long long fnv(unsigned long long h, const unsigned char *p, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

int doc_stamp_file(const char *path, doc_stamp *st)
{
    struct stat sb;
    unsigned char buf[65536];
    unsigned long long h = 14695981039346656037ULL;
    ssize_t got;
    int fd, e;
    memset(st, 0, sizeof *st);
    fd = open(path, O_RDONLY);
    if (fd < 0)
        return -1;
    if (fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
        e = S_ISREG(sb.st_mode) ? errno : EINVAL;
        close(fd);
        errno = e;
        return -1;
    }
    while ((got = read(fd, buf, sizeof buf)) != 0) {
        if (got < 0) {
            if (errno == EINTR)
                continue;
            e = errno;
            close(fd);
            errno = e;
            return -1;
        }
        h = fnv(h, buf, (size_t)got);
    }
    close(fd);
    st->have = 1;
    st->dev = (unsigned long long)sb.st_dev;
    st->ino = (unsigned long long)sb.st_ino;
    st->size = (unsigned long long)sb.st_size;
    st->mtime_s = (long long)sb.st_mtim.tv_sec;
    st->mtime_ns = sb.st_mtim.tv_nsec;
    st->hash = h;
    return 0;
}

int doc_disk_changed(const doc *d)
{
    doc_stamp now;
    if (!d->path || doc_stamp_file(d->path, &now) != 0)
        return 0;
    /* A file this document never read (a new design given a name that
     * another program has since used) is someone else's work too. */
    if (!d->disk.have)
        return 1;
    /* The bytes decide: a touch, or a copy back of the same text, is no
     * change; a new size or new content is. */
    return now.size != d->disk.size || now.hash != d->disk.hash;
}

int doc_target(const char *path, unsigned long *nlink)
{
    struct stat sb;
    if (nlink)
        *nlink = 0;
    if (stat(path, &sb) != 0)
        return DOC_TARGET_NEW;
    if (!S_ISREG(sb.st_mode))
        return DOC_TARGET_NOTFILE;
    if (nlink)
        *nlink = (unsigned long)sb.st_nlink;
    /* root may write anything, so the mode bits say what the owner
     * meant: a file nobody may write is read-only for root too. */
    if (geteuid() == 0 ? (sb.st_mode & 0222) == 0 : access(path, W_OK) != 0)
        return DOC_TARGET_READONLY;
    return DOC_TARGET_FILE;
}

int doc_is_own_file(const doc *d, const char *path)
{
    struct stat a, b;
    if (!d->path)
        return 0;
    if (strcmp(d->path, path) == 0)
        return 1;
    return stat(d->path, &a) == 0 && stat(path, &b) == 0 && a.st_dev == b.st_dev &&
           a.st_ino == b.st_ino;
}

int doc_save(doc *d, const char *path, sg_diag *dg)
{
    return doc_save_flags(d, path, 0, dg);
}

int doc_save_flags(doc *d, const char *path, unsigned flags, sg_diag *dg)
{
    int rc, t;
    if (!path)
        path = d->path;
    if (!path)
        return sg_diag_set(dg, SG_EINVAL, "no file name: give one to save as");
    if (sg_zar_detect(path, NULL, 0))
        return sg_diag_set(dg, SG_EUNSUPPORTED, "%s: sagitta reads Zemax archives but does not "
                                                "write them: save as .json or .zmx", path);
    t = doc_target(path, NULL);
    if (t == DOC_TARGET_READONLY)
        return sg_diag_set(dg, SG_EIO, "%s is read-only: not saved (save under another name, "
                                       "or make it writable)", path);
    /* The engine's save keeps a file's hard links (it rewrites such a file
     * in place after a backup) in every format. */
    rc = sg_design_save_flags(d->sys, path, flags, dg);
    if (rc != SG_EOK)
        return rc;
    if (path != d->path && doc_set_path(d, path) != SG_EOK)
        return sg_diag_set(dg, SG_ENOMEM, "%s: saved, but out of memory", path);
    d->saved_id = d->id;
    if (doc_stamp_file(d->path, &d->disk) != 0)
        d->disk.have = 0;
    return SG_EOK;
}

int doc_system_equal(const sg_system *a, const sg_system *b)
{
    return sg_system_equal(a, b);
}
