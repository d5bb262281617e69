/* tests/scatter_emul.h: CPU emulations of the GPU scattering methods
 * (nbt/gl_scatter.h), the same discrete algorithms in double precision,
 * written from the method descriptions, not from the shader code. Where a
 * method takes a discrete decision (window membership, nearer pixel) the
 * emulation computes its operands in float as the GPU does, so that both
 * decide alike; every weight is then evaluated in double. */
#ifndef NBT_SCATTER_EMUL_H
#define NBT_SCATTER_EMUL_H

#include <nbt/gl_scatter.h>

/* S: w*h*3 doubles. NBT_ENOMEM or NBT_EINVAL (unknown method). */
nbt_status scatter_emul(nbt_gls_method m, const nbt_gls_input *in, double *S);

/* method nbt with a given slab count (scatter_emul: NBT_GLS_NBT_SLABS). */
nbt_status scatter_emul_nbt(const nbt_gls_input *in, unsigned slabs, double *S);

/* A&S 7.1.26 G(x) = erfc(x/sqrt 2)/2, x >= 0, as the shaders evaluate it. */
double scatter_emul_G(double x);

#endif
