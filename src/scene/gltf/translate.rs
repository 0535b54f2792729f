//! The glTF document's meaning, translated into the [`Scene`](crate::scene::Scene): the
//! node hierarchy with its world transforms, meshes (primitive modes, texture coordinates,
//! `extras.specula`), materials (mirror, dielectric, diffuse), punctual lights, the camera.

use glam::{Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Checked;
use gltf::mesh::{Mode, Semantic};
use serde_json::Value;

use super::Importer;
use crate::error::{Error, Result};
use crate::scene::{Camera, Light, LightKind, Material, Mesh, SurfaceKind};

fn parse_extras(extras: &gltf::json::Extras) -> Option<Value> {
    extras.as_ref().and_then(|raw| serde_json::from_str::<Value>(raw.get()).ok())
}

/// `extras.specula` as an object, if present.
fn specula_extras(extras: &gltf::json::Extras, file: &str, field: &str) -> Result<Option<serde_json::Map<String, Value>>> {
    let Some(value) = parse_extras(extras) else {
        return Ok(None);
    };
    match value.get("specula") {
        None => Ok(None),
        Some(Value::Object(map)) => Ok(Some(map.clone())),
        Some(_) => Err(Error::scene(file, format!("{field}.extras.specula"), "must be an object")),
    }
}

fn json_vec3(v: &Value, file: &str, field: &str) -> Result<Vec3> {
    let nums: Option<Vec<f32>> = v.as_array().and_then(|a| a.iter().map(|x| x.as_f64().map(|f| f as f32)).collect());
    match nums {
        Some(n) if n.len() == 3 && n.iter().all(|x| x.is_finite()) => Ok(Vec3::new(n[0], n[1], n[2])),
        _ => Err(Error::scene(file, field, format!("expected an array of 3 finite numbers, got {v}"))),
    }
}

fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::TriangleStrip => "triangle-strip",
        Mode::TriangleFan => "triangle-fan",
        _ => "triangle",
    }
}

/// κ of the ideal reflector that KHR_materials_ior's ior = 0 stands for: with ν = 1 its
/// reflectance is 1 − 4/(4 + κ²) ≥ 1 − 4·10⁻⁸ at normal incidence and closer to 1 elsewhere.
const INFINITE_IOR_KAPPA: f32 = 1e4;

/// ν of a conductor with κ = 0 whose normal-incidence reflectance is `f0`.
fn nu_from_f0(f0: f32) -> f32 {
    let f0 = if f0.is_nan() { 0.0 } else { f0.clamp(0.0, 0.9999) };
    let s = f0.sqrt();
    (1.0 + s) / (1.0 - s)
}

fn apply_texture_transform(uv: Vec2, t: &gltf::texture::TextureTransform) -> Vec2 {
    let [ox, oy] = t.offset();
    let [sx, sy] = t.scale();
    let (s, c) = t.rotation().sin_cos();
    let (u, v) = (uv.x * sx, uv.y * sy);
    Vec2::new(c * u + s * v + ox, -s * u + c * v + oy)
}

/// Maps a `Scene::add_*` validation error into a scene error; `field` picks the glTF field
/// from the suffix of the error's `what` ("mesh 'x': positions" → "positions").
fn map_invalid(file: &str, e: Error, field: impl Fn(Option<&str>) -> String) -> Error {
    match e {
        Error::InvalidInput { what, message } => {
            let suffix = what.rsplit_once(": ").map(|(_, s)| s.to_string());
            Error::scene(file, field(suffix.as_deref()), format!("{what}: {message}"))
        }
        other => other,
    }
}

