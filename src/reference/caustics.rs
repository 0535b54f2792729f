//! Caustics of the exact CPU reference (survey §6): the light paths L S+ D, which the
//! Whitted recursion of the camera rays cannot find, by light tracing (photon mapping).
//!
//! - **Emission.** For every punctual light and every *caustic generator* (a visible mesh
//!   of a specular material: mirror or dielectric, thin or solid), `Quality::reference_photons`
//!   photons are sent only towards the generator's bounding sphere (centre and half
//!   diagonal of its bounding box). Point and spot lights: directions uniform in the cone
//!   of half-angle asin(r/d) around the axis light → centre (the whole sphere of directions
//!   when the light lies inside), power I(ω)·Ω/N, where I(ω) is the intensity times the spot
//!   ramp and the glTF range window at the photon's first hit (`ShadeLight::incident`).
//!   Directional lights: origins uniform on the disk of radius r across the light's
//!   direction, upstream of the scene, power E·πr²/N. The samples are the first N points of
//!   the R2 sequence (Roberts' 2-D Kronecker sequence), so the result is deterministic and
//!   converges faster than random sampling.
//! - **No double counting.** A photon sent towards generator A counts only if its first
//!   hit is a triangle of A; a first hit elsewhere is direct light, which `shade_diffuse`
//!   already has (or another generator's photon).
//! - **Tracing.** At every specular hit the camera tracer's Fresnel split
//!   (`shade::specular_split`) is sampled: the reflected branch with probability
//!   p = mean(fr)/(mean(fr) + mean(ft)) by a per-photon hash, the power multiplied by f/p of
//!   the chosen branch (unbiased; under TIR fr = 1). At most `Quality::depth` specular
//!   bounces; rays start `epsilon` off the surface and skip the triangle they leave. The
//!   first diffuse hit stores the photon (position, the receiver's normal on the side the
//!   photon came from, power); escaping photons are dropped. Photons are traced in parallel
//!   (rayon) and collected in order.
//! - **Density estimate.** E(x) = Σ Φ_p · 2/(πr²) · (1 − d²/r²) over the photons within
//!   d = |x − x_p| < r whose receiver normal agrees with the shading normal (n·n_p > 0.5:
//!   only the lit side) and that lie within r/2 of the tangent plane: the Epanechnikov
//!   kernel on a disk, normalised to 1 over it. r = `Quality::caustic_radius`, by default
//!   0.5 % of the scene's bounding-box diagonal; the photons sit in a uniform hash grid of
//!   cell r. The shading adds albedo/π · E.
//! - **Error.** The estimate is consistent, not exact: it is the irradiance convolved with
//!   the kernel, so sharp foci and caustic edges are blurred over r (bias of order r² times
//!   the irradiance's curvature where it is smooth, up to the whole peak at a focus
//!   narrower than r), and it is noisy where few photons fall in a disk (relative noise
//!   about 1/√(photons per disk), less thanks to the low-discrepancy emission). More
//!   photons with a smaller radius converge to the exact caustic irradiance.

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::shade::{self, ShadeLight};
use super::{hash, Next, Ray, Tracer};
use crate::error::{Error, Result};
use crate::quality::Quality;
use crate::scene::{LightKind, SurfaceKind};

/// A photon stored on a diffuse receiver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    pub position: DVec3,
    /// The receiver's unit normal on the side the photon arrived from.
    pub normal: DVec3,
    /// Power per channel [W].
    pub power: DVec3,
    /// Specular interactions on its way from the light (≥ 1).
    pub bounces: u32,
}

/// The caustic photons of a scene in a uniform hash grid of cell `radius`.
pub struct PhotonMap {
    /// Sorted by grid cell.
    photons: Vec<Photon>,
    radius: f64,
    /// Grid cell → range in `photons`.
    cells: HashMap<[i64; 3], (usize, usize)>,
}

/// Point `i` of the R2 sequence in [0, 1)².
fn r2(i: u32) -> DVec2 {
    const G: f64 = 1.324_717_957_244_746; // the plastic number
    DVec2::new(0.5 + i as f64 / G, 0.5 + i as f64 / (G * G)).fract()
}

