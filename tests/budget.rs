//! The budgeted planner's files and command line: models files checked and named, forced
//! objects kept, a scene's own calibration (`specula tradeoff --calibrate`) used by `render`
//! and `plan`, predictions used without one (lavapipe, validation on). Whether budgets hold
//! on scenes the models never saw: tests/planner.rs.

mod common;

use specula::plan::budget::{self, Budget, Models};
use specula::plan::Choices;
use specula::Quality;

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

/// The GPU timings of one scene's checks must not share the cores with another's.
/// (Every test here takes it: the CLI's GPU work would share the cores too.)
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn models_cover_objects_keep_forced_ones_and_bad_files_are_named() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let scene = common::mirror_and_glass(12);
    // A models set that knows neither object nor their classes covers nothing.
    let empty = Models { format: budget::FORMAT.into(), scene: "none".into(), device: String::new(), size: [8, 8], variants: Vec::new() };
    let r = budget::choose(&scene, &Choices::default(), &quality(), Budget::MinPsnr(30.0), SIZE, &[(&empty, "empty".into())]).unwrap();
    assert!(r.is_none());
    // Predictions cover every object by its own facts (no class lookup).
    let target = specula::plan::predict::Target::nominal().unwrap();
    let facts = specula::plan::facts::SceneFacts::new(&scene, &quality(), true);
    let defaults = specula::plan::predict::predict_models(&scene, &facts, &quality(), &target, &["default".into()]).unwrap();
    let (choices, _, p) =
        budget::choose(&scene, &Choices::default(), &quality(), Budget::MaxMs(1e9), SIZE, &[(&defaults, "predicted".into())])
            .unwrap()
            .unwrap();
    assert!(choices.objects.len() == 2 || matches!(choices.method, specula::Choice::Method(_)), "{choices:?}");
    assert!(p.objects.iter().all(|o| o.model.starts_with("object '")), "{:?}", p.objects);
    // An object the user forced keeps its method.
    let forced = Choices { method: specula::Choice::Auto, objects: vec![("mirror".into(), specula::methods::ENVMAP)] };
    let (choices, _, _) =
        budget::choose(&scene, &forced, &quality(), Budget::MaxMs(1e9), SIZE, &[(&defaults, "predicted".into())]).unwrap().unwrap();
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
    let dir = common::scratch_dir("budget-cli");
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
        let numbers: Vec<f64> = line.split_whitespace().filter_map(|w| w.parse::<f64>().ok()).collect();
        assert!(numbers.len() >= 4, "{line}");
        // Per pass kind, predicted/actual: maps and frame effects, camera work; the actual
        // parts are the object's actual ms, the predicted parts its predicted ms.
        let pairs: Vec<(f64, f64)> = line
            .split_whitespace()
            .filter_map(|w| w.split_once('/'))
            .filter_map(|(a, b)| Some((a.parse::<f64>().ok()?, b.parse::<f64>().ok()?)))
            .collect();
        assert_eq!(pairs.len(), 2, "{line}");
        assert!((pairs[0].0 + pairs[1].0 - numbers[0]).abs() < 2e-3, "predicted parts of {line}");
        assert!((pairs[0].1 + pairs[1].1 - numbers[1]).abs() < 2e-3, "actual parts of {line}");
    }
    assert!(png.exists());

    // plan without a calibration: predicted from the objects' facts; JSON carries it.
    let (ok, stdout, stderr) = run(&["plan", scene, "--size", "24x24", "--max-ms", "1000", "--json"]);
    assert!(ok, "{stdout}{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(v["prediction"]["source"].as_str().unwrap().starts_with("predicted"), "{stdout}");
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
