//! `specula demo`: `auto` and every method of the registry on the bundled demo scene:
//! images, traces, a timing table, errors against the reference, a labelled contact
//! sheet and the trade-off figure.

use std::path::Path;

use specula::demo::Tile;
use specula::scene;
use specula::tradeoff::{Metric, Panel, Row};
use specula::{Choice, Method, Quality};

use crate::args::{context, parse_size, reference_summary, reference_timing, render_reference, write_image};

/// The README's main job: every method on the demo scene, images and a timing table.
pub fn run(outdir: &Path, size: &str, validate: bool, device: &Option<String>) -> specula::Result<()> {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo/demo.gltf");
    let scene = scene::load(&scene_path)?;
    let (w, h) = parse_size(size)?;
    std::fs::create_dir_all(outdir).map_err(|e| specula::Error::io(outdir, e))?;
    let ctx = context(validate, device)?;
    // Each method's whole frame, maps included, is what the timing table shows.
    let q = {
        let mut knobs = Quality::default();
        knobs.frame.map_updates_always = true;
        knobs
    };
    let mut report = format!("specula demo: {} at {w}x{h} on {} ({})\n\n", scene_path.display(), ctx.device_name, ctx.driver_info);

    // The exact reference first: every tile's label carries its error against it.
    let reference_method = specula::methods::REFERENCE;
    let (reference, ref_ms) = render_reference(&scene, &q, (w, h))?;
    let stem = outdir.join(reference_method.name());
    write_image(&stem.with_extension("png"), &reference)?;
    write_image(&stem.with_extension("exr"), &reference)?;
    let trace = stem.with_extension("trace.json");
    specula::output::write_file(&trace, specula::profile::chrome_trace(&[reference_timing(ref_ms)], &[], "CPU").as_bytes())?;
    report += &format!("== method reference -> {}\n{}\n\n", stem.with_extension("png").display(), reference_summary(&q, w, h, ref_ms));

    let choices = std::iter::once(Choice::Auto).chain(Method::ALL.iter().copied().filter(|m| m.is_gpu()).map(Choice::Method));
    let mut tiles = Vec::new();
    let mut rows = Vec::new();
    let mut errors = String::from("== error against the reference (PSNR, frame GPU ms, device memory)\n");
    for choice in choices {
        let name = choice.name();
        let plan = specula::plan(&scene, choice, &q);
        let methods: Vec<String> = plan.objects.iter().map(|o| format!("{}: {} ({})", o.name, o.method.name(), o.reason)).collect();
        // The ray engine and the ray hierarchy test every triangle for every ray (O(N) per
        // ray): one frame of each is minutes on lavapipe at 512², so they render one frame at
        // a quarter of the size a side (at most 128²; the sheet and the label say so),
        // compared with the reference box-filtered to that size and shown enlarged.
        let linear = matches!(choice, Choice::Method(m) if specula::methods::raytrace::bench::complexity(m).starts_with("O(N)"));
        let (warmup, frames) = if linear { (0, 1) } else { (2, 5) };
        let k = if linear { (w / 128).max(h / 128).max(1) } else { 1 };
        let small = (w / k, h / k);
        let mut frame = specula::render_plan(&ctx, &scene, plan, small, (warmup, frames))?;
        let own_reference = if k > 1 { box_filter(&reference, k) } else { reference.clone() };
        let e = specula::metrics::compare(&frame.image, &own_reference)?;
        if k > 1 {
            frame.image = enlarge(&frame.image, k);
        }
        let at = if k > 1 { format!(" at {}x{}", small.0, small.1) } else { String::new() };
        let png = outdir.join(format!("{name}.png"));
        write_image(&png, &frame.image)?;
        write_image(&outdir.join(format!("{name}.exr")), &frame.image)?;
        let trace = outdir.join(format!("{name}.trace.json"));
        specula::output::write_file(&trace, specula::profile::chrome_trace(&frame.passes, &frame.memory, &ctx.device_name).as_bytes())?;
        report += &format!("== method {name} -> {} (median of {frames} frame(s){at})\n", png.display());
        for m in &methods {
            report += &format!("   {m}\n");
        }
        report += &specula::profile::table(&frame.passes, &frame.memory);
        report.push('\n');
        errors += &format!("{name:<24} {e}  {:.2} ms  {:.1} MiB{at}\n", frame.gpu_ms(), frame.memory_bytes() as f64 / 1048576.0);
        // Frame ms as the trade-off study counts it: every pass but the readback copy.
        let row = Row::new(&format!("{name}{at}"), "default", &frame.passes, e);
        let ms = if row.frame_ms >= 100.0 { format!("{:.0} ms", row.frame_ms) } else { format!("{:.1} ms", row.frame_ms) };
        // Narrow tiles get time and PSNR on lines of their own.
        let sep = if w < 256 { "\n" } else { "  " };
        tiles.push(Tile { name: name.into(), label: format!("{name}{at}\n{ms}{sep}{:.2} dB", e.psnr), image: frame.image });
        rows.push(row);
    }
    tiles.push(Tile { name: reference_method.name().into(), label: format!("reference\n{ref_ms:.0} ms CPU"), image: reference });
    report += &errors;
    report.push('\n');
    // All of them side by side (the survey's Figures 20 and 24 in one sheet).
    let sheet = specula::demo::write_composite(outdir, &tiles, w, h)?;
    report += &format!("side by side: {}\n", sheet.display());
    // Planar mirrors (§5): the mirror scene's corridor of images, by the planner (planar
    // mirrors mirrored, the sphere ray traced), by planar-mirror for every mirror it serves
    // and by distance maps, against the reference.
    let (text, mirror_rows) = mirrors(&ctx, &outdir.join("mirrors"), (w, h), &q)?;
    report += &text;
    report += &flat_glass(&ctx, &outdir.join("glass"), (w, h), &q)?;
    // The trade-off figure of both scenes, one panel each (every method at its defaults).
    let panels = [Panel { name: "demo scene".into(), rows }, Panel { name: "mirror scene".into(), rows: mirror_rows }];
    let title = format!("specula demo at {w}x{h} on {}: PSNR vs GPU time", ctx.device_name);
    let fig = specula::tradeoff::plot(&outdir.join("tradeoff"), &panels, Metric::Psnr, &title)?;
    report += &format!("trade-off figure: {}, {}\n", fig.svg.display(), fig.png.display());
    report += &showcase(&outdir.join("showcase"), (w, h), validate, device)?;
    print!("{report}");
    let table = outdir.join("timings.txt");
    specula::output::write_file(&table, report.as_bytes())?;

    // Frames over time: the mirror sphere on its path (the scene's glTF animation), the
    // planner's methods, maps regenerated only when what they see moved.
    let anim = crate::args::RenderArgs {
        scene: scene_path.to_path_buf(),
        method: "auto".into(),
        objects: Vec::new(),
        size: "128x128".into(),
        quality: vec!["cube_size=128".into(), "map_updates=on_change".into()],
        env: None,
        camera_pos: None,
        camera_target: None,
        fov: None,
        time: None,
        validate,
        device: device.clone(),
        warmup: 0,
        frames: 1,
    };
    crate::animate::run(&anim, 12.0, None, (&[], false), &outdir.join("animation"))
}

