/* nbt/mc.h: photon counting, the ground truth for the beam models.
 *
 * A pencil beam enters at the origin along +z. The medium fills z >= 0 with
 * density rho(z) (layers as in nbt/beam.h; for a slab, rho = 1 on [0, d] and
 * vacuum elsewhere); z < 0 is vacuum. Photons scatter with the given phase
 * function and are absorbed with probability 1 - albedo per interaction
 * (analog: every tally is a count, so results are exactly reproducible;
 * the weighted estimator below keeps photons and lowers their weight).
 * Without a slab, a photon is followed until absorbed, escaped through
 * z = 0, or deeper than z_cut (default twice the last tally plane plus 20
 * mean free paths at density 1), from where its return is not counted.
 *
 * With `infinite` set the medium fills all space (a source inside fog):
 * for z < 0 the density is the density at z = 0+ (the first layer's, or
 * rho_fn(0)), so photons that go back behind the source keep scattering and
 * may return; they are dropped below -z_cut. Tallies are the same (only
 * forward crossings of planes z_j > 0 count). A slab cannot be infinite.
 *
 * Tallies on planes z_j: every forward crossing (mu > 0) by a photon that
 * has scattered at least once adds 1/(N * annulus area) to the radial bin
 * of its crossing radius, r in [0, F z_j) in equal bins, so Psi is per unit
 * area per launched photon; M0 and M2 count all radii. Standard errors come
 * from 64 fixed batches (by photon index), so results are identical for
 * any thread count (and any split over processes, see nbt_mc_run_part). */
#ifndef NBT_MC_H
#define NBT_MC_H

#include <stddef.h>
#include <stdint.h>
#include <nbt/error.h>
#include <nbt/phase.h>

