/*
 * fuzz_zar.c - libFuzzer harness for the Zemax archive (.zar) reader.
 *
 * The bytes go to sg_zar_parse() with the bundled catalog, and to
 * sg_zar_member() for the lens file.  Whatever happens, the diagnostic
 * must be a terminated string that names the input, and a member that
 * unpacks must come back with its stated length and a NUL after it.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

#define NAME "fuzz.zar"

static sg_catalog *cat;

static void die(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_zar: %s\n%s\n", what, detail ? detail : "");
    abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    sg_diag d;
    (void)argc;
    (void)argv;
    cat = sg_catalog_new();
    sg_diag_clear(&d);
    if (!cat || sg_catalog_load_default(cat, &d) != SG_OK || sg_catalog_count(cat) == 0) {
        fprintf(stderr, "fuzz_zar: no glass catalog (%s); set SAGITTA_LENSDB\n", d.msg);
        exit(1);
    }
    return 0;
}

static void check_diag(const sg_diag *d, int rc)
{
    int k, n = d->nwarn < SG_DIAG_MAXWARN ? d->nwarn : SG_DIAG_MAXWARN;
    if (!memchr(d->msg, '\0', sizeof d->msg))
        die("unterminated message", NULL);
    for (k = 0; k < n; k++)
        if (!memchr(d->warn[k], '\0', sizeof d->warn[k]))
            die("unterminated warning", NULL);
    if (rc != SG_OK && rc != SG_ENOMEM && strstr(d->msg, NAME) == NULL)
        die("a failure whose message does not name the input", d->msg);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sg_system *a = sg_system_new();
    void *m = NULL;
    size_t n = 0;
    char name[256];
    sg_diag d;
    int rc;
    if (!a)
        die("out of memory", NULL);
    sg_diag_clear(&d);
    rc = sg_zar_parse(a, data, size, NAME, cat, &d);
    check_diag(&d, rc);
    sg_diag_clear(&d);
    rc = sg_zar_member(data, size, NAME, NULL, &m, &n, name, &d);
    check_diag(&d, rc);
    if (rc == SG_OK && (!m || ((const char *)m)[n] != '\0' || !memchr(name, '\0', sizeof name)))
        die("a member without its terminating NUL", name);
    free(m);
    sg_system_free(a);
    return 0;
}
