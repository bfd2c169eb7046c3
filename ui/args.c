/* args.c - strict parsing of numbers typed by the user. */
#include "args.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *args_strerror(int code)
{
    switch (code) {
    case ARGS_OK: return "no error";
    case ARGS_EMPTY: return "empty value";
    case ARGS_SYNTAX: return "not a number";
    case ARGS_RANGE: return "out of range";
    case ARGS_NONFINITE: return "not a finite number";
    case ARGS_COUNT: return "wrong number of values";
    default: return "invalid value";
    }
}

static int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

static const char *skip_blanks(const char *p, const char *end)
{
    while (p < end && is_blank(*p))
        p++;
    return p;
}

/* Parses the double in [s, end).  The copy keeps strtod from reading past
 * end (into the next list item) and gives it a terminated string. */
static int parse_span(const char *s, const char *end, int flags, double *out)
{
    char buf[128];
    char *stop;
    size_t len;
    double v;

    s = skip_blanks(s, end);
    while (end > s && is_blank(end[-1]))
        end--;
    len = (size_t)(end - s);
    if (len == 0)
        return ARGS_EMPTY;
    /* No double needs 127 characters except with absurd zero padding,
     * which a user does not type. */
    if (len >= sizeof buf)
        return ARGS_SYNTAX;
    memcpy(buf, s, len);
    buf[len] = '\0';
    errno = 0;
    v = strtod(buf, &stop);
    if (stop == buf || *stop != '\0')
        return ARGS_SYNTAX;
    if (isnan(v))
        return ARGS_NONFINITE;
    if (isinf(v)) {
        /* An infinity the user spelled out is a value; one produced by
         * overflow of a finite literal is not. */
        if (errno == ERANGE)
            return ARGS_RANGE;
        if (!(flags & ARGS_ALLOW_INF))
            return ARGS_NONFINITE;
    }
    *out = v;
    return ARGS_OK;
}

int args_double(const char *s, int flags, double *out)
{
    if (!s)
        return ARGS_EMPTY;
    return parse_span(s, s + strlen(s), flags, out);
}

int args_double_list(const char *s, int flags, double *out, int n, int *bad)
{
    const char *p, *end;
    int k = 0, rc, nitems = 1;

    if (bad)
        *bad = -1;
    if (!s || n < 1)
        return ARGS_EMPTY;
    for (p = s; *p; p++)
        if (*p == ',')
            nitems++;
    if (nitems != n) {
        /* A lone blank string is "empty", not "1 item of n". */
        if (nitems == 1 && *skip_blanks(s, s + strlen(s)) == '\0')
            return ARGS_EMPTY;
        return ARGS_COUNT;
    }
    p = s;
    for (k = 0; k < n; k++) {
        end = strchr(p, ',');
        if (!end)
            end = p + strlen(p);
        rc = parse_span(p, end, flags, &out[k]);
        if (rc != ARGS_OK) {
            if (bad)
                *bad = k;
            return rc;
        }
        p = *end ? end + 1 : end;
    }
    return ARGS_OK;
}

int args_long(const char *s, long lo, long hi, long *out)
{
    const char *end;
    char *stop;
    long v;

    if (!s)
        return ARGS_EMPTY;
    s = skip_blanks(s, s + strlen(s));
    if (*s == '\0')
        return ARGS_EMPTY;
    if (!(*s == '+' || *s == '-' || (*s >= '0' && *s <= '9')))
        return ARGS_SYNTAX;
    errno = 0;
    v = strtol(s, &stop, 10);
    if (stop == s)
        return ARGS_SYNTAX;
    end = skip_blanks(stop, stop + strlen(stop));
    if (*end != '\0')
        return ARGS_SYNTAX;
    if (errno == ERANGE || v < lo || v > hi)
        return ARGS_RANGE;
    *out = v;
    return ARGS_OK;
}

int args_int(const char *s, int lo, int hi, int *out)
{
    long v;
    int rc = args_long(s, lo, hi, &v);
    if (rc == ARGS_OK)
        *out = (int)v;
    return rc;
}