/// Shirley and Chiu's concentric map of [0, 1)² onto the unit disk: area-preserving and
/// continuous, the square's centre at the disk's, so that low-discrepancy points stay
/// well spread near the cone's axis (where a ball's focus lies) as everywhere else.
fn concentric(u: DVec2) -> DVec2 {
    let (a, b) = (2.0 * u.x - 1.0, 2.0 * u.y - 1.0);
    let (r, phi) = if a == 0.0 && b == 0.0 {
        return DVec2::ZERO;
    } else if a.abs() > b.abs() {
        (a, PI / 4.0 * b / a)
    } else {
        (b, PI / 2.0 - PI / 4.0 * a / b)
    };
    DVec2::from_angle(phi) * r
}

/// Where a light's photons towards one generator start: origin and unit direction of
/// sample `u`, and the solid angle (point, spot) or area (directional) they share.
struct Emitter<'l> {
    light: &'l ShadeLight,
    centre: DVec3,
    axis: DVec3,
    frame: (DVec3, DVec3),
    radius: f64,
    /// Cosine of the cone's half-angle (point, spot); upstream distance (directional).
    extent: f64,
    measure: f64,
}

impl<'l> Emitter<'l> {
    fn new(light: &'l ShadeLight, centre: DVec3, radius: f64, upstream: f64) -> Emitter<'l> {
        let (axis, extent, measure) = if light.kind == LightKind::Directional {
            (light.direction.normalize_or(DVec3::NEG_Y), upstream, PI * radius * radius)
        } else {
            let to = centre - light.position;
            let d = to.length();
            let cos_max = if d > radius { (1.0 - (radius / d).powi(2)).sqrt() } else { -1.0 };
            (to.normalize_or(DVec3::Y), cos_max, TAU * (1.0 - cos_max))
        };
        Emitter { light, centre, axis, frame: axis.any_orthonormal_pair(), radius, extent, measure }
    }

    /// The photon of `u` ∈ [0, 1)²: the square mapped onto the unit disk preserving area
    /// (`concentric`), the disk onto the cone's spherical cap (area again: 1 − cos θ ∝ ρ²)
    /// or onto the directional light's disk.
    fn ray(&self, u: DVec2) -> (DVec3, DVec3) {
        let (t1, t2) = self.frame;
        let q = concentric(u);
        let across = t1 * q.x + t2 * q.y;
        if self.light.kind == LightKind::Directional {
            (self.centre + across * self.radius - self.axis * self.extent, self.axis)
        } else {
            let rho2 = q.length_squared();
            let cos_t = 1.0 - rho2 * (1.0 - self.extent);
            let sin_over_rho = if rho2 > 0.0 { ((1.0 - cos_t * cos_t).max(0.0) / rho2).sqrt() } else { 0.0 };
            (self.light.position, (across * sin_over_rho + self.axis * cos_t).normalize())
        }
    }
}

impl PhotonMap {
    /// Traces `quality.reference.reference_photons` photons per light and caustic generator of the
    /// tracer's scene and sorts the stored ones into the grid.
    pub(super) fn build(tracer: &Tracer, quality: &Quality) -> Result<PhotonMap> {
        let n = quality.reference.reference_photons;
        if n == 0 {
            return Err(Error::invalid("knob reference_photons", "must be at least 1"));
        }
        let radius = Self::radius_for(tracer, quality)?;
        Self::trace(tracer, n, 0, radius)
    }

    /// The density estimate's radius under `quality`: `caustic_radius`, auto 0.5 % of the
    /// scene's bounding-box diagonal.
    pub(super) fn radius_for(tracer: &Tracer, quality: &Quality) -> Result<f64> {
        let diag = tracer.scene.bounds().diagonal() as f64;
        let radius = quality.reference.caustic_radius.map_or(0.005 * diag, |r| r as f64);
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(Error::invalid("knob caustic_radius", format!("{radius} m is not a radius > 0")));
        }
        Ok(radius)
    }

