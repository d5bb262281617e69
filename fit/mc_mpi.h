/* fit/mc_mpi.h: "nbt-fit mc" over MPI ranks. Each rank runs its share of
 * the 64 photon batches (nbt_mc_part_range), rank 0 gathers the raw tallies
 * and finishes, so its output is the one a single process writes. MPI's
 * types stay in fit/mc_mpi.c. */
#ifndef NBT_FIT_MC_MPI_H
#define NBT_FIT_MC_MPI_H

#include <nbt/nbt.h>

/* mc_mpi_start starts MPI (0 on success) and gives this rank and the
 * number of ranks. mc_mpi_run runs this rank's part and reduces to rank 0:
 * a failure in any part comes back on every rank (err: which rank, why);
 * on rank 0, *out is the result, seconds the wall time of the whole run. */
int mc_mpi_start(int *rank, int *size);
nbt_status mc_mpi_run(const nbt_mc_config *cfg, int rank, int size, nbt_mc_result **out, char *err, size_t errlen);
void mc_mpi_stop(void);

#endif
