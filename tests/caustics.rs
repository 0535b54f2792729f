//! Caustics (survey §6): photon hit location images, photon splatting and caustic
//! triangles into light cube maps, projection with the distance test; against closed forms
//! and the CPU light tracer (src/reference/caustics.rs).

mod common;

use glam::{DVec3, Mat4, Vec3};
use specula::quality::Quality;
use specula::scene::{shapes, Camera, Light, LightKind, Material, Scene, SurfaceKind};
use specula::vk::read_image;
use specula::{plan, Renderer};

/// A solid glass sphere (radius `R`, centre `C`) above a diffuse floor, lit by a point
/// light straight above it.
const R: f32 = 0.5;
const C: Vec3 = Vec3::new(0.0, 1.0, 0.0);
const LIGHT: Vec3 = Vec3::new(0.0, 3.0, 0.0);
const INTENSITY: f32 = 10.0;

fn sphere_over_floor(ior: f32) -> Scene {
    scaled_sphere_over_floor(ior, 1.0)
}

/// The same scene scaled by `k` (1 km: 1000, 1 mm: 0.001), the light's intensity by k² so
/// that irradiance stays the same.
fn scaled_sphere_over_floor(ior: f32, k: f32) -> Scene {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    let glass = s
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, 0.0, -3.0) * k, Vec3::new(6.0, 0.0, 0.0) * k, Vec3::new(0.0, 0.0, 6.0) * k, 8, floor))
        .unwrap();
    s.add_mesh(shapes::uv_sphere("glass", C * k, R * k, 48, 24, glass)).unwrap();
    s.add_light(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position: LIGHT * k,
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(INTENSITY * k * k),
        range: None,
    })
    .unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 1.2, 3.0) * k, Vec3::ZERO, 50f32.to_radians()));
    s
}

fn quality(pairs: &[&str]) -> Quality {
    let mut q = Quality::default();
    // Caustics off unless a test asks for them (the knob's default is triangles).
    for p in ["cube_size=64", "shadow_size=128", "fresnel=exact", "photons=64", "caustics=off"].iter().chain(pairs) {
        q.set_pair(p).unwrap();
    }
    q
}

/// The power a point light sends through a glass sphere by two refractions (the closed
/// form the caustic's energy is checked against): ∫ I (1 − F(θ))² dΩ over the sphere's cone,
/// θ the incidence angle at impact parameter b = d sin ψ (exit at the same angle inside).
fn two_refraction_power(ior: f64) -> f64 {
    spot_two_refraction_power(ior, None)
}

/// The same under a spot light aimed straight down with cones (inner, outer): each
/// direction's intensity weighted by glTF's smooth falloff, clamp((cos ψ − cos outer) /
/// (cos inner − cos outer), 0, 1)², with the cones' cosines rounded to f32 as the GPU's
/// light table holds them.
fn spot_two_refraction_power(ior: f64, cones: Option<(f32, f32)>) -> f64 {
    let falloff = |psi: f64| match cones {
        None => 1.0,
        Some((inner, outer)) => {
            let (ci, co) = (inner.cos() as f64, outer.cos() as f64);
            ((psi.cos() - co) / (ci - co)).clamp(0.0, 1.0).powi(2)
        }
    };
    let d = (LIGHT - C).length() as f64;
    let r = R as f64;
    let psi_max = (r / d).asin();
    let n = 20000;
    let mut sum = 0.0;
    for k in 0..n {
        let psi = (k as f64 + 0.5) / n as f64 * psi_max;
        let sin_i = (d * psi.sin() / r).min(1.0);
        let cos_i = (1.0 - sin_i * sin_i).sqrt();
        let t = 1.0 - specula::optics::fresnel_dielectric(cos_i, ior);
        sum += falloff(psi) * t * t * 2.0 * std::f64::consts::PI * psi.sin() * (psi_max / n as f64);
    }
    INTENSITY as f64 * sum
}

/// Σ J·Ω over the texels of the light cube `cube` (the caustic's total power, W).
fn cube_power(data: &specula::image::ImageData, cube: u32) -> DVec3 {
    let n = data.width;
    let mut sum = DVec3::ZERO;
    for face in 6 * cube..6 * cube + 6 {
        for y in 0..n {
            for x in 0..n {
                let s = 2.0 * (x as f64 + 0.5) / n as f64 - 1.0;
                let t = 2.0 * (y as f64 + 0.5) / n as f64 - 1.0;
                let omega = (2.0 / n as f64).powi(2) / (1.0 + s * s + t * t).powf(1.5);
                let j = data.texel(face, x, y);
                sum += DVec3::new(j[0] as f64, j[1] as f64, j[2] as f64) * omega;
            }
        }
    }
    sum
}

/// Renders with `method` at 64×64; the frame's image.
fn image(ctx: &specula::vk::Context, scene: &Scene, q: &Quality) -> specula::image::ImageData {
    specula::render(ctx, scene, specula::methods::REFRACTOR_MAP, q, (64, 64), (0, 1)).unwrap().image
}

fn luminance(img: &specula::image::ImageData, i: usize) -> f64 {
    let p = &img.data[4 * i..4 * i + 3];
    (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0
}

/// The light cube's total power Σ J·Ω after one frame, and the frame's pass names.
fn caustic_power(ctx: &specula::vk::Context, scene: &Scene, q: &Quality) -> (f64, Vec<String>) {
    let (power, passes) = caustic_power_rgb(ctx, scene, q);
    (power.x, passes)
}

/// `caustic_power` per channel.
fn caustic_power_rgb(ctx: &specula::vk::Context, scene: &Scene, q: &Quality) -> (DVec3, Vec<String>) {
    let p = plan(scene, specula::methods::REFRACTOR_MAP, q);
    assert!(p.caustics.is_some(), "caustics planned: {:?}", p.passes);
    let mut r = Renderer::new(ctx, scene, p, 16, 16).unwrap();
    let f = r.render(ctx).unwrap();
    let cube = read_image(ctx, r.maps().image(&specula::methods::caustics::slots::CAUSTIC_MAPS).unwrap()).unwrap();
    let power = cube_power(&cube, 0);
    assert!(power.is_finite(), "{power}");
    r.destroy(ctx);
    (power, f.passes.iter().map(|p| p.name.clone()).collect())
}

#[test]
fn caustic_power_matches_the_fresnel_transmittances() {
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    let expected = two_refraction_power(1.5);
    // Lost: triangles across the silhouette (a photon missing) and across distance gaps,
    // texels of the photon cone's rim; a few per cent, less with more photons. The loss
    // 1 − ratio may be at most 1.122 × what was measured: splat 0.0100 at 64² and 128²
    // photons (ratios 0.99002, 0.98997), triangles 0.0577 at 64² (0.94233), 0.0319 at 128²
    // (0.96814).
    // Nothing is gained: at most 1.005 (the quadrature's and f32 accumulation's error).
    for (filter, photons, lo) in [("splat", 64, 0.9888), ("splat", 128, 0.9888), ("triangles", 64, 0.9353), ("triangles", 128, 0.9643)] {
        let q = quality(&[&format!("caustics={filter}"), &format!("photons={photons}"), "caustic_paths=refracted"]);
        let (power, passes) = caustic_power(&ctx, &scene, &q);
        let ratio = power / expected;
        eprintln!("{filter} photons={photons}: power {power:.4} W, closed form {expected:.4} W, ratio {ratio:.5}");
        assert!((lo..=1.005).contains(&ratio), "{filter} {photons}: {ratio}");
        let accumulate = if filter == "splat" { "caustics.splat" } else { "caustics.triangles" };
        for name in ["caustics.receivers", "caustics.photons", accumulate, "caustics.filter", "caustics.project"] {
            assert!(passes.iter().any(|p| p == name), "{name} in {passes:?}");
        }
    }
    // Texture space (SKALP05): the light map's power Σ E·A over its texels (one texel area for
    // the whole map). Measured ratio 0.99540 at 128² photons and 512² texels (the cube: 0.98997).
    let q = quality(&["caustics=splat", "photons=128", "caustic_paths=refracted", "caustic_space=texture", "light_map_size=512"]);
    let mut r = Renderer::new(&ctx, &scene, plan(&scene, specula::methods::REFRACTOR_MAP, &q), 16, 16).unwrap();
    r.render(&ctx).unwrap();
    let map = read_image(&ctx, r.maps().image(&specula::methods::caustics::slots::CAUSTIC_LIGHT_MAP).unwrap()).unwrap();
    r.destroy(&ctx);
    let atlas = specula::methods::caustics::atlas::Atlas::build(&scene, 512, specula::methods::caustics::atlas::gutter()).unwrap();
    let power = (0..map.width * map.height).map(|i| map.data[4 * i as usize] as f64).sum::<f64>() * atlas.texel * atlas.texel;
    eprintln!("texture space: power {power:.4} W, closed form {expected:.4} W, ratio {:.5}", power / expected);
    assert!((0.9888..=1.005).contains(&(power / expected)), "texture space: {power} vs {expected}");
    common::assert_clean(&ctx);
}

/// A planar mirror panel (F0 0.9, 2 × 1.6 m on a wall) under a point light, beside a wide
/// floor, and the power the panel reflects onto the floor, ∫ F(θ) I dΩ over the panel's
/// points whose reflection reaches the floor (a quadrature: the panel in 400 × 400 cells,
/// exact conductor Fresnel with ν from F0, κ 0).
fn mirror_panel() -> (Scene, f64) {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    let f0 = 0.9f64;
    let mirror = s.add_material(common::mirror(f0 as f32)).unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-1.5, 0.0, -12.0), Vec3::new(24.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 24.0), 8, floor)).unwrap();
    let (corner, u, v) = (Vec3::new(-1.5, 0.3, 1.0), Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 1.6, 0.0));
    s.add_mesh(shapes::quad("panel", corner, u, v, 2, mirror)).unwrap();
    let light = Vec3::new(0.2, 1.4, 0.1);
    s.add_light(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position: light,
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(INTENSITY),
        range: None,
    })
    .unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(2.0, 2.0, 2.0), Vec3::new(-0.5, 0.0, 0.0), 60f32.to_radians()));
    let nu = (1.0 + f0.sqrt()) / (1.0 - f0.sqrt());
    let normal = DVec3::X;
    let cells = 400;
    let mut expected = 0.0;
    for i in 0..cells {
        for j in 0..cells {
            let p = (corner + u * ((i as f32 + 0.5) / cells as f32) + v * ((j as f32 + 0.5) / cells as f32)).as_dvec3();
            let to = p - light.as_dvec3();
            let r2 = to.length_squared();
            let d = to / r2.sqrt();
            let cos = -d.dot(normal);
            let refl = d - 2.0 * d.dot(normal) * normal;
            // Onto the floor (y = 0, x < 22.5, |z| < 12).
            let t = -p.y / refl.y;
            let hit = p + refl * t;
            if !(refl.y < 0.0 && hit.x < 22.5 && hit.z.abs() < 12.0) {
                continue;
            }
            let area = (u.length() * v.length()) as f64 / (cells * cells) as f64;
            let f = specula::optics::fresnel_conductor(cos, nu, 0.0);
            expected += f * INTENSITY as f64 * cos * area / r2;
        }
    }
    (s, expected)
}

/// The mirror panel's light cube map holds the power the panel reflects onto the floor
/// (`mirror_panel`): the photon image is fitted to the panel's corners as the light sees
/// them (every photon on the panel; the bounding sphere's cone spent most of them beside it),
/// for splats and caustic triangles.
#[test]
fn a_planar_mirror_throws_its_light_whole() {
    let ctx = common::gpu();
    let (s, expected) = mirror_panel();
    // Measured ratios (photons=128): splats 1.0393 (1.0384 at photons=512: not the
    // silhouette; a 4 % excess that the sphere's splats do not show, not found), triangles
    // 0.8569 (the triangles whose corners land on the far floor at distances from the cube's
    // centre more than CAUSTIC_GAP apart are dropped). With the bounding sphere's cone
    // instead of the fitted image: splats 1.0340, triangles 0.6361 (the jagged, missing
    // region issue 33 reported). Bounds: splats within [0.97, 1.08], triangles at least 0.80.
    for (filter, lo, hi) in [("splat", 0.97, 1.08), ("triangles", 0.80, 1.08)] {
        let q = quality(&[&format!("caustics={filter}"), "photons=128", "fresnel=exact"]);
        let (power, _) = caustic_power(&ctx, &s, &q);
        let ratio = power / expected;
        eprintln!("planar mirror, {filter}: power {power:.4} W, quadrature {expected:.4} W, ratio {ratio:.5}");
        assert!((lo..=hi).contains(&ratio), "planar mirror, {filter}: {ratio}");
    }
    common::assert_clean(&ctx);
}

