//! Models: their format, the stored defaults, reading, writing and merging them.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::Cost;
use crate::error::{Error, Result};
use crate::plan::ids::Method;
use crate::quality::Quality;

/// The first line of every models file's `format` field.
pub const FORMAT: &str = "specula-models 1";
/// PSNR is stored capped here (an exact method's infinite PSNR does not fit JSON).
pub const PSNR_CAP: f64 = 200.0;

/// One object with one method in one variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectModel {
    /// The object's (mesh) name.
    pub object: String,
    /// `ObjectClass::label`.
    pub class: String,
    /// Its pixels in the calibration frame (the reference's first hits).
    pub pixels: usize,
    pub method: String,
    /// Its share of the per-object passes.
    pub cost: Cost,
    /// Its method's shared kernels, whole (a camera pass that declares them shared:
    /// `Profiled::shared`).
    #[serde(default)]
    pub shared: Cost,
    /// Inter-object cycles of the calibration frame (its maps' share covers that many).
    #[serde(default = "one")]
    pub cycles: u32,
    /// The whole-scene method of the calibration row (`method` where it served the object,
    /// else that method's fallback is `method`).
    #[serde(default)]
    pub row: String,
    /// PSNR on its own pixels, capped at [`PSNR_CAP`].
    pub psnr_db: f64,
    /// How far its method's cost model under-predicts a frame (`MethodCost::under`; 1 for
    /// a measured row): a frame-time budget counts its time times this.
    #[serde(default = "unit")]
    pub under: f64,
}

fn unit() -> f64 {
    1.0
}

fn one() -> u32 {
    1
}

/// One knob variant of the calibration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariantModel {
    /// `default`, or `knob=value knob=value` applied over the base knobs.
    pub knobs: String,
    /// What belongs to no object (median over the variant's rows).
    pub base: Cost,
    /// Each whole-scene row's own base (a row predicts exactly its measured frame).
    #[serde(default)]
    pub row_bases: Vec<RowBase>,
    pub objects: Vec<ObjectModel>,
}

/// One calibration row's base.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RowBase {
    pub row: String,
    pub base: Cost,
}

/// Per-object error and cost models of a scene (or, as stored defaults, of a few scenes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Models {
    pub format: String,
    /// Where they were measured (a scene name, or several joined by `+`).
    pub scene: String,
    pub device: String,
    /// The calibration frames' size.
    pub size: [u32; 2],
    pub variants: Vec<VariantModel>,
}

impl Models {
    pub fn parse(text: &str, what: &str) -> Result<Models> {
        let m: Models = serde_json::from_str(text).map_err(|e| Error::invalid(what.to_string(), format!("not a models file: {e}")))?;
        if m.format != FORMAT {
            return Err(Error::invalid(format!("{what} format"), format!("'{}', expected '{FORMAT}'", crate::error::clip(&m.format))));
        }
        for v in &m.variants {
            variant_quality(&Quality::default(), &v.knobs).map_err(|e| Error::invalid(format!("{what} knobs"), e.to_string()))?;
            for o in &v.objects {
                Method::parse(&o.method).map_err(|e| Error::invalid(format!("{what} object '{}' method", o.object), e.to_string()))?;
                let costs = [o.cost.fixed_ms, o.cost.screen_ms, o.shared.fixed_ms, o.shared.screen_ms];
                let finite = costs.iter().chain([&o.psnr_db]).all(|x| x.is_finite());
                if !finite || costs.iter().any(|c| *c < 0.0) || o.cycles == 0 {
                    return Err(Error::invalid(
                        format!("{what} object '{}'", o.object),
                        format!(
                            "costs {:?} {:?} and PSNR {} must be finite and non-negative, cycles {} at least 1",
                            o.cost, o.shared, o.psnr_db, o.cycles
                        ),
                    ));
                }
            }
        }
        if m.size[0] == 0 || m.size[1] == 0 {
            return Err(Error::invalid(format!("{what} size"), format!("{:?} is empty", m.size)));
        }
        Ok(m)
    }

