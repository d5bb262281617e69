// shaders/nbt_weights.glsl: the Legendre weights shared by H and J tables:
// nbt_hw[p] holds w_k = (2k+1) b_k for orders 4p..4p+3 (HG: b_k = g^k),
// 0 for orders not used, so the number of terms and g change at run time.
// Fixed-phase tables use nbt_hw[0] = (1, 0, 0, 0). NBT_W_PACKS is the largest
// pack count of the tables in use. With NBT_G_SLICED (g-sliced H/J tables)
// nbt_g is the Henyey-Greenstein g the tables are read at (clamped to their
// g axis); nbt_hw is then unused.
NBT_BLOCK_BEGIN(nbt_weights_block, 0)
NBT_U vec4 nbt_hw[NBT_W_PACKS];
#ifdef NBT_G_SLICED
NBT_U float nbt_g;
#endif
NBT_BLOCK_END
