/*
 * design_json.c - the JSON design format read (sagitta-design(5)): load
 * and parse, every value checked and named in its message; json_write.c
 * writes and saves it.
 *
 * cJSON does the parsing and string escaping.
 */
/* realpath() is XSI, beyond the POSIX base the build asks for. */
#define _XOPEN_SOURCE 700

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <locale.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "formats_int.h"
#include "design.h"

/* Larger inputs are refused before parsing: a design this big is a mistake,
 * and cJSON's tree would need several times the text's size in memory. */
#define DESIGN_MAX_BYTES ((size_t)64 * 1024 * 1024)

#define FORMAT_NAME "sagitta-design"

/* The names of an enumeration or a closed set of texts, from the table. */
static const sg_param *sysp(const char *key)
{
    return sg_param_find(SG_SCOPE_SYSTEM, key);
}
#define units_names (sysp("units")->names)
#define field_type_names (sysp("fields.type")->names)
#define field_norm_names (sysp("fields.normalization")->names)
#define aper_type_names (sysp("aperture.type")->names)
#define aim_names (sysp("ray_aiming")->names)
#define surf_type_names (sg_param_find(SG_SCOPE_SURFACE, "type")->names)
#define NELEM(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* ------------------------------------------------------------------------
 * Messages
 * ------------------------------------------------------------------------ */

typedef struct jctx {
    const char *name; /* file name or caller's label, for messages */
    sg_diag *d;
} jctx;

/* Copies s for display in a message: control bytes become '?', and a long
 * text is cut (on a UTF-8 character boundary) and marked with "...". */
static void show_text(char *dst, size_t n, const char *s)
{
    size_t k = 0, max = n > 4 ? n - 4 : 0;
    for (; *s && k < max; s++, k++) {
        unsigned char ch = (unsigned char)*s;
        dst[k] = (ch < 0x20 || ch == 0x7f) ? '?' : (char)ch;
    }
    if (*s) {
        /* Drop a character the cut would split: its continuation bytes
         * already copied, then its lead byte. */
        if (((unsigned char)*s & 0xC0) == 0x80) {
            while (k > 0 && ((unsigned char)dst[k - 1] & 0xC0) == 0x80)
                k--;
            if (k > 0)
                k--;
        }
        memcpy(dst + k, "...", 3);
        k += 3;
    }
    dst[k] = '\0';
}

/* A short description of a JSON value, for "expected X, got Y". */
static void describe(const cJSON *v, char *buf, size_t n)
{
    char tmp[48];
    if (cJSON_IsString(v)) {
        show_text(tmp, sizeof tmp, v->valuestring ? v->valuestring : "");
        snprintf(buf, n, "string \"%s\"", tmp);
    } else if (cJSON_IsNumber(v)) {
        if (isfinite(v->valuedouble)) {
            sg_json_fmt_double(tmp, v->valuedouble);
            snprintf(buf, n, "number %s", tmp);
        } else {
            snprintf(buf, n, "a number too large for a double");
        }
    } else if (cJSON_IsTrue(v)) {
        snprintf(buf, n, "true");
    } else if (cJSON_IsFalse(v)) {
        snprintf(buf, n, "false");
    } else if (cJSON_IsNull(v)) {
        snprintf(buf, n, "null");
    } else if (cJSON_IsArray(v)) {
        snprintf(buf, n, "an array");
    } else if (cJSON_IsObject(v)) {
        snprintf(buf, n, "an object");
    } else {
        snprintf(buf, n, "an invalid value");
    }
}

/* Records "NAME: WHERE: message" and returns code. */
static int perr(jctx *c, int code, const char *where, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static int perr(jctx *c, int code, const char *where, const char *fmt, ...)
{
    char msg[SG_DIAG_MSG];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (where && where[0])
        return sg_diag_set(c->d, code, "%s: %s: %s", c->name, where, msg);
    return sg_diag_set(c->d, code, "%s: %s", c->name, msg);
}

static void pwarn(jctx *c, const char *where, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void pwarn(jctx *c, const char *where, const char *fmt, ...)
{
    char msg[SG_DIAG_MSG];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (where && where[0])
        sg_diag_warn(c->d, "%s: %s: %s", c->name, where, msg);
    else
        sg_diag_warn(c->d, "%s: %s", c->name, msg);
}

/* Joins an object's place and a key: "surface 3" + "radius". */
static const char *join(char *buf, size_t n, const char *where, const char *key)
{
    if (where && where[0])
        snprintf(buf, n, "%s: %s", where, key);
    else
        snprintf(buf, n, "%s", key);
    return buf;
}

/* ------------------------------------------------------------------------
 * Reading values
 * ------------------------------------------------------------------------ */

/* The last member named key, matching the choice pick_keys() makes. */
static const cJSON *last_item(const cJSON *obj, const char *key)
{
    const cJSON *it, *found = NULL;
    cJSON_ArrayForEach(it, obj) {
        if (it->string && strcmp(it->string, key) == 0)
            found = it;
    }
    return found;
}

/* Fills out[i] with the member named names[i] (the last one when a key is
 * repeated, as JavaScript does) and warns about unknown and repeated keys. */
static void pick_keys(jctx *c, const cJSON *obj, const char *where,
                      const char *const names[], int n, const cJSON *out[])
{
    const cJSON *it;
    int i;
    for (i = 0; i < n; i++)
        out[i] = NULL;
    cJSON_ArrayForEach(it, obj) {
        const char *k = it->string ? it->string : "";
        char shown[48];
        for (i = 0; i < n && strcmp(k, names[i]) != 0; i++)
            ;
        show_text(shown, sizeof shown, k);
        if (i == n) {
            pwarn(c, where, "unknown key \"%s\" ignored", shown);
        } else {
            if (out[i])
                pwarn(c, where, "duplicate key \"%s\"; the last one is used", shown);
            out[i] = it;
        }
    }
}

static int expect_object(jctx *c, const cJSON *v, const char *where)
{
    char got[80];
    if (cJSON_IsObject(v))
        return SG_OK;
    describe(v, got, sizeof got);
    return perr(c, SG_EPARSE, where, "expected an object, got %s", got);
}

static int get_finite(jctx *c, const cJSON *v, const char *where, double *out)
{
    char got[80];
    if (!cJSON_IsNumber(v)) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected a number, got %s", got);
    }
    if (!isfinite(v->valuedouble))
        return perr(c, SG_EPARSE, where, "must be finite (the number is too large for a double)");
    *out = v->valuedouble;
    return SG_OK;
}

static int get_nonneg(jctx *c, const cJSON *v, const char *where, double *out)
{
    char got[80];
    if (!cJSON_IsNumber(v)) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected a number, got %s", got);
    }
    if (!isfinite(v->valuedouble) || v->valuedouble < 0.0) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "must be finite and not negative, got %s", got);
    }
    *out = v->valuedouble;
    return SG_OK;
}

static int get_positive(jctx *c, const cJSON *v, const char *where, double *out)
{
    char got[80];
    if (!cJSON_IsNumber(v)) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected a number, got %s", got);
    }
    if (!isfinite(v->valuedouble) || !(v->valuedouble > 0.0)) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "must be positive and finite, got %s", got);
    }
    *out = v->valuedouble;
    return SG_OK;
}

static int get_int(jctx *c, const cJSON *v, const char *where, int *out)
{
    char got[80];
    double x;
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) ||
        floor(v->valuedouble) != v->valuedouble || fabs(v->valuedouble) > 1e9) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected an integer, got %s", got);
    }
    x = v->valuedouble;
    *out = (int)x;
    return SG_OK;
}

static int get_bool(jctx *c, const cJSON *v, const char *where, int *out)
{
    char got[80];
    if (!cJSON_IsBool(v)) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected true or false, got %s", got);
    }
    *out = cJSON_IsTrue(v) ? 1 : 0;
    return SG_OK;
}

/* A string that must fit a buffer of cap bytes with its terminator. */
static int get_string(jctx *c, const cJSON *v, const char *where, char *dst, size_t cap)
{
    char got[80];
    size_t len;
    if (!cJSON_IsString(v) || !v->valuestring) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected a string, got %s", got);
    }
    len = strlen(v->valuestring);
    if (len >= cap)
        return perr(c, SG_EPARSE, where, "too long (%zu bytes; the limit is %zu)", len, cap - 1);
    memcpy(dst, v->valuestring, len + 1);
    return SG_OK;
}

static int ascii_casecmp(const char *a, const char *b)
{
    for (; *a && *b; a++, b++) {
        int x = tolower((unsigned char)*a), y = tolower((unsigned char)*b);
        if (x != y)
            return x - y;
    }
    return (unsigned char)*a - (unsigned char)*b;
}

/* One of a fixed set of names (case-insensitive); *out is its index. */
static int get_enum(jctx *c, const cJSON *v, const char *where,
                    const char *const names[], int n, int *out)
{
    char got[80], allowed[256];
    size_t k = 0;
    int i;
    if (cJSON_IsString(v) && v->valuestring) {
        for (i = 0; i < n; i++) {
            if (ascii_casecmp(v->valuestring, names[i]) == 0) {
                *out = i;
                return SG_OK;
            }
        }
    }
    allowed[0] = '\0';
    for (i = 0; i < n && k < sizeof allowed; i++) {
        int w = snprintf(allowed + k, sizeof allowed - k, "%s\"%s\"",
                         i == 0 ? "" : (i == n - 1 ? " or " : ", "), names[i]);
        if (w < 0)
            break;
        k += (size_t)w;
    }
    describe(v, got, sizeof got);
    return perr(c, SG_EPARSE, where, "expected %s, got %s", allowed, got);
}

/* +1 for "inf", "+inf", "infinity", ...; -1 for the negative forms; else 0. */
static int inf_word(const char *s)
{
    int sign = 1;
    if (!s)
        return 0;
    if (*s == '+' || *s == '-') {
        sign = *s == '-' ? -1 : 1;
        s++;
    }
    if (ascii_casecmp(s, "inf") == 0 || ascii_casecmp(s, "infinity") == 0)
        return sign;
    return 0;
}

static int get_radius(jctx *c, const cJSON *v, const char *where, double *out)
{
    char got[80];
    if (cJSON_IsNumber(v)) {
        if (!isfinite(v->valuedouble))
            return perr(c, SG_EPARSE, where,
                        "the number is too large for a double; write \"inf\" for a flat surface");
        /* A radius below 1/DBL_MAX (5e-324 ...) has no curvature in the
         * doubles: .zmx files store the curvature, and traces use it. */
        if (v->valuedouble != 0.0 && !isfinite(1.0 / v->valuedouble))
            return perr(c, SG_ERANGE, where,
                        "%g is so small that its curvature 1/R is beyond the doubles; "
                        "|R| must be at least %g", v->valuedouble, 1.0 / DBL_MAX);
        /* Zemax writes 0 for a flat surface; it can only mean that. */
        *out = v->valuedouble == 0.0 ? INFINITY : v->valuedouble;
        return SG_OK;
    }
    if (cJSON_IsString(v) && inf_word(v->valuestring) != 0) {
        *out = inf_word(v->valuestring) * INFINITY;
        return SG_OK;
    }
    describe(v, got, sizeof got);
    return perr(c, SG_EPARSE, where, "expected a number or \"inf\", got %s", got);
}

