#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE HYBRID HYBRID_PER_SAMPLE HYBRID_UNCOUNTED HYBRID_UNCOUNTED_PER_SAMPLE
#ifdef HYBRID_UNCOUNTED_PER_SAMPLE
#define HYBRID_UNCOUNTED
#define PER_SAMPLE
#endif
#ifdef HYBRID_UNCOUNTED
#define HYBRID
#define HYBRID_NO_COUNTS
#endif
#ifdef HYBRID_PER_SAMPLE
#define HYBRID
#define PER_SAMPLE
#endif
#ifdef HYBRID
#extension GL_EXT_ray_query : require
#define SPECULA_RAY_QUERY
#endif
// refractor.search: self refraction with a refractor map (survey §4.4), seen by the camera.
// HYBRID (hybrid=rays|confirm): searches that cannot answer, inside the refractor and out in the
// environment, traced through Vulkan ray queries (distance/hybrid.glsl).
#ifdef HYBRID
#include "distance/hybrid.glsl"
#define REFRACTOR_ENV hybrid_radiance
#define REFRACTOR_EXIT hybrid_exit
#define REFRACTOR_OUT(o, p, d, w, hits) hybrid_outside(o, p, d, w, hybrid_used + (hits))
#define REFRACTOR_LAST_BOUNCE (hybrid_budget() - 1u - hybrid_used)
#endif
#include "distance/refractor/trace.glsl"

#ifdef HYBRID
// The inside path, then those queued (by rays that came back in, hybrid_outside; by the
// camera's reflection into the refractor itself): at most twice the list's length of them,
// each of which may queue more. One call site of the inside search, as below: each is a copy
// of every search in the compiled shader.
uint hybrid_camera_triangle = RAY_NO_TRIANGLE;
vec3 hybrid_inside_ior(Object o, Material m, vec3 p, vec3 dir, vec3 weight, vec3 c, float ior) {
    hybrid_ior = ior;
    HybridPath path = HybridPath(p, dir, weight, 1u, hybrid_camera_triangle);
    for (uint k = 0u; k <= 2u * HYBRID_PATHS; ++k) {
        hybrid_used = path.used;
        hybrid_from = path.from;
        c = refractor_inside_ior(o, m, path.pos, path.dir, path.weight, c, ior);
        if (hybrid_queued == 0u) break;
        hybrid_queued -= 1u;
        path = hybrid_paths[hybrid_queued];
    }
    hybrid_queued = 0u;
    return c;
}

// refractor_radiance (refractor/trace.glsl) for the hybrid search: the camera's reflection
// that goes into the refractor's own surface (below its triangle, near a silhouette) goes on
// inside it, as through the exact tracers; on a refractor that is not convex the reflection
// is traced against it (hybrid_outside), which finds that case as the exact tracers do,
// without the screen-space normal that a silhouette's pixel quad gets wrong. Every channel
// (one, without dispersion) inside through one call site; under dispersion the reflection too
// is followed per channel, so that the paths it queues refract with that channel's index.
vec3 hybrid_refractor_radiance(Object o, Material m, vec3 p, vec3 n, vec3 eye) {
    SpecularSplit s = specular_split(m, p, n, eye);
    vec3 c = vec3(0.0);
    // The triangle the camera sees at p (the pass rasterises without triangle ids): the
    // refractor's nearest along the eye's ray to just past p.
    float seen = length(p - eye);
    RQ_COUNT(2u * push.object);
    RQ_COUNT(2u * push.object + 1u);
    hybrid_camera_triangle = rq_trace_mesh(eye, (p - eye) / seen, 0.0, seen * (1.0 + 1e-3), push.object, true, RAY_NO_TRIANGLE).triangle;
    bool into = dot(s.r, hybrid_ng) < 0.0 && (push.flags & FLAG_HYBRID_REENTERS) == 0u;
    bool disperses = material_disperses(m);
    for (int k = 0; k < (disperses ? 3 : 1); ++k) {
        vec3 mask = disperses ? channel_mask(k) : vec3(1.0);
        float ior = disperses ? m.nu[k] : material_ior(m);
        hybrid_ior = ior;
        hybrid_queued = 0u;
        if (into) {
            hybrid_paths[0] = HybridPath(p, s.r, s.fr * mask, 1u, hybrid_camera_triangle);
            hybrid_queued = 1u;
        } else {
            // Off a refractor that is not convex, the reflection may meet it again.
            hybrid_from = hybrid_camera_triangle;
            c += hybrid_outside(o, p, s.r, s.fr * mask, 1u);
        }
        vec3 w = s.ft * mask;
        vec3 dir = disperses ? s.tc[k] : s.t;
        if (any(greaterThan(w, vec3(0.0))) || hybrid_queued > 0u) c = hybrid_inside_ior(o, m, p, dir, w, c, ior);
    }
    return c;
}
#define REFRACTOR_RADIANCE hybrid_refractor_radiance
#else
#define REFRACTOR_RADIANCE refractor_radiance
#endif

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
#ifdef HYBRID
    hybrid_ng = hybrid_geometric_normal(in_position, views[in_view].eye.xyz);
#endif
    out_color = vec4(REFRACTOR_RADIANCE(o, m, in_position, normalize(in_normal), views[in_view].eye.xyz), 1.0);
}
