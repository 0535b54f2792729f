//! Scene → Plan: "model only what the scene requires". The plan names, per specular
//! object, the method and the maps it needs, and the passes a frame records. A scene
//! without specular objects gets no environment-map pass and no cube map; one without
//! punctual lights no shadow map.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::quality::Quality;
use crate::scene::{LightKind, Scene};

/// The rendering methods. Names are the CLI's `--method` values, a stable interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Method {
    /// Classic environment mapping (survey §3, §3.1).
    Envmap,
    /// The exact CPU reference (`crate::reference`): Whitted ray tracing in the original
    /// geometry, in f64. Ground truth for the tests and for `specula tradeoff`; it has no
    /// GPU passes, and `Renderer::new` refuses its plan.
    Reference,
}

impl Method {
    /// Every method, GPU methods first; a new method joins the CLI, the demo and the
    /// trade-off study by being listed here.
    pub const ALL: &'static [Method] = &[Method::Envmap, Method::Reference];

    pub fn name(self) -> &'static str {
        match self {
            Method::Envmap => "envmap",
            Method::Reference => "reference",
        }
    }

    /// Whether the method renders on the GPU (through `Renderer`); the reference renders
    /// on the CPU (`reference::render_reference`).
    pub fn is_gpu(self) -> bool {
        !matches!(self, Method::Reference)
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
        Method::Envmap => scene
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
    if !envmaps.is_empty() {
        passes.push("envmap.generate");
    }
    passes.push("scene.direct");
    if !envmaps.is_empty() {
        passes.push("envmap.shade");
    }
    let diag = scene.bounds().diagonal();
    let cube_near = if diag > 0.0 { diag * 1e-5 } else { 1e-4 };
    Plan { method, quality: quality.clone(), shadow_cubes, shadow_planes, envmaps, passes, cube_near }
}
