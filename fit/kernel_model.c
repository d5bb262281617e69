/* fit/kernel_model.c: annulus averages of the heuristic kernel. */
#include <config.h>
#include <math.h>
#include "kernel_model.h"

static double G(double x)
{
    return 0.5 * erfc(x / sqrt(2.0));
}

static double phi(double x)
{
    return exp(-0.5 * x * x) / sqrt(2.0 * M_PI);
}

static double J(double x)
{
    return x * G(x) - phi(x) + phi(0);
}

double kernel_annulus(double alpha, double beta, double lo, double hi, double *da, double *db)
{
    double area = M_PI * (hi * hi - lo * lo), xl = lo / beta, xh = hi / beta;
    double base = 2.0 * M_PI * beta / area * (J(xh) - J(xl));
    if (da)
        *da = base;
    if (db)
        *db = 2.0 * M_PI * alpha / area * (phi(xl) - phi(xh));
    return alpha * base;
}

double gauss_annulus(double M, double s, double lo, double hi, double *dm, double *ds)
{
    double area = M_PI * (hi * hi - lo * lo), el = exp(-lo * lo / (2 * s * s)), eh = exp(-hi * hi / (2 * s * s));
    double base = (el - eh) / area;
    if (dm)
        *dm = base;
    if (ds)
        *ds = M / area * (el * lo * lo - eh * hi * hi) / (s * s * s);
    return M * base;
}

/* mass fraction outside r of the diffuse part: ((q + s)/(h + s)) e^{-(q - h)/s}, q = sqrt(r^2 + h^2),
 * with its log-derivatives in s and h */
static double pexp_outside(double r, double s, double h, double *ls, double *lh)
{
    double q = sqrt(r * r + h * h), qh = r * r / (q + h); /* q - h */
    *ls = 1 / (q + s) - 1 / (h + s) + qh / (s * s);
    *lh = (h / q) / (q + s) - 1 / (h + s) + qh / (q * s);
    return (q + s) / (h + s) * exp(-qh / s);
}

double pexp_annulus(double M, double s, double h, double lo, double hi, double *dm, double *ds, double *dh)
{
    double area = M_PI * (hi * hi - lo * lo), sl, hl, sh, hh;
    double fl = pexp_outside(lo, s, h, &sl, &hl), fh = pexp_outside(hi, s, h, &sh, &hh);
    if (dm)
        *dm = (fl - fh) / area;
    if (ds)
        *ds = M * (fl * sl - fh * sh) / area;
    if (dh)
        *dh = M * (fl * hl - fh * hh) / area;
    return M * (fl - fh) / area;
}

double shape_annulus(int shape, const double *p, double lo, double hi, double *grad)
{
    double m = kernel_annulus(p[0], p[1], lo, hi, grad ? &grad[0] : NULL, grad ? &grad[1] : NULL);
    if (shape == 2)
        m += kernel_annulus(p[2], p[3], lo, hi, grad ? &grad[2] : NULL, grad ? &grad[3] : NULL);
    else if (shape == 3)
        m += gauss_annulus(p[2], p[3], lo, hi, grad ? &grad[2] : NULL, grad ? &grad[3] : NULL);
    return m;
}

int shape_params(int shape)
{
    return shape == 1 ? 2 : 4;
}

void shape_rms_parts(const psi_data *d, size_t j, int shape, const double *p, double *num, double *den)
{
    for (size_t k = 0; k < d->nbins; k++) {
        size_t i = j * d->nbins + k;
        double w = M_PI * (d->lo[i] + d->hi[i]); /* 2 pi r_c */
        double m = p[0] > 0 && p[1] > 0 ? shape_annulus(shape, p, d->lo[i], d->hi[i], NULL) : 0;
        *num += w * w * (m - d->psi[i]) * (m - d->psi[i]);
        *den += w * w * d->psi[i] * d->psi[i];
    }
}

void kernel_rms_parts(const psi_data *d, size_t j, double alpha, double beta, double *num, double *den)
{
    double p[2] = {alpha, beta};
    shape_rms_parts(d, j, 1, p, num, den);
}

double run_rms_den(const psi_data *d)
{
    double num = 0, den = 0;
    for (size_t j = 0; j < d->nplanes; j++)
        kernel_rms_parts(d, j, 0, 0, &num, &den);
    return den;
}
