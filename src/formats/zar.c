/*
 * zar.c - Zemax archives (.zar): the lens file inside, read with the .zmx
 * reader (sagitta-design(5), ZEMAX ARCHIVES).
 *
 * An archive is a run of members, each a fixed header and then its packed
 * bytes.  Two header layouts are known, told apart by the first byte:
 *   0xEC: 0x288 bytes; packed size (64 bits, little-endian) at 0x10, size
 *         unpacked at 0x18, the name in UTF-16LE from 0x30 to a NUL;
 *   0xEA: 0x14C bytes; packed size (32 bits) at 0x0C, the name in bytes
 *         from 0x20 to a NUL.
 * A member whose name ends in ".LZW" is compressed: LZW with codes read
 * most significant bit first, 9 bits wide at the start and one bit wider
 * whenever the table has filled the width, no clear or end code, and the
 * table never reset.  The rest are stored as they are.
 *
 * Every size is checked against what is left of the input, the table
 * grows with the codes read (so with the input), and the unpacked bytes
 * are capped, so a hostile archive costs bounded memory and time.
 */
#include <ctype.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "formats_int.h"

#define ZAR_MAX_BYTES ((size_t)64 * 1024 * 1024)
#define ZAR_NAME 256

typedef struct zar_member {
    char name[ZAR_NAME]; /* UTF-8, ".LZW" kept */
    const unsigned char *data;
    size_t size;      /* packed */
    size_t unpacked;  /* from the header; SIZE_MAX when it has none */
    int lzw;
} zar_member;

static uint64_t le(const unsigned char *p, int n)
{
    uint64_t v = 0;
    while (n-- > 0)
        v = v << 8 | p[n];
    return v;
}

static int ends_with_ci(const char *s, const char *tail)
{
    size_t n = strlen(s), m = strlen(tail), i;
    if (n < m)
        return 0;
    for (i = 0; i < m; i++)
        if (tolower((unsigned char)s[n - m + i]) != tolower((unsigned char)tail[i]))
            return 0;
    return 1;
}

/* A name from UTF-16LE code units, as UTF-8; a unit that is not a
 * character on its own (a surrogate) becomes '?'. */
static void name_utf16(const unsigned char *p, size_t n, char out[ZAR_NAME])
{
    size_t i, k = 0;
    for (i = 0; i + 1 < n; i += 2) {
        unsigned u = (unsigned)p[i] | (unsigned)p[i + 1] << 8;
        if (u == 0)
            break;
        if (u >= 0xD800 && u < 0xE000)
            u = '?';
        if (u < 0x80 && k + 1 < ZAR_NAME) {
            out[k++] = (char)u;
        } else if (u < 0x800 && k + 2 < ZAR_NAME) {
            out[k++] = (char)(0xC0 | u >> 6);
            out[k++] = (char)(0x80 | (u & 0x3F));
        } else if (u >= 0x800 && k + 3 < ZAR_NAME) {
            out[k++] = (char)(0xE0 | u >> 12);
            out[k++] = (char)(0x80 | (u >> 6 & 0x3F));
            out[k++] = (char)(0x80 | (u & 0x3F));
        } else {
            break;
        }
    }
    out[k] = '\0';
}

/* A name in bytes; a control byte becomes '?', so a message can show it. */
static void name_bytes(const unsigned char *p, size_t n, char out[ZAR_NAME])
{
    size_t i;
    for (i = 0; i < n && i + 1 < ZAR_NAME && p[i]; i++)
        out[i] = p[i] < 0x20 || p[i] == 0x7F ? '?' : (char)p[i];
    out[i] = '\0';
}

