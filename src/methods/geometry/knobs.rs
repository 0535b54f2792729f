//! The geometry family's knobs: planar mirrors and refractions, curved reflectors (§5).

use crate::quality::knob::knobs;

knobs! {
    /// Planar mirrors and refractions, curved reflectors (§5).
    pub struct GeometryKnobs {
        /// planar-mirror and planar-refraction (§5): the most mirrored or refracted views a frame renders, chosen best first (the
        /// pixels a view covers times its path's Fresnel weight: mirrors and refractions seen from the camera before weak
        /// reflections and views seen in views); where the budget can cut views, each planar object gets a distance map (and a
        /// solid a refractor map) of its own, in which planes beyond the budget are traced; planes deeper than depth end with
        /// the environment along their rays, as the reference's paths end. A flat-faced solid needs about two views per pair of
        /// faces a ray crosses
        mirror_budget: u32 = 8, count(0..=64, "views");
        /// planar mirrors (planar-mirror, §5) inside the other objects' cube maps (envmap, proxy-sphere, proxy-box, distance,
        /// distance-multi, refractor-map): per map face that sees one, the scene drawn again from the reference point mirrored
        /// through the mirror's plane (oblique near plane), masked to the mirror's pixels by the depth buffer and weighted by its
        /// Fresnel factor; one reflection deep (no mirror inside a mirror in a map), at most mirror_budget mirrors, redrawn only
        /// when the map is; off: the map shows the mirror reflecting the environment only
        map_mirrors: bool = "on", one_of()["on" => true, "off" => false];
        /// curved-reflector (§5, EMD*05): edge of each reflector's geometry image (world positions and normals rasterised over its
        /// UV parameterisation, or where it has none a planar projection, a cube atlas for a closed surface): the reflection points' sampling
        geometry_image: u32 = 128, count(8..=1024, "texels");
        /// curved-reflector: coarse-to-fine levels of each vertex's reflection-point search in the geometry image: the coarsest
        /// level (every 2^levels-th texel) is searched exhaustively, each finer one in a 5×5 window around the last best, then a
        /// sub-texel refinement; 0: exhaustive at full resolution (slowest, finds the global minimum of the sampled image)
        curved_search: u32 = 3, count(0..=8, "levels");
        /// curved-reflector: each environment triangle is split into tessellation² triangles before its vertices are moved to their
        /// virtual positions (survey Table 1: geometry transformation needs high tessellation, since the reflection of a straight
        /// edge in a curved mirror is curved)
        tessellation: u32 = 4, count(1..=32, "subdivisions");
    }
}
