// The body of every intersection kernel: one invocation per query, INTERSECT(q) defined
// by the scheme's kernel before this include. In the GRADED_MEDIA variant (the ray
// pipeline of a scene with graded media, survey §6.5), a query in a graded medium
// (q.medium ≠ 0) marches its curved path chord by chord through the same scheme
// (common/medium_march.glsl) and writes its last chord back as the query's origin and
// direction, with the path length before it (`before`), so that shading and spawning see
// where and along what direction it met the surface. (Only that variant reads the frame's
// materials and trace parameters: the plain kernels also run under the schemes' own
// harness, src/methods/raytrace/gpu.rs, whose layout has neither.)
layout(local_size_x = 64) in;

#ifdef GRADED_MEDIA
RayHit intersect_chord(vec3 o, vec3 d, float t_min, float t_max, uint skip) {
    return INTERSECT(RayQuery(vec4(o, t_min), vec4(d, t_max), skip, 0u, 0u, 0u));
}
#define MEDIUM_TRACE intersect_chord
#include "common/medium_march.glsl"
#endif

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= ray_count || (queries[i].flags & RAY_HIT_KNOWN) != 0u) return;
    RayQuery q = queries[i];
#ifdef GRADED_MEDIA
    if (q.medium != 0u) {
        MediumMarch r = medium_march(materials[q.medium - 1u], q.origin.xyz, q.direction.xyz, q.origin.w, q.skip, trace.medium_turn);
        queries[i].origin.xyz = r.origin;
        queries[i].direction = vec4(r.dir, r.hit.t);
        queries[i].before = floatBitsToUint(r.before);
        if (r.lost) queries[i].flags |= RAY_LOST;
        hits[i] = r.hit;
        return;
    }
#endif
    hits[i] = INTERSECT(q);
}
