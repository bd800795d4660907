//! Adaptive integration: accuracy against exact solutions, step-size memory across calls,
//! FSAL invalidation, error reporting, dense output and serialisation of the integrator.

use breathing_torso::solver::{Integrator, Method, Ode, Options, SolverError};

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
    for m in Method::EMBEDDED {
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
    for m in Method::EMBEDDED {
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

/// y' = -y + u with a piecewise-constant input u.
struct Input {
    u: f64,
}
impl Ode for Input {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = -y[0] + self.u;
    }
}

/// y' = y^2, y(0) = 1: y = 1/(1 - t), blows up at t = 1.
struct BlowUp;
impl Ode for BlowUp {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = y[0] * y[0];
    }
}

/// y' = -y, but the right-hand side is NaN for t > t_nan while `poisoned`.
struct NanAfter {
    t_nan: f64,
    poisoned: bool,
}
impl Ode for NanAfter {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = if self.poisoned && t > self.t_nan {
            f64::NAN
        } else {
            -y[0]
        };
    }
}

/// y' = -λ (y - cos t): stiff for large λ.
struct Stiff {
    lambda: f64,
}
impl Ode for Stiff {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = -self.lambda * (y[0] - t.cos());
    }
}

fn osc_error(t: f64, y: &[f64]) -> f64 {
    (y[0] - t.cos()).abs().max((y[1] + t.sin()).abs())
}

/// y' = 3 y^2 sin 3t, y(0) = 1/3: y = 1/(2 + cos 3t) (nonlinear, time-dependent).
struct Nonlinear;
impl Ode for Nonlinear {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], d: &mut [f64]) {
        d[0] = 3.0 * y[0] * y[0] * (3.0 * t).sin();
    }
}

