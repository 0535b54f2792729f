#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// envmap.shade: classic environment mapping (survey §3, §3.1). The reflected and the
// refracted direction look the object's cube map up, ignoring the ray origin; the
// radiances are weighted by the Fresnel function (survey eq. 1). The cube is the object's
// radiance cube, or its distance map where composition draws it so (envmap/cube.glsl).
#include "common/specular.glsl"
#include "envmap/cube.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    vec3 c = s.fr * own_cube(o, s.r);
    vec3 refracted;
    REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, normalize(in_normal), dir) * own_cube(o, dir));
    c += refracted;
    out_color = vec4(c, 1.0);
}
