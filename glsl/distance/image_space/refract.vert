#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// Wyman's second pass: the mesh with each vertex's precomputed distance through the object
// along its inverted normal (d_N): `thickness`, set 1 binding 3 (src/frame/layout.in.rs).
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_view;
layout(location = 4) out float out_thickness;

void main() {
    uint v = push.view + gl_ViewIndex;
    out_position = in_position;
    out_normal = in_normal;
    out_uv = in_uv;
    out_view = v;
    out_thickness = thickness[gl_VertexIndex];
    gl_Position = views[v].view_proj * vec4(in_position, 1.0);
}
