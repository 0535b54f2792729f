//! `specula corpus` (measure the generated corpus: the measuring planner's error data) and
//! `specula calibrate` (this device's unit costs, cached).

use std::path::Path;

use specula::plan::predict::error_model;
use specula::scenes::corpus;
use specula::tradeoff::{self, Measure};
use specula::vk::{Context, DeviceOptions};

use crate::args::parse_size;

/// Measures corpus scenes `scenes` (every one when empty) and writes the corpus file; prints
/// the error models' leave-one-scene-out accuracy.
/// The knob variants `specula corpus` measures by default: the cube maps' size and the
/// frame's anti-aliasing (the planner's candidates, `plan::predict::budget_variants`).
pub fn default_variants() -> Vec<String> {
    specula::plan::predict::budget_variants()
}

/// `variants` empty: [`default_variants`]; `methods` empty: every GPU method; `merge`: the
/// corpus file whose measurements the new ones join (replacing those they re-measure).
/// What `specula corpus` measures: scene numbers, knob variants and methods (each empty:
/// all of them).
pub struct Selection<'a> {
    pub scenes: &'a [usize],
    pub variants: &'a [String],
    pub methods: &'a [String],
}

pub fn run_corpus(
    out: &Path,
    size: &str,
    pick: Selection,
    merge: Option<&Path>,
    validate: bool,
    device: &Option<String>,
) -> specula::Result<()> {
    let Selection { scenes, variants, methods } = pick;
    let size = parse_size(size)?;
    let variants = if variants.is_empty() { default_variants() } else { variants.to_vec() };
    for v in variants.iter().filter(|v| *v != "default") {
        specula::plan::budget::variant_quality(&specula::Quality::default(), v)?;
    }
    let old = match merge {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| specula::Error::io(p, e))?;
            Some(specula::plan::predict::samples::Corpus::parse(&text, &p.display().to_string())?)
        }
        None => None,
    };
    let ctx = Context::new(&DeviceOptions { validation: validate, device_filter: device.clone(), ..Default::default() })?;
    let cfg = Measure {
        scenes: if scenes.is_empty() { (0..corpus::SIZE).collect() } else { scenes.to_vec() },
        sizes: vec![size],
        variants,
        methods: if methods.is_empty() {
            tradeoff::gpu_methods()
        } else {
            methods.iter().map(|m| specula::Method::parse(m)).collect::<specula::Result<Vec<_>>>()?
        },
        sparse: vec![(specula::methods::RAY_ENGINE, 12), (specula::methods::RAY_HIERARCHY, 12)],
        variant_scenes: None,
        warmup: 1,
        frames: 1,
        base: specula::Quality::default(),
        errors: true,
    };
    let t = std::time::Instant::now();
    let measured = tradeoff::measure(&ctx, &cfg, &mut |s| eprintln!("[{:7.1} s] {s}", t.elapsed().as_secs_f64()))?;
    let c = match old {
        Some(mut c) => {
            c.merge(measured);
            c
        }
        None => measured,
    };
    specula::output::write_file(out, c.to_json().as_bytes())?;
    let held = error_model::leave_one_scene_out(&c.samples);
    let (median, p90) = error_model::abs_error_quantiles(&held);
    println!(
        "{} samples of {} scenes at {}x{} on {} in {:.0} s; wrote {}",
        c.samples.len(),
        c.scenes().len(),
        size.0,
        size.1,
        c.device.label(),
        t.elapsed().as_secs_f64(),
        out.display()
    );
    println!(
        "error models, leave-one-scene-out: |predicted − measured| median {median:.2} dB, 90th percentile {p90:.2} dB ({} predictions)",
        held.len()
    );
    let validation = (ctx.validation.error_count(), ctx.validation.warning_count());
    if validation.0 > 0 {
        return Err(specula::Error::invalid("validation", format!("{} validation errors", validation.0)));
    }
    Ok(())
}

/// Writes unit costs to `out`, or to the cache; where they went.
fn write_costs(out: Option<&Path>, c: &specula::plan::predict::cost_model::CostModel) -> specula::Result<std::path::PathBuf> {
    match out {
        Some(p) => {
            specula::output::write_file(p, c.to_json().as_bytes())?;
            Ok(p.to_path_buf())
        }
        None => {
            let dir = specula::plan::predict::cost_model::cache_dir().ok_or_else(|| {
                specula::Error::invalid("cache", "no SPECULA_CACHE_DIR, XDG_CACHE_HOME or HOME to cache into: pass --out")
            })?;
            specula::plan::predict::cost_model::store(&dir, c)
        }
    }
}

