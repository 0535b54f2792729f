//! The scene the renderer consumes: world-space meshes, classified materials, punctual
//! lights, a camera and an optional environment map. Loaded from glTF (`load`) or built
//! in code (`Scene::add_mesh` …), which is what the C ABI and the tests do.
//!
//! Conventions are glTF's: right-handed, +Y up, metres, the camera looks down −Z.
//! Radiometry: a punctual light's intensity is used 1:1 as radiant intensity [W/sr]
//! (point, spot) or irradiance [W/m²] (directional); emission and images are linear
//! radiance.

pub mod animation;
mod environment;
pub mod faces;
mod fingerprint;
pub mod gltf;
pub mod medium;
pub mod shapes;
pub mod update;

pub use self::gltf::load;
pub use environment::*;
pub use fingerprint::{Fingerprint, Kept};

use glam::{Mat3, Mat4, Vec2, Vec3};

use crate::error::{Error, Result};

/// How a surface scatters light, as the survey classifies it (§1.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceKind {
    /// Emission plus Lambertian reflection of punctual lights.
    Diffuse,
    /// Ideal mirror (glTF: metallic 1, roughness 0). Index of refraction ν and extinction
    /// coefficient κ per RGB channel; F0 follows from survey eq. 2.
    Mirror { nu: Vec3, kappa: Vec3 },
    /// Ideal dielectric (glTF: transmission 1, roughness 0) of index of refraction `ior`
    /// relative to the outside medium. `thin` surfaces (KHR_materials_volume thickness 0)
    /// are thin-walled: light passes through without bending.
    Dielectric { ior: f32, thin: bool },
}

impl SurfaceKind {
    pub fn is_specular(&self) -> bool {
        !matches!(self, SurfaceKind::Diffuse)
    }
    pub fn label(&self) -> &'static str {
        match self {
            SurfaceKind::Diffuse => "diffuse",
            SurfaceKind::Mirror { .. } => "mirror",
            SurfaceKind::Dielectric { thin: true, .. } => "dielectric (thin-walled)",
            SurfaceKind::Dielectric { thin: false, .. } => "dielectric (solid)",
        }
    }
}

/// A material after classification. Textures index `Scene::textures`.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear base colour (albedo of diffuse surfaces).
    pub base_color: Vec3,
    pub base_color_texture: Option<usize>,
    /// Emitted radiance (emissive factor × KHR_materials_emissive_strength).
    pub emissive: Vec3,
    pub emissive_texture: Option<usize>,
    pub kind: SurfaceKind,
    /// KHR_materials_specular: scales the Fresnel reflectance of dielectrics
    /// (F0 colour and the strength at every angle); (1,1,1) and 1 without it.
    pub specular_color: Vec3,
    pub specular_factor: f32,
    /// KHR_materials_volume: absorption coefficient σ per RGB channel [1/m] of a solid
    /// dielectric's inside (Beer–Lambert: a path of length d inside keeps exp(−σd) of its
    /// radiance); zero without absorption, ignored on other surfaces. From glTF's
    /// attenuation colour c and distance d: σ = −ln c / d ([`Material::absorption_from`]).
    pub absorption: Vec3,
    /// KHR_materials_dispersion: 20 / V (V the Abbe number) of a solid dielectric, whose
    /// index `ior` is then the d line's and each RGB channel refracts with its own
    /// ([`Material::channel_iors`]); 0: none.
    pub dispersion: f32,
    /// A solid dielectric whose index varies in space (survey §6.5; [`medium::GradedIndex`]:
    /// `ior` is its value at the field's origin): rays inside it curve. `None`: uniform.
    pub graded: Option<medium::GradedIndex>,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: String::new(),
            base_color: Vec3::ONE,
            base_color_texture: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            kind: SurfaceKind::Diffuse,
            specular_color: Vec3::ONE,
            specular_factor: 1.0,
            absorption: Vec3::ZERO,
            dispersion: 0.0,
            graded: None,
        }
    }
}

