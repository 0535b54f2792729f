#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// caustics.splat: photon splatting (survey §6.3.1). One quad per texel of the photon hit
// location image (layer push.object), placed by this shader from the image: no readback.
// Drawn into each face of the generator's light cube map (view push.view + gl_ViewIndex:
// the face's view around the cube's centre), so a splat near an edge reaches both faces.
#include "common/scene.glsl"

layout(location = 0) out vec2 out_offset;
layout(location = 1) flat out vec3 out_scale;

const vec2 CORNERS[6] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));

void main() {
    uint n = caustic.photon_size;
    uint photon = uint(gl_VertexIndex) / 6u;
    ivec3 tc = ivec3(int(photon % n), int(photon / n), int(push.object));
    vec4 hit = texelFetch(photon_hits, tc, 0);
    vec3 power = texelFetch(photon_power, tc, 0).rgb;
    View v = views[push.view + gl_ViewIndex];
    vec4 c = v.view_proj * vec4(v.eye.xyz + hit.xyz, 1.0);
    vec2 corner = CORNERS[uint(gl_VertexIndex) % 6u];
    out_offset = corner;
    if (hit.w == 0.0 || c.w <= 0.0 || all(lessThanEqual(power, vec3(0.0)))) {
        out_scale = vec3(0.0);
        gl_Position = vec4(0.0, 0.0, 0.0, -1.0);  // outside every clip volume: no quad
        return;
    }
    // The kernel covers r texels around the hit; each texel it covers gets the share
    // K(u)/r² of the photon's power, as radiant intensity over the texel's solid angle
    // (2/N)²·(|major axis|/|d|)³ at the hit's direction d.
    float size = float(caustic.cube_size);
    float r = caustic.splat_size;
    vec3 d = abs(hit.xyz);
    float major = max(d.x, max(d.y, d.z));
    float solid = (4.0 / (size * size)) * pow(major / length(hit.xyz), 3.0);
    out_scale = power / (r * r * solid);
    gl_Position = c + vec4(corner * (2.0 * r / size) * c.w, 0.0, 0.0);
}
