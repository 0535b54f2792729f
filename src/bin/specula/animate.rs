//! `specula animate`: a frame sequence of a scene's glTF animations through one renderer —
//! each frame poses the scene (`Scene::set_time`), hands it to `Renderer::update`, and
//! renders, so only the maps whose inputs moved are regenerated. Writes
//! `frame_NNNN.png` + `.exr`, `frames.csv` (time, GPU ms, the maps rebuilt and why) and
//! `preview.gif`.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use crate::args::{context, prepare, write_image, RenderArgs};

/// An object moved at a constant velocity (`--slide OBJECT=DX,DY,DZ`).
struct Slide {
    mesh: usize,
    velocity: glam::Vec3,
    world: glam::Mat4,
}

/// Parses `--slide OBJECT=DX,DY,DZ` against the scene's object names.
fn slides(scene: &specula::scene::Scene, specs: &[String]) -> specula::Result<Vec<Slide>> {
    specs
        .iter()
        .map(|spec| {
            let bad = |why: String| specula::Error::invalid("--slide", format!("'{spec}': {why}"));
            let (name, v) = spec.rsplit_once('=').ok_or_else(|| bad("expected OBJECT=DX,DY,DZ".into()))?;
            let mesh = scene.meshes.iter().position(|m| m.name == name).ok_or_else(|| {
                let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
                bad(format!("no object named '{name}' (objects: {})", names.join(", ")))
            })?;
            let parts: Vec<f32> =
                v.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| bad(e.to_string()))?;
            match parts[..] {
                [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
                    Ok(Slide { mesh, velocity: glam::Vec3::new(x, y, z), world: scene.meshes[mesh].world })
                }
                _ => Err(bad(format!("expected three finite numbers, got '{v}'"))),
            }
        })
        .collect()
}

