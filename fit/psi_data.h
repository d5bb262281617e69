/* fit/psi_data.h: photon-counting data (nbt-fit mc output, CSV or EXR) for fitting. */
#ifndef NBT_FIT_PSI_DATA_H
#define NBT_FIT_PSI_DATA_H

#include <stddef.h>

typedef struct {
    size_t nplanes, nbins;       /* every plane has nbins annuli */
    double *z;                   /* [plane] */
    double *lo, *hi, *psi, *se;  /* [plane * nbins + bin] */
    double albedo, sigma_t, B;   /* the medium, NaN when the file does not say */
    int infinite;                /* 1: the EXR's metadata says the source was inside the medium (mc --infinite) */
    char name[256];
} psi_data;

/* Read FILE.csv (z,r_lo,r_hi,psi,psi_stderr) or FILE.exr (a PSI table).
 * Returns 0, or 1 with a one-line reason in err. */
int psi_data_read(const char *path, psi_data *d, char *err, size_t errlen);
/* psi_data_read, then the medium from albedo, sigma_t and B where they are not
 * NaN (the command line overrides the file); 1 with a one-line reason in err
 * also when the medium stays unknown. */
int psi_data_read_medium(const char *path, psi_data *d, double albedo, double sigma_t, double B, char *err,
                         size_t errlen);
void psi_data_free(psi_data *d);
/* The smallest positive standard error of plane j (+inf when the plane counted nothing): the
 * error the fits give a bin that counted nothing (its own standard error is 0). */
double psi_floor_se(const psi_data *d, size_t j);
/* ((m - psi)/se)^2 for bin i of plane j, with psi_floor_se(d, j) = floor where se is 0. */
double psi_chi2_term(const psi_data *d, size_t i, double floor, double m);

#endif
