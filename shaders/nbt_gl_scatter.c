/* shaders/nbt_gl_scatter.c: screen-space scattering by GLSL compute shaders
 * (nbt/gl_scatter.h): programs, textures, dispatches, read-back. */
#include <config.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <nbt/screen.h>
#include "nbt/gl_scatter.h"
#include "gl_internal.h"

/* libnbt's error reporting (libnbt/internal.h): the reason goes to the
 * caller's handler (nbt_set_error_handler) */

/* generated from the GLSL modules at build time (nbt_glsl.c) */
extern const char nbt_glsl_nbt_beam[], nbt_glsl_nbt_scatter_common[], nbt_glsl_nbt_scatter_near[],
    nbt_glsl_nbt_scatter_shinya[], nbt_glsl_nbt_scatter_literal[], nbt_glsl_nbt_scatter_pyr0[],
    nbt_glsl_nbt_scatter_down[], nbt_glsl_nbt_scatter_naive[], nbt_glsl_nbt_scatter_elek[],
    nbt_glsl_nbt_scatter_nbtc[], nbt_glsl_nbt_scatter_nbt0[], nbt_glsl_nbt_scatter_nbtdown[],
    nbt_glsl_nbt_scatter_nbtmix[], nbt_glsl_nbt_scatter_nbtup[], nbt_glsl_nbt_scatter_nbtwide[],
    nbt_glsl_nbt_scatter_nbt[];

enum { P_NEAR, P_SHINYA, P_LITERAL, P_PYR0, P_DOWN, P_NAIVE, P_ELEK, P_NBT0, P_NBTDOWN, P_NBTUP, P_NBTWIDE, P_NBT, NPASS };
#define FIRST_NBT_PASS P_NBT0 /* these get nbt_scatter_nbtc too */

static const struct {
    const char *name;
    const char *src;
} PASSES[NPASS] = {
    {"near", nbt_glsl_nbt_scatter_near},       {"shinya", nbt_glsl_nbt_scatter_shinya},
    {"literal", nbt_glsl_nbt_scatter_literal}, {"pyr0", nbt_glsl_nbt_scatter_pyr0},
    {"down", nbt_glsl_nbt_scatter_down},       {"naive", nbt_glsl_nbt_scatter_naive},
    {"elek", nbt_glsl_nbt_scatter_elek},       {"nbt0", nbt_glsl_nbt_scatter_nbt0},
    {"nbtdown", nbt_glsl_nbt_scatter_nbtdown}, {"nbtup", nbt_glsl_nbt_scatter_nbtup},
    {"nbtwide", nbt_glsl_nbt_scatter_nbtwide}, {"nbt", nbt_glsl_nbt_scatter_nbt},
};

static const char *const MNAMES[NBT_GLS_NMETHODS] = {"shinya", "shinya-literal", "naive", "elek", "nbt"};
#define NBT_LAYERS (3 * NBT_GLS_NBT_MAXSLABS + 1)

struct nbt_gls {
    size_t w, h, pw, ph; /* image and padded (pyramid) size */
    GLuint prog[NPASS];
    GLuint tc, tp, tn0, tn1, tlut, tout, tpyr, twb;
    GLuint tnlut, tsrc, tcol; /* nbt: centre table, source pyramid, collapse */
    GLuint ttail;             /* nbt: the atom's tail along a line (the in-slab excess) */
    GLuint tdk;               /* nbt: the depth keys alone (R32F): the march reads 4 bytes a tap, not 16 */
    GLuint stage;             /* nbt: the levels' stores, a band of rows at a time (nbt_sc_put) */
    size_t stage_cap;         /* its size in texels (vec4) */
    unsigned band_rows;       /* a cap on the rows per band (nbt_gls_set_band_rows), 0: none */
    unsigned slabs;
    GLuint stamp[NBT_GLS_MAXPASSES + 1]; /* GL_TIMESTAMP before the passes and after each group */
    const char *pname[NBT_GLS_MAXPASSES]; /* the groups of the last exec */
    double pms[NBT_GLS_MAXPASSES], pcpu[NBT_GLS_MAXPASSES + 1]; /* GPU ms; process CPU s at each stamp */
    unsigned nmark; /* stamps issued in this exec */
    float *buf; /* staging, w*h*4 */
};

const char *nbt_gls_method_name(nbt_gls_method m)
{
    return (unsigned)m < NBT_GLS_NMETHODS ? MNAMES[m] : "?";
}

nbt_status nbt_gls_method_parse(const char *name, nbt_gls_method *m)
{
    for (unsigned i = 0; i < NBT_GLS_NMETHODS; i++)
        if (!strcmp(name, MNAMES[i])) {
            *m = (nbt_gls_method)i;
            return NBT_OK;
        }
    return NBT_EINVAL;
}

unsigned nbt_gls_npasses(void)
{
    return NPASS;
}

const char *nbt_gls_pass_name(unsigned i)
{
    return i < NPASS ? PASSES[i].name : NULL;
}

char *nbt_gls_pass_source(unsigned i)
{
    if (i >= NPASS)
        return NULL;
    char head[900];
    int n = snprintf(head, sizeof head,
                     "#version 430 core\n#define NBT_SC_TAIL_PER %d\n#define NBT_SC_TAIL_N %d\n"
                     "#define NBT_SC_LUT_LO %d\n#define NBT_SC_LUT_PER %d\n#define NBT_SC_LUT_N %d\n"
                     "#define NBT_SC_NAIVE_C %.9g\n#define NBT_SC_ELEK_C %.9g\n#define NBT_SC_NBT_MAXSLABS %d\n"
                     "#define NBT_SC_NBT_LO %d\n#define NBT_SC_NBT_HI %d\n#define NBT_SC_NBT_BLUR %.9g\n#define NBT_SC_NBT_K %d\n"
                     "#define NBT_SC_NBT_NW %d\n#define NBT_SC_NBT_WT %d\n",
                     NBT_GLS_TAIL_PER, NBT_GLS_TAIL_N, NBT_GLS_LUT_LO, NBT_GLS_LUT_PER, NBT_GLS_LUT_N, NBT_GLS_NAIVE_C, NBT_GLS_ELEK_C,
                     NBT_GLS_NBT_MAXSLABS, NBT_GLS_NBT_LO, NBT_GLS_NBT_HI, NBT_GLS_NBT_BLUR, NBT_GLS_K,
                     NBT_GLS_NBT_NW, NBT_GLS_NBT_WT);
    const char *parts[6] = {head, nbt_glsl_nbt_beam, nbt_glsl_nbt_scatter_common,
                            i >= FIRST_NBT_PASS ? nbt_glsl_nbt_scatter_nbtc : "",
                            i == P_NBTUP ? nbt_glsl_nbt_scatter_nbtmix : "", PASSES[i].src};
    size_t len = 1;
    for (int k = 0; k < 6; k++)
        len += strlen(parts[k]) + 1;
    char *s = malloc(len);
    if (!s || n < 0)
        return free(s), NULL;
    s[0] = '\0';
    for (int k = 0; k < 6; k++) {
        strcat(s, parts[k]);
        strcat(s, "\n");
    }
    return s;
}

