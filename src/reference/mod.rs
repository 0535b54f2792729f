//! The exact CPU reference renderer: Whitted-style ray tracing in the original geometry
//! (survey §2, Table 1: "exact, all") in f64, the ground truth that tests and
//! `specula tradeoff` measure every GPU method against.
//!
//! - Geometry: every scene triangle in a SAH BVH (`bvh`), Möller–Trumbore hits.
//! - Specular surfaces: *both* the reflected and the refracted branch are followed,
//!   weighted by the Fresnel function of `Quality::fresnel` (survey eq. 1, 2),
//!   deterministically, up to `Quality::depth` bounces; a path still specular after that
//!   ends black. Branches whose path weight drops below `MIN_PATH_WEIGHT` in every channel
//!   are not followed (their share is below the GPU maps' half-float precision).
//! - Everything else is shaded as the GPU shades it (`shade`): emission + Lambertian
//!   direct light with the glTF range window and spot cone, with exact shadow rays in place
//!   of distance maps; rays that leave the scene see the same environment lookup.
//! - The camera is the GPU's: the same pinhole, aspect ratio of the output size, near
//!   plane (geometry nearer than `znear` along the view axis is clipped), pixel (x, y)
//!   spanning [x, x+1]×[y, y+1] with row 0 at the top. `Quality::spp` samples per pixel on a
//!   k×k stratified grid with a fixed hash jitter (1 sample = the pixel centre, as the GPU's
//!   single sample), averaged (box filter).
//! - Caustics (paths L S+ D, survey §6) only with `Quality::caustics` other than off:
//!   light-traced photons and a density estimate (`caustics`), added to the diffuse
//!   shading.
//! - Rows are rendered in parallel (rayon), the result is deterministic.

pub mod bvh;
pub mod caustics;
pub mod knobs;
pub mod ppm;
pub mod shade;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::image::ImageData;
use crate::quality::{Caustics, FresnelMode, Quality};
use crate::scene::{medium, Camera, Scene, SurfaceKind};
use bvh::{Bvh, Hit};
use caustics::PhotonMap;
use shade::{ShadeLight, Sky, Textures};

/// Path weights below this (every channel) are not traced further.
pub const MIN_PATH_WEIGHT: f64 = 1e-6;

/// A scene prepared for tracing: BVH, decoded textures, environment, lights.
pub struct Tracer<'a> {
    scene: &'a Scene,
    bvh: Bvh,
    textures: Textures,
    sky: Sky,
    lights: Vec<ShadeLight>,
    fresnel: FresnelMode,
    depth: u32,
    /// Secondary and shadow rays start this far from the surface they leave (and skip its
    /// triangle): a fixed fraction of the scene's size, so scaling the scene scales it.
    epsilon: f64,
    /// The caustic photons, built only when `Quality::caustics` is not off (and the
    /// estimate is the fixed kernel's).
    caustics: Option<PhotonMap>,
    /// `caustic_estimate=progressive` with caustics on: `render_reference` gathers them by
    /// progressive photon mapping at the camera paths' diffuse hits (`ppm`).
    progressive: bool,
    /// `shadows=off`: no shadow rays (every light reaches what faces it).
    shadows: bool,
}

/// What one camera ray sees, pre-computed per pixel sample.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    eye: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    tan_half: f64,
    aspect: f64,
    width: u32,
    height: u32,
    znear: f64,
}

impl CameraRays {
    /// The GPU camera (`Renderer::camera_view_proj`: reversed-Z infinite perspective,
    /// Vulkan y-down) as rays.
    pub fn new(camera: &Camera, width: u32, height: u32) -> CameraRays {
        let w = camera.world_from_camera.as_dmat4();
        CameraRays {
            eye: w.transform_point3(DVec3::ZERO),
            right: w.transform_vector3(DVec3::X),
            up: w.transform_vector3(DVec3::Y),
            forward: w.transform_vector3(DVec3::NEG_Z),
            tan_half: (camera.yfov as f64 * 0.5).tan(),
            aspect: width as f64 / height as f64,
            width,
            height,
            znear: camera.znear as f64,
        }
    }