/// KHR_materials_volume: photons through absorbing glass lose exp(−σ·2R·cos θ_t) on the
/// chord between their two refractions. The closed form, per channel, is
/// two_refraction_power's integral with that factor; the caustic's power through the
/// sampled geometry's refractor map (caustic_paths=refracted) and through ray queries
/// (exact, which adds the surface's reflection) must follow it. Measured ratios: refracted
/// (0.9924, 0.9941, 0.9982), exact (0.9982, 1.0039, 1.0223) (with the bounding cone's photon
/// images: (0.9914, 0.9929, 0.9965) and (0.9951, 0.9987, 1.0093)); photons that ignored
/// absorption would be off by 1.6 to 34 times (the exact ones by 1.4 to 2.2).
#[test]
fn absorbing_glass_dims_its_caustic() {
    let ctx = common::gpu();
    let sigma = DVec3::new(0.5, 1.5, 4.0);
    let mut scene = wide_floor(1.5);
    let glass = scene.meshes[1].material;
    scene.materials[glass].absorption = sigma.as_vec3();
    let (d, r) = ((LIGHT - C).length() as f64, R as f64);
    let psi_max = (r / d).asin();
    let n = 20000;
    let mut expected = DVec3::ZERO;
    for k in 0..n {
        let psi = (k as f64 + 0.5) / n as f64 * psi_max;
        let sin_i = (d * psi.sin() / r).min(1.0);
        let cos_i = (1.0 - sin_i * sin_i).sqrt();
        let cos_t = (1.0 - sin_i * sin_i / (1.5 * 1.5)).sqrt();
        let t = 1.0 - specula::optics::fresnel_dielectric(cos_i, 1.5);
        let absorbed = (-sigma * 2.0 * r * cos_t).exp();
        expected += absorbed * t * t * 2.0 * std::f64::consts::PI * psi.sin() * (psi_max / n as f64);
    }
    expected *= INTENSITY as f64;
    let clear = two_refraction_power(1.5);
    let mut paths = vec!["refracted"];
    if ctx.ray_query.is_ok() {
        paths.push("exact");
    }
    for p in paths {
        let q = quality(&["caustics=splat", "photons=64", &format!("caustic_paths={p}"), "internal_bounces=0"]);
        let (power, _) = caustic_power_rgb(&ctx, &scene, &q);
        // Exact paths add the surface's reflection (its R layer), which absorption leaves.
        let expected = if p == "exact" { expected + reflected_power(1.5) } else { expected };
        let ratio = power / expected;
        eprintln!("{p}: power {power:.4} W, closed form {expected:.4} W (clear glass {clear:.4} W), ratio {ratio:.5}");
        // A few per cent lost at the silhouette, per channel, as in
        // caustic_power_matches_the_fresnel_transmittances; nothing gained beyond the
        // quadratures' error (the reflected layer's, which dominates the exact blue: 1.03).
        let hi = if p == "exact" { 1.03 } else { 1.005 };
        for k in 0..3 {
            assert!((0.97..=hi).contains(&ratio[k]), "{p}, channel {k}: ratio {}", ratio[k]);
        }
    }
    // The CPU light tracer (the reference's photon map): its photons of two bounces are
    // the T·T layer (the others are the surface's reflection). On a finely tessellated
    // sphere: the 48 × 24 one bends the rim's rays by its interpolated normals enough to
    // move the blue, which the rim carries, by 13 % (measured 1.133; the GPU loses rim
    // photons besides).
    let mut fine = scene.clone();
    fine.meshes[1] = shapes::uv_sphere("glass", C, R, 256, 128, glass);
    let mut q = quality(&["caustics=splat", "caustic_estimate=kernel", "reference_photons=200000"]);
    q.frame.depth = 2;
    let tracer = specula::reference::Tracer::new(&fine, &q).unwrap();
    let photons = tracer.photon_map().unwrap().photons();
    let truth = photons.iter().filter(|p| p.bounces == 2).fold(DVec3::ZERO, |s, p| s + p.power);
    let ratio = truth / expected;
    eprintln!("light tracer: T·T power {truth:.4} W, ratio {ratio:.5}");
    // Measured: (0.9985, 0.9986, 1.0002).
    assert!(ratio.min_element() > 0.99 && ratio.max_element() < 1.01, "light tracer: ratio {ratio}");
    common::assert_clean(&ctx);
}

/// The power the glass sphere's surface reflects down to the floor: ∫ I F(θ_i) dΩ over the
/// light's directions whose reflection goes down (the floor of `wide_floor` catches them).
fn reflected_power(ior: f64) -> f64 {
    let (l, c, r) = (LIGHT.as_dvec3(), C.as_dvec3(), R as f64);
    let psi_max = (r / (l - c).length()).asin();
    let n = 20000;
    let mut expected = 0.0;
    for k in 0..n {
        let psi = (k as f64 + 0.5) / n as f64 * psi_max;
        let d = DVec3::new(psi.sin(), -psi.cos(), 0.0);
        // First intersection of the ray l + t d with the sphere.
        let oc = l - c;
        let b = oc.dot(d);
        let t = -b - (b * b - oc.length_squared() + r * r).max(0.0).sqrt();
        let normal = (l + d * t - c) / r;
        let cos_i = -d.dot(normal);
        let reflected = d + normal * (2.0 * cos_i);
        if reflected.y < -0.05 {
            let f = specula::optics::fresnel_dielectric(cos_i, ior);
            expected += INTENSITY as f64 * f * 2.0 * std::f64::consts::PI * psi.sin() * (psi_max / n as f64);
        }
    }
    expected
}

/// The glass sphere over a floor 8 times wider: every reflected photon lands on it.
fn wide_floor(ior: f32) -> Scene {
    let mut scene = sphere_over_floor(ior);
    scene.meshes[0].positions.iter_mut().for_each(|p| *p *= 8.0);
    scene
}

#[test]
fn the_reflected_branch_adds_the_glass_surface_reflection() {
    // caustic_paths=both adds the photons the sphere's surface reflects: ∫ I F(θ_i) dΩ over
    // the directions whose reflection goes down to the (wide) floor.
    let ctx = common::gpu();
    let scene = wide_floor(1.5);
    let expected = reflected_power(1.5);
    let (both, _) = caustic_power(&ctx, &scene, &quality(&["caustics=splat", "photons=128"]));
    let (refracted, _) = caustic_power(&ctx, &scene, &quality(&["caustics=splat", "photons=128", "caustic_paths=refracted"]));
    let added = both - refracted;
    eprintln!("reflected branch: {added:.4} W, quadrature {expected:.4} W, ratio {:.5}", added / expected);
    // Measured ratio 1.04490: |ratio − 1| at most 1.122 × 0.0449.
    assert!((added / expected - 1.0).abs() <= 0.0503, "{added} vs {expected}");
    common::assert_clean(&ctx);
}

/// caustic_paths=exact (photons traced in the original geometry through ray queries, §6.1.1):
/// with no internal reflections its layers are T·T and R, whose powers have closed forms
/// (the two refractions' Fresnel transmittances, the surface reflection's quadrature); on the
/// glass prism, where total and partial internal reflections carry power, its power is nearer
/// the CPU light tracer's than caustic_paths=both (the sampled geometry's refractor map).
#[test]
fn exact_photons_match_the_closed_forms_and_the_light_tracer() {
    let ctx = common::gpu();
    let scene = wide_floor(1.5);
    let expected = two_refraction_power(1.5) + reflected_power(1.5);
    // Lost, as for caustic_paths=both: photons at the silhouette and the rim; the R layer's
    // wide triangles lose most (measured ratios: exact splat 0.99528 with the bounding cone's
    // photon images, 0.99379 with the fitted ones, triangles 0.90113; both, in the sampled
    // geometry, 0.99447 and 0.90154; refracted only 0.99058 and 0.96814). The loss may be at
    // most 1.122 × the larger measured one; nothing is gained (≤ 1.005).
    for (filter, lo) in [("splat", 0.9930), ("triangles", 0.8889)] {
        let q = quality(&[&format!("caustics={filter}"), "photons=128", "caustic_paths=exact", "internal_bounces=0"]);
        let (power, _) = caustic_power(&ctx, &scene, &q);
        let ratio = power / expected;
        eprintln!("exact {filter}: power {power:.4} W, closed forms (T·T + R) {expected:.4} W, ratio {ratio:.5}");
        assert!((lo..=1.005).contains(&ratio), "exact {filter}: {ratio}");
    }
    // The prism of total_internal_reflection_paths_reach_the_floor.
    let mut s = sphere_over_floor(1.5);
    let glass = s.meshes[1].material;
    s.meshes[1] = glass_box(C, 0.35, std::f32::consts::FRAC_PI_4, glass);
    s.meshes[0].positions.iter_mut().for_each(|p| *p *= 8.0);
    let mut q = quality(&["caustics=splat", "caustic_estimate=kernel", "reference_photons=400000"]);
    q.frame.depth = 16;
    let tracer = specula::reference::Tracer::new(&s, &q).unwrap();
    let truth: f64 = tracer.photon_map().unwrap().photons().iter().map(|p| p.power.x).sum();
    let power = |paths: &str| {
        caustic_power(&ctx, &s, &quality(&["caustics=splat", "photons=128", "internal_bounces=4", &format!("caustic_paths={paths}")])).0
    };
    let (both, exact) = (power("both"), power("exact"));
    eprintln!(
        "prism: light tracer {truth:.4} W, both {both:.4} W ({:+.5}), exact {exact:.4} W ({:+.5})",
        both / truth - 1.0,
        exact / truth - 1.0
    );
    // Measured: both +0.01441, exact −0.00822 (its T·Rᵏ·T layers follow the partial internal
    // reflections both leaves out; what remains is the splats' rim loss).
    assert!(
        (exact / truth - 1.0).abs() < (both / truth - 1.0).abs(),
        "exact {exact} is no nearer the light tracer {truth} than both {both}"
    );
    common::assert_clean(&ctx);
}

#[test]
fn directional_and_grazing_light_keep_the_power() {
    // A directional light of irradiance E: a ray at impact parameter b enters and leaves the
    // sphere with the transmittance (1 − F)², deviated by 2(θ_i − θ_t) towards the centre;
    // those still going down land on the (wide) floor, those deviated above the horizon
    // (at grazing light, many) leave to the sky. The quadrature over b and the azimuth is
    // the expected power.
    let ctx = common::gpu();
    let e = 2.0f64;
    let r = R as f64;
    // Measured ratios 0.99033 (0°) and 1.00842 (60°): |ratio − 1| at most 1.122 × those.
    for (degrees, tolerance) in [(0.0f64, 0.0108), (60.0, 0.0094)] {
        let a = degrees.to_radians();
        let d = DVec3::new(a.sin(), -a.cos(), 0.0);
        let (u, v) = (DVec3::Z, d.cross(DVec3::Z).normalize());
        let (nb, nphi) = (2000, 360);
        let mut expected = 0.0;
        for k in 0..nb {
            let b = (k as f64 + 0.5) / nb as f64 * r;
            let sin_i = b / r;
            let cos_i = (1.0 - sin_i * sin_i).sqrt();
            let t = 1.0 - specula::optics::fresnel_dielectric(cos_i, 1.5);
            let deviation = 2.0 * (sin_i.asin() - (sin_i / 1.5).asin());
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) / nphi as f64 * std::f64::consts::TAU;
                let offset = u * phi.cos() + v * phi.sin();
                let exit = d * deviation.cos() - offset * deviation.sin();
                if exit.y < -0.05 {
                    expected += e * t * t * b * (r / nb as f64) * (std::f64::consts::TAU / nphi as f64);
                }
            }
        }
        let mut scene = sphere_over_floor(1.5);
        // A floor wide enough for every photon that goes down.
        scene.meshes[0].positions.iter_mut().for_each(|p| *p *= 8.0);
        scene.lights[0] = Light {
            name: "sun".into(),
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: d.as_vec3(),
            intensity: Vec3::splat(e as f32),
            range: None,
        };
        let (power, _) = caustic_power(&ctx, &scene, &quality(&["caustics=splat", "photons=128", "caustic_paths=refracted"]));
        eprintln!("directional at {degrees}°: {power:.4} W, quadrature {expected:.4} W, ratio {:.5}", power / expected);
        assert!((power / expected - 1.0).abs() <= tolerance, "{degrees}°: {power} vs {expected}");
    }
    common::assert_clean(&ctx);
}

#[test]
fn spot_lights_send_photons_only_where_their_cone_reaches() {
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    // A spot whose inner cone holds the sphere: the point light's caustic.
    scene.lights[0].kind = LightKind::Spot { inner_cone: 0.4, outer_cone: 0.5 };
    let refracted = quality(&["caustics=splat", "caustic_paths=refracted"]);
    let (power, _) = caustic_power(&ctx, &scene, &refracted);
    let expected = two_refraction_power(1.5);
    // Narrower than the sphere: only its cone's share, the same quadrature weighted by the
    // spot's falloff.
    scene.lights[0].kind = LightKind::Spot { inner_cone: 0.05, outer_cone: 0.1 };
    let (narrow, _) = caustic_power(&ctx, &scene, &refracted);
    let share = spot_two_refraction_power(1.5, Some((0.05, 0.1)));
    eprintln!(
        "spot: wide {power:.4} W, closed form {expected:.4} W, ratio {:.5}; narrow {narrow:.4} W, its share {share:.4} W ({:.4} of the sphere's), ratio {:.5}",
        power / expected,
        share / expected,
        narrow / share
    );
    // Measured: wide 0.99002 of the closed form (the point light's loss: at most 1.122 ×
    // 0.00998); narrow 0.99076 of its share (0.0869 of the sphere's; |ratio − 1| at most
    // 1.122 × 0.00924).
    assert!((0.9888..=1.005).contains(&(power / expected)), "{power} vs {expected}");
    assert!((narrow / share - 1.0).abs() <= 0.0103, "{narrow} vs {share}");
    // Aimed away: the light sees no generator, the plan has no caustics.
    scene.lights[0].direction = Vec3::Y;
    let p = plan(&scene, specula::methods::REFRACTOR_MAP, &quality(&["caustics=splat"]));
    assert!(p.caustics.is_none() && !p.passes.iter().any(|n| n.starts_with("caustics")), "{:?}", p.passes);
    common::assert_clean(&ctx);
}

