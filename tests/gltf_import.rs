//! glTF import and environment-map I/O: every supported extension is read, and every kind
//! of bad input is an `Err` naming the file and the field, never a panic. Pure CPU.

mod common;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use base64::Engine;
use glam::{Quat, Vec2, Vec3};
use serde_json::{json, Value};
use specula::scene::{linear_to_srgb, load, load_environment, srgb_to_linear, write_exr, write_png_srgb, LightKind, Scene, SurfaceKind};

// ------------------------------------------------------------------------ helpers

static COUNTER: AtomicUsize = AtomicUsize::new(0);

/// A fresh directory under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("specula-gltf-test-{}-{tag}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        TempDir(dir)
    }
    fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A glTF document and its single binary buffer.
#[derive(Clone)]
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

const POS_OFFSET: usize = 0;
const NRM_OFFSET: usize = 48;
const IDX_OFFSET: usize = 128;

/// A unit quad in the z = 0 plane facing +Z: 4 vertices (with normals and uvs), 2 triangles
/// (u32 indices), one node, one scene, no material.
fn quad_doc() -> Doc {
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin = Vec::new();
    bin.extend(positions.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bin.extend((0..4).flat_map(|_| [0f32, 0.0, 1.0]).flat_map(|v| v.to_le_bytes()));
    bin.extend(uvs.iter().flatten().flat_map(|v| v.to_le_bytes()));
    bin.extend(indices.iter().flat_map(|v| v.to_le_bytes()));
    assert_eq!(bin.len(), 152);
    let json = json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "quad", "primitives": [{
            "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3
        }] }],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR" }
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": POS_OFFSET, "byteLength": 48 },
            { "buffer": 0, "byteOffset": NRM_OFFSET, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
            { "buffer": 0, "byteOffset": IDX_OFFSET, "byteLength": 24 }
        ],
        "buffers": [{ "byteLength": 152 }]
    });
    Doc { json, bin }
}

impl Doc {
    /// Gives the quad one primitive per material (all sharing the accessors).
    fn with_materials(mut self, materials: Value) -> Doc {
        let n = materials.as_array().unwrap().len();
        let prim = self.json["meshes"][0]["primitives"][0].clone();
        let prims: Vec<Value> = (0..n)
            .map(|i| {
                let mut p = prim.clone();
                p["material"] = json!(i);
                p
            })
            .collect();
        self.json["meshes"][0]["primitives"] = json!(prims);
        self.json["materials"] = materials;
        self
    }
    fn set_f32(&mut self, offset: usize, v: f32) {
        self.bin[offset..offset + 4].copy_from_slice(&v.to_le_bytes());
    }
    fn set_u32(&mut self, offset: usize, v: u32) {
        self.bin[offset..offset + 4].copy_from_slice(&v.to_le_bytes());
    }
}

#[derive(Clone, Copy)]
enum Form {
    /// `.gltf` with the buffer as a base64 data URI.
    Embedded,
    /// `.gltf` + `.bin`.
    External,
    /// `.glb` with a BIN chunk.
    Glb,
}

fn glb_bytes(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

fn b64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

fn write(dir: &TempDir, name: &str, doc: &Doc, form: Form) -> PathBuf {
    let mut json = doc.json.clone();
    match form {
        Form::Embedded => {
            json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", b64(&doc.bin)));
            let path = dir.join(&format!("{name}.gltf"));
            std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
            path
        }
        Form::External => {
            std::fs::write(dir.join(&format!("{name}.bin")), &doc.bin).unwrap();
            json["buffers"][0]["uri"] = json!(format!("{name}.bin"));
            let path = dir.join(&format!("{name}.gltf"));
            std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
            path
        }
        Form::Glb => {
            let path = dir.join(&format!("{name}.glb"));
            std::fs::write(&path, glb_bytes(&json, &doc.bin)).unwrap();
            path
        }
    }
}

/// Writes `doc` embedded and loads it.
fn load_doc(tag: &str, doc: &Doc) -> Scene {
    let dir = TempDir::new(tag);
    let path = write(&dir, tag, doc, Form::Embedded);
    load(&path).unwrap_or_else(|e| panic!("{tag}: {e}"))
}

/// Asserts `result` is an error whose message names the file and contains every needle.
fn assert_err(result: specula::Result<Scene>, file: &Path, needles: &[&str]) -> String {
    let msg = match result {
        Ok(_) => panic!("{}: expected an error mentioning {needles:?}", file.display()),
        Err(e) => e.to_string(),
    };
    eprintln!("{msg}");
    let name = file.file_name().unwrap().to_str().unwrap();
    assert!(msg.contains(name), "error does not name the file {name:?}: {msg}");
    for n in needles {
        assert!(msg.contains(n), "error lacks {n:?}: {msg}");
    }
    msg
}

/// Writes `doc` embedded, loads it and checks the error.
fn expect_error(tag: &str, doc: &Doc, needles: &[&str]) -> String {
    let dir = TempDir::new(tag);
    let path = write(&dir, tag, doc, Form::Embedded);
    assert_err(load(&path), &path, needles)
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

fn png_bytes(img: &image::RgbaImage) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn material<'a>(scene: &'a Scene, name: &str) -> &'a specula::scene::Material {
    scene.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}"))
}

// ------------------------------------------------------------------------ buffers, geometry

#[test]
fn embedded_external_and_glb_buffers_agree() {
    let dir = TempDir::new("forms");
    let doc = quad_doc();
    let scenes: Vec<Scene> = [Form::Embedded, Form::External, Form::Glb]
        .into_iter()
        .enumerate()
        .map(|(i, form)| {
            let path = write(&dir, &format!("quad{i}"), &doc, form);
            load(&path).unwrap_or_else(|e| panic!("{e}"))
        })
        .collect();
    let s = &scenes[0];
    assert_eq!(s.meshes.len(), 1);
    let m = &s.meshes[0];
    assert_eq!(m.name, "quad/0");
    assert_eq!(m.positions, vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]);
    assert_eq!(m.normals, vec![Vec3::Z; 4]);
    assert_eq!(m.uvs[0], Vec2::new(0.0, 1.0));
    assert_eq!(m.indices, vec![0, 1, 2, 0, 2, 3]);
    // No material: one default white diffuse one.
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.materials[0].kind, SurfaceKind::Diffuse);
    assert_eq!(s.materials[0].base_color, Vec3::ONE);
    assert!(s.camera.is_none());
    assert!(s.lights.is_empty());
    assert_eq!(&scenes[1], s);
    assert_eq!(&scenes[2], s);
}

#[test]
fn default_material_is_created_once() {
    let mut doc = quad_doc();
    let prim = doc.json["meshes"][0]["primitives"][0].clone();
    doc.json["meshes"][0]["primitives"] = json!([prim.clone(), prim]);
    doc.json["nodes"] = json!([{ "mesh": 0 }, { "mesh": 0, "translation": [0.0, 0.0, 5.0] }]);
    doc.json["scenes"][0]["nodes"] = json!([0, 1]);
    let s = load_doc("default_material", &doc);
    assert_eq!(s.meshes.len(), 4);
    assert_eq!(s.materials.len(), 1);
    assert!(s.meshes.iter().all(|m| m.material == 0));
    assert_eq!(s.meshes[3].positions[0], Vec3::new(0.0, 0.0, 5.0));
}

