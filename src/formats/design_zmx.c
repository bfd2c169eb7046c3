/*
 * design_zmx.c - Zemax .zmx lens files: read and write (sagitta-design(5),
 * section ZEMAX FILES).
 *
 * The reader takes UTF-16LE with a byte-order mark, UTF-8 (with or without
 * a mark) and ISO-8859-1.  Every keyword either maps onto the model, is
 * known not to change a sequential trace (display, coatings, tolerancing,
 * the merit function), or refuses the file with a message that names the
 * file, the line, the surface and what sagitta lacks.  Nothing that changes
 * the optics is dropped or approximated.
 *
 * Numbers are read with strtod from the text as written.  The curvature is
 * the one exception: the model holds the radius, so the radius is the
 * correctly rounded reciprocal of the exact decimal written (GMP rational
 * arithmetic), and the writer prints 1/R to 25 digits, whose reciprocal
 * rounds back to R.  A design therefore survives export and import bit for
 * bit.
 */
#include <ctype.h>
#include <errno.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <gmp.h>
#include <mpfr.h>

#include "formats_int.h"
#include "shape.h"

#define ZMX_MAX_BYTES ((size_t)64 * 1024 * 1024)
#define ZMX_MAX_TOK 64       /* tokens read from one line */
#define ZMX_MAX_NUMBER 80    /* characters of one number */
#define ZMX_NPARM 8          /* even-asphere PARM 1..8 */
#define ZMX_MAX_PARM 64      /* PARM numbers accepted at all */
#define ZMX_MAX_XDAT 250     /* XDAT numbers accepted at all */
#define ZMX_NWSLOT 24        /* WAVM slots */
#define ZMX_MAX_GCAT 16

/* Keywords that do not change a sequential trace of the model, and why;
 * sagitta-design(5) lists them with the same reasons. */
static const char *const ignored_header[] = {
    "VERS", /* the writer's version */
    "NOTE", "AUTH", "LANG", "LUID", "DBDT", "BLNK", /* notes, vendor data */
    "PFIL", "POLS", "NSCD", "COFN", /* polarization, non-sequential, coatings */
    "GFAC", "GLRS", "GSTD", "RGLA", /* glass substitution for optimisation */
    "SDMA", "OMMA", "ROPD", "PICB", "HYPR", "EERA", "IWDP", "STUD", "RCMF",
    /* semi-diameter margins, OPD reference, display settings */
    "MOFF", "TCMM", /* multi-configuration rows of MNUM 1; a tolerance row's comment */
};
/* Surface keywords whose fields Zemax does not publish, met in public
 * files: kept as they are, with a note, when every number is 0 (nothing
 * set); refused otherwise, since sagitta cannot tell what a value does. */
static const char *const zero_surface[] = {"TOLE", "SPID", "USAP", "FSVY"};
#define ZMX_NZERO_KW 4
static const char *const ignored_surface[] = {
    "FIMP", "HIDE", "MIRR", "SLAB", "SCOL", "POPS", "MEMA", "OEMA", "COAT", "SSID",
    "VPAR", "VCRV", "VDSZ", "VTHI", "VCON", "VGLS", "TCEX", "CONF",
    /* drawing, labels, physical optics, mechanical apertures, coatings,
     * variable flags for optimisation, thermal expansion (Zemax applies it
     * only in multi-configuration thermal analysis, which sagitta lacks) */
};

typedef struct ztok {
    const char *p;
    size_t n;
} ztok;

typedef struct zline {
    ztok t[ZMX_MAX_TOK];
    int n;
    const char *rest1; /* the text after the keyword, for NAME and COMM */
    int indented;
} zline;

typedef struct zsurf {
    long line;           /* SURF line */
    char type[24];       /* "" when no TYPE line: STANDARD */
    long type_line;
    double parm[ZMX_MAX_PARM + 1];
    long parm_line[ZMX_MAX_PARM + 1];
    int have_diam;
    double diam;
    long pend_line;      /* first refusal inside the block, reported after TYPE's */
    int pend_code;
    char pend_msg[SG_DIAG_MSG];
    long xdat_line;      /* first nonzero XDAT */
    double xdat;
    /* Every XDAT value by number, for the types that read extra data. */
    double xd[ZMX_MAX_XDAT + 1];
    long xd_line[ZMX_MAX_XDAT + 1];
    int ap;              /* 0 none, 1 CLAP, 2 FLAP */
    double ap_min, ap_max;
    long ap_line;
    int apk;             /* another aperture or obscuration: an sg_aperture_type */
    double apk_a, apk_b; /* its radii or half widths */
    long apk_line;
    double obdc_x, obdc_y; /* the aperture's decenter (OBDC) */
    long obdc_line;
    sg_frame_change scbd;  /* the tilt and decenter before the surface (SCBD 1) */
    long scbd_line;        /* 0: none, or all zero */
    sg_frame_change scad;  /* after the surface (SCBD 2) */
    int scad_mode;         /* its Zemax mode: 0 explicit, 1 pickup, 2 reverse */
    long scad_line;
} zsurf;

#define ZMX_MAX_MROWS 4096 /* merit function rows mapped to the design's */

typedef struct zctx {
    const char *name;
    sg_diag *d;
    const sg_catalog *cat;
    long line;
    sg_system *sys;
    int cur;             /* current surface, -1 in the header */
    int after;           /* past the surfaces: merit function and tolerances */
    /* The merit function's rows: Zemax's row number (from 1) to the
     * design's operand (from 1; 0 left out), and whether it is dropped. */
    int nmrow, mrow[ZMX_MAX_MROWS + 1], merit_drop;
    long merit_drop_line;
    char merit_drop_why[160];
    /* The tolerance rows read (TOL lines) and their lines. */
    long tol_line[SG_MAX_TOL_OPERANDS], comp_line[SG_MAX_COMPENSATORS];
    zsurf zs;
    int nstop, stop;
    long stop_line;
    /* header values, resolved at the end */
    int have_ftyp, ftyp_nfield, ftyp_nwave;
    long ftyp_line;
    double xfln[SG_MAX_FIELDS], yfln[SG_MAX_FIELDS], fwgn[SG_MAX_FIELDS];
    int nxfln, nyfln, nfwgn;
    /* The old XFLD, YFLD and FWGT lists (older files write both forms). */
    double oldf[3][SG_MAX_FIELDS];
    int noldf[3];
    long oldf_line[3];
    /* Zemax's vignetting factors, VDXN VDYN VCXN VCYN VANN, per field. */
    double vig[5][SG_MAX_FIELDS];
    int nvig[5];
    long xfln_line, yfln_line;
    double wum[ZMX_NWSLOT], wwt[ZMX_NWSLOT];
    int whave[ZMX_NWSLOT];
    int nwavl, nwwgt;
    double wavl[ZMX_NWSLOT], wwgt[ZMX_NWSLOT];
    /* WAVN and WWGN: the twelve slots of an older layout, checked against
     * the wavelengths read. */
    int nwavn, nwwgn;
    double wavn[ZMX_NWSLOT], wwgn[ZMX_NWSLOT];
    long wavn_line, wwgn_line;
    int pwav;
    long pwav_line;
    int have_aper;
    long aper_line;
    char gcat[ZMX_MAX_GCAT][SG_GLASS_NAME];
    int ngcat;
    int nfrozen;
    int nlive; /* solves and pickups kept (sagitta-design(5), SOLVES) */
    /* Each line's place, for the lossless save: -1 the header, -2 after
     * the surfaces, else the surface whose block holds it. */
    int *lsect;
    int nlsect;
    /* Each merit function row's operand (from 1), -1 for a row that is
     * none (DMFS, an operand left out), 0 for other lines. */
    int *lmop;
    const sg_zmx_subst *sub; /* glasses to substitute, or NULL */
    int nzero_kw[ZMX_NZERO_KW]; /* zero_surface lines kept */
    /* The configurations (MNUM n, n > 1) and, per operand, its first
     * line and which configurations gave it a value. */
    long push_line; /* a PUSH line with a shift */
    int mnum;
    long mnum_line;
    long mline[SG_MAX_CONFIG_OPS];
    unsigned char *mfill[SG_MAX_CONFIG_OPS];
} zctx;

/* ------------------------------------------------------------------------
 * Text: decoding to UTF-8
 * ------------------------------------------------------------------------ */

