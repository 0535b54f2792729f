#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.splat: the filter texture of a photon's splat, an Epanechnikov kernel
// K(u) = 2/π (1 − |u|²) on the unit disk (∫K = 1: each photon's power is conserved),
// blended additively into the light cube map (texture space: the light map, its alpha the
// signed sum of the channels, caustics/splat.vert).
#include "common/scene.glsl"

layout(location = 0) in vec2 in_offset;
layout(location = 1) flat in vec4 in_scale;
layout(location = 0) out vec4 out_intensity;

void main() {
    float u2 = dot(in_offset, in_offset);
    if (u2 >= 1.0) discard;
    out_intensity = in_scale * (0.636619772 * (1.0 - u2));
}