    pub fn load(path: &Path) -> Result<Models> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Models::parse(&text, &path.display().to_string())
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Several scenes' models as one: variants with the same knobs join (objects appended,
    /// base averaged); screen costs are rescaled to the first one's size.
    pub fn merge(all: Vec<Models>) -> Models {
        let mut it = all.into_iter();
        let Some(mut out) = it.next() else {
            return Models { format: FORMAT.into(), scene: String::new(), device: String::new(), size: [1, 1], variants: Vec::new() };
        };
        let px = (out.size[0] * out.size[1]) as f64;
        let mut counts: Vec<f64> = vec![1.0; out.variants.len()];
        for m in it {
            let scale = px / (m.size[0] * m.size[1]) as f64;
            out.scene = format!("{}+{}", out.scene, m.scene);
            for mut v in m.variants {
                v.base.screen_ms *= scale;
                v.row_bases.iter_mut().for_each(|b| b.base.screen_ms *= scale);
                for o in &mut v.objects {
                    o.cost.screen_ms *= scale;
                    o.shared.screen_ms *= scale;
                    o.pixels = (o.pixels as f64 * scale).round() as usize;
                }
                match out.variants.iter().position(|w| w.knobs == v.knobs) {
                    Some(k) => {
                        let n = counts[k];
                        let b = &mut out.variants[k].base;
                        b.fixed_ms = (b.fixed_ms * n + v.base.fixed_ms) / (n + 1.0);
                        b.screen_ms = (b.screen_ms * n + v.base.screen_ms) / (n + 1.0);
                        counts[k] += 1.0;
                        out.variants[k].objects.extend(v.objects);
                        // Rows of several scenes: their bases differ; the variant's mean serves.
                        out.variants[k].row_bases.clear();
                    }
                    None => {
                        out.variants.push(v);
                        counts.push(1.0);
                    }
                }
            }
        }
        out
    }
}

/// `base` with a variant's knobs applied.
pub fn variant_quality(base: &Quality, knobs: &str) -> Result<Quality> {
    let mut q = base.clone();
    if knobs != "default" {
        for pair in knobs.split_whitespace() {
            q.set_pair(pair)?;
        }
    }
    Ok(q)
}

pub(crate) fn mse_of(psnr: f64) -> f64 {
    10f64.powf(-psnr.min(PSNR_CAP) / 10.0)
}

pub(crate) fn psnr_of(mse: f64) -> f64 {
    if mse > 0.0 {
        (-10.0 * mse.log10()).min(PSNR_CAP)
    } else {
        PSNR_CAP
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_joins_variants_and_rescales_screen_costs() {
        let obj = |name: &str, screen| ObjectModel {
            object: name.into(),
            class: "mirror".into(),
            pixels: 10,
            method: "envmap".into(),
            cost: Cost { fixed_ms: 1.0, screen_ms: screen },
            shared: Cost::default(),
            cycles: 1,
            row: "envmap".into(),
            psnr_db: 30.0,
            under: 1.0,
        };
        let m = |size: u32, screen| Models {
            format: FORMAT.into(),
            scene: format!("s{size}"),
            device: String::new(),
            size: [size, size],
            variants: vec![VariantModel {
                knobs: "default".into(),
                base: Cost { fixed_ms: 2.0, screen_ms: screen },
                row_bases: Vec::new(),
                objects: vec![obj("a", screen)],
            }],
        };
        let joined = Models::merge(vec![m(10, 1.0), m(20, 4.0)]);
        assert_eq!(joined.scene, "s10+s20");
        assert_eq!(joined.variants.len(), 1);
        let v = &joined.variants[0];
        assert_eq!(v.objects.len(), 2);
        // 20² → 10²: a quarter of the pixels, a quarter of the screen time.
        assert_eq!((v.objects[1].cost.screen_ms, v.objects[1].pixels), (1.0, 3));
        assert_eq!(v.base, Cost { fixed_ms: 2.0, screen_ms: 1.0 });
        assert_eq!(Cost { fixed_ms: 1.0, screen_ms: 2.0 }.at(200.0, 100.0), 5.0);
    }
}
