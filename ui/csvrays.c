/* csvrays.c - the ray list read by "sagitta trace --rays FILE.csv". */
#include "csvrays.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "args.h"

#define NCOLS_MAX 6

static const char *const norm_names[4] = { "hx", "hy", "px", "py" };
static const char *const sd_names[6] = { "x", "y", "z", "l", "m", "n" };

typedef struct span {
    const char *p;
    size_t n;
} span;

static int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

static span trim(span s)
{
    while (s.n > 0 && is_blank(s.p[0])) {
        s.p++;
        s.n--;
    }
    while (s.n > 0 && is_blank(s.p[s.n - 1]))
        s.n--;
    return s;
}

/* Copies a field into buf for a message, cut short and with control bytes
 * replaced so a hostile file cannot drive the terminal. */
static const char *show(span s, char *buf, size_t n)
{
    size_t k, m = s.n < n - 1 ? s.n : n - 1;
    for (k = 0; k < m; k++) {
        unsigned char c = (unsigned char)s.p[k];
        buf[k] = (c < 0x20 || c == 0x7f) ? '?' : (char)c;
    }
    buf[m] = '\0';
    if (s.n > m && m >= 3)
        memcpy(buf + m - 3, "...", 3);
    return buf;
}

static int name_is(span s, const char *name)
{
    size_t k, n = strlen(name);
    if (s.n != n)
        return 0;
    for (k = 0; k < n; k++) {
        char c = s.p[k];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != name[k])
            return 0;
    }
    return 1;
}

/* Splits a line at commas; returns the number of fields, or -1 when there
 * are more than max (the count is still reported through *count). */
static int split(span line, span *f, int max, int *count)
{
    int n = 0;
    const char *p = line.p, *end = line.p + line.n;
    for (;;) {
        const char *c = memchr(p, ',', (size_t)(end - p));
        const char *e = c ? c : end;
        if (n < max) {
            f[n].p = p;
            f[n].n = (size_t)(e - p);
        }
        n++;
        if (!c)
            break;
        p = c + 1;
    }
    *count = n;
    return n <= max ? n : -1;
}

static int parse_header(span line, const char *name, long lineno,
                        sg_ray_kind *kind, int *map, int *ncol, sg_diag *d)
{
    char buf[48], unknown[256] = "";
    int k, j, nnorm = 0, nsd = 0, nunknown = 0;
    int seen_norm[4] = { 0 }, seen_sd[6] = { 0 };
    size_t used = 0;
    span all[64];
    int nall;

    /* Split generously first so an over-long header can still name its
     * unknown columns rather than only saying "too many". */
    split(line, all, 64, &nall);
    for (k = 0; k < nall && k < 64; k++) {
        span s = trim(all[k]);
        int known = 0;
        if (s.n >= 2 && s.p[0] == '"' && s.p[s.n - 1] == '"') {
            s.p++;
            s.n -= 2;
            s = trim(s);
        }
        if (s.n == 0)
            return sg_diag_set(d, SG_EPARSE,
                               "%s:%ld: column %d of the header has no name",
                               name, lineno, k + 1);
        for (j = 0; j < 4; j++)
            if (name_is(s, norm_names[j])) {
                if (seen_norm[j]++)
                    return sg_diag_set(d, SG_EPARSE,
                                       "%s:%ld: column \"%s\" appears twice",
                                       name, lineno, norm_names[j]);
                nnorm++;
                known = 1;
                if (k < NCOLS_MAX)
                    map[k] = j;
            }
        for (j = 0; j < 6; j++)
            if (name_is(s, sd_names[j])) {
                if (seen_sd[j]++)
                    return sg_diag_set(d, SG_EPARSE,
                                       "%s:%ld: column \"%s\" appears twice",
                                       name, lineno, sd_names[j]);
                nsd++;
                known = 1;
                if (k < NCOLS_MAX)
                    map[k] = j;
            }
        if (!known) {
            int w = snprintf(unknown + used, sizeof unknown - used, "%s\"%s\"",
                             nunknown ? ", " : "", show(s, buf, sizeof buf));
            if (w > 0 && (size_t)w < sizeof unknown - used)
                used += (size_t)w;
            nunknown++;
        }
    }
    if (nall > 64)
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: header has %d columns; "
                           "expected hx,hy,px,py or x,y,z,l,m,n",
                           name, lineno, nall);
    if (nunknown)
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: unknown column%s %s; "
                           "expected hx,hy,px,py or x,y,z,l,m,n",
                           name, lineno, nunknown > 1 ? "s" : "", unknown);
    if (nnorm && nsd)
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: the header mixes normalized "
                           "columns (hx,hy,px,py) with start and direction "
                           "columns (x,y,z,l,m,n)", name, lineno);
    if (nnorm) {
        *kind = SG_RAYS_NORMALIZED;
        for (j = 0; j < 4; j++)
            if (!seen_norm[j])
                return sg_diag_set(d, SG_EPARSE, "%s:%ld: missing column \"%s\"",
                                   name, lineno, norm_names[j]);
    } else {
        *kind = SG_RAYS_START_DIR;
        for (j = 0; j < 6; j++)
            if (!seen_sd[j])
                return sg_diag_set(d, SG_EPARSE, "%s:%ld: missing column \"%s\"",
                                   name, lineno, sd_names[j]);
    }
    *ncol = nall;
    return SG_OK;
}

