#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// caustics.triangles: caustic triangles (survey §6.3.2). Every 2×2 block of neighbouring
// photons of the hit location image (layer push.object) makes two triangles on the
// receivers; a triangle carries a sixth of each corner's power (each photon belongs to six
// triangles of the grid) and its radiant intensity is that flux over the triangle's solid
// angle seen from the cube's centre (flux conservation). Triangles with a missing
// corner, or whose corners lie at distances from the centre more than CAUSTIC_GAP
// apart (different surfaces), are dropped. Drawn into each face of the light cube map.
#include "common/scene.glsl"

layout(location = 0) flat out vec3 out_intensity;
// Small triangles: the centroid in framebuffer texels, and 1 (a tent around it).
layout(location = 1) flat out vec2 out_centre;
layout(location = 2) flat out float out_tent;

// Corners of the two triangles of a block, as (dx, dy).
const ivec2 CORNERS[6] = ivec2[](ivec2(0, 0), ivec2(1, 0), ivec2(0, 1), ivec2(1, 0), ivec2(1, 1), ivec2(0, 1));

// Solid angle of the triangle (a, b, c) seen from the origin (Van Oosterom–Strackee); the
// triple product from the edges, which keeps its precision for tiny triangles.
float solid_angle(vec3 a, vec3 b, vec3 c) {
    float la = length(a), lb = length(b), lc = length(c);
    float num = abs(dot(a, cross(b - a, c - a)));
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0 * atan(num, den);
}

void main() {
    int n = int(caustic.photon_size);
    int tri = gl_VertexIndex / 3;
    int k = gl_VertexIndex % 3;
    int block = tri / 2;
    int first = 3 * (tri % 2);
    ivec2 base = ivec2(block % (n - 1), block / (n - 1));
    vec3 h[3];
    vec3 flux = vec3(0.0);
    bool ok = true;
    float lo = 1e38, hi = 0.0;
    for (int j = 0; j < 3; ++j) {
        ivec3 tc = ivec3(base + CORNERS[first + j], int(push.object));
        vec4 hit = texelFetch(photon_hits, tc, 0);
        ok = ok && hit.w != 0.0;
        h[j] = hit.xyz;
        float len = length(hit.xyz);
        lo = min(lo, len);
        hi = max(hi, len);
        flux += texelFetch(photon_power, tc, 0).rgb;
    }
    float omega = solid_angle(h[0], h[1], h[2]);
    ok = ok && hi <= lo * (1.0 + CAUSTIC_GAP) && omega > 0.0;
    View v = views[push.view + gl_ViewIndex];
    out_centre = vec2(0.0);
    out_tent = 0.0;
    if (!ok) {
        out_intensity = vec3(0.0);
        gl_Position = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    out_intensity = flux / (6.0 * omega);
    gl_Position = v.view_proj * vec4(v.eye.xyz + h[k], 1.0);
    // A triangle under a few texels would be drawn into the texels whose centres it covers,
    // one, two or none: at the photon spacing of a light cube texel that aliases into a
    // pattern of holes. Such a triangle goes into the 2×2 texels around its centroid
    // instead, with bilinear (tent) weights that sum to 1 wherever the centroid lies: its
    // flux is kept, and smoothly. The face that holds the centroid draws it, and a face
    // whose edge is within a texel of it draws its share.
    vec3 mid = (h[0] + h[1] + h[2]) / 3.0;
    float size = float(caustic.cube_size);
    vec3 ad = abs(mid);
    float major = max(ad.x, max(ad.y, ad.z));
    float texel_omega = (4.0 / (size * size)) * pow(major / length(mid), 3.0);
    out_tent = 0.0;
    if (omega < 4.0 * texel_omega) {
        vec4 c = v.view_proj * vec4(v.eye.xyz + mid, 1.0);
        vec2 ndc = c.xy / c.w;
        if (c.w <= 0.0 || any(greaterThan(abs(ndc), vec2(1.0 + 2.0 / size)))) {
            gl_Position = vec4(0.0, 0.0, 0.0, -1.0);
            return;
        }
        // A triangle of legs 4.2 texels holds the 2×2 texels' square around the centroid.
        const vec2 AROUND[3] = vec2[](vec2(-1.0, -1.0), vec2(3.2, -1.0), vec2(-1.0, 3.2));
        out_centre = (ndc * 0.5 + 0.5) * size;
        out_tent = 1.0;
        out_intensity = flux / (6.0 * texel_omega);
        gl_Position = vec4(ndc + AROUND[k] * (2.0 / size), c.z / c.w, 1.0);
    }
}
