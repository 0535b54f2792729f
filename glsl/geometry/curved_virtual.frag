#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.virtual, the draw: the environment's radiance at the real surface point (as
// scene.direct shades it), alpha 1 marking the pixel as covered. A triangle with a vertex
// that has no reflection point on the reflector (off its silhouette or rim) is dropped:
// the interpolated validity is below 1 everywhere inside it.
#include "common/specular.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 4) in float in_valid;
layout(location = 0) out vec4 out_color;

void main() {
    if (in_valid < 0.999) discard;
    Material m = materials[objects[push.object].material];
    vec3 n = normalize(in_normal);
    vec3 eye = views[in_view].eye.xyz;
    vec3 c;
    if (m.kind == KIND_DIFFUSE) {
        c = shade_diffuse(m, in_position, n, eye, in_uv);
    } else {
        SpecularSplit s = specular_split(m, in_position, n, eye);
        c = s.fr * sky_radiance(s.r);
        if (any(greaterThan(s.ft, vec3(0.0)))) c += s.ft * sky_radiance(s.t);
    }
    out_color = vec4(c, 1.0);
}
