//! Readback of images to the CPU as f32 texels ([`ImageData`]).

use ash::vk;

use super::{Access, Buffer, Context, Image, MemoryLocation};
use crate::error::{Error, Result};
use crate::image::ImageData;

/// Records a copy of every layer of `image` into `buffer` (which must hold `byte_size`).
pub fn record_copy_to_buffer(ctx: &Context, cmd: vk::CommandBuffer, image: &Image, buffer: &Buffer) {
    let region = vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: image.aspect,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: image.layers(),
        },
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D { width: image.width, height: image.height, depth: 1 },
    };
    unsafe { ctx.device.cmd_copy_image_to_buffer(cmd, image.raw, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer.raw, &[region]) };
}

/// Decodes the bytes of a copied image into f32 texels (8-bit formats: the stored code / 255,
/// sRGB codes not decoded).
pub fn decode(format: vk::Format, width: u32, height: u32, layers: u32, bytes: &[u8]) -> Result<ImageData> {
    let n = (width * height * layers) as usize;
    let (channels, data): (u32, Vec<f32>) = match format {
        vk::Format::R32G32B32A32_SFLOAT => (4, bytemuck::pod_collect_to_vec(&bytes[..n * 16])),
        vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT => (1, bytemuck::pod_collect_to_vec(&bytes[..n * 4])),
        vk::Format::R16G16B16A16_SFLOAT => {
            (4, bytes[..n * 8].chunks_exact(2).map(|h| half::f16::from_le_bytes([h[0], h[1]]).to_f32()).collect())
        }
        vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB => (4, bytes[..n * 4].iter().map(|&b| b as f32 / 255.0).collect()),
        // Stored B, G, R, A: returned as R, G, B, A.
        vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB => {
            (4, bytes[..n * 4].chunks_exact(4).flat_map(|p| [p[2], p[1], p[0], p[3]]).map(|b| b as f32 / 255.0).collect())
        }
        f => return Err(Error::invalid("readback", format!("unsupported format {f:?}"))),
    };
    Ok(ImageData { width, height, layers, channels, data })
}

/// Standalone helper: copies `image` to the host now (submits and waits) and decodes it.
/// Leaves the image in TRANSFER_SRC layout (tracked).
pub fn read_image(ctx: &Context, image: &Image) -> Result<ImageData> {
    let mut staging = Buffer::new(
        ctx,
        &format!("{}.readback", image.name),
        image.byte_size(),
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    let r = ctx.one_shot(|cmd| {
        if let Some(b) = image.transition(Access::TransferSrc) {
            let barriers = [b];
            unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers)) };
        }
        record_copy_to_buffer(ctx, cmd, image, &staging);
        Ok(())
    });
    let out = r.and_then(|_| decode(image.format, image.width, image.height, image.layers(), staging.read()?));
    staging.destroy(ctx);
    out
}
