//! The study's data: one row per measured configuration, the metric it ranks by, the
//! Pareto front of (time, error) and the figure's panels (the whole image, each specular
//! object).

use crate::error::{Error, Result};
use crate::metrics::ImageErrors;

/// One measured configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub method: String,
    pub knobs: String,
    /// Median GPU ms per pass, in frame order.
    pub passes: Vec<(String, f64)>,
    /// Sum of the passes except `frame.readback` (the standalone copy to the host).
    pub frame_ms: f64,
    pub errors: ImageErrors,
    /// The error where the method acts (issue 15): per specular object, on all specular
    /// pixels and on the rest (`metrics::errors_by_object`); empty where not measured.
    pub regions: Vec<crate::metrics::MaskedError>,
}

impl Row {
    pub fn new(method: &str, knobs: &str, passes: &[crate::vk::PassTiming], errors: ImageErrors) -> Row {
        let passes: Vec<(String, f64)> = passes.iter().map(|p| (p.name.clone(), p.gpu_ms)).collect();
        let frame_ms = passes.iter().filter(|(n, _)| n != "frame.readback").map(|(_, ms)| ms).sum();
        Row { method: method.into(), knobs: knobs.into(), passes, frame_ms, errors, regions: Vec::new() }
    }
}

/// The figure's panels: the whole image, and with PSNR, one panel per specular object (its
/// rows' PSNR and RMSE those of its pixels; FLIP is per image only): where the method acts.
pub fn region_panels(rows: &[Row], metric: Metric) -> Vec<Panel> {
    let mut panels = vec![Panel { name: "whole image".into(), rows: rows.to_vec() }];
    let objects: Vec<String> = rows
        .first()
        .map(|r| r.regions.iter().map(|e| e.name.clone()).filter(|n| n != "specular" && n != "non-specular").collect())
        .unwrap_or_default();
    if metric != Metric::Psnr || objects.is_empty() {
        return panels;
    }
    for name in objects {
        let rows: Vec<Row> = rows
            .iter()
            .filter_map(|r| {
                let e = r.regions.iter().find(|e| e.name == name)?;
                let mut r = r.clone();
                r.errors = ImageErrors { rmse: e.rmse, psnr: e.psnr, flip: f64::NAN, ..r.errors };
                Some(r)
            })
            .collect();
        panels.push(Panel { name: format!("{name} (its pixels)"), rows });
    }
    panels
}

/// Which of the points (time, cost) are Pareto-optimal, the cost lower-is-better (see
/// [`Metric::cost`]): no other point is at least as fast and at least as accurate and
/// strictly better in one of the two. NaN never is.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(t, e)| !t.is_nan() && !e.is_nan() && !points.iter().any(|&(t2, e2)| t2 <= t && e2 <= e && (t2 < t || e2 < e)))
        .collect()
}

/// The error the study plots and ranks by (`specula tradeoff --metric`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Metric {
    /// PSNR against the reference in dB (peak 1): higher is better.
    #[default]
    Psnr,
    /// Mean FLIP against the reference, in [0, 1]: lower is better.
    Flip,
}

impl Metric {
    /// `psnr` or `flip` (any case).
    pub fn parse(s: &str) -> Result<Metric> {
        match s.trim().to_ascii_lowercase().as_str() {
            "psnr" => Ok(Metric::Psnr),
            "flip" => Ok(Metric::Flip),
            _ => Err(Error::invalid("--metric", format!("'{s}' is neither psnr nor flip"))),
        }
    }

    /// Its name in titles: `PSNR` or `mean FLIP`.
    pub fn name(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR",
            Metric::Flip => "mean FLIP",
        }
    }

    pub fn value(self, e: &ImageErrors) -> f64 {
        match self {
            Metric::Psnr => e.psnr,
            Metric::Flip => e.flip,
        }
    }

    pub fn higher_is_better(self) -> bool {
        self == Metric::Psnr
    }

    /// The value as a cost, lower is better: what [`pareto_front`] minimises.
    pub fn cost(self, e: &ImageErrors) -> f64 {
        if self.higher_is_better() {
            -self.value(e)
        } else {
            self.value(e)
        }
    }

    pub(super) fn axis_label(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR vs reference [dB]  (higher is better)",
            Metric::Flip => "mean FLIP vs reference  (lower is better)",
        }
    }
}

/// One panel of the trade-off figure: what its rows measure (the whole image, or one
/// specular object) and the rows.
#[derive(Clone, Debug)]
pub struct Panel {
    pub name: String,
    pub rows: Vec<Row>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_the_undominated() {
        let pts = [(1.0, 0.5), (2.0, 0.2), (3.0, 0.3), (0.5, 0.9), (2.0, 0.2), (f64::NAN, 0.0)];
        assert_eq!(pareto_front(&pts), [true, true, false, true, true, false]);
    }

    #[test]
    fn metric_parses_and_ranks() {
        assert_eq!(Metric::parse("PSNR").unwrap(), Metric::Psnr);
        assert_eq!(Metric::parse("flip").unwrap(), Metric::Flip);
        assert!(Metric::parse("rmse").is_err());
        assert_eq!(Metric::default(), Metric::Psnr);
        let e = ImageErrors { rmse: 0.1, psnr: 20.0, max_abs: 0.5, p99_abs: 0.3, flip: 0.2 };
        assert_eq!((Metric::Psnr.cost(&e), Metric::Flip.cost(&e)), (-20.0, 0.2));
    }
}
