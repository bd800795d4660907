//! Solver overhead per right-hand-side evaluation on a large, cheap system: a chain of
//! 1,500 damped unit masses joined by springs (3,000 states). The time of the bare
//! right-hand side is subtracted from the integration time, leaving what the integrator
//! itself costs (stage combinations, error norm, step control).
//!
//! Each figure is the fastest of 7 repetitions, which filters out interference from other
//! processes.
//!
//! Run: `cargo bench --bench solver`.

use std::hint::black_box;
use std::time::Instant;

use breathing_torso::solver::{Integrator, Method, Ode, Options};

/// x_i'' = k (x_{i-1} - 2 x_i + x_{i+1}) - c x_i', fixed ends; state (x, v).
struct Chain {
    n: usize,
    k: f64,
    c: f64,
}

impl Ode for Chain {
    fn dim(&self) -> usize {
        2 * self.n
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        let n = self.n;
        let (x, v) = y.split_at(n);
        let (dx, dv) = d.split_at_mut(n);
        dx.copy_from_slice(v);
        for i in 0..n {
            let left = if i > 0 { x[i - 1] } else { 0.0 };
            let right = if i + 1 < n { x[i + 1] } else { 0.0 };
            dv[i] = self.k * (left - 2.0 * x[i] + right) - self.c * v[i];
        }
    }
}

fn main() {
    let n = 1500;
    let mut ode = Chain {
        n,
        k: 100.0,
        c: 0.5,
    };
    let y0: Vec<f64> = (0..2 * n)
        .map(|i| {
            if i < n {
                (std::f64::consts::PI * i as f64 / n as f64).sin() * 0.01
            } else {
                0.0
            }
        })
        .collect();

    // bare right-hand side
    let mut d = vec![0.0; 2 * n];
    let reps = 5_000;
    let t_rhs = (0..7)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..reps {
                ode.rhs(0.0, black_box(&y0), &mut d);
                black_box(&d);
            }
            start.elapsed().as_secs_f64() / reps as f64
        })
        .fold(f64::INFINITY, f64::min);
    println!(
        "states {}, right-hand side {:.2} us per evaluation",
        2 * n,
        t_rhs * 1e6
    );

    for m in Method::EMBEDDED {
        for rtol in [1e-6, 1e-9] {
            let opts = Options {
                rtol,
                atol: rtol * 1e-2,
                ..Options::default()
            };
            let mut it = Integrator::new(m, opts, 2 * n).unwrap();
            let mut y = y0.clone();
            let mut t = 0.0;
            let start = Instant::now();
            // 200 communication steps of 10 ms
            for i in 1..=200 {
                it.integrate(&mut ode, &mut t, &mut y, i as f64 * 0.01)
                    .unwrap();
            }
            let total = start.elapsed().as_secs_f64();
            let s = it.stats();
            let evals = s.rhs_evaluations as f64;
            let overhead = (total - evals * t_rhs) / evals;
            println!(
                "{:>10} rtol {rtol:.0e}: {} steps, {} rejected, {} evaluations, {:.1} ms total, \
                 solver overhead {:.2} us per evaluation",
                m.name(),
                s.steps,
                s.rejected,
                s.rhs_evaluations,
                total * 1e3,
                overhead * 1e6
            );
        }
    }
}
