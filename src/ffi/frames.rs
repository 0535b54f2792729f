//! Frames: knobs, configure (plan + renderer), standalone render, host-device record,
//! per-pass timings and memory.

use std::ffi::{c_char, c_void};

use ash::vk::{self, Handle};

use super::handle::{cstr, fail, fixed_str, header, list_args, with_ctx, write_list, FfiResult, SpeculaContext};
use super::types::*;
use crate::methods::registry::ABI_AUTO;
use crate::methods::{Choice, Method};
use crate::plan::budget::{self, Budget, Models};
use crate::plan::Choices;
use crate::renderer::Renderer;
use crate::vk::Image;

/// Caps the device memory this context's resources may hold, in bytes (0: no cap beyond the
/// device's heaps). A configuration that does not fit fails with SPECULA_ERROR_OUT_OF_MEMORY
/// naming the resource and its size, frees what it had allocated, and leaves the context
/// usable for a smaller one.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_memory_budget(ctx: *mut SpeculaContext, bytes: u64) -> SpeculaResult {
    with_ctx(ctx, |c| {
        c.vk.memory.set_budget(Some(bytes).filter(|&b| b > 0));
        Ok(SPECULA_SUCCESS)
    })
}

/// Sets an accuracy knob by name, as the CLI's `-q key=value` (see `specula knobs`).
/// Takes effect at the next specula_context_configure.
#[no_mangle]
pub unsafe extern "C" fn specula_context_set_knob(ctx: *mut SpeculaContext, key: *const c_char, value: *const c_char) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let (k, v) = (cstr(key, "key")?, cstr(value, "value")?);
        c.quality.set(k, v)?;
        Ok(SPECULA_SUCCESS)
    })
}

