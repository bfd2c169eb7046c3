/* report.c - ray-trace and paraxial results as text, CSV or JSON. */
#define _GNU_SOURCE 1 /* fopencookie */
#include "report.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio_ext.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "numfmt.h"
#include "safetext.h"

/* One end of a --surface item, text [a, b): a number, OBJ, STO or IMA.
 * Returns the surface, or -1 (err set, naming the item). */
static int surface_word(const char *a, const char *b, const char *item, int nsurf, int stop,
                        char *err, size_t errlen)
{
    size_t n = (size_t)(b - a);
    long v = 0;
    const char *p;
    if (n == 3 && strncasecmp(a, "IMA", 3) == 0)
        return nsurf - 1;
    if (n == 3 && strncasecmp(a, "STO", 3) == 0)
        return stop;
    if (n == 3 && strncasecmp(a, "OBJ", 3) == 0)
        return 0;
    for (p = a; p < b && *p >= '0' && *p <= '9' && v <= 1000000; p++)
        v = 10 * v + (*p - '0');
    if (n == 0 || p < b) {
        snprintf(err, errlen,
                 "--surface: \"%s\" is not a surface (a number, a range A-B, OBJ, STO or IMA)",
                 item);
        return -1;
    }
    if (v > nsurf - 1) {
        snprintf(err, errlen, "--surface: \"%s\": surface %ld is past the image, surface %d",
                 item, v, nsurf - 1);
        return -1;
    }
    return (int)v;
}

int report_parse_surfaces(const char *list, int nsurf, int stop, int *sel, int *nsel,
                          char *err, size_t errlen)
{
    char *keep, item[64];
    const char *p = list;
    int i, n = 0;
    if (!list || nsurf < 1) {
        snprintf(err, errlen, "--surface: no surfaces");
        return -1;
    }
    keep = calloc((size_t)nsurf, 1);
    if (!keep) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    for (;;) {
        const char *end = strchr(p, ','), *dash, *a, *b;
        size_t len;
        int lo, hi;
        if (!end)
            end = p + strlen(p);
        /* Blanks around an item are allowed, as around a CSV field. */
        for (a = p; a < end && (*a == ' ' || *a == '\t'); a++)
            ;
        for (b = end; b > a && (b[-1] == ' ' || b[-1] == '\t'); b--)
            ;
        len = (size_t)(b - a);
        snprintf(item, sizeof item, "%.*s%s", (int)(len < 40 ? len : 40), a,
                 len > 40 ? "..." : "");
        if (len == 0) {
            snprintf(err, errlen, "--surface: an empty item in \"%.60s\"", list);
            free(keep);
            return -1;
        }
        dash = memchr(a, '-', len);
        lo = surface_word(a, dash ? dash : b, item, nsurf, stop, err, errlen);
        hi = lo < 0 ? -1 : dash ? surface_word(dash + 1, b, item, nsurf, stop, err, errlen) : lo;
        if (lo < 0 || hi < 0) {
            free(keep);
            return -1;
        }
        if (hi < lo) {
            snprintf(err, errlen, "--surface: \"%s\": the range runs from %d down to %d", item,
                     lo, hi);
            free(keep);
            return -1;
        }
        for (i = lo; i <= hi; i++)
            keep[i] = 1;
        if (!*end)
            break;
        p = end + 1;
    }
    /* In surface order, each once. */
    for (i = 0; i < nsurf; i++)
        if (keep[i])
            sel[n++] = i;
    *nsel = n;
    free(keep);
    return 0;
}

int report_parse_fmt(const char *s)
{
    if (!s)
        return -1;
    if (strcmp(s, "text") == 0)
        return REPORT_TEXT;
    if (strcmp(s, "csv") == 0)
        return REPORT_CSV;
    if (strcmp(s, "json") == 0)
        return REPORT_JSON;
    return -1;
}

const char *report_status_name(int status)
{
    const char *name;
    switch (status) {
    case SG_OK: return "OK";
    case SG_EMISS: return "MISS";
    case SG_ETIR: return "TIR";
    case SG_EVIGNETTED: return "VIGNETTED";
    case SG_ENOCONV: return "NOCONV";
    case SG_ENOTREACHED: return "NOT REACHED";
    case SG_EAIM: return "AIM FAILED";
    case SG_ERANGE: return "OUT OF RANGE";
    default:
        name = sg_err_name(status);
        return strncmp(name, "SG_E", 4) == 0 ? name + 4 : name;
    }
}

/* The status of a whole ray when the caller has no return code: the first
 * surface that failed, as the trace functions themselves report it. */
static int ray_status(const sg_ray_surface *s, int nsurf, const int *status,
                      size_t r)
{
    int i;
    if (status)
        return status[r];
    for (i = 0; i < nsurf; i++)
        if (s[i].status != SG_OK)
            return s[i].status;
    return SG_OK;
}

/* How many rows of a ray a report writes, and the surface of row k: the
 * chosen surfaces (trace --surface), or every one. */
static int row_count(const report_meta *m, int nsurf)
{
    return m && m->surfaces ? m->nsurfaces : nsurf;
}

static int row_surface(const report_meta *m, int k)
{
    return m && m->surfaces ? m->surfaces[k] : k;
}

static int first_failure(const sg_ray_surface *s, int nsurf)
{
    int i;
    for (i = 0; i < nsurf; i++)
        if (s[i].status != SG_OK && s[i].status != SG_ENOTREACHED)
            return i;
    return -1;
}

/* Shortest %g text that reads back as the same double, for header lines
 * meant for people (0.55, not 0.55000000000000004). */
