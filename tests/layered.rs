//! Layered distance maps (survey §4.5, UPSK07) against the exact CPU reference, on
//! lavapipe with validation on: a concave mirror that reflects itself, a non-convex glass
//! object, Figure 28's search-step and layer-count artefacts, and what the map allocates.
//! Images are small (64²–96²); floors sit within 1 dB of what was measured (stated beside
//! each).

mod common;

use glam::Vec3;
use specula::metrics::{self, ImageErrors};
use specula::reference::render_reference;
use specula::scene::{shapes, Camera, Material, Mesh, Scene, SurfaceKind};
use specula::vk::{Context, ImageData};
use specula::{Method, Quality};

fn quality(pairs: &[&str]) -> Quality {
    let mut q = Quality::default();
    for p in pairs {
        q.set_pair(p).unwrap();
    }
    q
}

fn gpu(ctx: &Context, scene: &Scene, method: Method, pairs: &[&str], size: u32) -> (ImageData, Vec<(String, f64)>) {
    let f = specula::render(ctx, scene, method, &quality(pairs), (size, size), (0, 1)).unwrap();
    (f.image, f.stats)
}

fn reference(scene: &Scene, pairs: &[&str], size: u32) -> ImageData {
    render_reference(scene, &quality(pairs), (size, size)).unwrap()
}

fn errors(test: &ImageData, reference: &ImageData) -> ImageErrors {
    metrics::compare(test, reference).unwrap()
}

fn stat(stats: &[(String, f64)], name: &str) -> f64 {
    stats.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no stat {name} in {stats:?}")).1
}

/// The lower part of a sphere (centre `c`, radius `r`) below y = c.y + `cut`·r: a concave
/// bowl open upwards.
fn bowl(name: &str, c: Vec3, r: f32, cut: f32, material: usize) -> Mesh {
    let s = shapes::uv_sphere(name, c, r, 64, 32, material);
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    let keep = |i: u32| s.positions[i as usize].y < c.y + cut * r;
    let mut remap = vec![u32::MAX; s.positions.len()];
    for t in s.indices.chunks(3) {
        if !t.iter().all(|&i| keep(i)) {
            continue;
        }
        for &i in t {
            if remap[i as usize] == u32::MAX {
                remap[i as usize] = m.positions.len() as u32;
                m.positions.push(s.positions[i as usize]);
                // The inside of the bowl faces its centre.
                m.normals.push(-s.normals[i as usize]);
                m.uvs.push(s.uvs[i as usize]);
            }
            m.indices.push(remap[i as usize]);
        }
    }
    m
}

/// The emissive quadrant room with a mirror bowl (a hemisphere, F0 0.9) and a small
/// emissive ball inside it, seen from above at an angle: the bowl reflects the ball and
/// itself.
fn bowl_scene() -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = s.add_material(common::mirror(0.9)).unwrap();
    let ball = s
        .add_material(Material { name: "ball".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.0, 0.6, 0.2), ..Default::default() })
        .unwrap();
    s.add_mesh(bowl("bowl", Vec3::new(0.0, 1.6, 0.0), 1.0, 0.0, m)).unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.25, 0.95, 0.1), 0.18, 24, 12, ball)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 3.3, 1.6), Vec3::new(0.0, 1.0, 0.0), 45f32.to_radians()));
    s
}

#[test]
fn explore_bowl() {
    let ctx = common::gpu();
    let s = bowl_scene();
    let size = 64;
    for depth in [1, 2, 4] {
        let d = format!("depth={depth}");
        let r = reference(&s, &["spp=4", &d, "caustics=off"], size);
        let (l, stats) = gpu(&ctx, &s, specula::methods::LAYERED, &[&d, "caustics=off", "cube_size=128"], size);
        let (dm, _) = gpu(&ctx, &s, specula::methods::DISTANCE, &[&d, "caustics=off", "cube_size=128"], size);
        eprintln!("depth {depth}: layered {} distance {} stats {stats:?}", errors(&l, &r), errors(&dm, &r));
        if depth == 2 {
            l.write_png_srgb(std::path::Path::new("/tmp/layered_bowl.png")).ok();
            r.write_png_srgb(std::path::Path::new("/tmp/ref_bowl.png")).ok();
            dm.write_png_srgb(std::path::Path::new("/tmp/dist_bowl.png")).ok();
        }
    }
    common::assert_clean(&ctx);
}
