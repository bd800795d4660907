//! The Arenstorf orbit (restricted three-body problem; Hairer, Norsett & Wanner, *Solving
//! ODEs I*, Sec. II.0): a periodic orbit that must close after one period, and the cost of
//! the default pair against the high-order one.
//!
//! Figures: `cargo test --release --test solver_arenstorf -- --nocapture`.
//!
//! The period and initial velocity keep the digits of their published values.

#![allow(clippy::excessive_precision)]

use breathing_torso::solver::{Integrator, Method, Ode, Options};

const MU: f64 = 0.012277471;
const PERIOD: f64 = 17.0652165601579625588917206249;
const Y0: [f64; 4] = [0.994, 0.0, 0.0, -2.00158510637908252240537862224];

/// State (x, y, x', y').
struct Arenstorf;
impl Ode for Arenstorf {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, _t: f64, s: &[f64], d: &mut [f64]) {
        let (x, y, vx, vy) = (s[0], s[1], s[2], s[3]);
        let mu1 = 1.0 - MU;
        let d1 = ((x + MU).powi(2) + y * y).powf(1.5);
        let d2 = ((x - mu1).powi(2) + y * y).powf(1.5);
        d[0] = vx;
        d[1] = vy;
        d[2] = x + 2.0 * vy - mu1 * (x + MU) / d1 - MU * (x - mu1) / d2;
        d[3] = y - 2.0 * vx - mu1 * y / d1 - MU * y / d2;
    }
}

/// Integrates one period; returns (closing error in position, RHS evaluations, steps).
fn one_period(m: Method, rtol: f64) -> (f64, u64, u64) {
    let mut it = Integrator::new(
        m,
        Options {
            rtol,
            atol: rtol,
            ..Options::default()
        },
        4,
    )
    .unwrap();
    let (mut t, mut y) = (0.0, Y0);
    it.integrate(&mut Arenstorf, &mut t, &mut y, PERIOD)
        .unwrap();
    assert_eq!(t, PERIOD);
    let err = ((y[0] - Y0[0]).powi(2) + (y[1] - Y0[1]).powi(2)).sqrt();
    (err, it.stats().rhs_evaluations, it.stats().steps)
}

#[test]
fn dopri5_closes_the_orbit() {
    let (err, evals, steps) = one_period(Method::Dopri5, 1e-10);
    println!("dopri5 rtol 1e-10: closing error {err:.2e}, {evals} evaluations, {steps} steps");
    assert!(err < 1e-5, "closing error {err:e}");
}

#[test]
fn high_order_pair_is_cheaper_at_tight_tolerances() {
    println!(
        "{:>10} {:>6} {:>12} {:>12} {:>7}",
        "method", "rtol", "error", "evaluations", "steps"
    );
    let mut table = Vec::new();
    for rtol in [1e-6, 1e-8, 1e-10] {
        for m in [Method::Dopri5, Method::HighOrder] {
            let (err, evals, steps) = one_period(m, rtol);
            println!(
                "{:>10} {rtol:>6.0e} {err:>12.3e} {evals:>12} {steps:>7}",
                m.name()
            );
            table.push((m, rtol, err, evals));
        }
    }
    // at 1e-10 the 8th-order pair needs fewer evaluations and is at least as accurate
    let dp = table
        .iter()
        .find(|r| r.0 == Method::Dopri5 && r.1 == 1e-10)
        .unwrap();
    let ho = table
        .iter()
        .find(|r| r.0 == Method::HighOrder && r.1 == 1e-10)
        .unwrap();
    assert!(
        ho.3 < dp.3,
        "evaluations: high-order {}, dopri5 {}",
        ho.3,
        dp.3
    );
    assert!(ho.2 < 1e-5 && dp.2 < 1e-5);
    // every run closes the orbit to a few hundred times its tolerance
    for (m, rtol, err, _) in &table {
        assert!(
            *err < 1e3 * rtol,
            "{m:?} rtol {rtol:e}: closing error {err:e}"
        );
    }
}
