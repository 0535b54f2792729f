//! The GPU's shading conventions in f64: `glsl/common/shading.glsl` (emission plus
//! Lambertian direct light from punctual lights, glTF range window, spot cone ramp),
//! `glsl/common/specular.glsl` (the split into reflected and refracted branches with their
//! Fresnel weights), `glsl/common/sky.glsl` (equirectangular environment lookup) and the
//! samplers the GPU binds (bilinear, REPEAT; R8G8B8A8_SRGB textures decoded before
//! filtering). Only visibility differs: exact shadow rays instead of distance maps.

use glam::{DVec2, DVec3};

use crate::optics::{fresnel_conductor, fresnel_dielectric, fresnel_f0, fresnel_schlick, reflect_dir, refract_dir};
use crate::quality::FresnelMode;
use crate::scene::{EnvironmentMap, Light, LightKind, Material, SurfaceKind, Texture};

/// sRGB-encoded byte → linear, as the R8G8B8A8_SRGB format decodes it.
fn srgb_table() -> [f64; 256] {
    let mut t = [0.0; 256];
    for (i, v) in t.iter_mut().enumerate() {
        let e = i as f64 / 255.0;
        *v = if e <= 0.04045 { e / 12.92 } else { ((e + 0.055) / 1.055).powf(2.4) };
    }
    t
}

/// Bilinear filtering with REPEAT addressing on a `w`×`h` grid, as a Vulkan LINEAR
/// sampler does it: texel centres at half-integers, weights from the fractional part.
fn bilinear(w: u32, h: u32, uv: DVec2, texel: impl Fn(usize) -> DVec3) -> DVec3 {
    let x = uv.x * w as f64 - 0.5;
    let y = uv.y * h as f64 - 0.5;
    if !(x.is_finite() && y.is_finite()) {
        return DVec3::ZERO;
    }
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let wrap = |i: f64, n: u32| (i.rem_euclid(n as f64)) as usize % n as usize;
    let (xa, xb) = (wrap(x0, w), wrap(x0 + 1.0, w));
    let (ya, yb) = (wrap(y0, h), wrap(y0 + 1.0, h));
    let w_ = w as usize;
    let t = |x: usize, y: usize| texel(y * w_ + x);
    (t(xa, ya) * (1.0 - fx) + t(xb, ya) * fx) * (1.0 - fy) + (t(xa, yb) * (1.0 - fx) + t(xb, yb) * fx) * fy
}

/// The scene's textures with their texels decoded to linear f64 once.
pub struct Textures {
    maps: Vec<(u32, u32, Vec<DVec3>)>,
}

impl Textures {
    pub fn new(textures: &[Texture]) -> Textures {
        let lut = srgb_table();
        let maps = textures
            .iter()
            .map(|t| {
                let texels =
                    t.rgba8.chunks_exact(4).map(|p| DVec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize])).collect();
                (t.width, t.height, texels)
            })
            .collect();
        Textures { maps }
    }

    /// `texture(textures, vec3(uv, layer)).rgb` of glsl/common/shading.glsl.
    pub fn sample(&self, index: usize, uv: DVec2) -> DVec3 {
        let (w, h, texels) = &self.maps[index];
        bilinear(*w, *h, uv, |i| texels[i])
    }
}

/// `sky_radiance` of glsl/common/sky.glsl: u = ½ + atan2(dₓ, −d_z)/2π, v = acos(d_y)/π,
/// bilinear with REPEAT; black without an environment map.
pub struct Sky {
    map: Option<(u32, u32, Vec<DVec3>)>,
}

impl Sky {
    pub fn new(env: Option<&EnvironmentMap>) -> Sky {
        Sky {
            map: env.map(|e| {
                let texels = e.rgba32f.chunks_exact(4).map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
                (e.width, e.height, texels)
            }),
        }
    }

    pub fn radiance(&self, d: DVec3) -> DVec3 {
        let Some((w, h, texels)) = &self.map else { return DVec3::ZERO };
        let d = d.normalize();
        let uv = DVec2::new(0.5 + d.x.atan2(-d.z) / std::f64::consts::TAU, d.y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI);
        bilinear(*w, *h, uv, |i| texels[i])
    }
}

/// A light as the shader sees it (the GPU's light table): cone cosines precomputed.
pub struct ShadeLight {
    pub kind: LightKind,
    pub position: DVec3,
    pub direction: DVec3,
    pub intensity: DVec3,
    /// glTF range, 0 for none (the shader's convention).
    pub range: f64,
    pub cos_outer: f64,
    pub cos_inner: f64,
}

