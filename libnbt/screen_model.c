/* libnbt/screen_model.c: fitted models of the higher scattering orders of
 * screen kernels (nbt_screen_model, nbt/screen.h): a grid of normalised
 * shapes and log masses over (family parameter, albedo, optical depth), one
 * per geometry, its text form, and the model libnbt ships (fitted by
 * doc/screenmodel.sh, compiled in from libnbt/screen_model_hg.h). */
#include <config.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/screen.h>
#include "internal.h"
#include "screen_internal.h"

#define FP_N 33 /* a fixed phase's fingerprint: 4 pi p at mu = cos(k pi / 32) */

struct nbt_screen_model {
    int fixed;                 /* 0: the HG family over g; 1: one phase */
    char phase[128];           /* fixed: the phase's name when fitted */
    double fp[FP_N];
    size_t np, na, nt;
    double *param, *albedo, *tau;
    int have[2];
    double *logm;              /* [((geo * np + ip) * na + ia) * nt + it] */
    nbt_screen_shape *shape;   /* the same index, normalised to unit mass */
};

static size_t node(const nbt_screen_model *m, int geo, size_t ip, size_t ia, size_t it)
{
    return (((size_t)geo * m->np + ip) * m->na + ia) * m->nt + it;
}

void nbt_screen_model_free(nbt_screen_model *m)
{
    if (!m)
        return;
    free(m->param);
    free(m->albedo);
    free(m->tau);
    free(m->logm);
    free(m->shape);
    free(m);
}

static void fingerprint(const nbt_phase *p, double *fp)
{
    for (int k = 0; k < FP_N; k++)
        fp[k] = 4.0 * NBT_PI * nbt_phase_eval(p, cos(NBT_PI * k / (FP_N - 1)));
}

static int increasing(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]) || (i && !(v[i] > v[i - 1])))
            return 0;
    return 1;
}

/* NULL on a bad grid (*why = NBT_EDOM) or no memory (NBT_ENOMEM); reports nothing */
static nbt_screen_model *model_new(int fixed, size_t np, const double *param, size_t na, const double *albedo, size_t nt,
                                   const double *tau, nbt_status *why)
{
    if (fixed)
        np = 1;
    *why = NBT_EDOM;
    if (np < 1 || na < 1 || nt < 2 || (!fixed && !param) || !albedo || !tau || (!fixed && !increasing(param, np)) ||
        !increasing(albedo, na) || !increasing(tau, nt) || !(albedo[0] > 0) || !(albedo[na - 1] < 1) ||
        !(tau[0] > 0) || (!fixed && !(param[0] > -1 && param[np - 1] < 1)))
        return NULL;
    *why = NBT_ENOMEM;
    nbt_screen_model *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->fixed = fixed;
    m->np = np;
    m->na = na;
    m->nt = nt;
    m->param = malloc(np * sizeof *m->param);
    m->albedo = malloc(na * sizeof *m->albedo);
    m->tau = malloc(nt * sizeof *m->tau);
    size_t nn = 2 * np * na * nt;
    m->logm = malloc(nn * sizeof *m->logm);
    m->shape = calloc(nn, sizeof *m->shape);
    if (!m->param || !m->albedo || !m->tau || !m->logm || !m->shape) {
        nbt_screen_model_free(m);
        return NULL;
    }
    m->param[0] = 0;
    if (!fixed)
        memcpy(m->param, param, np * sizeof *param);
    memcpy(m->albedo, albedo, na * sizeof *albedo);
    memcpy(m->tau, tau, nt * sizeof *tau);
    for (size_t i = 0; i < nn; i++)
        m->logm[i] = -INFINITY;
    *why = NBT_OK;
    return m;
}

