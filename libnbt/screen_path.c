/* libnbt/screen_path.c: the path-traced reference of nbt/screen_path.h.
 *
 * Estimator. L(x, w), the radiance seen from x along w, is
 *     T(t_b) L_b + int_0^{t_b} sigma_s e^{-sigma_t t} <p L(x + t w, .)> dt,
 * t_b the distance to the first patch or the medium's edge, L_b what lies
 * there. A camera ray keeps only the integral (the scattered part). Every
 * integral is sampled at a collision forced before t_b; at a collision the
 * in-scattered light's boundary term is estimated twice, by next-event
 * estimation to a patch and by the phase-sampled direction, weighted by the
 * power heuristic, and the integral term recurses along that same phase-
 * sampled direction (so each vertex casts two rays). RGB media: the
 * collision distance is drawn from the balance mixture of the channels'
 * truncated exponentials, each channel weighted by its own f/p (bounded by
 * 3 albedo), so one path serves all channels.
 *
 * Ray casting. A patch is hit at z = Z, so only the part of a ray with
 * Z_min <= z <= Z_max matters. Its perspective projection is a straight
 * segment in the image (u = VP + Q/z with VP the vanishing point), traversed
 * monotonically in t; walking the pixels it crosses in order (2-D DDA) and
 * testing in each whether the ray reaches z = Z(pixel) inside that pixel's
 * footprint finds the nearest patch exactly. Footprints are widened by 1e-9
 * px so that a ray through the shared edge of two patches at the same depth
 * never slips between them. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/screen.h>
#include <nbt/screen_path.h>
#include "internal.h"
#include "rng.h"

#define EDGE_EPS 1e-9 /* footprint widening, pixels */
#define RR_ORDER 2    /* Russian roulette from this order on (paths are long) ... */
#define RR_BETA 0.6   /* ... survival max-channel weight / RR_BETA (larger: heavier tails) */
#define NB_MAX 64     /* at most this many bright patches get per-vertex selection weights */
#define NB_RATIO 16.0 /* a patch is bright when its power is this many times the mean */
#define NB_FLOOR (0.01 / (4.0 * NBT_PI)) /* phase floor in the bright weights: never zero where light can come */
#define NB_TAB 512 /* the bright weights' phase: a table over s = sin(theta / 2), nearest entry */

typedef struct {
    size_t w, h;
    const float *Z, *rgb;
    double dth, cx, cy, zmin, zmax;
    /* next-event estimation: emitting patches by power (|c| summed over channels x area) */
    size_t nlights;
    double *cdf;    /* nlights, increasing to 1 */
    size_t *lidx;   /* world pixel of each light */
    double *pick;   /* w*h: probability of choosing each pixel from the rest (0: never or bright) */
    /* bright patches (HDR lamps): chosen with probability pb by a per-vertex weight
     * lum A cos / r^2 (phase + floor) at their centres; the rest by power */
    size_t nb;
    size_t bidx[NB_MAX];
    double blum[NB_MAX], bpos[NB_MAX][3], barea[NB_MAX];
    long *bslot; /* w*h: index into the bright list, -1: not bright */
    double pb;   /* probability of the bright list when a vertex sees any bright patch */
    double ptab[NB_TAB + 1]; /* phase at s = k / NB_TAB, plus NB_FLOOR (weights only: any positive function) */
    /* medium */
    double sig[3], sigs[3], act[3];
    int nact;
    double R, sky[3];
    const nbt_phase *ph;
    unsigned max_order;
    int nee;
    /* the run */
    size_t x0, y0, ow, oh;
    unsigned long spp, pass;
    uint64_t seed;
    double *sum, *sum2; /* ow*oh*3 */
} pctx;

typedef struct {
    double t;
    long idx; /* world pixel, -1: none */
} phit;

/* the bright patches' selection weights at one vertex */
typedef struct {
    double w[NB_MAX], sum, pb; /* pb: the bright list's probability here (0 when no bright patch is in front) */
} bweights;

