// shaders/nbt_airlight.glsl: airlight of an isotropic point source along a
// view ray from H tables (Hong, eq. 4.18 with albedo and 1/4pi explicit):
//   L_a = kappa_s I0 e^{-kappa_t t}/(4 pi h) sum_k w_k [H_k(kappa_t h, theta_d) - H_k(kappa_t h, theta_0)]
// Defines: NBT_H_PACKS (1..4 RGBA textures holding orders 4p..4p+3) with
// weights nbt_hw[p] (nbt_weights.glsl; a pack of form sub adds its closed
// form back: nbt_Hp_sub, _sub_w, _sub_c, nbt_sub in nbt_table.glsl), or, with NBT_FIXED_PHASE, one
// fixed-phase table (channel R, weight (1, 0, 0, 0)), or, with NBT_G_SLICED,
// one g-sliced table H_p(u, v; g) of the HG phase (a sampler3D, channel R,
// axis 2 = g, the tail form below): nbt_airlight_g(..., g) reads it at any g,
// nbt_airlight at the uniform nbt_g (g clamps to the table's g range).
// Singular places: gamma is clamped to [NBT_GAMMA_EPS, pi - NBT_GAMMA_EPS]
// (a ray through the source has infinite airlight; the clamp gives that of a
// ray passing at angle NBT_GAMMA_EPS); u beyond the table reads its edge.
#ifndef NBT_GAMMA_EPS
#define NBT_GAMMA_EPS 1e-3
#endif
#ifdef NBT_G_SLICED
NBT_SAMPLER3D(nbt_H0, 3)
#else
NBT_SAMPLER(nbt_H0, 3)
#endif
#if NBT_H_PACKS > 1
NBT_SAMPLER(nbt_H1, 4)
#endif
#if NBT_H_PACKS > 2
NBT_SAMPLER(nbt_H2, 5)
#endif
#if NBT_H_PACKS > 3
NBT_SAMPLER(nbt_H3, 6)
#endif
NBT_BLOCK_BEGIN(nbt_H_block, 1)
NBT_U vec4 nbt_H_ax0, nbt_H_ax1; // u axis, v axis: vec4(lo, hi, c, n)
NBT_U int nbt_H_map0, nbt_H_map1;
#ifdef NBT_G_SLICED
NBT_U vec4 nbt_H_ax2; // g axis
NBT_U int nbt_H_map2;
NBT_U int nbt_H_interp2; // the table's interp2: 3 cubic in g (nbt_lookup3c), else quadratic (nbt_lookup3q)
#else
// per pack: form sub's closed form (nbt_sub; set by nbt_gl_set_table_sub, all 0 for a plain table)
NBT_U vec4 nbt_H0_sub_c[10];
NBT_U int nbt_H0_sub;
NBT_U float nbt_H0_sub_w;
#if NBT_H_PACKS > 1
NBT_U vec4 nbt_H1_sub_c[10];
NBT_U int nbt_H1_sub;
NBT_U float nbt_H1_sub_w;
#endif
#if NBT_H_PACKS > 2
NBT_U vec4 nbt_H2_sub_c[10];
NBT_U int nbt_H2_sub;
NBT_U float nbt_H2_sub_w;
#endif
#if NBT_H_PACKS > 3
NBT_U vec4 nbt_H3_sub_c[10];
NBT_U int nbt_H3_sub;
NBT_U float nbt_H3_sub_w;
#endif
#endif
NBT_BLOCK_END

#ifndef NBT_G_SLICED

// one pack's H(u, v1) - H(u, v0), its closed form added back for form sub
#define NBT_H_PACK(t, sub, w, c) (nbt_lookup_sub(t, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, sub, w, c, u, v1) - nbt_lookup_sub(t, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, sub, w, c, u, v0))

