/* libnbt/beam.c: narrow beam moments and kernels (Shinya et al. sec. 3). */
#include <config.h>
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/beam.h>
#include <nbt/phase.h>
#include <nbt/quad.h>
#include "internal.h"

nbt_beam_medium nbt_beam_homogeneous(double sigma_t, double albedo, double B)
{
    nbt_beam_medium m;
    memset(&m, 0, sizeof m);
    m.sigma_t = sigma_t;
    m.albedo = albedo;
    m.nlobes = 1;
    m.w[0] = 1.0;
    m.B[0] = B;
    return m;
}

nbt_status nbt_beam_check(const nbt_beam_medium *m)
{
    if (!(m->sigma_t > 0) || !isfinite(m->sigma_t))
        return nbt__failv(NBT_EDOM, "beam: sigma_t = %g is not accepted: finite and > 0", m->sigma_t);
    if (!(m->albedo >= 0 && m->albedo <= 1))
        return nbt__failv(NBT_EDOM, "beam: albedo = %g is not accepted: in [0, 1]", m->albedo);
    if (m->nlobes < 1 || m->nlobes > NBT_BEAM_MAX_LOBES)
        return nbt__failv(NBT_EDOM, "beam: %zu Gaussian lobes are not accepted: 1 to %d", m->nlobes,
                          NBT_BEAM_MAX_LOBES);
    double sw = 0;
    for (size_t i = 0; i < m->nlobes; i++) {
        if (!(m->w[i] >= 0) || !isfinite(m->w[i]))
            return nbt__failv(NBT_EDOM, "beam: lobe %zu's weight w = %g is not accepted: finite and >= 0", i, m->w[i]);
        if (!(m->B[i] > 0) || !isfinite(m->B[i]))
            return nbt__failv(NBT_EDOM, "beam: lobe %zu's spread B = %g is not accepted: finite and > 0", i, m->B[i]);
        sw += m->w[i];
    }
    if (fabs(sw - 1) > 1e-12)
        return nbt__failv(NBT_EDOM, "beam: lobe weights summing to %.15g are not accepted: they must sum to 1", sw);
    if (m->nlayers > 0 && !m->rho_fn) {
        if (!m->z || !m->rho)
            NBT_FAIL(NBT_EDOM, "beam: layers need their boundaries z and a density per layer (z or rho is NULL)");
        if (m->z[0] != 0)
            return nbt__failv(NBT_EDOM, "beam: the first layer boundary z[0] = %g is not accepted: it must be 0",
                              m->z[0]);
        for (size_t i = 0; i < m->nlayers; i++) {
            if (!(m->rho[i] >= 0) || !isfinite(m->rho[i]))
                return nbt__failv(NBT_EDOM, "beam: layer %zu's density rho = %g is not accepted: finite and >= 0", i,
                                  m->rho[i]);
            if (!isfinite(m->z[i]))
                return nbt__failv(NBT_EDOM, "beam: layer boundary z[%zu] = %g is not accepted: finite", i, m->z[i]);
            if (i > 0 && !(m->z[i] > m->z[i - 1]))
                return nbt__failv(NBT_EDOM, "beam: layer boundary z[%zu] = %g is not accepted: boundaries must "
                                  "increase (z[%zu] = %g)", i, m->z[i], i - 1, m->z[i - 1]);
        }
    }
    return NBT_OK;
}

static double rho_at(const nbt_beam_medium *m, double z)
{
    if (m->rho_fn) {
        double r = m->rho_fn(z, m->rho_data);
        return r > 0 && isfinite(r) ? r : 0.0;
    }
    if (m->nlayers == 0)
        return 1.0;
    size_t i = m->nlayers - 1;
    while (i > 0 && z < m->z[i])
        i--;
    return m->rho[i];
}

static int rho_f(double z, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    f[0] = rho_at(vp, z);
    return 0;
}

