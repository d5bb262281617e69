/* airlight_example.c: the smallest program that links libnbt. It compares
 * the airlight of a point light in fog computed two ways: Nishita's integral
 * along the ray and Hong's Legendre series over H_k, each with its error
 * estimate. Installed with nbt; build it against an installed libnbt with
 *   cc airlight_example.c $(pkg-config --cflags --libs nbt) -lm -o airlight_example */
#include <math.h>
#include <stdio.h>
#include <nbt/nbt.h>

int main(void)
{
    const double g = 0.7;
    nbt_phase *p = nbt_phase_hg(g);
    if (!p)
        return 1;
    enum { N = 120 }; /* g^N = 3e-19: truncation far below the tolerance */
    double b[N];
    for (int k = 0; k < N; k++)
        b[k] = pow(g, k); /* Henyey-Greenstein: b_k = g^k */
    nbt_airlight_geom geom = {.kappa_s = 0.1, .kappa_t = 0.12, .I0 = 3, .dsv = 7, .gamma = 0.4, .dvp = INFINITY};
    double direct, e_direct, series, e_series;
    nbt_status s = nbt_airlight_direct(p, &geom, 1e-10, &direct, &e_direct);
    if (s == NBT_OK)
        s = nbt_airlight_series(b, N, &geom, 1e-10, &series, &e_series);
    nbt_phase_free(p);
    if (s != NBT_OK) {
        fprintf(stderr, "airlight_example: %s\n", nbt_strerror(s));
        return 1;
    }
    printf("direct integral  %.15g +- %.2g\n", direct, e_direct);
    printf("Legendre series  %.15g +- %.2g (%d terms)\n", series, e_series, N);
    printf("nbt %s\n", nbt_version());
    /* the two methods share no code beyond the phase moments: they must agree
     * within their combined error estimates */
    if (fabs(direct - series) > e_direct + e_series) {
        fprintf(stderr, "airlight_example: the methods differ by %.3g, more than their errors\n", fabs(direct - series));
        return 1;
    }
    return 0;
}
