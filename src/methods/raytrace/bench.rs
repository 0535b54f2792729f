//! `specula raytrace-bench`: survey Table 1's rows for ray tracing in the original geometry
//! measured — per scheme and scene size N the structure's CPU build time, the frame's GPU
//! time and the structure's device memory, on a procedural scene (the demo room with a
//! tessellated mirror sphere and glass sphere of N triangles together), plotted log–log;
//! the ray hierarchy's culling rate against its tile size; and the survey's headline
//! ratio, the default distance-map method's frame against `bvh`'s on the demo scene with
//! both methods' PSNR against the reference; and the planner's mutual-view rule measured:
//! k mirror spheres that see each other, the sampled-geometry methods against `bvh`.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::{Error, Result};
use crate::methods::{Method, BIH, BVH, DISTANCE, DISTANCE_MULTI, GRID, KD_TREE, OCTREE, RAY_ENGINE, RAY_HIERARCHY, RAY_QUERY};
use crate::quality::Quality;
use crate::scene::{shapes, Scene};
use crate::vk::Context;

/// The survey's asymptotic class of each scheme's cost per ray (Table 1 and §2).
pub fn complexity(m: Method) -> &'static str {
    match m.name() {
        "ray-engine" => "O(N) per ray",
        "ray-hierarchy" => "O(N) per tile, culled",
        "grid" => "O(N^(1/3)) cells per ray",
        "ray-query" => "O(log N) per ray, the driver's",
        _ => "O(log N) per ray",
    }
}

/// The demo room with its two spheres replaced by tessellations of `n` triangles in all.
pub fn scene_with(demo: &Scene, n: usize) -> Result<Scene> {
    let mut s = demo.clone();
    let spheres: Vec<usize> = s.specular_meshes().map(|(i, _)| i).collect();
    if spheres.len() != 2 {
        return Err(Error::invalid("raytrace-bench", "the demo scene should have two specular spheres"));
    }
    // A uv sphere of `seg` segments and seg/2 rings has seg · (seg − 2) triangles.
    let per = (n / 2).max(8) as f64;
    let seg = ((1.0 + (1.0 + per).sqrt()).round() as u32).max(4);
    for &i in spheres.iter().rev() {
        let m = s.meshes.remove(i);
        let b = m.bounds();
        let c = b.center();
        let r = (b.max - b.min).max_element() * 0.5;
        let mut sphere = shapes::uv_sphere(&m.name, c, r, seg, seg / 2, m.material);
        sphere.aliases = m.aliases.clone();
        s.meshes.insert(i, sphere);
    }
    for m in &mut s.meshes {
        if m.normals.len() != m.positions.len() {
            m.normals = crate::scene::compute_normals(&m.positions, &m.indices);
        }
    }
    s.validate()?;
    Ok(s)
}

/// The demo room with its two spheres replaced by `k` mirror spheres on a ring, each
/// seeing the others (the planner's mutual-view case); the box stays.
pub fn mutual_scene(demo: &Scene, k: usize) -> Result<Scene> {
    let mut s = demo.clone();
    let spheres: Vec<usize> = s.specular_meshes().map(|(i, _)| i).collect();
    let mirror =
        spheres.iter().map(|&i| s.meshes[i].material).find(|&m| matches!(s.materials[m].kind, crate::scene::SurfaceKind::Mirror { .. }));
    let Some(mirror) = mirror else {
        return Err(Error::invalid("raytrace-bench", "the demo scene should have a mirror sphere"));
    };
    for &i in spheres.iter().rev() {
        s.meshes.remove(i);
    }
    let centre = glam::Vec3::new(-0.45, 0.4, -0.55);
    for j in 0..k {
        let a = std::f32::consts::TAU * j as f32 / k.max(1) as f32 + 0.4;
        let c = centre + if k > 1 { 0.8 * glam::Vec3::new(a.cos(), 0.0, a.sin()) } else { glam::Vec3::ZERO };
        s.meshes.push(shapes::uv_sphere(&format!("mirror_{j}"), c, 0.38, 48, 24, mirror));
    }
    s.validate()?;
    Ok(s)
}

/// Which parts [`run`] measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    Table1,
    Culling,
    Headline,
    Mutual,
    Moves,
}

impl Part {
    pub fn parse(s: &str) -> Option<Part> {
        Some(match s {
            "table1" => Part::Table1,
            "culling" => Part::Culling,
            "headline" => Part::Headline,
            "mutual" => Part::Mutual,
            "moves" => Part::Moves,
            _ => return None,
        })
    }
}

