// Dielectrics whose index varies in space (survey §6.5: curved rays in varying media): the
// field n(x) = ior + g·(x − o) + ½ (x − o)ᵀ H (x − o) of src/scene/medium.rs and its ray
// equation, integrated by classical RK4 in the optical parameter τ (dx/dτ = v, dv/dτ = n ∇n,
// |v| = n imposed after each step), each step as long as turns the ray by at most `turn`
// radians, the chords between steps intersected with the scene. In f32; the CPU reference's
// twin is GradedIndex::march.
#ifndef COMMON_MEDIUM_GLSL
#define COMMON_MEDIUM_GLSL
#include "common/scene.glsl"

// The least index the field evaluates to (scene/medium.rs MIN_INDEX), and how far a ray
// may turn before it is given up (MAX_TURN: ⌈MEDIUM_MAX_TURN / turn⌉ chords).
const float MEDIUM_MIN_INDEX = 1e-3;
const float MEDIUM_MAX_TURN = 51.2;
#define MEDIUM_INF uintBitsToFloat(0x7f800000u)

bool material_graded(Material m) {
    return m.medium_origin.w != 0.0;
}

// n(p) (clamped at MEDIUM_MIN_INDEX) and ∇n(p).
float medium_index(Material m, vec3 p, out vec3 grad) {
    vec3 d = p - m.medium_origin.xyz;
    vec4 a = m.medium_hessian;   // xx, yy, zz, xy
    vec4 b = m.medium_hessian2;  // xz, yz
    vec3 hd = vec3(a.x * d.x + a.w * d.y + b.x * d.z, a.w * d.x + a.y * d.y + b.y * d.z, b.x * d.x + b.y * d.y + a.z * d.z);
    grad = m.medium_gradient.xyz + hd;
    return max(m.nu.y + dot(m.medium_gradient.xyz, d) + 0.5 * dot(d, hd), MEDIUM_MIN_INDEX);
}

// The index at p: the material's, or its field's value there.
float material_ior_at(Material m, vec3 p) {
    vec3 g;
    return material_graded(m) ? medium_index(m, p, g) : m.nu.y;
}

// The graded medium (its material + 1; 0: none) a ray leaving a surface of material
// `material` (m; n the mesh's outward normal) along `dir` runs in, coming from medium `from`:
// inside a graded material's object, that material; off any other surface a reflected ray
// stays in its medium, a refracted one leaves it (the reference's Tracer::child_medium).
uint medium_after(uint material, Material m, vec3 n, vec3 dir, bool reflected, uint from) {
    if (material_graded(m)) return dot(dir, n) < 0.0 ? material + 1u : 0u;
    return reflected ? from : 0u;
}

vec3 medium_acceleration(Material m, vec3 p) {
    vec3 g;
    float n = medium_index(m, p, g);
    return n * g;
}

// Arc length of a step at a point of index n and gradient g: where the ray turns by at most
// `turn` (by the gradient, and by how far the Hessian lets the gradient grow); infinite in a
// uniform field.
float medium_step_length(Material m, float n, vec3 g, float turn) {
    float gl = length(g);
    float by_gradient = gl > 0.0 ? turn * n / gl : MEDIUM_INF;
    float by_hessian = m.medium_gradient.w > 0.0 ? sqrt(2.0 * turn * n / m.medium_gradient.w) : MEDIUM_INF;
    return min(by_gradient, by_hessian);
}

// One RK4 step of dτ on (x, v); |v| = n(x) afterwards.
void medium_rk4(Material m, inout vec3 x, inout vec3 v, float dt) {
    vec3 k1x = v, k1v = medium_acceleration(m, x);
    vec3 k2x = v + 0.5 * dt * k1v, k2v = medium_acceleration(m, x + 0.5 * dt * k1x);
    vec3 k3x = v + 0.5 * dt * k2v, k3v = medium_acceleration(m, x + 0.5 * dt * k2x);
    vec3 k4x = v + dt * k3v, k4v = medium_acceleration(m, x + dt * k3x);
    vec3 x1 = x + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    vec3 v1 = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    vec3 g;
    float n1 = medium_index(m, x1, g);
    v = (dot(v1, v1) > 0.0 ? normalize(v1) : normalize(v)) * n1;
    x = x1;
}

#endif
