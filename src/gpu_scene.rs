//! The scene on the GPU: one interleaved world-space vertex buffer, one index buffer, the
//! material and light tables, textures and the environment map. Images are uploaded by
//! the first frame's `scene.upload` pass (recorded into whatever command buffer renders
//! it), so host-device mode needs no queue of its own.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::error::{Error, Result};
pub use crate::frame::layout::{GpuLight, GpuMaterial, GpuObject, GpuView};
use crate::frame::layout::{KIND_DIELECTRIC, KIND_DIFFUSE, KIND_MIRROR, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT};
use crate::scene::{LightKind, Scene, SurfaceKind};
use crate::vk::{Access, Buffer, Context, Image, ImageDesc, ImageKind, Recorder};

/// Most textures one scene may use (layers of the texture array).
pub const MAX_TEXTURES: usize = 256;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}

/// One mesh's draw call.
#[derive(Clone, Copy, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: i32,
    pub mesh: u32,
    pub specular: bool,
    /// World-space bounds (per-face culling of cube-map passes); kept current by updates.
    pub lo: glam::Vec3,
    pub hi: glam::Vec3,
}

pub struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub materials: Buffer,
    /// Every texture as a layer of one 2D array, resampled to the largest size.
    pub textures: Option<Image>,
    pub environment: Option<Image>,
    pub draws: Vec<Draw>,
    staging: Vec<(Buffer, usize)>,
    uploaded: bool,
}

pub fn gpu_material(m: &crate::scene::Material) -> GpuMaterial {
    let (kind, nu, kappa, thin) = match m.kind {
        SurfaceKind::Diffuse => (KIND_DIFFUSE, [1.0; 3], [0.0; 3], 0),
        SurfaceKind::Mirror { nu, kappa } => (KIND_MIRROR, nu.to_array(), kappa.to_array(), 0),
        // ν per channel: the ior, or each channel's under KHR_materials_dispersion.
        SurfaceKind::Dielectric { ior, thin } => {
            (KIND_DIELECTRIC, m.channel_iors().unwrap_or(glam::Vec3::splat(ior)).to_array(), [0.0; 3], thin as u32)
        }
    };
    let v4 = |a: [f32; 3]| [a[0], a[1], a[2], 0.0];
    GpuMaterial {
        base_color: v4(m.base_color.to_array()),
        emissive: v4(m.emissive.to_array()),
        nu: v4(nu),
        kappa: v4(kappa),
        specular: [m.specular_color.x, m.specular_color.y, m.specular_color.z, m.specular_factor],
        kind,
        base_texture: m.base_color_texture.map_or(-1, |t| t as i32),
        emissive_texture: m.emissive_texture.map_or(-1, |t| t as i32),
        thin,
        absorption: if m.absorbs() { v4(m.absorption.to_array()) } else { [0.0; 4] },
        medium_origin: m.medium().map_or([0.0; 4], |f| [f.origin.x, f.origin.y, f.origin.z, 1.0]),
        medium_gradient: m.medium().map_or([0.0; 4], |f| [f.gradient.x, f.gradient.y, f.gradient.z, f.hessian_norm() as f32]),
        medium_hessian: m.medium().map_or([0.0; 4], |f| [f.hessian[0].x, f.hessian[1].y, f.hessian[2].z, f.hessian[0].y]),
        medium_hessian2: m.medium().map_or([0.0; 4], |f| [f.hessian[0].z, f.hessian[1].z, 0.0, 0.0]),
    }
}

/// A mesh's interleaved vertices, as `scene.vertices` holds them.
pub fn vertices_of(m: &crate::scene::Mesh) -> impl Iterator<Item = Vertex> + '_ {
    m.positions.iter().zip(&m.normals).zip(&m.uvs).map(|((p, n), t)| Vertex {
        position: p.to_array(),
        normal: n.to_array(),
        uv: t.to_array(),
    })
}

/// `LIGHT_*` of a light, as `GpuLight.direction_kind.w` holds it.
pub fn light_kind_code(k: LightKind) -> f32 {
    let code = match k {
        LightKind::Point => LIGHT_POINT,
        LightKind::Spot { .. } => LIGHT_SPOT,
        LightKind::Directional => LIGHT_DIRECTIONAL,
    };
    code as f32
}

