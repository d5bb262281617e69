/* libnbt/mc_kernel.c: photon counts of screen kernels (nbt_mc_kernel_run,
 * nbt/mc.h): first crossings of planes by a pencil beam in a homogeneous
 * medium, binned in radius and scattering order, at several albedos from
 * one set of paths. */
#include <config.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/mc.h>
#include "internal.h"
#include "rng.h"

#define KCHUNKS 16 /* fixed photon ranges, each summed in photon order: results do not depend on threads */

typedef struct {
    const nbt_mc_kernel_config *cf;
    size_t nbins, cells;  /* cells = planes * albedos * 2 * bins */
    unsigned nmax;
    double *pw;           /* pw[k * (nmax + 1) + n] = albedo_k^n */
    double *sum, *sq;     /* per chunk: cells each */
    double *lost;         /* per chunk, per albedo: weight of paths still unfinished at nmax */
    nbt_phase_kind skind; /* HG: sampled inline */
    double g;
    atomic_uint done;
} kctx;

static inline double sample_mu(const kctx *c, nbt__rng *rs)
{
    if (c->skind == NBT_PHASE_HG && fabs(c->g) >= 1e-6) {
        double g = c->g, f = (1.0 - g * g) / (1.0 - g + 2.0 * g * nbt__rng_u(rs));
        double mu = (1.0 + g * g - f * f) / (2.0 * g);
        return mu > 1.0 ? 1.0 : (mu < -1.0 ? -1.0 : mu);
    }
    return nbt__phase_sample_mu(c->cf->phase, nbt__rng_cb, rs);
}

