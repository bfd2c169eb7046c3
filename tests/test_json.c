/*
 * test_json.c - the JSON design format: exact numbers, defaults, bit-exact
 * round trips, every error with its place, warnings, atomic saves and the
 * bundled examples.
 *
 * Expected values come from the hand-written texts here (the C compiler's own
 * reading of the same literals), from sagitta-design(5) and from the
 * published prescriptions cited in the examples, never from the program.
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testutil.h"

/* A scratch directory for the files the tests write. */
static char scratch[256];

static const char *scratch_path(const char *name, char *buf, size_t n)
{
    snprintf(buf, n, "%s/%s", scratch, name);
    return buf;
}

static void remove_tree(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return;
    if (S_ISDIR(st.st_mode)) {
        DIR *dir = opendir(path);
        struct dirent *e;
        if (dir) {
            while ((e = readdir(dir)) != NULL) {
                char sub[1024];
                if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                    continue;
                snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
                remove_tree(sub);
            }
            closedir(dir);
        }
        rmdir(path);
    } else {
        unlink(path);
    }
}

static int group_setup(void **state)
{
    const char *base = getenv("TMPDIR");
    snprintf(scratch, sizeof scratch, "%s/sg_test_json_XXXXXX", base ? base : "/tmp");
    if (!mkdtemp(scratch))
        return -1;
    (void)state;
    return 0;
}

static int group_teardown(void **state)
{
    remove_tree(scratch);
    (void)state;
    return 0;
}

static int parse_text(sg_system *sys, const char *text, sg_diag *d)
{
    sg_diag_clear(d);
    return sg_design_parse(sys, text, strlen(text), "t.json", d);
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(fputs(text, f) >= 0, 1);
    assert_int_equal(fclose(f), 0);
}

/* The whole file, or NULL when it cannot be read. */
static char *read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *buf;
    long n;
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    if (buf)
        buf[n] = '\0';
    fclose(f);
    return buf;
}

/* Entries of the scratch directory whose names start with prefix. */
static int count_prefixed(const char *dirpath, const char *prefix)
{
    DIR *dir = opendir(dirpath);
    struct dirent *e;
    int n = 0;
    if (!dir)
        return -1;
    while ((e = readdir(dir)) != NULL)
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0)
            n++;
    closedir(dir);
    return n;
}

/* Compares every value of two systems bit for bit; *ndoubles counts the
 * doubles compared.  Returns NULL or a description of the first mismatch. */
static const char *system_diff(const sg_system *a, const sg_system *b, long *ndoubles,
                               char *buf, size_t n)
{
    int i, k;
    long cnt = 0;
#define DBL(x, y, ...)                                                                 \
    do {                                                                               \
        cnt++;                                                                         \
        if (!same_bits((x), (y))) {                                                    \
            snprintf(buf, n, __VA_ARGS__);                                             \
            goto differ;                                                               \
        }                                                                              \
    } while (0)
#define INT(x, y, what)                                                                \
    do {                                                                               \
        if ((x) != (y)) {                                                              \
            snprintf(buf, n, "%s: %d vs %d", what, (int)(x), (int)(y));                \
            goto differ;                                                               \
        }                                                                              \
    } while (0)
    if (strcmp(a->title, b->title) != 0 || strcmp(a->units, b->units) != 0) {
        snprintf(buf, n, "title or units differ");
        goto differ;
    }
    INT(a->nwave, b->nwave, "nwave");
    INT(a->primary_wave, b->primary_wave, "primary");
    for (k = 0; k < a->nwave; k++) {
        DBL(a->wave[k].um, b->wave[k].um, "wave %d um", k);
        DBL(a->wave[k].weight, b->wave[k].weight, "wave %d weight", k);
    }
    INT(a->field_type, b->field_type, "field type");
    INT(a->field_norm, b->field_norm, "field norm");
    INT(a->nfield, b->nfield, "nfield");
    for (k = 0; k < a->nfield; k++) {
        DBL(a->field[k].x, b->field[k].x, "field %d x", k);
        DBL(a->field[k].y, b->field[k].y, "field %d y", k);
        DBL(a->field[k].weight, b->field[k].weight, "field %d weight", k);
    }
    INT(a->aper_type, b->aper_type, "aperture type");
    DBL(a->aper_value, b->aper_value, "aperture value");
    INT(a->aim, b->aim, "aim");
    INT(a->stop, b->stop, "stop");
    INT(a->nsurf, b->nsurf, "nsurf");
    for (i = 0; i < a->nsurf; i++) {
        const sg_surface *s = &a->surf[i], *t = &b->surf[i];
        INT(s->type, t->type, "type");
        if (strcmp(s->comment, t->comment) != 0) {
            snprintf(buf, n, "surface %d comment", i);
            goto differ;
        }
        DBL(s->radius, t->radius, "surface %d radius %.17g vs %.17g", i, s->radius, t->radius);
        DBL(s->thickness, t->thickness, "surface %d thickness", i);
        INT(s->mat.kind, t->mat.kind, "material kind");
        if (s->mat.kind == SG_MAT_GLASS && strcmp(s->mat.name, t->mat.name) != 0) {
            snprintf(buf, n, "surface %d glass %s vs %s", i, s->mat.name, t->mat.name);
            goto differ;
        }
        if (s->mat.kind == SG_MAT_INDEX)
            DBL(s->mat.index, t->mat.index, "surface %d index", i);
        DBL(s->semi_diameter, t->semi_diameter, "surface %d semi-diameter", i);
        INT(!!s->sd_fixed, !!t->sd_fixed, "sd_fixed");
        DBL(s->conic, t->conic, "surface %d conic", i);
        for (k = 0; k < SG_NASPH; k++)
            DBL(s->asph[k], t->asph[k], "surface %d asphere[%d] %.17g vs %.17g", i, k,
                s->asph[k], t->asph[k]);
    }
#undef DBL
#undef INT
    if (ndoubles)
        *ndoubles += cnt;
    return NULL;
differ:
    if (ndoubles)
        *ndoubles += cnt;
    return buf;
}

/* ------------------------------------------------------------------------ */

static const char known_text[] =
    "{\n"
    "  \"format\": \"sagitta-design\",\n"
    "  \"version\": 1,\n"
    "  \"title\": \"known values\",\n"
    "  \"units\": \"in\",\n"
    "  \"wavelengths\": { \"primary\": 3, \"list\": [ {\"um\": 0.4861327},\n"
    "      {\"um\": 0.5875618, \"weight\": 2}, {\"um\": 0.6562725, \"weight\": 0.5} ] },\n"
    "  \"fields\": { \"type\": \"object_height\", \"normalization\": \"rectangular\",\n"
    "      \"list\": [ {\"y\": 0}, {\"x\": -1.25, \"y\": 4e6, \"weight\": 0} ] },\n"
    "  \"aperture\": { \"type\": \"image_fnum\", \"value\": 3.5 },\n"
    "  \"ray_aiming\": \"real\",\n"
    "  \"surfaces\": [\n"
    "    { \"thickness\": \"inf\" },\n"
    "    { \"radius\": -10478.5, \"thickness\": 2.5e-3, \"material\": \"n-bk7\",\n"
    "      \"semi_diameter\": 12.7, \"sd_fixed\": true, \"comment\": \"front\" },\n"
    "    { \"type\": \"even_asphere\", \"radius\": \"-inf\", \"thickness\": -0.0,\n"
    "      \"material\": 1.5, \"conic\": -1, \"asphere\": [0, 1e-5, -2.5e-9], \"stop\": true },\n"
    "    { \"radius\": 0, \"material\": \"MIRROR\", \"thickness\": -40 },\n"
    "    { \"radius\": \"Infinity\", \"material\": \"air\", \"thickness\": 0.1 },\n"
    "    { \"material\": \"\" }\n"
    "  ]\n"
    "}\n";

static void test_known_values(void **state)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    int k, checks = 0;
    (void)state;
    assert_non_null(s);
    assert_int_equal(parse_text(s, known_text, &d), SG_OK);
    assert_int_equal(d.nwarn, 0);

#define EQD(a, b)                                                                      \
    do {                                                                               \
        assert_true(same_bits((a), (b)));                                              \
        checks++;                                                                      \
    } while (0)
    /* The compiler's reading of each literal, and strtod's, are the truth. */
    EQD(s->surf[1].radius, -10478.5);
    EQD(s->surf[1].radius, strtod("-10478.5", NULL));
    EQD(s->surf[1].thickness, 2.5e-3);
    EQD(s->surf[1].thickness, strtod("2.5e-3", NULL));
    EQD(s->surf[1].semi_diameter, 12.7);
    EQD(s->wave[0].um, 0.4861327);
    EQD(s->wave[1].um, 0.5875618);
    EQD(s->wave[2].um, 0.6562725);
    EQD(s->wave[0].weight, 1.0);
    EQD(s->wave[1].weight, 2.0);
    EQD(s->wave[2].weight, 0.5);
    EQD(s->field[0].x, 0.0);
    EQD(s->field[0].y, 0.0);
    EQD(s->field[0].weight, 1.0);
    EQD(s->field[1].x, -1.25);
    EQD(s->field[1].y, 4e6);
    EQD(s->field[1].weight, 0.0);
    EQD(s->aper_value, 3.5);
    EQD(s->surf[2].thickness, -0.0);
    assert_true(signbit(s->surf[2].thickness));
    EQD(s->surf[2].mat.index, 1.5);
    EQD(s->surf[2].conic, -1.0);
    EQD(s->surf[2].asph[0], 0.0);
    EQD(s->surf[2].asph[1], 1e-5);
    EQD(s->surf[2].asph[2], -2.5e-9);
    for (k = 3; k < SG_NASPH; k++)
        EQD(s->surf[2].asph[k], 0.0);
    EQD(s->surf[3].thickness, -40.0);
    EQD(s->surf[4].thickness, 0.1);