impl ShadeLight {
    pub fn new(l: &Light) -> ShadeLight {
        let (cos_outer, cos_inner) = match l.kind {
            // The GPU stores the cone cosines in f32 (its light table).
            LightKind::Spot { inner_cone, outer_cone } => (outer_cone.cos() as f64, inner_cone.cos() as f64),
            _ => (-2.0, -1.0),
        };
        ShadeLight {
            kind: l.kind,
            position: l.position.as_dvec3(),
            direction: l.direction.as_dvec3(),
            intensity: l.intensity.as_dvec3(),
            range: l.range.unwrap_or(0.0) as f64,
            cos_outer,
            cos_inner,
        }
    }

    /// Direction towards the light, its irradiance at `p` on a surface facing it, and the
    /// distance to it (∞ for directional lights), the loop body of `shade_diffuse`.
    pub fn incident(&self, p: DVec3) -> (DVec3, DVec3, f64) {
        if self.kind == LightKind::Directional {
            return (-self.direction, self.intensity, f64::INFINITY);
        }
        let d = self.position - p;
        let d2 = d.length_squared().max(1e-12);
        let dist = d2.sqrt();
        let wi = d / dist;
        let mut e = self.intensity / d2;
        if self.range > 0.0 {
            // KHR_lights_punctual's recommended window, max(min(1 − (d/range)⁴, 1), 0) (the
            // shader's `light_irradiance` is its twin; not squared as some engines do).
            let r = dist / self.range;
            e *= (1.0 - r * r * r * r).clamp(0.0, 1.0);
        }
        if matches!(self.kind, LightKind::Spot { .. }) {
            // KHR_lights_punctual's recommended falloff (the ramp in cos θ, squared), as the
            // shader's `light_irradiance`.
            let cd = self.direction.dot(-wi);
            let ramp = ((cd - self.cos_outer) / (self.cos_inner - self.cos_outer).max(1e-4)).clamp(0.0, 1.0);
            e *= ramp * ramp;
        }
        (wi, e, dist)
    }
}

/// `material_base_color` and `material_emission`.
pub fn base_color(m: &Material, textures: &Textures, uv: DVec2) -> DVec3 {
    let c = m.base_color.as_dvec3();
    m.base_color_texture.map_or(c, |t| c * textures.sample(t, uv))
}

pub fn emission(m: &Material, textures: &Textures, uv: DVec2) -> DVec3 {
    let e = m.emissive.as_dvec3();
    m.emissive_texture.map_or(e, |t| e * textures.sample(t, uv))
}

/// `material_fresnel`: the Fresnel reflectance of `m` at incidence cosine `cos_i`, `eta` =
/// ν_t/ν_i for dielectrics; KHR_materials_specular scales F0 (colour) and the lobe (factor).
pub fn material_fresnel(m: &Material, mode: FresnelMode, cos_i: f64, eta: f64) -> DVec3 {
    let exact = mode == FresnelMode::Exact;
    if let SurfaceKind::Mirror { nu, kappa } = m.kind {
        let (nu, kappa) = (nu.as_dvec3(), kappa.as_dvec3());
        let f = |k: usize| {
            if exact {
                fresnel_conductor(cos_i, nu[k], kappa[k])
            } else {
                fresnel_schlick(fresnel_f0(nu[k], kappa[k]), cos_i)
            }
        };
        return DVec3::new(f(0), f(1), f(2));
    }
    let f = if exact {
        DVec3::splat(fresnel_dielectric(cos_i, eta))
    } else {
        // Schlick is written for incidence from the optically thinner side: the shader uses
        // the transmitted cosine when leaving a denser medium and reports TIR as 1.
        let mut c = cos_i;
        if eta < 1.0 {
            let s2 = (1.0 - cos_i * cos_i) / (eta * eta);
            if s2 >= 1.0 {
                return DVec3::ONE;
            }
            c = (1.0 - s2).sqrt();
        }
        let f0 = (DVec3::splat(fresnel_f0(eta, 0.0)) * m.specular_color.as_dvec3()).min(DVec3::ONE);
        DVec3::new(fresnel_schlick(f0.x, c), fresnel_schlick(f0.y, c), fresnel_schlick(f0.z, c))
    };
    f * m.specular_factor as f64
}