/// One measured cell of Table 1.
#[derive(Clone, Debug)]
pub struct Row {
    pub method: &'static str,
    pub objects_triangles: usize,
    pub scene_triangles: usize,
    /// The structure's build: CPU milliseconds, or for `ray-query` the BLAS builds' GPU ms.
    pub build_ms: f64,
    /// `ray-query`: the TLAS build's GPU ms within the frame (rebuilt every frame here,
    /// `map_updates=always`).
    pub tlas_ms: f64,
    pub frame_ms: f64,
    pub structure_bytes: u64,
}

fn structure_bytes(frame: &crate::Frame, scheme: &str) -> u64 {
    let prefix = format!("raytrace.{scheme}.");
    frame.memory.iter().filter(|(n, _)| n.starts_with(&prefix) && !n.ends_with(".triangles")).map(|(_, b)| b).sum()
}

/// Renders `scene` with `m` (median of `frames` after one warm-up) and returns the row.
fn measure(ctx: &Context, scene: &Scene, m: Method, q: &Quality, size: (u32, u32), frames: u32, n: usize) -> Result<Row> {
    let f = crate::render(ctx, scene, m, q, size, (1, frames))?;
    let stat = |name: &str| f.stats.iter().find(|(k, _)| k == name).map_or(0.0, |(_, v)| *v);
    let gpu_build: f64 = f.passes.iter().filter(|p| p.name == "raytrace.build").map(|p| p.gpu_ms).sum();
    let scheme = match m.name() {
        "kd-tree" => "kdtree",
        other => other,
    };
    Ok(Row {
        method: m.name(),
        objects_triangles: n,
        scene_triangles: scene.triangle_count(),
        // ray-query: the BLAS builds' GPU time (its CPU side is nothing); a BVH built on the
        // GPU (bvh_build=lbvh, rebuilt every frame under map_updates=always): its pass, out
        // of the frame, which is then the traversal's alone.
        build_ms: if m == RAY_QUERY {
            stat("raytrace.blas_build_ms")
        } else if gpu_build > 0.0 {
            gpu_build
        } else {
            stat("raytrace.build_ms")
        },
        tlas_ms: f.passes.iter().filter(|p| p.name == "raytrace.tlas").map(|p| p.gpu_ms).sum(),
        frame_ms: f.gpu_ms() - gpu_build,
        structure_bytes: structure_bytes(&f, scheme),
    })
}

/// What [`run`] measures.
pub struct Config {
    pub demo: Scene,
    pub sizes: Vec<usize>,
    pub size: (u32, u32),
    pub depth: u32,
    /// A scheme whose frame exceeds this is not measured at larger N.
    pub budget_ms: f64,
    pub frames: u32,
    /// The headline comparison's image size.
    pub headline_size: (u32, u32),
    pub parts: Vec<Part>,
}

/// Runs the benchmark; prints its tables and returns them as Markdown, writing the plot
/// (`table1.svg`) and the rows (`table1.csv`) into `out`.
pub fn run(ctx: &Context, c: &Config, out: &Path) -> Result<String> {
    let methods = [BVH, KD_TREE, GRID, OCTREE, BIH, RAY_QUERY, RAY_HIERARCHY, RAY_ENGINE];
    let q = {
        let mut knobs = Quality::default();
        knobs.frame.depth = c.depth;
        knobs.frame.map_updates_always = true;
        knobs
    };
    let mut rows: Vec<Row> = Vec::new();
    let mut md = String::new();
    if c.parts.contains(&Part::Table1) {
        table1(ctx, c, &q, &methods, &mut md, &mut rows)?;
    }
    if c.parts.contains(&Part::Culling) {
        culling(ctx, c, &q, &mut md)?;
    }
    if c.parts.contains(&Part::Headline) {
        headline(ctx, c, &q, &mut md)?;
    }
    if c.parts.contains(&Part::Mutual) {
        mutual(ctx, c, &q, &mut md)?;
    }
    if c.parts.contains(&Part::Moves) {
        moves(ctx, c, &mut md)?;
    }
    if !rows.is_empty() {
        write_table1(&rows, c, out)?;
    }
    Ok(md)
}