#[test]
fn only_scenes_with_lit_generators_and_receivers_get_caustics() {
    let q = quality(&["caustics=triangles"]);
    let scene = sphere_over_floor(1.5);
    let p = plan(&scene, specula::methods::DISTANCE, &q);
    let c = p.caustics.as_ref().expect("a lit glass sphere over a floor");
    assert_eq!((c.generators.len(), c.photon_layers), (1, 2), "one view, both branches");
    assert!(c.bytes > 0 && p.map_bytes() >= c.bytes);
    // A solid refractor's photons search its refractor map, whatever its method.
    assert!(p.passes.contains(&"refractor.generate"), "{:?}", p.passes);
    let text = specula::plan::table(&p, &scene);
    assert!(text.contains("generator  glass lit by 'lamp'"), "{text}");
    let none = |s: &Scene, q: &Quality| {
        let p = plan(s, specula::methods::DISTANCE, q);
        p.caustics.is_none() && !p.passes.iter().any(|n| n.starts_with("caustics"))
    };
    assert!(none(&scene, &quality(&["caustics=off"])));
    let mut dark = scene.clone();
    dark.lights.clear();
    assert!(none(&dark, &q), "no light, no caustic");
    let mut bare = scene.clone();
    bare.meshes.retain(|m| m.name != "glass");
    assert!(none(&bare, &q), "no generator, no caustic");
    let mut all_glass = scene.clone();
    all_glass.meshes.retain(|m| m.name == "glass");
    assert!(none(&all_glass, &q), "no diffuse receiver, no caustic");
    // A light inside the generator's bounding sphere sees it through six views.
    let mut inside = scene.clone();
    inside.lights[0].position = C + Vec3::new(0.0, 0.3, 0.0);
    assert_eq!(plan(&inside, specula::methods::DISTANCE, &q).caustics.unwrap().photon_layers, 12);
}

#[test]
fn the_distance_test_stops_light_leaks() {
    // A diffuse plate between the sphere and the floor catches the caustic; the floor under
    // it, seen from low down, stays dark, unless the distance test is switched off.
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    let plate = scene.add_material(Material { name: "plate".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    scene
        .add_mesh(shapes::quad("plate", Vec3::new(-0.6, 0.3, -0.6), Vec3::new(0.0, 0.0, 1.2), Vec3::new(1.2, 0.0, 0.0), 2, plate))
        .unwrap();
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.12, 2.0), Vec3::new(0.0, 0.1, 0.0), 50f32.to_radians()));
    let off = image(&ctx, &scene, &quality(&["caustics=off"]));
    // Measured: cube space 90 leak pixels, residual 6.010 of the test-less 67.532 (0.0890);
    // light space 88 pixels, 5.502 of 49.674 (0.1108). Floors on the leak a factor 1.122
    // under; ceilings on the residual's share 1.122 over (light space: 0.12, 1.083 over).
    for (space, min_leak, max_share) in [("cube", 81, 0.0998), ("light", 79, 0.12)] {
        let space = format!("caustic_space={space}");
        let on = image(&ctx, &scene, &quality(&["caustics=triangles", &space]));
        let leaky = image(&ctx, &scene, &quality(&["caustics=triangles", "caustic_distance_test=off", &space]));
        // Where the caustic would leak: pixels the test-less render brightens by over 10 %.
        let leak: Vec<usize> = (0..64 * 64).filter(|&i| luminance(&leaky, i) > 1.1 * luminance(&off, i) + 1e-4).collect();
        let sum = |img: &specula::image::ImageData| -> f64 { leak.iter().map(|&i| luminance(img, i)).sum() };
        let (s_off, s_on, s_leak) = (sum(&off), sum(&on), sum(&leaky));
        eprintln!(
            "{space}: {} leak pixels: off {s_off:.3}, distance test {s_on:.3}, no test {s_leak:.3}, residual share {:.5}",
            leak.len(),
            (s_on - s_off).abs() / (s_leak - s_off)
        );
        assert!(leak.len() >= min_leak, "the test-less render leaks onto {} pixels", leak.len());
        // What remains is a rim one filter radius wide along the plate's edge, where the box
        // filter spreads the plate's caustic into the floor's directions.
        assert!(
            (s_on - s_off).abs() <= max_share * (s_leak - s_off),
            "{space}: with the test the floor under the plate stays dark: {s_on} vs {s_off}"
        );
    }
    common::assert_clean(&ctx);
}

/// caustic_space=texture (survey §6.2, SKALP05) leaks where cube space does not: with a plate
/// over half of the caustic, a splat on the floor beside the plate's shadow spreads over the
/// floor's texture-space neighbourhood, the floor under the plate included; cube space's
/// distance test keeps it off (the survey's claim, asserted both ways). The plate's photons
/// stay on its top: its underside, one texel of the map with its top, stays dark.
#[test]
fn texture_space_leaks_under_the_plate() {
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    let plate = scene.add_material(Material { name: "plate".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    scene.add_mesh(shapes::quad("plate", Vec3::new(0.0, 0.3, -0.6), Vec3::new(0.0, 0.0, 1.2), Vec3::new(0.6, 0.0, 0.0), 2, plate)).unwrap();
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.12, 2.0), Vec3::new(0.0, 0.1, 0.0), 50f32.to_radians()));
    let off = image(&ctx, &scene, &quality(&["caustics=off"]));
    let leaky = image(&ctx, &scene, &quality(&["caustics=splat", "caustic_distance_test=off"]));
    let ids = specula::reference::object_ids(&scene, (64, 64)).unwrap();
    // The floor in the plate's shadow: where the test-less projection lights it and the light
    // tracer does not; and the plate's underside.
    let mut r = quality(&["cube_size=128", "spp=4", "caustic_estimate=progressive"]);
    let ref_off = specula::reference::render_reference(&scene, &r, (64, 64)).unwrap();
    r.set("caustics", "triangles").unwrap();
    let truth = caustic_part(&specula::reference::render_reference(&scene, &r, (64, 64)).unwrap(), &ref_off);
    let under: Vec<usize> =
        (0..64 * 64).filter(|&i| ids[i] == 1 && luminance(&leaky, i) > 1.1 * luminance(&off, i) + 1e-4 && truth[i] < 1e-3).collect();
    let underside: Vec<usize> = (0..64 * 64).filter(|&i| ids[i] == 3).collect();
    let sum = |img: &specula::image::ImageData, px: &[usize]| -> f64 { px.iter().map(|&i| luminance(img, i) - luminance(&off, i)).sum() };
    let splat = |pairs: &[&str]| image(&ctx, &scene, &quality(&[&["caustics=splat"], pairs].concat()));
    let cube = splat(&["caustic_space=cube"]);
    let (c, l) = (sum(&cube, &under), sum(&leaky, &under));
    let truth_sum: f64 = under.iter().map(|&i| truth[i]).sum();
    eprintln!(
        "the floor in the plate's shadow ({} px, light tracer {truth_sum:.4}, no distance test {l:.4}): cube {c:.4}; the underside ({} px): cube {:.4}",
        under.len(),
        underside.len(),
        sum(&cube, &underside),
    );
    let mut leaks = Vec::new();
    for size in [64, 256, 1024] {
        let texture = splat(&["caustic_space=texture", &format!("light_map_size={size}")]);
        let (t, u) = (sum(&texture, &under), sum(&texture, &underside));
        eprintln!("  texture, light_map_size {size}: the shadow {t:.4}, the underside {u:.4}");
        assert!(u.abs() < 1e-3, "the underside takes its top's light at {size}: {u}");
        leaks.push(t);
    }
    // Measured: the shadow 0.0000 in cube space; texture space 0.2736 at 64² (the test-less
    // projection's 0.3204), 0.0000 at 256² and 1024²: the leak is the light map's texel.
    assert!(under.len() >= 40 && c.abs() < 1e-3, "cube space keeps the shadow dark: {c}");
    assert!(leaks[0] > 0.2736 / 1.122 && leaks[2].abs() < 1e-3, "texture space leaks at 64² texels, not at 1024²: {leaks:?}");

    // `specula plan` says what the light map holds: the floor's and the plate's charts.
    let text = specula::plan::table(
        &plan(&scene, specula::methods::REFRACTOR_MAP, &quality(&["caustics=splat", "caustic_space=texture"])),
        &scene,
    );
    assert!(text.contains("light map of the receivers' 2 chart(s)"), "{text}");
    // The charts follow their objects: the plate moved and turned over two frames renders as
    // a fresh renderer of the moved scene does (the light map's charts in object space).
    let q = quality(&["caustics=splat", "caustic_space=texture"]);
    let plan = |s: &Scene| specula::plan::plan_with(s, &specula::plan::Choices::all(specula::methods::REFRACTOR_MAP), &q).unwrap();
    let mut r = Renderer::new(&ctx, &scene, plan(&scene), 64, 64).unwrap();
    r.render(&ctx).unwrap();
    let mut moved = scene.clone();
    for k in 1..=2 {
        let t = 0.15 * k as f32;
        // Centred under the ball, spun about the vertical and tilted a little.
        let pose = Mat4::from_translation(Vec3::new(0.0, 0.3 + 0.05 * t, 0.0))
            * Mat4::from_rotation_y(3.0 * t)
            * Mat4::from_rotation_z(t)
            * Mat4::from_translation(Vec3::new(-0.3, -0.3, 0.0));
        moved.set_object_transform(2, pose).unwrap();
        r.update(&moved).unwrap();
        let got = r.render(&ctx).unwrap().image;
        let mut fresh = Renderer::new(&ctx, &moved, plan(&moved), 64, 64).unwrap();
        let want = fresh.render(&ctx).unwrap().image;
        fresh.destroy(&ctx);
        let (d, lit) = (0..64 * 64).fold((0f64, 0f64), |(d, l), i| {
            (d.max((luminance(&got, i) - luminance(&want, i)).abs()), l.max(luminance(&want, i) - luminance(&off, i)))
        });
        eprintln!("plate moved, frame {k}: largest difference from a fresh render {d:.2e} (its brightest caustic {lit:.3})");
        assert!(d < 1e-3 * lit.max(1.0), "frame {k}: {d} against {lit}");
    }
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

#[test]
fn nu_near_one_fills_the_shadow_with_the_light_it_blocked() {
    // ν = 1.0001: the sphere neither bends nor reflects; its shadow filled by the caustic
    // must equal the floor lit without the sphere.
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.0001);
    let mut gone = scene.clone();
    gone.meshes.iter_mut().filter(|m| m.name == "glass").for_each(|m| m.hidden = true);
    let q = quality(&["caustics=triangles", "photons=128"]);
    let lit = image(&ctx, &gone, &quality(&["caustics=off"]));
    let shadow = image(&ctx, &scene, &quality(&["caustics=off"]));
    let filled = image(&ctx, &scene, &q);
    let region: Vec<usize> = (0..64 * 64).filter(|&i| luminance(&shadow, i) < 0.5 * luminance(&lit, i)).collect();
    // Measured 344 pixels; floor a factor 1.122 under.
    assert!(region.len() >= 307, "the sphere casts a shadow of {} pixels", region.len());
    let mut ratios: Vec<f64> = region.iter().map(|&i| luminance(&filled, i) / luminance(&lit, i)).collect();
    ratios.sort_by(f64::total_cmp);
    let (median, mean) = (ratios[ratios.len() / 2], ratios.iter().sum::<f64>() / ratios.len() as f64);
    eprintln!("ν→1: {} shadow pixels, caustic/lit median {median:.5} mean {mean:.5}", ratios.len());
    // Measured: median 1.00286, mean 0.91256 (the shadow's rim, where the caustic's filter
    // spreads the light out of the shadow); |median − 1| and |mean − 1| at most 1.122 × those.
    assert!((median - 1.0).abs() <= 0.0032 && (mean - 1.0).abs() <= 0.098, "{median} {mean}");
    common::assert_clean(&ctx);
}

#[test]
fn caustics_hold_at_1_km_and_1_mm() {
    let ctx = common::gpu();
    let q = quality(&["caustics=splat", "photons=64"]);
    let (unit, _) = caustic_power(&ctx, &sphere_over_floor(1.5), &q);
    for k in [1000.0f32, 0.001] {
        // Radiant intensity scales with k² like the light's: the same power over k².
        let (power, _) = caustic_power(&ctx, &scaled_sphere_over_floor(1.5, k), &q);
        let ratio = power / (k as f64 * k as f64) / unit;
        eprintln!("scale {k}: power ratio to 1 m {ratio:.6}");
        // Measured 0.99994 (1 km), 0.99991 (1 mm): f32 rounding; the bound is
        // tests/README.md rule 2's 10⁻³.
        assert!((ratio - 1.0).abs() <= 1e-3, "scale {k}: {ratio}");
    }
    common::assert_clean(&ctx);
}

#[test]
fn the_caustic_is_seen_through_the_glass() {
    // The distance maps the refractor's camera pass searches shade their floor with the
    // caustic too (Figure 39): the sphere's pixels brighten.
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    let off = image(&ctx, &scene, &quality(&["caustics=off"]));
    let on = image(&ctx, &scene, &quality(&["caustics=triangles"]));
    // The sphere's pixels: those the refractor pass draws (their difference to a scene
    // without it is large); compare their sum.
    let mut gone = scene.clone();
    gone.meshes.iter_mut().filter(|m| m.name == "glass").for_each(|m| m.hidden = true);
    let bare = image(&ctx, &gone, &quality(&["caustics=off"]));
    let sphere: Vec<usize> = (0..64 * 64).filter(|&i| (luminance(&off, i) - luminance(&bare, i)).abs() > 0.02).collect();
    let (a, b): (f64, f64) = (sphere.iter().map(|&i| luminance(&off, i)).sum(), sphere.iter().map(|&i| luminance(&on, i)).sum());
    eprintln!("sphere pixels {}: off {a:.3}, with caustics {b:.3}, ratio {:.4}", sphere.len(), b / a);
    // Measured ratio 6.212; floor a factor 1.122 under.
    assert!(b > a * 5.53, "{b} vs {a}");
    common::assert_clean(&ctx);
}

/// The caustic's share of an image: each pixel's radiance minus the caustic-less one's.
fn caustic_part(with: &specula::image::ImageData, without: &specula::image::ImageData) -> Vec<f64> {
    (0..(with.width * with.height) as usize).map(|i| luminance(with, i) - luminance(without, i)).collect()
}

