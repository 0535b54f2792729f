#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// image-based.shade: image-based reflections (survey §3.3, src/methods/envmap/captures.rs).
// The reflected and refracted rays of a fragment at p take the captures at the corners of
// p's cell in the object's lattice of captures (trilinear weights over the nominal lattice),
// and each capture answers the ray from its own centre:
// - warped by its distances (push_capture_warp() 0): the ray is searched in the capture's
//   distance map (§4.1, the search knobs); a hit the capture holds (its distance within
//   CAPTURE_HELD of what the texel stores, the texels around it one surface) is a surface
//   point on the ray, so the nearest such hit over the captures is where the ray ends: the
//   captures that hold it blend their radiance, those that see past it (the occluder hidden
//   from them) or hold no hit are left out; with no hit held, all of them blend;
// - blended (1): each capture looked up towards where the ray leaves the scene's box (the
//   parallax correction of proxy-box, §3.2), the lookups blended by the weights.
#include "common/specular.glsl"
#include "envmap/proxy.glsl"

float capture_layer = 0.0;
#define SEARCH_DISTANCE(dir) textureLod(captures, vec4(dir, capture_layer), 0.0).a
#include "common/search.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

// A search hit is a surface the capture holds when its distance from the capture's centre is
// within CAPTURE_HELD of the stored one and the four texels around it lie within CAPTURE_GAP
// of each other (else the ray passed a silhouette, where the filtered distance bridges a gap).
const float CAPTURE_HELD = 0.01;
const float CAPTURE_GAP = 0.1;
// Held hits within this fraction of the nearest are the same surface.
const float CAPTURE_SAME = 0.05;

// Capture `layer`'s first view: its centre in eye.xyz, its nominal lattice point in dir.xyz.
View capture_view(uint layer) {
    return views[push_capture_view_base() + 6u * layer];
}

struct CaptureHit {
    float t;     // ray parameter of the hit; +inf: the environment at infinity
    vec3 L;      // the radiance the capture stores there
    bool held;   // a surface the capture holds (or the sky, where it sees the sky)
};

CaptureHit capture_search(uint layer, vec3 p, vec3 dir) {
    capture_layer = float(layer);
    vec3 x = p - capture_view(layer).eye.xyz;
    SearchResult s = push_search_linear_steps() == 0u
        ? parallax_search(x, dir, int(max(push_search_parallax_iterations(), 1u)))
        : linear_search(x, dir, int(push_search_linear_steps()), int(push_search_binary_steps()), int(push_search_secant_steps()), push_search_tolerance());
    vec4 texel = textureLod(captures, vec4(s.dir, capture_layer), 0.0);
    CaptureHit h;
    h.L = texel.rgb;
    if (s.escaped) {
        h.t = 1.0 / 0.0;
        h.held = search_is_sky(texel.a);
        return h;
    }
    vec4 around = textureGather(captures, vec4(s.dir, capture_layer), 3);
    float nearest = min(min(around.x, around.y), min(around.z, around.w));
    float farthest = max(max(around.x, around.y), max(around.z, around.w));
    h.t = s.d;
    h.held = abs(length(x + dir * s.d) - texel.a) <= CAPTURE_HELD * texel.a && farthest - nearest <= CAPTURE_GAP * nearest;
    return h;
}

vec3 capture_radiance(Object o, vec3 p, vec3 dir) {
    uint n = max(push_captures_per_axis(), 1u);
    uint base = uint(max(o.envmap_layer, 0)) * n * n * n;
    vec3 lo = capture_view(base).dir.xyz;
    vec3 hi = capture_view(base + n * n * n - 1u).dir.xyz;
    vec3 f = vec3(0.0);
    if (n > 1u) {
        vec3 extent = hi - lo;
        f = clamp(mix(vec3(0.0), (p - lo) / extent, greaterThan(extent, vec3(0.0))), 0.0, 1.0) * float(n - 1u);
    }
    uvec3 i0 = n > 1u ? min(uvec3(floor(f)), uvec3(n - 2u)) : uvec3(0u);
    vec3 fr = n > 1u ? f - vec3(i0) : vec3(0.0);
    bool blend = push_capture_warp() != 0u;
    vec3 exit;
    bool inside = proxy_box_exit(o, p, dir, exit);
    CaptureHit hits[8];
    float weights[8];
    uint count = 0u;
    vec3 sum = vec3(0.0);
    float total = 0.0;
    float nearest = 1.0 / 0.0;
    for (uint k = 0u; k < 8u; k++) {
        uvec3 off = uvec3(k & 1u, (k >> 1) & 1u, (k >> 2) & 1u);
        vec3 w3 = mix(1.0 - fr, fr, vec3(off));
        float w = w3.x * w3.y * w3.z;
        uvec3 i = i0 + off;
        if (w <= 1e-4 || any(greaterThanEqual(i, uvec3(n)))) continue;
        uint layer = base + i.x + n * (i.y + n * i.z);
        if (blend) {
            vec3 toward = inside ? exit - capture_view(layer).eye.xyz : dir;
            sum += w * textureLod(captures, vec4(toward, float(layer)), 0.0).rgb;
            total += w;
            continue;
        }
        CaptureHit h = capture_search(layer, p, dir);
        hits[count] = h;
        weights[count] = w;
        count++;
        if (h.held) nearest = min(nearest, h.t);
    }
    if (blend) return sum / max(total, 1e-30);
    for (uint k = 0u; k < count; k++) {
        bool same = isinf(nearest) ? isinf(hits[k].t) : hits[k].t <= nearest * (1.0 + CAPTURE_SAME);
        if (hits[k].held && same) {
            sum += weights[k] * hits[k].L;
            total += weights[k];
        }
    }
    if (total > 0.0) return sum / total;
    // No capture holds a hit: all of them, by weight.
    for (uint k = 0u; k < count; k++) {
        sum += weights[k] * hits[k].L;
        total += weights[k];
    }
    return sum / max(total, 1e-30);
}

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    vec3 c = s.fr * capture_radiance(o, in_position, s.r);
    vec3 refracted;
    REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, normalize(in_normal), dir) * capture_radiance(o, in_position, dir));
    c += refracted;
    out_color = vec4(c, 1.0);
}
