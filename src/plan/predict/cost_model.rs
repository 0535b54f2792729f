//! Cost models: per method, an object's GPU milliseconds on one device as non-negative
//! unit costs times its workload (`features`), split as the frame spends them: map passes
//! (a constant per object, cube-map rasterisation per texel × scene triangle, per texel,
//! per texel × light, per texel × caustic cube), camera work (per covered pixel; per pixel ×
//! hierarchy depth, more for dielectrics, whose rays bounce; per object) and whole-screen
//! kernels (per frame, per screen pixel, × hierarchy depth, × lights, × caustic cubes), and
//! the frame's base: its own stages and its effects, the same whatever methods the objects
//! get (per frame, per screen pixel, per light, per light × scene triangle, and the
//! caustics' photons, cube texels and receiver rasterisation: [`BASE_FEATURES`]). The unit
//! costs are fitted (non-negative least squares) on a calibration run on the device itself
//! (`tradeoff::calibrate`), keyed by the device and cached on disk.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use super::device::DeviceKey;
use super::features::{map_features, screen_features, shared_features, Workload, MAP_FEATURES, SCREEN_FEATURES, SHARED_FEATURES};
use super::linear;
use super::samples::Corpus;
use crate::error::{Error, Result};

/// The first line of every cost file's `format` field.
/// (2: anti-aliasing's samples, multisampled and supersampled, as workload terms of their
/// own; 3: a method's whole-screen kernels gain a constant per frame and one per scene
/// triangle. `MethodCost::under`, the under-prediction margin, came later without a new
/// format: a file without it reads as margin 1. 4: light terms (lit cube texels, shadow
/// rays, caustic cubes read, the caustics themselves in the frame's base), a constant per
/// object in the camera work, and the whole-screen kernels' term per scene triangle gone.
/// 5: a method's own maps' texels, not one cube's; its maps of the whole scene and the
/// layers its search reads as terms of their own.)
pub const FORMAT: &str = "specula-costs 5";

/// The quantile of a method's measured-over-predicted frame times that [`MethodCost::under`]
/// keeps, frames weighted by their measured time: the median, the fit's bias on the method's
/// frames. (The 90 % quantile, 1.1–1.7 with the light terms, made `--max-ms` give up the
/// exact tracer where it fitted T by 25 %: a plan of 12 dB instead of 27 on corpus-49; the
/// issue's contract is on the median frame, within 1.25 T.)
pub const UNDER_QUANTILE: f64 = 0.5;

/// Unit costs of one method, over `features::MAP_FEATURES` (per object, its maps),
/// `SCREEN_FEATURES` (per object, its camera work) and `SHARED_FEATURES` (per frame, the
/// method's whole-screen kernels).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodCost {
    pub fixed: Vec<f64>,
    pub screen: Vec<f64>,
    pub shared: Vec<f64>,
    /// Inter-object cycles of the frames it was measured in (the map part covers that many).
    pub cycles: u32,
    pub samples: usize,
    /// Its frames' measured time over the fit's prediction, at [`UNDER_QUANTILE`] of the
    /// calibration's measured time of the method (frames weighted by their time, so that a
    /// frame of a tenth of a millisecond does not set it), at least 1: how far the fit
    /// under-predicts this method's frames. A frame-time budget (`--max-ms`) counts the
    /// method's time times this.
    #[serde(default = "unit")]
    pub under: f64,
}

fn unit() -> f64 {
    1.0
}

/// The `q` quantile of values weighted by their weights (`(value, weight)`): the least value
/// whose values at most it carry a `q` share of the weight; 1 for none.
fn quantile(mut v: Vec<(f64, f64)>, q: f64) -> f64 {
    v.retain(|(_, w)| *w > 0.0);
    if v.is_empty() {
        return 1.0;
    }
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = v.iter().map(|(_, w)| w).sum();
    let mut sum = 0.0;
    for &(value, w) in &v {
        sum += w;
        if sum >= q * total * (1.0 - 1e-12) {
            return value;
        }
    }
    v[v.len() - 1].0
}

