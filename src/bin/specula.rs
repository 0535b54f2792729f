//! The specula command line: render, info, plan, knobs, demo, bench, compare, tradeoff.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use glam::Vec3;
use specula::scene::{self, Camera};
use specula::vk::{Context, DeviceOptions, ImageData, PassTiming};
use specula::{Method, Quality, Scene};

#[derive(Parser)]
#[command(name = "specula", version, about = "Specular effects on the GPU through raw Vulkan")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone)]
struct RenderArgs {
    /// glTF 2.0 scene (.gltf or .glb).
    scene: PathBuf,
    /// Rendering method (`specula knobs` lists methods and knobs).
    #[arg(long, default_value = "envmap")]
    method: String,
    /// Output size WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512")]
    size: String,
    /// Accuracy knob key=value (repeatable).
    #[arg(long = "quality", short = 'q')]
    quality: Vec<String>,
    /// Equirectangular environment map (.exr, .hdr, .png, .jpg).
    #[arg(long)]
    env: Option<PathBuf>,
    /// Camera position x,y,z (overrides the scene's camera; with --camera-target).
    #[arg(long)]
    camera_pos: Option<String>,
    /// Camera target x,y,z.
    #[arg(long)]
    camera_target: Option<String>,
    /// Vertical field of view in degrees (with --camera-pos).
    #[arg(long, default_value_t = 60.0)]
    fov: f32,
    /// Enable the Khronos validation layer; any validation error fails the command.
    #[arg(long)]
    validate: bool,
    /// Device name filter (substring, e.g. llvmpipe); default SPECULA_DEVICE or the first GPU.
    #[arg(long)]
    device: Option<String>,
    /// Untimed frames before the timed ones.
    #[arg(long, default_value_t = 1)]
    warmup: u32,
    /// Timed frames; the profile reports the median per pass.
    #[arg(long, default_value_t = 1)]
    frames: u32,
}

#[derive(clap::Args, Clone)]
struct TradeoffArgs {
    /// glTF 2.0 scene (.gltf or .glb).
    scene: PathBuf,
    /// Output size WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256")]
    size: String,
    /// Base accuracy knobs key=value (repeatable); spp and depth set the reference's.
    #[arg(long = "quality", short = 'q')]
    quality: Vec<String>,
    /// Equirectangular environment map.
    #[arg(long)]
    env: Option<PathBuf>,
    /// Untimed frames before the timed ones (at least 1: the first frame uploads the scene).
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Timed frames per configuration; the median per pass is reported.
    #[arg(long, default_value_t = 5)]
    frames: u32,
    /// Enable the Khronos validation layer.
    #[arg(long)]
    validate: bool,
    /// Device name filter (substring).
    #[arg(long)]
    device: Option<String>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (.png: sRGB, clamped; .exr: linear radiance).
    Render {
        #[command(flatten)]
        args: RenderArgs,
        /// Output image.
        #[arg(long)]
        out: PathBuf,
        /// Write the per-pass profile as Chrome trace-event JSON (opens in Perfetto).
        #[arg(long)]
        profile: Option<PathBuf>,
    },
    /// List meshes, materials with their classification, lights, camera and bounds.
    Info { scene: PathBuf },
    /// Print the plan (maps, passes, knobs) a scene gets, as JSON.
    Plan {
        #[command(flatten)]
        args: RenderArgs,
    },
    /// List methods and accuracy knobs with their ranges and defaults.
    Knobs,
    /// Time a method over several frames for each value of one knob, in one run, and print
    /// per-pass medians with each variant's frame time relative to the first.
    Bench {
        #[command(flatten)]
        args: RenderArgs,
        /// knob=v1,v2,... (e.g. cube_mode=six,multiview); without it, one variant.
        #[arg(long)]
        sweep: Option<String>,
    },
    /// Image errors of TEST against REFERENCE (.exr linear, .png/.jpg sRGB-decoded): RMSE,
    /// PSNR, max and p99 absolute error, mean FLIP.
    Compare {
        test: PathBuf,
        reference: PathBuf,
        /// Write the FLIP error map in false colour (PNG).
        #[arg(long)]
        error_image: Option<PathBuf>,
    },
    /// The speed–accuracy trade-off: every GPU method (× every --sweep combination) timed
    /// and compared with the exact reference; writes tradeoff.csv and tradeoff.svg to --out.
    Tradeoff {
        #[command(flatten)]
        args: TradeoffArgs,
        /// knob=v1,v2,... (repeatable: the combinations multiply); ref_point values split on ';'.
        #[arg(long)]
        sweep: Vec<String>,
        /// Only these methods (repeatable); default every GPU method.
        #[arg(long = "method")]
        methods: Vec<String>,
        /// Output directory.
        #[arg(long, default_value = "tradeoff")]
        out: PathBuf,
    },
    /// Render the bundled demo scene with every method into OUTDIR, with a timing table.
    Demo {
        #[arg(default_value = "out")]
        outdir: PathBuf,
        #[arg(long, default_value = "512x512")]
        size: String,
        #[arg(long)]
        validate: bool,
        #[arg(long)]
        device: Option<String>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("specula: {e}");
            ExitCode::FAILURE
        }
    }
}

