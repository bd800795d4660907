//! The quasi-static mechanics: the chest wall in equilibrium at every instant, the lung volume
//! the only state (docs/dynamics.md, "Quasi-static mechanics").
//!
//! Breathing is slow against the chest wall's own mechanics: at 0.25 Hz the inertial pressure
//! is well under 1 % of the elastic recoil (Mead 1956; reference physiology), and the one time
//! constant that matters is airway resistance times respiratory compliance. So the positions
//! z of the ribs (one angle each), the sternum (centre of mass and orientation) and the free
//! vertices of the abdominal surface are the static equilibrium under the activations,
//! gravity, the preloads, the abdominal pressure (a penalty of the cavity's near
//! incompressibility, P_A = K (V0 / V_A - 1), thesis eq. 2.5) and the pleural pressure P_pl,
//! which is the multiplier of the constraint that the thoracic volume holds the lungs:
//!
//! ```text
//! R(z, P_pl) = G(z) + P_A(V_A(z)) dV_A/dz + P_pl dV_T/dz = 0,   V_T(z) = V_target,
//! ```
//!
//! with G the generalised forces of the elements, springs, gravity and preloads (every
//! velocity zero: the elements' dampers, the nodal damping and the cavities' viscosities do
//! not act) and V_target the thoracic volume that holds the current lung volume. The lung
//! volume then follows the airflow, dV_L/dt = (P_ao - P_alv) / R_aw with P_alv = P_pl +
//! P_L(V_L) ([`super::pleural`], the model's airway resistance): see `model::torso`.
//!
//! **Newton's method on the bordered system.** With J = dR/dz (the sparse part S by forward
//! differences over a distance-2 colouring with both pressures frozen, plus the abdominal
//! pressure's exact rank-one part P_A' u_A u_A^T, u = dV/dz being the generalised force of a
//! unit pressure), each iteration solves
//!
//! ```text
//! [ J_aug  u_T ] [dz  ]   [ -R + rho u_T c ]
//! [ u_T^T  0   ] [dP  ] = [ -c             ],   c = V_T(z) - V_target,
//! ```
//!
//! J_aug = J - rho u_T u_T^T, the augmented form (Hestenes 1969; Nocedal & Wright 2006,
//! ch. 17), with rho the lungs' elastance: J_aug is the stiffness of the chest wall with the
//! lungs attached and the airway shut, negative definite wherever that system is stable,
//! and the border is eliminated by two solves with its factorisation (dP = (u_T^T a + c) /
//! (u_T^T b), a = J_aug^-1 (-R + rho u_T c), b = J_aug^-1 u_T, dz = a - dP b). The
//! factorisation (the block LU of [`crate::solver::sparse`], minimum-degree ordered, with the
//! Woodbury correction for the rank-two part) is kept from solve to solve while each
//! correction is at most half the one before (modified Newton); the first iteration of a
//! solve from the last solution is the tangent predictor. A kept factorisation that fails
//! that test is taken again at the failed step's start, and one whose contraction cannot
//! reach the tolerance in the iterations left is taken again at once; a step with a fresh
//! one that fails the restricted monotonicity test (Deuflhard 2004, *Newton Methods for
//! Nonlinear Problems*, sec. 3.3: the next correction at most 1 - lambda/2 of this one) is
//! halved. A solve that still fails is retried from the last solution with the activations
//! and the volume stepped there gradually (continuation); a solve that fails then is an
//! error, and the last solution is kept. Where the continuation stops part of the way, the
//! error says how far and whether the path folds ([`StaticsError::PathEnds`]).
//!
//! **Stability, checked at every factorisation.** By Haynsworth's inertia additivity, the
//! number of positive eigenvalues of J_aug = S + U C U^T (C = diag(P_A', -rho), both
//! negative) is that of S plus that of the 2 x 2 matrix -C^-1 - U^T S^-1 U, less 2; S's
//! comes from its pivot blocks (Sylvester's law of inertia). A positive eigenvalue is a
//! buckled chest wall; so is a border with u_T^T b >= 0, which would make the alveolar
//! pressure fall as the lungs fill (dP_alv/dV_L = -1 / (u_T^T b) must be positive). Either
//! is reported as [`StaticsError::Unstable`], never passed over to another branch.

use super::model::Model;
use super::state::Layout;
use super::structure::{RIBS, volume};
use super::{Activations, Data, accelerations, forces, kinematics};
use crate::solver::sparse::ShiftedSolver;
use crate::solver::{Colouring, Jacobian, Pattern};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Newton iterations allowed in one attempt at a solve.
const MAX_ITERATIONS: u32 = 16;

/// Smallest damping of a Newton step (four halvings) before the attempt is given up.
const MIN_DAMPING: f64 = 1.0 / 16.0;

/// The stiffness floor, as a fraction of the largest diagonal stiffness: modes softer than
/// it count as mechanisms of slack elements, not as buckling (module doc). The measured
/// soft modes of the quiet breath sit at 3e-6 of the largest (0.41 / 1.46e5 N/m at level 1,
/// `examples/quasi_static`); 1e-5 keeps them apart from a loss of stability the size of a
/// foundation spring.
const STIFFNESS_FLOOR: f64 = 1e-5;

/// Solutions the predictor extrapolates from (a quadratic).
const HISTORY: usize = 3;

/// Solutions kept: more than a Dormand-Prince step's six stages, so that after a rejected
/// step the solution at the step's start is still there to start the retry from.
const KEPT: usize = 8;

/// Oldest solution the predictor uses [s]: an eighth of a quiet breath, so that a stale one
/// (after a restart) is not extrapolated from.
const HISTORY_SPAN: f64 = 0.5;

/// Lever [m] that turns a rib's or the sternum's rotation [rad] into a displacement for the
/// convergence test: about the distance from a rib's hinge to its ventral end (docs/anatomy.md:
/// rib lengths of 0.15-0.3 m).
pub(crate) const LEVER: f64 = 0.2;

/// Halvings of the continuation's failed step that locate where the equilibrium path ends:
/// 6 resolve it to 1/1024 of the way from the last solution to the activations asked.
const BISECTIONS: u32 = 6;

