/* recover.c - the recovery file: written as edits happen, offered after a
 * crash.  See recover.h for the format and the place. */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* realpath */
#endif

#include "recover.h"

#include <cjson/cJSON.h>
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include "ed.h"

/* A header longer than this is not one of ours. */
#define REC_HEADER_MAX 65536
/* Nor is a file larger than this (a design of SG_MAX_SURFACES surfaces
 * is well below it). */
#define REC_FILE_MAX ((size_t)1 << 30)

static int put(char *buf, size_t n, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* snprintf that reports truncation, since a cut path names another file. */
static int put(char *buf, size_t n, const char *fmt, ...)
{
    va_list ap;
    int k;
    va_start(ap, fmt);
    k = vsnprintf(buf, n, fmt, ap);
    va_end(ap);
    return k < 0 || (size_t)k >= n ? -1 : 0;
}

int rec_dir(char *buf, size_t n)
{
    const char *x = getenv("XDG_STATE_HOME"), *h = getenv("HOME");
    /* The XDG rules say a relative path in the variable is to be ignored. */
    if (x && x[0] == '/')
        return put(buf, n, "%s/sagitta", x);
    if (h && h[0] == '/')
        return put(buf, n, "%s/.local/state/sagitta", h);
    return -1;
}

int rec_abspath(const char *path, char *buf, size_t n)
{
    char res[PATH_MAX], dir[PATH_MAX], cwd[PATH_MAX];
    const char *slash, *base;
    if (!path || !path[0])
        return -1;
    if (realpath(path, res))
        return put(buf, n, "%s", res);
    /* A file not written yet: resolve its directory instead. */
    slash = strrchr(path, '/');
    base = slash ? slash + 1 : path;
    if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else if (slash) {
        if ((size_t)(slash - path) >= sizeof dir)
            return -1;
        memcpy(dir, path, (size_t)(slash - path));
        dir[slash - path] = '\0';
    } else
        snprintf(dir, sizeof dir, ".");
    if (base[0] && strcmp(base, ".") != 0 && strcmp(base, "..") != 0 && realpath(dir, res))
        return put(buf, n, "%s%s%s", res, strcmp(res, "/") == 0 ? "" : "/", base);
    if (path[0] == '/')
        return put(buf, n, "%s", path);
    if (!getcwd(cwd, sizeof cwd))
        return -1;
    return put(buf, n, "%s/%s", cwd, path);
}

/* ------------------------------------------------------------------------
 * Who wrote a file, and is it still running?
 * ------------------------------------------------------------------------ */

/* Start time of a process in clock ticks after boot (field 22 of
 * /proc/PID/stat), which tells a live process from a later one that got
 * the same pid; 0 where there is no /proc.  *state (may be NULL) gets the
 * state letter, 'Z' for a dead process nobody has reaped yet. */
static unsigned long long proc_stat(long pid, char *state)
{
    char path[64], buf[1024], *p;
    int fd, field;
    ssize_t k;
    snprintf(path, sizeof path, "/proc/%ld/stat", pid);
    fd = open(path, O_RDONLY);
    if (fd < 0)
        return 0;
    k = read(fd, buf, sizeof buf - 1);
    close(fd);
    if (k <= 0)
        return 0;
    buf[k] = '\0';
    /* The command name in parentheses may hold blanks and ')'. */
    p = strrchr(buf, ')');
    if (!p)
        return 0;
    p++;
    if (state)
        *state = p[0] == ' ' ? p[1] : '?';
    for (field = 2; field < 21 && *p; field++) {
        while (*p == ' ')
            p++;
        while (*p && *p != ' ')
            p++;
    }
    while (*p == ' ')
        p++;
    return field == 21 && isdigit((unsigned char)*p) ? strtoull(p, NULL, 10) : 0;
}

static void boot_id(char *buf, size_t n)
{
    int fd = open("/proc/sys/kernel/random/boot_id", O_RDONLY);
    ssize_t k = -1;
    buf[0] = '\0';
    if (fd >= 0) {
        k = read(fd, buf, n - 1);
        close(fd);
    }
    buf[k > 0 ? k : 0] = '\0';
    buf[strcspn(buf, "\r\n")] = '\0';
}

static void host_name(char *buf, size_t n)
{
    if (gethostname(buf, n) != 0)
        buf[0] = '\0';
    buf[n - 1] = '\0';
}

int rec_is_orphan(const rec_info *info)
{
    char host[256], boot[40], state = '?';
    unsigned long long st;
    host_name(host, sizeof host);
    if (info->host[0] && host[0] && strcmp(info->host, host) != 0)
        return 0;
    boot_id(boot, sizeof boot);
    if (info->boot[0] && boot[0] && strcmp(info->boot, boot) != 0)
        return 1;
    if (info->pid <= 0)
        return 1;
    if (kill((pid_t)info->pid, 0) != 0 && errno == ESRCH)
        return 1;
    st = proc_stat(info->pid, &state);
    /* A zombie has exited; its parent has not looked yet. */
    if (state == 'Z' || state == 'X')
        return 1;
    if (info->start && st != 0 && st != info->start)
        return 1;
    return 0;
}

void rec_time_text(long long t, char *buf, size_t n)
{
    time_t tt = (time_t)t;
    struct tm tm;
    if (!localtime_r(&tt, &tm) || strftime(buf, n, "%Y-%m-%d %H:%M:%S", &tm) == 0)
        snprintf(buf, n, "%lld", t);
}

/* ------------------------------------------------------------------------
 * Writing and reading
 * ------------------------------------------------------------------------ */

static int write_all(int fd, const char *p, size_t n)
{
    while (n > 0) {
        ssize_t k = write(fd, p, n);
        if (k < 0) {
            if (errno == EINTR)
                continue;
            return -1;
        }
        p += k;
        n -= (size_t)k;
    }
    return 0;
}

/* The stamp's numbers are 64-bit, beyond a JSON number's exact range, so
 * they are written as decimal (and the hash as hex) strings. */
static int add_stamp(cJSON *h, const doc_stamp *st)
{
    char v[6][32];
    cJSON *o;
    if (!st || !st->have)
        return 1;
    o = cJSON_AddObjectToObject(h, "disk");
    snprintf(v[0], sizeof v[0], "%llu", st->dev);
    snprintf(v[1], sizeof v[1], "%llu", st->ino);
    snprintf(v[2], sizeof v[2], "%llu", st->size);
    snprintf(v[3], sizeof v[3], "%lld", st->mtime_s);
    snprintf(v[4], sizeof v[4], "%ld", st->mtime_ns);
    snprintf(v[5], sizeof v[5], "%016llx", st->hash);
    return o && cJSON_AddStringToObject(o, "dev", v[0]) && cJSON_AddStringToObject(o, "ino", v[1]) &&
           cJSON_AddStringToObject(o, "size", v[2]) &&
           cJSON_AddStringToObject(o, "mtime_s", v[3]) &&
           cJSON_AddStringToObject(o, "mtime_ns", v[4]) && cJSON_AddStringToObject(o, "hash", v[5]);
}

/* Reads what add_stamp wrote; a missing or malformed one leaves st->have 0,
 * so a save asks before replacing the file. */
static void read_stamp(const cJSON *h, doc_stamp *st)
{
    const cJSON *o = cJSON_GetObjectItemCaseSensitive(h, "disk");
    const char *k[6] = {"dev", "ino", "size", "mtime_s", "mtime_ns", "hash"};
    const char *v[6];
    char *end;
    int i;
    memset(st, 0, sizeof *st);
    if (!cJSON_IsObject(o))
        return;
    for (i = 0; i < 6; i++) {
        const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, k[i]);
        if (!cJSON_IsString(x) || !x->valuestring[0])
            return;
        v[i] = x->valuestring;
    }
    errno = 0;
    st->dev = strtoull(v[0], &end, 10);
    if (*end)
        return;
    st->ino = strtoull(v[1], &end, 10);
    if (*end)
        return;
    st->size = strtoull(v[2], &end, 10);
    if (*end)
        return;
    st->mtime_s = strtoll(v[3], &end, 10);
    if (*end)
        return;
    st->mtime_ns = strtol(v[4], &end, 10);
    if (*end)
        return;
    st->hash = strtoull(v[5], &end, 16);
    if (*end || errno)
        return;
    st->have = 1;
}

