//! The exact tracer's error on each specular object, measured on the scene itself at the
//! frame's size: the part of every method's error that the corpus cannot predict well.
//!
//! An exact tracer renders what the reference renders, one sample per pixel: its error is
//! aliasing alone, and aliasing is a property of the object's image — its silhouette, the
//! edges it reflects and refracts, how far away they are — at this size, which the error
//! model's features describe only coarsely (on the concave mirror at 512² the model
//! predicted the exact tracer at 28.5 dB; it measures 33.9). So the planner measures it: the
//! CPU reference traces a sample of the object's pixels at the pixel centre (what the exact
//! tracers shade), at the four standard multisample positions (`aa=msaa4`, shaded per
//! sample), on a 2×2 grid (`aa=ssaa2`) and with the reference's stratified samples (what
//! the error is measured against), and the mean squared differences are the exact tracer's
//! error under each. [`super::error_model::ErrorModel::predict`] anchors every method's
//! aliasing on it.

use std::collections::BTreeMap;

use glam::DVec3;
use rayon::prelude::*;

use super::samples::Sample;
use crate::error::Result;

use crate::quality::{Caustics, Quality};
use crate::reference::{sample_offset, CameraRays, Tracer};
use crate::scene::Scene;

/// Pixel centres tested for the object they show (a lattice over the frame).
pub const LATTICE: u32 = 16384;
/// Pixels traced per object (evenly spread over its lattice pixels).
pub const PIXELS: usize = 128;
/// The reference's samples per pixel when the quality's `spp` is not a perfect square.
const REFERENCE_SPP: u32 = 16;
/// Vulkan's standard sample locations for 4 samples.
const MSAA4: [(f64, f64); 4] = [(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)];
/// The 2×2 supersampling grid, resolved by averaging.
const SSAA2: [(f64, f64); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

/// The exact tracer's mean squared error (per channel, linear radiance, as PSNR measures it)
/// on an object's pixels against the reference, without anti-aliasing and under the
/// variants the planner chooses among; from `pixels` traced pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aliasing {
    pub pixels: usize,
    pub off: f64,
    pub msaa4: f64,
    pub ssaa2: f64,
}

impl Aliasing {
    /// The error under `aa` (a value of the `aa` knob; `per_sample`: multisamples are
    /// shaded per sample); `None` for one the probe does not trace.
    pub fn mse(&self, aa: &str, per_sample: bool) -> Option<f64> {
        match aa {
            "off" => Some(self.off),
            "msaa4" if per_sample => Some(self.msaa4),
            "ssaa2" => Some(self.ssaa2),
            _ => None,
        }
    }
}

/// Per mesh of `scene` (indexed as `scene.meshes`), the exact tracer's error on its
/// pixels at `size` with `quality`'s bounces and Fresnel; `None` for meshes that are not
/// specular or that no lattice pixel shows, and for every mesh when the reference cannot
/// trace the scene.
pub fn measure(scene: &Scene, quality: &Quality, size: (u32, u32)) -> Vec<Option<Aliasing>> {
    let none = vec![None; scene.meshes.len()];
    let (w, h) = size;
    if w == 0 || h == 0 || scene.specular_meshes().next().is_none() {
        return none;
    }
    let mut q = quality.clone();
    q.caustics.caustics = Caustics::Off; // a caustic is the same light in every sample
    let Ok(tracer) = Tracer::new(scene, &q) else { return none };
    let camera = scene.camera_or_default();
    if camera.validate().is_err() {
        return none;
    }
    let rays = CameraRays::new(&camera, w, h);
    let spp = match quality.reference.spp {
        s if s > 0 && s.isqrt().pow(2) == s => s,
        _ => REFERENCE_SPP,
    };
    let step = ((w as f64 * h as f64 / LATTICE as f64).sqrt().ceil() as u32).max(1);
    let specular: Vec<bool> = (0..scene.meshes.len()).map(|m| scene.specular_meshes().any(|(i, _)| i == m)).collect();
    // One pixel per lattice cell (placed in the cell by a hash), grouped by what it shows.
    let cells: Vec<(u32, u32)> = (0..h.div_ceil(step)).flat_map(|j| (0..w.div_ceil(step)).map(move |i| (i, j))).collect();
    let shown: Vec<Option<(u32, (u32, u32))>> = cells
        .par_iter()
        .map(|&(i, j)| {
            let r = crate::reference::hash(i, j, 0x5eed);
            let x = (i * step + r % step).min(w - 1);
            let y = (j * step + (r >> 16) % step).min(h - 1);
            let (o, d, t) = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            tracer.first_mesh(o, d, t).filter(|&m| specular[m as usize]).map(|m| (m, (x, y)))
        })
        .collect();
    let mut by_mesh: Vec<Vec<(u32, u32)>> = vec![Vec::new(); scene.meshes.len()];
    for (m, p) in shown.into_iter().flatten() {
        by_mesh[m as usize].push(p);
    }
    let depth = tracer.depth();
    let at = |x: u32, y: u32, (dx, dy): (f64, f64)| {
        let (o, d, t) = rays.ray(x as f64 + dx, y as f64 + dy);
        tracer.radiance(o, d, t, depth)
    };
    let mean = |x: u32, y: u32, offsets: &[(f64, f64)]| offsets.iter().map(|&s| at(x, y, s)).sum::<DVec3>() / offsets.len() as f64;
    by_mesh
        .into_iter()
        .map(|pixels| {
            if pixels.is_empty() {
                return None;
            }
            let n = pixels.len().min(PIXELS);
            let chosen: Vec<(u32, u32)> = (0..n).map(|k| pixels[k * pixels.len() / n]).collect();
            let sq = |a: DVec3, b: DVec3| (a - b).length_squared() / 3.0;
            let sums = chosen
                .par_iter()
                .map(|&(x, y)| {
                    let reference: Vec<(f64, f64)> = (0..spp).map(|s| sample_offset(x, y, s, spp)).collect();
                    let r = mean(x, y, &reference);
                    let e = [sq(at(x, y, (0.5, 0.5)), r), sq(mean(x, y, &MSAA4), r), sq(mean(x, y, &SSAA2), r)];
                    if e.iter().all(|v| v.is_finite()) {
                        (e, 1usize)
                    } else {
                        ([0.0; 3], 0)
                    }
                })
                .reduce(|| ([0.0; 3], 0), |a, b| ([a.0[0] + b.0[0], a.0[1] + b.0[1], a.0[2] + b.0[2]], a.1 + b.1));
            let (e, k) = sums;
            (k > 0).then(|| Aliasing { pixels: k, off: e[0] / k as f64, msaa4: e[1] / k as f64, ssaa2: e[2] / k as f64 })
        })
        .collect()
}

