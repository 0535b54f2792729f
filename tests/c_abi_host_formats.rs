//! Host-device mode refuses target images it cannot write, before recording anything:
//! VK_FORMAT_UNDEFINED, depth/stencil formats, values that are no VkFormat, and colour
//! formats without BLIT_DST on the device — each an error code with a message naming the
//! value, and no validation error. (The host's own device here is one the library's Rust
//! API created; the C host example renders through host-device mode for real in c_abi.rs.)

mod common;

use std::ffi::{c_void, CStr, CString};

use ash::vk;
use specula::ffi::*;

#[test]
fn bad_host_target_formats_are_refused() {
    let own = common::gpu();
    let desc = common::host_desc(&own, 0);
    let mut ctx = std::ptr::null_mut();
    unsafe {
        assert_eq!(specula_context_create_host(&desc, &mut ctx), SPECULA_SUCCESS, "{:?}", CStr::from_ptr(specula_creation_error()));
        let scene = CString::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf")).unwrap();
        assert_eq!(specula_context_load_gltf(ctx, scene.as_ptr()), SPECULA_SUCCESS);
        let knob = (CString::new("cube_size").unwrap(), CString::new("16").unwrap());
        assert_eq!(specula_context_set_knob(ctx, knob.0.as_ptr(), knob.1.as_ptr()), SPECULA_SUCCESS);
        let render = common::render_desc(specula::methods::ENVMAP, 16, 16);
        assert_eq!(specula_context_configure(ctx, &render), SPECULA_SUCCESS);
        let cases = [
            (vk::Format::UNDEFINED.as_raw() as u32, SPECULA_ERROR_INVALID_ARGUMENT, "UNDEFINED"),
            (vk::Format::D32_SFLOAT.as_raw() as u32, SPECULA_ERROR_INVALID_ARGUMENT, "depth"),
            (vk::Format::D24_UNORM_S8_UINT.as_raw() as u32, SPECULA_ERROR_INVALID_ARGUMENT, "depth"),
            (999_999, SPECULA_ERROR_UNSUPPORTED, "999999"),
            (vk::Format::BC1_RGB_UNORM_BLOCK.as_raw() as u32, SPECULA_ERROR_UNSUPPORTED, "BLIT_DST"),
        ];
        for (format, want, needle) in cases {
            let target = SpeculaHostImage {
                r#type: SPECULA_STRUCT_HOST_IMAGE,
                size: std::mem::size_of::<SpeculaHostImage>() as u32,
                image: 1, // never touched: the format is refused first
                view: 0,
                format,
                width: 16,
                height: 16,
                current_layout: vk::ImageLayout::UNDEFINED.as_raw() as u32,
                final_layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL.as_raw() as u32,
                debug_name: std::ptr::null(),
            };
            let got = specula_context_record(ctx, std::ptr::NonNull::<c_void>::dangling().as_ptr(), &target);
            let msg = CStr::from_ptr(specula_context_last_error(ctx)).to_string_lossy().into_owned();
            assert_eq!(got, want, "format {format}: {msg}");
            assert!(msg.contains(needle) && msg.contains("target.format"), "format {format}: {msg}");
        }
        assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS);
    }
    common::assert_clean(&own);
}

