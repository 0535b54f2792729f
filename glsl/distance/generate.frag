#version 460
#extension GL_GOOGLE_include_directive : require
// variants: INTER_OBJECT PLANAR CAUSTICS_TEXTURE INTER_OBJECT_TEXTURE PLANAR_TEXTURE PLANAR_INTER_OBJECT PLANAR_INTER_OBJECT_TEXTURE
// distance.generate: a distance map (survey §4): radiance and the Euclidean distance from
// the reference point (not window-space z); also image-based reflections' captures (§3.3)
// and (PLANAR: the depth along an orthographic view's direction) displacement-mapped
// proxies' height maps (§3.2). Specular objects other than the map's owner
// reflect the environment map, or, in inter-object mode (§4.3), are shaded by their own
// method from their maps of the previous cycle: searched in their distance map, or self
// refracted in their refractor map (§4.4). The inter-object paths are compiled only into
// the INTER_OBJECT variant, which the frames that run inter-object cycles use: the other
// maps see the environment map alone, and their pipeline compiles in a small part of the
// time (the searches of every other object's maps are most of the shader). The *_TEXTURE
// variants (caustic_space=texture) also read the receivers' light map at the fragment's triangle.
// Image-based captures and relief height maps of a plan with inter-object cycles take the
// INTER_OBJECT variants too, drawn after the cycles from the last one's distance maps.
#if defined(INTER_OBJECT_TEXTURE)
#define INTER_OBJECT
#define CAUSTICS_TEXTURE
#elif defined(PLANAR_TEXTURE)
#define PLANAR
#define CAUSTICS_TEXTURE
#elif defined(PLANAR_INTER_OBJECT_TEXTURE)
#define PLANAR
#define INTER_OBJECT
#define CAUSTICS_TEXTURE
#elif defined(PLANAR_INTER_OBJECT)
#define PLANAR
#define INTER_OBJECT
#endif
#include "distance/refractor/trace.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_radiance_distance;

void main() {
    CAUSTIC_TRIANGLE_HERE();
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 n = normalize(in_normal);
    vec3 eye = views[in_view].eye.xyz;
    vec3 c;
    if (m.kind == KIND_DIFFUSE) {
        c = shade_diffuse(m, in_position, n, eye, in_uv);
    } else {
        SpecularSplit s = specular_split(m, in_position, n, eye);
#ifdef INTER_OBJECT
        o = as_shown(o);
        bool inter = (push.flags & FLAG_INTER_OBJECT) != 0u && o.map_shading != MAP_SHADING_SKY;
        if (inter && (push.flags & FLAG_FIRST_CYCLE) != 0u) {
            c = vec3(0.0);
        } else if (inter && o.map_shading == MAP_SHADING_REFRACTOR) {
            c = refractor_radiance(o, m, in_position, n, eye);
        } else {
            c = s.fr * (inter ? traced_radiance(o, in_position, s.r) : sky_radiance(s.r));
            vec3 refracted;
            REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, n, dir) * (inter ? traced_radiance(o, in_position, dir) : sky_radiance(dir)));
            c += refracted;
        }
#else
        c = s.fr * sky_radiance(s.r);
        vec3 refracted;
        REFRACTED_RADIANCE(refracted, m, s, chord_transmittance(o, m, in_position, n, dir) * sky_radiance(dir));
        c += refracted;
#endif
    }
#ifdef PLANAR
    // Planar views (displacement-mapped proxies' height maps, envmap/relief.frag) store the
    // depth along their direction.
    out_radiance_distance = vec4(c, dot(in_position - eye, views[in_view].dir.xyz));
#else
    out_radiance_distance = vec4(c, length(in_position - eye));
#endif
}
