//! The facade's quasi-static mode ([`crate::solver::Method::QuasiStatic`]): the state is the
//! lung volume, integrated by Dormand-Prince 5(4) with
//!
//! ```text
//! dV_L/dt = (P_ao - P_alv) / R_aw,   P_alv = P_pl + P_L(V_L),
//! ```
//!
//! P_pl the multiplier of the chest wall's static equilibrium holding V_L
//! ([`crate::dynamics::statics`]), P_L the lungs' recoil ([`crate::dynamics::pleural`]) and
//! R_aw the airway resistance. The positions are solved when something reads them (volumes
//! other than the lungs', pressures, markers), once per communication point, warm-started from
//! the last solution; the lung and thoracic volumes come from the state alone.

use super::{Applied, Torso};
use crate::Error;
use crate::dynamics::statics::{Statics, StaticsError, StaticsMemory};
use crate::dynamics::{Activations, Data, Model};
use crate::solver::Ode;
use serde::{Deserialize, Serialize};

/// Length of the held activations in the memory: three sides per muscle group, then the
/// airway-opening pressure.
const HELD_LEN: usize = 3 * crate::anatomy::MuscleGroup::COUNT + 1;

/// Litres per cubic metre: the reduced state is held in litres, so that the integrator's
/// absolute tolerance (1e-8 by default) is a volume the user reads.
const LITRES: f64 = 1e3;

/// The quasi-static memory of one torso.
#[derive(Clone, Debug)]
pub(crate) struct Quasi {
    /// The static solver and its last solution.
    pub(crate) statics: Statics,
    /// The lung volume [L] (the integrated state).
    pub(crate) volume: [f64; 1],
    /// Whether the facade's state vector holds the equilibrium at the current time.
    pub(crate) fresh: bool,
    /// The airflow at the current time [L/s] and the pleural pressure relative to rest [Pa],
    /// when `fresh`.
    pub(crate) flow: f64,
    pub(crate) pleural: f64,
    /// The last failure of a solve inside an integration, for the error message.
    pub(crate) failure: Option<StaticsError>,
    /// The activations the positions at the current time balance: those of the last step's
    /// end (or of the start, a reset or a set state). An input set since acts from the next
    /// step on, as it does on the inertial formulation's state, so that what is read at a
    /// communication point does not depend on whether it was read before the inputs were
    /// set (no direct feedthrough, as `<ModelStructure>` declares).
    pub(crate) held: Activations,
}

/// What a snapshot keeps of the quasi-static mode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct QuasiMemory {
    /// The lung volume [L].
    pub volume: f64,
    /// The static solver's memory.
    pub statics: StaticsMemory,
    /// Whether the positions were those of the current time, and if so the airflow [L/s]
    /// and pleural pressure relative to rest [Pa] there.
    pub fresh: bool,
    /// Airflow [L/s] (when `fresh`).
    pub flow: f64,
    /// Pleural pressure relative to rest [Pa] (when `fresh`).
    pub pleural: f64,
    /// The activations the positions at the current time balance (levels, then the
    /// airway-opening pressure); memories written before it existed give the activations
    /// applied at the restored time.
    #[serde(default)]
    pub held: Option<Vec<f64>>,
}

/// The displacement tolerance of the static solves for an integrator's relative tolerance:
/// 1e-2 rtol in metres (1e-8 m at the default 1e-6), at most 1e-8 m: measured on 4 s of
/// quiet breathing at level 0 (`tests/quasi_static.rs`), 1e-2 rtol left the lung volume's
/// error at rtol 1e-6 and 1e-8 as it was with 1e-3 rtol (1.24e-6 and 1.29e-8 L) with 30 %
/// fewer Newton iterations, but at rtol 1e-4 it let the solves' error through (4.9e-4 L
/// against 3.5e-6 L), hence the cap.
pub(crate) fn statics_tolerance(rtol: f64) -> f64 {
    (1e-2 * rtol).clamp(1e-13, 1e-8)
}

/// The lung volume [L] held by a thoracic mesh volume [m^3].
pub(crate) fn lung_of(model: &Model, thorax_mesh: f64) -> f64 {
    (thorax_mesh - model.dome_faceting_volume - model.non_lung_volume) * LITRES
}

/// The thoracic mesh volume [m^3] that holds a lung volume [L].
pub(crate) fn thorax_of(model: &Model, lung: f64) -> f64 {
    lung / LITRES + model.dome_faceting_volume + model.non_lung_volume
}

