/* vtest.c - running the built sagitta binary from cmocka tests. */
#include "vtest.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"

/* Running the program is tests/cli's job; this file adds the JSON. */

void vt_init(int argc, char **argv)
{
    ct_init(argc, argv);
}

void vt_cleanup(void)
{
    ct_cleanup();
}

const char *vt_file(const char *name, const char *text)
{
    return ct_file(name, text);
}

const char *vt_source(const char *rel, char *buf, size_t n)
{
    const char *root = getenv("SAGITTA_SOURCE_ROOT");
    snprintf(buf, n, "%s/%s", root && *root ? root : ".", rel);
    return buf;
}

void vt_run(vt_result *r, ...)
{
    const char *args[64];
    ct_result cr;
    va_list ap;
    int n = 0;
    va_start(ap, r);
    do {
        assert_true(n < 63);
        args[n] = va_arg(ap, const char *);
    } while (args[n++]);
    va_end(ap);
    ct_runv(&cr, args);
    r->code = cr.code;
    r->out = cr.out;
    r->err = cr.err;
    r->json = cJSON_Parse(r->out);
}

void vt_free(vt_result *r)
{
    free(r->out);
    free(r->err);
    cJSON_Delete(r->json);
    memset(r, 0, sizeof *r);
}

static cJSON *vget(const cJSON *j, va_list ap)
{
    const char *name;
    cJSON *cur = (cJSON *)j;
    assert_non_null(cur);
    while ((name = va_arg(ap, const char *)) != NULL) {
        cJSON *next = cJSON_GetObjectItemCaseSensitive(cur, name);
        if (!next)
            fail_msg("JSON member \"%s\" missing", name);
        cur = next;
    }
    return cur;
}

cJSON *vt_get(const cJSON *j, ...)
{
    va_list ap;
    cJSON *r;
    va_start(ap, j);
    r = vget(j, ap);
    va_end(ap);
    return r;
}

double vt_num(const cJSON *j, ...)
{
    va_list ap;
    cJSON *r;
    va_start(ap, j);
    r = vget(j, ap);
    va_end(ap);
    if (!cJSON_IsNumber(r))
        fail_msg("JSON member \"%s\" is not a number", r->string ? r->string : "?");
    return r->valuedouble;
}
