//! Scene building: load a glTF file, add materials, meshes and lights, set the camera.

use std::ffi::c_char;

use glam::{Mat4, Vec3};

use super::handle::{cstr, fail, header, header_grown, vec3, with_ctx, FfiResult, SpeculaContext};
use super::types::*;
use crate::scene::{Camera, Light, LightKind, Material, Mesh, SurfaceKind};

/// Replaces the context's scene by a glTF 2.0 file (.gltf or .glb). Invalidates the
/// configured renderer (configure again) and clears the per-object methods.
#[no_mangle]
pub unsafe extern "C" fn specula_context_load_gltf(ctx: *mut SpeculaContext, path: *const c_char) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let path = cstr(path, "path")?;
        c.scene = crate::scene::load(std::path::Path::new(path))?;
        c.object_methods.clear();
        c.scene_version += 1;
        Ok(SPECULA_SUCCESS)
    })
}

/// Adds a material to the context's scene; `*out_index` (may be NULL) receives its index.
#[no_mangle]
pub unsafe extern "C" fn specula_context_add_material(
    ctx: *mut SpeculaContext,
    desc: *const SpeculaMaterialDesc,
    out_index: *mut u32,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let (d, _) = material_desc(desc)?;
        let m = material_from_desc(&d, format!("material{}", c.scene.materials.len()))?;
        let i = c.scene.add_material(m)?;
        c.scene_version += 1;
        if !out_index.is_null() {
            *out_index = i as u32;
        }
        Ok(SPECULA_SUCCESS)
    })
}

/// A material descriptor of any released size, and which of the later fields it carries.
pub(super) unsafe fn material_desc(desc: *const SpeculaMaterialDesc) -> FfiResult<(SpeculaMaterialDesc, MaterialFields)> {
    let (d, size) = header_grown(desc, SPECULA_STRUCT_MATERIAL_DESC, "material", MATERIAL_DESC_SIZE_V1)?;
    Ok((d, MaterialFields { volume: size >= MATERIAL_DESC_SIZE_V2, graded: size >= std::mem::size_of::<SpeculaMaterialDesc>() }))
}

/// Which fields added after the first release a material descriptor carries.
#[derive(Clone, Copy)]
pub(super) struct MaterialFields {
    /// attenuation and dispersion
    pub volume: bool,
    /// the graded index
    pub graded: bool,
}

/// The material a descriptor describes (validated by the scene's setters).
pub(super) fn material_from_desc(d: &SpeculaMaterialDesc, name: String) -> FfiResult<Material> {
    let kind = match d.surface {
        SPECULA_SURFACE_DIFFUSE => SurfaceKind::Diffuse,
        SPECULA_SURFACE_MIRROR => SurfaceKind::Mirror { nu: vec3(d.nu), kappa: vec3(d.kappa) },
        SPECULA_SURFACE_DIELECTRIC => SurfaceKind::Dielectric { ior: d.ior, thin: d.thin != 0 },
        s => return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("material.surface: unknown value {s}")),
    };
    let absorption = match d.attenuation_distance {
        0.0 => Vec3::ZERO,
        dist => {
            let c = vec3(d.attenuation_color);
            match Material::absorption_from(c, dist) {
                Some(s) => s,
                None => {
                    return fail(
                        SPECULA_ERROR_INVALID_ARGUMENT,
                        format!(
                            "material.attenuation_color {c} and material.attenuation_distance {dist}: the colour must be in 0..=1 per channel and the distance > 0 (0: no absorption)"
                        ),
                    )
                }
            }
        }
    };
    Ok(Material {
        name,
        base_color: vec3(d.base_color),
        emissive: vec3(d.emission),
        kind,
        absorption,
        dispersion: d.dispersion,
        graded: (d.graded != 0).then(|| {
            let h = d.index_hessian;
            crate::scene::medium::GradedIndex {
                origin: vec3(d.index_origin),
                gradient: vec3(d.index_gradient),
                hessian: [Vec3::new(h[0], h[3], h[4]), Vec3::new(h[3], h[1], h[5]), Vec3::new(h[4], h[5], h[2])],
            }
        }),
        ..Default::default()
    })
}