static char *header_json(const char *abspath, const doc_stamp *disk)
{
    char boot[40], host[256], start[32];
    cJSON *h = cJSON_CreateObject();
    char *s = NULL;
    if (!h)
        return NULL;
    boot_id(boot, sizeof boot);
    host_name(host, sizeof host);
    snprintf(start, sizeof start, "%llu", proc_stat((long)getpid(), NULL));
    if (cJSON_AddNumberToObject(h, "sagitta_recovery", 1) &&
        (abspath && abspath[0] ? cJSON_AddStringToObject(h, "path", abspath) != NULL
                               : cJSON_AddNullToObject(h, "path") != NULL) &&
        cJSON_AddNumberToObject(h, "pid", (double)getpid()) &&
        cJSON_AddStringToObject(h, "start", start) && cJSON_AddStringToObject(h, "boot", boot) &&
        cJSON_AddStringToObject(h, "host", host) &&
        cJSON_AddNumberToObject(h, "time", (double)time(NULL)) && add_stamp(h, disk))
        s = cJSON_PrintUnformatted(h);
    cJSON_Delete(h);
    return s;
}

int rec_write_file(const char *file, const char *abspath, const sg_system *sys,
                   const doc_stamp *disk, sg_diag *d)
{
    char tmp[REC_PATH + 16], dir[REC_PATH];
    char *text, *head;
    const char *slash;
    int fd, err = 0;

    text = sg_design_to_json(sys);
    head = header_json(abspath, disk);
    if (!text || !head) {
        free(text);
        free(head);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", file);
    }
    if (put(tmp, sizeof tmp, "%s.tmpXXXXXX", file) != 0) {
        free(text);
        free(head);
        return sg_diag_set(d, SG_EINVAL, "%s: name too long", file);
    }
    /* mkstemp gives mode 0600: a design can be confidential. */
    fd = mkstemp(tmp);
    if (fd < 0) {
        err = errno;
        free(text);
        free(head);
        return sg_diag_set(d, SG_EIO, "%s: cannot create a temporary file: %s", file,
                           strerror(err));
    }
    if (write_all(fd, head, strlen(head)) != 0 || write_all(fd, "\n", 1) != 0 ||
        write_all(fd, text, strlen(text)) != 0 || fsync(fd) != 0)
        err = errno ? errno : EIO;
    if (close(fd) != 0 && !err)
        err = errno;
    free(text);
    free(head);
    if (!err && rename(tmp, file) != 0)
        err = errno;
    if (err) {
        unlink(tmp);
        return sg_diag_set(d, SG_EIO, "%s: cannot write: %s", file, strerror(err));
    }
    /* The rename itself must reach the disk too. */
    slash = strrchr(file, '/');
    if (slash && put(dir, sizeof dir, "%.*s", (int)(slash - file), file) == 0 && dir[0]) {
        fd = open(dir, O_RDONLY | O_DIRECTORY);
        if (fd >= 0) {
            (void)fsync(fd);
            close(fd);
        }
    }
    return SG_OK;
}

