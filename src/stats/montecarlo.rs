//! Monte-Carlo size and power of the cosinor equality tests: pairs of records that share a
//! breathing curve, with independent iid or AR(1) errors, and optionally an amplitude
//! difference; the share of replications each test rejects at level alpha.
//!
//! The curve is the one the Python cross-checks use, `2.5 + 0.25 (1 - cos a) + 0.03
//! sin 2a`, `a = 2 pi f0 t`, sampled at 56 Hz (SLP cameras) at f0 = 0.25 Hz (0.5 L tidal
//! volume). The second record's oscillation about the mean 2.75 L is scaled by
//! `amplitude_ratio` (1 under the null), so the means stay equal, as the data preparation
//! makes them. Errors of each
//! record are a stationary AR(1) `e_t = phi e_{t-1} + u_t` with marginal standard deviation
//! `noise_sd` (first value drawn from the stationary law).
//!
//! The robust test's bootstrap p-value needs B refits per replication; its rejection rate
//! is estimated by the warp-speed method of Giacomini, Politis & White (2013, Econometric
//! Theory 29:567): one bootstrap series per replication, each observed statistic compared
//! with the pooled bootstrap statistics of all replications. That estimates the rejection
//! rate of the test with B -> infinity at the cost of two fits per replication.

use super::autoreg::{ArGlsConfig, ArRegression};
use super::bars::{BarsConfig, bars_equality};
use super::cosinor::{compare_cosinor, cosinor_design};
use crate::numeric::rng::Pcg64;
use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;

/// One Monte-Carlo setting.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Scenario {
    /// Samples per record.
    pub n: usize,
    /// Sampling rate [Hz].
    pub rate_hz: f64,
    /// Breathing frequency [Hz] (known to the tests).
    pub frequency_hz: f64,
    /// Cosinor harmonics C.
    pub harmonics: usize,
    /// AR(1) coefficient of the errors (0: iid).
    pub phi: f64,
    /// Marginal standard deviation of the errors [L].
    pub noise_sd: f64,
    /// Breathing amplitude of the second record relative to the first (1: null).
    pub amplitude_ratio: f64,
    /// Replications.
    pub replications: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario {
            n: 500,
            rate_hz: 56.0,
            frequency_hz: 0.25,
            harmonics: 4,
            phi: 0.0,
            noise_sd: 0.02,
            amplitude_ratio: 1.0,
            replications: 400,
            seed: 1,
        }
    }
}

/// Rejection rates of each test at the level given to [`rejection_rates`].
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RejectionRates {
    /// Extra-sum-of-squares F with the intercept (iid errors assumed).
    pub f_with_intercept: f64,
    /// Extra-sum-of-squares F without the intercept (iid errors assumed).
    pub f_without_intercept: f64,
    /// Paired F on the differences (iid errors assumed).
    pub paired_f: f64,
    /// Robust test with the intercept, bootstrap p-value (warp-speed estimate).
    pub robust_with_intercept: f64,
    /// Robust test without the intercept, bootstrap p-value (warp-speed estimate).
    pub robust_without_intercept: f64,
    /// Robust test with the intercept, nominal F p-value (no bootstrap).
    pub robust_nominal_with_intercept: f64,
    /// Robust test without the intercept, nominal F p-value (no bootstrap).
    pub robust_nominal_without_intercept: f64,
    /// Replications.
    pub replications: usize,
}

fn ar1(g: &mut Pcg64, n: usize, phi: f64, sd: f64) -> Vec<f64> {
    let innov = sd * (1.0 - phi * phi).sqrt();
    let mut e = Vec::with_capacity(n);
    let mut prev = sd * g.normal();
    e.push(prev);
    for _ in 1..n {
        prev = phi * prev + innov * g.normal();
        e.push(prev);
    }
    e
}

/// The breathing curve of the module doc at times `t`, its oscillation about 2.75 L
/// scaled by `ratio`.
pub fn breathing_curve(t: &[f64], f0: f64, ratio: f64) -> Vec<f64> {
    t.iter()
        .map(|&s| {
            let a = 2.0 * PI * f0 * s;
            2.75 + ratio * (-0.25 * a.cos() + 0.03 * (2.0 * a).sin())
        })
        .collect()
}

/// A pair of records of the scenario (one replication), drawn from `g`.
pub fn draw_pair(sc: &Scenario, t: &[f64], g: &mut Pcg64) -> (Vec<f64>, Vec<f64>) {
    let s1 = breathing_curve(t, sc.frequency_hz, 1.0);
    let s2 = breathing_curve(t, sc.frequency_hz, sc.amplitude_ratio);
    let y1 = s1
        .iter()
        .zip(ar1(g, t.len(), sc.phi, sc.noise_sd))
        .map(|(a, b)| a + b)
        .collect();
    let y2 = s2
        .iter()
        .zip(ar1(g, t.len(), sc.phi, sc.noise_sd))
        .map(|(a, b)| a + b)
        .collect();
    (y1, y2)
}

