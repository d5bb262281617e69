/* libnbt/mc.c: analog photon counting for a pencil beam in a layered medium. */
#include <config.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <nbt/mc.h>
#include "internal.h"
#include "rng.h"

#define NBATCH NBT_MC_BATCHES
/* weighted estimator: roulette below this weight (default), survival probability (MCML's values) */
#define MC_WROUL 1e-4
#define MC_WROUL_P 0.1

typedef struct {
    const nbt_mc_config *cfg;
    size_t nlay;        /* regions [b[i], b[i+1]) with density rho[i]; b[nlay] = top; b[0] = 0 (infinite: -z_cut) */
    double *b, *rho;
    double *kinv;       /* 1/(sigma_t rho[i]), +inf in vacuum */
    double *binscale;   /* per plane: r_bins/(F z_j) */
    double top;         /* slab: thickness (escape above); else z_cut (photon dropped) */
    int slab;
    int single;         /* one layer, density > 0: leaving it ends the photon */
    nbt_phase_kind skind; /* HG or GAUSS: sampled inline (sparam = g or B); else ISO marks the general sampler */
    double sparam, sinv; /* sinv: HG 1/(2g); Gaussian: the truncation 1 - e^{-pi^2/4B} */
    size_t stride;      /* doubles per batch: nplanes*(r_bins + 2) + 3 */
    double *acc;        /* NBATCH * stride */
    size_t b0, nbatch;  /* this part runs batches [b0, b0 + nbatch) */
    atomic_int *over;   /* rho_fn exceeded rho_max somewhere (a flag outside the
                         * context, which the photon loop sees as const) */
    /* progress: photons of this part finished by all threads, counted in chunks of
     * MC_CHUNK as they go (not only as batches end: one batch of 10^12 photons is
     * hours), and reported from the calling thread (see mc_report) */
    atomic_uint_fast64_t *pdone;
    uint64_t ptotal;
} mc_ctx;

#define MC_CHUNK 256

/* the progress callback with the fraction of this part's photons done (calling thread only) */
static void mc_report(const mc_ctx *c)
{
    if (c->cfg->progress)
        c->cfg->progress((double)atomic_load(c->pdone) / (double)c->ptotal, c->cfg->progress_data);
}

static void mc_watch(void *vp)
{
    mc_report(vp);
}

/* Tally forward crossings of planes in (z0, z1] along a move; *jp is the
 * first plane above z0 and comes back as the first plane above z1. */
static inline void tally(const mc_ctx *c, double *a, size_t *jp, double x, double y, double z0, double z1, double ux,
                         double uy, double uz, double w)
{
    const nbt_mc_config *cf = c->cfg;
    size_t np = cf->nplanes, nb = cf->r_bins, j = *jp;
    for (; j < np && cf->z_planes[j] <= z1; j++) {
        double t = (cf->z_planes[j] - z0) / uz, px = x + t * ux, py = y + t * uy;
        double r2 = px * px + py * py;
        double *pl = a + j * (nb + 2);
        double bin = sqrt(r2) * c->binscale[j];
        if (bin < (double)nb)
            pl[(size_t)bin] += w;
        pl[nb] += w;
        pl[nb + 1] += w * r2; /* analog: w = 1, the same bits as r2 */
    }
    *jp = j;
}

/* keep *jp the first plane above z after a move that tallied nothing */
static inline void plane_index(const nbt_mc_config *cf, size_t *jp, double z)
{
    size_t j = *jp;
    while (j > 0 && cf->z_planes[j - 1] > z)
        j--;
    while (j < cf->nplanes && cf->z_planes[j] <= z)
        j++;
    *jp = j;
}

static inline double sample_mu(const mc_ctx *c, nbt__rng *rs)
{
    if (c->skind == NBT_PHASE_HG) { /* as nbt__phase_sample_mu, inline */
        double g = c->sparam, u = nbt__rng_u(rs);
        if (fabs(g) < 1e-6)
            return 2.0 * u - 1.0;
        double f = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        double mu = (1.0 + g * g - f * f) * c->sinv; /* sinv = 1/(2g) */
        return mu > 1.0 ? 1.0 : (mu < -1.0 ? -1.0 : mu);
    }
    if (c->skind == NBT_PHASE_GAUSS) { /* as nbt__phase_sample_mu: inverse CDF of theta^2 < pi^2 */
        double th = sqrt(-4.0 * c->sparam * log1p(-c->sinv * nbt__rng_u(rs)));
        return cos(fmin(th, NBT_PI));
    }
    /* a copy goes to the general sampler, so that the photon's own state
     * never has its address taken and can stay in registers */
    nbt__rng t = *rs;
    double mu = nbt__phase_sample_mu(c->cfg->phase, nbt__rng_cb, &t);
    *rs = t;
    return mu;
}