/// A path whose stiffness along it has fallen below this fraction of its value at the
/// path's start is reported as folding. Near a fold at s* the stiffness along the path goes
/// to zero like sqrt(s* - s); the continuation's path starts at s = 0 and, where a fold
/// stops it (s* >= 1/16 of the way), ends within 1/1024 of it after the halvings, so its
/// stiffness there is at most sqrt((1/1024) / (1/16)) = 0.125 of the start's to leading
/// order; twice that leaves room for the higher orders. Measured (before the external
/// intercostals' rostrocaudal drive silenced the lowest interspaces): soak scene 35's fold
/// keeps 4 % (-482 to -19.5 N/m); a path that stopped without softening, scene 5 before the
/// damped steps let it run, kept 90 % (`torso bench soak --scenes 40 --seconds 20 --solver
/// quasi-static`).
const FOLD_FRACTION: f64 = 0.25;

/// Why a static solve failed.
#[derive(Clone, Debug, PartialEq)]
pub enum StaticsError {
    /// The chest wall lost its stability (buckled) at these activations and volume.
    Unstable {
        /// What was found: positive eigenvalues of the stiffness, or the alveolar pressure
        /// falling with volume.
        reason: String,
    },
    /// The iterations did not converge, even with the activations stepped gradually.
    NotConverged {
        /// The last correction's size [m].
        correction: f64,
    },
    /// The equilibrium path from the last solution could be followed only part of the way
    /// to the activations asked: the chest wall's stiffness along the path tends to zero
    /// where it folds (a snap-through, which a quasi-static formulation cannot follow).
    PathEnds {
        /// How far the path was followed, as a fraction of the way from the last solution's
        /// activations and volume to those asked.
        reached: f64,
        /// The stiffness along the path at its start [N/m] (negative: stable).
        stiffness_start: f64,
        /// The stiffness along the path at the last equilibrium reached [N/m].
        stiffness_end: f64,
        /// The last correction's size there [m].
        correction: f64,
    },
    /// A non-finite value appeared (the factorisation failed or a force overflowed).
    NonFinite,
}

impl std::fmt::Display for StaticsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StaticsError::Unstable { reason } => write!(
                f,
                "the chest wall buckled: {reason} (it would snap through to another \
                 equilibrium, which the quasi-static formulation cannot follow; the inertial \
                 one, solver.method 0, can)"
            ),
            StaticsError::NotConverged { correction } => write!(
                f,
                "the static equilibrium did not converge (last correction {correction:.3e} m)"
            ),
            StaticsError::PathEnds {
                reached,
                stiffness_start,
                stiffness_end,
                correction,
            } => write!(
                f,
                "the static equilibrium could be followed only {:.1} % of the way to these \
                 activations (last correction {correction:.3e} m); the chest wall's stiffness \
                 along the path went from {stiffness_start:.3e} N/m to {stiffness_end:.3e} N/m \
                 there{}",
                100.0 * reached,
                if stiffness_end.abs() < FOLD_FRACTION * stiffness_start.abs() {
                    " (the path folds: the chest wall would snap through, which the \
                     quasi-static formulation cannot follow; the inertial one, solver.method 0, \
                     can)"
                } else {
                    ""
                }
            ),
            StaticsError::NonFinite => write!(f, "a non-finite value in the static equilibrium"),
        }
    }
}

/// Work counts of the static solves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StaticsStats {
    /// Solves asked for.
    pub solves: u64,
    /// Newton iterations (each one residual evaluation and one back-substitution).
    pub iterations: u64,
    /// Jacobian evaluations (each one residual evaluation per colour, plus three).
    pub jacobians: u64,
    /// Factorisations.
    pub factorisations: u64,
    /// Residual evaluations in all.
    pub residuals: u64,
    /// Solves that needed the activations stepped gradually.
    pub continuations: u64,
}

/// What a solve leaves behind and a restart needs to continue bit for bit: the solution
/// (warm start) and the point where the kept factorisation was evaluated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticsMemory {
    /// The last solution: the state vector's positions (velocities zero).
    pub state: Vec<f64>,
    /// Its pleural pressure, relative to rest [Pa].
    pub pleural: f64,
    /// Its activations (levels, then the airway-opening pressure).
    pub activations: Vec<f64>,
    /// The thoracic volume it holds [m^3].
    pub volume: f64,
    /// Where the kept factorisation was evaluated: state, pleural pressure, activations
    /// (`None`: no factorisation kept).
    pub factored_at: Option<(Vec<f64>, f64, Vec<f64>)>,
    /// The contraction rate the last solve's iterations measured (the first iteration's
    /// convergence test of the next solve uses it).
    pub contraction: f64,
    /// The predictor's history: times, states, pleural pressures and thoracic volumes of the
    /// last solutions.
    #[serde(default)]
    pub history: Vec<(f64, Vec<f64>, f64, f64)>,
    /// The activations of each solution of `history` (levels, then the airway-opening
    /// pressure); memories written before it existed give each the last solution's.
    #[serde(default)]
    pub history_activations: Vec<Vec<f64>>,
    /// Work counts.
    pub stats: StaticsStats,
}

/// Length of an activation vector in the memory: three sides per muscle group, then the
/// airway-opening pressure.
const ACT_LEN: usize = 3 * crate::anatomy::MuscleGroup::COUNT + 1;

fn act_to_vec(a: &Activations) -> Vec<f64> {
    let mut v: Vec<f64> = a.level.iter().flatten().copied().collect();
    v.push(a.airway_opening);
    v
}

fn act_from_vec(v: &[f64]) -> Activations {
    let mut a = Activations::default();
    for (g, sides) in a.level.iter_mut().enumerate() {
        for (s, x) in sides.iter_mut().enumerate() {
            *x = v.get(3 * g + s).copied().unwrap_or(0.0);
        }
    }
    a.airway_opening = v.get(ACT_LEN - 1).copied().unwrap_or(0.0);
    a
}

