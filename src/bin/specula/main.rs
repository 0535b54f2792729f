//! The specula command line: render, view, info, plan, knobs, demo, bench, compare, tradeoff.
//! One file per subcommand; `args` holds what they share (argument structs, parsers, the
//! scene-and-knobs preparation, image output, the timed CPU reference).

mod animate;
mod args;
mod bench;
mod budget;
mod compare;
mod corpus;
mod demo;
mod info;
mod knobs;
mod plan;
mod raytrace;
mod render;
mod tradeoff;
#[cfg(feature = "viewer")]
mod view;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use args::{RenderArgs, TradeoffArgs};

#[derive(Parser)]
#[command(name = "specula", version, about = "Specular effects on the GPU through raw Vulkan")]
struct Cli {
    #[command(subcommand)]
    command: Command,
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
        #[command(flatten)]
        budget: budget::BudgetArgs,
    },
    /// List meshes, materials with their classification, lights, camera and bounds.
    Info { scene: PathBuf },
    /// Print the plan a scene gets: per object its method and why, maps, passes, knobs.
    Plan {
        #[command(flatten)]
        args: RenderArgs,
        /// Print JSON instead of the table.
        #[arg(long)]
        json: bool,
        /// Also print, per specular object, the candidates `auto` chose from: every method's
        /// predicted ms and PSNR on the Pareto front (none faster and more accurate).
        #[arg(long)]
        candidates: bool,
        #[command(flatten)]
        budget: budget::BudgetArgs,
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
        /// The scene both images show (at their size, from its camera): the errors are also
        /// reported per specular object, on all specular pixels and on the rest (issue 15),
        /// from the exact first hits of its pixels.
        #[arg(long)]
        scene: Option<PathBuf>,
        /// With --scene: restrict the error image to these pixels: `specular`,
        /// `non-specular` or an object's name.
        #[arg(long, requires = "scene")]
        mask: Option<String>,
    },
    /// The speed–accuracy trade-off: every GPU method (× every --sweep combination) timed
    /// and compared with the exact reference; writes tradeoff.csv and the figure
    /// tradeoff.svg + tradeoff.png (--metric psnr|flip against log time) to --out.
    Tradeoff {
        #[command(flatten)]
        args: TradeoffArgs,
        /// knob=v1,v2,... (repeatable: the combinations multiply); ref_point values split on ';'.
        #[arg(long)]
        sweep: Vec<String>,
        /// Vary one --sweep at a time from the base knobs (-q), each its own curve per
        /// method, named METHOD (KNOB), instead of every combination.
        #[arg(long)]
        each: bool,
        /// Only these methods (repeatable); default every GPU method but the O(N)-per-ray
        /// ray engine and ray hierarchy (minutes a frame on a CPU device: name them to run them).
        #[arg(long = "method")]
        methods: Vec<String>,
        /// Output directory.
        #[arg(long, default_value = "tradeoff")]
        out: PathBuf,
        /// Also fit the budgeted planner's per-object error and cost models from the study
        /// and write them (to --models, default SCENE.specula-models.json next to the scene).
        #[arg(long)]
        calibrate: bool,
        /// Where --calibrate writes the models.
        #[arg(long, requires = "calibrate")]
        models: Option<PathBuf>,
    },
    /// Measure the measuring planner's corpus (scenes generated in code): every method and
    /// knob variant against the exact tracer, object by object; writes the corpus file the
    /// error models are fitted on and prints their leave-one-scene-out accuracy.
    Corpus {
        /// The corpus file to write.
        #[arg(long, default_value = "assets/models/corpus.json")]
        out: PathBuf,
        /// Frame size WIDTHxHEIGHT.
        #[arg(long, default_value = "128x128")]
        size: String,
        /// Only these corpus scene numbers (comma-separated); default all.
        #[arg(long, value_delimiter = ',')]
        scenes: Vec<usize>,
        /// A knob variant to measure, `default` or `KNOB=VALUE ...` (repeatable); default the
        /// planner's candidates: default, cube_size=128/512, aa=msaa4, aa=ssaa2.
        #[arg(long = "variant")]
        variants: Vec<String>,
        /// Only these methods (repeatable; default every GPU method). Objects a method does
        /// not serve are measured under its fallback.
        #[arg(long = "method")]
        methods: Vec<String>,
        /// Join the measurements to this corpus file's (a re-measured sample replaces its
        /// old one) and write the whole to --out.
        #[arg(long)]
        merge: Option<PathBuf>,
        /// Measure nothing: evaluate the error models on this corpus file (leave-one-scene-out
        /// per ridge penalty and per method) and write the scatter to --figure.
        #[arg(long)]
        evaluate: Option<PathBuf>,
        /// With --evaluate: the scatter's path without extension (.svg and .png).
        #[arg(long, default_value = "docs/predicted-vs-measured")]
        figure: PathBuf,
        #[arg(long)]
        validate: bool,
        #[arg(long)]
        device: Option<String>,
    },
    /// Measure this device's unit costs for the planner (a few corpus scenes, every method,
    /// two sizes) and cache them (SPECULA_CACHE_DIR, else the user cache directory) or write
    /// them to --out. Runs by itself the first time `auto` meets a device.
    Calibrate {
        #[arg(long)]
        out: Option<PathBuf>,
        /// Also write the measurements the unit costs are fitted on (a corpus file)
        #[arg(long)]
        samples: Option<PathBuf>,
        /// Measure nothing: fit the unit costs from measurements written by --samples
        /// (after a change to the cost model; the device is the one they were measured on)
        #[arg(long, conflicts_with = "samples")]
        refit: Option<PathBuf>,
        /// Measure only what a move costs the BVH (the CPU's SAH build, the GPU's linear BVH
        /// and refit, a few seconds) and add it to this device's costs: those in --out if it
        /// exists (else the cache, the stored file or a full calibration), written back there
        #[arg(long, conflicts_with_all = ["samples", "refit"])]
        bvh_updates: bool,
        #[arg(long)]
        validate: bool,
        #[arg(long)]
        device: Option<String>,
    },
    /// Survey Table 1 measured for ray tracing in the original geometry: per scheme and
    /// scene size the CPU build, the GPU frame and the structure's memory (table1.csv,
    /// table1.svg in --out, log–log), the ray hierarchy's culling rate per tile size, and
    /// the default distance-map method's frame against bvh's on the demo scene.
    RaytraceBench {
        /// Triangles of the two specular spheres together (comma-separated).
        #[arg(long, default_value = "1000,10000,100000,1000000")]
        triangles: String,
        #[arg(long, default_value = "256x256")]
        size: String,
        #[arg(long, default_value_t = 4)]
        depth: u32,
        /// Seconds a scheme's frame may take before larger scenes are skipped for it.
        #[arg(long, default_value_t = 60.0)]
        budget_s: f64,
        #[arg(long, default_value_t = 3)]
        frames: u32,
        /// Image size of the distance-vs-bvh comparison.
        #[arg(long, default_value = "512x512")]
        headline_size: String,
        /// Parts to run (comma-separated): table1, culling, headline, mutual, moves (what a
        /// move costs bvh: the CPU's SAH rebuild, the GPU's linear BVH, the GPU refit).
        #[arg(long, default_value = "table1,culling,headline,mutual,moves")]
        parts: String,
        #[arg(long, default_value = "raytrace-bench")]
        out: PathBuf,
        #[arg(long)]
        device: Option<String>,
    },
    /// Render a frame sequence of a scene's glTF animations: PNG + EXR per frame, per-frame
    /// timings with the maps each frame rebuilt (OUT/frames.csv), an animated preview
    /// (OUT/preview.gif).
    Animate {
        #[command(flatten)]
        args: RenderArgs,
        /// Frames per second.
        #[arg(long, default_value_t = 24.0)]
        fps: f32,
        /// Seconds to render; default: the animation's duration (2 s without animations).
        #[arg(long)]
        duration: Option<f32>,
        /// Moves an object from its first pose at a constant velocity (units per second),
        /// e.g. `--slide box/0=0.2,0,0` (repeatable; it replaces that object's own animation):
        /// frames over time for any object, for profiling what a move rebuilds.
        #[arg(long = "slide", value_name = "OBJECT=DX,DY,DZ")]
        slides: Vec<String>,
        /// Holds the scene's own animations at their first pose (only `--slide` moves).
        #[arg(long)]
        freeze: bool,
        #[arg(long, default_value = "animation")]
        out: PathBuf,
    },
    /// Look at a scene in a window: fly or orbit, switch methods and knobs, per-pass timings
    /// live, F12 for a screenshot (PNG + EXR + the `specula render` command that repeats it).
    #[cfg(feature = "viewer")]
    View {
        #[command(flatten)]
        args: view::ViewArgs,
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

/// Output piped into a reader that stops early (`specula compare … | head -3`) ends the
/// process quietly, as other Unix tools do, instead of a panic in `println!`: Rust ignores
/// SIGPIPE by default, so the default action is restored first.
#[cfg(unix)]
fn restore_sigpipe() {
    extern "C" {
        fn signal(signum: i32, handler: usize) -> usize;
    }
    const SIGPIPE: i32 = 13;
    const SIG_DFL: usize = 0;
    // SAFETY: setting a signal's disposition to its default touches no Rust state.
    unsafe { signal(SIGPIPE, SIG_DFL) };
}

fn main() -> ExitCode {
    #[cfg(unix)]
    restore_sigpipe();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return parse_error(e),
    };
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("specula: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Help and version print as clap prints them (exit 0); every other argument error is one
/// line on stderr, exit 1, as every other error.
fn parse_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        use clap::CommandFactory;
        let names: Vec<String> = Cli::command().get_subcommands().map(|c| c.get_name().to_string()).collect();
        eprintln!("specula: a subcommand is required ({}; see specula --help)", names.join(", "));
        return ExitCode::FAILURE;
    }
    eprintln!("specula: {}", one_line(&e.render().to_string()));
    ExitCode::FAILURE
}

