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
    /// Reference renderer: maximum number of specular bounces R followed (survey Table 1).
    pub depth: u32,
    /// Reference renderer: samples per pixel, a k×k stratified grid (k² = spp).
    pub spp: u32,
}

/// A knob's documentation: one line each, shown by `specula knobs`.
pub struct Knob {
    pub name: &'static str,
    pub values: &'static str,
    pub default: &'static str,
    pub doc: &'static str,
}

pub const KNOBS: &[Knob] = &[
    Knob { name: "cube_size", values: "16..=4096 texels", default: "256", doc: "edge of each face of an object's environment cube map" },
    Knob { name: "cube_precision", values: "half|single", default: "half", doc: "radiance cube-map storage: RGBA16F or RGBA32F" },
    Knob {
        name: "cube_mode",
        values: "six|multiview",
        default: "six",
        doc: "cube faces in six passes or one multiview pass (six measured faster on lavapipe, BENCHMARKS.md)",
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
        default: "8",
        doc: "reference: specular recursion depth R; paths still specular after R bounces end black",
    },
    Knob {
        name: "spp",
        values: "1, 4, 9, ..., 1024",
        default: "16",
        doc: "reference: samples per pixel on a k×k stratified grid (a perfect square; 1 = pixel centre)",
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
            depth: 8,
            spp: 16,
        }
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
