//! Shared helpers of the GPU tests: a validated context, scenes built in code.
#![allow(dead_code)]

use glam::Vec3;
use specula::scene::{shapes, Camera, Material, Scene, SurfaceKind};
use specula::vk::{Context, DeviceOptions};

/// A context with the Khronos validation layer on (every GPU test uses one). Dropping it
/// fails the test if destroying the device reported errors (objects the test left alive:
/// the layer reports them at vkDestroyDevice, after `assert_clean` ran).
pub fn gpu() -> Gpu {
    Gpu(Some(
        Context::new(&DeviceOptions { validation: true, device_filter: None, ..Default::default() })
            .expect("Vulkan context with validation (is vulkan-validationlayers installed?)"),
    ))
}

/// A test's context (see `gpu`).
pub struct Gpu(Option<Context>);

impl std::ops::Deref for Gpu {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.0.as_ref().expect("context alive")
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        let before = specula::vk::process_validation_errors();
        drop(self.0.take());
        let after = specula::vk::process_validation_errors();
        // Another test's device destroyed at the same moment could be the one to blame; either
        // way an error was reported and the suite must not pass.
        if after > before && !std::thread::panicking() {
            panic!("destroying the device reported {} validation error(s): objects left alive (see stderr)", after - before);
        }
    }
}

/// Fails the test on any validation error or warning (none is allowed: each would need a
/// named reason here).
pub fn assert_clean(ctx: &Context) {
    assert_eq!(ctx.validation.error_count(), 0, "validation errors: {:#?}", ctx.validation.error_messages());
    assert_eq!(ctx.validation.warning_count(), 0, "validation warnings: {:#?}", ctx.validation.error_messages());
}

/// The emitted colour of quadrant `q` of wall `w` in `quadrant_room`: distinct for all 24.
pub fn quadrant_color(w: usize, q: usize) -> Vec3 {
    specula::scenes::quadrant_color(w, q)
}

/// A room of 24 emissive quadrants (no lights) of half-size `half` around `center`.
pub fn emissive_room(scene: &mut Scene, center: Vec3, half: f32) {
    specula::scenes::emissive_room(scene, center, half).unwrap()
}

/// A scratch directory of this test process, under Cargo's target/tmp (not created).
pub fn scratch_dir(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("specula-{name}-{}", std::process::id()))
}

/// A mirror material of reflectance `f0` at normal incidence (κ = 0, ν from eq. 2).
pub fn mirror(f0: f32) -> Material {
    let s = f0.sqrt();
    let nu = (1.0 + s) / (1.0 - s);
    Material { name: format!("mirror{f0}"), kind: SurfaceKind::Mirror { nu: Vec3::splat(nu), kappa: Vec3::ZERO }, ..Default::default() }
}

/// Maximum absolute difference of two RGB triples.
pub fn max_diff(a: &[f32], b: Vec3) -> f32 {
    (a[0] - b.x).abs().max((a[1] - b.y).abs()).max((a[2] - b.z).abs())
}

