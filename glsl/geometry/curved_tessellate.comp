#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.virtual.tessellate: the environment's tessellation (survey Table 1: geometry
// transformation needs "high tessellation", since only vertices move): every scene
// triangle (a, b, c) becomes a barycentric grid of (t + 1)(t + 2)/2 vertices
// a + (b − a)·i/t + (c − a)·j/t (i + j ≤ t, row by row), read from the scene's vertex
// buffer, so that a moved object is re-tessellated on the GPU. Its t² triangles' indices
// are fixed (written once by the CPU).
layout(local_size_x = 64) in;
#include "geometry/curved.glsl"

vec3 vertex_attribute(uint v, uint at) {
    uint o = 8u * v + at;
    return vec3(scene_vertices[o], scene_vertices[o + 1u], scene_vertices[o + 2u]);
}

vec2 uv_of(uint v) {
    return vec2(scene_vertices[8u * v + 6u], scene_vertices[8u * v + 7u]);
}

void main() {
    uint g = gl_GlobalInvocationID.x;
    if (g >= curved.vertex_count) return;
    uint t = curved.tessellation;
    uint per = (t + 1u) * (t + 2u) / 2u;
    uvec4 tri = source_triangles[g / per];
    uint l = g % per;
    uint i = 0u;
    while (l >= t + 1u - i) {
        l -= t + 1u - i;
        ++i;
    }
    float s = float(i) / float(t), r = float(l) / float(t);
    float w = 1.0 - s - r;
    vec3 p = vertex_attribute(tri.x, 0u) * w + vertex_attribute(tri.y, 0u) * s + vertex_attribute(tri.z, 0u) * r;
    vec3 n = vertex_attribute(tri.x, 3u) * w + vertex_attribute(tri.y, 3u) * s + vertex_attribute(tri.z, 3u) * r;
    vec2 uv = uv_of(tri.x) * w + uv_of(tri.y) * s + uv_of(tri.z) * r;
    CurvedVertex v;
    v.position = vec4(p, 1.0);
    v.normal = vec4(dot(n, n) > 0.0 ? normalize(n) : vec3(0.0), 0.0);
    v.uv = vec4(uv, 0.0, 0.0);
    curved_vertices[g] = v;
}