/// One device's unit costs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CostModel {
    pub format: String,
    pub key: DeviceKey,
    pub methods: BTreeMap<String, MethodCost>,
    /// Over [`BASE_FEATURES`].
    pub base: Vec<f64>,
    /// Seconds the calibration took.
    pub calibration_s: f64,
    /// What following moved geometry costs the BVH on this device (`bvh_update=auto`
    /// rebuilds by the cheaper builder); none in files from before they were measured.
    #[serde(default)]
    pub bvh_updates: Option<BvhUpdateCosts>,
}

/// What following moved geometry costs the BVH on one device, per way milliseconds =
/// `[a, b]`: a + b · triangles / 10⁶, fitted over the calibration's ladder of triangle counts
/// (`tradeoff::calibrate::BVH_LADDER`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BvhUpdateCosts {
    /// The CPU's SAH build (host milliseconds: the frame waits for it).
    pub sah: [f64; 2],
    /// A linear BVH built on the GPU (its pass, `raytrace.build`).
    pub lbvh: [f64; 2],
    /// A refit on the GPU (`raytrace.refit`).
    pub refit: [f64; 2],
}

impl BvhUpdateCosts {
    /// Milliseconds of `way` over `triangles`.
    pub fn predict(way: [f64; 2], triangles: f64) -> f64 {
        (way[0] + way[1] * triangles / 1e6).max(0.0)
    }

    /// Fitted from timings: per way the least-squares line through its (triangles, ms),
    /// slope and intercept at least 0 (the other refitted where one is clamped). None unless
    /// every way has timings at two triangle counts or more.
    pub fn fit(samples: &[super::samples::BvhUpdateSample]) -> Option<BvhUpdateCosts> {
        let line = |way: &str| -> Option<[f64; 2]> {
            let pts: Vec<(f64, f64)> = samples
                .iter()
                .filter(|s| s.way == way && s.triangles.is_finite() && s.ms.is_finite())
                .map(|s| (s.triangles / 1e6, s.ms))
                .collect();
            let n = pts.len() as f64;
            let (sx, sy) = pts.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
            let (mx, my) = (sx / n, sy / n);
            let sxx: f64 = pts.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
            if pts.len() < 2 || sxx <= 0.0 {
                return None;
            }
            let b = pts.iter().map(|(x, y)| (x - mx) * (y - my)).sum::<f64>() / sxx;
            let a = my - b * mx;
            Some(match (a >= 0.0, b >= 0.0) {
                (true, true) => [a, b],
                // Through the origin: the slope alone.
                (false, _) => [0.0, (pts.iter().map(|(x, y)| x * y).sum::<f64>() / pts.iter().map(|(x, _)| x * x).sum::<f64>()).max(0.0)],
                (true, false) => [my.max(0.0), 0.0],
            })
        };
        Some(BvhUpdateCosts { sah: line("sah")?, lbvh: line("lbvh")?, refit: line("refit")? })
    }
}

/// Names of the frame's base features, in the order [`base_features`] returns them.
pub const BASE_FEATURES: [&str; 8] =
    ["frame", "screen", "lights", "light_triangles", "caustic_photons", "caustic_texels", "caustic_raster", "caustic_screen"];

/// What the frame's base scales with (its own stages, and its effects, which cost the same
/// whatever methods the objects get): a constant, the screen's pixels (1e4: direct light,
/// resolve), per light and per light × scene triangle (1e4: shadow maps), and the caustics
/// (§6): photons traced (1e6: photon images, splats or caustic triangles), caustic cube
/// texels (1e6: clears, filters), those times the scene's triangles (1e9: the receiver
/// maps' rasterisation), and the screen where there are caustics (their projection onto the
/// camera's diffuse surfaces). The screen terms count supersamples (the whole frame renders
/// larger), not multisamples (diffuse surfaces shade once per pixel).
fn base_features(w: &Workload) -> Vec<f64> {
    let screen = w.screen * if w.supersampled > 0.0 { w.samples } else { 1.0 } / 1e4;
    let caustics = (w.caustic_photons > 0.0) as u8 as f64;
    vec![
        1.0,
        screen,
        w.lights,
        w.lights * w.scene_triangles / 1e4,
        w.caustic_photons / 1e6,
        w.caustic_texels / 1e6,
        w.caustic_texels * w.scene_triangles / 1e9,
        screen * caustics,
    ]
}

