/* libnbt/table.c: axes, node-aligned tables, GPU-style bilinear lookup, and
 * the fill-then-measure step shared by the H and J table builders. */
#include <config.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/table.h>
#include "internal.h"
#include "tablefill.h"

/* ends: s of the middle r = 1/2, where the halves' slopes ds/dr (log1p with
 * c/2 from lo, c from hi) match, so that the map is C^1 */
static double ends_split(double c)
{
    double k1 = log1p(0.5 * c) * (1.0 + 0.5 * c) / (0.5 * c), k2 = log1p(c) * (1.0 + c) / c;
    return k1 / (k1 + k2);
}

double nbt_axis_to_unit(const nbt_axis *a, double x)
{
    if (a->map == NBT_AXIS_ATANH) {
        double s = (atanh(fmin(fmax(x, a->lo), a->hi)) - atanh(a->lo)) / (atanh(a->hi) - atanh(a->lo));
        return !(s > 0.0) ? 0.0 : s >= 1.0 ? 1.0 : s;
    }
    double r = (x - a->lo) / (a->hi - a->lo);
    if (!(r > 0.0))
        return 0.0;
    if (r >= 1.0)
        return 1.0;
    switch (a->map) {
    case NBT_AXIS_SQRT:
        return sqrt(r);
    case NBT_AXIS_LOG1P:
        return log1p(a->c * r) / log1p(a->c);
    case NBT_AXIS_LOG1P_CBRT:
        return cbrt(log1p(a->c * r) / log1p(a->c));
    case NBT_AXIS_COS:
        return acos(1.0 - 2.0 * r) / NBT_PI;
    case NBT_AXIS_ASINH:
        return 0.5 + 0.5 * asinh(a->c * (2.0 * r - 1.0)) / asinh(a->c);
    case NBT_AXIS_ENDS: {
        double f = ends_split(a->c);
        if (r <= 0.5)
            return f * log1p(a->c * r) / log1p(0.5 * a->c);
        return 1.0 - (1.0 - f) * log1p(2.0 * a->c * (1.0 - r)) / log1p(a->c);
    }
    default:
        return r;
    }
}

double nbt_axis_from_unit(const nbt_axis *a, double s)
{
    double r;
    switch (a->map) {
    case NBT_AXIS_SQRT:
        r = s * s;
        break;
    case NBT_AXIS_LOG1P:
        r = expm1(s * log1p(a->c)) / a->c;
        break;
    case NBT_AXIS_LOG1P_CBRT:
        r = expm1(s * s * s * log1p(a->c)) / a->c;
        break;
    case NBT_AXIS_COS:
        r = 0.5 * (1.0 - cos(NBT_PI * s));
        break;
    case NBT_AXIS_ASINH:
        r = 0.5 + 0.5 * sinh((2.0 * s - 1.0) * asinh(a->c)) / a->c;
        break;
    case NBT_AXIS_ENDS: {
        double f = ends_split(a->c);
        r = s <= f ? expm1(s / f * log1p(0.5 * a->c)) / a->c
                   : 1.0 - 0.5 * expm1((1.0 - s) / (1.0 - f) * log1p(a->c)) / a->c;
        break;
    }
    case NBT_AXIS_ATANH:
        if (s <= 0.0)
            return a->lo;
        if (s >= 1.0)
            return a->hi;
        return tanh(atanh(a->lo) + s * (atanh(a->hi) - atanh(a->lo)));
    default:
        r = s;
    }
    if (s >= 1.0)
        return a->hi; /* the last node is exactly the range end */
    return a->lo + r * (a->hi - a->lo);
}

double nbt_axis_node(const nbt_axis *a, size_t i)
{
    return nbt_axis_from_unit(a, (double)i / (double)(a->n - 1));
}

const char *nbt_axis_map_name(nbt_axis_map m)
{
    return m == NBT_AXIS_SQRT ? "sqrt" : m == NBT_AXIS_LOG1P ? "log1p" : m == NBT_AXIS_COS ? "cos"
         : m == NBT_AXIS_LOG1P_CBRT ? "log1p_cbrt" : m == NBT_AXIS_ATANH ? "atanh"
         : m == NBT_AXIS_ASINH ? "asinh" : m == NBT_AXIS_ENDS ? "ends" : "linear";
}

nbt_status nbt_axis_map_parse(const char *name, nbt_axis_map *m)
{
    if (!strcmp(name, "linear"))
        *m = NBT_AXIS_LINEAR;
    else if (!strcmp(name, "sqrt"))
        *m = NBT_AXIS_SQRT;
    else if (!strcmp(name, "log1p"))
        *m = NBT_AXIS_LOG1P;
    else if (!strcmp(name, "cos"))
        *m = NBT_AXIS_COS;
    else if (!strcmp(name, "log1p_cbrt"))
        *m = NBT_AXIS_LOG1P_CBRT;
    else if (!strcmp(name, "atanh"))
        *m = NBT_AXIS_ATANH;
    else if (!strcmp(name, "asinh"))
        *m = NBT_AXIS_ASINH;
    else if (!strcmp(name, "ends"))
        *m = NBT_AXIS_ENDS;
    else
        return NBT_EFORMAT;
    return NBT_OK;
}

const char *nbt_table_form_name(nbt_table_form f)
{
    switch (f) {
    case NBT_FORM_TAIL:
        return "tail";
    case NBT_FORM_LOG_ET:
        return "log_et";
    case NBT_FORM_SUB:
        return "sub";
    case NBT_FORM_PLAIN:
    default:
        return "plain";
    }
}