fn table1(ctx: &Context, c: &Config, q: &Quality, methods: &[Method], md: &mut String, rows: &mut Vec<Row>) -> Result<()> {
    let mut stopped: Vec<String> = Vec::new();
    let _ = writeln!(md, "### Table 1 measured: {}×{}, depth {}, median of {} frames\n", c.size.0, c.size.1, c.depth, c.frames);
    let _ = writeln!(md, "| scheme | class | N (objects) | scene triangles | build ms (CPU; ray-query's BLAS and bvh_build=lbvh: GPU) | TLAS ms (GPU) | frame ms (GPU; lbvh: without its build) | structure memory |");
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|");
    // Every scheme at its defaults, and the knob variants that change its traversal or its
    // scene: the kd-tree's ropes, the octree's volumetric approximation (approximate).
    let mut runs: Vec<(&'static str, Method, Quality)> = methods.iter().map(|&m| (m.name(), m, q.clone())).collect();
    // (and bvh built on the GPU: a linear BVH, what moving geometry gets).
    for (label, m, pair) in [
        ("bvh, bvh_build=lbvh", BVH, "bvh_build=lbvh"),
        ("kd-tree, kd_traversal=ropes", KD_TREE, "kd_traversal=ropes"),
        ("octree, octree_volume=on", OCTREE, "octree_volume=on"),
    ] {
        let mut qv = q.clone();
        qv.set_pair(pair)?;
        runs.push((label, m, qv));
    }
    for &n in &c.sizes {
        let scene = scene_with(&c.demo, n)?;
        for (label, m, q) in &runs {
            let (label, m) = (*label, *m);
            if stopped.iter().any(|s| s.starts_with(label)) {
                continue;
            }
            let mut row = measure(ctx, &scene, m, q, c.size, c.frames, n)?;
            row.method = label;
            let line = format!(
                "| {} | {} | {} | {} | {:.1} | {} | {:.1} | {:.2} MiB |",
                row.method,
                complexity(m),
                n,
                row.scene_triangles,
                row.build_ms,
                if m == RAY_QUERY { format!("{:.2}", row.tlas_ms) } else { "–".into() },
                row.frame_ms,
                row.structure_bytes as f64 / (1 << 20) as f64
            );
            println!("{line}");
            let _ = writeln!(md, "{line}");
            if row.frame_ms > c.budget_ms {
                stopped.push(format!(
                    "{} stopped after N = {n}: its frame took {:.0} ms > the budget of {:.0} ms",
                    label, row.frame_ms, c.budget_ms
                ));
            }
            rows.push(row);
        }
    }
    for s in &stopped {
        println!("{s}");
        let _ = writeln!(md, "\n{s}.");
    }
    Ok(())
}

fn culling(ctx: &Context, c: &Config, q: &Quality, md: &mut String) -> Result<()> {
    // The ray hierarchy's culling against its tile size (demo scene).
    let _ = writeln!(md, "\n### Ray-hierarchy culling rate (tile × triangle pairs rejected by the cone test), demo scene\n");
    let _ = writeln!(md, "| tile | frame ms | culling per bounce: rays / shadow rays |");
    let _ = writeln!(md, "|---:|---:|---|");
    for tile in [8u32, 16, 32] {
        let qt = {
            let mut knobs = q.clone();
            knobs.raytrace.tile_size = tile;
            knobs.raytrace.ray_stats = true;
            knobs
        };
        let f = crate::render(ctx, &c.demo, RAY_HIERARCHY, &qt, c.size, (0, 1))?;
        let mut per = Vec::new();
        for k in 0..=c.depth {
            let get = |label: &str| f.stats.iter().find(|(n, _)| *n == format!("raytrace.cull_rate.bounce{k}.{label}")).map(|(_, v)| *v);
            let fmt = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{:.0} %", 100.0 * v));
            per.push(format!("{}: {} / {}", k, fmt(get("rays")), fmt(get("shadow_rays"))));
        }
        let line = format!("| {tile} | {:.1} | {} |", f.gpu_ms(), per.join("; "));
        println!("{line}");
        let _ = writeln!(md, "{line}");
    }
    Ok(())
}

fn headline(ctx: &Context, c: &Config, q: &Quality, md: &mut String) -> Result<()> {
    // The headline: sampled geometry against ray tracing in the original geometry.
    let (w, h) = c.headline_size;
    let reference = crate::reference::render_reference(
        &c.demo,
        &{
            let mut knobs = q.clone();
            knobs.reference.spp = 1;
            knobs
        },
        (w, h),
    )?;
    let mut head = Vec::new();
    for m in [DISTANCE, BVH] {
        let f = crate::render(ctx, &c.demo, m, q, (w, h), (1, c.frames))?;
        let psnr = crate::metrics::compare(&f.image, &reference)?.psnr;
        head.push((m.name(), f.gpu_ms(), psnr));
    }
    let _ = writeln!(md, "\n### Sampled geometry against the original geometry: demo scene, {w}×{h}, depth {}\n", c.depth);
    let _ = writeln!(md, "| method | frame ms (GPU) | PSNR vs reference (1 spp, same depth) |");
    let _ = writeln!(md, "|---|---:|---:|");
    for (name, ms, psnr) in &head {
        let line = format!("| {name} | {ms:.1} | {psnr:.2} dB |");
        println!("{line}");
        let _ = writeln!(md, "{line}");
    }
    let ratio = head[1].1 / head[0].1;
    let line = format!("bvh's frame / distance's frame = {ratio:.2}× (the survey's claim: sampled geometry at least 10× faster; the compass goal ≥ 20× at ≥ 35 dB)");
    println!("{line}");
    let _ = writeln!(md, "\n{line}.");
    Ok(())
}

/// The planner's mutual-view rule measured: k = 1 … 5 mirror spheres that see each other,
/// `distance` (single-bounce maps), `distance-multi` (inter-object cycles) and `bvh`, each
/// frame against its PSNR.
fn mutual(ctx: &Context, c: &Config, q: &Quality, md: &mut String) -> Result<()> {
    let (w, h) = c.size;
    let _ = writeln!(md, "\n### Mutual view: k mirror spheres on a ring in the demo room, {w}×{h}, depth {}\n", c.depth);
    let _ = writeln!(md, "| k | method | frame ms (GPU) | PSNR vs reference | bvh's frame / this frame |");
    let _ = writeln!(md, "|---:|---|---:|---:|---:|");
    for k in 1..=5usize {
        let scene = mutual_scene(&c.demo, k)?;
        let reference = crate::reference::render_reference(
            &scene,
            &{
                let mut knobs = q.clone();
                knobs.reference.spp = 1;
                knobs
            },
            (w, h),
        )?;
        let mut got = Vec::new();
        for m in [DISTANCE, DISTANCE_MULTI, BVH] {
            let f = crate::render(ctx, &scene, m, q, (w, h), (1, c.frames))?;
            got.push((m.name(), f.gpu_ms(), crate::metrics::compare(&f.image, &reference)?.psnr));
        }
        let bvh_ms = got[2].1;
        for (name, ms, psnr) in &got {
            let line = format!("| {k} | {name} | {ms:.1} | {psnr:.2} dB | {:.2} |", bvh_ms / ms);
            println!("{line}");
            let _ = writeln!(md, "{line}");
        }
    }
    Ok(())
}

/// What a move costs `bvh` on Table 1's ladder: the mirror sphere moves every frame by
/// 0.02 or 0.3 of its diagonal (`frames` moves after a first frame), and the tree follows
/// by `bvh_update` — the CPU's SAH builder (the frame waits for it), a linear BVH built on
/// the GPU, a GPU refit of the first frame's SAH tree (its boxes loosen as the sphere
/// travels), or auto's choice between them. Per way: the
/// median CPU milliseconds of the update, the GPU milliseconds of the build or refit pass,
/// and of the frame's traversal and shading without it.
fn moves(ctx: &Context, c: &Config, md: &mut String) -> Result<()> {
    let (w, h) = c.size;
    let _ = writeln!(md, "\n### What a move costs bvh: {w}×{h}, depth {}, median of {} moves of the mirror sphere\n", c.depth, c.frames);
    let _ = writeln!(md, "| N (objects) | move (of the sphere's diagonal) | bvh_update | update ms (CPU) | build or refit ms (GPU) | frame ms without it (GPU) |");
    let _ = writeln!(md, "|---:|---:|---|---:|---:|---:|");
    for &n in &c.sizes {
        let scene = scene_with(&c.demo, n)?;
        let mirror = scene
            .meshes
            .iter()
            .position(|m| matches!(scene.materials[m.material].kind, crate::scene::SurfaceKind::Mirror { .. }))
            .ok_or_else(|| Error::invalid("raytrace-bench", "the demo scene should have a mirror sphere"))?;
        let size = scene.meshes[mirror].bounds().diagonal();
        for (step, way) in [0.02f32, 0.3, 1.0].into_iter().flat_map(|s| ["sah", "lbvh", "refit", "auto"].map(|w| (s, w))) {
            let mut q = Quality::default();
            q.frame.depth = c.depth;
            q.set("bvh_update", way)?;
            let plan = crate::plan::plan_with(&scene, &crate::plan::Choices::all(BVH), &q)?;
            let mut r = crate::Renderer::new(ctx, &scene, plan, w, h)?;
            let mut moved = scene.clone();
            let result = (|| {
                r.render(ctx)?;
                let (mut cpu, mut gpu, mut frame) = (Vec::new(), Vec::new(), Vec::new());
                for k in 1..=c.frames {
                    let world =
                        glam::Mat4::from_translation(glam::Vec3::new(step * size * k as f32, 0.0, 0.0)) * scene.meshes[mirror].world;
                    moved.set_object_transform(mirror, world)?;
                    r.update(&moved)?;
                    let f = r.render(ctx)?;
                    let stat = |name: &str| f.stats.iter().find(|(k, _)| k == name).map_or(0.0, |(_, v)| *v);
                    let pass: f64 =
                        f.passes.iter().filter(|p| p.name == "raytrace.build" || p.name == "raytrace.refit").map(|p| p.gpu_ms).sum();
                    // The CPU side of the update: the SAH build, or the triangles rewritten.
                    cpu.push(stat("raytrace.build_ms"));
                    gpu.push(pass);
                    frame.push(f.gpu_ms() - pass);
                }
                Ok::<_, Error>((median(&mut cpu), median(&mut gpu), median(&mut frame)))
            })();
            r.destroy(ctx);
            let (cpu, gpu, frame) = result?;
            let line = format!("| {n} | {step} | {way} | {cpu:.1} | {:.1} | {frame:.1} |", gpu.max(0.0));
            println!("{line}");
            let _ = writeln!(md, "{line}");
        }
    }
    Ok(())
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

fn write_table1(rows: &[Row], c: &Config, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut csv = String::from("method,objects_triangles,scene_triangles,build_ms,tlas_ms,frame_ms,structure_bytes\n");
    for r in rows {
        let _ = writeln!(
            csv,
            "{},{},{},{:.3},{:.3},{:.3},{}",
            r.method, r.objects_triangles, r.scene_triangles, r.build_ms, r.tlas_ms, r.frame_ms, r.structure_bytes
        );
    }
    crate::output::write_file(&out.join("table1.csv"), csv.as_bytes())?;
    let mut svg = String::new();
    crate::output::register_font()?;
    plot(&mut svg, rows, c).map_err(|e| Error::invalid("table1.svg", e))?;
    crate::output::write_file(&out.join("table1.svg"), svg.as_bytes())
}

/// Frame time against N, log–log, one line per scheme.
fn plot(svg: &mut String, rows: &[Row], c: &Config) -> std::result::Result<(), String> {
    use plotters::prelude::*;
    let err = |e: &dyn std::fmt::Display| e.to_string();
    let root = SVGBackend::with_string(svg, (960, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let n_max = rows.iter().map(|r| r.objects_triangles as f64).fold(10.0, f64::max) * 2.0;
    let t_max = rows.iter().map(|r| r.frame_ms.max(r.build_ms)).fold(10.0, f64::max) * 2.0;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Table 1 measured: ray tracing in the original geometry, {}×{}, depth {}", c.size.0, c.size.1, c.depth),
            ("sans-serif", 20),
        )
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((500.0..n_max).log_scale(), (1.0..t_max).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("N: triangles of the specular objects")
        .y_desc("ms (solid: GPU frame, dashed: CPU build)")
        .draw()
        .map_err(|e| err(&e))?;
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.method) {
            names.push(r.method);
        }
    }
    for (k, name) in names.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let pts: Vec<(f64, f64)> =
            rows.iter().filter(|r| r.method == *name).map(|r| (r.objects_triangles as f64, r.frame_ms.max(1.0))).collect();
        chart
            .draw_series(LineSeries::new(pts.iter().copied(), ShapeStyle::from(&color).stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, color.filled()))).map_err(|e| err(&e))?;
        let build: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.method == *name && r.build_ms > 0.0)
            .map(|r| (r.objects_triangles as f64, r.build_ms.max(1.0)))
            .collect();
        if !build.is_empty() {
            chart.draw_series(DashedLineSeries::new(build, 6, 4, ShapeStyle::from(&color).stroke_width(1))).map_err(|e| err(&e))?;
        }
    }
    chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw().map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutual_scene_puts_k_mirror_spheres_apart_in_the_room() {
        let demo = crate::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo/demo.gltf")).unwrap();
        for k in 1..=5 {
            let s = mutual_scene(&demo, k).unwrap();
            let spheres: Vec<_> = s.specular_meshes().map(|(_, m)| m.bounds()).collect();
            assert_eq!(spheres.len(), k);
            for (i, a) in spheres.iter().enumerate() {
                assert!(a.min.cmpge(glam::Vec3::new(-2.0, 0.0, -2.0)).all() && a.max.cmple(glam::Vec3::new(2.0, 3.0, 2.0)).all());
                for b in &spheres[i + 1..] {
                    assert!((a.center() - b.center()).length() > 0.8, "spheres {k} overlap");
                }
            }
        }
        assert_eq!(Part::parse("mutual"), Some(Part::Mutual));
        assert_eq!(Part::parse("tabel1"), None);
    }
}
