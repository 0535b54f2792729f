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
//!
//! On every specular object the same pixels also measure the cube-map methods' lookups
//! ([`LOOKUP_METHODS`]), and on a solid dielectric its self refraction ([`REFRACTOR_METHOD`]):
//! the other part the features describe coarsely (proxy-box on a mirror ball in a room's
//! corner: 22.1 dB predicted by the model, 39.1 measured; refractor-map on a glass ball:
//! 24.2 predicted, 38.1 measured). Each map is simulated as the GPU renders it — an
//! environment map's texel holds what its centre's direction shows from the reference
//! point with the object left out, a refractor map's the object's own nearest surface —
//! filtered bilinearly, the proxies intersected as `proxy.frag` does, the maps searched by
//! `search.rs`, the CPU twin of the GLSL search, and the refracted ray followed through the
//! solid as `glsl/distance/refractor/trace.glsl` does. Without anti-aliasing a method's
//! prediction is its simulated pixel centres against the converged pixels, measured rather
//! than summed from the maps' error and the aliasing, which are correlated (on the glass ball
//! the simulated refractor-map measures 38.4 dB, the GPU's image 38.1, the sum 36.6); with
//! anti-aliasing, the maps' error (against the exact centres) plus the aliasing `aa` leaves.

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
/// Pixels traced per object (evenly spread over its lattice pixels) where the frame shows at
/// most [`PIXELS_PER_FRAME`] / [`PIXELS`] specular objects.
pub const PIXELS: usize = 256;
/// Pixels traced over all objects: with more objects each gets its share, at least
/// [`MIN_PIXELS`], so that the probe's time grows with the objects only past 32 of them (20
/// spheres, mirrors and glass, at 512²: 1.09 s in a release build on 2 cores).
pub const PIXELS_PER_FRAME: usize = 1024;
pub const MIN_PIXELS: usize = 32;
/// Pixels of an object the probe's pilot looks at (four samples each) to draw its pixels
/// from.
pub const PILOT: usize = 1024;
/// Samples per pixel of the image errors are measured against: the converged pixel, as 16
/// stratified samples estimate it (as `specula tradeoff`'s reference and the corpus's 4×4
/// supersampling do), whatever `spp` the caller's own reference renders take.
const REFERENCE_SPP: u32 = 16;
/// Vulkan's standard sample locations for 4 samples.
const MSAA4: [(f64, f64); 4] = [(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)];
/// The 2×2 supersampling grid, resolved by averaging.
const SSAA2: [(f64, f64); 4] = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)];

/// The environment-map methods whose error the probe measures: each answers a reflected (and
/// a once-refracted) ray by one lookup of a cube map around the object's reference point.
pub const LOOKUP_METHODS: [&str; 5] = ["envmap", "proxy-sphere", "proxy-box", "distance", "distance-multi"];
/// Self refraction in a solid's own refractor map, simulated on solid dielectrics.
pub const REFRACTOR_METHOD: &str = "refractor-map";

/// What the probe measures on an object (mean squared errors per channel, linear radiance,
/// as PSNR measures them, against the reference, over `pixels` traced pixels): the exact
/// tracer's without anti-aliasing and under the variants the planner chooses among, and on
/// a mirror the error of each cube-map lookup ([`LOOKUP_METHODS`]) at each cube size.
#[derive(Clone, Debug, PartialEq)]
pub struct Aliasing {
    pub pixels: usize,
    pub off: f64,
    pub msaa4: f64,
    pub ssaa2: f64,
    /// Per simulated method and cube size, its error.
    pub lookups: Vec<Lookup>,
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

    /// The simulated error of `method` with cube maps of `cube_size`, where measured.
    pub fn lookup(&self, method: &str, cube_size: u32) -> Option<&Lookup> {
        self.lookups.iter().find(|l| l.method == method && l.cube_size == cube_size)
    }
}

/// A method's simulated error on an object's traced pixels (mean squared errors per channel).
#[derive(Clone, Debug, PartialEq)]
pub struct Lookup {
    pub method: &'static str,
    pub cube_size: u32,
    /// Shading each pixel at its centre, against the converged pixel: the method's error
    /// without anti-aliasing. The maps' error and the aliasing are correlated (a lookup's
    /// blur partly offsets the centre's aliasing), so this is measured, not summed.
    pub off: f64,
    /// Against the exact tracer at the pixel centres: the maps' error alone.
    pub maps: f64,
    /// Shaded at the four multisample positions (per sample) and on the 2×2 grid, averaged,
    /// against the converged pixel: measured at the quality's cube size (the variants that
    /// vary `aa` keep it), `None` at the others.
    pub msaa4: Option<f64>,
    pub ssaa2: Option<f64>,
}

