/* libnbt/nnls.c: non-negative least squares (Lawson and Hanson's active-set
 * method), for fitting kernels as non-negative mixtures of atoms. Small
 * dense problems only (tens of unknowns); each passive-set solve is a
 * Householder QR of the passive columns, so near-collinear atoms (Gaussians
 * at neighbouring scales) cost accuracy as cond(A), not cond(A)^2. */
#include <config.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "internal.h"

/* min |A_P z - b| over the columns P[0..k) of A (m x n, row-major, lda = n):
 * Householder QR on a copy in q (m x k), r gets Q^T b. Returns 0 when a
 * column is (numerically) dependent on the ones before it. */
static int ls_passive(const double *A, size_t m, size_t n, const double *b, const size_t *P, size_t k, double *q,
                      double *r, double *z)
{
    for (size_t i = 0; i < m; i++) {
        for (size_t j = 0; j < k; j++)
            q[i * k + j] = A[i * n + P[j]];
        r[i] = b[i];
    }
    for (size_t j = 0; j < k; j++) {
        double norm = 0;
        for (size_t i = j; i < m; i++)
            norm += q[i * k + j] * q[i * k + j];
        norm = sqrt(norm);
        double colmax = 0;
        for (size_t i = 0; i < m; i++)
            colmax = fmax(colmax, fabs(A[i * n + P[j]]));
        if (!(norm > 1e-13 * colmax) || j >= m)
            return 0;
        double alpha = q[j * k + j] > 0 ? -norm : norm, v0 = q[j * k + j] - alpha;
        /* v = (v0, q[j+1..m-1][j]); H = I - 2 v v^T / |v|^2 */
        double vv = v0 * v0;
        for (size_t i = j + 1; i < m; i++)
            vv += q[i * k + j] * q[i * k + j];
        q[j * k + j] = alpha;
        for (size_t c = j + 1; c <= k; c++) { /* c == k: the right-hand side */
            double s = v0 * (c < k ? q[j * k + c] : r[j]);
            for (size_t i = j + 1; i < m; i++)
                s += q[i * k + j] * (c < k ? q[i * k + c] : r[i]);
            s *= 2.0 / vv;
            if (c < k) {
                q[j * k + c] -= s * v0;
                for (size_t i = j + 1; i < m; i++)
                    q[i * k + c] -= s * q[i * k + j];
            } else {
                r[j] -= s * v0;
                for (size_t i = j + 1; i < m; i++)
                    r[i] -= s * q[i * k + j];
            }
        }
    }
    for (size_t jj = k; jj-- > 0;) {
        double s = r[jj];
        for (size_t c = jj + 1; c < k; c++)
            s -= q[jj * k + c] * z[c];
        z[jj] = s / q[jj * k + jj];
    }
    return 1;
}

nbt_status nbt__nnls(const double *A, size_t m, size_t n, const double *b, double *x, double *resid)
{
    double *w = malloc((n * 2 + m * (n + 2)) * sizeof *w), *zp = w + n, *q = zp + n, *r = q + m * n, *res = r + m;
    size_t *P = malloc(n * sizeof *P);
    unsigned char *in = calloc(n, 1);
    if (!w || !P || !in) {
        free(w);
        free(P);
        free(in);
        NBT_FAIL(NBT_ENOMEM, "nnls: out of memory");
    }
    memset(x, 0, n * sizeof *x);
    size_t k = 0;
    double bnorm = 0;
    for (size_t i = 0; i < m; i++)
        bnorm = fmax(bnorm, fabs(b[i]));
    nbt_status st = NBT_OK;
    for (size_t outer = 0; outer < 3 * n + 10; outer++) {
        /* the gradient w = A^T (b - A x) */
        for (size_t i = 0; i < m; i++) {
            double s = b[i];
            for (size_t j = 0; j < n; j++)
                s -= A[i * n + j] * x[j];
            res[i] = s;
        }
        size_t t = n;
        double best = 0;
        for (size_t j = 0; j < n; j++) {
            if (in[j])
                continue;
            double s = 0, amax = 0;
            for (size_t i = 0; i < m; i++) {
                s += A[i * n + j] * res[i];
                amax = fmax(amax, fabs(A[i * n + j]));
            }
            w[j] = s;
            if (s > 1e-14 * amax * bnorm * (double)m && s > best) {
                best = s;
                t = j;
            }
        }
        if (t == n)
            break;
        P[k++] = t;
        in[t] = 1;
        for (;;) {
            if (!ls_passive(A, m, n, b, P, k, q, r, zp)) { /* t adds nothing new: drop it for good */
                in[P[--k]] = 2;
                break;
            }
            int feasible = 1;
            for (size_t j = 0; j < k; j++)
                feasible &= zp[j] > 0;
            if (feasible) {
                for (size_t j = 0; j < k; j++)
                    x[P[j]] = zp[j];
                break;
            }
            /* step towards z until the first passive coefficient reaches 0; it and
             * any other that rounding put at or below 0 leave the passive set */
            double alpha = 1;
            size_t hit = k; /* none yet: with zp exactly 0 (a = 1) no step is shorter, and P[0] must stay */
            for (size_t j = 0; j < k; j++)
                if (zp[j] <= 0) {
                    double a = x[P[j]] / (x[P[j]] - zp[j]);
                    if (a < alpha) {
                        alpha = a;
                        hit = j;
                    }
                }
            size_t kk = 0;
            for (size_t j = 0; j < k; j++) {
                double v = x[P[j]] + alpha * (zp[j] - x[P[j]]);
                if (j != hit && v > 0) {
                    x[P[j]] = v;
                    P[kk++] = P[j];
                } else {
                    x[P[j]] = 0;
                    in[P[j]] = 0;
                }
            }
            k = kk;
            if (k == 0)
                break;
        }
    }
    if (resid) {
        double s2 = 0;
        for (size_t i = 0; i < m; i++) {
            double s = b[i];
            for (size_t j = 0; j < n; j++)
                s -= A[i * n + j] * x[j];
            s2 += s * s;
        }
        *resid = sqrt(s2);
    }
    free(w);
    free(P);
    free(in);
    return st;
}
