/*
 * progress.c - progress of a long run on standard error.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "progress.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void ui_progress_init(ui_progress *p, const char *what, const char *noun)
{
    const char *ci = getenv("CI");
    memset(p, 0, sizeof *p);
    p->on = isatty(STDERR_FILENO) && !(ci && ci[0]);
    p->t0 = p->last = now_s();
    p->what = what;
    p->noun = noun;
}

void ui_progress_show(ui_progress *p, size_t count, unsigned long long done,
                      unsigned long long total)
{
    double t;
    if (!p->on)
        return;
    t = now_s();
    if (t - p->t0 < 1.0 || t - p->last < 0.25)
        return;
    p->last = t;
    p->shown = 1;
    if (total > 0)
        fprintf(stderr, "\rsagitta: %s: %5.1f%%, %zu %s, %.0f s", p->what,
                100.0 * (double)done / (double)total, count, p->noun, t - p->t0);
    else
        fprintf(stderr, "\rsagitta: %s: %zu %s, %.0f s", p->what, count, p->noun, t - p->t0);
    fflush(stderr);
}

void ui_progress_end(ui_progress *p)
{
    if (p->shown)
        fputs("\r\033[K", stderr);
    p->shown = 0;
}

int ui_progress_cb(void *ctx, size_t done, size_t total)
{
    ui_progress_show(ctx, done, done, total);
    return 0;
}