impl CostModel {
    /// Fits unit costs from a measurement run on the device `key`.
    pub fn fit(corpus: &Corpus, key: DeviceKey, calibration_s: f64) -> CostModel {
        let mut by: BTreeMap<String, Vec<&super::samples::Sample>> = BTreeMap::new();
        for s in &corpus.samples {
            by.entry(super::error_model::candidate(&s.method, &s.knobs)).or_default().push(s);
        }
        // Plain methods first: a `METHOD+hybrid` candidate is fitted as its method's unit
        // costs plus non-negative extra ones (its ray queries come on top of the method's
        // own passes; fitted alone, its few frames at one cube size put the cube maps' cost
        // into the constant, and it could be predicted cheaper than its method).
        let mut order: Vec<(String, Vec<&super::samples::Sample>)> = by.into_iter().collect();
        order.sort_by_key(|(m, _)| m.contains('+'));
        let mut methods: BTreeMap<String, MethodCost> = BTreeMap::new();
        for (m, ss) in order {
            let plain = methods.get(super::error_model::candidate_method(&m)).filter(|_| m.contains('+')).cloned();
            let cost = Self::fit_method(&ss, plain.as_ref());
            methods.insert(m, cost);
        }
        let xb: Vec<Vec<f64>> = corpus.frames.iter().map(|f| base_features(&f.work)).collect();
        let yb: Vec<f64> = corpus.frames.iter().map(|f| f.base_ms).collect();
        let wb = vec![1.0; yb.len()];
        let base = linear::fit(&xb, &yb, &wb, 1e-4, true);
        let bvh_updates = BvhUpdateCosts::fit(&corpus.bvh_updates);
        CostModel { format: FORMAT.into(), key, methods, base, calibration_s, bvh_updates }
    }

