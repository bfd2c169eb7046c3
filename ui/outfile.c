/* outfile.c - a report file that appears whole or not at all. */
/* fchmod() and readlink() are X/Open. */
#define _XOPEN_SOURCE 700
#include "outfile.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* ------------------------------------------------------------------------
 * Temporary files removed by the signals that end the program
 * ------------------------------------------------------------------------ */

/* Each slot's name is written before it is marked used and unmarked before
 * it is reused, so the handler reads only whole names; the names live here,
 * not in the callers' memory, which a signal may find freed. */
static char temp_name[OUTFILE_TEMPS][4096 + 32];
static volatile sig_atomic_t temp_used[OUTFILE_TEMPS];
static pthread_mutex_t temp_lock = PTHREAD_MUTEX_INITIALIZER;
static int handlers_set;

static const int end_signals[] = {SIGHUP,  SIGINT,  SIGQUIT, SIGTERM,   SIGPIPE, SIGALRM,
                                  SIGUSR1, SIGUSR2, SIGXCPU, SIGXFSZ, SIGVTALRM, SIGPROF};
#define N_END_SIGNALS ((int)(sizeof end_signals / sizeof end_signals[0]))

/* unlink() is async-signal-safe; SA_RESETHAND has put the default action
 * back, so the signal raised again on return ends the program as it would
 * have without us (status, core dump and all). */
static void on_end_signal(int sig)
{
    int k, saved = errno;
    for (k = 0; k < OUTFILE_TEMPS; k++)
        if (temp_used[k])
            (void)unlink(temp_name[k]);
    (void)raise(sig);
    errno = saved;
}

static void set_handlers(void)
{
    struct sigaction sa, old;
    int k;
    if (handlers_set)
        return;
    handlers_set = 1;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_end_signal;
    sigemptyset(&sa.sa_mask);
    for (k = 0; k < N_END_SIGNALS; k++)
        sigaddset(&sa.sa_mask, end_signals[k]);
    sa.sa_flags = SA_RESETHAND;
    for (k = 0; k < N_END_SIGNALS; k++)
        if (sigaction(end_signals[k], NULL, &old) == 0 && !(old.sa_flags & SA_SIGINFO) &&
            old.sa_handler == SIG_DFL)
            (void)sigaction(end_signals[k], &sa, NULL);
}

void outfile_block_signals(sigset_t *old)
{
    sigset_t set;
    int k;
    sigemptyset(&set);
    for (k = 0; k < N_END_SIGNALS; k++)
        sigaddset(&set, end_signals[k]);
    pthread_sigmask(SIG_BLOCK, &set, old);
}

void outfile_restore_signals(const sigset_t *old)
{
    pthread_sigmask(SIG_SETMASK, old, NULL);
}

int outfile_track(const char *path)
{
    int k, slot = -1;
    if (!path || strlen(path) >= sizeof temp_name[0])
        return -1;
    pthread_mutex_lock(&temp_lock);
    set_handlers();
    for (k = 0; k < OUTFILE_TEMPS && slot < 0; k++)
        if (!temp_used[k]) {
            strcpy(temp_name[k], path);
            /* The whole name before the mark, for a handler on this thread. */
            atomic_signal_fence(memory_order_seq_cst);
            temp_used[k] = 1;
            slot = k;
        }
    pthread_mutex_unlock(&temp_lock);
    return slot;
}

void outfile_untrack(int slot)
{
    if (slot < 0 || slot >= OUTFILE_TEMPS)
        return;
    pthread_mutex_lock(&temp_lock);
    temp_used[slot] = 0;
    pthread_mutex_unlock(&temp_lock);
}

void outfile_temp_hook(const char *path, int add)
{
    int k;
    if (add) {
        (void)outfile_track(path);
        return;
    }
    pthread_mutex_lock(&temp_lock);
    for (k = 0; k < OUTFILE_TEMPS; k++)
        if (temp_used[k] && strcmp(temp_name[k], path) == 0) {
            temp_used[k] = 0;
            break;
        }
    pthread_mutex_unlock(&temp_lock);
}

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

/* Follows a chain of symbolic links in buf (a path) to its end, whether
 * that exists or not: a dangling link is written through and stays a
 * link.  A loop is left as it is (the rename then fails). */
static void link_target(char *buf, size_t n)
{
    char link[4096], next[4096 + 4096];
    struct stat st;
    int hops;
    for (hops = 0; hops < 40; hops++) {
        const char *slash;
        ssize_t k;
        if (lstat(buf, &st) != 0 || !S_ISLNK(st.st_mode))
            return;
        k = readlink(buf, link, sizeof link - 1);
        if (k < 0)
            return;
        link[k] = '\0';
        /* A relative link is relative to the link's own directory. */
        slash = strrchr(buf, '/');
        if (link[0] != '/' && slash)
            snprintf(next, sizeof next, "%.*s%s", (int)(slash - buf + 1), buf, link);
        else
            snprintf(next, sizeof next, "%s", link);
        if (strlen(next) >= n)
            return;
        strcpy(buf, next);
    }
}

/* Removes the temporary and its listing. */
static void drop_temp(outfile *o)
{
    sigset_t old;
    outfile_block_signals(&old);
    unlink(o->tmp);
    outfile_untrack(o->slot);
    o->slot = -1;
    o->tmp[0] = '\0';
    outfile_restore_signals(&old);
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
    sigset_t old;
    memset(o, 0, sizeof *o);
    o->slot = -1;
    if (!path || strcmp(path, "-") == 0) {
        o->f = std;
        return 0;
    }
    o->path = path;
    snprintf(o->target, sizeof o->target, "%s", path);
    link_target(o->target, sizeof o->target);
    if (stat(o->target, &st) == 0 && (!S_ISREG(st.st_mode) || st.st_nlink > 1))
        return in_place(o, path);
    slash = strrchr(o->target, '/');
    if (slash)
        snprintf(o->tmp, sizeof o->tmp, "%.*s.sagitta-XXXXXX", (int)(slash - o->target + 1),
                 o->target);
    else
        snprintf(o->tmp, sizeof o->tmp, ".sagitta-XXXXXX");
    outfile_block_signals(&old);
    fd = mkstemp(o->tmp);
    if (fd >= 0)
        o->slot = outfile_track(o->tmp);
    outfile_restore_signals(&old);
    if (fd < 0)
        /* A directory we may not create in: write in place after all. */
        return in_place(o, path);
    if (stat(o->target, &st) == 0) {
        struct stat now;
        /* The new file keeps the old one's owner and group, then (chown
         * clears set-id bits) its mode; where it cannot, the rename would
         * change them. */
        if (fstat(fd, &now) != 0 ||
            ((now.st_uid != st.st_uid || now.st_gid != st.st_gid) &&
             fchown(fd, st.st_uid, st.st_gid) != 0) ||
            fchmod(fd, st.st_mode & 07777) != 0) {
            /* Not ours to chown or chmod: in place keeps owner and mode. */
            close(fd);
            drop_temp(o);
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
        drop_temp(o);
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
        sigset_t old;
        /* Renamed and unlisted together: a signal meanwhile waits, and
         * then finds the file whole in place. */
        outfile_block_signals(&old);
        if (!err && rename(o->tmp, o->target) != 0)
            err = errno;
        if (err)
            unlink(o->tmp);
        outfile_untrack(o->slot);
        o->slot = -1;
        o->tmp[0] = '\0';
        outfile_restore_signals(&old);
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
        drop_temp(o);
    o->f = NULL;
}