impl Lookup {
    /// The method's error under `aa` (`per_sample`: multisamples shaded per sample), where
    /// the exact tracer's under it is `aliasing` (`None`: not traced): as measured, else the
    /// maps' error on top of that aliasing, at most the error without.
    pub fn under(&self, aa: &str, per_sample: bool, aliasing: Option<f64>) -> f64 {
        let measured = match aa {
            "off" => Some(self.off),
            "msaa4" if per_sample => self.msaa4,
            "ssaa2" => self.ssaa2,
            _ => None,
        };
        measured.unwrap_or_else(|| aliasing.map_or(self.off, |a| (self.maps + a).min(self.off)))
    }
}

/// What to measure besides aliasing: per specular mesh whose maps the probe simulates its
/// reference point (the maps' centre), and the cube sizes the lookups run at (the search's,
/// proxies' and internal bounces' knobs are the quality's).
pub struct Lookups<'a> {
    pub objects: &'a [(usize, glam::Vec3)],
    pub cube_sizes: &'a [u32],
}

/// Per mesh of `scene` (indexed as `scene.meshes`), what the probe measures on its pixels at
/// `size` with `quality`'s bounces, Fresnel and search knobs; `None` for meshes that are not
/// specular or that no lattice pixel shows, and for every mesh when the reference cannot
/// trace the scene.
///
/// The same inputs measure the same values (the pixels are placed by a hash, the sums run in
/// a fixed order), so the last [`REMEMBERED`] measurements are kept, keyed by a fingerprint
/// of everything they read ([`Scene::fingerprint`], the quality, the size and the lookups):
/// configuring `auto` again on an unchanged scene (an engine's re-configure, the planner's
/// budgets, the C ABI's misuse checks) costs the fingerprint (one pass over the scene's
/// arrays), not the tracing (84 % of tests/per_object.rs's prediction test under perf).
pub fn measure(scene: &Scene, quality: &Quality, size: (u32, u32), lookups: &Lookups) -> Vec<Option<Aliasing>> {
    static KEPT: crate::scene::Kept<Vec<Option<Aliasing>>, REMEMBERED> = crate::scene::Kept::new();
    let key = {
        let mut h = crate::scene::Fingerprint::new();
        scene.fingerprint(&mut h);
        h.text(&format!("{quality:?} {size:?} {:?} {:?}", lookups.objects, lookups.cube_sizes));
        h.finish()
    };
    KEPT.get(key, || measure_once(scene, quality, size, lookups)).as_ref().clone()
}

/// Measurements [`measure`] keeps (the most recently used).
pub const REMEMBERED: usize = 16;

