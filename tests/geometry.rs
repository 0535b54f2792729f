//! Geometry transformation (survey §5): planar mirrors by rendering the mirrored camera's
//! view (`planar-mirror`), against the exact CPU reference at the same recursion depth.

mod common;

use glam::Vec3;
use specula::image::ImageData;
use specula::scene::{shapes, Camera, Material, Scene};
use specula::{Method, Quality};

const SIZE: (u32, u32) = (64, 48);

/// An emissive room (24 distinct quadrants, no lights: nothing but geometry and Fresnel
/// decides the image) of half-size 2 m, an emissive ball, and planar mirrors.
fn room(mirrors: &[(Vec3, Vec3, Vec3)], camera: (Vec3, Vec3)) -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::ZERO, 2.0);
    let ball = s
        .add_material(Material { name: "ball".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.5, 0.8, 0.2), ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.4, -0.8, -0.6), 0.35, 24, 12, ball)).unwrap();
    let m = s.add_material(common::mirror(0.9)).unwrap();
    for (i, (o, u, v)) in mirrors.iter().enumerate() {
        s.add_mesh(shapes::quad(&format!("mirror{i}"), *o, *u, *v, 1, m)).unwrap();
    }
    s.camera = Some(Camera::look_at(camera.0, camera.1, 60f32.to_radians()));
    s
}

fn quality(depth: u32) -> Quality {
    let mut q = Quality { depth, spp: 1, ..Quality::default() };
    q.set("fresnel", "exact").unwrap();
    q
}

fn psnr(a: &ImageData, b: &ImageData) -> f64 {
    specula::metrics::compare(a, b).unwrap().psnr
}

fn gpu(ctx: &specula::vk::Context, s: &Scene, m: Method, q: &Quality) -> specula::Frame {
    specula::render(ctx, s, m, q, SIZE, (0, 1)).unwrap()
}

#[test]
fn a_mirror_wall_is_exact_up_to_rasterisation() {
    let ctx = common::gpu();
    // A 2.4 m × 2.2 m mirror 0.1 m in front of the back wall, seen at an angle.
    let wall = (Vec3::new(-1.2, -1.0, -1.9), Vec3::new(2.4, 0.0, 0.0), Vec3::new(0.0, 2.2, 0.0));
    let s = room(&[wall], (Vec3::new(0.9, 0.3, 1.5), Vec3::new(-0.3, 0.0, -1.9)));
    let q = quality(4);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let f = gpu(&ctx, &s, specula::methods::PLANAR_MIRROR, &q);
    let p = psnr(&f.image, &reference);
    let d = psnr(&gpu(&ctx, &s, specula::methods::DISTANCE, &q).image, &reference);
    println!("mirror wall: planar-mirror {p:.2} dB, distance {d:.2} dB");
    f.image.write_png_srgb(std::path::Path::new("/tmp/gt/wall.png")).ok();
    reference.write_png_srgb(std::path::Path::new("/tmp/gt/wall_ref.png")).ok();
    let names: Vec<&str> = f.passes.iter().map(|p| p.name.as_str()).collect();
    assert!(names.contains(&"geometry.mirror") && names.contains(&"geometry.mirror_view"), "{names:?}");
    assert!(p >= 45.0, "planar-mirror {p:.2} dB against the reference");
    common::assert_clean(&ctx);
}
