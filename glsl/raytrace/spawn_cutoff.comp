#version 460
#extension GL_GOOGLE_include_directive : require
// A queue budget's cuts (raytrace/trace.glsl): push.object = 2 · which + phase (which 0:
// the spawn budget and the next queue, 1: the shadow budget and the shadow queue). Phase 0:
// the heaviest weight bins whose rays all fit are kept, the first that does not is cut;
// phase 1: of the cut bin, the sub-bins that still fit.
layout(local_size_x = 1) in;
#include "raytrace/trace.glsl"

void cut(inout SpawnBudgetState b, uint capacity, uint phase) {
    if (phase == 0u) {
        b.kept = 0u;
        b.cutoff = SPAWN_BINS;
        for (uint k = 0u; k < SPAWN_BINS; ++k) {
            if (b.kept + b.hist[k] > capacity) {
                b.cutoff = k;
                return;
            }
            b.kept += b.hist[k];
        }
        return;
    }
    uint kept = b.kept;
    b.sub_cutoff = 0u;
    for (uint k = 0u; k < SPAWN_BINS && kept + b.sub[k] <= capacity; ++k) {
        kept += b.sub[k];
        b.sub_cutoff = k + 1u;
    }
}

void main() {
    uint which = push.object / 2u;
    uint phase = push.object % 2u;
    if (which == 0u) {
        SpawnBudgetState b = spawn_budget;
        cut(b, trace.capacity, phase);
        spawn_budget = b;
    } else {
        SpawnBudgetState b = shadow_budget;
        cut(b, trace.shadow_capacity, phase);
        shadow_budget = b;
    }
}
