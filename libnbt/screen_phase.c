/* libnbt/screen_phase.c: screen kernels built for a phase function
 * (nbt/screen.h, doc/screenspace.md "Kernels for any phase"): radial
 * shapes as non-negative mixtures of atoms on a fixed grid of scales, the
 * first scattering order exactly for any phase, and the kernel family that
 * adds a fitted model's higher orders. */
#include <config.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/screen.h>
#include "internal.h"
#include "screen_internal.h"

double nbt_screen_slot_scale(int m)
{
    return exp2(0.5 * (double)m);
}

/* ---- atoms' radial masses ---- */

/* mass of a unit atom outside radius a * scale */
double nbt__atom_tail(nbt_atom_shape shape, double a)
{
    if (shape == NBT_ATOM_GAUSS)
        return exp(-0.5 * a * a);
    /* sqrt(2 pi) int_a^inf G = sqrt(2 pi) (phi(a) - a G(a)) */
    return exp(-0.5 * a * a) - sqrt(2.0 * NBT_PI) * a * 0.5 * erfc(a / sqrt(2.0));
}

/* mass of a unit atom inside radius a * scale, accurate for small a */
static double atom_inside(nbt_atom_shape shape, double a)
{
    if (shape == NBT_ATOM_GAUSS)
        return -expm1(-0.5 * a * a);
    return -expm1(-0.5 * a * a) + a * sqrt(0.5 * NBT_PI) * erfc(a / sqrt(2.0));
}

double nbt_screen_atom_mass(nbt_atom_shape shape, double a0, double a1)
{
    if (a0 >= 1.0)
        return nbt__atom_tail(shape, a0) - (isinf(a1) ? 0.0 : nbt__atom_tail(shape, a1));
    return (isinf(a1) ? 1.0 : atom_inside(shape, a1)) - atom_inside(shape, a0);
}

double nbt_screen_shape_mass(const nbt_screen_shape *s, double lo, double hi)
{
    double m = 0;
    for (int k = 0; k < NBT_SCREEN_NSLOTS; k++) {
        double sc = nbt_screen_slot_scale(k + NBT_SCREEN_SLOT_LO);
        if (s->erfc[k] > 0)
            m += s->erfc[k] * nbt_screen_atom_mass(NBT_ATOM_ERFC, lo / sc, hi / sc);
        if (s->gauss[k] > 0)
            m += s->gauss[k] * nbt_screen_atom_mass(NBT_ATOM_GAUSS, lo / sc, hi / sc);
    }
    return m;
}

/* ---- fitting a shape ---- */

