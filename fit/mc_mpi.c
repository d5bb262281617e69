/* fit/mc_mpi.c: photon counting split over MPI ranks (see mc_mpi.h). */
#include <config.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <mpi.h>
#include "mc_mpi.h"

int mc_mpi_start(int *rank, int *size)
{
    if (MPI_Init(NULL, NULL) != MPI_SUCCESS)
        return 1;
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    return 0;
}

void mc_mpi_stop(void)
{
    MPI_Finalize();
}

nbt_status mc_mpi_run(const nbt_mc_config *cfg, int rank, int size, nbt_mc_result **out, char *err, size_t errlen)
{
    *out = NULL;
    err[0] = '\0';
    struct timespec t0, t1;
    MPI_Barrier(MPI_COMM_WORLD);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    size_t len = nbt_mc_tally_len(cfg), b0, b1;
    /* slices of batches run elsewhere stay 0, so the element-wise sum below
     * adds exact zeros to the one rank's value of each slice */
    double *tally = calloc(len ? len : 1, sizeof(double));
    int st = tally ? NBT_OK : NBT_ENOMEM;
    nbt_mc_part_range((size_t)rank, (size_t)size, &b0, &b1);
    if (st == NBT_OK)
        st = nbt_mc_run_part(cfg, b0, b1, tally);
    if (st != NBT_OK)
        snprintf(err, errlen, "rank %d (batches %zu..%zu): %s", rank, b0, b1, nbt_strerror((nbt_status)st));
    /* every rank learns the worst status (the lowest rank's message is the one rank 0 can print) */
    int worst = st, who = st != NBT_OK ? rank : size;
    MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &who, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (worst != NBT_OK) {
        if (who != 0 && rank == 0)
            snprintf(err, errlen, "rank %d: %s", who, nbt_strerror((nbt_status)worst));
        free(tally);
        return (nbt_status)worst;
    }
    for (size_t off = 0; off < len;) { /* counts are int: chunks of at most 2^28 doubles */
        size_t n = len - off < ((size_t)1 << 28) ? len - off : (size_t)1 << 28;
        MPI_Reduce(rank == 0 ? MPI_IN_PLACE : tally + off, tally + off, (int)n, MPI_DOUBLE, MPI_SUM, 0,
                   MPI_COMM_WORLD);
        off += n;
    }
    nbt_status fs = NBT_OK;
    if (rank == 0) {
        fs = nbt_mc_finish(cfg, tally, out);
        if (fs == NBT_OK) {
            clock_gettime(CLOCK_MONOTONIC, &t1);
            (*out)->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        } else
            snprintf(err, errlen, "%s", nbt_strerror(fs));
    }
    free(tally);
    return fs;
}