static int get_thickness(jctx *c, const cJSON *v, const char *where, int isurf, double *out)
{
    char got[80];
    if (cJSON_IsNumber(v))
        return get_finite(c, v, where, out);
    if (cJSON_IsString(v) && inf_word(v->valuestring) > 0) {
        if (isurf != 0)
            return perr(c, SG_EPARSE, where,
                        "\"inf\" is allowed only on the object surface (surface 0)");
        *out = INFINITY;
        return SG_OK;
    }
    describe(v, got, sizeof got);
    if (isurf == 0)
        return perr(c, SG_EPARSE, where, "expected a number or \"inf\", got %s", got);
    return perr(c, SG_EPARSE, where, "expected a number, got %s", got);
}

/* A glass or catalog name into out, upper case (catalog names are; ASCII
 * only, so no locale matters). */
static int get_upper_name(jctx *c, const char *s, const char *where, const char *what,
                          char *out, size_t n)
{
    char got[64];
    size_t k, len = strlen(s);
    if (len >= n) {
        show_text(got, 48, s);
        return perr(c, SG_EPARSE, where, "%s \"%s\" is too long (%zu bytes; the limit is %zu)",
                    what, got, len, n - 1);
    }
    for (k = 0; k <= len; k++)
        out[k] = (s[k] >= 'a' && s[k] <= 'z') ? (char)(s[k] - 'a' + 'A') : s[k];
    return SG_OK;
}

static int get_material(jctx *c, const cJSON *v, const char *where, sg_material *m)
{
    char got[80];
    memset(m, 0, sizeof *m);
    if (cJSON_IsNumber(v)) {
        m->kind = SG_MAT_INDEX;
        return get_finite(c, v, where, &m->index);
    }
    if (cJSON_IsString(v) && v->valuestring) {
        const char *s = v->valuestring;
        if (s[0] == '\0' || ascii_casecmp(s, "AIR") == 0) {
            m->kind = SG_MAT_AIR;
            return SG_OK;
        }
        if (ascii_casecmp(s, "MIRROR") == 0) {
            m->kind = SG_MAT_MIRROR;
            return SG_OK;
        }
        m->kind = SG_MAT_GLASS;
        return get_upper_name(c, s, where, "glass name", m->name, sizeof m->name);
    }
    if (cJSON_IsObject(v) && cJSON_GetObjectItemCaseSensitive(v, "glass")) {
        /* A catalog's glass: { "glass": ..., "catalog": ... }. */
        static const char *const keys[] = {"glass", "catalog"};
        const cJSON *k[2];
        char at[160];
        int rc;
        pick_keys(c, v, where, keys, 2, k);
        m->kind = SG_MAT_GLASS;
        snprintf(at, sizeof at, "%s.glass", where);
        if (!cJSON_IsString(k[0]) || !k[0]->valuestring || !k[0]->valuestring[0]) {
            describe(k[0], got, sizeof got);
            return perr(c, SG_EPARSE, at, "expected a glass name, got %s", got);
        }
        if ((rc = get_upper_name(c, k[0]->valuestring, at, "glass name", m->name,
                                 sizeof m->name)) != SG_OK)
            return rc;
        if (!k[1])
            return SG_OK;
        snprintf(at, sizeof at, "%s.catalog", where);
        if (!cJSON_IsString(k[1]) || !k[1]->valuestring) {
            describe(k[1], got, sizeof got);
            return perr(c, SG_EPARSE, at, "expected a catalog name, got %s", got);
        }
        return get_upper_name(c, k[1]->valuestring, at, "catalog name", m->catalog,
                              sizeof m->catalog);
    }
    if (cJSON_IsObject(v)) {
        /* A model glass: { "nd": ..., "vd": ..., "dpgf": ... }. */
        static const char *const keys[] = {"nd", "vd", "dpgf"};
        const cJSON *k[3];
        char at[160];
        int rc;
        pick_keys(c, v, where, keys, 3, k);
        if (!k[0] || !k[1])
            return perr(c, SG_EPARSE, where, "a model glass needs \"nd\" and \"vd\"");
        m->kind = SG_MAT_MODEL;
        snprintf(at, sizeof at, "%s.nd", where);
        if ((rc = get_finite(c, k[0], at, &m->index)) != SG_OK)
            return rc;
        snprintf(at, sizeof at, "%s.vd", where);
        if ((rc = get_finite(c, k[1], at, &m->vd)) != SG_OK)
            return rc;
        snprintf(at, sizeof at, "%s.dpgf", where);
        if (k[2] && (rc = get_finite(c, k[2], at, &m->dpgf)) != SG_OK)
            return rc;
        if (!(m->index >= SG_MODEL_ND_MIN && m->index <= SG_MODEL_ND_MAX) ||
            !(m->vd >= SG_MODEL_VD_MIN && m->vd <= SG_MODEL_VD_MAX) ||
            !(fabs(m->dpgf) <= SG_MODEL_DPGF_MAX))
            return perr(c, SG_ERANGE, where,
                        "model glass nd %.17g, vd %.17g, dpgf %.17g: nd must be %g to %g, vd "
                        "%g to %g and |dpgf| at most %g",
                        m->index, m->vd, m->dpgf, SG_MODEL_ND_MIN, SG_MODEL_ND_MAX,
                        SG_MODEL_VD_MIN, SG_MODEL_VD_MAX, SG_MODEL_DPGF_MAX);
        return SG_OK;
    }
    describe(v, got, sizeof got);
    return perr(c, SG_EPARSE, where,
                "expected a glass name, \"AIR\", \"MIRROR\", a number (a fixed index) or "
                "{\"nd\", \"vd\", \"dpgf\"} (a model glass), got %s",
                got);
}

/* One parameter of the table from its JSON value into obj; where names
 * the object ("surface 3", "fields: list[1]"), isurf the surface (or -1). */
static int read_param(jctx *c, const sg_param *p, const cJSON *v, const char *where,
                      const char *sep, int isurf, void *obj)
{
    char at[96];
    void *q = sg_param_ptr(p, obj);
    int rc, e;
    if (where && where[0])
        snprintf(at, sizeof at, "%s%s%s", where, sep, p->key);
    else
        snprintf(at, sizeof at, "%s", p->key);
    switch (p->kind) {
    case SG_PARAM_ENUM:
        if ((rc = get_enum(c, v, at, p->names, p->nnames, &e)) != SG_OK)
            return rc;
        *(int *)q = e;
        return SG_OK;
    case SG_PARAM_TEXT:
        if (p->names) {
            if ((rc = get_enum(c, v, at, p->names, p->nnames, &e)) != SG_OK)
                return rc;
            sg_strlcpy(q, p->names[e], p->size);
            return SG_OK;
        }
        return get_string(c, v, at, q, p->size);
    case SG_PARAM_MATERIAL:
        return get_material(c, v, at, q);
    case SG_PARAM_BOOL:
        return get_bool(c, v, at, q);
    case SG_PARAM_REAL:
        break;
    }
    if (p->count > 1) {
        const cJSON *it;
        double *arr = q;
        int j = 0, na;
        if (!cJSON_IsArray(v)) {
            char got[80];
            describe(v, got, sizeof got);
            return perr(c, SG_EPARSE, at, "expected an array of numbers, got %s", got);
        }
        na = cJSON_GetArraySize(v);
        if (na > p->count)
            return perr(c, SG_EPARSE, at, "%d terms; at most %d (%s%d to %s%d) are allowed", na,
                        p->count, p->elem_mul == 2 ? "r^" : "", p->elem_add,
                        p->elem_mul == 2 ? "r^" : "", p->elem_mul * (p->count - 1) + p->elem_add);
        cJSON_ArrayForEach(it, v) {
            char el[120];
            snprintf(el, sizeof el, "%s[%d]", at, j);
            if ((rc = get_finite(c, it, el, &arr[j])) != SG_OK)
                return rc;
            j++;
        }
        return SG_OK;
    }
    if (p->flags & SG_PARAM_INF)
        return get_radius(c, v, at, q);
    if (p->flags & SG_PARAM_OBJ_INF)
        return get_thickness(c, v, at, isurf, q);
    if (p->flags & SG_PARAM_POSITIVE)
        return get_positive(c, v, at, q);
    if (p->flags & SG_PARAM_NONNEG)
        return get_nonneg(c, v, at, q);
    return get_finite(c, v, at, q);
}

/* The keys of a scope's table, plus extra (may be NULL), for pick_keys. */
#define MAX_KEYS 64
static int scope_keys(sg_param_scope scope, const char *const *extra, int nextra,
                      const char *names[MAX_KEYS])
{
    int n = sg_param_count(scope), i, j;
    for (i = 0; i < n && i < MAX_KEYS - nextra; i++)
        names[i] = sg_param_at(scope, i)->key;
    for (j = 0; j < nextra; j++)
        names[i++] = extra[j];
    return i;
}

/* Reads every key of a scope's table present in v into obj (the caller
 * set the defaults); a required key must be there. */
