/*
 * fileio.c - whole files read and text saved atomically, for every format
 * (design_json.c, design_zmx.c, zar.c), so none of them reaches into
 * another for it.
 */
#define _XOPEN_SOURCE 700

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "formats_int.h"

int sg_read_file(const char *path, size_t max, char **out, size_t *outlen, sg_diag *d)
{
    FILE *f;
    struct stat st;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int e;

    *out = NULL;
    *outlen = 0;
    f = fopen(path, "rb");
    if (!f) {
        e = errno;
        return sg_diag_set(d, SG_EIO, "%s: cannot open: %s", path, strerror(e));
    }
    if (fstat(fileno(f), &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            fclose(f);
            return sg_diag_set(d, SG_EIO, "%s: cannot read: %s", path, strerror(EISDIR));
        }
        if (S_ISREG(st.st_mode) && (unsigned long long)st.st_size > max) {
            fclose(f);
            return sg_diag_set(d, SG_ERANGE, "%s: the file is %lld bytes; the limit is %zu (64 MiB)",
                               path, (long long)st.st_size, max);
        }
    }
    /* Read in chunks: a pipe or a file that grows has no reliable size. */
    for (;;) {
        size_t got;
        if (len == cap) {
            size_t ncap = cap ? cap * 2 : 65536;
            char *p;
            if (ncap > max + 1)
                ncap = max + 1;
            if (ncap <= cap) {
                free(buf);
                fclose(f);
                return sg_diag_set(d, SG_ERANGE, "%s: the file is larger than %zu bytes (64 MiB)",
                                   path, max);
            }
            p = realloc(buf, ncap);
            if (!p) {
                free(buf);
                fclose(f);
                return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
            }
            buf = p;
            cap = ncap;
        }
        got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0)
            break;
    }
    if (ferror(f)) {
        e = errno;
        free(buf);
        fclose(f);
        return sg_diag_set(d, SG_EIO, "%s: cannot read: %s", path, strerror(e));
    }
    fclose(f);
    if (len > max) {
        free(buf);
        return sg_diag_set(d, SG_ERANGE, "%s: the file is larger than %zu bytes (64 MiB)", path,
                           max);
    }
    *out = buf;
    *outlen = len;
    return SG_OK;
}

/* A text that opens with a UTF-16 byte order mark, as UTF-8 (without the
 * mark) in *out; SG_EPARSE naming the byte offset of an unpaired surrogate
 * or a stray last byte.  A line break stays a line break, so a later error's
 * line number is the file's. */
/* The permissions a new file would get: 0666 less the umask.  The umask is
 * read from /proc, since umask() can only be read by changing it, which
 * would race with other threads creating files. */
static mode_t new_file_mode(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[128];
    unsigned mask = 022;
    if (f) {
        while (fgets(line, sizeof line, f))
            if (sscanf(line, "Umask: %o", &mask) == 1)
                break;
        fclose(f);
    }
    return (mode_t)(0666 & ~mask);
}

/* Makes the rename durable; failure here loses nothing already written. */
static void sync_parent_dir(const char *path)
{
    char *dir = malloc(strlen(path) + 2);
    char *slash;
    int fd;
    if (!dir)
        return;
    strcpy(dir, path);
    slash = strrchr(dir, '/');
    if (!slash)
        strcpy(dir, ".");
    else if (slash == dir)
        dir[1] = '\0';
    else
        *slash = '\0';
    fd = open(dir, O_RDONLY);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
    free(dir);
}

static sg_temp_hook temp_hook;

void sg_set_temp_hook(sg_temp_hook hook)
{
    temp_hook = hook;
}

/* The file a save writes: path, or where its chain of symbolic links ends,
 * whether that exists or not (a dangling link is written through, so it
 * stays a link, as vim does).  NULL with errno set: out of memory, or a
 * loop of links. */