/// (centroid x, y) of a non-negative weight image.
fn centroid(w: &[f64], width: usize) -> (f64, f64) {
    let (mut sx, mut sy, mut s) = (0.0, 0.0, 0.0);
    for (i, &v) in w.iter().enumerate() {
        let v = v.max(0.0);
        sx += v * (i % width) as f64;
        sy += v * (i / width) as f64;
        s += v;
    }
    (sx / s, sy / s)
}

/// KHR_materials_dispersion in the caustic: a ball of strong dispersion (ν_d 1.5, Abbe
/// number 10) focuses blue nearer than red, so on the floor, near the focus, each channel's
/// caustic has its own size. Per channel, the RMS radius (pixels, about the channel's
/// centroid) of the caustic's part of the image: the CPU light tracer's differ between red
/// and blue; the GPU's photons (refracted through the refractor map as one channel each,
/// glsl/caustics/photons.frag) must match them channel by channel.
#[test]
fn dispersion_colours_the_caustic() {
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    let glass = scene.meshes[1].material;
    scene.materials[glass].dispersion = 2.0;
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.9, 1.2), Vec3::ZERO, 40f32.to_radians()));
    let size = (64u32, 64u32);
    let radii = |with: &specula::image::ImageData, without: &specula::image::ImageData| -> [f64; 3] {
        std::array::from_fn(|k| {
            let part: Vec<f64> = (0..64 * 64).map(|i| (with.data[4 * i + k] - without.data[4 * i + k]).max(0.0) as f64).collect();
            let (cx, cy) = centroid(&part, 64);
            let (mut m2, mut s) = (0.0, 0.0);
            for (i, &v) in part.iter().enumerate() {
                m2 += v * (((i % 64) as f64 - cx).powi(2) + ((i / 64) as f64 - cy).powi(2));
                s += v;
            }
            (m2 / s).sqrt()
        })
    };
    let mut q = quality(&["cube_size=128", "spp=4", "caustic_radius=0.03"]);
    let off = specula::reference::render_reference(&scene, &q, size).unwrap();
    q.set("caustics", "splat").unwrap();
    let truth = radii(&specula::reference::render_reference(&scene, &q, size).unwrap(), &off);
    let q = quality(&["cube_size=128", "caustics=splat", "photons=128"]);
    let gpu = radii(&image(&ctx, &scene, &q), &image(&ctx, &scene, &quality(&["cube_size=128"])));
    eprintln!("RMS radius per channel: light tracer {truth:.3?} px, GPU splats {gpu:.3?} px");
    // Measured: the light tracer's (9.727, 9.973, 10.722) px, blue / red 1.102 (without
    // dispersion the three are one); the GPU's (10.065, 10.428, 11.079) px, blue / red 1.101
    // (3.5–4.6 % wider in every channel: the splats' kernel). Bounds: blue / red above 1.06 and
    // within 0.03 of the light tracer's; each channel within 7 %.
    let (ratio, gpu_ratio) = (truth[2] / truth[0], gpu[2] / gpu[0]);
    assert!(ratio > 1.06, "dispersion shows in the light tracer: {truth:?}");
    assert!((gpu_ratio - ratio).abs() < 0.03, "blue / red: GPU {gpu_ratio:.3}, light tracer {ratio:.3}");
    for k in 0..3 {
        assert!((gpu[k] / truth[k] - 1.0).abs() < 0.07, "channel {k}: {} px against {} px", gpu[k], truth[k]);
    }
    common::assert_clean(&ctx);
}

#[test]
fn caustics_match_the_cpu_light_tracer() {
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    // Close to the caustic, beside the sphere.
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.9, 1.2), Vec3::ZERO, 40f32.to_radians()));
    let size = (64, 64);
    let base = ["cube_size=128", "spp=4"];
    let mut q = quality(&base);
    let off = specula::reference::render_reference(&scene, &q, size).unwrap();
    q.set("caustics", "triangles").unwrap();
    let exact = specula::reference::render_reference(&scene, &q, size).unwrap();
    let truth = caustic_part(&exact, &off);
    let region: Vec<usize> = (0..truth.len()).filter(|&i| truth[i] > 0.01).collect();
    // Measured 3085 pixels; floor a factor 1.122 under.
    assert!(region.len() >= 2750, "the reference has a caustic of {} pixels", region.len());
    let peak = truth.iter().cloned().fold(0.0, f64::max);
    let (cx, cy) = centroid(&truth, 64);
    let mut errors = Vec::new();
    for filter in ["splat", "triangles"] {
        for photons in [32, 64, 128] {
            let q = quality(&["cube_size=128", &format!("caustics={filter}"), &format!("photons={photons}")]);
            let gpu = image(&ctx, &scene, &q);
            let gpu_off = image(&ctx, &scene, &quality(&["cube_size=128"]));
            let part = caustic_part(&gpu, &gpu_off);
            let (gx, gy) = centroid(&part, 64);
            let mse = region.iter().map(|&i| (part[i] - truth[i]).powi(2)).sum::<f64>() / region.len() as f64;
            let psnr = 10.0 * (peak * peak / mse).log10();
            let l1: f64 = region.iter().map(|&i| (part[i] - truth[i]).abs()).sum::<f64>() / region.iter().map(|&i| truth[i]).sum::<f64>();
            eprintln!("   relative L1 {l1:.5}, region {} px", region.len());
            let shift = ((gx - cx).powi(2) + (gy - cy).powi(2)).sqrt();
            eprintln!("{filter} photons={photons}: caustic PSNR {psnr:.3} dB (peak {peak:.3}), centroid off by {shift:.3} px");
            errors.push((filter, photons, psnr, shift, l1));
        }
    }
    // Measured (lavapipe) at 32² / 64² / 128² photons against the converged reference
    // (progressive photon mapping, the default estimate since 2026-12-07; its peak 152.0
    // where the 3 cm kernel's was 90.7): relative L1 splat 0.5761 / 0.4605 / 0.4295,
    // triangles 0.4455 / 0.3870 / 0.3571; PSNR over the peak splat 36.651 / 36.661 / 36.658
    // dB, triangles 37.710 / 37.711 / 37.712 dB; the centroid off by 0.224 / 0.407 / 0.387 px
    // (splat), 1.040 / 0.632 / 0.381 px (triangles). (Against the kernel's blur: L1 splat
    // 0.3522 / 0.2343 / 0.2035, triangles 0.2031 / 0.1403 / 0.1097, PSNR 39.8 and 44.6 dB.)
    // What remains: the light cube's texels and filter blur the focus, and the paths the
    // photon pass does not follow (internal reflections, a dim halo). Per case: PSNR floors
    // 1 dB under, L1 and centroid ceilings a factor 1.122 over (centroids: over the larger
    // of this and the kernel's measurement); each step's fall in L1 at least the measured
    // one (1.2511, 1.0721 splat; 1.1511, 1.0836 triangles) over 1.122, and a fall.
    let expected: [(&str, u32, f64, f64, f64); 6] = [
        // (filter, photons, PSNR floor, L1 ceiling, centroid ceiling)
        ("splat", 32, 35.65, 0.6464, 0.296),
        ("splat", 64, 35.66, 0.5167, 0.457),
        ("splat", 128, 35.65, 0.4819, 0.435),
        ("triangles", 32, 36.71, 0.4999, 1.167),
        ("triangles", 64, 36.71, 0.435, 0.709),
        ("triangles", 128, 36.71, 0.4007, 0.428),
    ];
    for (e, &(filter, photons, psnr, l1, shift)) in errors.iter().zip(&expected) {
        assert_eq!((e.0, e.1), (filter, photons));
        assert!(e.2 > psnr && e.4 < l1 && e.3 < shift, "{filter} {photons}: {} dB, L1 {}, centroid {} px off", e.2, e.4, e.3);
    }
    for (filter, falls) in [("splat", [1.1151, 1.0]), ("triangles", [1.0259, 1.0])] {
        let e: Vec<_> = errors.iter().filter(|e| e.0 == filter).collect();
        for k in 0..2 {
            assert!(e[k].4 > falls[k] * e[k + 1].4, "{filter}: the error falls as photons grow: {e:?}");
        }
    }
    // Triangles beat splats at equal photons (survey §6.3.2): measured L1 0.4295 against
    // 0.3571 at 128², a factor 1.2027; at least that over 1.122.
    let l1 = |f: &str| errors.iter().find(|e| e.0 == f && e.1 == 128).unwrap().4;
    assert!(l1("splat") > 1.0719 * l1("triangles"), "triangles beat splats at equal photons (survey §6.3.2)");
    common::assert_clean(&ctx);
}

/// The photon map (caustics=photon-map, survey §6.1.1, PDC03): the photons sorted into a
/// hashed grid on the GPU, the irradiance gathered per shaded point from its photon_k
/// nearest. On the glass sphere's caustic at 64², against the light tracer converged by
/// progressive photon mapping (the focus resolved, not a kernel's blur), relative L1 on the
/// caustic's pixels: it falls as photons grow and as k grows from 1 to 16; the photon map
/// resolves the focus the light cube maps blur; no light cube map is allocated; the image
/// is the same bits twice (the scatter's atomics place photons in another order each time).
#[test]
fn the_photon_map_gathers_the_caustic() {
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.9, 1.2), Vec3::ZERO, 40f32.to_radians()));
    let size = (64, 64);
    let mut q = quality(&["cube_size=128", "spp=4", "caustic_estimate=progressive"]);
    let off = specula::reference::render_reference(&scene, &q, size).unwrap();
    q.set("caustics", "triangles").unwrap();
    let truth = caustic_part(&specula::reference::render_reference(&scene, &q, size).unwrap(), &off);
    let region: Vec<usize> = (0..truth.len()).filter(|&i| truth[i] > 0.01).collect();
    let peak = truth.iter().cloned().fold(0.0, f64::max);
    let gpu_off = image(&ctx, &scene, &quality(&["cube_size=128"]));
    let measure = |knobs: &[&str]| {
        let mut pairs = vec!["cube_size=128"];
        pairs.extend_from_slice(knobs);
        let part = caustic_part(&image(&ctx, &scene, &quality(&pairs)), &gpu_off);
        let l1 = region.iter().map(|&i| (part[i] - truth[i]).abs()).sum::<f64>() / region.iter().map(|&i| truth[i]).sum::<f64>();
        let top = part.iter().cloned().fold(0.0, f64::max);
        eprintln!("{knobs:?}: caustic relative L1 {l1:.4}, peak {top:.2} (the light tracer's {peak:.2})");
        (l1, top / peak)
    };
    let photons: Vec<(f64, f64)> = [64, 128, 256].iter().map(|n| measure(&["caustics=photon-map", &format!("photons={n}")])).collect();
    let ks: Vec<(f64, f64)> =
        [1, 4, 16].iter().map(|k| measure(&["caustics=photon-map", "photons=128", &format!("photon_k={k}")])).collect();
    let splat = measure(&["caustics=splat", "photons=128"]);
    let triangles = measure(&["caustics=triangles", "photons=128"]);
    // Measured L1 0.3259 / 0.3146 / 0.3147 at 64² / 128² / 256² photons (the caustic seen
    // through the glass is not gathered: the map passes hold no gather); 0.9026 / 0.5374 /
    // 0.3146 at k 1 / 4 / 16; splats 0.4295, triangles 0.3571 (the bounds: a factor 1.122 on
    // the measured ceiling and ratios). The peak: 0.948 of the light tracer's (splats 0.339,
    // triangles 0.407: the light cube's texels and its box filter blur the focus). The
    // caustic's pixels sum to 1.16 of the light tracer's at 128² photons (1.06 at 512²): the
    // resolved focus is sampled at pixel centres, where the light tracer averages 4 samples
    // over each pixel; the power itself is kept (the mirror's test below).
    assert!(photons[0].0 > photons[1].0 && photons[2].0 < 1.01 * photons[1].0, "the error falls as photons grow: {photons:?}");
    assert!(ks[0].0 > 1.5 * ks[1].0 && ks[1].0 > 1.2 * ks[2].0, "the error falls as k grows to 16: {ks:?}");
    assert!(photons[2].0 < 0.3455 && splat.0 > 1.2 * ks[2].0, "photon map {photons:?}, splats {splat:?}");
    assert!((0.85..1.15).contains(&ks[2].1) && splat.1 < 0.5 && triangles.1 < 0.5, "the focus: {ks:?} {splat:?} {triangles:?}");

    // No light cube maps; the pass that builds the grid; the same bits twice.
    let pm = quality(&["cube_size=128", "caustics=photon-map", "photons=128"]);
    let p = plan(&scene, specula::methods::REFRACTOR_MAP, &pm);
    let mut r = Renderer::new(&ctx, &scene, p, 64, 64).unwrap();
    let a = r.render(&ctx).unwrap();
    let b = r.render(&ctx).unwrap();
    assert!(a.passes.iter().any(|p| p.name == "caustics.photon_map"), "{:?}", a.passes.iter().map(|p| &p.name).collect::<Vec<_>>());
    use specula::methods::caustics::slots::{CAUSTIC_MAPS, PHOTON_GRID, PHOTON_LIST};
    assert!(r.maps().image(&CAUSTIC_MAPS).is_none() && r.maps().buffer(&PHOTON_GRID).is_some() && r.maps().buffer(&PHOTON_LIST).is_some());
    assert!(a.image.data == b.image.data, "the photon map's image differs between two frames");
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// The photon map keeps the power the mirror panel throws (`mirror_panel`'s quadrature),
/// measured in world space: the floor seen straight from above through a narrow lens (a
/// plane parallel to the image: every pixel covers the same area), the caustic's
/// irradiance E = π ΔL / ρ over every pixel times its area.
#[test]
fn the_photon_map_keeps_the_mirrors_power() {
    let ctx = common::gpu();
    let (mut s, expected) = mirror_panel();
    let (h, fov, n) = (200.0f32, 8f32, 128u32);
    s.camera = Some(Camera::look_at(Vec3::new(10.5, h, 0.001), Vec3::new(10.5, 0.0, 0.0), fov.to_radians()));
    let area = (2.0 * (fov.to_radians() as f64 / 2.0).tan() * h as f64 / n as f64).powi(2);
    let render = |knobs: &[&str]| {
        let mut pairs = vec!["cube_size=128", "fresnel=exact", "photons=128"];
        pairs.extend_from_slice(knobs);
        specula::render(&ctx, &s, specula::methods::DISTANCE, &quality(&pairs), (n, n), (0, 1)).unwrap().image
    };
    let off = render(&[]);
    // Measured ratios 0.97261 (the photon map: kernels that reach past the floor's far edge
    // lose their share there) and 1.00323 (splats, the same measure as the light cube's power
    // above): at most 1.122 × the photon map's loss; splats within the light cube's bounds.
    for (knobs, lo, hi) in [(&["caustics=photon-map"][..], 0.9693, 1.03), (&["caustics=splat"][..], 0.97, 1.08)] {
        let on = render(knobs);
        let sum: f64 = (0..(n * n) as usize).map(|i| luminance(&on, i) - luminance(&off, i)).sum();
        let power = sum * std::f64::consts::PI / 0.8 * area;
        eprintln!("{knobs:?}: the floor receives {power:.4} W, quadrature {expected:.4} W, ratio {:.5}", power / expected);
        assert!((lo..=hi).contains(&(power / expected)), "{knobs:?}: {power} W against {expected} W");
    }
    common::assert_clean(&ctx);
}