/* Photons [p0, p1) into the batch slice a; R, T sums and the event count
 * come back in out[3]. Always inlined with planes and weighted as
 * constants (see run_batch), so that each case compiles without the
 * branches, and without the x, y tracking, it does not need. Every
 * MC_CHUNK photons the part's count of photons done grows; the calling
 * thread (reporter) then also reports progress. */
static inline __attribute__((always_inline)) void photons(const mc_ctx *c, double *a, uint64_t p0, uint64_t p1,
                                                          const int planes, const int weighted, int reporter,
                                                          double out[3])
{
    unsigned since = 0; /* photons since the count last grew */
    const nbt_mc_config *cf = c->cfg;
    uint64_t events = 0;
    double srefl = 0, strans = 0; /* summed here, not in the shared array (no false sharing) */
    const double albedo = cf->albedo, bottom = c->b[0], top = c->top, slabw = c->slab ? 1.0 : 0.0;
    const double wroul = cf->roulette_weight > 0 ? cf->roulette_weight : MC_WROUL;
    for (uint64_t ph = p0; ph < p1; ph++) {
        nbt__rng rs;
        nbt__rng_seed(&rs, cf->seed, ph);
        double x = 0, y = 0, z = 0, ux = 0, uy = 0, uz = 1;
        size_t li = 0, jp = 0; /* layer; first tally plane above z */
        unsigned scattered = 0; /* scatterings so far */
        double w = 1.0;         /* the photon's weight (analog: always 1) */
        for (;;) {
            int alive = 1;
            if (cf->rho_fn) {
                /* delta tracking: tentative collisions at the majorant rate,
                 * real with probability rho(z)/rho_max */
                for (;;) {
                    double d = -log1p(-nbt__rng_u(&rs)) / (cf->sigma_t * cf->rho_max);
                    double z1 = z + d * uz;
                    if (z1 < bottom || z1 > top) { /* leaves through z = 0 (infinite: below -z_cut), or dropped below z_cut */
                        if (planes && scattered && uz > 0)
                            tally(c, a, &jp, x, y, z, fmin(z1, top), ux, uy, uz, w);
                        alive = 0;
                        break;
                    }
                    if (planes && scattered && uz > 0)
                        tally(c, a, &jp, x, y, z, z1, ux, uy, uz, w);
                    else if (planes)
                        plane_index(cf, &jp, z1);
                    x += d * ux;
                    y += d * uy;
                    z = z1;
                    double rho = cf->rho_fn(z > 0 ? z : 0.0, cf->rho_data); /* infinite: rho(0) continues behind */
                    if (rho > cf->rho_max)
                        atomic_store(c->over, 1);
                    if (nbt__rng_u(&rs) * cf->rho_max < rho)
                        break;
                }
            } else {
                double tau = -log1p(-nbt__rng_u(&rs)); /* optical depth to the next interaction */
                /* the common case: the interaction lies inside the current layer */
                double dn = tau * c->kinv[li], z1 = z + dn * uz;
                if (z1 > c->b[li] && z1 < c->b[li + 1]) { /* both tests, not a branch on the sign of uz */
                    if (planes && scattered && uz > 0)
                        tally(c, a, &jp, x, y, z, z1, ux, uy, uz, w);
                    else if (planes)
                        plane_index(cf, &jp, z1);
                    x += dn * ux;
                    y += dn * uy;
                    z = z1;
                    tau = 0;
                } else if (c->single) { /* one layer with medium: the photon leaves it */
                    int up = z1 >= c->b[1];
                    if (planes && scattered && uz > 0)
                        tally(c, a, &jp, x, y, z, c->b[1], ux, uy, uz, w);
                    if (up)
                        strans += slabw * w; /* through the top (else: dropped below z_cut) */
                    else
                        srefl += slabw * w;  /* out through z = 0 (infinite: dropped below -z_cut) */
                    alive = 0;
                    tau = 0;
                }
                while (alive && tau > 0) {
                    double rho = c->rho[li], zb;
                    int up = uz > 0;
                    if (uz > 0)
                        zb = c->b[li + 1];
                    else if (uz < 0)
                        zb = c->b[li];
                    else
                        zb = NAN;
                    double db = uz != 0 ? (zb - z) / uz : INFINITY;
                    dn = rho > 0 ? tau / (cf->sigma_t * rho) : INFINITY;
                    double d = dn < db ? dn : db;
                    if (isinf(d)) { /* horizontal flight in vacuum: never returns */
                        alive = 0;
                        break;
                    }
                    z1 = dn < db ? z + d * uz : zb;
                    if (planes && scattered && uz > 0)
                        tally(c, a, &jp, x, y, z, z1, ux, uy, uz, w);
                    else if (planes)
                        plane_index(cf, &jp, z1);
                    x += d * ux;
                    y += d * uy;
                    z = z1;
                    if (dn < db) {
                        tau = 0;
                        break;
                    }
                    tau -= cf->sigma_t * rho * db;
                    if (up) {
                        if (++li == c->nlay) { /* through the top */
                            strans += slabw * w;
                            alive = 0;
                        }
                    } else {
                        if (li-- == 0) { /* out through z = 0 (infinite: dropped below -z_cut) */
                            srefl += slabw * w;
                            alive = 0;
                        }
                    }
                }
            }
            if (!alive)
                break;
            events++;
            if (!weighted) {
                if (nbt__rng_u(&rs) >= albedo)
                    break; /* absorbed */
            } else {
                w *= albedo; /* implicit capture: the absorbed fraction leaves the weight */
                if (w < wroul) { /* Russian roulette keeps E[w] */
                    if (!(w > 0) || nbt__rng_u(&rs) >= MC_WROUL_P)
                        break;
                    w *= 1.0 / MC_WROUL_P;
                }
            }
            if (cf->order_max && scattered == cf->order_max)
                break; /* would scatter an (order_max+1)-th time */
            scattered++;
            double mu = sample_mu(c, &rs);
            double s2 = 1.0 - mu * mu, st = sqrt(s2 > 0 ? s2 : 0.0), phi = 2.0 * NBT_PI * nbt__rng_u(&rs);
            if (!planes) {
                /* no tally planes (a slab): nothing observes x, y, ux or uy, so
                 * only uz turns, and the azimuth enters through cos(phi) alone
                 * (|uz| <= 1 up to rounding, by Cauchy-Schwarz) */
                uz = -st * cos(phi) * sqrt(fmax(0.0, 1.0 - uz * uz)) + uz * mu;
                continue;
            }
            double u[3] = {ux, uy, uz};
            nbt__turn(u, mu, st, cos(phi), sin(phi));
            ux = u[0];
            uy = u[1];
            uz = u[2];
        }
        if (++since == MC_CHUNK) {
            atomic_fetch_add_explicit(c->pdone, MC_CHUNK, memory_order_relaxed);
            since = 0;
            if (reporter)
                mc_report(c);
        }
    }
    atomic_fetch_add_explicit(c->pdone, since, memory_order_relaxed);
    out[0] = srefl;
    out[1] = strans;
    out[2] = (double)events;
}

