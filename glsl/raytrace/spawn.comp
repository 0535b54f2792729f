#version 460
#extension GL_GOOGLE_include_directive : require
// Spawning (survey §2.3.1): a specular hit with bounces left splits the ray into its
// reflected and refracted children, each weighted by its Fresnel factor (survey eq. 1;
// total internal reflection gives the reflected child weight 1; under dispersion a refracted
// child per channel), as the CPU reference's recursion does; children below MIN_PATH_WEIGHT in every channel are not followed.
//
// The next queue holds at most trace.capacity rays (the ray_budget knob): the kernel runs
// in the budget's three modes (push.object, raytrace/trace.glsl), so that a full queue keeps
// the heaviest paths, whatever order the GPU runs it in.
layout(local_size_x = 64) in;
#include "raytrace/trace.glsl"

// `medium`: the graded medium the child runs in (its material + 1; 0: none).
void child(vec3 o, vec3 d, uint skip, vec3 w, uint pixel, uint medium) {
    if (max(max(w.x, w.y), w.z) < MIN_PATH_WEIGHT) return;
    if (budget_admit(0u, push.object, w, pixel, d)) {
        RayQuery q = make_query(o, d, trace.t_min, 1.0 / 0.0, skip, 0u);
        q.medium = medium;
        push_ray(q, make_payload(w, pixel));
    }
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(ray_count, trace.capacity) || trace.last != 0u) return;
    if (push.object == BUDGET_SUB && spawn_budget.cutoff == SPAWN_BINS) return;  // nothing cut
    RayHit h = hits[i];
    if (h.triangle == RAY_NO_TRIANGLE || (queries[i].flags & RAY_LOST) != 0u) return;
    Surface s = hit_surface(h);
    Material m = materials[s.material];
    if (m.kind == KIND_DIFFUSE) return;
    RayPayload pl = payloads[i];
    RayQuery q = queries[i];
    vec3 d = normalize(q.direction.xyz);
    SpecularSplit sp = specular_split(m, s.p, s.n, s.p - d);
    // A ray that ran inside an absorbing solid to this hit (Beer–Lambert over its length,
    // a curved ray's chords before its last included).
    float len = h.t * length(q.direction.xyz) + (q.medium != 0u ? uintBitsToFloat(q.before) : 0.0);
    vec3 w = pl.weight.rgb * segment_transmittance(m, s.n, d, len);
    vec3 r = normalize(sp.r);
    child(s.p, r, h.triangle, w * sp.fr, pl.pixel, medium_after(s.material, m, s.n, r, true, q.medium));
    if (!material_disperses(m)) {
        vec3 t = normalize(sp.t);
        child(s.p, t, h.triangle, w * sp.ft, pl.pixel, medium_after(s.material, m, s.n, t, false, q.medium));
    } else {
        // KHR_materials_dispersion: a child per channel along its own refraction, carrying
        // that channel alone (a ray that carries one channel spawns one).
        for (int k = 0; k < 3; ++k) {
            child(s.p, normalize(sp.tc[k]), h.triangle, w * sp.ft * channel_mask(k), pl.pixel, 0u);
        }
    }
}
