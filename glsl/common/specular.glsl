// Splits the view ray at an ideal specular surface into its reflected and refracted
// branches with their Fresnel weights (survey eq. 1). How each branch's radiance is found
// is the method's business: that is the survey's whole taxonomy.
#ifndef SPECULAR_GLSL
#define SPECULAR_GLSL
#include "common/shading.glsl"

struct SpecularSplit {
    vec3 r;    // reflected direction
    vec3 t;    // refracted direction (valid when any(ft > 0))
    vec3 fr;   // weight of the reflected radiance
    vec3 ft;   // weight of the refracted radiance
};

SpecularSplit specular_split(Material m, vec3 p, vec3 n, vec3 eye) {
    SpecularSplit s;
    vec3 i = normalize(p - eye);
    float cos_i = -dot(n, i);
    bool entering = cos_i >= 0.0;
    if (!entering) { n = -n; cos_i = -cos_i; }
    s.r = reflect_dir(i, n);
    s.t = i;
    s.ft = vec3(0.0);
    if (m.kind == KIND_MIRROR) {
        s.fr = material_fresnel(m, cos_i, 1.0);
        return s;
    }
    float ior = m.nu.x;
    if (m.thin != 0u) {
        // Thin-walled: the two interfaces are parallel, the ray leaves undeviated.
        s.fr = material_fresnel(m, cos_i, ior);
        s.ft = 1.0 - s.fr;
        return s;
    }
    float eta = entering ? ior : 1.0 / ior;  // ν_t / ν_i
    if (!refract_dir(i, n, 1.0 / eta, s.t)) {
        s.fr = vec3(1.0);  // total internal reflection
        return s;
    }
    s.fr = material_fresnel(m, cos_i, eta);
    s.ft = 1.0 - s.fr;
    return s;
}
#endif