/// The static solver of one instance: pattern, colouring, factorisation and scratch, sized
/// once per model, and the last solution.
#[derive(Clone, Debug)]
pub struct Statics {
    l: Layout,
    /// Number of position unknowns: 24 rib angles, the sternum's 3 + 3, 3 per free vertex.
    m: usize,
    jac: Jacobian,
    colouring: Colouring,
    solver: ShiftedSolver,
    floor: Vec<f64>,
    zero: Vec<f64>,
    zpert: Vec<f64>,
    f0: Vec<f64>,
    f1: Vec<f64>,
    r: Vec<f64>,
    a: Vec<f64>,
    /// J_aug^-1 u_T and u_T of the kept factorisation.
    b: Vec<f64>,
    ut: Vec<f64>,
    /// The elastance rho of the augmented form at the kept factorisation [Pa/m^3].
    rho: f64,
    dy: Vec<f64>,
    ytmp: Vec<f64>,
    /// The last Newton step's start (state, pleural pressure) and full correction.
    y_back: Vec<f64>,
    pleural_back: f64,
    r_back: Vec<f64>,
    dp_back: f64,
    /// The current iterate / last solution (full state layout, velocities zero).
    y: Vec<f64>,
    /// The last solution, kept while a solve iterates (a failed solve returns to it).
    y_good: Vec<f64>,
    pleural: f64,
    pleural_good: f64,
    act_good: Activations,
    volume_good: f64,
    factored_at: Option<(Vec<f64>, f64, Activations)>,
    /// Contraction rate of the last converged solve's iterations.
    theta: f64,
    /// The last solutions (time, state, pleural pressure, thoracic volume), for the
    /// predictor and as starting points.
    history: Vec<(f64, Vec<f64>, f64, f64)>,
    /// The activations of each solution in `history`.
    history_act: Vec<Activations>,
    /// Work counts.
    pub stats: StaticsStats,
}

/// Unknowns of body `b` among the m position unknowns.
fn body_unknowns(b: usize) -> std::ops::Range<usize> {
    if b < RIBS {
        b..b + 1
    } else if b == RIBS {
        RIBS..RIBS + 6
    } else {
        let j = b - RIBS - 1;
        RIBS + 6 + 3 * j..RIBS + 9 + 3 * j
    }
}

impl Statics {
    /// Pattern (bodies that share an element, a spring or a pressure triangle), colouring and
    /// symbolic factorisation for `model`, with `start` (a state vector at rest or at an
    /// equilibrium, velocities ignored) as the first solution and the activations `act` it
    /// balances.
    pub fn new(model: &Model, start: &[f64], act: &Activations) -> Statics {
        let l = model.layout;
        let m = RIBS + 6 + 3 * l.vertices;
        let adj = super::jacobian::body_adjacency(model);
        let mut rows: Vec<Vec<u32>> = vec![Vec::new(); m];
        let mut groups = vec![0u32; m];
        for (b, nb) in adj.iter().enumerate() {
            let cols: Vec<u32> = nb
                .iter()
                .flat_map(|&o| body_unknowns(o as usize).map(|i| i as u32))
                .collect();
            for i in body_unknowns(b) {
                groups[i] = b as u32;
                rows[i] = cols.clone();
            }
        }
        let pattern = Pattern::from_rows(rows);
        let colouring = Colouring::new(&pattern);
        let mut solver = ShiftedSolver::new(&pattern, &groups);
        solver.lu_mut().count_inertia(true);
        // perturbations sqrt(eps) x floor: 1.5e-8 rad for angles, 4.5e-9 m for positions
        let mut floor = vec![0.3; m];
        floor[..RIBS].fill(1.0);
        floor[RIBS + 3..RIBS + 6].fill(1.0);
        let mut y = start.to_vec();
        y[l.theta_dot..].fill(0.0);
        Statics {
            l,
            m,
            jac: Jacobian::zeros(pattern, 2),
            colouring,
            solver,
            floor,
            zero: vec![0.0; m],
            zpert: vec![0.0; m],
            f0: vec![0.0; m],
            f1: vec![0.0; m],
            r: vec![0.0; m],
            a: vec![0.0; m],
            b: vec![0.0; m],
            ut: vec![0.0; m],
            rho: 0.0,
            dy: vec![0.0; l.len],
            ytmp: vec![0.0; l.len],
            y_back: vec![0.0; l.len],
            pleural_back: 0.0,
            r_back: vec![0.0; m],
            dp_back: 0.0,
            y_good: y.clone(),
            volume_good: volume_of(model, &y),
            y,
            pleural: 0.0,
            pleural_good: 0.0,
            act_good: *act,
            factored_at: None,
            theta: 0.1,
            history: Vec::new(),
            history_act: Vec::new(),
            stats: StaticsStats::default(),
        }
    }

    /// Number of colours of the Jacobian's sparse part (residual evaluations per Jacobian).
    pub fn colours(&self) -> usize {
        self.colouring.colours
    }

    /// Number of position unknowns.
    pub fn unknowns(&self) -> usize {
        self.m
    }

    /// The last solution: a state vector (positions, velocities zero).
    pub fn state(&self) -> &[f64] {
        &self.y_good
    }

    /// The pleural pressure of the last solution, relative to rest [Pa].
    pub fn last_pleural(&self) -> f64 {
        self.pleural_good
    }

    /// The thoracic volume the last solution holds [m^3].
    pub fn volume(&self) -> f64 {
        self.volume_good
    }

    /// Makes `state` (positions, velocities ignored), balanced by `act` at pleural pressure
    /// `pleural`, the last solution, and forgets the factorisation.
    pub fn reset(&mut self, model: &Model, state: &[f64], pleural: f64, act: &Activations) {
        self.y_good.copy_from_slice(state);
        self.y_good[self.l.theta_dot..].fill(0.0);
        self.y.copy_from_slice(&self.y_good);
        self.pleural_good = pleural;
        self.pleural = pleural;
        self.act_good = *act;
        self.volume_good = volume_of(model, &self.y_good);
        self.factored_at = None;
        self.theta = 0.1;
        self.history.clear();
        self.history_act.clear();
        self.solver.clear();
    }

    /// What a restart needs to continue bit for bit ([`StaticsMemory`]).
    pub fn memory(&self) -> StaticsMemory {
        StaticsMemory {
            state: self.y_good.clone(),
            pleural: self.pleural_good,
            activations: act_to_vec(&self.act_good),
            volume: self.volume_good,
            factored_at: self
                .factored_at
                .as_ref()
                .map(|(y, p, a)| (y.clone(), *p, act_to_vec(a))),
            contraction: self.theta,
            history: self.history.clone(),
            history_activations: self.history_act.iter().map(act_to_vec).collect(),
            stats: self.stats,
        }
    }

