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

RayQuery make_query(vec3 o, vec3 d, float t_min, float t_max, uint skip, uint flags) {
    return RayQuery(vec4(o, t_min), vec4(d, t_max), skip, flags, uint[2](0u, 0u));
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