nbt_screen_model *nbt_screen_model_alloc(const nbt_phase *fixed, size_t np, const double *param, size_t na,
                                         const double *albedo, size_t nt, const double *tau)
{
    nbt_status why;
    nbt_screen_model *m = model_new(fixed != NULL, np, param, na, albedo, nt, tau, &why);
    if (!m) {
        nbt__fail(why, why == NBT_ENOMEM ? "screen model: out of memory"
                                         : "screen model: needs increasing grids: g in (-1, 1), albedo in (0, 1), "
                                           "tau > 0 (two or more)");
        return NULL;
    }
    if (fixed) {
        snprintf(m->phase, sizeof m->phase, "%s", nbt_phase_name(fixed));
        fingerprint(fixed, m->fp);
    }
    return m;
}

nbt_status nbt_screen_model_set(nbt_screen_model *m, nbt_screen_geometry geo, size_t ip, size_t ia, size_t it,
                                const nbt_screen_shape *s)
{
    if ((geo != NBT_SCREEN_INSIDE && geo != NBT_SCREEN_ENTERING) || ip >= m->np || ia >= m->na || it >= m->nt)
        NBT_FAIL(NBT_EINVAL, "screen model: node out of range");
    double t = 0;
    for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
        if (!(s->erfc[k] >= 0 && s->gauss[k] >= 0) || !isfinite(s->erfc[k] + s->gauss[k]))
            NBT_FAIL(NBT_EDOM, "screen model: shape masses must be finite and >= 0");
        t += s->erfc[k] + s->gauss[k];
    }
    size_t n = node(m, (int)geo, ip, ia, it);
    m->logm[n] = t > 0 ? log(t) : -INFINITY;
    for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
        m->shape[n].erfc[k] = t > 0 ? s->erfc[k] / t : 0;
        m->shape[n].gauss[k] = t > 0 ? s->gauss[k] / t : 0;
    }
    m->have[geo] = 1;
    return NBT_OK;
}

/* ---- text form ---- */

static const char *const GEO[2] = {"inside", "entering"};

nbt_status nbt_screen_model_write(const nbt_screen_model *m, const char *path, const char *comment, char *err,
                                  size_t errlen)
{
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) {
        int e = errno;
        return nbt__failf(err, errlen, nbt__io_status(e), "screen model '%s' cannot be written: %s", path, strerror(e));
    }
    fprintf(f, "# nbt screen kernel model: higher scattering orders (nbt/screen.h, doc/screenspace.md)\n");
    if (comment)
        for (const char *c = comment; *c;) {
            size_t n = strcspn(c, "\n");
            fprintf(f, "# %.*s\n", (int)n, c);
            c += n + (c[n] == '\n');
        }
    if (m->fixed) {
        fprintf(f, "family fixed %s\nfingerprint", m->phase);
        for (int k = 0; k < FP_N; k++)
            fprintf(f, " %.9g", m->fp[k]);
        fprintf(f, "\n");
    } else {
        fprintf(f, "family hg\nparam");
        for (size_t i = 0; i < m->np; i++)
            fprintf(f, " %.9g", m->param[i]);
        fprintf(f, "\n");
    }
    fprintf(f, "albedo");
    for (size_t i = 0; i < m->na; i++)
        fprintf(f, " %.9g", m->albedo[i]);
    fprintf(f, "\ntau");
    for (size_t i = 0; i < m->nt; i++)
        fprintf(f, " %.9g", m->tau[i]);
    fprintf(f, "\n# node GEOMETRY IPARAM IALBEDO ITAU LN_MASS then e|g<slot>:<weight> (weights sum to 1)\n");
    for (int g = 0; g < 2; g++) {
        if (!m->have[g])
            continue;
        for (size_t ip = 0; ip < m->np; ip++)
            for (size_t ia = 0; ia < m->na; ia++)
                for (size_t it = 0; it < m->nt; it++) {
                    size_t n = node(m, g, ip, ia, it);
                    if (isinf(m->logm[n]))
                        continue;
                    fprintf(f, "node %s %zu %zu %zu %.6g", GEO[g], ip, ia, it, m->logm[n]);
                    for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
                        /* 3 digits and no weight below 2e-4: the counts' own noise is larger */
                        if (m->shape[n].erfc[k] >= 2e-4)
                            fprintf(f, " e%d:%.3g", k + NBT_SCREEN_SLOT_LO, m->shape[n].erfc[k]);
                        if (m->shape[n].gauss[k] >= 2e-4)
                            fprintf(f, " g%d:%.3g", k + NBT_SCREEN_SLOT_LO, m->shape[n].gauss[k]);
                    }
                    fprintf(f, "\n");
                }
    }
    int bad = ferror(f);
    if (fclose(f) != 0 || bad || rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        return nbt__failf(err, errlen, nbt__io_status(e), "screen model '%s' cannot be written: %s", path, strerror(e));
    }
    return NBT_OK;
}

