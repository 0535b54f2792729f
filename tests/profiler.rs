//! The per-pass profiler: every pass of a frame is reported by its stable name with a
//! positive GPU time, the Chrome trace JSON parses, and the CLI writes both.

mod common;

use std::path::Path;
use std::process::Command;

use specula::Quality;

fn demo() -> specula::Scene {
    specula::scene::load(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap()
}

fn small() -> Quality {
    let mut q = Quality::default();
    q.set("cube_size", "32").unwrap();
    q.set("shadow_size", "32").unwrap();
    q
}

#[test]
fn every_pass_is_reported_with_positive_gpu_time() {
    let ctx = common::gpu();
    let scene = demo();
    let plan = specula::plan(&scene, specula::methods::ENVMAP, &small());
    let f = specula::render(&ctx, &scene, specula::methods::ENVMAP, &small(), (48, 32), (0, 1)).unwrap();
    let names: Vec<_> = f.passes.iter().map(|p| p.name.as_str()).collect();
    // The first frame uploads the textures; everything the plan names is there, in order.
    let mut expected: Vec<&str> = plan.passes.clone();
    expected.push("frame.readback");
    assert_eq!(names, expected);
    for p in &f.passes {
        assert!(p.gpu_ms > 0.0, "{} has GPU time {}", p.name, p.gpu_ms);
        // Recording a pass takes time on the CPU too (Instant's nanoseconds).
        assert!(p.cpu_ms > 0.0 && p.cpu_ms < 1e4, "{} has CPU time {}", p.name, p.cpu_ms);
    }
    assert!(f.memory_bytes() > 0);
    let json: serde_json::Value = serde_json::from_str(&specula::profile::chrome_trace(&f.passes, &f.memory, &ctx.device_name)).unwrap();
    let events = json["traceEvents"].as_array().unwrap();
    for name in &names {
        assert!(events.iter().any(|e| e["name"] == *name && e["ph"] == "X" && e["dur"].as_f64().unwrap() > 0.0), "{name} in trace");
    }
    assert_eq!(json["otherData"]["device_memory_total_bytes"].as_u64().unwrap(), f.memory_bytes());
    common::assert_clean(&ctx);
}

fn specula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_specula"))
}

#[test]
fn cli_render_writes_image_profile_and_table() {
    let dir = common::scratch_dir("cli");
    std::fs::create_dir_all(&dir).unwrap();
    let (png, exr, trace) = (dir.join("a.png"), dir.join("a.exr"), dir.join("trace.json"));
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    for out in [&png, &exr] {
        let o = specula()
            .args([
                "render",
                scene,
                "--method",
                "envmap",
                "--size",
                "40x30",
                "--validate",
                "-q",
                "cube_size=32",
                "-q",
                "shadow_size=32",
                "--out",
            ])
            .arg(out)
            .arg("--profile")
            .arg(&trace)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{stdout}{}", String::from_utf8_lossy(&o.stderr));
        for pass in ["shadow.generate", "envmap.generate", "scene.direct", "envmap.shade", "device memory", "validation: 0 error(s)"] {
            assert!(stdout.contains(pass), "table lacks {pass}: {stdout}");
        }
    }
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (40, 30));
    let env = specula::scene::load_environment(&exr).unwrap();
    assert_eq!((env.width, env.height), (40, 30));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&trace).unwrap()).unwrap();
    assert!(json["traceEvents"].as_array().unwrap().len() > 4);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn cli_bad_input_is_one_line_and_nonzero() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    let cases: &[&[&str]] = &[
        &["render", "/nonexistent/scene.gltf", "--out", "/tmp/x.png"],
        &["render", scene, "--method", "raytrace-everything", "--out", "/tmp/x.png"],
        &["render", scene, "--size", "0x10", "--out", "/tmp/x.png"],
        &["render", scene, "-q", "cube_size=3", "--out", "/tmp/x.png"],
        &["render", scene, "-q", "fresnel=maybe", "--out", "/tmp/x.png"],
        &["render", scene, "--out", "/tmp/x.bmp"],
        &["render", scene, "--camera-pos", "1,nan,2", "--out", "/tmp/x.png"],
        &["render", scene, "--device", "no-such-gpu", "--out", "/tmp/x.png"],
        &["info", "/nonexistent.glb"],
        // One camera validation for every entry point.
        &["render", scene, "--camera-pos", "1,1,1", "--camera-target", "1,1,1", "--out", "/tmp/x.png"],
        &["render", scene, "--camera-target", "0,0,0", "--out", "/tmp/x.png"],
        &["render", scene, "--fov", "40", "--out", "/tmp/x.png"],
        &["render", scene, "--camera-pos", "0,1,3", "--fov", "180", "--out", "/tmp/x.png"],
        // Argument-parser errors go through the same one-line reporter.
        &["render", scene],
        &["render", scene, "--out", "/tmp/x.png", "--frames", "abc"],
        &["rendr", scene],
        &["render", scene, "--out", "/tmp/x.png", "--no-such-flag"],
        &[],
    ];
    for args in cases {
        let o = specula().args(*args).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.starts_with("specula: ") && stderr.trim_end().lines().count() == 1, "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

/// Help and version still print as usual and exit 0; parser errors name what is wrong.
#[test]
fn cli_help_version_and_parser_messages() {
    for args in [&["--help"][..], &["--version"], &["render", "--help"]] {
        let o = specula().args(args).output().unwrap();
        assert_eq!(o.status.code(), Some(0), "{args:?}");
        assert!(!o.stdout.is_empty(), "{args:?}");
    }
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    for (args, want) in [
        (&["render", scene][..], "--out"),
        (&["render", scene, "--out", "/tmp/x.png", "--frames", "abc"], "abc"),
        (&["rendr", scene], "rendr"),
    ] {
        let o = specula().args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(want), "{args:?}: {stderr}");
    }
}

#[test]
fn cli_info_lists_classification() {
    let o = specula().args(["info", concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf")]).output().unwrap();
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    for want in ["mirror", "dielectric (solid)", "diffuse", "Point", "camera: at", "bounds:"] {
        assert!(s.contains(want), "info lacks {want}: {s}");
    }
}

/// A failed write is an error: a full device, a folder that cannot be created, a parent
/// that is a file — exit 1, one line naming the path; no partial file under the final name.
#[test]
fn cli_failed_writes_exit_1_naming_the_path() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    let dir = common::scratch_dir("writes");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let under_file = file.join("x.png");
    let mut cases: Vec<(Vec<String>, String)> = vec![
        (vec!["--out".into(), "/proc/specula-no/x.png".into()], "/proc/specula-no".into()),
        (vec!["--out".into(), under_file.display().to_string()], "is not a folder".into()),
        (
            vec!["--out".into(), dir.join("ok.png").display().to_string(), "--profile".into(), "/proc/specula-no/t.json".into()],
            "/proc/specula-no".into(),
        ),
    ];
    if std::path::Path::new("/dev/full").exists() {
        cases.push((vec!["--out".into(), "/dev/full".into(), "-q".into(), "cube_size=16".into()], "/dev/full".into()));
    }
    for (args, want) in cases {
        let o = specula()
            .args(["render", scene, "--method", "envmap", "--size", "16x16", "-q", "shadow_size=16", "-q", "cube_size=16"])
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.trim_end().lines().count() == 1 && stderr.contains(&want), "{args:?}: {stderr}");
    }
    let leftovers: Vec<_> =
        std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name()).filter(|n| n.to_string_lossy().contains("partial")).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(&dir).ok();
}