nbt_status nbt_screen_shape_fit(size_t nedges, const double *edges, const double *mass, const double *se,
                                int slot_step, nbt_screen_shape *out, double *misfit)
{
    memset(out, 0, sizeof *out);
    if (misfit)
        *misfit = 0;
    if (nedges < 2 || !edges || !mass || (slot_step != 1 && slot_step != 2))
        NBT_FAIL(NBT_EINVAL, "screen shape fit: needs >= 2 edges, the masses and a slot step of 1 or 2");
    size_t nb = nedges + 1;
    double total = 0;
    for (size_t b = 0; b < nb; b++) {
        if (!(mass[b] >= 0) || !isfinite(mass[b]) || (se && !(se[b] >= 0 && isfinite(se[b]))))
            NBT_FAIL(NBT_EDOM, "screen shape fit: masses and errors must be finite and >= 0");
        total += mass[b];
    }
    for (size_t e = 0; e < nedges; e++)
        if (!(edges[e] > 0) || !isfinite(edges[e]) || (e && !(edges[e] > edges[e - 1])))
            NBT_FAIL(NBT_EDOM, "screen shape fit: edges must be finite, > 0 and increasing");
    if (!(total > 0))
        return NBT_OK;
    /* the bins that hold the mass: the core below the first, and the tail beyond
     * the last, each hold at most 1e-7 of it and are merged into one bin each */
    size_t b0 = 0, b1 = nb - 1;
    double c = 0;
    while (b0 + 1 < nb && c + mass[b0] <= 1e-7 * total)
        c += mass[b0++];
    c = 0;
    while (b1 > b0 && c + mass[b1] <= 1e-7 * total)
        c += mass[b1--];
    /* rows: bin b0 taken from radius 0 (the core folded in), bin b1 to infinity (the tail), then the total */
    double rlo = b0 > 0 ? edges[b0 - 1] : edges[0] / 2, rhi = b1 < nedges ? edges[b1] : edges[nedges - 1] * 2;
    int m0 = (int)floor(2.0 * log2(rlo / 4.0)), m1 = (int)ceil(2.0 * log2(rhi * 4.0));
    if (m0 < NBT_SCREEN_SLOT_LO)
        m0 = NBT_SCREEN_SLOT_LO;
    if (m1 > NBT_SCREEN_SLOT_HI)
        m1 = NBT_SCREEN_SLOT_HI;
    if (slot_step == 2) { /* even slots only (whole octaves) */
        m0 += (m0 & 1) ? 1 : 0;
        m1 -= (m1 & 1) ? 1 : 0;
    }
    size_t ns = m1 >= m0 ? (size_t)((m1 - m0) / slot_step + 1) : 0, ncol = 2 * ns, nrow = b1 - b0 + 2;
    if (ns == 0)
        NBT_FAIL(NBT_EDOM, "screen shape fit: the masses lie outside the slots' scales");
    double *A = malloc(nrow * ncol * sizeof *A), *rhs = malloc(nrow * sizeof *rhs), *x = malloc(ncol * sizeof *x),
           *wr = malloc(nrow * sizeof *wr);
    if (!A || !rhs || !x || !wr) {
        free(A);
        free(rhs);
        free(x);
        free(wr);
        NBT_FAIL(NBT_ENOMEM, "screen shape fit: out of memory");
    }
    for (size_t i = 0; i + 1 < nrow; i++) {
        size_t b = b0 + i;
        double lo = i == 0 ? 0.0 : edges[b - 1], hi = b == b1 ? INFINITY : edges[b], m = 0;
        if (i == 0 && b == b1)
            m = total;
        else if (i == 0)
            for (size_t k = 0; k <= b0; k++)
                m += mass[k];
        else if (b == b1)
            for (size_t k = b1; k < nb; k++)
                m += mass[k];
        else
            m = mass[b];
        /* relative accuracy per bin, down to a floor; counts also by their noise */
        double s = m + 1e-4 * total;
        if (se)
            s = sqrt(s * s * 1e-4 + se[b] * se[b]) + 1e-6 * total;
        wr[i] = 1.0 / s;
        rhs[i] = m * wr[i];
        for (size_t j = 0; j < ns; j++) {
            double sc = nbt_screen_slot_scale(m0 + (int)j * slot_step);
            A[i * ncol + 2 * j] = nbt_screen_atom_mass(NBT_ATOM_ERFC, lo / sc, hi / sc) * wr[i];
            A[i * ncol + 2 * j + 1] = nbt_screen_atom_mass(NBT_ATOM_GAUSS, lo / sc, hi / sc) * wr[i];
        }
    }
    /* the total, heavily weighted: every atom has unit mass */
    size_t t = nrow - 1;
    wr[t] = 1e3 / total;
    rhs[t] = total * wr[t];
    for (size_t j = 0; j < ncol; j++)
        A[t * ncol + j] = wr[t];
    nbt_status st = nbt__nnls(A, nrow, ncol, rhs, x, NULL);
    if (st == NBT_OK) {
        for (size_t j = 0; j < ns; j++) {
            size_t s = (size_t)(m0 + (int)j * slot_step - NBT_SCREEN_SLOT_LO);
            out->erfc[s] = x[2 * j];
            out->gauss[s] = x[2 * j + 1];
        }
        if (misfit) {
            double l1 = 0;
            for (size_t i = 0; i + 1 < nrow; i++) {
                double f = 0;
                for (size_t j = 0; j < ncol; j++)
                    f += A[i * ncol + j] * x[j];
                l1 += fabs(f - rhs[i]) / wr[i];
            }
            *misfit = l1 / total;
        }
    }
    free(A);
    free(rhs);
    free(x);
    free(wr);
    return st;
}

