// Non-specular shading: emission plus Lambertian direct light from punctual lights,
// shadowed by distance maps (cube maps for point and spot lights, planar for directional).
#ifndef SHADING_GLSL
#define SHADING_GLSL
#include "common/scene.glsl"
#include "common/optics.glsl"
#include "common/sky.glsl"
#include "caustics/project.glsl"

// Compute shaders have no derivatives: they define SHADING_LOD0 and sample level 0 (the
// only level: textures have no mip chain, so the result is the same).
#ifdef SHADING_LOD0
#define MATERIAL_TEXTURE(uv, layer) textureLod(textures, vec3(uv, float(layer)), 0.0)
#else
#define MATERIAL_TEXTURE(uv, layer) texture(textures, vec3(uv, float(layer)))
#endif

vec3 material_base_color(Material m, vec2 uv) {
    vec3 c = m.base_color.rgb;
    if (m.base_texture >= 0) c *= MATERIAL_TEXTURE(uv, m.base_texture).rgb;
    return c;
}

vec3 material_emission(Material m, vec2 uv) {
    vec3 e = m.emissive.rgb;
    if (m.emissive_texture >= 0) e *= MATERIAL_TEXTURE(uv, m.emissive_texture).rgb;
    return e;
}

// Fraction of light i reaching p (0 or 1; the shadow maps store distances).
float light_visibility(Light l, vec3 p, vec3 n) {
    float layer = l.cone.z;
    if (layer < 0.0) return 1.0;
    float texel = 2.0 / l.cone.w;  // one texel's size at unit distance
    if (uint(l.direction_kind.w) == LIGHT_DIRECTIONAL) {
        vec3 q = p + n * (1.5 * l.intensity.w);  // normal offset: intensity.w is one texel in metres
        vec4 c = l.shadow_view_proj * vec4(q, 1.0);
        vec2 uv = c.xy * 0.5 + 0.5;
        if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;
        float stored = textureLod(shadow_planes, vec3(uv, layer), 0.0).r;
        float d = dot(q - l.position_range.xyz, l.direction_kind.xyz);
        return d <= stored + l.intensity.w ? 1.0 : 0.0;
    }
    vec3 to_p = p - l.position_range.xyz;
    float dist = length(to_p);
    vec3 q = p + n * (dist * texel * 1.5);  // normal offset grows with distance
    vec3 dq = q - l.position_range.xyz;
    float stored = textureLod(shadow_cubes, vec4(dq, layer), 0.0).r;
    return length(dq) <= stored * (1.0 + 2.0 * texel) ? 1.0 : 0.0;  // relative only: scale-free
}

// Irradiance E of light l at p on a surface facing it (range window, spot cone), the unit
// direction wi towards it and its distance (+∞ for directional lights).
vec3 light_irradiance(Light l, vec3 p, out vec3 wi, out float dist) {
    uint kind = uint(l.direction_kind.w);
    if (kind == LIGHT_DIRECTIONAL) {
        wi = -l.direction_kind.xyz;
        dist = 1.0 / 0.0;
        return l.intensity.rgb;
    }
    vec3 d = l.position_range.xyz - p;
    float d2 = max(dot(d, d), 1e-12);
    dist = sqrt(d2);
    wi = d / dist;
    vec3 e = l.intensity.rgb / d2;
    float range = l.position_range.w;
    if (range > 0.0) {  // KHR_lights_punctual's recommended window (not squared)
        float r = dist / range;
        e *= clamp(1.0 - r * r * r * r, 0.0, 1.0);
    }
    if (kind == LIGHT_SPOT) {
        // KHR_lights_punctual's recommended falloff: the ramp linear in cos θ between the
        // outer and inner cone, squared (src/reference/shade.rs is its twin).
        float cd = dot(l.direction_kind.xyz, -wi);
        float ramp = clamp((cd - l.cone.x) / max(l.cone.y - l.cone.x, 1e-4), 0.0, 1.0);
        e *= ramp * ramp;
    }
    return e;
}

// Emission + albedo/π · (Σ E_i · visibility + the caustics' E) (radiance towards any
// direction).
vec3 shade_diffuse(Material m, vec3 p, vec3 n, vec3 eye, vec2 uv) {
    vec3 albedo = material_base_color(m, uv);
    vec3 v = normalize(eye - p);
    if (dot(n, v) < 0.0) n = -n;  // two-sided
    vec3 l_sum = vec3(0.0);
    for (uint i = 0u; i < push.light_count; ++i) {
        Light l = lights[i];
        vec3 wi;
        float dist;
        vec3 e = light_irradiance(l, p, wi, dist);
        float cos_t = dot(n, wi);
        if (cos_t <= 0.0) continue;
        l_sum += e * cos_t * light_visibility(l, p, n);
    }
    // Caustics (§6): light through specular objects; the camera has a pass for them.
    if ((push.flags & FLAG_CAUSTICS_APART) == 0u) l_sum += caustic_irradiance(p, n);
    return material_emission(m, uv) + albedo / PI * l_sum;
}

// Fresnel reflectance of material m at incidence cosine cos_i; `eta` = ν_t/ν_i for
// dielectrics. KHR_materials_specular scales F0 (colour) and the whole lobe (factor).
vec3 material_fresnel(Material m, float cos_i, float eta) {
    bool exact = (push.flags & FLAG_FRESNEL_EXACT) != 0u;
    if (m.kind == KIND_MIRROR) {
        return exact ? fresnel_conductor(cos_i, m.nu.rgb, m.kappa.rgb)
                     : fresnel_schlick(fresnel_f0(m.nu.rgb, m.kappa.rgb), cos_i);
    }
    vec3 f;
    if (exact) {
        f = vec3(fresnel_dielectric(cos_i, eta));
    } else {
        // Schlick is written for incidence from the optically thinner side: use the
        // transmitted cosine when leaving a denser medium, and report TIR as 1.
        float c = cos_i;
        if (eta < 1.0) {
            float s2 = (1.0 - cos_i * cos_i) / (eta * eta);
            if (s2 >= 1.0) return vec3(1.0);
            c = sqrt(1.0 - s2);
        }
        vec3 f0 = min(fresnel_f0(vec3(eta), vec3(0.0)) * m.specular.rgb, vec3(1.0));
        f = fresnel_schlick(f0, c);
    }
    return f * m.specular.a;
}
#endif