#undef EQD
    assert_true(isinf(s->surf[0].thickness) && s->surf[0].thickness > 0);
    assert_true(isinf(s->surf[0].radius) && s->surf[0].radius > 0);
    assert_true(isinf(s->surf[2].radius) && s->surf[2].radius < 0);
    assert_true(isinf(s->surf[3].radius) && s->surf[3].radius > 0); /* 0 means flat */
    assert_true(isinf(s->surf[4].radius) && s->surf[4].radius > 0);
    assert_string_equal(s->title, "known values");
    assert_string_equal(s->units, "in");
    assert_int_equal(s->nwave, 3);
    assert_int_equal(s->primary_wave, 2); /* 1-based 3 in the file */
    assert_int_equal(s->field_type, SG_FIELD_OBJECT_HEIGHT);
    assert_int_equal(s->field_norm, SG_NORM_RECT);
    assert_int_equal(s->nfield, 2);
    assert_int_equal(s->aper_type, SG_APER_IMAGE_FNUM);
    assert_int_equal(s->aim, SG_AIM_REAL);
    assert_int_equal(s->nsurf, 6);
    assert_int_equal(s->stop, 2);
    assert_string_equal(s->surf[1].comment, "front");
    assert_int_equal(s->surf[1].mat.kind, SG_MAT_GLASS);
    assert_string_equal(s->surf[1].mat.name, "N-BK7");
    assert_true(s->surf[1].sd_fixed);
    assert_int_equal(s->surf[2].type, SG_SURF_EVENASPH);
    assert_int_equal(s->surf[2].mat.kind, SG_MAT_INDEX);
    assert_int_equal(s->surf[3].mat.kind, SG_MAT_MIRROR);
    assert_int_equal(s->surf[4].mat.kind, SG_MAT_AIR);
    assert_int_equal(s->surf[5].mat.kind, SG_MAT_AIR);
    assert_int_equal(s->surf[0].type, SG_SURF_STANDARD);
    print_message("# known values: %d doubles equal bit for bit to the compiler's and "
                  "strtod's reading of the literals; worst difference 0 ulp\n", checks);
    print_message("# known values: \"inf\", \"-inf\", \"Infinity\" and 0 read as flat; "
                  "materials, enums, 1-based primary and stop read as documented\n");
    sg_system_free(s);
}

static void test_defaults(void **state)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    int i, k;
    (void)state;
    assert_int_equal(parse_text(s, "{\"surfaces\": [{}, {\"stop\": true}, {}]}", &d), SG_OK);
    /* The defaults listed in sagitta-design(5). */
    assert_string_equal(s->title, "");
    assert_string_equal(s->units, "mm");
    assert_int_equal(s->nwave, 1);
    assert_true(same_bits(s->wave[0].um, 0.5875618));
    assert_true(same_bits(s->wave[0].weight, 1.0));
    assert_int_equal(s->primary_wave, 0);
    assert_int_equal(s->field_type, SG_FIELD_ANGLE);
    assert_int_equal(s->field_norm, SG_NORM_RADIAL);
    assert_int_equal(s->nfield, 1);
    assert_true(same_bits(s->field[0].x, 0.0) && same_bits(s->field[0].y, 0.0));
    assert_true(same_bits(s->field[0].weight, 1.0));
    assert_int_equal(s->aper_type, SG_APER_EPD);
    assert_true(same_bits(s->aper_value, 10.0));
    assert_int_equal(s->aim, SG_AIM_OFF);
    assert_int_equal(s->nsurf, 3);
    assert_int_equal(s->stop, 1);
    for (i = 0; i < 3; i++) {
        const sg_surface *f = &s->surf[i];
        assert_int_equal(f->type, SG_SURF_STANDARD);
        assert_string_equal(f->comment, "");
        assert_true(isinf(f->radius) && f->radius > 0);
        if (i == 0)
            assert_true(isinf(f->thickness) && f->thickness > 0);
        else
            assert_true(same_bits(f->thickness, 0.0));
        assert_int_equal(f->mat.kind, SG_MAT_AIR);
        assert_true(same_bits(f->semi_diameter, 0.0));
        assert_false(f->sd_fixed);
        assert_true(same_bits(f->conic, 0.0));
        for (k = 0; k < SG_NASPH; k++)
            assert_true(same_bits(f->asph[k], 0.0));
    }
    print_message("# defaults: 3-surface minimal design matches every default in "
                  "sagitta-design(5) (object thickness inf, others 0)\n");
    sg_system_free(s);
}

/* ------------------------------------------------------------------------ */

