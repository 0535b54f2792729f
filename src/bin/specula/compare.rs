//! `specula compare`: image errors of one image against another.

use std::path::Path;

use specula::image::ImageData;
use specula::scene;

fn read_linear(path: &Path) -> specula::Result<ImageData> {
    let e = scene::load_environment(path)?;
    Ok(ImageData { width: e.width, height: e.height, layers: 1, channels: 4, data: e.rgba32f })
}

/// `specula compare`: the metrics of specula::metrics, and the FLIP map in false colour.
pub fn run(test: &Path, reference: &Path, error_image: Option<&Path>) -> specula::Result<()> {
    let (t, r) = (read_linear(test)?, read_linear(reference)?);
    let e = specula::metrics::compare(&t, &r)?;
    println!("{} vs {} ({}x{})", test.display(), reference.display(), t.width, t.height);
    println!("RMSE      {:.6}", e.rmse);
    println!("PSNR      {:.2} dB", e.psnr);
    println!("max |Δ|   {:.6}", e.max_abs);
    println!("p99 |Δ|   {:.6}", e.p99_abs);
    println!("mean FLIP {:.6}", e.flip);
    if let Some(path) = error_image {
        specula::metrics::write_error_png(path, &specula::metrics::flip_map(&t, &r)?, t.width, t.height)?;
        println!("error image: {}", path.display());
    }
    Ok(())
}
