//! The cosinor model (Nelson et al. 1979; thesis 4.4.3, eq. 4.1) with C harmonics of a known
//! fundamental, and tests of equality of two series' cosinor fits.
//!
//! `y(t) = M + sum_k [beta_k cos(k w0 t) + gamma_k sin(k w0 t)] + e`, fitted by least squares:
//! `theta = (X'X)^-1 X'y`, `sigma^2 = RSS / (N - 2C - 1)`, `Cov = sigma^2 (X'X)^-1`.
//! Amplitude `A_k = sqrt(beta_k^2 + gamma_k^2)`, acrophase `phi_k = atan2(-gamma_k, beta_k)`
//! (so `y = M + sum A_k cos(k w0 t + phi_k)`), standard errors by the delta method:
//! `var A = (beta^2 var beta + gamma^2 var gamma + 2 beta gamma cov) / A^2`,
//! `var phi = (gamma^2 var beta + beta^2 var gamma - 2 beta gamma cov) / A^4`.
//! Zero-amplitude test `F = [(TSS - RSS) / 2C] / [RSS / (N - 2C - 1)]`.
//!
//! Equality of two series on one time grid (reference "Equality of two series", [R]):
//! - extra sum of squares (Chow) with the intercept: pooled fit against separate fits,
//!   `q = 2C + 1`, `F(q, 2N - 2(2C + 1))`;
//! - the same without the intercept (each series keeps its own mesor, `q = 2C`), because
//!   the data preparation equalises the means;
//! - paired form on `d = y1 - y2`: `F = [(d'd - RSS_d) / p] / [RSS_d / (N - p)]`;
//! - the robust test: the paired regression with autoregressive errors, fitted by REML and
//!   tested by GLS F with a sieve-bootstrap p-value ([`super::autoreg`]), with and without
//!   the intercept. The F tests above assume independent errors; samples of a breathing
//!   record at 56 Hz are strongly autocorrelated, and then they reject true nulls far more
//!   often than their level (docs/validation.md gives the measured rates).

use super::autoreg::{ArGlsConfig, ArGlsTest, ar_gls_tests};
use super::ols::{FTest, OlsFit, ols};
use crate::{Error, Result};
use nalgebra::DMatrix;
use serde::Serialize;
use std::f64::consts::PI;

/// Design matrix [1, cos(w0 t), sin(w0 t), ..., cos(C w0 t), sin(C w0 t)].
pub fn cosinor_design(t: &[f64], frequency_hz: f64, harmonics: usize) -> DMatrix<f64> {
    let p = 2 * harmonics + 1;
    DMatrix::from_fn(t.len(), p, |i, j| {
        if j == 0 {
            1.0
        } else {
            let k = j.div_ceil(2) as f64;
            let arg = 2.0 * PI * k * frequency_hz * t[i];
            if j % 2 == 1 { arg.cos() } else { arg.sin() }
        }
    })
}

/// One harmonic of a cosinor fit.
#[derive(Debug, Clone, Serialize)]
pub struct CosinorComponent {
    /// Harmonic number k (1 is the breathing frequency).
    pub harmonic: usize,
    /// Its frequency k f0 [Hz].
    pub frequency_hz: f64,
    /// Cosine coefficient beta_k.
    pub beta: f64,
    /// Sine coefficient gamma_k.
    pub gamma: f64,
    /// Amplitude A_k.
    pub amplitude: f64,
    /// Delta-method standard error of A_k.
    pub amplitude_se: f64,
    /// Acrophase phi_k = atan2(-gamma, beta) [rad].
    pub acrophase: f64,
    /// Delta-method standard error of phi_k [rad].
    pub acrophase_se: f64,
}

/// A cosinor fit with C harmonics.
#[derive(Debug, Clone, Serialize)]
pub struct CosinorFit {
    /// Fundamental frequency f0 [Hz].
    pub frequency_hz: f64,
    /// Number of harmonics C.
    pub harmonics: usize,
    /// Number of observations N.
    pub n: usize,
    /// Mesor M.
    pub mesor: f64,
    /// Standard error of M.
    pub mesor_se: f64,
    /// Per-harmonic parameters.
    pub components: Vec<CosinorComponent>,
    /// All coefficients [M, beta_1, gamma_1, ...].
    pub coefficients: Vec<f64>,
    /// Their standard errors.
    pub standard_errors: Vec<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Total sum of squares about the mean.
    pub tss: f64,
    /// Coefficient of determination.
    pub r_squared: f64,
    /// Residual standard deviation.
    pub sigma: f64,
    /// Zero-amplitude F test (all harmonics zero).
    pub zero_amplitude: FTest,
    /// Fitted values.
    #[serde(skip)]
    pub fitted: Vec<f64>,
}

