/* nbt/table.h: node-aligned 2-D and 3-D lookup tables, their axis mappings,
 * the bilinear/trilinear lookup a GPU sampler performs on them, and OpenEXR
 * I/O.
 *
 * Axis convention: node i of n sits at unit coordinate s_i = i/(n-1); the
 * physical value is x_i = from_unit(s_i), so the first and last nodes are
 * exactly the range ends. A shader samples at texture coordinate
 * (s*(n-1) + 0.5)/n. Mappings (x in [lo, hi], r = (x - lo)/(hi - lo)):
 *   linear: s = r
 *   sqrt:   s = sqrt(r)
 *   log1p:  s = log1p(c r)/log1p(c), c > 0 clusters nodes at lo,
 *           -1 < c < 0 clusters them at hi
 *   cos:    s = acos(1 - 2r)/pi   (nodes clustered at both ends, Chebyshev-like)
 *   log1p_cbrt: s = cbrt(log1p(c r)/log1p(c)), c > 0: near lo, x - lo ~ s^3,
 *           which turns the (x - lo) log(x - lo) behaviour of H and J at
 *           u, T = 0 into a C^2 function of s: bilinear error falls as N^-2
 *           (doc/tables.md); log-like spacing far from lo
 *   atanh:  s = (atanh x - atanh lo)/(atanh hi - atanh lo), -1 < lo < hi < 1:
 *           uniform in atanh x, nodes clustered towards +-1 (the HG asymmetry
 *           g, whose forward peak narrows like 1 - |g|)
 *   asinh:  s = 1/2 + asinh(c (2r - 1))/(2 asinh c), 0 < c <= 1000: nodes
 *           c/asinh(c) times denser at the middle of the range than linear,
 *           sqrt(1 + c^2) times sparser at its ends (theta of J^1: its
 *           Lambert horizon at pi/2, doc/tables.md)
 *   ends:   log1p from both ends, c/2 at lo and c at hi, 0 < c <= 1000:
 *           s = f log1p(c r)/log1p(c/2) for r <= 1/2,
 *           1 - s = (1 - f) log1p(2 c (1 - r))/log1p(c) above, f where the
 *           two slopes meet at r = 1/2 (C^1); nodes 1 + c/2 and 1 + c times
 *           denser at lo and hi than at the middle (v of the g-sliced tail
 *           form: HG's peaks of width ~1 - |g| at -pi/2 (g > 0) and, harder,
 *           at pi/2 (g < 0), doc/tables.md)
 *
 * 3-D tables (g-sliced): a third axis (axis[2]) holds slices, e.g. the HG
 * asymmetry g of H_p and J_p^n tables that serve a phase chosen at run time.
 * Slice m is a 2-D table at x2 = node m of axis[2]; the data are slices one
 * after another, exactly the layout glTexImage3D takes (x fastest, then y,
 * then slice), and the lookup is the trilinear one of a sampler3D with the
 * same node-aligned texture coordinates on all three axes (interp2 = 1), or
 * quadratic in the slice coordinate through the three nearest slices
 * (interp2 = 2: three bilinear fetches at slice centres, the same weights in
 * GLSL), or cubic through four (interp2 = 3, nbt_lookup3c). A 2-D table has
 * axis[2].n == 1.
 *
 * Value forms (nbt_table_form): what a table's values are. PLAIN: the
 * quantity itself (H_k, J_k^n, ...). Other forms store a transformed value
 * that interpolates better; their definitions are in doc/tables.md, and a
 * reader that does not know a form refuses the file. */
#ifndef NBT_TABLE_H_INCLUDED
#define NBT_TABLE_H_INCLUDED

#include <stddef.h>
#include <nbt/error.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    NBT_AXIS_LINEAR,
    NBT_AXIS_SQRT,
    NBT_AXIS_LOG1P,
    NBT_AXIS_COS,
    NBT_AXIS_LOG1P_CBRT,
    NBT_AXIS_ATANH,
    NBT_AXIS_ASINH,
    NBT_AXIS_ENDS,
} nbt_axis_map;

typedef struct {
    double lo, hi;      /* range, lo < hi */
    nbt_axis_map map;
    double c;           /* log1p strength (LOG1P: c > 0 or -1 < c < 0; LOG1P_CBRT: c > 0);
                           ASINH: clustering at the middle, 0 < c <= 1000;
                           ENDS: clustering at lo (c/2) and hi (c), 0 < c <= 1000 */
    size_t n;           /* number of nodes, >= 2 */
} nbt_axis;