/// The airflow into the lungs [L/s] at lung volume `lung` [L] and pleural pressure `pleural`
/// (relative to rest) [Pa] under `act`.
pub(crate) fn airflow(model: &Model, act: &Activations, lung: f64, pleural: f64) -> f64 {
    let recoil = model.pleural.recoil(thorax_of(model, lung));
    (act.airway_opening - pleural - recoil) / model.airway_resistance * LITRES
}

impl Quasi {
    /// A quasi-static memory starting at state `y` (an equilibrium of `act`, velocities zero)
    /// with its pleural pressure `pleural`.
    pub(crate) fn new(model: &Model, y: &[f64], pleural: f64, act: &Activations) -> Quasi {
        let statics = Statics::new(model, y, act);
        let mut q = Quasi {
            volume: [lung_of(model, statics.volume())],
            statics,
            fresh: true,
            flow: 0.0,
            pleural,
            failure: None,
            held: *act,
        };
        q.reset(model, y, pleural, act);
        q
    }

    /// Restarts from state `y`, an equilibrium of `act` at pleural pressure `pleural`.
    pub(crate) fn reset(&mut self, model: &Model, y: &[f64], pleural: f64, act: &Activations) {
        self.statics.reset(model, y, pleural, act);
        self.volume = [lung_of(model, self.statics.volume())];
        self.pleural = pleural;
        self.flow = airflow(model, act, self.volume[0], pleural);
        self.fresh = true;
        self.failure = None;
        self.held = *act;
    }

    /// What a snapshot keeps.
    pub(crate) fn memory(&self) -> QuasiMemory {
        QuasiMemory {
            volume: self.volume[0],
            statics: self.statics.memory(),
            fresh: self.fresh,
            flow: self.flow,
            pleural: self.pleural,
            held: Some(self.statics_act_vec()),
        }
    }

    fn statics_act_vec(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self.held.level.iter().flatten().copied().collect();
        v.push(self.held.airway_opening);
        v
    }

    /// Restores [`Quasi::memory`] (the factorisation re-evaluated where it was taken, so
    /// that the run continues bit for bit); on error nothing is usable and the caller keeps
    /// its own state.
    pub(crate) fn restore(
        &mut self,
        model: &Model,
        data: &mut Data,
        memory: &QuasiMemory,
    ) -> Result<(), StaticsError> {
        if !memory.volume.is_finite() {
            return Err(StaticsError::NonFinite);
        }
        let held = memory
            .held
            .as_deref()
            .unwrap_or(&memory.statics.activations);
        if held.len() != HELD_LEN || held.iter().any(|v| !v.is_finite()) {
            return Err(StaticsError::NonFinite);
        }
        self.statics.restore(model, data, &memory.statics)?;
        self.volume = [memory.volume];
        self.fresh = memory.fresh;
        self.flow = memory.flow;
        self.pleural = memory.pleural;
        self.failure = None;
        for (g, sides) in self.held.level.iter_mut().enumerate() {
            sides.copy_from_slice(&held[3 * g..3 * g + 3]);
        }
        self.held.airway_opening = held[HELD_LEN - 1];
        Ok(())
    }
}

/// The reduced system seen by the integrator.
pub(super) struct QuasiSystem<'a> {
    pub(super) model: &'a Model,
    pub(super) data: &'a mut Data,
    pub(super) statics: &'a mut Statics,
    pub(super) applied: Applied<'a>,
    pub(super) tolerance: f64,
    pub(super) failure: &'a mut Option<StaticsError>,
}

impl Ode for QuasiSystem<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let act = self.applied.activations(t);
        let target = thorax_of(self.model, y[0]);
        dydt[0] = match self
            .statics
            .solve(self.model, self.data, t, &act, target, self.tolerance)
        {
            Ok(pleural) => airflow(self.model, &act, y[0], pleural),
            Err(e) => {
                // a non-finite rate makes the integrator reject the step and shorten it
                self.failure.get_or_insert(e);
                f64::NAN
            }
        };
    }
}

impl Torso {
    /// In quasi-static mode, solves the positions at the current time if they are not
    /// current: the equilibrium holding the integrated lung volume under the activations
    /// applied now. Nothing in the other modes.
    pub(super) fn current_positions(&mut self) {
        let time = self.time;
        let tolerance = super::quasi::statics_tolerance(self.config.solver.rtol);
        let Torso {
            compiled,
            data,
            quasi,
            y,
            ..
        } = self;
        let Some(q) = quasi.as_deref_mut() else {
            return;
        };
        if q.fresh {
            return;
        }
        let act = q.held;
        let model = &compiled.model;
        let target = thorax_of(model, q.volume[0]);
        match q.statics.solve(model, data, time, &act, target, tolerance) {
            Ok(pleural) => {
                y.copy_from_slice(q.statics.state());
                q.pleural = pleural;
                q.flow = airflow(model, &act, q.volume[0], pleural);
            }
            Err(e) => {
                // the last solution stays; the pressures say that this one failed
                q.pleural = f64::NAN;
                q.flow = f64::NAN;
                q.failure = Some(e);
            }
        }
        q.fresh = true;
    }
}

