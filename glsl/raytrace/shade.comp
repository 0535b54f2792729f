#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CAUSTICS_PHOTON_MAP
// Shading of one bounce's hits (survey §2.3.1): a ray that left the scene adds the
// environment, a diffuse hit its emission and, per light, one shadow query carrying the
// unshadowed Lambertian contribution (added by shadow.comp when nothing occludes it), all
// weighted by the ray's path weight. Specular hits are spawn.comp's.
//
// Where the shadow queue may overflow (its capacity clamped by the device's storage-buffer
// range below one query per light and ray), the shadow queries go through a budget as
// spawn.comp's children do (push.object: BUDGET_COUNT and BUDGET_SUB count and add nothing,
// BUDGET_KEEP shades and queues the kept ones, raytrace/trace.glsl); elsewhere the kernel
// runs once, BUDGET_ALL.
layout(local_size_x = 64) in;
#include "raytrace/trace.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(ray_count, trace.capacity)) return;
    RayQuery q = queries[i];
    RayHit h = hits[i];
    RayPayload pl = payloads[i];
    vec3 w = pl.weight.rgb;
    vec3 d = normalize(q.direction.xyz);
    bool count_only = push.object == BUDGET_COUNT || push.object == BUDGET_SUB;
    if (push.object == BUDGET_SUB && shadow_budget.cutoff == SPAWN_BINS) return;  // nothing cut
    if ((q.flags & RAY_LOST) != 0u) return;  // given up inside a graded medium: black
    if (h.triangle == RAY_NO_TRIANGLE) {
        if (!count_only) accumulate(pl.pixel, w * sky_radiance(d));
        return;
    }
    Surface s = hit_surface(h);
    Material m = materials[s.material];
    if (m.kind != KIND_DIFFUSE) return;
    vec3 albedo = material_base_color(m, s.uv);
    vec3 n = dot(s.n, -d) < 0.0 ? -s.n : s.n;  // two-sided
    if (!count_only) {
        accumulate(pl.pixel, w * material_emission(m, s.uv));
        // Caustics (§6.3.3): light through specular objects, from their light cube maps; in
        // screen space only on the primary hits, from the camera's pixel.
        vec3 e = caustic_irradiance(s.p, n);
        if ((caustic.flags & CAUSTIC_SCREEN_SPACE) != 0u && trace.bounce == 0u) {
            uint at = pl.pixel / trace.samples;
            e = caustic_screen_irradiance(ivec2(at % trace.width, at / trace.width), n, -d);
        }
        if ((caustic.flags & CAUSTIC_TEXTURE_SPACE) != 0u) e = caustic_texture_irradiance(h.triangle, s.p, -d);
        accumulate(pl.pixel, w * albedo / PI * e);
    }
    for (uint k = 0u; k < push.light_count; ++k) {
        vec3 wi;
        float dist;
        vec3 e = light_irradiance(lights[k], s.p, wi, dist);
        float cos_t = dot(n, wi);
        vec3 c = w * albedo / PI * e * cos_t;
        if (cos_t <= 0.0 || all(equal(c, vec3(0.0)))) continue;
        // Up to the light, short of it by the offset the ray starts with.
        float t_max = isinf(dist) ? dist : dist - trace.t_min;
        if ((push.flags & FLAG_UNSHADOWED) != 0u) {
            if (!count_only) accumulate(pl.pixel, c);  // shadows=off: unoccluded, as the reference then
            continue;
        }
        if (budget_admit(1u, push.object, c, pl.pixel, wi)) {
            push_shadow(make_query(s.p, wi, trace.t_min, t_max, h.triangle, RAY_ANY_HIT), make_payload(c, pl.pixel));
        }
    }
}