/// Issue 37: the engine path writes into the host's own image in the formats engines use
/// (R8G8B8A8_UNORM, R16G16B16A16_SFLOAT, B8G8R8A8_SRGB), leaving it in the layout the host
/// asks for (GENERAL, SHADER_READ_ONLY_OPTIMAL, COLOR_ATTACHMENT_OPTIMAL) — recorded twice
/// per image, first from UNDEFINED, then from the layout it was left in — and the image
/// equals the standalone frame converted to that format within one step of the format (an
/// 8-bit code, a half-float ulp): Vulkan leaves a blit's rounding to the implementation.
/// Measured on lavapipe (Mesa 25.0.7), 32×24: R8G8B8A8_UNORM bit for bit; R16G16B16A16_SFLOAT
/// 1963 of 3072 channels as round-to-nearest gives them, the rest one ulp off; B8G8R8A8_SRGB
/// 2897 of 3072 as `linear_to_srgb` encodes them, the rest one code off. The validation
/// layer's synchronization validation is on.
#[test]
fn host_images_in_three_formats_and_three_layouts_equal_the_standalone_frame() {
    const W: u32 = 32;
    const H: u32 = 24;
    let scene = CString::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf")).unwrap();
    let knob = (CString::new("cube_size").unwrap(), CString::new("16").unwrap());
    let render = common::render_desc(specula::methods::ENVMAP, W, H);
    let setup = |ctx: *mut SpeculaContext| unsafe {
        assert_eq!(specula_context_load_gltf(ctx, scene.as_ptr()), SPECULA_SUCCESS);
        assert_eq!(specula_context_set_knob(ctx, knob.0.as_ptr(), knob.1.as_ptr()), SPECULA_SUCCESS);
        assert_eq!(specula_context_configure(ctx, &render), SPECULA_SUCCESS);
    };
    // The standalone frame, linear RGBA32F.
    let standalone = common::c_context();
    setup(standalone);
    let mut reference = vec![0f32; (W * H * 4) as usize];
    unsafe {
        let bytes = reference.len() * 4;
        assert_eq!(specula_context_render(standalone, SPECULA_PIXEL_RGBA32F, reference.as_mut_ptr().cast(), bytes), SPECULA_SUCCESS);
        assert_eq!(specula_context_destroy(standalone), SPECULA_SUCCESS);
    }

    let own = common::gpu();
    let desc = common::host_desc(&own, 0);
    let mut ctx = std::ptr::null_mut();
    unsafe { assert_eq!(specula_context_create_host(&desc, &mut ctx), SPECULA_SUCCESS, "{:?}", CStr::from_ptr(specula_creation_error())) };
    setup(ctx);
    let formats = [vk::Format::R8G8B8A8_UNORM, vk::Format::R16G16B16A16_SFLOAT, vk::Format::B8G8R8A8_SRGB];
    let layouts = [vk::ImageLayout::GENERAL, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL];
    for format in formats {
        for layout in layouts {
            let usage = vk::ImageUsageFlags::TRANSFER_DST
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::COLOR_ATTACHMENT;
            let desc = specula::vk::ImageDesc { name: "host image", format, width: W, height: H, kind: specula::vk::ImageKind::D2, usage };
            let mut image = specula::vk::Image::new(&own, &desc).unwrap();
            for arrives in [vk::ImageLayout::UNDEFINED, layout] {
                let target = SpeculaHostImage {
                    r#type: SPECULA_STRUCT_HOST_IMAGE,
                    size: std::mem::size_of::<SpeculaHostImage>() as u32,
                    image: vk::Handle::as_raw(image.raw),
                    view: vk::Handle::as_raw(image.view),
                    format: format.as_raw() as u32,
                    width: W,
                    height: H,
                    current_layout: arrives.as_raw() as u32,
                    final_layout: layout.as_raw() as u32,
                    debug_name: std::ptr::null(),
                };
                own.one_shot(|cmd| {
                    let got = unsafe { specula_context_record(ctx, vk::Handle::as_raw(cmd) as *mut c_void, &target) };
                    let why = unsafe { CStr::from_ptr(specula_context_last_error(ctx)) }.to_string_lossy().into_owned();
                    assert_eq!(got, SPECULA_SUCCESS, "{format:?} {layout:?}: {why}");
                    Ok(())
                })
                .unwrap();
            }
            // The library left it in `layout` (its last barrier covers every later stage).
            image.assume_state(specula::vk::ImageState {
                stage: vk::PipelineStageFlags2::ALL_COMMANDS,
                access: vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE,
                layout,
            });
            let got = specula::vk::read_image(&own, &image).unwrap();
            image.destroy(&own);
            let (mut exact, mut worst) = (0usize, 0f32);
            for (i, (&g, &r)) in got.data.iter().zip(&reference).enumerate() {
                // The difference in the format's own steps: 8-bit codes or half-float ulps.
                let steps = match format {
                    vk::Format::R16G16B16A16_SFLOAT => {
                        (half::f16::from_f32(g).to_bits() as i32 - half::f16::from_f32(r).to_bits() as i32).abs() as f32
                    }
                    vk::Format::B8G8R8A8_SRGB if i % 4 != 3 => (g * 255.0 - specula::scene::linear_to_srgb(r) as f32).abs(),
                    _ => (g * 255.0 - (r.clamp(0.0, 1.0) * 255.0).round()).abs(),
                };
                exact += (steps < 0.01) as usize;
                worst = worst.max(steps);
            }
            eprintln!("{format:?} left in {layout:?}: {exact} of {} channels exact, worst {worst} step(s)", got.data.len());
            assert!(worst <= 1.0, "{format:?} {layout:?}: a channel differs by {worst} steps from the standalone frame");
        }
    }
    unsafe { assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS) };
    common::assert_clean(&own);
}
