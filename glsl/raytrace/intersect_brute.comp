#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// Brute force: every triangle for every ray (the baseline of the conformance tests).
#include "raytrace/rays.glsl"

RayHit intersect_brute(RayQuery q) {
    RayHit best = no_hit(q);
    bool any_hit = (q.flags & RAY_ANY_HIT) != 0u;
    // lavapipe before Mesa 25 gives each invocation one budget of 65535 loop iterations, shared by all its
    // loops (gallivm's loop limiter; measured: with one loop the 65536th triangle is never
    // tested, with two nested loops the budget ends sooner), so the loop tests 8 triangles
    // per iteration: up to 524280 triangles there.
    uint n = accel.triangle_count;
#define BRUTE_TEST(j) \
    if (base + j < n && test_triangle(base + j, q, best) && any_hit) return best;
    for (uint base = 0u; base < n; base += 8u) {
        BRUTE_TEST(0u) BRUTE_TEST(1u) BRUTE_TEST(2u) BRUTE_TEST(3u)
        BRUTE_TEST(4u) BRUTE_TEST(5u) BRUTE_TEST(6u) BRUTE_TEST(7u)
    }
    return best;
}

#define INTERSECT intersect_brute
#include "raytrace/intersect_main.glsl"