// sum_k w_k [H_k(u, v1) - H_k(u, v0)]
float nbt_h_diff(float u, float v0, float v1)
{
    float s = dot(nbt_hw[0], NBT_H_PACK(nbt_H0, nbt_H0_sub, nbt_H0_sub_w, nbt_H0_sub_c));
#if NBT_H_PACKS > 1
    s += dot(nbt_hw[1], NBT_H_PACK(nbt_H1, nbt_H1_sub, nbt_H1_sub_w, nbt_H1_sub_c));
#endif
#if NBT_H_PACKS > 2
    s += dot(nbt_hw[2], NBT_H_PACK(nbt_H2, nbt_H2_sub, nbt_H2_sub_w, nbt_H2_sub_c));
#endif
#if NBT_H_PACKS > 3
    s += dot(nbt_hw[3], NBT_H_PACK(nbt_H3, nbt_H3_sub, nbt_H3_sub_w, nbt_H3_sub_c));
#endif
    return s;
}
#define NBT_H_DIFF(u, v0, v1, g) nbt_h_diff(u, v0, v1)

// kappa_s, kappa_t [1/length], I0, dsv = viewer-source distance, gamma = angle
// between the view ray and the source direction, dvp = distance to the
// surface along the ray (use a huge value, e.g. 1e30, for none); gph: the
// HG g of a g-sliced table (unused otherwise)
float nbt_airlight_core(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp, float gph)
{
    float g = clamp(gamma, NBT_GAMMA_EPS, NBT_PI - NBT_GAMMA_EPS);
    float h = dsv * sin(g), t = dsv * cos(g);
    float th0 = g - 0.5 * NBT_PI;
    float thd = atan(dvp - t, h);
    float d = NBT_H_DIFF(kappa_t * h, th0, thd, gph);
    // e^{-kappa_t t} can overflow where t < 0 while d is tiny: combine in logs
    return d == 0.0 ? 0.0 : sign(d) * exp(-kappa_t * t + log(abs(d) * kappa_s * I0 / (4.0 * NBT_PI * h)));
}
#endif

#ifdef NBT_G_SLICED
// The g-sliced H table is in the tail form (libnbt/gslice_tail.c, doc/tables.md):
// channel R holds log(C W), C(u, v; g) = int_v^{pi/2} e^{-u (s(t) - s(v))} 4 pi p_g(-sin t) dt,
// W = 1 + s/2 + u s^2/2, s(v) = tan(pi/4 + v/2); with t_f = d_sv cos(gamma),
// u s(theta_0) + kappa_t t_f = kappa_t d_sv and u s(theta_d) + kappa_t t_f = kappa_t (d_sp + d_vp):
//   L_a = kappa_s I0/(4 pi h) [e^{-kappa_t d_sv} C(u, theta_0) - e^{-kappa_t (d_sp + d_vp)} C(u, theta_d)].
// Where the second term exceeds NBT_TAIL_SHORT of the first, the segment is integrated instead
// by the 16-point Gauss-Legendre rule in HG's angle phi = 2 atan(s (1 + g)/(1 - g)), where
// 4 pi p dt = sqrt(1 + g^2 + 2 g cos phi)/(1 - g^2) dphi. nbt_airlight_table_g does the same.
#ifndef NBT_TAIL_SHORT
#define NBT_TAIL_SHORT 0.25
#endif
const float nbt_gl16x[8] = float[8](0.095012509838, 0.281603550779, 0.458016777657, 0.617876244403,
                                    0.755404408355, 0.865631202388, 0.944575023073, 0.989400934992);
const float nbt_gl16w[8] = float[8](0.189450610455, 0.182603415045, 0.169156519395, 0.149595988817,
                                    0.124628971256, 0.095158511682, 0.062253523939, 0.027152459412);

// s(t) = tan(pi/4 + t/2) without cancellation on either side of t = 0
float nbt_tail_s(float t)
{
    return t < 0.0 ? cos(t) / (1.0 - sin(t)) : (1.0 + sin(t)) / cos(t);
}

