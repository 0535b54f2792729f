#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// proxy-relief.shade: displacement-mapped proxies (survey §3.2, PMDS06; src/methods/envmap/
// relief.rs). The scene's box is six rectangles displaced by height maps: layer 6·o + f of
// `relief_maps` holds what stands in front of face f between the object o's side away from
// it and face f, seen orthographically along f's direction c (rgb radiance, alpha its depth
// from the view's eye, just inside the opposite face). A ray
// p + t·dir that moves towards face f (dir·c > 0) and starts in front of that height map is
// marched through it (relief_steps linear steps up to where it leaves the box, then eight
// halvings): the first step whose depth reaches the map's is the hit. A height map takes
// everything behind its surface for solid, so a ray that crosses into the space hidden
// behind a step of it (a cliff: the four texels around the hit more than RELIEF_CLIFF texel
// widths apart, or the ray far behind the map's depth there) has met either the side of
// something or free space the map cannot see: the march goes on past it, the nearest hit
// off a cliff, in any face's map, wins; the nearest cliff only where no map holds one. A
// ray no map holds sees the environment.
#include "common/specular.glsl"
#include "envmap/proxy.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

const float RELIEF_CLIFF = 4.0;

float relief_depth(vec2 uv, float layer) {
    return textureLod(relief_maps, vec3(uv, layer), 0.0).a;
}

// The march through layer `layer` up to t_end: the hit's t (negative: none), radiance, and
// whether it lies on a cliff. Past a cliff the ray is in the space the map hides behind a
// step (a ball in front of the wall stretched into a column to it), which the march takes
// for free space: it goes on until the ray is in front of the map again and takes the next
// hit that is not a cliff (the wall behind the ball); the first cliff only where there is
// none. A ray that truly meets the side of something is held nearer by the map of a face
// that sees that side.
float relief_march(uint layer, vec3 p, vec3 dir, float t_end, out vec3 L, out bool cliff) {
    View v = views[push_relief_view_base() + layer];
    vec3 c = v.dir.xyz;
    float along = dot(dir, c);
    if (along <= 0.0) return -1.0;
    float l = float(layer);
    vec4 c0 = v.view_proj * vec4(p, 1.0);
    vec4 c1 = v.view_proj * vec4(p + dir * t_end, 1.0);
    vec2 uv0 = c0.xy * 0.5 + 0.5, uv1 = c1.xy * 0.5 + 0.5;
    float d0 = dot(p - v.eye.xyz, c), d1 = d0 + along * t_end;
    // Behind this map's surface (hidden from where the map starts): not this map's ray.
    if (d0 >= relief_depth(uv0, l)) return -1.0;
    int n = int(max(push_relief_steps(), 1u));
    // A texel's width in world units: the view's x row is a / (half width).
    float half_width = 1.0 / length(vec3(v.view_proj[0][0], v.view_proj[1][0], v.view_proj[2][0]));
    float texel = 2.0 * half_width / float(textureSize(relief_maps, 0).x);
    float prev = 0.0, cliff_t = -1.0;
    vec3 cliff_L = vec3(0.0);
    bool hidden = false;
    for (int i = 1; i <= n; i++) {
        float s = float(i) / float(n);
        bool behind = mix(d0, d1, s) >= relief_depth(mix(uv0, uv1, s), l);
        if (!behind || hidden) {
            hidden = hidden && behind;
            prev = s;
            continue;
        }
        float lo = prev, hi = s;
        for (int k = 0; k < 8; k++) {
            float m = 0.5 * (lo + hi);
            if (mix(d0, d1, m) >= relief_depth(mix(uv0, uv1, m), l)) hi = m; else lo = m;
        }
        vec2 uv = mix(uv0, uv1, hi);
        vec3 radiance = textureLod(relief_maps, vec3(uv, l), 0.0).rgb;
        vec4 around = textureGather(relief_maps, vec3(uv, l), 3);
        float spread = max(max(around.x, around.y), max(around.z, around.w)) - min(min(around.x, around.y), min(around.z, around.w));
        // Where the ray stepped into the hidden space at a silhouette (not onto a surface),
        // it is far behind the map's depth there even after the halvings.
        float past = mix(d0, d1, hi) - relief_depth(uv, l);
        if (spread <= RELIEF_CLIFF * texel && past <= RELIEF_CLIFF * texel) {
            L = radiance;
            cliff = false;
            return hi * t_end;
        }
        if (cliff_t < 0.0) {
            cliff_t = hi * t_end;
            cliff_L = radiance;
        }
        hidden = true;
        prev = s;
    }
    L = cliff_L;
    cliff = cliff_t >= 0.0;
    return cliff_t;
}

vec3 relief_radiance(Object o, vec3 p, vec3 dir) {
    vec3 exit;
    if (!proxy_box_exit(o, p, dir, exit)) return sky_radiance(dir);
    float t_end = length(exit - p);
    uint base = 6u * uint(max(o.envmap_layer, 0));
    float held_t = 1.0 / 0.0, cliff_t = 1.0 / 0.0;
    vec3 held_L = vec3(0.0), cliff_L = vec3(0.0);
    for (uint f = 0u; f < 6u; f++) {
        vec3 L;
        bool cliff;
        float t = relief_march(base + f, p, dir, t_end, L, cliff);
        if (t < 0.0) continue;
        if (!cliff && t < held_t) {
            held_t = t;
            held_L = L;
        } else if (cliff && t < cliff_t) {
            cliff_t = t;
            cliff_L = L;
        }
    }
    if (!isinf(held_t)) return held_L;
    return isinf(cliff_t) ? sky_radiance(dir) : cliff_L;
}

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    vec3 c = s.fr * relief_radiance(o, in_position, s.r);
    vec3 refracted;
    REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, normalize(in_normal), dir) * relief_radiance(o, in_position, dir));
    c += refracted;
    out_color = vec4(c, 1.0);
}
