/* tests/test_screen_path.c: the path-traced screen reference (nbt/screen_path.h)
 * against independent quadrature of the first scattering order, against
 * photon counting (nbt_mc_kernel_run) for all orders, against itself without
 * next-event estimation, and its own error estimate against the spread of
 * independent runs. Tolerances are 4.5 standard errors plus a stated bias
 * bound. */
#include <config.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/nbt.h>
#include "testutil.h"

static const double GL4x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
static const double GL4w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};

/* ---- a world ---- */
typedef struct {
    nbt_screen_world W;
    float *rgb, *Z;
} world;

static world world_alloc(size_t w, size_t h, double dtheta, double cx, double cy)
{
    world r;
    r.rgb = calloc(w * h * 3, sizeof(float));
    r.Z = calloc(w * h, sizeof(float));
    r.W = (nbt_screen_world){.w = w, .h = h, .rgb = r.rgb, .Z = r.Z, .dtheta = dtheta, .cx = cx, .cy = cy,
                             .x0 = 0, .y0 = 0, .ow = w, .oh = h};
    return r;
}

static void world_fill(world *r, float Z, const float c[3])
{
    for (size_t i = 0; i < r->W.w * r->W.h; i++) {
        r->Z[i] = Z;
        for (int ch = 0; ch < 3; ch++)
            r->rgb[3 * i + ch] = c[ch];
    }
}

static void world_free(world *r)
{
    free(r->rgb);
    free(r->Z);
}

static void dir_of(const nbt_screen_world *W, double px, double py, double d[3])
{
    double u = (px - W->cx) * W->dtheta, v = (W->cy - py) * W->dtheta, n = sqrt(1 + u * u + v * v);
    d[0] = u / n;
    d[1] = v / n;
    d[2] = 1 / n;
}

/* ---- first order from a uniform infinite wall at depth Z (radiance 1) ----
 * S1(d) = sigma_s int_{w_z > 0} p(d.w) int_0^{t_w} e^{-sigma t} e^{-sigma (Z - t d_z)/w_z} dt dw,
 * the t integral in closed form: e^{-sigma Z/w_z} (1 - e^{-a t_w})/a,
 * a = sigma (1 - d_z/w_z), t_w = Z/d_z. d in the xz plane (symmetry), w at
 * polar angle th from +z and azimuth ph. */
typedef struct {
    const nbt_phase *p;
    double sig[3], sigs[3], Z, st, ct, th;
    nbt_quad_ws *ws;
} wall_ctx;

static int wall_phi(double ph, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    wall_ctx *c = vp;
    double cw = cos(c->th), sw = sin(c->th), tw = c->Z / c->ct;
    double pp = nbt_phase_eval(c->p, c->st * sw * cos(ph) + c->ct * cw);
    for (int ch = 0; ch < 3; ch++) {
        double a = c->sig[ch] * (1 - c->ct / cw), x = a * tw, E;
        if (fabs(x) < 1e-4)
            E = exp(-c->sig[ch] * c->Z / cw) * tw * (1 - x / 2 + x * x / 6);
        else
            E = (exp(-c->sig[ch] * c->Z / cw) - exp(-c->sig[ch] * tw)) / a;
        f[ch] = 2 * c->sigs[ch] * pp * sw * E; /* 2: azimuth over [0, pi] */
    }
    return 0;
}

static int wall_theta(double th, void *vp, unsigned fdim, double *f)
{
    wall_ctx *c = vp;
    c->th = th;
    double e[3];
    if (th >= M_PI / 2) {
        f[0] = f[1] = f[2] = 0;
        return 0;
    }
    nbt_status st = nbt_quad_gk(c->ws, wall_phi, c, fdim, 0, M_PI, 1e-14, 1e-9, f, e);
    return st != NBT_OK && st != NBT_ETOL;
}

static void wall_first(const nbt_phase *p, const double sig[3], const double alb[3], double Z, const double d[3],
                       double out[3])
{
    nbt_quad_ws *w1 = nbt_quad_ws_alloc(3, 2000), *w2 = nbt_quad_ws_alloc(3, 2000);
    wall_ctx c = {.p = p, .Z = Z, .ct = d[2], .st = sqrt(d[0] * d[0] + d[1] * d[1]), .ws = w2};
    for (int ch = 0; ch < 3; ch++) {
        c.sig[ch] = sig[ch];
        c.sigs[ch] = sig[ch] * alb[ch];
    }
    double e[3], thd = atan2(c.st, c.ct);
    nbt_quad_gk_pts(w1, wall_theta, &c, 3, 0, M_PI / 2, &thd, thd > 0 ? 1 : 0, 1e-14, 1e-9, out, e);
    nbt_quad_ws_free(w1);
    nbt_quad_ws_free(w2);
}

