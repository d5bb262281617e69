/* tests/table_roundtrip.h: a table written to a temporary EXR and read
 * back, and a table stripped to the bounds older files keep, for the tests
 * (and bench/bench_gslice) that check what a file keeps. */
#ifndef NBT_TABLE_ROUNDTRIP_H
#define NBT_TABLE_ROUNDTRIP_H

#include <stdlib.h>
#include <unistd.h>
#include <nbt/nbt.h>

/* t written to a temporary EXR and read back (NULL where either fails) */
static inline nbt_table *exr_round_trip(const nbt_table *t)
{
    char path[] = "/tmp/nbt_table_roundtrip_XXXXXX.exr", rerr[256];
    int fd = mkstemps(path, 4);
    if (fd < 0)
        return NULL;
    close(fd);
    nbt_table *back = NULL;
    if (nbt_table_write_exr(t, path, NBT_EXR_ZIP) != NBT_OK || nbt_table_read_exr(path, &back, rerr, sizeof rerr) != NBT_OK)
        back = NULL;
    unlink(path);
    return back;
}

/* a copy without the theta map (the per-row bound files written before it
 * give) and, keep_rows 0, without its rows (the per-g-cell bound) */
static inline nbt_table *strip_bounds(const nbt_table *t, int keep_rows)
{
    nbt_table *c = nbt_table_dup(t);
    if (!c)
        return NULL;
    free(c->theta_err);
    c->theta_err = NULL;
    c->theta_cells = 0;
    if (!keep_rows) {
        free(c->row_err);
        c->row_err = NULL;
    }
    return c;
}

#endif
