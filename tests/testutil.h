/* testutil.h - small helpers shared by the cmocka tests. */
#ifndef SG_TESTUTIL_H
#define SG_TESTUTIL_H

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include "sagitta.h"

/* Path of a file relative to the source tree ($SAGITTA_SOURCE_ROOT, set by
 * meson test), written into buf. */
const char *tu_path(const char *rel, char *buf, size_t n);

/* Loads the bundled catalog or fails the test. */
sg_catalog *tu_catalog(void);

/* Loads an example design from examples/ or fails the test. */
sg_system *tu_example(const char *file);

/* A tracer of sys with default options and method m, or fails the test. */
sg_tracer *tu_tracer(const sg_system *sys, const sg_catalog *cat, sg_method m);
/* The same with an mpfr precision of bits (0: the default). */
sg_tracer *tu_tracer_bits(const sg_system *sys, const sg_catalog *cat, sg_method m, int bits);

/* Object at infinity, surface 1 (the stop, flat air until the test sets
 * it) and the image: a system for tests of one surface. */
sg_system *tu_one_surface(void);

/* Distance between two doubles in units in the last place of the larger
 * magnitude of ref_scale (so a coordinate near zero is not judged by its
 * own tiny ulp). */
double tu_ulps(double a, double b, double ref_scale);
/* Whether two rows hold the same bits in every number and the same status
 * (the struct's padding is no part of a result). */
int tu_same_row(const sg_ray_surface *a, const sg_ray_surface *b);

/* ulp of |x| for a double (spacing of doubles at x). */
double tu_ulp(double x);

/* A case that cannot run here prints a line "# SKIP reason" and returns:
 * tools/dev.sh counts it as a skip.  (cmocka's skip() prints "not ok # SKIP",
 * which meson counts as a failure.)
 *
 * Nonzero when the tests run in CI (CI set, and not "", 0, false or no),
 * where a case that cannot run must fail rather than be skipped. */
int tu_ci(void);

/* Root's writes ignore a directory's mode, so a read-only-directory case
 * run as root would test nothing.  tu_unpriv_begin() switches this
 * thread's filesystem user and group to nobody (TU_NOBODY) with
 * setfsuid(2), which also drops root's file capabilities, and returns 1;
 * tu_unpriv_end() switches back.  The case first chowns what nobody must
 * own.  Not root: both do nothing and tu_unpriv_begin() returns 0.  Call
 * no cmocka assertion in between (a failure would leave the ids changed). */
#define TU_NOBODY 65534
int tu_unpriv_begin(void);
void tu_unpriv_end(void);

#endif
