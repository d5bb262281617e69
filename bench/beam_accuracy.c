/* bench/beam_accuracy.c: the experiment of Shinya et al. Fig. 2 and 4.
 * sigma_t = 1, Gaussian phase with dtheta = 30 and 60 degrees (4B = dtheta^2),
 * albedo 0.1 .. 0.99, planes z = 1..10, r in [0, z) in 20 bins. For each model
 * the relative RMS error of 2 pi r Psi against photon counting,
 *   sqrt( sum (model - mc)^2 / sum mc^2 )  over the (z, r) grid,
 * with the model averaged over each annulus as the counter is. Also the
 * counter's own relative standard error on the same norm, and the moments.
 * Usage: beam_accuracy [photons] [DATA_DIR] [DEG,DEG...]  (writes rms.dat for gnuplot;
 * DATA_DIR '-' writes nothing; the phase widths default to 30,60) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <nbt/nbt.h>

#define NZ 10
#define NR 20
#define NMODEL 5

typedef struct {
    const nbt_beam_medium *m;
    nbt_psi_model model;
    double z;
} ctx;

static int f_ann(double r, void *vp, unsigned fdim, double *f)
{
    (void)fdim;
    const ctx *c = vp;
    double p;
    nbt_beam_psi(c->m, c->model, c->z, r, &p, NULL);
    f[0] = 2 * M_PI * r * p;
    return 0;
}

int main(int argc, char **argv)
{
    double photons = argc > 1 ? atof(argv[1]) : 1e6;
    const char *dir = argc > 2 && strcmp(argv[2], "-") ? argv[2] : NULL;
    static const char *names[NMODEL] = {"ishimaru", "smallangle", "lineint", "single", "elek"};
    static const nbt_psi_model models[NMODEL] = {NBT_PSI_ISHIMARU, NBT_PSI_SMALLANGLE, NBT_PSI_LINEINT,
                                                 NBT_PSI_SINGLE, NBT_PSI_ELEK};
    double albedos[] = {0.1, 0.3, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99};
    double degs[8] = {30, 60};
    size_t nd = 2;
    if (argc > 3) {
        char *p = argv[3], *end;
        for (nd = 0; nd < 8 && *p; p = *end ? end + 1 : end) {
            degs[nd] = strtod(p, &end);
            if (end == p || !(degs[nd] > 0 && degs[nd] < 180)) {
                fprintf(stderr, "beam_accuracy: phase widths: degrees in (0, 180), comma-separated\n");
                return 2;
            }
            nd++;
        }
    }
    size_t na = sizeof albedos / sizeof albedos[0];
    FILE *dat = NULL;
    if (dir) {
        char path[1024];
        snprintf(path, sizeof path, "%s/rms.dat", dir);
        dat = fopen(path, "w");
        if (!dat) {
            fprintf(stderr, "cannot write %s\n", path);
            return 1;
        }
        fprintf(dat, "# dtheta albedo mc_se");
        for (int k = 0; k < NMODEL; k++)
            fprintf(dat, " %s", names[k]);
        fprintf(dat, "\n");
    }
    nbt_quad_ws *ws = nbt_quad_ws_alloc(1, 2000);
    printf("# relative RMS error of 2 pi r Psi vs photon counting (%.0f photons per row), z = 1..10, r in [0, z)\n",
           photons);
    printf("%6s %6s %8s", "dtheta", "albedo", "mc_se");
    for (int k = 0; k < NMODEL; k++)
        printf(" %10s", names[k]);
    printf("   M2(z=10): mc / ishimaru / smallangle\n");
    for (size_t d = 0; d < nd; d++) {
        double th = degs[d] * M_PI / 180, B = th * th / 4;
        nbt_phase *ph = nbt_phase_gauss(B);
        for (size_t ia = 0; ia < na; ia++) {
            double planes[NZ];
            for (int j = 0; j < NZ; j++)
                planes[j] = j + 1;
            nbt_mc_config c;
            memset(&c, 0, sizeof c);
            c.sigma_t = 1;
            c.albedo = albedos[ia];
            c.phase = ph;
            c.nplanes = NZ;
            c.z_planes = planes;
            c.r_bins = NR;
            c.r_max_scale = 1;
            c.photons = (uint64_t)photons;
            c.seed = 1000 + 10 * d + ia;
            nbt_mc_result *r;
            if (nbt_mc_run(&c, &r) != NBT_OK)
                return 1;
            nbt_beam_medium m = nbt_beam_homogeneous(1, albedos[ia], B);
            double num[NMODEL] = {0}, den = 0, var = 0;
            for (int j = 0; j < NZ; j++) {
                double z = planes[j], dr = z / NR;
                for (int k = 0; k < NR; k++) {
                    double lo = k * dr, hi = lo + dr, rc = lo + dr / 2, area = M_PI * (hi * hi - lo * lo);
                    double mc = 2 * M_PI * rc * r->psi[j * NR + k], se = 2 * M_PI * rc * r->psi_se[j * NR + k];
                    den += mc * mc;
                    var += se * se;
                    for (int q = 0; q < NMODEL; q++) {
                        ctx cx = {&m, models[q], z};
                        double v, e;
                        nbt_quad_gk(ws, f_ann, &cx, 1, lo > 0 ? lo : 1e-9 * dr, hi, 1e-300, 1e-7, &v, &e);
                        double mod = 2 * M_PI * rc * v / area;
                        num[q] += (mod - mc) * (mod - mc);
                    }
                }
            }
            double M0, M2i, M2r;
            nbt_beam_moments(&m, NBT_BEAM_ISHIMARU, 10, &M0, &M2i, NULL);
            nbt_beam_moments(&m, NBT_BEAM_SMALLANGLE, 10, &M0, &M2r, NULL);
            printf("%6.0f %6.2f %8.4f", degs[d], albedos[ia], sqrt(var / den));
            if (dat)
                fprintf(dat, "%g %g %g", degs[d], albedos[ia], sqrt(var / den));
            for (int q = 0; q < NMODEL; q++) {
                printf(" %10.4f", sqrt(num[q] / den));
                if (dat)
                    fprintf(dat, " %g", sqrt(num[q] / den));
            }
            printf("   %.4g / %.4g / %.4g\n", r->M2[NZ - 1], M2i, M2r);
            if (dat)
                fprintf(dat, "\n");
            fflush(stdout);
            nbt_mc_result_free(r);
        }
        if (dat)
            fprintf(dat, "\n\n");
        nbt_phase_free(ph);
    }
    if (dat)
        fclose(dat);
    nbt_quad_ws_free(ws);
    return 0;
}