    /// Pass `pass` of `n` photons per light and generator (the sequence's photons
    /// `pass·n … (pass + 1)·n − 1`, each carrying 1/n of the light's power into the
    /// generator's cone), in a grid of cells of `radius`.
    pub(super) fn trace(tracer: &Tracer, n: u32, pass: u32, radius: f64) -> Result<PhotonMap> {
        let first = pass.checked_mul(n).ok_or_else(|| Error::invalid("knob ppm_passes", "passes × photons exceed 2³²"))?;
        let scene_box = tracer.scene.bounds();
        let diag = scene_box.diagonal() as f64;
        let generators: Vec<(u32, DVec3, f64)> = (tracer.scene.meshes.iter().enumerate())
            .filter(|(_, m)| !m.hidden && tracer.scene.materials[m.material].kind.is_specular())
            .map(|(g, m)| {
                let b = m.bounds();
                (g as u32, b.center().as_dvec3(), 0.5 * b.diagonal() as f64)
            })
            .filter(|&(_, _, r)| r > 0.0)
            .collect();
        let mut photons = Vec::new();
        for (l, light) in tracer.lights.iter().enumerate() {
            for &(g, centre, r) in &generators {
                let upstream = (centre - scene_box.center().as_dvec3()).length() + diag + r;
                let emitter = Emitter::new(light, centre, r, upstream);
                let seed = hash(l as u32, g, 0xca05_7105);
                photons.par_extend((first..first + n).into_par_iter().filter_map(|i| tracer.trace_photon(&emitter, g, i, seed, n)));
            }
        }
        Ok(PhotonMap::new(photons, radius))
    }

    fn new(mut photons: Vec<Photon>, radius: f64) -> PhotonMap {
        let cell = |p: &Photon| cell_of(p.position, radius);
        photons.sort_by_key(cell);
        let mut cells = HashMap::new();
        let mut start = 0;
        for chunk in photons.chunk_by(|a, b| cell(a) == cell(b)) {
            cells.insert(cell(&chunk[0]), (start, start + chunk.len()));
            start += chunk.len();
        }
        PhotonMap { photons, radius, cells }
    }

    /// The stored photons (in grid order).
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// The density estimate's radius (metres).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Caustic irradiance at `x` on a surface of unit normal `n` (the side it is seen
    /// from): the Epanechnikov disk estimate of the module doc.
    pub fn irradiance(&self, x: DVec3, n: DVec3) -> DVec3 {
        let (r, r2) = (self.radius, self.radius * self.radius);
        let norm = 2.0 / (PI * r2);
        self.around(x, n, r).map(|(p, d2)| p.power * (norm * (1.0 - d2 / r2))).sum()
    }

    /// The photons within `r` (at most the grid's cell) of `x` that the kernel's tests
    /// accept (same side, normal within 60°, within half the radius of the plane), with
    /// their squared distances.
    fn around(&self, x: DVec3, n: DVec3, r: f64) -> impl Iterator<Item = (&Photon, f64)> + '_ {
        let r = r.min(self.radius);
        let k = cell_of(x, self.radius);
        (-1..=1)
            .flat_map(move |dz| {
                (-1..=1)
                    .flat_map(move |dy| (-1..=1).map(move |dx| [k[0].saturating_add(dx), k[1].saturating_add(dy), k[2].saturating_add(dz)]))
            })
            .filter_map(|key| self.cells.get(&key))
            .flat_map(|&(a, b)| &self.photons[a..b])
            .filter_map(move |p| {
                let v = p.position - x;
                let d2 = v.length_squared();
                (d2 < r * r && n.dot(p.normal) > 0.5 && v.dot(n).abs() < 0.5 * r).then_some((p, d2))
            })
    }

    /// The photons [`around`](Self::around) `x` within `r`: their number and their summed
    /// power (progressive photon mapping's gather, `ppm.rs`).
    pub(super) fn within(&self, x: DVec3, n: DVec3, r: f64) -> (usize, DVec3) {
        self.around(x, n, r).fold((0, DVec3::ZERO), |(c, f), (p, _)| (c + 1, f + p.power))
    }
}

fn cell_of(p: DVec3, r: f64) -> [i64; 3] {
    let c = (p / r).floor();
    [c.x as i64, c.y as i64, c.z as i64]
}

