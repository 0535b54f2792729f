//! Scene → Plan: "model only what the scene requires". The plan names, per specular
//! object, the method and the maps it needs, and the passes a frame records. A scene
//! without specular objects gets no environment-map pass and no cube map; one without
//! punctual lights no shadow map.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::quality::Quality;
use crate::scene::{LightKind, Scene, SurfaceKind};

/// The rendering methods. Names are the CLI's `--method` values, a stable interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Method {
    /// Classic environment mapping (survey §3, §3.1).
    Envmap,
    /// Localised environment mapping with a proxy sphere around the reference point (§3.2).
    ProxySphere,
    /// Localised environment mapping with a proxy box, the scene's bounding box (§3.2): the
    /// "parallax-corrected cube map" of modern engines.
    ProxyBox,
    /// Single reflections and refractions traced in distance maps (§4.1, §4.2).
    Distance,
    /// Inter-object multiple reflections and refractions: distance maps regenerated in
    /// cycles up to `depth`, or one cycle per frame with `frame_latency` (§4.3).
    DistanceMulti,
    /// Self refraction through refractor maps with total internal reflection, then the
    /// environment's distance map (§4.4).
    RefractorMap,
    /// Wyman's two-pass image-space double refraction (§4.4).
    ImageSpaceRefraction,
    /// The exact CPU reference (`crate::reference`): Whitted ray tracing in the original
    /// geometry, in f64. Ground truth for the tests and for `specula tradeoff`; it has no
    /// GPU passes, and `Renderer::new` refuses its plan.
    Reference,
}

impl Method {
    /// Every method, GPU methods first; a new method joins the CLI, the demo and the
    /// trade-off study by being listed here.
    pub const ALL: &'static [Method] = &[
        Method::Envmap,
        Method::ProxySphere,
        Method::ProxyBox,
        Method::Distance,
        Method::DistanceMulti,
        Method::RefractorMap,
        Method::ImageSpaceRefraction,
        Method::Reference,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::Envmap => "envmap",
            Method::ProxySphere => "proxy-sphere",
            Method::ProxyBox => "proxy-box",
            Method::Distance => "distance",
            Method::DistanceMulti => "distance-multi",
            Method::RefractorMap => "refractor-map",
            Method::ImageSpaceRefraction => "image-space-refraction",
            Method::Reference => "reference",
        }
    }

    /// Whether the method renders on the GPU (through `Renderer`); the reference renders
    /// on the CPU (`reference::render_reference`).
    pub fn is_gpu(self) -> bool {
        !matches!(self, Method::Reference)
    }

    /// Whether the method's maps store distances (§4) rather than radiance alone (§3).
    pub fn uses_distance_maps(self) -> bool {
        matches!(self, Method::Distance | Method::DistanceMulti | Method::RefractorMap | Method::ImageSpaceRefraction)
    }

    pub fn parse(s: &str) -> Result<Method> {
        Method::ALL.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<_> = Method::ALL.iter().map(|m| m.name()).collect();
            Error::invalid("method", format!("unknown method '{s}' (known: {})", names.join(", ")))
        })
    }
}

/// One specular object's cube map.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EnvmapPlan {
    pub mesh: usize,
    /// Index of the cube in the environment-map array.
    pub layer: u32,
    pub reference_point: Vec3,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Plan {
    pub method: Method,
    pub quality: Quality,
    /// Lights that get a cube distance map (point and spot), in cube order.
    pub shadow_cubes: Vec<usize>,
    /// Directional lights, each with a planar distance map, in layer order.
    pub shadow_planes: Vec<usize>,
    pub envmaps: Vec<EnvmapPlan>,
    /// The passes a frame records, in order, by their stable names.
    pub passes: Vec<&'static str>,
    /// Near plane of cube-map rendering (metres), relative to the scene's size.
    pub cube_near: f32,
    /// Distance-map cycles per frame (§4.3): 1, or `depth` for `distance-multi`.
    pub cycles: u32,
    /// Solid dielectrics that get a refractor map (`refractor-map`), in layer order.
    pub refractors: Vec<usize>,
    /// Solid dielectrics shaded by image-space double refraction.
    pub image_space: Vec<usize>,
    /// Proxy geometry (§3.2): sphere radius and box, world space.
    pub proxy_radius: f32,
    pub proxy_box: (Vec3, Vec3),
}

