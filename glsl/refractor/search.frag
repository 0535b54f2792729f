#version 460
#extension GL_GOOGLE_include_directive : require
// refractor.search: self refraction with a refractor map (survey §4.4): the refracted ray
// is searched inside the object's own refractor map, refracted out with Snell's law, or
// reflected internally on total internal reflection, up to `internal_bounces` times; each
// ray that leaves searches the environment's distance map. Fresnel weights every interface.
#include "common/specular.glsl"
#include "common/traced.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 p = in_position;
    SpecularSplit s = specular_split(m, p, normalize(in_normal), views[in_view].eye.xyz);
    vec3 c = s.fr * traced_radiance(o, p, s.r);
    vec3 weight = s.ft;
    vec3 pos = p;
    vec3 dir = s.t;
    float ior = m.nu.x;
    vec3 ref = o.reference_point.xyz;
    for (uint bounce = 0u; bounce <= push.internal_bounces && any(greaterThan(weight, vec3(1e-4))); ++bounce) {
        search_map = 1;
        search_layer = float(o.refractor_layer);
        // The ray starts on the refractor's own surface, where |l| = |l'|: start the search
        // just inside, so that the surface it leaves is not mistaken for the one it meets.
        float eps = 1e-2 * length(pos - ref);
        SearchResult h = search_ray(pos + dir * eps - ref, dir);
        if (h.escaped) {  // an open refractor: the ray is out
            c += weight * traced_radiance(o, pos, dir);
            weight = vec3(0.0);
            break;
        }
        vec3 hit = pos + dir * (eps + h.d);
        vec3 n2 = normalize(textureLod(refractor_maps, vec4(h.dir, search_layer), 0.0).xyz);
        if (dot(n2, dir) < 0.0) n2 = -n2;       // the outward normal, along the leaving ray
        float cos_i = dot(dir, n2);
        vec3 out_dir;
        // Leaving the object: ν_i/ν_t = ior, the normal faces the inside (−n2).
        if (refract_dir(dir, -n2, ior, out_dir)) {
            vec3 f = material_fresnel(m, cos_i, 1.0 / ior);
            c += weight * (1.0 - f) * traced_radiance(o, hit, out_dir);
            weight *= f;
        }
        // Total internal reflection (or the reflected part): on inside the object.
        dir = reflect_dir(dir, -n2);
        pos = hit;
    }
    out_color = vec4(c, 1.0);
}
