/* batch.c - commands from a script, without a screen. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ed.h"

/* A command fits in ED_LINE bytes, so a longer line is no script of ours;
 * the total is capped too, so an endless input such as /dev/zero or a
 * pipe that never ends in a newline cannot eat the memory. */
#define BATCH_LINE_MAX (ED_LINE - 1)
#define BATCH_TOTAL_MAX ((long long)64 << 20)

/* Reads one line of at most BATCH_LINE_MAX bytes into buf (without the
 * newline).  Returns its length, -1 at the end of the input, -2 when the
 * line is too long, -3 when it holds a NUL byte. */
static long read_line(FILE *f, char *buf, long long *total)
{
    long n = 0;
    int c, nul = 0;
    for (;;) {
        c = getc(f);
        if (c == EOF) {
            if (n == 0 && !nul)
                return -1;
            break;
        }
        (*total)++;
        if (c == '\n')
            break;
        if (c == '\0')
            nul = 1;
        if (n >= BATCH_LINE_MAX)
            return -2;
        buf[n++] = (char)c;
        if (nul)
            return -3;
        if (*total > BATCH_TOTAL_MAX)
            break;
    }
    buf[n] = '\0';
    return nul ? -3 : n;
}

int ed_batch(ed *e, const char *script)
{
    FILE *f;
    char line[ED_LINE];
    long len;
    long long total = 0;
    long lineno = 0;
    int status = 0, flags;
    const char *name = strcmp(script, "-") == 0 ? "(stdin)" : script;

    f = strcmp(script, "-") == 0 ? stdin : fopen(script, "r");
    if (!f) {
        fprintf(stderr, "sagitta edit: %s: %s\n", script, strerror(errno));
        return 1;
    }
    e->batch = 1;
    for (;;) {
        len = read_line(f, line, &total);
        if (len == -1)
            break;
        lineno++;
        if (len == -2) {
            fprintf(stderr, "%s:%ld: the line is longer than %d bytes; a command is shorter\n",
                    name, lineno, BATCH_LINE_MAX);
            status = 1;
            break;
        }
        if (len == -3) {
            fprintf(stderr, "%s:%ld: the line holds a NUL byte; a script is text\n", name,
                    lineno);
            status = 1;
            break;
        }
        if (total > BATCH_TOTAL_MAX) {
            fprintf(stderr, "%s:%ld: the script is longer than %lld MiB; it is stopped here\n",
                    name, lineno, BATCH_TOTAL_MAX >> 20);
            status = 1;
            break;
        }
        while (len > 0 && line[len - 1] == '\r')
            line[--len] = '\0';
        flags = cmd_exec(e, line);
        if (flags & ED_ERROR) {
            fprintf(stderr, "%s:%ld: %s\n", name, lineno, e->msg);
            status = 1;
            break;
        }
        if (flags & ED_QUIT)
            break;
    }
    if (!status && ferror(f)) {
        fprintf(stderr, "sagitta edit: %s: read error\n", name);
        status = 1;
    }
    if (f != stdin)
        fclose(f);
    return status;
}
