//! A device's unit costs for the measuring planner: measured by rendering a few corpus
//! scenes with every method at two sizes (`specula calibrate`, or automatically the first
//! time a device is seen), fitted (`plan::predict::cost_model`), cached on disk per device
//! (`cost_model::cache_dir`, overridable) and kept in memory per process.

use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use super::corpus::{gpu_methods, measure, Measure};
use crate::error::Result;
use crate::methods::{RAY_ENGINE, RAY_HIERARCHY};
use crate::plan::predict::cost_model::{cache_dir, load_cached, store, CostModel, DeviceKey};
use crate::plan::predict::samples::{BvhUpdateSample, Corpus};
use crate::quality::Quality;
use crate::vk::Context;

/// The corpus scenes a calibration renders: mirrors, glass, a planar mirror, a thin pane,
/// near and far rooms, an occluder, a light, two objects, and tessellations from 600 to 10⁴
/// triangles.
pub const SCENES: [usize; 6] = [0, 3, 6, 7, 14, 22];
/// The scenes on which the knob variants are timed at the larger size too (a glass blob
/// with a mirror sphere and a light; a thin pane, a glass sphere and a glass blob behind an
/// occluder in a far room): solid, thin and mirror objects, 2·10³ to 10⁴ triangles.
pub const VARIANT_SCENES: [usize; 2] = [3, 22];
/// Its two frame sizes, 16× apart in pixels (screen-proportional costs are told from the
/// per-frame ones by the pair). On lavapipe a ray tracer's frame at 64² is mostly its
/// per-dispatch constant, and at 192² its pixels added too little above the noise to be
/// told apart: a calibration there predicted bvh's 512² frame on the concave mirror at its
/// 64² frame's 35 ms (measured 106).
pub const SIZES: [(u32, u32); 2] = [(64, 64), (256, 256)];

/// What a calibration renders.
pub fn plan() -> Measure {
    Measure {
        scenes: SCENES.to_vec(),
        sizes: SIZES.to_vec(),
        // The second variant tells the cube maps' texel costs and multisampling's per-sample
        // costs from the rest at once (they fall in separate terms: maps, camera work); the
        // third supersampling's; the fourth (the methods that read it, where the device has
        // ray queries) the hybrid search's; the fifth (on the lit scenes only) the caustics'
        // from the light's other costs (shadow maps, lit cube texels, shadow rays), which
        // otherwise always come together.
        variants: vec!["default".into(), "cube_size=128 aa=msaa4".into(), "aa=ssaa2".into(), "hybrid=rays".into(), "caustics=off".into()],
        methods: gpu_methods(),
        // The software ray engine and ray hierarchy take 50–100× bvh's time on lavapipe:
        // two scenes give their unit costs.
        sparse: vec![(RAY_ENGINE, 7), (RAY_HIERARCHY, 7)],
        variant_scenes: Some(VARIANT_SCENES.to_vec()),
        warmup: 1,
        // The median of three frames: with two, one slow frame moved a scene's time by up to
        // 1.7× between calibrations (corpus-22's bvh frame at 64²: 48 and 58 ms, 33–47 when
        // benched), and the fit took it for a per-triangle or per-dielectric cost.
        frames: 3,
        errors: false,
        // Every map regenerated every frame: what a frame costs when objects move (the
        // planner's frame budget is for that frame).
        base: {
            let mut q = Quality::default();
            q.frame.map_updates_always = true;
            q
        },
    }
}

/// Measures and fits `ctx`'s unit costs.
pub fn calibrate(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<CostModel> {
    calibrate_measured(ctx, progress).map(|(_, c)| c)
}

/// [`calibrate`], with the measurements the unit costs were fitted on.
pub fn calibrate_measured(ctx: &Context, progress: &mut dyn FnMut(&str)) -> Result<(Corpus, CostModel)> {
    let t = std::time::Instant::now();
    let mut corpus = measure(ctx, &plan(), progress)?;
    progress("what a move costs the BVH");
    corpus.bvh_updates = measure_bvh_updates(ctx, &BVH_LADDER)?;
    let c = CostModel::fit(&corpus, DeviceKey::of(ctx), t.elapsed().as_secs_f64());
    Ok((corpus, c))
}

/// Triangle counts at which a calibration times how the BVH follows moved geometry
/// (tessellated spheres; a few seconds on lavapipe in all).
pub const BVH_LADDER: [usize; 3] = [2_000, 20_000, 200_000];

/// Times each way a BVH follows moved geometry (`bvh_update`) over tessellated spheres of
/// each of `ladder`'s triangle counts, the median of 3: the CPU's SAH build (host ms; the
/// frame waits for it), a linear BVH built on the GPU and a refit on the GPU (GPU ms of their
/// passes).
pub fn measure_bvh_updates(ctx: &Context, ladder: &[usize]) -> Result<Vec<BvhUpdateSample>> {
    use crate::methods::raytrace::gpu::Intersector;
    use crate::methods::raytrace::lbvh::Work;
    use crate::methods::raytrace::{Scheme, TriangleList};
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mut out = Vec::new();
    for &n in ladder {
        // A uv sphere of `seg` segments and seg/2 rings has seg · (seg − 2) triangles.
        let seg = ((1.0 + (1.0 + n as f64).sqrt()).round() as u32).max(4);
        let mesh = crate::scene::shapes::uv_sphere("ladder", glam::Vec3::ZERO, 1.0, seg, seg / 2, 0);
        let tris: Vec<[glam::Vec3; 3]> = mesh.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| mesh.positions[t[k] as usize])).collect();
        let list = TriangleList::from_soup(tris)?;
        let triangles = list.len() as f64;
        let cpu = Scheme::Bvh { stackless: false, gpu: false };
        let mut sah = Vec::new();
        for _ in 0..3 {
            let t = std::time::Instant::now();
            cpu.build(&list)?;
            sah.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let gpu = Scheme::Bvh { stackless: false, gpu: true };
        let mut x = Intersector::new(ctx, gpu, &list, &gpu.build(&list)?)?;
        let timed = (|| {
            let mut lbvh = Vec::new();
            let mut refit = Vec::new();
            for _ in 0..3 {
                lbvh.push(x.update(ctx, &list, Work::Build)?);
                refit.push(x.update(ctx, &list, Work::Refit)?);
            }
            Ok::<_, crate::Error>((lbvh, refit))
        })();
        x.destroy(ctx);
        let (lbvh, refit) = timed?;
        for (way, ms) in [("sah", median(sah)), ("lbvh", median(lbvh)), ("refit", median(refit))] {
            out.push(BvhUpdateSample { way: way.into(), triangles, ms });
        }
    }
    Ok(out)
}

