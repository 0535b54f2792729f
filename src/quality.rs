//! Accuracy knobs. Each knob is written once here: name, unit, range, default and what it
//! does; the CLI (`--quality key=value`), the Rust API and the C ABI all go through
//! `Quality::set`.

use glam::Vec3;

use crate::error::{Error, Result};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum FresnelMode {
    /// Schlick's approximation with F0 from ν, κ (survey eq. 2).
    Schlick,
    /// The exact Fresnel equations for dielectrics and conductors.
    Exact,
}

/// How the six faces of a cube map are rasterised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CubeMode {
    /// One render pass per face.
    SixPasses,
    /// All six faces in one pass with multiview (view mask 0x3F).
    Multiview,
}

/// Storage precision of radiance cube maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Precision {
    Half,
    Single,
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    pub cube_size: u32,
    pub cube_precision: Precision,
    pub cube_mode: CubeMode,
    pub fresnel: FresnelMode,
    /// Overrides every specular object's reference point (world space, metres).
    pub ref_point: Option<Vec3>,
    pub shadow_size: u32,
    /// Specular recursion depth R (survey Table 1): the reference renderer's bounces, and
    /// the map cycles of inter-object reflections (`distance-multi`, §4.3).
    pub depth: u32,
    /// Reference renderer: samples per pixel, a k×k stratified grid (k² = spp).
    pub spp: u32,
    /// Distance-map search (§4.1): linear steps (0: parallax correction only).
    pub linear_steps: u32,
    pub secant_steps: u32,
    pub binary_steps: u32,
    pub parallax_iterations: u32,
    /// Early exit once | |l|/|l'| − 1 | ≤ this.
    pub search_tolerance: f32,
    /// Self refraction (§4.4): internal reflections followed inside a refractor.
    pub internal_bounces: u32,
    /// Inter-object reflections (§4.3): one map cycle per frame, reusing the last frame's.
    pub frame_latency: bool,
    /// Proxy sphere radius of `proxy-sphere` (§3.2), metres; `None`: the mean half-extent
    /// of the scene's bounding box.
    pub proxy_radius: Option<f32>,
}

/// A knob's documentation: one line each, shown by `specula knobs`.
pub struct Knob {
    pub name: &'static str,
    pub values: &'static str,
    pub default: &'static str,
    pub doc: &'static str,
}

pub const KNOBS: &[Knob] = &[
    Knob { name: "cube_size", values: "16..=4096 texels", default: "256", doc: "edge of each face of an object's cube maps (environment, distance, refractor)" },
    Knob { name: "cube_precision", values: "half|single", default: "half", doc: "cube-map storage (radiance and distance): RGBA16F or RGBA32F" },
    Knob {
        name: "cube_mode",
        values: "six|multiview",
        default: "six",
        doc: "cube faces in six passes or one multiview pass (equal speed on lavapipe, six needs less depth memory: BENCHMARKS.md)",
    },
    Knob {
        name: "fresnel",
        values: "schlick|exact",
        default: "schlick",
        doc: "Schlick's approximation (survey eq. 2) or the exact Fresnel equations",
    },
    Knob {
        name: "ref_point",
        values: "auto|x,y,z (metres)",
        default: "auto",
        doc: "reference point of every specular object's maps; auto = its bounding-box centre",
    },
    Knob { name: "shadow_size", values: "16..=4096 texels", default: "512", doc: "edge of each shadow distance map face" },
    Knob {
        name: "depth",
        values: "1..=64 bounces",
        default: "4",
        doc: "specular recursion depth R: the reference's bounces (paths still specular after R end black); distance-multi's map cycles (§4.3)",
    },
    Knob {
        name: "spp",
        values: "1, 4, 9, ..., 1024",
        default: "16",
        doc: "reference: samples per pixel on a k×k stratified grid (a perfect square; 1 = pixel centre)",
    },
    Knob {
        name: "linear_steps",
        values: "0..=256",
        default: "16",
        doc: "distance-map linear search steps (§4.1.2); 0: parallax correction only",
    },
    Knob {
        name: "secant_steps",
        values: "0..=64",
        default: "2",
        doc: "secant (false position) refinement steps after the linear search (survey eq. 5)",
    },
    Knob { name: "binary_steps", values: "0..=64", default: "0", doc: "binary refinement steps after the linear search (§4.1.4)" },
    Knob {
        name: "parallax_iterations",
        values: "1..=64",
        default: "1",
        doc: "parallax-correction iterations (survey eq. 4) when linear_steps = 0",
    },
    Knob { name: "search_tolerance", values: "0..=1", default: "0.001", doc: "search stops once | |l|/|l'| − 1 | is within this" },
    Knob {
        name: "internal_bounces",
        values: "0..=16",
        default: "2",
        doc: "refractor-map: total internal reflections followed inside a refractor (§4.4)",
    },
    Knob {
        name: "frame_latency",
        values: "on|off",
        default: "off",
        doc: "distance-multi: one map cycle per frame reusing the previous frame's maps (§4.3)",
    },
    Knob {
        name: "proxy_radius",
        values: "auto|metres",
        default: "auto",
        doc: "proxy-sphere radius (§3.2); auto: mean half-extent of the scene's box",
    },
];

impl Default for Quality {
    fn default() -> Self {
        Quality {
            cube_size: 256,
            cube_precision: Precision::Half,
            cube_mode: CubeMode::SixPasses,
            fresnel: FresnelMode::Schlick,
            ref_point: None,
            shadow_size: 512,
            depth: 4,
            spp: 16,
            linear_steps: 16,
            secant_steps: 2,
            binary_steps: 0,
            parallax_iterations: 1,
            search_tolerance: 1e-3,
            internal_bounces: 2,
            frame_latency: false,
            proxy_radius: None,
        }
    }
}