    /// One candidate's unit costs from its samples; over `plain` (its method's), as extra
    /// non-negative unit costs added to them.
    fn fit_method(ss: &[&super::samples::Sample], plain: Option<&MethodCost>) -> MethodCost {
        // Relative error matters (a 1 ms part beside a 100 ms one): weight by 1/y².
        let nnls = |x: Vec<Vec<f64>>, y: Vec<f64>| {
            let mean = y.iter().sum::<f64>() / y.len().max(1) as f64;
            let w: Vec<f64> = y.iter().map(|v| 1.0 / (v + 0.1 * mean + 1e-3).powi(2)).collect();
            linear::fit(&x, &y, &w, 1e-4, true)
        };
        // Fits `x → y` as `plain`'s costs (if any) plus non-negative extra ones.
        let fit_over = |x: Vec<Vec<f64>>, y: Vec<f64>, plain: Option<Vec<f64>>| {
            let own = |x: &[f64]| plain.as_ref().map_or(0.0, |b| linear::dot(b, x));
            let extra = nnls(x.clone(), x.iter().zip(&y).map(|(x, y)| (y - own(x)).max(0.0)).collect());
            match &plain {
                Some(b) => extra.iter().zip(b).map(|(e, b)| e + b).collect(),
                None => extra,
            }
        };
        // Maps: per object.
        let fixed = fit_over(
            ss.iter().map(|s| map_features(&s.work)).collect(),
            ss.iter().map(|s| s.fixed_ms).collect(),
            plain.map(|p| p.fixed.clone()),
        );
        // Camera work and whole-screen kernels: per frame (a ray tracer's kernels serve
        // every object at once; its time is the frame's, its features the sum of its
        // objects' and the screen's).
        let mut frames: Vec<(Vec<f64>, f64)> = Vec::new();
        let mut keys: Vec<(usize, &str, u64)> = Vec::new();
        // Per frame, its objects' map shares: (measured, predicted), for the margin below.
        let mut maps: Vec<(f64, f64)> = Vec::new();
        for s in ss {
            let key = (s.scene, s.knobs.as_str(), s.work.screen as u64);
            let per = screen_features(&s.work);
            let k = keys.iter().position(|k| *k == key).unwrap_or(keys.len());
            if k == maps.len() {
                maps.push((0.0, 0.0));
            }
            maps[k].0 += s.fixed_ms;
            maps[k].1 += linear::dot(&fixed, &map_features(&s.work));
            if k < keys.len() {
                let (x, y) = &mut frames[k];
                per.iter().enumerate().for_each(|(j, v)| x[j] += v);
                *y += s.screen_ms;
            } else {
                keys.push(key);
                let mut x = per;
                x.extend(shared_features(&s.work));
                frames.push((x, s.screen_ms + s.shared_ms));
            }
        }
        let (x, y): (Vec<Vec<f64>>, Vec<f64>) = frames.into_iter().unzip();
        let beta = fit_over(x.clone(), y.clone(), plain.map(|p| p.screen.iter().chain(&p.shared).copied().collect()));
        let n = SCREEN_FEATURES.len();
        // Per frame (its map shares, camera work and kernels): measured over predicted, and
        // the measured ms.
        let ratios: Vec<(f64, f64)> = x
            .iter()
            .zip(&y)
            .zip(&maps)
            .map(|((x, y), (mm, mp))| ((y + mm) / (linear::dot(&beta, x) + mp).max(1e-6), y + mm))
            .filter(|(r, _)| r.is_finite())
            .collect();
        MethodCost {
            fixed,
            screen: beta[..n].to_vec(),
            shared: beta[n..].to_vec(),
            cycles: ss.iter().map(|s| s.cycles).max().unwrap_or(1).max(1),
            samples: ss.len(),
            under: quantile(ratios, UNDER_QUANTILE).max(1.0),
        }
    }

    /// Predicted (map, camera, whole-screen) milliseconds of `method` (an
    /// `error_model::candidate` name) for an object of this workload; `None` for one the
    /// calibration did not measure.
    pub fn predict(&self, method: &str, w: &Workload) -> Option<(f64, f64, f64)> {
        let c = self.methods.get(method)?;
        Some((
            linear::dot(&c.fixed, &map_features(w)),
            linear::dot(&c.screen, &screen_features(w)),
            linear::dot(&c.shared, &shared_features(w)),
        ))
    }

    /// The frame's base (what belongs to no object) at this workload's screen and lights.
    pub fn base_ms(&self, w: &Workload) -> f64 {
        linear::dot(&self.base, &base_features(w))
    }

