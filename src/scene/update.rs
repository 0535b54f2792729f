//! Changes to a loaded scene between frames (an engine moves objects every frame): an
//! object's world transform, a material's parameters, a light. Each setter validates like
//! the initial load does and leaves the scene as it was when it refuses; none changes the
//! scene's topology (meshes, triangles, material kinds, light kinds), so that a renderer can
//! take the change in place (`Renderer::update`).

use std::sync::Arc;

use glam::{Mat3, Mat4, Vec3};

use super::{validate_transform, Light, LightKind, Material, Mesh, Scene, SurfaceKind};
use crate::error::{Error, Result};

/// An object's geometry in object space (before its world transform).
#[derive(Clone, Debug, PartialEq)]
pub struct Rest {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub reference_point: Option<Vec3>,
}

impl Rest {
    /// The object-space geometry of `m`: its data as stored when its transform is the
    /// identity, else the data carried back through the inverse transform (once; every
    /// later transform starts from this copy, so rounding does not accumulate).
    fn of(m: &Mesh) -> Rest {
        if m.world == Mat4::IDENTITY {
            return Rest { positions: m.positions.clone(), normals: m.normals.clone(), reference_point: m.reference_point };
        }
        let inv = m.world.inverse();
        // Normals went through the inverse transpose; back through the transpose.
        let back = Mat3::from_mat4(m.world).transpose();
        Rest {
            positions: m.positions.iter().map(|p| inv.transform_point3(*p)).collect(),
            normals: m.normals.iter().map(|n| (back * *n).normalize_or_zero()).collect(),
            reference_point: m.reference_point.map(|p| inv.transform_point3(p)),
        }
    }
}

impl Mesh {
    /// The object-space positions (before the world transform): the stored positions while
    /// the object has not moved from an identity transform, else those it was moved from.
    pub fn object_positions(&self) -> Vec<Vec3> {
        match &self.rest {
            Some(r) => r.positions.clone(),
            None if self.world == Mat4::IDENTITY => self.positions.clone(),
            None => Rest::of(self).positions,
        }
    }
}

/// Whether a material keeps its class (diffuse, mirror, solid or thin dielectric), which
/// decides the methods that may serve its objects.
fn same_kind(a: &SurfaceKind, b: &SurfaceKind) -> bool {
    kind_name(a) == kind_name(b)
}

fn kind_name(k: &SurfaceKind) -> &'static str {
    match k {
        SurfaceKind::Diffuse => "diffuse",
        SurfaceKind::Mirror { .. } => "mirror",
        SurfaceKind::Dielectric { thin: false, .. } => "solid dielectric",
        SurfaceKind::Dielectric { thin: true, .. } => "thin dielectric",
    }
}

fn light_kind_name(k: LightKind) -> &'static str {
    match k {
        LightKind::Point => "point",
        LightKind::Spot { .. } => "spot",
        LightKind::Directional => "directional",
    }
}

impl Scene {
    /// Sets object `index`'s world transform (column-major object → world, like glTF's
    /// node matrix and the C ABI's `transform`). Refused, with the scene unchanged: an
    /// unknown object, a transform that is not finite or not invertible, one that mirrors
    /// when the object's first transform did not (or the other way round: the winding of
    /// its triangles would flip), and one that carries a vertex to infinity.
    pub fn set_object_transform(&mut self, index: usize, world: Mat4) -> Result<()> {
        let count = self.meshes.len();
        let m = self
            .meshes
            .get(index)
            .ok_or_else(|| Error::invalid("object", format!("{index} is out of range (the scene has {count} objects)")))?;
        validate_transform(&world, &format!("object '{}'", m.name))?;
        let what = format!("object '{}': transform", m.name);
        let (old, new) = (Mat3::from_mat4(m.world).determinant(), Mat3::from_mat4(world).determinant());
        if (old < 0.0) != (new < 0.0) {
            return Err(Error::invalid(
                what,
                format!("determinant {new} has the opposite sign of the object's first transform ({old}): a mirroring change would flip its triangles' winding"),
            ));
        }
        let rest = m.rest.clone().unwrap_or_else(|| Arc::new(Rest::of(m)));
        // Only what `transform` moves (the winding stays: the determinant's sign does).
        let mut moved = Mesh {
            positions: rest.positions.clone(),
            normals: rest.normals.clone(),
            reference_point: rest.reference_point,
            ..Mesh::default()
        };
        moved.transform(world);
        if let Some(v) = moved.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::invalid(what, format!("carries vertex {v} to {} (not finite)", moved.positions[v])));
        }
        let m = &mut self.meshes[index];
        m.positions = moved.positions;
        m.normals = moved.normals;
        m.reference_point = moved.reference_point;
        m.world = world;
        m.rest = Some(rest);
        Ok(())
    }

    /// Hides object `index` (drawn nowhere, hit by no ray) or shows it again.
    pub fn set_object_visible(&mut self, index: usize, visible: bool) -> Result<()> {
        let count = self.meshes.len();
        let m = self
            .meshes
            .get_mut(index)
            .ok_or_else(|| Error::invalid("object", format!("{index} is out of range (the scene has {count} objects)")))?;
        m.hidden = !visible;
        Ok(())
    }

    /// Replaces material `index`'s parameters (ν, κ, ior, base colour, emission, specular
    /// colour and factor, textures), validated like [`Scene::add_material`]. Its kind stays:
    /// a mirror stays a mirror (a new kind changes which method serves the objects: make a
    /// new plan for that).
    pub fn set_material(&mut self, index: usize, m: Material) -> Result<()> {
        let count = self.materials.len();
        let old = self
            .materials
            .get(index)
            .ok_or_else(|| Error::invalid("material", format!("{index} is out of range (the scene has {count} materials)")))?;
        if !same_kind(&old.kind, &m.kind) {
            return Err(Error::invalid(
                format!("material '{}': kind", old.name),
                format!("is {}, the update makes it {}: a change of kind needs a new plan", kind_name(&old.kind), kind_name(&m.kind)),
            ));
        }
        if old.medium().is_some() != m.medium().is_some() {
            return Err(Error::invalid(
                format!("material '{}': graded_index", old.name),
                "a varying index appearing or going away changes which methods can serve its objects (curved rays): that needs a new plan",
            ));
        }
        m.validate()?;
        for (field, t) in [("base_color_texture", m.base_color_texture), ("emissive_texture", m.emissive_texture)] {
            if let Some(t) = t.filter(|&t| t >= self.textures.len()) {
                return Err(Error::invalid(
                    format!("material '{}': {field}", m.name),
                    format!("texture {t} out of range ({} textures)", self.textures.len()),
                ));
            }
        }
        self.materials[index] = m;
        Ok(())
    }

    /// Replaces light `index` (position, direction, colour × intensity, range, cone),
    /// validated like [`Scene::add_light`]. Its kind stays (point, spot and directional
    /// lights get different shadow maps).
    pub fn set_light(&mut self, index: usize, l: Light) -> Result<()> {
        let count = self.lights.len();
        let old = self
            .lights
            .get(index)
            .ok_or_else(|| Error::invalid("light", format!("{index} is out of range (the scene has {count} lights)")))?;
        if std::mem::discriminant(&old.kind) != std::mem::discriminant(&l.kind) {
            return Err(Error::invalid(
                format!("light '{}': kind", old.name),
                format!(
                    "is {}, the update makes it {}: a change of kind needs a new plan",
                    light_kind_name(old.kind),
                    light_kind_name(l.kind)
                ),
            ));
        }
        l.validate()?;
        self.lights[index] = Light { direction: l.direction.normalize_or_zero(), ..l };
        Ok(())
    }
}