impl Material {
    /// σ = −ln c / d of KHR_materials_volume's `attenuationColor` c and `attenuationDistance`
    /// d (the distance at which light of colour 1 is left with c): zero for d = ∞ (glTF's
    /// default) or c = 1; a channel of c = 0 absorbs as c = 10⁻³⁰ does (σ ≈ 69/d), so that
    /// σ stays finite. `None` for d ≤ 0, NaN, or c outside 0..=1.
    pub fn absorption_from(color: Vec3, distance: f32) -> Option<Vec3> {
        if distance.is_nan() || distance <= 0.0 || !color.is_finite() || color.min_element() < 0.0 || color.max_element() > 1.0 {
            return None;
        }
        if distance.is_infinite() {
            return Some(Vec3::ZERO);
        }
        let sigma = |c: f32| (-(c.max(1e-30) as f64).ln() / distance as f64).max(0.0) as f32;
        let s = Vec3::new(sigma(color.x), sigma(color.y), sigma(color.z));
        s.is_finite().then_some(s)
    }

    /// The wavelengths [nm] the RGB channels refract at under dispersion: Fraunhofer's C, d
    /// and F lines, the ones the Abbe number V = (n_d − 1)/(n_F − n_C) is defined by.
    pub const CHANNEL_WAVELENGTHS: [f32; 3] = [656.3, 587.6, 486.1];

    /// The index of refraction per RGB channel: `ior` for each without dispersion; with it,
    /// KHR_materials_dispersion's n(λ) = max(n + (n − 1)/V · (523655/λ² − 1.5168), 1) at
    /// [`Material::CHANNEL_WAVELENGTHS`] (below 1 the formula is kept above 0 instead). `None`
    /// for surfaces that do not refract.
    pub fn channel_iors(&self) -> Option<Vec3> {
        let SurfaceKind::Dielectric { ior, thin } = self.kind else { return None };
        if thin || self.dispersion <= 0.0 {
            return Some(Vec3::splat(ior));
        }
        let v = 20.0 / self.dispersion as f64;
        let n = ior as f64;
        let at = |lambda: f32| {
            let x = n + (n - 1.0) / v * (523655.0 / (lambda as f64 * lambda as f64) - 1.5168);
            (if n >= 1.0 { x.max(1.0) } else { x.max(1e-3) }) as f32
        };
        let [r, g, b] = Self::CHANNEL_WAVELENGTHS;
        Some(Vec3::new(at(r), at(g), at(b)))
    }

    /// Whether the channels refract differently: a solid dielectric with dispersion.
    pub fn disperses(&self) -> bool {
        matches!(self.kind, SurfaceKind::Dielectric { thin: false, ior } if ior != 1.0) && self.dispersion > 0.0
    }

    /// The index field of a solid dielectric whose index varies (`graded`), else `None`.
    pub fn medium(&self) -> Option<&medium::GradedIndex> {
        match self.kind {
            SurfaceKind::Dielectric { thin: false, .. } => self.graded.as_ref(),
            _ => None,
        }
    }

    /// The index at `p`: `ior`, or the graded field's value there.
    pub fn ior_at(&self, p: glam::DVec3) -> Option<f64> {
        let SurfaceKind::Dielectric { ior, .. } = self.kind else { return None };
        Some(self.medium().map_or(ior as f64, |f| f.index(ior as f64, p).0))
    }

    /// Whether light inside the surface's volume is absorbed: a solid dielectric with σ > 0.
    pub fn absorbs(&self) -> bool {
        matches!(self.kind, SurfaceKind::Dielectric { thin: false, .. }) && self.absorption.max_element() > 0.0
    }
}

/// An RGBA8 texture whose colour channels are sRGB-encoded (decoded on sampling).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

