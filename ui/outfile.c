/* outfile.c - a report file that appears whole or not at all. */
/* realpath() and fchmod() are X/Open. */
#define _XOPEN_SOURCE 700
#include "outfile.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* A larger buffer than stdio's, when memory allows; without it the
 * stream keeps its own. */
static void big_buffer(outfile *o)
{
    o->buf = malloc(OUTFILE_BUF);
    if (o->buf && setvbuf(o->f, o->buf, _IOFBF, OUTFILE_BUF) != 0) {
        free(o->buf);
        o->buf = NULL;
    }
}

/* fclose's result; the buffer goes after the stream that used it. */
static int close_file(outfile *o)
{
    int rc = fclose(o->f);
    free(o->buf);
    o->buf = NULL;
    return rc;
}

/* Writes in place, as fopen(path, "w") does. */
static int in_place(outfile *o, const char *path)
{
    o->tmp[0] = '\0';
    o->f = fopen(path, "w");
    if (!o->f)
        return errno;
    big_buffer(o);
    return 0;
}

int outfile_open(outfile *o, const char *path, FILE *std)
{
    struct stat st;
    const char *slash;
    int fd, err;
    memset(o, 0, sizeof *o);
    if (!path || strcmp(path, "-") == 0) {
        o->f = std;
        return 0;
    }
    o->path = path;
    snprintf(o->target, sizeof o->target, "%s", path);
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
        char *real = realpath(path, NULL);
        if (real) {
            snprintf(o->target, sizeof o->target, "%s", real);
            free(real);
        }
    }
    if (stat(o->target, &st) == 0 && (!S_ISREG(st.st_mode) || st.st_nlink > 1))
        return in_place(o, path);
    slash = strrchr(o->target, '/');
    if (slash)
        snprintf(o->tmp, sizeof o->tmp, "%.*s.sagitta-XXXXXX", (int)(slash - o->target + 1),
                 o->target);
    else
        snprintf(o->tmp, sizeof o->tmp, ".sagitta-XXXXXX");
    fd = mkstemp(o->tmp);
    if (fd < 0)
        /* A directory we may not create in: write in place after all. */
        return in_place(o, path);
    if (stat(o->target, &st) == 0) {
        if (fchmod(fd, st.st_mode & 07777) != 0) {
            /* Not ours to chmod: in place keeps owner and mode. */
            close(fd);
            unlink(o->tmp);
            return in_place(o, path);
        }
    } else {
        mode_t mask = umask(0);
        umask(mask);
        /* Failing, mkstemp's 0600 is a safe mode to keep. */
        (void)!fchmod(fd, 0666 & ~mask);
    }
    o->f = fdopen(fd, "w");
    if (!o->f) {
        err = errno;
        close(fd);
        unlink(o->tmp);
        o->tmp[0] = '\0';
        return err;
    }
    big_buffer(o);
    return 0;
}

int outfile_commit(outfile *o)
{
    int err = 0;
    if (!o->f)
        return EINVAL;
    if (fflush(o->f) != 0 || ferror(o->f))
        err = errno ? errno : EIO;
    if (o->path) {
        if (close_file(o) != 0 && !err)
            err = errno ? errno : EIO;
    }
    o->f = NULL;
    if (o->tmp[0]) {
        if (!err && rename(o->tmp, o->target) != 0)
            err = errno;
        if (err)
            unlink(o->tmp);
        o->tmp[0] = '\0';
    }
    return err;
}

void outfile_abort(outfile *o)
{
    if (o->f && o->path)
        close_file(o);
    else if (o->f)
        fflush(o->f);
    if (o->tmp[0])
        unlink(o->tmp);
    o->tmp[0] = '\0';
    o->f = NULL;
}
