//! Accuracy knobs. Each knob is declared once, in `KNOBS`: its name, values (range and
//! unit), default, what it does, and its parser and printer. The CLI (`-q key=value`), the
//! Rust API, the C ABI, `specula knobs`, `specula plan` and the README test all go through
//! that table. A knob means one thing: `depth` is the exact renderers' recursion depth,
//! `cycles` the inter-object map cycles of `distance-multi`.

use glam::Vec3;

use crate::error::{clip, Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum FresnelMode {
    /// Schlick's approximation with F0 from ν, κ (survey eq. 2).
    Schlick,
    /// The exact Fresnel equations for dielectrics and conductors.
    Exact,
}

/// How the six faces of a cube map are rasterised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CubeMode {
    /// One render pass per face.
    SixPasses,
    /// All six faces in one pass with multiview (view mask 0x3F).
    Multiview,
}

/// Storage precision of radiance cube maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Precision {
    Half,
    Single,
}

/// What `--method auto` optimises when it picks a method per object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Planner {
    /// The most accurate method that serves the object.
    Accuracy,
    /// A cheaper rung: single distance maps for mirrors, image-space refraction for solids.
    Speed,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    pub cube_size: u32,
    pub cube_precision: Precision,
    pub cube_mode: CubeMode,
    pub fresnel: FresnelMode,
    /// Overrides every specular object's reference point (world space, metres).
    pub ref_point: Option<Vec3>,
    pub shadow_size: u32,
    /// Specular recursion depth R (survey Table 1) of the exact renderers (the reference):
    /// paths still specular after R bounces end black.
    pub depth: u32,
    /// Inter-object map cycles of `distance-multi` (§4.3).
    pub cycles: u32,
    /// Reference renderer: samples per pixel, a k×k stratified grid (k² = spp).
    pub spp: u32,
    /// Distance-map search (§4.1): linear steps (0: parallax correction only).
    pub linear_steps: u32,
    pub secant_steps: u32,
    pub binary_steps: u32,
    pub parallax_iterations: u32,
    /// Early exit once | |l|/|l'| − 1 | ≤ this.
    pub search_tolerance: f32,
    /// Self refraction (§4.4): internal reflections followed inside a refractor.
    pub internal_bounces: u32,
    /// Inter-object reflections (§4.3): one map cycle per frame, reusing the last frame's.
    pub frame_latency: bool,
    /// Proxy sphere radius of `proxy-sphere` (§3.2), metres; `None`: the mean half-extent
    /// of the scene's bounding box.
    pub proxy_radius: Option<f32>,
    /// What `--method auto` optimises.
    pub planner: Planner,
    /// Ray tracing in the original geometry (§2): rays per pixel each bounce's queue holds.
    pub ray_budget: u32,
    /// `bvh`: traversal with a short stack, else stackless along hit/miss links (CHCH06).
    pub bvh_stackless: bool,
    /// `grid`: about this many cells per triangle.
    pub grid_density: f32,
    /// `grid`: empty-space skipping by distance to the nearest non-empty cell (KL04).
    pub grid_skip: bool,
    /// `kd-tree`: the deepest level (0: 8 + 1.3 log₂ N, at most 64).
    pub kd_max_depth: u32,
    /// `kd-tree`: nodes of at most this many triangles stay leaves.
    pub kd_leaf_size: u32,
    /// `kd-tree`: kd-restart from the root at each leaf's exit (FS05), else a short stack
    /// with push-down (HSHH07).
    pub kd_restart: bool,
    /// `ray-hierarchy`: edge of the ray-texture tiles whose cones are tested (§2.2.1).
    pub tile_size: u32,
    /// Ray tracing: count rays per bounce and the ray hierarchy's culling (costs a pass).
    pub ray_stats: bool,
    /// Maps (shadow, environment, distance, refractor) regenerated every frame, else only
    /// when what they depend on changed (frames over time).
    pub map_updates_always: bool,
    /// Anti-aliasing of the camera passes (`aa`).
    pub aa: Aa,
    /// `planar-mirror` (§5): the most mirrored views a frame renders.
    pub mirror_budget: u32,
    /// Planar mirrors drawn into other objects' cube maps by their mirrored views (§5).
    pub map_mirrors: bool,
    /// Debug output: each pixel's first-hit object beside the colour (`Frame::object_ids`).
    pub object_ids: bool,
    /// Shadows of punctual lights, in the GPU renderers and the reference alike.
    pub shadows: bool,
    /// `curved-reflector` (§5): edge of each reflector's geometry image, texels.
    pub geometry_image: u32,
    /// `curved-reflector`: coarse-to-fine levels of the reflection-point search.
    pub curved_search: u32,
    /// `curved-reflector`: each environment triangle is split into this many² triangles.
    pub tessellation: u32,
    /// With MSAA: the specular camera passes shade every sample (their search depends on
    /// the sample's position and normal), else once per pixel and coverage.
    pub msaa_per_sample: bool,
    /// Caustics (§6): how photon hits are filtered into the light cube maps, or none.
    pub caustics: Caustics,
    /// Caustics: edge of each photon hit location image (photons per light and generator
    /// view: `photons`²).
    pub photons: u32,
    /// Caustics, `splat`: radius of a photon's splat in light-cube texels.
    pub splat_size: f32,
    /// Caustics: radius in texels of the light cube maps' box filter before projection
    /// (0: none).
    pub caustic_filter: u32,
    /// Caustics: the projection's distance test against the receiver distance map (the
    /// shadow-map-like test that stops light leaks, §6.3.3).
    pub caustic_distance_test: bool,
    /// Caustics: the receiver-orientation factor cos α of the projection (off: every
    /// receiver taken as facing the generator).
    pub caustic_orientation: bool,
    /// Caustics: dielectric generators also send their reflected photons (else only the
    /// refracted ones, the stronger branch).
    pub caustic_reflections: bool,
    /// Caustics: where the photon hits and the light cube maps live (survey §6.1.2).
    pub caustic_space: CausticSpace,
    /// CPU reference: photons traced per light and caustic generator.
    pub reference_photons: u32,
    /// CPU reference: radius of the caustic density estimate (metres); `None`: 0.5 % of
    /// the scene's bounding-box diagonal.
    pub caustic_radius: Option<f32>,
    /// Layered distance maps (§4.5): the most layers peeled; `None` (auto): as many as the
    /// scene's depth complexity from the map's reference point, measured on the GPU, up to
    /// `MAX_LAYERS`.
    pub layers: Option<u32>,
    /// Layered maps: a dielectric hit in the layers continues along both Fresnel branches
    /// while the ray stack has room (else the stronger one carrying both weights), or always
    /// along the stronger one only.
    pub layered_both: bool,
    /// Test knob: a deliberate fault injected into a method, so that the tests can check
    /// that the per-object error measurements see it. Never for images.
    pub debug_fault: DebugFault,
}

