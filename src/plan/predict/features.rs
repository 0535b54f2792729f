//! What the models see of an object: the planner's facts (`plan::facts`) and the knobs, as
//! named numbers. Error features describe how hard the object is for a method (how
//! non-convex, how close what it reflects, how strongly it bends light, what else specular
//! it sees); workload features say how much work a method does for it (pixels, triangles,
//! map texels).

use serde::{Deserialize, Serialize};

use crate::plan::facts::{Curvature, ObjectFacts};
use crate::plan::ids::ObjectClass;
use crate::quality::Quality;
use crate::scene::{Scene, SurfaceKind};

/// Names of the error features, in the order [`error_features`] returns them.
pub const ERROR_FEATURES: [&str; 16] = [
    "bias",
    "non_convex",
    "self_facing",
    "log_depth_ratio",
    "box_fraction",
    "edge_angle",
    "sees_specular",
    "sees_planar_mirror",
    "nu_minus_1",
    "log_near_ratio",
    "planar",
    "concave",
    "saddle",
    "solid",
    "thin",
    "log2_cube_size",
];

/// An object's error features (anti-aliasing is not one: `error_model` composes its effect
/// with the exact tracer's predicted aliasing).
pub fn error_features(f: &ObjectFacts, scene: &Scene, q: &Quality) -> Vec<f64> {
    let nu = match scene.materials[scene.meshes[f.mesh].material].kind {
        SurfaceKind::Dielectric { ior, .. } => ior as f64,
        _ => 1.0,
    };
    let b = |x: bool| x as u8 as f64;
    vec![
        1.0,
        1.0 - f.visible_fraction as f64,
        f.self_facing as f64,
        (f.depth_ratio.max(1.0) as f64).ln(),
        f.box_fraction as f64,
        f.edge_angle as f64,
        f.specular_coverage() as f64,
        b(f.sees_planar_mirror),
        // Refraction's strength, saturating (ν 2.4 bends little more than 1.8 does).
        (nu - 1.0).min(1.0),
        (f.near_ratio.max(0.05) as f64).ln(),
        b(f.planar),
        b(f.curvature == Curvature::Concave),
        b(f.curvature == Curvature::Saddle),
        b(f.class == ObjectClass::SolidDielectric),
        b(f.class == ObjectClass::ThinDielectric),
        (q.cube.cube_size.max(1) as f64 / 256.0).log2(),
    ]
}

/// Anti-aliasing's samples per output pixel as the cost and as the error see them:
/// (shaded samples, samples that resolve detail). Supersampling n×n shades and resolves n²;
/// multisampling n with sample-rate shading (`msaa_shading=sample`) shades and resolves n;
/// with pixel-rate shading it shades once per covered pixel (plus its n-sample raster) and
/// resolves only edges (counted as √n).
pub fn aa_samples(q: &Quality) -> (f64, f64) {
    let (s, m) = (q.frame.aa.ssaa() as f64, q.frame.aa.msaa() as f64);
    if s > 1.0 {
        (s * s, s * s)
    } else if q.frame.msaa_per_sample {
        (m, m)
    } else {
        (1.0, m.sqrt())
    }
}

/// The work a frame does for an object (inputs of the cost model), at a frame size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Workload {
    /// The object's pixels in the frame.
    pub pixels: f64,
    /// The frame's pixels.
    pub screen: f64,
    /// Triangles of the whole scene (what a cube map rasterises per face, what rays search).
    pub scene_triangles: f64,
    /// The object's own triangles.
    pub triangles: f64,
    /// Texels of one cube map (6 faces of `cube_size`²).
    pub cube_texels: f64,
    /// Punctual lights (one shadow map each).
    pub lights: f64,
    /// 1 for a solid dielectric, 0 else: its rays refract in and out and reflect inside
    /// (a ray tracer's bounces per pixel).
    #[serde(default)]
    pub solid: f64,
    /// 1 for a thin dielectric, 0 else: a reflected and a transmitted ray per hit.
    #[serde(default)]
    pub thin: f64,
    /// Shaded samples per output pixel (anti-aliasing, [`aa_samples`]): camera work and
    /// whole-screen kernels scale with it.
    #[serde(default = "one")]
    pub samples: f64,
    /// 1 when those samples are supersampled (the whole frame rendered larger), 0 when
    /// multisampled (one raster, shading per sample): the two cost differently.
    #[serde(default)]
    pub supersampled: f64,
    /// Photons the frame's caustics trace, every generator's and light's
    /// (`methods::caustics::photon_work`; 0 without caustics): a frame effect's work, the
    /// same whatever methods the objects get.
    #[serde(default)]
    pub caustic_photons: f64,
    /// Texels of the frame's caustic cubes (receiver distance cubes and light cubes).
    #[serde(default)]
    pub caustic_texels: f64,
    /// The frame's pixels that show geometry (not the environment), where rays start and
    /// diffuse shading runs; `None` (measured before it): the whole screen, as every
    /// calibration scene is a closed room.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub covered: Option<f64>,
    /// Texels the method's own maps draw for the object (`MapInfo::texels` summed: a
    /// refractor map and a distance map are two cubes, image-based captures `captures³`,
    /// relief height maps `6 · relief_size²`); `None` (measured before it): one cube map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_texels: Option<f64>,
    /// Texels of the method's maps of the whole scene, drawn once a frame for all its
    /// objects (the layered map's layers: `MapInfo::shared`); 0 for none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub shared_texels: f64,
    /// Layers its camera search reads per pixel (a layered map's; 1 else).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub layers: f64,
}