/// BARS equality (Behseta & Kass 2005 as reconstructed in [`super::bars`]) on the
/// scenario: the share of replications with `P(H0 | data) < alpha` and the share whose
/// Hotelling T^2 screening p-value is below alpha. `P(H0)` is a posterior probability, not
/// a p-value: the first share is how often it would be read as a rejection.
pub fn bars_rejection_rates(sc: &Scenario, cfg: &BarsConfig, alpha: f64) -> Result<(f64, f64)> {
    let t: Vec<f64> = (0..sc.n).map(|i| i as f64 / sc.rate_hz).collect();
    let mut g = Pcg64::new(sc.seed, 0xba25);
    let (mut low_ph0, mut low_t2) = (0usize, 0usize);
    for r in 0..sc.replications {
        let (y1, y2) = draw_pair(sc, &t, &mut g);
        let c = BarsConfig {
            seed: cfg.seed.wrapping_add(r as u64),
            ..*cfg
        };
        let eq = bars_equality(&t, &y1, &y2, &c)?;
        if eq.p_h0 < alpha {
            low_ph0 += 1;
        }
        if eq.t2_p_value < alpha {
            low_t2 += 1;
        }
    }
    let r = sc.replications as f64;
    Ok((low_ph0 as f64 / r, low_t2 as f64 / r))
}

/// Runs the scenario and returns each test's rejection rate at level `alpha`.
pub fn rejection_rates(sc: &Scenario, alpha: f64) -> Result<RejectionRates> {
    if sc.phi.is_nan() || sc.phi.abs() >= 1.0 {
        return Err(Error::invalid("AR(1) coefficient phi", sc.phi, "(-1, 1)"));
    }
    if sc.replications == 0 {
        return Err(Error::invalid("replications", 0, "at least 1"));
    }
    let t: Vec<f64> = (0..sc.n).map(|i| i as f64 / sc.rate_hz).collect();
    let x = cosinor_design(&t, sc.frequency_hz, sc.harmonics);
    let p = x.ncols();
    let all: Vec<usize> = (0..p).collect();
    let harm: Vec<usize> = (1..p).collect();
    let cfg = ArGlsConfig {
        bootstrap: 0,
        ..ArGlsConfig::default()
    };
    let reg = ArRegression::new(&x, cfg.max_order)?;
    let mut g = Pcg64::new(sc.seed, 0x5eed);
    let mut count = [0usize; 5];
    let mut observed = Vec::with_capacity(sc.replications);
    let mut boot = Vec::with_capacity(sc.replications);
    for _ in 0..sc.replications {
        let (y1, y2) = draw_pair(sc, &t, &mut g);
        let eq = compare_cosinor(&t, &y1, &y2, sc.frequency_hz, sc.harmonics, &cfg)?;
        for (c, pv) in count.iter_mut().zip([
            eq.f_with_intercept.p_value,
            eq.f_without_intercept.p_value,
            eq.paired_f.p_value,
            eq.robust_with_intercept.p_value,
            eq.robust_without_intercept.p_value,
        ]) {
            if pv <= alpha {
                *c += 1;
            }
        }
        let d: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a - b).collect();
        let fit = reg.fit(&d)?;
        observed.push((fit.f_test(&all).f, fit.f_test(&harm).f));
        let null = reg.simulate_null(&fit, &mut g);
        let fs = reg.fit(&null)?;
        boot.push((fs.f_test(&all).f, fs.f_test(&harm).f));
    }
    let r = sc.replications as f64;
    let warp = |pick: fn(&(f64, f64)) -> f64| -> f64 {
        let mut b: Vec<f64> = boot.iter().map(pick).collect();
        b.sort_by(f64::total_cmp);
        let rejected = observed
            .iter()
            .filter(|o| {
                let f = pick(o);
                // Bootstrap statistics at or above f, by binary search in the sorted pool.
                let above = b.len() - b.partition_point(|v| *v < f);
                (1 + above) as f64 / (b.len() + 1) as f64 <= alpha
            })
            .count();
        rejected as f64 / r
    };
    Ok(RejectionRates {
        f_with_intercept: count[0] as f64 / r,
        f_without_intercept: count[1] as f64 / r,
        paired_f: count[2] as f64 / r,
        robust_nominal_with_intercept: count[3] as f64 / r,
        robust_nominal_without_intercept: count[4] as f64 / r,
        robust_with_intercept: warp(|o| o.0),
        robust_without_intercept: warp(|o| o.1),
        replications: sc.replications,
    })
}