/// The exact tracer's error measured on the corpus's objects, by (scene, object, frame
/// pixels): what the planner would measure on each (`error_model::leave_one_scene_out_probed`).
pub type Probes = BTreeMap<(usize, String, u64), Aliasing>;

/// [`measure`] on every object of the corpus scenes (`crate::scenes::corpus`) that `keep`
/// admits, at each size `samples` measured them at, with the default knobs' bounces and
/// Fresnel (square frames, as the corpus renders).
pub fn probe_corpus(samples: &[Sample], keep: &dyn Fn(usize) -> bool) -> Result<Probes> {
    let mut keys: Vec<(usize, u64)> = samples.iter().filter(|s| keep(s.scene)).map(|s| (s.scene, s.work.screen.round() as u64)).collect();
    keys.sort();
    keys.dedup();
    let q = Quality::default();
    let mut probes = Probes::new();
    for (scene, screen) in keys {
        let s = crate::scenes::corpus::scene(scene)?;
        let side = (screen as f64).sqrt().round() as u32;
        for (m, a) in measure(&s, &q, (side, side)).into_iter().enumerate() {
            if let Some(a) = a {
                probes.insert((scene, s.meshes[m].name.clone(), screen), a);
            }
        }
    }
    Ok(probes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A mirror ball in a checkered room (corpus scene 0) aliases at its silhouette and in
    /// the edges it reflects: sampling the pixel more finely brings it nearer the reference,
    /// and a larger frame aliases less; the same call measures the same numbers; a scene
    /// with nothing specular measures nothing.
    #[test]
    fn sampling_more_finely_aliases_less() {
        let mut room = Scene::new();
        crate::scenes::checker_room(&mut room, Vec3::ZERO, 2.0).unwrap();
        assert!(measure(&room, &Quality::default(), (32, 32)).iter().all(Option::is_none));
        let s = crate::scenes::corpus::scene(0).unwrap();
        let ball = s.specular_meshes().next().unwrap().0;
        let q = Quality::default();
        let small = measure(&s, &q, (48, 48))[ball].expect("the ball is in view");
        let large = measure(&s, &q, (192, 192))[ball].unwrap();
        assert!(small.pixels >= 64 && large.pixels == PIXELS, "{small:?} {large:?}");
        assert!(small.off > 0.0 && small.msaa4 < small.off && small.ssaa2 < small.off, "{small:?}");
        assert!(large.off < small.off, "{small:?} {large:?}");
        assert_eq!(measure(&s, &q, (48, 48))[ball], Some(small));
        assert_eq!(small.mse("msaa4", false), None, "multisamples shaded once per pixel are not traced");
    }
}
