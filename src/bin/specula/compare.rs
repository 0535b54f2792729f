//! `specula compare`: image errors of one image against another.

use std::path::Path;

use specula::image::ImageData;
use specula::scene;

fn read_linear(path: &Path) -> specula::Result<ImageData> {
    let e = scene::load_environment(path)?;
    Ok(ImageData { width: e.width, height: e.height, layers: 1, channels: 4, data: e.rgba32f })
}

/// `specula compare`: the metrics of specula::metrics, and the FLIP map in false colour;
/// with the scene, the errors per specular object, on the specular pixels and on the rest,
/// and the error image restricted to one of those masks.
pub fn run(
    test: &Path,
    reference: &Path,
    error_image: Option<&Path>,
    scene_path: Option<&Path>,
    mask: Option<&str>,
) -> specula::Result<()> {
    let (t, r) = (read_linear(test)?, read_linear(reference)?);
    let e = specula::metrics::compare(&t, &r)?;
    println!("{} vs {} ({}x{})", test.display(), reference.display(), t.width, t.height);
    println!("RMSE      {:.6}", e.rmse);
    println!("PSNR      {:.2} dB", e.psnr);
    println!("max |Δ|   {:.6}", e.max_abs);
    println!("p99 |Δ|   {:.6}", e.p99_abs);
    println!("mean FLIP {:.6}", e.flip);
    let mut keep: Option<Vec<bool>> = None;
    if let Some(path) = scene_path {
        let s = crate::args::load_scene(path)?;
        let ids = specula::reference::object_ids(&s, (t.width, t.height))?;
        let specular: Vec<bool> = s.meshes.iter().map(|m| s.materials[m.material].kind.is_specular()).collect();
        let names: Vec<String> = s.meshes.iter().map(|m| m.name.clone()).collect();
        println!("{:<24} {:>8} {:>10} {:>10}", "pixels of", "count", "PSNR dB", "RMSE");
        for m in specula::metrics::errors_by_object(&t, &r, &ids, &specular, &names)? {
            println!("{:<24} {:>8} {:>10.2} {:>10.6}", m.name, m.pixels, m.psnr, m.rmse);
        }
        if let Some(name) = mask {
            let is_specular = |id: u32| id > 0 && specular[id as usize - 1];
            let object = names.iter().position(|n| n == name);
            let mask: Vec<bool> = match (name, object) {
                ("specular", _) => ids.iter().map(|&id| is_specular(id)).collect(),
                ("non-specular", _) => ids.iter().map(|&id| !is_specular(id)).collect(),
                (_, Some(m)) => ids.iter().map(|&id| id == m as u32 + 1).collect(),
                _ => {
                    return Err(specula::Error::invalid(
                        "--mask",
                        format!("'{}' is neither specular, non-specular nor an object of {}", specula::error::clip(name), path.display()),
                    ))
                }
            };
            keep = Some(mask);
        }
    }
    if let Some(path) = error_image {
        let mut map = specula::metrics::flip_map(&t, &r)?;
        if let Some(keep) = &keep {
            map.iter_mut().zip(keep).filter(|(_, k)| !**k).for_each(|(v, _)| *v = 0.0);
        }
        specula::metrics::write_error_png(path, &map, t.width, t.height)?;
        println!("error image: {}{}", path.display(), mask.map_or(String::new(), |m| format!(" (pixels of {m} only)")));
    }
    Ok(())
}