/* numbers after a keyword: all finite; *n gets their count */
static int read_list(const char *s, double *v, size_t max, size_t *n)
{
    *n = 0;
    for (;;) {
        s += strspn(s, " \t\r\n");
        if (!*s)
            return 1;
        char *end;
        double x = strtod(s, &end);
        if (end == s || !isfinite(x) || *n == max)
            return 0;
        v[(*n)++] = x;
        s = end;
    }
}

#define MAXGRID 64

/* the text form, from a string (a file read whole, or the compiled-in model) */
static nbt_status parse_model(const char *text, const char *name, nbt_screen_model **out, char *err, size_t errlen)
{
    *out = NULL;
    char line[8192], phase[128] = "";
    double param[MAXGRID], alb[MAXGRID], tau[MAXGRID], fp[FP_N];
    size_t np = 0, na = 0, nt = 0, nfp = 0;
    int fam = -1, ln = 0;
    nbt_screen_model *m = NULL;
    nbt_status st = NBT_OK;
    while (st == NBT_OK && *text) {
        size_t len = strcspn(text, "\n");
        ln++;
        if (len >= sizeof line) {
            st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: longer than %zu characters", name, ln,
                            sizeof line - 1);
            break;
        }
        memcpy(line, text, len);
        line[len] = '\0';
        text += len + (text[len] == '\n');
        char *p = line + strspn(line, " \t");
        if (*p == '#' || *p == '\n' || *p == '\r' || !*p)
            continue;
        if (!strncmp(p, "family ", 7)) {
            char a[16], b[128];
            int k = sscanf(p + 7, "%15s %127s", a, b);
            if (k == 1 && !strcmp(a, "hg"))
                fam = 0;
            else if (k == 2 && !strcmp(a, "fixed")) {
                fam = 1;
                snprintf(phase, sizeof phase, "%s", b);
            } else
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: expected 'family hg' or "
                                "'family fixed SPEC'", name, ln);
        } else if (!strncmp(p, "param ", 6)) {
            if (!read_list(p + 6, param, MAXGRID, &np))
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: bad 'param' list", name, ln);
        } else if (!strncmp(p, "fingerprint ", 12)) {
            if (!read_list(p + 12, fp, FP_N, &nfp) || nfp != FP_N)
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: 'fingerprint' needs %d numbers",
                                name, ln, FP_N);
        } else if (!strncmp(p, "albedo ", 7)) {
            if (!read_list(p + 7, alb, MAXGRID, &na))
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: bad 'albedo' list", name, ln);
        } else if (!strncmp(p, "tau ", 4)) {
            if (!read_list(p + 4, tau, MAXGRID, &nt))
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: bad 'tau' list", name, ln);
        } else if (!strncmp(p, "node ", 5)) {
            if (!m) {
                nbt_status why = NBT_EFORMAT;
                m = fam < 0 ? NULL : model_new(fam == 1, np, param, na, alb, nt, tau, &why);
                if (!m && why == NBT_ENOMEM) {
                    st = nbt__failf(err, errlen, NBT_ENOMEM, "out of memory");
                    break;
                }
                if (!m) {
                    st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: a node before a valid "
                                    "'family', grid ('param' for hg, 'albedo', 'tau': increasing, albedo in (0, 1), "
                                    "tau > 0, two or more depths) and fingerprint", name, ln);
                    break;
                }
                if (fam == 1) {
                    if (nfp != FP_N) {
                        st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s': a fixed phase needs its "
                                        "fingerprint before the nodes", name);
                        break;
                    }
                    snprintf(m->phase, sizeof m->phase, "%s", phase);
                    memcpy(m->fp, fp, sizeof fp);
                }
            }
            char geo[16];
            size_t ip, ia, it;
            double lm;
            int off = 0;
            if (sscanf(p + 5, "%15s %zu %zu %zu %lf%n", geo, &ip, &ia, &it, &lm, &off) != 5 ||
                (strcmp(geo, GEO[0]) && strcmp(geo, GEO[1])) || ip >= m->np || ia >= m->na || it >= m->nt ||
                !isfinite(lm)) {
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: expected 'node inside|entering "
                                "IPARAM IALBEDO ITAU LN_MASS' inside the grid", name, ln);
                break;
            }
            nbt_screen_shape sh;
            memset(&sh, 0, sizeof sh);
            char *q = p + 5 + off;
            for (;;) {
                q += strspn(q, " \t\r\n");
                if (!*q)
                    break;
                char kind = *q;
                char *end;
                long slot = strtol(q + 1, &end, 10);
                double w = NAN;
                if (*end == ':')
                    w = strtod(end + 1, &end);
                if ((kind != 'e' && kind != 'g') || slot < NBT_SCREEN_SLOT_LO || slot > NBT_SCREEN_SLOT_HI ||
                    !(w >= 0) || !isfinite(w) || (*end && !strchr(" \t\r\n", *end))) {
                    st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: expected e<slot>:<weight> or "
                                    "g<slot>:<weight>, slot in [%d, %d], weight >= 0", name, ln, NBT_SCREEN_SLOT_LO,
                                    NBT_SCREEN_SLOT_HI);
                    break;
                }
                (kind == 'e' ? sh.erfc : sh.gauss)[slot - NBT_SCREEN_SLOT_LO] += w;
                q = end;
            }
            if (st != NBT_OK)
                break;
            double t = 0;
            for (int k = 0; k < NBT_SCREEN_NSLOTS; k++)
                t += sh.erfc[k] + sh.gauss[k];
            if (!(t > 0)) {
                st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: a node without weights", name, ln);
                break;
            }
            int g = !strcmp(geo, GEO[1]);
            size_t n = node(m, g, ip, ia, it);
            m->logm[n] = lm;
            for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
                m->shape[n].erfc[k] = sh.erfc[k] / t;
                m->shape[n].gauss[k] = sh.gauss[k] / t;
            }
            m->have[g] = 1;
        } else
            st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s' line %d: unknown line (expected family, "
                            "param, fingerprint, albedo, tau or node)", name, ln);
    }
    if (st == NBT_OK && !m)
        st = nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s': no nodes", name);
    if (st != NBT_OK) {
        nbt_screen_model_free(m);
        return st;
    }
    *out = m;
    return NBT_OK;
}