fn measure_once(scene: &Scene, quality: &Quality, size: (u32, u32), lookups: &Lookups) -> Vec<Option<Aliasing>> {
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
    let spp = REFERENCE_SPP;
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
    let shown_objects = by_mesh.iter().filter(|p| !p.is_empty()).count().max(1);
    let per_object = (PIXELS_PER_FRAME / shown_objects).clamp(MIN_PIXELS, PIXELS);
    let env = Environment { scene, quality, tracer: &tracer, cube_sizes: lookups.cube_sizes };
    let aa_size: Vec<u32> = lookups.cube_sizes.iter().copied().filter(|&n| n == quality.cube.cube_size).collect();
    by_mesh
        .into_iter()
        .enumerate()
        .map(|(mesh, pixels)| {
            if pixels.is_empty() {
                return None;
            }
            let sq = |a: DVec3, b: DVec3| (a - b).length_squared() / 3.0;
            // Pixels drawn with probability proportional to how much their 2×2 grid samples
            // vary (plus a floor), each weighing the inverse: an aliasing error is
            // heavy-tailed (a few edge pixels carry most of it), and an even sample of it
            // misses the tail (8 unseen scenes at 512²: `aa` variants predicted 2–8 dB too
            // high). The pilot looks at up to PILOT pixels spread evenly over the object's.
            let pilot: Vec<(u32, u32)> = {
                let m = pixels.len().min(PILOT);
                (0..m).map(|k| pixels[k * pixels.len() / m]).collect()
            };
            let spread: Vec<f64> = pilot
                .par_iter()
                .map(|&(x, y)| {
                    let v: Vec<DVec3> = SSAA2.iter().map(|&s| at(x, y, s)).collect();
                    let m = v.iter().sum::<DVec3>() / v.len() as f64;
                    let e = v.iter().map(|&c| sq(c, m)).sum::<f64>() / v.len() as f64;
                    if e.is_finite() {
                        e
                    } else {
                        0.0
                    }
                })
                .collect();
            let (chosen, weights) = importance_sample(&pilot, &spread, per_object);
            let centre = lookups.objects.iter().find(|(m, _)| *m == mesh).map(|(_, c)| c.as_dvec3());
            let per_pixel: Vec<(f64, Vec<f64>)> = chosen
                .par_iter()
                .zip(&weights)
                .map(|(&(x, y), &weight)| {
                    let reference: Vec<(f64, f64)> = (0..spp).map(|s| sample_offset(x, y, s, spp)).collect();
                    let r = mean(x, y, &reference);
                    let exact = at(x, y, (0.5, 0.5));
                    // The exact tracer at the anti-aliasing samples, traced once for its own
                    // error and for the maps' simulation there.
                    let (m4_exact, s2_exact): (Vec<DVec3>, Vec<DVec3>) =
                        (MSAA4.iter().map(|&o| at(x, y, o)).collect(), SSAA2.iter().map(|&o| at(x, y, o)).collect());
                    let avg = |v: &[DVec3]| v.iter().sum::<DVec3>() / v.len() as f64;
                    let mut e = vec![sq(exact, r), sq(avg(&m4_exact), r), sq(avg(&s2_exact), r)];
                    if let Some(c) = centre {
                        let shades = env.shades(mesh as u32, c, rays.ray(x as f64 + 0.5, y as f64 + 0.5), exact, env.cube_sizes);
                        e.extend(shades.into_iter().flat_map(|v| [sq(v, r), sq(v, exact)]));
                        // The maps sampled as anti-aliasing samples them, at the asked cube size
                        // (the variants that vary `aa` keep it).
                        let sampled = |offsets: &[(f64, f64)], exact: &[DVec3]| {
                            let mut sum = vec![DVec3::ZERO; env.keys(mesh, &aa_size).len()];
                            for (&(dx, dy), &ex) in offsets.iter().zip(exact) {
                                let ray = rays.ray(x as f64 + dx, y as f64 + dy);
                                for (s, v) in sum.iter_mut().zip(env.shades(mesh as u32, c, ray, ex, &aa_size)) {
                                    *s += v / offsets.len() as f64;
                                }
                            }
                            sum
                        };
                        let (m4, s2) = (sampled(&MSAA4, &m4_exact), sampled(&SSAA2, &s2_exact));
                        e.extend(m4.into_iter().zip(s2).flat_map(|(a, b)| [sq(a, r), sq(b, r)]));
                    }
                    (weight, e)
                })
                .filter(|(_, e)| e.iter().all(|v| v.is_finite()))
                .collect();
            let k = per_pixel.len();
            let total: f64 = per_pixel.iter().map(|(w, _)| w).sum();
            if k == 0 || total.is_nan() || total <= 0.0 {
                return None;
            }
            let sum = |i: usize| per_pixel.iter().map(|(w, e)| w * e[i]).sum::<f64>() / total;
            let lookups = match centre {
                Some(_) => {
                    let keys = env.keys(mesh, env.cube_sizes);
                    let sampled = env.keys(mesh, &aa_size);
                    let at_aa = |method: &str, cube_size: u32, k: usize| {
                        let i = sampled.iter().position(|&(m, n)| m == method && n == cube_size)?;
                        Some(sum(3 + 2 * keys.len() + 2 * i + k))
                    };
                    keys.iter()
                        .enumerate()
                        .map(|(i, &(method, cube_size))| Lookup {
                            method,
                            cube_size,
                            off: sum(3 + 2 * i),
                            maps: sum(4 + 2 * i),
                            msaa4: at_aa(method, cube_size, 0),
                            ssaa2: at_aa(method, cube_size, 1),
                        })
                        .collect()
                }
                None => Vec::new(),
            };
            Some(Aliasing { pixels: k, off: sum(0), msaa4: sum(1), ssaa2: sum(2), lookups })
        })
        .collect()
}

