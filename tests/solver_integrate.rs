//! Adaptive integration: accuracy against exact solutions, step-size memory across calls,
//! FSAL invalidation, error reporting, dense output and serialisation of the integrator.

use breathing_torso::solver::{Integrator, Method, Ode, Options};

/// y' = -y + sin t, y(0) = 1: y = 3/2 e^{-t} + (sin t - cos t)/2 (time-dependent forcing).
struct Forced;
impl Ode for Forced {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = -y[0] + t.sin();
    }
}
fn forced_exact(t: f64) -> f64 {
    1.5 * (-t).exp() + 0.5 * (t.sin() - t.cos())
}

/// Harmonic oscillator x'' = -x, x(0) = 1, x'(0) = 0.
struct Oscillator;
impl Ode for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = y[1];
        d[1] = -y[0];
    }
}

fn opts(rtol: f64, atol: f64) -> Options {
    Options {
        rtol,
        atol,
        ..Options::default()
    }
}

#[test]
fn forced_problem_reaches_end_exactly_and_accurately() {
    for m in Method::ALL {
        let mut it = Integrator::new(m, opts(1e-8, 1e-10), 1).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        it.integrate(&mut Forced, &mut t, &mut y, 10.0).unwrap();
        assert_eq!(t, 10.0);
        let err = (y[0] - forced_exact(10.0)).abs();
        assert!(err < 1e-6, "{m:?}: error {err:e}");
        let s = it.stats();
        assert!(s.steps > 0 && s.rhs_evaluations > s.steps, "{s:?}");
    }
}

#[test]
fn oscillator_many_communication_steps() {
    for m in Method::ALL {
        let mut it = Integrator::new(m, opts(1e-9, 1e-12), 2).unwrap();
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        for i in 1..=1000 {
            it.integrate(&mut Oscillator, &mut t, &mut y, i as f64 * 0.01)
                .unwrap();
            assert_eq!(t, i as f64 * 0.01);
        }
        let err = (y[0] - 10f64.cos()).abs().max((y[1] + 10f64.sin()).abs());
        assert!(err < 1e-6, "{m:?}: error {err:e}");
    }
}
