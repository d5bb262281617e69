/* libnbt/jcache.c: a store of G rows (nbt__jcache, internal.h) shared by the
 * J builds of one plan. G_k(T, g) does not depend on the cosine exponent n
 * or on theta, so J^1 and the Phong sets of a scene, and their planning
 * proxies, need the same rows wherever their T nodes coincide. */
#include <config.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include "internal.h"

typedef struct {
    nbt__jkey k;       /* k.hg: the entry's own copy */
    double *row;       /* k.len values, then the errors (nerr(&k)) */
} entry;

static size_t nerr(const nbt__jkey *k)
{
    return k->hg ? k->fdim : 1;
}

struct nbt__jcache {
    pthread_mutex_t mu;
    entry *e;          /* open addressing, cap slots, row == NULL: empty */
    size_t cap, used, bytes, max_bytes;
};

nbt__jcache *nbt__jcache_alloc(size_t max_bytes)
{
    nbt__jcache *c = calloc(1, sizeof *c);
    if (!c)
        return NULL;
    if (pthread_mutex_init(&c->mu, NULL) != 0) {
        free(c);
        return NULL;
    }
    c->max_bytes = max_bytes;
    return c;
}

void nbt__jcache_free(nbt__jcache *c)
{
    if (!c)
        return;
    for (size_t i = 0; i < c->cap; i++) {
        free(c->e[i].row);
        free((double *)c->e[i].k.hg);
    }
    free(c->e);
    pthread_mutex_destroy(&c->mu);
    free(c);
}

static int same(const nbt__jkey *a, const nbt__jkey *b)
{
    return memcmp(&a->T, &b->T, sizeof a->T) == 0 && a->tol == b->tol && a->len == b->len && a->ngeo == b->ngeo &&
           a->nhi == b->nhi && a->split == b->split && a->fdim == b->fdim && !a->hg == !b->hg &&
           (!a->hg || memcmp(a->hg, b->hg, a->fdim * sizeof *a->hg) == 0);
}

static size_t slot(const nbt__jcache *c, const nbt__jkey *k)
{
    unsigned long long h;
    memcpy(&h, &k->T, sizeof h);
    h ^= (unsigned long long)k->len * 0x9e3779b97f4a7c15ull ^ (unsigned long long)k->split << 7 ^
         (unsigned long long)k->fdim << 17;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    size_t i = (size_t)h & (c->cap - 1);
    while (c->e[i].row && !same(&c->e[i].k, k))
        i = (i + 1) & (c->cap - 1);
    return i;
}

int nbt__jcache_get(nbt__jcache *c, const nbt__jkey *k, double *row, double *err)
{
    int hit = 0;
    pthread_mutex_lock(&c->mu);
    if (c->cap) {
        entry *e = &c->e[slot(c, k)];
        if (e->row) {
            memcpy(row, e->row, k->len * sizeof *row);
            memcpy(err, e->row + k->len, nerr(k) * sizeof *err);
            hit = 1;
        }
    }
    pthread_mutex_unlock(&c->mu);
    return hit;
}

void nbt__jcache_put(nbt__jcache *c, const nbt__jkey *k, const double *row, const double *err)
{
    pthread_mutex_lock(&c->mu);
    size_t need = (k->len + nerr(k)) * sizeof *row, ng = k->hg ? k->fdim * sizeof *k->hg : 0;
    if (c->bytes + need > c->max_bytes) /* full: later rows are computed again */
        goto out;
    if (2 * (c->used + 1) > c->cap) { /* grow: load factor <= 1/2 */
        size_t ncap = c->cap ? 2 * c->cap : 256;
        entry *old = c->e, *ne = calloc(ncap, sizeof *ne);
        if (!ne)
            goto out;
        size_t ocap = c->cap;
        c->e = ne;
        c->cap = ncap;
        for (size_t i = 0; i < ocap; i++)
            if (old[i].row)
                c->e[slot(c, &old[i].k)] = old[i];
        free(old);
    }
    entry *e = &c->e[slot(c, k)];
    if (e->row)
        goto out;
    double *hg = ng ? malloc(ng) : NULL;
    if ((ng && !hg) || !(e->row = malloc(need))) {
        free(hg);
        goto out;
    }
    memcpy(e->row, row, k->len * sizeof *row);
    memcpy(e->row + k->len, err, nerr(k) * sizeof *err);
    e->k = *k;
    if (ng)
        e->k.hg = memcpy(hg, k->hg, ng);
    c->used++;
    c->bytes += need + ng;
out:
    pthread_mutex_unlock(&c->mu);
}