    /// Restores [`Statics::memory`]: the last solution, and the factorisation re-evaluated at
    /// the point it was kept from (the same positions, pressure and activations give the same
    /// factors). An error if the memory is malformed or its factorisation fails.
    pub fn restore(
        &mut self,
        model: &Model,
        data: &mut Data,
        memory: &StaticsMemory,
    ) -> Result<(), StaticsError> {
        if memory.state.len() != self.y.len() || memory.activations.len() != ACT_LEN {
            return Err(StaticsError::NonFinite);
        }
        self.reset(
            model,
            &memory.state,
            memory.pleural,
            &act_from_vec(&memory.activations),
        );
        if let Some((y, p, a)) = &memory.factored_at {
            if y.len() != self.y.len() || a.len() != ACT_LEN {
                return Err(StaticsError::NonFinite);
            }
            let stats = self.stats;
            self.factor_at(model, data, y, *p, &act_from_vec(a))?;
            self.stats = stats;
        }
        self.stats = memory.stats;
        if !(memory.contraction > 0.0 && memory.contraction < 1.0) {
            return Err(StaticsError::NonFinite);
        }
        self.theta = memory.contraction;
        if memory
            .history
            .iter()
            .any(|(_, y, _, _)| y.len() != self.y.len())
        {
            return Err(StaticsError::NonFinite);
        }
        self.history.clone_from(&memory.history);
        self.history_act = if memory.history_activations.len() == memory.history.len()
            && memory
                .history_activations
                .iter()
                .all(|a| a.len() == ACT_LEN)
        {
            memory
                .history_activations
                .iter()
                .map(|a| act_from_vec(a))
                .collect()
        } else {
            vec![self.act_good; memory.history.len()]
        };
        Ok(())
    }

    /// The residual R (generalised forces at zero velocity) at state `y` with the abdominal
    /// pressure from its volume and the pleural pressure `pleural` into `out`; returns
    /// (V_A, V_T) [m^3].
    fn residual(
        &mut self,
        model: &Model,
        data: &mut Data,
        act: &Activations,
        pleural: f64,
    ) -> (f64, f64) {
        let (va, vt) = pressures_and_residual(
            model,
            data,
            &self.l,
            act,
            &self.y,
            None,
            pleural,
            &mut self.dy,
        );
        self.stats.residuals += 1;
        (va, vt)
    }

