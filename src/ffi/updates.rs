//! Frames over time: an object's transform, a material, a light changed between frames.
//! Each call validates like the scene-building calls, keeps the previous state when it
//! refuses, and needs no idle GPU: a configured renderer takes the change in place and the
//! next recorded frame uploads it (and regenerates only the maps that depend on it).

use glam::Mat4;

use super::handle::{fail, fixed_str, header, list_args, with_ctx, write_list, FfiResult, SpeculaContext};
use super::scene::{light_from_desc, material_desc, material_from_desc};
use super::types::*;
use crate::scene::Scene;

/// Applies `change` to the context's scene and hands the new state to its renderer (if one
/// is configured for this scene); on any refusal the old `part` is put back.
fn apply<T: Clone>(
    c: &mut SpeculaContext,
    get: impl Fn(&mut Scene) -> &mut T,
    change: impl FnOnce(&mut Scene) -> crate::Result<()>,
) -> FfiResult<SpeculaResult> {
    let old = get(&mut c.scene).clone();
    change(&mut c.scene)?;
    if c.renderer_version == c.scene_version {
        if let Some(r) = c.renderer.as_mut() {
            match r.update(&c.scene) {
                Ok(_) => {}
                // A valid change the renderer cannot take in place: the scene keeps it, the
                // renderer is stale. Standalone contexts rebuild it at the next render; a host
                // configures again (with an idle GPU, as configuring always needs).
                Err(crate::Error::PlanChanged(why)) => {
                    c.scene_version += 1;
                    let owned = c.vk.owns_device();
                    c.replan = owned;
                    let next = if owned { "the next specula_context_render reconfigures" } else { "call specula_context_configure again" };
                    c.log(SPECULA_LOG_WARNING, &format!("the update changes the plan ({why}): {next}"));
                }
                Err(e) => {
                    *get(&mut c.scene) = old;
                    return Err(e.into());
                }
            }
        }
    }
    Ok(SPECULA_SUCCESS)
}

fn index(i: u32, count: usize, what: &str) -> FfiResult<usize> {
    if (i as usize) < count {
        Ok(i as usize)
    } else {
        fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("{what}: {i} is out of range (the scene has {count})"))
    }
}

/// Sets object `object`'s world transform: 16 floats, column-major (like glTF and the
/// mesh descriptor's `transform`), replacing the one it was added or loaded with. Refused:
/// NaN or infinite entries, a singular matrix (zero scale), a mirroring matrix for an object
/// that was not mirrored (or the reverse), an unknown object. Not thread-safe with other
/// calls on the same context; the GPU need not be idle. A move that changes the plan (with
/// SPECULA_METHOD_AUTO, objects coming into each other's view may start to compose) is
/// accepted and logged as a warning: a standalone context reconfigures at its next
/// specula_context_render; a host-device context's next specula_context_record returns
/// SPECULA_ERROR_WRONG_ORDER until it is configured again (idle GPU).
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_object_transform(ctx: *mut SpeculaContext, object: u32, matrix: *const f32) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if matrix.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "matrix is NULL");
        }
        let i = index(object, c.scene.meshes.len(), "object")?;
        let m = Mat4::from_cols_slice(std::slice::from_raw_parts(matrix, 16));
        apply(c, |s| &mut s.meshes[i], |s| s.set_object_transform(i, m))
    })
}

/// Hides object `object` (visible = 0: drawn nowhere, in no map, hit by no ray) or shows it
/// again (visible ≠ 0). The GPU need not be idle.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_object_visible(ctx: *mut SpeculaContext, object: u32, visible: u32) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let i = index(object, c.scene.meshes.len(), "object")?;
        apply(c, |s| &mut s.meshes[i], |s| s.set_object_visible(i, visible != 0))
    })
}

/// Replaces material `index`'s parameters (base colour, emission, ν and κ, ior, absorption, dispersion; its
/// textures and KHR_materials_specular colour and factor stay). Its surface kind must stay (a mirror stays a mirror: a new kind needs a new plan, configure
/// again). Validated like specula_context_add_material; the GPU need not be idle.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_material(
    ctx: *mut SpeculaContext,
    index: u32,
    desc: *const SpeculaMaterialDesc,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let (d, fields) = material_desc(desc)?;
        let i = self::index(index, c.scene.materials.len(), "material")?;
        let old = c.scene.materials[i].clone();
        let d = material_from_desc(&d, old.name.clone())?;
        // What the descriptor does not carry (textures, KHR_materials_specular; the
        // absorption from a descriptor of the first release's size) stays.
        let (absorption, dispersion) = if fields.volume { (d.absorption, d.dispersion) } else { (old.absorption, old.dispersion) };
        let graded = if fields.graded { d.graded } else { old.graded };
        let m =
            crate::scene::Material { base_color: d.base_color, emissive: d.emissive, kind: d.kind, absorption, dispersion, graded, ..old };
        apply(c, |s| &mut s.materials[i], |s| s.set_material(i, m))
    })
}

/// Replaces light `index` (position, direction, intensity, range, cone). Its kind must
/// stay. Validated like specula_context_add_light; the GPU need not be idle.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_light(ctx: *mut SpeculaContext, index: u32, desc: *const SpeculaLightDesc) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let d = header(desc, SPECULA_STRUCT_LIGHT_DESC, "light")?;
        let i = self::index(index, c.scene.lights.len(), "light")?;
        let l = light_from_desc(d, c.scene.lights[i].name.clone())?;
        apply(c, |s| &mut s.lights[i], |s| s.set_light(i, l))
    })
}

/// Copies the maps the last recorded frame regenerated, with why (first frame, a moved
/// object, a changed material or light, the camera for camera-space maps,
/// map_updates=always), into `out` (up to `capacity`), their number into `*count`. A map
/// not listed kept its contents. `out` may be NULL with capacity 0 to query the count.
/// Returns SPECULA_WARNING_TRUNCATED when capacity was too small.
#[no_mangle]
pub unsafe extern "C" fn specula_get_map_updates(
    ctx: *mut SpeculaContext,
    out: *mut SpeculaMapUpdate,
    capacity: u32,
    count: *mut u32,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        list_args(out, capacity, count)?;
        let Some(r) = c.renderer.as_ref() else {
            return fail(SPECULA_ERROR_WRONG_ORDER, "no renderer: call specula_context_configure first");
        };
        let list: Vec<SpeculaMapUpdate> =
            r.map_updates().iter().map(|u| SpeculaMapUpdate { stage: fixed_str(u.stage), reason: fixed_str(&u.reason) }).collect();
        Ok(write_list(&list, out, capacity, count))
    })
}