double nbt_beam_zeta(const nbt_beam_medium *m, double z)
{
    if (m->rho_fn) {
        nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 200);
        double v = NAN, e;
        if (ws && z > 0)
            nbt_quad_gk(ws, rho_f, (void *)m, 1, 0.0, z, 1e-15, 1e-12, &v, &e);
        else if (z <= 0)
            v = 0;
        nbt_quad_ws_free(ws);
        return v;
    }
    if (m->nlayers == 0)
        return z;
    double s = 0;
    for (size_t i = 0; i < m->nlayers && m->z[i] < z; i++) {
        double hi = i + 1 < m->nlayers ? fmin(m->z[i + 1], z) : z;
        s += m->rho[i] * (hi - m->z[i]);
    }
    return s;
}

static double bmix(const nbt_beam_medium *m)
{
    double b = 0;
    for (size_t i = 0; i < m->nlobes; i++)
        b += m->w[i] * m->B[i];
    return b;
}

/* Layer boundaries inside (0, z) as quadrature breakpoints. */
static size_t breakpoints(const nbt_beam_medium *m, double z, double *pts, size_t max)
{
    size_t n = 0;
    if (m->rho_fn)
        return 0;
    for (size_t i = 1; i < m->nlayers && n < max; i++)
        if (m->z[i] > 0 && m->z[i] < z)
            pts[n++] = m->z[i];
    return n;
}

typedef struct {
    const nbt_beam_medium *m;
    double z, zeta_z, ss, bm, r;
    nbt_beam_model model;
} line_ctx;

/* eq. 29 integrand (Ishimaru), or the random walk's, at depth y */
static int m2_f(double y, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const line_ctx *c = vp;
    double rho = rho_at(c->m, y);
    if (rho == 0) {
        f[0] = 0;
        return 0;
    }
    double zy = nbt_beam_zeta(c->m, y);
    if (c->model == NBT_BEAM_SMALLANGLE) {
        f[0] = 4.0 * c->bm * c->ss * rho * (c->z - y) * (c->z - y);
        return 0;
    }
    double Ahat = c->ss * c->bm * (c->zeta_z - zy), s = 0;
    for (size_t i = 0; i < c->m->nlobes; i++) {
        double B = c->m->B[i], S2 = B + Ahat, C2 = B * y * y * (1.0 - B / S2), d = c->z - B * y / S2;
        s += c->m->w[i] * (C2 + d * d * S2);
    }
    f[0] = 4.0 * rho * c->ss * exp(-c->ss * zy) * s;
    return 0;
}

nbt_status nbt_beam_moments(const nbt_beam_medium *m, nbt_beam_model model, double z, double *M0,
                            double *M2, double *err)
{
    nbt_status st = nbt_beam_check(m);
    if (st != NBT_OK)
        return st;
    if (!(z >= 0) || !isfinite(z))
        NBT_FAIL(NBT_EDOM, "beam: z must be finite and >= 0");
    double ss = m->albedo * m->sigma_t, sa = m->sigma_t - ss, zeta = nbt_beam_zeta(m, z), bm = bmix(m);
    /* e^{-sa zeta} (1 - e^{-ss zeta}) without cancellation at small zeta */
    *M0 = exp(-sa * zeta) * -expm1(-ss * zeta);
    if (err)
        *err = 0;
    if (m->nlayers == 0 && !m->rho_fn) {
        double e = exp(-sa * z);
        if (model == NBT_BEAM_SMALLANGLE) {
            *M2 = e * 4.0 / 3.0 * ss * bm * z * z * z;
            return NBT_OK;
        }
        /* eq. 26 with A = ss B: 4 e^{-sa z} [e^{-az}(A z^2/a - 2B/a^2) + 2B/a^2 - 2Bz/a + (B - A/a) z^2 + A z^3].
         * For a z small the bracket cancels to O(z^3): use its series there. */
        double a = ss, A = ss * bm, B = bm, az = a * z;
        if (a == 0) {
            *M2 = 0;
        } else if (az < 0.5) {
            /* The n = 0..2 terms of e^{-x}, x = a z, cancel the polynomial
             * analytically, leaving A a z^4/2 + sum_{n>=3} (-x)^n/n! (A z^2/a - 2B/a^2):
             * no cancellation (leading term B a z^3/3, single scattering). */
            double x = az, c = A * z * z / a - 2.0 * B / (a * a), t = x * x * x / 6.0, br = A * a * z * z * z * z / 2.0;
            for (int n = 3; n < 40; n++) {
                br += ((n % 2) ? -t : t) * c;
                t *= x / (n + 1);
            }
            *M2 = 4.0 * e * br;
        } else {
            double ea = exp(-az);
            *M2 = 4.0 * e * (ea * (A * z * z / a - 2.0 * B / (a * a)) + 2.0 * B / (a * a) - 2.0 * B * z / a +
                             (B - A / a) * z * z + A * z * z * z);
        }
        return NBT_OK;
    }
    line_ctx c = {m, z, zeta, ss, bm, 0, model};
    double pts[64], r, e;
    size_t np = breakpoints(m, z, pts, 64);
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 2000);
    if (!ws)
        NBT_FAIL(NBT_ENOMEM, "beam: out of memory");
    st = nbt_quad_gk_pts(ws, m2_f, &c, 1, 0.0, z, pts, np, 0.0, 1e-11, &r, &e);
    nbt_quad_ws_free(ws);
    double pre = exp(-sa * zeta);
    *M2 = pre * r;
    if (err)
        *err = pre * e;
    return st;
}

