//! [`Torso`]: the model facade.

use super::{Checkpoint, Config, Drive, Quantity, Snapshot};
use crate::anatomy::{Anatomy, MuscleGroup, Posture};
use crate::dynamics::equilibrium::Equilibrium;
use crate::dynamics::jacobian::TorsoJacobian;
use crate::dynamics::{self, Activations, Data, GravityLoads, Model, Params};
use crate::observe::markers::{MarkerCache, MarkerOutputs};
use crate::observe::{self, Compartments, Observation};
use crate::solver::{
    ErrorWeights, Integrator, Jacobian, JacobianStructure, Method, Ode, Options, Stats, StiffOde,
};
use crate::{Error, Result};
use std::sync::{Arc, Mutex};

mod markers;
mod quasi;
mod sampled;

pub use quasi::QuasiMemory;
use quasi::{Quasi, QuasiSystem};

pub use sampled::Sample;

/// Allowed pressure at the airway opening [Pa]: +-50 cmH2O, beyond the peak pressures of
/// mechanical ventilation (lung-protective ventilation keeps the plateau at or below 30
/// cmH2O; ARDS Network 2000, N Engl J Med 342:1301).
pub const AIRWAY_OPENING_RANGE: (f64, f64) = (-50.0 * 98.0665, 50.0 * 98.0665);

/// The gain of each group on each side: the side's overall gain times the group's.
fn side_gains(config: &Config) -> ([f64; MuscleGroup::COUNT], [f64; MuscleGroup::COUNT]) {
    let g = &config.group_gains;
    (
        g.right.map(|x| x * config.gain_right),
        g.left.map(|x| x * config.gain_left),
    )
}

/// Statistics of one [`Torso::advance_to`] call.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdvanceStats {
    /// Accepted steps in this call.
    pub steps: u64,
    /// Rejected steps in this call.
    pub rejected: u64,
    /// Right-hand-side evaluations in this call.
    pub rhs_evaluations: u64,
}

/// Options of [`Torso::advance_to_with`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdvanceOptions {
    /// Check the state the step ends in against the physiological bounds
    /// ([`Torso::physiology_violation`]); a step that leaves them is rolled back and fails
    /// with [`Error::Unphysiological`]. The FMU, the C ABI and `torso simulate` step with it.
    pub check_physiology: bool,
}

/// The compiled, immutable part of a torso, shareable between instances and threads.
#[derive(Debug)]
pub struct Compiled {
    /// The anatomy (rest-pose geometry).
    pub anatomy: Anatomy,
    /// The compiled dynamics.
    pub model: Model,
    /// Wall regions for the displaced compartments.
    pub compartments: Compartments,
    /// Fingerprint of `model`.
    pub fingerprint: u64,
    /// The error weighting of the state for the step-size control
    /// ([`dynamics::error_weights`]): reference component and weight of each.
    pub error_weights: (Vec<u32>, Vec<f64>),
    /// Skin and marker grids, built when markers are first read.
    pub markers: MarkerCache,
    /// The static equilibria solved so far, per applied activations (airway-opening pressure
    /// included), most recent last; at most [`EQUILIBRIUM_CACHE`] are kept.
    pub equilibria: Mutex<Vec<(Activations, Arc<Equilibrium>)>>,
    /// Thorax, abdomen and trunk volumes of the rest state [L], computed when first needed
    /// ([`Compiled::rest_volumes`]).
    pub rest_volumes: std::sync::OnceLock<[f64; 3]>,
}

/// How many static equilibria a compiled model keeps (a fit varying the drive solves a new
/// one per drive; a simulation or an FMU instance needs one).
pub const EQUILIBRIUM_CACHE: usize = 16;

impl Config {
    /// The constants of the dynamics this configuration compiles with: its `params` when set,
    /// else the defaults of its posture and muscle law ([`Params::for_posture_and_law`]; under
    /// gravity acting the standing ones, every posture being the standing anatomy) with its
    /// gravity, its gravity loads, the true posture's abdominal tone, scaled with gravity
    /// ([`crate::dynamics::abdominal_tone`]), or none when its `postural_tone` is off, and
    /// the true posture's expiratory rib-cage drive
    /// ([`crate::dynamics::expiration_with_abdominals`]).
    pub fn model_params(&self) -> Params {
        self.params.clone().unwrap_or_else(|| {
            let posture = self.subject.posture;
            let built = if self.gravity_loads == GravityLoads::Acting {
                Posture::Standing
            } else {
                posture
            };
            let mut p = Params::for_posture_and_law(built, self.muscle_law);
            p.gravity = self.gravity;
            p.gravity_loads = self.gravity_loads;
            p.abdominal_tone = if self.postural_tone {
                crate::dynamics::abdominal_tone(posture, self.muscle_law) * self.gravity
                    / crate::dynamics::GRAVITY
            } else {
                0.0
            };
            p.expiration_with_abdominals =
                crate::dynamics::expiration_with_abdominals(posture, self.muscle_law);
            p
        })
    }
}

impl Compiled {
    /// Builds the anatomy and compiles the dynamics for `config` (subject, posture, level of
    /// detail).
    pub fn build(config: &Config) -> Result<Compiled> {
        config.validate()?;
        let acting = config
            .params
            .as_ref()
            .map_or(config.gravity_loads, |p| p.gravity_loads)
            == GravityLoads::Acting;
        // Under gravity acting every posture is the standing anatomy with its tables, gravity
        // turned (`dynamics::GravityLoads::Acting`).
        let posture = config.subject.posture;
        let mut built = config.subject.clone();
        if acting {
            built.posture = Posture::Standing;
        }
        let anatomy = Anatomy::build_on(
            &built,
            config.scene.level_of_detail,
            config.subject_mesh_dir.as_deref(),
        )?;
        let params = config.model_params();
        let mut model = if acting {
            Model::compile_in(&anatomy, params, posture)
        } else {
            Model::compile(&anatomy, params)
        };
        model.set_lung_fraction(config.lung_ratio);
        Ok(Compiled::from_model(anatomy, model))
    }