/// Fits the cosinor model with `harmonics` harmonics of `frequency_hz` to (t, y).
pub fn fit_cosinor(
    t: &[f64],
    y: &[f64],
    frequency_hz: f64,
    harmonics: usize,
) -> Result<CosinorFit> {
    if harmonics == 0 || harmonics > 50 {
        return Err(Error::invalid("harmonics", harmonics, "1..=50"));
    }
    if !(frequency_hz > 0.0 && frequency_hz.is_finite()) {
        return Err(Error::invalid(
            "cosinor frequency [Hz]",
            frequency_hz,
            "(0, inf)",
        ));
    }
    let x = cosinor_design(t, frequency_hz, harmonics);
    let fit = ols(&x, y)?;
    Ok(summarise(&x, y, &fit, frequency_hz, harmonics))
}

fn summarise(x: &DMatrix<f64>, y: &[f64], fit: &OlsFit, f0: f64, harmonics: usize) -> CosinorFit {
    let n = y.len();
    let cov = fit.covariance();
    let c = &fit.coef;
    let mean = y.iter().sum::<f64>() / n as f64;
    let tss: f64 = y.iter().map(|v| (v - mean) * (v - mean)).sum();
    let components = (1..=harmonics)
        .map(|k| {
            let (ib, ig) = (2 * k - 1, 2 * k);
            let (b, g) = (c[ib], c[ig]);
            let (vb, vg, cbg) = (cov[(ib, ib)], cov[(ig, ig)], cov[(ib, ig)]);
            let a2 = b * b + g * g;
            let a = a2.sqrt();
            CosinorComponent {
                harmonic: k,
                frequency_hz: k as f64 * f0,
                beta: b,
                gamma: g,
                amplitude: a,
                amplitude_se: ((b * b * vb + g * g * vg + 2.0 * b * g * cbg) / a2).sqrt(),
                acrophase: (-g).atan2(b),
                acrophase_se: ((g * g * vb + b * b * vg - 2.0 * b * g * cbg) / (a2 * a2)).sqrt(),
            }
        })
        .collect();
    let df = n - 2 * harmonics - 1;
    let fitted = (x * nalgebra::DVector::from_column_slice(c))
        .as_slice()
        .to_vec();
    CosinorFit {
        frequency_hz: f0,
        harmonics,
        n,
        mesor: c[0],
        mesor_se: cov[(0, 0)].sqrt(),
        components,
        coefficients: c.clone(),
        standard_errors: (0..c.len()).map(|i| cov[(i, i)].sqrt()).collect(),
        rss: fit.rss,
        tss,
        r_squared: 1.0 - fit.rss / tss,
        sigma: fit.sigma2().sqrt(),
        zero_amplitude: FTest::new(
            ((tss - fit.rss) / (2 * harmonics) as f64) / (fit.rss / df as f64),
            (2 * harmonics) as f64,
            df as f64,
        ),
        fitted,
    }
}

/// Tests of equality of two cosinor fits on one time grid (see the module doc).
#[derive(Debug, Clone, Serialize)]
pub struct CosinorEquality {
    /// Extra-sum-of-squares F, all 2C + 1 coefficients equal (iid errors).
    pub f_with_intercept: FTest,
    /// Extra-sum-of-squares F, the 2C harmonic coefficients equal, mesors free (iid errors).
    pub f_without_intercept: FTest,
    /// Paired F on d = y1 - y2, all coefficients of d zero (iid errors).
    pub paired_f: FTest,
    /// Robust test on d (AR errors, GLS F, bootstrap p-value): all 2C + 1 coefficients zero.
    pub robust_with_intercept: ArGlsTest,
    /// Robust test on d: the 2C harmonic coefficients zero.
    pub robust_without_intercept: ArGlsTest,
    /// Autoregressive order of the robust test's error model (BIC).
    pub robust_ar_order: usize,
    /// REML autoregressive coefficients of the robust test's error model.
    pub robust_ar: Vec<f64>,
    /// Settings of the robust test.
    pub robust_config: ArGlsConfig,
    /// Lag-1 autocorrelation of the paired residuals (near 1 means the iid tests overstate
    /// the evidence).
    pub residual_lag1_autocorrelation: f64,
}

