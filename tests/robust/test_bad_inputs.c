/*
 * test_bad_inputs.c - every bad input gets a clear answer (issue 6, part 1).
 *
 * One table row per case: an input file (a design, a ray list, or a large
 * generated file), the command line, the exit status that man/sagitta.1
 * (EXIT STATUS) documents for it, and text the message must contain - the
 * FILE:LINE:COL of a syntax error, the surface and field of a content
 * error, the status of a ray that failed.  The expected values come from
 * the manual pages and from the geometry of each input, never from the
 * program's own output.
 *
 * Every case runs the real binary (argv[1]) under a time limit, and fails
 * when the child hangs or dies by a signal, whatever else it printed.
 */
#define _DEFAULT_SOURCE /* wait4(), for the child's peak memory */

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <setjmp.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

extern char **environ;

/* A hang is a failure, not a slow pass: no case needs more than a second
 * unsanitized, so this leaves room for sanitizers on a busy machine. */
#define CASE_TIMEOUT_S 60.0

/* Limits of a refusal that must not read the whole input. */
#define FAST_SECONDS 3.0
#define FAST_MAX_RSS_KB (48L * 1024)

/* Flags of a case. */
#define F_ONCE 1u  /* err_has occurs exactly once in standard error */
#define F_FAST 2u  /* refused within FAST_SECONDS and FAST_MAX_RSS_KB */
#define F_OR_0 4u  /* exit 0 (failures reported per ray) is accepted too */

typedef void (*gen_fn)(const char *path);

typedef struct bad_case {
    const char *name;     /* TAP name */
    const char *what;     /* what the case checks, for its "# " line */
    const char *file;     /* input file written for the case (@F), or NULL */
    const char *text;     /* its content; NULL when gen makes it */
    gen_fn gen;
    const char *stdin_text; /* standard input, or NULL for /dev/null */
    const char *args[16]; /* @F the input, @D a good design, @E examples dir */
    int code;             /* expected exit status */
    const char *err_has;  /* in standard error (@F expanded), or NULL */
    const char *out_has;  /* in standard output, or NULL */
    const char *out_alt;  /* accepted in place of out_has, or NULL */
    const char *forbid;   /* in neither output, or NULL */
    unsigned flags;
} bad_case;

/* ------------------------------------------------------------------ inputs */

/* A design of fixed indices (no catalog needed) with the stop on a
 * biconvex lens: R 50/-50, index 1.5, EPD 10, fields 0 and 5 degrees. */
#define HEAD "{\n" HEAD_KEYS
#define HEAD_KEYS                                                             \
    "  \"format\": \"sagitta-design\",\n"                                     \
    "  \"wavelengths\": {\"primary\": 1, \"list\": [{\"um\": 0.55}]},\n"      \
    "  \"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 5}]},\n" \
    "  \"aperture\": {\"type\": \"epd\", \"value\": 10},\n"                   \
    "  \"surfaces\": [\n"
#define OBJ "    {\"radius\": \"inf\", \"thickness\": \"inf\"},\n"
#define S1 "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
#define S1NOSTOP "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5},\n"
#define S2 "    {\"radius\": -50, \"thickness\": 45},\n"
#define IMA "    {\"radius\": \"inf\", \"thickness\": 0}\n"
#define TAIL "  ]\n}\n"
#define SINGLET HEAD OBJ S1 S2 IMA TAIL

/* The same head with ray aiming set, for the aiming cases. */
#define HEAD_AIM(mode, epd)                                                   \
    "{\n"                                                                     \
    "  \"wavelengths\": {\"list\": [{\"um\": 0.55}]},\n"                      \
    "  \"fields\": {\"type\": \"angle\", \"list\": [{\"y\": 0}, {\"y\": 5}]},\n" \
    "  \"aperture\": {\"type\": \"epd\", \"value\": " epd "},\n"              \
    "  \"ray_aiming\": \"" mode "\",\n"                                       \
    "  \"surfaces\": [\n"

/* A biconvex F/2 lens (R 20/-20, index 1.5, 5 thick) whose stop sits 10 mm
 * behind it, just past the paraxial focus (BFL 9.13).  Parallel rays
 * entering at height h cross the stop at a height that rises to a maximum
 * near h = 6.5 and falls again (spherical aberration), so the paraxial
 * marginal target on the stop (EPD 10 -> 2.1875) lies beyond every real
 * ray: aiming must fail, and fail in bounded time. */
#define AIM_LENS                                                              \
    OBJ                                                                       \
    "    {\"radius\": 20, \"thickness\": 5, \"material\": 1.5},\n"            \
    "    {\"radius\": -20, \"thickness\": 10},\n"                             \
    "    {\"stop\": true, \"thickness\": 30},\n"                              \
    IMA TAIL

static void write_or_die(const char *path, const void *p, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(p, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

/* A file of 100 MiB that occupies no disk: the program must refuse it by
 * its size, before reading it. */
static void gen_sparse_100m(const char *path)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, 100L * 1024 * 1024), 0);
    assert_int_equal(close(fd), 0);
}

/* One million empty surface objects: 3 MB of valid JSON, ten times the
 * surface limit. */
static void gen_million_surfaces(const char *path)
{
    const size_t n = 1000000;
    size_t k, len = 0;
    char *t = malloc(3 * n + 64);
    assert_non_null(t);
    len += (size_t)sprintf(t, "{\"surfaces\": [");
    for (k = 0; k < n; k++) {
        memcpy(t + len, k ? ",{}" : "{}", k ? 3 : 2);
        len += k ? 3 : 2;
    }
    len += (size_t)sprintf(t + len, "]}\n");
    write_or_die(path, t, len);
    free(t);
}

/* 100000 nested arrays: deeper than any parser's stack should go. */
static void gen_deep(const char *path)
{
    const size_t n = 100000;
    char *t = malloc(n);
    assert_non_null(t);
    memset(t, '[', n);
    write_or_die(path, t, n);
    free(t);
}

/* A NUL byte at line 2, column 5; cJSON alone would stop there and
 * ignore the rest. */
static void gen_nul_design(const char *path)
{
    static const char t[] = "{\n  \"a\0\": 1,\n  \"surfaces\": []\n}\n";
    write_or_die(path, t, sizeof t - 1);
}

/* 65 fields, one more than SG_MAX_FIELDS. */
static void gen_65_fields(const char *path)
{
    char t[8192];
    size_t len = (size_t)sprintf(t, "{\"fields\": {\"list\": [");
    int k;
    for (k = 0; k < 65; k++)
        len += (size_t)sprintf(t + len, "%s{\"y\": %d}", k ? ", " : "", k);
    len += (size_t)sprintf(t + len, "]}, \"surfaces\": [{}, {\"stop\": true}, {}]}\n");
    write_or_die(path, t, len);
}

/* 25 wavelengths, one more than SG_MAX_WAVES. */
static void gen_25_waves(const char *path)
{
    char t[8192];
    size_t len = (size_t)sprintf(t, "{\"wavelengths\": {\"list\": [");
    int k;
    for (k = 0; k < 25; k++)
        len += (size_t)sprintf(t + len, "%s{\"um\": 0.%d}", k ? ", " : "", 40 + k);
    len += (size_t)sprintf(t + len, "]}, \"surfaces\": [{}, {\"stop\": true}, {}]}\n");
    write_or_die(path, t, len);
}

/* A title of 200 bytes; the limit is 127. */
static void gen_long_title(const char *path)
{
    char t[512];
    size_t len = (size_t)sprintf(t, "{\"title\": \"");
    memset(t + len, 'T', 200);
    len += 200;
    len += (size_t)sprintf(t + len, "\", \"surfaces\": [{}, {\"stop\": true}, {}]}\n");
    write_or_die(path, t, len);
}

/* 1100 identical biconvex lenses in a row (2202 surfaces), each imaging
 * the last one's focus: a legal, long system whose reported numbers must
 * stay numbers ("undefined" is how the text report prints a NaN). */
static void gen_long_system(const char *path)
{
    const int nlens = 1100;
    size_t cap = 160 * (size_t)nlens + 1024, len;
    char *t = malloc(cap);
    int k;
    assert_non_null(t);
    len = (size_t)sprintf(t, "{\"surfaces\": [\n{\"thickness\": \"inf\"},\n");
    for (k = 0; k < nlens; k++)
        len += (size_t)sprintf(t + len,
                               "{\"radius\": 100, \"thickness\": 1, \"material\": 1.5%s},\n"
                               "{\"radius\": -100, \"thickness\": 1},\n",
                               k == 0 ? ", \"stop\": true" : "");
    len += (size_t)sprintf(t + len, "{}]}\n");
    assert_true(len < cap);
    write_or_die(path, t, len);
    free(t);
}