static void bright_weights(const pctx *c, const double x[3], const double d[3], bweights *bw)
{
    bw->sum = 0.0;
    for (size_t j = 0; j < c->nb; j++) {
        const double *q = c->bpos[j];
        double v0 = q[0] - x[0], v1 = q[1] - x[1], v2 = q[2] - x[2], wj = 0.0;
        if (v2 > 0) {
            double r2 = v0 * v0 + v1 * v1 + v2 * v2, ir = 1.0 / sqrt(r2);
            double mu = (d[0] * v0 + d[1] * v1 + d[2] * v2) * ir, sh = sqrt(fmax(0.0, 0.5 * (1.0 - mu)));
            int k = (int)(sh * NB_TAB + 0.5);
            wj = c->blum[j] * c->barea[j] * v2 * ir / r2 * c->ptab[k > NB_TAB ? NB_TAB : k];
        }
        bw->w[j] = wj;
        bw->sum += wj;
    }
    bw->pb = bw->sum > 0 ? (c->nlights > c->nb ? c->pb : 1.0) : 0.0;
}

/* probability (per unit area of the patch) that NEE at this vertex picks a point on patch id */
static double pick_area_pdf(const pctx *c, const bweights *bw, size_t id)
{
    long s = c->nb ? c->bslot[id] : -1;
    if (s >= 0)
        return bw->pb * bw->w[s] / bw->sum / c->barea[s];
    double Zj = c->Z[id];
    return (1.0 - bw->pb) * c->pick[id] / (Zj * Zj * c->dth * c->dth);
}

/* The nearest patch along o + t d, 0 < t <= tmax. */
static phit trace(const pctx *c, const double o[3], const double d[3], double tmax)
{
    phit r = {INFINITY, -1};
    if (!(c->zmin < INFINITY) || d[2] == 0.0)
        return r;
    double lo = c->zmin * (1.0 - 1e-9), hi = c->zmax * (1.0 + 1e-9), ta, tb;
    if (d[2] > 0) {
        ta = (lo - o[2]) / d[2];
        tb = (hi - o[2]) / d[2];
    } else {
        ta = (hi - o[2]) / d[2];
        tb = (lo - o[2]) / d[2];
    }
    if (ta < 0)
        ta = 0;
    if (tb > tmax)
        tb = tmax;
    if (!(ta <= tb))
        return r;
    /* the segment's ends in pixel coordinates (z > 0 at both) */
    double za = o[2] + ta * d[2], zb = o[2] + tb * d[2], k = 1.0 / c->dth;
    double ax = c->cx + (o[0] + ta * d[0]) / za * k, ay = c->cy - (o[1] + ta * d[1]) / za * k;
    double bx = c->cx + (o[0] + tb * d[0]) / zb * k, by = c->cy - (o[1] + tb * d[1]) / zb * k;
    double Dx = bx - ax, Dy = by - ay, s0 = 0.0, s1 = 1.0;
    /* Liang-Barsky clip to [0, w] x [0, h] */
    const double p[4] = {-Dx, Dx, -Dy, Dy}, q[4] = {ax, (double)c->w - ax, ay, (double)c->h - ay};
    for (int i = 0; i < 4; i++) {
        if (p[i] == 0.0) {
            if (q[i] < 0)
                return r;
        } else {
            double s = q[i] / p[i];
            if (p[i] < 0) {
                if (s > s0)
                    s0 = s;
            } else if (s < s1)
                s1 = s;
        }
    }
    if (s0 > s1)
        return r;
    double sx = ax + s0 * Dx, sy = ay + s0 * Dy;
    long ix = (long)floor(sx), iy = (long)floor(sy), W = (long)c->w, H = (long)c->h;
    ix = ix < 0 ? 0 : ix >= W ? W - 1 : ix;
    iy = iy < 0 ? 0 : iy >= H ? H - 1 : iy;
    int stx = Dx > 0 ? 1 : -1, sty = Dy > 0 ? 1 : -1;
    double tmx = Dx > 0 ? (ix + 1 - ax) / Dx : Dx < 0 ? (ix - ax) / Dx : INFINITY;
    double tmy = Dy > 0 ? (iy + 1 - ay) / Dy : Dy < 0 ? (iy - ay) / Dy : INFINITY;
    double tdx = Dx != 0 ? fabs(1.0 / Dx) : INFINITY, tdy = Dy != 0 ? fabs(1.0 / Dy) : INFINITY;
    double idz = 1.0 / d[2];
    for (;;) {
        size_t id = (size_t)iy * c->w + (size_t)ix;
        float zf = c->Z[id];
        if (zf < NBT_SCREEN_SKY) {
            double t = (zf - o[2]) * idz;
            if (t > 0 && t <= tmax) {
                double kz = k / zf;
                double px = c->cx + (o[0] + t * d[0]) * kz, py = c->cy - (o[1] + t * d[1]) * kz;
                if (px >= ix - EDGE_EPS && px <= ix + 1 + EDGE_EPS && py >= iy - EDGE_EPS && py <= iy + 1 + EDGE_EPS) {
                    r.t = t;
                    r.idx = (long)id;
                    return r;
                }
            }
        }
        if (tmx < tmy) {
            if (tmx > s1)
                break;
            ix += stx;
            if (ix < 0 || ix >= W)
                break;
            tmx += tdx;
        } else {
            if (tmy > s1)
                break;
            iy += sty;
            if (iy < 0 || iy >= H)
                break;
            tmy += tdy;
        }
    }
    return r;
}

