// caustics=photon-map (survey §6.1.1, PDC03): the photons of every photon hit location image
// sorted into a hashed uniform grid on the GPU (caustics/grid.comp, caustics/grid_scan.comp:
// count per bucket, scan, scatter; no readback), and the caustic irradiance at a shaded
// point gathered from its k nearest photons on its surface.
#ifndef CAUSTICS_PHOTON_MAP_GLSL
#define CAUSTICS_PHOTON_MAP_GLSL

// The grid cell of world point p: cells twice as wide as the gather's largest radius, so
// that a gather visits at most two cells along each axis.
ivec3 photon_cell(vec3 p) {
    return ivec3(floor(p / (2.0 * caustic.gather_radius)));
}

// The bucket of cell c (grid_cells is a power of two). Cells that share a bucket are told
// apart by their photons' positions.
uint photon_bucket(ivec3 c) {
    uvec3 u = uvec3(c);
    return ((u.x * 73856093u) ^ (u.y * 19349663u) ^ (u.z * 83492791u)) & (caustic.grid_cells - 1u);
}

// A unit direction as one float holding an integer below 2²⁴ (exact in f32): its octahedral
// coordinates, 12 bits each.
float photon_direction_code(vec3 d) {
    d /= abs(d.x) + abs(d.y) + abs(d.z);
    vec2 e = d.xy;
    if (d.z < 0.0) {
        vec2 s = vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
        e = (1.0 - abs(d.yx)) * s;
    }
    uvec2 q = uvec2(clamp(round((e * 0.5 + 0.5) * 4095.0), 0.0, 4095.0));
    return float(q.x * 4096u + q.y);
}

vec3 photon_direction(float code) {
    uint c = uint(code);
    vec2 e = vec2(float(c >> 12u), float(c & 4095u)) / 4095.0 * 2.0 - 1.0;
    vec3 d = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (d.z < 0.0) {
        vec2 s = vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
        d.xy = (1.0 - abs(d.yx)) * s;
    }
    return normalize(d);
}

// The most photons a gather keeps (photon_k's largest value), and one more: the (k + 1)-th
// nearest sets the kernel's radius.
const uint PHOTON_K_MAX = 64u;

// Whether the photon at offset q (|q|² = d2) from a point of normal n, arriving along
// `code`, lies on that point's surface: within a thin disc about its tangent plane (a photon
// on a wall meeting the floor is not the floor's), and arrived on its seen side.
bool photon_on_surface(vec3 q, float d2, vec3 n, float code) {
    if (abs(dot(q, n)) > 0.1 * caustic.gather_radius + 0.25 * sqrt(d2)) return false;
    return dot(photon_direction(code), n) < 0.0;
}

// The caustic irradiance at p (n: the normal on the side it is seen from) from its k
// nearest photons within gather_radius on its surface (photon_on_surface), under an
// Epanechnikov kernel K(u) = 2/π (1 − u²) over the disc that reaches the (k + 1)-th nearest,
// or gather_radius where fewer lie within it. The cells within gather_radius of p are
// visited (at most two along each axis: they are twice as wide); the photons kept are the
// k + 1 smallest (distance², place): the same whatever order the scatter's atomics gave
// them, so the image is the same every frame.
vec3 photon_map_irradiance(vec3 p, vec3 n) {
    uint k = clamp(caustic.gather_k, 1u, PHOTON_K_MAX);
    uint keep = k + 1u;
    float radius = caustic.gather_radius;
    float d2s[PHOTON_K_MAX + 1u];
    uint ids[PHOTON_K_MAX + 1u];
    uint found = 0u;
    float limit = radius * radius;
    ivec3 lo = photon_cell(p - vec3(radius));
    ivec3 hi = photon_cell(p + vec3(radius));
    for (int z = lo.z; z <= hi.z; ++z) {
        for (int y = lo.y; y <= hi.y; ++y) {
            for (int x = lo.x; x <= hi.x; ++x) {
                ivec3 c = ivec3(x, y, z);
                uint b = photon_bucket(c);
                uint start = photon_grid[b];
                uint end = start + photon_grid[caustic.grid_cells + b];
                for (uint j = start; j < end; ++j) {
                    vec4 a = photon_list[2u * j];
                    vec3 q = a.xyz - p;
                    float d2 = dot(q, q);
                    if (d2 > limit) continue;
                    if (found == keep && d2 == limit && j > ids[k]) continue;
                    if (photon_cell(a.xyz) != c) continue;  // another cell's, in the same bucket
                    if (!photon_on_surface(q, d2, n, photon_list[2u * j + 1u].z)) continue;
                    // Into the sorted list of the keep smallest (d2, j).
                    uint at = min(found, keep - 1u);
                    while (at > 0u && (d2s[at - 1u] > d2 || (d2s[at - 1u] == d2 && ids[at - 1u] > j))) {
                        d2s[at] = d2s[at - 1u];
                        ids[at] = ids[at - 1u];
                        --at;
                    }
                    d2s[at] = d2;
                    ids[at] = j;
                    found = min(found + 1u, keep);
                    if (found == keep) limit = d2s[k];
                }
            }
        }
    }
    float r2 = found == keep ? d2s[k] : radius * radius;
    if (!(r2 > 0.0)) return vec3(0.0);
    vec3 e = vec3(0.0);
    for (uint i = 0u; i < min(found, k); ++i) {
        vec4 a = photon_list[2u * ids[i]];
        vec4 b = photon_list[2u * ids[i] + 1u];
        e += vec3(a.w, b.x, b.y) * max(1.0 - d2s[i] / r2, 0.0);
    }
    return e * (0.636619772 / r2);
}
#endif
