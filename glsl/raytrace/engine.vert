#version 460
#extension GL_GOOGLE_include_directive : require
// The ray engine: one quad over the rows of the ray texture that hold rays, per triangle
// (instance). The triangle's id goes flat to the fragment shader.
#include "raytrace/engine.glsl"

layout(location = 0) flat out uint triangle_id;

void main() {
    triangle_id = uint(gl_InstanceIndex);
    vec2 p = quad_corner(uint(gl_VertexIndex) % 6u, vec2(0.0), vec2(trace.ray_texture_width, engine_rows()));
    gl_Position = engine_clip(p);
}
