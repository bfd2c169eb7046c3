/* test_cli_errors.c - exit statuses and messages of "sagitta", checked
 * against the contract in man/sagitta.1 (EXIT STATUS): 2 for a bad command
 * line, 3 for a file that cannot be read or parsed, 4 for a design that
 * cannot be traced, and never a crash. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "clitest.h"
#include "sagitta.h"

static const char *const SINGLET =
    "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
    "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
    "    {\"radius\": -50, \"thickness\": 45},\n"
    "    {\"radius\": \"inf\", \"thickness\": 0}";

/* Runs the arguments and checks the exit status, that stderr starts with
 * "sagitta: " and contains every needle given (NULL-terminated after the
 * arguments' own NULL). */
static void expect(int code, const char *const *args, const char *n1,
                   const char *n2)
{
    ct_result r;
    char cmd[512] = "";
    int k;
    for (k = 0; args[k]; k++) {
        strncat(cmd, " ", sizeof cmd - strlen(cmd) - 1);
        strncat(cmd, args[k], sizeof cmd - strlen(cmd) - 1);
    }
    ct_runv(&r, args);
    if (r.code != code)
        fail_msg("sagitta%s: exit %d, expected %d; stderr:\n%s", cmd, r.code, code,
                 r.err);
    if (code != 0) {
        if (strncmp(r.err, "sagitta: ", 9) != 0)
            fail_msg("sagitta%s: stderr lacks the \"sagitta: \" prefix:\n%s", cmd, r.err);
        if (r.out[0])
            fail_msg("sagitta%s: failed but wrote to stdout:\n%s", cmd, r.out);
    }
    if (n1 && !strstr(r.err, n1))
        fail_msg("sagitta%s: stderr lacks \"%s\":\n%s", cmd, n1, r.err);
    if (n2 && !strstr(r.err, n2))
        fail_msg("sagitta%s: stderr lacks \"%s\":\n%s", cmd, n2, r.err);
    print_message("# exit %d as expected:%s -> %.*s\n", code, cmd,
                  (int)strcspn(r.err, "\n"), r.err);
    ct_free(&r);
}

#define ARGS(...) ((const char *const[]){ __VA_ARGS__, NULL })

static void test_missing_file(void **state)
{
    const char *path = ct_path("no-such-design.json");
    (void)state;
    expect(3, ARGS("trace", path, "--ray", "0,0,0,0"), path, NULL);
    expect(3, ARGS("paraxial", path), path, NULL);
}

static void test_syntax_error(void **state)
{
    /* The stray comma is on line 3, after column 14. */
    const char *path = ct_file("syntax.json",
                               "{\n"
                               "  \"format\": \"sagitta-design\",\n"
                               "  \"version\": 1,,\n"
                               "  \"surfaces\": []\n"
                               "}\n");
    ct_result r;
    const char *p;
    int found = 0;
    (void)state;
    ct_run(&r, "trace", path, "--ray", "0,0,0,0", NULL);
    assert_int_equal(r.code, 3);
    assert_non_null(strstr(r.err, path));
    /* FILE:LINE:COL: with the line of the stray comma. */
    for (p = strstr(r.err, ":3:"); p; p = strstr(p + 1, ":3:"))
        if (isdigit((unsigned char)p[3])) {
            found = 1;
            break;
        }
    if (!found)
        fail_msg("no \":3:COL\" in: %s", r.err);
    print_message("# syntax error reported at line 3 with a column: %s", r.err);
    ct_free(&r);

    path = ct_file("garbage.json", "\x7f" "ELF\x01\x02\x03 not json at all");
    expect(3, ARGS("trace", path, "--ray", "0,0,0,0"), path, NULL);
}

