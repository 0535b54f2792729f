//! What the subcommands share: the scene-and-knobs arguments, their parsers, the prepared
//! job, image output by extension and the timed CPU reference.

use std::path::{Path, PathBuf};

use glam::Vec3;
use specula::image::ImageData;
use specula::plan::{Choices, Plan};
use specula::scene::{self, Camera};
use specula::vk::{Context, DeviceOptions, PassTiming};
use specula::{Choice, Method, Quality, Scene};

#[derive(clap::Args, Clone)]
pub struct RenderArgs {
    /// glTF 2.0 scene (.gltf or .glb), or builtin:NAME (corner-mirror, concave-occluder,
    /// glass-1.1, glass-1.5, flat-glass, convex-mirror, caustic-ball, caustic-room, mirage, grin-lens, pool).
    pub scene: PathBuf,
    /// Rendering method of every specular object, or `auto`: the planner picks one per
    /// object (`specula knobs` lists methods and knobs).
    #[arg(long, default_value = "auto")]
    pub method: String,
    /// One object's method, NAME=METHOD (NAME: the glTF node or mesh name; repeatable);
    /// overrides --method and the scene file's extras.specula.method.
    #[arg(long = "object")]
    pub objects: Vec<String>,
    /// Output size WIDTHxHEIGHT.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    /// Accuracy knob key=value (repeatable).
    #[arg(long = "quality", short = 'q')]
    pub quality: Vec<String>,
    /// Equirectangular environment map (.exr, .hdr, .png, .jpg).
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Camera position x,y,z (overrides the scene's camera; with --camera-target).
    #[arg(long)]
    pub camera_pos: Option<String>,
    /// Camera target x,y,z.
    #[arg(long)]
    pub camera_target: Option<String>,
    /// Vertical field of view in degrees (with --camera-pos; default 60).
    #[arg(long)]
    pub fov: Option<f32>,
    /// Pose the scene at this time of its glTF animations (seconds).
    #[arg(long)]
    pub time: Option<f32>,
    /// Enable the Khronos validation layer; any validation error fails the command.
    #[arg(long)]
    pub validate: bool,
    /// Device name filter (substring, e.g. llvmpipe); default SPECULA_DEVICE or the first GPU.
    #[arg(long)]
    pub device: Option<String>,
    /// Untimed frames before the timed ones.
    #[arg(long, default_value_t = 1)]
    pub warmup: u32,
    /// Timed frames; the profile reports the median per pass.
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
}

#[derive(clap::Args, Clone)]
pub struct TradeoffArgs {
    /// glTF 2.0 scene (.gltf or .glb), or builtin:NAME (corner-mirror, concave-occluder,
    /// glass-1.1, glass-1.5, flat-glass, convex-mirror, caustic-ball, caustic-room, mirage, grin-lens, pool).
    pub scene: PathBuf,
    /// Output size WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256")]
    pub size: String,
    /// Base accuracy knobs key=value (repeatable); spp and depth set the reference's.
    #[arg(long = "quality", short = 'q')]
    pub quality: Vec<String>,
    /// Equirectangular environment map.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Untimed frames before the timed ones (at least 1: the first frame uploads the scene).
    #[arg(long, default_value_t = 2)]
    pub warmup: u32,
    /// Timed frames per configuration; the median per pass is reported.
    #[arg(long, default_value_t = 5)]
    pub frames: u32,
    /// The figure's error axis: psnr (higher is better) or flip (mean FLIP, lower is better).
    #[arg(long, default_value = "psnr")]
    pub metric: String,
    /// Enable the Khronos validation layer.
    #[arg(long)]
    pub validate: bool,
    /// Device name filter (substring).
    #[arg(long)]
    pub device: Option<String>,
}

pub fn parse_vec3(what: &str, s: &str) -> specula::Result<Vec3> {
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

pub fn parse_size(s: &str) -> specula::Result<(u32, u32)> {
    let bad = || specula::Error::invalid("--size", format!("'{s}' is not WIDTHxHEIGHT"));
    let (w, h) = s.split_once('x').ok_or_else(bad)?;
    let (w, h) = (w.parse::<u32>().map_err(|_| bad())?, h.parse::<u32>().map_err(|_| bad())?);
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(specula::Error::invalid("--size", format!("{w}x{h} is outside 1..=16384")));
    }
    Ok((w, h))
}

/// A scene with its environment and camera overrides applied, the knobs, the methods and
/// the output size.
pub struct Job {
    pub scene: Scene,
    pub choices: Choices,
    pub quality: Quality,
    pub width: u32,
    pub height: u32,
    /// The device's unit costs for `auto` (found once, by `Job::target`).
    pub target: std::sync::OnceLock<Option<specula::plan::predict::Target>>,
}

impl Job {
    /// What `auto` predicts for: the job's size on the first device that opens (its unit costs),
    /// else on the stored calibration's device.
    pub fn target(&self) -> Option<specula::plan::predict::Target> {
        let t = self.target.get_or_init(|| {
            let ctx = specula::vk::Context::new(&specula::vk::DeviceOptions::default()).ok();
            ctx.as_ref().and_then(|c| specula::target_for(c, (1, 1)))
        });
        t.clone().map(|t| specula::plan::predict::Target { size: (self.width, self.height), ..t }).or_else(|| {
            specula::plan::predict::Target::nominal().map(|n| specula::plan::predict::Target { size: (self.width, self.height), ..n })
        })
    }

