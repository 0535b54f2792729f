#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// A full-screen triangle; the fragment shader unprojects it to a world direction.
#include "common/scene.glsl"

layout(location = 0) out vec2 out_ndc;
layout(location = 1) flat out uint out_view;

void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    out_ndc = p;
    out_view = push.view + gl_ViewIndex;
    gl_Position = vec4(p, 0.0, 1.0);
}
