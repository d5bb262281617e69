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