/* ---- the first order, exactly ---- */

/* theta panels, SS_GL nodes each: geometric by sqrt 2 from SS_TH0 up to
 * pi/4 (the phase's forward peak), and from pi/4 towards pi/2 down to
 * SS_TH0 short of it: the oblique leg's attenuation 1 - e^{-tau (sec th - 1)}
 * turns over within ~tau of pi/2, which one panel of 8 nodes over
 * [1.11, pi/2] missed by up to 1e-3 of the mass at tau = 0.003 */
#define SS_TH0 1e-7
#define SS_GL 8
#define SS_MAXP 100

typedef struct {
    size_t np, nn;               /* panels, nodes (np * SS_GL) */
    double edge[SS_MAXP + 1];
    double th[SS_MAXP * SS_GL], wf[SS_MAXP * SS_GL], k[SS_MAXP * SS_GL], cot[SS_MAXP * SS_GL];
    double gx[SS_GL], gw[SS_GL];
    double p1;                   /* p(mu = 1), for the sliver [0, SS_TH0] */
} ss_rule;

/* k = sec(theta) - 1 without cancellation */
static double sec_m1(double th)
{
    double s = sin(0.5 * th);
    return 2.0 * s * s / cos(th);
}

static void ss_rule_init(ss_rule *r, const nbt_phase *p)
{
    nbt__gl_nodes(SS_GL, r->gx, r->gw);
    /* half the edges up to pi/4, mirrored about pi/4 (the sliver within SS_TH0
     * of pi/2 holds ~p SS_TH0^2 / 2 of the mass: left out) */
    size_t h = 0;
    double lo[SS_MAXP / 2 + 1];
    lo[0] = SS_TH0;
    while (lo[h] * sqrt(2.0) < 0.5 * NBT_PI_2 && h + 1 < SS_MAXP / 2) {
        lo[h + 1] = lo[h] * sqrt(2.0);
        h++;
    }
    r->np = 2 * h + 1;
    for (size_t i = 0; i <= h; i++) {
        r->edge[i] = lo[i];
        r->edge[r->np - i] = NBT_PI_2 - lo[i];
    }
    r->nn = r->np * SS_GL;
    for (size_t i = 0; i < r->np; i++) {
        double a = r->edge[i], b = r->edge[i + 1];
        for (int j = 0; j < SS_GL; j++) {
            size_t n = i * SS_GL + (size_t)j;
            double th = 0.5 * (a + b) + 0.5 * (b - a) * r->gx[j];
            r->th[n] = th;
            r->wf[n] = 0.5 * (b - a) * r->gw[j] * 2.0 * NBT_PI * nbt__phase_eval_cs(p, cos(th), sin(th)) * sin(th);
            r->k[n] = sec_m1(th);
            r->cot[n] = cos(th) / sin(th);
        }
    }
    r->p1 = nbt_phase_eval(p, 1.0);
}

/* (1 - e^{-U k}) / k, U at k -> 0 */
static double ss_E(double U, double k)
{
    double x = U * k;
    return x > 1e-12 ? -expm1(-x) / k : U;
}

/* C(tau, rho): the first order's mass inside radius rho tau on the plane at
 * optical depth tau, per unit albedo (sigma_t = 1): a light path goes
 * straight to depth s, turns by theta and meets the wall at u = tau - s
 * further, r = u tan(theta) off the axis, so
 *   C = e^{-tau} int_0^{pi/2} 2 pi p(cos th) sin th (1 - e^{-U k})/k dth,
 * k = sec th - 1 (the longer oblique leg), U = min(tau, rho tau cot th). */
