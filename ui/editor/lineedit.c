/* lineedit.c - one line of UTF-8 text under a cursor. */
#include "lineedit.h"

#include <string.h>

#include "term.h"

void le_set(lineedit *le, const char *text)
{
    size_t n = strlen(text);
    if (n >= LE_MAX)
        n = LE_MAX - 1;
    /* Never keep half a character. */
    while (n > 0 && ((unsigned char)text[n] & 0xC0) == 0x80)
        n--;
    memcpy(le->buf, text, n);
    le->buf[n] = '\0';
    le->len = le->cur = n;
}

static size_t prev_char(const lineedit *le, size_t i)
{
    if (i == 0)
        return 0;
    i--;
    while (i > 0 && ((unsigned char)le->buf[i] & 0xC0) == 0x80)
        i--;
    return i;
}

static size_t next_char(const lineedit *le, size_t i)
{
    if (i >= le->len)
        return le->len;
    i++;
    while (i < le->len && ((unsigned char)le->buf[i] & 0xC0) == 0x80)
        i++;
    return i;
}

static void erase(lineedit *le, size_t from, size_t to)
{
    memmove(le->buf + from, le->buf + to, le->len - to + 1);
    le->len -= to - from;
    le->cur = from;
}

static int encode(int c, char *out)
{
    if (c < 0x80) {
        out[0] = (char)c;
        return 1;
    }
    if (c < 0x800) {
        out[0] = (char)(0xC0 | (c >> 6));
        out[1] = (char)(0x80 | (c & 0x3F));
        return 2;
    }
    if (c < 0x10000) {
        out[0] = (char)(0xE0 | (c >> 12));
        out[1] = (char)(0x80 | ((c >> 6) & 0x3F));
        out[2] = (char)(0x80 | (c & 0x3F));
        return 3;
    }
    out[0] = (char)(0xF0 | (c >> 18));
    out[1] = (char)(0x80 | ((c >> 12) & 0x3F));
    out[2] = (char)(0x80 | ((c >> 6) & 0x3F));
    out[3] = (char)(0x80 | (c & 0x3F));
    return 4;
}

int le_key(lineedit *le, int key)
{
    size_t i;
    switch (key) {
    case K_ENTER: return LE_ENTER;
    case K_ESC:
    case K_CTRL('c'):
    case K_CTRL('g'): return LE_CANCEL;
    case K_LEFT:
    case K_CTRL('b'): le->cur = prev_char(le, le->cur); return LE_MOVED;
    case K_RIGHT:
    case K_CTRL('f'): le->cur = next_char(le, le->cur); return LE_MOVED;
    case K_HOME:
    case K_CTRL('a'): le->cur = 0; return LE_MOVED;
    case K_END:
    case K_CTRL('e'): le->cur = le->len; return LE_MOVED;
    case K_BACKSPACE:
    case K_CTRL('h'):
        if (le->cur == 0)
            return LE_IGNORED;
        erase(le, prev_char(le, le->cur), le->cur);
        return LE_CHANGED;
    case K_DEL:
    case K_CTRL('d'):
        if (le->cur >= le->len)
            return LE_IGNORED;
        erase(le, le->cur, next_char(le, le->cur));
        return LE_CHANGED;
    case K_CTRL('u'): erase(le, 0, le->cur); return LE_CHANGED;
    case K_CTRL('k'):
        le->buf[le->cur] = '\0';
        le->len = le->cur;
        return LE_CHANGED;
    case K_CTRL('w'):
        i = le->cur;
        while (i > 0 && le->buf[i - 1] == ' ')
            i--;
        while (i > 0 && le->buf[i - 1] != ' ')
            i--;
        erase(le, i, le->cur);
        return LE_CHANGED;
    default:
        if (key >= 0x20 && key < K_BASE && key != 0x7f && !(key >= 0x80 && key < 0xA0)) {
            char enc[4];
            int k = encode(key, enc);
            if (le->len + (size_t)k >= LE_MAX)
                return LE_IGNORED;
            memmove(le->buf + le->cur + k, le->buf + le->cur, le->len - le->cur + 1);
            memcpy(le->buf + le->cur, enc, (size_t)k);
            le->len += (size_t)k;
            le->cur += (size_t)k;
            return LE_CHANGED;
        }
        return LE_IGNORED;
    }
}

void le_view(const lineedit *le, int width, size_t *start, int *cursor_col)
{
    /* Columns from the start of the text to the cursor, one per character. */
    size_t i = 0, s = 0;
    int col = 0;
    for (i = 0; i < le->cur; i = next_char(le, i))
        col++;
    if (width < 2)
        width = 2;
    /* Keep the cursor inside the field, with the text scrolled left. */
    while (col >= width) {
        s = next_char(le, s);
        col--;
    }
    *start = s;
    *cursor_col = col;
}