static char *save_target(const char *path)
{
    char *cur = malloc(strlen(path) + 1), *next, buf[4096];
    struct stat st;
    int hops;
    if (!cur)
        return NULL;
    strcpy(cur, path);
    for (hops = 0; hops < 40; hops++) {
        const char *slash;
        size_t dl;
        ssize_t n;
        if (lstat(cur, &st) != 0 || !S_ISLNK(st.st_mode))
            return cur;
        n = readlink(cur, buf, sizeof buf - 1);
        if (n < 0) {
            free(cur);
            return NULL;
        }
        buf[n] = '\0';
        /* A relative link is relative to the link's own directory. */
        slash = strrchr(cur, '/');
        dl = buf[0] != '/' && slash ? (size_t)(slash - cur) + 1 : 0;
        next = malloc(dl + (size_t)n + 1);
        if (!next) {
            free(cur);
            return NULL;
        }
        memcpy(next, cur, dl);
        memcpy(next + dl, buf, (size_t)n + 1);
        free(cur);
        cur = next;
    }
    free(cur);
    errno = ELOOP;
    return NULL;
}

static int write_all_fd(int fd, const char *p, size_t n)
{
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return -1;
        }
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* A backup of old beside target, else in $TMPDIR or /tmp (mode 0600);
 * its name into *name (malloc'ed).  Returns 0 or -1 with errno set. */
static int write_backup(const char *target, const char *old, size_t oldlen, char **name)
{
    const char *slash = strrchr(target, '/'), *tmpdir = getenv("TMPDIR");
    const char *dirs[3];
    size_t dl[3];
    int k, fd, e = EACCES;
    dirs[0] = target;
    dl[0] = slash ? (size_t)(slash - target) + 1 : 0;
    dirs[1] = tmpdir && tmpdir[0] == '/' ? tmpdir : "/tmp";
    dl[1] = strlen(dirs[1]);
    dirs[2] = "/tmp";
    dl[2] = 4;
    for (k = 0; k < 3; k++) {
        char *b = malloc(dl[k] + sizeof "/.sagitta-bak-XXXXXX");
        if (!b)
            return -1;
        memcpy(b, dirs[k], dl[k]);
        strcpy(b + dl[k], k == 0 ? ".sagitta-bak-XXXXXX" : "/sagitta-bak-XXXXXX");
        fd = mkstemp(b);
        if (fd >= 0) {
            if (write_all_fd(fd, old, oldlen) == 0 && fsync(fd) == 0 && close(fd) == 0) {
                *name = b;
                return 0;
            }
            e = errno;
            close(fd);
            unlink(b);
        } else {
            e = errno;
        }
        free(b);
    }
    errno = e;
    return -1;
}

/* Rewrites target in place, keeping its inode, owner, group and mode: for
 * a file in a directory we may not create in, or whose owner a new file
 * could not keep.  A backup of the old bytes is made first (vim's
 * 'backup'); should the rewrite fail the old bytes are put back, or the
 * message names the backup.  No backup, no save. */
static int save_in_place(const char *path, const char *target, const char *text, size_t len,
                         sg_diag *d)
{
    char *old = NULL, *bak = NULL, *nb;
    size_t oldlen = 0, cap = 0;
    ssize_t got;
    int fd, e, rc;
    fd = open(target, O_RDWR);
    if (fd < 0) {
        e = errno;
        return sg_diag_set(d, SG_EIO, "%s: cannot write: %s", path, strerror(e));
    }
    for (;;) {
        if (cap - oldlen < 65536) {
            cap = cap ? 2 * cap : 65536;
            nb = realloc(old, cap);
            if (!nb) {
                rc = sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
                goto out;
            }
            old = nb;
        }
        got = read(fd, old + oldlen, cap - oldlen);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            e = errno;
            rc = sg_diag_set(d, SG_EIO, "%s: cannot read it to back it up: %s", path,
                             strerror(e));
            goto out;
        }
        if (got == 0)
            break;
        oldlen += (size_t)got;
    }
    if (write_backup(target, old, oldlen, &bak) != 0) {
        e = errno;
        rc = sg_diag_set(d, SG_EIO, "%s: not saved: its directory cannot be written and no "
                                    "backup could be made: %s", path, strerror(e));
        goto out;
    }
    if (lseek(fd, 0, SEEK_SET) != 0 || write_all_fd(fd, text, len) != 0 ||
        ftruncate(fd, (off_t)len) != 0 || fsync(fd) != 0) {
        e = errno;
        if (lseek(fd, 0, SEEK_SET) == 0 && write_all_fd(fd, old, oldlen) == 0 &&
            ftruncate(fd, (off_t)oldlen) == 0 && fsync(fd) == 0) {
            unlink(bak);
            rc = sg_diag_set(d, SG_EIO, "%s: cannot write: %s (the file is as it was)", path,
                             strerror(e));
        } else {
            rc = sg_diag_set(d, SG_EIO, "%s: cannot write: %s; its old content is in %s", path,
                             strerror(e), bak);
        }
        goto out;
    }
    unlink(bak);
    rc = SG_OK;
out:
    close(fd);
    free(bak);
    free(old);
    return rc;
}

