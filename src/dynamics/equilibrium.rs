//! The static equilibrium of the compiled model under held activations and airway-opening
//! pressure: the positions, at zero velocity, where every generalised force balances (rib
//! torques, the sternum's force and torque, the free vertices' forces), so that a run can
//! start on it instead of in a transient. This module owns how the equilibrium is found and
//! how far from balance a state is; when it is used (initialisation, reset) is the facade's.
//!
//! The equilibrium is found by damped relaxation: the equations of motion themselves,
//! activations held, integrated from a start state until the loads left at zero velocity are
//! small. Every motion of the model is damped (elements, springs, vertex foundation, airway
//! and abdominal viscosity), so the state settles on a stable equilibrium, and only on a
//! stable one; the integration error changes the path, not where it ends, because the
//! equilibrium is a fixed point of the right-hand side whatever the step. With zero
//! activation and the airway open to the surface the rest pose is the equilibrium by
//! construction (the preloads of `Model::compile` balance it), and the relaxation stops
//! before its first step.
//!
//! How far from balance: each generalised force is expressed as a force [N] (a rib's torque
//! divided by its longest lever, the distance from its hinge to its farthest anchor; the
//! sternum's torque likewise), and the largest is compared with the largest force any anchor
//! carries from the elements, membranes, springs and pressures. The ratio is the relative
//! imbalance: a state within a relative imbalance epsilon is displaced from the exact
//! equilibrium by about epsilon of the displacements those forces make, the same relative
//! measure the integrator's relative tolerance keeps.

use super::accelerations;
use super::model::{Model, RIBS};
use super::state::{Layout, error_weights};
use super::{Activations, Data, forces, kinematics, rhs};
use crate::solver::{ErrorWeights, Integrator, Method, Ode, Options};

/// Longest simulated time the relaxation may take [s]: ten 4 s quiet breaths; a model that
/// has not settled by then is reported as not converged.
pub const MAX_RELAXATION: f64 = 40.0;

/// Simulated time between two checks of the imbalance [s]: a check costs about one
/// right-hand-side evaluation, against the tens of steps the integration takes in this time;
/// the relaxation runs at most this much past the point where it settled.
const CHECK_INTERVAL: f64 = 0.1;

/// A solved static equilibrium.
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    /// The state: positions at equilibrium, every velocity zero.
    pub state: Vec<f64>,
    /// Largest unbalanced generalised force left at `state`, as a force [N] (module doc).
    pub residual: f64,
    /// Largest force on any anchor at `state` [N]: the scale of `residual`.
    pub force_scale: f64,
    /// Whether `residual <= tolerance * force_scale` was reached within
    /// [`MAX_RELAXATION`].
    pub converged: bool,
    /// Simulated time the relaxation took [s].
    pub relaxation_time: f64,
    /// Right-hand-side evaluations the relaxation took.
    pub rhs_evaluations: u64,
}

impl Equilibrium {
    /// `residual / force_scale`, the relative imbalance.
    pub fn relative_residual(&self) -> f64 {
        if self.force_scale > 0.0 {
            self.residual / self.force_scale
        } else {
            self.residual
        }
    }
}

/// The imbalance of `y`'s positions (its velocities taken as zero) under `act`: the largest
/// generalised force as a force [N], and the largest anchor force [N] (module doc).
pub fn imbalance(model: &Model, data: &mut Data, act: &Activations, y: &[f64]) -> (f64, f64) {
    let l = Layout::new(model);
    let mut still = y.to_vec();
    still[l.theta_dot..].fill(0.0);
    let mut load = vec![0.0; l.len];
    kinematics::positions_and_velocities(model, data, &l, &still);
    forces::accumulate(model, data, act);
    accelerations::forces_and_rates(model, data, &l, &still, &mut load);
    let scale = data.force.iter().map(|f| f.norm()).fold(0.0, f64::max);
    let mut residual: f64 = 0.0;
    for r in 0..RIBS {
        let lever = model.rib_anchors[r]
            .iter()
            .map(|&a| (model.rest[a as usize] - model.rib_head[r]).norm())
            .fold(0.0, f64::max);
        if lever > 0.0 {
            residual = residual.max(load[l.theta_dot + r].abs() / lever);
        }
    }
    let force = &load[l.sternum_v..l.sternum_v + 3];
    residual = residual.max(norm3(force));
    let lever = model
        .sternum_anchors
        .iter()
        .map(|&a| (model.rest[a as usize] - model.sternum_com).norm())
        .fold(0.0, f64::max);
    if lever > 0.0 {
        residual = residual.max(norm3(&load[l.sternum_w..l.sternum_w + 3]) / lever);
    }
    for f in load[l.vertex_v..].chunks_exact(3) {
        residual = residual.max(norm3(f));
    }
    (residual, scale)
}

fn norm3(v: &[f64]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The equations of motion with the activations held.
struct Held<'a> {
    model: &'a Model,
    data: &'a mut Data,
    act: Activations,
    weights: (Vec<u32>, Vec<f64>),
}

impl Ode for Held<'_> {
    fn dim(&self) -> usize {
        self.model.state_len()
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) {
        rhs(self.model, self.data, &self.act, y, dydt);
    }
    fn error_weights(&self) -> Option<ErrorWeights<'_>> {
        Some(ErrorWeights {
            reference: &self.weights.0,
            weight: &self.weights.1,
        })
    }
}

