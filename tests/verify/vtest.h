/* vtest.h - running the built sagitta binary and reading its JSON output,
 * for the tests of "sagitta verify". */
#ifndef SG_VTEST_H
#define SG_VTEST_H

#include <stddef.h>
#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include <cjson/cJSON.h>

typedef struct vt_result {
    int code;    /* exit status, or 128 + signal */
    char *out;   /* standard output */
    char *err;   /* standard error */
    cJSON *json; /* standard output parsed, when it is JSON; else NULL */
} vt_result;

/* Takes the binary's path from argv[1] and makes a private temporary
 * directory; exits with a message when either fails. */
void vt_init(int argc, char **argv);
/* Removes the temporary files and directory. */
void vt_cleanup(void);
/* Writes text to NAME in the temporary directory and returns its path. */
const char *vt_file(const char *name, const char *text);
/* $SAGITTA_SOURCE_ROOT/rel, written into buf. */
const char *vt_source(const char *rel, char *buf, size_t n);

/* Runs sagitta with the NULL-terminated arguments. */
void vt_run(vt_result *r, ...);
void vt_free(vt_result *r);

/* Members by a path of names, e.g. vt_get(j, "summary", "precise", NULL);
 * fails the test when a member is missing. */
cJSON *vt_get(const cJSON *j, ...);
/* The number at a path; fails the test unless it is a number. */
double vt_num(const cJSON *j, ...);

#endif