void nbt_beam_kernel_params(double M0, double M2, double *alpha, double *beta)
{
    if (!(M0 > 0) || !(M2 > 0)) {
        *alpha = *beta = 0;
        return;
    }
    *beta = sqrt(1.5 * M2 / M0);
    *alpha = M0 / (sqrt(2.0 * NBT_PI) * *beta);
}

/* G(x) = erfc(x/sqrt 2)/2 */
static double G(double x)
{
    return 0.5 * erfc(x / sqrt(2.0));
}

double nbt_beam_kernel(double alpha, double beta, double r)
{
    if (!(beta > 0) || !(r > 0))
        return 0;
    return alpha / r * G(r / beta);
}

/* Psi_lineint integrand: rho e^{-ss zeta(z')} sum_i w_i exp(-r^2/4W_i^2)/W_i^2 */
static int lineint_f(double y, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const line_ctx *c = vp;
    double rho = rho_at(c->m, y), s = 0;
    if (rho > 0) {
        double zy = nbt_beam_zeta(c->m, y), Ahat = c->ss * c->bm * (c->zeta_z - zy);
        for (size_t i = 0; i < c->m->nlobes; i++) {
            double B = c->m->B[i], S2 = B + Ahat, C2 = B * y * y * (1.0 - B / S2), d = c->z - B * y / S2;
            double W2 = C2 + d * d * S2;
            if (W2 > 0)
                s += c->m->w[i] * exp(-c->r * c->r / (4.0 * W2)) / W2;
        }
        s *= rho * exp(-c->ss * zy);
    }
    f[0] = s;
    return 0;
}

/* single scattering at depth y: rho(y) e^{...} p2D(r/(z-y))/(z-y)^2 */
static int single_f(double y, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const line_ctx *c = vp;
    double rho = rho_at(c->m, y), d = c->z - y, s = 0;
    if (rho > 0 && d > 0) {
        double q = c->r / d;
        for (size_t i = 0; i < c->m->nlobes; i++)
            s += c->m->w[i] * exp(-q * q / (4.0 * c->m->B[i])) / (4.0 * NBT_PI * c->m->B[i]);
        s *= rho / (d * d);
    }
    f[0] = s;
    return 0;
}