/* ---- first order from one lamp patch (radiance Le, depth Zl, footprint
 * [u0,u1] x [v0,v1]) for a view ray d: int_0^{t_l} dt sigma_s e^{-sigma t}
 * int_lamp p(d.w) Le e^{-sigma s} cos_y / s^2 dA, t_l where the ray reaches
 * the lamp's plane (beyond it the lamp shows its back) ---- */
typedef struct {
    const nbt_phase *p;
    double sig[3], sigs[3], Le[3], Zl, u0, u1, v0, v1, d[3], t, u;
    nbt_quad_ws *wu, *wv;
} lamp_ctx;

static int lamp_v(double v, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    lamp_ctx *c = vp;
    double x[3] = {c->t * c->d[0], c->t * c->d[1], c->t * c->d[2]};
    double y[3] = {c->Zl * c->u, c->Zl * v, c->Zl};
    double r[3] = {y[0] - x[0], y[1] - x[1], y[2] - x[2]}, s = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    double mu = (r[0] * c->d[0] + r[1] * c->d[1] + r[2] * c->d[2]) / s, cy = r[2] / s;
    double g = nbt_phase_eval(c->p, mu) * cy / (s * s) * c->Zl * c->Zl;
    for (int ch = 0; ch < 3; ch++)
        f[ch] = c->sigs[ch] * exp(-c->sig[ch] * (c->t + s)) * g * c->Le[ch];
    return 0;
}

static int lamp_u(double u, void *vp, unsigned fdim, double *f)
{
    lamp_ctx *c = vp;
    c->u = u;
    double e[3];
    nbt_status st = nbt_quad_gk(c->wv, lamp_v, c, fdim, c->v0, c->v1, 1e-15, 1e-9, f, e);
    return st != NBT_OK && st != NBT_ETOL;
}

static int lamp_t(double t, void *vp, unsigned fdim, double *f)
{
    lamp_ctx *c = vp;
    c->t = t;
    double e[3];
    nbt_status st = nbt_quad_gk(c->wu, lamp_u, c, fdim, c->u0, c->u1, 1e-15, 1e-9, f, e);
    return st != NBT_OK && st != NBT_ETOL;
}

static void lamp_first(lamp_ctx *c, const double d[3], double out[3])
{
    nbt_quad_ws *wt = nbt_quad_ws_alloc(3, 2000);
    memcpy(c->d, d, sizeof c->d);
    double e[3];
    nbt_quad_gk(wt, lamp_t, c, 3, 0, c->Zl / d[2], 1e-15, 1e-9, out, e);
    nbt_quad_ws_free(wt);
}

/* ---- 1. nothing scatters: exactly zero ---- */
static void test_zero(void)
{
    world r = world_alloc(9, 5, 0.1, 4.3, 2.2);
    world_fill(&r, 2.0f, (const float[3]){1, 2, 3});
    r.Z[7] = INFINITY;
    nbt_phase *p = nbt_phase_hg(0.7);
    nbt_screen_path_medium m = {.sigma_t = {1, 1, 1}, .albedo = {0, 0, 0}, .phase = p, .radius = INFINITY};
    nbt_screen_path_opts o = {.spp = 8, .seed = 1, .nthreads = 1};
    double S[9 * 5 * 3], se[9 * 5 * 3], mx = 0;
    t_true(nbt_screen_path(&r.W, &m, &o, S, se, NULL) == NBT_OK, "albedo 0 runs");
    for (size_t i = 0; i < 9 * 5 * 3; i++)
        mx = fmax(mx, fabs(S[i]) + se[i]);
    t_true(mx == 0, "albedo 0: S = 0 exactly (max %g)", mx);
    m = (nbt_screen_path_medium){.sigma_t = {0, 0, 0}, .albedo = {1, 1, 1}, .phase = p, .radius = 3.0,
                                 .sky = {1, 1, 1}};
    t_true(nbt_screen_path(&r.W, &m, &o, S, se, NULL) == NBT_OK, "sigma_t 0 runs");
    mx = 0;
    for (size_t i = 0; i < 9 * 5 * 3; i++)
        mx = fmax(mx, fabs(S[i]) + se[i]);
    t_true(mx == 0, "sigma_t 0: S = 0 exactly (max %g)", mx);
    /* one channel without scattering stays exactly 0 (its sum starts at 0), the others do not; each channel in turn */
    for (int z = 0; z < 3; z++) {
        m = (nbt_screen_path_medium){.sigma_t = {1, 0.5, 2}, .albedo = {0.9, 0.7, 0.5}, .phase = p, .radius = INFINITY};
        m.albedo[z] = 0;
        nbt_screen_path(&r.W, &m, &o, S, se, NULL);
        double zc = 0, rest = 0;
        for (size_t i = 0; i < 9 * 5; i++)
            for (int c = 0; c < 3; c++)
                if (c == z)
                    zc = fmax(zc, fabs(S[3 * i + c]) + se[3 * i + c]);
                else
                    rest += S[3 * i + c];
        t_true(zc == 0 && rest > 0, "albedo 0 in channel %d only: it is exactly 0 (%g), the others > 0 (%g)", z, zc, rest);
    }
    nbt_phase_free(p);
    world_free(&r);
}