/* A ray file whose second line is one field of a million digits. */
static void gen_csv_huge_line(const char *path)
{
    const size_t n = 1000000;
    char *t = malloc(n + 64);
    size_t len = (size_t)sprintf(t, "hx,hy,px,py\n");
    assert_non_null(t);
    memset(t + len, '1', n);
    len += n;
    len += (size_t)sprintf(t + len, ",0,0,0\n");
    write_or_die(path, t, len);
    free(t);
}

/* A ray line of a million and one fields. */
static void gen_csv_wide(const char *path)
{
    const size_t n = 1000000;
    char *t = malloc(2 * n + 64);
    size_t k, len = (size_t)sprintf(t, "hx,hy,px,py\n");
    assert_non_null(t);
    for (k = 0; k < n; k++) {
        t[len++] = '0';
        t[len++] = ',';
    }
    t[len++] = '0';
    t[len++] = '\n';
    write_or_die(path, t, len);
    free(t);
}

static void gen_csv_nul(const char *path)
{
    static const char t[] = "hx,hy,px,py\n0,0,\0,0\n";
    write_or_die(path, t, sizeof t - 1);
}

/* SINGLET in UTF-16 (little-endian, with its byte order mark) or, with
 * csv set, a ray list so. */
static void write_utf16(const char *path, const char *text)
{
    char buf[4096];
    size_t n = 0, k;
    buf[n++] = (char)0xFF;
    buf[n++] = (char)0xFE;
    for (k = 0; text[k] && n + 2 <= sizeof buf; k++) {
        buf[n++] = text[k];
        buf[n++] = 0;
    }
    write_or_die(path, buf, n);
}

static void gen_utf16_design(const char *path)
{
    write_utf16(path, SINGLET);
}

static void gen_utf16_csv(const char *path)
{
    write_utf16(path, "hx,hy,px,py\n0,0,0,0\n");
}

/* A Zemax archive of one stored member (the 0xEC layout, sagitta-design(5)
 * ZEMAX ARCHIVES) holding text; cut leaves the header's last bytes off. */
static void write_zar(const char *path, const char *name, const char *text, int cut)
{
    unsigned char h[0x288];
    size_t n = strlen(text), i;
    FILE *f = fopen(path, "wb");
    if (!f)
        abort();
    memset(h, 0, sizeof h);
    h[0] = 0xEC;
    h[1] = 0x03;
    for (i = 0; i < 8; i++) {
        h[0x10 + i] = (unsigned char)((uint64_t)n >> (8 * i));
        h[0x18 + i] = (unsigned char)((uint64_t)n >> (8 * i));
    }
    for (i = 0; name[i]; i++)
        h[0x30 + 2 * i] = (unsigned char)name[i];
    if (fwrite(h, 1, cut ? 100 : sizeof h, f) != (cut ? 100 : sizeof h) ||
        (!cut && fwrite(text, 1, n, f) != n) || fclose(f) != 0)
        abort();
}

static void gen_zar_cut(const char *path)
{
    write_zar(path, "L.ZMX", "", 1);
}

static void gen_zar_bad_line(const char *path)
{
    write_zar(path, "L.ZMX",
              "MODE SEQ\nENPD 10\nWAVM 1 0.55 1\nPWAV 1\nSURF 0\nSURF 1\n  CURV 1..2\n", 0);
}

/* --------------------------------------------------------------- the table */

#define ARGS(...) { __VA_ARGS__, NULL }
/* The header of a small .zmx file: four lines. */
#define ZH "MODE SEQ\nENPD 10\nWAVM 1 0.55 1\nPWAV 1\n"
#define TRACE0(...) ARGS("trace", "@F", "--ray", "0,0,0,0", __VA_ARGS__)