    /// Evaluates J_aug at `y` (pleural pressure `pleural`, activations `act`), factors it
    /// and checks its inertia; keeps the factorisation and where it was taken.
    fn factor_at(
        &mut self,
        model: &Model,
        data: &mut Data,
        y: &[f64],
        pleural: f64,
        act: &Activations,
    ) -> Result<(), StaticsError> {
        let l = self.l;
        let m = self.m;
        self.ytmp.copy_from_slice(y);
        // base point and the pressures it is frozen at
        let (va, vt) = pressures_and_residual(
            model,
            data,
            &l,
            act,
            &self.ytmp,
            None,
            pleural,
            &mut self.dy,
        );
        let pa = abdominal_pressure(model, va);
        self.f0.copy_from_slice(&self.dy[l.theta_dot..]);
        let frozen = Some(pa);
        {
            let Statics {
                colouring,
                zero,
                floor,
                zpert,
                f1,
                jac,
                ytmp,
                dy,
                f0,
                ..
            } = self;
            let mut f = |z: &[f64], out: &mut [f64]| {
                ytmp.copy_from_slice(y);
                apply(&l, ytmp, z);
                pressures_and_residual(model, data, &l, act, ytmp, frozen, pleural, dy);
                out.copy_from_slice(&dy[l.theta_dot..]);
            };
            let evals = colouring.differences(&mut f, zero, f0, floor, zpert, f1, &mut jac.values);
            self.stats.residuals += evals + 1;
        }
        // u = generalised force of a unit pressure = dV/dz (exact: R is affine in each)
        let mut u = [vec![0.0; m], vec![0.0; m]];
        for (k, uk) in u.iter_mut().enumerate() {
            self.ytmp.copy_from_slice(y);
            let (pa_k, pl_k) = if k == 0 {
                (pa + 1.0, pleural)
            } else {
                (pa, pleural + 1.0)
            };
            pressures_and_residual(
                model,
                data,
                &l,
                act,
                &self.ytmp,
                Some(pa_k),
                pl_k,
                &mut self.dy,
            );
            self.stats.residuals += 1;
            for ((o, &a), &b) in uk.iter_mut().zip(&self.dy[l.theta_dot..]).zip(&self.f0) {
                *o = a - b;
            }
        }
        let slope_a = -model.params.bulk_modulus * model.abdomen_rest_volume / (va * va);
        let rho = model.pleural.slope(vt);
        self.jac.u[..m].copy_from_slice(&u[0]);
        self.jac.u[m..].copy_from_slice(&u[1]);
        for (i, (ua, ut)) in u[0].iter().zip(&u[1]).enumerate() {
            self.jac.v[i] = slope_a * ua;
            self.jac.v[m + i] = -rho * ut;
        }
        self.stats.jacobians += 1;
        self.factored_at = None;
        self.solver
            .factor_general(&self.jac, 0.0, -1.0)
            .map_err(|_| StaticsError::Unstable {
                reason: "the stiffness matrix is singular".into(),
            })?;
        self.stats.factorisations += 1;
        // Stability: no positive eigenvalue of J_aug (module doc). Modes softer than the
        // floor are mechanisms that slack elements leave (measured: a few vertices at the top
        // of the dome, whose membrane is nearly flat, reach +0.03 to +0.41 N/m at the end of a
        // quiet expiration at level 1, against -1.46e5 N/m for the stiffest mode), not
        // buckling; the equilibrium is still solved on its branch with the exact J_aug.
        let c = [slope_a, -rho];
        let (positive, zero) = self.positive_eigenvalues(&u, c);
        if positive > 0 || zero > 0 {
            let scale = (0..m)
                .filter_map(|i| self.jac.pattern.position(i, i))
                .fold(0.0f64, |s, e| s.max(self.jac.values[e].abs()));
            let floor = STIFFNESS_FLOOR * scale;
            let shifted = self.solver.factor_general(&self.jac, -floor, -1.0);
            let (positive, zero) = match shifted {
                Ok(()) => self.positive_eigenvalues(&u, c),
                Err(_) => (1, 0),
            };
            self.stats.factorisations += 2;
            if positive > 0 || zero > 0 {
                return Err(StaticsError::Unstable {
                    reason: format!(
                        "the stiffness of the chest wall with the lungs attached has {} \
                         mode(s) of negative stiffness, below -{floor:.3e} N/m (the floor of \
                         {STIFFNESS_FLOOR:e} of its largest, {scale:.3e} N/m)",
                        positive.max(0) as usize + zero
                    ),
                });
            }
            self.solver
                .factor_general(&self.jac, 0.0, -1.0)
                .map_err(|_| StaticsError::Unstable {
                    reason: "the stiffness matrix is singular".into(),
                })?;
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        self.ut.copy_from_slice(&u[1]);
        self.b.copy_from_slice(&u[1]);
        self.solver.solve(&mut self.b);
        let utb = dot(&self.ut, &self.b);
        if utb >= 0.0 || !utb.is_finite() {
            return Err(StaticsError::Unstable {
                reason: format!(
                    "the alveolar pressure would fall as the lungs fill (u^T J^-1 u = {utb:.3e})"
                ),
            });
        }
        self.rho = rho;
        self.factored_at = Some((y.to_vec(), pleural, *act));
        Ok(())
    }

    /// The numbers of positive and zero eigenvalues of the factored J_aug = S + U C U^T
    /// (Haynsworth: those of S, from its pivot blocks, plus those of the 2 x 2 matrix
    /// -C^-1 - U^T S^-1 U, less the 2 of -C^-1; module doc).
    fn positive_eigenvalues(&mut self, u: &[Vec<f64>; 2], c: [f64; 2]) -> (i64, usize) {
        let [pos_s, zero_s, _] = self.solver.lu_mut().inertia();
        let mut sinv = [u[0].clone(), u[1].clone()];
        for s in &mut sinv {
            self.solver.lu_mut().solve(s);
        }
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let mut mm = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                mm[i][j] = -0.5 * (dot(&u[i], &sinv[j]) + dot(&u[j], &sinv[i]));
            }
            mm[i][i] -= 1.0 / c[i];
        }
        let (tr, det) = (
            mm[0][0] + mm[1][1],
            mm[0][0] * mm[1][1] - mm[0][1] * mm[1][0],
        );
        let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
        let pos_m = [0.5 * tr + disc, 0.5 * tr - disc]
            .iter()
            .filter(|e| **e > 0.0)
            .count();
        ((pos_s + pos_m) as i64 - 2, zero_s)
    }

    /// The slope of the alveolar pressure with the lung volume at the kept factorisation,
    /// dP_alv/dV_L = -1 / (u_T^T J_aug^-1 u_T) [Pa/m^3] (module doc): the respiratory
    /// system's elastance with the muscles held; `None` without a factorisation.
    pub fn elastance(&self) -> Option<f64> {
        self.factored_at.as_ref()?;
        let utb: f64 = self.ut.iter().zip(&self.b).map(|(x, y)| x * y).sum();
        Some(-1.0 / utb)
    }

    /// One attempt: Newton iterations from the current iterate towards the equilibrium at
    /// `act` holding thoracic volume `target`, to a displacement tolerance `tol` [m].
    fn iterate(
        &mut self,
        model: &Model,
        data: &mut Data,
        act: &Activations,
        target: f64,
        tol: f64,
    ) -> Result<(), StaticsError> {
        // size of the last step's full correction, its damping, and whether its Jacobian
        // was taken at its start (a fresh one) or before (a kept one)
        let mut prev = f64::INFINITY;
        let mut lambda = 1.0;
        let mut step_fresh = false;
        // corrections since the kept factorisation was taken at the iterate
        let mut age = usize::MAX;
        let mut theta = self.theta;
        let mut last = f64::INFINITY;
        let l = self.l;
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        for k in 0..MAX_ITERATIONS {
            let (_, vt) = self.residual(model, data, act, self.pleural);
            let c = vt - target;
            if !c.is_finite() || self.dy.iter().any(|v| !v.is_finite()) {
                return Err(StaticsError::NonFinite);
            }
            if self.factored_at.is_none() {
                let y = self.y.clone();
                self.factor_at(model, data, &y, self.pleural, act)?;
                age = 0;
                // the factorisation's differences use `dy` as scratch (the last, the residual
                // at 1 Pa more pleural pressure); its base point is this residual
                let th = l.theta_dot;
                self.dy[th..th + self.m].copy_from_slice(&self.f0);
            }
            // a = J_aug^-1 (-R + rho u_T c)
            for (i, a) in self.a.iter_mut().enumerate() {
                *a = -self.dy[l.theta_dot + i] + self.rho * self.ut[i] * c;
            }
            self.solver.solve(&mut self.a);
            let dp = (dot(&self.ut, &self.a) + c) / dot(&self.ut, &self.b);
            for (r, (a, b)) in self.r.iter_mut().zip(self.a.iter().zip(&self.b)) {
                *r = a - dp * b;
            }
            if !dp.is_finite() || self.r.iter().any(|v| !v.is_finite()) {
                return Err(StaticsError::NonFinite);
            }
            self.stats.iterations += 1;
            let size = correction_size(&self.r);
            last = size;
            if prev.is_finite() {
                // restricted monotonicity (Deuflhard 2004, sec. 3.3): the correction at the
                // new iterate must have shrunk by 1 - lambda / 2 of the last one
                if size > (1.0 - 0.5 * lambda) * prev {
                    if !step_fresh {
                        // a kept Jacobian that no longer contracts: back to the step's
                        // start, refactor there
                        self.y.copy_from_slice(&self.y_back);
                        self.pleural = self.pleural_back;
                        self.factored_at = None;
                        prev = f64::INFINITY;
                        lambda = 1.0;
                        continue;
                    }
                    if lambda * 0.5 < MIN_DAMPING || k + 1 == MAX_ITERATIONS {
                        break;
                    }
                    // a fresh Jacobian overshoots (the forces bend within the step):
                    // halve the step from its start
                    lambda *= 0.5;
                    self.y.copy_from_slice(&self.y_back);
                    self.pleural = self.pleural_back + lambda * self.dp_back;
                    let r = std::mem::take(&mut self.r_back);
                    self.r.iter_mut().zip(&r).for_each(|(x, v)| *x = lambda * v);
                    self.r_back = r;
                    apply(&l, &mut self.y, &self.r);
                    continue;
                }
                if lambda == 1.0 {
                    theta = size / prev;
                }
            }
            // error after this step about theta / (1 - theta) of it (Hairer & Wanner IV.8)
            if size <= tol || (theta < 1.0 && theta / (1.0 - theta) * size <= tol) {
                apply(&l, &mut self.y, &self.r);
                self.pleural += dp;
                self.theta = theta.clamp(1e-3, 0.9);
                return Ok(());
            }
            // a kept Jacobian whose contraction cannot reach the tolerance in the
            // iterations left: refactor here
            let left = (MAX_ITERATIONS - k - 1) as i32;
            if age > 0 && prev.is_finite() && theta.powi(left) * size > tol {
                self.factored_at = None;
                prev = f64::INFINITY;
                continue;
            }
            self.y_back.copy_from_slice(&self.y);
            self.pleural_back = self.pleural;
            self.r_back.copy_from_slice(&self.r);
            self.dp_back = dp;
            step_fresh = age == 0;
            lambda = if prev.is_finite() {
                (2.0 * lambda).min(1.0)
            } else {
                lambda
            };
            if lambda < 1.0 {
                self.r.iter_mut().for_each(|x| *x *= lambda);
            }
            apply(&l, &mut self.y, &self.r);
            self.pleural += lambda * dp;
            prev = size;
            age = age.saturating_add(1);
        }
        Err(StaticsError::NotConverged { correction: last })
    }

    /// The equilibrium at activations `act` holding thoracic volume `target` [m^3], to a
    /// displacement tolerance `tol` [m], from the last solution (module doc). Returns the
    /// pleural pressure relative to rest [Pa]; on error the last solution is kept.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        model: &Model,
        data: &mut Data,
        time: f64,
        act: &Activations,
        target: f64,
        tol: f64,
    ) -> Result<f64, StaticsError> {
        self.stats.solves += 1;
        if *act == self.act_good && target == self.volume_good {
            return Ok(self.pleural_good);
        }
        // where to start from: the latest solution at or before `time` (after a rejected
        // step the later solutions are its stages', off the trajectory being retried)
        let origin = self.origin(time);
        let predicted = self.predict(time, target);
        if !predicted {
            self.start_at(origin);
        }
        let mut first = self.iterate(model, data, act, target, tol);
        if predicted && first.is_err() {
            // the extrapolation led astray: start again from the origin
            self.start_at(origin);
            first = self.iterate(model, data, act, target, tol);
        }
        // An iterate off the equilibrium may be unstable where the equilibrium is not
        // (elements slack or compressed on the way): the continuation, whose first
        // factorisation is at the origin's equilibrium, decides whether the chest wall buckles.
        let outcome = match first {
            Ok(()) => Ok(()),
            Err(_) => self.continuation(model, data, act, target, tol, origin),
        };
        match outcome {
            Ok(()) => {
                self.y_good.copy_from_slice(&self.y);
                self.pleural_good = self.pleural;
                self.act_good = *act;
                self.volume_good = target;
                self.remember(time);
                Ok(self.pleural)
            }
            Err(e) => {
                self.y.copy_from_slice(&self.y_good);
                self.pleural = self.pleural_good;
                Err(e)
            }
        }
    }

    /// The predictor: the latest solutions at or before `time` (at most [`HISTORY`], at
    /// distinct times within [`HISTORY_SPAN`] of it) extrapolated to `time` by their Lagrange polynomial, into
    /// the iterate, then moved along the tangent dz/dV = J_aug^-1 u / (u^T J_aug^-1 u) of the
    /// kept factorisation (module doc) from the extrapolated volume to `target`; whether there
    /// were at least two solutions to extrapolate from. Along a smooth drive the positions
    /// are a smooth function of time, and a Runge-Kutta stage's volume departs from the
    /// trajectory's by a step's error, which the tangent takes up to first order.
    fn predict(&mut self, time: f64, target: f64) -> bool {
        // the latest solutions at or before `time`: after a rejected step the later ones
        // are its stages', off the trajectory being retried
        let mut nodes: Vec<usize> = (0..self.history.len())
            .filter(|&i| self.history[i].0 <= time && time - self.history[i].0 <= HISTORY_SPAN)
            .collect();
        nodes.sort_by(|&a, &b| self.history[b].0.total_cmp(&self.history[a].0));
        nodes.truncate(HISTORY);
        if nodes.len() < 2 {
            return false;
        }
        let weights: Vec<f64> = nodes
            .iter()
            .map(|&i| {
                let ti = self.history[i].0;
                nodes
                    .iter()
                    .filter(|&&j| j != i)
                    .map(|&j| {
                        let tj = self.history[j].0;
                        (time - tj) / (ti - tj)
                    })
                    .product()
            })
            .collect();
        if weights.iter().any(|w| !w.is_finite() || w.abs() > 10.0) {
            return false;
        }
        self.y.fill(0.0);
        self.pleural = 0.0;
        let mut volume = 0.0;
        for (&i, &w) in nodes.iter().zip(&weights) {
            let (_, y, p, v) = &self.history[i];
            for (a, b) in self.y.iter_mut().zip(y) {
                *a += w * b;
            }
            self.pleural += w * p;
            volume += w * v;
        }
        let q = self.l.sternum_q;
        let norm = self.y[q..q + 4].iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm.is_nan() || norm <= 0.0 {
            return false;
        }
        self.y[q..q + 4].iter_mut().for_each(|v| *v /= norm);
        if self.factored_at.is_some() {
            let utb: f64 = self.ut.iter().zip(&self.b).map(|(x, y)| x * y).sum();
            let dv = target - volume;
            if utb < 0.0 && dv.is_finite() {
                let scale = dv / utb;
                for (r, b) in self.r.iter_mut().zip(&self.b) {
                    *r = scale * b;
                }
                let l = self.l;
                apply(&l, &mut self.y, &self.r);
                self.pleural -= (self.rho + 1.0 / utb) * dv;
            }
        }
        true
    }

    /// Adds the solution just accepted, at `time`, to the history (replacing one at a time
    /// closer than 1 us, dropping the oldest beyond [`KEPT`]).
    /// The oldest entry's buffer is reused, so that a full history allocates nothing.
    fn remember(&mut self, time: f64) {
        let mut i = 0;
        while i < self.history.len() {
            if (self.history[i].0 - time).abs() <= 1e-6 {
                self.history.remove(i);
                self.history_act.remove(i);
            } else {
                i += 1;
            }
        }
        let mut state = if self.history.len() >= KEPT {
            self.history_act.remove(0);
            self.history.remove(0).1
        } else {
            Vec::with_capacity(self.y_good.len())
        };
        state.clear();
        state.extend_from_slice(&self.y_good);
        self.history
            .push((time, state, self.pleural_good, self.volume_good));
        self.history_act.push(self.act_good);
    }

    /// From the last solution to (act, target) in 4, then 16 equal steps of the activations
    /// and the volume, each solved from the one before with a fresh Jacobian. Where the
    /// 16 steps fail past the first, the failed step is halved ([`BISECTIONS`] times) to find
    /// how far the path goes, and the error says how far and how stiff the chest wall was
    /// along the path at its start and at its last equilibrium ([`StaticsError::PathEnds`]).
    fn continuation(
        &mut self,
        model: &Model,
        data: &mut Data,
        act: &Activations,
        target: f64,
        tol: f64,
        origin: Option<usize>,
    ) -> Result<(), StaticsError> {
        self.stats.continuations += 1;
        let (a0, v0) = match origin {
            Some(i) => (self.history_act[i], self.history[i].3),
            None => (self.act_good, self.volume_good),
        };
        let along = |s: f64| {
            let mut a = *act;
            for (g, sides) in a.level.iter_mut().enumerate() {
                for (i, x) in sides.iter_mut().enumerate() {
                    *x = a0.level[g][i] + s * (act.level[g][i] - a0.level[g][i]);
                }
            }
            a.airway_opening = a0.airway_opening + s * (act.airway_opening - a0.airway_opening);
            (a, v0 + s * (target - v0))
        };
        let mut error = StaticsError::NotConverged {
            correction: f64::INFINITY,
        };
        for steps in [4u32, 16] {
            self.start_at(origin);
            self.factored_at = None;
            // the converged points of this pass: (s, state, pleural pressure)
            let mut path = vec![(0.0, self.y.clone(), self.pleural)];
            let mut ok = true;
            for k in 1..=steps {
                let s = f64::from(k) / f64::from(steps);
                let (a, v) = along(s);
                let before = self.stats.iterations;
                if let Err(e) = self.iterate(model, data, &a, v, tol) {
                    // unstable at the origin's own equilibrium (the first factorisation of
                    // the first step, before any correction): the chest wall buckles there,
                    // finer steps do not help
                    let at_origin = k == 1
                        && self.stats.iterations == before
                        && matches!(e, StaticsError::Unstable { .. });
                    error = e;
                    ok = false;
                    if at_origin {
                        return Err(error);
                    }
                    if steps == 16 && matches!(error, StaticsError::NotConverged { .. }) {
                        error =
                            self.path_end(model, data, &along, &mut path, tol, 1.0 / 16.0, error);
                    }
                    break;
                }
                path.push((s, self.y.clone(), self.pleural));
            }
            if ok {
                return Ok(());
            }
        }
        Err(error)
    }

    /// Where the continuation's `path` (its converged points, the last at s) stops: the step
    /// `ds` after it, which failed, is halved [`BISECTIONS`] times, each half solved from the
    /// last point reached; then the stiffness along the path ([`Statics::path_stiffness`])
    /// at its first and its last secant. Returns [`StaticsError::PathEnds`], or `failure`
    /// if the path has fewer than two points to take a secant from.
    #[allow(clippy::too_many_arguments)]
    fn path_end(
        &mut self,
        model: &Model,
        data: &mut Data,
        along: &dyn Fn(f64) -> (Activations, f64),
        path: &mut Vec<(f64, Vec<f64>, f64)>,
        tol: f64,
        ds: f64,
        failure: StaticsError,
    ) -> StaticsError {
        let correction = match failure {
            StaticsError::NotConverged { correction } => correction,
            _ => return failure,
        };
        let mut ds = ds;
        for _ in 0..BISECTIONS {
            ds *= 0.5;
            let (s, y, p) = path.last().cloned().expect("the origin is on the path");
            self.y.copy_from_slice(&y);
            self.pleural = p;
            self.factored_at = None;
            let (a, v) = along(s + ds);
            if self.iterate(model, data, &a, v, tol).is_ok() {
                path.push((s + ds, self.y.clone(), self.pleural));
            }
        }
        if path.len() < 2 {
            return failure;
        }
        let n = path.len();
        let (a_start, _) = along(path[0].0);
        let start = self.path_stiffness(model, data, &a_start, &path[0].1, &path[1].1, path[0].2);
        let (a_end, _) = along(path[n - 1].0);
        let end = self.path_stiffness(
            model,
            data,
            &a_end,
            &path[n - 1].1,
            &path[n - 2].1,
            path[n - 1].2,
        );
        let (_, y, p) = path.last().cloned().expect("two points");
        self.y.copy_from_slice(&y);
        self.pleural = p;
        StaticsError::PathEnds {
            reached: path[n - 1].0,
            stiffness_start: start,
            stiffness_end: end,
            correction,
        }
    }

    /// The stiffness of the chest wall with the lungs attached along the direction from
    /// state `from` to state `at` (a secant of the equilibrium path), at `at`: the Rayleigh
    /// quotient t^T J_aug t / t^T t of the unit direction t, J_aug t by a difference of the
    /// residual at the pleural pressure `pleural` (the lungs' part -rho (u^T t)^2 from the
    /// thoracic volumes) [N/m]; rotations count times [`LEVER`]. Negative where stable; it
    /// tends to zero where the path folds, as the secant turns into the softening mode.
    fn path_stiffness(
        &mut self,
        model: &Model,
        data: &mut Data,
        act: &Activations,
        at: &[f64],
        from: &[f64],
        pleural: f64,
    ) -> f64 {
        let l = self.l;
        let mut t = difference(&l, self.m, from, at);
        for (i, v) in t.iter_mut().enumerate() {
            if i < RIBS || (RIBS + 3..RIBS + 6).contains(&i) {
                *v *= LEVER;
            }
        }
        let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 || !norm.is_finite() {
            return f64::NAN;
        }
        // back to the state's units, as a unit displacement of EPS metres
        const EPS: f64 = 1e-7;
        for (i, v) in t.iter_mut().enumerate() {
            *v *= EPS / norm;
            if i < RIBS || (RIBS + 3..RIBS + 6).contains(&i) {
                *v /= LEVER;
            }
        }
        self.y.copy_from_slice(at);
        let (_, v0) = self.residual(model, data, act, pleural);
        self.f0
            .copy_from_slice(&self.dy[l.theta_dot..l.theta_dot + self.m]);
        apply(&l, &mut self.y, &t);
        let (_, v1) = self.residual(model, data, act, pleural);
        let work: f64 = (0..self.m)
            .map(|i| (self.dy[l.theta_dot + i] - self.f0[i]) * t[i])
            .sum();
        let rho = model.pleural.slope(v0);
        (work - rho * (v1 - v0) * (v1 - v0)) / (EPS * EPS)
    }
    /// The latest solution at or before `time` ([`Statics::solve`]'s starting point).
    fn origin(&self, time: f64) -> Option<usize> {
        (0..self.history.len())
            .filter(|&i| self.history[i].0 <= time)
            .max_by(|&a, &b| self.history[a].0.total_cmp(&self.history[b].0))
    }

    /// The iterate set to the solution `origin` (or the last solution).
    fn start_at(&mut self, origin: Option<usize>) {
        match origin {
            Some(i) => {
                self.y.copy_from_slice(&self.history[i].1);
                self.pleural = self.history[i].2;
            }
            None => {
                self.y.copy_from_slice(&self.y_good);
                self.pleural = self.pleural_good;
            }
        }
    }
}

