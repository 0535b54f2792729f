//! `specula animate` and `render --time`: the demo scene's animated mirror sphere as a frame
//! sequence (PNG + EXR per frame, frames.csv with the maps each frame rebuilt, an animated
//! GIF), with the validation layer on; `--slide` moves any object; bad `--fps`, `--duration`,
//! `--time` and `--slide` are refused.

use std::path::PathBuf;
use std::process::Command;

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");

fn specula(args: &[&str]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_specula")).env("SPECULA_DEVICE", "llvmpipe").args(args).output().unwrap();
    (o.status.success(), format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr)))
}

fn temp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("specula-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn animate_writes_frames_timings_and_a_preview() {
    let dir = temp("animate");
    let small = ["--size", "24x16", "-q", "cube_size=16", "-q", "shadow_size=16", "--validate", "--method", "distance"];
    let mut args = vec!["animate", SCENE, "--fps", "2", "--duration", "1.5", "--out", dir.to_str().unwrap()];
    args.extend(small);
    let (ok, out) = specula(&args);
    assert!(ok, "{out}");
    assert!(out.contains("3 frames at 2 fps") && out.contains("validation: 0 error(s)"), "{out}");
    for k in 0..3 {
        for ext in ["png", "exr"] {
            assert!(dir.join(format!("frame_{k:04}.{ext}")).is_file(), "frame {k} .{ext}");
        }
    }
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 4, "{csv}");
    assert!(rows[1].contains("distance.generate (first frame)"), "{csv}");
    assert!(rows[2].contains("distance.generate (moved 'mirror_sphere/0')"), "the sphere moves: {csv}");
    let gif = std::fs::read(dir.join("preview.gif")).unwrap();
    assert!(gif.starts_with(b"GIF89a"));
    use image::AnimationDecoder;
    let frames = image::codecs::gif::GifDecoder::new(std::io::Cursor::new(gif)).unwrap().into_frames().count();
    assert_eq!(frames, 3);
    // Moving frames differ; --time poses a single render the same way.
    let a = std::fs::read(dir.join("frame_0000.exr")).unwrap();
    let b = std::fs::read(dir.join("frame_0002.exr")).unwrap();
    assert!(a != b, "the mirror sphere moved between t = 0 and t = 1");
    let posed = dir.join("posed.exr");
    let mut args = vec!["render", SCENE, "--time", "1", "--out", posed.to_str().unwrap()];
    args.extend(small);
    let (ok, out) = specula(&args);
    assert!(ok, "{out}");
    assert!(std::fs::read(&posed).unwrap() == b, "render --time 1 equals the animation's frame at t = 1");
    // --slide moves any object, --freeze holds the scene's own animation: the box moves
    // alone, and frames.csv says what its move rebuilt.
    let slid = dir.join("slid");
    let mut args = vec!["animate", SCENE, "--fps", "2", "--duration", "1", "--freeze", "--slide", "box/0=0.2,0,0"];
    args.extend(["--out", slid.to_str().unwrap()]);
    args.extend(small);
    let (ok, out) = specula(&args);
    assert!(ok, "{out}");
    let csv = std::fs::read_to_string(slid.join("frames.csv")).unwrap();
    assert!(csv.contains("moved 'box/0'") && !csv.contains("mirror_sphere"), "{csv}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_animation_arguments_are_refused() {
    let dir = temp("animate-bad");
    let out_dir = dir.to_str().unwrap();
    for (args, want) in [
        (vec!["animate", SCENE, "--fps", "0", "--out", out_dir], "--fps"),
        (vec!["animate", SCENE, "--duration=-1", "--out", out_dir], "--duration"),
        (vec!["render", SCENE, "--time=-2", "--out", "x.png"], "--time"),
        (vec!["animate", SCENE, "--method", "reference", "--out", out_dir], "--method"),
        (vec!["animate", SCENE, "--slide", "nobox=1,0,0", "--out", out_dir], "no object named 'nobox'"),
        (vec!["animate", SCENE, "--slide", "box/0=1,x,0", "--out", out_dir], "--slide"),
    ] {
        let (ok, out) = specula(&args);
        assert!(!ok && out.contains(want), "{args:?}: {out}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Poses where the plan's structure changes (the demo's mirror sphere on distance maps and its
/// glass sphere on refractor maps: the mirror comes into the glass sphere's view around
/// t = 2.58 s and the objects start to compose through inter-object cycles) get a new
/// renderer: the sequence goes on, and frames.csv says so.
#[test]
fn animate_replans_where_the_pose_changes_the_plan() {
    let dir = temp("animate-replan");
    let out_dir = dir.to_str().unwrap();
    let args = [
        "animate",
        SCENE,
        "--fps",
        "12",
        "--duration",
        "2.7",
        "--size",
        "16x12",
        "-q",
        "cube_size=16",
        "-q",
        "shadow_size=16",
        "--object",
        "mirror_sphere=distance",
        "--object",
        "glass_sphere=refractor-map",
        "--out",
        out_dir,
    ];
    // Only the frames around the change are rendered at full rate: 2.7 s × 12 fps = 32 frames.
    let (ok, out) = specula(&args);
    assert!(ok, "{out}");
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    assert_eq!(csv.lines().count(), 33, "{csv}");
    assert!(csv.contains("new renderer (scene update: the plan changes"), "{csv}");
    std::fs::remove_dir_all(&dir).ok();
}
