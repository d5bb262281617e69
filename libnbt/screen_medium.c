/* libnbt/screen_medium.c: per-pixel moment kernels through a heterogeneous
 * medium (Shinya et al. eq. 28/29), by marching each view ray. */
#include <config.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/screen.h>
#include "internal.h"

static void normalize(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    v[0] /= n, v[1] /= n, v[2] /= n;
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

void nbt_camera_ray(const nbt_camera *cam, size_t w, size_t h, double dtheta, size_t x, size_t y, double dir[3])
{
    double f[3] = {cam->fwd[0], cam->fwd[1], cam->fwd[2]}, r[3], u[3];
    normalize(f);
    cross(f, cam->up, r);
    normalize(r);
    cross(r, f, u);
    double a = ((double)x + 0.5 - 0.5 * (double)w) * dtheta, b = ((double)y + 0.5 - 0.5 * (double)h) * dtheta;
    for (int i = 0; i < 3; i++)
        dir[i] = f[i] + a * r[i] - b * u[i];
    normalize(dir);
}

typedef struct {
    const nbt_screen_input *in;
    const nbt_beam_medium *m;
    nbt_density_fn rho;
    void *ctx;
    const nbt_camera *cam;
    double step, bm, *err_row;
    const float *sky;
    nbt_screen_pixkern *pix;
} march_ctx;

/* eq. 28/29 by the trapezoid rule on n intervals of the samples r[0..N]
 * taken every `stride` (n = N/stride): zeta, M0, M2 at z = D. */
static void moments(const march_ctx *c, const double *r, double *zeta, size_t N, size_t stride, double D,
                    double *M0, double *M2, double *zD)
{
    const nbt_beam_medium *m = c->m;
    double ss = m->albedo * m->sigma_t, sa = m->sigma_t - ss, h = D / (double)(N / stride);
    zeta[0] = 0;
    for (size_t j = stride; j <= N; j += stride)
        zeta[j] = zeta[j - stride] + 0.5 * h * (r[j - stride] + r[j]);
    double Z = zeta[N], I = 0;
    for (size_t j = 0; j <= N; j += stride) {
        if (r[j] == 0)
            continue;
        double y = (double)j / (double)N * D, Ahat = ss * c->bm * (Z - zeta[j]), s = 0;
        for (size_t l = 0; l < m->nlobes; l++) {
            double B = m->B[l], S2 = B + Ahat, C2 = B * y * y * (1.0 - B / S2), d = D - B * y / S2;
            s += m->w[l] * (C2 + d * d * S2);
        }
        double f = 4.0 * r[j] * ss * exp(-ss * zeta[j]) * s;
        I += (j == 0 || j == N ? 0.5 : 1.0) * h * f;
    }
    *M0 = exp(-sa * Z) * -expm1(-ss * Z);
    *M2 = exp(-sa * Z) * I;
    *zD = Z;
}

static nbt_status march_row(size_t y, unsigned thread, void *vp)
{
    (void)thread;
    march_ctx *c = vp;
    const nbt_screen_input *in = c->in;
    double *buf = NULL;
    size_t cap = 0;
    c->err_row[y] = 0;
    for (size_t x = 0; x < in->w; x++) {
        size_t i = y * in->w + x;
        int sky = in->D[i] >= NBT_SCREEN_SKY;
        double dir[3], D = sky ? (c->sky ? c->sky[i] : INFINITY) : in->D[i];
        nbt_camera_ray(c->cam, in->w, in->h, in->dtheta, x, y, dir);
        nbt_screen_pixkern *p = &c->pix[i];
        p->T = isinf(D) ? 0 : 1, p->M0 = 0, p->beta_px = 0;
        if (!(D > 0) || isinf(D))
            continue;
        size_t N = (size_t)ceil(D / c->step);
        if (N < 2)
            N = 2;
        N += N % 2; /* even: the 2-step estimate uses every other sample */
        if (2 * (N + 1) > cap) {
            double *b = realloc(buf, 2 * (N + 1) * sizeof *b);
            if (!b) {
                free(buf);
                NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
            }
            buf = b;
            cap = 2 * (N + 1);
        }
        double *r = buf, *zeta = buf + N + 1;
        /* sample j at beam depth z' = j D/N from the surface, i.e. distance D - z' from the camera */
        for (size_t j = 0; j <= N; j++) {
            double t = D - (double)j / (double)N * D, q[3];
            for (int a = 0; a < 3; a++)
                q[a] = c->cam->pos[a] + t * dir[a];
            double v = c->rho(q, c->ctx);
            r[j] = v > 0 && isfinite(v) ? v : 0.0;
        }
        double M0, M2, Z, M0b, M2b, Zb;
        moments(c, r, zeta, N, 2, D, &M0b, &M2b, &Zb);
        moments(c, r, zeta, N, 1, D, &M0, &M2, &Z);
        p->T = exp(-c->m->sigma_t * Z);
        double alpha, beta;
        nbt_beam_kernel_params(M0, M2, &alpha, &beta);
        p->M0 = beta > 0 ? M0 : 0;
        p->beta_px = beta / (D * in->dtheta);
        double e = 0;
        if (M0 > 0)
            e = fmax(fabs(M0 - M0b) / M0, M2 > 0 ? fabs(M2 - M2b) / M2 : 0) / 3.0;
        c->err_row[y] = fmax(c->err_row[y], e);
    }
    free(buf);
    return NBT_OK;
}

nbt_status nbt_screen_medium_kernels(const nbt_screen_input *in, const nbt_beam_medium *m, nbt_density_fn rho,
                                     void *ctx, const nbt_camera *cam, double step, const float *sky_D,
                                     unsigned nthreads, nbt_screen_pixkern *pix, double *max_err)
{
    nbt_screen_input probe = *in;
    probe.pix = NULL;
    nbt_status st = nbt_screen_check(&probe);
    if (st != NBT_OK)
        return st;
    if ((st = nbt_beam_check(m)) != NBT_OK)
        return st;
    if (!rho || !cam)
        NBT_FAIL(NBT_EINVAL, "screen: a density and a camera are needed");
    if (!(step > 0) || !isfinite(step))
        NBT_FAIL(NBT_EDOM, "screen: step must be finite and > 0");
    for (size_t i = 0; sky_D && i < in->w * in->h; i++)
        if (in->D[i] >= NBT_SCREEN_SKY && !(sky_D[i] >= 0 && isfinite(sky_D[i])))
            NBT_FAIL(NBT_EDOM, "screen: sky_D must be finite and >= 0 at sky pixels");
    double r[3];
    cross(cam->fwd, cam->up, r);
    if (!(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] > 0))
        NBT_FAIL(NBT_EDOM, "screen: the camera's up must not be parallel to its view direction");
    march_ctx c = {in, m, rho, ctx, cam, step, 0, malloc(in->h * sizeof(double)), sky_D, pix};
    if (!c.err_row)
        NBT_FAIL(NBT_ENOMEM, "screen: out of memory");
    for (size_t l = 0; l < m->nlobes; l++)
        c.bm += m->w[l] * m->B[l];
    st = nbt__parallel_for(in->h, nthreads, march_row, &c);
    if (max_err) {
        *max_err = 0;
        for (size_t y = 0; y < in->h; y++)
            *max_err = fmax(*max_err, c.err_row[y]);
    }
    free(c.err_row);
    return st;
}
