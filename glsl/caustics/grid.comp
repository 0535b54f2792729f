#version 460
#extension GL_GOOGLE_include_directive : require
// variants: SCATTER COARSE
// caustics.photon_map (survey §6.1.1, PDC03), building the photon grid on the GPU: one
// invocation per texel of photon layer push.object, whose caustic cube is push.flags (its
// hits are stored relative to that cube's centre). Without SCATTER it counts the photons
// of each bucket's fine cells (photon_grid[grid_cells + b]) and coarse cells
// (photon_grid[2 grid_cells + b]); caustics/grid_scan.comp turns the counts
// into each bucket's first place and zeroes them; with SCATTER each photon takes the next
// place of its bucket: the photons end sorted by bucket, with no readback. COARSE then
// runs over the sorted photons: each one's place into the next place of its coarse cell's
// bucket (photon_coarse), whose counts the first kernel took and the scan turned into first
// places (photon_grid[2 grid_cells + b], photon_grid[3 grid_cells + b]).
layout(local_size_x = 64) in;
#include "common/scene.glsl"
#include "caustics/photon_map.glsl"

// The invocation's index: dispatches of more than 32768 groups spread over y (Rust's
// `spread_groups`), within every device's 65535 groups an axis.
uint invocation() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
}

#ifdef COARSE
void main() {
    uint j = invocation();
    uint h = caustic.grid_cells;
    if (j >= photon_grid[h - 1u] + photon_grid[2u * h - 1u]) return;  // beyond the photons placed
    uint b = photon_bucket(photon_coarse_cell(photon_list[2u * j].xyz));
    photon_coarse[photon_grid[2u * h + b] + atomicAdd(photon_grid[3u * h + b], 1u)] = j;
}
#else
void main() {
    uint n = caustic.photon_size;
    uint i = invocation();
    if (i >= n * n) return;
    ivec3 tc = ivec3(int(i % n), int(i / n), int(push.object));
    vec4 hit = texelFetch(photon_hits, tc, 0);
    vec4 power = texelFetch(photon_power, tc, 0);
    if (!(hit.w > 0.0) || all(lessThanEqual(power.rgb, vec3(0.0)))) return;
    vec3 p = cubes[push.flags].centre.xyz + hit.xyz;
    if (any(isnan(p)) || any(isinf(p))) return;
    uint b = photon_bucket(photon_cell(p));
#ifdef SCATTER
    uint slot = photon_grid[b] + atomicAdd(photon_grid[caustic.grid_cells + b], 1u);
    photon_list[2u * slot] = vec4(p, power.r);
    photon_list[2u * slot + 1u] = vec4(power.g, power.b, power.w, 0.0);
#else
    atomicAdd(photon_grid[caustic.grid_cells + b], 1u);
    atomicAdd(photon_grid[3u * caustic.grid_cells + photon_bucket(photon_coarse_cell(p))], 1u);
#endif
}
#endif
