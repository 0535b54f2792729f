#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// distance.search: single reflections and refractions using the sampled geometry (§4.2):
// the reflected and refracted rays are traced in the object's distance map and the hit
// texel's radiance is weighted by Fresnel.
#include "common/specular.glsl"
#include "common/traced.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    // The test knob debug_fault=flip_reflection: a deliberately broken reflection.
    if ((push.flags & FLAG_DEBUG_FLIP_REFLECTION) != 0u) s.r = -s.r;
    vec3 c = s.fr * traced_radiance(o, in_position, s.r);
    if (any(greaterThan(s.ft, vec3(0.0)))) c += s.ft * traced_radiance(o, in_position, s.t);
    out_color = vec4(c, 1.0);
}
