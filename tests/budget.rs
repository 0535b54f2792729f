//! The budgeted planner (issue 15): a calibration study fits per-object models, then
//! `--min-psnr` and `--max-ms` choose per object a method and the frame's knobs, on two
//! scenes (a mirror and a glass sphere; flat glass), checked against what the same study
//! measured for every single-method configuration (lavapipe, validation on).
//!
//! Times are compared as ratios within one run (tests/README.md rule 4): the planner's
//! *predicted* time is checked exactly against the study's figures; the frame it then
//! renders is checked with a generous factor, since the machine is shared.

mod common;

use specula::plan::budget::{self, Budget, Models};
use specula::plan::{plan_with, Choices};
use specula::tradeoff::{Config, Metric, Row, Sweep};
use specula::{Method, Quality, Scene};

const SIZE: (u32, u32) = (48, 48);

fn quality() -> Quality {
    // Maps regenerated every frame: a frame's whole cost (as the CLI times it).
    {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 32;
        knobs.frame.shadow_size = 32;
        knobs.frame.map_updates_always = true;
        knobs
    }
}

/// The calibration study of `scene` over `methods` × `sweep`.
fn calibrate(name: &str, scene: &Scene, methods: &[Method], sweep: &str) -> (Vec<Row>, Models) {
    let out = std::env::temp_dir().join(format!("specula-budget-{name}-{}", std::process::id()));
    let cfg = Config {
        scene: scene.clone(),
        scene_name: name.into(),
        quality: quality(),
        sweeps: vec![Sweep::parse(sweep).unwrap()],
        each: false,
        methods: methods.iter().map(|&m| m.into()).collect(),
        size: SIZE,
        warmup: 1,
        frames: 3,
        device: specula::vk::DeviceOptions { validation: true, device_filter: None },
        out: out.clone(),
        metric: Metric::Psnr,
        calibrate: Some(out.join("models.json")),
    };
    let report = specula::tradeoff::run(&cfg, &mut |_| {}).unwrap();
    assert_eq!(report.validation, (0, 0));
    let written = Models::load(&out.join("models.json")).unwrap();
    assert_eq!(Some(&written), report.models.as_ref(), "the file holds what the study fitted");
    std::fs::remove_dir_all(&out).ok();
    (report.rows, written)
}

/// The lowest PSNR over the scene's specular objects in a row.
fn floor(row: &Row, objects: &[&str]) -> f64 {
    objects.iter().map(|o| row.regions.iter().find(|e| e.name == *o).map_or(f64::NEG_INFINITY, |e| e.psnr)).fold(f64::INFINITY, f64::min)
}

/// The budgeted choice's frame: (per-object PSNR, specular PSNR).
fn errors(ctx: &specula::vk::Context, scene: &Scene, choices: &Choices, q: &Quality) -> (Vec<(String, f64)>, f64) {
    let plan = plan_with(scene, choices, q).unwrap();
    let frame = specula::render_plan(ctx, scene, plan, SIZE, (1, 1)).unwrap();
    let reference = specula::reference::render_reference(scene, q, SIZE).unwrap();
    let ids = specula::reference::object_ids(scene, SIZE).unwrap();
    let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
    let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
    let regions = specula::metrics::errors_by_object(&frame.image, &reference, &ids, &specular, &names).unwrap();
    let spec = regions.iter().find(|e| e.name == "specular").unwrap().psnr;
    (regions.into_iter().map(|e| (e.name, e.psnr)).collect(), spec)
}

/// Frame times of configurations measured in turns (five rounds of three frames each,
/// the fastest round's median kept per configuration): ratios within one moment of a
/// shared machine.
fn times(ctx: &specula::vk::Context, scene: &Scene, configs: &[(Choices, Quality)]) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; configs.len()];
    for _ in 0..5 {
        for (i, (c, q)) in configs.iter().enumerate() {
            let frame = specula::render_plan(ctx, scene, plan_with(scene, c, q).unwrap(), SIZE, (1, 3)).unwrap();
            let ms: f64 = frame.passes.iter().filter(|p| p.name != "frame.readback").map(|p| p.gpu_ms).sum();
            best[i] = best[i].min(ms);
        }
    }
    best
}