static double ss_cumulative(const ss_rule *r, const nbt_phase *p, double tau, double rho)
{
    double ts = isinf(rho) ? NBT_PI_2 : atan(rho), s = 0;
    /* the sliver below SS_TH0 (p ~ p(1), theta small) */
    s += 2.0 * NBT_PI * r->p1 * tau * 0.5 * SS_TH0 * SS_TH0 * fmin(1.0, rho / SS_TH0);
    for (size_t i = 0; i < r->np; i++) {
        double a = r->edge[i], b = r->edge[i + 1];
        if (ts > a && ts < b) { /* the kink of min(): split the panel there */
            for (int h = 0; h < 2; h++) {
                double lo = h ? ts : a, hi = h ? b : ts;
                for (int j = 0; j < SS_GL; j++) {
                    double th = 0.5 * (lo + hi) + 0.5 * (hi - lo) * r->gx[j];
                    double wf = 0.5 * (hi - lo) * r->gw[j] * 2.0 * NBT_PI * nbt__phase_eval_cs(p, cos(th), sin(th)) *
                                sin(th);
                    double U = h ? tau * rho * cos(th) / sin(th) : tau;
                    s += wf * ss_E(U, sec_m1(th));
                }
            }
            continue;
        }
        for (int j = 0; j < SS_GL; j++) {
            size_t n = i * SS_GL + (size_t)j;
            double U = r->th[n] < ts ? tau : tau * rho * r->cot[n];
            s += r->wf[n] * ss_E(U, r->k[n]);
        }
    }
    return exp(-tau) * s;
}

/* radii of the first order's fit: rho = 2^(i/4), i in [SS_RLO, SS_RHI) */
#define SS_RLO (-76)
#define SS_RHI 48
#define SS_NR (SS_RHI - SS_RLO)

/* the first order's shape at tau (albedo 1), normalised to unit mass */
static nbt_status ss_shape(const ss_rule *r, const nbt_phase *p, double tau, nbt_screen_shape *sh)
{
    double e[SS_NR], m[SS_NR + 1], prev = 0;
    double M = ss_cumulative(r, p, tau, INFINITY);
    for (int i = 0; i < SS_NR; i++) {
        e[i] = exp2(0.25 * (double)(SS_RLO + i));
        double C = ss_cumulative(r, p, tau, e[i]);
        m[i] = fmax(C - prev, 0.0);
        prev = fmax(C, prev);
    }
    m[SS_NR] = fmax(M - prev, 0.0);
    nbt_status st = nbt_screen_shape_fit(SS_NR, e, m, NULL, 1, sh, NULL);
    if (st != NBT_OK)
        return st;
    double t = 0;
    for (int s = 0; s < NBT_SCREEN_NSLOTS; s++)
        t += sh->erfc[s] + sh->gauss[s];
    for (int s = 0; s < NBT_SCREEN_NSLOTS && t > 0; s++) {
        sh->erfc[s] /= t;
        sh->gauss[s] /= t;
    }
    return NBT_OK;
}

/* ---- the kernel family for a phase ---- */

/* first-order shapes at tau = 2^(i/4), i in [PK_ILO, PK_IHI], computed on first use */
#define PK_ILO (-48)
#define PK_IHI 28
#define PK_N (PK_IHI - PK_ILO + 1)

struct nbt__phase_kern {
    const nbt_phase *p;
    double sigma_t, albedo;
    nbt_screen_geometry geo;
    const nbt_screen_model *model; /* NULL: the first order only */
    double param;                  /* the model's family parameter of p */
    ss_rule rule;
    pthread_mutex_t lock;
    atomic_uchar ready[PK_N];
    nbt_screen_shape shape[PK_N];
};