/* ---- bad input: one message, status, S untouched ---- */
static void test_bad(void)
{
    world r = world_alloc(6, 4, 0.1, 3, 2);
    world_fill(&r, 1.0f, (const float[3]){1, 1, 1});
    nbt_phase *p = nbt_phase_iso();
    nbt_screen_path_medium m = {.sigma_t = {1, 1, 1}, .albedo = {0.5, 0.5, 0.5}, .phase = p, .radius = INFINITY};
    nbt_screen_path_opts o = {.spp = 4, .seed = 1, .nthreads = 1};
    double S[6 * 4 * 3];
    for (size_t i = 0; i < 72; i++)
        S[i] = 42;
    r.W.dtheta = 0;
    t_true(nbt_screen_path(&r.W, &m, &o, S, NULL, NULL) == NBT_EDOM, "dtheta 0 rejected");
    r.W.dtheta = 0.1;
    r.W.x0 = 2; /* 2 + 6 > 6 */
    t_true(nbt_screen_path(&r.W, &m, &o, S, NULL, NULL) == NBT_EINVAL, "rectangle outside the world rejected");
    r.W.x0 = 0;
    r.Z[5] = -1;
    t_true(nbt_screen_path(&r.W, &m, &o, S, NULL, NULL) == NBT_EDOM, "negative depth rejected");
    r.Z[5] = 1;
    m.albedo[1] = 1.5;
    t_true(nbt_screen_path(&r.W, &m, &o, S, NULL, NULL) == NBT_EDOM, "albedo 1.5 rejected");
    m.albedo[1] = 0.5;
    o.spp = 1;
    t_true(nbt_screen_path(&r.W, &m, &o, S, NULL, NULL) == NBT_EDOM, "spp 1 rejected");
    int same = 1;
    for (size_t i = 0; i < 72; i++)
        same &= S[i] == 42;
    t_true(same, "S untouched after bad input");
    nbt_phase_free(p);
    world_free(&r);
}

/* the path tracer on the 1 x 1 display window at world pixel (x, y) */
static void path_pixel(world *r, const nbt_screen_path_medium *m, nbt_screen_path_opts *o, size_t x, size_t y,
                       double S[3], double se[3])
{
    r->W.x0 = x;
    r->W.y0 = y;
    r->W.ow = r->W.oh = 1;
    S[0] = S[1] = S[2] = NAN; /* a refusal must not leave a previous pixel's values */
    nbt_status st = nbt_screen_path(&r->W, m, o, S, se, NULL);
    if (st != NBT_OK)
        t_true(0, "path at pixel (%zu, %zu): status %d", x, y, st);
}

/* ---- 2. first order against quadrature: a uniform wall, a lamp ---- */
static void test_first_wall(void)
{
    /* non-square 240 x 160 world, axis off centre; it spans u in [-12.4, 17.6],
     * v in [-9.9, 10.1]: light from beyond crosses >= 9 Z of medium, < 1e-4 */
    world r = world_alloc(240, 160, 0.125, 99.3, 79.4);
    const float L[3] = {1.0f, 0.5f, 2.0f};
    const double Z = 1.3, sig[3] = {0.8, 1.0, 1.4}, alb[3] = {0.9, 0.8, 0.7};
    world_fill(&r, (float)Z, L);
    const double gs[2] = {0.8, -0.3};
    const size_t px[2][2] = {{99, 79}, {80, 66}}; /* the axis pixel; one 19 px left and 13 px up */
    for (int ig = 0; ig < 2; ig++) {
        nbt_phase *p = nbt_phase_hg(gs[ig]);
        nbt_screen_path_medium m = {.sigma_t = {sig[0], sig[1], sig[2]}, .albedo = {alb[0], alb[1], alb[2]},
                                    .phase = p, .radius = INFINITY};
        nbt_screen_path_opts o = {.spp = 30000, .seed = 11 + ig, .nthreads = 0, .max_order = 1};
        for (int k = 0; k < 2; k++) {
            double S[3], se[3], ref[3] = {0, 0, 0}, d[3], v[3];
            path_pixel(&r, &m, &o, px[k][0], px[k][1], S, se);
            /* the footprint average by 4 x 4 Gauss-Legendre */
            for (int i = 0; i < 4; i++)
                for (int j = 0; j < 4; j++) {
                    dir_of(&r.W, px[k][0] + 0.5 + 0.5 * GL4x[i], px[k][1] + 0.5 + 0.5 * GL4x[j], d);
                    wall_first(p, sig, alb, Z, d, v);
                    for (int ch = 0; ch < 3; ch++)
                        ref[ch] += 0.25 * GL4w[i] * GL4w[j] * v[ch] * L[ch];
                }
            for (int ch = 0; ch < 3; ch++)
                t_abs(S[ch], ref[ch], 4.5 * se[ch] + 2e-4 * ref[ch],
                      "first order, wall, g %g, pixel (%zu, %zu), channel %d: %.5g +- %.2g vs %.5g", gs[ig],
                      px[k][0], px[k][1], ch, S[ch], se[ch], ref[ch]);
        }
        nbt_phase_free(p);
    }
    world_free(&r);
}

