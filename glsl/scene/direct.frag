#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CAUSTICS_TEXTURE
// scene.direct: non-specular surfaces (emission + Lambertian direct light with shadows).
// The same shader fills environment maps, where specular objects other than the map's
// owner have no map of their own yet: they reflect and refract the environment map.
// CAUSTICS_TEXTURE (caustic_space=texture, for the environment maps): diffuse surfaces read
// the receivers' light map at their triangle.
#include "common/specular.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    CAUSTIC_TRIANGLE_HERE();
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 n = normalize(in_normal);
    vec3 eye = views[in_view].eye.xyz;
    vec3 c;
    if (m.kind == KIND_DIFFUSE) {
        c = shade_diffuse(m, in_position, n, eye, in_uv);
    } else {
        SpecularSplit s = specular_split(m, in_position, n, eye);
        c = s.fr * sky_radiance(s.r);
        vec3 refracted;
        REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, n, dir) * sky_radiance(dir));
        c += refracted;
    }
    out_color = vec4(c, 1.0);
}
