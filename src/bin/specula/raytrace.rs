//! `specula raytrace-bench`: survey Table 1 measured for ray tracing in the original
//! geometry (`specula::methods::raytrace::bench`); writes `table1.md`, `table1.csv` and
//! `table1.svg` into `out`.

use std::path::Path;

use specula::methods::raytrace::bench::{self, Config};

use crate::args::{context, parse_size};

#[allow(clippy::too_many_arguments)]
pub fn run(
    triangles: &str,
    size: &str,
    depth: u32,
    budget_s: f64,
    frames: u32,
    headline_size: &str,
    parts: &str,
    out: &Path,
    device: &Option<String>,
) -> specula::Result<()> {
    let sizes = triangles
        .split(',')
        .map(|t| {
            t.trim().parse::<usize>().ok().filter(|&n| (8..=10_000_000).contains(&n)).ok_or_else(|| {
                specula::Error::invalid("--triangles", format!("'{}' is not a triangle count in 8..=10000000", specula::error::clip(t)))
            })
        })
        .collect::<specula::Result<Vec<usize>>>()?;
    if !(1..=64).contains(&depth) {
        return Err(specula::Error::invalid("--depth", format!("{depth} is outside 1..=64")));
    }
    if !(budget_s > 0.0 && budget_s.is_finite()) {
        return Err(specula::Error::invalid("--budget-s", format!("must be a positive number of seconds, got {budget_s}")));
    }
    let parts = parts
        .split(',')
        .map(|p| {
            bench::Part::parse(p.trim()).ok_or_else(|| {
                specula::Error::invalid(
                    "--parts",
                    format!("'{}' is not one of table1, culling, headline, mutual, moves", specula::error::clip(p)),
                )
            })
        })
        .collect::<specula::Result<Vec<_>>>()?;
    let demo = specula::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo/demo.gltf"))?;
    let ctx = context(false, device)?;
    println!("raytrace-bench on {} ({})", ctx.device_name, ctx.driver_info);
    let config = Config {
        demo,
        sizes,
        size: parse_size(size)?,
        depth,
        budget_ms: budget_s * 1e3,
        frames: frames.max(1),
        headline_size: parse_size(headline_size)?,
        parts,
    };
    let md = bench::run(&ctx, &config, out)?;
    let header = format!("Device: {} ({})\n\n", ctx.device_name, ctx.driver_info);
    specula::output::write_file(&out.join("table1.md"), (header + &md).as_bytes())?;
    println!("wrote {}", out.join("table1.md").display());
    Ok(())
}
