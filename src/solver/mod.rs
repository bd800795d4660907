//! Time integration, knowing nothing of the torso: embedded explicit Runge-Kutta pairs
//! (Dormand-Prince 5(4) by default), a weighted RMS error norm with rtol/atol, PI step-size
//! control, FSAL, dense output, step size kept across calls, statistics, and a stiffness
//! detector that reports. Everything is generic over the [`Ode`] trait.
//!
//! Failures (non-finite state, step below its floor, too many rejections) are returned as
//! [`SolverError`]s and leave the caller's state at the last accepted step; nothing panics.
//!
//! Layout: `tableau.rs` holds the coefficients of the pairs (Dormand & Prince 1980, Bogacki
//! & Shampine 1989, DOP853 of Hairer, Norsett & Wanner), `integrator.rs` the stepping, step
//! control and dense output ([`Integrator`]); `control.rs` the PI step-size controller and
//! `norm.rs` the weighted RMS error norm, both shared by the explicit pairs and the stiff
//! method; `rosenbrock.rs` the stiff method ([`Method::Rosenbrock`], ROS34PW2), `sparse.rs`
//! its sparse Jacobian, colouring and linear solver; `symplectic.rs` a fixed-step
//! semi-implicit Euler for comparison ([`SemiImplicitEuler`]); this file the public types.
//! A problem offers its Jacobian's structure to the stiff method through [`StiffOde`]
//! (found by [`Ode::as_stiff`]); without it the stiff method differences densely.
//!
//! ```
//! use breathing_torso::solver::{Integrator, Method, Ode, Options};
//!
//! /// y' = -y
//! struct Decay;
//! impl Ode for Decay {
//!     fn dim(&self) -> usize {
//!         1
//!     }
//!     fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) {
//!         dydt[0] = -y[0];
//!     }
//! }
//!
//! let mut solver = Integrator::new(Method::Dopri5, Options::default(), 1)?;
//! let (mut t, mut y) = (0.0, [1.0]);
//! for i in 1..=10 {
//!     // communication steps of 0.1: the step size and FSAL stage carry over
//!     solver.integrate(&mut Decay, &mut t, &mut y, 0.1 * i as f64)?;
//! }
//! assert_eq!(t, 1.0);
//! assert!((y[0] - (-1.0f64).exp()).abs() < 1e-6);
//! # Ok::<(), breathing_torso::solver::SolverError>(())
//! ```

mod control;
mod integrator;
mod norm;
mod rosenbrock;
pub mod sparse;
mod symplectic;
pub mod tableau;

pub use integrator::Integrator;
pub use rosenbrock::JacobianStructure;
pub use sparse::{Colouring, Jacobian, Pattern};
pub use symplectic::{SecondOrder, SemiImplicitEuler};
pub use tableau::Tableau;

/// A first-order system of ordinary differential equations y' = f(t, y).
///
/// `rhs` takes `&mut self` so that implementations can keep preallocated scratch memory and
/// never allocate while the solver runs.
pub trait Ode {
    /// Number of state variables.
    fn dim(&self) -> usize;
    /// Writes f(t, y) into `dydt` (same length as `y`).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]);
    /// The problem's Jacobian interface for the stiff method, if it has one; the default
    /// (`None`) makes [`Method::Rosenbrock`] difference the whole Jacobian densely.
    fn as_stiff(&mut self) -> Option<&mut dyn StiffOde> {
        None
    }
    /// How the error norm weighs each component, if not all alike: for component i, a
    /// factor `weight[i]` on the absolute tolerance and the component `reference[i]` whose
    /// magnitude sets its relative tolerance, so that its scale is weight_i atol + rtol
    /// max(|y0_r|, |y1_r|), r = reference_i. A second-order system gives each velocity the
    /// weight omega (a rate the solver need not resolve): an absolute velocity error counts
    /// as much as the position error it would make within 1 / omega. `None` (the default):
    /// every component refers to itself with weight 1, the norm of Hairer, Norsett & Wanner.
    fn error_weights(&self) -> Option<ErrorWeights<'_>> {
        None
    }
}

/// Per-component error weighting (see [`Ode::error_weights`]).
#[derive(Clone, Copy, Debug)]
pub struct ErrorWeights<'a> {
    /// The component whose magnitude sets each component's relative tolerance.
    pub reference: &'a [u32],
    /// Factor on each component's scale (> 0).
    pub weight: &'a [f64],
}

