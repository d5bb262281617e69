/* nbt/gslice.h: g-sliced tables, H_p(u, v; g) and J_p^n(T, theta; g) for a
 * Henyey-Greenstein phase function whose asymmetry g is chosen at run time.
 *
 * A g-sliced table is a 3-D nbt_table (nbt/table.h): axes 0 and 1 as for a
 * fixed-phase H or J table, axis[2] the asymmetry g (map "cos", nodes
 * clustered towards both ends of [g_lo, g_hi]; H: "atanh"); one channel
 * (two for H's tail form), k[0] = -1, phase "hg". H tables are built in the
 * tail form (NBT_FORM_TAIL, nbt_gslice_fill_form below: log of a scaled
 * tail integral and an error map). Otherwise slice m holds the fixed-phase
 * values of nbt/airlight.h (H_p) and nbt/surface.h (J_p^n) for p = HG(g_m),
 * g_m node m of axis[2], in the table's value form (t->form: PLAIN, or for
 * J LOG_ET, T + ln J), so a sampler3D at node-aligned coordinates on all
 * three axes returns what nbt_table_lookup3 does (interp2 = 2:
 * nbt_lookup3q's three fetches; H's tail form interp2 = 3: nbt_lookup3c's
 * four).
 *
 * Recorded error (in the value form; LOG_ET: in ln J, i.e. relative), per
 * g cell (cell_err, nbt_table_err_at) and its largest (max_err[0]): the
 * error of the interpolation in g, measured as |lookup - exact| on the exact
 * slice at the cell's g midpoint at every (u, v) node (quadratic: both
 * stencils that meet there), plus the in-slice bilinear errors of the
 * slices used there (each slice's own midpoint measurement) times sum |w|,
 * plus the largest quadrature error estimate. This bounds the error at any
 * point by the triangle inequality, up to the variation of the g error
 * between (u, v) nodes (tests/test_gslice.c checks it against
 * independently integrated values at random (u, v, g)). */
#ifndef NBT_GSLICE_H
#define NBT_GSLICE_H

#include <stddef.h>
#include <nbt/error.h>
#include <nbt/table.h>
#include <nbt/airlight.h>
#include <nbt/surface.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Accepted g range of g-sliced tables: |g| <= NBT_GSLICE_GMAX. */
#define NBT_GSLICE_GMAX 0.99

/* Fill a 3-D table whose kind (H or J), axes (axis[2]: g within
 * [-NBT_GSLICE_GMAX, NBT_GSLICE_GMAX], n >= 2) and, for J, n are set;
 * sets nch = 1, k[0] = -1, phase "hg", quad_tol, quad_err, max_abs and (with
 * o->measure_error) max_err and cell_err as described above (NaN without).
 * H: every slice is an ordinary fixed-phase build (nbt_h_table_build); J:
 * all slices in one pass (one quadrature per node for every g), in the
 * table's form (PLAIN or LOG_ET).
 * NBT_EINVAL for a 2-D table or another kind, NBT_EDOM for a g axis
 * outside the range. */
nbt_status nbt_gslice_fill(nbt_table *t, const nbt_build_opts *o);
/* The same in a given value form: nbt_gslice_fill is this with
 * NBT_FORM_TAIL for H and, for J, the form the table holds (PLAIN unless
 * set to LOG_ET). TAIL (H only; axis[1] must
 * be [-pi/2, pi/2], axis[0] start at 0) stores R = C(u, v; g) W(u, v),
 * C the scaled tail integral of nbt/table.h, W = 1 + s/2 + u s^2/2,
 * s = tan(pi/4 + v/2) (R(u, pi/2) = 4 pi p_g(-1)), needs 3 slices or more,
 * sets interp2 = 3 (cubic in g; with 3 slices 2, quadratic) and records
 * the error relative to the value: cell_err
 * per g cell, max_err their largest (doc/tables.md). PLAIN as described
 * above. NBT_EINVAL for TAIL on a J table or LOG_ET on an H table, and for
 * PLAIN or LOG_ET with interp2 = 3 (their error measurement knows the
 * linear and quadratic stencils). */
nbt_status nbt_gslice_fill_form(nbt_table *t, nbt_table_form form, const nbt_build_opts *o);

/* An error-driven g-sliced table. */
typedef struct {
    nbt_table_kind kind;      /* NBT_TABLE_H or NBT_TABLE_J */
    int n;                    /* J: cosine exponent 1..10000 */
    double xmax;              /* u or T in [0, xmax], 0 < xmax <= 1e6 */
    double g[2];              /* g range, -NBT_GSLICE_GMAX <= g[0] < g[1] <= NBT_GSLICE_GMAX */
    double tol;               /* target max_err / max_abs in (0, 1); 0: use size */
    size_t size[3];           /* nodes per axis (u|T, v|theta, g) when tol == 0: 2..4096, g 2..1024 */
    int half;                 /* store half floats */
} nbt_gslice_request;

