//! Weighted least squares with a ridge penalty, optionally non-negative (costs): cyclic
//! coordinate descent, which needs no matrix algebra and handles the constraint exactly.

/// Coefficients β minimising Σ wᵢ (yᵢ − xᵢ·β)² + ridge Σⱼ₌₁ ‖xⱼ‖²_w βⱼ² (the first column,
/// a bias or a per-object constant, is not penalised; the penalty scales with each column's
/// weighted norm, so it does not depend on the features' units). `nonneg`: every βⱼ ≥ 0.
pub fn fit(x: &[Vec<f64>], y: &[f64], w: &[f64], ridge: f64, nonneg: bool) -> Vec<f64> {
    let n = x.first().map_or(0, |r| r.len());
    let mut beta = vec![0.0; n];
    if x.is_empty() || n == 0 {
        return beta;
    }
    let norm: Vec<f64> = (0..n).map(|j| x.iter().zip(w).map(|(r, wi)| wi * r[j] * r[j]).sum()).collect();
    let mut resid: Vec<f64> = y.to_vec();
    for _ in 0..2000 {
        let mut change = 0.0f64;
        for j in 0..n {
            if norm[j] <= 0.0 {
                continue;
            }
            let rho: f64 = x.iter().zip(&resid).zip(w).map(|((r, e), wi)| wi * r[j] * (e + r[j] * beta[j])).sum();
            let penalty = if j == 0 { 0.0 } else { ridge * norm[j] };
            let mut b = rho / (norm[j] + penalty);
            if nonneg {
                b = b.max(0.0);
            }
            let d = b - beta[j];
            if d != 0.0 {
                x.iter().zip(resid.iter_mut()).for_each(|(r, e)| *e -= r[j] * d);
                beta[j] = b;
                change = change.max(d.abs() * norm[j].sqrt());
            }
        }
        if change < 1e-10 {
            break;
        }
    }
    beta
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_line_and_respects_the_sign_constraint() {
        let x: Vec<Vec<f64>> = (0..20).map(|i| vec![1.0, i as f64, (i * i) as f64 / 10.0]).collect();
        let y: Vec<f64> = x.iter().map(|r| 2.0 + 0.5 * r[1] - 0.3 * r[2]).collect();
        let w = vec![1.0; 20];
        let b = fit(&x, &y, &w, 0.0, false);
        assert!((b[0] - 2.0).abs() < 1e-6 && (b[1] - 0.5).abs() < 1e-6 && (b[2] + 0.3).abs() < 1e-6, "{b:?}");
        let b = fit(&x, &y, &w, 0.0, true);
        assert!(b.iter().all(|c| *c >= 0.0), "{b:?}");
        assert_eq!(b[2], 0.0);
    }
}