/// What a method's maps draw for one object: its own maps' texels, its maps of the whole
/// scene's, and the layers its search reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapWork {
    pub texels: f64,
    pub shared_texels: f64,
    pub layers: f64,
}

impl MapWork {
    /// `m`'s maps under `q` at a `size` camera; `layers` the layers a layered map allocates
    /// and its search reads (`methods::layered::layers_for`), `drawn` the cubes' worth of
    /// faces its peel draws (`methods::layered::drawn_cubes`: a face peels only the layers
    /// its texels reach); any for methods that peel none.
    pub fn of(m: crate::plan::Method, q: &Quality, (layers, drawn): (u32, f64), size: (u32, u32)) -> MapWork {
        let maps = m.gpu.as_ref().map_or(&[][..], |g| g.maps);
        let sum = |shared: bool| maps.iter().filter(|i| i.shared == shared).map(|i| (i.texels)(q, layers, size)).sum::<f64>();
        let peels = maps.iter().any(|i| i.name == crate::methods::layered::LAYERED_CUBES.name);
        // The shared maps are the layered peel's: the texels its drawn faces rasterise.
        let drawn_share = if peels && layers > 0 { (drawn / layers as f64).clamp(0.0, 1.0) } else { 1.0 };
        MapWork { texels: sum(false), shared_texels: sum(true) * drawn_share, layers: if peels { layers.max(1) as f64 } else { 1.0 } }
    }
}

/// What a frame does beyond its objects' own work, the same for each of them: its caustics
/// (`methods::caustics::photon_work`) and the pixels that show geometry.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameWork {
    pub caustic_photons: f64,
    pub caustic_texels: f64,
    pub covered: f64,
}

impl FrameWork {
    /// The frame of `scene` whose specular objects are `meshes`, under `q`, with `covered`
    /// pixels showing geometry (its caustics as the plan would make them).
    pub fn new(scene: &Scene, meshes: &[usize], q: &Quality, covered: f64) -> FrameWork {
        Self::with(crate::methods::caustics::photon_work(scene, meshes, q), covered)
    }

    /// The frame with caustics doing `(photons, caustic cube texels)`
    /// (`CausticsPlan::work` of a planned frame).
    pub fn with((caustic_photons, caustic_texels): (f64, f64), covered: f64) -> FrameWork {
        FrameWork { caustic_photons, caustic_texels, covered }
    }
}