/// A problem that supplies its Jacobian J = S + U V^T to the stiff method: a sparse part S
/// on a fixed pattern and a low-rank part (e.g. the coupling through a global pressure).
pub trait StiffOde: Ode {
    /// Pattern of S, block grouping of the unknowns and rank of U V^T (asked once).
    fn jacobian_structure(&mut self) -> JacobianStructure;
    /// Fills `jac` (values of S on the pattern, U and V) at (t, y), `f0` = f(t, y).
    /// Returns the number of right-hand-side evaluations it made.
    fn jacobian(&mut self, t: f64, y: &[f64], f0: &[f64], jac: &mut Jacobian) -> u64;
}

use serde::{Deserialize, Serialize};

/// The integration methods offered (FMI parameter `solver.method`, by code).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Method {
    /// Dormand-Prince 5(4), FSAL, 7 stages (code 0, the default).
    #[default]
    Dopri5,
    /// Bogacki-Shampine 3(2), FSAL, 4 stages (code 1).
    BogackiShampine3,
    /// A high-order pair (code 2): DOP853 of Hairer, Norsett & Wanner, 8th order with
    /// 5th/3rd-order error estimators and 7th-order dense output.
    HighOrder,
    /// The stiff method (code 3): ROS34PW2, a linearly implicit Rosenbrock-W method of
    /// order 3(2) (Rang & Angermann 2005) with a sparse Jacobian; for stiff scenes.
    Rosenbrock,
    /// A model's quasi-static formulation (code 4): the model reduces itself to the few
    /// states that carry its slow dynamics (the torso: the lung volume, its positions the
    /// static equilibrium at every instant), which Dormand-Prince 5(4) integrates.
    QuasiStatic,
}

impl Method {
    /// All methods, by code.
    pub const ALL: [Method; 5] = [
        Method::Dopri5,
        Method::BogackiShampine3,
        Method::HighOrder,
        Method::Rosenbrock,
        Method::QuasiStatic,
    ];
    /// The explicit embedded Runge-Kutta pairs (those with a [`Tableau`]).
    pub const EMBEDDED: [Method; 3] = [Method::Dopri5, Method::BogackiShampine3, Method::HighOrder];
    /// FMI code of the method.
    pub fn code(self) -> i32 {
        self as i32
    }
    /// Method from its FMI code.
    pub fn from_code(code: i64) -> Option<Method> {
        usize::try_from(code)
            .ok()
            .and_then(|i| Self::ALL.get(i).copied())
    }
    /// Short name (`dopri5`, `bs3`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Method::Dopri5 => "dopri5",
            Method::BogackiShampine3 => "bs3",
            Method::HighOrder => "high-order",
            Method::Rosenbrock => "rosenbrock",
            Method::QuasiStatic => "quasi-static",
        }
    }
    /// Method from its short name.
    pub fn from_name(name: &str) -> Option<Method> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// Cumulative integration statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Accepted steps at which the stiffness test fired.
    pub stiff_steps: u64,
    /// Jacobian evaluations (stiff method).
    #[serde(default)]
    pub jacobian_evaluations: u64,
    /// LU factorisations (stiff method).
    #[serde(default)]
    pub factorizations: u64,
}

/// Tolerances and limits of the adaptive integrator.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Options {
    /// Relative tolerance, in [0, 1).
    pub rtol: f64,
    /// Absolute tolerance, >= 0 (rtol and atol not both 0).
    pub atol: f64,
    /// Largest step size, > 0 (may be infinite).
    #[serde(with = "infinite_as_none")]
    pub h_max: f64,
    /// Smallest step size allowed before [`SolverError::StepTooSmall`], >= 0; the final
    /// step of a call, shortened to land on the end time, is exempt.
    pub h_min: f64,
    /// First step size; `None` for Hairer's automatic choice.
    pub h_init: Option<f64>,
    /// Largest number of step attempts (accepted or rejected) in one integrate call.
    pub max_steps: u64,
    /// Largest number of consecutive rejected steps.
    pub max_rejections: u32,
    /// Run Hairer's stiffness test on accepted steps (counts [`Stats::stiff_steps`]).
    pub stiffness_check: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rtol: 1e-6,
            atol: 1e-8,
            h_max: f64::INFINITY,
            h_min: 1e-12,
            h_init: None,
            max_steps: 1_000_000,
            max_rejections: 50,
            stiffness_check: true,
        }
    }
}