/// A row's configuration: its whole-scene method with its knob variant.
fn config(row: &Row) -> (Choices, Quality) {
    (Choices::all(Method::parse(&row.method).unwrap()), budget::variant_quality(&quality(), &row.knobs).unwrap())
}

/// The GPU timings of one scene's checks must not share the cores with another's.
/// (Every test here takes it: the CLI's GPU work would share the cores too.)
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Both budgets on one scene: the choice meets them where the study says it can, and is no
/// worse than the best single-method configuration of the same study.
fn check(name: &str, scene: &Scene, objects: &[&str], methods: &[Method], sweep: &str) {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (rows, models) = calibrate(name, scene, methods, sweep);
    let single: Vec<&Row> = rows.iter().filter(|r| r.method != "auto").collect();
    for r in &single {
        eprintln!("{name}: {} {}: {:.3} ms, floor {:.2} dB", r.method, r.knobs, r.frame_ms, floor(r, objects));
    }
    let sources = [(&models, format!("{name} calibration"))];
    let ctx = common::gpu();

    // --min-psnr X, X the median of the single-method rows' floors: some reach it, some not.
    let mut floors: Vec<f64> = single.iter().map(|r| floor(r, objects)).collect();
    floors.sort_by(f64::total_cmp);
    let x = floors[floors.len() / 2];
    let cheapest = single.iter().filter(|r| floor(r, objects) >= x).min_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms)).unwrap();
    let (choices, q, p) = budget::choose(scene, &Choices::default(), &quality(), Budget::MinPsnr(x), SIZE, &sources).unwrap().unwrap();
    eprintln!("{name}: --min-psnr {x:.2}\n{}", budget::report(&p, None));
    eprintln!("{name}: cheapest single method reaching it: {} {} at {:.3} ms", cheapest.method, cheapest.knobs, cheapest.frame_ms);
    assert!(p.met, "{name}: the study reached {x:.2} dB, the models must");
    assert!(p.objects.iter().all(|o| o.psnr_db >= x), "{name}: predicted floors {:?}", p.objects);
    // The single-method configuration is one of the candidates: the choice predicts no
    // slower (the base is the variant's median, hence the 5 %).
    assert!(p.frame_ms <= cheapest.frame_ms * 1.05, "{name}: predicted {:.3} ms vs {:.3}", p.frame_ms, cheapest.frame_ms);
    let (psnr, _) = errors(&ctx, scene, &choices, &q);
    for o in objects {
        let got = psnr.iter().find(|(n, _)| n == o).unwrap().1;
        assert!(got >= x - 0.5, "{name}: '{o}' measured {got:.2} dB under --min-psnr {x:.2}");
    }
    let t = times(&ctx, scene, &[(choices, q), config(cheapest)]);
    eprintln!("{name}: measured {:.3} ms against the cheapest single method's {:.3}: {:.2}×", t[0], t[1], t[0] / t[1]);
    // Generous (rule 4: a shared machine; the same configuration measured 1.2× apart in one
    // run): `cargo run --release --example bench_budget` prints the ratios (BENCHMARKS.md).
    assert!(t[0] <= t[1] * 2.0, "{name}: {:.3} ms vs the cheapest single method's {:.3}", t[0], t[1]);

    // --max-ms T, T the median single-method frame: the choice predicts within it, and no
    // less accurate on the specular pixels than the best single method within it.
    let mut by_time: Vec<&Row> = single.clone();
    by_time.sort_by(|a, b| a.frame_ms.total_cmp(&b.frame_ms));
    let median = by_time[by_time.len() / 2];
    let budget_ms = median.frame_ms;
    let spec = |r: &Row| r.regions.iter().find(|e| e.name == "specular").unwrap().psnr;
    let best = single.iter().filter(|r| r.frame_ms <= budget_ms).map(|r| spec(r)).fold(f64::NEG_INFINITY, f64::max);
    let (choices, q, p) =
        budget::choose(scene, &Choices::default(), &quality(), Budget::MaxMs(budget_ms), SIZE, &sources).unwrap().unwrap();
    eprintln!("{name}: --max-ms {budget_ms:.3}\n{}", budget::report(&p, None));
    assert!(p.met && p.frame_ms <= budget_ms, "{name}: predicted {:.3} ms over {budget_ms:.3}", p.frame_ms);
    assert!(p.specular_psnr_db >= best - 0.05, "{name}: predicted {:.2} dB vs the best single method's {best:.2}", p.specular_psnr_db);
    let (_, measured) = errors(&ctx, scene, &choices, &q);
    assert!(measured >= p.specular_psnr_db - 0.5, "{name}: measured {measured:.2} dB, predicted {:.2}", p.specular_psnr_db);
    // The budget, re-measured now as the row that set it.
    let t = times(&ctx, scene, &[(choices, q), config(median)]);
    eprintln!("{name}: measured {:.3} ms against the budget re-measured at {:.3}: {:.2}×", t[0], t[1], t[0] / t[1]);
    // 2×: a frame measured 1.84× its re-measured budget once in the full suite (another
    // binary's build or GPU work on the same two cores); bench_budget measures 0.20–0.68.
    assert!(t[0] <= t[1] * 2.0, "{name}: {:.3} ms against --max-ms re-measured at {:.3}", t[0], t[1]);
    common::assert_clean(&ctx);
}

