//! The equations of motion. The state holds rib angles and rates, the sternum's pose and
//! velocity, and the positions and velocities of the abdominal surface's free vertices; the
//! right-hand side is computed in stages, one file each, in the manner of MuJoCo's forward
//! dynamics:
//!
//! 1. [`kinematics`]: body poses from the state, then every anchor's position and velocity;
//! 2. [`forces`]: muscle elements (thesis eq. 2.2-2.3, tension only after Zajac), membrane,
//!    cartilage joints and wall foundation, abdominal pressure P = K (V0/V - 1) with P A n / 3
//!    per vertex per triangle (eq. 2.5-2.6), pleural pressure from lung elastance;
//! 3. [`accelerations`]: forces reduced to generalised forces (rib torques about the hinge
//!    axes, sternum force and torque, vertex forces), joint springs, gravity and preload, then
//!    accelerations.
//!
//! The compiled [`Model`] never changes during a run: `model.rs` compiles its [`Structure`]
//! (`structure.rs`) first, derives the mass matrix (`inertia.rs`) and the preloads (stage 3's
//! [`accelerations::Preload`]) from it, and assembles the model once with the state's
//! [`Layout`] (`state.rs`). [`Data`] holds the scratch memory, so
//! that the right-hand side allocates nothing; it and the [`Activations`] live in `data.rs`,
//! the pipeline that runs the stages ([`rhs`], [`rhs_local`]) in this file.

pub mod accelerations;
pub mod airway;
mod data;
pub mod energy;
pub mod equilibrium;
pub mod forces;
pub mod inertia;
pub mod jacobian;
pub mod kinematics;
mod model;
pub mod muscle;
mod params;
pub mod pleural;
pub mod pretension;
pub mod state;
pub mod statics;
mod structure;

pub use data::{Activations, Data};
pub use model::Model;
pub use params::{
    ABDOMINAL_CONTENTS_DENSITY, CHEST_WALL_COMPLIANCE, DIAPHRAGM_CONTRACTION_UPRIGHT, GRAVITY,
    GRAVITY_MAX, GravityLoads, HILL_ABDOMINAL_WALL_FACTOR, HILL_CARTILAGE_FACTOR,
    HILL_PASSIVE_WALL_SCALE, LUNG_RECOIL_AT_FRC, PLEURAL_BARRIER_MARGIN, PLEURAL_BARRIER_PRESSURE,
    Params, STANDING_ABDOMINAL_TONE, abdominal_tone, abdominal_wall_tension_only,
    abdominal_wall_unloading, diaphragm_contraction, diaphragm_length_ratio,
    expiration_with_abdominals,
};
pub use state::{Layout, error_weights, rest_state};
pub use structure::{
    Carrier, Elements, PASSIVE, PASSIVE_SLACK, PATH_CORE, REST_LUNG_FRACTION, RIBS, Structure, VIA,
    VectorSprings, path_length, via_segment_length, volume,
};

/// The right-hand side with the mass matrix's block-diagonal part only (no volume
/// inertances, `inertia::MassMatrix::solve_local`): the equilibrium's residual, whose
/// Jacobian [`jacobian::TorsoJacobian::new`] gives (the stiff method's,
/// [`jacobian::TorsoJacobian::full`], maps it through the whole mass matrix).
pub fn rhs_local(model: &Model, data: &mut Data, act: &Activations, y: &[f64], dy: &mut [f64]) {
    let layout = &model.layout;
    kinematics::positions_and_velocities(model, data, layout, y);
    forces::accumulate(model, data, act);
    accelerations::compute_local(model, &model.preload, &model.mass, data, layout, y, dy);
}

/// The right-hand side y' = f(y) for the given activations, in stages.
pub fn rhs(model: &Model, data: &mut Data, act: &Activations, y: &[f64], dy: &mut [f64]) {
    let layout = &model.layout;
    kinematics::positions_and_velocities(model, data, layout, y);
    forces::accumulate(model, data, act);
    accelerations::compute(model, &model.preload, &model.mass, data, layout, y, dy);
}
