//! Renders a glass sphere in the quadrant room with the refraction methods and the
//! reference, side by side (a development aid for §4.4): `cargo run --release --example
//! glass_compare -- OUT.png [IOR]`.
use glam::Vec3;
use specula::scene::{shapes, Camera, Material, Scene, SurfaceKind};
use specula::vk::{Context, DeviceOptions};
use specula::Quality;

fn main() -> specula::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).cloned().unwrap_or_else(|| "glass_compare.png".into());
    let ior: f32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1.5);
    let mut s = Scene::new();
    specula::scenes::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0)?;
    let g = s.add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() })?;
    s.add_mesh(shapes::uv_sphere("glass", Vec3::new(0.0, 1.5, 0.0), 0.6, 96, 48, g))?;
    s.camera = Some(Camera::look_at(Vec3::new(0.3, 1.8, 1.9), Vec3::new(0.0, 1.5, 0.0), 40f32.to_radians()));
    let ctx = Context::new(&DeviceOptions::default())?;
    let mut q = Quality::default();
    q.set("fresnel", "exact")?;
    q.set("spp", "4")?;
    let size = 256u32;
    let mut images = vec![specula::reference::render_reference(&s, &q, (size, size))?];
    for m in [specula::methods::DISTANCE, specula::methods::REFRACTOR_MAP, specula::methods::IMAGE_SPACE_REFRACTION] {
        images.push(specula::render(&ctx, &s, m, &q, (size, size), (0, 1))?.image);
    }
    let mut row = vec![0f32; (size * size * 4) as usize * images.len()];
    for (i, img) in images.iter().enumerate() {
        for y in 0..size {
            for x in 0..size {
                let src = ((y * size + x) * 4) as usize;
                let dst = ((y * size * images.len() as u32 + i as u32 * size + x) * 4) as usize;
                row[dst..dst + 4].copy_from_slice(&img.data[src..src + 4]);
            }
        }
    }
    specula::scene::write_png_srgb(std::path::Path::new(&out), size * images.len() as u32, size, &row)
}
