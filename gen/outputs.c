/* gen/outputs.c: see outputs.h. The list is only ever prepended to (a node
 * is complete before it is published) and never freed, so the signal
 * handler can walk it at any moment using only unlink, rmdir, write and
 * raise, which are async-signal-safe. */
#include <config.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include "outputs.h"

enum { F_IDLE, F_WRITING, F_DONE, F_FAILED, F_DIR, F_KEPT };

struct outputs_file {
    char *path, *tmp;
    atomic_int state;
    struct outputs_file *next;
};

static _Atomic(outputs_file *) head;
static atomic_int stopping;
/* files between outputs_begin and outputs_end: all threads, and this thread's
 * own (a writer interrupted by the handler cannot finish while it waits) */
static atomic_int inflight;
static _Thread_local int inflight_here;

static outputs_file *push(const char *path, int state)
{
    size_t n = strlen(path) + 1;
    outputs_file *f = malloc(sizeof *f);
    char *p = malloc(n), *t = malloc(n + 32);
    if (!f || !p || !t) {
        free(f);
        free(p);
        free(t);
        return NULL;
    }
    memcpy(p, path, n);
    snprintf(t, n + 32, "%s.tmp%ld", path, (long)getpid());
    f->path = p;
    f->tmp = t;
    atomic_init(&f->state, state);
    f->next = atomic_load(&head);
    while (!atomic_compare_exchange_weak(&head, &f->next, f))
        ;
    return f;
}

/* Remove what is not kept. A file being written: its temporary; if that was
 * already gone, the rename may have happened, so the file too (it was
 * about to replace any older one of that name anyway). */
static int remove_all(void)
{
    int touched = 0; /* files or directories this run made (removed now) */
    for (outputs_file *f = atomic_load(&head); f; f = f->next) {
        int st = atomic_exchange(&f->state, F_KEPT);
        touched += st == F_WRITING || st == F_DONE || st == F_FAILED || st == F_DIR;
        if (st == F_WRITING) {
            if (unlink(f->tmp) != 0)
                unlink(f->path);
        } else if (st == F_DONE)
            unlink(f->path);
        else if (st == F_FAILED)
            unlink(f->tmp);
        else if (st == F_DIR)
            rmdir(f->path); /* nodes are newest first: its files are gone by now */
        else if (st != F_KEPT)
            atomic_store(&f->state, st);
    }
    return touched;
}

static void on_signal(int sig)
{
    atomic_store(&stopping, 1);
    /* A writer thread may be about to create its temporary: removing first
     * and dying next would leave it behind. No new write starts now
     * (outputs_begin sees stopping); wait for those in flight to end, at
     * most 2 s (a write blocked for good, e.g. on a FIFO, is removed as it
     * stands). */
    struct timespec tick = {0, 10000000};
    for (int i = 0; i < 200 && atomic_load(&inflight) - inflight_here > 0; i++)
        nanosleep(&tick, NULL);
    static const char msg[] = "nbt-gen: interrupted: the files of this run were removed\n";
    static const char none[] = "nbt-gen: interrupted (no files written yet)\n";
    ssize_t w = remove_all() ? write(STDERR_FILENO, msg, sizeof msg - 1) : write(STDERR_FILENO, none, sizeof none - 1);
    (void)w;
    signal(sig, SIG_DFL);
    raise(sig); /* the shell sees the signal: exit status 128 + sig */
}

static void at_exit(void)
{
    (void)remove_all(); /* nothing after outputs_commit */
}

void outputs_install(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    int sigs[3] = {SIGINT, SIGTERM, SIGHUP};
    for (int i = 0; i < 3; i++) {
        struct sigaction old;
        /* a signal ignored by the caller (nohup) stays ignored */
        if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(sigs[i], &sa, NULL);
    }
    atexit(at_exit);
}

outputs_file *outputs_add(const char *path)
{
    return push(path, F_IDLE);
}

int outputs_begin(outputs_file *f)
{
    /* counted before stopping is read, the handler sets stopping before it
     * reads the count: one of the two sees the other */
    atomic_fetch_add(&inflight, 1);
    inflight_here++;
    if (atomic_load(&stopping)) {
        inflight_here--;
        atomic_fetch_sub(&inflight, 1);
        return 1;
    }
    if (f)
        atomic_store(&f->state, F_WRITING);
    return 0;
}

void outputs_end(outputs_file *f, int ok)
{
    if (f)
        atomic_store(&f->state, ok ? F_DONE : F_FAILED);
    inflight_here--;
    atomic_fetch_sub(&inflight, 1);
}

void outputs_dir(const char *dir)
{
    push(dir, F_DIR);
}

void outputs_commit(void)
{
    for (outputs_file *f = atomic_load(&head); f; f = f->next)
        atomic_store(&f->state, F_KEPT);
}

void outputs_abort(void)
{
    remove_all();
}
