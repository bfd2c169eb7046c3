/*
 * numfmt.h - doubles to and from decimal text, fast and exact.
 *
 * numfmt_g17 writes the bytes snprintf("%.17g") writes in the C locale;
 * numfmt_parse reads a plain decimal number to the double strtod returns.
 * Both decide with a 128-bit product (printing: or an exact fused
 * multiply-add) and hand the rare cases they cannot decide to the C
 * library, so the results are the library's, bit for bit.
 */
#ifndef SG_UI_NUMFMT_H
#define SG_UI_NUMFMT_H

#include <stddef.h>
#include <stdint.h>

/* Room numfmt_g17 needs, with its terminating NUL (at most 25 bytes are
 * text; it writes scratch bytes after the NUL, within this room). */
#define NUMFMT_G17_MAX 32

/* Writes v as "%.17g" (C locale; "-0", "inf", "-inf", "nan" and "-nan" as
 * glibc writes them) into buf, NUL-terminated; returns the length. */
size_t numfmt_g17(double v, char *buf);

/* Reads [s, s + n) as [+-]digits[.digits][(e|E)[+-]digits] with at least
 * one digit, the whole span and nothing else, always with '.' as the
 * decimal point.  Returns 1 with *out the correctly rounded double, or 0
 * when the text is not of that form or its value is out of the normal
 * range (the caller then asks strtod, which also judges the syntax). */
/* numfmt_g17 of v[0..n-1], each into its own slot of NUMFMT_G17_MAX bytes
 * (slot i at out + i NUMFMT_G17_MAX, NUL-terminated) and its length into
 * len[i]: the same bytes, eight numbers at a time where the processor has
 * AVX-512. */
void numfmt_g17_n(const double *v, size_t n, char *out, unsigned char *len);

/* The eight decimal digits of x < 10^8, leading zeros included, as
 * ASCII; no NUL (numfmt_g17's digit step, exposed for its test). */
void numfmt_digits8(uint32_t x, char out[8]);

/* The shortest decimal f 10^e that reads back as v (finite), the closest
 * to v of those, an even last digit at a tie; f has no trailing zeros (0
 * for a zero).  Schubfach (numfmt.c).  Returns 0 for an infinity or NaN. */
int numfmt_shortest_decimal(double v, uint64_t *f, int *e);
/* Room the two forms below need, with the NUL: a 17-digit fraction of a
 * subnormal's size (0.000...) is the longest. */
#define NUMFMT_SHORTEST_MAX 352
/* That decimal as snprintf("%.*g", digits, v) writes it ("-0" for -0,
 * "inf", "nan" as %g); the length.  The same text as the search for the
 * fewest digits that read back, but for the rare doubles where a shorter
 * decimal lies in the rounding interval away from the nearest one. */
size_t numfmt_shortest_g(double v, char *buf);
/* The same decimal in plain positional form, without an exponent
 * ("1000", "0.00125"); an infinity, NaN or |v| >= 1e300 as the %g form. */
size_t numfmt_shortest_f(double v, char *buf);

int numfmt_parse(const char *s, size_t n, double *out);
/* The same for the longest such number from s (before end): where it
 * stops, with *out its double; NULL where numfmt_parse would return 0
 * for it.  Whatever follows is the caller's to judge (a comma, say). */
const char *numfmt_parse_to(const char *s, const char *end, double *out);

#endif
