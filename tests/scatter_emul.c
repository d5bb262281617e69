/* tests/scatter_emul.c: CPU emulations of the GPU scattering methods
 * (scatter_emul.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "scatter_emul.h"

#define SKY_KEY 1e30f
#define SQRT2PI 2.50662827463100050

double scatter_emul_G(double x)
{
    double y = x / sqrt(2.0), t = 1.0 / (1.0 + 0.3275911 * y);
    double p = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return 0.5 * p * exp(-y * y);
}

static float key(float D)
{
    return D < 1e10f ? D : SKY_KEY;
}

static double sigma_of(const nbt_gls_input *in, size_t i)
{
    return in->sigma_px ? in->sigma_px[i] : (float)(in->beta_px[i] / sqrt(3.0));
}

/* ---- shinya: operator A by a windowed gather ---- */

/* the six near weights of pixel i's kernel: M0 times the table, linear in log2 beta */
static void near_weights(const nbt_gls_input *in, const float *lut, size_t i, double *nw)
{
    double M0 = in->M0[i], b = in->beta_px[i], scale = 1;
    memset(nw, 0, 6 * sizeof *nw);
    if (!(M0 > 0))
        return;
    double u = b > 0 ? (log2(b) - NBT_GLS_LUT_LO) * NBT_GLS_LUT_PER : -1, f;
    int j;
    if (u <= 0) {
        j = 0;
        f = 0;
    } else if (u >= NBT_GLS_LUT_N - 1) {
        j = NBT_GLS_LUT_N - 2;
        f = 1;
        scale = exp2(NBT_GLS_LUT_LO + (double)(NBT_GLS_LUT_N - 1) / NBT_GLS_LUT_PER) / b;
    } else {
        j = (int)floor(u);
        f = u - j;
    }
    for (int k = 0; k < 6; k++)
        nw[k] = M0 * scale * ((1 - f) * lut[8 * j + k] + f * lut[8 * (j + 1) + k]);
}

/* unit erfc atom over a whole pixel at r >= 3: centre value + laplacian/24 */
static double far_weight(double b, double r)
{
    double u = r / b, phi = exp(-0.5 * u * u) / SQRT2PI, G = scatter_emul_G(u);
    double lap = u * phi / (b * b * r) + phi / (b * r * r) + G / (r * r * r);
    return (G / r + lap / 24.0) / (SQRT2PI * b);
}

static nbt_status emul_shinya(const nbt_gls_input *in, double *S)
{
    size_t w = in->w, h = in->h, np = w * h;
    double *nw = malloc(np * 6 * sizeof *nw);
    float *lut = malloc(NBT_GLS_LUT_N * 8 * sizeof *lut);
    if (!nw || !lut) {
        free(nw);
        free(lut);
        return NBT_ENOMEM;
    }
    nbt_gls_near_table(lut);
    double rmax = 2;
    for (size_t i = 0; i < np; i++) {
        near_weights(in, lut, i, nw + 6 * i);
        if (in->M0[i] > 0 && key(in->D[i]) < SKY_KEY)
            rmax = fmax(rmax, ceil(in->cut * in->beta_px[i]));
    }
    long R = (long)fmin(rmax, (double)(w > h ? w : h));
    float cutf = (float)in->cut;
    for (long x1 = 0; x1 < (long)h; x1++)
        for (long x0 = 0; x0 < (long)w; x0++) {
            size_t ix = (size_t)x1 * w + (size_t)x0;
            float Dx = key(in->D[ix]);
            double s[3] = {0, 0, 0};
            for (long dy = -R; dy <= R; dy++)
                for (long dx = -R; dx <= R; dx++) {
                    long y0 = x0 + dx, y1 = x1 + dy;
                    if (y0 < 0 || y1 < 0 || y0 >= (long)w || y1 >= (long)h)
                        continue;
                    size_t iy = (size_t)y1 * w + (size_t)y0;
                    size_t n = key(in->D[iy]) > Dx ? ix : iy; /* the nearer pixel's kernel; ties: the source's */
                    long ax = labs(dx), ay = labs(dy), hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
                    if (hi > 2 && dx * dx + dy * dy > R * R) /* the window is a disc of radius R */
                        continue;
                    double wt = 0;
                    if (hi <= 2)
                        wt = nw[6 * n + hi * (hi + 1) / 2 + lo];
                    else {
                        float cb = cutf * in->beta_px[n], r2 = (float)(dx * dx + dy * dy);
                        if (in->M0[n] > 0 && r2 <= cb * cb)
                            wt = in->M0[n] * far_weight(in->beta_px[n], sqrt((double)r2));
                    }
                    for (int c = 0; c < 3; c++)
                        s[c] += wt * in->rgb[3 * iy + c];
                }
            for (int c = 0; c < 3; c++)
                S[3 * ix + c] = s[c];
        }
    free(nw);
    free(lut);
    return NBT_OK;
}