static void test_unknown_glass(void **state)
{
    const char *path = ct_design("glass.json",
        "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "    {\"radius\": 50, \"thickness\": 5, \"material\": \"NO-SUCH-GLASS-42\", \"stop\": true},\n"
        "    {\"radius\": -50, \"thickness\": 45},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0}");
    (void)state;
    expect(4, ARGS("trace", path, "--ray", "0,0,0,0"), "surface 1", "NO-SUCH-GLASS-42");
    expect(4, ARGS("paraxial", path), "surface 1", NULL);
    expect(4, ARGS("thermal", path, "--temperature", "40", "-o", ct_path("hot.json")),
           "surface 1", "NO-SUCH-GLASS-42");
}

/* sagitta psf and mtf: bad options named, and a perfect paraboloid's MTF
 * JSON against the circular pupil's 2/pi (phi - cos phi sin phi). */
static void test_diffraction(void **state)
{
    const char *path = ct_design("psf.json", SINGLET);
    const char *mirror = ct_file("parab.json",
        "{\"format\": \"sagitta-design\", \"version\": 1, \"units\": \"mm\",\n"
        " \"aperture\": {\"type\": \"epd\", \"value\": 20},\n"
        " \"fields\": {\"type\": \"angle\", \"list\": [{\"x\": 0, \"y\": 0}]},\n"
        " \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},\n"
        " \"surfaces\": [\n"
        "  {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "  {\"radius\": \"inf\", \"thickness\": 0, \"stop\": true},\n"
        "  {\"radius\": -400, \"conic\": -1, \"thickness\": -200, \"material\": \"MIRROR\"},\n"
        "  {\"radius\": \"inf\", \"thickness\": 0}]}\n");
    ct_result r;
    const char *p;
    double nuc = 1.0 / (0.55e-3 * 10.0), worst = 0.0;
    int j;
    (void)state;
    expect(2, ARGS("psf", path, "--sampling", "16"), "--sampling", NULL);
    expect(2, ARGS("mtf", path, "--max-frequency", "-1"), "--max-frequency", NULL);
    expect(2, ARGS("psf", path, "--max-frequency", "10"), "--max-frequency", NULL);
    expect(2, ARGS("mtf", path, "--field", "9"), "--field 9", NULL);
    ct_run(&r, "mtf", mirror, "--sampling", "64", "--format", "json", (const char *)NULL);
    if (r.code != 0)
        fail_msg("sagitta mtf: exit %d: %s", r.code, r.err);
    /* "frequency" then "tangential": read the pairs in order. */
    p = strstr(r.out, "\"frequency\": [");
    assert_non_null(p);
    {
        double fr[64], t[64];
        const char *q = strstr(p, "\"tangential\": [");
        assert_non_null(q);
        p += strlen("\"frequency\": [");
        q += strlen("\"tangential\": [");
        for (j = 0; j < 64; j++) {
            char *e;
            fr[j] = strtod(p, &e);
            p = e + 1;
            t[j] = strtod(q, &e);
            q = e + 1;
        }
        for (j = 0; j < 64; j++) {
            double x = fr[j] / nuc, phi = acos(x < 1 ? x : 1);
            worst = fmax(worst, fabs(t[j] - 2.0 / 3.14159265358979 * (phi - cos(phi) * sin(phi))));
        }
        assert_true(fabs(fr[63] / nuc - 1.0) < 1e-9);
    }
    print_message("# mtf --format json of a perfect F/10: largest difference %.3g\n", worst);
    assert_true(worst < 0.004);
    assert_non_null(strstr(r.out, "\"diffraction_limit\": {\"frequency\": ["));
    ct_free(&r);
    ct_run(&r, "psf", mirror, "--format", "json", (const char *)NULL);
    assert_int_equal(r.code, 0);
    p = strstr(r.out, "\"strehl\": ");
    assert_non_null(p);
    assert_true(fabs(strtod(p + 10, NULL) - 1.0) < 1e-9);
    assert_non_null(strstr(r.out, "\"spacing_um\": "));
    ct_free(&r);
    /* psf --method huygens: the perfect mirror's Strehl ratio is 1; the
     * diffraction methods belong to their commands. */
    expect(2, ARGS("mtf", path, "--image-size", "16"), "--method huygens", NULL);
    expect(2, ARGS("mtf", path, "--through-focus", "0.1", "--frequency", "20", "--method",
                   "huygens"), "--through-focus", NULL);
    expect(2, ARGS("throughfocus", path, "--range", "0.1", "--frequency", "20", "--method",
                   "huygens"), "fft or geometric", NULL);
    expect(2, ARGS("psf", path, "--method", "geometric"), "geometric", NULL);
    expect(2, ARGS("psf", path, "--image-size", "16"), "--method huygens", NULL);
    ct_run(&r, "psf", mirror, "--method", "huygens", "--method", "classic", "--sampling", "32",
           "--format", "json", (const char *)NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "\"method\": \"huygens\""));
    p = strstr(r.out, "\"strehl\": ");
    assert_non_null(p);
    assert_true(fabs(strtod(p + 10, NULL) - 1.0) < 1e-9);
    ct_free(&r);
    /* mtf --through-focus: the options go together; in focus the mirror's
     * MTF at half the cutoff is the circle's, 2/pi (pi/3 - sqrt(3)/4). */
    expect(2, ARGS("mtf", path, "--through-focus", "0.1"), "--frequency", NULL);
    expect(2, ARGS("mtf", path, "--steps", "3"), "--through-focus", NULL);
    expect(2, ARGS("mtf", path, "--through-focus", "0.1", "--frequency", "20", "--steps", "1"),
           "--steps", NULL);
    {
        char fr[32];
        snprintf(fr, sizeof fr, "%.17g", nuc / 2);
        ct_run(&r, "mtf", mirror, "--through-focus", "0.01", "--frequency", fr, "--steps", "3",
               "--format", "json", (const char *)NULL);
    }
    if (r.code != 0)
        fail_msg("sagitta mtf --through-focus: exit %d: %s", r.code, r.err);
    p = strstr(r.out, "\"tangential\": [");
    assert_non_null(p);
    p = strchr(p, ',');
    assert_true(fabs(strtod(p + 1, NULL) -
                     2.0 / 3.14159265358979 * (3.14159265358979 / 3 - sqrt(3.0) / 4)) < 0.004);
    assert_non_null(strstr(r.out, "\"strehl\": ["));
    /* throughfocus is Zemax's name for the same analysis: the same JSON. */
    expect(2, ARGS("throughfocus", path, "--frequency", "20"), "--range R", NULL);
    expect(2, ARGS("mtf", path, "--range", "0.1"), "throughfocus only", NULL);
    {
        char fr[32];
        ct_result t;
        snprintf(fr, sizeof fr, "%.17g", nuc / 2);
        ct_run(&t, "throughfocus", mirror, "--range", "0.01", "--frequency", fr, "--steps", "3",
               "--format", "json", (const char *)NULL);
        if (t.code != 0)
            fail_msg("sagitta throughfocus: exit %d: %s", t.code, t.err);
        assert_string_equal(t.out, r.out);
        ct_free(&t);
    }
    ct_free(&r);
    /* Several frequencies in one run: in focus each is the circle's
     * 2/pi (acos s - s sqrt(1 - s^2)) at s = nu / nu_c; bad lists named. */
    expect(2, ARGS("throughfocus", path, "--range", "0.1", "--frequency", "20,abc"),
           "--frequency", NULL);
    expect(2, ARGS("throughfocus", path, "--range", "0.1", "--frequency", "20,-1"),
           "not a positive", NULL);
    expect(2, ARGS("throughfocus", path, "--range", "0.1", "--frequency", "1,2,3,4,5,6,7,8,9"),
           "at most 8", NULL);
    expect(2, ARGS("psf", path, "--frequency", "20"), "mtf throughfocus only", NULL);
    {
        char fr[80];
        const double sv[2] = { 0.25, 0.5 };
        int q;
        snprintf(fr, sizeof fr, "%.17g,%.17g", nuc * sv[0], nuc * sv[1]);
        ct_run(&r, "throughfocus", mirror, "--range", "0.01", "--frequency", fr, "--steps", "3",
               "--format", "json", (const char *)NULL);
        if (r.code != 0)
            fail_msg("sagitta throughfocus, two frequencies: exit %d: %s", r.code, r.err);
        assert_non_null(strstr(r.out, "\"frequencies\": ["));
        p = strstr(r.out, "\"mtf\": [");
        assert_non_null(p);
        for (q = 0; q < 2; q++) {
            double s = sv[q], want = 2.0 / 3.14159265358979 * (acos(s) - s * sqrt(1.0 - s * s));
            p = strstr(p, "\"tangential\": [");
            assert_non_null(p);
            p = strchr(p, ',');
            assert_true(fabs(strtod(p + 1, NULL) - want) < 0.004);
        }
        ct_free(&r);
        ct_run(&r, "throughfocus", mirror, "--range", "0.01", "--frequency", "20,40", "--steps",
               "3", "--format", "csv", (const char *)NULL);
        assert_int_equal(r.code, 0);
        assert_non_null(strstr(r.out, "shift,field1_tangential_20,field1_sagittal_20,"
                                      "field1_tangential_40,field1_sagittal_40,field1_strehl"));
    }
    ct_free(&r);
    /* encircled: bad options named; the perfect F/10's energy within its
     * first dark ring, v = 3.8317 (1.2197 lambda F#), is Rayleigh's 0.838. */
    expect(2, ARGS("encircled", path, "--type", "round"), "--type", NULL);
    expect(2, ARGS("encircled", path, "--max-radius", "0"), "--max-radius", NULL);
    expect(2, ARGS("mtf", path, "--rays", "10"), "--rays", NULL);
    expect(4, ARGS("encircled", path, "--max-radius", "1e6"), "maximum radius", NULL);
    {
        char rad[32];
        snprintf(rad, sizeof rad, "%.17g", 3.8317059702075123 * 0.55 * 10.0 / 3.14159265358979);
        ct_run(&r, "encircled", mirror, "--max-radius", rad, "--format", "json",
               (const char *)NULL);
    }
    if (r.code != 0)
        fail_msg("sagitta encircled: exit %d: %s", r.code, r.err);
    p = strstr(r.out, "\"fraction\": [");
    assert_non_null(p);
    p = strchr(p, ']');
    while (p[-1] != ' ')
        p--;
    print_message("# encircled --format json, F/10 at the first dark ring: %g\n", strtod(p, NULL));
    assert_true(fabs(strtod(p, NULL) - 0.838) < 0.003);
    assert_non_null(strstr(r.out, "\"radius_um\": [0, "));
    assert_non_null(strstr(r.out, "\"geometric\": ["));
    assert_non_null(strstr(r.out, "\"diffraction_limit\": ["));
    ct_free(&r);
}

/* sagitta thermal: the N-BK7 singlet at 60 C from 20 C has its first radius
 * grown by the glass's catalog TCE, 7.1e-6/K (ED line), the environment
 * set, and the file written; bad options are usage errors. */
static void test_thermal(void **state)
{
    const char *path = ct_design("bk7.json",
        "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
        "    {\"radius\": 50, \"thickness\": 5, \"material\": \"N-BK7\", \"stop\": true},\n"
        "    {\"radius\": -50, \"thickness\": 45, \"tce\": 23.6},\n"
        "    {\"radius\": \"inf\", \"thickness\": 0}");
    const char *out = ct_path("bk7-60.json");
    ct_result r;
    char *text, *p;
    (void)state;
    ct_run(&r, "thermal", path, "--temperature", "60", "-o", out, (const char *)NULL);
    if (r.code != 0)
        fail_msg("exit %d: %s", r.code, r.err);
    assert_non_null(strstr(r.out, "Saved: "));
    text = ct_read(out);
    assert_non_null(strstr(text, "\"temperature\": 60"));
    assert_non_null(strstr(text, "\"adjust_index\": true"));
    assert_non_null(strstr(text, "\"tce\": 23.6"));
    p = strstr(text, "\"radius\": 5");
    assert_non_null(p);
    assert_true(strtod(p + 10, NULL) == 50.0 * (1.0 + 7.1 * 1e-6 * 40.0));
    free(text);
    ct_free(&r);
    expect(2, ARGS("thermal", path, "--temperature", "1001", "-o", out), "--temperature",
           "outside -250 to 1000 C");
    expect(2, ARGS("thermal", path, "--temperature", "20", "--pressure", "-1", "-o", out),
           "--pressure", NULL);
    expect(2, ARGS("thermal", path, "-o", out), "missing --temperature", NULL);
    expect(2, ARGS("thermal", path, "--temperature", "40"), "missing -o", NULL);
    expect(3, ARGS("thermal", ct_path("none.json"), "--temperature", "40", "-o", out),
           "none.json", NULL);
}

static void test_bad_values(void **state)
{
    const char *d = ct_design("good.json", SINGLET);
    (void)state;
    expect(2, ARGS("trace", d, "--ray", "0,1,x"), "--ray",
           "expected 4 comma-separated numbers Hx,Hy,Px,Py, got \"0,1,x\"");
    expect(2, ARGS("trace", d, "--ray", "0,1,0,x"), "--ray", "Py");
    expect(2, ARGS("trace", d, "--ray", "nan,0,0,0"), "--ray", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,1e999"), "--ray", NULL);
    expect(2, ARGS("trace", d, "--frobnicate"), "--frobnicate", NULL);
    expect(2, ARGS("trace", d, "--ray"), "--ray", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--bits", "52"), "--bits", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--method", "mpfr", "--bits", "100001"),
           "--bits", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--bits", "64.5"), "--bits", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--method", "fast"), "--method", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--format", "xml"), "--format", NULL);
    expect(2, ARGS("paraxial", d, "--format", "csv"), "--format", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--wave", "0"), "--wave", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--threads", "-1"), "--threads", NULL);
    expect(2, ARGS("trace", d, "--start", "0,0", "--dir", "0,0,1"), "--start", NULL);
    expect(2, ARGS("trace", d, "--start", "0,0,-1", "--dir", "0,0,0"), "--dir", NULL);
    expect(2, ARGS("trace", d, "--start", "0,0,-1"), "--dir", NULL);
    expect(2, ARGS("trace", d), "--ray", NULL);
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--start", "0,0,-1", "--dir", "0,0,1"),
           "only one", NULL);
    expect(2, ARGS("trace", "--ray", "0,0,0,0"), "DESIGN", NULL);
    expect(2, ARGS("trace", d, d, "--ray", "0,0,0,0"), "unexpected", NULL);
    expect(2, ARGS("trace", d, "--no-clip=yes", "--ray", "0,0,0,0"), "--no-clip", NULL);
    expect(2, ARGS("frobnicate"), "frobnicate", NULL);
    expect(2, ARGS("--frobnicate"), "--frobnicate", NULL);
    expect(2, ARGS("help", "frobnicate"), "frobnicate", NULL);
}