#[test]
fn normals_computed_when_absent() {
    let mut doc = quad_doc();
    doc.json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("NORMAL");
    let s = load_doc("no_normals", &doc);
    assert_eq!(s.meshes[0].normals.len(), 4);
    assert!(s.meshes[0].normals.iter().all(|&n| close(n, Vec3::Z)), "{:?}", s.meshes[0].normals);
}

#[test]
fn missing_indices_are_generated() {
    let mut doc = quad_doc();
    // Three vertices, no indices: one triangle 0 1 2.
    doc.json["meshes"][0]["primitives"][0].as_object_mut().unwrap().remove("indices");
    for a in 0..3 {
        doc.json["accessors"][a]["count"] = json!(3);
    }
    let s = load_doc("no_indices", &doc);
    assert_eq!(s.meshes[0].indices, vec![0, 1, 2]);
}

#[test]
fn node_hierarchy_transforms_compose() {
    let mut doc = quad_doc();
    // Parent: translation (10, 0, 0) and 90° about +Y; child: scale 2.
    let r = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    doc.json["nodes"] = json!([
        { "children": [1], "translation": [10.0, 0.0, 0.0], "rotation": r.to_array() },
        { "mesh": 0, "scale": [2.0, 2.0, 2.0] }
    ]);
    let s = load_doc("hierarchy", &doc);
    let m = &s.meshes[0];
    // (1, 0, 0) → scale (2, 0, 0) → rotate (0, 0, −2) → translate (10, 0, −2).
    assert!(close(m.positions[1], Vec3::new(10.0, 0.0, -2.0)), "{:?}", m.positions);
    assert!(close(m.positions[3], Vec3::new(10.0, 2.0, 0.0)), "{:?}", m.positions);
    // The +Z normal is rotated to +X.
    assert!(m.normals.iter().all(|&n| close(n, Vec3::X)), "{:?}", m.normals);
}

#[test]
fn parent_translation_and_child_scale() {
    let mut doc = quad_doc();
    doc.json["nodes"] = json!([{ "children": [1], "translation": [0.0, 5.0, 0.0] }, { "mesh": 0, "scale": [2.0, 1.0, 1.0] }]);
    // Normals (1, 1, 0)/√2 under scale (2, 1, 1) transform by the inverse transpose: ∝ (0.5, 1, 0).
    let s = 0.5f32.sqrt();
    for v in 0..4 {
        doc.set_f32(NRM_OFFSET + v * 12, s);
        doc.set_f32(NRM_OFFSET + v * 12 + 4, s);
        doc.set_f32(NRM_OFFSET + v * 12 + 8, 0.0);
    }
    let scene = load_doc("translate_scale", &doc);
    let m = &scene.meshes[0];
    assert!(close(m.positions[2], Vec3::new(2.0, 6.0, 0.0)), "{:?}", m.positions);
    let expected = Vec3::new(0.5, 1.0, 0.0).normalize();
    assert!(m.normals.iter().all(|&n| close(n, expected)), "{:?}", m.normals);
}

#[test]
fn negative_determinant_flips_winding() {
    let mut doc = quad_doc();
    doc.json["nodes"][0]["scale"] = json!([-1.0, 1.0, 1.0]);
    doc.json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("NORMAL");
    let s = load_doc("mirrored", &doc);
    let m = &s.meshes[0];
    assert_eq!(m.indices, vec![0, 2, 1, 0, 3, 2]);
    // Still facing +Z: the mirrored geometry keeps its front face.
    let (a, b, c) = (m.positions[m.indices[0] as usize], m.positions[m.indices[1] as usize], m.positions[m.indices[2] as usize]);
    assert!((b - a).cross(c - a).z > 0.0);
    assert!(m.normals.iter().all(|&n| close(n, Vec3::Z)));
}

#[test]
fn zero_scale_node_is_skipped_with_a_note() {
    // glTF hides nodes by scale 0; the C ABI refuses the same transform (tests/validation_paths.rs).
    let mut doc = quad_doc();
    doc.json["nodes"] = json!([{ "mesh": 0, "scale": [1.0, 0.0, 1.0] }, { "mesh": 0, "translation": [0.0, 0.0, 1.0] }]);
    doc.json["scenes"][0]["nodes"] = json!([0, 1]);
    let s = load_doc("zero_scale", &doc);
    assert_eq!(s.meshes.len(), 1, "only the visible node's mesh");
    assert!(s.skipped.iter().any(|n| n.contains("nodes[0]") && n.contains("determinant 0")), "{:?}", s.skipped);
    // Every node hidden: the render error says why.
    doc.json["scenes"][0]["nodes"] = json!([0]);
    let s = load_doc("all_zero_scale", &doc);
    let e = s.check_renderable().unwrap_err().to_string();
    assert!(e.contains("nodes[0]") && e.contains("invertible"), "{e}");
}

#[test]
fn reference_point_from_extras_in_world_space() {
    let mut doc = quad_doc();
    doc.json["nodes"][0]["translation"] = json!([0.0, 1.0, 0.0]);
    doc.json["meshes"][0]["extras"] = json!({ "specula": { "reference_point": [0.5, 0.5, 0.0] } });
    let s = load_doc("reference_point", &doc);
    assert_eq!(s.meshes[0].reference_point, Some(Vec3::new(0.5, 1.5, 0.0)));
    // A node's reference point wins over the mesh's.
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "reference_point": [0.0, 0.0, 1.0] } });
    let s = load_doc("reference_point_node", &doc);
    assert_eq!(s.meshes[0].reference_point, Some(Vec3::new(0.0, 1.0, 1.0)));
}

/// Adds a sparse substitution of vertex `index` by `value` to the POSITION accessor.
fn with_sparse_position(mut doc: Doc, index: u32, value: [f32; 3]) -> Doc {
    let offset = doc.bin.len();
    doc.bin.extend(index.to_le_bytes());
    doc.bin.extend(value.iter().flat_map(|v| v.to_le_bytes()));
    doc.json["buffers"][0]["byteLength"] = json!(doc.bin.len());
    let views = doc.json["bufferViews"].as_array_mut().unwrap();
    views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": 4 }));
    views.push(json!({ "buffer": 0, "byteOffset": offset + 4, "byteLength": 12 }));
    let (iv, vv) = (views.len() - 2, views.len() - 1);
    doc.json["accessors"][0]["sparse"] = json!({
        "count": 1, "indices": { "bufferView": iv, "componentType": 5125 }, "values": { "bufferView": vv }
    });
    doc.json["accessors"][0]["max"] = json!([2.0, 1.0, 0.0]);
    doc
}

#[test]
fn sparse_positions() {
    let doc = with_sparse_position(quad_doc(), 1, [2.0, 0.0, 0.0]);
    let s = load_doc("sparse", &doc);
    assert_eq!(s.meshes[0].positions[1], Vec3::new(2.0, 0.0, 0.0));
    assert_eq!(s.meshes[0].positions[2], Vec3::new(1.0, 1.0, 0.0));
    // Without a base bufferView the other vertices are zero (if the validator allows it).
    let mut doc = doc;
    doc.json["accessors"][0].as_object_mut().unwrap().remove("bufferView");
    let dir = TempDir::new("sparse_no_view");
    let path = write(&dir, "sparse_no_view", &doc, Form::Embedded);
    match load(&path) {
        Ok(s) => assert_eq!(s.meshes[0].positions, vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::ZERO, Vec3::ZERO]),
        Err(e) => assert!(e.to_string().contains("accessors[0]"), "{e}"),
    }
    // A sparse index past the end.
    let doc = with_sparse_position(quad_doc(), 9, [2.0, 0.0, 0.0]);
    expect_error("sparse_out_of_range", &doc, &["accessors[0].sparse.indices", "index 9"]);
}