nbt__phase_kern *nbt__phase_kern_alloc(const nbt_phase *p, double sigma_t, double albedo, nbt_screen_geometry geo,
                                       const nbt_screen_model *model)
{
    if (!p) {
        nbt__fail(NBT_EINVAL, "screen: a kernel for a phase needs the phase");
        return NULL;
    }
    if (!(sigma_t > 0) || !isfinite(sigma_t) || !(albedo >= 0 && albedo <= 1)) {
        nbt__fail(NBT_EDOM, "screen: a kernel for a phase needs sigma_t > 0 (finite) and albedo in [0, 1]");
        return NULL;
    }
    if (geo != NBT_SCREEN_INSIDE && geo != NBT_SCREEN_ENTERING) {
        nbt__fail(NBT_EINVAL, "screen: unknown geometry");
        return NULL;
    }
    double param = 0;
    if (model && nbt__screen_model_param(model, p, geo, &param) != NBT_OK)
        return NULL;
    nbt__phase_kern *k = calloc(1, sizeof *k);
    if (!k) {
        nbt__fail(NBT_ENOMEM, "screen: out of memory");
        return NULL;
    }
    k->p = p;
    k->sigma_t = sigma_t;
    k->albedo = albedo;
    k->geo = geo;
    k->model = model;
    k->param = param;
    ss_rule_init(&k->rule, p);
    pthread_mutex_init(&k->lock, NULL);
    for (int i = 0; i < PK_N; i++)
        atomic_init(&k->ready[i], 0);
    return k;
}

void nbt__phase_kern_free(nbt__phase_kern *k)
{
    if (!k)
        return;
    pthread_mutex_destroy(&k->lock);
    free(k);
}

static nbt_status node_shape(nbt__phase_kern *k, int i, const nbt_screen_shape **sh)
{
    int j = i - PK_ILO;
    nbt_status st = NBT_OK;
    if (!atomic_load_explicit(&k->ready[j], memory_order_acquire)) {
        pthread_mutex_lock(&k->lock);
        if (!atomic_load_explicit(&k->ready[j], memory_order_relaxed)) {
            st = ss_shape(&k->rule, k->p, exp2(0.25 * (double)i), &k->shape[j]);
            if (st == NBT_OK)
                atomic_store_explicit(&k->ready[j], 1, memory_order_release);
        }
        pthread_mutex_unlock(&k->lock);
    }
    *sh = &k->shape[j];
    return st;
}

/* the first order's mass at depth D (fraction of the source's radiance) */
double nbt__phase_kern_first_mass(const nbt__phase_kern *k, double D)
{
    return k->albedo * ss_cumulative(&k->rule, k->p, k->sigma_t * D, INFINITY);
}

nbt_status nbt__phase_kern_eval(nbt__phase_kern *k, double D, nbt_screen_kern *o)
{
    double tau = k->sigma_t * D, li = 4.0 * log2(tau);
    int i = (int)floor(li);
    double f = li - i;
    if (i < PK_ILO) { /* below the grid the shape no longer changes (no attenuation): hold it */
        i = PK_ILO;
        f = 0;
    } else if (i >= PK_IHI) {
        i = PK_IHI - 1;
        f = 1;
    }
    const nbt_screen_shape *a, *b;
    nbt_status st = node_shape(k, i, &a);
    if (st == NBT_OK)
        st = node_shape(k, i + 1, &b);
    if (st != NBT_OK)
        return st;
    double M1 = nbt__phase_kern_first_mass(k, D);
    nbt_screen_shape tot;
    for (int s = 0; s < NBT_SCREEN_NSLOTS; s++) {
        tot.erfc[s] = M1 * ((1 - f) * a->erfc[s] + f * b->erfc[s]);
        tot.gauss[s] = M1 * ((1 - f) * a->gauss[s] + f * b->gauss[s]);
    }
    if (k->model) {
        nbt_screen_shape hi;
        if ((st = nbt__screen_model_eval(k->model, k->param, k->geo, k->albedo, tau, &hi)) != NBT_OK)
            return st;
        for (int s = 0; s < NBT_SCREEN_NSLOTS; s++) {
            tot.erfc[s] += hi.erfc[s];
            tot.gauss[s] += hi.gauss[s];
        }
    }
    o->T = exp(-tau);
    o->n = 0;
    for (int s = 0; s < NBT_SCREEN_NSLOTS; s++) {
        double sc = nbt_screen_slot_scale(s + NBT_SCREEN_SLOT_LO) * D;
        nbt__add_atom(o, NBT_ATOM_ERFC, tot.erfc[s], sc);
        nbt__add_atom(o, NBT_ATOM_GAUSS, tot.gauss[s], sc);
    }
    return NBT_OK;
}