static void test_wave_beyond_design(void **state)
{
    const char *d = ct_design("good.json", SINGLET);
    (void)state;
    /* The design has one wavelength. */
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--wave", "2"), "--wave", NULL);
    expect(2, ARGS("paraxial", d, "--wave", "2"), "--wave", NULL);
}

/* --config N (sagitta-design(5), CONFIGURATIONS): a design without
 * configurations has configuration 1 alone. */
static void test_config_option(void **state)
{
    const char *d = ct_design("good.json", SINGLET);
    ct_result r;
    (void)state;
    expect(2, ARGS("paraxial", d, "--config", "2"), "configuration 2",
           "the design has one configuration");
    expect(2, ARGS("trace", d, "--ray", "0,0,0,0", "--config", "x"), "--config", NULL);
    expect(2, ARGS("paraxial", d, "--config=0"), "--config", NULL);
    expect(2, ARGS("paraxial", d, "--config"), "--config", NULL);
    ct_runv(&r, ARGS("paraxial", d, "--config", "1"));
    assert_int_equal(r.code, 0);
    ct_free(&r);
    /* An operand of a surface the design lacks is a design error (4),
     * whatever configuration is asked for. */
    {
        const char *bad = ct_file(
            "badcfg.json",
            "{ \"wavelengths\": { \"primary\": 1, \"list\": [ { \"um\": 0.55 } ] },\n"
            "  \"fields\": { \"type\": \"angle\", \"list\": [ { \"y\": 0 } ] },\n"
            "  \"aperture\": { \"type\": \"epd\", \"value\": 10 },\n"
            "  \"surfaces\": [\n    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
            "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
            "    {\"radius\": -50, \"thickness\": 45},\n"
            "    {\"radius\": \"inf\", \"thickness\": 0} ],\n"
            "  \"configurations\": { \"count\": 2, \"operands\": [\n"
            "    { \"type\": \"THIC\", \"surface\": 9, \"values\": [45, 40] } ] } }\n");
        expect(4, ARGS("paraxial", bad), "configuration 1: configuration operand THIC 9",
               "surfaces 0 to 3");
        expect(4, ARGS("paraxial", bad, "--config", "2"), "THIC 9", NULL);
    }
}

