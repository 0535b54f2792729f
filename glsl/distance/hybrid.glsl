// The hybrid search (hybrid=rays, src/methods/distance/hybrid.rs): what a distance-map
// camera pass does where its search cannot answer. Included by the HYBRID variants, which
// define SPECULA_RAY_QUERY and enable GL_EXT_ray_query first.
#ifndef DISTANCE_HYBRID_GLSL
#define DISTANCE_HYBRID_GLSL
// The per-object ray counters (`distance.hybrid.*` in the frame's stats) are storage writes
// from a fragment shader: the HYBRID_UNCOUNTED variants leave them out where the device was
// not created with fragmentStoresAndAtomics (a host's device: its features are not known).
#ifdef HYBRID_NO_COUNTS
#define RQ_COUNT(k)
#else
#define RQ_COUNT(k) atomicAdd(rq_counts[k], 1u)
#endif
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

// hybrid=confirm (FLAG_HYBRID_CONFIRM): the ray query that confirms a search's hit runs from
// the ray's start to this fraction of the map's distance past the hit: the search's hit bounds
// the query (t_max), and whatever the map cannot see before it — a face hidden from the
// reference point that the linear search stepped over — is found too.
const float HYBRID_WINDOW = 0.01;

// The most meetings with its own surface that hybrid_outside follows one ray that left a
// refractor through (the budget of interfaces ends it first: 16 internal bounces + 2).
const uint HYBRID_MAX_MEETINGS = 18u;

// Where a ray query from surface point p starts: off the surface by 10⁻⁵ of p's distance from
// the reference point `ref`, and by more than the f32 rounding of p far from the origin.
float hybrid_t_min(vec3 p, vec3 ref) {
    return max(1e-5 * length(p - ref), 1e-6 * length(p)) + 1e-30;
}

bool hybrid_confirms() {
    return (push.flags & FLAG_HYBRID_CONFIRM) != 0u;
}

