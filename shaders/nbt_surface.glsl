// shaders/nbt_surface.glsl: radiance of a surface point lit by an isotropic
// point source through the medium (Hong, eq. 4.12/4.20, albedo and 1/4pi explicit):
//   L_p = I0 e^{-kappa_t d}/d^2 (kd cos+theta_s + ks cos+^n theta_r)
//       + kappa_s I0/(4 pi d) sum_k w_k [kd J_k^1(T, theta_s) + ks J_k^n(T, theta_r)],  T = kappa_t d
// theta_s: normal to source; theta_r: mirror direction of the view to source.
// Defines: NBT_J1_PACKS (1..4) diffuse tables; NBT_JN_PACKS (0..4) Phong
// tables for one exponent n (0: no specular term). With NBT_G_SLICED the
// J^1 and J^n tables (at most one each) are g-sliced J_p^n(T, theta; g) of the
// HG phase (sampler3D, channel R, axis 2 = g): nbt_surface_g(..., g) reads
// them at any g, nbt_surface at the uniform nbt_g (g clamps to the tables' g
// range). T beyond the table reads its edge. A 2-D pack of form sub adds
// its closed form back (nbt_J1_p_sub, _sub_w, _sub_c and nbt_Jn_p_*: nbt_sub
// in nbt_table.glsl). nbt_J_form and nbt_J_interp2
// (set by nbt_gl_set_table_axes) name the tables' value form and g
// interpolation, as libnbt's nbt_surface_table_g reads them.
#ifdef NBT_G_SLICED
#define NBT_JSAMPLER NBT_SAMPLER3D
#else
#define NBT_JSAMPLER NBT_SAMPLER
#endif
NBT_JSAMPLER(nbt_J1_0, 7)
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
#ifdef NBT_G_SLICED
NBT_U vec4 nbt_J_ax2; // g axis
NBT_U int nbt_J_map2;
NBT_U int nbt_J_form;    // 0: plain J; 1: log_et, the texel holds T + ln J
NBT_U int nbt_J_interp2; // 3: cubic in g (nbt_lookup3c), 2: quadratic (nbt_lookup3q), else trilinear
#else
// per pack: form sub's closed form (nbt_sub; set by nbt_gl_set_table_sub, all 0 for a plain table)
NBT_U vec4 nbt_J1_0_sub_c[10];
NBT_U int nbt_J1_0_sub;
NBT_U float nbt_J1_0_sub_w;
#if NBT_J1_PACKS > 1
NBT_U vec4 nbt_J1_1_sub_c[10];
NBT_U int nbt_J1_1_sub;
NBT_U float nbt_J1_1_sub_w;
#endif
#if NBT_J1_PACKS > 2
NBT_U vec4 nbt_J1_2_sub_c[10];
NBT_U int nbt_J1_2_sub;
NBT_U float nbt_J1_2_sub_w;
#endif
#if NBT_J1_PACKS > 3
NBT_U vec4 nbt_J1_3_sub_c[10];
NBT_U int nbt_J1_3_sub;
NBT_U float nbt_J1_3_sub_w;
#endif
#if NBT_JN_PACKS > 0
NBT_U vec4 nbt_Jn_0_sub_c[10];
NBT_U int nbt_Jn_0_sub;
NBT_U float nbt_Jn_0_sub_w;
#endif
#if NBT_JN_PACKS > 1
NBT_U vec4 nbt_Jn_1_sub_c[10];
NBT_U int nbt_Jn_1_sub;
NBT_U float nbt_Jn_1_sub_w;
#endif
#if NBT_JN_PACKS > 2
NBT_U vec4 nbt_Jn_2_sub_c[10];
NBT_U int nbt_Jn_2_sub;
NBT_U float nbt_Jn_2_sub_w;
#endif
#if NBT_JN_PACKS > 3
NBT_U vec4 nbt_Jn_3_sub_c[10];
NBT_U int nbt_Jn_3_sub;
NBT_U float nbt_Jn_3_sub_w;
#endif
#endif
NBT_BLOCK_END
#if NBT_JN_PACKS > 0
NBT_JSAMPLER(nbt_Jn_0, 11)
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