static void test_help_version(void **state)
{
    ct_result r;
    (void)state;
    ct_run(&r, "--version", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, SG_VERSION_STRING));
    ct_free(&r);
    ct_run(&r, "--help", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "trace"));
    assert_non_null(strstr(r.out, "paraxial"));
    ct_free(&r);
    ct_run(&r, "help", "trace", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "--rays"));
    ct_free(&r);
    ct_run(&r, "trace", "-h", NULL);
    assert_int_equal(r.code, 0);
    assert_non_null(strstr(r.out, "--start"));
    ct_free(&r);
    print_message("# --version prints %s; --help, help trace and trace -h exit 0\n",
                  SG_VERSION_STRING);
}

static void test_csv_errors(void **state)
{
    const char *d = ct_design("good.json", SINGLET);
    const char *c;
    char where[1024];
    (void)state;
    c = ct_file("badhead.csv", "hx,hy,px,pz\n0,0,0,0\n");
    snprintf(where, sizeof where, "%s:1:", c);
    expect(3, ARGS("trace", d, "--rays", c), where, "\"pz\"");

    c = ct_file("count.csv", "hx,hy,px,py\n0,0,0,0\n0,0,0\n");
    snprintf(where, sizeof where, "%s:3:", c);
    expect(3, ARGS("trace", d, "--rays", c), where, "got 3");

    c = ct_file("nonnum.csv", "# rays\nhx,hy,px,py\n0,0,0,0\n0,0,zero,0\n");
    snprintf(where, sizeof where, "%s:4: column \"px\"", c);
    expect(3, ARGS("trace", d, "--rays", c), where, NULL);

    c = ct_path("absent.csv");
    expect(3, ARGS("trace", d, "--rays", c), c, NULL);
}