static const char *json_str(const cJSON *h, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(h, key);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static int parse_header(const char *file, const char *text, size_t len, rec_info *info,
                        sg_diag *d)
{
    cJSON *h = cJSON_ParseWithLength(text, len);
    const cJSON *tag, *pid, *t, *path;
    const char *s;
    if (!h)
        return sg_diag_set(d, SG_EPARSE, "%s: not a sagitta recovery file", file);
    tag = cJSON_GetObjectItemCaseSensitive(h, "sagitta_recovery");
    pid = cJSON_GetObjectItemCaseSensitive(h, "pid");
    t = cJSON_GetObjectItemCaseSensitive(h, "time");
    path = cJSON_GetObjectItemCaseSensitive(h, "path");
    if (!cJSON_IsObject(h) || !cJSON_IsNumber(tag) || tag->valuedouble != 1.0 ||
        !cJSON_IsNumber(pid) || !cJSON_IsNumber(t) ||
        !(cJSON_IsString(path) || cJSON_IsNull(path)) ||
        !(pid->valuedouble >= 0 && pid->valuedouble < 4294967296.0) ||
        !(t->valuedouble > -1e15 && t->valuedouble < 1e15)) {
        cJSON_Delete(h);
        return sg_diag_set(d, SG_EPARSE, "%s: not a sagitta recovery file (bad header)", file);
    }
    info->pid = (long)pid->valuedouble;
    info->time = (long long)t->valuedouble;
    if (put(info->path, sizeof info->path, "%s",
            cJSON_IsString(path) ? path->valuestring : "") != 0) {
        cJSON_Delete(h);
        return sg_diag_set(d, SG_EPARSE, "%s: the design's path is too long", file);
    }
    s = json_str(h, "start");
    info->start = s ? strtoull(s, NULL, 10) : 0;
    snprintf(info->boot, sizeof info->boot, "%s", (s = json_str(h, "boot")) ? s : "");
    snprintf(info->host, sizeof info->host, "%s", (s = json_str(h, "host")) ? s : "");
    read_stamp(h, &info->disk);
    cJSON_Delete(h);
    info->orphan = rec_is_orphan(info);
    return SG_OK;
}

/* The whole file in a malloc'ed buffer, NUL-terminated. */
static char *slurp(const char *file, size_t *len, sg_diag *d)
{
    struct stat st;
    char *buf;
    size_t got = 0;
    int fd = open(file, O_RDONLY);
    if (fd < 0) {
        sg_diag_set(d, SG_EIO, "%s: %s", file, strerror(errno));
        return NULL;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || (size_t)st.st_size > REC_FILE_MAX) {
        close(fd);
        sg_diag_set(d, SG_EIO, "%s: not a regular file of a sensible size", file);
        return NULL;
    }
    buf = malloc((size_t)st.st_size + 1);
    if (!buf) {
        close(fd);
        sg_diag_set(d, SG_ENOMEM, "%s: out of memory", file);
        return NULL;
    }
    while (got < (size_t)st.st_size) {
        ssize_t k = read(fd, buf + got, (size_t)st.st_size - got);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            break;
        got += (size_t)k;
    }
    close(fd);
    buf[got] = '\0';
    *len = got;
    return buf;
}

int rec_read_file(const char *file, rec_info *info, sg_system *sys, sg_diag *d)
{
    char *buf, *nl;
    size_t len;
    int rc;
    memset(info, 0, sizeof *info);
    if (put(info->file, sizeof info->file, "%s", file) != 0)
        return sg_diag_set(d, SG_EINVAL, "recovery file name too long");
    if (!sys) {
        /* Listing needs only the header line. */
        FILE *f = fopen(file, "r");
        char *line = NULL;
        size_t cap = 0;
        ssize_t k;
        if (!f)
            return sg_diag_set(d, SG_EIO, "%s: %s", file, strerror(errno));
        k = getline(&line, &cap, f);
        fclose(f);
        if (k <= 0 || k > REC_HEADER_MAX) {
            free(line);
            return sg_diag_set(d, SG_EPARSE, "%s: not a sagitta recovery file", file);
        }
        rc = parse_header(file, line, (size_t)k, info, d);
        free(line);
        return rc;
    }
    buf = slurp(file, &len, d);
    if (!buf)
        return d ? d->code : SG_EIO;
    nl = memchr(buf, '\n', len < REC_HEADER_MAX ? len : REC_HEADER_MAX);
    if (!nl) {
        free(buf);
        return sg_diag_set(d, SG_EPARSE, "%s: not a sagitta recovery file", file);
    }
    rc = parse_header(file, buf, (size_t)(nl - buf), info, d);
    if (rc == SG_OK)
        rc = sg_design_parse(sys, nl + 1, len - (size_t)(nl + 1 - buf), file, d);
    free(buf);
    return rc;
}

static int newest_first(const void *a, const void *b)
{
    const rec_info *x = a, *y = b;
    if (x->time != y->time)
        return x->time > y->time ? -1 : 1;
    return strcmp(x->file, y->file);
}

int rec_orphans(const char *dir, const char *abspath, const char *skip, rec_info **out)
{
    DIR *dp;
    struct dirent *de;
    rec_info *v = NULL, info;
    int n = 0, cap = 0;
    size_t sl = strlen(REC_SUFFIX);
    char file[REC_PATH];
    *out = NULL;
    dp = opendir(dir);
    if (!dp)
        return errno == ENOENT ? 0 : -1;
    while ((de = readdir(dp)) != NULL) {
        size_t len = strlen(de->d_name);
        if (de->d_name[0] == '.' || len <= sl || strcmp(de->d_name + len - sl, REC_SUFFIX) != 0 ||
            put(file, sizeof file, "%s/%s", dir, de->d_name) != 0)
            continue;
        if (skip && strcmp(file, skip) == 0)
            continue;
        /* A file that cannot be read as ours is left alone, not offered. */
        if (rec_read_file(file, &info, NULL, NULL) != SG_OK || !info.orphan)
            continue;
        if (abspath && strcmp(info.path, abspath) != 0)
            continue;
        if (n == cap) {
            rec_info *nv = realloc(v, (size_t)(cap ? cap * 2 : 4) * sizeof *nv);
            if (!nv)
                break;
            v = nv;
            cap = cap ? cap * 2 : 4;
        }
        v[n++] = info;
    }
    closedir(dp);
    if (n > 1)
        qsort(v, (size_t)n, sizeof *v, newest_first);
    *out = v;
    return n;
}

void rec_sweep_temps(const char *dir)
{
    DIR *dp = opendir(dir);
    struct dirent *de;
    char file[REC_PATH];
    struct stat st;
    time_t now = time(NULL);
    if (!dp)
        return;
    while ((de = readdir(dp)) != NULL) {
        const char *t = strstr(de->d_name, REC_SUFFIX ".tmp");
        size_t len = strlen(de->d_name), ll = strlen(REC_LOCK_SUFFIX);
        rec_info info;
        /* A lock left by an editor that died holds no work. */
        if (len > ll && strcmp(de->d_name + len - ll, REC_LOCK_SUFFIX) == 0) {
            if (put(file, sizeof file, "%s/%s", dir, de->d_name) == 0 &&
                rec_read_file(file, &info, NULL, NULL) == SG_OK && info.orphan)
                (void)unlink(file);
            continue;
        }
        if (!t || strlen(t) != strlen(REC_SUFFIX ".tmp") + 6 ||
            put(file, sizeof file, "%s/%s", dir, de->d_name) != 0)
            continue;
        if (lstat(file, &st) == 0 && S_ISREG(st.st_mode) && st.st_mtime + 60 < now)
            (void)unlink(file);
    }
    closedir(dp);
}

/* ------------------------------------------------------------------------
 * The editor's own file
 * ------------------------------------------------------------------------ */

/* Creates dir and any missing parents with mode 0700, as the XDG rules
 * ask, and checks that it is ours. */
static int make_dir(const char *dir, char *err, size_t n)
{
    char p[REC_PATH];
    size_t i;
    struct stat st;
    if (put(p, sizeof p, "%s", dir) != 0)
        return put(err, n, "%s: name too long", dir), -1;
    for (i = 1; p[i]; i++) {
        if (p[i] != '/')
            continue;
        p[i] = '\0';
        if (mkdir(p, 0700) != 0 && errno != EEXIST)
            return put(err, n, "%s: %s", p, strerror(errno)), -1;
        p[i] = '/';
    }
    if (mkdir(p, 0700) != 0 && errno != EEXIST)
        return put(err, n, "%s: %s", p, strerror(errno)), -1;
    if (stat(p, &st) != 0 || !S_ISDIR(st.st_mode))
        return put(err, n, "%s: not a directory", p), -1;
    /* Another user's directory could be made to feed us a design. */
    if (st.st_uid != geteuid())
        return put(err, n, "%s: owned by another user", p), -1;
    return 0;
}

static unsigned long long fnv1a(const char *s)
{
    unsigned long long h = 14695981039346656037ULL;
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 1099511628211ULL;
    }
    return h;
}

