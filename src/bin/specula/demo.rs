//! `specula demo`: every method on the bundled demo scene, images, traces, a timing table,
//! errors against the reference and a contact sheet.

use std::path::Path;

use specula::image::ImageData;
use specula::scene;
use specula::{Method, Quality};

use crate::args::{context, parse_size, reference_summary, reference_timing, render_reference, write_image};

/// The README's main job: every method on the demo scene, images and a timing table.
pub fn run(outdir: &Path, size: &str, validate: bool, device: &Option<String>) -> specula::Result<()> {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo/demo.gltf");
    let scene = scene::load(&scene_path)?;
    let (w, h) = parse_size(size)?;
    std::fs::create_dir_all(outdir).map_err(|e| specula::Error::io(outdir, e))?;
    let ctx = context(validate, device)?;
    let mut report = format!("specula demo: {} at {w}x{h} on {} ({})\n\n", scene_path.display(), ctx.device_name, ctx.driver_info);
    let mut images: Vec<(&str, ImageData)> = Vec::new();
    for &method in Method::ALL {
        let png = outdir.join(format!("{}.png", method.name()));
        let exr = outdir.join(format!("{}.exr", method.name()));
        if !method.is_gpu() {
            let q = Quality::default();
            let (img, ms) = render_reference(&scene, &q, (w, h))?;
            write_image(&png, &img)?;
            write_image(&exr, &img)?;
            let trace = outdir.join(format!("{}.trace.json", method.name()));
            std::fs::write(&trace, specula::profile::chrome_trace(&[reference_timing(ms)], &[], "CPU"))
                .map_err(|e| specula::Error::io(&trace, e))?;
            report += &format!("== method {} -> {}\n{}\n\n", method.name(), png.display(), reference_summary(&q, w, h, ms));
            images.push((method.name(), img));
            continue;
        }
        let frame = specula::render(&ctx, &scene, method, &Quality::default(), (w, h), (2, 5))?;
        write_image(&png, &frame.image)?;
        write_image(&exr, &frame.image)?;
        let trace = outdir.join(format!("{}.trace.json", method.name()));
        std::fs::write(&trace, specula::profile::chrome_trace(&frame.passes, &frame.memory, &ctx.device_name))
            .map_err(|e| specula::Error::io(&trace, e))?;
        report += &format!("== method {} -> {} (median of 5 frames)\n", method.name(), png.display());
        report += &specula::profile::table(&frame.passes, &frame.memory);
        report.push('\n');
        images.push((method.name(), frame.image));
    }
    // Every method against the exact reference, and all of them side by side (the survey's
    // Figures 20 and 24 in one sheet): methods.png, and methods.svg with labels.
    if let Some((_, reference)) = images.iter().find(|(n, _)| *n == specula::methods::REFERENCE.name()) {
        report += "== error against the reference\n";
        for (name, img) in images.iter().filter(|(n, _)| *n != specula::methods::REFERENCE.name()) {
            report += &format!("{name:<24} {}\n", specula::metrics::compare(img, reference)?);
        }
        report.push('\n');
    }
    specula::demo::write_composite(outdir, &images, w, h)?;
    report += &format!("side by side: {}, {}\n", outdir.join("methods.png").display(), outdir.join("methods.svg").display());
    print!("{report}");
    let table = outdir.join("timings.txt");
    std::fs::write(&table, &report).map_err(|e| specula::Error::io(&table, e))?;
    Ok(())
}
