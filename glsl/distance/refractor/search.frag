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
#include "distance/hybrid.glsl"
#define REFRACTOR_ENV hybrid_radiance
#define REFRACTOR_EXIT hybrid_exit
#endif
#include "distance/refractor/trace.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    out_color = vec4(refractor_radiance(o, m, in_position, normalize(in_normal), views[in_view].eye.xyz), 1.0);
}
