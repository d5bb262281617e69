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

static int parse_lines(FILE *f, const char *path, scene_t *s, char *err, size_t n)
{
    char buf[1024], opt[160];
    int line = 0;
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
        if (!strcmp(key, "kappa_t")) {
            if (msg_range(err, n, opt, val, 0, 1e3, &s->kt_lo, &s->kt_hi))
                return -1;
            if (!(s->kt_hi > 0)) {
                snprintf(err, n, "%s = '%s' is not accepted: extinction must be > 0", opt, val);
                return -1;
            }
            s->have_kt = 1;
        } else if (!strcmp(key, "kappa_s")) {
            if (msg_range(err, n, opt, val, 0, 1e3, &s->ks_lo, &s->ks_hi))
                return -1;
            s->have_ks = 1;
        } else if (!strcmp(key, "distance")) {
            if (msg_range(err, n, opt, val, 0, 1e9, &s->d_lo, &s->d_hi))
                return -1;
            if (!(s->d_hi > 0)) {
                snprintf(err, n, "%s = '%s' is not accepted: the largest distance must be > 0", opt, val);
                return -1;
            }
            s->have_d = 1;
        } else if (!strcmp(key, "g")) {
            if (msg_range(err, n, opt, val, -0.99, 0.99, &s->g_lo, &s->g_hi))
                return -1;
            s->have_g = 1;
        } else if (!strcmp(key, "phase")) {
            snprintf(s->phase, sizeof s->phase, "%s", val);
        } else if (!strcmp(key, "airlight")) {
            if (yesno(path, line, key, val, &s->airlight, err, n))
                return -1;
        } else if (!strcmp(key, "diffuse")) {
            if (yesno(path, line, key, val, &s->diffuse, err, n))
                return -1;
        } else if (!strcmp(key, "half")) {
            if (yesno(path, line, key, val, &s->half, err, n))
                return -1;
        } else if (!strcmp(key, "orders_max")) {
            if (msg_long(err, n, opt, val, 1, 512, &s->orders_max))
                return -1;
        } else if (!strcmp(key, "tol")) {
            if (msg_double(err, n, opt, val, 1e-7, 0, 0.5, 0, &s->tol))
                return -1;
        } else if (!strcmp(key, "phong")) {
            char *save = NULL;
            for (char *tok = strtok_r(val, " ,", &save); tok; tok = strtok_r(NULL, " ,", &save)) {
                long e;
                if (s->nphong == sizeof s->phong / sizeof s->phong[0]) {
                    snprintf(err, n, "%s: at most 16 Phong exponents", opt);
                    return -1;
                }
                if (msg_long(err, n, opt, tok, 2, 10000, &e))
                    return -1;
                s->phong[s->nphong++] = (int)e;
            }
        } else {
            snprintf(err, n, "%s:%d: unknown key '%s': accepted are kappa_t, kappa_s, distance, g, phase, airlight, "
                     "diffuse, phong, tol, half, orders_max", path, line, key);
            return -1;
        }
    }
    return 0;
}

int scene_parse(const char *path, scene_t *s, char *err, size_t n)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, n, "scene: cannot open '%s': %s", path, strerror(errno));
        return -1;
    }
    memset(s, 0, sizeof *s);
    s->airlight = s->diffuse = 1;
    s->tol = 1e-3;
    s->orders_max = NBT_SCENE_GL_ORDERS;
    int rc = parse_lines(f, path, s, err, n);
    fclose(f);
    if (rc)
        return -1;
    if (!s->have_kt || !s->have_d)
        snprintf(err, n, "%s: kappa_t and distance are required", path);
    else if (s->have_g == !!s->phase[0])
        snprintf(err, n, "%s: give exactly one of g (a value or range: Legendre tables) and phase (fixed phase)", path);
    else if (s->have_ks && s->ks_hi > s->kt_hi)
        snprintf(err, n, "%s: kappa_s (%g) must not exceed kappa_t (%g)", path, s->ks_hi, s->kt_hi);
    else if (!s->airlight && !s->diffuse && s->nphong == 0)
        snprintf(err, n, "%s: the scene needs no tables (airlight = no, diffuse = no, no phong)", path);
    else
        return 0;
    return -1;
}