    /// The ray through image point (x, y) in pixels (pixel centres at half-integers): its
    /// origin, unit direction and the ray parameter of the near plane.
    pub fn ray(&self, x: f64, y: f64) -> (DVec3, DVec3, f64) {
        let ndc_x = 2.0 * x / self.width as f64 - 1.0;
        let ndc_y = 2.0 * y / self.height as f64 - 1.0;
        // View space (x right, y up, −z forward) at unit depth.
        let d = self.right * (ndc_x * self.tan_half * self.aspect) - self.up * (ndc_y * self.tan_half) + self.forward;
        let len = d.length();
        (self.eye, d / len, self.znear * len)
    }
}

/// Sample `s` of `spp` = k² in pixel (x, y): the centre of stratum (s mod k, s div k),
/// jittered within it by a fixed hash; spp = 1 is the pixel centre.
pub fn sample_offset(x: u32, y: u32, s: u32, spp: u32) -> (f64, f64) {
    if spp <= 1 {
        return (0.5, 0.5);
    }
    let k = spp.isqrt().max(1);
    let (i, j) = (s % k, s / k);
    let h = hash(x, y, s);
    let jx = (h & 0xffff) as f64 / 65536.0;
    let jy = (h >> 16) as f64 / 65536.0;
    ((i as f64 + jx) / k as f64, (j as f64 + jy) / k as f64)
}

/// A 32-bit integer hash (lowbias32 by Chris Wellons) of the pixel and sample.
pub(crate) fn hash(x: u32, y: u32, s: u32) -> u32 {
    let mut h = x.wrapping_mul(0x9E37_79B9) ^ y.wrapping_mul(0x85EB_CA6B) ^ s.wrapping_mul(0xC2B2_AE35);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^ (h >> 16)
}