impl Torso {
    /// In quasi-static mode, the reduced right-hand side for external integrators: the
    /// airflow into the lungs dV_L/dt [L/s] at time `t` and lung volume `lung_volume` [L],
    /// with the current inputs plus the drive (and tone) at `t`, the same function the model's own
    /// integrator steps ([`QuasiSystem`]: the static equilibrium holding that volume solved
    /// to the tolerance of the configured `solver.rtol`). The time, the lung volume and the
    /// inputs do not change; the static solver keeps the equilibrium as a warm start (what
    /// is solved later agrees with a fresh model's to the solves' tolerance, not bit for
    /// bit). An error in the other modes ([`Error::State`]), for a non-finite time or a
    /// volume that is not positive ([`Error::InvalidParameter`]), and when the equilibrium
    /// cannot be solved ([`Error::Numerical`], naming subject, posture and activations).
    pub fn quasi_rate(&mut self, t: f64, lung_volume: f64) -> crate::Result<f64> {
        self.check_reduced_state(t, lung_volume)?;
        let tolerance = statics_tolerance(self.config.solver.rtol);
        let mut failure = None;
        let mut rate = [0.0];
        {
            let Torso {
                compiled,
                data,
                inputs,
                airway_opening,
                config,
                quasi,
                ..
            } = self;
            let Some(q) = quasi.as_deref_mut() else {
                return Err(not_quasi_static());
            };
            let mut system = QuasiSystem {
                model: &compiled.model,
                data,
                statics: &mut q.statics,
                applied: Applied::new(
                    config,
                    &compiled.model.params,
                    *inputs,
                    *airway_opening,
                    None,
                ),
                tolerance,
                failure: &mut failure,
            };
            system.rhs(t, &[lung_volume], &mut rate);
        }
        match failure {
            Some(e) => Err(Error::Numerical {
                time: t,
                reason: format!(
                    "the reduced right-hand side at lung volume {lung_volume} L: {e} ({})",
                    self.describe_scene_at(t)
                ),
            }),
            None if !rate[0].is_finite() => Err(Error::Numerical {
                time: t,
                reason: format!(
                    "the reduced right-hand side at lung volume {lung_volume} L is {}",
                    rate[0]
                ),
            }),
            None => Ok(rate[0]),
        }
    }

    /// In quasi-static mode, sets the time and the integrated state, the lung volume [L], for
    /// external integrators of [`Torso::quasi_rate`]: what is read afterwards is that of the
    /// equilibrium holding `lung_volume` under the activations applied at `t` (solved when
    /// read, warm-started), and the next [`Torso::advance_to`] continues from it. Errors as
    /// [`Torso::quasi_rate`]'s; on error nothing changes.
    pub fn set_lung_volume(&mut self, t: f64, lung_volume: f64) -> crate::Result<()> {
        self.check_reduced_state(t, lung_volume)?;
        let held = self.applied(t);
        let Some(q) = self.quasi.as_deref_mut() else {
            return Err(not_quasi_static());
        };
        q.volume = [lung_volume];
        q.held = held;
        q.fresh = false;
        q.failure = None;
        self.time = t;
        self.at_start = false;
        self.integrator.invalidate();
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        Ok(())
    }

    /// The checks of [`Torso::quasi_rate`]'s and [`Torso::set_lung_volume`]'s arguments.
    fn check_reduced_state(&self, t: f64, lung_volume: f64) -> crate::Result<()> {
        if self.quasi.is_none() {
            return Err(not_quasi_static());
        }
        if !t.is_finite() {
            return Err(Error::invalid("time", t, "a finite time"));
        }
        if !(lung_volume.is_finite() && lung_volume > 0.0) {
            return Err(Error::invalid(
                "lung volume",
                lung_volume,
                "a finite volume > 0 L",
            ));
        }
        Ok(())
    }
}

/// The error of the reduced state's functions outside quasi-static mode.
fn not_quasi_static() -> Error {
    Error::State(
        "the reduced state (the lung volume alone) exists in quasi-static mode only \
         (solver.method 4, quasi-static); the other methods integrate the full state"
            .into(),
    )
}