nbt_status nbt_table_form_parse(const char *name, nbt_table_form *f)
{
    if (!strcmp(name, "plain"))
        *f = NBT_FORM_PLAIN;
    else if (!strcmp(name, "tail"))
        *f = NBT_FORM_TAIL;
    else if (!strcmp(name, "log_et"))
        *f = NBT_FORM_LOG_ET;
    else if (!strcmp(name, "sub"))
        *f = NBT_FORM_SUB;
    else
        return NBT_EFORMAT;
    return NBT_OK;
}

const char *nbt_table_kind_name(nbt_table_kind k)
{
    static const char *n[4] = {"H", "J", "PSI", "KERNEL"};
    return n[(int)k >= 0 && (int)k < 4 ? (int)k : 0];
}

const char *nbt_table_axis_name(nbt_table_kind k, int axis)
{
    static const char *n[4][3] = {{"u", "v", "g"}, {"T", "theta", "g"}, {"r/z", "z", "slice"},
                                  {"tau", "albedo", "slice"}};
    return n[(int)k >= 0 && (int)k < 4 ? (int)k : 0][axis < 0 ? 0 : axis > 2 ? 2 : axis];
}

static int axis_ok(const nbt_axis *a)
{
    return a->n >= 2 && a->n <= 65536 && isfinite(a->lo) && isfinite(a->hi) && a->lo < a->hi &&
           (a->map != NBT_AXIS_LOG1P || ((a->c > 0 || (a->c > -1 && a->c < 0)) && isfinite(a->c))) &&
           (a->map != NBT_AXIS_LOG1P_CBRT || (a->c > 0 && isfinite(a->c))) &&
           (a->map != NBT_AXIS_ATANH || (a->lo > -1.0 && a->hi < 1.0)) &&
           (a->map != NBT_AXIS_ASINH || (a->c > 0 && a->c <= 1e3)) &&
           (a->map != NBT_AXIS_ENDS || (a->c > 0 && a->c <= 1e3));
}

nbt_table *nbt_table_alloc3(nbt_table_kind kind, const nbt_axis *ax0, const nbt_axis *ax1, const nbt_axis *ax2,
                            size_t nch)
{
    if (!axis_ok(ax0) || !axis_ok(ax1) || !(ax2->n == 1 || axis_ok(ax2)) || nch < 1 || nch > NBT_TABLE_MAX_CH ||
        (double)ax0->n * (double)ax1->n * (double)ax2->n * (double)nch > 2147483648.0)
        return NULL;
    nbt_table *t = calloc(1, sizeof *t);
    if (!t)
        return NULL;
    t->kind = kind;
    t->axis[0] = *ax0;
    t->axis[1] = *ax1;
    t->axis[2] = *ax2;
    t->nch = nch;
    t->interp2 = 1;
    t->data = calloc(nbt_table_size(t), sizeof(float));
    if (ax2->n > 1) {
        size_t ne = (ax2->n - 1) * nch;
        t->cell_err = malloc(ne * sizeof *t->cell_err);
        for (size_t i = 0; t->cell_err && i < ne; i++)
            t->cell_err[i] = NAN;
    }
    if (!t->data || (ax2->n > 1 && !t->cell_err)) {
        nbt_table_free(t);
        return NULL;
    }
    return t;
}

nbt_table *nbt_table_dup(const nbt_table *t)
{
    nbt_table *c = nbt_table_alloc3(t->kind, &t->axis[0], &t->axis[1], &t->axis[2], t->nch);
    if (!c)
        return NULL;
    float *d = c->data;
    double *e = c->cell_err;
    *c = *t;
    c->data = d;
    c->cell_err = e;
    c->row_err = c->theta_err = NULL;
    memcpy(d, t->data, nbt_table_size(t) * sizeof(float));
    if (e)
        memcpy(e, t->cell_err, (t->axis[2].n - 1) * t->nch * sizeof *e);
    if (t->row_err) {
        if (nbt_table_row_err_alloc(c) != NBT_OK) {
            nbt_table_free(c);
            return NULL;
        }
        memcpy(c->row_err, t->row_err, nbt_table_row_err_len(t) * sizeof *c->row_err);
    }
    if (t->theta_err) {
        if (nbt_table_theta_err_alloc(c, t->theta_cells) != NBT_OK) {
            nbt_table_free(c);
            return NULL;
        }
        memcpy(c->theta_err, t->theta_err, nbt_table_theta_err_len(t) * sizeof *c->theta_err);
    }
    return c;
}

double nbt_table_err_at(const nbt_table *t, size_t c, double x2)
{
    if (!t->cell_err || c >= t->nch)
        return c < t->nch ? t->max_err[c] : NAN;
    size_t m;
    double f;
    nbt__axis_cell(&t->axis[2], x2, &m, &f);
    double e = t->cell_err[m * t->nch + c];
    return isnan(e) ? t->max_err[c] : e;
}

size_t nbt_table_row_err_len(const nbt_table *t)
{
    return (t->axis[2].n > 1 ? t->axis[2].n - 1 : 1) * (t->axis[0].n - 1) * t->nch;
}

/* n values, all NaN (not recorded), or NULL */
static double *nan_filled(size_t n)
{
    double *r = malloc(n * sizeof *r);
    for (size_t i = 0; r && i < n; i++)
        r[i] = NAN;
    return r;
}

void nbt__band_max(const double *bands, size_t nb, size_t nk, double *rows)
{
    for (size_t k = 0; k < nk; k++) {
        double r = 0;
        for (size_t b = 0; b < nb; b++)
            r = fmax(r, bands[b * nk + k]);
        rows[k] = r;
    }
}

