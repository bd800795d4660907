//! Stage 1: body poses from the state, then the position and velocity of every anchor.
//!
//! A rib turns by theta about its unit hinge axis u through its head h (Rodrigues):
//! p = h + R(u, theta)(p0 - h), v = theta' u x (p - h). The sternum is a free rigid body:
//! p = x + R(q)(p0 - x0), v = x' + w x (p - x). Free vertices are read directly.

use super::Data;
use super::model::{Model, RIBS};
use super::state::Layout;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Rotation matrix about unit axis `u` by `angle` (Rodrigues' formula).
pub fn axis_rotation(u: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let k = u.cross_matrix();
    Matrix3::identity() + k * s + k * k * (1.0 - c)
}

/// Fills `data.pos` and `data.vel` for all moving anchors.
pub fn positions_and_velocities(model: &Model, data: &mut Data, l: &Layout, y: &[f64]) {
    for r in 0..RIBS {
        data.rib_rotation[r] = axis_rotation(&model.rib_axis[r], y[l.theta + r]);
    }
    let q = Quaternion::new(
        y[l.sternum_q],
        y[l.sternum_q + 1],
        y[l.sternum_q + 2],
        y[l.sternum_q + 3],
    );
    data.sternum_rotation = UnitQuaternion::from_quaternion(q);
    data.sternum_x = nalgebra::Point3::new(y[l.sternum_x], y[l.sternum_x + 1], y[l.sternum_x + 2]);
    data.sternum_w = Vector3::new(y[l.sternum_w], y[l.sternum_w + 1], y[l.sternum_w + 2]);
    let sternum_v = Vector3::new(y[l.sternum_v], y[l.sternum_v + 1], y[l.sternum_v + 2]);

    for r in 0..RIBS {
        let (h, rot, u) = (model.rib_head[r], data.rib_rotation[r], model.rib_axis[r]);
        let rate = y[l.theta_dot + r];
        for &a in &model.rib_anchors[r] {
            let a = a as usize;
            let arm = rot * (model.rest[a] - h);
            data.pos[a] = h + arm;
            data.vel[a] = u.cross(&arm) * rate;
        }
    }
    let rot = data.sternum_rotation.to_rotation_matrix();
    for &a in &model.sternum_anchors {
        let a = a as usize;
        let arm = rot * (model.rest[a] - model.sternum_com);
        data.pos[a] = data.sternum_x + arm;
        data.vel[a] = sternum_v + data.sternum_w.cross(&arm);
    }
    for (j, &a) in model.vertex_anchor.iter().enumerate() {
        let a = a as usize;
        let (px, pv) = (l.vertex_x + 3 * j, l.vertex_v + 3 * j);
        data.pos[a] = nalgebra::Point3::new(y[px], y[px + 1], y[px + 2]);
        data.vel[a] = Vector3::new(y[pv], y[pv + 1], y[pv + 2]);
    }
    debug_assert!(model.carrier.len() == data.pos.len());
}