impl GpuScene {
    pub fn new(ctx: &Context, scene: &Scene) -> Result<GpuScene> {
        scene.check_renderable()?;
        scene.validate()?;
        if scene.textures.len() > MAX_TEXTURES {
            return Err(Error::invalid("scene", format!("{} textures exceed the limit of {MAX_TEXTURES}", scene.textures.len())));
        }
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut draws = Vec::new();
        for (i, m) in scene.meshes.iter().enumerate() {
            draws.push(Draw {
                first_index: indices.len() as u32,
                index_count: if m.hidden { 0 } else { m.indices.len() as u32 },
                vertex_offset: vertices.len() as i32,
                mesh: i as u32,
                specular: scene.materials[m.material].kind.is_specular(),
                lo: m.bounds().min,
                hi: m.bounds().max,
            });
            vertices.extend(vertices_of(m));
            indices.extend_from_slice(&m.indices);
        }
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(gpu_material).collect();

        let out = GpuScene {
            vertices: Buffer::placeholder(),
            indices: Buffer::placeholder(),
            materials: Buffer::placeholder(),
            textures: None,
            environment: None,
            draws,
            staging: Vec::new(),
            uploaded: false,
        };
        crate::vk::build(ctx, out, |out| {
            // Also a storage buffer: curved reflectors' tessellation pre-pass reads it (§5).
            let usage = vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER;
            out.vertices = Buffer::with_data(ctx, "scene.vertices", &vertices, usage)?;
            out.indices = Buffer::with_data(ctx, "scene.indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
            out.materials = Buffer::with_data(ctx, "scene.materials", &materials, vk::BufferUsageFlags::STORAGE_BUFFER)?;
            out.create_images(ctx, scene)
        })
    }

    fn create_images(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        if !scene.textures.is_empty() {
            let w = scene.textures.iter().map(|t| t.width).max().unwrap_or(1);
            let h = scene.textures.iter().map(|t| t.height).max().unwrap_or(1);
            let mut texels = Vec::with_capacity((w * h * 4) as usize * scene.textures.len());
            for t in &scene.textures {
                texels.extend_from_slice(&resampled(t, w, h)?);
            }
            let kind = ImageKind::D2Array { layers: scene.textures.len() as u32 };
            self.textures = Some(Image::new(
                ctx,
                &ImageDesc { name: "scene.textures", format: vk::Format::R8G8B8A8_SRGB, width: w, height: h, kind, usage },
            )?);
            let staging = Buffer::with_data(ctx, "scene.textures.staging", &texels, vk::BufferUsageFlags::TRANSFER_SRC)?;
            self.staging.push((staging, 0));
        }
        if let Some(env) = &scene.environment {
            let img = Image::new(
                ctx,
                &ImageDesc {
                    name: "scene.environment",
                    format: vk::Format::R32G32B32A32_SFLOAT,
                    width: env.width,
                    height: env.height,
                    kind: ImageKind::D2,
                    usage,
                },
            )?;
            self.environment = Some(img);
            let staging = Buffer::with_data(ctx, "scene.environment.staging", &env.rgba32f, vk::BufferUsageFlags::TRANSFER_SRC)?;
            self.staging.push((staging, usize::MAX));
        }
        Ok(())
    }

    /// Whether the next frame must record `scene.upload`.
    pub fn needs_upload(&self) -> bool {
        !self.uploaded && !self.staging.is_empty()
    }

    /// Records the image uploads (the `scene.upload` pass). Staging memory is kept until
    /// `release_staging` or `destroy`, because the GPU reads it when the frame runs.
    pub fn record_upload(&mut self, rec: &mut Recorder) {
        if !self.needs_upload() {
            return;
        }
        let mut pass = rec.pass("scene.upload");
        for (_, i) in &self.staging {
            let img = if *i == usize::MAX { self.environment.as_mut() } else { self.textures.as_mut() };
            let Some(img) = img else { continue };
            pass = pass.writes(img, Access::TransferDst);
        }
        let open = pass.begin();
        for (buf, i) in &self.staging {
            let img = if *i == usize::MAX { self.environment.as_ref() } else { self.textures.as_ref() };
            let Some(img) = img else { continue };
            let region = vk::BufferImageCopy {
                buffer_offset: 0,
                buffer_row_length: 0,
                buffer_image_height: 0,
                image_subresource: vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: img.layers(),
                },
                image_offset: vk::Offset3D::default(),
                image_extent: vk::Extent3D { width: img.width, height: img.height, depth: 1 },
            };
            unsafe { rec.ctx.device.cmd_copy_buffer_to_image(rec.cmd, buf.raw, img.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[region]) };
        }
        rec.end(open);
        self.uploaded = true;
    }

    /// Frees the staging buffers once the frame that uploaded has completed.
    pub fn release_staging(&mut self, ctx: &Context) {
        if self.uploaded {
            for (mut b, _) in self.staging.drain(..) {
                b.destroy(ctx);
            }
        }
    }

    pub fn bind_geometry(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        unsafe {
            ctx.device.cmd_bind_vertex_buffers(cmd, 0, &[self.vertices.raw], &[0]);
            ctx.device.cmd_bind_index_buffer(cmd, self.indices.raw, 0, vk::IndexType::UINT32);
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.vertices.destroy(ctx);
        self.indices.destroy(ctx);
        self.materials.destroy(ctx);
        if let Some(t) = &mut self.textures {
            t.destroy(ctx);
        }
        if let Some(e) = &mut self.environment {
            e.destroy(ctx);
        }
        for (b, _) in &mut self.staging {
            b.destroy(ctx);
        }
    }
}

/// A texture's RGBA8 texels at `w`×`h` (bilinear resampling when its size differs).
fn resampled(t: &crate::scene::Texture, w: u32, h: u32) -> Result<Vec<u8>> {
    if t.width == w && t.height == h {
        return Ok(t.rgba8.clone());
    }
    let img = image::RgbaImage::from_raw(t.width, t.height, t.rgba8.clone())
        .ok_or_else(|| Error::invalid(format!("texture '{}'", t.name), "texel data does not match its size"))?;
    Ok(image::imageops::resize(&img, w, h, image::imageops::FilterType::Triangle).into_raw())
}

impl crate::vk::Owner for GpuScene {
    fn destroy(&mut self, ctx: &Context) {
        GpuScene::destroy(self, ctx)
    }
}