/// One drawable: a triangle list in world space with one material.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
    pub material: usize,
    /// Reference point for the maps of a specular object (§3); `None`: chosen by the
    /// planner (the centre of the mesh's bounding box unless that lies inside another
    /// object).
    pub reference_point: Option<Vec3>,
    /// Other names that address this object (`--object NAME=METHOD`, the C ABI): the glTF
    /// mesh name when the object is named after its node.
    pub aliases: Vec<String>,
    /// The method the scene file asks for (`extras.specula.method`), if any.
    pub method: Option<String>,
    /// The object-to-world transform its positions carry (every [`Mesh::transform`]
    /// composed: the glTF node's world matrix, the C ABI's `transform`); identity for
    /// geometry given in world space. [`Scene::set_object_transform`] replaces it.
    pub world: Mat4,
    /// The geometry in object space, kept once the object has been moved (see
    /// `scene::update`), so that every new transform starts from the same data.
    pub rest: Option<std::sync::Arc<update::Rest>>,
    /// Hidden objects are drawn nowhere (camera, maps, shadows) and hit by no ray; they
    /// keep their place in the scene so that showing them again is an update.
    pub hidden: bool,
}

impl Mesh {
    /// Applies an object-to-world transform in place: positions (and the reference point)
    /// by `world`; normals by the inverse transpose of its linear (upper 3×3) part and
    /// renormalised, or dropped (so that [`Scene::add_mesh`] computes them) when that part
    /// is singular or not finite; a mirroring transform (negative determinant) swaps the
    /// last two indices of every triangle so that the winding stays counter-clockwise.
    /// Used by the glTF importer (node world transforms) and the C ABI (`transform`).
    pub fn transform(&mut self, world: Mat4) {
        self.world = world * self.world;
        for p in &mut self.positions {
            *p = world.transform_point3(*p);
        }
        let linear = Mat3::from_mat4(world);
        let det = linear.determinant();
        if !self.normals.is_empty() {
            if det.is_finite() && det != 0.0 {
                let normal_matrix = linear.inverse().transpose();
                for nrm in &mut self.normals {
                    *nrm = (normal_matrix * *nrm).normalize_or_zero();
                }
            } else {
                self.normals.clear(); // degenerate transform: let add_mesh compute them
            }
        }
        if det < 0.0 {
            for t in self.indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        if let Some(p) = &mut self.reference_point {
            *p = world.transform_point3(*p);
        }
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| Aabb { min: b.min.min(p), max: b.max.max(p) })
    }
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn diagonal(&self) -> f32 {
        if self.is_empty() {
            0.0
        } else {
            (self.max - self.min).length()
        }
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cone angles in radians from the axis, glTF's KHR_lights_punctual semantics.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
    Directional,
}

/// A punctual light (KHR_lights_punctual). `direction` is where the light travels
/// (the node's −Z); unused for point lights.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    pub position: Vec3,
    pub direction: Vec3,
    /// Colour × intensity: radiant intensity [W/sr] or irradiance [W/m²] per channel.
    pub intensity: Vec3,
    /// glTF `range`: beyond it the light contributes nothing; `None` is unbounded.
    pub range: Option<f32>,
}

impl Light {
    /// The one light validation of every entry point: each refusal names the light, the
    /// field and the value as given.
    pub fn validate(&self) -> Result<()> {
        let what = |field: &str| format!("light '{}': {field}", self.name);
        if !self.position.is_finite() {
            return Err(Error::invalid(what("position"), format!("must be finite, got {}", self.position)));
        }
        if !self.intensity.is_finite() || self.intensity.min_element() < 0.0 {
            return Err(Error::invalid(what("intensity"), format!("must be finite and ≥ 0 per channel, got {}", self.intensity)));
        }
        if self.kind != LightKind::Point && (!self.direction.is_finite() || self.direction.length_squared() == 0.0) {
            return Err(Error::invalid(what("direction"), format!("must be finite and non-zero, got {}", self.direction)));
        }
        if let Some(r) = self.range {
            if !(r > 0.0 && r.is_finite()) {
                return Err(Error::invalid(what("range"), format!("must be finite and > 0, got {r}")));
            }
        }
        if let LightKind::Spot { inner_cone, outer_cone } = self.kind {
            if !(0.0 <= inner_cone && inner_cone <= outer_cone && outer_cone <= std::f32::consts::FRAC_PI_2) {
                return Err(Error::invalid(
                    what("cone"),
                    format!("needs 0 ≤ inner ≤ outer ≤ π/2, got inner {inner_cone}, outer {outer_cone}"),
                ));
            }
        }
        Ok(())
    }
}

