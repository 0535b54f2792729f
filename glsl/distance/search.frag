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
#include "distance/hybrid.glsl"
#define RADIANCE hybrid_radiance
#define REFLECTED hybrid_reflected
#else
#define RADIANCE traced_radiance
#define REFLECTED traced_radiance
#endif

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
#ifdef HYBRID
    hybrid_ng = hybrid_geometric_normal(in_position, views[in_view].eye.xyz);
#endif
    // The test knob debug_fault=flip_reflection: a deliberately broken reflection.
    if ((push.flags & FLAG_DEBUG_FLIP_REFLECTION) != 0u) s.r = -s.r;
    vec3 c = s.fr * REFLECTED(o, in_position, s.r);
    vec3 refracted;
    REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, normalize(in_normal), dir) * RADIANCE(o, in_position, dir));
    c += refracted;
    out_color = vec4(c, 1.0);
}
