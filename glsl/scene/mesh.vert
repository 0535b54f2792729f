#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// World-space scene vertices into the view `push.view + gl_ViewIndex` (cube faces use
// multiview or one draw per face; both index the same view table).
#include "common/scene.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_view;

void main() {
    uint v = push.view + gl_ViewIndex;
    out_position = in_position;
    out_normal = in_normal;
    out_uv = in_uv;
    out_view = v;
    gl_Position = views[v].view_proj * vec4(in_position, 1.0);
}
