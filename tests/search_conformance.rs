//! glsl/common/search.glsl against its twin src/search.rs on the same rays and the same
//! analytic distance maps (box rooms), on lavapipe with validation on. The GPU evaluates in
//! f32, the CPU in f64: ray parameters agree within 2.5e-6 of the ray's scale (10× the
//! measured worst, 2.42e-7 over 1868 cases: f32 rounding), and both sides agree on escape
//! and on the hit being within the search's accuracy of the exact exit (per room and
//! knobs, within a factor 1.122 of the error measured there: `EXIT_ERROR`).
//! The extremes: the reference point on the ray, rays starting at it, rays along cube-face
//! boundaries (axes, face diagonals, cube corners), a very distant wall (1e4 m), a very
//! near one (1 mm), an empty map (sky everywhere).

mod common;

use bytemuck::{Pod, Zeroable};
use glam::DVec3;
use specula::search::{box_exit, box_room, linear_search, parallax_search, search_is_sky, DistanceMap};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Case {
    x: [f32; 4],
    r: [f32; 4],
    knobs: [u32; 4],
    box_min: [f32; 4],
    box_max: [f32; 4],
    center: [f32; 4],
}

/// The secant-refined searches' worst |search − exact exit| / scale per room and knobs
/// (linear steps, secant steps, binary steps, parallax iterations), as measured, and the
/// bound: the measured value × 1.122 (rule 1), or × 10 where it is f64 rounding (the ray
/// through the reference point in the room, which the search lands on exactly).
const EXIT_ERROR: [(&str, [u32; 4], f64, f64); 9] = [
    ("room", [16, 4, 0, 1], 1.456e-3, 1.63e-3),
    ("room", [8, 8, 0, 1], 9.163e-5, 1.02e-4),
    ("room", [16, 8, 0, 1], 1.17e-16, 1.2e-15),
    ("distant wall 1e4 m", [16, 4, 0, 1], 3.304e-8, 3.70e-8),
    ("distant wall 1e4 m", [8, 8, 0, 1], 3.304e-8, 3.70e-8),
    ("distant wall 1e4 m", [16, 8, 0, 1], 1.009e-8, 1.13e-8),
    ("near wall 1 mm", [16, 4, 0, 1], 7.778e-7, 8.72e-7),
    ("near wall 1 mm", [8, 8, 0, 1], 7.836e-7, 8.79e-7),
    ("near wall 1 mm", [16, 8, 0, 1], 1.115e-8, 1.25e-8),
];

struct Room {
    min: DVec3,
    max: DVec3,
    center: DVec3,
    /// 0: closed, 1: empty (sky everywhere), 2: open to the sky at its top (+y).
    sky: u8,
}

/// The open-top room's map: the box room's distance, or sky where the ceiling would be.
fn open_top(min: DVec3, max: DVec3, center: DVec3) -> impl Fn(DVec3) -> f64 {
    let room = box_room(min, max, center);
    move |dir: DVec3| {
        let d = dir.normalize();
        let t = room(dir);
        // The ceiling is the nearest face: its plane is reached at t.
        let ceiling = d.y > 0.0 && ((max.y - center.y) / d.y - t).abs() <= 1e-12 * t.max(1.0);
        if ceiling {
            f64::INFINITY
        } else {
            t
        }
    }
}

