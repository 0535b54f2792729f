#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.receivers for caustic_space=texture (SKALP05): the receiver distance map as
// shadow/distance.frag writes it, and beside it the receiver triangle in each direction —
// its index in the scene's list + 1 (the mesh's first, from caustic_atlas, + gl_PrimitiveID:
// the stage's device has the geometryShader feature), as a float, exact below 2²⁴ — from
// which the splats (caustics/splat.vert#TEXTURE) take a sampled photon's light-map coordinates.
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out float out_distance;
layout(location = 1) out float out_triangle;

void main() {
    View v = views[in_view];
    out_distance = v.eye.w == 0.0 ? length(in_position - v.eye.xyz) : dot(in_position - v.eye.xyz, v.dir.xyz);
    uint first = floatBitsToUint(caustic_atlas[4u * push.object + 3u].x);
    out_triangle = float(first + uint(gl_PrimitiveID) + 1u);
}
