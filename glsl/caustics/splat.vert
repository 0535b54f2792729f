#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_multiview : require
// variants: SCREEN TEXTURE
// caustics.splat: photon splatting (survey §6.3.1). One quad per texel of the photon hit
// location image (layer push.object), placed by this shader from the image: no readback.
// Drawn into each face of the generator's light cube map (view push.view + gl_ViewIndex:
// the face's view around the cube's centre), so a splat near an edge reaches both faces.
//
// SCREEN (caustic_space=screen, LC04/WD06b): into the camera's view (push.view; push.flags:
// the layer's caustic cube, whose centre the hits are stored from), as irradiance per unit
// area across the view at the photon's depth: the screen's pixel there spans px × py, so a
// splat of r pixels spreads the power over r² px py. The quad lies nudged towards the camera
// by two pixels' width, so that a photon on the surface the camera sees passes the depth
// test of caustics/screen_depth.frag's depth, and one behind it does not.
//
// TEXTURE (caustic_space=texture, SKALP05): into the receivers' light map (push.flags: the
// layer's caustic cube) at the light-map coordinates of the receiver triangle the photon
// landed on — an exact photon's in its hit's w (2 + its index in the scene's list), a
// sampled one's from the receiver triangles its cube sees in its direction — as irradiance:
// a splat of r texels spreads the power over r² texels of the receiver's texel area. Alpha
// carries the signed sum of the channels (+ where the photon arrived on the chart's front).
#include "common/scene.glsl"
#ifdef TEXTURE
#include "caustics/project.glsl"
#include "caustics/photon_map.glsl"
#endif

layout(location = 0) out vec2 out_offset;
layout(location = 1) flat out vec4 out_scale;

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
#if defined(TEXTURE)
    vec4 packed = texelFetch(photon_power, tc, 0);
    uint cube = push.flags;
    float id = hit.w > 1.5 ? hit.w - 1.0 : textureLod(caustic_receiver_ids, vec4(hit.xyz, float(cube)), 0.0).r;
    vec2 uv;
    vec3 normal;
    float area;
    bool lands = hit.w > 0.0 && id >= 1.0 && id < 16777217.0 && any(greaterThan(power, vec3(0.0)))
              && caustic_texture_point(uint(id) - 1u, cubes[cube].centre.xyz + hit.xyz, uv, normal, area) && area > 0.0;
    if (!lands) {
        out_scale = vec4(0.0);
        gl_Position = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    // The splat covers what splat_size light-cube texels cover at the photon's distance from
    // the cube's centre (the same kernel as in cube space: far photons, sparser, spread
    // wider), in light-map texels: at least one (so that it reaches a texel's centre), at
    // most TEXTURE_SPLAT_MAX (the atlas's gutter keeps that off the neighbouring chart).
    float texel = sqrt(area);
    float r = clamp(caustic.splat_size * 2.0 * length(hit.xyz) / (float(caustic.cube_size) * texel), 1.0, TEXTURE_SPLAT_MAX);
    float front = dot(photon_direction(packed.w), normal) < 0.0 ? 1.0 : -1.0;
    out_scale = vec4(power, front * (power.r + power.g + power.b)) / (r * r * area);
    gl_Position = vec4(uv * 2.0 - 1.0 + corner * (2.0 * r / float(caustic.light_map_size)), 0.0, 1.0);
#elif defined(SCREEN)
    vec3 p = cubes[push.flags].centre.xyz + hit.xyz;
    vec4 clip = v.view_proj * vec4(p, 1.0);
    if (!(hit.w > 0.0) || clip.w <= 0.0 || all(lessThanEqual(power, vec3(0.0)))) {
        out_scale = vec4(0.0);
        gl_Position = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    vec2 screen = vec2(float(caustic.screen_width), float(caustic.screen_height));
    vec3 ndc = clip.xyz / clip.w;
    vec4 a = v.inv_view_proj * vec4(ndc.xy + vec2(2.0 / screen.x, 0.0), ndc.z, 1.0);
    vec4 b = v.inv_view_proj * vec4(ndc.xy + vec2(0.0, 2.0 / screen.y), ndc.z, 1.0);
    float px = length(a.xyz / a.w - p);
    float py = length(b.xyz / b.w - p);
    float r = caustic.splat_size;
    out_scale = vec4(power / (r * r * px * py), 0.0);
    vec4 near = v.view_proj * vec4(p + normalize(v.eye.xyz - p) * 2.0 * max(px, py), 1.0);
    gl_Position = vec4((ndc.xy + corner * (2.0 * r / screen)) * near.w, near.z, near.w);
#else
    if (!(hit.w > 0.0) || c.w <= 0.0 || all(lessThanEqual(power, vec3(0.0)))) {
        out_scale = vec4(0.0);
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
    out_scale = vec4(power / (r * r * solid), 0.0);
    gl_Position = c + vec4(corner * (2.0 * r / size) * c.w, 0.0, 0.0);
#endif
}