/// Plans and creates everything a frame of the scene needs with the given method and size.
/// With a budget (`max_ms` or `min_psnr_db`, SPECULA_METHOD_AUTO only) the budgeted planner
/// chooses per object a method and the knobs (see SpeculaRenderDesc); it returns
/// SPECULA_WARNING_NO_MODELS when no models cover the scene (auto's default chose). A desc of
/// SPECULA_RENDER_DESC_SIZE_V1 bytes (before the budget fields) is read as no budget.
/// Reconfiguring destroys the previous renderer: needs an idle GPU in host-device mode.
#[no_mangle]
pub unsafe extern "C" fn specula_context_configure(ctx: *mut SpeculaContext, desc: *const SpeculaRenderDesc) -> SpeculaResult {
    with_ctx(ctx, |c| {
        let v1 = header(desc as *const RenderDescV1, SPECULA_STRUCT_RENDER_DESC, "render desc")?;
        let (method, width, height) = (v1.method, v1.width, v1.height);
        let (max_ms, min_psnr, models_path, cache_dir) = if v1.size == SPECULA_RENDER_DESC_SIZE_V1 {
            (0.0, 0.0, std::ptr::null(), std::ptr::null())
        } else if v1.size == SPECULA_RENDER_DESC_SIZE_V2 {
            let d = &*(desc as *const RenderDescV2);
            (d.max_ms, d.min_psnr_db, d.models_path, std::ptr::null())
        } else {
            let d = header(desc, SPECULA_STRUCT_RENDER_DESC, "render desc")?;
            (d.max_ms, d.min_psnr_db, d.models_path, d.cache_dir)
        };
        let choice = match method {
            ABI_AUTO => Choice::Auto,
            m => match Method::by_abi(m).filter(|m| m.is_gpu()) {
                Some(m) => Choice::Method(m),
                None => {
                    let known: Vec<String> = Method::ALL.iter().filter(|m| m.is_gpu()).map(|m| format!("{} = {}", m.abi, m.name)).collect();
                    return fail(
                        SPECULA_ERROR_INVALID_ARGUMENT,
                        format!("render desc.method: {m} is not a GPU method (known: {ABI_AUTO} = auto, {})", known.join(", ")),
                    );
                }
            },
        };
        // Kept by the context only if the call succeeds.
        let cache = if cache_dir.is_null() {
            c.cache_dir.clone()
        } else {
            Some(std::path::PathBuf::from(cstr(cache_dir, "render desc.cache_dir")?))
        };
        let unset = |v: f64| Some(v).filter(|v| *v != 0.0);
        let budget = Budget::from_limits(unset(max_ms), unset(min_psnr)).map_err(|e| match e {
            crate::Error::InvalidInput { what, message } => {
                crate::Error::invalid(format!("render desc.{}", what.replace('-', "_")), message)
            }
            other => other,
        })?;
        let mut no_models = false;
        let chosen = match budget {
            None => None,
            Some(b) => {
                if choice != Choice::Auto {
                    return fail(
                        SPECULA_ERROR_INVALID_ARGUMENT,
                        format!("render desc: a budget needs SPECULA_METHOD_AUTO (method {method} = {})", choice.name()),
                    );
                }
                let choices = Choices { method: Choice::Auto, objects: c.object_methods.clone() };
                let r = if models_path.is_null() {
                    // Predicted from the object's facts and this device's unit costs.
                    match target(c, cache.clone(), (width, height)) {
                        Some(t) => {
                            crate::plan::predict::choose(&c.scene, &choices, &c.quality, b, &t, &crate::plan::predict::budget_variants())?
                        }
                        None => None,
                    }
                } else {
                    let p = std::path::PathBuf::from(cstr(models_path, "render desc.models_path")?);
                    let m = Models::load(&p)?;
                    budget::choose(&c.scene, &choices, &c.quality, b, (width, height), &[(&m, format!("calibration {}", p.display()))])?
                };
                no_models = r.is_none();
                r
            }
        };
        let unreachable = chosen.as_ref().filter(|(_, _, p)| !p.met).map(|(_, _, p)| {
            format!(
                "budget {}: no choice is predicted to meet it; configured the nearest (predicted {:.3} ms, {:.2} dB on the specular pixels)",
                p.budget.describe(),
                p.frame_ms,
                p.specular_psnr_db
            )
        });
        let previous = std::mem::replace(&mut c.budget, chosen);
        let previous_cache = std::mem::replace(&mut c.cache_dir, cache);
        let fallbacks = match configure(c, choice, width, height) {
            Ok(f) => f,
            Err(e) => {
                c.budget = previous;
                c.cache_dir = previous_cache;
                return Err(e);
            }
        };
        for f in &fallbacks {
            c.log(SPECULA_LOG_WARNING, f);
        }
        if let Some(why) = unreachable {
            c.log(SPECULA_LOG_WARNING, &why);
            return Ok(SPECULA_WARNING_BUDGET_UNREACHABLE);
        }
        Ok(if no_models {
            SPECULA_WARNING_NO_MODELS
        } else if !fallbacks.is_empty() {
            SPECULA_WARNING_DEVICE_FALLBACK
        } else {
            SPECULA_SUCCESS
        })
    })
}

/// What `auto` predicts for: the device's unit costs (from the context's cache directory, a
/// calibration said through the log) at this size; the stored calibration's when the device
/// has none.
fn target(c: &mut SpeculaContext, dir: Option<std::path::PathBuf>, size: (u32, u32)) -> Option<crate::plan::predict::Target> {
    let mut warnings = Vec::new();
    let found = crate::tradeoff::costs_for(&c.vk, dir, &mut |w| warnings.push(w));
    for w in warnings {
        c.log(SPECULA_LOG_WARNING, &w);
    }
    match found {
        Ok((costs, source)) => {
            if let crate::tradeoff::Source::Calibrated(path) = source {
                let to = path.map_or("not cached".to_string(), |p| format!("cached in {}", p.display()));
                c.log(SPECULA_LOG_INFO, &format!("calibrated this device's unit costs for auto ({to})"));
            }
            Some(crate::plan::predict::Target { size, costs })
        }
        Err(e) => {
            c.log(SPECULA_LOG_WARNING, &format!("no unit costs for this device ({e}): auto predicts with the stored calibration's"));
            crate::plan::predict::Target::nominal().map(|t| crate::plan::predict::Target { size, ..t })
        }
    }
}