nbt_status nbt_screen_model_read(const char *path, nbt_screen_model **out, char *err, size_t errlen)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) {
        int e = errno;
        return nbt__failf(err, errlen, nbt__io_status(e), "screen model '%s' cannot be opened: %s", path, strerror(e));
    }
    size_t cap = 1 << 16, n = 0;
    char *text = malloc(cap);
    while (text) {
        n += fread(text + n, 1, cap - 1 - n, f);
        if (n < cap - 1)
            break;
        char *t = cap < ((size_t)1 << 28) ? realloc(text, cap * 2) : NULL; /* a model is kilobytes; refuse 256 MB */
        if (!t) {
            free(text);
            text = NULL;
            break;
        }
        text = t;
        cap *= 2;
    }
    int bad = ferror(f);
    fclose(f);
    if (!text)
        return nbt__failf(err, errlen, NBT_ENOMEM, "screen model '%s': out of memory (or larger than 256 MB)", path);
    if (bad) {
        free(text);
        return nbt__failf(err, errlen, NBT_EIO, "screen model '%s' cannot be read", path);
    }
    text[n] = '\0';
    if (strlen(text) != n) {
        free(text);
        return nbt__failf(err, errlen, NBT_EFORMAT, "screen model '%s': not a text file (a NUL byte)", path);
    }
    nbt_status st = parse_model(text, path, out, err, errlen);
    free(text);
    return st;
}

