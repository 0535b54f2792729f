#version 460
#extension GL_GOOGLE_include_directive : require
// MSAA: runs per sample (gl_SampleID makes the pass sample-rate) and writes that sample's
// own ray's radiance (raytrace/resolve.glsl).
#include "raytrace/resolve.glsl"

void main() {
    resolve(uint(gl_SampleID));
}
