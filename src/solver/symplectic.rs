//! A fixed-step semi-implicit (symplectic) Euler method, the integrator of most game and
//! interactive physics engines, for comparison with the adaptive pairs. It needs from the
//! problem a split of the state into a configuration part and a velocity part
//! ([`SecondOrder`]); it knows nothing else about the problem.
//!
//! One step of size h from (t_n, q_n, v_n) (Hairer, Lubich & Wanner, *Geometric Numerical
//! Integration*, 2nd ed. 2006, Sec. I.1.2 and VI.3, "symplectic Euler"; with a velocity- and
//! time-dependent force the force is taken explicitly at the start of the step, as engines do):
//!
//! ```text
//! v_{n+1} = v_n + h a(t_n, q_n, v_n)
//! q_{n+1} = q_n + h G(q_n) v_{n+1}          (G: kinematic map, e.g. q' = (0, w) q / 2)
//! q_{n+1} <- P(q_{n+1})                     (projection onto the manifold, e.g. unit quaternions)
//! ```
//!
//! One right-hand-side evaluation per step, first order, no error estimate: accuracy is
//! chosen through the step size alone, and stability ends at h ~ 2 / omega_max for an
//! undamped oscillator (less with explicit damping). An interval is covered by equal steps
//! no larger than the nominal one, so that every call lands exactly on its end time.

use super::{Ode, SolverError, Stats};

/// A first-order system whose state is a configuration q followed by velocities v:
/// y = [q | v], with q' = G(q) v given by a cheap kinematic map and v' read from
/// [`Ode::rhs`].
pub trait SecondOrder: Ode {
    /// Length of the configuration part q (the first entries of y); the rest is v.
    fn configuration_len(&self) -> usize;
    /// Writes q' = G(q) v for the state `y` (configuration and velocities) into `dq`
    /// (`configuration_len` values). Must not evaluate forces.
    fn configuration_rates(&self, y: &[f64], dq: &mut [f64]);
    /// Projects y back onto the configuration manifold after a step (e.g. renormalises
    /// quaternions). The default does nothing.
    fn project(&self, _y: &mut [f64]) {}
}

/// Fixed-step semi-implicit Euler integrator with preallocated memory and [`Stats`].
#[derive(Clone, Debug)]
pub struct SemiImplicitEuler {
    h: f64,
    dim: usize,
    /// Right-hand side at the start of the step.
    f: Vec<f64>,
    /// Configuration rates G(q_n) v_{n+1}.
    dq: Vec<f64>,
    /// State at the start of the step, restored when a step fails.
    backup: Vec<f64>,
    stats: Stats,
}

