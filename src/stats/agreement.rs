//! Agreement between two measurement methods: Pearson correlation (thesis 4.4.1) with its
//! t-test p-value and Fisher-z confidence interval, and Bland-Altman analysis (Bland &
//! Altman 1986; thesis 4.4.2): bias, limits of agreement `bias +- 1.96 s` with the sample
//! standard deviation (ddof = 1), the standard error of the bias `s / sqrt(n)` and of each
//! limit `sqrt(3 s^2 / n)` (Bland & Altman 1986, section 5), and the share of points
//! outside the limits.

use super::special::{normal_quantile, t_quantile, t_sf_two_sided};
use crate::{Error, Result};
use serde::Serialize;

/// Pearson correlation with its inference.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Pearson {
    /// Correlation coefficient r.
    pub r: f64,
    /// Number of pairs.
    pub n: usize,
    /// Two-sided p-value of H0: rho = 0 (t = r sqrt((n - 2) / (1 - r^2)), n - 2 df).
    pub p_value: f64,
    /// Lower bound of the 95 % confidence interval (Fisher z).
    pub ci_low: f64,
    /// Upper bound of the 95 % confidence interval (Fisher z).
    pub ci_high: f64,
}

fn check_pairs(a: &[f64], b: &[f64], min: usize) -> Result<()> {
    if a.len() != b.len() {
        return Err(Error::invalid(
            "paired series lengths",
            format!("{} and {}", a.len(), b.len()),
            "equal",
        ));
    }
    if a.len() < min {
        return Err(Error::invalid(
            "number of pairs",
            a.len(),
            format!("at least {min}"),
        ));
    }
    Ok(())
}

/// Pearson correlation of paired samples (at least 3 pairs, neither series constant).
pub fn pearson(a: &[f64], b: &[f64]) -> Result<Pearson> {
    check_pairs(a, b, 3)?;
    let n = a.len();
    let nf = n as f64;
    let ma = a.iter().sum::<f64>() / nf;
    let mb = b.iter().sum::<f64>() / nf;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (x - ma, y - mb);
        sab += dx * dy;
        saa += dx * dx;
        sbb += dy * dy;
    }
    if saa == 0.0 || sbb == 0.0 {
        return Err(Error::invalid(
            "series variance",
            0,
            "non-zero (a series is constant)",
        ));
    }
    let r = (sab / (saa.sqrt() * sbb.sqrt())).clamp(-1.0, 1.0);
    let df = nf - 2.0;
    let p_value = if r.abs() >= 1.0 {
        0.0
    } else {
        t_sf_two_sided(r * (df / (1.0 - r * r)).sqrt(), df)
    };
    let (ci_low, ci_high) = if n > 3 && r.abs() < 1.0 {
        let z = r.atanh();
        let se = 1.0 / (nf - 3.0).sqrt();
        let q = normal_quantile(0.975);
        ((z - q * se).tanh(), (z + q * se).tanh())
    } else {
        (r, r)
    };
    Ok(Pearson {
        r,
        n,
        p_value,
        ci_low,
        ci_high,
    })
}

/// Bland-Altman statistics of differences `a - b` against means `(a + b) / 2`.
#[derive(Debug, Clone, Serialize)]
pub struct BlandAltman {
    /// Number of pairs.
    pub n: usize,
    /// Mean difference (bias).
    pub bias: f64,
    /// Standard deviation of the differences, ddof = 1.
    pub sd: f64,
    /// Lower limit of agreement bias - 1.96 sd.
    pub loa_low: f64,
    /// Upper limit of agreement bias + 1.96 sd.
    pub loa_high: f64,
    /// Standard error of the bias, sd / sqrt(n).
    pub bias_se: f64,
    /// Standard error of each limit, sqrt(3 sd^2 / n).
    pub loa_se: f64,
    /// 95 % confidence interval of the bias (Student t, n - 1 df).
    pub bias_ci: [f64; 2],
    /// Fraction of pairs outside the limits of agreement.
    pub fraction_outside: f64,
    /// Means of each pair (for the plot).
    #[serde(skip)]
    pub means: Vec<f64>,
    /// Differences of each pair (for the plot).
    #[serde(skip)]
    pub diffs: Vec<f64>,
}

/// The multiplier of the limits of agreement (Bland & Altman use 1.96).
pub const LOA_Z: f64 = 1.96;

/// Bland-Altman analysis of paired measurements (at least 2 pairs).
pub fn bland_altman(a: &[f64], b: &[f64]) -> Result<BlandAltman> {
    check_pairs(a, b, 2)?;
    let n = a.len();
    let nf = n as f64;
    let diffs: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let means: Vec<f64> = a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect();
    let bias = diffs.iter().sum::<f64>() / nf;
    let sd = (diffs.iter().map(|d| (d - bias) * (d - bias)).sum::<f64>() / (nf - 1.0)).sqrt();
    let (loa_low, loa_high) = (bias - LOA_Z * sd, bias + LOA_Z * sd);
    let bias_se = sd / nf.sqrt();
    let tq = t_quantile(0.975, nf - 1.0);
    let outside = diffs
        .iter()
        .filter(|&&d| d < loa_low || d > loa_high)
        .count();
    Ok(BlandAltman {
        n,
        bias,
        sd,
        loa_low,
        loa_high,
        bias_se,
        loa_se: (3.0 * sd * sd / nf).sqrt(),
        bias_ci: [bias - tq * bias_se, bias + tq * bias_se],
        fraction_outside: outside as f64 / nf,
        means,
        diffs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pearson_of_linear_relation_is_one() {
        let a: Vec<f64> = (0..50).map(f64::from).collect();
        let b: Vec<f64> = a.iter().map(|x| 3.0 * x - 1.0).collect();
        assert!((pearson(&a, &b).unwrap().r - 1.0).abs() < 1e-14);
        assert!(pearson(&a, &[1.0; 50]).is_err());
    }

    #[test]
    fn bland_altman_known_values() {
        let a = [1.0, 2.0, 3.0, 4.0];
        let b = [0.5, 2.5, 2.0, 4.0];
        let ba = bland_altman(&a, &b).unwrap();
        // d = [0.5, -0.5, 1, 0], mean 0.25, sd = sqrt(1.25/3).
        assert!((ba.bias - 0.25).abs() < 1e-15);
        assert!((ba.sd - (1.25f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!((ba.loa_se - (3.0 * 1.25 / 3.0 / 4.0f64).sqrt()).abs() < 1e-15);
    }
}
