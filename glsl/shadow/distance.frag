#version 460
#extension GL_GOOGLE_include_directive : require
// shadow.generate: a distance map from a light (radial distance for cube maps of point
// and spot lights, distance along the light's direction for directional lights).
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out float out_distance;

void main() {
    View v = views[in_view];
    out_distance = v.eye.w == 0.0 ? length(in_position - v.eye.xyz) : dot(in_position - v.eye.xyz, v.dir.xyz);
}
