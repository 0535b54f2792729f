//! The CLI of issue 3: `render --method reference` (CPU, no GPU plan), `compare` and
//! `tradeoff` (every GPU method × every sweep combination against the reference, CSV and
//! SVG plot). Small sizes: these run the real renderers.

use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
/// refractor-map at cube_size 64 over 16 on the demo (see its use): measured 33.947 vs
/// 33.383 dB, the bound at half the 0.564 dB gain (tests/README.md rule 1).
const MARGIN: f64 = 0.282;

fn specula() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_specula"));
    c.env("SPECULA_DEVICE", "llvmpipe");
    c
}

fn run(args: &[&str]) -> String {
    let o = specula().args(args).output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(o.status.success(), "{args:?}: {out}{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn temp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("specula-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn reference_renders_on_the_cpu_and_compare_reports_metrics() {
    let dir = temp("ref-cli");
    let (reference, envmap, err) = (dir.join("ref.exr"), dir.join("env.exr"), dir.join("err.png"));
    let out = run(&["render", SCENE, "--method", "reference", "--size", "40x30", "-q", "spp=4", "-q", "depth=3", "--out", s(&reference)]);
    assert!(out.contains("reference on the CPU") && out.contains("4 spp, depth 3"), "{out}");
    run(&["render", SCENE, "--method", "envmap", "--size", "40x30", "-q", "cube_size=32", "-q", "shadow_size=32", "--out", s(&envmap)]);
    let out = run(&["compare", s(&envmap), s(&reference), "--error-image", s(&err)]);
    for key in ["RMSE", "PSNR", "max |Δ|", "p99 |Δ|", "mean FLIP"] {
        assert!(out.contains(key), "compare lacks {key}: {out}");
    }
    let psnr: f64 = out.lines().find(|l| l.starts_with("PSNR")).unwrap().split_whitespace().nth(1).unwrap().parse().unwrap();
    eprintln!("compare envmap reference:\n{out}");
    // Measured 19.61 dB: the floor 1 dB under it (tests/README.md rule 1); not identical.
    assert!((18.61..60.0).contains(&psnr), "envmap vs reference is neither garbage nor identical: {psnr}");
    let img = image::open(&err).unwrap();
    assert_eq!((img.width(), img.height()), (40, 30));
    // An image compared with itself: zero error, infinite PSNR.
    let out = run(&["compare", s(&reference), s(&reference)]);
    assert!(out.contains("RMSE      0.000000") && out.contains("PSNR      inf dB"), "{out}");

    // The reference's plan is one CPU pass; bad knobs are one-line errors.
    let plan = run(&["plan", SCENE, "--method", "reference", "--json"]);
    let json: serde_json::Value = serde_json::from_str(&plan).unwrap();
    assert_eq!(json["passes"], serde_json::json!(["reference.trace"]));
    assert_eq!(json["envmaps"], serde_json::json!([]));
    for bad in [["-q", "spp=3"], ["-q", "depth=0"]] {
        let o = specula().args(["render", SCENE, "--method", "reference", "--out", "/tmp/x.png"]).args(bad).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{bad:?}");
        assert!(stderr.starts_with("specula: ") && stderr.trim_end().lines().count() == 1, "{stderr}");
    }
    let o = specula().args(["compare", s(&reference), "/nonexistent.exr"]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn tradeoff_writes_csv_and_plot_for_every_gpu_method_and_sweep() {
    let dir = temp("tradeoff-cli");
    let out = run(&[
        "tradeoff",
        SCENE,
        "--size",
        "32x32",
        "-q",
        "spp=1",
        "-q",
        "shadow_size=32",
        // Caustics off: with them every method's image depends on the map knobs (below).
        "-q",
        "caustics=off",
        // One capture and small height maps: the CLI's output is checked here, not their error.
        "-q",
        "captures=1",
        "-q",
        "relief_size=16",
        "--sweep",
        "cube_size=16,64",
        "--sweep",
        // One value: a sweep of one value labels every row with it (the cross product of
        // two multi-valued sweeps runs below, with caustics: each method here costs a render
        // per combination, 30 s of CI for two more).
        "cube_precision=half",
        "--frames",
        "1",
        "--warmup",
        "1",
        "--validate",
        "--out",
        s(&dir),
    ]);
    assert!(out.contains("validation: 0 error(s)"), "{out}");
    let csv = std::fs::read_to_string(dir.join("tradeoff.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(&header[..9], ["method", "knobs", "frame_ms", "rmse", "psnr_db", "flip_mean", "p99_abs", "max_abs", "pareto"]);
    for pass in ["envmap.generate ms", "scene.direct ms", "envmap.shade ms"] {
        assert!(header.contains(&pass), "no {pass} column: {}", lines[0]);
    }
    // `auto` and every GPU method of the registry, each under its name, but the O(N)-per-ray
    // schemes (minutes a frame on lavapipe: only when named with --method).
    let linear = |m: &specula::Method| specula::methods::raytrace::bench::complexity(*m).starts_with("O(N)");
    let gpu_methods: Vec<&str> =
        std::iter::once("auto").chain(specula::Method::ALL.iter().filter(|m| m.is_gpu() && !linear(m)).map(|m| m.name())).collect();
    assert!(!csv.contains("\nray-engine,") && !csv.contains("\nray-hierarchy,"), "{csv}");
    assert_eq!(lines.len() - 1, gpu_methods.len() * 2, "one row per method and combination:\n{csv}");
    for m in &gpu_methods {
        assert_eq!(lines[1..].iter().filter(|l| l.split(',').next() == Some(m)).count(), 2, "{m}");
    }
    let mut points = Vec::new();
    // (method, knobs) → (RMSE, PSNR, mean FLIP) as printed.
    let mut metrics = std::collections::HashMap::new();
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        let frame_ms: f64 = f[2].parse().unwrap();
        let (rmse, psnr, flip): (f64, f64, f64) = (f[3].parse().unwrap(), f[4].parse().unwrap(), f[5].parse().unwrap());
        assert!(frame_ms > 0.0 && rmse > 0.0 && psnr.is_finite() && flip > 0.0 && flip < 1.0, "{l}");
        // PSNR is −20 log10 RMSE (peak 1), up to the printed digits: RMSE to 1e-6 (a
        // relative 5e-7 / RMSE: 0.02 dB at the ray tracers' 2e-4 here) and PSNR to 0.001 dB.
        let digits = 20.0 * (1.0 + 5e-7 / rmse).log10() + 0.0005;
        assert!((psnr + 20.0 * rmse.log10()).abs() <= digits + 1e-6, "PSNR {psnr} dB vs RMSE {rmse}: {l}");
        points.push((frame_ms, flip, f[8] == "true", l.to_string()));
        metrics.insert((f[0].to_string(), f[1].to_string()), (f[3].to_string(), psnr, f[5].to_string()));
    }
    let row = |m: &str, knobs: &str| metrics[&(m.to_string(), knobs.to_string())].clone();
    // The exact ray tracers agree with each other and ignore the cube-map knobs (caustics
    // off): the same printed metrics in every row (measured 73.685 dB against the 1-spp
    // reference, the rounding of two exact renderers; floor 1 dB under, rule 1).
    let traced = row("bvh", "cube_size=16 cube_precision=half");
    eprintln!("ray tracers: RMSE {}, {} dB, mean FLIP {}", traced.0, traced.1, traced.2);
    assert!(traced.1 >= 72.68, "bvh {} dB against the reference", traced.1);
    for m in ["bvh", "kd-tree", "grid"] {
        for knobs in ["cube_size=16 cube_precision=half", "cube_size=64 cube_precision=half"] {
            assert_eq!(row(m, knobs), traced, "{m} {knobs}");
        }
    }
    // The sweep reaches the renderer: refractor-map's maps (distance's for the mirror) at
    // cube_size 64 against 16 (caustics off, the 6.5 cd light; the margin asserted at half the
    // measured one, rule 1). (auto ray traces this scene on lavapipe: its rows are the
    // tracers'.)
    let (small, large) =
        (row("refractor-map", "cube_size=16 cube_precision=half").1, row("refractor-map", "cube_size=64 cube_precision=half").1);
    eprintln!("refractor-map: cube_size 16 {small} dB, 64 {large} dB");
    assert!(large >= small + MARGIN, "refractor-map: cube_size 64 {large} dB vs 16 {small} dB");
    // The front is the undominated set in (frame ms, mean FLIP), checked from the printed
    // values (a relative 1e-3 for their rounding): no row on it is beaten in both, every row
    // off it is matched or beaten in both by some row.
    let tol = |a: f64, b: f64| a <= b * (1.0 + 1e-3) + 1e-9;
    for (t, e, on, l) in &points {
        let beaten = points.iter().any(|(t2, e2, _, _)| *t2 < t * (1.0 - 1e-3) && *e2 < e * (1.0 - 1e-3));
        let matched = points.iter().any(|(t2, e2, _, l2)| l2 != l && tol(*t2, *t) && tol(*e2, *e) && (*t2 < *t || *e2 < *e));
        if *on {
            assert!(!beaten, "on the front but dominated: {l}");
        } else {
            assert!(matched, "off the front but undominated: {l}");
        }
    }
    assert!(points.iter().any(|p| p.2) && points.iter().any(|p| !p.2), "the front is a proper subset");
    assert!(lines.iter().any(|l| l.contains("cube_size=64 cube_precision=half")));
    // Where the methods act (issue 15): a PSNR column per specular object, for the specular
    // pixels and for the rest; the non-specular pixels do not depend on the cube-map knobs
    // of a ray tracer, and the figure has a panel per specular object.
    for col in ["psnr_db[mirror_sphere/0]", "psnr_db[glass_sphere/0]", "psnr_db[specular]", "psnr_db[non-specular]"] {
        assert!(header.contains(&col), "no {col} column: {}", lines[0]);
    }
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (spec, rest) = (column("psnr_db[specular]"), column("psnr_db[non-specular]"));
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        let (a, b): (f64, f64) = (f[spec].parse().unwrap(), f[rest].parse().unwrap());
        assert!(a.is_finite() && b.is_finite(), "{l}");
    }
    let svg = std::fs::read_to_string(dir.join("tradeoff.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("Pareto front"));
    for panel in ["whole image", "mirror_sphere/0 (its pixels)", "glass_sphere/0 (its pixels)"] {
        assert!(svg.contains(panel), "no panel {panel}");
    }
    assert!(dir.join("reference.exr").exists());
    std::fs::remove_dir_all(&dir).ok();

    // With caustics on, a ray tracer's image depends on the map knobs too (its caustics come
    // from light cube maps of cube_size): each variant is measured, not copied from the
    // first (they once were, and the demo's trade-off figure showed bvh at cube_size 16's
    // error for every cube size).
    let dir = temp("tradeoff-cli-caustics");
    run(&[
        "tradeoff",
        SCENE,
        "--size",
        "16x16",
        "-q",
        "spp=1",
        "-q",
        "shadow_size=32",
        "--method",
        "bvh",
        "--sweep",
        "cube_size=16,64",
        "--sweep",
        "caustics=off,triangles",
        "--each",
        "--frames",
        "1",
        "--warmup",
        "1",
        "--out",
        s(&dir),
    ]);
    let csv = std::fs::read_to_string(dir.join("tradeoff.csv")).unwrap();
    let rows: Vec<(&str, &str, &str)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0], f[1], f[3])
        })
        .collect();
    eprintln!("bvh with caustics: {rows:?}");
    // cube_size is a map knob (bvh lists it: its caustics' light cubes); caustics is the
    // frame's (no GPU method lists it): with --each, bvh gets a curve of each.
    assert_eq!(
        rows.iter().map(|r| (r.0, r.1)).collect::<Vec<_>>(),
        [
            ("bvh (cube_size)", "cube_size=16"),
            ("bvh (cube_size)", "cube_size=64"),
            ("bvh (caustics)", "caustics=off"),
            ("bvh (caustics)", "caustics=triangles"),
        ]
    );
    assert_ne!(rows[0].2, rows[1].2, "bvh's caustics at cube_size 16 and 64 were not both measured");
    assert_ne!(rows[2].2, rows[3].2, "bvh with and without caustics measured the same");
    std::fs::remove_dir_all(&dir).ok();
}