/* Distance from x (inside the ball) to the medium's edge along unit w. */
static double exit_dist(const pctx *c, const double x[3], const double w[3])
{
    if (!isfinite(c->R))
        return INFINITY;
    double b = x[0] * w[0] + x[1] * w[1] + x[2] * w[2];
    double cc = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - c->R * c->R;
    if (cc > 0)
        cc = 0;
    double sq = sqrt(b * b - cc);
    return b > 0 ? -cc / (b + sq) : sq - b;
}

/* A unit vector at cosine mu from unit d, azimuth phi. */
static void rotate(const double d[3], double mu, double phi, double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = d[i];
    nbt__turn(out, mu, sqrt(fmax(0.0, 1.0 - mu * mu)), cos(phi), sin(phi));
}

/* Next-event estimation from the collision x (travelling along d) to a patch chosen by power. */
static void nee(const pctx *c, nbt__rng *r, const double x[3], const double d[3], const double beta[3],
                const bweights *bw, double L[3])
{
    double u = nbt__rng_u(r);
    size_t id;
    if (u < bw->pb) { /* a bright patch by its weight here; u reused, rescaled */
        double t = u / bw->pb * bw->sum, acc = 0.0;
        size_t j = 0;
        for (; j + 1 < c->nb; j++) {
            acc += bw->w[j];
            if (t < acc && bw->w[j] > 0)
                break;
        }
        while (bw->w[j] <= 0) /* rounding at the top end: the last positive weight */
            j--;
        id = c->bidx[j];
    } else {
        if (c->nlights == c->nb)
            return;
        u = (u - bw->pb) / (1.0 - bw->pb);
        size_t lo = 0, hi = c->nlights - c->nb - 1;
        while (lo < hi) { /* first cdf entry > u */
            size_t mid = (lo + hi) / 2;
            if (c->cdf[mid] > u)
                hi = mid;
            else
                lo = mid + 1;
        }
        id = c->lidx[lo];
    }
    size_t ix = id % c->w, iy = id / c->w;
    double Zj = c->Z[id];
    double pu = ((double)ix + nbt__rng_u(r) - c->cx) * c->dth, pv = (c->cy - (double)iy - nbt__rng_u(r)) * c->dth;
    if (!(x[2] < Zj))
        return; /* behind the emitting face */
    double v[3] = {Zj * pu - x[0], Zj * pv - x[1], Zj - x[2]};
    double dist = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    double w[3] = {v[0] / dist, v[1] / dist, v[2] / dist};
    double cosy = w[2];
    double pn = pick_area_pdf(c, bw, id) * dist * dist / cosy; /* solid angle */
    double pp = nbt_phase_eval(c->ph, d[0] * w[0] + d[1] * w[1] + d[2] * w[2]);
    if (!(pp > 0))
        return;
    phit h = trace(c, x, w, dist * (1.0 + 1e-9));
    if (h.idx >= 0 && h.t < dist * (1.0 - 1e-9))
        return;
    double tm = fmin(dist, exit_dist(c, x, w));
    /* beta p Le T / pn times the power heuristic pn^2 / (pn^2 + pp^2) */
    double f = pp * pn / (pn * pn + pp * pp);
    const float *Le = c->rgb + 3 * id;
    for (int ch = 0; ch < 3; ch++)
        L[ch] += beta[ch] * f * Le[ch] * exp(-c->sig[ch] * tm);
}

