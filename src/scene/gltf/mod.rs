//! glTF 2.0 import (`.gltf` with external or embedded buffers, `.glb`) into a world-space
//! [`Scene`].
//!
//! The `gltf` crate parses and validates the JSON; everything that touches binary data
//! (buffers, buffer views, accessors, images) is read and bounds-checked here, so that a
//! malformed file gives an [`Error::Scene`] naming the file and the offending field
//! (`meshes[0].primitives[1].attributes.POSITION`, `images[2] (uri "wall.png")` …) and
//! never a panic.
//!
//! Choices where glTF leaves room:
//! - Primitive modes: triangles, triangle strips and triangle fans are imported (strips and
//!   fans are converted to lists); points and lines are skipped without error, as are
//!   primitives with no vertices or no triangles.
//! - Materials are imported when a drawn primitive uses them (so `Scene::materials` is not
//!   indexed like the glTF `materials` array), but every material's scalar parameters
//!   (KHR_materials_ior, KHR_materials_emissive_strength) are validated up front.
//!   Only images that an imported base-colour or emissive texture refers to are decoded.
//! - Texture coordinates: the set the base-colour texture names (KHR_texture_transform's
//!   `texCoord` override included; set 0 without a base-colour texture), with the base-colour
//!   texture's KHR_texture_transform applied. The emissive texture shares these coordinates.
//! - Only perspective cameras are considered; orthographic ones are ignored. The first one
//!   in depth-first traversal order wins.
//! - `extras.specula.reference_point` (on the node, else on the mesh) is given in the node's
//!   local frame and transformed to world space.
//! - `extras.specula.method` (on the node, else on the material): the method of that
//!   specular object when the whole scene's method is `auto` (a registered GPU method's
//!   name, or "auto"); an unknown name is an error naming the field.
//! - Objects are named `<mesh name>/<primitive>`; the mesh name and the node name address
//!   them too (`--object NAME=METHOD`, the C ABI).
//! - Animations (translation, rotation, scale; STEP, LINEAR, CUBICSPLINE) are read into
//!   `Scene::animation`; the scene is loaded in the nodes' static pose and
//!   `Scene::set_time` poses it. Skins and morph targets are ignored.
//! - A node hierarchy with a cycle is an error.
//!
//! - The glTF schema's rules the `gltf` crate leaves unchecked (versions, required
//!   extensions, strides, factor and camera/light ranges) are enforced first (`schema`).
//!
//! Files: this one parses the document and holds the importer's state; `schema` checks the
//! JSON against the schema's rules; `accessors` reads
//! the binary data (buffers, buffer views, accessors, images), `translate` turns nodes,
//! meshes, materials, lights and the camera into the scene.

mod accessors;
mod animations;
pub mod schema;
mod translate;

use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};

use gltf::json::validation::Checked;

use super::Scene;
use crate::error::{Error, Result};

/// Loads a `.gltf` or `.glb` file into a world-space scene. See the module documentation.
pub fn load(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let base = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    load_slice(&path.display().to_string(), &bytes, &base)
}

/// Loads a `.gltf` or `.glb` held in memory, named `file` in messages, with external URIs
/// resolved against `base` (the fuzz targets' entry point).
pub fn load_slice(file: &str, bytes: &[u8], base: &Path) -> Result<Scene> {
    // Everything below checks its input; the unwind guard is a last line of defence against
    // a panic inside a dependency on input nobody anticipated.
    match std::panic::catch_unwind(AssertUnwindSafe(|| import(file, base.to_path_buf(), bytes))) {
        Ok(result) => result,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(Error::scene(file, "(document)", format!("internal error while importing: {what}")))
        }
    }
}

/// Checks a GLB container's header and chunk table against the bytes before the `gltf`
/// crate reads it (it subtracts declared lengths unchecked: found by fuzzing).
fn precheck_glb(file: &str, bytes: &[u8]) -> Result<()> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let err = |field: &str, m: String| Error::scene(file, format!("(GLB {field})"), m);
    let u32_at = |i: usize| bytes.get(i..i + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(err("header", format!("{} bytes, shorter than the 12-byte header", bytes.len())));
    };
    if version != 2 {
        return Err(err("header", format!("version {version}, expected 2")));
    }
    let length = length as usize;
    if length < 12 || length > bytes.len() {
        return Err(err("header", format!("declares {length} bytes; the file holds {} and the header alone is 12", bytes.len())));
    }
    let mut at = 12;
    let mut index = 0;
    while at < length {
        let (Some(chunk_len), Some(kind)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(err(&format!("chunk {index}"), format!("header at byte {at} runs past the declared {length} bytes")));
        };
        let end = (at + 8).checked_add(chunk_len as usize).filter(|&e| e <= length);
        let Some(end) = end else {
            return Err(err(&format!("chunk {index}"), format!("declares {chunk_len} bytes at byte {at}, past the declared {length}")));
        };
        if index == 0 && kind != 0x4E4F_534A {
            return Err(err("chunk 0", format!("type 0x{kind:08x}, expected JSON")));
        }
        at = end;
        index += 1;
    }
    if index == 0 {
        return Err(err("chunk 0", "missing: a GLB starts with a JSON chunk".into()));
    }
    Ok(())
}

