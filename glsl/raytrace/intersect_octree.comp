#version 460
#extension GL_GOOGLE_include_directive : require
// variants: OCTREE_VOLUME GRADED_MEDIA OCTREE_VOLUME_GRADED_MEDIA
#ifdef OCTREE_VOLUME_GRADED_MEDIA
#define OCTREE_VOLUME
#define GRADED_MEDIA
#endif
// Octree traversal (survey §2.3.2, MGK05) over the nodes of src/methods/raytrace/octree.rs:
// node k is accel_nodes[k] = (first child, 0, 0, OCT_INTERIOR) with eight children first + i,
// i = x | y << 1 | z << 2 the upper halves, or (first reference, count, aux, OCT_LEAF); node
// 0 is the root, whose cube is accel.bounds_min/max.
//
// The ray's current point (its entry into the root at first) is located by a top-down
// containment test from the root, halving the cell as the builder did (mid = lo + half); the
// leaf's triangles are tested; unless a hit lies within the leaf, the ray moves on to the
// point where it leaves the leaf, that point's coordinate on the face it leaves through set
// to the face's (so that the next descent, which sends a point on a mid plane to the side
// the ray heads to, lands in the neighbour: the survey's "translating the exit point a
// little along the ray", without an epsilon). The builder lists a triangle in every cell its
// part reaches within a slack, so a point that f32 rounding attributes to a neighbouring
// cell still finds it.
//
// OCTREE_VOLUME (MGK05's volumetric approximation): a leaf is one plane (aux words: unit
// normal, w) and a representative triangle, instead of its triangles; the hit is where the
// ray meets the plane inside the leaf, reported on the representative triangle at the
// plane hit's barycentrics clamped to it.
#include "raytrace/rays.glsl"

const uint OCT_INTERIOR = 0u;  // src/methods/raytrace/octree.rs INTERIOR
const uint OCT_LEAF = 1u;      // LEAF
const uint OCT_MAX_DEPTH = 20u;  // MAX_DEPTH
// A bound on the leaves one ray visits (guarding against rounding that keeps it in place).
const uint OCT_STEPS = 16384u;

#ifdef OCTREE_VOLUME
// The ray against leaf w's plane inside [t0, t1] (and before the best hit).
bool oct_volume(uvec4 w, RayQuery q, float t0, float t1, inout RayHit best) {
    uint a = w.z;
    uint tri = accel_aux[a + 4u];
    if (tri == RAY_NO_TRIANGLE || tri == q.skip) return false;
    vec3 n = uintBitsToFloat(uvec3(accel_aux[a], accel_aux[a + 1u], accel_aux[a + 2u]));
    float pw = uintBitsToFloat(accel_aux[a + 3u]);
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    float den = dot(n, d);
    if (abs(den) < 1e-30) return false;
    float t = -(dot(n, o) + pw) / den;
    if (!(t >= max(t0, q.origin.w) && t <= t1 * 1.0000004 && t < best.t)) return false;
    // Barycentrics of the plane hit projected into the representative, clamped to it.
    Triangle tr = triangles[tri];
    vec3 e1 = tr.v1.xyz - tr.v0.xyz;
    vec3 e2 = tr.v2.xyz - tr.v0.xyz;
    vec3 r = o + d * t - tr.v0.xyz;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float det = d11 * d22 - d12 * d12;
    vec2 uv = det > 0.0 ? vec2(d22 * dot(r, e1) - d12 * dot(r, e2), d11 * dot(r, e2) - d12 * dot(r, e1)) / det : vec2(0.0);
    uv = max(uv, vec2(0.0));
    float s = uv.x + uv.y;
    if (s > 1.0) uv /= s;
    best = RayHit(t, uv.x, uv.y, tri);
    return true;
}
#endif

RayHit intersect_octree(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.node_count == 0u) return best;
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    vec3 inv_d = safe_inverse(d);
    vec3 root_lo = accel.bounds_min.xyz;
    vec3 root_hi = accel.bounds_max.xyz;
    vec3 ta = (root_lo - o) * inv_d;
    vec3 tb = (root_hi - o) * inv_d;
    vec3 t_lo = min(ta, tb);
    vec3 t_hi = max(ta, tb);
    float t = max(max(t_lo.x, t_lo.y), max(t_lo.z, q.origin.w));
    float t_end = min(min(t_hi.x, t_hi.y), min(t_hi.z, best.t)) * 1.0000004;
    if (!(t <= t_end)) return best;
    bvec3 up = greaterThanEqual(d, vec3(0.0));
    vec3 p = clamp(o + d * t, root_lo, root_hi);
    for (uint step = 0u; step < OCT_STEPS; ++step) {
        // Top-down containment test: the leaf holding p; on a mid plane, the side the ray
        // heads to.
        uint node = 0u;
        vec3 lo = root_lo;
        vec3 hi = root_hi;
        uvec4 w = accel_nodes[0];
        for (uint level = 0u; level <= OCT_MAX_DEPTH && w.w == OCT_INTERIOR; ++level) {
            vec3 mid = lo + (hi - lo) * 0.5;
            bvec3 upper = bvec3(p.x > mid.x || (p.x == mid.x && up.x), p.y > mid.y || (p.y == mid.y && up.y),
                                p.z > mid.z || (p.z == mid.z && up.z));
            lo = mix(lo, mid, upper);
            hi = mix(mid, hi, upper);
            node = w.x + uint(upper.x) + 2u * uint(upper.y) + 4u * uint(upper.z);
            w = accel_nodes[node];
        }
        vec3 t_far = (mix(lo, hi, up) - o) * inv_d;
        uint axis = t_far.x <= t_far.y ? (t_far.x <= t_far.z ? 0u : 2u) : (t_far.y <= t_far.z ? 1u : 2u);
        float t_exit = t_far[axis];
#ifdef OCTREE_VOLUME
        oct_volume(w, q, t, t_exit, best);
        if ((q.flags & RAY_ANY_HIT) != 0u && best.triangle != RAY_NO_TRIANGLE) return best;
#else
        if (test_leaf(w.x, w.y, q, best)) return best;
#endif
        if (best.t <= t_exit * 1.0000004) return best;
        if (t_exit >= t_end) return best;
        t = max(t, t_exit);
        p = o + d * t_exit;
        p[axis] = up[axis] ? hi[axis] : lo[axis];  // on the face it leaves through
        if (p[axis] == (up[axis] ? root_hi[axis] : root_lo[axis])) return best;  // out of the root
    }
    return best;
}

#define INTERSECT intersect_octree
#include "raytrace/intersect_main.glsl"