#[test]
fn triangle_strip_is_converted_and_lines_are_skipped() {
    let mut doc = quad_doc();
    let mut strip = doc.json["meshes"][0]["primitives"][0].clone();
    strip.as_object_mut().unwrap().remove("indices");
    strip["mode"] = json!(5); // strip over 0 1 3 2 would need indices; use 0 1 2 3
    let mut lines = strip.clone();
    lines["mode"] = json!(1);
    doc.json["meshes"][0]["primitives"] = json!([strip, lines]);
    let s = load_doc("strip", &doc);
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].indices, vec![0, 1, 2, 2, 1, 3]);
}

// ------------------------------------------------------------------------ materials

#[test]
fn materials_are_classified_with_their_extensions() {
    let doc = quad_doc().with_materials(json!([
        { "name": "emissive", "emissiveFactor": [1.0, 0.5, 0.25],
          "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.4, 0.6, 1.0] },
          "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } } },
        { "name": "thin_glass", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
          "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": 1.33 } } },
        { "name": "solid_glass", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
          "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": 1.7 },
                          "KHR_materials_volume": { "thicknessFactor": 0.5, "attenuationColor": [0.5, 0.25, 0.0], "attenuationDistance": 2.0 },
                          "KHR_materials_dispersion": { "dispersion": 0.5 } } },
        { "name": "zero_thickness", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
          "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 },
                          "KHR_materials_volume": { "thicknessFactor": 0.0, "attenuationColor": [0.5, 0.5, 0.5], "attenuationDistance": 1.0 } } },
        { "name": "grey_mirror", "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0 } },
        { "name": "silver", "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.0 },
          "extras": { "specula": { "nu": [0.15, 0.12, 0.14], "kappa": [3.3, 2.3, 1.8] } } },
        { "name": "specular", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.5 },
          "extensions": { "KHR_materials_specular": { "specularFactor": 0.5, "specularColorFactor": [1.0, 0.5, 0.2] } } },
        { "name": "half_transmission", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
          "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.5 } } },
        { "name": "black_mirror", "pbrMetallicRoughness": { "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0 } },
        { "name": "rough_metal", "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.1 } }
    ]));
    let mut doc = doc;
    doc.json["extensionsUsed"] = json!([
        "KHR_materials_emissive_strength",
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_volume",
        "KHR_materials_dispersion",
        "KHR_materials_specular"
    ]);
    let s = load_doc("materials", &doc);
    assert_eq!(s.materials.len(), 10);
    assert_eq!(s.meshes.len(), 10);

    let m = material(&s, "emissive");
    assert_eq!(m.kind, SurfaceKind::Diffuse);
    assert!(close(m.emissive, Vec3::new(4.0, 2.0, 1.0)));
    assert!(close(m.base_color, Vec3::new(0.2, 0.4, 0.6)));
    assert_eq!((m.specular_factor, m.specular_color), (1.0, Vec3::ONE));

    assert_eq!(material(&s, "thin_glass").kind, SurfaceKind::Dielectric { ior: 1.33, thin: true });
    assert_eq!(material(&s, "solid_glass").kind, SurfaceKind::Dielectric { ior: 1.7, thin: false });
    assert_eq!(material(&s, "zero_thickness").kind, SurfaceKind::Dielectric { ior: 1.5, thin: true });
    assert_eq!(material(&s, "solid_glass").kind.label(), "dielectric (solid)");
    // KHR_materials_volume's attenuation: σ = −ln c / d (a colour of 0 absorbs as 10⁻³⁰
    // does, finite); a thin-walled surface has no volume to absorb in, glass without the
    // extension none either.
    let sigma = material(&s, "solid_glass").absorption;
    let expected = Vec3::new(2f32.ln() / 2.0, 4f32.ln() / 2.0, 1e30f32.ln() / 2.0);
    assert!(close(sigma, expected), "{sigma} vs {expected}");
    assert!(material(&s, "solid_glass").absorbs());
    assert_eq!(material(&s, "zero_thickness").absorption, Vec3::ZERO);
    assert_eq!(material(&s, "thin_glass").absorption, Vec3::ZERO);
    // KHR_materials_dispersion 0.5: Abbe number 40; ior is the d line's, the channels refract
    // at the C and F lines: n_F − n_C = (n_d − 1)/V (the Abbe number's definition).
    let glass = material(&s, "solid_glass");
    assert_eq!(glass.dispersion, 0.5);
    assert!(glass.disperses());
    let n = glass.channel_iors().unwrap();
    assert!((n.y - 1.7).abs() < 1e-3 && ((n.z - n.x) - 0.7 / 40.0).abs() < 1e-4, "{n}");
    assert_eq!(material(&s, "thin_glass").channel_iors(), Some(Vec3::splat(1.33)));

    let SurfaceKind::Mirror { nu, kappa } = material(&s, "grey_mirror").kind else { panic!("grey_mirror is not a mirror") };
    let root = 0.5f32.sqrt();
    assert!(close(nu, Vec3::splat((1.0 + root) / (1.0 - root))), "{nu}");
    assert_eq!(kappa, Vec3::ZERO);

    assert_eq!(material(&s, "silver").kind, SurfaceKind::Mirror { nu: Vec3::new(0.15, 0.12, 0.14), kappa: Vec3::new(3.3, 2.3, 1.8) });
    assert_eq!(material(&s, "black_mirror").kind, SurfaceKind::Mirror { nu: Vec3::ONE, kappa: Vec3::ZERO });

    let m = material(&s, "specular");
    assert_eq!(m.kind, SurfaceKind::Diffuse);
    assert_eq!(m.specular_factor, 0.5);
    assert_eq!(m.specular_color, Vec3::new(1.0, 0.5, 0.2));

    assert_eq!(material(&s, "half_transmission").kind, SurfaceKind::Diffuse);
    assert_eq!(material(&s, "rough_metal").kind, SurfaceKind::Diffuse);
}

