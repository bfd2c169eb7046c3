/*
 * test_zar.c - Zemax archives (.zar), issue 17.
 *
 * The archives here are built by the test itself, with an LZW encoder
 * written from the format as sagitta-design(5) states it (two member
 * header layouts; codes most significant bit first, 9 bits wide at the
 * start and one wider each time the table fills the width).  The lens file
 * packed is a Zemax-written one (tests/data/zmx/lens1.zmx, see its
 * README), so the design read from the archive must be the design read
 * from that file.  Archives written by Zemax were checked outside the
 * suite (the closing note of issue 17 has the command): their lens files
 * unpack byte for byte to the .zmx files their vendor publishes beside
 * them.  Hostile archives must fail with a message naming the member.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

/* ------------------------------------------------------------------------
 * The encoder: a plain dictionary LZW over (prefix code, byte) pairs.
 * ------------------------------------------------------------------------ */

typedef struct bitw {
    unsigned char *p;
    size_t nbit, cap;
} bitw;

static void put_bits(bitw *w, uint32_t v, unsigned n)
{
    unsigned i;
    for (i = 0; i < n; i++, w->nbit++) {
        size_t byte = w->nbit >> 3;
        assert_true(byte < w->cap);
        if ((w->nbit & 7) == 0)
            w->p[byte] = 0;
        if (v >> (n - 1 - i) & 1)
            w->p[byte] |= (unsigned char)(0x80 >> (w->nbit & 7));
    }
}

#define HBITS 20
#define HSIZE ((size_t)1 << HBITS)

/* in[0..n) packed into a new buffer; *outlen its bytes. */
static unsigned char *lzw_pack(const unsigned char *in, size_t n, size_t *outlen)
{
    uint64_t *key = calloc(HSIZE, sizeof *key); /* prefix << 8 | byte, +1; 0 empty */
    uint32_t *val = calloc(HSIZE, sizeof *val);
    bitw w = { malloc(2 * n + 16), 0, 2 * n + 16 };
    uint32_t next = 256, cur, ncode = 0;
    size_t i;
    assert_non_null(key);
    assert_non_null(val);
    assert_non_null(w.p);
    if (n == 0) {
        *outlen = 0;
        free(key);
        free(val);
        return w.p;
    }
    cur = in[0];
    for (i = 1; i <= n; i++) {
        uint64_t k = 0;
        size_t h = 0;
        if (i < n) {
            k = ((uint64_t)cur << 8 | in[i]) + 1;
            h = (size_t)((k * UINT64_C(0x9E3779B97F4A7C15)) >> (64 - HBITS));
            while (key[h] && key[h] != k)
                h = (h + 1) & (HSIZE - 1);
            if (key[h]) {
                cur = val[h];
                continue;
            }
        }
        {
            /* The decoder's table before it reads code number ncode: 256,
             * and one more for each code after the first. */
            uint32_t nt = 256 + (ncode ? ncode - 1 : 0);
            unsigned width = 9;
            while (nt >= (UINT32_C(1) << width))
                width++;
            put_bits(&w, cur, width);
            ncode++;
        }
        if (i < n) {
            key[h] = k;
            val[h] = next++;
            cur = in[i];
        }
    }
    free(key);
    free(val);
    *outlen = (w.nbit + 7) / 8;
    return w.p;
}

/* ------------------------------------------------------------------------
 * Archives
 * ------------------------------------------------------------------------ */

typedef struct arch {
    unsigned char *p;
    size_t n, cap;
} arch;

static void arch_put(arch *a, const void *b, size_t n)
{
    if (n == 0)
        return;
    if (a->n + n > a->cap) {
        a->cap = (a->n + n) * 2 + 1024;
        a->p = realloc(a->p, a->cap);
        assert_non_null(a->p);
    }
    memcpy(a->p + a->n, b, n);
    a->n += n;
}

