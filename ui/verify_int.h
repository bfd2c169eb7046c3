/*
 * verify_int.h - what "sagitta verify"'s files share: the methods compared,
 * the limits, the digits of a point, the JSON builder and the output.
 */
#ifndef SG_UI_VERIFY_INT_H
#define SG_UI_VERIFY_INT_H

#include "cli.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <mpfr.h>

#include "args.h"
#include "measure.h"
#include "report.h"
#include "safetext.h"
#include "xquant.h"


enum { M_PRECISE = 0, M_CLASSIC = 1, M_MPFR = 2, NMETHOD = 3 };
static const char *const mname[NMETHOD] = { "precise", "classic", "mpfr" };
static const sg_method mcode[NMETHOD] = { SG_METHOD_PRECISE, SG_METHOD_CLASSIC,
                                          SG_METHOD_MPFR };

#define DIGITS_CAP MEAS_DIGITS_CAP
/* The least reference precision verify accepts: over twice the precise
 * method's 53-bit output and above its 106-bit working precision. */
#define VERIFY_MIN_BITS 128
#define DEFAULT_GRID 7
#define DEFAULT_COUNT 10000
#define DEFAULT_SEED 20230421
/* The rays are traced in blocks, but each compared point's digits and
 * bound/error are kept for the exact medians (24 bytes a ray-surface),
 * so the set is bounded: this many ray-surfaces take about 48 MB. */
#define MAX_RAY_SURFACES 2000000
/* Failed rays and disagreements listed in text output; JSON lists all. */
#define TEXT_LIST_MAX 20


/* ----------------------------------------------------------------- numbers */

static inline double ulp_of(double x)
{
    x = fabs(x);
    if (!isfinite(x))
        return NAN;
    if (x == 0.0)
        return nextafter(0.0, 1.0);
    return nextafter(x, INFINITY) - x;
}

static inline double max_abs3(const double v[3])
{
    return fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
}

/* The digits of a point: see measure.h, shared with the editor's digits
 * view.  A reference point at the origin (a chief ray through a vertex)
 * has no size of its own, so it borrows scale, the size of the other
 * points on its surface; 0 judges it against nothing. */
static inline double point_digits_s(const double a[3], const double b[3], double scale)
{
    return meas_point_digits(a, b, scale);
}

static inline double point_digits(const double a[3], const double b[3])
{
    return meas_point_digits(a, b, 0.0);
}

static inline double max_diff3(const double a[3], const double b[3])
{
    double e = 0.0;
    int k;
    for (k = 0; k < 3; k++) {
        double d = fabs(a[k] - b[k]);
        if (!(d <= e)) /* keeps a NaN */
            e = d;
    }
    return e;
}

static inline void point_of(const sg_ray_surface *s, double p[3])
{
    p[0] = s->x;
    p[1] = s->y;
    p[2] = s->z;
}

static inline void dir_of(const sg_ray_surface *s, double p[3])
{
    p[0] = s->l;
    p[1] = s->m;
    p[2] = s->n;
}

static inline int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

