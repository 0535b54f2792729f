// Recursive ray tracing in a layered distance map (survey §4.5, UPSK07): the ray is
// searched in every layer with the combined linear + secant search (layer_search in
// common/search.glsl), the nearest hit over the layers wins; a diffuse texel gives its
// radiance, a specular one continues the ray, reflected and refracted with Fresnel weights,
// up to the recursion depth. Self reflections of concave mirrors, internal reflections in
// non-convex glass and inter-object reflections all come from this one loop.
#ifndef LAYERED_TRACE_GLSL
#define LAYERED_TRACE_GLSL
#include "common/specular.glsl"
#include "common/sky.glsl"

int layered_layer = 0;
// Whether a path met a surface in the last layer (the farthest surface, where the peel is
// cut; layered/search.frag's COUNT_FAR counts such pixels).
bool layered_met_last = false;

float layered_distance(vec3 dir) {
    return textureLod(layered_maps, vec4(dir, float(layered_layer)), 0.0).a;
}
#define SEARCH_DISTANCE(dir) layered_distance(dir)
#include "common/search.glsl"

struct LayeredHit {
    bool escaped;
    int layer;
    vec3 dir;   // direction from the reference point of the hit texel
    float d;    // ray parameter
};

// The nearest hit of the ray x + R·d (x relative to the map's reference point) over the
// layers. The ray leaves a surface of normal n (zero: none): the layer that holds that
// surface (the one whose distance at x is nearest |x|, within LAYERED_GAP) is told on
// which side of it the ray leaves, so that the search does not find the origin again.
LayeredHit layered_hit(vec3 x, vec3 R, vec3 n) {
    int layers = textureSize(layered_maps, 0).z;
    float len_x = length(x);
    int origin = -1;
    float best = LAYERED_GAP;
    if (dot(n, n) > 0.0 && len_x > 0.0) {
        for (int k = 0; k < layers; ++k) {
            layered_layer = k;
            float s = layered_distance(x);
            if (search_is_sky(s)) continue;
            float r = abs(len_x / s - 1.0);
            if (r < best) { best = r; origin = k; }
        }
    }
    int side = dot(R, n) * dot(x, n) > 0.0 ? 1 : -1;
    LayeredHit h;
    h.escaped = true;
    h.layer = 0;
    h.dir = R;
    h.d = 1e30;
    int steps = max(int(push_search_linear_steps()), 1);
    for (int k = 0; k < layers; ++k) {
        layered_layer = k;
        SearchResult s = layer_search(x, R, steps, int(push_search_binary_steps()), int(push_search_secant_steps()), push_search_tolerance(),
                                      LAYERED_GAP, k == origin ? side : 0, h.d);
        if (!s.escaped && s.d < h.d) {
            h.escaped = false;
            h.layer = k;
            h.dir = s.dir;
            h.d = s.d;
        }
    }
    return h;
}

struct LayeredRay {
    vec3 origin;
    vec3 dir;
    vec3 normal;  // of the surface it leaves
    vec3 weight;
    uint left;    // specular bounces it may still take
};

// Branches below this path weight in every channel are not followed (the reference's
// MIN_PATH_WEIGHT).
const float LAYERED_MIN_WEIGHT = 1e-6;

LayeredRay layered_stack[LAYERED_STACK];
int layered_top = 0;

void layered_push(vec3 p, vec3 dir, vec3 n, vec3 w, uint left) {
    if (max(w.r, max(w.g, w.b)) < LAYERED_MIN_WEIGHT || layered_top >= int(LAYERED_STACK)) return;
    layered_stack[layered_top] = LayeredRay(p, dir, n, w, left);
    layered_top++;
}

// The children of a specular surface hit (material m) with weight w: both Fresnel branches
// while the stack has room for both (and layered_branches=both), else the stronger one
// carrying the weight of both. Under dispersion the refracted branch is one per channel
// (each carrying its channel; a ray that carries one channel makes one), where the stack
// has room for them; the stronger-branch mode refracts all three along the d line's.
void layered_branch(Material m, SpecularSplit s, vec3 p, vec3 n, vec3 w, uint left) {
    bool refracts = any(greaterThan(s.ft, vec3(0.0)));
    bool disperses = material_disperses(m);
    bool both = (push.flags & FLAG_LAYERED_STRONGEST) == 0u && layered_top + (disperses ? 4 : 2) <= int(LAYERED_STACK);
    if (!refracts) {
        layered_push(p, s.r, n, w * s.fr, left);
    } else if (both) {
        if (disperses) {
            for (int k = 0; k < 3; ++k) {
                layered_push(p, s.tc[k], n, w * s.ft * channel_mask(k), left);
            }
        } else {
            layered_push(p, s.t, n, w * s.ft, left);
        }
        layered_push(p, s.r, n, w * s.fr, left);
    } else {
        bool t = dot(s.ft, vec3(1.0)) > dot(s.fr, vec3(1.0));
        layered_push(p, t ? s.t : s.r, n, w * (s.fr + s.ft), left);
    }
}

// Radiance reaching the eye from the specular surface point p (normal n, material m) of an
// object whose map's reference point is `centre`, with `left` more specular bounces.
vec3 layered_radiance(vec3 centre, Material m, vec3 p, vec3 n, vec3 eye, uint left) {
    layered_top = 0;
    layered_branch(m, specular_split(m, p, n, eye), p, n, vec3(1.0), left);
    vec3 c = vec3(0.0);
    while (layered_top > 0) {
        layered_top--;
        LayeredRay r = layered_stack[layered_top];
        LayeredHit h = layered_hit(r.origin - centre, r.dir, r.normal);
        if (h.escaped) {
            c += r.weight * sky_radiance(r.dir);
            continue;
        }
        layered_met_last = layered_met_last || h.layer == textureSize(layered_maps, 0).z - 1;
        vec4 texel = textureLod(layered_maps, vec4(h.dir, float(h.layer)), 0.0);
        vec4 surface = textureLod(layered_normals, vec4(h.dir, float(h.layer)), 0.0);
        if (surface.w < 0.5) {
            c += r.weight * texel.rgb;
            continue;
        }
        if (r.left == 0u) continue;  // still specular after R bounces: black, as the reference
        Material hm = materials[uint(surface.w + 0.5) - 1u];
        vec3 q = r.origin + r.dir * h.d;
        vec3 hn = normalize(surface.xyz);
        vec3 w = r.weight * segment_transmittance(hm, hn, r.dir, h.d * length(r.dir));  // absorbed inside a solid
        layered_branch(hm, specular_split(hm, q, hn, q - r.dir), q, hn, w, r.left - 1u);
    }
    return c;
}
#endif