/* Physical value -> unit coordinate in [0, 1] (clamped outside the range). */
double nbt_axis_to_unit(const nbt_axis *a, double x);
/* Unit coordinate -> physical value. */
double nbt_axis_from_unit(const nbt_axis *a, double s);
/* Physical value of node i. */
double nbt_axis_node(const nbt_axis *a, size_t i);
/* "linear", "sqrt", "log1p", "cos", "log1p_cbrt", "atanh", "asinh", "ends"; parse returns NBT_EFORMAT
 * for other names (so an older reader refuses a file with a newer mapping). */
const char *nbt_axis_map_name(nbt_axis_map m);
nbt_status nbt_axis_map_parse(const char *name, nbt_axis_map *m);

#define NBT_TABLE_MAX_CH 4

typedef enum {
    NBT_FORM_PLAIN,
    /* g-sliced H only (nbt/gslice.h, doc/tables.md): channel 0 holds
     * log(C W), C the scaled tail integral
     *   C(u, v; g) = int_v^{pi/2} exp(-u (s(t) - s(v))) 4 pi p_g(-sin t) dt,
     * W = 1 + s(v)/2 + u s(v)^2/2, s(t) = tan(pi/4 + t/2): smooth, no
     * forward peak to subtract, and the airlight needs only physical
     * exponentials; channel 1 a per-node relative error map; cell_err and
     * max_err are relative too */
    NBT_FORM_TAIL,
    NBT_FORM_LOG_ET,   /* J tables: ln(e^T J) = T + ln J (J > 0); the bilinear error is relative */
    /* 2-D H and J tables: the value minus a closed form S(x0, x1) =
     * d(x0 - lo0) sum_q sub_c[c][q] b_q(x1) (nbt_table_sub; its fit at x0 = lo0
     * in doc/tables.md, "33^2 at 1e-3"), which the lookups add back:
     * nbt_table_lookup and _lookup_grid return the quantity itself, max_err
     * and max_abs are the quantity's. The shaders add it back too
     * (nbt_sub, libnbt-gl's nbt_gl_set_table_sub). */
    NBT_FORM_SUB,
} nbt_table_form;

/* NBT_FORM_SUB's terms b_q(y): 1, y, cos y, sin y, cos 2y, sin 2y, cos 3y,
 * sin 3y, cos 4y, 1/sqrt(y^2 + w^2) (0 when w = 0) */
#define NBT_SUB_TERMS 10
/* its decay d(x): 1/(1 + x) or e^-x */
typedef enum { NBT_SUB_RECIP, NBT_SUB_EXP } nbt_sub_decay;

/* "plain", "tail", "log_et", "sub"; parse returns NBT_EFORMAT for other names. */
const char *nbt_table_form_name(nbt_table_form f);
nbt_status nbt_table_form_parse(const char *name, nbt_table_form *f);

/* H: airlight H_k(u, v); J: surface J_k^n(T, theta); PSI: photon counts
 * Psi(r/z, z) with its standard error (nbt-fit mc), bins at the nodes;
 * KERNEL: the narrow-beam kernel's alpha/sigma_t and beta sigma_t over
 * optical depth tau = sigma_t z and albedo (nbt-gen kernel). */
typedef enum { NBT_TABLE_H, NBT_TABLE_J, NBT_TABLE_PSI, NBT_TABLE_KERNEL } nbt_table_kind;

/* "H", "J", "PSI", "KERNEL"; the names of the axes ("u", "v"; "T",
 * "theta"; "r/z", "z"; "tau", "albedo"; axis 2: "g" for H and J, else
 * "slice"). */
const char *nbt_table_kind_name(nbt_table_kind k);
const char *nbt_table_axis_name(nbt_table_kind k, int axis);