/* Sorts v in place and returns its median (NaN when empty). */
static inline double median(double *v, size_t n)
{
    if (n == 0)
        return NAN;
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static inline double min_of(const double *v, size_t n)
{
    double m = NAN;
    size_t k;
    for (k = 0; k < n; k++)
        if (k == 0 || v[k] < m)
            m = v[k];
    return m;
}

/* The reference's own failure (it found no aim, or its iteration did not
 * converge), as opposed to a ray that misses, TIRs or is vignetted. */
static inline int ref_broken_status(int st)
{
    return st == SG_EAIM || st == SG_ENOCONV || st == SG_EUNCERT;
}

/* The surface where a ray stopped, or -1 when it reached the image. */
static inline int fail_surface(const sg_ray_surface *out, int nsurf)
{
    int i;
    for (i = 0; i < nsurf; i++)
        if (out[i].status != SG_OK)
            return i;
    return -1;
}

/* The precise bound fails when the difference from the reference exceeds
 * it plus the reference's own bound: the reference is a double too, within
 * its bound (half an ulp) of the exact value, so nothing smaller proves the
 * precise bound wrong. */
static inline int bound_fails(double err, double bound, double refbound)
{
    if (!isfinite(refbound))
        refbound = 0.0;
    return !(err <= bound + refbound);
}

/* -------------------------------------------------------------------- JSON */

/* A JSON tree whose numbers are printed %.17g; bad counts failed inserts,
 * which only happen when memory runs out. */
typedef struct jb {
    int bad;
} jb;

static inline cJSON *jnumber(double v)
{
    char buf[40];
    if (!isfinite(v))
        return cJSON_CreateNull();
    snprintf(buf, sizeof buf, "%.17g", v);
    return cJSON_CreateRaw(buf);
}

static inline cJSON *jput(jb *b, cJSON *obj, const char *name, cJSON *item)
{
    int ok = item != NULL &&
             (cJSON_IsArray(obj) ? cJSON_AddItemToArray(obj, item)
                                 : cJSON_AddItemToObject(obj, name, item));
    if (!ok) {
        cJSON_Delete(item);
        b->bad++;
        return NULL;
    }
    return item;
}

static inline void jnum(jb *b, cJSON *obj, const char *name, double v)
{
    jput(b, obj, name, jnumber(v));
}

static inline void jint(jb *b, cJSON *obj, const char *name, long v)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%ld", v);
    jput(b, obj, name, cJSON_CreateRaw(buf));
}

static inline void jstr(jb *b, cJSON *obj, const char *name, const char *s)
{
    jput(b, obj, name, cJSON_CreateString(s));
}

static inline void jbool(jb *b, cJSON *obj, const char *name, int v)
{
    jput(b, obj, name, cJSON_CreateBool(v));
}

static inline cJSON *jobj(jb *b, cJSON *obj, const char *name)
{
    return jput(b, obj, name, cJSON_CreateObject());
}

static inline cJSON *jarr(jb *b, cJSON *obj, const char *name)
{
    return jput(b, obj, name, cJSON_CreateArray());
}

static inline void jvec3(jb *b, cJSON *obj, const char *name, const double v[3])
{
    cJSON *a = jarr(b, obj, name);
    int k;
    if (!a)
        return;
    for (k = 0; k < 3; k++)
        jnum(b, a, NULL, v[k]);
}

/* Prints the tree and frees it; returns the exit status. */
static inline int jemit(jb *b, cJSON *root, FILE *f)
{
    char *s = b->bad ? NULL : cJSON_Print(root);
    int rc = CLI_EXIT_OK;
    cJSON_Delete(root);
    if (!s) {
        cli_error("out of memory writing JSON");
        return CLI_EXIT_INTERNAL;
    }
    if (fputs(s, f) < 0 || fputc('\n', f) < 0)
        rc = CLI_EXIT_FILE;
    free(s);
    return rc;
}

/* -------------------------------------------------------------- the output */

typedef struct vout {
    FILE *f;
    const char *path;
} vout;

static inline int open_out(vout *o, const char *path)
{
    o->path = path;
    o->f = cli_open_output(path);
    return o->f ? CLI_EXIT_OK : CLI_EXIT_FILE;
}

/* Closes the output; a write error wins over rc unless rc is already an
 * error. */
static inline int close_out(vout *o, int rc)
{
    int crc;
    if (!o->f)
        return rc;
    crc = cli_close_output(o->f, o->path);
    o->f = NULL;
    return rc == CLI_EXIT_OK || rc == CLI_EXIT_VERIFY ? (crc ? crc : rc) : rc;
}


/* verify_design.c: a design's rays against the mpfr reference. */
int verify_design(const char *path, const double *ray4, int grid, int bits, int wave1, int fmt,
                  const char *output);
/* verify_paper.c: the paper's Tables 1 and 2. */
int experiment_table1(int bits, int fmt, const char *output);
int experiment_table2(int bits, size_t count, uint64_t seed, int fmt, const char *output);

#endif
