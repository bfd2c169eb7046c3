/* csvrays.c - the ray list read by "sagitta trace --rays FILE.csv". */
#include "csvrays.h"

#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "args.h"
#include "numfmt.h"

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

/* The usual row in one pass: ncol plain decimals (numfmt_parse's form)
 * separated by single commas, nothing else.  Returns 0, with *ray
 * untouched, for anything else, which parse_row then reads field by
 * field: the same values where this one succeeds (each field here is
 * what split and trim give there), and its messages where it fails. */
static int parse_row_fast(span line, sg_ray_kind kind, const int *map, int ncol,
                          sg_ray_in *ray)
{
    const char *p = line.p, *end = line.p + line.n;
    sg_ray_in r;
    int k;
    memset(&r, 0, sizeof r);
    for (k = 0; k < ncol; k++) {
        p = numfmt_parse_to(p, end, &r.v[map[k]]);
        if (!p)
            return 0;
        if (k + 1 < ncol) {
            if (p == end || *p != ',')
                return 0;
            p++;
        }
    }
    if (p != end)
        return 0;
    if (kind == SG_RAYS_START_DIR && r.v[3] == 0 && r.v[4] == 0 && r.v[5] == 0)
        return 0;
    *ray = r;
    return 1;
}

static int parse_row(span line, const char *name, long lineno, sg_ray_kind kind,
                     const int *map, int ncol, sg_ray_in *ray, sg_diag *d)
{
    span f[NCOLS_MAX];
    char buf[48];
    const char *const *names = kind == SG_RAYS_NORMALIZED ? norm_names : sd_names;
    int count, k;

    if (parse_row_fast(line, kind, map, ncol, ray))
        return SG_OK;
    split(line, f, NCOLS_MAX, &count);
    if (count != ncol)
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: expected %d fields, got %d",
                           name, lineno, ncol, count);
    memset(ray, 0, sizeof *ray);
    for (k = 0; k < ncol; k++) {
        span s = trim(f[k]);
        char num[128];
        int rc;
        /* A plain decimal is read here, correctly rounded, as strtod
         * would; anything else (hex, inf, bad text) goes to args_double
         * for its value or its message. */
        if (numfmt_parse(s.p, s.n, &ray->v[map[k]]))
            continue;
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

/* A ray list read a piece at a time: from a file or standard input
 * through a buffer of at least one whole line, or from text in memory. */
struct csvrays_reader {
    FILE *f;            /* NULL for text in memory */
    int own;            /* f is ours to close */
    char *buf;          /* file data; or the text itself */
    size_t pos, len, cap;
    int eof;
    char name[1024];
    long lineno;
    int ncol, map[NCOLS_MAX];
    sg_ray_kind kind;
    unsigned long long consumed, total; /* bytes, for progress */
    size_t nray;                        /* rays read so far */
    int threads;                        /* parsing threads, 1 or more */
    char *arena;                        /* a block's rows, copied */
    size_t arena_len, arena_cap;
    struct pending *rows;
    size_t nrows, rows_cap;
};

/* A row gathered for parsing: its text in the arena, its line number and
 * the ray it becomes. */
typedef struct pending {
    size_t off, len, slot;
    long lineno;
} pending;

/* Refills the buffer so that it holds a whole line from pos, or all that
 * is left.  Returns SG_OK, or an error naming the line. */
static int fill(csvrays_reader *r)
{
    for (;;) {
        size_t got;
        if (memchr(r->buf + r->pos, '\n', r->len - r->pos) || r->eof)
            return SG_OK;
        /* A line being gathered is checked for NUL as it grows, so a file
         * of zeros is named as such before it is too long. */
        if (memchr(r->buf + r->pos, '\0', r->len - r->pos))
            return SG_EPARSE;
        if (r->pos > 0) {
            memmove(r->buf, r->buf + r->pos, r->len - r->pos);
            r->len -= r->pos;
            r->pos = 0;
        }
        if (r->len == r->cap) {
            size_t ncap = 2 * r->cap;
            char *nb;
            if (r->cap >= CSVRAYS_MAX_LINE)
                return SG_ERANGE;
            if (ncap > CSVRAYS_MAX_LINE)
                ncap = CSVRAYS_MAX_LINE;
            nb = realloc(r->buf, ncap);
            if (!nb)
                return SG_ENOMEM;
            r->buf = nb;
            r->cap = ncap;
        }
        got = fread(r->buf + r->len, 1, r->cap - r->len, r->f);
        r->len += got;
        if (got == 0) {
            if (ferror(r->f))
                return SG_EIO;
            r->eof = 1;
        }
    }
}

/* Whether the file opens with a UTF-16 byte order mark (its first line is
 * at pos). */
static int utf16_start(const csvrays_reader *r)
{
    const unsigned char *b = (const unsigned char *)r->buf + r->pos;
    return r->lineno == 0 && r->len - r->pos >= 2 &&
           ((b[0] == 0xFF && b[1] == 0xFE) || (b[0] == 0xFE && b[1] == 0xFF));
}

/* The NUL refusal, or on a first line in UTF-16 what the NULs mean. */
static void nul_message(const csvrays_reader *r, long at, sg_diag *d)
{
    if (utf16_start(r))
        sg_diag_set(d, SG_EPARSE,
                    "%s: the file is UTF-16 text (byte order mark %s); ray lists are read "
                    "as UTF-8 or ASCII: convert it, e.g. iconv -f UTF-16 -t UTF-8",
                    r->name, (unsigned char)r->buf[r->pos] == 0xFF ? "FF FE" : "FE FF");
    else
        sg_diag_set(d, SG_EPARSE, "%s:%ld: NUL byte in line", r->name, at);
}

/* The next line (without its newline) in *line; returns 0 at the end, 1
 * for a line, or -1 with d filled.  A UTF-8 byte order mark before the
 * first line is skipped (spreadsheets write one). */
static int next_line(csvrays_reader *r, span *line, sg_diag *d)
{
    const char *nl;
    if (r->f) {
        int rc = fill(r);
        if (rc != SG_OK) {
            long at = r->lineno + 1;
            if (rc == SG_EPARSE)
                nul_message(r, at, d);
            else if (rc == SG_ERANGE)
                sg_diag_set(d, SG_EPARSE, "%s:%ld: line longer than %d MiB", r->name, at,
                            (int)(CSVRAYS_MAX_LINE >> 20));
            else if (rc == SG_EIO)
                sg_diag_set(d, SG_EIO, "%s: %s", r->name, strerror(errno));
            else
                sg_diag_set(d, SG_ENOMEM, "%s: out of memory reading line %ld", r->name, at);
            return -1;
        }
    }
    if (r->pos >= r->len)
        return 0;
    if (r->lineno == 0 && r->len - r->pos >= 3 &&
        memcmp(r->buf + r->pos, "\xEF\xBB\xBF", 3) == 0) {
        r->pos += 3;
        r->consumed += 3;
    }
    if (utf16_start(r)) {
        nul_message(r, 1, d);
        return -1;
    }
    line->p = r->buf + r->pos;
    nl = memchr(line->p, '\n', r->len - r->pos);
    line->n = (size_t)((nl ? nl : r->buf + r->len) - line->p);
    r->pos += line->n + (nl ? 1 : 0);
    r->consumed += line->n + (nl ? 1 : 0);
    r->lineno++;
    if (memchr(line->p, '\0', line->n)) {
        sg_diag_set(d, SG_EPARSE, "%s:%ld: NUL byte in line", r->name, r->lineno);
        return -1;
    }
    return 1;
}

/* Reads up to the header row. */
static int read_header(csvrays_reader *r, sg_diag *d)
{
    span line, t;
    int got;
    while ((got = next_line(r, &line, d)) > 0) {
        t = trim(line);
        if (t.n == 0 || t.p[0] == '#')
            continue;
        return parse_header(t, r->name, r->lineno, &r->kind, r->map, &r->ncol, d);
    }
    if (got < 0)
        return d && d->code ? d->code : SG_EPARSE;
    return sg_diag_set(d, SG_EPARSE, "%s: no header row; expected the "
                       "columns hx,hy,px,py or x,y,z,l,m,n", r->name);
}

static csvrays_reader *reader_new(const char *name)
{
    csvrays_reader *r = calloc(1, sizeof *r);
    if (r) {
        snprintf(r->name, sizeof r->name, "%s", name);
        r->kind = SG_RAYS_NORMALIZED;
        r->threads = 1;
    }
    return r;
}

static int open_file(FILE *f, int own, const char *name, csvrays_reader **out, sg_diag *d)
{
    csvrays_reader *r;
    int rc;
    *out = NULL;
    r = reader_new(name);
    if (!r) {
        if (own)
            fclose(f);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    }
    r->f = f;
    r->own = own;
    r->cap = (size_t)1 << 20;
    r->buf = malloc(r->cap);
    if (!r->buf) {
        csvrays_close(r);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    }
    {
        struct stat st;
        if (fstat(fileno(r->f), &st) == 0 && S_ISREG(st.st_mode))
            r->total = (unsigned long long)st.st_size;
    }
    rc = read_header(r, d);
    if (rc != SG_OK) {
        csvrays_close(r);
        return rc;
    }
    *out = r;
    return SG_OK;
}

int csvrays_open(const char *path, csvrays_reader **out, sg_diag *d)
{
    FILE *f;
    *out = NULL;
    if (strcmp(path, "-") == 0)
        return open_file(stdin, 0, "<stdin>", out, d);
    f = fopen(path, "rb");
    if (!f)
        return sg_diag_set(d, SG_EIO, "%s: %s", path, strerror(errno));
    return open_file(f, 1, path, out, d);
}

int csvrays_open_stream(FILE *f, const char *name, csvrays_reader **out, sg_diag *d)
{
    return open_file(f, 0, name, out, d);
}

int csvrays_count(csvrays_reader *r, size_t *n, sg_diag *d)
{
    span line, t;
    int got;
    *n = 0;
    while ((got = next_line(r, &line, d)) > 0) {
        t = trim(line);
        if (t.n != 0 && t.p[0] != '#')
            ++*n;
    }
    return got < 0 ? (d && d->code ? d->code : SG_EPARSE) : SG_OK;
}

int csvrays_open_text(const char *text, size_t len, const char *name,
                      csvrays_reader **out, sg_diag *d)
{
    csvrays_reader *r;
    int rc;
    *out = NULL;
    r = reader_new(name);
    if (!r)
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    r->buf = (char *)text;
    r->len = len;
    r->total = len;
    r->eof = 1;
    rc = read_header(r, d);
    if (rc != SG_OK) {
        csvrays_close(r);
        return rc;
    }
    *out = r;
    return SG_OK;
}

sg_ray_kind csvrays_kind(const csvrays_reader *r)
{
    return r->kind;
}

/* Rows longer than this are parsed as they come, not copied, so a block's
 * copy stays small; a valid row is far shorter. */
#define ROW_COPY_MAX 4096
#define PARSE_MIN_ROWS 256
#define PARSE_MAX_THREADS 64

typedef struct parse_job {
    const csvrays_reader *r;
    sg_ray_in *rays;
    size_t from, to;
    size_t bad;  /* index of the first bad row, or to */
    int rc;
    sg_diag d;
} parse_job;

static void *parse_main(void *arg)
{
    parse_job *j = arg;
    const csvrays_reader *r = j->r;
    size_t i;
    j->bad = j->to;
    j->rc = SG_OK;
    sg_diag_clear(&j->d);
    for (i = j->from; i < j->to; i++) {
        const pending *p = &r->rows[i];
        span t;
        t.p = r->arena + p->off;
        t.n = p->len;
        j->rc = parse_row(t, r->name, p->lineno, r->kind, r->map, r->ncol,
                          &j->rays[p->slot], &j->d);
        if (j->rc != SG_OK) {
            j->bad = i;
            break;
        }
    }
    return NULL;
}

/* Parses the gathered rows, in contiguous shares on the reader's threads;
 * the first bad row in file order decides the error, as reading them one
 * by one would. */
static int flush_rows(csvrays_reader *r, sg_ray_in *rays, sg_diag *d)
{
    parse_job job[PARSE_MAX_THREADS];
    pthread_t tid[PARSE_MAX_THREADS];
    int started[PARSE_MAX_THREADS];
    int k, nt = r->threads;
    size_t n = r->nrows;
    if (n == 0)
        return SG_OK;
    if ((size_t)nt > n / (PARSE_MIN_ROWS / 2))
        nt = (int)(n / (PARSE_MIN_ROWS / 2));
    if (nt < 1)
        nt = 1;
    for (k = 0; k < nt; k++) {
        job[k].r = r;
        job[k].rays = rays;
        job[k].from = n * (size_t)k / (size_t)nt;
        job[k].to = n * (size_t)(k + 1) / (size_t)nt;
        started[k] = k > 0 && pthread_create(&tid[k], NULL, parse_main, &job[k]) == 0;
    }
    parse_main(&job[0]);
    for (k = 1; k < nt; k++) {
        if (started[k])
            pthread_join(tid[k], NULL);
        else
            parse_main(&job[k]);
    }
    r->nrows = 0;
    r->arena_len = 0;
    for (k = 0; k < nt; k++)
        if (job[k].rc != SG_OK) {
            if (d)
                *d = job[k].d;
            return job[k].rc;
        }
    return SG_OK;
}

/* Copies a row into the block's arena for flush_rows. */
static int gather(csvrays_reader *r, span t, size_t slot)
{
    pending *p;
    if (r->nrows == r->rows_cap) {
        size_t cap = r->rows_cap ? 2 * r->rows_cap : 1024;
        pending *n = realloc(r->rows, cap * sizeof *n);
        if (!n)
            return SG_ENOMEM;
        r->rows = n;
        r->rows_cap = cap;
    }
    if (r->arena_len + t.n > r->arena_cap) {
        size_t cap = r->arena_cap ? 2 * r->arena_cap : (size_t)1 << 16;
        char *n;
        while (cap < r->arena_len + t.n)
            cap *= 2;
        n = realloc(r->arena, cap);
        if (!n)
            return SG_ENOMEM;
        r->arena = n;
        r->arena_cap = cap;
    }
    memcpy(r->arena + r->arena_len, t.p, t.n);
    p = &r->rows[r->nrows++];
    p->off = r->arena_len;
    p->len = t.n;
    p->slot = slot;
    p->lineno = r->lineno;
    r->arena_len += t.n;
    return SG_OK;
}

void csvrays_set_threads(csvrays_reader *r, int threads)
{
    long n = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);
    r->threads = n < 1 ? 1 : n > PARSE_MAX_THREADS ? PARSE_MAX_THREADS : (int)n;
}