/* radial bin of r / z among the edges: [0, e0) is 0, [e_{E-1}, inf) is E */
static inline size_t rbin(const double *e, size_t ne, double x)
{
    size_t lo = 0, hi = ne;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (x < e[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

static nbt_status run_chunk(size_t ch, unsigned thread, void *vp)
{
    kctx *c = vp;
    const nbt_mc_kernel_config *cf = c->cf;
    const size_t np = cf->nplanes, na = cf->nalbedo, nb = c->nbins;
    const double *zp = cf->z_planes;
    double *sum = c->sum + ch * c->cells, *sq = c->sq + ch * c->cells, *lost = c->lost + ch * na;
    uint64_t p0 = cf->photons * ch / KCHUNKS, p1 = cf->photons * (ch + 1) / KCHUNKS;
    const double zcut = cf->z_cut > 0 ? cf->z_cut : 2.0 * zp[np - 1] + 20.0;
    for (uint64_t ph = p0; ph < p1; ph++) {
        nbt__rng rs;
        nbt__rng_seed(&rs, cf->seed, ph);
        /* the unscattered flight: every plane it passes is first crossed by the direct beam */
        double z = -log1p(-nbt__rng_u(&rs)), x = 0, y = 0, ux = 0, uy = 0, uz = 1;
        size_t jf = 0;
        while (jf < np && zp[jf] <= z)
            jf++;
        unsigned n = 0;
        while (jf < np) {
            if (n == c->nmax) { /* not followed further: what it could still add is at most its weight */
                for (size_t k = 0; k < na; k++)
                    lost[k] += c->pw[k * (c->nmax + 1) + n];
                break;
            }
            n++;
            double mu = sample_mu(c, &rs), s2 = 1.0 - mu * mu, st = sqrt(s2 > 0 ? s2 : 0.0);
            double phi = 2.0 * NBT_PI * nbt__rng_u(&rs), cp = cos(phi), sp = sin(phi);
            double u[3] = {ux, uy, uz};
            nbt__turn(u, mu, st, cp, sp);
            ux = u[0];
            uy = u[1];
            uz = u[2];
            double d = -log1p(-nbt__rng_u(&rs)), z1 = z + d * uz;
            if (uz > 0)
                for (; jf < np && zp[jf] <= z1; jf++) {
                    double t = (zp[jf] - z) / uz, px = x + t * ux, py = y + t * uy;
                    size_t b = rbin(cf->edges, cf->nedges, sqrt(px * px + py * py) / zp[jf]);
                    size_t base = (jf * na * 2 + (n > 1)) * nb + b;
                    for (size_t k = 0; k < na; k++) {
                        double w = c->pw[k * (c->nmax + 1) + n];
                        sum[base + k * 2 * nb] += w;
                        sq[base + k * 2 * nb] += w * w;
                    }
                }
            x += d * ux;
            y += d * uy;
            z = z1;
            if (z < (cf->infinite ? -zcut : 0.0))
                break; /* escaped through the camera plane (half space), or dropped far behind */
        }
    }
    unsigned dn = atomic_fetch_add(&c->done, 1) + 1;
    if (thread == 0 && cf->progress)
        cf->progress((double)dn / KCHUNKS, cf->progress_data);
    return NBT_OK;
}

void nbt_mc_kernel_result_free(nbt_mc_kernel_result *r)
{
    if (!r)
        return;
    free(r->mass);
    free(r->mass_se);
    free(r->lost);
    free(r);
}

nbt_status nbt_mc_kernel_run(const nbt_mc_kernel_config *cf, nbt_mc_kernel_result **out)
{
    *out = NULL;
    if (!cf->phase)
        NBT_FAIL(NBT_EINVAL, "mc kernel: no phase function");
    if (cf->nplanes < 1 || !cf->z_planes || cf->nalbedo < 1 || !cf->albedo || (cf->nedges > 0 && !cf->edges))
        NBT_FAIL(NBT_EINVAL, "mc kernel: needs planes, albedos and (when nedges > 0) the edges");
    for (size_t j = 0; j < cf->nplanes; j++)
        if (!(cf->z_planes[j] > 0) || !isfinite(cf->z_planes[j]) || (j && !(cf->z_planes[j] > cf->z_planes[j - 1])))
            NBT_FAIL(NBT_EDOM, "mc kernel: planes must be finite, > 0 and increasing");
    for (size_t j = 0; j < cf->nedges; j++)
        if (!(cf->edges[j] > 0) || !isfinite(cf->edges[j]) || (j && !(cf->edges[j] > cf->edges[j - 1])))
            NBT_FAIL(NBT_EDOM, "mc kernel: radial edges must be finite, > 0 and increasing");
    double amax = 0;
    for (size_t k = 0; k < cf->nalbedo; k++) {
        if (!(cf->albedo[k] >= 0 && cf->albedo[k] <= 1))
            NBT_FAIL(NBT_EDOM, "mc kernel: albedos must lie in [0, 1]");
        amax = fmax(amax, cf->albedo[k]);
    }
    if (cf->photons < KCHUNKS)
        NBT_FAIL(NBT_EDOM, "mc kernel: at least 16 photons");
    if (!(cf->z_cut >= 0) || !isfinite(cf->z_cut))
        NBT_FAIL(NBT_EDOM, "mc kernel: z_cut must be finite and >= 0");
    unsigned nmax = cf->order_max;
    if (nmax == 0) { /* follow a path until the largest albedo has taken its weight below 1e-9 */
        if (!(amax < 1))
            NBT_FAIL(NBT_EDOM, "mc kernel: an albedo of 1 needs order_max (paths would never end)");
        double n = amax > 0 ? ceil(log(1e-9) / log(amax)) : 1;
        nmax = n < 1 ? 1u : (n > 1e6 ? 1000000u : (unsigned)n);
    }
    kctx c = {.cf = cf, .nbins = cf->nedges + 1, .nmax = nmax};
    atomic_init(&c.done, 0);
    c.cells = cf->nplanes * cf->nalbedo * 2 * c.nbins;
    if (!nbt__phase_sample_param(cf->phase, &c.skind, &c.g))
        c.skind = NBT_PHASE_ISO;
    c.pw = malloc(cf->nalbedo * (nmax + 1) * sizeof *c.pw);
    c.sum = calloc(KCHUNKS * c.cells, sizeof *c.sum);
    c.sq = calloc(KCHUNKS * c.cells, sizeof *c.sq);
    c.lost = calloc(KCHUNKS * cf->nalbedo, sizeof *c.lost);
    nbt_mc_kernel_result *r = calloc(1, sizeof *r);
    nbt_status st = NBT_OK;
    if (r) {
        r->mass = malloc(c.cells * sizeof *r->mass);
        r->mass_se = malloc(c.cells * sizeof *r->mass_se);
        r->lost = calloc(cf->nalbedo, sizeof *r->lost);
    }
    if (!c.pw || !c.sum || !c.sq || !c.lost || !r || !r->mass || !r->mass_se || !r->lost)
        st = nbt__fail(NBT_ENOMEM, "mc kernel: out of memory");
    if (st == NBT_OK) {
        for (size_t k = 0; k < cf->nalbedo; k++) {
            double w = 1;
            for (unsigned n = 0; n <= nmax; n++, w *= cf->albedo[k])
                c.pw[k * (nmax + 1) + n] = w;
        }
        st = nbt__parallel_for(KCHUNKS, cf->threads, run_chunk, &c);
    }
    if (st == NBT_OK) {
        double N = (double)cf->photons;
        r->nplanes = cf->nplanes;
        r->nalbedo = cf->nalbedo;
        r->nbins = c.nbins;
        r->order_max = nmax;
        for (size_t i = 0; i < c.cells; i++) {
            double s = 0, q = 0;
            for (size_t ch = 0; ch < KCHUNKS; ch++) {
                s += c.sum[ch * c.cells + i];
                q += c.sq[ch * c.cells + i];
            }
            double m = s / N, v = (q / N - m * m) / (N - 1);
            r->mass[i] = m;
            r->mass_se[i] = sqrt(v > 0 ? v : 0);
        }
        for (size_t k = 0; k < cf->nalbedo; k++) {
            for (size_t ch = 0; ch < KCHUNKS; ch++)
                r->lost[k] += c.lost[ch * cf->nalbedo + k];
            r->lost[k] /= N;
        }
        *out = r;
        r = NULL;
    }
    nbt_mc_kernel_result_free(r);
    free(c.pw);
    free(c.sum);
    free(c.sq);
    free(c.lost);
    return st;
}