static uint64_t splitmix64(uint64_t *st)
{
    uint64_t z = (*st += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Random finite doubles from random bit patterns; a quarter of them have a
 * zero exponent field, so subnormals and signed zeros come up often. */
static double random_double(uint64_t *st)
{
    for (;;) {
        uint64_t b = splitmix64(st), pick = splitmix64(st);
        double x;
        if ((pick & 3) == 0)
            b &= 0x800FFFFFFFFFFFFFull;
        if ((pick & 0x3c) == 0)
            b &= 0x8000000000000000ull; /* +-0 */
        memcpy(&x, &b, sizeof x);
        if (isfinite(x))
            return x;
    }
}

static const double special[] = {
    -0.0, 0.0, DBL_TRUE_MIN, -DBL_TRUE_MIN, DBL_MIN, -DBL_MIN, 2.2250738585072009e-308,
    DBL_MAX, -DBL_MAX, 0.1, 1.0 / 3.0, 5e-324, 1e23, 9007199254740993.0, 0.5875618,
    -10478.5, 1e-300, 4.9406564584124654e-320};

static void test_roundtrip_random(void **state)
{
    uint64_t st = 0x73616769747461ull; /* fixed seed: "sagitta" */
    char path[512], why[160];
    long total = 0, subnormal = 0, negzero = 0;
    int round, i, k, nspecial = (int)(sizeof special / sizeof special[0]), used = 0;
    (void)state;
    scratch_path("roundtrip.json", path, sizeof path);
    for (round = 0; round < 12; round++) {
        sg_system *a = sg_system_new(), *b = sg_system_new();
        sg_diag d;
        char *t1, *t2;
        const char *diff;
        assert_int_equal(sg_system_reset(a, 40), SG_OK);
        a->stop = 1 + round % 38;
        snprintf(a->title, sizeof a->title, "round %d \"quoted\" \\ tab\t \xc3\xa9", round);
        a->nwave = SG_MAX_WAVES;
        a->primary_wave = round % SG_MAX_WAVES;
        for (k = 0; k < a->nwave; k++) {
            double u;
            do
                u = fabs(random_double(&st));
            while (!(u > 0.0));
            a->wave[k].um = u;
            a->wave[k].weight = fabs(random_double(&st));
        }
        a->nfield = SG_MAX_FIELDS;
        for (k = 0; k < a->nfield; k++) {
            a->field[k].x = random_double(&st);
            a->field[k].y = random_double(&st);
            a->field[k].weight = fabs(random_double(&st));
        }
        a->aper_value = fabs(random_double(&st));
        for (i = 0; i < a->nsurf; i++) {
            sg_surface *s = &a->surf[i];
            double r;
            s->type = (sg_surf_type)(i % 2);
            snprintf(s->comment, sizeof s->comment, "s%d \x01 \"%d\"", i, round);
            r = random_double(&st);
            /* A zero radius reads back as flat (documented), so it is
             * written as INFINITY here to keep the comparison exact; a
             * radius whose curvature overflows (|r| < 1/DBL_MAX) is
             * refused on load (sagitta-design(5)), so it is flat too. */
            s->radius = r == 0.0 || !isfinite(1.0 / r) ? INFINITY : r;
            s->thickness = i == 0 && round % 2 ? INFINITY : random_double(&st);
            s->semi_diameter = fabs(random_double(&st));
            s->sd_fixed = (int)(splitmix64(&st) & 1);
            s->conic = random_double(&st);
            for (k = 0; k < SG_NASPH; k++) {
                if (used < nspecial && (k + i) % 3 == 0)
                    s->asph[k] = special[used++];
                else
                    s->asph[k] = random_double(&st);
            }
            switch (i % 4) {
            case 0:
                s->mat.kind = SG_MAT_AIR;
                break;
            case 1:
                s->mat.kind = SG_MAT_GLASS;
                snprintf(s->mat.name, sizeof s->mat.name, "N-BK%d", i);
                break;
            case 2:
                s->mat.kind = SG_MAT_INDEX;
                s->mat.index = random_double(&st);
                break;
            default:
                s->mat.kind = SG_MAT_MIRROR;
                break;
            }
            for (k = 0; k < SG_NASPH; k++) {
                if (s->asph[k] != 0.0 && fabs(s->asph[k]) < DBL_MIN)
                    subnormal++;
                if (s->asph[k] == 0.0 && signbit(s->asph[k]))
                    negzero++;
            }
            /* The mount's TCE: within its limits, 0 (not written) on every
             * third surface. */
            s->tce = i % 3 ? ldexp((double)(splitmix64(&st) >> 11), -53) * 2000.0 - 1000.0
                           : 0.0;
            if (s->conic != 0.0 && fabs(s->conic) < DBL_MIN)
                subnormal++;
            if (s->conic == 0.0 && signbit(s->conic))
                negzero++;
        }
        sg_diag_clear(&d);
        assert_int_equal(sg_design_save(a, path, &d), SG_OK);
        sg_diag_clear(&d);
        if (sg_design_load(b, path, &d) != SG_OK)
            fail_msg("round %d: load failed: %s", round, d.msg);
        diff = system_diff(a, b, &total, why, sizeof why);
        if (diff)
            fail_msg("round %d: %s", round, diff);
        /* The text is stable too: saving what was loaded writes the same bytes. */
        t1 = sg_design_to_json(a);
        t2 = sg_design_to_json(b);
        assert_non_null(t1);
        assert_non_null(t2);
        assert_string_equal(t1, t2);
        free(t1);
        free(t2);
        sg_system_free(a);
        sg_system_free(b);
    }
    assert_true(subnormal > 0);
    assert_true(negzero > 0);
    print_message("# round trip: %ld doubles over 12 random systems (40 surfaces, 24 waves, "
                  "64 fields) saved, loaded and compared with memcmp: 0 differ\n", total);
    print_message("# round trip: included %ld subnormal and %ld -0.0 values, %d special values "
                  "(DBL_MAX, DBL_TRUE_MIN, ...); worst difference 0 ulp\n",
                  subnormal, negzero, used);
}

/* ------------------------------------------------------------------------ */

static void expect_syntax(const char *text, size_t len, const char *want)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    int rc;
    sg_diag_clear(&d);
    rc = sg_design_parse(s, text, len, "t.json", &d);
    if (rc != SG_EPARSE || strstr(d.msg, want) == NULL)
        fail_msg("expected SG_EPARSE with \"%s\", got %s: %s", want, sg_err_name(rc), d.msg);
    print_message("# syntax: %-26s -> %s\n", want, d.msg);
    sg_system_free(s);
}

static void test_syntax_errors(void **state)
{
    /* Each error is placed by hand; line and column are counted from the
     * text (columns in bytes from 1). */
    static const char at[] = "{\n"
                             "  \"title\": \"syntax\",\n"
                             "  \"surfaces\": [\n"
                             "    {},\n"
                             "    { \"stop\": true, \"radius\": @ },\n"
                             "    {}\n"
                             "  ]\n"
                             "}\n";
    static const char commas[] = "{\n"
                                 "  \"surfaces\": [\n"
                                 "    {\"asphere\": [1, 2,, 3]},\n"
                                 "    {}, {}]}\n";
    static const char cut[] = "{\n  \"surfaces\": [\n    {}";
    static const char trailing[] = "{\"surfaces\": []} x";
    static const char crlf[] = "{\r\n  \"a\": @\r\n}";
    static const char nul[] = "{\"title\": \"a\"}\0 {";
    (void)state;
    /* Sanity checks that the hand counts point at the intended bytes. */
    assert_int_equal(strstr(at, "@") - strstr(at, "    { \"stop\""), 30);
    expect_syntax(at, strlen(at), "t.json:5:31: JSON syntax error near '@ },'");
    expect_syntax(commas, strlen(commas), "t.json:3:23: JSON syntax error near ', 3]},'");
    expect_syntax(cut, strlen(cut), "t.json:3:7: JSON syntax error near end of input");
    expect_syntax(trailing, strlen(trailing), "t.json:1:18: JSON syntax error near 'x'");
    expect_syntax(crlf, strlen(crlf), "t.json:2:8: JSON syntax error near '@'");
    expect_syntax(nul, sizeof nul - 1, "t.json:1:15: JSON syntax error: NUL byte");
    expect_syntax("", 0, "t.json:1:1: JSON syntax error near end of input");
}

/* ------------------------------------------------------------------------ */

#define S3 "\"surfaces\": [{}, {\"stop\": true}, {}]"

typedef struct err_case {
    const char *text;
    int code;
    const char *want;
} err_case;

static const err_case err_cases[] = {
    {"{\"surfaces\": [{}, {}, {\"stop\": true}, {\"radius\": \"abc\"}, {}]}", SG_EPARSE,
     "t.json: surface 3: radius: expected a number or \"inf\", got string \"abc\""},
    {"{\"fields\": {\"list\": [{}, {}, {\"y\": \"up\"}]}, " S3 "}", SG_EPARSE,
     "t.json: fields: list[2].y: expected a number, got string \"up\""},
    {"{\"wavelengths\": {\"list\": [{\"um\": -0.5}]}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: list[0].um: must be positive and finite"},
    {"{\"wavelengths\": {\"list\": [{\"um\": 1e400}]}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: list[0].um: must be positive and finite"},
    {"{\"wavelengths\": {\"list\": [{\"weight\": 1}]}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: list[0]: required key \"um\" is missing"},
    {"{\"wavelengths\": {\"list\": [{\"um\": 0.5, \"weight\": -1}]}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: list[0].weight: must be finite and not negative"},
    {"{\"wavelengths\": {\"list\": []}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: list: is empty"},
    {"{\"wavelengths\": {\"primary\": 2, \"list\": [{\"um\": 0.5}]}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: primary: 2 is not one of the wavelengths 1 to 1"},
    {"{\"wavelengths\": {\"primary\": 0}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: primary: 0 is not one of"},
    {"{\"wavelengths\": {\"primary\": 1.5}, " S3 "}", SG_EPARSE,
     "t.json: wavelengths: primary: expected an integer, got number 1.5"},
    {"{\"fields\": {\"list\": []}, " S3 "}", SG_EPARSE, "t.json: fields: list: is empty"},
    {"{\"fields\": {\"list\": [{\"weight\": -2}]}, " S3 "}", SG_EPARSE,
     "t.json: fields: list[0].weight: must be finite and not negative"},
    {"{\"fields\": {\"list\": [{\"x\": 1e999}]}, " S3 "}", SG_EPARSE,
     "t.json: fields: list[0].x: must be finite"},
    {"{\"fields\": {\"type\": \"height\"}, " S3 "}", SG_EPARSE,
     "t.json: fields: type: expected \"angle\", \"object_height\", \"paraxial_image_height\" or "
     "\"real_image_height\", got string \"height\""},
    {"{\"fields\": {\"normalization\": 1}, " S3 "}", SG_EPARSE,
     "t.json: fields: normalization: expected \"radial\" or \"rectangular\", got number 1"},
    {"{\"aperture\": {\"type\": \"fnum\"}, " S3 "}", SG_EPARSE, "t.json: aperture: type:"},
    {"{\"aperture\": {\"value\": -3}, " S3 "}", SG_EPARSE,
     "t.json: aperture: value: must be finite and not negative"},
    {"{\"ray_aiming\": true, " S3 "}", SG_EPARSE,
     "t.json: ray_aiming: expected \"off\", \"paraxial\" or \"real\", got true"},
    {"{\"units\": \"km\", " S3 "}", SG_EPARSE, "t.json: units: expected \"mm\", \"cm\", \"in\" or \"m\""},
    {"{\"title\": 7, " S3 "}", SG_EPARSE, "t.json: title: expected a string, got number 7"},
    {"{\"format\": \"zemax\", " S3 "}", SG_EPARSE,
     "t.json: format: expected \"sagitta-design\", got string \"zemax\""},
    {"{\"version\": 8, " S3 "}", SG_EUNSUPPORTED, "t.json: version: this is format version 8; this program reads version 7 and older"},
    {"{\"version\": \"1\", " S3 "}", SG_EPARSE, "t.json: version: expected an integer"},
    {"{\"title\": \"no surfaces\"}", SG_EPARSE, "t.json: surfaces: required key is missing"},
    {"{\"surfaces\": {}}", SG_EPARSE, "t.json: surfaces: expected an array"},
    {"[1, 2]", SG_EPARSE, "t.json: the document must be a JSON object, got an array"},
    {"{\"surfaces\": [{}, {\"stop\": true}]}", SG_ENOSYS, "t.json: surfaces: 2 given"},
    {"{\"surfaces\": []}", SG_ENOSYS, "t.json: surfaces: 0 given"},
    {"{\"surfaces\": [{}, {}, {}]}", SG_ENOSTOP, "t.json: surfaces: no surface has \"stop\": true"},
    {"{\"surfaces\": [{}, {\"stop\": true}, {}, {\"stop\": true}, {}]}", SG_ETWOSTOPS,
     "t.json: surfaces: surface 1 and surface 3 both have \"stop\": true"},
    {"{\"surfaces\": [{\"stop\": true}, {}, {}]}", SG_EPARSE,
     "t.json: surface 0: stop: the object surface cannot be the aperture stop"},
    {"{\"surfaces\": [{}, {}, {\"stop\": true}]}", SG_EPARSE,
     "t.json: surface 2: stop: the image surface cannot be the aperture stop"},
    {"{\"surfaces\": [{}, {\"stop\": 1}, {}]}", SG_EPARSE,
     "t.json: surface 1: stop: expected true or false, got number 1"},
    {"{\"surfaces\": [{}, {\"stop\": true}, 5]}", SG_EPARSE,
     "t.json: surface 2: expected an object, got number 5"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"thickness\": \"inf\"}, {}]}", SG_EPARSE,
     "t.json: surface 1: thickness: \"inf\" is allowed only on the object surface"},
    {"{\"surfaces\": [{\"thickness\": \"-inf\"}, {\"stop\": true}, {}]}", SG_EPARSE,
     "t.json: surface 0: thickness: expected a number or \"inf\", got string \"-inf\""},
    {"{\"surfaces\": [{}, {\"stop\": true, \"thickness\": 2e308}, {}]}", SG_EPARSE,
     "t.json: surface 1: thickness: must be finite"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"radius\": -1e309}, {}]}", SG_EPARSE,
     "t.json: surface 1: radius: the number is too large for a double"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"radius\": null}, {}]}", SG_EPARSE,
     "t.json: surface 1: radius: expected a number or \"inf\", got null"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"conic\": 1e400}, {}]}", SG_EPARSE,
     "t.json: surface 1: conic: must be finite"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"semi_diameter\": -1}, {}]}", SG_EPARSE,
     "t.json: surface 1: semi_diameter: must be finite and not negative, got number -1"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"sd_fixed\": \"yes\"}, {}]}", SG_EPARSE,
     "t.json: surface 1: sd_fixed: expected true or false, got string \"yes\""},
    {"{\"surfaces\": [{}, {\"stop\": true, \"type\": \"toroid\"}, {}]}", SG_EPARSE,
     "t.json: surface 1: type: expected \"standard\", \"even_asphere\", \"coordinate_break\", "
     "\"odd_asphere\", \"toroidal\", \"biconic\", \"zernike_fringe\", \"zernike_standard\", "
     "\"xy_polynomial\", \"q_type_asphere\", \"paraxial\", \"diffraction_grating\", "
     "\"binary_2\" or \"zernike_fringe_phase\", got string \"toroid\""},
    /* Coordinate breaks and tilts: each message names the surface and key. */
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"break\": {\"tilt\": [1, 2, 3]}}, {}]}", SG_EPARSE,
     "t.json: surface 2: break: only a coordinate_break has a break; use \"before\""},
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"type\": \"coordinate_break\", \"before\": {}}, {}]}",
     SG_EPARSE, "t.json: surface 2: before: a coordinate_break takes its change as \"break\""},
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"type\": \"coordinate_break\", \"break\": {\"tilt\": [1, 2]}}, {}]}",
     SG_EPARSE, "t.json: surface 2: break: tilt: expected an array of 3 numbers, got an array"},
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"type\": \"coordinate_break\", \"break\": {\"decenter\": [1, \"a\"]}}, {}]}",
     SG_EPARSE, "t.json: surface 2: break: decenter[1]: expected a number, got string \"a\""},
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"type\": \"coordinate_break\", \"break\": {\"order\": \"x\"}}, {}]}",
     SG_EPARSE, "t.json: surface 2: break: order: expected \"decenter_then_tilt\" or \"tilt_then_decenter\""},
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"after\": \"rev\"}, {}]}", SG_EPARSE,
     "t.json: surface 2: after: expected \"reverse\" or an object"},
    {"{\"surfaces\": [{}, {\"stop\": true}, {\"type\": \"coordinate_break\", \"after\": {}}, {}]}",
     SG_EPARSE, "t.json: surface 2: after: a coordinate_break has no after change"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"material\": true}, {}]}", SG_EPARSE,
     "t.json: surface 1: material: expected a glass name"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"material\": 1e400}, {}]}", SG_EPARSE,
     "t.json: surface 1: material: must be finite"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"asphere\": [1, 2, 3, 4, 5, 6, 7, 8, 9]}, {}]}",
     SG_EPARSE, "t.json: surface 1: asphere: 9 terms; at most 8"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"asphere\": [1, \"x\"]}, {}]}", SG_EPARSE,
     "t.json: surface 1: asphere[1]: expected a number, got string \"x\""},
    {"{\"surfaces\": [{}, {\"stop\": true, \"asphere\": 0}, {}]}", SG_EPARSE,
     "t.json: surface 1: asphere: expected an array of numbers, got number 0"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"comment\": "
     "\"0123456789012345678901234567890123456789012345678901234567890123\"}, {}]}",
     SG_EPARSE, "t.json: surface 1: comment: too long (64 bytes; the limit is 63)"},
    {"{\"surfaces\": [{}, {\"stop\": true, \"material\": \"GLASS-NAME-THAT-IS-32-BYTES-LONG\"}, {}]}",
     SG_EPARSE, "t.json: surface 1: material: glass name \"GLASS-NAME-THAT-IS-32-BYTES-LONG\" is "
                "too long (32 bytes; the limit is 31)"},
};