/// A deliberately broken method (`debug_fault`, a test knob).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DebugFault {
    None,
    /// `distance.search` (the `distance` method's camera pass, §4.2) looks up the reflected
    /// ray's opposite direction: reflections come from behind the surface.
    FlipReflection,
}

/// The most layers a layered distance map (§4.5) peels.
pub const MAX_LAYERS: u32 = 16;

/// Where caustic photon hits are stored and projected from (survey §6.1.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CausticSpace {
    /// Cube-map space (UPSK08): one cube per generator, around its reference point.
    Cube,
    /// Light space (the shadow-map space of SP07): one cube per generator and point or spot
    /// light, around the light; directional lights stay in cube-map space.
    Light,
}

/// How caustics are rendered (survey §6.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Caustics {
    Off,
    /// Photon splatting (§6.3.1).
    Splat,
    /// Caustic triangles (§6.3.2).
    Triangles,
}

/// Anti-aliasing of the camera passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aa {
    Off,
    /// Multisampling with this many samples per pixel (2, 4 or 8; the device's standard
    /// sample positions), resolved (averaged) on the GPU.
    Msaa(u32),
    /// Supersampling: this many samples per pixel along each axis (2 or 4, a regular
    /// grid), box-filtered on the GPU.
    Ssaa(u32),
}

/// Serialised as the knob's value (`msaa4`).
impl serde::Serialize for Aa {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&name_of(*self, AA))
    }
}

impl Aa {
    /// Supersampling factor per axis (1 unless `Ssaa`).
    pub fn ssaa(self) -> u32 {
        match self {
            Aa::Ssaa(n) => n,
            _ => 1,
        }
    }

    /// Samples per pixel of the camera target (1 unless `Msaa`).
    pub fn msaa(self) -> u32 {
        match self {
            Aa::Msaa(n) => n,
            _ => 1,
        }
    }
}

/// One knob, declared once.
pub struct Knob {
    pub name: &'static str,
    /// Accepted values with their unit, as `specula knobs` and the README show them.
    pub values: &'static str,
    pub default: &'static str,
    pub doc: &'static str,
    /// Parses a textual value into the knob's field; the error says what is accepted.
    pub set: fn(&mut Quality, &str) -> std::result::Result<(), String>,
    /// The field's value, as `set` accepts it.
    pub get: fn(&Quality) -> String,
}

fn count(v: &str, lo: u32, hi: u32) -> std::result::Result<u32, String> {
    match v.trim().parse::<i64>() {
        Ok(n) if (lo as i64..=hi as i64).contains(&n) => Ok(n as u32),
        Ok(n) => Err(format!("{n} is outside {lo}..={hi}")),
        Err(_) => Err(format!("'{}' is not a whole number", clip(v))),
    }
}

fn real(v: &str, lo: f32, hi: f32) -> std::result::Result<f32, String> {
    match v.trim().parse::<f32>() {
        Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        Ok(x) if x.is_nan() => Err(format!("NaN is not a number in {lo}..={hi}")),
        Ok(x) => Err(format!("{x} is outside {lo}..={hi}")),
        Err(_) => Err(format!("'{}' is not a number (expected {lo}..={hi})", clip(v))),
    }
}

