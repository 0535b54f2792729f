#version 460
#extension GL_GOOGLE_include_directive : require
// The spawn budget's cut (raytrace/spawn.comp): the heaviest weight bins whose children
// all fit in the next queue are kept, the first that does not fit and every lighter one
// dropped.
layout(local_size_x = 1) in;
#include "raytrace/trace.glsl"

void main() {
    uint kept = 0u;
    uint cutoff = SPAWN_BINS;
    for (uint b = 0u; b < SPAWN_BINS; ++b) {
        uint n = spawn_budget.hist[b];
        if (kept + n > trace.capacity) {
            cutoff = b;
            break;
        }
        kept += n;
    }
    spawn_budget.cutoff = cutoff;
}
