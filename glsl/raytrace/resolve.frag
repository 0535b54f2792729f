#version 460
#extension GL_GOOGLE_include_directive : require
// One ray per pixel: its radiance into the frame's target (raytrace/resolve.glsl).
#include "raytrace/resolve.glsl"

void main() {
    resolve(0u);
}