impl Importer<'_> {
    // ---------------------------------------------------------------- traversal

    pub(super) fn walk(&mut self) -> Result<()> {
        let doc = self.doc;
        let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().map(|n| n.index()).collect(),
            None => {
                let mut is_child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                (0..is_child.len()).filter(|&i| !is_child[i]).collect()
            }
        };
        let nodes: Vec<gltf::Node> = doc.nodes().collect();
        // Iterative depth-first pre-order; `path` holds the ancestors of the current node.
        let mut stack: Vec<(usize, Mat4, usize)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY, 0)).collect();
        let mut path: Vec<usize> = Vec::new();
        let mut on_path = vec![false; nodes.len()];
        while let Some((index, parent, depth)) = stack.pop() {
            for old in path.drain(depth..) {
                on_path[old] = false;
            }
            if on_path[index] {
                return Err(self.err(format!("nodes[{index}]"), "the node hierarchy has a cycle (a node is its own ancestor)"));
            }
            path.push(index);
            on_path[index] = true;
            let node = &nodes[index];
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * local;
            self.visit(node, world, &path)?;
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child.index(), world, depth + 1));
            }
        }
        Ok(())
    }

    fn visit(&mut self, node: &gltf::Node, world: Mat4, path: &[usize]) -> Result<()> {
        let animated = self.doc.animations().len() > 0;
        let (meshes, lights) = (self.scene.meshes.len(), self.scene.lights.len());
        if let Some(mesh) = node.mesh() {
            let mut hidden = false;
            let mut world = world;
            if let Err(Error::InvalidInput { message, .. }) = crate::scene::validate_transform(&world, "node") {
                let field = format!("nodes[{}]", node.index());
                if !world.is_finite() {
                    return Err(self.err(field, format!("the node's world transform {message}")));
                }
                // glTF hides nodes by scale 0. One that an animation scales up later (a node
                // on its path is animated) is imported hidden, in object space, so that
                // `Scene::set_time` can show it; any other is skipped, with a note saying why.
                let on_path = |n: usize| path.contains(&n);
                let animated_path = self.doc.animations().any(|a| a.channels().any(|c| on_path(c.target().node().index())));
                if !animated_path {
                    self.scene.skipped.push(format!("{field} (meshes[{}]): the world transform {message}", mesh.index()));
                    return Ok(());
                }
                hidden = true;
                world = Mat4::IDENTITY;
            }
            if mesh.primitives().len() == 0 {
                self.scene.skipped.push(format!("meshes[{}] (node {}) has no primitives", mesh.index(), node.index()));
            }
            for prim in mesh.primitives() {
                self.import_primitive(node, &mesh, &prim, world)?;
            }
            for m in &mut self.scene.meshes[meshes..] {
                m.hidden = hidden;
            }
        }
        if let Some(light) = node.light() {
            self.import_light(node, &light, world)?;
        }
        // Where the animation will find them: the node path of each object just imported.
        if animated {
            let anim = self.scene.animation.get_or_insert_with(Default::default);
            anim.meshes.extend((meshes..self.scene.meshes.len()).map(|m| (m, path.to_vec())));
            anim.lights.extend((lights..self.scene.lights.len()).map(|l| (l, path.to_vec())));
        }
        if self.scene.camera.is_none() {
            if let Some(cam) = node.camera() {
                self.import_camera(node, cam.index(), world)?;
                if animated && self.scene.camera.is_some() {
                    self.scene.animation.get_or_insert_with(Default::default).camera = Some(path.to_vec());
                }
            }
        }
        Ok(())
    }

    // ---------------------------------------------------------------- meshes

    fn import_primitive(&mut self, node: &gltf::Node, mesh: &gltf::Mesh, prim: &gltf::Primitive, world: Mat4) -> Result<()> {
        let (m, p) = (mesh.index(), prim.index());
        let pfield = format!("meshes[{m}].primitives[{p}]");
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            self.scene.skipped.push(format!("{pfield}: mode {mode:?} draws no triangles"));
            return Ok(());
        }

        // Positions.
        let pos_field = format!("{pfield}.attributes.POSITION");
        let Some(pos_acc) = prim.get(&Semantic::Positions) else {
            return Err(self.err(pos_field, "missing"));
        };
        let raw = self.read_floats(&pos_acc, Dimensions::Vec3, &[DataType::F32], &pos_field)?;
        let local_positions: Vec<Vec3> = raw.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some(i) = local_positions.iter().position(|v| !v.is_finite()) {
            return Err(self.err(pos_field, format!("vertex {i} is not finite ({})", local_positions[i])));
        }
        let n = local_positions.len();
        if n == 0 {
            self.scene.skipped.push(format!("{pfield}: {pos_field} has no vertices"));
            return Ok(());
        }
        if n > u32::MAX as usize {
            return Err(self.err(pos_field, format!("{n} vertices is too many")));
        }

        // Normals.
        let mut normals = Vec::new();
        if let Some(acc) = prim.get(&Semantic::Normals) {
            let field = format!("{pfield}.attributes.NORMAL");
            let raw = self.read_floats(&acc, Dimensions::Vec3, &[DataType::F32], &field)?;
            if raw.len() / 3 != n {
                return Err(self.err(field, format!("{} normals for {n} vertices", raw.len() / 3)));
            }
            normals = raw.chunks_exact(3).map(Vec3::from_slice).collect();
        }

        // Texture coordinates of the base-colour texture's set.
        let material = prim.material();
        let base_info = material.pbr_metallic_roughness().base_color_texture();
        let transform = base_info.as_ref().and_then(|i| i.texture_transform());
        let set = transform.as_ref().and_then(|t| t.tex_coord()).or_else(|| base_info.as_ref().map(|i| i.tex_coord())).unwrap_or(0);
        let uv_field = format!("{pfield}.attributes.TEXCOORD_{set}");
        let mut uvs = Vec::new();
        if let Some(acc) = prim.get(&Semantic::TexCoords(set)) {
            let raw = self.read_floats(&acc, Dimensions::Vec2, &[DataType::F32, DataType::U8, DataType::U16], &uv_field)?;
            if raw.len() / 2 != n {
                return Err(self.err(uv_field, format!("{} texture coordinates for {n} vertices", raw.len() / 2)));
            }
            uvs = raw.chunks_exact(2).map(Vec2::from_slice).collect();
            if let Some(t) = &transform {
                for uv in &mut uvs {
                    *uv = apply_texture_transform(*uv, t);
                }
            }
        }

        // Indices.
        let idx_field = format!("{pfield}.indices");
        let (raw_indices, count_field) = match prim.indices() {
            Some(acc) => (self.read_indices(&acc, &idx_field)?, idx_field.clone()),
            None => ((0..n as u32).collect(), pos_field.clone()),
        };
        if let Some(k) = raw_indices.iter().position(|&i| i as usize >= n) {
            return Err(self.err(idx_field, format!("index {} (element {k}) is out of range: only {n} vertices", raw_indices[k])));
        }
        let indices = match mode {
            Mode::Triangles => {
                if raw_indices.len() % 3 != 0 {
                    return Err(self.err(count_field, format!("{} indices is not a whole number of triangles", raw_indices.len())));
                }
                raw_indices
            }
            Mode::TriangleStrip => {
                let mut out = Vec::with_capacity(raw_indices.len().saturating_sub(2) * 3);
                for i in 0..raw_indices.len().saturating_sub(2) {
                    let (a, b, c) = (raw_indices[i], raw_indices[i + 1], raw_indices[i + 2]);
                    if i % 2 == 0 {
                        out.extend([a, b, c]);
                    } else {
                        out.extend([b, a, c]);
                    }
                }
                out
            }
            _ => {
                let mut out = Vec::with_capacity(raw_indices.len().saturating_sub(2) * 3);
                for i in 1..raw_indices.len().saturating_sub(1) {
                    out.extend([raw_indices[i], raw_indices[i + 1], raw_indices[0]]);
                }
                out
            }
        };
        if indices.is_empty() {
            self.scene.skipped.push(format!("{pfield}: no complete triangle in its {} indices", mode_name(mode)));
            return Ok(());
        }

        // To world space.
        let mut geometry = Mesh { positions: local_positions, normals, uvs, indices, ..Mesh::default() };
        geometry.transform(world);
        if let Some(i) = geometry.positions.iter().position(|v| !v.is_finite()) {
            return Err(self.err(
                format!("nodes[{}]", node.index()),
                format!("the node's world transform makes vertex {i} of {pos_field} non-finite"),
            ));
        }

        // Reference point: node extras first, then the mesh's.
        let mut reference_point = None;
        for (extras, field) in [(node.extras(), format!("nodes[{}]", node.index())), (mesh.extras(), format!("meshes[{m}]"))] {
            if let Some(map) = specula_extras(extras, self.file, &field)? {
                if let Some(v) = map.get("reference_point") {
                    let rp_field = format!("{field}.extras.specula.reference_point");
                    let local = json_vec3(v, self.file, &rp_field)?;
                    reference_point = Some(world.transform_point3(local));
                    break;
                }
            }
        }

        // The method the file asks for: node extras first, then the material's.
        let mut method = None;
        let mut method_field = String::new();
        let mfield = material.index().map_or("the default material".to_string(), |i| format!("materials[{i}]"));
        for (extras, field) in [(node.extras(), format!("nodes[{}]", node.index())), (material.extras(), mfield)] {
            if let Some(map) = specula_extras(extras, self.file, &field)? {
                if let Some(v) = map.get("method") {
                    let mf = format!("{field}.extras.specula.method");
                    let name = v.as_str().ok_or_else(|| {
                        Error::scene(self.file, &mf, format!("must be a method name, got {}", crate::error::clip(&v.to_string())))
                    })?;
                    if name != "auto" {
                        let m = crate::methods::Method::parse(name).map_err(|e| Error::scene(self.file, &mf, e.to_string()))?;
                        if !m.is_gpu() {
                            return Err(Error::scene(self.file, &mf, format!("'{name}' renders on the CPU, not per object")));
                        }
                        method = Some(name.to_string());
                        method_field = mf;
                    }
                    break;
                }
            }
        }

        let material_index = self.material_index(&material)?;
        if let Some(name) = &method {
            let kind = &self.scene.materials[material_index].kind;
            let serves =
                crate::methods::Method::parse(name).ok().zip(crate::methods::ObjectClass::of(kind)).is_some_and(|(m, c)| m.can_serve(c));
            if !serves {
                return Err(Error::scene(self.file, &method_field, format!("'{name}' cannot serve this {} object", kind.label())));
            }
        }
        let mesh_name = mesh.name().map(str::to_string).unwrap_or_else(|| m.to_string());
        let name = format!("{mesh_name}/{p}");
        // `--object NAME=METHOD` and the C ABI address the object by its node or mesh name.
        let mut aliases = vec![mesh_name];
        if let Some(n) = node.name() {
            if !aliases.iter().any(|a| a == n) {
                aliases.push(n.to_string());
            }
        }
        let mesh_value = Mesh { name, material: material_index, reference_point, aliases, method, ..geometry };
        let file = self.file;
        self.scene.add_mesh(mesh_value).map_err(|e| {
            map_invalid(file, e, |suffix| match suffix {
                Some("positions") => pos_field.clone(),
                Some("indices") => idx_field.clone(),
                Some("normals") => format!("{pfield}.attributes.NORMAL"),
                Some("uvs") => uv_field.clone(),
                Some("material") => format!("{pfield}.material"),
                Some("reference_point") => {
                    format!("nodes[{}].extras.specula.reference_point", node.index())
                }
                _ => pfield.clone(),
            })
        })?;
        Ok(())
    }

    // ---------------------------------------------------------------- materials

    pub(super) fn check_material_scalars(&self, material: &gltf::Material) -> Result<()> {
        let i = material.index().unwrap_or(0);
        if let Some(ior) = material.ior() {
            // KHR_materials_ior admits 0 (infinite IOR, Fresnel 1) or ≥ 1 (see schema.rs).
            if !(ior == 0.0 || (ior >= 1.0 && ior.is_finite())) {
                return Err(self.err(
                    format!("materials[{i}].extensions.KHR_materials_ior.ior"),
                    format!("index of refraction must be 0 or finite and ≥ 1, got {ior}"),
                ));
            }
        }
        if let Some(s) = material.emissive_strength() {
            if !(s >= 0.0 && s.is_finite()) {
                return Err(self.err(
                    format!("materials[{i}].extensions.KHR_materials_emissive_strength.emissiveStrength"),
                    format!("must be finite and ≥ 0, got {s}"),
                ));
            }
        }
        Ok(())
    }

    fn material_index(&mut self, material: &gltf::Material) -> Result<usize> {
        let Some(i) = material.index() else {
            if let Some(d) = self.default_material {
                return Ok(d);
            }
            let d = self
                .scene
                .add_material(Material { name: "default".into(), ..Material::default() })
                .map_err(|e| map_invalid(self.file, e, |_| "(default material)".into()))?;
            self.default_material = Some(d);
            return Ok(d);
        };
        if let Some(&s) = self.materials.get(&i) {
            return Ok(s);
        }
        let s = self.import_material(material, i)?;
        self.materials.insert(i, s);
        Ok(s)
    }

    /// `extras.specula.graded_index` of a material (survey §6.5, `scene::medium`): a solid
    /// dielectric's index field in world space, n(x) = ior + g·(x − o) + ½ (x − o)ᵀH(x − o),
    /// as `{"origin": [x, y, z], "gradient": [gx, gy, gz], "hessian": [[…], […], […]]}`, or a
    /// radial profile `"radial": k` about `"axis": [ax, ay, az]` through the origin (n falls
    /// by ½ k r² at r from the axis), which adds to the Hessian. Every member may be left out
    /// (zero; the axis +y).
    fn graded_index(&self, material: &gltf::Material, field: &str) -> Result<Option<crate::scene::medium::GradedIndex>> {
        let Some(extras) = specula_extras(material.extras(), self.file, field)? else { return Ok(None) };
        let Some(g) = extras.get("graded_index") else { return Ok(None) };
        let at = |k: &str| format!("{field}.extras.specula.graded_index.{k}");
        let Some(g) = g.as_object() else {
            return Err(self.err(format!("{field}.extras.specula.graded_index"), format!("must be an object, got {g}")));
        };
        if let Some(k) = g.keys().find(|k| !["origin", "gradient", "hessian", "radial", "axis"].contains(&k.as_str())) {
            return Err(self.err(at(k), "unknown member (known: origin, gradient, hessian, radial, axis)"));
        }
        let v3 = |k: &str, default: Vec3| g.get(k).map_or(Ok(default), |v| json_vec3(v, self.file, &at(k)));
        let mut hessian = [Vec3::ZERO; 3];
        if let Some(h) = g.get("hessian") {
            let rows = h
                .as_array()
                .filter(|r| r.len() == 3)
                .ok_or_else(|| self.err(at("hessian"), format!("expected 3 rows of 3 numbers, got {h}")))?;
            for (k, r) in rows.iter().enumerate() {
                hessian[k] = json_vec3(r, self.file, &format!("{}[{k}]", at("hessian")))?;
            }
        }
        if let Some(k) = g.get("radial") {
            let k =
                k.as_f64().filter(|k| k.is_finite()).ok_or_else(|| self.err(at("radial"), format!("expected a finite number, got {k}")))?;
            let axis = v3("axis", Vec3::Y)?;
            if axis.length_squared() == 0.0 {
                return Err(self.err(at("axis"), "must be non-zero"));
            }
            let r = crate::scene::medium::GradedIndex::radial_hessian(axis, k as f32);
            hessian = [hessian[0] + r[0], hessian[1] + r[1], hessian[2] + r[2]];
        }
        Ok(Some(crate::scene::medium::GradedIndex { origin: v3("origin", Vec3::ZERO)?, gradient: v3("gradient", Vec3::ZERO)?, hessian }))
    }

    fn import_material(&mut self, material: &gltf::Material, i: usize) -> Result<usize> {
        let field = format!("materials[{i}]");
        self.check_material_scalars(material)?;
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor();
        let base_color = Vec3::new(r, g, b);
        let roughness = pbr.roughness_factor();
        let transmission = material.transmission().map(|t| t.transmission_factor()).unwrap_or(0.0);

        let kind = if pbr.metallic_factor() == 1.0 && roughness == 0.0 {
            let extras = specula_extras(material.extras(), self.file, &field)?;
            let nu = extras.as_ref().and_then(|m| m.get("nu"));
            let kappa = extras.as_ref().and_then(|m| m.get("kappa"));
            match (nu, kappa) {
                (Some(nu), kappa) => SurfaceKind::Mirror {
                    nu: json_vec3(nu, self.file, &format!("{field}.extras.specula.nu"))?,
                    kappa: match kappa {
                        Some(k) => json_vec3(k, self.file, &format!("{field}.extras.specula.kappa"))?,
                        None => Vec3::ZERO,
                    },
                },
                (None, Some(_)) => {
                    return Err(self.err(format!("{field}.extras.specula.kappa"), "kappa given without nu"));
                }
                (None, None) => SurfaceKind::Mirror { nu: Vec3::new(nu_from_f0(r), nu_from_f0(g), nu_from_f0(b)), kappa: Vec3::ZERO },
            }
        } else if transmission == 1.0 && roughness == 0.0 && material.ior() == Some(0.0) {
            // KHR_materials_ior's ior = 0: infinite IOR, Fresnel 1 at every angle: nothing is
            // transmitted, an ideal mirror of reflectance 1 (a conductor with a huge κ).
            SurfaceKind::Mirror { nu: Vec3::ONE, kappa: Vec3::splat(INFINITE_IOR_KAPPA) }
        } else if transmission == 1.0 && roughness == 0.0 {
            let thin = material.volume().is_none_or(|v| v.thickness_factor() == 0.0);
            SurfaceKind::Dielectric { ior: material.ior().unwrap_or(1.5), thin }
        } else {
            SurfaceKind::Diffuse
        };

        let base_color_texture = match pbr.base_color_texture() {
            Some(info) => {
                Some(self.texture_index(info.texture().source().index(), &format!("{field}.pbrMetallicRoughness.baseColorTexture"))?)
            }
            None => None,
        };
        let emissive_texture = match material.emissive_texture() {
            Some(info) => Some(self.texture_index(info.texture().source().index(), &format!("{field}.emissiveTexture"))?),
            None => None,
        };
        let emissive = Vec3::from(material.emissive_factor()) * material.emissive_strength().unwrap_or(1.0);
        let (specular_factor, specular_color) = match material.specular() {
            Some(s) => (s.specular_factor(), Vec3::from(s.specular_color_factor())),
            None => (1.0, Vec3::ONE),
        };
        // KHR_materials_volume's attenuation (world-space distance): absorption inside
        // solid dielectrics; the schema check above has refused colours outside 0..=1 and
        // distances ≤ 0.
        let absorption = match material.volume() {
            Some(v) if matches!(kind, SurfaceKind::Dielectric { thin: false, .. }) => {
                let (c, d) = (Vec3::from(v.attenuation_color()), v.attenuation_distance());
                Material::absorption_from(c, d).ok_or_else(|| {
                    self.err(
                        format!("{field}.extensions.KHR_materials_volume"),
                        format!("attenuationColor {c} and attenuationDistance {d}: the colour must be in 0..=1 and the distance > 0"),
                    )
                })?
            }
            _ => Vec3::ZERO,
        };
        // KHR_materials_dispersion (not in the gltf crate: read from its JSON; the schema
        // check has refused negative values).
        let dispersion = match material.extension_value("KHR_materials_dispersion").and_then(|v| v.get("dispersion")) {
            Some(v) if matches!(kind, SurfaceKind::Dielectric { thin: false, .. }) => v.as_f64().unwrap_or(0.0) as f32,
            _ => 0.0,
        };
        let m = Material {
            name: material.name().map(str::to_string).unwrap_or_else(|| format!("material{i}")),
            base_color,
            base_color_texture,
            emissive,
            emissive_texture,
            kind,
            specular_color,
            specular_factor,
            absorption,
            dispersion,
            graded: self.graded_index(material, &field)?,
        };
        let file = self.file;
        self.scene.add_material(m).map_err(|e| {
            map_invalid(file, e, |suffix| match suffix {
                Some("ior") => format!("{field}.extensions.KHR_materials_ior.ior"),
                Some("nu" | "kappa") => format!("{field}.extras.specula"),
                Some("base_color") => format!("{field}.pbrMetallicRoughness.baseColorFactor"),
                Some("emission") => format!("{field}.emissiveFactor"),
                Some("specular_color") => format!("{field}.extensions.KHR_materials_specular.specularColorFactor"),
                Some("specular_factor") => format!("{field}.extensions.KHR_materials_specular.specularFactor"),
                Some("absorption") => format!("{field}.extensions.KHR_materials_volume"),
                Some("dispersion") => format!("{field}.extensions.KHR_materials_dispersion.dispersion"),
                Some(f) if f.starts_with("graded_index") => format!("{field}.extras.specula.{f}"),
                _ => field.clone(),
            })
        })
    }

    // ---------------------------------------------------------------- lights, camera

    fn import_light(&mut self, node: &gltf::Node, light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Result<()> {
        use gltf::khr_lights_punctual::Kind;
        let j = light.index();
        let field = format!("extensions.KHR_lights_punctual.lights[{j}]");
        let kind = match light.kind() {
            Kind::Point => LightKind::Point,
            Kind::Directional => LightKind::Directional,
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let ok = inner_cone_angle >= 0.0 && inner_cone_angle <= outer_cone_angle && outer_cone_angle <= std::f32::consts::FRAC_PI_2;
                if !ok {
                    return Err(self.err(
                        format!("{field}.spot"),
                        format!("cone angles must satisfy 0 ≤ inner ({inner_cone_angle}) ≤ outer ({outer_cone_angle}) ≤ π/2"),
                    ));
                }
                LightKind::Spot { inner_cone: inner_cone_angle, outer_cone: outer_cone_angle }
            }
        };
        let range = light.range();
        if let Some(r) = range {
            if r.is_nan() || r <= 0.0 {
                return Err(self.err(format!("{field}.range"), format!("must be > 0, got {r}")));
            }
        }
        let l = Light {
            name: light.name().map(str::to_string).unwrap_or_else(|| format!("light{j}")),
            kind,
            position: world.w_axis.truncate(),
            direction: world.transform_vector3(Vec3::NEG_Z).normalize_or_zero(),
            intensity: Vec3::from(light.color()) * light.intensity(),
            range,
        };
        let file = self.file;
        let node_index = node.index();
        self.scene.add_light(l).map_err(|e| map_invalid(file, e, |_| format!("{field} (on nodes[{node_index}])")))?;
        Ok(())
    }

    fn import_camera(&mut self, node: &gltf::Node, camera: usize, world: Mat4) -> Result<()> {
        let json = &self.doc.as_json().cameras[camera];
        if json.type_ != Checked::Valid(gltf::json::camera::Type::Perspective) {
            return Ok(()); // orthographic: ignored
        }
        let field = format!("cameras[{camera}].perspective");
        let Some(p) = &json.perspective else {
            return Err(self.err(field, "type is \"perspective\" but the perspective object is missing"));
        };
        if !(p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
            return Err(self.err(format!("{field}.yfov"), format!("must be in (0, π), got {}", p.yfov)));
        }
        if !(p.znear > 0.0 && p.znear.is_finite()) {
            return Err(self.err(format!("{field}.znear"), format!("must be finite and > 0, got {}", p.znear)));
        }
        if let Some(zfar) = p.zfar {
            if zfar.is_nan() || zfar <= p.znear {
                return Err(self.err(format!("{field}.zfar"), format!("must be > znear ({}), got {zfar}", p.znear)));
            }
        }
        let (_, rotation, translation) = world.to_scale_rotation_translation();
        let world_from_camera = Mat4::from_rotation_translation(rotation.normalize(), translation);
        if !world_from_camera.is_finite() {
            return Err(self.err(format!("nodes[{}]", node.index()), "the camera node's world transform is degenerate"));
        }
        self.scene.camera = Some(Camera { position: translation, world_from_camera, yfov: p.yfov, znear: p.znear, zfar: p.zfar });
        Ok(())
    }
}
