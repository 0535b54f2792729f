#version 460
#extension GL_GOOGLE_include_directive : require
// variants: EXACT_PATHS
#ifdef EXACT_PATHS
#extension GL_EXT_ray_query : require
#define SPECULA_RAY_QUERY
#endif
// caustics.photons: the photon hit location image (survey §6.1.2, SKALP05/UPSK08). The
// generator is rasterised from the light; each texel is one photon that follows its path
// through the generator in the sampled geometry (§4): reflected by a mirror (or by a
// dielectric, in the layers of its reflected branch: caustic_paths=both), or refracted
// in, searched in the refractor map (§4.4, total internal reflection included) and
// refracted out, then searched in the generator's receiver distance map to its terminal
// hit, which is stored relative to its caustic cube's centre (the generator's reference point
// in cube-map space, UPSK08; the light in light space, SP07) with the
// photon's power: the light's intensity × the texel's solid angle (its area for a
// directional light) × the Fresnel transmittances along the path, and (w) the direction it
// arrives along (photon_direction_code, for the photon map's gather and the texture space's
// sides).
//
// EXACT_PATHS (caustic_paths=exact, survey §6.1.1): the photon is traced in the original
// geometry through ray queries (set 5) instead: the light's visibility by a shadow ray; at
// a solid dielectric generator its layer's branch — 0: refracted in and out (T·T), 1:
// reflected (R), k ≥ 2: refracted in, k − 1 internal reflections, refracted out (T·Rᵏ⁻¹·T),
// each interface weighted by its Fresnel factor (total internal reflection by 1, and a
// branch that would transmit there carries nothing); then every specular surface it meets
// (mirrors reflect, dielectrics transmit, or reflect totally) up to the recursion depth
// (caustic.exact_bounces, the depth knob, as the reference's photons), to the
// first diffuse hit.
#include "distance/refractor/trace.glsl"
#include "caustics/photon_map.glsl"

// KHR_materials_dispersion: a photon refracts as one channel, the same all along its
// path: chosen by its texel at the first dispersive surface it enters ((x + y) mod 3, so
// that each channel has a third of the photons), its power ×3 in that channel and 0 in
// the others. -1 until then. The splats resolve the channels' separate caustics; caustic
// triangles, spanned by neighbouring texels, average them.
int photon_channel = -1;

// The direction the photon of weight w refracts along at a surface of material m (split
// s), and its index there for the way out.
vec3 photon_refraction(Material m, SpecularSplit s, inout vec3 w) {
    if (!material_disperses(m)) return s.t;
    if (photon_channel < 0) {
        photon_channel = int((uint(gl_FragCoord.x) + uint(gl_FragCoord.y)) % 3u);
        vec3 mask = vec3(0.0);
        mask[photon_channel] = 3.0;
        w *= mask;
    }
    return s.tc[photon_channel];
}

float photon_ior(Material m) {
    return photon_channel >= 0 && material_disperses(m) ? m.nu[photon_channel] : material_ior(m);
}
#ifdef EXACT_PATHS
#include "raytrace/ray_query.glsl"


// The shading normal and material (and its index) at hit h of a ray along d.
void exact_surface(RayHit h, vec3 d, out vec3 n, out Material m, out uint material) {
    RqSurface s = rq_surface(h, d);
    n = s.n;
    material = s.material;
    m = materials[s.material];
}

// Graded media (survey §6.5): a photon inside one follows the curved path that the ray
// tracers' rays do (common/medium_march.glsl through ray queries).
RayHit rq_chord(vec3 o, vec3 d, float t_min, float t_max, uint skip) {
    return rq_trace(o, d, t_min, t_max, skip, false);
}
#define MEDIUM_TRACE rq_chord
#include "common/medium_march.glsl"

// The next surface a photon meets leaving pos along dir (off triangle skip): straight, or
// curved through the graded medium `medium` (its material + 1; 0: none), pos and dir then
// the last chord's. `len`: the path's length (absorption); no hit where it escapes or is lost.
RayHit photon_next(inout vec3 pos, inout vec3 dir, uint skip, uint medium, out float len) {
    if (medium == 0u) {
        RayHit h = rq_trace(pos, dir, caustic.ray_offset, RQ_T_MAX, skip, false);
        len = h.t * length(dir);
        return h;
    }
    MediumMarch r = medium_march(materials[medium - 1u], pos, dir, caustic.ray_offset, skip, caustic.medium_turn);
    pos = r.origin;
    dir = r.dir;
    len = r.before + r.hit.t;
    return r.lost ? RayHit(0.0, 0.0, 0.0, RAY_NO_TRIANGLE) : r.hit;
}