fn import(file: &str, base: PathBuf, bytes: &[u8]) -> Result<Scene> {
    precheck_glb(file, bytes)?;
    let gltf = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| gltf_error(file, e))?;
    let (doc, blob) = (gltf.document, gltf.blob);
    // gltf-json's validation indexes the POSITION accessor before checking the index.
    precheck(file, doc.as_json())?;
    let doc = gltf::Document::from_json(doc.into_json()).map_err(|e| gltf_error(file, e))?;
    // The schema's ranges and rules that the gltf crate leaves unchecked (on the validated
    // document: every enum is valid, so it serialises back).
    let json =
        serde_json::to_value(doc.as_json()).map_err(|e| Error::scene(file, "(JSON)", format!("cannot re-read the document: {e}")))?;
    schema::check(file, &json)?;

    let mut imp = Importer {
        file,
        glb: bytes.starts_with(b"glTF"),
        base,
        doc: &doc,
        buffers: Vec::new(),
        scene: Scene::new(),
        materials: HashMap::new(),
        default_material: None,
        textures: HashMap::new(),
    };
    imp.buffers = imp.load_buffers(blob)?;
    for material in doc.materials() {
        imp.check_material_scalars(&material)?;
    }
    imp.walk()?;
    imp.import_animations()?;
    Ok(imp.scene)
}

/// gltf-json spells extension names in its paths as Rust fields ("khrLightsPunctual").
fn extension_names(path: String) -> String {
    const NAMES: &[(&str, &str)] = &[
        ("khrLightsPunctual", "KHR_lights_punctual"),
        ("khrMaterialsIor", "KHR_materials_ior"),
        ("khrMaterialsTransmission", "KHR_materials_transmission"),
        ("khrMaterialsVolume", "KHR_materials_volume"),
        ("khrMaterialsSpecular", "KHR_materials_specular"),
        ("khrMaterialsEmissiveStrength", "KHR_materials_emissive_strength"),
        ("khrTextureTransform", "KHR_texture_transform"),
        ("textureTransform", "KHR_texture_transform"),
    ];
    NAMES.iter().fold(path, |p, (from, to)| p.replace(from, to))
}

/// Wraps a `gltf` crate error; validation errors name the first offending path.
fn gltf_error(file: &str, e: gltf::Error) -> Error {
    match e {
        gltf::Error::Validation(list) => {
            let field = list.first().map(|(p, _)| extension_names(p.to_string())).unwrap_or_else(|| "(document)".into());
            let message = list.iter().map(|(p, e)| format!("{}: {e}", extension_names(p.to_string()))).collect::<Vec<_>>().join("; ");
            Error::scene(file, field, format!("invalid glTF: {message}"))
        }
        gltf::Error::Deserialize(e) => Error::scene(file, "(JSON)", format!("malformed glTF JSON: {e}")),
        gltf::Error::Binary(e) => Error::scene(file, "(GLB container)", format!("malformed GLB: {e}")),
        other => Error::scene(file, "(document)", other.to_string()),
    }
}

/// Checks what gltf-json's validation would otherwise index out of range.
fn precheck(file: &str, root: &gltf::json::Root) -> Result<()> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let name = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "?".into(),
                    };
                    return Err(Error::scene(
                        file,
                        format!("meshes[{m}].primitives[{p}].attributes.{name}"),
                        format!("accessor index {} out of range ({} accessors)", index.value(), root.accessors.len()),
                    ));
                }
            }
        }
    }
    Ok(())
}

struct Importer<'a> {
    file: &'a str,
    /// The file is a GLB container (it may have a BIN chunk).
    glb: bool,
    base: PathBuf,
    doc: &'a gltf::Document,
    buffers: Vec<Vec<u8>>,
    scene: Scene,
    /// glTF material index → scene material.
    materials: HashMap<usize, usize>,
    default_material: Option<usize>,
    /// glTF image index → scene texture.
    textures: HashMap<usize, usize>,
}

impl<'a> Importer<'a> {
    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::scene(self.file, field, message)
    }
}
