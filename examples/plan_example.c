/* examples/plan_example.c: a renderer asks libnbt for the tables its scene
 * needs, at a stated error, in a few calls (nbt/plan.h):
 *
 *   nbt_scene_init + fill in the scene   the keys of a scene file
 *   nbt_plan_scene                       sets, orders, sizes, mappings,
 *                                        predicted error and build time
 *   nbt_plan_execute                     the tables, error measured
 *   nbt_table_write_exr                  (optional) files nbt-gen would write
 *
 * Usage: plan_example [DIR]   (with DIR: writes DIR/H_k0-3.exr, ...)
 * Exit 0 when every set meets its target, 1 otherwise. Build against an
 * installed libnbt with: cc plan_example.c $(pkg-config --cflags --libs nbt)
 * (or make -f PREFIX/share/nbt/examples/Makefile plan_example) */
#include <stdio.h>
#include <string.h>
#include <nbt/nbt.h>

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : NULL;

    /* Fog around street lamps: extinction 0.05-0.2 per metre, lamps up to
     * 40 m away, HG g chosen at run time in [0, 0.3], Lambertian surfaces,
     * 2% relative error. */
    nbt_scene s;
    nbt_scene_init(&s);
    s.kappa_t[0] = 0.05;
    s.kappa_t[1] = 0.2;
    s.distance[1] = 40;
    s.have_g = 1;
    s.g[0] = 0;
    s.g[1] = 0.3;
    s.tol = 2e-2;

    char err[512];
    nbt_plan *plan = NULL;
    size_t needed = 0;
    nbt_status st = nbt_plan_scene(&s, 0, &plan, &needed, err, sizeof err);
    if (st != NBT_OK) {
        fprintf(stderr, "plan_example: %s\n", err);
        return 1;
    }
    nbt_plan_legendre leg = nbt_plan_legendre_budget(plan);
    printf("Legendre terms %zu (truncation %.2e), per-table target %.2e (amplification %.3g)\n", leg.nterms,
           leg.trunc_err, leg.table_tol, leg.amp);
    printf("%-4s %5s %9s  %-22s %-8s %10s %10s | %10s %9s\n", "set", "packs", "size", "u/T mapping", "v/theta",
           "pred err", "pred s", "err", "s");

    int rc = 0;
    for (size_t i = 0; i < nbt_plan_count(plan); i++) {
        const nbt_plan_set *ps = nbt_plan_get(plan, i);
        char name[64], map0[64];
        nbt_plan_stem(&ps->req, name, sizeof name);
        if (ps->axis[0].map == NBT_AXIS_LOG1P || ps->axis[0].map == NBT_AXIS_LOG1P_CBRT)
            snprintf(map0, sizeof map0, "%s(c=%g)[0,%g]", nbt_axis_map_name(ps->axis[0].map), ps->axis[0].c,
                     ps->axis[0].hi);
        else
            snprintf(map0, sizeof map0, "%s[0,%g]", nbt_axis_map_name(ps->axis[0].map), ps->axis[0].hi);

        nbt_tableset ts;
        st = nbt_plan_execute(plan, i, &ts, err, sizeof err);
        if (st != NBT_OK) {
            fprintf(stderr, "plan_example: %s\n", err);
            rc = 1;
            break;
        }
        printf("%-4s %5zu %4zux%-4zu  %-22s %-8s %10.2e %10.3f | %10.2e %9.3f\n", name, ps->npacks,
               ts.t[0]->axis[0].n, ts.t[0]->axis[1].n, map0, nbt_axis_map_name(ps->axis[1].map), ps->pred_err,
               ps->pred_seconds, ts.rel_err, ts.seconds);
        if (ts.rel_err > ps->req.tol) {
            fprintf(stderr, "plan_example: %s misses its target %.2e\n", name, ps->req.tol);
            rc = 1;
        }
        /* the tables are ordinary nbt_table objects: look them up, or write
         * them as nbt-gen does (one EXR per pack of four orders) */
        for (size_t p = 0; dir && p < ts.count && rc == 0; p++) {
            char path[1024];
            snprintf(path, sizeof path, "%s/%s_k%d-%d.exr", dir, name, ts.t[p]->k[0], ts.t[p]->k[ts.t[p]->nch - 1]);
            if (nbt_table_write_exr(ts.t[p], path, NBT_EXR_ZIP) != NBT_OK) {
                fprintf(stderr, "plan_example: cannot write %s\n", path);
                rc = 1;
            }
        }
        nbt_tableset_free(&ts);
    }
    nbt_plan_free(plan);
    return rc;
}