typedef struct {
    nbt_table_kind kind;
    nbt_axis axis[3];      /* H: u, v;  J: T, theta;  PSI: r/z, z;  axis[2]: slices
                              (g for H and J), n == 1 for a 2-D table */
    size_t nch;            /* channels, 1..4 (RGBA) */
    int k[NBT_TABLE_MAX_CH];     /* Legendre order per channel; -1: fixed phase (see phase) */
    int n;                 /* J: cosine exponent (1 = Lambert, >1 Phong); H: 0 */
    char phase[128];       /* fixed-phase channels: the phase SPEC (g-sliced: the
                              family, e.g. "hg", its parameter on axis[2]);
                              PSI: the run; else "" */
    double quad_tol;       /* relative tolerance of the quadrature at the nodes */
    double quad_err;       /* largest estimated quadrature error at a node (absolute) */
    double max_err[NBT_TABLE_MAX_CH];  /* estimated max |bilinear - exact| per channel */
    double max_abs[NBT_TABLE_MAX_CH];  /* max |value| per channel (scale for max_err) */
    int half;              /* values rounded to half precision (written as HALF) */
    nbt_table_form form;   /* what the values are (PLAIN unless a builder says otherwise) */
    int interp2;           /* axis 2 interpolation: 1 linear, 2 quadratic (needs axis[2].n >= 3),
                              3 cubic (needs axis[2].n >= 4) */
    double *cell_err;      /* 3-D tables: (axis[2].n - 1) * nch values, cell_err[m * nch + c]
                              bounds |lookup3 - exact| of channel c for x2 between nodes m
                              and m + 1; NaN: not recorded (max_err applies). NULL for 2-D. */
    float *data;           /* data[((ig * axis[1].n + iy) * axis[0].n + ix) * nch + c] */
    double *row_err;       /* per x0 row and x2 cell, or NULL (cell_err applies): nbt_table_row_err_len(t)
                              values, row_err[(m * (axis[0].n - 1) + i) * nch + c] bounds |lookup3 - exact|
                              of channel c for x0 between nodes i and i + 1 and x2 in cell m (a 2-D table:
                              m = 0, its bilinear error), any x1; NaN: not recorded there */
    size_t theta_cells;    /* x1 cells per band of theta_err (its bands: nbt_table_theta_bands) */
    double *theta_err;     /* per x0 row, x1 band and x2 cell, or NULL (row_err applies):
                              nbt_table_theta_err_len(t) values, theta_err[((m * bands + b) * (axis[0].n - 1)
                              + i) * nch + c] bounds |lookup3 - exact| of channel c for x0 between nodes i
                              and i + 1, x1 in cells b theta_cells .. (b + 1) theta_cells - 1 (the last band
                              may hold fewer) and x2 in cell m; NaN: not recorded there */
    nbt_sub_decay sub_decay;  /* NBT_FORM_SUB: d(x) */
    double sub_w;             /* NBT_FORM_SUB: the peak term's width, > 0, or 0: no peak term */
    double sub_c[NBT_TABLE_MAX_CH][NBT_SUB_TERMS]; /* NBT_FORM_SUB: coefficients (float values: the EXR
                                                      stores them as floats) */
} nbt_table;

/* NBT_FORM_SUB's closed form S of channel c at (x0, x1), both clamped to
 * the axes' ranges as the lookup clamps them; 0 for other forms. */
double nbt_table_sub(const nbt_table *t, size_t c, double x0, double x1);

/* Values in row_err: max(axis[2].n - 1, 1) (axis[0].n - 1) nch. */
size_t nbt_table_row_err_len(const nbt_table *t);
/* Allocates t->row_err (all NaN, replacing any); NBT_OK or NBT_ENOMEM. */
nbt_status nbt_table_row_err_alloc(nbt_table *t);
/* Bands of theta_err: ceil((axis[1].n - 1) / theta_cells). */
size_t nbt_table_theta_bands(const nbt_table *t);
/* Values in theta_err: max(axis[2].n - 1, 1) bands (axis[0].n - 1) nch. */
size_t nbt_table_theta_err_len(const nbt_table *t);
/* Allocates t->theta_err (all NaN, replacing any) for bands of `cells` x1
 * cells (1 .. axis[1].n - 1); NBT_OK, NBT_EINVAL or NBT_ENOMEM. */
nbt_status nbt_table_theta_err_alloc(nbt_table *t, size_t cells);

/* Allocates the data for the axes' sizes; axes and channels must be set.
 * Returns NULL on bad sizes or no memory. alloc: a 2-D table (axis[2] gets
 * n = 1); alloc3: a 3-D table, ax2->n >= 2, at most 2^31 values. */
nbt_table *nbt_table_alloc(nbt_table_kind kind, const nbt_axis *ax0, const nbt_axis *ax1, size_t nch);
nbt_table *nbt_table_alloc3(nbt_table_kind kind, const nbt_axis *ax0, const nbt_axis *ax1, const nbt_axis *ax2,
                            size_t nch);
void nbt_table_free(nbt_table *t);
/* A deep copy (data and cell_err), or NULL on no memory. */
nbt_table *nbt_table_dup(const nbt_table *t);
/* Values in the table: axis[0].n axis[1].n axis[2].n nch. */
size_t nbt_table_size(const nbt_table *t);

/* Bilinear interpolation at physical (x0, x1), as a GPU sampler with
 * CLAMP_TO_EDGE does at texture coordinate (s*(n-1)+0.5)/n; out has nch
 * values. On a 3-D table: slice 0 (x2 = axis[2].lo). */