impl SemiImplicitEuler {
    /// An integrator of nominal step `h` (finite, > 0) for systems of dimension `dim` (> 0).
    pub fn new(h: f64, dim: usize) -> Result<Self, SolverError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(SolverError::InvalidArgument(format!(
                "fixed step size {h} is outside its allowed range (0, inf)"
            )));
        }
        if dim == 0 {
            return Err(SolverError::InvalidArgument(
                "system dimension is 0; it must be at least 1".into(),
            ));
        }
        Ok(SemiImplicitEuler {
            h,
            dim,
            f: vec![0.0; dim],
            dq: vec![0.0; dim],
            backup: vec![0.0; dim],
            stats: Stats::default(),
        })
    }

    /// The nominal step size.
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Cumulative statistics (steps and right-hand-side evaluations; never rejections).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Advances `(t, y)` to `t_end` (>= t) in ceil((t_end - t) / h) equal steps. A step that
    /// produces a non-finite state ends the call with [`SolverError::NonFinite`], `t` and `y`
    /// left at the last good step (the sign that h is beyond the stability limit).
    pub fn integrate<O: SecondOrder + ?Sized>(
        &mut self,
        ode: &mut O,
        t: &mut f64,
        y: &mut [f64],
        t_end: f64,
    ) -> Result<(), SolverError> {
        let p = ode.configuration_len();
        if y.len() != self.dim || ode.dim() != self.dim || p > self.dim {
            return Err(SolverError::InvalidArgument(format!(
                "state of length {} (configuration {p}) given to an integrator of dimension {}",
                y.len(),
                self.dim
            )));
        }
        if !t_end.is_finite() || t_end < *t {
            return Err(SolverError::InvalidArgument(format!(
                "end time {t_end} is not a finite time >= the current time {t}"
            )));
        }
        let span = t_end - *t;
        if span == 0.0 {
            return Ok(());
        }
        // equal steps no larger than h (the 1e-9 keeps an exact multiple from gaining a step)
        let steps = ((span / self.h) * (1.0 - 1e-9)).ceil().max(1.0) as u64;
        let h = span / steps as f64;
        let t0 = *t;
        for k in 1..=steps {
            self.backup.copy_from_slice(y);
            ode.rhs(*t, y, &mut self.f);
            self.stats.rhs_evaluations += 1;
            for (v, a) in y[p..].iter_mut().zip(&self.f[p..]) {
                *v += h * a;
            }
            ode.configuration_rates(y, &mut self.dq[..p]);
            for (q, dq) in y[..p].iter_mut().zip(&self.dq[..p]) {
                *q += h * dq;
            }
            ode.project(y);
            if y.iter().any(|v| !v.is_finite()) {
                y.copy_from_slice(&self.backup);
                return Err(SolverError::NonFinite { t: *t });
            }
            self.stats.steps += 1;
            *t = if k == steps { t_end } else { t0 + k as f64 * h };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x'' = -omega^2 x - c x' + F cos(t), as y = [x, v].
    struct Oscillator {
        omega: f64,
        damping: f64,
        forcing: f64,
    }

    impl Ode for Oscillator {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) {
            dydt[0] = y[1];
            dydt[1] = -self.omega.powi(2) * y[0] - self.damping * y[1] + self.forcing * t.cos();
        }
    }

    impl SecondOrder for Oscillator {
        fn configuration_len(&self) -> usize {
            1
        }
        fn configuration_rates(&self, y: &[f64], dq: &mut [f64]) {
            dq[0] = y[1];
        }
    }

    fn run(ode: &mut Oscillator, h: f64, t_end: f64) -> Result<([f64; 2], Stats), SolverError> {
        let mut s = SemiImplicitEuler::new(h, 2)?;
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        s.integrate(ode, &mut t, &mut y, t_end)?;
        assert_eq!(t, t_end);
        Ok((y, s.stats()))
    }

    #[test]
    fn first_order_on_a_forced_damped_oscillator() {
        // exact solution from a very fine step (the method converges), then the error
        // must halve when h halves
        let mut ode = Oscillator {
            omega: 3.0,
            damping: 0.5,
            forcing: 1.0,
        };
        let (exact, _) = run(&mut ode, 1e-6, 2.0).expect("fine run");
        let err = |h: f64, ode: &mut Oscillator| {
            let (y, _) = run(ode, h, 2.0).expect("stable");
            (y[0] - exact[0]).abs()
        };
        let e1 = err(1e-3, &mut ode);
        let e2 = err(5e-4, &mut ode);
        let ratio = e1 / e2;
        assert!((1.8..2.2).contains(&ratio), "order-1 ratio {ratio}");
    }

    #[test]
    fn energy_stays_bounded_without_damping() {
        // symplectic: the energy error oscillates but does not drift over 1,000 periods,
        // unlike explicit Euler, whose energy would grow by a factor (1 + h^2 w^2)^steps
        let mut ode = Oscillator {
            omega: 2.0,
            damping: 0.0,
            forcing: 0.0,
        };
        let periods = 1000.0 * std::f64::consts::PI;
        let (y, stats) = run(&mut ode, 0.01, periods).expect("stable");
        let energy = 0.5 * y[1] * y[1] + 0.5 * 4.0 * y[0] * y[0];
        assert!((energy - 2.0).abs() < 0.05, "energy {energy}");
        assert_eq!(stats.steps, stats.rhs_evaluations);
        assert_eq!(stats.steps, (periods / 0.01).ceil() as u64);
    }

    #[test]
    fn unstable_step_reports_non_finite_and_keeps_the_last_good_state() {
        // beyond h = 2 / omega the amplitude grows geometrically until it overflows
        let mut ode = Oscillator {
            omega: 1e3,
            damping: 0.0,
            forcing: 0.0,
        };
        let mut s = SemiImplicitEuler::new(3e-3, 2).expect("valid");
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        let e = s.integrate(&mut ode, &mut t, &mut y, 100.0).unwrap_err();
        assert!(matches!(e, SolverError::NonFinite { .. }), "{e}");
        assert!(t > 0.0 && t < 100.0);
        assert!(y.iter().all(|v| v.is_finite()));
        // the same oscillator is stable below the limit
        let mut s = SemiImplicitEuler::new(1.9e-3, 2).expect("valid");
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        s.integrate(&mut ode, &mut t, &mut y, 1.0).expect("stable");
        assert!(y[0].abs() <= 5.0, "bounded near the limit: {}", y[0]);
    }

    #[test]
    fn equal_steps_land_on_the_end_time_and_bad_arguments_are_named() {
        let mut ode = Oscillator {
            omega: 1.0,
            damping: 0.0,
            forcing: 0.0,
        };
        let mut s = SemiImplicitEuler::new(0.3, 2).expect("valid");
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        s.integrate(&mut ode, &mut t, &mut y, 1.0).expect("runs");
        assert_eq!((t, s.stats().steps), (1.0, 4));
        // an exact multiple takes exactly that many steps
        s.integrate(&mut ode, &mut t, &mut y, 1.9).expect("runs");
        assert_eq!((t, s.stats().steps), (1.9, 7));
        assert!(s.integrate(&mut ode, &mut t, &mut y, 0.5).is_err());
        assert!(SemiImplicitEuler::new(0.0, 2).is_err());
        assert!(SemiImplicitEuler::new(f64::NAN, 2).is_err());
        assert!(SemiImplicitEuler::new(0.1, 0).is_err());
    }
}
