/*
 * progress.h - progress of a long run on standard error.
 */
#ifndef SG_UI_PROGRESS_H
#define SG_UI_PROGRESS_H

#include <stddef.h>

/* Shown only on a terminal, never in CI (CI set) or a pipe, first after a
 * second and then four times a second, erased at the end. */
typedef struct ui_progress {
    int on, shown;
    double t0, last;
    const char *what; /* the command, "trace" */
    const char *noun; /* what is counted, "rays" */
} ui_progress;

void ui_progress_init(ui_progress *p, const char *what, const char *noun);
/* count things done, done of total (a percentage when total > 0). */
void ui_progress_show(ui_progress *p, size_t count, unsigned long long done,
                      unsigned long long total);
void ui_progress_end(ui_progress *p);
/* An engine's progress callback (sg_wavefront_opts.progress): ctx is a
 * ui_progress; never asks to stop, as Ctrl-C ends the program. */
int ui_progress_cb(void *ctx, size_t done, size_t total);

#endif
