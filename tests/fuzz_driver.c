/* tests/fuzz_driver.c: runs tests/fuzz_parsers.c without libFuzzer: every
 * file given (or in a directory given) once, then, with -t SECONDS, random
 * mutations of them (bit flips, random and boundary bytes, inserted, deleted
 * and duplicated runs, truncation, splices of two inputs; the first byte, the
 * reader, kept most of the time) until the time is up. Deterministic for a
 * seed (-s): a failure reproduces with the seed it printed, and with
 * NBT_FUZZ_SAVE=FILE the failing input is left in FILE.
 *   fuzz_replay [-t SECONDS] [-s SEED] FILE|DIR ... */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct {
    uint8_t *d;
    size_t n;
} input;
static input *in;
static size_t nin, cap;

static void add_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "fuzz_replay: cannot open '%s'\n", path);
        exit(2);
    }
    uint8_t *d = NULL;
    size_t n = 0, c = 0;
    for (;;) {
        if (n == c) {
            c = c ? 2 * c : 4096;
            d = realloc(d, c);
            if (!d)
                exit(1);
        }
        size_t r = fread(d + n, 1, c - n, f);
        n += r;
        if (r == 0)
            break;
    }
    fclose(f);
    if (nin == cap) {
        cap = cap ? 2 * cap : 64;
        in = realloc(in, cap * sizeof *in);
        if (!in)
            exit(1);
    }
    in[nin].d = d;
    in[nin].n = n;
    nin++;
}

static void add(const char *path)
{
    struct stat st;
    if (stat(path, &st)) {
        fprintf(stderr, "fuzz_replay: cannot open '%s'\n", path);
        exit(2);
    }
    if (!S_ISDIR(st.st_mode)) {
        add_file(path);
        return;
    }
    DIR *dp = opendir(path);
    struct dirent *e;
    while (dp && (e = readdir(dp))) {
        if (e->d_name[0] == '.')
            continue;
        char p[4096];
        snprintf(p, sizeof p, "%s/%s", path, e->d_name);
        add(p);
    }
    if (dp)
        closedir(dp);
}

static uint64_t rs;
static uint64_t rnd(void) /* splitmix64 */
{
    uint64_t z = (rs += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return z ^ (z >> 31);
}
static size_t below(size_t n) { return n ? (size_t)(rnd() % n) : 0; }

/* one mutated copy of a corpus entry in buf (capacity cap); returns its size */
static size_t mutate(uint8_t *buf, size_t bcap)
{
    const input *a = &in[below(nin)];
    size_t n = a->n < bcap ? a->n : bcap;
    memcpy(buf, a->d, n);
    static const uint8_t special[] = {0, 1, 0x7f, 0x80, 0xff, '\n', ' ', '#', '-', '.', 'e', '9', ',', ':', 'n', 'i'};
    int steps = 1 + (int)below(4);
    for (int s = 0; s < steps; s++) {
        size_t lo = n > 1 ? 1 : 0; /* keep the reader byte */
        if (below(50) == 0)
            lo = 0;
        switch (below(7)) {
        case 0: /* bit flip */
            if (n > lo)
                buf[lo + below(n - lo)] ^= (uint8_t)(1u << below(8));
            break;
        case 1: /* a special byte */
            if (n > lo)
                buf[lo + below(n - lo)] = special[below(sizeof special)];
            break;
        case 2: /* random byte inserted */
            if (n < bcap) {
                size_t p = lo + below(n - lo + 1);
                memmove(buf + p + 1, buf + p, n - p);
                buf[p] = (uint8_t)rnd();
                n++;
            }
            break;
        case 3: { /* a run deleted */
            if (n > lo) {
                size_t p = lo + below(n - lo), k = 1 + below(n - p < 16 ? n - p : 16);
                memmove(buf + p, buf + p + k, n - p - k);
                n -= k;
            }
            break;
        }
        case 4: /* truncated */
            if (n > lo)
                n = lo + below(n - lo + 1);
            break;
        case 5: { /* a run duplicated */
            if (n > lo) {
                size_t p = lo + below(n - lo), k = 1 + below(n - p < 32 ? n - p : 32);
                if (n + k <= bcap) {
                    memmove(buf + p + k, buf + p, n - p);
                    n += k;
                }
            }
            break;
        }
        default: { /* the tail of another input spliced in */
            const input *b = &in[below(nin)];
            if (b->n > 1) {
                size_t p = lo + below(n - lo + 1), q = 1 + below(b->n - 1), k = b->n - q;
                if (p + k > bcap)
                    k = bcap - p;
                memcpy(buf + p, b->d + q, k);
                n = p + k;
            }
            break;
        }
        }
    }
    return n;
}

int main(int argc, char **argv)
{
    double seconds = 0;
    uint64_t seed = (uint64_t)time(NULL);
    int i = 1;
    for (; i < argc && argv[i][0] == '-'; i += 2) {
        if (i + 1 >= argc)
            break;
        if (!strcmp(argv[i], "-t"))
            seconds = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "-s"))
            seed = strtoull(argv[i + 1], NULL, 10);
        else {
            fprintf(stderr, "fuzz_replay: unknown option '%s': -t SECONDS, -s SEED\n", argv[i]);
            return 2;
        }
    }
    if (i >= argc) {
        fprintf(stderr, "usage: fuzz_replay [-t SECONDS] [-s SEED] FILE|DIR ...\n");
        return 2;
    }
    for (; i < argc; i++)
        add(argv[i]);
    if (nin == 0) {
        fprintf(stderr, "fuzz_replay: no inputs\n");
        return 2;
    }
    for (size_t k = 0; k < nin; k++)
        LLVMFuzzerTestOneInput(in[k].d, in[k].n);
    printf("fuzz_replay: %zu corpus inputs replayed\n", nin);
    fflush(stdout);
    if (seconds > 0) {
        rs = seed;
        printf("fuzz_replay: mutating for %g s, seed %llu\n", seconds, (unsigned long long)seed);
        fflush(stdout);
        const char *save = getenv("NBT_FUZZ_SAVE");
        size_t bcap = 1 << 16;
        uint8_t *buf = malloc(bcap);
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        unsigned long long runs = 0;
        double el = 0;
        do {
            for (int k = 0; k < 64; k++, runs++) {
                /* an exact-size copy, so that ASan sees any read past the end */
                size_t n = mutate(buf, bcap);
                uint8_t *x = malloc(n ? n : 1);
                memcpy(x, buf, n);
                if (save) { /* NBT_FUZZ_SAVE=FILE: each input written first, so a crash leaves it there */
                    FILE *sf = fopen(save, "wb");
                    if (sf) {
                        fwrite(x, 1, n, sf);
                        fclose(sf);
                    }
                }
                LLVMFuzzerTestOneInput(x, n);
                free(x);
            }
            clock_gettime(CLOCK_MONOTONIC, &t1);
            el = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        } while (el < seconds);
        printf("fuzz_replay: %llu mutated inputs in %.1f s, no failure\n", runs, el);
        free(buf);
    }
    for (size_t k = 0; k < nin; k++)
        free(in[k].d);
    free(in);
    return 0;
}