int sg_save_text_atomic(const char *path, const char *text, size_t len, sg_diag *d)
{
    char *tmp, *target;
    const char *slash;
    size_t dirlen;
    struct stat st, now;
    FILE *f;
    int fd, e, have;
    /* Saving through a symbolic link writes the file it points at, even
     * one not there yet; renaming over the link itself would replace it
     * with a plain file. */
    target = save_target(path);
    if (!target) {
        e = errno;
        return sg_diag_set(d, e == ENOMEM ? SG_ENOMEM : SG_EIO, "%s: %s", path, strerror(e));
    }
    have = stat(target, &st) == 0 && S_ISREG(st.st_mode);
    /* A file with other hard links: a rename would give the new text a new
     * inode and leave every other link on the old bytes. */
    if (have && st.st_nlink > 1) {
        int rc = save_in_place(path, target, text, len, d);
        free(target);
        return rc;
    }
    /* The temporary file is a short hidden name in the target's directory,
     * so even a name at the file system's length limit can be saved. */
    slash = strrchr(target, '/');
    dirlen = slash ? (size_t)(slash - target) + 1 : 0;
    tmp = malloc(dirlen + sizeof ".sagitta-XXXXXX");
    if (!tmp) {
        free(target);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
    }
    memcpy(tmp, target, dirlen);
    strcpy(tmp + dirlen, ".sagitta-XXXXXX");
    fd = mkstemp(tmp);
    if (fd < 0) {
        int rc;
        e = errno;
        free(tmp);
        /* A writable file in a directory we may not create in: in place. */
        if ((e == EACCES || e == EPERM) && have) {
            rc = save_in_place(path, target, text, len, d);
            free(target);
            return rc;
        }
        free(target);
        return sg_diag_set(d, SG_EIO, "%s: cannot create a temporary file: %s", path, strerror(e));
    }
    if (temp_hook)
        temp_hook(tmp, 1);
    if (have) {
        /* The new file keeps the old one's owner and group (root may give
         * any; an owner may give a group of theirs); where it cannot, the
         * rename would change them, so the file is rewritten in place. */
        if (fstat(fd, &now) != 0 ||
            ((now.st_uid != st.st_uid || now.st_gid != st.st_gid) &&
             fchown(fd, st.st_uid, st.st_gid) != 0)) {
            int rc;
            close(fd);
            unlink(tmp);
            if (temp_hook)
                temp_hook(tmp, 0);
            free(tmp);
            rc = save_in_place(path, target, text, len, d);
            free(target);
            return rc;
        }
        /* After the chown, which clears set-id bits: the old mode whole. */
        (void)fchmod(fd, st.st_mode & 07777);
    } else {
        /* mkstemp makes the file 0600; give a new file the mode open()
         * would have. */
        (void)fchmod(fd, new_file_mode());
    }
    f = fdopen(fd, "w");
    if (!f) {
        e = errno;
        close(fd);
        goto fail;
    }
    errno = 0;
    if (fwrite(text, 1, len, f) != len || fflush(f) != 0 || fsync(fileno(f)) != 0) {
        e = errno ? errno : EIO;
        fclose(f);
        goto fail;
    }
    if (fclose(f) != 0) {
        e = errno;
        goto fail;
    }
    if (rename(tmp, target) != 0) {
        e = errno;
        goto fail;
    }
    if (temp_hook)
        temp_hook(tmp, 0);
    sync_parent_dir(target);
    free(tmp);
    free(target);
    return SG_OK;

fail:
    unlink(tmp);
    if (temp_hook)
        temp_hook(tmp, 0);
    free(tmp);
    free(target);
    return sg_diag_set(d, SG_EIO, "%s: cannot write: %s", path, strerror(e));
}
