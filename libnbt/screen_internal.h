/* libnbt/screen_internal.h: what screen.c shares with screen_fft.c; not installed. */
#ifndef NBT_SCREEN_INTERNAL_H
#define NBT_SCREEN_INTERNAL_H

#include <stddef.h>
#include <nbt/screen.h>

/* Gauss-Legendre points per octave panel of an erfc atom's deviation range */
#define SCREEN_GL 12
#define SCREEN_MAX_NODES 1024

/* A kernel at one pixel's depth, in pixel units, as a mixture of Gaussians:
 * weight(dx, dy) = sum_n wt[n] cell(sig[n], dx) cell(sig[n], dy). */
typedef struct {
    double T, mass, radius; /* radius: the widest atom's beta or sigma, pixels */
    long R;                 /* truncation: offsets |dx|, |dy| <= R */
    size_t n;
    double sig[SCREEN_MAX_NODES], wt[SCREEN_MAX_NODES];
} nbt__pkern;

/* Gauss-Legendre nodes and weights on [-1, 1]. */
void nbt__gl_nodes(size_t n, double *x, double *w);
/* Integral of a unit 1-D Gaussian of deviation s over [d - 1/2, d + 1/2] (s = 0: a delta). */
double nbt__gauss_cell(double s, long d);
/* An evaluated kernel as Gaussian nodes in units of px (world length per pixel). */
size_t nbt__kern_nodes(const nbt_screen_kern *kn, double px, double *sig, double *wt, size_t max);
/* The kernel of a pixel at depth D; R is clipped to clip (offsets beyond the
 * image's size never pair two of its pixels). */
nbt_status nbt__pixel_kernel(const nbt_screen_kernel *k, double D, double dtheta, double tail, long clip,
                             nbt__pkern *pk);
/* The kernel of pixel i of the input: its own (in->pix) or the family's at its depth. */
nbt_status nbt__input_kernel(const nbt_screen_kernel *k, const nbt_screen_input *in, size_t i, double tail,
                             nbt__pkern *pk);
/* Quadrant weights (*wq)[j*(R+1) + i] of offsets (i, j) >= 0; buffers grow as needed. */
nbt_status nbt__pixel_weights(const nbt__pkern *pk, double **wq, double **cell, size_t *cap);
/* The largest offset two pixels of the image can have. */
long nbt__clip(const nbt_screen_input *in);
/* Depth for ordering: sky as +infinity. */
double nbt__depth_key(float D);

#endif
