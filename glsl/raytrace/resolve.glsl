// Writes the traced radiance of the pixels this stage renders into the frame's target
// (64-bit fixed-point sums → float); other pixels keep what earlier passes drew. Sample s
// of the pixel: its own ray's radiance with MSAA (resolve_samples.frag), 0 without.
#ifndef RAYTRACE_RESOLVE_GLSL
#define RAYTRACE_RESOLVE_GLSL
#include "raytrace/trace.glsl"

layout(location = 0) out vec4 colour;

void resolve(uint s) {
    ivec2 xy = ivec2(gl_FragCoord.xy);
    uint id = imageLoad(visibility, ivec3(xy, s)).r;
    if (id == RAY_NO_TRIANGLE || handled[floatBitsToUint(shading[id].uv2.z)] == 0u) discard;
    uint i = 6u * ((uint(xy.y) * trace.width + uint(xy.x)) * trace.samples + s);
    vec3 c;
    for (uint k = 0u; k < 3u; ++k) {
        c[k] = (float(accum[i + 2u * k + 1u]) * 4294967296.0 + float(accum[i + 2u * k])) / ACCUM_SCALE;
    }
    colour = vec4(c, 1.0);
}
#endif