/// The bottom of a sphere (centre `c`, radius `r`) below the plane y = c.y − 0.6 r: a
/// concave mirror bowl, open upwards.
fn bowl(c: Vec3, r: f32, material: usize) -> specula::scene::Mesh {
    let s = shapes::uv_sphere("bowl", c, r, 64, 32, material);
    let mut m = specula::scene::Mesh { name: "bowl".into(), material, ..Default::default() };
    let keep = |i: u32| s.positions[i as usize].y < c.y - 0.6 * r;
    let mut remap = vec![u32::MAX; s.positions.len()];
    for t in s.indices.chunks(3) {
        if !t.iter().all(|&i| keep(i)) {
            continue;
        }
        for &i in t {
            if remap[i as usize] == u32::MAX {
                remap[i as usize] = m.positions.len() as u32;
                m.positions.push(s.positions[i as usize]);
                m.normals.push(s.normals[i as usize]);
                m.uvs.push(s.uvs[i as usize]);
            }
            m.indices.push(remap[i as usize]);
        }
    }
    m
}

#[test]
fn a_concave_mirror_focuses_a_point_light() {
    // An ideal mirror bowl (κ = 10⁴: F ≈ 1) under a point light on its axis, a ceiling above:
    // every photon the bowl catches reaches the ceiling, I·Ω of the bowl's rim seen from the
    // light (single reflections; a second one inside the bowl is not followed).
    let ctx = common::gpu();
    let mut s = Scene::new();
    let white = s.add_material(Material { name: "white".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    let mirror = s
        .add_material(Material {
            name: "ideal mirror".into(),
            kind: SurfaceKind::Mirror { nu: Vec3::ONE, kappa: Vec3::splat(1e4) },
            ..Default::default()
        })
        .unwrap();
    let (c, r) = (Vec3::new(0.0, 1.0, 0.0), 1.0);
    let b = bowl(c, r, mirror);
    // The rim: the highest ring of vertices the bowl kept.
    let top = b.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    let rho = b.positions.iter().filter(|p| p.y > top - 1e-4).map(|p| p.x.hypot(p.z)).fold(0.0f32, f32::max) as f64;
    s.add_mesh(b).unwrap();
    s.add_mesh(shapes::quad("ceiling", Vec3::new(-20.0, 4.0, -20.0), Vec3::new(0.0, 0.0, 40.0), Vec3::new(40.0, 0.0, 0.0), 4, white))
        .unwrap();
    // At the paraxial focus (r/2 above the bottom): the reflected beam goes up, nearly
    // parallel; the light lies inside the bowl's bounding sphere (six photon views).
    let light_y = 0.5f32;
    s.add_light(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position: Vec3::new(0.0, light_y, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(INTENSITY),
        range: None,
    })
    .unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 0.5, 3.0), Vec3::new(0.0, 2.0, 0.0), 60f32.to_radians()));
    let h = (light_y - top) as f64;
    let expected = INTENSITY as f64 * std::f64::consts::TAU * (1.0 - h / (h * h + rho * rho).sqrt());
    let p = plan(&s, specula::methods::DISTANCE, &quality(&["caustics=triangles", "photons=128"]));
    assert_eq!(p.caustics.as_ref().map(|c| c.photon_layers), Some(6), "a mirror has one branch, seen in six views");
    let (power, _) = caustic_power(&ctx, &s, &quality(&["caustics=splat", "photons=128"]));
    eprintln!("mirror bowl: {power:.4} W, I·Ω(rim) {expected:.4} W, ratio {:.5}", power / expected);
    // Measured ratio 0.99663: |ratio − 1| at most 1.122 × 0.00337.
    assert!((power / expected - 1.0).abs() <= 0.0037, "{power} vs {expected}");
    common::assert_clean(&ctx);
}

#[test]
fn a_light_inside_the_generators_bounds_sees_it_through_six_views() {
    // A wide thin glass pane just under a point light (inside the pane's bounding sphere):
    // six photon views; the floor below gets the light the pane lets through, 1 − F(0) of
    // the unshadowed irradiance straight under the light.
    let ctx = common::gpu();
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    let pane = s
        .add_material(Material { name: "pane".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: true }, ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, 0.0, -3.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 6.0), 8, floor)).unwrap();
    s.add_mesh(shapes::quad("pane", Vec3::new(-2.0, 1.0, -2.0), Vec3::new(0.0, 0.0, 4.0), Vec3::new(4.0, 0.0, 0.0), 4, pane)).unwrap();
    s.add_light(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position: Vec3::new(0.0, 1.3, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(INTENSITY),
        range: None,
    })
    .unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 0.6, 1.5), Vec3::ZERO, 40f32.to_radians()));
    let q = quality(&["caustics=triangles", "photons=128", "caustic_paths=refracted", "cube_size=128"]);
    let p = plan(&s, specula::methods::DISTANCE, &q);
    assert_eq!(p.caustics.as_ref().unwrap().photon_layers, 6);
    let through = specula::render(&ctx, &s, specula::methods::DISTANCE, &q, (64, 64), (0, 1)).unwrap().image;
    s.meshes[1].hidden = true;
    let open = specula::render(&ctx, &s, specula::methods::DISTANCE, &quality(&["caustics=off"]), (64, 64), (0, 1)).unwrap().image;
    // The floor around the point under the light (the image's centre): the mean over a
    // patch, since caustic triangles as large as a texel alias into a pattern of ±30 % at
    // this resolution (the filter's business) while keeping their flux.
    let patch: Vec<usize> = (24..40).flat_map(|y| (24..40).map(move |x| y * 64 + x)).collect();
    let ratio = patch.iter().map(|&i| luminance(&through, i)).sum::<f64>() / patch.iter().map(|&i| luminance(&open, i)).sum::<f64>();
    let f0 = specula::optics::fresnel_dielectric(1.0, 1.5);
    eprintln!("pane: floor through / open {ratio:.5}, 1 − F(0) = {:.5}, off by {:.5}", 1.0 - f0, (ratio - (1.0 - f0)).abs());
    // Measured 0.95640 against 0.96000: off by at most 1.122 × 0.00360.
    assert!((ratio - (1.0 - f0)).abs() < 0.0040, "{ratio}");
    common::assert_clean(&ctx);
}

#[test]
fn every_method_shows_the_caustic() {
    // The caustic is an effect of the frame, not of the generator's method: the ray tracers'
    // shading kernels project it like the rasterised passes.
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.9, 1.2), Vec3::ZERO, 40f32.to_radians()));
    let mut q = quality(&["spp=4"]);
    let off = specula::reference::render_reference(&scene, &q, (48, 48)).unwrap();
    q.set("caustics", "triangles").unwrap();
    let exact = specula::reference::render_reference(&scene, &q, (48, 48)).unwrap();
    let truth = caustic_part(&exact, &off);
    let region: Vec<usize> = (0..truth.len()).filter(|&i| truth[i] > 0.01).collect();
    // Against the converged reference (progressive photon mapping, 4 samples a pixel: one
    // sample a pixel aliases the focus), measured relative L1: envmap 0.42540, distance,
    // refractor-map, bvh and ray-engine 0.41798 (against the 3 cm kernel's blur they were
    // 0.142 and 0.134: the light cube's texels and filter blur the focus); ceilings a factor
    // 1.122 over.
    for (m, ceiling) in [
        (specula::methods::ENVMAP, 0.4773),
        (specula::methods::DISTANCE, 0.4690),
        (specula::methods::REFRACTOR_MAP, 0.4690),
        (specula::methods::BVH, 0.4690),
        (specula::methods::RAY_ENGINE, 0.4690),
    ] {
        let render = |c: &str| {
            let q = quality(&["cube_size=128", &format!("caustics={c}")]);
            let p = plan(&scene, m, &q);
            assert_eq!(p.caustics.is_some(), c != "off", "{}: {:?}", m.name, p.passes);
            specula::render_plan(&ctx, &scene, p, (48, 48), (0, 1)).unwrap().image
        };
        let part = caustic_part(&render("triangles"), &render("off"));
        let l1 = region.iter().map(|&i| (part[i] - truth[i]).abs()).sum::<f64>() / region.iter().map(|&i| truth[i]).sum::<f64>();
        eprintln!("{}: caustic relative L1 {l1:.5}", m.name);
        assert!(l1 < ceiling, "{}: {l1}", m.name);
    }
    common::assert_clean(&ctx);
}

/// A layered map (§4.5) is one map of the scene around one point shared by its objects;
/// their caustics must not move with it. With a mirror sphere beside the glass the shared
/// point lies between the two, where the receiver map had the glass in front of its own
/// caustic: the photons through it landed on the wrong side of the floor (the demo's glass
/// caustic, seen in its 512² run). Each generator's light cube stays around its own
/// reference point, so the caustic on the floor is the distance-mapped plan's.
#[test]
fn a_shared_layered_map_keeps_each_generators_caustic() {
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    let mirror = scene.add_material(common::mirror(0.9)).unwrap();
    scene.add_mesh(shapes::uv_sphere("mirror", Vec3::new(-1.6, 0.4, -1.0), 0.3, 32, 16, mirror)).unwrap();
    let size = (48, 48);
    let ids = specula::reference::object_ids(&scene, size).unwrap();
    let shared = plan(&scene, specula::methods::LAYERED, &quality(&[])).objects[0].reference_point;
    assert!((shared - C).length() > 1.5 * R, "the shared point {shared} lies outside the glass");
    let part = |m| {
        let render = |c: &str| {
            let q = quality(&["cube_size=128", &format!("caustics={c}")]);
            specula::render_plan(&ctx, &scene, plan(&scene, m, &q), size, (0, 1)).unwrap().image
        };
        caustic_part(&render("triangles"), &render("off"))
    };
    let (distance, layered) = (part(specula::methods::DISTANCE), part(specula::methods::LAYERED));
    // The floor's pixels (mesh 0): the spheres' own pixels show the caustic through each
    // method's own refraction and reflection.
    let floor: Vec<usize> = (0..ids.len()).filter(|&i| ids[i] == 1).collect();
    let total: f64 = floor.iter().map(|&i| distance[i]).sum();
    let l1 = floor.iter().map(|&i| (layered[i] - distance[i]).abs()).sum::<f64>() / total;
    eprintln!("floor caustic: {total:.3} with distance maps, layered off by {l1:.3e} (relative L1)");
    // Measured 0 (the same photons, cubes and receiver maps: the same bits); 1.0 with the
    // light cube around the shared point. Bound 1e-3.
    assert!(total > 1.0, "the floor has a caustic: {total}");
    assert!(l1 <= 1e-3, "layered's floor caustic differs from distance maps' by {l1:.3e}");
    common::assert_clean(&ctx);
}

#[test]
fn multiview_and_six_passes_make_the_same_caustic() {
    // The caustics stage renders its cubes in six passes whatever cube_mode says: lavapipe's
    // multiview scatters this scene's floor triangles over the wrong cube faces (measured:
    // with caustics off too, every cube-mapped method's image differs from six passes by up
    // to 90 % here, see ../shared/LAVAPIPE-NOTES.md). The caustic is the same in both modes.
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    for filter in ["splat", "triangles"] {
        let six = quality(&[&format!("caustics={filter}"), "cube_mode=six"]);
        let multi = quality(&[&format!("caustics={filter}"), "cube_mode=multiview"]);
        let (a, b) = (caustic_power(&ctx, &scene, &six).0, caustic_power(&ctx, &scene, &multi).0);
        eprintln!("{filter}: power six {a:.5} multiview {b:.5}, relative difference {:e}", (a - b).abs() / a);
        // Measured: the same power (relative difference 0).
        assert!((a - b).abs() <= 1e-6 * a, "{filter}: {a} vs {b}");
    }
    common::assert_clean(&ctx);
}

