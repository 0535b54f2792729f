#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.photon_map: for each level of the photon grid (fine, then coarse: base 0 and
// 2 grid_cells) the exclusive scan of its bucket counts (photon_grid[base + grid_cells + b])
// into each bucket's first place (photon_grid[base + b]), the counts zeroed for the scatters
// to count again. One workgroup: each invocation scans a run of buckets, the runs' totals
// are scanned in shared memory.
layout(local_size_x = 256) in;
#include "common/scene.glsl"

shared uint totals[256];

void main() {
    uint h = caustic.grid_cells;
    uint t = gl_LocalInvocationID.x;
    uint run = (h + 255u) / 256u;
    uint begin = min(t * run, h);
    uint end = min(begin + run, h);
    for (uint base = 0u; base <= 2u * h; base += 2u * h) {
        uint sum = 0u;
        for (uint i = begin; i < end; ++i) sum += photon_grid[base + h + i];
        totals[t] = sum;
        memoryBarrierShared();
        barrier();
        if (t == 0u) {
            uint acc = 0u;
            for (uint k = 0u; k < 256u; ++k) {
                uint v = totals[k];
                totals[k] = acc;
                acc += v;
            }
        }
        memoryBarrierShared();
        barrier();
        uint at = totals[t];
        for (uint i = begin; i < end; ++i) {
            uint c = photon_grid[base + h + i];
            photon_grid[base + i] = at;
            photon_grid[base + h + i] = 0u;
            at += c;
        }
        barrier();
    }
}
