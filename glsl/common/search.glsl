// Ray tracing in a distance map (survey §4.1): the ray x + R·d, with x relative to the
// map's reference point and |R| = 1, is intersected with the surface the map samples.
// Twin of src/search.rs: same names, same steps.
//
// The including shader defines SEARCH_DISTANCE(dir): the stored Euclidean distance of the
// surface seen from the reference point in direction `dir` (a cube-map lookup).
// A probe at ray parameter d compares |l| with |l'| for l = x + R·d: |l| < |l'| is an
// undershooting, |l| > |l'| an overshooting (§4.1).
#ifndef SEARCH_GLSL
#define SEARCH_GLSL

// Stored distances at or beyond this are "nothing there": the environment at infinity.
const float SEARCH_SKY = 1e19;

struct SearchResult {
    float d;        // ray parameter of the hit (when !escaped)
    vec3 dir;       // direction, from the reference point, whose texel holds the hit
    bool escaped;   // no surface: the ray leaves to the environment at infinity
    int lookups;    // distance-map fetches spent
};

bool search_is_sky(float stored) {
    return !(stored < SEARCH_SKY);  // also true for +inf and NaN
}

// |l| / |l'| at ray parameter d: < 1 undershoots, > 1 overshoots. A probe at the reference
// point itself undershoots whatever is stored.
float search_ratio(vec3 x, vec3 R, float d, inout int lookups) {
    vec3 l = x + R * d;
    float len = length(l);
    if (len <= 0.0) return 0.0;
    lookups++;
    float stored = SEARCH_DISTANCE(l);
    if (search_is_sky(stored)) return 0.0;
    return len / max(stored, 1e-30);
}

SearchResult search_result(vec3 x, vec3 R, float d, bool escaped, int lookups) {
    SearchResult r;
    r.d = d;
    r.escaped = escaped;
    r.dir = escaped ? R : x + R * d;
    if (!escaped && dot(r.dir, r.dir) <= 0.0) r.dir = R;
    r.lookups = lookups;
    return r;
}

// Parallax correction (survey eq. 4): assume the surface at r (hit in direction R) is
// perpendicular to the ray, d_p = |r| − R·x; iterated, each step assumes the plane through
// the surface point in the direction of the previous guess (§4.1.1).
SearchResult parallax_search(vec3 x, vec3 R, int iterations) {
    int lookups = 1;
    float stored = SEARCH_DISTANCE(R);
    if (search_is_sky(stored)) return search_result(x, R, 0.0, true, lookups);
    float d = max(stored - dot(R, x), 0.0);
    for (int k = 1; k < iterations; ++k) {
        vec3 l = x + R * d;
        float len = length(l);
        if (len <= 0.0) break;
        lookups++;
        float s = SEARCH_DISTANCE(l);
        if (search_is_sky(s)) break;
        d = max(dot(R, l / len) * s - dot(R, x), 0.0);
    }
    return search_result(x, R, d, false, lookups);
}

// The ray's end at infinity, seen in direction R with something there (far_stored): the
// parallax estimate of it (§4.1.3: pairing the ray's end with parallax correction), pushed
// out until it overshoots; the pushes move the undershooting end (d_l, a_l) along. False:
// it never overshoots (the ray escapes).
bool search_far_end(vec3 x, vec3 R, float far_stored, inout float d_l, inout float a_l, out float d, out float a, inout int lookups) {
    float len_x = length(x);
    d = max(far_stored - dot(R, x), d_l);
    a = search_ratio(x, R, d, lookups);
    for (int k = 0; k < 8 && a < 1.0; ++k) {
        d_l = d;
        a_l = a;
        d = 2.0 * d + len_x + far_stored;
        a = search_ratio(x, R, d, lookups);
    }
    return a >= 1.0;
}

// Refinement of a bracket (d_l, a_l), (d_p, a_p) whose ratios lie on either side of 1:
// `binary_steps` halvings (§4.1.4), then `secant_steps` false-position steps (survey eq. 5:
// the ray meets the segment between the overshooting and the undershooting surface
// points). A probe within tolerance is the answer, else it replaces the bracket end on its
// side. Returns the ray parameter found, or the better end of the final bracket.
float search_refine(vec3 x, vec3 R, inout float d_l, inout float a_l, inout float d_p, inout float a_p,
                    int binary_steps, int secant_steps, float tolerance, inout int lookups) {
    for (int i = 0; i < binary_steps + secant_steps; ++i) {
        float den = a_p - a_l;
        float d = i < binary_steps ? 0.5 * (d_l + d_p) : d_l + (d_p - d_l) * (1.0 - a_l) / (abs(den) > 1e-30 ? den : 1e-30);
        float a = search_ratio(x, R, d, lookups);
        if (abs(a - 1.0) <= tolerance) return d;
        if ((a < 1.0) == (a_l < 1.0)) { d_l = d; a_l = a; } else { d_p = d; a_p = a; }
    }
    return abs(a_l - 1.0) < abs(a_p - 1.0) ? d_l : d_p;
}

