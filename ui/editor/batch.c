/* batch.c - commands from a script, without a screen. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ed.h"

int ed_batch(ed *e, const char *script)
{
    FILE *f;
    char *line = NULL;
    size_t cap = 0;
    ssize_t len;
    long lineno = 0;
    int status = 0, flags;
    const char *name = strcmp(script, "-") == 0 ? "(stdin)" : script;

    f = strcmp(script, "-") == 0 ? stdin : fopen(script, "r");
    if (!f) {
        fprintf(stderr, "sagitta edit: %s: %s\n", script, strerror(errno));
        return 1;
    }
    e->batch = 1;
    while ((len = getline(&line, &cap, f)) >= 0) {
        lineno++;
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r'))
            line[--len] = '\0';
        if (strlen(line) != (size_t)len) {
            fprintf(stderr, "%s:%ld: the line holds a NUL byte\n", name, lineno);
            status = 1;
            break;
        }
        flags = cmd_exec(e, line);
        if (flags & ED_ERROR) {
            fprintf(stderr, "%s:%ld: %s\n", name, lineno, e->msg);
            status = 1;
            break;
        }
        if (flags & ED_QUIT)
            break;
    }
    if (ferror(f)) {
        fprintf(stderr, "sagitta edit: %s: read error\n", name);
        status = 1;
    }
    free(line);
    if (f != stdin)
        fclose(f);
    return status;
}
