//! The camera's targets and their resolve: the colour and depth the camera passes draw
//! into (`aa=ssaaN`: N² samples per pixel; `aa=msaaN`: N samples per pixel), and the steps
//! that bring them down to the output size.

use ash::vk;

use crate::error::{Error, Result};
use crate::frame::direct::{DEPTH_FORMAT, TARGET_FORMAT};
use crate::plan::Plan;
use crate::vk::pipeline::{sample_count_flags, Multisample};
use crate::vk::{Access, Context, Image, ImageDesc, ImageKind, Recorder};

/// The camera's colour and depth, and the images that resolve them to the output size.
pub(super) struct Targets {
    pub target: Image,
    pub depth: Image,
    /// Supersampling per axis (`aa=ssaaN`): the camera passes render `ssaa`² samples per
    /// pixel into `target`, and `resolve` halves it down to the output size (2×2 box each
    /// step). Multisampling (`aa=msaaN`): `target` and `depth` hold `multisample.samples`
    /// samples per pixel, and `resolve` is the one image they are averaged into.
    pub ssaa: u32,
    pub multisample: Multisample,
    pub resolve: Vec<Image>,
}

impl Targets {
    /// Nothing allocated yet: `create` fills it, `destroy` frees whatever exists.
    pub fn empty(ssaa: u32, multisample: Multisample) -> Targets {
        Targets { target: Image::placeholder(), depth: Image::placeholder(), ssaa, multisample, resolve: Vec::new() }
    }

    /// Checks the plan's `aa` for a `width`×`height` output on this device.
    pub fn check(ctx: &Context, plan: &Plan, width: u32, height: u32) -> Result<(u32, Multisample)> {
        let ssaa = plan.quality.frame.aa.ssaa();
        if ![1, 2, 4].contains(&ssaa) {
            return Err(Error::invalid("knob aa", format!("{ssaa} samples per axis: supersampling takes 1, 2 or 4")));
        }
        if width * ssaa > 16384 || height * ssaa > 16384 {
            return Err(Error::invalid("knob aa", format!("{width}x{height} with {ssaa}×{ssaa} samples exceeds 16384 per axis")));
        }
        Ok((ssaa, camera_multisample(ctx, plan)?))
    }

    /// The camera targets' size (the output's times the supersampling factor).
    pub fn size(&self, width: u32, height: u32) -> (u32, u32) {
        (width * self.ssaa, height * self.ssaa)
    }

    /// Creates the camera targets for a `width`×`height` output.
    pub fn create(&mut self, ctx: &Context, width: u32, height: u32) -> Result<()> {
        let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED;
        let (sw, sh) = self.size(width, height);
        let samples = self.multisample.samples;
        let kind = if samples > 1 { ImageKind::D2Multisample { samples } } else { ImageKind::D2 };
        // A multisampled target is only resolved from, never sampled.
        let usage = if samples > 1 { usage & !vk::ImageUsageFlags::SAMPLED } else { usage };
        self.target = Image::new(ctx, &ImageDesc { name: "frame.color", format: TARGET_FORMAT, width: sw, height: sh, kind, usage })?;
        self.depth = Image::new(
            ctx,
            &ImageDesc {
                name: "frame.depth",
                format: DEPTH_FORMAT,
                width: sw,
                height: sh,
                kind,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            },
        )?;
        if samples > 1 {
            let usage = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED;
            let desc = ImageDesc { name: "frame.resolved", format: TARGET_FORMAT, width: sw, height: sh, kind: ImageKind::D2, usage };
            self.resolve.push(Image::new(ctx, &desc)?);
        }
        // Supersampling: halving steps down to the output size (linear 2:1 blits average
        // each 2×2 block exactly).
        if self.ssaa > 1 {
            let props = unsafe { ctx.instance.get_physical_device_format_properties(ctx.physical, TARGET_FORMAT) };
            let need =
                vk::FormatFeatureFlags::BLIT_SRC | vk::FormatFeatureFlags::BLIT_DST | vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR;
            if !props.optimal_tiling_features.contains(need) {
                return Err(Error::invalid("knob aa", format!("the device cannot blit {TARGET_FORMAT:?} with linear filtering")));
            }
            let mut f = self.ssaa;
            while f > 1 {
                f /= 2;
                let usage = vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::SAMPLED;
                let name = if f == 1 { "frame.resolved" } else { "frame.resolve_half" };
                let desc = ImageDesc { name, format: TARGET_FORMAT, width: width * f, height: height * f, kind: ImageKind::D2, usage };
                self.resolve.push(Image::new(ctx, &desc)?);
            }
        }
        Ok(())
    }

    /// The image at the output size: the last resolve step's, or the target itself.
    pub fn output(&self) -> &Image {
        self.resolve.last().unwrap_or(&self.target)
    }