// The hit image's w for an exact photon landing on triangle `tri` of the scene's list: 1,
// or in texture space 2 + tri (the splats find its light-map coordinates there; exact in f32
// below 2²⁴ triangles, which the stage checks).
float exact_hit_code(uint tri) {
    return (caustic.flags & CAUSTIC_TEXTURE_SPACE) != 0u ? 2.0 + float(tri) : 1.0;
}

#endif

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_hit;
layout(location = 1) out vec4 out_power;

void main() {
    out_hit = vec4(0.0);
    out_power = vec4(0.0);
    Object o = objects[push.object];
    Material m = materials[o.material];
    uint cube = (push.flags >> CAUSTIC_CUBE_SHIFT) & 0xffu;
    Light l = lights[push.flags >> CAUSTIC_LIGHT_SHIFT];
    View v = views[in_view];
    vec3 p = in_position;
    // Where the photon comes from, and what it carries (light_irradiance's E times d² is
    // the intensity in this direction, spot cone and range window included).
    vec3 wi;
    float dist;
    vec3 e = light_irradiance(l, p, wi, dist);
    vec3 i = -wi;
    vec3 power;
    if (uint(l.direction_kind.w) == LIGHT_DIRECTIONAL) {
        power = e * v.dir.w;  // irradiance × the texel's area
    } else {
        float c = max(dot(i, v.dir.xyz), 0.0);
        power = e * dist * dist * v.dir.w * c * c * c;  // intensity × the texel's solid angle
    }
    vec3 n = normalize(in_normal);
    if (dot(n, i) > 0.0) n = -n;  // the side the photon arrives on
    uint branch = (push.flags >> CAUSTIC_BRANCH_SHIFT) & 0xfu;
#ifdef EXACT_PATHS
    float offset = caustic.ray_offset;
    // Occluders between the light and the generator: a shadow ray.
    bool directional = uint(l.direction_kind.w) == LIGHT_DIRECTIONAL;
    if (rq_trace(p, -i, offset, directional ? RQ_T_MAX : dist * (1.0 - 1e-6), RAY_NO_TRIANGLE, true).triangle != RAY_NO_TRIANGLE) return;
#else
    // Occluders between the light and the generator: the shadow map, offset towards the
    // light (not along the normal: at the silhouette, grazing, the generator would shadow
    // its own photons).
    power *= light_visibility(l, p, -i);
#endif
    if (all(lessThanEqual(power, vec3(0.0)))) return;

    SpecularSplit s = specular_split(m, p, n, p - i);
    vec3 centre = cubes[cube].centre.xyz;
    vec3 pos = p;
    vec3 dir;
    vec3 w;
#ifdef EXACT_PATHS
    uint skip = RAY_NO_TRIANGLE;
    // The graded medium the photon runs in (material + 1; 0: none): the generator's when it
    // is one and the photon enters it.
    uint medium = 0u;
    if (m.kind == KIND_MIRROR || branch == 1u) {
        dir = s.r;
        w = s.fr;
    } else if (m.thin != 0u) {
        dir = s.t;
        w = s.ft;
    } else {
        // Refracted in; branch k ≥ 2 reflects k − 1 times inside, then every branch leaves.
        if (all(lessThanEqual(s.ft, vec3(0.0)))) return;
        w = s.ft;
        dir = photon_refraction(m, s, w);
        medium = material_graded(m) ? o.material + 1u : 0u;
        uint reflections = branch == 0u ? 0u : branch - 1u;
        for (uint k = 0u; k <= reflections; ++k) {
            float len;
            RayHit h = photon_next(pos, dir, skip, medium, len);
            if (h.triangle == RAY_NO_TRIANGLE) return;  // an open object: no exit surface
            vec3 n2;
            Material m2;
            uint mi;
            exact_surface(h, dir, n2, m2, mi);
            pos += dir * h.t;
            if (m2.kind == KIND_DIFFUSE) {
                // A receiver inside the generator (a pool's floor under its water, §6.4):
                // branch 0's path ends there (T, then the floor); the others' are not theirs.
                if (k > 0u || branch != 0u) return;
                w *= volume_transmittance(m, len);  // absorbed in the generator on the way
                out_hit = vec4(pos - centre, exact_hit_code(h.triangle));
                out_power = vec4(w * power, photon_direction_code(dir));
                return;
            }
            w *= segment_transmittance(m2, n2, dir, len);  // absorbed inside
            skip = h.triangle;
            SpecularSplit s2 = specular_split(m2, pos, n2, pos - dir);
            if (k < reflections) {
                dir = s2.r;
                w *= s2.fr;
                medium = medium_after(mi, m2, n2, dir, true, medium);
            } else {
                if (all(lessThanEqual(s2.ft, vec3(0.0)))) return;  // totally reflected: another branch's
                w *= s2.ft;
                dir = photon_refraction(m2, s2, w);
                medium = medium_after(mi, m2, n2, dir, false, medium);
            }
        }
    }
    // On to the first diffuse surface, through every specular one on the way.
    for (uint bounce = 0u; bounce <= caustic.exact_bounces; ++bounce) {
        if (all(lessThan(w, vec3(1e-6)))) return;
        float len;
        RayHit h = photon_next(pos, dir, skip, medium, len);
        if (h.triangle == RAY_NO_TRIANGLE) return;  // escaped
        vec3 n2;
        Material m2;
        uint mi;
        exact_surface(h, dir, n2, m2, mi);
        w *= segment_transmittance(m2, n2, dir, len);  // absorbed inside a solid
        pos += dir * h.t;
        skip = h.triangle;
        if (m2.kind == KIND_DIFFUSE) {
            out_hit = vec4(pos - centre, exact_hit_code(h.triangle));
            out_power = vec4(w * power, photon_direction_code(dir));
            return;
        }
        SpecularSplit s2 = specular_split(m2, pos, n2, pos - dir);
        if (m2.kind != KIND_MIRROR && any(greaterThan(s2.ft * w, vec3(0.0)))) {
            w *= s2.ft;
            dir = photon_refraction(m2, s2, w);
            medium = medium_after(mi, m2, n2, dir, false, medium);
        } else {
            dir = s2.r;
            w *= s2.fr;
            medium = medium_after(mi, m2, n2, dir, true, medium);
        }
    }
    return;
#else
    if (m.kind == KIND_MIRROR || branch == 1u) {
        // A mirror reflects, and so does a dielectric in its reflected-branch layer.
        dir = s.r;
        w = s.fr;
    } else if (m.thin != 0u) {
        // A thin-walled dielectric lets the photon through undeviated.
        dir = s.t;
        w = s.ft;
    } else {
        // A solid dielectric: refracted in, then out where the refractor map says, or
        // reflected inside on total internal reflection; the internally reflected share of
        // a partial reflection is not followed (the stronger branch, 1 − F, is).
        if (all(lessThanEqual(s.ft, vec3(0.0)))) return;
        w = s.ft;
        dir = photon_refraction(m, s, w);
        float ior = photon_ior(m);
        // caustic_paths=surface (§6.4, water): the receivers lie inside the generator, the
        // photon goes on from its refraction at the surface.
        bool out_of_it = (caustic.flags & CAUSTIC_SURFACE_PATHS) != 0u;
        for (uint bounce = 0u; !out_of_it && bounce <= push_internal_bounces(); ++bounce) {
            vec3 hit, n2;
            if (!refractor_exit(o, pos, dir, hit, n2)) {  // an open refractor: the photon is out
                out_of_it = true;
                break;
            }
            vec3 out_dir;
            w *= volume_transmittance(m, length(hit - pos));  // absorbed on the way through
            pos = hit;
            if (refract_dir(dir, -n2, ior, out_dir)) {
                w *= 1.0 - material_fresnel(m, dot(dir, n2), 1.0 / ior);
                dir = out_dir;
                out_of_it = true;
                break;
            }
            dir = reflect_dir(dir, -n2);  // total internal reflection
        }
        if (!out_of_it) return;  // still inside after internal_bounces reflections
    }
    // The terminal hit on the receivers: the §4 search in the receiver distance map.
    search_map = 2;
    search_layer = float(cube);
    vec3 x = pos - centre;
    SearchResult h = search_ray(x, dir);
    if (h.escaped) {
        // No receiver: w −1 says so (caustics/reach.comp: its region has no bound); every
        // other pass takes only w > 0.
        out_hit = vec4(dir, -1.0);
        return;
    }
    if ((caustic.flags & CAUSTIC_SURFACE_PATHS) != 0u && m.kind == KIND_DIELECTRIC && m.thin == 0u && branch == 0u) {
        w *= volume_transmittance(m, h.d * length(dir));  // absorbed inside on the way there
    }
    // w: 1/(1 + the ray's length from where it left the generator), in (0, 1]: a photon
    // (w > 0), not an exact path's code (> 1.5); caustics/reach.comp recovers the length.
    out_hit = vec4(x + dir * h.d, 1.0 / (1.0 + h.d * length(dir)));
    out_power = vec4(w * power, photon_direction_code(dir));
#endif
}
