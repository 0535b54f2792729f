#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// Uniform grid with 3D-DDA traversal (survey §2.3.1, Amanatides–Woo) and optional
// empty-space skipping by Chebyshev distance (KL04). Cell c is accel_nodes[c] = (first
// reference, count, empty distance, 0); see src/methods/raytrace/grid.rs.
#include "raytrace/rays.glsl"

// The next cell boundary along each axis from cell c, and the step between boundaries.
void dda_setup(ivec3 c, vec3 o, vec3 d, vec3 inv_d, vec3 lo, vec3 cell, out vec3 t_next) {
    for (int a = 0; a < 3; ++a) {
        if (d[a] > 0.0) t_next[a] = (lo[a] + float(c[a] + 1) * cell[a] - o[a]) * inv_d[a];
        else if (d[a] < 0.0) t_next[a] = (lo[a] + float(c[a]) * cell[a] - o[a]) * inv_d[a];
        else t_next[a] = 1.0 / 0.0;
    }
}

ivec3 cell_at(vec3 p, vec3 lo, vec3 inv_cell, ivec3 res) {
    return clamp(ivec3(floor((p - lo) * inv_cell)), ivec3(0), res - 1);
}

RayHit intersect_grid(RayQuery q) {
    RayHit best = no_hit(q);
    if (accel.triangle_count == 0u) return best;
    vec3 o = q.origin.xyz;
    vec3 d = q.direction.xyz;
    vec3 inv_d = safe_inverse(d);
    ivec3 res = ivec3(accel.grid_res.xyz);
    bool skip_empty = accel.grid_res.w != 0u;
    vec3 lo = accel.grid_min.xyz;
    vec3 inv_cell = accel.grid_inv_cell.xyz;
    vec3 cell = 1.0 / inv_cell;
    vec3 hi = lo + vec3(res) * cell;
    float t;
    if (!ray_box(lo, hi, o, inv_d, q.origin.w, best.t, t)) return best;
    bool any_hit = (q.flags & RAY_ANY_HIT) != 0u;
    ivec3 c = cell_at(o + d * t, lo, inv_cell, res);
    ivec3 step_dir = ivec3(sign(d));
    vec3 t_delta = abs(cell * inv_d);
    vec3 t_next;
    dda_setup(c, o, d, inv_d, lo, cell, t_next);
    // Every step leaves a cell, so res.x + res.y + res.z steps cross the grid; skips only
    // shorten the walk. The bound guards against a non-advancing loop on rounding.
    int budget = 2 * (res.x + res.y + res.z) + 8;
    for (int it = 0; it < budget; ++it) {
        uvec4 w = accel_nodes[c.x + res.x * (c.y + res.y * c.z)];
        float t_exit = min(min(t_next.x, t_next.y), t_next.z);
        if (w.y > 0u) {
            // Four references per iteration: lavapipe's loop budget (raytrace/rays.glsl)
            // then covers 262140 tests per ray, for cells crowded by a dense object.
#define GRID_TEST(j) \
    if (i + j < end && test_triangle(accel_refs[i + j], q, best) && any_hit) return best;
            uint end = w.x + w.y;
            for (uint i = w.x; i < end; i += 4u) {
                GRID_TEST(0u) GRID_TEST(1u) GRID_TEST(2u) GRID_TEST(3u)
            }
            // A hit before this cell's exit is the nearest: every triangle that an earlier
            // point of the ray meets is listed in a cell already visited.
            if (best.triangle != RAY_NO_TRIANGLE && best.t <= t_exit * 1.0000004) return best;
        } else if (skip_empty && w.z > 1u) {
            // The block of cells within w.z − 1 of c is empty: leave it in one jump.
            int r = int(w.z) - 1;
            ivec3 blo = max(c - r, ivec3(0));
            ivec3 bhi = min(c + r, res - 1);
            float t_jump = 1.0 / 0.0;
            for (int a = 0; a < 3; ++a) {
                if (d[a] > 0.0) t_jump = min(t_jump, (lo[a] + float(bhi[a] + 1) * cell[a] - o[a]) * inv_d[a]);
                else if (d[a] < 0.0) t_jump = min(t_jump, (lo[a] + float(blo[a]) * cell[a] - o[a]) * inv_d[a]);
            }
            if (t_jump >= best.t) return best;
            ivec3 nc = cell_at(o + d * t_jump, lo, inv_cell, res);
            // Continue from the cell the jump lands in, if it moved forward past c.
            ivec3 moved = (nc - c) * step_dir;
            if (t_jump > t_exit && all(greaterThanEqual(moved, ivec3(0))) && any(greaterThan(moved, ivec3(0)))) {
                // Outside the grid after the jump?
                vec3 p = o + d * t_jump;
                if (any(lessThan(p, lo - cell * 0.5)) || any(greaterThan(p, hi + cell * 0.5))) return best;
                c = nc;
                dda_setup(c, o, d, inv_d, lo, cell, t_next);
                continue;
            }
        }
        if (t_exit > best.t) return best;
        // Step into the neighbour across the nearest boundary.
        int a = (t_next.x <= t_next.y && t_next.x <= t_next.z) ? 0 : (t_next.y <= t_next.z ? 1 : 2);
        c[a] += step_dir[a];
        if (c[a] < 0 || c[a] >= res[a]) return best;
        t_next[a] += t_delta[a];
    }
    return best;
}

#define INTERSECT intersect_grid
#include "raytrace/intersect_main.glsl"