    /// Wraps an anatomy and the model compiled from it (for experiments that compile a
    /// modified anatomy or model).
    pub fn from_model(anatomy: Anatomy, model: Model) -> Compiled {
        Compiled {
            error_weights: dynamics::error_weights(&model),
            compartments: Compartments::new(&model),
            fingerprint: model.fingerprint(),
            anatomy,
            model,
            markers: MarkerCache::default(),
            equilibria: Mutex::new(Vec::new()),
            rest_volumes: std::sync::OnceLock::new(),
        }
    }

    /// The static equilibrium under `act` ([`dynamics::equilibrium::solve`] from the rest
    /// state, relative imbalance at most `tolerance`), solved once and cached for later calls
    /// with the same activations and a tolerance the cached state meets; a solve that did not
    /// converge (its `converged` flag false) is cached as it ended and reused for the same
    /// tolerance, since running it again gives the same state. `converged` is judged against
    /// this call's `tolerance`.
    pub fn equilibrium(
        &self,
        act: &Activations,
        tolerance: f64,
        options: Options,
    ) -> Arc<Equilibrium> {
        // a panic elsewhere while the cache was held leaves it valid: entries are whole
        let lock = || {
            self.equilibria
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner())
        };
        // A solve that did not settle is deterministic too: the same activations and
        // tolerance give the same state, so it is reused rather than run again.
        if let Some((_, e)) = lock().iter().find(|(a, e)| {
            a == act
                && (e.relative_residual() <= tolerance
                    || (!e.converged && e.tolerance == tolerance))
        }) {
            // judged against this caller's tolerance, which may be looser than the solve's
            let converged = e.relative_residual() <= tolerance;
            if converged == e.converged {
                return e.clone();
            }
            return Arc::new(Equilibrium {
                converged,
                tolerance,
                ..(**e).clone()
            });
        }
        let start = dynamics::rest_state(&self.model);
        let solved = Arc::new(dynamics::equilibrium::solve(
            &self.model,
            act,
            &start,
            tolerance,
            options,
        ));
        {
            let mut cache = lock();
            if cache.len() >= EQUILIBRIUM_CACHE {
                cache.remove(0);
            }
            cache.push((*act, solved.clone()));
        }
        solved
    }
}

/// What acts on the model over an integration: inputs, airway-opening pressure, drive and
/// gains, giving the activations clamp(input + drive + tone, 0, 1) at any time.
struct Applied<'a> {
    inputs: [f64; MuscleGroup::COUNT],
    /// Pressure at the airway opening [Pa].
    airway_opening: f64,
    /// The occluded airway's dry gas content [Pa m^3] (`None`: open).
    occlusion: Option<f64>,
    drive: &'a Drive,
    /// Gain of each group on the right and left sides (overall side gain times group gain).
    gains: ([f64; MuscleGroup::COUNT], [f64; MuscleGroup::COUNT]),
    /// Each group's tone ([`tones`]).
    tone: [f64; MuscleGroup::COUNT],
    /// Whether the internal intercostals take the drive's abdominal wave
    /// ([`crate::dynamics::Params::expiration_with_abdominals`]).
    expiration_with_abdominals: bool,
}

/// Each group's tonic activation under `params`: the abdominal wall's tone
/// ([`crate::dynamics::Params::abdominal_tone`]) on its four muscles, none on the others.
fn tones(params: &crate::dynamics::Params) -> [f64; MuscleGroup::COUNT] {
    let mut tone = [0.0; MuscleGroup::COUNT];
    for g in [
        MuscleGroup::TransversusAbdominis,
        MuscleGroup::RectusAbdominis,
        MuscleGroup::ExternalObliques,
        MuscleGroup::InternalObliques,
    ] {
        tone[g.index()] = params.abdominal_tone;
    }
    tone
}

impl<'a> Applied<'a> {
    /// What acts on a model compiled with `params` under `config` (its drive and side gains),
    /// with these inputs, airway-opening pressure and occlusion: the tone and the posture's
    /// expiratory drive are the constants'.
    fn new(
        config: &'a Config,
        params: &crate::dynamics::Params,
        inputs: [f64; MuscleGroup::COUNT],
        airway_opening: f64,
        occlusion: Option<f64>,
    ) -> Applied<'a> {
        Applied {
            inputs,
            airway_opening,
            occlusion,
            drive: &config.drive,
            gains: side_gains(config),
            tone: tones(params),
            expiration_with_abdominals: params.expiration_with_abdominals,
        }
    }

    /// Each group's applied activation at time `t`: clamp(input + drive + tone, 0, 1), the
    /// internal intercostals' drive the abdominal family's wave where the posture couples
    /// them ([`crate::dynamics::Params::expiration_with_abdominals`]).
    fn groups(&self, t: f64) -> [f64; MuscleGroup::COUNT] {
        let mut groups = [0.0; MuscleGroup::COUNT];
        for g in MuscleGroup::ALL {
            let wave = if g == MuscleGroup::InternalIntercostals && self.expiration_with_abdominals
            {
                MuscleGroup::TransversusAbdominis
            } else {
                g
            };
            groups[g.index()] =
                (self.inputs[g.index()] + self.drive.activation(wave, t) + self.tone[g.index()])
                    .clamp(0.0, 1.0);
        }
        groups
    }

    fn activations(&self, t: f64) -> Activations {
        Activations::per_group(&self.groups(t), &self.gains.0, &self.gains.1)
            .with_airway_opening(self.airway_opening)
            .with_occlusion(self.occlusion)
    }
}

