//! Step-size control shared by the explicit pairs (`integrator.rs`) and the Rosenbrock
//! method (`rosenbrock.rs`): the PI controller on the weighted error norm, the handling of
//! steps clipped to land on the end time, and the bookkeeping of one chain of attempts
//! (step and rejection limits, the last accepted proposal, and which error a failing chain
//! reports).
//!
//! Sources: Hairer, Norsett & Wanner, *Solving ODEs I* (2nd ed., 1993), Sec. II.4 and the
//! `dopri5` code (safety factor, ratio limits, the `facold` floor); K. Gustafsson, "Control
//! theoretic techniques for stepsize selection in explicit Runge-Kutta methods", ACM TOMS 17
//! (1991) 533-554 (PI exponents 0.7/k and 0.4/k for an error estimate of order k).

use super::{Options, SolverError};

/// Lower bound of the PI memory (Hairer's `facold` floor).
pub(super) const ERR_OLD_MIN: f64 = 1e-4;
/// Step-size ratio after a step failed with non-finite values (or a singular system).
const FAC_NON_FINITE: f64 = 0.25;

/// Constants of one method's PI step-size controller.
#[derive(Clone, Copy, Debug)]
pub(super) struct Controller {
    /// Safety factor applied to every proposal.
    pub safety: f64,
    /// Smallest step-size ratio h_new / h.
    pub fac_min: f64,
    /// Largest step-size ratio h_new / h.
    pub fac_max: f64,
    /// Exponent of the current error (0.7/k, or 1/k with no PI memory).
    pub alpha: f64,
    /// Exponent of the previous error.
    pub beta: f64,
    /// A proposed increase below this ratio keeps the step unchanged (1 = always take it).
    pub hold_ratio: f64,
}

/// The size of the next attempt.
#[derive(Clone, Copy, Debug)]
pub(super) struct Planned {
    /// The step to attempt.
    pub h: f64,
    /// The controller's proposal before clipping to the end time.
    pub h_nat: f64,
    /// Whether the step was stretched or shortened to land on the end time.
    pub clipped: bool,
}

/// Bookkeeping of one call's chain of attempts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Chain {
    attempts: u64,
    rejections: u32,
    last_non_finite: bool,
    h_good: f64,
}

impl Chain {
    /// A chain starting from the proposal `h_start`.
    pub fn new(h_start: f64) -> Chain {
        Chain {
            attempts: 0,
            rejections: 0,
            last_non_finite: false,
            h_good: h_start,
        }
    }

    /// The next attempt from `t` towards `t_end` with the proposal `*h_next`. A step within 1 %
    /// of the remaining interval lands on `t_end`. Errors (the proposal restored to the last
    /// accepted one) when the step budget is spent or the step falls below the floor.
    pub fn plan(
        &mut self,
        h_next: &mut f64,
        t: f64,
        t_end: f64,
        opts: &Options,
    ) -> Result<Planned, SolverError> {
        if self.attempts >= opts.max_steps {
            return Err(SolverError::TooManySteps {
                t,
                steps: self.attempts,
            });
        }
        let h_nat = h_next.min(opts.h_max);
        let remaining = t_end - t;
        let clipped = h_nat * 1.01 >= remaining;
        let h = if clipped { remaining } else { h_nat };
        if (h_nat < opts.h_min || t + h_nat == t) && !(clipped && h > 0.0) {
            *h_next = self.h_good;
            return Err(if self.last_non_finite {
                SolverError::NonFinite { t }
            } else {
                SolverError::StepTooSmall { t, h: h_nat }
            });
        }
        self.attempts += 1;
        Ok(Planned { h, h_nat, clipped })
    }

    /// An accepted step with error norm `err` (<= 1): returns the next proposal and updates
    /// the PI memory `err_old`, which a clipped, shortened step leaves alone (its natural
    /// size is kept as the proposal instead).
    pub fn accept(&mut self, ctl: &Controller, err: f64, err_old: &mut f64, p: Planned) -> f64 {
        let h = p.h;
        let fac = (err.powf(ctl.alpha) / err_old.powf(ctl.beta) / ctl.safety)
            .clamp(1.0 / ctl.fac_max, 1.0 / ctl.fac_min);
        let mut h_new = h / fac;
        if self.rejections > 0 {
            h_new = h_new.min(h);
        }
        if h_new > h && h_new < ctl.hold_ratio * h {
            h_new = h;
        }
        if p.clipped && h < p.h_nat {
            h_new = h_new.max(p.h_nat);
        } else {
            *err_old = err.max(ERR_OLD_MIN);
        }
        self.h_good = h_new;
        self.rejections = 0;
        self.last_non_finite = false;
        h_new
    }

