#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.reach (issue 33 item 4): where the photons of photon layer push.object, of
// caustic cube push.flags, went — the world bounds of their terminal hits and of the
// receiver surfaces their search read, whether one escaped the receivers (w −1 in the hit
// image, or a probe that sees none) and how many landed — folded into caustic_reach's eight
// words of the cube (min xyz, max xyz as reach_key, escaped, count), first within the
// workgroup, then once per workgroup. The stage reads them back after the frame: a later move
// that reaches neither these bounds (with the generator and the cube's centre) nor the
// light's way to the generator leaves the generator's caustic as it is.
//
// The search (common/search.glsl) reads the receiver distance map in the directions, from the
// centre, of probes along the photon's line x + R·d (x where it left the generator, the hit h
// at d = t, both known: w = 1/(1 + t)). Its n linear samples at d = |x| s/(1 − s), s = i/n,
// grow by at most k = 2(n − 1)/(n − 2) from one to the next, so the last one short of the hit
// lies beyond t/k and the first past it within k·t (the false-position steps lie between);
// where t exceeds the last sample, |x|(n − 1), the far end's bracket looks past the hit in
// directions on the arc from h's to R's, and its last undershoot lies beyond that sample;
// where the first sample already overshoots, the bracket's other end is x itself. The
// surfaces the map holds in REACH_PROBES directions of each stretch are added, and those around
// the hit's direction as far as its splat and the filter spread it (past a silhouette they
// light a farther receiver).
layout(local_size_x = 64) in;
#include "common/scene.glsl"
#include "caustics/photon_map.glsl"

const int REACH_PROBES = 4;

// An order-preserving key of a float: a < b ⇔ reach_key(a) < reach_key(b) (unsigned).
uint reach_key(float f) {
    uint b = floatBitsToUint(f);
    return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}

shared uint lo[3];
shared uint hi[3];
shared uint escaped;
shared uint landed;

// Adds a world point to the workgroup's bounds.
void reach_include(vec3 p) {
    if (any(isnan(p)) || any(isinf(p))) return;
    for (int k = 0; k < 3; ++k) {
        atomicMin(lo[k], reach_key(p[k]));
        atomicMax(hi[k], reach_key(p[k]));
    }
}

void main() {
    uint t = gl_LocalInvocationIndex;
    if (t < 3u) {
        lo[t] = 0xffffffffu;
        hi[t] = 0u;
    }
    if (t == 0u) {
        escaped = 0u;
        landed = 0u;
    }
    barrier();
    uint n = caustic.photon_size;
    // Dispatches of more than 32768 groups spread over y (Rust's `spread_groups`).
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    if (i < n * n) {
        vec4 hit = texelFetch(photon_hits, ivec3(int(i % n), int(i / n), int(push.object)), 0);
        if (hit.w < 0.0) {
            atomicOr(escaped, 1u);
        } else if (hit.w > 0.0 && hit.w <= 1.0) {
            CausticCube c = cubes[push.flags];
            vec3 p = c.centre.xyz + hit.xyz;
            if (all(not(isnan(p))) && all(not(isinf(p)))) {
                reach_include(p);
                atomicAdd(landed, 1u);
                // The surfaces the search's probes read: along the photon's line from its start
                // (at most |hit| + radius before the hit) to its farthest probe past it.
                vec3 dir = photon_direction(texelFetch(photon_power, ivec3(int(i % n), int(i / n), int(push.object)), 0).w);
                float steps = float(max(push_search_linear_steps(), 3u));
                float len = 1.0 / hit.w - 1.0;
                vec3 x = hit.xyz - dir * len;
                float last = length(x) * (steps - 1.0);
                float k = 2.0 * (steps - 1.0) / (steps - 2.0);
                vec3 at = normalize(hit.xyz);
                bool far_end = len >= last * 0.999;
                vec3 past = far_end ? dir : normalize(hit.xyz + dir * ((k - 1.0) * len));
                float before = far_end ? max(len - last, len * (1.0 - 1.0 / k)) : len * (1.0 - 1.0 / k);
                // Around the hit: the splat's radius and the filter's, in texels of the cube.
                float spread = (caustic.splat_size + float(caustic.filter_radius) + 1.0) * 2.0 / float(caustic.cube_size);
                vec3 t1 = normalize(cross(at, abs(at.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0)));
                vec3 t2 = cross(at, t1);
                for (int j = 0; j < 4; ++j) {
                    vec3 d = normalize(at + spread * (j < 2 ? t1 : t2) * (j % 2 == 0 ? 1.0 : -1.0));
                    float s = textureLod(caustic_distances, vec4(d, float(push.flags)), 0.0).r;
                    if (s >= 1e30) {
                        atomicOr(escaped, 1u);
                    } else {
                        reach_include(c.centre.xyz + d * s);
                    }
                }
                if (len * (steps - 1.0) <= length(x) * 1.001) {
                    // The first sample overshoots: the bracket's start is x.
                    float s = textureLod(caustic_distances, vec4(normalize(x), float(push.flags)), 0.0).r;
                    if (s < 1e30) reach_include(c.centre.xyz + normalize(x) * s);
                }
                for (int j = 0; j <= 2 * REACH_PROBES; ++j) {
                    float t = float(j) / float(REACH_PROBES);
                    // j ≤ REACH_PROBES: on the arc from the hit's direction past it; then before it.
                    vec3 l = j <= REACH_PROBES ? mix(at, past, t) : hit.xyz - dir * (before * (t - 1.0));
                    float ll = length(l);
                    if (!(ll > 0.0)) continue;
                    float stored = textureLod(caustic_distances, vec4(l / ll, float(push.flags)), 0.0).r;
                    if (stored >= 1e30) {
                        atomicOr(escaped, 1u);  // a probe that sees no receiver: any move may
                    } else {
                        reach_include(c.centre.xyz + l / ll * stored);
                    }
                }
            }
        }
    }
    barrier();
    uint base = 8u * push.flags;
    if (t < 3u && landed > 0u) {
        atomicMin(caustic_reach[base + t], lo[t]);
        atomicMax(caustic_reach[base + 3u + t], hi[t]);
    }
    if (t == 0u) {
        if (escaped != 0u) atomicOr(caustic_reach[base + 6u], 1u);
        if (landed > 0u) atomicAdd(caustic_reach[base + 7u], landed);
    }
}