/// Runs the equality tests of two series `y1`, `y2` sampled at the same times `t`;
/// `robust` configures the robust test.
pub fn compare_cosinor(
    t: &[f64],
    y1: &[f64],
    y2: &[f64],
    frequency_hz: f64,
    harmonics: usize,
    robust: &ArGlsConfig,
) -> Result<CosinorEquality> {
    let n = t.len();
    if y1.len() != n || y2.len() != n {
        return Err(Error::invalid(
            "series lengths",
            format!("{} and {}", y1.len(), y2.len()),
            format!("both {n}"),
        ));
    }
    let p = 2 * harmonics + 1;
    let x = cosinor_design(t, frequency_hz, harmonics);
    let f1 = ols(&x, y1)?;
    let f2 = ols(&x, y2)?;
    let rss_full = f1.rss + f2.rss;
    let df_full = 2 * n - 2 * p;
    // Pooled: stacked data on the stacked design.
    let stacked_y: Vec<f64> = y1.iter().chain(y2).copied().collect();
    let xs = DMatrix::from_fn(2 * n, p, |i, j| x[(i % n, j)]);
    let pooled = ols(&xs, &stacked_y)?;
    // Common harmonics, separate mesors: add a series indicator column.
    let xi = DMatrix::from_fn(2 * n, p + 1, |i, j| {
        if j < p {
            x[(i % n, j)]
        } else if i >= n {
            1.0
        } else {
            0.0
        }
    });
    let pooled_free_mesor = ols(&xi, &stacked_y)?;
    let d: Vec<f64> = y1.iter().zip(y2).map(|(a, b)| a - b).collect();
    let fd = ols(&x, &d)?;
    let dd: f64 = d.iter().map(|v| v * v).sum();
    let paired_f = FTest::new(
        ((dd - fd.rss) / p as f64) / (fd.rss / (n - p) as f64),
        p as f64,
        (n - p) as f64,
    );
    let all: Vec<usize> = (0..p).collect();
    let harm: Vec<usize> = (1..p).collect();
    let mut rob = ar_gls_tests(&x, &d, &[&all, &harm], robust)?;
    let robust_without_intercept = rob
        .tests
        .pop()
        .ok_or_else(|| Error::State("robust test missing".into()))?;
    let robust_with_intercept = rob
        .tests
        .pop()
        .ok_or_else(|| Error::State("robust test missing".into()))?;
    let r = &fd.residuals;
    let r0: f64 = r.iter().map(|e| e * e).sum();
    let r1: f64 = r.windows(2).map(|w| w[0] * w[1]).sum();
    Ok(CosinorEquality {
        f_with_intercept: FTest::extra_sum_of_squares(pooled.rss, rss_full, p, df_full),
        f_without_intercept: FTest::extra_sum_of_squares(
            pooled_free_mesor.rss,
            rss_full,
            p - 1,
            df_full,
        ),
        paired_f,
        robust_with_intercept,
        robust_without_intercept,
        robust_ar_order: rob.order,
        robust_ar: rob.ar,
        robust_config: *robust,
        residual_lag1_autocorrelation: r1 / r0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_known_parameters() {
        let f0 = 0.25;
        let t: Vec<f64> = (0..1000).map(|i| i as f64 / 56.0).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|&s| {
                2.5 + 0.4 * (2.0 * PI * f0 * s + 0.7).cos() + 0.1 * (4.0 * PI * f0 * s - 1.2).cos()
            })
            .collect();
        let fit = fit_cosinor(&t, &y, f0, 3).unwrap();
        assert!((fit.mesor - 2.5).abs() < 1e-10);
        assert!((fit.components[0].amplitude - 0.4).abs() < 1e-10);
        assert!((fit.components[0].acrophase - 0.7).abs() < 1e-10);
        assert!((fit.components[1].acrophase + 1.2).abs() < 1e-10);
        assert!(fit.components[2].amplitude < 1e-10);
    }
}