/* a lamp patch at world pixel (lx, ly), depth Zl, radiance Le, placed in r,
 * and its first-order quadrature context for the medium (sig, alb, p) */
static lamp_ctx lamp_place(world *r, const nbt_phase *p, const double sig[3], const double alb[3], size_t lx,
                           size_t ly, float Zl, const float Le[3])
{
    size_t li = ly * r->W.w + lx;
    r->Z[li] = Zl;
    memcpy(r->rgb + 3 * li, Le, 3 * sizeof *Le);
    lamp_ctx c = {.p = p, .Zl = Zl, .u0 = (lx - r->W.cx) * r->W.dtheta, .u1 = (lx + 1 - r->W.cx) * r->W.dtheta,
                  .v0 = (r->W.cy - ly - 1) * r->W.dtheta, .v1 = (r->W.cy - ly) * r->W.dtheta,
                  .wu = nbt_quad_ws_alloc(3, 2000), .wv = nbt_quad_ws_alloc(3, 2000)};
    for (int ch = 0; ch < 3; ch++) {
        c.sig[ch] = sig[ch];
        c.sigs[ch] = sig[ch] * alb[ch];
        c.Le[ch] = Le[ch];
    }
    return c;
}

/* the first order of nl lamps averaged over pixel (x, y)'s footprint by 4 x 4 Gauss-Legendre */
static void lamps_footprint(const world *r, lamp_ctx *c, int nl, size_t x, size_t y, double ref[3])
{
    double d[3], v[3];
    ref[0] = ref[1] = ref[2] = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            dir_of(&r->W, x + 0.5 + 0.5 * GL4x[i], y + 0.5 + 0.5 * GL4x[j], d);
            for (int l = 0; l < nl; l++) {
                lamp_first(&c[l], d, v);
                for (int ch = 0; ch < 3; ch++)
                    ref[ch] += 0.25 * GL4w[i] * GL4w[j] * v[ch];
            }
        }
}

static void test_first_lamp(void)
{
    /* one lamp patch at Z 1 in front of a black wall at Z 2.5; pixels beside
     * it, above-left and below-right: a v axis upside down, a lost emitter
     * cosine or half the azimuths show here */
    world r = world_alloc(50, 36, 0.04, 21.6, 15.3);
    world_fill(&r, 2.5f, (const float[3]){0, 0, 0});
    const size_t lx = 27, ly = 12;
    nbt_phase *p = nbt_phase_hg(0.5);
    const double sig[3] = {0.5, 0.7, 0.9}, alb[3] = {0.95, 0.9, 0.8};
    lamp_ctx c = lamp_place(&r, p, sig, alb, lx, ly, 1.0f, (const float[3]){5.0f, 2.0f, 1.0f});
    nbt_screen_path_medium m = {.sigma_t = {sig[0], sig[1], sig[2]}, .albedo = {alb[0], alb[1], alb[2]},
                                .phase = p, .radius = INFINITY};
    nbt_screen_path_opts o = {.spp = 20000, .seed = 5, .nthreads = 0, .max_order = 1};
    const long off[3][2] = {{-3, -2}, {2, 1}, {0, 4}};
    for (int k = 0; k < 3; k++) {
        size_t x = lx + off[k][0], y = ly + off[k][1];
        double S[3], se[3], ref[3];
        path_pixel(&r, &m, &o, x, y, S, se);
        lamps_footprint(&r, &c, 1, x, y, ref);
        for (int ch = 0; ch < 3; ch++)
            t_abs(S[ch], ref[ch], 4.5 * se[ch] + 1e-3 * ref[ch],
                  "first order, lamp, pixel offset (%ld, %ld), channel %d: %.5g +- %.2g vs %.5g", off[k][0],
                  off[k][1], ch, S[ch], se[ch], ref[ch]);
    }
    nbt_quad_ws_free(c.wu);
    nbt_quad_ws_free(c.wv);
    nbt_phase_free(p);
    world_free(&r);
}

/* two lamps (at different depths, different colours): next-event estimation picks a lamp by its
 * weight; a pick that favours the first lamp while dividing by the true weights biases both pixels
 * (one beside each lamp) against the sum of the two lamps' first-order quadratures */
