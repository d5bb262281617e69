// shaders/nbt_scatter_nbt.glsl: method nbt, the receivers. Pixel x in
// finite slab i (sky: i = n, D = 0: S = 0):
//   S = U col(i') + M0_x (U col(n + i) + delta_x U col(2n + i)) + centre
// i' = min(i, n - 1); the gather terms only for i < n; U the bilinear read
// of level 1 at x; delta_x = lb(beta_x) - nbt_sc_lb[i]; centre = the 3x3
// taps by the exact nearer-pixel rule of operator A (the source is
// farther: x's weights, else the source's; ties: the source's) from the
// per-pixel weights M0 (a00, a10, a11) of the centre table
// (nbt_gls_nbt_near_table, through nbt_scatter_near); a nearer pixel at
// D = 0 gives nothing.
// Within slab i the pyramid part sends every pair through the source's
// kernel, but operator A takes the nearer pixel's: a source y farther than
// the receiver x gives K_y - K_x too much (+2% energy on a floor receding
// to a horizon). nbt_sc_excess estimates that excess and the receiver
// subtracts it. Along a line from x the depth profile D(t) changes the
// kernel from K_{D(t)} to K_{D(t+dt)}, and the change applies to every
// source beyond t: the excess from one side is the sum over the profile's
// changes of c~ (band(K after, t) - band(K before, t)), band(K, t) =
// M0 (tail(t/beta) - tail(h/beta)) the kernel's mass at distances t .. h
// along the line (all across it; tail: nbt_gls_nbt_tail_table), h where
// the slab ends (farther sources are gathered with x's kernel) or the
// screen does; a tap nearer than x keeps x's kernel (no excess). The march
// samples the profile at t = 1, 2, 3, 4, 6, 8, 12, ... up to 2 beta_x (the
// atom's mass beyond 2 beta along a line is 0.3%); a change counts at the
// middle of its interval, with c~ the slab's mean colour there (the source
// pyramid's colour layer at level log2 of the interval, so a lamp between
// taps is not missed); the first interval leaves out the 3x3 taps (exact
// already). A straight step at distance d gives J tail(d), a slope g gives
// g times the kernel's uphill moment; marching both ways along x and along
// y and adding the axes in quadrature is exact for a slope in any
// direction and for the energy of a straight step in any direction. Not
// modelled: kernels wider than the screen's sides (the strips are assumed
// whole across the line).
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 3) uniform sampler2DArray nbt_sc_colt;
layout(binding = 4) uniform sampler2D nbt_sc_n0;
layout(rgba32f, binding = 0) uniform writeonly image2D nbt_sc_out;
uniform ivec2 nbt_sc_usize; // texture size of level 1 (texture level 0)
layout(binding = 5) uniform sampler2D nbt_sc_alut; // the atom's near table (nbt_gls_near_table)
layout(binding = 9) uniform sampler2D nbt_sc_dk; // nbt_sc_c's depth keys alone (R32F): a quarter of the memory per tap
layout(binding = 6) uniform sampler2D nbt_sc_tail; // nbt_gls_nbt_tail_table, texel k = (tail[k], tail[k + 1])
layout(binding = 7) uniform sampler2DArray nbt_sc_srct; // the source pyramid (levels 1 .. K)

// M0 (a10 + 2 a11) of the unit erfc atom at beta_px (as nbt_scatter_near):
// the 3x3 taps on one side of a line through x
float nbt_sc_side3(vec2 pq)
{
    int i;
    float f, scale;
    nbt_sc_lut_at(pq.y, i, f, scale);
    vec2 a = mix(texelFetch(nbt_sc_alut, ivec2(i, 0), 0).yz, texelFetch(nbt_sc_alut, ivec2(i + 1, 0), 0).yz, f);
    return pq.x * scale * (a.x + 2.0 * a.y);
}

// the unit atom's mass beyond v beta along a line (nbt_gls_nbt_tail_table), linear
float nbt_sc_tailv(float v)
{
    float u = v * float(NBT_SC_TAIL_PER);
    if (!(u < float(NBT_SC_TAIL_N - 1)))
        return 0.0;
    int k = int(u);
    float f = u - float(k);
    vec2 t = texelFetch(nbt_sc_tail, ivec2(k, 0), 0).rg; // (tail[k], tail[k + 1])
    return mix(t.x, t.y, f);
}

float nbt_sc_band(vec2 pq, float t, float h)
{
    float b = max(pq.y, 1e-6);
    return pq.x * (nbt_sc_tailv(t / b) - nbt_sc_tailv(h / b));
}

int nbt_sc_tap(int t)
{
    return t < 4 ? t + 1 : (t & (t - 1)) == 0 ? t + t / 2 : t + t / 3; // 1 2 3 4 6 8 12 16 24 32 ...
}

// the mean colour of slab i's pixels around pixel q over about 2^l px:
// level l of the source pyramid's layer C_i (nbt_scatter_nbt0), bilinear
vec3 nbt_sc_cmean(ivec2 q, int i, int l)
{
    vec2 sz = vec2(max(nbt_sc_usize >> (l - 1), ivec2(1)));
    vec2 uv = ((vec2(q) + 0.5) / float(1 << l) + 1.0) / sz; // logical (q + 0.5)/2^l - 0.5, physical + 1
    return textureLod(nbt_sc_srct, vec3(uv, float(2 * nbt_sc_nslab + i)), float(l - 1)).rgb;
}