// C(u, v; g) from the table
float nbt_tail_c(float u, float v, float s, float g)
{
    float r = nbt_H_interp2 == 3
        ? nbt_lookup3c(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, nbt_H_ax2, nbt_H_map2, u, v, g).r
        : nbt_lookup3q(nbt_H0, nbt_H_ax0, nbt_H_map0, nbt_H_ax1, nbt_H_map1, nbt_H_ax2, nbt_H_map2, u, v, g).r;
    return exp(r) / (1.0 + 0.5 * s + 0.5 * u * s * s);
}

// int over [phi_0, phi_d] of e^{-e0 - u (s - s0)} sqrt(1 + g^2 + 2 g cos phi)/(1 - g^2) dphi,
// 16 points, s = k tan(phi/2), s0 = s(theta_0), ds = s(theta_d) - s0; written without
// cancellation: dphi by the atan difference, u (s - s0) = u k sin(delta/2)/(cos(phi/2) cos(phi_0/2))
float nbt_tail_gauss(float g, float u, float e0, float s0, float ds)
{
    float k = (1.0 - g) / (1.0 + g), a = s0 / k, b = a + ds / k;
    float c0 = inversesqrt(1.0 + a * a), n0 = a * c0, dphi = 2.0 * atan((ds / k) / (1.0 + a * b)), sum = 0.0;
    for (int i = 0; i < 8; i++) {
        for (int sg = -1; sg <= 1; sg += 2) {
            float hd = 0.25 * dphi * (1.0 + float(sg) * nbt_gl16x[i]), sd = sin(hd), ci = c0 * cos(hd) - n0 * sd;
            float y = e0 + u * k * sd / (ci * c0);
            sum += nbt_gl16w[i] * exp(-y) * sqrt(max(1.0 + g * g + 2.0 * g * (2.0 * ci * ci - 1.0), 0.0));
        }
    }
    return 0.5 * dphi * sum / (1.0 - g * g);
}

float nbt_airlight_g(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp, float gph)
{
    float gm = clamp(gamma, NBT_GAMMA_EPS, NBT_PI - NBT_GAMMA_EPS);
    float g = clamp(gph, nbt_H_ax2.x, nbt_H_ax2.y);
    float h = dsv * sin(gm), tf = dsv * cos(gm), u = kappa_t * h;
    float th0 = gm - 0.5 * NBT_PI, thd = atan(dvp - tf, h);
    float s0 = tan(0.5 * gm), dsp = length(vec2(dvp - tf, h)); // s(theta_0) = tan(gamma/2): no cancellation
    float A = exp(-kappa_t * dsv), B = exp(-kappa_t * (dsp + dvp));
    float c0 = nbt_tail_c(u, th0, s0, g), bd = 0.0;
    float pref = kappa_s * I0 / (4.0 * NBT_PI * h);
    if (B > 0.0 && thd < 0.5 * NBT_PI) {
        float sd = nbt_tail_s(thd);
        bd = B * nbt_tail_c(u, thd, sd, g);
        if (bd > NBT_TAIL_SHORT * A * c0) {
            // d_sp + d_vp - d_sv = d_vp (d_sv - t_f + d_sp + d_vp - t_f)/(d_sp + d_sv), without cancellation
            float q = dvp - tf, sh = sin(0.5 * gm);
            float ex = dvp * (2.0 * dsv * sh * sh + (q >= 0.0 ? dsp + q : h * h / (dsp - q))) / (dsp + dsv);
            return pref * nbt_tail_gauss(g, u, kappa_t * dsv, s0, ex / h);
        }
    }
    return pref * (A * c0 - bd);
}

float nbt_airlight(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp)
{
    return nbt_airlight_g(kappa_s, kappa_t, I0, dsv, gamma, dvp, nbt_g);
}
#else
float nbt_airlight(float kappa_s, float kappa_t, float I0, float dsv, float gamma, float dvp)
{
    return nbt_airlight_core(kappa_s, kappa_t, I0, dsv, gamma, dvp, 0.0);
}
#endif