impl<'a> Tracer<'a> {
    /// Validates the scene and prepares it.
    pub fn new(scene: &'a Scene, quality: &Quality) -> Result<Tracer<'a>> {
        scene.validate()?;
        scene.check_renderable()?;
        if !(1..=64).contains(&quality.frame.depth) {
            return Err(Error::invalid("knob depth", format!("{} is outside 1..=64", quality.frame.depth)));
        }
        let diag = scene.bounds().diagonal() as f64;
        let mut tracer = Tracer {
            scene,
            bvh: Bvh::new(scene),
            textures: Textures::new(&scene.textures),
            sky: Sky::new(scene.environment.as_ref()),
            lights: scene.lights.iter().map(ShadeLight::new).collect(),
            fresnel: quality.frame.fresnel,
            depth: quality.frame.depth,
            epsilon: diag.max(f64::MIN_POSITIVE) * 1e-9,
            caustics: None,
            progressive: false,
            shadows: quality.frame.shadows,
        };
        if quality.caustics.caustics != Caustics::Off {
            if quality.reference.caustic_estimate == knobs::CausticEstimate::Progressive {
                tracer.progressive = true;
            } else {
                tracer.caustics = Some(PhotonMap::build(&tracer, quality)?);
            }
        }
        Ok(tracer)
    }

    /// The caustic photon map, `None` with caustics off.
    pub fn photon_map(&self) -> Option<&PhotonMap> {
        self.caustics.as_ref()
    }

    /// Caustic irradiance at `p` on a surface of unit normal `n` (towards the viewer):
    /// the photon map's density estimate, zero with caustics off.
    pub fn caustic_irradiance(&self, p: DVec3, n: DVec3) -> DVec3 {
        self.caustics.as_ref().map_or(DVec3::ZERO, |m| m.irradiance(p, n))
    }

    /// Radiance arriving at `o` from direction `-d` (d a unit vector): what the ray
    /// o + t d, t > t_min, sees, with `bounces` specular bounces left.
    pub fn radiance(&self, o: DVec3, d: DVec3, t_min: f64, bounces: u32) -> DVec3 {
        self.trace(Ray { o, d, t_min, skip: None, medium: None }, bounces, DVec3::ONE, None)
    }

    /// The mesh the ray o + t d, t > t_min, meets first (`None`: the sky).
    pub fn first_mesh(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<u32> {
        self.bvh.intersect(o, d, t_min, f64::INFINITY, None).map(|h| self.bvh.triangles[h.triangle as usize].mesh)
    }

    /// The specular bounces a path may take (the `depth` knob).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Where the ray o + t d, t > t_min, first meets a specular surface: its mesh, the
    /// point, the shading normal, the material and how it splits the ray (reflected and
    /// refracted directions, Fresnel weights); `None` where it meets a diffuse one or the sky.
    pub fn specular_hit(&self, o: DVec3, d: DVec3, t_min: f64) -> Option<SpecularHit> {
        let hit = self.bvh.intersect(o, d, t_min, f64::INFINITY, None)?;
        let surface = self.surface(&hit);
        let m = &self.scene.materials[surface.material];
        if m.kind == SurfaceKind::Diffuse {
            return None;
        }
        let split = shade::specular_split_at(m, self.fresnel, d, surface.normal, surface.position);
        let mesh = self.bvh.triangles[hit.triangle as usize].mesh;
        Some(SpecularHit { mesh, position: surface.position, material: surface.material, split })
    }

    /// How material `m` splits the ray of direction `d` (unit) meeting a surface of shading
    /// normal `n`, with this tracer's Fresnel.
    pub fn split(&self, m: &crate::scene::Material, d: DVec3, n: DVec3) -> shade::SpecularSplit {
        shade::specular_split(m, self.fresnel, d, n)
    }

    /// From `c` in direction `d` (unit), the first surface of mesh `only`, every other mesh
    /// passed through (what that mesh's refractor map holds: the mesh alone): its distance
    /// and interpolated unit normal; `None` where the ray misses the mesh.
    pub fn surface_of(&self, c: DVec3, d: DVec3, only: u32) -> Option<(f64, DVec3)> {
        let mut t_min = 0.0;
        for _ in 0..64 {
            let h = self.bvh.intersect(c, d, t_min, f64::INFINITY, None)?;
            if self.bvh.triangles[h.triangle as usize].mesh == only {
                return Some((h.t, self.surface(&h).normal));
            }
            t_min = h.t;
        }
        None
    }

    /// From `c` in direction `d` (unit), past every surface of mesh `exclude` (what a map of
    /// that mesh's environment holds): the first other surface's distance (`None`: the sky).
    pub fn distance_without(&self, c: DVec3, d: DVec3, exclude: u32) -> Option<f64> {
        self.past(c, d, exclude).map(|(t, _)| t)
    }

    /// What [`Tracer::distance_without`]'s surface shows (the sky where there is none), with
    /// one bounce fewer than the camera's.
    pub fn seen_without(&self, c: DVec3, d: DVec3, exclude: u32) -> DVec3 {
        match self.past(c, d, exclude) {
            Some((_, t_min)) => {
                self.trace(Ray { o: c, d, t_min, skip: None, medium: None }, self.depth.saturating_sub(1), DVec3::ONE, None)
            }
            None => self.sky.radiance(d),
        }
    }

    /// The first hit from `c` along `d` on a mesh other than `exclude`: its distance and the
    /// ray parameter just past `exclude`'s surfaces before it.
    fn past(&self, c: DVec3, d: DVec3, exclude: u32) -> Option<(f64, f64)> {
        let mut t_min = 0.0;
        for _ in 0..64 {
            let h = self.bvh.intersect(c, d, t_min, f64::INFINITY, None)?;
            if self.bvh.triangles[h.triangle as usize].mesh != exclude {
                return Some((h.t, t_min));
            }
            t_min = h.t;
        }
        None
    }

    /// `radiance`, recording the path's diffuse hits in `sink` for progressive photon
    /// mapping instead of adding a photon map's estimate there.
    /// The surface `ray` meets next: straight, or along the curved path of the graded
    /// medium it runs in (`scene::medium::GradedIndex::march`, at `REFERENCE_TURN`).
    fn next(&self, ray: &Ray) -> Next {
        let Ray { o, d, t_min, skip, medium } = *ray;
        let straight = |o, d, t_min, t_max, skip| self.bvh.intersect(o, d, t_min, t_max, skip);
        let Some((m, f)) = medium.and_then(|i| self.scene.materials[i].medium().map(|f| (&self.scene.materials[i], f))) else {
            return match straight(o, d, t_min, f64::INFINITY, skip) {
                Some(h) => Next::Hit(h, d, h.t),
                None => Next::Sky(d),
            };
        };
        let SurfaceKind::Dielectric { ior, .. } = m.kind else { return Next::Lost };
        let march = f.march(ior as f64, o, d, medium::REFERENCE_TURN, medium::REFERENCE_REFINE, |p, dir, t_max, first| {
            if first {
                straight(p, dir, t_min, t_max, skip)
            } else {
                straight(p, dir, 0.0, t_max, None)
            }
        });
        match march {
            None => Next::Lost,
            Some(medium::March { hit: Some(h), dir, before, .. }) => Next::Hit(h, dir, before + h.t),
            Some(medium::March { hit: None, dir, .. }) => Next::Sky(dir),
        }
    }

    /// The medium a child ray leaving a surface of material `material` (normal `n`, the
    /// mesh's outward one) along `dir` runs in: inside a graded material's object it runs in
    /// that material; off any other surface a reflected child stays in the medium it came
    /// from (`from`) and a refracted one leaves it (a dielectric nested in a graded medium:
    /// its rays straight).
    fn child_medium(&self, material: usize, n: DVec3, dir: DVec3, reflected: bool, from: Option<usize>) -> Option<usize> {
        if self.scene.materials[material].medium().is_some() {
            (dir.dot(n) < 0.0).then_some(material)
        } else if reflected {
            from
        } else {
            None
        }
    }

    fn trace(&self, ray: Ray, bounces: u32, weight: DVec3, mut sink: Option<&mut HitSink>) -> DVec3 {
        if !ray.d.is_finite() || !ray.o.is_finite() {
            return DVec3::ZERO; // never a NaN colour
        }
        let (hit, d, len) = match self.next(&ray) {
            Next::Hit(h, d, len) => (h, d, len),
            Next::Sky(d) => return self.sky.radiance(d),
            Next::Lost => return DVec3::ZERO,
        };
        let surface = self.surface(&hit);
        let m = &self.scene.materials[surface.material];
        if m.kind == SurfaceKind::Diffuse {
            return self.shade_diffuse(&surface, hit.triangle, d, weight, sink);
        }
        if bounces == 0 {
            return DVec3::ZERO;
        }
        // Absorbed on the way here when the ray ran inside a solid (KHR_materials_volume).
        let absorbed = shade::segment_transmittance(m, surface.normal, d, len);
        let split = shade::specular_split_at(m, self.fresnel, d, surface.normal, surface.position);
        // Under dispersion a refracted branch per channel, carrying that channel alone.
        let mask = |k: usize| DVec3::from_array(std::array::from_fn(|j| (j == k) as u32 as f64));
        let refracted: [(DVec3, DVec3); 3] = if m.disperses() {
            std::array::from_fn(|k| (split.tc[k], split.ft * absorbed * mask(k)))
        } else {
            [(split.t, split.ft * absorbed), (split.t, DVec3::ZERO), (split.t, DVec3::ZERO)]
        };
        let mut c = DVec3::ZERO;
        for (k, (dir, f)) in std::iter::once((split.r, split.fr * absorbed)).chain(refracted).enumerate() {
            let w = weight * f;
            if w.max_element() >= MIN_PATH_WEIGHT {
                let medium = self.child_medium(surface.material, surface.normal, dir, k == 0, ray.medium);
                let next = Ray { o: surface.position, d: dir.normalize(), t_min: self.epsilon, skip: Some(hit.triangle), medium };
                c += f * self.trace(next, bounces - 1, w, sink.as_deref_mut());
            }
        }
        c
    }

    /// Position, interpolated unit normal, texture coordinates and material of a hit.
    fn surface(&self, hit: &Hit) -> Surface {
        let tri = &self.bvh.triangles[hit.triangle as usize];
        let mesh = &self.scene.meshes[tri.mesh as usize];
        let idx = &mesh.indices[3 * tri.tri as usize..3 * tri.tri as usize + 3];
        let (u, v) = (hit.u, hit.v);
        let w = 1.0 - u - v;
        let n = |i: u32| mesh.normals[i as usize].as_dvec3();
        let t = |i: u32| mesh.uvs[i as usize].as_dvec2();
        let normal =
            (n(idx[0]) * w + n(idx[1]) * u + n(idx[2]) * v).try_normalize().unwrap_or_else(|| tri.e1.cross(tri.e2).normalize_or(DVec3::Y));
        Surface {
            position: tri.v0 + tri.e1 * u + tri.e2 * v,
            normal,
            uv: t(idx[0]) * w + t(idx[1]) * u + t(idx[2]) * v,
            material: mesh.material,
        }
    }

    /// `shade_diffuse` of glsl/common/shading.glsl, seen along `d`: emission +
    /// albedo/π Σ E cos θ · visibility, visibility by an exact shadow ray, plus the caustic
    /// irradiance when caustics are on.
    fn shade_diffuse(&self, s: &Surface, triangle: u32, d: DVec3, weight: DVec3, sink: Option<&mut HitSink>) -> DVec3 {
        let m = &self.scene.materials[s.material];
        let albedo = shade::base_color(m, &self.textures, s.uv);
        let n = if s.normal.dot(-d) < 0.0 { -s.normal } else { s.normal }; // two-sided
        let mut sum = DVec3::ZERO;
        for l in &self.lights {
            let (wi, e, dist) = l.incident(s.position);
            let cos_t = n.dot(wi);
            if cos_t <= 0.0 {
                continue;
            }
            let t_max = if dist.is_finite() { dist - self.epsilon } else { f64::INFINITY };
            if !self.shadows || !self.bvh.occluded(s.position, wi, self.epsilon, t_max, Some(triangle)) {
                sum += e * cos_t;
            }
        }
        if let Some(map) = &self.caustics {
            sum += map.irradiance(s.position, n);
        }
        if let Some(sink) = sink {
            let w = weight * albedo / std::f64::consts::PI * sink.scale;
            if w.max_element() > 0.0 {
                sink.points.push(ppm::HitPoint::new(sink.pixel, s.position, n, w));
            }
        }
        shade::emission(m, &self.textures, s.uv) + albedo / std::f64::consts::PI * sum
    }
}

/// A ray's first hit on a specular surface ([`Tracer::specular_hit`]).
#[derive(Clone, Copy, Debug)]
pub struct SpecularHit {
    pub mesh: u32,
    pub position: DVec3,
    /// The surface's material (an index of the scene's materials).
    pub material: usize,
    pub split: shade::SpecularSplit,
}

/// A ray o + t d, t > t_min, that does not hit triangle `skip` (the one it leaves).
#[derive(Clone, Copy)]
struct Ray {
    o: DVec3,
    d: DVec3,
    t_min: f64,
    skip: Option<u32>,
    /// The graded medium (a material index) the ray runs in, its path curving
    /// (`scene::medium`); `None`: straight.
    medium: Option<usize>,
}

/// What a ray meets next ([`Tracer::next`]).
enum Next {
    /// A surface: the hit, the (unit) direction the ray meets it along, the path length.
    Hit(Hit, DVec3, f64),
    /// Nothing: the sky along this direction.
    Sky(DVec3),
    /// Given up inside a graded medium (`scene::medium::max_steps` chords).
    Lost,
}

/// Where a camera sample's diffuse hits go (progressive photon mapping): its pixel and the
/// sample's share of it.
struct HitSink<'a> {
    points: &'a mut Vec<ppm::HitPoint>,
    pixel: u32,
    scale: f64,
}

struct Surface {
    position: DVec3,
    normal: DVec3,
    uv: DVec2,
    material: usize,
}

/// The camera paths' diffuse hits the progressive estimate keeps at once (about 120 bytes
/// each: 512 MiB); a larger image is gathered in bands of rows, each band tracing the passes'
/// photons again.
const HIT_POINT_BUDGET: usize = 1 << 22;

/// Renders `scene` exactly at `width`×`height` (camera: the scene's, or the default one
/// that frames it, as the GPU renderer takes it) with `quality.reference.spp` samples per pixel and
/// `quality.frame.depth` specular bounces. Linear radiance RGBA32F, alpha 1.
pub fn render_reference(scene: &Scene, quality: &Quality, size: (u32, u32)) -> Result<ImageData> {
    render_in_bands(scene, quality, size, HIT_POINT_BUDGET)
}

/// `render_reference` with the progressive estimate's hit points at most about `budget`.
fn render_in_bands(scene: &Scene, quality: &Quality, (width, height): (u32, u32), budget: usize) -> Result<ImageData> {
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(Error::invalid("size", format!("{width}x{height} is outside 1..=16384")));
    }
    let spp = quality.reference.spp;
    if !(1..=1024).contains(&spp) || spp.isqrt().pow(2) != spp {
        return Err(Error::invalid("knob spp", format!("{spp} is not a perfect square in 1..=1024")));
    }
    let camera = scene.camera_or_default();
    camera.validate()?;
    let tracer = Tracer::new(scene, quality)?;
    let rays = CameraRays::new(&camera, width, height);
    let mut data = vec![0f32; (width * height * 4) as usize];
    // Progressive photon mapping: each row's camera paths record their diffuse hits, gathered
    // band by band of rows so that the hit points stay within HIT_POINT_BUDGET (about 120
    // bytes each); every band's passes trace the same photons (the R2 sequence), so the
    // image is the same whatever the bands.
    let band = if tracer.progressive { (budget / (2 * width as usize * spp as usize)).clamp(1, height as usize) } else { height as usize };
    let row_len = width as usize * 4;
    for (b, chunk) in data.chunks_mut(band * row_len).enumerate() {
        let first_row = (b * band) as u32;
        let mut rows: Vec<Vec<ppm::HitPoint>> = (0..chunk.len() / row_len).map(|_| Vec::new()).collect();
        chunk.par_chunks_mut(row_len).zip(rows.par_iter_mut()).enumerate().for_each(|(dy, (row, points))| {
            let y = first_row + dy as u32;
            for x in 0..width {
                let mut c = DVec3::ZERO;
                for s in 0..spp {
                    let (jx, jy) = sample_offset(x, y, s, spp);
                    let (o, d, t_min) = rays.ray(x as f64 + jx, y as f64 + jy);
                    let mut sink = HitSink { points: &mut *points, pixel: y * width + x, scale: 1.0 / spp as f64 };
                    let sink = tracer.progressive.then_some(&mut sink);
                    c += tracer.trace(Ray { o, d, t_min, skip: None, medium: None }, tracer.depth, DVec3::ONE, sink);
                }
                c /= spp as f64;
                let px = &mut row[4 * x as usize..4 * x as usize + 4];
                px.copy_from_slice(&[c.x as f32, c.y as f32, c.z as f32, 1.0]);
            }
        });
        if tracer.progressive {
            let mut points: Vec<ppm::HitPoint> = rows.into_iter().flatten().collect();
            ppm::gather(&tracer, quality, &mut points)?;
            let passes = quality.reference.ppm_passes.max(1);
            let first = first_row as usize * width as usize;
            for p in &points {
                let c = p.weight * p.irradiance(passes);
                let at = 4 * (p.pixel as usize - first);
                for k in 0..3 {
                    chunk[at + k] += c[k] as f32;
                }
            }
        }
    }
    Ok(ImageData { width, height, layers: 1, channels: 4, data })
}