/// `n` of `pixels` drawn with probability proportional to `spread` (each pixel's) plus a
/// floor of the mean spread (half the draw even: the lookups' errors lie where the grid
/// samples agree too; with a tenth of it proxy-box's held-out median rose 0.35 → 0.87 dB),
/// by systematic sampling over the cumulative weights (deterministic, each pixel at most
/// once; a pattern periodic in the pixels' order can alias with it), and each drawn pixel's
/// weight, the inverse of its probability: weighted means of the drawn pixels estimate the
/// mean over `pixels`. All of them, weighing alike, where `n` covers them.
fn importance_sample(pixels: &[(u32, u32)], spread: &[f64], n: usize) -> (Vec<(u32, u32)>, Vec<f64>) {
    if pixels.len() <= n {
        return (pixels.to_vec(), vec![1.0; pixels.len()]);
    }
    let mean = spread.iter().sum::<f64>() / spread.len().max(1) as f64;
    let floor = if mean > 0.0 { mean } else { 1.0 };
    let p: Vec<f64> = spread.iter().map(|&v| v.max(0.0) + floor).collect();
    let sum: f64 = p.iter().sum();
    // Probabilities of inclusion n·p/Σp, capped at 1: a pixel at the cap is taken for sure
    // and the rest share what is left.
    let mut inclusion: Vec<f64> = p.iter().map(|&v| n as f64 * v / sum).collect();
    for _ in 0..8 {
        let capped: f64 = inclusion.iter().filter(|&&v| v >= 1.0).count() as f64;
        let rest: f64 = p.iter().zip(&inclusion).filter(|(_, &v)| v < 1.0).map(|(&w, _)| w).sum();
        if rest <= 0.0 {
            break;
        }
        let share = (n as f64 - capped).max(0.0) / rest;
        let next: Vec<f64> = p.iter().zip(&inclusion).map(|(&w, &v)| if v >= 1.0 { 1.0 } else { (w * share).min(1.0) }).collect();
        if next == inclusion {
            break;
        }
        inclusion = next;
    }
    let (mut chosen, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut acc = 0.0;
    let mut next = 0.5;
    for (i, &v) in inclusion.iter().enumerate() {
        acc += v;
        if acc > next {
            chosen.push(pixels[i]);
            weights.push(1.0 / v);
            while next < acc {
                next += 1.0;
            }
        }
    }
    (chosen, weights)
}

/// The cube-map lookups of [`LOOKUP_METHODS`] and [`REFRACTOR_METHOD`]'s searches,
/// simulated with the reference: an environment map's texel holds what its centre's
/// direction shows from the reference point with the object left out, a refractor map's
/// the object's own nearest surface (distance and normal) with everything else left out (as
/// the GPU's maps are rendered), bilinearly filtered as the shaders sample them, and rays
/// searched in them by `search.rs`, the CPU twin of the GLSL search.
struct Environment<'a> {
    scene: &'a Scene,
    quality: &'a Quality,
    tracer: &'a Tracer<'a>,
    cube_sizes: &'a [u32],
}

