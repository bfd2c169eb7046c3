/*
 * measure.h - how a traced value is judged against a reference, shared by
 * "sagitta verify" and the editor's digits view so both read the same, and
 * the residual of a reported point computed as defined.
 */
#ifndef SG_UI_MEASURE_H
#define SG_UI_MEASURE_H

#include "sagitta.h"

/* Digits are capped here: two equal doubles agree in every digit. */
#define MEAS_DIGITS_CAP 17.0
/* A coordinate much smaller than its point is judged against this fraction
 * of the point's largest coordinate rather than against itself. */
#define MEAS_DIGITS_FLOOR 1e-6

/* Digits by which a agrees with the reference b, one coordinate of a point
 * (or direction) whose largest reference coordinate is size:
 * -log10(|a - b| / max(|b|, 1e-6 size)), 17 when equal, floored at 0.
 * size 0 (a point at the origin with nothing to borrow) judges b alone. */
double meas_coord_digits(double a, double b, double size);

/* The least digits over three coordinates, each judged as above with size
 * the point's own largest reference coordinate, or scale when the
 * reference point is the origin (a chief ray through a vertex has no size
 * of its own and borrows that of its surface). */
double meas_point_digits(const double a[3], const double b[3], double scale);

/* |z - sag(x, y)| of the point (x, y, z) in surface s's local frame, with
 * the sag evaluated exactly enough (MPFR, precision grown until the result
 * is known to 20 bits) that a point a few ulp off the surface reads as its
 * true distance, not as 0.  NaN when the point lies outside the conic's
 * domain. */
double meas_residual(const sg_surface *s, double x, double y, double z);

#endif
