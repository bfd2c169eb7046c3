/*
 * fuzz_common.h - what the .zmx and .zar harnesses share: the bundled
 * catalog, loaded once, and the check every diagnostic must pass.
 * Included by one harness each build (run.sh compiles a harness alone).
 */
#ifndef SG_FUZZ_COMMON_H
#define SG_FUZZ_COMMON_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

static void fuzz_die(const char *who, const char *what, const char *detail)
{
    fprintf(stderr, "%s: %s\n%s\n", who, what, detail ? detail : "");
    abort();
}

/* The bundled catalog, or exit: a harness without glasses tests nothing. */
static sg_catalog *fuzz_catalog(const char *who)
{
    sg_catalog *c = sg_catalog_new();
    sg_diag d;
    sg_diag_clear(&d);
    if (!c || sg_catalog_load_default(c, &d) != SG_OK || sg_catalog_count(c) == 0) {
        fprintf(stderr, "%s: no glass catalog (%s); set SAGITTA_LENSDB\n", who, d.msg);
        exit(1);
    }
    return c;
}

/* Messages and warnings are terminated, and a failure names the input. */
static void fuzz_check_diag(const char *who, const char *name, const sg_diag *d, int rc)
{
    int k, n = d->nwarn < SG_DIAG_MAXWARN ? d->nwarn : SG_DIAG_MAXWARN;
    if (!memchr(d->msg, '\0', sizeof d->msg))
        fuzz_die(who, "unterminated message", NULL);
    for (k = 0; k < n; k++)
        if (!memchr(d->warn[k], '\0', sizeof d->warn[k]))
            fuzz_die(who, "unterminated warning", NULL);
    if (rc != SG_OK && rc != SG_ENOMEM && strstr(d->msg, name) == NULL)
        fuzz_die(who, "a failure whose message does not name the input", d->msg);
}

#endif
