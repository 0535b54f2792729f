//! Accuracy knobs. Each family declares its own in its folder with [`knob::knobs!`] (name,
//! values with range and unit, default, doc, parser and printer from one declaration);
//! `Quality` composes the families and `KNOBS` is their tables in order. The CLI
//! (`-q key=value`), the Rust API, the C ABI, `specula knobs`, `specula plan` and the
//! README test all go through that table. A knob means one thing: `depth` is the exact
//! renderers' recursion depth, `cycles` the inter-object map cycles of `distance-multi`.

pub mod knob;

pub use crate::frame::knobs::{Aa, DebugFault, FrameKnobs, FresnelMode};
pub use crate::methods::caustics::knobs::{CausticPaths, CausticSpace, Caustics, CausticsKnobs};
pub use crate::methods::cube_knobs::{CubeKnobs, CubeMode, Precision};
pub use crate::methods::distance::knobs::{DistanceKnobs, SearchKnobs};
pub use crate::methods::envmap::knobs::{CaptureBox, CaptureWarp, EnvmapKnobs, ReliefSource};
pub use crate::methods::geometry::knobs::GeometryKnobs;
pub use crate::methods::layered::knobs::{LayeredKnobs, MAX_LAYERS};
pub use crate::methods::raytrace::knobs::RaytraceKnobs;
pub use crate::plan::knobs::{PlanKnobs, Planner};
pub use crate::reference::knobs::ReferenceKnobs;
pub use knob::Knob;

use crate::error::{clip, Error, Result};