/// The light a descriptor describes (validated by the scene's setters).
pub(super) fn light_from_desc(d: &SpeculaLightDesc, name: String) -> FfiResult<Light> {
    let kind = match d.kind {
        SPECULA_LIGHT_POINT => LightKind::Point,
        SPECULA_LIGHT_SPOT => LightKind::Spot { inner_cone: d.inner_cone, outer_cone: d.outer_cone },
        SPECULA_LIGHT_DIRECTIONAL => LightKind::Directional,
        k => return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("light.kind: unknown value {k}")),
    };
    if d.range.is_nan() || d.range < 0.0 {
        return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("light.range: must be ≥ 0 (0: unbounded), got {}", d.range));
    }
    let range = (d.range > 0.0).then_some(d.range);
    Ok(Light { name, kind, position: vec3(d.position), direction: vec3(d.direction), intensity: vec3(d.intensity), range })
}

/// Adds a triangle mesh (copied) to the context's scene.
#[no_mangle]
pub unsafe extern "C" fn specula_context_add_mesh(
    ctx: *mut SpeculaContext,
    desc: *const SpeculaMeshDesc,
    out_index: *mut u32,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let d = header(desc, SPECULA_STRUCT_MESH_DESC, "mesh")?;
        if d.positions.is_null() || d.indices.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "mesh.positions and mesh.indices must not be NULL");
        }
        const LIMIT: u32 = 1 << 28;
        if d.vertex_count == 0 || d.index_count == 0 || d.vertex_count > LIMIT || d.index_count > LIMIT {
            return fail(
                SPECULA_ERROR_INVALID_ARGUMENT,
                format!(
                    "mesh.vertex_count and mesh.index_count: each must be in 1..={LIMIT}, got {} and {}",
                    d.vertex_count, d.index_count
                ),
            );
        }
        let n = d.vertex_count as usize;
        let pos = std::slice::from_raw_parts(d.positions, 3 * n);
        let transform =
            if d.transform.is_null() { Mat4::IDENTITY } else { Mat4::from_cols_slice(std::slice::from_raw_parts(d.transform, 16)) };
        if let Err(crate::Error::InvalidInput { message, .. }) = crate::scene::validate_transform(&transform, "mesh") {
            return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("mesh.transform: {message}"));
        }
        let mut mesh = Mesh {
            name: format!("mesh{}", c.scene.meshes.len()),
            positions: pos.chunks_exact(3).map(Vec3::from_slice).collect(),
            indices: std::slice::from_raw_parts(d.indices, d.index_count as usize).to_vec(),
            material: d.material as usize,
            ..Default::default()
        };
        if !d.normals.is_null() {
            mesh.normals = std::slice::from_raw_parts(d.normals, 3 * n).chunks_exact(3).map(Vec3::from_slice).collect();
        }
        // The values as given, before the transform moves them.
        if let Some(k) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("mesh.positions: vertex {k} is not finite, got {}", mesh.positions[k]));
        }
        if let Some((k, &i)) = mesh.indices.iter().enumerate().find(|(_, &i)| i >= d.vertex_count) {
            return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("mesh.indices[{k}]: {i} is out of range ({} vertices)", d.vertex_count));
        }
        mesh.transform(transform);
        let i = c.scene.add_mesh(mesh)?;
        c.scene_version += 1;
        if !out_index.is_null() {
            *out_index = i as u32;
        }
        Ok(SPECULA_SUCCESS)
    })
}

/// Adds a punctual light to the context's scene.
#[no_mangle]
pub unsafe extern "C" fn specula_context_add_light(ctx: *mut SpeculaContext, desc: *const SpeculaLightDesc) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let d = header(desc, SPECULA_STRUCT_LIGHT_DESC, "light")?;
        let l = light_from_desc(d, format!("light{}", c.scene.lights.len()))?;
        c.scene.add_light(l)?;
        c.scene_version += 1;
        Ok(SPECULA_SUCCESS)
    })
}

/// Sets the camera. Takes effect on the next frame without reconfiguring.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_camera(ctx: *mut SpeculaContext, desc: *const SpeculaCameraDesc) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let d = header(desc, SPECULA_STRUCT_CAMERA_DESC, "camera")?;
        let cam = Camera::checked(vec3(d.position), vec3(d.target), d.yfov, d.znear)?;
        c.scene.camera = Some(cam);
        if let Some(r) = c.renderer.as_mut() {
            r.set_camera(cam)?;
        }
        Ok(SPECULA_SUCCESS)
    })
}
