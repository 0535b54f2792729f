// Möller–Trumbore ray–triangle intersection (survey §2.1.1, [MT97]). Twin of
// `ray_triangle` in src/optics.rs: same threshold, same inclusive edges, a miss on any NaN
// or infinite input (t_max = +∞ means "no limit"), on zero-area triangles and on rays
// parallel to the triangle's plane.
#ifndef RAY_TRIANGLE_GLSL
#define RAY_TRIANGLE_GLSL
#include "common/optics.glsl"

// |det| ≤ RAY_TRIANGLE_PARALLEL |d| |e1| |e2| is rounding noise: the ray is parallel.
const float RAY_TRIANGLE_PARALLEL = 1e-6;

// Solves o + t d = (1 − u − v) v0 + u v1 + v v2 by Cramer's rule. On a hit (t_min < t <
// t_max, u ≥ −eps, v ≥ −eps, u + v ≤ 1 + eps) returns true and tuv = (t, u, v). `eps` widens
// the triangle by that much of its barycentric extent: eps > 0 closes the cracks that f32
// rounding opens along shared edges (ray tracing in the original geometry uses 2⁻²⁰).
bool ray_triangle_eps(vec3 o, vec3 d, vec3 v0, vec3 v1, vec3 v2, float t_min, float t_max, float eps, out vec3 tuv) {
    tuv = vec3(0.0);
    vec3 e1 = v1 - v0;
    vec3 e2 = v2 - v0;
    float det_min = RAY_TRIANGLE_PARALLEL * length(d) * length(e1) * length(e2);
    if (!is_finite(o) || !is_finite(v0) || !is_finite(det_min) || !is_finite(t_min) || is_nan(t_max)) return false;
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    if (!is_finite(det) || abs(det) <= det_min) return false;  // parallel, or zero area
    float inv = 1.0 / det;
    vec3 s = o - v0;
    float u = dot(s, p) * inv;
    if (is_nan(u) || u < -eps || u > 1.0 + eps) return false;
    vec3 q = cross(s, e1);
    float v = dot(d, q) * inv;
    if (is_nan(v) || v < -eps || u + v > 1.0 + eps) return false;
    float t = dot(e2, q) * inv;
    if (!is_finite(t) || t <= t_min || t >= t_max) return false;
    tuv = vec3(t, u, v);
    return true;
}

// The twin of src/optics.rs `ray_triangle`: inclusive edges, no widening.
bool ray_triangle(vec3 o, vec3 d, vec3 v0, vec3 v1, vec3 v2, float t_min, float t_max, out vec3 tuv) {
    return ray_triangle_eps(o, d, v0, v1, v2, t_min, t_max, 0.0, tuv);
}

#endif