/* A long title (128 bytes) and the limits of the lists are built at run time. */
static char *repeat_doc(const char *head, const char *item, int n, const char *tail)
{
    size_t len = strlen(head) + (size_t)n * (strlen(item) + 2) + strlen(tail) + 1;
    char *p = malloc(len);
    int i;
    assert_non_null(p);
    strcpy(p, head);
    for (i = 0; i < n; i++) {
        if (i)
            strcat(p, ", ");
        strcat(p, item);
    }
    strcat(p, tail);
    return p;
}

/* Checks code and message, and that the target system was not touched. */
static void expect_error(const char *text, int code, const char *want)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    int rc;
    assert_non_null(s);
    snprintf(s->title, sizeof s->title, "SENTINEL");
    s->surf[1].radius = 42.0;
    rc = parse_text(s, text, &d);
    if (rc != code || strstr(d.msg, want) == NULL)
        fail_msg("expected %s with \"%s\", got %s: %s", sg_err_name(code), want,
                 sg_err_name(rc), d.msg);
    assert_int_equal(d.code, code);
    assert_string_equal(s->title, "SENTINEL");
    assert_int_equal(s->nsurf, 3);
    assert_true(same_bits(s->surf[1].radius, 42.0));
    assert_true(same_bits(s->surf[1].thickness, 10.0));
    print_message("# %-15s %s\n", sg_err_name(rc), d.msg);
    sg_system_free(s);
}

/* The environment and model glasses read, write and read back unchanged;
 * bad values name their key. */
static void test_environment_and_model(void **state)
{
    static const char text[] =
        "{ \"format\": \"sagitta-design\", \"temperature\": 35.5, \"pressure\": 0.8,\n"
        "  \"adjust_index\": true,\n"
        "  \"surfaces\": [ { \"thickness\": \"inf\" },\n"
        "    { \"radius\": 50, \"thickness\": 5, \"stop\": true,\n"
        "      \"material\": { \"nd\": 1.5168, \"vd\": 64.17, \"dpgf\": -0.0009 } },\n"
        "    { \"thickness\": 40 }, {} ] }\n";
    sg_system *s = sg_system_new(), *r = sg_system_new();
    sg_diag d;
    char *out;
    (void)state;
    assert_int_equal(parse_text(s, text, &d), SG_OK);
    assert_true(s->temperature == 35.5 && s->pressure == 0.8 && s->adjust_index == 1);
    assert_int_equal(s->surf[1].mat.kind, SG_MAT_MODEL);
    assert_true(s->surf[1].mat.index == 1.5168 && s->surf[1].mat.vd == 64.17 &&
                s->surf[1].mat.dpgf == -0.0009);
    out = sg_design_to_json(s);
    assert_non_null(out);
    assert_int_equal(parse_text(r, out, &d), SG_OK);
    assert_true(same_bits(r->temperature, 35.5) && same_bits(r->pressure, 0.8) &&
                r->adjust_index == 1);
    assert_int_equal(r->surf[1].mat.kind, SG_MAT_MODEL);
    assert_true(same_bits(r->surf[1].mat.index, 1.5168) && same_bits(r->surf[1].mat.vd, 64.17) &&
                same_bits(r->surf[1].mat.dpgf, -0.0009));
    free(out);
    /* Defaults are not written, so older designs save as before. */
    sg_system_free(r);
    r = sg_system_new();
    out = sg_design_to_json(r);
    assert_null(strstr(out, "temperature"));
    assert_null(strstr(out, "adjust_index"));
    free(out);
    assert_true(r->temperature == 20.0 && r->pressure == 1.0 && r->adjust_index == 0);
    sg_system_free(s);
    sg_system_free(r);

    expect_error("{\"temperature\": -300, \"surfaces\": [{}, {\"stop\": true}, {}]}", SG_ERANGE,
                 "temperature: -300 C is outside -250 to 1000 C");
    expect_error("{\"pressure\": -1, \"surfaces\": [{}, {\"stop\": true}, {}]}", SG_EPARSE,
                 "pressure");
    expect_error("{\"pressure\": 101, \"surfaces\": [{}, {\"stop\": true}, {}]}", SG_ERANGE,
                 "pressure: 101 atm is outside 0 to 100 atm");
    expect_error("{\"adjust_index\": 1, \"surfaces\": [{}, {\"stop\": true}, {}]}", SG_EPARSE,
                 "adjust_index: expected true or false");
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"material\": {\"nd\": 1.5}}, {}]}",
                 SG_EPARSE, "a model glass needs \"nd\" and \"vd\"");
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"material\": {\"nd\": 1.5, \"vd\": 2}},"
                 " {}]}", SG_ERANGE, "model glass nd 1.5, vd 2");
}

