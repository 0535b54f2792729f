//! specula: mirror reflections, refractions and caustics on the GPU through raw Vulkan,
//! after Szirmay-Kalos et al., "Specular Effects on the GPU: State of the Art".

pub mod error;
pub mod scene;
pub mod scenes;

pub use error::{Error, Result};
pub mod cube;
pub mod demo;
pub mod docs;
pub mod frame;
pub mod gpu_scene;
pub mod image;
pub mod methods;
pub mod metrics;
pub mod optics;
pub mod output;
pub mod plan;
pub mod profile;
pub mod quality;
pub mod reference;
pub mod renderer;
pub mod shaders;
pub mod tradeoff;
pub mod vk;

pub use methods::{Choice, Method};
pub use plan::{plan, plan_with, Choices, Plan};
pub use quality::Quality;
pub use renderer::{Frame, MapUpdate, Renderer};
pub use scene::Scene;

/// Renders `scene` with `method` (or `Choice::Auto`) at `(width, height)`: `warmup` frames
/// (pipelines compile lazily on some drivers), then `frames` timed ones. Returns the last
/// frame with the median per pass.
pub fn render(
    ctx: &vk::Context,
    scene: &Scene,
    method: impl Into<Choice>,
    quality: &Quality,
    size: (u32, u32),
    frames: (u32, u32),
) -> Result<Frame> {
    let choices = Choices::all(method);
    let target = target_for(ctx, size);
    render_plan(ctx, scene, plan::plan_for(scene, &choices, quality, target.as_ref())?, size, frames)
}

/// What `auto` predicts for on `ctx` at `size`: the device's unit costs (cached, stored or
/// calibrated now: `tradeoff::costs_for`; a cache file that cannot be read is said on
/// stderr and replaced). `None` when the device cannot be calibrated (the nominal target
/// serves, and the error is said on stderr).
pub fn target_for(ctx: &vk::Context, size: (u32, u32)) -> Option<plan::predict::Target> {
    match tradeoff::costs_for(ctx, None, &mut |w| eprintln!("specula: {w}")) {
        Ok((costs, _)) => Some(plan::predict::Target { size, costs }),
        Err(e) => {
            eprintln!("specula: no unit costs for {}: {e}; auto predicts with the stored calibration's", ctx.device_name);
            None
        }
    }
}

/// Renders a plan (per-object methods: `plan_with`), as `render`.
pub fn render_plan(
    ctx: &vk::Context,
    scene: &Scene,
    plan: Plan,
    (width, height): (u32, u32),
    (warmup, frames): (u32, u32),
) -> Result<Frame> {
    render_frames(ctx, scene, plan, (width, height), (warmup, frames), |_, _| {})
}

/// As [`render_plan`], handing every frame (warm-up ones included, numbered from 0) to
/// `each` as it completes: what `specula render` prints of the maps each frame rebuilt.
pub fn render_frames(
    ctx: &vk::Context,
    scene: &Scene,
    plan: Plan,
    (width, height): (u32, u32),
    (warmup, frames): (u32, u32),
    mut each: impl FnMut(u32, &Frame),
) -> Result<Frame> {
    let mut r = Renderer::new(ctx, scene, plan, width, height)?;
    let result = (|| {
        for k in 0..warmup {
            each(k, &r.render(ctx)?);
        }
        let mut all = Vec::new();
        for k in 0..frames.max(1) {
            let f = r.render(ctx)?;
            each(warmup + k, &f);
            all.push(f);
        }
        let passes = profile::median_passes(&all);
        let mut last = all.pop().unwrap();
        last.passes = passes;
        Ok(last)
    })();
    r.destroy(ctx);
    result
}
pub mod ffi;
pub mod fuzzing;
pub mod search;