void nbt_gls_near_table(float *lut)
{
    static const long off[6][2] = {{0, 0}, {1, 0}, {1, 1}, {2, 0}, {2, 1}, {2, 2}};
    for (int i = 0; i < NBT_GLS_LUT_N; i++) {
        double b = exp2(NBT_GLS_LUT_LO + (double)i / NBT_GLS_LUT_PER);
        for (int k = 0; k < 6; k++)
            lut[8 * i + k] = (float)nbt_screen_atom_pixel(NBT_ATOM_ERFC, b, off[k][0], off[k][1]);
        lut[8 * i + 6] = lut[8 * i + 7] = 0.0f;
    }
}

static float nbt_tail_tab[NBT_GLS_TAIL_N];
static pthread_once_t nbt_tail_once = PTHREAD_ONCE_INIT;

static void nbt_tail_fill(void)
{
    /* ∫_0^1 G(v/s) ds by the midpoint rule on 4096 panels (G(v/s) falls
     * smoothly from G(v) to 0 as s goes to 0) */
    for (int k = 0; k < NBT_GLS_TAIL_N; k++) {
        double v = (double)k / NBT_GLS_TAIL_PER, sum = 0;
        for (int j = 0; j < 4096; j++)
            sum += 0.5 * erfc(v / ((j + 0.5) / 4096) / M_SQRT2);
        nbt_tail_tab[k] = (float)(sum / 4096);
    }
}

void nbt_gls_nbt_tail_table(float *t)
{
    pthread_once(&nbt_tail_once, nbt_tail_fill);
    memcpy(t, nbt_tail_tab, sizeof nbt_tail_tab);
}

/* ---- NBT_GLS_NBT: the kernel fit ---- */

#define KB_N 4096 /* 1-D domain of the level kernels: impulse near KB_N/2 */
#define KB_C (KB_N / 2)
static double nbt_kbar_tab[NBT_GLS_NBT_NB][KB_N];
static double nbt_wtab[NBT_GLS_NBT_N * NBT_GLS_NBT_NB];
static pthread_once_t nbt_fit_once = PTHREAD_ONCE_INIT;

void nbt_gls_nbt_wide_taps(int m, double t[NBT_GLS_NBT_WT + 1])
{
    /* sigma 1.5 and 3 texels cut at 9, 6 cut at 18 (3 sigma); taps beyond
     * a kernel's cut are 0 (the wide pass walks only the cut of the
     * widest kernel in use) */
    static const double sig[NBT_GLS_NBT_NW] = {1.5, 3.0, 6.0};
    static const int cut[NBT_GLS_NBT_NW] = {9, 9, 18};
    double s = sig[m], sum = 0;
    for (int d = 0; d <= NBT_GLS_NBT_WT; d++) {
        t[d] = d <= cut[m] ? exp(-0.5 * d * d / (s * s)) : 0.0;
        sum += d ? 2 * t[d] : t[d];
    }
    for (int d = 0; d <= NBT_GLS_NBT_WT; d++)
        t[d] /= sum;
}

/* 1-D kernels U^l [B] D^l of an impulse, averaged over its 2^l phases */
static void nbt_level_kernels(void)
{
    enum { K = NBT_GLS_K, WT = NBT_GLS_NBT_WT };
    static const double F[4] = {0.13, 0.37, 0.37, 0.13};
    static double a[NBT_GLS_K + 1][KB_N];
    double bl = NBT_GLS_NBT_BLUR, t[KB_N], g[WT + 1];
    for (int b = 0; b < NBT_GLS_NBT_NB; b++) {
        int l = b < 2 * K ? b % K + 1 : K, blur = b >= K && b < 2 * K, wide = b >= 2 * K, P = 1 << l;
        if (wide)
            nbt_gls_nbt_wide_taps(b - 2 * K, g);
        memset(nbt_kbar_tab[b], 0, sizeof nbt_kbar_tab[b]);
        for (int ph = 0; ph < P; ph++) {
            memset(a, 0, sizeof a);
            a[0][KB_C + ph] = 1;
            for (int j = 1; j <= l; j++)
                for (int p = 0; p < KB_N >> j; p++) {
                    double s = 0;
                    for (int k = 0; k < 4; k++) {
                        int q = 2 * p - 1 + k;
                        if (q >= 0 && q < KB_N >> (j - 1))
                            s += F[k] * a[j - 1][q];
                    }
                    a[j][p] = s;
                }
            int n = KB_N >> l;
            if (blur) {
                for (int p = 0; p < n; p++)
                    t[p] = (1 - 2 * bl) * a[l][p] + (p > 0 ? bl * a[l][p - 1] : 0) + (p + 1 < n ? bl * a[l][p + 1] : 0);
                memcpy(a[l], t, (size_t)n * sizeof *t);
            }
            if (wide) {
                for (int p = 0; p < n; p++) {
                    t[p] = 0;
                    for (int d = -WT; d <= WT; d++)
                        if (p + d >= 0 && p + d < n)
                            t[p] += g[abs(d)] * a[l][p + d];
                }
                memcpy(a[l], t, (size_t)n * sizeof *t);
            }
            for (int j = l; j >= 1; j--) { /* the bilinear octave up-step */
                int m = KB_N >> (j - 1);
                for (int q = 0; q < m; q++) {
                    int p = q >> 1, o = (q & 1) ? p + 1 : p - 1;
                    a[j - 1][q] = 0.75 * a[j][p] + (o >= 0 && o < m / 2 ? 0.25 * a[j][o] : 0.0);
                }
            }
            for (int x = 0; x < KB_N; x++) {
                int d = x - (KB_C + ph);
                if (d > -KB_C && d < KB_C)
                    nbt_kbar_tab[b][KB_C + d] += a[0][x] / P;
            }
        }
    }
}

double nbt_gls_nbt_kbar(int b, long d)
{
    nbt_gls_nbt_table();
    return b >= 0 && b < NBT_GLS_NBT_NB && labs(d) < KB_C ? nbt_kbar_tab[b][KB_C + d] : 0.0;
}

/* a unit erfc atom over a pixel at r > 4: centre value + laplacian/24 */
static double nbt_far(double b, double r)
{
    double u = r / b, phi = exp(-0.5 * u * u) / 2.50662827463100050, G = 0.5 * erfc(u / sqrt(2.0));
    double lap = u * phi / (b * b * r) + phi / (b * r * r) + G / (r * r * r);
    return (G / r + lap / 24.0) / (2.50662827463100050 * b);
}

/* the fit window's largest half-width: the widest wide kernel reaches
 * about 1300 px (18 texels of 64 px plus the pyramid's up-steps) */