static void test_first_two_lamps(void)
{
    world r = world_alloc(50, 36, 0.04, 21.6, 15.3);
    world_fill(&r, 2.5f, (const float[3]){0, 0, 0});
    nbt_phase *p = nbt_phase_hg(0.5);
    const double sig[3] = {0.5, 0.7, 0.9}, alb[3] = {0.95, 0.9, 0.8};
    lamp_ctx c[2] = {lamp_place(&r, p, sig, alb, 27, 12, 1.0f, (const float[3]){5.0f, 2.0f, 1.0f}),
                     lamp_place(&r, p, sig, alb, 14, 22, 1.4f, (const float[3]){1.0f, 3.0f, 4.0f})};
    nbt_screen_path_medium m = {.sigma_t = {sig[0], sig[1], sig[2]}, .albedo = {alb[0], alb[1], alb[2]},
                                .phase = p, .radius = INFINITY};
    nbt_screen_path_opts o = {.spp = 20000, .seed = 9, .nthreads = 0, .max_order = 1};
    const size_t px[2][2] = {{25, 10}, {16, 24}};
    for (int k = 0; k < 2; k++) {
        double S[3], se[3], ref[3];
        path_pixel(&r, &m, &o, px[k][0], px[k][1], S, se);
        lamps_footprint(&r, c, 2, px[k][0], px[k][1], ref);
        for (int ch = 0; ch < 3; ch++)
            t_abs(S[ch], ref[ch], 4.5 * se[ch] + 1e-3 * ref[ch],
                  "first order, two lamps, pixel (%zu, %zu), channel %d: %.5g +- %.2g vs %.5g", px[k][0], px[k][1],
                  ch, S[ch], se[ch], ref[ch]);
    }
    for (int l = 0; l < 2; l++) {
        nbt_quad_ws_free(c[l].wu);
        nbt_quad_ws_free(c[l].wv);
    }
    nbt_phase_free(p);
    world_free(&r);
}

/* ---- 3. all orders against photon counting: the axis pixel before a
 * uniform wall sees L times the kernel's total scattered mass (reciprocity) ---- */
static void test_all_orders(void)
{
    const double tau = 1.0, a = 0.9, g = 0.6;
    nbt_phase *p = nbt_phase_hg(g);
    double zp[1] = {tau}, edges[1] = {1.0}, albs[1] = {a};
    nbt_mc_kernel_config kc = {.phase = p, .infinite = 1, .nplanes = 1, .z_planes = zp, .nedges = 1,
                               .edges = edges, .nalbedo = 1, .albedo = albs, .photons = 400000, .seed = 7};
    nbt_mc_kernel_result *kr = NULL;
    t_true(nbt_mc_kernel_run(&kc, &kr) == NBT_OK, "photon counts run");
    double M = 0, Mse = 0;
    for (size_t i = 0; i < 4; i++) {
        M += kr->mass[i];
        Mse += kr->mass_se[i]; /* correlated: the sum of SEs bounds the SE of the sum */
    }
    /* non-square 600 x 400 world, pitch 0.05: the wall reaches >= 10 mean
     * free paths sideways; the axis pixel's footprint changes S by < 1e-3 */
    world r = world_alloc(600, 400, 0.05, 300.5, 200.5);
    world_fill(&r, (float)tau, (const float[3]){1.0f, 1.0f, 1.0f});
    nbt_screen_path_medium m = {.sigma_t = {1, 1, 1}, .albedo = {a, a, a}, .phase = p, .radius = INFINITY};
    nbt_screen_path_opts o = {.spp = 30000, .seed = 3, .nthreads = 0};
    double S[3], se[3];
    path_pixel(&r, &m, &o, 300, 200, S, se);
    t_abs(S[1], M, 4.5 * sqrt(se[1] * se[1] + Mse * Mse) + 1e-3 * M,
          "all orders, wall tau %g, HG %g, albedo %g: path %.5g +- %.2g vs photon counting %.5g +- %.2g", tau, g, a,
          S[1], se[1], M, Mse);
    nbt_mc_kernel_result_free(kr);
    nbt_phase_free(p);
    world_free(&r);
}

/* ---- all orders under a uniform sky: a conservative ball of radius R
 * around the camera lit by sky radiance Ls from every direction is in
 * equilibrium, L = Ls everywhere inside it (extinction sigma Ls is balanced by
 * in-scattering sigma Ls for any phase function), so the scattered part seen
 * at the centre is Ls (1 - exp(-sigma R)) in every direction ---- */
