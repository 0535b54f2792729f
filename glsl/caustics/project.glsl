// caustics.project (survey §6.3.3): the caustic irradiance at a diffuse point, looked up in
// each caustic cube's light cube map in the point's direction from the cube's centre (a
// generator's reference point, or a light). The map holds radiant intensity J seen from there, so a receiver at distance D whose normal
// makes the angle α with that direction receives E = J cos α / D². The shadow-map-like
// distance test stops light leaks: the point takes the caustic only if it is the surface
// the receiver distance map holds in that direction. Receivers facing away from the
// generator (back faces) take none.
//
// caustics=photon-map gathers from the photon grid instead (caustics/photon_map.glsl).
#ifndef CAUSTICS_PROJECT_GLSL
#define CAUSTICS_PROJECT_GLSL
#ifdef CAUSTICS_PHOTON_MAP
// Only the variants of the passes that gather (caustics/project.frag, raytrace/shade.comp):
// the gather's k-nearest lists, in every diffuse shader, slowed other methods' frames on
// lavapipe even where the branch was never taken (tests/planner.rs measured it).
#include "caustics/photon_map.glsl"
#endif

// caustic_space=texture: the scene triangle (its index in the scene's list) the fragment being
// shaded lies on, set by CAUSTIC_TRIANGLE_HERE in the CAUSTICS_TEXTURE variants of the passes
// that draw the surface they shade (gl_PrimitiveID: the geometryShader feature, which texture
// space needs); none elsewhere, where caustic_irradiance then gives none.
const uint NO_CAUSTIC_TRIANGLE = 0xffffffffu;
uint caustic_triangle = NO_CAUSTIC_TRIANGLE;
#ifdef CAUSTICS_TEXTURE
#define CAUSTIC_TRIANGLE_HERE() caustic_triangle = floatBitsToUint(caustic_atlas[4u * push.object + 3u].x) + uint(gl_PrimitiveID)
#else
#define CAUSTIC_TRIANGLE_HERE()
#endif

vec3 caustic_texture_irradiance(uint tri, vec3 p, vec3 towards);

// n: the receiver's normal on the side it is seen from.
vec3 caustic_irradiance(vec3 p, vec3 n) {
    vec3 e = vec3(0.0);
    uint count = caustic.cube_count;
    if (count == 0u) return e;
#ifdef CAUSTICS_PHOTON_MAP
    if ((caustic.flags & CAUSTIC_PHOTON_MAP) != 0u) return photon_map_irradiance(p, n);
#else
    if ((caustic.flags & CAUSTIC_PHOTON_MAP) != 0u) return e;  // gathered by the camera's passes only
#endif
    // Screen space: only the camera's own surfaces (caustic_screen_irradiance) get caustics;
    // texture space: the surfaces whose triangle the pass knows.
    if ((caustic.flags & CAUSTIC_TEXTURE_SPACE) != 0u) {
        return caustic_triangle == NO_CAUSTIC_TRIANGLE ? e : caustic_texture_irradiance(caustic_triangle, p, n);
    }
    if ((caustic.flags & CAUSTIC_SCREEN_SPACE) != 0u) return e;
    float texel = 2.0 / float(caustic.cube_size);
    for (uint g = 0u; g < count; ++g) {
        vec3 w = p - cubes[g].centre.xyz;
        float d = length(w);
        if (!(d > 0.0)) continue;
        vec3 dir = w / d;
        float cos_a = -dot(n, dir);
        if (cos_a <= 0.0) continue;
        if ((caustic.flags & CAUSTIC_DISTANCE_TEST) != 0u) {
            // Within a texel the receiver's distance varies by about D·texel/cos α.
            float stored = textureLod(caustic_distances, vec4(dir, float(g)), 0.0).r;
            if (abs(d - stored) > d * texel * (2.0 + 1.0 / max(cos_a, 0.05))) continue;
        }
        vec3 j = textureLod(caustic_maps, vec4(dir, float(g)), 0.0).rgb;
        float cos_factor = (caustic.flags & CAUSTIC_ORIENTATION) != 0u ? cos_a : 1.0;
        e += j * cos_factor / (d * d);
    }
    return e;
}

// caustic_space=screen (LC04, WD06b): the caustic irradiance at the camera's pixel `pixel`
// of a surface of normal n seen along v (towards the eye, unit): caustics.screen holds it per
// unit area across the view, which a surface tilted by θ from the view spreads over 1/cos θ
// as much area.
vec3 caustic_screen_irradiance(ivec2 pixel, vec3 n, vec3 v) {
    return texelFetch(caustic_screen, pixel, 0).rgb * abs(dot(n, v));
}

// caustic_space=texture (SKALP05): world point p of triangle `tri` (its index in the scene's
// list) in its mesh's object space, then in the light map's coordinates of its chart
// (clamped into the chart), and the chart's normal in world space (src/methods/caustics/atlas.rs
// lays out caustic_atlas). `false` where the triangle is no receiver's.
bool caustic_texture_point(uint tri, vec3 p, out vec2 uv, out vec3 normal, out float texel_area) {
    uint base = caustic.atlas_meshes + 4u * tri;
    vec4 nm = caustic_atlas[base + 3u];
    uint h = 4u * floatBitsToUint(nm.w);
    vec4 rect = caustic_atlas[base + 2u];
    vec4 mesh = caustic_atlas[h + 3u];
    if (mesh.z == 0.0 || !(rect.z > rect.x)) return false;
    vec4 r0 = caustic_atlas[h], r1 = caustic_atlas[h + 1u], r2 = caustic_atlas[h + 2u];
    vec3 q = vec3(dot(r0.xyz, p) + r0.w, dot(r1.xyz, p) + r1.w, dot(r2.xyz, p) + r2.w);
    vec4 ru = caustic_atlas[base], rv = caustic_atlas[base + 1u];
    uv = clamp(vec2(dot(ru.xyz, q) + ru.w, dot(rv.xyz, q) + rv.w), rect.xy, rect.zw);
    // Normals go by the inverse transpose of the object's transform: the transpose of the
    // world-to-object rows.
    normal = r0.xyz * nm.x + r1.xyz * nm.y + r2.xyz * nm.z;
    texel_area = mesh.y;
    return true;
}

// caustic_space=texture: the irradiance of the light map at point p of triangle `tri`,
// seen from the side `towards` points to (from p to the eye, or back along the ray). The
// map's alpha holds the signed sum of r + g + b (+ where the photons arrived on the chart's
// front), so a thin receiver's two sides, one texel of the map, keep their own light.
vec3 caustic_texture_irradiance(uint tri, vec3 p, vec3 towards) {
    vec2 uv;
    vec3 normal;
    float area;
    if (caustic.cube_count == 0u || !caustic_texture_point(tri, p, uv, normal, area)) return vec3(0.0);
    vec4 e = textureLod(caustic_light_map, uv, 0.0);
    float sum = e.r + e.g + e.b;
    if (!(sum > 0.0)) return vec3(0.0);
    float side = dot(towards, normal) >= 0.0 ? 1.0 : -1.0;
    return e.rgb * clamp(0.5 + 0.5 * side * e.a / sum, 0.0, 1.0);
}
#endif