static int parse_row(span line, const char *name, long lineno, sg_ray_kind kind,
                     const int *map, int ncol, sg_ray_in *ray, sg_diag *d)
{
    span f[NCOLS_MAX];
    char buf[48];
    const char *const *names = kind == SG_RAYS_NORMALIZED ? norm_names : sd_names;
    int count, k;

    split(line, f, NCOLS_MAX, &count);
    if (count != ncol)
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: expected %d fields, got %d",
                           name, lineno, ncol, count);
    memset(ray, 0, sizeof *ray);
    for (k = 0; k < ncol; k++) {
        span s = trim(f[k]);
        char num[128];
        int rc;
        if (s.n >= sizeof num) {
            rc = ARGS_SYNTAX;
        } else {
            memcpy(num, s.p, s.n);
            num[s.n] = '\0';
            rc = args_double(num, 0, &ray->v[map[k]]);
        }
        if (rc == ARGS_EMPTY)
            return sg_diag_set(d, SG_EPARSE, "%s:%ld: column \"%s\": empty field",
                               name, lineno, names[map[k]]);
        if (rc != ARGS_OK)
            return sg_diag_set(d, SG_EPARSE, "%s:%ld: column \"%s\": %s: \"%s\"",
                               name, lineno, names[map[k]], args_strerror(rc),
                               show(s, buf, sizeof buf));
    }
    if (kind == SG_RAYS_START_DIR && ray->v[3] == 0 && ray->v[4] == 0 &&
        ray->v[5] == 0)
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: direction (l, m, n) is zero",
                           name, lineno);
    return SG_OK;
}

int csvrays_parse(const char *text, size_t len, const char *name,
                  sg_ray_kind *kind, sg_ray_in **rays, size_t *nray,
                  sg_diag *d)
{
    const char *p = text, *end = text + len;
    long lineno = 0;
    int have_header = 0, ncol = 0, map[NCOLS_MAX] = { 0 };
    sg_ray_in *v = NULL;
    size_t n = 0, cap = 0;
    int rc;

    *rays = NULL;
    *nray = 0;
    *kind = SG_RAYS_NORMALIZED;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        span line, t;
        line.p = p;
        line.n = (size_t)((nl ? nl : end) - p);
        p = nl ? nl + 1 : end;
        lineno++;
        if (memchr(line.p, '\0', line.n)) {
            rc = sg_diag_set(d, SG_EPARSE, "%s:%ld: NUL byte in line", name, lineno);
            goto fail;
        }
        t = trim(line);
        if (t.n == 0 || t.p[0] == '#')
            continue;
        if (!have_header) {
            rc = parse_header(t, name, lineno, kind, map, &ncol, d);
            if (rc != SG_OK)
                goto fail;
            have_header = 1;
            continue;
        }
        if (n == cap) {
            size_t ncap = cap ? 2 * cap : 64;
            sg_ray_in *nv;
            if (ncap > SIZE_MAX / sizeof *v) {
                rc = sg_diag_set(d, SG_ENOMEM, "%s: too many rays", name);
                goto fail;
            }
            nv = realloc(v, ncap * sizeof *v);
            if (!nv) {
                rc = sg_diag_set(d, SG_ENOMEM, "%s: out of memory after %zu rays",
                                 name, n);
                goto fail;
            }
            v = nv;
            cap = ncap;
        }
        rc = parse_row(t, name, lineno, *kind, map, ncol, &v[n], d);
        if (rc != SG_OK)
            goto fail;
        n++;
    }
    if (!have_header) {
        rc = sg_diag_set(d, SG_EPARSE, "%s: no header row; expected the "
                         "columns hx,hy,px,py or x,y,z,l,m,n", name);
        goto fail;
    }
    if (n == 0) {
        rc = sg_diag_set(d, SG_EPARSE, "%s: no rays after the header", name);
        goto fail;
    }
    *rays = v;
    *nray = n;
    return SG_OK;
fail:
    free(v);
    return rc;
}

int csvrays_read(const char *path, sg_ray_kind *kind, sg_ray_in **rays,
                 size_t *nray, sg_diag *d)
{
    int use_stdin = strcmp(path, "-") == 0;
    const char *name = use_stdin ? "<stdin>" : path;
    FILE *f = use_stdin ? stdin : fopen(path, "rb");
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int rc;

    *rays = NULL;
    *nray = 0;
    if (!f)
        return sg_diag_set(d, SG_EIO, "%s: %s", name, strerror(errno));
    for (;;) {
        size_t got;
        /* A ray file has a limit like a design does, so that /dev/zero or a
         * runaway pipe is refused instead of exhausting memory. */
        if (len > CSVRAYS_MAX_BYTES) {
            rc = sg_diag_set(d, SG_ERANGE, "%s: larger than %d MiB; split the rays into "
                             "several files", name, (int)(CSVRAYS_MAX_BYTES >> 20));
            goto done;
        }
        if (cap - len < 65536) {
            size_t ncap = cap ? 2 * cap : 65536;
            char *nb;
            if (ncap < cap || !(nb = realloc(buf, ncap))) {
                rc = sg_diag_set(d, SG_ENOMEM, "%s: out of memory reading the file",
                                 name);
                goto done;
            }
            buf = nb;
            cap = ncap;
        }
        got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) {
            if (ferror(f)) {
                rc = sg_diag_set(d, SG_EIO, "%s: %s", name, strerror(errno));
                goto done;
            }
            break;
        }
    }
    rc = csvrays_parse(buf, len, name, kind, rays, nray, d);
done:
    free(buf);
    if (!use_stdin)
        fclose(f);
    return rc;
}
