#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.virtual, the draw (survey §5, EMDT06): one environment object at its virtual
// position for one reflector, seen from the camera; shading takes its real position.
#include "geometry/curved.glsl"

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_view;
layout(location = 4) out float out_valid;
layout(location = 5) out vec3 out_virtual;

void main() {
    CurvedVertex v = curved_vertices[gl_VertexIndex];
    vec4 w = virtual_vertices[curved_reflector() * curved.vertex_count + gl_VertexIndex];
    out_position = v.position.xyz;
    out_normal = v.normal.xyz;
    out_uv = v.uv.xy;
    out_view = push.view;
    out_valid = w.w;
    out_virtual = w.xyz;
    gl_Position = views[push.view].view_proj * vec4(w.xyz, 1.0);
}
