#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.triangles, set-up (survey §6.3.2): each caustic triangle of photon layer
// push.object, made once. Every 2×2 block of neighbouring photons makes two triangles on
// the receivers; a triangle carries a sixth of each corner's power (each photon belongs to
// six triangles of the grid) and its radiant intensity is that flux over its solid angle
// seen from the cube's centre (flux conservation). Triangles with a missing corner, or whose
// corners lie at distances from the centre more than CAUSTIC_GAP apart (different
// surfaces), are dropped. A triangle under four texels would be drawn into the texels whose
// centres it covers, one, two or none: at the photon spacing of a texel that aliases into
// holes, so it goes into the 2×2 texels around its centroid instead, with bilinear (tent)
// weights that sum to 1 wherever the centroid lies. Each triangle is flagged for the faces
// of its cube whose frustum it may reach (faces from view push.view): the faces then shade
// only their own, in triangle order (no atomics: the image is the same bits every frame).
layout(local_size_x = 64) in;
#include "common/scene.glsl"

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
    uint t = gl_GlobalInvocationID.x;
    if (t >= caustic.layer_triangles) return;
    int n = int(caustic.photon_size);
    int block = int(t) / 2;
    int first = 3 * (int(t) % 2);
    ivec2 base = ivec2(block % (n - 1), block / (n - 1));
    int layer = int(push.object);
    vec3 h[3];
    vec3 flux = vec3(0.0);
    bool ok = true;
    float lo = 1e38, hi = 0.0;
    for (int j = 0; j < 3; ++j) {
        ivec3 tc = ivec3(base + CORNERS[first + j], layer);
        vec4 hit = texelFetch(photon_hits, tc, 0);
        ok = ok && hit.w > 0.0;
        h[j] = hit.xyz;
        float len = length(hit.xyz);
        lo = min(lo, len);
        hi = max(hi, len);
        flux += texelFetch(photon_power, tc, 0).rgb;
    }
    float omega = solid_angle(h[0], h[1], h[2]);
    uint index = uint(layer) * caustic.layer_triangles + t;
    if (!(ok && hi <= lo * (1.0 + CAUSTIC_GAP) && omega > 0.0)) {
        for (uint f = 0u; f < 6u; ++f) caustic_faces[f * caustic.triangle_count + index] = 0u;
        return;
    }
    vec3 mid = (h[0] + h[1] + h[2]) / 3.0;
    float size = float(caustic.cube_size);
    vec3 ad = abs(mid);
    float major = max(ad.x, max(ad.y, ad.z));
    float texel_omega = (4.0 / (size * size)) * pow(major / length(mid), 3.0);
    bool tent = omega < 4.0 * texel_omega;
    vec3 j = flux / (6.0 * (tent ? texel_omega : omega));
    caustic_triangles[4u * index + 0u] = vec4(h[0], j.r);
    caustic_triangles[4u * index + 1u] = vec4(h[1], j.g);
    caustic_triangles[4u * index + 2u] = vec4(h[2], j.b);
    caustic_triangles[4u * index + 3u] = vec4(tent ? 1.0 : 0.0, 0.0, 0.0, 0.0);
    // The faces it may reach: not wholly behind a face's eye, nor wholly beyond one of its
    // four sides (a tent: its centroid within a texel of the face).
    for (uint f = 0u; f < 6u; ++f) {
        mat4 vp = views[push.view + f].view_proj;
        bool reach;
        if (tent) {
            vec4 c = vp * vec4(views[push.view + f].eye.xyz + mid, 1.0);
            reach = c.w > 0.0 && all(lessThanEqual(abs(c.xy), vec2(c.w * (1.0 + 2.0 / size))));
        } else {
            vec4 c0 = vp * vec4(views[push.view + f].eye.xyz + h[0], 1.0);
            vec4 c1 = vp * vec4(views[push.view + f].eye.xyz + h[1], 1.0);
            vec4 c2 = vp * vec4(views[push.view + f].eye.xyz + h[2], 1.0);
            vec3 w = vec3(c0.w, c1.w, c2.w);
            vec3 x = vec3(c0.x, c1.x, c2.x), y = vec3(c0.y, c1.y, c2.y);
            reach = any(greaterThan(w, vec3(0.0))) && !all(greaterThan(x, w)) && !all(lessThan(x, -w)) && !all(greaterThan(y, w))
                && !all(lessThan(y, -w));
        }
        caustic_faces[f * caustic.triangle_count + index] = reach ? 1u : 0u;
    }
}
