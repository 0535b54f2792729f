#version 460
// layered.count: one surface more along this texel's ray (additive blending).
layout(location = 0) out float out_count;

void main() {
    out_count = 1.0;
}
