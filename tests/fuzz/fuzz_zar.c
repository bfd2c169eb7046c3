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

#include "fuzz_common.h"
#include "sagitta.h"

#define NAME "fuzz.zar"

static sg_catalog *cat;

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    cat = fuzz_catalog("fuzz_zar");
    return 0;
}

#define die(what, detail) fuzz_die("fuzz_zar", what, detail)
#define check_diag(d, rc) fuzz_check_diag("fuzz_zar", NAME, d, rc)

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
