/* gen/scene.h: the scene file of nbt-gen scene (doc/scene-format.md). */
#ifndef NBT_GEN_SCENE_H
#define NBT_GEN_SCENE_H

#include <stddef.h>
#include <nbt/nbt.h>

/* Read the scene in PATH into *s (libnbt's nbt_scene, checked by
 * nbt_scene_check); a fixed phase is parsed into *ph (the caller frees it with
 * nbt_phase_free; NULL for Legendre tables). 0, or -1 with one line in err
 * naming file:line, the key and what is accepted (what nbt-gen prints, exit 2);
 * then nothing is left to free. */
int scene_parse(const char *path, nbt_scene *s, nbt_phase **ph, char *err, size_t errlen);

#endif