nbt_status nbt_beam_psi(const nbt_beam_medium *m, nbt_psi_model model, double z, double r, double *psi,
                        double *err)
{
    nbt_status st = nbt_beam_check(m);
    if (st != NBT_OK)
        return st;
    if (!(z > 0) || !isfinite(z) || !(r > 0) || !isfinite(r))
        NBT_FAIL(NBT_EDOM, "beam: Psi needs finite z > 0 and r > 0");
    double ss = m->albedo * m->sigma_t, sa = m->sigma_t - ss, zeta = nbt_beam_zeta(m, z), bm = bmix(m);
    if (err)
        *err = 0;
    double M0, M2, alpha, beta;
    switch (model) {
    case NBT_PSI_ISHIMARU:
    case NBT_PSI_SMALLANGLE:
        st = nbt_beam_moments(m, model == NBT_PSI_ISHIMARU ? NBT_BEAM_ISHIMARU : NBT_BEAM_SMALLANGLE, z, &M0, &M2, err);
        nbt_beam_kernel_params(M0, M2, &alpha, &beta);
        *psi = nbt_beam_kernel(alpha, beta, r);
        return st;
    case NBT_PSI_ELEK: {
        double b[2] = {0, 0};
        nbt_phase *p = nbt_phase_sog(m->nlobes, m->w, m->B);
        if (!p)
            NBT_FAIL(NBT_ENOMEM, "beam: out of memory");
        st = nbt_phase_moments(p, 1, b);
        nbt_phase_free(p);
        double g = b[1];
        nbt_beam_moments(m, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
        /* eq. 2 is for homogeneous media: layers enter through their mean density */
        double rho = zeta / z, s = z;
        double inv = 2.0 * sa * rho / (3.0 * s) + (ss > 0 && rho > 0 ? 4.0 / (s * s * s * ss * rho * (1.0 - g)) : INFINITY);
        double W2 = 0.5 / inv;
        *psi = W2 > 0 ? M0 * exp(-r * r / (2.0 * W2)) / (2.0 * NBT_PI * W2) : 0.0;
        return st;
    }
    case NBT_PSI_SINGLE:
        if (m->nlayers == 0 && !m->rho_fn) {
            double s = 0;
            for (size_t i = 0; i < m->nlobes; i++)
                s += m->w[i] / (2.0 * sqrt(NBT_PI * m->B[i])) * G(r / (z * sqrt(2.0 * m->B[i])));
            *psi = ss * exp(-m->sigma_t * z) * s / r;
            return NBT_OK;
        }
        /* fall through to quadrature */
        break;
    case NBT_PSI_LINEINT:
        break;
    default:
        NBT_FAIL(NBT_EINVAL, "beam: unknown Psi model");
    }
    line_ctx c = {m, z, zeta, ss, bm, r, NBT_BEAM_ISHIMARU};
    double pts[64], v, e;
    size_t np = breakpoints(m, z, pts, 64);
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 4000);
    if (!ws)
        NBT_FAIL(NBT_ENOMEM, "beam: out of memory");
    st = nbt_quad_gk_pts(ws, model == NBT_PSI_SINGLE ? single_f : lineint_f, &c, 1, 0.0, z, pts, np, 1e-300, 1e-10,
                         &v, &e);
    nbt_quad_ws_free(ws);
    double pre = model == NBT_PSI_SINGLE ? ss * exp(-m->sigma_t * zeta) : ss * exp(-sa * zeta) / (4.0 * NBT_PI);
    *psi = pre * v;
    if (err)
        *err = pre * e;
    return st;
}

double nbt_beam_direct(const nbt_beam_medium *m, double z)
{
    return exp(-m->sigma_t * nbt_beam_zeta(m, z));
}

static int density_row(size_t i, double z, double rho, double prev, char *why, size_t n)
{
    if (i == 0 && z != 0)
        snprintf(why, n, "the first z = %.17g is not accepted: the first z must be 0", z);
    else if (i > 0 && !(z > prev))
        snprintf(why, n, "z = %.17g is not accepted: z must increase (the previous z is %.17g)", z, prev);
    else if (rho < 0)
        snprintf(why, n, "rho = %.17g is not accepted: rho must be >= 0", rho);
    else
        return 0;
    return 1;
}

nbt_status nbt_density_read(const char *path, double **z, double **rho, size_t *n, char *err, size_t errlen)
{
    return nbt__read_columns(path, "density file", "z rho", density_row, z, rho, n, err, errlen);
}

void nbt_kernel_correction_terms(double tau, double albedo, double B, double *t)
{
    double x = log(tau), b = log(B);
    t[0] = 1;
    t[1] = x;
    t[2] = x * x;
    t[3] = albedo;
    t[4] = albedo * x;
    t[5] = b;
    t[6] = b * x;
}

