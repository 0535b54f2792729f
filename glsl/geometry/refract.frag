#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE COUNT_FALLBACKS COUNT_FALLBACKS_PER_SAMPLE
#ifdef COUNT_FALLBACKS_PER_SAMPLE
#define COUNT_FALLBACKS
#define PER_SAMPLE
#endif
// geometry.refract: a flat-faced dielectric (survey §5, GS04/Sch03), or a thin-walled
// pane. Each face the view sees has up to two child views, laid onto the face's own
// pixels: its reflection (the view mirrored through the face, exact) and its refraction
// (the view through the face, by the linearised refraction of the eye ray: an affine map
// per face that is exact for the face's central ray; a pane's is exact, it transmits
// undeviated). From inside the solid, the faces are seen from within: internal
// reflections and the refraction out. The Fresnel split is the pixel's own, at its eye
// ray's incidence (total internal reflection included). A branch whose view the budget left
// out continues in the object's own maps where the plan gave it them (its views can be cut
// by the budget, src/methods/geometry/mod.rs): outside, traced in its distance map (§4.1);
// inside a solid, through its refractor map (§4.4) as refractor-map traces it. At the
// recursion depth (FLAG_MIRROR_DEPTH_END), or without the maps, the environment along that
// branch's ray (where the reference's paths end).
#include "common/specular.glsl"
#include "common/sky.glsl"
#include "distance/refractor/trace.glsl"

// Radiance along a branch (p, dir) the views left out: `inside` the solid or not.
vec3 fallback(Object o, Material m, vec3 p, vec3 dir, bool inside) {
    if (o.envmap_layer < 0 || (push.flags & FLAG_MIRROR_DEPTH_END) != 0u) return sky_radiance(dir);
    if (inside && o.refractor_layer >= 0) return refractor_inside(o, m, p, dir, vec3(1.0), vec3(0.0));
    return traced_radiance(o, p, dir);
}

#ifdef COUNT_FALLBACKS
// Fallbacks are counted per fragment that survives the depth test (geometry.fallback_pixels).
layout(early_fragment_tests) in;
#define COUNT_FALLBACK() atomicAdd(fallbacks[push.object], 1u)
#else
#define COUNT_FALLBACK()
#endif
layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 eye = views[in_view].eye.xyz;
    vec3 n = normalize(in_normal);
    SpecularSplit s = specular_split(m, in_position, n, eye);
    // The eye inside the solid (a view through one of its faces): the reflection stays
    // inside, the refraction leaves; outside, the other way round. The interpolated normal
    // points out.
    bool eye_inside = dot(n, eye - in_position) < 0.0;
    bool solid = o.refractor_layer >= 0;
    vec3 reflected = fallback(o, m, in_position, s.r, eye_inside && solid);
    vec3 refracted = any(greaterThan(s.ft, vec3(0.0))) ? fallback(o, m, in_position, s.t, !eye_inside && solid) : vec3(0.0);
    // Absorption inside the solid (KHR_materials_volume). A view from inside looks through
    // one of its faces, its clip plane: the eye ray's part from that plane to this point
    // ran inside (the length the mirrored view preserves; the refracted view's affine map
    // keeps it exactly along its central ray), so everything this pixel shows is absorbed
    // over it, and views nested in views multiply their segments up. A branch into the
    // solid that no view follows is absorbed by its fallback: the refractor map traces the
    // inside, the environment takes the chord through the object's bounds.
    vec3 absorbed = vec3(1.0);
    View here = views[in_view];
    float across = dot(here.clip.xyz, in_position - eye);
    if (eye_inside && m.thin == 0u && abs(across) > 0.0) {
        float enters = -(dot(here.clip.xyz, eye) + here.clip.w) / across;  // where the eye ray crosses the face
        absorbed = volume_transmittance(m, max(1.0 - enters, 0.0) * length(in_position - eye));
    }
    bool fallback_absorbs = !eye_inside && solid && o.envmap_layer >= 0 && (push.flags & FLAG_MIRROR_DEPTH_END) == 0u;
    if (!fallback_absorbs && !eye_inside) refracted *= chord_transmittance(o, m, in_position, n, s.t);
    // Which branches a child view serves: the others took the fallback.
    bool viewed_r = false, viewed_t = false;
    if ((push.flags & FLAG_MIRROR_VIEW) != 0u) {
        // The face's plane, towards the eye; its child views keep that side (reflection)
        // or the other (refraction), `dir.w` beyond the plane.
        vec3 towards = dot(n, eye - in_position) >= 0.0 ? n : -n;
        // Positions interpolated at a sample (PER_SAMPLE) rather than the pixel centre
        // were measured off the face's plane by ~25 hairs on lavapipe (a quarter of a
        // pixel's footprint at most): the plane test allows a quarter footprint too.
        float slack = 0.25 * length(fwidth(in_position));
        uint first = (push.flags >> MIRROR_LAYER_SHIFT) & 0xffu;
        uint count = push.flags >> MIRROR_COUNT_SHIFT;
        for (uint i = 0u; i < count; ++i) {
            uint layer = first + i;
            View c = views[push_extra_view_base() + layer];
            float facing = dot(c.clip.xyz, towards);
            float offset = abs(dot(c.clip.xyz, in_position) + c.clip.w);
            // Its plane: the normals agree and the pixel lies `hair` from the clip plane
            // (within a few hairs for the rounding of the interpolated position).
            if (abs(abs(facing) - 1.0) > 1e-3 || offset > 4.0 * c.dir.w + slack) {
                continue;
            }
            vec3 texel = texelFetch(mirror_views, ivec3(ivec2(gl_FragCoord.xy), int(layer)), 0).rgb;
            if (facing > 0.0) {
                reflected = texel;
                viewed_r = true;
            } else {
                refracted = texel;
                viewed_t = true;
            }
        }
    }
    // The image's own fragments (not the views') whose branch the budget cut.
    bool maps = o.envmap_layer >= 0 && (push.flags & FLAG_MIRROR_DEPTH_END) == 0u && push.view < push_extra_view_base();
    if (maps && (!viewed_r || (!viewed_t && any(greaterThan(s.ft, vec3(0.0)))))) COUNT_FALLBACK();
    out_color = vec4(absorbed * (s.fr * reflected + s.ft * refracted), 1.0);
}