/// A perspective pinhole camera. The output size's aspect ratio wins over any stored one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    /// World-from-camera rotation+translation; the camera looks down its −Z.
    pub world_from_camera: Mat4,
    /// Vertical field of view in radians.
    pub yfov: f32,
    pub znear: f32,
    /// `None`: infinite far plane.
    pub zfar: Option<f32>,
}

impl Camera {
    /// A camera at `eye` looking at `target` with +Y up.
    pub fn look_at(eye: Vec3, target: Vec3, yfov: f32) -> Camera {
        // Looking straight up or down, +Y cannot be the up vector: take −Z instead.
        let dir = (target - eye).normalize_or(Vec3::NEG_Z);
        let up = if dir.cross(Vec3::Y).length_squared() < 1e-10 { Vec3::NEG_Z } else { Vec3::Y };
        let world_from_camera = Mat4::look_to_rh(eye, dir, up).inverse();
        Camera { position: eye, world_from_camera, yfov, znear: 0.01, zfar: None }
    }
    /// The one camera validation of every entry point (glTF, CLI, C ABI, Rust API): a
    /// camera at `eye` looking at `target` (finite, distinct) with `yfov` and `znear`.
    pub fn checked(eye: Vec3, target: Vec3, yfov: f32, znear: f32) -> Result<Camera> {
        if !eye.is_finite() {
            return Err(Error::invalid("camera.position", format!("must be finite, got {eye}")));
        }
        if !target.is_finite() {
            return Err(Error::invalid("camera.target", format!("must be finite, got {target}")));
        }
        if eye == target {
            return Err(Error::invalid("camera.target", format!("equals camera.position {eye}: there is no view direction")));
        }
        let mut c = Camera::look_at(eye, target, yfov);
        c.znear = znear;
        c.validate()?;
        Ok(c)
    }

    /// Finite transform, 0 < yfov < π, 0 < znear < ∞, zfar > znear: each refusal names the
    /// field and the value.
    pub fn validate(&self) -> Result<()> {
        if !self.position.is_finite() || !self.world_from_camera.is_finite() {
            return Err(Error::invalid("camera.transform", format!("must be finite, got position {}", self.position)));
        }
        if !(self.yfov > 0.0 && self.yfov < std::f32::consts::PI) {
            return Err(Error::invalid("camera.yfov", format!("must be in (0, π) radians, got {}", self.yfov)));
        }
        if !(self.znear > 0.0 && self.znear.is_finite()) {
            return Err(Error::invalid("camera.znear", format!("must be finite and > 0, got {}", self.znear)));
        }
        if let Some(f) = self.zfar {
            if f.is_nan() || f <= self.znear {
                return Err(Error::invalid("camera.zfar", format!("must be > znear ({}), got {f}", self.znear)));
            }
        }
        Ok(())
    }

    pub fn forward(&self) -> Vec3 {
        -self.world_from_camera.z_axis.truncate().normalize()
    }
    pub fn view(&self) -> Mat4 {
        self.world_from_camera.inverse()
    }
}

/// Equirectangular linear-radiance environment map: direction d maps to
/// u = 0.5 + atan2(d.x, −d.z)/2π, v = acos(d.y)/π (v = 0 is straight up).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    pub rgba32f: Vec<f32>,
}

impl EnvironmentMap {
    pub fn constant(c: Vec3) -> EnvironmentMap {
        EnvironmentMap { width: 1, height: 1, rgba32f: vec![c.x, c.y, c.z, 1.0] }
    }