/// A glass box of half-size `half` around `c`, turned `angle` about z: merged quads.
fn glass_box(c: Vec3, half: f32, angle: f32, material: usize) -> specula::scene::Mesh {
    let rot = glam::Quat::from_rotation_z(angle);
    let mut m = specula::scene::Mesh { name: "prism".into(), material, ..Default::default() };
    let h = half;
    // (origin, u, v) of each face, u × v outwards.
    let faces = [
        (Vec3::new(h, -h, -h), Vec3::new(0.0, 2.0 * h, 0.0), Vec3::new(0.0, 0.0, 2.0 * h)),
        (Vec3::new(-h, -h, -h), Vec3::new(0.0, 0.0, 2.0 * h), Vec3::new(0.0, 2.0 * h, 0.0)),
        (Vec3::new(-h, h, -h), Vec3::new(0.0, 0.0, 2.0 * h), Vec3::new(2.0 * h, 0.0, 0.0)),
        (Vec3::new(-h, -h, -h), Vec3::new(2.0 * h, 0.0, 0.0), Vec3::new(0.0, 0.0, 2.0 * h)),
        (Vec3::new(-h, -h, h), Vec3::new(2.0 * h, 0.0, 0.0), Vec3::new(0.0, 2.0 * h, 0.0)),
        (Vec3::new(-h, -h, -h), Vec3::new(0.0, 2.0 * h, 0.0), Vec3::new(2.0 * h, 0.0, 0.0)),
    ];
    for (o, u, v) in faces {
        let q = shapes::quad("face", o, u, v, 4, material);
        let base = m.positions.len() as u32;
        m.positions.extend(q.positions.iter().map(|p| c + rot * *p));
        m.normals.extend(q.normals.iter().map(|n| rot * *n));
        m.uvs.extend(q.uvs.iter().copied());
        m.indices.extend(q.indices.iter().map(|i| base + i));
    }
    m
}

#[test]
fn total_internal_reflection_paths_reach_the_floor() {
    // A glass cube turned 45° about z under a point light: photons entering a slanted upper
    // face reach the opposite lower face beyond the critical angle and are totally
    // reflected before they leave. Without internal bounces they are lost; with them the
    // caustic's power approaches the CPU light tracer's (which also has the partial internal
    // reflections the photon pass does not follow).
    let ctx = common::gpu();
    let mut s = sphere_over_floor(1.5);
    let glass = s.meshes[1].material;
    s.meshes[1] = glass_box(C, 0.35, std::f32::consts::FRAC_PI_4, glass);
    s.meshes[0].positions.iter_mut().for_each(|p| *p *= 8.0);
    let power =
        |bounces: &str| caustic_power(&ctx, &s, &quality(&["caustics=splat", "photons=128", &format!("internal_bounces={bounces}")])).0;
    let (none, some) = (power("0"), power("4"));
    let mut q = quality(&["caustics=splat", "caustic_estimate=kernel", "reference_photons=400000"]);
    q.frame.depth = 16;
    let tracer = specula::reference::Tracer::new(&s, &q).unwrap();
    let exact: f64 = tracer.photon_map().unwrap().photons().iter().map(|p| p.power.x).sum();
    eprintln!(
        "prism: internal_bounces=0 {none:.4} W, 4: {some:.4} W, light tracer {exact:.4} W; with / without {:.4}, with / tracer {:.5}",
        some / none,
        some / exact
    );
    // Measured: 0.7432 W without bounces, 1.0074 W with (a factor 1.3556; at least that
    // over 1.122), the light tracer 0.9931 W (ratio 1.01441: |ratio − 1| at most 1.122 ×
    // 0.01441).
    assert!(some > 1.208 * none, "TIR paths carry power: {some} vs {none}");
    assert!((some / exact - 1.0).abs() <= 0.0161, "{some} vs {exact}");
    common::assert_clean(&ctx);
}

#[test]
fn the_caustic_is_seen_in_a_planar_mirror() {
    // A planar mirror behind the sphere (survey §5, planar-mirror for it, auto for the
    // glass): its mirrored view shades the floor with the caustic too (Figure 40).
    let ctx = common::gpu();
    let mut s = sphere_over_floor(1.5);
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::quad("mirror", Vec3::new(-1.5, 0.0, -1.2), Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0), 1, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 0.6, 3.0), Vec3::new(0.0, 0.4, -1.2), 50f32.to_radians()));
    let choices =
        specula::plan::Choices { method: specula::Choice::Auto, objects: vec![("mirror".into(), specula::methods::PLANAR_MIRROR)] };
    let render = |s: &Scene, c: &str| {
        let knobs: Vec<String> = c.split(' ').map(|k| format!("caustics={k}").replace("caustics=caustic_", "caustic_")).collect();
        let q = quality(&knobs.iter().map(|k| k.as_str()).collect::<Vec<_>>());
        specula::render_plan(&ctx, s, specula::plan::plan_with(s, &choices, &q).unwrap(), (64, 64), (0, 1)).unwrap()
    };
    let p = specula::plan::plan_with(&s, &choices, &quality(&["caustics=triangles"])).unwrap();
    assert_eq!(p.object(2).map(|o| o.method.name), Some("planar-mirror"), "{:?}", p.objects);
    let (off, on) = (render(&s, "off").image, render(&s, "triangles").image);
    // Screen space (LC04, WD06b) splats onto the camera's own view only: the mirror shows none.
    let screen = render(&s, "splat caustic_space=screen").image;
    let mut gone = s.clone();
    gone.meshes[2].hidden = true;
    let bare = render(&gone, "off").image;
    let seen: Vec<usize> = (0..64 * 64).filter(|&i| (luminance(&off, i) - luminance(&bare, i)).abs() > 1e-3).collect();
    let (a, b): (f64, f64) = (seen.iter().map(|&i| luminance(&off, i)).sum(), seen.iter().map(|&i| luminance(&on, i)).sum());
    eprintln!("mirror pixels {}: off {a:.3}, with caustics {b:.3}, ratio {:.4}", seen.len(), b / a);
    let c: f64 = seen.iter().map(|&i| luminance(&screen, i)).sum();
    eprintln!("screen space: the mirror's pixels {c:.3}, ratio {:.4}", c / a);
    // Texture space (SKALP05): the mirrored view reads the floor's light map as the camera does.
    let texture = render(&s, "splat caustic_space=texture").image;
    let t: f64 = seen.iter().map(|&i| luminance(&texture, i)).sum();
    eprintln!("texture space: the mirror's pixels {t:.3}, ratio {:.4}", t / a);
    // Measured 370 pixels, ratio 1.5639 (this comment said 388 and 1.3726, from an earlier
    // version of the caustic stage); floors a factor 1.122 under. Screen space: 1.0024.
    assert!(seen.len() >= 330 && b > a * 1.394, "{} pixels: {b} vs {a}", seen.len());
    assert!((c / a - 1.0).abs() < 0.01, "screen space: the mirror shows no caustic: {c} vs {a}");
    // Measured 1.5985: the mirrored view reads the light map.
    assert!(t > a * 1.4247, "texture space: the mirror shows the caustic: {t} vs {a}");
    common::assert_clean(&ctx);
}

/// caustic_space=screen (survey §6.2, LC04/WD06b): the photons splatted straight onto the
/// camera's image of the receivers. What the camera sees directly takes the caustic as cube
/// space gives it; the caustic seen through the glass and in a planar mirror is missing
/// (the survey's claim, asserted); and photons on a thin plate's top light its underside
/// seen from below (the depth test knows one depth a pixel: the survey's light leak).
#[test]
fn screen_space_caustics_show_only_what_the_camera_sees() {
    let ctx = common::gpu();
    // Splats stored in cube, light or screen space; the photon map (world space) beside them.
    let splat = |space: &str| match space {
        "photon-map" => quality(&["cube_size=128", "caustics=photon-map", "photons=128"]),
        _ => quality(&["cube_size=128", "caustics=splat", "photons=128", &format!("caustic_space={space}")]),
    };
    const SPACES: [&str; 5] = ["cube", "light", "screen", "photon-map", "texture"];
    // Directly seen: the floor around the sphere from the close camera, against the light
    // tracer, on the caustic's pixels the sphere does not cover.
    let mut scene = sphere_over_floor(1.5);
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.9, 1.2), Vec3::ZERO, 40f32.to_radians()));
    let mut r = quality(&["cube_size=128", "spp=4", "caustic_estimate=progressive"]);
    let ref_off = specula::reference::render_reference(&scene, &r, (64, 64)).unwrap();
    r.set("caustics", "triangles").unwrap();
    let truth = caustic_part(&specula::reference::render_reference(&scene, &r, (64, 64)).unwrap(), &ref_off);
    let off = image(&ctx, &scene, &quality(&["cube_size=128"]));
    // The pixels of the floor (mesh 0) and of the glass (mesh 1).
    let ids = specula::reference::object_ids(&scene, (64, 64)).unwrap();
    let floor: Vec<usize> = (0..truth.len()).filter(|&i| truth[i] > 0.01 && ids[i] == 1).collect();
    let through: Vec<usize> = (0..64 * 64).filter(|&i| ids[i] == 2 && truth[i] > 0.01).collect();
    let mut l1 = Vec::new();
    let mut seen = Vec::new();
    for space in SPACES {
        let img = image(&ctx, &scene, &splat(space));
        let part = caustic_part(&img, &off);
        let e = floor.iter().map(|&i| (part[i] - truth[i]).abs()).sum::<f64>() / floor.iter().map(|&i| truth[i]).sum::<f64>();
        let g = through.iter().map(|&i| luminance(&img, i)).sum::<f64>() / through.iter().map(|&i| luminance(&off, i)).sum::<f64>();
        eprintln!(
            "{space} space: the floor's caustic L1 {e:.4} ({} px); the sphere's {} pixels that show it brighten {g:.4}×",
            floor.len(),
            through.len()
        );
        l1.push(e);
        seen.push(g);
    }
    // Exact photons (ray queries) name their receiver triangle by their hit, not through the
    // receiver cube: the same light map.
    let exact = caustic_part(
        &image(&ctx, &scene, &quality(&["cube_size=128", "caustics=splat", "photons=128", "caustic_space=texture", "caustic_paths=exact"])),
        &off,
    );
    let exact_l1 = floor.iter().map(|&i| (exact[i] - truth[i]).abs()).sum::<f64>() / floor.iter().map(|&i| truth[i]).sum::<f64>();
    eprintln!("texture space, exact photons: the floor's caustic L1 {exact_l1:.4}");
    // Measured 0.3007 (the sampled photons' 0.3008): a ceiling 1.122 over.
    assert!(exact_l1 < 1.122 * 0.3007, "texture space with exact photons: {exact_l1}");
    // The ray tracers' diffuse hits read the light map too: through the glass with bvh.
    let traced = |q: &Quality| specula::render(&ctx, &scene, specula::methods::BVH, q, (64, 64), (0, 1)).unwrap().image;
    let (bvh_off, bvh_texture) = (traced(&quality(&["cube_size=128"])), traced(&splat("texture")));
    let bvh_seen =
        through.iter().map(|&i| luminance(&bvh_texture, i)).sum::<f64>() / through.iter().map(|&i| luminance(&bvh_off, i)).sum::<f64>();
    eprintln!("texture space through the glass, traced by bvh: {bvh_seen:.4}×");
    // Measured L1 0.4242 (cube) and 0.4261 (screen: the same splats, across the view); the
    // glass's pixels that show the caustic 32.28× brighter in cube space, 1.0000× in screen
    // space. Bounds: screen within 1.122 × cube's L1; cube's gain at least 32.28 / 1.122.
    assert!(l1[2] < 1.122 * l1[0], "screen space on what the camera sees: {l1:?}");
    assert!(seen[0] > 28.77 && (seen[2] - 1.0).abs() < 1e-3, "through the glass: {seen:?}");
    // Texture space (SKALP05): L1 0.3008, the best of the splats (each photon's splat on its
    // own surface); through the glass 36.31× (the distance map's pass reads the light map at
    // its triangles, as every map pass does), and by the ray tracers' diffuse hits (bvh:
    // 42.83×).
    assert!(l1[4] < 1.122 * 0.3008 && seen[4] > 36.31 / 1.122 && bvh_seen > 42.83 / 1.122, "texture space: {l1:?} {seen:?} {bvh_seen}");
    let refused = specula::render(
        &ctx,
        &scene,
        specula::methods::REFRACTOR_MAP,
        &quality(&["caustics=triangles", "caustic_space=texture"]),
        (64, 64),
        (0, 1),
    );
    let e = refused.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("caustic_space") && e.contains("caustics=splat"), "texture space with caustic triangles: {e}");

    // The leak: the plate of the_distance_test_stops_light_leaks catches the caustic on its
    // top; seen from below, its underside (one depth with its top) takes the splats in screen
    // space, none in cube space (the projection lights no face turned from the generator).
    let mut plated = sphere_over_floor(1.5);
    let plate = plated.add_material(Material { name: "plate".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    plated
        .add_mesh(shapes::quad("plate", Vec3::new(-0.6, 0.3, -0.6), Vec3::new(0.0, 0.0, 1.2), Vec3::new(1.2, 0.0, 0.0), 2, plate))
        .unwrap();
    plated.camera = Some(Camera::look_at(Vec3::new(0.0, 0.12, 2.0), Vec3::new(0.0, 0.1, 0.0), 50f32.to_radians()));
    let ids = specula::reference::object_ids(&plated, (64, 64)).unwrap();
    let under: Vec<usize> = (0..64 * 64).filter(|&i| ids[i] == 3).collect();
    let sum = |img: &specula::image::ImageData| -> f64 { under.iter().map(|&i| luminance(img, i)).sum() };
    let dark = sum(&image(&ctx, &plated, &quality(&["cube_size=128"])));
    let leaks: Vec<f64> = SPACES.iter().map(|s| sum(&image(&ctx, &plated, &splat(s))) - dark).collect();
    eprintln!("the plate's underside ({} px, {dark:.4} unlit) with the caustic on its top, per {SPACES:?}: {leaks:.4?}", under.len());
    // Measured +22.48 in screen space, 0 elsewhere (texture space keeps the two sides apart
    // by the photons' arrival side): screen space at least 22.48 / 1.122.
    assert!(under.len() > 100 && leaks[0].abs() < 1e-3 && leaks[2] > 20.0 && leaks[4].abs() < 1e-3, "the leak: {leaks:?}");
    common::assert_clean(&ctx);
}

#[test]
fn light_space_caustics_keep_the_power_and_compare_with_cube_space() {
    // caustic_space=light (SP07's light-space storage): one cube per generator and point
    // light, centred at the light. The same power reaches the receivers; against the light
    // tracer both spaces are measured, and so is the leak under the plate.
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    let expected = two_refraction_power(1.5);
    let q = quality(&["caustics=splat", "photons=128", "caustic_paths=refracted", "caustic_space=light"]);
    let p = plan(&scene, specula::methods::REFRACTOR_MAP, &q);
    let c = p.caustics.as_ref().unwrap();
    assert_eq!((c.cubes.len(), c.cubes[0].light), (1, Some(0)));
    let (power, _) = caustic_power(&ctx, &scene, &q);
    // Measured 0.93: the photons leave the generator 2.5 m from the cube's centre (the light),
    // where the linear search's probes are as far apart; a ray grazing out over the floor's
    // edge between two probes reads the sky beyond it and escapes (cube space: 0.99).
    eprintln!("light space: {power:.4} W, closed form {expected:.4} W, ratio {:.5}", power / expected);
    // Measured ratio 0.92853: the loss 1 − ratio at most 1.122 × 0.07147.
    assert!((0.9199..=1.005).contains(&(power / expected)), "{power}");

    let mut close = scene.clone();
    close.camera = Some(Camera::look_at(Vec3::new(0.0, 0.9, 1.2), Vec3::ZERO, 40f32.to_radians()));
    let mut r = quality(&["spp=4"]);
    let off = specula::reference::render_reference(&close, &r, (64, 64)).unwrap();
    r.set("caustics", "triangles").unwrap();
    let truth = caustic_part(&specula::reference::render_reference(&close, &r, (64, 64)).unwrap(), &off);
    let region: Vec<usize> = (0..truth.len()).filter(|&i| truth[i] > 0.01).collect();
    let gpu_off = image(&ctx, &close, &quality(&["cube_size=128"]));
    let mut l1s = Vec::new();
    for space in ["cube", "light"] {
        let gpu = image(&ctx, &close, &quality(&["cube_size=128", "caustics=triangles", "photons=128", &format!("caustic_space={space}")]));
        let part = caustic_part(&gpu, &gpu_off);
        let l1 = region.iter().map(|&i| (part[i] - truth[i]).abs()).sum::<f64>() / region.iter().map(|&i| truth[i]).sum::<f64>();
        eprintln!("{space} space: caustic relative L1 {l1:.5}");
        l1s.push(l1);
    }
    // Measured against the converged reference 0.3571 (cube) and 0.7953 (light; against the
    // kernel's blur 0.1098 and 0.7452): from the light, 3 m above, the focus under the sphere
    // covers a few texels of its cube and smears over them, and the search misses the photons
    // that graze out far (above); from the sphere's centre it is resolved better. Ceilings a
    // factor 1.122 over; light space at least 2.227 / 1.122 times cube space.
    assert!(l1s[0] < 0.4007 && l1s[1] < 0.8924 && l1s[1] > 1.985 * l1s[0], "{l1s:?}");
    common::assert_clean(&ctx);
}

#[test]
fn caustic_buffers_beyond_the_storage_buffer_range_are_refused_by_name() {
    // Caustic triangles live in one storage buffer of 64 bytes each: a photon image whose
    // triangles exceed the device's maxStorageBufferRange (lavapipe: 128 MiB, 1024² photons
    // for one layer) is refused naming the knob, before anything is allocated for it.
    // (caustic_paths=both: a glass sphere's two photon layers.)
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    // The photon map keeps 32 bytes a photon likewise (2048² photons in two layers: 256 MiB).
    let limit = ctx.properties.limits.max_storage_buffer_range as u64;
    for (filter, need) in [("triangles", 2u64 * 2 * 2047 * 2047 * 64), ("photon-map", 2u64 * 2048 * 2048 * 32)] {
        let q = quality(&[&format!("caustics={filter}"), "photons=2048"]);
        let r = Renderer::new(&ctx, &scene, plan(&scene, specula::methods::REFRACTOR_MAP, &q), 16, 16);
        match r {
            Err(e) => {
                let msg = e.to_string();
                assert!(need > limit && msg.contains("knob photons") && msg.contains("caustics=splat"), "{filter}: {msg}");
            }
            Ok(mut r) => {
                assert!(need <= limit, "{filter}: {need} bytes accepted beyond the range {limit}");
                r.destroy(&ctx);
            }
        }
    }
    common::assert_clean(&ctx);
}

#[test]
fn the_receiver_orientation_factor_matches_the_light_tracer() {
    // E = J cos α / D²: a directional light at 60° puts the caustic on the floor 1.7 m from
    // the sphere, where the floor is seen from the sphere's centre at about 60°. Without
    // cos α (caustic_orientation=off) it is about twice too bright; with it, it matches the
    // light tracer.
    let ctx = common::gpu();
    let mut scene = sphere_over_floor(1.5);
    scene.meshes[0].positions.iter_mut().for_each(|p| *p *= 8.0);
    let a = 60f32.to_radians();
    scene.lights[0] = Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        position: Vec3::ZERO,
        direction: Vec3::new(a.sin(), -a.cos(), 0.0),
        intensity: Vec3::splat(2.0),
        range: None,
    };
    scene.camera = Some(Camera::look_at(Vec3::new(1.7, 1.2, 1.6), Vec3::new(1.7, 0.0, 0.0), 50f32.to_radians()));
    let mut r = quality(&["spp=1", "caustic_radius=0.03"]);
    let off = specula::reference::render_reference(&scene, &r, (48, 48)).unwrap();
    r.set("caustics", "triangles").unwrap();
    let truth = caustic_part(&specula::reference::render_reference(&scene, &r, (48, 48)).unwrap(), &off);
    let base = image48(&ctx, &scene, &["cube_size=128"]);
    let sum = |o: &str| -> f64 {
        caustic_part(&image48(&ctx, &scene, &["cube_size=128", "caustics=triangles", &format!("caustic_orientation={o}")]), &base)
            .iter()
            .sum()
    };
    let (exact, on, no) = (truth.iter().sum::<f64>(), sum("on"), sum("off"));
    eprintln!(
        "caustic in view: light tracer {exact:.3}, orientation on {on:.3}, off {no:.3}; on / tracer {:.5}, off / on {:.4}",
        on / exact,
        no / on
    );
    // Measured: the light tracer's caustic sums to 76.688 (floor a factor 1.122 under); on /
    // tracer 0.97510 (|ratio − 1| at most 1.122 × 0.0249); off / on 1.8580 (at least that
    // over 1.122).
    assert!(exact > 68.35, "the caustic is in view: {exact}");
    assert!((on / exact - 1.0).abs() < 0.0279 && no > 1.656 * on, "{exact} {on} {no}");
    common::assert_clean(&ctx);
}