impl Options {
    /// Checks every field against its allowed range; the error names the field.
    pub fn validate(&self) -> Result<(), SolverError> {
        let bad = |name: &str, value: f64, range: &str| {
            Err(SolverError::InvalidArgument(format!(
                "solver option `{name}` = {value} is outside its allowed range {range}"
            )))
        };
        if !(self.rtol.is_finite() && (0.0..1.0).contains(&self.rtol)) {
            return bad("rtol", self.rtol, "[0, 1)");
        }
        if !(self.atol.is_finite() && self.atol >= 0.0) {
            return bad("atol", self.atol, "[0, inf)");
        }
        if self.rtol == 0.0 && self.atol == 0.0 {
            return Err(SolverError::InvalidArgument(
                "solver options `rtol` and `atol` are both 0; at least one must be > 0".into(),
            ));
        }
        if self.h_max.is_nan() || self.h_max <= 0.0 {
            return bad("h_max", self.h_max, "(0, inf]");
        }
        if !(self.h_min.is_finite() && self.h_min >= 0.0 && self.h_min <= self.h_max) {
            return bad("h_min", self.h_min, "[0, h_max]");
        }
        if let Some(h) = self.h_init
            && !(h.is_finite() && h > 0.0)
        {
            return bad("h_init", h, "(0, inf)");
        }
        if self.max_steps == 0 {
            return bad("max_steps", 0.0, "[1, 2^64)");
        }
        if self.max_rejections == 0 {
            return bad("max_rejections", 0.0, "[1, 2^32)");
        }
        Ok(())
    }
}

/// Serialises an `f64` that may be +infinity as an `Option` (`None` = infinity), so that
/// every serde format (JSON included, which has no infinity) round-trips it.
mod infinite_as_none {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        let o = if *v == f64::INFINITY { None } else { Some(*v) };
        o.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}

/// Why an integration stopped. In every case the caller's time and state hold the last
/// accepted step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolverError {
    /// The state or right-hand side became NaN or infinite and shrinking the step did not
    /// help.
    #[error(
        "non-finite state or right-hand side at t = {t}: shrinking the step did not help \
         (state kept at the last accepted step)"
    )]
    NonFinite {
        /// Last accepted time.
        t: f64,
    },
    /// The step size fell below `h_min` (or below the round-off of t).
    #[error(
        "step size {h:e} fell below its floor at t = {t} (a singularity or a very stiff \
         problem; state kept at the last accepted step)"
    )]
    StepTooSmall {
        /// Last accepted time.
        t: f64,
        /// The step size that was too small.
        h: f64,
    },
    /// Too many consecutive rejected steps.
    #[error("{count} consecutive rejected steps at t = {t} (state kept at the last accepted step)")]
    TooManyRejections {
        /// Last accepted time.
        t: f64,
        /// Consecutive rejections.
        count: u32,
    },
    /// The step budget of one call (`max_steps`) ran out.
    #[error(
        "{steps} step attempts in one call did not reach the end time; stopped at t = {t} \
         (raise `max_steps` or loosen the tolerances)"
    )]
    TooManySteps {
        /// Last accepted time.
        t: f64,
        /// Attempts made.
        steps: u64,
    },
    /// An argument or option is out of range.
    #[error("invalid solver argument: {0}")]
    InvalidArgument(String),
}

impl SolverError {
    /// The last accepted time, when the error happened during integration.
    pub fn time(&self) -> Option<f64> {
        match self {
            SolverError::NonFinite { t }
            | SolverError::StepTooSmall { t, .. }
            | SolverError::TooManyRejections { t, .. }
            | SolverError::TooManySteps { t, .. } => Some(*t),
            SolverError::InvalidArgument(_) => None,
        }
    }
}

impl From<SolverError> for crate::Error {
    /// Integration failures become [`crate::Error::Numerical`] at the last accepted time;
    /// bad arguments become [`crate::Error::State`].
    fn from(e: SolverError) -> Self {
        match e.time() {
            Some(time) => crate::Error::Numerical {
                time,
                reason: e.to_string(),
            },
            None => crate::Error::State(e.to_string()),
        }
    }
}
