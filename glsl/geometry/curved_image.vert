#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.image: a reflector's geometry image (survey §5, GGH02/EMD*05). Its triangles
// (`reflector_vertices`) are rasterised over their
// parameterisation (u, v) ∈ [0,1]², each texel taking the world position and normal of the
// surface point mapped to it.
#include "geometry/curved.glsl"

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;

void main() {
    CurvedVertex v = reflector_vertices[gl_VertexIndex];
    out_position = v.position.xyz;
    out_normal = v.normal.xyz;
    gl_Position = vec4(v.uv.xy * 2.0 - 1.0, 0.5, 1.0);
}