#[test]
fn global_error_follows_tolerance() {
    type Case = (&'static str, fn() -> Box<dyn Ode>, fn(f64) -> f64, f64);
    let cases: [Case; 2] = [
        ("forced", || Box::new(Forced), forced_exact, 20.0),
        (
            "nonlinear",
            || Box::new(Nonlinear),
            |t| 1.0 / (2.0 + (3.0 * t).cos()),
            10.0,
        ),
    ];
    for (name, make, exact, t_end) in cases {
        for m in Method::EMBEDDED {
            let mut last = f64::INFINITY;
            for k in 4..=10 {
                let rtol = 10f64.powi(-k);
                let mut it = Integrator::new(m, opts(rtol, rtol), 1).unwrap();
                let (mut t, mut y) = (0.0, [exact(0.0)]);
                let mut ode = make();
                it.integrate(ode.as_mut(), &mut t, &mut y, t_end).unwrap();
                let err = (y[0] - exact(t_end)).abs();
                println!(
                    "{name:>9} {:>10} rtol {rtol:.0e}: error {err:.3e} ({:.2} rtol), {} evaluations",
                    m.name(),
                    err / rtol,
                    it.stats().rhs_evaluations
                );
                assert!(
                    err < last,
                    "{m:?} {name}: error did not decrease at rtol {rtol:e}: {err:e} >= {last:e}"
                );
                assert!(
                    err < 100.0 * rtol && err > rtol / 1e3,
                    "{m:?} {name}: error {err:e} at rtol {rtol:e}"
                );
                last = err;
            }
        }
    }
}

#[test]
fn fsal_costs_stages_minus_one_per_step() {
    for m in Method::EMBEDDED {
        let s = m.tableau().unwrap().stages as u64;
        let mut it = Integrator::new(m, opts(1e-7, 1e-9), 2).unwrap();
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        it.integrate(&mut Oscillator, &mut t, &mut y, 5.0).unwrap();
        let st = it.stats();
        // f(t0, y0), one evaluation for the initial step, then s - 1 per attempt
        assert_eq!(
            st.rhs_evaluations,
            2 + (s - 1) * (st.steps + st.rejected),
            "{m:?} {st:?}"
        );
        // a second call continues from the stored FSAL stage: no extra evaluation
        let before = it.stats();
        it.integrate(&mut Oscillator, &mut t, &mut y, 6.0).unwrap();
        let after = it.stats();
        let attempts = (after.steps + after.rejected) - (before.steps + before.rejected);
        assert_eq!(
            after.rhs_evaluations - before.rhs_evaluations,
            (s - 1) * attempts,
            "{m:?}"
        );
    }
}

#[test]
fn step_size_is_carried_across_calls() {
    for m in Method::EMBEDDED {
        // communication steps of half the natural step size (the co-simulation case): with
        // memory each call is one step; a cold start pays the initial-step search and the
        // ramp-up every time
        let mut warm = Integrator::new(m, opts(1e-8, 1e-10), 2).unwrap();
        let (mut tw, mut yw) = (0.0, [1.0, 0.0]);
        warm.integrate(&mut Oscillator, &mut tw, &mut yw, 1.0)
            .unwrap();
        let dt = 0.5 * warm.step_size();
        let mut cold = warm.clone();
        let (mut tc, mut yc) = (tw, yw);
        let warm_before = warm.stats();
        let mut cold_steps = 0;
        let mut cold_evals = 0;
        let calls = 200;
        for i in 1..=calls {
            let te = 1.0 + i as f64 * dt;
            warm.integrate(&mut Oscillator, &mut tw, &mut yw, te)
                .unwrap();
            cold.reset();
            cold.integrate(&mut Oscillator, &mut tc, &mut yc, te)
                .unwrap();
            cold_steps += cold.stats().steps;
            cold_evals += cold.stats().rhs_evaluations;
        }
        let warm_steps = warm.stats().steps - warm_before.steps;
        let warm_evals = warm.stats().rhs_evaluations - warm_before.rhs_evaluations;
        println!(
            "{:>10}: {calls} calls of {dt:.3e}: warm {warm_steps} steps / {warm_evals} evaluations, \
             cold {cold_steps} steps / {cold_evals} evaluations",
            m.name()
        );
        // about one step per call (the natural step varies a little along the orbit)
        assert!(
            warm_steps <= calls + calls / 4,
            "{m:?}: {warm_steps} steps for {calls} calls"
        );
        assert!(
            2 * warm_steps < cold_steps,
            "{m:?}: warm {warm_steps}, cold {cold_steps}"
        );
        assert!(
            9 * warm_evals < 5 * cold_evals,
            "{m:?}: warm {warm_evals}, cold {cold_evals}"
        );
        assert!(osc_error(tw, &yw) < 1e-7, "{m:?}");
    }
}

#[test]
fn shortened_final_step_keeps_natural_step_size() {
    for m in Method::EMBEDDED {
        let mut it = Integrator::new(m, opts(1e-6, 1e-8), 2).unwrap();
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        it.integrate(&mut Oscillator, &mut t, &mut y, 3.0).unwrap();
        let h = it.step_size();
        assert!(h > 1e-3, "{m:?}: {h}");
        it.integrate(&mut Oscillator, &mut t, &mut y, 3.0 + 1e-7)
            .unwrap();
        assert_eq!(t, 3.0 + 1e-7);
        assert!(
            it.step_size() >= h,
            "{m:?}: natural {h}, now {}",
            it.step_size()
        );
    }
}

#[test]
fn invalidate_drops_stale_fsal_stage() {
    // u switches from 0 to 1 at t = 1; exact y(2) = 1 + (e^{-1} - 1) e^{-1}
    let exact = 1.0 + ((-1f64).exp() - 1.0) * (-1f64).exp();
    let run = |invalidate: bool| {
        let mut ode = Input { u: 0.0 };
        let mut it = Integrator::new(Method::Dopri5, opts(1e-9, 1e-12), 1).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        it.integrate(&mut ode, &mut t, &mut y, 1.0).unwrap();
        ode.u = 1.0;
        if invalidate {
            it.invalidate();
        }
        let h = it.step_size();
        let evals = it.stats().rhs_evaluations;
        it.integrate(&mut ode, &mut t, &mut y, 2.0).unwrap();
        (y[0], h, it.stats().rhs_evaluations - evals, it.step_size())
    };
    let (good, h_before, _, _) = run(true);
    let (stale, ..) = run(false);
    let err_good = (good - exact).abs();
    let err_stale = (stale - exact).abs();
    assert!(err_good < 1e-8, "{err_good:e}");
    assert!(
        err_stale > 100.0 * err_good,
        "stale {err_stale:e}, good {err_good:e}"
    );
    assert!(h_before > 0.0);
}

#[test]
fn blow_up_returns_error_at_last_accepted_state() {
    for m in Method::EMBEDDED {
        let mut it = Integrator::new(m, opts(1e-8, 1e-10), 1).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        let r = it.integrate(&mut BlowUp, &mut t, &mut y, 2.0);
        let e = r.expect_err("integration past the singularity must fail");
        println!("{:>10}: {e}", m.name());
        assert!(matches!(
            e,
            SolverError::StepTooSmall { .. }
                | SolverError::NonFinite { .. }
                | SolverError::TooManyRejections { .. }
        ));
        assert_eq!(e.time(), Some(t));
        // stopped at the singularity (the numerical solution lags the exact one a little)
        assert!(t > 0.99 && t < 1.0 + 1e-6, "{m:?}: stopped at {t}");
        assert!(y[0].is_finite() && y[0] > 1e3, "{m:?}: {}", y[0]);
        // and the integrator can still be serialised
        serde_json::to_string(&it).unwrap();
    }
}

#[test]
fn nan_rhs_returns_error_and_recovers() {
    for m in Method::EMBEDDED {
        let mut ode = NanAfter {
            t_nan: 0.5,
            poisoned: true,
        };
        let mut it = Integrator::new(m, opts(1e-8, 1e-10), 1).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        let e = it.integrate(&mut ode, &mut t, &mut y, 1.0).unwrap_err();
        assert!(matches!(e, SolverError::NonFinite { .. }), "{m:?}: {e}");
        assert!(t <= 0.5 && t > 0.49, "{m:?}: {t}");
        assert!((y[0] - (-t).exp()).abs() < 1e-7, "{m:?}");
        assert!(it.stats().rejected > 0);
        // once the right-hand side is healthy again, integration continues from there
        ode.poisoned = false;
        it.invalidate();
        it.integrate(&mut ode, &mut t, &mut y, 1.0).unwrap();
        assert_eq!(t, 1.0);
        assert!((y[0] - (-1f64).exp()).abs() < 1e-7, "{m:?}");
        // NaN at the very start point
        let mut ode = NanAfter {
            t_nan: -1.0,
            poisoned: true,
        };
        let (mut t, mut y) = (0.0, [1.0]);
        let e = it.integrate(&mut ode, &mut t, &mut y, 1.0).unwrap_err();
        assert_eq!(e, SolverError::NonFinite { t: 0.0 });
        assert_eq!((t, y[0]), (0.0, 1.0));
        serde_json::to_string(&it).unwrap();
    }
}

#[test]
fn limits_are_enforced() {
    let mut it = Integrator::new(
        Method::Dopri5,
        Options {
            max_steps: 10,
            ..opts(1e-10, 1e-12)
        },
        2,
    )
    .unwrap();
    let (mut t, mut y) = (0.0, [1.0, 0.0]);
    let e = it
        .integrate(&mut Oscillator, &mut t, &mut y, 100.0)
        .unwrap_err();
    assert!(
        matches!(e, SolverError::TooManySteps { steps: 10, .. }),
        "{e}"
    );
    assert!(t > 0.0 && t < 100.0);
    assert!(osc_error(t, &y) < 1e-8);

    let mut it = Integrator::new(
        Method::Dopri5,
        Options {
            h_max: 0.01,
            ..opts(1e-4, 1e-6)
        },
        2,
    )
    .unwrap();
    let (mut t, mut y) = (0.0, [1.0, 0.0]);
    it.integrate(&mut Oscillator, &mut t, &mut y, 1.0).unwrap();
    assert!(it.stats().steps >= 100);

    // a bounded number of rejections: a right-hand side that is NaN beyond t = 0.5 with
    // h_min = 0 can only stop through the rejection limit
    let mut it = Integrator::new(
        Method::Dopri5,
        Options {
            h_min: 0.0,
            max_rejections: 5,
            ..opts(1e-6, 1e-8)
        },
        1,
    )
    .unwrap();
    let mut ode = NanAfter {
        t_nan: 0.5,
        poisoned: true,
    };
    let (mut t, mut y) = (0.0, [1.0]);
    let e = it.integrate(&mut ode, &mut t, &mut y, 1.0).unwrap_err();
    assert!(matches!(e, SolverError::NonFinite { .. }), "{e}");
}

#[test]
fn invalid_arguments_are_reported() {
    let bad = [
        Options {
            rtol: -1.0,
            ..Options::default()
        },
        Options {
            rtol: f64::NAN,
            ..Options::default()
        },
        Options {
            atol: -1e-3,
            ..Options::default()
        },
        Options {
            rtol: 0.0,
            atol: 0.0,
            ..Options::default()
        },
        Options {
            h_max: 0.0,
            ..Options::default()
        },
        Options {
            h_min: 1.0,
            h_max: 0.5,
            ..Options::default()
        },
        Options {
            h_init: Some(0.0),
            ..Options::default()
        },
        Options {
            max_steps: 0,
            ..Options::default()
        },
        Options {
            max_rejections: 0,
            ..Options::default()
        },
    ];
    for o in bad {
        let e = Integrator::new(Method::Dopri5, o, 1).unwrap_err();
        assert!(matches!(e, SolverError::InvalidArgument(_)), "{o:?}");
        assert!(
            e.to_string().contains('`'),
            "message should name the option: {e}"
        );
    }
    assert!(Integrator::new(Method::Dopri5, Options::default(), 0).is_err());
    let mut it = Integrator::new(Method::Dopri5, Options::default(), 2).unwrap();
    assert!(
        it.set_options(Options {
            rtol: 2.0,
            ..Options::default()
        })
        .is_err()
    );
    assert_eq!(*it.options(), Options::default());
    let (mut t, mut y) = (0.0, [1.0]);
    assert!(matches!(
        it.integrate(&mut Forced, &mut t, &mut y, 1.0),
        Err(SolverError::InvalidArgument(_))
    ));
    let (mut t, mut y) = (1.0, [1.0, 0.0]);
    assert!(matches!(
        it.integrate(&mut Oscillator, &mut t, &mut y, 0.5),
        Err(SolverError::InvalidArgument(_))
    ));
    let r = it.integrate_dense(&mut Oscillator, &mut t, &mut y, 2.0, &[1.5, 1.2], |_, _| {});
    assert!(matches!(r, Err(SolverError::InvalidArgument(_))));
    // t_end == t is a no-op
    it.integrate(&mut Oscillator, &mut t, &mut y, 1.0).unwrap();
    assert_eq!(it.stats().rhs_evaluations, 0);
    // errors convert into the crate error
    let e: breathing_torso::Error = SolverError::StepTooSmall { t: 1.5, h: 1e-13 }.into();
    assert!(matches!(e, breathing_torso::Error::Numerical { time, .. } if time == 1.5));
}

#[test]
fn dense_output_is_accurate_and_does_not_change_steps() {
    for m in Method::EMBEDDED {
        let o = opts(1e-9, 1e-12);
        let times: Vec<f64> = (0..=400).map(|i| -0.5 + i as f64 * 0.025).collect();
        let mut it = Integrator::new(m, o, 2).unwrap();
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        let mut seen = Vec::new();
        let mut worst: f64 = 0.0;
        it.integrate_dense(&mut Oscillator, &mut t, &mut y, 5.0, &times, |tau, yy| {
            seen.push(tau);
            worst = worst.max(osc_error(tau, yy));
        })
        .unwrap();
        let at_end = osc_error(t, &y);
        it.integrate_dense(&mut Oscillator, &mut t, &mut y, 9.0, &times, |tau, yy| {
            seen.push(tau);
            worst = worst.max(osc_error(tau, yy));
        })
        .unwrap();
        let expected: Vec<f64> = times
            .iter()
            .copied()
            .filter(|&v| v > 0.0 && v <= 9.0)
            .collect();
        assert_eq!(
            seen, expected,
            "{m:?}: outputs in (t, t_end], in order, once"
        );
        println!(
            "{:>10}: dense error {worst:.2e}, error at grid point {at_end:.2e}",
            m.name()
        );
        assert!(worst < 1e-7, "{m:?}: dense output error {worst:e}");
        assert!(
            worst < 50.0 * at_end.max(1e-11),
            "{m:?}: dense {worst:e} vs step {at_end:e}"
        );

        // same steps as without outputs
        let mut plain = Integrator::new(m, o, 2).unwrap();
        let (mut t2, mut y2) = (0.0, [1.0, 0.0]);
        plain
            .integrate(&mut Oscillator, &mut t2, &mut y2, 5.0)
            .unwrap();
        plain
            .integrate(&mut Oscillator, &mut t2, &mut y2, 9.0)
            .unwrap();
        assert_eq!(plain.stats().steps, it.stats().steps, "{m:?}");
        assert_eq!(y2, y, "{m:?}: dense output must not perturb the solution");
    }
}

#[test]
fn stiffness_is_detected_and_only_reported() {
    for m in Method::EMBEDDED {
        let mut it = Integrator::new(m, opts(1e-6, 1e-8), 1).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        it.integrate(&mut Stiff { lambda: 1e4 }, &mut t, &mut y, 2.0)
            .unwrap();
        assert_eq!(t, 2.0);
        assert!((y[0] - 2f64.cos()).abs() < 1e-3);
        let st = it.stats();
        println!("{:>10}: stiff problem {st:?}", m.name());
        if m.tableau().unwrap().stiff_stage.is_none() {
            assert_eq!(st.stiff_steps, 0);
            continue;
        }
        assert!(st.stiff_steps > st.steps / 4, "{m:?}: {st:?}");
        assert!(it.stiffness_detected(), "{m:?}");

        let mut it = Integrator::new(m, opts(1e-6, 1e-8), 2).unwrap();
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        it.integrate(&mut Oscillator, &mut t, &mut y, 20.0).unwrap();
        assert_eq!(it.stats().stiff_steps, 0, "{m:?}");
        assert!(!it.stiffness_detected());

        let o = Options {
            stiffness_check: false,
            ..opts(1e-6, 1e-8)
        };
        let mut it = Integrator::new(m, o, 1).unwrap();
        let (mut t, mut y) = (0.0, [1.0]);
        it.integrate(&mut Stiff { lambda: 1e4 }, &mut t, &mut y, 0.5)
            .unwrap();
        assert_eq!(it.stats().stiff_steps, 0);
    }
}

#[test]
fn serde_round_trip_continues_bit_identically() {
    for m in Method::EMBEDDED {
        let mut it = Integrator::new(m, opts(1e-8, 1e-10), 2).unwrap();
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        it.integrate(&mut Oscillator, &mut t, &mut y, 3.3).unwrap();
        let json = serde_json::to_string(&it).unwrap();
        let mut restored: Integrator = serde_json::from_str(&json).unwrap();
        assert_eq!(restored.options(), it.options());
        assert_eq!(restored.step_size().to_bits(), it.step_size().to_bits());
        let (mut t2, mut y2) = (t, y);
        for te in [4.0, 7.5, 11.0] {
            it.integrate(&mut Oscillator, &mut t, &mut y, te).unwrap();
            restored
                .integrate(&mut Oscillator, &mut t2, &mut y2, te)
                .unwrap();
        }
        assert_eq!(t.to_bits(), t2.to_bits());
        assert_eq!(y[0].to_bits(), y2[0].to_bits(), "{m:?}");
        assert_eq!(y[1].to_bits(), y2[1].to_bits(), "{m:?}");
        assert_eq!(it.stats(), restored.stats());
        assert_eq!(it.step_size().to_bits(), restored.step_size().to_bits());
        // and a second round trip of the continued integrator gives the same text
        assert_eq!(
            serde_json::to_string(&it).unwrap(),
            serde_json::to_string(&restored).unwrap()
        );
    }
}