/// The ODE seen by the solver: the model with activations = clamp(input + drive + tone, 0, 1).
struct System<'a> {
    model: &'a Model,
    /// Error weighting of the state ([`Compiled::error_weights`]).
    weights: &'a (Vec<u32>, Vec<f64>),
    data: &'a mut Data,
    applied: Applied<'a>,
    /// Jacobian memory, when the stiff method is in use.
    jacobian: Option<&'a mut TorsoJacobian>,
}

impl System<'_> {
    fn activations(&self, t: f64) -> Activations {
        self.applied.activations(t)
    }
}

impl Ode for System<'_> {
    fn dim(&self) -> usize {
        self.model.state_len()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) {
        let act = self.activations(t);
        dynamics::rhs(self.model, self.data, &act, y, dydt);
    }
    fn error_weights(&self) -> Option<ErrorWeights<'_>> {
        Some(ErrorWeights {
            reference: &self.weights.0,
            weight: &self.weights.1,
        })
    }
    fn as_stiff(&mut self) -> Option<&mut dyn StiffOde> {
        if self.jacobian.is_some() {
            Some(self)
        } else {
            None
        }
    }
}

impl StiffOde for System<'_> {
    fn jacobian_structure(&mut self) -> JacobianStructure {
        match &self.jacobian {
            Some(j) => j.structure(),
            None => JacobianStructure::default(),
        }
    }
    fn jacobian(&mut self, t: f64, y: &[f64], f0: &[f64], jac: &mut Jacobian) -> u64 {
        let act = self.activations(t);
        match &mut self.jacobian {
            Some(j) => j.evaluate(self.model, self.data, &act, y, f0, jac),
            None => 0,
        }
    }
}

/// A breathing torso: a compiled model plus its mutable data.
pub struct Torso {
    config: Config,
    compiled: Arc<Compiled>,
    data: Data,
    y: Vec<f64>,
    time: f64,
    inputs: [f64; MuscleGroup::COUNT],
    /// Pressure at the airway opening [Pa] (an input, like the activations).
    airway_opening: f64,
    /// The airway occluded: the lungs' dry gas content [Pa m^3] fixed when it closed
    /// ([`Torso::set_airway_occluded`]); `None` open.
    occlusion: Option<f64>,
    integrator: Integrator,
    observation: Option<Observation>,
    /// Each side's share of the observation (right, left), computed when first read.
    sides: Option<[observe::SideObservation; 2]>,
    markers: MarkerOutputs,
    /// Marker set read instead of the grid ([`Torso::set_marker_set`]).
    marker_set: Option<Arc<crate::anatomy::skin::MarkerSet>>,
    /// Jacobian pattern and scratch of the stiff method (built when it is used).
    jacobian: Option<Box<TorsoJacobian>>,
    /// Whether the state is still the start state (built or reset, started at equilibrium,
    /// not advanced since): a new drive then moves the start to its equilibrium.
    at_start: bool,
    /// The state before the current [`Torso::advance_to_with`] step, to roll back to (buffers
    /// reused from step to step).
    step_start: Checkpoint,
    /// The quasi-static mode's memory ([`Method::QuasiStatic`]; `None` in the others).
    quasi: Option<Box<Quasi>>,
}

/// Loosest relative tolerance of the quasi-static mode's start equilibrium (the default
/// `solver.rtol`; [`Torso::settle`]).
const QUASI_START_RTOL: f64 = 1e-6;

/// Loosest absolute tolerance of the quasi-static mode's start equilibrium (the default
/// `solver.atol`).
const QUASI_START_ATOL: f64 = 1e-8;

fn solver_options(config: &Config) -> Options {
    Options {
        rtol: config.solver.rtol,
        atol: config.solver.atol,
        h_max: config.solver.max_step,
        ..Options::default()
    }
}

impl Torso {
    /// Builds the model for `config` (validated first; the error names the bad field).
    pub fn new(config: Config) -> Result<Torso> {
        let compiled = Arc::new(Compiled::build(&config)?);
        Torso::with_compiled(config, compiled)
    }

    /// [`Torso::new`] left at the rest pose ([`Torso::start_at_rest`]) without solving the
    /// drive's start equilibrium: for fits and measurements that start from rest and would
    /// discard that solve.
    pub fn new_at_rest(config: Config) -> Result<Torso> {
        let compiled = Arc::new(Compiled::build(&config)?);
        Torso::with_compiled_at_rest(config, compiled)
    }

    /// An instance sharing an already compiled model (built from the same subject, posture
    /// and level of detail); used by fits and batches to compile once.
    pub fn with_compiled(config: Config, compiled: Arc<Compiled>) -> Result<Torso> {
        let mut torso = Torso::with_compiled_at_rest(config, compiled)?;
        torso.start_at_equilibrium();
        Ok(torso)
    }

    /// [`Torso::with_compiled`] left at the rest pose, as [`Torso::new_at_rest`].
    pub fn with_compiled_at_rest(config: Config, compiled: Arc<Compiled>) -> Result<Torso> {
        config.validate()?;
        let model = &compiled.model;
        if model.lung_fraction != config.lung_ratio {
            return Err(Error::invalid(
                "lung.ratio",
                config.lung_ratio,
                format!("{} (the compiled model's rest split)", model.lung_fraction),
            ));
        }
        let y = dynamics::rest_state(model);
        let quasi = (config.solver.method == Method::QuasiStatic)
            .then(|| Box::new(Quasi::new(model, &y, 0.0, &Activations::default())));
        let dim = if quasi.is_some() { 1 } else { y.len() };
        let integrator = Integrator::new(config.solver.method, solver_options(&config), dim)
            .map_err(|e| Error::invalid("solver", e.to_string(), "valid solver options"))?;
        Ok(Torso {
            data: Data::new(model),
            y,
            time: 0.0,
            inputs: [0.0; MuscleGroup::COUNT],
            airway_opening: 0.0,
            occlusion: None,
            integrator,
            observation: None,
            sides: None,
            markers: MarkerOutputs::default(),
            marker_set: None,
            jacobian: (config.solver.method == Method::Rosenbrock)
                .then(|| Box::new(TorsoJacobian::full(model))),
            config,
            compiled,
            at_start: false,
            step_start: Checkpoint::default(),
            quasi,
        })
    }