/* One camera path through the footprint of world pixel (px, py): its scattered radiance. */
static void sample(const pctx *c, nbt__rng *r, size_t px, size_t py, double L[3])
{
    L[0] = L[1] = L[2] = 0.0;
    double u = ((double)px + nbt__rng_u(r) - c->cx) * c->dth, v = (c->cy - (double)py - nbt__rng_u(r)) * c->dth;
    double n = sqrt(u * u + v * v + 1.0);
    double d[3] = {u / n, v / n, 1.0 / n}, x[3] = {0, 0, 0}, beta[3] = {1, 1, 1};
    phit h = trace(c, x, d, INFINITY);
    double teff = fmin(h.t, exit_dist(c, x, d));
    for (unsigned order = 1;; order++) {
        /* a collision forced into [0, teff): channel mixture of truncated exponentials */
        if (!(teff > 0))
            break;
        double F[3], t, pmix = 0.0;
        for (int k = 0; k < c->nact; k++)
            F[k] = -expm1(-c->act[k] * teff);
        int k = (int)(nbt__rng_u(r) * c->nact);
        t = -log1p(-nbt__rng_u(r) * F[k]) / c->act[k];
        if (t >= teff)
            t = teff * (1.0 - 1e-12);
        for (int j = 0; j < c->nact; j++)
            pmix += c->act[j] * exp(-c->act[j] * t) / F[j];
        pmix /= c->nact;
        double bmax = 0.0;
        for (int ch = 0; ch < 3; ch++) {
            beta[ch] *= c->sigs[ch] * exp(-c->sig[ch] * t) / pmix;
            bmax = fmax(bmax, fabs(beta[ch]));
        }
        if (!(bmax > 0))
            break;
        for (int i = 0; i < 3; i++)
            x[i] += t * d[i];
        bweights bw;
        if (c->nee && c->nlights) {
            bright_weights(c, x, d, &bw);
            nee(c, r, x, d, beta, &bw, L);
        }
        /* the phase-sampled direction: its boundary term now, its integral next */
        double mu = nbt__phase_sample_mu(c->ph, nbt__rng_cb, r), wn[3];
        rotate(d, mu, 2.0 * NBT_PI * nbt__rng_u(r), wn);
        h = trace(c, x, wn, INFINITY);
        double te = exit_dist(c, x, wn);
        if (h.idx >= 0) {
            if (wn[2] > 0) { /* the emitting face */
                double wgt = 1.0;
                double pa = c->nee && c->nlights ? pick_area_pdf(c, &bw, (size_t)h.idx) : 0.0;
                if (pa > 0) {
                    double pn = pa * h.t * h.t / wn[2];
                    double pp = nbt_phase_eval(c->ph, mu);
                    wgt = pp * pp / (pp * pp + pn * pn);
                }
                const float *Le = c->rgb + 3 * h.idx;
                double tm = fmin(h.t, te);
                for (int ch = 0; ch < 3; ch++)
                    L[ch] += beta[ch] * wgt * Le[ch] * exp(-c->sig[ch] * tm);
            }
        } else if (isfinite(te)) {
            for (int ch = 0; ch < 3; ch++)
                L[ch] += beta[ch] * c->sky[ch] * exp(-c->sig[ch] * te);
        }
        if (c->max_order && order >= c->max_order)
            break;
        if (order >= RR_ORDER && bmax < RR_BETA) {
            double q = bmax / RR_BETA;
            if (nbt__rng_u(r) >= q)
                break;
            for (int ch = 0; ch < 3; ch++)
                beta[ch] /= q;
        }
        memcpy(d, wn, sizeof d);
        teff = fmin(h.t, te);
    }
}

static nbt_status row_task(size_t j, unsigned thread, void *vp)
{
    (void)thread;
    const pctx *c = vp;
    for (size_t i = 0; i < c->ow; i++) {
        size_t pix = j * c->ow + i;
        nbt__rng r;
        nbt__rng_seed(&r, c->seed, (uint64_t)c->pass * (uint64_t)(c->ow * c->oh) + pix);
        double s[3] = {0, 0, 0}, s2[3] = {0, 0, 0}, L[3];
        for (unsigned long k = 0; k < c->spp; k++) {
            sample(c, &r, c->x0 + i, c->y0 + j, L);
            for (int ch = 0; ch < 3; ch++) {
                s[ch] += L[ch];
                s2[ch] += L[ch] * L[ch];
            }
        }
        for (int ch = 0; ch < 3; ch++) {
            c->sum[3 * pix + ch] += s[ch];
            c->sum2[3 * pix + ch] += s2[ch];
        }
    }
    return NBT_OK;
}