/* ---- shinya-literal: Alg. 1-4 as printed ---- */

static void point(const nbt_gls_input *in, long x0, long x1, double D, double *P)
{
    double u = (x0 + 0.5 - 0.5 * (double)in->w) * in->dtheta, v = (x1 + 0.5 - 0.5 * (double)in->h) * in->dtheta;
    double n = sqrt(1 + u * u + v * v);
    P[0] = D * u / n;
    P[1] = D * v / n;
    P[2] = D / n;
}

static nbt_status emul_literal(const nbt_gls_input *in, double *S)
{
    size_t w = in->w, h = in->h, np = w * h;
    double rmax = 0;
    for (size_t i = 0; i < np; i++)
        if (in->M0[i] > 0 && key(in->D[i]) < SKY_KEY)
            rmax = fmax(rmax, floor(2.0 * in->beta_px[i] * in->beta_px[i] * in->D[i] * in->dtheta) + 1);
    long R = (long)fmin(rmax, (double)(w > h ? w : h));
    float dth = (float)in->dtheta;
    for (long x1 = 0; x1 < (long)h; x1++)
        for (long x0 = 0; x0 < (long)w; x0++) {
            size_t ix = (size_t)x1 * w + (size_t)x0;
            float Dx = key(in->D[ix]);
            double s[3] = {0, 0, 0}, Px[3], Py[3];
            point(in, x0, x1, Dx, Px);
            for (long dy = -R; dy <= R; dy++)
                for (long dx = -R; dx <= R; dx++) {
                    long y0 = x0 + dx, y1 = x1 + dy;
                    if (y0 < 0 || y1 < 0 || y0 >= (long)w || y1 >= (long)h)
                        continue;
                    size_t iy = (size_t)y1 * w + (size_t)y0;
                    float Dy = key(in->D[iy]);
                    if (Dy == Dx) /* strict '>' in Alg. 2 and 3 */
                        continue;
                    size_t n = Dy > Dx ? ix : iy;
                    float Dn = Dy > Dx ? Dx : Dy, Df = Dy > Dx ? Dy : Dx;
                    if (!(in->M0[n] > 0) || Df >= 1e10f)
                        continue;
                    /* the window test in float, as on the GPU */
                    float pitch = Dn * dth, bwf = in->beta_px[n] * pitch, blf = 2.0f * bwf * bwf;
                    long m = labs(dx) > labs(dy) ? labs(dx) : labs(dy);
                    if ((float)m * pitch > blf)
                        continue;
                    double bw = (double)in->beta_px[n] * Dn * in->dtheta, bl = 2 * bw * bw; /* beta[] = 3 M2/M0 */
                    point(in, y0, y1, Dy, Py);
                    double d = sqrt((Py[0] - Px[0]) * (Py[0] - Px[0]) + (Py[1] - Px[1]) * (Py[1] - Px[1]) +
                                    (Py[2] - Px[2]) * (Py[2] - Px[2]));
                    double wt = in->M0[n] / (bw * bw) / d * scatter_emul_G(d / bl); /* alpha[] = 2 M0/beta[] */
                    for (int c = 0; c < 3; c++)
                        s[c] += wt * in->rgb[3 * iy + c];
                }
            for (int c = 0; c < 3; c++)
                S[3 * ix + c] = s[c];
        }
    return NBT_OK;
}

/* ---- pyramids ---- */

typedef struct {
    size_t w, h;
    double *I; /* 4 per texel: rgb, W */
    double *B; /* 2 per texel: W v, v */
} level;

static const double F4[4] = {0.13, 0.37, 0.37, 0.13};

static double mask(double W, double T, double eps)
{
    if (eps <= 0)
        return W >= T ? 1.0 : 0.0;
    double t = (W - T) / (eps * T);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return t * t * (3 - 2 * t);
}

