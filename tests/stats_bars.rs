//! Acceptance tests of BARS: recovery of known smooth curves (DiMatteo, Genovese & Kass
//! 2001 example 1 and a breathing-like curve), reproducibility for a seed, and the equality
//! test on identical and on 10 %-different curves.

use breathing_torso::numeric::rng::Pcg64;
use breathing_torso::stats::bars::{BarsConfig, bars_equality, bars_fit};
use std::f64::consts::PI;

fn rmse(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / a.len() as f64).sqrt()
}

fn noisy(truth: &[f64], sd: f64, seed: u64) -> Vec<f64> {
    let mut g = Pcg64::new(seed, 77);
    truth.iter().map(|v| v + sd * g.normal()).collect()
}

/// Breathing-like lung volume: 0.27 Hz with a second harmonic, 18 s at 56 Hz.
fn breathing(n: usize, amplitude: f64) -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..n).map(|i| i as f64 / 56.0).collect();
    let y = t
        .iter()
        .map(|&s| {
            let a = 2.0 * PI * 0.27 * s;
            2.5 + amplitude * (0.25 * (1.0 - a.cos()) + 0.04 * (2.0 * a).sin())
        })
        .collect();
    (t, y)
}

#[test]
fn recovers_dimatteo_example_1_below_noise_level() {
    // f(x) = sin(x) + 2 exp(-30 x^2) on [-2, 2], 101 points, noise sd 0.3 (DiMatteo et al.
    // 2001, section 4, first example).
    let t: Vec<f64> = (0..101).map(|i| -2.0 + 4.0 * i as f64 / 100.0).collect();
    let truth: Vec<f64> = t
        .iter()
        .map(|&x| x.sin() + 2.0 * (-30.0 * x * x).exp())
        .collect();
    let mut total = 0.0;
    for seed in 1..=5 {
        let y = noisy(&truth, 0.3, seed);
        let fit = bars_fit(
            &t,
            &y,
            &BarsConfig {
                seed,
                ..BarsConfig::default()
            },
        )
        .unwrap();
        let e = rmse(&fit.mean, &truth);
        total += e;
        assert!(
            e < 0.3 * 0.6,
            "seed {seed}: rmse {e} not clearly below the noise sd 0.3"
        );
        // The 95 % band covers most of the truth.
        let covered = truth
            .iter()
            .enumerate()
            .filter(|(i, v)| fit.lower[*i] <= **v && **v <= fit.upper[*i])
            .count();
        assert!(
            covered as f64 >= 0.75 * t.len() as f64,
            "seed {seed}: band covers {covered} of 101"
        );
    }
    assert!(
        total / 5.0 < 0.3 / 2.0,
        "mean rmse {} not below half the noise sd",
        total / 5.0
    );
}

#[test]
fn recovers_breathing_curve_below_noise_level() {
    let (t, truth) = breathing(1000, 1.0);
    let y = noisy(&truth, 0.02, 4);
    let fit = bars_fit(&t, &y, &BarsConfig::default()).unwrap();
    let e = rmse(&fit.mean, &truth);
    assert!(e < 0.02 / 2.0, "rmse {e} not below half the noise sd");
    assert!((fit.sigma - 0.02).abs() < 0.003, "sigma {}", fit.sigma);
}

#[test]
fn same_seed_same_result_other_seed_other_chain() {
    let (t, truth) = breathing(400, 1.0);
    let y = noisy(&truth, 0.02, 8);
    let cfg = BarsConfig {
        seed: 42,
        ..BarsConfig::default()
    };
    let a = bars_fit(&t, &y, &cfg).unwrap();
    let b = bars_fit(&t, &y, &cfg).unwrap();
    assert_eq!(a.mean, b.mean);
    assert_eq!(a.lower, b.lower);
    assert_eq!(a.knots_histogram, b.knots_histogram);
    let c = bars_fit(&t, &y, &BarsConfig { seed: 43, ..cfg }).unwrap();
    assert_ne!(a.knots_histogram, c.knots_histogram);
    let e1 = bars_equality(&t, &y, &noisy(&truth, 0.02, 9), &cfg).unwrap();
    let e2 = bars_equality(&t, &y, &noisy(&truth, 0.02, 9), &cfg).unwrap();
    assert_eq!(e1.p_h0, e2.p_h0);
    assert_eq!(e1.t2, e2.t2);
}

#[test]
fn equality_accepts_two_noisy_copies_of_one_curve() {
    let (t, truth) = breathing(1000, 1.0);
    for seed in [1u64, 2, 3] {
        let y1 = noisy(&truth, 0.02, 10 * seed);
        let y2 = noisy(&truth, 0.02, 10 * seed + 1);
        let eq = bars_equality(
            &t,
            &y1,
            &y2,
            &BarsConfig {
                seed,
                ..BarsConfig::default()
            },
        )
        .unwrap();
        assert!(eq.p_h0 > 0.9, "seed {seed}: P(H0) = {}", eq.p_h0);
        assert!(
            eq.t2_p_value > 0.001,
            "seed {seed}: T2 p = {}",
            eq.t2_p_value
        );
    }
}

#[test]
fn equality_rejects_curves_differing_by_ten_percent_amplitude() {
    let (t, a) = breathing(1000, 1.0);
    let (_, b) = breathing(1000, 1.1);
    for seed in [1u64, 2, 3] {
        let y1 = noisy(&a, 0.02, 10 * seed);
        let y2 = noisy(&b, 0.02, 10 * seed + 1);
        let eq = bars_equality(
            &t,
            &y1,
            &y2,
            &BarsConfig {
                seed,
                ..BarsConfig::default()
            },
        )
        .unwrap();
        assert!(eq.p_h0 < 0.05, "seed {seed}: P(H0) = {}", eq.p_h0);
        assert!(
            eq.t2_p_value < 1e-6,
            "seed {seed}: T2 p = {}",
            eq.t2_p_value
        );
    }
}

#[test]
fn rejects_bad_input() {
    assert!(bars_fit(&[0.0, 1.0], &[1.0, 2.0], &BarsConfig::default()).is_err());
    let t: Vec<f64> = (0..50).map(f64::from).collect();
    assert!(bars_fit(&t, &t[..40], &BarsConfig::default()).is_err());
    assert!(
        bars_fit(
            &t,
            &t,
            &BarsConfig {
                c: 0.9,
                ..BarsConfig::default()
            }
        )
        .is_err()
    );
}