/* The member whose header starts at b + off; *next is the offset after it. */
static int member_at(const unsigned char *b, size_t len, size_t off, const char *path,
                     zar_member *m, size_t *next, sg_diag *d)
{
    size_t hdr, left;
    uint64_t size;

    if (len - off < 2)
        return sg_diag_set(d, SG_EPARSE, "%s: byte %zu: an archive member's header is cut off",
                           path, off);
    if (b[off] == 0xEC)
        hdr = 0x288;
    else if (b[off] == 0xEA)
        hdr = 0x14C;
    else
        return sg_diag_set(d, SG_EPARSE,
                           "%s: byte %zu: not a Zemax archive member (it starts 0x%02X 0x%02X; "
                           "known headers start 0xEC or 0xEA)",
                           path, off, b[off], b[off + 1]);
    if (len - off < hdr)
        return sg_diag_set(d, SG_EPARSE,
                           "%s: byte %zu: an archive member's header of %zu bytes is cut off "
                           "after %zu",
                           path, off, hdr, len - off);
    memset(m, 0, sizeof *m);
    if (hdr == 0x288) {
        uint64_t u = le(b + off + 0x18, 8);
        size = le(b + off + 0x10, 8);
        /* Anything past the cap is refused in unpack; one more says so. */
        m->unpacked = u > ZAR_MAX_BYTES ? ZAR_MAX_BYTES + 1 : (size_t)u;
        name_utf16(b + off + 0x30, hdr - 0x30, m->name);
    } else {
        size = le(b + off + 0x0C, 4);
        m->unpacked = SIZE_MAX;
        name_bytes(b + off + 0x20, hdr - 0x20, m->name);
    }
    if (!m->name[0])
        return sg_diag_set(d, SG_EPARSE, "%s: byte %zu: an archive member without a name",
                           path, off);
    left = len - off - hdr;
    if (size > left)
        return sg_diag_set(d, SG_EPARSE,
                           "%s: member %s (byte %zu): %llu packed bytes, but the file has %zu "
                           "left",
                           path, m->name, off, (unsigned long long)size, left);
    m->data = b + off + hdr;
    m->size = (size_t)size;
    m->lzw = ends_with_ci(m->name, ".LZW");
    *next = off + hdr + (size_t)size;
    return SG_OK;
}

typedef struct lzw_ent {
    uint32_t prefix; /* the entry this one extends */
    uint32_t len;    /* of the string */
    unsigned char ch, first;
} lzw_ent;