nbt_status nbt_table_row_err_alloc(nbt_table *t)
{
    double *r = nan_filled(nbt_table_row_err_len(t));
    if (!r)
        return NBT_ENOMEM;
    free(t->row_err);
    t->row_err = r;
    return NBT_OK;
}

double nbt_table_err_at_row(const nbt_table *t, size_t c, double x0, double x2)
{
    if (!t->row_err || c >= t->nch)
        return nbt_table_err_at(t, c, x2);
    size_t i, m = 0;
    double f;
    /* the x0 cell the lookup interpolates in (nbt_table_lookup3's, clamped) */
    nbt__axis_cell(&t->axis[0], x0, &i, &f);
    if (t->axis[2].n > 1)
        nbt__axis_cell(&t->axis[2], x2, &m, &f);
    double e = t->row_err[(m * (t->axis[0].n - 1) + i) * t->nch + c];
    return isnan(e) ? nbt_table_err_at(t, c, x2) : e;
}

size_t nbt_table_theta_bands(const nbt_table *t)
{
    size_t nc = t->axis[1].n - 1;
    return t->theta_cells ? (nc + t->theta_cells - 1) / t->theta_cells : 0;
}

size_t nbt_table_theta_err_len(const nbt_table *t)
{
    return nbt_table_row_err_len(t) * nbt_table_theta_bands(t);
}

nbt_status nbt_table_theta_err_alloc(nbt_table *t, size_t cells)
{
    if (cells < 1 || cells > t->axis[1].n - 1)
        return NBT_EINVAL;
    free(t->theta_err);
    t->theta_err = NULL;
    t->theta_cells = cells;
    if (!(t->theta_err = nan_filled(nbt_table_theta_err_len(t)))) {
        t->theta_cells = 0;
        return NBT_ENOMEM;
    }
    return NBT_OK;
}

double nbt_table_err_at3(const nbt_table *t, size_t c, double x0, double x1, double x2)
{
    if (!t->theta_err || c >= t->nch)
        return nbt_table_err_at_row(t, c, x0, x2);
    size_t i, j, m = 0;
    double f;
    /* the cells the lookup interpolates in (nbt_table_lookup3's, clamped) */
    nbt__axis_cell(&t->axis[0], x0, &i, &f);
    nbt__axis_cell(&t->axis[1], x1, &j, &f);
    if (t->axis[2].n > 1)
        nbt__axis_cell(&t->axis[2], x2, &m, &f);
    size_t b = j / t->theta_cells, nb = nbt_table_theta_bands(t);
    double e = t->theta_err[((m * nb + b) * (t->axis[0].n - 1) + i) * t->nch + c];
    return isnan(e) ? nbt_table_err_at_row(t, c, x0, x2) : e;
}

nbt_table *nbt_table_alloc(nbt_table_kind kind, const nbt_axis *ax0, const nbt_axis *ax1, size_t nch)
{
    const nbt_axis one = {0.0, 1.0, NBT_AXIS_LINEAR, 0.0, 1};
    return nbt_table_alloc3(kind, ax0, ax1, &one, nch);
}

size_t nbt_table_size(const nbt_table *t)
{
    return t->axis[0].n * t->axis[1].n * t->axis[2].n * t->nch;
}

void nbt_table_free(nbt_table *t)
{
    if (!t)
        return;
    free(t->data);
    free(t->cell_err);
    free(t->row_err);
    free(t->theta_err);
    free(t);
}

void nbt__axis_cell(const nbt_axis *a, double x, size_t *i0, double *f)
{
    double p = nbt_axis_to_unit(a, x) * (double)(a->n - 1);
    double fl = floor(p);
    if (fl > (double)(a->n - 2))
        fl = (double)(a->n - 2);
    *i0 = (size_t)fl;
    *f = p - fl;
}

/* bilinear in slice m */
static void lookup_slice(const nbt_table *t, size_t m, size_t i, double fx, size_t j, double fy, double *out)
{
    size_t nx = t->axis[0].n, nc = t->nch;
    const float *a = t->data + ((m * t->axis[1].n + j) * nx + i) * nc, *b = a + nx * nc;
    for (size_t c = 0; c < nc; c++) {
        double lo = (1.0 - fx) * a[c] + fx * a[nc + c];
        double hi = (1.0 - fx) * b[c] + fx * b[nc + c];
        out[c] = (1.0 - fy) * lo + fy * hi;
    }
}

/* NBT_FORM_SUB's terms at y (nbt/table.h) */
static void sub_basis(double y, double w, double *b)
{
    double c1 = cos(y), s1 = sin(y);
    b[0] = 1.0;
    b[1] = y;
    b[2] = c1;
    b[3] = s1;
    b[4] = c1 * c1 - s1 * s1;
    b[5] = 2.0 * s1 * c1;
    b[6] = b[4] * c1 - b[5] * s1;
    b[7] = b[5] * c1 + b[4] * s1;
    b[8] = b[6] * c1 - b[7] * s1;
    b[9] = w > 0 ? 1.0 / sqrt(y * y + w * w) : 0.0;
}

static double sub_decay(const nbt_table *t, double x0)
{
    double x = fmin(fmax(x0, t->axis[0].lo), t->axis[0].hi) - t->axis[0].lo;
    return t->sub_decay == NBT_SUB_EXP ? exp(-x) : 1.0 / (1.0 + x);
}

/* sum_q sub_c[c][q] b_q(y) for every channel */
static void sub_profile(const nbt_table *t, double x1, double *out)
{
    double b[NBT_SUB_TERMS], y = fmin(fmax(x1, t->axis[1].lo), t->axis[1].hi);
    sub_basis(y, t->sub_w, b);
    for (size_t c = 0; c < t->nch; c++) {
        double s = 0;
        for (int q = 0; q < NBT_SUB_TERMS; q++)
            s += t->sub_c[c][q] * b[q];
        out[c] = s;
    }
}