impl Plan {
    /// Whether mesh `m` is a solid dielectric handled by the self-refraction passes.
    pub fn self_refracted(&self, m: usize) -> bool {
        self.refractors.contains(&m) || self.image_space.contains(&m)
    }
}

/// The passes `Method::Reference` reports: one CPU pass, no maps (its shadows are exact
/// shadow rays, its reflections and refractions traced rays).
pub const REFERENCE_PASS: &str = "reference.trace";

pub fn plan(scene: &Scene, method: Method, quality: &Quality) -> Plan {
    if method == Method::Reference {
        let diag = scene.bounds().diagonal();
        return Plan {
            method,
            quality: quality.clone(),
            shadow_cubes: Vec::new(),
            shadow_planes: Vec::new(),
            envmaps: Vec::new(),
            passes: vec![REFERENCE_PASS],
            cube_near: if diag > 0.0 { diag * 1e-5 } else { 1e-4 },
            cycles: 0,
            refractors: Vec::new(),
            image_space: Vec::new(),
            proxy_radius: 0.0,
            proxy_box: (Vec3::ZERO, Vec3::ZERO),
        };
    }
    let mut shadow_cubes = Vec::new();
    let mut shadow_planes = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        match l.kind {
            LightKind::Point | LightKind::Spot { .. } => shadow_cubes.push(i),
            LightKind::Directional => shadow_planes.push(i),
        }
    }
    let envmaps: Vec<EnvmapPlan> = match method {
        Method::Reference => Vec::new(),
        _ => scene
            .specular_meshes()
            .enumerate()
            .map(|(layer, (mesh, _))| EnvmapPlan {
                mesh,
                layer: layer as u32,
                reference_point: quality.ref_point.unwrap_or_else(|| scene.reference_point(mesh)),
            })
            .collect(),
    };
    let has_diffuse = scene.meshes.iter().any(|m| !scene.materials[m.material].kind.is_specular());
    let mut passes = Vec::new();
    if !scene.textures.is_empty() || scene.environment.is_some() {
        passes.push("scene.upload");
    }
    // Shadows matter only where a diffuse surface receives light.
    if has_diffuse && !(shadow_cubes.is_empty() && shadow_planes.is_empty()) {
        passes.push("shadow.generate");
    } else {
        shadow_cubes.clear();
        shadow_planes.clear();
    }
    let solid = |m: usize| matches!(scene.materials[scene.meshes[m].material].kind, SurfaceKind::Dielectric { thin: false, .. });
    let solids: Vec<usize> = envmaps.iter().map(|e| e.mesh).filter(|&m| solid(m)).collect();
    let refractors = if method == Method::RefractorMap { solids.clone() } else { Vec::new() };
    let image_space = if method == Method::ImageSpaceRefraction { solids } else { Vec::new() };
    let cycles = match method {
        Method::DistanceMulti if quality.frame_latency => 1,
        Method::DistanceMulti => quality.depth,
        _ => 1,
    };
    if !envmaps.is_empty() {
        passes.push(if method.uses_distance_maps() { "distance.generate" } else { "envmap.generate" });
    }
    if !refractors.is_empty() {
        passes.push("refractor.generate");
    }
    passes.push("scene.direct");
    if !image_space.is_empty() {
        passes.push("image_space.backfaces");
    }
    let others = envmaps.iter().any(|e| !refractors.contains(&e.mesh) && !image_space.contains(&e.mesh));
    if others {
        passes.push(match method {
            Method::ProxySphere | Method::ProxyBox => "proxy.shade",
            m if m.uses_distance_maps() => "distance.search",
            _ => "envmap.shade",
        });
    }
    if !refractors.is_empty() {
        passes.push("refractor.search");
    }
    if !image_space.is_empty() {
        passes.push("image_space.refract");
    }
    let bounds = scene.bounds();
    let proxy_radius = quality.proxy_radius.unwrap_or_else(|| {
        let half = (bounds.max - bounds.min) * 0.5;
        if bounds.is_empty() {
            1.0
        } else {
            ((half.x + half.y + half.z) / 3.0).max(1e-6)
        }
    });
    let diag = bounds.diagonal();
    let cube_near = if diag > 0.0 { diag * 1e-5 } else { 1e-4 };
    Plan {
        method,
        quality: quality.clone(),
        shadow_cubes,
        shadow_planes,
        envmaps,
        passes,
        cube_near,
        cycles,
        refractors,
        image_space,
        proxy_radius,
        proxy_box: (bounds.min, bounds.max),
    }
}