/* ---- the shipped model ---- */

static const char nbt_screen_model_hg_text[] =
#include "screen_model_hg.h"
    ;
static nbt_screen_model *default_model;
static pthread_once_t default_once = PTHREAD_ONCE_INIT;

static void default_init(void)
{
    char err[256];
    if (parse_model(nbt_screen_model_hg_text, "(compiled in)", &default_model, err, sizeof err) != NBT_OK)
        default_model = NULL; /* a build whose model does not parse: test_screen_model fails on it */
}

const nbt_screen_model *nbt_screen_model_default(void)
{
    pthread_once(&default_once, default_init);
    return default_model;
}

/* ---- coverage and evaluation ---- */

static int phase_param(const nbt_screen_model *m, const nbt_phase *p, double *param)
{
    if (m->fixed) {
        double fp[FP_N];
        fingerprint(p, fp);
        for (int k = 0; k < FP_N; k++)
            if (!(fabs(fp[k] - m->fp[k]) <= 1e-6 * fabs(m->fp[k]) + 1e-9))
                return 0;
        *param = 0;
        return 1;
    }
    if (nbt_phase_get_kind(p) != NBT_PHASE_HG)
        return 0;
    double g = nbt_phase_mean_cosine(p);
    *param = g;
    return g >= m->param[0] - 1e-12 && g <= m->param[m->np - 1] + 1e-12;
}

nbt_status nbt_screen_model_covers(const nbt_screen_model *m, const nbt_phase *p, nbt_screen_geometry geo, char *err,
                                   size_t errlen)
{
    double param;
    if (!m || !p)
        return nbt__failf(err, errlen, NBT_EINVAL, "screen model: no model or no phase");
    if (!phase_param(m, p, &param)) {
        if (m->fixed)
            return nbt__failf(err, errlen, NBT_EDOM, "the kernel model was fitted for the phase %s, not %s "
                              "(refit it for yours with nbt-fit screenmodel)", m->phase, nbt_phase_name(p));
        return nbt__failf(err, errlen, NBT_EDOM, "the kernel model covers HG phases with g in [%g, %g], not %s "
                          "(refit it for yours with nbt-fit screenmodel, or use the first order alone)", m->param[0],
                          m->param[m->np - 1], nbt_phase_name(p));
    }
    if ((geo != NBT_SCREEN_INSIDE && geo != NBT_SCREEN_ENTERING) || !m->have[geo])
        return nbt__failf(err, errlen, NBT_EDOM, "the kernel model holds no fit for the geometry '%s'",
                          (unsigned)geo < 2 ? GEO[geo] : "?");
    return NBT_OK;
}

nbt_status nbt__screen_model_param(const nbt_screen_model *m, const nbt_phase *p, nbt_screen_geometry geo,
                                   double *param)
{
    char err[256];
    nbt_status st = nbt_screen_model_covers(m, p, geo, err, sizeof err);
    if (st != NBT_OK)
        NBT_FAIL(st, err);
    phase_param(m, p, param);
    return NBT_OK;
}