static nbt_status run_batch(size_t i, unsigned thread, void *vp)
{
    mc_ctx *c = vp;
    size_t batch = c->b0 + i;
    const nbt_mc_config *cf = c->cfg;
    double *a = c->acc + batch * c->stride, out[3];
    uint64_t p0 = cf->photons * batch / NBATCH, p1 = cf->photons * (batch + 1) / NBATCH;
    size_t tail = c->stride - 3; /* R, T, events */
    const int planes = cf->nplanes > 0, weighted = cf->estimator == NBT_MC_WEIGHTED;
    const int rep = thread == 0 && cf->progress;
    if (planes)
        weighted ? photons(c, a, p0, p1, 1, 1, rep, out) : photons(c, a, p0, p1, 1, 0, rep, out);
    else
        weighted ? photons(c, a, p0, p1, 0, 1, rep, out) : photons(c, a, p0, p1, 0, 0, rep, out);
    a[tail] = out[0];
    a[tail + 1] = out[1];
    a[tail + 2] = out[2];
    if (rep)
        mc_report(c);
    return NBT_OK;
}

static nbt_status check(const nbt_mc_config *c)
{
    if (!(c->sigma_t > 0) || !isfinite(c->sigma_t))
        NBT_FAIL(NBT_EDOM, "mc: sigma_t must be finite and > 0");
    if (!(c->albedo >= 0 && c->albedo <= 1))
        NBT_FAIL(NBT_EDOM, "mc: albedo must lie in [0, 1]");
    if (!c->phase)
        NBT_FAIL(NBT_EINVAL, "mc: no phase function");
    if (c->photons < NBATCH)
        NBT_FAIL(NBT_EDOM, "mc: at least 64 photons");
    if (!(c->slab >= 0) || !isfinite(c->slab))
        NBT_FAIL(NBT_EDOM, "mc: slab thickness must be finite and >= 0");
    if (c->nplanes > 0) {
        if (!c->z_planes || c->r_bins < 1 || !(c->r_max_scale > 0) || !isfinite(c->r_max_scale))
            NBT_FAIL(NBT_EDOM, "mc: planes need r_bins >= 1 and r_max_scale > 0");
        for (size_t j = 0; j < c->nplanes; j++)
            if (!(c->z_planes[j] > 0) || !isfinite(c->z_planes[j]) || (j > 0 && !(c->z_planes[j] > c->z_planes[j - 1])))
                NBT_FAIL(NBT_EDOM, "mc: tally planes must be finite, > 0 and increasing");
    } else if (c->slab == 0)
        NBT_FAIL(NBT_EINVAL, "mc: nothing to tally (no planes, no slab)");
    if (c->rho_fn && !(c->rho_max > 0 && isfinite(c->rho_max)))
        NBT_FAIL(NBT_EDOM, "mc: a density callback needs a finite bound rho_max > 0");
    if (c->estimator != NBT_MC_ANALOG && c->estimator != NBT_MC_WEIGHTED)
        NBT_FAIL(NBT_EINVAL, "mc: estimator must be NBT_MC_ANALOG or NBT_MC_WEIGHTED");
    if (!(c->roulette_weight >= 0 && c->roulette_weight < 1))
        NBT_FAIL(NBT_EDOM, "mc: roulette_weight must lie in [0, 1)");
    if (c->infinite && c->slab > 0)
        NBT_FAIL(NBT_EINVAL, "mc: a slab cannot be infinite (infinite and slab exclude each other)");
    if (c->rho_fn && c->slab > 0)
        NBT_FAIL(NBT_EINVAL, "mc: a density callback and a slab exclude each other");
    if (c->nlayers > 0 && c->slab == 0 && !c->rho_fn) {
        if (!c->z || !c->rho || c->z[0] != 0)
            NBT_FAIL(NBT_EDOM, "mc: layers need z[0] = 0 and a density per layer");
        for (size_t i = 0; i < c->nlayers; i++)
            if (!(c->rho[i] >= 0) || !isfinite(c->rho[i]) || !isfinite(c->z[i]) || (i > 0 && !(c->z[i] > c->z[i - 1])))
                NBT_FAIL(NBT_EDOM, "mc: layer boundaries must increase and densities be finite, >= 0");
    }
    if (!(c->z_cut >= 0) || !isfinite(c->z_cut))
        NBT_FAIL(NBT_EDOM, "mc: z_cut must be finite and >= 0");
    return NBT_OK;
}

