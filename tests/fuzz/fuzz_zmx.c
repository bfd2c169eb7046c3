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

#include "fuzz_common.h"
#include "sagitta.h"

#define NAME "fuzz.zmx"

static sg_catalog *cat;

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    cat = fuzz_catalog("fuzz_zmx");
    return 0;
}

#define die(what, detail) fuzz_die("fuzz_zmx", what, detail)
#define check_diag(d, rc) fuzz_check_diag("fuzz_zmx", NAME, d, rc)

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
