/* test_safetext.c - text from files cannot drive the terminal.
 *
 * safe_text() against hand-written cases: ESC, BEL, DEL and the C1
 * controls become '?', as do bytes that are not UTF-8 (overlong forms,
 * surrogates, a cut sequence); other UTF-8 stays, and a cut never splits a
 * character.  Then the program: a design whose title holds an OSC window
 * title sequence, a clear-screen CSI and a C1 CSI, in a file whose name
 * holds ESC, through bench, paraxial, trace and a usage error; no control
 * byte of the title or the name may reach either output. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clitest.h"
#include "safetext.h"

static void test_cases(void **state)
{
    char b[64];
    (void)state;
    assert_string_equal(safe_text("plain title", b, sizeof b), "plain title");
    assert_string_equal(safe_text("a\x1b[2Jb", b, sizeof b), "a?[2Jb");
    assert_string_equal(safe_text("\x1b]0;x\x07", b, sizeof b), "?]0;x?");
    assert_string_equal(safe_text("tab\there\nnl\r\x7f", b, sizeof b), "tab?here?nl??");
    /* U+009B (C1 CSI), as UTF-8: both bytes are shown as '?'. */
    assert_string_equal(safe_text("x\xc2\x9b" "31m", b, sizeof b), "x??31m");
    /* U+00B5 (micro) and U+2013 (en dash) and U+1F600 stay. */
    assert_string_equal(safe_text("5 \xc2\xb5m \xe2\x80\x93 \xf0\x9f\x98\x80", b, sizeof b),
                        "5 \xc2\xb5m \xe2\x80\x93 \xf0\x9f\x98\x80");
    /* Latin-1, an overlong '/', a surrogate, past U+10FFFF, a cut tail. */
    assert_string_equal(safe_text("caf\xe9", b, sizeof b), "caf?");
    assert_string_equal(safe_text("\xc0\xaf", b, sizeof b), "??");
    assert_string_equal(safe_text("\xed\xa0\x80", b, sizeof b), "???");
    assert_string_equal(safe_text("\xf4\x90\x80\x80", b, sizeof b), "????");
    assert_string_equal(safe_text("ab\xe2\x80", b, sizeof b), "ab??");
    /* Cut to fit, never mid-character: 4 bytes of room hold "a" and one
     * two-byte character but not the next. */
    assert_string_equal(safe_text("a\xc2\xb5\xc2\xb5", b, 5), "a\xc2\xb5");
    assert_string_equal(safe_text("a\xc2\xb5\xc2\xb5", b, 4), "a\xc2\xb5");
    assert_string_equal(safe_text("a\xc2\xb5\xc2\xb5", b, 3), "a");
    assert_string_equal(safe_text(NULL, b, sizeof b), "");
}

/* Bytes that drive a terminal: C0 controls other than newline, DEL, and
 * a C1 control in UTF-8 or raw. */
static void no_controls(const char *what, const char *s)
{
    const unsigned char *p;
    for (p = (const unsigned char *)s; *p; p++) {
        if ((*p < 0x20 && *p != '\n') || *p == 0x7f || *p == 0x9b || *p == 0x9d)
            fail_msg("%s: control byte 0x%02x at offset %ld", what, *p,
                     (long)(p - (const unsigned char *)s));
        if (p[0] == 0xc2 && p[1] >= 0x80 && p[1] <= 0x9f)
            fail_msg("%s: a C1 control at offset %ld", what,
                     (long)(p - (const unsigned char *)s));
    }
}

static const char design_text[] =
    "{\"format\": \"sagitta-design\", \"version\": 1,\n"
    " \"title\": \"evil\\u001b]0;pwned\\u0007\\u001b[2J\\u009b31m \\u00b5 end\",\n"
    " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55, \"weight\": 1}]},\n"
    " \"fields\": {\"type\": \"angle\", \"normalization\": \"radial\",\n"
    "            \"list\": [{\"x\": 0, \"y\": 0, \"weight\": 1}]},\n"
    " \"aperture\": {\"type\": \"epd\", \"value\": 10}, \"ray_aiming\": \"off\",\n"
    " \"surfaces\": [\n"
    "  {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "  {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
    "  {\"radius\": \"inf\", \"thickness\": 95},\n"
    "  {\"radius\": \"inf\", \"thickness\": 0}]}\n";

static void test_program(void **state)
{
    const char *d = ct_file("t\x1b[31mx.json", design_text);
    ct_result r;
    (void)state;

    ct_run(&r, "bench", d, "--quick", "--repeat", "1", "--threads", "1", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "evil?]0;pwned??[2J??31m \xc2\xb5 end"));
    no_controls("bench stdout", r.out);
    no_controls("bench stderr", r.err);
    ct_free(&r);

    ct_run(&r, "paraxial", d, NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "t?[31mx.json"));
    no_controls("paraxial stdout", r.out);
    ct_free(&r);

    ct_run(&r, "trace", d, "--ray", "0,0,0,0.5", NULL);
    assert_int_equal(r.code, 0);
    no_controls("trace stdout", r.out);
    ct_free(&r);

    ct_run(&r, "verify", d, "--ray", "0,0,0,0.5", NULL);
    no_controls("verify stdout", r.out);
    no_controls("verify stderr", r.err);
    ct_free(&r);

    /* A stray argument is quoted back in a usage error. */
    ct_run(&r, "trace", d, "extra\x1b[2J", "--ray", "0,0,0,0", NULL);
    assert_int_equal(r.code, 2);
    assert_non_null(strstr(r.err, "extra\\x1b[2J"));
    no_controls("usage stderr", r.err);
    ct_free(&r);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cases),
        cmocka_unit_test(test_program),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
