//! Per-object methods: each specular object (addressed by its name — the glTF node or mesh
//! name, `meshN` for meshes added through the C ABI — or by its index in the scene) can be
//! given its own method, overriding the render description's. Checked when set: the object
//! must exist and be specular, the method must exist, render on the GPU and serve it — its
//! class and its shape (planar methods a planar mesh, …): whatever the library can judge at
//! the call is refused there, and a refused call leaves the context as it was (the object's
//! earlier method included).

use std::ffi::c_char;

use super::handle::{cstr, fail, with_ctx, FfiResult, SpeculaContext};
use super::types::*;
use crate::methods::registry::{ObjectClass, ABI_AUTO};
use crate::methods::Method;

/// The number of objects (meshes) of the context's scene; specular and not.
#[no_mangle]
pub unsafe extern "C" fn specula_context_object_count(ctx: *mut SpeculaContext, out_count: *mut u32) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if out_count.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "out_count is NULL");
        }
        *out_count = c.scene.meshes.len() as u32;
        Ok(SPECULA_SUCCESS)
    })
}

/// Writes object `index`'s name, NUL-terminated, into `buf` of `size` bytes; a name that
/// does not fit is truncated (at a character boundary) and SPECULA_WARNING_TRUNCATED
/// returned.
#[no_mangle]
pub unsafe extern "C" fn specula_context_object_name(ctx: *mut SpeculaContext, index: u32, buf: *mut c_char, size: usize) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if buf.is_null() || size == 0 {
            return fail(SPECULA_ERROR_NULL_POINTER, "buf is NULL or size is 0");
        }
        let Some(m) = c.scene.meshes.get(index as usize) else {
            return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("object index {index}: the scene has {} objects", c.scene.meshes.len()));
        };
        let name = m.name.as_bytes();
        let mut n = name.len().min(size - 1);
        while !m.name.is_char_boundary(n) {
            n -= 1;
        }
        std::ptr::copy_nonoverlapping(name.as_ptr(), buf as *mut u8, n);
        *buf.add(n) = 0;
        Ok(if n < name.len() { SPECULA_WARNING_TRUNCATED } else { SPECULA_SUCCESS })
    })
}

/// Gives the specular object named `object` its own method (SPECULA_METHOD_*), overriding
/// the render description's; SPECULA_METHOD_AUTO removes the override. Takes effect at the
/// next specula_context_configure. Loading another scene clears every override.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_object_method(
    ctx: *mut SpeculaContext,
    object: *const c_char,
    method: SpeculaMethod,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let name = cstr(object, "object")?;
        let Some(index) = c.scene.meshes.iter().position(|m| m.name == name || m.aliases.iter().any(|a| a == name)) else {
            let names: Vec<&str> = c.scene.specular_meshes().map(|(_, m)| m.name.as_str()).collect();
            return fail(
                SPECULA_ERROR_INVALID_ARGUMENT,
                format!(
                    "specula_context_set_object_method: no object is named '{}' (specular objects: {})",
                    crate::error::clip(name),
                    names.join(", ")
                ),
            );
        };
        set(c, index, method)
    })
}

/// As specula_context_set_object_method, for the object at `index` (the order of
/// specula_context_add_mesh's out_index, or of the glTF scene's meshes).
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_object_method_at(
    ctx: *mut SpeculaContext,
    index: u32,
    method: SpeculaMethod,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if index as usize >= c.scene.meshes.len() {
            return fail(
                SPECULA_ERROR_INVALID_ARGUMENT,
                format!("specula_context_set_object_method_at: object index {index}, the scene has {} objects", c.scene.meshes.len()),
            );
        }
        set(c, index as usize, method)
    })
}

fn set(c: &mut SpeculaContext, index: usize, method: SpeculaMethod) -> FfiResult<SpeculaResult> {
    let mesh = &c.scene.meshes[index];
    let name = mesh.name.clone();
    let material = &c.scene.materials[mesh.material];
    let Some(class) = ObjectClass::of(&material.kind) else {
        return fail(
            SPECULA_ERROR_INVALID_ARGUMENT,
            format!("object '{name}' is not specular (material '{}' is diffuse): only specular objects take a method", material.name),
        );
    };
    if method == ABI_AUTO {
        c.object_methods.retain(|(n, _)| *n != name);
        return Ok(SPECULA_SUCCESS);
    }
    let Some(m) = Method::by_abi(method).filter(|m| m.is_gpu()) else {
        let known: Vec<String> = Method::ALL.iter().filter(|m| m.is_gpu()).map(|m| format!("{} = {}", m.abi, m.name)).collect();
        return fail(
            SPECULA_ERROR_INVALID_ARGUMENT,
            format!("object '{name}': method {method} is not a GPU method (known: {ABI_AUTO} = auto, {})", known.join(", ")),
        );
    };
    if !m.can_serve(class) {
        let serves: Vec<&str> = m.serves.iter().map(|c| c.label()).collect();
        return fail(
            SPECULA_ERROR_INVALID_ARGUMENT,
            format!("object '{name}': method '{}' cannot serve a {} (it serves: {})", m.name, class.label(), serves.join(", ")),
        );
    }
    // Its shape: judged as the planner judges it, from the mesh (rigid and affine moves keep its
    // curvature) and, for a curved mirror, its reflection points seen from the camera (which
    // moves can change: a later update may then refuse it by name).
    let facts = crate::plan::facts::SceneFacts::new(&c.scene, &c.quality, false);
    if let Some(f) = facts.objects.iter().find(|f| f.mesh == index).filter(|f| !m.fits(f)) {
        return fail(
            SPECULA_ERROR_INVALID_ARGUMENT,
            format!(
                "object '{name}': method '{}' cannot serve {} {}: {}",
                m.name,
                m.shape.misfit_of(f),
                f.class.label(),
                m.shape.refusal(f)
            ),
        );
    }
    c.object_methods.retain(|(n, _)| *n != name);
    c.object_methods.push((name, m));
    Ok(SPECULA_SUCCESS)
}
