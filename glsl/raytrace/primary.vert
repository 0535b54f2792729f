#version 460
#extension GL_GOOGLE_include_directive : require
// Primary hits by rasterisation (survey §2): every triangle of the list drawn from the
// camera, its id carried flat to the fragment. Vertex pulling from the triangle list, so
// the id is the vertex index / 3 and no index buffer is needed. With MSAA the pass runs
// once per sample (push.object = s), the image shifted so that pixel centres fall on
// sample s's position.
#include "raytrace/rays.glsl"

layout(location = 0) flat out uint triangle_id;

void main() {
    uint id = uint(gl_VertexIndex) / 3u;
    Triangle tr = triangles[id];
    uint corner = uint(gl_VertexIndex) % 3u;
    vec3 p = corner == 0u ? tr.v0.xyz : (corner == 1u ? tr.v1.xyz : tr.v2.xyz);
    triangle_id = id;
    vec4 clip = views[push.view].view_proj * vec4(p, 1.0);
    if (trace.samples > 1u) {
        vec2 offset = sample_position(push.object, trace.samples) - 0.5;
        clip.xy -= offset * 2.0 / vec2(trace.width, trace.height) * clip.w;
    }
    gl_Position = clip;
}