    /// Size matches texels, every texel finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 || self.rgba32f.len() as u64 != self.width as u64 * self.height as u64 * 4 {
            return Err(Error::invalid(
                "environment map",
                format!("{} floats for {}x{} RGBA", self.rgba32f.len(), self.width, self.height),
            ));
        }
        if self.rgba32f.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err(Error::invalid("environment map", "non-finite or negative radiance"));
        }
        Ok(())
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub camera: Option<Camera>,
    /// What rays that leave the scene see; `None` is black.
    pub environment: Option<EnvironmentMap>,
    /// What the importer read but could not render (points, lines, empty primitives, meshes
    /// without primitives), with its place in the file; says why a scene has no triangles.
    pub skipped: Vec<String>,
    /// The file's animations (glTF), if any: [`Scene::set_time`] poses the scene.
    pub animation: Option<animation::Animation>,
}

impl Scene {
    pub fn new() -> Scene {
        Scene::default()
    }

    pub fn add_material(&mut self, m: Material) -> Result<usize> {
        let what = format!("material '{}'", m.name);
        m.validate()?;
        for (field, t) in [("base_color_texture", m.base_color_texture), ("emissive_texture", m.emissive_texture)] {
            if let Some(t) = t.filter(|&t| t >= self.textures.len()) {
                return Err(Error::invalid(
                    format!("{what}: {field}"),
                    format!("texture {t} out of range ({} textures)", self.textures.len()),
                ));
            }
        }
        self.materials.push(m);
        Ok(self.materials.len() - 1)
    }

    /// Adds a world-space mesh; normals are computed (area-weighted) when `normals` is empty,
    /// uvs default to zero. Validates everything: finite positions, in-range indices.
    pub fn add_mesh(&mut self, mut mesh: Mesh) -> Result<usize> {
        let what = format!("mesh '{}'", mesh.name);
        validate_mesh(&mut mesh, self.materials.len(), &what)?;
        self.meshes.push(mesh);
        Ok(self.meshes.len() - 1)
    }

    /// Adds an RGBA8 (sRGB) texture; its texel count must match its size.
    pub fn add_texture(&mut self, t: Texture) -> Result<usize> {
        if t.width == 0 || t.height == 0 || t.rgba8.len() as u64 != t.width as u64 * t.height as u64 * 4 {
            return Err(Error::invalid(
                format!("texture '{}'", t.name),
                format!("{} bytes for {}x{} RGBA8", t.rgba8.len(), t.width, t.height),
            ));
        }
        self.textures.push(t);
        Ok(self.textures.len() - 1)
    }

    /// Sets the environment map after checking its size against its texels.
    pub fn set_environment(&mut self, e: EnvironmentMap) -> Result<()> {
        e.validate()?;
        self.environment = Some(e);
        Ok(())
    }

    pub fn add_light(&mut self, l: Light) -> Result<usize> {
        l.validate()?;
        self.lights.push(Light { direction: l.direction.normalize_or_zero(), ..l });
        Ok(self.lights.len() - 1)
    }

    pub fn bounds(&self) -> Aabb {
        self.meshes.iter().fold(Aabb::EMPTY, |b, m| b.union(&m.bounds()))
    }