/// Plans the scene as it is now for `choice` (with the per-object methods, or the budgeted
/// planner's choices and knobs) and replaces the renderer by one of `width`×`height`. A
/// planning error keeps the previous renderer; a creation error leaves none.
/// Returns what the device made the plan give up: per object whose method it cannot run, a
/// message naming the object, the method, why, and its fallback.
fn configure(c: &mut SpeculaContext, choice: Choice, width: u32, height: u32) -> FfiResult<Vec<String>> {
    let (choices, quality) = match &c.budget {
        Some((choices, quality, _)) => (choices.clone(), quality.clone()),
        None => (Choices { method: choice, objects: c.object_methods.clone() }, c.quality.clone()),
    };
    let target = target(c, c.cache_dir.clone(), (width, height));
    let p = crate::plan::plan_for(&c.scene, &choices, &quality, target.as_ref())?;
    let asked: Vec<(usize, Method)> = p.objects.iter().map(|o| (o.mesh, o.method)).collect();
    c.destroy_renderer();
    let r = Renderer::new(&c.vk, &c.scene, p, width, height)?;
    let fallbacks = r
        .plan
        .objects
        .iter()
        .filter(|o| asked.iter().any(|(m, method)| *m == o.mesh && *method != o.method))
        .map(|o| format!("object '{}': {}", o.name, o.reason))
        .collect();
    c.choice = choice;
    c.renderer = Some(r);
    c.renderer_version = c.scene_version;
    c.replan = false;
    Ok(fallbacks)
}

/// Copies what the budgeted planner predicted at the last specula_context_configure with a
/// budget into `out` (up to `capacity`): one entry per specular object, then "frame"; their
/// number into `*count` (0 without a budget, or when no models covered the scene). `out` may
/// be NULL with capacity 0 to query the count. Returns SPECULA_WARNING_TRUNCATED when
/// capacity was too small. Compare with specula_get_pass_timings after a frame.
#[no_mangle]
pub unsafe extern "C" fn specula_get_predictions(
    ctx: *mut SpeculaContext,
    out: *mut SpeculaPrediction,
    capacity: u32,
    count: *mut u32,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        list_args(out, capacity, count)?;
        let mut list: Vec<SpeculaPrediction> = Vec::new();
        if let Some((_, _, p)) = &c.budget {
            for o in &p.objects {
                list.push(SpeculaPrediction {
                    name: fixed_str(&o.name),
                    method: o.method.abi,
                    pixels: o.pixels.min(u32::MAX as usize) as u32,
                    predicted_ms: o.ms,
                    predicted_psnr_db: o.psnr_db,
                });
            }
            let pixels: usize = p.objects.iter().map(|o| o.pixels).sum();
            list.push(SpeculaPrediction {
                name: fixed_str("frame"),
                method: ABI_AUTO,
                pixels: pixels.min(u32::MAX as usize) as u32,
                predicted_ms: p.frame_ms,
                predicted_psnr_db: p.specular_psnr_db,
            });
        }
        Ok(write_list(&list, out, capacity, count))
    })
}