static void le_put(unsigned char *p, uint64_t v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

/* One member: layout 0xEC (new) or 0xEA (old); packed with LZW when the
 * name ends in ".LZW". */
static void add_member(arch *a, int layout, const char *name, const void *data, size_t n)
{
    unsigned char hdr[0x288];
    size_t hn = layout == 0xEC ? 0x288 : 0x14C, i, pn = n;
    size_t nl = strlen(name);
    unsigned char *packed = NULL;
    const void *body = data;
    if (nl > 4 && strcmp(name + nl - 4, ".LZW") == 0) {
        packed = lzw_pack(data, n, &pn);
        body = packed;
    }
    memset(hdr, 0, sizeof hdr);
    hdr[0] = (unsigned char)layout;
    hdr[1] = 0x03;
    if (layout == 0xEC) {
        le_put(hdr + 0x10, pn, 8);
        le_put(hdr + 0x18, n, 8);
        for (i = 0; i < nl; i++)
            hdr[0x30 + 2 * i] = (unsigned char)name[i];
    } else {
        le_put(hdr + 0x0C, pn, 4);
        memcpy(hdr + 0x20, name, nl);
    }
    arch_put(a, hdr, hn);
    arch_put(a, body, pn);
    free(packed);
}

static char *read_all(const char *rel, size_t *n)
{
    char path[1024];
    FILE *f = fopen(tu_path(rel, path, sizeof path), "rb");
    char *buf;
    long len;
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    len = ftell(f);
    assert_true(len > 0);
    rewind(f);
    buf = malloc((size_t)len + 1);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    buf[len] = 0;
    *n = (size_t)len;
    return buf;
}

/* The Cooke triplet written by Zemax, read from an archive of each layout,
 * with catalogs and a stored member beside it, is the design read from
 * the file itself. */
static void test_lens_from_archive(void **state)
{
    size_t n;
    char *zmx = read_all("tests/data/zmx/lens1.zmx", &n);
    const char agf[] = "CC a catalog the archive carries\nNM X 2 500000 1.5 60 0 0\n";
    sg_catalog *cat = tu_catalog();
    sg_system *ref = sg_system_new(), *got = sg_system_new();
    int layout;
    sg_diag d;
    (void)state;

    assert_int_equal(sg_zmx_parse(ref, zmx, n, "lens1.zmx", cat, NULL), SG_OK);
    for (layout = 0xEA; layout <= 0xEC; layout += 2) {
        arch a = { NULL, 0, 0 };
        add_member(&a, layout, "LENS1.ZMX.LZW", zmx, n);
        add_member(&a, layout, "SCHOTT.AGF.LZW", agf, sizeof agf - 1);
        add_member(&a, layout, "THORC.ZEC", "stored as it is", 15);
        sg_diag_clear(&d);
        assert_true(sg_zar_detect("x.bin", a.p, a.n));
        if (sg_zar_parse(got, a.p, a.n, "lens1.zar", cat, &d) != SG_OK)
            fail_msg("layout 0x%X: %s", layout, d.msg);
        assert_true(sg_system_equal(ref, got));
        /* Every member comes back as it went in. */
        {
            void *m;
            size_t mn;
            char name[256];
            assert_int_equal(sg_zar_member(a.p, a.n, "a.zar", "schott.agf", &m, &mn, name, &d),
                             SG_OK);
            assert_string_equal(name, "SCHOTT.AGF");
            assert_int_equal(mn, sizeof agf - 1);
            assert_memory_equal(m, agf, mn);
            free(m);
            assert_int_equal(sg_zar_member(a.p, a.n, "a.zar", "THORC.ZEC", &m, &mn, NULL, &d),
                             SG_OK);
            assert_int_equal(mn, 15);
            assert_memory_equal(m, "stored as it is", 15);
            free(m);
        }
        free(a.p);
    }
    sg_system_free(ref);
    sg_system_free(got);
    sg_catalog_free(cat);
    free(zmx);
}

/* The decoder against the encoder on data that walks the code width from
 * 9 bits past 17, and on the string-defined-by-itself case (aaaa...). */
static void test_lzw_widths(void **state)
{
    size_t sizes[] = { 0, 1, 2, 3, 255, 256, 257, 600, 5000, 70000, 400000 };
    uint64_t s = 0x2545F4914F6CDD1DULL;
    size_t k, i;
    (void)state;
    for (k = 0; k < sizeof sizes / sizeof *sizes; k++) {
        int kind;
        for (kind = 0; kind < 3; kind++) {
            size_t n = sizes[k], mn;
            unsigned char *data = malloc(n + 1);
            arch a = { NULL, 0, 0 };
            void *m;
            sg_diag d;
            for (i = 0; i < n; i++) {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                /* random bytes (the table grows by a code a byte or so),
                 * one byte repeated, and a small alphabet */
                data[i] = kind == 0 ? (unsigned char)s : kind == 1 ? 'a' : (unsigned char)('a' + s % 3);
            }
            add_member(&a, 0xEC, "D.BIN.LZW", data, n);
            sg_diag_clear(&d);
            if (sg_zar_member(a.p, a.n, "t.zar", "d.bin", &m, &mn, NULL, &d) != SG_OK)
                fail_msg("%zu bytes, kind %d: %s", n, kind, d.msg);
            assert_int_equal(mn, n);
            if (n)
                assert_memory_equal(m, data, n);
            free(m);
            free(a.p);
            free(data);
        }
    }
}

/* A glass the catalog lacks: the message names the archive's catalogs. */
static void test_missing_glass(void **state)
{
    const char zmx[] = "VERS 1\nMODE SEQ\nUNIT MM X W X CM MR CPMM\nENPD 10\nGCAT ACME\n"
                       "WAVM 1 0.55 1\nPWAV 1\nSURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n"
                       "  DISZ 5\n  GLAS NOSUCHGLASS 0 0 1.5 50\nSURF 2\n  DISZ 10\nSURF 3\n";
    sg_catalog *cat = tu_catalog();
    sg_system *sys = sg_system_new();
    arch a = { NULL, 0, 0 };
    sg_diag d;
    (void)state;
    add_member(&a, 0xEC, "L.ZMX.LZW", zmx, sizeof zmx - 1);
    add_member(&a, 0xEC, "ACME.AGF.LZW", "NM NOSUCHGLASS 2 0 1.5 50\n", 26);
    sg_diag_clear(&d);
    assert_int_equal(sg_zar_parse(sys, a.p, a.n, "acme.zar", cat, &d), SG_ENOGLASS);
    if (!strstr(d.msg, "acme.zar:L.ZMX:13: surface 1: GLAS: glass NOSUCHGLASS") ||
        !strstr(d.msg, "ACME.AGF"))
        fail_msg("message: %s", d.msg);
    free(a.p);
    sg_system_free(sys);
    sg_catalog_free(cat);
}

/* Saving to an archive name is refused: its other members would be lost. */
static void test_no_write(void **state)
{
    sg_system *sys = tu_example("singlet.json");
    char path[] = "/tmp/sagitta-zar-XXXXXX";
    char name[64];
    int fd = mkstemp(path);
    sg_diag d;
    (void)state;
    assert_true(fd >= 0);
    close(fd);
    unlink(path);
    snprintf(name, sizeof name, "%s.zar", path);
    sg_diag_clear(&d);
    assert_int_equal(sg_design_save(sys, name, &d), SG_EUNSUPPORTED);
    assert_non_null(strstr(d.msg, "does not write them"));
    assert_int_equal(access(name, F_OK), -1);
    sg_system_free(sys);
}

/* ------------------------------------------------------------------------
 * Hostile archives: each fails with its code and a message naming what
 * is wrong, and nothing is read past the input.
 * ------------------------------------------------------------------------ */

enum { H_TRUNC_HDR, H_BIG_SIZE, H_BAD_CODE, H_LONGER, H_SHORTER, H_NO_LENS, H_TWO_LENS,
       H_BAD_BYTE, H_EMPTY, H_STORED_SIZE, H_NONAME, H_N };

/* An archive of many members with long names and no lens file: the
 * refusal lists the names that fit and ends with ", ..." (the list once
 * wrote past its end: fuzz_zar, under AddressSanitizer). */
static void test_long_member_list(void **state)
{
    arch a = { NULL, 0, 0 };
    void *out = NULL;
    size_t outn = 0;
    char n1[128], n2[64], got[256];
    sg_diag d;
    (void)state;
    /* 100 and 53 characters: the list reaches 155 of its 160 bytes, where
     * the old ", ..." wrote one byte past the end. */
    memset(n1, 'M', 96);
    strcpy(n1 + 96, ".DAT");
    memset(n2, 'N', 49);
    strcpy(n2 + 49, ".DAT");
    add_member(&a, 0xEC, n1, "x", 1);
    add_member(&a, 0xEC, n2, "x", 1);
    add_member(&a, 0xEC, "C.DAT", "x", 1);
    add_member(&a, 0xEC, "D.DAT", "x", 1);
    sg_diag_clear(&d);
    assert_int_equal(sg_zar_member(a.p, a.n, "t.zar", NULL, &out, &outn, got, &d), SG_EPARSE);
    assert_non_null(strstr(d.msg, "(it holds MMMM"));
    assert_non_null(strstr(d.msg, "M.DAT, ...)"));
    assert_null(out);
    free(a.p);
}

static void test_hostile(void **state)
{
    static const struct {
        int code;
        const char *msg;
    } want[H_N] = {
        { SG_EPARSE, "t.zar: byte 0: an archive member's header of 648 bytes is cut off" },
        { SG_EPARSE, "t.zar: member A.ZMX.LZW (byte 0): 1000000 packed bytes, but the file has" },
        { SG_EPARSE, "is beyond the table of 256 entries: the archive is damaged" },
        { SG_EPARSE, "t.zar: member A.ZMX.LZW unpacks to more than the 10 bytes its header says" },
        { SG_EPARSE, "unpacks to 40 bytes, but its header says 50" },
        { SG_EPARSE, "t.zar: the archive holds no lens file (.ZMX) (it holds A.AGF, B.DAT)" },
        { SG_EUNSUPPORTED, "t.zar: the archive holds 2 lens files (A.ZMX, B.ZMX)" },
        { SG_EPARSE, "t.zar: byte 659: not a Zemax archive member (it starts 0x50 0x4B; known" },
        { SG_EPARSE, "t.zar: the file is empty, not a Zemax archive" },
        { SG_EPARSE, "t.zar: member A.ZMX is stored with 5 bytes, but its header says 9" },
        { SG_EPARSE, "t.zar: byte 0: an archive member without a name" },
    };
    char text[40];
    sg_catalog *cat = tu_catalog();
    int h;
    (void)state;
    memset(text, 'V', sizeof text);
    for (h = 0; h < H_N; h++) {
        arch a = { NULL, 0, 0 };
        sg_system *sys = sg_system_new();
        sg_diag d;
        int rc;
        switch (h) {
        case H_TRUNC_HDR:
            add_member(&a, 0xEC, "A.ZMX", text, 0);
            a.n = 100;
            break;
        case H_BIG_SIZE:
            add_member(&a, 0xEC, "A.ZMX.LZW", text, sizeof text);
            le_put(a.p + 0x10, 1000000, 8);
            break;
        case H_BAD_CODE:
            /* 9-bit code 300 first: nothing is defined yet. */
            add_member(&a, 0xEC, "A.ZMX.LZW", text, 2);
            a.p[0x288] = (unsigned char)(300 >> 1);
            a.p[0x289] = (unsigned char)((300 & 1) << 7);
            break;
        case H_LONGER:
            add_member(&a, 0xEC, "A.ZMX.LZW", text, sizeof text);
            le_put(a.p + 0x18, 10, 8);
            break;
        case H_SHORTER:
            add_member(&a, 0xEC, "A.ZMX.LZW", text, sizeof text);
            le_put(a.p + 0x18, 50, 8);
            break;
        case H_NO_LENS:
            add_member(&a, 0xEC, "A.AGF.LZW", text, sizeof text);
            add_member(&a, 0xEA, "B.DAT", text, 3);
            break;
        case H_TWO_LENS:
            add_member(&a, 0xEC, "A.ZMX.LZW", text, sizeof text);
            add_member(&a, 0xEC, "B.ZMX", text, 3);
            break;
        case H_BAD_BYTE:
            add_member(&a, 0xEC, "A.ZMX.LZW", text, sizeof text);
            arch_put(&a, "PK\3\4 a zip file", 15);
            break;
        case H_EMPTY:
            arch_put(&a, "", 0);
            break;
        case H_STORED_SIZE:
            add_member(&a, 0xEC, "A.ZMX", text, 5);
            le_put(a.p + 0x18, 9, 8);
            break;
        case H_NONAME:
            add_member(&a, 0xEC, "", text, 5);
            break;
        }
        sg_diag_clear(&d);
        rc = sg_zar_parse(sys, a.p ? a.p : (unsigned char *)"", a.n, "t.zar", cat, &d);
        if (rc != want[h].code || !strstr(d.msg, want[h].msg))
            fail_msg("case %d: code %s, message: %s", h, sg_err_name(rc), d.msg);
        free(a.p);
        sg_system_free(sys);
    }
    sg_catalog_free(cat);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lens_from_archive),
        cmocka_unit_test(test_lzw_widths),
        cmocka_unit_test(test_missing_glass),
        cmocka_unit_test(test_no_write),
        cmocka_unit_test(test_hostile),
        cmocka_unit_test(test_long_member_list),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
