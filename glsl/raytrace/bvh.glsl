// BVH traversal (survey §2.3.5) over the nodes of src/methods/raytrace/bvh.rs: node k is
// accel_nodes[2k] = (min bits, first), accel_nodes[2k + 1] = (max bits, count); count 0:
// interior with children first and first + 1; accel_aux[k]: the miss link.
#ifndef RAYTRACE_BVH_GLSL
#define RAYTRACE_BVH_GLSL
#include "raytrace/rays.glsl"

const uint BVH_STACK = 96u;  // src/methods/raytrace/bvh.rs STACK
const uint BVH_END = 0xffffffffu;

bool bvh_box(uint k, vec3 o, vec3 inv_d, float t_min, float t_max, out float t_near) {
    uvec4 a = accel_nodes[2u * k];
    uvec4 b = accel_nodes[2u * k + 1u];
    return ray_box(uintBitsToFloat(a.xyz), uintBitsToFloat(b.xyz), o, inv_d, t_min, t_max, t_near);
}

// Tests leaf k's triangles; true when an any-hit query may stop.
bool bvh_leaf(uint k, RayQuery q, inout RayHit best) {
    uint first = accel_nodes[2u * k].w;
    uint count = accel_nodes[2u * k + 1u].w;
    bool any_hit = (q.flags & RAY_ANY_HIT) != 0u;
    for (uint i = first; i < first + count; ++i) {
        if (test_triangle(accel_refs[i], q, best) && any_hit) return true;
    }
    return false;
}

// Traversal state, private to each invocation (globals, so that the step functions below
// share them without copying the stack).
uint bvh_stack_node[BVH_STACK];
float bvh_stack_t[BVH_STACK];
uint bvh_sp;
uint bvh_k;
vec3 bvh_o;
vec3 bvh_inv_d;

// One node of the nearest-child-first traversal; false when the traversal is done (or an
// any-hit query may stop). Popped nodes whose entry lies beyond the nearest hit are skipped.
bool bvh_step(RayQuery q, inout RayHit best) {
    uint k = bvh_k;
    uint first = accel_nodes[2u * k].w;
    uint count = accel_nodes[2u * k + 1u].w;
    float t_min = q.origin.w;
    if (count > 0u) {
        if (bvh_leaf(k, q, best)) return false;
    } else {
        float tl, tr;
        bool hl = bvh_box(first, bvh_o, bvh_inv_d, t_min, best.t, tl);
        bool hr = bvh_box(first + 1u, bvh_o, bvh_inv_d, t_min, best.t, tr);
        if (hl && hr) {
            bool left_first = tl <= tr;
            bvh_stack_node[bvh_sp] = left_first ? first + 1u : first;
            bvh_stack_t[bvh_sp] = left_first ? tr : tl;
            bvh_sp++;
            bvh_k = left_first ? first : first + 1u;
            return true;
        }
        if (hl || hr) {
            bvh_k = hl ? first : first + 1u;
            return true;
        }
    }
    while (bvh_sp > 0u) {  // at most BVH_STACK iterations
        bvh_sp--;
        if (bvh_stack_t[bvh_sp] <= best.t * 1.0000004) {
            bvh_k = bvh_stack_node[bvh_sp];
            return true;
        }
    }
    return false;
}

// Nearest child first with a short stack.
RayHit intersect_bvh(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.node_count == 0u) return best;
    bvh_o = q.origin.xyz;
    bvh_inv_d = safe_inverse(q.direction.xyz);
    bvh_sp = 0u;
    bvh_k = 0u;
    float t_root;
    if (!bvh_box(0u, bvh_o, bvh_inv_d, q.origin.w, best.t, t_root)) return best;
    while (bvh_step(q, best)) {
    }
    return best;
}

// One node of the stackless traversal (CHCH06): children in stored order, the miss link
// when a box is missed or a leaf is done; no per-ray memory but no nearest-first order.
bool bvh_stackless_step(RayQuery q, inout RayHit best) {
    uint k = bvh_k;
    float t_near;
    if (!bvh_box(k, bvh_o, bvh_inv_d, q.origin.w, best.t, t_near)) {
        bvh_k = accel_aux[k];
    } else if (accel_nodes[2u * k + 1u].w > 0u) {
        if (bvh_leaf(k, q, best)) return false;
        bvh_k = accel_aux[k];
    } else {
        bvh_k = accel_nodes[2u * k].w;
    }
    return bvh_k != BVH_END;
}

// Every node is visited at most once, so the walk ends after node_count steps.
RayHit intersect_bvh_stackless(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.node_count == 0u) return best;
    bvh_o = q.origin.xyz;
    bvh_inv_d = safe_inverse(q.direction.xyz);
    bvh_k = 0u;
    while (bvh_stackless_step(q, best)) {
    }
    return best;
}

#endif