impl Environment<'_> {
    /// (method, cube size) for each of `sizes`, in the order [`Environment::shades`] returns
    /// them for `mesh`: every lookup method on a mirror or a dielectric that neither disperses nor
    /// absorbs (the shaders' single-refraction lookups weight absorption by a bounding
    /// chord, which the probe does not model), and self refraction on a solid that does
    /// not disperse; none on other objects.
    fn keys(&self, mesh: usize, sizes: &[u32]) -> Vec<(&'static str, u32)> {
        let m = &self.scene.materials[self.scene.meshes[mesh].material];
        let lookups = match m.kind {
            crate::scene::SurfaceKind::Mirror { .. } => true,
            crate::scene::SurfaceKind::Dielectric { .. } => !m.disperses() && !m.absorbs(),
            crate::scene::SurfaceKind::Diffuse => return Vec::new(),
        };
        let solid = matches!(m.kind, crate::scene::SurfaceKind::Dielectric { thin: false, .. }) && !m.disperses();
        let methods = LOOKUP_METHODS.iter().filter(|_| lookups).chain(std::iter::once(&REFRACTOR_METHOD).filter(|_| solid));
        methods.flat_map(|&m| sizes.iter().map(move |&n| (m, n))).collect()
    }

    /// A ray of direction `r` from `x`, searched in the distance map of reference point `c`
    /// (x relative to it) with the quality's search knobs, as `search_ray` of
    /// glsl/common/traced.glsl: linear search, or parallax correction with no linear steps.
    fn search(&self, map: &impl crate::search::DistanceMap, x: DVec3, r: DVec3) -> crate::search::SearchResult {
        let s = &self.quality.search;
        if s.linear_steps == 0 {
            return crate::search::parallax_search(map, x, r, s.parallax_iterations.max(1));
        }
        crate::search::linear_search(map, x, r, s.linear_steps, s.binary_steps, s.secant_steps, s.search_tolerance as f64)
    }

    /// Per key of [`Environment::keys`] at `sizes`, what the method shades where the ray
    /// o + t d meets `mesh` (whose maps are centred on `c`); `exact` (the exact tracer's
    /// radiance at the pixel centre) where it meets something else (the silhouette's pixels,
    /// whose error the aliasing part holds) or the simulation is not finite.
    fn shades(&self, mesh: u32, c: DVec3, (o, d, t): (DVec3, DVec3, f64), exact: DVec3, sizes: &[u32]) -> Vec<DVec3> {
        let keys = self.keys(mesh as usize, sizes);
        let Some(hit) = self.tracer.specular_hit(o, d, t).filter(|h| h.mesh == mesh) else { return vec![exact; keys.len()] };
        let x = hit.position;
        let bounds = self.scene.bounds();
        let radius = crate::plan::proxy_radius(self.scene, self.quality) as f64;
        let map = |dir: DVec3| {
            let len = dir.length();
            if len <= 0.0 {
                return 0.0;
            }
            self.tracer.distance_without(c, dir / len, mesh).unwrap_or(2.0 * crate::search::SEARCH_SKY)
        };
        // Where each method looks a ray of direction r leaving x up in the map.
        let towards = |m: &str, x: DVec3, r: DVec3| -> DVec3 {
            match m {
                "envmap" => r,
                "proxy-sphere" => sphere_exit(x - c, r, radius),
                "proxy-box" => box_exit(bounds.min.as_dvec3(), bounds.max.as_dvec3(), x, r).map_or(r, |p| p - c),
                _ => self.search(&map, x - c, r).dir,
            }
        };
        let s = hit.split;
        keys.iter()
            .map(|&(m, n)| {
                let seen = |m: &str, x: DVec3, r: DVec3| bilinear(towards(m, x, r), n, &|dir| self.tracer.seen_without(c, dir, mesh));
                let shaded = if m == REFRACTOR_METHOD {
                    s.fr * seen("distance", x, s.r) + self.refracted_inside(mesh, c, &hit, n, &|x, r| seen("distance", x, r))
                } else {
                    let refracted = if s.ft.max_element() > 0.0 { s.ft * seen(m, x, s.t) } else { DVec3::ZERO };
                    s.fr * seen(m, x, s.r) + refracted
                };
                if shaded.is_finite() {
                    shaded
                } else {
                    exact
                }
            })
            .collect()
    }

    /// `refractor_inside` of glsl/distance/refractor/trace.glsl: the refracted ray of `hit`
    /// searched in the refractor map (size `n`) of `mesh` centred on `c` to the surface it
    /// meets, refracted out there (Fresnel) or reflected on inside up to `internal_bounces`
    /// times, each ray that leaves looked up by `env(point, direction)`.
    fn refracted_inside(
        &self,
        mesh: u32,
        c: DVec3,
        hit: &crate::reference::SpecularHit,
        n: u32,
        env: &dyn Fn(DVec3, DVec3) -> DVec3,
    ) -> DVec3 {
        let m = &self.scene.materials[hit.material];
        let own = |dir: DVec3| {
            let len = dir.length();
            if len <= 0.0 {
                return 0.0;
            }
            self.tracer.surface_of(c, dir / len, mesh).map_or(2.0 * crate::search::SEARCH_SKY, |(t, _)| t)
        };
        let normal = |dir: DVec3| self.tracer.surface_of(c, dir, mesh).map_or(DVec3::ZERO, |(_, n)| n);
        let (mut pos, mut dir, mut weight) = (hit.position, hit.split.t, hit.split.ft);
        let mut c_out = DVec3::ZERO;
        for _ in 0..=self.quality.distance.internal_bounces {
            if weight.max_element() <= 1e-4 {
                break;
            }
            // Started just inside, so that the surface it leaves is not the one it meets.
            let eps = 1e-2 * (pos - c).length();
            let h = self.search(&own, pos + dir * eps - c, dir);
            if h.escaped {
                return c_out + weight * env(pos, dir);
            }
            let exit = pos + dir * (eps + h.d);
            let mut n2 = bilinear(h.dir, n, &normal).normalize_or_zero();
            if n2.dot(dir) < 0.0 {
                n2 = -n2;
            }
            weight *= crate::reference::shade::segment_transmittance(m, n2, dir, (exit - pos).length());
            let s = self.tracer.split(m, dir, n2);
            if s.ft.max_element() > 0.0 {
                c_out += weight * s.ft * env(exit, s.t);
            }
            weight *= s.fr;
            (pos, dir) = (exit, s.r);
        }
        c_out
    }
}

