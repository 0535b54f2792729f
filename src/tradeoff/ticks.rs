//! The figure's axes: log-axis ticks and tick labels.

/// Labelled ticks of a log axis over `lo..hi`: 1-2-5 per decade (1 alone over many
/// decades, 1 to 9 over a few), at least four; linear steps of 1, 2 or 5 × 10^k over a
/// range too narrow for that.
pub(super) fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let per_decade = |mults: &[f64]| {
        let mut v = Vec::new();
        let mut p = 10f64.powf(lo.log10().floor());
        while p <= hi {
            v.extend(mults.iter().map(|m| m * p).filter(|x| (lo..=hi).contains(x)));
            p *= 10.0;
        }
        v
    };
    for mults in [&[1.0][..], &[1.0, 2.0, 5.0], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]] {
        let v = per_decade(mults);
        if (4..=12).contains(&v.len()) {
            return v;
        }
    }
    let rough = (hi - lo) / 5.0;
    let mag = 10f64.powf(rough.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= rough).unwrap_or(10.0 * mag);
    ((lo / step).ceil() as i64..=(hi / step).floor() as i64).map(|i| i as f64 * step).collect()
}

/// The grid's light lines on a log axis: 1 to 9 × 10^k.
pub(super) fn minor_log_ticks(r: std::ops::Range<f64>) -> Vec<f64> {
    let mut v = Vec::new();
    if !(r.start > 0.0 && r.end > r.start && r.end.is_finite()) {
        return v;
    }
    let mut p = 10f64.powf(r.start.log10().floor());
    while p <= r.end {
        v.extend((1..10).map(|m| m as f64 * p).filter(|x| r.contains(x)));
        p *= 10.0;
    }
    v
}

/// A tick label: a few significant digits, no trailing zeros.
pub(super) fn fmt_num(v: f64) -> String {
    let a = v.abs();
    let s = if a >= 100.0 {
        format!("{v:.0}")
    } else if a >= 10.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.2}")
    } else if a >= 0.001 || a == 0.0 {
        format!("{v:.4}")
    } else {
        return format!("{v:.1e}");
    };
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_axis_ticks_fit_the_range() {
        assert_eq!(log_ticks(0.5, 2000.0), [1.0, 10.0, 100.0, 1000.0]);
        assert_eq!(log_ticks(0.7, 30.0), [1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(log_ticks(1.5, 9.5), [2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        let narrow = log_ticks(2.3, 4.1);
        assert!(narrow.len() >= 4 && narrow.iter().all(|t| (2.3..=4.1).contains(t)), "{narrow:?}");
        let minor = minor_log_ticks(0.5..3.0);
        assert_eq!(minor.len(), 7, "{minor:?}");
        assert!(minor.iter().zip([0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 2.0]).all(|(a, b)| (a - b).abs() < 1e-12), "{minor:?}");
        assert_eq!(
            (fmt_num(0.30000000000000004), fmt_num(12.0), fmt_num(24.5), fmt_num(0.0002)),
            ("0.3".into(), "12".into(), "24.5".into(), "2.0e-4".into())
        );
    }
}