/// Each pixel's first-hit object from the camera (issue 15's masks): its mesh index + 1,
/// 0 where the ray through the pixel's centre meets nothing (the sky). The same rays as
/// `render_reference`'s single sample; hidden objects are hit by no ray.
pub fn object_ids(scene: &Scene, (width, height): (u32, u32)) -> Result<Vec<u32>> {
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(Error::invalid("size", format!("{width}x{height} is outside 1..=16384")));
    }
    scene.validate()?;
    let camera = scene.camera_or_default();
    camera.validate()?;
    let bvh = Bvh::new(scene);
    let rays = CameraRays::new(&camera, width, height);
    let mut ids = vec![0u32; (width * height) as usize];
    ids.par_chunks_mut(width as usize).enumerate().for_each(|(y, row)| {
        for (x, id) in row.iter_mut().enumerate() {
            let (o, d, t_min) = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            if let Some(hit) = bvh.intersect(o, d, t_min, f64::INFINITY, None) {
                *id = bvh.triangles[hit.triangle as usize].mesh + 1;
            }
        }
    });
    Ok(ids)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{shapes, Material};
    use glam::Vec3;

    #[test]
    fn strata_cover_the_pixel_once_each() {
        for spp in [4u32, 16, 25] {
            let k = spp.isqrt();
            let mut seen = vec![false; spp as usize];
            for s in 0..spp {
                let (x, y) = sample_offset(3, 5, s, spp);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                let cell = (y * k as f64) as usize * k as usize + (x * k as f64) as usize;
                assert!(!seen[cell], "stratum {cell} twice");
                seen[cell] = true;
            }
        }
        assert_eq!(sample_offset(7, 9, 0, 1), (0.5, 0.5));
    }

    /// The camera rays are those of the GPU's view-projection matrix: unprojecting a pixel
    /// centre through `Renderer::camera_view_proj`'s construction gives the same direction.
    #[test]
    fn camera_rays_match_the_gpu_projection() {
        let cam = Camera::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-0.5, 0.2, 0.0), 0.9);
        let (w, h) = (40u32, 30u32);
        let mut proj = glam::DMat4::perspective_infinite_reverse_rh(cam.yfov as f64, w as f64 / h as f64, cam.znear as f64);
        proj.y_axis.y = -proj.y_axis.y;
        let inv = (proj * cam.view().as_dmat4()).inverse();
        let rays = CameraRays::new(&cam, w, h);
        for (x, y) in [(0.5, 0.5), (20.0, 15.0), (39.5, 2.5)] {
            // Reversed-Z: ndc z = znear / depth; a far point keeps the f32 view matrix's
            // rounding small relative to its distance.
            let ndc = glam::DVec4::new(2.0 * x / w as f64 - 1.0, 2.0 * y / h as f64 - 1.0, 1e-4, 1.0);
            let p = inv * ndc;
            let expected = (p.truncate() / p.w - rays.eye).normalize();
            let (o, d, t_min) = rays.ray(x, y);
            assert!((d - expected).length() < 1e-6, "{d} vs {expected}");
            assert!((o - cam.position.as_dvec3()).length() < 1e-6);
            // The near plane: t_min along d is znear along the view axis.
            assert!((d.dot(rays.forward) * t_min / cam.znear as f64 - 1.0).abs() < 1e-6);
        }
    }

    /// Emission only: every pixel that sees the emitter is exactly its radiance.
    #[test]
    fn emitter_is_seen_at_its_radiance() {
        let mut s = Scene::new();
        let m = s.add_material(Material { base_color: Vec3::ZERO, emissive: Vec3::new(0.25, 0.5, 2.0), ..Default::default() }).unwrap();
        s.add_mesh(shapes::quad("q", Vec3::new(-1.0, -1.0, -1.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0), 2, m)).unwrap();
        s.camera = Some(Camera::look_at(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, 0.5));
        let q = {
            let mut knobs = Quality::default();
            knobs.reference.spp = 4;
            knobs
        };
        let img = render_reference(&s, &q, (8, 8)).unwrap();
        for p in img.data.chunks_exact(4) {
            assert_eq!(p, [0.25, 0.5, 2.0, 1.0]);
        }
    }

    /// KHR_materials_volume: a slab of solid glass (ν 1.5, 0.5 m thick, σ per channel) in a
    /// uniformly emissive room, seen at normal incidence, against the closed form: with F
    /// the Fresnel reflectance and T = exp(−σd), L·[F + (1−F)²·T] when the depth allows one
    /// pass through (2 bounces), L·[F + (1−F)²·T/(1 − F·T)] summed over every internal
    /// reflection (depth 64).
    #[test]
    fn absorption_through_a_slab_is_beer_lambert() {
        let sigma = Vec3::new(0.5, 1.0, 2.0);
        let mut s = Scene::new();
        let l = Vec3::new(2.0, 3.0, 4.0);
        let wall = s.add_material(Material { base_color: Vec3::ZERO, emissive: l, ..Default::default() }).unwrap();
        let glass = s
            .add_material(Material { kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, absorption: sigma, ..Default::default() })
            .unwrap();
        s.add_mesh(shapes::cuboid("room", Vec3::ZERO, Vec3::splat(5.0), wall)).unwrap();
        s.add_mesh(shapes::cuboid("slab", Vec3::ZERO, Vec3::new(2.0, 2.0, 0.25), glass)).unwrap();
        let f = 0.04f64; // ((ν − 1)/(ν + 1))² at normal incidence, Schlick and exact alike
        for (depth, series) in [(2u32, false), (64, true)] {
            let mut q = Quality::default();
            q.frame.depth = depth;
            let tracer = Tracer::new(&s, &q).unwrap();
            let c = tracer.radiance(DVec3::new(0.0, 0.0, 3.0), DVec3::NEG_Z, 0.0, depth);
            for k in 0..3 {
                let t = (-(sigma[k] as f64) * 0.5).exp();
                let inside = if series { t / (1.0 - f * t) } else { t };
                let expected = l[k] as f64 * (f + (1.0 - f) * (1.0 - f) * inside);
                assert!((c[k] - expected).abs() < 1e-5 * expected, "depth {depth}, channel {k}: {} vs {expected}", c[k]);
            }
        }
        // The same slab without absorption lets everything through: L.
        let clear =
            Scene { materials: s.materials.iter().map(|m| Material { absorption: Vec3::ZERO, ..m.clone() }).collect(), ..s.clone() };
        let mut q = Quality::default();
        q.frame.depth = 64;
        let c = Tracer::new(&clear, &q).unwrap().radiance(DVec3::new(0.0, 0.0, 3.0), DVec3::NEG_Z, 0.0, 64);
        assert!((c - l.as_dvec3()).abs().max_element() < 1e-6, "{c}");
    }
}
