/* libnbt/rng.h: the counter-seeded generator every Monte Carlo in libnbt
 * uses (not installed). xoshiro256+ seeded from (seed, stream index) by
 * splitmix64: each stream (a photon, a pixel sample) depends on nothing
 * else, whichever thread runs it, so results do not depend on threads. */
#ifndef NBT_RNG_H
#define NBT_RNG_H

#include <stdint.h>

typedef struct {
    uint64_t s[4];
} nbt__rng;

static inline uint64_t nbt__splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}

static inline void nbt__rng_seed(nbt__rng *r, uint64_t seed, uint64_t stream)
{
    uint64_t x = seed ^ (stream * 0xd1b54a32d192ed03u);
    nbt__splitmix(&x);
    for (int i = 0; i < 4; i++)
        r->s[i] = nbt__splitmix(&x);
}

static inline uint64_t nbt__rotl(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

/* uniform in [0, 1) */
static inline double nbt__rng_u(nbt__rng *r)
{
    uint64_t *s = r->s, res = s[0] + s[3], t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = nbt__rotl(s[3], 45);
    return (double)(res >> 11) * 0x1.0p-53;
}

/* the same as a callback for nbt__phase_sample_mu */
static inline double nbt__rng_cb(void *r)
{
    return nbt__rng_u(r);
}

#endif