fn image48(ctx: &specula::vk::Context, scene: &Scene, pairs: &[&str]) -> specula::image::ImageData {
    specula::render(ctx, scene, specula::methods::REFRACTOR_MAP, &quality(pairs), (48, 48), (0, 1)).unwrap().image
}

/// Caustics through a graded medium (survey §6.5, issue 36 item 7): a flat slab of graded-
/// index glass (n = 1.6 − ½·3.7·r² off its vertical axis) focuses a point light onto the
/// floor as a lens would, though its faces are flat. caustic_paths=exact follows the
/// photons' curved paths (common/medium_march.glsl through ray queries), the CPU light
/// tracer its own (scene::medium, f64). The caustic's power and its share within 0.15 m of
/// the axis on the floor (the light tracer's photons against the GPU's light cube, each
/// texel's power where its direction from the cube's centre meets the floor) must agree, and
/// the light tracer's caustic through a slab of uniform index (the same n on its axis) must
/// be far wider, so that straight photons fail. Measured: 3.3925 W / 0.8822 (light tracer),
/// 3.3947 W / 0.8840 (GPU), uniform slab 3.2003 W / 0.0308. Bounds: power within 1 %, the
/// share within 0.02.
#[test]
fn a_graded_index_slab_focuses_the_caustic() {
    let ctx = common::gpu();
    let slab = |graded: bool| {
        let mut s = Scene::new();
        let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
        let glass = s
            .add_material(Material {
                name: "grin".into(),
                kind: SurfaceKind::Dielectric { ior: 1.6, thin: false },
                graded: graded.then(|| specula::scene::medium::GradedIndex {
                    origin: Vec3::ZERO,
                    gradient: Vec3::ZERO,
                    hessian: specula::scene::medium::GradedIndex::radial_hessian(Vec3::Y, 3.7),
                }),
                ..Default::default()
            })
            .unwrap();
        s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, 0.0, -3.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 6.0), 8, floor))
            .unwrap();
        s.add_mesh(shapes::cuboid("slab", Vec3::new(0.0, 1.2, 0.0), Vec3::new(0.5, 0.2, 0.5), glass)).unwrap();
        s.add_light(Light {
            name: "lamp".into(),
            kind: LightKind::Point,
            position: LIGHT,
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(INTENSITY),
            range: None,
        })
        .unwrap();
        s.camera = Some(Camera::look_at(Vec3::new(0.0, 0.6, 2.2), Vec3::new(0.0, 0.0, 0.0), 50f32.to_radians()));
        s
    };
    // (power, the share of it within 0.15 m of the slab's axis on the floor) of weighted
    // floor points.
    let spread = |points: &[(DVec3, f64)]| {
        let p: f64 = points.iter().map(|(_, w)| w).sum();
        let near: f64 = points.iter().filter(|(x, _)| x.x.hypot(x.z) < 0.15).map(|(_, w)| w).sum();
        (p, near / p)
    };
    let light_tracer = |scene: &Scene| {
        let mut q = quality(&["caustics=splat", "caustic_estimate=kernel", "reference_photons=200000"]);
        q.frame.depth = 16;
        let tracer = specula::reference::Tracer::new(scene, &q).unwrap();
        let photons: Vec<(DVec3, f64)> = tracer.photon_map().unwrap().photons().iter().map(|p| (p.position, p.power.x)).collect();
        spread(&photons)
    };
    let (truth, straight) = (light_tracer(&slab(true)), light_tracer(&slab(false)));
    let scene = slab(true);
    let q = quality(&["caustics=splat", "photons=128", "cube_size=128", "caustic_paths=exact", "internal_bounces=4"]);
    let texels = light_cube_on_floor(&ctx, &scene, &q, "slab");
    let gpu = spread(&texels);
    eprintln!(
        "graded slab's caustic: power / share within 0.15 m of the axis: light tracer {:.4} W / {:.4}, GPU exact {:.4} W / {:.4}; uniform slab (light tracer) {:.4} W / {:.4}",
        truth.0, truth.1, gpu.0, gpu.1, straight.0, straight.1
    );
    assert!(
        truth.1 > 2.0 * straight.1,
        "the graded index focuses: {:.4} of the power near the axis against uniform {:.4}",
        truth.1,
        straight.1
    );
    assert!((gpu.0 / truth.0 - 1.0).abs() < 0.01, "power: GPU {:.4} W, light tracer {:.4} W", gpu.0, truth.0);
    assert!((gpu.1 - truth.1).abs() < 0.02, "share near the axis: GPU {:.4}, light tracer {:.4}", gpu.1, truth.1);
    common::assert_clean(&ctx);
}