#define NBT_FIT_RMAX 1344
/* windows 5 beta wider than this take the whole RMAX window and share its
 * normal matrix (their atom is < 3e-7 of G(0) beyond 5 beta): each one
 * pixel by pixel up to 1344 px made the fit 15 s instead of 0.3 */
#define NBT_FIT_RRING 640

/* non-negative least squares over the pixels outside the 3x3 centre,
 * |dx|, |dy| <= R (5 beta, 12 .. NBT_FIT_RRING, else NBT_FIT_RMAX), through the normal equations */
static void nbt_fit_one(double beta, double *w)
{
    enum { NB = NBT_GLS_NBT_NB };
    long R = (long)ceil(5 * beta);
    /* kernels wider than NBT_FIT_RRING share the RMAX window (nbt_fit_all
     * runs once, serially). A 1/r
     * weight (relative error per ring) was tried: 64x48 +4.4% -> +3.6%, but
     * 160x120 -0.4% -> -3.0% against operator A at beta_px 800 */
    int ring = R > NBT_FIT_RRING;
    R = R < 12 ? 12 : ring ? NBT_FIT_RMAX : R;
    /* and, beyond r = FB px, their projections f_i t in radial bins of FD
     * px with a first-order term (t is smooth there: relative error ~1e-6),
     * so each later one costs bins, not pixels */
    enum { FB = 16, NBIN = (int)(NBT_FIT_RMAX * 1.4143 - FB) * 2 + 2 };
    const double FD = 0.5;
    static double Fb[NB][NBIN], Fb1[NB][NBIN];
    static int have_ring;
    double G[NB][NB], r[NB], f[NB];
    int binned = ring && have_ring;
    /* the basis is separable, f_i(x, y) = k_i(x) k_i(y), and the window a
     * square less the 3x3 centre: G_ij = S_ij(R)^2 - S_ij(1)^2 with S_ij(R)
     * = sum over |x| <= R of k_i(x) k_j(x) (k even), R NB^2 work, not R^2 */
    for (int i = 0; i < NB; i++)
        for (int j = 0; j <= i; j++) {
            const double *ki = nbt_kbar_tab[i] + KB_C, *kj = nbt_kbar_tab[j] + KB_C;
            double s1 = ki[0] * kj[0] + 2 * ki[1] * kj[1], sR = s1;
            for (long x = 2; x <= R; x++)
                sR += 2 * ki[x] * kj[x];
            G[i][j] = sR * sR - s1 * s1;
        }
    memset(r, 0, sizeof r);
    /* one octant 0 <= y <= x, each pixel counted with its mirror images:
     * the level kernels are even (to 1e-17) and the atom radial */
    for (long y = 0; y <= (binned ? FB : R); y++)
        for (long x = y; x <= (binned ? FB : R); x++) {
            if (x <= 1)
                continue;
            double rr = sqrt((double)(x * x + y * y));
            if (binned && rr > FB)
                continue;
            double t = rr > 4 ? nbt_far(beta, rr) : nbt_screen_atom_pixel(NBT_ATOM_ERFC, beta, x, y);
            for (int i = 0; i < NB; i++)
                f[i] = nbt_kbar_tab[i][KB_C + x] * nbt_kbar_tab[i][KB_C + y];
            double mult = (y > 0 ? 2.0 : 1.0) * (x > y ? 2.0 : 1.0) * 2.0;
            double wt = mult;
            for (int i = 0; i < NB; i++)
                r[i] += wt * f[i] * t;
            if (ring && !have_ring && rr > FB) {
                int k = (int)((rr - FB) / FD);
                double dr = rr - (FB + (k + 0.5) * FD);
                for (int i = 0; i < NB; i++) {
                    Fb[i][k] += wt * f[i];
                    Fb1[i][k] += wt * f[i] * dr;
                }
            }
        }
    for (int k = 0; binned && k < NBIN; k++) {
        double rho = FB + (k + 0.5) * FD, t = nbt_far(beta, rho);
        double dt = (nbt_far(beta, rho + 0.05) - nbt_far(beta, rho - 0.05)) / 0.1;
        for (int i = 0; i < NB; i++)
            r[i] += Fb[i][k] * t + Fb1[i][k] * dt;
    }
    for (int i = 0; i < NB; i++)
        for (int j = i + 1; j < NB; j++)
            G[i][j] = G[j][i];
    have_ring |= ring;
    /* |f w - t|^2 = |L^T w - L^-1 r|^2 + const with G = L L^T: an exact
     * active-set NNLS on the NB x NB factor (cyclic coordinate descent,
     * used before, was far from converged after 3000 sweeps once the wide
     * kernels made the basis near-collinear: +1% mass at beta ~ 100 px) */
    double L[NB][NB], LT[NB * NB], y[NB];
    memset(L, 0, sizeof L);
    for (int i = 0; i < NB; i++) {
        for (int j = 0; j <= i; j++) {
            double s = G[i][j];
            for (int k = 0; k < j; k++)
                s -= L[i][k] * L[j][k];
            L[i][j] = i == j ? sqrt(s > 0 ? s : 0) : L[j][j] > 0 ? s / L[j][j] : 0;
        }
        double s = r[i];
        for (int k = 0; k < i; k++)
            s -= L[i][k] * y[k];
        y[i] = L[i][i] > 0 ? s / L[i][i] : 0;
    }
    for (int i = 0; i < NB; i++)
        for (int j = 0; j < NB; j++)
            LT[i * NB + j] = L[j][i];
    if (nbt__nnls(LT, NB, NB, y, w, NULL) != NBT_OK)
        for (int i = 0; i < NB; i++)
            w[i] = 0;
}

static void nbt_fit_all(void)
{
    nbt_level_kernels();
    for (int i = 0; i < NBT_GLS_NBT_N; i++)
        nbt_fit_one(exp2(NBT_GLS_NBT_LO + (double)i / NBT_GLS_NBT_PER), nbt_wtab + i * NBT_GLS_NBT_NB);
}

const double *nbt_gls_nbt_table(void)
{
    pthread_once(&nbt_fit_once, nbt_fit_all); /* once per process, whichever thread asks first */
    return nbt_wtab;
}

void nbt_gls_nbt_weights(double lb, double *a, double *da)
{
    const double *t = nbt_gls_nbt_table();
    double u = (lb - NBT_GLS_NBT_LO) * NBT_GLS_NBT_PER, f, scale = 1;
    int i, hold = 0;
    if (!(u > 0)) {
        i = 0, f = 0, hold = 1;
    } else if (u >= NBT_GLS_NBT_N - 1) {
        i = NBT_GLS_NBT_N - 2, f = 1, hold = 2;
        scale = exp2(NBT_GLS_NBT_HI - lb);
    } else {
        i = (int)floor(u);
        f = u - i;
    }
    for (int b = 0; b < NBT_GLS_NBT_NB; b++) {
        double t0 = t[i * NBT_GLS_NBT_NB + b], t1 = t[(i + 1) * NBT_GLS_NBT_NB + b];
        a[b] = scale * (t0 + f * (t1 - t0));
        if (da)
            da[b] = hold == 1 ? 0.0 : hold == 2 ? -M_LN2 * a[b] : (t1 - t0) * NBT_GLS_NBT_PER;
    }
}

