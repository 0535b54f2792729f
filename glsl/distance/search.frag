#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE HYBRID HYBRID_PER_SAMPLE
#ifdef HYBRID_PER_SAMPLE
#define HYBRID
#define PER_SAMPLE
#endif
#ifdef HYBRID
#extension GL_EXT_ray_query : require
#define SPECULA_RAY_QUERY
#endif
// distance.search: single reflections and refractions using the sampled geometry (§4.2):
// the reflected and refracted rays are traced in the object's distance map and the hit
// texel's radiance is weighted by Fresnel. HYBRID (hybrid=rays, src/methods/distance/
// hybrid.rs): a ray the search cannot answer is traced through Vulkan ray queries instead.
#include "common/specular.glsl"
#include "common/traced.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

#ifdef HYBRID
#include "raytrace/ray_query.glsl"

// The counters' atomics would move the depth test after the shader: hidden fragments (the
// ball's back faces) would trace and count too.
layout(early_fragment_tests) in;

// A search hit is the map's when its distance from the reference point is within
// HYBRID_TOLERANCE of what the map holds in its direction, and the four texels around that
// direction hold one surface (their distances within HYBRID_GAP of each other, as the caustic
// triangles' CAUSTIC_GAP): else the ray passed a silhouette, where the map's filtered
// distance bridges the gap to a point it does not see.
const float HYBRID_TOLERANCE = 0.002;
const float HYBRID_GAP = 0.1;

// The nearest triangle along o + t d, t ≥ t_min, of any object but `mesh` (the distance map
// leaves the object out; its rays' fallback does too).
RayHit rq_trace_outside(vec3 o, vec3 d, float t_min, uint mesh) {
    RayHit best = RayHit(RQ_T_MAX, 0.0, 0.0, RAY_NO_TRIANGLE);
    if (!is_finite(o) || !is_finite(d) || dot(d, d) == 0.0) return best;
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsNoOpaqueEXT, 0xffu, o, t_min, d, RQ_T_MAX);
    while (rayQueryProceedEXT(rq)) {
        if (rayQueryGetIntersectionTypeEXT(rq, false) != gl_RayQueryCandidateIntersectionTriangleEXT) continue;
        if (floatBitsToUint(rq_shading[RQ_TRIANGLE(rq, false)].uv2.z) != mesh) rayQueryConfirmIntersectionEXT(rq);
    }
    if (rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        vec2 uv = rayQueryGetIntersectionBarycentricsEXT(rq, true);
        best = RayHit(rayQueryGetIntersectionTEXT(rq, true), uv.x, uv.y, RQ_TRIANGLE(rq, true));
    }
    return best;
}

// Radiance arriving at p from dir: the distance-map search's, or where it cannot answer, the
// ray query's hit shaded (a diffuse surface lit as the camera's; a specular one by what the
// map holds in its direction). Counts per object the rays asked and traced.
vec3 hybrid_radiance(Object o, vec3 p, vec3 dir) {
    search_map = 0;
    search_layer = float(o.envmap_layer);
    vec3 x = p - o.reference_point.xyz;
    SearchResult s = search_ray(x, dir);
    vec4 texel = textureLod(distance_maps, vec4(s.dir, search_layer), 0.0);
    vec4 around = textureGather(distance_maps, vec4(s.dir, search_layer), 3);
    float nearest = min(min(around.x, around.y), min(around.z, around.w));
    float farthest = max(max(around.x, around.y), max(around.z, around.w));
    bool resolved = !s.escaped && abs(length(x + dir * s.d) - texel.a) <= HYBRID_TOLERANCE * texel.a
                    && farthest - nearest <= HYBRID_GAP * nearest;
    atomicAdd(rq_counts[2u * push.object], 1u);
    if (resolved) return texel.rgb;
    atomicAdd(rq_counts[2u * push.object + 1u], 1u);
    // Off the surface by 10⁻⁵ of its distance from the reference point (f32 rounding of p).
    RayHit h = rq_trace_outside(p, dir, 1e-5 * length(x) + 1e-30, push.object);
    // Nothing: the environment at infinity, as the map holds it in that direction.
    if (h.triangle == RAY_NO_TRIANGLE) return textureLod(distance_maps, vec4(dir, search_layer), 0.0).rgb;
    TriangleShading sh = rq_shading[h.triangle];
    float w = 1.0 - h.u - h.v;
    vec3 n = sh.n0.xyz * w + sh.n1.xyz * h.u + sh.n2.xyz * h.v;
    n = dot(n, n) > 0.0 ? normalize(n) : -dir;
    vec2 uv = sh.uv01.xy * w + sh.uv01.zw * h.u + sh.uv2.xy * h.v;
    Material m2 = materials[floatBitsToUint(sh.n0.w)];
    vec3 q = p + dir * h.t;
    if (m2.kind == KIND_DIFFUSE) return shade_diffuse(m2, q, n, p, uv);
    return textureLod(distance_maps, vec4(normalize(q - o.reference_point.xyz), search_layer), 0.0).rgb;
}
#define RADIANCE hybrid_radiance
#else
#define RADIANCE traced_radiance
#endif

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    // The test knob debug_fault=flip_reflection: a deliberately broken reflection.
    if ((push.flags & FLAG_DEBUG_FLIP_REFLECTION) != 0u) s.r = -s.r;
    vec3 c = s.fr * RADIANCE(o, in_position, s.r);
    if (any(greaterThan(s.ft, vec3(0.0)))) c += s.ft * RADIANCE(o, in_position, s.t);
    out_color = vec4(c, 1.0);
}