static const char *shortest(double v, char *buf, size_t n)
{
    int prec;
    if (isinf(v))
        return v > 0 ? "Infinity" : "-Infinity";
    if (isnan(v))
        return "undefined";
    for (prec = 1; prec <= 17; prec++) {
        snprintf(buf, n, "%.*g", prec, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    return buf;
}

/* Scientific text of fixed width for the tables.  A NaN should not reach
 * a report; if one does, it reads as a word rather than "nan". */
static const char *sci(double v, int prec, char *buf, size_t n)
{
    if (isinf(v))
        return v > 0 ? "Infinity" : "-Infinity";
    if (isnan(v))
        return "undefined";
    snprintf(buf, n, "%.*e", prec, v);
    return buf;
}

/* Classic's error figure is an estimate, not a bound (it is exceeded on
 * ordinary lenses), so its column carries another name; precise's and
 * mpfr's keep "bound". */
static int is_estimate(const report_meta *m)
{
    return m && m->method && strcmp(m->method, "classic") == 0;
}

static const char *bound_key(const report_meta *m)
{
    return is_estimate(m) ? "error_estimate" : "error_bound";
}

static const char *const norm_label[4] = { "Hx", "Hy", "Px", "Py" };
static const char *const sd_json[6] = { "x", "y", "z", "l", "m", "n" };
static const char *const norm_json[4] = { "hx", "hy", "px", "py" };

/* ---------------------------------------------------------------- text */

static void text_ray_line(FILE *f, sg_ray_kind kind, const sg_ray_in *ray)
{
    char b[6][40];
    int k;
    if (kind == SG_RAYS_NORMALIZED) {
        fputs("Ray         :", f);
        for (k = 0; k < 4; k++)
            fprintf(f, " %s = %s%s", norm_label[k], shortest(ray->v[k], b[k], sizeof b[k]),
                    k < 3 ? "," : "\n");
    } else {
        fprintf(f, "Start       : x = %s, y = %s, z = %s (surface 1 frame)\n",
                shortest(ray->v[0], b[0], sizeof b[0]),
                shortest(ray->v[1], b[1], sizeof b[1]),
                shortest(ray->v[2], b[2], sizeof b[2]));
        fprintf(f, "Direction   : l = %s, m = %s, n = %s\n",
                shortest(ray->v[3], b[3], sizeof b[3]),
                shortest(ray->v[4], b[4], sizeof b[4]),
                shortest(ray->v[5], b[5], sizeof b[5]));
    }
}

static void text_status_line(FILE *f, const report_meta *m, const sg_ray_surface *s,
                             int nsurf, int st)
{
    int at = first_failure(s, nsurf);
    char why[160];
    if (st == SG_OK)
        fputs("Status      : OK\n", f);
    else if (at >= 0 && m->sys && sg_err_is_stopped(st))
        fprintf(f, "Status      : %s (%s)\n", report_status_name(st),
                sg_ray_stop_text(m->sys, at, st, why, sizeof why));
    else if (at >= 0)
        fprintf(f, "Status      : %s at surface %d (%s)\n", report_status_name(st),
                at, sg_strerror(st));
    else
        fprintf(f, "Status      : %s (%s)\n", report_status_name(st), sg_strerror(st));
}

static void text_table(FILE *f, const report_meta *m, const sg_ray_surface *s, int nsurf)
{
    int i, k, nrow = row_count(m, nsurf);
    fprintf(f, "%4s %23s %23s %23s %23s %23s %23s %10s %10s %23s %24s  %s\n", "Surf",
            "X", "Y", "Z", "L", "M", "N", "Residual", is_estimate(m) ? "ErrEst" : "ErrBound",
            "Path", "OPL", "Status");
    for (k = 0; k < nrow; k++) {
        const sg_ray_surface *e = &s[i = row_surface(m, k)];
        char label[16], b[10][40];
        if (i == 0)
            strcpy(label, "OBJ");
        else if (i == nsurf - 1)
            strcpy(label, "IMA");
        else
            snprintf(label, sizeof label, "%d", i);
        if (e->status != SG_OK) {
            /* The numbers of a failed surface mean nothing; the name of
             * the failure stands in their place. */
            fprintf(f, "%4s %23s\n", label, report_status_name(e->status));
            continue;
        }
        fprintf(f, "%4s %23s %23s %23s %23s %23s %23s %10s %10s %23s %24s  %s\n", label,
                sci(e->x, 15, b[0], sizeof b[0]), sci(e->y, 15, b[1], sizeof b[1]),
                sci(e->z, 15, b[2], sizeof b[2]), sci(e->l, 15, b[3], sizeof b[3]),
                sci(e->m, 15, b[4], sizeof b[4]), sci(e->n, 15, b[5], sizeof b[5]),
                sci(e->residual, 3, b[6], sizeof b[6]),
                sci(e->error_bound, 3, b[7], sizeof b[7]),
                sci(e->path, 15, b[8], sizeof b[8]), sci(e->opl, 16, b[9], sizeof b[9]), "OK");
    }
}

static void text_head(FILE *f, const report_meta *m, int multi, size_t total)
{
    char b[40];
    fputs(!multi ? "Single ray trace\n" : "Ray trace\n", f);
    /* A file name or title may hold escape codes; text goes to terminals. */
    fputs("Design      : ", f);
    safe_fputs(m && m->design ? m->design : "(untitled)", f);
    fputc('\n', f);
    if (m && m->method) {
        if (m->bits > 0)
            fprintf(f, "Method      : %s, %d bits\n", m->method, m->bits);
        else
            fprintf(f, "Method      : %s\n", m->method);
    }
    if (m)
        fprintf(f, "Wavelength  : %s um (wave %d)\n",
                shortest(m->wave_um, b, sizeof b), m->wave_index);
    if (m && m->global)
        fprintf(f, "Coordinates are global, in the frame of surface %d; L, M, N are the "
                "direction cosines after the surface.\n", m->global_ref);
    else
        fputs("Coordinates are in each surface's local frame; L, M, N are the "
              "direction cosines after the surface.\n", f);
    if (is_estimate(m))
        fputs("ErrEst is the classic method's error estimate, not a bound: the true "
              "error can exceed it.\n", f);
    if (multi)
        fprintf(f, "Rays        : %zu\n", total);
}

/* The OPD line: the wavefront against the reference sphere, in waves of
 * the ray's wavelength, and the transverse aberration. */
static void text_opd_line(FILE *f, const report_meta *m, const sg_opd *o)
{
    char b[4][40];
    if (o->status != SG_OK) {
        fprintf(f, "OPD         : none (%s)\n", sg_strerror(o->status));
        return;
    }
    fprintf(f, "OPD         : %s waves (%s %s); ex = %s, ey = %s\n",
            sci(o->opd_waves, 15, b[0], sizeof b[0]),
            is_estimate(m) ? "error estimate" : "error bound",
            sci(o->error_bound, 3, b[1], sizeof b[1]), sci(o->ex, 15, b[2], sizeof b[2]),
            sci(o->ey, 15, b[3], sizeof b[3]));
}

static void text_ray(FILE *f, const report_meta *m, int multi, size_t index, int nsurf,
                     const sg_ray_surface *s, int st, sg_ray_kind kind, const sg_ray_in *ray,
                     const sg_opd *opd)
{
    fputc('\n', f);
    if (multi)
        fprintf(f, "Ray %zu\n", index);
    if (ray)
        text_ray_line(f, kind, ray);
    text_status_line(f, m, s, nsurf, st);
    if (opd)
        text_opd_line(f, m, opd);
    fputc('\n', f);
    text_table(f, m, s, nsurf);
}

/* ----------------------------------------------------------- CSV, JSON */

/* A number as CSV and JSON carry it: %.17g, so it reads back exactly.
 * JSON has no infinity, so both formats spell it as the string strtod and
 * most readers accept; JSON gets it quoted. */
static void put_num(FILE *f, double v, int json)
{
    if (isnan(v))
        fputs(json ? "null" : "", f);
    else if (isinf(v))
        fputs(json ? (v > 0 ? "\"inf\"" : "\"-inf\"") : (v > 0 ? "inf" : "-inf"), f);
    else {
        /* numfmt_g17 writes printf's bytes, about ten times faster. */
        char b[NUMFMT_G17_MAX];
        fwrite(b, 1, numfmt_g17(v, b), f);
    }
}

/* A number that comes from the design or the user (a wavelength, a ray's
 * launch, a paraxial datum) as CSV and JSON carry it: the shortest decimal
 * that reads back to the same double, so 0.5875618 stays 0.5875618, where
 * %.17g writes 0.58756180000000002; -0 is written 0. */
static void put_short(FILE *f, double v, int json)
{
    char b[NUMFMT_SHORTEST_MAX];
    if (!isfinite(v)) {
        put_num(f, v, json);
        return;
    }
    fwrite(b, 1, numfmt_shortest_g(v == 0.0 ? 0.0 : v, b), f);
}

static void csv_head(FILE *f, const report_meta *m, int multi, int inputs, sg_ray_kind kind)
{
    if (multi)
        fputs("ray,", f);
    if (inputs)
        fputs(kind == SG_RAYS_NORMALIZED ? "hx,hy,px,py," : "x0,y0,z0,l0,m0,n0,", f);
    fprintf(f, "surface,x,y,z,l,m,n,residual,%s,path,status,opl,opl_%s", bound_key(m),
            bound_key(m));
    if (m && m->opd)
        fprintf(f, ",opd_waves,opd_%s,ex,ey", bound_key(m));
    fputc('\n', f);
}

/* Room one CSV row needs: the index, six inputs, the surface, 15 numbers
 * of at most NUMFMT_G17_MAX bytes each (numfmt_g17's scratch included),
 * a status name, commas and the newline. */
#define CSV_ROW_MAX (24 + 22 * NUMFMT_G17_MAX + 64 + 32)

/* A non-negative integer as %zu or %d writes it. */
static char *mem_uint(char *p, size_t v)
{
    char t[24];
    int n = 0;
    if (v < 10) {
        *p = (char)('0' + v);
        return p + 1;
    }
    do {
        t[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    while (n)
        *p++ = t[--n];
    return p;
}

/* The numbers of one CSV row, in the row's order, into v; returns how
 * many (at most CSV_ROW_NUMS).  csv_row writes them in the same order. */
#define CSV_ROW_NUMS 21
static int csv_row_nums(double *v, int i, int nsurf, const sg_ray_surface *e, int nin,
                        const sg_ray_in *ray, const sg_opd *opd)
{
    int k, n = 0;
    for (k = 0; k < nin; k++)
        v[n++] = ray->v[k];
    if (e->status == SG_OK) {
        v[n++] = e->x;
        v[n++] = e->y;
        v[n++] = e->z;
        v[n++] = e->l;
        v[n++] = e->m;
        v[n++] = e->n;
        v[n++] = e->residual;
        v[n++] = e->error_bound;
        v[n++] = e->path;
        v[n++] = e->opl;
        v[n++] = e->opl_error_bound;
    }
    if (opd && i == nsurf - 1 && opd->status == SG_OK) {
        v[n++] = opd->opd_waves;
        v[n++] = opd->error_bound;
        v[n++] = opd->ex;
        v[n++] = opd->ey;
    }
    return n;
}

/* The next formatted number of a row (put_num's CSV bytes): its slot
 * copied whole (the room allows it), then the end moved to its length. */
typedef struct csv_nums {
    const double *v;
    const char *txt;
    const unsigned char *len;
    int at;
} csv_nums;

static char *take_num(char *p, csv_nums *c)
{
    int k = c->at++;
    if (isnan(c->v[k]))
        return p;
    memcpy(p, c->txt + (size_t)k * NUMFMT_G17_MAX, NUMFMT_G17_MAX);
    return p + c->len[k];
}

/* Surface i of a ray as one CSV row at p (CSV_ROW_MAX bytes of room),
 * after the text ix (nix bytes: the ray's number and a comma, or none),
 * its numbers taken in csv_row_nums' order from c; returns the end.  Written
 * into memory, not through stdio, because a list's rows are most of a
 * run's time. */
static char *csv_row(char *p, const char *ix, size_t nix, int i, int nsurf,
                     const sg_ray_surface *e, int nin, const sg_opd *opd, csv_nums *c)
{
    int k;
    const char *st;
    size_t len;
    /* The ray's number and its comma, made once for its rows. */
    memcpy(p, ix, nix);
    p += nix;
    for (k = 0; k < nin; k++) {
        p = take_num(p, c);
        *p++ = ',';
    }
    p = mem_uint(p, (size_t)i);
    *p++ = ',';
    if (e->status == SG_OK) {
        for (k = 0; k < 9; k++) {
            p = take_num(p, c);
            *p++ = ',';
        }
    } else {
        memcpy(p, ",,,,,,,,,", 9);
        p += 9;
    }
    st = report_status_name(e->status);
    len = strlen(st);
    if (len > 64)
        len = 64;
    memcpy(p, st, len);
    p += len;
    *p++ = ',';
    if (e->status == SG_OK) {
        p = take_num(p, c);
        *p++ = ',';
        p = take_num(p, c);
    } else {
        *p++ = ',';
    }
    if (opd) {
        /* A ray's OPD belongs to its image row. */
        if (i == nsurf - 1 && opd->status == SG_OK) {
            for (k = 0; k < 4; k++) {
                *p++ = ',';
                p = take_num(p, c);
            }
        } else {
            memcpy(p, ",,,,", 4);
            p += 4;
        }
    }
    *p++ = '\n';
    return p;
}

/* Rows a group formats together: their numbers go through numfmt_g17_n
 * at once (eight at a time on AVX-512). */
#define CSV_GROUP 16

/* Rows [i0, i1) of a ray (at most CSV_GROUP) as CSV rows at p, with
 * (i1 - i0) CSV_ROW_MAX bytes of room; returns the end.  Row k is surface
 * sel[k], or k without a selection. */
static char *csv_rows(char *p, int multi, size_t index, int i0, int i1, int nsurf,
                      const int *sel, const sg_ray_surface *s, sg_ray_kind kind,
                      const sg_ray_in *ray, const sg_opd *opd)
{
    double v[CSV_GROUP * CSV_ROW_NUMS];
    char txt[CSV_GROUP * CSV_ROW_NUMS * NUMFMT_G17_MAX];
    unsigned char len[CSV_GROUP * CSV_ROW_NUMS];
    int nin = ray ? (kind == SG_RAYS_NORMALIZED ? 4 : 6) : 0, i, n = 0;
    char ix[24];
    size_t nix = 0;
    csv_nums c;
    if (multi) {
        nix = (size_t)(mem_uint(ix, index) - ix);
        ix[nix++] = ',';
    }
    int start[CSV_GROUP], k;
    for (i = i0; i < i1; i++) {
        int si = sel ? sel[i] : i;
        start[i - i0] = n;
        n += csv_row_nums(v + n, si, nsurf, &s[si], nin, ray, opd);
    }
    if (n > 0)
        numfmt_g17_n(v, (size_t)n, txt, len);
    /* The launch is the user's: its shortest decimal, as JSON's "input". */
    for (k = 0; k < nin; k++) {
        char b[NUMFMT_SHORTEST_MAX];
        size_t bl = isfinite(ray->v[k]) ? numfmt_shortest_g(ray->v[k] == 0.0 ? 0.0 : ray->v[k], b)
                                        : numfmt_g17(ray->v[k], b);
        for (i = i0; i < i1; i++) {
            memcpy(txt + (size_t)(start[i - i0] + k) * NUMFMT_G17_MAX, b, bl + 1);
            len[start[i - i0] + k] = (unsigned char)bl;
        }
    }
    c.v = v;
    c.txt = txt;
    c.len = len;
    c.at = 0;
    for (i = i0; i < i1; i++) {
        int si = sel ? sel[i] : i;
        p = csv_row(p, ix, nix, si, nsurf, &s[si], nin, opd, &c);
    }
    return p;
}

static void csv_ray(FILE *f, const report_meta *m, int multi, size_t index, int nsurf,
                    const sg_ray_surface *s, sg_ray_kind kind, const sg_ray_in *ray,
                    const sg_opd *opd)
{
    char rows[CSV_GROUP * CSV_ROW_MAX];
    int i, nrow = row_count(m, nsurf);
    for (i = 0; i < nrow; i += CSV_GROUP) {
        int i1 = nrow - i < CSV_GROUP ? nrow : i + CSV_GROUP;
        char *end = csv_rows(rows, multi, index, i, i1, nsurf, m ? m->surfaces : NULL, s, kind,
                             ray, opd);
        fwrite(rows, 1, (size_t)(end - rows), f);
    }
}

/* Writes s as a JSON string; cJSON does the escaping. */
static int put_str(FILE *f, const char *s)
{
    cJSON *j = cJSON_CreateString(s ? s : "");
    char *t = j ? cJSON_PrintUnformatted(j) : NULL;
    cJSON_Delete(j);
    if (!t) {
        errno = ENOMEM;
        return -1;
    }
    fputs(t, f);
    cJSON_free(t);
    return 0;
}

static int json_meta(FILE *f, const report_meta *m)
{
    fputs("  \"design\": ", f);
    if (m && m->design) {
        if (put_str(f, m->design) < 0)
            return -1;
    } else {
        fputs("null", f);
    }
    if (m && m->method) {
        fputs(",\n  \"method\": ", f);
        if (put_str(f, m->method) < 0)
            return -1;
    }
    if (m && m->bits > 0)
        fprintf(f, ",\n  \"bits\": %d", m->bits);
    if (m) {
        fputs(",\n  \"wavelength_um\": ", f);
        put_short(f, m->wave_um, 1);
        fprintf(f, ",\n  \"wave\": %d", m->wave_index);
        /* Only said when it is not the usual local frame. */
        if (m->global)
            fprintf(f, ",\n  \"frame\": \"global\",\n  \"global_reference\": %d",
                    m->global_ref);
    }
    return 0;
}

static void json_input(FILE *f, sg_ray_kind kind, const sg_ray_in *ray)
{
    int k, n = kind == SG_RAYS_NORMALIZED ? 4 : 6;
    const char *const *names = kind == SG_RAYS_NORMALIZED ? norm_json : sd_json;
    fputc('{', f);
    for (k = 0; k < n; k++) {
        fprintf(f, "%s\"%s\": ", k ? ", " : "", names[k]);
        put_short(f, ray->v[k], 1);
    }
    fputc('}', f);
}

static void json_surfaces(FILE *f, const report_meta *m, const sg_ray_surface *s, int nsurf,
                          const char *indent)
{
    int i, r, nrow = row_count(m, nsurf);
    fputs("[\n", f);
    for (r = 0; r < nrow; r++) {
        const sg_ray_surface *e = &s[i = row_surface(m, r)];
        const char *const key[9] = { "x", "y", "z", "l", "m", "n",
                                     "residual", bound_key(m), "path" };
        const double v[9] = { e->x, e->y, e->z, e->l, e->m, e->n,
                              e->residual, e->error_bound, e->path };
        int k;
        fprintf(f, "%s  {\"surface\": %d", indent, i);
        for (k = 0; k < 9; k++) {
            fprintf(f, ", \"%s\": ", key[k]);
            if (e->status == SG_OK)
                put_num(f, v[k], 1);
            else
                fputs("null", f);
        }
        fputs(", \"opl\": ", f);
        if (e->status == SG_OK)
            put_num(f, e->opl, 1);
        else
            fputs("null", f);
        fprintf(f, ", \"opl_%s\": ", bound_key(m));
        if (e->status == SG_OK)
            put_num(f, e->opl_error_bound, 1);
        else
            fputs("null", f);
        fprintf(f, ", \"status\": \"%s\"}%s\n", report_status_name(e->status),
                r + 1 < nrow ? "," : "");
    }
    fprintf(f, "%s]", indent);
}

/* One ray of the list form.  The separator goes before every ray but
 * the first, so a stream need not know which ray is the last. */
/* The OPD keys of a ray's object: null where there is no OPD, with the
 * reason in opd_status. */
static void json_opd(FILE *f, const report_meta *m, const sg_opd *o, const char *sep)
{
    int ok = o->status == SG_OK;
    fprintf(f, "%s\"opd_status\": \"%s\"", sep, report_status_name(o->status));
    fprintf(f, "%s\"opd_waves\": ", sep);
    put_num(f, ok ? o->opd_waves : NAN, 1);
    fprintf(f, "%s\"opd_%s\": ", sep, bound_key(m));
    put_num(f, ok ? o->error_bound : NAN, 1);
    fprintf(f, "%s\"ex\": ", sep);
    put_num(f, ok ? o->ex : NAN, 1);
    fprintf(f, "%s\"ey\": ", sep);
    put_num(f, ok ? o->ey : NAN, 1);
}

static void json_ray(FILE *f, const report_meta *m, size_t index, int nsurf,
                     const sg_ray_surface *s, int st, sg_ray_kind kind, const sg_ray_in *ray,
                     const sg_opd *opd)
{
    if (index > 0)
        fputs(",\n", f);
    fprintf(f, "    {\"ray\": %zu", index);
    if (ray) {
        fputs(", \"input\": ", f);
        json_input(f, kind, ray);
    }
    fprintf(f, ", \"status\": \"%s\"", report_status_name(st));
    if (opd)
        json_opd(f, m, opd, ", ");
    fputs(", \"surfaces\": ", f);
    json_surfaces(f, m, s, nsurf, "    ");
    fputc('}', f);
}

static void json_single(FILE *f, const report_meta *m, int nsurf, const sg_ray_surface *s,
                        int st, sg_ray_kind kind, const sg_ray_in *ray, const sg_opd *opd)
{
    if (ray) {
        fputs(",\n  \"input\": ", f);
        json_input(f, kind, ray);
    }
    fprintf(f, ",\n  \"status\": \"%s\"", report_status_name(st));
    if (opd)
        json_opd(f, m, opd, ",\n  ");
    fputs(",\n  \"surfaces\": ", f);
    json_surfaces(f, m, s, nsurf, "  ");
    fputs("\n}\n", f);
}

/* stdio keeps the first write error sticky, so checking once at the end
 * (after a flush) catches a full disk anywhere in the report. */
static int finish(FILE *f)
{
    if (fflush(f) != 0)
        return -1;
    if (ferror(f)) {
        if (errno == 0)
            errno = EIO;
        return -1;
    }
    return 0;
}

int report_begin(report_stream *s, FILE *f, report_fmt fmt, const report_meta *m,
                 int nsurf, sg_ray_kind kind, int multi, size_t total)
{
    memset(s, 0, sizeof *s);
    if (!f || nsurf < 0 || (fmt != REPORT_TEXT && fmt != REPORT_CSV && fmt != REPORT_JSON)) {
        errno = EINVAL;
        return -1;
    }
    s->f = f;
    s->fmt = fmt;
    s->m = m;
    s->nsurf = nsurf;
    s->kind = kind;
    s->multi = multi != 0;
    switch (fmt) {
    case REPORT_TEXT:
        text_head(f, m, s->multi, total);
        break;
    case REPORT_CSV:
        csv_head(f, m, s->multi, m && m->csv_inputs, kind);
        break;
    default:
        fputs("{\n", f);
        if (json_meta(f, m) < 0)
            return -1;
        if (s->multi)
            fputs(",\n  \"rays\": [\n", f);
        break;
    }
    return ferror(f) ? -1 : 0;
}

/* Rays [from, to) of a block, numbered on from first; opds, when the
 * header names the OPD columns, holds each ray's OPD (NULL: none known). */
static void write_rays(FILE *f, const report_stream *s, const sg_ray_surface *out,
                       const int *status, size_t from, size_t to, const sg_ray_in *rays,
                       const sg_opd *opds, size_t first)
{
    size_t r;
    for (r = from; r < to; r++) {
        const sg_ray_surface *o = out + r * (size_t)s->nsurf;
        const sg_ray_in *in = rays ? &rays[r] : NULL;
        int st = ray_status(o, s->nsurf, status, r);
        size_t index = first + (r - from);
        /* The OPD columns are the header's: present whenever it names them. */
        const sg_opd none = { SG_EINVAL, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN };
        const sg_opd *opd = s->m && s->m->opd ? (opds ? &opds[r] : &none) : NULL;
        switch (s->fmt) {
        case REPORT_TEXT:
            text_ray(f, s->m, s->multi, index, s->nsurf, o, st, s->kind, in, opd);
            break;
        case REPORT_CSV:
            csv_ray(f, s->m, s->multi, index, s->nsurf, o, s->kind,
                    s->m && s->m->csv_inputs ? in : NULL, opd);
            break;
        default:
            if (s->multi)
                json_ray(f, s->m, index, s->nsurf, o, st, s->kind, in, opd);
            else
                json_single(f, s->m, s->nsurf, o, st, s->kind, in, opd);
            break;
        }
    }
}

/* One thread's share of a block, formatted into memory. */
typedef struct fmt_job {
    const report_stream *s;
    const sg_ray_surface *out;
    const int *status;
    const sg_ray_in *rays;
    const sg_opd *opds;
    size_t from, to;
    char *text;
    size_t len, cap;
    int failed;
} fmt_job;

/* The memory a share is formatted into, sized up front from the rows so
 * it seldom grows (open_memstream grows by copying and zeroing). */
static ssize_t job_write(void *cookie, const char *buf, size_t n)
{
    fmt_job *j = cookie;
    if (j->len + n > j->cap) {
        size_t cap = j->cap ? j->cap : 4096;
        char *p;
        while (cap < j->len + n)
            cap *= 2;
        p = realloc(j->text, cap);
        if (!p) {
            j->failed = 1;
            errno = ENOMEM;
            return -1;
        }
        j->text = p;
        j->cap = cap;
    }
    memcpy(j->text + j->len, buf, n);
    j->len += n;
    return (ssize_t)n;
}

/* A CSV share straight into the job's memory. */
static void fmt_csv(fmt_job *j)
{
    const report_stream *s = j->s;
    const sg_opd none = { SG_EINVAL, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN };
    const int inputs = s->m && s->m->csv_inputs;
    size_t r;
    int i, nrow = row_count(s->m, s->nsurf);
    for (r = j->from; r < j->to; r++) {
        const sg_ray_surface *o = j->out + r * (size_t)s->nsurf;
        const sg_ray_in *in = inputs && j->rays ? &j->rays[r] : NULL;
        const sg_opd *opd = s->m && s->m->opd ? (j->opds ? &j->opds[r] : &none) : NULL;
        size_t index = s->next + r;
        for (i = 0; i < nrow; i += CSV_GROUP) {
            int i1 = nrow - i < CSV_GROUP ? nrow : i + CSV_GROUP;
            size_t room = (size_t)(i1 - i) * CSV_ROW_MAX;
            char *end;
            if (j->cap - j->len < room) {
                size_t cap = j->cap ? 2 * j->cap : 256 * (size_t)nrow * (j->to - j->from);
                char *p;
                if (cap < j->len + room)
                    cap = j->len + room;
                p = realloc(j->text, cap);
                if (!p) {
                    j->failed = 1;
                    errno = ENOMEM;
                    return;
                }
                j->text = p;
                j->cap = cap;
            }
            end = csv_rows(j->text + j->len, s->multi, index, i, i1, s->nsurf,
                           s->m ? s->m->surfaces : NULL, o, s->kind, in, opd);
            j->len = (size_t)(end - j->text);
        }
    }
}

static void *fmt_main(void *arg)
{
    fmt_job *j = arg;
    cookie_io_functions_t io = { NULL, job_write, NULL, NULL };
    FILE *f;
    j->len = 0;
    if (j->from == j->to)
        return NULL;
    if (j->s->fmt == REPORT_CSV) {
        fmt_csv(j);
        return NULL;
    }
    f = fopencookie(j, "w", io);
    if (!f) {
        j->failed = 1;
        return NULL;
    }
    /* The stream is this thread's alone; stdio's locks would only cost. */
    __fsetlocking(f, FSETLOCKING_BYCALLER);
    write_rays(f, j->s, j->out, j->status, j->from, j->to, j->rays, j->opds,
               j->s->next + j->from);
    if (ferror(f))
        j->failed = 1;
    if (fclose(f) != 0)
        j->failed = 1;
    return NULL;
}

/* Below this many rays a block is written on the calling thread. */
#define PAR_MIN_RAYS 64
#define PAR_MAX_THREADS 64
/* Rows a thread formats in a round: its text (about 200 bytes a CSV row)
 * stays in a buffer of about two megabytes that the next round reuses;
 * rounds this long make the threads' start a small part of the time. */
#define PAR_ROUND_ROWS 8192

/* Formats the block in rounds; in each, nthreads contiguous shares go
 * each into its own memory and are written in order: the bytes of the
 * serial loop.  Returns 0, 1 if the first round could not be made (the
 * caller writes serially), or -1 on a write error. */
static int write_parallel(report_stream *s, const sg_ray_surface *out, const int *status,
                          size_t n, const sg_ray_in *rays, const sg_opd *opds, int nthreads)
{
    fmt_job job[PAR_MAX_THREADS];
    pthread_t tid[PAR_MAX_THREADS];
    int started[PAR_MAX_THREADS];
    int k, rc = 0;
    int nrow = row_count(s->m, s->nsurf);
    size_t per = PAR_ROUND_ROWS / (size_t)(nrow > 0 ? nrow : 1), at, round;

    if (per < 16)
        per = 16;
    round = per * (size_t)nthreads;
    memset(job, 0, sizeof job);
    for (at = 0; at < n && rc == 0; at += round) {
        size_t m = n - at < round ? n - at : round;
        for (k = 0; k < nthreads; k++) {
            job[k].s = s;
            job[k].out = out;
            job[k].status = status;
            job[k].rays = rays;
            job[k].opds = opds;
            job[k].from = at + m * (size_t)k / (size_t)nthreads;
            job[k].to = at + m * (size_t)(k + 1) / (size_t)nthreads;
            /* The calling thread formats share 0 itself. */
            started[k] = k > 0 && pthread_create(&tid[k], NULL, fmt_main, &job[k]) == 0;
        }
        fmt_main(&job[0]);
        for (k = 1; k < nthreads; k++) {
            if (started[k])
                pthread_join(tid[k], NULL);
            else
                fmt_main(&job[k]);
        }
        for (k = 0; k < nthreads; k++)
            if (job[k].failed)
                rc = at == 0 ? 1 : -1;
        for (k = 0; k < nthreads && rc == 0; k++)
            if (job[k].len > 0 && fwrite(job[k].text, 1, job[k].len, s->f) != job[k].len)
                rc = -1;
    }
    for (k = 0; k < nthreads; k++)
        free(job[k].text);
    if (rc < 0 && errno == 0)
        errno = ENOMEM;
    return rc;
}

static int resolve_threads(int threads)
{
    long n = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1)
        n = 1;
    return n > PAR_MAX_THREADS ? PAR_MAX_THREADS : (int)n;
}

void report_set_threads(report_stream *s, int threads)
{
    s->threads = resolve_threads(threads);
}

int report_rays(report_stream *s, const sg_ray_surface *out, const int *status, size_t n,
                const sg_ray_in *rays)
{
    return report_rays_opd(s, out, status, n, rays, NULL);
}

int report_rays_opd(report_stream *s, const sg_ray_surface *out, const int *status, size_t n,
                    const sg_ray_in *rays, const sg_opd *opds)
{
    if (!s->f || (n > 0 && !out) || (!s->multi && s->next + n > 1)) {
        errno = EINVAL;
        return -1;
    }
    if (s->threads > 1 && s->multi && n >= PAR_MIN_RAYS) {
        int nt = (size_t)s->threads < n / (PAR_MIN_RAYS / 2) ? s->threads
                                                                : (int)(n / (PAR_MIN_RAYS / 2));
        int rc = write_parallel(s, out, status, n, rays, opds, nt);
        if (rc == 0) {
            s->next += n;
            return ferror(s->f) ? -1 : 0;
        }
        if (rc < 0)
            return -1;
    }
    write_rays(s->f, s, out, status, 0, n, rays, opds, s->next);
    s->next += n;
    return ferror(s->f) ? -1 : 0;
}

int report_end(report_stream *s)
{
    if (!s->f) {
        errno = EINVAL;
        return -1;
    }
    if (s->fmt == REPORT_JSON && s->multi)
        fputs(s->next > 0 ? "\n  ]\n}\n" : "  ]\n}\n", s->f);
    return finish(s->f);
}

void report_opd_block(sg_tracer *t, sg_opd_ref *ref, const sg_ray_in *rays, size_t n,
                      const sg_ray_surface *out, int nsurf, sg_opd *opd)
{
    report_opd_block_mt(t, ref, rays, n, out, nsurf, opd, 1);
}

/* A run of rays of one field: its first ray and its sphere. */
typedef struct opd_run {
    size_t from;
    sg_opd_ref ref;
} opd_run;

typedef struct opd_job {
    const sg_tracer *t;
    const opd_run *runs;
    size_t nrun, from, to;
    const sg_ray_surface *out;
    int nsurf;
    sg_opd *opd;
} opd_job;

static void *opd_main(void *arg)
{
    const opd_job *j = arg;
    size_t r, k = 0;
    /* The run holding the share's first ray. */
    while (k + 1 < j->nrun && j->runs[k + 1].from <= j->from)
        k++;
    /* Each run's part of the share at once, on vector lanes. */
    for (r = j->from; r < j->to; k++) {
        size_t end = k + 1 < j->nrun && j->runs[k + 1].from < j->to ? j->runs[k + 1].from : j->to;
        sg_opd_of_rays(j->t, &j->runs[k].ref,
                       &j->out[r * (size_t)j->nsurf + (size_t)j->nsurf - 1], (size_t)j->nsurf,
                       end - r, &j->opd[r]);
        r = end;
    }
    return NULL;
}

/* Below this many rays, or without memory for the runs, one thread. */
#define OPD_PAR_MIN 256

static void opd_block_runs(sg_tracer *t, sg_opd_ref *ref, const sg_ray_in *rays, size_t n,
                           const sg_ray_surface *out, int nsurf, sg_opd *opd, int threads);

/* Fields a block may hold for its rays to be taken field by field. */
#define OPD_FIELDS 64

/* The block's rays field by field, each field's in their order, into
 * perm: when the fields (as the sphere's hx, hy compare them) are few
 * and interleaved, so that each field's sphere is found once a block, not
 * once a run.  Returns 0 (perm unset) when the rays already come field by
 * field or the fields are many. */
static int opd_field_order(const sg_ray_in *rays, size_t n, size_t *perm)
{
    double fx[OPD_FIELDS], fy[OPD_FIELDS];
    size_t count[OPD_FIELDS + 1], r, runs = 0;
    int nf = 0, f, last = -1;
    unsigned char *id = malloc(n);
    if (!id)
        return 0;
    for (r = 0; r < n; r++) {
        for (f = 0; f < nf && !(fx[f] == rays[r].v[0] && fy[f] == rays[r].v[1]); f++)
            ;
        if (f == nf) {
            if (nf == OPD_FIELDS || rays[r].v[0] != rays[r].v[0] ||
                rays[r].v[1] != rays[r].v[1]) {
                free(id);
                return 0;
            }
            fx[nf] = rays[r].v[0];
            fy[nf++] = rays[r].v[1];
        }
        runs += f != last;
        last = f;
        id[r] = (unsigned char)f;
    }
    if (runs == (size_t)nf) {
        free(id);
        return 0;
    }
    memset(count, 0, sizeof count);
    for (r = 0; r < n; r++)
        count[id[r] + 1]++;
    for (f = 0; f < nf; f++)
        count[f + 1] += count[f];
    for (r = 0; r < n; r++)
        perm[count[id[r]]++] = r;
    free(id);
    return 1;
}

void report_opd_block_mt(sg_tracer *t, sg_opd_ref *ref, const sg_ray_in *rays, size_t n,
                         const sg_ray_surface *out, int nsurf, sg_opd *opd, int threads)
{
    size_t *perm = n > 1 ? malloc(n * sizeof *perm) : NULL;
    sg_ray_in *r2 = NULL;
    sg_ray_surface *img = NULL;
    sg_opd *o2 = NULL;
    size_t k;
    /* A ray's OPD depends on its image row and its field's sphere alone,
     * so the rays may be taken in any order: field by field, through
     * copies of their launches and image rows. */
    if (perm && opd_field_order(rays, n, perm) && (r2 = malloc(n * sizeof *r2)) &&
        (img = malloc(n * sizeof *img)) && (o2 = malloc(n * sizeof *o2))) {
        for (k = 0; k < n; k++) {
            r2[k] = rays[perm[k]];
            img[k] = out[perm[k] * (size_t)nsurf + (size_t)nsurf - 1];
        }
        opd_block_runs(t, ref, r2, n, img, 1, o2, threads);
        for (k = 0; k < n; k++)
            opd[perm[k]] = o2[k];
    } else {
        opd_block_runs(t, ref, rays, n, out, nsurf, opd, threads);
    }
    free(perm);
    free(r2);
    free(img);
    free(o2);
}

/* The OPD of rays in runs of one field, each run's sphere found once. */
static void opd_block_runs(sg_tracer *t, sg_opd_ref *ref, const sg_ray_in *rays, size_t n,
                           const sg_ray_surface *out, int nsurf, sg_opd *opd, int threads)
{
    opd_run *runs = NULL;
    size_t r, nrun = 0, cap = 0;
    int nt = resolve_threads(threads), k;
    opd_job job[PAR_MAX_THREADS];
    pthread_t tid[PAR_MAX_THREADS];
    int started[PAR_MAX_THREADS];
    const sg_opd_ref first = *ref;

    /* A reference is found once for a run of rays of one field (sets and
     * ray lists are usually field-major), in order, as the serial loop
     * finds it; *ref ends as the last field's. */
    if (nt > 1 && n >= OPD_PAR_MIN) {
        for (r = 0; r < n; r++) {
            if (ref->status == SG_EINVAL || ref->hx != rays[r].v[0] || ref->hy != rays[r].v[1]) {
                sg_opd_reference(t, rays[r].v[0], rays[r].v[1], ref, NULL);
                if (ref->status == SG_EINVAL)
                    ref->status = SG_ERANGE;
            } else if (nrun > 0) {
                continue;
            }
            if (nrun == cap) {
                size_t c = cap ? 2 * cap : 16;
                opd_run *p = realloc(runs, c * sizeof *p);
                if (!p)
                    break;
                runs = p;
                cap = c;
            }
            runs[nrun].from = r;
            runs[nrun].ref = *ref;
            nrun++;
        }
        if (r == n) {
            if ((size_t)nt > n / (OPD_PAR_MIN / 2))
                nt = (int)(n / (OPD_PAR_MIN / 2));
            for (k = 0; k < nt; k++) {
                job[k].t = t;
                job[k].runs = runs;
                job[k].nrun = nrun;
                job[k].from = n * (size_t)k / (size_t)nt;
                job[k].to = n * (size_t)(k + 1) / (size_t)nt;
                job[k].out = out;
                job[k].nsurf = nsurf;
                job[k].opd = opd;
                started[k] = k > 0 && pthread_create(&tid[k], NULL, opd_main, &job[k]) == 0;
            }
            opd_main(&job[0]);
            for (k = 1; k < nt; k++) {
                if (started[k])
                    pthread_join(tid[k], NULL);
                else
                    opd_main(&job[k]);
            }
            free(runs);
            return;
        }
        /* Out of memory for the runs: all on this thread, from the
         * sphere the block began with. */
        free(runs);
        *ref = first;
    }
    for (r = 0; r < n;) {
        size_t end = r + 1;
        if (ref->status == SG_EINVAL || ref->hx != rays[r].v[0] || ref->hy != rays[r].v[1]) {
            sg_opd_reference(t, rays[r].v[0], rays[r].v[1], ref, NULL);
            if (ref->status == SG_EINVAL)
                ref->status = SG_ERANGE;
        }
        /* The run of rays in this field, at once. */
        while (end < n && ref->hx == rays[end].v[0] && ref->hy == rays[end].v[1])
            end++;
        sg_opd_of_rays(t, ref, &out[r * (size_t)nsurf + (size_t)nsurf - 1], (size_t)nsurf,
                       end - r, &opd[r]);
        r = end;
    }
}

int report_write(FILE *f, report_fmt fmt, const report_meta *m, int nsurf,
                 const sg_ray_surface *out, const int *status, size_t nray,
                 sg_ray_kind kind, const sg_ray_in *rays)
{
    return report_write_opd(f, fmt, m, nsurf, out, status, nray, kind, rays, NULL);
}

int report_write_opd(FILE *f, report_fmt fmt, const report_meta *m, int nsurf,
                     const sg_ray_surface *out, const int *status, size_t nray,
                     sg_ray_kind kind, const sg_ray_in *rays, const sg_opd *opd)
{
    report_stream s;
    if (!f || nsurf < 0 || (nray > 0 && !out)) {
        errno = EINVAL;
        return -1;
    }
    if (report_begin(&s, f, fmt, m, nsurf, kind, nray != 1, nray) < 0)
        return -1;
    if (report_rays_opd(&s, out, status, nray, rays, opd) < 0)
        return -1;
    return report_end(&s);
}

/* ------------------------------------------------------------ paraxial */

struct pfield {
    const char *label; /* text */
    const char *key;   /* JSON and CSV */
    size_t off;
};

#define PF_(label, key, member) { label, key, offsetof(sg_paraxial, member) }
static const struct pfield pfields[] = {
    PF_("Effective focal length", "efl", efl),
    PF_("Back focal length", "bfl", bfl),
    PF_("Paraxial image distance", "image_distance", image_dist),
    PF_("Entrance pupil diameter", "entrance_pupil_diameter", epd),
    PF_("Entrance pupil position", "entrance_pupil_position", enp_pos),
    PF_("Exit pupil diameter", "exit_pupil_diameter", exp_diam),
    PF_("Exit pupil position", "exit_pupil_position", exp_pos),
    PF_("Image space F/#", "image_fnum", image_fnum),
    PF_("Paraxial working F/#", "working_fnum", working_fnum),
    PF_("Object space NA", "object_na", object_na),
    PF_("Paraxial image height", "paraxial_image_height", parax_image_height),
    PF_("Paraxial magnification", "magnification", magnification),
    PF_("Total track", "total_track", total_track),
    PF_("Paraxial stop radius", "stop_radius", stop_radius),
};
#undef PF_
#define NPFIELDS (sizeof pfields / sizeof pfields[0])

static double pget(const sg_paraxial *p, size_t k)
{
    double v;
    memcpy(&v, (const char *)p + pfields[k].off, sizeof v);
    return v;
}

int report_write_paraxial(FILE *f, report_fmt fmt, const report_meta *m,
                          const sg_paraxial *p)
{
    size_t k;
    char b[40];
    if (!f || !p) {
        errno = EINVAL;
        return -1;
    }
    switch (fmt) {
    case REPORT_TEXT:
        fprintf(f, "%-24s:  ", "Design");
        safe_fputs(m && m->design ? m->design : "(untitled)", f);
        fputc('\n', f);
        if (m)
            fprintf(f, "%-24s:  %s um (wave %d)\n", "Wavelength",
                    shortest(m->wave_um, b, sizeof b), m->wave_index);
        for (k = 0; k < NPFIELDS; k++) {
            double v = pget(p, k);
            fprintf(f, "%-24s:  ", pfields[k].label);
            if (isinf(v) || isnan(v))
                fputs(isnan(v) ? "undefined" : v > 0 ? "Infinity" : "-Infinity", f);
            else
                put_short(f, v, 0);
            fputc('\n', f);
        }
        break;
    case REPORT_CSV:
        fputs("quantity,value\n", f);
        for (k = 0; k < NPFIELDS; k++) {
            fprintf(f, "%s,", pfields[k].key);
            put_short(f, pget(p, k), 0);
            fputc('\n', f);
        }
        break;
    case REPORT_JSON:
        fputs("{\n", f);
        if (json_meta(f, m) < 0)
            return -1;
        for (k = 0; k < NPFIELDS; k++) {
            fprintf(f, ",\n  \"%s\": ", pfields[k].key);
            put_short(f, pget(p, k), 1);
        }
        fputs("\n}\n", f);
        break;
    default:
        errno = EINVAL;
        return -1;
    }
    return finish(f);
}
