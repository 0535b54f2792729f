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

// Two-level search: linear search for the first undershoot/overshoot pair, marching
// uniformly on the segment between the projections of the ray's start and end on the unit
// sphere, d(t) = |x|/|R| · t/(1−t) (§4.1.2); then `binary_steps` halvings (§4.1.4) and
// `secant_steps` false-position steps (survey eq. 5, §4.1.3), stopping once |l|/|l'| is
// within `tolerance` of 1.
SearchResult linear_search(vec3 x, vec3 R, int steps, int binary_steps, int secant_steps, float tolerance) {
    int lookups = 0;
    float len_x = length(x);
    // A ray from the reference point: the map answers it exactly.
    float far_stored = SEARCH_DISTANCE(R);
    lookups++;
    if (len_x <= 1e-6 * min(far_stored, 1e30)) {
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
            if (search_is_sky(far_stored)) return search_result(x, R, 0.0, true, lookups);
            d = max(far_stored - dot(R, x), d_l);
            a = search_ratio(x, R, d, lookups);
            for (int k = 0; k < 8 && a < 1.0; ++k) {
                d_l = d;
                a_l = a;
                d = 2.0 * d + len_x + far_stored;
                a = search_ratio(x, R, d, lookups);
            }
            if (a < 1.0) return search_result(x, R, 0.0, true, lookups);
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
    // Refinement: binary halvings, then secant steps (survey eq. 5: the ray meets the segment
    // between the overshooting and the undershooting surface points). Each probe is done
    // within tolerance, else replaces the bracket end of its kind (false position).
    for (int i = 0; i < binary_steps + secant_steps; ++i) {
        float d = i < binary_steps ? 0.5 * (d_l + d_p) : d_l + (d_p - d_l) * (1.0 - a_l) / max(a_p - a_l, 1e-30);
        float a = search_ratio(x, R, d, lookups);
        if (abs(a - 1.0) <= tolerance) return search_result(x, R, d, false, lookups);
        if (a < 1.0) { d_l = d; a_l = a; } else { d_p = d; a_p = a; }
    }
    // The better end of the bracket.
    float d = abs(a_l - 1.0) < abs(a_p - 1.0) ? d_l : d_p;
    return search_result(x, R, d, false, lookups);
}

#endif