/// `specula calibrate --bvh-updates`: measures what a move costs the BVH on this device and
/// adds it to its unit costs (`out` if it exists, else those `auto` would use), written to
/// `out` or the cache.
pub fn run_bvh_updates(out: Option<&Path>, validate: bool, device: &Option<String>) -> specula::Result<()> {
    use specula::plan::predict::cost_model::{BvhUpdateCosts, CostModel, DeviceKey};
    let ctx = Context::new(&DeviceOptions { validation: validate, device_filter: device.clone(), ..Default::default() })?;
    let mut c = match out.filter(|p| p.exists()) {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(|e| specula::Error::io(p, e))?;
            CostModel::parse(&text, &p.display().to_string())?
        }
        None => (*tradeoff::costs_for(&ctx, None, &mut |w| eprintln!("specula: {w}"))?.0).clone(),
    };
    if c.key != DeviceKey::of(&ctx) {
        return Err(specula::Error::invalid(
            "--out",
            format!("its costs are {}'s, not this device's ({})", c.key.label(), DeviceKey::of(&ctx).label()),
        ));
    }
    let samples = tradeoff::calibrate::measure_bvh_updates(&ctx, &tradeoff::calibrate::BVH_LADDER)?;
    for s in &samples {
        println!("{:<6} {:>8} triangles {:>10.2} ms", s.way, s.triangles, s.ms);
    }
    c.bvh_updates =
        Some(BvhUpdateCosts::fit(&samples).ok_or_else(|| specula::Error::invalid("bvh updates", "too few timings to fit a line per way"))?);
    let path = write_costs(out, &c)?;
    let b = c.bvh_updates.as_ref().expect("just set");
    println!("ms = a + b · triangles/1e6: sah {:?}, lbvh {:?}, refit {:?}; wrote {}", b.sah, b.lbvh, b.refit, path.display());
    Ok(())
}

/// Calibrates this device's unit costs and writes them to `out`, or to the cache.
/// `samples`: also write the measurements; `refit`: fit from such measurements instead of
/// measuring (no device is opened).
pub fn run_calibrate(
    out: Option<&Path>,
    samples: Option<&Path>,
    refit: Option<&Path>,
    validate: bool,
    device: &Option<String>,
) -> specula::Result<()> {
    use specula::plan::predict::cost_model::CostModel;
    let c = match refit {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| specula::Error::io(path, e))?;
            let measured = specula::plan::predict::samples::Corpus::parse(&text, &path.display().to_string())?;
            let key = measured.device.clone();
            CostModel::fit(&measured, key, 0.0)
        }
        None => {
            let ctx = Context::new(&DeviceOptions { validation: validate, device_filter: device.clone(), ..Default::default() })?;
            let t = std::time::Instant::now();
            let (measured, c) = tradeoff::calibrate_measured(&ctx, &mut |s| eprintln!("[{:6.1} s] {s}", t.elapsed().as_secs_f64()))?;
            if let Some(p) = samples {
                specula::output::write_file(p, measured.to_json().as_bytes())?;
            }
            c
        }
    };
    let path = write_costs(out, &c)?;
    println!("calibrated {} in {:.1} s; wrote {}", c.key.label(), c.calibration_s, path.display());
    use specula::plan::predict::features::{MAP_FEATURES, SCREEN_FEATURES, SHARED_FEATURES};
    let names: Vec<&str> = MAP_FEATURES.iter().chain(&SCREEN_FEATURES).chain(&SHARED_FEATURES).copied().collect();
    println!("unit costs (ms per unit of each feature: plan::predict::features)");
    println!("{:<24} {:>17}{}", "method", "margin", names.iter().map(|n| format!("{n:>17}")).collect::<String>());
    for (m, u) in &c.methods {
        let all: Vec<f64> = u.fixed.iter().chain(&u.screen).chain(&u.shared).copied().collect();
        println!("{m:<24} {:>17.2}{}", u.under, all.iter().map(|v| format!("{v:>17.3}")).collect::<String>());
    }
    use specula::plan::predict::cost_model::BASE_FEATURES;
    println!("\nthe frame's base (its own stages and effects)");
    println!("{}", BASE_FEATURES.iter().map(|n| format!("{n:>17}")).collect::<String>());
    println!("{}", c.base.iter().map(|v| format!("{v:>17.3}")).collect::<String>());
    Ok(())
}

