/* clitest.h - running the built sagitta binary from cmocka tests. */
#ifndef SG_CLITEST_H
#define SG_CLITEST_H

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

typedef struct ct_result {
    int code;  /* exit status, or 128 + signal */
    char *out; /* standard output, NUL-terminated */
    char *err; /* standard error, NUL-terminated */
    long maxrss_kb; /* the child's peak resident set, from wait4 */
} ct_result;

/* Takes the binary's path from argv[1] (meson passes it) and makes a
 * private temporary directory.  Exits with a message when either fails. */
void ct_init(int argc, char **argv);
/* Removes the files written by ct_file and the directory. */
void ct_cleanup(void);

/* Writes text to NAME in the temporary directory; returns its path, which
 * stays valid until ct_cleanup. */
const char *ct_file(const char *name, const char *text);
/* A path in the temporary directory that ct_cleanup will remove. */
const char *ct_path(const char *name);
/* A whole file as a NUL-terminated string (free it); fails the test if it cannot be read. */
char *ct_read(const char *path);

/* Writes a design file NAME whose "surfaces" array is the JSON text
 * surfaces; one wavelength (0.55 um), fields 0 and 5 degrees, EPD 10, no
 * ray aiming.  Returns its path. */
const char *ct_design(const char *name, const char *surfaces);

/* Runs sagitta with the NULL-terminated arguments, capturing both outputs. */
void ct_run(ct_result *r, ...);
void ct_runv(ct_result *r, const char *const *args);
void ct_free(ct_result *r);

/* Value in data row (0-based) and named column of a CSV text, copied into
 * buf; NULL when absent. */
const char *ct_csv(const char *text, int row, const char *col, char *buf, size_t n);
/* The same, parsed with strtod; fails the test when absent or not a number. */
double ct_csv_num(const char *text, int row, const char *col);

/* Nonzero when hay contains needle, ignoring ASCII case. */
int ct_contains_nocase(const char *hay, const char *needle);

/* Fails unless |a - b| <= tol * max(|b|, scale); returns the scaled error
 * so callers can report the worst. */
double ct_close(double a, double b, double tol, double scale, const char *what);

#endif