    /// Fixes the start: later drive changes act from the current state as steps, without
    /// moving the start to their equilibrium (the FMU calls it when its initialisation ends;
    /// docs/dynamics.md, "The start state").
    pub fn fix_start(&mut self) {
        self.at_start = false;
    }

    /// The activations applied at time `t` with the current inputs, drive and airway-opening
    /// pressure.
    pub(crate) fn applied(&self, t: f64) -> Activations {
        self.applying().activations(t)
    }

    /// What is applied now: the current inputs, drive, gains, tone and airway.
    fn applying(&self) -> Applied<'_> {
        Applied::new(
            &self.config,
            &self.compiled.model.params,
            self.inputs,
            self.airway_opening,
            self.occlusion,
        )
    }

    /// Puts the model at the static equilibrium of the activations applied now (inputs plus
    /// the drive's value at the current time) and the current airway-opening pressure, at rest
    /// (every velocity zero), so that a run started here has no start-up transient
    /// ([`dynamics::equilibrium`]; docs/dynamics.md, "The start state"). The equilibrium is
    /// solved once per compiled model and activations and then cached
    /// ([`Compiled::equilibrium`]); its relative imbalance is at most the solver's relative
    /// tolerance. Called when the model is built and reset; call it after setting the
    /// inputs a run starts with (the FMU does at the end of its initialisation). Returns the
    /// equilibrium (its `converged` flag false if Newton stalled and the relaxation did not settle in
    /// [`dynamics::equilibrium::MAX_RELAXATION`]; the state is then where it got to).
    pub fn start_at_equilibrium(&mut self) -> Arc<Equilibrium> {
        self.settle()
    }

    /// Puts the model at its rest pose at rest (every muscle relaxed, the airway open to the
    /// surface: the equilibrium of zero activation, [`dynamics::rest_state`]), whatever the
    /// drive's start; a later drive change does not move it. The fits start here and
    /// discard the start-up breath themselves.
    pub fn start_at_rest(&mut self) {
        self.y = dynamics::rest_state(&self.compiled.model);
        if let Some(q) = self.quasi.as_deref_mut() {
            q.reset(&self.compiled.model, &self.y, 0.0, &Activations::default());
        }
        self.integrator.invalidate();
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        self.at_start = false;
    }

    /// [`Torso::start_at_equilibrium`]'s work.
    fn settle(&mut self) -> Arc<Equilibrium> {
        let act = self.applied(self.time);
        // The quasi-static mode's start is where its Newton iterations begin: solved no looser
        // than the default tolerances (rtol 1e-6, atol 1e-8), since at rtol 1e-3 and atol
        // 1e-5 the start left the first solve outside their reach (level 1, quiet drive: "did
        // not converge", last correction 3.2e-3 m; `tests/quasi_static.rs`).
        let (rtol, atol) = match self.quasi {
            Some(_) => (
                self.config.solver.rtol.min(QUASI_START_RTOL),
                self.config.solver.atol.min(QUASI_START_ATOL),
            ),
            None => (self.config.solver.rtol, self.config.solver.atol),
        };
        let tolerance = rtol;
        let options = Options {
            rtol,
            atol,
            ..Options::default()
        };
        let solved = self.compiled.equilibrium(&act, tolerance, options);
        self.y.copy_from_slice(&solved.state);
        if let Some(q) = self.quasi.as_deref_mut() {
            // the airway is open and nothing flows: the pleural pressure balances the recoil
            let model = &self.compiled.model;
            let thorax = dynamics::statics::volume_of(model, &self.y);
            let pleural = act.airway_opening - model.pleural.recoil(thorax);
            q.reset(model, &self.y, pleural, &act);
        }
        self.integrator.invalidate();
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        self.at_start = true;
        solved
    }

    /// The compiled model (shareable).
    pub fn compiled(&self) -> &Arc<Compiled> {
        &self.compiled
    }

    /// The configuration the model was built from (with the current drive).
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Current simulated time [s].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Sets the activation input of `group` (in [0, 1]); a rejected value leaves the state as it was.
    pub fn set_activation(&mut self, group: MuscleGroup, value: f64) -> Result<()> {
        super::check(&format!("activation.{}", group.name()), value, (0.0, 1.0))?;
        if self.inputs[group.index()] != value {
            self.inputs[group.index()] = value;
            self.integrator.invalidate();
        }
        Ok(())
    }

    /// Sets the pressure at the airway opening relative to the body surface [Pa], within
    /// [`AIRWAY_OPENING_RANGE`] (0 breathing air; a ventilator's pressure; negative for
    /// negative-pressure ventilation). It acts on the alveolar and pleural pressures at once
    /// and on the volumes through the dynamics; a rejected value leaves the state as it was.
    pub fn set_airway_opening(&mut self, pressure: f64) -> Result<()> {
        super::check("pressure.airway_opening", pressure, AIRWAY_OPENING_RANGE)?;
        if self.airway_opening != pressure {
            self.airway_opening = pressure;
            self.integrator.invalidate();
            self.observation = None;
            self.sides = None;
        }
        Ok(())
    }

    /// The pressure at the airway opening [Pa].
    pub fn airway_opening(&self) -> f64 {
        self.airway_opening
    }

    /// Occludes the airway at the mouth (`true`) or opens it (`false`). Occluding fixes the
    /// lungs' dry gas content at the current state, (P_B + P_alv - P_H2O) V_lung with the
    /// alveolar pressure of that moment; from then on no gas flows (`flow.airway` reads 0),
    /// the alveolar pressure follows Boyle's law as the thoracic wall moves, and the mouth
    /// pressure equals it ([`crate::dynamics::airway`]). Opening restores the airflow through
    /// the airway resistance from the pressure difference of the moment. Occluding an occluded
    /// airway or opening an open one changes nothing. The quasi-static formulation
    /// (`solver.method` quasi-static) refuses an occlusion: its state is the lung volume,
    /// which an occluded airway ties to the equilibrium by the gas law instead of the airflow,
    /// and that constraint is not solved there; the state is then left as it was.
    pub fn set_airway_occluded(&mut self, occluded: bool) -> Result<()> {
        if occluded == self.occlusion.is_some() {
            return Ok(());
        }
        if occluded && self.quasi.is_some() {
            return Err(Error::invalid(
                "airway.occluded",
                "true",
                "false under solver.method quasi-static (an occluded airway is simulated by \
                 the inertial methods only)",
            ));
        }
        self.occlusion = if occluded {
            let o = self.observation();
            Some(dynamics::airway::gas_content(o.lung, o.alveolar_pressure))
        } else {
            None
        };
        self.integrator.invalidate();
        self.observation = None;
        self.sides = None;
        Ok(())
    }

    /// Whether the airway is occluded ([`Torso::set_airway_occluded`]).
    pub fn airway_occluded(&self) -> bool {
        self.occlusion.is_some()
    }

    /// The occluded lungs' dry gas content (P_B + P_alv - P_H2O) V_gas [Pa m^3] fixed when the
    /// airway closed; `None` while it is open.
    pub fn occluded_gas_content(&self) -> Option<f64> {
        self.occlusion
    }

    /// The activation input of `group`.
    pub fn activation_input(&self, group: MuscleGroup) -> f64 {
        self.inputs[group.index()]
    }

    /// The activation applied to `group` now: clamp(input + drive + tone, 0, 1), the tone the
    /// posture's ([`crate::dynamics::Params::abdominal_tone`]).
    pub fn applied_activation(&self, group: MuscleGroup) -> f64 {
        self.applying().groups(self.time)[group.index()]
    }

    /// Replaces the drive (validated first).
    pub fn set_drive(&mut self, drive: Drive) -> Result<()> {
        drive.validate()?;
        if drive != self.config.drive {
            self.config.drive = drive;
            self.integrator.invalidate();
            if self.at_start {
                self.start_at_equilibrium();
            }
        }
        Ok(())
    }

    /// What one integration call borrows at once: the model seen as an ODE (with the
    /// current inputs and drive), the state, the time and the integrator.
    fn integration_parts(&mut self) -> (System<'_>, &mut [f64], &mut f64, &mut Integrator) {
        let Torso {
            compiled,
            data,
            y,
            time,
            inputs,
            airway_opening,
            occlusion,
            integrator,
            config,
            jacobian,
            ..
        } = self;
        let system = System {
            model: &compiled.model,
            weights: &compiled.error_weights,
            data,
            applied: Applied::new(
                config,
                &compiled.model.params,
                *inputs,
                *airway_opening,
                *occlusion,
            ),
            jacobian: jacobian.as_deref_mut(),
        };
        (system, y, time, integrator)
    }

    /// Integrates from the current time to `t`, inputs held constant. On failure the torso
    /// stays at its last good time (see [`Torso::time`]) and the error says why.
    pub fn advance_to(&mut self, t: f64) -> Result<AdvanceStats> {
        if !t.is_finite() || t < self.time {
            return Err(Error::invalid(
                "time",
                t,
                format!("a finite time >= the current time {}", self.time),
            ));
        }
        let before = self.integrator.stats();
        if t > self.time && self.quasi.is_some() {
            self.advance_quasi_static(t)?;
        } else if t > self.time {
            let past = self.config.solver.step_past_outputs;
            let (mut system, y, time, integrator) = self.integration_parts();
            let result = if past {
                integrator.integrate_ahead(&mut system, time, y, t)
            } else {
                integrator.integrate(&mut system, time, y, t)
            };
            self.observation = None;
            self.sides = None;
            self.markers.invalidate();
            self.at_start = false;
            result.map_err(|e| Error::Numerical {
                time: self.time,
                reason: e.to_string(),
            })?;
        }
        let after = self.integrator.stats();
        Ok(AdvanceStats {
            steps: after.steps - before.steps,
            rejected: after.rejected - before.rejected,
            rhs_evaluations: after.rhs_evaluations - before.rhs_evaluations,
        })
    }

    /// [`Torso::advance_to`] with `options`: with [`AdvanceOptions::check_physiology`], a step
    /// that ends outside the physiological bounds is rolled back to where it started and
    /// fails with [`Error::Unphysiological`] (a solver failure stays an
    /// [`Error::Numerical`], the model at its last good time).
    pub fn advance_to_with(&mut self, t: f64, options: AdvanceOptions) -> Result<AdvanceStats> {
        if !options.check_physiology {
            return self.advance_to(t);
        }
        let mut start = std::mem::take(&mut self.step_start);
        self.checkpoint(&mut start);
        let result = self.advance_to(t).and_then(|stats| {
            let Some(reason) = self.physiology_violation()? else {
                return Ok(stats);
            };
            let stiffness_detected = self.stiffness_detected();
            self.rollback(&start)?;
            Err(Error::Unphysiological {
                time: start.time,
                at: t,
                reason,
                stiffness_detected,
            })
        });
        self.step_start = start;
        result
    }

    /// [`Torso::advance_to`] in quasi-static mode: the lung volume integrated to `t`, the
    /// positions left to be solved when read.
    fn advance_quasi_static(&mut self, t: f64) -> Result<()> {
        let past = self.config.solver.step_past_outputs;
        let tolerance = quasi::statics_tolerance(self.config.solver.rtol);
        let Torso {
            compiled,
            data,
            time,
            inputs,
            airway_opening,
            occlusion,
            integrator,
            config,
            quasi,
            ..
        } = self;
        let Some(q) = quasi.as_deref_mut() else {
            return Ok(());
        };
        let Quasi {
            statics,
            volume,
            failure,
            ..
        } = q;
        *failure = None;
        let mut system = QuasiSystem {
            model: &compiled.model,
            data,
            statics,
            applied: Applied::new(
                config,
                &compiled.model.params,
                *inputs,
                *airway_opening,
                *occlusion,
            ),
            tolerance,
            failure,
        };
        let result = if past {
            integrator.integrate_ahead(&mut system, time, volume, t)
        } else {
            integrator.integrate(&mut system, time, volume, t)
        };
        q.fresh = false;
        // the positions at the new time balance the activations the step ended with
        q.held = Applied::new(
            &self.config,
            &self.compiled.model.params,
            self.inputs,
            self.airway_opening,
            self.occlusion,
        )
        .activations(self.time);
        let failure = q.failure.take();
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        self.at_start = false;
        result.map_err(|e| {
            let why = match &failure {
                Some(f) => format!(
                    "the quasi-static step failed and shorter steps did not help (state kept \
                     at the last accepted step): {f}; {}",
                    self.describe_scene()
                ),
                None => e.to_string(),
            };
            Error::Numerical {
                time: self.time,
                reason: why,
            }
        })
    }

    /// Subject, posture and applied activations, for the messages of failed solves.
    fn describe_scene(&self) -> String {
        self.describe_scene_at(self.time)
    }

    /// [`Torso::describe_scene`] with the activations applied at time `t`.
    fn describe_scene_at(&self, t: f64) -> String {
        let s = &self.config.subject;
        let groups = self.applying().groups(t);
        let act: Vec<String> = MuscleGroup::ALL
            .iter()
            .map(|g| format!("{} {:.3}", g.name(), groups[g.index()]))
            .collect();
        format!(
            "{:?} subject {} m, {} kg, {:?}; activations {}; airway opening {} Pa{}",
            s.sex,
            s.stature,
            s.mass,
            s.posture,
            act.join(", "),
            self.airway_opening,
            if self.occlusion.is_some() {
                ", airway occluded"
            } else {
                ""
            }
        )
    }

    /// The observation of the current state, computed once per state (lazily).
    pub fn observation(&mut self) -> Observation {
        if let Some(o) = self.observation {
            return o;
        }
        self.current_positions();
        let model = &self.compiled.model;
        dynamics::kinematics::positions_and_velocities(
            model,
            &mut self.data,
            &model.layout,
            &self.y,
        );
        let o = observe::observe(
            model,
            &self.compiled.compartments,
            &self.data.pos,
            &self.data.vel,
            self.airway_opening,
            self.occlusion,
        );
        let o = match self.quasi.as_deref() {
            // the flow and the pressures are the reduced system's, not the positions'
            Some(q) => observe::with_flow(model, o, q.flow * 1e-3, q.pleural, self.airway_opening),
            None => o,
        };
        self.observation = Some(o);
        o
    }

    /// Each side's share of the observation of the current state: right, then left.
    pub fn side_observation(&mut self) -> [observe::SideObservation; 2] {
        if let Some(s) = self.sides {
            return s;
        }
        // The positions of the current state (scratch that an external rhs call may have
        // overwritten since the observation was cached).
        self.current_positions();
        let model = &self.compiled.model;
        dynamics::kinematics::positions_and_velocities(
            model,
            &mut self.data,
            &model.layout,
            &self.y,
        );
        let s = observe::observe_sides(&self.compiled.compartments, &self.data.pos);
        self.sides = Some(s);
        s
    }

    /// Reads a quantity (volumes in litres, pressure in Pa, lengths in m).
    pub fn read(&mut self, quantity: Quantity) -> Result<f64> {
        let litres = 1e3;
        if let Some(q) = self.quasi.as_deref() {
            // the integrated state: no positions needed
            let m = &self.compiled.model;
            match quantity {
                Quantity::LungVolume => return Ok(q.volume[0]),
                Quantity::ThoraxVolume => return Ok(q.volume[0] + m.non_lung_volume * litres),
                _ => {}
            }
        }
        Ok(match quantity {
            Quantity::Time => self.time,
            Quantity::LungVolume => self.observation().lung * litres,
            Quantity::ThoraxVolume => self.observation().thorax * litres,
            Quantity::AbdomenVolume => self.observation().abdomen * litres,
            Quantity::TrunkVolume => self.observation().trunk * litres,
            Quantity::RibCageDisplaced => self.observation().rib_cage_displaced * litres,
            Quantity::AbdomenDisplaced => self.observation().abdomen_displaced * litres,
            Quantity::AbdominalPressure => self.observation().abdominal_pressure,
            Quantity::DiaphragmDisplacement => self.observation().diaphragm_displacement,
            Quantity::PleuralPressure => self.observation().pleural_pressure,
            Quantity::AlveolarPressure => self.observation().alveolar_pressure,
            Quantity::MouthPressure => self.observation().mouth_pressure,
            Quantity::AirwayFlow => self.observation().airway_flow * litres,
            Quantity::LungVolumeSide(s) if s < 2 => {
                let m = &self.compiled.model;
                let rest = m.thorax_rest_volume - m.dome_faceting_volume - m.non_lung_volume;
                let share = if s == 0 {
                    observe::RIGHT_LUNG_FRACTION
                } else {
                    1.0 - observe::RIGHT_LUNG_FRACTION
                };
                (rest * share + self.side_observation()[s as usize].lung_change) * litres
            }
            Quantity::RibCageDisplacedSide(s) if s < 2 => {
                self.side_observation()[s as usize].rib_cage_displaced * litres
            }
            Quantity::AbdomenDisplacedSide(s) if s < 2 => {
                self.side_observation()[s as usize].abdomen_displaced * litres
            }
            Quantity::DiaphragmDisplacementSide(s) if s < 2 => {
                self.side_observation()[s as usize].diaphragm_displacement
            }
            Quantity::SternumDisplacement(axis) if axis < 3 => {
                self.observation().sternum_displacement[axis as usize]
            }
            Quantity::Activation(g) if (g as usize) < MuscleGroup::COUNT => {
                self.applied_activation(MuscleGroup::ALL[g as usize])
            }
            Quantity::SolverSteps => self.integrator.stats().steps as f64,
            Quantity::SolverRejectedSteps => self.integrator.stats().rejected as f64,
            Quantity::SolverRhsEvaluations => self.integrator.stats().rhs_evaluations as f64,
            Quantity::Marker { index, axis } => return self.read_marker(index, axis),
            q => {
                return Err(Error::invalid(
                    "quantity",
                    format!("{q:?}"),
                    "a valid quantity",
                ));
            }
        })
    }

    /// Work counts of the static solves in quasi-static mode (`None` in the other modes).
    pub fn statics_stats(&self) -> Option<dynamics::statics::StaticsStats> {
        self.quasi.as_deref().map(|q| q.statics.stats)
    }

    /// Cumulative solver statistics.
    pub fn solver_stats(&self) -> Stats {
        self.integrator.stats()
    }

    /// Whether the solver's stiffness test has fired (the scene may be better served by a
    /// stiff method).
    pub fn stiffness_detected(&self) -> bool {
        self.integrator.stiffness_detected()
    }

    /// Length of the state vector.
    pub fn state_dim(&self) -> usize {
        self.y.len()
    }

    /// The current state vector (layout: [`crate::dynamics::Layout`]). In quasi-static mode
    /// the positions are those of the last equilibrium solved for an output, every velocity
    /// zero: after [`Torso::advance_to`] they are solved when something reads them, so call
    /// [`Torso::current_state`] for those of the current time.
    pub fn state(&self) -> &[f64] {
        &self.y
    }

    /// The state vector at the current time: in quasi-static mode the positions are solved
    /// first if they are not current; in the other modes the same as [`Torso::state`].
    pub fn current_state(&mut self) -> &[f64] {
        self.current_positions();
        &self.y
    }

    /// Sets the time and the state vector, for external integrators: what is read afterwards
    /// ([`Torso::read`], markers) is that of `y` at `t`, and the next [`Torso::advance_to`]
    /// continues from it. `y` must have [`Torso::state_dim`] finite elements and `t` must be
    /// finite; on error nothing changes. The state is taken as given (a sternum quaternion
    /// off the unit sphere is normalised wherever it is used).
    pub fn set_state(&mut self, t: f64, y: &[f64]) -> Result<()> {
        let n = self.y.len();
        if y.len() != n {
            return Err(Error::invalid("state length", y.len(), format!("{n}")));
        }
        if !t.is_finite() {
            return Err(Error::invalid("time", t, "a finite time"));
        }
        if let Some(i) = y.iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(
                format!("state[{i}]"),
                y[i],
                "a finite value",
            ));
        }
        self.time = t;
        self.y.copy_from_slice(y);
        if self.quasi.is_some() {
            // the positions start the next solve; the lung volume is the one they hold
            let act = self.applied(t);
            let model = &self.compiled.model;
            let thorax = dynamics::statics::volume_of(model, y);
            let pleural = act.airway_opening - model.pleural.recoil(thorax);
            if let Some(q) = self.quasi.as_deref_mut() {
                q.reset(model, y, pleural, &act);
            }
        }
        self.at_start = false;
        self.integrator.invalidate();
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        Ok(())
    }

    /// Evaluates the right-hand side f(t, y) with the current inputs and drive, for external
    /// integrators. `y` and `dydt` must have [`Torso::state_dim`] elements.
    pub fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<()> {
        if self.quasi.is_some() {
            return Err(Error::State(
                "Torso::rhs evaluates the inertial equations of motion; in quasi-static mode \
                 the only state is the lung volume (solver.method quasi-static)"
                    .into(),
            ));
        }
        let n = self.y.len();
        if y.len() != n || dydt.len() != n {
            return Err(Error::invalid(
                "state length",
                y.len().max(dydt.len()),
                format!("{n}"),
            ));
        }
        let Torso {
            compiled,
            data,
            inputs,
            airway_opening,
            occlusion,
            config,
            ..
        } = self;
        let mut system = System {
            model: &compiled.model,
            weights: &compiled.error_weights,
            data,
            applied: Applied::new(
                config,
                &compiled.model.params,
                *inputs,
                *airway_opening,
                *occlusion,
            ),
            jacobian: None,
        };
        system.rhs(t, y, dydt);
        Ok(())
    }

    /// Mechanical energy of the current state [J] (passive: as if no muscle were active).
    pub fn mechanical_energy(&mut self) -> f64 {
        dynamics::energy::mechanical_energy(&self.compiled.model, &mut self.data, &self.y)
    }

    /// Mechanical energy of the current state [J] with the muscles held at the activations
    /// applied now (the inputs, the drive's value at the current time and the posture's tone;
    /// [`dynamics::energy::mechanical_energy_at`]). While those stay constant (the drive off,
    /// a standing tone held) and the airway is open at zero pressure, a motion only loses it
    /// (the airway's work is not counted).
    pub fn mechanical_energy_held(&mut self) -> f64 {
        let act = self.applied(self.time);
        dynamics::energy::mechanical_energy_at(&self.compiled.model, &mut self.data, &self.y, &act)
    }

    /// A snapshot of the mutable data.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            version: super::snapshot::SNAPSHOT_VERSION,
            fingerprint: self.compiled.fingerprint,
            time: self.time,
            state: self.y.clone(),
            inputs: self.inputs,
            airway_opening: self.airway_opening,
            occlusion: self.occlusion,
            drive: self.config.drive,
            solver: serde_json::to_value(&self.integrator).unwrap_or(serde_json::Value::Null),
            quasi: self.quasi.as_deref().map(Quasi::memory),
        }
    }

    /// Restores a snapshot taken from a model with the same fingerprint; on error nothing changes.
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<()> {
        if snapshot.fingerprint != self.compiled.fingerprint {
            return Err(Error::State(
                "snapshot belongs to a different model (subject, posture or level of detail)"
                    .into(),
            ));
        }
        if snapshot.state.len() != self.y.len()
            || snapshot.state.iter().any(|v| !v.is_finite())
            || !snapshot.time.is_finite()
        {
            return Err(Error::State("snapshot state is malformed".into()));
        }
        snapshot.drive.validate()?;
        if let Some(n) = snapshot.occlusion
            && !(n.is_finite() && n > 0.0)
        {
            return Err(Error::State(format!(
                "snapshot occlusion: gas content {n} Pa m^3, allowed a finite positive value"
            )));
        }
        for (g, v) in MuscleGroup::ALL.iter().zip(snapshot.inputs) {
            super::check(&format!("activation.{}", g.name()), v, (0.0, 1.0))?;
        }
        let integrator: Integrator = serde_json::from_value(snapshot.solver.clone())
            .map_err(|e| Error::State(format!("snapshot solver memory is malformed: {e}")))?;
        let dim = if self.quasi.is_some() {
            1
        } else {
            self.y.len()
        };
        if integrator.dim() != dim || self.quasi.is_some() != snapshot.quasi.is_some() {
            return Err(Error::State(
                "snapshot solver memory has the wrong dimension (taken with another solver.method)"
                    .into(),
            ));
        }
        if let (Some(q), Some(memory)) = (self.quasi.as_deref_mut(), &snapshot.quasi) {
            let mut restored = q.clone();
            restored
                .restore(&self.compiled.model, &mut self.data, memory)
                .map_err(|e| Error::State(format!("snapshot quasi-static memory: {e}")))?;
            *q = restored;
        }
        if integrator.method() == Method::Rosenbrock && self.jacobian.is_none() {
            self.jacobian = Some(Box::new(TorsoJacobian::full(&self.compiled.model)));
        }
        self.integrator = integrator;
        self.at_start = false;
        self.time = snapshot.time;
        self.y.copy_from_slice(&snapshot.state);
        self.inputs = snapshot.inputs;
        self.airway_opening = snapshot.airway_opening;
        self.occlusion = snapshot.occlusion;
        self.config.drive = snapshot.drive;
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        Ok(())
    }

    /// Copies the evolving state (time, state vector, inputs, drive, solver memory) into
    /// `checkpoint`, reusing its buffers: the cheap, in-memory form of [`Torso::snapshot`]
    /// taken before every communication step so that a failed step can be rolled back.
    pub fn checkpoint(&self, checkpoint: &mut Checkpoint) {
        checkpoint.fingerprint = self.compiled.fingerprint;
        checkpoint.time = self.time;
        checkpoint.state.clone_from(&self.y);
        checkpoint.inputs = self.inputs;
        checkpoint.airway_opening = self.airway_opening;
        checkpoint.occlusion = self.occlusion;
        checkpoint.drive = Some(self.config.drive);
        match &mut checkpoint.solver {
            Some(solver) => solver.copy_memory_from(&self.integrator),
            None => checkpoint.solver = Some(self.integrator.memory()),
        }
        checkpoint.quasi = self.quasi.as_deref().map(Quasi::memory);
    }

    /// Goes back to a checkpoint taken from this model: afterwards the model continues bit
    /// for bit as after restoring the equivalent snapshot. An empty checkpoint or one from
    /// another model is an error, and nothing changes.
    pub fn rollback(&mut self, checkpoint: &Checkpoint) -> Result<()> {
        let (Some(solver), Some(drive)) = (&checkpoint.solver, checkpoint.drive) else {
            return Err(Error::State("rollback to an empty checkpoint".into()));
        };
        if checkpoint.fingerprint != self.compiled.fingerprint
            || checkpoint.state.len() != self.y.len()
            || solver.dim() != self.y.len()
        {
            return Err(Error::State(
                "checkpoint belongs to a different model (subject, posture or level of detail)"
                    .into(),
            ));
        }
        if solver.method() == Method::Rosenbrock && self.jacobian.is_none() {
            self.jacobian = Some(Box::new(TorsoJacobian::full(&self.compiled.model)));
        }
        if let (Some(q), Some(memory)) = (self.quasi.as_deref_mut(), &checkpoint.quasi) {
            let mut restored = q.clone();
            restored
                .restore(&self.compiled.model, &mut self.data, memory)
                .map_err(|e| Error::State(format!("checkpoint quasi-static memory: {e}")))?;
            *q = restored;
        }
        self.integrator.copy_memory_from(solver);
        self.at_start = false;
        self.time = checkpoint.time;
        self.y.copy_from_slice(&checkpoint.state);
        self.inputs = checkpoint.inputs;
        self.airway_opening = checkpoint.airway_opening;
        self.occlusion = checkpoint.occlusion;
        self.config.drive = drive;
        self.observation = None;
        self.sides = None;
        self.markers.invalidate();
        Ok(())
    }

    /// Back to the freshly built state (time 0, zero inputs and airway pressure, the airway
    /// open, the static
    /// equilibrium of the drive's start, solver memory cleared).
    pub fn reset(&mut self) {
        self.time = 0.0;
        self.inputs = [0.0; MuscleGroup::COUNT];
        self.airway_opening = 0.0;
        self.occlusion = None;
        self.integrator.reset();
        self.start_at_equilibrium();
    }
}