/// `extras.specula.graded_index` (survey §6.5): a solid dielectric's index field, linear
/// plus a radial profile; a malformed one is refused naming the material's JSON path, the
/// member and the value.
#[test]
fn graded_index_from_extras() {
    let glass = |graded: serde_json::Value| {
        quad_doc().with_materials(json!([
            { "name": "grin", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
              "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": 1.6 },
                              "KHR_materials_volume": { "thicknessFactor": 1.0 } },
              "extras": { "specula": { "graded_index": graded } } }
        ]))
    };
    let mut doc = glass(json!({ "origin": [0.0, 1.0, 0.0], "gradient": [0.0, 0.25, 0.0], "radial": 2.0, "axis": [0.0, 0.0, 3.0] }));
    doc.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]);
    let s = load_doc("graded", &doc);
    let m = material(&s, "grin");
    let f = m.medium().expect("a graded medium");
    assert_eq!((f.origin, f.gradient), (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.25, 0.0)));
    // n = 1.6 + 0.25 (y − 1) − ½·2·(x² + y'²) about the z axis through the origin
    let n = m.ior_at(glam::DVec3::new(0.5, 1.0, 7.0)).unwrap();
    assert!((n - (1.6 - 0.25)).abs() < 1e-6, "{n}");
    for (graded, needles) in [
        (json!({ "gradient": [0.0, 1.0] }), &["materials[0].extras.specula.graded_index.gradient", "3 finite numbers"][..]),
        (json!({ "hessian": [[0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]] }), &["graded_index.hessian", "symmetric"][..]),
        (json!({ "slope": 1.0 }), &["graded_index.slope", "unknown member"][..]),
        (json!({ "radial": 1.0, "axis": [0.0, 0.0, 0.0] }), &["graded_index.axis", "non-zero"][..]),
        (json!(3.0), &["materials[0].extras.specula.graded_index", "must be an object"][..]),
    ] {
        let mut doc = glass(graded);
        doc.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]);
        expect_error("graded_bad", &doc, needles);
    }
    // On a thin-walled pane there is no volume for the index to vary in.
    let mut doc = glass(json!({ "gradient": [0.0, 1.0, 0.0] }));
    doc.json["materials"][0]["extensions"]["KHR_materials_volume"]["thicknessFactor"] = json!(0.0);
    doc.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]);
    expect_error("graded_thin", &doc, &["materials[0].extras.specula.graded_index", "solid"]);
    // An index that falls to zero inside its object is refused where the scene is checked.
    let mut doc = glass(json!({ "gradient": [-10.0, 0.0, 0.0] }));
    doc.json["extensionsUsed"] = json!(["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"]);
    let s = load_doc("graded_negative", &doc);
    let e = s.validate().unwrap_err().to_string();
    assert!(e.contains("graded_index") && e.contains("must stay > 0") && e.contains("grin"), "{e}");
}

#[test]
fn base_colour_texture_from_embedded_png() {
    let img = image::RgbaImage::from_fn(2, 2, |x, y| image::Rgba([x as u8 * 200, y as u8 * 100, 7, 255]));
    let png = png_bytes(&img);
    let mut doc = quad_doc().with_materials(json!([
        { "name": "a", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0,
            "extensions": { "KHR_texture_transform": { "offset": [0.5, 0.0], "scale": [0.5, 0.5] } } } } },
        { "name": "b", "pbrMetallicRoughness": { "baseColorTexture": { "index": 1 } }, "emissiveTexture": { "index": 0 } }
    ]));
    doc.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    doc.json["images"] = json!([{ "uri": format!("data:image/png;base64,{}", b64(&png)) }]);
    doc.json["textures"] = json!([{ "source": 0 }, { "source": 0 }]);
    let s = load_doc("texture", &doc);
    // Both textures name the same image: decoded once.
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!((t.width, t.height), (2, 2));
    assert_eq!(t.rgba8, img.into_raw());
    let (a, b) = (material(&s, "a"), material(&s, "b"));
    assert_eq!(a.base_color_texture, Some(0));
    assert_eq!(b.base_color_texture, Some(0));
    assert_eq!(b.emissive_texture, Some(0));
    // KHR_texture_transform of the base-colour texture: uv × 0.5 + (0.5, 0).
    let ma = s.meshes.iter().find(|m| m.material == s.materials.iter().position(|m| m.name == "a").unwrap()).unwrap();
    assert_eq!(ma.uvs[1], Vec2::new(1.0, 0.5)); // (1, 1)
    assert_eq!(ma.uvs[3], Vec2::new(0.5, 0.0)); // (0, 0)
    let mb = s.meshes.iter().find(|m| m.material != ma.material).unwrap();
    assert_eq!(mb.uvs[1], Vec2::new(1.0, 1.0));
}

#[test]
fn glb_with_image_in_buffer_view() {
    let img = image::RgbaImage::from_fn(3, 1, |x, _| image::Rgba([x as u8 * 100, 50, 25, 255]));
    let png = png_bytes(&img);
    let mut doc = quad_doc().with_materials(json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]));
    let offset = doc.bin.len();
    doc.bin.extend_from_slice(&png);
    doc.json["buffers"][0]["byteLength"] = json!(doc.bin.len());
    doc.json["bufferViews"].as_array_mut().unwrap().push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": png.len() }));
    doc.json["images"] = json!([{ "bufferView": 4, "mimeType": "image/png" }]);
    doc.json["textures"] = json!([{ "source": 0 }]);
    let dir = TempDir::new("glb_image");
    let path = write(&dir, "image", &doc, Form::Glb);
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.textures.len(), 1);
    assert_eq!((s.textures[0].width, s.textures[0].height), (3, 1));
    assert_eq!(s.textures[0].rgba8, img.into_raw());
    assert_eq!(s.materials[0].base_color_texture, Some(0));
}

#[test]
fn unused_images_are_not_decoded() {
    let mut doc = quad_doc();
    doc.json["images"] = json!([{ "uri": "data:image/png;base64,AAAA" }]);
    doc.json["textures"] = json!([{ "source": 0 }]);
    let s = load_doc("unused_image", &doc);
    assert!(s.textures.is_empty());
}

// ------------------------------------------------------------------------ lights, camera

#[test]
fn lights_point_spot_directional() {
    let mut doc = quad_doc();
    let down = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let west = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    doc.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "name": "bulb", "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 10.0, "range": 5.0 },
        { "name": "spot", "type": "spot", "intensity": 2.0, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } },
        { "name": "sun", "type": "directional", "color": [1.0, 1.0, 0.9], "intensity": 3.0 }
    ] } });
    doc.json["nodes"] = json!([
        { "mesh": 0 },
        { "translation": [1.0, 2.0, 3.0], "extensions": { "KHR_lights_punctual": { "light": 0 } } },
        { "translation": [0.0, 3.0, 0.0], "rotation": down.to_array(), "extensions": { "KHR_lights_punctual": { "light": 1 } } },
        { "translation": [5.0, 0.0, 0.0], "children": [4] },
        { "rotation": west.to_array(), "extensions": { "KHR_lights_punctual": { "light": 2 } } }
    ]);
    doc.json["scenes"][0]["nodes"] = json!([0, 1, 2, 3]);
    let s = load_doc("lights", &doc);
    assert_eq!(s.lights.len(), 3);
    let [bulb, spot, sun] = [&s.lights[0], &s.lights[1], &s.lights[2]];
    assert_eq!(bulb.name, "bulb");
    assert_eq!(bulb.kind, LightKind::Point);
    assert!(close(bulb.position, Vec3::new(1.0, 2.0, 3.0)));
    assert!(close(bulb.intensity, Vec3::new(10.0, 5.0, 2.5)));
    assert_eq!(bulb.range, Some(5.0));

    assert_eq!(spot.kind, LightKind::Spot { inner_cone: 0.2, outer_cone: 0.6 });
    assert!(close(spot.position, Vec3::new(0.0, 3.0, 0.0)));
    assert!(close(spot.direction, Vec3::NEG_Y), "{}", spot.direction);
    assert!(close(spot.intensity, Vec3::splat(2.0)));
    assert_eq!(spot.range, None);

    assert_eq!(sun.kind, LightKind::Directional);
    assert!(close(sun.direction, Vec3::NEG_X), "{}", sun.direction);
    assert!(close(sun.position, Vec3::new(5.0, 0.0, 0.0)));
    assert!(close(sun.intensity, Vec3::new(3.0, 3.0, 2.7)));
}