    /// Re-checks a scene whose public fields may have been filled by hand: every index in
    /// range, every number finite, attribute arrays of matching length.
    pub fn validate(&self) -> Result<()> {
        for m in &self.materials {
            let what = format!("material '{}'", m.name);
            m.validate()?;
            if [m.base_color_texture, m.emissive_texture].into_iter().flatten().any(|t| t >= self.textures.len()) {
                return Err(Error::invalid(what, "texture index out of range"));
            }
        }
        for t in &self.textures {
            if t.width == 0 || t.height == 0 || t.rgba8.len() as u64 != t.width as u64 * t.height as u64 * 4 {
                return Err(Error::invalid(format!("texture '{}'", t.name), "texel count does not match its size"));
            }
        }
        for m in &self.meshes {
            let what = format!("mesh '{}'", m.name);
            let n = m.positions.len();
            if m.material >= self.materials.len() {
                return Err(Error::invalid(
                    format!("{what}: material"),
                    format!("index {} out of range ({} materials)", m.material, self.materials.len()),
                ));
            }
            if m.normals.len() != n || m.uvs.len() != n || m.indices.len() % 3 != 0 || m.indices.iter().any(|&i| i as usize >= n) {
                return Err(Error::invalid(what, "attribute lengths or indices inconsistent (add meshes with Scene::add_mesh)"));
            }
            if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
                return Err(Error::invalid(format!("{what}: positions"), format!("vertex {i} is not finite, got {}", m.positions[i])));
            }
            if let Some(i) = m.normals.iter().position(|p| !p.is_finite()) {
                return Err(Error::invalid(format!("{what}: normals"), format!("vertex {i} is not finite, got {}", m.normals[i])));
            }
            if let Some(i) = m.uvs.iter().position(|p| !p.is_finite()) {
                return Err(Error::invalid(format!("{what}: uvs"), format!("vertex {i} is not finite, got {}", m.uvs[i])));
            }
            // A graded index must stay positive inside the object (the field is sampled
            // on a 5³ lattice over its box; beyond, it is clamped at medium::MIN_INDEX).
            let mat = &self.materials[m.material];
            if let (Some(f), SurfaceKind::Dielectric { ior, .. }) = (mat.medium(), mat.kind) {
                let b = m.bounds();
                for i in 0..125 {
                    let t = Vec3::new((i % 5) as f32, (i / 5 % 5) as f32, (i / 25) as f32) / 4.0;
                    let p = b.min + (b.max - b.min) * t;
                    let raw = f.unclamped(ior as f64, p.as_dvec3());
                    if raw.is_nan() || raw <= 0.0 {
                        return Err(Error::invalid(
                            format!("material '{}': graded_index", mat.name),
                            format!("the index falls to {raw} at {p} inside object '{}' (it must stay > 0)", m.name),
                        ));
                    }
                }
            }
        }
        if let Some(e) = &self.environment {
            e.validate()?;
        }
        for l in &self.lights {
            l.validate()?;
        }
        if let Some(c) = &self.camera {
            c.validate()?;
        }
        Ok(())
    }

    pub fn specular_meshes(&self) -> impl Iterator<Item = (usize, &Mesh)> {
        self.meshes.iter().enumerate().filter(|(_, m)| self.materials[m.material].kind.is_specular())
    }

    /// The reference point of a mesh's maps (survey §3): its own, or its box centre.
    pub fn reference_point(&self, mesh: usize) -> Vec3 {
        let m = &self.meshes[mesh];
        m.reference_point.unwrap_or_else(|| m.bounds().center())
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Fails with what the scene lacks and where when it has no triangle to render.
    pub fn check_renderable(&self) -> Result<()> {
        if self.triangle_count() > 0 {
            return Ok(());
        }
        let why = if self.skipped.is_empty() {
            "it has no meshes".to_string()
        } else {
            let n = self.skipped.len();
            let shown: Vec<&str> = self.skipped.iter().take(4).map(String::as_str).collect();
            format!("{}{}", shown.join("; "), if n > 4 { format!("; and {} more", n - 4) } else { String::new() })
        };
        Err(Error::invalid("scene", format!("has no triangles to render: {why}")))
    }

    /// A camera that frames the whole scene when none was given.
    pub fn camera_or_default(&self) -> Camera {
        self.camera.unwrap_or_else(|| {
            let b = self.bounds();
            let (c, r) = if b.is_empty() { (Vec3::ZERO, 1.0) } else { (b.center(), b.diagonal().max(1e-3) * 0.5) };
            Camera::look_at(c + Vec3::new(0.0, 0.0, 2.5 * r), c, 45f32.to_radians())
        })
    }
}