static nbt_status build(const nbt_gls_input *in, int masked, level *L)
{
    size_t pad = (size_t)1 << NBT_GLS_K;
    size_t pw = (in->w + pad - 1) / pad * pad, ph = (in->h + pad - 1) / pad * pad;
    for (int k = 0; k <= NBT_GLS_K; k++) {
        L[k].w = pw >> k;
        L[k].h = ph >> k;
        L[k].I = calloc(L[k].w * L[k].h * 4, sizeof(double));
        L[k].B = calloc(L[k].w * L[k].h * 2, sizeof(double));
        if (!L[k].I || !L[k].B)
            return NBT_ENOMEM;
    }
    for (size_t y = 0; y < in->h; y++)
        for (size_t x = 0; x < in->w; x++) {
            size_t i = y * in->w + x, j = y * pw + x;
            for (int c = 0; c < 3; c++)
                L[0].I[4 * j + c] = (double)in->M0[i] * in->rgb[3 * i + c];
            L[0].I[4 * j + 3] = sigma_of(in, i);
            L[0].B[2 * j] = sigma_of(in, i);
            L[0].B[2 * j + 1] = 1;
        }
    double eps = (float)in->eps;
    for (int k = 1; k <= NBT_GLS_K; k++) {
        const level *s = &L[k - 1];
        level *d = &L[k];
        double T = (float)(NBT_GLS_ELEK_C * ldexp(1.0, k - 1));
        for (size_t py = 0; py < d->h; py++)
            for (size_t px = 0; px < d->w; px++) {
                double I[3] = {0, 0, 0}, b[2] = {0, 0}, yw = 0, ys = 0, vw = 0, vs = 0;
                for (int bb = 0; bb < 4; bb++)
                    for (int a = 0; a < 4; a++) {
                        long qx = 2 * (long)px - 1 + a, qy = 2 * (long)py - 1 + bb;
                        if (qx < 0 || qy < 0 || qx >= (long)s->w || qy >= (long)s->h)
                            continue;
                        const double *v = s->I + 4 * ((size_t)qy * s->w + (size_t)qx);
                        const double *wv = s->B + 2 * ((size_t)qy * s->w + (size_t)qx);
                        double f = F4[a] * F4[bb], m = masked ? mask(v[3], T, eps) : 1;
                        double Y = fabs(0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]);
                        for (int c = 0; c < 3; c++)
                            I[c] += f * m * v[c];
                        b[0] += f * wv[0];
                        b[1] += f * wv[1];
                        yw += Y * v[3];
                        ys += Y;
                        vw += wv[1] * v[3];
                        vs += wv[1];
                    }
                double *o = d->I + 4 * (py * d->w + px), *ob = d->B + 2 * (py * d->w + px);
                for (int c = 0; c < 3; c++)
                    o[c] = I[c];
                o[3] = ys > 0 ? yw / ys : vs > 0 ? vw / vs : 0;
                ob[0] = b[0];
                ob[1] = b[1];
            }
    }
    return NBT_OK;
}

static void free_levels(level *L)
{
    for (int k = 0; k <= NBT_GLS_K; k++) {
        free(L[k].I);
        free(L[k].B);
    }
}

/* a texture unit's bilinear read (zero border) at texel-centre coordinates (tx, ty) */
static void bilinear(const level *l, int img, double tx, double ty, double *out, int nch)
{
    long i0 = (long)floor(tx), j0 = (long)floor(ty);
    double a = tx - i0, b = ty - j0;
    for (int c = 0; c < nch; c++)
        out[c] = 0;
    for (int dj = 0; dj < 2; dj++)
        for (int di = 0; di < 2; di++) {
            long i = i0 + di, j = j0 + dj;
            if (i < 0 || j < 0 || i >= (long)l->w || j >= (long)l->h)
                continue;
            double wgt = (di ? a : 1 - a) * (dj ? b : 1 - b);
            const double *v = img ? l->B + 2 * ((size_t)j * l->w + (size_t)i) : l->I + 4 * ((size_t)j * l->w + (size_t)i);
            for (int c = 0; c < nch; c++)
                out[c] += wgt * v[c];
        }
}

static double level_of(double W, double c)
{
    if (!(W > 0))
        return 0;
    double l = log2(W / c);
    return l < 0 ? 0 : l > NBT_GLS_K ? NBT_GLS_K : l;
}

static nbt_status emul_naive(const nbt_gls_input *in, double *S)
{
    level L[NBT_GLS_K + 1];
    memset(L, 0, sizeof L);
    nbt_status st = build(in, 0, L);
    for (size_t y = 0; y < in->h && st == NBT_OK; y++)
        for (size_t x = 0; x < in->w; x++) {
            double l = level_of(sigma_of(in, y * in->w + x), NBT_GLS_NAIVE_C), v[2][4];
            int k0 = (int)floor(l), k1 = k0 + 1 > NBT_GLS_K ? NBT_GLS_K : k0 + 1;
            int ks[2] = {k0, k1};
            for (int t = 0; t < 2; t++) {
                double n = ldexp(1.0, ks[t]);
                bilinear(&L[ks[t]], 0, (x + 0.5) / n - 0.5, (y + 0.5) / n - 0.5, v[t], 3);
            }
            for (int c = 0; c < 3; c++)
                S[3 * (y * in->w + x) + c] = v[0][c] + (l - k0) * (v[1][c] - v[0][c]);
        }
    free_levels(L);
    return st;
}

