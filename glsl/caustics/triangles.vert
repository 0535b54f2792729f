#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// caustics.triangles (survey §6.3.2): the caustic triangles of photon layer push.object
// that caustics/setup.comp made, drawn into the face of view push.view (push.flags: the
// face) when it flagged them for it: the triangle itself, or a small triangle's tent over
// the 2×2 texels around its centroid.
#include "common/scene.glsl"

layout(location = 0) flat out vec3 out_intensity;
// Small triangles: the centroid in framebuffer texels, and 1 (a tent around it).
layout(location = 1) flat out vec2 out_centre;
layout(location = 2) flat out float out_tent;

void main() {
    uint index = push.object * caustic.layer_triangles + uint(gl_VertexIndex) / 3u;
    uint corner = uint(gl_VertexIndex) % 3u;
    if (caustic_faces[push.flags * caustic.triangle_count + index] == 0u) {
        out_intensity = vec3(0.0);
        out_centre = vec2(0.0);
        out_tent = 0.0;
        gl_Position = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    vec4 a = caustic_triangles[4u * index + 0u];
    vec4 b = caustic_triangles[4u * index + 1u];
    vec4 c = caustic_triangles[4u * index + 2u];
    bool tent = caustic_triangles[4u * index + 3u].x != 0.0;
    View v = views[push.view + gl_ViewIndex];
    out_intensity = vec3(a.w, b.w, c.w);
    out_centre = vec2(0.0);
    out_tent = 0.0;
    vec3 h = corner == 0u ? a.xyz : corner == 1u ? b.xyz : c.xyz;
    if (!tent) {
        gl_Position = v.view_proj * vec4(v.eye.xyz + h, 1.0);
        return;
    }
    vec3 mid = (a.xyz + b.xyz + c.xyz) / 3.0;
    float size = float(caustic.cube_size);
    vec4 p = v.view_proj * vec4(v.eye.xyz + mid, 1.0);
    vec2 ndc = p.xy / p.w;
    if (p.w <= 0.0 || any(greaterThan(abs(ndc), vec2(1.0 + 2.0 / size)))) {
        gl_Position = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    // A triangle of legs 4.2 texels holds the 2×2 texels' square around the centroid.
    const vec2 AROUND[3] = vec2[](vec2(-1.0, -1.0), vec2(3.2, -1.0), vec2(-1.0, 3.2));
    out_centre = (ndc * 0.5 + 0.5) * size;
    out_tent = 1.0;
    gl_Position = vec4(ndc + AROUND[corner] * (2.0 / size), p.z / p.w, 1.0);
}
