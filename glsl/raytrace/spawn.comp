#version 460
#extension GL_GOOGLE_include_directive : require
// Spawning (survey §2.3.1): a specular hit with bounces left splits the ray into its
// reflected and refracted children, each weighted by its Fresnel factor (survey eq. 1;
// total internal reflection gives the reflected child weight 1), as the CPU reference's
// recursion does; children below MIN_PATH_WEIGHT in every channel are not followed.
layout(local_size_x = 64) in;
#include "raytrace/trace.glsl"

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
    vec3 wr = pl.weight.rgb * sp.fr;
    vec3 wt = pl.weight.rgb * sp.ft;
    if (max(max(wr.x, wr.y), wr.z) >= MIN_PATH_WEIGHT) {
        push_ray(make_query(s.p, normalize(sp.r), trace.t_min, 1.0 / 0.0, h.triangle, 0u), make_payload(wr, pl.pixel));
    }
    if (max(max(wt.x, wt.y), wt.z) >= MIN_PATH_WEIGHT) {
        push_ray(make_query(s.p, normalize(sp.t), trace.t_min, 1.0 / 0.0, h.triangle, 0u), make_payload(wt, pl.pixel));
    }
}
