/* tests/mcref.h: closed-form-plus-quadrature references for the photon
 * counters' tests. */
#ifndef NBT_TESTS_MCREF_H
#define NBT_TESTS_MCREF_H
#include <math.h>
#include <nbt/phase.h>

/* Single-scattering reflectance of a slab of optical thickness tau, pencil
 * beam at normal incidence, albedo w: a photon scatters once at depth t
 * (density e^{-t}) into theta > pi/2 and leaves through the top with
 * e^{-t/|cos theta|}; the t integral is closed-form:
 *   R1 = w Int_{pi/2}^{pi} 2 pi p(cos th) sin th (1 - e^{-tau (1 + 1/|c|)})/(1 + 1/|c|) dth.
 * The theta integral by the composite midpoint rule on 20000 panels
 * (smooth integrand: error ~1e-10; no endpoint, where a Gaussian phase's
 * theta/sin(theta) is cut). */
__attribute__((unused)) static double mcref_slab_r1(const nbt_phase *p, double tau, double w)
{
    const int n = 20000;
    double h = (M_PI / 2) / n, s = 0;
    for (int i = 0; i < n; i++) {
        double th = M_PI / 2 + (i + 0.5) * h, c = fabs(cos(th)), a = 1 + 1 / c;
        s += 2 * M_PI * nbt_phase_eval(p, cos(th)) * sin(th) * -expm1(-tau * a) / a;
    }
    return w * s * h;
}
#endif
