/* tests/fuzz_parsers.c: one fuzz target for every reader of user input. The
 * first byte picks the reader, the rest is the input:
 *   0 density file (z rho)        1 phase SPEC string      2 phase table file
 *   3 sum-of-Gaussians file       4 photon-count CSV       5 table EXR (header, attributes, data)
 *   6 image EXR                   7 kernel correction file 8 CLI numbers (double, integer, LO:HI)
 *   9 scene file (nbt-gen scene)
 * Files are written to a private temporary directory and read back through
 * the public path-taking API, as the programs read them. Every call must
 * return (a status, never a crash, hang or leak); successes must give sane
 * objects. Built two ways: with libFuzzer (clang -fsanitize=fuzzer) for make
 * fuzz and a bounded run in make check, or with fuzz_driver.c, which replays
 * the corpus and mutates it for a fixed time when libFuzzer is not there. */
#include <config.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <nbt/nbt.h>
#include "../fit/psi_data.h"
#include "../gen/cli.h"
#include "../gen/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { N_TARGETS = 10 };
static char dir[64], f_txt[96], f_csv[96], f_exr[96];

static void cleanup(void)
{
    unlink(f_txt);
    unlink(f_csv);
    unlink(f_exr);
    rmdir(dir);
}

static int setup(void)
{
    if (dir[0])
        return 0;
    snprintf(dir, sizeof dir, "/tmp/nbt-fuzz-XXXXXX");
    if (!mkdtemp(dir))
        return -1;
    snprintf(f_txt, sizeof f_txt, "%s/in.txt", dir);
    snprintf(f_csv, sizeof f_csv, "%s/in.csv", dir);
    snprintf(f_exr, sizeof f_exr, "%s/in.exr", dir);
    atexit(cleanup);
    return 0;
}

static const char *put(const char *path, const uint8_t *d, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        abort(); /* the harness itself is broken: say so loudly */
    if (n && fwrite(d, 1, n, f) != n)
        abort();
    if (fclose(f))
        abort();
    return path;
}

/* a NUL-terminated copy of the input */
static char *str(const uint8_t *d, size_t n)
{
    char *s = malloc(n + 1);
    if (!s)
        abort();
    memcpy(s, d, n);
    s[n] = '\0';
    return s;
}

static void check_table(const nbt_table *t)
{
    /* a table the reader accepted is usable: a lookup anywhere is finite or NaN-free when the data are */
    double out[NBT_TABLE_MAX_CH];
    if (t->axis[0].n < 2 || t->axis[1].n < 2 || t->nch < 1 || t->nch > NBT_TABLE_MAX_CH)
        abort();
    nbt_table_lookup(t, t->axis[0].lo, t->axis[1].hi, out);
    nbt_table_lookup(t, 0.5 * (t->axis[0].lo + t->axis[0].hi), 0.5 * (t->axis[1].lo + t->axis[1].hi), out);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1 || setup())
        return 0;
    int target = data[0] % N_TARGETS;
    const uint8_t *d = data + 1;
    size_t n = size - 1;
    char err[1024];
    err[0] = '\0';
    switch (target) {
    case 0: {
        double *z = NULL, *rho = NULL;
        size_t m = 0;
        if (nbt_density_read(put(f_txt, d, n), &z, &rho, &m, err, sizeof err) == NBT_OK) {
            if (m == 0 || z[0] != 0)
                abort(); /* documented: at least one layer, the first at z = 0 */
            for (size_t i = 0; i < m; i++)
                if (!isfinite(z[i]) || !(rho[i] >= 0) || (i && !(z[i] > z[i - 1])))
                    abort();
        }
        free(z);
        free(rho);
        break;
    }
    case 1: {
        char *s = str(d, n);
        nbt_phase *p = NULL;
        /* file specs are targets 2 and 3 (a random path could name a device) */
        if (!strstr(s, "table:") && !strstr(s, "sog:") && nbt_phase_parse(s, &p, err, sizeof err) == NBT_OK) {
            double b[4];
            if (!p || nbt_phase_moments(p, 3, b) != NBT_OK || fabs(b[0] - 1) > 1e-9 || !isfinite(nbt_phase_eval(p, 0.3)))
                abort();
        }
        nbt_phase_free(p);
        free(s);
        break;
    }
    case 2:
    case 3: {
        char spec[128];
        snprintf(spec, sizeof spec, "%s:%s", target == 2 ? "table" : "sog", put(f_txt, d, n));
        nbt_phase *p = NULL;
        if (nbt_phase_parse(spec, &p, err, sizeof err) == NBT_OK) {
            if (!p || !(nbt_phase_eval(p, -1.0) >= 0) || !(nbt_phase_eval(p, 0.7) >= 0))
                abort();
        }
        nbt_phase_free(p);
        break;
    }
    case 4: {
        psi_data pd;
        if (psi_data_read(put(f_csv, d, n), &pd, err, sizeof err) == 0) {
            if (pd.nplanes == 0 || pd.nbins == 0)
                abort();
            psi_data_free(&pd);
        }
        break;
    }
    case 5: {
        nbt_table *t = NULL;
        if (nbt_table_read_exr(put(f_exr, d, n), &t, err, sizeof err) == NBT_OK)
            check_table(t);
        nbt_table_free(t);
        break;
    }
    case 6: {
        nbt_image *im = NULL;
        nbt_image_read_exr(put(f_exr, d, n), &im, err, sizeof err);
        nbt_image_free(im);
        break;
    }
    case 7: {
        nbt_kernel_correction c;
        nbt_kernel_correction_read(put(f_txt, d, n), &c, err, sizeof err);
        break;
    }
    case 8: {
        char *s = str(d, n);
        double v, a, b;
        long l;
        if (parse_double(s, -1e3, 1, 1e3, 0, &v) == 0 && !(v > -1e3 && v <= 1e3))
            abort();
        if (parse_long(s, -5, 1L << 40, &l) == 0 && !(l >= -5 && l <= (1L << 40)))
            abort();
        if (parse_range(s, 0, 1, &a, &b) == NULL && !(a >= 0 && a <= b && b <= 1))
            abort();
        free(s);
        break;
    }
    case 9: {
        nbt_scene sc;
        nbt_phase *ph = NULL;
        if (scene_parse(put(f_txt, d, n), &sc, &ph, err, sizeof err) == 0) {
            if (!(sc.kappa_t[1] > 0) || !(sc.distance[1] > 0) || sc.nphong > NBT_SCENE_MAX_PHONG ||
                !(sc.tol >= 1e-7 && sc.tol <= 0.5) || sc.orders_max < 1 || sc.orders_max > 512 ||
                sc.kappa_s[1] > sc.kappa_t[1] || sc.have_g == (sc.phase != NULL) || (sc.sub != 0 && sc.sub != 1))
                abort(); /* accepted, but not what the format allows */
            nbt_phase_free(ph);
        } else if (!err[0] || strchr(err, '\n')) {
            abort(); /* a rejection has one line */
        }
        break;
    }
    }
    return 0;
}
