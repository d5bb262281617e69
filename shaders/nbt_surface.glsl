// shaders/nbt_surface.glsl: radiance of a surface point lit by an isotropic
// point source through the medium (Hong, eq. 4.12/4.20, albedo and 1/4pi explicit):
//   L_p = I0 e^{-kappa_t d}/d^2 (kd cos+theta_s + ks cos+^n theta_r)
//       + kappa_s I0/(4 pi d) sum_k w_k [kd J_k^1(T, theta_s) + ks J_k^n(T, theta_r)],  T = kappa_t d
// theta_s: normal to source; theta_r: mirror direction of the view to source.
// Defines: NBT_J1_PACKS (1..4) diffuse tables; NBT_JN_PACKS (0..4) Phong
// tables for one exponent n (0: no specular term). T beyond the table reads
// its edge.
NBT_SAMPLER(nbt_J1_0, 7)
#if NBT_J1_PACKS > 1
NBT_SAMPLER(nbt_J1_1, 8)
#endif
#if NBT_J1_PACKS > 2
NBT_SAMPLER(nbt_J1_2, 9)
#endif
#if NBT_J1_PACKS > 3
NBT_SAMPLER(nbt_J1_3, 10)
#endif
NBT_BLOCK_BEGIN(nbt_J_block, 2)
NBT_U vec4 nbt_J_ax0, nbt_J_ax1; // T axis, theta axis (all J tables share them)
NBT_U int nbt_J_map0, nbt_J_map1;
NBT_BLOCK_END
#if NBT_JN_PACKS > 0
NBT_SAMPLER(nbt_Jn_0, 11)
#endif
#if NBT_JN_PACKS > 1
NBT_SAMPLER(nbt_Jn_1, 12)
#endif
#if NBT_JN_PACKS > 2
NBT_SAMPLER(nbt_Jn_2, 13)
#endif
#if NBT_JN_PACKS > 3
NBT_SAMPLER(nbt_Jn_3, 14)
#endif

#define NBT_JLOOK(tex, T, th) nbt_lookup(tex, nbt_J_ax0, nbt_J_map0, nbt_J_ax1, nbt_J_map1, T, th)

float nbt_j1_sum(float T, float th)
{
    float s = dot(nbt_hw[0], NBT_JLOOK(nbt_J1_0, T, th));
#if NBT_J1_PACKS > 1
    s += dot(nbt_hw[1], NBT_JLOOK(nbt_J1_1, T, th));
#endif
#if NBT_J1_PACKS > 2
    s += dot(nbt_hw[2], NBT_JLOOK(nbt_J1_2, T, th));
#endif
#if NBT_J1_PACKS > 3
    s += dot(nbt_hw[3], NBT_JLOOK(nbt_J1_3, T, th));
#endif
    return s;
}

#if NBT_JN_PACKS > 0
float nbt_jn_sum(float T, float th)
{
    float s = dot(nbt_hw[0], NBT_JLOOK(nbt_Jn_0, T, th));
#if NBT_JN_PACKS > 1
    s += dot(nbt_hw[1], NBT_JLOOK(nbt_Jn_1, T, th));
#endif
#if NBT_JN_PACKS > 2
    s += dot(nbt_hw[2], NBT_JLOOK(nbt_Jn_2, T, th));
#endif
#if NBT_JN_PACKS > 3
    s += dot(nbt_hw[3], NBT_JLOOK(nbt_Jn_3, T, th));
#endif
    return s;
}
#endif

float nbt_surface(float kappa_s, float kappa_t, float I0, float dsp, float theta_s, float theta_r, float kd, float ks,
                  float n)
{
    float T = kappa_t * dsp;
    float direct = kd * max(cos(theta_s), 0.0);
    float scat = kd * nbt_j1_sum(T, theta_s);
#if NBT_JN_PACKS > 0
    direct += ks * pow(max(cos(theta_r), 0.0), n);
    scat += ks * nbt_jn_sum(T, theta_r);
#endif
    return I0 * exp(-T) / (dsp * dsp) * direct + kappa_s * I0 / (4.0 * NBT_PI * dsp) * scat;
}
