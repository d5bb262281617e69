/* libnbt/screen.c: screen-space scattering kernels, pixel integration, the
 * brute-force references and metrics (nbt/screen.h; doc/screenspace.md). */
#include <config.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/phase.h>
#include <nbt/screen.h>
#include "internal.h"
#include "screen_internal.h"

struct nbt_screen_kernel {
    nbt_skernel_kind kind;
    nbt_screen_kernel_fn fn; /* custom, or NULL */
    void *ctx;
    nbt_beam_medium m;
    nbt_kernel_correction corr;
    double g;                 /* ELEK: mean cosine of the lobes */
    nbt__phase_kern *pk;      /* FITTED, FIRST: the family for a phase */
    nbt_screen_kernel *ch[3]; /* an RGB kernel: one per channel (owned); else NULL */
};

static const char *const KNAMES[] = {"moment", "smallangle", "corrected", "single", "lineint", "elek", "fitted", "first"};

const char *nbt_skernel_name(nbt_skernel_kind kind)
{
    return (unsigned)kind < sizeof KNAMES / sizeof KNAMES[0] ? KNAMES[kind] : "?";
}

nbt_status nbt_skernel_parse(const char *name, nbt_skernel_kind *kind)
{
    for (unsigned i = 0; i < sizeof KNAMES / sizeof KNAMES[0]; i++)
        if (!strcmp(name, KNAMES[i])) {
            *kind = (nbt_skernel_kind)i;
            return NBT_OK;
        }
    return NBT_EINVAL;
}

static nbt_screen_kernel *kernel_new(void)
{
    nbt_screen_kernel *k = calloc(1, sizeof *k);
    if (!k)
        nbt__fail(NBT_ENOMEM, "screen: out of memory");
    return k;
}

nbt_screen_kernel *nbt_screen_kernel_alloc(nbt_skernel_kind kind, const nbt_beam_medium *medium,
                                           const nbt_kernel_correction *corr)
{
    if (nbt_beam_check(medium) != NBT_OK)
        return NULL;
    if (medium->nlayers > 0 || medium->rho_fn) {
        nbt__fail(NBT_EINVAL, "screen: kernels over depth need a homogeneous medium");
        return NULL;
    }
    if ((unsigned)kind > NBT_SKERNEL_ELEK || (kind == NBT_SKERNEL_CORRECTED && !corr)) {
        nbt__fail(NBT_EINVAL, "screen: unknown kernel, or CORRECTED without a correction (FITTED and FIRST: "
                              "nbt_screen_kernel_phase)");
        return NULL;
    }
    nbt_screen_kernel *k = kernel_new();
    if (!k)
        return NULL;
    k->kind = kind;
    k->m = *medium;
    if (corr)
        k->corr = *corr;
    if (kind == NBT_SKERNEL_ELEK) {
        /* W's g is the true mean cosine of the sphere-mapped lobes, not 1 - 2B */
        double b[2] = {0, 0};
        nbt_phase *p = nbt_phase_sog(medium->nlobes, medium->w, medium->B);
        if (!p || nbt_phase_moments(p, 1, b) != NBT_OK) {
            nbt_phase_free(p);
            free(k);
            nbt__fail(NBT_ENOMEM, "screen: the lobes' mean cosine could not be computed");
            return NULL;
        }
        nbt_phase_free(p);
        k->g = b[1];
    }
    return k;
}

nbt_screen_kernel *nbt_screen_kernel_custom(nbt_screen_kernel_fn fn, void *ctx)
{
    if (!fn) {
        nbt__fail(NBT_EINVAL, "screen: custom kernel without a function");
        return NULL;
    }
    nbt_screen_kernel *k = kernel_new();
    if (!k)
        return NULL;
    k->fn = fn;
    k->ctx = ctx;
    return k;
}

nbt_screen_kernel *nbt_screen_kernel_phase(nbt_skernel_kind kind, double sigma_t, double albedo, const nbt_phase *p,
                                           nbt_screen_geometry geo, const nbt_screen_model *model)
{
    if (kind != NBT_SKERNEL_FITTED && kind != NBT_SKERNEL_FIRST && kind != NBT_SKERNEL_ELEK) {
        nbt__fail(NBT_EINVAL, "screen: a kernel for a phase is FITTED, FIRST or ELEK");
        return NULL;
    }
    if (kind != NBT_SKERNEL_FIRST && !model && !(model = nbt_screen_model_default())) {
        nbt__fail(NBT_EINVAL, "screen: the compiled-in kernel model could not be read");
        return NULL;
    }
    nbt__phase_kern *pk = nbt__phase_kern_alloc(p, sigma_t, albedo, geo, kind != NBT_SKERNEL_FIRST ? model : NULL);
    if (!pk)
        return NULL;
    nbt_screen_kernel *k = kernel_new();
    if (!k) {
        nbt__phase_kern_free(pk);
        return NULL;
    }
    k->kind = kind;
    k->pk = pk;
    k->m.sigma_t = sigma_t; /* ELEK's width */
    k->m.albedo = albedo;
    k->g = nbt_phase_mean_cosine(p);
    return k;
}