#ifdef __cplusplus
extern "C" {
#endif

/* How a photon's absorption is counted. */
typedef enum {
    NBT_MC_ANALOG = 0,  /* absorbed by chance (1 - albedo per interaction); every tally a count */
    NBT_MC_WEIGHTED = 1 /* survival biasing: never absorbed, its weight w (from 1) is multiplied by
                         * the albedo at every interaction and tallies add w; below w = 1e-4 (or
                         * roulette_weight) Russian roulette keeps it with probability 1/10 at
                         * weight 10 w (MCML's rule), so every tally keeps its expectation */
} nbt_mc_estimator;

typedef struct {
    double sigma_t;          /* extinction at unit density, > 0 */
    double albedo;           /* [0, 1] */
    const nbt_phase *phase;  /* any phase function; sampled exactly */
    size_t nlayers;          /* 0: rho = 1 for z >= 0 */
    const double *z, *rho;   /* layers: z[0] = 0 < z[1] < ..., density per layer */
    /* or a continuous density for z >= 0 (overrides the layers): sampled by
     * delta (Woodcock) tracking against the bound rho_max >= rho_fn(z);
     * a value above the bound makes the run fail with NBT_EDOM */
    double (*rho_fn)(double z, void *data);
    void *rho_data;
    double rho_max;
    double slab;             /* > 0: slab of this thickness (overrides layers), R and T tallied */
    size_t nplanes;          /* tally planes (may be 0 with a slab) */
    const double *z_planes;  /* increasing, > 0 */
    size_t r_bins;           /* radial bins per plane, >= 1 */
    double r_max_scale;      /* F: r range [0, F z_j), > 0 */
    double z_cut;            /* 0: default (see above) */
    uint64_t photons;        /* >= 64 */
    uint64_t seed;
    unsigned threads;        /* 0: all CPUs */
    /* optional progress callback, called from the calling thread with the
     * fraction of photons done (counted every 256 photons on every thread,
     * not only as batches end: the calling thread reports between its own
     * photons, and about every 0.25 s while the last batches run on other
     * threads), at least once with 1 at the end; may be NULL */
    void (*progress)(double fraction, void *data);
    void *progress_data;
    int infinite;            /* nonzero: the medium fills all space (see above); not with a slab */
    /* 0: every scattering order; n >= 1: a photon is dropped at the
     * interaction that would scatter it an (n+1)-th time, so tallies hold
     * orders 1..n only (R and T: photons scattered at most n times) */
    unsigned order_max;
    nbt_mc_estimator estimator; /* default (0): analog; either is deterministic per seed */
    double roulette_weight;     /* weighted: roulette below this weight; 0: 1e-4 (MCML's); must be < 1 */
} nbt_mc_config;

typedef struct {
    size_t nplanes, r_bins;
    double *psi, *psi_se;    /* [plane * r_bins + bin] */
    double *M0, *M0_se, *M2, *M2_se; /* per plane */
    double R, R_se, T, T_se; /* slab only: reflected, transmitted (unscattered included) */
    double seconds;          /* wall time of the run */
    uint64_t interactions;   /* total scattering + absorption events */
} nbt_mc_result;

nbt_status nbt_mc_run(const nbt_mc_config *cfg, nbt_mc_result **out);
void nbt_mc_result_free(nbt_mc_result *r);

/* One run split over processes or machines (nbt-fit mc does this over MPI
 * ranks; libnbt itself knows nothing of MPI). A run is NBT_MC_BATCHES fixed
 * batches of photon indices, batch b holding photons
 * [N b / 64, N (b + 1) / 64). Its raw tally is nbt_mc_tally_len(cfg)
 * doubles, one slice per batch (counts, and sums of r^2 for M2), each slice
 * filled in photon order by one thread. nbt_mc_run_part(cfg, b0, b1, tally)
 * overwrites the slices of batches [b0, b1) and leaves the others alone
 * (b0 == b1: nothing to do, NBT_OK). Parts run anywhere and combined slice by
 * slice (copied, or summed element-wise where every other part holds zeros:
 * x + 0 = x exactly) give the very array one process computes, and
 * nbt_mc_finish turns it into a result equal bit for bit to nbt_mc_run's
 * (seconds = 0: the caller times). nbt_mc_part_range gives part p of n
 * parts (p < n) its batches; parts beyond the 64th are empty. The progress
 * callback of a part reports the fraction of that part's photons. */
#define NBT_MC_BATCHES 64
size_t nbt_mc_tally_len(const nbt_mc_config *cfg);
void nbt_mc_part_range(size_t part, size_t nparts, size_t *b0, size_t *b1);
nbt_status nbt_mc_run_part(const nbt_mc_config *cfg, size_t b0, size_t b1, double *tally);
nbt_status nbt_mc_finish(const nbt_mc_config *cfg, const double *tally, nbt_mc_result **out);


/* Photon counts of screen kernels (nbt/screen.h's fitted higher orders):
 * a pencil beam at the origin along +z in a homogeneous medium of unit
 * extinction (lengths are optical depths), filling all space (infinite: the
 * camera inside the medium) or z >= 0 only (the medium starts at the
 * camera; a path that returns through z = 0 escapes). Plane z_j stands for
 * an emitting wall that ends a path: only a photon's FIRST crossing of it
 * counts, and only if it has scattered before (a first crossing by the
 * unscattered beam is the direct part). Every photon runs at albedo 1; a
 * crossing after n scatterings adds albedo_k^n to the tally of albedo k,
 * which is the analog count at that albedo (so one set of paths serves
 * every albedo). Radius bins in units of z_j: bin 0 is [0, e_0), bin b is
 * [e_{b-1}, e_b), the last [e_{nedges-1}, inf). A path is followed until it
 * has crossed every plane, escapes, drops below -z_cut (infinite; 0: twice
 * the last plane + 20), or has scattered order_max times (0: until the
 * largest albedo's weight is below 1e-9; an albedo of 1 needs a cap); the
 * weight of paths cut at order_max is reported as a bound of what they
 * could still add. Deterministic per seed for any thread count. */
typedef struct {
    const nbt_phase *phase;
    int infinite;
    size_t nplanes;
    const double *z_planes;   /* optical depths, increasing, > 0 */
    size_t nedges;
    const double *edges;      /* bin edges in units of z_j, increasing, > 0 */
    size_t nalbedo;
    const double *albedo;     /* in [0, 1] */
    unsigned order_max;
    double z_cut;
    uint64_t photons, seed;   /* photons >= 16 */
    unsigned threads;         /* 0: all CPUs */
    void (*progress)(double fraction, void *data);
    void *progress_data;
} nbt_mc_kernel_config;

typedef struct {
    size_t nplanes, nalbedo, nbins; /* nbins = nedges + 1 */
    /* the mass (per launched photon) of first crossings in each bin and its
     * standard error, [((plane * nalbedo + k) * 2 + o) * nbins + bin],
     * o = 0: after exactly one scattering, o = 1: after two or more */
    double *mass, *mass_se;
    double *lost;       /* per albedo: weight of the paths cut at order_max, per photon */
    unsigned order_max; /* the cap used */
} nbt_mc_kernel_result;

nbt_status nbt_mc_kernel_run(const nbt_mc_kernel_config *cfg, nbt_mc_kernel_result **out);
void nbt_mc_kernel_result_free(nbt_mc_kernel_result *r);

#ifdef __cplusplus
}
#endif
#endif
