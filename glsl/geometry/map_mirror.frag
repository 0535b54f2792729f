#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.map_mirror: a planar mirror drawn into another object's cube map over its
// mirrored view (geometry.map_mask and the view drawn there): the colour already in the
// face is multiplied by the mirror's Fresnel weight at the reference point's incidence
// (the pipeline's blend), the alpha replaced by the distance from the reference point.
#include "common/specular.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_weight_distance;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 eye = views[in_view].eye.xyz;
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), eye);
    out_weight_distance = vec4(s.fr, length(in_position - eye));
}
