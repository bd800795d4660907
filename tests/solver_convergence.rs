//! Observed convergence order of every pair with fixed steps on problems with exact
//! solutions, time-dependent ones included (a wrong abscissa c_i shows up only there), and
//! of the dense output.

use breathing_torso::solver::{Integrator, Method, Ode, Options};

/// A scalar problem y' = f(t, y) with its exact solution.
struct Scalar {
    f: fn(f64, f64) -> f64,
}
impl Ode for Scalar {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = (self.f)(t, y[0]);
    }
}

struct Problem {
    name: &'static str,
    f: fn(f64, f64) -> f64,
    exact: fn(f64) -> f64,
    t_end: f64,
}

const PROBLEMS: [Problem; 4] = [
    // forced linear: y = 3/2 e^{-t} + (sin t - cos t)/2
    Problem {
        name: "forced",
        f: |t, y| -y + t.sin(),
        exact: |t| 1.5 * (-t).exp() + 0.5 * (t.sin() - t.cos()),
        t_end: 6.0,
    },
    // pure quadrature y' = e^t: y = e^t (depends on the weights and abscissae only)
    Problem {
        name: "quadrature",
        f: |t, _| t.exp(),
        exact: |t| t.exp(),
        t_end: 3.0,
    },
    // nonlinear, time-dependent: y' = 3 y^2 sin 3t, y(0) = 1/3: y = 1/(2 + cos 3t)
    Problem {
        name: "nonlinear-t",
        f: |t, y| 3.0 * y * y * (3.0 * t).sin(),
        exact: |t| 1.0 / (2.0 + (3.0 * t).cos()),
        t_end: 5.0,
    },
    // logistic, autonomous: y' = y (1 - y), y(0) = 0.1: y = 1/(1 + 9 e^{-t})
    Problem {
        name: "logistic",
        f: |_, y| y * (1.0 - y),
        exact: |t| 1.0 / (1.0 + 9.0 * (-t).exp()),
        t_end: 8.0,
    },
];

fn fixed_error(m: Method, p: &Problem, n: u32) -> f64 {
    let mut it = Integrator::new(m, Options::default(), 1).unwrap();
    let mut ode = Scalar { f: p.f };
    let (mut t, mut y) = (0.0, [(p.exact)(0.0)]);
    let h = p.t_end / n as f64;
    if it
        .integrate_fixed(&mut ode, &mut t, &mut y, p.t_end, h)
        .is_err()
    {
        // far too coarse for this problem (the state blew up): not a usable resolution
        return f64::INFINITY;
    }
    assert_eq!(t, p.t_end);
    assert_eq!(it.stats().steps, n as u64);
    (y[0] - (p.exact)(p.t_end)).abs()
}

/// Errors with n = 2, 3, 4, 6, 8, 11, ... (ratio about √2) steps, keeping the resolutions whose error lies between
/// round-off (2e-13) and 1e-3; the observed order is taken from the finest ones, which are
/// in the asymptotic range.
fn usable_errors(m: Method, p: &Problem) -> Vec<(u32, f64)> {
    (2..=24)
        .map(|k| 2f64.powf(k as f64 / 2.0).round() as u32)
        .map(|n| (n, fixed_error(m, p, n)))
        .filter(|&(_, e)| e > 2e-13 && e < 1e-3)
        .collect()
}

#[test]
fn observed_order_matches_nominal() {
    for m in Method::EMBEDDED {
        let nominal = m.tableau().unwrap().order as f64;
        for p in &PROBLEMS {
            let errs = usable_errors(m, p);
            assert!(
                errs.len() >= 3,
                "{m:?} on {}: too few usable resolutions {errs:?}",
                p.name
            );
            let last = &errs[errs.len() - 3..];
            for (i, w) in last.windows(2).enumerate() {
                let observed = (w[0].1 / w[1].1).ln() / (w[1].0 as f64 / w[0].0 as f64).ln();
                println!(
                    "{:>10} {:>12}: n = {:>4} -> {:>4}: errors {:.3e} -> {:.3e}, order {observed:.2}",
                    m.name(),
                    p.name,
                    w[0].0,
                    w[1].0,
                    w[0].1,
                    w[1].1
                );
                // the finest pair must match within 0.3; the one before within 0.6
                let tol = if i == 1 { 0.3 } else { 0.6 };
                assert!(
                    (observed - nominal).abs() < tol,
                    "{m:?} on {}: observed order {observed:.2}, nominal {nominal} ({errs:?})",
                    p.name
                );
            }
        }
    }
}
