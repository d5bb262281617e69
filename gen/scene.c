/* gen/scene.c: reading a scene file (doc/scene-format.md). Errors are
 * returned, not exited on, so the parser can be fuzzed (tests/fuzz_parsers.c). */
#include <config.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include "cli.h"
#include "scene.h"

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    char *e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\n' || e[-1] == '\r'))
        *--e = '\0';
    return s;
}

static int yesno(const char *file, int line, const char *key, const char *v, int *out, char *err, size_t n)
{
    if (!strcmp(v, "yes") || !strcmp(v, "no")) {
        *out = !strcmp(v, "yes");
        return 0;
    }
    snprintf(err, n, "%s:%d: %s = '%s' is not accepted: yes or no", file, line, key, v);
    return -1;
}

/* values the file set (the rest keeps nbt_scene_init's defaults) */
typedef struct {
    int have_kt, have_d;
    long orders_max;
    char phase[256];
} seen_t;

static const char *const scene_keys[] = {"kappa_t", "kappa_s", "distance", "g", "basis", "phase",
                                         "airlight", "diffuse", "phong", "tol", "half", "orders_max", "form"};
#define NKEYS (sizeof scene_keys / sizeof scene_keys[0])

static int parse_lines(FILE *f, const char *path, nbt_scene *s, seen_t *seen, char *err, size_t n)
{
    char buf[1024], opt[160];
    int line = 0, first[NKEYS] = {0}; /* the line that set each key */
    while (fgets(buf, sizeof buf, f)) {
        line++;
        char *h = strchr(buf, '#');
        if (h)
            *h = '\0';
        char *l = trim(buf);
        if (!*l)
            continue;
        char *eq = strchr(l, '=');
        if (!eq) {
            snprintf(err, n, "%s:%d: expected 'key = value', got '%s'", path, line, l);
            return -1;
        }
        *eq = '\0';
        char *key = trim(l), *val = trim(eq + 1);
        snprintf(opt, sizeof opt, "%s:%d: %s", path, line, key);
        /* a second value would silently replace the first: refuse it */
        for (size_t i = 0; i < NKEYS; i++)
            if (!strcmp(key, scene_keys[i])) {
                if (first[i]) {
                    snprintf(err, n, "%s:%d: %s is given twice (first at line %d): give each key once", path, line,
                             key, first[i]);
                    return -1;
                }
                first[i] = line;
            }
        if (!strcmp(key, "kappa_t")) {
            if (msg_range(err, n, opt, val, 0, 1e3, &s->kappa_t[0], &s->kappa_t[1]))
                return -1;
            if (!(s->kappa_t[1] > 0)) {
                snprintf(err, n, "%s = '%s' is not accepted: extinction must be > 0", opt, val);
                return -1;
            }
            seen->have_kt = 1;
        } else if (!strcmp(key, "kappa_s")) {
            if (msg_range(err, n, opt, val, 0, 1e3, &s->kappa_s[0], &s->kappa_s[1]))
                return -1;
        } else if (!strcmp(key, "distance")) {
            if (msg_range(err, n, opt, val, 0, 1e9, &s->distance[0], &s->distance[1]))
                return -1;
            if (!(s->distance[1] > 0)) {
                snprintf(err, n, "%s = '%s' is not accepted: the largest distance must be > 0", opt, val);
                return -1;
            }
            seen->have_d = 1;
        } else if (!strcmp(key, "g")) {
            if (msg_range(err, n, opt, val, -0.99, 0.99, &s->g[0], &s->g[1]))
                return -1;
            s->have_g = 1;
        } else if (!strcmp(key, "basis")) {
            nbt_basis b;
            if (nbt_basis_parse(val, &b) != NBT_OK) {
                snprintf(err, n, "%s = '%s' is not accepted: auto, legendre or slices", opt, val);
                return -1;
            }
            s->basis = (int)b;
        } else if (!strcmp(key, "phase")) {
            snprintf(seen->phase, sizeof seen->phase, "%s", val);
        } else if (!strcmp(key, "airlight")) {
            if (yesno(path, line, key, val, &s->airlight, err, n))
                return -1;
        } else if (!strcmp(key, "diffuse")) {
            if (yesno(path, line, key, val, &s->diffuse, err, n))
                return -1;
        } else if (!strcmp(key, "half")) {
            if (yesno(path, line, key, val, &s->half, err, n))
                return -1;
        } else if (!strcmp(key, "form")) {
            if (strcmp(val, "plain") && strcmp(val, "sub")) {
                snprintf(err, n, "%s = '%s' is not accepted: plain or sub", opt, val);
                return -1;
            }
            s->sub = !strcmp(val, "sub");
        } else if (!strcmp(key, "orders_max")) {
            if (msg_long(err, n, opt, val, 1, 512, &seen->orders_max))
                return -1;
        } else if (!strcmp(key, "tol")) {
            if (msg_double(err, n, opt, val, 1e-7, 0, 0.5, 0, &s->tol))
                return -1;
        } else if (!strcmp(key, "phong")) {
            char *save = NULL;
            for (char *tok = strtok_r(val, " ,", &save); tok; tok = strtok_r(NULL, " ,", &save)) {
                long e;
                if (s->nphong == NBT_SCENE_MAX_PHONG) {
                    snprintf(err, n, "%s: at most 16 Phong exponents", opt);
                    return -1;
                }
                if (msg_long(err, n, opt, tok, 2, 10000, &e))
                    return -1;
                s->phong[s->nphong++] = (int)e;
            }
        } else {
            snprintf(err, n, "%s:%d: unknown key '%s': accepted are kappa_t, kappa_s, distance, g, basis, phase, "
                     "airlight, diffuse, phong, tol, half, orders_max, form", path, line, key);
            return -1;
        }
    }
    return 0;
}

int scene_parse(const char *path, nbt_scene *s, nbt_phase **ph, char *err, size_t n)
{
    *ph = NULL;
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, n, "scene: cannot open '%s': %s", path, strerror(errno));
        return -1;
    }
    nbt_scene_init(s);
    seen_t seen = {0, 0, NBT_PLAN_GL_ORDERS, ""};
    int rc = parse_lines(f, path, s, &seen, err, n);
    fclose(f);
    if (rc)
        return -1;
    if (!seen.have_kt || !seen.have_d) {
        snprintf(err, n, "%s: no '%s = ...' line: kappa_t and distance are required", path,
                 !seen.have_kt ? "kappa_t" : "distance");
        return -1;
    }
    s->orders_max = (size_t)seen.orders_max;
    if (seen.phase[0]) {
        char perr[256];
        if (nbt_phase_parse(seen.phase, ph, perr, sizeof perr) != NBT_OK) {
            snprintf(err, n, "%s: phase: %s", path, perr);
            return -1;
        }
        s->phase = *ph;
    }
    char cerr[512];
    if (nbt_scene_check(s, cerr, sizeof cerr) != NBT_OK) {
        snprintf(err, n, "%s: %s", path, cerr);
        nbt_phase_free(*ph);
        *ph = NULL;
        return -1;
    }
    return 0;
}