// slab i's depth keys (i < n): nbt_sc_slab(D) == i exactly when D > 0,
// D >= r.x and D < r.y, the bounds never decreasing (nbt_gls_nbt_plan_of);
// two compares per tap instead of a loop over the bounds
vec2 nbt_sc_slab_range(int i)
{
    vec2 r = vec2(0.0, NBT_SC_SKY);
    for (int k = 1; k < NBT_SC_NBT_MAXSLABS; k++) {
        r.x = k == i ? nbt_sc_bound[k] : r.x;
        r.y = k == i + 1 && k < nbt_sc_nslab ? min(nbt_sc_bound[k], NBT_SC_SKY) : r.y;
    }
    return r;
}

// the excess from the sources on one side of x along axis direction e
// (r: slab i's nbt_sc_slab_range)
vec3 nbt_sc_march(ivec2 x, float Dx, vec2 r, int i, vec2 px, ivec2 e)
{
    const int NT = 24;
    float reach = 2.0 * px.y, h = 1e30;
    // pass 1: how many taps lie in the slab, where the slab or the screen
    // ends, whether any tap is farther than x (if none, no excess)
    int t = 1, tprev = 0, cnt = 0;
    bool farther = false;
    for (int k = 0; k < NT && float(t) <= reach; k++) {
        ivec2 y = x + t * e;
        if (!nbt_sc_inside(y, nbt_sc_size)) {
            h = float(e.x > 0 ? nbt_sc_size.x - x.x : e.x < 0 ? x.x + 1 : e.y > 0 ? nbt_sc_size.y - x.y : x.y + 1) - 0.5;
            break;
        }
        float Dy = texelFetch(nbt_sc_dk, y, 0).r;
        if (!(Dy > 0.0 && Dy >= r.x && Dy < r.y)) {
            h = 0.5 * float(tprev + t);
            break;
        }
        farther = farther || Dy > Dx;
        cnt++;
        tprev = t;
        t = nbt_sc_tap(t);
    }
    vec3 E = vec3(0.0);
    if (!farther)
        return E;
    // pass 2: each interval's change of kernel times the slab's mean colour
    // at its far tap, over about the interval's length. A tap whose kernel
    // is its predecessor's (nearer than x: x's own) changes nothing (d = 0
    // exactly) and is skipped; the predecessor's band beyond h is carried.
    vec2 prev = px;
    float hprev = nbt_sc_tailv(h / max(px.y, 1e-6));
    t = 1;
    tprev = 0;
    for (int k = 0; k < cnt; k++) {
        ivec2 y = x + t * e;
        float Dy = texelFetch(nbt_sc_dk, y, 0).r;
        vec2 ky = Dy > Dx ? texelFetch(nbt_sc_p, y, 0).xy : px;
        if (ky != prev) {
            float tm = 0.5 * float(tprev + t), by = max(ky.y, 1e-6), hy = nbt_sc_tailv(h / by);
            // nbt_sc_band(ky, tm, h) - nbt_sc_band(prev, tm, h), the same float operations
            float d = ky.x * (nbt_sc_tailv(tm / by) - hy) - prev.x * (nbt_sc_tailv(tm / max(prev.y, 1e-6)) - hprev);
            if (k == 0)
                d -= nbt_sc_side3(ky) - nbt_sc_side3(prev);
            E += d * nbt_sc_cmean(y, i, clamp(findMSB(t - tprev), 1, NBT_SC_NBT_K));
            prev = ky;
            hprev = hy;
        }
        tprev = t;
        t = nbt_sc_tap(t);
    }
    return E;
}

vec3 nbt_sc_excess(ivec2 x, float Dx, int i, vec2 px)
{
    vec2 r = nbt_sc_slab_range(i);
    vec3 ex = nbt_sc_march(x, Dx, r, i, px, ivec2(1, 0)) + nbt_sc_march(x, Dx, r, i, px, ivec2(-1, 0));
    vec3 ey = nbt_sc_march(x, Dx, r, i, px, ivec2(0, 1)) + nbt_sc_march(x, Dx, r, i, px, ivec2(0, -1));
    return sign(ex + ey) * sqrt(ex * ex + ey * ey);
}

void main()
{
    ivec2 x = ivec2(gl_GlobalInvocationID.xy);
    if (!nbt_sc_inside(x, nbt_sc_size))
        return;
    float Dx = texelFetch(nbt_sc_c, x, 0).a;
    int i = nbt_sc_slab(Dx), n = nbt_sc_nslab;
    vec3 s = vec3(0.0);
    if (i >= 0) {
        vec2 uv = (0.5 * (vec2(x) + 0.5) + 1.0) / vec2(nbt_sc_usize); // logical (x + 0.5)/2 - 0.5, physical + 1
        s = textureLod(nbt_sc_colt, vec3(uv, float(min(i, n - 1))), 0.0).rgb;
        vec2 p = texelFetch(nbt_sc_p, x, 0).xy;
        if (i < n && p.x > 0.0) {
            float d = nbt_sc_lbeta(p.y) - nbt_sc_lb[i];
            s += p.x * (textureLod(nbt_sc_colt, vec3(uv, float(n + i)), 0.0).rgb +
                        d * textureLod(nbt_sc_colt, vec3(uv, float(2 * n + i)), 0.0).rgb);
        }
        if (i < n)
            s -= nbt_sc_excess(x, Dx, i, p);
        vec4 nx = texelFetch(nbt_sc_n0, x, 0);
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                ivec2 y = x + ivec2(dx, dy);
                if (!nbt_sc_inside(y, nbt_sc_size))
                    continue;
                vec4 cy = texelFetch(nbt_sc_c, y, 0);
                bool mine = cy.a > Dx;
                if (!mine && !(cy.a > 0.0))
                    continue;
                s += (mine ? nx : texelFetch(nbt_sc_n0, y, 0))[abs(dx) + abs(dy)] * cy.rgb;
            }
    }
    imageStore(nbt_sc_out, x, vec4(s, 1.0));
}