#[test]
fn first_perspective_camera_with_scale_removed() {
    let mut doc = quad_doc();
    let r = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    doc.json["cameras"] = json!([
        { "type": "orthographic", "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } },
        { "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1, "zfar": 100.0, "aspectRatio": 2.0 } },
        { "type": "perspective", "perspective": { "yfov": 0.3, "znear": 0.5 } }
    ]);
    doc.json["nodes"] = json!([
        { "mesh": 0 },
        { "camera": 0 },
        { "scale": [3.0, 3.0, 3.0], "children": [3] },
        { "camera": 1, "translation": [1.0, 2.0, 3.0], "rotation": r.to_array() },
        { "camera": 2, "translation": [9.0, 9.0, 9.0] }
    ]);
    doc.json["scenes"][0]["nodes"] = json!([0, 1, 2, 4]);
    let s = load_doc("camera", &doc);
    let c = s.camera.expect("a camera");
    assert_eq!((c.yfov, c.znear, c.zfar), (0.8, 0.1, Some(100.0)));
    assert!(close(c.position, Vec3::new(3.0, 6.0, 9.0)), "{}", c.position);
    assert!(close(c.forward(), Vec3::NEG_X), "{}", c.forward());
    // Scale removed: the rotation part is orthonormal.
    for axis in [c.world_from_camera.x_axis, c.world_from_camera.y_axis, c.world_from_camera.z_axis] {
        assert!((axis.truncate().length() - 1.0).abs() < 1e-5);
    }
    assert!(close(c.world_from_camera.w_axis.truncate(), c.position));

    // Infinite far plane.
    doc.json["scenes"][0]["nodes"] = json!([0, 4]);
    let s = load_doc("camera_infinite", &doc);
    let c = s.camera.unwrap();
    assert_eq!((c.yfov, c.zfar), (0.3, None));
}

// ------------------------------------------------------------------------ bad input

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let dir = TempDir::new("missing");
    let path = dir.join("does_not_exist.gltf");
    let err = load(&path).unwrap_err();
    assert!(matches!(err, specula::Error::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("does_not_exist.gltf"), "{err}");
}

#[test]
fn malformed_json() {
    let dir = TempDir::new("malformed");
    let path = dir.join("broken.gltf");
    std::fs::write(&path, b"{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ ").unwrap();
    assert_err(load(&path), &path, &["JSON"]);
    std::fs::write(&path, b"").unwrap();
    assert_err(load(&path), &path, &["JSON"]);
}

#[test]
fn accessor_index_out_of_range_in_json() {
    let mut doc = quad_doc();
    doc.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99);
    expect_error("bad_position_accessor", &doc, &["meshes[0].primitives[0].attributes", "POSITION"]);

    let mut doc = quad_doc();
    doc.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(7);
    expect_error("bad_normal_accessor", &doc, &["meshes[0].primitives[0].attributes", "NORMAL"]);

    let mut doc = quad_doc();
    doc.json["meshes"][0]["primitives"][0]["indices"] = json!(42);
    expect_error("bad_indices_accessor", &doc, &["meshes[0].primitives[0].indices"]);

    let mut doc = quad_doc();
    doc.json["accessors"][0]["bufferView"] = json!(12);
    expect_error("bad_buffer_view", &doc, &["accessors[0].bufferView"]);
}

#[test]
fn vertex_index_out_of_range() {
    let mut doc = quad_doc();
    doc.set_u32(IDX_OFFSET + 5 * 4, 7);
    expect_error("bad_vertex_index", &doc, &["meshes[0].primitives[0].indices", "index 7", "4 vertices"]);
}

#[test]
fn nan_and_infinite_positions() {
    let mut doc = quad_doc();
    doc.set_f32(POS_OFFSET + 2 * 12 + 4, f32::NAN);
    expect_error("nan_position", &doc, &["meshes[0].primitives[0].attributes.POSITION", "vertex 2", "not finite"]);
    let mut doc = quad_doc();
    doc.set_f32(POS_OFFSET, f32::INFINITY);
    expect_error("inf_position", &doc, &["meshes[0].primitives[0].attributes.POSITION", "vertex 0"]);
}

/// KHR_materials_ior's schema admits 0 (its specular-glossiness compatibility mode: infinite
/// IOR, Fresnel 1 at every angle) or values ≥ 1; 0 on a transmissive material imports as an
/// ideal mirror of reflectance 1, anything in (0, 1) or below 0 is refused.
#[test]
fn ior_zero_or_negative() {
    let doc = quad_doc().with_materials(json!([{
        "name": "infinite", "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
        "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": 0.0 } }
    }]));
    let s = load_doc("ior_zero", &doc);
    let SurfaceKind::Mirror { nu, kappa } = material(&s, "infinite").kind else { panic!("{:?}", material(&s, "infinite").kind) };
    let f =
        specula::optics::fresnel_conductor(1.0, nu.x as f64, kappa.x as f64).min(specula::optics::fresnel_f0(nu.x as f64, kappa.x as f64));
    assert!(f > 1.0 - 1e-6, "reflectance {f}");
    for ior in [0.5, -1.0] {
        let doc = quad_doc().with_materials(json!([{
            "pbrMetallicRoughness": { "metallicFactor": 0.0, "roughnessFactor": 0.0 },
            "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1.0 }, "KHR_materials_ior": { "ior": ior } }
        }]));
        let msg = expect_error("bad_ior", &doc, &["materials[0].extensions.KHR_materials_ior.ior"]);
        assert!(msg.contains(&format!("{ior}")), "{msg}");
    }
    // Also on a material no primitive uses, and on a non-transmissive one.
    let mut doc = quad_doc().with_materials(json!([{ "name": "fine" }]));
    doc.json["materials"].as_array_mut().unwrap().push(json!({ "extensions": { "KHR_materials_ior": { "ior": -2.0 } } }));
    expect_error("bad_ior_unused", &doc, &["materials[1].extensions.KHR_materials_ior.ior"]);
}

#[test]
fn bad_mirror_extras() {
    let doc = quad_doc().with_materials(json!([{
        "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.0 },
        "extras": { "specula": { "nu": [1.0, "x", 1.0] } }
    }]));
    expect_error("bad_nu", &doc, &["materials[0].extras.specula.nu"]);
    let doc = quad_doc().with_materials(json!([{
        "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.0 },
        "extras": { "specula": { "nu": [-1.0, 1.0, 1.0], "kappa": [0.0, 0.0, 0.0] } }
    }]));
    expect_error("negative_nu", &doc, &["materials[0].extras.specula"]);
}

