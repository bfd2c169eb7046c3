/*
 * datadir.c - where the data that installs with sagitta (glass catalogs,
 * example designs) lies.
 *
 * A program running from the build tree reads the source tree's copies, so
 * an edit to lensdb/ shows without installing.  Anything else looks beside
 * itself: the installed program in bindir, or the shared library in libdir,
 * finds DATADIR/sagitta/NAME by the same relative path the install made,
 * so a relocated or DESTDIR install still finds its own data and never a
 * source tree.  The configured absolute path is the last resort.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sagitta.h"
#include "sg_config.h"

/* An object of this file, whose address dladdr turns into the path of the
 * program or library that holds it. */
static const char sg_data_marker = 0;

static int is_dir(const char *p)
{
    struct stat st;
    return p && *p && stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

/* Whether absolute path p lies inside directory root. */
static int inside(const char *p, const char *root)
{
    size_t n = strlen(root);
    return strncmp(p, root, n) == 0 && (p[n] == '/' || p[n] == '\0');
}

/* The relative path from absolute directory from to absolute path to,
 * both as configured (no links, no dots): "../share/sagitta/lensdb". */
static int relative(const char *from, const char *to, char *out, size_t n)
{
    size_t common = 0, i, len = 0;
    int w;

    /* The longest shared prefix that ends at a component boundary. */
    for (i = 0; from[i] && from[i] == to[i]; i++)
        if (from[i] == '/')
            common = i;
    if (!from[i] && (to[i] == '/' || !to[i]))
        common = i;
    out[0] = '\0';
    for (i = common; from[i]; i++)
        if (from[i] == '/' && from[i + 1]) {
            w = snprintf(out + len, n - len, "../");
            if (w < 0 || (size_t)w >= n - len)
                return -1;
            len += (size_t)w;
        }
    w = snprintf(out + len, n - len, "%s", to[common] == '/' ? to + common + 1 : to + common);
    return w < 0 || (size_t)w >= n - len ? -1 : 0;
}

/* DATA relative to the directory of the object file obj (a program in
 * bindir or the library in libdir), if that directory exists. */
static const char *beside(const char *obj, const char *data, char *buf, size_t n)
{
    static const char *const homes[] = { SG_INSTALL_BINDIR, SG_INSTALL_LIBDIR };
    char real[PATH_MAX], rel[PATH_MAX], canon[PATH_MAX], *slash;
    size_t k;

    if (!obj || !*obj || !realpath(obj, real))
        return NULL;
    slash = strrchr(real, '/');
    if (!slash)
        return NULL;
    *slash = '\0';
    for (k = 0; k < sizeof homes / sizeof homes[0]; k++) {
        int w;
        if (relative(homes[k], data, rel, sizeof rel) != 0)
            continue;
        w = snprintf(buf, n, "%s/%s", real, rel);
        if (w > 0 && (size_t)w < n && is_dir(buf) && realpath(buf, canon) &&
            strlen(canon) < n)
            return strcpy(buf, canon);
    }
    return NULL;
}

const char *sg_data_dir(const char *name, char *buf, size_t n)
{
    char exe[PATH_MAX], data[PATH_MAX];
    const char *src;
    ssize_t k;
    Dl_info info;
    int w;

    if (!name || !buf || n == 0)
        return NULL;
    if (strcmp(name, "lensdb") == 0)
        src = SG_SOURCE_LENSDB;
    else if (strcmp(name, "examples") == 0)
        src = SG_SOURCE_EXAMPLES;
    else
        return NULL;
    w = snprintf(data, sizeof data, "%s/%s", SG_INSTALL_DATADIR, name);
    if (w < 0 || (size_t)w >= sizeof data)
        return NULL;

    k = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (k > 0) {
        exe[k] = '\0';
        if (inside(exe, SG_BUILD_ROOT) && is_dir(src))
            return src;
        if (beside(exe, data, buf, n))
            return buf;
    }
    if (dladdr(&sg_data_marker, &info) && beside(info.dli_fname, data, buf, n))
        return buf;
    if (is_dir(data) && (size_t)snprintf(buf, n, "%s", data) < n)
        return buf;
    return NULL;
}