static const bad_case cases[] = {
    /* ---- JSON syntax errors: exit 3, FILE:LINE:COL ---- */
    { "json_stray_comma", "a doubled comma on line 3 is a syntax error at line 3",
      "comma.json",
      "{\n  \"format\": \"sagitta-design\",\n  \"version\": 1,,\n  \"surfaces\": []\n}\n",
      NULL, NULL, ARGS("trace", "@F", "--ray", "0,0,0,0"), 3,
      "@F:3:", NULL, NULL, NULL, 0 },
    { "json_bad_token", "a bare word at line 2, column 12 is reported there",
      "token.json", "{\n  \"title\": x,\n  \"surfaces\": []\n}\n",
      NULL, NULL, ARGS("trace", "@F", "--ray", "0,0,0,0"), 3,
      "@F:2:12: JSON syntax error near 'x", NULL, NULL, NULL, 0 },
    { "json_truncated", "a file cut inside the surface list ends early",
      "cut.json", HEAD OBJ S1, NULL, NULL, ARGS("trace", "@F", "--ray", "0,0,0,0"), 3,
      "JSON syntax error near end of input", NULL, NULL, NULL, 0 },
    { "json_empty", "an empty file is a syntax error at 1:1",
      "empty.json", "", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "@F:1:1: JSON syntax error", NULL, NULL, NULL, 0 },
    { "json_unterminated_string", "a string without its closing quote, line 2",
      "quote.json", "{\n  \"title\": \"abc\n}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "@F:2:", NULL, NULL, NULL, 0 },
    { "json_binary", "binary garbage is a syntax error at 1:1",
      "garbage.json", "\x7f" "ELF\x01\x02\x03 not json", NULL, NULL,
      ARGS("paraxial", "@F"), 3, "@F:1:1: JSON syntax error", NULL, NULL, NULL, 0 },
    { "json_escaped_nul", "\\u0000 in a material would cut it: refused with the key's path",
      "enul.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": "
      "\"N-BK7\\u0000garbage\", \"stop\": true},\n" S2 IMA TAIL, NULL, NULL,
      ARGS("paraxial", "@F"), 3, "@F: surfaces[1].material: the text holds \\u0000", NULL, NULL,
      NULL, 0 },
    { "json_escaped_backslash_u0000", "an escaped backslash before u0000 is plain text",
      "ebs.json", "{\n  \"title\": \"a\\\\u0000b\",\n" HEAD_KEYS OBJ S1 S2 IMA TAIL, NULL, NULL,
      ARGS("paraxial", "@F"), 0, NULL, "Effective focal length", NULL, NULL, 0 },
    { "json_invalid_utf8", "a Latin-1 byte in a comment is not UTF-8: refused with the path",
      "latin1.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, "
      "\"comment\": \"caf\xE9\", \"stop\": true},\n" S2 IMA TAIL, NULL, NULL,
      ARGS("paraxial", "@F"), 3,
      "@F: surfaces[1].comment: the text is not valid UTF-8 (byte 0xE9 after 3 valid bytes)",
      NULL, NULL, NULL, 0 },
    { "json_invalid_utf8_key", "an overlong encoding in a key is not UTF-8",
      "key8.json", "{\n  \"ti\xC0\xAEtle\": \"x\",\n" HEAD_KEYS OBJ S1 S2 IMA TAIL, NULL, NULL,
      ARGS("paraxial", "@F"), 3, "the key is not valid UTF-8 (byte 0xC0 after 2 valid bytes)",
      NULL, NULL, NULL, 0 },
    { "json_utf8_bom", "a UTF-8 byte order mark before the design is ignored (RFC 8259)",
      "bom.json", "\xEF\xBB\xBF" SINGLET, NULL, NULL, ARGS("paraxial", "@F"), 0, NULL,
      "Effective focal length", NULL, NULL, 0 },
    { "json_utf16", "a design in UTF-16 with its byte order mark is read as JSON",
      "u16.json", NULL, gen_utf16_design, NULL, ARGS("paraxial", "@F"), 0, NULL,
      "Effective focal length", NULL, NULL, 0 },
    { "trace_point_like_surface", "R = 1e-300: precise names the surface and the reason",
      "tiny.json", HEAD OBJ "    {\"radius\": 1e-300, \"thickness\": 5, \"material\": 1.5, "
      "\"stop\": true},\n" S2 IMA TAIL, NULL, NULL, ARGS("trace", "@F", "--ray", "0,0,0,0"), 4,
      "@F: trace failed on surface 1: nonphysical surface or system (status NONPHYS): the "
      "surface's normal", NULL, NULL, NULL, 0 },
    { "spot_point_like_surface", "R = 1e-300: spot's chief-ray line names the surface",
      "tiny2.json", HEAD OBJ "    {\"radius\": 1e-300, \"thickness\": 5, \"material\": 1.5, "
      "\"stop\": true},\n" S2 IMA TAIL, NULL, NULL, ARGS("spot", "@F"), 0, NULL,
      "chief ray: nonphysical surface or system at surface 1\n", NULL, NULL, 0 },
    { "trace_huge_direction", "a direction of 1e308 a component is (1, 1, 1) / sqrt 3",
      NULL, NULL, NULL, NULL,
      ARGS("trace", "@D", "--start", "0,0,-1", "--dir", "1e308,1e308,1e308", "--format", "csv"),
      0, NULL, "0,0,-1,0.577350269189625", NULL, "INVAL", 0 },
    { "trace_tiny_direction", "a direction of 1e-300 a component is (1, 0, 1) / sqrt 2",
      NULL, NULL, NULL, NULL,
      ARGS("trace", "@D", "--start", "0,0,-1", "--dir", "1e-300,0,1e-300", "--format", "csv",
           "--method", "classic"),
      0, NULL, "0,0,-1,0.70710678118654", NULL, "INVAL", 0 },
    { "trace_huge_direction_list", "the same direction in a classic ray list (the batch)",
      NULL, NULL, NULL, "x,y,z,l,m,n\n0,0,-1,1e308,1e308,1e308\n",
      ARGS("trace", "@D", "--rays", "-", "--format", "csv", "--method", "classic"),
      0, NULL, "\n0,0,0,-1,0.577350269189625", NULL, "MISS", 0 }, /* it meets the lens */
    { "json_nul_byte", "a NUL byte at line 2, column 5 is refused there",
      "nul.json", NULL, gen_nul_design, NULL, ARGS("paraxial", "@F"), 3,
      "@F:2:5: JSON syntax error: NUL byte", NULL, NULL, NULL, 0 },
    { "json_deep_nesting", "100000 nested arrays are refused without exhausting the stack",
      "deep.json", NULL, gen_deep, NULL, ARGS("paraxial", "@F"), 3,
      "@F:1:", NULL, NULL, NULL, 0 },
    { "json_not_object", "a top-level array is not a design",
      "array.json", "[1, 2, 3]\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "must be a JSON object, got an array", NULL, NULL, NULL, 0 },

    /* ---- wrong types: exit 3, surface and field named ---- */
    { "type_thickness_string", "a quoted thickness names surface 2 and the field",
      "t1.json", HEAD OBJ S1 "    {\"radius\": -50, \"thickness\": \"45\"},\n" IMA TAIL,
      NULL, NULL, TRACE0("--format", "csv"), 3,
      "@F: surface 2: thickness: expected a number, got string \"45\"", NULL, NULL, NULL, 0 },
    { "type_stop_number", "\"stop\": 1 is not a boolean",
      "t2.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": 1},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: stop: expected true or false, got number 1", NULL, NULL, NULL, 0 },
    { "type_surfaces_object", "\"surfaces\" must be an array",
      "t3.json", "{\"surfaces\": {\"radius\": 5}}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surfaces: expected an array of surface objects, got an object", NULL, NULL, NULL, 0 },
    { "type_surface_number", "a surface that is a number, not an object",
      "t4.json", HEAD OBJ S1 "    42,\n" IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 2: expected an object, got number 42", NULL, NULL, NULL, 0 },
    { "type_um_string", "a quoted wavelength names its list entry",
      "t5.json", "{\"wavelengths\": {\"list\": [{\"um\": 0.5}, {\"um\": \"0.6\"}]},"
      " \"surfaces\": [{}, {\"stop\": true}, {}]}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "wavelengths: list[1].um: expected a number, got string \"0.6\"", NULL, NULL, NULL, 0 },
    { "type_aperture_enum", "an unknown aperture type lists the allowed ones",
      "t6.json", "{\"aperture\": {\"type\": \"diameter\"}, \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "aperture: type: expected \"epd\"", NULL, NULL, NULL, 0 },
    { "type_asphere_scalar", "\"asphere\" must be an array",
      "t7.json", HEAD OBJ "    {\"type\": \"even_asphere\", \"radius\": 50, \"thickness\": 5,"
      " \"material\": 1.5, \"stop\": true, \"asphere\": 1e-5},\n" S2 IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: asphere: expected an array of numbers, got number 1e-05", NULL, NULL, NULL, 0 },
    { "type_asphere_too_long", "nine asphere terms, one more than r^2..r^16",
      "t8.json", HEAD OBJ "    {\"type\": \"even_asphere\", \"radius\": 50, \"thickness\": 5,"
      " \"material\": 1.5, \"stop\": true, \"asphere\": [0,0,0,0,0,0,0,0,0]},\n" S2 IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: asphere: 9 terms", NULL, NULL, NULL, 0 },
    { "type_material_bool", "a material that is a boolean",
      "t9.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": true, \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: material: expected a glass name", NULL, NULL, NULL, 0 },
    { "type_units", "units must be mm, cm, in or m",
      "t10.json", "{\"units\": \"furlong\", \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3, "units: expected", NULL, NULL, NULL, 0 },
    { "type_format_name", "a foreign \"format\" string is refused",
      "t11.json", "{\"format\": \"zemax-zmx\", \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "format: expected \"sagitta-design\", got string \"zemax-zmx\"", NULL, NULL, NULL, 0 },
    { "type_newer_version", "a newer format version names both versions",
      "t12.json", "{\"version\": 8, \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "version: this is format version 8; this program reads version 7", NULL, NULL, NULL, 0 },
    { "frame_break_first", "a coordinate break as surface 1 and the stop names the surface",
      "t12b.json", "{\"surfaces\": [{}, {\"type\": \"coordinate_break\", \"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 4,
      "surface 1: a coordinate break cannot be the stop", NULL, NULL, NULL, 0 },
    { "frame_tilt_range", "a tilt beyond a turn names the surface and the tilt",
      "t12c.json", "{\"surfaces\": [{}, {\"stop\": true}, {\"before\": {\"tilt\": [0, 0, 720]}}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 4,
      "surface 2: before tilt about z 720 is beyond 360 degrees", NULL, NULL, NULL, 0 },
    { "type_primary_range", "a primary wavelength beyond the list",
      "t13.json", "{\"wavelengths\": {\"primary\": 3, \"list\": [{\"um\": 0.5}]},"
      " \"surfaces\": [{}, {\"stop\": true}, {}]}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "wavelengths: primary: 3 is not one of the wavelengths 1 to 1", NULL, NULL, NULL, 0 },

    /* ---- missing fields: exit 3 ---- */
    { "missing_surfaces", "a design without \"surfaces\"",
      "m1.json", "{\"title\": \"no surfaces key\"}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "@F: surfaces: required key is missing", NULL, NULL, NULL, 0 },
    { "missing_um", "a wavelength entry without \"um\"",
      "m2.json", "{\"wavelengths\": {\"list\": [{\"weight\": 1}]},"
      " \"surfaces\": [{}, {\"stop\": true}, {}]}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "wavelengths: list[0]: required key \"um\" is missing", NULL, NULL, NULL, 0 },
    { "missing_empty_waves", "an empty wavelength list",
      "m3.json", "{\"wavelengths\": {\"list\": []}, \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3, "wavelengths: list: is empty", NULL, NULL, NULL, 0 },

    /* ---- unknown and repeated keys: a warning, exit 0, the trace runs ---- */
    { "unknown_key_top", "an unknown top-level key is a warning; the trace still runs",
      "u1.json", "{\n  \"colour\": \"red\",\n" HEAD_KEYS OBJ S1 S2 IMA TAIL, NULL, NULL,
      TRACE0("--format", "csv"), 0,
      "sagitta: warning: @F: unknown key \"colour\" ignored", "3,0,0,", NULL, NULL, 0 },
    { "unknown_key_surface", "an unknown surface key names the surface",
      "u2.json", HEAD OBJ S1 "    {\"radius\": -50, \"thickness\": 45, \"radius_mm\": 3},\n" IMA TAIL,
      NULL, NULL, TRACE0("--format", "csv"), 0,
      "warning: @F: surface 2: unknown key \"radius_mm\" ignored", "3,0,0,", NULL, NULL, 0 },
    { "duplicate_key", "a repeated key is a warning; the last value wins",
      "u3.json", HEAD OBJ S1 "    {\"radius\": -50, \"thickness\": 1, \"thickness\": 45},\n" IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 0,
      "warning: @F: surface 2: duplicate key \"thickness\"", NULL, NULL, NULL, 0 },

    /* ---- NaN and infinity where they are not allowed: exit 3 ---- */
    { "inf_radius_1e400", "a radius of 1e400 overflows a double",
      "n1.json", HEAD OBJ "    {\"radius\": 1e400, \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: radius: the number is too large for a double", NULL, NULL, NULL, 0 },
    { "inf_thickness_1e400", "a thickness of 1e400",
      "n2.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 1e400, \"material\": 1.5, \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: thickness: must be finite", NULL, NULL, NULL, 0 },
    { "inf_thickness_word", "\"inf\" thickness is only for the object surface",
      "n3.json", HEAD OBJ S1 "    {\"radius\": -50, \"thickness\": \"inf\"},\n" IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 2: thickness: \"inf\" is allowed only on the object surface", NULL, NULL, NULL, 0 },
    { "nan_radius_word", "\"NaN\" is not a radius",
      "n4.json", HEAD OBJ "    {\"radius\": \"NaN\", \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: radius: expected a number or \"inf\", got string \"NaN\"", NULL, NULL, NULL, 0 },
    { "inf_conic", "a conic of -1e999",
      "n5.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true,"
      " \"conic\": -1e999},\n" S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: conic: must be finite", NULL, NULL, NULL, 0 },
    { "inf_asphere_term", "an asphere term of 1e400 names its index",
      "n6.json", HEAD OBJ "    {\"type\": \"even_asphere\", \"radius\": 50, \"thickness\": 5,"
      " \"material\": 1.5, \"stop\": true, \"asphere\": [0, 1e400]},\n" S2 IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: asphere[1]: must be finite", NULL, NULL, NULL, 0 },
    { "inf_index", "a fixed index of 1e400",
      "n7.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 1e400, \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: material: must be finite", NULL, NULL, NULL, 0 },
    { "inf_aperture", "an aperture value of 1e400",
      "n8.json", "{\"aperture\": {\"value\": 1e400}, \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "aperture: value: must be finite and not negative", NULL, NULL, NULL, 0 },
    { "inf_field", "a field height of 1e309 names its list entry",
      "n9.json", "{\"fields\": {\"list\": [{\"y\": 0}, {\"y\": 1e309}]},"
      " \"surfaces\": [{}, {\"stop\": true}, {}]}\n", NULL, NULL, ARGS("paraxial", "@F"), 3,
      "fields: list[1].y: must be finite", NULL, NULL, NULL, 0 },
    { "zero_wavelength", "a wavelength of 0 um",
      "n10.json", "{\"wavelengths\": {\"list\": [{\"um\": 0}]}, \"surfaces\": [{}, {\"stop\": true}, {}]}\n",
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "wavelengths: list[0].um: must be positive and finite", NULL, NULL, NULL, 0 },

    /* ---- a negative semi-diameter: exit 3 ---- */
    { "negative_sd", "a negative semi-diameter names surface and field",
      "sd.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true,"
      " \"semi_diameter\": -12.7},\n" S2 IMA TAIL, NULL, NULL, TRACE0("--format", "csv"), 3,
      "@F: surface 1: semi_diameter: must be finite and not negative, got number -12.7",
      NULL, NULL, NULL, 0 },

    /* ---- too few surfaces, stops: exit 4, "no aperture stop, too few
     * surfaces" (sagitta(1), EXIT STATUS) ---- */
    { "no_surfaces", "an empty surface list is too few surfaces (exit 4)",
      "few0.json", HEAD TAIL, NULL, NULL, ARGS("paraxial", "@F"), 4,
      "surfaces: 0 given", NULL, NULL, NULL, 0 },
    { "one_surface", "a single surface is too few surfaces (exit 4)",
      "few1.json", HEAD "    {\"thickness\": \"inf\"}\n" TAIL, NULL, NULL,
      TRACE0("--format", "csv"), 4, "surfaces: 1 given", NULL, NULL, NULL, 0 },
    { "two_surfaces", "object and image alone are too few surfaces (exit 4)",
      "few2.json", HEAD OBJ IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 4,
      "surfaces: 2 given", NULL, NULL, NULL, 0 },
    { "no_stop", "no surface marked as the stop (exit 4)",
      "nostop.json", HEAD OBJ S1NOSTOP S2 IMA TAIL, NULL, NULL, TRACE0("--format", "csv"), 4,
      "no surface has \"stop\": true", NULL, NULL, NULL, 0 },
    { "two_stops", "two stops name both surfaces (exit 4)",
      "twostops.json", HEAD OBJ S1 "    {\"radius\": -50, \"thickness\": 45, \"stop\": true},\n" IMA TAIL,
      NULL, NULL, TRACE0("--format", "csv"), 4,
      "surface 1 and surface 2 both have \"stop\": true", NULL, NULL, NULL, 0 },
    { "stop_on_object", "the object surface cannot be the stop (an invalid entry, exit 3)",
      "objstop.json", HEAD "    {\"thickness\": \"inf\", \"stop\": true},\n" S1NOSTOP S2 IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 0: stop: the object surface cannot be the aperture stop", NULL, NULL, NULL, 0 },

    /* ---- glasses: an unknown glass is exit 4; a wavelength outside a
     * glass's range is one warning ---- */
    { "unknown_glass", "an unknown glass names the surface and the glass",
      "glass.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": \"N-NOSUCH7\", \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, TRACE0("--format", "csv"), 4,
      "@F: surface 1: material \"N-NOSUCH7\" is not in the catalog", NULL, NULL, NULL, 0 },
    { "unknown_glass_escape", "a glass name with an ESC byte is shown without it",
      "glassesc.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": \"\\u001b[2J\", \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 4,
      "surface 1: material", NULL, NULL, NULL, 0 },
    { "glass_wave_range", "5 um is outside N-BK7's range: one warning, trace runs",
      "range.json", "{\"wavelengths\": {\"list\": [{\"um\": 5}]},\n \"surfaces\": [\n" OBJ
      "    {\"radius\": 50, \"thickness\": 5, \"material\": \"N-BK7\", \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, TRACE0("--format", "csv"), 0,
      "warning: @F: surface 1: wavelength 5 um is outside the range", "3,0,0,", NULL, NULL, F_ONCE },
    { "glass_wave_range_paraxial", "the same warning from paraxial, once",
      "range.json", "{\"wavelengths\": {\"list\": [{\"um\": 5}]},\n \"surfaces\": [\n" OBJ
      "    {\"radius\": 50, \"thickness\": 5, \"material\": \"N-BK7\", \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 0,
      "warning: @F: surface 1: wavelength 5 um is outside the range", "Effective focal length",
      NULL, NULL, F_ONCE },
    { "index_zero", "a fixed index of 0 is not physical (exit 4)",
      "idx0.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 0, \"stop\": true},\n"
      S2 IMA TAIL, NULL, NULL, ARGS("paraxial", "@F"), 4,
      "surface 1: material index 0 is not physical", NULL, NULL, NULL, 0 },

    /* ---- absurd sizes: refused with a message ---- */
    { "million_surfaces", "1e6 surfaces are refused, naming the limit",
      "million.json", NULL, gen_million_surfaces, NULL, ARGS("paraxial", "@F"), 3,
      "surfaces: 1000000 given; the limit is 100000", NULL, NULL, NULL, 0 },
    { "file_100mb", "a 100 MiB file is refused by its size, quickly, without reading it",
      "big.json", NULL, gen_sparse_100m, NULL, TRACE0("--format", "csv"), 3,
      "@F: the file is 104857600 bytes; the limit is", NULL, NULL, NULL, F_FAST },
    { "fields_65", "65 fields, one over the limit",
      "f65.json", NULL, gen_65_fields, NULL, ARGS("paraxial", "@F"), 3,
      "fields: list: 65 fields; the limit is 64", NULL, NULL, NULL, 0 },
    { "waves_25", "25 wavelengths, one over the limit",
      "w25.json", NULL, gen_25_waves, NULL, ARGS("paraxial", "@F"), 3,
      "wavelengths: list: 25 wavelengths; the limit is 24", NULL, NULL, NULL, 0 },
    { "title_200", "a 200-byte title",
      "title.json", NULL, gen_long_title, NULL, ARGS("paraxial", "@F"), 3,
      "title: too long (200 bytes; the limit is 127)", NULL, NULL, NULL, 0 },
    { "glass_name_long", "a 40-byte glass name",
      "gname.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"stop\": true,"
      " \"material\": \"GLASS-NAME-OF-FORTY-BYTES-0123456789ABCD\"},\n" S2 IMA TAIL,
      NULL, NULL, ARGS("paraxial", "@F"), 3,
      "surface 1: material: glass name", NULL, NULL, NULL, 0 },
    { "design_missing", "a design that does not exist",
      "absent.json", NULL, NULL, NULL, ARGS("paraxial", "@F.none"), 3,
      "@F.none: cannot open", NULL, NULL, NULL, 0 },
    { "design_directory", "a directory given as the design",
      NULL, NULL, NULL, NULL, ARGS("trace", "@E", "--ray", "0,0,0,0"), 3,
      "@E: cannot read", NULL, NULL, NULL, 0 },

    /* ---- Zemax .zmx files (issue 17): exit 3 for what cannot be read or
     *      represented, 4 for an unknown glass, the line and surface named,
     *      and import writes nothing (here: no design on standard output) ---- */
    { "zmx_coordbrk", "a coordinate break's parameter 7 (line 9) is refused there",
      "cb.zmx", ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  TYPE COORDBRK\n  PARM 7 1\n", NULL, NULL,
      ARGS("import", "@F", "-o", "-"), 3, "@F:9: surface 1: PARM 7 is 1; a coordinate break has "
      "parameters 1 to 6", NULL, NULL, "sagitta-design", 0 },
    { "zmx_obscuration", "an obscuration with a negative radius on line 9 is refused, traced",
      "obsc.zmx", ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  OBSC 0 -2 0\n", NULL, NULL,
      ARGS("trace", "@F", "--ray", "0,0,0,0"), 3, "@F:9: surface 1: OBSC: 0 and -2 must not be "
      "negative", NULL, NULL, NULL, 0 },
    { "zmx_vignetting", "an old-form vignetting factor on line 3 names its field",
      "vig.zmx", "FTYP 0 0 2 1 0 0 0\nYFLN 0 5\nZVDY 0 0.2\n", NULL, NULL,
      ARGS("paraxial", "@F"), 3, "@F:3: ZVDY: field 2", NULL, NULL, NULL, 0 },
    { "zmx_syntax", "a curvature that is not a number, line 7",
      "num.zmx", ZH "SURF 0\nSURF 1\n  CURV 1..2\n", NULL, NULL,
      ARGS("import", "@F", "-o", "-"), 3, "@F:7: surface 1: curvature: not a number", NULL,
      NULL, "sagitta-design", 0 },
    { "zmx_glass", "an unknown glass is exit 4, as in a JSON design, with its catalog",
      "glass.zmx", "GCAT ACME\n" ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n"
      "  GLAS NOGLASS 0 0 1.6 40.5\n", NULL, NULL, ARGS("import", "@F", "-o", "-"), 4,
      "@F:10: surface 1: GLAS: glass NOGLASS (from the file's catalogs ACME)", NULL, NULL,
      "sagitta-design", 0 },
    { "zmx_utf16_cut", "UTF-16 text of an odd length is refused",
      "odd.zmx", "\xFF\xFEM\0O", NULL, NULL, ARGS("import", "@F", "-o", "-"), 3,
      "odd number of bytes", NULL, NULL, "sagitta-design", 0 },
    { "zmx_scbd_flags", "a surface tilt with flags Zemax does not write (side 3), line 9",
      "scbd.zmx", ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  SCBD 3 0 0 0 0 1 0 0\n", NULL,
      NULL, ARGS("import", "@F", "-o", "-"), 3, "@F:9: surface 1: SCBD: flags 3 0 0", NULL, NULL,
      "sagitta-design", 0 },
    { "zmx_tiltsurf_curved", "a tilted surface with a curvature is refused at its TYPE line",
      "tilt.zmx", ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  TYPE TILTSURF\n  CURV 0.1\n"
      "SURF 2\n", NULL, NULL, ARGS("import", "@F", "-o", "-"), 3,
      "@F:9: surface 1: TYPE TILTSURF with a curvature", NULL, NULL, "sagitta-design", 0 },
    { "position_later", "a position solve from a later surface names both surfaces",
      "pos.json", "{\"surfaces\": [{}, {\"stop\": true}, {\"solves\": {\"thickness\": "
      "{\"type\": \"position\", \"from\": 3, \"value\": 5}}}, {}]}\n", NULL, NULL,
      ARGS("paraxial", "@F"), 4, "@F: surface 2: thickness: the position solve's reference "
      "surface 3 is not this or an earlier surface", NULL, NULL, NULL, 0 },
    { "zar_cut", "an archive whose first member's header is cut off (exit 3)",
      "cut.zar", NULL, gen_zar_cut, NULL, ARGS("import", "@F", "-o", "-"), 3,
      "@F: byte 0: an archive member's header of 648 bytes is cut off after 100", NULL, NULL,
      "sagitta-design", 0 },
    { "zar_bad_line", "a bad line of the lens file in an archive names both, and the line",
      "bad.zar", NULL, gen_zar_bad_line, NULL, ARGS("import", "@F", "-o", "-"), 3,
      "@F:L.ZMX:7: surface 1: curvature: not a number", NULL, NULL, "sagitta-design", 0 },
    { "zmx_scad", "a tilt after a surface (SCAD, line 9) is refused, not guessed",
      "scad.zmx", ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  SCAD 1 0 0 0 0 1 0 0\n", NULL,
      NULL, ARGS("import", "@F", "-o", "-"), 3, "@F:9: surface 1: SCAD: a tilt or decenter after",
      NULL, NULL, "sagitta-design", 0 },
    { "zmx_telecentric_epd", "telecentric object space (FTYP, line 1) with an EPD (line 3)",
      "tele.zmx", "FTYP 1 1 1 1 0 0 0\n" ZH "SURF 0\n  DISZ 100\nSURF 1\n  STOP\n  DISZ 5\n"
      "SURF 2\n", NULL, NULL, ARGS("import", "@F", "-o", "-"), 3,
      "@F:1: FTYP: telecentric object space with a system aperture other than the object NA "
      "or cone angle (line 3)", NULL, NULL, "sagitta-design", 0 },
    { "json_telecentric_number", "\"telecentric\" must be true or false",
      "tele1.json", "{\"aperture\": {\"type\": \"object_na\", \"value\": 0.1, \"telecentric\": 2},"
      " \"surfaces\": [{\"thickness\": 100}, {\"stop\": true}, {}]}\n", NULL, NULL,
      ARGS("paraxial", "@F"), 3, "aperture: telecentric: expected true or false, got number 2",
      NULL, NULL, NULL, 0 },
    { "json_telecentric_epd", "a telecentric object space needs an object NA (exit 4)",
      "tele2.json", "{\"aperture\": {\"type\": \"epd\", \"value\": 10, \"telecentric\": true},"
      " \"fields\": {\"type\": \"object_height\", \"list\": [{\"y\": 0}]},"
      " \"surfaces\": [{\"thickness\": 100}, {\"stop\": true}, {}]}\n", NULL, NULL,
      ARGS("paraxial", "@F"), 4, "its aperture is an object NA or cone angle, not an entrance pupil diameter",
      NULL, NULL, NULL, 0 },
    { "json_cone_90", "an object cone angle of 90 degrees (exit 4, as an NA of 1)",
      "cone.json", "{\"aperture\": {\"type\": \"object_cone_angle\", \"value\": 90},"
      " \"surfaces\": [{\"thickness\": 100}, {\"stop\": true}, {}]}\n", NULL, NULL,
      ARGS("paraxial", "@F"), 4, "aperture: object cone angle 90 must be below 90 degrees",
      NULL, NULL, NULL, 0 },
    { "json_cone_infinite", "an object cone angle with the object at infinity (exit 4)",
      "cone2.json", "{\"aperture\": {\"type\": \"object_cone_angle\", \"value\": 9},"
      " \"surfaces\": [{}, {\"stop\": true}, {}]}\n", NULL, NULL, ARGS("paraxial", "@F"), 4,
      "aperture: object-space cone angle needs an object at a finite distance", NULL, NULL,
      NULL, 0 },
    { "zmx_no_stop", "a lens file without STOP is a design error, exit 4",
      "nostop.zmx", ZH "SURF 0\n  DISZ INFINITY\nSURF 1\n  DISZ 1\nSURF 2\n", NULL, NULL,
      ARGS("import", "@F", "-o", "-"), 4, "no STOP line", NULL, NULL, "sagitta-design", 0 },

    /* ---- bad ray lists: exit 3, FILE:LINE and the column ---- */
    { "csv_bad_header", "an unknown column in the header, line 1",
      "h.csv", "hx,hy,px,pz\n0,0,0,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:1: unknown column \"pz\"", NULL, NULL, NULL, 0 },
    { "csv_repeated_column", "a repeated column",
      "rep.csv", "hx,hy,px,hx\n0,0,0,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:1: column \"hx\" appears twice", NULL, NULL, NULL, 0 },
    { "csv_missing_column", "a header without py",
      "miss.csv", "# three columns\nhx,hy,px\n0,0,0\n", NULL, NULL,
      ARGS("trace", "@D", "--rays", "@F"), 3, "@F:2: missing column \"py\"", NULL, NULL, NULL, 0 },
    { "csv_mixed_header", "normalized and start/direction columns mixed",
      "mix.csv", "hx,hy,px,py,x\n0,0,0,0,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:1: the header mixes", NULL, NULL, NULL, 0 },
    { "csv_wrong_count", "three fields under four columns, line 3",
      "count.csv", "hx,hy,px,py\n0,0,0,0\n0,0,0\n", NULL, NULL,
      ARGS("trace", "@D", "--rays", "@F"), 3, "@F:3: expected 4 fields, got 3", NULL, NULL, NULL, 0 },
    { "csv_non_number", "\"zero\" in column px of line 4",
      "word.csv", "# rays\nhx,hy,px,py\n0,0,0,0\n0,0,zero,0\n", NULL, NULL,
      ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:4: column \"px\": not a number: \"zero\"", NULL, NULL, NULL, 0 },
    { "csv_trailing_text", "\"1.5x\" is not a number",
      "tail.csv", "hx,hy,px,py\n0,0,1.5x,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: column \"px\": not a number: \"1.5x\"", NULL, NULL, NULL, 0 },
    { "csv_empty_field", "an empty field",
      "hole.csv", "hx,hy,px,py\n0,,0,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: column \"hy\": empty field", NULL, NULL, NULL, 0 },
    { "csv_nan", "nan in a ray",
      "nan.csv", "hx,hy,px,py\n0,0,nan,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: column \"px\": not a finite number", NULL, NULL, NULL, 0 },
    { "csv_overflow", "1e999 overflows",
      "ovf.csv", "hx,hy,px,py\n0,0,0,1e999\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: column \"py\": out of range", NULL, NULL, NULL, 0 },
    { "csv_zero_direction", "a zero direction",
      "zdir.csv", "x,y,z,l,m,n\n0,0,-1,0,0,0\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: direction (l, m, n) is zero", NULL, NULL, NULL, 0 },
    { "csv_empty", "an empty ray file",
      "empty.csv", "", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F: no header row", NULL, NULL, NULL, 0 },
    { "csv_header_only", "a header and no rays",
      "hdr.csv", "# nothing\nhx,hy,px,py\n\n", NULL, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F: no rays after the header", NULL, NULL, NULL, 0 },
    { "csv_huge_line", "a field of a million digits is refused, shortened in the message",
      "long.csv", NULL, gen_csv_huge_line, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: column \"hx\": not a number", NULL, NULL, "1111111111111111111111111111111111111111111111111", 0 },
    { "csv_wide_line", "a line of a million fields",
      "wide.csv", NULL, gen_csv_wide, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: expected 4 fields, got 1000001", NULL, NULL, NULL, 0 },
    { "csv_utf8_bom", "a UTF-8 byte order mark before the header is skipped",
      "bom.csv", "\xEF\xBB\xBFhx,hy,px,py\n0,0,0,0\n", NULL, NULL,
      ARGS("trace", "@D", "--rays", "@F"), 0, NULL, NULL, NULL, "unknown column", 0 },
    { "csv_utf16", "a ray list in UTF-16 is named so, with how to convert it",
      "u16.csv", NULL, gen_utf16_csv, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F: the file is UTF-16 text (byte order mark FF FE)", NULL, NULL, NULL, 0 },
    { "csv_nul", "a NUL byte in line 2",
      "nul.csv", NULL, gen_csv_nul, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:2: NUL byte", NULL, NULL, NULL, 0 },
    { "csv_sparse_100mb", "a 100 MiB file of NUL bytes is refused at line 1",
      "big.csv", NULL, gen_sparse_100m, NULL, ARGS("trace", "@D", "--rays", "@F"), 3,
      "@F:1: NUL byte", NULL, NULL, NULL, 0 },
    { "csv_stdin", "a bad list on standard input is named <stdin>",
      NULL, NULL, NULL, "hx,hy\n0,0\n", ARGS("trace", "@D", "--rays", "-"), 3,
      "<stdin>:1: missing column \"px\"", NULL, NULL, NULL, 0 },
    { "csv_missing", "a ray file that does not exist",
      "absent.csv", NULL, NULL, NULL, ARGS("trace", "@D", "--rays", "@F.none"), 3,
      "@F.none", NULL, NULL, NULL, 0 },
    /* Not in the table: "--rays /dev/zero".  The reader has no size limit,
     * so it allocates until the machine runs out of memory (reported to
     * the lead; ui/csvrays.c, csvrays_read). */

    /* ---- bad command-line values: exit 2, the option named ---- */
    { "cli_ray_three", "--ray 0,1,x: three items where four are needed",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,1,x"), 2,
      "sagitta: --ray: expected 4 comma-separated numbers Hx,Hy,Px,Py, got \"0,1,x\"",
      NULL, NULL, NULL, 0 },
    { "cli_ray_word", "--ray 0,1,0,x names Py",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,1,0,x"), 2,
      "(Py: not a number)", NULL, NULL, NULL, 0 },
    { "cli_ray_empty", "--ray with an empty value",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray="), 2, "--ray", NULL, NULL, NULL, 0 },
    { "cli_ray_overflow", "--ray 0,0,0,1e999",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,1e999"), 2,
      "(Py: out of range)", NULL, NULL, NULL, 0 },
    { "cli_ray_inf", "--ray inf,0,0,0",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "inf,0,0,0"), 2,
      "(Hx: not a finite number)", NULL, NULL, NULL, 0 },
    { "cli_bits_10", "--bits 10 is below 53",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--method", "mpfr", "--bits", "10"), 2,
      "--bits: expected an integer from 53 to 100000, got \"10\"", NULL, NULL, NULL, 0 },
    { "cli_wave_99", "--wave 99 is beyond any design",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--wave", "99"), 2,
      "--wave: expected an integer from 1 to 24, got \"99\"", NULL, NULL, NULL, 0 },
    { "cli_wave_design", "--wave 4 on a design of 3 wavelengths",
      NULL, NULL, NULL, NULL, ARGS("paraxial", "@E/singlet.json", "--wave", "4"), 2,
      "--wave 4: @E/singlet.json has 3 wavelengths", NULL, NULL, NULL, 0 },
    { "cli_format_xml", "--format xml",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--format", "xml"), 2,
      "--format: expected text, csv, json or hdf5, got \"xml\"", NULL, NULL, NULL, 0 },
    { "cli_paraxial_csv", "paraxial has no csv format",
      NULL, NULL, NULL, NULL, ARGS("paraxial", "@D", "--format", "csv"), 2,
      "--format: expected text or json", NULL, NULL, NULL, 0 },
    { "cli_method", "--method fast",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--method", "fast"), 2,
      "--method: expected precise, classic or mpfr, got \"fast\"", NULL, NULL, NULL, 0 },
    { "cli_threads", "--threads -1",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--rays", "-", "--threads", "-1"), 2,
      "--threads: expected an integer from 0 to 4096", NULL, NULL, NULL, 0 },
    { "cli_unknown_option", "an unknown option",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--frobnicate"), 2,
      "sagitta: trace: unknown option --frobnicate", NULL, NULL, NULL, 0 },
    { "cli_missing_value", "--method without its value",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--method"), 2,
      "--method needs a value", NULL, NULL, NULL, 0 },
    { "cli_missing_design", "trace without a design",
      NULL, NULL, NULL, NULL, ARGS("trace", "--ray", "0,0,0,0"), 2,
      "sagitta: trace: missing DESIGN.json", NULL, NULL, NULL, 0 },
    { "cli_paraxial_no_design", "paraxial without a design",
      NULL, NULL, NULL, NULL, ARGS("paraxial"), 2,
      "sagitta: paraxial: missing DESIGN.json", NULL, NULL, NULL, 0 },
    { "cli_no_ray", "trace without a ray",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D"), 2, "give a ray with --ray", NULL, NULL, NULL, 0 },
    { "cli_two_sources", "--ray and --rays together",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "--rays", "-"), 2,
      "give only one of", NULL, NULL, NULL, 0 },
    { "cli_zero_dir", "--dir 0,0,0",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--start", "0,0,-1", "--dir", "0,0,0"), 2,
      "--dir: the direction 0,0,0 is zero", NULL, NULL, NULL, 0 },
    { "cli_unknown_command", "an unknown command",
      NULL, NULL, NULL, NULL, ARGS("tracee"), 2, "unknown command \"tracee\"", NULL, NULL, NULL, 0 },
    { "cli_output_dir", "-o into a directory that does not exist",
      NULL, NULL, NULL, NULL, ARGS("trace", "@D", "--ray", "0,0,0,0", "-o", "@T/no/such/dir.csv"), 3,
      "@T/no/such/dir.csv", NULL, NULL, NULL, 0 },

    /* ---- physical failures: a per-surface status, exit 0 ---- */
    { "ray_miss", "a ray 15 mm off axis misses a sphere of radius 10: MISS on surface 1",
      "miss.json", HEAD OBJ "    {\"radius\": 10, \"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
      "    {\"radius\": -10, \"thickness\": 45},\n" IMA TAIL, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,15,-1", "--dir", "0,0,1", "--format", "csv"), 0,
      NULL, "\n1,,,,,,,,,,MISS,,\n2,,,,,,,,,,NOT REACHED,,\n", NULL, NULL, 0 },
    /* Inside index 1.5 the ray meets a sphere of radius 10 at height 8:
     * sin(i) = 0.8 > 1/1.5, so it is totally internally reflected. */
    { "ray_tir", "sin(i) = 0.8 inside index 1.5: TIR on surface 2",
      "tir.json", HEAD OBJ "    {\"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
      "    {\"radius\": -10, \"thickness\": 45},\n" IMA TAIL, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,8,-1", "--dir", "0,0,1", "--format", "csv"), 0,
      NULL, "\n2,,,,,,,,,,TIR,,\n3,,,,,,,,,,NOT REACHED,,\n", NULL, NULL, 0 },
    { "ray_tir_text", "the same TIR in the text report",
      "tir.json", HEAD OBJ "    {\"thickness\": 5, \"material\": 1.5, \"stop\": true},\n"
      "    {\"radius\": -10, \"thickness\": 45},\n" IMA TAIL, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,8,-1", "--dir", "0,0,1"), 0,
      NULL, "TIR at surface 2", NULL, "undefined", 0 },
    /* The asphere z = r^2 (flat base, a2 = 1): a ray leaving (0, 1, 0)
     * along (0, 1, 0.1) stays below it for ever (z = 0.1 (y - 1) < y^2),
     * so the intersection has no root and Newton cannot converge. */
#define WILD_ASPHERE                                                          \
    HEAD OBJ "    {\"type\": \"even_asphere\", \"thickness\": 5, \"asphere\": [1], \"stop\": true},\n" \
    "    {\"thickness\": 45},\n" IMA TAIL
    { "asphere_noconv_precise", "a ray that never meets z = r^2: UNCERT or MISS, no hang",
      "wild.json", WILD_ASPHERE, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,1,0", "--dir", "0,1,0.1", "--format", "csv"), 0,
      NULL, "\n1,,,,,,,,,,UNCERT,,\n", "\n1,,,,,,,,,,MISS,,\n", NULL, 0 },
    { "asphere_noconv_classic", "the same with --method classic",
      "wild.json", WILD_ASPHERE, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,1,0", "--dir", "0,1,0.1", "--format", "csv",
           "--method", "classic"), 0,
      NULL, "\n1,,,,,,,,,,NOCONV,,\n", "\n1,,,,,,,,,,MISS,,\n", NULL, 0 },
    { "asphere_noconv_mpfr", "the same with --method mpfr",
      "wild.json", WILD_ASPHERE, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,1,0", "--dir", "0,1,0.1", "--format", "csv",
           "--method", "mpfr"), 0,
      NULL, "\n1,,,,,,,,,,NOCONV,,\n", "\n1,,,,,,,,,,MISS,,\n", NULL, 0 },
    { "aim_impossible_precise", "paraxial aiming at an unreachable stop height: AIM FAILED",
      "aim.json", HEAD_AIM("paraxial", "10") AIM_LENS, NULL, NULL,
      ARGS("trace", "@F", "--ray", "0,0,0,1", "--format", "csv"), 0,
      NULL, "\n0,0,0,1,0,,,,,,,,,,AIM FAILED,,,,,,\n0,0,0,1,1,,,,,,,,,,NOT REACHED,,,,,,\n", NULL, NULL, 0 },
    { "aim_impossible_classic", "the same with --method classic",
      "aim.json", HEAD_AIM("paraxial", "10") AIM_LENS, NULL, NULL,
      ARGS("trace", "@F", "--ray", "0,0,0,1", "--format", "csv", "--method", "classic"), 0,
      NULL, "\n0,0,0,1,0,,,,,,,,,,AIM FAILED,,,,,,\n0,0,0,1,1,,,,,,,,,,NOT REACHED,,,,,,\n", NULL, NULL, 0 },
    { "aim_impossible_mpfr", "the same with --method mpfr",
      "aim.json", HEAD_AIM("paraxial", "10") AIM_LENS, NULL, NULL,
      ARGS("trace", "@F", "--ray", "0,0,0,1", "--format", "csv", "--method", "mpfr"), 0,
      NULL, "\n0,0,0,1,0,,,,,,,,,,AIM FAILED,,,,,,\n0,0,0,1,1,,,,,,,,,,NOT REACHED,,,,,,\n", NULL, NULL, 0 },
    { "aim_batch", "a batch mixing AIM FAILED and traced rays, 2 threads",
      "aim.json", HEAD_AIM("paraxial", "10") AIM_LENS, NULL,
      "hx,hy,px,py\n0,0,0,1\n0,0,0,0\n", ARGS("trace", "@F", "--rays", "-", "--threads", "2",
                                           "--format", "csv"), 0,
      NULL, "\n0,0,0,0,1,0,,,,,,,,,,AIM FAILED,,,,,,\n", NULL, NULL, 0 }, /* ray, launch, surface */
    /* With real aiming and EPD 100 the on-axis marginal ray (height 50)
     * misses the R 20 sphere, so the tracer cannot size the stop: the
     * design cannot be traced as set up (exit 4), not an internal error. */
    { "aim_real_no_stop", "real aiming whose marginal ray misses: exit 4, names the stop",
      "aimreal.json", HEAD_AIM("real", "100") AIM_LENS, NULL, NULL,
      ARGS("trace", "@F", "--ray", "0,0,0,1", "--format", "csv"), 4,
      "ray aiming: the on-axis marginal ray does not reach the stop (surface 3)", NULL, NULL,
      NULL, 0 },
    { "vignetted", "a ray beyond a fixed semi-diameter of 5: VIGNETTED on surface 1",
      "vig.json", HEAD OBJ "    {\"radius\": 50, \"thickness\": 5, \"material\": 1.5, \"stop\": true,"
      " \"semi_diameter\": 5, \"sd_fixed\": true},\n" S2 IMA TAIL, NULL, NULL,
      ARGS("trace", "@F", "--start", "0,8,-1", "--dir", "0,0,1", "--format", "csv"), 0,
      NULL, "\n1,,,,,,,,,,VIGNETTED,,\n", NULL, NULL, 0 },
    /* The image surface lies on the last lens (thickness 0), so the chief
     * ray's paraxial height there is 0 for every field angle and a field
     * given as a paraxial image height has no angle: refusing the design
     * (exit 4) or failing the ray are both answers; NaN numbers are not. */
#define NO_IMAGE_HEIGHT                                                       \
    "{\"aperture\": {\"type\": \"paraxial_working_fnum\", \"value\": 4},\n"      \
    " \"fields\": {\"type\": \"paraxial_image_height\", \"list\": [{\"y\": 2}]},\n" \
    " \"surfaces\": [{}, {\"material\": 1.6, \"stop\": true}, {\"radius\": -20}, {}]}\n"
    { "degenerate_image_height", "a field in image height on a system with no image height",
      "noheight.json", NO_IMAGE_HEIGHT, NULL, NULL, ARGS("trace", "@F", "--ray", "0,1,0,1"), 4,
      NULL, NULL, NULL, "undefined", F_OR_0 },
    { "degenerate_image_height_mpfr", "the same with --method mpfr",
      "noheight.json", NO_IMAGE_HEIGHT, NULL, NULL,
      ARGS("trace", "@F", "--ray", "0,1,0,1", "--method", "mpfr"), 4,
      NULL, NULL, NULL, "undefined", F_OR_0 },
    /* Surface 1 sends the light back 100 mm, so the stop (surface 2) lies
     * on the object plane: the entrance pupil is at the object and no
     * finite ray joins an object point to a pupil point. */
#define PUPIL_AT_OBJECT                                                       \
    "{\"surfaces\": [{\"thickness\": 100}, {\"thickness\": -100},\n"          \
    "  {\"stop\": true, \"thickness\": 50}, {}]}\n"
    { "pupil_at_object", "an entrance pupil on the object plane: no NaN numbers",
      "pupobj.json", PUPIL_AT_OBJECT, NULL, NULL, ARGS("trace", "@F", "--ray", "0,0,0,1"), 4,
      NULL, NULL, NULL, "undefined", F_OR_0 },
    { "pupil_at_object_paraxial", "the same design's paraxial data: no NaN numbers",
      "pupobj.json", PUPIL_AT_OBJECT, NULL, NULL, ARGS("paraxial", "@F"), 4,
      NULL, NULL, NULL, "undefined", F_OR_0 },
    { "long_system_numbers", "2202 surfaces: every OK surface has numbers, never NaN",
      "long.json", NULL, gen_long_system, NULL,
      ARGS("trace", "@F", "--ray", "0,0,0,0.1"), 0,
      NULL, "Status      : OK", NULL, "undefined", 0 },
};

#define NCASES (sizeof cases / sizeof cases[0])

/* ------------------------------------------------------------- the runner */

static const char *exe_path;
static char tmpdir[512];
/* The outputs of the last case, kept here so that a failing check, which
 * leaves run_case by a long jump, does not leak them. */
static char *last_out, *last_err;
static char examples[1024];
static char good_design[1100];

/* Replaces @F, @D, @E and @T in s. */
static void expand(char *dst, size_t n, const char *s, const char *file)
{
    size_t k = 0;
    dst[0] = '\0';
    for (; *s && k + 1 < n; s++) {
        const char *rep = NULL;
        if (s[0] == '@') {
            switch (s[1]) {
            case 'F': rep = file ? file : "(no file)"; break;
            case 'D': rep = good_design; break;
            case 'E': rep = examples; break;
            case 'T': rep = tmpdir; break;
            default: break;
            }
        }
        if (rep) {
            int w = snprintf(dst + k, n - k, "%s", rep);
            assert_true(w >= 0 && (size_t)w < n - k);
            k += (size_t)w;
            s++;
        } else {
            dst[k++] = *s;
            dst[k] = '\0';
        }
    }
    assert_true(*s == '\0');
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    size_t n = 0, cap = 0, got;
    assert_non_null(f);
    do {
        if (cap - n < 65536) {
            cap = cap ? 2 * cap : 65536;
            buf = realloc(buf, cap + 1);
            assert_non_null(buf);
        }
        got = fread(buf + n, 1, cap - n, f);
        n += got;
    } while (got > 0);
    fclose(f);
    buf[n] = '\0';
    *len = n;
    return buf;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static size_t count_of(const char *hay, const char *needle)
{
    size_t n = 0, len = strlen(needle);
    const char *p = hay;
    while ((p = strstr(p, needle)) != NULL) {
        n++;
        p += len;
    }
    return n;
}

/* The first control byte other than a newline, or -1.  Messages quote
 * what they read from files, and a file must not drive the terminal. */
static int control_byte(const char *s, size_t n)
{
    size_t k;
    for (k = 0; k < n; k++) {
        unsigned char c = (unsigned char)s[k];
        if ((c < 0x20 && c != '\n') || c == 0x7f)
            return c;
    }
    return -1;
}

static void run_case(void **state)
{
    const bad_case *c = *state;
    char file[1024], argbuf[16][1200], needle[1400], stdin_path[1100];
    char outp[1100], errp[1100];
    const char *argv[20];
    const char *file_p = NULL;
    posix_spawn_file_actions_t fa;
    struct rusage ru;
    char *out, *err;
    size_t outn, errn;
    double t0, t1, sleep_s = 0.001;
    pid_t pid, w;
    int n = 0, k, st = 0, rc, ctl, hung = 0;

    snprintf(outp, sizeof outp, "%s/stdout", tmpdir);
    snprintf(errp, sizeof errp, "%s/stderr", tmpdir);
    snprintf(stdin_path, sizeof stdin_path, "%s/stdin", tmpdir);
    if (c->file) {
        snprintf(file, sizeof file, "%s/%s", tmpdir, c->file);
        file_p = file;
        if (c->text)
            write_or_die(file, c->text, strlen(c->text));
        else if (c->gen)
            c->gen(file);
    }
    if (c->stdin_text)
        write_or_die(stdin_path, c->stdin_text, strlen(c->stdin_text));

    argv[n++] = exe_path;
    for (k = 0; c->args[k]; k++) {
        expand(argbuf[k], sizeof argbuf[k], c->args[k], file_p);
        argv[n++] = argbuf[k];
    }
    argv[n] = NULL;

    assert_int_equal(posix_spawn_file_actions_init(&fa), 0);
    posix_spawn_file_actions_addopen(&fa, 0, c->stdin_text ? stdin_path : "/dev/null",
                                     O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, outp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    posix_spawn_file_actions_addopen(&fa, 2, errp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    t0 = now_s();
    rc = posix_spawn(&pid, exe_path, &fa, NULL, (char *const *)argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0)
        fail_msg("%s: cannot run %s: %s", c->name, exe_path, strerror(rc));

    /* Poll so that a hang is caught by the deadline, not by meson. */
    for (;;) {
        memset(&ru, 0, sizeof ru);
        w = wait4(pid, &st, WNOHANG, &ru);
        if (w == pid)
            break;
        if (w < 0 && errno != EINTR)
            fail_msg("%s: wait4: %s", c->name, strerror(errno));
        if (now_s() - t0 > CASE_TIMEOUT_S) {
            kill(pid, SIGKILL);
            while (wait4(pid, &st, 0, &ru) < 0 && errno == EINTR)
                ;
            hung = 1;
            break;
        }
        {
            struct timespec ts = {0, (long)(sleep_s * 1e9)};
            nanosleep(&ts, NULL);
            if (sleep_s < 0.02)
                sleep_s *= 2;
        }
    }
    t1 = now_s();
    free(last_out);
    free(last_err);
    last_out = out = slurp(outp, &outn);
    last_err = err = slurp(errp, &errn);

    if (hung)
        fail_msg("%s: no answer within %.0f s (a hang); stderr so far:\n%.2000s", c->name,
                 CASE_TIMEOUT_S, err);
    if (WIFSIGNALED(st))
        fail_msg("%s: killed by signal %d (%s); stderr:\n%.2000s", c->name, WTERMSIG(st),
                 strsignal(WTERMSIG(st)), err);
    assert_true(WIFEXITED(st));
    if (WEXITSTATUS(st) != c->code && !((c->flags & F_OR_0) && WEXITSTATUS(st) == 0))
        fail_msg("%s: exit %d, expected %d (%s); stderr:\n%.2000s", c->name, WEXITSTATUS(st),
                 c->code, c->what, err);
    if (WEXITSTATUS(st) != 0) {
        if (strncmp(err, "sagitta: ", 9) != 0)
            fail_msg("%s: the message lacks the \"sagitta: \" prefix:\n%.2000s", c->name, err);
        if (outn != 0)
            fail_msg("%s: failed but wrote %zu bytes to standard output", c->name, outn);
    }
    if (c->err_has) {
        expand(needle, sizeof needle, c->err_has, file_p);
        if (!strstr(err, needle))
            fail_msg("%s: stderr lacks \"%s\":\n%.2000s", c->name, needle, err);
        if ((c->flags & F_ONCE) && count_of(err, needle) != 1)
            fail_msg("%s: \"%s\" appears %zu times, expected once:\n%.2000s", c->name, needle,
                     count_of(err, needle), err);
    }
    if (c->out_has && !strstr(out, c->out_has) && !(c->out_alt && strstr(out, c->out_alt)))
        fail_msg("%s: stdout lacks \"%s\"%s%s%s:\n%.2000s", c->name, c->out_has,
                 c->out_alt ? " (or \"" : "", c->out_alt ? c->out_alt : "",
                 c->out_alt ? "\")" : "", out);
    if (c->forbid && (strstr(out, c->forbid) || strstr(err, c->forbid)))
        fail_msg("%s: output contains \"%s\" (%s)", c->name, c->forbid, c->what);
    ctl = control_byte(err, errn);
    if (ctl >= 0)
        fail_msg("%s: stderr contains the control byte 0x%02x:\n%.2000s", c->name, ctl, err);
    if (c->flags & F_FAST) {
        if (t1 - t0 > FAST_SECONDS)
            fail_msg("%s: took %.2f s; a refusal by size must not read the file", c->name,
                     t1 - t0);
        if (ru.ru_maxrss > FAST_MAX_RSS_KB)
            fail_msg("%s: peak memory %ld KiB; a refusal by size must not read the file",
                     c->name, ru.ru_maxrss);
    }
    print_message("# %s: %s -> exit %d as documented, %.3f s, %ld KiB; %.*s\n", c->name,
                  c->what, WEXITSTATUS(st), t1 - t0, ru.ru_maxrss,
                  (int)strcspn(errn ? err : out, "\n"), errn ? err : out);
    if (c->file)
        remove(file);
}

/* The good design (@D) every command-line and ray-file case traces. */
static int group_setup(void **state)
{
    const char *src = getenv("SAGITTA_SOURCE_ROOT");
    const char *ex = getenv("SAGITTA_EXAMPLES");
    const char *base = getenv("TMPDIR");
    (void)state;
    snprintf(tmpdir, sizeof tmpdir, "%s/sagitta-robust-XXXXXX", base && *base ? base : "/tmp");
    if (!mkdtemp(tmpdir))
        return -1;
    if (ex && *ex)
        snprintf(examples, sizeof examples, "%s", ex);
    else
        snprintf(examples, sizeof examples, "%s/examples", src && *src ? src : ".");
    snprintf(good_design, sizeof good_design, "%s/good.json", tmpdir);
    {
        FILE *f = fopen(good_design, "wb");
        if (!f || fputs(SINGLET, f) < 0 || fclose(f) != 0)
            return -1;
    }
    return 0;
}

/* Removes what the cases wrote, including the inputs of failed cases. */
static int group_teardown(void **state)
{
    DIR *dir = opendir(tmpdir);
    struct dirent *e;
    char p[1400];
    (void)state;
    free(last_out);
    free(last_err);
    last_out = last_err = NULL;
    if (dir) {
        while ((e = readdir(dir)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            snprintf(p, sizeof p, "%s/%s", tmpdir, e->d_name);
            remove(p);
        }
        closedir(dir);
    }
    return rmdir(tmpdir) == 0 ? 0 : -1;
}

int main(int argc, char **argv)
{
    static struct CMUnitTest tests[NCASES];
    size_t k;
    if (argc < 2) {
        fprintf(stderr, "usage: %s PATH-TO-SAGITTA\n", argv[0]);
        return 1;
    }
    exe_path = argv[1];
    for (k = 0; k < NCASES; k++) {
        tests[k].name = cases[k].name;
        tests[k].test_func = run_case;
        tests[k].setup_func = NULL;
        tests[k].teardown_func = NULL;
        tests[k].initial_state = (void *)&cases[k];
    }
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
