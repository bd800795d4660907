//! Layout of the state vector: positions then velocities.
//!
//! y = [ theta (24 rib angles) | sternum position (3) | sternum orientation quaternion (w, x,
//! y, z) | free vertex positions (3n) | theta rates (24) | sternum velocity (3) | sternum
//! angular velocity, world frame (3) | free vertex velocities (3n) ].

use super::structure::{RIBS, Structure};

/// Offsets into the state vector.
#[derive(Clone, Copy, Debug)]
pub struct Layout {
    /// Rib angles.
    pub theta: usize,
    /// Sternum centre of mass.
    pub sternum_x: usize,
    /// Sternum quaternion.
    pub sternum_q: usize,
    /// Free vertex positions.
    pub vertex_x: usize,
    /// Rib angular rates.
    pub theta_dot: usize,
    /// Sternum velocity.
    pub sternum_v: usize,
    /// Sternum angular velocity.
    pub sternum_w: usize,
    /// Free vertex velocities.
    pub vertex_v: usize,
    /// Number of free vertices.
    pub vertices: usize,
    /// Total length.
    pub len: usize,
}

impl Layout {
    /// The layout of the state of a model of `structure` (stored in
    /// [`Model::layout`](super::Model::layout)).
    pub fn new(structure: &Structure) -> Layout {
        let n = structure.free_vertices();
        let theta = 0;
        let sternum_x = RIBS;
        let sternum_q = sternum_x + 3;
        let vertex_x = sternum_q + 4;
        let theta_dot = vertex_x + 3 * n;
        let sternum_v = theta_dot + RIBS;
        let sternum_w = sternum_v + 3;
        let vertex_v = sternum_w + 3;
        let len = vertex_v + 3 * n;
        Layout {
            theta,
            sternum_x,
            sternum_q,
            vertex_x,
            theta_dot,
            sternum_v,
            sternum_w,
            vertex_v,
            vertices: n,
            len,
        }
    }
}

/// The rest state: all angles zero, sternum and vertices at rest, identity orientation.
pub fn rest_state(model: &Structure) -> Vec<f64> {
    let l = Layout::new(model);
    let mut y = vec![0.0; l.len];
    let c = model.sternum_com;
    y[l.sternum_x..l.sternum_x + 3].copy_from_slice(&[c.x, c.y, c.z]);
    y[l.sternum_q] = 1.0;
    for (j, &a) in model.vertex_anchor.iter().enumerate() {
        let p = model.rest[a as usize];
        y[l.vertex_x + 3 * j..l.vertex_x + 3 * j + 3].copy_from_slice(&[p.x, p.y, p.z]);
    }
    y
}

/// How the step-size control weighs each component of the state
/// ([`crate::solver::Ode::error_weights`]): positions, angles and the quaternion as usual;
/// each velocity with its absolute tolerance multiplied by omega = 2 pi f_inertia, the rate
/// above which the model has no inertial mode ([`super::Params::inertia_frequency`]). An
/// absolute velocity error then counts as much as the position error it makes within
/// 1 / omega, and the errors of velocities that relax within a step cannot hold the step
/// (about atol_v = 2 pi 20 Hz x atol). Returns `(reference, weight)`; every component refers
/// to itself.
pub fn error_weights(model: &Structure) -> (Vec<u32>, Vec<f64>) {
    let l = Layout::new(model);
    let reference: Vec<u32> = (0..l.len as u32).collect();
    let mut weight = vec![1.0; l.len];
    let omega = 2.0 * std::f64::consts::PI * model.params.inertia_frequency;
    weight[l.theta_dot..].fill(omega);
    (reference, weight)
}