// The nearest triangle along o + t d, t_min ≤ t ≤ t_max, of any object but `mesh` (inside:
// false; the distance map leaves the object out, its rays' fallback does too), or of `mesh`
// alone (inside: true; a refractor's own surface); of every object for mesh RQ_EVERY_MESH
// and inside false. Never triangle `skip`: the one the ray leaves, as the exact tracers skip
// it (RAY_NO_TRIANGLE: none known) — a grazing ray from a point that f32 rounding put just
// off that triangle's plane meets it again farther than any t_min would cover.
const uint RQ_EVERY_MESH = 0xffffffffu;
RayHit rq_trace_mesh(vec3 o, vec3 d, float t_min, float t_max, uint mesh, bool inside, uint skip) {
    RayHit best = RayHit(RQ_T_MAX, 0.0, 0.0, RAY_NO_TRIANGLE);
    t_max = min(t_max, RQ_T_MAX);
    if (!is_finite(o) || !is_finite(d) || dot(d, d) == 0.0 || !(0.0 <= t_min && t_min <= t_max)) return best;
    rayQueryEXT rq;
    rayQueryInitializeEXT(rq, tlas, gl_RayFlagsNoOpaqueEXT, 0xffu, o, t_min, d, t_max);
    while (rayQueryProceedEXT(rq)) {
        if (rayQueryGetIntersectionTypeEXT(rq, false) != gl_RayQueryCandidateIntersectionTriangleEXT) continue;
        uint id = RQ_TRIANGLE(rq, false);
        if ((floatBitsToUint(rq_shading[id].uv2.z) == mesh) == inside && id != skip) rayQueryConfirmIntersectionEXT(rq);
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

// Radiance arriving at p from dir along ray-query hit h (none: the environment at infinity,
// as the map holds it in that direction): a diffuse surface lit as the camera's; a specular
// one by what the map holds in its direction.
vec3 hybrid_shade(Object o, vec3 p, vec3 dir, RayHit h) {
    if (h.triangle == RAY_NO_TRIANGLE) return textureLod(distance_maps, vec4(dir, search_layer), 0.0).rgb;
    RqSurface sf = rq_surface(h, dir);
    Material m2 = materials[sf.material];
    vec3 q = p + dir * h.t;
    if (m2.kind == KIND_DIFFUSE) return shade_diffuse(m2, q, sf.n, p, sf.uv);
    return textureLod(distance_maps, vec4(normalize(q - o.reference_point.xyz), search_layer), 0.0).rgb;
}

// Radiance arriving at p from dir: the distance-map search's, or where it cannot answer, the
// ray query's hit shaded (hybrid_shade). Counts per object the rays asked and traced.
vec3 hybrid_radiance(Object o, vec3 p, vec3 dir) {
    search_map = 0;
    search_layer = float(o.envmap_layer);
    vec3 x = p - o.reference_point.xyz;
    SearchResult s = search_ray(x, dir);
    vec4 texel = textureLod(distance_maps, vec4(s.dir, search_layer), 0.0);
    bool resolved = hybrid_resolved(s, x, dir, texel.a, textureGather(distance_maps, vec4(s.dir, search_layer), 3));
    RQ_COUNT(2u * push.object);
    float t_min = hybrid_t_min(p, o.reference_point.xyz);
    RayHit h = RayHit(RQ_T_MAX, 0.0, 0.0, RAY_NO_TRIANGLE);
    if (resolved) {
        if (!hybrid_confirms()) return texel.rgb;
        // The map's hit confirmed: the nearest triangle up to just past it, shaded.
        float w = HYBRID_WINDOW * texel.a;
        h = rq_trace_mesh(p, dir, t_min, s.d + w, push.object, false, RAY_NO_TRIANGLE);
    }
    if (h.triangle == RAY_NO_TRIANGLE) {
        RQ_COUNT(2u * push.object + 1u);
        h = rq_trace_mesh(p, dir, t_min, RQ_T_MAX, push.object, false, RAY_NO_TRIANGLE);
    }
    return hybrid_shade(o, p, dir, h);
}

// The geometric normal of the camera fragment's triangle, turned to the eye
// (hybrid_geometric_normal; set by the camera pass's main).
vec3 hybrid_ng = vec3(0.0);

// The reflected ray r from the camera fragment's point p: a ray that goes into the object's
// own surface (below its triangle's plane: the interpolated normal tilted past the
// triangle's, near a silhouette) goes on inside, as through the exact tracers (its own
// surface is no part of its maps): off a mirror nothing reaches p from there where it meets
// the object; others see what the hybrid search finds (a solid refractor's camera pass
// follows it inside: refractor/search.frag). The rest as hybrid_radiance.
vec3 hybrid_reflected(Object o, vec3 p, vec3 r) {
    if (!(dot(r, hybrid_ng) < 0.0) || materials[o.material].kind != KIND_MIRROR) return hybrid_radiance(o, p, r);
    search_layer = float(o.envmap_layer);
    RQ_COUNT(2u * push.object);
    RQ_COUNT(2u * push.object + 1u);
    RayHit h = rq_trace_mesh(p, r, 1e-5 * length(p - o.reference_point.xyz) + 1e-30, RQ_T_MAX, RQ_EVERY_MESH, false, RAY_NO_TRIANGLE);
    if (h.triangle != RAY_NO_TRIANGLE && floatBitsToUint(rq_shading[h.triangle].uv2.z) == push.object) return vec3(0.0);
    return hybrid_shade(o, p, r, h);
}

// The geometric normal of the fragment's triangle at p, on the side of the eye (the side the
// reflected ray leaves on); 0 where the derivatives degenerate (no ray is then taken for one
// into the surface). Called in uniform control flow.
vec3 hybrid_geometric_normal(vec3 p, vec3 eye) {
    vec3 ng = cross(dFdx(p), dFdy(p));
    if (!(dot(ng, ng) > 0.0) || !is_finite(ng)) return vec3(0.0);
    return dot(ng, eye - p) < 0.0 ? -ng : ng;
}

// A solid refractor that is not convex (FLAG_HYBRID_REENTERS): a ray that leaves it may meet
// it again, which neither map holds (the distance map leaves the object out). Such rays ask
// one ray query of every object: where the nearest is the refractor itself, the refracted path is queued here,
// followed inside after the path that found it (a work list instead of recursion; a path
// that finds the list full is dropped), and the reflected ray goes on the same way.
//
// A path's budget counts its interfaces as the exact tracers' `depth` does (the camera's
// hit, each surface met inside, each meeting from outside): internal_bounces + 2, so that the
// camera's path inside meets internal_bounces + 1 surfaces, as without the hybrid, and paths
// that come back in spend the same budget instead of starting a new one. Past it a path
// still specular ends black, as through the exact tracers.
const uint HYBRID_PATHS = 4u;
struct HybridPath {
    vec3 pos;
    vec3 dir;
    vec3 weight;
    // The interfaces the path has met up to pos (pos's included).
    uint used;
    // The triangle at pos (RAY_NO_TRIANGLE: not known).
    uint from;
};
HybridPath hybrid_paths[HYBRID_PATHS];
uint hybrid_queued = 0u;
// The index the current inside paths refract with (a channel's under dispersion).
float hybrid_ior = 1.0;
// The interfaces the current inside path had met where it started.
uint hybrid_used = 1u;
// The refractor's triangle the current inside path is at (where hybrid_exit last found it,
// RAY_NO_TRIANGLE where a map answered): what its next ray query skips.
uint hybrid_from = RAY_NO_TRIANGLE;

uint hybrid_budget() {
    return push_internal_bounces() + 2u;
}

// What a ray that left refractor o at p along d (p: its `used`-th interface) brings back,
// times w: hybrid_radiance, or where it meets the refractor again before anything else, the
// refracted path there queued and the reflected ray followed on (refractor/trace.glsl's
// REFRACTOR_OUT).
vec3 hybrid_outside(Object o, vec3 p, vec3 d, vec3 w, uint used) {
    // One search at the end whatever the ray met (every call site is a copy of the search
    // in the compiled shader).
    vec3 from = p;
    vec3 along = d;
    vec3 times = w;
    uint skip = hybrid_from;
    if ((push.flags & FLAG_HYBRID_REENTERS) != 0u) {
        for (uint k = 0u; k < HYBRID_MAX_MEETINGS; ++k) {
            float r = length(from - o.reference_point.xyz);
            float t_min = hybrid_t_min(from, o.reference_point.xyz);
            // A point the refractor map answered (no triangle known) may lie off the surface
            // by the search's tolerance: start past it, or the ray meets the surface it left.
            if (skip == RAY_NO_TRIANGLE) t_min = max(t_min, 2.0 * HYBRID_TOLERANCE * r);
            RQ_COUNT(2u * push.object);
            RQ_COUNT(2u * push.object + 1u);
            // The nearest triangle of any object: the refractor's own, or the ray goes on to
            // the search (one query for both questions).
            RayHit own = rq_trace_mesh(from, along, t_min, RQ_T_MAX, RQ_EVERY_MESH, false, skip);
            if (own.triangle == RAY_NO_TRIANGLE || floatBitsToUint(rq_shading[own.triangle].uv2.z) != push.object) break;
            skip = own.triangle;
            // It meets the refractor again: its (used + 1)-th interface.
            used += 1u;
            if (used > hybrid_budget()) return vec3(0.0);
            vec3 q = from + along * own.t;
            // It comes from outside, entering, unless the interpolated normal faces along the
            // ray (near a silhouette), where the exact tracers take it as leaving.
            vec3 n = rq_surface(own, along).n;
            bool entering = dot(n, along) <= 0.0;
            if (!entering) n = -n;  // against the ray
            // Taken as leaving, the segment ran inside as the exact tracers see it: absorbed.
            if (!entering) times *= volume_transmittance(materials[o.material], own.t);
            float eta_t_i = entering ? hybrid_ior : 1.0 / hybrid_ior;
            vec3 f = material_fresnel(materials[o.material], -dot(along, n), eta_t_i);
            vec3 t;
            if (used < hybrid_budget() && hybrid_queued < HYBRID_PATHS && refract_dir(along, n, 1.0 / eta_t_i, t)) {
                hybrid_paths[hybrid_queued] = HybridPath(q, t, times * (1.0 - f), used, own.triangle);
                hybrid_queued += 1u;
            }
            from = q;
            along = reflect_dir(along, n);
            times *= f;
        }
    }
    return times * hybrid_radiance(o, from, along);
}

// refractor_exit (distance/refractor/trace.glsl) where its refractor-map search cannot
// answer: the exit surface found by a ray query against the refractor's own triangles, with
// its interpolated normal as it is (refractor_inside_ior decides leaving or entering by it).
bool hybrid_exit(Object o, vec3 pos, vec3 dir, out vec3 hit, out vec3 n2) {
    vec3 ref = o.reference_point.xyz;
    search_map = 1;
    search_layer = float(o.refractor_layer);
    float eps = 1e-2 * length(pos - ref);
    vec3 x = pos + dir * eps - ref;
    SearchResult h = search_ray(x, dir);
    vec4 texel = textureLod(refractor_maps, vec4(h.dir, search_layer), 0.0);
    vec4 around = textureGather(refractor_maps, vec4(h.dir, search_layer), 3);
    RQ_COUNT(2u * push.object);
    float t_min = hybrid_t_min(pos, ref);
    RayHit r = RayHit(RQ_T_MAX, 0.0, 0.0, RAY_NO_TRIANGLE);
    if (hybrid_resolved(h, x, dir, texel.w, around)) {
        if (!hybrid_confirms()) {
            hit = pos + dir * (eps + h.d);
            hybrid_from = RAY_NO_TRIANGLE;
            n2 = normalize(texel.xyz);
            if (dot(n2, dir) < 0.0) n2 = -n2;
            return true;
        }
        // The map's exit confirmed: the refractor's own nearest triangle up to just past it.
        float w = HYBRID_WINDOW * texel.w;
        r = rq_trace_mesh(pos, dir, t_min, eps + h.d + w, push.object, true, hybrid_from);
    }
    if (r.triangle == RAY_NO_TRIANGLE) {
        RQ_COUNT(2u * push.object + 1u);
        r = rq_trace_mesh(pos, dir, t_min, RQ_T_MAX, push.object, true, hybrid_from);
    }
    if (r.triangle == RAY_NO_TRIANGLE) return false;  // an open refractor: the ray is out
    // The interpolated normal as it is: where it faces the ray, the exact tracers take the
    // ray as entering, and so does refractor_inside_ior.
    n2 = rq_surface(r, dir).n;
    hit = pos + dir * r.t;
    hybrid_from = r.triangle;
    return true;
}
#endif
