/* nbt/plan.h: the table planner, FFTW's plan/execute for lookup tables.
 *
 * A scene description (the keys of nbt-gen's scene files, doc/scene-format.md)
 * or a list of table requests goes in; a plan comes out: which table sets
 * (H or J^n), how many Legendre orders, axis ranges, mappings and sizes, with
 * a predicted interpolation error and a predicted build time for each. One
 * call then builds a set (or all of them) as nbt_table objects, ready for
 * nbt_table_write_exr or the lookup functions.
 *
 * How it plans (doc/tables.md, "The planner"):
 *  - Legendre terms (scenes with a g range): the smallest N whose airlight
 *    series truncation stays below tol/2 on sample rays; every table then
 *    gets tol/2 over the error amplification A = sum_{k<N} (2k+1)|g|^k.
 *  - Mappings by rule (measured, doc/tables.md): u/T log1p_cbrt with
 *    c = max(xmax, 10) (second order at u, T = 0); v/theta cos, linear
 *    for J^1.
 *  - Size (tol > 0): all packs are built at 33^2 (error measured at all cell
 *    and edge midpoints); where the set may reach 65^2 also at 65^2, which
 *    gives the convergence rate p (else p = 1.75). The
 *    plan takes the smallest size on the ladder 33, 49, 65, 97, ..., 2049
 *    where err(33) (32/(N-1))^p meets tol. At a fixed size the same fit
 *    predicts the error. The proxy builds are kept: executing at 33^2 or
 *    65^2 copies them.
 *  - Cost: the 33^2 build's time scaled as N^a (a from the two builds, or
 *    2 for H, 1.1 for J, whose work is mostly per row).
 * Execution measures the real error (as every table build does); when a set
 * planned for tol misses it, the set grows along the ladder until it meets
 * tol (NBT_ETOL past 2049 nodes). Plans hold borrowed phase pointers: keep
 * the phase alive until the plan is freed. Thread-safe: no global state. */
#ifndef NBT_PLAN_H
#define NBT_PLAN_H

#include <stddef.h>
#include <nbt/error.h>
#include <nbt/phase.h>
#include <nbt/table.h>

