/* tests/table_roundtrip.h: a table written to a temporary EXR and read
 * back, for the tests that check what the file keeps. */
#ifndef NBT_TABLE_ROUNDTRIP_H
#define NBT_TABLE_ROUNDTRIP_H

#include <stdlib.h>
#include <unistd.h>
#include <nbt/nbt.h>

/* t written to a temporary EXR and read back (NULL where either fails) */
static nbt_table *exr_round_trip(const nbt_table *t)
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

#endif