static void test_sky_ball(void)
{
    /* every pixel sky (no patch to hit): each path ends on the sky; a 7 x 3
     * world off-centre, so the pixel's direction is oblique */
    world r = world_alloc(7, 3, 0.2, 2.4, 1.3);
    world_fill(&r, INFINITY, (const float[3]){0, 0, 0});
    nbt_phase *p = nbt_phase_hg(0.6);
    const double R = 1.5;
    nbt_screen_path_medium m = {.sigma_t = {1.0, 0.4, 2.0}, .albedo = {1, 1, 1}, .phase = p, .radius = R,
                                .sky = {0.5, 1.0, 2.0}};
    nbt_screen_path_opts o = {.spp = 20000, .seed = 5, .nthreads = 0};
    double S[3], se[3];
    path_pixel(&r, &m, &o, 5, 0, S, se);
    for (int ch = 0; ch < 3; ch++) {
        double want = m.sky[ch] * -expm1(-m.sigma_t[ch] * R);
        t_abs(S[ch], want, 4.5 * se[ch], "uniform sky %g on a conservative ball sigma R = %g, channel %d: %.5g +- %.2g vs Ls (1 - exp(-sigma R)) = %.5g",
              m.sky[ch], m.sigma_t[ch] * R, ch, S[ch], se[ch], want);
    }
    nbt_phase_free(p);
    world_free(&r);
}

/* ---- patches nearer than a collision: a world of black patches at Z 1 with a 2 x 2 window onto black
 * patches at Z 2.5, sky radiance beyond a ball of radius 4, isotropic scattering. The first order at a
 * window pixel: collisions between the two depths receive the sky from behind (towards the camera) only
 * through the window or past the world's edge, the near patches' backs block the rest. Reference: a
 * brute-force Monte Carlo of the same integral (collision by the truncated exponential, direction uniform
 * on the sphere, every patch tested for each direction, sky radiance attenuated to the ball's edge) ---- */
static void brute_first_sky(const world *r, double sig, double alb, double R, size_t px, size_t py, long n,
                            double *mean, double *se)
{
    const nbt_screen_world *W = &r->W;
    double s1 = 0, s2 = 0;
    for (long k = 0; k < n; k++) {
        double u = (px + t_uniform() - W->cx) * W->dtheta, v = (W->cy - py - t_uniform()) * W->dtheta;
        double nr = sqrt(1 + u * u + v * v), d[3] = {u / nr, v / nr, 1 / nr};
        float Zp = r->Z[py * W->w + px];
        double tb = fmin(isfinite(Zp) ? Zp * nr : INFINITY, R), F = -expm1(-sig * tb);
        double t = -log1p(-t_uniform() * F) / sig, x[3] = {t * d[0], t * d[1], t * d[2]};
        double wz = 2 * t_uniform() - 1, ph = 2 * M_PI * t_uniform(), ws = sqrt(fmax(0, 1 - wz * wz));
        double w[3] = {ws * cos(ph), ws * sin(ph), wz};
        int blocked = 0;
        for (size_t j = 0; j < W->w * W->h && !blocked && wz != 0; j++) {
            double Z = r->Z[j], tau = (Z - x[2]) / wz;
            if (!isfinite(Z) || !(tau > 0))
                continue;
            double pu = (x[0] + tau * w[0]) / Z, pv = (x[1] + tau * w[1]) / Z;
            size_t ix = j % W->w, iy = j / W->w;
            blocked = pu >= (ix - W->cx) * W->dtheta && pu <= (ix + 1 - W->cx) * W->dtheta &&
                      pv >= (W->cy - iy - 1) * W->dtheta && pv <= (W->cy - iy) * W->dtheta;
        }
        double b = x[0] * w[0] + x[1] * w[1] + x[2] * w[2], c = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - R * R;
        double f = blocked ? 0 : alb * F * exp(-sig * (-b + sqrt(b * b - c)));
        s1 += f;
        s2 += f * f;
    }
    *mean = s1 / n;
    *se = sqrt(fmax(0, s2 / n - *mean * *mean) / (n - 1));
}

static void test_near_backs(void)
{
    world r = world_alloc(12, 8, 0.25, 5.7, 3.8);
    world_fill(&r, 1.0f, (const float[3]){0, 0, 0});
    for (size_t y = 3; y <= 4; y++)
        for (size_t x = 5; x <= 6; x++)
            r.Z[y * 12 + x] = 2.5f;
    nbt_phase *p = nbt_phase_hg(0.0);
    const double sig = 0.5, alb = 0.9, R = 4.0;
    nbt_screen_path_medium m = {.sigma_t = {sig, sig, sig}, .albedo = {alb, alb, alb}, .phase = p, .radius = R,
                                .sky = {1.0, 2.0, 0.5}};
    nbt_screen_path_opts o = {.spp = 20000, .seed = 13, .nthreads = 0, .max_order = 1};
    const size_t px[2][2] = {{5, 3}, {6, 4}};
    for (int k = 0; k < 2; k++) {
        double S[3], se[3], ref, rse;
        path_pixel(&r, &m, &o, px[k][0], px[k][1], S, se);
        brute_first_sky(&r, sig, alb, R, px[k][0], px[k][1], 1000000, &ref, &rse);
        for (int ch = 0; ch < 3; ch++) {
            double want = m.sky[ch] * ref, wse = m.sky[ch] * rse;
            t_abs(S[ch], want, 4.5 * sqrt(se[ch] * se[ch] + wse * wse),
                  "first order behind near patches, pixel (%zu, %zu), channel %d: %.5g +- %.2g vs brute force %.5g +- %.2g",
                  px[k][0], px[k][1], ch, S[ch], se[ch], want, wse);
        }
    }
    nbt_phase_free(p);
    world_free(&r);
}