/// Where `ctx`'s costs came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// This process measured them.
    Memory,
    /// Read from this cache file.
    Cache(PathBuf),
    /// The stored corpus was measured on this very device (driver included).
    Stored,
    /// Calibrated now (and written to this cache file, if any).
    Calibrated(Option<PathBuf>),
}

/// Per device and cache directory, what this process found.
type Known = Mutex<Vec<((DeviceKey, Option<PathBuf>), Arc<CostModel>)>>;

fn known() -> &'static Known {
    static K: OnceLock<Known> = OnceLock::new();
    K.get_or_init(|| Mutex::new(Vec::new()))
}

/// `ctx`'s unit costs: from this process, the cache (`dir`, else `cost_model::cache_dir`),
/// the stored corpus when it was measured on this device, or a calibration run now (and
/// cached). A cache file that cannot be read is reported through `warn` and replaced.
/// Candidates this context cannot run are left out (a device key names the hardware and
/// driver, not what a host enabled: `ray-query` and the hybrid search need ray queries).
pub fn costs_for(ctx: &Context, dir: Option<PathBuf>, warn: &mut dyn FnMut(String)) -> Result<(Arc<CostModel>, Source)> {
    let (c, source) = costs_found(ctx, dir, warn)?;
    if ctx.ray_query.is_ok() {
        return Ok((c, source));
    }
    let mut runnable = (*c).clone();
    runnable.methods.retain(|name, _| {
        let method = crate::plan::predict::error_model::candidate_method(name);
        !crate::plan::predict::error_model::candidate_traces(name)
            && crate::methods::Method::parse(method).is_ok_and(|m| m.needs.missing_on(ctx).is_none())
    });
    Ok((Arc::new(runnable), source))
}

fn costs_found(ctx: &Context, dir: Option<PathBuf>, warn: &mut dyn FnMut(String)) -> Result<(Arc<CostModel>, Source)> {
    let key = DeviceKey::of(ctx);
    let dir = dir.or_else(cache_dir);
    let id = (key.clone(), dir.clone());
    if let Some((_, c)) = known().lock().ok().and_then(|k| k.iter().find(|(k2, _)| *k2 == id).cloned()) {
        return Ok((c, Source::Memory));
    }
    let remember = |c: CostModel| {
        let c = Arc::new(c);
        if let Ok(mut k) = known().lock() {
            k.push((id.clone(), c.clone()));
        }
        c
    };
    let mut corrupt = false;
    if let Some(d) = &dir {
        match load_cached(d, &key) {
            Ok(Some(c)) => return Ok((remember(c), Source::Cache(d.join(key.file_name())))),
            Ok(None) => {}
            Err(e) => {
                warn(format!("{e}: re-calibrating"));
                corrupt = true;
            }
        }
    }
    if let Some(c) = crate::plan::predict::stored_costs().filter(|c| c.key.label() == key.label()) {
        // The stored calibration is this device's: it replaces a cache file that could not
        // be read.
        if let (true, Some(d)) = (corrupt, &dir) {
            if let Err(e) = store(d, c) {
                warn(format!("could not replace the cache file: {e}"));
            }
        }
        return Ok((remember(c.clone()), Source::Stored));
    }
    // A calibration renders whole-scene methods only, which never ask for costs; this
    // guards against a future path that would (a calibration inside a calibration).
    thread_local!(static CALIBRATING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) });
    if CALIBRATING.with(|c| c.replace(true)) {
        return Err(crate::Error::invalid("calibration", "asked for unit costs while calibrating"));
    }
    let c = calibrate(ctx, &mut |_| {});
    CALIBRATING.with(|f| f.set(false));
    let c = c?;
    let written = match &dir {
        Some(d) => match store(d, &c) {
            Ok(p) => Some(p),
            Err(e) => {
                warn(format!("could not cache the calibration: {e}"));
                None
            }
        },
        None => None,
    };
    Ok((remember(c), Source::Calibrated(written)))
}