/* the cubic B-spline at pixel (x, y) of level k, as 4 bilinear fetches */
static void bspline(const level *L, int img, size_t x, size_t y, int k, double *out, int nch)
{
    double n = ldexp(1.0, k), c[2] = {(x + 0.5) / n - 0.5, (y + 0.5) / n - 0.5}, g0[2], g1[2], h0[2], h1[2];
    for (int a = 0; a < 2; a++) {
        double i = floor(c[a]), f = c[a] - i, g = 1 - f;
        double w0 = g * g * g / 6, w3 = f * f * f / 6, w1 = (4 - 6 * f * f + 3 * f * f * f) / 6, w2 = 1 - w0 - w1 - w3;
        g0[a] = w0 + w1;
        g1[a] = w2 + w3;
        h0[a] = i - 1 + w1 / g0[a];
        h1[a] = i + 1 + w3 / g1[a];
    }
    double t[4];
    for (int ch = 0; ch < nch; ch++)
        out[ch] = 0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            bilinear(&L[k], img, i ? h1[0] : h0[0], j ? h1[1] : h0[1], t, nch);
            double wgt = (i ? g1[0] : g0[0]) * (j ? g1[1] : g0[1]);
            for (int ch = 0; ch < nch; ch++)
                out[ch] += wgt * t[ch];
        }
}

static void read_levels(const level *L, int img, size_t x, size_t y, double l, double *out, int nch)
{
    int k0 = (int)floor(l), k1 = k0 + 1 > NBT_GLS_K ? NBT_GLS_K : k0 + 1;
    double a[4], b[4];
    bspline(L, img, x, y, k0, a, nch);
    bspline(L, img, x, y, k1, b, nch);
    for (int c = 0; c < nch; c++)
        out[c] = a[c] + (l - k0) * (b[c] - a[c]);
}

static nbt_status emul_elek(const nbt_gls_input *in, double *S)
{
    level L[NBT_GLS_K + 1];
    memset(L, 0, sizeof L);
    nbt_status st = build(in, 1, L);
    for (size_t y = 0; y < in->h && st == NBT_OK; y++)
        for (size_t x = 0; x < in->w; x++) {
            double W = sigma_of(in, y * in->w + x), wb[2], v[3];
            int sky = key(in->D[y * in->w + x]) >= SKY_KEY; /* no width of its own: the coarsest blur */
            read_levels(L, 1, x, y, sky ? (double)NBT_GLS_K : level_of(W, NBT_GLS_ELEK_C), wb, 2);
            double Wt = wb[1] > 0 ? wb[0] / wb[1] : W;
            read_levels(L, 0, x, y, level_of(Wt, NBT_GLS_ELEK_C), v, 3);
            for (int c = 0; c < 3; c++)
                S[3 * (y * in->w + x) + c] = v[c];
        }
    free_levels(L);
    return st;
}

/* ---- nbt: fitted pyramid kernels, depth slabs, exact centre taps ---- */

typedef struct {
    size_t w, h, nl;
    double *v; /* nl layers of w*h rgb */
} stack;

static double *at(const stack *a, size_t layer, long x, long y)
{
    return a->v + 3 * ((layer * a->h + (size_t)y) * a->w + (size_t)x);
}

static int stack_new(stack *a, size_t w, size_t h, size_t nl)
{
    a->w = w, a->h = h, a->nl = nl;
    a->v = calloc(w * h * nl * 3, sizeof(double));
    return a->v != NULL;
}

/* the texture unit's bilinear read of one layer at texel-centre coordinates, zero border */
static void stack_bilinear(const stack *a, size_t layer, double tx, double ty, double *out)
{
    long i0 = (long)floor(tx), j0 = (long)floor(ty);
    double fx = tx - i0, fy = ty - j0;
    out[0] = out[1] = out[2] = 0;
    for (int dj = 0; dj < 2; dj++)
        for (int di = 0; di < 2; di++) {
            long i = i0 + di, j = j0 + dj;
            if (i < 0 || j < 0 || i >= (long)a->w || j >= (long)a->h)
                continue;
            double wgt = (di ? fx : 1 - fx) * (dj ? fy : 1 - fy);
            const double *v = at(a, layer, i, j);
            for (int c = 0; c < 3; c++)
                out[c] += wgt * v[c];
        }
}

