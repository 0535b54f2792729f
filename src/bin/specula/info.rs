//! `specula info`: meshes, materials with their classification, lights, camera, bounds.

use std::path::Path;

use specula::scene;
use specula::Scene;

/// Prints what the scene holds; a scene with nothing to render is the same one-line error
/// as `render` gives (after the listing), exit 1.
pub fn run(path: &Path) -> specula::Result<()> {
    let s = crate::args::load_scene(path)?;
    print!("{}", info(&s));
    for note in &s.skipped {
        println!("skipped: {note}");
    }
    crate::args::renderable(path, &s)
}

fn info(s: &Scene) -> String {
    use std::fmt::Write as _;
    let mut o = String::new();
    let b = s.bounds();
    let _ = writeln!(o, "meshes: {} ({} triangles)", s.meshes.len(), s.triangle_count());
    for m in &s.meshes {
        let mb = m.bounds();
        let _ = writeln!(
            o,
            "  {:<28} {:>7} tris  material {:<3} box [{:.3} {:.3} {:.3}]..[{:.3} {:.3} {:.3}]",
            m.name,
            m.triangle_count(),
            m.material,
            mb.min.x,
            mb.min.y,
            mb.min.z,
            mb.max.x,
            mb.max.y,
            mb.max.z
        );
    }
    let _ = writeln!(o, "materials: {}", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let detail = match m.kind {
            scene::SurfaceKind::Diffuse => format!("base {:?} emissive {:?}", m.base_color.to_array(), m.emissive.to_array()),
            scene::SurfaceKind::Mirror { nu, kappa } => format!("nu {:?} kappa {:?}", nu.to_array(), kappa.to_array()),
            scene::SurfaceKind::Dielectric { ior, .. } => format!("ior {ior}"),
        };
        let _ = writeln!(o, "  [{i}] {:<20} {:<24} {detail}", m.name, m.kind.label());
    }
    let _ = writeln!(o, "textures: {}", s.textures.len());
    let _ = writeln!(o, "lights: {}", s.lights.len());
    for l in &s.lights {
        let _ = writeln!(
            o,
            "  {:<20} {:?} at {:?} dir {:?} intensity {:?}",
            l.name,
            l.kind,
            l.position.to_array(),
            l.direction.to_array(),
            l.intensity.to_array()
        );
    }
    match &s.camera {
        Some(c) => {
            let _ = writeln!(
                o,
                "camera: at {:?} looking {:?}, yfov {:.1}°",
                c.position.to_array(),
                c.forward().to_array(),
                c.yfov.to_degrees()
            );
        }
        None => {
            let _ = writeln!(o, "camera: none (a default camera frames the bounds)");
        }
    }
    let _ = writeln!(o, "bounds: [{:.3} {:.3} {:.3}]..[{:.3} {:.3} {:.3}]", b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z);
    o
}