void nbt_mc_result_free(nbt_mc_result *r)
{
    if (!r)
        return;
    free(r->psi);
    free(r->psi_se);
    free(r->M0);
    free(r->M0_se);
    free(r->M2);
    free(r->M2_se);
    free(r);
}

/* mean of per-photon values from batch sums, and its standard error from the
 * spread of the batch means (sizes differ by at most one photon) */
static void batch_stats(const nbt_mc_config *cf, const double *acc, size_t stride, size_t off, double scale,
                        double *mean, double *se)
{
    double N = (double)cf->photons, tot = 0;
    for (size_t b = 0; b < NBATCH; b++)
        tot += acc[b * stride + off];
    double m = tot / N, v = 0;
    for (size_t b = 0; b < NBATCH; b++) {
        double nb = (double)(cf->photons * (b + 1) / NBATCH - cf->photons * b / NBATCH);
        double d = acc[b * stride + off] / nb - m;
        v += nb * d * d;
    }
    *mean = m * scale;
    *se = sqrt(v / ((NBATCH - 1) * N)) * scale;
}

size_t nbt_mc_tally_len(const nbt_mc_config *cfg)
{
    return NBT_MC_BATCHES * (cfg->nplanes * (cfg->r_bins + 2) + 3);
}

void nbt_mc_part_range(size_t part, size_t nparts, size_t *b0, size_t *b1)
{
    if (nparts == 0 || part >= nparts) {
        *b0 = *b1 = NBT_MC_BATCHES;
        return;
    }
    *b0 = NBT_MC_BATCHES * part / nparts;
    *b1 = NBT_MC_BATCHES * (part + 1) / nparts;
}

