// Splits the view ray at an ideal specular surface into its reflected and refracted
// branches with their Fresnel weights (survey eq. 1). How each branch's radiance is found
// is the method's business: that is the survey's whole taxonomy.
#ifndef SPECULAR_GLSL
#define SPECULAR_GLSL
#include "common/shading.glsl"
#include "common/medium.glsl"

struct SpecularSplit {
    vec3 r;    // reflected direction
    vec3 t;    // refracted direction (valid when any(ft > 0)): the d line's (green) under dispersion
    vec3 fr;   // weight of the reflected radiance
    vec3 ft;   // weight of the refracted radiance
    // Under dispersion (material_disperses): each channel's refracted direction, its
    // weights fr[k], ft[k] with its own index (total internal reflection per channel); a
    // method that follows each channel's ray reads tc[k] (refracted_channels below), one
    // that follows one ray takes t for all three. Without it, all three are t.
    vec3 tc[3];
};

// The index of refraction of a dielectric: glTF's `ior` (the d line's under dispersion).
float material_ior(Material m) { return m.nu.y; }

// Channel k alone (1 there, 0 in the others): the weight mask of a dispersed ray.
vec3 channel_mask(int k) {
    return vec3(equal(ivec3(0, 1, 2), ivec3(k)));
}

// KHR_materials_dispersion: a solid dielectric whose channels refract with their own
// indices (Material.nu holds one per channel, src/scene/mod.rs Material::channel_iors).
bool material_disperses(Material m) {
    return m.kind == KIND_DIELECTRIC && m.thin == 0u && (m.nu.x != m.nu.y || m.nu.z != m.nu.y);
}

SpecularSplit specular_split(Material m, vec3 p, vec3 n, vec3 eye) {
    SpecularSplit s;
    vec3 i = normalize(p - eye);
    float cos_i = -dot(n, i);
    bool entering = cos_i >= 0.0;
    if (!entering) { n = -n; cos_i = -cos_i; }
    s.r = reflect_dir(i, n);
    s.t = i;
    s.ft = vec3(0.0);
    s.tc[0] = i;
    s.tc[1] = i;
    s.tc[2] = i;
    if (m.kind == KIND_MIRROR) {
        s.fr = material_fresnel(m, cos_i, 1.0);
        return s;
    }
    float ior = material_ior_at(m, p);  // a graded medium's index where the ray meets it
    if (m.thin != 0u) {
        // Thin-walled: the two interfaces are parallel, the ray leaves undeviated.
        s.fr = material_fresnel(m, cos_i, ior);
        s.ft = 1.0 - s.fr;
        return s;
    }
    if (material_disperses(m)) {
        bool any_t = false;
        for (int k = 0; k < 3; ++k) {
            float eta = entering ? m.nu[k] : 1.0 / m.nu[k];  // ν_t / ν_i
            vec3 t;
            if (refract_dir(i, n, 1.0 / eta, t)) {
                s.tc[k] = t;
                s.fr[k] = material_fresnel(m, cos_i, eta)[k];
                s.ft[k] = 1.0 - s.fr[k];
                if (!any_t || k == 1) s.t = t;
                any_t = true;
            } else {
                s.fr[k] = 1.0;  // total internal reflection in this channel
            }
        }
        return s;
    }
    float eta = entering ? ior : 1.0 / ior;  // ν_t / ν_i
    if (!refract_dir(i, n, 1.0 / eta, s.t)) {
        s.fr = vec3(1.0);  // total internal reflection
        return s;
    }
    s.tc[0] = s.t;
    s.tc[1] = s.t;
    s.tc[2] = s.t;
    s.fr = material_fresnel(m, cos_i, eta);
    s.ft = 1.0 - s.fr;
    return s;
}

// The refracted branch's radiance for a method that looks radiance up along a direction:
// `result` = s.ft · LOOKUP, where LOOKUP is an expression of `dir` (the direction looked
// along); under dispersion one lookup per channel along its own direction, each keeping its
// channel. Nothing where nothing is refracted.
#define REFRACTED_RADIANCE(result, m, s, LOOKUP)                           \
    {                                                                      \
        result = vec3(0.0);                                                \
        if (!material_disperses(m)) {                                      \
            if (any(greaterThan(s.ft, vec3(0.0)))) {                       \
                vec3 dir = s.t;                                            \
                result = s.ft * (LOOKUP);                                  \
            }                                                              \
        } else {                                                           \
            for (int k_ = 0; k_ < 3; ++k_) {                               \
                if (s.ft[k_] <= 0.0) continue;                             \
                vec3 dir = s.tc[k_];                                       \
                result[k_] = s.ft[k_] * (LOOKUP)[k_];                      \
            }                                                              \
        }                                                                  \
    }

// Absorption inside solid dielectrics (KHR_materials_volume, Beer–Lambert): what is left
// of radiance after a path of length len inside material m (σ is zero elsewhere).
vec3 volume_transmittance(Material m, float len) {
    return exp(-m.absorption.rgb * max(len, 0.0));
}

// The transmittance of the segment a ray of direction d ran, `len` long, to the surface
// (material m, normal n either way round) it hits: the segment lay inside m's solid when
// the ray meets that surface from within (as specular_split tells entering from leaving).
vec3 segment_transmittance(Material m, vec3 n, vec3 d, float len) {
    if (m.kind != KIND_DIELECTRIC || m.thin != 0u || dot(n, d) <= 0.0) return vec3(1.0);
    return volume_transmittance(m, len);
}

// The length of the ray p + t·dir, t ≥ 0, from a point of object o's surface into its
// solid, up to where it leaves the object's bounding box and bounding sphere: for a
// method that does not trace the inside (a single refraction, §3–4.1) the path its
// absorption takes. Exact for spheres and axis-aligned boxes, at least the true chord
// for every convex solid (p lies inside both bounds).
float bounds_chord(Object o, vec3 p, vec3 dir) {
    vec3 lo = o.bounds_min.xyz, hi = o.bounds_max.xyz;
    vec3 inv = 1.0 / mix(dir, vec3(1e-20), equal(dir, vec3(0.0)));  // no 0 · ∞ below
    vec3 t1 = (lo - p) * inv, t2 = (hi - p) * inv;
    vec3 far = max(t1, t2);
    float t_box = max(min(min(far.x, far.y), far.z), 0.0);
    vec3 c = 0.5 * (lo + hi) - p;
    float r = o.bounds_min.w;
    float b = dot(c, dir);
    float disc = b * b - (dot(c, c) - r * r);
    float t_sphere = disc > 0.0 ? max(b + sqrt(disc), 0.0) : 0.0;
    return min(t_box, t_sphere);
}

// Absorption along the refracted branch of a single-refraction method at point p of
// object o (material m): the chord through its bounds, when the branch enters the solid.
vec3 chord_transmittance(Object o, Material m, vec3 p, vec3 n, vec3 t) {
    if (m.kind != KIND_DIELECTRIC || m.thin != 0u || dot(n, t) >= 0.0 || all(equal(m.absorption.rgb, vec3(0.0)))) return vec3(1.0);
    return volume_transmittance(m, bounds_chord(o, p, t));
}
#endif