/// `specula corpus --evaluate FILE`: the error models' leave-one-scene-out accuracy on a
/// measured corpus, per ridge penalty and per method at the chosen one, and the
/// predicted-against-measured scatter into `figure` (SVG and PNG).
pub fn run_evaluate(path: &Path, figure: &Path) -> specula::Result<()> {
    let text = std::fs::read_to_string(path).map_err(|e| specula::Error::io(path, e))?;
    let c = specula::plan::predict::samples::Corpus::parse(&text, &path.display().to_string())?;
    println!("{} samples of {} scenes measured on {}", c.samples.len(), c.scenes().len(), c.device.label());
    println!("ridge     median |err| dB   90th pct dB");
    for ridge in [0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1.0] {
        let (m, p) = error_model::abs_error_quantiles(&error_model::leave_one_scene_out_with(&c.samples, ridge));
        println!("{ridge:<9} {m:>15.2} {p:>13.2}{}", if ridge == error_model::RIDGE { "   (used)" } else { "" });
    }
    let held = error_model::leave_one_scene_out(&c.samples);
    println!("\nper method at ridge {} (held-out scenes):", error_model::RIDGE);
    println!("{:<24} {:>6} {:>14} {:>12} {:>10}", "method", "n", "median |err|", "90th pct", "bias");
    for (m, hs) in grouped(&held, |h| &h.method) {
        let (med, p90) = error_model::abs_error_quantiles(&hs);
        let bias = hs.iter().map(|h| h.predicted_db - h.measured_db).sum::<f64>() / hs.len() as f64;
        println!("{m:<24} {:>6} {med:>14.2} {p90:>12.2} {bias:>10.2}", hs.len());
    }
    let (med, p90) = error_model::abs_error_quantiles(&held);
    println!("{:<24} {:>6} {med:>14.2} {p90:>12.2}", "all", held.len());
    println!("\nper knob variant (held-out scenes):");
    for (v, hs) in grouped(&held, |h| &h.knobs) {
        let (med, p90) = error_model::abs_error_quantiles(&hs);
        println!("{v:<24} {:>6} {med:>14.2} {p90:>12.2}", hs.len());
    }
    println!("\nper frame size (held-out scenes), with the size exponents and with the size ignored:");
    let ignored = error_model::leave_one_scene_out_unsized(&c.samples);
    let size_of = |h: &error_model::Held| format!("{0}x{0}", h.screen.sqrt().round());
    let mut sizes: Vec<String> = held.iter().map(size_of).collect();
    sizes.sort();
    sizes.dedup();
    for size in sizes {
        let stats = |hs: &[error_model::Held]| {
            let hs: Vec<_> = hs.iter().filter(|h| size_of(h) == size).cloned().collect();
            let (med, p90) = error_model::abs_error_quantiles(&hs);
            let bias = hs.iter().map(|h| h.predicted_db - h.measured_db).sum::<f64>() / hs.len().max(1) as f64;
            format!("{:>6} {med:>8.2} {p90:>8.2} {bias:>8.2}", hs.len())
        };
        println!("{size:<10} sized: n, median, 90th pct, bias {}   ignored: {}", stats(&held), stats(&ignored));
    }
    let probes = specula::plan::predict::aliasing::probe_corpus(&c.samples, &|_| true)?;
    let probed = error_model::leave_one_scene_out_probed(&c.samples, &probes);
    println!(
        "\nwith the exact tracer's error measured on each held-out object (plan::predict::aliasing; {} objects and sizes):",
        probes.len()
    );
    println!(
        "{:<24} {:>6} {:>14} {:>12} {:>10}   without: {:>8} {:>8} {:>8}",
        "method", "n", "median |err|", "90th pct", "bias", "median", "90th", "bias"
    );
    let stats = |hs: &[error_model::Held]| {
        let (med, p90) = error_model::abs_error_quantiles(hs);
        (med, p90, hs.iter().map(|h| h.predicted_db - h.measured_db).sum::<f64>() / hs.len().max(1) as f64)
    };
    let mut pairs: Vec<(String, Vec<error_model::Held>, Vec<error_model::Held>)> = grouped(&probed, |h| &h.method)
        .into_iter()
        .map(|(m, hs)| (m.to_string(), hs, held.iter().filter(|h| h.method == m).cloned().collect()))
        .collect();
    pairs.push(("all".to_string(), probed.clone(), held.clone()));
    for (m, with, without) in pairs {
        let (a, b) = (stats(&with), stats(&without));
        println!("{m:<24} {:>6} {:>14.2} {:>12.2} {:>10.2}   without: {:>8.2} {:>8.2} {:>8.2}", with.len(), a.0, a.1, a.2, b.0, b.1, b.2);
    }
    let model = error_model::ErrorModel::fit(&c.samples, &|_| true);
    println!("\nanti-aliasing's factor on the aliasing part of the error (per method; measured samples):");
    for ((m, aa), (f, n)) in &model.aa {
        println!("{m:<28} {aa:<8} {f:>8.3} {n:>6}");
    }
    println!("\nsize exponent k: the aliasing part scales as (N / 128)^-k (per method; measured samples):");
    for (m, (k, n)) in &model.size {
        println!("{m:<28} {k:>8.2} {n:>6}");
    }
    // As the planner predicts: with the exact tracer's error and a mirror's lookups measured
    // on each held-out object.
    let points: Vec<(f64, f64, String)> = probed.iter().map(|h| (h.measured_db, h.predicted_db, h.method.clone())).collect();
    let title = format!("Held-out PSNR per object, the scene's aliasing and lookups measured ({} scenes, leave-one-out)", c.scenes().len());
    let f = specula::tradeoff::scatter(
        figure,
        &points,
        (0.0, 62.0),
        3.0,
        &title,
        "measured PSNR against the exact tracer (dB)",
        "predicted (dB)",
    )?;
    println!("wrote {} and {}", f.svg.display(), f.png.display());
    Ok(())
}

/// Held-out predictions grouped by `key`, in its order.
fn grouped(held: &[error_model::Held], key: impl Fn(&error_model::Held) -> &String) -> Vec<(&str, Vec<error_model::Held>)> {
    let mut keys: Vec<&str> = held.iter().map(|h| key(h).as_str()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter().map(|k| (k, held.iter().filter(|h| key(h) == k).cloned().collect())).collect()
}
