#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// image_space.refract: Wyman's front-face/back-face double refraction (survey §4.4). The
// distance to the second interface is interpolated between d_V (back-face distance along
// the view ray, from the first pass) and d_N (precomputed along the inverted normal) by the
// angles of incidence and refraction; the back-face normal is fetched where that point
// projects. The ray that leaves searches the environment's distance map.
#include "common/specular.glsl"
#include "common/traced.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 4) SAMPLE_INTERP in float in_thickness;
layout(location = 0) out vec4 out_color;

// The radiance the refracted ray t (weight ft, refracting out with index ior) brings: its
// second interface found in image space, then out (or, totally reflected, looked up there).
vec3 through(Object o, Material m, View v, vec3 eye, vec3 p1, vec3 n1, vec3 t, vec3 ft, float ior) {
    vec3 i = normalize(p1 - eye);
    if (dot(n1, i) > 0.0) n1 = -n1;
    float theta_i = acos(clamp(-dot(i, n1), -1.0, 1.0));
    float theta_t = acos(clamp(-dot(t, n1), -1.0, 1.0));
    float ratio = theta_i > 1e-4 ? theta_t / theta_i : 1.0 / ior;  // Snell's small-angle limit
    ivec2 size = textureSize(backface_map, 0);
    vec2 uv = gl_FragCoord.xy / vec2(size);
    float d_v = max(textureLod(backface_map, uv, 0.0).w - length(p1 - eye), 0.0);
    float d = ratio * d_v + (1.0 - ratio) * in_thickness;
    vec3 p2 = p1 + t * d;
    vec4 clip = v.view_proj * vec4(p2, 1.0);
    vec2 uv2 = clamp(clip.xy / clip.w * 0.5 + 0.5, vec2(0.0), vec2(1.0));
    // image_space_iterations (beyond the paper): Newton steps on f(d) = |p(d) − eye| − D(p(d)),
    // D the back faces' distance from the eye where p(d) projects, its derivative taken as
    // the refracted ray's component along the view direction (D held still).
    for (uint k = 0u; k < push_image_space_iterations(); ++k) {
        float back = textureLod(backface_map, uv2, 0.0).w;
        vec3 to = p2 - eye;
        float dist = length(to);
        float slope = dot(t, to / max(dist, 1e-30));
        if (back <= 0.0 || abs(slope) < 0.05) break;  // no back face there, or grazing
        d = max(d - (dist - back) / slope, 0.0);
        p2 = p1 + t * d;
        clip = v.view_proj * vec4(p2, 1.0);
        uv2 = clamp(clip.xy / clip.w * 0.5 + 0.5, vec2(0.0), vec2(1.0));
    }
    vec3 n2 = textureLod(backface_map, uv2, 0.0).xyz;
    n2 = dot(n2, n2) > 0.0 ? normalize(n2) : -n1;
    if (dot(n2, t) < 0.0) n2 = -n2;  // outward, along the leaving ray
    ft *= volume_transmittance(m, d);  // absorbed on the way through
    vec3 t2;
    if (refract_dir(t, -n2, ior, t2)) {
        vec3 f = material_fresnel(m, dot(t, n2), 1.0 / ior);
        return ft * (1.0 - f) * traced_radiance(o, p2, t2);
    }
    // Total internal reflection: the two-pass method has no third interface; the
    // internally reflected ray looks the environment up as if it left here.
    return ft * traced_radiance(o, p2, reflect_dir(t, -n2));
}

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    View v = views[in_view];
    vec3 eye = v.eye.xyz;
    vec3 p1 = in_position;
    vec3 n1 = normalize(in_normal);
    SpecularSplit s = specular_split(m, p1, n1, eye);
    vec3 c = s.fr * traced_radiance(o, p1, s.r);
    if (!material_disperses(m)) {
        if (any(greaterThan(s.ft, vec3(0.0)))) c += through(o, m, v, eye, p1, n1, s.t, s.ft, material_ior(m));
    } else {
        // KHR_materials_dispersion: each channel along its own refraction.
        for (int k = 0; k < 3; ++k) {
            if (s.ft[k] > 0.0) c += through(o, m, v, eye, p1, n1, s.tc[k], s.ft * channel_mask(k), m.nu[k]);
        }
    }
    out_color = vec4(c, 1.0);
}
