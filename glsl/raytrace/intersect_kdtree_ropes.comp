#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// kd-tree, stackless along ropes (survey §2.3.3, PGSS07): the entry point's leaf is
// located from the root; then, leaf by leaf, the ray leaves through one face of the leaf's
// box, follows that face's rope to the node across it and descends from there to the leaf
// holding the exit point. The leaves' boxes and ropes are accel_aux words (12 per leaf at
// the offset in the leaf's third word, src/methods/raytrace/kdtree.rs). A hit before the
// leaf's exit (widened by ray_box's 1 + 2γ₃) is the nearest, as in kdtree.glsl.
#include "raytrace/kdtree.glsl"

const uint KD_NO_ROPE = 0xffffffffu;  // src/methods/raytrace/kdtree.rs NO_ROPE

// The leaf under `node` holding point p; on a split plane, the side the ray heads to.
uint kd_locate(uint node, vec3 p, vec3 d) {
    for (uint i = 0u; i <= KD_MAX_DEPTH; ++i) {
        uvec4 w = accel_nodes[node];
        if (w.w == KD_LEAF) return node;
        uint a = w.w;
        float s = uintBitsToFloat(w.x);
        node = (p[a] < s || (p[a] == s && d[a] < 0.0)) ? w.y : w.z;
    }
    return node;
}

RayHit intersect_kdtree_ropes(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.node_count == 0u) return best;
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    vec3 inv_d = safe_inverse(d);
    vec3 ta = (accel.bounds_min.xyz - o) * inv_d;
    vec3 tb = (accel.bounds_max.xyz - o) * inv_d;
    vec3 t_lo = min(ta, tb);
    vec3 t_hi = max(ta, tb);
    float t0 = max(max(t_lo.x, t_lo.y), max(t_lo.z, q.origin.w));
    float t_end = min(min(t_hi.x, t_hi.y), min(t_hi.z, best.t)) * 1.0000004;
    if (!(t0 <= t_end)) return best;
    // The faces the ray can leave a box through: per axis, the one it heads to.
    bvec3 up = greaterThanEqual(d, vec3(0.0));
    uint node = kd_locate(0u, o + d * t0, d);
    for (uint step = 0u; step < KD_STEPS; ++step) {
        uvec4 w = accel_nodes[node];
        if (kd_leaf(w, q, best)) return best;
        uint a = w.z;
        vec3 lo = uintBitsToFloat(uvec3(accel_aux[a], accel_aux[a + 1u], accel_aux[a + 2u]));
        vec3 hi = uintBitsToFloat(uvec3(accel_aux[a + 3u], accel_aux[a + 4u], accel_aux[a + 5u]));
        vec3 t_far = (mix(lo, hi, up) - o) * inv_d;
        uint axis = t_far.x <= t_far.y ? (t_far.x <= t_far.z ? 0u : 2u) : (t_far.y <= t_far.z ? 1u : 2u);
        float t_exit = t_far[axis];
        if (best.t <= t_exit * 1.0000004) return best;
        if (t_exit >= t_end) return best;
        uint rope = accel_aux[a + 6u + 2u * axis + (up[axis] ? 1u : 0u)];
        if (rope == KD_NO_ROPE) return best;
        node = kd_locate(rope, o + d * t_exit, d);
    }
    return best;
}

#define INTERSECT intersect_kdtree_ropes
#include "raytrace/intersect_main.glsl"