static int read_scope(jctx *c, sg_param_scope scope, const cJSON *v, const char *where,
                      const char *sep, int isurf, void *obj, const char *const *extra,
                      int nextra, const cJSON **extra_out)
{
    const char *names[MAX_KEYS];
    const cJSON *k[MAX_KEYS];
    int n = scope_keys(scope, extra, nextra, names), i, rc;
    pick_keys(c, v, where, names, n, k);
    for (i = 0; i < sg_param_count(scope); i++) {
        const sg_param *p = sg_param_at(scope, i);
        /* A frame change's values are read from its nested object. */
        if (k[i] && (p->flags & SG_PARAM_NESTED)) {
            pwarn(c, where, "unknown key \"%s\" ignored", p->key);
            continue;
        }
        if (!k[i]) {
            if (p->flags & SG_PARAM_REQUIRED)
                return perr(c, SG_EPARSE, where, "required key \"%s\" is missing", p->key);
            continue;
        }
        if ((rc = read_param(c, p, k[i], where, sep, isurf, obj)) != SG_OK)
            return rc;
    }
    /* The keys outside the table, in the order asked for. */
    for (i = 0; i < nextra; i++)
        extra_out[i] = k[n - nextra + i];
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Reading sections
 * ------------------------------------------------------------------------ */

enum { W_PRIMARY, W_LIST, W_N };
static const char *const wave_keys[] = {"primary", "list"};

static int read_wavelengths(jctx *c, const cJSON *v, sg_system *sys)
{
    const cJSON *k[W_N], *it;
    char where[64], at[96];
    int rc, n, i, primary = 1;
    if ((rc = expect_object(c, v, "wavelengths")) != SG_OK)
        return rc;
    pick_keys(c, v, "wavelengths", wave_keys, W_N, k);
    if (k[W_LIST]) {
        if (!cJSON_IsArray(k[W_LIST])) {
            describe(k[W_LIST], at, sizeof at);
            return perr(c, SG_EPARSE, "wavelengths: list", "expected an array, got %s", at);
        }
        n = cJSON_GetArraySize(k[W_LIST]);
        if (n == 0)
            return perr(c, SG_EPARSE, "wavelengths: list",
                        "is empty; at least one wavelength is needed");
        if (n > SG_MAX_WAVES)
            return perr(c, SG_ERANGE, "wavelengths: list",
                        "%d wavelengths; the limit is %d", n, SG_MAX_WAVES);
        i = 0;
        cJSON_ArrayForEach(it, k[W_LIST]) {
            sg_wave *w = &sys->wave[i];
            snprintf(where, sizeof where, "wavelengths: list[%d]", i);
            if ((rc = expect_object(c, it, where)) != SG_OK)
                return rc;
            sg_param_defaults(SG_SCOPE_WAVE, w);
            if ((rc = read_scope(c, SG_SCOPE_WAVE, it, where, ".", -1, w, NULL, 0, NULL)) !=
                SG_OK)
                return rc;
            i++;
        }
        sys->nwave = n;
    }
    if (k[W_PRIMARY]) {
        if ((rc = get_int(c, k[W_PRIMARY], "wavelengths: primary", &primary)) != SG_OK)
            return rc;
        if (primary < 1 || primary > sys->nwave)
            return perr(c, SG_EPARSE, "wavelengths: primary",
                        "%d is not one of the wavelengths 1 to %d", primary, sys->nwave);
    }
    sys->primary_wave = primary - 1;
    return SG_OK;
}

enum { F_TYPE, F_NORM, F_LIST, F_N };
static const char *const field_keys[] = {"type", "normalization", "list"};

static int read_fields(jctx *c, const cJSON *v, sg_system *sys)
{
    const cJSON *k[F_N], *it;
    char where[64], at[96];
    int rc, n, i, e;
    if ((rc = expect_object(c, v, "fields")) != SG_OK)
        return rc;
    pick_keys(c, v, "fields", field_keys, F_N, k);
    if (k[F_TYPE]) {
        if ((rc = get_enum(c, k[F_TYPE], "fields: type", field_type_names,
                           sysp("fields.type")->nnames, &e)) != SG_OK)
            return rc;
        sys->field_type = (sg_field_type)e;
    }
    if (k[F_NORM]) {
        if ((rc = get_enum(c, k[F_NORM], "fields: normalization", field_norm_names,
                           sysp("fields.normalization")->nnames, &e)) != SG_OK)
            return rc;
        sys->field_norm = (sg_field_norm)e;
    }
    if (!k[F_LIST])
        return SG_OK;
    if (!cJSON_IsArray(k[F_LIST])) {
        describe(k[F_LIST], at, sizeof at);
        return perr(c, SG_EPARSE, "fields: list", "expected an array, got %s", at);
    }
    n = cJSON_GetArraySize(k[F_LIST]);
    if (n == 0)
        return perr(c, SG_EPARSE, "fields: list", "is empty; at least one field is needed");
    if (n > SG_MAX_FIELDS)
        return perr(c, SG_ERANGE, "fields: list", "%d fields; the limit is %d", n,
                    SG_MAX_FIELDS);
    i = 0;
    cJSON_ArrayForEach(it, k[F_LIST]) {
        sg_field *f = &sys->field[i];
        snprintf(where, sizeof where, "fields: list[%d]", i);
        if ((rc = expect_object(c, it, where)) != SG_OK)
            return rc;
        sg_param_defaults(SG_SCOPE_FIELD, f);
        if ((rc = read_scope(c, SG_SCOPE_FIELD, it, where, ".", -1, f, NULL, 0, NULL)) != SG_OK)
            return rc;
        i++;
    }
    sys->nfield = n;
    return SG_OK;
}

enum { A_TYPE, A_VALUE, A_TELE, A_N };
static const char *const aper_keys[] = {"type", "value", "telecentric"};

static int read_aperture(jctx *c, const cJSON *v, sg_system *sys)
{
    const cJSON *k[A_N];
    int rc, e = 0;
    if ((rc = expect_object(c, v, "aperture")) != SG_OK)
        return rc;
    pick_keys(c, v, "aperture", aper_keys, A_N, k);
    if (k[A_TYPE]) {
        if ((rc = get_enum(c, k[A_TYPE], "aperture: type", aper_type_names,
                           sysp("aperture.type")->nnames, &e)) != SG_OK)
            return rc;
        sys->aper_type = (sg_aper_type)e;
    }
    if (k[A_VALUE] && (rc = get_nonneg(c, k[A_VALUE], "aperture: value", &sys->aper_value)) != SG_OK)
        return rc;
    if (k[A_TELE] && (rc = get_bool(c, k[A_TELE], "aperture: telecentric", &sys->telecentric)) != SG_OK)
        return rc;
    return SG_OK;
}

/* Reads surface i of n; *is_stop reports its "stop" flag. */
/* An array of exactly n finite numbers. */
static int get_vec(jctx *c, const cJSON *v, const char *where, int n, double *out)
{
    const cJSON *it;
    char got[80];
    int j = 0;
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n) {
        describe(v, got, sizeof got);
        return perr(c, SG_EPARSE, where, "expected an array of %d numbers, got %s", n, got);
    }
    cJSON_ArrayForEach(it, v) {
        char el[96];
        int rc;
        snprintf(el, sizeof el, "%s[%d]", where, j);
        if ((rc = get_finite(c, it, el, &out[j])) != SG_OK)
            return rc;
        j++;
    }
    return SG_OK;
}

enum { C_DECENTER, C_TILT, C_ORDER, C_N };
static const char *const change_keys[] = {"decenter", "tilt", "order"};
static const char *const order_names[] = {"decenter_then_tilt", "tilt_then_decenter"};

/* A frame change: {"decenter": [x, y], "tilt": [x, y, z], "order": ...};
 * missing keys are zero and "decenter_then_tilt".  Its values are one
 * nested object, not rows of the parameter table. */
static int get_change(jctx *c, const cJSON *v, const char *where, sg_frame_change *f)
{
    const cJSON *k[C_N];
    char at[96];
    double dec[2] = {0.0, 0.0}, tilt[3] = {0.0, 0.0, 0.0};
    int rc, e = 0;
    if ((rc = expect_object(c, v, where)) != SG_OK)
        return rc;
    pick_keys(c, v, where, change_keys, C_N, k);
    memset(f, 0, sizeof *f);
    if (k[C_DECENTER] &&
        (rc = get_vec(c, k[C_DECENTER], join(at, sizeof at, where, "decenter"), 2, dec)) != SG_OK)
        return rc;
    if (k[C_TILT] &&
        (rc = get_vec(c, k[C_TILT], join(at, sizeof at, where, "tilt"), 3, tilt)) != SG_OK)
        return rc;
    if (k[C_ORDER]) {
        if ((rc = get_enum(c, k[C_ORDER], join(at, sizeof at, where, "order"), order_names,
                           NELEM(order_names), &e)) != SG_OK)
            return rc;
        f->order = e;
    }
    f->dx = dec[0];
    f->dy = dec[1];
    f->tx = tilt[0];
    f->ty = tilt[1];
    f->tz = tilt[2];
    return SG_OK;
}

/* A surface's solves: {"radius": {...}, "thickness": {...}, "conic": {...}},
 * each {"type": KIND, "from": N, "scale": S, "offset": O} for a pickup,
 * {"type": "position", "from": N, "value": L}, or {"type": KIND, "value":
 * V} for another solve (sagitta-design(5), SOLVES).
 * Their values are one nested object, not rows of the parameter table;
 * sg_solve_check checks them with the rest of the design. */
enum { V_TYPE, V_FROM, V_SCALE, V_OFFSET, V_VALUE, V_MIN, V_MAX, V_N };
static const char *const solve_keys[V_N] = {"type", "from", "scale", "offset", "value",
                                            "min", "max"};

/* A variable on another row of the surface table: {"type": "variable",
 * "element": K, "min": A, "max": B}, or an array of them (one an element). */
static int get_pvars(jctx *c, const cJSON *v, const char *at, const sg_param *p, sg_surface *s)
{
    static const char *const keys[] = {"type", "element", "min", "max"};
    const cJSON *it, *k[4];
    char at2[160];
    int rc;
    if (cJSON_IsArray(v)) {
        cJSON_ArrayForEach(it, v) {
            if ((rc = get_pvars(c, it, at, p, s)) != SG_OK)
                return rc;
        }
        return SG_OK;
    }
    if ((rc = expect_object(c, v, at)) != SG_OK)
        return rc;
    pick_keys(c, v, at, keys, 4, k);
    {
        sg_pvar q;
        memset(&q, 0, sizeof q);
        q.param = p;
        q.lo = -INFINITY;
        q.hi = INFINITY;
        if (!k[0] || !cJSON_IsString(k[0]) || !k[0]->valuestring ||
            strcmp(k[0]->valuestring, "variable") != 0)
            return perr(c, SG_EPARSE, at, "only a \"variable\" can sit on the %s (the other "
                        "solves sit on radius, thickness and conic)", p->key);
        if (k[1] && (rc = get_int(c, k[1], join(at2, sizeof at2, at, "element"), &q.elem)) !=
            SG_OK)
            return rc;
        if (q.elem < 0 || q.elem >= p->count)
            return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "element"), "%d is not 0 to %d",
                        q.elem, p->count - 1);
        if ((k[2] && (rc = get_finite(c, k[2], join(at2, sizeof at2, at, "min"), &q.lo)) !=
                         SG_OK) ||
            (k[3] && (rc = get_finite(c, k[3], join(at2, sizeof at2, at, "max"), &q.hi)) !=
                         SG_OK))
            return rc;
        if (q.lo > q.hi)
            return perr(c, SG_EPARSE, at, "the variable's min %.17g is above its max %.17g",
                        q.lo, q.hi);
        if (!sg_param_used(p, q.elem, s->type))
            return perr(c, SG_EPARSE, at, "a %s surface does not use element %d of %s",
                        sg_param_find(SG_SCOPE_SURFACE, "type")->names[s->type], q.elem,
                        p->key);
        /* As sg_variable_set: on a model glass alone, within its limits. */
        if (sg_param_material_part(p)) {
            if (s->mat.kind != SG_MAT_MODEL)
                return perr(c, SG_EPARSE, at, "the material is not a model glass, which "
                            "alone has %s", p->key);
            q.lo = q.lo > p->min ? q.lo : p->min;
            q.hi = q.hi < p->max ? q.hi : p->max;
            if (!(q.lo <= q.hi))
                return perr(c, SG_EPARSE, at, "min and max lie outside the model's %g to %g",
                            p->min, p->max);
        }
        if (s->nvar >= SG_SURF_MAXVARS)
            return perr(c, SG_ERANGE, at, "more than %d variables on one surface",
                        SG_SURF_MAXVARS);
        s->var[s->nvar++] = q;
    }
    return SG_OK;
}