/* A glass named with its catalog (format version 4) reads, writes and
 * reads back; without a catalog the file stays as older versions wrote
 * it; bad values name their key. */
static void test_catalog_glass(void **state)
{
    static const char text[] =
        "{ \"format\": \"sagitta-design\",\n"
        "  \"surfaces\": [ { \"thickness\": \"inf\" },\n"
        "    { \"radius\": 50, \"thickness\": 5, \"stop\": true,\n"
        "      \"material\": { \"glass\": \"baf2\", \"catalog\": \"hoya\" } },\n"
        "    { \"radius\": -50, \"thickness\": 3, \"material\": { \"glass\": \"F2\" } },\n"
        "    { \"thickness\": 40 }, {} ] }\n";
    sg_system *s = sg_system_new(), *r = sg_system_new();
    sg_diag d;
    char *out;
    (void)state;
    assert_int_equal(parse_text(s, text, &d), SG_OK);
    assert_int_equal(s->surf[1].mat.kind, SG_MAT_GLASS);
    assert_string_equal(s->surf[1].mat.name, "BAF2");
    assert_string_equal(s->surf[1].mat.catalog, "HOYA");
    assert_string_equal(s->surf[2].mat.name, "F2");
    assert_string_equal(s->surf[2].mat.catalog, "");
    out = sg_design_to_json(s);
    assert_non_null(out);
    assert_non_null(strstr(out, "\"version\": 4"));
    assert_non_null(strstr(out, "{ \"glass\": \"BAF2\", \"catalog\": \"HOYA\" }"));
    assert_non_null(strstr(out, "\"material\": \"F2\""));
    assert_int_equal(parse_text(r, out, &d), SG_OK);
    assert_true(sg_system_equal(s, r));
    /* The catalog is part of the design: another makes another design. */
    snprintf(r->surf[1].mat.catalog, sizeof r->surf[1].mat.catalog, "CDGM");
    assert_false(sg_system_equal(s, r));
    free(out);
    s->surf[1].mat.catalog[0] = '\0';
    out = sg_design_to_json(s);
    assert_non_null(strstr(out, "\"version\": 1"));
    free(out);
    sg_system_free(s);
    sg_system_free(r);

    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"material\": {\"glass\": 7}}, {}]}",
                 SG_EPARSE, "surface 1: material.glass: expected a glass name, got number 7");
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"material\": {\"glass\": \"\"}}, {}]}",
                 SG_EPARSE, "material.glass: expected a glass name");
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"material\": {\"glass\": \"F2\", "
                 "\"catalog\": [1]}}, {}]}",
                 SG_EPARSE, "surface 1: material.catalog: expected a catalog name, got");
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"material\": {\"glass\": \"F2\", "
                 "\"catalog\": \"ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789\"}}, {}]}",
                 SG_EPARSE, "catalog name \"ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789\" is too long");
}

/* A frame change whose values are all zero but whose order is set moves
 * nothing, yet it is the user's setting: a save and load keeps it (it was
 * once dropped, and sg_system_equal then told the two apart). */
static void test_frame_order_kept(void **state)
{
    static const char text[] =
        "{ \"format\": \"sagitta-design\",\n"
        "  \"surfaces\": [ { \"thickness\": \"inf\" },\n"
        "    { \"radius\": 50, \"thickness\": 5, \"stop\": true },\n"
        "    { \"radius\": -50, \"thickness\": 40 }, {} ] }\n";
    sg_system *s = sg_system_new(), *r = sg_system_new();
    sg_diag d;
    char *out;
    (void)state;
    assert_int_equal(parse_text(s, text, &d), SG_OK);
    s->surf[1].before.order = 1;
    s->surf[2].after.order = 1;
    out = sg_design_to_json(s);
    assert_non_null(out);
    assert_null(strstr(out, "\"version\": 1"));
    assert_int_equal(parse_text(r, out, &d), SG_OK);
    assert_int_equal(r->surf[1].before.order, 1);
    assert_int_equal(r->surf[2].after.order, 1);
    assert_true(sg_system_equal(s, r));
    free(out);
    sg_system_free(s);
    sg_system_free(r);
}

/* The shapes beyond the even asphere (format version 3) read, write and
 * read back bit for bit; only the keys a surface uses are written; bad
 * values name the surface and key. */
static void test_shapes(void **state)
{
    static const char text[] =
        "{ \"format\": \"sagitta-design\",\n"
        "  \"surfaces\": [ { \"thickness\": \"inf\" },\n"
        "    { \"type\": \"odd_asphere\", \"radius\": 50, \"thickness\": 5, \"stop\": true,\n"
        "      \"odd\": [1e-3, -2e-4, 3e-6], \"material\": \"N-BK7\" },\n"
        "    { \"type\": \"toroidal\", \"radius\": -40, \"radius_x\": -35.5, \"conic\": -0.5,\n"
        "      \"asphere\": [0, 1e-7], \"thickness\": 2 },\n"
        "    { \"type\": \"biconic\", \"radius\": 80, \"radius_x\": \"inf\", \"conic_x\": -1,\n"
        "      \"thickness\": 3, \"material\": \"N-BK7\" },\n"
        "    { \"type\": \"zernike_fringe\", \"radius\": -70, \"norm_radius\": 12.5,\n"
        "      \"terms\": [0, 0, 0, 1e-3, 2e-4, 0, 0, 3e-5], \"thickness\": 4 },\n"
        "    { \"type\": \"zernike_standard\", \"norm_radius\": 11, \"terms\": [0, 1e-4, 0, 2e-3],\n"
        "      \"zernike_decenter_x\": -2.5, \"zernike_decenter_y\": 0.375, \"thickness\": 4 },\n"
        "    { \"type\": \"xy_polynomial\", \"radius\": 300, \"norm_radius\": 10,\n"
        "      \"terms\": [0, 0, 1e-3, 0, -2e-3, 0, 4e-5], \"thickness\": 30 }, {} ] }\n";
    sg_system *s = sg_system_new(), *r = sg_system_new();
    sg_diag d;
    char *out;
    (void)state;
    assert_int_equal(parse_text(s, text, &d), SG_OK);
    assert_int_equal(s->surf[1].type, SG_SURF_ODDASPH);
    assert_true(s->surf[1].odd[1] == -2e-4);
    assert_int_equal(s->surf[2].type, SG_SURF_TOROIDAL);
    assert_true(s->surf[2].radius_x == -35.5 && s->surf[2].asph[1] == 1e-7);
    assert_int_equal(s->surf[3].type, SG_SURF_BICONIC);
    assert_true(isinf(s->surf[3].radius_x) && s->surf[3].conic_x == -1.0);
    assert_int_equal(s->surf[4].type, SG_SURF_ZERNIKE_FRINGE);
    assert_true(s->surf[4].norm_radius == 12.5 && s->surf[4].terms[7] == 3e-5);
    assert_int_equal(s->surf[5].type, SG_SURF_ZERNIKE_STANDARD);
    assert_true(s->surf[5].zern_dx == -2.5 && s->surf[5].zern_dy == 0.375);
    assert_true(s->surf[4].zern_dx == 0.0 && s->surf[4].zern_dy == 0.0);
    assert_int_equal(s->surf[6].type, SG_SURF_XYPOLY);
    assert_true(s->surf[6].terms[6] == 4e-5);
    out = sg_design_to_json(s);
    assert_non_null(out);
    assert_non_null(strstr(out, "\"version\": 3"));
    assert_int_equal(parse_text(r, out, &d), SG_OK);
    assert_true(sg_system_equal(s, r));
    /* The decenters are written where they are set, and only there. */
    {
        const char *x = strstr(out, "\"zernike_decenter_x\": -2.5");
        assert_non_null(x);
        assert_null(strstr(x + 4, "zernike_decenter_x"));
        assert_true(strstr(out, "zernike_decenter_x") == x + 1);
        assert_non_null(strstr(out, "\"zernike_decenter_y\": 0.375"));
    }
    free(out);
    /* A design without the new shapes is still written as version 1 or 2. */
    sg_system_free(r);
    r = sg_system_new();
    out = sg_design_to_json(r);
    assert_null(strstr(out, "\"version\": 3"));
    assert_null(strstr(out, "norm_radius"));
    assert_null(strstr(out, "terms"));
    assert_null(strstr(out, "zernike_decenter"));
    free(out);
    sg_system_free(s);
    sg_system_free(r);

    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"type\": \"toric\"}, {}]}", SG_EPARSE,
                 "surface 1: type: expected");
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"type\": \"xy_polynomial\", "
                 "\"norm_radius\": 0}, {}]}", SG_EPARSE, "norm_radius");
    /* What only the shape knows, sg_system_validate asks it. */
    {
        static const char *const bad[][2] = {
            {"{\"surfaces\": [{}, {\"stop\": true, \"type\": \"zernike_fringe\", \"terms\": ["
             "0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,1]},"
             " {}]}", "surface 1: Fringe Zernike term 38; there are 37"},
            {"{\"surfaces\": [{}, {\"stop\": true, \"type\": \"toroidal\", "
             "\"asphere\": [0,0,0,0,0,0,0,1]}, {}]}", "surface 1: a toroid's y curve has terms "
             "up to y^14; the y^16 term must be 0"}};
        size_t b;
        for (b = 0; b < sizeof bad / sizeof bad[0]; b++) {
            s = sg_system_new();
            assert_int_equal(parse_text(s, bad[b][0], &d), SG_OK);
            sg_diag_clear(&d);
            assert_int_equal(sg_system_validate(s, NULL, &d), SG_ERANGE);
            if (!strstr(d.msg, bad[b][1]))
                fail_msg("expected \"%s\", got \"%s\"", bad[b][1], d.msg);
            print_message("# %s\n", d.msg);
            sg_system_free(s);
        }
    }
    expect_error("{\"surfaces\": [{}, {\"stop\": true, \"terms\": [" 
                 "0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,0,0,0,"
                 "0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,0,0,0,0, 0,0,0,0,0,0,1]}, "
                 "{}]}", SG_EPARSE, "67 terms; at most 66");
}

