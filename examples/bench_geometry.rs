//! Geometry transformation (survey §5) measured on flat-faced glass: `cargo run --release
//! --example bench_geometry -- [SIZE] [FRAMES]` (default 256 and 5). The emissive quadrant
//! room (no lights: nothing but geometry and Fresnel decides a pixel) with a glass slab and a
//! glass prism of ν 1.5 seen from above at an angle, exact Fresnel. Prints, as Markdown:
//!   1. the cost of each recursion level: `planar-refraction` at depth 1..6 (mirror_budget 64),
//!      views rendered, GPU frame ms (median of FRAMES after one warm-up), the views' share,
//!      PSNR against the reference at the same depth;
//!   2. the budget at depth 4: mirror_budget 0..64 against the depth-4 reference, beside the
//!      exact per-pixel refraction (`bvh`) and refractor maps (`refractor-map`).
//!
//! GPU times are lavapipe's (or the device's) timestamp queries: the build profile of this
//! crate does not enter them.

use specula::vk::{Context, DeviceOptions};
use specula::{Method, Quality};

fn stat(f: &specula::Frame, name: &str) -> f64 {
    f.stats.iter().find(|(n, _)| n == name).map_or(0.0, |(_, v)| *v)
}

fn views_ms(f: &specula::Frame) -> f64 {
    f.passes.iter().filter(|p| p.name == "geometry.mirror_view").map(|p| p.gpu_ms).sum()
}

fn main() -> specula::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let size: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(256);
    let frames: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let s = specula::scenes::flat_glass()?;
    let ctx = Context::new(&DeviceOptions::default())?;
    let quality = |depth: u32, budget: u32| -> specula::Result<Quality> {
        let mut q = {
            let mut knobs = Quality::default();
            knobs.frame.depth = depth;
            knobs.reference.spp = 1;
            knobs
        };
        q.set("fresnel", "exact")?;
        q.set("mirror_budget", &budget.to_string())?;
        Ok(q)
    };
    let run = |m: Method, q: &Quality| specula::render(&ctx, &s, m, q, (size, size), (1, frames));
    let psnr = |a: &specula::image::ImageData, b: &specula::image::ImageData| specula::metrics::compare(a, b).map(|c| c.psnr);
    println!("device: {}", ctx.device_name);
    println!("\n#### planar-refraction per recursion level, {size}², mirror_budget 64");
    println!("| depth | views | frame ms | views' share | PSNR vs reference (same depth) |");
    println!("|---:|---:|---:|---:|---:|");
    for depth in 1..=6 {
        let q = quality(depth, 64)?;
        let reference = specula::reference::render_reference(&s, &q, (size, size))?;
        let f = run(specula::methods::PLANAR_REFRACTION, &q)?;
        let share = 100.0 * views_ms(&f) / f.gpu_ms().max(1e-9);
        println!(
            "| {depth} | {} | {:.1} | {share:.0} % | {:.2} dB |",
            stat(&f, "geometry.mirror_views"),
            f.gpu_ms(),
            psnr(&f.image, &reference)?
        );
    }
    let q4 = quality(4, 8)?;
    let reference = specula::reference::render_reference(&s, &q4, (size, size))?;
    println!("\n#### mirror_budget at depth 4, {size}², against the depth-4 reference");
    println!("| method | mirror_budget | views | fallbacks | frame ms | PSNR |");
    println!("|---|---:|---:|---:|---:|---:|");
    for budget in [0, 4, 8, 16, 32, 64] {
        let q = quality(4, budget)?;
        let f = run(specula::methods::PLANAR_REFRACTION, &q)?;
        let (views, fallbacks) = (stat(&f, "geometry.mirror_views"), stat(&f, "geometry.mirror_fallbacks"));
        println!("| planar-refraction | {budget} | {views} | {fallbacks} | {:.1} | {:.2} dB |", f.gpu_ms(), psnr(&f.image, &reference)?);
    }
    for m in [specula::methods::BVH, specula::methods::REFRACTOR_MAP] {
        let f = run(m, &q4)?;
        println!("| {} | – | – | – | {:.1} | {:.2} dB |", m.name(), f.gpu_ms(), psnr(&f.image, &reference)?);
    }
    Ok(())
}
