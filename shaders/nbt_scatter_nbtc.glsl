// shaders/nbt_scatter_nbtc.glsl: what the passes of method nbt share (after
// nbt_scatter_common): the slab plan (nbt_gls_nbt_plan_of) as uniforms.

uniform int nbt_sc_nslab;                            // n finite slabs
uniform float nbt_sc_bound[NBT_SC_NBT_MAXSLABS];     // bound[k]: lower depth of slab k, k >= 1
uniform float nbt_sc_lb[NBT_SC_NBT_MAXSLABS];        // mid log2 beta_px per slab

// slab of a depth key: -1 for D = 0, n for sky, else the bounds below D
int nbt_sc_slab(float D)
{
    if (!(D > 0.0))
        return -1;
    if (D >= NBT_SC_SKY)
        return nbt_sc_nslab;
    int s = 0;
    for (int k = 1; k < nbt_sc_nslab; k++)
        s += nbt_sc_bound[k] <= D ? 1 : 0;
    return s;
}

// log2 beta_px, held below the fit's range (the weights are; above it they
// scale as 1/beta and their slope follows)
float nbt_sc_lbeta(float b)
{
    return log2(max(b, exp2(float(NBT_SC_NBT_LO))));
}

// Stores of a whole pyramid level (nbt_scatter_nbt0, nbt_scatter_nbtup) go
// to a buffer, rows band.x .. band.x + band.y - 1 of a level band.z texels
// wide, layer-major as glTexSubImage3D reads them, and libnbt-gl copies the
// band into the texture level: llvmpipe pays about ten times more per
// imageStore than per buffer store plus the copy.
layout(std430, binding = 0) writeonly buffer nbt_sc_stageb { vec4 nbt_sc_stage[]; };
uniform ivec3 nbt_sc_rows;

bool nbt_sc_in_band(ivec2 P)
{
    return P.y >= nbt_sc_rows.x && P.y < nbt_sc_rows.x + nbt_sc_rows.y;
}

void nbt_sc_put(ivec2 P, int z, vec3 v)
{
    nbt_sc_stage[(z * nbt_sc_rows.y + P.y - nbt_sc_rows.x) * nbt_sc_rows.z + P.x] = vec4(v, 0.0);
}
