/*
 * args.h - strict parsing of numbers typed by the user.
 *
 * Every parser consumes the whole string (surrounding blanks allowed), so
 * "1.5x" or "" is an error rather than 1.5 or 0; numbers go through strtod
 * and strtol, which round correctly.  The command line and the editor's ':'
 * prompt share these so that both accept and refuse the same text.
 */
#ifndef SG_UI_ARGS_H
#define SG_UI_ARGS_H

enum {
    ARGS_OK = 0,
    ARGS_EMPTY = 1,     /* nothing but blanks */
    ARGS_SYNTAX = 2,    /* not a number, or text after it */
    ARGS_RANGE = 3,     /* overflows, or outside the allowed range */
    ARGS_NONFINITE = 4, /* NaN, or an infinity where none is allowed */
    ARGS_COUNT = 5      /* a list with the wrong number of items */
};

/* Flags for args_double(). */
#define ARGS_ALLOW_INF 1 /* accept "inf", "-inf", "infinity" (never NaN) */

/* Short English reason for an ARGS_* code, e.g. "not a number". */
const char *args_strerror(int code);

/* Parses one double.  Overflow to infinity is ARGS_RANGE; underflow to a
 * subnormal or zero is accepted, since strtod still returns the nearest
 * double.  On error *out is left unchanged. */
int args_double(const char *s, int flags, double *out);

/* Parses exactly n comma-separated doubles (n >= 1) into out[0..n-1].  On
 * error, *bad (when not NULL) receives the 0-based index of the offending
 * item, or -1 when the count is wrong. */
int args_double_list(const char *s, int flags, double *out, int n, int *bad);

/* Parses a decimal integer in [lo, hi]. */
int args_long(const char *s, long lo, long hi, long *out);
int args_int(const char *s, int lo, int hi, int *out);

#endif
