// The intersection query of ray tracing in the original geometry (survey §2.3.1): every
// scheme's kernel answers RayQuery → RayHit (set 2 of src/frame/layout.in.rs) with the
// same triangle test, so they agree hit for hit up to ties at shared edges.
#ifndef RAYTRACE_RAYS_GLSL
#define RAYTRACE_RAYS_GLSL
#include "common/scene.glsl"
#include "common/ray_triangle.glsl"

// lavapipe before Mesa 25 gives each invocation one budget of 65535 loop iterations shared by all its
// loops (gallivm's loop limiter: the loop that exhausts it stops). Traversals stay far
// below it (a ray visits hundreds of nodes or cells); brute force unrolls its loop. Mesa
// 25.0.7 has no such budget (measured: hash chains of 200000 and 2 × 200000 steps complete).

// Sample s of n per pixel, in the pixel's [0, 1)² (framebuffer axes): the Vulkan spec's
// standard sample locations for n = 2, 4, 8 (the positions an MSAA camera target samples
// where the device reports standardSampleLocations), the pixel centre for n = 1.
vec2 sample_position(uint s, uint n) {
    const vec2 two[2] = vec2[2](vec2(0.75, 0.75), vec2(0.25, 0.25));
    const vec2 four[4] = vec2[4](vec2(0.375, 0.125), vec2(0.875, 0.375), vec2(0.125, 0.625), vec2(0.625, 0.875));
    const vec2 eight[8] = vec2[8](vec2(0.5625, 0.3125), vec2(0.4375, 0.6875), vec2(0.8125, 0.5625), vec2(0.3125, 0.1875),
                                  vec2(0.1875, 0.8125), vec2(0.0625, 0.4375), vec2(0.6875, 0.9375), vec2(0.9375, 0.0625));
    if (n == 2u) return two[s & 1u];
    if (n == 4u) return four[s & 3u];
    if (n == 8u) return eight[s & 7u];
    return vec2(0.5);
}

RayHit no_hit(RayQuery q) {
    return RayHit(q.direction.w, 0.0, 0.0, RAY_NO_TRIANGLE);
}

// Triangles are widened by this much of their barycentric extent: a ray through a shared
// edge hits both neighbours instead of slipping between them through f32 rounding (a crack:
// measured, rays through the edges where two walls of a room meet escaped the room).
const float RAY_EDGE_EPS = 9.5367431640625e-7;  // 2^-20

// Tests triangle `id` (never the one the ray leaves); a hit nearer than best.t replaces it.
bool test_triangle(uint id, RayQuery q, inout RayHit best) {
    if (id == q.skip) return false;
    Triangle tr = triangles[id];
    vec3 tuv;
    if (!ray_triangle_eps(q.origin.xyz, q.direction.xyz, tr.v0.xyz, tr.v1.xyz, tr.v2.xyz, q.origin.w, best.t, RAY_EDGE_EPS, tuv)) return false;
    best = RayHit(tuv.x, tuv.y, tuv.z, id);
    return true;
}

// Tests the triangles refs[first..first + count] (a tree's leaf), four per iteration
// (lavapipe's loop budget: a leaf may list many triangles that no plane separates); true
// when an any-hit query may stop.
bool test_leaf(uint first, uint count, RayQuery q, inout RayHit best) {
    bool any_hit = (q.flags & RAY_ANY_HIT) != 0u;
    uint end = first + count;
#define LEAF_TEST(j) \
    if (i + j < end && test_triangle(accel_refs[i + j], q, best) && any_hit) return true;
    for (uint i = first; i < end; i += 4u) {
        LEAF_TEST(0u) LEAF_TEST(1u) LEAF_TEST(2u) LEAF_TEST(3u)
    }
    return false;
}

// 1 / d with zero components replaced by ±1e-30 (so that slab products never form 0 · ∞).
vec3 safe_inverse(vec3 d) {
    vec3 s = mix(vec3(1.0), vec3(-1.0), lessThan(d, vec3(0.0)));
    return 1.0 / mix(d, s * 1e-30, lessThan(abs(d), vec3(1e-30)));
}

// Slab test of the box [lo, hi] on t_min ≤ t ≤ t_max; `t_near` is where the ray enters.
// The far bound is widened by 1 + 2γ₃ (PBRT's robust bounds) so that rounding never
// rejects a box that a hit on its face lies in.
bool ray_box(vec3 lo, vec3 hi, vec3 o, vec3 inv_d, float t_min, float t_max, out float t_near) {
    vec3 t0 = (lo - o) * inv_d;
    vec3 t1 = (hi - o) * inv_d;
    vec3 a = min(t0, t1);
    vec3 b = max(t0, t1);
    t_near = max(max(a.x, a.y), max(a.z, t_min));
    float t_far = min(min(b.x, b.y), min(b.z, t_max)) * 1.0000004;
    return t_near <= t_far;
}

#endif
