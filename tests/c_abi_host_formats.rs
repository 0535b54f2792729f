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