static void test_output_errors(void **state)
{
    const char *d = ct_design("good.json", SINGLET);
    const char *o = ct_path("no-such-dir/out.csv");
    (void)state;
    expect(3, ARGS("trace", d, "--ray", "0,0,0,0", "-o", o), o, NULL);
}

/* A device that is always full: the write error is reported.  Without
 * /dev/full the case is a skip, and in CI a failure. */
static void test_output_full(void **state)
{
    const char *d = ct_design("good.json", SINGLET);
    const char *ci = getenv("CI");
    FILE *f = fopen("/dev/full", "w");
    (void)state;
    if (!f) {
        if (ci && *ci && strcmp(ci, "0") && strcmp(ci, "false") && strcmp(ci, "no"))
            fail_msg("/dev/full cannot be opened; CI must run this case");
        print_message("# SKIP /dev/full cannot be opened\n");
        return;
    }
    fclose(f);
    expect(3, ARGS("trace", d, "--ray", "0,0,0,0", "--format", "csv", "-o", "/dev/full"),
           "/dev/full", NULL);
}

/* Issue 30, item 23: a SAGITTA_LENSDB that is missing or not a directory
 * is said on stderr, naming the variable and the path, while the bundled
 * catalogs stand in (the trace still succeeds). */
static void test_bad_lensdb(void **state)
{
    const char *saved = getenv("SAGITTA_LENSDB");
    char *keep = saved ? strdup(saved) : NULL;
    const char *d = ct_design("lensdb.json", SINGLET);
    const char *notdir = ct_file("not-a-dir", "x\n");
    const char *bad[2];
    ct_result r;
    int k;
    (void)state;
    bad[0] = ct_path("no-such-lensdb");
    bad[1] = notdir;
    for (k = 0; k < 2; k++) {
        char want[1024];
        setenv("SAGITTA_LENSDB", bad[k], 1);
        ct_run(&r, "trace", d, "--ray", "0,0,0,1", NULL);
        snprintf(want, sizeof want, "SAGITTA_LENSDB=%s is not a directory", bad[k]);
        if (r.code != 0 || !strstr(r.err, want))
            fail_msg("SAGITTA_LENSDB=%s: exit %d, stderr lacks \"%s\":\n%s", bad[k], r.code,
                     want, r.err);
        print_message("# %s\n", r.err);
        ct_free(&r);
    }
    if (keep)
        setenv("SAGITTA_LENSDB", keep, 1);
    else
        unsetenv("SAGITTA_LENSDB");
    free(keep);
    /* A good one says nothing. */
    ct_run(&r, "trace", d, "--ray", "0,0,0,1", NULL);
    assert_int_equal(r.code, 0);
    assert_null(strstr(r.err, "SAGITTA_LENSDB"));
    ct_free(&r);
}