    pub fn parse(text: &str, what: &str) -> Result<CostModel> {
        let c: CostModel = serde_json::from_str(text).map_err(|e| Error::invalid(what.to_string(), format!("not a cost file: {e}")))?;
        if c.format != FORMAT {
            return Err(Error::invalid(format!("{what} format"), format!("'{}', expected '{FORMAT}'", crate::error::clip(&c.format))));
        }
        let ok = |v: &[f64], n: usize| v.len() == n && v.iter().all(|x| x.is_finite() && *x >= 0.0);
        for (m, mc) in &c.methods {
            crate::plan::Method::parse(super::error_model::candidate_method(m))
                .map_err(|e| Error::invalid(format!("{what} methods"), e.to_string()))?;
            if !ok(&mc.fixed, MAP_FEATURES.len())
                || !ok(&mc.screen, SCREEN_FEATURES.len())
                || !ok(&mc.shared, SHARED_FEATURES.len())
                || mc.cycles == 0
            {
                return Err(Error::invalid(
                    format!("{what} methods.{m}"),
                    "unit costs must be finite, non-negative and complete".to_string(),
                ));
            }
        }
        if !ok(&c.base, BASE_FEATURES.len()) {
            return Err(Error::invalid(
                format!("{what} base"),
                format!("{:?}: {} finite non-negative unit costs expected", c.base, BASE_FEATURES.len()),
            ));
        }
        Ok(c)
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}

/// Where cost files are cached: `SPECULA_CACHE_DIR`, else `$XDG_CACHE_HOME/specula`, else
/// `$HOME/.cache/specula`; `None` when none is set (nothing is cached then).
pub fn cache_dir() -> Option<PathBuf> {
    let var = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    var("SPECULA_CACHE_DIR")
        .or_else(|| var("XDG_CACHE_HOME").map(|d| d.join("specula")))
        .or_else(|| var("HOME").map(|h| h.join(".cache/specula")))
}

/// The cached unit costs of `key` in `dir`: `Ok(None)` when none are cached; an error naming
/// the file when it cannot be read or is not a cost file of that device.
pub fn load_cached(dir: &Path, key: &DeviceKey) -> Result<Option<CostModel>> {
    let path = dir.join(key.file_name());
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(&path, e)),
    };
    let c = CostModel::parse(&text, &path.display().to_string())?;
    if &c.key != key {
        return Err(Error::invalid(path.display().to_string(), format!("holds the costs of {}, not {}", c.key.label(), key.label())));
    }
    Ok(Some(c))
}