    /// A rejected step of size `h` with error norm `err` (`None`: non-finite values or a
    /// singular system): returns the smaller proposal, or the error that ends the chain when
    /// the rejections exceed the limit (the proposal then restored to the last accepted one).
    pub fn reject(
        &mut self,
        ctl: &Controller,
        err: Option<f64>,
        h: f64,
        t: f64,
        h_next: &mut f64,
        opts: &Options,
    ) -> Result<(), SolverError> {
        self.rejections += 1;
        *h_next = match err {
            Some(err) => {
                self.last_non_finite = false;
                h / (err.powf(ctl.alpha) / ctl.safety).min(1.0 / ctl.fac_min)
            }
            None => {
                self.last_non_finite = true;
                h * FAC_NON_FINITE
            }
        };
        if self.rejections > opts.max_rejections {
            *h_next = self.h_good;
            return Err(if self.last_non_finite {
                SolverError::NonFinite { t }
            } else {
                SolverError::TooManyRejections {
                    t,
                    count: self.rejections,
                }
            });
        }
        Ok(())
    }

    /// Ends the chain on a failure after an accepted error norm (a non-finite value found
    /// while finishing the step): the proposal goes back to the last accepted one.
    pub fn fail_non_finite(&self, h_next: &mut f64, t: f64) -> SolverError {
        *h_next = self.h_good;
        SolverError::NonFinite { t }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CTL: Controller = Controller {
        safety: 0.9,
        fac_min: 0.2,
        fac_max: 10.0,
        alpha: 0.7 / 5.0,
        beta: 0.4 / 5.0,
        hold_ratio: 1.0,
    };

    fn opts() -> Options {
        Options::default()
    }

    #[test]
    fn a_step_near_the_end_lands_on_it() {
        let mut chain = Chain::new(0.1);
        let mut h = 0.1;
        let p = chain.plan(&mut h, 0.0, 0.1005, &opts()).unwrap();
        assert!(p.clipped && p.h == 0.1005);
        let p = chain.plan(&mut h, 0.0, 0.5, &opts()).unwrap();
        assert!(!p.clipped && p.h == 0.1);
    }

    #[test]
    fn small_errors_grow_the_step_within_the_limits() {
        let mut chain = Chain::new(0.1);
        let mut err_old = 1e-4;
        let p = Planned {
            h: 0.1,
            h_nat: 0.1,
            clipped: false,
        };
        let h_new = chain.accept(&CTL, 1e-12, &mut err_old, p);
        assert_eq!(h_new, 0.1 * CTL.fac_max);
        assert_eq!(err_old, 1e-4);
        // a moderate error after a moderate one: a small increase
        err_old = 0.1;
        let h_new = chain.accept(&CTL, 0.1, &mut err_old, p);
        assert!(h_new > 0.1 && h_new < 0.2, "{h_new}");
        assert_eq!(err_old, 0.1);
        // a large error after a small one: a decrease although the step was accepted
        err_old = 1e-4;
        assert!(chain.accept(&CTL, 0.9, &mut err_old, p) < 0.1);
    }

    #[test]
    fn after_a_rejection_the_step_does_not_grow() {
        let mut chain = Chain::new(0.1);
        let mut err_old = 1e-4;
        let mut h = 0.1;
        chain
            .reject(&CTL, Some(4.0), 0.1, 0.0, &mut h, &opts())
            .unwrap();
        assert!((0.1 * CTL.fac_min..0.1).contains(&h));
        let p = Planned {
            h,
            h_nat: h,
            clipped: false,
        };
        assert_eq!(chain.accept(&CTL, 1e-6, &mut err_old, p), h);
    }

    #[test]
    fn the_proposal_is_held_below_the_hold_ratio() {
        let ctl = Controller {
            hold_ratio: 1.2,
            ..CTL
        };
        let mut chain = Chain::new(0.1);
        let p = Planned {
            h: 0.1,
            h_nat: 0.1,
            clipped: false,
        };
        let mut err_old = 0.1;
        assert!(chain.accept(&CTL, 0.1, &mut err_old, p) > 0.1);
        let mut err_old = 0.1;
        assert_eq!(chain.accept(&ctl, 0.1, &mut err_old, p), 0.1);
    }

    #[test]
    fn too_many_rejections_end_the_chain_with_the_last_good_proposal() {
        let o = Options {
            max_rejections: 2,
            ..opts()
        };
        let mut chain = Chain::new(0.1);
        let mut h = 0.1;
        chain.reject(&CTL, None, 0.1, 1.0, &mut h, &o).unwrap();
        assert_eq!(h, 0.025);
        chain.reject(&CTL, Some(2.0), h, 1.0, &mut h, &o).unwrap();
        let err = chain.reject(&CTL, None, h, 1.0, &mut h, &o).unwrap_err();
        assert!(matches!(err, SolverError::NonFinite { .. }), "{err:?}");
        assert_eq!(h, 0.1);
    }

    #[test]
    fn steps_below_the_floor_are_an_error() {
        let o = Options {
            h_min: 1e-3,
            ..opts()
        };
        let mut chain = Chain::new(1e-4);
        let mut h = 1e-4;
        let err = chain.plan(&mut h, 0.0, 1.0, &o).unwrap_err();
        assert!(matches!(err, SolverError::StepTooSmall { .. }), "{err:?}");
    }
}