/* A plan, sized by rules measured with bench/bench_gslice (doc/tables.md).
 * H (tail form): u log1p_cbrt(c = 10) and v cos with 129 nodes at tol 1e-3;
 * J (log_et form): T log1p_cbrt(c = 20) with 65 nodes, theta linear
 * (Lambert) or cos (Phong) with 257; both times sqrt(1e-3/tol) up a ladder.
 * g uniform in atanh, cubic (H) or quadratic (J), with
 * 1 + 32 (atanh span / 2 atanh 0.95)
 * (1e-3/tol)^(1/3) slices up the g ladder 9, 13, 17, 25, 33, 49, 65, ...
 * The predicted time is a 33x33x3 proxy's scaled by the node count. */
typedef struct {
    nbt_gslice_request req;
    nbt_axis axis[3];
    double pred_err;          /* predicted g interpolation error / max_abs */
    double pred_seconds;      /* predicted build time, error measurement included */
    double bytes;             /* table size as float (half: half) */
    double plan_seconds;      /* time spent planning (proxies) */
} nbt_gslice_plan_t;

nbt_status nbt_gslice_plan(const nbt_gslice_request *r, unsigned nthreads, nbt_gslice_plan_t *out, char *err,
                           size_t errlen);
/* Build the plan's table and measure its error (the rule decides the size;
 * the recorded errors bound it: H's error map per lookup, J's cell_err).
 * With req.half, the values are rounded and the rounding added to J's
 * recorded errors (H's error map). */
nbt_status nbt_gslice_execute(const nbt_gslice_plan_t *p, unsigned nthreads, nbt_table **out, char *err,
                              size_t errlen);
/* Plan and execute; seconds (may be NULL): total time, proxies included. */
nbt_status nbt_gslice_build(const nbt_gslice_request *r, unsigned nthreads, nbt_table **out, double *seconds,
                            char *err, size_t errlen);
/* nbt_gslice_build for r[0..n-1] (a scene's J^1 and J^n: the same T and g
 * axes), the J builds sharing the quadrature of G(T, g) over the HG
 * components, which depends on neither n nor theta: each table the same as
 * built alone. out[i] and seconds[i] (seconds may be NULL) per table; on
 * failure all out[] are NULL and err says why, as nbt_gslice_build's. */
nbt_status nbt_gslice_build_set(const nbt_gslice_request *r, size_t n, unsigned nthreads, nbt_table **out,
                                double *seconds, char *err, size_t errlen);

/* Which basis serves a g range: Legendre packs (nbt/plan.h) or g slices. */
typedef enum { NBT_BASIS_AUTO = 0, NBT_BASIS_LEGENDRE, NBT_BASIS_SLICES } nbt_basis;
/* "auto", "legendre", "slices"; parse: NBT_EINVAL for other names. */
const char *nbt_basis_name(nbt_basis b);
nbt_status nbt_basis_parse(const char *name, nbt_basis *b);

typedef struct {
    nbt_basis basis;          /* the choice: LEGENDRE or SLICES */
    size_t leg_nterms;        /* Legendre terms the range needs (513: more than 512) */
    double leg_seconds, leg_bytes, leg_err;  /* Legendre packs' predicted build time, size, error
                                                (INFINITY/NaN: out of reach or not asked) */
    size_t sl_size[3];
    double sl_seconds, sl_bytes, sl_err;     /* the g-sliced table's */
    char reason[320];         /* one line: the choice and the numbers behind it */
    nbt_gslice_plan_t sl_plan; /* the slices' plan (for nbt_gslice_execute) when predicted */
} nbt_basis_choice;

/* Predict both for a table kind over r->g at r->tol (r->size unused) and
 * choose (want = AUTO): the smaller predicted build work, i.e. CPU time (slices
 * only when 1.5x cheaper; wall times of the small proxies move with the
 * machine's load, their CPU times far less; reason gives both); Legendre only
 * when at most orders_max orders meet tol. want = LEGENDRE or SLICES
 * predicts only that one (LEGENDRE out of reach: NBT_ETOL naming the
 * orders). Planning runs the planners' proxy builds (about a tenth of a
 * build). */
nbt_status nbt_basis_choose(const nbt_gslice_request *r, size_t orders_max, nbt_basis want, unsigned nthreads,
                            nbt_basis_choice *out, char *err, size_t errlen);

/* Nonzero when t is a g-sliced table (3-D, kind H or J, one channel or the
 * tail form's two, HG). */