nbt_status nbt_mc_run_part(const nbt_mc_config *cf, size_t b0, size_t b1, double *tally)
{
    nbt_status st = check(cf);
    if (st != NBT_OK)
        return st;
    if (!tally || b0 > b1 || b1 > NBATCH)
        NBT_FAIL(NBT_EINVAL, "mc: a part needs a tally array and batches b0 <= b1 <= 64");
    if (b0 == b1)
        return NBT_OK; /* a part with no photons adds nothing */
    mc_ctx c = {.cfg = cf, .acc = tally, .b0 = b0, .nbatch = b1 - b0};
    atomic_int over;
    atomic_init(&over, 0);
    c.over = &over;
    atomic_uint_fast64_t pdone;
    atomic_init(&pdone, 0);
    c.pdone = &pdone;
    c.ptotal = cf->photons * b1 / NBATCH - cf->photons * b0 / NBATCH;
    size_t nl = cf->slab > 0 || cf->rho_fn ? 1 : (cf->nlayers ? cf->nlayers : 1);
    c.nlay = nl;
    c.slab = cf->slab > 0;
    c.b = malloc((nl + 1) * sizeof(double));
    c.rho = malloc(nl * sizeof(double));
    c.kinv = malloc(nl * sizeof(double));
    c.binscale = malloc((cf->nplanes + 1) * sizeof(double));
    if (!nbt__phase_sample_param(cf->phase, &c.skind, &c.sparam))
        c.skind = NBT_PHASE_ISO;
    c.sinv = c.skind == NBT_PHASE_HG      ? 0.5 / c.sparam
           : c.skind == NBT_PHASE_GAUSS ? -expm1(-NBT_PI * NBT_PI / (4.0 * c.sparam))
                                        : 0.0;
    c.stride = cf->nplanes * (cf->r_bins + 2) + 3;
    if (!c.b || !c.rho || !c.kinv || !c.binscale) {
        free(c.b);
        free(c.rho);
        free(c.kinv);
        free(c.binscale);
        NBT_FAIL(NBT_ENOMEM, "mc: out of memory");
    }
    if (c.slab) {
        c.b[0] = 0;
        c.b[1] = cf->slab;
        c.rho[0] = 1;
    } else {
        for (size_t i = 0; i < nl; i++) {
            int lay = cf->nlayers && !cf->rho_fn;
            c.b[i] = lay ? cf->z[i] : 0.0;
            c.rho[i] = lay ? cf->rho[i] : 1.0;
        }
        double last = cf->nplanes ? cf->z_planes[cf->nplanes - 1] : 0;
        double zc = cf->z_cut > 0 ? cf->z_cut : 2.0 * last + 20.0 / cf->sigma_t;
        if (zc <= c.b[nl - 1])
            zc = c.b[nl - 1] + 20.0 / cf->sigma_t;
        c.b[nl] = zc;
        if (cf->infinite)
            c.b[0] = -zc; /* the first layer (or rho_fn(0)) continues behind the source */
    }
    c.top = c.b[nl];
    c.single = nl == 1 && c.rho[0] > 0;
    for (size_t i = 0; i < nl; i++)
        c.kinv[i] = c.rho[i] > 0 ? 1.0 / (cf->sigma_t * c.rho[i]) : INFINITY;
    for (size_t j = 0; j < cf->nplanes; j++)
        c.binscale[j] = (double)cf->r_bins / (cf->r_max_scale * cf->z_planes[j]);
    /* a batch's slice starts from zero and is filled by one thread in photon
     * order: the same bits whoever runs it */
    memset(tally + b0 * c.stride, 0, (b1 - b0) * c.stride * sizeof(double));
    /* progress as photons finish, also while the last batches run on other threads */
    st = nbt__parallel_for_watch(c.nbatch, cf->threads, run_batch, &c, cf->progress ? mc_watch : NULL, &c, 0.25);
    if (st == NBT_OK)
        mc_report(&c); /* all done: 1 */
    if (st == NBT_OK && atomic_load(&over))
        st = nbt__fail(NBT_EDOM, "mc: the density callback exceeded rho_max");
    free(c.b);
    free(c.rho);
    free(c.kinv);
    free(c.binscale);
    return st;
}