/// Simplified water caustics (survey §6.4, issue 34 item 6; `builtin:pool`): a water body
/// (ν 1.33) whose floor lies inside it, under the sun. `caustic_paths=surface` refracts each
/// photon once at the surface and takes it straight to the floor: its caustic's power must be
/// the light through the surface times the Fresnel transmittance (the closed form, summed
/// over the triangles the sun sees), as the exact photons' and the light tracer's are; the
/// sampled-geometry paths (`both`) exit through the water's bottom, under the floor, and are
/// searched from there: some power lost and the pattern far off the exact photons'. The
/// pattern moves with the waves while its power stays.
#[test]
fn water_caustics_carry_the_light_through_the_surface() {
    use specula::scenes::water;
    let ctx = common::gpu();
    let scene = water::pool_at(0.0).unwrap();
    let water_mesh = scene.meshes.iter().position(|m| m.name == "water").unwrap();
    let sun = -water::SUN.as_dvec3().normalize();
    let m = &scene.meshes[water_mesh];
    let mut closed = 0.0;
    for t in m.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize].as_dvec3());
        let g = (b - a).cross(c - a);
        let cos = g.normalize().dot(sun);
        if cos > 0.0 {
            closed += water::SUN_IRRADIANCE as f64 * 0.5 * g.length() * cos * (1.0 - specula::optics::fresnel_dielectric(cos, 1.33));
        }
    }
    let power = |paths: &str, scene: &Scene| {
        caustic_power(&ctx, scene, &quality(&["caustics=splat", "photons=128", "cube_size=128", &format!("caustic_paths={paths}")])).0
    };
    let (surface, exact, both) = (power("surface", &scene), power("exact", &scene), power("both", &scene));
    // Surface paths never leave the water: no refractor map is drawn for it.
    let passes = |paths: &str| plan(&scene, specula::methods::BVH, &quality(&["caustics=splat", &format!("caustic_paths={paths}")])).passes;
    assert!(!passes("surface").iter().any(|p| p.contains("refractor")), "{:?}", passes("surface"));
    assert!(passes("both").iter().any(|p| p.contains("refractor")), "{:?}", passes("both"));
    let mut q = quality(&["caustics=triangles", "caustic_estimate=kernel", "reference_photons=200000"]);
    q.frame.depth = 16;
    let tracer = specula::reference::Tracer::new(&scene, &q).unwrap();
    let truth: f64 = tracer.photon_map().unwrap().photons().iter().map(|p| p.power.x).sum();
    eprintln!(
        "pool: closed form {closed:.4} W; surface {surface:.4} ({:.4}), exact {exact:.4} ({:.4}), both {both:.4} ({:.4}), light tracer {truth:.4} ({:.4})",
        surface / closed,
        exact / closed,
        both / closed,
        truth / closed
    );
    // Measured: surface 1.0009 of the closed form, exact 0.9890 (photons that leave through
    // the sides), the light tracer 1.0157 (its photons include the surface's reflection,
    // about 2 %), both 0.9914 (its photons leave through the water's bottom and are searched
    // from there). Bounds: surface within 1 %, exact and the light tracer within 3 %.
    assert!((surface / closed - 1.0).abs() < 0.01, "surface paths: {surface} W against {closed} W");
    assert!((exact / closed - 1.0).abs() < 0.03, "exact paths: {exact} W against {closed} W");
    assert!((truth / closed - 1.0).abs() < 0.03, "the light tracer: {truth} W against {closed} W");
    assert!((surface / closed - 1.0).abs() < (both / closed - 1.0).abs(), "surface {surface} W is no nearer than both {both} W");
    // The pattern on the floor: each paths' caustic image against the exact photons'.
    let render = |s: &Scene, q: &Quality| specula::render(&ctx, s, specula::methods::BVH, q, (64, 64), (0, 1)).unwrap().image;
    let off = quality(&["photons=128", "cube_size=128"]);
    let part = |s: &Scene, paths: &str| {
        let q = quality(&["caustics=splat", "photons=128", "cube_size=128", &format!("caustic_paths={paths}")]);
        caustic_part(&render(s, &q), &render(s, &off))
    };
    let l1 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| (a - b).abs()).sum::<f64>() / b.iter().map(|b| b.abs()).sum::<f64>();
    let reference = part(&scene, "exact");
    let (surface_l1, both_l1) = (l1(&part(&scene, "surface"), &reference), l1(&part(&scene, "both"), &reference));
    eprintln!("the floor's caustic against the exact photons' (relative L1): surface {surface_l1:.4}, both {both_l1:.4}");
    // Measured 0.0379 and 0.1888: bounds a factor 1.12 off.
    assert!(surface_l1 < 0.0379 * 1.12 && both_l1 > 0.1888 / 1.12, "surface {surface_l1:.4}, both {both_l1:.4}");
    // The waves move on: the caustic on the floor changes, its power stays.
    let later = water::pool_at(0.3).unwrap();
    let (now, then) = (part(&scene, "surface"), part(&later, "surface"));
    let changed = now.iter().zip(&then).map(|(a, b)| (a - b).abs()).sum::<f64>() / now.iter().map(|a| a.abs()).sum::<f64>();
    let moved = power("surface", &later);
    eprintln!("0.3 s later: the caustic's pixels changed by {changed:.3} of their sum; power {moved:.4} W");
    // Measured 0.319 of the caustic's sum changed; its power 17.7417 against 17.7482 W.
    assert!(changed > 0.319 / 1.12, "the caustic moves with the waves: {changed}");
    assert!((moved / surface - 1.0).abs() < 0.02, "its power stays: {moved} against {surface} W");
    common::assert_clean(&ctx);
}

/// A planar mirror lights the floor as its mirrored light would (issue 34 item 5): on the
/// mirror panel's floor, per pixel, the caustic's radiance against the closed form of the
/// point light mirrored in the panel's plane (ρ/π · F(θ) · I cos θ_floor / d², where the
/// line to the mirrored light passes through the panel's outline, else nothing): the
/// irradiance inside the mirrored light's outline and the edge of it, with no seams.
#[test]
fn a_mirror_lights_the_floor_as_its_mirrored_light() {
    let ctx = common::gpu();
    let (scene, _) = mirror_panel();
    let (w, h) = (96u32, 96u32);
    let q = |pairs: &[&str]| quality(&[&["cube_size=256", "photons=128"][..], pairs].concat());
    let render = |q: &Quality| specula::render(&ctx, &scene, specula::methods::BVH, q, (w, h), (0, 1)).unwrap().image;
    let part = caustic_part(&render(&q(&["caustics=triangles"])), &render(&q(&[])));
    // The panel: x = −1.5, z from −1 to 1, y from 0.3 to 1.9, facing +x; the light mirrored.
    let light = scene.lights[0].position.as_dvec3();
    let mirrored = DVec3::new(-3.0 - light.x, light.y, light.z);
    let nu = (1.0 + 0.9f64.sqrt()) / (1.0 - 0.9f64.sqrt());
    let rays = specula::reference::CameraRays::new(scene.camera.as_ref().unwrap(), w, h);
    let tracer = specula::reference::Tracer::new(&scene, &q(&[])).unwrap();
    let (mut inside, mut outside, mut edge) = (Vec::new(), Vec::new(), 0);
    for y in 0..h {
        for x in 0..w {
            let (o, d, _) = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            if tracer.first_mesh(o, d, 0.0) != Some(0) || d.y >= 0.0 {
                continue; // not the floor
            }
            let p = o + d * (-o.y / d.y);
            let to = mirrored - p;
            let m = p + to * ((-1.5 - p.x) / to.x); // where the line crosses the panel's plane
            let margin = |v: f64, lo: f64, hi: f64| (v - lo).min(hi - v);
            // Distance of the crossing inside the outline (negative: outside), in metres.
            let e = margin(m.z, -1.0, 1.0).min(margin(m.y, 0.3, 1.9));
            let i = (y * w + x) as usize;
            if e.abs() < 0.06 || p.x < -1.5 {
                edge += 1;
                continue; // at the outline's projection (a pixel's footprint), or behind the panel
            }
            if e < 0.0 {
                outside.push(part[i]);
                continue;
            }
            let r2 = to.length_squared();
            let dir = to / r2.sqrt();
            let f = specula::optics::fresnel_conductor(dir.x.abs(), nu, 0.0);
            let expected = 0.8 / std::f64::consts::PI * f * INTENSITY as f64 * dir.y / r2;
            inside.push((part[i], expected));
        }
    }
    let l1 = inside.iter().map(|(g, e)| (g - e).abs()).sum::<f64>() / inside.iter().map(|(_, e)| e).sum::<f64>();
    let worst = inside.iter().map(|(g, e)| (g / e - 1.0).abs()).fold(0.0, f64::max);
    let leak = outside.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let peak = inside.iter().map(|(_, e)| *e).fold(0.0, f64::max);
    eprintln!(
        "mirrored light on the floor: {} pixels inside, relative L1 {l1:.4}, worst pixel {worst:.4}; {} outside, largest {leak:.5} (peak {peak:.4}); {edge} at the edge",
        inside.len(),
        outside.len()
    );
    assert!(inside.len() > 500 && outside.len() > 500, "{} / {}", inside.len(), outside.len());
    // Measured: 4245 pixels inside at a relative L1 of 0.0524, the worst 0.42 off (scattered
    // pixels, the triangles' texel pattern; no seam); 1014 outside with nothing. Bounds a
    // factor 1.12 off; outside at most 1 % of the peak.
    assert!(l1 < 0.0524 * 1.12 && worst < 0.42 * 1.12, "inside: L1 {l1}, worst {worst}");
    assert!(leak < 0.01 * peak, "outside: {leak} against a peak of {peak}");
    common::assert_clean(&ctx);
}

/// Chains of generators (issue 34 item 5): light → mirror → glass → floor. A glass ball in
/// front of the mirror panel focuses the mirrored light into a second caustic. The light
/// tracer's photons that took three specular bounces or more (the chain; the ball's own
/// internal paths are a few per cent of them) land around a focus; the GPU's exact photons
/// (`caustic_paths=exact`: every specular bounce to the first diffuse hit) must put the same
/// power within 0.15 m of it, counted in the mirror's light cube (each texel's power where its
/// direction from the cube's centre meets the floor). The sampled-geometry paths end a mirror
/// photon at the first surface its receiver cube holds, the ball: the second caustic is
/// missing there.
#[test]
fn a_mirror_and_a_glass_ball_chain_their_caustics() {
    let ctx = common::gpu();
    let (mut scene, _) = mirror_panel();
    let glass = scene
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })
        .unwrap();
    // The light higher, so that the ball's image of the mirrored light falls near the floor.
    scene.lights[0].position = Vec3::new(0.2, 2.4, 0.1);
    scene.add_mesh(shapes::uv_sphere("ball", Vec3::new(-1.0, 0.35, 0.1), 0.3, 48, 24, glass)).unwrap();
    let mut q = quality(&["caustics=splat", "caustic_estimate=kernel", "reference_photons=400000"]);
    q.frame.depth = 8;
    let tracer = specula::reference::Tracer::new(&scene, &q).unwrap();
    let chain: Vec<(DVec3, f64)> =
        tracer.photon_map().unwrap().photons().iter().filter(|p| p.bounces >= 3).map(|p| (p.position, p.power.x)).collect();
    let total: f64 = chain.iter().map(|(_, w)| w).sum();
    // The focus: the densest 5 cm cell of those photons on the floor.
    let mut cells: std::collections::HashMap<(i64, i64), f64> = std::collections::HashMap::new();
    for (x, w) in &chain {
        *cells.entry(((x.x / 0.05).floor() as i64, (x.z / 0.05).floor() as i64)).or_default() += w;
    }
    let (&(cx, cz), _) = cells.iter().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
    let focus = DVec3::new((cx as f64 + 0.5) * 0.05, 0.0, (cz as f64 + 0.5) * 0.05);
    let near = |points: &[(DVec3, f64)]| points.iter().filter(|(x, _)| (*x - focus).length() < 0.15).map(|(_, w)| w).sum::<f64>();
    let truth = near(&chain);
    let gpu = |paths: &str| {
        let q = quality(&["caustics=splat", "photons=256", "cube_size=256", &format!("caustic_paths={paths}")]);
        near(&light_cube_on_floor(&ctx, &scene, &q, "panel"))
    };
    let (exact, both) = (gpu("exact"), gpu("both"));
    // The chain is followed up to the recursion depth: after the panel a photon meets the
    // ball's two surfaces, so at depth 1 it is given up before the floor.
    let shallow = {
        let mut q = quality(&["caustics=splat", "photons=256", "cube_size=256", "caustic_paths=exact"]);
        q.frame.depth = 1;
        near(&light_cube_on_floor(&ctx, &scene, &q, "panel"))
    };
    eprintln!("chain at depth 1: {shallow:.4} W (depth 16: {exact:.4} W)");
    // Measured 0.0000 W against 0.1780.
    assert!(shallow.abs() < 0.01 * exact, "depth 1 ends the chain before the floor: {shallow} vs {exact}");
    // `specula plan` says where the sampled paths stop.
    let chains = |paths: &str| {
        let q = quality(&["caustics=splat", &format!("caustic_paths={paths}")]);
        specula::plan::table(&plan(&scene, specula::methods::REFRACTOR_MAP, &q), &scene).contains("caustic_paths=exact follows it")
    };
    assert!(chains("both") && !chains("exact"), "the plan names the chain's remedy");
    eprintln!(
        "the chain's caustic at {focus:.3}: light tracer {truth:.4} W within 0.15 m (of {total:.4} W on three bounces or more), GPU exact {exact:.4} W, both {both:.4} W"
    );
    // Measured: the focus at (−0.625, 0, 0.075), the light tracer 0.1789 W within 0.15 m of it
    // (of 0.2287 W on three bounces or more), the GPU's exact photons 0.1780 W, the sampled
    // geometry's 0.0119 W. Bounds: exact within 3 %, the sampled paths under half.
    assert!(truth > 0.5 * total, "the chain focuses: {truth} of {total} W");
    assert!((exact / truth - 1.0).abs() < 0.03, "exact photons follow the chain: {exact} W against {truth} W");
    assert!(both < 0.5 * truth, "the sampled-geometry paths stop at the ball: {both} W against {truth} W");
    common::assert_clean(&ctx);
}

/// One frame's light cube of the generator named `generator` (`bvh`, caustics by `q`), as
/// points on the floor (y = 0): each texel's power J·Ω where its direction from the cube's
/// centre meets the floor.
fn light_cube_on_floor(ctx: &specula::vk::Context, scene: &Scene, q: &Quality, generator: &str) -> Vec<(DVec3, f64)> {
    let p = plan(scene, specula::methods::BVH, q);
    let c = p.caustics.as_ref().expect("caustics planned");
    let k = c.cubes.iter().position(|k| scene.meshes[c.generators[k.generator].mesh].name == generator).expect("the generator's cube");
    let centre = scene.reference_point(c.generators[c.cubes[k].generator].mesh).as_dvec3();
    let mut r = Renderer::new(ctx, scene, p, 16, 16).unwrap();
    r.render(ctx).unwrap();
    let cube = read_image(ctx, r.maps().image(&specula::methods::caustics::slots::CAUSTIC_MAPS).unwrap()).unwrap();
    r.destroy(ctx);
    let n = cube.width;
    let mut texels = Vec::new();
    for face in 6 * k as u32..6 * k as u32 + 6 {
        for y in 0..n {
            for x in 0..n {
                let (s, t) = ((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64);
                let d = specula::cube::face_st_to_direction((face % 6) as usize, s as f32, t as f32).as_dvec3().normalize();
                let (u, v) = (2.0 * s - 1.0, 2.0 * t - 1.0);
                let j = cube.texel(face, x, y)[0] as f64 * (2.0 / n as f64).powi(2) / (1.0 + u * u + v * v).powf(1.5);
                if j > 0.0 && d.y < 0.0 {
                    texels.push((centre + d * (-centre.y / d.y), j));
                }
            }
        }
    }
    texels
}
