/* safetext.c - text from files made safe to print on a terminal. */
#include "safetext.h"

#include <string.h>

size_t safe_char_len(const unsigned char *s, size_t n)
{
    unsigned c = s[0];
    size_t len, k;
    unsigned long cp;
    if (c < 0x20 || c == 0x7f)
        return 0;
    if (c < 0x80)
        return 1;
    if (c >= 0xc2 && c <= 0xdf) {
        len = 2;
        cp = c & 0x1f;
    } else if (c >= 0xe0 && c <= 0xef) {
        len = 3;
        cp = c & 0x0f;
    } else if (c >= 0xf0 && c <= 0xf4) {
        len = 4;
        cp = c & 0x07;
    } else {
        return 0;
    }
    if (n < len)
        return 0;
    for (k = 1; k < len; k++) {
        if ((s[k] & 0xc0) != 0x80)
            return 0;
        cp = (cp << 6) | (s[k] & 0x3f);
    }
    /* Overlong forms, surrogates, beyond U+10FFFF, and the C1 controls,
     * which some terminals obey as ESC sequences. */
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10ffff)) ||
        (cp >= 0xd800 && cp <= 0xdfff) || (cp >= 0x80 && cp <= 0x9f))
        return 0;
    return len;
}

const char *safe_text(const char *s, char *buf, size_t n)
{
    const unsigned char *p = (const unsigned char *)(s ? s : "");
    size_t left = strlen((const char *)p), used = 0;
    if (n == 0)
        return buf;
    while (left > 0) {
        size_t k = safe_char_len(p, left);
        size_t w = k ? k : 1;
        if (used + w >= n)
            break;
        if (k)
            memcpy(buf + used, p, k);
        else
            buf[used] = '?';
        used += w;
        p += w;
        left -= w;
    }
    buf[used] = '\0';
    return buf;
}

int safe_fputs(const char *s, FILE *f)
{
    const unsigned char *p = (const unsigned char *)(s ? s : "");
    size_t left = strlen((const char *)p);
    while (left > 0) {
        size_t k = safe_char_len(p, left);
        if (k) {
            if (fwrite(p, 1, k, f) != k)
                return EOF;
        } else if (fputc('?', f) == EOF) {
            return EOF;
        }
        p += k ? k : 1;
        left -= k ? k : 1;
    }
    return 0;
}