void nbt_table_lookup(const nbt_table *t, double x0, double x1, double *out);
/* nbt_table_lookup at every point of the grid x0[i], x1[j] (out[(j n0 + i)
 * nch + c]), the same values, with each coordinate's mapping evaluated once
 * instead of once per point (resampling, previews). NBT_OK or NBT_ENOMEM. */
nbt_status nbt_table_lookup_grid(const nbt_table *t, const double *x0, size_t n0, const double *x1, size_t n1,
                                 double *out);
/* Interpolation at (x0, x1, x2): trilinear, as a sampler3D with CLAMP_TO_EDGE
 * does (interp2 = 1), or bilinear in (x0, x1) and quadratic in the unit
 * coordinate of x2 through the slices nearest to it (interp2 = 2: p = s2 (n-1),
 * m = round(p) clamped to [1, n-2], t = p - m, weights t(t-1)/2, 1 - t^2,
 * t(t+1)/2 on slices m-1, m, m+1; the stencil moves at midpoints between
 * slices, where the value jumps by the order of the interpolation error,
 * which the recorded error bounds on either side), or cubic (interp2 = 3:
 * Lagrange through slices m0 .. m0 + 3, m0 = floor(p) - 1 clamped to
 * [0, n-4], weights of x = p - m0 at the nodes 0..3; continuous in x2, the
 * error ~h^4 instead of ~h^3). x2 clamps to axis[2]'s range; on a 2-D
 * table x2 is ignored. */
void nbt_table_lookup3(const nbt_table *t, double x0, double x1, double x2, double *out);

/* The recorded error bound of channel c at x2: cell_err of the cell holding
 * x2 (clamped to the axis) where recorded, else max_err[c]. */
double nbt_table_err_at(const nbt_table *t, size_t c, double x2);
/* The same at (x0, x2): row_err of the x0 row (the two x0 nodes the lookup
 * interpolates between, clamped) and x2 cell where recorded, else
 * nbt_table_err_at. */
double nbt_table_err_at_row(const nbt_table *t, size_t c, double x0, double x2);
/* The same at (x0, x1, x2): theta_err of the x0 row, the band of the x1
 * cell the lookup interpolates in (clamped) and the x2 cell where recorded,
 * else nbt_table_err_at_row. */
double nbt_table_err_at3(const nbt_table *t, size_t c, double x0, double x1, double x2);

/* Round all values to IEEE half precision (as a HALF texture would hold them). */
void nbt_table_round_half(nbt_table *t);

/* The largest recorded interpolation error (max_err) and the largest |value|
 * (max_abs) over the table's channels; channels never measured (NaN) are
 * skipped. */
double nbt_table_max_err(const nbt_table *t);
double nbt_table_max_abs(const nbt_table *t);

/* Tabulate f(x0, x1) -> out[0..nch-1] at the table's nodes; with
 * measure_error, also at every edge and cell midpoint and record max_err
 * (largest |bilinear - f| there; no smoothness is assumed) and max_abs. f returns 0,
 * or non-zero to abort (NBT_EDOM). */
typedef int (*nbt_table_fn)(double x0, double x1, double *out, void *ctx);
nbt_status nbt_table_tabulate(nbt_table *t, nbt_table_fn f, void *ctx, int measure_error);

typedef enum { NBT_EXR_ZIP, NBT_EXR_NONE } nbt_exr_compression;

/* Write as a scan-line OpenEXR file (32-bit float, or HALF when t->half),
 * channels R, G, B, A in order, with nbt.* header attributes describing the
 * table completely. A 3-D table is one image axis[1].n axis[2].n scan lines
 * high, its slices one above the other (scan line m axis[1].n + y), with
 * nbt.axis2.* attributes (name, map, lo, hi, c, n, interp) naming the slice
 * axis and nbt.cell_err.R.. (float vectors, rounded up) where recorded;
 * nbt.form names the value form. Writes to a temporary file and renames it, so a failed
 * write leaves nothing behind. */
nbt_status nbt_table_write_exr(const nbt_table *t, const char *path, nbt_exr_compression comp);
/* The same, calling progress(fraction, data) (may be NULL) from the calling
 * thread after every chunk of scan lines is encoded, with the fraction of
 * scan lines written so far (1 after the last chunk, before the file is
 * closed and renamed): the deflate of a 4096^2 table's pack takes tens of
 * seconds. */
nbt_status nbt_table_write_exr_progress(const nbt_table *t, const char *path, nbt_exr_compression comp,
                                        void (*progress)(double fraction, void *data), void *data);

/* Read a table written by nbt_table_write_exr. On failure *out is NULL and
 * err holds a one-line reason. */
nbt_status nbt_table_read_exr(const char *path, nbt_table **out, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