/// The mirror scene (`assets/mirrors/`): images and a timing table into `outdir`; the
/// table and the trade-off rows.
fn mirrors(ctx: &specula::vk::Context, outdir: &Path, (w, h): (u32, u32), q: &Quality) -> specula::Result<(String, Vec<Row>)> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/mirrors/mirrors.gltf");
    let scene = scene::load(&path)?;
    std::fs::create_dir_all(outdir).map_err(|e| specula::Error::io(outdir, e))?;
    let mut report = format!("\n== planar mirrors (survey §5): {} at {w}x{h}\n", path.display());
    let (reference, ref_ms) = render_reference(&scene, q, (w, h))?;
    write_image(&outdir.join("reference.png"), &reference)?;
    report += &format!("reference: {ref_ms:.0} ms CPU\n");
    let mut rows = Vec::new();
    for choice in [Choice::Auto, Choice::Method(specula::methods::PLANAR_MIRROR), Choice::Method(specula::methods::DISTANCE)] {
        let name = choice.name();
        let frame = specula::render(ctx, &scene, choice, q, (w, h), (1, 3))?;
        write_image(&outdir.join(format!("{name}.png")), &frame.image)?;
        let e = specula::metrics::compare(&frame.image, &reference)?;
        let views = frame.stats.iter().find(|(n, _)| n == "geometry.mirror_views").map_or(0.0, |(_, v)| *v);
        report += &format!("-- {name}: {:.2} ms, {views} mirrored view(s), {e}\n", frame.gpu_ms());
        report += &specula::profile::table(&frame.passes, &frame.memory);
        rows.push(Row::new(name, "default", &frame.passes, e));
    }
    Ok((report, rows))
}