/* Picks a free name for our file: BASE-HASH-PID.sgrec (or untitled-PID),
 * with a counter when an older file has the name (a pid used again). */
static int claim(const char *dir, const char *key, const char *suffix, char *out, size_t n)
{
    char base[49], stem[REC_PATH];
    const char *b = strrchr(key, '/');
    struct stat st;
    size_t i;
    int k;
    if (key[0]) {
        b = b ? b + 1 : key;
        for (i = 0; b[i] && i + 1 < sizeof base; i++)
            base[i] = isalnum((unsigned char)b[i]) || strchr("._+-", b[i]) ? b[i] : '_';
        base[i] = '\0';
        if (base[0] == '.')
            base[0] = '_';
        if (put(stem, sizeof stem, "%s/%s-%016llx-%ld", dir, base, fnv1a(key), (long)getpid()) !=
            0)
            return -1;
    } else if (put(stem, sizeof stem, "%s/untitled-%ld", dir, (long)getpid()) != 0) {
        return -1;
    }
    for (k = 0; k < 100; k++) {
        if (k == 0 ? put(out, n, "%s%s", stem, suffix)
                   : put(out, n, "%s-%d%s", stem, k, suffix))
            return -1;
        if (lstat(out, &st) != 0 && errno == ENOENT)
            return 0;
    }
    return -1;
}