#[test]
fn texture_that_will_not_decode() {
    let dir = TempDir::new("bad_png");
    let mut doc = quad_doc().with_materials(json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]));
    doc.json["images"] = json!([{ "uri": "missing.png" }, { "uri": "wall.png" }]);
    doc.json["textures"] = json!([{ "source": 1 }]);
    let mut garbage = b"\x89PNG\r\n\x1a\n".to_vec();
    garbage.extend_from_slice(b"this is not a PNG body at all");
    std::fs::write(dir.join("wall.png"), &garbage).unwrap();
    let path = write(&dir, "bad_png", &doc, Form::External);
    assert_err(load(&path), &path, &["images[1] (uri \"wall.png\")", "decode"]);

    // An embedded (data URI) image that is garbage.
    doc.json["images"][1]["uri"] = json!(format!("data:image/png;base64,{}", b64(b"garbage garbage")));
    let path = write(&dir, "bad_png_embedded", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["images[1]", "decode"]);

    // A missing image file.
    doc.json["textures"] = json!([{ "source": 0 }]);
    let path = write(&dir, "missing_png", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["images[0] (uri \"missing.png\")", "missing.png"]);
}

#[test]
fn buffer_shorter_than_its_views() {
    let dir = TempDir::new("short_buffer");
    // The .bin holds fewer bytes than the buffer declares.
    let mut doc = quad_doc();
    doc.bin.truncate(100);
    let path = write(&dir, "short_bin", &doc, Form::External);
    assert_err(load(&path), &path, &["buffers[0]", "152", "100"]);

    // The same, embedded and as GLB.
    let path = write(&dir, "short_embedded", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["buffers[0]"]);
    let path = write(&dir, "short_glb", &doc, Form::Glb);
    assert_err(load(&path), &path, &["buffers[0]"]);

    // A view that reaches past the end of its buffer.
    let mut doc = quad_doc();
    doc.json["bufferViews"][3]["byteLength"] = json!(240);
    let path = write(&dir, "long_view", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["bufferViews[3]"]);

    // An accessor that reaches past the end of its view.
    let mut doc = quad_doc();
    doc.json["accessors"][0]["count"] = json!(10);
    let path = write(&dir, "long_accessor", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["accessors[0]"]);
    let mut doc = quad_doc();
    doc.json["accessors"][2]["byteOffset"] = json!(8);
    let path = write(&dir, "offset_accessor", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["accessors[2]"]);
    // An accessor with a huge count.
    let mut doc = quad_doc();
    doc.json["accessors"][3]["count"] = json!(4_000_000_000u64);
    let path = write(&dir, "huge_accessor", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["accessors[3]"]);
    let mut doc = quad_doc();
    doc.json["accessors"][0]["count"] = json!(3_000_000_000u64);
    let path = write(&dir, "huge_positions", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["accessors[0]"]);
    doc.json["accessors"][0].as_object_mut().unwrap().remove("bufferView");
    let path = write(&dir, "huge_zero_positions", &doc, Form::Embedded);
    assert_err(load(&path), &path, &["accessors[0]"]);
}