static void test_content_errors(void **state)
{
    size_t i;
    char *doc;
    char title[200];
    int n = 0;
    (void)state;
    for (i = 0; i < sizeof err_cases / sizeof err_cases[0]; i++, n++)
        expect_error(err_cases[i].text, err_cases[i].code, err_cases[i].want);

    memset(title, 'T', 128);
    title[128] = '\0';
    doc = malloc(400);
    assert_non_null(doc);
    snprintf(doc, 400, "{\"title\": \"%s\", " S3 "}", title);
    expect_error(doc, SG_EPARSE, "t.json: title: too long (128 bytes; the limit is 127)");
    free(doc);
    n++;

    doc = repeat_doc("{\"wavelengths\": {\"list\": [", "{\"um\": 0.5}", SG_MAX_WAVES + 1, "]}, " S3 "}");
    expect_error(doc, SG_ERANGE, "t.json: wavelengths: list: 25 wavelengths; the limit is 24");
    free(doc);
    doc = repeat_doc("{\"fields\": {\"list\": [", "{}", SG_MAX_FIELDS + 1, "]}, " S3 "}");
    expect_error(doc, SG_ERANGE, "t.json: fields: list: 65 fields; the limit is 64");
    free(doc);
    doc = repeat_doc("{\"surfaces\": [", "{}", SG_MAX_SURFACES + 1, "]}");
    expect_error(doc, SG_ERANGE, "t.json: surfaces: 100001 given; the limit is 100000");
    free(doc);
    n += 3;
    print_message("# content errors: %d cases gave the documented code and a message naming "
                  "the place; the target system was left unchanged each time\n", n);
}

/* Values exactly at the buffer limits are accepted. */
static void test_limits_accepted(void **state)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    char *doc, title[128];
    (void)state;
    memset(title, 'T', 127);
    title[127] = '\0';
    doc = malloc(600);
    assert_non_null(doc);
    snprintf(doc, 600,
             "{\"title\": \"%s\", \"surfaces\": [{}, {\"stop\": true, \"comment\": "
             "\"012345678901234567890123456789012345678901234567890123456789012\", "
             "\"material\": \"GLASS-NAME-THAT-IS-31-BYTE-LONG\", \"asphere\": [1, 2, 3, 4, 5, 6, 7, 8]}, {}]}",
             title);
    assert_int_equal(parse_text(s, doc, &d), SG_OK);
    assert_int_equal(strlen(s->title), 127);
    assert_int_equal(strlen(s->surf[1].comment), 63);
    assert_string_equal(s->surf[1].mat.name, "GLASS-NAME-THAT-IS-31-BYTE-LONG");
    assert_true(same_bits(s->surf[1].asph[7], 8.0));
    free(doc);

    doc = repeat_doc("{\"wavelengths\": {\"primary\": 24, \"list\": [", "{\"um\": 0.5}", SG_MAX_WAVES,
                     "]}, \"fields\": {\"list\": [");
    {
        char *doc2 = repeat_doc(doc, "{}", SG_MAX_FIELDS, "]}, " S3 "}");
        assert_int_equal(parse_text(s, doc2, &d), SG_OK);
        assert_int_equal(s->nwave, SG_MAX_WAVES);
        assert_int_equal(s->primary_wave, SG_MAX_WAVES - 1);
        assert_int_equal(s->nfield, SG_MAX_FIELDS);
        free(doc2);
    }
    free(doc);
    print_message("# limits: title 127 B, comment 63 B, glass name 31 B, 8 asphere terms, "
                  "24 wavelengths, 64 fields all accepted\n");
    sg_system_free(s);
}

static int valid_utf8(const char *p)
{
    const unsigned char *u = (const unsigned char *)p;
    while (*u) {
        int n = *u < 0x80 ? 0 : (*u & 0xE0) == 0xC0 ? 1 : (*u & 0xF0) == 0xE0 ? 2
              : (*u & 0xF8) == 0xF0 ? 3 : -1;
        if (n < 0)
            return 0;
        for (u++; n > 0; n--, u++)
            if ((*u & 0xC0) != 0x80)
                return 0;
    }
    return 1;
}

static void test_warnings(void **state)
{
    static const char text[] =
        "{\"colour\": \"red\", \"surfaces\": [{}, {\"stop\": true, \"radius\": 5, \"radius\": 7},"
        " {\"foo\": 1}], \"fields\": {\"list\": [{\"y\": 1, \"z\": 2}]}, \"title\": \"a\"}";
    static const char *const want[] = {
        "t.json: unknown key \"colour\" ignored",
        "t.json: fields: list[0]: unknown key \"z\" ignored",
        "t.json: surface 1: duplicate key \"radius\"; the last one is used",
        "t.json: surface 2: unknown key \"foo\" ignored",
    };
    sg_system *s = sg_system_new();
    sg_diag d;
    int i;
    (void)state;
    assert_int_equal(parse_text(s, text, &d), SG_OK);
    assert_int_equal(d.code, SG_OK);
    assert_int_equal(d.nwarn, 4);
    for (i = 0; i < 4; i++) {
        assert_string_equal(d.warn[i], want[i]);
        print_message("# warning %d: %s\n", i + 1, d.warn[i]);
    }
    assert_true(same_bits(s->surf[1].radius, 7.0));
    assert_true(same_bits(s->field[0].y, 1.0));

    /* A long key of two-byte characters is cut on a character boundary. */
    {
        char doc[512], key[200];
        int j;
        /* The leading 'a' puts the cut in the middle of a character. */
        key[0] = 'a';
        for (j = 0; j < 60; j++)
            memcpy(key + 1 + 2 * j, "\xc3\xa9", 2);
        key[121] = '\0';
        snprintf(doc, sizeof doc, "{\"%s\": 1, " S3 "}", key);
        assert_int_equal(parse_text(s, doc, &d), SG_OK);
        assert_int_equal(d.nwarn, 1);
        assert_true(valid_utf8(d.warn[0]));
        assert_non_null(strstr(d.warn[0], "...\" ignored"));
        print_message("# long UTF-8 key: %s\n", d.warn[0]);
    }
    sg_system_free(s);
}

/* ------------------------------------------------------------------------ */

static void test_file_errors(void **state)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    char path[512], want[600];
    int fd;
    (void)state;

    scratch_path("does-not-exist.json", path, sizeof path);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(s, path, &d), SG_EIO);
    snprintf(want, sizeof want, "%s: cannot open: %s", path, strerror(ENOENT));
    assert_string_equal(d.msg, want);
    print_message("# missing file: %s\n", d.msg);

    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(s, scratch, &d), SG_EIO);
    assert_non_null(strstr(d.msg, strerror(EISDIR)));
    print_message("# directory: %s\n", d.msg);

    /* A sparse file one byte over 64 MiB is refused by its size alone. */
    scratch_path("huge.json", path, sizeof path);
    fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (off_t)64 * 1024 * 1024 + 1), 0);
    close(fd);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_load(s, path, &d), SG_ERANGE);
    assert_non_null(strstr(d.msg, path));
    assert_non_null(strstr(d.msg, "67108865 bytes"));
    print_message("# 64 MiB + 1 file: %s\n", d.msg);
    unlink(path);

    {
        size_t big = (size_t)64 * 1024 * 1024 + 1;
        char *buf = calloc(big, 1);
        assert_non_null(buf);
        sg_diag_clear(&d);
        assert_int_equal(sg_design_parse(s, buf, big, "big", &d), SG_ERANGE);
        print_message("# 64 MiB + 1 text: %s\n", d.msg);
        free(buf);
    }
    assert_int_equal(s->nsurf, 3);
    sg_system_free(s);
}