fn one() -> f64 {
    1.0
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

impl Default for Workload {
    fn default() -> Workload {
        Workload {
            pixels: 0.0,
            screen: 0.0,
            scene_triangles: 0.0,
            triangles: 0.0,
            cube_texels: 0.0,
            lights: 0.0,
            solid: 0.0,
            thin: 0.0,
            samples: 1.0,
            supersampled: 0.0,
            caustic_photons: 0.0,
            caustic_texels: 0.0,
            covered: None,
            map_texels: None,
            shared_texels: 0.0,
            layers: 1.0,
        }
    }
}

/// Names of the per-object map features, in the order [`map_features`] returns them.
pub const MAP_FEATURES: [&str; 5] = ["object", "cube_raster", "cube_texels", "lit_cube_texels", "caustic_cube_texels"];

/// What an object's maps cost scales with: a constant per object (its passes), their
/// rasterisation (texels × scene triangles, 1e9), their texels (1e6), texels times lights
/// (1e6: every texel's diffuse surface shaded with each light's shadow map; on lavapipe a
/// lit 256² cube costs 3–5× an unlit one) and times the frame's caustic cubes (1e6: the
/// caustics projected onto them). The texels are the method's own maps'
/// ([`Workload::map_texels`]), not one cube's: relief height maps follow `relief_size`, not
/// `cube_size` (counted as cubes, a calibration's `cube_size=128` variant moved the feature
/// and not their cost, and an unseen lit scene measured 2.04× its prediction).
pub fn map_features(w: &Workload) -> Vec<f64> {
    let texels = w.map_texels.unwrap_or(w.cube_texels);
    let t = texels / 1e6;
    vec![1.0, texels * w.scene_triangles / 1e9, t, t * w.lights, t * caustic_cubes(w)]
}

/// The frame's caustic cubes (each a light cube map that diffuse shading reads).
fn caustic_cubes(w: &Workload) -> f64 {
    if w.cube_texels > 0.0 {
        w.caustic_texels / w.cube_texels
    } else {
        0.0
    }
}

/// Names of the per-object screen features, in the order [`screen_features`] returns them.
pub const SCREEN_FEATURES: [&str; 8] = [
    "pixels",
    "extra_msaa_samples",
    "extra_ssaa_samples",
    "pixel_rays",
    "solid_pixel_rays",
    "thin_pixel_rays",
    "object",
    "dielectric_object",
];

/// What an object's camera work scales with: its pixels (1e4), the anti-aliasing samples it
/// shades beyond one per pixel, multisampled and supersampled (unit costs of their own: a
/// sample-rate search does not cost what a pixel's does, nor a multisample what a
/// supersample does), its shaded samples times the depth of a hierarchy over the
/// scene's triangles (log₂ / 16: a traversal per ray), again for a solid dielectric's and a
/// thin one's (more rays per sample), and a constant per object, again for a dielectric
/// (its draws and dispatches; a dielectric's rays branch at every hit).
///
/// A search through layers (a layered map's) counts its pixels once per layer.
pub fn screen_features(w: &Workload) -> Vec<f64> {
    let px = w.pixels / 1e4;
    let rays = px * w.samples * depth(w);
    let [msaa, ssaa] = extra(w);
    vec![px * w.layers.max(1.0), px * msaa, px * ssaa, rays, rays * w.solid, rays * w.thin, 1.0, w.solid + w.thin]
}

/// Names of the whole-screen features, in the order [`shared_features`] returns them.
pub const SHARED_FEATURES: [&str; 10] = [
    "frame",
    "screen",
    "screen_extra_msaa_samples",
    "screen_extra_ssaa_samples",
    "screen_rays",
    "screen_shadow_rays",
    "screen_caustic_rays",
    "shared_map_raster",
    "shared_map_texels",
    "lit_shared_map_texels",
];

/// What a method's whole-screen kernels scale with: a constant per frame (its dispatches,
/// barriers and resets: a ray tracer's frame at 64² is mostly that), the frame's pixels
/// (1e4), its samples beyond one per pixel, its samples on geometry times the hierarchy
/// depth (every such sample's rays: one on the environment ends at once), that times the
/// lights (a ray tracer's shadow rays) and times the caustic cubes (the caustics its
/// diffuse hits read). Not the scene's triangles but their
/// logarithm: a traversal's frame grows with the hierarchy's depth (survey Table 1 measured,
/// BENCHMARKS.md: bvh 226 ms at 1.7·10³ triangles, 527 ms at 10⁶); a term linear in
/// triangles, fitted on six calibration scenes, took their noise and predicted bvh on the
/// concave mirror 2.5× its measured frame. Then its maps of the whole scene (a layered
/// map's peel, drawn once for all its objects): their rasterisation, texels and lit texels,
/// as an object's own maps' (without them, layered's frames were fitted as a constant and
/// measured 4× their prediction on an unseen scene of more layers).
pub fn shared_features(w: &Workload) -> Vec<f64> {
    let px = w.screen / 1e4;
    let [msaa, ssaa] = extra(w);
    let rays = w.covered.unwrap_or(w.screen).min(w.screen) / 1e4 * w.samples * depth(w);
    let t = w.shared_texels / 1e6;
    vec![
        1.0,
        px,
        px * msaa,
        px * ssaa,
        rays,
        rays * w.lights,
        rays * caustic_cubes(w),
        w.shared_texels * w.scene_triangles / 1e9,
        t,
        t * w.lights,
    ]
}

/// Samples beyond one per pixel, multisampled and supersampled.
fn extra(w: &Workload) -> [f64; 2] {
    let e = (w.samples - 1.0).max(0.0);
    [e * (1.0 - w.supersampled), e * w.supersampled]
}

fn depth(w: &Workload) -> f64 {
    w.scene_triangles.max(2.0).log2() / 16.0
}

/// The workload of object `f` at `size` covering `pixels` of it, in `frame`, with a
/// method whose maps do `maps`.
pub fn workload(f: &ObjectFacts, scene: &Scene, q: &Quality, maps: MapWork, size: (u32, u32), pixels: f64, frame: &FrameWork) -> Workload {
    let visible = |m: &&crate::scene::Mesh| !m.hidden;
    Workload {
        pixels,
        screen: size.0 as f64 * size.1 as f64,
        scene_triangles: scene.meshes.iter().filter(visible).map(|m| m.triangle_count() as f64).sum(),
        triangles: f.triangles as f64,
        cube_texels: 6.0 * (q.cube.cube_size as f64).powi(2),
        lights: scene.lights.len() as f64,
        solid: (f.class == ObjectClass::SolidDielectric) as u8 as f64,
        thin: (f.class == ObjectClass::ThinDielectric) as u8 as f64,
        samples: aa_samples(q).0,
        supersampled: (q.frame.aa.ssaa() > 1) as u8 as f64,
        caustic_photons: frame.caustic_photons,
        caustic_texels: frame.caustic_texels,
        covered: Some(frame.covered),
        map_texels: Some(maps.texels),
        shared_texels: maps.shared_texels,
        layers: maps.layers,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What each method's maps draw: relief height maps follow `relief_size` (not
    /// `cube_size`), image-based captures count `captures³` cubes, a refractor map and a
    /// distance map two cubes, the layered peel its layers as a map of the whole scene with
    /// the search reading each, the ray tracers none.
    #[test]
    fn map_work_follows_each_methods_maps() {
        use crate::methods::*;
        let mut q = Quality::default();
        q.set("cube_size", "128").unwrap();
        q.set("relief_size", "64").unwrap();
        let cube = 6.0 * 128.0 * 128.0;
        let of = |m| MapWork::of(m, &q, (3, 3.0), (64, 64));
        assert_eq!(of(ENVMAP), MapWork { texels: cube, shared_texels: 0.0, layers: 1.0 });
        assert_eq!(of(PROXY_RELIEF).texels, 6.0 * 64.0 * 64.0);
        assert_eq!(of(IMAGE_BASED).texels, cube * q.envmap.captures.pow(3) as f64);
        assert_eq!(of(REFRACTOR_MAP).texels, 2.0 * cube);
        assert_eq!(of(LAYERED), MapWork { texels: 0.0, shared_texels: 3.0 * cube, layers: 3.0 });
        assert_eq!(of(BVH), MapWork { texels: 0.0, shared_texels: 0.0, layers: 1.0 });
        let w = Workload { pixels: 1e4, map_texels: Some(of(PROXY_RELIEF).texels), cube_texels: cube, ..Workload::default() };
        assert_eq!(map_features(&w)[2], 6.0 * 64.0 * 64.0 / 1e6);
        assert_eq!(screen_features(&Workload { layers: 3.0, ..w })[0], 3.0);
    }

    /// A ray tracer's kernels trace rays from the pixels that show geometry: half the screen
    /// covered, half the rays (and their shadow and caustic rays); unknown, the whole screen.
    #[test]
    fn rays_start_on_covered_pixels() {
        let w = Workload {
            screen: 4e4,
            scene_triangles: 1e3,
            cube_texels: 1e5,
            lights: 2.0,
            caustic_texels: 2e5,
            covered: None,
            ..Workload::default()
        };
        let (all, half) = (shared_features(&w), shared_features(&Workload { covered: Some(2e4), ..w }));
        for k in 4..7 {
            assert!(all[k] > 0.0 && (half[k] - 0.5 * all[k]).abs() < 1e-12, "{k}: {all:?} {half:?}");
        }
        assert_eq!(all[..4], half[..4]);
    }
}