fn parse_vec3(what: &str, s: &str) -> specula::Result<Vec3> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| specula::Error::invalid(what, format!("'{s}' is not x,y,z")))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(specula::Error::invalid(what, format!("'{s}' is not three finite numbers x,y,z"))),
    }
}

fn parse_size(s: &str) -> specula::Result<(u32, u32)> {
    let bad = || specula::Error::invalid("--size", format!("'{s}' is not WIDTHxHEIGHT"));
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    let (w, h) = (w.parse::<u32>().map_err(|_| bad())?, h.parse::<u32>().map_err(|_| bad())?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(specula::Error::invalid("--size", format!("{w}x{h} is outside 1..=16384")));
    }
    Ok((w, h))
}

struct Job {
    scene: Scene,
    method: Method,
    quality: Quality,
    width: u32,
    height: u32,
}

fn prepare(a: &RenderArgs) -> specula::Result<Job> {
    let mut scene = scene::load(&a.scene)?;
    if let Some(env) = &a.env {
        scene.set_environment(scene::load_environment(env)?)?;
    }
    if let Some(pos) = &a.camera_pos {
        let eye = parse_vec3("--camera-pos", pos)?;
        let target = a.camera_target.as_deref().map(|t| parse_vec3("--camera-target", t)).transpose()?.unwrap_or(eye + Vec3::NEG_Z);
        if !(a.fov > 0.0 && a.fov < 180.0) {
            return Err(specula::Error::invalid("--fov", "must be in (0, 180) degrees"));
        }
        scene.camera = Some(Camera::look_at(eye, target, a.fov.to_radians()));
    }
    let mut quality = Quality::default();
    for q in &a.quality {
        quality.set_pair(q)?;
    }
    let (width, height) = parse_size(&a.size)?;
    Ok(Job { scene, method: Method::parse(&a.method)?, quality, width, height })
}

fn context(validate: bool, device: &Option<String>) -> specula::Result<Context> {
    Context::new(&DeviceOptions { validation: validate, device_filter: device.clone() })
}

fn write_image(path: &Path, img: &ImageData) -> specula::Result<()> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("exr") => scene::write_exr(path, img.width, img.height, &img.data),
        Some("png") => scene::write_png_srgb(path, img.width, img.height, &img.data),
        _ => Err(specula::Error::invalid("--out", format!("{}: use .png or .exr", path.display()))),
    }
}

