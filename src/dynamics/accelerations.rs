//! Stage 3: anchor forces reduced to generalised forces, then accelerations.
//!
//! ```text
//! rib r (one degree of freedom about its hinge):
//!     I_r theta'' = sum ((p - h) x F) . u + tau_gravity - k theta - d theta' + tau_preload
//! sternum (free rigid body):
//!     m x'' = sum F + m g + F_preload
//!     I_w w' = tau + tau_preload - w x I_w w,  I_w = R I_0 R^T,  q' = (0, w) q / 2
//! free vertex j (thesis eq. 2.1):
//!     m_j x'' = F_j + m_j g - gamma_j x' + F_preload
//! ```
//!
//! The left-hand sides are those of the true masses; the accelerations solve the generalised
//! forces against the scaled mass matrix of `dynamics::inertia` instead (M q'' = f, with
//! q'' = (theta'', x'', w', vertex x'') contiguous in the state's rates).
//!
//! The stage reads the [`Structure`] and the [`Preload`], never the whole model, so that the
//! preloads can be found with it before the model is assembled ([`Preload::at_rest`]).

use super::inertia::MassMatrix;
use super::state::{Layout, rest_state};
use super::structure::{RIBS, Structure};
use super::{Activations, Data, forces, kinematics};
use nalgebra::{Quaternion, Vector3};

/// Constant generalised loads holding the rest pose against gravity and the elements' rest
/// tension (`Model::preload`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Preload {
    /// Torque per rib [N m].
    pub rib: Vec<f64>,
    /// Force on the sternum [N].
    pub sternum_force: Vector3<f64>,
    /// Torque on the sternum about its centre of mass [N m] (the slack muscles' toe tension
    /// at rest has a moment).
    pub sternum_torque: Vector3<f64>,
    /// Force on each free vertex [N].
    pub vertex: Vec<Vector3<f64>>,
}

impl Preload {
    /// No load, for a structure with `free_vertices` free vertices.
    pub fn zero(free_vertices: usize) -> Preload {
        Preload {
            rib: vec![0.0; RIBS],
            sternum_force: Vector3::zeros(),
            sternum_torque: Vector3::zeros(),
            vertex: vec![Vector3::zeros(); free_vertices],
        }
    }

    /// The preloads that make the rest pose of `structure` an equilibrium: the generalised
    /// forces at rest (no activation, no velocity, no preload) are computed and cancelled.
    pub fn at_rest(structure: &Structure) -> Preload {
        let none = Preload::zero(structure.free_vertices());
        let l = Layout::new(structure);
        let mut data = Data::new(structure);
        let y = rest_state(structure);
        let mut dy = vec![0.0; y.len()];
        kinematics::positions_and_velocities(structure, &mut data, &l, &y);
        forces::accumulate(structure, &mut data, &Activations::default());
        forces_and_rates(structure, &none, &mut data, &l, &y, &mut dy);
        Preload {
            rib: data.rib_torque.iter().map(|t| -t).collect(),
            sternum_force: -data.sternum_force,
            sternum_torque: -data.sternum_torque,
            vertex: structure
                .vertex_anchor
                .iter()
                .zip(&structure.vertex_mass)
                .map(|(&a, m)| -data.force[a as usize] - structure.vertex_gravity * *m)
                .collect(),
        }
    }
}

/// Writes y' into `dy`: the generalised forces of [`forces_and_rates`] solved against the
/// mass matrix `mass`.
pub fn compute(
    structure: &Structure,
    preload: &Preload,
    mass: &MassMatrix,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    dy: &mut [f64],
) {
    forces_and_rates(structure, preload, data, l, y, dy);
    mass.solve(&mut dy[l.theta_dot..]);
}

/// As [`compute`], with the mass matrix's block-diagonal part only (the cavities' volume
/// inertances left out, [`super::inertia::MassMatrix::solve_local`]): the right-hand side
/// whose Jacobian is sparse plus rank 2 ([`super::jacobian::TorsoJacobian::new`]; the
/// stiff method's maps it through the whole mass matrix).
pub fn compute_local(
    structure: &Structure,
    preload: &Preload,
    mass: &MassMatrix,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    dy: &mut [f64],
) {
    forces_and_rates(structure, preload, data, l, y, dy);
    mass.solve_local(&mut dy[l.theta_dot..]);
}