/// clap's message without its usage block, on one line: "error: a\n  b\n\ntip: c" → "a b; tip: c".
fn one_line(text: &str) -> String {
    let mut parts: Vec<String> = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("Usage:") || line.starts_with("For more information") {
            break;
        }
        if line.is_empty() {
            continue;
        }
        let line = line.strip_prefix("error: ").unwrap_or(line);
        if line.starts_with("tip:") {
            parts.push(format!("; {line}"));
        } else {
            parts.push(format!(" {line}"));
        }
    }
    specula::error::clip_long(parts.concat().trim_start_matches([' ', ';']))
}

fn run(cmd: Command) -> specula::Result<()> {
    match cmd {
        Command::Render { args, out, profile, budget } => render::run(&args, &out, profile.as_deref(), &budget),
        Command::Info { scene } => info::run(&scene),
        Command::Animate { args, fps, duration, slides, freeze, out } => animate::run(&args, fps, duration, (&slides, freeze), &out),
        Command::Plan { args, json, candidates, budget } => plan::run(&args, json, candidates, &budget),
        Command::Knobs => knobs::run(),
        Command::Demo { outdir, size, validate, device } => demo::run(&outdir, &size, validate, &device),
        Command::RaytraceBench { triangles, size, depth, budget_s, frames, headline_size, parts, out, device } => {
            raytrace::run(&triangles, &size, depth, budget_s, frames, &headline_size, &parts, &out, &device)
        }
        Command::Corpus { evaluate: Some(file), figure, .. } => corpus::run_evaluate(&file, &figure),
        Command::Corpus { out, size, scenes, variants, methods, merge, validate, device, .. } => {
            let pick = corpus::Selection { scenes: &scenes, variants: &variants, methods: &methods };
            corpus::run_corpus(&out, &size, pick, merge.as_deref(), validate, &device)
        }
        Command::Calibrate { out, bvh_updates: true, validate, device, .. } => corpus::run_bvh_updates(out.as_deref(), validate, &device),
        Command::Calibrate { out, samples, refit, validate, device, .. } => {
            corpus::run_calibrate(out.as_deref(), samples.as_deref(), refit.as_deref(), validate, &device)
        }
        #[cfg(feature = "viewer")]
        Command::View { args } => view::run(&args),
        Command::Bench { args, sweep } => bench::run(&args, sweep.as_deref()),
        Command::Compare { test, reference, error_image, scene, mask } => {
            compare::run(&test, &reference, error_image.as_deref(), scene.as_deref(), mask.as_deref())
        }
        Command::Tradeoff { args, sweep, each, methods, out, calibrate, models } => {
            let models = calibrate.then(|| models.unwrap_or_else(|| budget::default_models_path(&args.scene)));
            tradeoff::run(&args, &sweep, each, &methods, &out, models.as_deref())
        }
    }
}