static int get_solves(jctx *c, const cJSON *v, const char *where, sg_surface *s)
{
    const char *kinds[SG_SOLVE_NKINDS];
    const cJSON *t[SG_SOLVE_NTARGETS + 96], *k[V_N];
    const char *targets[SG_SOLVE_NTARGETS + 96];
    const sg_param *extra[96];
    char at[96], at2[128];
    int i, rc, e = 0, nk = SG_SOLVE_NTARGETS;
    for (i = 0; i < SG_SOLVE_NKINDS; i++)
        kinds[i] = sg_solve_kind_name((sg_solve_kind)i);
    for (i = 0; i < SG_SOLVE_NTARGETS; i++)
        targets[i] = sg_solve_target_name((sg_solve_target)i);
    /* Every other real row of the surface table can hold a variable. */
    for (i = 0; i < sg_param_count(SG_SCOPE_SURFACE) && nk < SG_SOLVE_NTARGETS + 96; i++) {
        const sg_param *p = sg_param_at(SG_SCOPE_SURFACE, i);
        int j;
        if (p->kind != SG_PARAM_REAL)
            continue;
        for (j = 0; j < SG_SOLVE_NTARGETS && strcmp(p->key, targets[j]) != 0; j++)
            ;
        if (j < SG_SOLVE_NTARGETS)
            continue;
        extra[nk - SG_SOLVE_NTARGETS] = p;
        targets[nk++] = p->key;
    }
    if ((rc = expect_object(c, v, where)) != SG_OK)
        return rc;
    pick_keys(c, v, where, targets, nk, t);
    s->nvar = 0;
    for (i = SG_SOLVE_NTARGETS; i < nk; i++)
        if (t[i] && (rc = get_pvars(c, t[i], join(at, sizeof at, where, targets[i]),
                                    extra[i - SG_SOLVE_NTARGETS], s)) != SG_OK)
            return rc;
    for (i = 0; i < SG_SOLVE_NTARGETS; i++) {
        sg_solve *o = &s->solve[i];
        if (!t[i])
            continue;
        join(at, sizeof at, where, targets[i]);
        if ((rc = expect_object(c, t[i], at)) != SG_OK)
            return rc;
        pick_keys(c, t[i], at, solve_keys, V_N, k);
        memset(o, 0, sizeof *o);
        if (!k[V_TYPE])
            return perr(c, SG_EPARSE, at, "a solve needs a \"type\"");
        if ((rc = get_enum(c, k[V_TYPE], join(at2, sizeof at2, at, "type"), kinds,
                           SG_SOLVE_NKINDS, &e)) != SG_OK)
            return rc;
        o->kind = (sg_solve_kind)e;
        if (sg_solve_is_pickup(o->kind)) {
            o->scale = 1.0;
            if (!k[V_FROM])
                return perr(c, SG_EPARSE, at, "a pickup needs \"from\", its source surface");
            if ((rc = get_int(c, k[V_FROM], join(at2, sizeof at2, at, "from"), &o->from)) !=
                SG_OK)
                return rc;
            if (k[V_SCALE] && (rc = get_finite(c, k[V_SCALE], join(at2, sizeof at2, at, "scale"),
                                               &o->scale)) != SG_OK)
                return rc;
            if (k[V_OFFSET] && (rc = get_finite(c, k[V_OFFSET],
                                                join(at2, sizeof at2, at, "offset"),
                                                &o->offset)) != SG_OK)
                return rc;
        } else if (o->kind == SG_SOLVE_VARIABLE) {
            /* {"type": "variable", "min": A, "max": B}, each optional. */
            o->lo = -INFINITY;
            o->hi = INFINITY;
            if (k[V_MIN] && (rc = get_finite(c, k[V_MIN], join(at2, sizeof at2, at, "min"),
                                             &o->lo)) != SG_OK)
                return rc;
            if (k[V_MAX] && (rc = get_finite(c, k[V_MAX], join(at2, sizeof at2, at, "max"),
                                             &o->hi)) != SG_OK)
                return rc;
            if (o->lo > o->hi)
                return perr(c, SG_EPARSE, at, "the variable's min %.17g is above its max %.17g",
                            o->lo, o->hi);
        } else if (o->kind != SG_SOLVE_NONE) {
            if (o->kind == SG_SOLVE_POSITION) {
                if (!k[V_FROM])
                    return perr(c, SG_EPARSE, at, "a position solve needs \"from\", its "
                                "reference surface");
                if ((rc = get_int(c, k[V_FROM], join(at2, sizeof at2, at, "from"), &o->from)) !=
                    SG_OK)
                    return rc;
            }
            if (!k[V_VALUE])
                return perr(c, SG_EPARSE, at, "a %s solve needs a \"value\"", kinds[e]);
            if ((rc = get_finite(c, k[V_VALUE], join(at2, sizeof at2, at, "value"),
                                 &o->value)) != SG_OK)
                return rc;
        }
        if (!sg_solve_allowed((sg_solve_target)i, o->kind))
            return perr(c, SG_EPARSE, at, "a %s solve cannot sit on the %s", kinds[e],
                        targets[i]);
    }
    return SG_OK;
}

/* The surface keys outside the parameter table. */
enum { X_STOP, X_BREAK, X_BEFORE, X_AFTER, X_SOLVES, X_N };
static const char *const surf_extra[X_N] = {"stop", "break", "before", "after", "solves"};

static int read_surface(jctx *c, const cJSON *v, int i, int n, sg_surface *s, int *is_stop)
{
    const cJSON *x[X_N] = {NULL}, *stop;
    char where[32], at[64];
    int rc;
    snprintf(where, sizeof where, "surface %d", i);
    if ((rc = expect_object(c, v, where)) != SG_OK)
        return rc;
    sg_surface_init(s);
    if (i == 0)
        s->thickness = INFINITY;
    *is_stop = 0;
    if ((rc = read_scope(c, SG_SCOPE_SURFACE, v, where, ": ", i, s, surf_extra, X_N, x)) !=
        SG_OK)
        return rc;
    if (x[X_BREAK]) {
        join(at, sizeof at, where, "break");
        if (s->type != SG_SURF_COORDBRK)
            return perr(c, SG_EPARSE, at, "only a coordinate_break has a break; use \"before\"");
        if ((rc = get_change(c, x[X_BREAK], at, &s->before)) != SG_OK)
            return rc;
    }
    if (x[X_BEFORE]) {
        if (s->type == SG_SURF_COORDBRK)
            return perr(c, SG_EPARSE, join(at, sizeof at, where, "before"),
                        "a coordinate_break takes its change as \"break\"");
        if ((rc = get_change(c, x[X_BEFORE], join(at, sizeof at, where, "before"),
                             &s->before)) != SG_OK)
            return rc;
    }
    if (x[X_AFTER]) {
        join(at, sizeof at, where, "after");
        if (s->type == SG_SURF_COORDBRK)
            return perr(c, SG_EPARSE, at, "a coordinate_break has no after change");
        if (cJSON_IsString(x[X_AFTER]) && x[X_AFTER]->valuestring &&
            strcmp(x[X_AFTER]->valuestring, "reverse") == 0)
            s->after_mode = SG_AFTER_REVERSE;
        else if (cJSON_IsString(x[X_AFTER]))
            return perr(c, SG_EPARSE, at,
                        "expected \"reverse\" or an object with decenter, tilt and order");
        else if ((rc = get_change(c, x[X_AFTER], at, &s->after)) != SG_OK)
            return rc;
    }
    if (x[X_SOLVES] &&
        (rc = get_solves(c, x[X_SOLVES], join(at, sizeof at, where, "solves"), s)) != SG_OK)
        return rc;
    stop = x[X_STOP];
    if (stop) {
        if ((rc = get_bool(c, stop, join(at, sizeof at, where, "stop"), is_stop)) != SG_OK)
            return rc;
        if (*is_stop && (i == 0 || i == n - 1))
            return perr(c, SG_EPARSE, at, "the %s surface cannot be the aperture stop",
                        i == 0 ? "object" : "image");
    }
    return SG_OK;
}

/* The merit function: {"default": {"criterion": "spot", "reference":
 * "centroid" | "chief", "rings": N, "arms": M}, "operands": [{"type":
 * "EFFL", "wave": 2, "target": T, "weight": W}, ...]} (sagitta-design(5),
 * MERIT FUNCTION); an operand's other keys are its type's (design.h). */