fn cases() -> Vec<(Case, &'static str)> {
    let rooms = [
        (Room { min: DVec3::new(-2.0, 0.0, -2.0), max: DVec3::new(2.0, 3.0, 2.0), center: DVec3::new(0.0, 1.5, 0.0), sky: 0 }, "room"),
        (
            Room { min: DVec3::new(-2.0, 0.0, -2.0), max: DVec3::new(2.0, 3.0, 2.0), center: DVec3::new(0.0, 1.5, 0.0), sky: 2 },
            "open-top room",
        ),
        (Room { min: DVec3::splat(-1e4), max: DVec3::splat(1e4), center: DVec3::ZERO, sky: 0 }, "distant wall 1e4 m"),
        (Room { min: DVec3::new(-1e-3, -1.0, -1.0), max: DVec3::splat(1.0), center: DVec3::ZERO, sky: 0 }, "near wall 1 mm"),
        (Room { min: DVec3::splat(-1.0), max: DVec3::splat(1.0), center: DVec3::ZERO, sky: 1 }, "empty map"),
    ];
    let mut dirs: Vec<DVec3> = vec![
        DVec3::X,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(0.0, -1.0, 1.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(-1.0, 1.0, -1.0),
    ];
    for i in 0..24 {
        let a = i as f64 * 0.77;
        dirs.push(DVec3::new(a.cos(), (1.3 * a).sin(), (0.4 * a).cos() - 0.3));
    }
    let mut out = Vec::new();
    for (room, name) in &rooms {
        let s = if name.contains("1e4") {
            1000.0
        } else if name.contains("mm") {
            1e-4
        } else {
            1.0
        };
        let starts = [DVec3::ZERO, DVec3::new(0.3, -0.2, 0.25) * s, DVec3::new(-0.5, 0.4, -0.1) * s];
        for &x in &starts {
            for d in &dirs {
                let r = d.normalize();
                for knobs in [[16, 4, 0, 1], [8, 8, 0, 1], [32, 0, 8, 1], [0, 0, 0, 1], [0, 0, 0, 6]] {
                    let f = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
                    out.push((
                        Case {
                            x: f(x, 1e-6),
                            r: f(r, room.sky as f64),
                            knobs,
                            box_min: f(room.min, 0.0),
                            box_max: f(room.max, 0.0),
                            center: f(room.center, 0.0),
                        },
                        *name,
                    ));
                }
            }
            // The reference point on the ray: a ray through it.
            if x != DVec3::ZERO {
                let r = -x.normalize();
                let f = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
                out.push((
                    Case {
                        x: f(x, 1e-6),
                        r: f(r, room.sky as f64),
                        knobs: [16, 8, 0, 1],
                        box_min: f(room.min, 0.0),
                        box_max: f(room.max, 0.0),
                        center: f(room.center, 0.0),
                    },
                    *name,
                ));
            }
        }
    }
    out
}

#[test]
fn glsl_search_matches_rust_twin() {
    let ctx = common::gpu();
    let table = cases();
    let input: Vec<Case> = table.iter().map(|(c, _)| *c).collect();
    let gpu: Vec<[f32; 4]> = common::run_cases(&ctx, "test/search.comp", &input, &[]);
    let mut worst = 0.0f64;
    let mut exit_worst = std::collections::BTreeMap::new();
    // Open-top room: walls found although the map holds sky in the ray's own direction
    // (the linear search must not stop at an empty far end).
    let mut hidden_by_the_far_end = 0;
    for (i, ((c, name), g)) in table.iter().zip(&gpu).enumerate() {
        let v = |a: [f32; 4]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        let (x, r, center) = (v(c.x), v(c.r), v(c.center));
        let (min, max) = (v(c.box_min), v(c.box_max));
        let (sky, open) = (c.r[3] == 1.0, c.r[3] == 2.0);
        let room = box_room(min, max, center);
        let roofless = open_top(min, max, center);
        let empty = |_: DVec3| f64::INFINITY;
        let map: &dyn Fn(DVec3) -> f64 = if sky {
            &empty
        } else if open {
            &roofless
        } else {
            &room
        };
        let cpu = if c.knobs[0] == 0 {
            parallax_search(&Wrap(map), x, r, c.knobs[3])
        } else {
            linear_search(&Wrap(map), x, r, c.knobs[0], c.knobs[2], c.knobs[1], c.x[3] as f64)
        };
        let what = format!("case {i} ({name}) x={x} r={r} knobs={:?}: gpu {g:?}, cpu {cpu:?}", c.knobs);
        assert_eq!(g[1] != 0.0, cpu.escaped, "escape differs: {what}");
        assert!(g.iter().all(|v| !v.is_nan()), "NaN: {what}");
        if open {
            // The ray meets a wall below the open ceiling, or leaves through the ceiling.
            let exit = x + r * box_exit(min, max, center, x, r);
            let through_ceiling = (exit.y - (max.y - center.y)).abs() <= 1e-9;
            if !through_ceiling && !cpu.escaped && search_is_sky(roofless(r)) {
                hidden_by_the_far_end += 1;
            }
            assert!(cpu.escaped || !through_ceiling || c.knobs[0] == 0, "a hit through the open ceiling: {what}");
        }
        if cpu.escaped {
            assert!(sky || open, "only the empty map and the open ceiling let rays escape here: {what}");
            continue;
        }
        let scale = (x.length() + box_exit(min, max, center, x, r)).max(1e-9);
        let diff = (g[0] as f64 - cpu.d).abs() / scale;
        worst = worst.max(diff);
        // Measured worst 2.42e-7 (f32 rounding); bound 10× that (rule 2).
        assert!(diff < 2.5e-6, "ray parameter differs by {diff:e} of the scale: {what}");
        if c.knobs[0] > 0 && c.knobs[1] >= 4 && !open {
            // Secant-refined searches land on the exact exit of the box. (Binary steps alone
            // halve a bracket that the linear search leaves wide near t → 1: 8 of them are
            // not enough for 0.2 % at 1e4 m; that is the knob's trade, not an error.)
            let exact = box_exit(min, max, center, x, r);
            let err = (cpu.d - exact).abs() / scale;
            let w = exit_worst.entry((*name, c.knobs)).or_insert(0.0f64);
            *w = w.max(err);
            let &(_, _, measured, bound) = EXIT_ERROR
                .iter()
                .find(|(n, k, _, _)| n == name && *k == c.knobs)
                .unwrap_or_else(|| panic!("no measured exit error for {name}, knobs {:?}", c.knobs));
            assert!(err <= bound, "cpu search vs exact exit {exact}: {err:e} of the scale > {bound:e} (measured {measured:e}): {what}");
        }
    }
    eprintln!("{} cases, worst relative difference GPU vs CPU {worst:e}", table.len());
    eprintln!("open-top room: {hidden_by_the_far_end} walls found with sky in the ray's own direction");
    assert!(hidden_by_the_far_end >= 3, "{hidden_by_the_far_end} cases exercise the empty far end (measured 3)");
    for ((name, knobs), w) in &exit_worst {
        eprintln!("{name}, knobs {knobs:?}: worst |search − exact exit| / scale {w:e}");
    }
    assert_eq!(exit_worst.len(), EXIT_ERROR.len(), "every room and knob setting of EXIT_ERROR is checked");
    common::assert_clean(&ctx);
}

struct Wrap<'a>(&'a dyn Fn(DVec3) -> f64);

impl DistanceMap for Wrap<'_> {
    fn distance(&self, dir: DVec3) -> f64 {
        (self.0)(dir)
    }
}