static nbt_status check_args(const nbt_screen_world *W, const nbt_screen_path_medium *m, const nbt_screen_path_opts *o,
                             const double *S)
{
    if (!W || !m || !o || !S)
        return nbt__failv(NBT_EINVAL, "screen path: world, medium, options and S must not be NULL");
    if (W->w == 0 || W->h == 0 || !W->rgb || !W->Z)
        return nbt__failv(NBT_EINVAL, "screen path: empty world (w = %zu, h = %zu) or no colour/depth", W->w, W->h);
    if (!(W->dtheta > 0) || !isfinite(W->dtheta))
        return nbt__failv(NBT_EDOM, "screen path: dtheta = %g must be finite and > 0", W->dtheta);
    if (!isfinite(W->cx) || !isfinite(W->cy))
        return nbt__failv(NBT_EDOM, "screen path: the optical axis (%g, %g) must be finite", W->cx, W->cy);
    if (W->ow == 0 || W->oh == 0 || W->x0 > W->w || W->ow > W->w - W->x0 || W->y0 > W->h || W->oh > W->h - W->y0)
        return nbt__failv(NBT_EINVAL,
                     "screen path: the rendered rectangle %zux%zu at (%zu, %zu) must be non-empty and inside the "
                     "%zux%zu world",
                     W->ow, W->oh, W->x0, W->y0, W->w, W->h);
    for (int ch = 0; ch < 3; ch++) {
        if (!(m->sigma_t[ch] >= 0) || !isfinite(m->sigma_t[ch]))
            return nbt__failv(NBT_EDOM, "screen path: sigma_t[%d] = %g must be finite and >= 0", ch, m->sigma_t[ch]);
        if (!(m->albedo[ch] >= 0 && m->albedo[ch] <= 1))
            return nbt__failv(NBT_EDOM, "screen path: albedo[%d] = %g must lie in [0, 1]", ch, m->albedo[ch]);
        if (!isfinite(m->sky[ch]))
            return nbt__failv(NBT_EDOM, "screen path: sky[%d] = %g must be finite", ch, m->sky[ch]);
    }
    if (!m->phase)
        return nbt__failv(NBT_EINVAL, "screen path: no phase function");
    if (!(m->radius > 0))
        return nbt__failv(NBT_EDOM, "screen path: radius = %g must be > 0 (INFINITY: medium everywhere)", m->radius);
    if (o->spp < 2)
        return nbt__failv(NBT_EDOM, "screen path: spp = %lu must be >= 2 (a standard error needs two samples)", o->spp);
    if (!(o->target_noise >= 0) || !isfinite(o->target_noise))
        return nbt__failv(NBT_EDOM, "screen path: target_noise = %g must be finite and >= 0 (0: one pass)",
                     o->target_noise);
    if (o->target_noise > 0 && o->max_spp && o->max_spp < o->spp)
        return nbt__failv(NBT_EDOM, "screen path: max_spp = %lu must be >= spp = %lu (or 0)", o->max_spp, o->spp);
    for (size_t i = 0; i < W->w * W->h; i++) {
        float z = W->Z[i];
        if (!(z > 0))
            return nbt__failv(NBT_EDOM,
                         "screen path: depth %g at pixel (%zu, %zu) must be > 0 (>= 1e10 or inf: sky)", (double)z,
                         i % W->w, i / W->w);
        for (int ch = 0; ch < 3; ch++)
            if (!isfinite(W->rgb[3 * i + ch]))
                return nbt__failv(NBT_EDOM, "screen path: colour %g at pixel (%zu, %zu) must be finite",
                             (double)W->rgb[3 * i + ch], i % W->w, i / W->w);
    }
    return NBT_OK;
}