/* The member's bytes unpacked into a new buffer (NUL after them). */
static int unpack(const zar_member *m, const char *path, unsigned char **out, size_t *outlen,
                  sg_diag *d)
{
    const unsigned char *in = m->data;
    size_t nbits = m->size * 8, pos = 0, n = 0, cap, tcap = 0;
    size_t limit = m->unpacked != SIZE_MAX ? m->unpacked : ZAR_MAX_BYTES;
    lzw_ent *t = NULL;
    uint32_t nt = 256, prev = UINT32_MAX;
    unsigned w = 9;
    unsigned char *o;

    if (limit > ZAR_MAX_BYTES)
        return sg_diag_set(d, SG_ERANGE, "%s: member %s unpacks to more than %zu bytes (64 MiB)",
                           path, m->name, ZAR_MAX_BYTES);
    if (!m->lzw) {
        if (m->unpacked != SIZE_MAX && m->unpacked != m->size)
            return sg_diag_set(d, SG_EPARSE,
                               "%s: member %s is stored with %zu bytes, but its header says %zu",
                               path, m->name, m->size, m->unpacked);
        if (!(o = malloc(m->size + 1)))
            return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
        memcpy(o, in, m->size);
        o[m->size] = 0;
        *out = o;
        *outlen = m->size;
        return SG_OK;
    }
    cap = m->unpacked != SIZE_MAX ? m->unpacked : 4 * m->size + 64;
    if (cap > limit)
        cap = limit;
    if (!(o = malloc(cap + 1)))
        return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
    for (;;) {
        uint32_t code = 0, len, k, e;
        unsigned char first;
        unsigned i;
        if (nt >= (UINT32_C(1) << w) && w < 32)
            w++;
        if (nbits - pos < w)
            break;
        for (i = 0; i < w; i++, pos++)
            code = code << 1 | (uint32_t)(in[pos >> 3] >> (7 - (pos & 7)) & 1);
        if (code < 256) {
            len = 1;
            first = (unsigned char)code;
        } else if (code < nt) {
            len = t[code - 256].len;
            first = t[code - 256].first;
        } else if (code == nt && prev != UINT32_MAX) {
            /* The string being defined: the previous one and its first byte. */
            len = (prev < 256 ? 1 : t[prev - 256].len) + 1;
            first = prev < 256 ? (unsigned char)prev : t[prev - 256].first;
        } else {
            free(t);
            free(o);
            return sg_diag_set(d, SG_EPARSE,
                               "%s: member %s: LZW code %u at bit %zu is beyond the table of %u "
                               "entries: the archive is damaged",
                               path, m->name, (unsigned)code, pos - w, (unsigned)nt);
        }
        if (len > limit - n) {
            free(t);
            free(o);
            if (m->unpacked != SIZE_MAX)
                return sg_diag_set(d, SG_EPARSE,
                                   "%s: member %s unpacks to more than the %zu bytes its header "
                                   "says: the archive is damaged",
                                   path, m->name, m->unpacked);
            return sg_diag_set(d, SG_ERANGE,
                               "%s: member %s unpacks to more than %zu bytes (64 MiB)", path,
                               m->name, ZAR_MAX_BYTES);
        }
        if (n + len > cap) {
            size_t nc = cap * 2 > n + len ? cap * 2 : n + len;
            unsigned char *no;
            if (nc > limit)
                nc = limit;
            if (!(no = realloc(o, nc + 1))) {
                free(t);
                free(o);
                return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
            }
            o = no;
            cap = nc;
        }
        if (prev != UINT32_MAX) {
            /* The new entry: the previous string and this one's first byte. */
            if (nt - 256 >= tcap) {
                size_t nc = tcap ? tcap * 2 : 1024;
                lzw_ent *nt2 = realloc(t, nc * sizeof *t);
                if (!nt2) {
                    free(t);
                    free(o);
                    return sg_diag_set(d, SG_ENOMEM, "%s: out of memory", path);
                }
                t = nt2;
                tcap = nc;
            }
            t[nt - 256].prefix = prev;
            t[nt - 256].ch = first;
            t[nt - 256].len = (prev < 256 ? 1 : t[prev - 256].len) + 1;
            t[nt - 256].first = prev < 256 ? (unsigned char)prev : t[prev - 256].first;
            nt++;
        }
        /* The string, written from its last byte back along its prefixes. */
        for (k = len, e = code; k > 1; k--) {
            o[n + k - 1] = t[e - 256].ch;
            e = t[e - 256].prefix;
        }
        o[n] = (unsigned char)e;
        n += len;
        prev = code;
    }
    free(t);
    if (m->unpacked != SIZE_MAX && n != m->unpacked) {
        free(o);
        return sg_diag_set(d, SG_EPARSE,
                           "%s: member %s unpacks to %zu bytes, but its header says %zu: the "
                           "archive is damaged",
                           path, m->name, n, m->unpacked);
    }
    o[n] = 0;
    *out = o;
    *outlen = n;
    return SG_OK;
}

/* The member's name without ".LZW". */
static void plain_name(const zar_member *m, char out[ZAR_NAME])
{
    size_t n = strlen(m->name);
    memcpy(out, m->name, n + 1);
    if (m->lzw)
        out[n - 4] = '\0';
}