/* Rows are split into lines here, in order, and parsed a block at a time
 * on the reader's threads; the rays, and the first error, are those of
 * parsing them one by one. */
int csvrays_next(csvrays_reader *r, sg_ray_in *rays, size_t max, size_t *n, sg_diag *d)
{
    span line, t;
    int got, rc;
    size_t count = 0;
    *n = 0;
    r->nrows = 0;
    r->arena_len = 0;
    while (count < max && (got = next_line(r, &line, d)) != 0) {
        if (got < 0) {
            /* A bad row before the unreadable line is the first error. */
            int code = d && d->code ? d->code : SG_EPARSE;
            sg_diag keep;
            if (d)
                keep = *d;
            rc = flush_rows(r, rays, d);
            if (rc != SG_OK)
                return rc;
            if (d)
                *d = keep;
            return code;
        }
        t = trim(line);
        if (t.n == 0 || t.p[0] == '#')
            continue;
        if (r->threads > 1 && t.n <= ROW_COPY_MAX) {
            if (gather(r, t, count) != SG_OK)
                return sg_diag_set(d, SG_ENOMEM, "%s: out of memory reading line %ld",
                                   r->name, r->lineno);
        } else {
            rc = flush_rows(r, rays, d);
            if (rc == SG_OK)
                rc = parse_row(t, r->name, r->lineno, r->kind, r->map, r->ncol,
                               &rays[count], d);
            if (rc != SG_OK)
                return rc;
        }
        count++;
    }
    rc = flush_rows(r, rays, d);
    if (rc != SG_OK)
        return rc;
    *n = count;
    r->nray += count;
    if (*n == 0 && r->nray == 0)
        return sg_diag_set(d, SG_EPARSE, "%s: no rays after the header", r->name);
    return SG_OK;
}