/// Runs `shader` (a compute shader with `local_size_x = 64`, binding 0: readonly input
/// array, binding 1: output array) over `input` as one profiled pass, and returns `count`
/// outputs. The conformance tests' harness: GLSL functions against their Rust twins.
pub fn run_cases<I: bytemuck::Pod, O: bytemuck::Pod>(ctx: &Context, shader: &str, input: &[I], push: &[u8]) -> Vec<O> {
    use ash::vk;
    use specula::vk::pipeline::{allocate_set, compute_pipeline, descriptor_set_layout, pipeline_layout, write_buffer};
    use specula::vk::{Buffer, MemoryLocation, Profiler, Recorder};
    let n = input.len() as u32;
    let out_bytes = (input.len() * std::mem::size_of::<O>()) as u64;
    let mut cases = Buffer::with_data(ctx, "test.cases", input, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let mut results = Buffer::new(ctx, "test.results", out_bytes, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryLocation::GpuToCpu).unwrap();
    let bindings = [(0, vk::DescriptorType::STORAGE_BUFFER, 1), (1, vk::DescriptorType::STORAGE_BUFFER, 1)];
    let set_layout = descriptor_set_layout(ctx, "test.layout", &bindings, vk::ShaderStageFlags::COMPUTE).unwrap();
    let (pool, set) = allocate_set(ctx, "test.set", set_layout, &bindings).unwrap();
    let layout = pipeline_layout(ctx, "test.pipeline_layout", &[set_layout], push.len() as u32, vk::ShaderStageFlags::COMPUTE).unwrap();
    let pipeline = compute_pipeline(ctx, layout, shader).unwrap();
    write_buffer(ctx, set, 0, vk::DescriptorType::STORAGE_BUFFER, cases.raw);
    write_buffer(ctx, set, 1, vk::DescriptorType::STORAGE_BUFFER, results.raw);
    let mut profiler = Profiler::new(ctx, 2).unwrap();
    ctx.one_shot(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, &mut profiler);
        let open = rec.pass("test.cases").begin();
        unsafe {
            ctx.device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, pipeline);
            ctx.device.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, layout, 0, &[set], &[]);
            if !push.is_empty() {
                ctx.device.cmd_push_constants(cmd, layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            ctx.device.cmd_dispatch(cmd, n.div_ceil(64), 1, 1);
            // The shader's writes become visible to the host that reads them after the fence.
            let barrier = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::HOST)
                .dst_access_mask(vk::AccessFlags2::HOST_READ)];
            ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&barrier));
        }
        rec.end(open);
        Ok(())
    })
    .unwrap();
    assert_eq!(profiler.results(ctx).unwrap()[0].name, "test.cases");
    let out: Vec<O> = bytemuck::pod_collect_to_vec(&results.read().unwrap()[..out_bytes as usize]);
    // The context keeps its pipelines (`vk::pipeline_memo`): given back, not destroyed.
    specula::vk::pipeline::release_pipeline(ctx, pipeline);
    specula::vk::pipeline::destroy_pipeline_layout(ctx, layout);
    specula::vk::pipeline::destroy_set_layout(ctx, set_layout);
    unsafe { ctx.device.destroy_descriptor_pool(pool, None) };
    profiler.destroy(ctx);
    cases.destroy(ctx);
    results.destroy(ctx);
    out
}

/// The emissive quadrant room with a solid glass sphere (ν 1.5, centre `GLASS`) and a mirror
/// sphere (F0 0.9, centre `MIRROR`), both of radius 0.5 and `segments`×`segments/2` quads,
/// seen from inside the room.
pub const GLASS: Vec3 = Vec3::new(0.6, 1.5, 0.0);
pub const MIRROR: Vec3 = Vec3::new(-0.7, 1.5, -0.2);
pub fn mirror_and_glass(segments: u32) -> Scene {
    let mut s = Scene::new();
    emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let glass = s
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })
        .unwrap();
    let mirror = s.add_material(mirror(0.9)).unwrap();
    s.add_mesh(shapes::uv_sphere("glass", GLASS, 0.5, segments, segments / 2, glass)).unwrap();
    s.add_mesh(shapes::uv_sphere("mirror", MIRROR, 0.5, segments, segments / 2, mirror)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 1.8, 1.9), Vec3::new(0.0, 1.5, 0.0), 50f32.to_radians()));
    s
}

/// A standalone C ABI context with the validation layer on.
pub fn c_context() -> *mut specula::ffi::SpeculaContext {
    use specula::ffi::*;
    let desc = SpeculaContextDesc {
        r#type: SPECULA_STRUCT_CONTEXT_DESC,
        size: std::mem::size_of::<SpeculaContextDesc>() as u32,
        device_name: std::ptr::null(),
        enable_validation: 1,
        vulkan_allocator: std::ptr::null(),
    };
    let mut ctx = std::ptr::null_mut();
    unsafe { assert_eq!(specula_context_create(&desc, &mut ctx), SPECULA_SUCCESS) };
    ctx
}