#ifdef __cplusplus
extern "C" {
#endif

/* libnbt-gl's airlight and surface shaders take at most 4 RGBA packs of
 * Legendre orders per kind (GLSL 3.30 indexes sampler arrays with constant
 * expressions only): the default orders_max of a scene. */
#define NBT_PLAN_GL_ORDERS 16
/* Most packs of four orders in one set (512 orders). */
#define NBT_PLAN_MAX_PACKS 128
#define NBT_SCENE_MAX_PHONG 16

/* A scene: the keys of a scene file. */
typedef struct {
    double kappa_t[2];        /* extinction range [lo, hi], 0 <= lo <= hi <= 1e3, hi > 0 [1/length] */
    double kappa_s[2];        /* scattering range, hi <= kappa_t[1]; kappa_s[1] < 0: not given */
    double distance[2];       /* largest viewer-source and source-surface distance, hi > 0 */
    int have_g;               /* 1: Legendre tables serving HG g in [g[0], g[1]] at run time */
    double g[2];              /* -0.99 <= g[0] <= g[1] <= 0.99 */
    const nbt_phase *phase;   /* or one fixed phase (borrowed); exactly one of have_g, phase */
    int airlight;             /* H tables (default 1) */
    int diffuse;              /* J^1 tables (default 1) */
    int phong[NBT_SCENE_MAX_PHONG]; /* Phong exponents 2..10000: one J^n set each */
    size_t nphong;
    double tol;               /* relative error target, 1e-7 .. 0.5 (default 1e-3) */
    size_t orders_max;        /* most Legendre orders per set, 1 .. 512 (default NBT_PLAN_GL_ORDERS) */
    int half;                 /* store half floats */
    int basis;                /* with g: nbt_basis (nbt/gslice.h): 0 auto, 1 Legendre packs, 2 g slices;
                                 nbt_plan_scene plans Legendre packs, nbt_scene_basis chooses */
    int sub;                  /* 1: 2-D tables of form sub (NBT_FORM_SUB: the value minus its closed
                                 form; the default scene at 1e-3 fits 33^2), 0: plain (default); not
                                 with g slices (a g range needs basis legendre) */
} nbt_scene;

/* Defaults: airlight and diffuse on, tol 1e-3, orders_max 16, kappa_s not
 * given, everything else 0 (kappa_t, distance and g or phase must be set). */
void nbt_scene_init(nbt_scene *s);
/* NBT_EDOM with a one-line reason naming the key and the accepted range. */
nbt_status nbt_scene_check(const nbt_scene *s, char *err, size_t errlen);

/* One table set to plan: H or J^n over [0, xmax] x (v or theta range). */
typedef struct {
    nbt_table_kind kind;      /* NBT_TABLE_H or NBT_TABLE_J */
    int n;                    /* J: cosine exponent 1..10000 */
    size_t nterms;            /* Legendre orders 0..nterms-1 (1..512), when phase == NULL */
    const nbt_phase *phase;   /* one fixed-phase channel instead (borrowed), or NULL */
    double xmax;              /* u (H) or T (J) in [0, xmax], 0 < xmax <= 1e6 */
    double tol;               /* target: max_err / largest |value| of the first pack; 0: use size */
    size_t size[2];           /* nodes per axis (2..4096) when tol == 0 */
    int half;                 /* store half floats */
    int sub;                  /* 1: tables of form NBT_FORM_SUB (nbt/table.h; the CPU lookups and libnbt-gl's
                                 shaders add the closed form back): the default scene's three sets meet 1e-3
                                 at 33^2 */
} nbt_plan_request;

/* What the plan decided for one set. */
typedef struct {
    nbt_plan_request req;
    nbt_axis axis[2];         /* ranges, mappings and sizes */
    size_t npacks;            /* tables of up to 4 channels: ceil(nterms/4), or 1 */
    double pred_err;          /* predicted max_err / largest |value| of the first pack, all packs */
    double pred_seconds;      /* predicted build time, error measurement included */
} nbt_plan_set;

/* Legendre budget of a scene plan (zeros for a fixed phase). */
typedef struct {
    size_t nterms;            /* Legendre terms planned */
    double trunc_err;         /* measured airlight truncation error at nterms, relative */
    double amp;               /* error amplification sum_{k<nterms} (2k+1)|g|^k */
    double table_tol;         /* per-table target: tol/2 / amp */
} nbt_plan_legendre;

typedef struct nbt_plan nbt_plan;

/* Plan the requested sets (nreq >= 1). nthreads: for the proxies and the
 * builds (0: all online CPUs). Bad requests: NBT_EDOM/NBT_EINVAL with a
 * one-line reason in err. */
nbt_status nbt_plan_tables(const nbt_plan_request *req, size_t nreq, unsigned nthreads, nbt_plan **out,
                           char *err, size_t errlen);
/* Plan a scene: H (airlight), J^1 (diffuse), one J^n per Phong exponent over
 * u, T in [0, max kappa_t x max distance]. NBT_ETOL when |g| and tol need
 * more Legendre orders than orders_max (err names both; *needed, if not
 * NULL, gets the number, 513 meaning more than 512). */
nbt_status nbt_plan_scene(const nbt_scene *s, unsigned nthreads, nbt_plan **out, size_t *needed, char *err,
                          size_t errlen);
/* A plan keeps its proxy tables and the G rows its J builds computed (J^n
 * sets on one T axis share them; up to 64 MB, then rows are recomputed)
 * until it is freed. */
void nbt_plan_free(nbt_plan *p);

size_t nbt_plan_count(const nbt_plan *p);
const nbt_plan_set *nbt_plan_get(const nbt_plan *p, size_t i);
nbt_plan_legendre nbt_plan_legendre_budget(const nbt_plan *p);

/* The Legendre budget alone: smallest N <= nmax (nmax <= 512) whose airlight
 * series truncation is <= tol/2 for HG |g| <= gmax, u up to xmax; NBT_ETOL
 * when more are needed (out->nterms then holds the need, 513 past 512). */
nbt_status nbt_plan_legendre_terms(double gmax, double xmax, double tol, size_t nmax, nbt_plan_legendre *out);

/* A built set: its packs (orders 4i..4i+3, or the fixed phase), all with the
 * same axes. scale: largest |value| of the first pack; rel_err: max over
 * packs and channels of max_err / scale. */
typedef struct {
    nbt_table *t[NBT_PLAN_MAX_PACKS];
    size_t count;
    double scale, rel_err;
    double seconds;           /* build time, error measurement included */
} nbt_tableset;

/* Build set i of the plan, error measured. With a tol, grows the size until
 * every pack meets it (NBT_ETOL with err past 2049 nodes). On failure out
 * holds no tables. */
nbt_status nbt_plan_execute(const nbt_plan *p, size_t i, nbt_tableset *out, char *err, size_t errlen);
/* All sets: out[0 .. nbt_plan_count(p) - 1]; all or nothing. */
nbt_status nbt_plan_execute_all(const nbt_plan *p, nbt_tableset *out, char *err, size_t errlen);
void nbt_tableset_free(nbt_tableset *ts);

/* File stem for a set, e.g. "H", "J20", "H_hg_g_0.8" (portable characters). */
void nbt_plan_stem(const nbt_plan_request *r, char *buf, size_t n);

#ifdef __cplusplus
}
#endif
#endif
