//! `tradeoff.csv`: one line per row, a column per error, Pareto membership and pass.

use std::fmt::Write as _;

use super::rows::{pareto_front, Metric, Row};

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `tradeoff.csv`: method, knobs, frame ms, the errors, Pareto membership in (frame ms,
/// mean FLIP) (`pareto`) and in (frame ms, PSNR) (`pareto_psnr`), the device and driver
/// that ran it, then one `<pass> ms` column per pass name any row has (empty where a row
/// has no such pass).
pub fn csv(rows: &[Row], device: &str) -> String {
    let mut pass_names: Vec<&str> = Vec::new();
    for r in rows {
        for (n, _) in &r.passes {
            if !pass_names.contains(&n.as_str()) {
                pass_names.push(n);
            }
        }
    }
    let front = |m: Metric| pareto_front(&rows.iter().map(|r| (r.frame_ms, m.cost(&r.errors))).collect::<Vec<_>>());
    let (flip_front, psnr_front) = (front(Metric::Flip), front(Metric::Psnr));
    let mut regions: Vec<&str> = Vec::new();
    for r in rows {
        for e in &r.regions {
            if !regions.contains(&e.name.as_str()) {
                regions.push(&e.name);
            }
        }
    }
    let mut s = String::from("method,knobs,frame_ms,rmse,psnr_db,flip_mean,p99_abs,max_abs,pareto,pareto_psnr,device");
    for n in &regions {
        let _ = write!(s, ",{}", csv_field(&format!("psnr_db[{n}]")));
    }
    for n in &pass_names {
        let _ = write!(s, ",{} ms", csv_field(n));
    }
    s.push('\n');
    for ((r, on_flip), on_psnr) in rows.iter().zip(flip_front).zip(psnr_front) {
        let e = &r.errors;
        let _ = write!(
            s,
            "{},{},{:.4},{:.6},{:.3},{:.6},{:.6},{:.6},{},{},{}",
            csv_field(&r.method),
            csv_field(&r.knobs),
            r.frame_ms,
            e.rmse,
            e.psnr,
            e.flip,
            e.p99_abs,
            e.max_abs,
            on_flip,
            on_psnr,
            csv_field(device)
        );
        for n in &regions {
            match r.regions.iter().find(|e| e.name == *n) {
                Some(e) => {
                    let _ = write!(s, ",{:.3}", e.psnr);
                }
                None => s.push(','),
            }
        }
        for n in &pass_names {
            match r.passes.iter().find(|(p, _)| p == n) {
                Some((_, ms)) => {
                    let _ = write!(s, ",{ms:.4}");
                }
                None => s.push(','),
            }
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::ImageErrors;

    fn errors(flip: f64) -> ImageErrors {
        ImageErrors { rmse: flip, psnr: 1.0, max_abs: flip, p99_abs: flip, flip }
    }

    #[test]
    fn csv_has_a_column_per_pass_and_quotes() {
        let t = |n: &str, ms| crate::vk::PassTiming { name: n.into(), gpu_ms: ms, cpu_ms: 0.0, gpu_start_ms: 0.0 };
        let rows = [
            Row::new("envmap", "cube_size=32", &[t("envmap.generate", 2.0), t("frame.readback", 9.0)], errors(0.1)),
            Row::new("envmap", "ref_point=0,0,1", &[t("scene.direct", 1.0)], errors(0.2)),
        ];
        assert_eq!(rows[0].frame_ms, 2.0, "readback is not the method's time");
        let s = csv(&rows, "llvmpipe, Mesa");
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(
            lines[0],
            "method,knobs,frame_ms,rmse,psnr_db,flip_mean,p99_abs,max_abs,pareto,pareto_psnr,device,envmap.generate ms,frame.readback ms,scene.direct ms"
        );
        // Both on the FLIP front; the second, faster at the same PSNR, alone on PSNR's.
        assert!(lines[1].starts_with("envmap,cube_size=32,2.0000,") && lines[1].ends_with(",true,false,\"llvmpipe, Mesa\",2.0000,9.0000,"));
        assert!(lines[2].starts_with("envmap,\"ref_point=0,0,1\",1.0000,") && lines[2].ends_with(",true,true,\"llvmpipe, Mesa\",,,1.0000"));
    }
}