static void unlink_quiet(char *file)
{
    if (file[0])
        (void)unlink(file);
    file[0] = '\0';
}

/* Keeps our lock file in line with the document's name: one small file
 * saying that this editor has that design open. */
static void hold(ed *e)
{
    recov *r = &e->rec;
    const char *p = doc_path(&e->doc);
    char dir[REC_PATH], key[REC_PATH], err[ED_MSG], *head;
    int fd;
    if (p ? strcmp(p, r->lock_for) == 0 : !r->lock_for[0])
        return;
    unlink_quiet(r->lock);
    r->lock_for[0] = '\0';
    if (!p || put(r->lock_for, sizeof r->lock_for, "%s", p) != 0 ||
        rec_dir(dir, sizeof dir) != 0 || rec_abspath(p, key, sizeof key) != 0 ||
        make_dir(dir, err, sizeof err) != 0 ||
        claim(dir, key, REC_LOCK_SUFFIX, r->lock, sizeof r->lock) != 0) {
        r->lock[0] = '\0';
        return;
    }
    head = header_json(key, NULL);
    fd = head ? open(r->lock, O_WRONLY | O_CREAT | O_EXCL, 0600) : -1;
    if (fd < 0 || write_all(fd, head, strlen(head)) != 0 || write_all(fd, "\n", 1) != 0) {
        if (fd >= 0)
            unlink(r->lock);
        r->lock[0] = '\0';
    }
    if (fd >= 0)
        close(fd);
    free(head);
}