int sg_zar_member(const void *bytes, size_t len, const char *path, const char *want,
                  void **out, size_t *outlen, char name[256], sg_diag *d)
{
    const unsigned char *b = bytes;
    size_t off = 0, next;
    zar_member m, found;
    char plain[ZAR_NAME], list[160] = "";
    int nfound = 0, rc, cut = 0;

    if (!bytes || !out || !outlen)
        return sg_diag_set(d, SG_EINVAL, "archive: no bytes or no output");
    if (!path)
        path = "(archive)";
    *out = NULL;
    *outlen = 0;
    if (len == 0)
        return sg_diag_set(d, SG_EPARSE, "%s: the file is empty, not a Zemax archive", path);
    memset(&found, 0, sizeof found);
    while (off < len) {
        if ((rc = member_at(b, len, off, path, &m, &next, d)) != SG_OK)
            return rc;
        plain_name(&m, plain);
        /* A name goes in while the list keeps room for ", ..." after it;
         * the first that does not fit ends the list with it. */
        if (!cut && strlen(list) + 2 + strlen(plain) + sizeof ", ..." <= sizeof list) {
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s",
                     list[0] ? ", " : "", plain);
        } else if (!cut) {
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s",
                     list[0] ? ", ..." : "...");
            cut = 1;
        }
        if (want ? strcasecmp(plain, want) == 0 : ends_with_ci(plain, ".zmx")) {
            if (nfound++ == 0)
                found = m;
        }
        off = next;
    }
    if (nfound == 0)
        return sg_diag_set(d, SG_EPARSE, "%s: the archive holds no %s (it holds %s)", path,
                           want ? want : "lens file (.ZMX)", list);
    if (nfound > 1 && !want)
        return sg_diag_set(d, SG_EUNSUPPORTED,
                           "%s: the archive holds %d lens files (%s); sagitta reads archives "
                           "with one",
                           path, nfound, list);
    if (name)
        plain_name(&found, name);
    return unpack(&found, path, (unsigned char **)out, outlen, d);
}

/* The archive's glass catalogs (.AGF members), for a message. */
static void agf_names(const unsigned char *b, size_t len, char *out, size_t n)
{
    size_t off = 0, next;
    zar_member m;
    char plain[ZAR_NAME];
    out[0] = '\0';
    while (off < len && member_at(b, len, off, "", &m, &next, NULL) == SG_OK) {
        plain_name(&m, plain);
        if (ends_with_ci(plain, ".agf") && strlen(out) + strlen(plain) + 3 < n)
            snprintf(out + strlen(out), n - strlen(out), "%s%s", out[0] ? ", " : "", plain);
        off = next;
    }
}

int sg_zar_parse(sg_system *sys, const void *bytes, size_t len, const char *path,
                 const sg_catalog *cat, sg_diag *d)
{
    void *lens;
    size_t n;
    char inner[ZAR_NAME], where[SG_DIAG_MSG];
    int rc;

    if (!sys || !bytes)
        return sg_diag_set(d, SG_EINVAL, "archive: no system or no bytes");
    if (!path)
        path = "(archive)";
    rc = sg_zar_member(bytes, len, path, NULL, &lens, &n, inner, d);
    if (rc != SG_OK)
        return rc;
    /* Messages name the archive and the lens file in it: "A.zar:L.ZMX:12: ...". */
    snprintf(where, sizeof where, "%s:%s", path, inner);
    rc = sg_zmx_parse(sys, lens, n, where, cat, d);
    free(lens);
    if (rc == SG_ENOGLASS && d) {
        char agf[120];
        agf_names(bytes, len, agf, sizeof agf);
        if (agf[0] && strlen(d->msg) + strlen(agf) + 120 < sizeof d->msg)
            snprintf(d->msg + strlen(d->msg), sizeof d->msg - strlen(d->msg),
                     "; the archive carries the catalogs %s: sagitta reads glasses only from "
                     "its lensdb directory (or SAGITTA_LENSDB), so copy the one needed there",
                     agf);
    }
    return rc;
}

int sg_zar_load(sg_system *sys, const char *path, const sg_catalog *cat, sg_diag *d)
{
    char *buf = NULL;
    size_t len = 0;
    int rc = sg_read_file(path, ZAR_MAX_BYTES, &buf, &len, d);
    if (rc != SG_OK)
        return rc;
    rc = sg_zar_parse(sys, buf, len, path, cat, d);
    free(buf);
    return rc;
}

int sg_zar_detect(const char *path, const void *head, size_t n)
{
    const unsigned char *b = head;
    if (path && ends_with_ci(path, ".zar"))
        return 1;
    /* A member header: 0xEC or 0xEA, then 0x03, as Zemax writes them; no
     * JSON or lens file starts so. */
    return b && n >= 0x14C && (b[0] == 0xEC || b[0] == 0xEA) && b[1] == 0x03;
}