/// `Quality` with one field per family (serialised flat, as one struct of knobs), the
/// families' `Part` impls and the concatenated `KNOBS`.
macro_rules! compose {
    ($( $(#[doc = $doc:literal])* $field:ident: $T:ty, )*) => {
        #[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
        pub struct Quality {
            $( $(#[doc = $doc])* #[serde(flatten)] pub $field: $T, )*
        }

        $( impl knob::Part for $T {
            fn of(q: &Quality) -> &Self {
                &q.$field
            }
            fn of_mut(q: &mut Quality) -> &mut Self {
                &mut q.$field
            }
        } )*

        /// Every knob, family by family.
        pub const KNOBS: &[Knob] = &knob::concat::<{ 0 $(+ <$T>::KNOBS.len())* }>(&[$(<$T>::KNOBS),*]);
    };
}

compose! {
    /// Frame-wide: every method's frame reads these (shading, shadows, anti-aliasing, map
    /// updates, recursion depth, debug outputs).
    frame: FrameKnobs,
    /// Cube maps, shared by envmap, distance, layered and caustics.
    cube: CubeKnobs,
    /// The distance-map search (§4.1), shared by distance, layered and caustics.
    search: SearchKnobs,
    distance: DistanceKnobs,
    envmap: EnvmapKnobs,
    layered: LayeredKnobs,
    geometry: GeometryKnobs,
    raytrace: RaytraceKnobs,
    caustics: CausticsKnobs,
    reference: ReferenceKnobs,
    plan: PlanKnobs,
}

pub fn knob(name: &str) -> Option<&'static Knob> {
    KNOBS.iter().find(|k| k.name == name)
}

impl Quality {
    /// Sets one knob from its textual value.
    pub fn set(&mut self, key: &str, value: &str) -> Result<()> {
        let Some(k) = knob(key) else {
            let known: Vec<_> = KNOBS.iter().map(|k| k.name).collect();
            return Err(Error::invalid("knob", format!("unknown knob '{}' (known: {})", clip(key), known.join(", "))));
        };
        (k.set)(self, value.trim()).map_err(|m| Error::invalid(format!("knob {key}"), format!("{m} ({})", k.values)))
    }

    /// A knob's value in the form `set` accepts ("" for an unknown name).
    pub fn get(&self, key: &str) -> String {
        knob(key).map_or(String::new(), |k| (k.get)(self))
    }

    /// Parses `key=value`.
    pub fn set_pair(&mut self, pair: &str) -> Result<()> {
        let (k, v) = pair.split_once('=').ok_or_else(|| Error::invalid("knob", format!("'{}' is not key=value", clip(pair))))?;
        self.set(k.trim(), v.trim())
    }
}

#[cfg(test)]
mod tests {
    use super::knob::Range;
    use super::*;
    use glam::Vec3;

    #[test]
    fn knobs_parse_and_reject() {
        let mut q = Quality::default();
        q.set_pair("cube_size=128").unwrap();
        q.set_pair("fresnel=exact").unwrap();
        q.set_pair("ref_point=1,2,3").unwrap();
        assert_eq!((q.cube.cube_size, q.frame.fresnel, q.cube.ref_point), (128, FresnelMode::Exact, Some(Vec3::new(1.0, 2.0, 3.0))));
        assert!(q.set_pair("cube_size=8").is_err());
        assert!(q.set_pair("cube_size=abc").is_err());
        assert!(q.set_pair("ref_point=1,nan,3").is_err());
        assert!(q.set_pair("warp=9").is_err());
        assert!(q.set_pair("cube_size").is_err());
        q.set_pair("depth=1").unwrap();
        q.set_pair("spp=9").unwrap();
        q.set_pair("cycles=3").unwrap();
        assert_eq!((q.frame.depth, q.reference.spp, q.distance.cycles), (1, 9, 3));
        for bad in ["depth=0", "depth=65", "spp=8", "spp=0", "spp=2048", "spp=x", "cycles=0", "cycles=17", "planner=fast"] {
            assert!(q.set_pair(bad).is_err(), "{bad}");
        }
        for k in KNOBS {
            let mut q = Quality::default();
            q.set(k.name, k.default).unwrap();
            assert_eq!(q, Quality::default(), "documented default of {} is the real default", k.name);
            assert_eq!(Quality::default().get(k.name), k.default, "get() of {} prints the documented default", k.name);
        }
    }

    /// Every knob's range, from its one declaration: both ends parse and print back, just
    /// outside them does not, and the default lies inside.
    #[test]
    fn knob_ranges() {
        let names: Vec<_> = KNOBS.iter().map(|k| k.name).collect();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[..i].contains(n), "knob {n} is declared twice");
        }
        for k in KNOBS {
            let ok = |v: &str| {
                let mut q = Quality::default();
                q.set(k.name, v).map(|()| q.get(k.name))
            };
            let accepts = |v: &str| assert_eq!(ok(v).unwrap_or_else(|e| panic!("{}={v}: {e}", k.name)), v, "{}={v} prints back", k.name);
            let rejects = |v: &str| assert!(ok(v).is_err(), "{}={v} is outside {}", k.name, k.values);
            let auto = matches!(k.range, Range::AutoCount(..) | Range::AutoPositive | Range::AutoPoint);
            if auto {
                accepts("auto");
            }
            match k.range {
                Range::Count(lo, hi) | Range::AutoCount(lo, hi) => {
                    [lo, hi].into_iter().for_each(|v| accepts(&v.to_string()));
                    [lo as i64 - 1, hi as i64 + 1].into_iter().for_each(|v| rejects(&v.to_string()));
                    let d: u32 = if auto && k.default == "auto" { lo } else { k.default.parse().unwrap() };
                    assert!((lo..=hi).contains(&d), "default of {}", k.name);
                }
                Range::Square(hi) => {
                    [1, 4, hi].into_iter().for_each(|v| accepts(&v.to_string()));
                    [0, 2, hi + 1].into_iter().for_each(|v| rejects(&v.to_string()));
                    let d: u32 = k.default.parse().unwrap();
                    assert!(d <= hi && d.isqrt().pow(2) == d, "default of {}", k.name);
                }
                Range::Real(lo, hi) => {
                    [lo, hi].into_iter().for_each(|v| accepts(&v.to_string()));
                    let eps = (hi - lo) * 1e-3;
                    [lo - eps, hi + eps, f32::NAN, f32::INFINITY].into_iter().for_each(|v| rejects(&v.to_string()));
                    assert!((lo..=hi).contains(&k.default.parse::<f32>().unwrap()), "default of {}", k.name);
                }
                Range::Options(names) => {
                    names.iter().for_each(|v| accepts(v));
                    rejects("bogus");
                    assert!(names.contains(&k.default), "default of {}", k.name);
                }
                Range::AutoPositive => {
                    accepts("0.25");
                    ["0", "-1", "inf"].into_iter().for_each(rejects);
                }
                Range::AutoPoint => {
                    accepts("1,-2,0.5");
                    ["1,2", "1,2,x"].into_iter().for_each(rejects);
                }
            }
        }
        assert_eq!(MAX_LAYERS, 16);
    }

    #[test]
    fn messages_name_the_range() {
        let mut q = Quality::default();
        let e = q.set("linear_steps", "-32").unwrap_err().to_string();
        assert!(e.contains("-32 is outside 0..=256"), "{e}");
        let e = q.set("search_tolerance", "NaN").unwrap_err().to_string();
        assert!(e.contains("NaN is not a number in 0..=1"), "{e}");
        let long = "9".repeat(100_000);
        assert!(q.set("cube_size", &long).unwrap_err().to_string().len() < 300);
    }
}
