/* nbt/nbt.h: umbrella header of libnbt. */
#ifndef NBT_NBT_H
#define NBT_NBT_H

#include <nbt/error.h>
#include <nbt/quad.h>
#include <nbt/phase.h>
#include <nbt/table.h>
#include <nbt/airlight.h>
#include <nbt/surface.h>
#include <nbt/plan.h>
#include <nbt/gslice.h>
#include <nbt/beam.h>
#include <nbt/mc.h>
#include <nbt/screen.h>
#include <nbt/screen_path.h>
#include <nbt/image.h>
#include <nbt/grid.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The library's version string, e.g. "0.1.0". */
const char *nbt_version(void);

#ifdef __cplusplus
}
#endif
#endif