static void bin_sums(size_t w, size_t h, const double *A, const double *B, unsigned bin, int noise, double *num,
                     double *den)
{
    size_t b = bin ? bin : 1;
    *num = *den = 0.0;
    for (size_t by = 0; by < h; by += b)
        for (size_t bx = 0; bx < w; bx += b)
            for (int ch = 0; ch < 3; ch++) {
                double sa = 0.0, sb = 0.0;
                for (size_t y = by; y < by + b && y < h; y++)
                    for (size_t x = bx; x < bx + b && x < w; x++) {
                        size_t i = 3 * (y * w + x) + ch;
                        sa += A[i];
                        sb += noise ? B[i] * B[i] : B[i];
                    }
                if (noise) { /* A = S, B = se */
                    *num += sqrt(2.0 / NBT_PI) * sqrt(sb);
                    *den += fabs(sa);
                } else {
                    *num += fabs(sa - sb);
                    *den += fabs(sb);
                }
            }
}

double nbt_screen_binned_noise(size_t w, size_t h, const double *S, const double *se, unsigned bin)
{
    double num, den;
    bin_sums(w, h, S, se, bin, 1, &num, &den);
    return num == 0 ? 0.0 : den == 0 ? INFINITY : num / den;
}

double nbt_screen_binned_rel_l1(size_t w, size_t h, const double *A, const double *B, unsigned bin)
{
    double num, den;
    bin_sums(w, h, A, B, bin, 0, &num, &den);
    return num == 0 ? 0.0 : den == 0 ? INFINITY : num / den;
}

static void finish(const pctx *c, unsigned long n, double *S, double *se)
{
    size_t N = c->ow * c->oh * 3;
    for (size_t i = 0; i < N; i++) {
        double mean = c->sum[i] / (double)n;
        S[i] = mean;
        if (se) {
            double var = (c->sum2[i] - mean * c->sum[i]) / (double)(n - 1);
            se[i] = var > 0 ? sqrt(var / (double)n) : 0.0;
        }
    }
}

