#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// Bounding interval hierarchy traversal (survey §2.3.4, SKSS06: one pass with a stack) over
// the nodes of src/methods/raytrace/bih.rs: node k is accel_nodes[k] = (left maximum bits,
// right minimum bits, left child, axis 0/1/2) when interior, the right child the left + 1;
// (first reference, count, 0, BIH_LEAF) when a leaf; node 0 is the root, whose box is
// accel.bounds_min/max.
//
// A node's interval [t0, t1] of the ray gives each child the part of it on the child's
// side of the child's plane: the near child (the left when the ray heads up the axis) the
// interval up to its plane's crossing, the far child the interval from its plane's
// crossing on. Both non-empty: the far one waits on the stack. The children may overlap,
// so a hit in the near child ends the traversal only once nothing that waits starts
// before it (entries are popped while they start before the best hit).
#include "raytrace/rays.glsl"

const uint BIH_LEAF = 3u;        // src/methods/raytrace/bih.rs LEAF
const uint BIH_MAX_DEPTH = 48u;  // MAX_DEPTH
const uint BIH_STEPS = 32768u;

uint bih_stack_node[BIH_MAX_DEPTH];
float bih_stack_t0[BIH_MAX_DEPTH];
float bih_stack_t1[BIH_MAX_DEPTH];


RayHit intersect_bih(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.node_count == 0u) return best;
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    vec3 inv_d = safe_inverse(d);
    float t0;
    if (!ray_box(accel.bounds_min.xyz, accel.bounds_max.xyz, o, inv_d, q.origin.w, best.t, t0)) return best;
    vec3 ta = (accel.bounds_min.xyz - o) * inv_d;
    vec3 tb = (accel.bounds_max.xyz - o) * inv_d;
    vec3 t_hi = max(ta, tb);
    float t1 = min(min(t_hi.x, t_hi.y), min(t_hi.z, best.t)) * 1.0000004;
    uint node = 0u;
    uint depth = 0u;
    for (uint step = 0u; step < BIH_STEPS; ++step) {
        uvec4 w = accel_nodes[node];
        bool pop = false;
        if (w.w != BIH_LEAF) {
            uint a = w.w;
            // Each plane's crossing; rounding widens both children's intervals.
            float tl = (uintBitsToFloat(w.x) - o[a]) * inv_d[a];
            float tr = (uintBitsToFloat(w.y) - o[a]) * inv_d[a];
            bool ascending = d[a] >= 0.0;
            // The near child's interval ends at its plane, the far child's starts at its.
            float near_end = ascending ? tl : tr;
            float far_start = ascending ? tr : tl;
            near_end += abs(near_end) * 4e-7;
            far_start -= abs(far_start) * 4e-7;
            uint near = ascending ? w.z : w.z + 1u;
            uint far = ascending ? w.z + 1u : w.z;
            float n1 = min(t1, near_end);
            float f0 = max(t0, far_start);
            bool near_hit = t0 <= n1;
            bool far_hit = f0 <= t1 && f0 < best.t;
            if (near_hit && far_hit && depth < BIH_MAX_DEPTH) {
                bih_stack_node[depth] = far;
                bih_stack_t0[depth] = f0;
                bih_stack_t1[depth] = t1;
                depth++;
                node = near;
                t1 = n1;
            } else if (near_hit) {
                node = near;
                t1 = n1;
            } else if (far_hit) {
                node = far;
                t0 = f0;
            } else {
                pop = true;
            }
        } else {
            if (test_leaf(w.x, w.y, q, best)) return best;
            pop = true;
        }
        if (pop) {
            // The newest entry that starts before the best hit.
            for (;;) {
                if (depth == 0u) return best;
                depth--;
                if (bih_stack_t0[depth] < best.t) break;
            }
            node = bih_stack_node[depth];
            t0 = bih_stack_t0[depth];
            t1 = min(bih_stack_t1[depth], best.t * 1.0000004);
        }
    }
    return best;
}

#define INTERSECT intersect_bih
#include "raytrace/intersect_main.glsl"
