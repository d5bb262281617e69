/* gen/progress.c: progress lines on stderr (see progress.h). */
#include <config.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "cli.h"
#include "progress.h"

double progress_clock(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void progress_init(progress *p, const char *what, int quiet)
{
    p->what = what;
    p->t0 = p->last = progress_clock();
    p->quiet = quiet;
    p->tty = stderr_is_tty();
    p->open = p->warned = p->finished = 0;
    p->interval = 2.0;
    const char *e = getenv("NBT_PROGRESS_SECONDS");
    double v;
    if (e && parse_double(e, 0, 0, 3600, 0, &v) == 0)
        p->interval = v;
    p->long_s = PROGRESS_LONG_SECONDS;
    e = getenv("NBT_PROGRESS_WARN_SECONDS");
    if (e && parse_double(e, 0, 0, 1e9, 0, &v) == 0)
        p->long_s = v;
}

/* "1.2 s", "3 min 20 s", "2 h 05 min": durations a reader takes in at a glance */
static void duration(double s, char *buf, size_t n)
{
    if (!(s >= 0))
        s = 0;
    if (s < 60)
        snprintf(buf, n, "%.1f s", s);
    else if (s < 3600)
        snprintf(buf, n, "%d min %02d s", (int)(s / 60), (int)s % 60);
    else
        snprintf(buf, n, "%d h %02d min", (int)(s / 3600), (int)(s / 60) % 60);
}

static void emit(progress *p, int rewrite, const char *text)
{
    if (p->tty && p->open)
        fputs("\r\033[K", stderr);
    fprintf(stderr, "%s: %s: %s", cli_prog, p->what, text);
    if (p->tty && rewrite)
        p->open = 1;
    else {
        fputc('\n', stderr);
        p->open = 0;
    }
    fflush(stderr);
}

void progress_note(progress *p, const char *fmt, ...)
{
    if (p->quiet)
        return;
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    emit(p, 0, buf);
    p->last = progress_clock();
}

void progress_warn_long(progress *p, double predicted, const char *basis)
{
    if (p->quiet || p->warned || !(predicted > p->long_s))
        return;
    char d[32];
    duration(predicted, d, sizeof d);
    p->warned = 1;
    double last = p->last; /* not a progress line: the next one comes as it would have */
    progress_note(p, "warning: this run will take about %s (%s)", d, basis);
    p->last = last;
}

void progress_fraction(progress *p, double f)
{
    if (p->quiet || !(f > 0) || p->finished)
        return;
    double now = progress_clock(), el = now - p->t0, total = el / f;
    /* the projection el/f, once it rests on enough of the run (half a second, or 5% of it: start-up
     * costs are then a small part), at every update until it first exceeds long_s */
    if (!p->warned && (el >= 0.5 || f >= 0.05)) {
        char basis[96];
        snprintf(basis, sizeof basis, "projected from %.3g%% done in %.1f s", 100 * f, el);
        progress_warn_long(p, total, basis);
    }
    if (f < 1 && now - p->last < (p->tty ? 0.2 : p->interval))
        return;
    char a[32], b[32], buf[128];
    duration(el, a, sizeof a);
    duration(total - el, b, sizeof b);
    if (f < 1) /* truncated, so that 100% means done; below 1% with two digits */
        snprintf(buf, sizeof buf, f < 0.01 ? "%.2g%% done, %s elapsed, ETA %s" : "%3.0f%% done, %s elapsed, ETA %s",
                 f < 0.01 ? 100 * f : floor(100 * f), a, b);
    else
        snprintf(buf, sizeof buf, "100%% done, %s", a);
    emit(p, f < 1, buf);
    p->last = now;
    p->finished = f >= 1;
}

void progress_end(progress *p)
{
    if (p->tty && p->open) {
        fputc('\n', stderr);
        p->open = 0;
    }
}