nbt_screen_kernel *nbt_screen_kernel_rgb(nbt_screen_kernel *r, nbt_screen_kernel *g, nbt_screen_kernel *b)
{
    int args_ok = r && g && b && !r->ch[0] && !g->ch[0] && !b->ch[0];
    nbt_screen_kernel *k = args_ok ? kernel_new() : NULL;
    if (!k) {
        if (args_ok) /* kernel_new ran out of memory */
            nbt__fail(NBT_ENOMEM, "screen: out of memory");
        else if (r && g && b)
            nbt__fail(NBT_EINVAL, "screen: an RGB kernel takes three single-channel kernels");
        else
            nbt__fail(NBT_EINVAL, "screen: an RGB kernel needs three kernels");
        nbt_screen_kernel_free(r);
        nbt_screen_kernel_free(g);
        nbt_screen_kernel_free(b);
        return NULL;
    }
    k->kind = r->kind;
    k->ch[0] = r;
    k->ch[1] = g;
    k->ch[2] = b;
    return k;
}

unsigned nbt_screen_kernel_channels(const nbt_screen_kernel *k)
{
    return k && k->ch[0] ? 3u : 1u;
}

void nbt_screen_kernel_free(nbt_screen_kernel *k)
{
    if (!k)
        return;
    for (int c = 0; c < 3; c++)
        nbt_screen_kernel_free(k->ch[c]);
    nbt__phase_kern_free(k->pk);
    free(k);
}

void nbt__add_atom(nbt_screen_kern *o, nbt_atom_shape s, double mass, double scale)
{
    if (o->n < NBT_SCREEN_MAX_ATOMS && mass > 0 && scale > 0 && isfinite(mass) && isfinite(scale)) {
        o->shape[o->n] = s;
        o->mass[o->n] = mass;
        o->scale[o->n] = scale;
        o->n++;
    }
}

/* The eq. 16 line integral over the beam's depth y at Gauss-Legendre nodes:
 * Psi = ss e^{-sa z} int_0^z e^{-ss y} sum_i w_i N(r; sqrt2 W_i(y)) dy. */
static void lineint_atoms(const nbt_beam_medium *m, double z, nbt_screen_kern *o)
{
    size_t ny = NBT_SCREEN_MAX_ATOMS / m->nlobes;
    double x[NBT_SCREEN_MAX_ATOMS], w[NBT_SCREEN_MAX_ATOMS];
    nbt__gl_nodes(ny, x, w);
    double ss = m->albedo * m->sigma_t, sa = m->sigma_t - ss, bm = 0;
    for (size_t l = 0; l < m->nlobes; l++)
        bm += m->w[l] * m->B[l];
    for (size_t j = 0; j < ny; j++) {
        double y = 0.5 * z * (1.0 + x[j]), wy = 0.5 * z * w[j], Ah = ss * bm * (z - y);
        for (size_t i = 0; i < m->nlobes; i++) {
            double B = m->B[i], S = B + Ah, C2 = B * y * y * (1.0 - B / S), d = z - B * y / S;
            nbt__add_atom(o, NBT_ATOM_GAUSS, ss * exp(-sa * z) * wy * exp(-ss * y) * m->w[i], sqrt(2.0 * (C2 + d * d * S)));
        }
    }
}

nbt_status nbt_screen_kernel_eval(const nbt_screen_kernel *k, double D, nbt_screen_kern *o)
{
    return nbt_screen_kernel_eval_ch(k, 0, D, o);
}

