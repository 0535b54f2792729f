//! Fuzz targets: each takes arbitrary bytes and must return without a panic, a crash or an
//! "internal error" (a panic that the importer's last-line guard caught). They are run by
//! `cargo fuzz` (fuzz/, libFuzzer) and, on a checked-in seed corpus with deterministic
//! mutations, by `tests/fuzz_replay.rs` inside `cargo test`.

use std::ffi::CString;
use std::path::Path;

use crate::ffi::*;

/// What a target found wrong with one input.
pub type Finding = String;

fn internal(e: &crate::Error) -> Option<Finding> {
    let m = e.to_string();
    m.contains("internal error").then_some(m)
}

/// The glTF / GLB importer on `data` (as a `.gltf` or `.glb` in memory; external URIs
/// resolve against a folder that does not exist).
pub fn gltf(data: &[u8]) -> Option<Finding> {
    match crate::scene::gltf::load_slice("fuzz.gltf", data, Path::new("/nonexistent-specula-fuzz")) {
        Ok(scene) => scene.validate().err().map(|e| format!("imported scene fails its own validation: {e}")),
        Err(e) => internal(&e),
    }
}

/// The environment-map loader on `data` written as a file with extension `ext` (exr, hdr,
/// png, jpg) under `dir`.
pub fn environment(dir: &Path, ext: &str, data: &[u8]) -> Option<Finding> {
    let path = dir.join(format!("fuzz.{ext}"));
    if let Err(e) = std::fs::write(&path, data) {
        return Some(format!("cannot write the input: {e}"));
    }
    match crate::scene::load_environment(&path) {
        Ok(env) => env.validate().err().map(|e| format!("loaded map fails its own validation: {e}")),
        Err(e) => internal(&e),
    }
}

/// Bytes as a `T` (zero-filled when short).
fn read<T>(data: &[u8]) -> T {
    let mut v = std::mem::MaybeUninit::<T>::zeroed();
    let n = data.len().min(std::mem::size_of::<T>());
    // SAFETY: T is a plain repr(C) struct of integers, floats and pointers (set to NULL
    // below before use); any bit pattern of those is a value.
    unsafe {
        std::ptr::copy_nonoverlapping(data.as_ptr(), v.as_mut_ptr() as *mut u8, n);
        v.assume_init()
    }
}

/// The C ABI's struct parsing: a sequence of calls on `ctx`, each chosen and filled from
/// the input (type tags and sizes right half the time), with every pointer NULL or valid.
/// Every call must return a result code; a panic or a crash is the finding.
///
/// # Safety
/// `ctx` is a live context from `specula_context_create`.
pub unsafe fn c_abi(ctx: *mut SpeculaContext, data: &[u8]) -> Option<Finding> {
    let mut rest = data;
    while rest.len() > 2 {
        let (op, fix) = (rest[0] % 7, rest[1] & 1 == 0);
        rest = &rest[2..];
        let take = rest.len().min(96);
        let (chunk, tail) = rest.split_at(take);
        rest = tail;
        let r = match op {
            0 => {
                let mut d: SpeculaMaterialDesc = read(chunk);
                if fix {
                    (d.r#type, d.size) = (SPECULA_STRUCT_MATERIAL_DESC, std::mem::size_of::<SpeculaMaterialDesc>() as u32);
                }
                let mut out = 0;
                specula_context_add_material(ctx, &d, &mut out)
            }
            1 => {
                let mut d: SpeculaLightDesc = read(chunk);
                if fix {
                    (d.r#type, d.size) = (SPECULA_STRUCT_LIGHT_DESC, std::mem::size_of::<SpeculaLightDesc>() as u32);
                }
                specula_context_add_light(ctx, &d)
            }
            2 => {
                let mut d: SpeculaCameraDesc = read(chunk);
                if fix {
                    (d.r#type, d.size) = (SPECULA_STRUCT_CAMERA_DESC, std::mem::size_of::<SpeculaCameraDesc>() as u32);
                }
                specula_context_set_camera(ctx, &d)
            }
            3 => {
                // A mesh from the input's floats and indices, pointers valid.
                let floats: Vec<f32> = chunk.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
                let n = (floats.len() / 3).max(1);
                let positions: Vec<f32> = floats.iter().copied().chain(std::iter::repeat(0.0)).take(3 * n).collect();
                let indices: Vec<u32> = chunk.iter().map(|&b| b as u32 % (n as u32 + 1)).take(3 * (chunk.len() / 3).max(1)).collect();
                let mut d: SpeculaMeshDesc = read(&[]);
                d.r#type = SPECULA_STRUCT_MESH_DESC;
                d.size = if fix { std::mem::size_of::<SpeculaMeshDesc>() as u32 } else { chunk.first().copied().unwrap_or(0) as u32 };
                d.positions = positions.as_ptr();
                d.vertex_count = n as u32;
                d.indices = indices.as_ptr();
                d.index_count = indices.len() as u32;
                d.material = chunk.get(1).copied().unwrap_or(0) as u32 % 4;
                let mut out = 0;
                specula_context_add_mesh(ctx, &d, &mut out)
            }
            4 => {
                let mut d: SpeculaRenderDesc = read(chunk);
                // Pointers from random bytes would be the host's undefined behaviour, not the
                // library's: the paths are NULL or strings the harness owns.
                let path = CString::new(format!("/nonexistent/fuzz-{}", chunk.first().copied().unwrap_or(0))).unwrap_or_default();
                d.models_path = if chunk.len() % 3 == 1 { path.as_ptr() } else { std::ptr::null() };
                d.cache_dir = if chunk.len() % 3 == 2 { path.as_ptr() } else { std::ptr::null() };
                if fix {
                    (d.r#type, d.size) = (SPECULA_STRUCT_RENDER_DESC, std::mem::size_of::<SpeculaRenderDesc>() as u32);
                    (d.width, d.height) = (d.width % 33, d.height % 33);
                }
                let r = specula_context_configure(ctx, &d);
                if r == SPECULA_SUCCESS {
                    let mut px = vec![0u8; (d.width * d.height * 4) as usize];
                    specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, px.as_mut_ptr() as *mut _, px.len())
                } else {
                    r
                }
            }
            5 => {
                let text = String::from_utf8_lossy(chunk).replace('\0', "");
                let (k, v) = text.split_once('=').unwrap_or((&text, ""));
                let (k, v) = (CString::new(k).unwrap_or_default(), CString::new(v).unwrap_or_default());
                specula_context_set_knob(ctx, k.as_ptr(), v.as_ptr())
            }
            _ => {
                let text = String::from_utf8_lossy(&chunk[chunk.len().min(1)..]).replace('\0', "");
                let name = CString::new(text).unwrap_or_default();
                specula_context_set_object_method(ctx, name.as_ptr(), chunk.first().copied().unwrap_or(0) as u32)
            }
        };
        if r == SPECULA_ERROR_PANIC {
            let msg = std::ffi::CStr::from_ptr(specula_context_last_error(ctx)).to_string_lossy().into_owned();
            return Some(format!("call {op} panicked: {msg}"));
        }
    }
    None
}
