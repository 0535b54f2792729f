#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// proxy.shade: localised environment mapping (survey §3.2, Figure 15): the reflected or
// refracted ray is intersected with a proxy of the environment, a sphere around the
// reference point or a box (a "parallax-corrected cube map"), and the cube map is looked
// up in the direction of the proxy hit.
#include "common/specular.glsl"
#include "envmap/proxy.glsl"
#include "envmap/cube.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

// Direction from the reference point to where the ray leaves the proxy.
vec3 proxy_direction(Object o, vec3 p, vec3 dir) {
    vec3 c = o.reference_point.xyz;
    if ((push.flags & FLAG_PROXY_BOX) != 0u) {
        // A point outside the box keeps its direction.
        vec3 exit;
        return proxy_box_exit(o, p, dir, exit) ? exit - c : dir;
    }
    float r = o.reference_point.w;
    vec3 x = p - c;
    float b = dot(x, dir);
    float disc = b * b - (dot(x, x) - r * r);
    if (disc < 0.0) return dir;  // outside a proxy it misses: the direction alone
    float t = -b + sqrt(disc);
    return t > 0.0 ? x + dir * t : dir;
}

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    vec3 c = s.fr * own_cube(o, proxy_direction(o, in_position, s.r));
    vec3 refracted;
    REFRACTED_RADIANCE(refracted, m, s,
                       chord_transmittance(o, m, in_position, normalize(in_normal), dir) * own_cube(o, proxy_direction(o, in_position, dir)));
    c += refracted;
    out_color = vec4(c, 1.0);
}