int nbt_table_is_gslice(const nbt_table *t);

/* Airlight from a g-sliced H table at run-time g: the lookup of
 * nbt_airlight_table_g_lookup and its bound. Tail form: where the bound
 * exceeds 1e-3 of the value (or on the source axis) the ray integral with
 * HG(g) is returned with its error estimate. Plain form (older files): the
 * trilinear difference, bound 2 max_err times the prefactor, with
 * nbt_airlight_table_e's fallback policy (bound beyond 10% of the value). NBT_EDOM for g outside the
 * table's g range (no extrapolation), NBT_ETOL for u beyond its u range. */
nbt_status nbt_airlight_table_g(const nbt_table *t, double g, const nbt_airlight_geom *geo, double *La,
                                double *abserr);
/* The lookup alone, exactly the shader's arithmetic (shaders/nbt_airlight.glsl,
 * NBT_G_SLICED), no fallback: for a tail-form table
 *   L_a = kappa_s I0/(4 pi h) [e^{-kappa_t d_sv} C(u, theta_0) - e^{-kappa_t (d_sp + d_vp)} C(u, theta_d)]
 * with C = exp(lookup)/W, or, where the second term exceeds 0.25 of the
 * first, the 16-point Gauss-Legendre rule over [theta_0, theta_d] in HG's
 * angle phi (doc/tables.md); abserr: the error map's bound (Gauss: twice
 * the difference from 32 points); a plain table: the difference of two
 * lookups, bound 2 max_err times the prefactor. NBT_EDOM on the source
 * axis (h = 0) and for g outside the range, NBT_ETOL for u beyond it (the
 * value is the clamped lookup's). */
nbt_status nbt_airlight_table_g_lookup(const nbt_table *t, double g, const nbt_airlight_geom *geo, double *La,
                                       double *abserr);

/* Surface radiance from g-sliced J tables at run-time g: diffuse (n = 1)
 * and specular (n = geo->n) tables (either may be NULL when kd resp. ks is
 * 0), each in its value form (LOG_ET: J = e^{v - T}). abserr: each table's
 * recorded error at g (nbt_table_err_at; LOG_ET: J (e^err - 1)) times
 * kappa_s I0 kd (ks)/(4 pi d_sp);
 * where it exceeds 10% of the scattered part the lookup is kept but
 * NBT_ETOL is not raised (the direct term is exact); pass fallback_tol > 0
 * to integrate nbt_surface_direct with HG(g) there instead (slow: seconds).
 * NBT_EDOM for g outside a table's g range, NBT_ETOL for T beyond its T
 * range. */
nbt_status nbt_surface_table_g(const nbt_table *diffuse, const nbt_table *specular, double g,
                               const nbt_surface_geom *geo, double fallback_tol, double *Lp, double *abserr);

/* Mixtures of HG lobes from the same g-sliced tables: p = sum_i w_i HG(g_i)
 * with sum_i w_i = 1, e.g. two-term HG (w = {a, 1 - a}, g = {g_f, g_b}, a
 * forward and a backward lobe). Airlight and the scattered part of surface
 * radiance are linear in the phase function, and the direct term has total
 * weight sum_i w_i = 1, so each is sum_i w_i (the lobe's value), its bound
 * sum_i |w_i| (the lobe's bound), each lobe evaluated as above (fallbacks
 * included). A shader does the same with nbt_airlight_g / nbt_surface_g per
 * lobe. 1 <= n <= NBT_HG_MIX_MAX lobes, each g_i inside the table's range;
 * NBT_EDOM when n is out of range or sum_i w_i differs from 1 by more than
 * 1e-12. Status: the first lobe status other than NBT_OK (NBT_ETOL: the
 * values are still summed). */
#define NBT_HG_MIX_MAX 8
nbt_status nbt_airlight_table_hg_mix(const nbt_table *t, size_t n, const double *w, const double *g,
                                     const nbt_airlight_geom *geo, double *La, double *abserr);
nbt_status nbt_surface_table_hg_mix(const nbt_table *diffuse, const nbt_table *specular, size_t n, const double *w,
                                    const double *g, const nbt_surface_geom *geo, double fallback_tol, double *Lp,
                                    double *abserr);

/* The basis for a scene with a g range (s->have_g): nbt_basis_choose with
 * want = s->basis for its first set (H if airlight, else J^1, else the
 * first Phong J^n) over [0, max kappa_t x max distance] at s->tol with
 * s->orders_max; g slices need g[0] < g[1] (a single g is a fixed phase).
 * NBT_EINVAL for a scene without a g range. */
#include <nbt/plan.h>
nbt_status nbt_scene_basis(const nbt_scene *s, unsigned nthreads, nbt_basis_choice *out, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