    /// The CPU method, when the whole scene asks for one (the reference).
    pub fn cpu_method(&self) -> Option<Method> {
        match self.choices.method {
            Choice::Method(m) if !m.is_gpu() => Some(m),
            _ => None,
        }
    }

    pub fn plan(&self, quality: &Quality) -> specula::Result<Plan> {
        let target = self.target();
        specula::plan::plan_for(&self.scene, &self.choices, quality, target.as_ref())
    }

    /// What was asked for, for headings: the method or `auto`, plus the overrides.
    pub fn label(&self) -> String {
        let mut s = self.choices.method.name().to_string();
        for (n, m) in &self.choices.objects {
            s += &format!(" {n}={}", m.name());
        }
        s
    }
}

/// `NAME=METHOD` of --object.
pub fn parse_object(s: &str) -> specula::Result<(String, Method)> {
    let (n, m) = s
        .split_once('=')
        .ok_or_else(|| specula::Error::invalid("--object", format!("'{}' is not NAME=METHOD", specula::error::clip(s))))?;
    let m = Method::parse(m.trim())?;
    if !m.is_gpu() {
        return Err(specula::Error::invalid("--object", format!("'{}' renders on the CPU, not per object", m.name())));
    }
    Ok((n.trim().to_string(), m))
}

/// Loads a glTF file, or with `builtin:NAME` one of the scenes built in code
/// (`specula::scenes::builtin`); an unknown builtin name is an error that lists the names.
pub fn load_scene(path: &Path) -> specula::Result<Scene> {
    let Some(name) = path.to_str().and_then(|p| p.strip_prefix("builtin:")) else { return scene::load(path) };
    specula::scenes::builtin(name).unwrap_or_else(|| {
        Err(specula::Error::invalid(
            "scene",
            format!(
                "'builtin:{}' names no built-in scene (known: {}, and the planner's corpus builtin:corpus-N, N 0..=9999)",
                specula::error::clip(name),
                specula::scenes::BUILTIN.iter().map(|n| format!("builtin:{n}")).collect::<Vec<_>>().join(", ")
            ),
        ))
    })
}

/// Loads a scene that has something to render; otherwise says what it lacks and where.
pub fn load_renderable(path: &Path) -> specula::Result<Scene> {
    let scene = load_scene(path)?;
    renderable(path, &scene)?;
    Ok(scene)
}

/// `Scene::check_renderable`, naming the file.
pub fn renderable(path: &Path, scene: &Scene) -> specula::Result<()> {
    scene.check_renderable().map_err(|e| match e {
        specula::Error::InvalidInput { message, .. } => specula::Error::scene(path.display().to_string(), "(scene)", message),
        other => other,
    })
}

pub fn prepare(a: &RenderArgs) -> specula::Result<Job> {
    let mut scene = load_renderable(&a.scene)?;
    if let Some(t) = a.time {
        scene.set_time(t).map_err(|e| match e {
            specula::Error::InvalidInput { message, .. } => specula::Error::invalid("--time", message),
            other => other,
        })?;
    }
    if let Some(env) = &a.env {
        scene.set_environment(scene::load_environment(env)?)?;
    }
    if let Some(pos) = &a.camera_pos {
        let eye = parse_vec3("--camera-pos", pos)?;
        let target = a.camera_target.as_deref().map(|t| parse_vec3("--camera-target", t)).transpose()?.unwrap_or(eye + Vec3::NEG_Z);
        let fov = a.fov.unwrap_or(60.0);
        if !(fov > 0.0 && fov < 180.0) {
            return Err(specula::Error::invalid("--fov", format!("must be in (0, 180) degrees, got {fov}")));
        }
        let znear = scene.camera.map_or(0.01, |c| c.znear);
        scene.camera = Some(Camera::checked(eye, target, fov.to_radians(), znear).map_err(|e| match e {
            specula::Error::InvalidInput { what, message } => specula::Error::invalid(
                what.replace("camera.position", "--camera-pos").replace("camera.target", "--camera-target"),
                message,
            ),
            other => other,
        })?);
    } else if a.camera_target.is_some() || a.fov.is_some() {
        let which = if a.camera_target.is_some() { "--camera-target" } else { "--fov" };
        return Err(specula::Error::invalid(which, "needs --camera-pos (the scene's own camera is used otherwise)"));
    }
    // These commands time a static scene's frames: its maps are regenerated every frame
    // (what a frame costs) unless `-q map_updates=on_change` asks for steady state.
    let mut quality = {
        let mut knobs = Quality::default();
        knobs.frame.map_updates_always = true;
        knobs
    };
    for q in &a.quality {
        quality.set_pair(q)?;
    }
    let (width, height) = parse_size(&a.size)?;
    let objects = a.objects.iter().map(|o| parse_object(o)).collect::<specula::Result<Vec<_>>>()?;
    let choices = Choices { method: Choice::parse(&a.method)?, objects };
    Ok(Job { scene, choices, quality, width, height, target: Default::default() })
}

pub fn context(validate: bool, device: &Option<String>) -> specula::Result<Context> {
    Context::new(&DeviceOptions { validation: validate, device_filter: device.clone(), ..Default::default() })
}

pub fn write_image(path: &Path, img: &ImageData) -> specula::Result<()> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("exr") => img.write_exr(path),
        Some("png") => img.write_png_srgb(path),
        _ => Err(specula::Error::invalid("--out", format!("{}: use .png or .exr", path.display()))),
    }
}

/// The exact CPU reference, timed (wall-clock milliseconds).
pub fn render_reference(scene: &Scene, quality: &Quality, size: (u32, u32)) -> specula::Result<(ImageData, f64)> {
    let t = std::time::Instant::now();
    let img = specula::reference::render_reference(scene, quality, size)?;
    Ok((img, t.elapsed().as_secs_f64() * 1e3))
}

pub fn reference_timing(ms: f64) -> PassTiming {
    PassTiming { name: specula::plan::REFERENCE_PASS.into(), gpu_ms: 0.0, cpu_ms: ms, gpu_start_ms: 0.0 }
}

pub fn reference_summary(q: &Quality, w: u32, h: u32, ms: f64) -> String {
    format!(
        "reference on the CPU ({} threads), {w}x{h}, {} spp, depth {}, fresnel {:?}: {ms:.1} ms",
        rayon::current_num_threads(),
        q.reference.spp,
        q.frame.depth,
        q.frame.fresnel
    )
}
