/* messages.c - the message history (:messages): every status line message
 * and warning so far, whole, wrapped to the screen, the newest last. */
#include <stdio.h>
#include <string.h>

#include "term.h"
#include "ui.h"

/* Where the next row of s ends at width w: after the last blank that fits,
 * or at w (on a character's first byte) when a word is longer. */
static int row_end(const char *s, int w)
{
    int len = (int)strlen(s), k;
    if (len <= w)
        return len;
    for (k = w; k > w / 2; k--)
        if (s[k] == ' ')
            return k;
    k = w;
    while (k > 0 && ((unsigned char)s[k] & 0xC0) == 0x80)
        k--;
    return k > 0 ? k : w;
}

/* Lays out the history at width w: calls out (may be NULL) for each row
 * and returns the rows. */
static int layout(const ui *u, int w,
                  void (*out)(const ui *, int, int, int, const char *, int, void *), void *arg)
{
    const ed *e = u->e;
    int i, r = 0;
    for (i = 0; i < e->nhist; i++) {
        const char *s = e->hist[i] + 1;
        int err = e->hist[i][0] == '!', first = 1;
        do {
            /* Continuation rows are indented, so each message reads as one. */
            int ind = first ? 0 : 2, n = row_end(s, w - ind > 8 ? w - ind : w);
            if (out)
                out(u, r, err, ind, s, n, arg);
            s += n;
            while (*s == ' ')
                s++;
            r++;
            first = 0;
        } while (*s);
    }
    return r;
}

static void put_row(const ui *u, int r, int err, int ind, const char *s, int n, void *arg)
{
    int y = 1 + r - *(const int *)arg;
    char buf[ED_MSG + 8];
    if (y < 1 || y > u->rows - 2)
        return;
    snprintf(buf, sizeof buf, "%*s%.*s", ind, "", n, s);
    term_text(y, 0, u->cols, err ? T_ERROR : T_NORMAL, 1, buf);
}

void messages_draw(ui *u)
{
    int h = u->rows - 2, total = layout(u, u->cols, NULL, NULL), i;
    char buf[128];
    /* Opened at the newest message; scrolling stays within the text. */
    if (u->msg_top < 0 || u->msg_top > total - h)
        u->msg_top = total - h;
    if (u->msg_top < 0)
        u->msg_top = 0;
    term_fill(0, 0, u->cols, T_TITLE);
    term_text(0, 0, u->cols, T_TITLE, 1,
              " Messages, the newest last   Up/Down PgUp/PgDn scroll, Esc closes");
    for (i = 1; i <= h; i++)
        term_fill(i, 0, u->cols, T_NORMAL);
    if (u->e->nhist == 0)
        term_text(1, 0, u->cols, T_DIM, 1, "no messages yet");
    layout(u, u->cols, put_row, &u->msg_top);
    snprintf(buf, sizeof buf, " %d message%s, lines %d-%d of %d", u->e->nhist,
             u->e->nhist == 1 ? "" : "s", total ? u->msg_top + 1 : 0,
             u->msg_top + h < total ? u->msg_top + h : total, total);
    term_text(u->rows - 1, 0, u->cols, T_DIM, 1, buf);
}

int messages_key(ui *u, int key)
{
    /* End is -1: the drawing puts the newest message last. */
    if (ui_page_key(&u->msg_top, u->rows - 2, key, -1)) {
        if (u->msg_top < -1)
            u->msg_top = 0;
        return ED_HANDLED | ED_REDRAW;
    }
    switch (key) {
    case K_ESC:
    case 'q':
    case K_ENTER: u->mode = MODE_NORMAL; return ED_HANDLED | ED_REDRAW;
    default: return ED_HANDLED;
    }
}