/// Flat glass (`specula::scenes::flat_glass`, survey §5): the reference, planar-refraction
/// at mirror_budget 8 and 64, refractor-map and bvh, with their errors and pass tables.
fn flat_glass(ctx: &specula::vk::Context, outdir: &Path, (w, h): (u32, u32), q: &Quality) -> specula::Result<String> {
    let scene = specula::scenes::flat_glass()?;
    std::fs::create_dir_all(outdir).map_err(|e| specula::Error::io(outdir, e))?;
    let mut report = format!("\n== flat glass (survey §5): a slab and a prism of ν 1.5 at {w}x{h}\n");
    let mut q = q.clone();
    q.frame.depth = 4;
    let (reference, ref_ms) = render_reference(&scene, &q, (w, h))?;
    write_image(&outdir.join("reference.png"), &reference)?;
    report += &format!("reference (depth 4): {ref_ms:.0} ms CPU\n");
    let runs = [
        ("planar-refraction", specula::methods::PLANAR_REFRACTION, 8),
        ("planar-refraction-64", specula::methods::PLANAR_REFRACTION, 64),
        ("refractor-map", specula::methods::REFRACTOR_MAP, 8),
        ("bvh", specula::methods::BVH, 8),
    ];
    for (name, method, budget) in runs {
        let mut qm = q.clone();
        qm.geometry.mirror_budget = budget;
        let frame = specula::render(ctx, &scene, method, &qm, (w, h), (1, 3))?;
        write_image(&outdir.join(format!("{name}.png")), &frame.image)?;
        let e = specula::metrics::compare(&frame.image, &reference)?;
        let views = frame.stats.iter().find(|(n, _)| n == "geometry.mirror_views").map_or(0.0, |(_, v)| *v);
        report += &format!("-- {name} (mirror_budget {budget}): {:.2} ms, {views} view(s), {e}\n", frame.gpu_ms());
        report += &specula::profile::table(&frame.passes, &frame.memory);
    }
    Ok(report)
}

/// One showcase study (issue 15): a scene built in code, the methods of its family, the
/// base knobs and the sweeps, each varied alone from the base (`specula tradeoff --each`).
pub struct Study {
    pub scene: &'static str,
    pub methods: &'static [&'static str],
    pub base: &'static [&'static str],
    pub sweeps: &'static [&'static str],
}