void nbt_gls_nbt_near_table(float *lut)
{
    static const long off[3][2] = {{0, 0}, {1, 0}, {1, 1}};
    double a[NBT_GLS_NBT_NB];
    for (int i = 0; i < NBT_GLS_LUT_N; i++) {
        double lb = NBT_GLS_LUT_LO + (double)i / NBT_GLS_LUT_PER;
        nbt_gls_nbt_weights(lb, a, NULL);
        for (int k = 0; k < 8; k++)
            lut[8 * i + k] = 0.0f;
        for (int k = 0; k < 3; k++) {
            double v = nbt_screen_atom_pixel(NBT_ATOM_ERFC, exp2(lb), off[k][0], off[k][1]);
            for (int b = 0; b < NBT_GLS_NBT_NB; b++)
                v -= a[b] * nbt_kbar_tab[b][KB_C + off[k][0]] * nbt_kbar_tab[b][KB_C + off[k][1]];
            lut[8 * i + k] = (float)v;
        }
    }
}

static int is_sky(float D);

void nbt_gls_nbt_plan_of(const nbt_gls_input *in, unsigned slabs, nbt_gls_nbt_plan *p)
{
    memset(p, 0, sizeof *p);
    p->n = slabs < 1 ? 1 : slabs > NBT_GLS_NBT_MAXSLABS ? NBT_GLS_NBT_MAXSLABS : slabs;
    float dmin = INFINITY, dmax = 0;
    size_t np = in->w * in->h;
    for (size_t i = 0; i < np; i++)
        if (in->D[i] > 0 && !is_sky(in->D[i])) {
            dmin = fminf(dmin, in->D[i]);
            dmax = fmaxf(dmax, in->D[i]);
        }
    for (unsigned k = 0; k < NBT_GLS_NBT_MAXSLABS; k++)
        p->bound[k] = INFINITY; /* bound[k], k >= 1: the lower bound of slab k; bound[0] unused */
    if (dmax > dmin)
        for (unsigned k = 1; k < p->n; k++)
            p->bound[k] = (float)(dmin * pow((double)dmax / dmin, (double)k / p->n));
    double lo[NBT_GLS_NBT_MAXSLABS], hi[NBT_GLS_NBT_MAXSLABS];
    for (unsigned k = 0; k < p->n; k++)
        lo[k] = INFINITY, hi[k] = -INFINITY;
    for (size_t i = 0; i < np; i++) {
        float D = in->D[i];
        if (!(D > 0) || is_sky(D) || !(in->M0[i] > 0) || !(in->beta_px[i] > 0))
            continue;
        unsigned s = 0;
        for (unsigned k = 1; k < p->n; k++)
            s += p->bound[k] <= D;
        double lb = log2(in->beta_px[i]);
        lo[s] = fmin(lo[s], lb);
        hi[s] = fmax(hi[s], lb);
    }
    for (unsigned k = 0; k < p->n; k++)
        p->lb[k] = lo[k] <= hi[k] ? (float)(0.5 * (lo[k] + hi[k])) : 0.0f;
}

static GLuint compile_pass(unsigned i)
{
    char *src = nbt_gls_pass_source(i);
    if (!src) {
        nbt__fail(NBT_ENOMEM, "gl_scatter: out of memory");
        return 0;
    }
    char what[64];
    snprintf(what, sizeof what, "gl_scatter: pass %s", PASSES[i].name);
    GLuint p = nbt__gl_compute_program(src, what);
    free(src);
    return p;
}

static GLuint make_tex(GLsizei levels, GLenum fmt, size_t w, size_t h, int pyramid)
{
    GLuint t = 0;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexStorage2D(GL_TEXTURE_2D, levels, fmt, (GLsizei)w, (GLsizei)h);
    if (pyramid) {
        static const float zero[4] = {0, 0, 0, 0};
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
        glTexParameterfv(GL_TEXTURE_2D, GL_TEXTURE_BORDER_COLOR, zero);
    } else {
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    return t;
}

/* a 2-D array pyramid: mipmapped, bilinear within a level, zero border */
static GLuint make_arr(GLsizei levels, GLsizei layers, size_t w, size_t h)
{
    static const float zero[4] = {0, 0, 0, 0};
    GLuint t = 0;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D_ARRAY, t);
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, levels, GL_RGBA32F, (GLsizei)w, (GLsizei)h, layers);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
    glTexParameterfv(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_BORDER_COLOR, zero);
    return t;
}

/* a near table (8 floats per entry) as rows: texel (i, 0) = entries 0..3, (i, 1) = 4..7; 0 without memory */
static int upload_lut(GLuint tex, const float *lut)
{
    float *rows = malloc(NBT_GLS_LUT_N * 8 * sizeof *rows);
    if (!rows)
        return 0;
    for (int i = 0; i < NBT_GLS_LUT_N; i++)
        for (int k = 0; k < 4; k++) {
            rows[4 * i + k] = lut[8 * i + k];
            rows[4 * (NBT_GLS_LUT_N + i) + k] = lut[8 * i + 4 + k];
        }
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, NBT_GLS_LUT_N, 2, GL_RGBA, GL_FLOAT, rows);
    free(rows);
    return 1;
}

nbt_status nbt_gls_set_slabs(nbt_gls *g, unsigned slabs)
{
    if (!g || slabs < 1 || slabs > NBT_GLS_NBT_MAXSLABS)
        return nbt__fail(NBT_EDOM, "gl_scatter: slabs must lie in 1 .. NBT_GLS_NBT_MAXSLABS");
    g->slabs = slabs;
    return NBT_OK;
}

nbt_status nbt_gls_set_band_rows(nbt_gls *g, unsigned rows)
{
    if (!g)
        return nbt__fail(NBT_EINVAL, "gl_scatter: no context");
    g->band_rows = rows;
    return NBT_OK;
}

void nbt_gls_free(nbt_gls *g)
{
    if (!g)
        return;
    for (int i = 0; i < NPASS; i++)
        if (g->prog[i])
            glDeleteProgram(g->prog[i]);
    GLuint t[13] = {g->tc, g->tp, g->tn0, g->tn1, g->tlut, g->tout, g->tpyr, g->twb, g->tnlut, g->tsrc, g->tcol, g->ttail, g->tdk};
    for (int i = 0; i < 13; i++)
        if (t[i])
            glDeleteTextures(1, &t[i]);
    if (g->stamp[0])
        glDeleteQueries(NBT_GLS_MAXPASSES + 1, g->stamp);
    if (g->stage)
        glDeleteBuffers(1, &g->stage);
    free(g->buf);
    free(g);
}

