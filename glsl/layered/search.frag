#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE COUNT_FAR COUNT_FAR_PER_SAMPLE
#ifdef COUNT_FAR_PER_SAMPLE
#define COUNT_FAR
#define PER_SAMPLE
#endif
// layered.search (survey §4.5): a specular object traced in the layered distance map of
// the whole scene, recursively (layered/trace.glsl), up to `depth` bounces in all.
#include "layered/trace.glsl"
#ifdef COUNT_FAR
// Counted per fragment that survives the depth test; where the peel is not cut the counters
// are absent (a null descriptor: the adds are dropped).
layout(early_fragment_tests) in;
#endif

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 c = layered_radiance(o.map_centre.xyz, m, in_position, normalize(in_normal), views[in_view].eye.xyz, max(push_recursion_depth(), 1u) - 1u);
    out_color = vec4(c, 1.0);
#ifdef COUNT_FAR
    if (layered_met_last && textureSize(layered_maps, 0).z > 1) atomicAdd(layered_far[push.object], 1u);
#endif
}
