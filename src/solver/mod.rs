//! Time integration, knowing nothing of the torso: embedded explicit Runge-Kutta pairs
//! (Dormand-Prince 5(4) by default), a weighted RMS error norm with rtol/atol, PI step-size
//! control, FSAL, dense output, step size kept across calls, statistics, and a stiffness
//! detector that reports. Everything is generic over the [`Ode`] trait.
//!
//! Failures (non-finite state, step below its floor, too many rejections) are returned as
//! [`SolverError`]s and leave the caller's state at the last accepted step; nothing panics.

/// A first-order system of ordinary differential equations y' = f(t, y).
///
/// `rhs` takes `&mut self` so that implementations can keep preallocated scratch memory and
/// never allocate while the solver runs.
pub trait Ode {
    /// Number of state variables.
    fn dim(&self) -> usize;
    /// Writes f(t, y) into `dydt` (same length as `y`).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]);
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
    /// A high-order pair (code 2).
    HighOrder,
}

impl Method {
    /// All methods, by code.
    pub const ALL: [Method; 3] = [Method::Dopri5, Method::BogackiShampine3, Method::HighOrder];
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
}