fn run(cmd: Command) -> specula::Result<()> {
    match cmd {
        Command::Render { args, out, profile } => {
            let job = prepare(&args)?;
            if !job.method.is_gpu() {
                let (img, ms) = render_reference(&job.scene, &job.quality, (job.width, job.height))?;
                write_image(&out, &img)?;
                println!("{}", reference_summary(&job.quality, job.width, job.height, ms));
                if let Some(p) = profile {
                    let passes = [reference_timing(ms)];
                    std::fs::write(&p, specula::profile::chrome_trace(&passes, &[], "CPU")).map_err(|e| specula::Error::io(&p, e))?;
                }
                return Ok(());
            }
            let ctx = context(args.validate, &args.device)?;
            let frame = specula::render(&ctx, &job.scene, job.method, &job.quality, (job.width, job.height), (args.warmup, args.frames))?;
            write_image(&out, &frame.image)?;
            println!("{} on {} ({}), {}x{}", job.method.name(), ctx.device_name, ctx.driver_info, job.width, job.height);
            print!("{}", specula::profile::table(&frame.passes, &frame.memory));
            if let Some(p) = profile {
                let json = specula::profile::chrome_trace(&frame.passes, &frame.memory, &ctx.device_name);
                std::fs::write(&p, json).map_err(|e| specula::Error::io(&p, e))?;
            }
            if args.validate {
                println!("validation: {} error(s), {} warning(s)", ctx.validation.error_count(), ctx.validation.warning_count());
            }
            Ok(())
        }
        Command::Info { scene: path } => {
            let s = scene::load(&path)?;
            print!("{}", info(&s));
            Ok(())
        }
        Command::Plan { args } => {
            let job = prepare(&args)?;
            let p = specula::plan(&job.scene, job.method, &job.quality);
            println!("{}", serde_json::to_string_pretty(&p).unwrap_or_default());
            Ok(())
        }
        Command::Knobs => {
            println!("methods: {}", Method::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "));
            println!("\n{:<20} {:<22} {:<9} description", "knob", "values", "default");
            for k in specula::quality::KNOBS {
                println!("{:<20} {:<22} {:<9} {}", k.name, k.values, k.default, k.doc);
            }
            Ok(())
        }
        Command::Demo { outdir, size, validate, device } => demo(&outdir, &size, validate, &device),
        Command::Bench { args, sweep } => bench(&args, sweep.as_deref()),
        Command::Compare { test, reference, error_image } => compare(&test, &reference, error_image.as_deref()),
        Command::Tradeoff { args, sweep, methods, out } => tradeoff(&args, &sweep, &methods, &out),
    }
}

fn info(s: &Scene) -> String {
    use std::fmt::Write as _;
    let mut o = String::new();
    let b = s.bounds();
    let _ = writeln!(o, "meshes: {} ({} triangles)", s.meshes.len(), s.triangle_count());
    for m in &s.meshes {
        let mb = m.bounds();
        let _ = writeln!(
            o,
            "  {:<28} {:>7} tris  material {:<3} box [{:.3} {:.3} {:.3}]..[{:.3} {:.3} {:.3}]",
            m.name,
            m.triangle_count(),
            m.material,
            mb.min.x,
            mb.min.y,
            mb.min.z,
            mb.max.x,
            mb.max.y,
            mb.max.z
        );
    }
    let _ = writeln!(o, "materials: {}", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let detail = match m.kind {
            scene::SurfaceKind::Diffuse => format!("base {:?} emissive {:?}", m.base_color.to_array(), m.emissive.to_array()),
            scene::SurfaceKind::Mirror { nu, kappa } => format!("nu {:?} kappa {:?}", nu.to_array(), kappa.to_array()),
            scene::SurfaceKind::Dielectric { ior, .. } => format!("ior {ior}"),
        };
        let _ = writeln!(o, "  [{i}] {:<20} {:<24} {detail}", m.name, m.kind.label());
    }
    let _ = writeln!(o, "textures: {}", s.textures.len());
    let _ = writeln!(o, "lights: {}", s.lights.len());
    for l in &s.lights {
        let _ = writeln!(
            o,
            "  {:<20} {:?} at {:?} dir {:?} intensity {:?}",
            l.name,
            l.kind,
            l.position.to_array(),
            l.direction.to_array(),
            l.intensity.to_array()
        );
    }
    match &s.camera {
        Some(c) => {
            let _ = writeln!(
                o,
                "camera: at {:?} looking {:?}, yfov {:.1}°",
                c.position.to_array(),
                c.forward().to_array(),
                c.yfov.to_degrees()
            );
        }
        None => {
            let _ = writeln!(o, "camera: none (a default camera frames the bounds)");
        }
    }
    let _ = writeln!(o, "bounds: [{:.3} {:.3} {:.3}]..[{:.3} {:.3} {:.3}]", b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z);
    o
}

/// The README's main job: every method on the demo scene, images and a timing table.
fn demo(outdir: &Path, size: &str, validate: bool, device: &Option<String>) -> specula::Result<()> {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo/demo.gltf");
    let scene = scene::load(&scene_path)?;
    let (w, h) = parse_size(size)?;
    std::fs::create_dir_all(outdir).map_err(|e| specula::Error::io(outdir, e))?;
    let ctx = context(validate, device)?;
    let mut report = format!("specula demo: {} at {w}x{h} on {} ({})\n\n", scene_path.display(), ctx.device_name, ctx.driver_info);
    let mut images: Vec<(&str, specula::vk::ImageData)> = Vec::new();
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
    write_composite(outdir, &images, w, h)?;
    report += &format!("side by side: {}, {}\n", outdir.join("methods.png").display(), outdir.join("methods.svg").display());
    print!("{report}");
    let table = outdir.join("timings.txt");
    std::fs::write(&table, &report).map_err(|e| specula::Error::io(&table, e))?;
    Ok(())
}

/// `specula bench`: every variant in the same process and run, so the machine's noise
/// affects them alike; compare the ratios, not the absolute figures.
fn bench(args: &RenderArgs, sweep: Option<&str>) -> specula::Result<()> {
    let job = prepare(args)?;
    let variants: Vec<(String, Quality)> = match sweep {
        None => vec![("default".into(), job.quality.clone())],
        Some(s) => {
            let (key, values) = s.split_once('=').ok_or_else(|| specula::Error::invalid("--sweep", "expected knob=v1,v2,..."))?;
            values
                .split(',')
                .map(|v| {
                    let mut q = job.quality.clone();
                    q.set(key, v)?;
                    Ok((format!("{key}={v}"), q))
                })
                .collect::<specula::Result<_>>()?
        }
    };
    if !job.method.is_gpu() {
        println!(
            "{} on the CPU ({} threads), {}x{}, median of {} renders",
            job.method.name(),
            rayon::current_num_threads(),
            job.width,
            job.height,
            args.frames.max(1)
        );
        let mut base = None;
        for (label, q) in variants {
            let mut times = Vec::new();
            for _ in 0..args.frames.max(1) {
                times.push(render_reference(&job.scene, &q, (job.width, job.height))?.1);
            }
            times.sort_by(|a, b| a.total_cmp(b));
            let ms = times[times.len() / 2];
            let b = *base.get_or_insert(ms);
            println!("== {label}: {ms:.1} ms CPU ({:.2}x the first variant)", ms / b);
        }
        return Ok(());
    }
    let ctx = context(args.validate, &args.device)?;
    println!(
        "{} on {} ({}), {}x{}, median of {} frames after {} warm-up",
        job.method.name(),
        ctx.device_name,
        ctx.driver_info,
        job.width,
        job.height,
        args.frames,
        args.warmup
    );
    let mut base = None;
    for (label, q) in variants {
        let f = specula::render(&ctx, &job.scene, job.method, &q, (job.width, job.height), (args.warmup, args.frames))?;
        let ms = f.gpu_ms();
        let b = *base.get_or_insert(ms);
        println!(
            "\n== {label}: frame {ms:.3} ms GPU ({:.2}x the first variant), {:.2} MiB device memory",
            ms / b,
            f.memory_bytes() as f64 / 1048576.0
        );
        for p in &f.passes {
            println!("   {:<22} {:>9.3} ms GPU {:>8.3} ms CPU", p.name, p.gpu_ms, p.cpu_ms);
        }
    }
    Ok(())
}

/// The exact CPU reference, timed (wall-clock milliseconds).
fn render_reference(scene: &Scene, quality: &Quality, size: (u32, u32)) -> specula::Result<(ImageData, f64)> {
    let t = std::time::Instant::now();
    let img = specula::reference::render_reference(scene, quality, size)?;
    Ok((img, t.elapsed().as_secs_f64() * 1e3))
}

fn reference_timing(ms: f64) -> PassTiming {
    PassTiming { name: specula::plan::REFERENCE_PASS.into(), gpu_ms: 0.0, cpu_ms: ms, gpu_start_ms: 0.0 }
}

fn reference_summary(q: &Quality, w: u32, h: u32, ms: f64) -> String {
    format!(
        "reference on the CPU ({} threads), {w}x{h}, {} spp, depth {}, fresnel {:?}: {ms:.1} ms",
        rayon::current_num_threads(),
        q.spp,
        q.depth,
        q.fresnel
    )
}

fn read_linear(path: &Path) -> specula::Result<ImageData> {
    let e = scene::load_environment(path)?;
    Ok(ImageData { width: e.width, height: e.height, layers: 1, channels: 4, data: e.rgba32f })
}

/// `specula compare`: the metrics of specula::metrics, and the FLIP map in false colour.
fn compare(test: &Path, reference: &Path, error_image: Option<&Path>) -> specula::Result<()> {
    let (t, r) = (read_linear(test)?, read_linear(reference)?);
    let e = specula::metrics::compare(&t, &r)?;
    println!("{} vs {} ({}x{})", test.display(), reference.display(), t.width, t.height);
    println!("RMSE      {:.6}", e.rmse);
    println!("PSNR      {:.2} dB", e.psnr);
    println!("max |Δ|   {:.6}", e.max_abs);
    println!("p99 |Δ|   {:.6}", e.p99_abs);
    println!("mean FLIP {:.6}", e.flip);
    if let Some(path) = error_image {
        specula::metrics::write_error_png(path, &specula::metrics::flip_map(&t, &r)?, t.width, t.height)?;
        println!("error image: {}", path.display());
    }
    Ok(())
}

/// `specula tradeoff`: the reference once, then every GPU method × every sweep variant,
/// timed and compared; CSV, SVG plot and the images into `out`.
fn tradeoff(a: &TradeoffArgs, sweeps: &[String], only: &[String], out: &Path) -> specula::Result<()> {
    use specula::tradeoff::{csv, plot_svg, variants, Row, Sweep};
    let render_args = RenderArgs {
        scene: a.scene.clone(),
        method: Method::ALL[0].name().into(),
        size: a.size.clone(),
        quality: a.quality.clone(),
        env: a.env.clone(),
        camera_pos: None,
        camera_target: None,
        fov: 60.0,
        validate: a.validate,
        device: a.device.clone(),
        warmup: a.warmup,
        frames: a.frames,
    };
    let job = prepare(&render_args)?;
    let sweeps: Vec<Sweep> = sweeps.iter().map(|s| Sweep::parse(s)).collect::<specula::Result<_>>()?;
    let variants = variants(&job.quality, &sweeps)?;
    let mut methods: Vec<Method> = Method::ALL.iter().copied().filter(|m| m.is_gpu()).collect();
    if !only.is_empty() {
        let wanted = only.iter().map(|n| Method::parse(n)).collect::<specula::Result<Vec<_>>>()?;
        if let Some(m) = wanted.iter().find(|m| !m.is_gpu()) {
            return Err(specula::Error::invalid("--method", format!("'{}' is the reference itself", m.name())));
        }
        methods.retain(|m| wanted.contains(m));
    }
    std::fs::create_dir_all(out).map_err(|e| specula::Error::io(out, e))?;
    let (w, h) = (job.width, job.height);

    let bar = indicatif::ProgressBar::new((1 + methods.len() * variants.len()) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} [{elapsed_precise}] {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(format!("reference ({} spp, depth {})", job.quality.spp, job.quality.depth));
    let (reference, ref_ms) = render_reference(&job.scene, &job.quality, (w, h))?;
    write_image(&out.join("reference.exr"), &reference)?;
    write_image(&out.join("reference.png"), &reference)?;
    bar.inc(1);

    let ctx = context(a.validate, &a.device)?;
    let mut rows = Vec::new();
    for &method in &methods {
        for (label, q) in &variants {
            bar.set_message(format!("{} {label}", method.name()));
            let frame = specula::render(&ctx, &job.scene, method, q, (w, h), (a.warmup.max(1), a.frames.max(1)))?;
            let errors = specula::metrics::compare(&frame.image, &reference)?;
            let stem = format!("{}-{}", method.name(), label.replace([' ', '=', ',', ';', '/'], "_"));
            write_image(&out.join(format!("{stem}.png")), &frame.image)?;
            rows.push(Row::new(method.name(), label, &frame.passes, errors));
            bar.inc(1);
        }
    }
    bar.finish_and_clear();

    let csv_path = out.join("tradeoff.csv");
    let device = format!("{} ({})", ctx.device_name, ctx.driver_info);
    std::fs::write(&csv_path, csv(&rows, &device)).map_err(|e| specula::Error::io(&csv_path, e))?;
    let svg_path = out.join("tradeoff.svg");
    let title =
        format!("{} at {w}x{h} on {}: mean FLIP vs GPU time", a.scene.file_name().unwrap_or_default().to_string_lossy(), ctx.device_name);
    plot_svg(&svg_path, &rows, &title)?;
    println!(
        "{} on {} ({}), {w}x{h}, median of {} frames after {} warm-up",
        a.scene.display(),
        ctx.device_name,
        ctx.driver_info,
        a.frames.max(1),
        a.warmup.max(1)
    );
    println!("{}", reference_summary(&job.quality, w, h, ref_ms));
    println!("\n{:<10} {:<40} {:>10} {:>10} {:>9} {:>9} {:>9}", "method", "knobs", "frame ms", "RMSE", "PSNR dB", "FLIP", "p99");
    for r in &rows {
        let e = &r.errors;
        println!(
            "{:<10} {:<40} {:>10.3} {:>10.5} {:>9.2} {:>9.5} {:>9.5}",
            r.method, r.knobs, r.frame_ms, e.rmse, e.psnr, e.flip, e.p99_abs
        );
    }
    println!("\nwrote {} and {}", csv_path.display(), svg_path.display());
    if a.validate {
        println!("validation: {} error(s), {} warning(s)", ctx.validation.error_count(), ctx.validation.warning_count());
    }
    Ok(())
}

/// The demo's contact sheet: every method's image in a grid of four columns, as
/// `methods.png` and as `methods.svg` (the same grid with each method's name, referencing
/// the per-method PNGs beside it).
fn write_composite(outdir: &Path, images: &[(&str, specula::vk::ImageData)], w: u32, h: u32) -> specula::Result<()> {
    let cols = 4u32.min(images.len() as u32).max(1);
    let rows = (images.len() as u32).div_ceil(cols);
    let (sw, sh) = (cols * w, rows * h);
    let mut sheet = vec![0f32; (sw * sh * 4) as usize];
    for (i, (_, img)) in images.iter().enumerate() {
        let (ox, oy) = ((i as u32 % cols) * w, (i as u32 / cols) * h);
        for y in 0..h {
            let src = (y * w * 4) as usize;
            let dst = (((oy + y) * sw + ox) * 4) as usize;
            sheet[dst..dst + (w * 4) as usize].copy_from_slice(&img.data[src..src + (w * 4) as usize]);
        }
    }
    scene::write_png_srgb(&outdir.join("methods.png"), sw, sh, &sheet)?;
    let label = 24;
    let mut svg =
        format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{sw}\" height=\"{}\" style=\"background:#111\">\n", rows * (h + label));
    for (i, (name, _)) in images.iter().enumerate() {
        let (x, y) = ((i as u32 % cols) * w, (i as u32 / cols) * (h + label));
        svg += &format!(
            "<text x=\"{}\" y=\"{}\" fill=\"#eee\" font-family=\"sans-serif\" font-size=\"16\">{name}</text>\n<image x=\"{x}\" y=\"{}\" width=\"{w}\" height=\"{h}\" href=\"{name}.png\"/>\n",
            x + 6,
            y + 17,
            y + label
        );
    }
    svg += "</svg>\n";
    let path = outdir.join("methods.svg");
    std::fs::write(&path, svg).map_err(|e| specula::Error::io(&path, e))
}