double nbt_table_sub(const nbt_table *t, size_t c, double x0, double x1)
{
    if (t->form != NBT_FORM_SUB || c >= t->nch)
        return 0.0;
    double p[NBT_TABLE_MAX_CH];
    sub_profile(t, x1, p);
    return sub_decay(t, x0) * p[c];
}

/* a SUB table's lookup: the remainder's bilinear value plus S */
static void sub_add(const nbt_table *t, double x0, double x1, double *out)
{
    if (t->form != NBT_FORM_SUB)
        return;
    double p[NBT_TABLE_MAX_CH], d = sub_decay(t, x0);
    sub_profile(t, x1, p);
    for (size_t c = 0; c < t->nch; c++)
        out[c] += d * p[c];
}

void nbt_table_lookup(const nbt_table *t, double x0, double x1, double *out)
{
    size_t i, j;
    double fx, fy;
    nbt__axis_cell(&t->axis[0], x0, &i, &fx);
    nbt__axis_cell(&t->axis[1], x1, &j, &fy);
    lookup_slice(t, 0, i, fx, j, fy, out);
    sub_add(t, x0, x1, out);
}

nbt_status nbt_table_lookup_grid(const nbt_table *t, const double *x0, size_t n0, const double *x1, size_t n1,
                                 double *out)
{
    size_t *ij = malloc((n0 + n1) * sizeof *ij);
    double *f = malloc((n0 + n1) * sizeof *f);
    if (!ij || !f) {
        free(ij);
        free(f);
        return NBT_ENOMEM;
    }
    for (size_t i = 0; i < n0; i++)
        nbt__axis_cell(&t->axis[0], x0[i], &ij[i], &f[i]);
    for (size_t j = 0; j < n1; j++)
        nbt__axis_cell(&t->axis[1], x1[j], &ij[n0 + j], &f[n0 + j]);
    for (size_t j = 0; j < n1; j++) {
        double p[NBT_TABLE_MAX_CH];
        if (t->form == NBT_FORM_SUB)
            sub_profile(t, x1[j], p);
        for (size_t i = 0; i < n0; i++) {
            double *o = out + (j * n0 + i) * t->nch;
            lookup_slice(t, 0, ij[i], f[i], ij[n0 + j], f[n0 + j], o);
            if (t->form == NBT_FORM_SUB) {
                double d = sub_decay(t, x0[i]);
                for (size_t c = 0; c < t->nch; c++)
                    o[c] += d * p[c];
            }
        }
    }
    free(ij);
    free(f);
    return NBT_OK;
}

void nbt_table_lookup3(const nbt_table *t, double x0, double x1, double x2, double *out)
{
    size_t i, j, m;
    double fx, fy, fz, hi[NBT_TABLE_MAX_CH];
    nbt__axis_cell(&t->axis[0], x0, &i, &fx);
    nbt__axis_cell(&t->axis[1], x1, &j, &fy);
    if (t->axis[2].n < 2) {
        lookup_slice(t, 0, i, fx, j, fy, out);
        sub_add(t, x0, x1, out);
        return;
    }
    if (t->interp2 == 3 && t->axis[2].n >= 4) {
        /* cubic through the cell's slices and one on either side */
        double p = nbt_axis_to_unit(&t->axis[2], x2) * (double)(t->axis[2].n - 1);
        size_t m0 = nbt__cubic_first(p, t->axis[2].n);
        double w[4], s[NBT_TABLE_MAX_CH];
        nbt__cubic_weights(p - (double)m0, w);
        for (size_t c = 0; c < t->nch; c++)
            out[c] = 0.0;
        for (int q = 0; q < 4; q++) {
            lookup_slice(t, m0 + (size_t)q, i, fx, j, fy, s);
            for (size_t c = 0; c < t->nch; c++)
                out[c] += w[q] * s[c];
        }
        return;
    }
    if (t->interp2 == 2 && t->axis[2].n >= 3) {
        /* quadratic through the nearest slice and its two neighbours */
        double p = nbt_axis_to_unit(&t->axis[2], x2) * (double)(t->axis[2].n - 1);
        double mc = fmin(fmax(floor(p + 0.5), 1.0), (double)(t->axis[2].n - 2)), tt = p - mc;
        double w[3], s[NBT_TABLE_MAX_CH];
        nbt__quad_weights(tt, w);
        for (size_t c = 0; c < t->nch; c++)
            out[c] = 0.0;
        for (int q = 0; q < 3; q++) {
            lookup_slice(t, (size_t)mc - 1 + (size_t)q, i, fx, j, fy, s);
            for (size_t c = 0; c < t->nch; c++)
                out[c] += w[q] * s[c];
        }
        return;
    }
    nbt__axis_cell(&t->axis[2], x2, &m, &fz);
    lookup_slice(t, m, i, fx, j, fy, out);
    lookup_slice(t, m + 1, i, fx, j, fy, hi);
    for (size_t c = 0; c < t->nch; c++)
        out[c] = (1.0 - fz) * out[c] + fz * hi[c];
}

/* float -> nearest IEEE half -> float (round to nearest even) */
static float to_half_and_back(float v)
{
    if (!isfinite(v) || v == 0.0f)
        return v;
    float a = fabsf(v);
    if (a >= 65520.0f)
        return copysignf(INFINITY, v);
    int e;
    frexpf(a, &e);            /* a = m 2^e, m in [0.5, 1) */
    int q = e - 11;           /* 11 significant bits */
    if (q < -24)
        q = -24;              /* subnormal halves: fixed step 2^-24 */
    float step = ldexpf(1.0f, q);
    return copysignf(nearbyintf(a / step) * step, v);
}

