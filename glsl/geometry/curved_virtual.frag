#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.virtual, the draw: the environment's radiance at the real surface point (as
// scene.direct shades it), alpha 1 marking the pixel as covered. A triangle with a vertex
// that has no reflection point on the reflector (off its silhouette or rim) is dropped:
// the interpolated validity is below 1 everywhere inside it. A specular object of the
// environment is shaded as in the other objects' maps: by its own maps where its plan gives
// it them (traced in its distance map, or self refracted in its refractor map, §4.3–4.4),
// else reflecting the environment; seen from the reflection point, not the camera.
#include "distance/refractor/trace.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 4) in float in_valid;
layout(location = 5) in vec3 in_virtual;
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
        // The reflection point X: on the eye ray to the virtual point, as far from the real
        // point as from the virtual one (the mirror image's defining property).
        vec3 d = in_virtual - eye;
        vec3 ep = eye - in_position;
        float den = 2.0 * (dot(d, d) + dot(d, ep));
        float t = abs(den) > 1e-30 ? (dot(d, d) - dot(ep, ep)) / den : 1.0;
        eye += clamp(t, 0.0, 1.0) * d;
        Object o = as_shown(objects[push.object]);
        SpecularSplit s = specular_split(m, in_position, n, eye);
        bool own = o.map_shading != MAP_SHADING_SKY && o.envmap_layer >= 0;
        if (own && o.map_shading == MAP_SHADING_REFRACTOR && o.refractor_layer >= 0) {
            c = refractor_radiance(o, m, in_position, n, eye);
        } else {
            c = s.fr * (own ? traced_radiance(o, in_position, s.r) : sky_radiance(s.r));
            vec3 refracted;
            REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, n, dir) * (own ? traced_radiance(o, in_position, dir) : sky_radiance(dir)));
            c += refracted;
        }
    }
    out_color = vec4(c, 1.0);
}
