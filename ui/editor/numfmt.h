/*
 * numfmt.h - numbers as the editor shows them.
 *
 * A stored value is shown with the fewest significant digits that read
 * back as the same double, so two different values never look alike.  When
 * that text is wider than its column it is cut (never rounded) and marked
 * with an ellipsis, so the digits shown are always a prefix of the truth.
 */
#ifndef SG_ED_NUMFMT_H
#define SG_ED_NUMFMT_H

#include <stddef.h>

/* Longest text numfmt_shortest() writes, with its terminator. */
#define NUMFMT_MAX 40

/* Writes v with the fewest significant digits that strtod() reads back as
 * v (Schubfach, ui/numfmt.c), as %g lays them out, or in plain digits
 * where those are short.  Infinities read "Infinity" / "-Infinity", NaN
 * reads "NaN". */
void numfmt_shortest(double v, char *buf, size_t n);

/* Fits a number's text into width columns: unchanged when it fits, else
 * digits are cut and ell (one column wide, e.g. "\xe2\x80\xa6") is
 * appended; an exponent is kept.  When not even the integer part fits, the
 * number is rewritten in exponent form; failing that the column is filled
 * with '#'.  out needs width + strlen(ell) + 1 bytes. */
void numfmt_fit(const char *text, int width, const char *ell, char *out, size_t n);

/* numfmt_shortest() then numfmt_fit(). */
void numfmt_cell(double v, int width, const char *ell, char *out, size_t n);

/* Display width in columns of a UTF-8 string whose only non-ASCII text is
 * one-column characters (the ellipsis, a Greek lambda). */
int numfmt_width(const char *s);

#endif
