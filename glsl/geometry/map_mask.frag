#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.map_mask: a planar mirror in another object's cube map (survey §5 inside §3/§4).
// Marks the mirror's pixels of a cube face in the depth buffer — the farthest depth there,
// the nearest everywhere else (cleared so), so that the mirrored view drawn next lands on
// the mirror's pixels only — and fills them with the environment along the reflected ray
// (what the mirrored view shows where no geometry is).
#include "common/specular.glsl"
#include "common/sky.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    vec3 eye = views[in_view].eye.xyz;
    vec3 i = normalize(in_position - eye);
    vec3 n = normalize(in_normal);
    if (dot(n, i) > 0.0) n = -n;
    out_color = vec4(sky_radiance(reflect_dir(i, n)), 0.0);
    gl_FragDepth = 0.0;
}
