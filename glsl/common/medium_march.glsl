// The march of a ray through a graded medium (survey §6.5, common/medium.glsl) for an
// includer that defines MEDIUM_TRACE(o, d, t_min, t_max, skip) → RayHit, its straight
// intersection (an acceleration scheme's, or a ray query's).
#ifndef COMMON_MEDIUM_MARCH_GLSL
#define COMMON_MEDIUM_MARCH_GLSL
#include "common/medium.glsl"

// The march of a ray leaving o along d in medium m: chord by chord until one hits; that
// chord is then marched again at an eighth of the turn (MEDIUM_REFINE: a chord's sagitta,
// h²κ/8, is the march's error at the surface), as GradedIndex::march with refine = 1. The
// first chord leaves the surface (t_min, skip), the others start where the last ended.
const float MEDIUM_REFINE = 8.0;

struct MediumMarch {
    RayHit hit;     // on the last chord (RAY_NO_TRIANGLE: the sky, or lost)
    vec3 origin;    // the last chord's origin and unit direction
    vec3 dir;
    float before;   // the path length before it
    bool lost;      // ⌈MEDIUM_MAX_TURN / turn⌉ chords without a hit
};

MediumMarch medium_march(Material m, vec3 o, vec3 d, float t_min, uint skip, float turn) {
    MediumMarch r;
    MediumMarch coarse;
    r.before = 0.0;
    r.lost = false;
    vec3 g;
    vec3 x = o;
    float n = medium_index(m, x, g);
    vec3 v = normalize(d) * n;
    bool first = true;
    bool refined = false;
    float budget = MEDIUM_INF;
    uint steps = uint(ceil(MEDIUM_MAX_TURN / turn)) + 4u * uint(MEDIUM_REFINE);
    for (uint k = 0u; k < steps; ++k) {
        if (r.before > budget) return coarse;  // the refinement missed its chord's hit (rounding)
        float h = medium_step_length(m, n, g, turn);
        float lo = first ? t_min : 0.0;
        uint sk = first ? skip : RAY_NO_TRIANGLE;
        r.origin = x;
        if (isinf(h)) {
            r.dir = normalize(v);
            r.hit = MEDIUM_TRACE(x, r.dir, lo, MEDIUM_INF, sk);
            return r;
        }
        vec3 x1 = x, v1 = v;
        medium_rk4(m, x1, v1, h / n);
        vec3 c = x1 - x;
        float len = length(c);
        if (len > 0.0) {
            r.dir = c / len;
            // a little past the chord's end: no crack between chords
            r.hit = MEDIUM_TRACE(x, r.dir, lo, len * 1.000001, sk);
            if (r.hit.triangle != RAY_NO_TRIANGLE) {
                if (refined) return r;
                // March this chord again, finer, from its start.
                coarse = r;
                refined = true;
                turn /= MEDIUM_REFINE;
                budget = r.before + 1.5 * len;
                continue;
            }
        }
        r.before += len;
        x = x1;
        v = v1;
        n = medium_index(m, x, g);
        first = false;
    }
    if (refined) return coarse;
    r.origin = x;
    r.dir = normalize(v);
    r.hit = RayHit(0.0, 0.0, 0.0, RAY_NO_TRIANGLE);
    r.lost = true;
    return r;
}
#endif