impl Material {
    /// The one material validation of every entry point (glTF, the C ABI, the Rust API,
    /// [`Scene::validate`]): each refusal names the material, the field and the value as
    /// given. The glTF importer maps the field onto its JSON path.
    pub fn validate(&self) -> Result<()> {
        let what = |field: &str| format!("material '{}': {field}", self.name);
        let unit = |v: Vec3| v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0;
        let non_negative = |v: Vec3| v.is_finite() && v.min_element() >= 0.0;
        if !unit(self.base_color) {
            return Err(Error::invalid(what("base_color"), format!("must be in 0..=1 per channel, got {}", self.base_color)));
        }
        if !non_negative(self.emissive) {
            return Err(Error::invalid(what("emission"), format!("must be finite and ≥ 0 per channel, got {}", self.emissive)));
        }
        if !non_negative(self.specular_color) {
            return Err(Error::invalid(what("specular_color"), format!("must be finite and ≥ 0 per channel, got {}", self.specular_color)));
        }
        if !(0.0..=1.0).contains(&self.specular_factor) {
            return Err(Error::invalid(what("specular_factor"), format!("must be in 0..=1, got {}", self.specular_factor)));
        }
        if !(self.dispersion >= 0.0 && self.dispersion.is_finite()) {
            return Err(Error::invalid(what("dispersion"), format!("must be finite and ≥ 0 (20 / Abbe number), got {}", self.dispersion)));
        }
        if !non_negative(self.absorption) {
            return Err(Error::invalid(what("absorption"), format!("σ must be finite and ≥ 0 per channel [1/m], got {}", self.absorption)));
        }
        if let Some(f) = &self.graded {
            f.check().map_err(|(field, why)| Error::invalid(what(field), why))?;
            if !matches!(self.kind, SurfaceKind::Dielectric { thin: false, .. }) {
                return Err(Error::invalid(what("graded_index"), "a varying index needs a solid (not thin-walled) dielectric"));
            }
            if self.dispersion > 0.0 {
                return Err(Error::invalid(
                    what("graded_index"),
                    format!("a varying index and dispersion ({}) together are not supported", self.dispersion),
                ));
            }
        }
        match self.kind {
            SurfaceKind::Dielectric { ior, .. } if !(ior > 0.0 && ior.is_finite()) => {
                Err(Error::invalid(what("ior"), format!("index of refraction must be finite and > 0, got {ior}")))
            }
            SurfaceKind::Mirror { nu, .. } if !(nu.is_finite() && nu.min_element() > 0.0) => {
                Err(Error::invalid(what("nu"), format!("ν must be finite and > 0 per channel, got {nu}")))
            }
            SurfaceKind::Mirror { kappa, .. } if !non_negative(kappa) => {
                Err(Error::invalid(what("kappa"), format!("κ must be finite and ≥ 0 per channel, got {kappa}")))
            }
            _ => Ok(()),
        }
    }
}

/// The one object-to-world transform validation of every entry point: finite, and
/// invertible (a zero scale flattens the object: its normals and its maps' reference
/// point are undefined). The C ABI refuses such a transform; the glTF importer skips the
/// node's meshes with a note in [`Scene::skipped`] (glTF uses scale 0 to hide a node).
pub fn validate_transform(world: &Mat4, what: &str) -> Result<()> {
    if !world.is_finite() {
        let bad = world.to_cols_array().iter().position(|v| !v.is_finite()).unwrap_or(0);
        return Err(Error::invalid(
            format!("{what}: transform"),
            format!("must be finite, got {} at column {} row {}", world.to_cols_array()[bad], bad / 4, bad % 4),
        ));
    }
    let det = Mat3::from_mat4(*world).determinant();
    if !(det.is_finite() && det != 0.0) {
        return Err(Error::invalid(
            format!("{what}: transform"),
            format!("must be invertible (no zero scale), got a linear part of determinant {det}"),
        ));
    }
    Ok(())
}

