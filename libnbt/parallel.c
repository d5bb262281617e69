/* libnbt/parallel.c: a minimal parallel for-loop over independent items. */
#include <config.h>
#include <pthread.h>
#include <stdatomic.h>
#include <time.h>
#include <unistd.h>
#include "internal.h"

typedef struct {
    size_t n;
    atomic_size_t next;
    atomic_int status;
    atomic_uint running; /* threads other than the caller's still in their loop */
    nbt__task fn;
    void *ctx;
} pool;

typedef struct {
    pool *p;
    unsigned thread;
} worker_arg;

static void *worker(void *vp)
{
    worker_arg *a = vp;
    pool *p = a->p;
    for (;;) {
        if (atomic_load(&p->status) != NBT_OK)
            break;
        size_t i = atomic_fetch_add(&p->next, 1);
        if (i >= p->n)
            break;
        nbt_status s = p->fn(i, a->thread, p->ctx);
        if (s != NBT_OK) {
            int expected = NBT_OK;
            atomic_compare_exchange_strong(&p->status, &expected, (int)s);
        }
    }
    return NULL;
}

static void *started_worker(void *vp)
{
    worker_arg *a = vp;
    worker(vp);
    atomic_fetch_sub(&a->p->running, 1);
    return NULL;
}

unsigned nbt__nthreads(unsigned requested, size_t n)
{
    unsigned t = requested;
    if (t == 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        t = c > 0 ? (unsigned)c : 1u;
    }
    if (t > 64)
        t = 64;
    if ((size_t)t > n)
        t = n > 0 ? (unsigned)n : 1u;
    return t;
}

nbt_status nbt__parallel_for_watch(size_t n, unsigned nthreads, nbt__task fn, void *ctx, void (*watch)(void *),
                                   void *wctx, double period)
{
    pool p = {.n = n, .fn = fn, .ctx = ctx};
    atomic_init(&p.next, 0);
    atomic_init(&p.status, NBT_OK);
    atomic_init(&p.running, 0);
    unsigned nt = nbt__nthreads(nthreads, n);
    pthread_t th[64];
    worker_arg args[64];
    unsigned started = 0;
    for (unsigned t = 1; t < nt; t++) {
        args[t] = (worker_arg){&p, t};
        atomic_fetch_add(&p.running, 1);
        if (pthread_create(&th[t], NULL, started_worker, &args[t]) != 0) {
            atomic_fetch_sub(&p.running, 1);
            break; /* fewer threads: the loop still completes */
        }
        started = t;
    }
    args[0] = (worker_arg){&p, 0};
    worker(&args[0]);
    if (watch) { /* the caller's items are done: it watches the others finish theirs */
        struct timespec ts = {(time_t)period, (long)(1e9 * (period - (double)(time_t)period))};
        while (atomic_load(&p.running) > 0) {
            watch(wctx);
            nanosleep(&ts, NULL);
        }
    }
    for (unsigned t = 1; t <= started; t++)
        pthread_join(th[t], NULL);
    return (nbt_status)atomic_load(&p.status);
}

nbt_status nbt__parallel_for(size_t n, unsigned nthreads, nbt__task fn, void *ctx)
{
    return nbt__parallel_for_watch(n, nthreads, fn, ctx, NULL, NULL, 0);
}