/// The static equilibrium under `act`, relaxed from the positions of `start` (its velocities
/// are ignored) until the relative imbalance is at most `tolerance` (module doc) or
/// [`MAX_RELAXATION`] has passed. `options` are the integrator's (its relative tolerance
/// sets the path's accuracy, not the equilibrium's). A failed integration returns the last
/// state reached, not converged.
pub fn solve(
    model: &Model,
    act: &Activations,
    start: &[f64],
    tolerance: f64,
    options: Options,
) -> Equilibrium {
    let l = Layout::new(model);
    let mut data = Data::new(model);
    let mut y = start.to_vec();
    y[l.theta_dot..].fill(0.0);
    let (mut residual, mut scale) = imbalance(model, &mut data, act, &y);
    let settled = |r: f64, s: f64| r <= tolerance * s;
    let mut t = 0.0;
    let mut evaluations = 0;
    if !settled(residual, scale)
        && let Ok(mut integrator) = Integrator::new(Method::Dopri5, options, y.len())
    {
        let mut held = Held {
            model,
            data: &mut data,
            act: *act,
            weights: error_weights(model),
        };
        while t < MAX_RELAXATION {
            let end = (t + CHECK_INTERVAL).min(MAX_RELAXATION);
            if integrator
                .integrate(&mut held, &mut t, &mut y, end)
                .is_err()
                || y.iter().any(|v| !v.is_finite())
            {
                break;
            }
            (residual, scale) = imbalance(model, held.data, act, &y);
            if settled(residual, scale) {
                break;
            }
        }
        evaluations = integrator.stats().rhs_evaluations;
    }
    if y.iter().any(|v| !v.is_finite()) {
        y = start.to_vec();
        (residual, scale) = imbalance(model, &mut data, act, &y);
    }
    y[l.theta_dot..].fill(0.0);
    Equilibrium {
        state: y,
        residual,
        force_scale: scale,
        converged: settled(residual, scale),
        relaxation_time: t,
        rhs_evaluations: evaluations,
    }
}

#[cfg(test)]
mod tests {
    use super::{imbalance, solve};
    use crate::anatomy::{Anatomy, MuscleGroup, Subject};
    use crate::dynamics::{Activations, Data, Layout, Model, Params, rest_state};
    use crate::solver::{Integrator, Method, Options};

    fn model() -> Model {
        let anatomy = Anatomy::build(&Subject::default(), 0).expect("builds");
        Model::compile(&anatomy, Params::for_posture(anatomy.subject.posture))
    }

    fn options() -> Options {
        Options {
            rtol: 1e-6,
            atol: 1e-8,
            ..Options::default()
        }
    }

    /// The quiet drive's activations at its start (`Drive::quiet` at t = 0: the rib-cage
    /// groups at half their 0.096 amplitude, the diaphragm at 0.12 (1 + sin 0.1)), held.
    fn inspiration() -> Activations {
        let mut groups = [0.0; 8];
        for g in [
            MuscleGroup::ExternalIntercostals,
            MuscleGroup::InternalIntercostals,
            MuscleGroup::Scalenes,
        ] {
            groups[g.index()] = 0.048;
        }
        groups[MuscleGroup::Diaphragm.index()] = 0.12 * (1.0 + 0.1f64.sin());
        Activations::new(&groups, 1.0, 1.0)
    }

    /// With every muscle relaxed and the airway open, the rest pose is the equilibrium (the
    /// preloads balance it): the solve stops on it, balanced to the tolerance.
    #[test]
    fn zero_activation_returns_the_rest_pose() {
        let model = model();
        let rest = rest_state(&model);
        let act = Activations::default();
        let at_rest = solve(&model, &act, &rest, 1e-6, options());
        assert!(at_rest.converged);
        assert_eq!(at_rest.relaxation_time, 0.0);
        assert_eq!(at_rest.state, rest);
        assert!(at_rest.relative_residual() <= 1e-6);
    }

    /// Under held inspiratory activation the solved state balances its loads to the
    /// tolerance asked (relative to the largest anchor force), where the rest pose under the
    /// same activation is far from balance; and the equations of motion started there stay
    /// there.
    #[test]
    fn held_activation_balances_and_stays() {
        let model = model();
        let act = inspiration();
        let rest = rest_state(&model);
        let eq = solve(&model, &act, &rest, 1e-6, options());
        assert!(
            eq.converged,
            "relative imbalance {}",
            eq.relative_residual()
        );
        assert!(eq.relative_residual() <= 1e-6);
        let mut data = Data::new(&model);
        let (r0, s0) = imbalance(&model, &mut data, &act, &rest);
        assert!(
            r0 / s0 > 1e3 * eq.relative_residual(),
            "rest: {r0} of {s0} N"
        );
        // one 4 s breath's time with the activation held
        struct Held<'a>(&'a Model, Data, Activations);
        impl crate::solver::Ode for Held<'_> {
            fn dim(&self) -> usize {
                self.0.state_len()
            }
            fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
                crate::dynamics::rhs(self.0, &mut self.1, &self.2, y, dy);
            }
        }
        let mut held = Held(&model, Data::new(&model), act);
        let mut integrator = Integrator::new(Method::Dopri5, options(), eq.state.len()).unwrap();
        let (mut t, mut y) = (0.0, eq.state.clone());
        integrator
            .integrate(&mut held, &mut t, &mut y, 4.0)
            .unwrap();
        let l = Layout::new(&model);
        // the drift is under 1 % of the displacement the activation made from rest
        let moved = |a: &[f64], b: &[f64]| {
            a[l.sternum_x..l.theta_dot]
                .iter()
                .zip(&b[l.sternum_x..l.theta_dot])
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max)
        };
        let made = moved(&eq.state, &rest);
        let drift = moved(&y, &eq.state);
        assert!(made > 1e-3, "activation moved the wall {made} m");
        assert!(drift < 0.01 * made, "drift {drift} m against {made} m");
    }
}
