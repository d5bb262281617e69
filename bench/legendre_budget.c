/* The Legendre budget (nbt_plan_legendre_terms) between its sample rays.
 * The planner picks N on 6 x 6 rays (u, gamma) for g = +-gmax; this bench
 * takes an NU x NG grid of rays over the same range (u from xmax down to
 * xmax/1e3, gamma 0.05 .. 2.5) and compares the N-term series
 * (nbt_airlight_series) with Nishita's integral of the exact HG phase
 * (nbt_airlight_direct), both at 1e-10, for g = +gmax and -gmax. It prints
 * the planner's time and the worst relative truncation on the grid against
 * tol/2 (each figure less both integrals' error estimates).
 * Usage: legendre_budget GMAX XMAX TOL [NU NG] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <nbt/nbt.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 6) {
        fprintf(stderr, "usage: legendre_budget GMAX XMAX TOL [NU NG]\n");
        return 2;
    }
    double gmax = atof(argv[1]), xmax = atof(argv[2]), tol = atof(argv[3]);
    int nu = argc == 6 ? atoi(argv[4]) : 25, ng = argc == 6 ? atoi(argv[5]) : 41;
    if (nu < 2 || ng < 2) {
        fprintf(stderr, "legendre_budget: NU = %d, NG = %d: each must be >= 2\n", nu, ng);
        return 2;
    }
    nbt_plan_legendre l;
    double t0 = now();
    nbt_status st = nbt_plan_legendre_terms(gmax, xmax, tol, 512, &l);
    double tp = now() - t0;
    if (st != NBT_OK) {
        fprintf(stderr, "legendre_budget: %s (gmax 0 .. 0.99, xmax 0 .. 1e6, tol 0 .. 1)\n", nbt_strerror(st));
        return 1;
    }
    double *b = malloc(l.nterms * sizeof *b), worst = 0, wu = 0, wgam = 0, wg = 0;
    for (int sg = 1; sg >= -1 && b; sg -= 2) {
        char spec[64];
        nbt_phase *hg = NULL;
        snprintf(spec, sizeof spec, "hg:g=%.17g", sg * gmax);
        if (nbt_phase_parse(spec, &hg, NULL, 0) != NBT_OK)
            return 1;
        for (size_t k = 0; k < l.nterms; k++)
            b[k] = pow(sg * gmax, (double)k);
        for (int iu = 0; iu < nu; iu++) {
            double u = xmax * pow(10.0, -3.0 * iu / (nu - 1));
            for (int ig = 0; ig < ng; ig++) {
                double gam = 0.05 + 2.45 * ig / (ng - 1), d, de, s, se;
                nbt_airlight_geom geo = {1.0, 1.0, 1.0, u / sin(gam), gam, INFINITY};
                if (nbt_airlight_direct(hg, &geo, 1e-10, &d, &de) != NBT_OK ||
                    nbt_airlight_series(b, l.nterms, &geo, 1e-10, &s, &se) != NBT_OK)
                    return 1;
                double r = (fabs(s - d) - de - se) / d;
                if (r > worst) {
                    worst = r;
                    wu = u;
                    wgam = gam;
                    wg = sg * gmax;
                }
            }
        }
        nbt_phase_free(hg);
    }
    free(b);
    printf("gmax %g xmax %g tol %g: N %zu (planner %.3f s, its sample rays %.3g)\n", gmax, xmax, tol, l.nterms, tp,
           l.trunc_err);
    printf("  %dx%d grid: worst truncation %.3g at u %.4g gamma %.4f g %+g (tol/2 = %.3g): %s\n", nu, ng, worst, wu,
           wgam, wg, 0.5 * tol, worst <= 0.5 * tol ? "holds" : "MISSED");
    return 0;
}