double nbt_table_max_err(const nbt_table *t)
{
    double e = 0;
    for (size_t c = 0; c < t->nch; c++)
        e = fmax(e, t->max_err[c]);
    return e;
}

double nbt_table_max_abs(const nbt_table *t)
{
    double m = 0;
    for (size_t c = 0; c < t->nch; c++)
        m = fmax(m, t->max_abs[c]);
    return m;
}

void nbt_table_round_half(nbt_table *t)
{
    nbt__table_round_half_change(t, 0);
}

double nbt__table_round_half_change(nbt_table *t, size_t c)
{
    size_t n = nbt_table_size(t);
    double d = 0;
    for (size_t i = 0; i < n; i++) {
        float h = to_half_and_back(t->data[i]);
        if (i % t->nch == c)
            d = fmax(d, fabs((double)h - (double)t->data[i]));
        t->data[i] = h;
    }
    t->half = 1;
    return d;
}

nbt_status nbt__table_set_prepare(nbt_table *const *ts, size_t nt, const nbt_phase *fixed, int **kmap,
                                  size_t *nch, size_t *kmax)
{
    *kmap = NULL;
    if (nt == 0)
        NBT_FAIL(NBT_EINVAL, "table set: no tables given");
    size_t C = 0;
    for (size_t i = 0; i < nt; i++) {
        const nbt_table *t = ts[i];
        if (t->kind != ts[0]->kind || t->n != ts[0]->n || memcmp(&t->axis[0], &ts[0]->axis[0], sizeof t->axis[0]) ||
            memcmp(&t->axis[1], &ts[0]->axis[1], sizeof t->axis[1]))
            NBT_FAIL(NBT_EINVAL, "table set: the tables must share kind, n and axes");
        for (size_t c = 0; c < t->nch; c++)
            if (!fixed && t->k[c] < 0)
                NBT_FAIL(NBT_EINVAL, "table set: Legendre channels need k >= 0");
        C += t->nch;
    }
    if (!(*kmap = malloc(C * sizeof(int))))
        NBT_FAIL(NBT_ENOMEM, "table set: out of memory");
    *nch = 0;
    *kmax = 0;
    for (size_t i = 0; i < nt; i++)
        for (size_t c = 0; c < ts[i]->nch; c++) {
            if (fixed) {
                ts[i]->k[c] = -1;
                if (!ts[i]->phase[0]) /* name the phase, so the table alone says what it holds */
                    snprintf(ts[i]->phase, sizeof ts[i]->phase, "%s", nbt_phase_name(fixed));
            }
            else if ((size_t)ts[i]->k[c] > *kmax)
                *kmax = (size_t)ts[i]->k[c];
            (*kmap)[(*nch)++] = ts[i]->k[c];
        }
    return NBT_OK;
}

/* Rows between nodes (in the first axis) computed exactly when measuring:
 * the first MID_HEAD (where u, T -> 0 make the error peak), then every
 * MID_STRIDE-th and the last; the others are estimated from second
 * differences of the exact node rows. */
#define MID_HEAD 8
#define MID_STRIDE 4
/* bilinear error at a midpoint in s is -(h^2/8) f_ss: second differences /8,
 * with this margin for f_ss varying over the cell */
#define MID_MARGIN 1.0

static int mid_exact(size_t i, size_t ncell, int measure)
{
    return measure == NBT__MEASURE_FULL || i < MID_HEAD || i % MID_STRIDE == 0 || i + 1 == ncell;
}

/* Least squares fit of f (np values, stride fs) by the terms tq[0..m-1]
 * (modified Gram-Schmidt; A: np m scratch) into coef[tq[k]], each rounded
 * to float (the EXR's precision, so that writer and reader subtract the
 * same S); returns the largest |residual| / largest |f|. */
static double sub_lsq(const double *B, size_t np, const double *f, size_t fs, const int *tq, int m, double *A,
                      double *coef)
{
    double R[NBT_SUB_TERMS][NBT_SUB_TERMS] = {{0}}, qf[NBT_SUB_TERMS], x[NBT_SUB_TERMS];
    for (int k = 0; k < m; k++) {
        double *a = A + (size_t)k * np;
        for (size_t p = 0; p < np; p++)
            a[p] = B[p * NBT_SUB_TERMS + (size_t)tq[k]];
        for (int l = 0; l < k; l++) {
            const double *q = A + (size_t)l * np;
            double r = 0;
            for (size_t p = 0; p < np; p++)
                r += q[p] * a[p];
            R[l][k] = r;
            for (size_t p = 0; p < np; p++)
                a[p] -= r * q[p];
        }
        double nn = 0;
        for (size_t p = 0; p < np; p++)
            nn += a[p] * a[p];
        R[k][k] = sqrt(nn);
        qf[k] = 0;
        for (size_t p = 0; p < np; p++) {
            a[p] = R[k][k] > 0 ? a[p] / R[k][k] : 0.0;
            qf[k] += a[p] * f[p * fs];
        }
    }
    for (int k = m - 1; k >= 0; k--) {
        double s = qf[k];
        for (int l = k + 1; l < m; l++)
            s -= R[k][l] * x[l];
        x[k] = R[k][k] > 0 ? s / R[k][k] : 0.0;
    }
    for (int q = 0; q < NBT_SUB_TERMS; q++)
        coef[q] = 0;
    for (int k = 0; k < m; k++)
        coef[tq[k]] = (double)(float)x[k];
    double res = 0, mx = 0;
    for (size_t p = 0; p < np; p++) {
        double s = 0;
        for (int q = 0; q < NBT_SUB_TERMS; q++)
            s += coef[q] * B[p * NBT_SUB_TERMS + (size_t)q];
        res = fmax(res, fabs(s - f[p * fs]));
        mx = fmax(mx, fabs(f[p * fs]));
    }
    return mx > 0 ? res / mx : res;
}

