#version 460
#extension GL_GOOGLE_include_directive : require
// image_space.backfaces: first pass of Wyman's image-space double refraction (survey §4.4):
// normals and distances from the eye of the refractors' back faces, seen from the camera.
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_normal_distance;

void main() {
    out_normal_distance = vec4(normalize(in_normal), length(in_position - views[in_view].eye.xyz));
}