pub fn run(args: &RenderArgs, fps: f32, duration: Option<f32>, (slide, freeze): (&[String], bool), out: &Path) -> specula::Result<()> {
    if !(fps > 0.0 && fps <= 240.0) {
        return Err(specula::Error::invalid("--fps", format!("must be in (0, 240], got {fps}")));
    }
    let mut job = prepare(args)?;
    if job.cpu_method().is_some() {
        return Err(specula::Error::invalid(
            "--method",
            "animate renders on the GPU: the reference renders single frames (`specula render`)",
        ));
    }
    // Frames over time: maps are regenerated when what they see moved, unless asked otherwise.
    if !args.quality.iter().any(|q| q.trim_start().starts_with(specula::quality::FrameKnobs::map_updates)) {
        job.quality.frame.map_updates_always = false;
    }
    let duration = duration.unwrap_or_else(|| job.scene.animation.as_ref().map_or(2.0, |a| a.duration.max(1.0 / fps)));
    if !(duration > 0.0 && duration <= 3600.0) {
        return Err(specula::Error::invalid("--duration", format!("must be in (0, 3600] seconds, got {duration}")));
    }
    if job.scene.animation.is_none() && slide.is_empty() {
        eprintln!("specula: note: {} has no animations: every frame is the same pose", args.scene.display());
    }
    let slides = {
        let mut first = job.scene.clone();
        first.set_time(0.0)?;
        slides(&first, slide)?
    };
    let frames = ((duration * fps).round() as u32).max(1);
    std::fs::create_dir_all(out).map_err(|e| specula::Error::io(out, e))?;
    let ctx = context(args.validate, &args.device)?;
    let mut scene = job.scene.clone();
    scene.set_time(0.0)?;
    let plan = job.plan(&job.quality)?;
    let (w, h) = (job.width, job.height);
    let mut r = specula::Renderer::new(&ctx, &scene, plan, w, h)?;
    let mut csv = String::from("frame,time_s,gpu_ms,maps_rebuilt\n");
    let mut gif_frames = Vec::new();
    let (mut total_ms, mut rebuilt_frames) = (0.0, 0u32);
    let result = (|| -> specula::Result<()> {
        for k in 0..frames {
            let t = k as f32 / fps;
            scene.set_time(if freeze { 0.0 } else { t })?;
            for s in &slides {
                scene.set_object_transform(s.mesh, glam::Mat4::from_translation(s.velocity * t) * s.world)?;
            }
            let mut replanned = None;
            if let Err(e) = r.update(&scene) {
                // The pose changed the plan's structure (say, objects came into each other's
                // view and now compose through inter-object cycles): a renderer for this
                // pose takes over. A pose no renderer accepts fails with that renderer's error.
                let plan = specula::plan::plan_with(&scene, &job.choices, &job.quality)?;
                let fresh = specula::Renderer::new(&ctx, &scene, plan, w, h)?;
                r.destroy(&ctx);
                r = fresh;
                replanned = Some(e.to_string());
            }
            let f = r.render(&ctx)?;
            let stem = out.join(format!("frame_{k:04}"));
            write_image(&stem.with_extension("png"), &f.image)?;
            write_image(&stem.with_extension("exr"), &f.image)?;
            let mut maps: Vec<String> = f.map_updates.iter().map(|u| format!("{} ({})", u.stage, u.reason)).collect();
            if let Some(why) = replanned {
                maps.insert(0, format!("new renderer ({why})"));
            }
            let ms = f.gpu_ms();
            total_ms += ms;
            rebuilt_frames += !maps.is_empty() as u32;
            let _ = writeln!(csv, "{k},{t:.4},{ms:.3},\"{}\"", maps.join("; ").replace('"', "'"));
            gif_frames.push(preview_frame(&f.image, fps));
            let done = (k + 1) as usize * 30 / frames as usize;
            eprint!("\r[{}{}] {}/{frames} frames", "#".repeat(done), ".".repeat(30 - done), k + 1);
            let _ = std::io::stderr().flush();
        }
        eprintln!();
        Ok(())
    })();
    r.destroy(&ctx);
    result?;
    specula::output::write_file(&out.join("frames.csv"), csv.as_bytes())?;
    write_gif(&out.join("preview.gif"), gif_frames)?;
    println!(
        "{} on {} ({}), {w}x{h}: {frames} frames at {fps} fps, mean {:.2} ms GPU per frame; {rebuilt_frames} of {frames} frames rebuilt maps",
        job.label(),
        ctx.device_name,
        ctx.driver_info,
        total_ms / frames as f64
    );
    println!("wrote {} (frame_NNNN.png/.exr, frames.csv, preview.gif)", out.display());
    if args.validate {
        println!("validation: {} error(s), {} warning(s)", ctx.validation.error_count(), ctx.validation.warning_count());
    }
    Ok(())
}

/// One preview frame: sRGB, alpha opaque, shown for 1/fps seconds.
fn preview_frame(img: &specula::image::ImageData, fps: f32) -> image::Frame {
    let bytes: Vec<u8> = img
        .data
        .chunks_exact(4)
        .flat_map(|p| {
            [specula::scene::linear_to_srgb(p[0]), specula::scene::linear_to_srgb(p[1]), specula::scene::linear_to_srgb(p[2]), 255]
        })
        .collect();
    let rgba = image::RgbaImage::from_raw(img.width, img.height, bytes).unwrap_or_else(|| image::RgbaImage::new(1, 1));
    let delay = image::Delay::from_numer_denom_ms(1000, fps.round().max(1.0) as u32);
    image::Frame::from_parts(rgba, 0, 0, delay)
}

fn write_gif(path: &Path, frames: Vec<image::Frame>) -> specula::Result<()> {
    let mut bytes = Vec::new();
    {
        let mut enc = image::codecs::gif::GifEncoder::new_with_speed(&mut bytes, 10);
        let err = |e: image::ImageError| specula::Error::invalid(path.display().to_string(), format!("cannot encode the GIF: {e}"));
        enc.set_repeat(image::codecs::gif::Repeat::Infinite).map_err(err)?;
        enc.encode_frames(frames).map_err(err)?;
    }
    specula::output::write_file(path, &bytes)
}