/// What changed from one state of a scene to the next (same topology): the renderer's
/// dependency tracking reads it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Changes {
    /// Objects whose geometry (positions or normals) or visibility changed.
    pub moved: Vec<usize>,
    pub materials: Vec<usize>,
    pub lights: Vec<usize>,
    pub camera: bool,
}

impl Changes {
    /// Everything, as for a first frame.
    pub fn is_empty(&self) -> bool {
        self.moved.is_empty() && self.materials.is_empty() && self.lights.is_empty() && !self.camera
    }

    /// Adds `o`'s changes (a frame may see several updates).
    pub fn merge(&mut self, o: &Changes) {
        for (a, b) in [(&mut self.moved, &o.moved), (&mut self.materials, &o.materials), (&mut self.lights, &o.lights)] {
            for &i in b {
                if !a.contains(&i) {
                    a.push(i);
                }
            }
            a.sort_unstable();
        }
        self.camera |= o.camera;
    }

    /// The differences between `old` and `new`, or why `new` is not the same scene moved
    /// on: other meshes, triangles, textures, material or light kinds, environment.
    pub fn between(old: &Scene, new: &Scene) -> Result<Changes> {
        let refuse = |what: String| {
            Err(Error::invalid("scene update", format!("{what}: a renderer takes only changes that keep the topology; make a new one")))
        };
        if old.meshes.len() != new.meshes.len() {
            return refuse(format!("{} objects, the renderer's scene has {}", new.meshes.len(), old.meshes.len()));
        }
        if old.materials.len() != new.materials.len() || old.lights.len() != new.lights.len() {
            return refuse(format!(
                "{} materials and {} lights, the renderer's scene has {} and {}",
                new.materials.len(),
                new.lights.len(),
                old.materials.len(),
                old.lights.len()
            ));
        }
        if old.textures.len() != new.textures.len() || old.environment.is_some() != new.environment.is_some() {
            return refuse("other textures or environment".into());
        }
        let mut c = Changes::default();
        for (i, (a, b)) in old.meshes.iter().zip(&new.meshes).enumerate() {
            if a.indices != b.indices || a.positions.len() != b.positions.len() || a.material != b.material || a.uvs != b.uvs {
                return refuse(format!("object '{}' has other triangles, uvs or material", b.name));
            }
            if a.positions != b.positions || a.normals != b.normals || a.reference_point != b.reference_point || a.hidden != b.hidden {
                c.moved.push(i);
            }
        }
        for (i, (a, b)) in old.materials.iter().zip(&new.materials).enumerate() {
            if !same_kind(&a.kind, &b.kind) {
                return refuse(format!("material '{}' changes kind", b.name));
            }
            if a != b {
                c.materials.push(i);
            }
        }
        for (i, (a, b)) in old.lights.iter().zip(&new.lights).enumerate() {
            if std::mem::discriminant(&a.kind) != std::mem::discriminant(&b.kind) {
                return refuse(format!("light '{}' changes kind", b.name));
            }
            if a != b {
                c.lights.push(i);
            }
        }
        c.camera = old.camera != new.camera;
        Ok(c)
    }
}