/// The abdominal pressure at volume `va` (thesis eq. 2.5, relative to rest) [Pa].
fn abdominal_pressure(model: &Model, va: f64) -> f64 {
    model.params.bulk_modulus * (model.abdomen_rest_volume / va - 1.0)
}

/// The thoracic (mesh) volume of state `y` [m^3].
pub fn volume_of(model: &Model, y: &[f64]) -> f64 {
    let mut data = Data::new(model);
    kinematics::positions_and_velocities(model, &mut data, &model.layout, y);
    volume(&data.pos, &model.thorax_triangles)
}

/// The generalised forces at zero velocity into `dy`'s acceleration rows, with the abdominal
/// pressure `frozen_abdomen` (or that of the volume) and the pleural pressure `pleural`;
/// returns (V_A, V_T). `y`'s velocities must be zero.
#[allow(clippy::too_many_arguments)]
pub(crate) fn pressures_and_residual(
    model: &Model,
    data: &mut Data,
    l: &Layout,
    act: &Activations,
    y: &[f64],
    frozen_abdomen: Option<f64>,
    pleural: f64,
    dy: &mut [f64],
) -> (f64, f64) {
    kinematics::positions_and_velocities(model, data, l, y);
    let va = volume(&data.pos, &model.abdomen_triangles);
    let vt = volume(&data.pos, &model.thorax_triangles);
    let pa = frozen_abdomen.unwrap_or_else(|| abdominal_pressure(model, va));
    forces::accumulate_frozen(model, data, act, [pa, pleural]);
    accelerations::forces_and_rates(model, &model.preload, data, l, y, dy);
    (va, vt)
}