#[test]
fn budgets_on_mirror_and_glass_spheres() {
    use specula::methods::*;
    let scene = common::mirror_and_glass(24);
    check("spheres", &scene, &["glass", "mirror"], &[ENVMAP, DISTANCE, REFRACTOR_MAP, BVH], "cube_size=16,64");
}

#[test]
fn budgets_on_flat_glass() {
    use specula::methods::*;
    let scene = specula::scenes::flat_glass().unwrap();
    check("flat-glass", &scene, &["slab", "prism"], &[ENVMAP, REFRACTOR_MAP, PLANAR_REFRACTION, BVH], "mirror_budget=4,32");
}

#[test]
fn without_models_the_rules_choose_and_bad_models_are_named() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let scene = common::mirror_and_glass(12);
    // A models set that knows neither object nor their classes covers nothing.
    let empty = Models { format: budget::FORMAT.into(), scene: "none".into(), device: String::new(), size: [8, 8], variants: Vec::new() };
    let r = budget::choose(&scene, &Choices::default(), &quality(), Budget::MinPsnr(30.0), SIZE, &[(&empty, "empty".into())]).unwrap();
    assert!(r.is_none());
    // The stored defaults cover mirrors and solid glass by class.
    let defaults = budget::stored_defaults().unwrap();
    let (choices, _, p) =
        budget::choose(&scene, &Choices::default(), &quality(), Budget::MaxMs(1e9), SIZE, &[(&defaults, "defaults".into())])
            .unwrap()
            .unwrap();
    assert_eq!(choices.objects.len(), 2);
    assert!(p.objects.iter().all(|o| o.model.starts_with("class '")), "{:?}", p.objects);
    // An object the user forced keeps its method.
    let forced = Choices { method: specula::Choice::Auto, objects: vec![("mirror".into(), specula::methods::ENVMAP)] };
    let (choices, _, _) =
        budget::choose(&scene, &forced, &quality(), Budget::MaxMs(1e9), SIZE, &[(&defaults, "defaults".into())]).unwrap().unwrap();
    assert!(choices.objects.contains(&("mirror".into(), specula::methods::ENVMAP)));
    // Bad files name the file and the field.
    for (text, what) in [
        ("{", "not a models file"),
        (r#"{"format":"v0","scene":"","device":"","size":[1,1],"variants":[]}"#, "format"),
        (r#"{"format":"specula-models 1","scene":"","device":"","size":[0,1],"variants":[]}"#, "size"),
        (
            r#"{"format":"specula-models 1","scene":"","device":"","size":[1,1],"variants":[{"knobs":"bogus=1","base":{"fixed_ms":0,"screen_ms":0},"objects":[]}]}"#,
            "bogus",
        ),
        (
            r#"{"format":"specula-models 1","scene":"","device":"","size":[1,1],"variants":[{"knobs":"default","base":{"fixed_ms":0,"screen_ms":0},"objects":[{"object":"m","class":"mirror","pixels":1,"method":"envmap","cost":{"fixed_ms":-1,"screen_ms":0},"psnr_db":3}]}]}"#,
            "non-negative",
        ),
    ] {
        let e = Models::parse(text, "m.json").unwrap_err().to_string();
        assert!(e.contains("m.json") && e.contains(what), "{e}");
    }
    assert!(Budget::from_limits(Some(1.0), Some(30.0)).is_err());
    assert!(Budget::from_limits(Some(-1.0), None).unwrap_err().to_string().contains("max-ms"));
    assert!(Budget::from_limits(Some(f64::NAN), None).is_err());
    assert!(Budget::from_limits(Some(0.0), None).is_err(), "0 ms is no budget");
    assert_eq!(Budget::from_limits(None, None).unwrap(), None);
}

#[test]
fn the_cli_calibrates_predicts_and_reports_what_the_frame_measured() {
    // Its GPU work would share the cores with the other tests' timings.
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("specula-budget-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let models = dir.join("demo-models.json");
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_specula")).args(args).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let scene = "assets/demo/demo.gltf";
    let small = [
        "--size",
        "24x24",
        "-q",
        "cube_size=16",
        "-q",
        "shadow_size=16",
        "-q",
        "photons=32",
        "-q",
        "reference_photons=1000",
        "-q",
        "spp=1",
    ];
    let out = dir.to_str().unwrap();
    let m = models.to_str().unwrap();
    let mut args = vec![
        "tradeoff",
        scene,
        "--warmup",
        "1",
        "--frames",
        "1",
        "--method",
        "envmap",
        "--method",
        "bvh",
        "--calibrate",
        "--models",
        m,
        "--out",
        out,
    ];
    args.extend(small);
    let (ok, stdout, stderr) = run(&args);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains(&format!("wrote {m} (1 knob variant(s), 4 object × method model(s))")), "{stdout}");
    let fitted = Models::load(&models).unwrap();
    assert_eq!(fitted.size, [24, 24]);

    // render with a floor: the prediction beside what the frame measured, per object.
    let png = dir.join("budget.png");
    let mut args = vec!["render", scene, "--min-psnr", "1", "--models", m, "--out", png.to_str().unwrap()];
    args.extend(small);
    let (ok, stdout, stderr) = run(&args);
    assert!(ok, "{stdout}{stderr}");
    assert!(stdout.contains("budget --min-psnr 1: met (predicted)") && stdout.contains(&format!("models: calibration {m}")), "{stdout}");
    for object in ["mirror_sphere/0", "glass_sphere/0"] {
        let line =
            stdout.lines().find(|l| l.starts_with(object) && l.contains("object '")).unwrap_or_else(|| panic!("{object}:\n{stdout}"));
        // method, predicted ms, actual ms, predicted PSNR, actual PSNR: all numbers present.
        let numbers = line.split_whitespace().filter(|w| w.parse::<f64>().is_ok()).count();
        assert!(numbers >= 4, "{line}");
    }
    assert!(png.exists());

    // plan without a calibration: the stored defaults, by class; JSON carries the prediction.
    let (ok, stdout, stderr) = run(&["plan", scene, "--size", "24x24", "--max-ms", "1000", "--json"]);
    assert!(ok, "{stdout}{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(v["prediction"]["source"].as_str().unwrap().starts_with("stored defaults"), "{stdout}");
    assert_eq!(v["prediction"]["objects"].as_array().unwrap().len(), 2);

    // Bad input is named.
    for (args, want) in [
        (vec!["plan", scene, "--max-ms", "5", "--min-psnr", "30"], "not both"),
        (vec!["plan", scene, "--max-ms=-5"], "max-ms"),
        (vec!["plan", scene, "--max-ms", "0"], "max-ms"),
        (vec!["plan", scene, "--min-psnr", "30", "--method", "envmap"], "needs --method auto"),
        (vec!["plan", scene, "--models", m], "needs --max-ms or --min-psnr"),
        (vec!["plan", scene, "--min-psnr", "30", "--models", "no/such.json"], "no/such.json"),
        (vec!["plan", scene, "--min-psnr", "30", "--models", scene], "not a models file"),
    ] {
        let (ok, stdout, stderr) = run(&args);
        assert!(!ok && stderr.contains(want), "{args:?}: {stdout}{stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
