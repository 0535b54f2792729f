#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.reach (issue 33 item 4): where the photons of photon layer push.object, of
// caustic cube push.flags, went — the world bounds of their terminal hits, whether one
// escaped the receivers (w −1 in the hit image) and how many landed — folded into
// caustic_reach's eight words of the cube (min xyz, max xyz as reach_key, escaped, count),
// first within the workgroup, then once per workgroup. The stage reads them back after the
// frame: a later move that reaches neither these bounds nor the light's way to the generator
// leaves the generator's caustic as it is.
layout(local_size_x = 64) in;
#include "common/scene.glsl"

// An order-preserving key of a float: a < b ⇔ reach_key(a) < reach_key(b) (unsigned).
uint reach_key(float f) {
    uint b = floatBitsToUint(f);
    return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}

shared uint lo[3];
shared uint hi[3];
shared uint escaped;
shared uint landed;

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
        } else if (hit.w > 0.0) {
            vec3 p = cubes[push.flags].centre.xyz + hit.xyz;
            if (all(not(isnan(p))) && all(not(isinf(p)))) {
                for (int k = 0; k < 3; ++k) {
                    atomicMin(lo[k], reach_key(p[k]));
                    atomicMax(hi[k], reach_key(p[k]));
                }
                atomicAdd(landed, 1u);
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
