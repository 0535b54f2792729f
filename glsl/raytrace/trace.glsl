// The ray pipeline's shared pieces (survey §2.3.1): the surface a hit lies on, the
// fixed-point radiance accumulator, and appending to the ray and shadow queues. Every
// kernel of src/methods/raytrace/stage.rs includes it.
#ifndef RAYTRACE_TRACE_GLSL
#define RAYTRACE_TRACE_GLSL
#define SHADING_LOD0
#include "raytrace/rays.glsl"
#include "common/specular.glsl"

// Branches whose weight is below this in every channel are not followed (the CPU
// reference's MIN_PATH_WEIGHT).
const float MIN_PATH_WEIGHT = 1e-6;

struct Surface {
    vec3 p;   // position
    vec3 n;   // interpolated unit normal (geometric normal where it degenerates)
    vec2 uv;
    uint material;
};

// The surface at hit h: position from the barycentrics on the triangle's corners, the
// interpolated normal and texture coordinates, as the reference's `surface`.
Surface hit_surface(RayHit h) {
    Triangle tr = triangles[h.triangle];
    TriangleShading sh = shading[h.triangle];
    float w = 1.0 - h.u - h.v;
    Surface s;
    vec3 e1 = tr.v1.xyz - tr.v0.xyz;
    vec3 e2 = tr.v2.xyz - tr.v0.xyz;
    s.p = tr.v0.xyz + e1 * h.u + e2 * h.v;
    vec3 n = sh.n0.xyz * w + sh.n1.xyz * h.u + sh.n2.xyz * h.v;
    vec3 g = cross(e1, e2);
    s.n = dot(n, n) > 0.0 ? normalize(n) : (dot(g, g) > 0.0 ? normalize(g) : vec3(0.0, 1.0, 0.0));
    s.uv = sh.uv01.xy * w + sh.uv01.zw * h.u + sh.uv2.xy * h.v;
    s.material = floatBitsToUint(sh.n0.w);
    return s;
}

// Adds c (≥ 0, clamped to 2048) to pixel's 64-bit fixed-point sums, 2^-20 per unit: the
// low word's carry goes to the high word. Integer additions commute, so the result does
// not depend on the order in which rays reach the pixel.
const float ACCUM_SCALE = 1048576.0;  // 2^20
void accumulate(uint pixel, vec3 c) {
    c = clamp(c, vec3(0.0), vec3(2048.0));
    for (uint k = 0u; k < 3u; ++k) {
        uint add = uint(c[k] * ACCUM_SCALE + 0.5);
        if (add == 0u) continue;
        uint i = 6u * pixel + 2u * k;
        uint old = atomicAdd(accum[i], add);
        if (old + add < old) atomicAdd(accum[i + 1u], 1u);
    }
}

// Queue budgets: which rays a queue keeps when more arrive than it holds must not depend on
// the order the GPU runs the kernels that make them, or an overflowing frame would differ
// from run to run. The kernel that makes them runs in modes (push.object):
//   BUDGET_COUNT: counts its rays per weight bin (half an octave of the largest channel),
//   BUDGET_SUB: counts the rays of the cut bin per sub-bin (a hash of pixel and direction),
//   BUDGET_KEEP: queues the rays of the bins before the cut and of the sub-bins before the
//     sub-cut, and counts the others as dropped with their weight;
// spawn_cutoff.comp cuts between them. The heaviest paths are kept; within the cut bin a
// spatially even subset. BUDGET_ALL (shade.comp only): no budget, everything queued.
const uint BUDGET_ALL = 0u;
const uint BUDGET_COUNT = 1u;
const uint BUDGET_SUB = 2u;
const uint BUDGET_KEEP = 3u;

uint weight_bin(vec3 w) {
    float m = max(max(w.x, w.y), w.z);
    return uint(clamp(floor((16.0 - log2(max(m, 1e-30))) * 2.0), 0.0, float(SPAWN_BINS - 1u)));
}

uint budget_hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

uint sub_bin(uint pixel, vec3 d) {
    uint h = budget_hash(pixel);
    h = budget_hash(h ^ floatBitsToUint(d.x));
    h = budget_hash(h ^ floatBitsToUint(d.y));
    h = budget_hash(h ^ floatBitsToUint(d.z));
    return h >> 26;  // 0 … 63
}