/// proxy.frag's sphere: the direction from the centre to where x + t r leaves the sphere of
/// `radius` around it (x relative to the centre); r itself where it misses.
fn sphere_exit(x: DVec3, r: DVec3, radius: f64) -> DVec3 {
    let b = x.dot(r);
    let disc = b * b - (x.length_squared() - radius * radius);
    if disc < 0.0 {
        return r;
    }
    let t = -b + disc.sqrt();
    if t > 0.0 {
        x + r * t
    } else {
        r
    }
}

/// proxy.frag's box: where x + t r leaves the box (`None` where it does not, ahead).
fn box_exit(min: DVec3, max: DVec3, x: DVec3, r: DVec3) -> Option<DVec3> {
    let inv = r.recip();
    let (t0, t1) = ((min - x) * inv, (max - x) * inv);
    let t = t0.max(t1).min_element();
    (t > 0.0).then(|| x + r * t)
}

/// A cube map of `n`² texels a face, sampled bilinearly in direction `dir` (within its
/// face, clamped at the face's edge): `texel(d)` is what the texel whose centre lies in
/// direction d holds.
fn bilinear(dir: DVec3, n: u32, texel: &dyn Fn(DVec3) -> DVec3) -> DVec3 {
    let a = dir.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let major = dir[axis];
    if major == 0.0 || !major.is_finite() {
        return texel(dir);
    }
    let n = n.max(1) as f64;
    let coord = |k: usize| ((dir[k] / major.abs() + 1.0) * 0.5 * n - 0.5).clamp(0.0, n - 1.0);
    let (su, sv) = (coord(u), coord(v));
    let (iu, iv) = (su.floor(), sv.floor());
    let (fu, fv) = (su - iu, sv - iv);
    let centre = |i: f64, j: f64| {
        let mut d = DVec3::ZERO;
        d[axis] = major.signum();
        d[u] = ((i + 0.5) / n) * 2.0 - 1.0;
        d[v] = ((j + 0.5) / n) * 2.0 - 1.0;
        texel(d.normalize())
    };
    let (i1, j1) = ((iu + 1.0).min(n - 1.0), (iv + 1.0).min(n - 1.0));
    let weights = [((1.0 - fu) * (1.0 - fv), iu, iv), (fu * (1.0 - fv), i1, iv), ((1.0 - fu) * fv, iu, j1), (fu * fv, i1, j1)];
    weights.iter().filter(|(w, _, _)| *w > 0.0).map(|&(w, i, j)| centre(i, j) * w).sum()
}

