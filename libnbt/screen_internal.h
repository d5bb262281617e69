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
/* The kernel of a pixel at depth D in channel ch; R is clipped to clip (offsets beyond the
 * image's size never pair two of its pixels). */
nbt_status nbt__pixel_kernel(const nbt_screen_kernel *k, unsigned ch, double D, double dtheta, double tail, long clip,
                             nbt__pkern *pk);
/* The kernel of pixel i of the input in channel ch: its own (in->pix) or the family's at its depth. */
nbt_status nbt__input_kernel(const nbt_screen_kernel *k, unsigned ch, const nbt_screen_input *in, size_t i, double tail,
                             nbt__pkern *pk);
/* Quadrant weights (*wq)[j*(R+1) + i] of offsets (i, j) >= 0; buffers grow as needed. */
nbt_status nbt__pixel_weights(const nbt__pkern *pk, double **wq, double **cell, size_t *cap);
/* The largest offset two pixels of the image can have. */
long nbt__clip(const nbt_screen_input *in);
/* Depth for ordering: sky as +infinity. */
double nbt__depth_key(float D);


/* Appends an atom (dropped unless mass and scale are > 0 and finite, or when full). */
void nbt__add_atom(nbt_screen_kern *o, nbt_atom_shape s, double mass, double scale);
/* Mass of a unit atom outside radius a * scale. */
double nbt__atom_tail(nbt_atom_shape shape, double a);

/* A kernel family for a phase (screen_phase.c): the first order's shapes
 * cached per depth node (filled on first use, thread-safe), and the model. */
typedef struct nbt__phase_kern nbt__phase_kern;
nbt__phase_kern *nbt__phase_kern_alloc(const nbt_phase *p, double sigma_t, double albedo, nbt_screen_geometry geo,
                                       const nbt_screen_model *model);
void nbt__phase_kern_free(nbt__phase_kern *k);
nbt_status nbt__phase_kern_eval(nbt__phase_kern *k, double D, nbt_screen_kern *o);
double nbt__phase_kern_first_mass(const nbt__phase_kern *k, double D);

/* screen_model.c: the family parameter of p if the model covers it (else
 * NBT_EDOM through the error handler), and the higher orders at a parameter. */
nbt_status nbt__screen_model_param(const nbt_screen_model *m, const nbt_phase *p, nbt_screen_geometry geo,
                                   double *param);
nbt_status nbt__screen_model_eval(const nbt_screen_model *m, double param, nbt_screen_geometry geo, double albedo,
                                  double tau, nbt_screen_shape *out);

#endif