/// Standalone mode: renders one frame, waits for it, and writes width×height pixels of
/// `pixel_format` row by row (no padding) into `dst` of `dst_size` bytes.
#[no_mangle]
pub unsafe extern "C" fn specula_context_render(
    ctx: *mut SpeculaContext,
    pixel_format: SpeculaPixelFormat,
    dst: *mut c_void,
    dst_size: usize,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if !c.vk.owns_device() {
            return fail(SPECULA_ERROR_WRONG_ORDER, "host-device context: record frames with specula_context_record");
        }
        if dst.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "dst is NULL");
        }
        let bpp = match pixel_format {
            SPECULA_PIXEL_RGBA8_SRGB => 4,
            SPECULA_PIXEL_RGBA32F => 16,
            f => return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("pixel_format: unknown value {f}")),
        };
        if c.replan {
            // An update changed the plan (specula_context_set_object_transform …): the same
            // configuration planned afresh for the scene as it is now.
            let (width, height) = c.renderer.as_ref().map_or((0, 0), |r| (r.width, r.height));
            configure(c, c.choice, width, height)?;
        }
        let r = c.renderer()?;
        let need = r.width as usize * r.height as usize * bpp;
        if dst_size < need {
            return fail(SPECULA_ERROR_BUFFER_TOO_SMALL, format!("dst holds {dst_size} bytes, the image needs {need}"));
        }
        let vkc = &c.vk;
        let frame = c.renderer.as_mut().unwrap().render(vkc);
        c.forward_validation_messages();
        let frame = frame?;
        let out = std::slice::from_raw_parts_mut(dst as *mut u8, need);
        match pixel_format {
            SPECULA_PIXEL_RGBA32F => out.copy_from_slice(bytemuck::cast_slice(&frame.image.data)),
            _ => {
                for (o, px) in out.chunks_exact_mut(4).zip(frame.image.data.chunks_exact(4)) {
                    o[..3].iter_mut().zip(px).for_each(|(b, v)| *b = crate::scene::linear_to_srgb(*v));
                    o[3] = 255;
                }
            }
        }
        Ok(SPECULA_SUCCESS)
    })
}

/// Host-device mode: records one frame into the host's `command_buffer` (a VkCommandBuffer
/// in the recording state, outside a render pass, from `queue_family`) and copies the
/// result into `target`, leaving it in `target->final_layout`. The host submits. One frame
/// in flight at a time: the host must have waited for the previous frame of this context.
#[no_mangle]
pub unsafe extern "C" fn specula_context_record(
    ctx: *mut SpeculaContext,
    command_buffer: *mut c_void,
    target: *const SpeculaHostImage,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if c.vk.owns_device() {
            return fail(SPECULA_ERROR_WRONG_ORDER, "standalone context: render frames with specula_context_render");
        }
        if command_buffer.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "command_buffer is NULL");
        }
        let t = header(target, SPECULA_STRUCT_HOST_IMAGE, "target")?;
        if t.image == 0 {
            return fail(SPECULA_ERROR_NULL_POINTER, "target.image is VK_NULL_HANDLE");
        }
        let name = if t.debug_name.is_null() { "host.target".to_string() } else { cstr(t.debug_name, "target.debug_name")?.to_string() };
        let layout = |v: u32, what: &str| -> FfiResult<vk::ImageLayout> {
            let l = vk::ImageLayout::from_raw(v as i32);
            let known = [
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::GENERAL,
                vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                vk::ImageLayout::PRESENT_SRC_KHR,
            ];
            if known.contains(&l) {
                Ok(l)
            } else {
                fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("{what}: unsupported VkImageLayout {v}"))
            }
        };
        let current = layout(t.current_layout, "target.current_layout")?;
        let final_layout = layout(t.final_layout, "target.final_layout")?;
        if final_layout == vk::ImageLayout::UNDEFINED {
            return fail(SPECULA_ERROR_INVALID_ARGUMENT, "target.final_layout must not be UNDEFINED");
        }
        let format = host_format(c, t.format)?;
        let mut host = Image::external(vk::Image::from_raw(t.image), format, t.width, t.height, current, &name);
        c.vk.name(host.raw, &name);
        c.renderer()?;
        let vkc = &c.vk;
        let cmd = vk::CommandBuffer::from_raw(command_buffer as u64);
        c.renderer.as_mut().unwrap().record_into(vkc, cmd, &mut host, final_layout)?;
        Ok(SPECULA_SUCCESS)
    })
}