nbt_status nbt_kernel_corrected(const nbt_kernel_correction *c, const nbt_beam_medium *m, double z, double *alpha,
                                double *beta)
{
    double M0, M2;
    nbt_status st = nbt_beam_moments(m, NBT_BEAM_ISHIMARU, z, &M0, &M2, NULL);
    if (st != NBT_OK)
        return st;
    nbt_beam_kernel_params(M0, M2, alpha, beta);
    if (!c || !(z > 0))
        return NBT_OK;
    double t[NBT_KERNEL_CORR_TERMS], la = 0, lb = 0;
    nbt_kernel_correction_terms(m->sigma_t * nbt_beam_zeta(m, z), m->albedo, bmix(m), t);
    for (int i = 0; i < NBT_KERNEL_CORR_TERMS; i++) {
        la += c->alpha[i] * t[i];
        lb += c->beta[i] * t[i];
    }
    *alpha *= exp(la);
    *beta *= exp(lb);
    return NBT_OK;
}

nbt_status nbt_kernel_correction_read(const char *path, nbt_kernel_correction *c, char *err, size_t errlen)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        int e = errno;
        snprintf(err, errlen, "kernel correction '%s' cannot be opened: %s", path, strerror(e));
        return nbt__io_status(e);
    }
    char line[1024];
    int got = 0, ln = 0;
    nbt_status st = NBT_OK;
    /* strict, as the other text inputs: every line is blank, a '#' comment,
     * or one 'beta' / 'alpha' line of exactly 7 finite numbers; a mistyped
     * key, an eighth number or a second 'alpha' is an error, not skipped */
    while (st == NBT_OK && fgets(line, sizeof line, f)) {
        ln++;
        char *h = strchr(line, '#');
        if (h)
            *h = '\0';
        size_t len = strlen(line);
        while (len > 0 && isspace((unsigned char)line[len - 1]))
            line[--len] = '\0';
        char *p = line;
        while (isspace((unsigned char)*p))
            p++;
        if (*p == '\0')
            continue;
        int which = !strncmp(p, "beta", 4) && isspace((unsigned char)p[4]) ? 1
                    : !strncmp(p, "alpha", 5) && isspace((unsigned char)p[5]) ? 2 : 0;
        if (!which || (got & which)) {
            snprintf(err, errlen, "kernel correction '%s' line %d: '%.40s' is not accepted: %s", path, ln, p,
                     which ? "a second line of the same key" : "expected a 'beta' or 'alpha' line of 7 numbers");
            st = NBT_EFORMAT;
            break;
        }
        double *dst = which == 1 ? c->beta : c->alpha;
        p += which == 1 ? 4 : 5;
        for (int i = 0; i <= NBT_KERNEL_CORR_TERMS && st == NBT_OK; i++) {
            char *end;
            double v = strtod(p, &end);
            int number = end != p;
            if (i == NBT_KERNEL_CORR_TERMS ? number : !number || !isfinite(v)) {
                snprintf(err, errlen, "kernel correction '%s' line %d: expected %d finite numbers after '%s'", path,
                         ln, NBT_KERNEL_CORR_TERMS, which == 1 ? "beta" : "alpha");
                st = NBT_EFORMAT;
            } else if (i < NBT_KERNEL_CORR_TERMS)
                dst[i] = v;
            p = end;
        }
        while (st == NBT_OK && isspace((unsigned char)*p))
            p++;
        if (st == NBT_OK && *p != '\0') {
            snprintf(err, errlen, "kernel correction '%s' line %d: '%.40s' after the %d numbers is not accepted", path,
                     ln, p, NBT_KERNEL_CORR_TERMS);
            st = NBT_EFORMAT;
        }
        got |= which;
    }
    if (st == NBT_OK && ferror(f)) {
        snprintf(err, errlen, "kernel correction '%s' cannot be read: %s", path, strerror(errno));
        st = NBT_EIO;
    }
    fclose(f);
    if (st == NBT_OK && got != 3) {
        snprintf(err, errlen, "kernel correction '%s': needs a 'beta' and an 'alpha' line", path);
        st = NBT_EFORMAT;
    }
    return st;
}