/// Each specular object's mesh and reference point, from the planner's facts.
pub fn references(facts: &crate::plan::facts::SceneFacts) -> Vec<(usize, glam::Vec3)> {
    facts.objects.iter().map(|o| (o.mesh, o.reference_point)).collect()
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
        let objects = references(&crate::plan::facts::SceneFacts::new(&s, &q, false));
        let lookups = Lookups { objects: &objects, cube_sizes: &[128, 256, 512] };
        for (m, a) in measure(&s, &q, (side, side), &lookups).into_iter().enumerate() {
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
        assert!(measure(&room, &Quality::default(), (32, 32), &Lookups { objects: &[], cube_sizes: &[] }).iter().all(Option::is_none));
        let s = crate::scenes::corpus::scene(0).unwrap();
        let ball = s.specular_meshes().next().unwrap().0;
        let q = Quality::default();
        let none = Lookups { objects: &[], cube_sizes: &[] };
        let small = measure(&s, &q, (48, 48), &none)[ball].clone().expect("the ball is in view");
        let large = measure(&s, &q, (192, 192), &none)[ball].clone().unwrap();
        assert!(small.pixels >= 64 && large.pixels == PIXELS, "{small:?} {large:?}");
        assert!(small.off > 0.0 && small.msaa4 < small.off && small.ssaa2 < small.off, "{small:?}");
        assert!(large.off < small.off, "{small:?} {large:?}");
        assert_eq!(measure(&s, &q, (48, 48), &none)[ball], Some(small.clone()));
        assert_eq!(small.mse("msaa4", false), None, "multisamples shaded once per pixel are not traced");
        assert!(small.lookups.is_empty(), "no lookups asked for");
    }

    /// A mirror ball at the centre of a box room, its maps centred on it: the box proxy is
    /// the room itself and the distance map holds it, so both look up what the reflected
    /// rays see, up to the texels' filtering (less with larger maps); a lookup at infinity
    /// (envmap) and a sphere proxy miss the parallax.
    #[test]
    fn lookups_in_a_box_room_rank_as_its_geometry_says() {
        let mut s = Scene::new();
        crate::scenes::checker_room(&mut s, Vec3::ZERO, 2.0).unwrap();
        let m = s
            .add_material(crate::scene::Material {
                name: "m".into(),
                kind: crate::scene::SurfaceKind::Mirror { nu: Vec3::splat(3.0), kappa: Vec3::ZERO },
                ..Default::default()
            })
            .unwrap();
        let ball = s.add_mesh(crate::scene::shapes::uv_sphere("ball", Vec3::ZERO, 0.5, 32, 16, m)).unwrap();
        s.camera = Some(crate::scene::Camera::look_at(Vec3::new(0.3, 0.4, 1.8), Vec3::ZERO, 0.9));
        let lookups = Lookups { objects: &[(ball, Vec3::ZERO)], cube_sizes: &[64, 256] };
        let a = measure(&s, &Quality::default(), (64, 64), &lookups)[ball].clone().expect("the ball is in view");
        let at = |m: &str, n: u32| a.lookup(m, n).unwrap().maps;
        for n in [64, 256] {
            assert!(at("proxy-box", n) < 0.2 * at("envmap", n) && at("distance", n) < 0.2 * at("envmap", n), "{:?}", a.lookups);
            assert!(at("proxy-sphere", n) > at("proxy-box", n), "{:?}", a.lookups);
        }
        assert!(at("proxy-box", 256) < at("proxy-box", 64), "finer texels: {:?}", a.lookups);
        // The maps sampled as anti-aliasing samples them, at the asked cube size only (256,
        // the default): supersampling averages their error down.
        let l = a.lookup("proxy-box", 256).unwrap();
        assert!(l.ssaa2.is_some_and(|e| e < l.off) && l.msaa4.is_some(), "{l:?}");
        assert_eq!((a.lookup("proxy-box", 64).unwrap().ssaa2, a.lookup("proxy-box", 64).unwrap().msaa4), (None, None));
    }

    /// The pixels drawn by importance estimate a heavy-tailed mean better than as many drawn
    /// evenly: 1000 pixels, about one in 50 (placed by a hash) carrying 100× the others'
    /// error, 40 drawn; the mean relative error over 20 placements.
    #[test]
    fn importance_sampling_finds_the_tail() {
        let pixels: Vec<(u32, u32)> = (0..1000).map(|i| (i, 0)).collect();
        let (mut importance, mut even) = (0.0, 0.0);
        for seed in 0..20 {
            let error = |&(i, _): &(u32, u32)| if crate::reference::hash(i, seed, 7) % 50 == 7 { 100.0 } else { 1.0 };
            let truth = pixels.iter().map(error).sum::<f64>() / 1000.0;
            let spread: Vec<f64> = pixels.iter().map(error).collect();
            let (chosen, weights) = importance_sample(&pixels, &spread, 40);
            assert_eq!(chosen.len(), 40);
            let weighted = chosen.iter().zip(&weights).map(|(p, w)| w * error(p)).sum::<f64>() / weights.iter().sum::<f64>();
            let drawn = (0..40).map(|k| error(&pixels[k * 1000 / 40])).sum::<f64>() / 40.0;
            importance += (weighted - truth).abs() / truth / 20.0;
            even += (drawn - truth).abs() / truth / 20.0;
        }
        assert!(importance < 0.5 * even && importance < 0.2, "importance {importance:.3}, even {even:.3} (mean relative errors)");
        // Where the draw covers every pixel, all of them weigh alike.
        let (all, w) = importance_sample(&pixels[..10], &[1.0; 10], 40);
        assert_eq!((all.len(), w), (10, vec![1.0; 10]));
    }

    /// A solid glass ball at the centre of a box room, its maps centred on it: searching the
    /// refracted ray to the far side in the ball's own refractor map and refracting it out
    /// there (refractor-map) shades what the exact tracer does up to the texels' filtering;
    /// the single-refraction lookups (envmap, distance) look the once-refracted ray up as if
    /// it never left the glass, and miss by far more; a dispersive ball is not simulated.
    #[test]
    fn self_refraction_is_searched_to_the_far_side() {
        let mut s = Scene::new();
        crate::scenes::checker_room(&mut s, Vec3::ZERO, 2.0).unwrap();
        let glass = |s: &mut Scene, dispersion: f32| {
            s.add_material(crate::scene::Material {
                name: format!("glass{dispersion}"),
                kind: crate::scene::SurfaceKind::Dielectric { ior: 1.5, thin: false },
                dispersion,
                ..Default::default()
            })
            .unwrap()
        };
        let m = glass(&mut s, 0.0);
        let ball = s.add_mesh(crate::scene::shapes::uv_sphere("ball", Vec3::ZERO, 0.6, 48, 24, m)).unwrap();
        s.camera = Some(crate::scene::Camera::look_at(Vec3::new(0.2, 0.3, 1.9), Vec3::ZERO, 0.8));
        let lookups = Lookups { objects: &[(ball, Vec3::ZERO)], cube_sizes: &[64, 512] };
        let a = measure(&s, &Quality::default(), (48, 48), &lookups)[ball].clone().expect("the ball is in view");
        let at = |m: &str, n: u32| a.lookup(m, n).unwrap().maps;
        assert!(
            at("refractor-map", 512) < 0.05 * at("envmap", 512) && at("refractor-map", 512) < 0.05 * at("distance", 512),
            "{:?}",
            a.lookups
        );
        assert!(at("refractor-map", 512) < at("refractor-map", 64), "finer texels: {:?}", a.lookups);
        s.materials[m].dispersion = 20.0;
        let a = measure(&s, &Quality::default(), (48, 48), &lookups)[ball].clone().unwrap();
        assert!(a.lookups.is_empty(), "{:?}", a.lookups);
    }

    #[test]
    fn proxies_and_filtering_follow_the_shaders() {
        // From the centre of a unit sphere every ray leaves at distance 1 along itself.
        let r = DVec3::new(0.0, 0.6, 0.8);
        assert!((sphere_exit(DVec3::ZERO, r, 1.0) - r).length() < 1e-12);
        // A point outside a sphere it misses keeps the direction alone.
        assert_eq!(sphere_exit(DVec3::new(5.0, 0.0, 0.0), DVec3::Y, 1.0), DVec3::Y);
        let exit = box_exit(DVec3::splat(-1.0), DVec3::splat(1.0), DVec3::ZERO, DVec3::X).unwrap();
        assert!((exit - DVec3::X).length() < 1e-12);
        assert_eq!(box_exit(DVec3::splat(-1.0), DVec3::splat(1.0), DVec3::splat(3.0), DVec3::X), None);
        // Bilinear filtering reproduces what every texel holds alike, and weights 4 texels.
        let c = bilinear(DVec3::new(0.3, 1.0, -0.2), 16, &|_| DVec3::splat(2.0));
        assert!((c - DVec3::splat(2.0)).length() < 1e-12);
        let x = bilinear(DVec3::new(1.0, 0.01, 0.02), 8, &|d| d);
        assert!(x.x > 0.95 && x.y.abs() < 0.2 && x.z.abs() < 0.2, "{x:?}");
    }
}
