// Self refraction with a refractor map (survey §4.4): the refracted ray is searched inside
// the object's own refractor map, refracted out with Snell's law, or reflected internally
// on total internal reflection, up to `internal_bounces` times (the hybrid search: within
// its budget of interfaces, distance/hybrid.glsl); each ray that leaves
// searches the environment's distance map. Fresnel weights every interface, absorption
// (KHR_materials_volume) every segment inside. Used by the
// camera pass (refractor.search) and, for inter-object cycles, by distance-map generation.
#ifndef REFRACTOR_TRACE_GLSL
#define REFRACTOR_TRACE_GLSL
#include "common/specular.glsl"
#include "common/traced.glsl"

// The surface the ray (pos, dir) inside solid refractor o meets next, searched in its
// refractor map: false when there is none (an open refractor: the ray is out), else the hit
// and the outward normal there (along the leaving ray). Shared by the camera's self
// refraction below and the caustic photons (glsl/caustics/photons.frag).
bool refractor_exit(Object o, vec3 pos, vec3 dir, out vec3 hit, out vec3 n2) {
    vec3 ref = o.reference_point.xyz;
    search_map = 1;
    search_layer = float(o.refractor_layer);
    // The ray starts on the refractor's own surface, where |l| = |l'|: start the search
    // just inside, so that the surface it leaves is not mistaken for the one it meets.
    float eps = 1e-2 * length(pos - ref);
    SearchResult h = search_ray(pos + dir * eps - ref, dir);
    if (h.escaped) return false;
    hit = pos + dir * (eps + h.d);
    n2 = normalize(textureLod(refractor_maps, vec4(h.dir, search_layer), 0.0).xyz);
    if (dot(n2, dir) < 0.0) n2 = -n2;
    return true;
}

// What the camera's self refraction traces with: the map searches, unless a variant (the
// hybrid search, distance/hybrid.glsl) defines its own before including this file.
#ifndef REFRACTOR_ENV
#define REFRACTOR_ENV traced_radiance
#endif
#ifndef REFRACTOR_EXIT
#define REFRACTOR_EXIT refractor_exit
#endif
// What a ray that left the refractor at p along d brings back, times w; `hits`: the surfaces
// this inside path has met so far (the hybrid search follows the ray into the refractor again
// where it meets it, within the path's budget of interfaces).
#ifndef REFRACTOR_OUT
#define REFRACTOR_OUT(o, p, d, w, hits) ((w) * REFRACTOR_ENV(o, p, d))
#endif
// The last internal bounce an inside path takes (the hybrid's: what its budget leaves).
#ifndef REFRACTOR_LAST_BOUNCE
#define REFRACTOR_LAST_BOUNCE push_internal_bounces()
#endif

// c plus the radiance arriving at point p of solid refractor o (material m) along dir, a
// ray that runs inside it, times weight: searched in its refractor map to the surface it
// meets, refracted out there (Fresnel) or reflected on inside, up to internal_bounces times
// (REFRACTOR_LAST_BOUNCE).
// `ior`: the index the ray refracts out with (a channel's under dispersion).
vec3 refractor_inside_ior(Object o, Material m, vec3 p, vec3 dir, vec3 weight, vec3 c, float ior) {
    vec3 pos = p;
    uint last = REFRACTOR_LAST_BOUNCE;
    for (uint bounce = 0u; bounce <= last && any(greaterThan(weight, vec3(1e-4))); ++bounce) {
        vec3 hit, n2;
        if (!REFRACTOR_EXIT(o, pos, dir, hit, n2)) {  // an open refractor: the ray is out
            c += REFRACTOR_OUT(o, pos, dir, weight, bounce);
            weight = vec3(0.0);
            break;
        }
        // Leaving the object where the normal faces along the ray (the map's always does):
        // ν_i/ν_t = ior, the normal turned to the inside. A triangle's interpolated normal
        // (the hybrid's exits) may face the ray near a silhouette; the exact tracers then take
        // the ray as entering (specular_split), and so does this.
        float cos_i = dot(dir, n2);
        bool leaving = cos_i > 0.0;
        // Absorbed on the way there: a segment that meets the surface from within, as the
        // exact tracers absorb (segment_transmittance).
        if (leaving) weight *= volume_transmittance(m, length(hit - pos));
        vec3 against = leaving ? -n2 : n2;
        float eta_i_t = leaving ? ior : 1.0 / ior;
        vec3 out_dir;
        if (refract_dir(dir, against, eta_i_t, out_dir)) {
            vec3 f = material_fresnel(m, abs(cos_i), 1.0 / eta_i_t);
            c += REFRACTOR_OUT(o, hit, out_dir, weight * (1.0 - f), bounce + 1u);
            weight *= f;
        }
        // Total internal reflection (or the reflected part): on inside the object.
        dir = reflect_dir(dir, against);
        pos = hit;
    }
    return c;
}

vec3 refractor_inside(Object o, Material m, vec3 p, vec3 dir, vec3 weight, vec3 c) {
    return refractor_inside_ior(o, m, p, dir, weight, c, material_ior(m));
}

// Radiance leaving point p of solid refractor o (material m, interpolated normal n)
// towards eye; under dispersion each channel traced inside along its own refraction.
vec3 refractor_radiance(Object o, Material m, vec3 p, vec3 n, vec3 eye) {
    SpecularSplit s = specular_split(m, p, n, eye);
    vec3 c = s.fr * REFRACTOR_ENV(o, p, s.r);
    if (!material_disperses(m)) return refractor_inside(o, m, p, s.t, s.ft, c);
    for (int k = 0; k < 3; ++k) {
        if (s.ft[k] > 0.0) c = refractor_inside_ior(o, m, p, s.tc[k], s.ft * channel_mask(k), c, m.nu[k]);
    }
    return c;
}
#endif
