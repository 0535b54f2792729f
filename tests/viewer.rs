//! `specula view` headless under `xvfb-run`: scripted input moves the camera, orbits,
//! switches methods and knobs (one refused), resizes the window, pauses the animation; every screenshot is
//! rendered again by `specula render` from the command line the viewer wrote beside it and
//! must match bit for bit, with the validation layer clean over the whole session.
//!
//! Where no X server can start the tests say so and skip, unless SPECULA_REQUIRE_VIEWER=1
//! (scripts/test.sh sets it: its set-up installs Xvfb), where that is a failure.

#![cfg(feature = "viewer")]

mod common;

use std::path::Path;
use std::process::Command;

const EXE: &str = env!("CARGO_BIN_EXE_specula");

/// Runs the viewer under a fresh X server; `None` (after saying why) where none can start
/// and the viewer is not required.
fn view(args: &[&str]) -> Option<std::process::Output> {
    let required = std::env::var("SPECULA_REQUIRE_VIEWER").is_ok_and(|v| v == "1");
    let skip = |why: String| {
        assert!(!required, "SPECULA_REQUIRE_VIEWER=1 but {why}");
        eprintln!("SKIPPED: {why} (install xvfb and xauth to run the viewer's tests)");
        None
    };
    let Ok(out) = Command::new("xvfb-run").args(["-a", "-s", "-screen 0 640x480x24", EXE, "view"]).args(args).output() else {
        return skip("xvfb-run is not installed".into());
    };
    let err = String::from_utf8_lossy(&out.stderr);
    if err.contains("Xvfb failed to start") {
        return skip(format!("Xvfb failed to start: {}", err.trim()));
    }
    Some(out)
}

/// Views `scene` at `size` with validation on, playing `script` (written into `dir`), the
/// screenshots into `dir/shots`; `None` where no X server can start.
fn view_scripted(dir: &Path, scene: &str, size: &str, knobs: &[&str], script: &str) -> Option<std::process::Output> {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("script.txt");
    std::fs::write(&path, script).unwrap();
    let shots = dir.join("shots");
    let mut args = vec![scene, "--size", size, "--method", "distance", "--validate"];
    args.extend(knobs.iter().flat_map(|k| ["-q", k]));
    args.extend(["--script", path.to_str().unwrap(), "--screenshots", shots.to_str().unwrap()]);
    view(&args)
}

fn pixels(path: &Path) -> Vec<u32> {
    let img = specula::scene::load_environment(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.rgba32f.iter().map(|v| v.to_bits()).collect()
}

/// Renders screenshot NAME again with the `specula render` command written beside it and
/// returns both images' pixels.
fn rerender(shots: &Path, name: &str) -> (Vec<u32>, Vec<u32>, String) {
    let command = std::fs::read_to_string(shots.join(format!("{name}.txt"))).unwrap();
    let out = shots.join(format!("{name}.again.exr"));
    let words: Vec<String> = command.split_whitespace().map(|w| w.replace("OUT.exr", out.to_str().unwrap())).collect();
    assert_eq!(words[0], "specula", "{command}");
    let o = Command::new(EXE).args(&words[1..]).output().unwrap();
    assert!(o.status.success(), "{command}: {}", String::from_utf8_lossy(&o.stderr));
    (pixels(&shots.join(format!("{name}.exr"))), pixels(&out), command)
}

#[test]
fn scripted_input_moves_orbits_switches_and_resizes_and_each_screenshot_renders_again_bit_for_bit() {
    let dir = common::scratch_dir("viewer-input");
    let shots = dir.join("shots");
    let script = "0 screenshot start\n\
         0 key w down\n4 key w up\n5 look 30 10\n6 screenshot fly\n\
         7 orbit\n8 look 40 0\n9 wheel 1\n10 screenshot orbit\n\
         11 method * envmap\n12 knob cube_size=64\n13 screenshot envmap\n\
         14 method mirror_ball planar-mirror\n15 knob cube_size=3\n16 screenshot refused\n\
         17 resize 80 40\n21 screenshot resized\n22 quit\n";
    let Some(o) = view_scripted(&dir, "builtin:corner-mirror", "64x48", &[], script) else { return };
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("viewed 23 frames") && out.contains("validation: 0 error(s)"), "{out}");
    // The refused method (a sphere is not planar) and knob (outside its range) changed nothing.
    assert!(err.contains("planar-mirror for mirror_ball refused, nothing changed"), "{err}");
    assert!(err.contains("knob cube_size=3 refused, nothing changed"), "{err}");
    let mut images = Vec::new();
    for name in ["start", "fly", "orbit", "envmap", "refused", "resized"] {
        let (shot, again, command) = rerender(&shots, name);
        assert!(shot == again, "{name}: the screenshot differs from `{command}`");
        images.push((name, shot, command));
    }
    // The first view is the scene's own camera; each action moved or changed what is seen.
    assert!(!images[0].2.contains("--camera-pos"), "{}", images[0].2);
    for k in 1..4 {
        assert!(images[k].1 != images[k - 1].1, "{} shows the same image as {}", images[k].0, images[k - 1].0);
    }
    assert!(images[3].2.contains("--method envmap -q cube_size=64"), "{}", images[3].2);
    assert!(images[4].1 == images[3].1 && images[4].2 == images[3].2, "a refused change changed the view");
    // The window's new size: a new swapchain and a renderer at that size.
    assert!(images[5].2.contains("--size 80x40") && images[5].1.len() == 80 * 40 * 4, "{}", images[5].2);
    assert!(err.contains("new renderer: new size 80x40"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_gltf_animation_plays_pauses_and_its_screenshots_render_again_at_their_time() {
    let dir = common::scratch_dir("viewer-animation");
    let shots = dir.join("shots");
    let script = "0 screenshot t0\n6 screenshot t1\n7 pause\n10 screenshot paused\n11 quit\n";
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    let Some(o) = view_scripted(&dir, scene, "48x32", &["caustics=off"], script) else { return };
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success() && out.contains("validation: 0 error(s)"), "{out}\n{err}");
    let (t0, t0_again, c0) = rerender(&shots, "t0");
    let (t1, t1_again, c1) = rerender(&shots, "t1");
    let (paused, paused_again, cp) = rerender(&shots, "paused");
    assert!(t0 == t0_again && t1 == t1_again && paused == paused_again, "{c0}\n{c1}\n{cp}");
    // Six frames of 1/30 s moved the demo's objects; pausing after the seventh held them.
    assert!(c0.contains("--time=0 ") && c1.contains("--time=0.2 ") && cp.contains("--time=0.23333333 "), "{c0}\n{c1}\n{cp}");
    assert!(t1 != t0, "the animation did not move anything in six frames");
    std::fs::remove_dir_all(&dir).ok();
}