#[test]
fn malformed_containers_and_references_never_panic() {
    let dir = TempDir::new("malformed_misc");

    // Truncated GLB.
    let doc = quad_doc();
    let glb = glb_bytes(&doc.json, &doc.bin);
    let path = dir.join("truncated.glb");
    std::fs::write(&path, &glb[..glb.len() - 40]).unwrap();
    assert_err(load(&path), &path, &[]);
    std::fs::write(&path, &glb[..10]).unwrap();
    assert_err(load(&path), &path, &[]);

    // A node that is its own ancestor.
    let mut doc = quad_doc();
    doc.json["nodes"] = json!([{ "mesh": 0, "children": [1] }, { "children": [0] }]);
    expect_error("cycle", &doc, &["nodes[", "cycle"]);

    // A light index without any lights.
    let mut doc = quad_doc();
    doc.json["nodes"][0]["extensions"] = json!({ "KHR_lights_punctual": { "light": 3 } });
    expect_error("no_lights", &doc, &["nodes[0].extensions.KHR_lights_punctual.light"]);

    // A spot light without its spot object.
    let mut doc = quad_doc();
    doc.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [{ "type": "spot" }] } });
    doc.json["nodes"][0]["extensions"] = json!({ "KHR_lights_punctual": { "light": 0 } });
    expect_error("spot_without_spot", &doc, &["extensions.KHR_lights_punctual.lights[0].spot"]);

    // A spot light with inverted cone angles.
    doc.json["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"] = json!({ "innerConeAngle": 0.7, "outerConeAngle": 0.2 });
    expect_error("spot_cones", &doc, &["extensions.KHR_lights_punctual.lights[0].spot"]);

    // A "perspective" camera whose perspective object is missing.
    let mut doc = quad_doc();
    doc.json["cameras"] = json!([{ "type": "perspective", "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0 } }]);
    doc.json["nodes"][0]["camera"] = json!(0);
    expect_error("camera_without_perspective", &doc, &["cameras[0].perspective"]);

    // A camera with a zero field of view.
    doc.json["cameras"] = json!([{ "type": "perspective", "perspective": { "yfov": 0.0, "znear": 0.1 } }]);
    expect_error("camera_yfov", &doc, &["cameras[0].perspective.yfov"]);

    // Unknown primitive mode, unknown component type.
    let mut doc = quad_doc();
    doc.json["meshes"][0]["primitives"][0]["mode"] = json!(42);
    expect_error("bad_mode", &doc, &["meshes[0].primitives[0].mode"]);
    let mut doc = quad_doc();
    doc.json["accessors"][0]["componentType"] = json!(5121);
    doc.json["accessors"][0]["normalized"] = json!(false);
    expect_error("u8_positions", &doc, &["meshes[0].primitives[0].attributes.POSITION"]);

    // A buffer URI that does not percent-decode to UTF-8, and one with an unknown scheme.
    let mut doc = quad_doc();
    doc.json["buffers"][0]["uri"] = json!("%FF%FE.bin");
    let path = dir.join("bad_uri.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc.json).unwrap()).unwrap();
    assert_err(load(&path), &path, &["buffers[0]"]);
    doc.json["buffers"][0]["uri"] = json!("https://example.com/x.bin");
    std::fs::write(&path, serde_json::to_vec(&doc.json).unwrap()).unwrap();
    assert_err(load(&path), &path, &["buffers[0]", "scheme"]);
    // A missing external buffer.
    doc.json["buffers"][0]["uri"] = json!("nowhere.bin");
    std::fs::write(&path, serde_json::to_vec(&doc.json).unwrap()).unwrap();
    assert_err(load(&path), &path, &["buffers[0]", "nowhere.bin"]);
    // A buffer without URI in a .gltf (no BIN chunk).
    doc.json["buffers"][0].as_object_mut().unwrap().remove("uri");
    std::fs::write(&path, serde_json::to_vec(&doc.json).unwrap()).unwrap();
    assert_err(load(&path), &path, &["buffers[0]"]);

    // Indices not a whole number of triangles.
    let mut doc = quad_doc();
    doc.json["accessors"][3]["count"] = json!(5);
    expect_error("partial_triangle", &doc, &["meshes[0].primitives[0].indices", "5 indices"]);

    // A required extension nobody supports.
    let mut doc = quad_doc();
    doc.json["extensionsRequired"] = json!(["EXT_meshopt_compression"]);
    expect_error("required_extension", &doc, &["extensionsRequired"]);
}

// ------------------------------------------------------------------------ demo scene

#[test]
fn demo_scene_loads_with_expected_classification() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo/demo.gltf");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    let kinds: Vec<SurfaceKind> = s.materials.iter().map(|m| m.kind).collect();
    let diffuse = kinds.iter().filter(|k| **k == SurfaceKind::Diffuse).count();
    let mirrors = kinds.iter().filter(|k| matches!(k, SurfaceKind::Mirror { .. })).count();
    let solid = kinds.iter().filter(|k| matches!(k, SurfaceKind::Dielectric { thin: false, ior } if *ior == 1.5)).count();
    assert_eq!((s.materials.len(), diffuse, mirrors, solid), (9, 7, 1, 1));
    assert_eq!(s.textures.len(), 6);
    for name in ["floor", "ceiling", "back", "front", "left", "right"] {
        let m = material(&s, &format!("wall_{name}"));
        assert_eq!(m.kind, SurfaceKind::Diffuse);
        assert!(m.base_color_texture.is_some());
    }
    // The mirror's ν, κ reproduce its base colour as F0.
    let mirror = material(&s, "mirror");
    let SurfaceKind::Mirror { nu, kappa } = mirror.kind else { panic!() };
    let f0 = ((nu - 1.0) * (nu - 1.0) + kappa * kappa) / ((nu + 1.0) * (nu + 1.0) + kappa * kappa);
    assert!((f0 - mirror.base_color).abs().max_element() < 1e-3, "{f0} vs {}", mirror.base_color);

    // Room bounds and inward-facing walls.
    let b = s.bounds();
    assert!(close(b.min, Vec3::new(-2.0, 0.0, -2.0)) && close(b.max, Vec3::new(2.0, 3.0, 2.0)), "{b:?}");
    let centre = Vec3::new(0.0, 1.5, 0.0);
    for m in s.meshes.iter().filter(|m| m.name.starts_with("wall_")) {
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(n.dot(centre - *p) > 0.0, "{} faces outwards", m.name);
        }
        for t in m.indices.chunks_exact(3) {
            let (p0, p1, p2) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
            assert!((p1 - p0).cross(p2 - p0).dot(m.normals[t[0] as usize]) > 0.0, "{} winding", m.name);
        }
    }
    // Spheres where they should be.
    let sphere = |name: &str| s.meshes.iter().find(|m| m.name.starts_with(name)).unwrap().bounds();
    assert!(close(sphere("mirror_sphere").center(), Vec3::new(-1.2, 0.5, -1.1)));
    assert!(close(sphere("glass_sphere").center(), Vec3::new(0.9, 0.45, -0.3)));

    let light = &s.lights[0];
    assert_eq!((s.lights.len(), light.kind), (1, LightKind::Point));
    assert!(close(light.position, Vec3::new(0.0, 1.6, 0.0)) && close(light.intensity, Vec3::splat(6.5)));
    let c = s.camera.expect("demo camera");
    assert!(close(c.position, Vec3::new(1.6, 1.6, 1.9)));
    assert!((c.yfov - 60f32.to_radians()).abs() < 1e-5);
    let towards = (Vec3::new(-0.3, 0.8, -0.6) - c.position).normalize();
    assert!(close(c.forward(), towards), "{} vs {towards}", c.forward());
}

// ------------------------------------------------------------------------ environment maps

#[test]
fn environment_from_exr_round_trips() {
    let dir = TempDir::new("env_exr");
    let (w, h) = (4u32, 2u32);
    let pixels: Vec<f32> = (0..w * h).flat_map(|i| [i as f32 * 0.5, 10.0 + i as f32, 0.25, 1.0]).collect();
    let path = dir.join("sky.exr");
    write_exr(&path, w, h, &pixels).unwrap();
    let env = load_environment(&path).unwrap();
    assert_eq!((env.width, env.height), (w, h));
    assert_eq!(env.rgba32f, pixels);
}

#[test]
fn environment_from_png_is_decoded_to_linear() {
    let dir = TempDir::new("env_png");
    // Bytes written by the `image` crate (not the library's writer), decoded by the sRGB
    // transfer function written out here (IEC 61966-2-1).
    let bytes: [u8; 8] = [0, 64, 128, 255, 188, 10, 255, 255];
    let path = dir.join("sky.png");
    image::RgbaImage::from_raw(2, 1, bytes.to_vec()).unwrap().save(&path).unwrap();
    let env = load_environment(&path).unwrap();
    assert_eq!((env.width, env.height), (2, 1));
    let decode = |b: u8| {
        let c = b as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for (i, (a, b)) in env.rgba32f.iter().zip(bytes).enumerate() {
        // Alpha is linear already.
        let want = if i % 4 == 3 { b as f64 / 255.0 } else { decode(b) };
        assert!((*a as f64 - want).abs() < 1e-4, "channel {i}: {a} vs {want} ({:?})", env.rgba32f);
    }
    assert!((env.rgba32f[1] - 0.0513).abs() < 1e-3 && (env.rgba32f[2] - 0.2159).abs() < 1e-3, "{:?}", env.rgba32f);
}

#[test]
fn environment_errors_name_the_file() {
    let dir = TempDir::new("env_errors");
    let missing = dir.join("nowhere.exr");
    let err = load_environment(&missing).unwrap_err();
    assert!(err.to_string().contains("nowhere.exr"), "{err}");
    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"definitely not an exr").unwrap();
    let err = load_environment(&garbage).unwrap_err();
    assert!(err.to_string().contains("garbage.exr"), "{err}");
    let garbage = dir.join("garbage.hdr");
    std::fs::write(&garbage, b"#?RADIANCE\nnonsense").unwrap();
    let err = load_environment(&garbage).unwrap_err();
    assert!(err.to_string().contains("garbage.hdr"), "{err}");
    // Wrong pixel count when writing.
    assert!(write_exr(&dir.join("x.exr"), 2, 2, &[0.0; 3]).is_err());
    assert!(write_png_srgb(&dir.join("x.png"), 2, 2, &[0.0; 3]).is_err());
}

#[test]
fn srgb_helpers_round_trip() {
    for v in 0..=255u8 {
        assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
    }
    assert_eq!(srgb_to_linear(0), 0.0);
    assert_eq!(srgb_to_linear(255), 1.0);
    assert_eq!(linear_to_srgb(-1.0), 0);
    assert_eq!(linear_to_srgb(f32::NAN), 0);
    assert_eq!(linear_to_srgb(7.0), 255);
    assert!((srgb_to_linear(188) - 0.5).abs() < 0.003);
}

/// `extras.specula.method` on the node or the material: the object's method when the whole
/// scene asks for `auto`; the node's wins; the object answers to its mesh and node names.
#[test]
fn method_from_extras() {
    let mirror = json!([{ "name": "m", "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.0 },
                          "extras": { "specula": { "method": "proxy-box" } } }]);
    let mut doc = quad_doc().with_materials(mirror.clone());
    doc.json["nodes"][0]["name"] = json!("wall_mirror");
    let s = load_doc("method_material", &doc);
    assert_eq!(s.meshes[0].method.as_deref(), Some("proxy-box"));
    assert!(
        s.meshes[0].aliases.contains(&"quad".to_string()) && s.meshes[0].aliases.contains(&"wall_mirror".to_string()),
        "{:?}",
        s.meshes[0].aliases
    );
    let p = specula::plan(&s, specula::Choice::Auto, &specula::Quality::default());
    assert_eq!(p.objects[0].method.name(), "proxy-box");
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "method": "distance" } });
    assert_eq!(load_doc("method_node", &doc).meshes[0].method.as_deref(), Some("distance"));
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "method": "auto" } });
    assert_eq!(load_doc("method_auto", &doc).meshes[0].method, None);
    // Refused, naming the field and the value.
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "method": "warp-drive" } });
    expect_error("method_unknown", &doc, &["nodes[0].extras.specula.method", "warp-drive"]);
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "method": 3 } });
    expect_error("method_number", &doc, &["nodes[0].extras.specula.method", "method name"]);
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "method": "refractor-map" } });
    expect_error("method_cannot_serve", &doc, &["nodes[0].extras.specula.method", "cannot serve this mirror"]);
    doc.json["nodes"][0]["extras"] = json!({ "specula": { "method": "reference" } });
    expect_error("method_cpu", &doc, &["nodes[0].extras.specula.method", "CPU"]);
}