nbt_status nbt_screen_kernel_eval_ch(const nbt_screen_kernel *k, unsigned ch, double D, nbt_screen_kern *o)
{
    if (ch > 2)
        NBT_FAIL(NBT_EINVAL, "screen: channel must be 0, 1 or 2");
    if (k->ch[0])
        k = k->ch[ch];
    o->n = 0;
    o->T = 1;
    if (!(D >= 0))
        NBT_FAIL(NBT_EDOM, "screen: depth must be >= 0");
    if (D >= NBT_SCREEN_SKY) { /* behind infinite medium: nothing direct, mass over infinite area */
        o->T = 0;
        return NBT_OK;
    }
    if (D == 0)
        return NBT_OK;
    if (k->fn)
        return k->fn(D, o, k->ctx);
    const nbt_beam_medium *m = &k->m;
    double ss = m->albedo * m->sigma_t, M0, M2, alpha, beta;
    if (k->pk && k->kind != NBT_SKERNEL_ELEK)
        return nbt__phase_kern_eval(k->pk, D, o);
    nbt_status st = NBT_OK;
    o->T = exp(-m->sigma_t * D);
    switch (k->kind) {
    case NBT_SKERNEL_MOMENT:
    case NBT_SKERNEL_SMALLANGLE:
        st = nbt_beam_moments(m, k->kind == NBT_SKERNEL_MOMENT ? NBT_BEAM_ISHIMARU : NBT_BEAM_SMALLANGLE, D, &M0,
                              &M2, NULL);
        nbt_beam_kernel_params(M0, M2, &alpha, &beta);
        nbt__add_atom(o, NBT_ATOM_ERFC, M0, beta);
        break;
    case NBT_SKERNEL_CORRECTED:
        st = nbt_kernel_corrected(&k->corr, m, D, &alpha, &beta);
        nbt__add_atom(o, NBT_ATOM_ERFC, sqrt(2.0 * NBT_PI) * alpha * beta, beta);
        break;
    case NBT_SKERNEL_SINGLE: /* per lobe alpha = w ss e^{-tau}/(2 sqrt(pi B)), beta = D sqrt(2B): mass w ss D e^{-tau} */
        for (size_t i = 0; i < m->nlobes; i++)
            nbt__add_atom(o, NBT_ATOM_ERFC, m->w[i] * ss * D * o->T, D * sqrt(2.0 * m->B[i]));
        break;
    case NBT_SKERNEL_LINEINT:
        lineint_atoms(m, D, o);
        break;
    case NBT_SKERNEL_FITTED:
    case NBT_SKERNEL_FIRST:
        break; /* built by nbt_screen_kernel_phase: k->pk */
    case NBT_SKERNEL_ELEK: {
        if (k->pk) { /* for a phase: the fitted kernel's whole mass */
            st = nbt__phase_kern_eval(k->pk, D, o);
            M0 = 0;
            for (size_t a = 0; a < o->n; a++)
                M0 += o->mass[a];
            o->n = 0;
        } else
            st = nbt_beam_moments(m, NBT_BEAM_ISHIMARU, D, &M0, &M2, NULL);
        double sa = m->sigma_t - ss;
        double inv = 2.0 * sa / (3.0 * D) + (ss > 0 ? 4.0 / (D * D * D * ss * (1.0 - k->g)) : INFINITY);
        nbt__add_atom(o, NBT_ATOM_GAUSS, M0, sqrt(0.5 / inv));
        break;
    }
    }
    return st;
}

/* ---- pixel integration ---- */