nbt_gls *nbt_gls_alloc(size_t w, size_t h)
{
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 43) {
        nbt__fail(NBT_EINVAL, "gl_scatter: needs a current OpenGL >= 4.3 context (compute shaders)");
        return NULL;
    }
    GLint maxsz = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &maxsz);
    size_t pad = (size_t)1 << NBT_GLS_K;
    if (w == 0 || h == 0 || w > (size_t)maxsz - pad || h > (size_t)maxsz - pad) {
        nbt__fail(NBT_EDOM, "gl_scatter: image size outside 1 .. GL_MAX_TEXTURE_SIZE - 64");
        return NULL;
    }
    nbt_gls *g = calloc(1, sizeof *g);
    if (!g || !(g->buf = malloc(w * h * 4 * sizeof *g->buf))) {
        free(g);
        nbt__fail(NBT_ENOMEM, "gl_scatter: out of memory");
        return NULL;
    }
    g->w = w;
    g->h = h;
    g->pw = (w + pad - 1) / pad * pad;
    g->ph = (h + pad - 1) / pad * pad;
    while (glGetError() != GL_NO_ERROR)
        ;
    for (unsigned i = 0; i < NPASS; i++)
        if (!(g->prog[i] = compile_pass(i))) {
            nbt_gls_free(g);
            return NULL;
        }
    glActiveTexture(GL_TEXTURE0);
    g->tc = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tdk = make_tex(1, GL_R32F, w, h, 0);
    g->tp = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tn0 = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tn1 = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tout = make_tex(1, GL_RGBA32F, w, h, 0);
    g->tlut = make_tex(1, GL_RGBA32F, NBT_GLS_LUT_N, 2, 0);
    g->tpyr = make_tex(NBT_GLS_K + 1, GL_RGBA32F, g->pw, g->ph, 1);
    g->twb = make_tex(NBT_GLS_K + 1, GL_RG32F, g->pw, g->ph, 1);
    g->tnlut = make_tex(1, GL_RGBA32F, NBT_GLS_LUT_N, 2, 0);
    /* nbt: pyramid levels 1 .. K as texture levels 0 .. K-1, with a margin texel each side */
    g->tsrc = make_arr(NBT_GLS_K, NBT_LAYERS, g->pw / 2 + pad, g->ph / 2 + pad);
    g->tcol = make_arr(NBT_GLS_K, NBT_LAYERS, g->pw / 2 + pad, g->ph / 2 + pad);
    g->slabs = NBT_GLS_NBT_SLABS;
    /* the staging buffer: a whole level 1 of every layer, or as many rows
     * as one shader storage block holds (at least one) */
    GLint64 maxblk = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &maxblk);
    size_t l1w = (g->pw >> 1) + 2, l1h = (g->ph >> 1) + 2, row = l1w * NBT_LAYERS;
    g->stage_cap = row * l1h;
    if (maxblk > 0 && g->stage_cap > (size_t)maxblk / 16)
        g->stage_cap = (size_t)maxblk / 16 / row * row;
    if (g->stage_cap < row) {
        nbt_gls_free(g);
        nbt__fail(NBT_EDOM, "gl_scatter: image too wide for a shader storage block (GL_MAX_SHADER_STORAGE_BLOCK_SIZE)");
        return NULL;
    }
    glGenBuffers(1, &g->stage);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, g->stage);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(g->stage_cap * 16), NULL, GL_DYNAMIC_COPY);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    float *lut = malloc(NBT_GLS_LUT_N * 8 * sizeof *lut);
    if (!lut) {
        nbt_gls_free(g);
        nbt__fail(NBT_ENOMEM, "gl_scatter: out of memory");
        return NULL;
    }
    nbt_gls_nbt_near_table(lut);
    upload_lut(g->tnlut, lut);
    nbt_gls_near_table(lut);
    /* rows: texel (i, 0) = entries 0..3 of i, (i, 1) = entries 4..7 */
    int ok = upload_lut(g->tlut, lut);
    free(lut);
    /* texel k = (tail[k], tail[k + 1]): one fetch per linear lookup */
    g->ttail = make_tex(1, GL_RG32F, NBT_GLS_TAIL_N - 1, 1, 0);
    float tail[NBT_GLS_TAIL_N], pair[2 * (NBT_GLS_TAIL_N - 1)];
    nbt_gls_nbt_tail_table(tail);
    for (int k = 0; k + 1 < NBT_GLS_TAIL_N; k++)
        pair[2 * k] = tail[k], pair[2 * k + 1] = tail[k + 1];
    glBindTexture(GL_TEXTURE_2D, g->ttail);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, NBT_GLS_TAIL_N - 1, 1, GL_RG, GL_FLOAT, pair);
    glGenQueries(NBT_GLS_MAXPASSES + 1, g->stamp);
    if (!ok || glGetError() != GL_NO_ERROR) {
        nbt_gls_free(g);
        nbt__fail(ok ? NBT_EIO : NBT_ENOMEM, "gl_scatter: creating the textures failed");
        return NULL;
    }
    return g;
}

static int is_sky(float D)
{
    return !(D < (float)NBT_SCREEN_SKY);
}

static nbt_status check_input(nbt_gls_method m, const nbt_gls_input *in)
{
    if ((unsigned)m >= NBT_GLS_NMETHODS)
        return nbt__fail(NBT_EINVAL, "gl_scatter: unknown method");
    if (!in->rgb || !in->D || !in->M0 || !in->beta_px)
        return nbt__fail(NBT_EINVAL, "gl_scatter: rgb, D, M0 and beta_px are required");
    if (m == NBT_GLS_SHINYA_LITERAL && !(in->dtheta > 0 && isfinite(in->dtheta)))
        return nbt__fail(NBT_EDOM, "gl_scatter: dtheta must be finite and > 0");
    if (m == NBT_GLS_SHINYA && !(in->cut > 0 && isfinite(in->cut)))
        return nbt__fail(NBT_EDOM, "gl_scatter: cut must be finite and > 0");
    if (m == NBT_GLS_ELEK && !(in->eps >= 0 && isfinite(in->eps)))
        return nbt__fail(NBT_EDOM, "gl_scatter: eps must be finite and >= 0");
    for (size_t i = 0; i < in->w * in->h; i++) {
        if (!(in->D[i] >= 0))
            return nbt__fail(NBT_EDOM, "gl_scatter: a depth is negative or NaN");
        if (!(in->M0[i] >= 0 && isfinite(in->M0[i])) || !(in->beta_px[i] >= 0 && isfinite(in->beta_px[i])) ||
            (in->sigma_px && !(in->sigma_px[i] >= 0 && isfinite(in->sigma_px[i]))))
            return nbt__fail(NBT_EDOM, "gl_scatter: M0, beta_px and sigma_px must be finite and >= 0");
        for (int c = 0; c < 3; c++)
            if (!isfinite(in->rgb[3 * i + c]))
                return nbt__fail(NBT_EDOM, "gl_scatter: a colour is not finite");
    }
    return NBT_OK;
}

