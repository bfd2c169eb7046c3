/*
 * fuzz_zmx.c - libFuzzer harness for the Zemax .zmx reader.
 *
 * The bytes go to sg_zmx_parse() with the bundled catalog.  Whatever
 * happens, the diagnostic must be a terminated string that names the
 * input.  When the file is accepted: the design is written back with
 * sg_zmx_to_text(), which must succeed (everything the reader accepts is
 * writable); that text must be read again to the same design (compared as
 * its JSON text, which writes every double so that it reads back to the
 * same bits), and written again to the identical text.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sagitta.h"

#define NAME "fuzz.zmx"

static sg_catalog *cat;

static void die(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_zmx: %s\n%s\n", what, detail ? detail : "");
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
        fprintf(stderr, "fuzz_zmx: no glass catalog (%s); set SAGITTA_LENSDB\n", d.msg);
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
    sg_system *a = sg_system_new(), *b = sg_system_new();
    char *z1 = NULL, *z2 = NULL, *j1 = NULL, *j2 = NULL;
    sg_diag d;
    int rc;
    if (!a || !b)
        die("out of memory", NULL);
    sg_diag_clear(&d);
    rc = sg_zmx_parse(a, data, size, NAME, cat, &d);
    check_diag(&d, rc);
    if (rc != SG_OK)
        goto done;
    sg_diag_clear(&d);
    z1 = sg_zmx_to_text(a, cat, &d);
    if (!z1)
        die("an accepted design cannot be written", d.msg);
    sg_diag_clear(&d);
    if (sg_zmx_parse(b, z1, strlen(z1), NAME, cat, &d) != SG_OK)
        die("the written text does not read back", d.msg);
    j1 = sg_design_to_json(a);
    j2 = sg_design_to_json(b);
    if (!j1 || !j2 || strcmp(j1, j2) != 0)
        die("the design read back differs", z1);
    z2 = sg_zmx_to_text(b, cat, &d);
    if (!z2 || strcmp(z1, z2) != 0)
        die("writing again gives another text", z1);
done:
    free(z1);
    free(z2);
    free(j1);
    free(j2);
    sg_system_free(a);
    sg_system_free(b);
    return 0;
}