static int get_merit(jctx *c, const cJSON *v, sg_merit *m)
{
    enum { M_DEFAULT, M_OPERANDS, M_N };
    static const char *const mkeys[M_N] = {"default", "operands"};
    enum { D_CRIT, D_REF, D_RINGS, D_ARMS, D_N };
    static const char *const dkeys[D_N] = {"criterion", "reference", "rings", "arms"};
    static const char *const crits[] = {"spot"};
    static const char *const refs[] = {"centroid", "chief"};
    const cJSON *k[M_N], *dk[D_N], *it;
    char at[64], at2[96];
    int rc, e = 0, n;
    memset(m, 0, sizeof *m);
    m->present = 1;
    if ((rc = expect_object(c, v, "merit")) != SG_OK)
        return rc;
    pick_keys(c, v, "merit", mkeys, M_N, k);
    if (k[M_DEFAULT]) {
        if ((rc = expect_object(c, k[M_DEFAULT], "merit: default")) != SG_OK)
            return rc;
        pick_keys(c, k[M_DEFAULT], "merit: default", dkeys, D_N, dk);
        m->has_default = 1;
        m->rings = 3;
        m->arms = 6;
        if (dk[D_CRIT] && (rc = get_enum(c, dk[D_CRIT], "merit: default: criterion", crits, 1,
                                         &e)) != SG_OK)
            return rc;
        if (dk[D_REF]) {
            if ((rc = get_enum(c, dk[D_REF], "merit: default: reference", refs, 2, &e)) != SG_OK)
                return rc;
            m->reference = e;
        }
        if (dk[D_RINGS] && (rc = get_int(c, dk[D_RINGS], "merit: default: rings", &m->rings)) !=
            SG_OK)
            return rc;
        if (dk[D_ARMS] && (rc = get_int(c, dk[D_ARMS], "merit: default: arms", &m->arms)) != SG_OK)
            return rc;
        if (m->rings < 1 || m->rings > 20)
            return perr(c, SG_EPARSE, "merit: default: rings", "%d is not 1 to 20", m->rings);
        if (m->arms < 1 || m->arms > 64)
            return perr(c, SG_EPARSE, "merit: default: arms", "%d is not 1 to 64", m->arms);
    }
    if (!k[M_OPERANDS])
        return SG_OK;
    if (!cJSON_IsArray(k[M_OPERANDS]))
        return perr(c, SG_EPARSE, "merit: operands", "expected an array of operand objects");
    n = cJSON_GetArraySize(k[M_OPERANDS]);
    if (n > SG_MAX_OPERANDS)
        return perr(c, SG_ERANGE, "merit: operands", "%d given; the limit is %d", n,
                    SG_MAX_OPERANDS);
    cJSON_ArrayForEach(it, k[M_OPERANDS]) {
        enum { O_TYPE, O_K1, O_K2, O_HX, O_HY, O_PX, O_PY, O_TARGET, O_WEIGHT, O_N };
        const char *okeys[O_N];
        const cJSON *ok[O_N];
        const sg_op_info *inf;
        sg_operand *o = &m->op[m->nop];
        int t, nk = 0, idx[O_N];
        snprintf(at, sizeof at, "merit: operand %d", m->nop + 1);
        if ((rc = expect_object(c, it, at)) != SG_OK)
            return rc;
        ok[0] = last_item(it, "type");
        if (!ok[0] || !cJSON_IsString(ok[0]) || !ok[0]->valuestring)
            return perr(c, SG_EPARSE, at, "an operand needs a \"type\" (a Zemax operand name)");
        t = sg_op_parse(ok[0]->valuestring);
        if (t < 0) {
            char shown[48];
            show_text(shown, sizeof shown, ok[0]->valuestring);
            return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "type"),
                        "\"%s\" is not an operand sagitta knows", shown);
        }
        inf = sg_op_info_of((sg_op_type)t);
        /* The keys this type reads, so others are warned about. */
        okeys[nk] = "type"; idx[O_TYPE] = nk++;
        idx[O_K1] = idx[O_K2] = idx[O_HX] = idx[O_HY] = idx[O_PX] = idx[O_PY] = -1;
        if (inf->k1) { okeys[nk] = inf->k1; idx[O_K1] = nk++; }
        if (inf->k2) { okeys[nk] = inf->k2; idx[O_K2] = nk++; }
        if (inf->d[0]) { okeys[nk] = inf->d[0]; idx[O_HX] = nk++; }
        if (inf->d[1]) { okeys[nk] = inf->d[1]; idx[O_HY] = nk++; }
        if (inf->d[2]) { okeys[nk] = inf->d[2]; idx[O_PX] = nk++; }
        if (inf->d[3]) { okeys[nk] = inf->d[3]; idx[O_PY] = nk++; }
        okeys[nk] = "target"; idx[O_TARGET] = nk++;
        okeys[nk] = "weight"; idx[O_WEIGHT] = nk++;
        {
            const cJSON *got[O_N];
            pick_keys(c, it, at, okeys, nk, got);
            ok[O_TYPE] = got[idx[O_TYPE]];
            ok[O_K1] = idx[O_K1] >= 0 ? got[idx[O_K1]] : NULL;
            ok[O_K2] = idx[O_K2] >= 0 ? got[idx[O_K2]] : NULL;
            ok[O_HX] = idx[O_HX] >= 0 ? got[idx[O_HX]] : NULL;
            ok[O_HY] = idx[O_HY] >= 0 ? got[idx[O_HY]] : NULL;
            ok[O_PX] = idx[O_PX] >= 0 ? got[idx[O_PX]] : NULL;
            ok[O_PY] = idx[O_PY] >= 0 ? got[idx[O_PY]] : NULL;
            ok[O_TARGET] = got[idx[O_TARGET]];
            ok[O_WEIGHT] = got[idx[O_WEIGHT]];
        }
        memset(o, 0, sizeof *o);
        o->type = (sg_op_type)t;
        o->weight = 1.0;
        if ((ok[O_K1] && (rc = get_int(c, ok[O_K1], join(at2, sizeof at2, at, inf->k1), &o->i1))) ||
            (ok[O_K2] && (rc = get_int(c, ok[O_K2], join(at2, sizeof at2, at, inf->k2), &o->i2))) ||
            (ok[O_HX] && (rc = get_finite(c, ok[O_HX], join(at2, sizeof at2, at, inf->d[0]), &o->hx))) ||
            (ok[O_HY] && (rc = get_finite(c, ok[O_HY], join(at2, sizeof at2, at, inf->d[1]), &o->hy))) ||
            (ok[O_PX] && (rc = get_finite(c, ok[O_PX], join(at2, sizeof at2, at, inf->d[2]), &o->px))) ||
            (ok[O_PY] && (rc = get_finite(c, ok[O_PY], join(at2, sizeof at2, at, inf->d[3]), &o->py))) ||
            (ok[O_TARGET] &&
             (rc = get_finite(c, ok[O_TARGET], join(at2, sizeof at2, at, "target"), &o->target))) ||
            (ok[O_WEIGHT] &&
             (rc = get_nonneg(c, ok[O_WEIGHT], join(at2, sizeof at2, at, "weight"), &o->weight))))
            return rc;
        m->nop++;
    }
    return SG_OK;
}

/* The configurations: {"count": N, "operands": [{"type": "THIC",
 * "surface": 8, "values": [N numbers]}, ...]}; the number key is the
 * type's ("surface", "field", "wavelength" or none) and PRAM adds
 * "parameter"; GLSS's values are materials (sagitta-design(5),
 * CONFIGURATIONS). */
static int get_configs(jctx *c, const cJSON *v, sg_system *sys)
{
    static const char *const keys[] = {"count", "operands", "current"};
    const cJSON *k[3], *it;
    sg_configs *cf;
    char at[64], at2[96];
    int rc, n, i = 0;
    if ((rc = expect_object(c, v, "configurations")) != SG_OK)
        return rc;
    pick_keys(c, v, "configurations", keys, 3, k);
    if (!k[0])
        return perr(c, SG_EPARSE, "configurations: count", "required key is missing");
    if ((rc = get_int(c, k[0], "configurations: count", &n)) != SG_OK)
        return rc;
    if (n < 2 || n > SG_MAX_CONFIGS)
        return perr(c, SG_ERANGE, "configurations: count", "%d is not 2 to %d", n,
                    SG_MAX_CONFIGS);
    if (!k[1] || !cJSON_IsArray(k[1]))
        return perr(c, SG_EPARSE, "configurations: operands", "expected an array of operand "
                    "objects");
    if (!(cf = sg_configs_new(n)))
        return perr(c, SG_ENOMEM, "configurations", "out of memory");
    sg_configs_release(sys->configs);
    sys->configs = cf;
    /* The configuration the design's own values are (the editor's
     * current one); 1 when not given. */
    if (k[2]) {
        if ((rc = get_int(c, k[2], "configurations: current", &cf->current)) != SG_OK)
            return rc;
        if (cf->current < 1 || cf->current > n)
            return perr(c, SG_ERANGE, "configurations: current", "%d is not 1 to %d",
                        cf->current, n);
    }
    cJSON_ArrayForEach(it, k[1]) {
        static const char *const okeys[] = {"type", "surface", "field", "wavelength",
                                            "parameter", "values"};
        const cJSON *ok[6], *e;
        const char *numkey;
        sg_diag dd;
        int num = 0, num2 = 0, j = 0;
        sg_config_op *o;
        snprintf(at, sizeof at, "configurations: operand %d", ++i);
        if ((rc = expect_object(c, it, at)) != SG_OK)
            return rc;
        pick_keys(c, it, at, okeys, 6, ok);
        if (!ok[0] || !cJSON_IsString(ok[0]) || !ok[0]->valuestring)
            return perr(c, SG_EPARSE, at, "an operand needs a \"type\" (a Zemax "
                        "multi-configuration operand name)");
        sg_diag_clear(&dd);
        {
            const char *t = ok[0]->valuestring;
            numkey = !strcmp(t, "XFIE") || !strcmp(t, "YFIE") || !strcmp(t, "FLWT") ? "field"
                     : !strcmp(t, "WAVE") || !strcmp(t, "WLWT")                     ? "wavelength"
                     : !strcmp(t, "APER") || !strcmp(t, "STPS") || !strcmp(t, "TEMP") ||
                             !strcmp(t, "PRES")
                         ? NULL
                         : "surface";
            if (strlen(t) > 4 || sg_configs_add(cf, t, 0, 0, &dd) != SG_OK)
                return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "type"), "%s", dd.msg[0] ?
                            dd.msg : "not an operand sagitta applies");
        }
        o = &cf->op[cf->nop - 1];
        if (numkey) {
            const cJSON *nv = ok[!strcmp(numkey, "surface") ? 1 : !strcmp(numkey, "field") ? 2 : 3];
            if (!nv)
                return perr(c, SG_EPARSE, join(at2, sizeof at2, at, numkey), "required key is "
                            "missing");
            if ((rc = get_int(c, nv, join(at2, sizeof at2, at, numkey), &num)) != SG_OK)
                return rc;
        }
        if (!strcmp(o->type, "PRAM")) {
            if (!ok[4])
                return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "parameter"), "required key "
                            "is missing");
            if ((rc = get_int(c, ok[4], join(at2, sizeof at2, at, "parameter"), &num2)) != SG_OK)
                return rc;
        }
        o->num = num;
        o->num2 = num2;
        if (!ok[5] || !cJSON_IsArray(ok[5]) || cJSON_GetArraySize(ok[5]) != n)
            return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "values"), "expected an array of "
                        "%d values, one per configuration", n);
        cJSON_ArrayForEach(e, ok[5]) {
            char at3[128];
            snprintf(at3, sizeof at3, "%s: values: %d", at, j + 1);
            if (o->mat)
                rc = get_material(c, e, at3, &o->mat[j]);
            else
                rc = get_finite(c, e, at3, &o->value[j]);
            if (rc != SG_OK)
                return rc;
            j++;
        }
    }
    return SG_OK;
}

/* A tolerance row's "min" and "max" under at: both finite, min <= max. */
static int get_limits(jctx *c, const cJSON *kmin, const cJSON *kmax, const char *at,
                      double *min, double *max)
{
    char at2[160];
    int rc;
    if ((rc = get_finite(c, kmin, join(at2, sizeof at2, at, "min"), min)) ||
        (rc = get_finite(c, kmax, join(at2, sizeof at2, at, "max"), max)))
        return rc;
    if (*min > *max)
        return perr(c, SG_ERANGE, join(at2, sizeof at2, at, "min"), "%.17g is above max %.17g",
                    *min, *max);
    return SG_OK;
}

/* The tolerances (sagitta-design(5), TOLERANCES): {"operands": [{"type":
 * "TRAD", "surface": 2, "min": -0.05, "max": 0.05}, {"type": "TEDX",
 * "first": 3, "last": 4, ...}], "compensators": [{"surface": 7,
 * "parameter": "thickness", "min": -1, "max": 1}], "criterion": {"type":
 * "rms_spot", "reference": "centroid", "sampling": {"pattern":
 * "hexapolar", "density": 6}}, "monte_carlo": {"trials": 1000, "seed": 1,
 * "distribution": "normal"}}; sg_tol_check checks them against the
 * surfaces. */