static int nbt_slab(float D, const nbt_gls_nbt_plan *pl)
{
    float k = key(D);
    if (!(k > 0))
        return -1;
    if (k >= SKY_KEY)
        return (int)pl->n;
    int s = 0;
    for (unsigned b = 1; b < pl->n; b++)
        s += pl->bound[b] <= k;
    return s;
}

static double nbt_lbeta(double b)
{
    return log2(fmax(b, exp2(NBT_GLS_NBT_LO)));
}

/* nbt's in-slab excess at receiver x (slab s < n): along each of the four
 * axis directions the depth profile is sampled at t = 1, 2, 3, 4, 6, 8, 12,
 * 16, ... px up to 2 beta_x, stopping at the screen's edge (h = the distance
 * to it) or at the first pixel outside the slab (h = the middle of the last
 * interval); if no tap is farther than x there is nothing. Else each tap k
 * changes the kernel of the sources beyond the middle m of its interval
 * (t_{k-1}, t_k] from the previous one's to its own (x's own if the tap is
 * not farther than x), which adds c_k (M0 (tail(m/b) - tail(h/b)) of the new
 * kernel minus that of the old), c_k = level l = clamp(floor(log2(t_k -
 * t_{k-1})), 1, K) of the source pyramid's colour layer of slab s read
 * bilinearly at the tap; the first interval leaves out the 3x3 pixels on
 * that side (M0 (a10 + 2 a11), the exact centre taps). The two directions
 * of an axis add; the axes add in quadrature (sign of their sum). */
static double emul_tail(const float *tail, double v)
{
    double u = v * NBT_GLS_TAIL_PER;
    if (!(u < NBT_GLS_TAIL_N - 1))
        return 0;
    int k = (int)u;
    return tail[k] + (u - k) * (tail[k + 1] - tail[k]);
}

static double emul_band(const float *tail, double M0, double b, double t, double h)
{
    b = fmax(b, 1e-6);
    return M0 * (emul_tail(tail, t / b) - emul_tail(tail, h / b));
}

static int emul_tap(int t)
{
    return t < 4 ? t + 1 : (t & (t - 1)) == 0 ? t + t / 2 : t + t / 3;
}

typedef struct {
    const nbt_gls_input *in;
    const nbt_gls_nbt_plan *pl;
    const stack *src; /* src[1 .. K], logical texel j at index j + 1 */
    float alut[NBT_GLS_LUT_N * 8], tail[NBT_GLS_TAIL_N];
} excess_ctx;

static void emul_march(const excess_ctx *X, long x, long y, long ex, long ey, double *E)
{
    const nbt_gls_input *in = X->in;
    size_t w = in->w, h = in->h, ix = (size_t)y * w + (size_t)x;
    float Dx = key(in->D[ix]);
    int s = nbt_slab(in->D[ix], X->pl);
    double reach = (float)(2.0f * in->beta_px[ix]), hh = 1e30;
    int t = 1, tprev = 0, cnt = 0, farther = 0;
    for (int k = 0; k < 24 && t <= reach; k++) {
        long qx = x + t * ex, qy = y + t * ey;
        if (qx < 0 || qy < 0 || qx >= (long)w || qy >= (long)h) {
            hh = (ex > 0 ? (double)w - x : ex < 0 ? x + 1.0 : ey > 0 ? (double)h - y : y + 1.0) - 0.5;
            break;
        }
        size_t iq = (size_t)qy * w + (size_t)qx;
        if (nbt_slab(in->D[iq], X->pl) != s) {
            hh = 0.5 * (tprev + t);
            break;
        }
        farther |= key(in->D[iq]) > Dx;
        cnt++;
        tprev = t;
        t = emul_tap(t);
    }
    double pm = in->M0[ix], pb = in->beta_px[ix], nw[6];
    t = 1;
    tprev = 0;
    for (int k = 0; k < cnt && farther; k++) {
        long qx = x + t * ex, qy = y + t * ey;
        size_t iq = (size_t)qy * w + (size_t)qx;
        int far = key(in->D[iq]) > Dx;
        double km = far ? in->M0[iq] : in->M0[ix], kb = far ? in->beta_px[iq] : in->beta_px[ix];
        double m = 0.5 * (tprev + t);
        double d = emul_band(X->tail, km, kb, m, hh) - emul_band(X->tail, pm, pb, m, hh);
        if (k == 0) {
            near_weights(in, X->alut, far ? iq : ix, nw);
            d -= nw[1] + 2 * nw[2];
            near_weights(in, X->alut, ix, nw);
            d += nw[1] + 2 * nw[2];
        }
        int l = 0;
        while ((2 << l) <= t - tprev)
            l++;
        l = l < 1 ? 1 : l > NBT_GLS_K ? NBT_GLS_K : l;
        double c[3], sc = 1.0 / (1 << l);
        stack_bilinear(&X->src[l], (size_t)(2 * X->pl->n + (unsigned)s), (qx + 0.5) * sc + 0.5, (qy + 0.5) * sc + 0.5, c);
        for (int ch = 0; ch < 3; ch++)
            E[ch] += d * c[ch];
        pm = km, pb = kb;
        tprev = t;
        t = emul_tap(t);
    }
}