/// A host-device description of `own`'s instance and device (the C ABI's host mode over a
/// device the library's Rust API created); `ray_query_enabled` as the host says.
pub fn host_desc(own: &Context, ray_query_enabled: u32) -> specula::ffi::SpeculaHostDesc {
    use ash::vk::{self, Handle};
    use specula::ffi::*;
    use std::ffi::{c_char, c_void};
    type Gipa = unsafe extern "system" fn(vk::Instance, *const c_char) -> vk::PFN_vkVoidFunction;
    let gipa: Gipa = own.entry.static_fn().get_instance_proc_addr;
    SpeculaHostDesc {
        r#type: SPECULA_STRUCT_HOST_DESC,
        size: std::mem::size_of::<SpeculaHostDesc>() as u32,
        // The same function; the ABI spells the handle as a pointer.
        get_instance_proc_addr: unsafe { std::mem::transmute::<Option<Gipa>, SpeculaGetInstanceProcAddr>(Some(gipa)) },
        instance: own.instance.handle().as_raw() as *mut c_void,
        physical_device: own.physical.as_raw() as *mut c_void,
        device: own.device.handle().as_raw() as *mut c_void,
        queue_family: own.queue_family,
        debug_utils_enabled: 0,
        ray_query_enabled,
        vulkan_allocator: std::ptr::null(),
    }
}

/// A render description for `method` at `width`×`height`.
pub fn render_desc(method: specula::Method, width: u32, height: u32) -> specula::ffi::SpeculaRenderDesc {
    use specula::ffi::*;
    SpeculaRenderDesc {
        r#type: SPECULA_STRUCT_RENDER_DESC,
        size: std::mem::size_of::<SpeculaRenderDesc>() as u32,
        method: method.abi,
        width,
        height,
        max_ms: 0.0,
        min_psnr_db: 0.0,
        models_path: std::ptr::null(),
        cache_dir: std::ptr::null(),
    }
}

/// A 1×1 PNG whose IHDR declares 65536×65536 pixels (CRC fixed): a few bytes that claim
/// 16 GiB of RGBA.
pub fn huge_png_bytes() -> Vec<u8> {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(image::codecs::png::PngEncoder::new(&mut png), &[1, 2, 3, 255], 1, 1, image::ExtendedColorType::Rgba8)
        .unwrap();
    // Signature (8), length (4), "IHDR" (4), width, height; the CRC covers type and data.
    png[16..20].copy_from_slice(&65536u32.to_be_bytes());
    png[20..24].copy_from_slice(&65536u32.to_be_bytes());
    let mut c = 0xffff_ffffu32;
    for &b in &png[12..29] {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 { 0xedb8_8320 ^ (c >> 1) } else { c >> 1 };
        }
    }
    png[29..33].copy_from_slice(&(!c).to_be_bytes());
    png
}

/// `base` with every position and its camera scaled by `k` (1 mm and 1 km scenes).
pub fn scaled(base: &Scene, k: f32) -> Scene {
    let mut s = base.clone();
    for m in &mut s.meshes {
        m.positions.iter_mut().for_each(|p| *p *= k);
    }
    // A graded medium's field in the scaled coordinates: n(x/k) — the origin moves, the
    // gradient and Hessian fall by k and k².
    for m in &mut s.materials {
        if let Some(f) = &mut m.graded {
            f.origin *= k;
            f.gradient /= k;
            f.hessian = f.hessian.map(|r| r / (k * k));
        }
    }
    let mut cam = base.camera_or_default();
    cam.position *= k;
    cam.world_from_camera.w_axis = (cam.world_from_camera.w_axis.truncate() * k).extend(1.0);
    cam.znear *= k;
    s.camera = Some(cam);
    s
}

/// Per-object errors of `frame` against `reference` (the reference's first hits).
pub fn split(
    scene: &Scene,
    image: &specula::image::ImageData,
    reference: &specula::image::ImageData,
    ids: &[u32],
) -> Vec<specula::metrics::MaskedError> {
    let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
    let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
    specula::metrics::errors_by_object(image, reference, ids, &specular, &names).unwrap()
}

pub fn psnr(e: &[specula::metrics::MaskedError], name: &str) -> f64 {
    e.iter().find(|x| x.name == name).unwrap_or_else(|| panic!("{name}: {e:?}")).psnr
}
