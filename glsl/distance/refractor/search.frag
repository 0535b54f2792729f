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
// refractor.search: self refraction with a refractor map (survey §4.4), seen by the camera.
// HYBRID (hybrid=rays): searches that cannot answer, inside the refractor and out in the
// environment, traced through Vulkan ray queries (distance/hybrid.glsl).
#ifdef HYBRID
#include "common/scene.glsl"
// A reflected ray into the refractor's own surface goes on inside it (hybrid_reflected).
vec3 refractor_reflected_inside(Object o, vec3 p, vec3 r);
#define HYBRID_INSIDE refractor_reflected_inside
#include "distance/hybrid.glsl"
#define REFRACTOR_ENV hybrid_radiance
#define REFRACTOR_EXIT hybrid_exit
#define REFRACTOR_REFLECTED hybrid_reflected
#endif
#include "distance/refractor/trace.glsl"

#ifdef HYBRID
vec3 refractor_reflected_inside(Object o, vec3 p, vec3 r) {
    return refractor_inside(o, materials[o.material], p, r, vec3(1.0), vec3(0.0));
}
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
    out_color = vec4(refractor_radiance(o, m, in_position, normalize(in_normal), views[in_view].eye.xyz), 1.0);
}