/// Writes `c` into `dir` (created) under its device's file name, atomically (a reader never
/// sees half a file).
pub fn store(dir: &Path, c: &CostModel) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let path = dir.join(c.key.file_name());
    let tmp = dir.join(format!(".{}.{}", c.key.file_name(), std::process::id()));
    std::fs::write(&tmp, c.to_json()).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, &path).map_err(|e| Error::io(&path, e))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Per way a line through its timings: exact on a line, through the origin where the
    /// intercept would be negative, none with timings at one triangle count only.
    #[test]
    fn bvh_update_costs_are_a_line_per_way() {
        use super::super::samples::BvhUpdateSample;
        let at = |way: &str, n: f64, ms: f64| BvhUpdateSample { way: way.into(), triangles: n, ms };
        let samples = vec![
            at("sah", 1e4, 9.0),
            at("sah", 1e5, 90.0),
            at("lbvh", 1e4, 22.0),
            at("lbvh", 1e5, 40.0),
            at("refit", 1e4, 0.0),
            at("refit", 1e5, 10.0),
        ];
        let c = BvhUpdateCosts::fit(&samples).unwrap();
        assert!((c.sah[0]).abs() < 1e-9 && (c.sah[1] - 900.0).abs() < 1e-6, "{c:?}");
        assert!((c.lbvh[0] - 20.0).abs() < 1e-9 && (c.lbvh[1] - 200.0).abs() < 1e-6, "{c:?}");
        assert!(c.refit[0] == 0.0 && c.refit[1] > 0.0, "a negative intercept goes through the origin: {c:?}");
        assert!((BvhUpdateCosts::predict(c.lbvh, 1e6) - 220.0).abs() < 1e-6);
        assert_eq!(BvhUpdateCosts::fit(&samples[..2]), None, "no lbvh or refit timings");
        assert_eq!(BvhUpdateCosts::fit(&[at("sah", 1e4, 1.0), at("lbvh", 1e4, 1.0), at("refit", 1e4, 1.0)]), None, "one count each");
    }

    fn key(device: u32) -> DeviceKey {
        DeviceKey { vendor: 0x10005, device, driver: 1, name: format!("fake {device}"), driver_info: "fake driver".into() }
    }

    fn model(device: u32) -> CostModel {
        CostModel {
            format: FORMAT.into(),
            key: key(device),
            methods: BTreeMap::new(),
            base: vec![1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            calibration_s: 1.0,
            bvh_updates: None,
        }
    }

    /// A `METHOD+hybrid` candidate costs at least its method: fitted over the method's unit
    /// costs, even where its own frames alone would fit cheaper ones.
    #[test]
    fn a_hybrid_candidate_is_fitted_over_its_method() {
        use super::super::samples::{Corpus, Sample};
        let sample = |knobs: &str, px: f64, ms: f64| Sample {
            scene: px as usize,
            object: "o".into(),
            method: "distance".into(),
            knobs: knobs.into(),
            features: vec![0.0; super::super::features::ERROR_FEATURES.len()],
            work: Workload { pixels: px, screen: 4.0 * px, cube_texels: 1e5, ..Workload::default() },
            psnr_db: 30.0,
            fixed_ms: 1.0,
            screen_ms: ms,
            shared_ms: 0.0,
            cycles: 1,
        };
        let mut c = Corpus::new(key(1));
        for px in [1e3, 4e3, 9e3] {
            c.samples.push(sample("default", px, px / 1e3));
            // The hybrid's frames measured cheaper than the plain method's (noise).
            c.samples.push(sample("hybrid=rays", px, 0.8 * px / 1e3));
        }
        let m = CostModel::fit(&c, key(1), 0.0);
        let w = Workload { pixels: 5e3, screen: 2e4, cube_texels: 1e5, ..Workload::default() };
        let (plain, hybrid) = (m.predict("distance", &w).unwrap(), m.predict("distance+hybrid", &w).unwrap());
        assert!(plain.1 > 0.0 && hybrid.0 >= plain.0 && hybrid.1 + hybrid.2 >= plain.1 + plain.2, "{plain:?} {hybrid:?}");
        // Frames the linear model fits exactly: no margin.
        assert!((m.methods["distance"].under - 1.0).abs() < 1e-6, "{}", m.methods["distance"].under);
        // Four frames of ten measured 2× the trend: the four shortest, under a third of the
        // measured time, do not set the margin (frames are weighted by their time, and it is
        // their median); the four longest, three quarters of it, do.
        let margin = |slow: &[usize]| {
            let mut c = Corpus::new(key(1));
            for k in 1..=10 {
                let px = 1e3 * k as f64;
                c.samples.push(sample("default", px, if slow.contains(&k) { 2.0 } else { 1.0 } * px / 1e3));
            }
            CostModel::fit(&c, key(1), 0.0).methods["distance"].under
        };
        let (one, two) = (margin(&[1, 2, 3, 4]), margin(&[7, 8, 9, 10]));
        assert!(one < 1.2 && two > 1.3, "margins {one} and {two}");
    }

    /// Two device keys side by side in one cache; a corrupt or truncated file is an error
    /// naming it (the caller re-calibrates), never a panic; a file of another device is
    /// refused.
    #[test]
    fn cache_holds_devices_apart_and_refuses_corrupt_files() {
        let dir = std::env::temp_dir().join(format!("specula-costs-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(load_cached(&dir, &key(1)).unwrap(), None);
        store(&dir, &model(1)).unwrap();
        store(&dir, &model(2)).unwrap();
        assert_eq!(load_cached(&dir, &key(1)).unwrap(), Some(model(1)));
        assert_eq!(load_cached(&dir, &key(2)).unwrap(), Some(model(2)));
        let path = dir.join(key(1).file_name());
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, &text[..text.len() / 2]).unwrap();
        let e = load_cached(&dir, &key(1)).unwrap_err().to_string();
        assert!(e.contains(&key(1).file_name()) && e.contains("not a cost file"), "{e}");
        std::fs::write(&path, text.replace("\"fake 1\"", "\"fake 3\"")).unwrap();
        let e = load_cached(&dir, &key(1)).unwrap_err().to_string();
        assert!(e.contains("not fake 1"), "{e}");
        std::fs::write(&path, text.replace("0.5", "-0.5")).unwrap();
        assert!(load_cached(&dir, &key(1)).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// What a plan is predicted for: the frame's size and the device's unit costs.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    pub size: (u32, u32),
    pub costs: std::sync::Arc<CostModel>,
}