/* cell and weight of x on a grid in the coordinate f(v); clamped: *out says which side it left */
static void grid_pos(const double *v, size_t n, double x, double (*f)(double), size_t *i0, double *w, int *out)
{
    *out = 0;
    if (n == 1) {
        *i0 = 0;
        *w = 0;
        return;
    }
    if (x <= v[0]) {
        *out = x < v[0] ? -1 : 0;
        *i0 = 0;
        *w = 0;
        return;
    }
    if (x >= v[n - 1]) {
        *out = x > v[n - 1] ? 1 : 0;
        *i0 = n - 2;
        *w = 1;
        return;
    }
    size_t i = 0;
    while (i + 2 < n && x >= v[i + 1])
        i++;
    *i0 = i;
    *w = (f(x) - f(v[i])) / (f(v[i + 1]) - f(v[i]));
}

static double f_one_minus(double x)
{
    return -log1p(-x);
}

/* Lagrange weights on up to 4 nodes around interval [i0, i0+1] of an axis (in f's coordinate): cubic
 * inside, quadratic next to an end, linear on two nodes; the clamped position (w in [0, 1]) beyond the ends. */
static size_t cubic_pos(const double *v, size_t n, size_t i0, double w, double (*f)(double), size_t *idx, double *lw)
{
    if (n < 3) {
        idx[0] = i0, idx[1] = i0 + (n > 1);
        lw[0] = 1 - w, lw[1] = n > 1 ? w : 0;
        return 2;
    }
    size_t lo = i0 > 0 ? i0 - 1 : 0, hi = i0 + 2 < n ? i0 + 2 : n - 1, k = hi - lo + 1;
    double x = f(v[i0]) + w * (f(v[i0 + 1]) - f(v[i0]));
    for (size_t a = 0; a < k; a++) {
        double l = 1, xa = f(v[lo + a]);
        for (size_t b = 0; b < k; b++)
            if (b != a)
                l *= (x - f(v[lo + b])) / (xa - f(v[lo + b]));
        idx[a] = lo + a;
        lw[a] = l;
    }
    return k;
}