int rec_holders(const char *dir, const char *abspath, rec_info *first)
{
    DIR *dp;
    struct dirent *de;
    rec_info info;
    char file[REC_PATH];
    size_t ll = strlen(REC_LOCK_SUFFIX), rl = strlen(REC_SUFFIX);
    int n = 0;
    dp = opendir(dir);
    if (!dp)
        return 0;
    while ((de = readdir(dp)) != NULL) {
        size_t len = strlen(de->d_name);
        int lock = len > ll && strcmp(de->d_name + len - ll, REC_LOCK_SUFFIX) == 0;
        int rec = len > rl && strcmp(de->d_name + len - rl, REC_SUFFIX) == 0;
        if (de->d_name[0] == '.' || !(lock || rec) ||
            put(file, sizeof file, "%s/%s", dir, de->d_name) != 0 ||
            rec_read_file(file, &info, NULL, NULL) != SG_OK)
            continue;
        if (info.orphan) {
            /* A lock holds no work, so the one a dead editor left goes. */
            if (lock)
                (void)unlink(file);
            continue;
        }
        if (info.pid == (long)getpid() || strcmp(info.path, abspath) != 0)
            continue;
        if (n++ == 0 && first)
            *first = info;
    }
    closedir(dp);
    return n;
}

int rec_sync(ed *e, int force)
{
    recov *r = &e->rec;
    char key[REC_PATH], dir[REC_PATH], err[ED_MSG];
    const char *p = doc_path(&e->doc);
    int mod;
    double now;
    sg_diag d;

    if (!r->enabled || r->closed)
        return -1;
    hold(e);
    mod = doc_modified(&e->doc);
    key[0] = '\0';
    if (mod && p && rec_abspath(p, key, sizeof key) != 0)
        snprintf(key, sizeof key, "%s", p);
    /* Saved, undone back to the file, or renamed: the old copy goes. */
    if (r->file[0] && (!mod || strcmp(key, r->key) != 0))
        unlink_quiet(r->file);
    if (!mod || (r->file[0] && e->doc.id == r->written_id)) {
        r->pending = 0;
        return -1;
    }
    now = compute_now_ms();
    if (!force && r->last_ms > 0 && now - r->last_ms < r->gap_ms) {
        r->pending = 1;
        return (int)(r->gap_ms - (now - r->last_ms)) + 1;
    }
    r->last_ms = now;
    r->gap_ms = REC_DEBOUNCE_MS; /* a failed write is retried this often */
    r->pending = 1; /* until the write succeeds; the loop retries */
    err[0] = '\0';
    if (!r->file[0]) {
        if (rec_dir(dir, sizeof dir) != 0)
            snprintf(err, sizeof err, "neither XDG_STATE_HOME nor HOME is set");
        else if (make_dir(dir, err, sizeof err) == 0 &&
                 claim(dir, key, REC_SUFFIX, r->file, sizeof r->file) != 0)
            snprintf(err, sizeof err, "%.900s: no free name", dir);
        if (err[0])
            r->file[0] = '\0';
        else
            snprintf(r->key, sizeof r->key, "%s", key);
    }
    if (!err[0]) {
        /* A failed write leaves the previous copy, older but better than
         * none, under the name we keep. */
        sg_diag_clear(&d);
        if (rec_write_file(r->file, key, e->doc.sys, &e->doc.disk, &d) != SG_OK)
            snprintf(err, sizeof err, "%s", d.msg);
    }
    if (err[0]) {
        if (!r->failing)
            ed_msg(e, 1, "cannot keep a recovery file (%s): unsaved edits are not protected",
                   err);
        r->failing = 1;
        return (int)REC_DEBOUNCE_MS;
    }
    r->written_id = e->doc.id;
    r->gap_ms = REC_COST_FACTOR * (compute_now_ms() - now);
    if (r->gap_ms > REC_DEBOUNCE_MS)
        r->gap_ms = REC_DEBOUNCE_MS;
    r->pending = 0;
    r->failing = 0;
    /* Our own copy now holds what the adopted orphan held, or more. */
    if (r->adopted[0] && strcmp(r->adopted, r->file) != 0)
        unlink_quiet(r->adopted);
    return -1;
}

void rec_finish(ed *e)
{
    recov *r = &e->rec;
    unlink_quiet(r->file);
    unlink_quiet(r->lock);
    r->pending = 0;
    r->closed = 1;
}

void rec_saved(ed *e)
{
    unlink_quiet(e->rec.adopted);
}
