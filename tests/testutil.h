/* tests/testutil.h: a tiny GSL-style test harness. Each check prints a line
 * on failure (and with NBT_TEST_VERBOSE set, on success); t_done() prints
 * "N passed, M failed" and returns the exit status. */
#ifndef NBT_TESTUTIL_H
#define NBT_TESTUTIL_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static int t_pass, t_fail;

static void t_report(int ok, const char *fmt, va_list ap)
{
    if (ok)
        t_pass++;
    else
        t_fail++;
    if (!ok || getenv("NBT_TEST_VERBOSE")) {
        printf("%s: ", ok ? "PASS" : "FAIL");
        vprintf(fmt, ap);
        printf("\n");
    }
}

/* |got - want| <= tol |want| (absolute tol where want == 0) */
__attribute__((format(printf, 4, 5), unused))
static void t_rel(double got, double want, double tol, const char *fmt, ...)
{
    double d = fabs(got - want), s = want != 0 ? fabs(want) : 1.0;
    int ok = isfinite(got) && d <= tol * s;
    va_list ap;
    va_start(ap, fmt);
    t_report(ok, fmt, ap);
    va_end(ap);
    if (!ok)
        printf("      got %.17g want %.17g (rel diff %.3g, tol %.3g)\n", got, want, d / s, tol);
}

__attribute__((format(printf, 4, 5), unused))
static void t_abs(double got, double want, double tol, const char *fmt, ...)
{
    int ok = isfinite(got) && fabs(got - want) <= tol;
    va_list ap;
    va_start(ap, fmt);
    t_report(ok, fmt, ap);
    va_end(ap);
    if (!ok)
        printf("      got %.17g want %.17g (abs diff %.3g, tol %.3g)\n", got, want, fabs(got - want), tol);
}

__attribute__((format(printf, 2, 3), unused))
static void t_true(int cond, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    t_report(cond, fmt, ap);
    va_end(ap);
}

static int t_done(void)
{
    printf("%d passed, %d failed\n", t_pass, t_fail);
    return t_fail ? 1 : 0;
}

/* max |a[i]|, the scale of an image's error */
__attribute__((unused)) static double t_maxabs(const double *a, size_t n)
{
    double m = 0;
    for (size_t i = 0; i < n; i++)
        m = fmax(m, fabs(a[i]));
    return m;
}

/* Deterministic uniform numbers in [0, 1) (splitmix64): the same inputs on every run. */
static uint64_t t_rng_state = 0x2385u;
__attribute__((unused)) static double t_uniform(void)
{
    uint64_t z = (t_rng_state += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}

/* nbt-gen's built-in default scene (gen/cmd_tables.c) as nbt_plan_request's (kind, n, orders, phase,
 * xmax, tol, g, half, sub): H, J^1 and J^20 in form sub, 4 orders, x to 10, tol 1e-3 */
#define NBT_TEST_DEFAULT_SUB_REQUESTS                                                                              \
    {{NBT_TABLE_H, 0, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 1},                                                          \
     {NBT_TABLE_J, 1, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 1},                                                          \
     {NBT_TABLE_J, 20, 4, NULL, 10.0, 1e-3, {0, 0}, 0, 1}}

#endif