void csvrays_progress(const csvrays_reader *r, unsigned long long *done,
                      unsigned long long *total)
{
    *done = r->consumed;
    *total = r->total;
}

void csvrays_close(csvrays_reader *r)
{
    if (!r)
        return;
    if (r->f) {
        if (r->own)
            fclose(r->f);
        free(r->buf);
    }
    free(r->arena);
    free(r->rows);
    free(r);
}

int csvrays_parse(const char *text, size_t len, const char *name,
                  sg_ray_kind *kind, sg_ray_in **rays, size_t *nray,
                  sg_diag *d)
{
    csvrays_reader *r;
    sg_ray_in *v = NULL;
    size_t n = 0, cap = 0, got;
    int rc;

    *rays = NULL;
    *nray = 0;
    *kind = SG_RAYS_NORMALIZED;
    rc = csvrays_open_text(text, len, name, &r, d);
    if (rc != SG_OK)
        return rc;
    *kind = r->kind;
    for (;;) {
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
        rc = csvrays_next(r, v + n, cap - n, &got, d);
        if (rc != SG_OK)
            goto fail;
        if (got == 0)
            break;
        n += got;
    }
    csvrays_close(r);
    *rays = v;
    *nray = n;
    return SG_OK;
fail:
    csvrays_close(r);
    free(v);
    return rc;
}

int csvrays_read(const char *path, sg_ray_kind *kind, sg_ray_in **rays,
                 size_t *nray, sg_diag *d)
{
    csvrays_reader *r;
    sg_ray_in *v = NULL;
    size_t n = 0, cap = 0, got;
    int rc;

    *rays = NULL;
    *nray = 0;
    rc = csvrays_open(path, &r, d);
    if (rc != SG_OK)
        return rc;
    *kind = r->kind;
    for (;;) {
        if (n == cap) {
            size_t ncap = cap ? 2 * cap : 64;
            sg_ray_in *nv;
            if (ncap > SIZE_MAX / sizeof *v || !(nv = realloc(v, ncap * sizeof *v))) {
                rc = sg_diag_set(d, SG_ENOMEM, "%s: out of memory after %zu rays",
                                 r->name, n);
                goto fail;
            }
            v = nv;
            cap = ncap;
        }
        rc = csvrays_next(r, v + n, cap - n, &got, d);
        if (rc != SG_OK)
            goto fail;
        if (got == 0)
            break;
        n += got;
    }
    csvrays_close(r);
    *rays = v;
    *nray = n;
    return SG_OK;
fail:
    csvrays_close(r);
    free(v);
    return rc;
}