nbt_status nbt_screen_path(const nbt_screen_world *W, const nbt_screen_path_medium *m, const nbt_screen_path_opts *o,
                           double *S, double *se, unsigned long *spp_done)
{
    nbt_status st = check_args(W, m, o, S);
    if (st != NBT_OK)
        return st;
    pctx c = {.w = W->w, .h = W->h, .Z = W->Z, .rgb = W->rgb, .dth = W->dtheta, .cx = W->cx, .cy = W->cy,
              .zmin = INFINITY, .zmax = 0.0, .R = m->radius, .ph = m->phase, .max_order = o->max_order,
              .nee = !o->no_nee, .x0 = W->x0, .y0 = W->y0, .ow = W->ow, .oh = W->oh, .spp = o->spp, .seed = o->seed};
    size_t N = c.ow * c.oh * 3, npix = c.w * c.h;
    int scatters = 0;
    for (int ch = 0; ch < 3; ch++) {
        c.sig[ch] = m->sigma_t[ch];
        c.sigs[ch] = m->sigma_t[ch] * m->albedo[ch];
        c.sky[ch] = m->sky[ch];
        if (c.sig[ch] > 0)
            c.act[c.nact++] = c.sig[ch];
        scatters |= c.sigs[ch] > 0;
    }
    if (!scatters) { /* nothing scatters: S = 0 exactly */
        memset(S, 0, N * sizeof *S);
        if (se)
            memset(se, 0, N * sizeof *se);
        if (spp_done)
            *spp_done = 0;
        return NBT_OK;
    }
    c.pick = calloc(npix, sizeof *c.pick);
    c.sum = calloc(N, sizeof *c.sum);
    c.sum2 = calloc(N, sizeof *c.sum2);
    if (!c.pick || !c.sum || !c.sum2) {
        st = nbt__failv(NBT_ENOMEM, "screen path: out of memory");
        goto done;
    }
    double total = 0.0;
    for (size_t i = 0; i < npix; i++) {
        float z = c.Z[i];
        if (!(z < NBT_SCREEN_SKY))
            continue;
        c.zmin = fmin(c.zmin, z);
        c.zmax = fmax(c.zmax, z);
        double lum = fabs(c.rgb[3 * i]) + fabs(c.rgb[3 * i + 1]) + fabs(c.rgb[3 * i + 2]);
        if (lum > 0) {
            c.pick[i] = lum * (double)z * (double)z;
            total += c.pick[i];
            c.nlights++;
        }
    }
    if (c.nlights) {
        c.cdf = malloc(c.nlights * sizeof *c.cdf);
        c.lidx = malloc(c.nlights * sizeof *c.lidx);
        c.bslot = malloc(npix * sizeof *c.bslot);
        if (!c.cdf || !c.lidx || !c.bslot) {
            st = nbt__failv(NBT_ENOMEM, "screen path: out of memory");
            goto done;
        }
        /* the bright list: every light when there are few, else the (at most
         * NB_MAX) most powerful ones among those NB_RATIO times the mean */
        for (size_t i = 0; i < npix; i++)
            c.bslot[i] = -1;
        double thr = c.nlights <= NB_MAX ? 0.0 : NB_RATIO * total / (double)c.nlights, btot = 0.0;
        for (size_t i = 0; i < npix; i++) {
            if (!(c.pick[i] > 0) || c.pick[i] < thr)
                continue;
            size_t j = c.nb;
            if (j == NB_MAX) { /* full: replace the weakest if this one is stronger */
                size_t mw = 0;
                for (size_t k = 1; k < NB_MAX; k++)
                    if (c.pick[c.bidx[k]] < c.pick[c.bidx[mw]])
                        mw = k;
                if (!(c.pick[i] > c.pick[c.bidx[mw]]))
                    continue;
                j = mw;
            } else
                c.nb++;
            c.bidx[j] = i;
        }
        for (int k = 0; k <= NB_TAB; k++) {
            double sh = (double)k / NB_TAB;
            c.ptab[k] = nbt_phase_eval(c.ph, 1.0 - 2.0 * sh * sh) + NB_FLOOR;
        }
        for (size_t j = 0; j < c.nb; j++) {
            size_t i = c.bidx[j], ix = i % c.w, iy = i / c.w;
            double z = c.Z[i];
            c.bslot[i] = (long)j;
            c.blum[j] = c.pick[i] / (z * z);
            c.barea[j] = z * z * c.dth * c.dth;
            c.bpos[j][0] = z * ((double)ix + 0.5 - c.cx) * c.dth;
            c.bpos[j][1] = z * (c.cy - (double)iy - 0.5) * c.dth;
            c.bpos[j][2] = z;
            btot += c.pick[i];
        }
        /* the bright list's share: its power fraction, within [0.25, 0.9] when there is a rest */
        c.pb = c.nb == c.nlights ? 1.0 : c.nb == 0 ? 0.0 : fmin(0.9, fmax(0.25, btot / total));
        double rest = total - btot, acc = 0.0;
        size_t k = 0;
        for (size_t i = 0; i < npix; i++) {
            if (c.bslot[i] >= 0)
                c.pick[i] = 0.0;
            else if (c.pick[i] > 0) {
                acc += c.pick[i];
                c.pick[i] /= rest;
                c.cdf[k] = acc / rest;
                c.lidx[k++] = i;
            }
        }
        if (k)
            c.cdf[k - 1] = 1.0;
    }
    unsigned long maxspp = o->target_noise > 0 ? (o->max_spp ? o->max_spp : 64ul) : o->spp, n = 0;
    double *tmpse = se ? se : malloc(N * sizeof *tmpse);
    if (!tmpse) {
        st = nbt__failv(NBT_ENOMEM, "screen path: out of memory");
        goto done;
    }
    for (c.pass = 0;; c.pass++) {
        st = nbt__parallel_for(c.oh, o->nthreads, row_task, &c);
        if (st != NBT_OK)
            break;
        n += c.spp;
        finish(&c, n, S, tmpse);
        double noise = nbt_screen_binned_noise(c.ow, c.oh, S, tmpse, o->bin ? o->bin : 4);
        if (o->progress)
            fprintf(stderr, "path: pass %lu, %lu spp, binned noise %.3g%%\n", c.pass + 1, n, 100.0 * noise);
        if (!(o->target_noise > 0) || noise <= o->target_noise || n + c.spp > maxspp)
            break;
    }
    if (!se)
        free(tmpse);
    if (st == NBT_OK && spp_done)
        *spp_done = n;
done:
    free(c.pick);
    free(c.sum);
    free(c.sum2);
    free(c.cdf);
    free(c.lidx);
    free(c.bslot);
    return st;
}