static int get_tolerances(jctx *c, const cJSON *v, sg_tolerances *t)
{
    enum { K_OPS, K_COMPS, K_CRIT, K_MC, K_TWAV, K_N };
    static const char *const keys[K_N] = {"operands", "compensators", "criterion", "monte_carlo",
                                          "test_wavelength"};
    static const char *const crits[] = {"rms_spot", "merit", "rms_wavefront"};
    static const char *const refs[] = {"chief", "centroid"};
    static const char *const dists[] = {"normal", "uniform", "parabolic"};
    const cJSON *k[K_N], *it;
    char at[64], at2[96];
    int rc, n;
    memset(t, 0, sizeof *t);
    t->present = 1;
    t->pattern = SG_PUPIL_HEXAPOLAR;
    t->density = 6;
    t->grid = 64;
    t->seed = 1.0;
    if ((rc = expect_object(c, v, "tolerances")) != SG_OK)
        return rc;
    pick_keys(c, v, "tolerances", keys, K_N, k);
    /* Zemax's TWAV: the wavelength fringes are counted at. */
    if (k[K_TWAV]) {
        if ((rc = get_finite(c, k[K_TWAV], "tolerances: test_wavelength", &t->test_wave)))
            return rc;
        if (!(t->test_wave >= 0.1 && t->test_wave <= 100.0))
            return perr(c, SG_ERANGE, "tolerances: test_wavelength", "%.17g um is not 0.1 to "
                        "100 um", t->test_wave);
    }
    if (k[K_OPS]) {
        if (!cJSON_IsArray(k[K_OPS]))
            return perr(c, SG_EPARSE, "tolerances: operands", "expected an array of operand "
                        "objects");
        n = cJSON_GetArraySize(k[K_OPS]);
        if (n > SG_MAX_TOL_OPERANDS)
            return perr(c, SG_ERANGE, "tolerances: operands", "%d given; the limit is %d", n,
                        SG_MAX_TOL_OPERANDS);
        cJSON_ArrayForEach(it, k[K_OPS]) {
            enum { O_TYPE, O_SURF, O_FIRST, O_LAST, O_ADJ, O_PAR, O_ELEM, O_MIN, O_MAX,
                   O_ZMAX, O_ZMIN, O_N };
            static const char *const okeys[O_N] = {"type", "surface", "first", "last",
                                                   "adjust", "parameter", "element", "min",
                                                   "max", "max_term", "min_term"};
            const cJSON *ok[O_N];
            sg_tol_operand *o = &t->op[t->nop];
            int ty, elem;
            snprintf(at, sizeof at, "tolerances: operand %d", t->nop + 1);
            if ((rc = expect_object(c, it, at)) != SG_OK)
                return rc;
            pick_keys(c, it, at, okeys, O_N, ok);
            if (!ok[O_TYPE] || !cJSON_IsString(ok[O_TYPE]) || !ok[O_TYPE]->valuestring)
                return perr(c, SG_EPARSE, at, "an operand needs a \"type\" (a Zemax tolerance "
                            "operand name)");
            ty = sg_tol_parse(ok[O_TYPE]->valuestring);
            if (ty < 0) {
                char shown[48];
                show_text(shown, sizeof shown, ok[O_TYPE]->valuestring);
                return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "type"),
                            "\"%s\" is not a tolerance operand sagitta knows", shown);
            }
            memset(o, 0, sizeof *o);
            o->type = (sg_tol_type)ty;
            o->adjust = -1;
            elem = ty >= SG_TOL_TEDX && ty <= SG_TOL_TETZ;
            /* An element is first and last; every other row one surface. */
            if (elem ? !ok[O_FIRST] || !ok[O_LAST] : !ok[O_SURF])
                return perr(c, SG_EPARSE, at, elem ? "an element operand needs \"first\" and "
                            "\"last\"" : "the operand needs a \"surface\"");
            if (elem && ok[O_SURF])
                return perr(c, SG_EPARSE, at, "an element operand takes \"first\" and \"last\", "
                            "not \"surface\"");
            if (!elem && (ok[O_FIRST] || ok[O_LAST]))
                return perr(c, SG_EPARSE, at, "only element operands (TEDX ... TETZ) take "
                            "\"first\" and \"last\"");
            if (ty != SG_TOL_TTHI && ok[O_ADJ])
                return perr(c, SG_EPARSE, join(at2, sizeof at2, at, "adjust"),
                            "only TTHI takes it");
            if (ty != SG_TOL_TPAR && (ok[O_PAR] || ok[O_ELEM]))
                return perr(c, SG_EPARSE, at, "only TPAR takes \"parameter\" and \"element\"");
            if (ty == SG_TOL_TPAR && !ok[O_PAR])
                return perr(c, SG_EPARSE, at, "TPAR needs a \"parameter\" (a surface key)");
            if (ty != SG_TOL_TEZI && (ok[O_ZMAX] || ok[O_ZMIN]))
                return perr(c, SG_EPARSE, at, "only TEZI takes \"max_term\" and \"min_term\"");
            if (ty == SG_TOL_TEZI && !ok[O_ZMAX])
                return perr(c, SG_EPARSE, at, "TEZI needs a \"max_term\" (Zemax's Int2, the "
                            "last Standard Zernike term)");
            o->zmin = ty == SG_TOL_TEZI ? 2 : 0;
            if ((ok[O_ZMAX] && (rc = get_int(c, ok[O_ZMAX], join(at2, sizeof at2, at,
                                                                 "max_term"), &o->zmax))) ||
                (ok[O_ZMIN] && (rc = get_int(c, ok[O_ZMIN], join(at2, sizeof at2, at,
                                                                 "min_term"), &o->zmin))))
                return rc;
            if (!ok[O_MIN] || !ok[O_MAX])
                return perr(c, SG_EPARSE, at, "the operand needs \"min\" and \"max\"");
            if ((ok[O_SURF] && (rc = get_int(c, ok[O_SURF], join(at2, sizeof at2, at, "surface"),
                                             &o->surface))) ||
                (ok[O_FIRST] && (rc = get_int(c, ok[O_FIRST], join(at2, sizeof at2, at, "first"),
                                              &o->surface))) ||
                (ok[O_LAST] && (rc = get_int(c, ok[O_LAST], join(at2, sizeof at2, at, "last"),
                                             &o->last))) ||
                (ok[O_ADJ] && (rc = get_int(c, ok[O_ADJ], join(at2, sizeof at2, at, "adjust"),
                                            &o->adjust))) ||
                (ok[O_PAR] && (rc = get_string(c, ok[O_PAR], join(at2, sizeof at2, at,
                                                                  "parameter"),
                                               o->param, sizeof o->param))) ||
                (ok[O_ELEM] && (rc = get_int(c, ok[O_ELEM], join(at2, sizeof at2, at, "element"),
                                             &o->elem))) ||
                (rc = get_limits(c, ok[O_MIN], ok[O_MAX], at, &o->min, &o->max)))
                return rc;
            t->nop++;
        }
    }
    if (k[K_COMPS]) {
        if (!cJSON_IsArray(k[K_COMPS]))
            return perr(c, SG_EPARSE, "tolerances: compensators", "expected an array of "
                        "compensator objects");
        n = cJSON_GetArraySize(k[K_COMPS]);
        if (n > SG_MAX_COMPENSATORS)
            return perr(c, SG_ERANGE, "tolerances: compensators", "%d given; the limit is %d",
                        n, SG_MAX_COMPENSATORS);
        cJSON_ArrayForEach(it, k[K_COMPS]) {
            enum { C_SURF, C_PAR, C_ELEM, C_MIN, C_MAX, CK_N };
            static const char *const ckeys[CK_N] = {"surface", "parameter", "element", "min",
                                                    "max"};
            const cJSON *ck[CK_N];
            sg_tol_comp *o = &t->comp[t->ncomp];
            snprintf(at, sizeof at, "tolerances: compensator %d", t->ncomp + 1);
            if ((rc = expect_object(c, it, at)) != SG_OK)
                return rc;
            pick_keys(c, it, at, ckeys, CK_N, ck);
            memset(o, 0, sizeof *o);
            if (!ck[C_SURF] || !ck[C_PAR] || !ck[C_MIN] || !ck[C_MAX])
                return perr(c, SG_EPARSE, at, "a compensator needs \"surface\", \"parameter\", "
                            "\"min\" and \"max\"");
            if ((rc = get_int(c, ck[C_SURF], join(at2, sizeof at2, at, "surface"), &o->surface)) ||
                (rc = get_string(c, ck[C_PAR], join(at2, sizeof at2, at, "parameter"), o->param,
                                 sizeof o->param)) ||
                (ck[C_ELEM] && (rc = get_int(c, ck[C_ELEM], join(at2, sizeof at2, at, "element"),
                                             &o->elem))) ||
                (rc = get_limits(c, ck[C_MIN], ck[C_MAX], at, &o->min, &o->max)))
                return rc;
            t->ncomp++;
        }
    }
    if (k[K_CRIT]) {
        enum { R_TYPE, R_REF, R_SAMP, R_N };
        static const char *const rkeys[R_N] = {"type", "reference", "sampling"};
        const cJSON *rk[R_N];
        int e = 0;
        if ((rc = expect_object(c, k[K_CRIT], "tolerances: criterion")) != SG_OK)
            return rc;
        pick_keys(c, k[K_CRIT], "tolerances: criterion", rkeys, R_N, rk);
        if (rk[R_TYPE]) {
            if ((rc = get_enum(c, rk[R_TYPE], "tolerances: criterion: type", crits, 3, &e)))
                return rc;
            t->criterion = e;
        }
        if (rk[R_REF]) {
            if ((rc = get_enum(c, rk[R_REF], "tolerances: criterion: reference", refs, 2, &e)))
                return rc;
            t->reference = e;
        }
        if (rk[R_SAMP]) {
            enum { S_PAT, S_DENS, S_GRID, S_N };
            static const char *const skeys[S_N] = {"pattern", "density", "grid"};
            static const char *const pats[] = {"hexapolar", "square", "vogel"};
            const cJSON *sk[S_N];
            const char *w = "tolerances: criterion: sampling";
            sg_diag d2;
            if ((rc = expect_object(c, rk[R_SAMP], w)) != SG_OK)
                return rc;
            pick_keys(c, rk[R_SAMP], w, skeys, S_N, sk);
            if (sk[S_PAT]) {
                if ((rc = get_enum(c, sk[S_PAT], "tolerances: criterion: sampling: pattern",
                                   pats, 3, &e)))
                    return rc;
                t->pattern = e;
            }
            if (sk[S_DENS] && (rc = get_int(c, sk[S_DENS], "tolerances: criterion: sampling: "
                                            "density", &t->density)))
                return rc;
            if (sk[S_GRID]) {
                if ((rc = get_int(c, sk[S_GRID], "tolerances: criterion: sampling: grid",
                                  &t->grid)))
                    return rc;
                if (t->grid < 3 || t->grid > 4096)
                    return perr(c, SG_ERANGE, "tolerances: criterion: sampling: grid",
                                "%d is not 3 to 4096", t->grid);
            }
            sg_diag_clear(&d2);
            if (sg_pupil_check(t->pattern, t->density, &d2) != SG_OK)
                return perr(c, SG_ERANGE, "tolerances: criterion: sampling: density", "%s",
                            d2.msg);
        }
    }
    if (k[K_MC]) {
        enum { M_TRIALS, M_SEED, M_DIST, M_N };
        static const char *const mkeys[M_N] = {"trials", "seed", "distribution"};
        const cJSON *mk[M_N];
        int e = 0;
        const char *w = "tolerances: monte_carlo";
        if ((rc = expect_object(c, k[K_MC], w)) != SG_OK)
            return rc;
        pick_keys(c, k[K_MC], w, mkeys, M_N, mk);
        if (mk[M_TRIALS]) {
            if ((rc = get_int(c, mk[M_TRIALS], "tolerances: monte_carlo: trials", &t->trials)))
                return rc;
            if (t->trials < 0 || t->trials > 100000000)
                return perr(c, SG_ERANGE, "tolerances: monte_carlo: trials",
                            "%d is not 0 to 100000000", t->trials);
        }
        if (mk[M_SEED]) {
            if ((rc = get_finite(c, mk[M_SEED], "tolerances: monte_carlo: seed", &t->seed)))
                return rc;
            if (!(t->seed >= 0.0 && t->seed <= 0x1p53 && floor(t->seed) == t->seed))
                return perr(c, SG_ERANGE, "tolerances: monte_carlo: seed",
                            "%.17g is not an integer from 0 to 2^53", t->seed);
        }
        if (mk[M_DIST]) {
            if ((rc = get_enum(c, mk[M_DIST], "tolerances: monte_carlo: distribution", dists, 3,
                               &e)))
                return rc;
            t->distribution = e;
        }
    }
    return SG_OK;
}

