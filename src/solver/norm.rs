//! The weighted RMS error norm of the step-size control, shared by the explicit pairs
//! (`integrator.rs`) and the Rosenbrock method (`rosenbrock.rs`): the one place that says
//! how a local error estimate is measured against the tolerances.
//!
//! ‖e‖ = sqrt((1/n) Σ_i (e_i / sc_i)²), sc_i = w_i atol + rtol max(|y0_r|, |y1_r|) with
//! r = reference_i (Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., eq. II.4.11; the
//! weights and references of [`super::Ode::error_weights`], or w_i = 1 and r = i without
//! them). Each scale is floored at the smallest positive number so that atol = 0 at a zero
//! component does not divide by zero.

use super::ErrorWeights;

/// The scale of one component: `weight` atol + rtol max(|a|, |b|), at least the smallest
/// positive `f64`.
#[inline]
pub(super) fn scale(weight: f64, atol: f64, rtol: f64, a: f64, b: f64) -> f64 {
    (weight * atol + rtol * a.abs().max(b.abs())).max(f64::MIN_POSITIVE)
}

/// Σ_i (e_i / sc_i)² over the components of `e`, the scales from the states `y0` and `y1`
/// at the step's ends (see the module documentation).
pub(super) fn square_sum(
    e: &[f64],
    y0: &[f64],
    y1: &[f64],
    atol: f64,
    rtol: f64,
    weights: Option<ErrorWeights>,
) -> f64 {
    let n = e.len();
    match weights {
        None => e
            .iter()
            .zip(&y0[..n])
            .zip(&y1[..n])
            .map(|((&e, &a), &b)| (e / scale(1.0, atol, rtol, a, b)).powi(2))
            .sum(),
        Some(w) => e
            .iter()
            .zip(&w.reference[..n])
            .zip(&w.weight[..n])
            .map(|((&e, &r), &w)| {
                let r = r as usize;
                (e / scale(w, atol, rtol, y0[r], y1[r])).powi(2)
            })
            .sum(),
    }
}

/// The weighted RMS norm of the error estimate `e`: sqrt([`square_sum`] / n).
pub(super) fn rms(
    e: &[f64],
    y0: &[f64],
    y1: &[f64],
    atol: f64,
    rtol: f64,
    weights: Option<ErrorWeights>,
) -> f64 {
    (square_sum(e, y0, y1, atol, rtol, weights) / e.len() as f64).sqrt()
}
