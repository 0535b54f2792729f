#version 460
#extension GL_GOOGLE_include_directive : require
// frame.object_ids (issue 15): the first-hit object of each pixel, its mesh index + 1.
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out uint out_id;

void main() {
    out_id = push.object + 1u;
}