/* ---- 4. a lamp on a stepped wall: with and without next-event estimation;
 * determinism over threads and seeds ---- */
/* one: the lamp is the single patch (17, 10) at 4 x the radiance (the same power) instead of 2 x 2
 * patches, so the bright list holds exactly one patch among the 1120 lights */
static world lamp_scene_n(int one)
{
    world r = world_alloc(40, 28, 0.05, 18.7, 12.2);
    for (size_t y = 0; y < 28; y++)
        for (size_t x = 0; x < 40; x++) {
            size_t i = y * 40 + x;
            r.Z[i] = x < 22 ? 2.0f : 3.0f;
            r.rgb[3 * i] = 0.2f;
            r.rgb[3 * i + 1] = 0.3f;
            r.rgb[3 * i + 2] = 0.25f;
            if (one ? y == 10 && x == 17 : y >= 10 && y < 12 && x >= 17 && x < 19) {
                float k = one ? 4.0f : 1.0f;
                r.Z[i] = 1.5f;
                r.rgb[3 * i] = 60.0f * k;
                r.rgb[3 * i + 1] = 40.0f * k;
                r.rgb[3 * i + 2] = 20.0f * k;
            }
            if (y < 3 && x >= 30)
                r.Z[i] = INFINITY; /* a patch of sky */
        }
    r.W.x0 = 10;
    r.W.y0 = 6;
    r.W.ow = 16;
    r.W.oh = 12;
    return r;
}

static world lamp_scene(void)
{
    return lamp_scene_n(0);
}

static void bin_sum(const double *A, size_t w, size_t h, unsigned b, double *out, int square)
{
    size_t nbx = (w + b - 1) / b, nby = (h + b - 1) / b;
    memset(out, 0, nbx * nby * 3 * sizeof *out);
    for (size_t y = 0; y < h; y++)
        for (size_t x = 0; x < w; x++)
            for (int ch = 0; ch < 3; ch++) {
                double v = A[3 * (y * w + x) + ch];
                out[3 * ((y / b) * nbx + x / b) + ch] += square ? v * v : v;
            }
}

/* NEE + MIS at 300 spp against phase sampling only (an independent estimator) at 1500 spp: the same
 * image within the noise, and less noise per sample */
static void nee_vs_phase(const world *r, const char *what)
{
    nbt_phase *p = nbt_phase_hg(0.7);
    nbt_screen_path_medium m = {.sigma_t = {0.5, 0.6, 0.7}, .albedo = {0.9, 0.9, 0.85}, .phase = p,
                                .radius = INFINITY};
    size_t N = 16 * 12 * 3;
    double *A = malloc(N * sizeof *A), *Ae = malloc(N * sizeof *A), *B = malloc(N * sizeof *A),
           *Be = malloc(N * sizeof *A);
    nbt_screen_path_opts o = {.spp = 300, .seed = 21, .nthreads = 0};
    nbt_screen_path(&r->W, &m, &o, A, Ae, NULL);
    o.no_nee = 1;
    o.spp = 1500;
    o.seed = 22;
    nbt_screen_path(&r->W, &m, &o, B, Be, NULL);
    /* 4 x 4 bins: z scores of the difference */
    double bA[48 * 3], bB[48 * 3], vA[48 * 3], vB[48 * 3], chi2 = 0, zmax = 0;
    bin_sum(A, 16, 12, 4, bA, 0);
    bin_sum(B, 16, 12, 4, bB, 0);
    bin_sum(Ae, 16, 12, 4, vA, 1);
    bin_sum(Be, 16, 12, 4, vB, 1);
    size_t nb = 4 * 3 * 3;
    for (size_t i = 0; i < nb; i++) {
        double z = (bA[i] - bB[i]) / sqrt(vA[i] + vB[i]);
        chi2 += z * z;
        zmax = fmax(zmax, fabs(z));
    }
    /* chi^2 with 36 degrees of freedom: P(> 67) < 1e-3 */
    t_true(chi2 < 67 && zmax < 4.5, "%s: NEE + MIS vs phase sampling only: chi2 %.1f over %zu bins, max |z| %.2f",
           what, chi2, nb, zmax);
    /* per sample (noise x sqrt(spp)), next-event estimation is the better estimator */
    double eA = nbt_screen_binned_noise(16, 12, A, Ae, 4) * sqrt(300.0);
    double eB = nbt_screen_binned_noise(16, 12, B, Be, 4) * sqrt(1500.0);
    t_true(eA < 0.7 * eB, "%s: NEE lowers the noise per sample: %.3g vs %.3g", what, eA, eB);
    free(A);
    free(Ae);
    free(B);
    free(Be);
    nbt_phase_free(p);
}

