/* fit/kernel_model.h: the heuristic kernel averaged over annuli (as photon
 * counting measures it), with derivatives, and its depth correction. */
#ifndef NBT_FIT_KERNEL_MODEL_H
#define NBT_FIT_KERNEL_MODEL_H

/* Mean of Psi = alpha/r G(r/beta) over the annulus lo <= r < hi:
 * (2 pi alpha beta / area) [J(hi/beta) - J(lo/beta)], J(x) = int_0^x G =
 * x G(x) - phi(x) + phi(0); d/dalpha and d/dbeta into *da, *db (may be NULL). */
double kernel_annulus(double alpha, double beta, double lo, double hi, double *da, double *db);

/* Mean of a 2-D Gaussian of total weight M and variance s^2 per axis,
 * M exp(-r^2/2s^2)/(2 pi s^2), over the annulus; derivatives into *dm, *ds. */
double gauss_annulus(double M, double s, double lo, double hi, double *dm, double *ds);

/* Mean of the diffuse part of nbt_beam_fit, M e^{-(q - h)/s}/(2 pi s (h + s)),
 * q = sqrt(r^2 + h^2) (total weight M), over the annulus; derivatives in M, s, h. */
double pexp_annulus(double M, double s, double h, double lo, double hi, double *dm, double *ds, double *dh);

#include "psi_data.h"

/* The fitted shapes: 1 erfc (alpha, beta); 2 erfc2 (alpha1, beta1, alpha2,
 * beta2); 3 erfc+gauss (alpha, beta, M, s). Annulus mean and gradient. */
int shape_params(int shape);
double shape_annulus(int shape, const double *p, double lo, double hi, double *grad);

/* Add sum (2 pi r_c (m - mc))^2 and sum (2 pi r_c mc)^2 over plane j of d,
 * m the shape's annulus mean (0 when p[0] or p[1] is 0). */
void shape_rms_parts(const psi_data *d, size_t j, int shape, const double *p, double *num, double *den);
/* The same for one erfc kernel alpha/r G(r/beta). */
void kernel_rms_parts(const psi_data *d, size_t j, double alpha, double beta, double *num, double *den);
/* sum (2 pi r_c mc)^2 over all planes of d: a fit over several runs scales
 * run d's residuals by 1/sqrt of it, so every run counts by its RMS metric */
double run_rms_den(const psi_data *d);

#endif