/* NBT_FORM_SUB: fit every channel's profile at x0 = lo (computed by fill on
 * SUB_FIT_CELLS + 1 points, uniform in the unit coordinate of x1: as dense
 * where the table's nodes are) by the kind's terms (doc/tables.md, "33^2 at
 * 1e-3"): H_k(0, v) lies in the span of 1, v, cos mv, sin mv (m <= k), so
 * H (k <= 3) is fitted exactly, decaying as 1/(1 + u); J^1 by 1, cos y ..
 * cos 4y, J^n (n > 1) by 1, cos y, cos 2y and the source's peak, rounded off
 * by the lobe to 1/sqrt(theta^2 + w^2) with the w of the smallest residual
 * in [0.05, 1]; J decays as e^-T. The same fit for every size, so the
 * planner's 17^2 sub-grid of a 33^2 build is the 17^2 table. */
#define SUB_FIT_CELLS 256
static nbt_status sub_fit(nbt_table *const *ts, size_t nt, size_t C, nbt__grid_fill fill, void *ctx)
{
    const nbt_table *t0 = ts[0];
    static const int th[] = {0, 1, 2, 3, 4, 5, 6, 7}, tj1[] = {0, 2, 4, 6, 8}, tjn[] = {0, 2, 4, 9};
    const int *tq = t0->kind == NBT_TABLE_H ? th : t0->n == 1 ? tj1 : tjn;
    int m = t0->kind == NBT_TABLE_H ? 8 : t0->n == 1 ? 5 : 4;
    size_t np = SUB_FIT_CELLS + 1;
    if ((t0->kind != NBT_TABLE_H && t0->kind != NBT_TABLE_J) || t0->axis[2].n > 1)
        NBT_FAIL(NBT_EINVAL, "table: form sub is for 2-D H and J tables");
    double *ys = malloc(np * sizeof *ys), *f = malloc(np * C * sizeof *f);
    double *B = malloc(np * NBT_SUB_TERMS * sizeof *B), *A = malloc(np * NBT_SUB_TERMS * sizeof *A);
    nbt_status st = ys && f && B && A ? NBT_OK : nbt__fail(NBT_ENOMEM, "table: out of memory");
    double x = t0->axis[0].lo, q = 0;
    for (size_t p = 0; st == NBT_OK && p < np; p++)
        ys[p] = nbt_axis_from_unit(&t0->axis[1], (double)p / (double)(np - 1));
    if (st == NBT_OK)
        st = fill(ctx, &x, 1, ys, np, f, &q);
    double best = INFINITY, bw = 0;
    int peak = tq[m - 1] == 9;
    for (double w = peak ? 0.05 : 0; st == NBT_OK && w <= (peak ? 1.0 + 1e-9 : 0); w += 0.01) {
        double res = 0, coef[NBT_SUB_TERMS];
        for (size_t p = 0; p < np; p++)
            sub_basis(ys[p], w, B + p * NBT_SUB_TERMS);
        for (size_t ch = 0; ch < C; ch++)
            res = fmax(res, sub_lsq(B, np, f + ch, C, tq, m, A, coef));
        if (res < best) {
            best = res;
            bw = w;
        }
    }
    for (size_t p = 0; st == NBT_OK && p < np; p++)
        sub_basis(ys[p], bw, B + p * NBT_SUB_TERMS);
    for (size_t ti = 0, ch = 0; st == NBT_OK && ti < nt; ti++) {
        nbt_table *t = ts[ti];
        t->sub_decay = t->kind == NBT_TABLE_H ? NBT_SUB_RECIP : NBT_SUB_EXP;
        t->sub_w = peak ? (double)(float)bw : 0.0;
        for (size_t c = 0; c < t->nch; c++, ch++)
            sub_lsq(B, np, f + ch, C, tq, m, A, t->sub_c[c]);
    }
    free(ys);
    free(f);
    free(B);
    free(A);
    return st;
}

/* F (nr rows at xr, fy values at ys, C channels) -= S; amax[ch] gets the
 * largest |value| before, over the node entries (every step-th y) */
static void sub_apply(nbt_table *const *ts, size_t nt, const double *xr, size_t nr, const double *ys, size_t fy,
                      size_t step, size_t C, double *F, double *amax)
{
    for (size_t jr = 0; jr < fy; jr++) {
        double p[NBT_TABLE_MAX_CH];
        for (size_t ti = 0, off = 0; ti < nt; off += ts[ti]->nch, ti++) {
            sub_profile(ts[ti], ys[jr], p);
            for (size_t i = 0; i < nr; i++) {
                double d = sub_decay(ts[ti], xr[i]), *v = F + (i * fy + jr) * C + off;
                for (size_t c = 0; c < ts[ti]->nch; c++) {
                    if (amax && jr % step == 0 && fabs(v[c]) > amax[off + c])
                        amax[off + c] = fabs(v[c]);
                    v[c] -= d * p[c];
                }
            }
        }
    }
}

