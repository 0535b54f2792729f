#version 460
#extension GL_GOOGLE_include_directive : require
// The ray hierarchy's draw: per triangle (instance) one quad per tile of the ray texture,
// kept only where the triangle's bounding sphere meets the tile's cone; culled tiles
// collapse to a point outside the view (no fragments). The fragments are the ray engine's.
#include "raytrace/hierarchy.glsl"

layout(location = 0) flat out uint triangle_id;

void main() {
    triangle_id = uint(gl_InstanceIndex);
    uint tile = uint(gl_VertexIndex) / 6u;
    uint ts = trace.tile_size;
    vec2 lo = vec2(tile % trace.tiles_per_row, tile / trace.tiles_per_row) * float(ts);
    vec3 c;
    float r;
    triangle_sphere(triangles[triangle_id], c, r);
    if (lo.y >= float(engine_rows()) || !cone_meets_sphere(tile, c, r)) {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
        return;
    }
    vec2 hi = min(lo + float(ts), vec2(trace.ray_texture_width, engine_rows()));
    gl_Position = engine_clip(quad_corner(uint(gl_VertexIndex) % 6u, lo, hi));
}