pub(crate) fn validate_mesh(mesh: &mut Mesh, material_count: usize, what: &str) -> Result<()> {
    if mesh.material >= material_count {
        return Err(Error::invalid(
            format!("{what}: material"),
            format!("index {} out of range ({} materials)", mesh.material, material_count),
        ));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::invalid(format!("{what}: positions"), format!("vertex {i} is not finite, got {}", mesh.positions[i])));
    }
    if mesh.positions.is_empty() || mesh.indices.is_empty() {
        return Err(Error::invalid(format!("{what}: indices"), "mesh has no vertices or no triangles"));
    }
    if !mesh.indices.len().is_multiple_of(3) {
        return Err(Error::invalid(
            format!("{what}: indices"),
            format!("{} indices is not a whole number of triangles", mesh.indices.len()),
        ));
    }
    let n = mesh.positions.len();
    if let Some(&i) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(Error::invalid(format!("{what}: indices"), format!("index {i} out of range ({n} vertices)")));
    }
    if let Some(p) = mesh.reference_point {
        if !p.is_finite() {
            return Err(Error::invalid(format!("{what}: reference_point"), format!("must be finite, got {p}")));
        }
    }
    if mesh.normals.is_empty() {
        mesh.normals = compute_normals(&mesh.positions, &mesh.indices);
    } else if mesh.normals.len() != n {
        return Err(Error::invalid(format!("{what}: normals"), format!("{} normals for {} vertices", mesh.normals.len(), n)));
    } else {
        // Non-finite or zero normals (degenerate input) fall back to the computed ones.
        let computed = compute_normals(&mesh.positions, &mesh.indices);
        for (nrm, c) in mesh.normals.iter_mut().zip(computed) {
            *nrm = if nrm.is_finite() && nrm.length_squared() > 0.0 { nrm.normalize() } else { c };
        }
    }
    if mesh.uvs.is_empty() {
        mesh.uvs = vec![Vec2::ZERO; n];
    } else if mesh.uvs.len() != n {
        return Err(Error::invalid(format!("{what}: uvs"), format!("{} uvs for {} vertices", mesh.uvs.len(), n)));
    } else if mesh.uvs.iter().any(|t| !t.is_finite()) {
        let i = mesh.uvs.iter().position(|t| !t.is_finite()).unwrap_or(0);
        return Err(Error::invalid(format!("{what}: uvs"), format!("vertex {i} is not finite, got {}", mesh.uvs[i])));
    }
    Ok(())
}

/// Area-weighted vertex normals; a vertex only on degenerate triangles gets +Y.
pub fn compute_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
        let face = (b - a).cross(c - a); // length = 2 × area
        if face.is_finite() {
            for &i in t {
                n[i as usize] += face;
            }
        }
    }
    n.into_iter().map(|v| v.try_normalize().unwrap_or(Vec3::Y)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            indices: vec![0, 1, 2],
            reference_point: Some(Vec3::X),
            ..Mesh::default()
        }
    }

    #[test]
    fn transform_moves_points_and_keeps_normals_perpendicular() {
        let world = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let mut m = triangle();
        m.normals = vec![Vec3::new(1.0, 1.0, 0.0).normalize(); 3];
        m.transform(world);
        assert_eq!(m.positions, [Vec3::new(1.0, 2.0, 3.0), Vec3::new(3.0, 2.0, 3.0), Vec3::new(1.0, 3.0, 3.0)]);
        assert_eq!(m.reference_point, Some(Vec3::new(3.0, 2.0, 3.0)));
        // The plane x + y = 0 becomes x/2 + y = 0: its normal is (1/2, 1, 0), renormalised.
        assert!((m.normals[0] - Vec3::new(0.5, 1.0, 0.0).normalize()).length() < 1e-6);
        assert_eq!(m.indices, [0, 1, 2]);
    }

    #[test]
    fn mirroring_flips_the_winding_and_singular_drops_the_normals() {
        let mut m = triangle();
        m.transform(Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0)));
        assert_eq!(m.indices, [0, 2, 1]);
        assert_eq!(m.normals[0], Vec3::NEG_Z);
        let mut m = triangle();
        m.transform(Mat4::from_scale(Vec3::new(1.0, 1.0, 0.0)));
        assert!(m.normals.is_empty(), "add_mesh computes them");
    }
}