nbt_status nbt__screen_model_eval(const nbt_screen_model *m, double param, nbt_screen_geometry geo, double albedo,
                                  double tau, nbt_screen_shape *out)
{
    memset(out, 0, sizeof *out);
    if (!(tau > 0) || !(albedo > 0))
        return NBT_OK;
    size_t ip, ia, it;
    double wp, wa, wt;
    int op, oa, ot;
    grid_pos(m->param, m->np, param, f_one_minus, &ip, &wp, &op);
    grid_pos(m->albedo, m->na, albedo, f_one_minus, &ia, &wa, &oa);
    grid_pos(m->tau, m->nt, tau, log, &it, &wt, &ot);
    double lm = 0;
    for (int c = 0; c < 8; c++) { /* a single-point axis has weight 0 on its second corner */
        int dp = c & 1, da = (c >> 1) & 1, dt = (c >> 2) & 1;
        double w = (dp ? wp : 1 - wp) * (da ? wa : 1 - wa) * (dt ? wt : 1 - wt);
        if (w == 0)
            continue;
        size_t n = node(m, (int)geo, ip + (size_t)dp, ia + (size_t)da, it + (size_t)dt);
        if (isinf(m->logm[n])) { /* no light counted at a corner: none here either */
            memset(out, 0, sizeof *out);
            return NBT_OK;
        }
        lm += w * m->logm[n]; /* (replaced below by the cubic one when every node has light) */
        for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
            out->erfc[k] += w * m->shape[n].erfc[k];
            out->gauss[k] += w * m->shape[n].gauss[k];
        }
    }
    /* the log mass is cubic in -ln(1 - albedo) and ln(tau) (it bends: linear was 2-7% low between depth nodes) */
    {
        size_t ja[4], jt[4];
        double la[4], lt[4], lc = 0;
        size_t ka = cubic_pos(m->albedo, m->na, ia, wa, f_one_minus, ja, la);
        size_t kt = cubic_pos(m->tau, m->nt, it, wt, log, jt, lt);
        int ok = 1;
        for (int dp = 0; dp < 2 && ok; dp++) {
            double w = dp ? wp : 1 - wp;
            if (w == 0)
                continue;
            for (size_t a = 0; a < ka && ok; a++)
                for (size_t t = 0; t < kt; t++) {
                    double l = m->logm[node(m, (int)geo, ip + (size_t)dp, ja[a], jt[t])];
                    if (isinf(l)) {
                        ok = 0;
                        break;
                    }
                    lc += w * la[a] * lt[t] * l;
                }
        }
        if (ok) { /* the shapes too, clipped at 0 and renormalised */
            lm = lc;
            nbt_screen_shape sh;
            memset(&sh, 0, sizeof sh);
            for (int dp = 0; dp < 2; dp++) {
                double w = dp ? wp : 1 - wp;
                for (size_t a = 0; a < ka && w != 0; a++)
                    for (size_t t = 0; t < kt; t++) {
                        const nbt_screen_shape *ns = &m->shape[node(m, (int)geo, ip + (size_t)dp, ja[a], jt[t])];
                        double c = w * la[a] * lt[t];
                        for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
                            sh.erfc[k] += c * ns->erfc[k];
                            sh.gauss[k] += c * ns->gauss[k];
                        }
                    }
            }
            double tot = 0;
            for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
                sh.erfc[k] = fmax(sh.erfc[k], 0.0);
                sh.gauss[k] = fmax(sh.gauss[k], 0.0);
                tot += sh.erfc[k] + sh.gauss[k];
            }
            for (int k = 0; k < NBT_SCREEN_NSLOTS && tot > 0; k++) {
                out->erfc[k] = sh.erfc[k] / tot;
                out->gauss[k] = sh.gauss[k] / tot;
            }
        }
    }
    /* beyond the grid: the second order dominates at small albedo and depth (mass ~ a^2, tau^2);
     * deep, the mass falls on exponentially as between the last two depths */
    if (oa < 0)
        lm += 2.0 * log(albedo / m->albedo[0]);
    if (ot < 0)
        lm += 2.0 * log(tau / m->tau[0]);
    else if (ot > 0) {
        double slope = 0;
        size_t a = it, b = it + 1;
        for (int c = 0; c < 4; c++) { /* the slope in tau of the interpolated log mass between the last two depths */
            int dp = c & 1, da = (c >> 1) & 1;
            double w = (dp ? wp : 1 - wp) * (da ? wa : 1 - wa);
            if (w == 0)
                continue;
            double la = m->logm[node(m, (int)geo, ip + (size_t)dp, ia + (size_t)da, a)];
            double lb = m->logm[node(m, (int)geo, ip + (size_t)dp, ia + (size_t)da, b)];
            slope += w * (lb - la) / (m->tau[b] - m->tau[a]);
        }
        lm += fmin(slope, 0.0) * (tau - m->tau[m->nt - 1]);
    }
    double M = exp(lm);
    for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
        out->erfc[k] *= M;
        out->gauss[k] *= M;
    }
    return NBT_OK;
}

nbt_status nbt_screen_model_eval(const nbt_screen_model *m, const nbt_phase *p, nbt_screen_geometry geo, double albedo,
                                 double tau, nbt_screen_shape *out, int *extrapolated)
{
    double param;
    if (!(tau > 0) || !isfinite(tau) || !(albedo >= 0 && albedo <= 1))
        NBT_FAIL(NBT_EDOM, "screen model: needs tau > 0 (finite) and albedo in [0, 1]");
    nbt_status st = nbt__screen_model_param(m, p, geo, &param);
    if (st != NBT_OK)
        return st;
    if (extrapolated)
        *extrapolated = albedo < m->albedo[0] || albedo > m->albedo[m->na - 1] || tau < m->tau[0] ||
                        tau > m->tau[m->nt - 1];
    return nbt__screen_model_eval(m, param, geo, albedo, tau, out);
}
