/*
 * safetext.h - text from files (titles, comments, file names) made safe to
 * print on a terminal.
 *
 * A design's title or a file's name may hold escape sequences that would
 * drive the user's terminal: move the cursor, rewrite the screen, set the
 * window title.  Every report and message that prints such text passes it
 * through here, as the editor's screen does: C0 controls (including ESC),
 * DEL, C1 controls (U+0080 to U+009F) and bytes that are not UTF-8 are each
 * shown as '?'.  Other UTF-8 (a title of "f/5 µm") is kept.
 */
#ifndef SG_UI_SAFETEXT_H
#define SG_UI_SAFETEXT_H

#include <stddef.h>
#include <stdio.h>

/* Length of the UTF-8 character at s (up to n bytes) that may be printed
 * as is, or 0 when its first byte must be shown as '?'. */
size_t safe_char_len(const unsigned char *s, size_t n);

/* s made safe, into buf of n bytes (cut short to fit, never mid-character);
 * returns buf.  A NULL s gives "". */
const char *safe_text(const char *s, char *buf, size_t n);

/* Writes s made safe to f; returns what fputs returns. */
int safe_fputs(const char *s, FILE *f);

#endif
