//! Knob sweeps: `--sweep knob=v1,v2,…`, the variants they multiply out to (or one series
//! per sweep with `--each`), and which knobs are the frame's.

use crate::error::{Error, Result};
use crate::methods::Method;
use crate::quality::Quality;

/// One `--sweep knob=v1,v2,…`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub knob: String,
    pub values: Vec<String>,
}

impl Sweep {
    /// Parses `knob=v1,v2,…`; every value is checked against the knob's range now.
    pub fn parse(s: &str) -> Result<Sweep> {
        let (knob, values) = s.split_once('=').ok_or_else(|| Error::invalid("--sweep", format!("'{s}' is not knob=v1,v2,...")))?;
        let knob = knob.trim().to_string();
        // ref_point values contain commas themselves: split them on ';' instead.
        let sep = if knob == crate::quality::CubeKnobs::ref_point { ';' } else { ',' };
        let values: Vec<String> = values.split(sep).map(|v| v.trim().to_string()).filter(|v| !v.is_empty()).collect();
        if values.is_empty() {
            return Err(Error::invalid("--sweep", format!("'{s}' lists no values")));
        }
        for v in &values {
            Quality::default().set(&knob, v)?;
        }
        Ok(Sweep { knob, values })
    }
}

/// Every combination of the sweeps' values applied to `base` (the cartesian product, the
/// first sweep varying slowest), labelled `knob=value knob=value`; `base` alone, labelled
/// `default`, without sweeps.
pub fn variants(base: &Quality, sweeps: &[Sweep]) -> Result<Vec<(String, Quality)>> {
    let mut out = vec![(String::new(), base.clone())];
    for s in sweeps {
        let mut next = Vec::with_capacity(out.len() * s.values.len());
        for (label, q) in &out {
            for v in &s.values {
                let mut q = q.clone();
                q.set(&s.knob, v)?;
                let l = if label.is_empty() { format!("{}={v}", s.knob) } else { format!("{label} {}={v}", s.knob) };
                next.push((l, q));
            }
        }
        out = next;
    }
    if sweeps.is_empty() {
        out[0].0 = "default".into();
    }
    Ok(out)
}

/// One series of a study: the swept knob's name (`None`: every combination, or the
/// defaults) and its labelled variants.
pub type Series = (Option<String>, Vec<(String, Quality)>);

/// A knob no GPU method lists is the frame's (shadow maps, caustics, anti-aliasing): every
/// method's image may depend on it. (The CPU reference lists the ones it reads too.)
pub(super) fn frame_knob(k: &str) -> bool {
    !Method::ALL.iter().any(|m| m.is_gpu() && m.knobs.contains(&k))
}

/// The study's series: with `each`, one per sweep, its values applied to `base` one at a
/// time (the other knobs at `base`), named by the sweep's knob; else one unnamed series of
/// every combination ([`variants`]).
pub fn series(base: &Quality, sweeps: &[Sweep], each: bool) -> Result<Vec<Series>> {
    if !each || sweeps.is_empty() {
        return Ok(vec![(None, variants(base, sweeps)?)]);
    }
    sweeps.iter().map(|s| Ok((Some(s.knob.clone()), variants(base, std::slice::from_ref(s))?))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_sweep_is_a_series_of_its_own() {
        let s = [Sweep::parse("secant_steps=0,1").unwrap(), Sweep::parse("linear_steps=4,8,16").unwrap()];
        let base = {
            let mut knobs = Quality::default();
            knobs.search.linear_steps = 4;
            knobs.search.secant_steps = 0;
            knobs
        };
        let v = series(&base, &s, true).unwrap();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].0.as_deref(), Some("secant_steps"));
        assert_eq!(v[1].1.iter().map(|(l, _)| l.as_str()).collect::<Vec<_>>(), ["linear_steps=4", "linear_steps=8", "linear_steps=16"]);
        // The other knobs stay at the base.
        assert!(v[0].1.iter().all(|(_, q)| q.search.linear_steps == 4) && v[1].1.iter().all(|(_, q)| q.search.secant_steps == 0));
        assert_eq!(v[0].1[1].1.search.secant_steps, 1);
        let product = series(&base, &s, false).unwrap();
        assert_eq!((product.len(), product[0].0.clone(), product[0].1.len()), (1, None, 6));
    }

    #[test]
    fn sweeps_multiply_out() {
        let s = [Sweep::parse("cube_size=32,64").unwrap(), Sweep::parse("cube_precision=half,single").unwrap()];
        let v = variants(&Quality::default(), &s).unwrap();
        let labels: Vec<&str> = v.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(
            labels,
            [
                "cube_size=32 cube_precision=half",
                "cube_size=32 cube_precision=single",
                "cube_size=64 cube_precision=half",
                "cube_size=64 cube_precision=single"
            ]
        );
        assert_eq!(v[3].1.cube.cube_size, 64);
        assert_eq!(variants(&Quality::default(), &[]).unwrap()[0].0, "default");
        assert!(Sweep::parse("cube_size=8").is_err());
        assert!(Sweep::parse("nonsense=1").is_err());
        assert!(Sweep::parse("cube_size").is_err());
        assert_eq!(Sweep::parse("ref_point=auto;0,0,1").unwrap().values, ["auto", "0,0,1"]);
    }
}