// Budget `which` (0: the next ray queue, spawn_budget; 1: the shadow queue, shadow_budget)
// in `mode` for a ray of weight w: true where the ray is to be queued now.
bool budget_admit(uint which, uint mode, vec3 w, uint pixel, vec3 d) {
    if (mode == BUDGET_ALL) return true;
    uint bin = weight_bin(w);
    uint cutoff = which == 0u ? spawn_budget.cutoff : shadow_budget.cutoff;
    if (mode == BUDGET_COUNT) {
        if (which == 0u) atomicAdd(spawn_budget.hist[bin], 1u); else atomicAdd(shadow_budget.hist[bin], 1u);
        return false;
    }
    if (mode == BUDGET_SUB) {
        if (bin != cutoff) return false;
        uint s = sub_bin(pixel, d);
        if (which == 0u) atomicAdd(spawn_budget.sub[s], 1u); else atomicAdd(shadow_budget.sub[s], 1u);
        return false;
    }
    if (bin < cutoff) return true;
    if (bin == cutoff) {
        uint sub_cutoff = which == 0u ? spawn_budget.sub_cutoff : shadow_budget.sub_cutoff;
        if (sub_bin(pixel, d) < sub_cutoff) return true;
    }
    uint add = uint(clamp(max(max(w.x, w.y), w.z), 0.0, 2048.0) * ACCUM_SCALE + 0.5);
    if (which == 0u) {
        atomicAdd(spawn_budget.dropped, 1u);
        uint old = atomicAdd(spawn_budget.dropped_weight[0], add);
        if (old + add < old) atomicAdd(spawn_budget.dropped_weight[1], 1u);
    } else {
        atomicAdd(shadow_budget.dropped, 1u);
        uint old = atomicAdd(shadow_budget.dropped_weight[0], add);
        if (old + add < old) atomicAdd(shadow_budget.dropped_weight[1], 1u);
    }
    return false;
}

RayQuery make_query(vec3 o, vec3 d, float t_min, float t_max, uint skip, uint flags) {
    return RayQuery(vec4(o, t_min), vec4(d, t_max), skip, flags, 0u, 0u);
}

RayPayload make_payload(vec3 weight, uint pixel) {
    return RayPayload(vec4(weight, 0.0), pixel, uint[3](0u, 0u, 0u));
}

// Appends a ray to the next bounce's queue; false when the queue is full (the ray is
// dropped: the counter still counts it, so the frame can report the overflow).
bool push_ray(RayQuery q, RayPayload p) {
    uint slot = atomicAdd(next_count, 1u);
    if (slot >= trace.capacity) return false;
    next_queries[slot] = q;
    next_payloads[slot] = p;
    return true;
}

bool push_shadow(RayQuery q, RayPayload p) {
    uint slot = atomicAdd(shadow_count, 1u);
    if (slot >= trace.shadow_capacity) return false;
    shadow_queries[slot] = q;
    shadow_payloads[slot] = p;
    return true;
}

// The camera ray of pixel (x, y) through its sample s (the pixel centre without MSAA)
// through the camera view's inverse projection: the reference's CameraRays
// (src/reference/mod.rs).
void camera_ray(uint x, uint y, uint s, out vec3 o, out vec3 d) {
    View v = views[push.view];
    vec2 ndc = (vec2(x, y) + sample_position(s, trace.samples)) / vec2(trace.width, trace.height) * 2.0 - 1.0;
    vec4 far_point = v.inv_view_proj * vec4(ndc, 1e-4, 1.0);
    o = v.eye.xyz;
    d = normalize(far_point.xyz / far_point.w - o);
}

// The ray parameter of the camera's near plane along the unit camera ray d (reversed-Z:
// NDC depth 1 is the near plane), so that traced primary rays clip where rasterisation does.
float near_plane_t(vec3 d) {
    View v = views[push.view];
    vec4 c = v.inv_view_proj * vec4(0.0, 0.0, 1.0, 1.0);
    vec3 to_near = c.xyz / c.w - v.eye.xyz;
    float znear = length(to_near);
    float cos_a = dot(d, to_near / max(znear, 1e-30));
    return cos_a > 0.0 ? znear / cos_a : 0.0;
}

#endif
