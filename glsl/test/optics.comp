#version 460
#extension GL_GOOGLE_include_directive : require
// Conformance harness (tests/optics_conformance.rs): evaluates one function of
// common/optics.glsl or common/ray_triangle.glsl per case, so the test can compare each
// result with the f64 twin in src/optics.rs.
#include "common/ray_triangle.glsl"

layout(local_size_x = 64) in;

const uint OP_REFLECT = 0u;          // a.xyz = i, b.xyz = n                 -> r0.xyz
const uint OP_REFRACT = 1u;          // a.xyz = i, b.xyz = n, c.x = eta      -> r0.xyz = t, r1.x = refracted (1/0)
const uint OP_F0 = 2u;               // a.xyz = ν, b.xyz = κ                 -> r0.xyz
const uint OP_SCHLICK = 3u;          // a.xyz = F0, c.x = cos θ              -> r0.xyz
const uint OP_DIELECTRIC = 4u;       // c.x = cos θ, c.y = eta               -> r0.x
const uint OP_CONDUCTOR = 5u;        // c.x = cos θ, a.xyz = ν, b.xyz = κ    -> r0.xyz
const uint OP_RAY_TRIANGLE = 6u;     // a.xyz = o, a.w = t_min, b.xyz = d, b.w = t_max, c/d/e.xyz = v0/v1/v2
                                     //   -> r0 = (t, u, v, hit 1/0)

struct Case {
    uvec4 op;  // x: which function
    vec4 a;
    vec4 b;
    vec4 c;
    vec4 d;
    vec4 e;
};

struct Result {
    vec4 r0;
    vec4 r1;
};

layout(std430, set = 0, binding = 0) readonly buffer Cases { Case cases[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Results { Result results[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= push.count) return;
    Case c = cases[k];
    Result r;
    r.r0 = vec4(0.0);
    r.r1 = vec4(0.0);
    switch (c.op.x) {
    case OP_REFLECT:
        r.r0.xyz = reflect_dir(c.a.xyz, c.b.xyz);
        break;
    case OP_REFRACT: {
        vec3 t;
        bool ok = refract_dir(c.a.xyz, c.b.xyz, c.c.x, t);
        r.r0.xyz = t;
        r.r1.x = ok ? 1.0 : 0.0;
        break;
    }
    case OP_F0:
        r.r0.xyz = fresnel_f0(c.a.xyz, c.b.xyz);
        break;
    case OP_SCHLICK:
        r.r0.xyz = fresnel_schlick(c.a.xyz, c.c.x);
        break;
    case OP_DIELECTRIC:
        r.r0.x = fresnel_dielectric(c.c.x, c.c.y);
        break;
    case OP_CONDUCTOR:
        r.r0.xyz = fresnel_conductor(c.c.x, c.a.xyz, c.b.xyz);
        break;
    case OP_RAY_TRIANGLE: {
        vec3 tuv;
        bool hit = ray_triangle(c.a.xyz, c.b.xyz, c.c.xyz, c.d.xyz, c.e.xyz, c.a.w, c.b.w, tuv);
        r.r0 = vec4(tuv, hit ? 1.0 : 0.0);
        break;
    }
    default:
        r.r0 = vec4(-1.0);
        break;
    }
    results[k] = r;
}