/// The studies `specula demo` writes to out/showcase/NAME/. The reference takes one sample
/// per pixel, as the GPU frames do, so that a curve shows the method's error, not the
/// aliasing all of them share; bvh (exact) is each figure's anchor. Where the sweeps are
/// search knobs, the maps are built once (`map_updates=on_change`: a static scene's steady
/// state), so that the time axis shows what the search costs per frame; the concave
/// occluder compares methods whose maps differ (a layered map peels `layers` layers), so
/// its frames rebuild them.
pub const STUDIES: &[Study] = &[
    Study {
        scene: "corner-mirror",
        methods: &["distance", "bvh"],
        base: &["spp=1", "map_updates=on_change", "linear_steps=4", "secant_steps=0"],
        sweeps: &["secant_steps=0,1,2,4,8", "linear_steps=4,8,16,32"],
    },
    Study {
        scene: "concave-occluder",
        methods: &["distance", "distance-multi", "layered", "bvh"],
        base: &["spp=1"],
        sweeps: &["linear_steps=4,16,64", "layers=1,2,4"],
    },
    Study {
        scene: "glass-1.1",
        methods: &["refractor-map", "image-space-refraction", "bvh"],
        base: &["spp=1", "map_updates=on_change"],
        sweeps: &["internal_bounces=0,1,2,4", "linear_steps=4,8,16,32"],
    },
    Study {
        scene: "glass-1.5",
        methods: &["refractor-map", "image-space-refraction", "bvh"],
        base: &["spp=1", "map_updates=on_change"],
        sweeps: &["internal_bounces=0,1,2,4", "linear_steps=4,8,16,32"],
    },
    Study {
        scene: "flat-glass",
        methods: &["planar-refraction", "refractor-map", "bvh"],
        base: &["spp=1"],
        sweeps: &["mirror_budget=2,4,8,16,32,64"],
    },
    Study {
        scene: "convex-mirror",
        methods: &["curved-reflector", "distance", "bvh"],
        base: &["spp=1", "map_updates=on_change"],
        sweeps: &["geometry_image=16,32,64,128", "curved_search=0,1,2,3", "tessellation=1,2,4,8"],
    },
    Study {
        scene: "caustic-ball",
        methods: &["refractor-map", "bvh"],
        base: &["spp=1"],
        sweeps: &["caustics=off,splat,triangles", "photons=32,64,128,256", "caustic_filter=0,1,2,4"],
    },
    Study {
        scene: "pool",
        methods: &["bvh"],
        base: &["spp=1", "caustics=triangles", "caustic_paths=surface"],
        sweeps: &["caustic_paths=both,surface,exact", "photons=64,128,256"],
    },
    Study { scene: "mirage", methods: &["bvh", "ray-query"], base: &["spp=1"], sweeps: &["medium_turn=0.2,0.05,0.01"] },
];

/// The frames per configuration of the showcase studies: (warm-up, timed).
const STUDY_FRAMES: (u32, u32) = (1, 5);

impl Study {
    /// The `specula tradeoff` command that runs this study alone.
    pub fn command(&self, (w, h): (u32, u32), out: &Path) -> String {
        let mut c =
            format!("specula tradeoff builtin:{} --size {w}x{h} --warmup {} --frames {}", self.scene, STUDY_FRAMES.0, STUDY_FRAMES.1);
        for m in self.methods {
            c += &format!(" --method {m}");
        }
        for q in self.base {
            c += &format!(" -q {q}");
        }
        for s in self.sweeps {
            c += &format!(" --sweep {s}");
        }
        c + &format!(" --each --out {}", out.display())
    }
}

/// The showcase studies at the demo's size, at most 128 pixels a side: each scene's
/// tradeoff.csv, .svg and .png in `outdir`/NAME/; the report names them with the command
/// that runs each alone.
fn showcase(outdir: &Path, (w, h): (u32, u32), validate: bool, device: &Option<String>) -> specula::Result<String> {
    let size = (w.min(128), h.min(128));
    let mut report = format!("\n== showcase studies (issue 15) at {}x{}\n", size.0, size.1);
    for study in STUDIES {
        let out = outdir.join(study.scene);
        let scene = specula::scenes::builtin(study.scene).expect("a built-in scene")?;
        let mut quality = {
            let mut knobs = Quality::default();
            knobs.frame.map_updates_always = true;
            knobs
        };
        for q in study.base {
            quality.set_pair(q)?;
        }
        let cfg = specula::tradeoff::Config {
            scene,
            scene_name: format!("builtin:{}", study.scene),
            quality,
            sweeps: study.sweeps.iter().map(|s| specula::tradeoff::Sweep::parse(s)).collect::<specula::Result<_>>()?,
            each: true,
            methods: study.methods.iter().map(|m| Choice::parse(m)).collect::<specula::Result<_>>()?,
            size,
            warmup: STUDY_FRAMES.0,
            frames: STUDY_FRAMES.1,
            device: specula::vk::DeviceOptions { validation: validate, device_filter: device.clone(), ..Default::default() },
            out: out.clone(),
            metric: Metric::Psnr,
            calibrate: None,
        };
        let t = std::time::Instant::now();
        let r = specula::tradeoff::run(&cfg, &mut |_| {})?;
        report += &format!(
            "-- {} ({:.1} s): {}\n   {}\n",
            study.scene,
            t.elapsed().as_secs_f64(),
            r.figure.png.display(),
            study.command(size, &out)
        );
        for row in &r.rows {
            let ball = row.regions.iter().find(|e| e.name == "specular").map_or(f64::NAN, |e| e.psnr);
            report += &format!(
                "   {:<36} {:<22} {:>9.2} ms {:>7.2} dB (specular pixels {ball:.2} dB)\n",
                row.method, row.knobs, row.frame_ms, row.errors.psnr
            );
        }
    }
    Ok(report)
}

