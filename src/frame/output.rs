//! `frame.output`: host-device mode's last pass, the frame's image copied into the host's
//! (a bit-exact copy for the same format, a blit with conversion otherwise).

use ash::vk;

use crate::vk::{Access, Image, Recorder};

/// Copies `target` into `host` (same size) and leaves `host` in `final_layout`.
pub fn record_copy(rec: &mut Recorder, target: &Image, host: &mut Image, final_layout: vk::ImageLayout) {
    let (ctx, cmd) = (rec.ctx, rec.cmd);
    let open = rec.pass("frame.output").reads(target, Access::TransferSrc).writes(host, Access::TransferDst).begin();
    let layers = |aspect| vk::ImageSubresourceLayers { aspect_mask: aspect, mip_level: 0, base_array_layer: 0, layer_count: 1 };
    let c = vk::ImageAspectFlags::COLOR;
    let (w, h) = (target.width, target.height);
    let (src, dst) = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
    unsafe {
        if host.format == target.format {
            let region = vk::ImageCopy {
                src_subresource: layers(c),
                dst_subresource: layers(c),
                extent: vk::Extent3D { width: w, height: h, depth: 1 },
                ..Default::default()
            };
            ctx.device.cmd_copy_image(cmd, target.raw, src, host.raw, dst, &[region]);
        } else {
            let corner = vk::Offset3D { x: w as i32, y: h as i32, z: 1 };
            let region = vk::ImageBlit {
                src_subresource: layers(c),
                src_offsets: [vk::Offset3D::default(), corner],
                dst_subresource: layers(c),
                dst_offsets: [vk::Offset3D::default(), corner],
            };
            ctx.device.cmd_blit_image(cmd, target.raw, src, host.raw, dst, &[region], vk::Filter::NEAREST);
        }
        let barriers = [host.release_to(final_layout)];
        ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers));
    }
    rec.end(open);
}
