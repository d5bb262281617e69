// shaders/nbt_mc.glsl: the GLSL compute photon counter (nbt/gl_mc.h), the
// analog loop of libnbt/mc.c in single precision: a pencil beam at the origin
// along +z into a homogeneous medium (a slab [0, top], or a half-space whose
// photons are dropped beyond z_cut; infinite: the medium also fills z < 0),
// HG or Gaussian phase. One invocation is one photon; its random numbers
// are Philox4x32-10 keyed by the seed, counter (photon index, draw), so a
// photon's path depends on nothing else. Tallies are 64-bit integers held
// as (lo, hi) uint pairs (no 64-bit atomics needed): counts add 1, r^2 adds
// round(r^2 2^20); integer sums do not depend on the order of the atomics,
// hence not on the work-group size or how photons are split over dispatches.
// The host prepends "#version 430" and "#define NBT_MC_WG n".
layout(local_size_x = NBT_MC_WG) in;

layout(std430, binding = 0) buffer Tally { uint t[]; };       // [(batch stride + k) 2 + {lo, hi}]
layout(std430, binding = 1) readonly buffer Planes { float zp[]; };

uniform uvec2 u_seed;       // 64-bit seed as (lo, hi)
uniform uvec2 u_first;      // first photon index of this dispatch (lo, hi)
uniform uint u_count;       // photons in this dispatch
uniform uint u_base;        // tally offset of the batch: batch * stride
uniform float u_sigma_t, u_albedo, u_bottom, u_top, u_param, u_rscale;
uniform int u_phase;        // 0: HG (u_param = g), 1: Gaussian (u_param = B)
uniform int u_slab, u_nplanes, u_nbins;
uniform uint u_order_max;   // 0: all orders

uvec4 philox(uvec4 c, uvec2 k)
{
    for (int i = 0; i < 10; i++) {
        uint hi0, lo0, hi1, lo1;
        umulExtended(0xD2511F53u, c.x, hi0, lo0);
        umulExtended(0xCD9E8D57u, c.z, hi1, lo1);
        c = uvec4(hi1 ^ c.y ^ k.x, lo1, hi0 ^ c.w ^ k.y, lo0);
        k += uvec2(0x9E3779B9u, 0xBB67AE85u);
    }
    return c;
}

uvec2 g_ph;     // this photon's index
uint g_draw;    // blocks of 4 drawn so far
uvec4 g_buf;
int g_left = 0;

// uniform in [0, 1) on a 2^-24 grid
float rnd()
{
    if (g_left == 0) {
        g_buf = philox(uvec4(g_ph, g_draw++, 0u), u_seed);
        g_left = 4;
    }
    g_left--;
    uint v = g_left == 3 ? g_buf.x : g_left == 2 ? g_buf.y : g_left == 1 ? g_buf.z : g_buf.w;
    return float(v >> 8) * (1.0 / 16777216.0);
}

void add64(uint i, uint v)
{
    uint old = atomicAdd(t[2u * i], v);
    if (old > 0xFFFFFFFFu - v)
        atomicAdd(t[2u * i + 1u], 1u);
}

void addfix(uint i, float x) // x >= 0 in units of 2^-20, as a 64-bit integer
{
    float v = x * 1048576.0;
    uint hi = uint(v * (1.0 / 4294967296.0));
    uint lo = uint(v - float(hi) * 4294967296.0 + 0.5);
    add64(i, lo);
    if (hi > 0u)
        atomicAdd(t[2u * i + 1u], hi);
}

uniform uint u_threads;      // invocations in this dispatch (a multiple of the work-group size)

vec3 p, u;
uint scattered;
int jp; // first plane above z

// photon k of this dispatch: index u_first + k, at the origin along +z
void start(uint k)
{
    uint lo = u_first.x + k;
    g_ph = uvec2(lo, u_first.y + (lo < k ? 1u : 0u));
    g_draw = 0u;
    g_left = 0;
    p = vec3(0.0);
    u = vec3(0.0, 0.0, 1.0);
    scattered = 0u;
    jp = 0;
}

