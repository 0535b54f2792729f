#version 460
#extension GL_GOOGLE_include_directive : require
// Spawning (survey §2.3.1): a specular hit with bounces left splits the ray into its
// reflected and refracted children, each weighted by its Fresnel factor (survey eq. 1;
// total internal reflection gives the reflected child weight 1), as the CPU reference's
// recursion does; children below MIN_PATH_WEIGHT in every channel are not followed.
//
// The next queue holds at most trace.capacity rays (the ray_budget knob). Which children
// it keeps must not depend on the order the GPU runs this kernel in, or an overflowing
// frame would differ from run to run: the kernel runs twice. push.object 0 counts the
// children per weight bin (a quarter octave of their largest channel); spawn_cutoff.comp
// keeps the heaviest bins that fit; push.object 1 appends the children of the kept bins and
// counts the others, with their path weight, as dropped. Lighter paths go first, and the
// kept set is a function of the weights alone.
layout(local_size_x = 64) in;
#include "raytrace/trace.glsl"

uint weight_bin(vec3 w) {
    float m = max(max(w.x, w.y), w.z);
    return uint(clamp(floor(-log2(max(m, 1e-30)) * 4.0), 0.0, float(SPAWN_BINS - 1u)));
}

void child(vec3 o, vec3 d, uint skip, vec3 w, uint pixel) {
    if (max(max(w.x, w.y), w.z) < MIN_PATH_WEIGHT) return;
    uint bin = weight_bin(w);
    if (push.object == 0u) {
        atomicAdd(spawn_budget.hist[bin], 1u);
    } else if (bin < spawn_budget.cutoff) {
        push_ray(make_query(o, d, trace.t_min, 1.0 / 0.0, skip, 0u), make_payload(w, pixel));
    } else {
        atomicAdd(spawn_budget.dropped, 1u);
        uint add = uint(clamp(max(max(w.x, w.y), w.z), 0.0, 2048.0) * ACCUM_SCALE + 0.5);
        uint old = atomicAdd(spawn_budget.dropped_weight[0], add);
        if (old + add < old) atomicAdd(spawn_budget.dropped_weight[1], 1u);
    }
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= min(ray_count, trace.capacity) || trace.last != 0u) return;
    RayHit h = hits[i];
    if (h.triangle == RAY_NO_TRIANGLE) return;
    Surface s = hit_surface(h);
    Material m = materials[s.material];
    if (m.kind == KIND_DIFFUSE) return;
    RayPayload pl = payloads[i];
    vec3 d = normalize(queries[i].direction.xyz);
    SpecularSplit sp = specular_split(m, s.p, s.n, s.p - d);
    child(s.p, normalize(sp.r), h.triangle, pl.weight.rgb * sp.fr, pl.pixel);
    child(s.p, normalize(sp.t), h.triangle, pl.weight.rgb * sp.ft, pl.pixel);
}