fn one_of<T: Copy>(v: &str, options: &[(&str, T)]) -> std::result::Result<T, String> {
    options.iter().find(|(n, _)| *n == v).map(|(_, t)| *t).ok_or_else(|| {
        let names: Vec<_> = options.iter().map(|(n, _)| *n).collect();
        format!("'{}' is not one of {}", clip(v), names.join(", "))
    })
}

fn name_of<T: PartialEq>(t: T, options: &[(&'static str, T)]) -> String {
    options.iter().find(|(_, o)| *o == t).map_or("?", |(n, _)| n).to_string()
}

const PRECISIONS: &[(&str, Precision)] = &[("half", Precision::Half), ("single", Precision::Single)];
const CUBE_MODES: &[(&str, CubeMode)] = &[("six", CubeMode::SixPasses), ("multiview", CubeMode::Multiview)];
const FRESNEL: &[(&str, FresnelMode)] = &[("schlick", FresnelMode::Schlick), ("exact", FresnelMode::Exact)];
const ON_OFF: &[(&str, bool)] = &[("on", true), ("off", false)];
const AA: &[(&str, Aa)] = &[
    ("off", Aa::Off),
    ("msaa2", Aa::Msaa(2)),
    ("msaa4", Aa::Msaa(4)),
    ("msaa8", Aa::Msaa(8)),
    ("ssaa2", Aa::Ssaa(2)),
    ("ssaa4", Aa::Ssaa(4)),
];
const MSAA_SHADING: &[(&str, bool)] = &[("sample", true), ("pixel", false)];
const MAP_UPDATES: &[(&str, bool)] = &[("on_change", false), ("always", true)];
const KD_TRAVERSALS: &[(&str, bool)] = &[("short-stack", false), ("restart", true)];
const BVH_TRAVERSALS: &[(&str, bool)] = &[("stack", false), ("stackless", true)];
const CAUSTICS: &[(&str, Caustics)] = &[("off", Caustics::Off), ("splat", Caustics::Splat), ("triangles", Caustics::Triangles)];
const CAUSTIC_SPACES: &[(&str, CausticSpace)] = &[("cube", CausticSpace::Cube), ("light", CausticSpace::Light)];
const CAUSTIC_PATHS: &[(&str, bool)] = &[("both", true), ("refracted", false)];
const PLANNERS: &[(&str, Planner)] = &[("accuracy", Planner::Accuracy), ("speed", Planner::Speed)];

pub const KNOBS: &[Knob] = &[
    Knob {
        name: "cube_size",
        values: "16..=4096 texels",
        default: "256",
        doc: "edge of each face of an object's cube maps (environment, distance, refractor)",
        set: |q, v| {
            q.cube_size = count(v, 16, 4096)?;
            Ok(())
        },
        get: |q| q.cube_size.to_string(),
    },
    Knob {
        name: "cube_precision",
        values: "half|single",
        default: "half",
        doc: "cube-map storage (radiance and distance): RGBA16F or RGBA32F",
        set: |q, v| {
            q.cube_precision = one_of(v, PRECISIONS)?;
            Ok(())
        },
        get: |q| name_of(q.cube_precision, PRECISIONS),
    },
    Knob {
        name: "cube_mode",
        values: "six|multiview",
        default: "six",
        doc: "cube faces in six passes or one multiview pass (equal speed on lavapipe, six needs less depth memory: BENCHMARKS.md; lavapipe's multiview puts large clipped triangles on wrong faces: use six there); the caustics' cubes always take six passes",
        set: |q, v| {
            q.cube_mode = one_of(v, CUBE_MODES)?;
            Ok(())
        },
        get: |q| name_of(q.cube_mode, CUBE_MODES),
    },
    Knob {
        name: "fresnel",
        values: "schlick|exact",
        default: "schlick",
        doc: "Schlick's approximation (survey eq. 2) or the exact Fresnel equations",
        set: |q, v| {
            q.fresnel = one_of(v, FRESNEL)?;
            Ok(())
        },
        get: |q| name_of(q.fresnel, FRESNEL),
    },
    Knob {
        name: "ref_point",
        values: "auto|x,y,z (metres)",
        default: "auto",
        doc: "reference point of every specular object's maps; auto = its bounding-box centre, moved when that lies inside or next to another object",
        set: |q, v| {
            if v == "auto" {
                q.ref_point = None;
                return Ok(());
            }
            let parts: Vec<&str> = v.split(',').collect();
            let nums: Vec<f32> = parts.iter().filter_map(|s| s.trim().parse::<f32>().ok()).filter(|x| x.is_finite()).collect();
            if parts.len() != 3 || nums.len() != 3 {
                return Err(format!("'{}' is not auto or x,y,z with three finite numbers", clip(v)));
            }
            q.ref_point = Some(Vec3::new(nums[0], nums[1], nums[2]));
            Ok(())
        },
        get: |q| q.ref_point.map_or("auto".into(), |p| format!("{},{},{}", p.x, p.y, p.z)),
    },
    Knob {
        name: "shadow_size",
        values: "16..=4096 texels",
        default: "512",
        doc: "edge of each shadow distance map face",
        set: |q, v| {
            q.shadow_size = count(v, 16, 4096)?;
            Ok(())
        },
        get: |q| q.shadow_size.to_string(),
    },
    Knob {
        name: "depth",
        values: "1..=64 bounces",
        default: "16",
        doc: "specular recursion depth R of the exact renderers (the reference, ray tracing) and of the planar views of planar-mirror and planar-refraction (mirrors in mirrors, a face's refraction in, internal reflections, refraction out): paths still specular after R bounces end black; the default is converged for glass",
        set: |q, v| {
            q.depth = count(v, 1, 64)?;
            Ok(())
        },
        get: |q| q.depth.to_string(),
    },
    Knob {
        name: "cycles",
        values: "1..=16 cycles",
        default: "4",
        doc: "distance-multi: distance-map generation cycles per frame (§4.3); cycle k shows k specular bounces in the maps",
        set: |q, v| {
            q.cycles = count(v, 1, 16)?;
            Ok(())
        },
        get: |q| q.cycles.to_string(),
    },
    Knob {
        name: "spp",
        values: "1, 4, 9, ..., 1024",
        default: "16",
        doc: "reference: samples per pixel on a k×k stratified grid (a perfect square; 1 = pixel centre)",
        set: |q, v| {
            let n = count(v, 1, 1024)?;
            if n.isqrt().pow(2) != n {
                return Err(format!("{n} is not a perfect square (1, 4, 9, ..., 1024)"));
            }
            q.spp = n;
            Ok(())
        },
        get: |q| q.spp.to_string(),
    },
    Knob {
        name: "linear_steps",
        values: "0..=256",
        default: "16",
        doc: "distance-map linear search steps (§4.1.2); 0: parallax correction only",
        set: |q, v| {
            q.linear_steps = count(v, 0, 256)?;
            Ok(())
        },
        get: |q| q.linear_steps.to_string(),
    },
    Knob {
        name: "secant_steps",
        values: "0..=64",
        default: "2",
        doc: "secant (false position) refinement steps after the linear search (survey eq. 5)",
        set: |q, v| {
            q.secant_steps = count(v, 0, 64)?;
            Ok(())
        },
        get: |q| q.secant_steps.to_string(),
    },
    Knob {
        name: "binary_steps",
        values: "0..=64",
        default: "0",
        doc: "binary refinement steps after the linear search (§4.1.4)",
        set: |q, v| {
            q.binary_steps = count(v, 0, 64)?;
            Ok(())
        },
        get: |q| q.binary_steps.to_string(),
    },
    Knob {
        name: "parallax_iterations",
        values: "1..=64",
        default: "1",
        doc: "parallax-correction iterations (survey eq. 4) when linear_steps = 0",
        set: |q, v| {
            q.parallax_iterations = count(v, 1, 64)?;
            Ok(())
        },
        get: |q| q.parallax_iterations.to_string(),
    },
    Knob {
        name: "search_tolerance",
        values: "0..=1",
        default: "0.001",
        doc: "search stops once ‖l‖/‖l′‖ is within this of 1",
        set: |q, v| {
            q.search_tolerance = real(v, 0.0, 1.0)?;
            Ok(())
        },
        get: |q| q.search_tolerance.to_string(),
    },
    Knob {
        name: "internal_bounces",
        values: "0..=16",
        default: "2",
        doc: "refractor-map: total internal reflections followed inside a refractor (§4.4)",
        set: |q, v| {
            q.internal_bounces = count(v, 0, 16)?;
            Ok(())
        },
        get: |q| q.internal_bounces.to_string(),
    },
    Knob {
        name: "frame_latency",
        values: "on|off",
        default: "off",
        doc: "distance-multi: one map cycle per frame reusing the previous frame's maps (§4.3)",
        set: |q, v| {
            q.frame_latency = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.frame_latency, ON_OFF),
    },
    Knob {
        name: "ray_budget",
        values: "1..=64 rays per pixel",
        default: "4",
        doc: "ray tracing (§2): capacity of each bounce's ray queue; rays beyond it are dropped (and counted)",
        set: |q, v| {
            q.ray_budget = count(v, 1, 64)?;
            Ok(())
        },
        get: |q| q.ray_budget.to_string(),
    },
    Knob {
        name: "bvh_traversal",
        values: "stack|stackless",
        default: "stack",
        doc: "bvh (§2.3.5): nearest child first with a short stack, or stackless along hit/miss links (CHCH06)",
        set: |q, v| {
            q.bvh_stackless = one_of(v, BVH_TRAVERSALS)?;
            Ok(())
        },
        get: |q| name_of(q.bvh_stackless, BVH_TRAVERSALS),
    },
    Knob {
        name: "grid_density",
        values: "0.01..=64 cells per triangle",
        default: "2",
        doc: "grid (§2.3.1): cells of the uniform grid per triangle of the scene",
        set: |q, v| {
            q.grid_density = real(v, 0.01, 64.0)?;
            Ok(())
        },
        get: |q| q.grid_density.to_string(),
    },
    Knob {
        name: "grid_skip",
        values: "on|off",
        default: "on",
        doc: "grid: skip empty space by each empty cell's distance to the nearest non-empty cell (KL04)",
        set: |q, v| {
            q.grid_skip = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.grid_skip, ON_OFF),
    },
    Knob {
        name: "kd_max_depth",
        values: "0..=64 levels",
        default: "0",
        doc: "kd-tree (§2.3.3): the deepest level; 0: 8 + 1.3 log₂ N",
        set: |q, v| {
            q.kd_max_depth = count(v, 0, 64)?;
            Ok(())
        },
        get: |q| q.kd_max_depth.to_string(),
    },
    Knob {
        name: "kd_leaf_size",
        values: "1..=64 triangles",
        default: "4",
        doc: "kd-tree: nodes of at most this many triangles are not split",
        set: |q, v| {
            q.kd_leaf_size = count(v, 1, 64)?;
            Ok(())
        },
        get: |q| q.kd_leaf_size.to_string(),
    },
    Knob {
        name: "kd_traversal",
        values: "short-stack|restart",
        default: "short-stack",
        doc: "kd-tree: a short stack with push-down (HSHH07), or kd-restart from the root (FS05)",
        set: |q, v| {
            q.kd_restart = one_of(v, KD_TRAVERSALS)?;
            Ok(())
        },
        get: |q| name_of(q.kd_restart, KD_TRAVERSALS),
    },
    Knob {
        name: "tile_size",
        values: "8|16|32 rays",
        default: "16",
        doc: "ray-hierarchy (§2.2.1): edge of the ray-texture tiles bounded by one cone each",
        set: |q, v| {
            q.tile_size = one_of(v, &[("8", 8), ("16", 16), ("32", 32)])?;
            Ok(())
        },
        get: |q| q.tile_size.to_string(),
    },
    Knob {
        name: "ray_stats",
        values: "on|off",
        default: "off",
        doc: "ray tracing: report rays per bounce, dropped rays and the ray hierarchy's culling rate (an extra pass)",
        set: |q, v| {
            q.ray_stats = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.ray_stats, ON_OFF),
    },
    Knob {
        name: "proxy_radius",
        values: "auto|metres",
        default: "auto",
        doc: "proxy-sphere radius (§3.2); auto: mean half-extent of the scene's box",
        set: |q, v| {
            q.proxy_radius = match v {
                "auto" => None,
                v => match v.trim().parse::<f32>() {
                    Ok(r) if r > 0.0 && r.is_finite() => Some(r),
                    _ => return Err(format!("'{}' is not auto or a radius > 0 in metres", clip(v))),
                },
            };
            Ok(())
        },
        get: |q| q.proxy_radius.map_or("auto".into(), |r| r.to_string()),
    },
    Knob {
        name: "aa",
        values: "off|msaa2|msaa4|msaa8|ssaa2|ssaa4",
        default: "off",
        doc: "anti-aliasing of every GPU method's camera passes: multisampling with 2, 4 or 8 samples per pixel at the device's standard positions (ray-tracing methods trace one ray per sample; the counts a device offers vary: lavapipe has 4 only), or supersampling on a regular 2×2 (ssaa2) or 4×4 (ssaa4) grid per pixel; resolved by averaging on the GPU",
        set: |q, v| {
            q.aa = one_of(v, AA)?;
            Ok(())
        },
        get: |q| name_of(q.aa, AA),
    },
    Knob {
        name: "mirror_budget",
        values: "0..=64 views",
        default: "8",
        doc: "planar-mirror and planar-refraction (§5): the most mirrored or refracted views a frame renders, chosen best first (the pixels a view covers times its path's Fresnel weight: mirrors and refractions seen from the camera before weak reflections and views seen in views); planes beyond it, or deeper than depth, show the environment along their rays (black in a closed room). A flat-faced solid needs about two views per pair of faces a ray crosses",
        set: |q, v| {
            q.mirror_budget = count(v, 0, 64)?;
            Ok(())
        },
        get: |q| q.mirror_budget.to_string(),
    },
    Knob {
        name: "map_mirrors",
        values: "on|off",
        default: "on",
        doc: "planar mirrors (planar-mirror, §5) inside the other objects' cube maps (envmap, proxy-sphere, proxy-box, distance, distance-multi, refractor-map): per map face that sees one, the scene drawn again from the reference point mirrored through the mirror's plane (oblique near plane), masked to the mirror's pixels by the depth buffer and weighted by its Fresnel factor; one reflection deep (no mirror inside a mirror in a map), at most mirror_budget mirrors, redrawn only when the map is; off: the map shows the mirror reflecting the environment only",
        set: |q, v| {
            q.map_mirrors = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.map_mirrors, ON_OFF),
    },
    Knob {
        name: "object_ids",
        values: "on|off",
        default: "off",
        doc: "debug output (issue 15's masks): each frame also rasterises every object's mesh index + 1 (0: the sky) from the camera at the output size (pass frame.object_ids) and reads it back beside the colour, so that errors can be measured on one object's pixels, on the specular ones or on the rest; off: no pass, no image",
        set: |q, v| {
            q.object_ids = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.object_ids, ON_OFF),
    },
    Knob {
        name: "shadows",
        values: "on|off",
        default: "on",
        doc: "shadows of punctual lights on diffuse surfaces, in the GPU renderers (shadow maps; the ray tracers' shadow rays) and the CPU reference (exact shadow rays) alike; off: every light reaches what faces it unoccluded, in both, so that a comparison's error is not the shared term of shadow maps against exact shadows (issue 15: a specular knob's curve then shows that knob). Caustic photons stay occluded in the reference's light tracing. Off is not ground truth",
        set: |q, v| {
            q.shadows = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.shadows, ON_OFF),
    },
    Knob {
        name: "geometry_image",
        values: "8..=1024 texels",
        default: "128",
        doc: "curved-reflector (§5, EMD*05): edge of each reflector's geometry image (world positions and normals rasterised over its UV parameterisation, or a planar projection where it has none): the reflection points' sampling",
        set: |q, v| {
            q.geometry_image = count(v, 8, 1024)?;
            Ok(())
        },
        get: |q| q.geometry_image.to_string(),
    },
    Knob {
        name: "curved_search",
        values: "0..=8 levels",
        default: "3",
        doc: "curved-reflector: coarse-to-fine levels of each vertex's reflection-point search in the geometry image: the coarsest level (every 2^levels-th texel) is searched exhaustively, each finer one in a 5×5 window around the last best, then a sub-texel refinement; 0: exhaustive at full resolution (slowest, finds the global minimum of the sampled image)",
        set: |q, v| {
            q.curved_search = count(v, 0, 8)?;
            Ok(())
        },
        get: |q| q.curved_search.to_string(),
    },
    Knob {
        name: "tessellation",
        values: "1..=32 subdivisions",
        default: "4",
        doc: "curved-reflector: each environment triangle is split into tessellation² triangles before its vertices are moved to their virtual positions (survey Table 1: geometry transformation needs high tessellation, since the reflection of a straight edge in a curved mirror is curved)",
        set: |q, v| {
            q.tessellation = count(v, 1, 32)?;
            Ok(())
        },
        get: |q| q.tessellation.to_string(),
    },
    Knob {
        name: "msaa_shading",
        values: "sample|pixel",
        default: "sample",
        doc: "with aa=msaaN: the specular camera passes shade every sample (reflections inside curved objects anti-aliased too) or once per pixel (edges only); diffuse surfaces always shade once per pixel",
        set: |q, v| {
            q.msaa_per_sample = one_of(v, MSAA_SHADING)?;
            Ok(())
        },
        get: |q| name_of(q.msaa_per_sample, MSAA_SHADING),
    },
    Knob {
        name: "map_updates",
        values: "on_change|always",
        default: "on_change",
        doc: "frames over time: regenerate a map only when the objects, materials or lights it depends on changed, or every frame (benchmarks)",
        set: |q, v| {
            q.map_updates_always = one_of(v, MAP_UPDATES)?;
            Ok(())
        },
        get: |q| name_of(q.map_updates_always, MAP_UPDATES),
    },
    Knob {
        name: "planner",
        values: "accuracy|speed",
        default: "accuracy",
        doc: "what --method auto optimises: the most accurate method per object, or a cheaper rung (single distance maps, image-space refraction)",
        set: |q, v| {
            q.planner = one_of(v, PLANNERS)?;
            Ok(())
        },
        get: |q| name_of(q.planner, PLANNERS),
    },
    Knob {
        name: "caustics",
        values: "off|splat|triangles",
        default: "triangles",
        doc: "caustics (§6): photons from each punctual light traced through each caustic generator in its maps, stored as hits in cube-map space, then splatted (photon splatting) or meshed into caustic triangles (flux over area) into a light cube map around the generator, filtered, and projected onto diffuse surfaces with a distance test; the CPU reference adds light-traced caustics",
        set: |q, v| {
            q.caustics = one_of(v, CAUSTICS)?;
            Ok(())
        },
        get: |q| name_of(q.caustics, CAUSTICS),
    },
    Knob {
        name: "photons",
        values: "32..=2048 texels",
        default: "128",
        doc: "caustics: edge of each photon hit location image (photons² per light and generator view); caustic triangles keep 64 bytes per triangle in one storage buffer, within the device's maxStorageBufferRange (lavapipe's 128 MiB: 1024² photons for one photon layer, 592² for three)",
        set: |q, v| {
            q.photons = count(v, 32, 2048)?;
            Ok(())
        },
        get: |q| q.photons.to_string(),
    },
    Knob {
        name: "splat_size",
        values: "0.5..=16 texels",
        default: "2",
        doc: "caustics=splat: radius of each photon's splat (an Epanechnikov kernel normalised to the photon's power) in light-cube texels",
        set: |q, v| {
            q.splat_size = real(v, 0.5, 16.0)?;
            Ok(())
        },
        get: |q| q.splat_size.to_string(),
    },
    Knob {
        name: "caustic_filter",
        values: "0..=8 texels",
        default: "1",
        doc: "caustics: radius of the box filter over each light cube face before projection (0: none)",
        set: |q, v| {
            q.caustic_filter = count(v, 0, 8)?;
            Ok(())
        },
        get: |q| q.caustic_filter.to_string(),
    },
    Knob {
        name: "caustic_distance_test",
        values: "on|off",
        default: "on",
        doc: "caustics: a diffuse point takes the light cube map's irradiance only where its distance from the generator matches the receiver distance map (off: light leaks behind occluders, for comparison)",
        set: |q, v| {
            q.caustic_distance_test = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.caustic_distance_test, ON_OFF),
    },
    Knob {
        name: "caustic_orientation",
        values: "on|off",
        default: "on",
        doc: "caustics: the receiver-orientation factor of the projection, E = J·cos α/D² (off: cos α = 1, every receiver taken as facing the generator; wrong at grazing angles)",
        set: |q, v| {
            q.caustic_orientation = one_of(v, ON_OFF)?;
            Ok(())
        },
        get: |q| name_of(q.caustic_orientation, ON_OFF),
    },
    Knob {
        name: "caustic_space",
        values: "cube|light",
        default: "cube",
        doc: "caustics: photon hits stored and projected in cube-map space, one light cube map per generator around its reference point (UPSK08), or in light space, one per generator and point or spot light around the light (the shadow-map space of SP07; directional lights stay in cube-map space): their distance tests leak differently (BENCHMARKS.md)",
        set: |q, v| {
            q.caustic_space = one_of(v, CAUSTIC_SPACES)?;
            Ok(())
        },
        get: |q| name_of(q.caustic_space, CAUSTIC_SPACES),
    },
    Knob {
        name: "caustic_paths",
        values: "both|refracted",
        default: "both",
        doc: "caustics: a dielectric generator's photons follow both Fresnel branches, each its own photon image (the reflected one is weak and wide: 4 % at normal incidence), or only the refracted one; mirrors reflect either way",
        set: |q, v| {
            q.caustic_reflections = one_of(v, CAUSTIC_PATHS)?;
            Ok(())
        },
        get: |q| name_of(q.caustic_reflections, CAUSTIC_PATHS),
    },
    Knob {
        name: "reference_photons",
        values: "1000..=100000000 photons",
        default: "1000000",
        doc: "CPU reference: photons traced from each punctual light into each caustic generator's bounding cone for its caustics",
        set: |q, v| {
            q.reference_photons = count(v, 1000, 100_000_000)?;
            Ok(())
        },
        get: |q| q.reference_photons.to_string(),
    },
    Knob {
        name: "caustic_radius",
        values: "auto|metres",
        default: "auto",
        doc: "CPU reference: radius of the caustics' density estimate on the receivers (Epanechnikov kernel); auto: 0.5 % of the scene's bounding-box diagonal",
        set: |q, v| {
            q.caustic_radius = match v {
                "auto" => None,
                v => match v.trim().parse::<f32>() {
                    Ok(r) if r > 0.0 && r.is_finite() => Some(r),
                    _ => return Err(format!("'{}' is not auto or a radius > 0 in metres", clip(v))),
                },
            };
            Ok(())
        },
        get: |q| q.caustic_radius.map_or("auto".into(), |r| r.to_string()),
    },
    Knob {
        name: "layers",
        values: "auto|1..=16",
        default: "auto",
        doc: "layered maps (§4.5): depth-peeled layers; auto = the scene's depth complexity from the map's reference point, measured on the GPU (at most 16)",
        set: |q, v| {
            q.layers = if v == "auto" { None } else { Some(count(v, 1, MAX_LAYERS)?) };
            Ok(())
        },
        get: |q| q.layers.map_or("auto".into(), |l| l.to_string()),
    },
    Knob {
        name: "layered_branches",
        values: "both|strongest",
        default: "both",
        doc: "layered maps: a dielectric hit follows both Fresnel branches while the shader's ray stack (8 rays) has room, else the stronger one carrying both weights; strongest: always the stronger one",
        set: |q, v| {
            q.layered_both = one_of(v, LAYERED_BRANCHES)?;
            Ok(())
        },
        get: |q| name_of(q.layered_both, LAYERED_BRANCHES),
    },
    Knob {
        name: "debug_fault",
        values: "none|flip_reflection",
        default: "none",
        doc: "test knob (never for images): flip_reflection breaks the distance method on purpose (and distance-multi, which shares its camera pass distance.search, §4.2), the pass tracing the reflected ray's opposite direction, so that tests can check that the per-object errors see a broken method and the rest of the image does not move (issue 15); the C ABI's string setter takes it too",
        set: |q, v| {
            q.debug_fault = one_of(v, DEBUG_FAULTS)?;
            Ok(())
        },
        get: |q| name_of(q.debug_fault, DEBUG_FAULTS),
    },
];

const LAYERED_BRANCHES: &[(&str, bool)] = &[("both", true), ("strongest", false)];
const DEBUG_FAULTS: &[(&str, DebugFault)] = &[("none", DebugFault::None), ("flip_reflection", DebugFault::FlipReflection)];

impl Default for Quality {
    fn default() -> Self {
        Quality {
            cube_size: 256,
            cube_precision: Precision::Half,
            cube_mode: CubeMode::SixPasses,
            fresnel: FresnelMode::Schlick,
            ref_point: None,
            shadow_size: 512,
            depth: 16,
            cycles: 4,
            spp: 16,
            linear_steps: 16,
            secant_steps: 2,
            binary_steps: 0,
            parallax_iterations: 1,
            search_tolerance: 1e-3,
            internal_bounces: 2,
            frame_latency: false,
            proxy_radius: None,
            planner: Planner::Accuracy,
            ray_budget: 4,
            bvh_stackless: false,
            grid_density: 2.0,
            grid_skip: true,
            kd_max_depth: 0,
            kd_leaf_size: 4,
            kd_restart: false,
            tile_size: 16,
            ray_stats: false,
            map_updates_always: false,
            aa: Aa::Off,
            msaa_per_sample: true,
            mirror_budget: 8,
            map_mirrors: true,
            object_ids: false,
            shadows: true,
            geometry_image: 128,
            curved_search: 3,
            tessellation: 4,
            caustics: Caustics::Triangles,
            photons: 128,
            splat_size: 2.0,
            caustic_filter: 1,
            caustic_distance_test: true,
            caustic_orientation: true,
            caustic_reflections: true,
            caustic_space: CausticSpace::Cube,
            reference_photons: 1_000_000,
            caustic_radius: None,
            layers: None,
            layered_both: true,
            debug_fault: DebugFault::None,
        }
    }
}

pub fn knob(name: &str) -> Option<&'static Knob> {
    KNOBS.iter().find(|k| k.name == name)
}

impl Quality {
    /// Sets one knob from its textual value.
    pub fn set(&mut self, key: &str, value: &str) -> Result<()> {
        let Some(k) = knob(key) else {
            let known: Vec<_> = KNOBS.iter().map(|k| k.name).collect();
            return Err(Error::invalid("knob", format!("unknown knob '{}' (known: {})", clip(key), known.join(", "))));
        };
        (k.set)(self, value.trim()).map_err(|m| Error::invalid(format!("knob {key}"), format!("{m} ({})", k.values)))
    }

    /// A knob's value in the form `set` accepts ("" for an unknown name).
    pub fn get(&self, key: &str) -> String {
        knob(key).map_or(String::new(), |k| (k.get)(self))
    }

    /// Parses `key=value`.
    pub fn set_pair(&mut self, pair: &str) -> Result<()> {
        let (k, v) = pair.split_once('=').ok_or_else(|| Error::invalid("knob", format!("'{}' is not key=value", clip(pair))))?;
        self.set(k.trim(), v.trim())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knobs_parse_and_reject() {
        let mut q = Quality::default();
        q.set_pair("cube_size=128").unwrap();
        q.set_pair("fresnel=exact").unwrap();
        q.set_pair("ref_point=1,2,3").unwrap();
        assert_eq!((q.cube_size, q.fresnel, q.ref_point), (128, FresnelMode::Exact, Some(Vec3::new(1.0, 2.0, 3.0))));
        assert!(q.set_pair("cube_size=8").is_err());
        assert!(q.set_pair("cube_size=abc").is_err());
        assert!(q.set_pair("ref_point=1,nan,3").is_err());
        assert!(q.set_pair("warp=9").is_err());
        assert!(q.set_pair("cube_size").is_err());
        q.set_pair("depth=1").unwrap();
        q.set_pair("spp=9").unwrap();
        q.set_pair("cycles=3").unwrap();
        assert_eq!((q.depth, q.spp, q.cycles), (1, 9, 3));
        for bad in ["depth=0", "depth=65", "spp=8", "spp=0", "spp=2048", "spp=x", "cycles=0", "cycles=17", "planner=fast"] {
            assert!(q.set_pair(bad).is_err(), "{bad}");
        }
        for k in KNOBS {
            let mut q = Quality::default();
            q.set(k.name, k.default).unwrap();
            assert_eq!(q, Quality::default(), "documented default of {} is the real default", k.name);
            assert_eq!(Quality::default().get(k.name), k.default, "get() of {} prints the documented default", k.name);
        }
    }

    #[test]
    fn messages_name_the_range() {
        let mut q = Quality::default();
        let e = q.set("linear_steps", "-32").unwrap_err().to_string();
        assert!(e.contains("-32 is outside 0..=256"), "{e}");
        let e = q.set("search_tolerance", "NaN").unwrap_err().to_string();
        assert!(e.contains("NaN is not a number in 0..=1"), "{e}");
        let long = "9".repeat(100_000);
        assert!(q.set("cube_size", &long).unwrap_err().to_string().len() < 300);
    }
}