/// The host image's format, if the library can write it: RGBA32F is copied bit for bit;
/// any other colour format must support `BLIT_DST` with optimal tiling on the device (the
/// frame is blitted with conversion). UNDEFINED, depth/stencil formats, compressed ones and
/// values that are no VkFormat are refused, naming the value.
fn host_format(c: &SpeculaContext, raw: u32) -> FfiResult<vk::Format> {
    let f = vk::Format::from_raw(raw as i32);
    if f == vk::Format::R32G32B32A32_SFLOAT {
        return Ok(f);
    }
    let depth = [
        vk::Format::D16_UNORM,
        vk::Format::X8_D24_UNORM_PACK32,
        vk::Format::D32_SFLOAT,
        vk::Format::S8_UINT,
        vk::Format::D16_UNORM_S8_UINT,
        vk::Format::D24_UNORM_S8_UINT,
        vk::Format::D32_SFLOAT_S8_UINT,
    ];
    if f == vk::Format::UNDEFINED {
        return fail(SPECULA_ERROR_INVALID_ARGUMENT, "target.format is VK_FORMAT_UNDEFINED");
    }
    if depth.contains(&f) {
        return fail(SPECULA_ERROR_INVALID_ARGUMENT, format!("target.format {raw} ({f:?}) is a depth/stencil format: the frame is colour"));
    }
    // Only VkFormat values may be queried: Vulkan 1.0's 1..=184 and the ranges 1.1–1.3
    // promoted to core (YCbCr, 4444, ASTC HDR, the 1.3 additions).
    let core = [
        1..=184,
        1_000_066_000..=1_000_066_013,
        1_000_156_000..=1_000_156_033,
        1_000_330_000..=1_000_330_003,
        1_000_340_000..=1_000_340_001,
    ];
    if !core.iter().any(|r| r.contains(&(raw as i32))) {
        return fail(SPECULA_ERROR_UNSUPPORTED, format!("target.format {raw} is not a Vulkan 1.3 core VkFormat"));
    }
    let props = unsafe { c.vk.instance.get_physical_device_format_properties(c.vk.physical, f) };
    if !props.optimal_tiling_features.contains(vk::FormatFeatureFlags::BLIT_DST) {
        let what = format!("{f:?}");
        return fail(
            SPECULA_ERROR_UNSUPPORTED,
            format!("target.format {raw} ({what}) cannot be blitted to on this device (no BLIT_DST with optimal tiling): use R32G32B32A32_SFLOAT or a colour format that supports blits"),
        );
    }
    Ok(f)
}

/// Copies the per-pass timings of the last frame the GPU completed into `out` (up to
/// `capacity` entries) and the number of passes into `*count`. `out` may be NULL with
/// capacity 0 to query the count. Returns SPECULA_WARNING_TRUNCATED when capacity was too
/// small and SPECULA_WARNING_NOT_READY when no frame has completed yet.
#[no_mangle]
pub unsafe extern "C" fn specula_get_pass_timings(
    ctx: *mut SpeculaContext,
    out: *mut SpeculaPassTiming,
    capacity: u32,
    count: *mut u32,
) -> SpeculaResult {
    with_ctx(ctx, |c| {
        list_args(out, capacity, count)?;
        let vkc = &c.vk;
        let Some(r) = c.renderer.as_mut() else {
            return fail(SPECULA_ERROR_WRONG_ORDER, "no renderer: call specula_context_configure first");
        };
        let timings = r.last_timings(vkc)?;
        if timings.is_empty() {
            *count = 0;
            return Ok(SPECULA_WARNING_NOT_READY);
        }
        let list: Vec<SpeculaPassTiming> =
            timings.iter().map(|t| SpeculaPassTiming { name: fixed_str(&t.name), gpu_ms: t.gpu_ms, cpu_ms: t.cpu_ms }).collect();
        Ok(write_list(&list, out, capacity, count))
    })
}

/// Device memory the context's resources hold, in bytes, into `*out`.
#[no_mangle]
pub unsafe extern "C" fn specula_context_memory_bytes(ctx: *mut SpeculaContext, out: *mut u64) -> SpeculaResult {
    with_ctx(ctx, |c| {
        if out.is_null() {
            return fail(SPECULA_ERROR_NULL_POINTER, "out is NULL");
        }
        *out = c.vk.memory.total();
        Ok(SPECULA_SUCCESS)
    })
}