/// A scene with nothing to render (lines, points, a mesh without primitives): `info` lists
/// it and `render` refuses it, both exit 1 with the same one line naming the file, the mesh,
/// the primitive and its mode.
#[test]
fn info_and_render_agree_on_a_scene_without_triangles() {
    let mut doc = quad_doc();
    let mut lines = doc.json["meshes"][0]["primitives"][0].clone();
    lines["mode"] = json!(1);
    let mut points = lines.clone();
    points["mode"] = json!(0);
    doc.json["meshes"][0]["primitives"] = json!([lines, points]);
    let dir = TempDir::new("no_triangles");
    let path = write(&dir, "no_triangles", &doc, Form::Embedded);
    let s = load(&path).unwrap();
    assert_eq!(s.skipped.len(), 2, "{:?}", s.skipped);
    let exe = env!("CARGO_BIN_EXE_specula");
    let mut lines_of = Vec::new();
    for args in [&["info", path.to_str().unwrap()][..], &["render", path.to_str().unwrap(), "--out", dir.join("x.png").to_str().unwrap()]] {
        let o = std::process::Command::new(exe).args(args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        for want in ["no_triangles.gltf", "no triangles", "meshes[0].primitives[0]", "Lines", "meshes[0].primitives[1]", "Points"] {
            assert!(err.contains(want), "{args:?}: {err} lacks {want}");
        }
        lines_of.push(err);
    }
    assert_eq!(lines_of[0], lines_of[1], "info and render say the same");
}

/// The schema's rules through the loader (the full table is in src/scene/gltf/schema.rs's
/// unit tests): each refusal names the JSON path and the value.
#[test]
fn schema_rules_are_enforced() {
    let mut doc = quad_doc();
    doc.json["asset"]["version"] = json!("1.0");
    expect_error("version_1", &doc, &["asset.version", "1.0"]);
    let mut doc = quad_doc();
    doc.json["asset"]["minVersion"] = json!("2.1");
    expect_error("min_version", &doc, &["asset.minVersion", "2.1"]);
    let mut doc = quad_doc();
    doc.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    doc.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    expect_error("required", &doc, &["extensionsRequired[0]", "KHR_draco_mesh_compression"]);
    let mut doc = quad_doc();
    doc.json["bufferViews"][0]["byteStride"] = json!(8);
    expect_error("stride", &doc, &["bufferViews[0].byteStride"]);
    for (tag, m, needles) in [
        (
            "transmission_2",
            json!({ "extensions": { "KHR_materials_transmission": { "transmissionFactor": 2.0 } } }),
            ["transmissionFactor", "2"],
        ),
        ("thickness_neg", json!({ "extensions": { "KHR_materials_volume": { "thicknessFactor": -1.0 } } }), ["thicknessFactor", "-1"]),
        ("emissive_neg", json!({ "emissiveFactor": [-1.0, 0.0, 0.0] }), ["emissiveFactor[0]", "-1"]),
        ("albedo_2", json!({ "pbrMetallicRoughness": { "baseColorFactor": [2.0, 1.0, 1.0, 1.0] } }), ["baseColorFactor[0]", "2"]),
        ("ior_half", json!({ "extensions": { "KHR_materials_ior": { "ior": 0.5 } } }), ["KHR_materials_ior.ior", "0.5"]),
    ] {
        let doc = quad_doc().with_materials(json!([m]));
        expect_error(tag, &doc, &needles);
    }
    let mut doc = quad_doc();
    doc.json["cameras"] = json!([{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1, "aspectRatio": 0.0 } }]);
    expect_error("aspect_0", &doc, &["cameras[0].perspective.aspectRatio"]);
}

/// A texture whose PNG header declares 65536×65536 pixels is refused before decoding,
/// naming the image and the declared size.
#[test]
fn huge_declared_texture_is_refused() {
    let png = common::huge_png_bytes();
    let mut doc = quad_doc().with_materials(json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]));
    doc.json["images"] = json!([{ "uri": format!("data:image/png;base64,{}", b64(&png)) }]);
    doc.json["textures"] = json!([{ "source": 0 }]);
    expect_error("huge_texture", &doc, &["images[0]", "declares 65536×65536"]);
}

/// GLB headers and chunk tables that lie about their lengths (one made the `gltf` crate
/// subtract with overflow: found by tests/fuzz_replay.rs) are refused naming the field.
#[test]
fn glb_header_lengths_are_checked() {
    let dir = TempDir::new("glb_header");
    let doc = quad_doc();
    let glb = glb_bytes(&doc.json, &doc.bin);
    type Patch = Box<dyn Fn(&mut Vec<u8>)>;
    let cases: [(&str, Patch, &[&str]); 4] = [
        ("version", Box::new(|g: &mut Vec<u8>| g[4..8].copy_from_slice(&0x3f00_0002u32.to_le_bytes())), &["(GLB header)", "version"]),
        ("zero_length", Box::new(|g: &mut Vec<u8>| g[8..12].copy_from_slice(&0u32.to_le_bytes())), &["(GLB header)", "declares 0 bytes"]),
        ("long", Box::new(|g: &mut Vec<u8>| g[8..12].copy_from_slice(&1_000_000u32.to_le_bytes())), &["(GLB header)", "1000000"]),
        (
            "chunk",
            Box::new(|g: &mut Vec<u8>| g[12..16].copy_from_slice(&0xffff_fff0u32.to_le_bytes())),
            &["(GLB chunk 0)", "past the declared"],
        ),
    ];
    for (tag, patch, needles) in cases {
        let mut g = glb.clone();
        patch(&mut g);
        let path = dir.join(&format!("{tag}.glb"));
        std::fs::write(&path, &g).unwrap();
        assert_err(load(&path), &path, needles);
    }
}

/// A `.gltf` buffer without a uri is reported as that, not as a GLB chunk problem.
#[test]
fn gltf_buffer_without_uri() {
    let doc = quad_doc();
    let dir = TempDir::new("no_uri");
    let path = dir.join("no_uri.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc.json).unwrap()).unwrap();
    let msg = assert_err(load(&path), &path, &["buffers[0].uri", "missing"]);
    assert!(!msg.contains("GLB"), "{msg}");
}
