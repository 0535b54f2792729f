#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// layered.search (survey §4.5): a specular object traced in the layered distance map of
// the whole scene, recursively (layered/trace.glsl), up to `depth` bounces in all.
#include "layered/trace.glsl"

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
}