nbt_status nbt__table_fill(nbt_table *const *ts, size_t nt, int measure, nbt__grid_fill fill, void *ctx)
{
    const nbt_table *t0 = ts[0];
    size_t nx = t0->axis[0].n, ny = t0->axis[1].n, C = 0;
    for (size_t i = 0; i < nt; i++)
        C += ts[i]->nch;
    /* node rows (x nodes) at every y node and, when measuring, y midpoint;
     * then the chosen rows between x nodes at the same y */
    size_t fy = measure ? 2 * ny - 1 : ny, nm = 0;
    if (measure)
        for (size_t i = 0; i + 1 < nx; i++)
            nm += (size_t)mid_exact(i, nx - 1, measure);
    double *xs = malloc(nx * sizeof(double)), *ys = malloc(fy * sizeof(double));
    double *xm = malloc((nm ? nm : 1) * sizeof(double));
    size_t *im = malloc((nm ? nm : 1) * sizeof(size_t));
    double *F = malloc(nx * fy * C * sizeof(double)), *Fm = malloc((nm ? nm : 1) * fy * C * sizeof(double));
    if (!xs || !ys || !xm || !im || !F || !Fm) {
        free(xs);
        free(ys);
        free(xm);
        free(im);
        free(F);
        free(Fm);
        NBT_FAIL(NBT_ENOMEM, "table: out of memory");
    }
    for (size_t i = 0; i < nx; i++)
        xs[i] = nbt_axis_from_unit(&t0->axis[0], (double)i / (double)(nx - 1));
    for (size_t j = 0; j < fy; j++)
        ys[j] = nbt_axis_from_unit(&t0->axis[1], (double)j / (double)(fy - 1));
    nm = 0;
    if (measure)
        for (size_t i = 0; i + 1 < nx; i++)
            if (mid_exact(i, nx - 1, measure)) {
                im[nm] = i;
                xm[nm++] = nbt_axis_from_unit(&t0->axis[0], (2.0 * (double)i + 1.0) / (2.0 * (double)(nx - 1)));
            }
    double qerr = 0, qerr2 = 0;
    nbt_status st = fill(ctx, xs, nx, ys, fy, F, &qerr);
    if (st == NBT_OK && nm)
        st = fill(ctx, xm, nm, ys, fy, Fm, &qerr2);
    qerr = fmax(qerr, qerr2);
    size_t off = 0, step = measure ? 2 : 1;
    /* form sub: the tables hold f - S (after the node fills: J checks its
     * quadrature on the first call's rows); max_abs stays f's */
    double *amax = NULL;
    for (size_t i = 1; i < nt && st == NBT_OK; i++)
        if (ts[i]->form != t0->form)
            st = nbt__fail(NBT_EINVAL, "table set: the tables must share their form");
    if (st == NBT_OK && t0->form == NBT_FORM_SUB) {
        if (!(amax = calloc(C, sizeof *amax)))
            st = nbt__fail(NBT_ENOMEM, "table: out of memory");
        if (st == NBT_OK)
            st = sub_fit(ts, nt, C, fill, ctx);
        if (st == NBT_OK) {
            sub_apply(ts, nt, xs, nx, ys, fy, step, C, F, amax);
            sub_apply(ts, nt, xm, nm, ys, fy, step, C, Fm, NULL);
        }
    }
    for (size_t ti = 0; ti < nt && st == NBT_OK; off += ts[ti]->nch, ti++) {
        nbt_table *t = ts[ti];
        size_t nc = t->nch;
        for (size_t c = 0; c < nc; c++)
            t->max_abs[c] = t->max_err[c] = 0;
        /* in tiles of 16 x rows: F is column-major, the table row-major */
        for (size_t i0 = 0; i0 < nx; i0 += 16)
            for (size_t j = 0; j < ny; j++)
                for (size_t i = i0; i < nx && i < i0 + 16; i++)
                    for (size_t c = 0; c < nc; c++) {
                        double v = F[(i * fy + j * step) * C + off + c];
                        t->data[(j * nx + i) * nc + c] = (float)v;
                        if (fabs(v) > t->max_abs[c])
                            t->max_abs[c] = fabs(v);
                    }
        for (size_t c = 0; amax && c < nc; c++)
            t->max_abs[c] = amax[off + c];
        if (t->half)
            nbt_table_round_half(t);
        t->quad_err = qerr;
        if (!measure) {
            for (size_t c = 0; c < nc; c++)
                t->max_err[c] = NAN;
            continue;
        }
        /* the lookup at a midpoint of the unit grid is the average of the
         * two (edge) or four (centre) nodes around it */
        /* the table's values column-major, as F */
        double *DT = malloc(nx * ny * nc * sizeof(double));
        if (!DT) {
            st = nbt__fail(NBT_ENOMEM, "table: out of memory");
            break;
        }
        for (size_t i0 = 0; i0 < nx; i0 += 16)
            for (size_t j = 0; j < ny; j++)
                for (size_t i = i0; i < nx && i < i0 + 16; i++)
                    for (size_t c = 0; c < nc; c++)
                        DT[(i * ny + j) * nc + c] = t->data[(j * nx + i) * nc + c];
#define D(i, j, c) DT[((i) * ny + (j)) * nc + (c)]
#define EX(i, jr, c) F[((i) * fy + (jr)) * C + off + (c)]
        /* per x row (cell i between x nodes i and i + 1) and y band (cpb
         * y cells) where the builder asked for it (row_err, theta_err
         * allocated): a node row's or column's error belongs to both cells
         * that meet there; row_err is the max over the bands */
        size_t nb = t->theta_err ? nbt_table_theta_bands(t) : 1, cpb = t->theta_err ? t->theta_cells : ny - 1;
        int rows = t->row_err || t->theta_err;
        double *rw = rows ? calloc((nx - 1) * nb * nc, sizeof *rw) : NULL;
        if (rows && !rw) {
            free(DT);
            st = nbt__fail(NBT_ENOMEM, "table: out of memory");
            break;
        }
        /* row i, y cell j */
#define RUPD(i, j, c, v_) do { double *r_ = rw ? rw + (((j) / cpb * (nx - 1) + (i)) * nc + (c)) : NULL; \
                               if (r_ && v_ > *r_) *r_ = v_; } while (0)
        /* row i, fine y index jr (odd: a y cell's middle, even: a y node) */
#define RUPDJ(i, jr, c, v_) do { size_t j_ = (jr) / 2; if ((jr) % 2 == 1 || j_ + 1 < ny) RUPD(i, j_, c, v_); \
                                 if ((jr) % 2 == 0 && j_ >= 1) RUPD(i, j_ - 1, c, v_); } while (0)