/* Issue 30, item 2 for the commands: -o (and vignetting --save) replaces
 * an existing file, as the command line asks, whole or not at all; but a
 * command never writes over a file it reads (its design or its ray list,
 * by any name: device and inode are compared), which is refused with exit
 * status 3 and the file left as it was. */
static void test_output_is_input(void **state)
{
    const char *d = ct_design("own.json", SINGLET);
    const char *rays = ct_file("own_rays.csv", "hx,hy,px,py\n0,0,0,1\n");
    const char *lnk = ct_path("own_link.json");
    const char *hard = ct_path("own_hard.json");
    const char *other = ct_file("own_other.txt", "old\n");
    char *before = ct_read(d), *rb = ct_read(rays), *after;
    ct_result r;
    (void)state;
    assert_int_equal(symlink(d, lnk), 0);
    assert_int_equal(link(d, hard), 0);
    expect(3, ARGS("trace", d, "--ray", "0,0,0,1", "-o", d), "file this command reads", NULL);
    expect(3, ARGS("trace", d, "--ray", "0,0,0,1", "-o", lnk), lnk, NULL);
    expect(3, ARGS("trace", d, "--ray", "0,0,0,1", "-o", hard), hard, NULL);
    expect(3, ARGS("trace", d, "--rays", rays, "-o", rays), rays, NULL);
    expect(3, ARGS("trace", d, "--rays", rays, "--format", "csv", "-o", d), d, NULL);
    expect(3, ARGS("spot", d, "-o", d), d, NULL);
    expect(3, ARGS("paraxial", d, "-o", d), d, NULL);
    expect(3, ARGS("import", d, "-o", d), d, NULL);
    expect(3, ARGS("thermal", d, "--temperature", "40", "-o", d), d, NULL);
    expect(3, ARGS("vignetting", d, "--save", hard), hard, NULL);
    after = ct_read(d);
    assert_string_equal(after, before);
    free(after);
    after = ct_read(rays);
    assert_string_equal(after, rb);
    free(after);
    /* Another file named by -o is replaced. */
    ct_run(&r, "trace", d, "--ray", "0,0,0,1", "--format", "csv", "-o", other, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    after = ct_read(other);
    assert_null(strstr(after, "old"));
    assert_non_null(strstr(after, "surface"));
    free(after);
    free(before);
    free(rb);
}

/* Issue 30, item 5 for -o: the file replaced keeps its owner, group and
 * mode (as root, given to nobody first), and a dangling symbolic link
 * stays a link, the file it names written.  References: stat(), lstat(). */
static void test_output_keeps(void **state)
{
    const char *d = ct_design("keep.json", SINGLET);
    const char *own = ct_file("keep_owned.csv", "old\n");
    const char *lnk = ct_path("keep_link.csv");
    const char *target = ct_path("keep_target.csv");
    struct stat st;
    ct_result r;
    char *text;
    (void)state;
    assert_int_equal(chmod(own, 0640), 0);
    if (geteuid() == 0)
        assert_int_equal(chown(own, 65534, 65534), 0);
    /* spot writes through a temporary file renamed into place (a single
     * ray's trace writes in place). */
    ct_run(&r, "spot", d, "--format", "csv", "-o", own, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    assert_int_equal(stat(own, &st), 0);
    assert_int_equal(st.st_mode & 07777, 0640);
    if (geteuid() == 0) {
        assert_int_equal((long)st.st_uid, 65534);
        assert_int_equal((long)st.st_gid, 65534);
    }
    text = ct_read(own);
    assert_null(strstr(text, "old"));
    free(text);
    assert_int_equal(symlink("keep_target.csv", lnk), 0);
    ct_run(&r, "spot", d, "--format", "csv", "-o", lnk, NULL);
    assert_int_equal(r.code, 0);
    ct_free(&r);
    assert_int_equal(lstat(lnk, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(lstat(target, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    print_message("# -o kept owner %ld, mode %04o; a dangling link stayed a link\n",
                  (long)(geteuid() == 0 ? 65534 : geteuid()), 0640);
    unlink(lnk);
    unlink(target);
}

int main(int argc, char **argv)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_syntax_error),
        cmocka_unit_test(test_unknown_glass),
        cmocka_unit_test(test_bad_values),
        cmocka_unit_test(test_wave_beyond_design),
        cmocka_unit_test(test_config_option),
        cmocka_unit_test(test_help_version),
        cmocka_unit_test(test_csv_errors),
        cmocka_unit_test(test_output_errors),
        cmocka_unit_test(test_output_full),
        cmocka_unit_test(test_thermal),
        cmocka_unit_test(test_bad_lensdb),
        cmocka_unit_test(test_output_is_input),
        cmocka_unit_test(test_output_keeps),
        cmocka_unit_test(test_diffraction),
    };
    int rc;
    ct_init(argc, argv);
    rc = cmocka_run_group_tests(tests, NULL, NULL);
    ct_cleanup();
    return rc;
}