/// `image` averaged over k×k blocks (what a render at 1/k of the size a side is compared with).
fn box_filter(image: &specula::image::ImageData, k: u32) -> specula::image::ImageData {
    let (w, h, c) = (image.width / k, image.height / k, image.channels as usize);
    let mut data = vec![0.0f32; (w * h) as usize * c];
    for y in 0..h {
        for x in 0..w {
            let out = &mut data[((y * w + x) as usize) * c..][..c];
            for (dy, dx) in (0..k).flat_map(|dy| (0..k).map(move |dx| (dy, dx))) {
                for (o, v) in out.iter_mut().zip(image.texel(0, x * k + dx, y * k + dy)) {
                    *o += v / (k * k) as f32;
                }
            }
        }
    }
    specula::image::ImageData { width: w, height: h, layers: 1, channels: image.channels, data }
}

/// `image` enlarged k times a side by repeating pixels (for the sheet's tiles).
fn enlarge(image: &specula::image::ImageData, k: u32) -> specula::image::ImageData {
    let (w, h, c) = (image.width * k, image.height * k, image.channels as usize);
    let mut data = Vec::with_capacity((w * h) as usize * c);
    for y in 0..h {
        for x in 0..w {
            data.extend_from_slice(image.texel(0, x / k, y / k));
        }
    }
    specula::image::ImageData { width: w, height: h, layers: 1, channels: image.channels, data }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The O(N) tracers' small frames: a k×k box averages, enlarging repeats pixels, and
    /// enlarging then filtering gives the image back.
    #[test]
    fn box_filter_and_enlarge() {
        let data: Vec<f32> = (0..4 * 4 * 4).map(|i| i as f32).collect();
        let img = specula::image::ImageData { width: 4, height: 4, layers: 1, channels: 4, data };
        let small = box_filter(&img, 2);
        assert_eq!((small.width, small.height), (2, 2));
        // Pixels (0,0), (1,0), (0,1), (1,1): channel 0 values 0, 4, 16, 20.
        assert_eq!(small.texel(0, 0, 0)[0], 10.0);
        let big = enlarge(&small, 2);
        assert_eq!((big.width, big.height), (4, 4));
        assert_eq!(big.texel(0, 1, 1), small.texel(0, 0, 0));
        assert_eq!(box_filter(&big, 2).data, small.data);
    }

    /// Every study `specula demo` runs names a built-in scene, GPU methods, base knobs and
    /// sweeps that parse (the demo is not run by the suite: this is what would break it).
    #[test]
    fn every_study_parses() {
        for s in STUDIES {
            assert!(specula::scenes::builtin(s.scene).is_some_and(|r| r.is_ok()), "{}", s.scene);
            for m in s.methods {
                assert!(matches!(Choice::parse(m), Ok(Choice::Method(m)) if m.is_gpu()), "{}: {m}", s.scene);
            }
            let mut q = Quality::default();
            for p in s.base {
                q.set_pair(p).unwrap_or_else(|e| panic!("{}: {p}: {e}", s.scene));
            }
            for w in s.sweeps {
                specula::tradeoff::Sweep::parse(w).unwrap_or_else(|e| panic!("{}: {w}: {e}", s.scene));
            }
        }
        let names: Vec<&str> = STUDIES.iter().map(|s| s.scene).collect();
        assert_eq!(
            names,
            [
                "corner-mirror",
                "concave-occluder",
                "glass-1.1",
                "glass-1.5",
                "flat-glass",
                "convex-mirror",
                "caustic-ball",
                "pool",
                "mirage"
            ]
        );
    }
}