#define UPD(i, jr, c, v) do { double v_ = (v); if (v_ > e[c]) e[c] = v_; RUPDJ(i, jr, c, v_); } while (0)
        double e[NBT_TABLE_MAX_CH] = {0};
        /* node rows, between y nodes */
        for (size_t i = 0; i < nx; i++)
            for (size_t j = 0; j + 1 < ny; j++)
                for (size_t c = 0; c < nc; c++) {
                    double v = fabs(0.5 * (D(i, j, c) + D(i, j + 1, c)) - EX(i, 2 * j + 1, c));
                    UPD(i + 1 < nx ? i : i - 1, 2 * j + 1, c, v);
                    if (i >= 1 && i + 1 < nx)
                        RUPD(i - 1, j, c, v);
                }
        /* rows between x nodes: exact ones */
        for (size_t r = 0; r < nm; r++) {
            size_t i = im[r];
            for (size_t jr = 0; jr < fy; jr++) {
                size_t j = jr / 2;
                for (size_t c = 0; c < nc; c++) {
                    double lk = jr % 2 == 0 ? 0.5 * (D(i, j, c) + D(i + 1, j, c))
                                            : 0.25 * (D(i, j, c) + D(i + 1, j, c) + D(i, j + 1, c) + D(i + 1, j + 1, c));
                    UPD(i, jr, c, fabs(lk - Fm[(r * fy + jr) * C + off + c]));
                }
            }
        }
        /* the others: second differences in x of the exact node rows,
         * plus the error at the nodes next to them (rounding) or, for
         * centres, the y error there */
        for (size_t i = 0, r = 0; i + 1 < nx; i++) {
            if (r < nm && im[r] == i) {
                r++;
                continue;
            }
            for (size_t jr = 0; jr < fy; jr++) {
                size_t j = jr / 2;
                for (size_t c = 0; c < nc; c++) {
                    double d2 = 0;
                    if (i >= 1)
                        d2 = fabs(EX(i - 1, jr, c) - 2.0 * EX(i, jr, c) + EX(i + 1, jr, c));
                    if (i + 2 < nx) {
                        double d2b = fabs(EX(i, jr, c) - 2.0 * EX(i + 1, jr, c) + EX(i + 2, jr, c));
                        d2 = d2b > d2 ? d2b : d2;
                    }
                    double a0, a1;
                    if (jr % 2 == 1) {
                        a0 = fabs(0.5 * (D(i, j, c) + D(i, j + 1, c)) - EX(i, jr, c));
                        a1 = fabs(0.5 * (D(i + 1, j, c) + D(i + 1, j + 1, c)) - EX(i + 1, jr, c));
                    } else {
                        a0 = fabs(D(i, j, c) - EX(i, jr, c));
                        a1 = fabs(D(i + 1, j, c) - EX(i + 1, jr, c));
                    }
                    UPD(i, jr, c, MID_MARGIN * d2 / 8.0 + (a0 > a1 ? a0 : a1));
                }
            }
        }
        /* what the midpoints cannot see: the quadrature error at nodes */
        for (size_t c = 0; c < nc; c++)
            t->max_err[c] = e[c] + qerr;
        for (size_t k = 0; t->theta_err && k < (nx - 1) * nb * nc; k++)
            t->theta_err[k] = rw[k] + qerr;
        if (t->row_err) {
            nbt__band_max(rw, nb, (nx - 1) * nc, t->row_err);
            for (size_t k = 0; k < (nx - 1) * nc; k++)
                t->row_err[k] += qerr;
        }
        free(rw);
        free(DT);
#undef RUPDJ
#undef RUPD
#undef UPD
#undef D
#undef EX
    }
    free(amax);
    free(xs);
    free(ys);
    free(xm);
    free(im);
    free(F);
    free(Fm);
    return st;
}

typedef struct {
    nbt_table_fn f;
    void *ctx;
    size_t nch;
} tab_ctx;

static nbt_status tab_fill(void *vp, const double *xs, size_t nx, const double *ys, size_t ny, double *F,
                           double *quad_err)
{
    const tab_ctx *c = vp;
    *quad_err = 0;
    for (size_t j = 0; j < ny; j++)
        for (size_t i = 0; i < nx; i++)
            if (c->f(xs[i], ys[j], F + (i * ny + j) * c->nch, c->ctx))
                NBT_FAIL(NBT_EDOM, "table: the tabulated function failed");
    return NBT_OK;
}

nbt_status nbt_table_tabulate(nbt_table *t, nbt_table_fn f, void *ctx, int measure_error)
{
    tab_ctx c = {f, ctx, t->nch};
    /* an arbitrary function may be under-resolved somewhere (a bump as wide
     * as a cell), where second differences underestimate the error by 2x or
     * more: every midpoint is computed */
    return nbt__table_fill(&t, 1, measure_error ? NBT__MEASURE_FULL : 0, tab_fill, &c);
}
