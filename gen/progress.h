/* gen/progress.h: progress on stderr for long runs (nbt-gen table builds,
 * nbt-fit mc), shared by the programs like cli.c.
 *
 * On a terminal the current line is rewritten in place; otherwise every
 * update is one line, at most one per NBT_PROGRESS_SECONDS seconds (default
 * 2; 0 prints every update, which the tests use). Quiet: nothing at all.
 * Lines start with the program's name and the run's label. */
#ifndef NBT_GEN_PROGRESS_H
#define NBT_GEN_PROGRESS_H

/* Runs predicted to take longer than this get one early warning line
 * (NBT_PROGRESS_WARN_SECONDS changes it; the tests use a tiny value). */
#define PROGRESS_LONG_SECONDS 60.0

typedef struct {
    const char *what;   /* label, e.g. "mc" */
    double t0, last;    /* start, last line printed (monotonic seconds) */
    double interval;    /* least seconds between lines when not a terminal */
    double long_s;      /* warn when a run is predicted to take longer */
    int quiet, tty;
    int open;           /* a terminal line is shown and not yet ended */
    int warned;         /* the long-run warning was given */
    int finished;       /* the 100% line was printed: later updates print nothing */
} progress;

double progress_clock(void);
void progress_init(progress *p, const char *what, int quiet);
/* One line now (not rate-limited): starts and ends of stages. */
void progress_note(progress *p, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Fraction f in [0, 1] of the work done: percent, elapsed time and ETA
 * (elapsed (1 - f)/f), rate-limited; every update from half a second or 5%
 * on also checks the projected total (elapsed/f) against long_s, until the
 * warning has been given. */
void progress_fraction(progress *p, double f);
/* The early warning, once, when predicted > long_s; basis says
 * where the prediction comes from. */
void progress_warn_long(progress *p, double predicted, const char *basis);
/* Ends a terminal line left open. */
void progress_end(progress *p);

#endif
