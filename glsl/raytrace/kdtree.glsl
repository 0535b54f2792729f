// kd-tree traversal (survey §2.3.3) over the nodes of src/methods/raytrace/kdtree.rs: node
// k is accel_nodes[k] = (split bits, left child, right child, axis 0/1/2) when interior,
// (first reference, count, 0, KD_LEAF) when a leaf; node 0 is the root, whose box is
// accel.bounds_min/max.
//
// Front to back: a node's interval [t0, t1] of the ray is cut at the split plane's t into
// the near child's [t0, ts] and the far child's [ts, t1]. A leaf's triangles are tested
// with the current nearest hit as the ray's bound; once that hit lies before the leaf's
// exit t1 (widened by ray_box's 1 + 2γ₃ for rounding), it is the nearest: every triangle
// an earlier point of the ray meets is listed in a leaf already visited (the builder lists
// a triangle wherever it passes within a slack of a leaf, which covers the f32 rounding of
// the plane crossings). A hit beyond t1 is kept as the bound and confirmed later.
//
// KD_SHORT_STACK > 0 (HSHH07): the far children wait on a stack of that many entries, a
// ring whose oldest entry is overwritten when it is full; when it runs dry before the
// ray's exit, traversal restarts from the push-down node (the deepest node known to hold
// all of the ray that is left) at the last leaf's exit. KD_SHORT_STACK = 0: pure
// kd-restart (FS05), from the root at each leaf's exit, no per-ray memory.
#ifndef RAYTRACE_KDTREE_GLSL
#define RAYTRACE_KDTREE_GLSL
#include "raytrace/rays.glsl"

#ifndef KD_SHORT_STACK
#define KD_SHORT_STACK 0
#endif

const uint KD_LEAF = 3u;         // src/methods/raytrace/kdtree.rs LEAF
const uint KD_MAX_DEPTH = 64u;   // src/methods/raytrace/kdtree.rs MAX_DEPTH
// A bound on the steps (nodes visited) of one ray, guarding against a loop that rounding
// kept from advancing: half of lavapipe's loop budget (raytrace/rays.glsl), room for 512
// descents of the deepest tree (KD_MAX_DEPTH nodes each).
const uint KD_STEPS = 32768u;

// Tests leaf w's triangles (rays.glsl test_leaf).
bool kd_leaf(uvec4 w, RayQuery q, inout RayHit best) {
    return test_leaf(w.x, w.y, q, best);
}

#if KD_SHORT_STACK > 0
uint kd_stack_node[KD_SHORT_STACK];
float kd_stack_t0[KD_SHORT_STACK];
float kd_stack_t1[KD_SHORT_STACK];
#endif

RayHit intersect_kdtree(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.node_count == 0u) return best;
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    vec3 inv_d = safe_inverse(d);
    // The ray's interval in the root's box (ray_box's slabs, both ends kept).
    vec3 ta = (accel.bounds_min.xyz - o) * inv_d;
    vec3 tb = (accel.bounds_max.xyz - o) * inv_d;
    vec3 t_lo = min(ta, tb);
    vec3 t_hi = max(ta, tb);
    float t0 = max(max(t_lo.x, t_lo.y), max(t_lo.z, q.origin.w));
    float t_end = min(min(t_hi.x, t_hi.y), min(t_hi.z, best.t)) * 1.0000004;
    if (!(t0 <= t_end)) return best;
    float t1 = t_end;
    uint node = 0u;
#if KD_SHORT_STACK > 0
    uint top = 0u;   // the newest entry is kd_stack_*[top]
    uint depth = 0u; // entries held, at most KD_SHORT_STACK
    uint root = 0u;  // the push-down node
    bool push_down = true;
#endif
    for (uint step = 0u; step < KD_STEPS; ++step) {
        uvec4 w = accel_nodes[node];
        if (w.w != KD_LEAF) {
            uint a = w.w;
            float s = uintBitsToFloat(w.x);
            float ts = (s - o[a]) * inv_d[a];
            // The near child is the origin's side; on the plane, the side the ray heads to.
            bool below_first = o[a] < s || (o[a] == s && d[a] <= 0.0);
            uint near = below_first ? w.y : w.z;
            uint far = below_first ? w.z : w.y;
            if (ts > t1 || ts <= 0.0) {
                node = near;  // the plane is beyond the interval, or behind the origin
            } else if (ts <= t0) {
                node = far;  // ≤, not <: a restart at ts must move on to the far side
            } else {
#if KD_SHORT_STACK > 0
                top = (top + 1u) % uint(KD_SHORT_STACK);
                kd_stack_node[top] = far;
                kd_stack_t0[top] = ts;
                kd_stack_t1[top] = t1;
                depth = min(depth + 1u, uint(KD_SHORT_STACK));
                push_down = false;
#endif
                node = near;
                t1 = ts;
            }
#if KD_SHORT_STACK > 0
            if (push_down) root = node;
#endif
            continue;
        }
        if (kd_leaf(w, q, best)) return best;
        if (best.t <= t1 * 1.0000004) return best;
#if KD_SHORT_STACK > 0
        if (depth > 0u) {
            // The newest far child is the nearest: if it starts beyond the hit, all do.
            node = kd_stack_node[top];
            t0 = kd_stack_t0[top];
            t1 = kd_stack_t1[top];
            top = (top + uint(KD_SHORT_STACK) - 1u) % uint(KD_SHORT_STACK);
            depth--;
            if (t0 >= best.t) return best;
            continue;
        }
#endif
        // Nothing waits (or what waited was overwritten): restart at this leaf's exit.
        if (t1 >= t_end || t1 >= best.t) return best;
        t0 = t1;
        t1 = t_end;
#if KD_SHORT_STACK > 0
        node = root;
        push_down = true;
#else
        node = 0u;
#endif
    }
    return best;
}

#endif