fn parse_count(key: &str, v: &str, lo: u32, hi: u32) -> Result<u32> {
    match v.parse::<u32>() {
        Ok(n) if (lo..=hi).contains(&n) => Ok(n),
        _ => Err(Error::invalid(format!("knob {key}"), format!("'{v}' is not a whole number in {lo}..={hi}"))),
    }
}

fn parse_size(key: &str, v: &str) -> Result<u32> {
    let n: u32 = v.parse().map_err(|_| Error::invalid(format!("knob {key}"), format!("'{v}' is not a whole number")))?;
    if !(16..=4096).contains(&n) {
        return Err(Error::invalid(format!("knob {key}"), format!("{n} is outside 16..=4096")));
    }
    Ok(n)
}

impl Quality {
    /// Sets one knob from its textual value.
    pub fn set(&mut self, key: &str, value: &str) -> Result<()> {
        let bad = |expected: &str| Error::invalid(format!("knob {key}"), format!("'{value}' is not one of {expected}"));
        match key {
            "cube_size" => self.cube_size = parse_size(key, value)?,
            "shadow_size" => self.shadow_size = parse_size(key, value)?,
            "depth" => {
                self.depth = match value.parse::<u32>() {
                    Ok(n) if (1..=64).contains(&n) => n,
                    _ => return Err(bad("1..=64")),
                }
            }
            "spp" => {
                self.spp = match value.parse::<u32>() {
                    Ok(n) if (1..=1024).contains(&n) && n.isqrt().pow(2) == n => n,
                    _ => return Err(bad("the perfect squares 1, 4, 9, ..., 1024")),
                }
            }
            "linear_steps" => self.linear_steps = parse_count(key, value, 0, 256)?,
            "secant_steps" => self.secant_steps = parse_count(key, value, 0, 64)?,
            "binary_steps" => self.binary_steps = parse_count(key, value, 0, 64)?,
            "parallax_iterations" => self.parallax_iterations = parse_count(key, value, 1, 64)?,
            "internal_bounces" => self.internal_bounces = parse_count(key, value, 0, 16)?,
            "search_tolerance" => {
                self.search_tolerance = match value.parse::<f32>() {
                    Ok(t) if (0.0..=1.0).contains(&t) => t,
                    _ => return Err(bad("a number in 0..=1")),
                }
            }
            "frame_latency" => {
                self.frame_latency = match value {
                    "on" => true,
                    "off" => false,
                    _ => return Err(bad("on|off")),
                }
            }
            "proxy_radius" => {
                self.proxy_radius = match value {
                    "auto" => None,
                    v => match v.parse::<f32>() {
                        Ok(r) if r > 0.0 && r.is_finite() => Some(r),
                        _ => return Err(bad("auto|a radius > 0 in metres")),
                    },
                }
            }
            "cube_precision" => {
                self.cube_precision = match value {
                    "half" => Precision::Half,
                    "single" => Precision::Single,
                    _ => return Err(bad("half|single")),
                }
            }
            "cube_mode" => {
                self.cube_mode = match value {
                    "six" => CubeMode::SixPasses,
                    "multiview" => CubeMode::Multiview,
                    _ => return Err(bad("six|multiview")),
                }
            }
            "fresnel" => {
                self.fresnel = match value {
                    "schlick" => FresnelMode::Schlick,
                    "exact" => FresnelMode::Exact,
                    _ => return Err(bad("schlick|exact")),
                }
            }
            "ref_point" => {
                self.ref_point = if value == "auto" {
                    None
                } else {
                    let v: Vec<f32> = value
                        .split(',')
                        .map(|s| s.trim().parse::<f32>())
                        .collect::<std::result::Result<_, _>>()
                        .map_err(|_| bad("auto|x,y,z"))?;
                    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
                        return Err(bad("auto|x,y,z with three finite numbers"));
                    }
                    Some(Vec3::new(v[0], v[1], v[2]))
                }
            }
            _ => {
                let known: Vec<_> = KNOBS.iter().map(|k| k.name).collect();
                return Err(Error::invalid("knob", format!("unknown knob '{key}' (known: {})", known.join(", "))));
            }
        }
        Ok(())
    }

    /// Parses `key=value`.
    pub fn set_pair(&mut self, pair: &str) -> Result<()> {
        let (k, v) = pair.split_once('=').ok_or_else(|| Error::invalid("knob", format!("'{pair}' is not key=value")))?;
        self.set(k.trim(), v.trim())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knobs_parse_and_reject() {
        let mut q = Quality::default();
        q.set_pair("cube_size=128").unwrap();
        q.set_pair("fresnel=exact").unwrap();
        q.set_pair("ref_point=1,2,3").unwrap();
        assert_eq!((q.cube_size, q.fresnel, q.ref_point), (128, FresnelMode::Exact, Some(Vec3::new(1.0, 2.0, 3.0))));
        assert!(q.set_pair("cube_size=8").is_err());
        assert!(q.set_pair("cube_size=abc").is_err());
        assert!(q.set_pair("ref_point=1,nan,3").is_err());
        assert!(q.set_pair("warp=9").is_err());
        assert!(q.set_pair("cube_size").is_err());
        q.set_pair("depth=1").unwrap();
        q.set_pair("spp=9").unwrap();
        assert_eq!((q.depth, q.spp), (1, 9));
        for bad in ["depth=0", "depth=65", "spp=8", "spp=0", "spp=2048", "spp=x"] {
            assert!(q.set_pair(bad).is_err(), "{bad}");
        }
        for k in KNOBS {
            let mut q = Quality::default();
            q.set(k.name, k.default).unwrap();
            assert_eq!(q, Quality::default(), "documented default of {} is the real default", k.name);
        }
    }
}