// Two-level search: linear search for the first undershoot/overshoot pair, marching
// uniformly on the segment between the projections of the ray's start and end on the unit
// sphere, d(t) = |x|/|R| · t/(1−t) (§4.1.2); then `binary_steps` halvings (§4.1.4) and
// `secant_steps` false-position steps (survey eq. 5, §4.1.3), stopping once |l|/|l'| is
// within `tolerance` of 1.
SearchResult linear_search(vec3 x, vec3 R, int steps, int binary_steps, int secant_steps, float tolerance) {
    int lookups = 0;
    float len_x = length(x);
    // A ray from the reference point: the map answers it exactly. Off it, an empty far end
    // does not end the search: the ray may meet a surface on the way.
    float far_stored = SEARCH_DISTANCE(R);
    lookups++;
    if (len_x <= 0.0 || (!search_is_sky(far_stored) && len_x <= 1e-6 * far_stored)) {
        if (search_is_sky(far_stored)) return search_result(x, R, 0.0, true, lookups);
        return search_result(x, R, far_stored, false, lookups);
    }
    float d_l = 0.0;
    float a_l = search_ratio(x, R, 0.0, lookups);
    if (a_l >= 1.0) return search_result(x, R, 0.0, false, lookups);  // starts behind the surface
    float d_p = -1.0;
    float a_p = 0.0;
    steps = max(steps, 1);
    for (int i = 1; i <= steps; ++i) {
        float d, a;
        if (i < steps) {
            float t = float(i) / float(steps);
            d = len_x * t / (1.0 - t);
            a = search_ratio(x, R, d, lookups);
        } else {
            // t = 1 is the ray's end at infinity, seen in direction R. If something is
            // there, bracket with the parallax estimate of it (§4.1.3: pairing the ray's end
            // with parallax correction), pushed out until it overshoots.
            if (search_is_sky(far_stored) || !search_far_end(x, R, far_stored, d_l, a_l, d, a, lookups))
                return search_result(x, R, 0.0, true, lookups);
        }
        if (abs(a - 1.0) <= tolerance) return search_result(x, R, d, false, lookups);
        if (a > 1.0) {
            d_p = d;
            a_p = a;
            break;
        }
        d_l = d;
        a_l = a;
    }
    if (d_p < 0.0) return search_result(x, R, 0.0, true, lookups);
    return search_result(x, R, search_refine(x, R, d_l, a_l, d_p, a_p, binary_steps, secant_steps, tolerance, lookups), false, lookups);
}

// One layer of a multi-layer map (survey §4.5, UPSK07): SEARCH_DISTANCE reads that layer.
// A ray may start anywhere (in front of the layer's surface or behind it) and cross it
// either way, so the linear search looks for the first sign change of |l|/|l'| − 1 on the
// same projected-segment steps; `start_side` (+1 behind, −1 in front, 0 measure it) says
// on which side the ray leaves when it starts on this layer's surface. A bracket is a hit
// only where the ray meets the surface: the refined point, or else the false-position
// point of the final bracket, must be within `gap` of it (else the bracket spans the gap
// between two surfaces of the layer, a silhouette, and the march goes on). Not escaped:
// `d` is the hit. `bound`: the nearest hit the other layers gave (1e30: none); the march
// stops at the first step beyond it, whose brackets could give only farther hits.
SearchResult layer_search(vec3 x, vec3 R, int steps, int binary_steps, int secant_steps, float tolerance, float gap, int start_side,
                          float bound) {
    int lookups = 0;
    float len_x = length(x);
    float far_stored = SEARCH_DISTANCE(R);
    lookups++;
    // (A sparse layer is empty in many directions: an empty far end does not end the march.)
    if (len_x <= 0.0 || (!search_is_sky(far_stored) && len_x <= 1e-6 * far_stored)) {
        // From the reference point the layer answers exactly (its own surface excluded).
        if (search_is_sky(far_stored) || start_side != 0) return search_result(x, R, 0.0, true, lookups);
        return search_result(x, R, far_stored, false, lookups);
    }
    float d_l = 0.0;
    float a_l = search_ratio(x, R, 0.0, lookups);
    if (start_side != 0) a_l = start_side > 0 ? 2.0 : 0.0;
    steps = max(steps, 1);
    for (int i = 1; i <= steps; ++i) {
        // A crossing past the bound is no nearer than a hit already found: the march
        // stops there (what it would find further is discarded anyway).
        if (d_l >= bound) return search_result(x, R, 0.0, true, lookups);
        float d, a;
        if (i < steps) {
            float t = float(i) / float(steps);
            d = len_x * t / (1.0 - t);
            a = search_ratio(x, R, d, lookups);
        } else {
            // The ray's end at infinity is behind the layer's surface in direction R, if it
            // has one there; from in front, bracket with the parallax estimate pushed out.
            if (search_is_sky(far_stored) || a_l >= 1.0 || !search_far_end(x, R, far_stored, d_l, a_l, d, a, lookups))
                return search_result(x, R, 0.0, true, lookups);
        }
        if ((a < 1.0) != (a_l < 1.0)) {
            float e0 = d_l, b0 = a_l, e1 = d, b1 = a;
            float h = search_refine(x, R, e0, b0, e1, b1, binary_steps, secant_steps, tolerance, lookups);
            if (abs(search_ratio(x, R, h, lookups) - 1.0) <= gap) return search_result(x, R, h, false, lookups);
            float den = b1 - b0;
            float at = abs(den) > 1e-30 ? e0 + (e1 - e0) * (1.0 - b0) / den : h;
            if (abs(search_ratio(x, R, at, lookups) - 1.0) <= gap) return search_result(x, R, at, false, lookups);
        }
        d_l = d;
        a_l = a;
    }
    return search_result(x, R, 0.0, true, lookups);
}

#endif
