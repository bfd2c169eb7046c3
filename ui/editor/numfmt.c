/* numfmt.c - shortest round-trip text for doubles, cut to a column. */
#include "numfmt.h"
#include "../numfmt.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void numfmt_shortest(double v, char *buf, size_t n)
{
    char g[NUMFMT_SHORTEST_MAX], fixed[NUMFMT_SHORTEST_MAX];
    if (isnan(v)) {
        snprintf(buf, n, "NaN");
        return;
    }
    if (isinf(v)) {
        snprintf(buf, n, v > 0 ? "Infinity" : "-Infinity");
        return;
    }
    /* The fewest digits that read back (Schubfach, ../numfmt.c). */
    numfmt_shortest_g(v, g);
    /* %g writes 4500 as 4.5e+03; plain digits read more easily, so they
     * win whenever they are short enough to fit a column anyway. */
    if (strchr(g, 'e') && fabs(v) >= 1e-7 && fabs(v) < 1e15) {
        numfmt_shortest_f(v, fixed);
        if (strlen(fixed) < n && (strlen(fixed) <= 12 || strlen(fixed) <= strlen(g))) {
            snprintf(buf, n, "%s", fixed);
            return;
        }
    }
    snprintf(buf, n, "%s", g);
}

int numfmt_width(const char *s)
{
    int w = 0;
    for (; *s; s++)
        if (((unsigned char)*s & 0xC0) != 0x80)
            w++;
    return w;
}

/* Cuts the mantissa m (with exponent e, possibly "") to avail characters.
 * Returns 0 when the cut would drop digits before the decimal point. */
static int cut(const char *m, const char *e, int avail, const char *ell,
               char *out, size_t n)
{
    const char *dot = strchr(m, '.');
    int intlen = dot ? (int)(dot - m) : (int)strlen(m);
    int keep = avail;
    if (keep < intlen || keep < 1)
        return 0;
    /* A trailing point adds nothing once digits after it are gone. */
    if (dot && keep == intlen + 1)
        keep = intlen;
    snprintf(out, n, "%.*s%s%s", keep, m, ell, e);
    return 1;
}

void numfmt_fit(const char *text, int width, const char *ell, char *out, size_t n)
{
    char m[NUMFMT_MAX * 2], alt[NUMFMT_MAX * 2];
    const char *e;
    int len = (int)strlen(text), i;

    if (n == 0)
        return;
    if (width <= 0) {
        out[0] = '\0';
        return;
    }
    if (len <= width) {
        snprintf(out, n, "%s", text);
        return;
    }
    e = strpbrk(text, "eE");
    if (!e)
        e = text + len;
    snprintf(m, sizeof m, "%.*s", (int)(e - text), text);
    if (cut(m, e, width - 1 - (int)strlen(e), ell, out, n))
        return;
    /* The integer part alone is too wide: exponent form keeps the leading
     * digits and the magnitude. */
    if (!*e) {
        double v = strtod(text, NULL);
        if (isfinite(v)) {
            char ex[16];
            int prec;
            for (prec = 0; prec <= 16; prec++) {
                snprintf(alt, sizeof alt, "%.*e", prec, v);
                if (strtod(alt, NULL) == v)
                    break;
            }
            e = strchr(alt, 'e');
            snprintf(m, sizeof m, "%.*s", (int)(e - alt), alt);
            /* The exponent without its plus sign and leading zeros saves
             * room that the digits need more. */
            snprintf(ex, sizeof ex, "e%d", atoi(e + 1));
            if ((int)(strlen(m) + strlen(ex)) <= width) {
                snprintf(out, n, "%s%s", m, ex);
                return;
            }
            if (cut(m, ex, width - 1 - (int)strlen(ex), ell, out, n))
                return;
        }
    }
    for (i = 0; i < width && (size_t)i + 1 < n; i++)
        out[i] = '#';
    out[i] = '\0';
}

void numfmt_cell(double v, int width, const char *ell, char *out, size_t n)
{
    char full[NUMFMT_MAX];
    numfmt_shortest(v, full, sizeof full);
    numfmt_fit(full, width, ell, out, n);
}