/// Adds the increment `dz` (rib angles, sternum translation, sternum rotation vector in the
/// world frame about its centre of mass, vertex displacements) to the state `y`.
pub(crate) fn apply(l: &Layout, y: &mut [f64], dz: &[f64]) {
    for r in 0..RIBS {
        y[l.theta + r] += dz[r];
    }
    for k in 0..3 {
        y[l.sternum_x + k] += dz[RIBS + k];
    }
    let phi = Vector3::new(dz[RIBS + 3], dz[RIBS + 4], dz[RIBS + 5]);
    if phi != Vector3::zeros() {
        let q = UnitQuaternion::from_quaternion(Quaternion::new(
            y[l.sternum_q],
            y[l.sternum_q + 1],
            y[l.sternum_q + 2],
            y[l.sternum_q + 3],
        ));
        let q = UnitQuaternion::from_scaled_axis(phi) * q;
        y[l.sternum_q] = q.w;
        y[l.sternum_q + 1] = q.i;
        y[l.sternum_q + 2] = q.j;
        y[l.sternum_q + 3] = q.k;
    }
    for (i, d) in dz[RIBS + 6..].iter().enumerate() {
        y[l.vertex_x + i] += d;
    }
}

/// The increment that takes state `from` to state `to` ([`apply`]'s inverse), of `m`
/// unknowns.
fn difference(l: &Layout, m: usize, from: &[f64], to: &[f64]) -> Vec<f64> {
    let mut dz = vec![0.0; m];
    for r in 0..RIBS {
        dz[r] = to[l.theta + r] - from[l.theta + r];
    }
    for k in 0..3 {
        dz[RIBS + k] = to[l.sternum_x + k] - from[l.sternum_x + k];
    }
    let quat = |y: &[f64]| {
        let q = l.sternum_q;
        UnitQuaternion::from_quaternion(Quaternion::new(y[q], y[q + 1], y[q + 2], y[q + 3]))
    };
    let phi = (quat(to) * quat(from).inverse()).scaled_axis();
    dz[RIBS + 3..RIBS + 6].copy_from_slice(phi.as_slice());
    let n = dz.len() - RIBS - 6;
    for i in 0..n {
        dz[RIBS + 6 + i] = to[l.vertex_x + i] - from[l.vertex_x + i];
    }
    dz
}

/// The largest displacement a correction makes [m] (rotations times [`LEVER`]).
fn correction_size(dz: &[f64]) -> f64 {
    let rot = dz[..RIBS]
        .iter()
        .chain(&dz[RIBS + 3..RIBS + 6])
        .fold(0.0f64, |m, v| m.max(v.abs()))
        * LEVER;
    let lin = dz[RIBS..RIBS + 3]
        .iter()
        .chain(&dz[RIBS + 6..])
        .fold(0.0f64, |m, v| m.max(v.abs()));
    rot.max(lin)
}
