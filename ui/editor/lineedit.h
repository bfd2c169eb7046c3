/*
 * lineedit.h - a one-line text editor for cells, the ray selector and the
 * ':' line.  It knows key codes but not the terminal.
 */
#ifndef SG_ED_LINEEDIT_H
#define SG_ED_LINEEDIT_H

#include <stddef.h>

#define LE_MAX 4096

typedef struct lineedit {
    char buf[LE_MAX]; /* UTF-8, NUL-terminated */
    size_t len;
    size_t cur;       /* byte offset of the cursor, on a character boundary */
} lineedit;

enum { LE_IGNORED = 0, LE_CHANGED, LE_MOVED, LE_ENTER, LE_CANCEL };

void le_set(lineedit *le, const char *text);
/* Applies a key: printable characters insert; Left, Right, Home, End,
 * Ctrl-A, Ctrl-E move; Backspace, Delete, Ctrl-U, Ctrl-K, Ctrl-W delete;
 * Enter ends; Esc, Ctrl-C and Ctrl-G cancel.  Returns LE_*. */
int le_key(lineedit *le, int key);
/* Which part to show in a field of width columns: the byte offset of the
 * first character and the cursor's column within the field. */
void le_view(const lineedit *le, int width, size_t *start, int *cursor_col);

#endif
