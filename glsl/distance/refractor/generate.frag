#version 460
#extension GL_GOOGLE_include_directive : require
// refractor.generate: a refractor map (survey §4.4, Figure 23): the refractor's own surface
// seen from its reference point, storing the surface normal and the distance.
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_normal_distance;

void main() {
    out_normal_distance = vec4(normalize(in_normal), length(in_position - views[in_view].eye.xyz));
}
