/* libnbt/screen_fft.c: the screen-space operators for layered depth by FFT
 * convolution (FFTW). With layers sorted near to far, a receiver in layer i
 * gets (operator A)  sum_{j<i} K_j * c_j + K_i * (sum_{j>=i} c_j),
 * or (operator B) sum_j K_j * c_j. Both sums are accumulated in frequency
 * space, so a layer costs one kernel, three colour and three inverse
 * transforms. Zero padding to at least w + R (R the widest kernel's
 * truncation) makes the cyclic convolution linear on the image: light
 * scattered off screen is lost, as in the brute force. */
#include <config.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <fftw3.h>
#include <nbt/screen.h>
#include "internal.h"
#include "screen_internal.h"

/* FFTW's planner is not thread-safe; execution with new arrays is. */
static pthread_mutex_t plan_lock = PTHREAD_MUTEX_INITIALIZER;

static size_t good_size(size_t n)
{
    for (;; n++) {
        size_t m = n;
        while (m % 2 == 0)
            m /= 2;
        while (m % 3 == 0)
            m /= 3;
        while (m % 5 == 0)
            m /= 5;
        while (m % 7 == 0)
            m /= 7;
        if (m == 1)
            return n;
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

typedef struct {
    const nbt_screen_input *in;
    nbt_screen_rule rule;
    size_t px, py, nc, layer;
    long rx, ry; /* kernel extent kept: min(R, image size - 1) per axis */
    const unsigned short *lid;
    const nbt__pkern *pk; /* [layer * nk + kernel channel] */
    unsigned nk;          /* kernels per layer: 1 (grey) or 3 (RGB) */
    double *rbuf[6];
    fftw_complex *K[3], *Ci[3], *A[3], *Cs[3], *out[3];
    fftw_plan fwd, inv;
    double *S;
} fft_ctx;

/* task 0..2: colour channel of the current layer; 3..3+nk-1: its kernels */
static nbt_status forward_task(size_t t, unsigned thread, void *vp)
{
    (void)thread;
    fft_ctx *f = vp;
    const nbt_screen_input *in = f->in;
    double *r = f->rbuf[t];
    memset(r, 0, f->px * f->py * sizeof *r);
    if (t >= 3) {
        const nbt__pkern *pk = &f->pk[f->layer * f->nk + (t - 3)];
        double *wq = NULL, *cell = NULL;
        size_t cap = 0;
        nbt_status st = pk->n ? nbt__pixel_weights(pk, &wq, &cell, &cap) : NBT_OK;
        if (st == NBT_OK && pk->n)
            for (long dy = -(pk->R < f->ry ? pk->R : f->ry); dy <= pk->R && dy <= f->ry; dy++)
                for (long dx = -(pk->R < f->rx ? pk->R : f->rx); dx <= pk->R && dx <= f->rx; dx++) {
                    size_t X = (size_t)((dx + (long)f->px) % (long)f->px), Y = (size_t)((dy + (long)f->py) % (long)f->py);
                    r[Y * f->px + X] = wq[labs(dy) * (pk->R + 1) + labs(dx)];
                }
        free(wq);
        free(cell);
        if (st == NBT_OK)
            fftw_execute_dft_r2c(f->fwd, r, f->K[t - 3]);
        return st;
    }
    for (size_t y = 0; y < in->h; y++)
        for (size_t x = 0; x < in->w; x++) {
            size_t i = y * in->w + x;
            if (f->lid[i] == f->layer)
                r[y * f->px + x] = in->rgb[3 * i + t];
        }
    fftw_execute_dft_r2c(f->fwd, r, f->Ci[t]);
    return NBT_OK;
}

/* per channel: combine in frequency space, invert, keep this layer's pixels */
static nbt_status combine_task(size_t ch, unsigned thread, void *vp)
{
    (void)thread;
    fft_ctx *f = vp;
    fftw_complex *K = f->K[f->nk == 3 ? ch : 0], *C = f->Ci[ch], *A = f->A[ch], *Cs = f->Cs[ch], *o = f->out[ch];
    for (size_t i = 0; i < f->nc; i++) {
        double kr = K[i][0], ki = K[i][1];
        if (f->rule == NBT_SCREEN_NEAR) {
            o[i][0] = A[i][0] + kr * Cs[i][0] - ki * Cs[i][1];
            o[i][1] = A[i][1] + kr * Cs[i][1] + ki * Cs[i][0];
            Cs[i][0] -= C[i][0];
            Cs[i][1] -= C[i][1];
        }
        A[i][0] += kr * C[i][0] - ki * C[i][1];
        A[i][1] += kr * C[i][1] + ki * C[i][0];
    }
    if (f->rule != NBT_SCREEN_NEAR)
        return NBT_OK;
    const nbt_screen_input *in = f->in;
    double *r = f->rbuf[ch], norm = 1.0 / ((double)f->px * (double)f->py);
    fftw_execute_dft_c2r(f->inv, o, r);
    for (size_t y = 0; y < in->h; y++)
        for (size_t x = 0; x < in->w; x++) {
            size_t i = y * in->w + x;
            if (f->lid[i] == f->layer)
                f->S[3 * i + ch] = r[y * f->px + x] * norm;
        }
    return NBT_OK;
}

/* operator B: all layers summed in A; one inverse per channel at the end */
static nbt_status final_task(size_t ch, unsigned thread, void *vp)
{
    (void)thread;
    fft_ctx *f = vp;
    const nbt_screen_input *in = f->in;
    double *r = f->rbuf[ch], norm = 1.0 / ((double)f->px * (double)f->py);
    memcpy(f->out[ch], f->A[ch], f->nc * sizeof(fftw_complex));
    fftw_execute_dft_c2r(f->inv, f->out[ch], r);
    for (size_t y = 0; y < in->h; y++)
        for (size_t x = 0; x < in->w; x++)
            f->S[3 * (y * in->w + x) + ch] = r[y * f->px + x] * norm;
    return NBT_OK;
}

nbt_status nbt_screen_layered(const nbt_screen_input *in, const nbt_screen_kernel *k, nbt_screen_rule rule,
                              double tail, size_t max_layers, unsigned nthreads, double *S, double *T)
{
    nbt_status st = nbt_screen_check(in);
    if (st != NBT_OK)
        return st;
    if (!(tail > 0 && tail < 1))
        NBT_FAIL(NBT_EDOM, "screen: tail must lie in (0, 1)");
    if (in->pix || !k)
        NBT_FAIL(NBT_EINVAL, "screen: the layered FFT needs one kernel per depth (no per-pixel kernels)");
    if (max_layers < 1 || max_layers > 4096)
        NBT_FAIL(NBT_EDOM, "screen: max_layers must lie in [1, 4096]");
    size_t np = in->w * in->h, nl = 0;
    double *keys = malloc(np * sizeof *keys);
    unsigned short *lid = malloc(np * sizeof *lid);
    nbt__pkern *pk = NULL;
    fft_ctx f;
    memset(&f, 0, sizeof f);
    if (!keys || !lid) {
        st = nbt__fail(NBT_ENOMEM, "screen: out of memory");
        goto done;
    }
    for (size_t i = 0; i < np; i++)
        keys[i] = nbt__depth_key(in->D[i]);
    qsort(keys, np, sizeof *keys, cmp_double);
    for (size_t i = 0; i < np; i++)
        if (i == 0 || keys[i] != keys[i - 1])
            keys[nl++] = keys[i];
    if (nl > max_layers) {
        st = nbt__fail(NBT_EDOM, "screen: the depth map has more distinct depths than layers allowed");
        goto done;
    }
    for (size_t i = 0; i < np; i++) {
        double key = nbt__depth_key(in->D[i]);
        size_t lo = 0, hi = nl - 1;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (keys[mid] < key)
                lo = mid + 1;
            else
                hi = mid;
        }
        lid[i] = (unsigned short)lo;
    }
    unsigned nk = nbt_screen_kernel_channels(k);
    pk = malloc(nl * nk * sizeof *pk);
    if (!pk) {
        st = nbt__fail(NBT_ENOMEM, "screen: out of memory");
        goto done;
    }
    long R = 0;
    for (size_t l = 0; l < nl * nk && st == NBT_OK; l++) {
        double D = keys[l / nk];
        st = nbt__pixel_kernel(k, (unsigned)(l % nk), isinf(D) ? INFINITY : D, in->dtheta, tail, nbt__clip(in), &pk[l]);
        if (pk[l].n && pk[l].R > R)
            R = pk[l].R;
    }
    if (st != NBT_OK)
        goto done;
    if (T)
        for (size_t i = 0; i < np; i++)
            T[i] = pk[lid[i] * nk].T;
    f.in = in;
    f.rule = rule;
    f.lid = lid;
    f.pk = pk;
    f.nk = nk;
    f.S = S;
    f.rx = R < (long)in->w - 1 ? R : (long)in->w - 1;
    f.ry = R < (long)in->h - 1 ? R : (long)in->h - 1;
    f.px = good_size(in->w + (size_t)f.rx);
    f.py = good_size(in->h + (size_t)f.ry);
    f.nc = f.py * (f.px / 2 + 1);
    for (unsigned i = 0; i < 3 + nk; i++)
        if (!(f.rbuf[i] = fftw_malloc(f.px * f.py * sizeof(double))))
            st = NBT_ENOMEM;
    for (unsigned i = 0; i < nk; i++)
        if (!(f.K[i] = fftw_malloc(f.nc * sizeof(fftw_complex))))
            st = NBT_ENOMEM;
    for (int c = 0; c < 3; c++) {
        f.Ci[c] = fftw_malloc(f.nc * sizeof(fftw_complex));
        f.A[c] = fftw_malloc(f.nc * sizeof(fftw_complex));
        f.Cs[c] = fftw_malloc(f.nc * sizeof(fftw_complex));
        f.out[c] = fftw_malloc(f.nc * sizeof(fftw_complex));
        if (!f.Ci[c] || !f.A[c] || !f.Cs[c] || !f.out[c])
            st = NBT_ENOMEM;
    }
    if (st != NBT_OK) {
        st = nbt__fail(NBT_ENOMEM, "screen: out of memory for the FFT buffers");
        goto done;
    }
    pthread_mutex_lock(&plan_lock);
    f.fwd = fftw_plan_dft_r2c_2d((int)f.py, (int)f.px, f.rbuf[0], f.K[0], FFTW_ESTIMATE);
    f.inv = fftw_plan_dft_c2r_2d((int)f.py, (int)f.px, f.out[0], f.rbuf[0], FFTW_ESTIMATE);
    pthread_mutex_unlock(&plan_lock);
    if (!f.fwd || !f.inv) {
        st = nbt__fail(NBT_ENOMEM, "screen: FFTW could not plan the transforms");
        goto done;
    }
    /* the suffix sum starts as the whole image */
    for (int c = 0; c < 3; c++) {
        memset(f.A[c], 0, f.nc * sizeof(fftw_complex));
        double *r = f.rbuf[c];
        memset(r, 0, f.px * f.py * sizeof *r);
        for (size_t y = 0; y < in->h; y++)
            for (size_t x = 0; x < in->w; x++)
                r[y * f.px + x] = in->rgb[3 * (y * in->w + x) + c];
        fftw_execute_dft_r2c(f.fwd, r, f.Cs[c]);
    }
    for (size_t l = 0; l < nl && st == NBT_OK; l++) {
        f.layer = l;
        st = nbt__parallel_for(3 + nk, nthreads, forward_task, &f);
        if (st == NBT_OK)
            st = nbt__parallel_for(3, nthreads, combine_task, &f);
    }
    if (st == NBT_OK && rule != NBT_SCREEN_NEAR)
        st = nbt__parallel_for(3, nthreads, final_task, &f);
done:
    pthread_mutex_lock(&plan_lock);
    if (f.fwd)
        fftw_destroy_plan(f.fwd);
    if (f.inv)
        fftw_destroy_plan(f.inv);
    pthread_mutex_unlock(&plan_lock);
    for (int i = 0; i < 6; i++)
        fftw_free(f.rbuf[i]);
    for (int i = 0; i < 3; i++)
        fftw_free(f.K[i]);
    for (int c = 0; c < 3; c++) {
        fftw_free(f.Ci[c]);
        fftw_free(f.A[c]);
        fftw_free(f.Cs[c]);
        fftw_free(f.out[c]);
    }
    free(keys);
    free(lid);
    free(pk);
    return st;
}