/// The position rates into `dy`, and the generalised forces where the accelerations go
/// (rib torques, sternum force and torque, vertex forces, in the order of the rates; the
/// anchor forces of `data` must be those of `y`), with the constant loads `preload`: the
/// unbalanced loads that [`super::equilibrium`] drives to zero.
pub fn forces_and_rates(
    model: &Structure,
    preload: &Preload,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    dy: &mut [f64],
) {
    // Position derivatives are the velocities.
    dy[l.theta..l.theta + RIBS].copy_from_slice(&y[l.theta_dot..l.theta_dot + RIBS]);
    dy[l.sternum_x..l.sternum_x + 3].copy_from_slice(&y[l.sternum_v..l.sternum_v + 3]);
    let n3 = 3 * l.vertices;
    dy[l.vertex_x..l.vertex_x + n3].copy_from_slice(&y[l.vertex_v..l.vertex_v + n3]);
    // Quaternion rate (world-frame angular velocity): q' = 1/2 (0, w) q.
    let q = Quaternion::new(
        y[l.sternum_q],
        y[l.sternum_q + 1],
        y[l.sternum_q + 2],
        y[l.sternum_q + 3],
    );
    let w = data.sternum_w;
    let qd = Quaternion::new(0.0, w.x, w.y, w.z) * q * 0.5;
    dy[l.sternum_q] = qd.w;
    dy[l.sternum_q + 1] = qd.i;
    dy[l.sternum_q + 2] = qd.j;
    dy[l.sternum_q + 3] = qd.k;

    ribs(model, preload, data, l, y, dy);
    sternum(model, preload, data, l, dy);
    vertices(model, preload, data, l, y, dy);
}

/// Rib torques (generalised forces).
fn ribs(
    model: &Structure,
    preload: &Preload,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    dy: &mut [f64],
) {
    // one length for both arrays, so that one index check covers them
    let m = data.pos.len();
    let (pos, force) = (&data.pos[..], &data.force[..m]);
    for r in 0..RIBS {
        let (h, u) = (model.rib_head[r], model.rib_axis[r]);
        let mut moment = Vector3::zeros();
        for &a in &model.rib_anchors[r] {
            let a = a as usize;
            moment += (pos[a] - h).cross(&force[a]);
        }
        let com_arm = data.rib_rotation[r] * (model.rib_com[r] - h);
        moment += com_arm.cross(&(model.gravity * model.rib_mass[r]));
        let (theta, rate) = (y[l.theta + r], y[l.theta_dot + r]);
        let torque = moment.dot(&u) - model.rib_stiffness[r] * theta - model.rib_damping[r] * rate
            + preload.rib[r];
        data.rib_torque[r] = torque;
        dy[l.theta_dot + r] = torque;
    }
}

/// Sternum force and torque, less the gyroscopic torque w x I w of its true inertia.
fn sternum(model: &Structure, preload: &Preload, data: &mut Data, l: &Layout, dy: &mut [f64]) {
    let x = data.sternum_x;
    let mut force = model.gravity * model.sternum_mass + preload.sternum_force;
    let mut torque = preload.sternum_torque;
    for &a in &model.sternum_anchors {
        let a = a as usize;
        force += data.force[a];
        torque += (data.pos[a] - x).cross(&data.force[a]);
    }
    data.sternum_force = force;
    data.sternum_torque = torque;
    let rot = data.sternum_rotation.to_rotation_matrix();
    let inertia = rot.matrix() * model.sternum_inertia * rot.matrix().transpose();
    let w = data.sternum_w;
    let rhs = torque - w.cross(&(inertia * w));
    dy[l.sternum_v..l.sternum_v + 3].copy_from_slice(force.as_slice());
    dy[l.sternum_w..l.sternum_w + 3].copy_from_slice(rhs.as_slice());
}

/// Free vertex forces.
fn vertices(
    model: &Structure,
    preload: &Preload,
    data: &mut Data,
    l: &Layout,
    y: &[f64],
    dy: &mut [f64],
) {
    let n = l.vertices;
    let (mass, damping, preload) = (
        &model.vertex_mass[..n],
        &model.vertex_damping[..n],
        &preload.vertex[..n],
    );
    let vs = y[l.vertex_v..l.vertex_v + 3 * n].chunks_exact(3);
    let accs = dy[l.vertex_v..l.vertex_v + 3 * n].chunks_exact_mut(3);
    for (j, ((&a, v), acc)) in model.vertex_anchor[..n]
        .iter()
        .zip(vs)
        .zip(accs)
        .enumerate()
    {
        let v = Vector3::new(v[0], v[1], v[2]);
        let f =
            data.force[a as usize] + model.vertex_gravity * mass[j] + preload[j] - v * damping[j];
        acc.copy_from_slice(f.as_slice());
    }
}
