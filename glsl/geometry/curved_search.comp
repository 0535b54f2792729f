#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.virtual, the search (survey §5, EMD*05, Figure 29): for one environment vertex V
// and one reflector, the geometry-image sample P whose normal N encloses the smallest angle
// with the bisector of the directions from P to the eye and to V (the reflection law),
// searched coarse to fine: every 2^levels-th texel exhaustively, then 5×5 windows at half
// the stride down to single texels, then a sub-texel pattern search on the bilinearly
// interpolated image. V's virtual position lies on the eye ray through P, |V − P| beyond
// it: it projects onto P's pixel, and its depth orders the virtual objects by path length.
layout(local_size_x = 64) in;
#include "geometry/curved.glsl"

uint layer;
vec3 eye;
vec3 vertex;
int size;

// cos of the angle between n and the bisector of the directions from p to the eye and to
// the vertex (1: the reflection law holds).
float law(vec3 p, vec3 n) {
    vec3 h = normalize(eye - p) + normalize(vertex - p);
    float l = length(h);
    return l > 1e-6 ? dot(n, h) / l : -2.0;
}

// The law at texel t; -3 where the parameterisation leaves the texel empty.
float at_texel(ivec2 t, out vec3 p, out vec3 n) {
    vec4 q = texelFetch(geometry_positions, ivec3(t, int(layer)), 0);
    p = q.xyz;
    n = texelFetch(geometry_normals, ivec3(t, int(layer)), 0).xyz;
    return q.w > 0.5 ? law(p, n) : -3.0;
}

// The law at continuous texel coordinates c (texel centres at integers + 0.5), bilinear
// between the four nearest texels; -3 unless all four are covered.
float at_point(vec2 c, out vec3 p, out vec3 n) {
    vec2 f = c - 0.5;
    ivec2 i = ivec2(floor(f));
    if (any(lessThan(i, ivec2(0))) || any(greaterThan(i, ivec2(size - 2)))) return -3.0;
    vec2 t = f - vec2(i);
    vec4 p00 = texelFetch(geometry_positions, ivec3(i, int(layer)), 0);
    vec4 p10 = texelFetch(geometry_positions, ivec3(i + ivec2(1, 0), int(layer)), 0);
    vec4 p01 = texelFetch(geometry_positions, ivec3(i + ivec2(0, 1), int(layer)), 0);
    vec4 p11 = texelFetch(geometry_positions, ivec3(i + ivec2(1, 1), int(layer)), 0);
    if (min(min(p00.w, p10.w), min(p01.w, p11.w)) < 0.5) return -3.0;
    vec3 n00 = texelFetch(geometry_normals, ivec3(i, int(layer)), 0).xyz;
    vec3 n10 = texelFetch(geometry_normals, ivec3(i + ivec2(1, 0), int(layer)), 0).xyz;
    vec3 n01 = texelFetch(geometry_normals, ivec3(i + ivec2(0, 1), int(layer)), 0).xyz;
    vec3 n11 = texelFetch(geometry_normals, ivec3(i + ivec2(1, 1), int(layer)), 0).xyz;
    p = mix(mix(p00.xyz, p10.xyz, t.x), mix(p01.xyz, p11.xyz, t.x), t.y);
    vec3 m = mix(mix(n00, n10, t.x), mix(n01, n11, t.x), t.y);
    if (dot(m, m) <= 0.0) return -3.0;
    n = normalize(m);
    return law(p, n);
}

// Coarse to fine: the best of the coarsest level's samples (every 2^levels-th texel) that
// lie more than `apart` texels from `away`, refined by 5×5 windows at half the stride down
// to single texels. Returns its score; bt, bp, bn its texel, position and normal.
float descend(int levels, ivec2 away, int apart, out ivec2 bt, out vec3 bp, out vec3 bn) {
    int stride = 1 << levels;
    float best = -4.0;
    bt = ivec2(size / 2);
    bp = vec3(0.0);
    bn = vec3(0.0);
    vec3 p, n;
    for (int y = stride / 2; y < size; y += stride) {
        for (int x = stride / 2; x < size; x += stride) {
            ivec2 t = ivec2(x, y);
            ivec2 d = abs(t - away);
            if (max(d.x, d.y) <= apart) continue;
            float s = at_texel(t, p, n);
            if (s > best) { best = s; bt = t; bp = p; bn = n; }
        }
    }
    while (stride > 1) {
        stride /= 2;
        ivec2 c = bt;
        for (int dy = -2; dy <= 2; ++dy) {
            for (int dx = -2; dx <= 2; ++dx) {
                ivec2 t = c + ivec2(dx, dy) * stride;
                if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(size)))) continue;
                float s = at_texel(t, p, n);
                if (s > best) { best = s; bt = t; bp = p; bn = n; }
            }
        }
    }
    return best;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= curved.vertex_count) return;
    layer = push.object;
    eye = views[push.view].eye.xyz;
    vertex = curved_vertices[i].position.xyz;
    size = int(curved.image_size);
    // The coarsest level keeps at least 2×2 samples.
    int levels = min(int(curved.search_levels), max(findMSB(size) - 1, 0));
    ivec2 bt;
    vec3 bp, bn, p, n;
    float best = descend(levels, ivec2(-2 * size), 0, bt, bp, bn);
    // Several minima (survey §5: a reflector neither convex nor concave): every
    // CURVED_CHECK_STRIDE-th vertex is searched again, its coarsest level leaving out the
    // samples within two of its stride of the reflection point found; a second point that
    // meets the law as well with another normal (not the same valley reached again, nor the
    // same surface point under another texel, as at a pole or a seam) is counted.
    if (i % CURVED_CHECK_STRIDE == 0u && best >= CURVED_MIN_COS) {
        ivec2 ot;
        vec3 op, on;
        float other = descend(levels, bt, 2 << levels, ot, op, on);
        // As near the law as the first (within twice its angle and 2°): a point held at the
        // chart's border (a seam) by the window search is not a minimum.
        float near = 2.0 * acos(clamp(best, -1.0, 1.0)) + 0.035;
        bool law_holds = acos(clamp(other, -1.0, 1.0)) <= near;
        if (law_holds && dot(on, bn) < CURVED_MIN_COS && dot(on, eye - op) > 0.0 && dot(on, vertex - op) > 0.0)
            atomicAdd(curved_minima[layer], 1u);
    }
    // Sub-texel: a pattern search over the interpolated image, the step halved from half a
    // texel to 1/64.
    vec2 c = vec2(bt) + 0.5;
    float step = 0.5;
    for (int k = 0; k < 6; ++k, step *= 0.5) {
        for (int moves = 0; moves < 2; ++moves) {
            vec2 from = c;
            const vec2 dirs[4] = vec2[4](vec2(1, 0), vec2(-1, 0), vec2(0, 1), vec2(0, -1));
            for (int d = 0; d < 4; ++d) {
                vec2 q = from + dirs[d] * step;
                float s = at_point(q, p, n);
                if (s > best) { best = s; c = q; bp = p; bn = n; }
            }
            if (c == from) break;
        }
    }
    bool valid = best >= CURVED_MIN_COS && dot(bn, eye - bp) > 0.0 && dot(bn, vertex - bp) > 0.0;
    vec3 virt = valid ? bp + normalize(bp - eye) * length(vertex - bp) : vertex;
    virtual_vertices[layer * curved.vertex_count + i] = vec4(virt, valid ? 1.0 : 0.0);
}
