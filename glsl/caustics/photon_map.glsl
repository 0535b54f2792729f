// caustics=photon-map (survey §6.1.1, PDC03): the photons of every photon hit location image
// sorted into a hashed uniform grid on the GPU (caustics/grid.comp, caustics/grid_scan.comp:
// count per bucket, scan, scatter; no readback), and the caustic irradiance at a shaded
// point gathered from its k nearest photons on its surface.
#ifndef CAUSTICS_PHOTON_MAP_GLSL
#define CAUSTICS_PHOTON_MAP_GLSL

// The photon grid has two levels over the same number of buckets: coarse cells twice the
// gather's largest radius wide, fine cells a quarter of it. A point whose coarse cells hold
// few photons (PHOTON_DIRECT) reads them all (a sparse caustic, or none: eight reads); else
// it visits the fine cells ring by ring outwards until its k + 1 nearest are found (a dense
// caustic: the first rings).
const int PHOTON_RINGS = 4;

// The fine cell of world point p.
ivec3 photon_cell(vec3 p) {
    return ivec3(floor(p * (float(PHOTON_RINGS) / caustic.gather_radius)));
}

// The coarse cell of world point p.
ivec3 photon_coarse_cell(vec3 p) {
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

// A point whose coarse cells hold at most this many photons per photon it keeps reads them
// all instead of searching the fine cells.
const uint PHOTON_DIRECT = 32u;

// Whether the photon at offset q (|q|² = d2) from a point of normal n, arriving along
// `code`, lies on that point's surface: within a thin disc about its tangent plane (a photon
// on a wall meeting the floor is not the floor's), and arrived on its seen side.
bool photon_on_surface(vec3 q, float d2, vec3 n, float code) {
    if (abs(dot(q, n)) > 0.1 * caustic.gather_radius + 0.25 * sqrt(d2)) return false;
    return dot(photon_direction(code), n) < 0.0;
}

// Photon j of photon_list, at offset q = its position − p (|q|² = d2), into the sorted list
// of the `keep` smallest (distance², place) (`limit`: the largest kept once it is full) if
// it lies on p's surface. (A macro: GLSL passes no arrays by reference.)
#define PHOTON_CONSIDER(j, q, d2)                                                                         \
    if (d2 <= limit && !(found == keep && d2 == limit && j > ids[k]) &&                                  \
        photon_on_surface(q, d2, n, photon_list[2u * j + 1u].z)) {                                        \
        uint at = min(found, keep - 1u);                                                                  \
        while (at > 0u && (d2s[at - 1u] > d2 || (d2s[at - 1u] == d2 && ids[at - 1u] > j))) {              \
            d2s[at] = d2s[at - 1u];                                                                       \
            ids[at] = ids[at - 1u];                                                                       \
            --at;                                                                                         \
        }                                                                                                 \
        d2s[at] = d2;                                                                                     \
        ids[at] = j;                                                                                      \
        found = min(found + 1u, keep);                                                                    \
        if (found == keep) limit = d2s[k];                                                                \
    }

// The caustic irradiance at p (n: the normal on the side it is seen from) from its k
// nearest photons within gather_radius on its surface (photon_on_surface), under an
// Epanechnikov kernel K(u) = 2/π (1 − u²) over the disc that reaches the (k + 1)-th nearest,
// or gather_radius where fewer lie within it. Where the coarse cells around p hold many
// photons, the fine cells are visited in rings of growing Chebyshev distance from p's,
// until the (k + 1)-th nearest lies nearer than any cell of the next ring can. The photons
// kept are the k + 1 smallest (distance², place): the same whatever order the scatter's
// atomics gave them, so the image is the same every frame.
vec3 photon_map_irradiance(vec3 p, vec3 n) {
    uint h = caustic.grid_cells;
    float radius = caustic.gather_radius;
    uint k = clamp(caustic.gather_k, 1u, PHOTON_K_MAX);
    uint keep = k + 1u;
    float d2s[PHOTON_K_MAX + 1u];
    uint ids[PHOTON_K_MAX + 1u];
    uint found = 0u;
    float limit = radius * radius;

    ivec3 lo = photon_coarse_cell(p - vec3(radius));
    ivec3 hi = photon_coarse_cell(p + vec3(radius));
    uint near = 0u;
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) near += photon_grid[3u * h + photon_bucket(ivec3(x, y, z))];
    if (near == 0u) return vec3(0.0);
    if (near <= PHOTON_DIRECT * keep) {
        for (int z = lo.z; z <= hi.z; ++z) {
            for (int y = lo.y; y <= hi.y; ++y) {
                for (int x = lo.x; x <= hi.x; ++x) {
                    ivec3 c = ivec3(x, y, z);
                    uint b = photon_bucket(c);
                    uint start = photon_grid[2u * h + b];
                    uint end = start + photon_grid[3u * h + b];
                    for (uint i = start; i < end; ++i) {
                        uint j = photon_coarse[i];
                        vec3 pos = photon_list[2u * j].xyz;
                        vec3 q = pos - p;
                        float d2 = dot(q, q);
                        if (photon_coarse_cell(pos) != c) continue;  // another cell's, in the same bucket
                        PHOTON_CONSIDER(j, q, d2)
                    }
                }
            }
        }
    } else {
        float cell = radius / float(PHOTON_RINGS);
        ivec3 centre = photon_cell(p);
        for (int ring = 0; ring <= PHOTON_RINGS; ++ring) {
            // Every cell of this ring lies at least (ring − 1) · cell from p.
            if (ring > 0 && found == keep && limit <= float(ring - 1) * float(ring - 1) * cell * cell) break;
            for (int z = -ring; z <= ring; ++z) {
                for (int y = -ring; y <= ring; ++y) {
                    for (int x = -ring; x <= ring; ++x) {
                        if (max(abs(x), max(abs(y), abs(z))) != ring) continue;  // an inner ring's
                        ivec3 c = centre + ivec3(x, y, z);
                        uint b = photon_bucket(c);
                        uint start = photon_grid[b];
                        uint end = start + photon_grid[h + b];
                        for (uint j = start; j < end; ++j) {
                            vec3 pos = photon_list[2u * j].xyz;
                            vec3 q = pos - p;
                            float d2 = dot(q, q);
                            if (photon_cell(pos) != c) continue;  // another cell's, in the same bucket
                            PHOTON_CONSIDER(j, q, d2)
                        }
                    }
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