static void test_atomic_save(void **state)
{
    sg_system *s = sg_system_new();
    sg_diag d;
    char path[512], dirpath[512], sub[600], *text;
    struct stat st;
    struct rlimit old, small;
    (void)state;
    s->surf[1].mat.kind = SG_MAT_GLASS;
    strcpy(s->surf[1].mat.name, "N-BK7");

    /* A plain save replaces the old file and keeps its permissions. */
    scratch_path("plain.json", path, sizeof path);
    write_file(path, "OLD\n");
    assert_int_equal(chmod(path, 0640), 0);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, path, &d), SG_OK);
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 07777, 0640);
    text = read_file(path);
    assert_non_null(text);
    assert_non_null(strstr(text, "\"material\": \"N-BK7\""));
    free(text);
    assert_int_equal(count_prefixed(scratch, "plain.json."), 0);
    print_message("# plain save: replaced the old file, mode 0640 kept, no temporary left\n");

    /* The target is a directory: the rename fails, nothing is left behind. */
    scratch_path("adir.json", dirpath, sizeof dirpath);
    assert_int_equal(mkdir(dirpath, 0755), 0);
    snprintf(sub, sizeof sub, "%s/inside", dirpath);
    write_file(sub, "KEEP\n");
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, dirpath, &d), SG_EIO);
    assert_non_null(strstr(d.msg, dirpath));
    assert_non_null(strstr(d.msg, strerror(EISDIR)));
    assert_int_equal(stat(dirpath, &st), 0);
    assert_true(S_ISDIR(st.st_mode));
    text = read_file(sub);
    assert_string_equal(text, "KEEP\n");
    free(text);
    assert_int_equal(count_prefixed(scratch, "adir.json."), 0);
    print_message("# path is a directory: %s; directory intact, no temporary left\n", d.msg);

    /* A write that fails half way (file size limit) leaves the old file. */
    scratch_path("keep.json", path, sizeof path);
    write_file(path, "OLD CONTENT\n");
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    small = old;
    small.rlim_cur = 100;
    signal(SIGXFSZ, SIG_IGN);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &small), 0);
    sg_diag_clear(&d);
    {
        int rc = sg_design_save(s, path, &d);
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
        assert_int_equal(rc, SG_EIO);
    }
    signal(SIGXFSZ, SIG_DFL);
    assert_non_null(strstr(d.msg, path));
    assert_non_null(strstr(d.msg, strerror(EFBIG)));
    text = read_file(path);
    assert_string_equal(text, "OLD CONTENT\n");
    free(text);
    assert_int_equal(count_prefixed(scratch, "keep.json."), 0);
    print_message("# write fails (RLIMIT_FSIZE 100 B): %s; old file intact, no temporary left\n",
                  d.msg);

    /* A directory that cannot be written: the temporary cannot be made.
     * As root (CI), the save runs with nobody's filesystem ids, on a
     * directory nobody owns, below a scratch directory nobody may enter. */
    {
        char ro[512];
        int rc, unpriv;
        scratch_path("ro", ro, sizeof ro);
        assert_int_equal(mkdir(ro, 0755), 0);
        snprintf(sub, sizeof sub, "%s/old.json", ro);
        write_file(sub, "OLD\n");
        /* The file read-only too: a writable one is saved in place
         * (test_save_keeps). */
        assert_int_equal(chmod(sub, 0444), 0);
        assert_int_equal(chmod(ro, 0555), 0);
        if (geteuid() == 0) {
            assert_int_equal(chown(ro, TU_NOBODY, TU_NOBODY), 0);
            assert_int_equal(chmod(scratch, 0711), 0);
        }
        sg_diag_clear(&d);
        unpriv = tu_unpriv_begin();
        rc = sg_design_save(s, sub, &d);
        tu_unpriv_end();
        assert_int_equal(chmod(scratch, 0700), 0);
        assert_int_equal(chmod(ro, 0755), 0);
        assert_int_equal(rc, SG_EIO);
        assert_non_null(strstr(d.msg, strerror(EACCES)));
        text = read_file(sub);
        assert_string_equal(text, "OLD\n");
        free(text);
        print_message("# read-only directory%s: %s; old file intact\n",
                      unpriv ? " (as root, with the filesystem ids of nobody)" : "", d.msg);
    }
    scratch_path("no/such/dir/x.json", path, sizeof path);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, path, &d), SG_EIO);
    assert_non_null(strstr(d.msg, strerror(ENOENT)));
    print_message("# missing directory: %s\n", d.msg);

    /* NaN is refused before anything touches the disk. */
    scratch_path("keep.json", path, sizeof path);
    s->surf[2].conic = NAN;
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, path, &d), SG_EINVAL);
    assert_string_equal(d.msg, "surface 2: conic is nan");
    assert_null(sg_design_to_json(s));
    print_message("# NaN conic: %s\n", d.msg);
    s->surf[2].conic = 0.0;
    s->field[0].y = NAN;
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, path, &d), SG_EINVAL);
    assert_non_null(strstr(d.msg, "field 1"));
    print_message("# NaN field: %s\n", d.msg);
    s->field[0].y = 0.0;
    s->surf[1].thickness = INFINITY;
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, path, &d), SG_EINVAL);
    assert_non_null(strstr(d.msg, "surface 1: thickness"));
    print_message("# infinite thickness on surface 1: %s\n", d.msg);
    text = read_file(path);
    assert_string_equal(text, "OLD CONTENT\n");
    free(text);
    sg_system_free(s);
}

/* ------------------------------------------------------------------------ */

/* The double Gauss's are its patent's (US 2,701,982): SF5, BAF10, LAK9, SF15, SK16. */
static const char *const allowed_glass[] = {
    "N-BK7", "N-SK16", "F2", "N-F2", "N-SF5", "N-SF11", "N-LAK9", "N-BAF10", "N-SF6",
    "SILICA", "BK7", "CAF2", "SAPPHIRE", "SF5", "BAF10", "LAK9", "SF15", "SK16"};

static void check_glasses(const sg_system *s, const char *file)
{
    int i;
    size_t k;
    for (i = 0; i < s->nsurf; i++) {
        if (s->surf[i].mat.kind != SG_MAT_GLASS)
            continue;
        for (k = 0; k < sizeof allowed_glass / sizeof allowed_glass[0]; k++)
            if (strcmp(s->surf[i].mat.name, allowed_glass[k]) == 0)
                break;
        if (k == sizeof allowed_glass / sizeof allowed_glass[0])
            fail_msg("%s: surface %d: glass %s is not in the bundled list", file, i,
                     s->surf[i].mat.name);
    }
}

/* Published prescriptions: radius and thickness of surfaces 1..n-2. */
typedef struct rx {
    const char *file;
    int nsurf, stop;
    double r[16], t[16];
} rx;

static const rx published[] = {
    /* Thorlabs LA1509: R = 51.5 mm, tc = 3.6 mm (catalog). */
    {"singlet.json", 4, 1, {51.5, INFINITY}, {3.6, 97.278}},
    /* Sasian, OPTI 517 triplet (after Geiser). */
    {"cooke_triplet.json", 8, 3,
     {23.713, 7331.288, -24.456, 21.896, 86.759, -20.4942},
     {4.831, 5.86, 0.975, 4.822, 3.127, 41.2365}},
    /* Angenieux US 2,701,982 as tabulated by Smith, Modern Lens Design. */
    {"double_gauss.json", 17, 8,
     {164.12, 559.28, 100.12, 213.54, 58.04, 2551, 32.39, INFINITY, -40.42, 192.98, -55.53,
      192.98, -225.28, 175.1, -203.54},
     {10.99, 0.23, 11.45, 0.23, 22.95, 2.58, 15.66, 15.0, 2.74, 27.92, 0.23, 7.98, 0.23, 8.48,
      55.742}},
};