static void put_utf8(char *out, size_t *j, unsigned cp)
{
    if (cp < 0x80) {
        out[(*j)++] = (char)cp;
    } else if (cp < 0x800) {
        out[(*j)++] = (char)(0xC0 | (cp >> 6));
        out[(*j)++] = (char)(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
        out[(*j)++] = (char)(0xE0 | (cp >> 12));
        out[(*j)++] = (char)(0x80 | ((cp >> 6) & 0x3F));
        out[(*j)++] = (char)(0x80 | (cp & 0x3F));
    } else {
        out[(*j)++] = (char)(0xF0 | (cp >> 18));
        out[(*j)++] = (char)(0x80 | ((cp >> 12) & 0x3F));
        out[(*j)++] = (char)(0x80 | ((cp >> 6) & 0x3F));
        out[(*j)++] = (char)(0x80 | (cp & 0x3F));
    }
}

/* Length of the valid UTF-8 sequence at s, or 0. */
static size_t utf8_len(const unsigned char *s, size_t n)
{
    unsigned cp;
    size_t k, len;
    if (s[0] < 0x80)
        return 1;
    if (s[0] >= 0xC2 && s[0] <= 0xDF)
        len = 2, cp = s[0] & 0x1F;
    else if (s[0] >= 0xE0 && s[0] <= 0xEF)
        len = 3, cp = s[0] & 0x0F;
    else if (s[0] >= 0xF0 && s[0] <= 0xF4)
        len = 4, cp = s[0] & 0x07;
    else
        return 0;
    if (len > n)
        return 0;
    for (k = 1; k < len; k++) {
        if ((s[k] & 0xC0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[k] & 0x3F);
    }
    if ((len == 3 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) ||
        (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)))
        return 0;
    return len;
}

/* Line number (from 1) of byte offset off in a byte-oriented text. */
static long line_of(const unsigned char *b, size_t off, size_t unit)
{
    long ln = 1;
    size_t i;
    for (i = 0; i + unit <= off; i += unit)
        if (b[i] == '\n' && (unit == 1 || b[i + 1] == 0))
            ln++;
    return ln;
}

/* Decodes the file into NUL-terminated UTF-8 in *out.  *enc names the
 * encoding found, for messages. */
static int decode(const char *name, const unsigned char *b, size_t n, char **out,
                  const char **enc, sg_diag *d)
{
    char *o;
    size_t i, j = 0;
    *out = NULL;
    if (n >= 2 && b[0] == 0xFE && b[1] == 0xFF)
        return sg_diag_set(d, SG_EUNSUPPORTED,
                           "%s:1: UTF-16 big-endian text; Zemax writes UTF-16LE, UTF-8 or "
                           "ISO-8859-1, and sagitta reads those", name);
    if (n >= 2 && b[0] == 0xFF && b[1] == 0xFE) {
        *enc = "UTF-16LE";
        if (n % 2)
            return sg_diag_set(d, SG_EPARSE, "%s:%ld: UTF-16LE text of an odd number of bytes "
                               "(the file is cut)", name, line_of(b + 2, n - 3, 2));
        o = malloc((n / 2) * 3 + 1);
        if (!o)
            return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
        for (i = 2; i + 1 < n; i += 2) {
            unsigned u = b[i] | (unsigned)b[i + 1] << 8;
            if (u == 0) {
                free(o);
                return sg_diag_set(d, SG_EPARSE, "%s:%ld: NUL character in the text", name,
                                   line_of(b + 2, i - 2, 2));
            }
            if (u >= 0xD800 && u <= 0xDBFF && i + 3 < n) {
                unsigned v = b[i + 2] | (unsigned)b[i + 3] << 8;
                if (v >= 0xDC00 && v <= 0xDFFF) {
                    put_utf8(o, &j, 0x10000 + ((u - 0xD800) << 10) + (v - 0xDC00));
                    i += 2;
                    continue;
                }
            }
            if (u >= 0xD800 && u <= 0xDFFF) {
                free(o);
                return sg_diag_set(d, SG_EPARSE, "%s:%ld: unpaired UTF-16 surrogate 0x%04X", name,
                                   line_of(b + 2, i - 2, 2), u);
            }
            put_utf8(o, &j, u);
        }
        o[j] = '\0';
        *out = o;
        return SG_OK;
    }
    if (n >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF) {
        b += 3;
        n -= 3;
        *enc = "UTF-8";
    } else {
        *enc = NULL;
    }
    for (i = 0; i < n; i++)
        if (b[i] == 0)
            return sg_diag_set(d, SG_EPARSE, "%s:%ld: NUL byte in the text (UTF-16 without its "
                               "byte-order mark?)", name, line_of(b, i, 1));
    /* Valid UTF-8 is read as UTF-8; anything else is ISO-8859-1, in which
     * every byte is a character. */
    for (i = 0; i < n;) {
        size_t k = utf8_len(b + i, n - i);
        if (!k)
            break;
        i += k;
    }
    if (i < n && *enc) {
        return sg_diag_set(d, SG_EPARSE, "%s:%ld: invalid UTF-8 after a UTF-8 byte-order mark",
                           name, line_of(b, i, 1));
    }
    o = malloc(n * 2 + 1);
    if (!o)
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    if (i == n) {
        memcpy(o, b, n);
        j = n;
        if (!*enc)
            *enc = "UTF-8";
    } else {
        *enc = "ISO-8859-1";
        for (i = 0; i < n; i++)
            put_utf8(o, &j, b[i]);
    }
    o[j] = '\0';
    *out = o;
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Messages and tokens
 * ------------------------------------------------------------------------ */

/* A token for a message: printable ASCII, other bytes as '?', cut at 40. */
static void tok_show(const ztok *t, char *buf, size_t n)
{
    size_t i, j = 0, len = t->n > 40 ? 40 : t->n;
    for (i = 0; i < len && j + 1 < n; i++) {
        unsigned char c = (unsigned char)t->p[i];
        buf[j++] = (c >= 0x20 && c < 0x7F) ? (char)c : '?';
    }
    buf[j] = '\0';
    if (t->n > 40 && j + 4 < n)
        strcat(buf, "...");
}

static int tok_is(const ztok *t, const char *s)
{
    return t->n == strlen(s) && memcmp(t->p, s, t->n) == 0;
}

static const char *where(zctx *c, char *buf, size_t n)
{
    if (c->cur >= 0)
        snprintf(buf, n, "%s:%ld: surface %d", c->name, c->line, c->cur);
    else if (c->line > 0)
        snprintf(buf, n, "%s:%ld", c->name, c->line);
    else
        snprintf(buf, n, "%s", c->name);
    return buf;
}

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int zerr(zctx *c, int code, const char *fmt, ...)
{
    char msg[SG_DIAG_MSG], w[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sg_diag_set(c->d, code, "%s: %s", where(c, w, sizeof w), msg);
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void zwarn(zctx *c, const char *fmt, ...)
{
    char msg[SG_DIAG_MSG], w[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    sg_diag_warn(c->d, "%s: %s", where(c, w, sizeof w), msg);
}

/* A refusal inside a SURF block waits for the block's end, so that an
 * unsupported TYPE is the one reported whatever the order of the lines. */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static int pend(zctx *c, int code, const char *fmt, ...)
{
    va_list ap;
    if (c->zs.pend_line)
        return SG_OK;
    va_start(ap, fmt);
    vsnprintf(c->zs.pend_msg, sizeof c->zs.pend_msg, fmt, ap);
    va_end(ap);
    c->zs.pend_line = c->line;
    c->zs.pend_code = code;
    return SG_OK;
}

/* Strict decimal syntax: [+-]digits[.digits][(e|E)[+-]digits]. */
static int decimal_ok(const char *s)
{
    int digits = 0;
    if (*s == '+' || *s == '-')
        s++;
    while (isdigit((unsigned char)*s))
        s++, digits++;
    if (*s == '.') {
        s++;
        while (isdigit((unsigned char)*s))
            s++, digits++;
    }
    if (!digits)
        return 0;
    if (*s == 'e' || *s == 'E') {
        int ed = 0;
        s++;
        if (*s == '+' || *s == '-')
            s++;
        while (isdigit((unsigned char)*s))
            s++, ed++;
        if (!ed)
            return 0;
    }
    return *s == '\0';
}

/* Copies token k into buf as a C string, or fails naming what. */
static int tok_text(zctx *c, const zline *l, int k, const char *what, char *buf, size_t n)
{
    char q[48];
    if (k >= l->n)
        return zerr(c, SG_EPARSE, "missing %s", what);
    if (l->t[k].n >= n) {
        tok_show(&l->t[k], q, sizeof q);
        return zerr(c, SG_EPARSE, "%s: too long: '%s'", what, q);
    }
    memcpy(buf, l->t[k].p, l->t[k].n);
    buf[l->t[k].n] = '\0';
    return SG_OK;
}

/* Token k as a finite number, read by strtod exactly as written. */
static int tok_num(zctx *c, const zline *l, int k, const char *what, double *out)
{
    char buf[ZMX_MAX_NUMBER + 1], q[48];
    double v;
    int rc;
    if (k >= l->n)
        return zerr(c, SG_EPARSE, "%.4s: missing %s", l->t[0].p, what);
    if ((rc = tok_text(c, l, k, what, buf, sizeof buf)) != SG_OK)
        return rc;
    tok_show(&l->t[k], q, sizeof q);
    if (!decimal_ok(buf))
        return zerr(c, SG_EPARSE, "%s: not a number: '%s'", what, q);
    v = strtod(buf, NULL);
    if (!isfinite(v))
        return zerr(c, SG_ERANGE, "%s: %s is beyond the doubles", what, q);
    *out = v;
    return SG_OK;
}

/* Token k as an integer in [lo, hi]; Zemax sometimes writes "1.0". */
static int tok_int(zctx *c, const zline *l, int k, const char *what, int lo, int hi, int *out)
{
    double v;
    int rc = tok_num(c, l, k, what, &v);
    if (rc != SG_OK)
        return rc;
    if (v != floor(v) || v < lo || v > hi)
        return zerr(c, SG_ERANGE, "%s: %.17g is not a whole number from %d to %d", what, v, lo,
                    hi);
    *out = (int)v;
    return SG_OK;
}

/* Optional number: absent tokens read as dflt. */
static int opt_num(zctx *c, const zline *l, int k, const char *what, double dflt, double *out)
{
    if (k >= l->n) {
        *out = dflt;
        return SG_OK;
    }
    return tok_num(c, l, k, what, out);
}

/* Keeps a pickup read from the file (from already checked to be an
 * earlier surface) and counts it among the kept solves. */
static void keep_pickup(zctx *c, sg_solve *o, sg_solve_kind kind, double from, double scale,
                        double off)
{
    memset(o, 0, sizeof *o);
    o->kind = kind;
    o->from = (int)from;
    o->scale = scale;
    o->offset = off;
    c->nlive++;
}

/* Whether a radius pickup of scale k is the curvature pickup of scale
 * 1 / k with the same bits: k a power of two whose reciprocal is a
 * double, so that both scalings are exact. */
static int curv_scale_ok(double k)
{
    int e;
    double r = 1.0 / k;
    return k != 0.0 && isfinite(k) && fabs(frexp(k, &e)) == 0.5 && isfinite(r) && r != 0.0;
}

/* The radius nearest the exact decimal curvature in tok: 1/D rounded once,
 * by rational arithmetic. */
static int tok_curv(zctx *c, const zline *l, int k, double *radius)
{
    char buf[ZMX_MAX_NUMBER + 1], digits[ZMX_MAX_NUMBER + 1], q[48];
    const char *s;
    double cv;
    long e10 = 0;
    size_t nd = 0;
    int neg = 0, rc;
    mpz_t num, den;
    mpq_t r;
    mpfr_t R;

    if ((rc = tok_num(c, l, k, "curvature", &cv)) != SG_OK)
        return rc;
    if (cv == 0.0) {
        *radius = INFINITY;
        return SG_OK;
    }
    tok_show(&l->t[k], q, sizeof q);
    /* Beyond this the radius exceeds what sg_system_validate accepts. */
    if (fabs(cv) < 1e-150)
        return zerr(c, SG_ERANGE, "curvature %s: the radius is beyond 1e150 lens units", q);
    memcpy(buf, l->t[k].p, l->t[k].n);
    buf[l->t[k].n] = '\0';
    s = buf;
    if (*s == '+' || *s == '-')
        neg = *s++ == '-';
    for (; *s && *s != 'e' && *s != 'E'; s++)
        if (*s != '.')
            digits[nd++] = *s;
    digits[nd] = '\0';
    {
        const char *dot = strchr(buf, '.');
        const char *ex = strpbrk(buf, "eE");
        long frac = 0;
        if (dot)
            frac = (long)((ex ? ex : buf + strlen(buf)) - dot - 1);
        /* The exponent is bounded: the value is a finite nonzero double
         * and the text has at most ZMX_MAX_NUMBER characters. */
        e10 = (ex ? strtol(ex + 1, NULL, 10) : 0) - frac;
    }
    /* D = digits * 10^e10, so 1/D = 10^-e10 / digits. */
    mpz_init_set_str(num, digits, 10);
    mpz_init_set_ui(den, 1);
    if (e10 > 0) {
        mpz_t p;
        mpz_init(p);
        mpz_ui_pow_ui(p, 10, (unsigned long)e10);
        mpz_mul(num, num, p);
        mpz_clear(p);
    } else if (e10 < 0) {
        mpz_ui_pow_ui(den, 10, (unsigned long)(-e10));
    }
    mpq_init(r);
    mpq_set_num(r, den);
    mpq_set_den(r, num);
    mpq_canonicalize(r);
    mpfr_init2(R, 53);
    mpfr_set_q(R, r, MPFR_RNDN);
    *radius = mpfr_get_d(R, MPFR_RNDN);
    if (neg)
        *radius = -*radius;
    mpfr_clear(R);
    mpq_clear(r);
    mpz_clear(num);
    mpz_clear(den);
    /* Zemax writes a curvature in 16 to 19 digits, 1/R of the radius the
     * user typed; where a shorter decimal radius has exactly that
     * curvature, it is the radius (-1015, not -1015.0000000000001).  A
     * longer text, such as sagitta's own 25 digits, keeps its exact
     * reciprocal, so an exported design reads back bit for bit. */
    if (nd <= 20 && isfinite(*radius)) {
        int p;
        for (p = 1; p < 17; p++) {
            char t[40];
            double r2;
            snprintf(t, sizeof t, "%.*g", p, *radius);
            r2 = strtod(t, NULL);
            if (isfinite(r2) && r2 != 0.0 && 1.0 / r2 == cv) {
                *radius = r2;
                break;
            }
        }
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * Lines
 * ------------------------------------------------------------------------ */

static void split(char *s, zline *l)
{
    char *p = s;
    l->n = 0;
    l->rest1 = "";
    l->indented = *p == ' ' || *p == '\t';
    while (*p) {
        while (*p == ' ' || *p == '\t')
            p++;
        if (!*p)
            break;
        if (l->n == 1)
            l->rest1 = p;
        if (l->n < ZMX_MAX_TOK) {
            l->t[l->n].p = p;
            while (*p && *p != ' ' && *p != '\t')
                p++;
            l->t[l->n].n = (size_t)(p - l->t[l->n].p);
            l->n++;
        } else {
            break;
        }
    }
}

static int in_list(const ztok *t, const char *const *list, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (tok_is(t, list[i]))
            return 1;
    return 0;
}

/* Copies the rest of the line after the keyword.  Control characters
 * become spaces and blanks at either end go, as the writer would leave
 * them, so a text reads back the same after a round trip. */
static void rest_copy(const zline *l, char *dst, size_t n, int *cut)
{
    const char *src = l->rest1;
    size_t len, i, start = 0;
    len = strlen(src);
    *cut = 0;
    if (len >= n) {
        *cut = 1;
        len = n - 1;
        /* Cut on a UTF-8 character boundary. */
        while (len && ((unsigned char)src[len] & 0xC0) == 0x80)
            len--;
    }
    for (i = 0; i < len; i++) {
        unsigned char ch = (unsigned char)src[i];
        dst[i] = (ch < 0x20 || ch == 0x7F) ? ' ' : (char)ch;
    }
    while (len && dst[len - 1] == ' ')
        len--;
    while (start < len && dst[start] == ' ')
        start++;
    memmove(dst, dst + start, len - start);
    dst[len - start] = '\0';
}

/* Whether every number from token k on is zero (absent counts as zero). */
static int all_zero(zctx *c, const zline *l, int k, int *rc)
{
    double v;
    *rc = SG_OK;
    for (; k < l->n; k++) {
        if (l->t[k].n == 2 && l->t[k].p[0] == '"' && l->t[k].p[1] == '"')
            continue;
        if ((*rc = tok_num(c, l, k, "value", &v)) != SG_OK)
            return 0;
        if (v != 0.0)
            return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------------
 * Surfaces
 * ------------------------------------------------------------------------ */

/* Appends surface n (the next one) to the system being read. */
static int grow_to(zctx *c, int n)
{
    sg_system *s = c->sys;
    if (n <= s->nsurf)
        return SG_OK;
    if (n > SG_MAX_SURFACES)
        return zerr(c, SG_ERANGE, "more than %d surfaces", SG_MAX_SURFACES);
    if (n > s->capsurf) {
        int cap = s->capsurf ? s->capsurf * 2 : 8;
        sg_surface *p;
        if (cap > SG_MAX_SURFACES)
            cap = SG_MAX_SURFACES;
        p = realloc(s->surf, (size_t)cap * sizeof *p);
        if (!p)
            return zerr(c, SG_ENOMEM, "out of memory for %d surfaces", n);
        s->surf = p;
        s->capsurf = cap;
    }
    s->nsurf = n;
    return SG_OK;
}

static const sg_glass *nearest_of(const sg_catalog *cat, double nd, double vd)
{
    size_t i, m = cat ? sg_catalog_count(cat) : 0;
    const sg_glass *best = NULL;
    double bd = INFINITY;
    for (i = 0; i < m; i++) {
        const sg_glass *g = sg_catalog_at(cat, i);
        double e = pow((g->nd - nd) / 0.01, 2) + pow(g->vd - vd, 2);
        if (e < bd) {
            bd = e;
            best = g;
        }
    }
    return best;
}

static const char *nearest_glass(const sg_catalog *cat, double nd, double vd, char *buf,
                                 size_t n)
{
    size_t i, m = cat ? sg_catalog_count(cat) : 0;
    const sg_glass *best = NULL;
    double bd = INFINITY;
    for (i = 0; i < m; i++) {
        const sg_glass *g = sg_catalog_at(cat, i);
        /* 0.01 in nd weighs as much as 1 in vd, the usual glass-map scale. */
        double e = pow((g->nd - nd) / 0.01, 2) + pow(g->vd - vd, 2);
        if (e < bd) {
            bd = e;
            best = g;
        }
    }
    if (!best)
        snprintf(buf, n, "no catalog is loaded to suggest one");
    else
        snprintf(buf, n, "the nearest by nd and vd is %s (%s, nd %.6g, vd %.4g)", best->name,
                 best->catalog, best->nd, best->vd);
    return buf;
}

static int gcat_has(const zctx *c, const char *cat)
{
    int i;
    for (i = 0; i < c->ngcat; i++)
        if (strcmp(c->gcat[i], cat) == 0)
            return 1;
    return 0;
}

static int read_glas(zctx *c, const zline *l, sg_surface *s)
{
    char name[SG_GLASS_NAME], q[48], sug[160];
    double flag = 0.0, nd = 0.0, vd = 0.0;
    const sg_glass *g;
    size_t i;
    int rc, k;
    s->mat.catalog[0] = '\0';
    if (l->n < 2) {
        s->mat.kind = SG_MAT_AIR;
        return SG_OK;
    }
    tok_show(&l->t[1], q, sizeof q);
    if (l->t[1].n >= SG_GLASS_NAME)
        return zerr(c, SG_ERANGE, "GLAS: glass name '%s' is longer than %d characters", q,
                    SG_GLASS_NAME - 1);
    memcpy(name, l->t[1].p, l->t[1].n);
    name[l->t[1].n] = '\0';
    for (i = 0; name[i]; i++)
        name[i] = (char)toupper((unsigned char)name[i]);
    if ((rc = opt_num(c, l, 2, "glass solve", 0.0, &flag)) != SG_OK ||
        (rc = opt_num(c, l, 4, "nd", 0.0, &nd)) != SG_OK ||
        (rc = opt_num(c, l, 5, "vd", 0.0, &vd)) != SG_OK)
        return rc;
    if (strcmp(name, "MIRROR") == 0) {
        s->mat.kind = SG_MAT_MIRROR;
        return SG_OK;
    }
    if (strcmp(name, "AIR") == 0) {
        s->mat.kind = SG_MAT_AIR;
        return SG_OK;
    }
    if (strcmp(name, "___BLANK") == 0) {
        /* A model glass: nd, vd (and dPgF).  Without dispersion (vd 0) it
         * is a fixed index; with it, sagitta's model glass. */
        double dpgf = 0.0;
        if ((rc = opt_num(c, l, 6, "dPgF", 0.0, &dpgf)) != SG_OK)
            return rc;
        if (vd != 0.0 || dpgf != 0.0) {
            sg_glass probe;
            if (sg_model_glass(nd, vd, dpgf, &probe) != SG_OK)
                return zerr(c, SG_ERANGE,
                            "GLAS: model glass nd %.15g, vd %.15g, dPgF %.15g is outside "
                            "nd %g to %g, vd %g to %g, |dPgF| at most %g (%s)",
                            nd, vd, dpgf, SG_MODEL_ND_MIN, SG_MODEL_ND_MAX, SG_MODEL_VD_MIN,
                            SG_MODEL_VD_MAX, SG_MODEL_DPGF_MAX,
                            nearest_glass(c->cat, nd, vd, sug, sizeof sug));
            /* Zemax's model glass formula is not published. */
            zwarn(c, "GLAS: model glass nd %.15g, vd %.15g, dPgF %.15g: sagitta's model "
                  "(Conrady's formula through nd, vd and SCHOTT's normal line) is not Zemax's "
                  "unpublished one; indices may differ by some 1e-4",
                  nd, vd, dpgf);
            s->mat.kind = SG_MAT_MODEL;
            s->mat.index = nd;
            s->mat.vd = vd;
            s->mat.dpgf = dpgf;
            return SG_OK;
        }
        if (!(nd >= 1e-3 && nd < 100.0))
            return zerr(c, SG_ERANGE, "GLAS: model glass index %.17g is not physical", nd);
        s->mat.kind = SG_MAT_INDEX;
        s->mat.index = nd;
        return SG_OK;
    }
    if (flag != 0.0 && flag != 1.0) {
        c->nfrozen++;
        zwarn(c, "GLAS: the glass solve (type %g) is frozen: %s is used as stored", flag, name);
    }
    s->mat.kind = SG_MAT_GLASS;
    sg_strlcpy(s->mat.name, name, sizeof s->mat.name);
    if (!c->cat)
        return SG_OK;
    /* Zemax takes a glass from the first catalog of the GCAT line that
     * has one of its name; sagitta's order decides only when none does. */
    g = NULL;
    for (k = 0; k < c->ngcat && !g; k++)
        g = sg_catalog_find_in(c->cat, c->gcat[k], name);
    if (!g)
        g = sg_catalog_find(c->cat, name);
    if (!g) {
        char cats[128] = "";
        for (k = 0; k < c->ngcat; k++) {
            if (k)
                strncat(cats, " ", sizeof cats - strlen(cats) - 1);
            strncat(cats, c->gcat[k], sizeof cats - strlen(cats) - 1);
        }
        /* Zemax writes nd 1.5, vd 40 (or zeros) for a catalog glass whose
         * data it does not store. */
        int stored = nd > 0.0 && !(nd == 1.5 && vd == 40.0);
        const char *to = NULL;
        size_t nl = strlen(name);
        /* A substitution asked for: NAME=GLASS, or the nearest. */
        for (k = 0; c->sub && k < c->sub->n && !to; k++) {
            const char *p = c->sub->pairs[k];
            if (strlen(p) > nl && p[nl] == '=' && strncasecmp(p, name, nl) == 0)
                to = p + nl + 1;
        }
        if (to) {
            g = sg_catalog_find(c->cat, to);
            if (!g)
                return zerr(c, SG_ENOGLASS, "GLAS: glass %s is to be substituted by %s, which is "
                            "not in sagitta's catalog either", name, to);
        } else if (c->sub && c->sub->nearest && stored) {
            g = nearest_of(c->cat, nd, vd);
        }
        if (g) {
            zwarn(c, "GLAS: glass %s (nd %.6g, vd %.4g in the file) is substituted by %s (%s, "
                  "nd %.6g, vd %.4g)%s", name, nd, vd, g->name, g->catalog, g->nd, g->vd,
                  to ? "" : ", the nearest by nd and vd");
            sg_strlcpy(s->mat.name, g->name, sizeof s->mat.name);
            if (g != sg_catalog_find(c->cat, g->name))
                sg_strlcpy(s->mat.catalog, g->catalog, sizeof s->mat.catalog);
            return SG_OK;
        }
        if (stored)
            nearest_glass(c->cat, nd, vd, sug, sizeof sug);
        else
            snprintf(sug, sizeof sug, "the file stores no nd and vd to suggest one by");
        return zerr(c, SG_ENOGLASS,
                    "GLAS: glass %s (from the file's catalogs %s) is not in sagitta's catalog; "
                    "%s, but no glass is substituted.  Add its catalog (an AGF file, in "
                    "SAGITTA_LENSDB) or substitute it (sagitta import --substitute %s=GLASS%s)",
                    name, cats[0] ? cats : "(no GCAT line)", sug, name,
                    stored ? " or --substitute-nearest" : "");
    }
    if (c->ngcat && !gcat_has(c, g->catalog))
        zwarn(c, "GLAS: %s is taken from sagitta's %s catalog, which the file's GCAT line "
              "does not list", name, g->catalog);
    /* The design names the catalog only where the name alone would mean
     * another catalog's glass. */
    if (g != sg_catalog_find(c->cat, name))
        sg_strlcpy(s->mat.catalog, g->catalog, sizeof s->mat.catalog);
    return SG_OK;
}

/* PARM k of z must be 0 unless lo <= k <= hi: what the type reads. */
static int parm_only(zctx *c, zsurf *z, int lo, int hi, const char *what)
{
    int k;
    for (k = 0; k <= ZMX_MAX_PARM; k++)
        if ((k < lo || k > hi) && z->parm[k] != 0.0) {
            c->line = z->parm_line[k];
            return zerr(c, SG_EUNSUPPORTED, "PARM %d is %.17g; %s", k, z->parm[k], what);
        }
    return SG_OK;
}

/* The type whose record maps its .zmx block (the types end_surface
 * reads itself have none), by its TYPE keyword; NULL when none. */
#define ZMX_NAME_(name, json, zmx, rec) zmx,
static const char *const zmx_type_names[] = {SG_SURF_TYPES(ZMX_NAME_)};
#undef ZMX_NAME_
static const sg_shape_type *zmx_type_of(const char *name)
{
    int i;
    for (i = 0; i < SG_SURF_NTYPES; i++)
        if (strcmp(name, zmx_type_names[i]) == 0 && sg_shape_type_of(i)->zmx)
            return sg_shape_type_of(i);
    return NULL;
}

/* Element e of the surface parameter key. */
static double *zmx_value(sg_surface *s, const char *key, int e)
{
    return (double *)sg_param_ptr(sg_param_find(SG_SCOPE_SURFACE, key), s) + e;
}

/* A type's block by its record (src/shape.h): the PARM numbers it may
 * hold, its runs of PARM and XDAT values, its terms in XDAT. */
static int zmx_read_shape(zctx *c, zsurf *z, sg_surface *s, const sg_shape_type *t)
{
    const sg_zmx_map *m;
    int k;
    s->type = (sg_surf_type)t->type;
    if ((k = parm_only(c, z, t->parm_lo, t->parm_hi, t->parm_what)) != SG_OK)
        return k;
    if (t->extrapolate && z->parm_line[0] && z->parm[0] == 0.0)
        zwarn(c, "PARM 0: extrapolate is 0, so Zemax drops the Zernike terms beyond the "
              "normalization radius; sagitta applies them at every radius");
    for (m = t->zmx; m->key; m++)
        for (k = 0; k < m->n; k++) {
            double v = m->xdat ? z->xd[m->index + k] : z->parm[m->index + k];
            *zmx_value(s, m->key, m->elem + k) =
                (m->flags & SG_ZMX_ZERO_INF) && v == 0.0 ? INFINITY : v;
        }
    if (t->zmx_terms) {
        /* XDAT 1 the number of terms, 2 the normalization radius, 3 on
         * the coefficients. */
        int n = (int)z->xd[1], max = t->zmx_terms;
        if (z->xd[1] != (double)n || n < 0 || n > max) {
            c->line = z->xd_line[1];
            return zerr(c, SG_EUNSUPPORTED, "XDAT 1: %.17g terms; sagitta reads 0 to %d here",
                        z->xd[1], max);
        }
        s->norm_radius = z->xd[2];
        if (!(s->norm_radius > 0.0) || !isfinite(s->norm_radius)) {
            c->line = z->xd_line[2];
            return zerr(c, SG_ERANGE, "XDAT 2: normalization radius %.17g must be positive",
                        z->xd[2]);
        }
        for (k = 3; k <= ZMX_MAX_XDAT; k++)
            if (z->xd[k] != 0.0 && k - 2 > n) {
                c->line = z->xd_line[k];
                return zerr(c, SG_EUNSUPPORTED, "XDAT %d is %.17g, beyond the %d terms XDAT 1 "
                            "gives", k, z->xd[k], n);
            }
        for (k = 0; k < n; k++)
            s->terms[k] = z->xd[k + 3];
    }
    if (t->xdat_what)
        for (k = 3; k <= ZMX_MAX_XDAT; k++)
            if (z->xd[k] != 0.0) {
                c->line = z->xd_line[k];
                return zerr(c, SG_EUNSUPPORTED, "XDAT %d is %.17g: %s", k, z->xd[k],
                            t->xdat_what);
            }
    return SG_OK;
}

/* The shapes of sagitta-design(5), SURFACE TYPES, from their Zemax
 * parameters (PARM) and extra data (XDAT); SG_EUNSUPPORTED with the
 * message otherwise. */
static int zmx_shape(zctx *c, zsurf *z, sg_surface *s)
{
    const sg_shape_type *t = zmx_type_of(z->type);
    int k;
    if (t) {
        if ((k = zmx_read_shape(c, z, s, t)) != SG_OK)
            return k;
    } else if (strcmp(z->type, "TILTSURF") == 0) {
        /* Zemax's tilted plane, z = x tan(theta_x) + y tan(theta_y) with
         * the tangents in PARM 1 and 2: exactly the XY polynomial of the
         * terms x and y at normalization radius 1. */
        s->type = SG_SURF_XYPOLY;
        if ((k = parm_only(c, z, 1, 2, "a tilted surface has the x and y tangents (PARM 1 "
                                       "and 2)")) != SG_OK)
            return k;
        if (isfinite(s->radius) && s->radius != 0.0)
            return zerr(c, SG_EUNSUPPORTED, "TYPE TILTSURF with a curvature: Zemax's tilted "
                        "surface is a plane");
        if (s->conic != 0.0)
            return zerr(c, SG_EUNSUPPORTED, "TYPE TILTSURF with a conic: Zemax's tilted "
                        "surface is a plane");
        for (k = 1; k <= ZMX_MAX_XDAT; k++)
            if (z->xd[k] != 0.0) {
                c->line = z->xd_line[k];
                return zerr(c, SG_EUNSUPPORTED, "XDAT %d is %.17g: a tilted surface has no "
                            "extra data", k, z->xd[k]);
            }
        s->norm_radius = 1.0;
        s->terms[0] = z->parm[1];
        s->terms[1] = z->parm[2];
        zwarn(c, "TYPE TILTSURF: note: the tilted plane is read as the XY polynomial z = %.17g x "
              "+ %.17g y, the same surface, and is written back as XPOLYNOM", s->terms[0],
              s->terms[1]);
    } else {
        const char *what = strcmp(z->type, "BICONIC") == 0      ? "an old biconic"
                           : strcmp(z->type, "DGRATING") == 0   ? "a diffraction grating"
                           : strcmp(z->type, "EXTPOLY") == 0    ? "an extended polynomial"
                           : strcmp(z->type, "GRID_SAG") == 0   ? "a grid sag"
                           : strcmp(z->type, "NONSEQCO") == 0   ? "a non-sequential component"
                                                                : "this surface type";
        return zerr(c, SG_EUNSUPPORTED,
                    "TYPE %s is %s; sagitta has the standard, even and odd asphere, toroidal, "
                    "biconic, Zernike sag, XY polynomial and coordinate-break surfaces",
                    z->type, what);
    }
    /* Their extra data are read above; no other check applies. */
    z->xdat_line = 0;
    return SG_OK;
}

/* A pickup line, "from scale offset [column]": PZUP of a thickness, PKUP
 * of a conic (a Zemax 13 file writes "PKUP 2 1 0" for surface 2's conic
 * at scale 1; tests/data/zmx/README.md).  Column 0 (the same parameter)
 * from an earlier surface is kept; any other is frozen, with a warning. */
static int read_pickup(zctx *c, const zline *l, sg_surface *s, sg_solve_target t,
                       const char *what)
{
    double from, scale, off, col;
    int rc;
    if ((rc = opt_num(c, l, 1, "pickup surface", -1.0, &from)) != SG_OK ||
        (rc = opt_num(c, l, 2, "pickup scale", 1.0, &scale)) != SG_OK ||
        (rc = opt_num(c, l, 3, "pickup offset", 0.0, &off)) != SG_OK ||
        (rc = opt_num(c, l, 4, "pickup column", 0.0, &col)) != SG_OK)
        return rc;
    if (from == floor(from) && from >= 0 && from < c->cur && col == 0.0) {
        keep_pickup(c, &s->solve[t], SG_SOLVE_PICKUP, from, scale, off);
        zwarn(c, "%.4s: note: the %s pickup from surface %d is kept", l->t[0].p, what,
              (int)from);
        return SG_OK;
    }
    c->nfrozen++;
    zwarn(c, "%.4s: the %s pickup from surface %g (column %g) is frozen at the value stored in "
          "the file: sagitta keeps pickups of a %s from an earlier surface", l->t[0].p, what,
          from, col, what);
    return SG_OK;
}

/* The TYPE names sagitta reads (end_surface, zmx_shape). */
static int known_type(const char *t)
{
    int i;
    for (i = 0; i < SG_SURF_NTYPES; i++)
        if (strcmp(t, zmx_type_names[i]) == 0)
            return 1;
    return strcmp(t, "TILTSURF") == 0;
}

/* Ends the current surface block: its type, parameters and aperture. */
static int end_surface(zctx *c)
{
    sg_surface *s;
    zsurf *z = &c->zs;
    int k, save = c->cur;
    long save_line = c->line;
    if (c->cur < 0)
        return SG_OK;
    s = &c->sys->surf[c->cur];
    c->line = z->type_line ? z->type_line : z->line;
    if (!z->type[0] || strcmp(z->type, "STANDARD") == 0) {
        s->type = SG_SURF_STANDARD;
        for (k = 0; k <= ZMX_MAX_PARM; k++)
            if (z->parm[k] != 0.0) {
                c->line = z->parm_line[k];
                return zerr(c, SG_EUNSUPPORTED,
                            "PARM %d is %.17g on a standard surface, which has no parameter %d",
                            k, z->parm[k], k);
            }
    } else if (strcmp(z->type, "JONESMAT") == 0) {
        /* Zemax's Jones matrix surface is always a plane (it does not use
         * the radius column), and its matrix (PARM 1 to 8: A, B, C, D,
         * real and imaginary) acts on the polarization alone, which a
         * sequential trace does not carry: a plane, with its lines kept. */
        s->type = SG_SURF_STANDARD;
        for (k = 0; k <= ZMX_MAX_PARM; k++)
            if (z->parm[k] != 0.0 && (k < 1 || k > 8)) {
                c->line = z->parm_line[k];
                return zerr(c, SG_EUNSUPPORTED, "PARM %d is %.17g; a Jones matrix surface has "
                            "parameters 1 to 8", k, z->parm[k]);
            }
        if ((isfinite(s->radius) && s->radius != 0.0) || s->conic != 0.0)
            zwarn(c, "TYPE JONESMAT: note: Zemax's Jones matrix surface is a plane; its "
                  "radius %.17g and conic %.17g are not used", s->radius, s->conic);
        s->radius = INFINITY;
        s->conic = 0.0;
        zwarn(c, "TYPE JONESMAT: note: a Jones matrix surface, read as a plane: its matrix "
              "changes only the polarization, which sagitta does not trace, and its lines are "
              "kept for a .zmx save (sagitta-design(5), ZEMAX FILES)");
    } else if (strcmp(z->type, "EVENASPH") == 0) {
        s->type = SG_SURF_EVENASPH;
        for (k = 0; k <= ZMX_MAX_PARM; k++) {
            if (k >= 1 && k <= ZMX_NPARM)
                s->asph[k - 1] = z->parm[k];
            else if (z->parm[k] != 0.0) {
                c->line = z->parm_line[k];
                return zerr(c, SG_EUNSUPPORTED,
                            "PARM %d is %.17g; the even asphere has terms r^2 to r^16 "
                            "(PARM 1 to 8)", k, z->parm[k]);
            }
        }
    } else if (strcmp(z->type, "COORDBRK") == 0) {
        /* Zemax's parameters: decenter x, decenter y, tilt about x, y, z
         * (degrees), and the order flag (0: decenter, then tilt). */
        s->type = SG_SURF_COORDBRK;
        for (k = 7; k <= ZMX_MAX_PARM; k++)
            if (z->parm[k] != 0.0) {
                c->line = z->parm_line[k];
                return zerr(c, SG_EUNSUPPORTED,
                            "PARM %d is %.17g; a coordinate break has parameters 1 to 6", k,
                            z->parm[k]);
            }
        if (z->parm[0] != 0.0) {
            c->line = z->parm_line[0];
            return zerr(c, SG_EUNSUPPORTED, "PARM 0 is %.17g; a coordinate break has "
                        "parameters 1 to 6", z->parm[0]);
        }
        s->before.dx = z->parm[1];
        s->before.dy = z->parm[2];
        s->before.tx = z->parm[3];
        s->before.ty = z->parm[4];
        s->before.tz = z->parm[5];
        s->before.order = z->parm[6] != 0.0;
        /* Its medium is the one before it; its radius is not used. */
        if (s->mat.kind != SG_MAT_AIR) {
            c->line = z->type_line ? z->type_line : z->line;
            return zerr(c, SG_EUNSUPPORTED, "a coordinate break with a material (GLAS); "
                        "Zemax keeps the medium before it");
        }
        s->radius = INFINITY;
    } else if ((k = zmx_shape(c, z, s)) != SG_OK) {
        return k;
    }
    if (z->pend_line) {
        c->line = z->pend_line;
        return zerr(c, z->pend_code, "%s", z->pend_msg);
    }
    if (z->scbd_line) {
        /* The frame moves before the surface and stays moved after it,
         * as in Zemax when the after-surface tilt is zero. */
        c->line = z->scbd_line;
        if (s->type == SG_SURF_COORDBRK)
            return zerr(c, SG_EUNSUPPORTED, "SCBD: a tilt or decenter on a coordinate break; "
                        "its parameters are the break");
        /* Rays start on the object's axis, which nothing moves. */
        if (c->cur < 1)
            return zerr(c, SG_EUNSUPPORTED, "SCBD: a tilt or decenter before the object; "
                        "sagitta starts rays on the object's axis, which nothing moves");
        s->before = z->scbd;
    }
    if (z->scad_line) {
        c->line = z->scad_line;
        if (s->type == SG_SURF_COORDBRK)
            return zerr(c, SG_EUNSUPPORTED, "SCBD: a tilt or decenter on a coordinate break; "
                        "its parameters are the break");
        if (c->cur < 1)
            return zerr(c, SG_EUNSUPPORTED, "SCBD: a tilt or decenter after the object; "
                        "sagitta's rays start in surface 1's frame (in Zemax, add a dummy "
                        "surface and tilt from surface 2 on)");
        if (z->scad_mode == 2) {
            /* Reverse: Zemax stores the inverse, which must be it. */
            const sg_frame_change *b = &s->before;
            const sg_frame_change *a = &z->scad;
            if (!(a->dx == -b->dx && a->dy == -b->dy && a->tx == -b->tx && a->ty == -b->ty &&
                  a->tz == -b->tz && a->order == (b->order ^ 1)))
                return zerr(c, SG_EPARSE, "SCBD: the after side is \"reverse\" but its values "
                            "are not the before side's, negated, in the other order");
            s->after_mode = SG_AFTER_REVERSE;
            memset(&s->after, 0, sizeof s->after);
        } else {
            s->after = z->scad;
            s->after_mode = SG_AFTER_EXPLICIT;
        }
    }
    if (z->xdat_line) {
        c->line = z->xdat_line;
        return zerr(c, SG_EUNSUPPORTED, "XDAT: extra data %.17g; sagitta's surfaces have no "
                    "extra data", z->xdat);
    }
    if (z->apk && z->ap) {
        c->line = z->apk_line;
        return zerr(c, SG_EUNSUPPORTED, "two apertures on one surface (line %ld and this one); "
                    "Zemax keeps one", z->ap_line);
    }
    if (z->apk || (z->ap == 1 && (z->ap_min != 0.0 || z->obdc_x != 0.0 || z->obdc_y != 0.0))) {
        /* A surface aperture of the model: an annulus or a decentred disc
         * (CLAP with a minimum radius or an OBDC line), or another kind. */
        if (z->apk) {
            s->aperture = (sg_aperture_type)z->apk;
            if (z->apk == SG_OBSCURATION_CIRCULAR) {
                s->ap_rmin = z->apk_a;
                s->ap_rmax = z->apk_b;
            } else {
                s->ap_xhalf = z->apk_a;
                s->ap_yhalf = z->apk_b;
            }
        } else {
            s->aperture = SG_APERTURE_CIRCULAR;
            s->ap_rmin = z->ap_min;
            s->ap_rmax = z->ap_max;
        }
        s->ap_xdec = z->obdc_x;
        s->ap_ydec = z->obdc_y;
        if (z->have_diam) {
            s->semi_diameter = z->diam;
            s->sd_fixed = 0;
        }
    } else if (z->obdc_x != 0.0 || z->obdc_y != 0.0) {
        c->line = z->obdc_line;
        return zerr(c, SG_EUNSUPPORTED, "OBDC: an aperture decenter with no circular, "
                    "rectangular or elliptical aperture or obscuration to move%s",
                    z->ap == 2 ? " (a floating aperture is centred)" : "");
    } else if (z->ap) {
        if (z->have_diam && z->diam != z->ap_max) {
            c->line = z->ap_line;
            zwarn(c, "the %s aperture of radius %.17g vignettes; the semi-diameter shown "
                  "becomes it (DIAM was %.17g)", z->ap == 1 ? "circular" : "floating", z->ap_max,
                  z->diam);
        }
        s->semi_diameter = z->ap_max;
        s->sd_fixed = 1;
    } else if (z->have_diam) {
        s->semi_diameter = z->diam;
        s->sd_fixed = 0;
    }
    c->cur = save;
    c->line = save_line;
    return SG_OK;
}

static int surface_line(zctx *c, const zline *l)
{
    sg_surface *s = &c->sys->surf[c->cur];
    zsurf *z = &c->zs;
    const ztok *k = &l->t[0];
    char q[48];
    double v;
    int rc, nz;

    if (tok_is(k, "TYPE")) {
        if (l->n < 2)
            return zerr(c, SG_EPARSE, "TYPE: missing the surface type");
        if (z->type[0])
            return zerr(c, SG_EPARSE, "a second TYPE line in one surface");
        if ((rc = tok_text(c, l, 1, "surface type", z->type, sizeof z->type)) != SG_OK)
            return rc;
        z->type_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "CURV")) {
        if ((rc = tok_curv(c, l, 1, &s->radius)) != SG_OK)
            return rc;
        if ((rc = opt_num(c, l, 2, "curvature solve", 0.0, &v)) != SG_OK)
            return rc;
        if (v == 4.0) {
            /* A pickup: CURV c 4 from scale offset, of the curvature (a
             * Zemax file stores 2 c for scale 2), kept as Zemax
             * evaluates it. */
            double from, scale, off;
            if ((rc = opt_num(c, l, 3, "pickup surface", -1.0, &from)) != SG_OK ||
                (rc = opt_num(c, l, 4, "pickup scale", 1.0, &scale)) != SG_OK ||
                (rc = opt_num(c, l, 5, "pickup offset", 0.0, &off)) != SG_OK)
                return rc;
            if (from == floor(from) && from >= 0 && from < c->cur && isfinite(scale) &&
                isfinite(off)) {
                keep_pickup(c, &s->solve[SG_SOLVE_RADIUS], SG_SOLVE_CURV_PICKUP, from, scale,
                            off);
                zwarn(c, "CURV: note: the pickup from surface %d is kept", (int)from);
                return SG_OK;
            }
            c->nfrozen++;
            zwarn(c, "CURV: the curvature pickup from surface %g (scale %g, offset %g) is frozen "
                  "at the stored value: sagitta keeps curvature pickups from an earlier surface",
                  from, scale, off);
            return SG_OK;
        }
        if (v == 2.0 || v == 11.0) {
            /* The marginal ray angle (CURV c 2 angle ...) and the F number
             * (CURV c 11 F ...): files written by Zemax store the
             * curvatures these give (sagitta-design(5), ZEMAX FILES). */
            const char *what = v == 2.0 ? "marginal ray angle" : "F number";
            double val;
            if ((rc = opt_num(c, l, 3, what, 0.0, &val)) != SG_OK)
                return rc;
            if (c->cur >= 1 && strcmp(z->type, "COORDBRK") != 0 && (v == 2.0 || val != 0.0)) {
                sg_solve *o = &s->solve[SG_SOLVE_RADIUS];
                memset(o, 0, sizeof *o);
                o->kind = v == 2.0 ? SG_SOLVE_MARGINAL_ANGLE : SG_SOLVE_FNUM;
                o->value = val;
                c->nlive++;
                zwarn(c, "CURV: note: the %s solve (%g) is kept", what, val);
                return SG_OK;
            }
            c->nfrozen++;
            zwarn(c, "CURV: the %s solve %s is frozen at the stored value", what,
                  c->cur < 1 ? "on the object" : val == 0.0 && v == 11.0 ? "of F/0" :
                  "on a coordinate break");
            return SG_OK;
        }
        if (v != 0.0 && v != 1.0) {
            c->nfrozen++;
            zwarn(c, "CURV: the curvature solve (type %g) is frozen at the stored value", v);
        }
        return SG_OK;
    }
    if (tok_is(k, "DISZ")) {
        char buf[16];
        if (l->n >= 2 && l->t[1].n < sizeof buf) {
            memcpy(buf, l->t[1].p, l->t[1].n);
            buf[l->t[1].n] = '\0';
            if (strcmp(buf, "INFINITY") == 0 || strcmp(buf, "Infinity") == 0) {
                if (c->cur != 0)
                    return zerr(c, SG_ERANGE, "DISZ: an infinite thickness is allowed on the "
                                "object surface only");
                s->thickness = INFINITY;
                return SG_OK;
            }
        }
        return tok_num(c, l, 1, "thickness", &s->thickness);
    }
    if (tok_is(k, "GLAS"))
        return read_glas(c, l, s);
    if (tok_is(k, "CONI"))
        return tok_num(c, l, 1, "conic", &s->conic);
    if (tok_is(k, "PARM")) {
        int n;
        if ((rc = tok_int(c, l, 1, "parameter number", 0, ZMX_MAX_PARM, &n)) != SG_OK ||
            (rc = tok_num(c, l, 2, "parameter value", &v)) != SG_OK)
            return rc;
        z->parm[n] = v;
        z->parm_line[n] = c->line;
        return SG_OK;
    }
    if (tok_is(k, "XDAT")) {
        /* Extra data: the Zernike and XY types read theirs at the end of
         * the block, which refuses them on any other type; zeros change
         * nothing. */
        int n;
        if (l->n >= 3 && (rc = tok_num(c, l, 2, "extra data value", &v)) != SG_OK)
            return rc;
        if ((rc = tok_int(c, l, 1, "extra data number", 1, ZMX_MAX_XDAT, &n)) != SG_OK)
            return rc;
        if (l->n >= 3) {
            z->xd[n] = v;
            z->xd_line[n] = c->line;
        }
        if (l->n >= 3 && v != 0.0 && !z->xdat_line) {
            z->xdat_line = c->line;
            z->xdat = v;
        }
        return SG_OK;
    }
    if (tok_is(k, "DIAM")) {
        if ((rc = tok_num(c, l, 1, "semi-diameter", &z->diam)) != SG_OK)
            return rc;
        if (!(z->diam >= 0.0))
            return zerr(c, SG_ERANGE, "DIAM: semi-diameter %.17g is negative", z->diam);
        z->have_diam = 1;
        return SG_OK;
    }
    if (tok_is(k, "STOP")) {
        if (c->nstop++)
            return zerr(c, SG_ETWOSTOPS, "STOP: surface %d is the stop already", c->stop);
        c->stop = c->cur;
        c->stop_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "CLAP") || tok_is(k, "FLAP")) {
        double mn, mx;
        if ((rc = tok_num(c, l, 1, "minimum radius", &mn)) != SG_OK ||
            (rc = tok_num(c, l, 2, "maximum radius", &mx)) != SG_OK)
            return rc;
        if (!(mn >= 0.0) || !(mx >= 0.0))
            return zerr(c, SG_ERANGE, "%.4s: radii %.17g and %.17g must not be negative", k->p,
                        mn, mx);
        if (mn != 0.0 && tok_is(k, "FLAP"))
            return pend(c, SG_EUNSUPPORTED, "FLAP: a floating aperture with a minimum radius "
                        "%.17g; sagitta's floating aperture is a full disc", mn);
        z->ap = tok_is(k, "CLAP") ? 1 : 2;
        z->ap_min = mn;
        z->ap_max = mx;
        z->ap_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "OBDC")) {
        /* The aperture's decenter: x, then y. */
        if ((rc = tok_num(c, l, 1, "aperture x decenter", &z->obdc_x)) != SG_OK ||
            (rc = tok_num(c, l, 2, "aperture y decenter", &z->obdc_y)) != SG_OK)
            return rc;
        z->obdc_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "OBSC") || tok_is(k, "SQAP") || tok_is(k, "ELAP") || tok_is(k, "SQOB") ||
        tok_is(k, "ELOB")) {
        /* OBSC min max; the others x and y half widths. */
        double a, b2;
        if ((rc = tok_num(c, l, 1, tok_is(k, "OBSC") ? "minimum radius" : "x half width", &a)) !=
                SG_OK ||
            (rc = tok_num(c, l, 2, tok_is(k, "OBSC") ? "maximum radius" : "y half width", &b2)) !=
                SG_OK)
            return rc;
        if (!(a >= 0.0) || !(b2 >= 0.0))
            return zerr(c, SG_ERANGE, "%.4s: %.17g and %.17g must not be negative", k->p, a, b2);
        z->apk = tok_is(k, "OBSC")   ? SG_OBSCURATION_CIRCULAR
                 : tok_is(k, "SQAP") ? SG_APERTURE_RECTANGULAR
                 : tok_is(k, "SQOB") ? SG_OBSCURATION_RECTANGULAR
                 : tok_is(k, "ELAP") ? SG_APERTURE_ELLIPTICAL
                                     : SG_OBSCURATION_ELLIPTICAL;
        z->apk_a = a;
        z->apk_b = b2;
        z->apk_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "UDAD") || tok_is(k, "UDOD"))
        return pend(c, SG_EUNSUPPORTED, "%.4s: a user-defined aperture; sagitta has circular, "
                    "rectangular and elliptical apertures and obscurations", k->p);
    if (tok_is(k, "COMM")) {
        int cut;
        rest_copy(l, s->comment, sizeof s->comment, &cut);
        if (cut)
            zwarn(c, "COMM: the comment is cut to %d bytes", SG_COMMENT - 1);
        return SG_OK;
    }
    if (tok_is(k, "SCBD")) {
        /* SCBD side order mode dx dy tx ty tz (tilts in degrees).  Side 1
         * is before the surface, 2 after it; order 0 decenters then tilts,
         * 1 tilts then decenters; the after side's mode is 0 explicit, 1
         * pickup (the before values, as stored) or 2 reverse (the inverse
         * of the before change: the values negated, the order flipped).
         * Zemax 13 writes "SCBD 1 0 0 ... 45 ..." and "SCBD 2 0 1 ... 45
         * ..." for a fold mirror, "SCBD 2 1 2 -0 ..." for a reversed
         * after side (tests/data/zmx/README.md). */
        static const char *const what[5] = {"decenter x", "decenter y", "tilt about x",
                                            "tilt about y", "tilt about z"};
        double sv[5];
        int f[3], i;
        sg_frame_change fc;
        nz = !all_zero(c, l, 1, &rc);
        if (rc != SG_OK)
            return rc;
        if (!nz)
            return SG_OK;
        if (l->n < 9)
            return zerr(c, SG_EPARSE, "SCBD: %d of its 8 values (side, order and mode, decenter x "
                        "and y, tilts about x, y and z)", l->n - 1);
        for (i = 0; i < 3; i++)
            if ((rc = tok_int(c, l, 1 + i, "SCBD flag", -1000, 1000, &f[i])) != SG_OK)
                return rc;
        for (i = 0; i < 5; i++)
            if ((rc = tok_num(c, l, 4 + i, what[i], &sv[i])) != SG_OK)
                return rc;
        if ((f[0] != 1 && f[0] != 2) || (f[1] != 0 && f[1] != 1) ||
            (f[0] == 1 && f[2] != 0) || (f[0] == 2 && (f[2] < 0 || f[2] > 2)))
            return pend(c, SG_EUNSUPPORTED, "SCBD: flags %d %d %d; sagitta reads side 1 (before) "
                        "or 2 (after), order 0 or 1, and the after side's mode 0, 1 or 2, and "
                        "cannot check what others mean: in Zemax, convert the tilt to "
                        "coordinate breaks", f[0], f[1], f[2]);
        if (l->n > 9 && !all_zero(c, l, 9, &rc))
            return rc != SG_OK ? rc
                               : zerr(c, SG_EUNSUPPORTED, "SCBD: more than 8 values; sagitta "
                                      "cannot tell what the others mean");
        if (f[0] == 1 ? z->scbd_line != 0 : z->scad_line != 0)
            return zerr(c, SG_EPARSE, "SCBD: a second line for the %s side in one surface "
                        "(line %ld)", f[0] == 1 ? "before" : "after",
                        f[0] == 1 ? z->scbd_line : z->scad_line);
        fc.dx = sv[0];
        fc.dy = sv[1];
        fc.tx = sv[2];
        fc.ty = sv[3];
        fc.tz = sv[4];
        fc.order = f[1];
        if (f[0] == 1) {
            z->scbd = fc;
            z->scbd_line = c->line;
        } else {
            z->scad = fc;
            z->scad_mode = f[2];
            z->scad_line = c->line;
        }
        return SG_OK;
    }
    if (tok_is(k, "SCAD") || tok_is(k, "TLTX") || tok_is(k, "DECX")) {
        /* The tilt and decenter after a surface (and the old TLTX/DECX):
         * no file written by Zemax with these lines was found to check
         * their fields against; all zero is the identity. */
        nz = !all_zero(c, l, 1, &rc);
        if (rc != SG_OK)
            return rc;
        if (nz)
            return pend(c, SG_EUNSUPPORTED, "%.4s: a tilt or decenter %s the surface; sagitta "
                        "reads Zemax's coordinate breaks (TYPE COORDBRK) and the tilt before a "
                        "surface (SCBD), but not this line, whose fields it cannot check: in "
                        "Zemax, convert the tilt to coordinate breaks", k->p,
                        tok_is(k, "SCAD") ? "after" : "before");
        return SG_OK;
    }
    if (tok_is(k, "MAZH")) {
        /* MAZH height zone: zone 0 is the paraxial marginal ray. */
        double h, zone;
        if ((rc = opt_num(c, l, 1, "marginal ray height", 0.0, &h)) != SG_OK ||
            (rc = opt_num(c, l, 2, "pupil zone", 0.0, &zone)) != SG_OK)
            return rc;
        if (zone == 0.0 && c->cur >= 1) {
            sg_solve *o = &s->solve[SG_SOLVE_THICKNESS];
            memset(o, 0, sizeof *o);
            o->kind = SG_SOLVE_MARGINAL_HEIGHT;
            o->value = h;
            c->nlive++;
            zwarn(c, "MAZH: note: the marginal ray height solve (height %g) is kept", h);
            return SG_OK;
        }
        c->nfrozen++;
        zwarn(c, "MAZH: the marginal ray height solve at pupil zone %g (a real ray) is frozen at "
              "the value stored in the file", zone);
        return SG_OK;
    }
    if (tok_is(k, "CHZH")) {
        /* CHZH height x: the paraxial chief ray height solve on the
         * thickness; only the second field's 0, the one seen in files
         * written by Zemax, is kept. */
        double h, x;
        if ((rc = opt_num(c, l, 1, "chief ray height", 0.0, &h)) != SG_OK ||
            (rc = opt_num(c, l, 2, "chief ray height parameter", 0.0, &x)) != SG_OK)
            return rc;
        if (x == 0.0 && c->cur >= 1) {
            sg_solve *o = &s->solve[SG_SOLVE_THICKNESS];
            memset(o, 0, sizeof *o);
            o->kind = SG_SOLVE_CHIEF_HEIGHT;
            o->value = h;
            c->nlive++;
            zwarn(c, "CHZH: note: the chief ray height solve (height %g) is kept", h);
            return SG_OK;
        }
        c->nfrozen++;
        zwarn(c, "CHZH: the chief ray height solve (second field %g) is frozen at the value "
              "stored in the file", x);
        return SG_OK;
    }
    if (tok_is(k, "PZUP"))
        return read_pickup(c, l, s, SG_SOLVE_THICKNESS, "thickness");
    if (tok_is(k, "TCED")) {
        /* TCED tce 0 0: the TCE column (1e-6/K), the mount's expansion
         * for the air after the surface (Zemax 8 and 13 files write
         * "TCED 2.35E+1 0 0", aluminium, on the surface after a lens). */
        double tce, f2, f3;
        if ((rc = opt_num(c, l, 1, "TCE", 0.0, &tce)) != SG_OK ||
            (rc = opt_num(c, l, 2, "TCE solve", 0.0, &f2)) != SG_OK ||
            (rc = opt_num(c, l, 3, "TCE solve parameter", 0.0, &f3)) != SG_OK)
            return rc;
        if (!(fabs(tce) <= SG_TCE_MAX))
            return zerr(c, SG_ERANGE, "TCED: TCE %.17g (1e-6/K) is outside -%g to %g", tce,
                        SG_TCE_MAX, SG_TCE_MAX);
        s->tce = tce;
        if (f2 != 0.0 || f3 != 0.0) {
            c->nfrozen++;
            zwarn(c, "TCED: the TCE's solve (%g %g) is frozen at the value stored in the file",
                  f2, f3);
        }
        return SG_OK;
    }
    if (tok_is(k, "PKUP"))
        return read_pickup(c, l, s, SG_SOLVE_CONIC, "conic");
    if (tok_is(k, "PPAR") || tok_is(k, "EDGE")) {
        /* A parameter pickup, an edge thickness solve: the stored value
         * stays. */
        c->nfrozen++;
        zwarn(c, "%.4s: the solve or pickup is frozen at the value stored in the file", k->p);
        return SG_OK;
    }
    if (in_list(k, ignored_surface, sizeof ignored_surface / sizeof *ignored_surface))
        return SG_OK;
    {
        int w;
        for (w = 0; w < ZMX_NZERO_KW; w++)
            if (tok_is(k, zero_surface[w])) {
                nz = !all_zero(c, l, 1, &rc);
                if (rc != SG_OK)
                    return rc;
                if (nz)
                    return pend(c, SG_EUNSUPPORTED, "%s: a nonzero value; Zemax does not "
                                "publish what this line's fields mean, so sagitta cannot "
                                "tell whether it changes the trace (it keeps the line when "
                                "every number on it is 0)", zero_surface[w]);
                c->nzero_kw[w]++;
                return SG_OK;
            }
    }
    /* A keyword of a surface type sagitta lacks (NSOH of a non-sequential
     * component, GDAT of a grating): the type is the reason. */
    if (z->type[0] && !known_type(z->type)) {
        c->line = z->type_line;
        return zmx_shape(c, z, s);
    }
    tok_show(k, q, sizeof q);
    return zerr(c, SG_EUNSUPPORTED, "unknown surface keyword '%s'; sagitta cannot tell whether "
                "it changes the trace, so the file is refused", q);
}

/* ------------------------------------------------------------------------
 * The header
 * ------------------------------------------------------------------------ */

static int set_aper(zctx *c, sg_aper_type t, double v)
{
    if (c->have_aper)
        return zerr(c, SG_EPARSE, "a second aperture line (the first is on line %ld)",
                    c->aper_line);
    c->have_aper = 1;
    c->aper_line = c->line;
    c->sys->aper_type = t;
    c->sys->aper_value = v;
    return SG_OK;
}

static int read_list(zctx *c, const zline *l, double *dst, int cap, int *n)
{
    int k, rc;
    *n = 0;
    for (k = 1; k < l->n && *n < cap; k++) {
        if ((rc = tok_num(c, l, k, "value", &dst[*n])) != SG_OK)
            return rc;
        (*n)++;
    }
    return SG_OK;
}

/* VDXN, VDYN, VCXN, VCYN, VANN (which = 0 to 4): one value a field slot,
 * kept for the fields FTYP or the field lists settle at the end.  The old
 * ZVDX ... forms (which < 0), whose layout could not be checked, must be
 * zero. */
static int vignetting(zctx *c, const zline *l, int which, const char *what)
{
    double v;
    int k, rc;
    for (k = 1; k < l->n && k <= SG_MAX_FIELDS; k++) {
        if ((rc = tok_num(c, l, k, what, &v)) != SG_OK)
            return rc;
        if (which < 0) {
            if (v != 0.0 && (!c->have_ftyp || k <= c->ftyp_nfield))
                return zerr(c, SG_EUNSUPPORTED, "%.4s: field %d has the vignetting factor %.17g "
                            "in Zemax's old form, which sagitta does not read; its VDXN ... "
                            "lines are read", l->t[0].p, k, v);
            continue;
        }
        c->vig[which][k - 1] = v;
    }
    if (which >= 0 && k - 1 > c->nvig[which])
        c->nvig[which] = k - 1;
    return SG_OK;
}

/* One row of Zemax's Multi-Configuration Editor for one configuration:
 * "OPER num config value solve num2 ...".  MOFF is
 * an empty row and CWGT a configuration's weight in the merit function:
 * neither changes a trace. */
static int config_line(zctx *c, const zline *l)
{
    const ztok *k = &l->t[0];
    sg_configs *cf = c->sys->configs;
    char type[8], q[48];
    int num, cfg, num2 = 0, solve = 0, i, rc;
    sg_diag e;
    if (tok_is(k, "MOFF") || tok_is(k, "CWGT"))
        return SG_OK;
    tok_show(k, q, sizeof q);
    memcpy(type, k->p, 4);
    type[4] = '\0';
    if ((rc = tok_int(c, l, 1, "operand number", 0, SG_MAX_SURFACES, &num)) != SG_OK ||
        (rc = tok_int(c, l, 2, "configuration", 1, c->mnum, &cfg)) != SG_OK)
        return rc;
    if (l->n < 4)
        return zerr(c, SG_EPARSE, "MNUM: operand %s: missing its value", q);
    if (l->n > 5 && (rc = tok_int(c, l, 5, "operand's second number", 0, 1 << 20, &num2)) != SG_OK)
        return rc;
    if (l->n > 4 && (rc = tok_int(c, l, 4, "operand's solve", 0, 1 << 20, &solve)) != SG_OK)
        return rc;
    if (strcmp(type, "PRAM") != 0)
        num2 = 0;
    /* A row's values come one configuration after another, from 1; a
     * configuration 1 starts a row (two rows may address the same). */
    for (i = cf->nop - 1; i >= 0 && cfg > 1; i--)
        if (!strcmp(cf->op[i].type, type) && cf->op[i].num == num && cf->op[i].num2 == num2)
            break;
    if (i < 0 || cfg == 1) {
        i = cf->nop;
        sg_diag_clear(&e);
        if ((rc = sg_configs_add(cf, type, num, num2, &e)) != SG_OK)
            return zerr(c, rc == SG_ENOMEM ? SG_ENOMEM : SG_EUNSUPPORTED,
                        "MNUM: operand %s of %d configurations: %s", q, c->mnum, e.msg);
        c->mline[i] = c->line;
        if (!(c->mfill[i] = calloc((size_t)c->mnum, 1)))
            return zerr(c, SG_ENOMEM, "MNUM: out of memory");
    }
    if (c->mfill[i][cfg - 1])
        return zerr(c, SG_EPARSE, "MNUM: operand %s %d: configuration %d given twice (line %ld "
                    "gave the row)", q, num, cfg, c->mline[i]);
    c->mfill[i][cfg - 1] = 1;
    /* Pickups and thermal pickups (solve 2 and up) are read as the values
     * Zemax stored; 0 is fixed and 1 variable. */
    if (solve > 1)
        c->nfrozen++;
    if (cf->op[i].mat) {
        /* A glass as the GLAS line gives it: the name, quoted. */
        char gl[SG_GLASS_NAME + 8];
        zline g;
        sg_surface tmp;
        const char *p = l->t[3].p;
        size_t n = l->t[3].n;
        if (n >= 2 && p[0] == '"' && p[n - 1] == '"')
            p++, n -= 2;
        if (n >= SG_GLASS_NAME)
            return zerr(c, SG_ERANGE, "MNUM: GLSS: glass name '%s' is longer than %d characters",
                        q, SG_GLASS_NAME - 1);
        snprintf(gl, sizeof gl, "GLAS %.*s", (int)n, p);
        split(gl, &g);
        sg_surface_init(&tmp);
        if ((rc = read_glas(c, &g, &tmp)) != SG_OK)
            return rc;
        cf->op[i].mat[cfg - 1] = tmp.mat;
        return SG_OK;
    }
    return tok_num(c, l, 3, "operand value", &cf->op[i].value[cfg - 1]);
}

/* Every operand must give every configuration a value. */
static int config_finish(zctx *c)
{
    const sg_configs *cf = c->sys->configs;
    int i, k;
    for (i = 0; cf && i < cf->nop; i++)
        for (k = 0; k < cf->n; k++)
            if (!c->mfill[i][k]) {
                c->line = c->mline[i];
                return zerr(c, SG_EPARSE, "MNUM: operand %s %d has no value for configuration "
                            "%d of %d", cf->op[i].type, cf->op[i].num, k + 1, cf->n);
            }
    return SG_OK;
}


/* A merit function row after the surfaces, as Zemax writes its Merit
 * Function Editor: "TYPE int1 int2 data1 data2 data3 data4 target weight
 * [data5 data6]" (BLNK and DMFS rows as they are).  A row sagitta knows
 * becomes an operand; another is warned about, with its line, and left
 * out, and rows that refer to it by number (SUMM ...) with it.  Returns 1
 * when the line was a merit row, 0 when it is something else. */
static int merit_line(zctx *c, const zline *l)
{
    sg_merit *m = &c->sys->merit;
    char key[5], buf[ZMX_MAX_NUMBER + 1];
    double v[8] = {0};
    int i, t, cur = c->cur, row;
    memcpy(key, l->t[0].p, 4);
    key[4] = '\0';
    if (strcmp(key, "BLNK") != 0) {
        if (l->n < 9)
            return 0;
        for (i = 1; i <= 8; i++) {
            char *end;
            if (l->t[i].n >= sizeof buf)
                return 0;
            memcpy(buf, l->t[i].p, l->t[i].n);
            buf[l->t[i].n] = '\0';
            v[i - 1] = strtod(buf, &end);
            if (end == buf || *end || !isfinite(v[i - 1]))
                return 0;
        }
    }
    if (c->nmrow >= ZMX_MAX_MROWS)
        return 1;
    row = ++c->nmrow;
    c->mrow[row] = 0;
    if (c->lmop && c->line >= 1 && c->line <= c->nlsect)
        c->lmop[c->line - 1] = -1;
    /* Messages name the line, not the last surface. */
    c->cur = -1;
    t = sg_op_parse(key);
    if (strcmp(key, "DMFS") == 0) {
        /* The default merit function's start: its rows follow as rows. */
    } else if (t < 0) {
        zwarn(c, "merit function row %d: operand %s is not one sagitta knows; it is left out "
              "of the design's merit function", row, key);
    } else if (m->nop >= SG_MAX_OPERANDS) {
        if (!c->merit_drop) {
            c->merit_drop = 1;
            c->merit_drop_line = c->line;
            snprintf(c->merit_drop_why, sizeof c->merit_drop_why, "more than %d rows",
                     SG_MAX_OPERANDS);
        }
    } else {
        sg_operand *o = &m->op[m->nop];
        memset(o, 0, sizeof *o);
        o->type = (sg_op_type)t;
        o->i1 = (int)v[0];
        o->i2 = (int)v[1];
        o->hx = v[2];
        o->hy = v[3];
        o->px = v[4];
        o->py = v[5];
        o->target = v[6];
        o->weight = t == SG_OP_BLNK ? 0.0 : v[7];
        /* Rows named by number follow the design's numbering. */
        if (t == SG_OP_SUMM || t == SG_OP_DIFF || t == SG_OP_PROD || t == SG_OP_DIVI ||
            t == SG_OP_OPGT || t == SG_OP_OPLT || t == SG_OP_ABSO || t == SG_OP_SQRT) {
            int two = t <= SG_OP_DIVI, a = o->i1, b = o->i2;
            int ra = a >= 1 && a < row ? c->mrow[a] : 0, rb = b >= 1 && b < row ? c->mrow[b] : 0;
            if (!ra || (two && !rb)) {
                zwarn(c, "merit function row %d: %s refers to row %d, which is left out; it is "
                      "left out too", row, key, !ra ? a : b);
                c->cur = cur;
                return 1;
            }
            o->i1 = ra;
            if (two)
                o->i2 = rb;
        }
        m->present = 1;
        c->mrow[row] = ++m->nop;
        if (c->lmop && c->line >= 1 && c->line <= c->nlsect)
            c->lmop[c->line - 1] = m->nop;
    }
    c->cur = cur;
    return 1;
}

/* A number of a TOL row, or 0 with *ok cleared. */
static double tol_num(const ztok *t, int *ok)
{
    char buf[ZMX_MAX_NUMBER + 1], *end;
    double v;
    if (t->n == 0 || t->n >= sizeof buf) {
        *ok = 0;
        return 0.0;
    }
    memcpy(buf, t->p, t->n);
    buf[t->n] = '\0';
    v = strtod(buf, &end);
    if (end == buf || *end || !isfinite(v))
        *ok = 0;
    return v;
}

/* A row of Zemax's Tolerance Data Editor, after the surfaces: "TOL TYPE
 * int1 int2 min max 0 0 0" (sagitta-design(5), ZEMAX FILES, Tolerances).
 * TOFF is an empty row, TWAV the test wavelength (in the min column),
 * COMP a compensator (int1 the surface, int2 the code: 0 the thickness);
 * an operand sagitta knows becomes a row of the design's tolerances,
 * checked against the design at the end.  Any other row is warned about
 * with its line and left out of the design; the lossless save keeps every
 * TOL line as it is. */
static int tol_line(zctx *c, const zline *l)
{
    sg_tolerances *t = &c->sys->tol;
    char type[8];
    double v[4] = {0};
    int i, ok = 1, ty, cur = c->cur;
    c->cur = -1;
    if (l->n < 6 || l->t[1].n < 1 || l->t[1].n > 4) {
        zwarn(c, "TOL: a tolerance row needs a type and four numbers; it is left out of the "
              "design's tolerances");
        c->cur = cur;
        return SG_OK;
    }
    memcpy(type, l->t[1].p, l->t[1].n);
    type[l->t[1].n] = '\0';
    for (i = 0; i < 4; i++)
        v[i] = tol_num(&l->t[2 + i], &ok);
    /* Surface numbers and codes are small whole numbers. */
    for (i = 0; i < 2; i++)
        if (!(v[i] >= 0.0 && v[i] <= 1e6 && floor(v[i]) == v[i]))
            ok = 0;
    ty = sg_tol_parse(type);
    if (!ok) {
        zwarn(c, "TOL %s: a field is not a number (or Int1, Int2 not a whole number); the row "
              "is left out of the design's tolerances", type);
    } else if (strcmp(type, "TOFF") == 0) {
        /* An empty row of the editor. */
    } else if (strcmp(type, "TWAV") == 0) {
        if (v[2] >= 0.1 && v[2] <= 100.0)
            t->test_wave = v[2];
        else
            zwarn(c, "TOL TWAV: a test wavelength of %.17g um is not 0.1 to 100 um; fringes "
                  "stay at 0.6328 um", v[2]);
    } else if (strcmp(type, "COMP") == 0) {
        if (v[1] != 0.0)
            zwarn(c, "TOL COMP: compensator code %g on surface %g is not one sagitta maps "
                  "(0, the thickness, is); it is left out of the design's tolerances", v[1],
                  v[0]);
        else if (t->ncomp >= SG_MAX_COMPENSATORS)
            zwarn(c, "TOL COMP: more than %d compensators; the row is left out",
                  SG_MAX_COMPENSATORS);
        else {
            sg_tol_comp *o = &t->comp[t->ncomp];
            memset(o, 0, sizeof *o);
            o->surface = (int)v[0];
            snprintf(o->param, sizeof o->param, "thickness");
            o->min = v[2];
            o->max = v[3];
            c->comp_line[t->ncomp++] = c->line;
        }
    } else if (ty < 0 || ty == SG_TOL_TPAR || ty == SG_TOL_TEZI) {
        zwarn(c, "TOL %s: %s; it is left out of the design's tolerances", type,
              ty < 0                ? "not a tolerance operand sagitta knows"
              : ty == SG_TOL_TPAR ? "Zemax's TPAR numbers the parameter columns, which sagitta "
                                    "does not map"
                                  : "no file at hand shows where the TOL line keeps TEZI's "
                                    "Int3 (its first term)");
    } else if (t->nop >= SG_MAX_TOL_OPERANDS) {
        zwarn(c, "TOL %s: more than %d tolerance operands; the row is left out", type,
              SG_MAX_TOL_OPERANDS);
    } else {
        sg_tol_operand *o = &t->op[t->nop];
        memset(o, 0, sizeof *o);
        o->type = (sg_tol_type)ty;
        o->surface = (int)v[0];
        o->adjust = -1;
        /* An element is int1..int2; TTHI's int2 is the surface that takes
         * the opposite change, none when it is int1 itself. */
        if (ty >= SG_TOL_TEDX && ty <= SG_TOL_TETZ)
            o->last = (int)v[1];
        else if (ty == SG_TOL_TTHI && (int)v[1] != o->surface)
            o->adjust = (int)v[1];
        o->min = v[2];
        o->max = v[3];
        c->tol_line[t->nop++] = c->line;
    }
    c->cur = cur;
    return SG_OK;
}

static int header_line(zctx *c, const zline *l)
{
    const ztok *k = &l->t[0];
    sg_system *s = c->sys;
    char q[48], buf[32];
    double v, f;
    int rc, n, i;

    if (tok_is(k, "MODE")) {
        if (l->n < 2 || !tok_is(&l->t[1], "SEQ"))
            return zerr(c, SG_EUNSUPPORTED, "MODE: sagitta reads sequential files (MODE SEQ) only");
        return SG_OK;
    }
    if (tok_is(k, "NAME")) {
        int cut;
        rest_copy(l, s->title, sizeof s->title, &cut);
        if (cut)
            zwarn(c, "NAME: the title is cut to %zu bytes", sizeof s->title - 1);
        return SG_OK;
    }
    if (tok_is(k, "UNIT")) {
        if ((rc = tok_text(c, l, 1, "lens unit", buf, sizeof buf)) != SG_OK)
            return rc;
        if (strcmp(buf, "MM") == 0)
            sg_strlcpy(s->units, "mm", sizeof s->units);
        else if (strcmp(buf, "CM") == 0)
            sg_strlcpy(s->units, "cm", sizeof s->units);
        else if (strcmp(buf, "IN") == 0 || strcmp(buf, "INCH") == 0)
            sg_strlcpy(s->units, "in", sizeof s->units);
        else if (strcmp(buf, "METER") == 0 || strcmp(buf, "M") == 0)
            sg_strlcpy(s->units, "m", sizeof s->units);
        else
            return zerr(c, SG_EUNSUPPORTED, "UNIT: lens unit '%s'; sagitta has MM, CM, IN and "
                        "METER", buf);
        return SG_OK;
    }
    if (tok_is(k, "ENPD")) {
        if ((rc = tok_num(c, l, 1, "entrance pupil diameter", &v)) != SG_OK)
            return rc;
        return set_aper(c, SG_APER_EPD, v);
    }
    if (tok_is(k, "FNUM") || tok_is(k, "OBNA")) {
        int fn = tok_is(k, "FNUM");
        if ((rc = tok_num(c, l, 1, fn ? "F/#" : "object NA", &v)) != SG_OK ||
            (rc = opt_num(c, l, 2, "aperture kind", 0.0, &f)) != SG_OK)
            return rc;
        if (f == 0.0)
            return set_aper(c, fn ? SG_APER_IMAGE_FNUM : SG_APER_OBJECT_NA, v);
        if (f == 1.0 && fn)
            return set_aper(c, SG_APER_PARAX_WORKING_FNUM, v);
        if (f == 1.0) {
            /* The half angle of the axial object point's cone, in degrees. */
            if (!(v > 0.0 && v < 90.0))
                return zerr(c, SG_EUNSUPPORTED, "OBNA: an object cone angle of %.17g degrees; "
                            "sagitta takes angles below 90", v);
            return set_aper(c, SG_APER_OBJECT_CONE, v);
        }
        return zerr(c, SG_EUNSUPPORTED, "%.4s: aperture kind %.17g is not one sagitta knows",
                    k->p, f);
    }
    if (tok_is(k, "FLOA"))
        return set_aper(c, SG_APER_FLOAT_STOP, 0.0);
    if (tok_is(k, "ENVD")) {
        double t, p;
        if ((rc = tok_num(c, l, 1, "temperature", &t)) != SG_OK ||
            (rc = opt_num(c, l, 2, "pressure", 1.0, &p)) != SG_OK)
            return rc;
        if (!(t >= SG_TEMP_MIN && t <= SG_TEMP_MAX))
            return zerr(c, SG_ERANGE, "ENVD: temperature %.17g C is outside %g to %g C", t,
                        SG_TEMP_MIN, SG_TEMP_MAX);
        if (!(p >= 0.0 && p <= SG_PRES_MAX))
            return zerr(c, SG_ERANGE, "ENVD: pressure %.17g atm is outside 0 to %g atm", p,
                        SG_PRES_MAX);
        if ((rc = opt_num(c, l, 3, "index adjustment flag", 0.0, &f)) != SG_OK)
            return rc;
        /* The flag is Zemax's "Adjust Index Data To Environment". */
        s->temperature = t;
        s->pressure = p;
        s->adjust_index = f != 0.0;
        return SG_OK;
    }
    if (tok_is(k, "GCAT")) {
        for (i = 1; i < l->n; i++) {
            if (c->ngcat >= ZMX_MAX_GCAT)
                return zerr(c, SG_ERANGE, "GCAT: more than %d catalogs", ZMX_MAX_GCAT);
            if ((rc = tok_text(c, l, i, "catalog name", c->gcat[c->ngcat], SG_GLASS_NAME)) != SG_OK)
                return rc;
            c->ngcat++;
        }
        return SG_OK;
    }
    if (tok_is(k, "RAIM")) {
        int t = 0;
        if (l->n > 2 && (rc = tok_int(c, l, 2, "ray-aiming type", 0, 2, &t)) != SG_OK)
            return rc;
        s->aim = t == 0 ? SG_AIM_OFF : t == 1 ? SG_AIM_PARAXIAL : SG_AIM_REAL;
        return SG_OK;
    }
    if (tok_is(k, "PUSH")) {
        int nz = !all_zero(c, l, 1, &rc);
        if (rc != SG_OK)
            return rc;
        /* Zemax's pupil shift is ray aiming's first guess at where a ray
         * meets the stop; once a ray is aimed it plays no part, so with
         * ray aiming on it changes no trace (checked in finish, since
         * RAIM may come later). */
        if (nz)
            c->push_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "FTYP")) {
        int t, tel = 0, norm = 0, afocal = 0;
        if ((rc = tok_int(c, l, 1, "field type", 0, 99, &t)) != SG_OK ||
            (rc = tok_int(c, l, 3, "number of fields", 1, SG_MAX_FIELDS, &c->ftyp_nfield)) != SG_OK ||
            (rc = tok_int(c, l, 4, "number of wavelengths", 1, SG_MAX_WAVES, &c->ftyp_nwave)) != SG_OK)
            return rc;
        if ((l->n > 2 && (rc = tok_int(c, l, 2, "telecentric flag", 0, 1, &tel)) != SG_OK) ||
            (l->n > 5 && (rc = tok_int(c, l, 5, "field normalization", 0, 1, &norm)) != SG_OK) ||
            (l->n > 7 && (rc = tok_int(c, l, 7, "afocal flag", 0, 1, &afocal)) != SG_OK))
            return rc;
        if (t > 3)
            return zerr(c, SG_EUNSUPPORTED, "FTYP: field type %d (%s); sagitta has angle, object "
                        "height, paraxial and real image height", t,
                        t == 4 ? "theodolite angle" : "unknown");
        /* Telecentric object space: checked with the aperture and the
         * object distance when the design is validated. */
        s->telecentric = tel;
        s->afocal = afocal;
        s->field_type = (sg_field_type)t;
        s->field_norm = norm ? SG_NORM_RECT : SG_NORM_RADIAL;
        c->have_ftyp = 1;
        c->ftyp_line = c->line;
        return SG_OK;
    }
    if (tok_is(k, "XFLD") || tok_is(k, "YFLD") || tok_is(k, "FWGT")) {
        int w = tok_is(k, "XFLD") ? 0 : tok_is(k, "YFLD") ? 1 : 2;
        c->oldf_line[w] = c->line;
        return read_list(c, l, c->oldf[w], SG_MAX_FIELDS, &c->noldf[w]);
    }
    if (tok_is(k, "XFLN") || tok_is(k, "YFLN") || tok_is(k, "FWGN")) {
        int x = tok_is(k, "XFLN"), y = tok_is(k, "YFLN");
        rc = read_list(c, l, x ? c->xfln : y ? c->yfln : c->fwgn, SG_MAX_FIELDS,
                       x ? &c->nxfln : y ? &c->nyfln : &c->nfwgn);
        if (x)
            c->xfln_line = c->line;
        if (y)
            c->yfln_line = c->line;
        return rc;
    }
    if (tok_is(k, "VDXN") || tok_is(k, "VDYN") || tok_is(k, "VCXN") || tok_is(k, "VCYN") ||
        tok_is(k, "VANN") || tok_is(k, "ZVDX") || tok_is(k, "ZVDY") || tok_is(k, "ZVCX") ||
        tok_is(k, "ZVCY") || tok_is(k, "ZVAN"))
        return vignetting(c, l,
                          k->p[0] == 'Z'     ? -1
                          : tok_is(k, "VDXN") ? 0
                          : tok_is(k, "VDYN") ? 1
                          : tok_is(k, "VCXN") ? 2
                          : tok_is(k, "VCYN") ? 3
                                              : 4,
                          k->p[0] == 'Z' ? "vignetting factor" : k->p[1] == 'D' ? "vignetting decenter"
                          : k->p[1] == 'C' ? "vignetting compression" : "vignetting angle");
    if (tok_is(k, "WAVM")) {
        if ((rc = tok_int(c, l, 1, "wavelength number", 1, ZMX_NWSLOT, &n)) != SG_OK ||
            (rc = tok_num(c, l, 2, "wavelength", &c->wum[n - 1])) != SG_OK ||
            (rc = opt_num(c, l, 3, "wavelength weight", 1.0, &c->wwt[n - 1])) != SG_OK)
            return rc;
        c->whave[n - 1] = 1;
        return SG_OK;
    }
    if (tok_is(k, "WAVL"))
        return read_list(c, l, c->wavl, ZMX_NWSLOT, &c->nwavl);
    if (tok_is(k, "WWGT"))
        return read_list(c, l, c->wwgt, ZMX_NWSLOT, &c->nwwgt);
    if (tok_is(k, "WAVN")) {
        c->wavn_line = c->line;
        return read_list(c, l, c->wavn, ZMX_NWSLOT, &c->nwavn);
    }
    if (tok_is(k, "WWGN")) {
        c->wwgn_line = c->line;
        return read_list(c, l, c->wwgn, ZMX_NWSLOT, &c->nwwgn);
    }
    if (tok_is(k, "PWAV")) {
        c->pwav_line = c->line;
        return tok_int(c, l, 1, "primary wavelength", 1, ZMX_NWSLOT, &c->pwav);
    }
    if (tok_is(k, "MNUM")) {
        if ((rc = tok_int(c, l, 1, "number of configurations", 0, 1 << 20, &n)) != SG_OK)
            return rc;
        if (n > SG_MAX_CONFIGS)
            return zerr(c, SG_ERANGE, "MNUM: %d configurations; sagitta holds %d", n,
                        SG_MAX_CONFIGS);
        if (c->mnum)
            return zerr(c, SG_EPARSE, "MNUM: a second MNUM line (the first is line %ld)",
                        c->mnum_line);
        c->mnum = n < 1 ? 1 : n;
        c->mnum_line = c->line;
        /* With one configuration the rows that follow hold the design's
         * own values; with more, each row is read (config_line). */
        if (n > 1 && !(c->sys->configs = sg_configs_new(n)))
            return zerr(c, SG_ENOMEM, "MNUM: out of memory");
        /* Its second number is the current configuration, the one the
         * surfaces' values are (1 when it is not one of them). */
        if (n > 1 && l->n > 2) {
            int cur;
            if ((rc = tok_int(c, l, 2, "current configuration", 0, 1 << 20, &cur)) != SG_OK)
                return rc;
            c->sys->configs->current = cur >= 1 && cur <= n ? cur : 1;
        }
        return SG_OK;
    }
    if (tok_is(k, "TOL"))
        return tol_line(c, l);
    if (c->mnum > 1 && c->after && k->n == 4 && !tok_is(k, "CSUM"))
        return config_line(c, l);
    if (c->after && !c->mnum && k->n == 4 && merit_line(c, l))
        return SG_OK;
    if (in_list(k, ignored_header, sizeof ignored_header / sizeof *ignored_header))
        return SG_OK;
    /* After the surfaces come the merit function's operands (EFFL, REAY,
     * ...), which describe targets, not the system. */
    if (c->after && k->n == 4)
        return SG_OK;
    tok_show(k, q, sizeof q);
    return zerr(c, SG_EUNSUPPORTED, "unknown keyword '%s'; sagitta cannot tell whether it "
                "changes the trace, so the file is refused", q);
}

/* ------------------------------------------------------------------------
 * Resolving the header at the end
 * ------------------------------------------------------------------------ */

/* The TOL rows read, checked against the design row by row in the
 * file's order: a row the design cannot take (a surface out of range, a
 * flat surface's TRAD) is warned about with its line and left out, the
 * others kept with sagitta's defaults for the rest (criterion, Monte
 * Carlo), which Zemax keeps in its tolerancing dialog, not in the file. */
static int tol_finish(zctx *c)
{
    sg_system *s = c->sys;
    sg_tolerances *all;
    sg_diag md;
    int k, n = 0;
    long cline = c->line;
    if (!s->tol.nop && !s->tol.ncomp) {
        memset(&s->tol, 0, sizeof s->tol);
        return SG_OK;
    }
    if (!(all = malloc(sizeof *all)))
        return zerr(c, SG_ENOMEM, "out of memory");
    *all = s->tol;
    s->tol.present = 1;
    s->tol.pattern = SG_PUPIL_HEXAPOLAR;
    s->tol.density = 6;
    s->tol.grid = 64;
    s->tol.seed = 1.0;
    s->tol.nop = s->tol.ncomp = 0;
    c->cur = -1;
    for (k = 0; k < all->nop + all->ncomp; k++) {
        int op = k < all->nop;
        sg_diag_clear(&md);
        if (op)
            s->tol.op[s->tol.nop++] = all->op[k];
        else
            s->tol.comp[s->tol.ncomp++] = all->comp[k - all->nop];
        if (sg_tol_check(s, &md) == SG_OK) {
            n++;
            continue;
        }
        if (op)
            s->tol.nop--;
        else
            s->tol.ncomp--;
        c->line = op ? c->tol_line[k] : c->comp_line[k - all->nop];
        zwarn(c, "TOL %s: %s; the row is left out", op ? sg_tol_name(all->op[k].type) : "COMP",
              md.msg);
    }
    c->line = cline;
    free(all);
    if (!n)
        memset(&s->tol, 0, sizeof s->tol);
    return SG_OK;
}

static int finish(zctx *c)
{
    sg_system *s = c->sys;
    int nf, nw, i;

    c->cur = -1;
    if ((i = config_finish(c)) != SG_OK)
        return i;
    if (c->push_line) {
        c->line = c->push_line;
        if (s->aim == SG_AIM_OFF)
            return zerr(c, SG_EUNSUPPORTED, "PUSH: pupil shifts without ray aiming; sagitta "
                        "cannot tell how Zemax would use them");
        zwarn(c, "PUSH: note: the pupil shift is ray aiming's first guess and changes no "
              "aimed ray; it is kept for a .zmx save");
    }
    /* Messages about the file as a whole name no line. */
    c->line = 0;
    /* Fields: FTYP's count, else the values given. */
    nf = c->have_ftyp ? c->ftyp_nfield : (c->nyfln > c->nxfln ? c->nyfln : c->nxfln);
    if (nf < 1)
        nf = 1;
    if (nf > SG_MAX_FIELDS) {
        c->line = c->yfln_line;
        return zerr(c, SG_ERANGE, "%d fields; sagitta holds %d", nf, SG_MAX_FIELDS);
    }
    if ((c->nxfln || c->nyfln) && (c->nxfln < nf || c->nyfln < nf)) {
        c->line = c->nxfln < nf ? c->xfln_line : c->yfln_line;
        return zerr(c, SG_EPARSE, "%s: %d values for %d fields", c->nxfln < nf ? "XFLN" : "YFLN",
                    c->nxfln < nf ? c->nxfln : c->nyfln, nf);
    }
    /* The old lists: alone, they give the fields; beside the new ones,
     * each value they hold for a field must be the same. */
    for (i = 0; i < 3; i++) {
        double *nv = i == 0 ? c->xfln : i == 1 ? c->yfln : c->fwgn;
        int *nn = i == 0 ? &c->nxfln : i == 1 ? &c->nyfln : &c->nfwgn, j;
        static const char *const kw[3][2] = { { "XFLD", "XFLN" }, { "YFLD", "YFLN" },
                                               { "FWGT", "FWGN" } };
        if (!c->noldf[i])
            continue;
        if (!*nn) {
            if (c->noldf[i] < nf && i < 2) {
                c->line = c->oldf_line[i];
                return zerr(c, SG_EPARSE, "%s: %d values for %d fields", kw[i][0], c->noldf[i],
                            nf);
            }
            memcpy(nv, c->oldf[i], sizeof c->oldf[i]);
            *nn = c->noldf[i];
            continue;
        }
        for (j = 0; j < nf && j < c->noldf[i] && j < *nn; j++)
            if (c->oldf[i][j] != nv[j]) {
                c->line = c->oldf_line[i];
                return zerr(c, SG_EPARSE, "%s: field %d is %.17g here but %.17g in %s; sagitta "
                            "cannot tell which one Zemax uses", kw[i][0], j + 1, c->oldf[i][j],
                            nv[j], kw[i][1]);
            }
    }
    c->line = 0;
    s->nfield = nf;
    for (i = 0; i < nf; i++) {
        s->field[i].x = c->nxfln ? c->xfln[i] : 0.0;
        s->field[i].y = c->nyfln ? c->yfln[i] : 0.0;
        s->field[i].weight = i < c->nfwgn ? c->fwgn[i] : 1.0;
        s->field[i].vdx = i < c->nvig[0] ? c->vig[0][i] : 0.0;
        s->field[i].vdy = i < c->nvig[1] ? c->vig[1][i] : 0.0;
        s->field[i].vcx = i < c->nvig[2] ? c->vig[2][i] : 0.0;
        s->field[i].vcy = i < c->nvig[3] ? c->vig[3][i] : 0.0;
        s->field[i].van = i < c->nvig[4] ? c->vig[4][i] : 0.0;
        if (!(s->field[i].weight >= 0.0)) {
            return zerr(c, SG_ERANGE, "FWGN: field %d has the negative weight %.17g", i + 1,
                        s->field[i].weight);
        }
    }
    /* Wavelengths: WAVM slots, or the old WAVL and WWGT lists. */
    if (c->nwavl) {
        nw = c->have_ftyp ? c->ftyp_nwave : c->nwavl;
        if (c->nwavl < nw)
            return zerr(c, SG_EPARSE, "WAVL: %d wavelengths for %d", c->nwavl, nw);
        for (i = 0; i < nw; i++) {
            s->wave[i].um = c->wavl[i];
            s->wave[i].weight = i < c->nwwgt ? c->wwgt[i] : 1.0;
        }
    } else {
        nw = c->have_ftyp ? c->ftyp_nwave : 0;
        if (!c->have_ftyp)
            while (nw < ZMX_NWSLOT && c->whave[nw])
                nw++;
        if (nw < 1)
            return zerr(c, SG_EPARSE, "no wavelength (WAVM or WAVL)");
        for (i = 0; i < nw; i++) {
            if (!c->whave[i])
                return zerr(c, SG_EPARSE, "WAVM %d is missing; the file has %d wavelengths", i + 1,
                            nw);
            s->wave[i].um = c->wum[i];
            s->wave[i].weight = c->wwt[i];
        }
    }
    s->nwave = nw;
    /* The slot lists repeat the wavelengths and weights; one that says
     * otherwise leaves sagitta unable to tell which one Zemax uses. */
    for (i = 0; i < nw; i++) {
        if (i < c->nwavn && c->wavn[i] != s->wave[i].um) {
            c->line = c->wavn_line;
            return zerr(c, SG_EPARSE, "WAVN: wavelength %d is %.17g here but %.17g in the "
                        "WAVL or WAVM lines; sagitta cannot tell which one Zemax uses", i + 1,
                        c->wavn[i], s->wave[i].um);
        }
        if (i < c->nwwgn && c->wwgn[i] != s->wave[i].weight) {
            c->line = c->wwgn_line;
            return zerr(c, SG_EPARSE, "WWGN: wavelength %d has the weight %.17g here but "
                        "%.17g in the WWGT or WAVM lines; sagitta cannot tell which one Zemax "
                        "uses", i + 1, c->wwgn[i], s->wave[i].weight);
        }
    }
    c->line = 0;
    for (i = 0; i < nw; i++)
        if (!(s->wave[i].um > 0.0) || !(s->wave[i].weight >= 0.0))
            return zerr(c, SG_ERANGE, "wavelength %d: %.17g um, weight %.17g", i + 1,
                        s->wave[i].um, s->wave[i].weight);
    if (c->pwav > nw) {
        c->line = c->pwav_line;
        return zerr(c, SG_ERANGE, "PWAV: primary wavelength %d of %d", c->pwav, nw);
    }
    s->primary_wave = c->pwav ? c->pwav - 1 : 0;
    if (!c->have_aper)
        return zerr(c, SG_EPARSE, "no system aperture (ENPD, FNUM, OBNA or FLOA)");
    if (s->aper_type != SG_APER_FLOAT_STOP && !(s->aper_value > 0.0)) {
        c->line = c->aper_line;
        return zerr(c, SG_ERANGE, "aperture value %.17g must be positive", s->aper_value);
    }
    if (s->nsurf < 3)
        return zerr(c, SG_ENOSYS, "%d surfaces; a design needs an object, at least one surface "
                    "and an image", s->nsurf);
    if (!c->nstop)
        return zerr(c, SG_ENOSTOP, "no STOP line; sagitta needs the aperture stop marked");
    if (c->stop < 1 || c->stop > s->nsurf - 2) {
        c->line = c->stop_line;
        return zerr(c, SG_ENOSTOP, "the stop is surface %d; it must be one of 1 to %d", c->stop,
                    s->nsurf - 2);
    }
    s->stop = c->stop;
    if (s->surf[s->nsurf - 1].mat.kind != SG_MAT_AIR && s->surf[s->nsurf - 1].mat.kind != SG_MAT_GLASS)
        return zerr(c, SG_ENONPHYS, "the image surface cannot be a mirror");
    if (s->telecentric) {
        /* Zemax's own rules for telecentric object space, at FTYP's line. */
        c->line = c->ftyp_line;
        if (s->aper_type != SG_APER_OBJECT_NA && s->aper_type != SG_APER_OBJECT_CONE)
            return zerr(c, SG_EUNSUPPORTED, "FTYP: telecentric object space with a system "
                        "aperture other than the object NA or cone angle (line %ld); the "
                        "entrance pupil is at infinity", c->aper_line);
        if (!isfinite(s->surf[0].thickness))
            return zerr(c, SG_EUNSUPPORTED, "FTYP: telecentric object space with the object "
                        "at infinity");
        if (s->field_type == SG_FIELD_ANGLE)
            return zerr(c, SG_EUNSUPPORTED, "FTYP: telecentric object space with angle "
                        "fields; its chief rays are parallel to the axis");
    }
    /* The merit function's rows, checked against the design they came
     * with: one it cannot take leaves the whole merit function out (its
     * rows refer to each other), with a warning. */
    if (c->merit_drop) {
        zwarn(c, "merit function: %s from line %ld; sagitta leaves the merit function out",
              c->merit_drop_why, c->merit_drop_line);
        memset(&s->merit, 0, sizeof s->merit);
    } else if (s->merit.present) {
        int any = 0;
        for (i = 0; i < s->merit.nop; i++)
            any |= s->merit.op[i].type != SG_OP_BLNK;
        /* Zemax writes an empty editor as one BLNK row: no merit function. */
        if (!any)
            memset(&s->merit, 0, sizeof s->merit);
    }
    if (s->merit.present) {
        sg_diag md;
        sg_diag_clear(&md);
        if (sg_merit_check(s, &md) != SG_OK) {
            zwarn(c, "%s; sagitta leaves the merit function out", md.msg);
            memset(&s->merit, 0, sizeof s->merit);
        }
    }
    return tol_finish(c);
}

/* Keywords of a SURF block, recognised in files that do not indent them. */
static int is_surface_kw(const ztok *k)
{
    static const char *const kw[] = {
        "TYPE", "CURV", "DISZ", "GLAS", "CONI", "PARM", "XDAT", "DIAM", "STOP", "CLAP",
        "FLAP", "OBDC", "OBSC", "SQAP", "ELAP", "SQOB", "ELOB", "COMM", "SCBD", "SCAD",
        "PZUP", "PKUP", "PPAR", "MAZH", "CHZH", "EDGE", "TCED"};
    return in_list(k, kw, sizeof kw / sizeof *kw) ||
           in_list(k, zero_surface, ZMX_NZERO_KW) ||
           in_list(k, ignored_surface, sizeof ignored_surface / sizeof *ignored_surface);
}

static void mark_line(zctx *c, int sect)
{
    if (c->lsect && c->line >= 1 && c->line <= c->nlsect)
        c->lsect[c->line - 1] = sect;
}

static int parse_text(zctx *c, char *text)
{
    char *p = text, *nl;
    zline *l;
    int rc = SG_OK, seen_next = 0;

    l = malloc(sizeof *l);
    if (!l)
        return sg_diag_set(c->d, SG_ENOMEM, "%s: out of memory", c->name);
    c->line = 0;
    while (p && *p) {
        nl = strchr(p, '\n');
        if (nl)
            *nl = '\0';
        c->line++;
        {
            size_t n = strlen(p);
            if (n && p[n - 1] == '\r')
                p[n - 1] = '\0';
        }
        split(p, l);
        p = nl ? nl + 1 : NULL;
        if (l->n == 0) {
            mark_line(c, c->after ? -2 : c->cur);
            continue;
        }
        if (tok_is(&l->t[0], "SURF")) {
            int n;
            if (c->after) {
                rc = zerr(c, SG_EPARSE, "SURF after the end of the surfaces");
                break;
            }
            if ((rc = end_surface(c)) != SG_OK)
                break;
            c->cur = -1;
            if ((rc = tok_int(c, l, 1, "surface number", 0, SG_MAX_SURFACES - 1, &n)) != SG_OK)
                break;
            if (n != seen_next) {
                rc = zerr(c, SG_EPARSE, "SURF %d where SURF %d comes next (%s)", n, seen_next,
                          n < seen_next ? "a surface written twice" : "a surface is missing");
                break;
            }
            seen_next++;
            if ((rc = grow_to(c, n + 1)) != SG_OK)
                break;
            c->cur = n;
            mark_line(c, n);
            memset(&c->zs, 0, sizeof c->zs);
            c->zs.line = c->line;
            sg_surface_init(&c->sys->surf[n]);
            c->sys->surf[n].thickness = 0.0;
            continue;
        }
        /* An unindented CONF line is the merit function's (Zemax's CONF
         * operand), not the surface keyword. */
        if (c->cur >= 0 && (l->indented || (is_surface_kw(&l->t[0]) &&
                                            !(l->n >= 9 && tok_is(&l->t[0], "CONF"))))) {
            mark_line(c, c->cur);
            if ((rc = surface_line(c, l)) != SG_OK)
                break;
            continue;
        }
        if (c->cur >= 0) {
            if ((rc = end_surface(c)) != SG_OK)
                break;
            c->cur = -1;
            c->after = 1;
        }
        mark_line(c, c->after ? -2 : -1);
        if ((rc = header_line(c, l)) != SG_OK)
            break;
    }
    if (rc == SG_OK && c->cur >= 0)
        rc = end_surface(c);
    free(l);
    if (rc == SG_OK && seen_next == 0)
        return sg_diag_set(c->d, SG_EPARSE, "%s: no SURF line: not a Zemax lens file", c->name);
    if (rc == SG_OK)
        rc = finish(c);
    return rc;
}

typedef struct zbuf {
    char *p;
    size_t len, cap;
    int oom;
} zbuf;

static void zb_add(zbuf *b, const char *s, size_t n)
{
    if (b->oom)
        return;
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        char *q;
        while (cap < b->len + n + 1)
            cap *= 2;
        q = realloc(b->p, cap);
        if (!q) {
            b->oom = 1;
            return;
        }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->len, s, n);
    b->len += n;
    b->p[b->len] = '\0';
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void zb_printf(zbuf *b, const char *fmt, ...)
{
    char tmp[1024];
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    zb_add(b, tmp, (size_t)n < sizeof tmp ? (size_t)n : sizeof tmp - 1);
}

/* ------------------------------------------------------------------------
 * The file a design was read from, for the lossless save
 * ------------------------------------------------------------------------ */

enum { ZENC_UTF8, ZENC_UTF8_BOM, ZENC_LATIN1, ZENC_UTF16LE };

typedef struct zoline {
    size_t off, len, tlen; /* the text, and its line ending's bytes */
    int sect;              /* -1 header, -2 after the surfaces, else the surface */
    int mop;               /* a merit row's operand (from 1), -1 another merit row, 0 */
} zoline;

struct sg_zmx_origin {
    sg_origin_head head; /* first: the model counts and frees it (model.h) */
    char *text; /* the file decoded to UTF-8 */
    int enc;
    int nline;
    zoline *line;
    sg_system *base; /* the design as read, its surfaces' zmx_src 1, 2, ... */
    int nkept;       /* lines whose keyword sagitta does not interpret */
    /* The glass substitutions it was read with, to read a save back. */
    char **pairs;
    sg_zmx_subst sub;
};

static void zmx_origin_free(struct sg_zmx_origin *o)
{
    sg_system_free(o->base);
    while (o->pairs && o->sub.n--)
        free(o->pairs[o->sub.n]);
    free(o->pairs);
    free(o->line);
    free(o->text);
    free(o);
}

int sg_zmx_kept_lines(const sg_system *sys)
{
    return sys && sys->zmx ? sys->zmx->nkept : 0;
}

/* The lines as parse_text splits them: at '\n', a '\r' before it kept
 * with the ending. */
static zoline *split_lines(const char *t, int *n)
{
    const char *p = t;
    zoline *v = NULL;
    int k = 0, cap = 0;
    while (*p) {
        const char *nl = strchr(p, '\n');
        size_t all = nl ? (size_t)(nl - p) + 1 : strlen(p);
        size_t len = nl ? (size_t)(nl - p) : all;
        if (len && p[len - 1] == '\r')
            len--;
        if (k == cap) {
            zoline *q;
            cap = cap ? cap * 2 : 256;
            q = realloc(v, (size_t)cap * sizeof *v);
            if (!q) {
                free(v);
                return NULL;
            }
            v = q;
        }
        v[k].off = (size_t)(p - t);
        v[k].len = len;
        v[k].tlen = all - len;
        v[k].sect = -1;
        v[k].mop = 0;
        k++;
        p += all;
    }
    *n = k;
    return v ? v : calloc(1, sizeof *v);
}

/* A line's key: its keyword, with the number for those that repeat with
 * one (PARM 3, XDAT 5, WAVM 2, SCBD 1); "" for a blank line. */
static void line_key(const char *p, size_t n, char key[48])
{
    static const char *const two[] = {"PARM", "XDAT", "WAVM", "SCBD"};
    size_t i = 0, a, j = 0, k;
    key[0] = '\0';
    while (i < n && (p[i] == ' ' || p[i] == '\t'))
        i++;
    a = i;
    while (i < n && p[i] != ' ' && p[i] != '\t' && j < 20)
        key[j++] = p[i++];
    key[j] = '\0';
    for (k = 0; k < sizeof two / sizeof *two; k++)
        if (i - a == 4 && strcmp(key, two[k]) == 0) {
            while (i < n && (p[i] == ' ' || p[i] == '\t'))
                i++;
            key[j++] = ' ';
            while (i < n && p[i] != ' ' && p[i] != '\t' && j < 40)
                key[j++] = p[i++];
            key[j] = '\0';
        }
}

/* The older forms of the header's lists, read beside the newer ones:
 * each stands for a group of sagitta's own lines. */
static const char *alias_group(const char *key)
{
    if (!strcmp(key, "XFLD"))
        return "XFLN";
    if (!strcmp(key, "YFLD"))
        return "YFLN";
    if (!strcmp(key, "FWGT"))
        return "FWGN";
    if (!strcmp(key, "WAVL") || !strcmp(key, "WWGT") || !strcmp(key, "WAVN") ||
        !strcmp(key, "WWGN"))
        return "WAVM";
    return NULL;
}

/* sagitta's own .zmx text, cut into sections: 0 the header, i + 1 the
 * lines of surface i after its SURF line. */
typedef struct cline {
    const char *p; /* without its indentation */
    size_t n;
    char key[56]; /* line_key, then '#' and the occurrence */
} cline;

typedef struct csec {
    cline *l;
    int n, cap;
} csec;

static void key_occ(char key[56], int occ)
{
    size_t j = strlen(key);
    snprintf(key + j, 56 - j, "#%d", occ);
}

static csec *canon_split(char *t, int *nsec)
{
    csec *sec = calloc((size_t)SG_MAX_SURFACES + 2, sizeof *sec);
    int cur = 0, i;
    char *p = t;
    if (!sec)
        return NULL;
    while (p && *p) {
        char *nl = strchr(p, '\n');
        size_t n = nl ? (size_t)(nl - p) : strlen(p);
        csec *c;
        cline *l;
        if (n > 5 && strncmp(p, "SURF ", 5) == 0) {
            cur = atoi(p + 5) + 1;
            if (cur > SG_MAX_SURFACES + 1)
                cur = SG_MAX_SURFACES + 1;
            if (cur > *nsec)
                *nsec = cur;
            p = nl ? nl + 1 : NULL;
            continue;
        }
        c = &sec[cur];
        if (c->n == c->cap) {
            cline *q;
            c->cap = c->cap ? c->cap * 2 : 16;
            q = realloc(c->l, (size_t)c->cap * sizeof *q);
            if (!q)
                break;
            c->l = q;
        }
        l = &c->l[c->n];
        while (n && *p == ' ')
            p++, n--;
        l->p = p;
        l->n = n;
        line_key(p, n, l->key);
        {
            int occ = 0;
            for (i = 0; i < c->n; i++) {
                char k2[56];
                line_key(c->l[i].p, c->l[i].n, k2);
                occ += strcmp(k2, l->key) == 0;
            }
            key_occ(l->key, occ);
        }
        c->n++;
        p = nl ? nl + 1 : NULL;
    }
    *nsec = *nsec + 1;
    return sec;
}

static void canon_free(csec *sec)
{
    int i;
    if (!sec)
        return;
    for (i = 0; i < SG_MAX_SURFACES + 2; i++)
        free(sec[i].l);
    free(sec);
}

static int canon_find(const csec *c, const char *key)
{
    int i;
    for (i = 0; c && i < c->n; i++)
        if (strcmp(c->l[i].key, key) == 0)
            return i;
    return -1;
}

static int cline_same(const cline *a, const cline *b)
{
    return a->n == b->n && memcmp(a->p, b->p, a->n) == 0;
}

/* Whether the lines of group g (keys starting with it) are the same. */
static int group_same(const csec *b, const csec *c, const char *g)
{
    size_t gn = strlen(g);
    int i = 0, j = 0;
    for (;;) {
        while (i < b->n && strncmp(b->l[i].key, g, gn) != 0)
            i++;
        while (j < c->n && strncmp(c->l[j].key, g, gn) != 0)
            j++;
        if (i == b->n || j == c->n)
            return i == b->n && j == c->n;
        if (!cline_same(&b->l[i], &c->l[j]))
            return 0;
        i++, j++;
    }
}

/* Whether a line after the surfaces may name a surface by number: any
 * but the blank, BLNK, the configuration count (MNUM), the empty
 * configuration operand (MOFF) and the tolerances' header (TOL TOFF). */
static int may_name_surface(const char *p, size_t n)
{
    char key[48];
    line_key(p, n, key);
    if (!key[0] || !strcmp(key, "BLNK") || !strcmp(key, "MNUM") || !strcmp(key, "MOFF"))
        return 0;
    if (!strcmp(key, "TOL")) {
        size_t i = 3;
        while (i < n && (p[i] == ' ' || p[i] == '\t'))
            i++;
        return !(n - i >= 4 && strncmp(p + i, "TOFF", 4) == 0);
    }
    return 1;
}

/* Renumbering a kept line when surfaces were inserted, deleted or moved:
 * Zemax renumbers every field that names a surface.  The one table of
 * those fields: a keyword after the surfaces (merit function rows
 * "OPER Int1 Int2 ...", tolerance rows "TOL OPER Int1 Int2 ...",
 * configuration rows "OPER surface config value ...") and the bits of its
 * tokens (0 the keyword) that are surface numbers; 0 for a row that names
 * none.  From Zemax's Merit Function, Tolerance and Multi-Configuration
 * operand lists; a keyword not here is one whose fields sagitta cannot
 * tell, and a structural save refuses naming it. */
#define ZT(k) (1u << (k))
static const struct {
    const char *key;
    unsigned surf;
} zmx_surf_fields[] = {
    /* Merit rows whose Int1 is a surface. */
    {"CTGT", ZT(1)}, {"CTLT", ZT(1)}, {"CTVA", ZT(1)}, {"ETGT", ZT(1)}, {"ETLT", ZT(1)},
    {"ETVA", ZT(1)}, {"CVGT", ZT(1)}, {"CVLT", ZT(1)}, {"CVVA", ZT(1)}, {"COGT", ZT(1)},
    {"COLT", ZT(1)}, {"COVA", ZT(1)}, {"DMGT", ZT(1)}, {"DMLT", ZT(1)}, {"DMVA", ZT(1)},
    {"REAX", ZT(1)}, {"REAY", ZT(1)}, {"REAZ", ZT(1)}, {"REAR", ZT(1)}, {"REAA", ZT(1)},
    {"REAB", ZT(1)}, {"REAC", ZT(1)}, {"RENA", ZT(1)}, {"RENB", ZT(1)}, {"RENC", ZT(1)},
    {"RANG", ZT(1)}, {"RAID", ZT(1)}, {"RAED", ZT(1)}, {"PARX", ZT(1)}, {"PARY", ZT(1)},
    {"PARZ", ZT(1)}, {"PARR", ZT(1)}, {"PARA", ZT(1)}, {"PARB", ZT(1)}, {"PARC", ZT(1)},
    {"PANA", ZT(1)}, {"PANB", ZT(1)}, {"PANC", ZT(1)}, {"OPTH", ZT(1)}, {"DIST", ZT(1)},
    {"SPHA", ZT(1)}, {"COMA", ZT(1)}, {"ASTI", ZT(1)}, {"FCUR", ZT(1)},
    /* Merit rows whose Int1 and Int2 are a range of surfaces. */
    {"TTHI", ZT(1) | ZT(2)}, {"MNCT", ZT(1) | ZT(2)}, {"MXCT", ZT(1) | ZT(2)},
    {"MNET", ZT(1) | ZT(2)}, {"MXET", ZT(1) | ZT(2)}, {"MNCA", ZT(1) | ZT(2)},
    {"MXCA", ZT(1) | ZT(2)}, {"MNEA", ZT(1) | ZT(2)}, {"MXEA", ZT(1) | ZT(2)},
    {"MNCG", ZT(1) | ZT(2)}, {"MXCG", ZT(1) | ZT(2)}, {"MNEG", ZT(1) | ZT(2)},
    {"MXEG", ZT(1) | ZT(2)}, {"EFLX", ZT(1) | ZT(2)}, {"EFLY", ZT(1) | ZT(2)},
    /* Merit rows that name no surface: first order, rays at the image,
     * image quality, arithmetic (Int1 an operand row), headings. */
    {"BLNK", 0}, {"DMFS", 0}, {"CONF", 0}, {"CONS", 0}, {"EFFL", 0}, {"PMAG", 0},
    {"AMAG", 0}, {"WFNO", 0}, {"ISFN", 0}, {"ISNA", 0}, {"EPDI", 0}, {"EXPP", 0},
    {"ENPP", 0}, {"TOTR", 0}, {"TRAX", 0}, {"TRAY", 0}, {"TRAR", 0}, {"TRAC", 0},
    {"OPDC", 0}, {"OPDX", 0}, {"OPDM", 0}, {"RSCE", 0}, {"RSCH", 0}, {"RSRE", 0},
    {"RSRH", 0}, {"RWCE", 0}, {"RWCH", 0}, {"RWRE", 0}, {"RWRH", 0}, {"DIMX", 0},
    {"FCGS", 0}, {"FCGT", 0}, {"ZERN", 0}, {"AXCL", 0}, {"LACL", 0}, {"SUMM", 0},
    {"DIFF", 0}, {"PROD", 0}, {"DIVI", 0}, {"OPGT", 0}, {"OPLT", 0}, {"ABSO", 0},
    {"SQRT", 0}, {"ACOS", 0}, {"ASIN", 0}, {"ATAN", 0}, {"COSI", 0}, {"SINE", 0},
    {"TANG", 0}, {"ABGT", 0}, {"ABLT", 0}, {"EQUA", 0}, {"MTFT", 0}, {"MTFS", 0},
    {"MTFA", 0}, {"GMTT", 0}, {"GMTS", 0}, {"GMTA", 0}, {"STRH", 0}, {"ANAC", 0},
    {"ANAR", 0}, {"ANAX", 0}, {"ANAY", 0}, {"ANCX", 0}, {"ANCY", 0}, {"LINV", 0},
    {"USYM", 0}, {"CSUM", 0},
    /* Configuration rows: the surface, or (STPS) each value a surface. */
    {"THIC", ZT(1)}, {"CRVT", ZT(1)}, {"CONI", ZT(1)}, {"SDIA", ZT(1)}, {"GLSS", ZT(1)},
    {"PRAM", ZT(1)}, {"APMN", ZT(1)}, {"APMX", ZT(1)}, {"EDVA", ZT(1)}, {"STPS", ZT(3)},
    {"MNUM", 0}, {"MOFF", 0}, {"CWGT", 0}, {"MCOM", 0}, {"LTTL", 0}, {"APER", 0},
    {"TEMP", 0}, {"PRES", 0}, {"XFIE", 0}, {"YFIE", 0}, {"FLWT", 0}, {"WAVE", 0},
    {"WLWT", 0},
    /* Tolerance rows (tokens 2 and 3 are Int1 and Int2). */
    {"TOL TRAD", ZT(2)}, {"TOL TCUR", ZT(2)}, {"TOL TFRN", ZT(2)}, {"TOL TCON", ZT(2)},
    {"TOL TPAR", ZT(2)}, {"TOL TEDV", ZT(2)}, {"TOL TIND", ZT(2)}, {"TOL TABB", ZT(2)},
    {"TOL TSDX", ZT(2)}, {"TOL TSDY", ZT(2)}, {"TOL TSTX", ZT(2)}, {"TOL TSTY", ZT(2)},
    {"TOL TIRR", ZT(2)}, {"TOL TIRX", ZT(2)}, {"TOL TIRY", ZT(2)}, {"TOL TEXI", ZT(2)},
    {"TOL TEZI", ZT(2)}, {"TOL TTHI", ZT(2) | ZT(3)}, {"TOL TEDX", ZT(2) | ZT(3)},
    {"TOL TEDY", ZT(2) | ZT(3)}, {"TOL TETX", ZT(2) | ZT(3)}, {"TOL TETY", ZT(2) | ZT(3)},
    {"TOL TETZ", ZT(2) | ZT(3)}, {"TOL COMP", ZT(2)}, {"TOL TWAV", 0}, {"TOL TOFF", 0},
    {"TCMM", 0},
};

/* The surface fields of a line (its section: a surface's block, or -1 and
 * -2); -1 when they cannot be told. */
static long zmx_fields_of(const char *p, size_t n, int sect, const size_t *to, const size_t *tn,
                          int nt)
{
    char key[16];
    size_t i;
    /* The header's lines name no surface. */
    if (nt == 0 || sect == -1)
        return 0;
    snprintf(key, sizeof key, "%.*s", (int)(tn[0] < 8 ? tn[0] : 8), p + to[0]);
    if (sect >= 0) {
        /* In a surface's block: pickups (CURV c 4 from ..., PZUP from and
         * PKUP from); a parameter pickup's layout is not read. */
        if (!strcmp(key, "CURV"))
            return nt > 3 && tn[2] == 1 && p[to[2]] == '4' ? (long)ZT(3) : 0;
        if (!strcmp(key, "PZUP") || !strcmp(key, "PKUP"))
            return ZT(1);
        return strcmp(key, "PPAR") == 0 ? -1 : 0;
    }
    if (!strcmp(key, "TOL") && nt > 1)
        snprintf(key, sizeof key, "TOL %.*s", (int)(tn[1] < 8 ? tn[1] : 8), p + to[1]);
    for (i = 0; i < sizeof zmx_surf_fields / sizeof *zmx_surf_fields; i++)
        if (!strcmp(zmx_surf_fields[i].key, key))
            return (long)zmx_surf_fields[i].surf;
    return may_name_surface(p, n) ? -1 : 0;
}

/* What a structural save does to the lines it keeps: map[k] is the new
 * number of the file's surface k (-1: deleted); lines it cannot renumber
 * are listed in bad. */
typedef struct zren {
    const int *map;
    int nold;
    int nbad;
    char bad[480];
    int merit_unread; /* the file's merit rows were not read as operands */
} zren;

static void ren_bad(zren *r, const char *p, size_t n, long line, const char *why)
{
    char key[16];
    size_t i = 0, j = 0, len = strlen(r->bad);
    while (i < n && (p[i] == ' ' || p[i] == '\t'))
        i++;
    while (i < n && p[i] != ' ' && p[i] != '\t' && j < 8)
        key[j++] = p[i++];
    key[j] = '\0';
    if (!strcmp(key, "TOL")) {
        while (i < n && (p[i] == ' ' || p[i] == '\t'))
            i++;
        key[j++] = ' ';
        while (i < n && p[i] != ' ' && p[i] != '\t' && j < 13)
            key[j++] = p[i++];
        key[j] = '\0';
    }
    if (r->nbad++ < 8 && len + 80 < sizeof r->bad)
        snprintf(r->bad + len, sizeof r->bad - len, "%s%s (line %ld, %s)", len ? ", " : "", key,
                 line, why);
}

/* Line `line` (from 1) of the file renumbered: NULL when it stays as it
 * is (nothing moves, or it is listed in r->bad), else a malloc'ed copy
 * with only its surface numbers changed. */
static char *ren_line(zren *r, const char *p, size_t n, int sect, long line, size_t *outn)
{
    size_t to[16], tn[16], i = 0, last = 0;
    int nt = 0, k, change = 0;
    long m;
    int newv[16];
    zbuf b = {0};
    if (!r)
        return NULL;
    while (i < n && nt < 16) {
        while (i < n && (p[i] == ' ' || p[i] == '\t'))
            i++;
        if (i == n)
            break;
        to[nt] = i;
        while (i < n && p[i] != ' ' && p[i] != '\t')
            i++;
        tn[nt] = i - to[nt];
        nt++;
    }
    m = zmx_fields_of(p, n, sect, to, tn, nt);
    if (m < 0) {
        ren_bad(r, p, n, line, "its fields' meaning is unknown");
        return NULL;
    }
    for (k = 1; k < nt && k < 16; k++) {
        char buf[40], *end;
        double v;
        newv[k] = -1;
        if (!(m & (long)ZT(k)) || tn[k] >= sizeof buf)
            continue;
        memcpy(buf, p + to[k], tn[k]);
        buf[tn[k]] = '\0';
        v = strtod(buf, &end);
        /* Not a surface of the file (0 sums over all in SPHA ...). */
        if (*end || !(v >= 1 && v < r->nold) || v != floor(v))
            continue;
        if (r->map[(int)v] < 0) {
            ren_bad(r, p, n, line, "it names a deleted surface");
            return NULL;
        }
        if (r->map[(int)v] != (int)v) {
            newv[k] = r->map[(int)v];
            change = 1;
        }
    }
    if (!change)
        return NULL;
    for (k = 1; k < nt; k++) {
        char num[16];
        if (newv[k] < 0)
            continue;
        zb_add(&b, p + last, to[k] - last);
        snprintf(num, sizeof num, "%d", newv[k]);
        /* A right-aligned field keeps its width where it can. */
        if (strlen(num) > tn[k] && b.len && b.p[b.len - 1] == ' ' && to[k] >= 2 &&
            p[to[k] - 2] == ' ')
            b.len--;
        zb_add(&b, num, strlen(num));
        last = to[k] + tn[k];
    }
    zb_add(&b, p + last, n - last);
    if (b.oom) {
        free(b.p);
        ren_bad(r, p, n, line, "out of memory");
        return NULL;
    }
    *outn = b.len;
    return b.p;
}

typedef struct mline {
    const char *pre, *p, *term;
    size_t npre, n, nterm;
    int cidx;  /* the line of sagitta's text it stands for, or -1 */
    char *own; /* p when the line was renumbered (ren_line) */
} mline;

/* One section of the file: its lines (ol, on) as the design was read (B,
 * sagitta's text of it) and now (C).  A line is kept as it is where B and
 * C agree on its key; replaced by C's where they differ; dropped where C
 * has no such line; C's lines the file lacks are added after the line
 * before them in C.  The header's older lists go where their group
 * changed. */
static int merge_sec(zbuf *out, const struct sg_zmx_origin *o, const int *ol, int on,
                     const csec *B, const csec *C, int header, const char *term, size_t nterm,
                     zren *rn)
{
    static const csec none = {NULL, 0, 0};
    mline *m;
    int nm = 0, i, j, *used;
    if (!B)
        B = &none;
    if (!C)
        C = &none;
    m = malloc((size_t)(on + C->n + 1) * sizeof *m);
    used = calloc((size_t)C->n + 1, sizeof *used);
    if (!m || !used) {
        free(m);
        free(used);
        return SG_ENOMEM;
    }
    for (i = 0; i < on; i++) {
        const zoline *z = &o->line[ol[i]];
        const char *p = o->text + z->off;
        char key[56];
        int occ = 0, bi, ci;
        mline e = {"", p, p + z->len, 0, z->len, z->tlen, -1, NULL};
        line_key(p, z->len, key);
        if (!key[0]) {
            m[nm++] = e;
            continue;
        }
        if (header && alias_group(key)) {
            if (group_same(B, C, alias_group(key)))
                m[nm++] = e;
            continue;
        }
        for (j = 0; j < i; j++) {
            char k2[56];
            const zoline *y = &o->line[ol[j]];
            line_key(o->text + y->off, y->len, k2);
            occ += strcmp(k2, key) == 0;
        }
        key_occ(key, occ);
        bi = canon_find(B, key);
        ci = canon_find(C, key);
        if (ci >= 0)
            used[ci] = 1;
        if ((bi < 0 && ci < 0) || (ci >= 0 && bi >= 0 && cline_same(&B->l[bi], &C->l[ci]))) {
            /* The file's own line, its surface numbers renumbered. */
            size_t rn_n = 0;
            e.own = ren_line(rn, p, z->len, z->sect, (long)ol[i] + 1, &rn_n);
            if (e.own) {
                e.p = e.own;
                e.n = rn_n;
            }
            e.cidx = ci;
            m[nm++] = e;
        } else if (ci >= 0) {
            /* The edited line: the file's indentation and line ending. */
            size_t ind = 0;
            while (ind < z->len && (p[ind] == ' ' || p[ind] == '\t'))
                ind++;
            e.pre = p;
            e.npre = ind;
            e.p = C->l[ci].p;
            e.n = C->l[ci].n;
            e.cidx = ci;
            m[nm++] = e;
        }
    }
    for (j = 0; j < C->n; j++) {
        int bi, at = 0, best = -1, k;
        if (used[j])
            continue;
        bi = canon_find(B, C->l[j].key);
        if (bi >= 0 && cline_same(&B->l[bi], &C->l[j]))
            continue;
        for (k = 0; k < nm; k++)
            if (m[k].cidx >= 0 && m[k].cidx < j && m[k].cidx > best) {
                best = m[k].cidx;
                at = k + 1;
            }
        memmove(&m[at + 1], &m[at], (size_t)(nm - at) * sizeof *m);
        m[at].pre = "  ";
        m[at].npre = header ? 0 : 2;
        m[at].p = C->l[j].p;
        m[at].n = C->l[j].n;
        m[at].term = term;
        m[at].nterm = nterm;
        m[at].cidx = j;
        m[at].own = NULL;
        nm++;
    }
    for (i = 0; i < nm; i++) {
        zb_add(out, m[i].pre, m[i].npre);
        zb_add(out, m[i].p, m[i].n);
        zb_add(out, m[i].term, m[i].nterm);
        free(m[i].own);
    }
    free(m);
    free(used);
    return SG_OK;
}

static int write_text(zbuf *b, const sg_system *s, const sg_catalog *cat, int lax, sg_diag *d);

/* Lines whose keyword sagitta's own text of the design never writes
 * (display, tolerances, the merit function ...), the older lists aside:
 * what a JSON design does not keep. */
static int count_kept(const struct sg_zmx_origin *o, const sg_catalog *cat)
{
    zbuf b = {0};
    sg_diag scratch;
    int i, n = 0;
    sg_diag_clear(&scratch);
    /* Lax, with the configurations' lines, which are read. */
    if (write_text(&b, o->base, cat, 2, &scratch) != SG_OK || b.oom) {
        free(b.p);
        return 0;
    }
    for (i = 0; i < o->nline; i++) {
        const zoline *z = &o->line[i];
        char key[48], k2[48];
        const char *p, *q;
        line_key(o->text + z->off, z->len, key);
        if ((q = strchr(key, ' ')) != NULL)
            key[q - key] = '\0';
        if (!key[0] || alias_group(key) || !strcmp(key, "SURF"))
            continue;
        for (p = b.p; p && *p;) {
            q = strchr(p, '\n');
            line_key(p, q ? (size_t)(q - p) : strlen(p), k2);
            if ((q = strchr(k2, ' ')) != NULL)
                k2[q - k2] = '\0';
            if (strcmp(k2, key) == 0)
                break;
            p = strchr(p, '\n');
            p = p ? p + 1 : NULL;
        }
        if (!p || !*p)
            n++;
    }
    free(b.p);
    return n;
}

int sg_zmx_parse(sg_system *sys, const void *bytes, size_t len, const char *name,
                 const sg_catalog *cat, sg_diag *d)
{
    return sg_zmx_parse_subst(sys, bytes, len, name, cat, NULL, d);
}

int sg_zmx_parse_subst(sg_system *sys, const void *bytes, size_t len, const char *name,
                       const sg_catalog *cat, const sg_zmx_subst *sub, sg_diag *d)
{
    zctx *c;
    struct sg_zmx_origin *org = NULL;
    char *text = NULL;
    const char *enc = NULL;
    sg_system *tmp;
    sg_catalog *own = NULL;
    locale_t cloc, old = (locale_t)0;
    int rc, rc2;

    name = name ? name : "(memory)";
    if (!sys || (!bytes && len))
        return sg_diag_set(d, SG_EINVAL, "%s: no system or no text to parse", name);
    if (len > ZMX_MAX_BYTES)
        return sg_diag_set(d, SG_ERANGE, "%s: the file is %zu bytes; the limit is %zu (64 MiB)",
                           name, len, ZMX_MAX_BYTES);
    rc = decode(name, bytes ? bytes : (const void *)"", len, &text, &enc, d);
    if (rc != SG_OK)
        return rc;
    /* The text and its lines, kept for a lossless save. */
    org = calloc(1, sizeof *org);
    if (org) {
        const unsigned char *ub = bytes;
        org->head.refs = 1;
        org->head.free = zmx_origin_free;
        org->enc = strcmp(enc, "UTF-16LE") == 0     ? ZENC_UTF16LE
                   : strcmp(enc, "ISO-8859-1") == 0 ? ZENC_LATIN1
                   : len >= 3 && ub[0] == 0xEF && ub[1] == 0xBB && ub[2] == 0xBF
                       ? ZENC_UTF8_BOM
                       : ZENC_UTF8;
        org->text = strdup(text);
        org->line = org->text ? split_lines(org->text, &org->nline) : NULL;
        if (!org->line) {
            free(org->text);
            free(org);
            free(text);
            return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
        }
    } else {
        free(text);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    }
    if (!cat) {
        /* The default catalog checks the glasses and suggests neighbours;
         * without one, the names are kept for sg_system_validate. */
        sg_diag scratch;
        own = sg_catalog_new();
        sg_diag_clear(&scratch);
        if (own && sg_catalog_load_default(own, &scratch) != SG_OK) {
            sg_catalog_free(own);
            own = NULL;
        }
        cat = own;
    }
    c = calloc(1, sizeof *c);
    tmp = sg_system_new();
    if (!c || !tmp) {
        free(c);
        sg_system_free(tmp);
        sg_catalog_free(own);
        sg_zmx_origin_release(org);
        free(text);
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    }
    c->lsect = malloc(((size_t)org->nline + 1) * sizeof *c->lsect);
    c->lmop = calloc((size_t)org->nline + 1, sizeof *c->lmop);
    c->nlsect = c->lsect && c->lmop ? org->nline : 0;
    /* The header keeps sg_system_new's values until the file sets them;
     * the surfaces are appended as their SURF lines come. */
    tmp->nsurf = 0;
    c->name = name;
    c->d = d;
    c->cat = cat;
    c->sub = sub;
    c->sys = tmp;
    c->cur = -1;
    cloc = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (cloc)
        old = uselocale(cloc);
    rc = parse_text(c, text);
    if (cloc) {
        uselocale(old);
        freelocale(cloc);
    }
    if (rc == SG_OK && c->nlive)
        sg_diag_warn(d, "%s: note: %d solve or pickup line%s kept; sagitta recomputes %s from "
                     "the design (sagitta-design(5), Solves and pickups)", name, c->nlive,
                     c->nlive == 1 ? "" : "s", c->nlive == 1 ? "it" : "them");
    if (rc == SG_OK) {
        int w;
        for (w = 0; w < ZMX_NZERO_KW; w++)
            if (c->nzero_kw[w])
                sg_diag_warn(d, "%s: note: %d %s line%s, all zero, kept as they are (they are "
                             "written back on a .zmx save; sagitta-design(5), ZEMAX FILES)",
                             name, c->nzero_kw[w], zero_surface[w],
                             c->nzero_kw[w] == 1 ? "" : "s");
    }
    if (rc == SG_OK && tmp->configs && cat) {
        /* Each configuration must be a design sagitta can trace; the base
         * design's own faults are reported where it is loaded. */
        sg_diag e;
        sg_diag_clear(&e);
        if (sg_system_validate(tmp, cat, &e) == SG_OK &&
            (rc = sg_configs_check(tmp, cat, &e)) != SG_OK)
            sg_diag_set(d, rc, "%s: %s", name, e.msg);
    }
    if (rc == SG_OK && c->nfrozen)
        sg_diag_warn(d, "%s: %d solve%s and pickup%s frozen at the values the file stores; "
                     "sagitta does not evaluate them", name, c->nfrozen,
                     c->nfrozen == 1 ? "" : "s", c->nfrozen == 1 ? "" : "s");
    if (rc == SG_OK && c->lsect && sub && sub->n > 0) {
        int i;
        org->pairs = calloc((size_t)sub->n, sizeof *org->pairs);
        for (i = 0; org->pairs && i < sub->n; i++)
            if (!(org->pairs[i] = strdup(sub->pairs[i])))
                break;
        org->sub.n = i;
        org->sub.pairs = (const char *const *)org->pairs;
        if (!org->pairs || i < sub->n)
            rc = sg_diag_set(d, SG_ENOMEM, "%s: out of memory", name);
    }
    if (sub)
        org->sub.nearest = sub->nearest;
    if (rc == SG_OK && c->lsect && c->lmop) {
        /* Each surface knows its block in the file; the design as read is
         * what a save compares with to find the lines an edit changed. */
        int i;
        for (i = 0; i < tmp->nsurf; i++)
            tmp->surf[i].zmx_src = i + 1;
        for (i = 0; i < org->nline; i++)
            org->line[i].sect = c->lsect[i], org->line[i].mop = c->lmop[i];
        org->base = sg_system_clone(tmp);
        if (org->base) {
            org->nkept = count_kept(org, cat);
            tmp->zmx = org;
            org = NULL;
        }
    }
    if (rc == SG_OK) {
        rc = sg_system_assign(sys, tmp);
        if (rc != SG_OK)
            sg_diag_set(d, rc, "%s: cannot store the design: %s", name, sg_strerror(rc));
    }
    sg_zmx_origin_release(org);
    for (rc2 = 0; rc2 < SG_MAX_CONFIG_OPS; rc2++)
        free(c->mfill[rc2]);
    free(c->lsect);
    free(c->lmop);
    sg_system_free(tmp);
    sg_catalog_free(own);
    free(c);
    free(text);
    return rc;
}

/* ------------------------------------------------------------------------
 * Writing
 * ------------------------------------------------------------------------ */

/* The shortest of %.15g to %.17g that strtod reads back to x. */
static const char *num(char out[40], double x)
{
    int prec;
    for (prec = 15; prec <= 17; prec++) {
        snprintf(out, 40, "%.*g", prec, x);
        if (strtod(out, NULL) == x)
            break;
    }
    return out;
}

/* A text on one line: control characters become spaces. */
static void zb_text(zbuf *b, const char *s, int *changed)
{
    for (; *s; s++) {
        unsigned char ch = (unsigned char)*s;
        if (ch < 0x20 || ch == 0x7F) {
            *changed = 1;
            ch = ' ';
        }
        zb_add(b, (const char *)&ch, 1);
    }
}

static void zb_list(zbuf *b, const char *kw, const sg_system *s, int what)
{
    char n[40];
    int i;
    zb_add(b, kw, strlen(kw));
    for (i = 0; i < s->nfield; i++)
    {
        const sg_field *f = &s->field[i];
        const double v[8] = {f->x, f->y, f->weight, f->vdx, f->vdy, f->vcx, f->vcy, f->van};
        zb_printf(b, " %s", num(n, v[what]));
    }
    zb_add(b, "\n", 1);
}
/* A shape's PARM and XDAT lines, as zmx_shape reads them. */
/* The solve fields after a CURV value, as the .zmx reader keeps them: a
 * curvature pickup; a radius pickup of offset 0 and a power-of-two scale
 * (Zemax's scale is the curvature's, 1 / ours, and gives the same bits);
 * the marginal ray angle or the F number; else nothing, the value
 * frozen. */
static const char *zb_curv_solve(char out[128], const sg_surface *f)
{
    const sg_solve *v = &f->solve[SG_SOLVE_RADIUS];
    char n1[40], n2[40];
    out[0] = '\0';
    if (v->kind == SG_SOLVE_PICKUP && v->offset == 0.0 && curv_scale_ok(v->scale))
        snprintf(out, 128, " 4 %d %s 0 \"\"", v->from, num(n1, 1.0 / v->scale));
    else if (v->kind == SG_SOLVE_CURV_PICKUP)
        snprintf(out, 128, " 4 %d %s %s \"\"", v->from, num(n1, v->scale), num(n2, v->offset));
    else if (v->kind == SG_SOLVE_MARGINAL_ANGLE || v->kind == SG_SOLVE_FNUM)
        snprintf(out, 128, " %d %s 0 0 \"\"", v->kind == SG_SOLVE_FNUM ? 11 : 2,
                 num(n1, v->value));
    return out;
}

/* Whether the export keeps a solve (the others are written as values). */
static int zmx_keeps(const sg_surface *f, int t)
{
    const sg_solve *v = &f->solve[t];
    switch (t) {
    case SG_SOLVE_RADIUS:
        return (v->kind == SG_SOLVE_PICKUP && v->offset == 0.0 && curv_scale_ok(v->scale)) ||
               v->kind == SG_SOLVE_CURV_PICKUP || v->kind == SG_SOLVE_MARGINAL_ANGLE ||
               v->kind == SG_SOLVE_FNUM;
    case SG_SOLVE_THICKNESS:
        return v->kind == SG_SOLVE_PICKUP || v->kind == SG_SOLVE_MARGINAL_HEIGHT ||
               v->kind == SG_SOLVE_CHIEF_HEIGHT;
    case SG_SOLVE_CONIC:
        return v->kind == SG_SOLVE_PICKUP;
    default:
        return 0;
    }
}

/* The thickness solve's line after DISZ: MAZH height 0 (the paraxial
 * marginal ray), CHZH height 0 (the paraxial chief ray) or PZUP from
 * scale offset 0 (a thickness). */
static void zb_disz_solve(zbuf *b, const sg_surface *f)
{
    const sg_solve *v = &f->solve[SG_SOLVE_THICKNESS];
    char n1[40], n2[40];
    if (v->kind == SG_SOLVE_MARGINAL_HEIGHT)
        zb_printf(b, "  MAZH %s 0\n", num(n1, v->value));
    else if (v->kind == SG_SOLVE_PICKUP)
        zb_printf(b, "  PZUP %d %s %s 0\n", v->from, num(n1, v->scale), num(n2, v->offset));
    else if (v->kind == SG_SOLVE_CHIEF_HEIGHT)
        zb_printf(b, "  CHZH %s 0\n", num(n1, v->value));
}

static void zb_shape(zbuf *b, const sg_surface *f)
{
    const sg_shape_type *t = sg_shape_type_of(f->type);
    const sg_zmx_map *m, *g;
    char n1[40];
    int k, n = 0;
    if (!t || !t->zmx)
        return;
    if (t->extrapolate)
        /* Extrapolate set: the terms apply at every radius, as sagitta's. */
        zb_add(b, "  PARM 0 1\n", 11);
    for (m = t->zmx; m->key; m++) {
        if ((m->flags & SG_ZMX_IF_SET) && (m == t->zmx || !(m[-1].flags & SG_ZMX_IF_SET))) {
            /* A group of such runs is written when one of them is set. */
            int set = 0;
            for (g = m; g->key && (g->flags & SG_ZMX_IF_SET) && !set; g++)
                for (k = 0; k < g->n; k++)
                    set |= *zmx_value((sg_surface *)f, g->key, g->elem + k) != 0.0;
            if (!set) {
                while (m[1].key && (m[1].flags & SG_ZMX_IF_SET))
                    m++;
                continue;
            }
        }
        for (k = 0; k < m->n; k++) {
            double v = *zmx_value((sg_surface *)f, m->key, m->elem + k);
            if ((m->flags & SG_ZMX_ZERO_INF) && isinf(v))
                v = 0.0;
            zb_printf(b, "  %s %d %s\n", m->xdat ? "XDAT" : "PARM", m->index + k, num(n1, v));
        }
    }
    if (t->zmx_terms) {
        for (k = 0; k < SG_NTERMS; k++)
            if (f->terms[k] != 0.0)
                n = k + 1;
        zb_printf(b, "  XDAT 1 %d 0 0 0 0 0 0\n", n);
        zb_printf(b, "  XDAT 2 %s 0 0 0 0 0 0\n", num(n1, f->norm_radius));
        for (k = 0; k < n; k++)
            zb_printf(b, "  XDAT %d %s 0 0 0 0 0 0\n", k + 3, num(n1, f->terms[k]));
    }
}


/* The GCAT line's catalogs: each glass's catalog, in the order of first
 * use, except that Zemax takes a name from the first listed catalog that
 * holds it, so a glass's catalog must precede every other listed catalog
 * with a glass of that name.  A design whose glasses no order satisfies
 * (HOYA's F2 beside SCHOTT's F5: both catalogs have both names) cannot be
 * a .zmx file. */
static int gcat_order(const sg_system *s, const sg_catalog *cat,
                      char gcat[ZMX_MAX_GCAT][SG_GLASS_NAME], int *ngcat, sg_diag *d)
{
    char used[ZMX_MAX_GCAT][SG_GLASS_NAME];
    int nused = 0, placed[ZMX_MAX_GCAT] = {0}, i, j, k, n = 0;
    for (i = 0; i < s->nsurf; i++) {
        const sg_material *m = &s->surf[i].mat;
        const sg_glass *g = cat ? sg_material_glass(cat, m) : NULL;
        const char *c = g ? g->catalog : m->catalog;
        if (m->kind != SG_MAT_GLASS || !c[0])
            continue;
        for (j = 0; j < nused && strcmp(used[j], c) != 0; j++)
            ;
        if (j < nused)
            continue;
        if (nused == ZMX_MAX_GCAT)
            return sg_diag_set(d, SG_ERANGE, "export: surface %d: glasses from more than %d "
                               "catalogs", i, ZMX_MAX_GCAT);
        sg_strlcpy(used[nused++], c, SG_GLASS_NAME);
    }
    /* Place, each time, the first catalog in use order that no unplaced
     * catalog must precede. */
    while (n < nused) {
        int pick = -1, why = -1;
        for (j = 0; j < nused && pick < 0; j++) {
            int blocked = 0;
            if (placed[j])
                continue;
            for (i = 0; i < s->nsurf && !blocked && cat; i++) {
                const sg_glass *g = sg_material_glass(cat, &s->surf[i].mat);
                if (!g || strcmp(g->catalog, used[j]) == 0)
                    continue;
                for (k = 0; k < nused; k++)
                    if (!placed[k] && strcmp(g->catalog, used[k]) == 0)
                        break;
                /* Surface i's glass comes from unplaced catalog k, and
                 * catalog j also has a glass of its name. */
                if (k < nused && sg_catalog_find_in(cat, used[j], g->name)) {
                    blocked = 1;
                    why = i;
                }
            }
            if (!blocked)
                pick = j;
        }
        if (pick < 0) {
            const sg_material *m = &s->surf[why].mat;
            return sg_diag_set(d, SG_EUNSUPPORTED, "export: surface %d: glass %s of catalog %s: "
                               "no order of the GCAT line gives every surface its catalog's "
                               "glass (Zemax takes a name from the first catalog listed that "
                               "has it); use glasses of other names", why, m->name,
                               sg_material_glass(cat, m)->catalog);
        }
        placed[pick] = 1;
        sg_strlcpy(gcat[n++], used[pick], SG_GLASS_NAME);
    }
    *ngcat = n;
    return SG_OK;
}

/* lax: the text of any design, with no refusal, for the lossless save's
 * comparisons only. */
static int write_text(zbuf *b, const sg_system *s, const sg_catalog *cat, int lax, sg_diag *d)
{
    char n1[40], n2[40], cs[128], gcat[ZMX_MAX_GCAT][SG_GLASS_NAME];
    int ngcat = 0, i, k, changed = 0;
    mpfr_t q;

    if (s->nsurf < 3 || s->stop < 1 || s->stop > s->nsurf - 2)
        return sg_diag_set(d, SG_ENOSYS, "export: the design needs an object, a stop surface "
                           "and an image");
    if (s->nwave < 1 || s->nwave > SG_MAX_WAVES || s->nfield < 1 || s->nfield > SG_MAX_FIELDS ||
        s->primary_wave < 0 || s->primary_wave >= s->nwave)
        return sg_diag_set(d, SG_ERANGE, "export: wavelengths or fields out of range");

    for (i = 0; i < s->nsurf && !lax; i++) {
        const sg_surface *f = &s->surf[i];
        if (f->aperture != SG_APERTURE_NONE && f->sd_fixed)
            return sg_diag_set(d, SG_EUNSUPPORTED, "export: surface %d: a fixed semi-diameter "
                               "and a surface aperture; a .zmx surface holds one aperture (make "
                               "the semi-diameter free, or put the aperture on a dummy surface)",
                               i);
        if (f->radius != 0.0 && !isfinite(1.0 / f->radius))
            return sg_diag_set(d, SG_ERANGE, "export: surface %d: radius %g is so small that "
                               "its curvature, which a .zmx file holds, is beyond the doubles",
                               i, f->radius);
        if (isnan(f->radius) || isnan(f->thickness) || !isfinite(f->conic) ||
            (!isfinite(f->thickness) && !(i == 0 && f->thickness > 0)))
            return sg_diag_set(d, SG_ERANGE, "export: surface %d: a value a .zmx file cannot "
                               "hold (thickness %g, radius %g, conic %g)", i, f->thickness,
                               f->radius, f->conic);
        /* A tilt or decenter before or after a surface goes out as Zemax's
         * SCBD lines (side 1 and 2), which the reader checks. */
        if (f->type != SG_SURF_COORDBRK &&
            ((i < 1 && !sg_frame_change_is_zero(&f->before)) ||
             (i == 0 && f->after_mode == SG_AFTER_EXPLICIT &&
              !sg_frame_change_is_zero(&f->after))))
            return sg_diag_set(d, SG_EUNSUPPORTED, "export: surface %d: a tilt or decenter "
                               "around the object, which sagitta's .zmx reader does not take "
                               "(its rays start on the object's axis)", i);
        /* A shape whose record has no .zmx map (sagitta does not know
         * Zemax's layout of it) cannot be written. */
        if (sg_shape_ops_of(f->type) && !sg_shape_type_of(f->type)->zmx)
            return sg_diag_set(d, SG_EUNSUPPORTED, "export: surface %d: sagitta does not know "
                               "how a .zmx file holds a %s surface; keep the design as JSON",
                               i, sg_shape_type_of(f->type)->name);
        if (f->type == SG_SURF_EVENASPH)
            for (k = 0; k < SG_NASPH; k++)
                if (!isfinite(f->asph[k]))
                    return sg_diag_set(d, SG_ERANGE, "export: surface %d: asphere term r^%d is "
                                       "not finite", i, 2 * k + 2);
    }
    if ((k = gcat_order(s, cat, gcat, &ngcat, d)) != SG_OK && !lax)
        return k;
    /* No VERS line: Zemax reads a file without one, and a made-up version
     * number could select an old reading of the keywords. */
    zb_add(b, "MODE SEQ\nNAME ", 14);
    zb_text(b, s->title, &changed);
    zb_printf(b, "\nUNIT %s X W X CM MR CPMM\n",
              strcmp(s->units, "cm") == 0 ? "CM" : strcmp(s->units, "in") == 0 ? "IN"
              : strcmp(s->units, "m") == 0 ? "METER" : "MM");
    switch (s->aper_type) {
    case SG_APER_EPD:
        zb_printf(b, "ENPD %s\n", num(n1, s->aper_value));
        break;
    case SG_APER_IMAGE_FNUM:
        zb_printf(b, "FNUM %s 0\n", num(n1, s->aper_value));
        break;
    case SG_APER_PARAX_WORKING_FNUM:
        zb_printf(b, "FNUM %s 1\n", num(n1, s->aper_value));
        break;
    case SG_APER_OBJECT_NA:
        zb_printf(b, "OBNA %s 0\n", num(n1, s->aper_value));
        break;
    case SG_APER_OBJECT_CONE:
        zb_printf(b, "OBNA %s 1\n", num(n1, s->aper_value));
        break;
    default:
        zb_add(b, "FLOA\n", 5);
        break;
    }
    zb_printf(b, "ENVD %s %s %d\n", num(n1, s->temperature), num(n2, s->pressure),
              s->adjust_index ? 1 : 0);
    if (ngcat) {
        zb_add(b, "GCAT", 4);
        for (i = 0; i < ngcat; i++)
            zb_printf(b, " %s", gcat[i]);
        zb_add(b, "\n", 1);
    }
    zb_printf(b, "RAIM 0 %d 1 1 0 0 0 0 0\n", s->aim == SG_AIM_REAL ? 2 : s->aim == SG_AIM_PARAXIAL ? 1 : 0);
    zb_printf(b, "FTYP %d %d %d %d %d 0 %d\n", (int)s->field_type, s->telecentric ? 1 : 0,
              s->nfield, s->nwave,
              s->field_norm == SG_NORM_RECT ? 1 : 0, s->afocal ? 1 : 0);
    zb_list(b, "XFLN", s, 0);
    zb_list(b, "YFLN", s, 1);
    zb_list(b, "FWGN", s, 2);
    /* Vignetting factors only when some field has one, as Zemax's files
     * list them in any case. */
    for (i = 0; i < s->nfield; i++)
        if (s->field[i].vdx != 0.0 || s->field[i].vdy != 0.0 || s->field[i].vcx != 0.0 ||
            s->field[i].vcy != 0.0 || s->field[i].van != 0.0)
            break;
    if (i < s->nfield) {
        zb_list(b, "VDXN", s, 3);
        zb_list(b, "VDYN", s, 4);
        zb_list(b, "VCXN", s, 5);
        zb_list(b, "VCYN", s, 6);
        zb_list(b, "VANN", s, 7);
    }
    for (i = 0; i < s->nwave; i++)
        zb_printf(b, "WAVM %d %s %s\n", i + 1, num(n1, s->wave[i].um), num(n2, s->wave[i].weight));
    zb_printf(b, "PWAV %d\n", s->primary_wave + 1);
    mpfr_init2(q, 128);
    for (i = 0; i < s->nsurf; i++) {
        const sg_surface *f = &s->surf[i];
        /* The .zmx keyword of each type is the name the editor shows. */
        zb_printf(b, "SURF %d\n  TYPE %s\n", i,
                  sg_param_find(SG_SCOPE_SURFACE, "type")->shown[f->type]);
        if (f->comment[0]) {
            zb_add(b, "  COMM ", 7);
            zb_text(b, f->comment, &changed);
            zb_add(b, "\n", 1);
        }
        if (i == s->stop)
            zb_add(b, "  STOP\n", 7);
        if (f->radius == 0.0 || isinf(f->radius)) {
            zb_printf(b, "  CURV 0%s\n", zb_curv_solve(cs, f));
        } else {
            /* 1/R to 25 digits: its exact reciprocal rounds back to R. */
            char cv[64];
            mpfr_set_d(q, f->radius, MPFR_RNDN);
            mpfr_ui_div(q, 1, q, MPFR_RNDN);
            mpfr_snprintf(cv, sizeof cv, "%.24Re", q);
            zb_printf(b, "  CURV %s%s\n", cv, zb_curv_solve(cs, f));
        }
        if (f->type == SG_SURF_EVENASPH)
            for (k = 0; k < SG_NASPH; k++)
                zb_printf(b, "  PARM %d %s\n", k + 1, num(n1, f->asph[k]));
        if (f->type == SG_SURF_COORDBRK) {
            const double v[6] = {f->before.dx, f->before.dy, f->before.tx, f->before.ty,
                                 f->before.tz, f->before.order ? 1.0 : 0.0};
            for (k = 0; k < 6; k++)
                zb_printf(b, "  PARM %d %s\n", k + 1, num(n1, v[k]));
        }
        if (f->type != SG_SURF_COORDBRK && !sg_frame_change_is_zero(&f->before)) {
            char n3[40], n4[40], n5[40];
            zb_printf(b, "  SCBD 1 %d 0 %s %s %s %s %s\n", f->before.order ? 1 : 0,
                      num(n1, f->before.dx), num(n2, f->before.dy), num(n3, f->before.tx),
                      num(n4, f->before.ty), num(n5, f->before.tz));
        }
        if (f->type != SG_SURF_COORDBRK &&
            (f->after_mode == SG_AFTER_REVERSE
                 ? !sg_frame_change_is_zero(&f->before)
                 : !sg_frame_change_is_zero(&f->after))) {
            /* Reverse is written as Zemax does: the before change's values
             * negated, in the other order, mode 2. */
            char n3[40], n4[40], n5[40];
            int rev = f->after_mode == SG_AFTER_REVERSE;
            const sg_frame_change *a = rev ? &f->before : &f->after;
            double sg = rev ? -1.0 : 1.0;
            zb_printf(b, "  SCBD 2 %d %d %s %s %s %s %s\n", rev ? !a->order : a->order ? 1 : 0,
                      rev ? 2 : 0, num(n1, sg * a->dx), num(n2, sg * a->dy),
                      num(n3, sg * a->tx), num(n4, sg * a->ty), num(n5, sg * a->tz));
        }
        zb_shape(b, f);
        if (isinf(f->thickness))
            zb_add(b, "  DISZ INFINITY\n", 16);
        else
            zb_printf(b, "  DISZ %s\n", num(n1, f->thickness));
        zb_disz_solve(b, f);
        switch (f->mat.kind) {
        case SG_MAT_MIRROR:
            zb_add(b, "  GLAS MIRROR 0 0 1.5 40 0 0 0 0 0 0\n", 37);
            break;
        case SG_MAT_GLASS: {
            const sg_glass *g = cat ? sg_material_glass(cat, &f->mat) : NULL;
            zb_printf(b, "  GLAS %s 0 0 %s %s 0 0 0 0 0 0\n", f->mat.name,
                      num(n1, g ? g->nd : 0.0), num(n2, g ? g->vd : 0.0));
            break;
        }
        case SG_MAT_INDEX:
            /* A model glass without dispersion. */
            zb_printf(b, "  GLAS ___BLANK 1 0 %s 0 0 0 0 0 0 0\n", num(n1, f->mat.index));
            break;
        case SG_MAT_MODEL: {
            char n3[40];
            zb_printf(b, "  GLAS ___BLANK 1 0 %s %s %s 0 0 0 0 0\n", num(n1, f->mat.index),
                      num(n2, f->mat.vd), num(n3, f->mat.dpgf));
            break;
        }
        default:
            break;
        }
        zb_printf(b, "  CONI %s\n", num(n1, f->conic));
        if (f->solve[SG_SOLVE_CONIC].kind == SG_SOLVE_PICKUP) {
            const sg_solve *v = &f->solve[SG_SOLVE_CONIC];
            zb_printf(b, "  PKUP %d %s %s 0\n", v->from, num(n1, v->scale), num(n2, v->offset));
        }
        if (f->tce != 0.0)
            zb_printf(b, "  TCED %s 0 0\n", num(n1, f->tce));
        zb_printf(b, "  DIAM %s %d 0 0 1 \"\"\n", num(n1, f->semi_diameter), f->sd_fixed ? 1 : 0);
        if (f->sd_fixed)
            zb_printf(b, "  CLAP 0 %s 0\n", num(n1, f->semi_diameter));
        if (f->aperture != SG_APERTURE_NONE) {
            /* Zemax's lines: CLAP and OBSC take the radii, the others the
             * half widths; OBDC the decenter. */
            static const char *const kw[] = {"", "CLAP", "OBSC", "SQAP", "SQOB", "ELAP", "ELOB"};
            int circ = f->aperture == SG_APERTURE_CIRCULAR ||
                       f->aperture == SG_OBSCURATION_CIRCULAR;
            zb_printf(b, "  %s %s %s 0\n", kw[f->aperture],
                      num(n1, circ ? f->ap_rmin : f->ap_xhalf),
                      num(n2, circ ? f->ap_rmax : f->ap_yhalf));
            if (f->ap_xdec != 0.0 || f->ap_ydec != 0.0)
                zb_printf(b, "  OBDC %s %s\n", num(n1, f->ap_xdec), num(n2, f->ap_ydec));
        }
    }
    mpfr_clear(q);
    /* The merit function, as Zemax's editor rows "TYPE int1 int2 data1 ..
     * data4 target weight data5 data6": not in the merged save (lax 1),
     * which keeps the file's own lines. */
    if (s->merit.present && lax != 1) {
        char n3[40], n4[40], n5[40], n6[40];
        for (i = 0; i < s->merit.nop; i++) {
            const sg_operand *o = &s->merit.op[i];
            if (o->type == SG_OP_BLNK) {
                zb_printf(b, "BLNK\n");
                continue;
            }
            num(n1, o->hx);
            num(n2, o->hy);
            num(n3, o->px);
            num(n4, o->py);
            num(n5, o->target);
            num(n6, o->weight);
            zb_printf(b, "%s %d %d %s %s %s %s %s %s 0 0\n", sg_op_name(o->type), o->i1, o->i2,
                      n1, n2, n3, n4, n5, n6);
        }
    }
    /* The configurations, as Zemax's editor rows: not in the merged save
     * (lax 1), which keeps the file's own lines. */
    if (s->configs && lax != 1) {
        const sg_configs *cf = s->configs;
        zb_printf(b, "MNUM %d %d\n", cf->n, cf->current);
        for (i = 0; i < cf->nop; i++) {
            const sg_config_op *o = &cf->op[i];
            for (k = 0; k < cf->n; k++) {
                if (o->mat) {
                    const sg_material *m = &o->mat[k];
                    const char *g = m->kind == SG_MAT_GLASS    ? m->name
                                    : m->kind == SG_MAT_MIRROR ? "MIRROR"
                                    : m->kind == SG_MAT_AIR    ? ""
                                                               : NULL;
                    if (!g)
                        return sg_diag_set(d, SG_EUNSUPPORTED, "export: configuration %d: GLSS "
                                           "of surface %d is a fixed index or model glass, "
                                           "which a .zmx GLSS row cannot hold", k + 1, o->num);
                    zb_printf(b, "GLSS %d %d \"%s\" 0 0 0 %d %d 0 0.0 \"\"\n", o->num, k + 1, g,
                              k + 1, i + 1);
                } else {
                    zb_printf(b, "%s %d %d %s 0 %d 0 %d %d 1 0 0\n", o->type, o->num, k + 1,
                              num(n1, o->value[k]), o->num2, k + 1, i + 1);
                }
            }
        }
    }
    if (changed)
        sg_diag_warn(d, "export: control characters in the title or a comment became spaces");
    for (i = 0; i < s->nsurf; i++)
        for (k = 0; k < SG_SOLVE_NTARGETS; k++)
            if (s->surf[i].solve[k].kind != SG_SOLVE_NONE && !zmx_keeps(&s->surf[i], k))
                sg_diag_warn(d, "export: surface %d: the %s %s solve is written as its value; "
                             "sagitta writes .zmx solves for marginal_height and chief_height "
                             "thicknesses, "
                             "marginal_angle and fnum radii, curvature pickups, and pickups of a "
                             "thickness or (offset 0, a power-of-two scale) a radius", i,
                             sg_solve_target_name((sg_solve_target)k),
                             sg_solve_kind_name(s->surf[i].solve[k].kind));
    if (b->oom)
        return sg_diag_set(d, SG_ENOMEM, "export: out of memory");
    return SG_OK;
}

/* The design as sagitta's own .zmx text in *out (malloc'ed); the failure's
 * code, so a caller without a diagnostic still learns it. */
static int zmx_text(const sg_system *sys, const sg_catalog *cat, char **out, sg_diag *d)
{
    zbuf b = {0};
    locale_t cloc, old = (locale_t)0;
    int rc;
    *out = NULL;
    if (!sys)
        return sg_diag_set(d, SG_EINVAL, "export: no system");
    cloc = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (cloc)
        old = uselocale(cloc);
    rc = write_text(&b, sys, cat, 0, d);
    if (cloc) {
        uselocale(old);
        freelocale(cloc);
    }
    if (rc == SG_OK && (b.oom || !b.p))
        rc = sg_diag_set(d, SG_ENOMEM, "export: out of memory");
    if (rc != SG_OK) {
        free(b.p);
        return rc;
    }
    *out = b.p;
    return SG_OK;
}

char *sg_zmx_to_text(const sg_system *sys, const sg_catalog *cat, sg_diag *d)
{
    char *t;
    return zmx_text(sys, cat, &t, d) == SG_OK ? t : NULL;
}

/* UTF-8 text back into the file's encoding; a character ISO-8859-1 lacks
 * is SG_ELOSSY naming its line. */
static int encode(const char *t, size_t n, int enc, zbuf *out, char *why, size_t nwhy)
{
    size_t i = 0;
    long ln = 1;
    if (enc == ZENC_UTF8_BOM)
        zb_add(out, "\xEF\xBB\xBF", 3);
    if (enc == ZENC_UTF16LE)
        zb_add(out, "\xFF\xFE", 2);
    if (enc == ZENC_UTF8 || enc == ZENC_UTF8_BOM) {
        zb_add(out, t, n);
        return SG_OK;
    }
    while (i < n) {
        const unsigned char *u = (const unsigned char *)t + i;
        size_t k = utf8_len(u, n - i);
        unsigned cp;
        if (!k)
            k = 1;
        cp = k == 1 ? u[0] : k == 2 ? (u[0] & 0x1Fu) << 6 | (u[1] & 0x3Fu)
             : k == 3 ? (u[0] & 0x0Fu) << 12 | (u[1] & 0x3Fu) << 6 | (u[2] & 0x3Fu)
                      : (u[0] & 0x07u) << 18 | (u[1] & 0x3Fu) << 12 | (u[2] & 0x3Fu) << 6 |
                            (u[3] & 0x3Fu);
        if (cp == '\n')
            ln++;
        if (enc == ZENC_LATIN1) {
            char ch = (char)cp;
            if (cp > 0xFF) {
                snprintf(why, nwhy, "line %ld holds the character U+%04X, which the file's "
                         "encoding (ISO-8859-1) cannot hold", ln, cp);
                return SG_ELOSSY;
            }
            zb_add(out, &ch, 1);
        } else {
            char w[4];
            if (cp >= 0x10000) {
                unsigned v = cp - 0x10000, hi = 0xD800 + (v >> 10), lo = 0xDC00 + (v & 0x3FF);
                w[0] = (char)(hi & 0xFF), w[1] = (char)(hi >> 8);
                w[2] = (char)(lo & 0xFF), w[3] = (char)(lo >> 8);
                zb_add(out, w, 4);
            } else {
                w[0] = (char)(cp & 0xFF), w[1] = (char)(cp >> 8);
                zb_add(out, w, 2);
            }
        }
        i += k;
    }
    return SG_OK;
}

/* ------------------------------------------------------------------------
 * The merit function written into the file's rows (issue 32): each row
 * whose operand the design still has unchanged keeps its line byte for
 * byte; a changed operand's row gets only its changed fields; new
 * operands are written in Zemax's layout "TYPE Int1 Int2 Data1 Data2
 * Data3 Data4 target weight Data5 Data6" after the row before them; rows
 * of operands the design dropped are dropped.  Rows sagitta does not read
 * as operands (DMFS, operands it does not know) stay.
 * ------------------------------------------------------------------------ */

/* Operands whose Int1 (and Int2, the first four) are rows, as merit_line
 * reads them. */
static int op_rows(sg_op_type t)
{
    return t == SG_OP_SUMM || t == SG_OP_DIFF || t == SG_OP_PROD || t == SG_OP_DIVI ? 2
           : t == SG_OP_OPGT || t == SG_OP_OPLT || t == SG_OP_ABSO || t == SG_OP_SQRT ? 1
                                                                                      : 0;
}

static int op_same(const sg_operand *a, const sg_operand *b)
{
    return a->type == b->type && a->i1 == b->i1 && a->i2 == b->i2 &&
           !memcmp(&a->hx, &b->hx, sizeof a->hx) && !memcmp(&a->hy, &b->hy, sizeof a->hy) &&
           !memcmp(&a->px, &b->px, sizeof a->px) && !memcmp(&a->py, &b->py, sizeof a->py) &&
           !memcmp(&a->target, &b->target, sizeof a->target) &&
           !memcmp(&a->weight, &b->weight, sizeof a->weight);
}

/* The row's eight numbers as the file holds them: row references are the
 * file's rows (drow, from 1) of the operands named. */
static void op_fields(const sg_operand *o, const int *drow, int nd, double f[8])
{
    int r = op_rows(o->type);
    f[0] = o->i1, f[1] = o->i2, f[2] = o->hx, f[3] = o->hy, f[4] = o->px, f[5] = o->py;
    f[6] = o->target, f[7] = o->weight;
    if (r >= 1 && o->i1 >= 1 && o->i1 <= nd)
        f[0] = drow[o->i1 - 1];
    if (r == 2 && o->i2 >= 1 && o->i2 <= nd)
        f[1] = drow[o->i2 - 1];
}

/* A merit row's text for operand o: the file's line (p, n; NULL for a new
 * row) with the fields whose value differs replaced, else a new line. */
static void merit_row(zbuf *out, const char *p, size_t n, const sg_operand *o, const double f[8])
{
    const char *name = sg_op_name(o->type);
    size_t to[12], tn[12], i = 0, last = 0;
    int nt = 0, k;
    char nb[40];
    while (p && i < n && nt < 12) {
        while (i < n && (p[i] == ' ' || p[i] == '\t'))
            i++;
        if (i == n)
            break;
        to[nt] = i;
        while (i < n && p[i] != ' ' && p[i] != '\t')
            i++;
        tn[nt] = i - to[nt];
        nt++;
    }
    if (o->type == SG_OP_BLNK) {
        /* A blank row's text is its comment. */
        if (p && nt && tn[0] == 4 && !memcmp(p + to[0], "BLNK", 4))
            zb_add(out, p, n);
        else
            zb_add(out, "BLNK", 4);
        return;
    }
    if (!p || nt < 9 || tn[0] != 4 || memcmp(p + to[0], name, 4) != 0) {
        zb_printf(out, "%s %d %d", name, (int)f[0], (int)f[1]);
        for (k = 2; k < 8; k++)
            zb_printf(out, " %s", num(nb, f[k]));
        zb_add(out, " 0 0", 4);
        return;
    }
    for (k = 1; k <= 8; k++) {
        char buf[48], *end;
        double v;
        int same;
        if (tn[k] >= sizeof buf)
            same = 0;
        else {
            memcpy(buf, p + to[k], tn[k]);
            buf[tn[k]] = '\0';
            v = strtod(buf, &end);
            same = !*end && (k <= 2 ? (int)v == (int)f[k - 1] : v == f[k - 1]);
        }
        if (same)
            continue;
        zb_add(out, p + last, to[k] - last);
        if (k <= 2)
            zb_printf(out, "%d", (int)f[k - 1]);
        else
            zb_printf(out, "%s", num(nb, f[k - 1]));
        last = to[k] + tn[k];
    }
    zb_add(out, p + last, n - last);
}

/* The lines after the surfaces with the design's merit function in the
 * rows (see above); ren renumbers the other kept lines. */
static int merit_after(zbuf *out, const struct sg_zmx_origin *o, const sg_system *sys,
                       zren *ren, const char *term, size_t nterm)
{
    const sg_merit *B = &o->base->merit, *D = &sys->merit;
    int nb = B->nop, nd = D->present ? D->nop : 0, i, j, pass, lastm = -1;
    int *L = calloc((size_t)(nb + 1) * (size_t)(nd + 1), sizeof *L);
    int *match = malloc(((size_t)nb + 1) * sizeof *match);
    int *taken = calloc((size_t)nd + 1, sizeof *taken);
    int *drow = calloc((size_t)nd + 1, sizeof *drow);
    if (!L || !match || !taken || !drow) {
        free(L), free(match), free(taken), free(drow);
        return SG_ENOMEM;
    }
    /* The longest common subsequence of the rows as read and as now: those
     * keep their lines. */
#define LL(a, b) L[(size_t)(a) * (size_t)(nd + 1) + (size_t)(b)]
    for (i = nb - 1; i >= 0; i--)
        for (j = nd - 1; j >= 0; j--)
            LL(i, j) = op_same(&B->op[i], &D->op[j]) ? LL(i + 1, j + 1) + 1
                       : LL(i + 1, j) > LL(i, j + 1) ? LL(i + 1, j)
                                                     : LL(i, j + 1);
    for (i = 0; i < nb; i++)
        match[i] = -1;
    for (i = 0, j = 0; i < nb && j < nd;) {
        if (op_same(&B->op[i], &D->op[j]) && LL(i, j) == LL(i + 1, j + 1) + 1) {
            match[i] = j, taken[j] = 1;
            i++, j++;
        } else if (LL(i + 1, j) >= LL(i, j + 1)) {
            i++;
        } else {
            j++;
        }
    }
#undef LL
    for (i = 0; i < o->nline; i++)
        if (o->line[i].sect == -2 && o->line[i].mop)
            lastm = i;
    /* Pass 0 numbers the file's rows; pass 1 writes them. */
    for (pass = 0; pass < 2; pass++) {
        int row = 0, dj = 0;
        zbuf *w = pass ? out : NULL;
        double f[8];
#define NEWROW(k)                                                              \
    do {                                                                       \
        drow[k] = ++row;                                                       \
        if (w) {                                                               \
            op_fields(&D->op[k], drow, nd, f);                                 \
            merit_row(w, NULL, 0, &D->op[k], f);                               \
            zb_add(w, term, nterm);                                            \
        }                                                                      \
    } while (0)
        if (lastm < 0)
            for (; dj < nd; dj++)
                NEWROW(dj);
        for (i = 0; i < o->nline; i++) {
            const zoline *z = &o->line[i];
            const char *p = o->text + z->off;
            int bi = z->mop - 1;
            if (z->sect != -2)
                continue;
            if (z->mop > 0 && bi < nb && match[bi] >= 0) {
                for (; dj < match[bi]; dj++)
                    NEWROW(dj);
                drow[dj] = ++row;
                if (w) {
                    op_fields(&D->op[dj], drow, nd, f);
                    merit_row(w, p, z->len, &D->op[dj], f);
                    zb_add(w, p + z->len, z->tlen);
                }
                dj++;
            } else if (z->mop > 0) {
                /* A row the design changed (its next new operand takes
                 * the line) or dropped. */
                if (dj < nd && !taken[dj]) {
                    drow[dj] = ++row;
                    if (w) {
                        op_fields(&D->op[dj], drow, nd, f);
                        merit_row(w, p, z->len, &D->op[dj], f);
                        zb_add(w, p + z->len, z->tlen);
                    }
                    dj++;
                }
            } else {
                row += z->mop < 0;
                if (w) {
                    size_t rn_n = 0;
                    char *r = ren_line(ren, p, z->len, -2, (long)i + 1, &rn_n);
                    zb_add(w, r ? r : p, r ? rn_n : z->len);
                    zb_add(w, p + z->len, z->tlen);
                    free(r);
                }
            }
            if (i == lastm)
                for (; dj < nd; dj++)
                    NEWROW(dj);
        }
#undef NEWROW
    }
    free(L), free(match), free(taken), free(drow);
    return out->oom ? SG_ENOMEM : SG_OK;
}

/* The file the design was read from with only the lines its edits concern
 * changed, in the file's encoding (merge_sec).  *structural is set where
 * surfaces were inserted, deleted or moved. */
static int zmx_merged(const sg_system *sys, const sg_catalog *cat, zbuf *bytes,
                      int *structural, zren *rn, char *why, size_t nwhy)
{
    const struct sg_zmx_origin *o = sys->zmx;
    zbuf bt = {0}, ct = {0}, out = {0};
    csec *B = NULL, *C = NULL;
    sg_diag scratch;
    int nb = 0, nc = 0, rc = SG_OK, i, j, *ol = NULL, on, *taken = NULL, *map = NULL;
    zren *ren = NULL;
    const char *term = "\n";
    size_t nterm = 1;
    char sl[40];

    sg_diag_clear(&scratch);
    *structural = sys->nsurf != o->base->nsurf;
    if (write_text(&bt, o->base, cat, 1, &scratch) != SG_OK ||
        write_text(&ct, sys, cat, 1, &scratch) != SG_OK || bt.oom || ct.oom) {
        snprintf(why, nwhy, "%.300s", scratch.msg[0] ? scratch.msg : "out of memory");
        rc = scratch.code ? scratch.code : SG_ENOMEM;
        goto done;
    }
    B = canon_split(bt.p, &nb);
    C = canon_split(ct.p, &nc);
    ol = malloc(((size_t)o->nline + 1) * sizeof *ol);
    taken = calloc((size_t)o->base->nsurf + 1, sizeof *taken);
    map = malloc(((size_t)o->base->nsurf + 1) * sizeof *map);
    if (!B || !C || !ol || !taken || !map) {
        rc = SG_ENOMEM;
        snprintf(why, nwhy, "out of memory");
        goto done;
    }
    /* Where each of the file's surfaces went: kept lines that name
     * surfaces are renumbered when any moved. */
    for (i = 0; i < o->base->nsurf; i++)
        map[i] = -1;
    for (j = 0; j < sys->nsurf; j++) {
        int t = sys->surf[j].zmx_src;
        if (t >= 1 && t <= o->base->nsurf && map[t - 1] < 0)
            map[t - 1] = j;
    }
    for (i = 0; i < o->base->nsurf; i++)
        *structural |= map[i] != i;
    memset(rn, 0, sizeof *rn);
    rn->map = map;
    rn->nold = o->base->nsurf;
    ren = *structural ? rn : NULL;
    if (o->nline && o->line[0].tlen) {
        term = o->text + o->line[0].off + o->line[0].len;
        nterm = o->line[0].tlen;
    }
    /* The header. */
    for (on = 0, i = 0; i < o->nline; i++)
        if (o->line[i].sect == -1)
            ol[on++] = i;
    if ((rc = merge_sec(&out, o, ol, on, &B[0], &C[0], 1, term, nterm, ren)) != SG_OK)
        goto done;
    /* The surfaces: each with its block of the file, a new one (or a
     * second copy of one) with sagitta's lines. */
    for (j = 0; j < sys->nsurf; j++) {
        int t = sys->surf[j].zmx_src;
        if (t < 1 || t > o->base->nsurf || taken[t - 1]) {
            *structural = 1;
            snprintf(sl, sizeof sl, "SURF %d", j);
            zb_add(&out, sl, strlen(sl));
            zb_add(&out, term, nterm);
            if ((rc = merge_sec(&out, o, ol, 0, NULL, &C[j + 1], 0, term, nterm, ren)) != SG_OK)
                goto done;
            continue;
        }
        taken[t - 1] = 1;
        if (t != j + 1)
            *structural = 1;
        for (on = 0, i = 0; i < o->nline; i++)
            if (o->line[i].sect == t - 1)
                ol[on++] = i;
        /* The SURF line first, renumbered where the surface moved. */
        if (on) {
            const zoline *z = &o->line[ol[0]];
            if (t == j + 1) {
                zb_add(&out, o->text + z->off, z->len + z->tlen);
            } else {
                size_t ind = 0;
                while (ind < z->len && (o->text[z->off + ind] == ' ' ||
                                        o->text[z->off + ind] == '\t'))
                    ind++;
                snprintf(sl, sizeof sl, "SURF %d", j);
                zb_add(&out, o->text + z->off, ind);
                zb_add(&out, sl, strlen(sl));
                zb_add(&out, o->text + z->off + z->len, z->tlen);
            }
        }
        if ((rc = merge_sec(&out, o, ol + 1, on ? on - 1 : 0, &B[t], &C[j + 1], 0, term,
                            nterm, ren)) != SG_OK)
            goto done;
    }
    /* After the surfaces: the merit function, tolerances and the rest, as
     * they are. */
    /* A merit function the import left out (a row it could not take, or
     * an empty editor's one BLNK row) cannot take the design's rows. */
    for (i = 0; i < o->nline; i++)
        rn->merit_unread |= o->line[i].mop > o->base->merit.nop;
    if (!sg_merit_equal(&sys->merit, &o->base->merit) && !rn->merit_unread) {
        if ((rc = merit_after(&out, o, sys, ren, term, nterm)) != SG_OK) {
            snprintf(why, nwhy, "out of memory");
            goto done;
        }
    } else
    for (i = 0; i < o->nline; i++)
        if (o->line[i].sect == -2) {
            const zoline *z = &o->line[i];
            size_t rn_n = 0;
            char *r = ren_line(ren, o->text + z->off, z->len, -2, (long)i + 1, &rn_n);
            if (r) {
                zb_add(&out, r, rn_n);
                zb_add(&out, o->text + z->off + z->len, z->tlen);
                free(r);
            } else {
                zb_add(&out, o->text + z->off, z->len + z->tlen);
            }
        }
    if (out.oom) {
        rc = SG_ENOMEM;
        snprintf(why, nwhy, "out of memory");
        goto done;
    }
    rc = encode(out.p ? out.p : "", out.len, o->enc, bytes, why, nwhy);
    if (rc == SG_OK && bytes->oom) {
        rc = SG_ENOMEM;
        snprintf(why, nwhy, "out of memory");
    }
done:
    free(bt.p);
    free(ct.p);
    free(out.p);
    free(ol);
    free(taken);
    free(map);
    rn->map = NULL;
    canon_free(B);
    canon_free(C);
    return rc;
}

/* The first line where two JSON texts differ, as "KEY: A, not B", for
 * the message that says what a .zmx file would not keep. */
static void first_diff(const char *want, const char *got, char *buf, size_t n)
{
    const char *a = want, *b = got;
    while (*a && *b) {
        const char *ea = strchr(a, '\n'), *eb = strchr(b, '\n');
        size_t la = ea ? (size_t)(ea - a) : strlen(a), lb = eb ? (size_t)(eb - b) : strlen(b);
        /* The format version follows the features a design uses. */
        int ver = 0;
        size_t t = 0;
        while (t < la && a[t] == ' ')
            t++;
        ver = la - t > 9 && memcmp(a + t, "\"version\"", 9) == 0;
        if ((la != lb || memcmp(a, b, la) != 0) && !ver) {
            while (la && (*a == ' '))
                a++, la--;
            while (lb && (*b == ' '))
                b++, lb--;
            snprintf(buf, n, "the design has %.*s where the file would read back %.*s",
                     (int)(la > 120 ? 120 : la), a, (int)(lb > 120 ? 120 : lb), b);
            return;
        }
        a += la + (ea != NULL);
        b += lb + (eb != NULL);
    }
    snprintf(buf, n, "the file would read back with %s surfaces", *a ? "fewer" : "more");
}

int sg_zmx_save(const sg_system *sys, const char *path, const sg_catalog *cat, sg_diag *d)
{
    return sg_zmx_save_flags(sys, path, cat, 0, d);
}

int sg_zmx_save_flags(const sg_system *sys, const char *path, const sg_catalog *cat,
                      unsigned flags, sg_diag *d)
{
    sg_catalog *own = NULL;
    char *text = NULL, why[600] = "";
    int rc, structural = 0, back = 1;
    zren rn;
    zbuf bytes = {0};
    if (!sys || !path || !path[0])
        return sg_diag_set(d, SG_EINVAL, "save: no system or no path");
    if (!cat) {
        sg_diag scratch;
        own = sg_catalog_new();
        sg_diag_clear(&scratch);
        if (own && sg_catalog_load_default(own, &scratch) != SG_OK) {
            sg_catalog_free(own);
            own = NULL;
        }
        cat = own;
    }
    if (sys->zmx) {
        locale_t cloc = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0), old = (locale_t)0;
        if (cloc)
            old = uselocale(cloc);
        memset(&rn, 0, sizeof rn);
        rc = zmx_merged(sys, cat, &bytes, &structural, &rn, why, sizeof why);
        if (cloc) {
            uselocale(old);
            freelocale(cloc);
        }
        if (rc == SG_OK) {
            /* The file must read back as the design, bit for bit. */
            sg_system *r = sg_system_new();
            sg_diag scratch;
            sg_diag_clear(&scratch);
            if (!r) {
                rc = SG_ENOMEM;
            } else if (sg_zmx_parse_subst(r, bytes.p, bytes.len, path, cat, &sys->zmx->sub,
                                          &scratch) != SG_OK) {
                snprintf(why, sizeof why, "the file would not read back: %.300s", scratch.msg);
                back = 0;
            } else if (!sg_system_equal(r, sys)) {
                char *a = sg_design_to_json(sys), *b = sg_design_to_json(r);
                if (rn.merit_unread && !sg_merit_equal(&r->merit, &sys->merit))
                    snprintf(why, sizeof why, "the merit function changed, and the file's own "
                             "was not read (the import's warning says why), so the design's "
                             "cannot be written into its rows");
                else if (a && b)
                    first_diff(a, b, why, sizeof why);
                else
                    snprintf(why, sizeof why, "the file would read back as another design");
                free(a);
                free(b);
                /* Lines that could not be renumbered read back as they
                 * were, which is the difference: they are named below,
                 * and a save allowed to lose keeps them as they are. */
                if (!(structural && rn.nbad))
                    back = 0;
            }
            sg_system_free(r);
        } else if (rc == SG_ELOSSY) {
            back = 0;
        }
        if (rc == SG_ENOMEM) {
            sg_catalog_free(own);
            free(bytes.p);
            return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
        }
        if (rc == SG_OK && structural && rn.nbad)
            snprintf(why, sizeof why, "surfaces were inserted, deleted or moved, and %d kept "
                     "line%s cannot be renumbered: %s%s", rn.nbad, rn.nbad == 1 ? "" : "s",
                     rn.bad, rn.nbad > 8 ? ", ..." : "");
        if (rc != SG_OK && back)
            back = 0;
        if (why[0] && !(flags & SG_ZMX_ALLOW_LOSS)) {
            sg_catalog_free(own);
            free(bytes.p);
            return sg_diag_set(d, SG_ELOSSY, "%s: cannot be written faithfully: %s; nothing "
                               "was written", path, why);
        }
        if (back) {
            if (why[0])
                sg_diag_warn(d, "%s: written all the same: %s", path, why);
            rc = sg_save_text_atomic(path, bytes.p, bytes.len, d);
            sg_catalog_free(own);
            free(bytes.p);
            return rc;
        }
        free(bytes.p);
        sg_diag_warn(d, "%s: written as sagitta's own .zmx text, without the %d lines of the "
                     "original file it does not interpret: %s", path, sys->zmx->nkept, why);
    }
    rc = zmx_text(sys, cat, &text, d);
    sg_catalog_free(own);
    if (rc != SG_OK)
        return rc;
    rc = sg_save_text_atomic(path, text, strlen(text), d);
    free(text);
    return rc;
}

int sg_zmx_load_subst(sg_system *sys, const char *path, const sg_catalog *cat,
                      const sg_zmx_subst *sub, sg_diag *d)
{
    char *buf = NULL;
    size_t len = 0;
    int rc = sg_read_file(path, ZMX_MAX_BYTES, &buf, &len, d);
    if (rc != SG_OK)
        return rc;
    rc = sg_zmx_parse_subst(sys, buf, len, path, cat, sub, d);
    free(buf);
    return rc;
}

int sg_zmx_load(sg_system *sys, const char *path, const sg_catalog *cat, sg_diag *d)
{
    char *buf = NULL;
    size_t len = 0;
    int rc = sg_read_file(path, ZMX_MAX_BYTES, &buf, &len, d);
    if (rc != SG_OK)
        return rc;
    rc = sg_zmx_parse(sys, buf, len, path, cat, d);
    free(buf);
    return rc;
}

static int ends_with_zmx(const char *path)
{
    size_t n = path ? strlen(path) : 0;
    return n >= 4 && path[n - 4] == '.' && tolower((unsigned char)path[n - 3]) == 'z' &&
           tolower((unsigned char)path[n - 2]) == 'm' && tolower((unsigned char)path[n - 1]) == 'x';
}

int sg_zmx_detect(const char *path, const void *head, size_t n)
{
    const unsigned char *b = head;
    size_t i = 0;
    if (ends_with_zmx(path))
        return 1;
    if (!b)
        return 0;
    if (n >= 2 && ((b[0] == 0xFF && b[1] == 0xFE) || (b[0] == 0xFE && b[1] == 0xFF)))
        return 1;
    if (n >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF)
        i = 3;
    while (i < n && (b[i] == ' ' || b[i] == '\t' || b[i] == '\r' || b[i] == '\n'))
        i++;
    /* A JSON design opens with '{'; a lens file with a keyword. */
    return n - i >= 5 && (memcmp(b + i, "VERS ", 5) == 0 || memcmp(b + i, "MODE ", 5) == 0);
}