long nbt_gls_window(nbt_gls_method m, const nbt_gls_input *in)
{
    double r = 0, cap = (double)(in->w > in->h ? in->w : in->h);
    for (size_t i = 0; i < in->w * in->h; i++) {
        if (!(in->M0[i] > 0) || is_sky(in->D[i]))
            continue;
        double b = in->beta_px[i];
        if (m == NBT_GLS_SHINYA)
            r = fmax(r, ceil(in->cut * b));
        else if (m == NBT_GLS_SHINYA_LITERAL) /* half-size beta[] / (D dtheta) = 2 beta_px^2 D dtheta */
            r = fmax(r, floor(2.0 * b * b * in->D[i] * in->dtheta) + 1);
    }
    if (m == NBT_GLS_SHINYA)
        r = fmax(r, 2); /* the near taps */
    else if (m != NBT_GLS_SHINYA_LITERAL)
        return 0;
    return (long)fmin(r, cap);
}

static void bind_tex(GLuint unit, GLuint tex)
{
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_2D, tex);
}

/* a GL_TIMESTAMP after the group of passes called name (NULL: the start) */
static void mark(nbt_gls *g, const char *name)
{
    if (g->nmark > NBT_GLS_MAXPASSES)
        return;
    if (name)
        g->pname[g->nmark - 1] = name;
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    g->pcpu[g->nmark] = (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
    glQueryCounter(g->stamp[g->nmark++], GL_TIMESTAMP);
}

static void dispatch(size_t w, size_t h)
{
    glDispatchCompute((GLuint)((w + 7) / 8), (GLuint)((h + 7) / 8), 1);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
}

static void use(const nbt_gls *g, int pass)
{
    GLuint p = g->prog[pass];
    glUseProgram(p);
    glUniform2i(glGetUniformLocation(p, "nbt_sc_size"), (GLint)g->w, (GLint)g->h);
    glUniform2i(glGetUniformLocation(p, "nbt_sc_psize"), (GLint)g->pw, (GLint)g->ph);
    glUniform1i(glGetUniformLocation(p, "nbt_sc_K"), NBT_GLS_K);
}

/* the pyramid: level 0, then K levels (masked for Elek) */
static void build_pyramid(nbt_gls *g, int masked, float eps)
{
    use(g, P_PYR0);
    glBindImageTexture(0, g->tpyr, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, g->twb, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
    dispatch(g->pw, g->ph);
    mark(g, "pyr0");
    use(g, P_DOWN);
    GLuint p = g->prog[P_DOWN];
    glUniform1i(glGetUniformLocation(p, "nbt_sc_masked"), masked);
    glUniform1f(glGetUniformLocation(p, "nbt_sc_eps"), eps);
    for (int k = 1; k <= NBT_GLS_K; k++) {
        size_t sw = g->pw >> (k - 1), sh = g->ph >> (k - 1);
        glUniform2i(glGetUniformLocation(p, "nbt_sc_srcsize"), (GLint)sw, (GLint)sh);
        glUniform2i(glGetUniformLocation(p, "nbt_sc_dstsize"), (GLint)(sw / 2), (GLint)(sh / 2));
        glUniform1f(glGetUniformLocation(p, "nbt_sc_T"), (float)(NBT_GLS_ELEK_C * ldexp(1.0, k - 1)));
        glBindImageTexture(0, g->tpyr, k - 1, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glBindImageTexture(1, g->tpyr, k, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(2, g->twb, k - 1, GL_FALSE, 0, GL_READ_ONLY, GL_RG32F);
        glBindImageTexture(3, g->twb, k, GL_FALSE, 0, GL_WRITE_ONLY, GL_RG32F);
        dispatch(sw / 2, sh / 2);
    }
    mark(g, "down");
}

static void set_plan(const nbt_gls *g, int pass, const nbt_gls_nbt_plan *pl)
{
    GLuint p = g->prog[pass];
    glUniform1i(glGetUniformLocation(p, "nbt_sc_nslab"), (GLint)pl->n);
    glUniform1fv(glGetUniformLocation(p, "nbt_sc_bound"), NBT_GLS_NBT_MAXSLABS, pl->bound);
    glUniform1fv(glGetUniformLocation(p, "nbt_sc_lb"), NBT_GLS_NBT_MAXSLABS, pl->lb);
}

/* one pass that writes every texel of level tlevel of the array texture
 * tex (w x h, layers 0 .. L-1) through nbt_sc_put (per_layer: an
 * invocation per layer, gl_GlobalInvocationID.z): band by band of rows
 * into the staging buffer, each copied into the texture (a buffer store
 * and the copy cost llvmpipe about a tenth of an imageStore) */
static void staged(const nbt_gls *g, GLuint prog, GLuint tex, GLint tlevel, GLint w, GLint h, GLint L, int per_layer)
{
    GLint rows = (GLint)(g->stage_cap / ((size_t)w * (size_t)L)), band = glGetUniformLocation(prog, "nbt_sc_rows");
    if (g->band_rows && rows > (GLint)g->band_rows)
        rows = (GLint)g->band_rows;
    if (rows > h)
        rows = h;
    glActiveTexture(GL_TEXTURE8);
    glBindTexture(GL_TEXTURE_2D_ARRAY, tex);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, g->stage);
    for (GLint y0 = 0; y0 < h; y0 += rows) {
        GLint bh = h - y0 < rows ? h - y0 : rows;
        glUniform3i(band, y0, bh, w);
        glDispatchCompute((GLuint)(w + 7) / 8, (GLuint)(bh + 7) / 8, per_layer ? (GLuint)L : 1);
        glMemoryBarrier(GL_PIXEL_BUFFER_BARRIER_BIT);
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, g->stage);
        glTexSubImage3D(GL_TEXTURE_2D_ARRAY, tlevel, 0, y0, 0, w, bh, L, GL_RGBA, GL_FLOAT, NULL);
        glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
        /* the next band's stores may not overtake this copy (a GPU reads the buffer later) */
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
}

/* method nbt's wide kernels at level K (nbt_scatter_nbtwide), after the
 * collapse's step there; nothing when every wide weight is 0. Returns
 * whether it ran (it leaves its own program in use). */
static int run_nbt_wide(const nbt_gls *g, const nbt_gls_nbt_plan *pl, double a[][NBT_GLS_NBT_NB],
                        double da[][NBT_GLS_NBT_NB])
{
    enum { NW = NBT_GLS_NBT_NW, MS = NBT_GLS_NBT_MAXSLABS, WT = NBT_GLS_NBT_WT, K = NBT_GLS_K };
    float wc[NW * MS] = {0}, wdc[NW * MS] = {0}, wg[NW * (WT + 1)];
    int T = 0; /* the walk: the cut of the widest kernel with a weight, 0: none */
    for (int m = 0; m < NW; m++) {
        double tap[WT + 1];
        int any = 0, cut = 0;
        nbt_gls_nbt_wide_taps(m, tap);
        for (int d = 0; d <= WT; d++) {
            wg[m * (WT + 1) + d] = (float)tap[d];
            cut = tap[d] != 0 ? d : cut;
        }
        for (unsigned j = 0; j < pl->n; j++) {
            wc[m * MS + j] = (float)a[j][2 * K + m];
            wdc[m * MS + j] = (float)da[j][2 * K + m];
            any |= wc[m * MS + j] != 0 || wdc[m * MS + j] != 0;
        }
        T = any && cut > T ? cut : T;
    }
    if (T == 0)
        return 0;
    use(g, P_NBTWIDE);
    set_plan(g, P_NBTWIDE, pl);
    GLuint p = g->prog[P_NBTWIDE];
    glUniform1fv(glGetUniformLocation(p, "nbt_sc_wg"), NW * (WT + 1), wg);
    glUniform1fv(glGetUniformLocation(p, "nbt_sc_wc"), NW * MS, wc);
    glUniform1fv(glGetUniformLocation(p, "nbt_sc_wdc"), NW * MS, wdc);
    glUniform1i(glGetUniformLocation(p, "nbt_sc_wt"), T);
    glUniform2i(glGetUniformLocation(p, "nbt_sc_lsize"), (GLint)((g->pw >> K) + 2), (GLint)((g->ph >> K) + 2));
    glBindImageTexture(0, g->tsrc, K - 1, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
    glBindImageTexture(1, g->tcol, K - 1, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA32F);
    dispatch((g->pw >> K) + 2, (g->ph >> K) + 2);
    return 1;
}

/* method nbt: source pyramid, the collapse from level K to 1 (each level's
 * parts mixed from the source layers in the same pass, never stored), the
 * centre weights, the receivers */
static void run_nbt(nbt_gls *g, const nbt_gls_nbt_plan *pl)
{
    unsigned n = pl->n, L = 3 * n + 1;
    size_t bw = g->pw / 2 + ((size_t)1 << NBT_GLS_K), bh = g->ph / 2 + ((size_t)1 << NBT_GLS_K);
#define EXT(v, k) (((v) >> (k)) + 2) /* physical extent of level k: logical -1 .. n_k */
    use(g, P_NBT0);
    set_plan(g, P_NBT0, pl);
    glUniform2i(glGetUniformLocation(g->prog[P_NBT0], "nbt_sc_lsize"), (GLint)EXT(g->pw, 1), (GLint)EXT(g->ph, 1));
    staged(g, g->prog[P_NBT0], g->tsrc, 0, (GLint)EXT(g->pw, 1), (GLint)EXT(g->ph, 1), (GLint)L, 0);
    mark(g, "nbt0");
    use(g, P_NBTDOWN);
    GLuint p = g->prog[P_NBTDOWN];
    for (int k = 2; k <= NBT_GLS_K; k++) {
        glUniform2i(glGetUniformLocation(p, "nbt_sc_srcsize"), (GLint)EXT(g->pw, k - 1), (GLint)EXT(g->ph, k - 1));
        glUniform2i(glGetUniformLocation(p, "nbt_sc_dstsize"), (GLint)EXT(g->pw, k), (GLint)EXT(g->ph, k));
        glBindImageTexture(0, g->tsrc, k - 2, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
        staged(g, p, g->tsrc, k - 1, (GLint)EXT(g->pw, k), (GLint)EXT(g->ph, k), (GLint)L, 1);
    }
    mark(g, "nbtdown");
    /* the weights of each slab's mid beta and their slopes */
    double a[NBT_GLS_NBT_MAXSLABS][NBT_GLS_NBT_NB], da[NBT_GLS_NBT_MAXSLABS][NBT_GLS_NBT_NB];
    for (unsigned j = 0; j < n; j++)
        nbt_gls_nbt_weights(pl->lb[j], a[j], da[j]);
    use(g, P_NBTUP);
    set_plan(g, P_NBTUP, pl);
    p = g->prog[P_NBTUP];
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D_ARRAY, g->tcol);
    for (int k = NBT_GLS_K; k >= 1; k--) {
        float wa[NBT_GLS_NBT_MAXSLABS] = {0}, wda[NBT_GLS_NBT_MAXSLABS] = {0}, wb[NBT_GLS_NBT_MAXSLABS] = {0},
              wdb[NBT_GLS_NBT_MAXSLABS] = {0};
        for (unsigned j = 0; j < n; j++) {
            wa[j] = (float)a[j][k - 1];
            wda[j] = (float)da[j][k - 1];
            wb[j] = (float)a[j][NBT_GLS_K + k - 1];
            wdb[j] = (float)da[j][NBT_GLS_K + k - 1];
        }
        glUniform1fv(glGetUniformLocation(p, "nbt_sc_wa"), NBT_GLS_NBT_MAXSLABS, wa);
        glUniform1fv(glGetUniformLocation(p, "nbt_sc_wda"), NBT_GLS_NBT_MAXSLABS, wda);
        glUniform1fv(glGetUniformLocation(p, "nbt_sc_wb"), NBT_GLS_NBT_MAXSLABS, wb);
        glUniform1fv(glGetUniformLocation(p, "nbt_sc_wdb"), NBT_GLS_NBT_MAXSLABS, wdb);
        glUniform2i(glGetUniformLocation(p, "nbt_sc_lsize"), (GLint)EXT(g->pw, k), (GLint)EXT(g->ph, k));
        glUniform2i(glGetUniformLocation(p, "nbt_sc_usize"), (GLint)(bw >> k), (GLint)(bh >> k));
        glUniform1i(glGetUniformLocation(p, "nbt_sc_level"), k);
        glBindImageTexture(0, g->tsrc, k - 1, GL_TRUE, 0, GL_READ_ONLY, GL_RGBA32F);
        staged(g, p, g->tcol, k - 1, (GLint)EXT(g->pw, k), (GLint)EXT(g->ph, k), (GLint)(3 * n), 0);
        if (k == NBT_GLS_K && run_nbt_wide(g, pl, a, da)) {
            use(g, P_NBTUP); /* back to the collapse for levels K - 1 .. 1 */
            set_plan(g, P_NBTUP, pl);
        }
    }
    mark(g, "nbtup");
    use(g, P_NEAR);
    glUniform1i(glGetUniformLocation(g->prog[P_NEAR], "nbt_sc_only0"), 1); /* a store per pixel less */
    bind_tex(2, g->tnlut);
    glBindImageTexture(0, g->tn0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, g->tn1, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(g->w, g->h);
    mark(g, "near");
    use(g, P_NBT);
    set_plan(g, P_NBT, pl);
    glUniform2i(glGetUniformLocation(g->prog[P_NBT], "nbt_sc_usize"), (GLint)bw, (GLint)bh);
#undef EXT
    bind_tex(4, g->tn0);
    bind_tex(5, g->tlut);  /* the atom's 3x3 weights and */
    bind_tex(6, g->ttail); /* its tail: the in-slab excess */
    bind_tex(9, g->tdk);   /* the depth keys for the march */
    glActiveTexture(GL_TEXTURE7);
    glBindTexture(GL_TEXTURE_2D_ARRAY, g->tsrc); /* and the slabs' colours */
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D_ARRAY, g->tcol);
    glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(g->w, g->h);
    mark(g, "nbt");
    bind_tex(2, g->tlut);
    glActiveTexture(GL_TEXTURE7);
    glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D_ARRAY, 0);
}

nbt_status nbt_gls_exec(nbt_gls *g, nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms)
{
    if (!g || in->w != g->w || in->h != g->h)
        return nbt__fail(NBT_EINVAL, "gl_scatter: the input's size is not the context's");
    g->nmark = 0; /* a refused input leaves no pass times behind */
    nbt_status st = check_input(m, in);
    if (st != NBT_OK)
        return st;
    size_t w = g->w, h = g->h, np = w * h;
    while (glGetError() != GL_NO_ERROR)
        ;
    /* upload: (r, g, b, depth key) and (M0, beta_px, sigma_px, 0) */
    glActiveTexture(GL_TEXTURE0);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    for (size_t i = 0; i < np; i++) {
        for (int c = 0; c < 3; c++)
            g->buf[4 * i + c] = in->rgb[3 * i + c];
        g->buf[4 * i + 3] = is_sky(in->D[i]) ? 1e30f : in->D[i];
    }
    glBindTexture(GL_TEXTURE_2D, g->tc);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT, g->buf);
    if (m == NBT_GLS_NBT) { /* the depth keys alone, in place (i <= 4i + 3) */
        for (size_t i = 0; i < np; i++)
            g->buf[i] = g->buf[4 * i + 3];
        glBindTexture(GL_TEXTURE_2D, g->tdk);
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RED, GL_FLOAT, g->buf);
    }
    for (size_t i = 0; i < np; i++) {
        g->buf[4 * i] = in->M0[i];
        g->buf[4 * i + 1] = in->beta_px[i];
        g->buf[4 * i + 2] = in->sigma_px ? in->sigma_px[i] : (float)(in->beta_px[i] / sqrt(3.0));
        g->buf[4 * i + 3] = 0.0f;
    }
    glBindTexture(GL_TEXTURE_2D, g->tp);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_FLOAT, g->buf);
    bind_tex(0, g->tc);
    bind_tex(1, g->tp);
    bind_tex(2, g->tlut);
    long R = nbt_gls_window(m, in);
    nbt_gls_nbt_plan plan;
    if (m == NBT_GLS_NBT)
        nbt_gls_nbt_plan_of(in, g->slabs, &plan);

    /* timestamps, not GL_TIME_ELAPSED: llvmpipe reports 1 ns elapsed for
     * compute-only work, while its timestamps (and a GPU's) bracket it */
    g->nmark = 0;
    mark(g, NULL);
    switch (m) {
    case NBT_GLS_SHINYA:
        use(g, P_NEAR);
        glUniform1i(glGetUniformLocation(g->prog[P_NEAR], "nbt_sc_only0"), 0);
        glBindImageTexture(0, g->tn0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, g->tn1, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        mark(g, "near");
        use(g, P_SHINYA);
        bind_tex(3, g->tn0);
        bind_tex(4, g->tn1);
        glUniform1i(glGetUniformLocation(g->prog[P_SHINYA], "nbt_sc_R"), (GLint)R);
        glUniform1f(glGetUniformLocation(g->prog[P_SHINYA], "nbt_sc_cut"), (float)in->cut);
        glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        mark(g, "shinya");
        break;
    case NBT_GLS_SHINYA_LITERAL:
        use(g, P_LITERAL);
        glUniform1i(glGetUniformLocation(g->prog[P_LITERAL], "nbt_sc_R"), (GLint)R);
        glUniform1f(glGetUniformLocation(g->prog[P_LITERAL], "nbt_sc_dtheta"), (float)in->dtheta);
        glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        mark(g, "literal");
        break;
    case NBT_GLS_NAIVE:
    case NBT_GLS_ELEK: {
        int elek = m == NBT_GLS_ELEK;
        build_pyramid(g, elek, (float)in->eps);
        int pass = elek ? P_ELEK : P_NAIVE;
        use(g, pass);
        bind_tex(2, g->tpyr);
        bind_tex(3, g->twb);
        glBindImageTexture(0, g->tout, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
        mark(g, PASSES[pass].name);
        break;
    }
    case NBT_GLS_NBT:
        run_nbt(g, &plan);
        break;
    }
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, g->tout);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, g->buf);
    for (size_t i = 0; i < np; i++)
        for (int c = 0; c < 3; c++)
            S[3 * i + c] = g->buf[4 * i + c];
    GLuint64 t0 = 0, t1 = 0;
    glGetQueryObjectui64v(g->stamp[0], GL_QUERY_RESULT, &t0);
    for (unsigned k = 1; k < g->nmark; k++, t0 = t1) {
        glGetQueryObjectui64v(g->stamp[k], GL_QUERY_RESULT, &t1);
        g->pms[k - 1] = t1 > t0 ? (double)(t1 - t0) * 1e-6 : 0.0;
    }
    if (gpu_ms) {
        *gpu_ms = 0;
        for (unsigned k = 1; k < g->nmark; k++)
            *gpu_ms += g->pms[k - 1];
    }
    glUseProgram(0);
    if (glGetError() != GL_NO_ERROR)
        return nbt__fail(NBT_EIO, "gl_scatter: a GL call failed");
    return NBT_OK;
}

unsigned nbt_gls_pass_times(const nbt_gls *g, const char **names, double *ms, double *cpu_ms, unsigned max)
{
    unsigned n = g && g->nmark > 0 ? g->nmark - 1 : 0;
    for (unsigned k = 0; k < n && k < max; k++) {
        if (names)
            names[k] = g->pname[k];
        if (ms)
            ms[k] = g->pms[k];
        if (cpu_ms)
            cpu_ms[k] = 1e3 * (g->pcpu[k + 1] - g->pcpu[k]);
    }
    return n;
}

nbt_status nbt_gls_run(nbt_gls_method m, const nbt_gls_input *in, float *S, double *gpu_ms)
{
    nbt_gls *g = nbt_gls_alloc(in->w, in->h);
    if (!g)
        return NBT_EINVAL;
    nbt_status st = nbt_gls_exec(g, m, in, S, gpu_ms);
    nbt_gls_free(g);
    return st;
}