void nbt__gl_nodes(size_t n, double *x, double *w)
{
    /* Newton on P_n from Chebyshev guesses */
    for (size_t i = 0; i < (n + 1) / 2; i++) {
        double z = cos(NBT_PI * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; it++) {
            double p0 = 1, p1 = z;
            for (size_t j = 2; j <= n; j++) {
                double p2 = ((2.0 * j - 1) * z * p1 - (j - 1.0) * p0) / j;
                p0 = p1;
                p1 = p2;
            }
            dp = n * (z * p1 - p0) / (z * z - 1);
            double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        double p0 = 1, p1 = z;
        for (size_t j = 2; j <= n; j++) {
            double p2 = ((2.0 * j - 1) * z * p1 - (j - 1.0) * p0) / j;
            p0 = p1;
            p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = w[n - 1 - i] = 2.0 / ((1 - z * z) * dp * dp);
    }
}

/* integral of a unit 1-D Gaussian of deviation s over [d - 1/2, d + 1/2] */
double nbt__gauss_cell(double s, long d)
{
    double a = fabs((double)d);
    if (!(s > 0))
        return d == 0 ? 1.0 : 0.0;
    double k = 1.0 / (sqrt(2.0) * s);
    if (a == 0)
        return erf(0.5 * k);
    /* both ends positive: difference of erfc, no cancellation */
    return 0.5 * (erfc((a - 0.5) * k) - erfc((a + 0.5) * k));
}

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

size_t nbt__kern_nodes(const nbt_screen_kern *kn, double px, double *sig, double *wt, size_t max)
{
    double gx[SCREEN_GL], gw[SCREEN_GL];
    nbt__gl_nodes(SCREEN_GL, gx, gw);
    size_t n = 0, ne = 0;
    /* the ERFC atoms together are a mixture of Gaussians whose density over the
     * deviation is a staircase, sum of mass/s over the atoms with s above it:
     * integrated on panels between the atoms' scales and the octaves from 1/8 px */
    double br[NBT_SCREEN_MAX_ATOMS + 64], smax = 0;
    for (size_t a = 0; a < kn->n; a++) {
        double s = kn->scale[a] / px;
        if (kn->shape[a] == NBT_ATOM_GAUSS || !(s > 0)) {
            if (n < max) {
                sig[n] = s > 0 ? s : 0;
                wt[n++] = kn->mass[a];
            }
        } else {
            br[ne++] = s;
            smax = fmax(smax, s);
        }
    }
    if (ne == 0)
        return n;
    for (double o = 0.125; o < smax && ne < sizeof br / sizeof br[0]; o *= 2)
        br[ne++] = o;
    qsort(br, ne, sizeof *br, cmp_dbl);
    double lo = 0;
    for (size_t b = 0; b < ne; b++) {
        double hi = br[b];
        if (!(hi > lo * (1 + 1e-12)))
            continue;
        double dens = 0; /* constant on (lo, hi]: the atoms that reach past it */
        for (size_t a = 0; a < kn->n; a++)
            if (kn->shape[a] == NBT_ATOM_ERFC && kn->scale[a] / px >= hi * (1 - 1e-12))
                dens += kn->mass[a] / (kn->scale[a] / px);
        /* an octave takes SCREEN_GL nodes, a shorter panel proportionally fewer plus two (at least 6) */
        int ng = SCREEN_GL;
        double gxp[SCREEN_GL], gwp[SCREEN_GL];
        const double *x = gx, *w = gw;
        if (lo > 0 && log2(hi / lo) < 0.8) {
            ng = (int)ceil(SCREEN_GL * log2(hi / lo)) + 2;
            ng = ng < 6 ? 6 : ng > SCREEN_GL ? SCREEN_GL : ng;
            nbt__gl_nodes((size_t)ng, gxp, gwp);
            x = gxp;
            w = gwp;
        }
        for (int j = 0; j < ng && n < max; j++) {
            sig[n] = lo + 0.5 * (hi - lo) * (1.0 + x[j]);
            wt[n++] = dens * 0.5 * (hi - lo) * w[j];
        }
        lo = hi;
    }
    return n;
}

double nbt_screen_atom_pixel(nbt_atom_shape shape, double scale_px, long dx, long dy)
{
    nbt_screen_kern kn = {.T = 1, .n = 1, .shape = {shape}, .mass = {1}, .scale = {scale_px}};
    double sig[SCREEN_MAX_NODES], wt[SCREEN_MAX_NODES], s = 0;
    size_t n = nbt__kern_nodes(&kn, 1.0, sig, wt, SCREEN_MAX_NODES);
    for (size_t i = 0; i < n; i++)
        s += wt[i] * nbt__gauss_cell(sig[i], dx) * nbt__gauss_cell(sig[i], dy);
    return s;
}

long nbt_screen_atom_radius(nbt_atom_shape shape, double scale_px, double tail)
{
    if (!(scale_px > 0) || !(tail > 0 && tail < 1))
        return 0;
    double lo = 0, hi = 1;
    while (nbt__atom_tail(shape, hi) > tail && hi < 100)
        hi *= 2;
    for (int i = 0; i < 60; i++) {
        double mid = 0.5 * (lo + hi);
        if (nbt__atom_tail(shape, mid) > tail)
            lo = mid;
        else
            hi = mid;
    }
    double r = ceil(hi * scale_px - 0.5);
    return r > 0 ? (r < 1e7 ? (long)r : 10000000L) : 0;
}

/* ---- per-pixel kernels ---- */

/* Pixel i's kernel as atoms, and the world length px of one pixel at its depth
 * (per-pixel kernels are in pixels already: px = 1). */
static nbt_status input_atoms(const nbt_screen_kernel *k, unsigned ch, const nbt_screen_input *in, size_t i,
                              nbt_screen_kern *kn, double *px)
{
    if (!in->pix) {
        *px = in->D[i] * in->dtheta;
        return nbt_screen_kernel_eval_ch(k, ch, in->D[i], kn);
    }
    kn->T = in->pix[i].T;
    kn->n = 0;
    nbt__add_atom(kn, NBT_ATOM_ERFC, in->pix[i].M0, in->pix[i].beta_px);
    *px = 1.0;
    return NBT_OK;
}

/* the truncation, mass, widest scale and Gaussian nodes of an evaluated kernel */
static void pkern_from_atoms(const nbt_screen_kern *kn, double px, double tail, long clip, nbt__pkern *pk)
{
    pk->T = kn->T;
    pk->n = 0;
    pk->R = 0;
    pk->mass = 0;
    pk->radius = 0;
    if (kn->n == 0)
        return;
    for (size_t a = 0; a < kn->n; a++) {
        long r = nbt_screen_atom_radius(kn->shape[a], kn->scale[a] / px, tail);
        if (r > pk->R)
            pk->R = r;
        pk->mass += kn->mass[a];
        if (kn->scale[a] / px > pk->radius)
            pk->radius = kn->scale[a] / px;
    }
    if (pk->R > clip)
        pk->R = clip;
    pk->n = nbt__kern_nodes(kn, px, pk->sig, pk->wt, SCREEN_MAX_NODES);
}

nbt_status nbt__pixel_kernel(const nbt_screen_kernel *k, unsigned ch, double D, double dtheta, double tail, long clip,
                             nbt__pkern *pk)
{
    nbt_screen_kern kn;
    nbt_status st = nbt_screen_kernel_eval_ch(k, ch, D, &kn);
    if (st != NBT_OK)
        kn.n = 0;
    pkern_from_atoms(&kn, D * dtheta, tail, clip, pk);
    return st;
}

nbt_status nbt__input_kernel(const nbt_screen_kernel *k, unsigned ch, const nbt_screen_input *in, size_t i, double tail,
                             nbt__pkern *pk)
{
    nbt_screen_kern kn;
    double px;
    nbt_status st = input_atoms(k, ch, in, i, &kn, &px);
    if (st != NBT_OK)
        kn.n = 0;
    pkern_from_atoms(&kn, px, tail, nbt__clip(in), pk);
    return st;
}

/* Beyond this many pixels from the centre, the weights of a wide kernel come
 * from its radial profile: the average of f over a unit square is
 * f + (f_xx + f_yy)/24 + O(f^(4)/1920), and only nodes wider than
 * SCREEN_FAR_RN/8 px reach that far (a narrower one is below e^-32 of its
 * peak there); for those the dropped term is below ~1e-5 of the value.
 * The profile is tabulated every 1/8 px and read by cubic interpolation. */
#define SCREEN_FAR_RN 24
#define SCREEN_FAR_H 0.125

/* the separable sum of the nodes over offsets 0..box-1 per axis, into the quadrant w (row stride R1) */
static void separable(const nbt__pkern *pk, double *w, double *c, size_t R1, size_t box)
{
    for (size_t n = 0; n < pk->n; n++) {
        double *e = c;
        /* a node's support ends where its cells fall below 1e-16 of its centre */
        size_t last = 0;
        e[0] = nbt__gauss_cell(pk->sig[n], 0);
        for (size_t i = 1; i < box; i++) {
            e[i] = nbt__gauss_cell(pk->sig[n], (long)i);
            if (!(e[i] > 1e-16 * e[0]))
                break;
            last = i;
        }
        for (size_t j = 0; j <= last; j++) { /* upper triangle i >= j; symmetric */
            double f = pk->wt[n] * e[j];
            double *row = w + j * R1;
            for (size_t i = j; i <= last; i++)
                row[i] += f * e[i];
        }
    }
}

/* Quadrant weights wq[j*(R+1) + i] for offsets (i, j) >= 0. */
nbt_status nbt__pixel_weights(const nbt__pkern *pk, double **wq, double **cell, size_t *cap)
{
    size_t R1 = (size_t)pk->R + 1, need = R1 * R1;
    int far = pk->R > SCREEN_FAR_RN;
    /* cell holds one node's cells (R1), or the far profile (nt) */
    size_t nt = far ? (size_t)ceil((sqrt(2.0) * (double)R1 + 4.0) / SCREEN_FAR_H) : 0;
    if (need > *cap) {
        double *a = realloc(*wq, need * sizeof **wq), *b;
        if (!a)
            NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
        *wq = a;
        b = realloc(*cell, (need > nt ? need : nt) * sizeof **cell);
        if (!b)
            NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
        *cell = b;
        *cap = need;
    }
    if (nt > *cap) { /* the far profile outgrows a small quadrant */
        double *b = realloc(*cell, nt * sizeof **cell);
        if (!b)
            NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
        *cell = b;
    }
    double *w = *wq, *c = *cell;
    memset(w, 0, need * sizeof *w);
    size_t box = far ? SCREEN_FAR_RN + 1 : R1;
    separable(pk, w, c, R1, box);
    for (size_t j = 1; j < box; j++)
        for (size_t i = 0; i < j; i++)
            w[j * R1 + i] = w[i * R1 + j];
    if (!far)
        return NBT_OK;
    /* the radial profile f + lap f / 24 of the wide nodes at r = k h */
    for (size_t k = 0; k < nt; k++)
        c[k] = 0;
    for (size_t n = 0; n < pk->n; n++) {
        double sg = pk->sig[n];
        if (!(sg > SCREEN_FAR_RN / 8.0))
            continue;
        double a = pk->wt[n] / (2.0 * NBT_PI * sg * sg), is2 = 1.0 / (sg * sg);
        for (size_t k = 0; k < nt; k++) {
            double r2 = (double)k * SCREEN_FAR_H * (double)k * SCREEN_FAR_H, g = a * exp(-0.5 * r2 * is2);
            if (g == 0)
                break;
            c[k] += g * (1.0 + (r2 * is2 - 2.0) * is2 / 24.0);
        }
    }
    for (size_t j = 0; j < R1; j++)
        for (size_t i = j < box ? box : j; i < R1; i++) {
            double r = sqrt((double)(i * i + j * j)) / SCREEN_FAR_H, t;
            size_t k = (size_t)r;
            if (k < 1)
                k = 1;
            if (k + 2 >= nt)
                k = nt - 3;
            t = r - (double)k;
            /* Catmull-Rom through k-1 .. k+2 */
            double f0 = c[k - 1], f1 = c[k], f2 = c[k + 1], f3 = c[k + 2];
            double v = f1 + 0.5 * t * (f2 - f0 + t * (2.0 * f0 - 5.0 * f1 + 4.0 * f2 - f3 + t * (3.0 * (f1 - f2) + f3 - f0)));
            w[j * R1 + i] = v;
            w[i * R1 + j] = v;
        }
    return NBT_OK;
}

/* ---- input checks and depth ---- */

nbt_status nbt_screen_check(const nbt_screen_input *in)
{
    if (in->w == 0 || in->h == 0 || !in->rgb || !in->D)
        return nbt__failv(NBT_EINVAL, "screen: an empty image is not accepted (%zux%zu%s%s)", in->w, in->h,
                          in->rgb ? "" : ", no colours", in->D ? "" : ", no depths");
    if (!(in->dtheta > 0) || !isfinite(in->dtheta))
        return nbt__failv(NBT_EDOM, "screen: dtheta = %g is not accepted: finite and > 0", in->dtheta);
    for (size_t i = 0; i < in->w * in->h; i++) {
        size_t x = i % in->w, y = i / in->w;
        if (!(in->D[i] >= 0))
            return nbt__failv(NBT_EDOM, "screen: pixel (%zu, %zu): depth %g is not accepted: >= 0 (sky: infinite)", x,
                              y, (double)in->D[i]);
        if (in->pix && !(in->pix[i].T >= 0 && in->pix[i].T <= 1 && in->pix[i].M0 >= 0 && isfinite(in->pix[i].M0) &&
                         in->pix[i].beta_px >= 0 && isfinite(in->pix[i].beta_px)))
            return nbt__failv(NBT_EDOM, "screen: pixel (%zu, %zu): the kernel T = %g, M0 = %g, beta = %g px is not "
                              "accepted: T in [0, 1], M0 and beta >= 0 and finite", x, y, in->pix[i].T,
                              in->pix[i].M0, in->pix[i].beta_px);
        for (int c = 0; c < 3; c++)
            if (!isfinite(in->rgb[3 * i + c]))
                return nbt__failv(NBT_EDOM, "screen: pixel (%zu, %zu): colour channel %d = %g is not accepted: finite",
                                  x, y, c, (double)in->rgb[3 * i + c]);
    }
    return NBT_OK;
}

long nbt__clip(const nbt_screen_input *in)
{
    return (long)(in->w > in->h ? in->w : in->h) - 1;
}

double nbt__depth_key(float D)
{
    return D >= NBT_SCREEN_SKY ? INFINITY : (double)D;
}

double nbt_screen_ray_distance(double Z, size_t w, size_t h, double dtheta, size_t x, size_t y)
{
    if (Z >= NBT_SCREEN_SKY)
        return Z;
    double u = ((double)x + 0.5 - 0.5 * (double)w) * dtheta, v = ((double)y + 0.5 - 0.5 * (double)h) * dtheta;
    return Z * sqrt(1.0 + u * u + v * v);
}

/* ---- brute force ---- */

typedef struct {
    const nbt_screen_input *in;
    const nbt_screen_kernel *k;
    nbt_screen_rule rule;
    double tail;
    unsigned nchunks;
    double *S, *T, **buf;
} brute_ctx;

/* One pass over a fixed chunk of rows. Each pixel's kernel weights serve
 * twice: (NEAR) it gathers from strictly farther pixels with its own kernel,
 * and it spreads onto receivers as far or farther (NEAR) or onto every
 * receiver (SOURCE). Ties are counted once, by the spreading side. */
static nbt_status chunk_pass(size_t chunk, unsigned thread, void *vp)
{
    (void)thread;
    brute_ctx *b = vp;
    const nbt_screen_input *in = b->in;
    size_t ya = chunk * in->h / b->nchunks, yb = (chunk + 1) * in->h / b->nchunks;
    double *out = b->buf[chunk];
    nbt__pkern pk;
    double *wq = NULL, *cell = NULL;
    size_t cap = 0;
    nbt_status st = NBT_OK;
    /* a grey kernel serves the three colours at once; an RGB kernel one each */
    unsigned nk = nbt_screen_kernel_channels(b->k), c0 = 0, c1 = 3;
    if (in->pix)
        nk = 1;
    for (size_t y = ya; y < yb && st == NBT_OK; y++)
        for (size_t x = 0; x < in->w && st == NBT_OK; x++)
            for (unsigned kc = 0; kc < nk && st == NBT_OK; kc++) {
                if (nk == 3)
                    c0 = kc, c1 = kc + 1;
                size_t i = y * in->w + x;
                const float *c = in->rgb + 3 * i;
                int spread = 0, gather = b->rule == NBT_SCREEN_NEAR;
                for (unsigned ch = c0; ch < c1; ch++)
                    spread |= c[ch] != 0;
                st = nbt__input_kernel(b->k, kc, in, i, b->tail, &pk);
                if (b->T && kc == 0)
                    b->T[i] = pk.T;
                if (st != NBT_OK || pk.n == 0 || !(spread || gather))
                    continue;
                st = nbt__pixel_weights(&pk, &wq, &cell, &cap);
                double Di = nbt__depth_key(in->D[i]), s[3] = {0, 0, 0};
                long R = pk.R, R1 = R + 1;
                long y0 = (long)y - R < 0 ? 0 : (long)y - R, y1 = (long)y + R >= (long)in->h ? (long)in->h - 1 : (long)y + R;
                long x0 = (long)x - R < 0 ? 0 : (long)x - R, x1 = (long)x + R >= (long)in->w ? (long)in->w - 1 : (long)x + R;
                for (long yy = y0; yy <= y1 && st == NBT_OK; yy++) {
                    const double *row = wq + labs(yy - (long)y) * R1;
                    for (long xx = x0; xx <= x1; xx++) {
                        size_t j = (size_t)yy * in->w + (size_t)xx;
                        double Dj = nbt__depth_key(in->D[j]), wgt = row[labs(xx - (long)x)];
                        if (gather && Dj > Di) {
                            const float *cj = in->rgb + 3 * j;
                            for (unsigned ch = c0; ch < c1; ch++)
                                s[ch] += wgt * cj[ch];
                        }
                        if (spread && (!gather || Dj >= Di))
                            for (unsigned ch = c0; ch < c1; ch++)
                                out[3 * j + ch] += wgt * c[ch];
                    }
                }
                for (unsigned ch = c0; ch < c1; ch++)
                    out[3 * i + ch] += s[ch];
            }
    free(wq);
    free(cell);
    return st;
}

nbt_status nbt_screen_brute(const nbt_screen_input *in, const nbt_screen_kernel *k, nbt_screen_rule rule,
                            double tail, unsigned nthreads, double *S, double *T)
{
    nbt_status st = nbt_screen_check(in);
    if (st != NBT_OK)
        return st;
    if (!(tail > 0 && tail < 1))
        NBT_FAIL(NBT_EDOM, "screen: tail must lie in (0, 1)");
    size_t np = in->w * in->h;
    memset(S, 0, np * 3 * sizeof *S);
    brute_ctx b = {in, k, rule, tail, nbt__nthreads(nthreads, in->h), S, T, NULL};
    b.buf = calloc(b.nchunks, sizeof *b.buf);
    if (!b.buf)
        NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
    for (unsigned c = 0; c < b.nchunks && st == NBT_OK; c++)
        if (!(b.buf[c] = calloc(np * 3, sizeof(double))))
            st = nbt__fail(NBT_ENOMEM, "screen: out of memory");
    if (st == NBT_OK)
        st = nbt__parallel_for(b.nchunks, nthreads, chunk_pass, &b);
    for (unsigned c = 0; c < b.nchunks; c++) {
        if (st == NBT_OK)
            for (size_t i = 0; i < np * 3; i++)
                S[i] += b.buf[c][i];
        free(b.buf[c]);
    }
    free(b.buf);
    return st;
}

void nbt_screen_quantize(const float *D, size_t n, size_t L, float *out)
{
    double lo = INFINITY, hi = 0;
    for (size_t i = 0; i < n; i++)
        if (D[i] > 0 && D[i] < NBT_SCREEN_SKY) {
            lo = fmin(lo, D[i]);
            hi = fmax(hi, D[i]);
        }
    double span = hi > lo ? log(hi / lo) : 0;
    for (size_t i = 0; i < n; i++) {
        out[i] = D[i];
        if (D[i] > 0 && D[i] < NBT_SCREEN_SKY && span > 0 && L >= 2) {
            double k = nearbyint(log(D[i] / lo) / span * (double)(L - 1));
            out[i] = (float)(lo * exp(span * k / (double)(L - 1)));
        }
    }
}

/* ---- metrics ---- */

nbt_status nbt_screen_compare(const nbt_screen_input *in, const nbt_screen_kernel *k, const double *S,
                              const double *ref, nbt_screen_metrics *m)
{
    memset(m, 0, sizeof *m);
    size_t w = in->w, h = in->h, np = w * h;
    double *rad = malloc(np * sizeof *rad);
    unsigned char *band = calloc(np, 1);
    if (!rad || !band) {
        free(rad);
        free(band);
        NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
    }
    nbt_status st = NBT_OK;
    unsigned nk = in->pix ? 1 : nbt_screen_kernel_channels(k);
    for (size_t i = 0; i < np && st == NBT_OK; i++) { /* the widest atom's scale in pixels; no nodes needed */
        rad[i] = 0;
        for (unsigned kc = 0; kc < nk && st == NBT_OK; kc++) {
            nbt_screen_kern kn;
            double px;
            st = input_atoms(k, kc, in, i, &kn, &px);
            for (size_t a = 0; st == NBT_OK && a < kn.n; a++)
                rad[i] = fmax(rad[i], kn.scale[a] / px);
        }
    }
    /* mark the band: a disc of 2 radii around each discontinuity edge */
    for (size_t y = 0; y < h && st == NBT_OK; y++)
        for (size_t x = 0; x < w; x++)
            for (int dir = 0; dir < 2; dir++) {
                size_t x2 = x + (dir == 0), y2 = y + (dir == 1);
                if (x2 >= w || y2 >= h)
                    continue;
                size_t a = y * w + x, b2 = y2 * w + x2;
                double da = nbt__depth_key(in->D[a]), db = nbt__depth_key(in->D[b2]);
                double near = fmin(da, db), far = fmax(da, db);
                if (!(far - near > 0.05 * near) && !(isinf(far) && !isinf(near)))
                    continue;
                double r = 2.0 * fmax(rad[a], rad[b2]);
                if (r < 1)
                    r = 1;
                double cx = 0.5 * (double)(x + x2), cy = 0.5 * (double)(y + y2);
                long ylo = (long)floor(cy - r), yhi = (long)ceil(cy + r);
                for (long yy = ylo < 0 ? 0 : ylo; yy <= yhi && yy < (long)h; yy++) {
                    double dy = (double)yy - cy, hw = r * r - dy * dy;
                    if (hw < 0)
                        continue;
                    hw = sqrt(hw);
                    long xlo = (long)ceil(cx - hw), xhi = (long)floor(cx + hw);
                    for (long xx = xlo < 0 ? 0 : xlo; xx <= xhi && xx < (long)w; xx++)
                        band[(size_t)yy * w + (size_t)xx] = 1;
                }
            }
    double l1 = 0, l1r = 0, e2 = 0, r2 = 0, be2 = 0, br2 = 0, s = 0, sr = 0, mx = 0, mxr = 0;
    for (size_t i = 0; i < np * 3; i++) {
        double d = S[i] - ref[i];
        l1 += fabs(d);
        l1r += fabs(ref[i]);
        e2 += d * d;
        r2 += ref[i] * ref[i];
        s += S[i];
        sr += ref[i];
        mx = fmax(mx, fabs(d));
        mxr = fmax(mxr, fabs(ref[i]));
        if (band[i / 3]) {
            be2 += d * d;
            br2 += ref[i] * ref[i];
        }
    }
    for (size_t i = 0; i < np; i++)
        m->edge_pixels += band[i];
    m->rel_l1 = l1r > 0 ? l1 / l1r : l1;
    m->rel_rms = r2 > 0 ? sqrt(e2 / r2) : sqrt(e2);
    m->edge = br2 > 0 ? sqrt(be2 / br2) : 0;
    m->bias = sr != 0 ? s / sr - 1 : 0;
    m->max = mxr > 0 ? mx / mxr : mx;
    free(rad);
    free(band);
    return st;
}