static void test_nee(void)
{
    world r = lamp_scene();
    /* the 2 x 2 lamp: four bright patches; and a single-patch lamp, the bright list's one entry */
    nee_vs_phase(&r, "2 x 2 lamp");
    world r1 = lamp_scene_n(1);
    nee_vs_phase(&r1, "one-patch lamp");
    world_free(&r1);
    nbt_phase *p = nbt_phase_hg(0.7);
    nbt_screen_path_medium m = {.sigma_t = {0.5, 0.6, 0.7}, .albedo = {0.9, 0.9, 0.85}, .phase = p,
                                .radius = INFINITY};
    size_t N = 16 * 12 * 3;
    double *A = malloc(N * sizeof *A), *Ae = malloc(N * sizeof *A), *B = malloc(N * sizeof *A),
           *Be = malloc(N * sizeof *A);
    nbt_screen_path_opts o;

    /* determinism */
    o = (nbt_screen_path_opts){.spp = 16, .seed = 99, .nthreads = 1};
    nbt_screen_path(&r.W, &m, &o, A, Ae, NULL);
    o.nthreads = 3;
    nbt_screen_path(&r.W, &m, &o, B, Be, NULL);
    t_true(memcmp(A, B, N * sizeof *A) == 0 && memcmp(Ae, Be, N * sizeof *A) == 0,
           "1 and 3 threads: bit-identical S and SE");
    o.seed = 100;
    nbt_screen_path(&r.W, &m, &o, B, Be, NULL);
    size_t ndiff = 0;
    for (size_t i = 0; i < N; i++)
        ndiff += A[i] != B[i];
    t_true(ndiff > N / 2, "another seed: %zu of %zu values differ", ndiff, N);
    free(A);
    free(Ae);
    free(B);
    free(Be);
    nbt_phase_free(p);
    world_free(&r);
}

/* ---- 5. the binned noise against two independent runs ---- */
static void test_noise(void)
{
    world r = lamp_scene();
    r.W.x0 = 2;
    r.W.y0 = 2;
    r.W.ow = 36;
    r.W.oh = 24; /* 9 x 6 bins of 4 x 4 */
    nbt_phase *p = nbt_phase_hg(0.8);
    nbt_screen_path_medium m = {.sigma_t = {0.6, 0.6, 0.6}, .albedo = {0.9, 0.9, 0.9}, .phase = p,
                                .radius = 6.0, .sky = {0.5, 0.5, 1.0}};
    size_t N = 36 * 24 * 3;
    double *A = malloc(N * sizeof *A), *Ae = malloc(N * sizeof *A), *B = malloc(N * sizeof *A),
           *Be = malloc(N * sizeof *A);
    nbt_screen_path_opts o = {.spp = 24, .seed = 1, .nthreads = 0};
    nbt_screen_path(&r.W, &m, &o, A, Ae, NULL);
    o.seed = 2;
    nbt_screen_path(&r.W, &m, &o, B, Be, NULL);
    double nA = nbt_screen_binned_noise(36, 24, A, Ae, 4), nB = nbt_screen_binned_noise(36, 24, B, Be, 4);
    double l1 = nbt_screen_binned_rel_l1(36, 24, A, B, 4);
    /* E|A_b - B_b| = sqrt(2) sqrt(2/pi) SE_b: 162 terms, each |N| with
     * relative spread 0.76, so the sum is good to ~6% (1 sigma) */
    t_rel(l1, sqrt(2.0) * 0.5 * (nA + nB), 0.25, "binned rel L1 of two seeds %.4g vs sqrt(2) x noise %.4g", l1,
          sqrt(2.0) * 0.5 * (nA + nB));
    /* a target: passes until the noise is met */
    unsigned long done = 0;
    o = (nbt_screen_path_opts){.spp = 8, .seed = 3, .nthreads = 0, .target_noise = 0.5 * nA, .max_spp = 400};
    nbt_screen_path(&r.W, &m, &o, A, Ae, &done);
    double nT = nbt_screen_binned_noise(36, 24, A, Ae, 4);
    t_true(nT <= 0.5 * nA && done > 24 && done < 400, "target noise %.3g reached: %.3g at %lu spp", 0.5 * nA, nT,
           done);
    free(A);
    free(Ae);
    free(B);
    free(Be);
    nbt_phase_free(p);
    world_free(&r);
}

int main(void)
{
    test_zero();
    test_bad();
    test_first_wall();
    test_first_lamp();
    test_first_two_lamps();
    test_all_orders();
    test_sky_ball();
    test_near_backs();
    test_nee();
    test_noise();
    return t_done();
}