/// `SpecularSplit` of glsl/common/specular.glsl: the reflected and the refracted direction
/// with their weights (survey eq. 1). `t` is meaningful where `ft` is non-zero; under
/// dispersion `tc[k]` is channel k's refraction, `fr[k]` and `ft[k]` its weights (`t` the
/// d line's, green), without it all three are `t`.
#[derive(Clone, Copy, Debug)]
pub struct SpecularSplit {
    pub r: DVec3,
    pub t: DVec3,
    pub fr: DVec3,
    pub ft: DVec3,
    pub tc: [DVec3; 3],
}

/// `specular_split(m, p, n, eye)` with i = the (unit) ray direction: entering or leaving
/// is decided by the side of the shading normal the ray arrives from; thin-walled
/// dielectrics let the ray pass undeviated, weighted 1 − F; dispersive ones refract each
/// channel with its own index (`Material::channel_iors`, rounded to f32 as the GPU's).
pub fn specular_split(m: &Material, mode: FresnelMode, i: DVec3, n: DVec3) -> SpecularSplit {
    let ior = match m.kind {
        SurfaceKind::Dielectric { ior, .. } => ior as f64,
        _ => 1.0,
    };
    split_with_ior(m, mode, i, n, ior)
}

/// `specular_split` at the surface point `p`: a graded medium's surface refracts with the
/// field's index there (`Material::ior_at`).
pub fn specular_split_at(m: &Material, mode: FresnelMode, i: DVec3, n: DVec3, p: DVec3) -> SpecularSplit {
    match m.medium().and(m.ior_at(p)) {
        Some(ior) => split_with_ior(m, mode, i, n, ior),
        None => specular_split(m, mode, i, n),
    }
}

fn split_with_ior(m: &Material, mode: FresnelMode, i: DVec3, n: DVec3, ior: f64) -> SpecularSplit {
    let mut n = n;
    let mut cos_i = -n.dot(i);
    let entering = cos_i >= 0.0;
    if !entering {
        n = -n;
        cos_i = -cos_i;
    }
    let r = reflect_dir(i, n);
    match m.kind {
        SurfaceKind::Dielectric { thin, .. } => {
            if thin {
                let fr = material_fresnel(m, mode, cos_i, ior);
                return SpecularSplit { r, t: i, fr, ft: DVec3::ONE - fr, tc: [i; 3] };
            }
            if m.disperses() {
                let iors = m.channel_iors().unwrap_or(glam::Vec3::splat(ior as f32)).as_dvec3();
                let mut s = SpecularSplit { r, t: i, fr: DVec3::ONE, ft: DVec3::ZERO, tc: [i; 3] };
                let mut any = false;
                for k in 0..3 {
                    let eta = if entering { iors[k] } else { 1.0 / iors[k] };
                    if let Some(t) = refract_dir(i, n, 1.0 / eta) {
                        s.tc[k] = t;
                        s.fr[k] = material_fresnel(m, mode, cos_i, eta)[k];
                        s.ft[k] = 1.0 - s.fr[k];
                        if !any || k == 1 {
                            s.t = t;
                        }
                        any = true;
                    }
                }
                return s;
            }
            let eta = if entering { ior } else { 1.0 / ior }; // ν_t / ν_i
            match refract_dir(i, n, 1.0 / eta) {
                None => SpecularSplit { r, t: i, fr: DVec3::ONE, ft: DVec3::ZERO, tc: [i; 3] }, // total internal reflection
                Some(t) => {
                    let fr = material_fresnel(m, mode, cos_i, eta);
                    SpecularSplit { r, t, fr, ft: DVec3::ONE - fr, tc: [t; 3] }
                }
            }
        }
        _ => SpecularSplit { r, t: i, fr: material_fresnel(m, mode, cos_i, 1.0), ft: DVec3::ZERO, tc: [i; 3] },
    }
}

/// `segment_transmittance` of glsl/common/specular.glsl: what is left of radiance after the
/// segment of length `len` a ray of direction `d` ran to a surface of material `m` (shading
/// normal `n`, either way round): Beer–Lambert, exp(−σ·len), when the ray meets a solid
/// dielectric's surface from within (as `specular_split` tells leaving from entering), else 1.
pub fn segment_transmittance(m: &Material, n: DVec3, d: DVec3, len: f64) -> DVec3 {
    if !m.absorbs() || n.dot(d) <= 0.0 {
        return DVec3::ONE;
    }
    let sigma = m.absorption.as_dvec3();
    DVec3::new((-sigma.x * len).exp(), (-sigma.y * len).exp(), (-sigma.z * len).exp())
}