enum {
    T_FORMAT, T_VERSION, T_TITLE, T_UNITS, T_WAVES, T_FIELDS, T_APER, T_AIM, T_SURFS,
    T_TEMP, T_PRES, T_ADJUST, T_MERIT, T_CONFIGS, T_AFOCAL, T_TOL, T_N
};
static const char *const top_keys[] = {
    "format", "version", "title", "units", "wavelengths", "fields", "aperture",
    "ray_aiming", "surfaces", "temperature", "pressure", "adjust_index", "merit",
    "configurations", "afocal", "tolerances"};

/* Fills tmp from the document; the caller's system is not touched. */
static int read_design(jctx *c, const cJSON *root, sg_system *tmp)
{
    const cJSON *k[T_N], *it;
    char got[80];
    int rc, n, i, e = 0, stop = -1;

    if (!cJSON_IsObject(root)) {
        describe(root, got, sizeof got);
        return perr(c, SG_EPARSE, "", "the document must be a JSON object, got %s", got);
    }

    /* The version decides how the rest reads, so it is checked first. */
    it = last_item(root, "format");
    if (it && !(cJSON_IsString(it) && it->valuestring &&
                strcmp(it->valuestring, FORMAT_NAME) == 0)) {
        describe(it, got, sizeof got);
        return perr(c, SG_EPARSE, "format", "expected \"%s\", got %s", FORMAT_NAME, got);
    }
    it = last_item(root, "version");
    if (it) {
        int version = 0;
        if ((rc = get_int(c, it, "version", &version)) != SG_OK)
            return rc;
        if (version > SG_DESIGN_FORMAT_VERSION)
            return perr(c, SG_EUNSUPPORTED, "version",
                        "this is format version %d; this program reads version %d and older",
                        version, SG_DESIGN_FORMAT_VERSION);
        if (version < 1)
            return perr(c, SG_EPARSE, "version", "%d is not a valid format version", version);
    }
    pick_keys(c, root, "", top_keys, T_N, k);

    if (!k[T_SURFS])
        return perr(c, SG_EPARSE, "surfaces", "required key is missing");
    if (!cJSON_IsArray(k[T_SURFS])) {
        describe(k[T_SURFS], got, sizeof got);
        return perr(c, SG_EPARSE, "surfaces", "expected an array of surface objects, got %s", got);
    }
    n = cJSON_GetArraySize(k[T_SURFS]);
    if (n < 3)
        return perr(c, SG_ENOSYS, "surfaces",
                    "%d given; a design needs an object, at least one surface and an image", n);
    if (n > SG_MAX_SURFACES)
        return perr(c, SG_ERANGE, "surfaces", "%d given; the limit is %d", n, SG_MAX_SURFACES);
    rc = sg_system_reset(tmp, n);
    if (rc != SG_OK)
        return perr(c, rc, "surfaces", "cannot hold %d surfaces: %s", n, sg_strerror(rc));

    /* Every default is set here, so the file's meaning does not depend on
     * what sg_system_reset() happens to choose. */
    tmp->title[0] = '\0';
    sg_strlcpy(tmp->units, "mm", sizeof tmp->units);
    tmp->nwave = 1;
    tmp->primary_wave = 0;
    tmp->wave[0].um = 0.5875618;
    tmp->wave[0].weight = 1.0;
    tmp->field_type = SG_FIELD_ANGLE;
    tmp->field_norm = SG_NORM_RADIAL;
    tmp->nfield = 1;
    tmp->field[0].x = 0.0;
    tmp->field[0].y = 0.0;
    tmp->field[0].weight = 1.0;
    tmp->aper_type = SG_APER_EPD;
    tmp->aper_value = 10.0;
    tmp->aim = SG_AIM_OFF;

    if (k[T_TITLE] && (rc = get_string(c, k[T_TITLE], "title", tmp->title, sizeof tmp->title)) != SG_OK)
        return rc;
    if (k[T_UNITS]) {
        if ((rc = get_enum(c, k[T_UNITS], "units", units_names, sysp("units")->nnames, &e)) != SG_OK)
            return rc;
        sg_strlcpy(tmp->units, units_names[e], sizeof tmp->units);
    }
    if (k[T_WAVES] && (rc = read_wavelengths(c, k[T_WAVES], tmp)) != SG_OK)
        return rc;
    if (k[T_FIELDS] && (rc = read_fields(c, k[T_FIELDS], tmp)) != SG_OK)
        return rc;
    if (k[T_APER] && (rc = read_aperture(c, k[T_APER], tmp)) != SG_OK)
        return rc;
    if (k[T_AIM]) {
        if ((rc = get_enum(c, k[T_AIM], "ray_aiming", aim_names, sysp("ray_aiming")->nnames, &e)) != SG_OK)
            return rc;
        tmp->aim = (sg_aim)e;
    }
    /* The environment (Zemax's ENVD). */
    tmp->temperature = 20.0;
    tmp->pressure = 1.0;
    tmp->adjust_index = 0;
    if (k[T_TEMP] && (rc = get_finite(c, k[T_TEMP], "temperature", &tmp->temperature)) != SG_OK)
        return rc;
    if (k[T_PRES] && (rc = get_nonneg(c, k[T_PRES], "pressure", &tmp->pressure)) != SG_OK)
        return rc;
    if (k[T_ADJUST] && (rc = get_bool(c, k[T_ADJUST], "adjust_index", &tmp->adjust_index)) != SG_OK)
        return rc;
    if (!(tmp->temperature >= SG_TEMP_MIN && tmp->temperature <= SG_TEMP_MAX))
        return perr(c, SG_ERANGE, "temperature", "%.17g C is outside %g to %g C",
                    tmp->temperature, SG_TEMP_MIN, SG_TEMP_MAX);
    if (!(tmp->pressure <= SG_PRES_MAX))
        return perr(c, SG_ERANGE, "pressure", "%.17g atm is outside 0 to %g atm",
                    tmp->pressure, SG_PRES_MAX);

    i = 0;
    cJSON_ArrayForEach(it, k[T_SURFS]) {
        int is_stop;
        if ((rc = read_surface(c, it, i, n, &tmp->surf[i], &is_stop)) != SG_OK)
            return rc;
        if (is_stop) {
            if (stop >= 0)
                return perr(c, SG_ETWOSTOPS, "surfaces",
                            "surface %d and surface %d both have \"stop\": true; "
                            "a design has exactly one aperture stop",
                            stop, i);
            stop = i;
        }
        i++;
    }
    if (stop < 0)
        return perr(c, SG_ENOSTOP, "surfaces",
                    "no surface has \"stop\": true; mark the aperture stop");
    tmp->stop = stop;
    if (k[T_MERIT] && (rc = get_merit(c, k[T_MERIT], &tmp->merit)) != SG_OK)
        return rc;
    if (k[T_CONFIGS] && (rc = get_configs(c, k[T_CONFIGS], tmp)) != SG_OK)
        return rc;
    if (k[T_AFOCAL] && (rc = get_bool(c, k[T_AFOCAL], "afocal", &tmp->afocal)) != SG_OK)
        return rc;
    if (k[T_TOL]) {
        if ((rc = get_tolerances(c, k[T_TOL], &tmp->tol)) != SG_OK)
            return rc;
        sg_diag d2;
        sg_diag_clear(&d2);
        if ((rc = sg_tol_check(tmp, &d2)) != SG_OK)
            return sg_diag_set(c->d, rc, "%s: %s", c->name, d2.msg);
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * String checks: RFC 8259 text is UTF-8, and a C string cannot hold NUL
 * ------------------------------------------------------------------------ */

/* The bytes an escaped NUL (\u0000) becomes before cJSON sees the text:
 * cJSON would decode it to a NUL that silently ends the string, whereas
 * 0xC0 0x80 (an overlong NUL, never valid UTF-8) survives the parse and is
 * found, with its key's path, by check_strings. */
#define NUL_MARK "\xC0\x80\xC0\x80\xC0\x80"

/* Replaces every escaped NUL inside a string of buf with NUL_MARK, in place
 * (both are six bytes). */
static void mark_escaped_nuls(char *buf, size_t len)
{
    size_t k;
    int in_str = 0;
    for (k = 0; k < len; k++) {
        if (!in_str) {
            if (buf[k] == '"')
                in_str = 1;
        } else if (buf[k] == '"') {
            in_str = 0;
        } else if (buf[k] == '\\' && k + 1 < len) {
            if (k + 6 <= len && memcmp(buf + k + 1, "u0000", 5) == 0) {
                memcpy(buf + k, NUL_MARK, 6);
                k += 5;
            } else {
                k++; /* the escaped character, a quote or backslash among them */
            }
        }
    }
}

/* The length of the valid UTF-8 prefix of s (RFC 3629: no overlong forms,
 * no surrogates, nothing above U+10FFFF). */
static size_t utf8_valid_prefix(const unsigned char *s)
{
    const unsigned char *p = s;
    while (*p) {
        unsigned c = p[0];
        int n, i;
        unsigned cp;
        if (c < 0x80) {
            p++;
            continue;
        }
        if (c >= 0xC2 && c <= 0xDF)
            n = 1, cp = c & 0x1F;
        else if (c >= 0xE0 && c <= 0xEF)
            n = 2, cp = c & 0x0F;
        else if (c >= 0xF0 && c <= 0xF4)
            n = 3, cp = c & 0x07;
        else
            break;
        for (i = 1; i <= n; i++) {
            if ((p[i] & 0xC0) != 0x80)
                break;
            cp = cp << 6 | (p[i] & 0x3Fu);
        }
        if (i <= n || (n == 2 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) ||
            (n == 3 && (cp < 0x10000 || cp > 0x10FFFF)))
            break;
        p += n + 1;
    }
    return (size_t)(p - s);
}

/* Refuses a key or string value that holds an escaped NUL or is not UTF-8,
 * naming its path (surfaces[3].material).  raw_c0: the text itself held a
 * 0xC0 byte, so a NUL_MARK cannot be told from invalid bytes. */
static int check_strings(jctx *c, const cJSON *v, char *path, size_t cap, int raw_c0)
{
    size_t plen = strlen(path);
    const cJSON *it;
    int idx = 0;
    if (cJSON_IsString(v) || v->string) {
        const char *what[2];
        int w;
        what[0] = v->string;
        what[1] = cJSON_IsString(v) ? v->valuestring : NULL;
        for (w = 0; w < 2; w++) {
            const unsigned char *s = (const unsigned char *)what[w];
            size_t ok;
            if (!s)
                continue;
            ok = utf8_valid_prefix(s);
            if (!s[ok])
                continue;
            if (!raw_c0 && s[ok] == 0xC0 && s[ok + 1] == 0x80)
                return sg_diag_set(c->d, SG_EPARSE,
                                   "%s: %s: the %s holds \\u0000 (a NUL character), "
                                   "which no name or comment may contain",
                                   c->name, path[0] ? path : "(top level)",
                                   w ? "text" : "key");
            return sg_diag_set(c->d, SG_EPARSE,
                               "%s: %s: the %s is not valid UTF-8 (byte 0x%02X after %zu valid "
                               "bytes); JSON text must be UTF-8 (RFC 8259)",
                               c->name, path[0] ? path : "(top level)", w ? "text" : "key",
                               s[ok], ok);
        }
    }
    cJSON_ArrayForEach(it, v) {
        int rc;
        if (cJSON_IsArray(v))
            snprintf(path + plen, cap - plen, "[%d]", idx);
        else if (it->string && utf8_valid_prefix((const unsigned char *)it->string) ==
                                   strlen(it->string))
            snprintf(path + plen, cap - plen, "%s%s", plen ? "." : "", it->string);
        else
            snprintf(path + plen, cap - plen, "%s(key %d)", plen ? "." : "", idx + 1);
        rc = check_strings(c, it, path, cap, raw_c0);
        if (rc != SG_OK)
            return rc;
        path[plen] = '\0';
        idx++;
    }
    return SG_OK;
}

/* Line and column (both from 1, columns in bytes) of offset off. */
static void line_col(const char *text, size_t off, long *line, long *col)
{
    size_t k, start = 0;
    long ln = 1;
    for (k = 0; k < off; k++) {
        if (text[k] == '\n') {
            ln++;
            start = k + 1;
        }
    }
    *line = ln;
    *col = (long)(off - start) + 1;
}

int sg_design_parse(sg_system *sys, const char *text, size_t len, const char *name,
                    sg_diag *d)
{
    jctx c;
    char *buf;
    const char *end = NULL, *nul;
    cJSON *root;
    sg_system *tmp;
    int rc, raw_c0;

    c.name = name ? name : "(memory)";
    c.d = d;
    if (!sys || (!text && len > 0))
        return sg_diag_set(d, SG_EINVAL, "%s: no system or no text to parse", c.name);
    if (len > DESIGN_MAX_BYTES)
        return sg_diag_set(d, SG_ERANGE, "%s: the design is %zu bytes; the limit is %zu (64 MiB)",
                           c.name, len, DESIGN_MAX_BYTES);
    /* cJSON stops at a NUL byte and would silently ignore what follows. */
    nul = len ? memchr(text, '\0', len) : NULL;
    if (nul) {
        long line, col;
        line_col(text, (size_t)(nul - text), &line, &col);
        return sg_diag_set(d, SG_EPARSE, "%s:%ld:%ld: JSON syntax error: NUL byte in the text",
                           c.name, line, col);
    }
    /* cJSON wants the terminator inside the length to reject trailing text. */
    buf = malloc(len + 1);
    if (!buf)
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", c.name);
    if (len)
        memcpy(buf, text, len);
    buf[len] = '\0';
    raw_c0 = memchr(buf, 0xC0, len) != NULL;
    mark_escaped_nuls(buf, len);
    /* cJSON skips a UTF-8 byte order mark (RFC 8259, 8.1). */
    root = cJSON_ParseWithLengthOpts(buf, len + 1, &end, 1);
    if (!root) {
        long line, col;
        size_t off = end ? (size_t)(end - buf) : 0;
        char near[40];
        if (off > len)
            off = len;
        line_col(buf, off, &line, &col);
        if (off >= len) {
            rc = sg_diag_set(d, SG_EPARSE, "%s:%ld:%ld: JSON syntax error near end of input",
                             c.name, line, col);
        } else {
            size_t k;
            for (k = 0; k < 24 && off + k < len && buf[off + k] != '\n' && buf[off + k] != '\r'; k++)
                ;
            buf[off + k] = '\0';
            show_text(near, sizeof near, buf + off);
            rc = sg_diag_set(d, SG_EPARSE, "%s:%ld:%ld: JSON syntax error near '%s'", c.name, line,
                             col, near);
        }
        free(buf);
        return rc;
    }
    free(buf);
    {
        char path[512] = "";
        rc = check_strings(&c, root, path, sizeof path, raw_c0);
        if (rc != SG_OK) {
            cJSON_Delete(root);
            return rc;
        }
    }

    tmp = sg_system_new();
    if (!tmp) {
        cJSON_Delete(root);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", c.name);
    }
    rc = read_design(&c, root, tmp);
    cJSON_Delete(root);
    if (rc == SG_OK) {
        rc = sg_system_assign(sys, tmp);
        if (rc != SG_OK)
            sg_diag_set(d, rc, "%s: cannot store the design: %s", c.name, sg_strerror(rc));
    }
    sg_system_free(tmp);
    return rc;
}

static int utf16_to_utf8(const unsigned char *b, size_t n, const char *name, char **out,
                         size_t *outlen, sg_diag *d)
{
    int be = b[0] == 0xFE;
    size_t k, o = 0;
    char *u;
    if (n % 2)
        return sg_diag_set(d, SG_EPARSE,
                           "%s: UTF-16 text (byte order mark %02X %02X) of an odd number of "
                           "bytes (%zu): the file is cut",
                           name, b[0], b[1], n);
    u = malloc(n / 2 * 3 + 1);
    if (!u)
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    for (k = 2; k < n; k += 2) {
        unsigned cp = be ? (unsigned)b[k] << 8 | b[k + 1] : (unsigned)b[k + 1] << 8 | b[k];
        if (cp >= 0xD800 && cp <= 0xDBFF && k + 3 < n) {
            unsigned lo = be ? (unsigned)b[k + 2] << 8 | b[k + 3]
                             : (unsigned)b[k + 3] << 8 | b[k + 2];
            if (lo >= 0xDC00 && lo <= 0xDFFF) {
                cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                k += 2;
            }
        }
        if (cp >= 0xD800 && cp <= 0xDFFF) {
            free(u);
            return sg_diag_set(d, SG_EPARSE,
                               "%s: byte %zu: an unpaired UTF-16 surrogate (0x%04X); the text "
                               "is not valid UTF-16",
                               name, k, cp);
        }
        if (cp < 0x80) {
            u[o++] = (char)cp;
        } else if (cp < 0x800) {
            u[o++] = (char)(0xC0 | cp >> 6);
            u[o++] = (char)(0x80 | (cp & 0x3F));
        } else if (cp < 0x10000) {
            u[o++] = (char)(0xE0 | cp >> 12);
            u[o++] = (char)(0x80 | (cp >> 6 & 0x3F));
            u[o++] = (char)(0x80 | (cp & 0x3F));
        } else {
            u[o++] = (char)(0xF0 | cp >> 18);
            u[o++] = (char)(0x80 | (cp >> 12 & 0x3F));
            u[o++] = (char)(0x80 | (cp >> 6 & 0x3F));
            u[o++] = (char)(0x80 | (cp & 0x3F));
        }
    }
    u[o] = '\0';
    *out = u;
    *outlen = o;
    return SG_OK;
}

/* Whether a UTF-16 text (after its mark) opens with '{', spaces aside: a
 * JSON design, which a .zmx file in UTF-16 never is. */
static int utf16_opens_object(const unsigned char *b, size_t n)
{
    int be = b[0] == 0xFE;
    size_t k;
    for (k = 2; k + 1 < n; k += 2) {
        unsigned cp = be ? (unsigned)b[k] << 8 | b[k + 1] : (unsigned)b[k + 1] << 8 | b[k];
        if (cp == ' ' || cp == '\t' || cp == '\r' || cp == '\n')
            continue;
        return cp == '{';
    }
    return 0;
}

int sg_design_load(sg_system *sys, const char *path, sg_diag *d)
{
    char *buf;
    size_t len;
    int rc;

    if (!sys || !path)
        return sg_diag_set(d, SG_EINVAL, "load: no system or no path");
    rc = sg_read_file(path, DESIGN_MAX_BYTES, &buf, &len, d);
    if (rc != SG_OK)
        return rc;
    /* A JSON design in UTF-16 (RFC 8259 allows only UTF-8, but editors on
     * Windows write it) is read as the same text in UTF-8, whatever its
     * name; a lens file in UTF-16 is the .zmx reader's. */
    if (len >= 2 &&
        ((buf[0] == '\xFF' && buf[1] == '\xFE') || (buf[0] == '\xFE' && buf[1] == '\xFF')) &&
        utf16_opens_object((const unsigned char *)buf, len)) {
        char *u8 = NULL;
        size_t n8 = 0;
        rc = utf16_to_utf8((const unsigned char *)buf, len, path, &u8, &n8, d);
        free(buf);
        if (rc != SG_OK)
            return rc;
        rc = sg_design_parse(sys, u8, n8, path, d);
        free(u8);
        return rc;
    }
    /* A Zemax archive or lens file, by its name or its first bytes. */
    if (sg_zar_detect(path, buf, len))
        rc = sg_zar_parse(sys, buf, len, path, NULL, d);
    else if (sg_zmx_detect(path, buf, len))
        rc = sg_zmx_parse(sys, buf, len, path, NULL, d);
    else
        rc = sg_design_parse(sys, buf ? buf : "", len, path, d);
    free(buf);
    return rc;
}