static void emul_excess(const excess_ctx *X, long x, long y, double *out)
{
    double ex[3] = {0, 0, 0}, ey[3] = {0, 0, 0};
    emul_march(X, x, y, 1, 0, ex);
    emul_march(X, x, y, -1, 0, ex);
    emul_march(X, x, y, 0, 1, ey);
    emul_march(X, x, y, 0, -1, ey);
    for (int c = 0; c < 3; c++) {
        double sum = ex[c] + ey[c];
        out[c] = (sum > 0 ? 1 : sum < 0 ? -1 : 0) * sqrt(ex[c] * ex[c] + ey[c] * ey[c]);
    }
}

nbt_status scatter_emul_nbt(const nbt_gls_input *in, unsigned slabs, double *S)
{
    size_t pad = (size_t)1 << NBT_GLS_K, w = in->w, h = in->h, np = w * h;
    size_t pw = (w + pad - 1) / pad * pad, ph = (h + pad - 1) / pad * pad;
    nbt_gls_nbt_plan pl;
    nbt_gls_nbt_plan_of(in, slabs, &pl);
    long n = (long)pl.n, L = 3 * n + 1, Z = 3 * n;
    /* level k >= 1 holds logical texels -1 .. (pw >> k): index logical + 1 */
    stack src[NBT_GLS_K + 1], q[NBT_GLS_K + 1], col[NBT_GLS_K + 1];
    memset(src, 0, sizeof src);
    memset(q, 0, sizeof q);
    memset(col, 0, sizeof col);
    double *nw = malloc(np * 6 * sizeof *nw), *lev0 = calloc(np * 3 * (size_t)L, sizeof(double));
    float *lut = malloc(NBT_GLS_LUT_N * 8 * sizeof *lut);
    int ok = nw && lut && lev0;
    for (int k = 1; k <= NBT_GLS_K && ok; k++)
        ok = stack_new(&src[k], (pw >> k) + 2, (ph >> k) + 2, (size_t)L) &&
             stack_new(&q[k], (pw >> k) + 2, (ph >> k) + 2, (2 + NBT_GLS_NBT_NW) * (size_t)Z) &&
             stack_new(&col[k], (pw >> k) + 2, (ph >> k) + 2, (size_t)Z);
    nbt_status st = ok ? NBT_OK : NBT_ENOMEM;
    if (st == NBT_OK) {
        /* level 0 (image only): A_j = M0 c, E_j = delta M0 c, C_j = c */
        stack l0 = {w, h, (size_t)L, lev0};
        for (long y = 0; y < (long)h; y++)
            for (long x = 0; x < (long)w; x++) {
                size_t i = (size_t)y * w + (size_t)x;
                int s = nbt_slab(in->D[i], &pl);
                if (s < 0)
                    continue;
                for (int c = 0; c < 3; c++) {
                    at(&l0, (size_t)(2 * n + s), x, y)[c] = in->rgb[3 * i + c];
                    if (s < n) {
                        double m = (double)in->M0[i] * in->rgb[3 * i + c];
                        at(&l0, (size_t)s, x, y)[c] = m;
                        at(&l0, (size_t)(n + s), x, y)[c] = (nbt_lbeta(in->beta_px[i]) - pl.lb[s]) * m;
                    }
                }
            }
        /* decimation in logical texels; level 0 has no margin */
        for (int k = 1; k <= NBT_GLS_K; k++) {
            const stack *f = k == 1 ? &l0 : &src[k - 1];
            long m = k == 1 ? 0 : 1; /* index of logical 0 in the finer level */
            for (long z = 0; z < L; z++)
                for (long py = -1; py <= (long)(ph >> k); py++)
                    for (long px = -1; px <= (long)(pw >> k); px++) {
                        double *o = at(&src[k], (size_t)z, px + 1, py + 1);
                        for (int b = 0; b < 4; b++)
                            for (int a = 0; a < 4; a++) {
                                long qx = 2 * px - 1 + a + m, qy = 2 * py - 1 + b + m;
                                if (qx < 0 || qy < 0 || qx >= (long)f->w || qy >= (long)f->h)
                                    continue;
                                const double *v = at(f, (size_t)z, qx, qy);
                                for (int c = 0; c < 3; c++)
                                    o[c] += F4[a] * F4[b] * v[c];
                            }
                    }
        }
        /* the parts of each collapse per level */
        double a[NBT_GLS_NBT_MAXSLABS][NBT_GLS_NBT_NB], da[NBT_GLS_NBT_MAXSLABS][NBT_GLS_NBT_NB];
        for (long j = 0; j < n; j++)
            nbt_gls_nbt_weights(pl.lb[j], a[j], da[j]);
        /* parts: t = 0 sharp, 1 blurred, 2 + m wide kernel m (level K only) */
        enum { NT = 2 + NBT_GLS_NBT_NW, K = NBT_GLS_K };
        for (int k = 1; k <= NBT_GLS_K; k++)
            for (long py = 0; py < (long)q[k].h; py++)
                for (long px = 0; px < (long)q[k].w; px++) {
                    double acc[NT][3] = {{0}}, suf[3];
                    for (long j = 0; j < n; j++) {
                        const double *A = at(&src[k], (size_t)j, px, py), *E = at(&src[k], (size_t)(n + j), px, py);
                        double w1[NT] = {(float)a[j][k - 1], (float)a[j][K + k - 1]};
                        double w2[NT] = {(float)da[j][k - 1], (float)da[j][K + k - 1]};
                        for (int m = 0; m < NBT_GLS_NBT_NW && k == K; m++)
                            w1[2 + m] = (float)a[j][2 * K + m], w2[2 + m] = (float)da[j][2 * K + m];
                        for (int t = 0; t < NT; t++)
                            for (int c = 0; c < 3; c++) {
                                acc[t][c] += w1[t] * A[c] + w2[t] * E[c];
                                at(&q[k], (size_t)(t * Z + j), px, py)[c] = acc[t][c];
                            }
                    }
                    memcpy(suf, at(&src[k], (size_t)(3 * n), px, py), sizeof suf);
                    for (long i = n - 1; i >= 0; i--) {
                        double w1[NT] = {(float)a[i][k - 1], (float)a[i][K + k - 1]};
                        double w2[NT] = {(float)da[i][k - 1], (float)da[i][K + k - 1]};
                        for (int m = 0; m < NBT_GLS_NBT_NW && k == K; m++)
                            w1[2 + m] = (float)a[i][2 * K + m], w2[2 + m] = (float)da[i][2 * K + m];
                        for (int t = 0; t < NT; t++)
                            for (int c = 0; c < 3; c++) {
                                at(&q[k], (size_t)(t * Z + n + i), px, py)[c] = w1[t] * suf[c];
                                at(&q[k], (size_t)(t * Z + 2 * n + i), px, py)[c] = w2[t] * suf[c];
                            }
                        const double *C = at(&src[k], (size_t)(2 * n + i), px, py);
                        for (int c = 0; c < 3; c++)
                            suf[c] += C[c];
                    }
                }
        /* the collapse: col_k = q_k + blur + up(col_{k+1}) */
        const double bw[3] = {NBT_GLS_NBT_BLUR, 1 - 2 * NBT_GLS_NBT_BLUR, NBT_GLS_NBT_BLUR};
        for (int k = NBT_GLS_K; k >= 1; k--)
            for (long z = 0; z < Z; z++)
                for (long py = 0; py < (long)col[k].h; py++)
                    for (long px = 0; px < (long)col[k].w; px++) {
                        double *o = at(&col[k], (size_t)z, px, py), u[3];
                        memcpy(o, at(&q[k], (size_t)z, px, py), 3 * sizeof *o);
                        for (int dy = -1; dy <= 1; dy++)
                            for (int dx = -1; dx <= 1; dx++) {
                                long xx = px + dx, yy = py + dy;
                                if (xx < 0 || yy < 0 || xx >= (long)col[k].w || yy >= (long)col[k].h)
                                    continue;
                                const double *v = at(&q[k], (size_t)(Z + z), xx, yy);
                                for (int c = 0; c < 3; c++)
                                    o[c] += bw[dx + 1] * bw[dy + 1] * v[c];
                            }
                        for (int m = 0; m < NBT_GLS_NBT_NW && k == K; m++) { /* the wide blurs */
                            enum { WT = NBT_GLS_NBT_WT };
                            double g[WT + 1];
                            nbt_gls_nbt_wide_taps(m, g);
                            for (long dy = -WT; dy <= WT; dy++)
                                for (long dx = -WT; dx <= WT; dx++) {
                                    long xx = px + dx, yy = py + dy;
                                    if (xx < 0 || yy < 0 || xx >= (long)col[k].w || yy >= (long)col[k].h)
                                        continue;
                                    const double *v = at(&q[k], (size_t)((2 + m) * Z + z), xx, yy);
                                    for (int c = 0; c < 3; c++)
                                        o[c] += g[labs(dx)] * g[labs(dy)] * v[c];
                                }
                        }
                        if (k < NBT_GLS_K) { /* logical (q + 0.5)/2 - 0.5, index + 1 */
                            stack_bilinear(&col[k + 1], (size_t)z, (px - 1 + 0.5) / 2 + 0.5, (py - 1 + 0.5) / 2 + 0.5, u);
                            for (int c = 0; c < 3; c++)
                                o[c] += u[c];
                        }
                    }
        /* the receivers */
        excess_ctx *X = malloc(sizeof *X);
        if (X) {
            X->in = in, X->pl = &pl, X->src = src;
            nbt_gls_near_table(X->alut);
            nbt_gls_nbt_tail_table(X->tail);
        } else
            st = NBT_ENOMEM;
        nbt_gls_nbt_near_table(lut);
        for (size_t i = 0; i < np; i++)
            near_weights(in, lut, i, nw + 6 * i);
        for (long y = 0; X && y < (long)h; y++)
            for (long x = 0; x < (long)w; x++) {
                size_t ix = (size_t)y * w + (size_t)x;
                double *o = S + 3 * ix, u[3], v[3];
                o[0] = o[1] = o[2] = 0;
                int s = nbt_slab(in->D[ix], &pl);
                if (s < 0)
                    continue;
                double tx = (x + 0.5) / 2 + 0.5, ty = (y + 0.5) / 2 + 0.5; /* logical (x + 0.5)/2 - 0.5, index + 1 */
                stack_bilinear(&col[1], (size_t)(s < n ? s : n - 1), tx, ty, o);
                if (s < n && in->M0[ix] > 0) {
                    double d = nbt_lbeta(in->beta_px[ix]) - pl.lb[s];
                    stack_bilinear(&col[1], (size_t)(n + s), tx, ty, u);
                    stack_bilinear(&col[1], (size_t)(2 * n + s), tx, ty, v);
                    for (int c = 0; c < 3; c++)
                        o[c] += in->M0[ix] * (u[c] + d * v[c]);
                }
                if (s < n) {
                    double e[3];
                    emul_excess(X, x, y, e);
                    for (int c = 0; c < 3; c++)
                        o[c] -= e[c];
                }
                float Dx = key(in->D[ix]);
                for (long dy = -1; dy <= 1; dy++)
                    for (long dx = -1; dx <= 1; dx++) {
                        long y0 = x + dx, y1 = y + dy;
                        if (y0 < 0 || y1 < 0 || y0 >= (long)w || y1 >= (long)h)
                            continue;
                        size_t iy = (size_t)y1 * w + (size_t)y0;
                        float Dy = key(in->D[iy]);
                        int mine = Dy > Dx;
                        if (!mine && !(Dy > 0))
                            continue;
                        double wt = nw[6 * (mine ? ix : iy) + labs(dx) + labs(dy)];
                        for (int c = 0; c < 3; c++)
                            o[c] += wt * in->rgb[3 * iy + c];
                    }
            }
        free(X);
    }
    for (int k = 0; k <= NBT_GLS_K; k++) {
        free(src[k].v);
        free(q[k].v);
        free(col[k].v);
    }
    free(lev0);
    free(nw);
    free(lut);
    return st;
}

nbt_status scatter_emul(nbt_gls_method m, const nbt_gls_input *in, double *S)
{
    switch (m) {
    case NBT_GLS_SHINYA:
        return emul_shinya(in, S);
    case NBT_GLS_SHINYA_LITERAL:
        return emul_literal(in, S);
    case NBT_GLS_NAIVE:
        return emul_naive(in, S);
    case NBT_GLS_ELEK:
        return emul_elek(in, S);
    case NBT_GLS_NBT:
        return scatter_emul_nbt(in, NBT_GLS_NBT_SLABS, S);
    }
    return NBT_EINVAL;
}
