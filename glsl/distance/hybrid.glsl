// The hybrid search (hybrid=rays, src/methods/distance/hybrid.rs): what a distance-map
// camera pass does where its search cannot answer. Included by the HYBRID variants, which
// define SPECULA_RAY_QUERY and enable GL_EXT_ray_query first.
#ifndef DISTANCE_HYBRID_GLSL
#define DISTANCE_HYBRID_GLSL
#include "common/specular.glsl"
#include "common/traced.glsl"
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

// The nearest triangle along o + t d, t ≥ t_min, of any object but `mesh` (inside: false; the
// distance map leaves the object out, its rays' fallback does too), or of `mesh` alone
// (inside: true; a refractor's own surface).
RayHit rq_trace_mesh(vec3 o, vec3 d, float t_min, uint mesh, bool inside) {
    RayHit best = RayHit(RQ_T_MAX, 0.0, 0.0, RAY_NO_TRIANGLE);
    if (!is_finite(o) || !is_finite(d) || dot(d, d) == 0.0) return best;
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsNoOpaqueEXT, 0xffu, o, t_min, d, RQ_T_MAX);
    while (rayQueryProceedEXT(rq)) {
        if (rayQueryGetIntersectionTypeEXT(rq, false) != gl_RayQueryCandidateIntersectionTriangleEXT) continue;
        if ((floatBitsToUint(rq_shading[RQ_TRIANGLE(rq, false)].uv2.z) == mesh) == inside) rayQueryConfirmIntersectionEXT(rq);
    }
    if (rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT) {
        vec2 uv = rayQueryGetIntersectionBarycentricsEXT(rq, true);
        best = RayHit(rayQueryGetIntersectionTEXT(rq, true), uv.x, uv.y, RQ_TRIANGLE(rq, true));
    }
    return best;
}

// The search hit `s` of x + t dir in map `layer` of the refractor maps (search_map 1, the
// distance in .w) or the distance maps: is it the surface the map holds there?
bool hybrid_resolved(SearchResult s, vec3 x, vec3 dir, float stored, vec4 around) {
    float nearest = min(min(around.x, around.y), min(around.z, around.w));
    float farthest = max(max(around.x, around.y), max(around.z, around.w));
    return !s.escaped && abs(length(x + dir * s.d) - stored) <= HYBRID_TOLERANCE * stored && farthest - nearest <= HYBRID_GAP * nearest;
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
    bool resolved = hybrid_resolved(s, x, dir, texel.a, textureGather(distance_maps, vec4(s.dir, search_layer), 3));
    atomicAdd(rq_counts[2u * push.object], 1u);
    if (resolved) return texel.rgb;
    atomicAdd(rq_counts[2u * push.object + 1u], 1u);
    // Off the surface by 10⁻⁵ of its distance from the reference point (f32 rounding of p).
    RayHit h = rq_trace_mesh(p, dir, 1e-5 * length(x) + 1e-30, push.object, false);
    // Nothing: the environment at infinity, as the map holds it in that direction.
    if (h.triangle == RAY_NO_TRIANGLE) return textureLod(distance_maps, vec4(dir, search_layer), 0.0).rgb;
    RqSurface sf = rq_surface(h, dir);
    Material m2 = materials[sf.material];
    vec3 q = p + dir * h.t;
    if (m2.kind == KIND_DIFFUSE) return shade_diffuse(m2, q, sf.n, p, sf.uv);
    return textureLod(distance_maps, vec4(normalize(q - o.reference_point.xyz), search_layer), 0.0).rgb;
}

// refractor_exit (distance/refractor/trace.glsl) where its refractor-map search cannot
// answer: the exit surface found by a ray query against the refractor's own triangles, with
// its shading normal turned along the ray.
bool hybrid_exit(Object o, vec3 pos, vec3 dir, out vec3 hit, out vec3 n2) {
    vec3 ref = o.reference_point.xyz;
    search_map = 1;
    search_layer = float(o.refractor_layer);
    float eps = 1e-2 * length(pos - ref);
    vec3 x = pos + dir * eps - ref;
    SearchResult h = search_ray(x, dir);
    vec4 texel = textureLod(refractor_maps, vec4(h.dir, search_layer), 0.0);
    vec4 around = textureGather(refractor_maps, vec4(h.dir, search_layer), 3);
    atomicAdd(rq_counts[2u * push.object], 1u);
    if (hybrid_resolved(h, x, dir, texel.w, around)) {
        hit = pos + dir * (eps + h.d);
        n2 = normalize(texel.xyz);
        if (dot(n2, dir) < 0.0) n2 = -n2;
        return true;
    }
    atomicAdd(rq_counts[2u * push.object + 1u], 1u);
    RayHit r = rq_trace_mesh(pos, dir, 1e-5 * length(pos - ref) + 1e-30, push.object, true);
    if (r.triangle == RAY_NO_TRIANGLE) return false;  // an open refractor: the ray is out
    n2 = rq_surface(r, dir).n;
    if (dot(n2, dir) < 0.0) n2 = -n2;
    hit = pos + dir * r.t;
    return true;
}
#endif