#ifdef NBT_G_SLICED
// libnbt's nbt_surface_table_g: the lookup (cubic, quadratic or linear in g), then
// J = e^{v - T} for the log_et form
float nbt_jlook3(sampler3D tex, float T, float th, float g)
{
    float v = nbt_lookup3i(tex, nbt_J_ax0, nbt_J_map0, nbt_J_ax1, nbt_J_map1, nbt_J_ax2, nbt_J_map2, nbt_J_interp2,
                           T, th, g).r;
    return nbt_J_form == 1 ? exp(v - T) : v;
}
#define NBT_JLOOK3(tex, T, th, g) nbt_jlook3(tex, T, th, g)
#define NBT_J1_SUM(T, th, g) NBT_JLOOK3(nbt_J1_0, T, th, g)
#define NBT_JN_SUM(T, th, g) NBT_JLOOK3(nbt_Jn_0, T, th, g)
#else
// a pack's value, its closed form added back for form sub (the pack's uniforms: tex_sub, _sub_w, _sub_c)
#define NBT_JLOOK(tex, sub, w, c, T, th) nbt_lookup_sub(tex, nbt_J_ax0, nbt_J_map0, nbt_J_ax1, nbt_J_map1, sub, w, c, T, th)
#define NBT_J1_SUM(T, th, g) nbt_j1_sum(T, th)
#define NBT_JN_SUM(T, th, g) nbt_jn_sum(T, th)

float nbt_j1_sum(float T, float th)
{
    float s = dot(nbt_hw[0], NBT_JLOOK(nbt_J1_0, nbt_J1_0_sub, nbt_J1_0_sub_w, nbt_J1_0_sub_c, T, th));
#if NBT_J1_PACKS > 1
    s += dot(nbt_hw[1], NBT_JLOOK(nbt_J1_1, nbt_J1_1_sub, nbt_J1_1_sub_w, nbt_J1_1_sub_c, T, th));
#endif
#if NBT_J1_PACKS > 2
    s += dot(nbt_hw[2], NBT_JLOOK(nbt_J1_2, nbt_J1_2_sub, nbt_J1_2_sub_w, nbt_J1_2_sub_c, T, th));
#endif
#if NBT_J1_PACKS > 3
    s += dot(nbt_hw[3], NBT_JLOOK(nbt_J1_3, nbt_J1_3_sub, nbt_J1_3_sub_w, nbt_J1_3_sub_c, T, th));
#endif
    return s;
}

#if NBT_JN_PACKS > 0
float nbt_jn_sum(float T, float th)
{
    float s = dot(nbt_hw[0], NBT_JLOOK(nbt_Jn_0, nbt_Jn_0_sub, nbt_Jn_0_sub_w, nbt_Jn_0_sub_c, T, th));
#if NBT_JN_PACKS > 1
    s += dot(nbt_hw[1], NBT_JLOOK(nbt_Jn_1, nbt_Jn_1_sub, nbt_Jn_1_sub_w, nbt_Jn_1_sub_c, T, th));
#endif
#if NBT_JN_PACKS > 2
    s += dot(nbt_hw[2], NBT_JLOOK(nbt_Jn_2, nbt_Jn_2_sub, nbt_Jn_2_sub_w, nbt_Jn_2_sub_c, T, th));
#endif
#if NBT_JN_PACKS > 3
    s += dot(nbt_hw[3], NBT_JLOOK(nbt_Jn_3, nbt_Jn_3_sub, nbt_Jn_3_sub_w, nbt_Jn_3_sub_c, T, th));
#endif
    return s;
}
#endif
#endif

// gph: the HG g of g-sliced tables (unused otherwise)
float nbt_surface_core(float kappa_s, float kappa_t, float I0, float dsp, float theta_s, float theta_r, float kd,
                       float ks, float n, float gph)
{
    float T = kappa_t * dsp;
    float direct = kd * max(cos(theta_s), 0.0);
    float scat = kd * NBT_J1_SUM(T, theta_s, gph);
#if NBT_JN_PACKS > 0
    direct += ks * pow(max(cos(theta_r), 0.0), n);
    scat += ks * NBT_JN_SUM(T, theta_r, gph);
#endif
    return I0 * exp(-T) / (dsp * dsp) * direct + kappa_s * I0 / (4.0 * NBT_PI * dsp) * scat;
}

#ifdef NBT_G_SLICED
float nbt_surface_g(float kappa_s, float kappa_t, float I0, float dsp, float theta_s, float theta_r, float kd, float ks,
                    float n, float g)
{
    return nbt_surface_core(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n, g);
}

float nbt_surface(float kappa_s, float kappa_t, float I0, float dsp, float theta_s, float theta_r, float kd, float ks,
                  float n)
{
    return nbt_surface_core(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n, nbt_g);
}
#else
float nbt_surface(float kappa_s, float kappa_t, float I0, float dsp, float theta_s, float theta_r, float kd, float ks,
                  float n)
{
    return nbt_surface_core(kappa_s, kappa_t, I0, dsp, theta_s, theta_r, kd, ks, n, 0.0);
}
#endif