// Each invocation runs photons k = id, id + u_threads, ... one step at a
// time, starting the next photon as soon as one ends, so that the lanes of
// a SIMD group stay busy instead of waiting for the longest photon.
void main()
{
    uint k = gl_GlobalInvocationID.x;
    if (k >= u_count)
        return;
    start(k);
    uint events = 0u, stride = uint(u_nplanes * (u_nbins + 2) + 3);
    uint refl = 0u, trans = 0u;
    for (;;) {
        bool done = false;
        float d = -log(1.0 - rnd()) / u_sigma_t;
        float z1 = p.z + d * u.z;
        bool leaves = !(z1 > u_bottom && z1 < u_top);
        float zend = leaves ? (u.z > 0.0 ? u_top : u_bottom) : z1;
        if (scattered > 0u && u.z > 0.0) { // forward crossings of planes in (z, zend]
            for (; jp < u_nplanes && zp[jp] <= zend; jp++) {
                float s = (zp[jp] - p.z) / u.z;
                vec2 q = p.xy + s * u.xy;
                float r2 = dot(q, q);
                uint pl = u_base + uint(jp * (u_nbins + 2));
                float bin = sqrt(r2) * float(u_nbins) / (u_rscale * zp[jp]);
                if (bin < float(u_nbins))
                    add64(pl + uint(bin), 1u);
                add64(pl + uint(u_nbins), 1u);
                addfix(pl + uint(u_nbins) + 1u, r2);
            }
        } else {
            while (jp > 0 && zp[jp - 1] > zend)
                jp--;
            while (jp < u_nplanes && zp[jp] <= zend)
                jp++;
        }
        if (leaves) {
            if (u_slab != 0) {
                if (u.z > 0.0)
                    trans++;
                else
                    refl++;
            }
            done = true;
        } else {
            p += d * u;
            p.z = z1;
            events++;
            if (rnd() >= u_albedo || (u_order_max > 0u && scattered == u_order_max)) {
                done = true;
            } else {
                scattered++;
                float mu;
                if (u_phase == 0) {
                    float g = u_param, r = rnd();
                    if (abs(g) < 1e-4) {
                        mu = 2.0 * r - 1.0;
                    } else {
                        float f = (1.0 - g * g) / (1.0 - g + 2.0 * g * r);
                        mu = clamp((1.0 + g * g - f * f) / (2.0 * g), -1.0, 1.0);
                    }
                } else {
                    // theta^2 exponential with mean 4B truncated at pi^2, by its inverse CDF
                    float a = 1.0 - exp(-9.8696044 / (4.0 * u_param));
                    float th = sqrt(-4.0 * u_param * log(1.0 - a * rnd()));
                    mu = cos(min(th, 3.14159265));
                }
                float st = sqrt(max(0.0, 1.0 - mu * mu)), phi = 6.2831853 * rnd(), cp = cos(phi), sp = sin(phi);
                // about u itself at every tilt: the orthonormal basis of Duff et al. (2017), no pole
                float sgn = u.z >= 0.0 ? 1.0 : -1.0, a = -1.0 / (sgn + u.z), b = u.x * u.y * a;
                vec3 e1 = vec3(1.0 + sgn * u.x * u.x * a, sgn * b, -sgn * u.x);
                vec3 e2 = vec3(b, sgn + u.y * u.y * a, -u.y);
                u = normalize(mu * u + st * (cp * e1 + sp * e2));
            }
        }
        if (done) {
            k += u_threads;
            if (k >= u_count)
                break;
            start(k);
        }
    }
    uint tail = u_base + stride - 3u;
    if (refl > 0u)
        add64(tail, refl);
    if (trans > 0u)
        add64(tail + 1u, trans);
    if (events > 0u)
        add64(tail + 2u, events);
}
