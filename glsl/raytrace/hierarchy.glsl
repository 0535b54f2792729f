// The ray hierarchy (survey §2.2.1, Sze06/RAH07): the ray texture in tiles of
// tile_size² rays, each bounded by a cone that contains every ray of the tile; a triangle's
// bounding sphere is tested against a tile's cone before the tile is rasterised for it.
#ifndef RAYTRACE_HIERARCHY_GLSL
#define RAYTRACE_HIERARCHY_GLSL
#include "raytrace/engine.glsl"

// tile_cones[2k] = (apex, cos θ), tile_cones[2k + 1] = (axis, sin θ); cos θ = 2: no useful
// cone (rays too spread: test every triangle), 3: no rays in the tile.
const float CONE_ALL = 2.0;
const float CONE_EMPTY = 3.0;

// Whether the sphere (s, rho) may meet a ray of tile k's cone (conservative).
bool cone_meets_sphere(uint k, vec3 s, float rho) {
    vec4 a = tile_cones[2u * k];
    vec4 b = tile_cones[2u * k + 1u];
    if (a.w == CONE_EMPTY) return false;
    if (a.w == CONE_ALL) return true;
    vec3 v = s - a.xyz;
    float len = length(v);
    if (len <= rho) return true;
    // The angle between v and the axis is at most θ + asin(ρ / |v|).
    float sin_b = rho / len;
    float cos_b = sqrt(max(1.0 - sin_b * sin_b, 0.0));
    float cos_limit = a.w * cos_b - b.w * sin_b;  // cos(θ + β)
    if (b.w * cos_b + a.w * sin_b < 0.0) return true;  // θ + β > π: everything
    return dot(v, b.xyz) >= len * cos_limit - 1e-6 * len;
}

// The bounding sphere of what the intersection test accepts of triangle t: the centre of
// its box, the farthest corner, and a margin for the test's widening (RAY_EDGE_EPS of the
// barycentric extent moves a corner out by up to 3 ε times the longest edge ≤ 6 ε r) and
// for f32 rounding of the centre (a few ulps of its largest coordinate). Without the margin
// a ray through a corner of the widened triangle lay outside the sphere and its tile was
// culled (seen with the tight end-point cones of shadow-ray tiles, 1 run in 12).
void triangle_sphere(Triangle t, out vec3 c, out float r) {
    vec3 lo = min(min(t.v0.xyz, t.v1.xyz), t.v2.xyz);
    vec3 hi = max(max(t.v0.xyz, t.v1.xyz), t.v2.xyz);
    c = 0.5 * (lo + hi);
    float corner = max(max(length(t.v0.xyz - c), length(t.v1.xyz - c)), length(t.v2.xyz - c));
    vec3 m = max(abs(lo), abs(hi));
    r = corner * (1.0 + 8.0 * RAY_EDGE_EPS + 1e-6) + 4.8e-7 * max(max(m.x, m.y), m.z);
}

#endif