nbt_status nbt_mc_finish(const nbt_mc_config *cf, const double *tally, nbt_mc_result **out)
{
    *out = NULL;
    nbt_status st = check(cf);
    if (st != NBT_OK)
        return st;
    if (!tally)
        NBT_FAIL(NBT_EINVAL, "mc: no tally array");
    size_t stride = cf->nplanes * (cf->r_bins + 2) + 3;
    nbt_mc_result *r = calloc(1, sizeof *r);
    size_t nv = cf->nplanes * cf->r_bins;
    if (r) {
        r->psi = malloc((nv ? nv : 1) * sizeof(double));
        r->psi_se = malloc((nv ? nv : 1) * sizeof(double));
        r->M0 = malloc((cf->nplanes + 1) * sizeof(double));
        r->M0_se = malloc((cf->nplanes + 1) * sizeof(double));
        r->M2 = malloc((cf->nplanes + 1) * sizeof(double));
        r->M2_se = malloc((cf->nplanes + 1) * sizeof(double));
    }
    if (!r || !r->psi || !r->psi_se || !r->M0 || !r->M0_se || !r->M2 || !r->M2_se) {
        nbt_mc_result_free(r);
        NBT_FAIL(NBT_ENOMEM, "mc: out of memory");
    }
    r->nplanes = cf->nplanes;
    r->r_bins = cf->r_bins;
    size_t nb = cf->r_bins;
    for (size_t j = 0; j < cf->nplanes; j++) {
        double zj = cf->z_planes[j], dr = cf->r_max_scale * zj / (double)nb;
        for (size_t k = 0; k < nb; k++) {
            double area = NBT_PI * dr * dr * (double)(2 * k + 1); /* annulus [k dr, (k+1) dr) */
            batch_stats(cf, tally, stride, j * (nb + 2) + k, 1.0 / area, &r->psi[j * nb + k], &r->psi_se[j * nb + k]);
        }
        batch_stats(cf, tally, stride, j * (nb + 2) + nb, 1.0, &r->M0[j], &r->M0_se[j]);
        batch_stats(cf, tally, stride, j * (nb + 2) + nb + 1, 1.0, &r->M2[j], &r->M2_se[j]);
    }
    size_t tail = stride - 3;
    batch_stats(cf, tally, stride, tail, 1.0, &r->R, &r->R_se);
    batch_stats(cf, tally, stride, tail + 1, 1.0, &r->T, &r->T_se);
    double ev = 0;
    for (size_t b = 0; b < NBATCH; b++)
        ev += tally[b * stride + tail + 2];
    r->interactions = (uint64_t)ev;
    *out = r;
    return NBT_OK;
}

nbt_status nbt_mc_run(const nbt_mc_config *cf, nbt_mc_result **out)
{
    *out = NULL;
    nbt_status st = check(cf);
    if (st != NBT_OK)
        return st;
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    double *tally = malloc(nbt_mc_tally_len(cf) * sizeof(double));
    if (!tally)
        NBT_FAIL(NBT_ENOMEM, "mc: out of memory");
    st = nbt_mc_run_part(cf, 0, NBATCH, tally);
    if (st == NBT_OK)
        st = nbt_mc_finish(cf, tally, out);
    free(tally);
    if (st != NBT_OK)
        return st;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    (*out)->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    return NBT_OK;
}