impl Tracer<'_> {
    /// Photon `i` of `n` from `emitter` towards generator mesh `generator`: where it lands
    /// on a diffuse surface after ≥ 1 specular bounce, or `None`.
    fn trace_photon(&self, emitter: &Emitter, generator: u32, i: u32, seed: u32, n: u32) -> Option<Photon> {
        let (o, mut d) = emitter.ray(r2(i));
        let mut hit = self.bvh.intersect(o, d, 0.0, f64::INFINITY, None)?;
        if self.bvh.triangles[hit.triangle as usize].mesh != generator {
            return None; // direct light, or another generator's photon
        }
        let mut power = DVec3::ZERO;
        let mut bounces = 0;
        let mut len = hit.t;
        let mut medium = None;
        loop {
            let s = self.surface(&hit);
            if bounces == 0 {
                let (_, e, dist) = emitter.light.incident(s.position);
                let intensity = if dist.is_finite() { e * dist * dist } else { e };
                power = intensity * (emitter.measure / n as f64);
                if power.max_element() <= 0.0 {
                    return None;
                }
            }
            let m = &self.scene.materials[s.material];
            power *= shade::segment_transmittance(m, s.normal, d, len); // absorbed inside a solid
            if m.kind == SurfaceKind::Diffuse {
                let normal = if s.normal.dot(d) > 0.0 { -s.normal } else { s.normal };
                return Some(Photon { position: s.position, normal, power, bounces });
            }
            if bounces == self.depth {
                return None;
            }
            let split = shade::specular_split_at(m, self.fresnel, d, s.normal, s.position);
            let mean = |f: DVec3| f.element_sum() / 3.0;
            let (pr, pt) = (mean(split.fr), mean(split.ft));
            if pr + pt <= 0.0 || (pr + pt).is_nan() {
                return None; // a black mirror absorbs the photon
            }
            let p = pr / (pr + pt);
            let u = hash(i, bounces, seed) as f64 / 4_294_967_296.0;
            let reflected = u < p;
            let (mut dir, f, p) = if reflected { (split.r, split.fr, p) } else { (split.t, split.ft, 1.0 - p) };
            power *= f / p;
            if !reflected && m.disperses() {
                // KHR_materials_dispersion: the photon refracts as one channel, the one it
                // carries alone, else one chosen uniformly (its power ×3 in that channel).
                let carried: Vec<usize> = (0..3).filter(|&k| power[k] > 0.0).collect();
                let k = if carried.len() == 1 {
                    carried[0]
                } else {
                    let k = (hash(i ^ 0x9e37_79b9, bounces, seed) % 3) as usize;
                    power = DVec3::from_array(std::array::from_fn(|j| if j == k { 3.0 * power[k] } else { 0.0 }));
                    k
                };
                dir = split.tc[k];
            }
            d = dir.normalize();
            bounces += 1;
            // Through a graded medium along the curved path, as the camera's rays.
            medium = self.child_medium(s.material, s.normal, d, reflected, medium);
            let ray = Ray { o: s.position, d, t_min: self.epsilon, skip: Some(hit.triangle), medium };
            (hit, d, len) = match self.next(&ray) {
                Next::Hit(h, d, len) => (h, d, len),
                Next::Sky(_) | Next::Lost => return None,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::fresnel_dielectric;
    use crate::quality::{Caustics, FresnelMode};
    use crate::reference::render_reference;
    use crate::scene::{shapes, Camera, Light, Material, Scene};
    use glam::Vec3;

    fn point_light(position: Vec3, intensity: Vec3) -> Light {
        Light { name: "l".into(), kind: LightKind::Point, position, direction: Vec3::NEG_Y, intensity, range: None }
    }

    fn quality(photons: u32, radius: f32) -> Quality {
        {
            let mut knobs = Quality::default();
            knobs.caustics.caustics = Caustics::Splat;
            // These tests read the light tracer's photon map, which the kernel estimate builds.
            knobs.reference.caustic_estimate = crate::reference::knobs::CausticEstimate::Kernel;
            knobs.reference.reference_photons = photons;
            knobs.reference.caustic_radius = Some(radius);
            knobs.frame.fresnel = FresnelMode::Exact;
            knobs
        }
    }

    fn diffuse(s: &mut Scene) -> usize {
        s.add_material(Material { base_color: Vec3::new(0.8, 0.7, 0.6), ..Default::default() }).unwrap()
    }

    fn glass(s: &mut Scene, ior: f32) -> usize {
        s.add_material(Material { kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() }).unwrap()
    }

    /// A glass ball of radius 0.5 at (0, 1, 0) over a 6 m floor at y = 0, a point light of
    /// `intensity` at `light`.
    fn ball_over_floor(ior: f32, segments: u32, light: Vec3, intensity: Vec3) -> Scene {
        let mut s = Scene::new();
        let (floor, glass) = (diffuse(&mut s), glass(&mut s, ior));
        s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, 0.0, 3.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -6.0), 4, floor))
            .unwrap();
        s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.0, 1.0, 0.0), 0.5, segments, segments / 2, glass)).unwrap();
        s.add_light(point_light(light, intensity)).unwrap();
        s
    }

    /// ∫ over the cone that a sphere of radius `r` subtends at distance `d` of g(F(θᵢ)) dΩ,
    /// θᵢ the incidence angle on the sphere (midpoint rule in ψ, the angle off the axis).
    fn over_sphere_cone(r: f64, d: f64, ior: f64, g: impl Fn(f64) -> f64) -> f64 {
        let (alpha, steps) = ((r / d).asin(), 200_000);
        (0..steps)
            .map(|k| {
                let psi = alpha * (k as f64 + 0.5) / steps as f64;
                let sin_i = (d * psi.sin() / r).min(1.0);
                g(fresnel_dielectric((1.0 - sin_i * sin_i).sqrt(), ior)) * TAU * psi.sin() * alpha / steps as f64
            })
            .sum()
    }

    /// Energy: a solid glass ball (ν = 1.5) in a closed diffuse room, a point light 2 m above
    /// its centre. Exact Fresnel is symmetric (F at the exit equals F at the entry), so each
    /// photon entering the ball leaves it after two refractions with probability (1 − F)²
    /// (paths T T, which all reach a wall: `bounces == 2`) and the stored power of every
    /// path together is ∫ I (1 − (1 − F) F^(depth−1)) dΩ (what stays inside after `depth`
    /// interactions is lost; every other photon reaches a wall). Tolerance 0.5 %: the ball
    /// is a 128×64 polygon with interpolated normals (its silhouette and hit angles differ
    /// from the sphere's by ~1e-3); the emission noise is far below that.
    /// Measured: T T 0.9984 of the closed form, all paths 0.9993.
    #[test]
    fn glass_ball_transmits_the_fresnel_closed_form() {
        let mut s = Scene::new();
        let (wall, glass) = (diffuse(&mut s), glass(&mut s, 1.5));
        for m in shapes::quadrant_room(Vec3::new(0.0, 2.0, 0.0), 2.0, 1, |_, _| wall) {
            s.add_mesh(m).unwrap();
        }
        s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.0, 1.0, 0.0), 0.5, 128, 64, glass)).unwrap();
        s.add_light(point_light(Vec3::new(0.0, 3.0, 0.0), Vec3::ONE)).unwrap();
        let q = {
            let mut knobs = quality(200_000, 0.05);
            knobs.frame.depth = 4;
            knobs
        };
        let t = Tracer::new(&s, &q).unwrap();
        let photons = t.photon_map().unwrap().photons();
        let sum = |f: &dyn Fn(&Photon) -> bool| photons.iter().filter(|p| f(p)).map(|p| p.power.x).sum::<f64>();
        let (tt, all) = (sum(&|p| p.bounces == 2), sum(&|_| true));
        let tt_exact = over_sphere_cone(0.5, 2.0, 1.5, |f| (1.0 - f).powi(2));
        let all_exact = over_sphere_cone(0.5, 2.0, 1.5, |f| 1.0 - (1.0 - f) * f.powi(3));
        println!("energy: T T {tt:.6} vs {tt_exact:.6} ({:.5}), all {all:.6} vs {all_exact:.6} ({:.5})", tt / tt_exact, all / all_exact);
        assert!((tt / tt_exact - 1.0).abs() < 5e-3, "T T: {tt} vs {tt_exact}");
        assert!((all / all_exact - 1.0).abs() < 5e-3, "all: {all} vs {all_exact}");
        assert!(photons.iter().all(|p| (p.power - p.power.x).abs().max_element() < 1e-12), "grey glass keeps the colour");
    }

    /// A flat mirror tilted 45° under a point light 2 m above it sends the light sideways
    /// onto a wall 3 m away: the reflected spot is lit by the light's virtual image, 5 m
    /// away along the unfolded path, E = F(45°) I / 25 per channel. Tolerance 1 %: emission
    /// noise of ~1200 photons per kernel disk (low-discrepancy) and the kernel's bias
    /// (r²/L² ≈ 4e-4). Measured: 1.0015 (0.99984 with 1.6e6 photons). Outside the reflected
    /// beam the wall gets nothing.
    #[test]
    fn tilted_mirror_images_the_light_onto_a_wall() {
        let mut s = Scene::new();
        let wall = diffuse(&mut s);
        let mirror =
            Material { kind: SurfaceKind::Mirror { nu: Vec3::new(0.15, 0.5, 1.2), kappa: Vec3::new(3.5, 2.8, 2.2) }, ..Default::default() };
        let f = shade::material_fresnel(&mirror, FresnelMode::Exact, 0.5f64.sqrt(), 1.0);
        let mirror = s.add_material(mirror).unwrap();
        let (u, v) = (Vec3::Z, Vec3::new(1.0, -1.0, 0.0) / 2f32.sqrt()); // faces (1, 1, 0)/√2
        s.add_mesh(shapes::quad("mirror", -(u + v) * 0.5, u, v, 1, mirror)).unwrap();
        s.add_mesh(shapes::quad("wall", Vec3::new(3.0, -2.0, -2.0), Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 4.0, 0.0), 1, wall)).unwrap();
        let intensity = Vec3::new(1.0, 2.0, 3.0);
        s.add_light(point_light(Vec3::new(0.0, 2.0, 0.0), intensity)).unwrap();
        let t = Tracer::new(&s, &quality(400_000, 0.1)).unwrap();
        let e = t.caustic_irradiance(DVec3::new(3.0, 0.0, 0.0), DVec3::NEG_X);
        let expected = f * intensity.as_dvec3() / 25.0;
        println!("mirror: {e} vs {expected}, ratio {}", e / expected);
        assert!(((e / expected) - 1.0).abs().max_element() < 0.01, "{e} vs {expected}");
        assert_eq!(t.caustic_irradiance(DVec3::new(3.0, 0.0, 1.8), DVec3::NEG_X), DVec3::ZERO);
        // Seen from behind the wall (its normal away from the photons' side): nothing.
        assert_eq!(t.caustic_irradiance(DVec3::new(3.0, 0.0, 0.0), DVec3::X), DVec3::ZERO);
    }

    /// The estimate converges: RMSE over a 9×9 grid across the ball's caustic on the floor
    /// against 1.28e6 photons falls with the photon count (r = 3 cm). Measured: RMSE 0.0497,
    /// 0.0345, 0.0073 W/m² at 1e4, 4e4, 1.6e5 photons (6.8 %, 4.7 %, 1.0 % of the mean
    /// 0.73 W/m²); the 1.28e6-photon map takes 0.6 s to build on 2 cores.
    #[test]
    fn caustic_estimate_converges_with_photons() {
        let s = ball_over_floor(1.5, 64, Vec3::new(0.0, 3.0, 0.0), Vec3::ONE);
        let grid: Vec<DVec3> = (0..81).map(|k| DVec3::new((k % 9) as f64 * 0.06 - 0.24, 0.0, (k / 9) as f64 * 0.06 - 0.24)).collect();
        let estimate = |n: u32| {
            let start = std::time::Instant::now();
            let t = Tracer::new(&s, &quality(n, 0.03)).unwrap();
            let built = start.elapsed();
            let e: Vec<f64> = grid.iter().map(|&p| t.caustic_irradiance(p, DVec3::Y).x).collect();
            println!("{n} photons: map built in {built:?}, {} stored", t.photon_map().unwrap().photons().len());
            e
        };
        let reference = estimate(1_280_000);
        let mean = reference.iter().sum::<f64>() / reference.len() as f64;
        let mut last = f64::INFINITY;
        for n in [10_000, 40_000, 160_000] {
            let e = estimate(n);
            let rmse = (e.iter().zip(&reference).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / e.len() as f64).sqrt();
            println!("{n} photons: RMSE {rmse:.5} W/m² ({:.4} of the mean {mean:.4})", rmse / mean);
            assert!(rmse < last, "RMSE {rmse} at {n} photons is not below {last}");
            last = rmse;
        }
    }

    /// ν → 1: the ball is invisible to light, so the caustic under it is the unshadowed
    /// direct irradiance E cos θ of `ShadeLight::incident` (the shadow ray, which sees the
    /// ball as opaque, misses exactly that), for a point light, a spot light whose ramp
    /// falls across the ball (its falloff carried by the photons) and a slanted directional
    /// light. Tolerance 1 %: emission noise of several hundred photons per disk
    /// (low-discrepancy) and the kernel's blur of the spot's ramp. Measured: within 0.6 %.
    #[test]
    fn index_near_one_gives_the_unshadowed_direct_light() {
        let top = Vec3::new(0.0, 3.0, 0.0);
        let spot = LightKind::Spot { inner_cone: 0.1, outer_cone: 0.35 };
        let slanted = Vec3::new(0.3, -1.0, 0.0);
        for (kind, position, direction, shift) in
            [(LightKind::Point, top, Vec3::NEG_Y, 0.0), (spot, top, Vec3::NEG_Y, 0.0), (LightKind::Directional, top, slanted, 0.3)]
        {
            let mut s = ball_over_floor(1.0001, 32, top, Vec3::ONE);
            s.lights.clear();
            s.add_light(Light { kind, position, direction, intensity: Vec3::splat(2.0), ..point_light(top, Vec3::ONE) }).unwrap();
            let light = ShadeLight::new(&s.lights[0]);
            let t = Tracer::new(&s, &quality(400_000, 0.06)).unwrap();
            for x in [-0.3, 0.0, 0.2, 0.4] {
                let p = DVec3::new(x + shift, 0.0, 0.1);
                let e = t.caustic_irradiance(p, DVec3::Y).x;
                let (wi, direct, _) = light.incident(p);
                let direct = direct.x * wi.y;
                println!("ν → 1, {kind:?} at x = {x}: {e:.5} vs {direct:.5} ({:.4})", e / direct);
                assert!((e / direct - 1.0).abs() < 0.01, "{kind:?} at x = {x}: {e} vs {direct}");
            }
        }
    }

    fn golden_scene() -> Scene {
        let mut s = ball_over_floor(1.5, 48, Vec3::new(0.3, 3.0, 0.2), Vec3::new(4.0, 3.0, 2.0));
        s.camera = Some(Camera::look_at(Vec3::new(0.0, 2.5, 3.5), Vec3::new(0.0, 0.5, 0.0), 0.8));
        s
    }

    fn image_hash(q: &Quality) -> u64 {
        let img = render_reference(&golden_scene(), q, (32, 24)).unwrap();
        img.data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| (h ^ v.to_bits() as u64).wrapping_mul(0x100_0000_01b3))
    }

    /// caustics=off changes nothing: the image is bit for bit the one of the reference before
    /// caustics existed (FNV-1a of its f32 bits, recorded at commit 43b49c6), and no photon
    /// map is built. With caustics on the image changes (the floor under the ball).
    #[test]
    fn off_is_the_old_reference_bit_for_bit() {
        let off = {
            let mut knobs = Quality::default();
            knobs.caustics.caustics = Caustics::Off;
            knobs
        };
        assert_eq!(image_hash(&off), 0xd946_45ca_2b44_3afc);
        let s = golden_scene();
        let t = Tracer::new(&s, &off).unwrap();
        assert!(t.photon_map().is_none());
        assert_eq!(t.caustic_irradiance(DVec3::ZERO, DVec3::Y), DVec3::ZERO);
        assert_ne!(
            image_hash(&{
                let mut knobs = Quality::default();
                knobs.caustics.caustics = Caustics::Splat;
                knobs.reference.reference_photons = 20_000;
                knobs
            }),
            0xd946_45ca_2b44_3afc
        );
    }

    /// Without a specular object or without a light there are no photons.
    #[test]
    fn no_generator_or_no_light_no_photons() {
        let mut s = Scene::new();
        let floor = diffuse(&mut s);
        s.add_mesh(shapes::quad("floor", Vec3::new(-1.0, 0.0, 1.0), Vec3::X * 2.0, Vec3::NEG_Z * 2.0, 1, floor)).unwrap();
        s.add_light(point_light(Vec3::Y, Vec3::ONE)).unwrap();
        let q = quality(10_000, 0.05);
        assert!(Tracer::new(&s, &q).unwrap().photon_map().unwrap().photons().is_empty());
        let mut dark = ball_over_floor(1.5, 16, Vec3::Y * 3.0, Vec3::ONE);
        dark.lights.clear();
        assert!(Tracer::new(&dark, &q).unwrap().photon_map().unwrap().photons().is_empty());
        // Bad knobs are errors, not panics.
        assert!(Tracer::new(&s, &{
            let mut knobs = q.clone();
            knobs.reference.reference_photons = 0;
            knobs
        })
        .is_err());
        assert!(Tracer::new(&s, &{
            let mut knobs = q;
            knobs.reference.caustic_radius = Some(-1.0);
            knobs
        })
        .is_err());
    }
}