static void test_examples(void **state)
{
    char dirpath[512], path[1024], out[512], why[160];
    DIR *dir;
    struct dirent *e;
    int nfiles = 0;
    long total = 0;
    size_t k;
    (void)state;
    tu_path("examples", dirpath, sizeof dirpath);

    for (k = 0; k < sizeof published / sizeof published[0]; k++) {
        const rx *p = &published[k];
        sg_system *s = tu_example(p->file);
        char *file_text, *json;
        int i;
        assert_int_equal(s->nsurf, p->nsurf);
        assert_int_equal(s->stop, p->stop);
        assert_true(isinf(s->surf[0].thickness) && s->surf[0].thickness > 0);
        for (i = 1; i < p->nsurf - 1; i++) {
            if (!same_bits(s->surf[i].radius, p->r[i - 1]) ||
                !same_bits(s->surf[i].thickness, p->t[i - 1]))
                fail_msg("%s: surface %d: R %.17g t %.17g, published R %.17g t %.17g", p->file,
                         i, s->surf[i].radius, s->surf[i].thickness, p->r[i - 1], p->t[i - 1]);
        }
        check_glasses(s, p->file);
        /* The examples are written in the saver's own layout. */
        snprintf(path, sizeof path, "%s/%s", dirpath, p->file);
        file_text = read_file(path);
        json = sg_design_to_json(s);
        assert_non_null(file_text);
        assert_non_null(json);
        assert_string_equal(json, file_text);
        free(file_text);
        free(json);
        print_message("# %s: %d surfaces, stop %d, radii and thicknesses equal the published "
                      "prescription; glasses in the bundled list; saved text == file text\n",
                      p->file, p->nsurf, p->stop);
        sg_system_free(s);
    }

    /* Every bundled example survives save and load bit for bit. */
    dir = opendir(dirpath);
    assert_non_null(dir);
    while ((e = readdir(dir)) != NULL) {
        size_t n = strlen(e->d_name);
        sg_system *a, *b;
        sg_diag d;
        const char *diff;
        if (n < 6 || strcmp(e->d_name + n - 5, ".json") != 0)
            continue;
        a = tu_example(e->d_name);
        b = sg_system_new();
        scratch_path("example-copy.json", out, sizeof out);
        sg_diag_clear(&d);
        assert_int_equal(sg_design_save(a, out, &d), SG_OK);
        sg_diag_clear(&d);
        assert_int_equal(sg_design_load(b, out, &d), SG_OK);
        diff = system_diff(a, b, &total, why, sizeof why);
        if (diff)
            fail_msg("%s: %s", e->d_name, diff);
        nfiles++;
        sg_system_free(a);
        sg_system_free(b);
    }
    closedir(dir);
    assert_true(nfiles >= 3);
    print_message("# examples: %d files saved and reloaded, %ld doubles compared bit for bit, "
                  "0 differ\n", nfiles, total);
}

/* Issue 30, item 5: a save keeps what it should.  The owner and group of
 * the file (as root, the file given to nobody first), its mode; a dangling
 * symbolic link stays a link and the file it names is written; a writable
 * file in a directory that cannot be written is rewritten in place (same
 * inode), its backup gone afterwards.  References: stat() and lstat(). */
static void test_save_keeps(void **state)
{
    sg_system *s = sg_system_new(), *back = sg_system_new();
    sg_diag d;
    char path[512], link[512], target[512], ro[512], sub[600];
    struct stat st, before;
    char *text;
    int unpriv, rc;
    (void)state;
    s->surf[1].radius = -123.456;

    /* Owner and group. */
    scratch_path("owned.json", path, sizeof path);
    write_file(path, "OLD\n");
    assert_int_equal(chmod(path, 0640), 0);
    if (geteuid() == 0) {
        assert_int_equal(chown(path, TU_NOBODY, TU_NOBODY), 0);
        sg_diag_clear(&d);
        assert_int_equal(sg_design_save(s, path, &d), SG_OK);
        assert_int_equal(stat(path, &st), 0);
        assert_int_equal((long)st.st_uid, TU_NOBODY);
        assert_int_equal((long)st.st_gid, TU_NOBODY);
        assert_int_equal(st.st_mode & 07777, 0640);
        assert_int_equal(sg_design_load(back, path, &d), SG_OK);
        assert_true(back->surf[1].radius == -123.456);
        print_message("# root saved nobody's file: owner %ld, group %ld, mode %04o kept\n",
                      (long)st.st_uid, (long)st.st_gid, (unsigned)(st.st_mode & 07777));
    } else {
        print_message("# not root: the owner case needs a file of another user; skipped\n");
    }

    /* A dangling symbolic link, relative, and one through two links. */
    scratch_path("dangle.json", link, sizeof link);
    scratch_path("dangle-target.json", target, sizeof target);
    unlink(link);
    unlink(target);
    assert_int_equal(symlink("dangle-target.json", link), 0);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, link, &d), SG_OK);
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(lstat(target, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    assert_int_equal(sg_design_load(back, target, &d), SG_OK);
    assert_true(back->surf[1].radius == -123.456);
    scratch_path("dangle2.json", path, sizeof path);
    unlink(path);
    unlink(target);
    assert_int_equal(symlink(link, path), 0);
    assert_int_equal(sg_design_save(s, path, &d), SG_OK);
    assert_int_equal(lstat(path, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(lstat(target, &st), 0);
    assert_true(S_ISREG(st.st_mode));
    print_message("# dangling links (one, then a chain of two) stay links; the file they "
                  "name is written\n");
    /* A loop of links is refused, naming the path. */
    scratch_path("loop-a.json", path, sizeof path);
    scratch_path("loop-b.json", sub, sizeof sub);
    unlink(path);
    unlink(sub);
    assert_int_equal(symlink("loop-b.json", path), 0);
    assert_int_equal(symlink("loop-a.json", sub), 0);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, path, &d), SG_EIO);
    assert_non_null(strstr(d.msg, strerror(ELOOP)));
    print_message("# a loop of links: %s\n", d.msg);

    /* A writable file in a directory that cannot be written.  As root
     * (CI) both belong to nobody and the save runs with nobody's ids. */
    scratch_path("rodir", ro, sizeof ro);
    assert_int_equal(mkdir(ro, 0755), 0);
    snprintf(sub, sizeof sub, "%s/in.json", ro);
    write_file(sub, "OLD\n");
    assert_int_equal(chmod(sub, 0664), 0);
    if (geteuid() == 0) {
        assert_int_equal(chown(sub, TU_NOBODY, TU_NOBODY), 0);
        assert_int_equal(chown(ro, TU_NOBODY, TU_NOBODY), 0);
        assert_int_equal(chmod(scratch, 0711), 0);
    }
    assert_int_equal(chmod(ro, 0555), 0);
    assert_int_equal(stat(sub, &before), 0);
    sg_diag_clear(&d);
    unpriv = tu_unpriv_begin();
    rc = sg_design_save(s, sub, &d);
    tu_unpriv_end();
    assert_int_equal(chmod(scratch, 0700), 0);
    assert_int_equal(chmod(ro, 0755), 0);
    if (rc != SG_OK)
        fail_msg("save in a read-only directory: %s", d.msg);
    assert_int_equal(stat(sub, &st), 0);
    assert_true(st.st_ino == before.st_ino && st.st_uid == before.st_uid &&
                st.st_gid == before.st_gid && (st.st_mode & 07777) == 0664);
    text = read_file(sub);
    assert_non_null(strstr(text, "-123.456"));
    free(text);
    assert_int_equal(count_prefixed(ro, ".sagitta-"), 0);
    print_message("# writable file in a read-only directory%s: saved in place (inode %lu "
                  "kept), no backup left\n",
                  unpriv ? " (as nobody)" : "", (unsigned long)st.st_ino);
    unlink(sub);
    rmdir(ro);
    sg_system_free(s);
    sg_system_free(back);
}

/* Saving through a symbolic link writes the file it points at and keeps
 * the link; a name at the file system's length limit can be saved. */
static void test_save_links_and_long_names(void **state)
{
    sg_system *s = sg_system_new(), *back = sg_system_new();
    sg_diag d;
    char target[512], link[512], longname[1024], dir[512];
    struct stat st;
    size_t n;
    (void)state;
    s->surf[1].radius = -123.456;
    scratch_path("target.json", target, sizeof target);
    scratch_path("link.json", link, sizeof link);
    write_file(target, "OLD\n");
    unlink(link);
    assert_int_equal(symlink(target, link), 0);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(s, link, &d), SG_OK);
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(sg_design_load(back, target, &d), SG_OK);
    assert_true(back->surf[1].radius == -123.456);
    print_message("# save through a symlink: the link stays, the target holds radius %.17g\n",
                  back->surf[1].radius);

    /* NAME_MAX (255 bytes) long file name. */
    scratch_path("", dir, sizeof dir);
    n = strlen(dir);
    memcpy(longname, dir, n);
    memset(longname + n, 'a', 250);
    strcpy(longname + n + 250, ".json");
    assert_int_equal(sg_design_save(s, longname, &d), SG_OK);
    assert_int_equal(sg_design_load(back, longname, &d), SG_OK);
    assert_true(back->surf[1].radius == -123.456);
    print_message("# a 255-byte file name saves and loads back\n");
    unlink(longname);
    unlink(link);
    unlink(target);
    sg_system_free(s);
    sg_system_free(back);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_values),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_environment_and_model),
        cmocka_unit_test(test_roundtrip_random),
        cmocka_unit_test(test_syntax_errors),
        cmocka_unit_test(test_content_errors),
        cmocka_unit_test(test_shapes),
        cmocka_unit_test(test_frame_order_kept),
        cmocka_unit_test(test_catalog_glass),
        cmocka_unit_test(test_limits_accepted),
        cmocka_unit_test(test_warnings),
        cmocka_unit_test(test_file_errors),
        cmocka_unit_test(test_atomic_save),
        cmocka_unit_test(test_save_links_and_long_names),
        cmocka_unit_test(test_save_keeps),
        cmocka_unit_test(test_examples),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