    /// Records `frame.resolve`: the multisample resolve, or the supersampling's 2×2 box steps.
    pub fn record_resolve(&mut self, rec: &mut Recorder) {
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let layers =
            vk::ImageSubresourceLayers { aspect_mask: vk::ImageAspectFlags::COLOR, mip_level: 0, base_array_layer: 0, layer_count: 1 };
        let (s, d) = (vk::ImageLayout::TRANSFER_SRC_OPTIMAL, vk::ImageLayout::TRANSFER_DST_OPTIMAL);
        if self.multisample.samples > 1 {
            // Multisampling: the samples' average (vkCmdResolveImage on a float format).
            let dst = &mut self.resolve[0];
            let open = rec.pass("frame.resolve").reads(&self.target, Access::TransferSrc).writes(dst, Access::TransferDst).begin();
            let region = vk::ImageResolve {
                src_subresource: layers,
                src_offset: vk::Offset3D::default(),
                dst_subresource: layers,
                dst_offset: vk::Offset3D::default(),
                extent: vk::Extent3D { width: dst.width, height: dst.height, depth: 1 },
            };
            unsafe { ctx.device.cmd_resolve_image(cmd, self.target.raw, s, dst.raw, d, &[region]) };
            rec.end(open);
        }
        // Supersampling: 2×2 box steps down to the output size (with MSAA `resolve` holds
        // the multisample resolve's one image instead).
        let blits = if self.ssaa > 1 { self.resolve.len() } else { 0 };
        for i in 0..blits {
            let (done, rest) = self.resolve.split_at_mut(i);
            let src = done.last_mut().unwrap_or(&mut self.target);
            let dst = &mut rest[0];
            let open = rec.pass("frame.resolve").reads(src, Access::TransferSrc).writes(dst, Access::TransferDst).begin();
            let corner = |i: &Image| vk::Offset3D { x: i.width as i32, y: i.height as i32, z: 1 };
            let region = vk::ImageBlit {
                src_subresource: layers,
                src_offsets: [vk::Offset3D::default(), corner(src)],
                dst_subresource: layers,
                dst_offsets: [vk::Offset3D::default(), corner(dst)],
            };
            unsafe { ctx.device.cmd_blit_image(cmd, src.raw, s, dst.raw, d, &[region], vk::Filter::LINEAR) };
            rec.end(open);
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.target.destroy(ctx);
        self.depth.destroy(ctx);
        for i in &mut self.resolve {
            i.destroy(ctx);
        }
        self.resolve.clear();
    }
}

/// The camera target's samples for the plan's `aa` (MSAA), checked against what the
/// device can render: the sample counts of the target's colour and depth formats, and
/// sample-rate shading (the per-sample passes, and the ray pipelines' one ray per sample).
fn camera_multisample(ctx: &Context, plan: &Plan) -> Result<Multisample> {
    let q = &plan.quality;
    let samples = q.frame.aa.msaa();
    if samples == 1 {
        return Ok(Multisample::OFF);
    }
    let name = format!("msaa{samples}");
    if ![2, 4, 8].contains(&samples) {
        return Err(Error::invalid("knob aa", format!("{name}: multisampling takes 2, 4 or 8 samples per pixel")));
    }
    let counts = |format: vk::Format, usage: vk::ImageUsageFlags| unsafe {
        ctx.instance
            .get_physical_device_image_format_properties(
                ctx.physical,
                format,
                vk::ImageType::TYPE_2D,
                vk::ImageTiling::OPTIMAL,
                usage,
                vk::ImageCreateFlags::empty(),
            )
            .map_or(vk::SampleCountFlags::TYPE_1, |p| p.sample_counts)
    };
    let colour = counts(TARGET_FORMAT, vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC);
    let depth = counts(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT);
    let both =
        colour & depth & ctx.properties.limits.framebuffer_color_sample_counts & ctx.properties.limits.framebuffer_depth_sample_counts;
    if !both.contains(sample_count_flags(samples)) {
        let offered: Vec<String> =
            [2u32, 4, 8, 16].iter().filter(|&&n| both.contains(sample_count_flags(n))).map(|n| format!("msaa{n}")).collect();
        let offered = if offered.is_empty() { "none".to_string() } else { offered.join(", ") };
        return Err(Error::invalid(
            "knob aa",
            format!(
                "{name}: {} cannot render {TARGET_FORMAT:?} colour with {DEPTH_FORMAT:?} depth at {samples} samples per pixel (it offers: {offered}; ssaa2 and ssaa4 work everywhere)",
                ctx.device_name
            ),
        ));
    }
    if !ctx.sample_rate_shading {
        return Err(Error::invalid(
            "knob aa",
            format!(
                "{name} shades specular passes and ray-traced pixels per sample, which needs the device feature sampleRateShading: {} (ssaa2 and ssaa4 need nothing)",
                if ctx.queue.is_none() { "a host device does not tell whether it enabled it" } else { "this device lacks it" }
            ),
        ));
    }
    Ok(Multisample { samples, per_sample: q.frame.msaa_per_sample })
}
